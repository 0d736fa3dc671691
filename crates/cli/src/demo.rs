//! `jawtrack demo`: the main job on built-in defaults. It renders a short hinge session with
//! the synthetic rig, detects the tags in every frame and compares them with the ground truth,
//! then tracks the jaw (with the nominal marker file and with the marker as printed), reports
//! the mandible-in-maxilla error and the motion in plain words, and plots the incisor's path.

use crate::print::print_scene_summary;
use crate::progress::{detect_views, render_with_progress};
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
use jawtrack_calibration::{CalibrationOptions, Finding, calibrate};
use jawtrack_kinematics::Mounting;
use jawtrack_marker::Marker;
use jawtrack_pose::Pose;
use jawtrack_recording::{Overwrite, RecordingHeader, RecordingWriter};
use jawtrack_tracker::{Tracker, TrackerConfig};

use jawtrack_plot::{self as plot, Series, Style};
use jawtrack_synth::{GroundTruth, Realism, Resolution, SceneKind, SceneOptions, SynthConfig};
use nalgebra::Point3;
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
    let config = SynthConfig {
        scene: SceneKind::Hinge,
        resolution: Resolution::P1080,
        intrinsics: None,
        seed: a.seed,
        realism: Realism::default(),
        // One cycle per opening (10, 20, 30, 40 mm) sampled at 4 frames/s: 32 frames.
        options: SceneOptions { frames_per_view: 1, cycles: 1, fps: 4.0, ..SceneOptions::default() },
        marker: jawtrack_marker::Marker::default(),
        stride: 1,
        max_frames: None,
    };
    say!("JawTrack demo: rendering a hinge-opening session (10–40 mm) at 1080p with the synthetic rig…");
    let summary = render_with_progress(config, &a.out)?;
    print_scene_summary(SceneKind::Hinge, &a.out, &summary);
    detect_and_compare(&a.out)?;
    let calibrated = calibrate_from_recording(a)?;
    track_and_compare(&a.out, calibrated)?;
    Ok(())
}

