//! Criterion benchmarks of mcg-color-codec, each group with its baselines in the same group so
//! that results read as ratios:
//!
//! - `encode`, `decode`, `round_trip`: every codec of the crate against a plain f32 copy (the
//!   floor: 12 bytes moved) and R11G11B10 (the format a renderer author would otherwise pick).
//!   Target: the log codec's encode + decode within 2× of R11G11B10's. These call `encode` /
//!   `decode` once per colour.
//! - `batch_encode`, `batch_decode`: the slice API (`encode_slice` / `decode_slice`) over the
//!   same 1024 colours: R11G11B10's default per-colour loop against the log codec's batch form
//!   (four colours per vector), with the f32 copy.
//! - `round_trip` and `batch_round_trip` also hold the `half` crate's 3 × f16 (6 bytes, what
//!   a renderer keeps when it does not pack): per colour (`f16::from_f32` / `to_f32`, software
//!   conversions on baseline x86-64, which lacks F16C) and through its slice conversions.
//!   `batch_round_trip`: `encode_slice` then `decode_slice` of the 1024 colours, the slice
//!   API's round trip; targets: the log codec's round trip within 1.3× of R11G11B10's per
//!   colour and 1.1× through the slice API.
//! - `moving_average`: the atomic CAS update (`MovingAverage::update_atomic`) with 1 and 2
//!   threads against the same update as a plain, unsynchronised read-modify-write and a plain
//!   store of the encoded sample.
//!
//! Every iteration processes a batch of [`BATCH`] colours so the loop overhead is amortised.

use std::hint::black_box;
use std::sync::atomic::{AtomicU32, Ordering};

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_group, criterion_main};
use half::f16;
use half::slice::HalfFloatSliceExt;
use mcg_color_codec::glam::Vec3;
use mcg_color_codec::{
    ColorCodec, Gamma5R10G10B10A2, IrradianceLayout, LogLuv32, LogRgb, MovingAverage, R11G11B10,
    Rgb9E5, Rounding,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const BATCH: usize = 1024;

/// Colours with dynamic range: hue and saturation uniform, intensity log-uniform in [10⁻³, 8].
fn colours() -> Vec<Vec3> {
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    (0..BATCH)
        .map(|_| {
            let c = Vec3::new(rng.random(), rng.random(), rng.random());
            c * 10f32.powf(rng.random::<f32>() * 3.9 - 3.0)
        })
        .collect()
}

fn group<'a>(c: &'a mut Criterion, name: &str) -> BenchmarkGroup<'a, WallTime> {
    let mut g = c.benchmark_group(name);
    g.throughput(Throughput::Elements(BATCH as u64));
    g
}

// Each bench calls the concrete codec type (static dispatch), so that it inlines.
macro_rules! each_codec {
    ($g:expr, $body:ident) => {
        $body!($g, "r11g11b10_baseline", R11G11B10);
        $body!($g, "log_r9g9b8_down", LogRgb::ADGI);
        $body!($g, "log_r9g9b8_nearest", LogRgb::ADGI_NEAREST);
        $body!($g, "log_r10g10b10_down", LogRgb::EQUAL_10);
        $body!($g, "rgb9e5", Rgb9E5);
        $body!($g, "logluv32", LogLuv32);
        $body!($g, "gamma5_r10g10b10a2", Gamma5R10G10B10A2);
    };
}

/// The per-colour codec groups `encode`, `decode` and `round_trip` on one batch.
fn bench_codecs(c: &mut Criterion) {
    let input = colours();
    bench_encode(c, &input);
    bench_decode(c, &input);
    bench_round_trip(c, &input);
}

/// Group `encode`: the f32 copy baseline, then each codec's encode of the batch.
fn bench_encode(c: &mut Criterion, input: &[Vec3]) {
    let mut g = group(c, "encode");
    let mut out = vec![Vec3::ZERO; BATCH];
    g.bench_function("f32_copy_baseline", |b| {
        b.iter(|| {
            out.copy_from_slice(black_box(input));
            black_box(&out);
        })
    });
    let mut words = vec![0u32; BATCH];
    macro_rules! enc {
        ($g:expr, $name:expr, $codec:expr) => {
            $g.bench_function($name, |b| {
                let codec = $codec;
                b.iter(|| {
                    for (w, &c) in words.iter_mut().zip(black_box(input)) {
                        *w = codec.encode(c);
                    }
                    black_box(&words);
                })
            });
        };
    }
    each_codec!(g, enc);
    g.finish();
}

