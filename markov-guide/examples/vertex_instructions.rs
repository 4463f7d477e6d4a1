//! Runs the `guided_vertex` benchmark's vertices (`benches/common/vertices.rs`) a given number
//! of passes on a trained guide, for an instruction count under valgrind's callgrind that a
//! noisy machine cannot blur: `scripts/guide-instructions` runs it with 1 and 3 passes and
//! reports (Ir(3) − Ir(1)) / (2 · vertices), the instructions of one full guided vertex.
//!
//! ```text
//! cargo run --release -p mcg-markov-guide --example vertex_instructions -- CASE PASSES
//! ```
//!
//! CASE is `cosine` (the baseline), `vertex` (no cache) or `vertex_cache`.

#[path = "../benches/common/vertices.rs"]
mod vertices;

use std::hint::black_box;

use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;
use vertices::{BATCH, cosine_batch, cosine_inputs, inputs, trained_guide};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let case = args.get(1).map_or("vertex", String::as_str);
    let passes: usize = args.get(2).and_then(|p| p.parse().ok()).unwrap_or(1);
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let inputs = inputs(&mut rng, BATCH);
    let us = cosine_inputs(&mut rng, BATCH);
    let mut total = 0.0;
    match case {
        "cosine" => {
            for _ in 0..passes {
                total += cosine_batch(black_box(&us));
            }
        }
        "vertex" | "vertex_cache" => {
            let guide = trained_guide(case == "vertex_cache", &inputs);
            for _ in 0..passes {
                total += vertices::vertices(black_box(&guide), &inputs);
            }
        }
        other => {
            eprintln!("unknown case {other}: cosine, vertex or vertex_cache");
            std::process::exit(2);
        }
    }
    println!("{case} passes {passes} vertices {BATCH} checksum {total}");
}
