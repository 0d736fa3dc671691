//! `jawtrack-bench`: the benchmarks a user runs, kept out of the product binary: the tracking
//! pipeline's speed, the benchtop accuracy experiments and the dense refinement (all in `jawtrack-tracker-bench`,
//! whose `bench-accuracy` binary adds the C reference's columns), and the phone link against a
//! real `jawtrack receive` process ([`link`]).
//!
//! `cargo run --release -p jawtrack-bench -- pipeline` (or `accuracy`, `dense`, `link`); `--help` lists
//! each one's flags.

mod link;

use clap::{Parser, Subcommand};

/// The benchmarks of JawTrack: tracking speed, benchtop accuracy on rendered frames, the phone link.
#[derive(Parser)]
#[command(name = "jawtrack-bench", version)]
struct BenchArgs {
    #[command(subcommand)]
    which: BenchKind,
}

#[derive(Subcommand)]
enum BenchKind {
    /// Time per frame of detection, pose and the whole pipeline; PnP per body beside OpenCV.
    Pipeline(jawtrack_tracker_bench::pipeline::PipelineArgs),
    /// The thesis's benchtop experiments on rendered frames: static grid, hinge, excursions,
    /// after calibrating the marker; tables, CSV, plots and a report.
    ///
    /// jawtrack links no C, so its report has our columns only. For the reference stack's
    /// columns (AprilTag C + OpenCV SQPnP) beside ours, give the same flags to
    /// `cargo run --release -p jawtrack-tracker-bench --bin bench-accuracy -- …`.
    Accuracy(Box<jawtrack_tracker_bench::accuracy::AccuracyArgs>),
    /// The dense (photometric) refinement beside the corner pipeline on the same rendered
    /// frames: error against the truth, a still jaw's jitter against its Cramér–Rao bound, time
    /// per body.
    Dense(jawtrack_tracker_bench::dense::DenseArgs),
    /// The phone link on loopback: a sustained stream against a real receiver (loss, CPU), then
    /// random, forged and replayed datagrams (none accepted, every one counted).
    Link(link::LinkBenchArgs),
}

fn main() {
    let a = BenchArgs::parse();
    let done = match &a.which {
        BenchKind::Pipeline(p) => jawtrack_tracker_bench::pipeline::run(p),
        BenchKind::Accuracy(a) => jawtrack_tracker_bench::accuracy::run(a),
        BenchKind::Dense(a) => jawtrack_tracker_bench::dense::run(a),
        BenchKind::Link(a) => link::run(a),
    };
    if let Err(e) = done {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// A bar labelled `what` over `len` items called `unit`: the tools' one bar.
fn progress_bar(what: &str, len: u64, unit: &str) -> jawtrack_progress::ProgressBar {
    jawtrack_progress::bar(what, Some(len), unit)
}
