//! Marker-to-scan registration against ground truth: the printable harness body (dodecahedron
//! and mounting post, from `jawtrack-harness`) moved by a known `scan_from_marker`, cut so
//! that only part of the dodecahedron is scanned, with a "tooth" next to it, optionally
//! tessellated finely and noised like a scan; ICP must recover the known pose from a guess
//! 1.5 mm and 5° off, and say so honestly when it cannot.

use jawtrack_harness::{HarnessParams, body_mesh};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_mesh::{Mesh, scenes};
use jawtrack_pose::Pose;
use jawtrack_registration::icp::{
    Acceptance, IcpOptions, IcpResult, RegisterError, SurfaceSample, centred_init, marker_surface_samples, register,
};
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use std::time::Instant;

/// The body with its post, in the marker (body) frame.
fn harness(marker: &Marker) -> Mesh {
    let size = marker.bodies[0].tags[0].size;
    body_mesh(marker.solid, marker.edge, size, &HarnessParams::default()).expect("default harness")
}

/// Each triangle split into four, `levels` times, sharing edge midpoints (the mesh stays closed).
fn subdivide(mesh: &Mesh, levels: usize) -> Mesh {
    let mut m = mesh.clone();
    for _ in 0..levels {
        let mut mid = HashMap::new();
        let mut vertices = m.vertices.clone();
        let mut at = |a: u32, b: u32| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                vertices.push(Point3::from((m.vertices[a as usize].coords + m.vertices[b as usize].coords) / 2.0));
                (vertices.len() - 1) as u32
            })
        };
        let mut triangles = Vec::with_capacity(4 * m.triangles.len());
        for &[a, b, c] in &m.triangles {
            let (ab, bc, ca) = (at(a, b), at(b, c), at(c, a));
            triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        m = Mesh { vertices, triangles };
    }
    m
}

/// Keeps the triangles whose centroid satisfies `keep`.
fn cut(mesh: &Mesh, keep: impl Fn(&Point3<f64>) -> bool) -> Mesh {
    let triangles = (0..mesh.triangles.len())
        .filter(|&t| {
            let [a, b, c] = mesh.corners(t);
            keep(&Point3::from((a.coords + b.coords + c.coords) / 3.0))
        })
        .map(|t| mesh.triangles[t])
        .collect();
    Mesh { vertices: mesh.vertices.clone(), triangles }
}

/// Every vertex coordinate moved by a uniform amount in ±`amplitude` mm (deterministic).
fn noisy(mesh: &Mesh, amplitude: f64, seed: u64) -> Mesh {
    let mut state = seed;
    let mut uniform = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let vertices =
        mesh.vertices.iter().map(|p| p + Vector3::new(uniform(), uniform(), uniform()) * amplitude).collect();
    Mesh { vertices, triangles: mesh.triangles.clone() }
}

/// 20° about a skewed axis, then (12, −30, 41) mm.
fn truth() -> Pose {
    Pose::from_axis_angle(
        Vector3::new(0.4, -0.7, 0.59).normalize() * 20f64.to_radians(),
        Vector3::new(12.0, -30.0, 41.0),
    )
}

/// The truth turned 5° about another skewed axis through the marker's centre and shifted
/// 1.5 mm: a guess as rough as one placed by hand.
fn rough_guess(truth: &Pose) -> Pose {
    *truth
        * Pose::from_axis_angle(
            Vector3::new(-0.3, 0.5, 0.81).normalize() * 5f64.to_radians(),
            Vector3::new(1.0, -0.8, 0.75).normalize() * 1.5,
        )
}

/// The scene of the tests: the harness cut by the plane x = 4 mm of the marker frame (about a
/// third of the dodecahedron unscanned), a 5 mm "tooth" 0.5 mm off one face, all moved into
/// the scan frame by `truth`.
fn scene(marker: &Marker, levels: usize) -> Mesh {
    let body = cut(&subdivide(&harness(marker), levels), |p| p.x < 4.0);
    let face = marker.geometry().faces()[7].clone();
    let tooth = scenes::sphere(Point3::from(face.center + face.normal * 5.5), 5.0, 24);
    Mesh::concat(&[body, tooth]).0.transformed(|p| truth().transform_point(p))
}

fn samples(marker: &Marker) -> Vec<SurfaceSample> {
    marker_surface_samples(marker, BodyKind::Maxilla, 0.5).expect("samples")
}

