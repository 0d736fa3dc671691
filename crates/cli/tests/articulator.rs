//! `jawtrack articulator` on a recording of programmed border movements (`synth::scenes::guided`):
//! a protrusion (0–2 s), a laterotrusion toward the left (3–5 s) and toward the right (6–8 s),
//! each from the closed jaw, then centric occlusion held (9–9.5 s), noise-free. The values
//! printed as JSON must be the programmed ones.

use jawtrack_kinematics::Side;
use jawtrack_pose::Pose;
use jawtrack_synth::scenes::{Guidance, Rig};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
mod common;
use common::{jawtrack, ok, refused, s};

/// Only the poses' JSON round trip limits noise-free poses.
const TOL: f64 = 1e-5;

const GUIDANCE: Guidance = Guidance {
    condylar_inclination_deg: 36.0,
    bennett_deg: 11.0,
    side_shift_mm: 0.6,
    protrusive_guidance_deg: 48.0,
    lateral_guidance_deg: 31.0,
};

fn session(dir: &Path) -> PathBuf {
    let rig = Rig::default();
    let m = &rig.mounting;
    let header = jawtrack_recording::RecordingHeader::new("articulator test").to_line();
    let mut lines = vec![header];
    let mut frame = 0u64;
    let mut push = |t: f64, jaw: Pose| {
        let pose = m.head_from_maxilla.inverse() * jaw * m.head_from_mandible_rest;
        let pose = serde_json::to_value(pose).expect("a pose serialises");
        lines.push(
            json!({"frame": frame, "t": t, "maxilla": null, "mandible": null, "maxilla_from_mandible": pose})
                .to_string(),
        );
        frame += 1;
    };
    for k in 0..=40u32 {
        let u = f64::from(k) / 40.0;
        push(2.0 * u, rig.protrusion(&GUIDANCE, 8.0 * u));
    }
    for (start, side) in [(3.0, Side::Left), (6.0, Side::Right)] {
        for k in 0..=44u32 {
            // The side shift over the first 4 steps, then 8 mm of the non-working condyle's path.
            let travel = if k <= 4 { -1.0 + f64::from(k) / 4.0 } else { 8.0 * f64::from(k - 4) / 40.0 };
            push(start + 2.0 * f64::from(k) / 44.0, rig.laterotrusion(&GUIDANCE, side, travel));
        }
    }
    // Centric occlusion held at 9–9.5 s: 0.8 mm back and 0.3 mm up of the bite.
    for k in 0..=5u32 {
        let held = Pose::from_parts(nalgebra::UnitQuaternion::identity(), nalgebra::Vector3::new(0.0, -0.3, 0.8));
        push(9.0 + 0.1 * f64::from(k), held);
    }
    let file = dir.join("border.jsonl");
    std::fs::write(&file, lines.join("\n") + "\n").expect("write");
    file
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

#[test]
fn the_programmed_guidance_is_read_back() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path());
    let out =
        ok(&jawtrack(&["articulator", s(&rec), "--protrusion", "0:2", "--left", "3:5", "--right", "6:8", "--json"]));
    let v: Value = serde_json::from_str(&out).expect("one JSON object");
    let g = GUIDANCE;
    for condyle in ["left_condyle", "right_condyle"] {
        let c = &v[condyle];
        assert!((num(&c["condylar_inclination_deg"]) - g.condylar_inclination_deg).abs() < TOL, "{v}");
        assert!((num(&c["bennett_deg"]) - g.bennett_deg).abs() < TOL, "{v}");
        assert!((num(&c["immediate_side_shift_mm"]) - g.side_shift_mm).abs() < TOL, "{v}");
    }
    assert!((num(&v["protrusive_incisal_guidance_deg"]) - g.protrusive_guidance_deg).abs() < TOL, "{v}");
    for side in ["toward_left", "toward_right"] {
        assert!((num(&v["lateral_incisal_guidance_deg"][side]) - g.lateral_guidance_deg).abs() < TOL, "{v}");
    }
    assert_eq!(v["read_over_mm"], 5.0);
    // The summary, in words.
    let text = ok(&jawtrack(&["articulator", s(&rec), "--protrusion", "0:2", "--left", "3:5"]));
    assert!(text.contains("condylar inclination") && text.contains("36.0°"), "{text}");
    // Without --right, the left condyle's Bennett angle is unknown, not zero.
    assert!(text.lines().any(|l| l.starts_with("Bennett angle") && l.contains('—') && l.contains("11.0°")), "{text}");
}

