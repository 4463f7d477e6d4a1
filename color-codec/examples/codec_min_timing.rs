//! Load-robust timing of the log codec against R11G11B10, for a shared, noisy machine where
//! criterion's means drift with the other jobs: the same 1024-colour batches as the criterion
//! bench (`benches/color_codec.rs`, hue/saturation uniform, intensity log-uniform in
//! [10⁻³, 8]), each timed 50 times in a row, keeping the fastest of 20 such runs, the codecs
//! interleaved 15 times. Prints ns per batch and the ratio
//! `log (encode + decode) / R11G11B10 (encode + decode)`, and the fused `decode(encode(c))`,
//! once per colour (`encode` / `decode`) and once in the slice form (`encode_slice` /
//! `decode_slice`: R11G11B10's default loop, the log codec's 4-colours-per-vector batch; the
//! "round trip" there is `encode_slice` then `decode_slice`), and the per-colour round trip
//! once more shaped as the criterion bench (the loop in a closure that an out-of-line driver
//! calls, so that the codec is a run-time value there).
//!
//! `cargo run --release -p mcg-color-codec --example codec_min_timing`

use std::hint::black_box;
use std::time::Instant;

use mcg_color_codec::glam::Vec3;
use mcg_color_codec::{ColorCodec, LogRgb, R11G11B10};

const BATCH: usize = 1024;

fn colours() -> Vec<Vec3> {
    // A PCG-style LCG; any fixed sequence will do.
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

/// Fastest time of one call of `f`, in ns.
fn fastest<F: FnMut()>(mut f: F) -> f64 {
    let mut best = f64::MAX;
    for _ in 0..20 {
        let start = Instant::now();
        for _ in 0..50 {
            f();
        }
        best = best.min(start.elapsed().as_secs_f64() / 50.0);
    }
    best * 1e9
}

/// (encode, decode, round trip) in ns per batch.
fn time_codec<C: ColorCodec>(codec: &C, input: &[Vec3]) -> [f64; 3] {
    let mut words = vec![0u32; BATCH];
    let mut out = vec![Vec3::ZERO; BATCH];
    let encode = fastest(|| {
        for (w, &c) in words.iter_mut().zip(black_box(input)) {
            *w = codec.encode(c);
        }
        black_box(&words);
    });
    let encoded: Vec<u32> = input.iter().map(|&c| codec.encode(c)).collect();
    let decode = fastest(|| {
        for (o, &w) in out.iter_mut().zip(black_box(&encoded)) {
            *o = codec.decode(w);
        }
        black_box(&out);
    });
    let round_trip = fastest(|| {
        for (o, &c) in out.iter_mut().zip(black_box(input)) {
            *o = codec.decode(codec.encode(c));
        }
        black_box(&out);
    });
    [encode, decode, round_trip]
}

/// Fastest time of the per-colour round trip written as the criterion bench writes it: the
/// loop in a closure that an out-of-line driver calls (criterion's `Bencher::iter`), the codec
/// captured by reference, so that it is a run-time value in the loop, not a constant.
fn round_trip_as_bench<C: ColorCodec>(codec: &C, input: &[Vec3]) -> f64 {
    #[inline(never)]
    fn drive<F: FnMut()>(f: &mut F) -> f64 {
        fastest(f)
    }
    // As in criterion, where the codec reaches the loop through its closures.
    let codec = black_box(codec);
    let mut out = vec![Vec3::ZERO; BATCH];
    drive(&mut || {
        for (o, &c) in out.iter_mut().zip(black_box(input)) {
            *o = codec.decode(codec.encode(c));
        }
        black_box(&out);
    })
}

/// (encode_slice, decode_slice, both in a row) in ns per batch: the slice API (the default
/// per-colour loop for R11G11B10, the 4-colours-per-vector batch form for the log codec).
fn time_codec_batch<C: ColorCodec>(codec: &C, input: &[Vec3]) -> [f64; 3] {
    let mut words = vec![0u32; BATCH];
    let mut out = vec![Vec3::ZERO; BATCH];
    let encode = fastest(|| {
        codec.encode_slice(black_box(input), &mut words);
        black_box(&words);
    });
    let mut encoded = vec![0u32; BATCH];
    codec.encode_slice(input, &mut encoded);
    let decode = fastest(|| {
        codec.decode_slice(black_box(&encoded), &mut out);
        black_box(&out);
    });
    let round_trip = fastest(|| {
        codec.encode_slice(black_box(input), &mut words);
        codec.decode_slice(&words, &mut out);
        black_box(&out);
    });
    [encode, decode, round_trip]
}

fn main() {
    let input = colours();
    let codecs: [&dyn Fn() -> [f64; 3]; 6] = [
        &|| time_codec(&R11G11B10, &input),
        &|| time_codec(&LogRgb::ADGI, &input),
        &|| time_codec(&LogRgb::ADGI_NEAREST, &input),
        &|| time_codec_batch(&R11G11B10, &input),
        &|| time_codec_batch(&LogRgb::ADGI, &input),
        &|| time_codec_batch(&LogRgb::ADGI_NEAREST, &input),
    ];
    let as_bench: [&dyn Fn() -> f64; 2] = [&|| round_trip_as_bench(&R11G11B10, &input), &|| {
        round_trip_as_bench(&LogRgb::ADGI, &input)
    }];
    let mut best = [[f64::MAX; 3]; 6];
    let mut best_as_bench = [f64::MAX; 2];
    for _ in 0..15 {
        for (b, time) in best.iter_mut().zip(codecs) {
            let t = time();
            for k in 0..3 {
                b[k] = b[k].min(t[k]);
            }
        }
        for (b, time) in best_as_bench.iter_mut().zip(as_bench) {
            *b = b.min(time());
        }
    }
    let names = ["r11g11b10", "log_r9g9b8_down", "log_r9g9b8_nearest"];
    for (form, best) in [
        ("per colour (encode / decode)", &best[..3]),
        ("batch (encode_slice / decode_slice)", &best[3..]),
    ] {
        println!("{form}:");
        for (name, b) in names.iter().zip(best) {
            println!(
                "  {name:<20} encode {:>7.0} ns  decode {:>7.0} ns  round trip {:>7.0} ns",
                b[0], b[1], b[2]
            );
        }
        let base = best[0][0] + best[0][1];
        for (name, b) in names.iter().zip(best).skip(1) {
            println!(
                "  {name}: (encode + decode) ratio {:.2}, round-trip ratio {:.2}",
                (b[0] + b[1]) / base,
                b[2] / best[0][2]
            );
        }
    }
    println!(
        "per colour round trip shaped as the criterion bench (codec a run-time value):\n  \
         r11g11b10 {:>7.0} ns  log_r9g9b8_down {:>7.0} ns  ratio {:.2}",
        best_as_bench[0],
        best_as_bench[1],
        best_as_bench[1] / best_as_bench[0]
    );
}
