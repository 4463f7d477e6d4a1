//! Image files and error metrics: linear EXR in and out, sRGB PNG out, RMSE, relative MSE and
//! FLIP; the variance of a render's mean, estimated from its frames, and the error a
//! reference carries itself.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};

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
    let terms = channel_pairs(image, reference).map(|(x, y)| ((x - y) * (x - y), y));
    Some(mean_errors(image.len(), terms))
}

/// [`Errors`] from the squared error `e` and the reference value `r` of each of the 3 · `pixels`
/// channels: rmse = √(mean e), relMSE = mean e / (r² + ε).
fn mean_errors(pixels: usize, terms: impl Iterator<Item = (f64, f64)>) -> Errors {
    let (mut se, mut rel) = (0.0f64, 0.0f64);
    for (e, r) in terms {
        se += e;
        rel += e / (r * r + REL_MSE_EPSILON);
    }
    let n = (3 * pixels) as f64;
    Errors {
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
    }
}

/// The values of `a` and `b` at every pixel and channel, in order, as f64.
fn channel_pairs<'a>(a: &'a [Vec3], b: &'a [Vec3]) -> impl Iterator<Item = (f64, f64)> + 'a {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]), f64::from(q[c]))))
}

/// The file beside an image's EXR that holds the variance of its pixels
/// ([`FrameVariance`]): `DIR/nee.exr` → `DIR/nee.variance.exr`.
#[must_use]
pub fn variance_path(exr: &Path) -> PathBuf {
    let stem = exr.file_stem().and_then(|s| s.to_str()).unwrap_or("image");
    exr.with_file_name(format!("{stem}.variance.exr"))
}

/// The error a reference carries itself, in the units of [`Errors`]: `rmse` = √(mean Var Rₚ),
/// `rel_mse` = the mean of Var Rₚ / (Rₚ² + ε), over pixels and channels, from the per-pixel
/// `variance` of the reference `reference` ([`FrameVariance`]). `None` when the sizes differ.
///
/// A render X and a reference R rendered independently, both unbiased for the true image I,
/// have E[(X − R)²] = E[(X − I)²] + Var R per pixel (the cross term has mean 0), so an error
/// measured against R overstates the error against I by Var R. This is the same amount for
/// every method measured against R; it weighs most on the best ones (at 16 384 spp of `nee`
/// on scene (a), ≈ 0.0007, a tenth of `mcpg`'s relMSE after 64 frames and 3 % of `nee`'s).
/// Subtracting it gives an unbiased estimate of the MSE against I; for the relMSE, whose
/// weights 1/(Rₚ² + ε) come from the noisy reference too, an estimate to first order in the
/// reference's relative noise (a few percent per pixel at 16 384 spp).
#[must_use]
pub fn own_error(reference: &[Vec3], variance: &[Vec3]) -> Option<Errors> {
    if reference.len() != variance.len() || reference.is_empty() {
        return None;
    }
    let terms = channel_pairs(reference, variance).map(|(y, var)| (var, y));
    Some(mean_errors(reference.len(), terms))
}

/// The variance of the plain mean of a render's frames, per pixel and channel, estimated from
/// the frames themselves: s²/n, with s² the frames' sample variance (Welford's update, in f64)
/// and n the frames.
///
/// For frames X₁…Xₙ with one expectation whose errors are uncorrelated, E[s²/n] is exactly
/// Var(X̄) = Σ Var Xᵢ / n², whether or not the frames' variances are equal: true for
/// independent frames (`bsdf`, `nee`) and for a guide's frames, each unbiased given the guide
/// the frames before it left (their errors form a martingale difference sequence). It is not
/// the variance of a weighted mean (`--ramp-frames`) nor of an animated scene's frames.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameVariance {
    frames: u32,
    mean: Vec<DVec3>,
    m2: Vec<DVec3>,
}

impl FrameVariance {
    /// No frames yet, over `pixels` pixels.
    #[must_use]
    pub fn new(pixels: usize) -> Self {
        Self {
            frames: 0,
            mean: vec![DVec3::ZERO; pixels],
            m2: vec![DVec3::ZERO; pixels],
        }
    }

    /// Adds one frame (of the accumulator's size).
    pub fn add(&mut self, image: &[Vec3]) {
        self.frames += 1;
        let n = f64::from(self.frames);
        for ((mean, m2), p) in self.mean.iter_mut().zip(&mut self.m2).zip(image) {
            let x = p.as_dvec3();
            let delta = x - *mean;
            *mean += delta / n;
            *m2 += delta * (x - *mean);
        }
    }

    /// s²/n per pixel and channel; `None` before the second frame.
    #[must_use]
    pub fn variance_of_mean(&self) -> Option<Vec<Vec3>> {
        (self.frames >= 2).then(|| {
            let n = f64::from(self.frames);
            let scale = 1.0 / ((n - 1.0) * n);
            self.m2.iter().map(|m| (*m * scale).as_vec3()).collect()
        })
    }
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

    /// s²/n of frames 1, 3 (mean 2, s² = 2) is 1; of frames 1, 3, 5 (s² = 4) 4/3; one frame
    /// gives none; a constant pixel 0.
    #[test]
    fn frame_variance_is_the_variance_of_the_mean() {
        let mut v = FrameVariance::new(2);
        assert_eq!(v.variance_of_mean(), None);
        for x in [1.0, 3.0] {
            v.add(&[Vec3::new(x, -x, 10.0 * x), Vec3::splat(0.25)]);
        }
        assert_eq!(
            v.variance_of_mean().unwrap(),
            [Vec3::new(1.0, 1.0, 100.0), Vec3::ZERO]
        );
        v.add(&[Vec3::new(5.0, -5.0, 50.0), Vec3::splat(0.25)]);
        let var = v.variance_of_mean().unwrap();
        assert!(
            (var[0] - Vec3::new(4.0, 4.0, 400.0) / 3.0)
                .abs()
                .max_element()
                < 1e-4
        );
        // The own error of a reference of 1 with variance 0.01: RMSE 0.1, relMSE 0.01/(1 + ε).
        let own = own_error(&[Vec3::ONE], &[Vec3::splat(0.01)]).unwrap();
        assert!((own.rmse - 0.1).abs() < 1e-7);
        assert!((own.rel_mse - 0.01 / (1.0 + REL_MSE_EPSILON)).abs() < 1e-7);
        assert!(own_error(&[Vec3::ONE], &[]).is_none());
        assert_eq!(
            variance_path(Path::new("out/nee.exr")),
            Path::new("out/nee.variance.exr")
        );
    }

    #[test]
    fn exr_round_trip() {
        let scratch = tempfile::Builder::new()
            .prefix("mcg-exr-")
            .tempdir()
            .unwrap();
        let dir = scratch.path();
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
    }
}