/// Group `decode`: the f32 copy baseline, then each codec's decode of the encoded batch.
fn bench_decode(c: &mut Criterion, input: &[Vec3]) {
    let mut out = vec![Vec3::ZERO; BATCH];
    let mut g = group(c, "decode");
    g.bench_function("f32_copy_baseline", |b| {
        b.iter(|| {
            out.copy_from_slice(black_box(input));
            black_box(&out);
        })
    });
    macro_rules! dec {
        ($g:expr, $name:expr, $codec:expr) => {
            $g.bench_function($name, |b| {
                let codec = $codec;
                let encoded: Vec<u32> = input.iter().map(|&c| codec.encode(c)).collect();
                b.iter(|| {
                    for (o, &w) in out.iter_mut().zip(black_box(&encoded)) {
                        *o = codec.decode(w);
                    }
                    black_box(&out);
                })
            });
        };
    }
    each_codec!(g, dec);
    g.finish();
}

/// Group `round_trip`: the f32 copy baseline, each codec's encode + decode, and f16 × 3.
fn bench_round_trip(c: &mut Criterion, input: &[Vec3]) {
    let mut out = vec![Vec3::ZERO; BATCH];
    let mut g = group(c, "round_trip");
    g.bench_function("f32_copy_baseline", |b| {
        b.iter(|| {
            out.copy_from_slice(black_box(input));
            black_box(&out);
        })
    });
    macro_rules! rt {
        ($g:expr, $name:expr, $codec:expr) => {
            $g.bench_function($name, |b| {
                let codec = $codec;
                b.iter(|| {
                    for (o, &c) in out.iter_mut().zip(black_box(input)) {
                        *o = codec.decode(codec.encode(c));
                    }
                    black_box(&out);
                })
            });
        };
    }
    each_codec!(g, rt);
    g.bench_function("half_f16x3_peer", |b| {
        b.iter(|| {
            for (o, &c) in out.iter_mut().zip(black_box(input)) {
                let h = black_box([f16::from_f32(c.x), f16::from_f32(c.y), f16::from_f32(c.z)]);
                *o = Vec3::new(h[0].to_f32(), h[1].to_f32(), h[2].to_f32());
            }
            black_box(&out);
        })
    });
    g.finish();
}

// The three codecs with a batch form worth measuring (the baseline and the log codec's two).
macro_rules! each_batch_codec {
    ($g:expr, $body:ident) => {
        $body!($g, "r11g11b10_baseline", R11G11B10);
        $body!($g, "log_r9g9b8_down", LogRgb::ADGI);
        $body!($g, "log_r9g9b8_nearest", LogRgb::ADGI_NEAREST);
    };
}

/// The slice API (`ColorCodec::encode_slice` / `decode_slice`): R11G11B10's is the default
/// per-colour loop (which the compiler vectorises across colours), the log codec's the batch
/// form (four colours per 4-lane vector, lane = colour).
fn bench_batch(c: &mut Criterion) {
    let input = colours();
    bench_batch_encode(c, &input);
    bench_batch_decode(c, &input);
    bench_batch_round_trip(c, &input);
}

/// Group `batch_encode`: the f32 copy baseline, then each codec's `encode_slice`.
fn bench_batch_encode(c: &mut Criterion, input: &[Vec3]) {
    let mut out = vec![Vec3::ZERO; BATCH];
    let mut words = vec![0u32; BATCH];

    let mut g = group(c, "batch_encode");
    g.bench_function("f32_copy_baseline", |b| {
        b.iter(|| {
            out.copy_from_slice(black_box(input));
            black_box(&out);
        })
    });
    macro_rules! enc {
        ($g:expr, $name:expr, $codec:expr) => {
            $g.bench_function($name, |b| {
                let codec = $codec;
                b.iter(|| {
                    codec.encode_slice(black_box(input), &mut words);
                    black_box(&words);
                })
            });
        };
    }
    each_batch_codec!(g, enc);
    g.finish();
}

