//! The tracker under a rolling shutter: corners seen where each body was when its row was read,
//! the jaw chewing fast, and the relative pose checked at the frame's time.

use jawtrack_apriltag::Detection;
use jawtrack_marker::Marker;
use jawtrack_pose::{CameraIntrinsics, Pose, RollingShutter};
use jawtrack_tracker::{Tracker, TrackerConfig};
use nalgebra::{Point2, Point3, UnitQuaternion, Vector3};
use std::f64::consts::{PI, TAU};

const ROWS: usize = 1080;
const FPS: f64 = 60.0;
const READOUT_S: f64 = 0.010;

fn camera() -> CameraIntrinsics {
    CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5)
}

/// Both markers facing the camera from ~100 mm, the upper above the lower, so that the two
/// are read about half a readout apart.
fn maxilla() -> Pose {
    Pose::from_parts(facing(), Vector3::new(2.0, -22.0, 100.0))
}

fn facing() -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI)
        * UnitQuaternion::from_scaled_axis(Vector3::new(0.25, 0.15, 0.0))
}

/// The mandible chewing: opening 10 mm and swinging 3 mm sideways in 0.7 s cycles, turning with
/// the opening (about 90 mm/s at its fastest).
fn mandible(t: f64) -> Pose {
    let phase = TAU * t / 0.7;
    let open = 5.0 * (1.0 - phase.cos());
    let turn = UnitQuaternion::from_scaled_axis(Vector3::new(0.012 * open, 0.0, 0.0));
    Pose::from_parts(facing() * turn, Vector3::new(1.0 + 3.0 * phase.sin(), 22.0 + open, 104.0 - 0.3 * open))
}

/// Where `point` of a body moving along `pose_at` is seen: on the row whose time puts it there.
fn seen(point: &Point3<f64>, pose_at: &Motion, t: f64, shutter: &RollingShutter) -> Point2<f64> {
    let k = camera();
    let mut p = k.project(&pose_at(t).transform_point(point)).expect("in front");
    for _ in 0..50 {
        p = k.project(&pose_at(t + shutter.offset_s(p.y)).transform_point(point)).expect("in front");
    }
    p
}

/// A body's pose over time.
type Motion = dyn Fn(f64) -> Pose;

fn detections(marker: &Marker, t: f64, shutter: &RollingShutter) -> Vec<Detection> {
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
                Detection { id, hamming: 0, decision_margin: 100.0, center, corners, homography: [0.0; 9] }
            })
        })
        .collect()
}

/// The worst error (mm) of `maxilla_from_mandible`'s incisor-region point over a second of
/// chewing, from the third frame on (the first two have no velocity yet), tracked with the
/// tracker told `readout_s`.
fn worst_error(told_readout_s: f64) -> f64 {
    let marker = Marker::default();
    let shutter = RollingShutter::new(READOUT_S, ROWS).expect("valid");
    let config = TrackerConfig { readout_s: told_readout_s, ..TrackerConfig::default() };
    let mut tracker = Tracker::new(marker.clone(), config).expect("tracker");
    let probe = Point3::new(0.0, -20.0, -30.0);
    let mut worst: f64 = 0.0;
    for i in 0..60 {
        let t = f64::from(i) / FPS;
        let r = tracker.solve(detections(&marker, t, &shutter), &camera(), t, ROWS);
        let got = r.maxilla_from_mandible.expect("both bodies");
        let truth = maxilla().inverse() * mandible(t);
        if i >= 2 {
            worst = worst.max((got.transform_point(&probe) - truth.transform_point(&probe)).norm());
        }
    }
    worst
}

#[test]
fn the_jaw_is_solved_at_the_frame_time_under_a_rolling_shutter() {
    let ignored = worst_error(0.0);
    let compensated = worst_error(READOUT_S);
    // Half a readout apart at ~90 mm/s: a few tenths of a millimetre when the shutter is
    // ignored; carried to the frame's time, the noise-free corners give the jaw to microns.
    assert!(ignored > 0.2, "ignoring a 10 ms readout should cost tenths of a mm, got {ignored} mm");
    assert!(compensated < 0.01, "compensated worst error {compensated} mm (ignored: {ignored} mm)");
}

#[test]
fn a_readout_out_of_range_is_refused_by_name() {
    for bad in [-0.001, f64::NAN, 2.0] {
        let config = TrackerConfig { readout_s: bad, ..TrackerConfig::default() };
        let e = Tracker::new(Marker::default(), config).expect_err("refused").to_string();
        assert!(e.contains("readout"), "{e}");
    }
}
