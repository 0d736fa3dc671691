//! `jawtrack demo`: the main job on built-in defaults. It renders a short hinge session with
//! the synthetic rig, detects the tags in every frame and compares them with the ground truth,
//! then tracks the jaw (with the nominal marker file and with the marker as printed), reports
//! the mandible-in-maxilla error and the motion in plain words, and plots the incisor's path.
//! The steps are `jawtrack_demo`'s; this file renders, calibrates and prints.

use crate::print::print_scene_summary;
use crate::progress::{detect_views, render_with_progress};
use anyhow::Result;
use clap::Args;
use jawtrack_calibration::{CalibrationOptions, Finding, calibrate};
use jawtrack_demo::{Motion, TrackingCheck, calibration_scene, hinge_scene, read_truth};
use jawtrack_marker::Marker;
use jawtrack_synth::{GroundTruth, SceneKind};
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack demo`.
#[derive(Args)]
pub(crate) struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub(crate) fn run(a: &DemoArgs) -> Result<()> {
    say!("JawTrack demo: rendering a hinge-opening session (10–40 mm) at 1080p with the synthetic rig…");
    let summary = render_with_progress(hinge_scene(a.seed), &a.out)?;
    print_scene_summary(SceneKind::Hinge, &a.out, &summary);
    let truth = read_truth(&a.out)?;
    let d = jawtrack_demo::check_detection(&a.out, &truth)?;
    say!(
        "detection: {} of {} detectable tags found; corner error against ground truth median {:.3} px, 90th percentile {:.3} px; {:.0} ms per frame (median, one thread)",
        d.found,
        d.want,
        d.corner_error_median_px,
        d.corner_error_p90_px,
        d.ms_median
    );
    let calibrated = calibrate_from_recording(a)?;
    track_and_compare(&a.out, &truth, calibrated)?;
    Ok(())
}

/// Renders a calibration recording of the same printed marker (same seed, so the same print
/// errors), calibrates the marker from it as `jawtrack calibrate-marker` does, and writes the
/// calibrated marker file.
fn calibrate_from_recording(a: &DemoArgs) -> Result<Marker> {
    let dir = a.out.join("calibration");
    say!("Rendering a marker-calibration recording: the same printed markers seen from 18 angles…");
    let summary = render_with_progress(calibration_scene(a.seed), &dir)?;
    let truth: GroundTruth = serde_json::from_str(&std::fs::read_to_string(dir.join("ground_truth.json"))?)?;
    let source = jawtrack_frames::open_frames(None, std::slice::from_ref(&dir), None)?;
    let views = detect_views(source, &Marker::default(), &truth.intrinsics, truth.realism.gamma)?;
    let mut cal = calibrate(&Marker::default(), &views, &CalibrationOptions::default())?;
    cal.name_recordings(&[dir.display().to_string()]);
    let file = a.out.join("calibrated_marker.json");
    cal.marker.save(&file)?;
    for b in &cal.bodies {
        let assembly: Vec<String> =
            b.findings.iter().filter(|f| !matches!(f, Finding::Uncalibrated { .. })).map(Finding::to_string).collect();
        say!(
            "calibration, {}: {} tags placed from {} of {} views, reprojection error {:.2} px → {:.2} px; assembly {}",
            b.body,
            b.tags.len(),
            b.views,
            summary.frames,
            b.rms_before_px,
            b.rms_after_px,
            if assembly.is_empty() { "as designed".to_owned() } else { assembly.join("; ") }
        );
    }
    say!(
        "  calibrated marker file: {} (the faces turned toward the patient are never seen and stay nominal)",
        file.display()
    );
    Ok(cal.marker)
}

/// Tracks the rendered session with the nominal marker file, the calibrated one and the marker
/// as printed (`jawtrack_demo::track_against_truth`), tells the lower incisor's motion in plain
/// words, plots its path and writes the report.
fn track_and_compare(dir: &Path, truth: &GroundTruth, calibrated: Marker) -> Result<()> {
    let mut tracked: Vec<TrackingCheck> = Vec::new();
    for (label, marker, file) in jawtrack_demo::markers(truth, calibrated)? {
        let c = jawtrack_demo::track_against_truth(dir, truth, label, marker, file)?;
        say!(
            "tracking, {label}: jaw pose in {} of {} frames; mandible-in-maxilla error median {:.3} mm / {:.3}°, worst {:.3} mm / {:.3}°; {:.1} ms per frame; poses in {}",
            c.posed,
            c.frames,
            c.error_mm[0],
            c.error_deg[0],
            c.error_mm[1],
            c.error_deg[1],
            c.ms_median,
            c.poses.display()
        );
        tracked.push(c);
    }
    let m = Motion::of(truth, &tracked[0].path);
    say!(
        "The jaw: the lower incisor opened {} times, widest {:.1} mm from its closed position (truth {:.1} mm), and moved back by up to {:.1} mm as it swung about the condyles.",
        m.openings,
        m.widest_mm,
        m.truth_widest_mm,
        m.back_mm,
    );
    let written = jawtrack_demo::plot_incisor(dir, truth, &tracked)?;
    say!(
        "Plots of the incisor's path: {}",
        written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
    say!(
        "Calibrating the marker (`jawtrack calibrate-marker`) closed most of the gap between the nominal marker and the marker as printed."
    );
    say!("Session report (open it in a browser): {}", jawtrack_demo::write_report(dir)?.display());
    Ok(())
}
