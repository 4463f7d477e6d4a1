//! Adversarial properties of mcg-color-codec: every public function called with NaN, ±∞, ±0,
//! subnormals, `f32::MAX`, `u32::MAX` counts and widths, arbitrary words and arbitrary codec
//! parameters.
//!
//! Asserted: constructors reject parameters that later calls could not handle (with the
//! variant named for the broken condition); no panic (the slice functions, which document a
//! panic on mismatched lengths, get matching slices); every decode is finite and
//! non-negative; no update ever stores a word that decodes to NaN or ∞. CI runs this with
//! overflow checks and debug assertions on (`--profile ci`).
//!
//! Deterministic: 1024 cases from the fixed seed 0x7E57_00A2 (`support::proptest_config`).

use std::sync::atomic::AtomicU32;

use glam::{Vec2, Vec3};
use mcg_color_codec::{
    CodecError, ColorCodec, Gamma5R10G10B10A2, Heuristics, HeuristicsLayout, HeuristicsWord,
    IrradianceLayout, IrradianceWord, LogCodec, LogLuv32, LogRgb, MAX_FIELD_BITS,
    MAX_QUANTIZE_CODE, MovingAverage, R11G11B10, Rgb9E5, Rounding, VisibilityLayout,
    VisibilityWord, f32_to_ufloat, quantize, quantize_unorm, ufloat_to_f32,
};
use proptest::prelude::*;

mod support;
use support::{any_f32, any_u32, any_uniform};

fn finite_non_negative(x: f32) -> bool {
    x.is_finite() && x >= 0.0
}

fn rounding() -> impl Strategy<Value = Rounding> {
    prop_oneof![
        Just(Rounding::Down),
        Just(Rounding::Nearest),
        any_uniform().prop_map(Rounding::Stochastic),
    ]
}

/// Codec parameters from the whole f32 range, and the codec `new` makes of them (if any).
fn any_codec() -> impl Strategy<Value = (f32, f32)> {
    prop_oneof![
        Just((5.0f32, 15.0f32)),
        Just((80.0, 1e-4)),
        Just((80.0, LogCodec::gamma_min(80.0))),
        Just((1e-30, 1e-45)),
        Just((LogCodec::BETA_MIN, LogCodec::gamma_min(LogCodec::BETA_MIN))),
        (0.0f32..=80.0, any_f32()),
        (any_f32(), any_f32()),
        (
            0.01f32..=80.0,
            prop_oneof![Just(f32::MAX), Just(1e30f32), 1e-6f32..1e6]
        ),
    ]
}

fn codec_of((beta, gamma): (f32, f32)) -> Result<LogCodec, CodecError> {
    let codec = LogCodec::new(beta, gamma);
    let want = if !(LogCodec::BETA_MIN..=LogCodec::BETA_MAX).contains(&beta) {
        Err(CodecError::BetaOutOfRange { beta })
    } else if !(gamma > 0.0 && gamma.is_finite()) {
        Err(CodecError::GammaNotPositive { gamma })
    } else if gamma < LogCodec::gamma_min(beta) {
        Err(CodecError::MaxValueOverflows {
            gamma,
            minimum: LogCodec::gamma_min(beta),
        })
    } else {
        Ok(())
    };
    // Compared through `Debug` so that a NaN parameter carried by the error compares equal.
    assert_eq!(
        format!("{:?}", codec.map(|_| ())),
        format!("{want:?}"),
        "LogCodec::new({beta}, {gamma})"
    );
    codec
}

fn colour() -> impl Strategy<Value = Vec3> {
    (any_f32(), any_f32(), any_f32()).prop_map(|(r, g, b)| Vec3::new(r, g, b))
}

