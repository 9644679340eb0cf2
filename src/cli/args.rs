//! Argument definitions (clap derive) and value parsers.

use clap::builder::TypedValueParser;
use clap::{Args, Parser, Subcommand};
use cullgraph::scene::procedural::{MAX_INSTANCES, MAX_KINDS, MAX_LIGHTS};
use glam::DVec3;
use std::path::PathBuf;

/// Most frames a bench measures, or warms up with, per configuration.
const MAX_BENCH_FRAMES: i64 = 100_000;
/// Longest duration a flag takes, in seconds: a day.
pub const MAX_SECONDS: f64 = 86_400.0;

/// GPU-driven culling and deferred rendering of huge scenes, through Vulkan.
#[derive(Parser, Debug)]
#[command(name = "cullgraph", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene headlessly and write a PNG and (optionally) JSON stats.
    Render(Box<RenderArgs>),
    /// Fly through a scene in a window (X11), with the culling-stat overlay, graph switching,
    /// shadows, frozen culling and hot reload; H in the window lists the keys.
    View(Box<ViewArgs>),
    /// List the Vulkan devices the loader sees (index: name (type, API version)).
    Devices,
    /// Measure culling and Hi-Z speed with timestamp queries; write bench.json and bench.md.
    Bench(Box<BenchArgs>),
    /// Check a render graph (RON), print its compiled plan, or export it as graphviz.
    Graph(GraphArgs),
    /// Fuzz the graph loader and compiler or the glTF importer for a while and report the
    /// outcomes by class; inputs that break a promise are kept (exit status 1 if any).
    Fuzz(FuzzArgs),
}

/// What `cullgraph fuzz` feeds mutated inputs to.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FuzzTarget {
    /// RON graphs: load, compile at 64x48 and 3840x2160, render two frames with validation.
    Graph,
    /// glTF files: import, render two frames with validation.
    Gltf,
}

impl FuzzTarget {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            FuzzTarget::Graph => "graph",
            FuzzTarget::Gltf => "gltf",
        }
    }
}

/// `cullgraph fuzz` flags.
#[derive(Args, Debug, Clone)]
pub struct FuzzArgs {
    /// What to fuzz.
    #[arg(value_enum)]
    pub target: FuzzTarget,
    /// How long, in seconds (at most a day).
    #[arg(long, default_value_t = 60.0, value_parser = parse_seconds, allow_hyphen_values = true)]
    pub seconds: f64,
    /// Seed of the mutations (a run is reproducible from it).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Folders of further seeds (`.ron` graphs, `.glb` scenes), repeatable.
    #[arg(long = "seeds", value_name = "DIR")]
    pub seed_dirs: Vec<PathBuf>,
    /// Where failing inputs and the report go.
    #[arg(long, default_value = "out/fuzz")]
    pub out: PathBuf,
    /// Run one saved input again and print its outcome.
    #[arg(long, value_name = "FILE")]
    pub replay: Option<PathBuf>,
    /// Internal: run inputs in this process (the supervisor starts workers).
    #[arg(long, hide = true)]
    pub worker: bool,
    /// Internal: the worker's first input.
    #[arg(long, hide = true, default_value_t = 0)]
    pub start: u64,
}

/// `cullgraph graph` subcommands.
#[derive(Args, Debug)]
pub struct GraphArgs {
    /// What to do with the graph.
    #[command(subcommand)]
    pub command: GraphCommand,
}

/// What `cullgraph graph` does.
#[derive(Subcommand, Debug)]
pub enum GraphCommand {
    /// Validate a graph: prints `FILE: ok (N passes, M resources)`, or every error as
    /// `file:line:col: message` and exits with status 1. Uses the Vulkan device when there is one.
    /// What depends on the output size or the scene (buffer sizes a slot needs, expressions out of
    /// range) is checked when the graph is compiled: `graph plan`, or rendering.
    Check(GraphCheckArgs),
    /// Compile a graph for an output size and scene and print the plan: pass order, barriers,
    /// pruned passes, resources, lifetimes and transient memory.
    Plan(GraphPlanArgs),
    /// Compile a graph and write it as graphviz (passes as boxes, resources as ellipses).
    Dot(GraphDotArgs),
}

/// `cullgraph graph check` flags.
#[derive(Args, Debug)]
pub struct GraphCheckArgs {
    /// The graph file.
    pub file: PathBuf,
    /// Override a graph parameter, NAME=VALUE (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = cullgraph::graph::parse_param_override)]
    pub params: Vec<(String, String)>,
    /// Vulkan device by name substring or index; env CULLGRAPH_DEVICE.
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<String>,
    /// Also compile for this output size, WIDTHxHEIGHT, and `--scene`: checks what depends on
    /// the size and the device's limits (buffer ranges, image and attachment sizes).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// The scene whose quantities size the graph (with --size).
    #[command(flatten)]
    pub scene: SceneArgs,
}

