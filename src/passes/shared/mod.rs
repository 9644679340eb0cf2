//! What the built-in passes share besides their slots: the scene on the GPU, its GPU layouts,
//! and this frame's constants and lights ([`SceneInputs`]).
//!
//! The graph knows none of it: the renderer hands a [`SceneInputs`] to every frame as the graph's
//! opaque shared data ([`crate::graph::FrameData::shared`]), and a pass reads it through
//! [`SceneInputs::of`]. An engine's own pass kinds read it the same way, for example to draw
//! the instances' bounds.

pub mod cull_blocks;
pub mod cull_data;
pub mod face_cull;
pub mod gpu_types;
pub mod instance_ranges;
pub(crate) mod lazy_pipeline;
pub mod scene_buffers;
pub mod scene_growth;
pub(crate) mod shadow_variants;
pub mod slot_layout;
pub mod textures;
pub(crate) mod transparent_draw;
pub mod vertex_streams;

use crate::gpu::{Buffer, BufferDesc, GpuContext, MemoryLocation};
use crate::graph::{FrameInputs, Growth, KindRegistry, PassContext, Quantity, FRAMES_IN_FLIGHT};
use crate::scene::Scene;
use ash::vk;
use gpu_types::{FrameConstants, GpuPointLight};
pub use scene_buffers::GpuScene;
use std::sync::Arc;

/// Host-visible data of one frame in flight.
pub(crate) struct FrameSlot {
    /// This frame's [`FrameConstants`].
    pub constants: Buffer,
    /// What `constants` was last given, for passes that read it on the host
    /// ([`SceneInputs::constants_written`]).
    pub written: FrameConstants,
    /// This frame's point lights ([`GpuPointLight`] each).
    pub lights: Buffer,
}

impl FrameSlot {
    /// Writes this frame's constants.
    pub fn write_constants(&mut self, constants: &FrameConstants) -> crate::Result<()> {
        self.constants.write_bytes(0, bytemuck::bytes_of(constants))?;
        self.written = *constants;
        Ok(())
    }
}

/// What one view's graph reads besides its slots: the world's scene on the GPU (shared by every
/// view) and the view's own per-frame buffers of each frame in flight (its constants and its
/// eye-relative lights); the renderer picks the frame's slot before recording it.
pub struct SceneInputs {
    /// The scene on the GPU (pools, instances, materials, the unculled draw list), shared by
    /// every view of the world.
    pub scene: Arc<GpuScene>,
    frames: Vec<FrameSlot>,
    current: usize,
    shadow_maps: ShadowMaps,
    /// Distinguishes these inputs from every other made in the process (a replay key part).
    id: u64,
}

/// The shadow maps a view's lighting samples (`shadows.glsl`): the sun's cascades and the spot
/// and point lights' faces, each a `D32_SFLOAT` 2D array view in `SHADER_READ_ONLY_OPTIMAL`, and
/// their comparison sampler. The frame constants and lights say which layers hold what; a view
/// without shadows reads none.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ShadowMaps {
    /// Whether the view has shadows: its lighting then takes the variant that samples them.
    pub on: bool,
    /// The sun's cascades.
    pub sun: vk::ImageView,
    /// The spot and point lights' faces.
    pub local: vk::ImageView,
    /// A comparison sampler ([`crate::gpu::Sampler::depth_compare`]).
    pub sampler: vk::Sampler,
    /// The ids of the sun's and the lights' map arrays ([`crate::gpu::DepthArray::id`]): new
    /// arrays are new maps even where Vulkan gave them the old ones' handles (replayed frames
    /// must not sample those).
    pub arrays: [u64; 2],
}

impl ShadowMaps {
    /// Where `shadows.glsl` declares the sun's maps.
    pub const SUN_BINDING: u32 = 15;
    /// Where `shadows.glsl` declares the spot and point lights' maps.
    pub const LOCAL_BINDING: u32 = 14;

