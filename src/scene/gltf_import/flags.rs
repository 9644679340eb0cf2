//! Instance flags from a node's glTF `extras`: `{"cullgraph": {"occluder": true, "no_aa": true}}`
//! marks the node's instances, and those of every node below it, as an occluder candidate
//! ([`FLAG_OCCLUDER`]) or as kept to one sample by selective AA ([`FLAG_NO_AA`]). Other
//! extras are the file's own business and ignored; a `cullgraph` entry that cullgraph cannot
//! read is an error, so that a typo does not silently do nothing.

use crate::scene::{FLAG_NO_AA, FLAG_OCCLUDER};
use gltf::Node;
use serde_json::Value;

/// The extras key cullgraph reads.
pub(super) const EXTRAS_KEY: &str = "cullgraph";

/// The flags `node`'s extras set (0 without a `cullgraph` entry), or what is wrong with them.
pub(super) fn node_flags(node: &Node<'_>) -> Result<u32, String> {
    let Some(raw) = node.extras() else { return Ok(0) };
    // Extras may be any JSON; only an object can hold our key.
    let Ok(Value::Object(extras)) = serde_json::from_str::<Value>(raw.get()) else { return Ok(0) };
    let Some(entry) = extras.get(EXTRAS_KEY) else { return Ok(0) };
    let Value::Object(entry) = entry else {
        return Err(format!("extras.{EXTRAS_KEY} must be an object such as {{\"occluder\": true, \"no_aa\": true}}"));
    };
    let mut flags = 0;
    for (key, value) in entry {
        let flag = match key.as_str() {
            "occluder" => FLAG_OCCLUDER,
            "no_aa" => FLAG_NO_AA,
            _ => return Err(format!("extras.{EXTRAS_KEY}.{key} is unknown (known: occluder, no_aa)")),
        };
        match value {
            Value::Bool(true) => flags |= flag,
            Value::Bool(false) => {}
            _ => return Err(format!("extras.{EXTRAS_KEY}.{key} must be true or false, not {value}")),
        }
    }
    Ok(flags)
}
