//! PnP on synthetic correspondences with exact poses: a cube-shaped body carrying square tags
//! (corners and centre, as the tracker feeds them) seen by a 1080p camera at 60–140 mm.

use jawtrack_pose::pnp::{pose_jacobian, projection_jacobian};
use jawtrack_pose::{CameraIntrinsics, Observation, PnpError, PnpOptions, Pose, solve_pnp};
use nalgebra::{Matrix6, Point2, Point3, Vector2, Vector3, Vector6};

/// A small deterministic generator (no dependency needed for a few random numbers).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    /// Standard normal (Box–Muller).
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.next().max(1e-300), self.next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

fn camera() -> CameraIntrinsics {
    CameraIntrinsics { fx: 1500.0, fy: 1500.0, cx: 959.5, cy: 539.5, k1: 0.05, k2: -0.02 }
}

/// Tag `id`'s corners and centre on face `face` of a 16 mm cube centred at the origin:
/// 10.6 mm squares, each turned within its face so no two faces share a pattern.
fn tag_points(id: u32, face: usize) -> Vec<Point3<f64>> {
    let normals: [Vector3<f64>; 6] =
        [Vector3::x(), Vector3::y(), Vector3::z(), -Vector3::x(), -Vector3::y(), -Vector3::z()];
    let n = normals[face];
    let a = if n.x.abs() < 0.5 { Vector3::x() } else { Vector3::y() };
    let u = n.cross(&a).normalize();
    let v = n.cross(&u);
    let turn = 0.3 * face as f64;
    let (u, v) = (u * turn.cos() + v * turn.sin(), v * turn.cos() - u * turn.sin());
    let c = n * 8.0;
    let h = 5.3;
    let _ = id;
    vec![
        Point3::from(c - u * h + v * h),
        Point3::from(c + u * h + v * h),
        Point3::from(c + u * h - v * h),
        Point3::from(c - u * h - v * h),
        Point3::from(c),
    ]
}

/// A pose looking at the body from `distance` mm with a random turn.
fn random_pose(rng: &mut Lcg, distance: f64) -> Pose {
    let axis = Vector3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
    let rot = axis.normalize() * rng.range(0.0, 3.0);
    Pose::from_axis_angle(rot, Vector3::new(rng.range(-20.0, 20.0), rng.range(-10.0, 10.0), distance))
}

/// Observations of every tag on a face turned toward the camera.
fn observe(pose: &Pose, cam: &CameraIntrinsics, faces: &[usize], noise: f64, rng: &mut Lcg) -> Vec<Observation> {
    let mut out = Vec::new();
    for &face in faces {
        let pts = tag_points(face as u32, face);
        for p in pts {
            let c = pose.transform_point(&p);
            let px = cam.project(&c).expect("in front");
            let pixel = Point2::new(px.x + noise * rng.normal(), px.y + noise * rng.normal());
            out.push(Observation { tag: face as u32, body: p, pixel });
        }
    }
    out
}

/// Faces whose outward normal points toward the camera by more than `min_cos`.
fn facing(pose: &Pose, min_cos: f64) -> Vec<usize> {
    let normals: [Vector3<f64>; 6] =
        [Vector3::x(), Vector3::y(), Vector3::z(), -Vector3::x(), -Vector3::y(), -Vector3::z()];
    (0..6)
        .filter(|&f| {
            let n = pose.transform_vector(&normals[f]);
            let c = pose.transform_point(&Point3::from(normals[f] * 8.0));
            -n.dot(&c.coords.normalize()) > min_cos
        })
        .collect()
}

/// The error of `estimate` against `truth` weighed by the inverse covariance: the left
/// perturbation taking the estimate to the truth, in the camera frame.
fn chi_square(estimate: &Pose, truth: &Pose, covariance: &Matrix6<f64>) -> f64 {
    let d = truth.compose(&estimate.inverse());
    let e = Vector6::from_iterator(d.rotation().scaled_axis().iter().chain(d.translation().iter()).copied());
    let inv: Matrix6<f64> = covariance.try_inverse().expect("invertible");
    (e.transpose() * inv * e)[(0, 0)]
}

/// The covariance of a single tag's points at `pose`: the inverse Gauss–Newton normal matrix
/// times the assumed corner variance (five points are too few to estimate it).
fn covariance_at(observations: &[Observation], pose: &Pose) -> Matrix6<f64> {
    let cam = camera();
    let focal = Vector2::new(cam.fx, cam.fy);
    let mut h = Matrix6::zeros();
    for o in observations {
        let c = pose.transform_point(&o.body);
        let j = pose_jacobian(&c, &projection_jacobian(&c, &focal).expect("in front"));
        h += j.transpose() * j;
    }
    h.try_inverse().expect("invertible") * PnpOptions::default().corner_sigma_px.powi(2)
}

