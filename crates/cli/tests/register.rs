//! `jawtrack register` end to end: the harness body that `jawtrack harness` writes, moved by a
//! known pose (and for the maxilla cut to a partial scan), is registered for each body into
//! one registration file, which must then hold both known poses and keep what else it had.
//! Bad inputs must fail naming the problem, and write nothing.

use jawtrack_occlusion::Mesh;
use jawtrack_pose::Pose;
use jawtrack_registration::Registration;
use nalgebra::{Point3, Vector3};
use std::path::{Path, PathBuf};
mod common;
use common::{jawtrack, ok, refused, s};

/// Writes the harness files into `dir/harness`; returns (marker file, body mesh in the marker
/// frame).
fn harness(dir: &Path) -> (PathBuf, Mesh) {
    let out = dir.join("harness");
    ok(&jawtrack(&["harness", "--out", s(&out)]));
    let body = Mesh::load(&out.join("dodecahedron-with-post.stl")).expect("the body STL reads");
    (out.join("marker.json"), body)
}

/// The body moved into a scan frame by `scan_from_marker`, keeping the triangles whose
/// centroid (marker frame) satisfies `keep`, written as STL.
fn write_scan(body: &Mesh, scan_from_marker: &Pose, keep: impl Fn(&Point3<f64>) -> bool, path: &Path) {
    let triangles = (0..body.triangles.len())
        .filter(|&t| {
            let [a, b, c] = body.corners(t);
            keep(&Point3::from((a.coords + b.coords + c.coords) / 3.0))
        })
        .map(|t| body.triangles[t])
        .collect();
    let cut = Mesh { vertices: body.vertices.clone(), triangles };
    cut.transformed(|p| scan_from_marker.transform_point(p)).write_stl_file(path).expect("writes the scan");
}

/// The truth turned 5° and shifted 1.5 mm in the marker frame.
fn rough(truth: &Pose) -> Pose {
    *truth
        * Pose::from_axis_angle(
            Vector3::new(-0.3, 0.5, 0.81).normalize() * 5f64.to_radians(),
            Vector3::new(1.0, -0.8, 0.75).normalize() * 1.5,
        )
}

/// `rx,ry,rz,tx,ty,tz` (degrees, mm).
fn six(p: &Pose) -> String {
    let r = p.rotation().scaled_axis().map(f64::to_degrees);
    let t = p.translation();
    format!("{},{},{},{},{},{}", r.x, r.y, r.z, t.x, t.y, t.z)
}

/// 16 row-major numbers.
fn sixteen(p: &Pose) -> String {
    p.to_row_major().map(|v| v.to_string()).join(",")
}

fn upper_truth() -> Pose {
    Pose::from_axis_angle(
        Vector3::new(0.4, -0.7, 0.59).normalize() * 20f64.to_radians(),
        Vector3::new(12.0, -30.0, 41.0),
    )
}

fn lower_truth() -> Pose {
    Pose::from_axis_angle(
        Vector3::new(-0.2, 0.9, 0.3).normalize() * 35f64.to_radians(),
        Vector3::new(-8.0, 22.5, -15.0),
    )
}

/// Asserts `got` is within 0.01 mm and 0.05° of `want` (STL stores single precision).
fn close(got: &Pose, want: &Pose, what: &str) {
    let (angle, mm) = got.distance_to(want);
    assert!(mm < 0.01 && angle.to_degrees() < 0.05, "{what}: {mm} mm, {}°", angle.to_degrees());
}

#[test]
fn both_bodies_register_into_one_file_that_keeps_the_rest() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (marker, body) = harness(dir.path());
    let upper_scan = dir.path().join("upper-harness.stl");
    let lower_scan = dir.path().join("lower-harness.ply");
    // The upper scan misses a third of the dodecahedron; the lower one is whole, and PLY.
    write_scan(&body, &upper_truth(), |p| p.x < 4.0, &upper_scan);
    let lower = body.transformed(|p| lower_truth().transform_point(p));
    lower.write_coloured_ply(&lower_scan, &vec![[200, 200, 200]; lower.vertices.len()]).expect("writes the PLY");

    let out = dir.path().join("reg.json");
    let mut existing = Registration::identity();
    let bite = Pose::from_axis_angle(Vector3::new(0.01, 0.0, -0.02), Vector3::new(0.3, -0.1, 0.2));
    existing.maxilla_scan_from_mandible_scan_at_intercuspation = bite;
    std::fs::write(&out, existing.to_json()).expect("writes the registration");

    let printed = ok(&jawtrack(&[
        "register",
        "--marker",
        s(&marker),
        "--body",
        "maxilla",
        "--scan",
        s(&upper_scan),
        "--init",
        &sixteen(&rough(&upper_truth())),
        "--out",
        s(&out),
    ]));
    assert!(printed.contains("registered") && printed.contains("mm RMS"), "{printed}");
    let after_upper = Registration::load(&out).expect("reads back");
    close(&after_upper.maxilla_scan_from_maxilla_marker, &upper_truth(), "maxilla");
    assert_eq!(after_upper.mandible_scan_from_mandible_marker, Pose::identity());

    let printed = ok(&jawtrack(&[
        "register",
        "--marker",
        s(&marker),
        "--body",
        "mandible",
        "--scan",
        s(&lower_scan),
        "--init",
        &six(&rough(&lower_truth())),
        "--out",
        s(&out),
    ]));
    assert!(printed.contains("mandible_scan_from_mandible_marker"), "{printed}");
    let both = Registration::load(&out).expect("reads back");
    // Kept (to the rounding of reading the matrix back).
    let (angle, mm) = both.maxilla_scan_from_maxilla_marker.distance_to(&after_upper.maxilla_scan_from_maxilla_marker);
    assert!(angle < 1e-12 && mm < 1e-12, "the maxilla entry is kept");
    close(&both.mandible_scan_from_mandible_marker, &lower_truth(), "mandible");
    let (angle, mm) = both.maxilla_scan_from_mandible_scan_at_intercuspation.distance_to(&bite);
    assert!(angle < 1e-12 && mm < 1e-12, "the intercuspation pose is kept");
}