/// `cullgraph bench` flags.
#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// What to measure, comma-separated: `culling` (the culling graphs on cities of growing
    /// size), `hiz` (the pyramid builds), `msaa` (speed against error of every anti-aliasing
    /// method), `dynamic` (instances moved, inserted and removed every frame), `views` (1 to
    /// 64 views of the largest `--instances` city in one frame, memory per view, resizing),
    /// `shadows` (the largest city's frame and passes with sun shadows off, on with every
    /// caster drawn and on with caster culling; the maps' memory and image error).
    #[arg(long, value_delimiter = ',', default_values_t = ["culling".to_string(), "hiz".into()])]
    pub suites: Vec<String>,
    /// Instances moved per frame in the `dynamic` suite (on the largest `--instances` city),
    /// comma-separated, at most that city's instances [default: 1000,10000,100000,1000000, those
    /// the city has].
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u64).range(1..=MAX_INSTANCES as u64).map(|n| n as usize))]
    pub moved: Vec<usize>,
    /// City sizes to measure (instances), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [10_000usize, 100_000, 1_000_000], value_parser = clap::value_parser!(u64).range(1..=MAX_INSTANCES as u64).map(|n| n as usize))]
    pub instances: Vec<usize>,
    /// Graphs to compare, comma-separated: names of the built-in ones, or RON files (`.ron`).
    #[arg(long, value_delimiter = ',', default_values_t = ["no_cull".to_string(), "frustum".into(), "two_phase".into(), "occluder_prepass".into(), "one_phase".into()])]
    pub graphs: Vec<String>,
    /// Output size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1920x1080", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Hi-Z sizes, comma-separated WIDTHxHEIGHT.
    #[arg(long, value_delimiter = ',', value_parser = parse_size, default_values = ["1920x1080", "3840x2160"])]
    pub hiz_sizes: Vec<(u32, u32)>,
    /// Frames before measuring.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=MAX_BENCH_FRAMES))]
    pub warmup: u32,
    /// Frames measured (medians are reported).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=MAX_BENCH_FRAMES))]
    pub frames: u32,
    /// Also check one frame per graph against exact visibility.
    #[arg(long)]
    pub verify: bool,
    /// Also time each step of multi-dispatch passes (`pass/step` rows; the timestamps between
    /// steps may add a little time to those passes).
    #[arg(long)]
    pub step_times: bool,
    /// MSAA suite: scenes, comma-separated (`builtin:city` or glTF files).
    #[arg(long, value_delimiter = ',', default_values_t = ["builtin:city".to_string()])]
    pub msaa_scenes: Vec<String>,
    /// MSAA suite: camera position x,y,z for every scene (default: each scene's own view).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, requires = "msaa_target")]
    pub msaa_eye: Option<DVec3>,
    /// MSAA suite: the point the camera looks at, x,y,z (with `--msaa-eye`).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, requires = "msaa_eye")]
    pub msaa_target: Option<DVec3>,
    /// MSAA suite: the methods (built-in graphs), comma-separated; `two_phase` (no AA) and
    /// `fxaa` run at one sample, the others at each of `--msaa-samples`.
    #[arg(long, value_delimiter = ',', default_values_t = cullgraph::bench::msaa::ONE_SAMPLE_METHODS.iter().chain(cullgraph::bench::msaa::MSAA_METHODS).map(|m| m.to_string()))]
    pub msaa_methods: Vec<String>,
    /// Views suite: the view counts, comma-separated (each from 1 to the most a renderer holds).
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 2, 4, 8, 16, cullgraph::render::MAX_VIEWS], value_parser = parse_view_count)]
    pub view_counts: Vec<usize>,
    /// Views suite: every view's levels of detail at this threshold in pixels (0: full detail),
    /// chosen by the views culled together in their own pixels.
    #[arg(long, default_value_t = 0.0, value_name = "PX", value_parser = parse_lod_threshold)]
    pub views_lod_threshold: f64,
    /// MSAA suite: sample counts, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [2u32, 4, 8], value_parser = parse_msaa_samples)]
    pub msaa_samples: Vec<u32>,
    /// MSAA suite: point-light counts, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [5usize, 50, 500], value_parser = clap::value_parser!(u64).range(0..=MAX_LIGHTS as u64).map(|n| n as usize))]
    pub msaa_lights: Vec<usize>,
    /// Shadows suite: sun cascades (1 to 4).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=4))]
    pub shadow_cascades: u32,
    /// Shadows suite: texels per side of each cascade's map.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub shadow_resolution: u32,
    /// Levels-of-detail suite: scenes, comma-separated (`builtin:NAME` or glTF files), each
    /// optionally with `@INSTANCES`.
    #[arg(long, value_delimiter = ',', default_values_t = ["builtin:dense".to_string(), "builtin:city".into()])]
    pub lod_scenes: Vec<String>,
    /// Levels-of-detail suite: thresholds in pixels, comma-separated (0 is always measured: the
    /// full detail every other is compared with).
    #[arg(long, value_delimiter = ',', default_values_t = cullgraph::bench::lod::DEFAULT_THRESHOLDS.to_vec(), value_parser = parse_lod_threshold)]
    pub lod_thresholds: Vec<f64>,
    /// The LOD suite: cluster culling off, on, or both (each threshold runs with each).
    #[arg(long, value_delimiter = ',', default_values = ["off", "on"], value_parser = parse_on_off, value_name = "off,on")]
    pub lod_clusters: Vec<bool>,
    /// MSAA, shadows and levels-of-detail suites: the reference's supersampling per axis (4: 16
    /// samples per pixel; 0: no image error against a reference).
    #[arg(long, default_value_t = 4, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=64))]
    pub reference: u32,
    /// Masked materials keep all or none of a pixel's samples (a plain alpha test) instead of
    /// a share by alpha-to-coverage, in every pass and the oracle: to measure what
    /// alpha-to-coverage costs and gains.
    #[arg(long)]
    pub alpha_test: bool,
    /// Folder for bench.json, bench.md and the plots (culling.svg, msaa.svg).
    #[arg(long, default_value = "out/bench")]
    pub out: PathBuf,
    /// Vulkan device by name substring or index; env CULLGRAPH_DEVICE.
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<String>,
}

