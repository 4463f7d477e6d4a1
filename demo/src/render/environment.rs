//! Environment maps — the radiance that arrives from outside the scene as an equirectangular
//! (latitude-longitude) image, and light sampling proportional to it — and portals, the
//! openings at which light samples of a uniform environment aim ([`Portal`]).
//!
//! **Directions.** glTF's +Y is up. A direction `d` at polar angle θ = acos(d.y) from +Y and
//! azimuth φ = atan2(d.x, −d.z) maps to the image coordinates `u = φ/2π + ½` (left to right)
//! and `v = θ/π` (top to bottom): the image's centre is the horizon straight down −Z (where a
//! glTF camera looks by default), its right quarter +X, its top row the zenith
//! ([`EnvironmentMap::direction`], [`EnvironmentMap::coordinates`]). Each texel holds constant
//! radiance (nearest-texel lookup, [`EnvironmentMap::radiance`]).
//!
//! **Sampling** (pbrt-v3, section 14.2.4 "Infinite Area Lights", and Pharr, Jakob and
//! Humphreys, *Physically Based Rendering*, 3rd ed., section 13.6.7 "Piecewise-Constant 2D
//! Distributions"): texel (i, j) is picked with probability proportional to its luminance
//! times sin θ at its row's centre — the texel's solid angle up to a constant — by a marginal
//! distribution over rows and a conditional one within the picked row, and the direction is
//! uniform in (u, v) within the texel. Its density is `p(u, v) = P(i, j)·W·H` in the unit
//! square and, since `dω = 2π²·sin θ du dv`, `p(ω) = p(u, v) / (2π² sin θ)`
//! ([`EnvironmentMap::pdf`]). The densities are read from the same `f32` cumulative tables the
//! sampling searches (differences of adjacent entries), so a texel whose probability rounds to
//! zero is never sampled and has density zero: light sampling and its MIS weights stay
//! consistent, and the estimate unbiased.
//!
//! The GPU tracer reads the same tables and texels from its texel buffer
//! ([`EnvironmentMap::gpu_words`]; WGSL `environment_radiance`, `environment_sample`,
//! `environment_map_pdf`).

use core::f32::consts::{PI, TAU};
use std::path::Path;

use glam::{Vec2, Vec3};
use mcg_markov_guide::mcpg::luminance;

use super::output::RgbImage;

/// An equirectangular environment map with its sampling tables (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    width: u32,
    height: u32,
    /// Radiance per texel, linear RGB, row-major from the top-left (the zenith row first).
    texels: Vec<Vec3>,
    /// The marginal distribution over rows: `height + 1` increasing entries from 0 to 1.
    row_cdf: Vec<f32>,
    /// The conditional distributions within each row: `width + 1` increasing entries from 0
    /// to 1 per row, row after row.
    column_cdf: Vec<f32>,
    /// [`EnvironmentMap::rotation`], radians.
    rotation: f32,
}

impl EnvironmentMap {
    /// The map of `width × height` texels `texels` (linear RGB radiance, row-major from the
    /// top-left, the zenith row first) and its sampling tables.
    ///
    /// # Errors
    /// When the size does not match the texels or is 0, when a channel is negative or not
    /// finite (or so large that the luminance is not), or when every texel is black.
    pub fn new(width: u32, height: u32, texels: Vec<Vec3>) -> Result<Self, String> {
        if width == 0 || height == 0 || texels.len() != width as usize * height as usize {
            return Err(format!(
                "{} texels do not make a {width} × {height} map",
                texels.len()
            ));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| !(t.is_finite() && t.min_element() >= 0.0 && luminance(*t).is_finite()))
        {
            return Err(format!(
                "texel ({}, {}) is {}, not finite and non-negative",
                i % width as usize,
                i / width as usize,
                texels[i]
            ));
        }
        let (w, h) = (width as usize, height as usize);
        let mut row_weights = Vec::with_capacity(h);
        let mut column_cdf = Vec::with_capacity(h * (w + 1));
        for (j, row) in texels.chunks_exact(w).enumerate() {
            let sin = ((j as f64 + 0.5) / h as f64 * core::f64::consts::PI).sin();
            let weights: Vec<f64> = row.iter().map(|&t| f64::from(luminance(t)) * sin).collect();
            let total: f64 = weights.iter().sum();
            row_weights.push(total);
            column_cdf.extend(cumulative(&weights, total));
        }
        let total: f64 = row_weights.iter().sum();
        if !(total > 0.0) {
            return Err("every texel is black".to_owned());
        }
        Ok(Self {
            width,
            height,
            row_cdf: cumulative(&row_weights, total),
            column_cdf,
            texels,
            rotation: 0.0,
        })
    }

