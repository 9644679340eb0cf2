//! Verification only: exact visibility by ray casting and by an unculled instance-id render, and
//! image metrics. Production code never uses it; the command line, the bench and the tests do.
//! The culling math it checks against is [`crate::cull`], the CPU twin of the shaders.
//!
//! - [`raycast`]: which instance each pixel sample sees, by casting primary rays through an
//!   `obvhs` BVH of the scene's world-space triangles.
//! - [`metrics`]: PSNR and mean absolute error of two RGBA8 images.
//! - [`image_error`]: the linear-light box downsample of a supersampled reference, and mean FLIP
//!   and PSNR of an image against it; [`reference`](mod@reference) renders that reference.
//! - [`visibility`]: the unculled instance-id render; [`verification`] attaches it to a renderer
//!   as an observer of its frames, to count what culling got wrong.

pub mod image_error;
pub mod metrics;
pub mod raycast;
pub mod reference;
pub mod verification;
pub mod visibility;

pub use image_error::ImageError;
pub use metrics::ImageDiff;
pub use raycast::{RaycastOracle, SamplePattern, VisibilityImage};
pub use reference::{reference_error, render_reference, DEFAULT_REFERENCE_SCALE};
pub use verification::{Verification, Verify};
