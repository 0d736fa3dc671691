//! `jawtrack metrics` on a recording whose motion is known: noise-free jaw poses from the
//! synthetic rig (a 30 mm hinge opening, a 6 mm left and a 5 mm right glide, an 8 mm
//! protrusion), with frames that lost a marker mixed in. The reported extremes must equal
//! where the rig's jaw motion moves the incisal point, to 1e-6 mm.

use jawtrack_synth::scenes::{Glide, JawMotion, Rig};
use nalgebra::{Point3, Vector3};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
mod common;
use common::{jawtrack, ok, refused};

/// Noise-free poses only lose precision in the pose's JSON round trip and matrix→quaternion.
const TOL_MM: f64 = 1e-6;

/// One frame with a jaw pose and the true displacement of the incisal point (head frame, mm).
struct Truth {
    frame: u64,
    t: f64,
    /// (opening, lateral, protrusive).
    d: [f64; 3],
}

/// The recorded session and its truth.
struct Session {
    file: PathBuf,
    truth: Vec<Truth>,
    lost: usize,
}

const HINGE_MM: f64 = 30.0;
const PROTRUSION_MM: f64 = 8.0;

/// Each motion takes 2 s in turn, sampled at 20 frames/s (so every peak, at the middle of its
/// 2 s, is a sample); the first record and every 13th after it lost a marker (no jaw pose).
/// `point_on_mandible_head` is the point whose truth is kept (head frame, jaw closed).
fn session(dir: &Path, point_on_mandible_head: Vector3<f64>) -> Session {
    let rig = Rig::default();
    let motions = [
        JawMotion::Hinge { opening_mm: HINGE_MM, start_s: 0.0, period_s: 2.0 },
        JawMotion::Glide { direction: Glide::Left, amplitude_mm: 6.0, start_s: 2.0, period_s: 2.0 },
        JawMotion::Glide { direction: Glide::Right, amplitude_mm: 5.0, start_s: 4.0, period_s: 2.0 },
        JawMotion::Glide { direction: Glide::Protrusive, amplitude_mm: PROTRUSION_MM, start_s: 6.0, period_s: 2.0 },
    ];
    let header = jawtrack_recording::RecordingHeader::new("metrics test").to_line();
    let mut lines = vec![header];
    let (mut truth, mut lost, mut frame) = (Vec::new(), 0, 0u64);
    let no_pose = |frame: u64, t: f64| {
        json!({"frame": frame, "t": t, "maxilla": null, "mandible": null, "maxilla_from_mandible": null}).to_string()
    };
    lines.push(no_pose(frame, -0.05));
    (lost, frame) = (lost + 1, frame + 1);
    for k in 0..=160u32 {
        let t = f64::from(k) / 20.0;
        let motion = &motions[(k as usize / 40).min(3)];
        let (maxilla, mandible) = rig.markers(motion, t);
        let pose = serde_json::to_value(maxilla.inverse() * mandible).expect("a pose serialises");
        lines.push(
            json!({"frame": frame, "t": t, "maxilla": null, "mandible": null, "maxilla_from_mandible": pose})
                .to_string(),
        );
        let p = Point3::from(point_on_mandible_head);
        let d = rig.jaw(motion, t).transform_point(&p) - p;
        truth.push(Truth { frame, t, d: [d.y, d.x, -d.z] });
        frame += 1;
        if k % 13 == 5 {
            lines.push(no_pose(frame, t + 0.025));
            (lost, frame) = (lost + 1, frame + 1);
        }
    }
    let file = dir.join("session.jsonl");
    std::fs::write(&file, lines.join("\n") + "\n").expect("write");
    Session { file, truth, lost }
}

