//! The Hi-Z build pass on the GPU (lavapipe, validation and synchronization validation on): every
//! texel of every stored mip, for both methods (`single`, `per_mip`), equals the CPU oracle
//! [`HiZPyramid`] computed from the depth read back from the GPU, bit for bit: stored mip `m` is
//! the oracle's level `m + 1` ([`HiZPyramid::stored_level`]; the single texel of a 1×1 depth).
//!
//! Depth comes from draws into a real depth attachment (1× or 4×): a full-screen triangle whose
//! fragment shader writes a pattern into `gl_FragDepth` per sample (random, or descending /
//! ascending along the rows so that the minimum of every footprint sits at its last / first
//! texel, which exercises the folded odd rows and columns), or random triangles depth-tested
//! the reversed-Z way. A compute shader copies every sample into a buffer for the oracle.

mod common;

use ash::vk;
use common::{boxes_camera, boxes_scene, readback_buffer, GpuTest};
use cullgraph::cull::hiz::{level_offset, level_size, stored_mip_count, stored_size, HiZPyramid};
use cullgraph::gpu::barrier::{cmd_barriers, image_barrier, memory_barrier};
use cullgraph::gpu::cmd_set_full_viewport;
use cullgraph::gpu::{Access, Bind, Buffer, GraphicsDesc, Image, ImageDesc, Pipeline, Sampler, ShaderCompiler};
use cullgraph::passes::hiz_build::{HizBuildPass, HizMethod, HIZ_FORMAT};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use glam::UVec2;
use std::collections::HashMap;

const FILL_VERT: &str = r#"#version 460
layout(push_constant) uniform Push { uvec2 size; uint pattern; uint seed; uint samples; };
uint hash(uint x) {
    x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
    return x;
}
float unorm(uint h) { return float(h >> 8) * (1.0 / 16777216.0); }
void main() {
#ifdef TRIANGLES
    // Random triangles, from sub-pixel to a third of the screen, at random depths.
    uint tri = uint(gl_VertexIndex) / 3u;
    uint h = hash(tri * 0x9e3779b9u + seed);
    vec2 center = vec2(unorm(hash(h + 1u)), unorm(hash(h + 2u))) * 2.4 - 1.2;
    float radius = 0.6 * pow(unorm(hash(h + 3u)), 3.0);
    uint c = hash(h + 4u + uint(gl_VertexIndex) % 3u);
    vec2 corner = center + radius * (vec2(unorm(c), unorm(hash(c))) * 2.0 - 1.0);
    gl_Position = vec4(corner, unorm(hash(h + 9u)), 1.0);
#else
    vec2 uv = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(uv * 2.0 - 1.0, 0.0, 1.0);
#endif
}
"#;

const FILL_FRAG: &str = r#"#version 460
layout(push_constant) uniform Push { uvec2 size; uint pattern; uint seed; uint samples; };
uint hash(uint x) {
    x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
    return x;
}
void main() {
    uvec2 p = uvec2(gl_FragCoord.xy);
    uint s = uint(gl_SampleID);  // per-sample shading
    uint i = (p.y * size.x + p.x) * samples + s;
    uint n = size.x * size.y * samples;
    float d;
    if (pattern == 0u) {         // random per sample
        d = float(hash(hash(i) ^ seed) >> 8) * (1.0 / 16777216.0);
    } else if (pattern == 1u) {  // descending along rows: each footprint's min is its last texel
        d = float(n - i) / float(n);
    } else if (pattern == 2u) {  // ascending: each footprint's min is its first texel
        d = float(i + 1u) / float(n);
    } else {                     // constant blocks of 3x5 pixels, one sample 1.0 (nearest)
        d = s == 1u ? 1.0 : float(hash((p.y / 5u) * 4096u + p.x / 3u + seed) >> 8) * (1.0 / 16777216.0);
    }
    gl_FragDepth = d;
}
"#;

const READ_DEPTH: &str = r#"#version 460
layout(local_size_x = 8, local_size_y = 8) in;
#ifdef MSAA
layout(binding = 0) uniform sampler2DMS depth_tex;
#else
layout(binding = 0) uniform sampler2D depth_tex;
#endif
layout(binding = 1) writeonly buffer Out { float values[]; };
layout(push_constant) uniform Push { uvec2 size; uint samples; };
void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, size))) return;
    for (uint s = 0u; s < samples; ++s) {
        values[(p.y * size.x + p.x) * samples + s] = texelFetch(depth_tex, ivec2(p), int(s)).r;
    }
}
"#;

