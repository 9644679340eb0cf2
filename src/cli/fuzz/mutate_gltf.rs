//! Structure-aware mutations of glTF documents (the JSON of a GLB; its binary chunk is kept).
//!
//! Like the graph mutations, the edits work on the generic tree (`serde_json::Value`) and draw
//! replacements from what the seeds hold at the same key (an accessor from another file, a
//! `bufferView` index, a `mimeType`), but they also know what glTF's fields mean: an index is
//! set just past its array's end or to another element, a count or byte offset beyond the
//! binary chunk, an accessor's type or component type swapped, a sparse block added, a `uri`
//! pointed at a data URI, a missing file or a device, a child made its own ancestor, a material
//! given textures, an extension required that nobody supports.

use rand::rngs::SmallRng;
use rand::Rng;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// glTF's top-level arrays that other fields index, by the field names that index them.
const INDEXED: &[(&str, &str)] = &[
    ("mesh", "meshes"),
    ("material", "materials"),
    ("indices", "accessors"),
    ("bufferView", "bufferViews"),
    ("buffer", "buffers"),
    ("source", "images"),
    ("sampler", "samplers"),
    ("camera", "cameras"),
    ("skin", "skins"),
    ("scene", "scenes"),
    ("index", "textures"),
    ("light", "lights"),
    ("POSITION", "accessors"),
    ("NORMAL", "accessors"),
    ("TANGENT", "accessors"),
    ("TEXCOORD_0", "accessors"),
    ("TEXCOORD_1", "accessors"),
    ("COLOR_0", "accessors"),
    ("JOINTS_0", "accessors"),
    ("WEIGHTS_0", "accessors"),
    ("inverseBindMatrices", "accessors"),
    ("input", "accessors"),
    ("output", "accessors"),
];

/// Edge values of counts, lengths, offsets and strides.
const SIZES: &[i64] = &[0, 1, 2, 3, 4, 5, 12, 252, 256, 65_535, 65_536, 2_147_483_647, 4_294_967_295, -1];

/// Values a string field may take instead of its own.
const ODD_STRINGS: &[&str] = &[
    "",
    "SCALAR",
    "VEC2",
    "VEC3",
    "VEC4",
    "MAT2",
    "MAT3",
    "MAT4",
    "VEC5",
    "image/png",
    "image/jpeg",
    "image/ktx2",
    "image/webp",
    "text/plain",
    "OPAQUE",
    "MASK",
    "BLEND",
    "point",
    "spot",
    "directional",
    "perspective",
    "orthographic",
    "missing.bin",
    "missing.png",
    "/dev/zero",
    "/dev/urandom",
    "../../../../etc/passwd",
    ".",
    "data:application/octet-stream;base64,AAAAAAAAAAAAAAAA",
    "data:application/octet-stream;base64,!!!!",
    "data:image/png;base64,iVBORw0KGgo=",
    "data:,",
    "KHR_draco_mesh_compression",
    "KHR_texture_transform",
    "\u{0}",
];

/// Every pointer of `value` with the key it sits under (`""` for array elements' own key,
/// which is their parent's).
fn pointers(value: &Value, at: &str, key: &str, out: &mut Vec<(String, String)>) {
    out.push((at.to_string(), key.to_string()));
    match value {
        Value::Object(map) => {
            for (k, v) in map {
                pointers(v, &format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")), k, out);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                pointers(v, &format!("{at}/{i}"), key, out);
            }
        }
        _ => {}
    }
}

/// What the seed documents hold under each key.
#[derive(Default)]
pub struct Pools {
    by_key: BTreeMap<String, Vec<Value>>,
}

impl Pools {
    /// Pools the values of every key of `docs`.
    pub fn of<'a>(docs: impl IntoIterator<Item = &'a Value>) -> Pools {
        let mut pools = Pools::default();
        for doc in docs {
            let mut all = Vec::new();
            pointers(doc, "", "", &mut all);
            for (pointer, key) in all {
                if let Some(v) = doc.pointer(&pointer) {
                    let pool = pools.by_key.entry(key).or_default();
                    // The big arrays of the game levels would crowd everything else out.
                    if pool.len() < 4096 {
                        pool.push(v.clone());
                    }
                }
            }
        }
        pools
    }

    fn donor(&self, rng: &mut SmallRng, key: &str) -> Option<Value> {
        let pool = self.by_key.get(key)?;
        (!pool.is_empty()).then(|| pool[rng.random_range(0..pool.len())].clone())
    }
}

