//! The camera file `jawtrack calibrate-camera` writes and `jawtrack track --camera` reads: the
//! calibration, the `track` flags it amounts to, and what the phone's lens was set to while the
//! calibration video was filmed. A phone's intrinsics belong to a zoom and a focus: focusing
//! moves the lens (3.5 % in focal length from infinity to 20 cm on a 6.8 mm lens), a zoom crops
//! the sensor; a recording made at another lens position or zoom is measured with the wrong
//! focal length, which [`CalibratedAt::differences`] names.

use crate::CameraCalibration;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The version this build writes and reads.
const VERSION: u32 = 1;

/// A lens position (AVFoundation's 0 near – 1 far) this much away from the calibration's is
/// taken as focus having moved: the positions a locked focus reports again differ by
/// thousandths.
pub const LENS_POSITION_MOVED: f64 = 0.02;

/// What the lens was set to while the calibration was filmed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct CalibratedAt {
    /// AVFoundation's lens position (0 near – 1 far), when known.
    #[serde(default)]
    pub lens_position: Option<f64>,
    /// The zoom (1, or a native crop), when known.
    #[serde(default)]
    pub zoom: Option<f64>,
}

impl CalibratedAt {
    /// How a recording made at `lens_position` and `zoom` (each when known) differs from the
    /// calibration, in words; empty when it does not (or nothing can be compared).
    pub fn differences(&self, lens_position: Option<f64>, zoom: Option<f64>) -> Vec<String> {
        let mut out = Vec::new();
        if let (Some(a), Some(b)) = (self.lens_position, lens_position)
            && (a - b).abs() > LENS_POSITION_MOVED
        {
            out.push(format!(
                "the lens position was {b:.3} while recording and {a:.3} while calibrating: focus moved, and with it the \
                 focal length (by up to 3.5 % between infinity and 20 cm)"
            ));
        }
        if let (Some(a), Some(b)) = (self.zoom, zoom)
            && (a - b).abs() > 1e-6
        {
            out.push(format!(
                "the zoom was {b}× while recording and {a}× while calibrating: the focal length differs by that factor"
            ));
        }
        out
    }

    /// What was given, each value not given taken from `recorded` (the app's recording of the
    /// calibration video); refused outside AVFoundation's lens positions (0–1) and the zooms a
    /// phone films at (1–20).
    ///
    /// # Examples
    ///
    /// ```
    /// use jawtrack_camera_calibration::CalibratedAt;
    /// let given = CalibratedAt { lens_position: Some(0.4), zoom: None };
    /// let recorded = CalibratedAt { lens_position: Some(0.7), zoom: Some(2.0) };
    /// assert_eq!(given.or_recorded(recorded).unwrap(), CalibratedAt { lens_position: Some(0.4), zoom: Some(2.0) });
    /// ```
    pub fn or_recorded(self, recorded: CalibratedAt) -> Result<Self, CameraFileError> {
        let at = CalibratedAt {
            lens_position: self.lens_position.or(recorded.lens_position),
            zoom: self.zoom.or(recorded.zoom),
        };
        if let Some(p) = at.lens_position.filter(|p| !(p.is_finite() && (0.0..=1.0).contains(p))) {
            return Err(CameraFileError::OutOfRange(format!(
                "--lens-position is AVFoundation's lens position, within 0–1; got {p}"
            )));
        }
        if let Some(z) = at.zoom.filter(|z| !(z.is_finite() && (1.0..=20.0).contains(z))) {
            return Err(CameraFileError::OutOfRange(format!(
                "--zoom must be at least 1 (1, or the native crop's 2), got {z}"
            )));
        }
        Ok(at)
    }
}

/// The camera file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CameraFile {
    /// Always 1.
    pub version: u32,
    /// The calibration.
    pub calibration: CameraCalibration,
    /// The flags that give `jawtrack track` this camera.
    pub track_flags: String,
    /// What the lens was set to.
    #[serde(default)]
    pub calibrated_at: CalibratedAt,
}

/// Why a camera file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum CameraFileError {
    /// The file could not be read.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
    /// A lens position or zoom to record with the calibration is out of range.
    #[error("{0}")]
    OutOfRange(String),
    /// Not a camera file of this version.
    #[error("{path}: not a camera file from `jawtrack calibrate-camera` ({reason})")]
    Format {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
}

impl CameraFile {
    /// The file for a calibration made at `calibrated_at`.
    pub fn new(calibration: CameraCalibration, calibrated_at: CalibratedAt) -> Self {
        let track_flags = track_flags(&calibration);
        CameraFile { version: VERSION, calibration, track_flags, calibrated_at }
    }

