//! The `jawtrack` binary as a user runs it: outputs written, bad input refused with a message
//! that says what was wrong, never a panic.

use std::path::Path;
use std::process::Command;
mod common;
use common::{jawtrack, ok, refused, s, stderr};

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

/// `jawtrack marker`'s nominal file at `path`, rewritten as a calibrated one: every tag
/// calibrated but those in `nominal`.
fn calibrated_marker_file(path: &Path, nominal: impl Fn(u64) -> bool) {
    assert!(jawtrack(&["marker", "--force", "--out", path.to_str().expect("utf-8 path")]).status.success());
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("written")).expect("json");
    for body in v["bodies"].as_array_mut().expect("bodies") {
        body["calibration"] = serde_json::json!(
            {"views": 18, "rms_before_px": 1.5, "rms_after_px": 0.2, "recordings": ["cal/frames"]});
        for tag in body["tags"].as_array_mut().expect("tags") {
            tag["calibration"] = if nominal(tag["id"].as_u64().expect("id")) {
                serde_json::json!({"status": "nominal", "views": 1})
            } else {
                serde_json::json!({"status": "calibrated", "views": 9, "rms_before_px": 2.25, "rms_after_px": 0.125})
            };
        }
    }
    std::fs::write(path, v.to_string()).expect("rewritten");
}

#[test]
fn check_marker_prints_the_calibration_provenance() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("m.json");
    let p = path.to_str().expect("utf-8 path");
    // A nominal marker: nothing recorded, nothing to flag.
    assert!(jawtrack(&["marker", "--out", p]).status.success());
    let out = ok(&jawtrack(&["check-marker", p]));
    assert!(out.contains("calibration: none recorded") && !out.contains("uncalibrated_tag"), "{out}");
    // A version 1 file still reads, its provenance unknown.
    let v1 = std::fs::read_to_string(&path).expect("written").replacen("\"version\": 3", "\"version\": 1", 1);
    std::fs::write(&path, v1).expect("rewritten");
    let out = ok(&jawtrack(&["check-marker", p]));
    assert!(out.contains("calibration: none recorded"), "{out}");
    // Calibrated but tags 17 and 21.
    calibrated_marker_file(&path, |id| id == 17 || id == 21);
    let out = ok(&jawtrack(&["check-marker", p]));
    assert!(!out.contains("none recorded"), "{out}");
    assert!(
        out.contains(
            "calibrated from 18 views of cal/frames: reprojection error 1.500 px nominal, 0.200 px calibrated"
        ),
        "{out}"
    );
    assert!(out.contains("     12  calibrated      9      2.250     0.125"), "{out}");
    assert!(out.contains("     17  nominal         1"), "{out}");
    assert!(out.contains("nominal tags 17, 21: a pose that uses them is flagged mandible:uncalibrated_tag"), "{out}");
    assert!(!out.contains("maxilla:uncalibrated_tag"), "every maxilla tag is calibrated: {out}");
    // A tag's residual that cannot be.
    let bad =
        std::fs::read_to_string(&path).expect("written").replacen("\"rms_after_px\":0.125", "\"rms_after_px\":-1", 1);
    std::fs::write(&path, bad).expect("rewritten");
    refused(&jawtrack(&["check-marker", p]), "rms_after_px");
}

