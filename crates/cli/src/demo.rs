//! `jawtrack demo`: the main job on built-in defaults. For now it renders a short hinge
//! session with the synthetic rig and summarises what was rendered; as detection and tracking
//! land it will track the session and compare with the ground truth.

use crate::render_with_progress;
use anyhow::Result;
use clap::Args;
use jawtrack_synth::{Realism, Resolution, SceneKind, SceneOptions, SceneSummary, SynthConfig};
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
    say!("Detection and tracking of these frames arrive with the detector and tracker; see the README.");
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
