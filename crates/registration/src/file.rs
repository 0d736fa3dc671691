//! Registration of the markers to the patient's tooth scans, and the maximal-intercuspation
//! calibration step.
//!
//! The registration file says where each marker sits in its arch's intra-oral scan
//! (`maxilla_scan_from_maxilla_marker`, `mandible_scan_from_mandible_marker`), so the tracked
//! `maxilla_from_mandible` becomes `maxilla_scan_from_mandible_scan`, the motion of the lower
//! scan against the upper one. It also holds the two scans' relative pose in maximal
//! intercuspation as the scanner's bite registration gave it (identity when the scans were
//! exported in occlusion). When the patient bites in maximal intercuspation in front of the
//! camera, [`calibrate_intercuspation`] corrects the mandible's registration so that the
//! tracked pose coincides with that scanned one, and says how large the correction was.

use jawtrack_pose::Pose;
use nalgebra::{Matrix4, UnitQuaternion, Vector3, Vector4};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The registration file's only version.
pub const REGISTRATION_VERSION: u32 = 1;

/// Where the markers sit in the tooth scans (mm, 4×4 row-major matrices in the file).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Registration {
    /// Always [`REGISTRATION_VERSION`].
    pub version: u32,
    /// Always `"mm"`.
    pub units: Units,
    /// Maps maxilla-marker points into the upper scan's frame.
    pub maxilla_scan_from_maxilla_marker: Pose,
    /// Maps mandible-marker points into the lower scan's frame.
    pub mandible_scan_from_mandible_marker: Pose,
    /// The lower scan in the upper scan's frame in maximal intercuspation (the scanner's bite
    /// registration); identity when the scans were exported in occlusion.
    #[serde(default = "Pose::identity")]
    pub maxilla_scan_from_mandible_scan_at_intercuspation: Pose,
}

/// The unit string of a file, checked on reading (`"mm"` is the only one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Units {
    /// Millimetres.
    #[serde(rename = "mm")]
    Millimetres,
}

/// Why a registration could not be read or used.
#[derive(Debug, thiserror::Error)]
pub enum RegistrationError {
    /// The file could not be read.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
    /// The JSON does not describe a registration; `field` is its path in the document.
    #[error("registration field `{field}`: {reason}")]
    Field {
        /// Where in the document (e.g. `maxilla_scan_from_maxilla_marker`).
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A version this build does not read.
    #[error("registration field `version`: {0} is not supported (expected {REGISTRATION_VERSION})")]
    Version(u32),
    /// Too few intercuspation samples to calibrate from.
    #[error("the intercuspation calibration needs at least {needed} frames with both bodies tracked, got {got}")]
    TooFewSamples {
        /// Required.
        needed: usize,
        /// Given.
        got: usize,
    },
}

impl Registration {
    /// Markers and scans sharing their frames: the scan poses are the marker poses.
    pub fn identity() -> Self {
        Registration {
            version: REGISTRATION_VERSION,
            units: Units::Millimetres,
            maxilla_scan_from_maxilla_marker: Pose::identity(),
            mandible_scan_from_mandible_marker: Pose::identity(),
            maxilla_scan_from_mandible_scan_at_intercuspation: Pose::identity(),
        }
    }

    /// Parses a registration file's text, naming the field at fault.
    pub fn from_json(text: &str) -> Result<Self, RegistrationError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let r: Registration = serde_path_to_error::deserialize(de).map_err(|e| {
            let field = e.path().to_string();
            RegistrationError::Field { field, reason: e.into_inner().to_string() }
        })?;
        if r.version != REGISTRATION_VERSION {
            return Err(RegistrationError::Version(r.version));
        }
        Ok(r)
    }

    /// Reads a registration file.
    pub fn load(path: &Path) -> Result<Self, RegistrationError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| RegistrationError::Io { path: path.display().to_string(), reason: e.to_string() })?;
        Self::from_json(&text)
    }

    /// The registration as JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The lower scan in the upper scan's frame, given the mandible marker in the maxilla
    /// marker's frame.
    pub fn maxilla_scan_from_mandible_scan(&self, maxilla_from_mandible: &Pose) -> Pose {
        self.maxilla_scan_from_maxilla_marker
            * *maxilla_from_mandible
            * self.mandible_scan_from_mandible_marker.inverse()
    }
}

