//! `jawtrack`: the command line of JawTrack. Each subcommand is a thin layer over a library
//! crate; this file only parses arguments, reports progress and prints results.

/// `println!` that ends the program quietly when stdout is closed (`jawtrack … | head`)
/// instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout(), $($arg)*).is_err() {
            std::process::exit(0);
        }
    }};
}

mod bench;
mod calibrate;
mod contacts;
mod demo;
mod detect;
mod export;
mod frames;
mod link;
mod linkbench;
mod live;
mod metrics;
mod occlusal;
mod register;
mod track;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use jawtrack_marker::{DEFAULT_EDGE_MM, Marker};
use jawtrack_pose::CameraIntrinsics;
use jawtrack_synth::{Realism, Resolution, SceneKind, SceneOptions, SynthConfig};
use std::path::{Path, PathBuf};

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
    /// Write the marker file of the ideal dodecahedron pair.
    Marker(MarkerArgs),
    /// Check a marker file and print what it describes.
    CheckMarker {
        /// The marker file.
        file: PathBuf,
    },
    /// Write the harness CAD: printable tag sheets (SVG, true mm), the body with its mounting
    /// post (STL) and the marker file.
    Harness(HarnessArgs),
    /// Render a synthetic scene: PNG frames and ground_truth.json.
    Synth(SynthArgs),
    /// Detect tag36h11 tags in images; one JSON line per image.
    Detect(detect::DetectArgs),
    /// Track recorded frames: both marker poses and the mandible in the maxilla, one JSON line
    /// per frame.
    Track(track::TrackArgs),
    /// Benchmarks: `bench pipeline` times the tracking pipeline and PnP beside OpenCV;
    /// `bench accuracy` runs the thesis's benchtop experiments on rendered frames.
    Bench(bench::BenchArgs),
    /// Calibrate the marker from frames of it turned in front of the camera: finds tags glued
    /// turned or on the wrong face, refines every tag's place, writes a marker file.
    CalibrateMarker(calibrate::CalibrateArgs),
    /// Register a marker to the scan of its printed harness (ICP of the dodecahedron from an
    /// initial guess), writing its entry of the registration file `track` reads.
    Register(register::RegisterArgs),
    /// Make a pairing key for the phone link (prints it; keep it secret).
    Keygen,
    /// Receive the phone's pose stream: record it, count losses, acknowledge, and optionally
    /// serve the live 3D viewer.
    Receive(link::ReceiveArgs),
    /// Simulate the phone: replay a recording to a receiver, with optional loss, reordering
    /// and duplication.
    Send(link::SendArgs),
    /// Replay a recording in the 3D viewer with a timeline.
    View(live::ViewArgs),
    /// Export a recording as CSV or as clean, time-ordered JSON lines.
    Export(export::ExportArgs),
    /// Plot a recording's lower-incisor path in the sagittal, frontal and transverse planes
    /// (SVG and PNG).
    Plot(export::PlotArgs),
    /// Measure a recording's lower-incisor motion: widest opening, left and right lateral
    /// excursion, protrusion and retrusion, and the envelope of motion (convex hull area) in
    /// the sagittal and frontal planes; optionally plot the envelopes.
    Metrics(metrics::MetricsArgs),
    /// Occlusal contacts over a recording: places the lower scan by each frame's pose, finds
    /// where the arches penetrate or come within a threshold, groups them into regions
    /// (centroid, area, depth, tooth), and writes contacts.jsonl, contact-frequency and depth
    /// PLYs and occlusal PNG views.
    Contacts(contacts::ContactsArgs),
}

#[derive(Args)]
struct HarnessArgs {
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    geometry: GeometryArgs,
    /// Length of the mounting post below the body's bottom vertex (mm).
    #[arg(long, default_value_t = 25.0, allow_hyphen_values = true)]
    post_length: f64,
    /// Diameter of the mounting post (mm).
    #[arg(long, default_value_t = 4.0, allow_hyphen_values = true)]
    post_diameter: f64,
}

/// The marker's printed geometry, shared by the commands that make a marker.
#[derive(Args)]
struct GeometryArgs {
    /// Edge length of the dodecahedron (mm).
    #[arg(long, default_value_t = DEFAULT_EDGE_MM, allow_hyphen_values = true)]
    edge: f64,
    /// Side of each tag's black-border square (mm); default: the largest that leaves a
    /// one-cell white margin on the face.
    #[arg(long, allow_hyphen_values = true)]
    tag_size: Option<f64>,
}

impl GeometryArgs {
    fn marker(&self) -> Result<Marker> {
        Ok(Marker::nominal(self.edge, self.tag_size)?)
    }
}

#[derive(Args)]
struct MarkerArgs {
    /// Where to write the marker file (JSON).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    geometry: GeometryArgs,
}