/// Renders a calibration recording of the same printed marker (same seed, so the same print
/// errors), calibrates the marker from it as `jawtrack calibrate-marker` does, and writes the
/// calibrated marker file.
fn calibrate_from_recording(a: &DemoArgs) -> Result<Marker> {
    let dir = a.out.join("calibration");
    let config = SynthConfig {
        scene: SceneKind::Calibration,
        resolution: Resolution::P1080,
        intrinsics: None,
        seed: a.seed,
        realism: Realism::default(),
        options: SceneOptions { frames_per_view: 1, cycles: 1, fps: 30.0, ..SceneOptions::default() },
        marker: Marker::default(),
        stride: 1,
        max_frames: None,
    };
    say!("Rendering a marker-calibration recording: the same printed markers seen from 18 angles…");
    let summary = render_with_progress(config, &dir)?;
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

/// Tracks the rendered session with the nominal marker file (what a user has before
/// calibration), the calibrated one, and the marker as printed (the limit of calibration),
/// writes the poses, compares the mandible in the maxilla with the ground truth, tells the
/// lower incisor's motion in plain words, and plots its path.
fn track_and_compare(dir: &Path, calibrated: Marker) -> Result<()> {
    let path = dir.join("ground_truth.json");
    let truth: GroundTruth = serde_json::from_str(&std::fs::read_to_string(&path)?)?;
    let printed = Marker::from_json(&truth.true_marker.to_string()).context("the printed marker in the truth")?;
    let config = TrackerConfig {
        detector: DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() },
        ..TrackerConfig::default()
    };
    let mounting = Mounting::default();
    let closed = Point3::from(mounting.lower_incisal_point);
    let truth_path: Vec<Sample> =
        truth.frames.iter().map(|f| (f.t, mounting.lower_incisor(&f.maxilla_from_mandible))).collect();
    let mut tracked_paths = Vec::new();
    let markers = [
        ("nominal marker file", Marker::default(), "poses.jsonl"),
        ("calibrated marker file", calibrated, "poses_calibrated.jsonl"),
        ("marker as printed (truth)", printed, "poses_printed_marker.jsonl"),
    ];
    for (label, marker, file) in markers {
        let mut tracker = Tracker::new(marker, config)?;
        let poses = dir.join(file);
        let mut header = RecordingHeader::new("jawtrack demo");
        header.intrinsics = Some(truth.intrinsics);
        header.marker = serde_json::from_str(&tracker.marker().to_json()).ok();
        // The demo's own output folder: a second run replaces the first's files.
        let mut out = RecordingWriter::create(&poses, header, Overwrite::Replace)?;
        let (mut dt, mut dr, mut ms, mut path) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (i, f) in truth.frames.iter().enumerate() {
            let img = image::open(dir.join(&f.file))?.to_luma8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            let r = tracker.track(&ImageView::new(img.as_raw(), w, h, w)?, &truth.intrinsics, f.t)?;
            ms.push((r.timings.detection_s + r.timings.pose_s) * 1e3);
            out.append(&r.to_record(i, Some(&f.file)))?;
            if let Some(m) = r.maxilla_from_mandible {
                let (angle, dist) = m.distance_to(&f.maxilla_from_mandible);
                dt.push(dist);
                dr.push(angle.to_degrees());
                path.push((f.t, mounting.lower_incisor(&m)));
            }
        }
        for v in [&mut dt, &mut dr, &mut ms] {
            v.sort_by(f64::total_cmp);
        }
        let pick =
            |v: &[f64], q: f64| v.get(((v.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(f64::NAN);
        say!(
            "tracking, {label}: jaw pose in {} of {} frames; mandible-in-maxilla error median {:.3} mm / {:.3}°, worst {:.3} mm / {:.3}°; {:.1} ms per frame; poses in {}",
            dt.len(),
            truth.frames.len(),
            pick(&dt, 0.5),
            pick(&dr, 0.5),
            pick(&dt, 1.0),
            pick(&dr, 1.0),
            pick(&ms, 0.5),
            poses.display()
        );
        tracked_paths.push((label, path));
    }
    let openings = |p: &[Sample]| -> Vec<(f64, f64)> { p.iter().map(|(t, x)| (*t, (x - closed).norm())).collect() };
    let (tracked, real) = (openings(&tracked_paths[0].1), openings(&truth_path));
    let peak = |v: &[(f64, f64)]| v.iter().map(|p| p.1).fold(0.0, f64::max);
    say!(
        "The jaw: the lower incisor opened {} times, widest {:.1} mm from its closed position (truth {:.1} mm), and moved back by up to {:.1} mm as it swung about the condyles.",
        jawtrack_kinematics::metrics::count_openings(&tracked.iter().map(|p| p.1).collect::<Vec<_>>()),
        peak(&tracked),
        peak(&real),
        tracked_paths[0].1.iter().map(|(_, x)| x.z - closed.z).fold(0.0, f64::max),
    );
    let written = plot_incisor(dir, &closed, &truth_path, &tracked_paths)?;
    say!(
        "Plots of the incisor's path: {}",
        written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
    say!(
        "Calibrating the marker (`jawtrack calibrate-marker`) closed most of the gap between the nominal marker and the marker as printed."
    );
    say!("Session report (open it in a browser): {}", write_report(dir)?.display());
    Ok(())
}

/// The session report of the calibrated marker's tracking, with the hinge axis of its
/// openings (`jawtrack report` on the same file does the same).
fn write_report(dir: &Path) -> Result<PathBuf> {
    let poses = dir.join("poses_calibrated.jsonl");
    let rec = jawtrack_recording::open(&poses)?;
    let posed: Vec<(f64, Pose)> = rec.frames.iter().filter_map(|f| Some((f.t, f.maxilla_from_mandible?))).collect();
    let (Some(&(from, rest)), Some(&(to, _))) = (posed.first(), posed.last()) else {
        bail!("{}: no frame has a jaw pose", poses.display());
    };
    let standard = jawtrack_session::anatomy(None, None, &rest)?;
    let inputs = jawtrack_report::Inputs {
        recording: &rec,
        recording_name: "poses_calibrated.jsonl".into(),
        anatomy: standard,
        points_file: None,
        registration_file: None,
        rest,
        rest_words: "the first frame (the jaw closed)".into(),
        windows: jawtrack_report::Windows {
            opening: Some(jawtrack_kinematics::Window { from, to }),
            ..jawtrack_report::Windows::default()
        },
        centric: None,
        contacts: None,
        made_unix_s: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64()),
    };
    let path = dir.join("report.html");
    std::fs::write(&path, jawtrack_report::render(&inputs).html)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

/// The lower incisor's position (head frame, mm) at a time (s).
type Sample = (f64, Point3<f64>);

/// Writes the incisor's opening over time and its sagittal path (SVG); returns the files.
fn plot_incisor(
    dir: &Path,
    closed: &Point3<f64>,
    truth: &[Sample],
    tracked: &[(&str, Vec<Sample>)],
) -> Result<Vec<PathBuf>> {
    let colors = ["#d62728", "#2ca02c", "#1f77b4"];
    let series = |f: &dyn Fn(&Sample) -> (f64, f64)| {
        let mut v =
            vec![Series { name: "truth", color: "#222", style: Style::Line, points: truth.iter().map(f).collect() }];
        for ((label, path), color) in tracked.iter().zip(colors) {
            v.push(Series { name: label, color, style: Style::Dots, points: path.iter().map(f).collect() });
        }
        v
    };
    // Head frame: y down, z posterior; plots show up and anterior as positive.
    let opening = plot::chart(
        "Lower incisor: distance from its closed position",
        "time (s)",
        "opening (mm)",
        &series(&|(t, x)| (*t, (x - *closed).norm())),
        false,
    );
    let sagittal = plot::chart(
        "Lower incisor path, sagittal plane (seen from the patient's right: facing right)",
        "anterior (mm)",
        "up (mm)",
        &series(&|(_, x)| (closed.z - x.z, closed.y - x.y)),
        true,
    );
    let mut written = Vec::new();
    for (name, doc) in [("incisor_opening.svg", opening), ("incisor_sagittal.svg", sagittal)] {
        let p = dir.join(name);
        svg::save(&p, &doc).with_context(|| format!("writing {}", p.display()))?;
        written.push(p);
    }
    Ok(written)
}

/// Runs the detector on the rendered session and compares with the ground truth.
fn detect_and_compare(dir: &Path) -> Result<()> {
    let path = dir.join("ground_truth.json");
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let truth: GroundTruth = serde_json::from_str(&text).with_context(|| format!("{}", path.display()))?;
    // Frames encoded with sRGB (as phones deliver them) are refined in linear light.
    let detector = Detector::new(DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() })?;
    let (mut want, mut found, mut errors, mut ms) = (0usize, 0usize, Vec::new(), Vec::new());
    for f in &truth.frames {
        let img = image::open(dir.join(&f.file))?.to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let t = std::time::Instant::now();
        let dets = detector.detect(&ImageView::new(img.as_raw(), w, h, w)?)?;
        ms.push(t.elapsed().as_secs_f64() * 1e3);
        for tag in f.tags.iter().filter(|t| t.should_be_detected()) {
            want += 1;
            if let Some(d) = dets.iter().find(|d| d.id == tag.id) {
                found += 1;
                errors.extend(d.corners.iter().zip(&tag.corners).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])));
            }
        }
    }
    errors.sort_by(f64::total_cmp);
    ms.sort_by(f64::total_cmp);
    let pick = |v: &[f64], q: f64| v.get(((v.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(f64::NAN);
    say!(
        "detection: {found} of {want} detectable tags found; corner error against ground truth median {:.3} px, 90th percentile {:.3} px; {:.0} ms per frame (median, one thread)",
        pick(&errors, 0.5),
        pick(&errors, 0.9),
        pick(&ms, 0.5)
    );
    Ok(())
}
