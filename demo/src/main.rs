//! `mcg-demo`: writes the mcg demo report (see the library docs of `mcg_demo`).
//!
//! ```text
//! cargo run --release -p mcg-demo [-- --out DIR] [--quick] [--samples N] [--seed N] [--no-progress]
//! cargo run --release -p mcg-demo -- render --scene FILE --method bsdf|nee|mcpg --device auto|cpu|gpu [OPTIONS]   (see render --help)
//! cargo run --release -p mcg-demo -- scenes [--out demo/scenes]
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mcg_demo::Config;
use mcg_demo::render::{RenderArgs, ScenesArgs, run_render, scene_generator};

const USAGE: &str = "\
Usage: mcg-demo [OPTIONS]
       mcg-demo render --scene FILE [OPTIONS]   (path traces a glTF scene; render --help)
       mcg-demo scenes [--out DIR]              (writes the built-in scenes)

Writes an HTML report with PNG charts that shows the mcg crates at work.

Options:
  --out DIR       output folder (default: out)
  --quick         fewer samples (100 000 per experiment instead of 1 000 000)
  --samples N     samples per experiment
  --seed N        seed of the random number generators (decimal or 0x-hex)
  --no-progress   no progress bars
  -h, --help      this text";

/// What the command line asks for.
enum Command {
    Run(Config),
    Help,
}

fn parse_args(args: impl IntoIterator<Item = String>) -> Result<Command, String> {
    let mut config = Config::default();
    let mut args = args.into_iter();
    while let Some(arg) = args.next() {
        let mut value = |name: &str| args.next().ok_or_else(|| format!("{name} needs a value"));
        match arg.as_str() {
            "-h" | "--help" => return Ok(Command::Help),
            "--out" => config.out_dir = PathBuf::from(value("--out")?),
            "--quick" => config.samples = Config::QUICK_SAMPLES,
            "--samples" => {
                let v = value("--samples")?;
                config.samples = v
                    .replace('_', "")
                    .parse()
                    .map_err(|_| format!("--samples: not a count: {v}"))?;
                if config.samples < 1000 {
                    return Err("--samples: use at least 1000".to_owned());
                }
            }
            "--seed" => {
                let v = value("--seed")?;
                let parsed = match v.strip_prefix("0x") {
                    Some(hex) => u64::from_str_radix(hex, 16),
                    None => v.parse(),
                };
                config.seed = parsed.map_err(|_| format!("--seed: not a number: {v}"))?;
            }
            "--no-progress" => config.progress = false,
            other => return Err(format!("unknown argument: {other}")),
        }
    }
    Ok(Command::Run(config))
}

/// `mcg-demo render …` and `mcg-demo scenes …`: clap parses the arguments after the name.
fn run_subcommand(name: &str, args: &[String]) -> ExitCode {
    let argv = std::iter::once(format!("mcg-demo {name}")).chain(args.iter().cloned());
    let result = if name == "render" {
        let args = RenderArgs::try_parse_from(argv).unwrap_or_else(|e| e.exit());
        let started = Instant::now();
        run_render(&args).map(|paths| {
            for p in paths {
                println!("{}", p.display());
            }
            println!("rendered in {:.1} s", started.elapsed().as_secs_f64());
        })
    } else {
        let args = ScenesArgs::try_parse_from(argv).unwrap_or_else(|e| e.exit());
        scene_generator::write_built_in_scenes(&args.out)
            .map(|()| println!("scenes written to {}", args.out.display()))
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("mcg-demo: {error}");
            ExitCode::FAILURE
        }
    }
}

/// Turns off Mesa's Vulkan device-select layer where it would print errors: the layer (loaded
/// implicitly beside lavapipe and Mesa's GPU drivers) asks Wayland for the display's GPU, and
/// libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set in the environment." twice
/// where there is no desktop session (CI, ssh, containers), in a run that is fine. The layer
/// only reorders the adapters; wgpu enumerates and chooses them itself. Its own switch,
/// `NODEVICE_SELECT=1`, is set only where `XDG_RUNTIME_DIR` is unset and the user has not set
/// the switch either way.
#[allow(unsafe_code)]
fn quiet_mesa_device_select() {
    use std::env::{set_var, var_os};
    if var_os("XDG_RUNTIME_DIR").is_none() && var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: the first statement of `main`, before this process starts any thread, so no
        // other thread reads or writes the environment meanwhile (`set_var`'s requirement).
        unsafe { set_var("NODEVICE_SELECT", "1") };
    }
}

fn main() -> ExitCode {
    quiet_mesa_device_select();
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(name @ ("render" | "scenes")) = args.first().map(String::as_str) {
        return run_subcommand(name, &args[1..]);
    }
    let config = match parse_args(args) {
        Ok(Command::Run(config)) => config,
        Ok(Command::Help) => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(message) => {
            eprintln!("mcg-demo: {message}\n\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let started = Instant::now();
    match mcg_demo::run(&config) {
        Ok(index) => {
            println!(
                "report written to {} — open it in a browser ({:.1} s)",
                index.display(),
                started.elapsed().as_secs_f64()
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("mcg-demo: {error}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Command, String> {
        parse_args(args.iter().map(|s| (*s).to_owned()))
    }

    #[test]
    fn arguments() {
        let Ok(Command::Run(c)) = parse(&[]) else {
            panic!()
        };
        assert_eq!(
            (c.out_dir, c.samples),
            (PathBuf::from("out"), Config::DEFAULT_SAMPLES)
        );
        let Ok(Command::Run(c)) =
            parse(&["--out", "x", "--quick", "--seed", "0x10", "--no-progress"])
        else {
            panic!()
        };
        assert_eq!(
            (c.out_dir, c.samples, c.seed, c.progress),
            (PathBuf::from("x"), Config::QUICK_SAMPLES, 16, false)
        );
        let Ok(Command::Run(c)) = parse(&["--samples", "20_000"]) else {
            panic!()
        };
        assert_eq!(c.samples, 20_000);
        assert!(matches!(parse(&["--help"]), Ok(Command::Help)));
        assert!(parse(&["--out"]).is_err());
        assert!(parse(&["--bogus"]).is_err());
        assert!(parse(&["--samples", "ten"]).is_err());
    }
}
