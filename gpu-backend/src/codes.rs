//! The integer codes the WGSL modules and the host exchange for Rust enums (bucket hash,
//! insert outcome, rounding mode, prior decay, mean-cosine update), defined once here and
//! emitted into `mcg::constants`.

use mcg_color_codec::Rounding;
use mcg_hashgrid::{BucketHash, Insert};
#[cfg(doc)]
use mcg_markov_guide::mcpg::Traced;
use mcg_markov_guide::mcpg::{DiscardRule, Hemisphere, Transition};
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

/// `MCPG_NO_LOBE`: the scatter (BSDF or phase-function) technique of `mcg::mcpg`'s samples
/// (`GuidedSample::lobe` = `None`).
pub const MCPG_NO_LOBE: u32 = u32::MAX;
/// `MCPG_SCATTER_LAMBERTIAN`: the cosine hemisphere about the vertex normal
/// (`mcg_markov_guide::mcpg::Lambertian`).
pub const MCPG_SCATTER_LAMBERTIAN: u32 = 0;
/// `MCPG_SCATTER_ISOTROPIC`: the isotropic phase function (`IsotropicPhase`).
pub const MCPG_SCATTER_ISOTROPIC: u32 = 1;
/// `MCPG_SCATTER_CUSTOM`: the renderer's own scattering (it samples and evaluates it itself).
pub const MCPG_SCATTER_CUSTOM: u32 = 2;
/// `MCPG_HEMISPHERE_SPHERE`: [`Hemisphere::Sphere`].
pub const MCPG_HEMISPHERE_SPHERE: u32 = 0;
/// `MCPG_HEMISPHERE_COSINE_PRODUCT`: [`Hemisphere::CosineProduct`].
pub const MCPG_HEMISPHERE_COSINE_PRODUCT: u32 = 1;
/// `MCPG_DISCARD_PAPER`: [`DiscardRule::Paper`].
pub const MCPG_DISCARD_PAPER: u32 = 0;
/// `MCPG_DISCARD_ENGINE`: [`DiscardRule::Engine`].
pub const MCPG_DISCARD_ENGINE: u32 = 1;
/// `MCPG_TRACED_HIT`: [`Traced::Hit`].
pub const MCPG_TRACED_HIT: u32 = 0;
/// `MCPG_TRACED_ESCAPED`: [`Traced::Escaped`].
pub const MCPG_TRACED_ESCAPED: u32 = 1;
/// `MCPG_TRANSITION_STORED`: [`Transition::Stored`].
pub const MCPG_TRANSITION_STORED: u32 = 0;
/// `MCPG_TRANSITION_DROPPED`: [`Transition::Dropped`].
pub const MCPG_TRANSITION_DROPPED: u32 = 1;
/// `MCPG_TRANSITION_REJECTED`: [`Transition::Rejected`].
pub const MCPG_TRANSITION_REJECTED: u32 = 2;
/// `MCPG_TRANSITION_DISCARDED`: [`Transition::Discarded`].
pub const MCPG_TRANSITION_DISCARDED: u32 = 3;
/// `MCPG_GUARD_LOCKED`: a state slot's guard word while a writer is inside (0 is the empty
/// state's stamp; stamps of other states start at `MCPG_GUARD_FIRST_STAMP`).
pub const MCPG_GUARD_LOCKED: u32 = 1;
/// `MCPG_GUARD_FIRST_STAMP`: the smallest stamp of a non-empty state.
pub const MCPG_GUARD_FIRST_STAMP: u32 = 2;
/// `MCPG_FRAME_WORD`: the index of the frame counter in the guide's words (`mcpg_words`).
pub const MCPG_FRAME_WORD: u32 = 0;
/// `MCPG_HEADER_WORDS`: words before the guide's first array in `mcpg_words`.
pub const MCPG_HEADER_WORDS: u32 = 4;
/// `MCPG_MAX_CANDIDATES`: [`mcg_markov_guide::mcpg::MAX_CANDIDATES`].
pub const MCPG_MAX_CANDIDATES: u32 = mcg_markov_guide::mcpg::MAX_CANDIDATES as u32;
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
    ("MCPG_NO_LOBE", MCPG_NO_LOBE),
    ("MCPG_SCATTER_LAMBERTIAN", MCPG_SCATTER_LAMBERTIAN),
    ("MCPG_SCATTER_ISOTROPIC", MCPG_SCATTER_ISOTROPIC),
    ("MCPG_SCATTER_CUSTOM", MCPG_SCATTER_CUSTOM),
    ("MCPG_HEMISPHERE_SPHERE", MCPG_HEMISPHERE_SPHERE),
    (
        "MCPG_HEMISPHERE_COSINE_PRODUCT",
        MCPG_HEMISPHERE_COSINE_PRODUCT,
    ),
    ("MCPG_DISCARD_PAPER", MCPG_DISCARD_PAPER),
    ("MCPG_DISCARD_ENGINE", MCPG_DISCARD_ENGINE),
    ("MCPG_TRACED_HIT", MCPG_TRACED_HIT),
    ("MCPG_TRACED_ESCAPED", MCPG_TRACED_ESCAPED),
    ("MCPG_TRANSITION_STORED", MCPG_TRANSITION_STORED),
    ("MCPG_TRANSITION_DROPPED", MCPG_TRANSITION_DROPPED),
    ("MCPG_TRANSITION_REJECTED", MCPG_TRANSITION_REJECTED),
    ("MCPG_TRANSITION_DISCARDED", MCPG_TRANSITION_DISCARDED),
    ("MCPG_GUARD_LOCKED", MCPG_GUARD_LOCKED),
    ("MCPG_GUARD_FIRST_STAMP", MCPG_GUARD_FIRST_STAMP),
    ("MCPG_FRAME_WORD", MCPG_FRAME_WORD),
    ("MCPG_HEADER_WORDS", MCPG_HEADER_WORDS),
    ("MCPG_MAX_CANDIDATES", MCPG_MAX_CANDIDATES),
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

/// The code of a hemisphere mode.
#[must_use]
pub const fn hemisphere(hemisphere: Hemisphere) -> u32 {
    match hemisphere {
        Hemisphere::Sphere => MCPG_HEMISPHERE_SPHERE,
        Hemisphere::CosineProduct => MCPG_HEMISPHERE_COSINE_PRODUCT,
    }
}

/// The code of a discard rule.
#[must_use]
pub const fn discard_rule(rule: DiscardRule) -> u32 {
    match rule {
        DiscardRule::Paper { .. } => MCPG_DISCARD_PAPER,
        DiscardRule::Engine { .. } => MCPG_DISCARD_ENGINE,
    }
}

/// The transition of a code `mcpg_finish` returned, `None` for an unknown code.
#[must_use]
pub const fn transition(code: u32) -> Option<Transition> {
    match code {
        MCPG_TRANSITION_STORED => Some(Transition::Stored),
        MCPG_TRANSITION_DROPPED => Some(Transition::Dropped),
        MCPG_TRANSITION_REJECTED => Some(Transition::Rejected),
        MCPG_TRANSITION_DISCARDED => Some(Transition::Discarded),
        _ => None,
    }
}