/// Which scene to load and how to generate it.
#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene: `builtin:city`, `builtin:field`, or a glTF 2.0 file (.gltf/.glb).
    #[arg(long, default_value = "builtin:city")]
    pub scene: String,
    /// Number of instances of a built-in scene (default 10,000; at most what the device's
    /// bindings address, 134,217,726 on NVIDIA and AMD, and what the machine's and the device's
    /// memory hold: a larger scene is refused with the limit or the memory it needs).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=MAX_INSTANCES as u64).map(|n| n as usize))]
    pub instances: Option<usize>,
    /// Number of distinct mesh kinds of `builtin:field` (default 64, at most 100,000).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=MAX_KINDS as u64).map(|n| n as usize))]
    pub kinds: Option<usize>,
    /// Number of point lights (built-in scenes; files get them only when they have none; at
    /// most 1,000,000).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(0..=MAX_LIGHTS as u64).map(|n| n as usize))]
    pub lights: Option<usize>,
    /// Seed of the built-in generators.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl SceneArgs {
    /// Loads or generates the scene.
    pub fn load(&self) -> cullgraph::Result<cullgraph::scene::Scene> {
        let source: cullgraph::scene::SceneSource = self.scene.parse()?;
        let options = cullgraph::scene::source::LoadOptions {
            instances: self.instances,
            kinds: self.kinds,
            lights: self.lights,
            seed: self.seed,
        };
        Ok(source.load(&options)?)
    }

    /// Refuses a built-in scene whose memory `room` does not hold (used as `usage`), naming the
    /// flags that size it; a scene file is not checked (its size is bounded by the file's).
    /// Returns what the scene needs.
    pub fn check_memory(
        &self,
        room: &super::memory::Room,
        usage: super::memory::Use,
    ) -> cullgraph::Result<super::memory::Need> {
        use cullgraph::scene::procedural::{city, field};
        let Ok(cullgraph::scene::SceneSource::Builtin(name)) = self.scene.parse() else {
            return Ok(Default::default());
        };
        let (instances, kinds, lights) = match name.as_str() {
            "city" => (city::DEFAULT_INSTANCES, 0, city::DEFAULT_LIGHTS),
            "field" => (field::DEFAULT_INSTANCES, self.kinds.unwrap_or(field::DEFAULT_KINDS), field::DEFAULT_LIGHTS),
            _ => return Ok(Default::default()), // the generator names the scenes it has
        };
        let instances = self.instances.unwrap_or(instances);
        let size = super::memory::SceneSize {
            instances: instances as u64,
            kinds: kinds as u64,
            lights: self.lights.unwrap_or(lights) as u64,
        };
        let mut value = instances.to_string();
        if self.instances.is_none() {
            value.push_str(" (the default)");
        }
        if let Some(k) = self.kinds.filter(|_| name == "field") {
            value.push_str(&format!(" with --kinds {k}"));
        }
        let need = super::memory::Need::of(size, usage);
        room.check("--instances", &value, need)?;
        Ok(need)
    }
}

/// The output size and scene a graph is compiled for.
#[derive(Args, Debug)]
pub struct GraphFrameArgs {
    /// Output size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The scene whose quantities (instances, meshes, lights, materials, triangles) size the graph.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Vulkan device whose limits the sizes are checked against; env CULLGRAPH_DEVICE.
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<String>,
}

/// `cullgraph graph plan` flags.
#[derive(Args, Debug)]
pub struct GraphPlanArgs {
    /// The graph file.
    pub file: PathBuf,
    /// Override a graph parameter, NAME=VALUE (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = cullgraph::graph::parse_param_override)]
    pub params: Vec<(String, String)>,
    /// Size and scene.
    #[command(flatten)]
    pub frame: GraphFrameArgs,
}

/// `cullgraph graph dot` flags.
#[derive(Args, Debug)]
pub struct GraphDotArgs {
    /// The graph file.
    pub file: PathBuf,
    /// Write here instead of standard output.
    #[arg(short = 'o', long = "out", value_name = "FILE.dot")]
    pub out: Option<PathBuf>,
    /// Override a graph parameter, NAME=VALUE (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = cullgraph::graph::parse_param_override)]
    pub params: Vec<(String, String)>,
    /// Size and scene.
    #[command(flatten)]
    pub frame: GraphFrameArgs,
}

