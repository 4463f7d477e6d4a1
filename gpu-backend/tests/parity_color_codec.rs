//! CPU/GPU parity of `mcg::color_codec`, `mcg::color_codec_texels` and `mcg::color_codec_logluv`:
//! packed words bit for bit, racing texel updates, LogLuv32.
//!
//! Runs on whatever wgpu adapter exists (lavapipe in CI); every test skips with a printed
//! reason when there is no adapter, and fails instead when `MCG_REQUIRE_GPU=1` (CI sets it).
//! Hashes, checksums, table outcomes, packed words and states must match bit for bit; the
//! vMF lobes go through `exp` and `log`, which WGSL only bounds loosely, so they are compared
//! within tolerances derived from WGSL's precision rules (see `common::tolerance`).

use glam::{Vec2, Vec3};
use mcg_gpu_backend::shaders::constants as prelude;
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_gpu_backend::types::{TexelParams, TexelUpdate};
use mcg_gpu_backend::{CodecKernels, GpuTexels};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

mod common;
use common::gpu_and_rng;

/// R11G11B10, RGB9E5, gamma-5 R10G10B10A2, and the ADGI irradiance (log codec with
/// round-down, nearest and stochastic rounding; count field), visibility and heuristics
/// words bit for bit, and their decoded values exactly (the heuristics' fractions within
/// [`decoded_close`]'s 4 ULP: a division), on 50 000 colours over 2⁻³⁰..2¹⁷ (log-uniform),
/// negatives, zeros, overflow, infinities, NaN (as 0: tested on the bits; with the guards
/// written as a no-NaN driver may rewrite them, e.g. `v_in <= 0.0` for the ufloat's
/// `!(v_in > 0.0)`, the NaN colours failed) and the rounding ties of the float formats. Broken once on purpose
/// (round-half-up instead of half-even in the WGSL ufloat): failed.
#[test]
fn packed_colour_words_match_the_cpu_bit_for_bit() {
    let Some(ctx) = gpu_or_skip("packed_colour_words_match_the_cpu_bit_for_bit") else {
        return;
    };
    use mcg_color_codec::{
        ColorCodec, Gamma5R10G10B10A2, Heuristics, HeuristicsLayout, IrradianceLayout, R11G11B10,
        Rgb9E5, Rounding, VisibilityLayout,
    };
    let mut rng = Pcg64::seed_from_u64(13);
    let mut values: Vec<[f32; 4]> = (0..50_000)
        .map(|_| {
            let mut v = [0.0_f32; 4];
            for x in v.iter_mut().take(3) {
                *x = (rng.random_range(-30.0_f32..17.0)).exp2();
            }
            v[3] = rng.random();
            v
        })
        .collect();
    let specials = [
        0.0,
        -0.0,
        -1.0,
        1.0,
        65024.0,
        65025.0,
        1e9,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
        6.1035156e-5,
        1.0 + 1.0 / 128.0,
        1.0 + 3.0 / 128.0,
        1e-40,
    ];
    for &a in &specials {
        for &b in &specials {
            values.push([a, b, 1.5, 0.5]);
        }
    }
    let reads = CodecKernels::new().pack_unpack(ctx, &values).unwrap();
    let irr = IrradianceLayout::ADGI;
    for (i, (v, read)) in values.iter().zip(&reads).enumerate() {
        let rgb = Vec3::new(v[0], v[1], v[2]);
        let count = i as u32 % 64;
        let cpu = [
            R11G11B10::pack(rgb),
            Rgb9E5::pack(rgb),
            Gamma5R10G10B10A2.encode(rgb),
            irr.encode(rgb, count, Rounding::Down).0,
        ];
        assert_eq!(
            read.formats, cpu,
            "R11G11B10, RGB9E5, gamma-5, irradiance (down) of {rgb}"
        );
        let nearest = irr.encode(rgb, count, Rounding::Nearest).0;
        let stochastic = irr.encode(rgb, count, Rounding::Stochastic(v[3])).0;
        let vis = VisibilityLayout::ADGI;
        let moments = Vec2::new(v[0], v[1]);
        let vis_nearest = vis.encode(moments, count, Rounding::Nearest);
        let vis_stochastic = vis.encode(moments, count, Rounding::Stochastic(v[3]));
        assert_eq!(
            read.rounded[2..],
            [vis_nearest.0, vis_stochastic.0],
            "visibility of {moments}, u = {}",
            v[3]
        );
        assert_eq!(
            read.decoded[5][..2],
            vis.decode(vis_nearest).to_array(),
            "visibility decode of {moments}"
        );
        assert_eq!(
            read.rounded[..2],
            [nearest, stochastic],
            "irradiance of {rgb}, u = {}",
            v[3]
        );
        let h = Heuristics {
            f_v: v[0].min(1.0),
            f_s: v[1].min(1.0),
            f_d: v[2].min(1.0),
            flags: count,
        };
        let heu = HeuristicsLayout::ADGI;
        let h_nearest = heu.encode_with(h, Rounding::Nearest);
        let h_stochastic = heu.encode_with(h, Rounding::Stochastic(v[3]));
        assert_eq!(
            read.heuristics[..2],
            [h_nearest.0, h_stochastic.0],
            "heuristics of {h:?}"
        );
        let hd = heu.decode(h_nearest);
        let cpu_heuristics = [hd.f_v, hd.f_s, hd.f_d, hd.flags as f32];
        assert!(
            decoded_close(&read.decoded[6], &cpu_heuristics, 4.0),
            "heuristics decode of {h:?}: GPU {:?} CPU {cpu_heuristics:?}",
            read.decoded[6]
        );
        let cpu_decoded = [
            R11G11B10::unpack(cpu[0]),
            Rgb9E5::unpack(cpu[1]),
            Gamma5R10G10B10A2.decode(cpu[2]),
            irr.decode(cpu[3].into()),
            irr.decode(nearest.into()),
        ];
        for (k, d) in cpu_decoded.iter().enumerate() {
            assert_eq!(read.decoded[k][..3], d.to_array(), "decode {k} of {rgb}");
        }
    }
}

