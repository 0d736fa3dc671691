//! `jawtrack bench`: starts the benchmark binary, `jawtrack-bench`, built beside this one.
//! Benchmarks are a separate program so that the product links none of them (and none of the
//! C reference libraries they compare against); this subcommand only finds and runs it.

use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use std::process::Command;

/// Arguments passed to `jawtrack-bench` unchanged.
#[derive(clap::Args)]
#[command(disable_help_flag = true)]
pub struct BenchArgs {
    /// `pipeline`, `accuracy`, `dense` or `link`, then that benchmark's flags (`jawtrack bench --help`
    /// lists them).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, num_args = 0..)]
    args: Vec<String>,
}

/// The environment variable naming the benchmark binary, for a build kept elsewhere.
const BENCH_ENV: &str = "JAWTRACK_BENCH";

pub fn run(a: &BenchArgs) -> Result<()> {
    let program = bench_program()?;
    let status = Command::new(&program)
        .args(if a.args.is_empty() { vec!["--help".to_owned()] } else { a.args.clone() })
        .status()
        .with_context(|| format!("starting {}", program.display()))?;
    match status.code() {
        Some(0) => Ok(()),
        Some(code) => std::process::exit(code),
        None => bail!("{} was stopped by a signal", program.display()),
    }
}

/// `$JAWTRACK_BENCH` if set, else `jawtrack-bench` beside this program.
fn bench_program() -> Result<PathBuf> {
    if let Some(p) = std::env::var_os(BENCH_ENV) {
        let p = PathBuf::from(p);
        if !p.is_file() {
            bail!("{BENCH_ENV} names {}, which is not a file: unset it or point it at jawtrack-bench", p.display());
        }
        return Ok(p);
    }
    let me = std::env::current_exe().context("finding this program")?;
    let beside = me.with_file_name(format!("jawtrack-bench{}", std::env::consts::EXE_SUFFIX));
    if !beside.is_file() {
        let release = if cfg!(debug_assertions) { "" } else { " --release" };
        bail!(
            "the benchmarks are a separate program, jawtrack-bench, and there is none beside {}: build it \
             (`cargo build{release} -p jawtrack-bench`) or run it directly \
             (`cargo run --release -p jawtrack-bench -- pipeline`)",
            me.display()
        );
    }
    Ok(beside)
}
