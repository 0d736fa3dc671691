//! `jawtrack calibrate-marker` and `jawtrack track --refine-marker` as a user runs them: the
//! marker calibrated from a rendered recording of the fixtures' printed marker, then tags its
//! calibration left nominal placed from a session, each judged by the jaw error against the
//! fixtures' truth.

use std::path::Path;
mod common;
use common::{jawtrack, ok, refused, s, stderr};

/// Mean (translation mm, rotation °) error of `jawtrack track`'s jaw poses against a fixture's truth.
fn jaw_error(poses: &Path, set: &Path) -> (f64, f64) {
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(set.join("ground_truth.json")).expect("truth")).expect("json");
    let (mut dt, mut dr, mut n) = (0.0, 0.0, 0.0);
    for (line, f) in
        std::fs::read_to_string(poses).expect("poses").lines().skip(1).zip(truth["frames"].as_array().expect("frames"))
    {
        let line: serde_json::Value = serde_json::from_str(line).expect("json line");
        let m: [f64; 16] = serde_json::from_value(line["maxilla_from_mandible"].clone()).expect("a jaw pose");
        let t: [f64; 16] = serde_json::from_value(f["maxilla_from_mandible"].clone()).expect("truth");
        let (a, b) = (nalgebra::Matrix4::from_row_slice(&m), nalgebra::Matrix4::from_row_slice(&t));
        dt += (a.fixed_view::<3, 1>(0, 3) - b.fixed_view::<3, 1>(0, 3)).norm();
        let r = a.fixed_view::<3, 3>(0, 0).transpose() * b.fixed_view::<3, 3>(0, 0);
        dr += ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
        n += 1.0;
    }
    (dt / n, dr / n)
}