fn layouts() -> impl Strategy<Value = (IrradianceLayout, VisibilityLayout)> {
    (1u32..=16, 1u32..=16, 1u32..=16, any_codec(), any_codec()).prop_filter_map(
        "valid widths and codecs",
        |(a, b, c, p, q)| {
            let (p, q) = (codec_of(p).ok()?, codec_of(q).ok()?);
            let count = 32u32
                .checked_sub(a + b + c)
                .filter(|&k| (1..=16).contains(&k))?;
            let irradiance = IrradianceLayout::new(a, b, c, count, p).ok()?;
            let count = 32u32
                .checked_sub(a + b)
                .filter(|&k| (1..=16).contains(&k))?;
            let visibility = VisibilityLayout::new(a, b, count, p, q).ok()?;
            Some((irradiance, visibility))
        },
    )
}

proptest! {
    #![proptest_config(support::proptest_config(1024, 0x7E57_00A2))]

    #[test]
    fn log_codecs_validate_and_decode_finite(
        params in any_codec(), v in any_f32(), u in any_f32(), bits in any_u32(),
        code in any_u32(), r in rounding(),
    ) {
        let Ok(codec) = codec_of(params) else { return Ok(()) };
        prop_assert!(finite_non_negative(codec.max_value()), "{codec:?}");
        let f = codec.forward(v);
        prop_assert!((0.0..=1.0).contains(&f), "{codec:?} forward({v}) = {f}");
        prop_assert!(finite_non_negative(codec.inverse(u)));
        let field = codec.field(bits);
        prop_assert!((1..=MAX_FIELD_BITS).contains(&field.bits()));
        let d = field.decode(code);
        prop_assert!(finite_non_negative(d), "{codec:?} {bits} bits: decode({code}) = {d}");
        let e = field.encode(v, r);
        prop_assert!(e <= field.max_code());
        prop_assert!(finite_non_negative(field.decode(e)));
        prop_assert!(finite_non_negative(field.quantum_at(code)));
        if v.is_finite() {
            let b = field.error_bound(v, r);
            prop_assert!(!b.is_nan() && b >= 0.0, "{codec:?} error_bound({v}) = {b}");
        }
        for x in [field.encode_scale(), field.exponent_scale(), field.decode_scale(), field.inv_gamma(), field.down_tolerance()] {
            prop_assert!(finite_non_negative(x), "{codec:?} {bits}: {x}");
        }
    }

    #[test]
    fn quantizers_never_overflow(x in any_f32(), max in any_u32(), bits in any_u32(), r in rounding(), n in any_u32(), code in any_u32()) {
        prop_assert!(quantize(x, max, r) <= max.min(MAX_QUANTIZE_CODE));
        let q = quantize_unorm(x, bits, r);
        prop_assert!(q <= MAX_QUANTIZE_CODE);
        let w = f32_to_ufloat(x, n);
        prop_assert!(finite_non_negative(ufloat_to_f32(w, n)));
        prop_assert!(finite_non_negative(ufloat_to_f32(code, n)));
        prop_assert!(finite_non_negative(Gamma5R10G10B10A2::decode_channel(code)));
        prop_assert!(Gamma5R10G10B10A2::encode_channel(x) <= 1023);
    }

    #[test]
    fn colour_codecs_round_trip_finite(rgb in colour(), word in any::<u32>()) {
        let codecs: [&dyn ColorCodec; 7] = [
            &LogRgb::ADGI, &LogRgb::ADGI_NEAREST, &LogRgb::EQUAL_10, &R11G11B10, &Rgb9E5,
            &LogLuv32, &Gamma5R10G10B10A2,
        ];
        for codec in codecs {
            let w = codec.encode(rgb);
            for c in [codec.decode(w), codec.decode(word)] {
                prop_assert!(c.is_finite() && c.cmpge(Vec3::ZERO).all(), "{}: {c}", codec.name());
            }
            let mut words = [0u32; 2];
            codec.encode_slice(&[rgb, -rgb], &mut words);
            let mut back = [Vec3::ZERO; 2];
            codec.decode_slice(&[word, words[1]], &mut back);
            prop_assert!(back.iter().all(|c| c.is_finite()));
        }
        // XYZ of out-of-gamut chromaticities can be negative (only the RGB decode clamps).
        prop_assert!(LogLuv32::unpack_xyz(word).is_finite());
        prop_assert!(LogLuv32::unpack_xyz(LogLuv32::pack_xyz(rgb)).is_finite());
        prop_assert!(Rgb9E5::unpack(Rgb9E5::pack(rgb)).is_finite());
        prop_assert!(R11G11B10::unpack(R11G11B10::pack(rgb)).is_finite());
    }

    #[test]
    fn packed_layouts_decode_finite_and_updates_store_finite_words(
        (irradiance, visibility) in layouts(), rgb in colour(), m in (any_f32(), any_f32()),
        count in any_u32(), word in any::<u32>(), r in rounding(), max_count in any_u32(),
        samples in proptest::collection::vec((colour(), any_uniform()), 1..8),
    ) {
        let moments = Vec2::new(m.0, m.1);
        let w = irradiance.encode(rgb, count, r);
        for w in [w, IrradianceWord(word)] {
            let c = irradiance.decode(w);
            prop_assert!(c.is_finite() && c.cmpge(Vec3::ZERO).all(), "{irradiance:?}: {c}");
            prop_assert!(irradiance.count(w) <= irradiance.max_count());
            let _ = irradiance.codes(w);
        }
        prop_assert!(irradiance.count(irradiance.with_count(w, count)) == count.min(irradiance.max_count()));
        let v = visibility.encode(moments, count, r);
        for v in [v, VisibilityWord(word)] {
            let d = visibility.decode(v);
            prop_assert!(d.is_finite() && d.cmpge(Vec2::ZERO).all(), "{visibility:?}: {d}");
            prop_assert!(visibility.count(v) <= visibility.max_count());
        }
        let mut colours = [Vec3::ZERO; 2];
        let mut words = [IrradianceWord(0); 2];
        irradiance.encode_slice(&[rgb, rgb * 2.0], count, r, &mut words);
        irradiance.decode_slice(&[words[0], IrradianceWord(word)], &mut colours);
        prop_assert!(colours.iter().all(|c| c.is_finite()));
        match MovingAverage::new(max_count) {
            Ok(average) => {
                prop_assert!(finite_non_negative(average.hysteresis()));
                let atomic = AtomicU32::new(word);
                let mut plain = word;
                for (sample, u) in samples {
                    plain = average.update(&irradiance, plain, sample, Rounding::Stochastic(u));
                    let (_, after) = average.update_atomic_swap(&irradiance, &atomic, sample, r);
                    for w in [plain, after] {
                        prop_assert!(irradiance.decode(IrradianceWord(w)).is_finite());
                    }
                    let v = average.update(&visibility, word, Vec2::new(sample.x, sample.y), r);
                    prop_assert!(visibility.decode(VisibilityWord(v)).is_finite());
                }
            }
            Err(e) => prop_assert!(max_count == 0 && e == CodecError::MaxCountZero),
        }
    }

    #[test]
    fn heuristics_layouts_never_shift_out_of_the_word(
        widths in [0u32..=17, 0u32..=17, 0u32..=17, 0u32..=17], h in (any_f32(), any_f32(), any_f32(), any_u32()),
        word in any::<u32>(), flags in any_u32(), r in rounding(),
    ) {
        let Ok(layout) = HeuristicsLayout::new(widths[0], widths[1], widths[2], widths[3]) else {
            let sum: u32 = widths.iter().sum();
            prop_assert!(widths[..3].iter().any(|&w| !(1..=16).contains(&w)) || widths[3] > 16 || sum != 32);
            return Ok(());
        };
        let h = Heuristics { f_v: h.0, f_s: h.1, f_d: h.2, flags: h.3 };
        for w in [layout.encode(h), layout.encode_with(h, r), HeuristicsWord(word)] {
            let d = layout.decode(w);
            for x in [d.f_v, d.f_s, d.f_d] {
                prop_assert!((0.0..=1.0).contains(&x), "{layout:?}: {d:?}");
            }
            let max_flags = if widths[3] == 0 { 0 } else { (1u32 << widths[3]) - 1 };
            prop_assert!(layout.flags(w) <= max_flags);
            prop_assert_eq!(layout.flags(layout.with_flags(w, flags)), flags & max_flags);
        }
    }
}
