//! WGSL sources: the generated prelude, one library module per primitive, and the kernels
//! this crate's host side runs, each as a `&'static str`.
//!
//! A library module needs the prelude (and nothing else), so a renderer includes
//! `PRELUDE` + the modules it wants + its own code, or one of the composed `*_MODULE`
//! constants + its own code:
//!
//! | constant | what it holds |
//! |---|---|
//! | [`PRELUDE`] | generated `const` declarations of every shared constant ([`crate::prelude`]) |
//! | [`COMMON`] | `mcg_invocation_index`, the flat index of a [`GpuContext::dispatch`](crate::GpuContext::dispatch) |
//! | [`VMF`] | `Vmf`, `SufficientStats`, `vmf_pdf`, `vmf_sample`, `vmf_sample_with_pdf`, `vmf_stats_update`, `vmf_from_sufficient_stats`, `vmf_product`, `vmf_convolve`, mean cosine ↔ κ (Banerjee and exact) |
//! | [`HASHGRID`] | `CellKey`, hashes, checksum, slot index, stochastic trilinear and jittered vertices, level choice, adaptive and static-grid keys |
//! | [`HASHGRID_TABLE`] | `hashgrid_find`, `hashgrid_insert_or_get` on `hashgrid_checksums` |
//! | [`HASHGRID_AGES`] | the age counter: `hashgrid_touch`, eviction of stale cells in two passes |
//! | [`VMF_MIXTURE`] | `VmfMixture` (K from the includer), pdf, component choice reusing one uniform, sampling |
//! | [`COLOR_CODEC`] | R11G11B10, RGB9E5, gamma-5 R10G10B10A2, the log codec (ADGI eq. 21) with round-down / nearest / stochastic rounding, the 9/9/8 + 6 irradiance, 13/13 + 6 visibility and 6/10/10 + 6 heuristics words, the moving-average update |
//! | [`MARKOV_GUIDE`] | the MCPG `GridState`: velocity (three f16), count, sufficient statistics; the MCMM `PixelState`: validity, resampling score, lobe |
//! | [`COLOR_CODEC_LOGLUV`] | LogLuv32 encode and decode (XYZ and linear sRGB), bit-exact, with the step tables in the includer's `codec_logluv_tables` |
//! | [`COLOR_CODEC_TEXELS`] | `codec_irradiance_update_atomic`, `codec_visibility_update_atomic`: the update as a compare-and-swap loop on `codec_texels` |
//!
//! Names are prefixed by module (`vmf_`, `hashgrid_`, `codec_`; constants `VMF_`, `HASHGRID_`,
//! `CODEC_`/layout names of mcg-color-codec, `MCG_`), so modules compose without clashes.
//! WGSL resolves module-scope names in any order, so a module may come before or after the
//! code that uses it. The table functions of [`HASHGRID_TABLE`] read a storage array the includer
//! declares as `hashgrid_checksums: array<atomic<u32>>` (see the module's header).

/// The generated constant prelude, `src/wgsl/generated/prelude.wgsl` (see [`crate::prelude`]).
pub const PRELUDE: &str = include_str!("wgsl/generated/prelude.wgsl");
/// Helpers shared by kernels: `mcg_invocation_index`.
pub const COMMON: &str = include_str!("wgsl/common.wgsl");
/// The mcg-vmf twin, `src/wgsl/vmf.wgsl`.
pub const VMF: &str = include_str!("wgsl/vmf.wgsl");
/// The mcg-hashgrid twin, `src/wgsl/hashgrid.wgsl`.
pub const HASHGRID: &str = include_str!("wgsl/hashgrid.wgsl");
/// The mcg-hashgrid table twin, `src/wgsl/hashgrid_table.wgsl`: `hashgrid_find` and
/// `hashgrid_insert_or_get` on a `hashgrid_checksums: array<atomic<u32>>` the includer
/// declares. Needs [`PRELUDE`] and [`HASHGRID`].
pub const HASHGRID_TABLE: &str = include_str!("wgsl/hashgrid_table.wgsl");
/// The mcg-hashgrid age-counter twin, `src/wgsl/hashgrid_ages.wgsl`: `hashgrid_touch`,
/// `hashgrid_evict_slot`, `hashgrid_trim_slot` on the includer's `hashgrid_checksums` and
/// `hashgrid_ages: array<atomic<u32>>`. Needs [`PRELUDE`], [`HASHGRID`] and
/// [`HASHGRID_TABLE`].
pub const HASHGRID_AGES: &str = include_str!("wgsl/hashgrid_ages.wgsl");
/// The `VmfMixture<K>` twin, `src/wgsl/vmf_mixture.wgsl`: `VmfMixture`, `vmf_mixture_pdf`,
/// `vmf_mixture_select`, `vmf_mixture_sample`, `vmf_mixture_sample_with_pdf`, with K from the
/// includer's `const VMF_MIXTURE_K: u32`. Needs [`PRELUDE`] and [`VMF`]; upload mixtures with
/// [`pack_mixtures`](crate::types::pack_mixtures).
pub const VMF_MIXTURE: &str = include_str!("wgsl/vmf_mixture.wgsl");
/// The mcg-color-codec twin, `src/wgsl/color_codec.wgsl`.
pub const COLOR_CODEC: &str = include_str!("wgsl/color_codec.wgsl");

