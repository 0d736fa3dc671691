//! The JSON files a user hands to `jawtrack`: marker, registration, points and camera files.
//! Each is read as the CLI and the FFI read it; a file that reads must write back to text that
//! reads to the same text (a fixed point after one round), so nothing accepted is lost or
//! changed by saving it.

use crate::run::Verdict;
use jawtrack_camera_calibration::{CalibratedAt, CameraCalibration, CameraFile};
use jawtrack_kinematics::AnatomicalPoints;
use jawtrack_kinematics::anatomy::{Condyles, OcclusalPlane};
use jawtrack_marker::Marker;
use jawtrack_registration::Registration;

/// Reads `text` with `read`, then checks `write` ∘ `read` is a fixed point from the first write.
pub fn round_trip<T, E: std::fmt::Display>(
    input: &[u8],
    read: impl Fn(&str) -> Result<T, E>,
    write: impl Fn(&T) -> String,
) -> Result<Verdict, String> {
    // The CLI reads files with `read_to_string`, which refuses what is not UTF-8.
    let Ok(text) = std::str::from_utf8(input) else { return Ok(Verdict::Refused) };
    let first = match read(text) {
        Ok(v) => v,
        Err(e) => return refused(e),
    };
    let written = write(&first);
    let again = read(&written).map_err(|e| format!("its own output does not read back: {e}\n{written}"))?;
    let rewritten = write(&again);
    if rewritten != written && !same_json(&written, &rewritten) {
        return Err(format!("written twice, it differs:\n{written}\n---\n{rewritten}"));
    }
    Ok(Verdict::Accepted)
}

/// Whether two JSON texts hold the same values, numbers agreeing to 1e-12 (relative, or
/// absolute below 1): a rotation read from a matrix is projected onto the rotations, which can
/// move its entries by an ulp each time it is read, and nothing else may change at all.
pub fn same_json(a: &str, b: &str) -> bool {
    match (serde_json::from_str(a), serde_json::from_str(b)) {
        (Ok(a), Ok(b)) => close(&a, &b),
        _ => false,
    }
}

fn close(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(x), Some(y)) if x.fract() != 0.0 || y.fract() != 0.0 => (x - y).abs() <= 1e-12 * x.abs().max(1.0),
            _ => x == y,
        },
        (Value::Array(x), Value::Array(y)) => x.len() == y.len() && x.iter().zip(y).all(|(x, y)| close(x, y)),
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| close(v, w)))
        }
        _ => a == b,
    }
}

/// A refusal, which must say why: an error with no message is a broken invariant.
pub fn refused(e: impl std::fmt::Display) -> Result<Verdict, String> {
    if e.to_string().trim().is_empty() { Err("refused with an empty message".into()) } else { Ok(Verdict::Refused) }
}

pub fn marker_seeds() -> Vec<Vec<u8>> {
    let v3 = Marker::default().to_json();
    let mut seeds = vec![v3.clone().into_bytes()];
    let value: serde_json::Value = serde_json::from_str(&v3).unwrap_or_default();
    for version in [1, 2] {
        let mut older = value.clone();
        older["version"] = version.into();
        if let Some(o) = older.as_object_mut() {
            o.remove("family");
            o.remove("solid");
        }
        seeds.push(older.to_string().into_bytes());
    }
    seeds
}

pub fn marker(input: &[u8]) -> Result<Verdict, String> {
    round_trip(input, Marker::from_json, Marker::to_json)
}

pub fn registration_seeds() -> Vec<Vec<u8>> {
    vec![Registration::identity().to_json().into_bytes()]
}

pub fn registration(input: &[u8]) -> Result<Verdict, String> {
    round_trip(input, Registration::from_json, Registration::to_json)
}

pub fn points_seeds() -> Vec<Vec<u8>> {
    let plane =
        OcclusalPlane { incisal: [0.0, -2.0, 45.0], left_molar: [24.0, 0.0, 5.0], right_molar: [-24.0, 0.0, 5.0] };
    let condyles = Condyles { left: [50.0, 20.0, -50.0], right: [-50.0, 20.0, -50.0] };
    [Some(condyles), None]
        .into_iter()
        .filter_map(|c| AnatomicalPoints::new(plane, [0.0, -3.0, 44.0], c).ok())
        .map(|p| p.to_json().into_bytes())
        .collect()
}

pub fn points(input: &[u8]) -> Result<Verdict, String> {
    round_trip(input, AnatomicalPoints::from_json, AnatomicalPoints::to_json)
}

pub fn camera_seeds() -> Vec<Vec<u8>> {
    let calibration = serde_json::json!({
        "image_size": [1920, 1080],
        "intrinsics": {"fx": 1450.0, "fy": 1450.5, "cx": 959.5, "cy": 539.5, "k1": 0.01, "k2": -0.002},
        "readout_s": 0.0101,
        "sigma": {"fx": 1.0, "fy": 1.0, "cx": 0.5, "cy": 0.5, "k1": 0.001, "k2": 0.001, "readout_s": 0.0001,
                  "corner_distortion_px": 0.1},
        "rms_px": 0.05, "frames_used": 100, "views_used": 180, "corners_used": 2000,
        "sightings_dropped": 0, "coverage": 0.7
    });
    let Ok(calibration) = serde_json::from_value::<CameraCalibration>(calibration) else { return vec![] };
    [CalibratedAt { lens_position: Some(0.81), zoom: Some(2.0) }, CalibratedAt::default()]
        .into_iter()
        .map(|at| CameraFile::new(calibration.clone(), at).to_json().into_bytes())
        .collect()
}

pub fn camera(input: &[u8]) -> Result<Verdict, String> {
    round_trip(input, |t| CameraFile::from_json(t, "camera.json"), CameraFile::to_json)
}
