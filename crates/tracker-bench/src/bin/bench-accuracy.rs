//! `bench-accuracy`: the benchtop experiments of `jawtrack-bench accuracy`, same flags and
//! same report, with the reference stack's columns (AprilTag C + OpenCV SQPnP) beside ours.
//! Run it with `cargo run --release -p jawtrack-tracker-bench --bin bench-accuracy -- …`.

use clap::Parser;
use jawtrack_tracker_bench::accuracy::{self, AccuracyArgs};

/// The thesis's benchtop experiments on rendered frames (static grid, hinge, excursions,
/// after calibrating the marker), ours beside the reference stack (AprilTag C + OpenCV
/// SQPnP, when Python has cv2): tables, CSV, plots and a report.
#[derive(Parser)]
#[command(name = "bench-accuracy", long_about = None)]
struct Cli {
    #[command(flatten)]
    args: AccuracyArgs,
}

fn main() {
    let cli = Cli::parse();
    if let Err(e) = accuracy::run(&cli.args) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