/// `cullgraph render` flags.
#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The camera.
    #[command(flatten)]
    pub camera: CameraArgs,
    /// A view of the world, `eye=X,Y,Z;target=X,Y,Z;fov=DEG;size=WxH` (repeatable; every key
    /// but eye and target optional, size defaults to `--size`): all views are rendered each
    /// frame over one copy of the scene, each with its own culling history. `--out F.png`
    /// then writes `F.view0.png`, `F.view1.png`, ..., and `--stats` each view's figures
    /// under `views`.
    #[arg(
        long = "view",
        value_name = "eye=X,Y,Z;target=X,Y,Z;fov=DEG;size=WxH",
        value_parser = super::views::parse_view,
        allow_hyphen_values = true,
        conflicts_with_all = ["eye", "target", "watch", "reference"]
    )]
    pub views: Vec<super::views::ViewArg>,
    /// From frame N on, the output (or every view) is WxH (repeatable), e.g. `--resize
    /// 640x360@10`: the renderer keeps the scene and rebuilds only what depends on the size.
    #[arg(long = "resize", value_name = "WxH@N", value_parser = super::views::parse_resize, conflicts_with = "watch")]
    pub resizes: Vec<((u32, u32), u32)>,
    /// Projection (all reversed-Z): `infinite` (perspective without a far plane, the default),
    /// `far:D` (perspective whose far plane at distance D culls), `ortho:H` (orthographic, H world
    /// units tall, far plane just past the scene) or `offcenter:L,R,U,D` (asymmetric perspective,
    /// as a VR eye's: the left, right, up and down edges in degrees from the view axis, in the
    /// OpenXR sense, so left and down are usually negative).
    #[arg(long, value_name = "KIND", value_parser = parse_projection, allow_hyphen_values = true)]
    pub projection: Option<ProjectionArg>,
    /// Sub-pixel jitter of each frame, as temporal anti-aliasing uses: `halton` (the Halton(2, 3)
    /// sequence, centred on the pixel) or a fixed `X,Y` in pixels (+y down, at most 1).
    #[arg(long, value_name = "halton|X,Y", value_parser = parse_jitter, allow_hyphen_values = true)]
    pub jitter: Option<JitterArg>,
    /// Number of frames to render (stats are recorded for each; the image is the last frame).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub frames: u32,
    /// Output image (PNG).
    #[arg(long, default_value = "out/frame.png")]
    pub out: PathBuf,
    /// Write per-frame statistics as JSON to this file.
    #[arg(long, value_name = "PATH")]
    pub stats: Option<PathBuf>,
    /// Write the last frame's linear HDR colour (the graph's output `hdr`, before tone mapping)
    /// as a 32-bit float OpenEXR image (RGBA). `builtin:post` has it.
    #[arg(long, value_name = "FILE.exr")]
    pub hdr_out: Option<PathBuf>,
    /// Write the last frame's motion vectors (the graph's output `motion`: pixels from this
    /// frame's position to the last frame's, x right, y down) as a 32-bit float OpenEXR image
    /// (R = x, G = y, B = 0). `builtin:post` has it.
    #[arg(long, value_name = "FILE.exr")]
    pub motion_out: Option<PathBuf>,
    /// Write the last frame's depth (the graph's output `depth_resolved`, else `depth`:
    /// reversed-Z, 1 at the near plane, 0 for the background) as a 32-bit float OpenEXR image
    /// (R = G = B = depth). `builtin:post` has it.
    #[arg(long, value_name = "FILE.exr")]
    pub depth_out: Option<PathBuf>,
    /// Render graph to run: a RON file, or `builtin:NAME` for one shipped in `graph/`
    /// (default, no_cull, frustum, ...). Default: `graph/default.ron`.
    #[arg(long, value_name = "FILE.ron|builtin:NAME")]
    pub graph: Option<String>,
    /// Render without culling (the built-in `no_cull` graph).
    #[arg(long, conflicts_with = "graph")]
    pub no_cull: bool,
    /// Draw the culling-stat overlay: this frame's counters, GPU milliseconds per pass (the built-in
    /// `overlay` graph, i.e. the default graph plus an overlay pass).
    #[arg(long, conflicts_with_all = ["graph", "no_cull"])]
    pub overlay: bool,
    /// What the overlay shows: stats (the panel), hiz (plus a Hi-Z mip in grey; `--param
    /// hiz_level=N`) or culled (plus occlusion-culled instances tinted red). Implies
    /// `--overlay` unless `--graph` names a graph with an `overlay_view` param.
    #[arg(long, value_name = "VIEW", value_parser = ["stats", "hiz", "culled"], conflicts_with = "no_cull")]
    pub overlay_view: Option<String>,
    /// Check every frame against exact visibility (an unculled instance-id render) and report
    /// visible instances, false negatives and false positives; fails if anything visible was culled.
    #[arg(long)]
    pub verify: bool,
    /// Let the compressed G-buffer's pool follow the frames' needs (counters read back a few
    /// frames late): grow when fragments were dropped, shrink after 30 mostly empty frames. It
    /// starts from the graph's `pool_fraction` (blocks per pixel; `--param pool_fraction=F`
    /// overrides it).
    #[arg(long)]
    pub pool_adapt: bool,
    /// Also time each step of multi-dispatch passes (`pass/step` entries in the stats JSON's
    /// `gpu_ms`; the timestamps between steps may add a little time to those passes).
    #[arg(long)]
    pub step_times: bool,
    /// Also render the last frame's supersampled reference: the same scene, camera and frame
    /// through `builtin:no_cull` (no AA) at N times the size, box-filtered down in linear light
    /// (N x N samples per pixel; N defaults to 4), and report the image's mean FLIP and PSNR
    /// against it (stats JSON: `reference`).
    #[arg(
        long,
        value_name = "N",
        num_args = 0..=1,
        default_missing_value = "4",
        value_parser = clap::value_parser!(u32).range(1..=64),
        conflicts_with = "watch"
    )]
    pub reference: Option<u32>,
    /// Move the scene and the camera together by x,y,z (large-world precision check).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, value_name = "x,y,z")]
    pub world_offset: Option<DVec3>,
    /// Replace the scene's sun by the default sun shining from direction x,y,z (towards the
    /// sun, any length but zero).
    #[arg(long, value_parser = parse_sun, allow_hyphen_values = true, value_name = "x,y,z")]
    pub sun: Option<glam::Vec3>,
    /// Shadows of the sun, on or off: each view gets `--cascades` cascades fitted to its
    /// camera, each a depth-only view culled in the camera's dispatches.
    #[arg(long, action = clap::ArgAction::Set, value_parser = parse_on_off, default_value = "off", value_name = "on|off")]
    pub shadows: bool,
    /// Sun shadow cascades per view, 1 to 4 (with --shadows on).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=4))]
    pub cascades: u32,
    /// With --shadows on: draw every caster into every cascade instead of culling them (the
    /// baseline caster culling is measured against; the image is the same).
    #[arg(long)]
    pub no_caster_cull: bool,
    /// Move the camera over the frames: still, orbit, dolly or shake.
    #[arg(long, default_value = "still", value_parser = parse_camera_path)]
    pub camera_path: cullgraph::scene::CameraPath,
    /// `builtin:city` with traffic: vehicles drive along the streets (one per 50 instances),
    /// leave at the edge and are replaced, and a few are removed and added mid-street every
    /// second; the renderer applies the changes each frame (30 frames a second of traffic).
    #[arg(long)]
    pub animate: bool,
    /// Stream the scene into a live world in N pieces (slabs along its longest axis): frame 0
    /// draws the first piece, and each following frame adds one more. Each piece registers only the meshes,
    /// materials and textures that earlier pieces did not, and the renderer applies it at once
    /// (a line per piece reports what it added and what the sync cost).
    #[arg(long, value_name = "N", conflicts_with = "animate", value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub stream: Option<u32>,
    /// Override a graph parameter, NAME=VALUE (repeatable), e.g. `--param exposure=1.2`.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = cullgraph::graph::parse_param_override)]
    pub params: Vec<(String, String)>,
    /// Shorthand for `--param debug_view=VIEW`: none, normals, albedo, depth, samples (distinct surfaces per pixel, MSAA graphs) or cascades (the lit image tinted by the shadow cascade of each pixel: red, green, blue, yellow from the nearest).
    #[arg(long, value_name = "VIEW")]
    pub debug_view: Option<String>,
    /// Levels of detail: each drawn instance takes the coarsest level of its mesh whose error,
    /// projected conservatively, is at most PX pixels (0: full meshes, the default). Shorthand
    /// for `--param lod_threshold=PX` (the shipped culling graphs have it); with `--shadows on`
    /// the shadow casters take the camera's levels.
    #[arg(long, value_name = "PX", value_parser = parse_lod_threshold, allow_hyphen_values = true)]
    pub lod_threshold: Option<f64>,
    /// Cluster culling: before each draw of a culled list, a `cluster_cull` pass tests the
    /// clusters of its instances (frustum, normal cone, Hi-Z) and the draw takes them cluster by
    /// cluster; the image does not change. `on` runs the graph's cluster variant
    /// (`two_phase_clusters` for the default, `frustum_clusters` and `occluder_prepass_clusters`
    /// for those built-in graphs).
    #[arg(long, action = clap::ArgAction::Set, value_parser = parse_on_off, default_value = "off", value_name = "on|off")]
    pub clusters: bool,
    /// Keep rendering; recompile when the graph file or a shader changes (on error the last
    /// good graph keeps running and the error is printed). Stop with Ctrl-C.
    #[arg(long)]
    pub watch: bool,
    /// With --watch: stop after this many seconds (at most a day).
    #[arg(long, value_name = "SECONDS", requires = "watch", value_parser = parse_seconds, allow_hyphen_values = true)]
    pub watch_for: Option<f64>,
    /// Device, validation and shaders.
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Which device renders, whether the validation layer watches, and where shaders come from.
#[derive(Args, Debug, Clone)]
pub struct GpuArgs {
    /// Vulkan device by name substring or index (see `cullgraph devices`); env CULLGRAPH_DEVICE.
    #[arg(long, value_name = "NAME|INDEX")]
    pub device: Option<String>,
    /// Enable the Khronos validation layer with synchronization validation (exit status 1 if
    /// it reported anything).
    #[arg(long)]
    pub validation: bool,
    /// Read shaders from this directory (reloaded when they change, with `--watch` and in
    /// `view`) instead of the copies built into the binary (env CULLGRAPH_SHADER_DIR).
    #[arg(long, value_name = "DIR")]
    pub shader_dir: Option<PathBuf>,
}

