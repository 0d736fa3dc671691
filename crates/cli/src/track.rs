//! `jawtrack track`: tracks recorded frames (image files, folders of them sorted by name, or a
//! video decoded by ffmpeg) and writes one JSON line per frame in the recording schema
//! (`jawtrack_recording`), after a header line naming the camera, marker and settings. Every
//! line is flushed as it is written, so a killed run leaves a readable file. The run and the
//! rules of which camera, marker and settings apply are `jawtrack_offline::track`'s; this file
//! gives it the flags, draws its bars and prints what it says.

use anyhow::Result;
use clap::Args;
use jawtrack_calibration::Refinement;
use jawtrack_offline::{OfflineError, Pass, Said, TrackEvents, TrackOptions, track};
use jawtrack_pose::CameraIntrinsics;
use jawtrack_progress::ProgressBar;
use jawtrack_recording::create_file;
use jawtrack_tracker::PoseRefinement;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `jawtrack track`.
#[derive(Args)]
pub(crate) struct TrackArgs {
    /// The marker file (nominal or calibrated); default: the --like recording's marker, else
    /// the nominal 12.7 mm marker.
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Camera intrinsics in pixels: fx,fy,cx,cy or fx,fy,cx,cy,k1,k2 (pixel centres at integer
    /// coordinates); default: the --camera file's, else the --like recording's.
    #[arg(long, allow_hyphen_values = true, required_unless_present_any = ["like", "camera"])]
    intrinsics: Option<CameraIntrinsics>,
    /// The camera file `jawtrack calibrate-camera` wrote: its intrinsics and readout (each
    /// unless given), and the lens position and zoom it was calibrated at, which the
    /// recording's are checked against (--lens-position, --zoom, or the --like recording's).
    #[arg(long, value_name = "CAMERA_JSON")]
    camera: Option<PathBuf>,
    /// The lens position (AVFoundation's 0 near – 1 far) the frames were filmed at, to check
    /// against the --camera file's; default: the --like recording's.
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    lens_position: Option<f64>,
    /// The zoom the frames were filmed at (1, or a native crop), to check likewise.
    #[arg(long, value_name = "Z", allow_hyphen_values = true)]
    zoom: Option<f64>,
    /// Track as a recording was made: its header's intrinsics, readout, exposure (else its
    /// frames' median exposure) and marker, each unless given here. For re-tracking the video
    /// the iPhone app recorded beside its poses (`--video session.mov --like session.jsonl`).
    #[arg(long, value_name = "RECORDING")]
    like: Option<PathBuf>,
    /// Registration of the markers to the tooth scans (JSON); adds
    /// `maxilla_scan_from_mandible_scan` to every line.
    #[arg(long)]
    registration: Option<PathBuf>,
    /// Frame rate, timing frame `i` at `i / fps` s; default 30 for images, while a video's
    /// frames keep their own presentation times (right for variable frame rates too).
    #[arg(long)]
    fps: Option<f64>,
    /// The camera's rolling-shutter readout, first row to last (ms; 0 = a global shutter):
    /// each corner is then carried from its row's time to the frame's, so both markers are
    /// solved at the same instant. iPhone main cameras read in about 2.4 ms (16 Pro Max) to
    /// 9 ms (14 Pro); on rendered chewing, ignoring a 5 ms readout made the error 13× larger.
    /// Frames are taken as the camera stored them (rows as read), as with --video. Recorded
    /// in the header. Default: the --like recording's, else 0.
    #[arg(long, value_name = "MS", allow_hyphen_values = true)]
    readout_ms: Option<f64>,
    /// The exposure the frames were taken with (ms; default 8.3, a phone's indoor 1/120 s),
    /// recorded in the header: with the markers' tracked velocity it predicts how far their
    /// tags smear, and frames smeared 3 px or more have their edges fitted as motion ramps.
    /// Keep exposures short while the jaw moves: 2 ms leaves a chewing jaw nearly sharp.
    #[arg(long, value_name = "MS", allow_hyphen_values = true)]
    exposure_ms: Option<f64>,
    /// Decimation for quad finding: 1, 1.5, 2, 3 or 4.
    #[arg(long, default_value_t = 2.0)]
    decimate: f32,
    /// Threads: the detector's, and with `--refine dense` the refinement's (bodies and pixels).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    #[command(flatten)]
    edges: crate::flags::EdgeArgs,
    /// Once tracked, search where the markers are expected (whole every 30th frame or on a loss).
    #[arg(long, alias = "roi", default_value_t = true, action = clap::ArgAction::Set)]
    region_search: bool,
    /// With --region-search: once tracked, look for each tag first where the poses predict it,
    /// the region only when a tag the last frame used is missing, the frame is smeared or blurred,
    /// the tags moved far, or the tone curve is fitted (a tracked 1080p frame in 60 % of the time).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    predict_tags: bool,
    /// Smooth the jaw pose (One-Euro filter; never more than one frame of lag).
    #[arg(long)]
    smooth: bool,
    /// `dense` refines each body's corner pose from every pixel of its tags (slow; where it
    /// fails, the corner pose stands, flagged `dense_failed`; docs/dense.md).
    #[arg(long, value_name = "corners|dense", default_value_t = PoseRefinement::Corners)]
    refine: PoseRefinement,
    /// Output file (JSON lines); `-` for standard output.
    #[arg(long)]
    out: PathBuf,
    /// After tracking, place the tags the marker's calibration left nominal (or every tag, for
    /// a nominal marker) from this session's own frames, keeping calibrated tags as they are;
    /// write the refined marker here and the recording from the refined marker. A tag keeps
    /// its place unless the session fits a new one better. An existing file here is replaced
    /// only with --force, as --out is.
    #[arg(long, value_name = "MARKER_OUT")]
    refine_marker: Option<PathBuf>,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// A video file to track instead of images (needs ffmpeg and ffprobe on the PATH). Frames
    /// are read as stored, whatever rotation the file asks players to show them with.
    #[arg(long, conflicts_with = "frames")]
    video: Option<PathBuf>,
    /// Frames: image files (PNG, JPEG) or folders of them, taken in name order.
    #[arg(required_unless_present = "video")]
    frames: Vec<PathBuf>,
}

impl TrackArgs {
    /// The flags as the library's options.
    fn options(&self) -> TrackOptions {
        TrackOptions {
            marker: self.marker.clone(),
            intrinsics: self.intrinsics,
            camera: self.camera.clone(),
            lens_position: self.lens_position,
            zoom: self.zoom,
            like: self.like.clone(),
            registration: self.registration.clone(),
            fps: self.fps,
            readout_ms: self.readout_ms,
            exposure_ms: self.exposure_ms,
            decimate: self.decimate,
            threads: self.threads,
            linear_edges: self.edges.linear_edges,
            tone: self.edges.tone,
            region_search: self.region_search,
            predict_tags: self.predict_tags,
            smooth: self.smooth,
            refine: self.refine,
            out: self.out.clone(),
            refine_marker: self.refine_marker.clone(),
            video: self.video.clone(),
            frames: self.frames.clone(),
        }
    }
}

/// Draws a run's bars and prints what it says; refuses outputs that exist and opens `--out`.
struct Printed<'a> {
    a: &'a TrackArgs,
    bar: Option<ProgressBar>,
}

