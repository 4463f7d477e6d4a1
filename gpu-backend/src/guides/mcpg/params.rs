//! The parameters `mcg::mcpg` reads (`McpgParams` in WGSL) and the layout of the guide's
//! buffers, both derived from the CPU guide's [`GuideConfig`].

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use mcg_hashgrid::{AdaptiveGrid, BucketHash, StaticGrid, TableError};
use mcg_markov_guide::mcpg::{CacheConfig, DiscardRule, GuideConfig, GuideError};

use crate::GpuError;
use crate::codes;
use crate::types::{HashgridLevelParams, HashgridTableParams, VmfFitParamsGpu};

/// The probe limit of every table of the guide (the CPU guide's `SharedGrid` and cache).
pub const MCPG_MAX_PROBES: u32 = 8;

/// Everything `mcg::mcpg` reads, WGSL `McpgParams` (uniform, 1 296 bytes): MCPG's constants,
/// the grids' geometry, the three tables' places in the hash words, where each array starts in
/// the guide's words, the camera, and every adaptive level's cell width (the CPU guide's own
/// table, so keys match bit for bit). Built by [`McpgGpuParams::new`] from the same
/// [`GuideConfig`] as the CPU guide.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct McpgGpuParams {
    /// N_mc.
    pub candidates: u32,
    /// p_adaptive.
    pub adaptive_probability: f32,
    /// p_bsdf.
    pub bsdf_probability: f32,
    /// The distance prior's scale.
    pub prior_scale: f32,
    /// The distance prior's floor.
    pub prior_min_weight: f32,
    /// The static grid's normal threshold.
    pub static_normal_threshold: f32,
    /// `codes::MCPG_DISCARD_*`.
    pub discard_rule: u32,
    /// The discard rule's estimate ratio.
    pub discard_ratio: f32,
    /// The MLE update's constants.
    pub fit: VmfFitParamsGpu,
    /// `codes::MCPG_HEMISPHERE_*`.
    pub hemisphere: u32,
    /// How far an escaped ray's virtual target lies.
    pub environment_distance: f32,
    /// The static grid's cell width.
    pub static_width: f32,
    /// 1 when states carry ages (`GuideConfig::max_state_age` is `Some`).
    pub age_tracking: u32,
    /// The camera position the adaptive levels follow.
    pub camera: Vec3,
    /// `GuideConfig::max_state_age` (0 without age tracking).
    pub max_state_age: u32,
    /// The adaptive grid's levels.
    pub levels: HashgridLevelParams,
    /// The adaptive grid's table in the hash words.
    pub adaptive_table: HashgridTableParams,
    /// The static grid's table in the hash words.
    pub static_table: HashgridTableParams,
    /// The irradiance cache's table in the hash words (zero without a cache).
    pub cache_table: HashgridTableParams,
    /// 1 with an irradiance cache.
    pub cache_enabled: u32,
    /// The cache's α_min.
    pub cache_accumulation: f32,
    /// Coarser levels a cache access tries after a miss or a full neighbourhood.
    pub cache_coarser_levels: u32,
    /// Levels the cache's cells are coarser than the states' target level.
    pub cache_level_bias: u32,
    /// Frames a cache cell may stay idle.
    pub cache_max_age: u32,
    /// 1/α_min, the cap on a cell's frame count (computed as the CPU computes it).
    pub cache_max_weight: f32,
    /// Word offset of the adaptive states (8 words per slot) in the guide's words.
    pub adaptive_states: u32,
    /// Word offset of the static states.
    pub static_states: u32,
    /// Word offset of the adaptive states' guard words (one per slot).
    pub adaptive_guards: u32,
    /// Word offset of the static states' guard words.
    pub static_guards: u32,
    /// Word offset of the cache cells (`CacheCell`, 4 words per slot).
    pub cache_cells: u32,
    /// Word offset of the cache's per-frame sums (R, G, B as f32 bits, count; 4 per slot).
    pub cache_sums: u32,
    /// 1/N_c of `McpgParams::confidence_samples` (the f32 reciprocal the CPU's
    /// `McpgParams::young_share` multiplies by), 0 for the paper's Alg. 2.
    pub confidence_inverse: f32,
    /// `CacheConfig::add_scale` (1/`add_probability`; 1 without a cache).
    pub cache_add_scale: f32,
    /// Padding to the 16-byte row of `widths`.
    pub _padding: [u32; 2],
    /// `AdaptiveGrid::width(level)` for levels 0..256, four per row.
    pub widths: [[f32; 4]; 64],
}
const _: () = assert!(size_of::<McpgGpuParams>() == 1296);

/// Sizes of the guide's two buffers, in `u32` words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct McpgBufferWords {
    /// `mcg_hashgrid_words`: the three tables' checksums and ages.
    pub table_words: u64,
    /// `mcpg_words`: the header, states, guards, cache cells and sums.
    pub guide_words: u64,
}