/// The outcome of the maximal-intercuspation calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct IntercuspationCalibration {
    /// The registration with the mandible's corrected.
    pub registration: Registration,
    /// How far the correction turned the lower scan (°).
    pub rotation_deg: f64,
    /// How far the correction moved the lower scan's origin (mm).
    pub translation_mm: f64,
    /// The largest distance (mm) between a sample's lower scan origin and their mean: how
    /// still the patient held the bite.
    pub spread_mm: f64,
    /// Frames used.
    pub samples: usize,
}

/// Corrects `registration` so that the mean of `maxilla_from_mandible` samples, taken while
/// the patient bites in maximal intercuspation, maps the lower scan onto its scanned
/// intercuspal pose. Only the mandible's registration changes: the upper scan is the
/// reference the lower one moves against.
pub fn calibrate_intercuspation(
    registration: &Registration,
    maxilla_from_mandible: &[Pose],
) -> Result<IntercuspationCalibration, RegistrationError> {
    const NEEDED: usize = 1;
    let Some(mean) = mean_pose(maxilla_from_mandible) else {
        return Err(RegistrationError::TooFewSamples { needed: NEEDED, got: maxilla_from_mandible.len() });
    };
    // maxilla_scan_from_maxilla_marker · mean · mandible_scan_from_mandible_marker'⁻¹ = target
    let target = registration.maxilla_scan_from_mandible_scan_at_intercuspation;
    let corrected = target.inverse() * registration.maxilla_scan_from_maxilla_marker * mean;
    let mandible_scan_from_mandible_marker = corrected;
    let correction = mandible_scan_from_mandible_marker * registration.mandible_scan_from_mandible_marker.inverse();
    let spread_mm =
        maxilla_from_mandible.iter().map(|p| (p.translation() - mean.translation()).norm()).fold(0.0, f64::max);
    Ok(IntercuspationCalibration {
        registration: Registration { mandible_scan_from_mandible_marker, ..*registration },
        rotation_deg: correction.rotation().angle().to_degrees(),
        translation_mm: correction.translation().norm(),
        spread_mm,
        samples: maxilla_from_mandible.len(),
    })
}

