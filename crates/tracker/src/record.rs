//! The recording schema: one JSON object per tracked frame, written as one line of a JSON
//! Lines file by `jawtrack track` (and, through the same code, by the app and the receiver).
//!
//! ```text
//! {"frame": i, "path": "…" | null, "t": seconds,
//!  "maxilla":  {"camera_from_body": M, "tags": [ids], "rejected_tags": [ids], "rms_px": …,
//!               "cov": [36 numbers]} | null,
//!  "mandible": {…} | null,
//!  "maxilla_from_mandible": M | null,
//!  "maxilla_scan_from_mandible_scan": M | null,   (only with a registration)
//!  "flags": ["mandible:single_tag", …],
//!  "searched": [x, y, width, height] | null,       (null: the whole frame)
//!  "timings_s": {"detection": …, "pose": …}}
//! ```
//!
//! Every `M` is a 4×4 row-major matrix in mm; `cov` is the 6×6 covariance of (rotation vector
//! [rad], translation [mm]), row-major. No value is ever NaN: the tracker never returns a
//! pose that is not finite, and JSON cannot carry one.

use crate::{BodyResult, Flag, FrameResult};
use jawtrack_pose::Pose;
use serde_json::{Value, json};

/// One frame's record.
pub fn frame_record(index: usize, path: Option<&str>, r: &FrameResult) -> Value {
    let matrix = |p: &Pose| json!(p.to_row_major());
    let body = |b: Option<&BodyResult>| match b {
        Some(b) => json!({
            "camera_from_body": matrix(&b.camera_from_body),
            "tags": b.tags,
            "rejected_tags": b.rejected_tags,
            "rms_px": b.rms_px,
            "cov": b.covariance.transpose().iter().copied().collect::<Vec<f64>>(),
        }),
        None => Value::Null,
    };
    let mut v = json!({
        "frame": index,
        "path": path,
        "t": r.t,
        "maxilla": body(r.maxilla.as_ref()),
        "mandible": body(r.mandible.as_ref()),
        "maxilla_from_mandible": r.maxilla_from_mandible.as_ref().map_or(Value::Null, matrix),
        "flags": r.flags.iter().map(Flag::name).collect::<Vec<_>>(),
        "searched": r.searched.map(|s| [s.x, s.y, s.width, s.height]),
        "timings_s": {"detection": r.timings.detection_s, "pose": r.timings.pose_s},
    });
    if let Some(s) = &r.maxilla_scan_from_mandible_scan {
        v["maxilla_scan_from_mandible_scan"] = matrix(s);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Timings;
    use nalgebra::{Matrix6, Vector3};

    #[test]
    fn a_record_carries_every_field_in_row_major_order() {
        let pose = Pose::from_axis_angle(Vector3::new(0.0, 0.1, 0.0), Vector3::new(1.0, 2.0, 100.0));
        let mut cov = Matrix6::zeros();
        cov[(0, 1)] = 7.0;
        let r = FrameResult {
            t: 0.5,
            maxilla: Some(BodyResult {
                camera_from_body: pose,
                tags: vec![0, 1],
                rejected_tags: vec![5],
                rms_px: 0.3,
                covariance: cov,
            }),
            mandible: None,
            maxilla_from_mandible: None,
            maxilla_scan_from_mandible_scan: None,
            flags: vec![Flag::Lost(jawtrack_marker::BodyKind::Mandible)],
            detections: Vec::new(),
            searched: None,
            timings: Timings { detection_s: 0.004, pose_s: 0.0001 },
        };
        let v = frame_record(3, Some("f.png"), &r);
        assert_eq!(v["frame"], 3);
        assert_eq!(v["path"], "f.png");
        assert_eq!(v["maxilla"]["camera_from_body"][3], 1.0);
        assert_eq!(v["maxilla"]["camera_from_body"][11], 100.0);
        assert_eq!(v["maxilla"]["cov"][1], 7.0, "row-major: (0, 1) is the second number");
        assert_eq!(v["maxilla"]["rejected_tags"][0], 5);
        assert!(v["mandible"].is_null() && v["maxilla_from_mandible"].is_null());
        assert!(v.get("maxilla_scan_from_mandible_scan").is_none());
        assert_eq!(v["flags"][0], "mandible:lost");
        assert_eq!(v["timings_s"]["detection"], 0.004);
    }
}
