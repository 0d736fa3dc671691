//! The marker file: versioned JSON describing both bodies' tags in millimetres.
//!
//! ```json
//! {"version": 1, "units": "mm", "edge": 12.7,
//!  "bodies": [{"name": "maxilla",
//!              "tags": [{"id": 0, "face": 0, "size": 10.6,
//!                        "corners": [[x,y,z] ×4], "center": [x,y,z], "face_polygon": [[x,y,z] ×5]}, …]},
//!             {"name": "mandible", "tags": […]}]}
//! ```
//!
//! Corners are in detection order (bottom-left, bottom-right, top-right, top-left of the
//! upright tag); the face polygon starts at the apex and runs counter-clockwise seen from
//! outside. A calibrated marker uses the same schema; its corners may deviate from the ideal
//! solid, within the tolerances checked here.

use crate::MarkerError;
use crate::model::{Body, BodyKind, Marker, Tag, fitted_normal, newell_normal, plane_deviation};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The only marker file version this build reads and writes.
pub const MARKER_FILE_VERSION: u32 = 1;

/// How far (mm) a face's vertices, or a tag's corners, may stray from their common plane.
/// Printed tags lie flat on a flat face; calibration noise is far below this.
pub const PLANARITY_TOLERANCE_MM: f64 = 0.1;

/// How far (mm) a corner may stick out of its face polygon.
const OUTSIDE_TOLERANCE_MM: f64 = 0.05;

/// How far a tag side may differ from `size`, as a fraction of it.
const SIDE_TOLERANCE: f64 = 0.1;

#[derive(Serialize, Deserialize)]
struct FileV1 {
    version: u32,
    units: String,
    edge: f64,
    bodies: Vec<FileBody>,
}

#[derive(Serialize, Deserialize)]
struct FileBody {
    name: String,
    tags: Vec<FileTag>,
}

#[derive(Serialize, Deserialize)]
struct FileTag {
    id: u32,
    face: usize,
    size: f64,
    corners: [[f64; 3]; 4],
    center: [f64; 3],
    face_polygon: [[f64; 3]; 5],
}

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn vec3(a: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

impl Marker {
    /// The marker file's JSON text (pretty-printed, numbers written to round-trip exactly).
    pub fn to_json(&self) -> String {
        let file = FileV1 {
            version: MARKER_FILE_VERSION,
            units: "mm".into(),
            edge: self.edge,
            bodies: self
                .bodies
                .iter()
                .map(|b| FileBody {
                    name: b.kind.name().into(),
                    tags: b
                        .tags
                        .iter()
                        .map(|t| FileTag {
                            id: t.id,
                            face: t.face,
                            size: t.size,
                            corners: t.corners.map(|c| arr(&c)),
                            center: arr(&t.center),
                            face_polygon: t.face_polygon.map(|c| arr(&c)),
                        })
                        .collect(),
                })
                .collect(),
        };
        serde_json::to_string_pretty(&file).expect("a marker always serialises")
    }

    /// Parses and checks a marker file's text. Errors name the field and the tag.
    pub fn from_json(text: &str) -> Result<Marker, MarkerError> {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| MarkerError::Json(e.to_string()))?;
        let version = value.get("version").ok_or_else(|| field("marker file", "version", "is missing"))?;
        match version.as_u64() {
            Some(v) if v == u64::from(MARKER_FILE_VERSION) => {}
            Some(v) => return Err(MarkerError::Version { found: v.to_string() }),
            None => return Err(MarkerError::Version { found: version.to_string() }),
        }
        let file: FileV1 = serde_path_to_error::deserialize(&value).map_err(|e| {
            let path = e.path().to_string();
            MarkerError::Field {
                location: describe_path(&value, &path),
                field: path,
                reason: e.into_inner().to_string(),
            }
        })?;
        let marker = from_file(file)?;
        marker.validate()?;
        Ok(marker)
    }

    /// Reads a marker file.
    pub fn load(path: &Path) -> Result<Marker, MarkerError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| MarkerError::Io { path: path.display().to_string(), reason: e.to_string() })?;
        Marker::from_json(&text).map_err(|e| e.in_file(path))
    }

    /// Writes the marker file.
    pub fn save(&self, path: &Path) -> Result<(), MarkerError> {
        std::fs::write(path, self.to_json() + "\n")
            .map_err(|e| MarkerError::Io { path: path.display().to_string(), reason: e.to_string() })
    }

    /// Checks everything a marker must satisfy to be tracked: known body names at most once,
    /// unique tag ids and faces, finite numbers, planar faces, tags on and inside their face,
    /// wound consistently with the outward normal and roughly square.
    pub fn validate(&self) -> Result<(), MarkerError> {
        if !self.edge.is_finite() || self.edge <= 0.0 {
            return Err(field("marker file", "edge", &format!("must be a positive number of mm, got {}", self.edge)));
        }
        if self.bodies.is_empty() {
            return Err(field("marker file", "bodies", "is empty"));
        }
        let mut ids = std::collections::HashMap::new();
        for (bi, body) in self.bodies.iter().enumerate() {
            if self.bodies[..bi].iter().any(|b| b.kind == body.kind) {
                return Err(field(&format!("bodies[{bi}]"), "name", &format!("body '{}' appears twice", body.kind)));
            }
            if body.tags.is_empty() {
                return Err(field(&format!("body '{}'", body.kind), "tags", "is empty"));
            }
            for (ti, tag) in body.tags.iter().enumerate() {
                let loc = format!("body '{}', tag id {} (bodies[{bi}].tags[{ti}])", body.kind, tag.id);
                if let Some(prev) = ids.insert(tag.id, body.kind) {
                    return Err(field(&loc, "id", &format!("duplicate id {} (already on the {prev})", tag.id)));
                }
                if body.tags[..ti].iter().any(|t| t.face == tag.face) {
                    return Err(field(&loc, "face", &format!("face {} carries two tags", tag.face)));
                }
                validate_tag(tag).map_err(|(f, reason)| field(&loc, f, &reason))?;
            }
        }
        Ok(())
    }
}

