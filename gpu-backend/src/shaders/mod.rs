//! The WGSL shader library: one module per primitive, for your own shaders.
//!
//! Every module is a WGSL file with a naga_oil header, `#define_import_path mcg::<name>`, and
//! `#import` lines naming what it takes from the others. Use it either way:
//!
//! - **naga_oil** (feature `compose`, on by default): [`add_to_composer`] registers every module
//!   with your [`Composer`](naga_oil::compose::Composer); your shader then writes
//!   `#import mcg::vmf::{Vmf, vmf_sample_with_pdf}` like any Bevy-style import, and errors point
//!   at your own file and line.
//! - **Plain WGSL**: [`compose`] takes your shader with the same `#import` lines and returns
//!   plain WGSL for `wgpu::ShaderSource::Wgsl`: your code first, line for line (so error line
//!   numbers stay yours), then each module it needs exactly once, in dependency order, with only
//!   the constants they use. [`wgsl`] returns the library part alone for a set of modules.
//!
//! | module | what it holds | CPU twin |
//! |---|---|---|
//! | `mcg::constants` | every shared constant, generated from the CPU crates ([`constants`]) | the crates' `constants` |
//! | `mcg::math` | `mcg_rounded` (no FMA fusing), `mcg_is_finite` | — |
//! | `mcg::sampling` | `mcg_pcg_hash`, `mcg_uniform_float`, `mcg_rng_*`, `mcg_frame_to_world`, `mcg_cosine_hemisphere_sample` / `_pdf` | [`crate::sampling`], `mcg_vmf::Frame`, `mcg_markov_guide::cosine_hemisphere` |
//! | `mcg::vmf` | `Vmf`, `VmfSufficientStats`, pdf, sampling, mean cosine ↔ κ, statistics update, reconstruction with a MAP prior, product, convolution | `mcg_vmf` |
//! | `mcg::vmf_mixture` | `VmfMixture` with K = shader def `MCG_VMF_MIXTURE_K` (default 4) | `mcg_vmf::VmfMixture` |
//! | `mcg::hashgrid` | `HashgridCellKey`, `HashgridTable`, hashes, checksums, slots, stochastic trilinear and jittered vertices, levels, adaptive and static keys | `mcg_hashgrid` |
//! | `mcg::hashgrid_table` | `hashgrid_find`, `hashgrid_insert_or_get`, `hashgrid_touch`, eviction, on the shared array `mcg_hashgrid_words` | `HashTable`, `ConcurrentTable` |
//! | `mcg::color_codec` | R11G11B10, RGB9E5, gamma-5, the log codec, irradiance / visibility / heuristics words, moving average | `mcg_color_codec` |
//! | `mcg::color_codec_logluv` | LogLuv32 on the table array `mcg_codec_logluv_tables` | `LogLuv32` |
//! | `mcg::color_codec_texels` | the moving average as a compare-and-swap loop on `mcg_codec_texels` | `MovingAverage::update_atomic` |
//! | `mcg::markov` | `MarkovGridState` (MCPG) and `MarkovPixelState` (MCMM): read, pack, validity, prediction (MCPG eq. 10), lobe | `mcg_markov_guide::{mcpg, mcmm}` |
//! | `mcg::mcpg` | the whole MCPG guide: `mcpg_begin`, `mcpg_sample`, `mcpg_pdf`, `mcpg_finish`, the irradiance cache, the per-frame pass, on the group of [`defs::MCPG_GROUP`] (host: `GpuMcpgGuide`) | `mcg_markov_guide::mcpg::Guide` |
//! | `mcg::mcmm` | MCMM's pixel chains: `McmmParams` and the guide's bindings, Alg. 1 (B-spline offsets, motion, reservoir), Alg. 2 (technique, pdf, sample), Alg. 3 (`mcmm_update`), tile shuffles and the tile-mixture density through workgroup memory | `mcg_markov_guide::mcmm`, `mcg_smis::{CyclicShift, XorPermutation}` |
//! | `mcg::adgi` | ADGI's probe cache: texel words with the CAS moving average, `adgi_update_sample`, DDGI's `adgi_blend_texel`, `adgi_irradiance_at` with Chebyshev visibility, the clip-volume count reset, on the group of [`defs::ADGI_GROUP`] (host: `GpuProbeCache`) | `mcg_probe_cache::ProbeTexels` |
//! | `mcg::adgi_chains` | ADGI's guiding function `adgi_guiding_value` (eq. 2), the chain state `AdgiChainState`, `adgi_locate` (nearest probe, cell, octant), `adgi_propose` (Alg. 5 with `adgi_normal_quantile`), `adgi_fold_direction`, `adgi_uniform_state`, the counter-based `adgi_chain_uniforms` (host: `GpuProbeChains`), the pilot rays' `adgi_pilot_uniforms` (SplitMix64 `adgi_hash_uniform` on u64 as `vec2<u32>`, sec. 4.4; mcg-demo's `lay_out_pilot_rays`) | `mcg_probe_cache::{guiding_function, proxies, probe_chains}`, `mcg_probe_cache::probe_update::{hash_uniform, ProbeUpdater::pilot_uniforms}`, `mcg_markov_guide::RandomWalk` |
//! | `mcg::dispatch` | `mcg_invocation_index` of a [`GpuContext::dispatch`](crate::GpuContext::dispatch) | — |
//!
//! # Names
//! Every module-scope name starts with `mcg`, `vmf`, `hashgrid`, `codec`, `markov` or `mcmm` (in the
//! case of its kind: `vmf_pdf`, `Vmf`, `VMF_KAPPA_MAX`), so the library never clashes with
//! your code in plain WGSL either (a test scans every module).
//!
//! # Storage and shader defs
//! Three modules declare a storage binding, placed by shader defs you choose (naga_oil's
//! `shader_defs`, or the `defs` of [`compose`]): `mcg::hashgrid_table` (the defs of
//! [`defs::HASHGRID_GROUP`], [`defs::HASHGRID_BINDING`]), `mcg::color_codec_texels` and
//! `mcg::color_codec_logluv`. All hash tables of a shader share the one `mcg_hashgrid_words`
//! array; a `HashgridTable` descriptor (offset and capacity) picks the table, so an adaptive
//! grid, a static grid and an irradiance cache sit side by side in one buffer. `mcg::mcmm`
//! declares the MCMM guide's three bindings (parameters, previous and current states) at
//! bindings 0-2 of the group [`defs::MCMM_GROUP`] names (`GpuMcmmGuide` builds the matching
//! layout), and a workgroup array for its tile shuffles.
//!
//! # Example
//! ```
//! use mcg_gpu_backend::shaders::{self, defs};
//!
//! let my_shader = "\
//! #import mcg::vmf::{Vmf, vmf_pdf}
//! #import mcg::hashgrid_table::hashgrid_find
//!
//! @group(0) @binding(0) var<storage, read_write> out: array<f32>;
//!
//! @compute @workgroup_size(64)
//! fn main(@builtin(global_invocation_id) id: vec3<u32>) {
//!     out[id.x] = vmf_pdf(Vmf(vec3<f32>(0.0, 0.0, 1.0), 10.0), vec3<f32>(0.0, 0.0, 1.0));
//! }
//! ";
//! let wgsl = shaders::compose(my_shader, &[(defs::HASHGRID_GROUP, 0), (defs::HASHGRID_BINDING, 1)])?;
//! assert!(wgsl.starts_with("\n\n\n@group(0)")); // your lines keep their numbers
//! assert!(wgsl.contains("fn vmf_pdf(") && wgsl.contains("fn hashgrid_find("));
//! # Ok::<(), mcg_gpu_backend::shaders::ShaderError>(())
//! ```

