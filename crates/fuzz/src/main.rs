//! `jawtrack-fuzz`: runs the fuzz targets. `--list` names them; `TARGET --runs N` feeds one N
//! inputs; `--all` feeds every target. Any panic, hang past the time limit or broken
//! invariant stops the run with exit status 1, printing the input and saving it for
//! `--replay`.

use clap::Parser;
use jawtrack_fuzz::mutate::Shape;
use jawtrack_fuzz::run::{self, Found, OnHang, Options, Problem, Run, Tally, Target, Verdict};
use jawtrack_fuzz::targets;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Fuzzes JawTrack's parsers and its C frame door on the stable toolchain.
#[derive(Parser)]
#[command(name = "jawtrack-fuzz", about, long_about = None)]
struct Args {
    /// The target to run (see --list).
    #[arg(required_unless_present_any = ["list", "all", "self_test"], conflicts_with = "all")]
    target: Option<String>,
    /// Names every target and what it feeds.
    #[arg(long)]
    list: bool,
    /// Runs every target, one after another.
    #[arg(long)]
    all: bool,
    /// Inputs per target, the seeds included.
    #[arg(long, default_value_t = 100_000)]
    runs: u64,
    /// The random seed: the same seed and runs feed the same inputs.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// An input that runs longer than this (ms) is a hang.
    #[arg(long, default_value_t = 1000, value_name = "MS")]
    time_limit_ms: u64,
    /// Feeds this one saved input to the target instead, and says what happened.
    #[arg(long, value_name = "FILE", conflicts_with = "all")]
    replay: Option<PathBuf>,
    /// Where a failing input is saved.
    #[arg(long, value_name = "DIR", default_value = "target/fuzz-failures")]
    failures: PathBuf,
    /// Runs a built-in target that fails on purpose (panic, hang or invariant), to show the
    /// runner catches it.
    #[arg(long, hide = true, value_name = "KIND")]
    self_test: Option<String>,
}

/// Writes a line to standard output; a closed pipe ends the program quietly.
fn say(line: &str) {
    if let Err(e) = writeln!(std::io::stdout(), "{line}") {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        tell(&format!("error: writing to standard output: {e}"));
        std::process::exit(1);
    }
}

/// Writes a line to standard error, never panicking when it is closed.
fn tell(line: &str) {
    let _ = writeln!(std::io::stderr(), "{line}");
}

fn main() {
    let args = Args::parse();
    run::quiet_panics();
    let all = targets::all();
    if args.list {
        for t in &all {
            say(&format!("{:<13} {}", t.name, t.about));
        }
        return;
    }
    let chosen: Vec<Target> = if let Some(kind) = &args.self_test {
        match self_test(kind) {
            Some(t) => vec![t],
            None => fail(&format!("--self-test {kind}: expected panic, hang or invariant")),
        }
    } else if args.all {
        all
    } else {
        let name = args.target.as_deref().unwrap_or_default();
        match all.into_iter().find(|t| t.name == name) {
            Some(t) => vec![t],
            None => fail(&format!("no target named `{name}`: `jawtrack-fuzz --list` names them")),
        }
    };
    if let Some(file) = &args.replay {
        let input = std::fs::read(file).unwrap_or_else(|e| fail(&format!("{}: {e}", file.display())));
        match run::replay(&chosen[0], &input) {
            Ok(v) => say(&format!("{}: {} ({} bytes)", chosen[0].name, verdict(v), input.len())),
            Err(problem) => {
                say(&format!("{}: {}", chosen[0].name, describe(&problem)));
                std::process::exit(1);
            }
        }
        return;
    }
    let options = Options { runs: args.runs, seed: args.seed, time_limit: Duration::from_millis(args.time_limit_ms) };
    for target in &chosen {
        let on_hang = hang_reporter(target.name, args.failures.clone(), args.seed);
        let mut last_said = std::time::Instant::now();
        let progress = |t: &Tally| {
            if last_said.elapsed() > Duration::from_secs(10) {
                last_said = std::time::Instant::now();
                tell(&format!("{}: {} of {} inputs, {:.0}/s", target.name, t.inputs, args.runs, rate(t)));
            }
        };
        match run::fuzz(target, &options, on_hang, progress) {
            Ok(t) => {
                let note = target.note.map(|n| format!("; {}", n())).unwrap_or_default();
                say(&format!(
                    "{:<13} {} inputs ({:.1} % accepted) in {:.1} s, {:.0}/s, slowest {:.1} ms: no panic, hang or broken \
                     invariant{note}",
                    target.name,
                    t.inputs,
                    100.0 * t.accepted as f64 / t.inputs.max(1) as f64,
                    t.elapsed_s,
                    rate(&t),
                    1e3 * t.slowest_s
                ))
            }
            Err(found) => {
                report(target.name, &found.problem, &found, &args.failures, args.seed);
                std::process::exit(1);
            }
        }
    }
}