/// The mcg-color-codec LogLuv32 twin, `src/wgsl/color_codec_logluv.wgsl`:
/// `codec_logluv32_pack_xyz`, `codec_logluv32_unpack_xyz`, `codec_logluv32_pack`,
/// `codec_logluv32_unpack`, bit for bit with `LogLuv32`. Needs [`PRELUDE`] and
/// [`COLOR_CODEC`], and the includer's `codec_logluv_tables: array<f32>` holding
/// [`prelude::logluv_tables`](crate::prelude::logluv_tables).
pub const COLOR_CODEC_LOGLUV: &str = include_str!("wgsl/color_codec_logluv.wgsl");

/// The mcg-color-codec texel twin, `src/wgsl/color_codec_texels.wgsl`:
/// `codec_irradiance_update_atomic` and `codec_visibility_update_atomic`, the moving-average
/// update as a compare-and-swap loop on a
/// `codec_texels: array<atomic<u32>>` the includer declares. Needs [`PRELUDE`] and
/// [`COLOR_CODEC`].
pub const COLOR_CODEC_TEXELS: &str = include_str!("wgsl/color_codec_texels.wgsl");

/// The mcg-markov-guide twin, `src/wgsl/markov_guide.wgsl`: the MCPG `GridState` (32 bytes)
/// with its velocity, count and sufficient statistics. Needs [`PRELUDE`] and [`VMF`].
pub const MARKOV_GUIDE: &str = include_str!("wgsl/markov_guide.wgsl");

/// [`PRELUDE`] + [`COMMON`] + [`VMF`]: a complete module to append your own code to.
pub const VMF_MODULE: &str = concat!(
    include_str!("wgsl/generated/prelude.wgsl"),
    include_str!("wgsl/common.wgsl"),
    include_str!("wgsl/vmf.wgsl"),
);
/// [`PRELUDE`] + [`COMMON`] + [`HASHGRID`] (without the table functions).
pub const HASHGRID_MODULE: &str = concat!(
    include_str!("wgsl/generated/prelude.wgsl"),
    include_str!("wgsl/common.wgsl"),
    include_str!("wgsl/hashgrid.wgsl"),
);
/// [`PRELUDE`] + [`COMMON`] + [`COLOR_CODEC`].
pub const COLOR_CODEC_MODULE: &str = concat!(
    include_str!("wgsl/generated/prelude.wgsl"),
    include_str!("wgsl/common.wgsl"),
    include_str!("wgsl/color_codec.wgsl"),
);