pub mod constants;
mod plain;

pub use plain::{ShaderError, compose, wgsl};

/// The names of the shader defs the library reads.
pub mod defs {
    /// Bind group of `mcg_hashgrid_words` (`mcg::hashgrid_table`).
    pub const HASHGRID_GROUP: &str = "MCG_HASHGRID_GROUP";
    /// Binding of `mcg_hashgrid_words` (`mcg::hashgrid_table`).
    pub const HASHGRID_BINDING: &str = "MCG_HASHGRID_BINDING";
    /// Bind group of `mcg_codec_texels` (`mcg::color_codec_texels`).
    pub const CODEC_TEXELS_GROUP: &str = "MCG_CODEC_TEXELS_GROUP";
    /// Binding of `mcg_codec_texels` (`mcg::color_codec_texels`).
    pub const CODEC_TEXELS_BINDING: &str = "MCG_CODEC_TEXELS_BINDING";
    /// Bind group of `mcg_codec_logluv_tables` (`mcg::color_codec_logluv`).
    pub const CODEC_LOGLUV_GROUP: &str = "MCG_CODEC_LOGLUV_GROUP";
    /// Binding of `mcg_codec_logluv_tables` (`mcg::color_codec_logluv`).
    pub const CODEC_LOGLUV_BINDING: &str = "MCG_CODEC_LOGLUV_BINDING";
    /// Bind group of the MCPG guide (`mcg::mcpg`: parameters at binding 0, the hash words at
    /// binding 1 with [`HASHGRID_GROUP`] set to the same group and [`HASHGRID_BINDING`] to 1,
    /// the guide's words at binding 2). `GpuMcpgGuide::shader_defs` gives all three.
    pub const MCPG_GROUP: &str = "MCG_MCPG_GROUP";
    /// Bind group of ADGI's probe cache (`mcg::adgi`: parameters at binding 0, the texel words
    /// at binding 1 with [`CODEC_TEXELS_GROUP`] set to the same group and
    /// [`CODEC_TEXELS_BINDING`] to 1, the texel table at 2, DDGI's rays at 3).
    /// `GpuProbeCache::shader_defs` gives all three.
    pub const ADGI_GROUP: &str = "MCG_ADGI_GROUP";
    /// Set (any value) to make `mcg::adgi`'s query read float texels (RGBA32F irradiance and
    /// RG32F moments at bindings 4 and 5 of its group) instead of the packed words: DDGI's
    /// storage, the baseline of the benches.
    pub const ADGI_FLOAT_TEXELS: &str = "MCG_ADGI_FLOAT_TEXELS";
    /// K, the number of lobes of `VmfMixture` (`mcg::vmf_mixture`); 4 when not set.
    pub const VMF_MIXTURE_K: &str = "MCG_VMF_MIXTURE_K";
    /// Bind group of the MCMM guide's parameters and state buffers (`mcg::mcmm`, bindings 0-2).
    pub const MCMM_GROUP: &str = "MCG_MCMM_GROUP";
    /// Set (any value) to compile `mcg::mcmm`'s subgroup shuffles (`mcmm_subgroup_*`; the
    /// device needs wgpu's `SUBGROUP` feature).
    pub const MCMM_SUBGROUPS: &str = "MCG_MCMM_SUBGROUPS";
}

