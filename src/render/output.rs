//! Writing rendered images to disk.

use crate::error::{Error, Result};
use std::path::Path;

/// An 8-bit RGBA image, rows top to bottom, sRGB-encoded.
pub type RgbaImage = image::RgbaImage;

/// Builds an image from tightly packed RGBA8 bytes.
pub fn rgba_from_bytes(width: u32, height: u32, bytes: Vec<u8>) -> Result<RgbaImage> {
    RgbaImage::from_raw(width, height, bytes)
        .ok_or_else(|| Error::Invalid(format!("readback of {width}x{height} pixels has the wrong size")))
}

/// Saves `image` as PNG, creating parent directories. The file is encoded in memory and written
/// in one go, so that a failed write (a full disk, `/dev/full`) is an error, not a short file.
pub fn save_png(image: &RgbaImage, path: &Path) -> Result<()> {
    let io = |source| Error::Io { path: path.display().to_string(), source };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let mut png = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut png, image::ImageFormat::Png)
        .map_err(|e| Error::Invalid(format!("{}: cannot encode the PNG: {e}", path.display())))?;
    std::fs::write(path, png.into_inner()).map_err(io)
}
