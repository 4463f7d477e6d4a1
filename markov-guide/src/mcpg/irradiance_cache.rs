//! MCPG's irradiance cache (sec. 4, "Irradiance Caching"): outgoing radiance at surface points
//! in an adaptive hash grid, queried for L(hit_next, −ω) when the chains are trained.

use std::boxed::Box;
use std::vec::Vec;

use core::sync::atomic::{AtomicU32, Ordering};

use bytemuck::{Pod, Zeroable};
use mcg_hashgrid::{AdaptiveGrid, BucketHash, CellKey, ConcurrentTable, normal_class};
use mcg_vmf::glam::Vec3;

use crate::error::ParamsError;

use super::GuideError;

/// One cache cell as the GPU reads it: linear RGB radiance and the number of frames folded in
/// (16 bytes, `#[repr(C)]` + `Pod`, all zeros = empty). The checksum that names the cell lives in
/// the table's checksum array beside it, as for the guiding states.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CacheCell {
    /// The cached outgoing (reflected) radiance, linear RGB.
    pub radiance: [f32; 3],
    /// Frames with samples folded into `radiance`, capped at 1/α_min (the blend factor is
    /// max(1/weight, α_min)). 0 means empty.
    pub weight: f32,
}

const _: () = assert!(core::mem::size_of::<CacheCell>() == 16);

/// The settings of the [`IrradianceCache`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheConfig {
    /// Slots of the cache's table.
    pub capacity: u32,
    /// α_min, the smallest blend factor of a frame's mean into a cell (MCPG: "a small
    /// accumulation factor"); the first frames average arithmetically (α = 1/frames).
    pub accumulation: f32,
    /// How many coarser levels an insert tries after a full probe neighbourhood (MCPG: "coarser
    /// levels are accessed only upon hash collisions"), and a lookup after a miss.
    pub coarser_levels: u32,
    /// Cells not touched for more frames than this are evicted by `end_frame`.
    pub max_age: u32,
    /// How many levels coarser than the guiding states' target level the cache's cells are
    /// ([`IrradianceCache::level`]); radiance is smoother than its directional distribution.
    /// With the default levels (width ×4 every 4 levels) 2 is twice the width. In the
    /// `guided_room` example (96 × 96, 48 frames) the guided MSE relative to cosine sampling
    /// was 0.135 with bias 0, 0.174 with 1, 0.152-0.158 with 2, 0.233 with 4 and 0.242 with 6;
    /// 2 costs 15 % less time than 0 (fewer cells).
    pub level_bias: u32,
    /// The probability with which [`GuidedVertex::finish`](super::GuidedVertex::finish) adds
    /// its vertex's sample to the cache (mcg's extension; 1, the paper, adds every sample).
    /// The decision and the add's corner come from the same uniform ([`add_uniform`](
    /// Self::add_uniform)), so a cell's frame mean stays unbiased and only gets fewer samples.
    /// With 2-3 scattering vertices per path at 128² and 8 spp, the cells of `mcg-demo`'s
    /// hidden-light room receive ~60 samples per frame at 1 and blend frames with α_min =
    /// 0.05; 1/4 and 1/16 rendered that room with the same error after 64 frames (within the
    /// seeds' spread) and cost 4 % fewer instructions per frame at 1/16
    /// (`benches/README.md`). Must lie in (0, 1].
    pub add_probability: f32,
}

impl CacheConfig {
    /// 2¹⁶ slots, α_min = 0.05, 1 coarser level on collision (each level tried costs a
    /// lookup on every miss), eviction after 64 idle frames, cells 2 levels coarser than the
    /// guiding states', every sample added.
    pub const DEFAULT: Self = Self {
        capacity: 1 << 16,
        accumulation: 0.05,
        coarser_levels: 1,
        max_age: 64,
        level_bias: 2,
        add_probability: 1.0,
    };

    /// Checks the probabilities: `accumulation` and `add_probability` in (0, 1].
    ///
    /// # Errors
    /// [`ParamsError::ProbabilityOutOfRange`] naming the first one outside (NaN included).
    pub fn validate(&self) -> Result<(), ParamsError> {
        for (parameter, value) in [
            ("cache.accumulation", self.accumulation),
            ("cache.add_probability", self.add_probability),
        ] {
            if !(value > 0.0 && value <= 1.0) {
                return Err(ParamsError::ProbabilityOutOfRange { parameter, value });
            }
        }
        Ok(())
    }

    /// 1 / `add_probability`, the factor [`add_uniform`](Self::add_uniform) scales its
    /// uniform by (the GPU guide receives this f32 and multiplies the same way).
    #[must_use]
    pub fn add_scale(&self) -> f32 {
        1.0 / self.add_probability
    }