/// ≈ 65 000 invocations fold samples into 1 056 shared irradiance texels with the
/// compare-and-swap loop, a texel's updates in consecutive invocations (racing). Hypothesis:
/// the result is one that some serial order of the updates gives. With one sample value per
/// texel every order gives the same word, so each texel must equal the CPU's word after the
/// same number of serial updates, and its count exactly that number (1..=62, below N_max)
/// or N_max = 63; the same for visibility words (N_max = 10). Then 65 536 distinct samples
/// into 64 irradiance texels: counts N_max, values within
/// the samples' range (± one quantum). Broken once on purpose (an `atomicStore` of the
/// update instead of the compare-and-swap): lost updates gave counts below the number of
/// updates and the test failed.
#[test]
fn concurrent_texel_updates_match_a_serial_order() {
    let Some(ctx) = gpu_or_skip("concurrent_texel_updates_match_a_serial_order") else {
        return;
    };
    use mcg_color_codec::{IrradianceLayout, IrradianceWord, MovingAverage, Rounding};
    let layout = IrradianceLayout::ADGI;
    let average = MovingAverage::STATIC;
    let mut rng = Pcg64::seed_from_u64(17);
    // 1 024 texels with 1..=62 updates each (below N_max = 63, so every lost update shows in
    // the count) and 32 texels with 1 024 updates each; a texel's updates are consecutive
    // invocations, so they race within and across workgroups.
    let counts: Vec<u32> = (0..1056_u32)
        .map(|t| if t < 1024 { 1 + t % 62 } else { 1024 })
        .collect();
    let texels = counts.len() as u32;
    let per_texel: Vec<Vec3> = (0..texels)
        .map(|_| {
            Vec3::new(
                rng.random_range(0.0..20.0),
                rng.random_range(0.0..2.0),
                rng.random_range(0.0..0.1),
            )
        })
        .collect();
    let mut updates = Vec::new();
    for (t, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            updates.push(TexelUpdate {
                sample: per_texel[t],
                texel: t as u32,
            });
        }
    }
    // Irradiance words (N_max = 63, static) and visibility words (moments = the sample's xy,
    // N_max = 10, dynamic): the GPU's texels after the racing updates, and the CPU's word and
    // count after n serial updates.
    use mcg_color_codec::{VisibilityLayout, VisibilityWord};
    let vis = VisibilityLayout::ADGI;
    let dynamic = MovingAverage::DYNAMIC;
    type Serial<'a> = Box<dyn Fn(u32, Vec3) -> (u32, u32) + 'a>;
    let serial_irradiance: Serial = Box::new(|n, x| {
        let w = (0..n).fold(0, |w, _| average.update(&layout, w, x, Rounding::Nearest));
        (w, layout.count(IrradianceWord(w)))
    });
    let serial_visibility: Serial = Box::new(|n, x| {
        let m = Vec2::new(x.x, x.y);
        let w = (0..n).fold(0, |w, _| dynamic.update(&vis, w, m, Rounding::Nearest));
        (w, vis.count(VisibilityWord(w)))
    });
    for (word_layout, max_count, serial) in [
        (0, average.max_count(), serial_irradiance),
        (1, dynamic.max_count(), serial_visibility),
    ] {
        let params = TexelParams {
            max_count,
            rounding_mode: 1,
            rounding_u: 0.0,
            word_layout,
        };
        let words = GpuTexels::upload(ctx, &vec![0; texels as usize]).unwrap();
        words.update(ctx, &updates, &params).unwrap();
        let gpu = words.read(ctx).unwrap();
        for t in 0..texels as usize {
            let n = counts[t];
            let (cpu, count) = serial(n, per_texel[t]);
            assert_eq!(count, n.min(max_count), "layout {word_layout}, texel {t}");
            assert_eq!(
                gpu[t], cpu,
                "layout {word_layout}, texel {t} after {n} equal updates"
            );
        }
    }
    // Distinct samples: exact counts, values within the samples' range.
    let updates: Vec<TexelUpdate> = (0..65_536_u32)
        .map(|k| TexelUpdate {
            sample: Vec3::splat(rng.random_range(1.0..2.0)),
            texel: k % 64,
        })
        .collect();
    let words = GpuTexels::upload(ctx, &[0; 64]).unwrap();
    let params = TexelParams {
        max_count: average.max_count(),
        rounding_mode: 1,
        rounding_u: 0.0,
        word_layout: 0,
    };
    words.update(ctx, &updates, &params).unwrap();
    for w in words.read(ctx).unwrap() {
        let w = IrradianceWord(w);
        assert_eq!(layout.count(w), average.max_count());
        let v = layout.decode(w);
        assert!(v.min_element() >= 0.97 && v.max_element() <= 2.03, "{v}");
    }
}

