//! Dynamic contacts against scenes with known answers: a 3 mm sphere (the lower arch) pressed
//! up into a flat, downward-facing patch (the upper arch) at z = 0. The sphere's pole is its
//! highest point, so the resolved pose, the contact force (the spring's, at equilibrium) and
//! the intercuspation correction are known in closed form.

use jawtrack_occlusion::contacts::{Arch, ContactSettings, contacts};
use jawtrack_occlusion::dynamics::{
    DynamicsError, DynamicsOptions, Step, interpolate_path, resolve_intercuspation, simulate,
};
use jawtrack_occlusion::{Mesh, scenes};
use jawtrack_pose::Pose;
use nalgebra::{Point3, UnitQuaternion, Vector3};
use std::f64::consts::TAU;
use std::sync::OnceLock;
use std::time::Instant;

const R: f64 = 3.0;

fn settings() -> ContactSettings {
    // Reach max(0.5, 2·0.05 + 0.3) = 0.5 mm: deeper than any step moves the sphere.
    ContactSettings { threshold_mm: 0.05, max_depth_mm: 0.5 }
}

fn arch(mesh: Mesh) -> Arch {
    Arch::new(vec![("arch".to_owned(), mesh)], &settings())
}

/// The patch (upper, facing down at z = 0) and the sphere (lower) touching it from below at
/// the identity pose; built once, as indexing takes longer than the tests' simulations.
fn scene() -> &'static (Arch, Arch) {
    static SCENE: OnceLock<(Arch, Arch)> = OnceLock::new();
    SCENE.get_or_init(|| {
        (arch(scenes::patch(10.0, 40, 0.0, true)), arch(scenes::sphere(Point3::new(0.0, 0.0, -R), R, 24)))
    })
}

fn at(x: f64, z: f64) -> Pose {
    Pose::from_parts(UnitQuaternion::identity(), Vector3::new(x, 0.0, z))
}

/// The spring force (N) at an offset of `mm` for `options`: m ω² x, kg·mm/s² → N.
fn spring_force(options: &DynamicsOptions, mm: f64) -> f64 {
    options.mass_kg * (TAU * options.natural_frequency_hz).powi(2) * mm * 1e-3
}

/// Runs `simulate` and prints its cost per integration step.
fn run(upper: &Arch, lower: &Arch, target: &[(f64, Pose)], options: &DynamicsOptions) -> Vec<Step> {
    let started = Instant::now();
    let steps = simulate(upper, lower, target, options).expect("simulates");
    let span = target[target.len() - 1].0 - target[0].0;
    let n = (span / options.dt_s).round().max(1.0);
    eprintln!(
        "{} integration steps (dt {} s) in {:.3} s: {:.1} µs a step",
        n,
        options.dt_s,
        started.elapsed().as_secs_f64(),
        started.elapsed().as_secs_f64() / n * 1e6
    );
    steps
}

/// The deepest penetration between the arches at `pose` measured independently by the
/// kinematic contacts (0 when none).
fn kinematic_depth(upper: &Arch, lower: &Arch, pose: &Pose) -> f64 {
    contacts(upper, lower, pose, &settings()).max_depth_mm().unwrap_or(f64::NEG_INFINITY).max(0.0)
}

#[test]
fn a_sphere_held_into_the_patch_rests_on_it_with_the_spring_force() {
    let (upper, lower) = scene();
    let options = DynamicsOptions::default();
    // The target holds the sphere 0.3 mm past contact for 0.2 s.
    let target: Vec<(f64, Pose)> = (0..=20).map(|i| (i as f64 * 0.01, at(0.0, 0.3))).collect();
    let steps = run(upper, lower, &target, &options);
    assert_eq!(steps.len(), target.len());
    let expected = spring_force(&options, 0.3);
    for s in &steps {
        let z = s.maxilla_scan_from_mandible_scan.translation().z;
        assert!(s.max_penetration_mm <= 0.01, "t {}: penetration {} mm", s.t, s.max_penetration_mm);
        let depth = kinematic_depth(upper, lower, &s.maxilla_scan_from_mandible_scan);
        assert!(depth <= 0.01, "t {}: kinematic depth {depth} mm", s.t);
        assert!(z.abs() <= 0.01, "t {}: the sphere's top is at {z} mm", s.t);
    }
    let settled: Vec<&Step> = steps.iter().filter(|s| s.t >= 0.05).collect();
    let mean = settled.iter().map(|s| s.force_n).sum::<f64>() / settled.len() as f64;
    let worst = settled.iter().map(|s| (s.force_n / expected - 1.0).abs()).fold(0.0, f64::max);
    let residual = steps.iter().map(|s| s.max_penetration_mm).fold(0.0, f64::max);
    eprintln!(
        "held: force {mean:.5} N vs m·ω²·0.3 mm = {expected:.5} N ({:+.3}%, worst sample {:.3}%), residual {residual:.2e} mm",
        (mean / expected - 1.0) * 100.0,
        worst * 100.0
    );
    assert!(worst < 0.05, "force {mean} N vs {expected} N: worst sample {:.2}% off", worst * 100.0);
    // The force pushes the sphere down (−z), at its pole.
    let last = &steps[steps.len() - 1];
    assert!(last.force[2] < 0.0 && last.force[0].abs() < 1e-3 * expected, "{:?}", last.force);
    assert!(!last.contacts.is_empty());
    let total: f64 = last.contacts.iter().map(|c| c.force_n).sum();
    assert!((total / last.force_n - 1.0).abs() < 1e-6, "{total} vs {}", last.force_n);
    assert!(last.contacts[0].point[0].abs() < 0.1 && last.contacts[0].point[2].abs() < 0.01, "{:?}", last.contacts[0]);
}

