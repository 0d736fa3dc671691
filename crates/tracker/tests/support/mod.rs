//! A chewing jaw seen under a rolling shutter, as exact detections: the corners are placed
//! where each body was when their row was read. Shared by the rolling-shutter test and the
//! pose-time benchmark.
#![allow(dead_code)]

use jawtrack_apriltag::Detection;
use jawtrack_marker::Marker;
use jawtrack_pose::{CameraIntrinsics, Pose, RollingShutter};
use nalgebra::{Point2, Point3, UnitQuaternion, Vector3};
use std::f64::consts::{PI, TAU};

pub const ROWS: usize = 1080;
pub const FPS: f64 = 60.0;
pub const READOUT_S: f64 = 0.010;

pub fn camera() -> CameraIntrinsics {
    CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5)
}

/// Both markers facing the camera from ~100 mm, the upper above the lower, so that the two
/// are read about half a readout apart.
pub fn maxilla() -> Pose {
    Pose::from_parts(facing(), Vector3::new(2.0, -22.0, 100.0))
}

pub fn facing() -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI)
        * UnitQuaternion::from_scaled_axis(Vector3::new(0.25, 0.15, 0.0))
}

/// The mandible chewing: opening 10 mm and swinging 3 mm sideways in 0.7 s cycles, turning with
/// the opening (about 90 mm/s at its fastest).
pub fn mandible(t: f64) -> Pose {
    let phase = TAU * t / 0.7;
    let open = 5.0 * (1.0 - phase.cos());
    let turn = UnitQuaternion::from_scaled_axis(Vector3::new(0.012 * open, 0.0, 0.0));
    Pose::from_parts(facing() * turn, Vector3::new(1.0 + 3.0 * phase.sin(), 22.0 + open, 104.0 - 0.3 * open))
}

/// Where `point` of a body moving along `pose_at` is seen: on the row whose time puts it there.
pub fn seen(point: &Point3<f64>, pose_at: &Motion, t: f64, shutter: &RollingShutter) -> Point2<f64> {
    let k = camera();
    let mut p = k.project(&pose_at(t).transform_point(point)).expect("in front");
    for _ in 0..50 {
        p = k.project(&pose_at(t + shutter.offset_s(p.y)).transform_point(point)).expect("in front");
    }
    p
}

/// A body's pose over time.
pub type Motion = dyn Fn(f64) -> Pose;

pub fn detections(marker: &Marker, t: f64, shutter: &RollingShutter) -> Vec<Detection> {
    let bodies: [(&[u32], &Motion); 2] = [(&[0, 1, 2], &|_| maxilla()), (&[12, 13, 14], &mandible)];
    bodies
        .iter()
        .flat_map(|(ids, pose_at)| {
            ids.iter().map(move |&id| {
                let (_, tag) = marker.find_tag(id).expect("marker tag");
                let corners = tag.corners.map(|c| {
                    let p = seen(&Point3::from(c), *pose_at, t, shutter);
                    [p.x, p.y]
                });
                let center =
                    [corners.iter().map(|c| c[0]).sum::<f64>() / 4.0, corners.iter().map(|c| c[1]).sum::<f64>() / 4.0];
                Detection {
                    id,
                    hamming: 0,
                    decision_margin: 100.0,
                    center,
                    corners,
                    homography: [0.0; 9],
                    blur_px: None,
                }
            })
        })
        .collect()
}