/// (translation error mm, rotation error °) of a result against the truth.
fn error(result: &IcpResult) -> (f64, f64) {
    let (angle, distance) = result.scan_from_marker.distance_to(&truth());
    (distance, angle.to_degrees())
}

#[test]
fn a_partial_noise_free_scan_gives_the_pose_exactly() {
    let marker = Marker::default();
    let model = samples(&marker);
    let scan = scene(&marker, 0);
    let start = Instant::now();
    let result = register(&model, &scan, &rough_guess(&truth()), &IcpOptions::default()).expect("registers");
    let elapsed = start.elapsed();
    let (mm, deg) = error(&result);
    eprintln!(
        "noise-free: {mm:.2e} mm, {deg:.2e}°, rms {:.2e} mm, {}/{} samples, {} iterations, {elapsed:?}",
        result.rms_mm, result.inliers, result.samples, result.iterations
    );
    assert!(result.converged && !result.inside_out, "{result:?}");
    assert!(mm < 0.01 && deg < 0.05, "{mm} mm {deg}°");
    // In fact to round-off.
    assert!(mm < 1e-6 && deg < 1e-6 && result.rms_mm < 1e-6, "{result:?}");
    // About two thirds of the model is scanned (less the post's footprint and the cut faces).
    assert!((0.45..0.8).contains(&result.overlap()), "{}", result.overlap());
    result.check(&Acceptance::default()).expect("a good fit passes the check");
}

#[test]
fn a_noisy_partial_scan_gives_the_pose_to_a_few_micrometres() {
    let marker = Marker::default();
    let model = samples(&marker);
    let amplitude = 0.02;
    // Triangles of about 0.5 mm, each vertex moved independently: the roughness of a scan.
    let scan = noisy(&scene(&marker, 4), amplitude, 7);
    let start = Instant::now();
    let result = register(&model, &scan, &rough_guess(&truth()), &IcpOptions::default()).expect("registers");
    let elapsed = start.elapsed();
    let (mm, deg) = error(&result);
    eprintln!(
        "noise ±{amplitude} mm on {} triangles: {mm:.2e} mm, {deg:.2e}°, rms {:.4} mm, {}/{} samples, {} \
         iterations, {elapsed:?}",
        scan.triangles.len(),
        result.rms_mm,
        result.inliers,
        result.samples,
        result.iterations
    );
    assert!(result.converged, "{result:?}");
    assert!(mm < 0.005 && deg < 0.02, "{mm} mm {deg}°");
    // A vertex moves σ = 0.02/√3 mm along the normal; the surface between vertices averages it
    // down (by 1/√2 at a random point of a triangle).
    let sigma = amplitude / 3f64.sqrt();
    assert!(result.rms_mm > 0.5 * sigma && result.rms_mm < 1.2 * sigma, "rms {} vs σ {sigma}", result.rms_mm);
    result.check(&Acceptance::default()).expect("a good fit passes the check");
}

#[test]
fn a_scan_wound_inside_out_registers_the_same() {
    let marker = Marker::default();
    let mut scan = scene(&marker, 0);
    for t in &mut scan.triangles {
        t.swap(1, 2);
    }
    let result = register(&samples(&marker), &scan, &rough_guess(&truth()), &IcpOptions::default()).expect("ok");
    let (mm, deg) = error(&result);
    assert!(result.inside_out && result.converged && mm < 1e-6 && deg < 1e-6, "{result:?}");
}

#[test]
fn without_a_guess_a_scan_in_the_marker_orientation_is_found_from_its_centre() {
    let marker = Marker::default();
    let shift = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(-20.0, 35.0, 7.5));
    let scan = harness(&marker).transformed(|p| shift.transform_point(p));
    let init = centred_init(&scan, &marker).expect("a scan with area");
    // The post pulls the centre only a little.
    assert!((init.translation() - shift.translation()).norm() < 1.0, "{:?}", init.translation());
    let result = register(&samples(&marker), &scan, &init, &IcpOptions::default()).expect("registers");
    let (angle, mm) = result.scan_from_marker.distance_to(&shift);
    assert!(result.converged && mm < 1e-6 && angle < 1e-8, "{result:?}");
    assert!(centred_init(&Mesh { vertices: vec![], triangles: vec![] }, &marker).is_none());
}

