//! `jawtrack hinge-axis` on recordings whose motion is known: noise-free jaw poses from the
//! synthetic rig, a 40 mm hinge opening about the mounting's hinge axis, then a left glide
//! (a turn about the working condyle's vertical axis, not about the hinge). The axis printed as
//! JSON must be the rig's, in the maxilla marker's frame and, given a registration, in the
//! upper scan's.

use jawtrack_kinematics::{Mounting, Side};
use jawtrack_pose::Pose;
use jawtrack_synth::scenes::{Glide, JawMotion, Rig};
use nalgebra::{Point3, Vector3};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
mod common;
use common::{jawtrack, ok, refused, s};

/// Only the poses' JSON round trip limits noise-free poses.
const TOL_MM: f64 = 1e-5;
const TOL_DEG: f64 = 1e-5;

/// The opening (0–2 s) and the glide (2–4 s) at 20 frames/s, as a recording in `dir`.
fn session(dir: &Path, opening_mm: f64) -> PathBuf {
    let rig = Rig::default();
    let header = jawtrack_recording::RecordingHeader::new("hinge-axis test").to_line();
    let mut lines = vec![header];
    for k in 0..80u32 {
        let t = f64::from(k) / 20.0;
        let motion = if t < 2.0 {
            JawMotion::Hinge { opening_mm, start_s: 0.0, period_s: 2.0 }
        } else {
            JawMotion::Glide { direction: Glide::Left, amplitude_mm: 6.0, start_s: 2.0, period_s: 2.0 }
        };
        let (maxilla, mandible) = rig.markers(&motion, t);
        let pose = serde_json::to_value(maxilla.inverse() * mandible).expect("a pose serialises");
        lines.push(
            json!({"frame": k, "t": t, "maxilla": null, "mandible": null, "maxilla_from_mandible": pose}).to_string(),
        );
    }
    let file = dir.join("opening.jsonl");
    std::fs::write(&file, lines.join("\n") + "\n").expect("write");
    file
}

fn vec3(v: &Value) -> Vector3<f64> {
    let a: Vec<f64> = v.as_array().expect("an array").iter().map(|c| c.as_f64().expect("a number")).collect();
    Vector3::new(a[0], a[1], a[2])
}

/// The rig's hinge axis in the maxilla marker's frame: its midpoint, condyles and direction.
fn true_axis() -> (Point3<f64>, [Point3<f64>; 2], Vector3<f64>) {
    let m = Mounting::default();
    let maxilla_from_head = m.head_from_maxilla.inverse();
    let at = |p: Vector3<f64>| maxilla_from_head.transform_point(&Point3::from(p));
    (
        at(m.hinge_point()),
        [at(m.condyle(Side::Left)), at(m.condyle(Side::Right))],
        maxilla_from_head.rotation() * Vector3::x(),
    )
}

/// Distance from `q` to the line through `p` along unit `d`.
fn off_line(q: &Point3<f64>, p: &Vector3<f64>, d: &Vector3<f64>) -> f64 {
    let r = q.coords - p;
    (r - d * r.dot(d)).norm()
}

fn json_of(args: &[&str]) -> Value {
    serde_json::from_str(&ok(&jawtrack(args))).expect("one JSON object")
}

