//! Every 32-bit word of every shipped word format decodes to finite, non-negative values, and
//! re-encodes to itself where the format promises it.
//!
//! | format | output checked | stability promised and checked |
//! |---|---|---|
//! | irradiance (`IrradianceLayout::ADGI`) | RGB finite, ≥ 0; count ≤ N_max | `encode(decode(w), count(w), Down) = w` (log codec: `encode(decode(q)) = q`) |
//! | visibility (`VisibilityLayout::ADGI`) | moments finite, ≥ 0; count ≤ N_max | `encode(decode(w), count(w), Down) = w` |
//! | heuristics (`HeuristicsLayout::ADGI`) | f_v, f_s, f_d in [0, 1] | `encode(decode(w)) = w` (flags kept) |
//! | R11G11B10 | RGB finite, ≥ 0 | `pack(unpack(w)) = w` unless a field has e = 31 (∞/NaN, which decode to the largest finite value by design) |
//! | RGB9E5 | RGB finite, ≥ 0 | `unpack(pack(unpack(w))) = unpack(w)` (several words share a value: denormalised mantissas) |
//! | LogLuv32 | RGB finite, ≥ 0; XYZ finite | `pack_xyz(unpack_xyz(w)) = w` for Le ≥ 1, no sign bit and a decoded XYZ ≥ 0 (the others decode to black or to an out-of-gamut colour by design) |
//! | gamma-5 R10G10B10A2 | RGB in [0, 1] | `encode(decode(w)) = w` with alpha = 3 (alpha is written as 3, ignored on decode) |
//!
//! The default run (CI) checks every word whose index is ≡ 0 mod 257 (16.7 million words per
//! format, coprime with every field width so all field values and their combinations are
//! visited) plus the edge words (0, 1, max − 1 and max of every field, combined over the fields,
//! and every single-bit, low-mask and their complements): 0.5-1.1 s per format, 5.5 s for all
//! seven, in `--profile ci` on 2 cores.
//!
//! The whole 2³² words of every format run with
//!
//! ```text
//! cargo test --profile ci -p mcg-color-codec --test exhaustive_decode -- --ignored
//! ```
//!
//! 257 times the strided work: about 24 minutes for all seven formats on 2 idle cores
//! (measured on 2 cores shared with parallel builds: RGB9E5 7.5 min, heuristics 6.4 min).
//! Every test spreads its words over all available threads, so it scales with the core count;
//! one format runs alone with e.g. `-- --ignored every_word::logluv32_all_words`.

use std::thread;

use mcg_color_codec::glam::Vec3;
use mcg_color_codec::{
    ColorCodec, Gamma5R10G10B10A2, HeuristicsLayout, HeuristicsWord, IrradianceLayout,
    IrradianceWord, LogLuv32, R11G11B10, Rgb9E5, Rounding, VisibilityLayout, VisibilityWord,
};

/// The CI stride: 257 is prime, so the strided words cover every residue of every field.
const STRIDE: u64 = 257;

/// Which words a test checks.
#[derive(Clone, Copy)]
enum Words {
    /// Every word ≡ 0 mod [`STRIDE`], plus the edge words.
    Strided,
    /// All 2³² words.
    All,
}

/// The edge words of a format with fields of the given widths (from bit 0 up): every
/// combination of the field values 0, 1, max − 1 and max, plus every single bit, every low mask
/// and their complements.
fn edge_words(widths: &[u32]) -> Vec<u32> {
    let mut words = vec![0, u32::MAX];
    for k in 0..32 {
        let bit = 1u32 << k;
        words.extend([bit, bit - 1, !bit, !(bit - 1)]);
    }
    let mut combos = vec![0u32];
    let mut shift = 0;
    for &w in widths {
        let max = if w >= 32 { u32::MAX } else { (1u32 << w) - 1 };
        let values = [0, 1.min(max), max.saturating_sub(1), max];
        combos = combos
            .iter()
            .flat_map(|&c| {
                values
                    .iter()
                    .map(move |&v| c | v.checked_shl(shift).unwrap_or(0))
            })
            .collect();
        shift += w;
    }
    words.extend(combos);
    words.sort_unstable();
    words.dedup();
    words
}

/// Runs `check` on the words `which` selects (plus `edges` when strided), spread over all
/// available threads; `check` panics with the word on a failure.
fn for_words(which: Words, edges: &[u32], check: impl Fn(u32) + Sync) {
    let threads = thread::available_parallelism().map_or(2, |n| n.get()) as u64;
    let (step, count) = match which {
        Words::Strided => (STRIDE, (1u64 << 32).div_ceil(STRIDE)),
        Words::All => (1, 1u64 << 32),
    };
    thread::scope(|s| {
        for t in 0..threads {
            let check = &check;
            s.spawn(move || {
                let mut i = t;
                while i < count {
                    check((i * step) as u32);
                    i += threads;
                }
            });
        }
    });
    if let Words::Strided = which {
        edges.iter().for_each(|&w| check(w));
    }
}