/// One module of the shader library.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Module {
    /// `mcg::constants`: the generated constants.
    Constants,
    /// `mcg::math`: float helpers of the bit-exact twins.
    Math,
    /// `mcg::sampling`: random numbers, frames, the cosine-weighted hemisphere.
    Sampling,
    /// `mcg::vmf`: von Mises-Fisher lobes.
    Vmf,
    /// `mcg::vmf_mixture`: K-lobe mixtures.
    VmfMixture,
    /// `mcg::hashgrid`: keys, hashes, vertices, levels.
    Hashgrid,
    /// `mcg::hashgrid_table`: lock-free tables and ages on `mcg_hashgrid_words`.
    HashgridTable,
    /// `mcg::color_codec`: packed colour words.
    ColorCodec,
    /// `mcg::color_codec_logluv`: LogLuv32.
    ColorCodecLogluv,
    /// `mcg::color_codec_texels`: the atomic moving average on `mcg_codec_texels`.
    ColorCodecTexels,
    /// `mcg::markov`: MCPG grid and MCMM pixel chain states.
    Markov,
    /// `mcg::dispatch`: the flat invocation index of this crate's dispatches.
    Dispatch,
    /// `mcg::mcpg`: the MCPG guide (MCPG Alg. 1-3, the irradiance cache, the per-frame pass).
    Mcpg,
    /// `mcg::mcmm`: MCMM's screen-space chains (Alg. 1-3) and tile shuffles.
    Mcmm,
    /// `mcg::adgi`: ADGI's probe cache (texels, per-sample update, DDGI's blend, the query).
    Adgi,
    /// `mcg::adgi_chains`: ADGI's guiding function and Metropolis probe chains.
    AdgiChains,
}

