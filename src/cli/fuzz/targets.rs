//! The two fuzz targets and how their outcomes are classified.
//!
//! - `graph`: a RON graph is checked as `graph check --size` checks it (loaded against the
//!   device, compiled at 64x48 for a small city and at 3840x2160 for 10^6 instances) and, when
//!   the check passes, rendered for two frames with validation on: a graph that passes the check
//!   must render (else the check lied).
//! - `gltf`: a glTF file is imported, and, when it imports, rendered for two frames with
//!   validation on.

use cullgraph::gpu::{GpuContext, ShaderCompiler};
use cullgraph::graph::{self, DeviceEnv, FrameInputs};
use cullgraph::passes::builtin_kinds;
use cullgraph::passes::shared::frame_inputs;
use cullgraph::render::graph_spec::shown_image_error;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Scene, SceneError, SceneSource};
use serde_json::{json, Value};
use std::path::Path;

/// What one input did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Class {
    /// Accepted (and rendered without a validation message).
    Ok,
    /// Refused with an error that names its place.
    Positioned,
    /// Refused with an error that does not say where.
    Unpositioned,
    /// A validation-layer message while rendering something that was accepted.
    Validation,
    /// A graph that passed the check (load and compile) and failed to render.
    CheckLied,
    /// A panic (caught).
    Panic,
    /// The process died (stack overflow, abort, signal).
    Crash,
    /// No answer within the hang limit.
    Hang,
}

impl Class {
    /// Every class, in report order.
    pub const ALL: [Class; 8] = [
        Class::Ok,
        Class::Positioned,
        Class::Unpositioned,
        Class::Validation,
        Class::CheckLied,
        Class::Panic,
        Class::Crash,
        Class::Hang,
    ];

    /// The name used in reports and in the worker's lines.
    pub fn name(self) -> &'static str {
        match self {
            Class::Ok => "ok",
            Class::Positioned => "positioned error",
            Class::Unpositioned => "unpositioned error",
            Class::Validation => "validation message",
            Class::CheckLied => "check lied",
            Class::Panic => "panic",
            Class::Crash => "crash",
            Class::Hang => "hang",
        }
    }

    /// The class called `name`.
    pub fn from_name(name: &str) -> Option<Class> {
        Class::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Whether inputs of this class break a promise (and are saved).
    pub fn is_failure(self) -> bool {
        !matches!(self, Class::Ok | Class::Positioned)
    }
}

/// What the targets share: the device (validation on) and a small scene to render with.
pub struct Bench {
    ctx: GpuContext,
    shaders: ShaderCompiler,
    city: Scene,
}

impl Bench {
    /// The device chosen as `cullgraph render` chooses it, with validation on.
    pub fn new() -> cullgraph::Result<Self> {
        let options = cullgraph::gpu::ContextOptions {
            device: cullgraph::gpu::DeviceSelector::or_from_env(None),
            validation: true,
            app_name: "cullgraph fuzz".into(),
            ..Default::default()
        };
        let ctx = GpuContext::new(&options)?;
        let shaders = ShaderCompiler::new(cullgraph::gpu::ShaderRoot::from_env())?;
        let options = LoadOptions { instances: Some(300), lights: Some(4), ..Default::default() };
        let city = SceneSource::Builtin("city".into()).load(&options)?;
        Ok(Self { ctx, shaders, city })
    }

    /// Renders two frames of `scene` through `spec` at 64x48; the class and, for failures, what
    /// happened.
    fn render(&self, scene: Scene, spec: &GraphSpec) -> (Class, String) {
        let before = self.ctx.validation_log().count();
        let camera = scene.default_camera(64.0 / 48.0);
        let result = Renderer::with_graph(&self.ctx, &self.shaders, scene, RenderSettings::new(64, 48), spec)
            .and_then(|mut r| (0..2).try_for_each(|_| r.render(&camera).map(|_| ())));
        let messages = self.ctx.validation_log().messages();
        if messages.len() > before {
            return (Class::Validation, messages[before].clone());
        }
        match result {
            Ok(()) => (Class::Ok, String::new()),
            Err(e) => runtime_class(&e),
        }
    }

    /// Checks a graph as `graph check --size` does (loads it against the device, compiles it
    /// at 64x48 for the small city and at 3840x2160 for 10^6 instances): whether it passes and
    /// whether it imports host resources; else the class and message of its refusal.
    pub fn check(&self, text: &str, dir: Option<&Path>) -> Result<bool, (Class, String)> {
        let env = DeviceEnv::new(&self.ctx, &self.shaders);
        let loaded = graph::load_in(text, "fuzz.ron", dir, &[], &env, &builtin_kinds())
            .map_err(|errors| graph_errors_class(&errors))?;
        let kinds = builtin_kinds();
        let big = FrameInputs::new(3840, 2160);
        let big = FrameInputs { quantities: big.quantities.with("instances", 1_000_000).with("meshes", 64), ..big };
        let small = frame_inputs(&kinds, &self.city, 64, 48).map_err(|e| runtime_class(&e))?;
        for frame in [small, big] {
            let plan = graph::compile(&loaded, &frame).map_err(|errors| graph_errors_class(&errors))?;
            shown_image_error(&plan, frame.width, frame.height).map_err(|errors| graph_errors_class(&errors))?;
        }
        Ok(loaded.resources.iter().any(|r| r.imported))
    }

