//! The sun's shadows: each camera view gets cascades fitted to its camera every frame
//! ([`crate::scene::cascades`]), and each cascade is a view of the renderer's world running a
//! depth-only graph (`graph/shadow.ron`) into its layer of the camera view's shadow-map array.
//! The cascades are recorded in lockstep with the cameras, so their culls share the cameras'
//! dispatches, and every cascade has finished drawing before the first pass of its camera that
//! samples the maps ([`crate::graph::PassNode::samples_sun_shadows`]).

use super::graphs::{build_runtime, Graphs};
use super::view::{View, ViewId, ViewRole};
use super::Renderer;
use crate::error::{Error, Result};
use crate::gpu::{Access, DepthArray, GpuContext, Sampler, ShaderCompiler};
use crate::graph::Imports;
use crate::passes::shared::gpu_types::GpuSunShadows;
use crate::passes::shared::{SceneInputs, SunShadowMaps};
use crate::render::{GraphSpec, RenderSettings};
use crate::scene::cascades::{fit_cascades, CascadeSettings, MAX_CASCADES};
use crate::scene::{Camera, Scene};
use ash::vk;
use glam::Mat4;

/// How a renderer draws the sun's shadows ([`Renderer::set_shadows`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowSettings {
    /// Cascades per camera view, 1 to [`MAX_CASCADES`].
    pub cascades: u32,
    /// Width and height of each cascade's map in texels.
    pub resolution: u32,
    /// How far from each camera shadows reach, in world units (`None`: 150, or the scene's
    /// diagonal when that is shorter).
    pub distance: Option<f32>,
    /// Between uniform (0) and logarithmic (1) cascade splits.
    pub lambda: f32,
    /// How far before each cascade, towards the sun, casters are drawn (`None`: the scene's
    /// diagonal when shadows are set, so that nothing in the scene's bounds at that time is
    /// left out).
    pub caster_reach: Option<f32>,
    /// Whether casters are culled (`graph/shadow.ron`: two-phase occlusion culling per
    /// cascade, in the cameras' dispatches) or all drawn (`graph/shadow_no_cull.ron`).
    pub caster_culling: bool,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self { cascades: 4, resolution: 2048, distance: None, lambda: 0.75, caster_reach: None, caster_culling: true }
    }
}

/// Where a view's graph reads the maps once they are drawn: the lighting in compute, the
/// transparent surfaces in fragment shaders.
const SAMPLED: Access = Access {
    stage: vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw() | vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw(),
    ),
    access: vk::AccessFlags2::SHADER_SAMPLED_READ,
    layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
};

/// One camera view's cascades.
pub(super) struct CameraShadows {
    /// The camera view.
    pub camera: ViewId,
    /// Its cascades' views, nearest first.
    pub cascades: Vec<ViewId>,
    /// One layer per cascade.
    pub maps: DepthArray,
    /// How the last recorded frame left the maps.
    pub state: Access,
    /// What each cascade's map was last drawn for (`None`: never drawn).
    pub drawn_for: Vec<Option<MapKey>>,
}

/// What a cascade's map depends on: its camera, the sun, and the world's version (any change of
/// a world counts, which is conservative: a change the cascade cannot see redraws it too).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct MapKey {
    camera: Camera,
    sun: glam::Vec3,
    world_version: Option<u64>,
}

/// The renderer's shadow state.
pub(super) struct SunShadows {
    /// `None`: no shadows.
    pub settings: Option<ShadowSettings>,
    /// Per camera view with shadows.
    pub cameras: Vec<CameraShadows>,
    sampler: Sampler,
    /// A one-layer array that views without shadows bind (never read: no cascades).
    fallback: DepthArray,
    fallback_ready: bool,
    /// The resolved caster reach and distance for the scene.
    reach: f32,
    distance: f32,
    /// Whether maps that would be drawn as they are are kept ([`Renderer::set_shadow_maps_kept`]).
    keep_unchanged: bool,
}

impl SunShadows {
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        Ok(Self {
            settings: None,
            cameras: Vec::new(),
            sampler: Sampler::depth_compare(ctx)?,
            fallback: DepthArray::new(ctx, "no shadow maps", 1, 1)?,
            fallback_ready: false,
            reach: 0.0,
            distance: 0.0,
            keep_unchanged: true,
        })
    }

    fn fallback_maps(&self) -> SunShadowMaps {
        SunShadowMaps { view: self.fallback.array_view(), sampler: self.sampler.handle() }
    }

    /// Device memory the shadow maps take.
    pub fn bytes(&self) -> u64 {
        self.cameras.iter().map(|c| c.maps.bytes()).sum()
    }
}