    /// The corner uniform of the cache add of a vertex finished with the cache uniform `u`:
    /// `u·s`, s = [`add_scale`](Self::add_scale), when that is below 1 (probability
    /// `add_probability` for a uniform `u`; then uniform in [0, 1) itself), `None` when this
    /// vertex adds nothing. With s = 1 every vertex adds, with its `u` unchanged.
    #[inline]
    #[must_use]
    pub fn add_uniform(&self, u: f32) -> Option<f32> {
        let s = self.add_scale();
        let v = u * s;
        (s <= 1.0 || v < 1.0).then_some(v)
    }
}

impl Default for CacheConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// MCPG's irradiance cache: an adaptive hash grid (level from the camera distance as for the
/// guiding states, the normal's cube-map class in the key) of [`CacheCell`]s.
///
/// - [`add`](Self::add) (`&self`, many threads): one radiance sample at a surface point, summed
///   into the cell's per-frame accumulator (f32 sums by compare-and-swap, a count).
/// - [`query`](Self::query) (`&self`): the cell's committed radiance; reads never see a value
///   being written, because cells change only in [`end_frame`](Self::end_frame).
/// - [`end_frame`](Self::end_frame) (`&mut self`): blends each cell's frame mean in with
///   α = max(1/frames, α_min) and evicts cells idle for `max_age` frames.
///
/// A cell is the stochastic-trilinear vertex of the target level plus `level_bias` (no jitter);
/// an insert that finds its probe neighbourhood full moves one level coarser, up to
/// `coarser_levels` times, and a lookup that misses does the same.
#[derive(Debug)]
pub struct IrradianceCache {
    grid: AdaptiveGrid,
    table: ConcurrentTable,
    cells: Vec<CacheCell>,
    /// Per slot: R, G, B sums (f32 bits) and the sample count of the current frame.
    accumulators: Box<[[AtomicU32; 4]]>,
    config: CacheConfig,
}

impl IrradianceCache {
    /// An empty cache on `grid`'s levels.
    ///
    /// # Errors
    /// [`GuideError::Table`] for a capacity below 8, [`GuideError::Params`] for an
    /// accumulation factor outside (0, 1].
    pub fn new(grid: AdaptiveGrid, config: CacheConfig) -> Result<Self, GuideError> {
        config.validate().map_err(GuideError::Params)?;
        let table = ConcurrentTable::new(config.capacity, 8, BucketHash::default())
            .map_err(GuideError::Table)?
            .with_age_tracking();
        Ok(Self {
            grid,
            table,
            cells: std::vec![CacheCell::default(); config.capacity as usize],
            accumulators: (0..config.capacity)
                .map(|_| core::array::from_fn(|_| AtomicU32::new(0)))
                .collect(),
            config,
        })
    }

    /// The settings.
    #[must_use]
    pub const fn config(&self) -> &CacheConfig {
        &self.config
    }

    /// The adaptive grid's target level at `position` seen from `camera` (no jitter): the
    /// `level` of [`add`](Self::add) and [`query`](Self::query), before the cache's
    /// `level_bias`.
    #[inline]
    #[must_use]
    pub fn level(&self, position: Vec3, camera: Vec3) -> u32 {
        self.grid.target_level(camera.distance(position))
    }

    #[inline]
    fn cell_level(&self, level: u32, extra: u32) -> u32 {
        level
            .saturating_add(self.config.level_bias)
            .saturating_add(extra)
            .min(self.grid.params().max_level)
    }

    #[inline]
    fn key(&self, position: Vec3, normal: Vec3, level: u32, corner: f32) -> CellKey {
        let width = self.grid.width(level);
        let vertex = mcg_hashgrid::stochastic_trilinear(position / width, corner);
        CellKey::new(vertex, level as u8, normal_class(normal))
    }

    /// Adds one sample of outgoing radiance at a surface point, from the cell of `level`
    /// ([`level`](Self::level)) on. Samples with a NaN, infinite or negative component are
    /// ignored. Returns `false` when no slot was found within `coarser_levels` coarser levels
    /// (the sample is dropped).
    pub fn add(
        &self,
        position: Vec3,
        normal: Vec3,
        level: u32,
        corner: f32,
        radiance: Vec3,
    ) -> bool {
        if !(radiance.is_finite() && radiance.min_element() >= 0.0 && position.is_finite()) {
            return false;
        }
        let base = level;
        for extra in 0..=self.config.coarser_levels {
            let level = self.cell_level(base, extra);
            let key = self.key(position, normal, level, corner);
            if let Some(slot) = self.table.insert_or_get(&key).slot() {
                let acc = &self.accumulators[slot as usize];
                for (word, value) in acc.iter().zip(radiance.to_array()) {
                    add_f32(word, value);
                }
                acc[3].fetch_add(1, Ordering::Relaxed);
                return true;
            }
        }
        false
    }