/// What the fill draw writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pattern {
    Random = 0,
    Descending = 1,
    Ascending = 2,
    Blocks = 3,
    Triangles = 4,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FillPush {
    size: [u32; 2],
    pattern: u32,
    seed: u32,
    samples: u32,
}

/// Pipelines shared by the cases of one test: depth fill and depth copy.
struct Tools {
    shaders: &'static ShaderCompiler,
    /// Per sample count: full-screen pattern, random triangles.
    fills: HashMap<u32, [Pipeline; 2]>,
    /// Depth copy, single-sample and multisampled.
    read_depth: [Pipeline; 2],
    sampler: Sampler,
    gpu: GpuTest,
}

/// The two passes under test and the tools (dropped last, the context last of all).
struct Harness {
    single: HizBuildPass,
    per_mip: HizBuildPass,
    tools: Tools,
}

/// A case's results: the depth as read back and each method's pyramid, its mips flat one after
/// another.
struct Outcome {
    depth: Vec<f32>,
    single: Vec<f32>,
    per_mip: Vec<f32>,
}

/// One case's images and readback buffers.
struct Case {
    depth: Image,
    depth_out: Buffer,
    hiz: [Image; 2],
    hiz_out: [Buffer; 2],
}

impl Tools {
    fn new() -> Self {
        let gpu = GpuTest::new();
        let shaders = gpu.shaders();
        let compute = |msaa: bool| {
            let defines: &[(&str, &str)] = if msaa { &[("MSAA", "1")] } else { &[] };
            let spirv = shaders.compile_source("hiz_test_read_depth.comp", READ_DEPTH, defines).unwrap();
            Pipeline::compute(&gpu, "read depth", &spirv).unwrap()
        };
        Self {
            fills: HashMap::new(),
            read_depth: [compute(false), compute(true)],
            sampler: Sampler::nearest_clamp(&gpu).unwrap(),
            shaders,
            gpu,
        }
    }

    fn prepare_fill(&mut self, samples: u32) {
        let (gpu, shaders) = (&self.gpu, &self.shaders);
        self.fills.entry(samples).or_insert_with(|| {
            let vert = shaders.compile_source("hiz_test_fill.vert", FILL_VERT, &[]).unwrap();
            let tri_vert = shaders.compile_source("hiz_test_fill.vert", FILL_VERT, &[("TRIANGLES", "1")]).unwrap();
            let frag = shaders.compile_source("hiz_test_fill.frag", FILL_FRAG, &[]).unwrap();
            let desc = |vertex, fragment, compare| GraphicsDesc {
                vertex,
                fragment,
                vertex_strides: &[],
                vertex_attributes: &[],
                color_formats: &[],
                depth_format: vk::Format::D32_SFLOAT,
                depth_compare: compare,
                depth_write: true,
                samples: vk::SampleCountFlags::from_raw(samples),
                stencil: Default::default(),
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                blend: false,
            };
            [
                Pipeline::graphics(gpu, "fill pattern", &desc(&vert, Some(&frag), vk::CompareOp::ALWAYS)).unwrap(),
                Pipeline::graphics(gpu, "fill triangles", &desc(&tri_vert, None, vk::CompareOp::GREATER)).unwrap(),
            ]
        });
    }

    fn case(&self, w: u32, h: u32, samples: u32, mips: u32) -> Case {
        let gpu = &self.gpu;
        let extent = vk::Extent2D { width: w, height: h };
        let pyramid = stored_size(UVec2::new(w, h));
        let depth = Image::new(
            gpu,
            &ImageDesc {
                name: "test depth",
                format: vk::Format::D32_SFLOAT,
                extent,
                mip_levels: 1,
                samples: vk::SampleCountFlags::from_raw(samples),
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
            },
        )
        .unwrap();
        let hiz = || {
            Image::new(
                gpu,
                &ImageDesc {
                    name: "test hiz",
                    format: HIZ_FORMAT,
                    extent: vk::Extent2D { width: pyramid.x, height: pyramid.y },
                    mip_levels: mips,
                    samples: vk::SampleCountFlags::TYPE_1,
                    usage: vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
                },
            )
            .unwrap()
        };
        let flat_bytes = level_offset(pyramid, mips) as u64 * 4;
        Case {
            depth,
            depth_out: readback_buffer(gpu, "depth readback", w as u64 * h as u64 * samples as u64 * 4),
            hiz: [hiz(), hiz()],
            hiz_out: [
                readback_buffer(gpu, "hiz readback", flat_bytes),
                readback_buffer(gpu, "hiz readback", flat_bytes),
            ],
        }
    }