impl GpuArgs {
    /// Refuses a `--shader-dir` that is not a readable directory, before anything is made.
    pub fn check(&self) -> cullgraph::Result<()> {
        match &self.shader_dir {
            Some(dir) => super::paths::input_dir("--shader-dir", dir),
            None => Ok(()),
        }
    }

    /// Context options for this device and validation (`CULLGRAPH_VALIDATION=1` turns it on
    /// too), named `app_name`.
    pub fn context_options(&self, app_name: &str) -> cullgraph::gpu::ContextOptions {
        use cullgraph::gpu::{ContextOptions, DeviceSelector};
        ContextOptions {
            device: DeviceSelector::or_from_env(self.device.as_deref().map(|d| d.parse().unwrap_or_default())),
            validation: self.validation || ContextOptions::default().validation,
            app_name: app_name.into(),
            ..Default::default()
        }
    }

    /// The shader compiler: from `--shader-dir`, else as `CULLGRAPH_SHADER_DIR` says.
    pub fn shaders(&self) -> cullgraph::Result<cullgraph::gpu::ShaderCompiler> {
        use cullgraph::gpu::ShaderRoot;
        let root = match &self.shader_dir {
            Some(dir) => ShaderRoot::Directory(dir.clone()),
            None => ShaderRoot::from_env(),
        };
        Ok(cullgraph::gpu::ShaderCompiler::new(root)?)
    }
}

