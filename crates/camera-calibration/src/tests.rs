//! Exact synthetic corners: the marker pair moved along a smooth known path, each corner
//! projected through a known camera at its own row's time, plus 0.1 px of noise.

use super::*;
use jawtrack_pose::Pose;
use nalgebra::{UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::{PI, TAU};

const W: u32 = 1920;
const H: u32 = 1080;
const FPS: f64 = 30.0;

fn truth() -> CameraIntrinsics {
    CameraIntrinsics { fx: 1512.0, fy: 1507.0, cx: 963.0, cy: 536.0, k1: -0.06, k2: 0.03 }
}

/// `camera_from_maxilla` waved across the image at 95–195 mm, tilted ±23°: up to ≈ 130 mm/s.
fn waved(t: f64) -> Pose {
    let z = 145.0 + 50.0 * (TAU * 0.21 * t + 0.3).sin();
    let x = z * 0.40 * (TAU * 0.33 * t).sin() - 20.0;
    let y = z * 0.24 * (TAU * 0.47 * t + 1.0).sin();
    let tilt =
        Vector3::new(0.4 * (TAU * 0.29 * t).sin(), 0.4 * (TAU * 0.37 * t + 0.5).sin(), 0.3 * (TAU * 0.23 * t).sin());
    // The body's +Z vertex toward the camera.
    let facing = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI);
    Pose::from_parts(UnitQuaternion::from_scaled_axis(tilt) * facing, Vector3::new(x, y, z))
}

/// The mandible marker 44 mm beside the maxilla's, turned a little to show other faces.
fn maxilla_from_mandible() -> Pose {
    Pose::from_axis_angle(Vector3::new(0.0, 0.25, 0.1), Vector3::new(44.0, 0.0, 0.0))
}

/// Frames at `times` of the bodies at `path(t)`, read out in `readout_s`, with `noise_px`.
fn frames(path: impl Fn(f64) -> Pose, times: &[f64], readout_s: f64, noise_px: f64, seed: u64) -> Vec<CameraFrame> {
    let camera = truth();
    let marker = Marker::default();
    let shutter = RollingShutter::new(readout_s, H as usize).expect("a valid readout");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, noise_px).expect("a valid spread");
    let inside = |p: &Point2<f64>| p.x >= 0.0 && p.y >= 0.0 && p.x <= f64::from(W - 1) && p.y <= f64::from(H - 1);
    times
        .iter()
        .map(|&t| {
            let mut tags = Vec::new();
            for (kind, tag) in marker.tags() {
                let body_at = |t: f64| match kind {
                    BodyKind::Maxilla => path(t),
                    BodyKind::Mandible => path(t) * maxilla_from_mandible(),
                };
                let pose = body_at(t);
                let centre = pose.transform_point(&Point3::from(tag.center)).coords;
                let facing = -pose.transform_vector(&tag.face_normal()).dot(&centre.normalize());
                if facing < 70f64.to_radians().cos() {
                    continue;
                }
                // Where each row sees the corner: the fixed point of the row's time.
                let seen: Option<Vec<Point2<f64>>> = tag
                    .corners
                    .iter()
                    .map(|c| {
                        let mut p = camera.project(&pose.transform_point(&Point3::from(*c)))?;
                        for _ in 0..20 {
                            p = camera
                                .project(&body_at(t + shutter.offset_s(p.y)).transform_point(&Point3::from(*c)))?;
                        }
                        Some(p)
                    })
                    .collect();
                let Some(seen) = seen.filter(|s| s.iter().all(inside)) else { continue };
                let corners =
                    std::array::from_fn(|i| [seen[i].x + noise.sample(&mut rng), seen[i].y + noise.sample(&mut rng)]);
                tags.push(SeenTag { id: tag.id, corners });
            }
            CameraFrame { t, tags }
        })
        .collect()
}

fn video(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64 / FPS).collect()
}