    /// Draws the pattern into `depth` and leaves it in `SHADER_READ_ONLY_OPTIMAL` for compute.
    fn record_fill(&self, cmd: vk::CommandBuffer, depth: &Image, pattern: Pattern, seed: u32) {
        let device = self.gpu.device();
        let e = depth.extent();
        let samples = depth.samples().as_raw();
        let [fullscreen, triangles] = &self.fills[&samples];
        cmd_barriers(device, cmd, &[], &[image_barrier(depth, Access::NONE, Access::DEPTH_ATTACHMENT)]);
        let attachment = vk::RenderingAttachmentInfo::default()
            .image_view(depth.view())
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } });
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: e };
        let rendering = vk::RenderingInfo::default().render_area(area).layer_count(1).depth_attachment(&attachment);
        let (pipeline, vertices) = match pattern {
            Pattern::Triangles => (triangles, 3 * 400),
            _ => (fullscreen, 3),
        };
        let push = FillPush { size: [e.width, e.height], pattern: pattern as u32, seed, samples };
        // SAFETY: cmd recording; the image is in DEPTH_ATTACHMENT_OPTIMAL with attachment usage.
        unsafe {
            device.cmd_begin_rendering(cmd, &rendering);
            cmd_set_full_viewport(device, cmd, e);
            device.cmd_set_cull_mode(cmd, vk::CullModeFlags::NONE);
            pipeline.bind(cmd);
            pipeline.push_constants(cmd, &push);
            device.cmd_draw(cmd, vertices, 1, 0, 0);
            device.cmd_end_rendering(cmd);
        }
        let to_compute = image_barrier(depth, Access::DEPTH_ATTACHMENT, Access::COMPUTE_READ);
        cmd_barriers(device, cmd, &[], &[to_compute]);
    }

    /// Copies every depth sample into `out` (and makes it host-visible).
    fn record_read_depth(&self, cmd: vk::CommandBuffer, depth: &Image, out: &Buffer) {
        let e = depth.extent();
        let samples = depth.samples().as_raw();
        let pipeline = &self.read_depth[usize::from(samples > 1)];
        pipeline.bind(cmd);
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        pipeline.push_bindings(
            cmd,
            &[Bind::Sampled(0, depth.view(), self.sampler.handle(), read), Bind::Buffer(1, out.handle())],
        );
        pipeline.push_constants(cmd, &[e.width, e.height, samples]);
        let device = self.gpu.device();
        // SAFETY: cmd recording with the pipeline bound.
        unsafe { device.cmd_dispatch(cmd, e.width.div_ceil(8), e.height.div_ceil(8), 1) };
        cmd_barriers(device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::HOST_READ)], &[]);
    }

    /// Copies every mip of `hiz` (a single-sample 32-bit image in `state`, e.g. a pyramid or a
    /// D32 depth buffer) into `out`, levels one after another (the oracle's flat layout).
    fn record_read_hiz(&self, cmd: vk::CommandBuffer, hiz: &Image, state: Access, out: &Buffer) {
        let device = self.gpu.device();
        let base = UVec2::new(hiz.extent().width, hiz.extent().height);
        cmd_barriers(device, cmd, &[], &[image_barrier(hiz, state, Access::TRANSFER_READ)]);
        let regions: Vec<_> = (0..hiz.mip_levels())
            .map(|k| {
                let size = level_size(base, k);
                vk::BufferImageCopy::default()
                    .buffer_offset(level_offset(base, k) as u64 * 4)
                    .image_subresource(vk::ImageSubresourceLayers {
                        aspect_mask: hiz.aspect(),
                        mip_level: k,
                        base_array_layer: 0,
                        layer_count: 1,
                    })
                    .image_extent(vk::Extent3D { width: size.x, height: size.y, depth: 1 })
            })
            .collect();
        // SAFETY: image in TRANSFER_SRC_OPTIMAL with TRANSFER_SRC usage; the buffer holds every level.
        unsafe {
            device.cmd_copy_image_to_buffer(
                cmd,
                hiz.handle(),
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                out.handle(),
                &regions,
            )
        };
        cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::HOST_READ)], &[]);
    }
}

