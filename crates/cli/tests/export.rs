//! `jawtrack export` and `jawtrack plot` on a tracked hinge fixture and on a received
//! recording written out of order.

use std::path::Path;
use std::process::Output;
mod common;
use common::{jawtrack, ok};

fn tracked_hinge(dir: &Path) -> String {
    let out = dir.join("hinge.jsonl").to_str().expect("utf-8").to_owned();
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/hinge-1080p");
    ok(&jawtrack(&["track", "--intrinsics", "1500,1500,959.5,539.5", "--out", &out, set]));
    out
}

#[test]
fn csv_export_gives_the_incisor_opening_per_frame() {
    let dir = tempfile::tempdir().expect("temp dir");
    let poses = tracked_hinge(dir.path());
    let text = ok(&jawtrack(&["export", &poses, "--csv"]));
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let headers = reader.headers().expect("header row").clone();
    let col = |name: &str| headers.iter().position(|h| h == name).unwrap_or_else(|| panic!("column {name}"));
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
    assert_eq!(rows.len(), 5);
    let opening = |rows: &[csv::StringRecord]| -> Vec<f64> {
        rows.iter().map(|r| r[col("opening_mm")].parse().expect("a number")).collect()
    };
    let tracked = opening(&rows);
    assert_eq!(tracked[0], 0.0, "measured from the first frame");
    // The same export of the fixture's true poses: the tracked opening follows it.
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/hinge-1080p/ground_truth.json"))
            .expect("truth"),
    )
    .expect("json");
    let lines: Vec<String> = truth["frames"]
        .as_array()
        .expect("frames")
        .iter()
        .enumerate()
        .map(|(i, f)| {
            serde_json::json!({"frame": i, "t": f["t"], "maxilla": null, "mandible": null,
                "maxilla_from_mandible": f["maxilla_from_mandible"]})
            .to_string()
        })
        .collect();
    let truth_file = dir.path().join("truth.jsonl");
    std::fs::write(&truth_file, lines.join("\n")).expect("write");
    let text = ok(&jawtrack(&["export", truth_file.to_str().expect("utf-8"), "--csv"]));
    let rows: Vec<csv::StringRecord> =
        csv::Reader::from_reader(text.as_bytes()).records().map(|r| r.expect("row")).collect();
    let real = opening(&rows);
    assert!(real.iter().any(|&o| o > 2.0), "the fixture opens the jaw: {real:?}");
    for (t, r) in tracked.iter().zip(&real) {
        assert!((t - r).abs() < 0.3, "tracked {tracked:?} vs true {real:?} (nominal marker: within 0.3 mm)");
    }
}

#[test]
fn jsonl_export_puts_received_frames_back_in_sequence_order() {
    let dir = tempfile::tempdir().expect("temp dir");
    let poses = tracked_hinge(dir.path());
    let text = std::fs::read_to_string(&poses).expect("poses");
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    // As a receiver writes them: seq numbers, arrival order 0 2 1 4 3, one line cut short.
    for (k, line) in lines.iter_mut().enumerate().skip(1) {
        let mut v: serde_json::Value = serde_json::from_str(line).expect("json");
        v["seq"] = (k - 1).into();
        *line = v.to_string();
    }
    lines.swap(2, 3);
    lines.swap(4, 5);
    lines.push("{\"frame\": 9, \"t\": 0.".into());
    let shuffled = dir.path().join("shuffled.jsonl");
    std::fs::write(&shuffled, lines.join("\n")).expect("write");
    let o = jawtrack(&["export", shuffled.to_str().expect("utf-8"), "--jsonl"]);
    let out = ok(&o);
    assert!(String::from_utf8_lossy(&o.stderr).contains("line 7 skipped"), "the cut line is named");
    let seqs: Vec<u64> = out
        .lines()
        .skip(1)
        .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("json")["seq"].as_u64().expect("seq"))
        .collect();
    assert_eq!(seqs, vec![0, 1, 2, 3, 4]);
    assert!(out.lines().next().is_some_and(|h| h.contains("\"recording\"")));
}

