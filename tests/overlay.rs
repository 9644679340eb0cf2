//! The culling-stat overlay (`graph/overlay.ron`, kind `overlay`) on lavapipe with validation on:
//! the panel reads back as exactly this frame's counters (each glyph cell decoded against
//! font8x8), view "stats" touches nothing outside the panel, and the debug views are what they
//! claim and deterministic.

mod common;

use common::{city_view, cube_mesh, GpuTest};
use cullgraph::graph::plan::ResolvedKind;
use cullgraph::passes::instance_cull::CullPassStats;
use cullgraph::passes::lighting_compressed::GbufferPassStats;
use cullgraph::passes::overlay::{glyph, glyph_origin, panel_rect, BAR_CHARS, LABEL_COLOR, MAX_COLS, NUMBER_COLOR};
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::{Camera, Instance, Material, Scene, Transform};
use cullgraph::stats::FrameStats;
use glam::{DVec3, Mat3, Vec3};

fn overlay_graph(params: &[(&str, &str)]) -> GraphSpec {
    GraphSpec::builtin("overlay").unwrap().with_overrides(params.iter().map(|(k, v)| (k.to_string(), v.to_string())))
}

/// Renders `frames` frames of `spec`; the last frame's stats and image.
fn render(
    gpu: &GpuTest,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    spec: &GraphSpec,
    frames: u32,
) -> (FrameStats, RgbaImage, Renderer) {
    let shaders = gpu.shaders();
    let mut r = Renderer::with_graph(gpu, shaders, scene.clone(), RenderSettings::new(size.0, size.1), spec).unwrap();
    let mut last = None;
    for _ in 0..frames {
        last = Some(r.render_to_image(camera).unwrap());
    }
    let (stats, image) = last.unwrap();
    (stats, image, r)
}

/// One decoded glyph cell: the character whose font8x8 bitmap matches the text-colored pixels
/// exactly (`'\u{FFFD}'` when none does), and whether they are number-colored.
fn read_cell(image: &RgbaImage, row: u32, col: u32, scale: u32) -> Option<(char, bool)> {
    let (x0, y0) = glyph_origin(row, col, scale);
    if x0 + 8 * scale > image.width() || y0 + 8 * scale > image.height() {
        return None;
    }
    let mut bits = [0u8; 8];
    let mut number = false;
    for (y, byte) in bits.iter_mut().enumerate() {
        for x in 0..8 {
            let p = image.get_pixel(x0 + x * scale, y0 + y as u32 * scale);
            let rgb = [p[0], p[1], p[2]];
            if rgb == LABEL_COLOR || rgb == NUMBER_COLOR {
                *byte |= 1 << x;
                number |= rgb == NUMBER_COLOR;
            }
        }
    }
    let c = (32u8..127).map(char::from).find(|&c| glyph(c) == bits).unwrap_or('\u{FFFD}');
    Some((c, number))
}

/// The panel's first `rows` rows as text (trailing blanks removed).
fn read_panel(image: &RgbaImage, rows: u32, scale: u32) -> Vec<String> {
    (0..rows)
        .map(|row| {
            let line: String =
                (0..MAX_COLS as u32).map_while(|col| read_cell(image, row, col, scale)).map(|(c, _)| c).collect();
            line.trim_end().to_string()
        })
        .collect()
}

/// Pixels of `a` and `b` that differ outside the rectangle `rect` (end exclusive).
fn differences_outside(a: &RgbaImage, b: &RgbaImage, rect: (u32, u32, u32, u32)) -> Vec<(u32, u32)> {
    let (x0, y0, x1, y1) = rect;
    a.enumerate_pixels()
        .filter(|(x, y, p)| !(*x >= x0 && *x < x1 && *y >= y0 && *y < y1) && **p != *b.get_pixel(*x, *y))
        .map(|(x, y, _)| (x, y))
        .collect()
}

