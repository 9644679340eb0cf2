//! Device creation, compute round trips, validation counting and shader errors.

mod common;

use ash::vk;
use common::GpuTest;
use cullgraph::gpu::{
    transfer, Bind, Buffer, BufferDesc, GpuTimer, MemoryLocation, Pipeline, ShaderError, UploadBatch,
};

#[test]
fn creates_a_validated_device_on_lavapipe() {
    let gpu = GpuTest::new();
    let caps = gpu.caps();
    assert!(!caps.name.is_empty());
    assert!(caps.subgroup_size >= 1);
    assert!(caps.timestamp_valid_bits > 0, "timestamps are needed for per-pass timings");
}

#[test]
fn compute_shader_round_trip_with_timestamps() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let source = r#"#version 460
        layout(local_size_x = 64) in;
        layout(set = 0, binding = 0) buffer Data { uint values[]; };
        layout(push_constant) uniform Push { uint count; uint add; };
        void main() {
            uint i = gl_GlobalInvocationID.x;
            if (i < count) values[i] = values[i] * 3u + add;
        }"#;
    let spirv = shaders.compile_source("test/triple.comp", source, &[]).unwrap();
    let pipeline = Pipeline::compute(&gpu, "triple", &spirv).unwrap();
    assert_eq!(pipeline.interface().local_size, Some([64, 1, 1]));
    assert_eq!(pipeline.interface().push_constant_bytes, 8);

    let input: Vec<u32> = (0..1000).collect();
    let mut batch = UploadBatch::default();
    let data = batch
        .buffer(
            &gpu,
            "data",
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            bytemuck::cast_slice(&input),
        )
        .unwrap();
    let mut timer = GpuTimer::new(&gpu, 4).unwrap();
    gpu.submit_and_wait(|cmd| {
        batch.record(&gpu, cmd);
        timer.reset(cmd);
        timer.begin(cmd, "triple");
        pipeline.bind(cmd);
        pipeline.push_bindings(cmd, &[Bind::Buffer(0, data.handle())]);
        pipeline.push_constants(cmd, &[1000u32, 7u32]);
        unsafe { gpu.device().cmd_dispatch(cmd, 1000u32.div_ceil(64), 1, 1) };
        timer.end(cmd);
        cullgraph::gpu::GpuResult::Ok(())
    })
    .unwrap();
    let out = transfer::read_buffer(&gpu, &data).unwrap();
    let out: &[u32] = bytemuck::cast_slice(&out);
    assert!(out.iter().enumerate().all(|(i, &v)| v == i as u32 * 3 + 7));
    let timings = timer.results().unwrap();
    assert_eq!(timings.len(), 1);
    assert_eq!(timings[0].name, "triple");
    assert!(timings[0].ms >= 0.0 && timings[0].ms < 10_000.0);
}

#[test]
fn a_synchronization_hazard_is_counted() {
    // The harness is only worth something if a real hazard reaches the counter.
    let gpu = GpuTest::new();
    let buffer = Buffer::new(
        &gpu,
        &BufferDesc {
            name: "hazard",
            size: 256,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuOnly,
        },
    )
    .unwrap();
    gpu.submit_and_wait(|cmd| {
        unsafe {
            gpu.device().cmd_fill_buffer(cmd, buffer.handle(), 0, 256, 1);
            gpu.device().cmd_fill_buffer(cmd, buffer.handle(), 0, 256, 2);
        }
        cullgraph::gpu::GpuResult::Ok(())
    })
    .unwrap();
    let messages = gpu.validation_log().messages();
    assert!(messages.iter().any(|m| m.contains("SYNC-HAZARD-WRITE-AFTER-WRITE")), "{messages:?}");
    // Expected here: clear the log so the harness does not fail this test on drop.
    std::mem::forget(gpu);
}

#[test]
fn shader_compile_errors_name_file_and_line() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let source = "#version 460\nlayout(local_size_x = 1) in;\nvoid main() {\n    undeclared_thing = 1;\n}\n";
    let err = shaders.compile_source("cull/broken.comp", source, &[]).unwrap_err();
    match &err {
        ShaderError::Compile { diagnostics, .. } => {
            let d = &diagnostics[0];
            assert_eq!((d.file.as_str(), d.line), ("cull/broken.comp", 4), "{err}");
            assert!(d.message.contains("undeclared_thing"), "{err}");
        }
        other => panic!("expected a compile error, got {other}"),
    }
    assert!(err.to_string().contains("cull/broken.comp:4: error:"), "{err}");
    // An error inside an included header names the header.
    let err = shaders
        .compile_source("x.comp", "#version 460\n#include \"common/missing.glsl\"\nvoid main(){}\n", &[])
        .unwrap_err();
    assert!(err.to_string().contains("common/missing.glsl"), "{err}");
    assert!(matches!(shaders.compile("no/such.comp", &[]), Err(ShaderError::NotFound(_))));
}

#[test]
fn every_library_shader_compiles() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut compiled = 0;
    for dir in std::fs::read_dir(&root).unwrap().flatten() {
        for file in std::fs::read_dir(dir.path()).into_iter().flatten().flatten() {
            let rel = file.path().strip_prefix(&root).unwrap().to_string_lossy().into_owned();
            if rel.ends_with(".comp") || rel.ends_with(".vert") || rel.ends_with(".frag") {
                shaders.compile(&rel, &[]).unwrap_or_else(|e| panic!("{e}"));
                compiled += 1;
            }
        }
    }
    assert!(compiled >= 3);
}

#[test]
fn a_hosts_extra_extensions_are_enabled_once_and_missing_ones_are_named() {
    use cullgraph::gpu::{ContextOptions, GpuContext};
    use std::ffi::CString;
    let device = std::env::var("CULLGRAPH_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let options = |instance: Vec<CString>, device_extensions: Vec<CString>| ContextOptions {
        device: device.parse().unwrap(),
        validation: true,
        app_name: "cullgraph-test".into(),
        instance_extensions: instance,
        device_extensions,
    };
    // Names cullgraph enables itself (debug utils with validation, push descriptors), and
    // the swapchain a window needs: each enabled once, and no validation message.
    let ctx = GpuContext::new(&options(
        vec![CString::from(ash::ext::debug_utils::NAME), CString::from(ash::khr::surface::NAME)],
        vec![CString::from(ash::khr::push_descriptor::NAME), CString::from(ash::khr::swapchain::NAME)],
    ))
    .unwrap();
    assert_eq!(ctx.validation_log().count(), 0, "{:?}", ctx.validation_log().messages());
    drop(ctx);
    let missing = GpuContext::new(&options(vec![], vec![CString::new("VK_NOPE_not_an_extension").unwrap()]));
    let e = missing.err().expect("refused").to_string();
    assert!(e.contains("VK_NOPE_not_an_extension"), "{e}");
    let missing = GpuContext::new(&options(vec![CString::new("VK_NOPE_instance").unwrap()], vec![]));
    let e = missing.err().expect("refused").to_string();
    assert!(e.contains("VK_NOPE_instance"), "{e}");
}