#[test]
fn track_counts_the_frames_resting_on_nominal_tags_of_a_calibrated_marker() {
    let frame = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/clean-hinge-1080p/frame_0000.png");
    let dir = tempfile::tempdir().expect("temp dir");
    let marker = dir.path().join("m.json");
    // The whole mandible left nominal, the maxilla calibrated.
    calibrated_marker_file(&marker, |id| id >= 12);
    let out = dir.path().join("poses.jsonl");
    let args = ["track", "--intrinsics", "1500,1500,959.5,539.5", "--marker", marker.to_str().expect("utf-8")];
    let o = jawtrack(&[&args[..], &["--out", out.to_str().expect("utf-8"), frame]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).expect("poses");
    let line: serde_json::Value = serde_json::from_str(text.lines().nth(1).expect("a frame")).expect("json");
    let flags: Vec<&str> = line["flags"].as_array().expect("flags").iter().filter_map(|f| f.as_str()).collect();
    assert!(flags.contains(&"mandible:uncalibrated_tag"), "{flags:?}");
    assert!(!flags.contains(&"maxilla:uncalibrated_tag"), "{flags:?}");
    let ids: Vec<String> =
        line["mandible"]["tags"].as_array().expect("mandible tags").iter().map(|t| t.to_string()).collect();
    let said = format!("warning: mandible: 1 frames rest on nominal tags {}", ids.join(", "));
    assert!(stderr(&o).contains(&said), "{said} in {}", stderr(&o));
    assert!(stderr(&o).contains("mandible:uncalibrated_tag ×1"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("maxilla: 1 frames rest"), "{}", stderr(&o));
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

#[test]
fn track_writes_one_line_per_frame_with_the_jaw_pose() {
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("poses.jsonl");
    let out = out.to_str().expect("utf-8 path");
    let o = jawtrack(&["track", "--intrinsics", "1500,1500,959.5,539.5", "--out", out, set]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("tracked 6 frames"), "{}", stderr(&o));
    assert!(stderr(&o).contains("assume 30 fps"), "says what the frame times rest on: {}", stderr(&o));
    let text = std::fs::read_to_string(out).expect("poses written");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(Path::new(set).join("ground_truth.json")).expect("truth"))
            .expect("json");
    let lines: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).expect("json line")).collect();
    assert_eq!(lines.len(), 7, "a header and six frames");
    assert_eq!(lines[0]["recording"]["source"], "jawtrack track");
    assert_eq!(lines[0]["recording"]["intrinsics"]["fx"], 1500.0);
    // The tone curve: asked for in the header, read through on the first frame, and said.
    assert_eq!(lines[0]["recording"]["settings"]["tone"], "auto");
    assert_eq!((&lines[1]["tone"]["setting"], &lines[1]["tone"]["curve"]), (&"auto".into(), &"srgb".into()));
    assert!(stderr(&o).contains("tone curve: srgb (auto: kept"), "{}", stderr(&o));
    let near_truth = |lines: &[serde_json::Value]| {
        for (i, (line, f)) in lines[1..].iter().zip(truth["frames"].as_array().expect("frames")).enumerate() {
            assert_eq!(line["frame"], i);
            assert!(line["maxilla"]["cov"].as_array().is_some_and(|c| c.len() == 36));
            // The nominal marker (print errors unknown): the mandible in the maxilla within 1 mm.
            let got: Vec<f64> = serde_json::from_value(line["maxilla_from_mandible"].clone()).expect("4x4 matrix");
            let want: Vec<f64> = serde_json::from_value(f["maxilla_from_mandible"].clone()).expect("truth matrix");
            let d = ((got[3] - want[3]).powi(2) + (got[7] - want[7]).powi(2) + (got[11] - want[11]).powi(2)).sqrt();
            assert!(d < 1.0, "frame {i}: {d:.3} mm from the truth");
            assert_eq!(&got[12..], &[0.0, 0.0, 0.0, 1.0]);
        }
    };
    near_truth(&lines);
    // With a rolling shutter: the header says how the frames were tracked, and the fixture's
    // jumps between views (taken as 30 fps footage) do not spoil the poses.
    let k = "1500,1500,959.5,539.5";
    let timed = jawtrack(&[
        "track",
        "--intrinsics",
        k,
        "--readout-ms",
        "5",
        "--exposure-ms",
        "2",
        "--tone",
        "srgb",
        "--out",
        "-",
        set,
    ]);
    assert!(timed.status.success(), "{}", stderr(&timed));
    assert!(stderr(&timed).contains("tone curve: srgb (as given)"), "{}", stderr(&timed));
    let timed: Vec<serde_json::Value> =
        String::from_utf8_lossy(&timed.stdout).lines().map(|l| serde_json::from_str(l).expect("json line")).collect();
    assert_eq!(timed[0]["recording"]["readout_s"], 0.005);
    assert_eq!(timed[0]["recording"]["exposure_s"], 0.002);
    assert_eq!(timed.len(), 7, "a header and six frames");
    near_truth(&timed);
    refused(&jawtrack(&["track", "--intrinsics", k, "--readout-ms", "-1", "--out", out, set]), "--readout-ms");
    refused(&jawtrack(&["track", "--intrinsics", k, "--exposure-ms", "0", "--out", out, set]), "--exposure-ms");
    refused(&jawtrack(&["track", "--intrinsics", k, "--tone", "gamma:0.5", "--out", out, set]), "between 1 and 4");
    refused(&jawtrack(&["track", "--intrinsics", "1500,1500,959.5", "--out", out, set]), "intrinsics");
    refused(
        &jawtrack(&["track", "--intrinsics", "1500,1500,959.5,539.5", "--out", out, "/nonexistent"]),
        "/nonexistent",
    );
    refused(&jawtrack(&["track", "--intrinsics", "1500,1500,959.5,539.5", "--fps", "0", "--out", out, set]), "--fps");
    let empty = tempfile::tempdir().expect("temp dir");
    refused(
        &jawtrack(&[
            "track",
            "--intrinsics",
            "1500,1500,959.5,539.5",
            "--out",
            out,
            empty.path().to_str().expect("utf-8"),
        ]),
        "holds no PNG or JPEG",
    );
}