    /// The cached outgoing radiance at a surface point: the committed value of the first cell
    /// found from `level` ([`level`](Self::level)) on, up to `coarser_levels` coarser; 0 when
    /// none holds one.
    #[must_use]
    pub fn query(&self, position: Vec3, normal: Vec3, level: u32, corner: f32) -> Vec3 {
        if !position.is_finite() {
            return Vec3::ZERO;
        }
        let base = level;
        for extra in 0..=self.config.coarser_levels {
            let level = self.cell_level(base, extra);
            let key = self.key(position, normal, level, corner);
            if let Some(slot) = self.table.find(&key) {
                let cell = &self.cells[slot as usize];
                if cell.weight > 0.0 {
                    return Vec3::from_array(cell.radiance);
                }
            }
        }
        Vec3::ZERO
    }

    /// Folds the frame's samples into the cells (α = max(1/frames, α_min)), clears the
    /// accumulators, advances the age counter and evicts cells idle for more than `max_age`
    /// frames. Returns the number of cells evicted.
    pub fn end_frame(&mut self) -> u32 {
        let alpha_min = self.config.accumulation;
        let max_weight = 1.0 / alpha_min;
        for (cell, acc) in self.cells.iter_mut().zip(self.accumulators.iter_mut()) {
            let count = core::mem::take(acc[3].get_mut());
            if count == 0 {
                continue;
            }
            let sum = Vec3::new(
                f32::from_bits(core::mem::take(acc[0].get_mut())),
                f32::from_bits(core::mem::take(acc[1].get_mut())),
                f32::from_bits(core::mem::take(acc[2].get_mut())),
            );
            let mean = sum / count as f32;
            if !mean.is_finite() {
                continue;
            }
            cell.weight = (cell.weight + 1.0).min(max_weight);
            let alpha = (1.0 / cell.weight).max(alpha_min);
            let old = Vec3::from_array(cell.radiance);
            cell.radiance = old.lerp(mean, alpha).to_array();
        }
        self.table.advance_frame();
        let cells = &mut self.cells;
        self.table.evict_older_than(self.config.max_age, |slot| {
            cells[slot as usize] = CacheCell::default()
        })
    }

    /// The cells in slot order, uploadable as they are (`bytemuck::cast_slice`), beside the
    /// table's checksum words ([`ConcurrentTable::checksums`] of [`table`](Self::table)).
    #[must_use]
    pub fn cells(&self) -> &[CacheCell] {
        &self.cells
    }

    /// The slot index.
    #[must_use]
    pub const fn table(&self) -> &ConcurrentTable {
        &self.table
    }
}

/// `word += value` on f32 bits, by compare-and-swap.
#[inline]
fn add_f32(word: &AtomicU32, value: f32) {
    let mut current = word.load(Ordering::Relaxed);
    loop {
        let next = (f32::from_bits(current) + value).to_bits();
        match word.compare_exchange_weak(current, next, Ordering::Relaxed, Ordering::Relaxed) {
            Ok(_) => return,
            Err(seen) => current = seen,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With `add_probability` p the decision and the corner come from one uniform: over a
    /// stratified grid of N uniforms exactly p·N add (p a power of two), their corners are
    /// the same grid stretched over [0, 1) (so uniform), and p = 1 adds every uniform at its
    /// own value.
    #[test]
    fn add_uniform_adds_the_share_p_with_uniform_corners() {
        const N: u32 = 4096;
        let grid = (0..N).map(|i| (i as f32 + 0.5) / N as f32);
        let all = CacheConfig::DEFAULT;
        assert!(grid.clone().all(|u| all.add_uniform(u) == Some(u)));
        let quarter = CacheConfig {
            add_probability: 0.25,
            ..CacheConfig::DEFAULT
        };
        let corners: Vec<f32> = grid.filter_map(|u| quarter.add_uniform(u)).collect();
        assert_eq!(corners.len() as u32, N / 4);
        for (i, c) in corners.iter().enumerate() {
            assert_eq!(*c, (i as f32 + 0.5) / (N / 4) as f32);
        }
    }

    #[test]
    fn probabilities_outside_the_unit_interval_are_rejected() {
        for p in [0.0, -0.5, 1.5, f32::NAN] {
            let c = CacheConfig {
                add_probability: p,
                ..CacheConfig::DEFAULT
            };
            assert!(matches!(
                c.validate(),
                Err(ParamsError::ProbabilityOutOfRange {
                    parameter: "cache.add_probability",
                    ..
                })
            ));
            assert!(IrradianceCache::new(AdaptiveGrid::default(), c).is_err());
        }
        assert!(CacheConfig::DEFAULT.validate().is_ok());
    }
}
