//! The node hierarchy: choosing the roots, composing local transforms into world transforms, and
//! refusing cycles, shared children, excessive depth and non-finite transforms.

use crate::scene::error::SceneError;
use crate::scene::Transform;
use glam::{DMat3, DQuat, DVec3, Mat3};
use gltf::scene::Transform as NodeTransform;
use gltf::{Document, Node};

/// Deepest hierarchy accepted; real files stay far below, and a deeper one is almost surely broken.
pub(super) const MAX_DEPTH: usize = 1024;

/// A visited node with its world transform.
pub(super) struct Placed<'a> {
    /// The node.
    pub node: Node<'a>,
    /// Local-to-world transform.
    pub world: Transform,
    /// Instance flags from its own and its ancestors' extras ([`super::flags`]).
    pub flags: u32,
}

/// `node 'name' (#i)`, or `node #i` for an unnamed node.
pub(super) fn node_label(node: &Node<'_>) -> String {
    match node.name() {
        Some(name) => format!("node '{name}' (#{})", node.index()),
        None => format!("node #{}", node.index()),
    }
}

/// The root nodes to draw: the default scene's, else scene 0's, else every node without a parent.
pub(super) fn roots<'a>(document: &'a Document, notes: &mut Vec<String>) -> Vec<Node<'a>> {
    let scene_count = document.scenes().len();
    let scene = document.default_scene().or_else(|| document.scenes().next());
    match scene {
        Some(scene) => {
            if scene_count > 1 {
                notes.push(format!("the file has {scene_count} scenes; only scene {} is drawn", scene.index()));
            }
            scene.nodes().collect()
        }
        None => {
            let mut has_parent = vec![false; document.nodes().len()];
            for node in document.nodes() {
                for child in node.children() {
                    has_parent[child.index()] = true;
                }
            }
            let roots: Vec<Node<'a>> = document.nodes().filter(|n| !has_parent[n.index()]).collect();
            if !roots.is_empty() {
                notes.push(format!("the file has no scene; drawing its {} parentless nodes", roots.len()));
            }
            roots
        }
    }
}

/// Visits the hierarchy under `roots` depth first and returns every node with its world
/// transform, in visiting order. `file` prefixes error places.
pub(super) fn walk<'a>(
    document: &'a Document,
    roots: Vec<Node<'a>>,
    file: &str,
    notes: &mut Vec<String>,
) -> Result<Vec<Placed<'a>>, SceneError> {
    let count = document.nodes().len();
    // Parent through which each node was first reached (None for roots), for cycle reports.
    let mut parent = vec![None::<usize>; count];
    let mut visited = vec![false; count];
    let mut out = Vec::new();
    let mut stack: Vec<(Node<'a>, Transform, u32, usize, Option<usize>)> =
        roots.into_iter().rev().map(|n| (n, Transform::default(), 0, 0, None)).collect();
    while let Some((node, parent_world, parent_flags, depth, from)) = stack.pop() {
        let i = node.index();
        let place = || format!("{file}: {}", node_label(&node));
        if visited[i] {
            return Err(SceneError::invalid(place(), revisit_message(document, &parent, i, from)));
        }
        visited[i] = true;
        parent[i] = from;
        if depth >= MAX_DEPTH {
            return Err(SceneError::invalid(place(), format!("the node hierarchy is deeper than {MAX_DEPTH} levels")));
        }
        let local = local_transform(&node, notes).map_err(|m| SceneError::invalid(place(), m))?;
        let world = parent_world.then(&local);
        if !world.is_finite() {
            return Err(SceneError::invalid(
                place(),
                "world transform is not finite (the composed transforms overflow)",
            ));
        }
        if let Some(e) = crate::scene::position_error("world translation", world.translation) {
            return Err(SceneError::invalid(place(), e));
        }
        let flags = parent_flags | super::flags::node_flags(&node).map_err(|m| SceneError::invalid(place(), m))?;
        let children: Vec<Node<'a>> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, flags, depth + 1, Some(i)));
        }
        out.push(Placed { node, world, flags });
    }
    Ok(out)
}

/// Why node `i` was reached a second time: a cycle when it is an ancestor of `from`, otherwise a
/// node with two parents (or listed twice among the roots).
fn revisit_message(document: &Document, parent: &[Option<usize>], i: usize, from: Option<usize>) -> String {
    let mut chain = vec![i];
    let mut at = from;
    while let Some(p) = at {
        chain.push(p);
        if p == i {
            chain.reverse();
            let path: Vec<String> = chain.iter().map(|n| format!("#{n}")).collect();
            return format!("the node hierarchy has a cycle ({}); glTF nodes must form a tree", path.join(" -> "));
        }
        if chain.len() > parent.len() + 1 {
            break;
        }
        at = parent[p];
    }
    let name = |n: Option<usize>| match n.and_then(|n| document.nodes().nth(n)) {
        Some(node) => node_label(&node),
        None => "the scene's root list".to_string(),
    };
    format!(
        "the node is reached twice (from {} and again from {}); glTF nodes must form a tree",
        name(parent[i]),
        name(from)
    )
}

/// A node's local transform, checked for finiteness; notes a projective matrix row.
pub(super) fn local_transform(node: &Node<'_>, notes: &mut Vec<String>) -> Result<Transform, String> {
    match node.transform() {
        NodeTransform::Matrix { matrix: m } => {
            if m.iter().flatten().any(|v| !v.is_finite()) {
                return Err("transform is not finite".into());
            }
            let last_row = [m[0][3], m[1][3], m[2][3], m[3][3]];
            if (last_row[0].abs() + last_row[1].abs() + last_row[2].abs() + (last_row[3] - 1.0).abs()) > 1e-5 {
                notes.push(format!(
                    "{}: matrix has the projective last row {last_row:?}; it is treated as [0, 0, 0, 1]",
                    node_label(node)
                ));
            }
            let col = |c: usize| glam::Vec3::new(m[c][0], m[c][1], m[c][2]);
            Ok(Transform {
                linear: Mat3::from_cols(col(0), col(1), col(2)),
                translation: DVec3::new(m[3][0] as f64, m[3][1] as f64, m[3][2] as f64),
            })
        }
        NodeTransform::Decomposed { translation: t, rotation: r, scale: s } => {
            if t.iter().chain(&r).chain(&s).any(|v| !v.is_finite()) {
                return Err("transform is not finite".into());
            }
            let q = DQuat::from_xyzw(r[0] as f64, r[1] as f64, r[2] as f64, r[3] as f64);
            if q.length() < 1e-6 {
                return Err(format!("rotation quaternion {r:?} has zero length"));
            }
            let linear = DMat3::from_quat(q.normalize())
                * DMat3::from_diagonal(DVec3::new(s[0] as f64, s[1] as f64, s[2] as f64));
            Ok(Transform { linear: linear.as_mat3(), translation: DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64) })
        }
    }
}
