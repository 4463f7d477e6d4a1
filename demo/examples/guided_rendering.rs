//! The report's section "Guided rendering" alone: renders the hidden-light room with `bsdf`,
//! `nee` and `mcpg` at equal samples and equal time and writes the section's figures, an
//! `index.html` with that section only and `guided-rendering.json` (the numbers) into OUT.
//!
//! ```text
//! cargo run --release -p mcg-demo --example guided_rendering -- [SAMPLES] [OUT]
//! ```
//!
//! SAMPLES picks the sizes as the report's `--samples` does (default 1 000 000: 128 × 128,
//! 64 frames of 8 spp; 100 000: `--quick`'s 64 × 64, 16 frames); OUT defaults to
//! `out/guided-rendering`. The reference is cached in `OUT/reference/`.

use std::path::PathBuf;
use std::time::Instant;

use mcg_demo::Config;
use mcg_demo::report::Report;
use mcg_demo::sections::{Context, guided_rendering};

fn main() -> mcg_demo::Result<()> {
    let mut args = std::env::args().skip(1);
    let samples = match args.next() {
        Some(s) => s.parse().map_err(|_| format!("not a sample count: {s}"))?,
        None => Config::DEFAULT_SAMPLES,
    };
    let config = Config {
        out_dir: args
            .next()
            .map_or_else(|| PathBuf::from("out/guided-rendering"), PathBuf::from),
        samples,
        ..Config::default()
    };
    std::fs::create_dir_all(&config.out_dir)?;
    mcg_demo::plot::register_fonts()?;
    let out = std::fs::canonicalize(&config.out_dir)?;
    let started = Instant::now();
    let section = guided_rendering::build(&Context::new(&config, &out))?;
    let mut page = Report::new("mcg — guided rendering");
    page.push_section(section);
    let index = page.write(&out)?;
    println!(
        "{} ({:.1} s)",
        index.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