/// One cascade's part of a frame: its view, camera and the import of its layer.
pub(super) struct CascadeFrame {
    pub view: ViewId,
    pub camera: Camera,
    pub imports: Imports,
    /// The camera view whose lighting waits for it.
    pub of: ViewId,
    /// What its map is drawn for.
    key: MapKey,
}

impl Renderer {
    /// Turns the sun's shadows on with `settings`, or off (`None`), from the next frame on.
    /// Every camera view gets its cascades; views added later get theirs when added. The
    /// sun is the scene's ([`crate::scene::Scene::sun`], `World::set_sun`).
    ///
    /// Errors: a cascade count outside 1 to 4, a resolution of 0 or beyond the device, a
    /// distance or reach that is not finite and positive, a lambda outside 0 to 1; nothing
    /// changes then.
    pub fn set_shadows(&mut self, shaders: &ShaderCompiler, settings: Option<ShadowSettings>) -> Result<()> {
        profiling::scope!("cullgraph::Renderer::set_shadows");
        let last_use = self.frame_index.saturating_sub(1);
        let Some(settings) = settings else {
            self.drop_all_shadows(last_use);
            self.shadows.settings = None;
            return Ok(());
        };
        let (reach, distance) = check_settings(&self.scene, &settings)?;
        let cameras: Vec<ViewId> = self.camera_views().collect();
        let mut made = Vec::new();
        for camera in cameras {
            match self.make_camera_shadows(shaders, camera, &settings) {
                Ok(shadows) => made.push(shadows),
                Err(e) => {
                    for (shadows, views) in made {
                        self.retire_camera_shadows(shadows, views, last_use);
                    }
                    return Err(camera.error(e));
                }
            }
        }
        self.drop_all_shadows(last_use);
        for (shadows, views) in made {
            self.views.extend(views);
            self.shadows.cameras.push(shadows);
        }
        self.shadows.settings = Some(settings);
        self.shadows.reach = reach;
        self.shadows.distance = distance;
        Ok(())
    }

    /// Whether a cascade's map is kept, not drawn again, while its camera, the sun and the
    /// world are what they were when it was drawn (the default). Off, every map is drawn every
    /// frame (to measure what drawing them costs).
    pub fn set_shadow_maps_kept(&mut self, on: bool) {
        self.shadows.keep_unchanged = on;
    }

    /// The shadow settings in force (`None`: no shadows).
    pub fn shadows(&self) -> Option<&ShadowSettings> {
        self.shadows.settings.as_ref()
    }

    /// Device memory the shadow maps take (0 without shadows).
    pub fn shadow_map_bytes(&self) -> u64 {
        self.shadows.bytes()
    }