/// A NaN sample leaves a texel word unchanged on the GPU, as `MovingAverage::update` does on
/// the CPU: 64 irradiance and 64 visibility words holding a value and a count, each updated
/// with samples that have a NaN in one component (each component the word reads, in turn).
/// Hypothesis: every
/// word is bit for bit what it was. Deterministic; the NaN test written as `any(x != x)` (which
/// lavapipe compiles as never true) fails it (checked once).
#[test]
fn nan_samples_leave_texel_words_unchanged() {
    let Some(ctx) = gpu_or_skip("nan_samples_leave_texel_words_unchanged") else {
        return;
    };
    use mcg_color_codec::{IrradianceLayout, MovingAverage, Rounding, VisibilityLayout};
    let average = MovingAverage::STATIC;
    let before: Vec<u32> = (0..64u32)
        .map(|t| {
            let x = Vec3::new(1.0 + t as f32, 0.5, 0.25);
            (0..3).fold(0, |w, _| {
                average.update(&IrradianceLayout::ADGI, w, x, Rounding::Nearest)
            })
        })
        .collect();
    let visibility: Vec<u32> = (0..64u32)
        .map(|t| {
            let m = Vec2::new(1.0 + t as f32, 2.0 + t as f32);
            (0..3).fold(0, |w, _| {
                average.update(&VisibilityLayout::ADGI, w, m, Rounding::Nearest)
            })
        })
        .collect();
    let updates: Vec<TexelUpdate> = (0..192u32)
        .map(|k| {
            let mut sample = Vec3::splat(3.0);
            sample[(k / 64) as usize] = f32::NAN;
            TexelUpdate {
                sample,
                texel: k % 64,
            }
        })
        .collect();
    // Visibility words read the sample's x and y (the moments): the first 128 updates.
    for (word_layout, words, updates) in [
        (0, &before, &updates[..]),
        (1, &visibility, &updates[..128]),
    ] {
        let params = TexelParams {
            max_count: average.max_count(),
            rounding_mode: 1,
            rounding_u: 0.0,
            word_layout,
        };
        let texels = GpuTexels::upload(ctx, words).unwrap();
        texels.update(ctx, updates, &params).unwrap();
        assert_eq!(&texels.read(ctx).unwrap(), words, "layout {word_layout}");
    }
}