impl Module {
    /// Every module, each after the modules it imports.
    pub const ALL: [Module; 16] = [
        Module::Constants,
        Module::Math,
        Module::Dispatch,
        Module::Sampling,
        Module::Vmf,
        Module::VmfMixture,
        Module::Hashgrid,
        Module::HashgridTable,
        Module::ColorCodec,
        Module::ColorCodecLogluv,
        Module::ColorCodecTexels,
        Module::Markov,
        Module::Mcpg,
        Module::Mcmm,
        Module::Adgi,
        Module::AdgiChains,
    ];

    /// The naga_oil import path, e.g. `"mcg::vmf"`.
    #[must_use]
    pub const fn import_path(self) -> &'static str {
        match self {
            Module::Constants => "mcg::constants",
            Module::Math => "mcg::math",
            Module::Sampling => "mcg::sampling",
            Module::Vmf => "mcg::vmf",
            Module::VmfMixture => "mcg::vmf_mixture",
            Module::Hashgrid => "mcg::hashgrid",
            Module::HashgridTable => "mcg::hashgrid_table",
            Module::ColorCodec => "mcg::color_codec",
            Module::ColorCodecLogluv => "mcg::color_codec_logluv",
            Module::ColorCodecTexels => "mcg::color_codec_texels",
            Module::Markov => "mcg::markov",
            Module::Dispatch => "mcg::dispatch",
            Module::Mcpg => "mcg::mcpg",
            Module::Mcmm => "mcg::mcmm",
            Module::Adgi => "mcg::adgi",
            Module::AdgiChains => "mcg::adgi_chains",
        }
    }

    /// The module's file in this crate, as error messages name it, e.g. `"mcg/vmf.wgsl"`.
    #[must_use]
    pub const fn file_path(self) -> &'static str {
        match self {
            Module::Constants => "mcg/constants.wgsl",
            Module::Math => "mcg/math.wgsl",
            Module::Sampling => "mcg/sampling.wgsl",
            Module::Vmf => "mcg/vmf.wgsl",
            Module::VmfMixture => "mcg/vmf_mixture.wgsl",
            Module::Hashgrid => "mcg/hashgrid.wgsl",
            Module::HashgridTable => "mcg/hashgrid_table.wgsl",
            Module::ColorCodec => "mcg/color_codec.wgsl",
            Module::ColorCodecLogluv => "mcg/color_codec_logluv.wgsl",
            Module::ColorCodecTexels => "mcg/color_codec_texels.wgsl",
            Module::Markov => "mcg/markov.wgsl",
            Module::Dispatch => "mcg/dispatch.wgsl",
            Module::Mcpg => "mcg/mcpg.wgsl",
            Module::Mcmm => "mcg/mcmm.wgsl",
            Module::Adgi => "mcg/adgi.wgsl",
            Module::AdgiChains => "mcg/adgi_chains.wgsl",
        }
    }

    /// The module's naga_oil source (`src/shaders/<name>.wgsl`).
    #[must_use]
    pub const fn source(self) -> &'static str {
        match self {
            Module::Constants => include_str!("constants.wgsl"),
            Module::Math => include_str!("math.wgsl"),
            Module::Sampling => include_str!("sampling.wgsl"),
            Module::Vmf => include_str!("vmf.wgsl"),
            Module::VmfMixture => include_str!("vmf_mixture.wgsl"),
            Module::Hashgrid => include_str!("hashgrid.wgsl"),
            Module::HashgridTable => include_str!("hashgrid_table.wgsl"),
            Module::ColorCodec => include_str!("color_codec.wgsl"),
            Module::ColorCodecLogluv => include_str!("color_codec_logluv.wgsl"),
            Module::ColorCodecTexels => include_str!("color_codec_texels.wgsl"),
            Module::Markov => include_str!("markov.wgsl"),
            Module::Dispatch => include_str!("dispatch.wgsl"),
            Module::Mcpg => include_str!("../guides/mcpg/mcpg.wgsl"),
            Module::Mcmm => include_str!("../guides/mcmm/mcmm.wgsl"),
            Module::Adgi => include_str!("../guides/adgi/adgi.wgsl"),
            Module::AdgiChains => include_str!("../guides/adgi/adgi_chains.wgsl"),
        }
    }

    /// The shader defs the module reads (group and binding of its storage array, or K).
    #[must_use]
    pub const fn shader_defs(self) -> &'static [&'static str] {
        match self {
            Module::HashgridTable => &[defs::HASHGRID_GROUP, defs::HASHGRID_BINDING],
            Module::ColorCodecTexels => &[defs::CODEC_TEXELS_GROUP, defs::CODEC_TEXELS_BINDING],
            Module::ColorCodecLogluv => &[defs::CODEC_LOGLUV_GROUP, defs::CODEC_LOGLUV_BINDING],
            Module::VmfMixture => &[defs::VMF_MIXTURE_K],
            Module::Mcpg => &[defs::MCPG_GROUP],
            Module::Mcmm => &[defs::MCMM_GROUP, defs::MCMM_SUBGROUPS],
            Module::Adgi => &[
                defs::ADGI_GROUP,
                defs::CODEC_TEXELS_GROUP,
                defs::CODEC_TEXELS_BINDING,
                defs::ADGI_FLOAT_TEXELS,
            ],
            _ => &[],
        }
    }

    /// The module of an import path such as `mcg::vmf`, `None` for any other path.
    #[must_use]
    pub fn from_import_path(path: &str) -> Option<Module> {
        Module::ALL.into_iter().find(|m| m.import_path() == path)
    }

    /// The modules this one imports directly, from its `#import` lines.
    #[must_use]
    pub fn dependencies(self) -> Vec<Module> {
        plain::imports(self.source())
            .filter_map(|import| Module::from_import_path(&import.module))
            .fold(Vec::new(), |mut deps, m| {
                if !deps.contains(&m) {
                    deps.push(m);
                }
                deps
            })
    }
}

