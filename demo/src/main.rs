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

use clap::{Arg, CommandFactory, FromArgMatches, Parser};
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
        let args = render_command()
            .try_get_matches_from(argv)
            .and_then(|m| RenderArgs::from_arg_matches(&m))
            .unwrap_or_else(|e| e.exit());
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

/// `render`'s clap command with its help in plain text: the options' help comes from the
/// doc comments of [`RenderArgs`] and its value enums, whose intra-doc links (`` [`x`] ``,
/// `` [`x`](path) ``, `[text](path)`) rustdoc renders and a terminal would show as written.
/// An option's possible values are listed in its cleaned help instead of by clap.
fn render_command() -> clap::Command {
    RenderArgs::command().mut_args(|arg| {
        let values = arg.get_possible_values();
        let mut help = arg.get_help().map(|h| plain_text(&h.to_string()));
        let mut long = arg.get_long_help().map(|h| plain_text(&h.to_string()));
        let hidden = arg.is_hide_possible_values_set();
        let listed = !hidden && values.iter().any(|v| v.get_help().is_some());
        if listed {
            let names: Vec<&str> = values.iter().map(|v| v.get_name()).collect();
            let list: Vec<String> = values
                .iter()
                .map(|v| {
                    let text = v.get_help().map(|h| plain_text(&h.to_string()));
                    format!("- {}: {}", v.get_name(), text.unwrap_or_default())
                })
                .collect();
            long = long
                .or_else(|| help.clone())
                .map(|h| format!("{h}\n\nPossible values:\n{}", list.join("\n")));
            help = help.map(|h| format!("{h} [possible values: {}]", names.join(", ")));
        }
        let mut arg: Arg = arg.hide_possible_values(hidden || listed);
        if let Some(h) = help {
            arg = arg.help(h);
        }
        if let Some(h) = long {
            arg = arg.long_help(h);
        }
        arg
    })
}

/// `text` with rustdoc's link syntax taken out: `` [`x`] `` and `` [`x`](path) `` become
/// `` `x` ``, `[text](path)` becomes `text`; other brackets stay.
fn plain_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find('[') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let Some(close) = after.find(']') else {
            out.push_str(&rest[open..]);
            return out;
        };
        let inner = &after[..close];
        let tail = &after[close + 1..];
        let code = inner.len() >= 2 && inner.starts_with('`') && inner.ends_with('`');
        let target = tail
            .strip_prefix('(')
            .and_then(|t| t.find(')').map(|end| &t[end + 1..]))
            .filter(|_| !inner.is_empty() && !inner.contains('['));
        match target {
            Some(after_target) => {
                out.push_str(inner);
                rest = after_target;
            }
            None if code => {
                out.push_str(inner);
                rest = tail;
            }
            None => {
                out.push('[');
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
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

    #[test]
    fn plain_text_takes_out_rustdoc_links_only() {
        assert_eq!(plain_text("see [`gpu`]; ok"), "see `gpu`; ok");
        assert_eq!(
            plain_text("[`Bvh::occluded`](super::bvh::Bvh::occluded)."),
            "`Bvh::occluded`."
        );
        assert_eq!(
            plain_text("the [paper's rule](crate::x) here"),
            "the paper's rule here"
        );
        assert_eq!(
            plain_text("[0, 1) and [a] and [`x`"),
            "[0, 1) and [a] and [`x`"
        );
        assert_eq!(plain_text("no links"), "no links");
    }

    /// `render --help` and `-h` show no link syntax, and still list every method with its help.
    #[test]
    fn render_help_is_plain_text_with_the_possible_values() {
        let mut cmd = render_command();
        let long = cmd.render_long_help().to_string();
        let short = cmd.render_help().to_string();
        for help in [&long, &short] {
            assert!(!help.contains("[`"), "{help}");
            assert!(!help.contains("]("), "{help}");
        }
        assert!(long.contains("- mcpg-nee: MCPG's guide"), "{long}");
        assert!(!long.contains("[possible values"), "{long}");
        assert!(
            short.contains("[possible values: bsdf, nee, mcpg"),
            "{short}"
        );
        // Parsing is unchanged.
        let m = render_command()
            .try_get_matches_from(["render", "--scene", "x.gltf", "--method", "mcpg"])
            .expect("parses");
        let args = <mcg_demo::render::RenderArgs as clap::FromArgMatches>::from_arg_matches(&m)
            .expect("arguments");
        assert_eq!(args.method, mcg_demo::render::cpu::Method::Mcpg);
    }
}
