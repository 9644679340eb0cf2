//! glTF images to decoded [`Texture`]s: PNG and JPEG (through the `image` crate), embedded in
//! a buffer view, in a `data:` URI or in a file next to the glTF.
//!
//! An image that cannot be used (missing, unreadable, corrupt, of a format we do not decode,
//! larger than [`MAX_IMAGE_SIDE`]) becomes the visible placeholder ([`Texture::placeholder`])
//! with a note naming it: the rest of the scene still loads.

use crate::scene::Texture;
use gltf::image::Source;
use gltf::Document;
use std::path::Path;
use std::sync::Arc;

/// The largest image side we decode: what every Vulkan device we target can sample
/// (`maxImageDimension2D` is at least 16384 there; larger is refused before any allocation).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The most bytes one image file may hold.
const IMAGE_FILE_LIMIT: u64 = 256 << 20;

/// The most memory one decode may allocate: an 8192² RGBA8 image with its decoder's buffers.
/// (Textures are reduced to 2048 texels a side on the GPU anyway.)
const DECODE_ALLOC_LIMIT: u64 = 320 << 20;

/// The most decoded texels, in bytes, one scene keeps: past it, further images are the
/// placeholder, so that a file of many huge images cannot exhaust memory.
const SCENE_TEXEL_BYTES: u64 = 1 << 30;

/// One texture per glTF image, in file order, and whether each is the placeholder.
pub(super) fn load(
    document: &Document,
    base: &Path,
    buffers: &[Vec<u8>],
    notes: &mut Vec<String>,
) -> Vec<(Arc<Texture>, bool)> {
    let mut kept = 0u64;
    document
        .images()
        .map(|image| {
            let name = label(document, &image);
            let decoded = if let Some(why) = source_problem(document, &image) {
                Err(why.to_string())
            } else if kept >= SCENE_TEXEL_BYTES {
                Err(format!("the scene's images already take {} MiB decoded, the most kept", SCENE_TEXEL_BYTES >> 20))
            } else {
                bytes(&image, base, buffers).and_then(|bytes| decode(&bytes, image.source()))
            };
            match decoded {
                Ok((width, height, rgba)) => {
                    kept += rgba.len() as u64;
                    (Arc::new(Texture { name, width, height, rgba }), false)
                }
                Err(why) => {
                    notes.push(format!("{name}: {why}; the placeholder texture is shown instead"));
                    (Arc::new(Texture::placeholder(&name)), true)
                }
            }
        })
        .collect()
}

/// `image 3 'bark.png'` (its name, else its URI, else nothing).
pub(super) fn label(document: &Document, image: &gltf::Image<'_>) -> String {
    // From the JSON: `image.source()` panics on the images `source_problem` finds.
    let uri = document.as_json().images.get(image.index()).and_then(|json| json.uri.as_deref());
    let named = image.name().or(uri.filter(|uri| !uri.starts_with("data:")));
    match named {
        Some(name) => format!("image {} '{name}'", image.index()),
        None => format!("image {}", image.index()),
    }
}

/// Why `image` has no source the `gltf` crate can give, if it has none: `Image::source`
/// unwraps a `uri` where there is no `bufferView`, and a `mimeType` where there is one, and
/// the crate's validation requires neither (gltf 1.4.1, `image.rs`).
fn source_problem(document: &Document, image: &gltf::Image<'_>) -> Option<&'static str> {
    let json = document.as_json().images.get(image.index())?;
    match (&json.buffer_view, &json.uri, &json.mime_type) {
        (None, None, _) => Some("it has neither a bufferView nor a uri"),
        (Some(_), _, None) => Some("it has a bufferView but no mimeType (glTF requires one with a bufferView)"),
        _ => None,
    }
}

/// The encoded bytes of `image`.
fn bytes(image: &gltf::Image<'_>, base: &Path, buffers: &[Vec<u8>]) -> Result<Vec<u8>, String> {
    match image.source() {
        Source::View { view, .. } => {
            let buffer = buffers.get(view.buffer().index()).ok_or("its buffer view's buffer is missing")?;
            let range = view.offset()..view.offset().saturating_add(view.length());
            buffer.get(range.clone()).map(<[u8]>::to_vec).ok_or_else(|| {
                format!(
                    "buffer view {} (bytes {}..{}) lies beyond its buffer's {} bytes",
                    view.index(),
                    range.start,
                    range.end,
                    buffer.len()
                )
            })
        }
        Source::Uri { uri, .. } if uri.starts_with("data:") => super::buffers::decode_data_uri(uri),
        Source::Uri { uri, .. } if uri.contains(':') && !uri.starts_with("file:") => {
            Err(format!("unsupported URI scheme in '{}'", super::buffers::shorten(uri)))
        }
        Source::Uri { uri, .. } => {
            let rest = uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:")).unwrap_or(uri);
            let relative = super::buffers::percent_decode(rest).ok_or_else(|| format!("malformed URI '{uri}'"))?;
            let path = base.join(relative);
            crate::files::read_limited(&path, IMAGE_FILE_LIMIT, "image file")
                .map_err(|e| format!("cannot read '{}': {e}", path.display()))
        }
    }
}

/// Decodes PNG or JPEG bytes to RGBA8, within the size limits.
fn decode(bytes: &[u8], source: Source<'_>) -> Result<(u32, u32, Vec<u8>), String> {
    let format = image::guess_format(bytes).map_err(|_| {
        let declared = match source {
            Source::View { mime_type, .. } => Some(mime_type),
            Source::Uri { mime_type, .. } => mime_type,
        };
        format!("not a PNG or JPEG file{}", declared.map(|m| format!(" (declared {m})")).unwrap_or_default())
    })?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
        return Err(format!("{format:?} images are not supported (PNG and JPEG are)"));
    }
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    limits.max_alloc = Some(DECODE_ALLOC_LIMIT);
    reader.limits(limits);
    let decoded = reader.decode().map_err(|e| format!("cannot be decoded: {e}"))?;
    let rgba = decoded.into_rgba8();
    Ok((rgba.width(), rgba.height(), rgba.into_raw()))
}
