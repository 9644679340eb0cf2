//! Two eyes drawn from instance lists both ways: one pass per eye into single-layer targets,
//! or one multiview pass (view mask `0b11`) into 2-layer targets, where `gl_ViewIndex` picks
//! the eye (`shaders/bench/stereo.vert`). The draws are the geometry of a G-buffer pass
//! (the scene's vertices, indices, instances and indirect commands, position as `gbuffer.vert`
//! computes it) with a fragment shader that writes the normal: the part multiview can share.

use super::eye_list::EyeList;
use super::layered::{LayeredImage, COLOR_FORMAT, DEPTH_FORMAT};
use crate::error::{Error, Result};
use crate::gpu::barrier::{cmd_barriers, image_barrier_raw, memory_barrier, Access};
use crate::gpu::{
    cmd_set_full_viewport, Bind, Buffer, BufferDesc, GpuContext, GraphicsDesc, MemoryLocation, Pipeline,
    ShaderCompiler, StencilRule,
};
use crate::passes::shared::gpu_types::split_hi_lo;
use crate::passes::shared::vertex_streams::{VertexFetch, VERTEX_STRIDES};
use crate::passes::shared::GpuScene;
use crate::scene::Camera;
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// The view mask of the multiview pass: both eyes.
pub const BOTH_EYES: u32 = 0b11;

/// One eye as the vertex shader reads it (`Eye` in `shaders/bench/stereo.vert`, 96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuEye {
    view_proj: [f32; 16],
    eye_hi: [f32; 4],
    eye_lo: [f32; 4],
}

impl GpuEye {
    fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let (hi, lo) = split_hi_lo(camera.eye);
        Self {
            view_proj: camera.jittered_view_projection_rel_eye(width, height).to_cols_array(),
            eye_hi: hi.extend(0.0).to_array(),
            eye_lo: lo.extend(0.0).to_array(),
        }
    }
}

/// Both eyes' colour (RGBA8 rows, top to bottom), left eye first.
pub type EyeImages = [Vec<u8>; 2];

/// What [`StereoDraws::read_colors`] reads.
pub struct EyeColors {
    /// Each eye's single-layer target.
    pub separate: EyeImages,
    /// The layers of the multiview target (`None` without multiview).
    pub multiview: Option<EyeImages>,
}

/// A colour and a depth attachment of one or two layers.
struct Target {
    color: LayeredImage,
    depth: LayeredImage,
}

impl Target {
    fn new(ctx: &GpuContext, name: &str, extent: vk::Extent2D, layers: u32) -> Result<Self> {
        Ok(Self {
            color: LayeredImage::new(ctx, &format!("{name} colour"), COLOR_FORMAT, extent, layers)?,
            depth: LayeredImage::new(ctx, &format!("{name} depth"), DEPTH_FORMAT, extent, layers)?,
        })
    }
}

/// The pipelines, eye constants and targets of both ways of drawing two eyes.
pub struct StereoDraws {
    ctx: GpuContext,
    extent: vk::Extent2D,
    /// One eye per pass (the pushed eye).
    separate: Pipeline,
    /// Both eyes in one pass; `None` where the device has no multiview.
    multiview: Option<Pipeline>,
    /// Both eyes' [`GpuEye`]s.
    eyes: Buffer,
    /// Each eye's single-layer target.
    single: [Target; 2],
    /// The 2-layer target of the multiview pass.
    layered: Option<Target>,
}

