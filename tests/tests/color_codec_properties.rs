//! Properties of mcg-color-codec over arbitrary words and inputs (proptest).

// Channel-indexed loops (`for c in 0..3`) read like the math.
#![allow(clippy::needless_range_loop)]

use mcg_color_codec::glam::{Vec2, Vec3};
use mcg_color_codec::{
    ColorCodec, Gamma5R10G10B10A2, HeuristicsLayout, HeuristicsWord, IrradianceLayout,
    IrradianceWord, LogLuv32, LogRgb, MovingAverage, R11G11B10, Rgb9E5, Rounding, VisibilityLayout,
    VisibilityWord,
};
use proptest::prelude::*;

mod support;

fn codecs() -> [&'static dyn ColorCodec; 7] {
    [
        &LogRgb::ADGI,
        &LogRgb::ADGI_NEAREST,
        &LogRgb::EQUAL_10,
        &R11G11B10,
        &Rgb9E5,
        &LogLuv32,
        &Gamma5R10G10B10A2,
    ]
}

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<f32>(),
        0.0f32..10.0,
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(-0.0),
    ]
}

proptest! {
    #![proptest_config(support::proptest_config(4000, 0x7E57_0003))]

    #[test]
    fn every_word_decodes_finite_non_negative(word in any::<u32>()) {
        for codec in codecs() {
            let c = codec.decode(word);
            prop_assert!(c.is_finite() && c.cmpge(Vec3::ZERO).all(), "{}: {word:#x} → {c}", codec.name());
        }
        let v = VisibilityLayout::ADGI.decode(VisibilityWord(word));
        prop_assert!(v.is_finite() && v.cmpge(Vec2::ZERO).all());
        let h = HeuristicsLayout::ADGI.decode(HeuristicsWord(word));
        prop_assert!((0.0..=1.0).contains(&h.f_v) && (0.0..=1.0).contains(&h.f_d));
    }

    #[test]
    fn any_input_encodes_to_a_word_that_round_trips(r in any_f32(), g in any_f32(), b in any_f32()) {
        for codec in codecs() {
            let d = codec.decode(codec.encode(Vec3::new(r, g, b)));
            prop_assert!(d.is_finite() && d.cmpge(Vec3::ZERO).all());
            // LogLuv32 clamps out-of-gamut decodes to RGB ≥ 0, which moves the chromaticity;
            // its idempotence holds in XYZ (checked below) and for in-gamut colours.
            if codec.name() != "LogLuv32" {
                prop_assert_eq!(codec.decode(codec.encode(d)), d, "{}", codec.name());
            }
        }
        let w = LogLuv32.encode(Vec3::new(r, g, b));
        let xyz = LogLuv32::unpack_xyz(w);
        prop_assert_eq!(LogLuv32::unpack_xyz(LogLuv32::pack_xyz(xyz)), xyz);
    }

    #[test]
    fn moving_average_never_corrupts_the_count(
        word in any::<u32>(), r in any_f32(), g in any_f32(), b in any_f32(), u in 0.0f32..1.0
    ) {
        let l = IrradianceLayout::ADGI;
        for avg in [MovingAverage::STATIC, MovingAverage::DYNAMIC] {
            for rounding in [Rounding::Down, Rounding::Nearest, Rounding::Stochastic(u)] {
                let new = IrradianceWord(avg.update(&l, word, Vec3::new(r, g, b), rounding));
                let n = l.count(IrradianceWord(word));
                if r.is_nan() || g.is_nan() || b.is_nan() {
                    prop_assert_eq!(new.0, word);
                } else {
                    prop_assert_eq!(l.count(new), (n + 1).min(avg.max_count()));
                }
                prop_assert!(l.decode(new).is_finite());
            }
        }
    }

    /// The slice API equals the per-colour one, bit for bit: `encode_slice` / `decode_slice`
    /// (the log codec's 4-colours-per-vector batch form, the other codecs' default loop) against
    /// `encode` / `decode` on arbitrary slices of 0-13 colours (every tail length), and
    /// `IrradianceLayout::encode_slice` with a count and a stochastic uniform.
    #[test]
    fn slices_equal_per_colour(
        rgb in proptest::collection::vec((any_f32(), any_f32(), any_f32()), 0..14),
        u in 0.0f32..1.0,
        count in 0u32..80,
    ) {
        let colours: Vec<Vec3> = rgb.iter().map(|&(r, g, b)| Vec3::new(r, g, b)).collect();
        let n = colours.len();
        for codec in codecs() {
            let mut words = vec![0u32; n];
            codec.encode_slice(&colours, &mut words);
            let want: Vec<u32> = colours.iter().map(|&c| codec.encode(c)).collect();
            prop_assert_eq!(&words, &want, "{}", codec.name());
            let mut dec = vec![Vec3::NAN; n];
            codec.decode_slice(&words, &mut dec);
            for (d, &w) in dec.iter().zip(&words) {
                prop_assert_eq!(d.to_array().map(f32::to_bits), codec.decode(w).to_array().map(f32::to_bits));
            }
        }
        for l in [IrradianceLayout::ADGI, IrradianceLayout::EQUAL_10] {
            for rounding in [Rounding::Down, Rounding::Nearest, Rounding::Stochastic(u)] {
                let mut words = vec![IrradianceWord(0); n];
                l.encode_slice(&colours, count, rounding, &mut words);
                let want: Vec<IrradianceWord> = colours.iter().map(|&c| l.encode(c, count, rounding)).collect();
                prop_assert_eq!(&words, &want, "{:?}", rounding);
            }
        }
    }
}