fn validate_tag(t: &Tag) -> Result<(), (&'static str, String)> {
    if t.face >= 12 {
        return Err(("face", format!("must be 0..11, got {}", t.face)));
    }
    if !t.size.is_finite() || t.size <= 0.0 {
        return Err(("size", format!("must be a positive number of mm, got {}", t.size)));
    }
    for (i, c) in t.corners.iter().enumerate() {
        if !c.iter().all(|v| v.is_finite()) {
            return Err(("corners", format!("corner {i} is not finite")));
        }
    }
    if !t.center.iter().all(|v| v.is_finite()) {
        return Err(("center", "is not finite".into()));
    }
    for (i, c) in t.face_polygon.iter().enumerate() {
        if !c.iter().all(|v| v.is_finite()) {
            return Err(("face_polygon", format!("vertex {i} is not finite")));
        }
    }
    // Each vertex against the plane of the other four: a least-squares plane through all
    // five would absorb part of a single misplaced vertex.
    let off = (0..5)
        .map(|i| {
            let others: Vec<Vector3<f64>> = (0..5).filter(|&k| k != i).map(|k| t.face_polygon[k]).collect();
            let n = fitted_normal(&others);
            let mean = others.iter().sum::<Vector3<f64>>() / 4.0;
            (t.face_polygon[i] - mean).dot(&n).abs().max(plane_deviation(&others, &n))
        })
        .fold(0.0, f64::max);
    if off > PLANARITY_TOLERANCE_MM {
        return Err((
            "face_polygon",
            format!(
                "the face is not planar: a vertex is {off:.3} mm off the plane of the others (tolerance {PLANARITY_TOLERANCE_MM} mm)"
            ),
        ));
    }
    let n = newell_normal(&t.face_polygon);
    if !n.iter().all(|v| v.is_finite()) {
        return Err(("face_polygon", "is degenerate (zero area)".into()));
    }
    let poly_center = t.face_polygon.iter().sum::<Vector3<f64>>() / 5.0;
    if n.dot(&poly_center) <= 0.0 {
        return Err(("face_polygon", "runs clockwise seen from outside (its normal points into the body)".into()));
    }
    for i in 0..5 {
        let a = t.face_polygon[(i + 1) % 5] - t.face_polygon[i];
        let b = t.face_polygon[(i + 2) % 5] - t.face_polygon[(i + 1) % 5];
        if a.cross(&b).dot(&n) <= 0.0 {
            return Err(("face_polygon", format!("is not convex at vertex {}", (i + 1) % 5)));
        }
    }
    let mean = poly_center;
    for (i, c) in t.corners.iter().enumerate() {
        let d = (c - mean).dot(&n).abs();
        if d > PLANARITY_TOLERANCE_MM {
            return Err(("corners", format!("corner {i} is {d:.3} mm off its face's plane")));
        }
        let inside = (0..5)
            .map(|k| {
                let a = t.face_polygon[k];
                let b = t.face_polygon[(k + 1) % 5];
                (a - c).dot(&(b - a).cross(&n).normalize())
            })
            .fold(f64::INFINITY, f64::min);
        if inside < -OUTSIDE_TOLERANCE_MM {
            return Err(("corners", format!("corner {i} lies {:.3} mm outside its face", -inside)));
        }
    }
    for i in 0..4 {
        let a = t.corners[(i + 1) % 4] - t.corners[i];
        let b = t.corners[(i + 2) % 4] - t.corners[(i + 1) % 4];
        if a.cross(&b).dot(&n) <= 0.0 {
            return Err((
                "corners",
                format!(
                    "wind clockwise seen from outside at corner {} (mirrored, or not in detection order bottom-left, \
                 bottom-right, top-right, top-left)",
                    (i + 1) % 4
                ),
            ));
        }
        let side = a.norm();
        if (side - t.size).abs() > SIDE_TOLERANCE * t.size {
            return Err(("corners", format!("side {i} measures {side:.3} mm but size says {:.3} mm", t.size)));
        }
    }
    let corner_mean = t.corners.iter().sum::<Vector3<f64>>() / 4.0;
    let off = (t.center - corner_mean).norm();
    if off > 0.1 * t.size {
        return Err(("center", format!("is {off:.3} mm from the middle of its corners")));
    }
    Ok(())
}

