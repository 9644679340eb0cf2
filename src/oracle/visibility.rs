//! Exact visibility on the GPU: every instance drawn without culling into an instance-id image
//! at every sample, with the same vertex transform (`invariant gl_Position`) as the G-buffer
//! pass. The instances whose id survives at some sample are the visible set; culling must draw
//! all of them (no false negatives), and what it draws beyond them are false positives.
//!
//! Each sample also keeps the triangle of the instance's full mesh that covers it, so that what
//! cluster culling drew can be checked cluster by cluster.
//!
//! Transparent (alphaMode BLEND) instances hide nothing: they are drawn after the opaque ones,
//! through the `transparent` pass's own fragment shader with its depth test against the opaque
//! depth, and marked seen wherever a fragment passes.

use crate::gpu::barrier::{cmd_barriers, image_barrier, memory_barrier};
use crate::gpu::cmd_set_full_viewport;
use crate::gpu::{
    Access, Bind, Buffer, BufferDesc, GpuContext, GraphicsDesc, Image, ImageDesc, MemoryLocation, Pipeline, Sampler,
    ShaderCompiler, VertexAttribute,
};
use crate::passes::shared::face_cull::FaceCull;
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::passes::shared::scene_buffers::GpuScene;
use crate::passes::shared::transparent_draw::{
    record_transparent, transparent_pipeline, TransparentDraws, TransparentShading,
};
use crate::passes::shared::vertex_streams::{POSITION_ATTRIBUTE, UV_ATTRIBUTE, VERTEX_STRIDES};
use ash::vk;
use std::collections::BTreeSet;

/// The vertex attributes `oracle/id.vert` reads, at the geometry passes' locations and offsets:
/// the position and the UV (for the alpha test). The normal and tangent are not fetched, which
/// the validation layer would otherwise report as attributes no shader consumes.
const ID_VERTEX_ATTRIBUTES: [VertexAttribute; 2] = [POSITION_ATTRIBUTE, UV_ATTRIBUTE];

/// Instance ids per sample of one frame, and the set of instances seen at some sample.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VisibleIds {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub samples: u32,
    /// `(y * width + x) * samples + s` -> instance id + 1 (0: nothing).
    pub ids: Vec<u32>,
    /// At the same index, the triangle of that instance's full mesh (its index in the mesh;
    /// meaningless where `ids` holds 0).
    pub triangles: Vec<u32>,
    /// Instances visible at one sample or more.
    pub visible: BTreeSet<u32>,
}

/// Renders instance ids without culling.
pub struct VisibilityOracle {
    draw: Pipeline,
    transparent: Pipeline,
    readback: Pipeline,
    sampler: Sampler,
    ids: Image,
    triangles: Image,
    depth: Image,
    out: Buffer,
    triangles_out: Buffer,
    extent: vk::Extent2D,
    samples: vk::SampleCountFlags,
}