#[test]
fn track_with_a_registration_writes_the_scans_pose_and_names_a_bad_field() {
    let frame = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/clean-hinge-1080p/frame_0000.png");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("poses.jsonl");
    let out = out.to_str().expect("utf-8 path");
    let reg = dir.path().join("reg.json");
    // The upper scan 38 mm behind the maxilla marker, the lower one likewise.
    let shift = |y: f64| format!("[1,0,0,0, 0,1,0,{y}, 0,0,1,38, 0,0,0,1]");
    let text = format!(
        r#"{{"version":1,"units":"mm","maxilla_scan_from_maxilla_marker":{},"mandible_scan_from_mandible_marker":{}}}"#,
        shift(22.0),
        shift(-22.0)
    );
    std::fs::write(&reg, text).expect("write");
    let reg = reg.to_str().expect("utf-8 path");
    let o = jawtrack(&["track", "--intrinsics", "1500,1500,959.5,539.5", "--registration", reg, "--out", out, frame]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out).expect("poses");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "a header and the frame");
    let line: serde_json::Value = serde_json::from_str(lines[1]).expect("json");
    let m: Vec<f64> = serde_json::from_value(line["maxilla_from_mandible"].clone()).expect("jaw pose");
    let s: Vec<f64> = serde_json::from_value(line["maxilla_scan_from_mandible_scan"].clone()).expect("scan pose");
    // Pure shifts on either side: the scans' pose is the markers' with the same rotation.
    for i in [0, 1, 2, 4, 5, 6, 8, 9, 10] {
        assert!((m[i] - s[i]).abs() < 1e-12, "rotation entry {i}");
    }
    std::fs::write(
        dir.path().join("bad.json"),
        r#"{"version":1,"units":"mm","maxilla_scan_from_maxilla_marker":[1,2]}"#,
    )
    .expect("write");
    let bad = dir.path().join("bad.json");
    refused(
        &jawtrack(&[
            "track",
            "--intrinsics",
            "1500,1500,959.5,539.5",
            "--registration",
            bad.to_str().expect("utf-8"),
            "--out",
            out,
            frame,
        ]),
        "maxilla_scan_from_maxilla_marker",
    );
}

#[test]
fn track_reads_a_video_through_ffmpeg_as_it_reads_the_frames() {
    if !have_ffmpeg() {
        return;
    }
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/clean-hinge-1080p");
    let dir = tempfile::tempdir().expect("temp dir");
    let video = dir.path().join("hinge.mkv");
    // FFV1 is lossless: the decoded luma equals the PNGs.
    let made = Command::new("ffmpeg")
        .args(["-v", "error", "-framerate", "30", "-i", &format!("{set}/frame_%04d.png")])
        .args(["-c:v", "ffv1", "-pix_fmt", "gray"])
        .arg(&video)
        .output()
        .expect("ffmpeg runs");
    assert!(made.status.success(), "{}", stderr(&made));
    let from_video = dir.path().join("v.jsonl");
    let from_images = dir.path().join("i.jsonl");
    // Matroska keeps milliseconds: --fps times both by index, so that the motion model sees
    // the same times.
    let args = ["track", "--intrinsics", "1500,1500,959.5,539.5", "--fps", "30", "--out"];
    let o = jawtrack(
        &[&args[..], &[from_video.to_str().expect("utf-8"), "--video", video.to_str().expect("utf-8")]].concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = jawtrack(&[&args[..], &[from_images.to_str().expect("utf-8"), set]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let poses = |p: &Path| -> Vec<serde_json::Value> {
        std::fs::read_to_string(p)
            .expect("poses")
            .lines()
            .skip(1)
            .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("json")["maxilla_from_mandible"].clone())
            .collect()
    };
    let (v, i) = (poses(&from_video), poses(&from_images));
    assert_eq!(v.len(), 5);
    assert_eq!(v, i, "the video's frames track exactly as the PNGs");
    refused(&jawtrack(&[&args[..], &["x.jsonl", "--video", "/nonexistent.mp4"]].concat()), "/nonexistent.mp4");
}

/// Whether ffmpeg and ffprobe run; says the test skipped if not.
fn have_ffmpeg() -> bool {
    let have = |tool: &str| Command::new(tool).arg("-version").output().is_ok_and(|o| o.status.success());
    let both = have("ffmpeg") && have("ffprobe");
    if !both {
        let _ = std::io::Write::write_all(&mut std::io::stderr(), b"SKIPPED: ffmpeg/ffprobe not installed\n");
    }
    both
}

/// Runs ffmpeg with `args`, asserting it succeeded.
fn ffmpeg(args: &[&str]) {
    let o = Command::new("ffmpeg").args(["-v", "error", "-y"]).args(args).output().expect("ffmpeg runs");
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Each frame line's time and jaw pose.
fn times_and_poses(p: &Path) -> Vec<(f64, serde_json::Value)> {
    std::fs::read_to_string(p)
        .expect("poses")
        .lines()
        .skip(1)
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).expect("json");
            (v["t"].as_f64().expect("t"), v["maxilla_from_mandible"].clone())
        })
        .collect()
}