/// The first frame where `f` of the true displacement is largest, and its value.
fn peak(truth: &[Truth], f: impl Fn(&[f64; 3]) -> f64) -> (f64, u64, f64) {
    truth.iter().fold((f64::NEG_INFINITY, 0, 0.0), |b, x| if f(&x.d) > b.0 { (f(&x.d), x.frame, x.t) } else { b })
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

fn check_extreme(report: &Value, key: &str, want: (f64, u64, f64)) {
    let e = &report[key];
    assert!((num(&e["mm"]) - want.0).abs() < TOL_MM, "{key}: {e} vs true {want:?}");
    assert_eq!(e["frame"], want.1, "{key}: {e} vs true {want:?}");
    assert_eq!(num(&e["t_s"]), want.2, "{key}");
}

/// (b − a) × (c − a).
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The reported hull is a convex counter-clockwise polygon, its corners are path points, every
/// path point is inside it (to 1e-6 mm), and its area is the polygon's and positive.
fn check_envelope(env: &Value, points: &[[f64; 2]]) -> f64 {
    let hull: Vec<[f64; 2]> =
        env["hull_mm"].as_array().expect("hull_mm").iter().map(|c| [num(&c[0]), num(&c[1])]).collect();
    let n = hull.len();
    assert!(n >= 3 && env["vertices"] == n, "{env}");
    for i in 0..n {
        let (a, b, c) = (hull[i], hull[(i + 1) % n], hull[(i + 2) % n]);
        assert!(cross(a, b, c) > 0.0, "convex and counter-clockwise at {b:?}");
        assert!(points.iter().any(|p| (p[0] - b[0]).hypot(p[1] - b[1]) < TOL_MM), "corner {b:?} is a path point");
        let edge = (b[0] - a[0]).hypot(b[1] - a[1]);
        for p in points {
            assert!(cross(a, b, *p) / edge > -TOL_MM, "{p:?} outside the edge {a:?}→{b:?}");
        }
    }
    let area = (0..n).map(|i| hull[i][0] * hull[(i + 1) % n][1] - hull[(i + 1) % n][0] * hull[i][1]).sum::<f64>() / 2.0;
    assert!(area > 0.0 && (num(&env["area_mm2"]) - area).abs() < 1e-9, "{env}: shoelace {area}");
    area
}

/// The true peak opening of the hinge at a point `r` mm from the hinge axis (Y, Z in the head
/// frame), turned by the angle that opens the standard incisal point by the chord `HINGE_MM`.
fn hinge_opening(rig: &Rig, point: Vector3<f64>) -> f64 {
    let lever = rig.mounting.lower_incisal_point - rig.mounting.hinge_point();
    let a = 2.0 * (HINGE_MM / (2.0 * lever.norm())).asin();
    let r = point - rig.mounting.hinge_point();
    // A turn by `a` about +X: y' = y cos a − z sin a.
    r.y * (a.cos() - 1.0) - r.z * a.sin()
}

#[test]
fn metrics_equal_the_known_motion() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = Rig::default();
    let s = session(dir.path(), rig.mounting.lower_incisal_point);
    let file = s.file.to_str().expect("utf-8");
    let out = dir.path().join("out");
    let o = jawtrack(&["metrics", file, "--json", "--out", out.to_str().expect("utf-8")]);
    let report: Value = serde_json::from_str(&ok(&o)).expect("one JSON object on stdout");

    assert_eq!(report["frames_skipped_no_pose"], s.lost, "frames without a pose are counted");
    assert_eq!(report["frames_used"], s.truth.len());
    assert_eq!(report["frames_total"], s.truth.len() + s.lost);
    assert_eq!(report["rest_frame"], 1, "the first frame with a jaw pose");
    assert!(String::from_utf8_lossy(&o.stderr).contains(&format!("{} of", s.lost)), "the skip count is printed");

    // The extremes against the rig's jaw motion, and the simple ones against closed forms.
    let opening = peak(&s.truth, |d| d[0]);
    assert!((opening.0 - hinge_opening(&rig, rig.mounting.lower_incisal_point)).abs() < 1e-9 && opening.2 == 1.0);
    check_extreme(&report, "max_opening", opening);
    check_extreme(&report, "max_left_lateral", peak(&s.truth, |d| d[1]));
    check_extreme(&report, "max_right_lateral", peak(&s.truth, |d| -d[1]));
    let protrusion = peak(&s.truth, |d| d[2]);
    assert!((protrusion.0 - PROTRUSION_MM).abs() < 1e-9 && protrusion.2 == 7.0, "{protrusion:?}");
    check_extreme(&report, "max_protrusion", protrusion);
    // Retrusion with the teeth near contact: the opening arc swings the incisor back further,
    // which is not a retrusion.
    let near_closed = |d: &[f64; 3]| if d[0] <= 2.0 { -d[2] } else { f64::NEG_INFINITY };
    let retrusion = peak(&s.truth, near_closed);
    assert!(peak(&s.truth, |d| -d[2]).0 > retrusion.0 + 1.0, "the arc swings back further");
    check_extreme(&report, "max_retrusion", retrusion);
    assert_eq!(report["retrusion_max_opening_mm"], 2.0);
    // The glides' amplitude is the incisor's arc about the working condyle; its lateral part
    // is smaller.
    let (left, right) = (num(&report["max_left_lateral"]["mm"]), num(&report["max_right_lateral"]["mm"]));
    assert!((4.5..6.0).contains(&left) && (3.5..5.0).contains(&right), "left {left}, right {right}");

    // The hulls are in the axes the plots and the borders use: anterior or left, and up.
    let sagittal: Vec<[f64; 2]> = s.truth.iter().map(|x| [x.d[2], -x.d[0]]).collect();
    let frontal: Vec<[f64; 2]> = s.truth.iter().map(|x| [x.d[1], -x.d[0]]).collect();
    let area = check_envelope(&report["envelope_sagittal"], &sagittal);
    // It holds rest, the widest opening and the farthest protrusion: at least their triangle.
    let at = |frame: u64| s.truth.iter().find(|x| x.frame == frame).map(|x| [x.d[2], -x.d[0]]).expect("a frame");
    let triangle = cross([0.0, 0.0], at(opening.1), at(protrusion.1)).abs() / 2.0;
    assert!(triangle > 50.0 && area >= triangle - 1e-6, "sagittal area {area}, triangle {triangle}");
    check_envelope(&report["envelope_frontal"], &frontal);

    // The traced borders lie inside the hulls and cover most of them.
    for (plane, hull) in [("sagittal", "envelope_sagittal"), ("frontal", "envelope_frontal")] {
        let border = num(&report[format!("border_{plane}")]["area_mm2"]);
        let hull = num(&report[hull]["area_mm2"]);
        assert!(border > 0.5 * hull && border <= hull + 1e-6, "{plane}: border {border}, hull {hull}");
    }
    assert!(report["border_transverse"]["landmarks"].as_array().is_some_and(|l| l.len() >= 4), "{report}");
    // --out: both envelopes and the three borders as SVG and PNG, and metrics.json holding what
    // stdout held.
    for stem in ["envelope_sagittal", "envelope_frontal", "border_sagittal", "border_frontal", "border_transverse"] {
        for ext in ["svg", "png"] {
            let p = out.join(format!("{stem}.{ext}"));
            assert!(std::fs::metadata(&p).is_ok_and(|m| m.len() > 1000), "{} written", p.display());
        }
    }
    let saved: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).expect("metrics.json")).expect("json");
    assert_eq!(saved, report);

    // The summary: one line per metric, in mm.
    let text = ok(&jawtrack(&["metrics", file]));
    for label in ["max opening", "max left lateral", "max right lateral", "max protrusion", "max retrusion"] {
        let line = text.lines().find(|l| l.starts_with(label)).unwrap_or_else(|| panic!("'{label}' in {text}"));
        assert!(line.contains(" mm "), "{line}");
    }
    assert!(text.contains(&format!("{} skipped", s.lost)) && text.contains("mm²"), "{text}");
}