fn from_file(file: FileV1) -> Result<Marker, MarkerError> {
    if file.units != "mm" {
        return Err(field("marker file", "units", &format!("must be \"mm\", got \"{}\"", file.units)));
    }
    let bodies = file
        .bodies
        .into_iter()
        .enumerate()
        .map(|(bi, b)| {
            let kind = BodyKind::from_name(&b.name).ok_or_else(|| {
                field(
                    &format!("bodies[{bi}]"),
                    "name",
                    &format!("must be \"maxilla\" or \"mandible\", got \"{}\"", b.name),
                )
            })?;
            let tags = b
                .tags
                .into_iter()
                .map(|t| Tag {
                    id: t.id,
                    face: t.face,
                    size: t.size,
                    corners: t.corners.map(|c| vec3(&c)),
                    center: vec3(&t.center),
                    face_polygon: t.face_polygon.map(|c| vec3(&c)),
                })
                .collect();
            Ok(Body { kind, tags })
        })
        .collect::<Result<Vec<_>, MarkerError>>()?;
    Ok(Marker { edge: file.edge, bodies })
}

fn field(location: &str, field: &str, reason: &str) -> MarkerError {
    MarkerError::Field { location: location.into(), field: field.into(), reason: reason.into() }
}

/// Turns a path like `bodies[0].tags[3].center` into "body 'maxilla', tag id 3 (bodies[0].tags[3])"
/// when the JSON lets us read those names.
fn describe_path(value: &serde_json::Value, path: &str) -> String {
    let parse_index = |s: &str, key: &str| -> Option<usize> {
        let start = s.find(&format!("{key}["))? + key.len() + 1;
        s[start..].split(']').next()?.parse().ok()
    };
    let Some(bi) = parse_index(path, "bodies") else { return "marker file".into() };
    let body = &value["bodies"][bi];
    let name = body["name"].as_str().map(|n| format!("body '{n}'")).unwrap_or_else(|| format!("bodies[{bi}]"));
    match parse_index(path, "tags") {
        Some(ti) => match body["tags"][ti]["id"].as_u64() {
            Some(id) => format!("{name}, tag id {id} (bodies[{bi}].tags[{ti}])"),
            None => format!("{name}, bodies[{bi}].tags[{ti}]"),
        },
        None => name,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{Value, json};

    fn nominal_json() -> Value {
        serde_json::from_str(&Marker::default().to_json()).expect("valid json")
    }

    fn err_of(v: &Value) -> String {
        Marker::from_json(&v.to_string()).expect_err("must be rejected").to_string()
    }

    #[test]
    fn json_round_trip_is_exact() {
        let m = Marker::default();
        let back = Marker::from_json(&m.to_json()).expect("own output parses");
        assert_eq!(m, back);
        let v = nominal_json();
        assert_eq!(v["version"], 1);
        assert_eq!(v["units"], "mm");
        assert_eq!(v["bodies"][1]["name"], "mandible");
        assert_eq!(v["bodies"][1]["tags"][0]["id"], 12);
    }

    #[test]
    fn calibrated_deviations_are_accepted() {
        let m = Marker::default()
            .with_print_errors(&[(3, crate::PrintError { shift_x: 0.3, shift_y: -0.2, rotation: 0.02 })])
            .expect("id 3");
        let back = Marker::from_json(&m.to_json()).expect("a displaced tag is a valid calibrated marker");
        assert_eq!(back, m);
    }

    #[test]
    fn wrong_version_is_named() {
        let mut v = nominal_json();
        v["version"] = json!(2);
        assert!(err_of(&v).contains("version 2"), "{}", err_of(&v));
        v.as_object_mut().expect("object").remove("version");
        assert!(err_of(&v).contains("version"));
    }

    #[test]
    fn missing_field_names_field_and_tag() {
        let mut v = nominal_json();
        v["bodies"][0]["tags"][3].as_object_mut().expect("object").remove("center");
        let e = err_of(&v);
        assert!(e.contains("tag id 3") && e.contains("center"), "{e}");
    }

    #[test]
    fn wrong_type_names_field_and_tag() {
        let mut v = nominal_json();
        v["bodies"][1]["tags"][2]["corners"][1][0] = json!("x");
        let e = err_of(&v);
        assert!(e.contains("tag id 14") && e.contains("corners"), "{e}");
    }

    #[test]
    fn non_planar_face_is_named() {
        let mut v = nominal_json();
        let z = v["bodies"][0]["tags"][7]["face_polygon"][2][2].as_f64().expect("number");
        v["bodies"][0]["tags"][7]["face_polygon"][2][2] = json!(z + 1.0);
        let e = err_of(&v);
        assert!(e.contains("tag id 7") && e.contains("not planar"), "{e}");
    }

    #[test]
    fn duplicate_id_is_named() {
        let mut v = nominal_json();
        v["bodies"][1]["tags"][4]["id"] = json!(2);
        let e = err_of(&v);
        assert!(e.contains("duplicate id 2"), "{e}");
    }

    #[test]
    fn non_finite_numbers_are_rejected() {
        // JSON has no NaN: the token itself is a syntax error, reported with its position.
        let text = Marker::default().to_json().replacen("\"size\": ", "\"size\": NaN, \"x\": ", 1);
        assert!(Marker::from_json(&text).expect_err("NaN").to_string().contains("JSON"));
        let mut m = Marker::default();
        m.bodies[0].tags[5].center.x = f64::NAN;
        let e = m.validate().expect_err("NaN centre").to_string();
        assert!(e.contains("tag id 5") && e.contains("center"), "{e}");
    }

    #[test]
    fn mirrored_tag_is_rejected() {
        let mut m = Marker::default();
        m.bodies[0].tags[1].corners.swap(0, 1);
        m.bodies[0].tags[1].corners.swap(2, 3);
        let e = m.validate().expect_err("mirrored").to_string();
        assert!(e.contains("tag id 1") && e.contains("clockwise"), "{e}");
    }

    #[test]
    fn other_bad_values_are_named() {
        let mut v = nominal_json();
        v["units"] = json!("m");
        assert!(err_of(&v).contains("units"));
        let mut v = nominal_json();
        v["bodies"][0]["name"] = json!("skull");
        assert!(err_of(&v).contains("maxilla"));
        let mut v = nominal_json();
        v["bodies"][0]["tags"][0]["size"] = json!(-3);
        assert!(err_of(&v).contains("size"));
        let mut v = nominal_json();
        v["bodies"][0]["tags"][0]["face"] = json!(1);
        assert!(err_of(&v).contains("face 1 carries two tags"));
        assert!(Marker::from_json("{not json").expect_err("syntax").to_string().contains("JSON"));
    }
}