fn floats(b: &Buffer) -> Vec<f32> {
    bytemuck::cast_slice::<u8, f32>(b.read_bytes().unwrap()).to_vec()
}

impl Harness {
    fn new() -> Self {
        let tools = Tools::new();
        let (gpu, shaders) = (&tools.gpu, &tools.shaders);
        Self {
            single: HizBuildPass::with_method(gpu, shaders, "hiz single", HizMethod::Single).unwrap(),
            per_mip: HizBuildPass::with_method(gpu, shaders, "hiz per_mip", HizMethod::PerMip).unwrap(),
            tools,
        }
    }

    /// Fills a `w`×`h` depth buffer with `samples` samples, builds a pyramid of `mips` mips with
    /// both methods (`repeat` times each, into the same image), reads everything back.
    fn run(
        &mut self,
        (w, h, samples): (u32, u32, u32),
        pattern: Pattern,
        seed: u32,
        mips: u32,
        repeat: u32,
    ) -> Outcome {
        self.tools.prepare_fill(samples);
        let tools = &self.tools;
        let case = tools.case(w, h, samples, mips);
        let ctx: &cullgraph::gpu::GpuContext = &tools.gpu;
        let device = ctx.device();
        let (single, per_mip) = (&mut self.single, &mut self.per_mip);
        ctx.submit_and_wait(|cmd| {
            tools.record_fill(cmd, &case.depth, pattern, seed);
            for (pass, hiz) in [(single, &case.hiz[0]), (per_mip, &case.hiz[1])] {
                let mut before = Access::NONE;
                for _ in 0..repeat {
                    cmd_barriers(device, cmd, &[], &[image_barrier(hiz, before, Access::COMPUTE_WRITE)]);
                    pass.record_images(ctx, cmd, &case.depth, hiz)?;
                    before = Access::COMPUTE_WRITE;
                }
            }
            tools.record_read_depth(cmd, &case.depth, &case.depth_out);
            for (hiz, out) in case.hiz.iter().zip(&case.hiz_out) {
                tools.record_read_hiz(cmd, hiz, Access::COMPUTE_WRITE, out);
            }
            Ok::<(), cullgraph::Error>(())
        })
        .unwrap();
        Outcome { depth: floats(&case.depth_out), single: floats(&case.hiz_out[0]), per_mip: floats(&case.hiz_out[1]) }
    }

    /// Runs a case and compares both methods with the oracle (the first `mips` stored mips; all
    /// when `None`).
    fn check(&mut self, (w, h, samples): (u32, u32, u32), pattern: Pattern, seed: u32, mips: Option<u32>) {
        let mips = mips.unwrap_or_else(|| stored_mip_count(UVec2::new(w, h)));
        let out = self.run((w, h, samples), pattern, seed, mips, 1);
        // The data must exercise the reduction: varying depths, and per-sample values with MSAA.
        let varies = |d: &[f32]| d.iter().any(|&x| x.to_bits() != d[0].to_bits());
        if pattern != Pattern::Triangles && out.depth.len() > 1 {
            assert!(varies(&out.depth), "{w}x{h} x{samples} {pattern:?}: constant depth");
        }
        if pattern == Pattern::Triangles && w * h > 1000 {
            assert!(out.depth.iter().any(|&d| d > 0.0), "{w}x{h} x{samples}: no triangle drawn");
        }
        if samples > 1 && pattern == Pattern::Random {
            assert!(out.depth.chunks(samples as usize).all(varies), "{w}x{h}: samples of a pixel must differ");
        }
        let oracle = HiZPyramid::from_msaa_depth(w, h, samples, &out.depth);
        assert_pyramid(&oracle, mips, &out.single, &format!("single {w}x{h} x{samples} {pattern:?} seed {seed}"));
        assert_pyramid(&oracle, mips, &out.per_mip, &format!("per_mip {w}x{h} x{samples} {pattern:?} seed {seed}"));
    }
}

