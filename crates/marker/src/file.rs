//! The marker file: versioned JSON describing both bodies' tags in millimetres.
//!
//! ```json
//! {"version": 3, "units": "mm", "family": "tag36h11", "solid": "dodecahedron", "edge": 12.7,
//!  "bodies": [{"name": "maxilla",
//!              "calibration": {"views": 18, "rms_before_px": 1.9, "rms_after_px": 0.21,
//!                              "recordings": ["calibration_frames"]},
//!              "tags": [{"id": 0, "face": 0, "size": 10.6,
//!                        "corners": [[x,y,z] ×4], "center": [x,y,z], "face_polygon": [[x,y,z] ×5 or ×4],
//!                        "calibration": {"status": "calibrated", "views": 9,
//!                                        "rms_before_px": 2.1, "rms_after_px": 0.2}}, …]},
//!             {"name": "mandible", "tags": […]}]}
//! ```
//!
//! Corners are in detection order (bottom-left, bottom-right, top-right, top-left of the
//! upright tag); the face polygon starts at the apex and runs counter-clockwise seen from
//! outside. A calibrated marker uses the same schema; its corners may deviate from the ideal
//! solid, within the tolerances checked here.
//!
//! **Provenance** (version 2): a calibrated body says how it was calibrated (`calibration`:
//! the views that showed two of its tags, the RMS reprojection error before and after, the
//! recordings), and each of its tags whether the calibration placed it (`"status":
//! "calibrated"`, with its views and RMS error before and after) or left it at the nominal place
//! (`"status": "nominal"`, with the views it had, 0 if never seen). A body has `calibration`
//! exactly when its tags have. A nominal marker has none; nor does a version 1 file, read with
//! its provenance unknown.
//!
//! **Family and solid** (version 3): the AprilTag family the tags are printed in (`tag36h11`,
//! `tag25h9` or `tag16h5`; every tag id must be in it) and the solid that carries them
//! (`dodecahedron`, whose faces are pentagons, or `cube`, whose faces are squares; see
//! [`crate::solid`]). Files of versions 1 and 2 are tag36h11 on a dodecahedron.