#[test]
fn a_far_off_guess_is_an_error_that_asks_for_a_better_one() {
    let marker = Marker::default();
    let scan = scene(&marker, 0);
    // 12 mm off, a few model points reach the scan's rim and the tooth, and the fit never
    // settles. 25 mm off, points reach the post, and the fit walks along it onto the
    // dodecahedron and settles perfectly, but on a turned copy with other faces: only its
    // distance from the guess gives it away. 40 mm off, nothing is within reach.
    for offset in [12.0, 25.0, 40.0] {
        let far = truth() * Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, offset, 0.0));
        let outcome = register(&samples(&marker), &scan, &far, &IcpOptions::default());
        let err = outcome.and_then(|r| r.check(&Acceptance::default())).expect_err("refused");
        let expected = match offset {
            12.0 => matches!(err, RegisterError::NotConverged { .. }),
            25.0 => matches!(err, RegisterError::Wandered { .. }),
            _ => matches!(err, RegisterError::TooFewCorrespondences { iteration: 1, .. }),
        };
        assert!(expected, "{offset} mm: {err:?}");
        let text = err.to_string();
        assert!(text.contains("initial guess"), "{text}");
        eprintln!("{offset} mm off: {text}");
    }
}

#[test]
fn a_guess_nearer_a_symmetric_copy_lands_on_that_copy() {
    // The surface cannot tell the faces apart: 72° about a face normal maps the dodecahedron
    // onto itself, so a guess 50° off converges, perfectly fitted, to the turned copy. This is
    // why the guess must be within about 30°, and why nothing here can flag it.
    let marker = Marker::default();
    let face = marker.geometry().faces()[0].clone();
    let turn = |deg: f64| Pose::from_axis_angle(face.normal * deg.to_radians(), Vector3::zeros());
    let scan = scene(&marker, 0);
    let result = register(&samples(&marker), &scan, &(truth() * turn(50.0)), &IcpOptions::default()).expect("fits");
    let (angle, mm) = result.scan_from_marker.distance_to(&(truth() * turn(72.0)));
    assert!(result.converged && result.rms_mm < 1e-6 && angle < 1e-6 && mm < 1e-6, "{result:?}");
    // From 25° off it comes back to the truth.
    let result = register(&samples(&marker), &scan, &(truth() * turn(25.0)), &IcpOptions::default()).expect("fits");
    let (mm, deg) = error(&result);
    assert!(result.converged && mm < 1e-6 && deg < 1e-6, "{result:?}");
}

#[test]
fn an_unrelated_scan_is_refused_not_fitted() {
    let marker = Marker::default();
    let model = samples(&marker);
    let solid = marker.geometry();
    let centre = truth().transform_point(&Point3::origin());
    let init = rough_guess(&truth());
    // A ball as wide as the dodecahedron's insphere, a flat plate through its centre, and a
    // smaller dodecahedron.
    let ball = scenes::sphere(centre, solid.inradius(), 60);
    let plate = scenes::patch(60.0, 60, 0.0, false).transformed(|p| truth().transform_point(p));
    let small = Marker::nominal(0.9 * marker.edge, None).expect("marker");
    let smaller = harness(&small).transformed(|p| truth().transform_point(p));
    for (name, scan) in [("ball", ball), ("plate", plate), ("smaller dodecahedron", smaller)] {
        let outcome = register(&model, &scan, &init, &IcpOptions::default());
        eprintln!("{name}: {outcome:?}");
        let verdict = outcome.and_then(|r| r.check(&Acceptance::default()).map(|()| r));
        let err = verdict.expect_err(name);
        eprintln!("{name}: {err}");
    }
}

#[test]
fn settings_and_guesses_that_cannot_work_are_errors() {
    let marker = Marker::default();
    let scan = scene(&marker, 0);
    let nan = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(f64::NAN, 0.0, 0.0));
    assert!(matches!(register(&samples(&marker), &scan, &nan, &IcpOptions::default()), Err(RegisterError::Init)));
    assert!(matches!(register(&[], &scan, &truth(), &IcpOptions::default()), Err(RegisterError::Options(_))));
    let empty = Mesh { vertices: vec![], triangles: vec![] };
    assert!(matches!(
        register(&samples(&marker), &empty, &truth(), &IcpOptions::default()),
        Err(RegisterError::TooFewCorrespondences { found: 0, .. })
    ));
    // One iteration cannot converge from a rough guess: reported, not hidden.
    let once = IcpOptions { max_iterations: 1, ..Default::default() };
    let result = register(&samples(&marker), &scan, &rough_guess(&truth()), &once).expect("runs");
    assert!(!result.converged);
    let err = result.check(&Acceptance::default()).expect_err("not converged").to_string();
    assert!(err.contains("did not converge in 1 iterations"), "{err}");
}
