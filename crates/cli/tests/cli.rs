//! The `jawtrack` binary as a user runs it: outputs written, bad input refused with a message
//! that says what was wrong, never a panic.

use std::path::Path;
use std::process::{Command, Output};

fn jawtrack(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_jawtrack")).args(args).output().expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn refused(o: &Output, needle: &str) {
    assert!(!o.status.success(), "should fail");
    let e = stderr(o);
    assert!(e.contains(needle), "stderr lacks '{needle}': {e}");
    assert!(!e.contains("panicked"), "panicked: {e}");
}

#[test]
fn marker_writes_a_valid_file_with_the_computed_tag_size() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("m.json");
    let p = path.to_str().expect("utf-8 path");
    let o = jawtrack(&["marker", "--out", p]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("tag size 10.6145 mm"));
    let o = jawtrack(&["check-marker", p]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("maxilla: 12 tags"));
}

#[test]
fn impossible_marker_parameters_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let p = dir.path().join("m.json");
    let p = p.to_str().expect("utf-8 path");
    refused(&jawtrack(&["marker", "--out", p, "--tag-size", "30"]), "larger than its face");
    refused(&jawtrack(&["marker", "--out", p, "--edge", "-2"]), "edge length must be a positive");
}

#[test]
fn a_broken_marker_file_is_named() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("m.json");
    let p = path.to_str().expect("utf-8 path");
    assert!(jawtrack(&["marker", "--out", p]).status.success());
    let text = std::fs::read_to_string(&path).expect("written");
    let broken = text.replacen("\"id\": 5,", "\"id\": 4,", 1);
    std::fs::write(&path, broken).expect("rewritten");
    refused(&jawtrack(&["check-marker", p]), "duplicate id 4");
    refused(&jawtrack(&["check-marker", "/nonexistent/marker.json"]), "/nonexistent/marker.json");
}

#[test]
fn synth_renders_a_scene_and_refuses_bad_settings() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("s");
    let o = jawtrack(&[
        "synth",
        "--scene",
        "excursion",
        "--clean",
        "--max-frames",
        "2",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("frame_0001.png").is_file() && out.join("ground_truth.json").is_file());
    let gt: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("ground_truth.json")).expect("truth")).expect("json");
    assert_eq!(gt["frames"].as_array().map(Vec::len), Some(2));

    refused(&jawtrack(&["synth", "--scene", "yawn", "--out", "x"]), "unknown scene 'yawn'");
    refused(&jawtrack(&["synth", "--scene", "static"]), "--out DIR is required");
    refused(&jawtrack(&["synth", "--scene", "static", "--out", "x", "--intrinsics", "1,2,3"]), "4 or 6 numbers");
    let realism = dir.path().join("r.json");
    std::fs::write(&realism, r#"{"f_numbr": 2.0}"#).expect("written");
    refused(
        &jawtrack(&["synth", "--scene", "static", "--out", "x", "--realism", realism.to_str().expect("utf-8")]),
        "f_numbr",
    );
    std::fs::write(&realism, r#"{"glare_probability": 3.0}"#).expect("written");
    refused(
        &jawtrack(&["synth", "--scene", "static", "--out", "x", "--realism", realism.to_str().expect("utf-8")]),
        "glare_probability must be at most 1",
    );
    assert!(!Path::new("x").exists(), "nothing written on refusal");
}

#[test]
fn self_check_passes() {
    let o = jawtrack(&["synth", "--self-check"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("ok: every edge within"));
}

#[test]
fn harness_writes_sheets_body_and_marker() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("h");
    let o = jawtrack(&["harness", "--out", out.to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["tags-maxilla.svg", "tags-mandible.svg", "dodecahedron-with-post.stl", "marker.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let bad = dir.path().join("bad");
    refused(&jawtrack(&["harness", "--out", bad.to_str().expect("utf-8"), "--post-diameter", "12"]), "post");
    refused(&jawtrack(&["harness", "--out", bad.to_str().expect("utf-8"), "--post-length", "-1"]), "post_length");
    assert!(!bad.exists(), "nothing written on refusal");
}

#[test]
fn detect_prints_one_json_line_per_image() {
    let frame = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/clean-static-1080p/frame_0000.png");
    let o = jawtrack(&["detect", "--decimate", "2", frame, frame]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 2);
    let v: serde_json::Value = serde_json::from_str(lines[0]).expect("json line");
    assert_eq!(v["width"], 1920);
    let ids: Vec<u64> = v["detections"].as_array().expect("array").iter().filter_map(|d| d["id"].as_u64()).collect();
    assert!(ids.len() >= 6 && ids.iter().all(|&id| id < 24), "{ids:?}");
    assert!(v["detections"][0]["corners"].as_array().is_some_and(|c| c.len() == 4));
    let c_mode = jawtrack(&["detect", "--linear-edges", "false", frame]);
    assert!(c_mode.status.success(), "{}", stderr(&c_mode));
    refused(&jawtrack(&["detect", "--max-hamming", "3", frame]), "max_hamming 3 is refused");
    refused(&jawtrack(&["detect", "--decimate", "2.5", frame]), "quad_decimate");
    refused(&jawtrack(&["detect", "/nonexistent.png"]), "/nonexistent.png");
}
