//! `jawtrack calibrate-camera`: the camera's intrinsics and rolling-shutter readout from a
//! short video of the markers waved in front of it (`jawtrack_camera_calibration`), each with
//! its uncertainty, written as JSON and printed as the flags `jawtrack track` takes.

use crate::progress::detect_marker_tags;
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_camera_calibration::{CalibratedAt, CameraCalibrationOptions, CameraFile, CameraFrame, calibrate_camera};
use jawtrack_frames::open_frames;
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use std::path::PathBuf;

/// Arguments of `jawtrack calibrate-camera`.
#[derive(Args)]
pub(crate) struct CalibrateCameraArgs {
    /// A video of the markers waved in front of the camera, filmed as the sessions will be
    /// (same phone, lens, resolution and orientation; no zoom or stabilisation). Needs ffmpeg
    /// and ffprobe on the PATH; each frame keeps its own presentation time.
    #[arg(long, conflicts_with = "frames")]
    video: Option<PathBuf>,
    /// Frames instead of a video: image files (PNG, JPEG) or folders of them, consecutive
    /// frames of one recording in name order, timed by --fps.
    #[arg(required_unless_present = "video")]
    frames: Vec<PathBuf>,
    /// Frame rate (frames/s), timing image frame i at i / fps s: required with image frames,
    /// since the readout is measured against the motion between frames; with --video it
    /// replaces the stored times.
    #[arg(long, allow_hyphen_values = true)]
    fps: Option<f64>,
    /// A first guess of the intrinsics, fx,fy,cx,cy or fx,fy,cx,cy,k1,k2 (px), e.g. another
    /// resolution's scaled. Default: from the image size; the focal length is scanned over a
    /// factor of 3 either way, so the guess need not be close.
    #[arg(long, allow_hyphen_values = true)]
    intrinsics: Option<CameraIntrinsics>,
    /// The marker file (default: the nominal 12.7 mm pair). A calibrated marker
    /// (`calibrate-marker`) removes its print errors from the camera's.
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Where to write the result (JSON: the intrinsics, the readout, each 1σ, the residual).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// Frames (showing a marker in a run of neighbouring frames) needed at least.
    #[arg(long, default_value_t = 20)]
    min_frames: usize,
    /// Refuse a fit whose RMS corner residual exceeds this (px).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    max_rms_px: f64,
    #[command(flatten)]
    edges: crate::flags::EdgeArgs,
    /// The lens position (AVFoundation's 0 near – 1 far) focus was locked at while filming,
    /// recorded with the calibration: intrinsics belong to a focus, and `jawtrack track
    /// --camera` warns when a recording's differs. Default: the --like recording's.
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    lens_position: Option<f64>,
    /// The zoom filmed at (1, or the sensor's native 2× crop), recorded likewise. Default: the
    /// --like recording's.
    #[arg(long, value_name = "Z", allow_hyphen_values = true)]
    zoom: Option<f64>,
    /// The JawTrack app's recording made with the calibration video: its lens position and zoom.
    #[arg(long, value_name = "RECORDING")]
    like: Option<PathBuf>,
}

pub(crate) fn run(a: &CalibrateCameraArgs) -> Result<()> {
    a.force.check_file(&a.out)?;
    if let Some(fps) = a.fps
        && !(fps.is_finite() && fps > 0.0)
    {
        bail!("--fps must be a positive number of frames per second, got {fps}");
    }
    if a.video.is_none() && a.fps.is_none() {
        bail!("--fps is required with image frames: the readout is measured against the time between frames");
    }
    if let Some(k) = &a.intrinsics {
        k.validate().context("--intrinsics")?;
    }
    if a.min_frames < 3 {
        bail!("--min-frames must be at least 3, got {}", a.min_frames);
    }
    if !(a.max_rms_px.is_finite() && a.max_rms_px > 0.0) {
        bail!("--max-rms-px must be a positive number of pixels, got {}", a.max_rms_px);
    }
    let calibrated_at = calibrated_at(a)?;
    let marker = match &a.marker {
        Some(p) => Marker::load(p)?,
        None => Marker::default(),
    };
    let (frames, width, height) = detect(a, &marker)?;
    say!(
        "detected the marker in {} of {} frames ({width}×{height})",
        frames.iter().filter(|f| !f.tags.is_empty()).count(),
        frames.len()
    );
    let options = CameraCalibrationOptions {
        initial: a.intrinsics,
        min_frames: a.min_frames,
        max_rms_px: a.max_rms_px,
        ..CameraCalibrationOptions::default()
    };
    let started = std::time::Instant::now();
    let c = calibrate_camera(&frames, width, height, &marker, &options)?;
    say!("calibrated in {:.1} s from {c}", started.elapsed().as_secs_f64());
    let file = CameraFile::new(c, calibrated_at);
    a.force.write_file(&a.out, (file.to_json() + "\n").as_bytes())?;
    say!("wrote {}", a.out.display());
    say!("track with: jawtrack track --camera {} … (or {})", a.out.display(), file.track_flags);
    Ok(())
}

/// The lens position and zoom filmed at: the flags, else the --like recording's capture.
fn calibrated_at(a: &CalibrateCameraArgs) -> Result<CalibratedAt> {
    let like = match &a.like {
        Some(p) => jawtrack_recording::open(p)?.header.and_then(|h| h.capture),
        None => None,
    };
    if a.like.is_some() && like.is_none() && (a.lens_position.is_none() || a.zoom.is_none()) {
        tell!("note: --like's recording has no capture plan: its lens position and zoom are not known");
    }
    let recorded = CalibratedAt {
        lens_position: like.as_ref().and_then(|c| c.lens_position),
        zoom: like.as_ref().map(|c| c.zoom),
    };
    Ok(CalibratedAt { lens_position: a.lens_position, zoom: a.zoom }.or_recorded(recorded)?)
}

/// Detects the marker's tags in every frame, with a progress bar; the frames and their size.
fn detect(a: &CalibrateCameraArgs, marker: &Marker) -> Result<(Vec<CameraFrame>, u32, u32)> {
    let frames = detect_marker_tags(open_frames(a.video.as_deref(), &a.frames, a.fps)?, marker, a.edges)?;
    let (w, h) = jawtrack_frames::one_size(&frames)?;
    Ok((frames.into_iter().map(|f| CameraFrame { t: f.t, tags: f.tags }).collect(), w, h))
}