#[test]
fn plot_writes_the_three_planes_and_the_opening_as_svg_and_png() {
    let dir = tempfile::tempdir().expect("temp dir");
    let poses = tracked_hinge(dir.path());
    let plots = dir.path().join("plots");
    let listed = ok(&jawtrack(&["plot", &poses, "--out", plots.to_str().expect("utf-8")]));
    for stem in ["incisor_sagittal", "incisor_frontal", "incisor_transverse", "incisor_opening"] {
        for ext in ["svg", "png"] {
            let p = plots.join(format!("{stem}.{ext}"));
            assert!(listed.contains(p.to_str().expect("utf-8")), "{stem}.{ext} listed");
            assert!(std::fs::metadata(&p).is_ok_and(|m| m.len() > 1000), "{} written", p.display());
        }
    }
}

#[test]
fn export_and_plot_refuse_what_they_cannot_use() {
    let dir = tempfile::tempdir().expect("temp dir");
    let empty = dir.path().join("empty.jsonl");
    std::fs::write(&empty, "{\"frame\":0,\"t\":0,\"maxilla\":null,\"mandible\":null,\"maxilla_from_mandible\":null}\n")
        .expect("write");
    let check = |o: Output, needle: &str| {
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success() && e.contains(needle) && !e.contains("panicked"), "wanted '{needle}': {e}");
    };
    let plots = dir.path().join("plots");
    check(
        jawtrack(&["plot", empty.to_str().expect("utf-8"), "--out", plots.to_str().expect("utf-8")]),
        "no frame has a jaw pose",
    );
    check(jawtrack(&["export", "/nonexistent.jsonl", "--csv"]), "/nonexistent.jsonl");
    check(jawtrack(&["export", empty.to_str().expect("utf-8")]), "--csv");
    check(jawtrack(&["export", empty.to_str().expect("utf-8"), "--csv", "--rest-frame", "4"]), "no such frame");

    // Not a recording, an empty file, and a pose that cannot be: refused, not "exported 0 frames"
    // or a NaN opening.
    let foreign = dir.path().join("notes.jsonl");
    std::fs::write(&foreign, (0..50).map(|i| format!("{{\"note\": {i}}}\n")).collect::<String>()).expect("write");
    let o = jawtrack(&["export", foreign.to_str().expect("utf-8"), "--csv"]);
    check(
        jawtrack(&["export", foreign.to_str().expect("utf-8"), "--csv"]),
        "has no frames that could be read (50 lines skipped)",
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("40 more lines"), "the warnings are capped");
    let blank = dir.path().join("blank.jsonl");
    std::fs::write(&blank, "").expect("write");
    check(jawtrack(&["export", blank.to_str().expect("utf-8"), "--csv"]), "has no frames that could be read");
    let absurd = dir.path().join("absurd.jsonl");
    let identity = |t: &str| format!("[1,0,0,{t},0,1,0,0,0,0,1,0,0,0,0,1]");
    std::fs::write(
        &absurd,
        format!(
            "{{\"frame\":0,\"t\":0,\"maxilla\":null,\"mandible\":null,\"maxilla_from_mandible\":{}}}\n",
            identity("1e308")
        ),
    )
    .expect("write");
    for command in ["export", "metrics"] {
        let o =
            jawtrack(&[command, absurd.to_str().expect("utf-8"), "--csv"][..if command == "export" { 3 } else { 2 }]);
        check(o, "has no frames that could be read");
    }
    let o = jawtrack(&["metrics", absurd.to_str().expect("utf-8")]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("implausible pose"), "says why the line was skipped");

    // A refused export leaves no file, so the rerun is not blocked by "already exists".
    for (flag, needle) in [
        ("--transforms-csv", "registration"),
        ("--transforms-json", "registration"),
        ("--trc", "no frame has a jaw pose"),
        ("--mot", "no frame has a jaw pose"),
        ("--c3d", "no frame has a jaw pose"),
    ] {
        let out = dir.path().join(format!("failed{flag}"));
        check(
            jawtrack(&["export", empty.to_str().expect("utf-8"), flag, "--out", out.to_str().expect("utf-8")]),
            needle,
        );
        assert!(!out.exists(), "{flag}: a failed export left {}", out.display());
    }
}

