//! One round-trip case of the criterion bench (`benches/color_codec.rs`, groups `round_trip`
//! and `batch_round_trip`) run a given number of passes, for instruction counting under
//! valgrind: `scripts/codec-instructions` runs each case with 1 and with 3 passes under
//! `callgrind` and divides the difference of the two totals by 2 · colours per pass, so the
//! set-up cancels out.
//!
//! `cargo run --release -p mcg-color-codec --example codec_instructions -- CASE PASSES`, CASE one of
//! `r11g11b10`, `log_down`, `log_nearest`, `half` (per colour: `decode(encode(c))`),
//! `r11g11b10_bench`, `log_down_bench` (the same, shaped as the criterion bench: the loop in a
//! closure called by an out-of-line driver, the codec a run-time value there) and
//! `r11g11b10_slice`, `log_down_slice`, `half_slice` (`encode_slice` then `decode_slice`).
//! Prints `CASE PASSES colours-per-pass CHECKSUM`.

use std::hint::black_box;

use half::f16;
use half::slice::HalfFloatSliceExt;
use mcg_color_codec::glam::Vec3;
use mcg_color_codec::{ColorCodec, LogRgb, R11G11B10};

/// Colours per batch, as in the bench.
const BATCH: usize = 1024;
/// Batches per pass.
const REPEAT: usize = 16;

/// The bench's colours: hue and saturation uniform, intensity log-uniform in [10⁻³, 8]
/// (a fixed LCG instead of the bench's PCG; any fixed sequence will do).
fn colours() -> Vec<Vec3> {
    let mut s: u64 = 11;
    let mut uniform = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..BATCH)
        .map(|_| {
            let c = Vec3::new(uniform(), uniform(), uniform());
            c * 10f32.powf(uniform() * 3.9 - 3.0)
        })
        .collect()
}

/// One pass of a per-colour round trip; returns a checksum of the decoded colours.
fn per_colour(codec: &impl ColorCodec, input: &[Vec3], out: &mut [Vec3]) -> f32 {
    for _ in 0..REPEAT {
        for (o, &c) in out.iter_mut().zip(black_box(input)) {
            *o = codec.decode(codec.encode(c));
        }
    }
    black_box(&*out).iter().map(|c| c.x).sum()
}

/// One pass of a per-colour round trip written as the criterion bench writes it: the loop in a
/// closure that an out-of-line driver calls (criterion's `Bencher::iter`), with the codec
/// captured by reference, so that it is a run-time value there, not a constant.
fn per_colour_bench(codec: &impl ColorCodec, input: &[Vec3], out: &mut [Vec3]) -> f32 {
    #[inline(never)]
    fn drive<F: FnMut()>(mut f: F) {
        for _ in 0..REPEAT {
            f();
        }
    }
    // As in criterion, where the codec reaches the loop through its closures.
    let codec = black_box(codec);
    drive(|| {
        for (o, &c) in out.iter_mut().zip(black_box(input)) {
            *o = codec.decode(codec.encode(c));
        }
        black_box(&*out);
    });
    black_box(&*out).iter().map(|c| c.x).sum()
}

/// One pass of a slice round trip.
fn slices(codec: &impl ColorCodec, input: &[Vec3], words: &mut [u32], out: &mut [Vec3]) -> f32 {
    for _ in 0..REPEAT {
        codec.encode_slice(black_box(input), words);
        codec.decode_slice(black_box(&*words), out);
    }
    black_box(&*out).iter().map(|c| c.x).sum()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: instructions CASE PASSES";
    let case = args.get(1).expect(usage).as_str();
    let passes: usize = args.get(2).expect(usage).parse().expect(usage);
    let input = colours();
    let mut out = vec![Vec3::ZERO; BATCH];
    let mut words = vec![0_u32; BATCH];
    let mut halves = vec![f16::ZERO; 3 * BATCH];
    let mut floats = vec![0.0_f32; 3 * BATCH];
    let flat: Vec<f32> = input.iter().flat_map(|c| c.to_array()).collect();
    let mut sum = 0.0;
    for _ in 0..passes {
        sum += match case {
            "r11g11b10" => per_colour(&R11G11B10, &input, &mut out),
            "log_down" => per_colour(&LogRgb::ADGI, &input, &mut out),
            "log_nearest" => per_colour(&LogRgb::ADGI_NEAREST, &input, &mut out),
            "r11g11b10_bench" => per_colour_bench(&R11G11B10, &input, &mut out),
            "log_down_bench" => per_colour_bench(&LogRgb::ADGI, &input, &mut out),
            "r11g11b10_slice" => slices(&R11G11B10, &input, &mut words, &mut out),
            "log_down_slice" => slices(&LogRgb::ADGI, &input, &mut words, &mut out),
            "half" => {
                for _ in 0..REPEAT {
                    for (o, &c) in out.iter_mut().zip(black_box(&input)) {
                        let h = c.to_array().map(f16::from_f32);
                        *o = Vec3::from_array(black_box(h).map(f16::to_f32));
                    }
                }
                black_box(&out).iter().map(|c| c.x).sum()
            }
            "half_slice" => {
                for _ in 0..REPEAT {
                    halves.convert_from_f32_slice(black_box(&flat));
                    black_box(&halves).convert_to_f32_slice(&mut floats);
                }
                black_box(&floats).iter().sum()
            }
            _ => panic!("unknown case {case}"),
        };
    }
    println!("{case} {passes} {} {sum}", BATCH * REPEAT);
}
