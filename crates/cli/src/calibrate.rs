//! `jawtrack calibrate-marker`: the marker's true tag placements from a short recording of it
//! turned in front of the camera (`jawtrack_calibration`), written as a marker file of the
//! nominal schema, with the assembly errors found, per-tag corrections, and the reprojection
//! error before and after.

use crate::print::{print_refinement, print_report};
use crate::progress::detect_views;
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_calibration::{CalibrationOptions, SessionOptions, calibrate, refine};
use jawtrack_frames::open_frames;
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use std::path::PathBuf;

/// Arguments of `jawtrack calibrate-marker`.
#[derive(Args)]
pub(crate) struct CalibrateArgs {
    /// The marker file to start from (default: the nominal 12.7 mm marker). With a calibrated
    /// marker, its calibrated tags are kept as they are and only the others are placed (never
    /// worse: a tag moves only when the recordings fit its new place better).
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Camera intrinsics in pixels: fx,fy,cx,cy, or fx,fy,cx,cy,k1,k2 with distortion.
    #[arg(long, allow_hyphen_values = true)]
    intrinsics: CameraIntrinsics,
    /// Where to write the calibrated marker file.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// Views a tag needs to be calibrated (with another tag of its body in each).
    #[arg(long, default_value_t = 3)]
    min_views: usize,
    #[command(flatten)]
    edges: crate::flags::EdgeArgs,
    /// A video to read (needs ffmpeg and ffprobe on the PATH); give it again for more
    /// recordings: a tracked session's video places the tags a calibration recording missed.
    #[arg(long)]
    video: Vec<PathBuf>,
    /// Frames: image files (PNG, JPEG) or folders of them, the marker turned to show every face.
    #[arg(required_unless_present = "video")]
    frames: Vec<PathBuf>,
}

pub(crate) fn run(a: &CalibrateArgs) -> Result<()> {
    a.intrinsics.validate().context("--intrinsics")?;
    a.force.check_file(&a.out)?;
    if a.min_views == 0 {
        bail!("--min-views must be at least 1");
    }
    let marker = match &a.marker {
        Some(p) => Marker::load(p)?,
        None => Marker::default(),
    };
    let mut frames = Vec::new();
    for video in &a.video {
        frames.extend(detect_views(open_frames(Some(video), &[], None)?, &marker, &a.intrinsics, a.edges)?);
    }
    if !a.frames.is_empty() {
        frames.extend(detect_views(open_frames(None, &a.frames, None)?, &marker, &a.intrinsics, a.edges)?);
    }
    let options = CalibrationOptions { min_views: a.min_views, ..CalibrationOptions::default() };
    // The marker file names what it was calibrated from: the videos and the frames as given.
    let recordings: Vec<String> = a.video.iter().chain(&a.frames).map(|p| p.display().to_string()).collect();
    let calibrated = if marker.is_calibrated() {
        let started = std::time::Instant::now();
        let mut r = refine(&marker, &frames, &SessionOptions { calibration: options, ..SessionOptions::default() })?;
        r.name_recording(&recordings.join(", "));
        print_refinement(&r, started.elapsed().as_secs_f64(), false);
        r.marker
    } else {
        let mut cal = calibrate(&marker, &frames, &options)?;
        cal.name_recordings(&recordings);
        print_report(&cal);
        cal.marker
    };
    a.force.write_file(&a.out, (calibrated.to_json() + "\n").as_bytes())?;
    say!("wrote {}", a.out.display());
    Ok(())
}