/// Registers every module of the library with a naga_oil composer, so shaders it composes can
/// `#import mcg::<name>::{…}`. Modules already registered are left as they are, so calling it
/// twice is harmless.
///
/// # Errors
/// The composer's error if a module fails to parse (a bug of this crate; the tests compose
/// every module).
///
/// # Example
/// ```
/// use naga_oil::compose::{Composer, NagaModuleDescriptor, ShaderDefValue};
///
/// let mut composer = Composer::default();
/// mcg_gpu_backend::shaders::add_to_composer(&mut composer)?;
/// let module = composer.make_naga_module(NagaModuleDescriptor {
///     source: "#import mcg::sampling::{mcg_cosine_hemisphere_sample, McgDirectionSample}
///         @group(0) @binding(0) var<storage, read_write> out: array<vec4<f32>>;
///         @compute @workgroup_size(64)
///         fn main(@builtin(global_invocation_id) id: vec3<u32>) {
///             let s = mcg_cosine_hemisphere_sample(vec3<f32>(0.0, 0.0, 1.0), vec2<f32>(0.3, 0.7));
///             out[id.x] = vec4<f32>(s.direction, s.pdf);
///         }",
///     file_path: "my_shader.wgsl",
///     ..Default::default()
/// })?;
/// assert_eq!(module.entry_points.len(), 1);
/// # Ok::<(), naga_oil::compose::ComposerError>(())
/// ```
#[cfg(feature = "compose")]
#[cfg_attr(docsrs, doc(cfg(feature = "compose")))]
// naga_oil's own error type, as its `Composer` methods return it.
#[allow(clippy::result_large_err)]
pub fn add_to_composer(
    composer: &mut naga_oil::compose::Composer,
) -> Result<(), naga_oil::compose::ComposerError> {
    for module in Module::ALL {
        if composer.contains_module(module.import_path()) {
            continue;
        }
        composer.add_composable_module(naga_oil::compose::ComposableModuleDescriptor {
            source: module.source(),
            file_path: module.file_path(),
            language: naga_oil::compose::ShaderLanguage::Wgsl,
            ..Default::default()
        })?;
    }
    Ok(())
}