    /// The views that are cameras (not cascades).
    pub(super) fn camera_views(&self) -> impl Iterator<Item = ViewId> + '_ {
        self.views.iter().filter(|v| v.role == ViewRole::Camera).map(|v| v.id)
    }

    /// Gives camera view `camera` its cascades (after [`Renderer::add_view`]) when shadows are on.
    pub(super) fn add_camera_shadows(&mut self, shaders: &ShaderCompiler, camera: ViewId) -> Result<()> {
        let Some(settings) = self.shadows.settings.clone() else { return Ok(()) };
        let (shadows, views) = self.make_camera_shadows(shaders, camera, &settings)?;
        self.views.extend(views);
        self.shadows.cameras.push(shadows);
        Ok(())
    }

    /// Removes camera view `camera`'s cascades (with the view).
    pub(super) fn remove_camera_shadows(&mut self, camera: ViewId) {
        let last_use = self.frame_index.saturating_sub(1);
        if let Some(at) = self.shadows.cameras.iter().position(|c| c.camera == camera) {
            let shadows = self.shadows.cameras.remove(at);
            let views = self.take_views(&shadows.cascades);
            self.retire_camera_shadows(shadows, views, last_use);
        }
    }

    fn drop_all_shadows(&mut self, last_use: u64) {
        for shadows in std::mem::take(&mut self.shadows.cameras) {
            let views = self.take_views(&shadows.cascades);
            self.retire_camera_shadows(shadows, views, last_use);
        }
    }

    fn take_views(&mut self, ids: &[ViewId]) -> Vec<View> {
        let mut taken = Vec::new();
        let mut at = 0;
        while at < self.views.len() {
            if ids.contains(&self.views[at].id) {
                taken.push(self.views.remove(at));
            } else {
                at += 1;
            }
        }
        taken
    }

    fn retire_camera_shadows(&mut self, shadows: CameraShadows, views: Vec<View>, last_use: u64) {
        for view in views {
            self.retired.views.push((last_use, view));
        }
        self.retired.shadow_maps.push((last_use, shadows.maps));
    }

    /// Camera view `camera`'s cascades (views not yet in the list, with ids from
    /// `next_view` on) and their maps.
    fn make_camera_shadows(
        &mut self,
        shaders: &ShaderCompiler,
        camera: ViewId,
        settings: &ShadowSettings,
    ) -> Result<(CameraShadows, Vec<View>)> {
        let name = if settings.caster_culling { "shadow" } else { "shadow_no_cull" };
        let kinds = self.view_state(camera)?.graphs.spec.kinds.clone();
        let spec = GraphSpec::from_library(kinds, name)?;
        let size = RenderSettings::new(settings.resolution, settings.resolution);
        let maps = DepthArray::new(&self.ctx, "sun shadow maps", settings.resolution, settings.cascades)?;
        let compiled = self.compiled_for(&spec, &size)?;
        let main = &self.views[0].graphs.runtime;
        let (step_timing, capture) = (main.step_timing(), main.captures_draw_lists());
        let mut views = Vec::new();
        let mut ids = Vec::new();
        for cascade in 0..settings.cascades {
            let runtime = build_runtime(&self.ctx, shaders, &compiled, &spec)?;
            let mut graphs = Graphs::new(&spec, runtime, compiled.clone());
            graphs.runtime.set_step_timing(step_timing);
            graphs.runtime.capture_draw_lists(capture)?;
            let id = ViewId(self.next_view);
            self.next_view += 1;
            ids.push(id);
            views.push(View {
                id,
                settings: size.clone(),
                graphs,
                inputs: SceneInputs::new(&self.ctx, self.gpu_scene.clone(), self.light_capacity)?,
                previous_camera: None,
                adaptations: None,
                role: ViewRole::SunCascade { of: camera, cascade },
            });
        }
        let drawn_for = vec![None; ids.len()];
        Ok((CameraShadows { camera, cascades: ids, maps, state: Access::NONE, drawn_for }, views))
    }

    /// This frame's cascades of the listed camera views (`cameras`: id and camera), with
    /// each camera view's shadow constants; views without shadows get none. Points every
    /// listed camera view at its maps (or the unread fallback), and makes the fallback ready
    /// on the first frame.
    pub(super) fn plan_shadow_frame(
        &mut self,
        cmd: vk::CommandBuffer,
        cameras: &[(ViewId, &Camera)],
    ) -> Result<(Vec<CascadeFrame>, Vec<GpuSunShadows>)> {
        if !self.shadows.fallback_ready {
            let barrier = crate::gpu::barrier::image_barrier_raw(
                self.shadows.fallback.handle(),
                self.shadows.fallback.range(),
                Access::NONE,
                SAMPLED,
            );
            let barriers = [barrier];
            // SAFETY: `cmd` is recording; the image is ours and unused so far.
            unsafe {
                self.ctx
                    .device()
                    .cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers))
            };
        }
        let mut frames = Vec::new();
        let mut constants = Vec::with_capacity(cameras.len());
        let fallback = self.shadows.fallback_maps();
        let world_version = self.synced_version();
        for &(id, camera) in cameras {
            let at = self.view_index(id)?;
            let samples = self.views[at].graphs.runtime.first_pass_sampling_sun_shadows().is_some();
            let shadows = self.shadows.cameras.iter_mut().find(|c| c.camera == id);
            let (Some(settings), Some(shadows), true) = (&self.shadows.settings, shadows, samples) else {
                self.views[at].inputs.set_sun_shadow_maps(fallback);
                constants.push(GpuSunShadows::default());
                continue;
            };
            let view_settings = &self.views[at].settings;
            let aspect = view_settings.width as f32 / view_settings.height as f32;
            let fit = CascadeSettings {
                count: settings.cascades,
                distance: self.shadows.distance.max(camera.near * 2.0),
                lambda: settings.lambda,
                resolution: settings.resolution,
                caster_reach: self.shadows.reach,
            };
            // A camera the cascades cannot be fitted to (no depth range to split) is lit
            // without shadows, as the fallback says; the camera itself was checked already.
            let Ok(cascades) = fit_cascades(camera, aspect, self.scene.sun.direction, &fit) else {
                self.views[at].inputs.set_sun_shadow_maps(fallback);
                constants.push(GpuSunShadows::default());
                continue;
            };
            let mut gpu =
                GpuSunShadows { info: [cascades.len() as u32, settings.resolution, 0, 0], ..Default::default() };
            for (c, (cascade, &view)) in cascades.iter().zip(&shadows.cascades).enumerate() {
                // The camera view's eye-relative positions, moved to the cascade's eye.
                let offset = (camera.eye - cascade.camera.eye).as_vec3();
                let m = cascade.camera.view_projection_rel_eye(1.0) * Mat4::from_translation(offset);
                gpu.cascades[c] = m.to_cols_array_2d();
                gpu.texel[c] = cascade.texel as f32;
                // A map whose camera, sun and world did not change since it was drawn is kept.
                let key = MapKey { camera: cascade.camera.clone(), sun: self.scene.sun.direction, world_version };
                if shadows.drawn_for[c].as_ref() == Some(&key) && self.shadows.keep_unchanged {
                    continue;
                }
                let imports = Imports::new().image("depth", shadows.maps.layer(c as u32), shadows.state, SAMPLED);
                frames.push(CascadeFrame { view, camera: cascade.camera.clone(), imports, of: id, key });
            }
            let maps = SunShadowMaps { view: shadows.maps.array_view(), sampler: self.shadows.sampler.handle() };
            self.views[at].inputs.set_sun_shadow_maps(maps);
            constants.push(gpu);
        }
        Ok((frames, constants))
    }
}