impl VisibilityOracle {
    /// An oracle for `width` x `height` frames with `samples` samples per pixel (the sample
    /// count of the frame it checks).
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        width: u32,
        height: u32,
        samples: vk::SampleCountFlags,
    ) -> crate::Result<Self> {
        let vertex = shaders.compile("oracle/id.vert", &[])?;
        // The same share of a masked material's samples as the geometry passes keep.
        let fragment = shaders.compile("oracle/id.frag", &[("MSAA_SAMPLES", &samples.as_raw().max(1).to_string())])?;
        let draw = Pipeline::graphics(
            ctx,
            "visibility oracle",
            &GraphicsDesc {
                vertex: &vertex,
                fragment: Some(&fragment),
                vertex_strides: &VERTEX_STRIDES,
                vertex_attributes: &ID_VERTEX_ATTRIBUTES,
                color_formats: &[vk::Format::R32_UINT, vk::Format::R32_UINT],
                depth_format: vk::Format::D32_SFLOAT,
                depth_compare: vk::CompareOp::GREATER,
                depth_write: true,
                samples,
                stencil: Default::default(),
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                blend: false,
            },
        )?;
        let transparent = transparent_pipeline(
            ctx,
            shaders,
            "visibility oracle, transparent",
            samples.as_raw(),
            TransparentShading::MarkSeen,
        )?;
        let defines: &[(&str, &str)] =
            if samples == vk::SampleCountFlags::TYPE_1 { &[] } else { &[("MULTISAMPLED", "1")] };
        let readback =
            Pipeline::compute(ctx, "visibility readback", &shaders.compile("oracle/id_readback.comp", defines)?)?;
        let extent = vk::Extent2D { width, height };
        let image =
            |name, format, usage| Image::new(ctx, &ImageDesc { name, format, extent, mip_levels: 1, samples, usage });
        let ids = image(
            "visibility ids",
            vk::Format::R32_UINT,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
        )?;
        let triangles = image(
            "visibility triangles",
            vk::Format::R32_UINT,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
        )?;
        let depth = image(
            "visibility depth",
            vk::Format::D32_SFLOAT,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
        )?;
        let count = width as u64 * height as u64 * samples.as_raw() as u64;
        let readback_buffer = |name| {
            Buffer::new(
                ctx,
                &BufferDesc {
                    name,
                    size: count * 4,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                    location: MemoryLocation::GpuToCpu,
                },
            )
        };
        let out = readback_buffer("visibility ids readback")?;
        let triangles_out = readback_buffer("visibility triangles readback")?;
        Ok(Self {
            draw,
            transparent,
            readback,
            sampler: Sampler::nearest_clamp(ctx)?,
            ids,
            triangles,
            depth,
            out,
            triangles_out,
            extent,
            samples,
        })
    }

    /// Records the transparent region of the unculled list against the opaque depth just
    /// drawn, marking in `seen` each instance with a fragment in front of it.
    fn mark_transparent(
        &self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        scene: &GpuScene,
        constants: &Buffer,
        seen: &Buffer,
        area: vk::Rect2D,
    ) {
        let device = ctx.device();
        let fragment_read = Access { stage: vk::PipelineStageFlags2::FRAGMENT_SHADER, ..Access::GRAPHICS_READ };
        let fragment_write = Access {
            stage: vk::PipelineStageFlags2::FRAGMENT_SHADER,
            access: vk::AccessFlags2::SHADER_STORAGE_WRITE,
            layout: vk::ImageLayout::UNDEFINED,
        };
        // SAFETY: cmd recording; the buffer is not in use.
        unsafe { device.cmd_fill_buffer(cmd, seen.handle(), 0, vk::WHOLE_SIZE, 0) };
        cmd_barriers(
            device,
            cmd,
            &[memory_barrier(Access::TRANSFER_WRITE, fragment_write)],
            &[image_barrier(&self.depth, Access::DEPTH_ATTACHMENT, fragment_read)],
        );
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let mut binds = vec![
            Bind::Buffer(1, scene.draw_instance_ids.handle()),
            Bind::Buffer(2, constants.handle()),
            Bind::Buffer(3, scene.materials.handle()),
            Bind::Sampled(5, self.depth.sampled_view(), self.sampler.handle(), read),
            Bind::Buffer(6, seen.handle()),
        ];
        binds.extend(scene.instance_binds(0));
        binds.extend_from_slice(scene.textures.bindings());
        let blended = FaceCull::Blended as usize;
        let draws = TransparentDraws {
            commands: &scene.draw_commands,
            offset: scene.regions.first[blended] as u64 * std::mem::size_of::<DrawIndexedIndirect>() as u64,
            count: &scene.draw_count,
            count_offset: blended as u64 * 4,
            max: scene.regions.len[blended],
        };
        record_transparent(ctx, cmd, &self.transparent, scene, &[], area.extent, &binds, &[], &draws);
        cmd_barriers(device, cmd, &[memory_barrier(fragment_write, Access::HOST_READ)], &[]);
    }

    /// Draws every instance of `scene` as `constants` (a [`crate::passes::shared::gpu_types::FrameConstants`]
    /// buffer) sees it, and reads the ids back. Submits and waits: a checking tool, not a frame pass.
    pub fn render(&self, ctx: &GpuContext, scene: &GpuScene, constants: &Buffer) -> crate::Result<VisibleIds> {
        let device = ctx.device();
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: self.extent };
        let blended = FaceCull::Blended as usize;
        let transparent_groups = scene.regions.len[blended];
        // One word per instance: 1 where a transparent fragment passed the depth test.
        let seen = Buffer::new(
            ctx,
            &BufferDesc {
                name: "visibility oracle, transparent seen",
                size: (scene.instance_count.max(1) as u64) * 4,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        ctx.submit_and_wait(|cmd| {
            let to_draw = [
                image_barrier(&self.ids, Access::NONE, Access::COLOR_ATTACHMENT),
                image_barrier(&self.triangles, Access::NONE, Access::COLOR_ATTACHMENT),
                image_barrier(&self.depth, Access::NONE, Access::DEPTH_ATTACHMENT),
            ];
            cmd_barriers(device, cmd, &[], &to_draw);
            let target = |image: &Image| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(image.view())
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: vk::ClearColorValue { uint32: [0; 4] } })
            };
            let color = [target(&self.ids), target(&self.triangles)];
            let depth = vk::RenderingAttachmentInfo::default()
                .image_view(self.depth.view())
                .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::DONT_CARE)
                .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } });
            // SAFETY: cmd recording; every handle outlives the submission (we wait below).
            unsafe {
                device.cmd_begin_rendering(
                    cmd,
                    &vk::RenderingInfo::default()
                        .render_area(area)
                        .layer_count(1)
                        .color_attachments(&color)
                        .depth_attachment(&depth),
                );
                cmd_set_full_viewport(device, cmd, self.extent);
                self.draw.bind(cmd);
                let mut binds = vec![
                    Bind::Buffer(1, scene.draw_instance_ids.handle()),
                    Bind::Buffer(2, constants.handle()),
                    Bind::Buffer(3, scene.materials.handle()),
                ];
                binds.extend(scene.instance_binds(0));
                binds.extend_from_slice(scene.textures.bindings());
                self.draw.push_bindings(cmd, &binds);
                scene.vertices.bind(device, cmd);
                device.cmd_bind_index_buffer(cmd, scene.indices.handle(), 0, vk::IndexType::UINT32);
                // The same faces as the frame's draws: one-sided materials lose their back faces.
                scene.regions.record(device, cmd, &scene.draw_commands, &scene.draw_count, &FaceCull::DRAWN);
                device.cmd_end_rendering(cmd);
            }
            if transparent_groups > 0 {
                self.mark_transparent(ctx, cmd, scene, constants, &seen, area);
            }
            let sampled = Access { access: vk::AccessFlags2::SHADER_SAMPLED_READ, ..Access::COMPUTE_READ };
            let to_read = [
                image_barrier(&self.ids, Access::COLOR_ATTACHMENT, sampled),
                image_barrier(&self.triangles, Access::COLOR_ATTACHMENT, sampled),
            ];
            cmd_barriers(device, cmd, &[], &to_read);
            let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
            let push = [self.extent.width, self.extent.height, self.samples.as_raw()];
            for (image, out) in [(&self.ids, &self.out), (&self.triangles, &self.triangles_out)] {
                let binds =
                    [Bind::Sampled(0, image.view(), self.sampler.handle(), read), Bind::Buffer(1, out.handle())];
                self.readback.dispatch_over(cmd, &binds, bytemuck::cast_slice(&push), self.extent);
            }
            cmd_barriers(device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::HOST_READ)], &[]);
            crate::gpu::GpuResult::Ok(())
        })?;
        let ids: Vec<u32> = bytemuck::cast_slice(self.out.read_bytes()?).to_vec();
        let triangles: Vec<u32> = bytemuck::cast_slice(self.triangles_out.read_bytes()?).to_vec();
        let mut visible: BTreeSet<u32> = ids.iter().filter(|&&id| id != 0).map(|&id| id - 1).collect();
        if transparent_groups > 0 {
            let seen: &[u32] = bytemuck::cast_slice(seen.read_bytes()?);
            visible.extend((0..seen.len() as u32).filter(|&i| seen[i as usize] != 0));
        }
        Ok(VisibleIds {
            width: self.extent.width,
            height: self.extent.height,
            samples: self.samples.as_raw(),
            ids,
            triangles,
            visible,
        })
    }
}
