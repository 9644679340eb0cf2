//! Shadows: each camera view gets cascades of the sun fitted to its camera every frame
//! ([`crate::scene::cascades`]) and the faces of its most important spot and point lights
//! ([`crate::scene::light_faces`]); each cascade and face is a view of the renderer's world
//! running a depth-only graph (`graph/shadow.ron`) into its layer of one of the camera view's
//! two shadow-map arrays. They are recorded in lockstep with the cameras, so their culls share
//! the cameras' dispatches, and each has finished drawing before the first pass of its camera
//! that samples the maps ([`crate::graph::PassNode::samples_shadow_maps`]).

mod frame;
mod map_set;

use super::graphs::{build_runtime, Graphs};
use super::view::{View, ViewId, ViewRole};
use super::Renderer;
use crate::error::{Error, Result};
use crate::gpu::{DepthArray, GpuContext, Sampler, ShaderCompiler};
use crate::passes::shared::gpu_types::MAX_LOCAL_FACES;
use crate::passes::shared::{SceneInputs, ShadowMaps};
use crate::render::{GraphSpec, RenderSettings};
use crate::scene::cascades::MAX_CASCADES;
use crate::scene::Scene;
pub(super) use frame::ViewShadowData;
use map_set::MapSet;

/// How a renderer draws the shadows of the sun and of its views' most important spot and point
/// lights ([`Renderer::set_shadows`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowSettings {
    /// Cascades per camera view, 1 to [`MAX_CASCADES`].
    pub cascades: u32,
    /// Width and height of each cascade's map in texels (default 1024: on GPUs that rasterise
    /// few pixels a clock, such as the H100 and H200, a map's cost is its texels).
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
    /// cascade and face, in the cameras' dispatches) or all drawn (`graph/shadow_no_cull.ron`).
    pub caster_culling: bool,
    /// The most spot and point lights that cast shadows in a view, 0 to
    /// [`MAX_SHADOWED_LIGHTS`]: each frame, those that bring the most light to what the camera
    /// sees (brightest and nearest, in front of it, within `distance` of its sphere). The
    /// others light without shadows.
    pub local_lights: u32,
    /// Width and height of each spot or point light face's map in texels.
    pub local_resolution: u32,
    /// Levels of detail of the casters, in pixels of the camera view (as the culling graphs'
    /// `lod_threshold`): each caster takes the level its camera view takes at this threshold,
    /// so a shadow is cast by the surface the camera sees, and as cheaply (0: every caster
    /// whole). With `caster_culling` only (the cull pass chooses the levels).
    pub lod_threshold: f64,
}

/// The most spot and point lights [`ShadowSettings::local_lights`] allows: each may be a cube
/// of six faces, and a view holds [`crate::passes::shared::gpu_types::MAX_LOCAL_FACES`].
pub const MAX_SHADOWED_LIGHTS: u32 = (MAX_LOCAL_FACES / 6) as u32;

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            cascades: 4,
            resolution: 1024,
            distance: None,
            lambda: 0.75,
            caster_reach: None,
            caster_culling: true,
            local_lights: 2,
            local_resolution: 512,
            lod_threshold: 0.0,
        }
    }
}

/// One camera view's shadow views and maps.
pub(super) struct CameraShadows {
    /// The camera view.
    pub camera: ViewId,
    /// Its sun cascades, nearest first.
    pub sun: MapSet,
    /// Its spot and point lights' faces (as many as the most its lights can take).
    pub local: MapSet,
}

/// The renderer's shadow state.
pub(super) struct ShadowState {
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
    /// The camera views whose maps the frame being recorded puts in the sampled layout.
    made_ready: Vec<ViewId>,
}

impl ShadowState {
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
            made_ready: Vec::new(),
        })
    }

    fn fallback_maps(&self) -> ShadowMaps {
        let view = self.fallback.array_view();
        let id = self.fallback.id();
        ShadowMaps { on: false, sun: view, local: view, sampler: self.sampler.handle(), arrays: [id, id] }
    }

    /// Device memory the shadow maps take.
    pub fn bytes(&self) -> u64 {
        self.cameras.iter().map(|c| c.sun.maps.bytes() + c.local.maps.bytes()).sum()
    }
}

impl Renderer {
    /// Turns the sun's shadows on with `settings`, or off (`None`), from the next frame on.
    /// Every camera view gets its cascades; views added later get theirs when added. The
    /// sun is the scene's ([`crate::scene::Scene::sun`], `World::set_sun`).
    ///
    /// Errors: a cascade count outside 1 to 4, a resolution of 0 or beyond the device, a
    /// distance or reach that is not finite and positive, a lambda outside 0 to 1, more
    /// shadowed lights than [`MAX_SHADOWED_LIGHTS`], a level of detail threshold outside 0 to
    /// [`crate::passes::instance_cull::MAX_LOD_THRESHOLD`]; nothing changes then.
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