#[test]
fn noise_free_points_give_the_exact_pose() {
    let (cam, mut rng) = (camera(), Lcg(7));
    let mut checked = 0;
    while checked < 200 {
        let distance = rng.range(60.0, 140.0);
        let truth = random_pose(&mut rng, distance);
        let faces = facing(&truth, 0.2);
        if faces.is_empty() {
            continue;
        }
        let obs = observe(&truth, &cam, &faces, 0.0, &mut rng);
        let got = solve_pnp(&obs, &cam, None, &PnpOptions::default()).expect("solves");
        let (dr, dt) = got.camera_from_body.distance_to(&truth);
        assert!(dt < 1e-9 && dr < 1e-9, "{} tags: off by {dt:.2e} mm, {dr:.2e} rad", faces.len());
        assert!(got.rms_px < 1e-7, "rms {}", got.rms_px);
        let mut want: Vec<u32> = faces.iter().map(|&f| f as u32).collect();
        want.sort_unstable();
        assert_eq!(got.tags, want);
        checked += 1;
    }
}

#[test]
fn the_order_of_the_points_does_not_matter() {
    let (cam, mut rng) = (camera(), Lcg(11));
    let truth = Pose::from_axis_angle(Vector3::new(0.4, -0.5, 0.2), Vector3::new(3.0, -2.0, 90.0));
    let faces = facing(&truth, 0.2);
    assert!(faces.len() >= 2);
    let mut obs = observe(&truth, &cam, &faces, 0.1, &mut rng);
    let first = solve_pnp(&obs, &cam, None, &PnpOptions::default()).expect("solves");
    for k in 0..20 {
        // A shuffle, and every corner list rotated and reversed in turn.
        for i in (1..obs.len()).rev() {
            let j = (rng.next() * (i + 1) as f64) as usize;
            obs.swap(i, j);
        }
        if k % 2 == 0 {
            obs.reverse();
        }
        let again = solve_pnp(&obs, &cam, None, &PnpOptions::default()).expect("solves");
        let (dr, dt) = again.camera_from_body.distance_to(&first.camera_from_body);
        assert!(dt < 1e-9 && dr < 1e-9, "order changed the pose by {dt:.2e} mm, {dr:.2e} rad");
    }
}

#[test]
fn a_single_tag_gives_its_true_pose_and_keeps_a_distinct_mirror() {
    let cam = camera();
    let mut rng = Lcg(3);
    let mut with_alternative = 0;
    // Face 2 (+z) turned from the camera's axis by 0.5° to 50° and spun about its normal.
    for tilt_deg in [0.5f64, 2.0, 5.0, 10.0, 20.0, 50.0] {
        for trial in 0..10 {
            let spin = f64::from(trial) * 0.7;
            let rot = nalgebra::UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 0.0, spin))
                * nalgebra::UnitQuaternion::from_scaled_axis(Vector3::new(
                    std::f64::consts::PI - tilt_deg.to_radians(),
                    0.0,
                    0.0,
                ));
            let truth = Pose::from_parts(rot, Vector3::new(5.0, 3.0, 100.0));
            assert!(facing(&truth, 0.0).contains(&2), "the +z face is seen");
            // Only its tag is given to the solver.
            let obs = observe(&truth, &cam, &[2], 0.0, &mut rng);
            let got = solve_pnp(&obs, &cam, None, &PnpOptions::default()).expect("solves");
            let (dr, dt) = got.camera_from_body.distance_to(&truth);
            assert!(dt < 1e-8 && dr < 1e-8, "tilt {tilt_deg}°, spin {spin}: off by {dt:.2e} mm, {dr:.2e} rad");
            // Where the mirror solution is a minimum of its own, it is kept, distinct and worse,
            // with the covariance at its own pose.
            if let Some(alt) = &got.alternative {
                with_alternative += 1;
                assert!(alt.rms_px >= got.rms_px);
                assert!(alt.camera_from_body.distance_to(&got.camera_from_body).0 > 1e-3, "a distinct pose");
                let want = covariance_at(&obs, &alt.camera_from_body);
                assert!((alt.covariance - want).norm() < 1e-9 * want.norm(), "the mirror's covariance");
                assert!((got.covariance - want).norm() > 1e-3 * want.norm(), "not the best pose's");
            }
        }
    }
    eprintln!("single tags: {with_alternative} of 60 kept a mirror solution");
    assert!(with_alternative > 0, "no mirror solution kept: the checks of one never ran");
}