/// The sphere pressed 0.3 mm into the patch while sliding 3 mm along x at 10 mm/s, sampled at
/// 100 Hz.
fn sliding_target() -> Vec<(f64, Pose)> {
    (0..=30).map(|i| (i as f64 * 0.01, at(-1.5 + 0.1 * i as f64, 0.3))).collect()
}

#[test]
fn a_sphere_slid_along_the_patch_stays_on_its_surface_and_follows_the_target() {
    let (upper, lower) = scene();
    let options = DynamicsOptions::default();
    let target = sliding_target();
    let steps = run(upper, lower, &target, &options);
    assert_eq!(steps.len(), target.len());
    let expected = spring_force(&options, 0.3);
    let (mut worst_z, mut worst_x, mut worst_force): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (s, (_, goal)) in steps.iter().zip(&target) {
        let (p, g) = (s.maxilla_scan_from_mandible_scan.translation(), goal.translation());
        // The penetration removed is the whole 0.3 mm: the sphere's top stays on z = 0.
        worst_z = worst_z.max((g.z - p.z - 0.3).abs());
        worst_x = worst_x.max((p.x - g.x).abs());
        assert!(s.max_penetration_mm <= 0.01, "t {}: penetration {}", s.t, s.max_penetration_mm);
        if s.t > 0.0 {
            worst_force = worst_force.max((s.force_n / expected - 1.0).abs());
        }
    }
    eprintln!(
        "sliding: |z − (target − 0.3)| ≤ {worst_z:.2e} mm, |x − target| ≤ {worst_x:.2e} mm, force within {:.3}%",
        worst_force * 100.0
    );
    assert!(worst_z <= 0.01, "z off the surface by {worst_z} mm");
    assert!(worst_x <= 0.01, "x off the target by {worst_x} mm");
    assert!(worst_force < 0.05, "force off the spring's by {:.2}%", worst_force * 100.0);
}

#[test]
fn a_sphere_pushed_up_into_a_slope_slides_along_it_to_where_the_forces_balance() {
    // The patch tilted 20° about y: the frictionless sphere, pulled straight up, must slide
    // sideways until the spring's pull is along the slope's normal; its centre then sits at the
    // target's projection onto the plane of centres r from the slope.
    static SLOPE: OnceLock<Arch> = OnceLock::new();
    let alpha = 20f64.to_radians();
    let slope = SLOPE.get_or_init(|| {
        let tilt = UnitQuaternion::from_scaled_axis(Vector3::y() * alpha);
        arch(scenes::patch(10.0, 40, 0.0, true).transformed(|p| tilt * p))
    });
    let (_, lower) = scene();
    // The slope's outward normal: −z turned 20° about y.
    let n = Vector3::new(-alpha.sin(), 0.0, -alpha.cos());
    let options = DynamicsOptions::default();
    let mut target = interpolate_path(&at(0.0, 0.0), &at(0.0, 0.3), 0.1, 100.0);
    target.extend((1..=20).map(|i| (0.1 + i as f64 * 0.01, at(0.0, 0.3))));
    let steps = run(slope, lower, &target, &options);
    let goal = Vector3::new(0.0, 0.0, 0.3 - R);
    let press = R - n.dot(&goal);
    let expected_centre = goal + n * press;
    let last = &steps[steps.len() - 1];
    let centre = last.maxilla_scan_from_mandible_scan.transform_point(&Point3::new(0.0, 0.0, -R)).coords;
    let expected = spring_force(&options, press);
    let force = Vector3::from(last.force);
    let angle = force.angle(&n).to_degrees();
    let residual = steps.iter().map(|s| s.max_penetration_mm).fold(0.0, f64::max);
    eprintln!(
        "slope: centre {centre:?} vs {expected_centre:?} ({:.2e} mm), force {:.5} vs {expected:.5} N ({:+.3}%), {angle:.3}° off the normal, residual {residual:.2e} mm",
        (centre - expected_centre).norm(),
        last.force_n,
        (last.force_n / expected - 1.0) * 100.0
    );
    assert!(centre.x < -0.1, "the sphere did not slide along the slope: {centre:?}");
    assert!((centre - expected_centre).norm() < 0.01, "{centre:?} vs {expected_centre:?}");
    assert!((last.force_n / expected - 1.0).abs() < 0.05, "{} vs {expected} N", last.force_n);
    assert!(angle < 1.0, "{angle}°");
    assert!(residual <= 0.01, "{residual}");
}

