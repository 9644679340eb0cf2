//! Built-in passes. Each records its own commands; the frame (and later the render graph)
//! decides the order and the barriers between them.

pub mod gbuffer;
pub mod lighting;