use crate::MarkerError;
use crate::SolidKind;
use crate::model::{
    Body, BodyKind, BodyProvenance, Marker, Tag, TagProvenance, fitted_normal, newell_normal, plane_deviation,
};
use jawtrack_tag_family::TagFamily;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The marker file version this build writes; it reads this one, version 2 (which names no
/// family or solid) and version 1 (which has no provenance either).
pub const MARKER_FILE_VERSION: u32 = 3;

/// How far (mm) a face's vertices, or a tag's corners, may stray from their common plane.
/// Printed tags lie flat on a flat face; calibration noise is far below this.
pub const PLANARITY_TOLERANCE_MM: f64 = 0.1;

/// How far (mm) a corner may stick out of its face polygon.
const OUTSIDE_TOLERANCE_MM: f64 = 0.05;

/// How far a tag side may differ from `size`, as a fraction of it.
const SIDE_TOLERANCE: f64 = 0.1;

#[derive(Serialize, Deserialize)]
struct File {
    version: u32,
    units: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    family: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    solid: Option<String>,
    edge: f64,
    bodies: Vec<FileBody>,
}

#[derive(Serialize, Deserialize)]
struct FileBody {
    name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    calibration: Option<FileBodyCalibration>,
    tags: Vec<FileTag>,
}

#[derive(Serialize, Deserialize)]
struct FileBodyCalibration {
    views: u32,
    rms_before_px: f64,
    rms_after_px: f64,
    recordings: Vec<String>,
}

#[derive(Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
enum FileTagCalibration {
    Nominal { views: u32 },
    Calibrated { views: u32, rms_before_px: f64, rms_after_px: f64 },
}

#[derive(Serialize, Deserialize)]
struct FileTag {
    id: u32,
    face: usize,
    size: f64,
    corners: [[f64; 3]; 4],
    center: [f64; 3],
    face_polygon: Vec<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    calibration: Option<FileTagCalibration>,
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
        let file = File {
            version: MARKER_FILE_VERSION,
            units: "mm".into(),
            family: Some(self.family.name.into()),
            solid: Some(self.solid.name().into()),
            edge: self.edge,
            bodies: self
                .bodies
                .iter()
                .map(|b| FileBody {
                    name: b.kind.name().into(),
                    calibration: b.provenance.as_ref().map(|p| FileBodyCalibration {
                        views: p.views,
                        rms_before_px: p.rms_before_px,
                        rms_after_px: p.rms_after_px,
                        recordings: p.recordings.clone(),
                    }),
                    tags: b
                        .tags
                        .iter()
                        .map(|t| FileTag {
                            id: t.id,
                            face: t.face,
                            size: t.size,
                            corners: t.corners.map(|c| arr(&c)),
                            center: arr(&t.center),
                            face_polygon: t.face_polygon.iter().map(arr).collect(),
                            calibration: t.provenance.map(|p| match p {
                                TagProvenance::Nominal { views } => FileTagCalibration::Nominal { views },
                                TagProvenance::Calibrated { views, rms_before_px, rms_after_px } => {
                                    FileTagCalibration::Calibrated { views, rms_before_px, rms_after_px }
                                }
                            }),
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
        let version = match version.as_u64() {
            Some(v @ 1..=3) => v,
            Some(v) => return Err(MarkerError::Version { found: v.to_string() }),
            None => return Err(MarkerError::Version { found: version.to_string() }),
        };
        let with_provenance = version >= 2;
        let mut file: File = serde_path_to_error::deserialize(&value).map_err(|e| {
            let path = e.path().to_string();
            MarkerError::Field {
                location: describe_path(&value, &path),
                field: path,
                reason: e.into_inner().to_string(),
            }
        })?;
        if version < 3 {
            // Family and solid came with version 3: before it every marker was tag36h11 on a
            // dodecahedron, whatever such keys a writer added.
            file.family = None;
            file.solid = None;
        } else {
            for key in ["family", "solid"] {
                if value.get(key).is_none() {
                    return Err(field("marker file", key, "is missing (a version 3 file names it)"));
                }
            }
        }
        if !with_provenance {
            // Version 1 had no provenance: whatever such keys a writer added mean nothing.
            for b in &mut file.bodies {
                b.calibration = None;
                for t in &mut b.tags {
                    t.calibration = None;
                }
            }
        }
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
    /// wound consistently with the outward normal and roughly square; provenance on a body
    /// exactly when on its tags, with finite, non-negative residuals.
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
            if let Some(p) = &body.provenance {
                for (name, v) in [("rms_before_px", p.rms_before_px), ("rms_after_px", p.rms_after_px)] {
                    if !(v.is_finite() && v >= 0.0) {
                        return Err(field(
                            &format!("body '{}'", body.kind),
                            "calibration",
                            &format!("`{name}` must be a non-negative number of px, got {v}"),
                        ));
                    }
                }
            }
            for (ti, tag) in body.tags.iter().enumerate() {
                let loc = format!("body '{}', tag id {} (bodies[{bi}].tags[{ti}])", body.kind, tag.id);
                if self.family.code(tag.id).is_none() {
                    let f = &self.family;
                    return Err(field(&loc, "id", &format!("is not in {} (ids 0–{})", f.name, f.count() - 1)));
                }
                if let Some(prev) = ids.insert(tag.id, body.kind) {
                    return Err(field(&loc, "id", &format!("duplicate id {} (already on the {prev})", tag.id)));
                }
                if body.tags[..ti].iter().any(|t| t.face == tag.face) {
                    return Err(field(&loc, "face", &format!("face {} carries two tags", tag.face)));
                }
                validate_tag(tag, self.solid).map_err(|(f, reason)| field(&loc, f, &reason))?;
                validate_provenance(tag, body.provenance.is_some())
                    .map_err(|reason| field(&loc, "calibration", &reason))?;
            }
        }
        Ok(())
    }
}

fn validate_provenance(t: &Tag, body_calibrated: bool) -> Result<(), String> {
    match (t.provenance, body_calibrated) {
        (None, false) => Ok(()),
        (None, true) => Err("is missing: the body records a calibration, so each of its tags says its own".into()),
        (Some(_), false) => Err("is given but the body records no calibration".into()),
        (Some(TagProvenance::Nominal { .. }), true) => Ok(()),
        (Some(TagProvenance::Calibrated { rms_before_px, rms_after_px, .. }), true) => {
            for (name, v) in [("rms_before_px", rms_before_px), ("rms_after_px", rms_after_px)] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(format!("`{name}` must be a non-negative number of px, got {v}"));
                }
            }
            Ok(())
        }
    }
}

fn validate_tag(t: &Tag, solid: SolidKind) -> Result<(), (&'static str, String)> {
    if t.face >= solid.face_count() {
        return Err(("face", format!("must be 0..{} on a {solid}, got {}", solid.face_count() - 1, t.face)));
    }
    let sides = t.face_polygon.len();
    if sides != solid.face_sides() {
        return Err(("face_polygon", format!("has {sides} vertices; a face of a {solid} has {}", solid.face_sides())));
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
    // Each vertex against the plane of the others: a least-squares plane through all of them
    // would absorb part of a single misplaced vertex.
    let off = (0..sides)
        .map(|i| {
            let others: Vec<Vector3<f64>> = (0..sides).filter(|&k| k != i).map(|k| t.face_polygon[k]).collect();
            let n = fitted_normal(&others);
            let mean = others.iter().sum::<Vector3<f64>>() / (sides - 1) as f64;
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
    let poly_center = t.face_polygon.iter().sum::<Vector3<f64>>() / sides as f64;
    if n.dot(&poly_center) <= 0.0 {
        return Err(("face_polygon", "runs clockwise seen from outside (its normal points into the body)".into()));
    }
    for i in 0..sides {
        let a = t.face_polygon[(i + 1) % sides] - t.face_polygon[i];
        let b = t.face_polygon[(i + 2) % sides] - t.face_polygon[(i + 1) % sides];
        if a.cross(&b).dot(&n) <= 0.0 {
            return Err(("face_polygon", format!("is not convex at vertex {}", (i + 1) % sides)));
        }
    }
    let mean = poly_center;
    for (i, c) in t.corners.iter().enumerate() {
        let d = (c - mean).dot(&n).abs();
        if d > PLANARITY_TOLERANCE_MM {
            return Err(("corners", format!("corner {i} is {d:.3} mm off its face's plane")));
        }
        let inside = (0..sides)
            .map(|k| {
                let a = t.face_polygon[k];
                let b = t.face_polygon[(k + 1) % sides];
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

fn from_file(file: File) -> Result<Marker, MarkerError> {
    if file.units != "mm" {
        return Err(field("marker file", "units", &format!("must be \"mm\", got \"{}\"", file.units)));
    }
    let family = match &file.family {
        None => TagFamily::TAG36H11,
        Some(name) => TagFamily::named(name).ok_or_else(|| {
            let known: Vec<&str> = TagFamily::ALL.iter().map(|f| f.name).collect();
            field(
                "marker file",
                "family",
                &format!("names \"{name}\", not a family this build reads ({})", known.join(", ")),
            )
        })?,
    };
    let solid = match &file.solid {
        None => SolidKind::Dodecahedron,
        Some(name) => SolidKind::from_name(name).ok_or_else(|| {
            let known: Vec<&str> = SolidKind::ALL.iter().map(|k| k.name()).collect();
            field(
                "marker file",
                "solid",
                &format!("names \"{name}\", not a solid this build knows ({})", known.join(", ")),
            )
        })?,
    };
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
                    face_polygon: t.face_polygon.iter().map(vec3).collect(),
                    provenance: t.calibration.map(|c| match c {
                        FileTagCalibration::Nominal { views } => TagProvenance::Nominal { views },
                        FileTagCalibration::Calibrated { views, rms_before_px, rms_after_px } => {
                            TagProvenance::Calibrated { views, rms_before_px, rms_after_px }
                        }
                    }),
                })
                .collect();
            let provenance = b.calibration.map(|c| BodyProvenance {
                views: c.views,
                rms_before_px: c.rms_before_px,
                rms_after_px: c.rms_after_px,
                recordings: c.recordings,
            });
            Ok(Body { kind, tags, provenance })
        })
        .collect::<Result<Vec<_>, MarkerError>>()?;
    Ok(Marker { family, solid, edge: file.edge, bodies })
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
        assert_eq!(v["version"], 3);
        assert_eq!(v["units"], "mm");
        assert_eq!((&v["family"], &v["solid"]), (&json!("tag36h11"), &json!("dodecahedron")));
        assert!(v["bodies"][0].get("calibration").is_none(), "a nominal marker records no calibration");
        assert!(v["bodies"][0]["tags"][0].get("calibration").is_none());
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
        v["version"] = json!(4);
        assert!(err_of(&v).contains("version 4"), "{}", err_of(&v));
        v.as_object_mut().expect("object").remove("version");
        assert!(err_of(&v).contains("version"));
    }

    /// The default marker with its mandible calibrated: tag 12 placed, tag 13 never seen.
    fn calibrated_mandible() -> Marker {
        let mut m = Marker::default();
        let body = &mut m.bodies[1];
        body.provenance = Some(BodyProvenance {
            views: 18,
            rms_before_px: 1.25,
            rms_after_px: 0.125,
            recordings: vec!["calibration/frames".into(), "second.mov".into()],
        });
        for t in &mut body.tags {
            t.provenance = Some(TagProvenance::Calibrated { views: 7, rms_before_px: 2.5, rms_after_px: 0.1 + 0.2 });
        }
        body.tags[1].provenance = Some(TagProvenance::Nominal { views: 0 });
        body.tags[5].provenance = Some(TagProvenance::Nominal { views: 2 });
        m
    }

    #[test]
    fn provenance_round_trips_exactly() {
        let m = calibrated_mandible();
        let back = Marker::from_json(&m.to_json()).expect("own output parses");
        assert_eq!(back, m);
        let v: Value = serde_json::from_str(&m.to_json()).expect("json");
        assert_eq!(v["version"], 3);
        let body = &v["bodies"][1]["calibration"];
        assert_eq!(body["views"], 18);
        assert_eq!(body["rms_before_px"], 1.25);
        assert_eq!(body["rms_after_px"], 0.125);
        assert_eq!(body["recordings"], json!(["calibration/frames", "second.mov"]));
        let t12 = &v["bodies"][1]["tags"][0]["calibration"];
        assert_eq!(t12["status"], "calibrated");
        assert_eq!(t12["views"], 7);
        assert_eq!(t12["rms_before_px"], 2.5);
        assert_eq!(v["bodies"][1]["tags"][1]["calibration"], json!({"status": "nominal", "views": 0}));
        assert!(v["bodies"][0].get("calibration").is_none(), "the maxilla was not calibrated");
        assert!(back.is_calibrated());
        // The maxilla, never calibrated, and the mandible's two tags left nominal.
        let loose: Vec<u32> = back.uncalibrated_tags().iter().map(|&(_, id)| id).collect();
        assert_eq!(loose, [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 17]);
        assert!(Marker::default().uncalibrated_tags().is_empty(), "a nominal marker has nothing to flag");
    }

    #[test]
    fn the_family_is_named_and_read_back() {
        let m = Marker::nominal_of(TagFamily::TAG25H9, 12.7, None).expect("tag25h9 marker");
        let v: Value = serde_json::from_str(&m.to_json()).expect("json");
        assert_eq!(v["family"], "tag25h9");
        let back = Marker::from_json(&m.to_json()).expect("own output parses");
        assert_eq!(back, m);
        assert_eq!(back.family, TagFamily::TAG25H9);
        // Seven cells across, one of margin: a smaller tag than tag36h11's on the same face.
        let size = m.bodies[0].tags[0].size;
        assert!(size < Marker::default().bodies[0].tags[0].size, "{size}");
        // tag16h5 has 30 ids: the pair fits; a family too small for 24 ids is refused.
        assert!(Marker::nominal_of(TagFamily::TAG16H5, 12.7, None).is_ok());
        let tiny = TagFamily { codes: &TagFamily::TAG16H5.codes[..20], ..TagFamily::TAG16H5 };
        assert!(Marker::nominal_of(tiny, 12.7, None).expect_err("20 ids").to_string().contains("0–23"));
    }

    #[test]
    fn a_cube_marker_is_named_and_read_back() {
        let m = Marker::nominal_on(SolidKind::Cube, TagFamily::TAG36H11, 12.7, None).expect("cube marker");
        let v: Value = serde_json::from_str(&m.to_json()).expect("json");
        assert_eq!(v["solid"], "cube");
        assert_eq!(v["bodies"][0]["tags"].as_array().map(Vec::len), Some(6));
        assert_eq!(v["bodies"][0]["tags"][0]["face_polygon"].as_array().map(Vec::len), Some(4));
        let back = Marker::from_json(&m.to_json()).expect("own output parses");
        assert_eq!(back, m);
        assert_eq!((back.solid, back.geometry().faces().len()), (SolidKind::Cube, 6));
        assert!(back.measured_tags().is_empty(), "a nominal cube read back is nominal");
        // A tag on a seventh face of a cube.
        let mut v = v;
        v["bodies"][0]["tags"][5]["face"] = json!(6);
        let e = err_of(&v);
        assert!(e.contains("`face` must be 0..5 on a cube, got 6"), "{e}");
    }

    #[test]
    fn family_and_solid_are_checked() {
        let mut v = nominal_json();
        v["family"] = json!("tag99h1");
        let e = err_of(&v);
        assert!(e.contains("`family`") && e.contains("tag99h1") && e.contains("tag25h9"), "{e}");
        let mut v = nominal_json();
        v["solid"] = json!("sphere");
        let e = err_of(&v);
        assert!(e.contains("`solid`") && e.contains("sphere") && e.contains("dodecahedron, cube"), "{e}");
        // A dodecahedron's pentagons relabelled as a cube's faces.
        let mut v = nominal_json();
        v["solid"] = json!("cube");
        let e = err_of(&v);
        assert!(e.contains("`face_polygon` has 5 vertices; a face of a cube has 4"), "{e}");
        for key in ["family", "solid"] {
            let mut v = nominal_json();
            v.as_object_mut().expect("object").remove(key);
            assert!(err_of(&v).contains(&format!("`{key}` is missing")), "{}", err_of(&v));
        }
        // An id the family does not have.
        let mut v: Value =
            serde_json::from_str(&Marker::nominal_of(TagFamily::TAG25H9, 12.7, None).expect("marker").to_json())
                .expect("json");
        v["bodies"][1]["tags"][11]["id"] = json!(35);
        let e = err_of(&v);
        assert!(e.contains("tag id 35") && e.contains("not in tag25h9 (ids 0–34)"), "{e}");
    }

    #[test]
    fn version_2_file_is_tag36h11_on_a_dodecahedron() {
        let mut v = nominal_json();
        v["version"] = json!(2);
        // Keys a version 2 writer could not mean are ignored, as provenance is in version 1.
        v["family"] = json!("tag16h5");
        v.as_object_mut().expect("object").remove("solid");
        let old = Marker::from_json(&v.to_string()).expect("a version 2 file still reads");
        assert_eq!(old, Marker::default());
        assert_eq!(old.family, TagFamily::TAG36H11);
    }

    #[test]
    fn version_1_file_reads_with_provenance_unknown() {
        let mut v = nominal_json();
        v["version"] = json!(1);
        let old = Marker::from_json(&v.to_string()).expect("a version 1 file still reads");
        assert_eq!(old, Marker::default());
        // Provenance-like keys in a version 1 file mean nothing.
        let mut v: Value = serde_json::from_str(&calibrated_mandible().to_json()).expect("json");
        v["version"] = json!(1);
        let old = Marker::from_json(&v.to_string()).expect("a version 1 file still reads");
        assert!(old.tags().all(|(_, t)| t.provenance.is_none()));
        assert!(old.bodies.iter().all(|b| b.provenance.is_none()));
        assert!(!old.is_calibrated() && old.uncalibrated_tags().is_empty());
    }

    #[test]
    fn bad_provenance_is_named() {
        let good: Value = serde_json::from_str(&calibrated_mandible().to_json()).expect("json");
        let mut v = good.clone();
        v["bodies"][1]["tags"][0]["calibration"]["rms_after_px"] = json!(-0.5);
        let e = err_of(&v);
        assert!(e.contains("tag id 12") && e.contains("rms_after_px") && e.contains("non-negative"), "{e}");
        let mut v = good.clone();
        v["bodies"][1]["calibration"]["rms_before_px"] = json!(-1.0);
        assert!(err_of(&v).contains("mandible"), "{}", err_of(&v));
        let mut v = good.clone();
        v["bodies"][1]["tags"][2]["calibration"]["status"] = json!("guessed");
        let e = err_of(&v);
        assert!(e.contains("tag id 14") && e.contains("calibration"), "{e}");
        let mut v = good.clone();
        v["bodies"][1]["tags"][3]["calibration"]["views"] = json!(-3);
        assert!(err_of(&v).contains("tag id 15"), "{}", err_of(&v));
        let mut v = good.clone();
        v["bodies"][1]["tags"][4].as_object_mut().expect("object").remove("calibration");
        let e = err_of(&v);
        assert!(e.contains("tag id 16") && e.contains("calibration") && e.contains("missing"), "{e}");
        let mut v = good;
        v["bodies"][0]["tags"][0]["calibration"] = json!({"status": "nominal", "views": 1});
        let e = err_of(&v);
        assert!(e.contains("tag id 0") && e.contains("no calibration"), "{e}");
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
