//! Reference kernels measured in the same run as the culling passes: a large buffer copy (the
//! device's practical bandwidth) and the naive frustum-only peer (64 bytes read per instance,
//! survivors appended through one global atomic).

use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{
    Access, Bind, Buffer, BufferDesc, GpuContext, GpuTimer, MemoryLocation, Pipeline, ShaderCompiler, UploadBatch,
};
use crate::scene::{Camera, Scene};
use ash::vk;
use glam::Vec4;

/// Bytes moved per millisecond, in GB/s.
pub fn gbps(bytes: u64, ms: f64) -> f64 {
    if ms <= 0.0 {
        0.0
    } else {
        bytes as f64 / (ms * 1e-3) / 1e9
    }
}

/// Copies `bytes` (at most what one storage-buffer binding sees) between two device buffers
/// `repeats` times, once with `vkCmdCopyBuffer` and once with a compute kernel; returns the
/// bandwidth of the faster of the two medians (the practical bandwidth a compute pass can
/// reach), in GB/s. A copy reads and writes every byte: `2 * bytes / time`.
pub fn copy_gbps(ctx: &GpuContext, shaders: &ShaderCompiler, bytes: u64, repeats: usize) -> crate::Result<f64> {
    // The compute copy binds each buffer whole: no more than one storage-buffer binding can see.
    let bytes = bytes.min(ctx.caps().limits.max_storage_buffer_range as u64) / 16 * 16;
    let buffer = |name| {
        Buffer::new(
            ctx,
            &BufferDesc {
                name,
                size: bytes,
                usage: vk::BufferUsageFlags::TRANSFER_SRC
                    | vk::BufferUsageFlags::TRANSFER_DST
                    | vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::GpuOnly,
            },
        )
    };
    let (a, b) = (buffer("bench copy source")?, buffer("bench copy destination")?);
    let pipeline = Pipeline::compute(ctx, "bench compute copy", &shaders.compile("bench/copy.comp", &[])?)?;
    let count = (bytes / 16) as u32;
    // Enough workgroups to fill any current GPU; the kernel strides over the rest.
    let groups = count.div_ceil(256).min(65_535);
    let mut timer = GpuTimer::new(ctx, 2)?;
    let (mut transfer, mut compute) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        ctx.submit_and_wait(|cmd| {
            // SAFETY: cmd recording; both buffers live until the wait returns.
            unsafe { ctx.device().cmd_fill_buffer(cmd, a.handle(), 0, vk::WHOLE_SIZE, 7) };
            // The fill before the copy reads the source; the copy's writes before the kernel's.
            cmd_barriers(ctx.device(), cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::TRANSFER_READ)], &[]);
            timer.reset(cmd);
            timer.begin(cmd, "transfer");
            // SAFETY: as above.
            unsafe {
                ctx.device().cmd_copy_buffer(
                    cmd,
                    a.handle(),
                    b.handle(),
                    &[vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes }],
                )
            };
            timer.end(cmd);
            cmd_barriers(ctx.device(), cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::COMPUTE_WRITE)], &[]);
            timer.begin(cmd, "compute");
            pipeline.bind(cmd);
            pipeline.push_bindings(cmd, &[Bind::Buffer(0, a.handle()), Bind::Buffer(1, b.handle())]);
            pipeline.push_constants(cmd, &count);
            // SAFETY: as above.
            unsafe { ctx.device().cmd_dispatch(cmd, groups, 1, 1) };
            timer.end(cmd);
            crate::gpu::GpuResult::Ok(())
        })?;
        for t in timer.results()? {
            if t.name == "transfer" {
                transfer.push(t.ms)
            } else {
                compute.push(t.ms)
            }
        }
    }
    Ok(gbps(2 * bytes, super::median(&mut transfer).min(super::median(&mut compute))))
}