/// Group `batch_decode`: the f32 copy baseline, then each codec's `decode_slice`.
fn bench_batch_decode(c: &mut Criterion, input: &[Vec3]) {
    let mut out = vec![Vec3::ZERO; BATCH];

    let mut g = group(c, "batch_decode");
    g.bench_function("f32_copy_baseline", |b| {
        b.iter(|| {
            out.copy_from_slice(black_box(input));
            black_box(&out);
        })
    });
    macro_rules! dec {
        ($g:expr, $name:expr, $codec:expr) => {
            $g.bench_function($name, |b| {
                let codec = $codec;
                let mut encoded = vec![0u32; BATCH];
                codec.encode_slice(input, &mut encoded);
                b.iter(|| {
                    codec.decode_slice(black_box(&encoded), &mut out);
                    black_box(&out);
                })
            });
        };
    }
    each_batch_codec!(g, dec);
    g.finish();
}

/// Group `batch_round_trip`: the f32 copy baseline, each codec's slices, and f16 × 3.
fn bench_batch_round_trip(c: &mut Criterion, input: &[Vec3]) {
    let mut out = vec![Vec3::ZERO; BATCH];
    let mut words = vec![0u32; BATCH];

    let mut g = group(c, "batch_round_trip");
    g.bench_function("f32_copy_baseline", |b| {
        b.iter(|| {
            out.copy_from_slice(black_box(input));
            black_box(&out);
        })
    });
    macro_rules! rt {
        ($g:expr, $name:expr, $codec:expr) => {
            $g.bench_function($name, |b| {
                let codec = $codec;
                b.iter(|| {
                    codec.encode_slice(black_box(input), &mut words);
                    codec.decode_slice(black_box(&words), &mut out);
                    black_box(&out);
                })
            });
        };
    }
    each_batch_codec!(g, rt);
    let mut halves = vec![f16::ZERO; 3 * BATCH];
    g.bench_function("half_f16x3_peer", |b| {
        b.iter(|| {
            halves.convert_from_f32_slice(bytemuck::cast_slice(black_box(input)));
            black_box(&halves).convert_to_f32_slice(bytemuck::cast_slice_mut(&mut out));
            black_box(&out);
        })
    });
    g.finish();
}

fn bench_moving_average(c: &mut Criterion) {
    let input = colours();
    let layout = IrradianceLayout::ADGI;
    let avg = MovingAverage::STATIC;
    const WORDS: usize = 64;
    let mut g = group(c, "moving_average");
    g.bench_function("plain_store_baseline", |b| {
        let mut words = vec![0u32; WORDS];
        b.iter(|| {
            for (i, &s) in black_box(&input).iter().enumerate() {
                words[i % WORDS] = layout.encode(s, 1, Rounding::Down).0;
            }
            black_box(&words);
        })
    });
    g.bench_function("unsynchronised_update", |b| {
        let mut words = vec![0u32; WORDS];
        b.iter(|| {
            for (i, &s) in black_box(&input).iter().enumerate() {
                let w = &mut words[i % WORDS];
                *w = avg.update(&layout, *w, s, Rounding::Down);
            }
            black_box(&words);
        })
    });
    g.bench_function("atomic_update_1_thread", |b| {
        let words: Vec<AtomicU32> = (0..WORDS).map(|_| AtomicU32::new(0)).collect();
        b.iter(|| {
            for (i, &s) in black_box(&input).iter().enumerate() {
                avg.update_atomic(&layout, &words[i % WORDS], s, Rounding::Down);
            }
            black_box(words[0].load(Ordering::Relaxed));
        })
    });
    // Two threads each apply the whole batch to the same 64 words, `iters` times, started
    // once per measurement (spawn cost amortised). Time per BATCH updates of each thread, so the
    // ratio to the 1-thread case is the contention cost (2× the work in the same wall time
    // would read 1.0).
    g.bench_function("atomic_update_2_threads", |b| {
        let words: Vec<AtomicU32> = (0..WORDS).map(|_| AtomicU32::new(0)).collect();
        b.iter_custom(|iters| {
            let start = std::time::Instant::now();
            std::thread::scope(|scope| {
                for t in 0..2 {
                    let (words, input) = (&words, &input);
                    scope.spawn(move || {
                        for _ in 0..iters {
                            for (i, &s) in black_box(input).iter().enumerate() {
                                avg.update_atomic(
                                    &layout,
                                    &words[(i + t * 7) % WORDS],
                                    s,
                                    Rounding::Down,
                                );
                            }
                        }
                    });
                }
            });
            black_box(words[0].load(Ordering::Relaxed));
            start.elapsed()
        })
    });
    g.finish();
}

criterion_group!(benches, bench_codecs, bench_batch, bench_moving_average);
criterion_main!(benches);