    /// Reads an equirectangular map from an OpenEXR (`.exr`, its first layer's RGB) or
    /// Radiance (`.hdr`) file, as linear RGB radiance.
    ///
    /// # Errors
    /// When the file cannot be read or decoded, or [`EnvironmentMap::new`] refuses its texels;
    /// the message names the file.
    pub fn open(path: &Path) -> Result<Self, String> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let (width, height, texels) = match extension.as_deref() {
            Some("exr") => {
                let image = RgbImage::read_exr(path).map_err(|e| e.to_string())?;
                (image.width, image.height, image.pixels)
            }
            Some("hdr") => {
                let image = image::open(path)
                    .map_err(|e| format!("{}: cannot read the image: {e}", path.display()))?
                    .into_rgb32f();
                let texels = image.pixels().map(|p| Vec3::from(p.0)).collect();
                (image.width(), image.height(), texels)
            }
            _ => {
                return Err(format!(
                    "{}: an environment map is an OpenEXR (.exr) or Radiance (.hdr) file",
                    path.display()
                ));
            }
        };
        Self::new(width, height, texels).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Width in texels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texels, row-major from the top-left.
    #[must_use]
    pub fn texels(&self) -> &[Vec3] {
        &self.texels
    }

    /// The map turned by `radians` about +Y (right-handed: at a quarter turn the image's
    /// centre, straight down −Z unturned, lies along −X), as renderers turn a sky to place
    /// its sun; the sampling tables stay, since a turn about +Y keeps every texel's polar
    /// angle. A non-finite angle leaves the map unturned.
    #[must_use]
    pub fn with_rotation(mut self, radians: f32) -> Self {
        self.rotation = if radians.is_finite() { radians } else { 0.0 };
        self
    }

    /// The turn about +Y, radians ([`EnvironmentMap::with_rotation`]; 0 by default).
    #[must_use]
    pub fn rotation(&self) -> f32 {
        self.rotation
    }

    /// The world direction `d` in the map's own frame (turned back by the rotation).
    fn to_map(&self, d: Vec3) -> Vec3 {
        if self.rotation == 0.0 {
            return d;
        }
        let (s, c) = self.rotation.sin_cos();
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// The map's direction `d` in the world (turned by the rotation).
    fn to_world(&self, d: Vec3) -> Vec3 {
        if self.rotation == 0.0 {
            return d;
        }
        let (s, c) = self.rotation.sin_cos();
        Vec3::new(c * d.x + s * d.z, d.y, c * d.z - s * d.x)
    }

    /// The unit direction of the image coordinates `(u, v)` ∈ [0, 1]² (module docs).
    #[must_use]
    pub fn direction(uv: Vec2) -> Vec3 {
        let (sin_phi, cos_phi) = (TAU * (uv.x - 0.5)).sin_cos();
        let (sin_theta, cos_theta) = (PI * uv.y).sin_cos();
        Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi)
    }

    /// The image coordinates `(u, v)` ∈ [0, 1]² of the unit direction `d` (module docs).
    #[must_use]
    pub fn coordinates(d: Vec3) -> Vec2 {
        Vec2::new(
            d.x.atan2(-d.z) * (0.5 / PI) + 0.5,
            d.x.hypot(d.z).atan2(d.y) * (1.0 / PI),
        )
    }