/// One to four edits of `doc`.
pub fn document(rng: &mut SmallRng, doc: &mut Value, pools: &Pools) {
    let edits = 1 + (0..3).take_while(|_| rng.random_bool(0.5)).count();
    for _ in 0..edits {
        let mut all = Vec::new();
        pointers(doc, "", "", &mut all);
        let (pointer, key) = all.swap_remove(rng.random_range(0..all.len()));
        match rng.random_range(0..10) {
            0 => add(rng, doc),
            _ => edit_at(rng, doc, &pointer, &key, pools),
        }
    }
}

/// Sets, removes or duplicates what is at `pointer` (under `key`), knowing what the key means.
fn edit_at(rng: &mut SmallRng, doc: &mut Value, pointer: &str, key: &str, pools: &Pools) {
    let length_of = |doc: &Value, array: &str| doc.get(array).and_then(Value::as_array).map_or(0, Vec::len) as i64;
    let target = INDEXED.iter().find(|(k, _)| *k == key).map(|(_, array)| length_of(doc, array));
    let bin_len = length_of(doc, "buffers").max(1) * 65_536;
    let Some(value) = doc.pointer_mut(pointer) else { return };
    let choice = rng.random_range(0..10);
    *value = match (choice, &*value) {
        // An index: past the end, the last, another, negative.
        (0..=5, Value::Number(_)) if target.is_some() => {
            let n = target.unwrap_or(0);
            json!(([n, n - 1, n + 1, rng.random_range(0..n.max(1)), -1, 4_294_967_295i64][rng.random_range(0..6)]))
        }
        (0..=4, Value::Number(_))
            if matches!(
                key,
                "count" | "byteLength" | "byteOffset" | "byteStride" | "componentType" | "mode" | "texCoord"
            ) =>
        {
            match key {
                "componentType" => json!(([5120, 5121, 5122, 5123, 5125, 5126, 5124, 0][rng.random_range(0..8)])),
                "mode" => json!(rng.random_range(0..8)),
                "texCoord" => json!(rng.random_range(0..3)),
                "byteOffset" | "byteLength" if rng.random_bool(0.5) => json!(bin_len + rng.random_range(-8..8)),
                _ => json!(SIZES[rng.random_range(0..SIZES.len())]),
            }
        }
        (0..=4, Value::Number(n)) => {
            let x = n.as_f64().unwrap_or(0.0);
            json!(([0.0, -x, x * 1e30, x + 1.0, 1e-30, f64::MAX, -f64::MAX, 0.5][rng.random_range(0..8)]))
        }
        (0..=3, Value::String(_)) => match pools.donor(rng, key) {
            Some(Value::String(s)) if rng.random_bool(0.5) => Value::String(s),
            _ => json!(ODD_STRINGS[rng.random_range(0..ODD_STRINGS.len())]),
        },
        (0..=3, Value::Array(items)) if !items.is_empty() => {
            let mut items = items.clone();
            let i = rng.random_range(0..items.len());
            match rng.random_range(0..5) {
                0 => {
                    items.remove(i);
                }
                1 => {
                    let copy = items[i].clone();
                    items.insert(rng.random_range(0..=items.len()), copy);
                }
                2 => {
                    let j = rng.random_range(0..items.len());
                    items.swap(i, j);
                }
                3 => items.truncate(i),
                _ => {
                    if let Some(donor) =
                        pools.donor(rng, key).and_then(|d| d.as_array().and_then(|a| a.first().cloned()))
                    {
                        items.push(donor);
                    }
                }
            }
            Value::Array(items)
        }
        (0..=3, Value::Object(map)) => {
            let mut map = map.clone();
            let keys: Vec<String> = map.keys().cloned().collect();
            match rng.random_range(0..3) {
                0 if !keys.is_empty() => {
                    map.remove(&keys[rng.random_range(0..keys.len())]);
                }
                _ => {
                    // A field that objects under this key have in some seed.
                    let sibling = pools.donor(rng, key).and_then(|d| match d {
                        Value::Object(m) => m.into_iter().nth(rng.random_range(0..8)),
                        Value::Array(a) => a.into_iter().find_map(|v| match v {
                            Value::Object(m) => m.into_iter().next(),
                            _ => None,
                        }),
                        _ => None,
                    });
                    if let Some((k, v)) = sibling {
                        map.insert(k, v);
                    }
                }
            }
            Value::Object(map)
        }
        (8, _) => edge_value(rng),
        (9, _) => Value::Null, // removed below
        _ => match pools.donor(rng, key) {
            Some(donor) => donor,
            None => edge_value(rng),
        },
    };
    if value.is_null() && rng.random_bool(0.8) {
        remove(doc, pointer);
    }
}