#[test]
fn a_tag_that_disagrees_is_dropped() {
    let (cam, mut rng) = (camera(), Lcg(5));
    let truth = Pose::from_axis_angle(Vector3::new(0.5, 0.6, -0.3), Vector3::new(-4.0, 2.0, 110.0));
    let faces = facing(&truth, 0.1);
    assert!(faces.len() >= 3, "{faces:?}");
    let mut obs = observe(&truth, &cam, &faces, 0.1, &mut rng);
    // A wrongly decoded or misplaced tag: its points 6 px off.
    let bad = faces[1] as u32;
    for o in obs.iter_mut().filter(|o| o.tag == bad) {
        o.pixel.x += 6.0;
        o.pixel.y -= 2.0;
    }
    let got = solve_pnp(&obs, &cam, None, &PnpOptions::default()).expect("solves");
    assert_eq!(got.rejected_tags, vec![bad]);
    assert!(!got.tags.contains(&bad));
    // The pose from the remaining tags is as good as their noise allows (chi-square of 6 degrees
    // of freedom under 22.5: a 1-in-1000 event).
    let chi2 = chi_square(&got.camera_from_body, &truth, &got.covariance);
    assert!(chi2 < 22.5, "error far outside the covariance: chi-square {chi2:.1}");
}

#[test]
fn the_covariance_matches_the_scatter_of_noisy_solutions() {
    // With 0.2 px noise, errors weighed by the inverse covariance must average 6 (chi-square
    // with 6 degrees of freedom) if the covariance is right.
    let (cam, mut rng) = (camera(), Lcg(21));
    let truth = Pose::from_axis_angle(Vector3::new(0.3, 2.5, 0.4), Vector3::new(2.0, 1.0, 100.0));
    let faces = facing(&truth, 0.2);
    assert!(faces.len() >= 2, "{faces:?}");
    let trials = 400;
    let mut chi2 = 0.0;
    for _ in 0..trials {
        let obs = observe(&truth, &cam, &faces, 0.2, &mut rng);
        let got = solve_pnp(&obs, &cam, None, &PnpOptions::default()).expect("solves");
        chi2 += chi_square(&got.camera_from_body, &truth, &got.covariance);
    }
    let mean = chi2 / f64::from(trials);
    assert!((4.5..8.0).contains(&mean), "mean chi-square {mean:.2}, want about 6");
}

#[test]
fn a_prior_pose_is_used_as_a_start() {
    let (cam, mut rng) = (camera(), Lcg(9));
    let truth = Pose::from_axis_angle(Vector3::new(3.0, 0.1, 0.0), Vector3::new(0.0, 0.0, 120.0));
    let obs = observe(&truth, &cam, &facing(&truth, 0.2), 0.0, &mut rng);
    let near = truth.compose(&Pose::from_axis_angle(Vector3::new(0.01, -0.02, 0.0), Vector3::new(0.3, 0.0, 0.5)));
    let got = solve_pnp(&obs, &cam, Some(&near), &PnpOptions::default()).expect("solves");
    let (dr, dt) = got.camera_from_body.distance_to(&truth);
    assert!(dt < 1e-9 && dr < 1e-9);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let (cam, mut rng) = (camera(), Lcg(1));
    let truth = Pose::from_axis_angle(Vector3::new(3.0, 0.1, 0.0), Vector3::new(0.0, 0.0, 120.0));
    let obs = observe(&truth, &cam, &facing(&truth, 0.2), 0.0, &mut rng);
    let opts = PnpOptions::default();
    assert_eq!(solve_pnp(&obs[..3], &cam, None, &opts), Err(PnpError::TooFewPoints(3)));
    assert_eq!(solve_pnp(&[], &cam, None, &opts), Err(PnpError::TooFewPoints(0)));
    let mut nan = obs.clone();
    nan[2].pixel.x = f64::NAN;
    assert_eq!(solve_pnp(&nan, &cam, None, &opts), Err(PnpError::NotFinite { index: 2 }));
    let bad_cam = CameraIntrinsics { fx: -1.0, ..cam };
    assert!(matches!(solve_pnp(&obs, &bad_cam, None, &opts), Err(PnpError::BadIntrinsics(_))));
    // Four collinear points determine nothing.
    let line: Vec<Observation> = (0..4)
        .map(|i| Observation {
            tag: 0,
            body: Point3::new(f64::from(i), 0.0, 0.0),
            pixel: Point2::new(900.0 + 10.0 * f64::from(i), 500.0),
        })
        .collect();
    assert!(solve_pnp(&line, &cam, None, &opts).is_err());
}
