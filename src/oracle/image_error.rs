//! Image error against a supersampled reference: the box-filter downsample in linear light that
//! makes the reference, and the figures reported for a test image (mean FLIP and PSNR).
//!
//! Images are RGBA8, rows top to bottom, sRGB-encoded (what the lighting passes write). FLIP is
//! NVIDIA's perceptual difference (LDR-FLIP, `nv-flip` crate) at its default 67 pixels per
//! degree (a 0.7 m viewing distance from a 24" 4K screen); 0 is identical, 1 is the largest error.

use super::metrics::compare_rgba8;
use crate::{Error, Result};

pub use crate::stats::ImageError;

/// sRGB-encoded 8-bit value to linear light (the exact piecewise curve).
pub fn srgb_to_linear(v: u8) -> f32 {
    let c = v as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear light (clamped to 0..=1) to an sRGB-encoded 8-bit value, rounded to nearest.
pub fn linear_to_srgb(l: f32) -> u8 {
    let l = if l.is_nan() { 0.0 } else { l.clamp(0.0, 1.0) };
    let c = if l <= 0.003_130_8 { l * 12.92 } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
    (c * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Box-filters an RGBA8 image of `(width·n) x (height·n)` pixels down to `width x height`: each
/// output pixel is the average of its `n x n` block in linear light (decode sRGB, average,
/// encode); alpha is averaged as it is (linear).
pub fn downsample_box_srgb(src: &[u8], width: u32, height: u32, n: u32) -> Result<Vec<u8>> {
    if n == 0 || width == 0 || height == 0 {
        return Err(Error::Invalid(format!("cannot downsample to {width}x{height} by {n}")));
    }
    let (sw, sh) = (width as usize * n as usize, height as usize * n as usize);
    if src.len() != sw * sh * 4 {
        return Err(Error::Invalid(format!("a {sw}x{sh} RGBA8 image has {} bytes, not {}", sw * sh * 4, src.len())));
    }
    let lut: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
    let n = n as usize;
    let inv = 1.0 / (n * n) as f32;
    let mut out = vec![0u8; width as usize * height as usize * 4];
    for (y, row) in out.chunks_exact_mut(width as usize * 4).enumerate() {
        for (x, px) in row.chunks_exact_mut(4).enumerate() {
            let mut sum = [0f32; 4];
            for sy in y * n..(y + 1) * n {
                let line = &src[(sy * sw + x * n) * 4..(sy * sw + (x + 1) * n) * 4];
                for s in line.chunks_exact(4) {
                    for c in 0..3 {
                        sum[c] += lut[s[c] as usize];
                    }
                    sum[3] += s[3] as f32;
                }
            }
            for c in 0..3 {
                px[c] = linear_to_srgb(sum[c] * inv);
            }
            px[3] = (sum[3] * inv).round().clamp(0.0, 255.0) as u8;
        }
    }
    Ok(out)
}

/// Mean LDR-FLIP error of `test` against `reference`, both RGBA8 of `width x height` (alpha
/// ignored).
pub fn mean_flip(reference: &[u8], test: &[u8], width: u32, height: u32) -> Result<f64> {
    let expected = width as usize * height as usize * 4;
    if width == 0 || height == 0 || reference.len() != expected || test.len() != expected {
        return Err(Error::Invalid(format!(
            "FLIP needs two {width}x{height} RGBA8 images ({expected} bytes), not {} and {} bytes",
            reference.len(),
            test.len()
        )));
    }
    let rgb = |rgba: &[u8]| -> Vec<u8> { rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(reference));
    let test = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(test));
    let error = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    Ok(nv_flip::FlipPool::from_image(&error).mean() as f64)
}

/// Mean FLIP and PSNR of `test` against `reference` (`width x height` RGBA8 each), labelled with
/// the reference's samples per pixel.
pub fn image_error(
    reference: &[u8],
    test: &[u8],
    width: u32,
    height: u32,
    samples_per_pixel: u32,
) -> Result<ImageError> {
    let mean_flip = mean_flip(reference, test, width, height)?;
    let psnr_db = compare_rgba8(reference, test)?.psnr_db;
    Ok(ImageError { samples_per_pixel, mean_flip, psnr_db })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solid(w: u32, h: u32, rgb: [u8; 3]) -> Vec<u8> {
        (0..w * h).flat_map(|_| [rgb[0], rgb[1], rgb[2], 255]).collect()
    }

    #[test]
    fn srgb_round_trips_every_value() {
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(v)), v);
        }
        assert_eq!(linear_to_srgb(-1.0), 0);
        assert_eq!(linear_to_srgb(2.0), 255);
        assert_eq!(linear_to_srgb(f32::NAN), 0);
    }

    #[test]
    fn checkerboard_downsamples_to_linear_grey() {
        // Black and white alternating pixels: half the light, sRGB 188, not the naive 128.
        let (w, h, n) = (3u32, 2u32, 4u32);
        let src: Vec<u8> = (0..h * n)
            .flat_map(|y| (0..w * n).map(move |x| (x + y) % 2))
            .flat_map(|on| {
                let v = if on == 1 { 255 } else { 0 };
                [v, v, v, 255]
            })
            .collect();
        let out = downsample_box_srgb(&src, w, h, n).unwrap();
        assert_eq!(out.len(), (w * h * 4) as usize);
        for p in out.chunks_exact(4) {
            assert_eq!(p, [188, 188, 188, 255]);
        }
        assert_eq!(linear_to_srgb(0.5), 188);
    }

    #[test]
    fn downsample_by_one_is_identity_and_flat_images_stay_flat() {
        let src: Vec<u8> = (0..4 * 3 * 4).map(|i| (i * 7 % 256) as u8).collect();
        assert_eq!(downsample_box_srgb(&src, 4, 3, 1).unwrap(), src);
        let flat = solid(8, 4, [12, 99, 200]);
        assert_eq!(downsample_box_srgb(&flat, 2, 1, 4).unwrap(), solid(2, 1, [12, 99, 200]));
    }

    #[test]
    fn downsample_refuses_bad_sizes() {
        assert!(downsample_box_srgb(&[0; 16], 1, 1, 0).is_err());
        assert!(downsample_box_srgb(&[0; 16], 2, 1, 2).is_err());
        assert!(downsample_box_srgb(&[], 0, 1, 2).is_err());
    }

    #[test]
    fn flip_of_identical_images_is_zero() {
        let a: Vec<u8> = (0..16 * 9 * 4).map(|i| (i * 13 % 256) as u8).collect();
        assert_eq!(mean_flip(&a, &a, 16, 9).unwrap(), 0.0);
        let e = image_error(&a, &a, 16, 9, 16).unwrap();
        assert_eq!((e.samples_per_pixel, e.mean_flip, e.psnr_db), (16, 0.0, f64::INFINITY));
    }

    #[test]
    fn flip_grows_with_the_difference() {
        let grey = solid(16, 16, [128, 128, 128]);
        let near = solid(16, 16, [136, 128, 128]);
        let far = solid(16, 16, [255, 0, 0]);
        let small = mean_flip(&grey, &near, 16, 16).unwrap();
        let large = mean_flip(&grey, &far, 16, 16).unwrap();
        assert!(0.0 < small && small < large && large <= 1.0, "{small} {large}");
        let black = solid(4, 4, [0, 0, 0]);
        let white = solid(4, 4, [255, 255, 255]);
        assert!(mean_flip(&black, &white, 4, 4).unwrap() > 0.9);
    }

    #[test]
    fn psnr_known_values() {
        // Every channel off by 16: MSE 256, PSNR 10·log10(65025 / 256) ≈ 24.048 dB.
        let a = solid(4, 4, [100, 100, 100]);
        let b = solid(4, 4, [116, 84, 116]);
        let e = image_error(&a, &b, 4, 4, 4).unwrap();
        assert!((e.psnr_db - 10.0 * (65025.0f64 / 256.0).log10()).abs() < 1e-9, "{}", e.psnr_db);
        assert!((e.psnr_db - 24.048).abs() < 1e-3);
    }

    #[test]
    fn infinite_psnr_survives_json() {
        let e = ImageError { samples_per_pixel: 16, mean_flip: 0.0, psnr_db: f64::INFINITY };
        let json = serde_json::to_string(&e).unwrap();
        assert!(json.contains("\"psnr_db\":null"), "{json}");
        assert_eq!(serde_json::from_str::<ImageError>(&json).unwrap(), e);
        let finite = ImageError { psnr_db: 31.5, ..e };
        assert_eq!(serde_json::from_str::<ImageError>(&serde_json::to_string(&finite).unwrap()).unwrap(), finite);
    }

    #[test]
    fn metrics_refuse_mismatched_sizes() {
        assert!(mean_flip(&[0; 16], &[0; 12], 2, 2).is_err());
        assert!(mean_flip(&[0; 16], &[0; 16], 4, 2).is_err());
        assert!(image_error(&[0; 16], &[0; 16], 0, 4, 1).is_err());
    }
}