/// The naive frustum peer over `scene`'s instances seen by `camera`: median milliseconds of
/// `repeats` runs and the survivors it found.
pub fn naive_frustum_ms(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &Scene,
    camera: &Camera,
    aspect: f32,
    repeats: usize,
) -> crate::Result<(f64, u32)> {
    let pipeline = Pipeline::compute(ctx, "naive frustum peer", &shaders.compile("bench/naive_frustum.comp", &[])?)?;
    // 64-byte records: world sphere (relative to the eye, as this peer has no hi/lo) + payload.
    let records: Vec<[f32; 16]> = scene
        .instances
        .iter()
        .map(|inst| {
            let mesh = &scene.meshes[inst.mesh as usize];
            let center = (inst.transform.apply(mesh.sphere.center) - camera.eye).as_vec3();
            let scale = inst
                .transform
                .linear
                .x_axis
                .length()
                .max(inst.transform.linear.y_axis.length())
                .max(inst.transform.linear.z_axis.length());
            let mut r = [1.0f32; 16];
            r[..4].copy_from_slice(&[center.x, center.y, center.z, mesh.sphere.radius * scale]);
            r
        })
        .collect();
    let mut uploads = UploadBatch::default();
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let records = uploads.buffer(ctx, "naive records", storage, bytemuck::cast_slice(&records))?;
    let counter = uploads.buffer(ctx, "naive counter", storage | vk::BufferUsageFlags::TRANSFER_SRC, &[0u8; 4])?;
    let out = Buffer::new(
        ctx,
        &BufferDesc {
            name: "naive survivors",
            size: scene.instances.len() as u64 * 4,
            usage: storage,
            location: MemoryLocation::GpuOnly,
        },
    )?;
    uploads.submit_and_wait(ctx)?;
    #[repr(C)]
    #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
    struct Push {
        planes: [[f32; 4]; 6],
        count: u32,
    }
    let push = Push { planes: frustum_planes(camera, aspect), count: scene.instances.len() as u32 };
    let groups = (scene.instances.len() as u32).div_ceil(256);
    let mut timer = GpuTimer::new(ctx, 1)?;
    let mut times = Vec::new();
    for _ in 0..repeats {
        ctx.submit_and_wait(|cmd| {
            // SAFETY: cmd recording; buffers live until the wait returns.
            unsafe { ctx.device().cmd_fill_buffer(cmd, counter.handle(), 0, 4, 0) };
            cmd_barriers(ctx.device(), cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::COMPUTE_WRITE)], &[]);
            timer.reset(cmd);
            timer.begin(cmd, "naive");
            pipeline.bind(cmd);
            pipeline.push_bindings(
                cmd,
                &[Bind::Buffer(0, records.handle()), Bind::Buffer(1, counter.handle()), Bind::Buffer(2, out.handle())],
            );
            pipeline.push_constants(cmd, &push);
            // SAFETY: as above.
            unsafe { ctx.device().cmd_dispatch(cmd, groups, 1, 1) };
            timer.end(cmd);
            cmd_barriers(ctx.device(), cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::TRANSFER_WRITE)], &[]);
            crate::gpu::GpuResult::Ok(())
        })?;
        times.extend(timer.results()?.into_iter().map(|t| t.ms));
    }
    let survivors = crate::gpu::transfer::read_buffer(ctx, &counter)?;
    Ok((super::median(&mut times), u32::from_le_bytes([survivors[0], survivors[1], survivors[2], survivors[3]])))
}

/// Six inward-facing planes (xyz normal, w distance) of `camera`'s frustum, eye-relative; a far
/// plane that never culls for perspective.
fn frustum_planes(camera: &Camera, aspect: f32) -> [[f32; 4]; 6] {
    let m = camera.view_projection_rel_eye(aspect);
    let row = |i: usize| Vec4::new(m.col(0)[i], m.col(1)[i], m.col(2)[i], m.col(3)[i]);
    let (r0, r1, r2, r3) = (row(0), row(1), row(2), row(3));
    let normalize = |p: Vec4| {
        let l = p.truncate().length().max(1e-20);
        (p / l).to_array()
    };
    // Reversed-Z: visible depth is in [0, 1] with 1 at the near plane.
    [normalize(r3 + r0), normalize(r3 - r0), normalize(r3 + r1), normalize(r3 - r1), normalize(r3 - r2), normalize(r2)]
}