/// Where the camera is and how it sees, over the scene's default view.
#[derive(Args, Debug, Clone)]
pub struct CameraArgs {
    /// Camera position x,y,z (default: the scene's camera, or a view that frames the scene).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<DVec3>,
    /// Point the camera looks at, x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<DVec3>,
    /// Vertical field of view in degrees (perspective).
    #[arg(long, value_name = "DEG")]
    pub fov: Option<f32>,
    /// Near-plane distance.
    #[arg(long)]
    pub near: Option<f32>,
}

impl CameraArgs {
    /// `camera` with the flags given applied.
    pub fn apply(&self, mut camera: cullgraph::scene::Camera) -> cullgraph::scene::Camera {
        if let Some(eye) = self.eye {
            camera.eye = eye;
        }
        if let Some(target) = self.target {
            camera.target = target;
        }
        if let Some(fov_y_deg) = self.fov {
            camera.projection = cullgraph::scene::Projection::Perspective { fov_y_deg };
        }
        if let Some(near) = self.near {
            camera.near = near;
        }
        camera
    }
}

/// `cullgraph view` flags.
#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Window size in pixels, WIDTHxHEIGHT (the frame follows the window when it is resized).
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The camera to start at.
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Player spawn points, lines of `MAP x,y,z x,y,z` (eye, target); default:
    /// `nexuiz_spawns.txt` beside a scene file, when there is one. C jumps to the next.
    #[arg(long, value_name = "FILE")]
    pub spawns: Option<PathBuf>,
    /// Render graph to start with: a RON file (reloaded when it or a shader changes), or
    /// `builtin:NAME`. G and Shift+G step through the built-in graphs.
    #[arg(long, value_name = "FILE.ron|builtin:NAME")]
    pub graph: Option<String>,
    /// Start with the culling-stat overlay on (O toggles it).
    #[arg(long)]
    pub overlay: bool,
    /// Override a graph parameter, NAME=VALUE (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = cullgraph::graph::parse_param_override)]
    pub params: Vec<(String, String)>,
    /// Shadows of the sun and the nearest lights, on or off (L toggles them).
    #[arg(long, action = clap::ArgAction::Set, value_parser = parse_on_off, default_value = "off", value_name = "on|off")]
    pub shadows: bool,
    /// Sun shadow cascades per view, 1 to 4.
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=4))]
    pub cascades: u32,
    /// Start with the city's traffic running (T toggles it; `builtin:city` only).
    #[arg(long)]
    pub animate: bool,
    /// Present FIFO (wait for the display's refresh) instead of mailbox or immediate.
    #[arg(long)]
    pub vsync: bool,
    /// Present this many frames, then exit (with --screenshot: write the last one).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub frames: Option<u32>,
    /// Where screenshots go: with --frames, the last presented frame; P writes here too
    /// (default: out/view-N.png).
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
    /// Play timed input from FILE: lines `FRAME key NAME down|up`, `FRAME press NAME`,
    /// `FRAME look DX DY`, `FRAME wheel N`, `FRAME resize WxH` (frames advance 1/60 s each).
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// Device, validation and shaders.
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT (e.g. 1280x720)"))?;
    let parse = |v: &str, what: &str| -> Result<u32, String> {
        let n: u32 = v.trim().parse().map_err(|_| format!("{what} '{v}' in '{s}' is not a whole number"))?;
        if n == 0 || n > 16384 {
            return Err(format!("{what} {n} in '{s}' must be between 1 and 16384"));
        }
        Ok(n)
    };
    Ok((parse(w, "width")?, parse(h, "height")?))
}

