//! The integer codes the WGSL modules and the host exchange for Rust enums (bucket hash,
//! insert outcome, rounding mode, prior decay, mean-cosine update), defined once here and
//! emitted into `mcg::constants`.

use mcg_color_codec::Rounding;
use mcg_hashgrid::{BucketHash, Insert};
use mcg_vmf::{MeanCosineUpdate, PriorDecay};

/// `HASHGRID_HASH_XOR_PRIMES`: [`BucketHash::XorPrimes`].
pub const HASH_XOR_PRIMES: u32 = 0;
/// `HASHGRID_HASH_MIX`: [`BucketHash::Mix`].
pub const HASH_MIX: u32 = 1;
/// `HASHGRID_HASH_MIX_COHERENT`: [`BucketHash::MixCoherent`].
pub const HASH_MIX_COHERENT: u32 = 2;
/// `HASHGRID_HASH_FOLD`: [`BucketHash::Fold`].
pub const HASH_FOLD: u32 = 3;
/// `HASHGRID_FOUND`: [`Insert::Found`].
pub const INSERT_FOUND: u32 = 0;
/// `HASHGRID_INSERTED`: [`Insert::Inserted`].
pub const INSERT_INSERTED: u32 = 1;
/// `HASHGRID_FULL`: [`Insert::Full`].
pub const INSERT_FULL: u32 = 2;
/// `HASHGRID_NO_SLOT`: the slot of a failed lookup or a full insert.
pub const NO_SLOT: u32 = u32::MAX;
/// `CODEC_ROUND_DOWN`: [`Rounding::Down`].
pub const ROUND_DOWN: u32 = 0;
/// `CODEC_ROUND_NEAREST`: [`Rounding::Nearest`].
pub const ROUND_NEAREST: u32 = 1;
/// `CODEC_ROUND_STOCHASTIC`: [`Rounding::Stochastic`].
pub const ROUND_STOCHASTIC: u32 = 2;
/// `VMF_PRIOR_DECAY_SQUARED_COUNT`: [`PriorDecay::SquaredCount`].
pub const PRIOR_DECAY_SQUARED_COUNT: u32 = 0;
/// `VMF_PRIOR_DECAY_COUNT`: [`PriorDecay::Count`].
pub const PRIOR_DECAY_COUNT: u32 = 1;
/// `VMF_MEAN_COSINE_RESULTANT`: [`MeanCosineUpdate::Resultant`].
pub const MEAN_COSINE_RESULTANT: u32 = 0;
/// `VMF_MEAN_COSINE_PROJECTED`: [`MeanCosineUpdate::Projected`].
pub const MEAN_COSINE_PROJECTED: u32 = 1;

// MCMM: score density and prior policy of `mcg::mcmm`, and its largest tile.
/// `MCMM_SCORE_TECHNIQUE`: [`ScoreDensity::Technique`](mcg_markov_guide::mcmm::ScoreDensity::Technique).
pub const MCMM_SCORE_TECHNIQUE: u32 = 0;
/// `MCMM_SCORE_TILE_MIXTURE`: [`ScoreDensity::TileMixture`](mcg_markov_guide::mcmm::ScoreDensity::TileMixture).
pub const MCMM_SCORE_TILE_MIXTURE: u32 = 1;
/// `MCMM_PRIOR_FIXED`: [`McmmPrior::Fixed`](mcg_markov_guide::mcmm::McmmPrior::Fixed).
pub const MCMM_PRIOR_FIXED: u32 = 0;
/// `MCMM_PRIOR_LIGHT_SIZE`: [`McmmPrior::LightSize`](mcg_markov_guide::mcmm::McmmPrior::LightSize).
pub const MCMM_PRIOR_LIGHT_SIZE: u32 = 1;

/// Every code with its WGSL name, for the constant generator.
pub const WGSL_CODES: &[(&str, u32)] = &[
    ("HASHGRID_HASH_XOR_PRIMES", HASH_XOR_PRIMES),
    ("HASHGRID_HASH_MIX", HASH_MIX),
    ("HASHGRID_HASH_MIX_COHERENT", HASH_MIX_COHERENT),
    ("HASHGRID_HASH_FOLD", HASH_FOLD),
    ("HASHGRID_FOUND", INSERT_FOUND),
    ("HASHGRID_INSERTED", INSERT_INSERTED),
    ("HASHGRID_FULL", INSERT_FULL),
    ("HASHGRID_NO_SLOT", NO_SLOT),
    ("CODEC_ROUND_DOWN", ROUND_DOWN),
    ("CODEC_ROUND_NEAREST", ROUND_NEAREST),
    ("CODEC_ROUND_STOCHASTIC", ROUND_STOCHASTIC),
    ("VMF_PRIOR_DECAY_SQUARED_COUNT", PRIOR_DECAY_SQUARED_COUNT),
    ("VMF_PRIOR_DECAY_COUNT", PRIOR_DECAY_COUNT),
    ("VMF_MEAN_COSINE_RESULTANT", MEAN_COSINE_RESULTANT),
    ("VMF_MEAN_COSINE_PROJECTED", MEAN_COSINE_PROJECTED),
    // MCMM
    ("MCMM_SCORE_TECHNIQUE", MCMM_SCORE_TECHNIQUE),
    ("MCMM_SCORE_TILE_MIXTURE", MCMM_SCORE_TILE_MIXTURE),
    ("MCMM_PRIOR_FIXED", MCMM_PRIOR_FIXED),
    ("MCMM_PRIOR_LIGHT_SIZE", MCMM_PRIOR_LIGHT_SIZE),
    ("MCMM_MAX_TILE_SIZE", mcg_smis::MAX_TILE_SIZE),
];

/// The code of a bucket hash.
#[must_use]
pub const fn bucket_hash(hash: BucketHash) -> u32 {
    match hash {
        BucketHash::XorPrimes => HASH_XOR_PRIMES,
        BucketHash::Mix => HASH_MIX,
        BucketHash::MixCoherent => HASH_MIX_COHERENT,
        BucketHash::Fold => HASH_FOLD,
    }
}

/// The insert outcome of a `(slot, code)` pair a kernel wrote, `None` for an unknown code.
#[must_use]
pub const fn insert(slot: u32, code: u32) -> Option<Insert> {
    match code {
        INSERT_FOUND => Some(Insert::Found(slot)),
        INSERT_INSERTED => Some(Insert::Inserted(slot)),
        INSERT_FULL => Some(Insert::Full),
        _ => None,
    }
}

/// The code and uniform of a rounding (`CodecRounding` in WGSL); the uniform is 0 unless
/// stochastic.
#[must_use]
pub const fn rounding(rounding: Rounding) -> (u32, f32) {
    match rounding {
        Rounding::Down => (ROUND_DOWN, 0.0),
        Rounding::Nearest => (ROUND_NEAREST, 0.0),
        Rounding::Stochastic(u) => (ROUND_STOCHASTIC, u),
    }
}

/// The code of a prior decay.
#[must_use]
pub const fn prior_decay(decay: PriorDecay) -> u32 {
    match decay {
        PriorDecay::SquaredCount => PRIOR_DECAY_SQUARED_COUNT,
        PriorDecay::Count => PRIOR_DECAY_COUNT,
    }
}

/// The code of a mean-cosine update.
#[must_use]
pub const fn mean_cosine_update(update: MeanCosineUpdate) -> u32 {
    match update {
        MeanCosineUpdate::Resultant => MEAN_COSINE_RESULTANT,
        MeanCosineUpdate::Projected => MEAN_COSINE_PROJECTED,
    }
}
