//! `cullgraph render --view ... --resize ...`: several views of one world per frame, and
//! outputs that change size while frames are rendered.

use super::args::{parse_size, parse_vec3, RenderArgs};
use super::paths;
use cullgraph::gpu::ShaderCompiler;
use cullgraph::render::output::save_png;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer, ViewId};
use cullgraph::scene::{Camera, Projection, Scene};
use cullgraph::stats::{RunStats, ViewRunStats};
use cullgraph::Result;
use glam::DVec3;

/// One `--view`: a camera and, optionally, its own field of view and size.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewArg {
    /// Camera position.
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Vertical field of view in degrees (default: the one of `--fov` or the scene's camera).
    pub fov: Option<f32>,
    /// Output size (default: `--size`).
    pub size: Option<(u32, u32)>,
}

/// Parses `eye=X,Y,Z;target=X,Y,Z;fov=DEG;size=WxH` (keys in any order, each at most once;
/// `eye` and `target` required).
pub fn parse_view(s: &str) -> Result<ViewArg, String> {
    let (mut eye, mut target, mut fov, mut size) = (None, None, None, None);
    for part in s.split(';').map(str::trim).filter(|p| !p.is_empty()) {
        let (key, value) = part.split_once('=').ok_or_else(|| format!("'{part}' is not KEY=VALUE"))?;
        let repeated = || format!("'{key}' is given twice");
        match key.trim() {
            "eye" if eye.is_none() => eye = Some(parse_vec3(value)?),
            "target" if target.is_none() => target = Some(parse_vec3(value)?),
            "fov" if fov.is_none() => {
                let deg: f32 = value.trim().parse().map_err(|_| format!("fov '{value}' is not a number"))?;
                if !(deg > 0.0 && deg < 180.0) {
                    return Err(format!("fov {value} must be between 0 and 180 degrees"));
                }
                fov = Some(deg);
            }
            "size" if size.is_none() => size = Some(parse_size(value)?),
            "eye" | "target" | "fov" | "size" => return Err(repeated()),
            other => return Err(format!("unknown key '{other}' (eye, target, fov, size)")),
        }
    }
    let eye = eye.ok_or("eye=X,Y,Z is missing")?;
    let target = target.ok_or("target=X,Y,Z is missing")?;
    if eye == target {
        return Err("eye and target are the same point".into());
    }
    Ok(ViewArg { eye, target, fov, size })
}

/// Parses `WxH@N`: from frame N on, the output is W x H.
pub fn parse_resize(s: &str) -> Result<((u32, u32), u32), String> {
    let (size, frame) = s.split_once('@').ok_or_else(|| format!("'{s}' is not WxH@FRAME (e.g. 640x360@10)"))?;
    let frame: u32 = frame.trim().parse().map_err(|_| format!("frame '{frame}' in '{s}' is not a frame number"))?;
    Ok((parse_size(size)?, frame))
}

/// The size every output has from frame `frame` on, given `--resize` (the last one listed for
/// the latest frame at or before `frame` wins); `None`: no resize reaches that frame.
pub fn size_at(resizes: &[((u32, u32), u32)], frame: u32) -> Option<(u32, u32)> {
    resizes.iter().filter(|(_, from)| *from <= frame).max_by_key(|(_, from)| *from).map(|(size, _)| *size)
}

/// `F.png` as the file of view `n`: `F.viewN.png`.
pub fn view_file(out: &std::path::Path, n: usize) -> std::path::PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "frame".into());
    let ext = out.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_else(|| "png".into());
    out.with_file_name(format!("{stem}.view{n}.{ext}"))
}

/// The output size of `view` (default `--size`).
pub fn view_size(args: &RenderArgs, view: &ViewArg) -> (u32, u32) {
    view.size.unwrap_or(args.size)
}

/// The camera of `view`: the scene's default camera for its aspect, with its eye, target and
/// field of view (`--fov`, `--near` and `--world-offset` apply to every view).
pub fn view_camera(args: &RenderArgs, scene: &Scene, view: &ViewArg) -> Result<Camera> {
    let (w, h) = view_size(args, view);
    let mut camera = scene.default_camera(w as f32 / h as f32);
    camera.eye = view.eye + args.world_offset.unwrap_or_default();
    camera.target = view.target + args.world_offset.unwrap_or_default();
    if let Some(fov) = view.fov.or(args.camera.fov) {
        camera.projection = Projection::Perspective { fov_y_deg: fov };
    }
    if let Some(near) = args.camera.near {
        camera.near = near;
    }
    super::render::apply_lens(args, &mut camera, view.fov.or(args.camera.fov), scene)?;
    camera.validate().map_err(|e| cullgraph::Error::Invalid(format!("--view {}: camera: {e}", view_label(view))))?;
    Ok(camera)
}

fn view_label(view: &ViewArg) -> String {
    format!(
        "eye={},{},{};target={},{},{}",
        view.eye.x, view.eye.y, view.eye.z, view.target.x, view.target.y, view.target.z
    )
}