#[test]
fn a_custom_incisal_point_is_measured_instead() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = Rig::default();
    // 10 mm below the standard incisal point (head frame, jaw closed), in the mandible
    // marker's frame.
    let lower = rig.mounting.lower_incisal_point + Vector3::new(0.0, 10.0, 0.0);
    let s = session(dir.path(), lower);
    let file = s.file.to_str().expect("utf-8");
    let in_marker = |p: Vector3<f64>| rig.mounting.head_from_mandible_rest.inverse().transform_point(&Point3::from(p));
    let arg = |p: Point3<f64>| format!("{},{},{}", p.x, p.y, p.z);
    let q = in_marker(lower);
    assert!(q.x < 0.0 || q.y < 0.0 || q.z < 0.0, "a negative coordinate is passed as it is: {q}");
    let report: Value =
        serde_json::from_str(&ok(&jawtrack(&["metrics", file, "--json", "--incisor", &arg(q)]))).expect("json");
    let opening = peak(&s.truth, |d| d[0]);
    assert!((opening.0 - hinge_opening(&rig, lower)).abs() < 1e-9);
    check_extreme(&report, "max_opening", opening);
    check_extreme(&report, "max_left_lateral", peak(&s.truth, |d| d[1]));
    check_extreme(&report, "max_protrusion", peak(&s.truth, |d| d[2]));
    assert_eq!(report["incisor_standard"], false);
    // Naming the standard point gives the default's numbers.
    let standard = in_marker(rig.mounting.lower_incisal_point);
    let named: Value =
        serde_json::from_str(&ok(&jawtrack(&["metrics", file, "--json", "--incisor", &arg(standard)]))).expect("json");
    let default: Value = serde_json::from_str(&ok(&jawtrack(&["metrics", file, "--json"]))).expect("json");
    for key in ["max_opening", "max_left_lateral", "max_right_lateral", "max_protrusion", "envelope_frontal"] {
        assert_eq!(named[key], default[key], "{key}");
    }
}