#[test]
fn calibrating_the_marker_from_a_turned_recording_restores_the_accuracy() {
    let dir = tempfile::tempdir().expect("temp dir");
    let frames = dir.path().join("calibration");
    let frames = frames.to_str().expect("utf-8");
    // The calibration recording of the same printed marker as the fixtures (seed 7).
    let o = jawtrack(&["synth", "--scene", "calibration", "--seed", "7", "--frames-per-view", "1", "--out", frames]);
    assert!(o.status.success(), "{}", stderr(&o));
    let calibrated = dir.path().join("calibrated.json");
    let calibrated = calibrated.to_str().expect("utf-8");
    let intrinsics = "1500,1500,959.5,539.5";
    let o = jawtrack(&["calibrate-marker", "--intrinsics", intrinsics, "--out", calibrated, frames]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = String::from_utf8_lossy(&o.stdout);
    // 18 frames; one view's sightings miss by far more than the others' and are left out.
    assert!(report.contains("maxilla: 17 views") && report.contains("px calibrated"), "{report}");
    // Faces turned toward the patient are never seen: named, kept nominal.
    assert!(stderr(&o).contains("warning: tag 9 was seen in 0 usable view(s)"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("check --intrinsics"), "the right intrinsics pass: {}", stderr(&o));
    let o = jawtrack(&["check-marker", calibrated]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The file says what it was calibrated from, and that tag 9 was left nominal.
    let listed = String::from_utf8_lossy(&o.stdout);
    assert!(listed.contains(&format!("views of {frames}:")), "{listed}");
    assert!(listed.contains("     9  nominal         0"), "{listed}");
    // Twice the focal length: the calibration says so, and names the factor that fits.
    let doubled = "3000,3000,959.5,539.5";
    let wrong = dir.path().join("wrong.json");
    let o = jawtrack(&["calibrate-marker", "--intrinsics", doubled, "--out", wrong.to_str().expect("utf-8"), frames]);
    assert!(stderr(&o).contains("check --intrinsics") && stderr(&o).contains("0.5"), "{}", stderr(&o));

    let set = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p"));
    let track = |marker: Option<&str>, out: &Path, intrinsics: &str| {
        let mut args = vec!["track", "--intrinsics", intrinsics, "--out", out.to_str().expect("utf-8")];
        if let Some(m) = marker {
            args.extend(["--marker", m]);
        }
        args.push(set.to_str().expect("utf-8"));
        let o = jawtrack(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    let (nominal, with_cal) = (dir.path().join("nominal.jsonl"), dir.path().join("calibrated.jsonl"));
    assert!(!track(None, &nominal, intrinsics).contains("check --intrinsics"));
    assert!(!track(Some(calibrated), &with_cal, intrinsics).contains("check --intrinsics"));
    // Tracking with the wrong focal length is warned of before any tag is blamed.
    let said = track(Some(calibrated), &dir.path().join("wrong.jsonl"), doubled);
    assert!(said.contains("warning: check --intrinsics"), "{said}");
    let (before, after) = (jaw_error(&nominal, set), jaw_error(&with_cal, set));
    eprintln!("static fixture, mandible in maxilla: nominal {before:.3?}, calibrated {after:.3?} (mm, °)");
    // Measured: 0.29 mm / 0.83° nominal, 0.025 mm / 0.049° calibrated.
    assert!(after.0 < before.0 / 4.0 && after.1 < before.1 / 4.0, "{before:?} → {after:?}");
    assert!(after.0 < 0.07 && after.1 < 0.15, "{after:?}");

    // Tags 2 and 13, which every fixture frame shows, put back to their nominal place as if
    // the calibration had never seen them; a session (the calibration recording, tracked)
    // places them again, and the fixture is judged with the refined marker.
    let holes = dir.path().join("holes.json");
    unplace(Path::new(calibrated), &[2, 13], &holes);
    let (with_holes, refined_poses) = (dir.path().join("holes.jsonl"), dir.path().join("refined.jsonl"));
    let said = track(Some(s(&holes)), &with_holes, intrinsics);
    assert!(said.contains("rest on nominal tag 2") && said.contains("--refine-marker"), "{said}");
    let refined = dir.path().join("refined.json");
    let args = ["track", "--intrinsics", intrinsics, "--marker", s(&holes), "--refine-marker", s(&refined)];
    let run = |extra: &[&str]| jawtrack(&[&args[..], &["--out", s(&refined_poses), frames], extra].concat());
    let o = run(&[]);
    let report = ok(&o);
    assert_eq!(placed(&report), [2, 13], "{report}");
    let listed = ok(&jawtrack(&["check-marker", s(&refined)]));
    assert!(!listed.contains("      2  nominal") && !listed.contains("     13  nominal"), "{listed}");
    // The recording was tracked with the refined marker and says so in its header.
    let header: serde_json::Value =
        serde_json::from_str(std::fs::read_to_string(&refined_poses).expect("poses").lines().next().expect("a header"))
            .expect("json");
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&refined).expect("marker")).expect("json");
    assert!(header["recording"]["marker"] == written, "the header's marker is the refined one");
    let refilled_poses = dir.path().join("refilled.jsonl");
    track(Some(s(&refined)), &refilled_poses, intrinsics);
    let (holed, refilled) = (jaw_error(&with_holes, set), jaw_error(&refilled_poses, set));
    eprintln!("static fixture: tags 2, 13 nominal {holed:.3?}, placed by the session {refilled:.3?} (mm, °)");
    assert!(refilled.0 < holed.0 && refilled.1 < holed.1, "{holed:?} → {refilled:?}");
    assert!(refilled.0 < after.0 + 0.02 && refilled.1 < after.1 + 0.03, "{after:?} vs {refilled:?}");
    // A recording written to standard output stays a recording: the report goes to stderr.
    let piped = dir.path().join("piped.json");
    let o =
        jawtrack(&[&args[..3], &["--marker", s(&holes), "--refine-marker", s(&piped), "--out", "-", frames]].concat());
    let stdout = ok(&o);
    let lines: Vec<serde_json::Value> =
        stdout.lines().map(|l| serde_json::from_str(l).expect("every line of the recording is JSON")).collect();
    assert!(lines[0]["recording"].is_object() && lines.len() > 10, "{stdout}");
    assert_eq!(placed(&stderr(&o)), [2, 13], "{}", stderr(&o));
    // Neither output is overwritten unless asked.
    refused(&run(&[]), "already exists");
    assert!(run(&["--force"]).status.success());
    // `calibrate-marker` given a calibrated marker refines it the same way from any frames.
    let again = dir.path().join("again.json");
    let o =
        jawtrack(&["calibrate-marker", "--intrinsics", intrinsics, "--marker", s(&holes), "--out", s(&again), frames]);
    let report = ok(&o);
    assert_eq!(placed(&report), [2, 13], "{report}");
    assert!(report.contains("tags calibrated before kept as they were"), "{report}");
    let (a, b) = (std::fs::read_to_string(&refined).expect("marker"), std::fs::read_to_string(&again).expect("marker"));
    let tags = |text: &str| -> Vec<serde_json::Value> {
        let v: serde_json::Value = serde_json::from_str(text).expect("json");
        v["bodies"]
            .as_array()
            .expect("bodies")
            .iter()
            .flat_map(|b| b["tags"].as_array().expect("tags").clone())
            .collect()
    };
    // The same tags placed, and every other tag left exactly as it was in the input.
    let holed = tags(&std::fs::read_to_string(&holes).expect("marker"));
    for ((x, y), h) in tags(&a).iter().zip(tags(&b)).zip(&holed) {
        if x["id"] == 2 || x["id"] == 13 {
            assert_ne!(y["corners"], h["corners"], "tag {} placed", x["id"]);
        } else {
            assert_eq!(y["corners"], h["corners"], "tag {} kept", x["id"]);
            assert_eq!(x["corners"], h["corners"], "tag {} kept", x["id"]);
        }
    }
}

/// The tags a refinement's report lists as placed: the first column of its tables' rows.
fn placed(report: &str) -> Vec<u32> {
    let mut ids: Vec<u32> = report
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("placed"))
        .filter(|l| l.split_whitespace().count() == 7)
        .filter_map(|l| l.split_whitespace().next()?.parse().ok())
        .collect();
    ids.sort_unstable();
    ids
}

/// Writes `calibrated` with the tags `ids` put back at their nominal place, marked nominal.
fn unplace(calibrated: &Path, ids: &[u64], out: &Path) {
    let dir = tempfile::tempdir().expect("temp dir");
    let nominal_path = dir.path().join("nominal.json");
    assert!(jawtrack(&["marker", "--out", s(&nominal_path)]).status.success());
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).expect("marker")).expect("json")
    };
    let (mut m, nominal) = (read(calibrated), read(&nominal_path));
    let nominal_tag = |id: u64| {
        nominal["bodies"]
            .as_array()
            .expect("bodies")
            .iter()
            .flat_map(|b| b["tags"].as_array().expect("tags"))
            .find(|t| t["id"] == id)
    };
    for body in m["bodies"].as_array_mut().expect("bodies") {
        for tag in body["tags"].as_array_mut().expect("tags") {
            let id = tag["id"].as_u64().expect("id");
            if ids.contains(&id) {
                let n = nominal_tag(id).expect("nominal tag");
                tag["corners"] = n["corners"].clone();
                tag["center"] = n["center"].clone();
                tag["calibration"] = serde_json::json!({"status": "nominal", "views": 0});
            }
        }
    }
    std::fs::write(out, m.to_string()).expect("written");
}