#[test]
fn a_portrait_video_is_tracked_as_stored_and_timed_by_its_own_clock() {
    if !have_ffmpeg() {
        return;
    }
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/clean-hinge-1080p");
    let dir = tempfile::tempdir().expect("temp dir");
    let (plain, turned, vfr) = (dir.path().join("h.mkv"), dir.path().join("turned.mov"), dir.path().join("vfr.mkv"));
    let pngs = format!("{set}/frame_%04d.png");
    ffmpeg(&["-framerate", "30", "-i", &pngs, "-c:v", "ffv1", "-pix_fmt", "gray", s(&plain)]);
    // A phone held upright stores landscape buffers and a 90° display rotation.
    ffmpeg(&["-i", s(&plain), "-c", "copy", "-metadata:s:v:0", "rotate=90", s(&turned)]);
    // Frames 3 and 4 come 100 ms late, as a variable-rate phone video's may.
    ffmpeg(&[
        "-framerate",
        "30",
        "-i",
        &pngs,
        "-vf",
        "setpts='N/(30*TB)+if(gte(N,3),0.1/TB,0)'",
        "-fps_mode",
        "vfr",
        "-c:v",
        "ffv1",
        "-pix_fmt",
        "gray",
        s(&vfr),
    ]);
    // --fps times frames by index, as the images are timed, so the motion model sees equal times.
    let args = ["track", "--intrinsics", "1500,1500,959.5,539.5", "--fps", "30", "--out"];
    let images = dir.path().join("i.jsonl");
    ok(&jawtrack(&[&args[..], &[s(&images), set]].concat()));
    let from_images = times_and_poses(&images);
    assert!(from_images.iter().all(|(_, p)| p.is_array()), "every PNG gives a jaw pose");

    let out = dir.path().join("turned.jsonl");
    let o = jawtrack(&[&args[..], &[s(&out), "--video", s(&turned)]].concat());
    assert!(stderr(&o).contains("turned 90°") && stderr(&o).contains("1920×1080"), "{}", stderr(&o));
    let poses: Vec<_> = times_and_poses(&out).into_iter().map(|(_, p)| p).collect();
    assert_eq!(poses, from_images.iter().map(|(_, p)| p.clone()).collect::<Vec<_>>(), "read as stored");

    let out = dir.path().join("vfr.jsonl");
    let stored = ["track", "--intrinsics", "1500,1500,959.5,539.5", "--out"];
    ok(&jawtrack(&[&stored[..], &[s(&out), "--video", s(&vfr)]].concat()));
    let times: Vec<f64> = times_and_poses(&out).into_iter().map(|(t, _)| t).collect();
    let expected = [0.0, 1.0 / 30.0, 2.0 / 30.0, 0.2, 0.2 + 1.0 / 30.0];
    assert_eq!(times.len(), expected.len());
    for (t, e) in times.iter().zip(expected) {
        // Matroska keeps milliseconds.
        assert!((t - e).abs() < 1e-3, "frame times {times:?}, wanted {expected:?}");
    }
}