    /// Reads and checks a camera file.
    pub fn load(path: &Path) -> Result<Self, CameraFileError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CameraFileError::Io { path: path.display().to_string(), reason: e.to_string() })?;
        CameraFile::from_json(&text, &path.display().to_string())
    }

    /// Parses and checks a camera file's text; errors name the file as `name`.
    pub fn from_json(text: &str, name: &str) -> Result<Self, CameraFileError> {
        let format = |reason: String| CameraFileError::Format { path: name.to_owned(), reason };
        let file: CameraFile = serde_json::from_str(text).map_err(|e| format(e.to_string()))?;
        if file.version != VERSION {
            return Err(format(format!("version {} (this build reads {VERSION})", file.version)));
        }
        file.calibration.intrinsics.validate().map_err(|e| format(e.to_string()))?;
        let r = file.calibration.readout_s;
        if !(r.is_finite() && (-0.01..1.0).contains(&r)) {
            return Err(format(format!("readout {r} s")));
        }
        if let Some(p) = file.calibrated_at.lens_position.filter(|p| !(p.is_finite() && (0.0..=1.0).contains(p))) {
            return Err(format(format!("lens position {p} (0–1)")));
        }
        if let Some(z) = file.calibrated_at.zoom.filter(|z| !(z.is_finite() && *z >= 1.0)) {
            return Err(format(format!("zoom {z} (at least 1)")));
        }
        Ok(file)
    }

    /// The file as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| unreachable!("a camera file always serialises: {e}"))
    }
}

/// The flags that give `jawtrack track` this camera.
fn track_flags(c: &CameraCalibration) -> String {
    let k = &c.intrinsics;
    // A readout estimated just below 0 (a global shutter, within its noise) is 0.
    format!(
        "--intrinsics {:.3},{:.3},{:.3},{:.3},{:.6},{:.6} --readout-ms {:.3}",
        k.fx,
        k.fy,
        k.cx,
        k.cy,
        k.k1,
        k.k2,
        (c.readout_s * 1e3).max(0.0)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Uncertainty;
    use jawtrack_pose::CameraIntrinsics;

    fn calibration() -> CameraCalibration {
        CameraCalibration {
            image_size: [1920, 1080],
            intrinsics: CameraIntrinsics::pinhole(3000.0, 3000.0, 959.5, 539.5),
            readout_s: 0.0101,
            sigma: Uncertainty {
                fx: 1.0,
                fy: 1.0,
                cx: 0.5,
                cy: 0.5,
                k1: 0.001,
                k2: 0.001,
                readout_s: 1e-4,
                corner_distortion_px: 0.1,
            },
            rms_px: 0.05,
            frames_used: 100,
            views_used: 180,
            corners_used: 2000,
            sightings_dropped: 0,
            coverage: 0.7,
        }
    }

    #[test]
    fn the_file_reads_back_and_names_a_moved_focus_or_zoom() {
        let at = CalibratedAt { lens_position: Some(0.81), zoom: Some(2.0) };
        let file = CameraFile::new(calibration(), at);
        assert!(
            file.track_flags.starts_with("--intrinsics 3000.000,3000.000,959.500,539.500,"),
            "{}",
            file.track_flags
        );
        let path = std::env::temp_dir().join(format!("jawtrack-camera-file-{}.json", std::process::id()));
        std::fs::write(&path, file.to_json()).expect("writes");
        assert_eq!(CameraFile::load(&path).expect("reads"), file);
        std::fs::write(&path, file.to_json().replace("0.81", "1.81")).expect("writes");
        let e = CameraFile::load(&path).expect_err("lens position out of range").to_string();
        assert!(e.contains("lens position 1.81"), "{e}");
        std::fs::remove_file(&path).ok();
        assert!(at.differences(Some(0.815), Some(2.0)).is_empty(), "the same lock reports again");
        let d = at.differences(Some(0.62), Some(1.0));
        assert!(d.len() == 2 && d[0].contains("focus moved") && d[1].contains("zoom was 1×"), "{d:?}");
        assert!(at.differences(None, None).is_empty(), "nothing to compare");
    }

    #[test]
    fn what_is_given_wins_and_out_of_range_values_are_refused() {
        let recorded = CalibratedAt { lens_position: Some(0.5), zoom: Some(2.0) };
        let given = CalibratedAt { lens_position: None, zoom: Some(1.0) };
        assert_eq!(
            given.or_recorded(recorded).expect("in range"),
            CalibratedAt { lens_position: Some(0.5), zoom: Some(1.0) }
        );
        let far = CalibratedAt { lens_position: Some(1.5), zoom: None }.or_recorded(recorded).expect_err("beyond 1");
        assert!(far.to_string().starts_with("--lens-position"), "{far}");
        let wide = CalibratedAt { lens_position: None, zoom: Some(0.5) }.or_recorded(CalibratedAt::default());
        assert!(wide.expect_err("below 1").to_string().starts_with("--zoom"));
    }
}
