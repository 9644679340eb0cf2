//! G-buffer geometry pass: draws every draw group with `vkCmdDrawIndexedIndirectCount` into
//! albedo/metallic, normal/roughness and reversed-Z depth.

use crate::gpu::{Bind, Buffer, GpuContext, GraphicsDesc, Image, Pipeline, ShaderCompiler};
use crate::graph::executor::{PassContext, PassNode};
use crate::render::scene_buffers::GpuScene;
use ash::vk;

/// Albedo (rgb) and metallic (a).
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// Normal (xyz) and roughness (a).
pub const NORMAL_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Reversed-Z depth: cleared to 0 (infinitely far), nearer is greater.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The attachments the pass renders into.
pub struct GbufferTargets<'a> {
    /// [`ALBEDO_FORMAT`] image.
    pub albedo: &'a Image,
    /// [`NORMAL_FORMAT`] image.
    pub normal: &'a Image,
    /// [`DEPTH_FORMAT`] image.
    pub depth: &'a Image,
}

/// Where the draws come from: the scene's unculled list, or a culling pass's output.
pub struct DrawSource<'a> {
    /// `VkDrawIndexedIndirectCommand`s.
    pub commands: &'a Buffer,
    /// Their number (read by the GPU).
    pub count: &'a Buffer,
    /// Instance ids, one slice per command.
    pub instance_ids: &'a Buffer,
    /// The most commands the count may say.
    pub max_draws: u32,
}

impl<'a> DrawSource<'a> {
    /// Every instance of the scene.
    pub fn unculled(scene: &'a GpuScene) -> Self {
        Self {
            commands: &scene.draw_commands,
            count: &scene.draw_count,
            instance_ids: &scene.draw_instance_ids,
            max_draws: scene.max_draws,
        }
    }
}

/// The G-buffer geometry pass.
pub struct GbufferPass {
    pipeline: Pipeline,
    /// Keep what earlier passes drew (`gbuffer_append`) instead of clearing.
    append: bool,
}

impl GbufferPass {
    /// Compiles the shaders and creates the pipeline.
    pub fn new(ctx: &GpuContext, shaders: &ShaderCompiler) -> crate::Result<Self> {
        let vertex = shaders.compile("gbuffer/gbuffer.vert", &[])?;
        let fragment = shaders.compile("gbuffer/gbuffer.frag", &[])?;
        let pipeline = Pipeline::graphics(
            ctx,
            "gbuffer",
            &GraphicsDesc {
                vertex: &vertex,
                fragment: Some(&fragment),
                vertex_stride: std::mem::size_of::<crate::scene::Vertex>() as u32,
                vertex_attributes: &[(0, vk::Format::R32G32B32_SFLOAT, 0), (1, vk::Format::R16G16_SNORM, 12)],
                color_formats: &[ALBEDO_FORMAT, NORMAL_FORMAT],
                depth_format: DEPTH_FORMAT,
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                samples: vk::SampleCountFlags::TYPE_1,
                // Two-sided: open meshes and mirrored instances must not lose faces.
                cull_mode: vk::CullModeFlags::NONE,
            },
        )?;
        Ok(Self { pipeline, append: false })
    }

    /// The pass that draws on top of what earlier passes left in the targets.
    pub fn appending(ctx: &GpuContext, shaders: &ShaderCompiler) -> crate::Result<Self> {
        Ok(Self { append: true, ..Self::new(ctx, shaders)? })
    }

    /// Records the pass. The targets must be in attachment layouts (see [`crate::gpu::Access`]).
    pub fn record(
        &self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        scene: &GpuScene,
        draws: &DrawSource<'_>,
        frame: &Buffer,
        targets: &GbufferTargets<'_>,
    ) {
        let device = ctx.device();
        let extent = targets.depth.extent();
        let load_op = if self.append { vk::AttachmentLoadOp::LOAD } else { vk::AttachmentLoadOp::CLEAR };
        let color = |image: &Image| {
            vk::RenderingAttachmentInfo::default()
                .image_view(image.view())
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(load_op)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } })
        };
        let colors = [color(targets.albedo), color(targets.normal)];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(targets.depth.view())
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(load_op)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } });
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        let rendering = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colors)
            .depth_attachment(&depth);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: cmd is recording; every handle is alive for the command buffer's execution.
        unsafe {
            device.cmd_begin_rendering(cmd, &rendering);
            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_set_scissor(cmd, 0, &[area]);
            self.pipeline.bind(cmd);
            self.pipeline.push_bindings(
                cmd,
                &[
                    Bind::Buffer(0, scene.instances.handle()),
                    Bind::Buffer(1, draws.instance_ids.handle()),
                    Bind::Buffer(2, frame.handle()),
                    Bind::Buffer(3, scene.materials.handle()),
                ],
            );
            device.cmd_bind_vertex_buffers(cmd, 0, &[scene.vertices.handle()], &[0]);
            device.cmd_bind_index_buffer(cmd, scene.indices.handle(), 0, vk::IndexType::UINT32);
            if draws.max_draws > 0 {
                device.cmd_draw_indexed_indirect_count(
                    cmd,
                    draws.commands.handle(),
                    0,
                    draws.count.handle(),
                    0,
                    draws.max_draws,
                    std::mem::size_of::<crate::render::gpu_types::DrawIndexedIndirect>() as u32,
                );
            }
            device.cmd_end_rendering(cmd);
        }
    }
}

impl PassNode for GbufferPass {
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let slots = &rec.slots;
        let targets = GbufferTargets {
            albedo: slots.required_image("albedo")?,
            normal: slots.required_image("normal")?,
            depth: slots.required_image("depth")?,
        };
        let scene = rec.frame.scene;
        let mut draws = DrawSource::unculled(scene);
        if let (Some(commands), Some(count), Some(ids)) =
            (slots.buffer("draw_commands"), slots.buffer("draw_count"), slots.buffer("draw_instance_ids"))
        {
            let stride = std::mem::size_of::<crate::render::gpu_types::DrawIndexedIndirect>() as u64;
            let max_draws = (commands.size() / stride).min(u32::MAX as u64) as u32;
            draws = DrawSource { commands, count, instance_ids: ids, max_draws };
        }
        GbufferPass::record(self, rec.ctx, rec.cmd, scene, &draws, rec.frame.constants, &targets);
        Ok(())
    }
}