#[test]
fn stats_panel_shows_this_frames_counters_and_touches_nothing_else() {
    let gpu = GpuTest::new();
    let size = (480, 270);
    let (scene, camera) = city_view(2000, size);
    let (lit_stats, lit, lit_renderer) = render(&gpu, &scene, &camera, size, &GraphSpec::default_graph(), 3);
    let (stats, image, renderer) = render(&gpu, &scene, &camera, size, &overlay_graph(&[]), 3);
    // The overlay changes nothing the frame computes.
    let counters =
        |s: &FrameStats| (s.frustum_culled, s.occlusion_culled, s.drawn, s.draws, s.triangles, CullPassStats::of(s));
    assert_eq!(counters(&stats), counters(&lit_stats));
    assert!(stats.occlusion_culled > 0 && stats.frustum_culled > 0, "{stats:?}");
    // graph/overlay.ron is graph/default.ron plus the overlay pass: the other passes are the same.
    let passes = |r: &Renderer| -> Vec<String> {
        let plan = r.plan();
        plan.passes
            .iter()
            .filter(|p| p.kind != "overlay")
            .map(|p| {
                let bindings: Vec<_> = p
                    .bindings
                    .iter()
                    .map(|b| (&b.slot, &plan.resources[b.resource].name, b.version, b.usage))
                    .collect();
                format!("{} {} {:?} {:?}", p.name, p.kind, p.settings, bindings)
            })
            .collect()
    };
    assert_eq!(passes(&renderer), passes(&lit_renderer), "graph/overlay.ron no longer matches graph/default.ron");

    // What the panel must say, from the CPU's readback of the same frame's counters.
    let passes = CullPassStats::of(&stats);
    let [early, late] = &passes[..] else { panic!("two cull passes expected: {stats:?}") };
    let widest = passes.iter().max_by_key(|p| p.tested).unwrap();
    let mut expected = vec![
        format!("instances {}  tested {}", stats.instances, widest.tested),
        format!("frustum culled {}", stats.frustum_culled),
        format!("occlusion culled {}", stats.occlusion_culled),
        format!("drawn {} (early {}, late {})", stats.drawn, early.drawn, late.drawn),
        format!("draws {}  triangles {}", stats.draws, stats.triangles),
        format!("gpu ms (frame {})", stats.frame - 1),
    ];
    let stat_rows = expected.len();
    // Times shown are those of the previous frame (the newest completed when this one was recorded).
    let timings = renderer.completed_timings(stats.frame - 1).unwrap();
    let names: Vec<&str> = renderer.plan().passes.iter().map(|p| p.name.as_str()).collect();
    let width = names.iter().map(|n| n.len()).max().unwrap().max(5);
    let mut times = Vec::new();
    for name in names.iter().copied().chain(["frame"]) {
        let ms = timings.iter().find(|t| t.name == name).unwrap_or_else(|| panic!("no time for {name}")).ms;
        let label = if name == "frame" { "total" } else { name };
        expected.push(format!("{label:width$}"));
        times.push(ms);
    }

    let lines = read_panel(&image, expected.len() as u32, 1);
    assert_eq!(lines[..stat_rows], expected[..stat_rows], "panel:\n{}", lines.join("\n"));
    for (k, ms) in times.iter().enumerate() {
        let line = &lines[stat_rows + k];
        let (label, value) = line.split_at(width.min(line.len()));
        assert_eq!(label, expected[stat_rows + k], "row {}: {line:?}", stat_rows + k);
        let shown: f64 = value.trim().parse().unwrap_or_else(|_| panic!("row {}: {line:?}", stat_rows + k));
        assert!((shown - ms).abs() <= 0.0011 + ms * 1e-6, "row {}: {line:?} but the pass took {ms} ms", stat_rows + k);
        assert_eq!(value.len(), 9, "times are right-aligned in 8 characters: {line:?}");
    }
    // Digits of the fields are number-colored, labels are not.
    assert_eq!(read_cell(&image, 0, 0, 1), Some(('i', false)));
    assert_eq!(read_cell(&image, 0, 10, 1), Some((stats.instances.to_string().chars().next().unwrap(), true)));

    // The panel spans the widest row (the time rows' bars reach bar column + BAR_CHARS), and the
    // image outside it is the default graph's, pixel for pixel.
    let bar_end = width + 1 + 8 + 1 + BAR_CHARS as usize;
    let cols = expected.iter().map(|l| l.len()).chain([bar_end]).max().unwrap() as u32;
    let rect = panel_rect(cols, expected.len() as u32, 1);
    assert!(rect.2 < size.0 && rect.3 < size.1, "{rect:?}");
    let outside = differences_outside(&image, &lit, rect);
    assert!(
        outside.is_empty(),
        "{} pixels outside the panel {rect:?} changed, e.g. {:?}",
        outside.len(),
        &outside[..outside.len().min(8)]
    );
    // Its last column and row are panel (darkened), so the GPU's width and height are exactly these.
    let edge: Vec<(u32, u32)> =
        (rect.1..rect.3).map(|y| (rect.2 - 1, y)).chain((rect.0..rect.2).map(|x| (x, rect.3 - 1))).collect();
    let darkened = edge.iter().filter(|&&(x, y)| image.get_pixel(x, y) != lit.get_pixel(x, y)).count();
    assert!(darkened * 10 >= edge.len() * 9, "only {darkened} of {} edge pixels belong to the panel", edge.len());
}