/// Removes what is at `pointer` from its object or array.
fn remove(doc: &mut Value, pointer: &str) {
    let Some((parent, key)) = pointer.rsplit_once('/') else { return };
    match doc.pointer_mut(parent) {
        Some(Value::Object(map)) => {
            map.remove(&key.replace("~1", "/").replace("~0", "~"));
        }
        Some(Value::Array(items)) => {
            if let Ok(i) = key.parse::<usize>() {
                if i < items.len() {
                    items.remove(i);
                }
            }
        }
        _ => {}
    }
}

/// The value at `path` (object keys, or array indices as numbers) below `root`, objects made
/// where keys are missing; None where the path meets a value of another kind (the document
/// may be mutated already) or an index out of range.
fn slot<'a>(root: &'a mut Value, path: &[&str]) -> Option<&'a mut Value> {
    let Some((first, rest)) = path.split_first() else { return Some(root) };
    let child = match root {
        Value::Object(map) => map.entry(first.to_string()).or_insert_with(|| json!({})),
        Value::Array(items) => items.get_mut(first.parse::<usize>().ok()?)?,
        _ => return None,
    };
    slot(child, rest)
}

/// Sets the value at `path` (see [`slot`]).
fn set(root: &mut Value, path: &[&str], value: Value) {
    if let Some(place) = slot(root, path) {
        *place = value;
    }
}

/// Appends to the array at `path`, made if missing.
fn push(root: &mut Value, path: &[&str], value: Value) {
    if let Some(place) = slot(root, path) {
        if !place.is_array() {
            *place = json!([]);
        }
        if let Value::Array(items) = place {
            items.push(value);
        }
    }
}