#[test]
fn an_unreadable_frame_is_skipped_and_flagged_and_a_run_with_none_readable_fails() {
    let set = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/clean-hinge-1080p"));
    let dir = tempfile::tempdir().expect("temp dir");
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).expect("frames dir");
    for i in 1..=3 {
        let name = format!("frame_000{i}.png");
        std::fs::copy(set.join(&name), frames.join(&name)).expect("copy");
    }
    std::fs::write(frames.join("frame_0002.png"), b"not a PNG").expect("damage one");
    let out = dir.path().join("o.jsonl");
    let o = jawtrack(&["track", "--intrinsics", "1500,1500,959.5,539.5", "--out", s(&out), s(&frames)]);
    assert!(o.status.success(), "one bad frame does not end the run: {}", stderr(&o));
    assert!(stderr(&o).contains("frame_0002.png") && stderr(&o).contains("1 unreadable"), "{}", stderr(&o));
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(&out)
        .expect("written")
        .lines()
        .skip(1)
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    assert_eq!(lines.len(), 3, "every frame keeps its line");
    assert_eq!(lines[1]["flags"], serde_json::json!(["unreadable"]));
    assert!(lines[1]["maxilla_from_mandible"].is_null());
    assert!(lines[0]["maxilla_from_mandible"].is_array() && lines[2]["maxilla_from_mandible"].is_array());
    let csv = dir.path().join("o.csv");
    let o = jawtrack(&["export", s(&out), "--csv", "--out", s(&csv)]);
    assert!(stderr(&o).contains("exported 3 frames"), "{}", stderr(&o));

    let bad = dir.path().join("bad");
    std::fs::create_dir(&bad).expect("dir");
    std::fs::write(bad.join("a.png"), b"not a PNG").expect("bad frame");
    let o =
        jawtrack(&["track", "--intrinsics", "1500,1500,959.5,539.5", "--out", s(&dir.path().join("b.jsonl")), s(&bad)]);
    refused(&o, "none of the 1 frames could be read");
}

#[test]
fn track_never_overwrites_a_recording_unless_forced() {
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("session.jsonl");
    std::fs::write(&out, "a patient's session\n").expect("write");
    let out = out.to_str().expect("utf-8 path");
    let args = ["track", "--intrinsics", "1500,1500,959.5,539.5", "--out", out, set];
    let o = jawtrack(&args);
    refused(&o, "already exists");
    assert!(stderr(&o).contains("--force"), "says how to replace it: {}", stderr(&o));
    assert_eq!(std::fs::read_to_string(out).expect("read"), "a patient's session\n", "left as it was");
    let o = jawtrack(&[&args[..], &["--force"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(out).expect("read").lines().count(), 7, "replaced: a header and six frames");
}

#[test]
fn a_marker_file_with_one_body_is_refused_before_tracking() {
    let dir = tempfile::tempdir().expect("temp dir");
    let full = dir.path().join("m.json");
    let full = full.to_str().expect("utf-8 path");
    assert!(jawtrack(&["marker", "--out", full]).status.success());
    let mut doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(full).expect("read")).expect("json");
    doc["bodies"].as_array_mut().expect("bodies").retain(|b| b["name"] == "maxilla");
    let half = dir.path().join("maxilla-only.json");
    std::fs::write(&half, doc.to_string()).expect("write");
    let half = half.to_str().expect("utf-8 path");
    refused(&jawtrack(&["check-marker", half]), "no mandible body");
    let out = dir.path().join("poses.jsonl");
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p");
    let o = jawtrack(&[
        "track",
        "--intrinsics",
        "1500,1500,959.5,539.5",
        "--marker",
        half,
        "--out",
        out.to_str().expect("utf-8 path"),
        set,
    ]);
    refused(&o, "no mandible body");
    assert!(!out.exists(), "refused before writing anything");
    assert!(jawtrack(&["check-marker", full]).status.success(), "the complete file still passes");
}

#[test]
fn a_bad_marker_field_is_said_once_naming_the_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("cm.json");
    let p = s(&path);
    ok(&jawtrack(&["marker", "--out", p]));
    let text = std::fs::read_to_string(&path).expect("written").replacen("\"units\": \"mm\"", "\"units\": \"cm\"", 1);
    std::fs::write(&path, text).expect("rewritten");
    let out = dir.path().join("poses.jsonl");
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p");
    let intrinsics = ["--intrinsics", "1500,1500,959.5,539.5"];
    for o in [
        jawtrack(&["check-marker", p]),
        jawtrack(&[&["track"], &intrinsics[..], &["--marker", p, "--out", s(&out), set]].concat()),
        jawtrack(&[&["calibrate-marker"], &intrinsics[..], &["--marker", p, "--out", s(&out), set]].concat()),
    ] {
        refused(&o, "`units` must be \"mm\", got \"cm\"");
        let e = stderr(&o);
        assert_eq!(e.matches("must be \"mm\"").count(), 1, "said once: {e}");
        assert_eq!(e.matches("cm.json").count(), 1, "the file named once: {e}");
    }
}