/// Every texel of the first `mips` stored mips of `gpu` (one after another) equals the oracle's
/// level `mip + 1`, bit for bit.
fn assert_pyramid(oracle: &HiZPyramid, mips: u32, gpu: &[f32], what: &str) {
    let pyramid = stored_size(oracle.base_size());
    assert_eq!(gpu.len(), level_offset(pyramid, mips) as usize, "{what}: texel count");
    for k in 0..mips {
        let level = oracle.stored_level(k);
        assert_eq!(UVec2::new(level.width, level.height), level_size(pyramid, k), "{what}: mip {k} size");
        let start = level_offset(pyramid, k) as usize;
        let mut wrong = Vec::new();
        for (i, (&want, &got)) in level.texels.iter().zip(&gpu[start..start + level.texels.len()]).enumerate() {
            if want.to_bits() != got.to_bits() {
                wrong.push((i as u32 % level.width, i as u32 / level.width, want, got));
            }
        }
        assert!(
            wrong.is_empty(),
            "{what}: mip {k} ({}x{}): {} texels differ, first (x, y, oracle, gpu): {:?}",
            level.width,
            level.height,
            wrong.len(),
            &wrong[..wrong.len().min(8)]
        );
    }
}

/// Sizes that exercise every footprint shape: unit, thin and odd axes, depths under 4 pixels and
/// 4..7-pixel edge blocks, a workgroup tile exactly, tiles plus folded remainders, and pyramids
/// with levels above the tiles (more than 6 stored mips).
const SIZES: &[(u32, u32)] = &[
    (1, 1),
    (1, 7),
    (7, 1),
    (2, 2),
    (3, 3),
    (5, 3),
    (4, 6),
    (15, 9),
    (64, 64),
    (65, 33),
    (127, 129),
    (128, 64),
    (191, 200),
    (130, 67),
    (255, 1),
    (1, 300),
    (1023, 767),
];

#[test]
fn both_methods_match_the_oracle_at_npot_odd_and_thin_sizes() {
    let mut h = Harness::new();
    for (i, &(w, hh)) in SIZES.iter().enumerate() {
        for pattern in [Pattern::Random, Pattern::Descending, Pattern::Ascending] {
            h.check((w, hh, 1), pattern, 17 + i as u32, None);
        }
    }
}

#[test]
fn msaa_4x_depth_is_reduced_across_samples_first() {
    let mut h = Harness::new();
    for (i, &(w, hh)) in [(1, 1), (1, 7), (5, 3), (65, 33), (127, 129), (300, 257)].iter().enumerate() {
        for pattern in [Pattern::Random, Pattern::Descending, Pattern::Blocks] {
            h.check((w, hh, 4), pattern, 100 + i as u32, None);
        }
    }
    h.check((1023, 767, 4), Pattern::Random, 7, None);
}

#[test]
fn random_triangles_give_the_oracle_pyramid() {
    let mut h = Harness::new();
    for seed in 0..3 {
        h.check((641, 479, 1), Pattern::Triangles, seed, None);
        h.check((333, 190, 4), Pattern::Triangles, seed, None);
    }
    h.check((1023, 767, 4), Pattern::Triangles, 9, None);
    h.check((1920, 1080, 1), Pattern::Triangles, 3, None);
}

#[test]
fn partial_mip_chains_match_the_oracle_prefix() {
    let mut h = Harness::new();
    h.check((300, 200, 1), Pattern::Random, 1, Some(3));
    h.check((129, 129, 1), Pattern::Descending, 2, Some(6)); // up to the tile level: no top pass
    h.check((1023, 767, 4), Pattern::Descending, 3, Some(7)); // one level above the tiles
    h.check((257, 3, 1), Pattern::Random, 4, Some(1));
    h.check((64, 9, 1), Pattern::Ascending, 5, Some(2));
}

#[test]
fn repeated_builds_into_one_image_give_the_oracle_pyramid() {
    let mut h = Harness::new();
    for (w, hh) in [(640u32, 480u32), (129, 1), (1100, 600), (4100, 3)] {
        for round in 0..2 {
            let out = h.run((w, hh, 1), Pattern::Random, 50 + round, stored_mip_count(UVec2::new(w, hh)), 3);
            let oracle = HiZPyramid::from_depth(w, hh, &out.depth);
            let mips = stored_mip_count(oracle.base_size());
            assert_pyramid(&oracle, mips, &out.single, &format!("single {w}x{hh} round {round}"));
            assert_pyramid(&oracle, mips, &out.per_mip, &format!("per_mip {w}x{hh} round {round}"));
        }
    }
}