/// The kernels this crate's host side runs (`src/shaders/kernels/*.wgsl`), as naga_oil sources
/// that import the library. [`compose`] turns one into plain WGSL with
/// [`KERNEL_DEFS`](kernels::KERNEL_DEFS).
pub mod kernels {
    /// The shader defs every kernel is composed with: the hash words at group 0 binding 1, the
    /// texels at binding 0, the LogLuv tables at binding 3.
    pub const KERNEL_DEFS: &[(&str, u32)] = &[
        (super::defs::HASHGRID_GROUP, 0),
        (super::defs::HASHGRID_BINDING, 1),
        (super::defs::CODEC_TEXELS_GROUP, 0),
        (super::defs::CODEC_TEXELS_BINDING, 0),
        (super::defs::CODEC_LOGLUV_GROUP, 0),
        (super::defs::CODEC_LOGLUV_BINDING, 3),
        (super::defs::MCPG_GROUP, 0),
        (super::defs::ADGI_GROUP, 0),
    ];
    /// Entry point `vmf_pdf_and_sample`: bindings `lobes`, `queries`, `pdfs`, `samples`.
    pub const VMF: &str = include_str!("kernels/vmf.wgsl");
    /// Entry point `vmf_stats`: bindings `stats`, `queries`, `results`.
    pub const VMF_STATS: &str = include_str!("kernels/vmf_stats.wgsl");
    /// Entry point `vmf_update`: bindings `stats`, `updates`, `fit`.
    pub const VMF_UPDATE: &str = include_str!("kernels/vmf_update.wgsl");
    /// Entry point `vmf_convolve_lobes`: bindings `lobes`, `params`, `convolved`, `kappas`.
    pub const VMF_CONVOLVE: &str = include_str!("kernels/vmf_convolve.wgsl");
    /// Entry point `vmf_mixture_eval` (K = 4): bindings `mixtures`, `queries`, `samples`,
    /// `choices`.
    pub const VMF_MIXTURE: &str = include_str!("kernels/vmf_mixture.wgsl");
    /// Entry point `hashgrid_hashes`: bindings `keys`, `hashes`, `levels`, `vertex_queries`,
    /// `vertex_keys`.
    pub const HASHGRID_KEYS: &str = include_str!("kernels/hashgrid_keys.wgsl");
    /// Entry point `hashgrid_vertices`: bindings `queries`, `static_keys`, `jittered`.
    pub const HASHGRID_VERTICES: &str = include_str!("kernels/hashgrid_vertices.wgsl");
    /// Entry points `hashgrid_insert`, `hashgrid_insert_serial`, `hashgrid_lookup`: bindings
    /// `table`, `mcg_hashgrid_words`, `keys`, `results`.
    pub const HASHGRID_TABLE: &str = include_str!("kernels/hashgrid_table.wgsl");
    /// Entry points `hashgrid_insert_touch`, `hashgrid_insert_touch_serial` (bindings `table`,
    /// `mcg_hashgrid_words`, `age_params`, `counter`, `keys`), `hashgrid_evict` (the first
    /// four) and `hashgrid_trim` (the first two).
    pub const HASHGRID_AGES: &str = include_str!("kernels/hashgrid_ages.wgsl");
    /// Entry point `codec_pack_unpack`: bindings `values`, `words`, `decoded`.
    pub const COLOR_CODEC: &str = include_str!("kernels/color_codec.wgsl");
    /// Entry point `codec_logluv`: bindings `values`, `packed`, `unpacked`,
    /// `mcg_codec_logluv_tables`.
    pub const COLOR_CODEC_LOGLUV: &str = include_str!("kernels/color_codec_logluv.wgsl");
    /// Entry point `codec_texel_updates`: bindings `mcg_codec_texels`, `updates`, `params`.
    pub const COLOR_CODEC_TEXELS: &str = include_str!("kernels/color_codec_texels.wgsl");
    /// Entry point `markov_grid_states`: bindings `states`, `velocities`, `stats`.
    pub const MARKOV_GUIDE: &str = include_str!("kernels/markov_guide.wgsl");
    /// Entry point `markov_pixel_states`: bindings `pixel_states`, `query`, `results`, `lobes`.
    pub const MARKOV_PIXEL: &str = include_str!("kernels/markov_pixel.wgsl");
    /// Entry point `markov_grid_write`: bindings `writes`, `grid_states`, `pixel_states`.
    pub const MARKOV_GRID_WRITE: &str = include_str!("kernels/markov_grid_write.wgsl");
    /// Entry point `markov_grid_queries`: bindings `states`, `query`, `results`, `predicted`,
    /// `lobes`.
    pub const MARKOV_GRID_QUERY: &str = include_str!("kernels/markov_grid_query.wgsl");