#[test]
fn negative_intrinsics_reach_their_check_without_an_equals_sign() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out");
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p");
    let bad = "-1500,1500,959.5,539.5";
    for o in [
        jawtrack(&["track", "--intrinsics", bad, "--out", s(&out), set]),
        jawtrack(&["calibrate-marker", "--intrinsics", bad, "--out", s(&out), set]),
        jawtrack(&["synth", "--scene", "static", "--intrinsics", bad, "--out", s(&out)]),
    ] {
        refused(&o, "focal lengths must be positive (fx=-1500");
    }
    assert!(!out.exists(), "refused before writing anything");
}

#[test]
fn synth_help_lists_every_scene() {
    let help = ok(&jawtrack(&["synth", "--help"]));
    for scene in jawtrack_synth::SceneKind::ALL {
        assert!(help.contains(scene.name()), "{} missing from:\n{help}", scene.name());
    }
    refused(&jawtrack(&["synth", "--out", "x"]), "calibration");
}

#[test]
fn results_are_never_overwritten_unless_forced() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (marker, recording) = (dir.path().join("m.json"), dir.path().join("r.jsonl"));
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/clean-hinge-1080p");
    ok(&jawtrack(&["track", "--intrinsics", "1500,1500,959.5,539.5", "--out", s(&recording), set]));
    let (csv, plots, metrics) = (dir.path().join("r.csv"), dir.path().join("plots"), dir.path().join("metrics"));
    let runs: Vec<Vec<&str>> = vec![
        vec!["marker", "--out", s(&marker)],
        vec!["export", s(&recording), "--csv", "--out", s(&csv)],
        vec!["plot", s(&recording), "--out", s(&plots)],
        vec!["metrics", s(&recording), "--out", s(&metrics)],
    ];
    for args in &runs {
        ok(&jawtrack(args));
    }
    let written = || {
        [&marker, &csv, &plots.join("incisor_opening.svg"), &metrics.join("metrics.json")]
            .map(|p| std::fs::read(p).expect("written"))
    };
    let before = written();
    // calibrate-marker refuses before reading any frame.
    let calibrate =
        vec!["calibrate-marker", "--intrinsics", "1500,1500,959.5,539.5", "--out", s(&marker), "/nonexistent"];
    for args in runs.iter().chain([&calibrate]) {
        let o = jawtrack(args);
        refused(&o, "add --force");
        assert!(!stderr(&o).contains("/nonexistent"), "refused before reading anything: {}", stderr(&o));
        assert!(written() == before, "{args:?} changed nothing");
    }
    for args in &runs {
        ok(&jawtrack(&[&args[..], &["--force"]].concat()));
    }
}

/// `jawtrack bench` starts the benchmark program it is pointed at (or the one beside it) with
/// the arguments unchanged, and passes its exit status on.
#[test]
fn bench_forwards_its_arguments_and_exit_status() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fake = dir.path().join("fake-bench.sh");
    std::fs::write(&fake, "#!/bin/sh\necho \"args: $*\"\nexit 3\n").expect("written");
    let mut perms = std::fs::metadata(&fake).expect("metadata").permissions();
    std::os::unix::fs::PermissionsExt::set_mode(&mut perms, 0o755);
    std::fs::set_permissions(&fake, perms).expect("executable");
    let o = Command::new(env!("CARGO_BIN_EXE_jawtrack"))
        .args(["bench", "pipeline", "--threads", "1,2", "--frames", "4"])
        .env("JAWTRACK_BENCH", &fake)
        .output()
        .expect("jawtrack runs");
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "args: pipeline --threads 1,2 --frames 4");
}

/// Without a benchmark program the message says how to build one.
#[test]
fn bench_without_the_benchmark_program_says_how_to_build_it() {
    let o = Command::new(env!("CARGO_BIN_EXE_jawtrack"))
        .args(["bench", "pipeline"])
        .env("JAWTRACK_BENCH", "/nonexistent/jawtrack-bench")
        .output()
        .expect("jawtrack runs");
    refused(&o, "JAWTRACK_BENCH names /nonexistent/jawtrack-bench, which is not a file");
}
