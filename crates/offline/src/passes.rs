//! One frame tracked, and the first pass of a two-pass run: every frame's detections kept, the
//! marker refined from them.

use crate::OfflineError;
use jawtrack_apriltag::{Detection, Roi};
use jawtrack_calibration::{CalibrationFrame, Refinement, SeenTag, SessionOptions, refine};
use jawtrack_frames::{Frame, FrameSource};
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_tracker::{FrameResult, Tracker};

/// One frame tracked, or why it could not be decoded or tracked.
pub fn track_frame(tracker: &mut Tracker, frame: &Frame, camera: &CameraIntrinsics) -> Result<FrameResult, String> {
    let image = frame.image.as_ref().map_err(Clone::clone)?;
    let view = image.view().map_err(|e| e.to_string())?;
    tracker.track(&view, camera, frame.t).map_err(|e| e.to_string())
}

/// A frame of the first pass: its detections, or why it was unreadable.
pub struct Kept {
    /// As [`Frame::name`].
    pub name: String,
    /// As [`Frame::t`].
    pub t: f64,
    /// What was detected, or why nothing could be.
    pub tracked: Result<Detected, String>,
}

/// What the first pass detected in a frame, and how.
pub struct Detected {
    detections: Vec<Detection>,
    /// The frame's height (px): its rows' times under a rolling shutter.
    rows: usize,
    detection_s: f64,
    searched: Option<Roi>,
}

impl Detected {
    /// The frame solved again by `tracker`, keeping the first pass's detection figures.
    pub fn solve(self, tracker: &mut Tracker, camera: &CameraIntrinsics, t: f64) -> FrameResult {
        let mut r = tracker.solve(self.detections, camera, t, self.rows);
        r.timings.detection_s = self.detection_s;
        r.searched = self.searched;
        r
    }
}

/// Tracks every frame of `source` with `tracker`, keeping each frame's detections
/// (`progress()` after each frame).
pub fn first_pass(
    tracker: &mut Tracker,
    source: &mut dyn FrameSource,
    camera: &CameraIntrinsics,
    progress: &mut dyn FnMut(),
) -> Result<Vec<Kept>, OfflineError> {
    let mut kept = Vec::new();
    while let Some(frame) = source.next_frame()? {
        let tracked = track_frame(tracker, &frame, camera).map(|r| {
            let rows = frame.image.as_ref().map_or(0, |i| i.height);
            Detected { detection_s: r.timings.detection_s, searched: r.searched, detections: r.detections, rows }
        });
        kept.push(Kept { name: frame.name, t: frame.t, tracked });
        progress();
    }
    Ok(kept)
}

/// `marker` refined from the first pass's detections, the session named `recording`.
pub fn refine_marker(
    marker: &Marker,
    kept: &[Kept],
    camera: &CameraIntrinsics,
    recording: &str,
) -> Result<Refinement, OfflineError> {
    let frames: Vec<CalibrationFrame> = kept
        .iter()
        .filter_map(|k| k.tracked.as_ref().ok())
        .map(|d| CalibrationFrame {
            camera: *camera,
            tags: d.detections.iter().map(|d| SeenTag { id: d.id, corners: d.corners }).collect(),
        })
        .collect();
    let mut refinement = refine(marker, &frames, &SessionOptions::default())?;
    refinement.name_recording(recording);
    Ok(refinement)
}
