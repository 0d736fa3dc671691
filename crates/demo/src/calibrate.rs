//! The demo's marker calibration: the markers of the hinge session, as printed, calibrated
//! from a recording of them turned in front of the camera, as `jawtrack calibrate-marker`
//! does, and what it found in plain words.

use crate::DemoError;
use jawtrack_calibration::{Calibration, CalibrationFrame, CalibrationOptions, Finding, calibrate};
use jawtrack_marker::Marker;
use std::fmt;
use std::path::{Path, PathBuf};

/// The calibrated marker, where it was written, and how each body was placed.
#[derive(Debug, Clone)]
pub struct MarkerCalibration {
    /// The calibration (its marker is the calibrated marker file's content).
    pub calibration: Calibration,
    /// The calibrated marker file.
    pub file: PathBuf,
    /// The frames of the calibration recording.
    pub frames: usize,
}

/// Calibrates the nominal marker from the `views` of the recording in `recording` (of
/// `frames` frames) and writes `calibrated_marker.json` into `out`.
pub fn calibrate_marker(
    out: &Path,
    recording: &Path,
    views: &[CalibrationFrame],
    frames: usize,
) -> Result<MarkerCalibration, DemoError> {
    let mut calibration = calibrate(&Marker::default(), views, &CalibrationOptions::default())?;
    calibration.name_recordings(&[recording.display().to_string()]);
    let file = out.join("calibrated_marker.json");
    calibration.marker.save(&file)?;
    Ok(MarkerCalibration { calibration, file, frames })
}

impl fmt::Display for MarkerCalibration {
    /// One line per body (tags placed, views, reprojection error before and after, what the
    /// assembly showed), then the file.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for b in &self.calibration.bodies {
            let assembly: Vec<String> = b
                .findings
                .iter()
                .filter(|f| !matches!(f, Finding::Uncalibrated { .. }))
                .map(Finding::to_string)
                .collect();
            writeln!(
                f,
                "calibration, {}: {} tags placed from {} of {} views, reprojection error {:.2} px → {:.2} px; assembly {}",
                b.body,
                b.tags.len(),
                b.views,
                self.frames,
                b.rms_before_px,
                b.rms_after_px,
                if assembly.is_empty() { "as designed".to_owned() } else { assembly.join("; ") }
            )?;
        }
        write!(
            f,
            "  calibrated marker file: {} (the faces turned toward the patient are never seen and stay nominal)",
            self.file.display()
        )
    }
}