fn finite_non_negative(c: Vec3) -> bool {
    c.is_finite() && c.cmpge(Vec3::ZERO).all()
}

fn irradiance(which: Words) {
    let l = IrradianceLayout::ADGI;
    let widths = l.widths();
    for_words(which, &edge_words(&widths), |w| {
        let word = IrradianceWord(w);
        let rgb = l.decode(word);
        assert!(finite_non_negative(rgb), "{w:#010x}: {rgb}");
        let count = l.count(word);
        assert!(count <= l.max_count(), "{w:#010x}: count {count}");
        assert_eq!(
            l.encode(rgb, count, Rounding::Down),
            word,
            "{w:#010x}: {rgb}"
        );
    });
}

fn visibility(which: Words) {
    let l = VisibilityLayout::ADGI;
    for_words(which, &edge_words(&l.widths()), |w| {
        let word = VisibilityWord(w);
        let m = l.decode(word);
        assert!(m.is_finite() && m.x >= 0.0 && m.y >= 0.0, "{w:#010x}: {m}");
        let count = l.count(word);
        assert!(count <= l.max_count());
        assert_eq!(l.encode(m, count, Rounding::Down), word, "{w:#010x}: {m}");
    });
}

fn heuristics(which: Words) {
    let l = HeuristicsLayout::ADGI;
    for_words(which, &edge_words(&l.widths()), |w| {
        let h = l.decode(HeuristicsWord(w));
        for x in [h.f_v, h.f_s, h.f_d] {
            assert!((0.0..=1.0).contains(&x), "{w:#010x}: {h:?}");
        }
        assert_eq!(l.encode(h), HeuristicsWord(w), "{w:#010x}: {h:?}");
    });
}

fn r11g11b10(which: Words) {
    for_words(which, &edge_words(&[6, 5, 6, 5, 5, 5]), |w| {
        let c = R11G11B10::unpack(w);
        assert!(finite_non_negative(c), "{w:#010x}: {c}");
        let exponents = [(w >> 6) & 31, (w >> 17) & 31, (w >> 27) & 31];
        if !exponents.contains(&31) {
            assert_eq!(R11G11B10::pack(c), w, "{w:#010x}: {c}");
        }
    });
}

fn rgb9e5(which: Words) {
    for_words(which, &edge_words(&[9, 9, 9, 5]), |w| {
        let c = Rgb9E5::unpack(w);
        assert!(finite_non_negative(c), "{w:#010x}: {c}");
        assert_eq!(Rgb9E5::unpack(Rgb9E5::pack(c)), c, "{w:#010x}: {c}");
    });
}

fn logluv32(which: Words) {
    for_words(which, &edge_words(&[8, 8, 15, 1]), |w| {
        let rgb = LogLuv32.decode(w);
        assert!(finite_non_negative(rgb), "{w:#010x}: {rgb}");
        let xyz = LogLuv32::unpack_xyz(w);
        assert!(xyz.is_finite(), "{w:#010x}: {xyz}");
        let le = (w >> 16) & 0x7fff;
        if le != 0 && w >> 31 == 0 && xyz.cmpge(Vec3::ZERO).all() {
            assert_eq!(LogLuv32::pack_xyz(xyz), w, "{w:#010x}: {xyz}");
        }
    });
}

fn gamma5(which: Words) {
    for_words(which, &edge_words(&[10, 10, 10, 2]), |w| {
        let c = Gamma5R10G10B10A2.decode(w);
        assert!(
            finite_non_negative(c) && c.cmple(Vec3::ONE).all(),
            "{w:#010x}: {c}"
        );
        assert_eq!(
            Gamma5R10G10B10A2.encode(c),
            (w & 0x3fff_ffff) | (3 << 30),
            "{w:#010x}: {c}"
        );
    });
}

macro_rules! formats {
    ($($name:ident, $all:ident;)*) => {$(
        #[test]
        fn $name() {
            super::$name(super::Words::Strided);
        }

        /// All 2³² words (see the file's docs for the command and its time).
        #[test]
        #[ignore = "2^32 words: 2-8 minutes per format on 2 cores, run with --ignored"]
        fn $all() {
            super::$name(super::Words::All);
        }
    )*};
}

mod every_word {
    formats! {
        irradiance, irradiance_all_words;
        visibility, visibility_all_words;
        heuristics, heuristics_all_words;
        r11g11b10, r11g11b10_all_words;
        rgb9e5, rgb9e5_all_words;
        logluv32, logluv32_all_words;
        gamma5, gamma5_all_words;
    }
}

#[test]
fn edge_words_cover_field_extremes() {
    let words = edge_words(&[9, 9, 8, 6]);
    assert!(words.contains(&0) && words.contains(&u32::MAX));
    // R = max, G = 1, B = max − 1, count = 0.
    assert!(words.contains(&(511 | (1 << 9) | (254 << 18))));
    assert!(words.len() > 4usize.pow(4));
}
