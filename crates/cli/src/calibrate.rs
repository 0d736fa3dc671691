//! `jawtrack calibrate-marker`: the marker's true tag placements from a short recording of it
//! turned in front of the camera (`jawtrack_calibration`), written as a marker file of the
//! nominal schema, with the assembly errors found, per-tag corrections, and the reprojection
//! error before and after.

use crate::frames::{FrameSource, detect_marker_tags, open_frames};
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_calibration::{
    Calibration, CalibrationFrame, CalibrationOptions, Finding, FocalCheck, Kept, Refinement, SessionOptions,
    TagCorrection, calibrate, refine,
};
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `jawtrack calibrate-marker`.
#[derive(Args)]
pub(crate) struct CalibrateArgs {
    /// The marker file to start from (default: the nominal 12.7 mm marker). With a calibrated
    /// marker, its calibrated tags are kept as they are and only the others are placed (never
    /// worse: a tag moves only when the recordings fit its new place better).
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Camera intrinsics in pixels: fx,fy,cx,cy[,k1,k2].
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
    /// Refine tag edges in linear light, reading frames as sRGB (as phones deliver them).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    linear_edges: bool,
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
        frames.extend(detect_views(open_frames(Some(video), &[], None)?, &marker, &a.intrinsics, a.linear_edges)?);
    }
    if !a.frames.is_empty() {
        frames.extend(detect_views(open_frames(None, &a.frames, None)?, &marker, &a.intrinsics, a.linear_edges)?);
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
    calibrated.save(&a.out).with_context(|| format!("writing {}", a.out.display()))?;
    say!("wrote {}", a.out.display());
    Ok(())
}

/// Detects the marker's tags in every frame, with a progress bar, as views taken by `camera`.
pub(crate) fn detect_views(
    source: Box<dyn FrameSource>,
    marker: &Marker,
    camera: &CameraIntrinsics,
    linear_edges: bool,
) -> Result<Vec<CalibrationFrame>> {
    let frames = detect_marker_tags(source, marker, linear_edges)?;
    Ok(frames.into_iter().map(|f| CalibrationFrame { camera: *camera, tags: f.tags }).collect())
}

/// Prints what the calibration found and each tag's correction; warns about tags left nominal.
pub(crate) fn print_report(cal: &Calibration) {
    for b in &cal.bodies {
        say!(
            "{}: {} views; reprojection error {:.3} px with the marker given, {:.3} px calibrated",
            b.body,
            b.views,
            b.rms_before_px,
            b.rms_after_px
        );
        for f in b.findings.iter().filter(|f| !matches!(f, Finding::Uncalibrated { .. })) {
            say!("  assembly: {f}");
        }
        say!("  tag  views  shift x mm  shift y mm  turn °   px before  px after");
        for t in &b.tags {
            say!("{}", correction_row(t, "tag".len()));
        }
        for f in b.findings.iter().filter(|f| matches!(f, Finding::Uncalibrated { .. })) {
            eprintln!("warning: {f} (turn the marker to show that face from a few angles)");
        }
    }
    if let Some(focal) = cal.focal.filter(FocalCheck::looks_wrong) {
        eprintln!("warning: {}", intrinsics_warning(&focal, cal.bodies.iter().map(|b| b.rms_after_px)));
    }
}

/// One row of a table of tag corrections, under a header whose first column is `id_width` wide.
fn correction_row(t: &TagCorrection, id_width: usize) -> String {
    format!(
        "  {:>id_width$}  {:5}  {:10.3}  {:10.3}  {:6.2}   {:9.3}  {:8.3}",
        t.id,
        t.views,
        t.placement.shift_x,
        t.placement.shift_y,
        t.placement.rotation.to_degrees(),
        t.rms_before_px,
        t.rms_after_px
    )
}

/// Says what a session refinement changed, per body: the tags placed, those kept and why; on
/// standard output, or on standard error when standard output carries the recording.
pub(crate) fn print_refinement(r: &Refinement, seconds: f64, to_stderr: bool) {
    let mut text = String::new();
    for b in &r.bodies {
        let _ = writeln!(
            text,
            "{}: {} views of the session; reprojection error {:.3} px with the marker given, {:.3} px refined",
            b.body, b.views, b.rms_before_px, b.rms_after_px
        );
        for f in &b.findings {
            let _ = writeln!(text, "  assembly: {f}");
        }
        if b.placed.is_empty() {
            let _ = writeln!(text, "  no tag moved");
        } else {
            let _ = writeln!(text, "  placed  views  shift x mm  shift y mm  turn °   px before  px after");
        }
        for t in &b.placed {
            let _ = writeln!(text, "{}", correction_row(t, "placed".len()));
        }
        let gauge = b.kept.iter().filter(|k| matches!(k, Kept::Calibrated { .. })).count();
        if gauge > 0 {
            let _ = writeln!(text, "  {gauge} tags calibrated before kept as they were");
        }
        for k in b.kept.iter().filter(|k| matches!(k, Kept::NotBetter { .. })) {
            let _ = writeln!(text, "  {k}");
        }
    }
    let _ = write!(text, "refined the marker from the session in {seconds:.1} s");
    if to_stderr {
        eprintln!("{text}");
    } else {
        say!("{text}");
    }
    for k in r.bodies.iter().flat_map(|b| &b.kept).filter(|k| matches!(k, Kept::TooFewViewpoints { .. })) {
        eprintln!("warning: {k} (it stays nominal: film that face from a few angles)");
    }
    if let Some(focal) = r.focal.filter(FocalCheck::looks_wrong) {
        eprintln!("warning: {}", intrinsics_warning(&focal, r.bodies.iter().map(|b| b.rms_after_px)));
    }
}

/// What to say when the views point to another focal length than the one given: shared by
/// `calibrate-marker` and `track`.
pub(crate) fn intrinsics_warning(focal: &FocalCheck, residuals_px: impl IntoIterator<Item = f64>) -> String {
    let worst = residuals_px.into_iter().fold(0.0, f64::max);
    format!(
        "check --intrinsics: {focal}{}. Intrinsics for another resolution or another lens make every \
         distance wrong by about that factor; a calibrated marker's residual is normally 0.1-0.5 px",
        if worst > 0.0 { format!(", and the marker fits with {worst:.2} px") } else { String::new() }
    )
}
