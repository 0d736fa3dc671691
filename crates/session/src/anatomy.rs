//! The anatomy a command measures in: the patient's points file placed through a registration
//! (their occlusal plane, lower incisal point and condyles), else the standard harness
//! mounting — and the words that say which, for every output.

use crate::SessionError;
use jawtrack_kinematics::{AnatomicalPoints, Anatomy};
use jawtrack_pose::Pose;
use jawtrack_registration::Registration;
use nalgebra::Vector3;
use std::path::Path;

/// Reads a points file (`jawtrack points`), naming it in any error.
pub fn read_points(file: &Path) -> Result<AnatomicalPoints, SessionError> {
    let err = |reason: String| SessionError::Points { path: file.display().to_string(), reason };
    let text = std::fs::read_to_string(file).map_err(|e| err(e.to_string()))?;
    AnatomicalPoints::from_json(&text).map_err(|e| err(e.to_string()))
}

/// Reads a registration file (`jawtrack register`) when one is given, naming it in any error.
pub fn read_registration(path: Option<&Path>) -> Result<Option<Registration>, SessionError> {
    path.map(|p| {
        Registration::load(p).map_err(|source| SessionError::Registration { path: p.display().to_string(), source })
    })
    .transpose()
}

/// The patient's left in the upper scan's frame, from a points file: where the contact maps
/// put the patient's left when the teeth are not named by FDI number.
pub fn upper_scan_left(points: Option<&Path>) -> Result<Option<Vector3<f64>>, SessionError> {
    Ok(match points {
        Some(p) => Some(read_points(p)?.head_from_scan().inverse().rotation() * Vector3::x()),
        None => None,
    })
}

/// The anatomy of the points file `points` through `registration`, with the closed jaw at
/// `rest`; the standard harness mounting without `points`.
///
/// # Examples
///
/// ```
/// let standard = jawtrack_session::anatomy(None, None, &jawtrack_pose::Pose::identity()).unwrap();
/// assert!(!standard.condyles_given);
/// ```
pub fn anatomy(
    points: Option<&Path>,
    registration: Option<&Registration>,
    rest: &Pose,
) -> Result<Anatomy, SessionError> {
    let Some(file) = points else {
        return Ok(Anatomy::standard());
    };
    let Some(reg) = registration else {
        return Err(SessionError::PointsNeedRegistration);
    };
    let p = read_points(file)?;
    let given = p.condyles.is_some();
    let mounting = p.mounting(&reg.maxilla_scan_from_maxilla_marker, rest);
    let mut warnings = Vec::new();
    if mounting.head_from_maxilla.translation().y > 0.0 {
        warnings.push(format!(
            "in the frame of {} the maxilla marker sits below the occlusal plane: are the left and right molar \
             points swapped?",
            file.display()
        ));
    }
    Ok(Anatomy {
        mounting,
        reference_plane: "the occlusal plane of the points file",
        landmarks: if given {
            "the points file's condyles and lower incisal point"
        } else {
            "the points file's lower incisal point, and the Bonwill triangle's condyles"
        },
        condyles_given: given,
        warnings,
    })
}
