//! # mcg-demo: the report that shows mcg at work
//!
//! `cargo run --release -p mcg-demo` runs the crates of this workspace on built-in defaults and
//! writes an HTML report, `out/index.html`, with PNG charts next to it. Nothing is read from
//! disk and nothing needs installing: the charts are drawn in pure Rust with an embedded font.
//!
//! ## Layout
//!
//! | module | what it does |
//! |---|---|
//! | [`run`] (this file) | creates the output folder, builds every section, writes the page |
//! | [`report`] | the HTML page: title, intro, sections with paragraphs, figures and tables |
//! | [`plot`] | thin helpers over `plotters`: line charts with log axes, histograms against a curve |
//! | [`sections`] | one module per section of the report, listed in [`sections::ALL`] |
//! | [`render`] | the path tracer of `mcg-demo render`: glTF scenes, BVH, materials, methods, image files |
//!
//! ## Adding a section
//!
//! 1. Write `src/sections/my_topic.rs` with `pub fn build(ctx: &Context) -> Result<Section>`.
//!    Draw charts with [`plot`] into [`Context::figure_path`], describe them with
//!    [`report::Section`] methods, and wrap long loops in [`Context::progress`].
//! 2. Declare the module in `src/sections/mod.rs` and append `my_topic::build` to
//!    [`sections::ALL`]. The smoke test in `tests/report.rs` then checks its figures too.
//!
//! [`Context`]: sections::Context
//! [`Context::figure_path`]: sections::Context::figure_path
//! [`Context::progress`]: sections::Context::progress

pub mod plot;
pub mod render;
pub mod report;
pub mod sections;

use std::path::PathBuf;
use std::time::Instant;

use report::Report;
use sections::Context;

/// Error type of the demo: anything that can go wrong while computing, drawing or writing.
pub type Error = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Result with the demo's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What a run of the report does: where it writes and how much work it spends.
#[derive(Clone, Debug)]
pub struct Config {
    /// Folder that receives `index.html` and the PNG files; created if missing.
    pub out_dir: PathBuf,
    /// Number of Monte Carlo samples per experiment (for example per κ in the vMF histograms).
    pub samples: usize,
    /// Seed of every random number generator in the report, so that runs are reproducible.
    pub seed: u64,
    /// Draw progress bars on the terminal (they stay hidden anyway when stderr is no terminal).
    pub progress: bool,
}

impl Config {
    /// Samples per experiment of a full run.
    pub const DEFAULT_SAMPLES: usize = 1_000_000;
    /// Samples per experiment with `--quick`.
    pub const QUICK_SAMPLES: usize = 100_000;
    /// The fixed seed used unless `--seed` says otherwise ("mcg" in ASCII).
    pub const DEFAULT_SEED: u64 = 0x6d_63_67;

    /// Of a section's three sizes, the one for a report of `samples` samples per experiment:
    /// `full` from [`Self::DEFAULT_SAMPLES`] on, `quick` from [`Self::QUICK_SAMPLES`] on,
    /// `smoke` below (the tests' tiny runs).
    #[must_use]
    pub fn tier<T>(samples: usize, full: T, quick: T, smoke: T) -> T {
        if samples >= Self::DEFAULT_SAMPLES {
            full
        } else if samples >= Self::QUICK_SAMPLES {
            quick
        } else {
            smoke
        }
    }
}

impl Default for Config {
    /// A full run into `out/` below the current directory, with progress bars.
    fn default() -> Self {
        Self {
            out_dir: PathBuf::from("out"),
            samples: Self::DEFAULT_SAMPLES,
            seed: Self::DEFAULT_SEED,
            progress: true,
        }
    }
}

/// Builds the whole report as `config` says and returns the absolute path of `index.html`.
///
/// Sections are built in the order of [`sections::ALL`]; the first error stops the run.
pub fn run(config: &Config) -> Result<PathBuf> {
    let started = Instant::now();
    std::fs::create_dir_all(&config.out_dir)
        .map_err(|e| format!("cannot create {}: {e}", config.out_dir.display()))?;
    let out_dir = std::fs::canonicalize(&config.out_dir)?;
    plot::register_fonts()?;

    let ctx = Context::new(config, &out_dir);
    let mut page = Report::new("mcg — demo report");
    page.paragraph(
        "This page is written by `cargo run --release -p mcg-demo`. It runs the crates of the mcg \
         workspace (Markov chain path guiding) on built-in defaults and shows, section by \
         section, that they do what their documentation promises: samples follow the densities, \
         and the f32 numerics hold where textbook formulas break down.",
    );
    page.paragraph(&format!(
        "Settings of this run: {} samples per experiment, seed {:#x}. Every number and chart is \
         reproducible from these two values.",
        group_thousands(config.samples),
        config.seed
    ));
    // Each section's wall-clock time goes to the footer, and to standard error as it ends when
    // progress is shown: where a long report spends its minutes.
    let mut times = Vec::with_capacity(sections::ALL.len());
    for build in sections::ALL {
        let section_started = Instant::now();
        let section = build(&ctx)?;
        let seconds = section_started.elapsed().as_secs_f64();
        if config.progress {
            eprintln!("{}: {seconds:.1} s", section.id());
        }
        times.push(format!("{} {seconds:.1} s", section.id()));
        page.push_section(section);
    }
    page.footer(&format!(
        "Generated by mcg-demo {} in {:.1} s ({}).",
        env!("CARGO_PKG_VERSION"),
        started.elapsed().as_secs_f64(),
        times.join(", ")
    ));
    Ok(page.write(&out_dir)?)
}

/// Formats an integer with thin spaces between groups of three digits (`1 000 000`).
pub fn group_thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3 * 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push('\u{2009}');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousands_are_grouped() {
        assert_eq!(group_thousands(0), "0");
        assert_eq!(group_thousands(999), "999");
        assert_eq!(group_thousands(1000), "1\u{2009}000");
        assert_eq!(group_thousands(1_000_000), "1\u{2009}000\u{2009}000");
    }
}