#[test]
fn the_opening_gives_the_rig_s_hinge_axis_in_both_frames() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path(), 40.0);
    let scan_from_maxilla = Pose::from_axis_angle(Vector3::new(0.1, -0.4, 0.05), Vector3::new(12.0, -3.0, 40.0));
    let registration = dir.path().join("registration.json");
    let reg = json!({
        "version": 1,
        "units": "mm",
        "maxilla_scan_from_maxilla_marker": scan_from_maxilla,
        "mandible_scan_from_mandible_marker": Pose::identity(),
    });
    std::fs::write(&registration, reg.to_string()).expect("write");
    let out = json_of(&["hinge-axis", s(&rec), "--to", "1.99", "--registration", s(&registration), "--json"]);
    let (mid, condyles, dir_true) = true_axis();
    let (p, d) = (vec3(&out["point"]), vec3(&out["direction"]));
    assert!((d.norm() - 1.0).abs() < 1e-9, "the direction is a unit vector: {out}");
    assert!(off_line(&mid, &p, &d) < TOL_MM, "{out}");
    for c in &condyles {
        assert!(off_line(c, &p, &d) < TOL_MM, "{out}");
    }
    let deg = d.angle(&dir_true).to_degrees();
    assert!(deg.min(180.0 - deg) < TOL_DEG, "{deg}°: {out}");
    // The point is the axis's nearest to the mandible marker at rest: on the midline, so at the
    // midpoint between the condyles.
    assert!((p - mid.coords).norm() < 0.01, "{p} vs {mid}");
    assert_eq!(out["frame"], "maxilla marker");
    assert_eq!(out["units"], "mm");
    assert!(out["uncertainty"]["point_mm"].as_f64().expect("σ") < 1e-4, "{out}");
    assert!(out["uncertainty"]["direction_deg"].as_f64().expect("σ") < 1e-4, "{out}");
    // Early opening only: the turns up to the default 12° of the 40 mm opening's 23.8°.
    let widest = out["max_rotation_deg"].as_f64().expect("widest");
    assert!(widest <= 12.0 && widest > 10.0, "{out}");
    // In the upper scan's frame: the same line, mapped.
    let (ps, ds) = (vec3(&out["point_scan"]), vec3(&out["direction_scan"]));
    assert!((ps - scan_from_maxilla.transform_point(&Point3::from(p)).coords).norm() < 1e-9);
    assert!((ds - scan_from_maxilla.rotation() * d).norm() < 1e-9);
    // The standard mounting's condyles lie on the rig's axis: moved by nothing.
    for side in ["left", "right"] {
        let c = &out["condyles_on_axis"][side];
        assert!(c["moved_mm"].as_f64().expect("mm") < TOL_MM, "{out}");
    }
    assert_eq!(out["condyles_on_axis"]["given"], false);
    // Condyles given 3 mm off the axis (from a CBCT, say) are moved onto it.
    let up = Vector3::new(0.0, 1.0, 0.0).cross(&dir_true).normalize() * 3.0;
    let (l, r) = (condyles[0].coords + up, condyles[1].coords + up);
    let given = format!("{},{},{},{},{},{}", l.x, l.y, l.z, r.x, r.y, r.z);
    let moved = json_of(&["hinge-axis", s(&rec), "--to", "1.99", "--condyles", &given, "--json"]);
    for (side, truth) in [("left", condyles[0]), ("right", condyles[1])] {
        let c = &moved["condyles_on_axis"][side];
        assert!((c["moved_mm"].as_f64().expect("mm") - 3.0).abs() < TOL_MM, "{moved}");
        assert!((vec3(&c["point"]) - truth.coords).norm() < TOL_MM, "{moved}");
    }
    // The same condyles from a points file, through the registration.
    let scan_from_head = scan_from_maxilla * Mounting::default().head_from_maxilla.inverse();
    let in_scan = |p: Vector3<f64>, from_head: bool| {
        let q = if from_head { scan_from_head } else { scan_from_maxilla }.transform_point(&Point3::from(p));
        format!("{},{},{}", q.x, q.y, q.z)
    };
    let occlusal = [Vector3::zeros(), Vector3::new(25.0, 0.0, 35.0), Vector3::new(-25.0, 0.0, 35.0)]
        .map(|p| in_scan(p, true))
        .join(",");
    let points = dir.path().join("points.json");
    ok(&jawtrack(&[
        "points",
        "--occlusal",
        &occlusal,
        "--lower-incisal",
        &in_scan(Vector3::new(0.0, 1.5, 1.0), true),
        "--condyles",
        &format!("{},{}", in_scan(l, false), in_scan(r, false)),
        "--out",
        s(&points),
    ]));
    let args = ["hinge-axis", s(&rec), "--to", "1.99", "--json", "--points", s(&points), "--registration"];
    let from_points = json_of(&[&args[..], &[s(&registration)]].concat());
    assert_eq!(from_points["condyles_on_axis"]["source"], "the points file's", "{from_points}");
    for (side, truth) in [("left", condyles[0]), ("right", condyles[1])] {
        let c = &from_points["condyles_on_axis"][side];
        assert!((c["moved_mm"].as_f64().expect("mm") - 3.0).abs() < TOL_MM, "{from_points}");
        assert!((vec3(&c["point"]) - truth.coords).norm() < TOL_MM, "{from_points}");
    }
    refused(&jawtrack(&args[..7]), "--points needs --registration");
    refused(&jawtrack(&["hinge-axis", s(&rec), "--condyles", "1,2,3"]), "6 numbers in mm");
    // The summary says the same in words.
    let text = ok(&jawtrack(&["hinge-axis", s(&rec), "--to", "1.99"]));
    assert!(text.contains("maxilla marker's frame") && text.contains("uncertainty (1σ)"), "{text}");
}

#[test]
fn the_window_keeps_the_glide_out() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path(), 40.0);
    let windowed = json_of(&["hinge-axis", s(&rec), "--to", "1.99", "--json"]);
    let whole = json_of(&["hinge-axis", s(&rec), "--json"]);
    let rms = |v: &Value| v["uncertainty"]["rms_mm"].as_f64().expect("rms");
    assert!(rms(&windowed) < 1e-6 && rms(&whole) > 0.05, "{windowed} {whole}");
    let (mid, _, _) = true_axis();
    let miss = off_line(&mid, &vec3(&whole["point"]), &vec3(&whole["direction"]));
    assert!(miss > 10.0 * TOL_MM, "a glide is not a hinge turn: {whole}");
    // A wider window takes the whole 40 mm arc.
    let wide = json_of(&["hinge-axis", s(&rec), "--to", "1.99", "--max-rotation-deg", "30", "--json"]);
    assert!(wide["max_rotation_deg"].as_f64().expect("widest") > 23.0, "{wide}");
}

#[test]
fn bad_windows_and_small_openings_are_refused_with_what_to_do() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path(), 40.0);
    refused(&jawtrack(&["hinge-axis", s(&rec), "--from", "3", "--to", "1"]), "is not before --to");
    refused(&jawtrack(&["hinge-axis", s(&rec), "--from", "10"]), "no frame from 10 s has a jaw pose");
    let sub = dir.path().join("small");
    std::fs::create_dir(&sub).expect("mkdir");
    let small = session(&sub, 4.0);
    refused(&jawtrack(&["hinge-axis", s(&small), "--to", "1.99"]), "record the jaw opening slowly");
    refused(&jawtrack(&["hinge-axis", s(&rec), "--max-rotation-deg", "0.2"]), "must be below the largest");
    refused(&jawtrack(&["hinge-axis", s(&dir.path().join("missing.jsonl"))]), "missing.jsonl");
}