#[test]
fn intercuspation_moves_a_tilted_sphere_straight_out_of_the_patch() {
    let (upper, lower) = scene();
    let options = DynamicsOptions::default();
    // The sphere 0.2 mm up into the patch, tilted 2° about a horizontal axis through its centre.
    let centre = Vector3::new(0.0, 0.0, -R);
    let tilt = UnitQuaternion::from_scaled_axis(Vector3::new(1.0, 0.5, 0.0).normalize() * 2f64.to_radians());
    let pose = Pose::from_parts(tilt, centre - tilt * centre + Vector3::new(0.0, 0.0, 0.2));
    // The faceted sphere's highest point is its highest vertex: that is how far it must come down.
    let top = lower.mesh.vertices.iter().map(|v| pose.transform_point(v).z).fold(f64::NEG_INFINITY, f64::max);
    assert!((top - 0.2).abs() < 0.003, "{top}");
    let c = resolve_intercuspation(upper, lower, &pose, &options).expect("resolves");
    let shift = Vector3::from(c.shift_mm);
    let error = (shift - Vector3::new(0.0, 0.0, -top)).norm();
    let depth = kinematic_depth(upper, lower, &c.maxilla_scan_from_mandible_scan);
    eprintln!(
        "intercuspation: shift {shift:?} vs (0, 0, {:.5}) mm: error {error:.2e} mm, rotation {:.2e}°, {} rounds, depth {:.4} → {:.2e} mm (kinematic {depth:.2e})",
        -top, c.rotation_deg, c.iterations, c.initial_depth_mm, c.residual_depth_mm
    );
    assert!(error < 1e-3, "shift {shift:?} vs straight down by {top}: {error} mm off");
    assert!((shift.z + 0.2).abs() < 3e-3, "{shift:?}");
    // The least motion also turns the sphere a little (≈ 0.2°): that lowers the tilted pole
    // vertex at a lever of 3 sin 2° mm as well, cheaply against the shell's inertia.
    assert!(c.rotation_deg < 0.5, "{}", c.rotation_deg);
    assert!(c.residual_depth_mm <= options.tolerance_mm && depth <= options.tolerance_mm, "{c:?} {depth}");
    assert!((c.initial_depth_mm - top).abs() < 1e-3, "{c:?}");
    // Nothing to do when nothing penetrates.
    let clear = resolve_intercuspation(upper, lower, &at(0.0, -0.1), &options).expect("resolves");
    assert_eq!((clear.iterations, clear.shift_mm, clear.residual_depth_mm), (0, [0.0; 3], 0.0));
}