#[test]
fn bad_input_is_refused_with_a_message_naming_the_problem() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).expect("write");
        p.to_str().expect("utf-8").to_owned()
    };
    refused(&jawtrack(&["metrics", "/nonexistent/session.jsonl"]), "/nonexistent/session.jsonl");
    refused(&jawtrack(&["metrics", &path("empty.jsonl", "")]), "has no frames");
    refused(&jawtrack(&["metrics", &path("garbage.jsonl", "not json\n{\"frame\":")]), "has no frames");
    let lost = "{\"frame\":0,\"t\":0,\"maxilla\":null,\"mandible\":null,\"maxilla_from_mandible\":null}\n";
    refused(&jawtrack(&["metrics", &path("lost.jsonl", lost)]), "no frame has a jaw pose");
    let s = session(dir.path(), Rig::default().mounting.lower_incisal_point);
    let file = s.file.to_str().expect("utf-8");
    refused(&jawtrack(&["metrics", file, "--rest-frame", "0"]), "frame 0 has no jaw pose");
    refused(&jawtrack(&["metrics", file, "--rest-frame", "9999"]), "no such frame");
    refused(&jawtrack(&["metrics", file, "--incisor", "1,2"]), "X,Y,Z (3 numbers in mm)");
    refused(&jawtrack(&["metrics", file, "--out", &path("a-file", "")]), "a-file");
}

/// The numbers in `v` that are zero with a minus sign.
fn negative_zeros(v: &Value) -> usize {
    match v {
        Value::Number(n) => usize::from(n.as_f64().is_some_and(|x| x == 0.0 && x.is_sign_negative())),
        Value::Array(a) => a.iter().map(negative_zeros).sum(),
        Value::Object(o) => o.values().map(negative_zeros).sum(),
        _ => 0,
    }
}