    /// The maps as a lighting pass binds them.
    pub fn binds(&self) -> [crate::gpu::Bind; 2] {
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        [
            crate::gpu::Bind::Sampled(Self::SUN_BINDING, self.sun, self.sampler, read),
            crate::gpu::Bind::Sampled(Self::LOCAL_BINDING, self.local, self.sampler, read),
        ]
    }
}

impl SceneInputs {
    /// Wraps `scene`, with per-frame buffers for up to `lights` point lights.
    pub fn new(ctx: &GpuContext, scene: Arc<GpuScene>, lights: usize) -> crate::Result<Self> {
        let light_bytes = (lights.max(1) * std::mem::size_of::<GpuPointLight>()) as u64;
        let frames = (0..FRAMES_IN_FLIGHT)
            .map(|i| -> crate::Result<FrameSlot> {
                // The constants are read as a uniform buffer (`FrameConstants` in
                // `common/scene.glsl` says why), the lights as a storage buffer.
                let host = |name: &str, size| {
                    Buffer::new(
                        ctx,
                        &BufferDesc {
                            name,
                            size,
                            usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::UNIFORM_BUFFER,
                            location: MemoryLocation::CpuToGpu,
                        },
                    )
                };
                Ok(FrameSlot {
                    constants: host(&format!("frame constants {i}"), std::mem::size_of::<FrameConstants>() as u64)?,
                    written: FrameConstants::default(),
                    lights: host(&format!("lights {i}"), light_bytes)?,
                })
            })
            .collect::<crate::Result<Vec<_>>>()?;
        static MADE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let id = MADE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(Self { scene, frames, current: 0, shadow_maps: ShadowMaps::default(), id })
    }

    /// The [`crate::graph::FrameData::replay_key`] of the frame these inputs are selected for:
    /// which inputs (a scene made anew, or lights outgrowing their buffers, make new ones),
    /// which frame slot of them, and which shadow maps. Everything else the passes read of
    /// them lives in buffers that stay.
    pub(crate) fn replay_key(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        (self.id, self.current, self.shadow_maps).hash(&mut hasher);
        hasher.finish()
    }

    /// The shared inputs of the frame `rec` records, or an error naming the pass when the host
    /// gave the graph something else (a graph run by another host than cullgraph's renderer).
    pub fn of<'a>(rec: &PassContext<'a>) -> crate::Result<&'a SceneInputs> {
        rec.frame.shared.downcast_ref::<SceneInputs>().ok_or_else(|| {
            crate::Error::Invalid(format!(
                "pass '{}' reads the scene, but the frame's shared data is not cullgraph's SceneInputs",
                rec.slots.pass_name()
            ))
        })
    }

    /// Makes frame `frame`'s slot the current one.
    pub(crate) fn select(&mut self, frame: u64) {
        self.current = (frame % FRAMES_IN_FLIGHT as u64) as usize;
    }

    /// The slot of frame `frame` (for writing it before the frame is recorded, or reading what
    /// it held once the frame has completed).
    pub(crate) fn slot_mut(&mut self, frame: u64) -> &mut FrameSlot {
        &mut self.frames[(frame % FRAMES_IN_FLIGHT as u64) as usize]
    }

    /// The slot of frame `frame` (what it held once that frame has completed).
    pub(crate) fn slot(&self, frame: u64) -> &FrameSlot {
        &self.frames[(frame % FRAMES_IN_FLIGHT as u64) as usize]
    }

    /// This frame's constants ([`FrameConstants`]).
    pub fn constants(&self) -> &Buffer {
        &self.frames[self.current].constants
    }

    /// This frame's constants as the host wrote them (what [`SceneInputs::constants`] holds),
    /// for a pass that hands some of them on in its own buffers.
    pub fn constants_written(&self) -> &FrameConstants {
        &self.frames[self.current].written
    }

    /// This frame's point lights.
    pub fn lights(&self) -> &Buffer {
        &self.frames[self.current].lights
    }

    /// The shadow maps this view samples.
    pub fn shadow_maps(&self) -> ShadowMaps {
        self.shadow_maps
    }

    /// Sets the shadow maps the next recorded frame samples (the renderer does, every frame).
    pub(crate) fn set_shadow_maps(&mut self, maps: ShadowMaps) {
        self.shadow_maps = maps;
    }
}

