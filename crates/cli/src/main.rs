//! `jawtrack`: the command line of JawTrack. Each subcommand is a thin layer over a library
//! crate; this file only parses arguments, reports progress and prints results.

/// `println!` that ends the program quietly when stdout is closed (`jawtrack … | head`), and
/// with an error (exit 1) when the write fails otherwise (a full disk, a bad redirect): a
/// pairing key or a clinical number that did not reach its file must not look written.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($arg)*) {
            crate::stdout_failed(&e);
        }
    }};
}

/// `eprintln!` that never panics. With standard error closed (`jawtrack … 2>&1 | head -1`)
/// `eprintln!` panics (exit 101, its message lost on the stream that is gone); this drops the
/// message instead, and the command ends with its own status.
macro_rules! tell {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// Ends the program after a failed write to standard output: quietly for a closed pipe, as an
/// error otherwise.
fn stdout_failed(e: &std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    tell!("error: writing to standard output: {e}");
    std::process::exit(1);
}

mod articulator;
mod bench;
mod calibrate;
mod calibrate_camera;
mod contacts;
mod demo;
mod detect;
mod export;
mod flags;
mod hinge_axis;
mod link;
mod marker;
mod metrics;
mod numbers;
mod output;
mod plan;
mod points;
mod print;
mod progress;
mod register;
mod report;
mod synth;
mod track;
mod viewer;

pub(crate) use progress::progress_bar;

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// JawTrack: 6-DoF jaw motion from two AprilTag dodecahedra filmed by a phone.
#[derive(Parser)]
#[command(name = "jawtrack", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a short session on built-in defaults and summarise it (no phone needed).
    Demo(demo::DemoArgs),
    /// Write the marker file of an ideal marker pair (dodecahedrons by default).
    Marker(marker::MarkerArgs),
    /// Check a marker file and print what it describes.
    CheckMarker {
        /// The marker file.
        file: PathBuf,
    },
    /// Write the harness CAD: printable tag sheets (SVG, true mm), the body with its mounting
    /// post (STL) and the marker file.
    Harness(marker::HarnessArgs),
    /// Render a synthetic scene: PNG frames and ground_truth.json.
    Synth(synth::SynthArgs),
    /// Detect tag36h11 tags in images; one JSON line per image.
    Detect(detect::DetectArgs),
    /// Track recorded frames: both marker poses and the mandible in the maxilla, one JSON line
    /// per frame.
    Track(track::TrackArgs),
    /// Calibrate the marker from frames of it turned in front of the camera: finds tags glued
    /// turned or on the wrong face, refines every tag's place, writes a marker file.
    CalibrateMarker(calibrate::CalibrateArgs),
    /// Calibrate the camera from a video of the markers waved in front of it: focal lengths,
    /// principal point, radial distortion and the rolling shutter's readout, each with its
    /// uncertainty; prints the flags `track` takes.
    CalibrateCamera(calibrate_camera::CalibrateCameraArgs),
    /// Where and how to film with a phone: camera, format, zoom and the distance to hold it at,
    /// beyond where its lens can focus, with focus locked there.
    Plan(plan::PlanArgs),
    /// Register a marker to the scan of its printed harness (ICP of the marker's solid from an
    /// initial guess), writing its entry of the registration file `track` reads.
    Register(register::RegisterArgs),
    /// Make a pairing key for the phone link (prints it; keep it secret).
    Keygen,
    /// Receive the phone's pose stream: record it, count losses, acknowledge, and optionally
    /// serve the live 3D viewer.
    Receive(link::receive::ReceiveArgs),
    /// Simulate the phone: replay a recording to a receiver, with optional loss, reordering
    /// and duplication.
    Send(link::send::SendArgs),
    /// Replay a recording in the 3D viewer with a timeline.
    View(viewer::ViewArgs),
    /// Export a recording as CSV or as clean, time-ordered JSON lines.
    Export(export::ExportArgs),
    /// Plot a recording's lower-incisor path in the sagittal, frontal and transverse planes
    /// (SVG and PNG).
    Plot(export::PlotArgs),
    /// Measure a recording's lower-incisor motion: widest opening, left and right lateral
    /// excursion, protrusion and retrusion, Posselt's border as traced in the sagittal, frontal
    /// and transverse planes (and the convex hulls); optionally plot them.
    Metrics(metrics::MetricsArgs),
    /// Write or check the anatomical points file: the occlusal plane, midline, lower incisal
    /// point and condyles picked on the upper scan, which replace the standard harness mounting.
    Points(points::PointsArgs),
    /// The kinematic hinge axis of a recorded opening: a point and direction in the maxilla
    /// marker's frame (and the upper scan's, given a registration), with its uncertainty.
    HingeAxis(hinge_axis::HingeAxisArgs),
    /// Articulator values from border movements: sagittal condylar inclination, Bennett angle
    /// and immediate side shift per condyle, protrusive and lateral incisal guidance.
    Articulator(articulator::ArticulatorArgs),
    /// One self-contained HTML report of a session (and a PDF through headless Chromium): session
    /// and calibration, quality, incisor metrics, Posselt's border movements, condylar paths, the
    /// hinge axis, articulator values and CO–MI of the windows given, and occlusal contacts.
    Report(report::ReportArgs),
    /// Occlusal contacts over a recording: places the lower scan by each frame's pose, finds
    /// where the arches penetrate or come within a threshold, groups them into regions
    /// (centroid, area, depth, tooth), and writes contacts.jsonl, contact-frequency and depth
    /// PLYs and occlusal PNG views.
    Contacts(contacts::ContactsArgs),
    /// Run a benchmark (`pipeline`, `accuracy`, `link`): starts `jawtrack-bench`, a separate
    /// program built beside this one, so that the product links no benchmark.
    Bench(bench::BenchArgs),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(a) => demo::run(&a),
        Command::Marker(a) => marker::marker(&a),
        Command::CheckMarker { file } => marker::check_marker(&file),
        Command::Harness(a) => marker::harness(&a),
        Command::Synth(a) => synth::run(&a),
        Command::Detect(a) => detect::run(&a),
        Command::Track(a) => track::run(&a),
        Command::CalibrateMarker(a) => calibrate::run(&a),
        Command::CalibrateCamera(a) => calibrate_camera::run(&a),
        Command::Plan(a) => plan::run(&a),
        Command::Register(a) => register::run(&a),
        Command::Keygen => {
            link::keygen();
            Ok(())
        }
        Command::Receive(a) => link::receive::run(&a),
        Command::Send(a) => link::send::run(&a),
        Command::View(a) => viewer::view(&a),
        Command::Export(a) => export::export(&a),
        Command::Plot(a) => export::plot(&a),
        Command::Metrics(a) => metrics::run(&a),
        Command::Points(a) => points::run(&a),
        Command::HingeAxis(a) => hinge_axis::run(&a),
        Command::Articulator(a) => articulator::run(&a),
        Command::Report(a) => report::run(&a),
        Command::Contacts(a) => contacts::run(&a),
        Command::Bench(a) => bench::run(&a),
    };
    if let Err(e) = result {
        tell!("error: {e:#}");
        std::process::exit(1);
    }
}