/// The complete kernel modules run by [`crate::kernels`] and the parity tests: a composed
/// library module followed by `src/wgsl/kernels/<name>.wgsl`.
pub mod kernels {
    /// Entry point `vmf_pdf_and_sample`: bindings `lobes`, `queries`, `pdfs`, `samples`.
    pub const VMF: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/vmf.wgsl"),
        include_str!("wgsl/kernels/vmf.wgsl"),
    );
    /// Entry point `vmf_stats`: bindings `stats`, `queries`, `results`.
    pub const VMF_STATS: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/vmf.wgsl"),
        include_str!("wgsl/kernels/vmf_stats.wgsl"),
    );
    /// Entry point `vmf_update`: bindings `stats`, `updates`, `fit`.
    pub const VMF_UPDATE: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/vmf.wgsl"),
        include_str!("wgsl/kernels/vmf_update.wgsl"),
    );
    /// Entry point `hashgrid_hashes`: bindings `keys`, `hashes`, `levels`, `vertex_queries`,
    /// `vertex_keys`.
    pub const HASHGRID_KEYS: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/hashgrid.wgsl"),
        include_str!("wgsl/kernels/hashgrid_keys.wgsl"),
    );
    /// Entry points `hashgrid_insert`, `hashgrid_insert_serial`, `hashgrid_lookup`: bindings
    /// `table`, `hashgrid_checksums`, `keys`, `results`.
    pub const HASHGRID_TABLE: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/hashgrid.wgsl"),
        include_str!("wgsl/hashgrid_table.wgsl"),
        include_str!("wgsl/kernels/hashgrid_table.wgsl"),
    );
    /// Entry point `codec_pack_unpack`: bindings `values`, `words`, `decoded`.
    pub const COLOR_CODEC: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/color_codec.wgsl"),
        include_str!("wgsl/kernels/color_codec.wgsl"),
    );

    /// Entry point `codec_logluv`: bindings `values`, `packed`, `unpacked`,
    /// `codec_logluv_tables`.
    pub const COLOR_CODEC_LOGLUV: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/color_codec.wgsl"),
        include_str!("wgsl/color_codec_logluv.wgsl"),
        include_str!("wgsl/kernels/color_codec_logluv.wgsl"),
    );

    /// Entry point `codec_texel_updates`: bindings `codec_texels`, `updates`, `params`.
    pub const COLOR_CODEC_TEXELS: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/color_codec.wgsl"),
        include_str!("wgsl/color_codec_texels.wgsl"),
        include_str!("wgsl/kernels/color_codec_texels.wgsl"),
    );

    /// Entry point `markov_grid_states`: bindings `states`, `velocities`, `stats`.
    pub const MARKOV_GUIDE: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/vmf.wgsl"),
        include_str!("wgsl/markov_guide.wgsl"),
        include_str!("wgsl/kernels/markov_guide.wgsl"),
    );

    /// Entry point `vmf_mixture_eval` (K = 4): bindings `mixtures`, `queries`, `samples`,
    /// `choices`.
    pub const VMF_MIXTURE: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/vmf.wgsl"),
        include_str!("wgsl/vmf_mixture.wgsl"),
        include_str!("wgsl/kernels/vmf_mixture.wgsl"),
    );
    /// Entry point `vmf_convolve_lobes`: bindings `lobes`, `params`, `convolved`, `kappas`.
    pub const VMF_CONVOLVE: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/vmf.wgsl"),
        include_str!("wgsl/kernels/vmf_convolve.wgsl"),
    );
    /// Entry point `hashgrid_vertices`: bindings `queries`, `static_keys`, `jittered`.
    pub const HASHGRID_VERTICES: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/hashgrid.wgsl"),
        include_str!("wgsl/kernels/hashgrid_vertices.wgsl"),
    );
    /// Entry points `hashgrid_insert_touch`, `hashgrid_insert_touch_serial` (bindings `table`,
    /// `hashgrid_checksums`, `hashgrid_ages`, `age_params`, `counter`, `keys`),
    /// `hashgrid_evict` (the first five) and `hashgrid_trim` (the first two).
    pub const HASHGRID_AGES: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/hashgrid.wgsl"),
        include_str!("wgsl/hashgrid_table.wgsl"),
        include_str!("wgsl/hashgrid_ages.wgsl"),
        include_str!("wgsl/kernels/hashgrid_ages.wgsl"),
    );
    /// Entry point `markov_pixel_states`: bindings `pixel_states`, `query`, `results`, `lobes`.
    pub const MARKOV_PIXEL: &str = concat!(
        include_str!("wgsl/generated/prelude.wgsl"),
        include_str!("wgsl/common.wgsl"),
        include_str!("wgsl/vmf.wgsl"),
        include_str!("wgsl/markov_guide.wgsl"),
        include_str!("wgsl/kernels/markov_pixel.wgsl"),
    );

    /// Every kernel module with its entry points, for validation loops.
    pub const ALL: &[(&str, &str, &[&str])] = &[
        ("vmf", VMF, &["vmf_pdf_and_sample"]),
        ("vmf_stats", VMF_STATS, &["vmf_stats"]),
        ("vmf_update", VMF_UPDATE, &["vmf_update"]),
        ("hashgrid_keys", HASHGRID_KEYS, &["hashgrid_hashes"]),
        (
            "hashgrid_table",
            HASHGRID_TABLE,
            &[
                "hashgrid_insert",
                "hashgrid_insert_serial",
                "hashgrid_lookup",
            ],
        ),
        ("color_codec", COLOR_CODEC, &["codec_pack_unpack"]),
        ("color_codec_logluv", COLOR_CODEC_LOGLUV, &["codec_logluv"]),
        ("markov_guide", MARKOV_GUIDE, &["markov_grid_states"]),
        (
            "color_codec_texels",
            COLOR_CODEC_TEXELS,
            &["codec_texel_updates"],
        ),
        ("vmf_mixture", VMF_MIXTURE, &["vmf_mixture_eval"]),
        ("vmf_convolve", VMF_CONVOLVE, &["vmf_convolve_lobes"]),
        (
            "hashgrid_vertices",
            HASHGRID_VERTICES,
            &["hashgrid_vertices"],
        ),
        (
            "hashgrid_ages",
            HASHGRID_AGES,
            &[
                "hashgrid_insert_touch",
                "hashgrid_insert_touch_serial",
                "hashgrid_evict",
                "hashgrid_trim",
            ],
        ),
        ("markov_pixel", MARKOV_PIXEL, &["markov_pixel_states"]),
    ];
}