/// Renders `args.frames` frames of every `--view` through `renderer` (whose main view is the
/// first), each frame all views in one command buffer; writes each view's last image and fills
/// `stats.views`. `step` runs before each frame (the traffic of `--animate`), `seen` after it
/// with each view's figures.
#[allow(clippy::too_many_arguments)]
pub fn render_views(
    args: &RenderArgs,
    renderer: &mut Renderer,
    shaders: &ShaderCompiler,
    spec: &GraphSpec,
    cameras: &[Camera],
    stats: &mut RunStats,
    mut step: impl FnMut(&mut Renderer) -> Result<()>,
    mut seen: impl FnMut(&cullgraph::stats::FrameStats),
) -> Result<()> {
    let mut ids = vec![ViewId::MAIN];
    for view in &args.views[1..] {
        let (w, h) = view_size(args, view);
        ids.push(renderer.add_view(shaders, RenderSettings::new(w, h), spec)?);
    }
    stats.views = ids
        .iter()
        .enumerate()
        .map(|(n, id)| ViewRunStats {
            view: id.number(),
            image: view_file(&args.out, n).display().to_string(),
            ..Default::default()
        })
        .collect();
    for frame in 0..args.frames {
        if let Some((w, h)) = size_at(&args.resizes, frame) {
            for &id in &ids {
                renderer.resize_view(shaders, id, w, h)?;
            }
        }
        step(renderer)?;
        let frame_cameras: Vec<Camera> = cameras
            .iter()
            .map(|c| {
                let mut camera = args.camera_path.camera_at(c, frame);
                if let Some(jitter) = args.jitter {
                    camera.jitter = jitter.at(frame);
                }
                camera
            })
            .collect();
        let views: Vec<(ViewId, &Camera)> = ids.iter().copied().zip(&frame_cameras).collect();
        let last = frame + 1 == args.frames;
        let rendered = if last {
            renderer.render_views_to_rgba8(&views)?
        } else {
            renderer.render_views(&views)?.into_iter().map(|s| (s, Vec::new())).collect()
        };
        for ((id, (frame_stats, bytes)), view_stats) in ids.iter().zip(rendered).zip(&mut stats.views) {
            seen(&frame_stats);
            if let Some(v) = frame_stats.verify.as_ref().filter(|v| v.false_negatives > 0) {
                eprintln!("frame {frame}, {id}: {} visible instance(s) culled, e.g. {:?}", v.false_negatives, v.missed);
            }
            if last {
                let settings = renderer.view_settings(*id)?;
                let image = cullgraph::render::output::rgba_from_bytes(settings.width, settings.height, bytes)?;
                let path = std::path::PathBuf::from(&view_stats.image);
                paths::output_file("--out", &path)?;
                save_png(&image, &path)?;
                (view_stats.width, view_stats.height) = (settings.width, settings.height);
                view_stats.view_bytes = renderer.view_runtime(*id)?.resource_bytes().iter().map(|r| r.bytes).sum();
            }
            // Every frame's figures only for `--stats`; otherwise the last, so memory stays flat.
            if args.stats.is_none() {
                view_stats.frames.clear();
            }
            view_stats.frames.push(frame_stats);
        }
        profiling::finish_frame!();
    }
    stats.frames = stats.views[0].frames.clone();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_parse_with_optional_keys_and_name_what_is_wrong() {
        let v = parse_view("eye=1,2,3;target=0,0,0").unwrap();
        assert_eq!((v.eye, v.target, v.fov, v.size), (DVec3::new(1.0, 2.0, 3.0), DVec3::ZERO, None, None));
        let v = parse_view("size=64x48; fov=30 ;target=0,1,0;eye=-1,2,3;").unwrap();
        assert_eq!((v.fov, v.size), (Some(30.0), Some((64, 48))));
        for (bad, says) in [
            ("target=0,0,0", "eye"),
            ("eye=1,1,1", "target"),
            ("eye=1,1,1;target=1,1,1", "same point"),
            ("eye=1,1,1;target=0,0,0;fov=180", "between 0 and 180"),
            ("eye=1,1,1;target=0,0,0;fov=abc", "not a number"),
            ("eye=1,1,1;target=0,0,0;size=0x4", "0x4"),
            ("eye=1,1,1;eye=2,2,2;target=0,0,0", "twice"),
            ("eye=1,1,1;target=0,0,0;zoom=2", "unknown key 'zoom'"),
            ("eye=1,1;target=0,0,0", "x,y,z"),
            ("eye", "KEY=VALUE"),
        ] {
            let err = parse_view(bad).unwrap_err();
            assert!(err.contains(says), "{bad}: {err}");
        }
    }

    #[test]
    fn resizes_apply_from_their_frame_on() {
        let resizes = [parse_resize("64x48@2").unwrap(), parse_resize("1x1@5").unwrap()];
        assert_eq!(resizes[0], ((64, 48), 2));
        let sizes: Vec<_> = (0..7).map(|f| size_at(&resizes, f)).collect();
        assert_eq!(sizes, [None, None, Some((64, 48)), Some((64, 48)), Some((64, 48)), Some((1, 1)), Some((1, 1))]);
        for bad in ["64x48", "64x48@x", "0x4@1", "64x48@-1"] {
            assert!(parse_resize(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn each_view_writes_its_own_file() {
        let out = std::path::Path::new("out/frame.png");
        assert_eq!(view_file(out, 0), std::path::Path::new("out/frame.view0.png"));
        assert_eq!(view_file(std::path::Path::new("f"), 3), std::path::Path::new("f.view3.png"));
    }
}