#[test]
fn missing_or_short_movements_are_refused_naming_them() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path());
    refused(&jawtrack(&["articulator", s(&rec)]), "at least one movement");
    refused(&jawtrack(&["articulator", s(&rec), "--protrusion", "2:1"]), "FROM must be before TO");
    refused(&jawtrack(&["articulator", s(&rec), "--protrusion", "20:30"]), "no frame");
    // The first 0.2 s of the protrusion: 0.8 mm of travel, under the 5 mm the values are read over.
    refused(&jawtrack(&["articulator", s(&rec), "--protrusion", "0:0.2"]), "protrusive path");
}

#[test]
fn a_recording_tracked_with_the_nominal_marker_is_warned_about() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path());
    let text = std::fs::read_to_string(&rec).expect("read");
    let (_, frames) = text.split_once('\n').expect("a header line");
    let mut header = jawtrack_recording::RecordingHeader::new("articulator test");
    let nominal = jawtrack_marker::Marker::default().to_json();
    header.marker = Some(serde_json::from_str(&nominal).expect("marker JSON"));
    let tracked = dir.path().join("nominal.jsonl");
    std::fs::write(&tracked, format!("{}\n{frames}", header.to_line())).expect("write");
    let o = jawtrack(&["articulator", s(&tracked), "--protrusion", "0:2"]);
    ok(&o);
    let e = common::stderr(&o);
    assert!(e.contains("nominal marker") && e.contains("calibrate-marker"), "{e}");
    let o = jawtrack(&["hinge-axis", s(&tracked), "--to", "2"]);
    assert!(common::stderr(&o).contains("nominal marker"), "{}", common::stderr(&o));
    // The programmed recording's header names no marker: no warning.
    assert!(!common::stderr(&jawtrack(&["articulator", s(&rec), "--protrusion", "0:2"])).contains("nominal"));
}

/// A points file whose occlusal plane is the standard head frame's horizontal turned by
/// `tilt_deg` about the transverse axis, with the rig's own condyles and incisal point, and a
/// registration placing the upper scan at an arbitrary pose on the maxilla marker.
fn tilted_anatomy(dir: &Path, tilt_deg: f64) -> (PathBuf, PathBuf, nalgebra::UnitQuaternion<f64>) {
    use nalgebra::{Point3, UnitQuaternion, Vector3};
    let m = Rig::default().mounting;
    let tilt = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), tilt_deg.to_radians());
    let scan_from_head = Pose::from_axis_angle(Vector3::new(0.2, 0.9, -0.3), Vector3::new(5.0, 30.0, -12.0));
    let at = |h: Vector3<f64>| {
        let p = scan_from_head.transform_point(&Point3::from(h));
        format!("{},{},{}", p.x, p.y, p.z)
    };
    let file = dir.join("points.json");
    ok(&jawtrack(&[
        "points",
        "--occlusal",
        &[at(Vector3::zeros()), at(tilt * Vector3::new(25.0, 0.0, 35.0)), at(tilt * Vector3::new(-25.0, 0.0, 35.0))]
            .join(","),
        "--lower-incisal",
        &at(m.lower_incisal_point),
        "--condyles",
        &format!("{},{}", at(m.condyles[0]), at(m.condyles[1])),
        "--out",
        s(&file),
    ]));
    let reg = jawtrack_registration::Registration {
        maxilla_scan_from_maxilla_marker: scan_from_head * m.head_from_maxilla,
        ..jawtrack_registration::Registration::identity()
    };
    let reg_file = dir.join("registration.json");
    std::fs::write(&reg_file, reg.to_json()).expect("write");
    (file, reg_file, tilt)
}

#[test]
fn with_a_points_file_angles_are_to_its_occlusal_plane() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path());
    let (points, reg, tilt) = tilted_anatomy(dir.path(), 10.0);
    let out = ok(&jawtrack(&[
        "articulator",
        s(&rec),
        "--protrusion",
        "0:2",
        "--points",
        s(&points),
        "--registration",
        s(&reg),
        "--json",
    ]));
    let v: Value = serde_json::from_str(&out).expect("one JSON object");
    // A straight path forward (−Z) and down (+Y) at `deg` in the head frame, read in the tilted
    // frame: its angle below that frame's horizontal.
    let in_tilted = |deg: f64| {
        let r = deg.to_radians();
        let d = tilt.inverse() * nalgebra::Vector3::new(0.0, r.sin(), -r.cos());
        d.y.atan2(-d.z).to_degrees()
    };
    let g = GUIDANCE;
    let want = in_tilted(g.condylar_inclination_deg);
    assert!((want - g.condylar_inclination_deg).abs() > 9.0, "the tilt must show: {want}");
    for condyle in ["left_condyle", "right_condyle"] {
        assert!((num(&v[condyle]["condylar_inclination_deg"]) - want).abs() < TOL, "{want}: {v}");
    }
    let want = in_tilted(g.protrusive_guidance_deg);
    assert!((num(&v["protrusive_incisal_guidance_deg"]) - want).abs() < TOL, "{want}: {v}");
    assert_eq!(v["reference_plane"], "the occlusal plane of the points file", "{v}");
    // The points need the registration that places them.
    refused(&jawtrack(&["articulator", s(&rec), "--protrusion", "0:2", "--points", s(&points)]), "--registration");
}

