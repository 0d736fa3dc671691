//! `jawtrack demo`: the main job on built-in defaults. It renders a short hinge session with
//! the synthetic rig, detects the tags in every frame and compares them with the ground truth,
//! calibrates the marker from a second recording, then tracks the jaw (with the nominal, the
//! calibrated and the as-printed marker file), reports the mandible-in-maxilla error and the
//! motion in plain words, plots the incisor's path and writes the report. The steps and their
//! words are `jawtrack_demo`'s; this file renders and detects with progress bars, and prints.

use crate::print::print_scene_summary;
use crate::progress::{detect_views, render_with_progress};
use anyhow::Result;
use clap::Args;
use jawtrack_demo::{Motion, calibration_scene, hinge_scene, read_truth};
use jawtrack_marker::Marker;
use jawtrack_synth::SceneKind;
use std::path::PathBuf;

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
    say!("{}", jawtrack_demo::check_detection(&a.out, &truth)?);

    // The same printed markers (same seed, so the same print errors) seen from 18 angles.
    let dir = a.out.join("calibration");
    say!("Rendering a marker-calibration recording: the same printed markers seen from 18 angles…");
    let rendered = render_with_progress(calibration_scene(a.seed), &dir)?;
    let turned = read_truth(&dir)?;
    let source = jawtrack_frames::open_frames(None, std::slice::from_ref(&dir), None)?;
    let edges =
        crate::flags::EdgeArgs { linear_edges: turned.realism.gamma, tone: jawtrack_apriltag::ToneSetting::Auto };
    let views = detect_views(source, &Marker::default(), &turned.intrinsics, edges)?;
    let calibrated = jawtrack_demo::calibrate_marker(&a.out, &dir, &views, rendered.frames)?;
    say!("{calibrated}");

    let mut tracked = Vec::new();
    for (label, marker, file) in jawtrack_demo::markers(&truth, calibrated.calibration.marker)? {
        tracked.push(jawtrack_demo::track_against_truth(&a.out, &truth, label, marker, file)?);
        say!("{}", tracked[tracked.len() - 1]);
    }
    // The calibrated file: the one the report below is made from.
    say!("{}", Motion::of(&truth, &tracked[1].poses)?);
    let written = jawtrack_demo::plot_incisor(&a.out, &truth, &tracked)?;
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    say!("Plots of the incisor's path: {}", names.join(", "));
    say!(
        "Calibrating the marker (`jawtrack calibrate-marker`) closed most of the gap between the nominal marker and the marker as printed."
    );
    say!("Session report (open it in a browser): {}", jawtrack_demo::write_report(&a.out)?.display());
    Ok(())
}
