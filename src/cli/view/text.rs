//! Text panels drawn over the presented image: the help, messages and errors. Rasterized on the
//! CPU with font8x8 (ASCII) and copied onto the swapchain image, so that they never touch the
//! renderer's frame or its graph.

use ash::vk;

/// Pixels of one glyph cell per axis, before scaling.
const CELL: u32 = 8;
/// Margin around the text, in cells' pixels before scaling.
const PAD: u32 = 4;

/// Colours of text.
pub const WHITE: [u8; 3] = [235, 235, 235];
/// Errors.
pub const RED: [u8; 3] = [255, 110, 100];
/// Headings and keys.
pub const YELLOW: [u8; 3] = [255, 215, 90];

/// An opaque box of text lines at a place in the window.
pub struct TextPanel {
    /// Left edge in window pixels.
    pub x: u32,
    /// Top edge in window pixels.
    pub y: u32,
    width: u32,
    height: u32,
    rgba: Vec<u8>,
}

impl TextPanel {
    /// `lines` (text and colour) in a dark box at (`x`, `y`), each glyph `scale` times its
    /// 8x8 bitmap. Characters outside ASCII show as '?'.
    pub fn new(lines: &[(String, [u8; 3])], x: u32, y: u32, scale: u32) -> Self {
        let scale = scale.clamp(1, 8);
        if lines.is_empty() {
            return Self { x, y, width: 0, height: 0, rgba: Vec::new() };
        }
        let columns = lines.iter().map(|(t, _)| t.chars().count() as u32).max().unwrap_or(0);
        let width = (columns * CELL + 2 * PAD) * scale;
        let height = (lines.len() as u32 * (CELL + 2) + 2 * PAD) * scale;
        let mut rgba = [18u8, 20, 26, 255].repeat((width * height) as usize);
        for (row, (text, colour)) in lines.iter().enumerate() {
            for (column, c) in text.chars().enumerate() {
                let glyph = glyph(c);
                for (gy, bits) in glyph.iter().enumerate() {
                    for gx in 0..CELL {
                        if bits >> gx & 1 == 0 {
                            continue;
                        }
                        let px = (PAD + column as u32 * CELL + gx) * scale;
                        let py = (PAD + row as u32 * (CELL + 2) + gy as u32) * scale;
                        for sy in 0..scale {
                            for sx in 0..scale {
                                let at = (((py + sy) * width + px + sx) * 4) as usize;
                                rgba[at..at + 3].copy_from_slice(colour);
                            }
                        }
                    }
                }
            }
        }
        Self { x, y, width, height, rgba }
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The panel's pixels as RGBA8 (or BGRA8 when `bgra`), rows top to bottom; `None` when it is
    /// empty.
    pub fn rgba_bytes(&self, bgra: bool) -> Option<Vec<u8>> {
        if self.width == 0 || self.height == 0 {
            return None;
        }
        let mut bytes = self.rgba.clone();
        if bgra {
            bytes.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        Some(bytes)
    }

    /// The copy of the panel's pixels (at `offset` in a buffer) onto an image of
    /// `image_width` x `image_height`, clipped to it; `None` when nothing of it is inside.
    pub fn copy_region(&self, offset: u64, image_width: u32, image_height: u32) -> Option<vk::BufferImageCopy> {
        let w = self.width.min(image_width.checked_sub(self.x)?);
        let h = self.height.min(image_height.checked_sub(self.y)?);
        if w == 0 || h == 0 {
            return None;
        }
        Some(
            vk::BufferImageCopy::default()
                .buffer_offset(offset)
                .buffer_row_length(self.width)
                .buffer_image_height(self.height)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_offset(vk::Offset3D { x: self.x as i32, y: self.y as i32, z: 0 })
                .image_extent(vk::Extent3D { width: w, height: h, depth: 1 }),
        )
    }
}

/// font8x8's bitmap of `c`: 8 rows, bit `x` of a row is column `x`.
fn glyph(c: char) -> [u8; 8] {
    let code = if c.is_ascii() { c as usize } else { '?' as usize };
    font8x8::legacy::BASIC_LEGACY[code]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panel_holds_its_lines_and_clips_to_the_image() {
        let panel = TextPanel::new(&[("AB".into(), WHITE), ("C".into(), RED)], 10, 20, 2);
        let (w, h) = panel.size();
        assert_eq!((w, h), ((2 * 8 + 8) * 2, (2 * 10 + 8) * 2));
        let bytes = panel.rgba_bytes(false).unwrap();
        // Some pixels of 'A' are white, and the background is opaque.
        assert!(bytes.chunks_exact(4).any(|p| p[..3] == WHITE));
        assert!(bytes.chunks_exact(4).any(|p| p[..3] == RED));
        assert!(bytes.chunks_exact(4).all(|p| p[3] == 255));
        let swapped = panel.rgba_bytes(true).unwrap();
        assert!(swapped.chunks_exact(4).any(|p| p[..3] == [WHITE[2], WHITE[1], WHITE[0]]));
        let inside = panel.copy_region(0, 1000, 1000).unwrap();
        assert_eq!((inside.image_extent.width, inside.image_extent.height), (w, h));
        let clipped = panel.copy_region(0, 30, 40).unwrap();
        assert_eq!((clipped.image_extent.width, clipped.image_extent.height), (20, 20));
        assert!(panel.copy_region(0, 10, 1000).is_none());
        assert!(TextPanel::new(&[], 0, 0, 1).rgba_bytes(false).is_none());
    }
}
