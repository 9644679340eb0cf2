//! Reading a glTF/GLB file and its buffers (GLB `BIN` chunk, external `.bin` files, `data:` URIs).
//! Images are read by `images.rs`, which turns any failure into a placeholder: a missing texture
//! must not stop a scene from loading.

use gltf::buffer::Source;
use gltf::{Document, Gltf};
use std::path::Path;

/// Parses the document (JSON and validation) from the file's bytes.
///
/// Validation is the `gltf` crate's (which guarantees that its own accessors cannot panic),
/// with one deliberate leniency: a POSITION accessor without `min`/`max` is accepted with a note,
/// because cullgraph computes bounds from the data; the data itself is then checked, and reports
/// the real problem (non-finite positions, truncated buffers) instead.
pub(super) fn parse(bytes: &[u8], notes: &mut Vec<String>) -> Result<Gltf, String> {
    use gltf::json::validation::{Error, Validate};
    let gltf = Gltf::from_slice_without_validation(bytes).map_err(describe_error)?;
    let root = gltf.document.as_json();
    let unsupported: Vec<&str> = root
        .extensions_required
        .iter()
        .map(String::as_str)
        .filter(|e| !gltf::json::extensions::ENABLED_EXTENSIONS.contains(e))
        .collect();
    if !unsupported.is_empty() {
        let hint = if unsupported.iter().any(|e| e.contains("draco")) {
            " (`assimp export in.glb out.glb -fglb2` decodes Draco)"
        } else if unsupported.iter().any(|e| e.contains("quantization") || e.contains("meshopt")) {
            " (`gltfpack -i in.glb -o out.glb -noq` writes unquantized meshes)"
        } else {
            ""
        };
        return Err(format!(
            "the file requires the unsupported extension(s) {}; convert it to core glTF 2.0 first{hint}",
            unsupported.join(", ")
        ));
    }
    // gltf-json's validator itself indexes `accessors` with the POSITION index before checking
    // it (gltf-json 1.4.1, mesh.rs), so that one index is checked first.
    let positions = gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive.attributes.get(&positions) {
                if index.value() >= root.accessors.len() {
                    return Err(format!(
                        "invalid glTF: meshes[{m}].primitives[{p}].attributes[\"POSITION\"]: accessor {} does not exist \
                         (the file has {})",
                        index.value(),
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    let mut errors = Vec::new();
    let mut missing_bounds = 0usize;
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        let bound = path.ends_with("[\"POSITION\"].min") || path.ends_with("[\"POSITION\"].max");
        if bound && error == Error::Missing {
            missing_bounds += 1;
        } else {
            errors.push(format!("{path}: {error}"));
        }
    });
    if !errors.is_empty() {
        let more = if errors.len() > 8 { format!(" (and {} more)", errors.len() - 8) } else { String::new() };
        errors.truncate(8);
        return Err(format!("invalid glTF: {}{more}", errors.join("; ")));
    }
    if missing_bounds > 0 {
        notes.push(format!(
            "{} POSITION accessor min/max values are missing (the spec requires them); bounds are computed from the data",
            missing_bounds
        ));
    }
    Ok(gltf)
}

/// Loads every buffer of `document`; `base` is the directory that relative URIs start from.
pub(super) fn load_buffers(
    document: &Document,
    base: &Path,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>, String> {
    // The declared lengths first: a buffer in a file of its own (or endless, or sparse and
    // huge) is capped like one embedded in the scene file, before anything is read.
    let mut declared = 0u64;
    for buffer in document.buffers() {
        declared = declared.saturating_add(buffer.length() as u64);
        if declared > crate::files::BUFFERS_LIMIT {
            return Err(format!(
                "buffer {}: its byteLength {} takes the scene's buffers to {declared} bytes; a scene's buffers may hold at most {} together",
                buffer.index(),
                buffer.length(),
                crate::files::BUFFERS_LIMIT
            ));
        }
    }
    let mut out = Vec::with_capacity(document.buffers().len());
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            Source::Bin => blob
                .take()
                .ok_or_else(|| format!("buffer {i} refers to the GLB binary chunk, which the file does not have"))?,
            Source::Uri(uri) if uri.starts_with("data:") => {
                decode_data_uri(uri).map_err(|e| format!("buffer {i} ({}): {e}", shorten(uri)))?
            }
            Source::Uri(uri) if uri.starts_with("file:") => {
                let rest = uri.strip_prefix("file://").unwrap_or(&uri["file:".len()..]);
                let relative = percent_decode(rest).ok_or_else(|| format!("buffer {i}: malformed URI '{uri}'"))?;
                let path = base.join(&relative);
                read_buffer_file(&path, buffer.length())
                    .map_err(|e| format!("buffer {i}: cannot read '{uri}' ({}): {e}", path.display()))?
            }
            Source::Uri(uri) if uri.contains(':') => {
                return Err(format!("buffer {i}: unsupported URI scheme in '{}'", shorten(uri)))
            }
            Source::Uri(uri) => {
                let relative = percent_decode(uri).ok_or_else(|| format!("buffer {i}: malformed URI '{uri}'"))?;
                let path = base.join(&relative);
                read_buffer_file(&path, buffer.length())
                    .map_err(|e| format!("buffer {i}: cannot read '{uri}' ({}): {e}", path.display()))?
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} has {} bytes, the file declares byteLength {}",
                data.len(),
                buffer.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes of a buffer's file, up to the `byteLength` the document declares (capped by
/// [`crate::files::BUFFERS_LIMIT`] already): a file that is larger (or sparse, or endless)
/// never costs more memory than the buffer; a special file is refused.
fn read_buffer_file(path: &Path, length: usize) -> Result<Vec<u8>, String> {
    crate::files::read_prefix(path, length as u64, "buffer file")
}

/// A readable description of a `gltf` error (JSON, GLB container or schema validation).
pub(super) fn describe_error(error: gltf::Error) -> String {
    match error {
        gltf::Error::Validation(errors) => {
            let shown: Vec<String> = errors.iter().take(8).map(|(path, e)| format!("{path}: {e}")).collect();
            let more = if errors.len() > 8 { format!(" (and {} more)", errors.len() - 8) } else { String::new() };
            format!("invalid glTF: {}{more}", shown.join("; "))
        }
        gltf::Error::Deserialize(e) => format!("not a valid glTF 2.0 document: {e}"),
        gltf::Error::Binary(e) => format!("not a valid GLB container: {e}"),
        gltf::Error::Io(e) => format!("I/O error: {e}"),
    }
}

/// The bytes of a `data:[<media type>];base64,<data>` URI (glTF embeds buffers so).
pub(super) fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    use base64::Engine;
    let (header, data) = uri.split_once(',').ok_or("a data URI needs a ',' before its data")?;
    if !header.ends_with(";base64") {
        return Err("only base64 data URIs are supported".into());
    }
    base64::engine::general_purpose::STANDARD.decode(data).map_err(|e| format!("invalid base64: {e}"))
}

/// Decodes `%XX` escapes of a relative URI; `None` when an escape is malformed or the result is
/// not UTF-8.
pub(super) fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// A URI cut to a printable length (data URIs can be megabytes long).
pub(super) fn shorten(uri: &str) -> String {
    match uri.char_indices().nth(48) {
        Some((at, _)) => format!("{}...", &uri[..at]),
        None => uri.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("plain.bin").as_deref(), Some("plain.bin"));
        assert_eq!(percent_decode("bad%2"), None);
        assert_eq!(percent_decode("bad%zz"), None);
        assert_eq!(percent_decode("%FF"), None);
    }
}

#[cfg(test)]
mod uri_tests {
    use super::*;

    fn document(uri: &str, length: usize) -> Document {
        let json =
            format!(r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"byteLength": {length}, "uri": "{uri}"}}]}}"#);
        Gltf::from_slice(json.as_bytes()).unwrap().document
    }

    #[test]
    fn data_uris_decode_base64() {
        let doc = document("data:application/octet-stream;base64,AQID", 3);
        assert_eq!(load_buffers(&doc, Path::new("."), None).unwrap(), vec![vec![1u8, 2, 3]]);
        let err = load_buffers(&document("data:application/octet-stream;base64,A*ID", 3), Path::new("."), None);
        assert!(err.unwrap_err().contains("invalid base64"));
        assert!(decode_data_uri("data:text/plain,abc").unwrap_err().contains("base64"));
        assert!(decode_data_uri("data:;base64").unwrap_err().contains("','"));
    }

    #[test]
    fn file_uris_read_relative_to_the_document() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a b.bin"), [7u8, 8]).unwrap();
        for uri in ["file:a%20b.bin", "file://a%20b.bin"] {
            assert_eq!(load_buffers(&document(uri, 2), dir.path(), None).unwrap(), vec![vec![7u8, 8]], "{uri}");
        }
        let short = load_buffers(&document("file:a%20b.bin", 3), dir.path(), None).unwrap_err();
        assert!(short.contains("byteLength 3"), "{short}");
        // A buffer is read up to its byteLength, and a special file not at all.
        std::fs::write(dir.path().join("long.bin"), [1u8; 64]).unwrap();
        assert_eq!(load_buffers(&document("long.bin", 4), dir.path(), None).unwrap(), vec![vec![1u8; 4]]);
        for uri in ["file:///dev/zero", "/dev/zero", "/proc/self/pagemap", "."] {
            let err = load_buffers(&document(uri, 4), dir.path(), None).unwrap_err();
            assert!(err.contains("not a regular file") && err.contains("buffer 0"), "{uri}: {err}");
        }
        // A declared length past the limit is refused before anything is read.
        let err = load_buffers(&document("/proc/self/pagemap", 100 << 30), dir.path(), None).unwrap_err();
        assert!(
            err.starts_with("buffer 0: its byteLength 107374182400") && err.contains("at most 2147483648"),
            "{err}"
        );
    }
}