/// Adds something the seeds may not have: a sparse block, a texture chain, a child cycle, a
/// required extension, an attribute, an image in a buffer view, a camera or light at an edge.
fn add(rng: &mut SmallRng, doc: &mut Value) {
    let len = |doc: &Value, k: &str| doc.get(k).and_then(Value::as_array).map_or(0, Vec::len);
    let any = |rng: &mut SmallRng, n: usize| rng.random_range(0..n + 1) as i64;
    let one_of = |rng: &mut SmallRng, n: usize| rng.random_range(0..n.max(1)).to_string();
    let (accessors, views, nodes, meshes) =
        (len(doc, "accessors"), len(doc, "bufferViews"), len(doc, "nodes"), len(doc, "meshes"));
    match rng.random_range(0..9) {
        0 => {
            let sparse = json!({
                "count": SIZES[rng.random_range(0..SIZES.len())],
                "indices": {"bufferView": any(rng, views), "componentType": ([5121, 5123, 5125, 5126][rng.random_range(0..4)]), "byteOffset": rng.random_range(0..16)},
                "values": {"bufferView": any(rng, views), "byteOffset": rng.random_range(0..16)},
            });
            set(doc, &["accessors", &one_of(rng, accessors), "sparse"], sparse);
        }
        1 => {
            let image = if rng.random_bool(0.5) {
                json!({"bufferView": any(rng, views), "mimeType": ODD_STRINGS[rng.random_range(9..14)]})
            } else {
                json!({"uri": ODD_STRINGS[rng.random_range(0..ODD_STRINGS.len())]})
            };
            push(doc, &["images"], image);
            let images = len(doc, "images");
            push(doc, &["textures"], json!({"source": any(rng, images), "sampler": any(rng, 1)}));
            push(
                doc,
                &["samplers"],
                json!({"magFilter": 9728, "wrapS": ([33071, 33648, 10497, 7][rng.random_range(0..4)])}),
            );
            let textures = len(doc, "textures") as i64;
            let slot = ["baseColorTexture", "metallicRoughnessTexture"][rng.random_range(0..2)];
            let info = json!({"index": textures - rng.random_range(0..2), "texCoord": rng.random_range(0..2),
                "extensions": {"KHR_texture_transform": {"scale": [1e30, 0.0], "rotation": 1.0}}});
            let material = match rng.random_range(0..3) {
                0 => json!({"normalTexture": info, "alphaMode": "MASK", "alphaCutoff": -1.0}),
                1 => json!({"emissiveTexture": info, "occlusionTexture": info, "alphaMode": "BLEND"}),
                _ => json!({"pbrMetallicRoughness": {slot: info}}),
            };
            push(doc, &["materials"], material);
            let m = len(doc, "materials") as i64 - 1;
            set(doc, &["meshes", &one_of(rng, meshes), "primitives", "0", "material"], json!(m));
        }
        2 => {
            // A node that is its own descendant, or the child of two parents.
            let child = json!(rng.random_range(0..nodes.max(1)));
            push(doc, &["nodes", &one_of(rng, nodes), "children"], child);
        }
        3 => {
            let name = ["KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_mesh_quantization", "X_unknown"]
                [rng.random_range(0..4)];
            push(doc, &["extensionsRequired"], json!(name));
            push(doc, &["extensionsUsed"], json!(name));
        }
        4 => {
            let attribute =
                ["TEXCOORD_0", "TANGENT", "NORMAL", "COLOR_0", "JOINTS_0", "TEXCOORD_1"][rng.random_range(0..6)];
            let index = json!(any(rng, accessors));
            set(doc, &["meshes", &one_of(rng, meshes), "primitives", "0", "attributes", attribute], index);
        }
        5 => {
            let camera = match rng.random_range(0..2) {
                0 => {
                    json!({"type": "orthographic", "orthographic": {"xmag": 0.0, "ymag": -1.0, "znear": 0.0, "zfar": 0.0}})
                }
                _ => {
                    json!({"type": "perspective", "perspective": {"yfov": ([0.0, 3.2, -1.0, 1e30][rng.random_range(0..4)]), "znear": ([0.0, 1e-30, -1.0][rng.random_range(0..3)]), "zfar": 0.001}})
                }
            };
            push(doc, &["cameras"], camera);
            let c = len(doc, "cameras") as i64 - 1;
            set(doc, &["nodes", &one_of(rng, nodes), "camera"], json!(c));
        }
        6 => {
            let n = one_of(rng, nodes);
            set(doc, &["nodes", &n, "matrix"], json!([1e30, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]));
            set(doc, &["nodes", &n, "scale"], json!([0.0, -1.0, 1e-30]));
        }
        7 => {
            let a = one_of(rng, accessors);
            set(doc, &["accessors", &a, "type"], json!(ODD_STRINGS[rng.random_range(1..9)]));
            set(doc, &["accessors", &a, "normalized"], json!(rng.random_bool(0.5)));
        }
        _ => {
            let light = json!({
                "type": (["spot", "directional", "point", "area"][rng.random_range(0..4)]),
                "intensity": ([0.0, -1.0, 1e30][rng.random_range(0..3)]), "range": ([0.0, -1.0, 1e-30][rng.random_range(0..3)]),
                "spot": {"innerConeAngle": 1.0, "outerConeAngle": 0.5}});
            push(doc, &["extensions", "KHR_lights_punctual", "lights"], light);
            let which = json!({"KHR_lights_punctual": {"light": rng.random_range(0..2)}});
            set(doc, &["nodes", &one_of(rng, nodes), "extensions"], which);
        }
    }
}

/// A value of another kind or at an edge.
fn edge_value(rng: &mut SmallRng) -> Value {
    match rng.random_range(0..12) {
        0 => json!(0),
        1 => json!(-1),
        2 => json!(4_294_967_295u64),
        3 => json!(1e30),
        4 => json!(0.5),
        5 => Value::Null,
        6 => json!([]),
        7 => json!({}),
        8 => json!("x"),
        9 => json!([1e30, 1e30, 1e30]),
        10 => json!(true),
        _ => json!([0.0, 0.0, 0.0, 0.0]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn edits_change_the_document_and_keep_it_json() {
        let (seed, _) = super::super::targets::gltf_seed();
        let pools = Pools::of([&seed]);
        let mut rng = SmallRng::seed_from_u64(3);
        let mut changed = 0;
        for _ in 0..300 {
            let mut doc = seed.clone();
            document(&mut rng, &mut doc, &pools);
            changed += usize::from(doc != seed);
            assert!(serde_json::to_vec(&doc).is_ok());
        }
        assert!(changed > 250, "{changed} of 300 changed");
    }
}