#[derive(Args)]
pub(crate) struct SynthArgs {
    /// Which scene: static, hinge, excursion or chew.
    #[arg(long)]
    scene: Option<SceneKind>,
    /// Output folder.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Frame size: 1080p or 4k.
    #[arg(long, default_value = "1080p")]
    resolution: Resolution,
    /// Seed of everything random (print errors, noise, tremor, clutter).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Camera intrinsics fx,fy,cx,cy[,k1,k2] (px); default: an iPhone wide camera.
    #[arg(long)]
    intrinsics: Option<CameraIntrinsics>,
    /// Marker file (default: the nominal 12.7 mm pair).
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Realism settings as JSON; fields left out keep their defaults.
    #[arg(long, conflicts_with = "clean")]
    realism: Option<PathBuf>,
    /// Exact geometry: no blur, noise, gamma, print error, occluders or glare.
    #[arg(long)]
    clean: bool,
    /// Frames per camera view (static scene).
    #[arg(long, default_value_t = 2)]
    frames_per_view: usize,
    /// Cycles per opening / glide (hinge, excursion, chew).
    #[arg(long, default_value_t = 2)]
    cycles: usize,
    /// Frame rate of the dynamic scenes (frames/s).
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
    /// Keep only every n-th frame.
    #[arg(long, default_value_t = 1)]
    stride: usize,
    /// Stop after this many frames.
    #[arg(long)]
    max_frames: Option<usize>,
    /// Instead of a scene, render a large tag and measure where its edges land (px).
    #[arg(long, conflicts_with_all = ["scene", "out"])]
    self_check: bool,
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(a) => demo::run(&a),
        Command::Marker(a) => marker(&a),
        Command::CheckMarker { file } => check_marker(&file),
        Command::Harness(a) => harness(&a),
        Command::Synth(a) => synth(&a),
        Command::Detect(a) => detect::run(&a),
        Command::Track(a) => track::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::CalibrateMarker(a) => calibrate::run(&a),
        Command::Register(a) => register::run(&a),
        Command::Keygen => {
            link::keygen();
            Ok(())
        }
        Command::Receive(a) => link::receive(&a),
        Command::Send(a) => link::send(&a),
        Command::View(a) => live::view(&a),
        Command::Export(a) => export::export(&a),
        Command::Plot(a) => export::plot(&a),
        Command::Metrics(a) => metrics::run(&a),
        Command::Contacts(a) => contacts::run(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn marker(a: &MarkerArgs) -> Result<()> {
    let m = a.geometry.marker()?;
    m.save(&a.out)?;
    let size = m.bodies[0].tags[0].size;
    say!("wrote {} (edge {} mm, tag size {:.4} mm, {} tags)", a.out.display(), m.edge, size, m.tags().count());
    Ok(())
}

fn harness(a: &HarnessArgs) -> Result<()> {
    let marker = a.geometry.marker()?;
    let params = jawtrack_harness::HarnessParams {
        post_length: a.post_length,
        post_diameter: a.post_diameter,
        ..jawtrack_harness::HarnessParams::default()
    };
    let written = jawtrack_harness::write_harness(&a.out, &marker, &params)?;
    for p in &written {
        say!("wrote {}", p.display());
    }
    say!("print the sheets at 100 % and check the 10 mm bar; see harness-cad/README.md for assembly");
    Ok(())
}

fn check_marker(file: &Path) -> Result<()> {
    let m = Marker::load(file)?;
    say!("{}: valid marker file, edge {} mm", file.display(), m.edge);
    for b in &m.bodies {
        let ids: Vec<String> = b.tags.iter().map(|t| t.id.to_string()).collect();
        say!("  {}: {} tags, ids {}", b.kind, b.tags.len(), ids.join(" "));
    }
    Ok(())
}

pub(crate) fn load_realism(a: &SynthArgs) -> Result<Realism> {
    if a.clean {
        return Ok(Realism::clean());
    }
    match &a.realism {
        None => Ok(Realism::default()),
        Some(p) => {
            let text = std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
            serde_json::from_str(&text).with_context(|| format!("{}: not a realism settings file", p.display()))
        }
    }
}

pub(crate) fn synth_config(a: &SynthArgs, scene: SceneKind) -> Result<SynthConfig> {
    let marker = match &a.marker {
        Some(p) => Marker::load(p)?,
        None => Marker::default(),
    };
    Ok(SynthConfig {
        scene,
        resolution: a.resolution,
        intrinsics: a.intrinsics,
        seed: a.seed,
        realism: load_realism(a)?,
        options: SceneOptions { frames_per_view: a.frames_per_view, cycles: a.cycles, fps: a.fps },
        marker,
        stride: a.stride,
        max_frames: a.max_frames,
    })
}

fn synth(a: &SynthArgs) -> Result<()> {
    if a.self_check {
        say!("side_px roll_deg rows  max_err_px rms_err_px");
        let mut worst: f64 = 0.0;
        for roll in [0.0, 7.0, 30.0, 45.0] {
            let c = jawtrack_synth::selfcheck::edge_self_check(400.0, roll);
            say!("{:7.0} {:8.1} {:5} {:10.4} {:10.4}", c.tag_side_px, roll, c.samples, c.max_error_px, c.rms_error_px);
            worst = worst.max(c.max_error_px);
        }
        if worst >= 0.05 {
            bail!("edge error {worst:.4} px exceeds 0.05 px");
        }
        say!("ok: every edge within {worst:.4} px of its projection");
        return Ok(());
    }
    let Some(scene) = a.scene else { bail!("--scene is required (static, hinge, excursion or chew)") };
    let Some(out) = &a.out else { bail!("--out DIR is required") };
    let config = synth_config(a, scene)?;
    let summary = render_with_progress(config, out)?;
    demo::print_scene_summary(scene, out, &summary);
    Ok(())
}

pub(crate) fn render_with_progress(config: SynthConfig, out: &Path) -> Result<jawtrack_synth::SceneSummary> {
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, {elapsed} elapsed, ~{eta} left")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_message(format!("rendering {}", config.scene.name()));
    let summary = jawtrack_synth::write_scene(config, out, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    Ok(summary)
}

/// A progress bar over `len` items, labelled `what`.
pub(crate) fn progress_bar(what: &str, len: usize) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len}, {elapsed} elapsed, ~{eta} left")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_message(what.to_owned());
    bar
}
