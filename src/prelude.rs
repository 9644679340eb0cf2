//! What an engine that embeds cullgraph needs, in one import: `use cullgraph::prelude::*;`.
//!
//! - the device: [`GpuContext`] (owned, or [`GpuContext::from_host`] with the engine's
//!   [`HostHandles`]), [`ShaderCompiler`];
//! - the scene: [`Scene`], [`Instance`], [`Material`], [`Camera`], [`SceneSource`];
//! - rendering: [`Renderer`] with a [`GraphSpec`], its views ([`ViewId`], [`ViewFrame`]),
//!   [`Imports`] of the engine's own images and buffers, [`FrameStats`] and [`PassTiming`] as
//!   plain data, outputs read back as [`OutputF32`];
//! - an engine's own pass kinds: [`PassKind`] registered in a [`KindRegistry`] (on top of
//!   [`builtin_kinds`]), with the pieces a kind declares ([`SlotDecl`], [`SettingDecl`] and
//!   [`crate::choice!`], [`Creates`], [`Counters`], [`Quantity`]) and records with
//!   ([`PassContext`], [`SceneInputs`]);
//! - observers of frames ([`FrameObserver`]).

pub use crate::error::{Error, Result};
pub use crate::gpu::{
    cmd_set_full_viewport, Access, Bind, Buffer, BufferDesc, ContextOptions, GpuContext, GraphicsDesc, HostHandles,
    HostImage, Image, MemoryLocation, PassTiming, Pipeline, RequiredFeatures, ShaderCompiler, ShaderRoot, Spirv,
    StencilRule, OPTIONAL_DEVICE_EXTENSIONS, REQUIRED_DEVICE_EXTENSIONS,
};
pub use crate::graph::{
    Bytes, Choice, Counters, Creates, Extent, FormatRule, Growth, Imports, KindCheck, KindRegistry, MipChain,
    NodeSetup, PassContext, PassKind, PassKindInfo, PassNode, Quantity, ResolvedKind, SettingDecl, SlotDecl, Stages,
    Usage, FRAMES_IN_FLIGHT,
};
pub use crate::passes::builtin_kinds;
pub use crate::passes::shared::{SceneCounts, SceneInputs};
pub use crate::render::{
    FrameObserver, FramePipeline, GraphSpec, OutputF32, ParamsApplied, RenderSettings, Renderer, ViewFrame, ViewId,
    MAX_VIEWS, USER_DATA_IMPORT,
};
pub use crate::scene::animation::{InstancePose, SceneAnimation};
pub use crate::scene::deform::{MeshDeform, MorphTarget};
pub use crate::scene::merge::SceneMerge;
pub use crate::scene::posing::Pose;
pub use crate::scene::source::LoadOptions;
pub use crate::scene::world::{InstanceHandle, LightHandle, World, WorldError, MAX_USER_WORDS};
pub use crate::scene::{
    Camera, DirectionalLight, Instance, Material, MeshData, PointLight, Projection, Scene, SceneSource, SpotCone,
    Texture, TextureRef, TextureSlot, Transform,
};
pub use crate::stats::{FrameStats, UpdateStats};