#[test]
fn two_sessions_in_one_file_are_never_mixed() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("received.jsonl");
    let pose = |y: f64| format!("[1,0,0,0,0,1,0,{y},0,0,1,0,0,0,0,1]");
    let line = |session: &str, frame: u32, y: f64| {
        format!(
            "{{\"frame\":{frame},\"session\":\"{session}\",\"t\":{frame},\"maxilla\":null,\"mandible\":null,\"maxilla_from_mandible\":{}}}\n",
            pose(y)
        )
    };
    let (a, b) = ("00000000000000aa", "00000000000000bb");
    let text = [line(a, 0, 40.0), line(b, 0, 10.0), line(a, 1, 45.0), line(b, 1, 12.0), line(a, 2, 50.0)].concat();
    std::fs::write(&file, text).expect("write");
    let file = file.to_str().expect("utf-8");
    let check = |o: Output, needle: &str| {
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success() && e.contains(needle) && !e.contains("panicked"), "wanted '{needle}': {e}");
    };
    for command in [&["metrics", file][..], &["export", file, "--csv"], &["plot", file, "--out", "/tmp/never"]] {
        check(jawtrack(command), "holds 2 sessions");
    }
    let one = ok(&jawtrack(&["export", file, "--session", a, "--jsonl"]));
    let frames: Vec<serde_json::Value> = one
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("json"))
        .filter(|v| v.get("frame").is_some())
        .collect();
    assert_eq!(frames.len(), 3, "session aa's three frames");
    assert!(frames.iter().all(|f| f["session"] == a));
    assert!(jawtrack(&["metrics", file, "--session", b]).status.success());
    check(jawtrack(&["metrics", file, "--session", "00000000000000cc"]), "no frame of session 00000000000000cc");
    check(jawtrack(&["metrics", file, "--session", "xyz"]), "16 hex digits");
}

