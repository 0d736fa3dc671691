//! `jawtrack bench`: the benchmarks a user can run from the product binary, which links no C:
//! the tracking pipeline's speed and the benchtop accuracy experiments (both in
//! `jawtrack-tracker-bench`, which adds the C reference in its own binary), and the phone link
//! against a real receiver process ([`link`]).

mod link;

use anyhow::Result;
use clap::{Args, Subcommand};

/// Arguments of `jawtrack bench`.
#[derive(Args)]
pub(crate) struct BenchArgs {
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
    /// The phone link on loopback: a sustained stream against a real receiver (loss, CPU), then
    /// random, forged and replayed datagrams (none accepted, every one counted).
    Link(link::LinkBenchArgs),
}

pub(crate) fn run(a: &BenchArgs) -> Result<()> {
    match &a.which {
        BenchKind::Pipeline(p) => jawtrack_tracker_bench::pipeline::run(p),
        BenchKind::Accuracy(a) => jawtrack_tracker_bench::accuracy::run(a),
        BenchKind::Link(a) => link::run(a),
    }
}
