//! What glTF `extras` tell cullgraph. A node's `{"cullgraph": {"occluder": true, "no_aa": true}}`
//! marks the node's instances, and those of every node below it, as an occluder candidate
//! ([`FLAG_OCCLUDER`]) or as kept to one sample by selective AA ([`FLAG_NO_AA`]); a mesh's
//! `{"cullgraph": {"lod": false}}` keeps its primitives whole at any distance
//! ([`crate::scene::MeshData::no_lod`]). Other extras are the file's own business and ignored;
//! a `cullgraph` entry that cullgraph cannot read is an error, so that a typo does not silently
//! do nothing.

use crate::scene::{FLAG_NO_AA, FLAG_OCCLUDER};
use gltf::Node;
use serde_json::Value;

/// The extras key cullgraph reads.
pub(super) const EXTRAS_KEY: &str = "cullgraph";

/// The `cullgraph` entry of `extras` as (key, true or false) pairs, each key one of `known`
/// (none without an entry), or what is wrong with it.
fn switches(extras: Option<&serde_json::value::RawValue>, known: &[&str]) -> Result<Vec<(String, bool)>, String> {
    let Some(raw) = extras else { return Ok(Vec::new()) };
    // Extras may be any JSON; only an object can hold our key.
    let Ok(Value::Object(extras)) = serde_json::from_str::<Value>(raw.get()) else { return Ok(Vec::new()) };
    let Some(entry) = extras.get(EXTRAS_KEY) else { return Ok(Vec::new()) };
    let example = known.iter().map(|k| format!("\"{k}\": true")).collect::<Vec<_>>().join(", ");
    let Value::Object(entry) = entry else {
        return Err(format!("extras.{EXTRAS_KEY} must be an object such as {{{example}}}"));
    };
    let mut out = Vec::new();
    for (key, value) in entry {
        if !known.contains(&key.as_str()) {
            return Err(format!("extras.{EXTRAS_KEY}.{key} is unknown (known: {})", known.join(", ")));
        }
        match value {
            Value::Bool(on) => out.push((key.clone(), *on)),
            _ => return Err(format!("extras.{EXTRAS_KEY}.{key} must be true or false, not {value}")),
        }
    }
    Ok(out)
}

/// The flags `node`'s extras set (0 without a `cullgraph` entry), or what is wrong with them.
pub(super) fn node_flags(node: &Node<'_>) -> Result<u32, String> {
    let mut flags = 0;
    for (key, on) in switches(node.extras().as_deref(), &["occluder", "no_aa"])? {
        if on {
            flags |= if key == "occluder" { FLAG_OCCLUDER } else { FLAG_NO_AA };
        }
    }
    Ok(flags)
}

/// Whether `mesh`'s extras keep its primitives whole (`"lod": false`), or what is wrong with them.
pub(super) fn mesh_keeps_detail(mesh: &gltf::Mesh<'_>) -> Result<bool, String> {
    Ok(switches(mesh.extras().as_deref(), &["lod"])?.iter().any(|(_, on)| !on))
}