#[test]
fn without_init_a_scan_in_the_marker_orientation_registers_into_a_new_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (marker, body) = harness(dir.path());
    let truth = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(5.0, -7.0, 60.0));
    let scan = dir.path().join("scan.stl");
    write_scan(&body, &truth, |_| true, &scan);
    let out = dir.path().join("new.json");
    let printed = ok(&jawtrack(&[
        "register",
        "--marker",
        s(&marker),
        "--body",
        "mandible",
        "--scan",
        s(&scan),
        "--out",
        s(&out),
    ]));
    assert!(printed.contains("no --init"), "{printed}");
    let r = Registration::load(&out).expect("a new registration file");
    close(&r.mandible_scan_from_mandible_marker, &truth, "mandible");
    assert_eq!(r.maxilla_scan_from_maxilla_marker, Pose::identity());
}

#[test]
fn bad_inputs_fail_naming_the_problem_and_write_nothing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (marker, body) = harness(dir.path());
    let scan = dir.path().join("scan.stl");
    write_scan(&body, &upper_truth(), |_| true, &scan);
    let out = dir.path().join("reg.json");
    let good_init = sixteen(&rough(&upper_truth()));
    let run = |marker: &Path, body: &str, scan: &Path, init: &str, out: &Path| {
        jawtrack(&[
            "register",
            "--marker",
            s(marker),
            "--body",
            body,
            "--scan",
            s(scan),
            "--init",
            init,
            "--out",
            s(out),
        ])
    };

    refused(&run(&marker, "maxilla", &dir.path().join("missing.stl"), &good_init, &out), "missing.stl");
    let metres = dir.path().join("metres.stl");
    body.transformed(|p| Point3::from(p.coords * 0.001)).write_stl_file(&metres).expect("writes");
    refused(&run(&marker, "maxilla", &metres, &good_init, &out), "metres");
    let corrupt = dir.path().join("corrupt.stl");
    std::fs::write(&corrupt, b"solid nothing\nfacet normal oops").expect("writes");
    refused(&run(&marker, "maxilla", &corrupt, &good_init, &out), "corrupt.stl");
    let bad_marker = dir.path().join("bad-marker.json");
    std::fs::write(&bad_marker, "{\"version\": 1, \"units\": \"inch\"").expect("writes");
    refused(&run(&bad_marker, "maxilla", &scan, &good_init, &out), "bad-marker.json");
    refused(&run(&marker, "incisor", &scan, &good_init, &out), "maxilla or mandible");
    refused(&run(&marker, "maxilla", &scan, "1,2,3", &out), "expected 6 numbers");
    // 15 mm off: nothing within reach.
    let far = upper_truth() * Pose::from_axis_angle(Vector3::zeros(), Vector3::new(15.0, 0.0, 0.0));
    refused(&run(&marker, "maxilla", &scan, &sixteen(&far), &out), "--init");
    // A demand the fit cannot meet: 90 % of the surface from a scan missing a third of it.
    let partial = dir.path().join("partial.stl");
    write_scan(&body, &upper_truth(), |p| p.x < 4.0, &partial);
    let strict = jawtrack(&[
        "register",
        "--marker",
        s(&marker),
        "--body",
        "maxilla",
        "--scan",
        s(&partial),
        "--init",
        &good_init,
        "--out",
        s(&out),
        "--min-overlap",
        "0.9",
    ]);
    refused(&strict, "of the marker solid's surface matched");
    assert!(!out.exists(), "nothing was written");

    let not_registration = dir.path().join("notes.json");
    std::fs::write(&not_registration, "{\"hello\": 1}").expect("writes");
    refused(&run(&marker, "maxilla", &scan, &good_init, &not_registration), "not a registration file");
    assert_eq!(std::fs::read_to_string(&not_registration).expect("still there"), "{\"hello\": 1}");
}