impl McpgGpuParams {
    /// The parameters of a guide built from `config`, validated as `Guide::new` validates it,
    /// the camera at the origin (as the CPU guide starts), and the sizes of its buffers.
    ///
    /// # Errors
    /// [`GpuError::Guide`] with the [`GuideError`] `Guide::new` would return (a capacity below
    /// 8 is [`TableError::MaxProbesAboveCapacity`]); [`GpuError::GuideTooLarge`] when a buffer
    /// holds more than `u32::MAX` words (the WGSL indexes them with `u32`).
    pub fn new(config: &GuideConfig) -> Result<(Self, McpgBufferWords), GpuError> {
        let (params, sizes) = Self::from_config(config).map_err(GpuError::Guide)?;
        let maximum = 4 * u64::from(u32::MAX);
        for words in [sizes.table_words, sizes.guide_words] {
            let bytes = 4 * words;
            if bytes > maximum {
                return Err(GpuError::GuideTooLarge { bytes, maximum });
            }
        }
        Ok((params, sizes))
    }

    /// [`McpgGpuParams::new`] before the size check: the offsets are computed in u64 and
    /// truncated to u32 (`new` rejects sizes whose offsets would not fit).
    fn from_config(config: &GuideConfig) -> Result<(Self, McpgBufferWords), GuideError> {
        let (adaptive, adaptive_table, static_table, cache) = Self::validated(config)?;
        let (ca, cs) = (config.adaptive_capacity, config.static_capacity);
        let cc = cache.map_or(0, |(c, _)| c.capacity);
        let (ca64, cs64, cc64) = (u64::from(ca), u64::from(cs), u64::from(cc));
        // Hash words: adaptive checksums and ages, static checksums and ages, the cache's.
        // Every offset is at most `table_words`, which `new` checks against `u32::MAX`.
        let words = |offset: u64| offset as u32;
        let adaptive_table = adaptive_table.at_offsets(0, ca);
        let static_table = static_table.at_offsets(words(2 * ca64), words(2 * ca64 + cs64));
        let table_words = 2 * (ca64 + cs64 + cc64);
        let cache_table = match cache {
            Some((_, t)) => t.at_offsets(words(2 * (ca64 + cs64)), words(2 * (ca64 + cs64) + cc64)),
            None => HashgridTableParams::default(),
        };
        // Guide words: header, states, guards, cache cells and sums. The states start at a
        // multiple of 4 words (header 4, 8 per state), as the shader's vec4 view of them needs.
        let header = u64::from(codes::MCPG_HEADER_WORDS);
        let adaptive_states = header;
        let static_states = adaptive_states + 8 * ca64;
        let adaptive_guards = static_states + 8 * cs64;
        let static_guards = adaptive_guards + ca64;
        let cache_cells = static_guards + cs64;
        let cache_sums = cache_cells + 4 * cc64;
        let guide_words = cache_sums + 4 * cc64;
        let mut widths = [[0.0; 4]; 64];
        for (level, w) in widths.iter_mut().flatten().enumerate() {
            *w = adaptive.width(level as u32);
        }
        let p = &config.params;
        let (DiscardRule::Paper { ratio } | DiscardRule::Engine { ratio }) = p.discard;
        let cache_config = cache.map(|(c, _)| c);
        let params = Self {
            candidates: p.candidates,
            adaptive_probability: p.adaptive_probability,
            bsdf_probability: p.bsdf_probability,
            prior_scale: p.prior_scale,
            prior_min_weight: p.prior_min_weight,
            static_normal_threshold: p.static_normal_threshold,
            discard_rule: codes::discard_rule(p.discard),
            discard_ratio: ratio,
            fit: VmfFitParamsGpu::from(&p.fit),
            hemisphere: codes::hemisphere(config.hemisphere),
            environment_distance: config.environment_distance,
            static_width: config.static_width,
            age_tracking: u32::from(config.max_state_age.is_some()),
            camera: Vec3::ZERO,
            max_state_age: config.max_state_age.unwrap_or(0),
            levels: HashgridLevelParams::from(&adaptive),
            adaptive_table,
            static_table,
            cache_table,
            cache_enabled: u32::from(cache.is_some()),
            cache_accumulation: cache_config.map_or(1.0, |c| c.accumulation),
            cache_coarser_levels: cache_config
                .map_or(0, |c| c.coarser_levels.min(adaptive.params().max_level)),
            cache_level_bias: cache_config
                .map_or(0, |c| c.level_bias.min(adaptive.params().max_level)),
            cache_max_age: cache_config.map_or(0, |c| c.max_age),
            cache_max_weight: cache_config.map_or(1.0, |c| 1.0 / c.accumulation),
            adaptive_states: adaptive_states as u32,
            static_states: static_states as u32,
            adaptive_guards: adaptive_guards as u32,
            static_guards: static_guards as u32,
            cache_cells: cache_cells as u32,
            cache_sums: cache_sums as u32,
            confidence_inverse: if p.confidence_samples > 0.0 {
                1.0 / p.confidence_samples
            } else {
                0.0
            },
            cache_add_scale: cache_config.map_or(1.0, |c| c.add_scale()),
            _padding: [0; 2],
            widths,
        };
        Ok((
            params,
            McpgBufferWords {
                table_words,
                guide_words,
            },
        ))
    }