    /// The texel `(column, row)` that holds the image coordinates `uv`.
    fn texel_of(&self, uv: Vec2) -> (usize, usize) {
        let column = ((uv.x * self.width as f32) as usize).min(self.width as usize - 1);
        let row = ((uv.y * self.height as f32) as usize).min(self.height as usize - 1);
        (column, row)
    }

    /// The radiance that arrives along `-d`, i.e. seen looking in the unit direction `d`: its
    /// texel's.
    #[must_use]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let (column, row) = self.texel_of(Self::coordinates(self.to_map(d)));
        self.texels[row * self.width as usize + column]
    }

    /// The probability of picking texel `(column, row)`: the product of its row's and its
    /// column's steps in the tables.
    fn texel_probability(&self, column: usize, row: usize) -> f32 {
        let c = &self.column_cdf[row * (self.width as usize + 1)..];
        (self.row_cdf[row + 1] - self.row_cdf[row]) * (c[column + 1] - c[column])
    }

    /// A direction drawn from uniforms `u` ∈ [0, 1)² with density proportional to the map's
    /// luminance (module docs), and its solid-angle density [`EnvironmentMap::pdf`]; `None`
    /// for a direction at a pole, where the density has no finite value.
    #[must_use]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let (row, v) = sample_table(&self.row_cdf, u.y);
        let columns = &self.column_cdf[row * (self.width as usize + 1)..][..=self.width as usize];
        let (column, s) = sample_table(columns, u.x);
        let uv = Vec2::new(
            (column as f32 + s) / self.width as f32,
            (row as f32 + v) / self.height as f32,
        );
        let d = self.to_world(Self::direction(uv));
        let pdf = self.texel_probability(column, row) * (self.width * self.height) as f32
            / (2.0 * PI * PI * (PI * uv.y).sin());
        (pdf > 0.0 && pdf.is_finite()).then_some((d, pdf))
    }

    /// The solid-angle density with which [`EnvironmentMap::sample`] draws the unit direction
    /// `d`: `P(texel)·W·H / (2π² sin θ)`; 0 at the poles and in texels it never picks.
    #[must_use]
    pub fn pdf(&self, d: Vec3) -> f32 {
        let turned = self.to_map(d);
        let uv = Self::coordinates(turned);
        let (column, row) = self.texel_of(uv);
        // sin θ of the unit direction itself (as accurate at the poles as anywhere).
        let sin = turned.x.hypot(turned.z);
        if !(sin > 0.0) {
            return 0.0;
        }
        self.texel_probability(column, row) * (self.width * self.height) as f32
            / (2.0 * PI * PI * sin)
    }

    /// The map as the GPU tracer reads it after the textures' texels, as `u32` words (`f32`
    /// bits): the row table (`height + 1`), the column tables (`height × (width + 1)`), then
    /// the texels' red, green and blue (3 per texel, row-major). The rotation travels in
    /// `GpuParams::environment_map`.
    #[must_use]
    pub fn gpu_words(&self) -> Vec<u32> {
        self.row_cdf
            .iter()
            .chain(&self.column_cdf)
            .copied()
            .chain(self.texels.iter().flat_map(|t| t.to_array()))
            .map(f32::to_bits)
            .collect()
    }
}

/// The cumulative table of `weights` (total `total`): `weights.len() + 1` entries from 0 to
/// 1, summed in `f64`; uniform steps for a total of 0 (a black row, which the row table
/// never picks).
fn cumulative(weights: &[f64], total: f64) -> Vec<f32> {
    let n = weights.len();
    let mut out = Vec::with_capacity(n + 1);
    out.push(0.0);
    let mut acc = 0.0;
    for (i, &w) in weights.iter().enumerate() {
        acc += w;
        out.push(if total > 0.0 {
            (acc / total) as f32
        } else {
            (i + 1) as f32 / n as f32
        });
    }
    out[n] = 1.0;
    out
}