    /// Removes camera view `camera`'s shadow views (with the view).
    pub(super) fn remove_camera_shadows(&mut self, camera: ViewId) {
        let last_use = self.frame_index.saturating_sub(1);
        if let Some(at) = self.shadows.cameras.iter().position(|c| c.camera == camera) {
            let shadows = self.shadows.cameras.remove(at);
            let views = self.take_views(&[shadows.sun.views.as_slice(), &shadows.local.views].concat());
            self.retire_camera_shadows(shadows, views, last_use);
        }
    }

    fn drop_all_shadows(&mut self, last_use: u64) {
        for shadows in std::mem::take(&mut self.shadows.cameras) {
            let views = self.take_views(&[shadows.sun.views.as_slice(), &shadows.local.views].concat());
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
        self.retired.shadow_maps.push((last_use, shadows.sun.maps));
        self.retired.shadow_maps.push((last_use, shadows.local.maps));
    }

    /// Camera view `camera`'s cascades and light faces (views not yet in the list, with ids
    /// from `next_view` on) and their maps.
    fn make_camera_shadows(
        &mut self,
        shaders: &ShaderCompiler,
        camera: ViewId,
        settings: &ShadowSettings,
    ) -> Result<(CameraShadows, Vec<View>)> {
        let name = if settings.caster_culling { "shadow" } else { "shadow_no_cull" };
        let kinds = self.view_state(camera)?.graphs.spec.kinds.clone();
        let mut spec = GraphSpec::from_library(kinds, name)?;
        if settings.caster_culling {
            spec = spec.with_overrides([("lod_threshold".to_string(), format!("{:?}", settings.lod_threshold))]);
        }
        let mut views = Vec::new();
        let sun =
            self.make_map_set(shaders, &spec, "sun shadow maps", settings.resolution, settings.cascades, &mut views)?;
        let faces = settings.local_lights * 6;
        let local =
            self.make_map_set(shaders, &spec, "light shadow maps", settings.local_resolution, faces, &mut views)?;
        Ok((CameraShadows { camera, sun, local }, views))
    }

    /// `count` shadow views drawing `resolution`² maps through `spec` (added to `views`), with
    /// their array `name` (one layer at least, so that there is always one to bind).
    fn make_map_set(
        &mut self,
        shaders: &ShaderCompiler,
        spec: &GraphSpec,
        name: &str,
        resolution: u32,
        count: u32,
        views: &mut Vec<View>,
    ) -> Result<MapSet> {
        let maps = DepthArray::new(&self.ctx, name, resolution, count.max(1))?;
        let size = RenderSettings::new(resolution, resolution);
        let compiled = self.compiled_for(spec, &size)?;
        let main = &self.views[0].graphs.runtime;
        let (step_timing, capture) = (main.step_timing(), main.captures_draw_lists());
        let mut ids = Vec::new();
        for _ in 0..count {
            let runtime = build_runtime(&self.ctx, shaders, &compiled, spec)?;
            let mut graphs = Graphs::new(spec, runtime, compiled.clone());
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
                role: ViewRole::Shadow,
            });
        }
        let drawn_for = vec![None; ids.len()];
        Ok(MapSet { views: ids, maps, ready: false, drawn_for })
    }
}

/// The caster reach and shadow distance `settings` resolve to on `scene`, or what is wrong
/// with them.
fn check_settings(scene: &Scene, settings: &ShadowSettings) -> Result<(f32, f32)> {
    let bad = |what: String| Err(Error::Invalid(format!("shadows: {what}")));
    if !(1..=MAX_CASCADES).contains(&settings.cascades) {
        return bad(format!("{} cascades; 1 to {MAX_CASCADES} are possible", settings.cascades));
    }
    if settings.resolution == 0 || settings.local_resolution == 0 {
        return bad("a shadow map of 0 texels".into());
    }
    if settings.local_lights > MAX_SHADOWED_LIGHTS {
        return bad(format!(
            "{} shadowed spot and point lights; at most {MAX_SHADOWED_LIGHTS} are possible",
            settings.local_lights
        ));
    }
    if !(0.0..=1.0).contains(&settings.lambda) {
        return bad(format!("lambda {} is outside 0 to 1", settings.lambda));
    }
    let most = crate::passes::instance_cull::MAX_LOD_THRESHOLD;
    if !(0.0..=most).contains(&settings.lod_threshold) {
        return bad(format!("level of detail threshold {} is outside 0 to {most} pixels", settings.lod_threshold));
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