impl TrackEvents for Printed<'_> {
    fn said(&mut self, said: Said) {
        let line = match said {
            Said::Note(n) => format!("note: {n}"),
            Said::Warning(w) => format!("warning: {w}"),
            Said::Wrote(w) => w,
        };
        match &self.bar {
            Some(bar) => bar.suspend(|| tell!("{line}")),
            None => tell!("{line}"),
        }
    }
    fn pass(&mut self, pass: Pass, frames: Option<u64>) {
        let what = match pass {
            Pass::Only => "tracking",
            Pass::First => "tracking (1 of 2)",
            Pass::Second => "tracking (2 of 2)",
        };
        self.bar = Some(crate::progress::bar(what, frames, "frames"));
    }
    fn frame(&mut self) {
        self.bar.iter().for_each(|b| b.inc(1));
    }
    fn pass_done(&mut self) {
        self.bar.take().iter().for_each(ProgressBar::finish_and_clear);
    }
    fn ready(&mut self) -> Result<(), OfflineError> {
        let refused = |e: anyhow::Error| OfflineError::Caller(e.into());
        let stdout = self.a.out.as_os_str() == "-";
        for path in std::iter::once(&self.a.out).filter(|_| !stdout).chain(&self.a.refine_marker) {
            self.a.force.check_file(path).map_err(refused)?;
        }
        Ok(())
    }
    fn refined(&mut self, refinement: &Refinement, seconds: f64) {
        // With `--out -` the recording is standard output: the report goes to standard error.
        crate::print::print_refinement(refinement, seconds, self.a.out.as_os_str() == "-");
    }
    fn output(&mut self) -> Result<Box<dyn Write>, OfflineError> {
        let a = self.a;
        if a.out.as_os_str() == "-" {
            return Ok(Box::new(std::io::stdout()));
        }
        let file = create_file(&a.out, a.force.overwrite());
        Ok(Box::new(file.map_err(|e| OfflineError::Caller(a.force.explain(e).into()))?))
    }
}

pub(crate) fn run(a: &TrackArgs) -> Result<()> {
    let mut tracked = track(&a.options(), &mut Printed { a, bar: None })?;
    tell!("tracked {} frames: {}; poses in {}", tracked.frames, tracked.summary.describe(), a.out.display());
    tell!("tone curve: {}", tracked.tone.describe());
    tracked.warnings.iter().for_each(|w| tell!("warning: {w}"));
    Ok(())
}