#[test]
fn transforms_for_cad_are_the_lower_scan_in_the_upper_scan_s_frame() {
    use jawtrack_pose::Pose;
    use jawtrack_registration::Registration;
    use nalgebra::Vector3;
    let dir = tempfile::tempdir().expect("temp dir");
    let poses = tracked_hinge(dir.path());
    let registration = Registration {
        maxilla_scan_from_maxilla_marker: Pose::from_axis_angle(
            Vector3::new(0.1, -0.2, 0.3),
            Vector3::new(4.0, -38.0, 9.0),
        ),
        mandible_scan_from_mandible_marker: Pose::from_axis_angle(
            Vector3::new(0.0, 0.2, -0.1),
            Vector3::new(-2.0, 40.0, 7.0),
        ),
        ..Registration::identity()
    };
    let reg = dir.path().join("reg.json");
    std::fs::write(&reg, registration.to_json()).expect("write");
    let reg = reg.to_str().expect("utf-8");
    let recording = jawtrack_recording::open(Path::new(&poses)).expect("reads");
    let want: Vec<[f64; 16]> = recording
        .frames
        .iter()
        .filter_map(|f| Some(registration.maxilla_scan_from_mandible_scan(&f.maxilla_from_mandible?).to_row_major()))
        .collect();
    assert_eq!(want.len(), 5);
    let text = ok(&jawtrack(&["export", &poses, "--transforms-csv", "--registration", reg]));
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let headers: Vec<String> = reader.headers().expect("header").iter().map(str::to_owned).collect();
    assert_eq!(headers[..3], ["frame", "t_s", "m00"]);
    assert_eq!(headers.last().map(String::as_str), Some("m33"));
    let rows: Vec<Vec<f64>> = reader
        .records()
        .map(|r| r.expect("row").iter().skip(2).map(|v| v.parse().expect("a number")).collect())
        .collect();
    assert_eq!(rows.len(), want.len());
    for (row, w) in rows.iter().zip(&want) {
        assert!(row.iter().zip(w).all(|(a, b)| (a - b).abs() < 1e-9), "{row:?} vs {w:?}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&ok(&jawtrack(&["export", &poses, "--transforms-json", "--registration", reg])))
            .expect("one JSON object");
    assert_eq!(json["units"], "mm");
    assert_eq!(json["layout"], "row-major 4x4");
    let first: Vec<f64> =
        json["frames"][0]["matrix"].as_array().expect("16").iter().map(|v| v.as_f64().expect("num")).collect();
    assert!(first.iter().zip(&want[0]).all(|(a, b)| (a - b).abs() < 1e-9));
    // Tracked without a registration, and none given: refused, saying what to give.
    let o = jawtrack(&["export", &poses, "--transforms-csv"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("--registration"), "{e}");
}

#[test]
fn opensim_files_carry_every_frame_in_opensim_s_axes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let poses = tracked_hinge(dir.path());
    let trc = ok(&jawtrack(&["export", &poses, "--trc"]));
    let lines: Vec<&str> = trc.lines().collect();
    assert!(lines[0].starts_with("PathFileType\t4\t(X/Y/Z)\thinge.jsonl"), "{}", lines[0]);
    let rate_row: Vec<&str> = lines[2].split('\t').collect();
    assert_eq!((rate_row[2], rate_row[3], rate_row[4]), ("5", "3", "mm"), "{}", lines[2]);
    assert_eq!(lines.len(), 5 + 5);
    let mot = ok(&jawtrack(&["export", &poses, "--mot"]));
    assert!(mot.contains("nRows=5\nnColumns=7\ninDegrees=yes\nendheader\ntime\tjaw_rx"), "{mot}");
    // The hinge fixture opens the jaw: its turn is about OpenSim's Z (the patient's right),
    // chin down being negative, and exceeds the other two.
    let rows: Vec<Vec<f64>> =
        mot.lines().skip(7).map(|l| l.split('\t').map(|v| v.parse().expect("a number")).collect()).collect();
    let widest = rows.iter().max_by(|a, b| a[3].abs().total_cmp(&b[3].abs())).expect("rows");
    assert!(widest[3] < -5.0 && widest[1].abs() < 1.0 && widest[2].abs() < 1.0, "{widest:?}");
    // The patient's points need the registration that places them.
    let o = jawtrack(&["export", &poses, "--trc", "--points", "points.json"]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--registration"));

    // C3D: the .trc's points, frames and rate (crates/c3d/tests checks the format against
    // ezc3d and py-c3d; here, that export fills it with the .trc's numbers).
    let file = dir.path().join("hinge.c3d");
    ok(&jawtrack(&["export", &poses, "--c3d", "--out", file.to_str().expect("utf-8")]));
    let c3d = std::fs::read(&file).expect("the C3D file");
    let word = |at: usize| u16::from_le_bytes([c3d[at], c3d[at + 1]]);
    let float = |at: usize| f32::from_le_bytes([c3d[at], c3d[at + 1], c3d[at + 2], c3d[at + 3]]);
    assert_eq!((c3d[1], word(2), word(6), word(8)), (0x50, 3, 1, 5), "key, points, first and last frame");
    let rate: f64 = rate_row[0].parse().expect("the .trc's rate");
    assert!(float(12) < 0.0 && (f64::from(float(20)) - rate).abs() < 1e-3, "float storage at {rate} frames/s");
    let data = (usize::from(word(16)) - 1) * 512;
    for (frame, line) in lines[5..].iter().enumerate() {
        let want: Vec<f64> = line.split('\t').skip(2).map(|v| v.parse().expect("a number")).collect();
        assert_eq!(want.len(), 9, "{line}");
        for (k, w) in want.iter().enumerate() {
            let got = float(data + frame * 3 * 16 + (k / 3) * 16 + (k % 3) * 4);
            assert!((f64::from(got) - w).abs() < 1e-3, "frame {frame}, value {k}: C3D {got}, .trc {w}");
        }
    }
}