/// A changing world's scene as cullgraph's renderer lays it out in slots: the scene in slot
/// order (empty slots included) with its layout, whose slots and draw groups include the room
/// the renderer keeps to grow.
pub struct LaidOutScene {
    /// The scene in slot order.
    pub scene: Scene,
    /// Its slot layout.
    pub layout: slot_layout::SlotLayout,
}

/// What cullgraph's renderer counts the graphs' quantities in: a [`Scene`] rendered as it is,
/// or a [`LaidOutScene`]. Quantities registered beside the built-in kinds read the host's
/// description through this.
pub struct SceneCounts<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The slot layout, for a world.
    pub layout: Option<&'a slot_layout::SlotLayout>,
}

impl<'a> SceneCounts<'a> {
    /// The host's description (`&Scene` or `&LaidOutScene`), or `None` for another type.
    pub fn downcast(scene: &'a dyn std::any::Any) -> Option<SceneCounts<'a>> {
        if let Some(scene) = scene.downcast_ref::<Scene>() {
            return Some(SceneCounts { scene, layout: None });
        }
        let laid = scene.downcast_ref::<LaidOutScene>()?;
        Some(SceneCounts { scene: &laid.scene, layout: Some(&laid.layout) })
    }
}

/// A quantity counted in [`SceneCounts`].
const fn scene_quantity(
    name: &'static str,
    doc: &'static str,
    count: fn(&dyn std::any::Any) -> Option<u64>,
    growth: Growth,
) -> Quantity {
    Quantity { name, doc, count, growth }
}

/// The quantities of every scene, which the built-in kinds' sizes use: `instances`, `meshes`
/// (draw groups), `lights`, `materials`, `triangles` and `emission_or_occlusion`.
pub fn scene_quantities() -> [Quantity; 6] {
    [
        scene_quantity(
            "instances",
            "instances of the scene (a world's slots)",
            |s| {
                let c = SceneCounts::downcast(s)?;
                Some(c.layout.map_or(c.scene.instances.len() as u64, |l| l.slots() as u64))
            },
            Growth::Grows,
        ),
        scene_quantity(
            "meshes",
            "draw groups a draw list may hold: each mesh once, and once more for each further region its instances need (one-sided, mirrored, double-sided, for opaque and for masked materials; transparent)",
            |s| {
                let c = SceneCounts::downcast(s)?;
                Some(c.layout.map_or(face_cull::command_capacity(c.scene) as u64, |l| l.groups.len() as u64))
            },
            Growth::Grows,
        ),
        scene_quantity(
            "lights",
            "point lights",
            |s| Some(SceneCounts::downcast(s)?.scene.lights.len() as u64),
            Growth::Grows,
        ),
        scene_quantity(
            "materials",
            "materials",
            |s| Some(SceneCounts::downcast(s)?.scene.materials.len() as u64),
            Growth::Grows,
        ),
        scene_quantity(
            "triangles",
            "triangles over all instances",
            |s| Some(scene_buffers::drawn_triangles(SceneCounts::downcast(s)?.scene)),
            Growth::Grows,
        ),
        scene_quantity(
            "emission_or_occlusion",
            "1 where some material emits light or has an occlusion texture, else 0 (a G-buffer's emissive_occlusion target exists only then)",
            |s| Some(SceneCounts::downcast(s)?.scene.has_emission_or_occlusion() as u64),
            Growth::Exact,
        ),
    ]
}

/// What a graph loaded with `kinds` is compiled for with `scene` at `width` x `height`: the
/// output size and the scene's quantities ([`SceneCounts`]).
pub fn frame_inputs(kinds: &KindRegistry, scene: &Scene, width: u32, height: u32) -> crate::Result<FrameInputs> {
    Ok(FrameInputs::with_quantities(width, height, kinds.count(scene)?))
}
