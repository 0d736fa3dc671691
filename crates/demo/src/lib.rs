//! The steps of `jawtrack demo`, the main job on built-in defaults: the two scenes it renders
//! ([`hinge_scene`], [`calibration_scene`]), the detector checked against the rendered
//! session's ground truth ([`check_detection`]), the jaw tracked with each marker file and
//! compared with the truth ([`track_against_truth`]), the incisor's motion in plain numbers
//! ([`Motion`]), its path plotted ([`plot_incisor`]) and the session's report
//! ([`write_report`]), and the marker calibrated from a second recording
//! ([`calibrate_marker`]). Each result prints itself as the demo says it. The command renders, calibrates and prints; the numbers are made here.
//!
//! # Examples
//!
//! ```no_run
//! use std::path::Path;
//! # fn main() -> Result<(), jawtrack_demo::DemoError> {
//! let dir = Path::new("out/demo");
//! let truth = jawtrack_demo::read_truth(dir)?;
//! let d = jawtrack_demo::check_detection(dir, &truth)?;
//! println!("{} of {} detectable tags found", d.found, d.want);
//! # Ok(()) }
//! ```

mod calibrate;
mod track;

pub use calibrate::{MarkerCalibration, calibrate_marker};
pub use track::{Motion, TrackingCheck, markers, plot_incisor, recorded_path, track_against_truth, write_report};

use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
use jawtrack_marker::Marker;
use jawtrack_synth::{GroundTruth, Realism, Resolution, SceneKind, SceneOptions, SynthConfig};
use std::fmt;
use std::path::Path;

/// Why a step of the demo failed.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// A file could not be read or written (`context` names it).
    #[error("{context}")]
    Io {
        /// What was being done, naming the file.
        context: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The ground truth is not JSON of its schema.
    #[error("{path}")]
    Truth {
        /// The ground truth file.
        path: String,
        /// Why.
        #[source]
        source: serde_json::Error,
    },
    /// The printed marker in the ground truth is not a marker file.
    #[error("the printed marker in the truth")]
    PrintedMarker(#[source] jawtrack_marker::MarkerError),
    /// A rendered frame could not be read.
    #[error(transparent)]
    Image(#[from] image::ImageError),
    /// The detector failed.
    #[error(transparent)]
    Detect(#[from] jawtrack_apriltag::DetectError),
    /// The tracker failed.
    #[error(transparent)]
    Track(#[from] jawtrack_tracker::TrackError),
    /// A recording could not be written or read.
    #[error(transparent)]
    Recording(#[from] jawtrack_recording::RecordingError),
    /// The session could not be read as the report needs it.
    #[error(transparent)]
    Session(#[from] jawtrack_session::SessionError),
    /// The marker could not be calibrated from the recording.
    #[error(transparent)]
    Calibrate(#[from] jawtrack_calibration::CalibrationError),
    /// The calibrated marker file could not be written.
    #[error(transparent)]
    Marker(#[from] jawtrack_marker::MarkerError),
    /// The recording has no jaw pose to report.
    #[error("{0}: no frame has a jaw pose")]
    NoJawPose(String),
}

/// The demo's session: one hinge opening to each of 10, 20, 30 and 40 mm, sampled at 4
/// frames/s (32 frames) at 1080p.
pub fn hinge_scene(seed: u64) -> SynthConfig {
    SynthConfig {
        scene: SceneKind::Hinge,
        resolution: Resolution::P1080,
        intrinsics: None,
        seed,
        realism: Realism::default(),
        // One cycle per opening (10, 20, 30, 40 mm) sampled at 4 frames/s: 32 frames.
        options: SceneOptions { frames_per_view: 1, cycles: 1, fps: 4.0, ..SceneOptions::default() },
        marker: Marker::default(),
        stride: 1,
        max_frames: None,
    }
}

/// The calibration recording of the same printed markers (the same `seed`, so the same print
/// errors) seen from 18 angles.
pub fn calibration_scene(seed: u64) -> SynthConfig {
    SynthConfig {
        scene: SceneKind::Calibration,
        options: SceneOptions { frames_per_view: 1, cycles: 1, fps: 30.0, ..SceneOptions::default() },
        ..hinge_scene(seed)
    }
}

/// The ground truth the renderer wrote into `dir`.
pub fn read_truth(dir: &Path) -> Result<GroundTruth, DemoError> {
    let path = dir.join("ground_truth.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|source| DemoError::Io { context: format!("reading {}", path.display()), source })?;
    serde_json::from_str(&text).map_err(|source| DemoError::Truth { path: path.display().to_string(), source })
}

/// The `q` quantile (0–1) of sorted `v`, the nearest sample; NaN when empty.
fn pick(v: &[f64], q: f64) -> f64 {
    v.get(((v.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(f64::NAN)
}

/// The detector against the ground truth: how many of the tags it should find it found, and
/// how far their corners are from the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectionCheck {
    /// Tags the truth says a detector should find, over all frames.
    pub want: usize,
    /// Of these, those found.
    pub found: usize,
    /// The corners' error (px): median.
    pub corner_error_median_px: f64,
    /// The corners' error (px): 90th percentile.
    pub corner_error_p90_px: f64,
    /// Detection time per frame (ms, median, one thread).
    pub ms_median: f64,
}

impl fmt::Display for DetectionCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "detection: {} of {} detectable tags found; corner error against ground truth median {:.3} px, 90th percentile {:.3} px; {:.0} ms per frame (median, one thread)",
            self.found, self.want, self.corner_error_median_px, self.corner_error_p90_px, self.ms_median
        )
    }
}

/// Runs the detector on the rendered session in `dir` and compares with its `truth`.
pub fn check_detection(dir: &Path, truth: &GroundTruth) -> Result<DetectionCheck, DemoError> {
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
    Ok(DetectionCheck {
        want,
        found,
        corner_error_median_px: pick(&errors, 0.5),
        corner_error_p90_px: pick(&errors, 0.9),
        ms_median: pick(&ms, 0.5),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_take_the_nearest_sample_and_nothing_is_nan() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!([pick(&v, 0.0), pick(&v, 0.5), pick(&v, 0.9), pick(&v, 1.0)], [1.0, 3.0, 5.0, 5.0]);
        assert!(pick(&[], 0.5).is_nan());
    }

    #[test]
    fn the_calibration_scene_is_the_hinge_scenes_print() {
        let (h, c) = (hinge_scene(7), calibration_scene(7));
        assert_eq!((h.scene, c.scene), (SceneKind::Hinge, SceneKind::Calibration));
        assert_eq!((h.seed, c.seed), (7, 7));
        assert_eq!((h.options.fps, c.options.fps), (4.0, 30.0));
    }
}
