//! An engine's own pass kind, written in Rust and used from RON like a built-in one.
//!
//! `instance_bounds` is a graphics pass: it draws the world-space box of every instance as lines
//! into the image bound to its `target` slot (dynamic rendering, the image's contents kept). With
//! this frame's visibility bits bound to `visibility`, the boxes the late cull pass found visible
//! are green and the ones it culled are red, a view of what occlusion culling removed; its
//! `show` setting picks all, the visible or the culled boxes. `graph/examples/instance_bounds.ron`
//! adds it after the lighting of the two-phase graph.
//!
//! `cargo run --release --example custom_pass -- [builtin:city|PATH.glb] [out.png]`

use ash::vk;
use cullgraph::prelude::*;

cullgraph::choice! {
    /// Which boxes the pass draws (setting `show`); the first is the default.
    enum Show {
        /// Every instance's.
        All = "all",
        /// The ones the late cull found visible.
        Visible = "visible",
        /// The ones it culled.
        Culled = "culled",
    }
}

/// The `instance_bounds` pass kind.
pub struct InstanceBoundsKind;

impl PassKind for InstanceBoundsKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "instance_bounds",
            doc: "draws every instance's world-space box as lines over an image: green where this frame's visibility bits say visible, red where culled",
            reads: vec![SlotDecl::new(
                "visibility",
                Usage::StorageBufferRead(Stages::Vertex),
                "this frame's visibility bits (a late instance_cull pass's `visibility`); unbound: every box white",
            )
            .at_least("ceil_div(instances, 32) * 4")],
            writes: vec![SlotDecl::new("target", Usage::ColorAttachmentLoad, "the image drawn on, its contents kept")
                .required()
                .format(FormatRule::Color)],
            settings: vec![SettingDecl::choice::<Show>("show", "which boxes: all, the visible ones or the culled ones")],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, setup: &NodeSetup<'_>) -> cullgraph::Result<Box<dyn PassNode>> {
        Ok(Box::new(InstanceBoundsPass::new(setup)?))
    }
}

/// One `instance_bounds` pass of a compiled graph.
pub struct InstanceBoundsPass {
    pipeline: Pipeline,
    visibility: bool,
    show: u32,
}

impl InstanceBoundsPass {
    fn new(setup: &NodeSetup<'_>) -> cullgraph::Result<Self> {
        let pass = setup.pass;
        let invalid = |m: &str| cullgraph::Error::Invalid(format!("pass '{}': {m}", pass.name));
        let target = pass.bindings.iter().find(|b| b.slot == "target").ok_or_else(|| invalid("no target bound"))?;
        let ResolvedKind::Image { format, samples, .. } = setup.plan.resources[target.resource].kind else {
            return Err(invalid("the target must be an image"));
        };
        let visibility = pass.bindings.iter().any(|b| b.slot == "visibility");
        let defines = [("HAS_VISIBILITY", if visibility { "1" } else { "0" })];
        let vertex =
            compile(setup.shaders, "instance_bounds.vert", include_str!("custom_pass/instance_bounds.vert"), &defines)?;
        let fragment =
            compile(setup.shaders, "instance_bounds.frag", include_str!("custom_pass/instance_bounds.frag"), &[])?;
        let pipeline = Pipeline::graphics(
            setup.ctx,
            &pass.name,
            &GraphicsDesc {
                vertex: &vertex,
                fragment: Some(&fragment),
                vertex_strides: &[],
                vertex_attributes: &[],
                color_formats: &[format],
                depth_format: vk::Format::UNDEFINED,
                depth_compare: vk::CompareOp::ALWAYS,
                depth_write: false,
                samples,
                stencil: StencilRule::Off,
                topology: vk::PrimitiveTopology::LINE_LIST,
                blend: false,
            },
        )?;
        // The variants' order is the shader's.
        let show = pass.choice::<Show>("show")? as u32;
        Ok(Self { pipeline, visibility, show })
    }
}

fn compile(shaders: &ShaderCompiler, name: &str, source: &str, defines: &[(&str, &str)]) -> cullgraph::Result<Spirv> {
    shaders.compile_source(name, source, defines).map_err(|e| cullgraph::Error::Invalid(e.to_string()))
}

impl PassNode for InstanceBoundsPass {
    fn record(&mut self, rec: &PassContext<'_>) -> cullgraph::Result<()> {
        let inputs = SceneInputs::of(rec)?;
        let target = rec.slots.required_image("target")?;
        let device = rec.ctx.device();
        let extent = target.extent();
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(target.view())
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let rendering = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&color);
        let mut binds =
            vec![Bind::Buffer(0, inputs.constants().handle()), Bind::Buffer(1, inputs.scene.cull_records.handle())];
        if self.visibility {
            binds.push(Bind::Buffer(2, rec.slots.buffer("visibility").expect("bound when created").handle()));
        }
        let slots = inputs.scene.instance_count;
        // SAFETY: the command buffer is recording, and the graph keeps every bound resource and
        // the scene alive until the frame has executed.
        unsafe {
            device.cmd_begin_rendering(rec.cmd, &rendering);
            cmd_set_full_viewport(device, rec.cmd, extent);
            device.cmd_set_cull_mode(rec.cmd, vk::CullModeFlags::NONE);
            self.pipeline.bind(rec.cmd);
            self.pipeline.push_bindings(rec.cmd, &binds);
            self.pipeline.push_constants(rec.cmd, &self.show);
            if slots > 0 {
                device.cmd_draw(rec.cmd, 24, slots, 0, 0);
            }
            device.cmd_end_rendering(rec.cmd);
        }
        Ok(())
    }
}

#[allow(dead_code)] // tests/custom_pass.rs includes this file for the kind alone.
fn main() -> Result<(), Box<dyn std::error::Error>> {
    use cullgraph::render::output::save_png;

    let mut args = std::env::args().skip(1);
    let source: SceneSource = args.next().unwrap_or_else(|| "builtin:city".into()).parse()?;
    let out = args.next().unwrap_or_else(|| "out/custom_pass.png".into());
    let scene = source.load(&LoadOptions::default())?;
    let settings = RenderSettings::new(960, 540);
    let camera = scene.default_camera(settings.width as f32 / settings.height as f32);

    // The built-in kinds plus ours; graphs loaded with this registry may use `instance_bounds`.
    let mut kinds = builtin_kinds();
    kinds.register(InstanceBoundsKind)?;
    let graph = concat!(env!("CARGO_MANIFEST_DIR"), "/graph/examples/instance_bounds.ron");
    let spec = GraphSpec::from_file(graph.as_ref())?.with_kinds(kinds);

    let ctx = GpuContext::new(&ContextOptions::default())?;
    let shaders = ShaderCompiler::new(ShaderRoot::Embedded)?;
    let mut renderer = Renderer::with_graph(&ctx, &shaders, scene, settings, &spec)?;
    // The first frames have no visibility history yet: two-phase culling settles by the third.
    renderer.render(&camera)?;
    renderer.render(&camera)?;
    let (stats, image) = renderer.render_to_image(&camera)?;
    save_png(&image, out.as_ref())?;
    println!(
        "{} instances: {} drawn (green boxes), {} occlusion-culled (red boxes), {} outside the view -> {out}",
        stats.instances, stats.drawn, stats.occlusion_culled, stats.frustum_culled
    );
    Ok(())
}