/// A wall in front of six boxes, one box beside it (tests/culling.rs's scene).
fn wall_scene() -> Scene {
    let mut scene = Scene { name: "wall".into(), ..Default::default() };
    let cube = scene.add_mesh("cube", &cube_mesh(), "cube").unwrap();
    let grey = scene.add_material(Material::default());
    let red = scene.add_material(Material {
        name: "red".into(),
        albedo: Vec3::new(0.8, 0.1, 0.1),
        roughness: 0.5,
        metallic: 0.0,
        double_sided: false,
        ..Default::default()
    });
    let mut place = |scale: Vec3, at: DVec3, material: u32| {
        scene.instances.push(Instance {
            transform: Transform { linear: Mat3::from_diagonal(scale), translation: at },
            mesh: cube,
            material,
            flags: 0,
        })
    };
    place(Vec3::new(40.0, 0.2, 40.0), DVec3::new(0.0, -0.1, 0.0), grey);
    place(Vec3::new(8.0, 6.0, 0.5), DVec3::new(0.0, 3.0, -4.0), grey);
    for i in 0..6 {
        place(Vec3::ONE, DVec3::new(-2.5 + i as f64, 2.5, -8.0), red);
    }
    place(Vec3::ONE, DVec3::new(6.0, 0.5, -6.0), red);
    scene
}

fn wall_camera() -> Camera {
    Camera { eye: DVec3::new(0.0, 1.5, 4.0), target: DVec3::new(0.0, 1.5, -10.0), ..Default::default() }
}

#[test]
fn hiz_view_shows_a_pyramid_level_in_grey_and_is_deterministic() {
    let gpu = GpuTest::new();
    let size = (320, 240);
    let spec = overlay_graph(&[("overlay_view", "hiz"), ("hiz_level", "2"), ("overlay_timings", "false")]);
    let (_, lit, _) = render(&gpu, &wall_scene(), &wall_camera(), size, &GraphSpec::default_graph(), 2);
    let (stats, image, renderer) = render(&gpu, &wall_scene(), &wall_camera(), size, &spec, 2);
    let (_, again, _) = render(&gpu, &wall_scene(), &wall_camera(), size, &spec, 2);
    assert!(image.as_raw() == again.as_raw(), "the hiz view differs between two runs");
    // The legend names the mip shown; the pyramid may start below the image's size.
    let plan = renderer.plan();
    let hiz = plan.resources.iter().find(|r| r.name == "hiz").unwrap();
    let ResolvedKind::Image { extent, mip_levels, .. } = hiz.kind else { panic!("{hiz:?}") };
    let first = (0..4).find(|k| (size.0 >> k, size.1 >> k) == (extent.width, extent.height)).unwrap();
    let block = 1u32 << (first + 2);
    let lines = read_panel(&image, 6, 1);
    let legend = format!("hi-z mip 2/{} ({}x{}), white = near", mip_levels - 1, extent.width >> 2, extent.height >> 2);
    assert_eq!(lines[5], legend, "panel:\n{}", lines.join("\n"));
    assert_eq!(lines[0], format!("instances {}  tested {}", stats.instances, stats.instances));

    // Below the panel: grey levels, constant over each texel of mip 2 (nearest upsampling), sky
    // black, nearer surfaces lighter, and not the lit image.
    let top = panel_rect(40, 6, 1).3;
    let mut differ = 0;
    for y in top..size.1 {
        for x in 0..size.0 {
            let p = image.get_pixel(x, y);
            assert!(p[0] == p[1] && p[1] == p[2], "({x}, {y}) is not grey: {p:?}");
            let (tx, ty) = (x / block * block, (y / block * block).max(top));
            assert_eq!(p, image.get_pixel(tx, ty), "({x}, {y}) differs from its texel's first pixel");
            differ += usize::from(p != lit.get_pixel(x, y));
        }
    }
    assert!(differ > (size.1 - top) as usize * size.0 as usize / 2, "only {differ} pixels differ from the lit image");
    let grey = |x: u32, y: u32| image.get_pixel(x, y)[0];
    // The ground right below the eye is nearer than the wall's middle, which is nearer than nothing.
    assert!(grey(160, 236) > grey(160, 130) && grey(160, 130) > 0, "{} {}", grey(160, 236), grey(160, 130));
}