    /// Entry points `mcpg_fold_cache`, `mcpg_evict`, `mcpg_trim`, `mcpg_next_frame`: the GPU
    /// MCPG guide's per-frame pass, the guide's group at group 0 (run by `GpuMcpgGuide` with
    /// the guide's own layout, so not in [`ALL`], whose kernels `GpuContext::dispatch` runs).
    pub const MCPG_MAINTENANCE: &str = include_str!("../guides/mcpg/maintenance.wgsl");

    /// Entry points `adgi_update_samples`, `adgi_blend`, `adgi_query`, `adgi_clip_reset`: the
    /// steps of `GpuProbeCache`, the cache's group at group 0 and the step's inputs at group 1
    /// (run with the cache's own layouts, so not in [`ALL`]).
    pub const ADGI_STEPS: &str = include_str!("../guides/adgi/kernels.wgsl");

    /// Entry points `adgi_guide_table`, `adgi_guide_values`, `adgi_chain_frame`: the steps of
    /// `GpuProbeChains` on the chains' group at group 0 (run with its layout, so not in
    /// [`ALL`]).
    pub const ADGI_CHAINS: &str = include_str!("../guides/adgi/chains.wgsl");

    /// Entry point `adgi_smooth_axis`: one axis of the triggers' smoothing
    /// (`GpuProbeCache::record_smoothing`), the cache's group at group 0 and the pass at
    /// group 1 (not in [`ALL`]).
    pub const ADGI_SMOOTHING: &str = include_str!("../guides/adgi/smoothing.wgsl");

    /// Entry point `adgi_octant_feedback`: the feedback ĝ of ADGI eq. 2 per probe and octant
    /// from the irradiance words (`GpuProbeChains::record_feedback`), the cache's group at
    /// group 0 and the chains' feedback table at group 1 (not in [`ALL`]).
    pub const ADGI_FEEDBACK: &str = include_str!("../guides/adgi/feedback.wgsl");

    /// Entry point `adgi_compose_heuristics`: the heuristics words of ADGI sec. 4.1-4.3
    /// (`GpuTriggerSmoothing::record_compose`), the cache's group at group 0 and the
    /// composition's inputs at group 1 (not in [`ALL`]).
    pub const ADGI_COMPOSE: &str = include_str!("../guides/adgi/compose.wgsl");

    /// Every kernel with its name and entry points, for validation loops.
    pub const ALL: &[(&str, &str, &[&str])] = &[
        ("vmf", VMF, &["vmf_pdf_and_sample"]),
        ("vmf_stats", VMF_STATS, &["vmf_stats"]),
        ("vmf_update", VMF_UPDATE, &["vmf_update"]),
        ("vmf_convolve", VMF_CONVOLVE, &["vmf_convolve_lobes"]),
        ("vmf_mixture", VMF_MIXTURE, &["vmf_mixture_eval"]),
        ("hashgrid_keys", HASHGRID_KEYS, &["hashgrid_hashes"]),
        (
            "hashgrid_vertices",
            HASHGRID_VERTICES,
            &["hashgrid_vertices"],
        ),
        (
            "hashgrid_table",
            HASHGRID_TABLE,
            &[
                "hashgrid_insert",
                "hashgrid_insert_serial",
                "hashgrid_lookup",
            ],
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
        ("color_codec", COLOR_CODEC, &["codec_pack_unpack"]),
        ("color_codec_logluv", COLOR_CODEC_LOGLUV, &["codec_logluv"]),
        (
            "color_codec_texels",
            COLOR_CODEC_TEXELS,
            &["codec_texel_updates"],
        ),
        ("markov_guide", MARKOV_GUIDE, &["markov_grid_states"]),
        ("markov_pixel", MARKOV_PIXEL, &["markov_pixel_states"]),
        (
            "markov_grid_write",
            MARKOV_GRID_WRITE,
            &["markov_grid_write"],
        ),
        (
            "markov_grid_query",
            MARKOV_GRID_QUERY,
            &["markov_grid_queries"],
        ),
    ];

    /// A kernel as plain WGSL (composed with [`KERNEL_DEFS`]).
    ///
    /// # Panics
    /// If the kernel does not compose, a bug of this crate that the tests catch.
    #[must_use]
    pub fn plain(source: &str) -> String {
        super::compose(source, KERNEL_DEFS).expect("the crate's kernels compose")
    }
}