    /// Validates `config` as `Guide::new` does; the adaptive grid, the tables' parameters
    /// (adaptive, static) and the cache's configuration and table.
    #[allow(clippy::type_complexity)]
    fn validated(
        config: &GuideConfig,
    ) -> Result<
        (
            AdaptiveGrid,
            HashgridTableParams,
            HashgridTableParams,
            Option<(CacheConfig, HashgridTableParams)>,
        ),
        GuideError,
    > {
        config.params.validate().map_err(GuideError::Params)?;
        if !(config.environment_distance > 0.0 && config.environment_distance.is_finite()) {
            return Err(GuideError::EnvironmentDistanceNotPositive {
                distance: config.environment_distance,
            });
        }
        let adaptive = AdaptiveGrid::new(config.adaptive).map_err(GuideError::Grid)?;
        StaticGrid::new(config.static_width).map_err(GuideError::Grid)?;
        let table = |capacity: u32| -> Result<HashgridTableParams, GuideError> {
            if capacity == 0 {
                return Err(GuideError::Table(TableError::CapacityZero));
            }
            if capacity < MCPG_MAX_PROBES {
                return Err(GuideError::Table(TableError::MaxProbesAboveCapacity {
                    max_probes: MCPG_MAX_PROBES,
                    capacity,
                }));
            }
            Ok(
                HashgridTableParams::new(capacity, MCPG_MAX_PROBES, BucketHash::default())
                    .expect("a non-zero capacity"),
            )
        };
        let adaptive_table = table(config.adaptive_capacity)?;
        let static_table = table(config.static_capacity)?;
        let cache = match config.cache {
            Some(c) => {
                c.validate().map_err(GuideError::Params)?;
                Some((c, table(c.capacity)?))
            }
            None => None,
        };
        Ok((adaptive, adaptive_table, static_table, cache))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The README's memory figure: `GuideConfig::PAPER` (2²⁰ + 2¹⁶ grid slots at 44 bytes,
    /// 2¹⁶ cache slots at 40, a 16-byte header) takes 51 642 384 bytes.
    /// Every state starts on a 16-byte boundary, where `mcpg_read_words` reads it as two
    /// `vec4<u32>`, whatever the capacities (odd ones included).
    #[test]
    fn states_start_on_vec4_boundaries() {
        for (adaptive, fixed) in [(1 << 20, 1 << 16), (4097, 1023), (12_345, 777)] {
            let mut c = GuideConfig::PAPER;
            c.adaptive_capacity = adaptive;
            c.static_capacity = fixed;
            let (p, _) = McpgGpuParams::new(&c).unwrap();
            assert_eq!(p.adaptive_states % 4, 0);
            assert_eq!(p.static_states % 4, 0);
        }
    }

    #[test]
    fn paper_configuration_takes_the_documented_memory() {
        let (_, sizes) = McpgGpuParams::new(&GuideConfig::PAPER).unwrap();
        let bytes = 4 * (sizes.table_words + sizes.guide_words);
        let slots = (1u64 << 20) + (1 << 16);
        assert_eq!(bytes, 44 * slots + 40 * (1 << 16) + 16);
        assert_eq!(bytes, 51_642_384);
    }

    #[test]
    fn invalid_configurations_are_rejected_as_the_cpu_guide_rejects_them() {
        let mut c = GuideConfig::PAPER;
        c.static_capacity = 4;
        assert_eq!(
            McpgGpuParams::new(&c).unwrap_err(),
            GpuError::Guide(GuideError::Table(TableError::MaxProbesAboveCapacity {
                max_probes: 8,
                capacity: 4
            }))
        );
        let mut c = GuideConfig::PAPER;
        c.environment_distance = f32::NAN;
        assert!(matches!(
            McpgGpuParams::new(&c).unwrap_err(),
            GpuError::Guide(GuideError::EnvironmentDistanceNotPositive { distance })
                if distance.is_nan()
        ));
        let mut c = GuideConfig::PAPER;
        c.cache = Some(CacheConfig {
            accumulation: 0.0,
            ..CacheConfig::DEFAULT
        });
        assert!(matches!(
            McpgGpuParams::new(&c).unwrap_err(),
            GpuError::Guide(GuideError::Params(_))
        ));
        let mut c = GuideConfig::PAPER;
        c.params.bsdf_probability = 2.0;
        assert!(mcg_markov_guide::mcpg::Guide::new(c).is_err());
        assert!(matches!(
            McpgGpuParams::new(&c).unwrap_err(),
            GpuError::Guide(GuideError::Params(_))
        ));
        // 2³¹ slots per grid: the hash words exceed u32 indices (was reported as a probe limit).
        let mut c = GuideConfig::PAPER;
        c.adaptive_capacity = 1 << 31;
        c.static_capacity = 1 << 31;
        assert!(matches!(
            McpgGpuParams::new(&c).unwrap_err(),
            GpuError::GuideTooLarge { bytes, maximum }
                if bytes > maximum && maximum == 4 * u64::from(u32::MAX)
        ));
    }
}
