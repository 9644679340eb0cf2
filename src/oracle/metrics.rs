//! Image metrics for comparing renders: mean absolute error and PSNR over the RGB channels of two
//! RGBA8 images (alpha ignored), in 8-bit units. (FLIP is in `oracle::image_error`.)

use crate::{Error, Result};

/// Differences between two RGBA8 images, over the R, G and B channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageDiff {
    /// Mean of `|a − b|` per channel value, in 8-bit units (0..=255).
    pub mean_abs_error: f64,
    /// Mean of `(a − b)²` per channel value.
    pub mean_sq_error: f64,
    /// `10·log₁₀(255² / MSE)` in dB; infinite for identical images.
    pub psnr_db: f64,
    /// Largest `|a − b|` of any channel value.
    pub max_abs_error: u8,
    /// Pixels where any RGB channel differs.
    pub pixels_differing: usize,
}

/// Compares two RGBA8 buffers of the same size (4 bytes per pixel, same pixel order).
///
/// Refuses buffers of different lengths, a length that is not a multiple of 4, and empty ones.
pub fn compare_rgba8(a: &[u8], b: &[u8]) -> Result<ImageDiff> {
    if a.len() != b.len() {
        return Err(Error::Invalid(format!("images differ in size: {} and {} bytes", a.len(), b.len())));
    }
    if a.is_empty() || !a.len().is_multiple_of(4) {
        return Err(Error::Invalid(format!("an RGBA8 image needs a positive multiple of 4 bytes, not {}", a.len())));
    }
    let (mut abs_sum, mut sq_sum, mut max_abs, mut differing) = (0u64, 0u64, 0u8, 0usize);
    for (p, q) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        let mut any = false;
        for c in 0..3 {
            let d = p[c].abs_diff(q[c]);
            abs_sum += d as u64;
            sq_sum += (d as u64) * (d as u64);
            max_abs = max_abs.max(d);
            any |= d != 0;
        }
        differing += any as usize;
    }
    let n = (a.len() / 4 * 3) as f64;
    let mse = sq_sum as f64 / n;
    let psnr_db = if sq_sum == 0 { f64::INFINITY } else { 10.0 * (255.0f64 * 255.0 / mse).log10() };
    Ok(ImageDiff {
        mean_abs_error: abs_sum as f64 / n,
        mean_sq_error: mse,
        psnr_db,
        max_abs_error: max_abs,
        pixels_differing: differing,
    })
}

/// PSNR in dB of two RGBA8 buffers over RGB (infinite when identical). See [`compare_rgba8`].
pub fn psnr(a: &[u8], b: &[u8]) -> Result<f64> {
    compare_rgba8(a, b).map(|d| d.psnr_db)
}

/// Mean absolute error in 8-bit units of two RGBA8 buffers over RGB. See [`compare_rgba8`].
pub fn mean_absolute_error(a: &[u8], b: &[u8]) -> Result<f64> {
    compare_rgba8(a, b).map(|d| d.mean_abs_error)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_infinite_psnr_and_no_error() {
        let a = vec![10u8, 20, 30, 255, 1, 2, 3, 0];
        let d = compare_rgba8(&a, &a).unwrap();
        assert_eq!(d.psnr_db, f64::INFINITY);
        assert_eq!((d.mean_abs_error, d.max_abs_error, d.pixels_differing), (0.0, 0, 0));
    }

    #[test]
    fn alpha_is_ignored() {
        let a = vec![10u8, 20, 30, 255];
        let b = vec![10u8, 20, 30, 0];
        assert_eq!(psnr(&a, &b).unwrap(), f64::INFINITY);
    }

    #[test]
    fn known_values() {
        // Two pixels; one channel off by 6 and one by 3: MAE = 9/6, MSE = 45/6.
        let a = vec![100u8, 100, 100, 255, 0, 0, 0, 255];
        let b = vec![106u8, 100, 100, 255, 0, 3, 0, 255];
        let d = compare_rgba8(&a, &b).unwrap();
        assert!((d.mean_abs_error - 1.5).abs() < 1e-12);
        assert!((d.mean_sq_error - 7.5).abs() < 1e-12);
        let expect = 10.0 * (65025.0f64 / 7.5).log10();
        assert!((d.psnr_db - expect).abs() < 1e-9);
        assert_eq!((d.max_abs_error, d.pixels_differing), (6, 2));
        // Black against white: 0 dB.
        let black = vec![0u8, 0, 0, 255];
        let white = vec![255u8, 255, 255, 255];
        assert!(psnr(&black, &white).unwrap().abs() < 1e-12);
        assert_eq!(mean_absolute_error(&black, &white).unwrap(), 255.0);
    }

    #[test]
    fn mismatched_sizes_are_refused() {
        assert!(compare_rgba8(&[0; 8], &[0; 4]).is_err());
        assert!(compare_rgba8(&[0; 6], &[0; 6]).is_err());
        assert!(compare_rgba8(&[], &[]).is_err());
    }
}