/// LogLuv32 (`pack_xyz`, `encode`, `unpack_xyz`, `decode`) bit for bit. Encode: 65 536
/// luminance boundaries (Y = 2ᵉ·T[k] and the float below it for every exponent e of the
/// range and every log₂ step k, so every Le boundary is crossed), 40 000 colours
/// log-uniform over 2⁻⁷⁰..2⁷⁰ per component (saturated and near-grey chromaticities), the
/// luminance bounds ± one ulp, zeros, negatives, NaN and infinities. Decode: every Le code
/// (0..2¹⁵) with random chromaticities, with and without the sign bit. Hypothesis: words equal
/// the CPU's exactly; decoded values within [`decoded_close`]'s 4 ULP (XYZ: the decoder's
/// `exp2` is the CPU's, table-driven, but its divisions are WGSL's, within 2.5 ULP) and 16 ULP
/// (RGB, through the matrix). NaN packs as 0, tested on the bits: with the clamps written as
/// a no-NaN driver may rewrite them (`select(c, 0, c <= 0)`), the NaN colours failed. Broken
/// once on purpose (the chroma
/// candidate not corrected by the exact sign test): words differed and the test failed.
#[test]
fn logluv32_matches_the_cpu_bit_for_bit() {
    let Some((ctx, mut rng)) = gpu_and_rng("logluv32_matches_the_cpu_bit_for_bit", 47) else {
        return;
    };
    use mcg_color_codec::{ColorCodec, LogLuv32};
    let log2_steps = &prelude::logluv_tables()[..256];
    let mut values: Vec<[f32; 4]> = Vec::new();
    for e in -64..64_i32 {
        for &t in log2_steps {
            for m in [t, f32::from_bits(t.to_bits() - 1)] {
                let y = m * 2f32.powi(e);
                let x = y * rng.random_range(0.0..2.0_f32);
                let z = y * rng.random_range(0.0..2.0_f32);
                values.push([x, y, z, 0.0]);
            }
        }
    }
    for _ in 0..40_000 {
        let mut v = [0.0; 4];
        let base = rng.random_range(-70.0..70.0_f32);
        for c in v.iter_mut().take(3) {
            *c = (base + rng.random_range(-8.0..8.0_f32)).exp2();
        }
        values.push(v);
    }
    let specials = [
        0.0,
        -1.0,
        1.0,
        f32::NAN,
        f32::INFINITY,
        1.837_197_6e19,
        1.837_197_7e19,
        1.837_197_5e19,
        5.413_676_9e-20,
        5.413_677e-20,
        5.413_676_8e-20,
        1e-30,
        3e38,
    ];
    for &a in &specials {
        for &b in &specials {
            for &c in &[0.0, 1.0, 1e30, f32::INFINITY] {
                values.push([a, b, c, 0.0]);
            }
        }
    }
    let mut words: Vec<u32> = (0..1u32 << 15)
        .map(|le| (le << 16) | rng.random_range(0..1u32 << 16))
        .collect();
    words.extend((0..2000).map(|_| rng.random::<u32>() | (1 << 31)));
    while words.len() < values.len() {
        words.push(rng.random());
    }
    values.resize(words.len(), [0.0; 4]);
    let colours: Vec<Vec3> = values.iter().map(|v| Vec3::from_slice(&v[..3])).collect();
    let reads = CodecKernels::new().logluv(ctx, &colours, &words).unwrap();
    for (i, ((&v, &w), read)) in colours.iter().zip(&words).zip(&reads).enumerate() {
        assert_eq!(
            read.packed,
            [LogLuv32::pack_xyz(v), LogLuv32.encode(v)],
            "{i}: pack of {v:?}"
        );
        let (xyz, rgb) = (LogLuv32::unpack_xyz(w), LogLuv32.decode(w));
        assert!(
            decoded_close(&read.xyz.to_array(), &xyz.to_array(), 4.0),
            "{i}: unpack_xyz of {w:#010x}: GPU {} CPU {xyz}",
            read.xyz
        );
        assert!(
            decoded_close(&read.rgb.to_array(), &rgb.to_array(), 16.0),
            "{i}: decode of {w:#010x}: GPU {} CPU {rgb}",
            read.rgb
        );
    }
}

/// Decoded values that divide (or go through a 3 × 3 matrix) agree within `ulps` ULP of the
/// vector's largest magnitude: WGSL's division is within 2.5 ULP and a compiler may fuse a
/// multiply with an add. Lavapipe decodes them bit for bit; an NVIDIA H200 decoded a
/// heuristics fraction and a LogLuv X 1 ULP away from the CPU. The packed words stay exact.
fn decoded_close(gpu: &[f32], cpu: &[f32], ulps: f32) -> bool {
    let scale = cpu.iter().fold(0.0_f32, |m, c| m.max(c.abs()));
    gpu.iter().zip(cpu).all(|(&g, &c)| {
        g == c || (g.is_nan() && c.is_nan()) || (g - c).abs() <= ulps * f32::EPSILON * scale
    })
}