#[test]
fn culled_view_tints_exactly_the_occlusion_culled_instances() {
    let gpu = GpuTest::new();
    let size = (480, 270);
    let (scene, camera) = city_view(2000, size);
    let spec = overlay_graph(&[("overlay_view", "culled"), ("overlay_timings", "false")]);
    let (_, lit, _) = render(&gpu, &scene, &camera, size, &GraphSpec::default_graph(), 3);
    let (stats, image, _) = render(&gpu, &scene, &camera, size, &spec, 3);
    let (_, again, _) = render(&gpu, &scene, &camera, size, &spec, 3);
    assert!(image.as_raw() == again.as_raw(), "the culled view differs between two runs");
    assert!(stats.occlusion_culled > 0, "{stats:?}");
    // The view marks exactly the instances the late pass counted as occlusion-culled (the same
    // frustum test, and not visible after the late pass).
    let lines = read_panel(&image, 6, 1);
    assert_eq!(lines[5], format!("red: {} occlusion-culled instances", stats.occlusion_culled), "{}", lines.join("\n"));

    // Outside the panel, every changed pixel moved towards red (tint) or is the edge red.
    let rect = panel_rect(MAX_COLS as u32, 6, 1);
    let tinted = differences_outside(&image, &lit, (0, 0, size.0, rect.3));
    assert!(!tinted.is_empty(), "nothing tinted");
    let red = [255.0, 41.0, 41.0];
    let distance = |p: &image::Rgba<u8>| (0..3).map(|c| (p[c] as f64 - red[c]).powi(2)).sum::<f64>().sqrt();
    let mut edges = 0;
    for &(x, y) in &tinted {
        let (p, q) = (image.get_pixel(x, y), lit.get_pixel(x, y));
        assert!(distance(p) < distance(q) + 2.0, "({x}, {y}) changed from {q:?} to {p:?}, not towards red");
        edges += usize::from(p.0[..3] == [255, 41, 41]);
    }
    assert!(edges > 0, "no rectangle edge drawn among {} tinted pixels", tinted.len());
}

#[test]
fn the_overlay_flags_of_cullgraph_render() {
    let tmp = tempfile::tempdir().unwrap();
    for view in [None, Some("hiz"), Some("culled")] {
        let out = tmp.path().join(format!("{}.png", view.unwrap_or("stats")));
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_cullgraph"));
        cmd.env("CULLGRAPH_DEVICE", std::env::var("CULLGRAPH_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into()));
        cmd.args(["render", "--instances", "1000", "--size", "200x120", "--frames", "2", "--validation", "--out"]);
        cmd.arg(&out);
        match view {
            Some(v) => cmd.args(["--overlay-view", v]),
            None => cmd.arg("--overlay"),
        };
        let result = cmd.output().unwrap();
        let stdout = String::from_utf8_lossy(&result.stdout);
        assert!(result.status.success(), "{view:?}: {stdout}\n{}", String::from_utf8_lossy(&result.stderr));
        assert!(stdout.contains("through 'overlay'"), "{stdout}");
        assert!(out.exists());
    }
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cullgraph"))
        .args(["render", "--overlay", "--no-cull"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn the_compressed_gbuffers_counters_on_the_panel_are_this_frames() {
    let gpu = GpuTest::new();
    let size = (480, 270);
    let (scene, camera) = city_view(2000, size);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let example = GraphSpec::from_file(&root.join("graph/examples/msaa_overlay.ron")).unwrap();
    // A pool this small overflows, so that every figure on the row is one the frame made.
    for pool_fraction in ["0.5", "0.004"] {
        let spec = example.clone().with_overrides([("pool_fraction".to_string(), pool_fraction.to_string())]);
        let (stats, image, _) = render(&gpu, &scene, &camera, size, &spec, 2);
        let g = &GbufferPassStats::of(&stats)[0];
        let edges: u32 = g.surfaces_per_pixel[1..].iter().sum();
        let lines = read_panel(&image, 8, 1);
        let row = |prefix: &str| lines.iter().find(|l| l.starts_with(prefix)).cloned().unwrap_or_default();
        assert_eq!(
            row("pool blocks"),
            format!("pool blocks {} / {}  overflow {} samples", g.pool_used, g.pool_blocks, g.overflow_samples),
            "panel:\n{}",
            lines.join("\n")
        );
        assert_eq!(row("pixels with"), format!("pixels with 2+ surfaces {edges}"));
        assert!(edges > 0, "the city has edge pixels");
        if pool_fraction == "0.004" {
            assert!(g.overflow_samples > 0 && g.pool_used == g.pool_blocks, "{g:?}");
        }
    }
}
