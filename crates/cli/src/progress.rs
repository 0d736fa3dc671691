//! The long steps the CLI shows progress for (detection, rendering), drawn with the tools' one
//! bar (`jawtrack_progress`).

use jawtrack_progress::ProgressBar;
pub(crate) use jawtrack_progress::bar;

/// A bar over `len` items labelled `what`.
pub(crate) fn progress_bar(what: &str, len: usize) -> ProgressBar {
    bar(what, Some(len as u64), "")
}

/// `jawtrack_frames::detect_marker_tags` with a bar, naming each unreadable frame and counting them.
pub(crate) fn detect_marker_tags(
    source: Box<dyn jawtrack_frames::FrameSource>,
    marker: &jawtrack_marker::Marker,
    edges: crate::flags::EdgeArgs,
) -> anyhow::Result<Vec<jawtrack_frames::TaggedFrame>> {
    use jawtrack_frames::Progress;
    let bar = bar("detecting", source.frame_count().map(|n| n as u64), "frames");
    let mut unreadable = 0;
    let frames =
        jawtrack_frames::detect_marker_tags(source, marker, (edges.linear_edges, edges.tone), &mut |p| match p {
            Progress::Frame => bar.inc(1),
            Progress::Unreadable(name, why) => {
                unreadable += 1;
                bar.suspend(|| tell!("warning: {name}: {why}; skipped"));
            }
        });
    bar.finish_and_clear();
    if unreadable > 0 {
        tell!("warning: {unreadable} frames could not be read and were left out");
    }
    Ok(frames?)
}

/// Detects the marker's tags in every frame, with a progress bar, as views taken by `camera`.
pub(crate) fn detect_views(
    source: Box<dyn jawtrack_frames::FrameSource>,
    marker: &jawtrack_marker::Marker,
    camera: &jawtrack_pose::CameraIntrinsics,
    edges: crate::flags::EdgeArgs,
) -> anyhow::Result<Vec<jawtrack_calibration::CalibrationFrame>> {
    let frames = detect_marker_tags(source, marker, edges)?;
    Ok(frames.into_iter().map(|f| jawtrack_calibration::CalibrationFrame { camera: *camera, tags: f.tags }).collect())
}

/// Renders a scene (`jawtrack_synth::write_scene`) with a bar.
pub(crate) fn render_with_progress(
    config: jawtrack_synth::SynthConfig,
    out: &std::path::Path,
) -> anyhow::Result<jawtrack_synth::SceneSummary> {
    let bar = bar(&format!("rendering {}", config.scene.name()), Some(0), "frames");
    let summary = jawtrack_synth::write_scene(config, out, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    Ok(summary)
}