/// The mean of rigid transforms: the mean translation, and the rotation whose quaternion is
/// the principal eigenvector of Σ qqᵀ (the chordal L2 mean, sign-invariant).
pub fn mean_pose(poses: &[Pose]) -> Option<Pose> {
    if poses.is_empty() {
        return None;
    }
    let n = poses.len() as f64;
    let translation = poses.iter().fold(Vector3::zeros(), |a, p| a + p.translation()) / n;
    let mut m = Matrix4::zeros();
    for p in poses {
        let q = p.rotation().into_inner().coords;
        m += q * q.transpose();
    }
    let eig = m.symmetric_eigen();
    let (best, _) = eig.eigenvalues.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let q: Vector4<f64> = eig.eigenvectors.column(best).into_owned();
    let rotation = UnitQuaternion::from_quaternion(nalgebra::Quaternion::from(q));
    Some(Pose::from_parts(rotation, translation)).filter(Pose::is_finite)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(r: [f64; 3], t: [f64; 3]) -> Pose {
        Pose::from_axis_angle(Vector3::from(r), Vector3::from(t))
    }

    #[test]
    fn scans_follow_the_markers() {
        let reg = Registration {
            maxilla_scan_from_maxilla_marker: pose([0.1, 0.0, 0.2], [5.0, -30.0, 40.0]),
            mandible_scan_from_mandible_marker: pose([0.0, -0.3, 0.1], [-2.0, 28.0, 41.0]),
            ..Registration::identity()
        };
        let maxilla_from_mandible = pose([0.2, 0.05, 0.0], [0.0, 44.0, 3.0]);
        let s = reg.maxilla_scan_from_mandible_scan(&maxilla_from_mandible);
        // A point of the lower scan, through the mandible marker and the maxilla marker.
        let x = nalgebra::Point3::new(1.0, 2.0, 3.0);
        let via_markers = reg.maxilla_scan_from_maxilla_marker.transform_point(
            &maxilla_from_mandible
                .transform_point(&reg.mandible_scan_from_mandible_marker.inverse().transform_point(&x)),
        );
        assert!((s.transform_point(&x) - via_markers).norm() < 1e-12);
    }

    #[test]
    fn intercuspation_calibration_recovers_the_registration_error() {
        // The true registration, and one off by 1.5° and 0.8 mm (a misplaced scan-body fit).
        let truth = Registration {
            maxilla_scan_from_maxilla_marker: pose([0.0, 0.0, 0.1], [0.0, -22.0, 38.0]),
            mandible_scan_from_mandible_marker: pose([0.05, 0.0, 0.0], [0.0, 22.0, 38.0]),
            maxilla_scan_from_mandible_scan_at_intercuspation: pose([0.0, 0.01, 0.0], [0.0, 0.3, 0.0]),
            ..Registration::identity()
        };
        let error = pose([0.0, 1.5f64.to_radians(), 0.0], [0.8, 0.0, 0.0]);
        let wrong = Registration {
            mandible_scan_from_mandible_marker: error * truth.mandible_scan_from_mandible_marker,
            ..truth
        };
        // What the tracker measures in the bite, with a little noise around the true pose.
        let bite = truth.maxilla_scan_from_maxilla_marker.inverse()
            * truth.maxilla_scan_from_mandible_scan_at_intercuspation
            * truth.mandible_scan_from_mandible_marker;
        let samples: Vec<Pose> = (0..20)
            .map(|i| {
                let s = if i % 2 == 0 { 1.0 } else { -1.0 };
                bite * pose([s * 1e-4, 0.0, -s * 1e-4], [s * 0.01, -s * 0.01, 0.0])
            })
            .collect();
        let cal = calibrate_intercuspation(&wrong, &samples).expect("calibrates");
        assert_eq!(cal.samples, 20);
        assert!((cal.rotation_deg - 1.5).abs() < 0.01, "{}", cal.rotation_deg);
        assert!(cal.spread_mm > 0.01 && cal.spread_mm < 0.02, "{}", cal.spread_mm);
        let fixed = cal.registration.maxilla_scan_from_mandible_scan(&bite);
        let (angle, dist) = fixed.distance_to(&truth.maxilla_scan_from_mandible_scan_at_intercuspation);
        assert!(angle < 1e-9 && dist < 1e-9, "{angle} rad, {dist} mm");
        assert_eq!(cal.registration.maxilla_scan_from_maxilla_marker, truth.maxilla_scan_from_maxilla_marker);
        assert!(matches!(
            calibrate_intercuspation(&wrong, &[]),
            Err(RegistrationError::TooFewSamples { needed: 1, got: 0 })
        ));
    }

    #[test]
    fn the_mean_of_rotations_ignores_quaternion_sign() {
        let a = pose([0.0, 0.0, 0.2], [1.0, 0.0, 0.0]);
        let b = pose([0.0, 0.0, 0.4], [3.0, 0.0, 0.0]);
        let flipped = Pose::from_parts(UnitQuaternion::new_unchecked(-b.rotation().into_inner()), b.translation());
        let m = mean_pose(&[a, flipped]).expect("mean");
        assert!((m.rotation().angle() - 0.3).abs() < 1e-3, "{}", m.rotation().angle());
        assert!((m.translation().x - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_bad_file_names_its_field() {
        let good = Registration::identity().to_json();
        assert_eq!(Registration::from_json(&good).expect("round trip"), Registration::identity());
        let e = Registration::from_json(&good.replace("\"version\": 1", "\"version\": 2")).expect_err("v2");
        assert!(e.to_string().contains("version"), "{e}");
        let e = Registration::from_json(r#"{"version":1,"units":"mm","maxilla_scan_from_maxilla_marker":[1,0,0,0]}"#)
            .expect_err("short matrix");
        assert!(e.to_string().contains("maxilla_scan_from_maxilla_marker"), "{e}");
        let e = Registration::from_json(&good.replace("\"mm\"", "\"cm\"")).expect_err("units");
        assert!(e.to_string().contains("units"), "{e}");
        let e = Registration::from_json(
            r#"{"version":1,"units":"mm","maxilla_scan_from_maxilla_marker":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}"#,
        )
        .expect_err("missing");
        assert!(e.to_string().contains("mandible_scan_from_mandible_marker"), "{e}");
        let bent = good.replacen("1.0", "1.5", 1);
        let e = Registration::from_json(&bent).expect_err("not a rotation");
        assert!(e.to_string().contains("maxilla_scan_from_maxilla_marker"), "{e}");
    }
}
