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

/// Saves `image` as PNG, creating parent directories.
pub fn save_png(image: &RgbaImage, path: &Path) -> Result<()> {
    let io = |source| Error::Io { path: path.display().to_string(), source };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    image.save_with_format(path, image::ImageFormat::Png).map_err(|e| match e {
        image::ImageError::IoError(source) => io(source),
        other => Error::Invalid(format!("{}: {other}", path.display())),
    })
}
