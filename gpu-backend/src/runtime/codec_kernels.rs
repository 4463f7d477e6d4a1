//! The colour-codec kernels.

use std::sync::OnceLock;

use glam::Vec3;

use super::lazy;
use crate::shaders::kernels as src;
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// The colour-codec kernels: every packed layout and LogLuv32 encoded and decoded on the GPU
/// (the WGSL twins of mcg-color-codec), for checking a device against the CPU crate or
/// converting arrays of colours. Pipelines are built on first use.
#[derive(Debug, Default)]
pub struct CodecKernels {
    pack_unpack: OnceLock<ComputeKernel>,
    logluv: OnceLock<ComputeKernel>,
}

/// What [`CodecKernels::pack_unpack`] computes for one input `[r, g, b, u]` (colour and the
/// uniform of stochastic rounding), with the sample count `i mod 64` of element `i`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CodecPackRead {
    /// R11G11B10, RGB9E5 and gamma-5 R10G10B10A2 words of the colour, and its ADGI irradiance
    /// word rounded down.
    pub formats: [u32; 4],
    /// The irradiance word rounded to nearest and stochastically with `u`; the visibility word
    /// of the moments `(r, g)` rounded to nearest and stochastically.
    pub rounded: [u32; 4],
    /// The heuristics word of `min(colour, 1)` rounded to nearest and stochastically (then 0, 0).
    pub heuristics: [u32; 4],
    /// The words decoded again: R11G11B10, RGB9E5, gamma-5, irradiance (down), irradiance
    /// (nearest) as RGB; the visibility moments (nearest) in `.xy`; the heuristics (nearest).
    pub decoded: [[f32; 4]; 7],
}

/// What [`CodecKernels::logluv`] computes for one colour and one word.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogLuvRead {
    /// `LogLuv32::pack_xyz(colour)` and `LogLuv32.encode(colour)` (the colour as CIE XYZ and as
    /// linear sRGB).
    pub packed: [u32; 2],
    /// `LogLuv32::unpack_xyz(word)`.
    pub xyz: Vec3,
    /// `LogLuv32.decode(word)` (linear sRGB).
    pub rgb: Vec3,
}

impl CodecKernels {
    /// The kernels, none built yet.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Encodes and decodes each `[r, g, b, u]` of `values` in every packed layout on the GPU
    /// (`codec_pack_unpack`); see [`CodecPackRead`].
    pub fn pack_unpack(
        &self,
        ctx: &GpuContext,
        values: &[[f32; 4]],
    ) -> Result<Vec<CodecPackRead>, GpuError> {
        let kernel = lazy(
            &self.pack_unpack,
            ctx,
            src::COLOR_CODEC,
            "codec_pack_unpack",
        )?;
        let n = values.len();
        let values = ctx.storage_buffer("values", values);
        let words: GpuBuffer<[u32; 4]> = ctx.zeroed_buffer("words", 3 * n);
        let decoded: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("decoded", 7 * n);
        ctx.dispatch(
            kernel,
            &[values.raw(), words.raw(), decoded.raw()],
            n as u32,
        )?;
        let words = ctx.read_back(&words)?;
        let decoded = ctx.read_back(&decoded)?;
        Ok(words
            .chunks_exact(3)
            .zip(decoded.chunks_exact(7))
            .map(|(w, d)| CodecPackRead {
                formats: w[0],
                rounded: w[1],
                heuristics: w[2],
                decoded: d.try_into().expect("seven entries"),
            })
            .collect())
    }

    /// LogLuv32 on the GPU (`codec_logluv`, with the step tables of
    /// [`logluv_tables`](crate::shaders::constants::logluv_tables)): each `colours[i]` packed,
    /// each `words[i]` unpacked.
    ///
    /// # Panics
    /// If `colours` and `words` differ in length.
    pub fn logluv(
        &self,
        ctx: &GpuContext,
        colours: &[Vec3],
        words: &[u32],
    ) -> Result<Vec<LogLuvRead>, GpuError> {
        GpuError::check_len(colours.len(), words.len())?;
        let kernel = lazy(&self.logluv, ctx, src::COLOR_CODEC_LOGLUV, "codec_logluv")?;
        let n = colours.len();
        let inputs: Vec<[u32; 4]> = colours
            .iter()
            .zip(words)
            .map(|(c, &w)| [c.x.to_bits(), c.y.to_bits(), c.z.to_bits(), w])
            .collect();
        let inputs = ctx.storage_buffer("values", &inputs);
        let tables = ctx.storage_buffer("tables", &crate::shaders::constants::logluv_tables());
        let packed: GpuBuffer<[u32; 2]> = ctx.zeroed_buffer("packed", n);
        let unpacked: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("unpacked", 2 * n);
        ctx.dispatch(
            kernel,
            &[inputs.raw(), packed.raw(), unpacked.raw(), tables.raw()],
            n as u32,
        )?;
        let packed = ctx.read_back(&packed)?;
        let unpacked = ctx.read_back(&unpacked)?;
        Ok(packed
            .into_iter()
            .zip(unpacked.chunks_exact(2))
            .map(|(packed, u)| LogLuvRead {
                packed,
                xyz: Vec3::new(u[0][0], u[0][1], u[0][2]),
                rgb: Vec3::new(u[1][0], u[1][1], u[1][2]),
            })
            .collect())
    }
}