    /// Runs one graph (`text`, from a seed in `dir`): checks it and renders what passes;
    /// `checked` is called when it has passed the check, before it is rendered. A graph that
    /// imports host resources is checked only: rendering it needs a host to hand them over.
    pub fn graph(&self, text: &str, dir: Option<&Path>, checked: &mut dyn FnMut()) -> (Class, String) {
        let imports = match self.check(text, dir) {
            Ok(imports) => imports,
            Err(refused) => return refused,
        };
        checked();
        if imports {
            return (Class::Ok, String::new());
        }
        let spec = GraphSpec {
            text: text.to_string(),
            file: "fuzz.ron".into(),
            dir: dir.map(Path::to_path_buf),
            overrides: Vec::new(),
            kinds: builtin_kinds(),
            settings: Vec::new(),
        };
        match self.render(self.city.clone(), &spec) {
            (Class::Positioned | Class::Unpositioned, error) => (Class::CheckLied, error),
            outcome => outcome,
        }
    }

    /// Imports the glTF file at `path` and renders it; `imported` is called when it has
    /// imported, before it is rendered.
    pub fn gltf(&self, path: &Path, imported: &mut dyn FnMut()) -> (Class, String) {
        match SceneSource::File(path.to_path_buf()).load(&LoadOptions::default()) {
            Ok(scene) => {
                imported();
                self.render(scene, &GraphSpec::default_graph())
            }
            Err(e) => scene_error_class(&e),
        }
    }
}

/// Load or compile errors: positioned when every one has a line.
fn graph_errors_class(errors: &graph::GraphErrors) -> (Class, String) {
    let unplaced = errors.iter().find(|e| e.line == 0 || e.col == 0);
    match unplaced {
        Some(e) => (Class::Unpositioned, e.to_string()),
        None => (Class::Positioned, errors.iter().next().map(|e| e.to_string()).unwrap_or_default()),
    }
}

/// An error of building a renderer or recording a frame: positioned when it names a place in
/// the graph file (`fuzz.ron:line:col`), a pass or a resource.
fn runtime_class(e: &cullgraph::Error) -> (Class, String) {
    let text = e.to_string();
    let placed = text.contains("fuzz.ron:") || text.contains("pass '") || text.contains("resource '");
    (if placed { Class::Positioned } else { Class::Unpositioned }, text)
}

/// A glTF import error: positioned when it names what in the file is wrong (a node, mesh,
/// accessor, ...), or where in the JSON a parse failed; a file that is not glTF at all has no
/// deeper place than the file.
fn scene_error_class(e: &SceneError) -> (Class, String) {
    let text = e.to_string();
    let placed = match e {
        SceneError::Invalid { .. } => true,
        SceneError::Import { message, .. } => {
            const PLACES: &[&str] = &[
                "line ",
                "node",
                "mesh",
                "accessor",
                "buffer",
                "material",
                "primitive",
                "image",
                "texture",
                "camera",
                "scene",
                "sampler",
                "skin",
                "animation",
                "extension",
                "GLB",
                "glb",
                "JSON",
                "json",
                "header",
                "chunk",
                "magic",
                "version",
                "length",
                "asset",
            ];
            PLACES.iter().any(|p| message.contains(p))
        }
        SceneError::Builtin(_) => false,
    };
    (if placed { Class::Positioned } else { Class::Unpositioned }, text)
}

/// A small valid glTF document and its binary chunk: two meshes (a quad and a tetrahedron with
/// normals), a node hierarchy with transforms, a material, a camera and a point light.
pub fn gltf_seed() -> (Value, Vec<u8>) {
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push = |bytes: &[u8], accessor: Value, target: u32| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len(), "target": target}));
        let mut a = accessor;
        a["bufferView"] = json!(views.len() - 1);
        accessors.push(a);
        bin.extend_from_slice(bytes);
    };
    let floats = |v: &[[f32; 3]]| v.iter().flatten().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let shorts = |v: &[u16]| v.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<u8>>();
    let quad = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let tetra = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let normals = [[0.0, 0.0, 1.0]; 4];
    const ARRAY: u32 = 34962;
    const ELEMENTS: u32 = 34963;
    let vec3 = |n: usize, min: [f32; 3], max: [f32; 3]| json!({"componentType": 5126, "count": n, "type": "VEC3", "min": min, "max": max});
    push(&floats(&quad), vec3(4, [0.0; 3], [1.0, 1.0, 0.0]), ARRAY);
    push(&floats(&normals), vec3(4, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]), ARRAY);
    push(&shorts(&[0, 1, 2, 2, 1, 3]), json!({"componentType": 5123, "count": 6, "type": "SCALAR"}), ELEMENTS);
    push(&floats(&tetra), vec3(4, [0.0; 3], [1.0; 3]), ARRAY);
    push(
        &shorts(&[0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3]),
        json!({"componentType": 5123, "count": 12, "type": "SCALAR"}),
        ELEMENTS,
    );
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1.0, 0.9, 0.8], "intensity": 20.0, "range": 10.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 3, 4]}],
        "nodes": [
            {"name": "root", "translation": [0.0, 0.0, -3.0], "children": [1, 2]},
            {"name": "quad", "mesh": 0, "scale": [2.0, 2.0, 2.0]},
            {"name": "tetra", "mesh": 1, "rotation": [0.0, 0.383, 0.0, 0.924], "translation": [1.5, 0.0, 0.0],
             "extras": {"cullgraph": {"occluder": true}}},
            {"name": "eye", "camera": 0, "translation": [0.5, 0.5, 2.0]},
            {"name": "lamp", "translation": [0.0, 2.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        ],
        "meshes": [
            {"name": "quad", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]},
            {"name": "tetra", "primitives": [{"attributes": {"POSITION": 3}, "indices": 4, "mode": 4}]},
        ],
        "materials": [{"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5}, "doubleSided": true}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "aspectRatio": 1.5}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    (doc, bin)
}

/// A glTF document's JSON text and its binary chunk as a binary glTF file.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}
