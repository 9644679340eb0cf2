//! Where the viewer can jump to: the scene's own camera, the player spawn points of a game
//! level (`nexuiz_spawns.txt` beside a `nexuiz_MAP.glb`, or `--spawns FILE`), and a view that
//! frames the whole scene.

use cullgraph::scene::{Camera, Scene};
use cullgraph::{Error, Result};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// The file of spawn points looked for beside a scene file.
pub const SPAWNS_FILE: &str = "nexuiz_spawns.txt";

/// A named place to look from.
#[derive(Clone, Debug)]
pub struct Spawn {
    /// What the viewer prints when it jumps there.
    pub name: String,
    /// Eye and target (the projection is the viewer's).
    pub camera: Camera,
}

/// The spawn points of `scene` (loaded from `scene_arg`), the first being where the viewer
/// starts (`start`): then the scene's camera, the file's points for this map, and a view of
/// the whole scene. `explicit` names a spawn file; otherwise one beside the scene is read if
/// there is one.
pub fn spawns(scene_arg: &str, scene: &Scene, start: &Camera, explicit: Option<&Path>) -> Result<Vec<Spawn>> {
    let mut out = vec![Spawn { name: "start".into(), camera: start.clone() }];
    if let Some(camera) = &scene.camera {
        out.push(Spawn { name: "the scene's camera".into(), camera: camera.clone() });
    }
    let file = explicit.map(Path::to_path_buf).or_else(|| beside(scene_arg));
    if let Some(file) = file {
        let text = cullgraph::files::read_limited_text(&file, cullgraph::files::GRAPH_LIMIT, "spawn file")
            .map_err(|e| Error::Io { path: file.display().to_string(), source: std::io::Error::other(e) })?;
        let map = map_name(scene_arg);
        for (n, (eye, target)) in parse(&file.display().to_string(), &text, map.as_deref())?.into_iter().enumerate() {
            let camera = Camera { eye, target, ..start.clone() };
            out.push(Spawn { name: format!("spawn {} of {}", n + 1, map.as_deref().unwrap_or("the file")), camera });
        }
    }
    if let Some((min, max)) = scene.world_bounds() {
        let framing = Camera::framing(min, max, 16.0 / 9.0);
        out.push(Spawn {
            name: "the whole scene".into(),
            camera: Camera { eye: framing.eye, target: framing.target, ..start.clone() },
        });
    }
    Ok(out)
}

/// `nexuiz_spawns.txt` in the scene file's folder, when the scene is a file and it exists.
fn beside(scene_arg: &str) -> Option<PathBuf> {
    if scene_arg.starts_with("builtin:") {
        return None;
    }
    let file = Path::new(scene_arg).parent()?.join(SPAWNS_FILE);
    file.is_file().then_some(file)
}

/// `MAP` of a scene file named `nexuiz_MAP.glb` (any extension), else the file's stem.
fn map_name(scene_arg: &str) -> Option<String> {
    let stem = Path::new(scene_arg).file_stem()?.to_str()?;
    Some(stem.strip_prefix("nexuiz_").unwrap_or(stem).to_string())
}

/// The points of `text`'s lines `MAP x,y,z x,y,z` (eye, target) for `map` (all of them when
/// `map` is `None`, or when no line names it); errors name `file:line`.
pub fn parse(file: &str, text: &str, map: Option<&str>) -> Result<Vec<(DVec3, DVec3)>> {
    let mut all = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let at = |why: &str| Error::Invalid(format!("{file}:{}: {why}", n + 1));
        let words: Vec<&str> = line.split_whitespace().collect();
        let [name, eye, target] = words[..] else { return Err(at("expected `MAP x,y,z x,y,z` (eye, then target)")) };
        let point = |s: &str| super::super::args::parse_vec3(s).map_err(|e| at(&e));
        let (eye, target) = (point(eye)?, point(target)?);
        if (target - eye).length() == 0.0 {
            return Err(at("the eye and the target are the same point"));
        }
        all.push((name.to_string(), eye, target));
    }
    let named: Vec<_> = all.iter().filter(|(m, ..)| Some(m.as_str()) == map).map(|(_, e, t)| (*e, *t)).collect();
    Ok(if named.is_empty() { all.into_iter().map(|(_, e, t)| (e, t)).collect() } else { named })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_gets_its_own_points_and_bad_lines_are_named() {
        let text = "a 1,2,3 1,2,4\nb 0,0,0 1,0,0\n\na 5,5,5 6,5,5\n";
        assert_eq!(parse("f", text, Some("a")).unwrap().len(), 2);
        assert_eq!(parse("f", text, Some("c")).unwrap().len(), 3);
        assert_eq!(map_name("dir/nexuiz_ons-reborn.glb").as_deref(), Some("ons-reborn"));
        let e = parse("f", "a 1,2,3\n", None).unwrap_err().to_string();
        assert!(e.contains("f:1: expected"), "{e}");
        let e = parse("f", "a 1,2,3 1,2,3\n", None).unwrap_err().to_string();
        assert!(e.contains("f:1: the eye and the target"), "{e}");
    }
}
