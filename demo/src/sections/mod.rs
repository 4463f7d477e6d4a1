//! The sections of the report, one module each.
//!
//! A section is a function `fn(&Context) -> Result<Section>`: it computes what it shows, writes
//! its PNG files into the output folder ([`Context::figure_path`]) and returns the text, figures
//! and tables as a [`Section`]. [`ALL`] lists them in page order; [`crate::run`] calls each once.

pub mod color_codec;
pub mod dynamic_gi;
pub mod gpu_backend;
pub mod guided_rendering;
pub mod hashgrid;
pub mod markov_guide;
pub mod probe_cache;
pub mod smis;
pub mod vmf;

use std::path::{Path, PathBuf};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

use crate::report::Section;
use crate::{Config, Result};

/// The median of `values`: the upper of the middle two for an even count, NaN for none.
pub(crate) fn median(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.into_iter().collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Signature of a section builder.
pub type BuildFn = fn(&Context<'_>) -> Result<Section>;

/// Every section of the report, in page order. Append new sections here.
pub const ALL: &[BuildFn] = &[
    guided_rendering::build,
    dynamic_gi::build,
    vmf::build,
    color_codec::build,
    smis::build,
    hashgrid::build,
    markov_guide::build,
    probe_cache::build,
    gpu_backend::build,
];

/// What a section builder gets: the run's settings and where to put files.
#[derive(Clone, Copy, Debug)]
pub struct Context<'a> {
    /// Settings of this run (sample count, seed, progress bars).
    pub config: &'a Config,
    out_dir: &'a Path,
}

impl<'a> Context<'a> {
    /// A context writing into `out_dir`, which must exist.
    pub fn new(config: &'a Config, out_dir: &'a Path) -> Self {
        Self { config, out_dir }
    }

    /// The output folder (absolute when built by [`crate::run`]).
    pub fn out_dir(&self) -> &Path {
        self.out_dir
    }

    /// Where to write a figure called `file`; pass the same `file` to
    /// [`Section::figure`] so the page links to it. Prefix file names with the section id to
    /// keep sections from overwriting each other's files.
    pub fn figure_path(&self, file: &str) -> PathBuf {
        self.out_dir.join(file)
    }

    /// A progress bar of `len` steps labelled `message` on stderr; hidden when progress is off
    /// in the config (indicatif also hides it by itself when stderr is not a terminal).
    /// Call `finish_and_clear` or `finish` on it when done.
    pub fn progress(&self, len: u64, message: &str) -> ProgressBar {
        if !self.config.progress {
            return ProgressBar::hidden();
        }
        let bar = ProgressBar::new(len).with_message(message.to_owned());
        if let Ok(style) = ProgressStyle::with_template(
            "{msg:<34} [{bar:32.cyan/blue}] {percent:>3}% {elapsed:>4}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.enable_steady_tick(Duration::from_millis(200));
        bar
    }
}