#[test]
fn the_resolved_motion_does_not_depend_on_the_step_size() {
    let (upper, lower) = scene();
    // Pressing in while sliding and turning: a minimum-jerk path at a recording's 60 Hz, from
    // touching to 0.3 mm past contact, 3 mm along x, tilted 2° about x and turned 3° about z.
    let from = at(-1.5, 0.0);
    let to = Pose::from_parts(
        UnitQuaternion::from_scaled_axis(Vector3::new(2f64.to_radians(), 0.0, 3f64.to_radians())),
        Vector3::new(1.5, 0.0, 0.3),
    );
    let mut target = interpolate_path(&from, &to, 0.3, 60.0);
    // Then held for 0.1 s.
    target.extend((1..=6).map(|i| (0.3 + i as f64 / 60.0, to)));
    let run_with = |dt_s: f64| run(upper, lower, &target, &DynamicsOptions { dt_s, ..Default::default() });
    let (coarse, fine) = (run_with(1e-3), run_with(5e-4));
    assert_eq!((coarse.len(), fine.len()), (target.len(), target.len()), "a step per target sample");
    // The correction: how far the contacts hold the sphere off the target.
    let correction = coarse.iter().map(|s| s.target_offset_mm).fold(0.0, f64::max);
    let allowed = (0.05 * correction).max(0.005);
    let worst = coarse
        .iter()
        .zip(&fine)
        .map(|(a, b)| {
            let (pa, pb) = (&a.maxilla_scan_from_mandible_scan, &b.maxilla_scan_from_mandible_scan);
            let centre = Point3::new(0.0, 0.0, -R);
            (pa.transform_point(&centre) - pb.transform_point(&centre)).norm()
        })
        .fold(0.0, f64::max);
    let mean = |steps: &[Step]| steps[1..].iter().map(|s| s.force_n).sum::<f64>() / (steps.len() - 1) as f64;
    let (fa, fb) = (mean(&coarse), mean(&fine));
    let force_change = (fa / fb - 1.0).abs();
    let residual = coarse.iter().chain(&fine).map(|s| s.max_penetration_mm).fold(0.0, f64::max);
    eprintln!(
        "dt 1 ms vs 0.5 ms: positions within {worst:.2e} mm ({:.2}% of the {correction:.3} mm correction), mean force {fa:.5} vs {fb:.5} N ({:.3}%), residual ≤ {residual:.2e} mm",
        worst / correction * 100.0,
        force_change * 100.0
    );
    assert!(correction > 0.2, "{correction}");
    assert!(worst <= allowed, "positions differ by {worst} mm, more than {allowed} mm");
    assert!(force_change < 0.05, "mean force {fa} N at 1 ms vs {fb} N at 0.5 ms: {:.2}%", force_change * 100.0);
    assert!(residual <= 0.01, "{residual}");
}

#[test]
fn bad_input_gives_errors() {
    let (upper, lower) = scene();
    let options = DynamicsOptions::default();
    let ok = [(0.0, at(0.0, 0.0)), (0.01, at(0.0, 0.0))];
    let err = |target: &[(f64, Pose)], options: &DynamicsOptions| {
        simulate(upper, lower, target, options).expect_err("must fail")
    };
    assert_eq!(err(&[], &options), DynamicsError::EmptyTarget);
    let e = err(&[ok[0], (0.0, at(0.0, 0.0))], &options);
    assert!(matches!(e, DynamicsError::NonIncreasingTime { index: 1, .. }), "{e}");
    let e = err(&[ok[0], ok[1], (0.005, at(0.0, 0.0))], &options);
    assert!(e.to_string().contains("not after"), "{e}");
    let e = err(&[ok[0], (0.01, at(f64::NAN, 0.0))], &options);
    assert_eq!(e, DynamicsError::NonFinite { index: 1 });
    let e = err(&[(f64::INFINITY, at(0.0, 0.0))], &options);
    assert_eq!(e, DynamicsError::NonFinite { index: 0 });
    for bad in [
        DynamicsOptions { dt_s: 0.0, ..options },
        DynamicsOptions { dt_s: -1e-3, ..options },
        DynamicsOptions { dt_s: 0.02, ..options },
        DynamicsOptions { dt_s: f64::NAN, ..options },
        // 10 ms is allowed in general, but not for a 15 Hz spring (ω·dt ≈ 0.94).
        DynamicsOptions { dt_s: 0.01, ..options },
        DynamicsOptions { mass_kg: 0.0, ..options },
        DynamicsOptions { mass_kg: -0.1, ..options },
        DynamicsOptions { mass_kg: f64::NAN, ..options },
        DynamicsOptions { natural_frequency_hz: 0.0, ..options },
        DynamicsOptions { tolerance_mm: 0.0, ..options },
        DynamicsOptions { max_iterations: 0, ..options },
    ] {
        let e = err(&ok, &bad);
        assert!(matches!(e, DynamicsError::Options(_)), "{bad:?}: {e}");
        let e = resolve_intercuspation(upper, lower, &ok[0].1, &bad).expect_err("must fail");
        assert!(matches!(e, DynamicsError::Options(_)), "{bad:?}: {e}");
    }
    let e = resolve_intercuspation(upper, lower, &at(f64::INFINITY, 0.0), &options).expect_err("must fail");
    assert_eq!(e, DynamicsError::NonFinitePose);
    // A target far beyond the patch drives the sphere too fast for the distance indexes.
    let e = err(&[ok[0], (0.01, at(0.0, -200.0))], &options);
    assert!(matches!(e, DynamicsError::TooFast { .. }), "{e}");
    // A single sample is a valid (resolved, motionless) path.
    let one = simulate(upper, lower, &[(0.5, at(0.0, 0.1))], &options).expect("one sample");
    assert_eq!(one.len(), 1);
    assert!(one[0].maxilla_scan_from_mandible_scan.translation().z.abs() < 0.01, "{:?}", one[0]);
}
