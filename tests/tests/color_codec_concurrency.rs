//! Concurrency of `MovingAverage::update_atomic`: several threads updating the same words with
//! the compare-and-swap loop lose nothing.
//!
//! 4 threads × 15 updates on each of 16 shared words, repeated for 200 rounds, all threads
//! released together by a barrier. Every update advances the count by one (60 < N_max = 63), so
//! a lost update shows up as a count below 60. With equal samples the value is exact to one
//! quantum: round-down stores the largest code ≤ s, and every later update leaves it there.

// Channel-indexed loops (`for c in 0..3`) read like the math.
#![allow(clippy::needless_range_loop)]

use std::sync::Barrier;
use std::sync::atomic::{AtomicU32, Ordering};

use mcg_color_codec::glam::{Vec2, Vec3};
use mcg_color_codec::{
    IrradianceLayout, IrradianceWord, MovingAverage, Rounding, VisibilityLayout, VisibilityWord,
};

const THREADS: usize = 4;
const UPDATES: u32 = 15;
const WORDS: usize = 16;
const ROUNDS: usize = 200;

#[test]
fn no_update_is_lost_irradiance() {
    let layout = IrradianceLayout::ADGI;
    let sample = Vec3::new(0.7, 0.35, 2.5);
    let expect = layout.decode(layout.encode(sample, 0, Rounding::Down));
    for round in 0..ROUNDS {
        let words: Vec<AtomicU32> = (0..WORDS).map(|_| AtomicU32::new(0)).collect();
        let barrier = Barrier::new(THREADS);
        std::thread::scope(|scope| {
            for t in 0..THREADS {
                let (words, barrier) = (&words, &barrier);
                scope.spawn(move || {
                    barrier.wait();
                    for k in 0..UPDATES as usize * WORDS {
                        // Each thread walks the words in its own order.
                        let i = (k * (2 * t + 1) + t) % WORDS;
                        MovingAverage::STATIC.update_atomic(
                            &layout,
                            &words[i],
                            sample,
                            Rounding::Down,
                        );
                    }
                });
            }
        });
        for (i, w) in words.iter().enumerate() {
            let word = IrradianceWord(w.load(Ordering::Relaxed));
            assert_eq!(
                layout.count(word),
                THREADS as u32 * UPDATES,
                "round {round}, word {i}"
            );
            let v = layout.decode(word);
            assert_eq!(v, expect, "round {round}, word {i}");
            for c in 0..3 {
                let f = layout.channel(c);
                mcg_tests::assert_close!(
                    v[c],
                    sample[c],
                    f.quantum_at(f.encode(sample[c], Rounding::Down))
                );
            }
        }
    }
}

#[test]
fn no_update_is_lost_visibility_with_distinct_samples() {
    let layout = VisibilityLayout::ADGI;
    for round in 0..ROUNDS / 4 {
        let words: Vec<AtomicU32> = (0..WORDS).map(|_| AtomicU32::new(0)).collect();
        let barrier = Barrier::new(THREADS);
        std::thread::scope(|scope| {
            for t in 0..THREADS {
                let (words, barrier) = (&words, &barrier);
                scope.spawn(move || {
                    barrier.wait();
                    for k in 0..UPDATES as usize * WORDS {
                        let d = 0.1 + 0.05 * (t * 7 + k % 5) as f32;
                        MovingAverage::STATIC.update_atomic(
                            &layout,
                            &words[k % WORDS],
                            Vec2::new(d, d * d),
                            Rounding::Stochastic(((k * 31 + t * 17) % 97) as f32 / 97.0),
                        );
                    }
                });
            }
        });
        for (i, w) in words.iter().enumerate() {
            let word = VisibilityWord(w.load(Ordering::Relaxed));
            assert_eq!(
                layout.count(word),
                THREADS as u32 * UPDATES,
                "round {round}, word {i}"
            );
            let m = layout.decode(word);
            // The mean of the samples lies in [0.1, 1.4]; the average stays inside.
            assert!(m.x >= 0.099 && m.x <= 1.4 && m.y >= m.x * m.x * 0.99, "{m}");
        }
    }
}
