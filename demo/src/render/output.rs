//! Image files and error metrics: linear EXR in and out, sRGB PNG out, RMSE, relative MSE and
//! FLIP.

use std::path::Path;

use glam::Vec3;

use crate::Result;

/// A linear RGB image, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels.
    pub pixels: Vec<Vec3>,
}

impl RgbImage {
    /// Writes the image as a 32-bit float RGB OpenEXR file.
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        let w = self.width as usize;
        exr::prelude::write_rgb_file(path, w, self.height as usize, |x, y| {
            let p = self.pixels[y * w + x];
            (p.x, p.y, p.z)
        })
        .map_err(|e| format!("{}: cannot write EXR: {e}", path.display()))?;
        Ok(())
    }

    /// Reads the RGB channels of the first layer of an OpenEXR file.
    ///
    /// # Errors
    /// When the file is missing or not an RGB(A) EXR.
    pub fn read_exr(path: &Path) -> Result<Self> {
        let image = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |size, _| (size.0, vec![Vec3::ZERO; size.0 * size.1]),
            |(w, pixels): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels[pos.1 * *w + pos.0] = Vec3::new(r, g, b);
            },
        )
        .map_err(|e| format!("{}: cannot read EXR: {e}", path.display()))?;
        let size = image.layer_data.size;
        Ok(Self {
            width: size.0 as u32,
            height: size.1 as u32,
            pixels: image.layer_data.channel_data.pixels.1,
        })
    }

    /// Writes the image as an 8-bit sRGB PNG: each channel clipped to [0, 1] and encoded with
    /// the sRGB transfer function (IEC 61966-2-1); no exposure change.
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        image::save_buffer(
            path,
            &self.to_srgb8(),
            self.width,
            self.height,
            image::ColorType::Rgb8,
        )
        .map_err(|e| format!("{}: cannot write PNG: {e}", path.display()))?;
        Ok(())
    }
}

impl RgbImage {
    /// The 8-bit sRGB bytes of [`RgbImage::write_png`], RGB interleaved, row-major.
    #[must_use]
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.to_array())
            .map(|c| (srgb_encode(c) * 255.0 + 0.5) as u8)
            .collect()
    }
}

/// Pixels per degree of visual angle at which [`flip`] compares: FLIP's default, a 0.7 m wide
/// 3840-pixel monitor seen from 0.7 m.
pub const FLIP_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// The mean LDR-FLIP error of `image` against `reference` (Andersson et al. 2020, "FLIP: A
/// Difference Evaluator for Alternating Images", HPG; NVIDIA's implementation through the
/// `nv-flip` crate), both as [`RgbImage::write_png`] encodes them (clipped, sRGB, 8 bits) and
/// seen at [`FLIP_PIXELS_PER_DEGREE`]: 0 for identical images, at most 1. `None` when the
/// sizes differ or the images are empty.
#[must_use]
pub fn flip(image: &RgbImage, reference: &RgbImage) -> Option<f64> {
    if (image.width, image.height) != (reference.width, reference.height)
        || image.pixels.is_empty()
        || image.pixels.len() != (image.width * image.height) as usize
        || reference.pixels.len() != image.pixels.len()
    {
        return None;
    }
    let encode = |i: &RgbImage| nv_flip::FlipImageRgb8::with_data(i.width, i.height, &i.to_srgb8());
    let map = nv_flip::flip(encode(reference), encode(image), FLIP_PIXELS_PER_DEGREE);
    Some(f64::from(nv_flip::FlipPool::from_image(&map).mean()))
}

/// The sRGB transfer function of a linear value, clipped to [0, 1] (NaN gives 0).
#[must_use]
pub fn srgb_encode(c: f32) -> f32 {
    let c = if c > 0.0 { c.min(1.0) } else { 0.0 };
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The ε of [`Errors::rel_mse`] that keeps black reference pixels from dominating.
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// Errors of an image against a reference of the same size.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Errors {
    /// Root mean squared error over all pixels and channels.
    pub rmse: f64,
    /// Relative MSE: the mean over pixels and channels of (x − r)² / (r² + ε), ε =
    /// [`REL_MSE_EPSILON`] (Rousselle et al. 2011, "Adaptive Sampling and Reconstruction
    /// using Greedy Error Minimization", SIGGRAPH Asia).
    pub rel_mse: f64,
}

/// [`Errors`] of `image` against `reference`; `None` when the sizes differ.
#[must_use]
pub fn errors(image: &[Vec3], reference: &[Vec3]) -> Option<Errors> {
    if image.len() != reference.len() || image.is_empty() {
        return None;
    }
    let (mut se, mut rel) = (0.0f64, 0.0f64);
    for (p, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let (x, y) = (f64::from(p[c]), f64::from(r[c]));
            let d2 = (x - y) * (x - y);
            se += d2;
            rel += d2 / (y * y + REL_MSE_EPSILON);
        }
    }
    let n = (3 * image.len()) as f64;
    Some(Errors {
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_of_known_images() {
        let r = vec![Vec3::ZERO, Vec3::ONE];
        let x = vec![Vec3::splat(0.1), Vec3::ONE];
        let e = errors(&x, &r).unwrap();
        assert!((e.rmse - (0.01f64 / 2.0).sqrt()).abs() < 1e-7);
        assert!((e.rel_mse - 0.5 * 0.01 / REL_MSE_EPSILON).abs() < 1e-6);
        assert!(errors(&x, &r[..1]).is_none());
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6 && srgb_encode(2.0) == srgb_encode(1.0));
        assert_eq!(srgb_encode(f32::NAN), 0.0);
    }

    /// FLIP is 0 for identical images, grows with the noise added to one, and refuses images
    /// of different sizes.
    #[test]
    fn flip_grows_with_noise() {
        let (w, h) = (32, 32);
        let base: Vec<Vec3> = (0..w * h)
            .map(|i| Vec3::splat(0.2 + 0.6 * (i % w) as f32 / w as f32))
            .collect();
        let noisy = |amplitude: f32| RgbImage {
            width: w,
            height: h,
            pixels: base
                .iter()
                .enumerate()
                .map(|(i, p)| *p * (1.0 + amplitude * if i % 3 == 0 { 1.0 } else { -0.5 }))
                .collect(),
        };
        let reference = noisy(0.0);
        let (zero, small, large) = (
            flip(&reference, &reference).unwrap(),
            flip(&noisy(0.1), &reference).unwrap(),
            flip(&noisy(0.5), &reference).unwrap(),
        );
        assert!(zero.abs() < 1e-6, "{zero}");
        assert!(
            0.0 < small && small < large && large <= 1.0,
            "{small} {large}"
        );
        let mut other = reference.clone();
        other.width = 16;
        other.pixels.truncate(16 * 32);
        other.height = 32;
        assert!(flip(&other, &reference).is_none());
    }

    #[test]
    fn exr_round_trip() {
        let dir = std::env::temp_dir().join(format!("mcg-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let image = RgbImage {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| Vec3::new(i as f32, 0.5 * i as f32, 1e3))
                .collect(),
        };
        let path = dir.join("a.exr");
        image.write_exr(&path).unwrap();
        assert_eq!(RgbImage::read_exr(&path).unwrap(), image);
        image.write_png(&dir.join("a.png")).unwrap();
        assert!(RgbImage::read_exr(&dir.join("missing.exr")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