/// Parses a duration in seconds: a finite number from 0 to [`MAX_SECONDS`].
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    let seconds: f64 = s.trim().parse().map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if !(0.0..=MAX_SECONDS).contains(&seconds) {
        return Err(format!("{s} seconds is not between 0 and {MAX_SECONDS} (a day)"));
    }
    Ok(seconds)
}

/// Parses a level-of-detail threshold in pixels: a finite number from 0 to the kind's largest.
fn parse_lod_threshold(s: &str) -> Result<f64, String> {
    let most = cullgraph::passes::instance_cull::MAX_LOD_THRESHOLD;
    match s.trim().parse::<f64>() {
        Ok(px) if (0.0..=most).contains(&px) => Ok(px),
        _ => Err(format!("'{s}' is not a threshold in pixels from 0 to {most}")),
    }
}

/// Parses an MSAA sample count the bench measures: 2, 4 or 8.
fn parse_msaa_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n @ (2 | 4 | 8)) => Ok(n),
        _ => Err(format!("'{s}' is not a sample count the MSAA methods take: 2, 4 or 8")),
    }
}

/// Parses a camera path name.
pub fn parse_camera_path(s: &str) -> Result<cullgraph::scene::CameraPath, String> {
    s.parse()
}

/// `--projection`: which projection, with its numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProjectionArg {
    /// `infinite`: perspective without a far plane.
    Infinite,
    /// `far:D`: perspective with a far plane at `D`.
    Far(f32),
    /// `ortho:H`: orthographic, `H` world units tall.
    Ortho(f32),
    /// `offcenter:L,R,U,D`: edge angles in degrees.
    OffCenter([f32; 4]),
}

impl std::fmt::Display for ProjectionArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ProjectionArg::Infinite => write!(f, "infinite"),
            ProjectionArg::Far(d) => write!(f, "far:{d}"),
            ProjectionArg::Ortho(h) => write!(f, "ortho:{h}"),
            ProjectionArg::OffCenter([l, r, u, d]) => write!(f, "offcenter:{l},{r},{u},{d}"),
        }
    }
}

/// Parses `infinite`, `far:D`, `ortho:H` or `offcenter:L,R,U,D`; the numbers must be finite
/// and positive (distances) or inside (−90, 90) degrees with left < right and down < up.
pub fn parse_projection(s: &str) -> Result<ProjectionArg, String> {
    let number = |p: &str, what: &str| -> Result<f32, String> {
        let x: f32 = p.trim().parse().map_err(|_| format!("{what} '{p}' in '{s}' is not a number"))?;
        if x.is_finite() {
            Ok(x)
        } else {
            Err(format!("{what} '{p}' in '{s}' is not finite"))
        }
    };
    let positive = |p: &str, what: &str| {
        let x = number(p, what)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(format!("{what} {x} in '{s}' must be positive"))
        }
    };
    let (kind, rest) = s.split_once(':').unwrap_or((s, ""));
    match (kind, rest) {
        ("infinite", "") => Ok(ProjectionArg::Infinite),
        ("far", d) if !d.is_empty() => Ok(ProjectionArg::Far(positive(d, "far distance")?)),
        ("ortho", h) if !h.is_empty() => Ok(ProjectionArg::Ortho(positive(h, "orthographic height")?)),
        ("offcenter", angles) if !angles.is_empty() => {
            let parts: Vec<&str> = angles.split(',').collect();
            if parts.len() != 4 {
                return Err(format!("'{s}' is not offcenter:LEFT,RIGHT,UP,DOWN (four angles in degrees)"));
            }
            let mut a = [0.0f32; 4];
            for ((slot, p), what) in a.iter_mut().zip(&parts).zip(["left", "right", "up", "down"]) {
                *slot = number(p, &format!("{what} angle"))?;
                if !(*slot > -90.0 && *slot < 90.0) {
                    return Err(format!("{what} angle {slot} in '{s}' must be in (-90, 90) degrees"));
                }
            }
            let [l, r, u, d] = a;
            if !(l < r && d < u) {
                return Err(format!("'{s}' needs left < right and down < up (left {l}, right {r}, up {u}, down {d})"));
            }
            Ok(ProjectionArg::OffCenter(a))
        }
        _ => Err(format!("'{s}' is not infinite, far:D, ortho:H or offcenter:L,R,U,D")),
    }
}

/// `--jitter`: the Halton sequence, or one fixed jitter in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JitterArg {
    /// Halton(2, 3), one point per frame.
    Halton,
    /// The same jitter every frame.
    Fixed(glam::Vec2),
}

impl JitterArg {
    /// The jitter of frame `frame`, in pixels.
    pub fn at(&self, frame: u32) -> glam::Vec2 {
        match *self {
            JitterArg::Halton => cullgraph::scene::projection::halton_jitter(frame as u64),
            JitterArg::Fixed(j) => j,
        }
    }
}

/// Parses `halton` or `X,Y` (pixels, each finite and at most 1 in magnitude).
pub fn parse_jitter(s: &str) -> Result<JitterArg, String> {
    if s == "halton" {
        return Ok(JitterArg::Halton);
    }
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 2 {
        return Err(format!("'{s}' is not halton or X,Y (pixels)"));
    }
    let mut v = [0.0f32; 2];
    for (slot, p) in v.iter_mut().zip(&parts) {
        let x: f32 = p.trim().parse().map_err(|_| format!("'{p}' in '{s}' is not a number"))?;
        if x.is_nan() || x.abs() > 1.0 {
            return Err(format!("'{p}' in '{s}' must be a sub-pixel jitter, at most 1 pixel in magnitude"));
        }
        *slot = x;
    }
    Ok(JitterArg::Fixed(glam::Vec2::from_array(v)))
}