const GRAPH: &str = r#"Graph(
    name: "hiz_test",
    params: { "method": "single" },
    resources: {
        "albedo": Image(format: R8G8B8A8_UNORM),
        "normal": Image(format: R16G16B16A16_SFLOAT),
        "depth": Image(format: D32_SFLOAT),
        "hiz": Image(format: R32_SFLOAT, size: Fixed("max(1, width / 2)", "max(1, height / 2)"), mips: All),
    },
    passes: [
        Pass(name: "gbuffer", kind: "gbuffer", writes: {"albedo": "albedo", "normal": "normal", "depth": "depth"}),
        Pass(name: "hiz", kind: "hiz_build", reads: {"depth": "depth"}, writes: {"hiz": "hiz"}, settings: {"method": "method"}),
    ],
    outputs: ["hiz", "depth"],
)"#;

#[test]
fn hiz_build_in_a_graph_reduces_the_gbuffer_depth() {
    let tools = Tools::new();
    let gpu = &tools.gpu;
    let (w, h) = (203u32, 131u32);
    for method in ["single", "per_mip"] {
        let spec = GraphSpec {
            text: GRAPH.into(),
            file: "hiz_test.ron".into(),
            dir: None,
            overrides: vec![("method".into(), method.into())],
            kinds: cullgraph::passes::builtin_kinds(),
            settings: Vec::new(),
        };
        let mut renderer =
            Renderer::with_graph(gpu, tools.shaders, boxes_scene(), RenderSettings::new(w, h), &spec).unwrap();
        let first = boxes_camera();
        let mut camera = first.clone();
        camera.eye.x -= 0.7;
        let base = UVec2::new(w, h);
        let pyramid = stored_size(base);
        let hiz_out = readback_buffer(gpu, "hiz readback", level_offset(pyramid, stored_mip_count(base)) as u64 * 4);
        let depth_out = readback_buffer(gpu, "depth readback", (w * h) as u64 * 4);
        let ctx: &cullgraph::gpu::GpuContext = gpu;
        ctx.submit_and_wait(|cmd| {
            // Two frames in one command buffer, so that synchronization validation sees the
            // second build's merges follow the first's reset only through the executor's barrier
            // (the pass's own dependency, folded into it).
            renderer.record(cmd, &first)?;
            renderer.record(cmd, &camera)?;
            let (hiz, hiz_state) = renderer.runtime().output_image(0).unwrap();
            assert_eq!(hiz.mip_levels(), stored_mip_count(base));
            assert_eq!((hiz.extent().width, hiz.extent().height), (pyramid.x, pyramid.y));
            tools.record_read_hiz(cmd, hiz, hiz_state, &hiz_out);
            let (depth, depth_state) = renderer.runtime().output_image(1).unwrap();
            tools.record_read_hiz(cmd, depth, depth_state, &depth_out);
            Ok::<(), cullgraph::Error>(())
        })
        .unwrap();
        let depth = floats(&depth_out);
        assert!(depth.iter().filter(|&&d| d > 0.0).count() > (w * h) as usize / 4, "the boxes cover the view");
        let oracle = HiZPyramid::from_depth(w, h, &depth);
        assert_pyramid(&oracle, stored_mip_count(base), &floats(&hiz_out), &format!("graph, method {method}"));
    }
}

#[test]
fn a_pyramid_of_the_wrong_size_is_rejected() {
    let mut h = Harness::new();
    let tools = &h.tools;
    let ctx: &cullgraph::gpu::GpuContext = &tools.gpu;
    let (w, hh) = (21u32, 11u32);
    let depth = tools.case(w, hh, 1, 1).depth;
    let hiz = |width, height, mips| {
        Image::new(
            ctx,
            &ImageDesc {
                name: "bad hiz",
                format: HIZ_FORMAT,
                extent: vk::Extent2D { width, height },
                mip_levels: mips,
                samples: vk::SampleCountFlags::TYPE_1,
                usage: vk::ImageUsageFlags::STORAGE,
            },
        )
        .unwrap()
    };
    // The depth's own size (a pyramid that would store level 0 too), and half rounded up. (A
    // pyramid of the right size cannot have too many mips: its own chain is the depth's minus 1.)
    let cases = [(hiz(w, hh, 1), "it must be 10x5"), (hiz(11, 6, 1), "it must be 10x5")];
    for (image, want) in &cases {
        for pass in [&mut h.single, &mut h.per_mip] {
            let err = ctx
                .submit_and_wait(|cmd| pass.record_images(ctx, cmd, &depth, image))
                .expect_err("the pass must reject the pyramid")
                .to_string();
            assert!(err.contains(want), "{err}");
        }
    }
}