#[test]
fn recovers_the_camera_and_the_readout_of_a_waved_marker() {
    let k = truth();
    for (readout_s, seed) in [(0.005, 1), (0.010, 2), (0.020, 3)] {
        let frames = frames(waved, &video(120), readout_s, 0.1, seed);
        let c = calibrate_camera(&frames, W, H, &Marker::default(), &CameraCalibrationOptions::default())
            .expect("a good recording calibrates");
        let s = &c.sigma;
        eprintln!(
            "readout {:.0} ms: fx {:.2} ± {:.2}, fy {:.2} ± {:.2}, cx {:.2} ± {:.2}, cy {:.2} ± {:.2}, k1 {:.4} ± {:.4}, \
             k2 {:.4} ± {:.4}, readout {:.3} ± {:.3} ms, rms {:.3} px, {} frames, coverage {:.2}",
            readout_s * 1e3,
            c.intrinsics.fx,
            s.fx,
            c.intrinsics.fy,
            s.fy,
            c.intrinsics.cx,
            s.cx,
            c.intrinsics.cy,
            s.cy,
            c.intrinsics.k1,
            s.k1,
            c.intrinsics.k2,
            s.k2,
            c.readout_s * 1e3,
            s.readout_s * 1e3,
            c.rms_px,
            c.frames_used,
            c.coverage
        );
        // The targets: focal length within 0.3 %, readout within 10 %.
        for (got, want) in [(c.intrinsics.fx, k.fx), (c.intrinsics.fy, k.fy)] {
            assert!((got / want - 1.0).abs() < 0.003, "focal {got} against {want}");
        }
        assert!((c.readout_s / readout_s - 1.0).abs() < 0.1, "readout {} against {readout_s}", c.readout_s);
        // The uncertainties are honest: each error within 4σ.
        let errors = [
            (c.intrinsics.fx - k.fx, s.fx),
            (c.intrinsics.fy - k.fy, s.fy),
            (c.intrinsics.cx - k.cx, s.cx),
            (c.intrinsics.cy - k.cy, s.cy),
            (c.intrinsics.k1 - k.k1, s.k1),
            (c.intrinsics.k2 - k.k2, s.k2),
            (c.readout_s - readout_s, s.readout_s),
        ];
        for (i, (e, sd)) in errors.iter().enumerate() {
            assert!(e.abs() < 4.0 * sd, "parameter {i}: error {e} against 1σ {sd}");
        }
        assert!((0.05..0.2).contains(&c.rms_px), "rms {} for 0.1 px noise per coordinate", c.rms_px);
        assert!(c.frames_used >= 115, "{} frames used", c.frames_used);
    }
}

#[test]
fn too_few_frames_are_refused() {
    let frames = frames(waved, &video(12), 0.010, 0.1, 4);
    let e = calibrate_camera(&frames, W, H, &Marker::default(), &CameraCalibrationOptions::default());
    assert!(matches!(e, Err(CameraCalibrationError::TooFewFrames { needed: 20, .. })), "{e:?}");
    assert!(e.expect_err("refused").to_string().contains("film longer"));
    let none = calibrate_camera(&[], W, H, &Marker::default(), &CameraCalibrationOptions::default());
    assert!(matches!(none, Err(CameraCalibrationError::TooFewFrames { usable: 0, .. })), "{none:?}");
}

#[test]
fn a_marker_held_still_in_the_middle_is_refused() {
    let still = |_: f64| waved(0.0) * Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 0.0, -40.0));
    let frames = frames(still, &video(60), 0.010, 0.1, 5);
    let e = calibrate_camera(&frames, W, H, &Marker::default(), &CameraCalibrationOptions::default());
    match e {
        Err(CameraCalibrationError::DistortionUnconstrained { coverage_percent, .. }) => {
            assert!(coverage_percent < 20.0, "{coverage_percent}");
        }
        other => panic!("expected the distortion to be refused, got {other:?}"),
    }
}

#[test]
fn still_frames_leave_the_readout_unconstrained() {
    // The marker held still at 40 places across the image, three frames at each, a second
    // between places (no row of a frame reads the previous place): everything but the readout
    // is seen.
    let holds: Vec<f64> = (0..40).flat_map(|k| (1..4).map(move |j| f64::from(k) + f64::from(j) / FPS)).collect();
    let path = |t: f64| waved(t.floor() * 0.173);
    let frames = frames(path, &holds, 0.010, 0.1, 6);
    let e = calibrate_camera(&frames, W, H, &Marker::default(), &CameraCalibrationOptions::default());
    assert!(matches!(e, Err(CameraCalibrationError::ReadoutUnconstrained { .. })), "{e:?}");
    assert!(e.expect_err("refused").to_string().contains("move the marker faster"));
}

#[test]
fn bad_input_is_refused_by_name() {
    let mut frames = frames(waved, &video(30), 0.010, 0.1, 7);
    frames[5].t = frames[4].t;
    let e = calibrate_camera(&frames, W, H, &Marker::default(), &CameraCalibrationOptions::default());
    assert!(matches!(&e, Err(CameraCalibrationError::BadInput(m)) if m.contains("frame times must increase")), "{e:?}");
    frames[5].t = f64::NAN;
    assert!(calibrate_camera(&frames, W, H, &Marker::default(), &CameraCalibrationOptions::default()).is_err());
    let e = calibrate_camera(&[], 0, H, &Marker::default(), &CameraCalibrationOptions::default());
    assert!(matches!(e, Err(CameraCalibrationError::BadInput(_))), "{e:?}");
    let bad_guess = CameraCalibrationOptions {
        initial: Some(CameraIntrinsics::pinhole(-1.0, 1.0, 0.0, 0.0)),
        ..CameraCalibrationOptions::default()
    };
    let e = calibrate_camera(&[], W, H, &Marker::default(), &bad_guess);
    assert!(matches!(&e, Err(CameraCalibrationError::BadInput(m)) if m.contains("initial guess")), "{e:?}");
}
