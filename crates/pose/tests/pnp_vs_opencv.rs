//! Our PnP against OpenCV's solvePnP on the same correspondences (`data/opencv_pnp_cases.json`,
//! written by `data/make_opencv_cases.py`): noise-free cases with radial distortion must give
//! the exact pose; on noisy cases (0.2 px, no distortion) ours and OpenCV's ITERATIVE minimise
//! the same reprojection error and must agree to numerical tolerance, while SQPnP (which
//! minimises an object-space error) must lie within our covariance of ours.

use jawtrack_pose::{CameraIntrinsics, Observation, PnpOptions, Pose, solve_pnp};
use nalgebra::{Matrix6, Point2, Point3, Vector3, Vector6};
use serde_json::Value;

fn pose(v: &Value) -> Pose {
    let r: Vec<f64> = serde_json::from_value(v["rvec"].clone()).expect("rvec");
    let t: Vec<f64> = serde_json::from_value(v["tvec"].clone()).expect("tvec");
    Pose::from_axis_angle(Vector3::new(r[0], r[1], r[2]), Vector3::new(t[0], t[1], t[2]))
}

/// Sum of squared reprojection errors (px²).
fn sum_sq(obs: &[Observation], camera: &CameraIntrinsics, pose: &Pose) -> f64 {
    obs.iter()
        .map(|o| {
            let p = camera.project(&pose.transform_point(&o.body)).expect("in front");
            (p - o.pixel).norm_squared()
        })
        .sum()
}

#[test]
fn agrees_with_opencv_solvepnp() {
    let text = include_str!("data/opencv_pnp_cases.json");
    let data: Value = serde_json::from_str(text).expect("json");
    let cases = data["cases"].as_array().expect("cases");
    let (mut worst_exact, mut worst_iterative, mut worst_sqpnp_chi2) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64), 0.0f64);
    let (mut exact, mut noisy) = (0, 0);
    for (i, case) in cases.iter().enumerate() {
        let camera: CameraIntrinsics = serde_json::from_value(case["camera"].clone()).expect("camera");
        let obs: Vec<Observation> = case["points"]
            .as_array()
            .expect("points")
            .iter()
            .map(|p| {
                let b: Vec<f64> = serde_json::from_value(p["body"].clone()).expect("body");
                let px: Vec<f64> = serde_json::from_value(p["pixel"].clone()).expect("pixel");
                Observation {
                    tag: p["tag"].as_u64().expect("tag") as u32,
                    body: Point3::new(b[0], b[1], b[2]),
                    pixel: Point2::new(px[0], px[1]),
                }
            })
            .collect();
        let ours = solve_pnp(&obs, &camera, None, &PnpOptions::default()).expect("solves");
        let truth = pose(&case["truth"]);
        let iterative = pose(&case["opencv"]["iterative"]);
        let sqpnp = pose(&case["opencv"]["sqpnp"]);
        if case["noise_px"].as_f64() == Some(0.0) {
            let (dr, dt) = ours.camera_from_body.distance_to(&truth);
            assert!(dt < 1e-9 && dr < 1e-9, "case {i}: {dt:.2e} mm, {dr:.2e} rad from the truth");
            worst_exact = (worst_exact.0.max(dt), worst_exact.1.max(dr));
            exact += 1;
            let (cr, ct) = iterative.distance_to(&truth);
            assert!(ct < 1e-6 && cr < 1e-6, "case {i}: OpenCV itself is off ({ct:.2e} mm, {cr:.2e} rad)");
        } else {
            // OpenCV stops a little short of the minimum: ours must fit at least as well and
            // lie within a micro-radian of it.
            let (dr, dt) = ours.camera_from_body.distance_to(&iterative);
            assert!(dt < 1e-4 && dr < 1e-6, "case {i}: {dt:.2e} mm, {dr:.2e} rad from OpenCV's ITERATIVE");
            let (mine, theirs) = (sum_sq(&obs, &camera, &ours.camera_from_body), sum_sq(&obs, &camera, &iterative));
            assert!(
                mine <= theirs * (1.0 + 1e-12),
                "case {i}: our fit {mine:.9} px² is worse than OpenCV's {theirs:.9}"
            );
            worst_iterative = (worst_iterative.0.max(dt), worst_iterative.1.max(dr));
            let d = sqpnp.compose(&ours.camera_from_body.inverse());
            let e = Vector6::from_iterator(d.rotation().scaled_axis().iter().chain(d.translation().iter()).copied());
            let inv: Matrix6<f64> = ours.covariance.try_inverse().expect("invertible");
            let chi2 = (e.transpose() * inv * e)[(0, 0)];
            assert!(chi2 < 22.5, "case {i}: SQPnP is far outside our covariance (chi-square {chi2:.1})");
            worst_sqpnp_chi2 = worst_sqpnp_chi2.max(chi2);
            noisy += 1;
        }
    }
    // `make_opencv_cases.py` writes 40 cases, noise-free and noisy in turn.
    assert_eq!((exact, noisy), (20, 20), "noise-free and noisy cases checked");
    eprintln!(
        "{} cases ({}): noise-free worst {:.1e} mm / {:.1e} rad from the truth; noisy worst {:.1e} mm / \
         {:.1e} rad from OpenCV ITERATIVE, SQPnP within chi-square {:.2} of ours",
        cases.len(),
        data["generator"].as_str().unwrap_or("?"),
        worst_exact.0,
        worst_exact.1,
        worst_iterative.0,
        worst_iterative.1,
        worst_sqpnp_chi2
    );
}