impl Renderer {
    /// Notes what a frame planned by [`Renderer::plan_shadow_frame`] did, once it has been
    /// recorded whole: the fallback's layout, and the maps its cascades drew (a frame whose
    /// recording failed is discarded by its host, so nothing is noted for it).
    pub(super) fn shadow_frame_recorded(&mut self, cascades: Vec<CascadeFrame>) {
        self.shadows.fallback_ready = true;
        for cascade in cascades {
            let Some(shadows) = self.shadows.cameras.iter_mut().find(|c| c.camera == cascade.of) else { continue };
            if let Some(c) = shadows.cascades.iter().position(|&v| v == cascade.view) {
                shadows.drawn_for[c] = Some(cascade.key);
                shadows.state = SAMPLED;
            }
        }
    }
}

/// The caster reach and shadow distance `settings` resolve to on `scene`, or what is wrong
/// with them.
fn check_settings(scene: &Scene, settings: &ShadowSettings) -> Result<(f32, f32)> {
    let bad = |what: String| Err(Error::Invalid(format!("shadows: {what}")));
    if !(1..=MAX_CASCADES).contains(&settings.cascades) {
        return bad(format!("{} cascades; 1 to {MAX_CASCADES} are possible", settings.cascades));
    }
    if settings.resolution == 0 {
        return bad("a shadow map of 0 texels".into());
    }
    if !(0.0..=1.0).contains(&settings.lambda) {
        return bad(format!("lambda {} is outside 0 to 1", settings.lambda));
    }
    let diagonal = scene.world_bounds().map_or(100.0, |(lo, hi)| (hi - lo).length() as f32).max(1.0);
    let distance = settings.distance.unwrap_or(150f32.min(diagonal));
    let reach = settings.caster_reach.unwrap_or(diagonal);
    if !(distance.is_finite() && distance > 0.0) {
        return bad(format!("distance {distance} must be finite and positive"));
    }
    if !(reach.is_finite() && reach >= 0.0) {
        return bad(format!("caster reach {reach} must be finite and at least 0"));
    }
    if scene.sun.direction.length_squared() < 1e-12 || !scene.sun.direction.is_finite() {
        return bad(format!("the sun's direction {} must be finite and not zero", scene.sun.direction));
    }
    Ok((reach, distance))
}