#[test]
fn the_co_mi_slide_is_the_held_offset() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path());
    let v: Value =
        serde_json::from_str(&ok(&jawtrack(&["articulator", s(&rec), "--co", "9:9.5", "--json"]))).expect("JSON");
    for point in ["lower_incisal_point", "left_condyle", "right_condyle"] {
        let d = &v["co_mi"][point];
        assert!((num(&d["forward_mm"]) - 0.8).abs() < TOL && (num(&d["down_mm"]) - 0.3).abs() < TOL, "{v}");
        assert!(num(&d["toward_left_mm"]).abs() < TOL && (num(&d["length_mm"]) - 0.8f64.hypot(0.3)).abs() < TOL);
    }
    let text = ok(&jawtrack(&["articulator", s(&rec), "--co", "9:9.5"]));
    assert!(text.contains("CO–MI slide") && text.contains("0.85"), "{text}");
    refused(&jawtrack(&["articulator", s(&rec), "--mi", "0:0.1"]), "--co");
}

#[test]
fn a_points_file_reaches_every_measure_of_the_incisor() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path());
    let (points, reg, _) = tilted_anatomy(dir.path(), 10.0);
    let anatomy = ["--points", s(&points), "--registration", s(&reg)];
    let with = |args: &[&str]| -> Vec<String> { args.iter().chain(&anatomy).map(|a| (*a).to_owned()).collect() };
    let run = |args: Vec<String>| ok(&jawtrack(&args.iter().map(String::as_str).collect::<Vec<_>>()));
    let opening = |v: &Value| num(&v["max_opening"]["mm"]);
    let metrics: Value = serde_json::from_str(&run(with(&["metrics", s(&rec), "--json"]))).expect("JSON");
    let standard: Value = serde_json::from_str(&ok(&jawtrack(&["metrics", s(&rec), "--json"]))).expect("JSON");
    // The tilted occlusal plane changes what "down" is: the points file must show.
    assert!((opening(&metrics) - opening(&standard)).abs() > 0.05, "{} vs {}", opening(&metrics), opening(&standard));
    assert_eq!(metrics["incisor_standard"], false);
    // The CSV's largest opening_mm, with the same flags.
    let csv = run(with(&["export", s(&rec), "--csv"]));
    let mut lines = csv.lines();
    let column = lines.next().expect("header").split(',').position(|c| c == "opening_mm").expect("opening_mm");
    let widest = lines
        .filter_map(|l| l.split(',').nth(column).and_then(|v| v.parse::<f64>().ok()))
        .fold(f64::NEG_INFINITY, f64::max);
    assert!((widest - opening(&metrics)).abs() < 1e-8, "CSV {widest} vs metrics {}", opening(&metrics));
    // plot prints the same widest opening.
    let plots = dir.path().join("plots");
    let o = jawtrack(&with(&["plot", s(&rec), "--out", s(&plots)]).iter().map(String::as_str).collect::<Vec<_>>());
    let said = common::stderr(&o);
    assert!(said.contains(&format!("widest opening {:.1} mm", opening(&metrics))), "{said}");
    // Without the registration the points cannot be placed.
    refused(&jawtrack(&["metrics", s(&rec), "--points", s(&points)]), "--registration");
}

#[test]
fn held_positions_and_options_are_checked_before_anything_is_measured() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rec = session(dir.path());
    // The protrusion moves: it is no held position, so no CO–MI slide is read from it.
    refused(&jawtrack(&["articulator", s(&rec), "--co", "0:2"]), "the jaw is not held still in that window");
    refused(&jawtrack(&["articulator", s(&rec), "--co", "NaN:1"]), "'NaN' in 'NaN:1' is not a number of seconds");
    refused(&jawtrack(&["metrics", s(&rec), "--rest-frame=-1"]), "a whole number, 0 or more");
    refused(&jawtrack(&["metrics", s(&rec), "--rest-frame", "-1"]), "a whole number, 0 or more");
    refused(&jawtrack(&["hinge-axis", s(&rec), "--max-rotation-deg", "-5"]), "expected a positive angle in degrees");
    refused(&jawtrack(&["metrics", s(&rec), "--incisor", "0,-20.5,-39000"]), "39000 mm from the mandible marker");
}
