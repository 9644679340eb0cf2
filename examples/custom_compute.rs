//! A user compute shader on cullgraph's GPU layer: compile GLSL at run time (with `#include`
//! of cullgraph's headers), get the pipeline layout from reflection, dispatch, read back.
//!
//! `cargo run --release --example custom_compute`

use ash::vk;
use cullgraph::gpu::{transfer, GpuResult, UploadBatch};
use cullgraph::prelude::*;

const SHADER: &str = r#"#version 460
#include "common/octahedral.glsl"
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) buffer Normals { vec4 normals[]; };
layout(push_constant) uniform Push { uint count; };
// Round-trips each normal through cullgraph's octahedral encoding; w receives the error angle.
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    vec3 n = normalize(normals[i].xyz);
    vec3 back = oct_decode(oct_encode(n));
    // atan2 of sine and cosine stays accurate for tiny angles, where acos(dot) does not.
    normals[i] = vec4(back, degrees(atan(length(cross(n, back)), dot(n, back))));
}
"#;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = GpuContext::new(&ContextOptions::default())?;
    let shaders = ShaderCompiler::new(ShaderRoot::Embedded)?;
    let spirv = shaders.compile_source("examples/octahedral_check.comp", SHADER, &[])?;
    let pipeline = Pipeline::compute(&ctx, "octahedral check", &spirv)?;

    let count = 4096u32;
    let input: Vec<[f32; 4]> = (0..count)
        .map(|i| {
            let (a, b) = (i as f32 * 0.37, i as f32 * 0.11);
            [a.sin() * b.cos(), a.cos(), a.sin() * b.sin(), 0.0]
        })
        .collect();
    let mut uploads = UploadBatch::default();
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
    let buffer = uploads.buffer(&ctx, "normals", usage, bytemuck::cast_slice(&input))?;
    ctx.submit_and_wait(|cmd| {
        uploads.record(&ctx, cmd);
        pipeline.bind(cmd);
        pipeline.push_bindings(cmd, &[Bind::Buffer(0, buffer.handle())]);
        pipeline.push_constants(cmd, &count);
        unsafe { ctx.device().cmd_dispatch(cmd, count.div_ceil(64), 1, 1) };
        GpuResult::Ok(())
    })?;
    let out = transfer::read_buffer(&ctx, &buffer)?;
    let out: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let worst = out.iter().map(|v| v[3]).fold(0.0f32, f32::max);
    println!("octahedral round trip on {}: worst error {worst:.5} degrees over {count} normals", ctx.caps().name);
    Ok(())
}