fn rate(t: &Tally) -> f64 {
    t.inputs as f64 / t.elapsed_s.max(1e-9)
}

fn verdict(v: Verdict) -> &'static str {
    match v {
        Verdict::Accepted => "accepted, its invariants held",
        Verdict::Refused => "refused with a clear error",
    }
}

fn describe(p: &Problem) -> String {
    match p {
        Problem::Panic(m) => format!("PANIC: {m}"),
        Problem::Invariant(m) => format!("BROKEN INVARIANT: {m}"),
    }
}

fn fail(message: &str) -> ! {
    tell(&format!("error: {message}"));
    std::process::exit(2);
}

/// Prints what failed and saves the input.
fn report(target: &str, problem: &Problem, found: &Found, dir: &Path, seed: u64) {
    tell(&format!("{target}: input {} (seed {seed}): {}", found.input_index, describe(problem)));
    show_input(target, &found.input, found.input_index, dir);
}

fn hang_reporter(target: &'static str, dir: PathBuf, seed: u64) -> OnHang {
    Box::new(move |input, index, ran| {
        tell(&format!("{target}: input {index} (seed {seed}): HANG: still running after {:.1} s", ran.as_secs_f64()));
        show_input(target, input, index, &dir);
        std::process::exit(1);
    })
}

/// The input as text when it is text (cut to 2,000 characters), else its first 512 bytes in
/// hex; and where it was saved, with the command that replays it.
fn show_input(target: &str, input: &[u8], index: u64, dir: &Path) {
    match std::str::from_utf8(input) {
        Ok(text) => {
            tell(&format!("input ({} bytes, as text): {:?}", input.len(), text.chars().take(2000).collect::<String>()))
        }
        Err(_) => {
            let hex: String = input.iter().take(512).map(|b| format!("{b:02x}")).collect();
            tell(&format!("input ({} bytes, hex): {hex}", input.len()));
        }
    }
    let file = dir.join(format!("{target}-{index}.bin"));
    match std::fs::create_dir_all(dir).and_then(|()| std::fs::write(&file, input)) {
        Ok(()) => tell(&format!(
            "saved to {}; replay: cargo run --release -p jawtrack-fuzz -- {target} --replay {}",
            file.display(),
            file.display()
        )),
        Err(e) => tell(&format!("could not save it to {}: {e}", file.display())),
    }
}

/// Targets that fail on purpose, for the runner's own test.
fn self_test(kind: &str) -> Option<Target> {
    fn seeds() -> Vec<Vec<u8>> {
        vec![b"seed".to_vec()]
    }
    let (name, run): (&'static str, Run) = match kind {
        "panic" => {
            ("self-test-panic", |d| if d.len() != 4 { panic!("a planted panic") } else { Ok(Verdict::Accepted) })
        }
        "hang" => ("self-test-hang", |d| {
            if d.len() != 4 {
                std::thread::sleep(Duration::from_secs(30));
            }
            Ok(Verdict::Accepted)
        }),
        "invariant" => ("self-test-invariant", |d| {
            if d.len() != 4 { Err("a planted invariant".into()) } else { Ok(Verdict::Accepted) }
        }),
        _ => return None,
    };
    Some(Target { name, about: "", shape: Shape::Binary, max_len: 64, seeds, run, note: None })
}