/// Parses `on` or `off`.
pub fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("'{s}' is neither on nor off")),
    }
}

/// Parses `--sun x,y,z`: a direction towards the sun, finite and not zero.
pub fn parse_sun(s: &str) -> Result<glam::Vec3, String> {
    let v = parse_vec3(s)?.as_vec3();
    if !v.is_finite() || v.length_squared() < 1e-12 {
        return Err(format!("'{s}' is no direction: the sun's must be finite and not zero"));
    }
    Ok(v.normalize())
}

/// Parses `x,y,z` into finite numbers.
pub fn parse_vec3(s: &str) -> Result<DVec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("'{s}' is not x,y,z"));
    }
    let mut v = [0.0f64; 3];
    for (slot, p) in v.iter_mut().zip(&parts) {
        let x: f64 = p.trim().parse().map_err(|_| format!("'{p}' in '{s}' is not a number"))?;
        if !x.is_finite() {
            return Err(format!("'{p}' in '{s}' is not finite"));
        }
        *slot = x;
    }
    Ok(DVec3::from_array(v))
}

/// A view count of the views suite: 1 to [`cullgraph::render::MAX_VIEWS`].
fn parse_view_count(s: &str) -> std::result::Result<usize, String> {
    let n: usize = s.trim().parse().map_err(|_| format!("'{s}' is not a view count"))?;
    if n == 0 || n > cullgraph::render::MAX_VIEWS {
        return Err(format!("{n} views: a renderer holds 1 to {}", cullgraph::render::MAX_VIEWS));
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_projections_and_jitter_with_clear_errors() {
        assert_eq!(parse_projection("infinite"), Ok(ProjectionArg::Infinite));
        assert_eq!(parse_projection("far:250"), Ok(ProjectionArg::Far(250.0)));
        assert_eq!(parse_projection("ortho:12.5"), Ok(ProjectionArg::Ortho(12.5)));
        assert_eq!(
            parse_projection("offcenter:-45,40,42,-50"),
            Ok(ProjectionArg::OffCenter([-45.0, 40.0, 42.0, -50.0]))
        );
        assert!(parse_projection("far:-3").unwrap_err().contains("must be positive"));
        assert!(parse_projection("far:").unwrap_err().contains("is not infinite, far:D"));
        assert!(parse_projection("ortho:nan").unwrap_err().contains("not finite"));
        assert!(parse_projection("offcenter:-45,40,42").unwrap_err().contains("four angles"));
        assert!(parse_projection("offcenter:-95,40,42,-50").unwrap_err().contains("(-90, 90)"));
        assert!(parse_projection("offcenter:40,-45,42,-50").unwrap_err().contains("left < right"));
        assert!(parse_projection("fisheye").unwrap_err().contains("is not infinite"));
        assert_eq!(parse_jitter("halton"), Ok(JitterArg::Halton));
        assert_eq!(parse_jitter("0.25,-0.5"), Ok(JitterArg::Fixed(glam::Vec2::new(0.25, -0.5))));
        assert!(parse_jitter("3,0").unwrap_err().contains("at most 1 pixel"));
        assert!(parse_jitter("nan,0").unwrap_err().contains("at most 1 pixel"));
        assert!(parse_jitter("1").unwrap_err().contains("halton or X,Y"));
        assert_eq!(JitterArg::Halton.at(0), cullgraph::scene::projection::halton_jitter(0));
    }

    #[test]
    fn parses_sizes_and_vectors_with_clear_errors() {
        assert_eq!(parse_size("1920x1080"), Ok((1920, 1080)));
        assert!(parse_size("0x10").unwrap_err().contains("between 1 and 16384"));
        assert!(parse_size("100").unwrap_err().contains("WIDTHxHEIGHT"));
        assert!(parse_size("axb").unwrap_err().contains("not a whole number"));
        assert_eq!(parse_vec3("1,-2.5,3e7"), Ok(DVec3::new(1.0, -2.5, 3e7)));
        assert_eq!(parse_sun("0,2,0"), Ok(glam::Vec3::Y));
        for bad in ["0,0,0", "1e-30,0,0", "1e300,0,0", "nan,1,0", "1,2"] {
            assert!(parse_sun(bad).is_err(), "{bad}");
        }
        assert!(parse_vec3("1,2").is_err());
        assert!(parse_vec3("1,nan,2").unwrap_err().contains("not finite"));
        assert_eq!(parse_seconds("1.5"), Ok(1.5));
        assert_eq!(parse_seconds("86400"), Ok(86_400.0));
        for bad in ["inf", "NaN", "-1", "86401", "1e300", "x"] {
            assert!(parse_seconds(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_msaa_samples("8"), Ok(8));
        assert!(parse_msaa_samples("3").unwrap_err().contains("2, 4 or 8"));
    }
}