impl StereoDraws {
    /// Pipelines and targets for `eyes` at `width` x `height` each; the multiview ones only
    /// where the device has multiview on ([`crate::gpu::DeviceCaps::multiview`]).
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        eyes: &[Camera; 2],
        width: u32,
        height: u32,
    ) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::Invalid(format!("multiview: an eye of {width}x{height} pixels is empty")));
        }
        let extent = vk::Extent2D { width, height };
        let fragment = shaders.compile("bench/stereo.frag", &[])?;
        let pipeline = |defines: &[(&str, &str)], view_mask: u32| -> Result<Pipeline> {
            let vertex = shaders.compile("bench/stereo.vert", defines)?;
            let desc = GraphicsDesc {
                vertex: &vertex,
                fragment: Some(&fragment),
                vertex_strides: &VERTEX_STRIDES,
                // Position and normal: what the shaders read of a vertex.
                vertex_attributes: &VertexFetch { normals: true, surface: false }.attributes(),
                color_formats: &[COLOR_FORMAT],
                depth_format: DEPTH_FORMAT,
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                samples: vk::SampleCountFlags::TYPE_1,
                stencil: StencilRule::Off,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                blend: false,
            };
            Ok(Pipeline::graphics_multiview(ctx, "stereo", &desc, view_mask)?)
        };
        let multiview = ctx.caps().multiview;
        let data = eyes.each_ref().map(|e| GpuEye::new(e, width, height));
        let mut buffer = Buffer::new(
            ctx,
            &BufferDesc {
                name: "stereo eyes",
                size: std::mem::size_of_val(&data) as u64,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::CpuToGpu,
            },
        )?;
        buffer.write_bytes(0, bytemuck::cast_slice(&data))?;
        Ok(Self {
            ctx: ctx.clone(),
            extent,
            separate: pipeline(&[], 0)?,
            multiview: if multiview { Some(pipeline(&[("MULTIVIEW", "1")], BOTH_EYES)?) } else { None },
            eyes: buffer,
            single: [Target::new(ctx, "left eye", extent, 1)?, Target::new(ctx, "right eye", extent, 1)?],
            layered: if multiview { Some(Target::new(ctx, "both eyes", extent, 2)?) } else { None },
        })
    }

    /// Whether the multiview pass can be recorded.
    pub fn has_multiview(&self) -> bool {
        self.multiview.is_some()
    }

    /// Records one pass per eye, eye `i` drawing `lists[i]` into its own target.
    pub fn record_separate(&self, cmd: vk::CommandBuffer, scene: &GpuScene, lists: [&EyeList; 2]) {
        for (eye, list) in lists.into_iter().enumerate() {
            self.record_pass(cmd, scene, &self.separate, &self.single[eye], 0, eye as u32, list);
        }
    }

    /// Records one multiview pass drawing `list` for both eyes into the 2-layer target; an
    /// error where the device has no multiview.
    pub fn record_multiview(&self, cmd: vk::CommandBuffer, scene: &GpuScene, list: &EyeList) -> Result<()> {
        let (Some(pipeline), Some(target)) = (&self.multiview, &self.layered) else {
            return Err(Error::Invalid(format!(
                "multiview: the multiview feature is not on on {}",
                self.ctx.caps().name
            )));
        };
        self.record_pass(cmd, scene, pipeline, target, BOTH_EYES, 0, list);
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn record_pass(
        &self,
        cmd: vk::CommandBuffer,
        scene: &GpuScene,
        pipeline: &Pipeline,
        target: &Target,
        view_mask: u32,
        eye: u32,
        list: &EyeList,
    ) {
        let device = self.ctx.device();
        target.color.discard_to(device, cmd, Access::COLOR_ATTACHMENT);
        target.depth.discard_to(device, cmd, Access::DEPTH_ATTACHMENT);
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(target.color.view())
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } })];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(target.depth.view())
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } });
        // With a view mask the layer count is ignored: each set bit renders its layer.
        let rendering = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent: self.extent })
            .layer_count(1)
            .view_mask(view_mask)
            .color_attachments(&color)
            .depth_attachment(&depth);
        // SAFETY: cmd is recording; every handle outlives the command buffer's execution
        // (the caller waits for it before dropping `self`, `scene` or `list`).
        unsafe {
            device.cmd_begin_rendering(cmd, &rendering);
            cmd_set_full_viewport(device, cmd, self.extent);
            pipeline.bind(cmd);
            pipeline.push_constants(cmd, &eye);
            scene.vertices.bind(device, cmd);
            device.cmd_bind_index_buffer(cmd, scene.indices.handle(), 0, vk::IndexType::UINT32);
            let mut binds = vec![Bind::Buffer(1, list.instance_ids.handle()), Bind::Buffer(2, self.eyes.handle())];
            binds.extend(scene.instance_binds(0));
            pipeline.push_bindings(cmd, &binds);
            list.record(device, cmd);
            device.cmd_end_rendering(cmd);
        }
    }

    /// Reads back the colour of both eyes as the last separate passes and the last multiview
    /// pass left them. Call after both were recorded and executed.
    pub fn read_colors(&self) -> Result<EyeColors> {
        let layer_bytes = self.extent.width as u64 * self.extent.height as u64 * 4;
        let readback = Buffer::new(
            &self.ctx,
            &BufferDesc {
                name: "stereo readback",
                size: layer_bytes * 4,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        // (image, layer, offset in the readback)
        let mut copies = vec![(&self.single[0].color, 0, 0), (&self.single[1].color, 0, layer_bytes)];
        if let Some(target) = &self.layered {
            copies.extend([(&target.color, 0, 2 * layer_bytes), (&target.color, 1, 3 * layer_bytes)]);
        }
        let device = self.ctx.device();
        self.ctx.submit_and_wait(|cmd| {
            let barriers: Vec<_> = [&self.single[0].color, &self.single[1].color]
                .into_iter()
                .chain(self.layered.as_ref().map(|t| &t.color))
                .map(|image| {
                    image_barrier_raw(image.handle(), image.range(), Access::COLOR_ATTACHMENT, Access::TRANSFER_READ)
                })
                .collect();
            cmd_barriers(device, cmd, &[], &barriers);
            for &(image, layer, offset) in &copies {
                let region = vk::BufferImageCopy::default()
                    .buffer_offset(offset)
                    .image_subresource(vk::ImageSubresourceLayers {
                        aspect_mask: vk::ImageAspectFlags::COLOR,
                        mip_level: 0,
                        base_array_layer: layer,
                        layer_count: 1,
                    })
                    .image_extent(vk::Extent3D { width: self.extent.width, height: self.extent.height, depth: 1 });
                // SAFETY: the image is in TRANSFER_SRC layout and the buffer holds every layer.
                unsafe {
                    device.cmd_copy_image_to_buffer(
                        cmd,
                        image.handle(),
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        readback.handle(),
                        &[region],
                    )
                };
            }
            cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::HOST_READ)], &[]);
            Ok::<(), Error>(())
        })?;
        let bytes = readback.read_bytes()?;
        let layer = |i: u64| bytes[(i * layer_bytes) as usize..((i + 1) * layer_bytes) as usize].to_vec();
        Ok(EyeColors { separate: [layer(0), layer(1)], multiview: self.layered.as_ref().map(|_| [layer(2), layer(3)]) })
    }
}
