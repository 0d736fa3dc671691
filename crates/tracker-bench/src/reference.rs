//! The reference stack on one frame: the AprilTag C library's detections, paired with a
//! marker file's corners, then OpenCV's SQPnP per body.

use crate::opencv::{BodyCase, OpenCv};
use anyhow::Result;
use jawtrack_apriltag_reference::ReferenceDetection;
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::{CameraIntrinsics, Pose};

/// Every corner of `kind`'s tags among the C library's detections, against the marker file's
/// corners (same order: the library's).
pub fn correspondences(marker: &Marker, kind: BodyKind, detections: &[ReferenceDetection]) -> BodyCase {
    let mut case = BodyCase::default();
    for d in detections {
        let Some((body, tag)) = marker.find_tag(d.id) else { continue };
        if body != kind {
            continue;
        }
        for (corner, pixel) in tag.corners.iter().zip(&d.corners) {
            case.object.push([corner.x, corner.y, corner.z]);
            case.image.push(*pixel);
        }
    }
    case
}

/// The reference stack's `maxilla_from_mandible` from one frame's detections, for each marker
/// file (one OpenCV request for all of them), or why it has none.
pub fn maxilla_from_mandible(
    cv: &mut OpenCv,
    markers: &[&Marker],
    detections: &[ReferenceDetection],
    camera: &CameraIntrinsics,
) -> Result<Vec<std::result::Result<Pose, String>>> {
    let mut cases = Vec::new();
    let mut slots = Vec::new();
    let mut poses: Vec<[std::result::Result<Pose, String>; 2]> =
        markers.iter().map(|_| BodyKind::ALL.map(|k| Err(format!("{k}: no tag")))).collect();
    for (m, marker) in markers.iter().enumerate() {
        for (b, kind) in BodyKind::ALL.into_iter().enumerate() {
            let case = correspondences(marker, kind, detections);
            if case.object.len() >= 4 {
                slots.push((m, b));
                cases.push(case);
            }
        }
    }
    if !cases.is_empty() {
        for (&(m, b), solved) in slots.iter().zip(cv.solve(camera, &cases)?) {
            poses[m][b] = solved.map(|s| s.camera_from_body).map_err(|e| format!("{}: OpenCV: {e}", BodyKind::ALL[b]));
        }
    }
    Ok(poses
        .into_iter()
        .map(|[maxilla, mandible]| match (maxilla, mandible) {
            (Ok(camera_from_maxilla), Ok(camera_from_mandible)) => {
                Ok(camera_from_maxilla.inverse().compose(&camera_from_mandible))
            }
            (Err(a), Err(b)) => Err(format!("{a}; {b}")),
            (Err(e), _) | (_, Err(e)) => Err(e),
        })
        .collect())
}