/// The step `i` of the cumulative table `cdf` that holds `u` ∈ [0, 1) (the last entry at or
/// below `u`, so that empty steps are skipped) and where `u` falls within it, in [0, 1).
fn sample_table(cdf: &[f32], u: f32) -> (usize, f32) {
    let i = (cdf.partition_point(|&c| c <= u).max(1) - 1).min(cdf.len() - 2);
    let step = cdf[i + 1] - cdf[i];
    let within = if step > 0.0 {
        ((u - cdf[i]) / step).clamp(0.0, ONE_BELOW)
    } else {
        0.5
    };
    (i, within)
}

/// The largest `f32` below 1.
pub(crate) const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// A portal: a parallelogram through which the environment lights an interior (a window or a
/// doorway; Bitterli et al. 2015, "Portal-Masked Environment Map Sampling", take the same
/// view of portals). Light samples of the environment aim at uniform points of the portals
/// ([`Portal::sample`]), so that from inside a room they are not spent on directions the walls
/// block. 48 bytes, as the GPU reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Portal {
    /// A corner.
    pub corner: [f32; 3],
    /// The area, `|edge_u × edge_v|`.
    pub area: f32,
    /// The edge from the corner to the next corner.
    pub edge_u: [f32; 3],
    /// The probability of picking this portal among the scene's (in proportion to area).
    pub pmf: f32,
    /// The other edge from the corner.
    pub edge_v: [f32; 3],
    /// Zero.
    pub pad: f32,
}

impl Portal {
    /// The parallelogram `corner + s·edge_u + t·edge_v`, s, t ∈ [0, 1] (its
    /// [`Portal::pmf`] 1 until the scene shares it); `None` when it has no finite positive
    /// area.
    #[must_use]
    pub fn new(corner: Vec3, edge_u: Vec3, edge_v: Vec3) -> Option<Self> {
        let area = edge_u.cross(edge_v).length();
        (corner.is_finite() && area > 0.0 && area.is_finite()).then_some(Self {
            corner: corner.to_array(),
            area,
            edge_u: edge_u.to_array(),
            pmf: 1.0,
            edge_v: edge_v.to_array(),
            pad: 0.0,
        })
    }

    /// The unit normal `edge_u × edge_v / area`.
    fn normal(&self) -> Vec3 {
        Vec3::from(self.edge_u).cross(Vec3::from(self.edge_v)) / self.area
    }

    /// A direction from `origin` to the uniform point `(u.x, u.y)` of the portal, and the
    /// solid-angle density of that choice given the portal, `d² / (area · |cos|)`; `None` where
    /// the point is not in a direction (at `origin`, or edge-on).
    #[must_use]
    pub fn sample(&self, origin: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
        let y =
            Vec3::from(self.corner) + u.x * Vec3::from(self.edge_u) + u.y * Vec3::from(self.edge_v);
        let to = y - origin;
        let dist2 = to.length_squared();
        let wi = to / dist2.sqrt();
        let cos = self.normal().dot(wi).abs();
        let pdf = dist2 / (self.area * cos);
        (pdf > 0.0 && pdf.is_finite()).then_some((wi, pdf))
    }

    /// The solid-angle density with which [`Portal::sample`] from `origin` draws the unit
    /// direction `d`: `t² / (area · |cos|)` where the ray crosses the portal at distance `t`,
    /// else 0.
    #[must_use]
    pub fn pdf(&self, origin: Vec3, d: Vec3) -> f32 {
        let n = self.normal();
        let cos = n.dot(d);
        let t = n.dot(Vec3::from(self.corner) - origin) / cos;
        if !(t > 0.0 && t.is_finite()) {
            return 0.0;
        }
        let p = origin + t * d - Vec3::from(self.corner);
        let (eu, ev) = (Vec3::from(self.edge_u), Vec3::from(self.edge_v));
        // The point's coordinates (s, r) in the edges' basis, by the dual basis of the plane.
        let s = p.cross(ev).dot(n) / self.area;
        let r = eu.cross(p).dot(n) / self.area;
        if !((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r)) {
            return 0.0;
        }
        t * t / (self.area * cos.abs())
    }
}
