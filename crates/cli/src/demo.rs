//! `jawtrack demo`: the main job on built-in defaults. It renders a short hinge session with
//! the synthetic rig, detects the tags in every frame and compares them with the ground truth,
//! then tracks the jaw (with the nominal marker file and with the marker as printed) and
//! reports the mandible-in-maxilla error and the motion in plain words.

use crate::render_with_progress;
use anyhow::{Context, Result};
use clap::Args;
use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
use jawtrack_marker::Marker;
use jawtrack_tracker::record::frame_record;
use jawtrack_tracker::{Tracker, TrackerConfig};
use std::io::Write as _;

use jawtrack_synth::{GroundTruth, Realism, Resolution, SceneKind, SceneOptions, SceneSummary, SynthConfig};
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
        options: SceneOptions { frames_per_view: 1, cycles: 1, fps: 4.0 },
        marker: jawtrack_marker::Marker::default(),
        stride: 1,
        max_frames: None,
    };
    say!("JawTrack demo: rendering a hinge-opening session (10–40 mm) at 1080p with the synthetic rig…");
    let summary = render_with_progress(config, &a.out)?;
    print_scene_summary(SceneKind::Hinge, &a.out, &summary);
    detect_and_compare(&a.out)?;
    track_and_compare(&a.out)?;
    Ok(())
}

/// Tracks the rendered session with the nominal marker file (what a user has before
/// calibration) and with the marker as printed (what calibration recovers), writes the poses,
/// and compares the mandible in the maxilla with the ground truth.
fn track_and_compare(dir: &Path) -> Result<()> {
    let path = dir.join("ground_truth.json");
    let truth: GroundTruth = serde_json::from_str(&std::fs::read_to_string(&path)?)?;
    let printed = Marker::from_json(&truth.true_marker.to_string()).context("the printed marker in the truth")?;
    let config = TrackerConfig {
        detector: DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() },
        ..TrackerConfig::default()
    };
    for (label, marker) in [("nominal marker file", Marker::default()), ("marker as printed", printed)] {
        let mut tracker = Tracker::new(marker, config)?;
        let poses = dir.join(if label.starts_with("nominal") { "poses.jsonl" } else { "poses_printed_marker.jsonl" });
        let mut out = std::io::BufWriter::new(std::fs::File::create(&poses)?);
        let (mut dt, mut dr, mut ms, mut opening) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (i, f) in truth.frames.iter().enumerate() {
            let img = image::open(dir.join(&f.file))?.to_luma8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            let t = std::time::Instant::now();
            let r = tracker.track(&ImageView::new(img.as_raw(), w, h, w)?, &truth.intrinsics, f.t)?;
            ms.push(t.elapsed().as_secs_f64() * 1e3);
            writeln!(out, "{}", frame_record(i, Some(&f.file), &r))?;
            if let Some(m) = r.maxilla_from_mandible {
                let (angle, dist) = m.distance_to(&f.maxilla_from_mandible);
                dt.push(dist);
                dr.push(angle.to_degrees());
                opening.push(m.translation().norm());
            }
        }
        out.flush()?;
        for v in [&mut dt, &mut dr, &mut ms] {
            v.sort_by(f64::total_cmp);
        }
        let pick =
            |v: &[f64], q: f64| v.get(((v.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(f64::NAN);
        say!(
            "tracking, {label}: jaw pose in {} of {} frames; mandible-in-maxilla error median {:.3} mm / {:.3}°, worst {:.3} mm / {:.3}°; {:.0} ms per frame; poses in {}",
            dt.len(),
            truth.frames.len(),
            pick(&dt, 0.5),
            pick(&dr, 0.5),
            pick(&dt, 1.0),
            pick(&dr, 1.0),
            pick(&ms, 0.5),
            poses.display()
        );
        if label.starts_with("nominal") {
            let (lo, hi) = opening.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
            say!(
                "  the mandible marker moved between {lo:.1} and {hi:.1} mm from the maxilla marker: the jaw opened and closed {} times",
                count_openings(&opening)
            );
        }
    }
    say!("The gap between the two lines is what calibrating the marker (`jawtrack calibrate`, planned) removes.");
    Ok(())
}

/// Openings in a sequence of marker separations: rises above the midpoint of its range.
fn count_openings(sep: &[f64]) -> usize {
    let (lo, hi) = sep.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let mid = 0.5 * (lo + hi);
    let mut above = false;
    let mut n = 0;
    for &v in sep {
        if v > mid && !above {
            n += 1;
        }
        above = v > mid;
    }
    n
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

pub(crate) fn print_scene_summary(scene: SceneKind, out: &Path, s: &SceneSummary) {
    say!(
        "{} scene: {} frames in {} ({:.1} s, {:.2} s/frame)",
        scene.name(),
        s.frames,
        out.display(),
        s.seconds,
        s.seconds / s.frames.max(1) as f64
    );
    say!(
        "  tags a detector should find per frame: min {}, mean {:.1}, max {}; median tag side {:.0} px",
        s.detectable_tags.0,
        s.detectable_tags.1,
        s.detectable_tags.2,
        s.median_tag_side_px
    );
    say!("  mandible marker travel relative to the maxilla: up to {:.1} mm", s.max_mandible_travel_mm);
    say!("  ground truth: {}", out.join("ground_truth.json").display());
}