#[test]
fn a_jaw_that_never_moves_measures_zero_without_a_minus_sign() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("still.jsonl");
    let identity = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    let lines: Vec<String> = (0..4u32)
        .map(|k| {
            json!({"frame": k, "t": f64::from(k) / 20.0, "maxilla": null, "mandible": null, "maxilla_from_mandible": identity})
                .to_string()
        })
        .collect();
    std::fs::write(&file, lines.join("\n") + "\n").expect("write");
    let file = file.to_str().expect("utf-8");
    let text = ok(&jawtrack(&["metrics", file]));
    assert!(!text.contains("-0.00") && text.contains("max right lateral      0.00 mm"), "{text}");
    let report: Value = serde_json::from_str(&ok(&jawtrack(&["metrics", file, "--json"]))).expect("JSON");
    assert_eq!(negative_zeros(&report), 0, "{report}");
    let out = dir.path().join("m");
    ok(&jawtrack(&["metrics", file, "--out", out.to_str().expect("utf-8")]));
    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).expect("written")).expect("JSON");
    assert_eq!(negative_zeros(&written), 0, "{written}");
    let plot = jawtrack(&["plot", file, "--out", out.to_str().expect("utf-8")]);
    ok(&plot);
    let said = String::from_utf8_lossy(&plot.stderr);
    assert!(said.contains("right 0.0 mm") && !said.contains("-0.0"), "{said}");
    let csv = ok(&jawtrack(&["export", file, "--csv", "--out", "-"]));
    assert!(csv.lines().skip(1).all(|l| l.split(',').all(|c| c != "-0")), "{csv}");
}

#[test]
fn the_bite_accepted_while_recording_is_the_rest_every_reader_measures_from() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rig = Rig::default();
    let s = session(dir.path(), rig.mounting.lower_incisal_point);
    let hinge = JawMotion::Hinge { opening_mm: HINGE_MM, start_s: 0.0, period_s: 2.0 };
    let pose_at = |t: f64| {
        let (maxilla, mandible) = rig.markers(&hinge, t);
        serde_json::to_value(maxilla.inverse() * mandible).expect("a pose serialises")
    };
    // The recording starts with the jaw half open (frame 0), then the held bite is accepted.
    let text = std::fs::read_to_string(&s.file).expect("session");
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    lines[1] =
        json!({"frame": 0, "t": -0.05, "maxilla": null, "mandible": null, "maxilla_from_mandible": pose_at(0.5)})
            .to_string();
    let bite = json!({"bite": {"t": -0.05, "maxilla_from_mandible": pose_at(0.0), "frames": 15, "span_s": 0.47,
        "spread_mm": 0.02, "spread_deg": 0.03}});
    let without = dir.path().join("without.jsonl");
    std::fs::write(&without, lines.join("\n") + "\n").expect("write");
    lines.push(bite.to_string());
    let with = dir.path().join("with.jsonl");
    std::fs::write(&with, lines.join("\n") + "\n").expect("write");

    let report = |file: &Path| -> Value {
        serde_json::from_str(&ok(&jawtrack(&["metrics", file.to_str().expect("utf-8"), "--json"]))).expect("JSON")
    };
    let opening = peak(&s.truth, |d| d[0]);
    let measured = report(&with);
    assert_eq!(measured["rest"]["source"], "bite", "{}", measured["rest"]);
    assert_eq!(measured["rest_frame"], Value::Null);
    check_extreme(&measured, "max_opening", opening);
    // Without it, the half-open first frame is the rest: every number is off.
    let naive = report(&without);
    assert_eq!(naive["rest"], json!({"source": "frame", "frame": 0}));
    assert!((num(&naive["max_opening"]["mm"]) - opening.0).abs() > 5.0, "{}", naive["max_opening"]);
    let text = ok(&jawtrack(&["metrics", with.to_str().expect("utf-8")]));
    assert!(text.contains("rest: the bite accepted at t = -0.05 s (15 frames held within 0.02 mm)"), "{text}");
    // --rest-frame still overrides it.
    let o = ok(&jawtrack(&["metrics", with.to_str().expect("utf-8"), "--json", "--rest-frame", "0"]));
    let chosen: Value = serde_json::from_str(&o).expect("JSON");
    assert_eq!(chosen["rest"]["source"], "frame");
}
