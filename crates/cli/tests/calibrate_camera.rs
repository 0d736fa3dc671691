//! `jawtrack calibrate-camera` as a user runs it: a rendered wave recording of a camera with
//! distortion and an 8 ms readout, calibrated, against the recording's truth; bad flags refused
//! by name.

mod common;
use common::{jawtrack, ok, refused, s};

#[test]
fn a_waved_marker_calibrates_the_camera_and_its_readout() {
    let dir = tempfile::tempdir().expect("temp dir");
    let frames = dir.path().join("wave");
    // 40 frames at 15 fps (2.7 s of waving), linear light and no blur: about 20 s to render.
    let truth = "1500,1495,962.5,537.5,-0.05,0.02";
    ok(&jawtrack(&[
        "synth",
        "--scene",
        "wave",
        "--clean",
        "--readout-ms",
        "8",
        "--intrinsics",
        truth,
        "--fps",
        "15",
        "--max-frames",
        "40",
        "--out",
        s(&frames),
    ]));
    let out = dir.path().join("camera.json");
    // The frames are linear light (--clean), so the detector reads them as they are.
    let run = |extra: &[&str]| {
        let base = ["calibrate-camera", "--fps", "15", "--linear-edges", "false", "--out", s(&out)];
        jawtrack(&[&base[..], extra, &[s(&frames)]].concat())
    };
    let report = ok(&run(&[]));
    let said = |w: &str| report.contains(w);
    assert!(
        said("track with: jawtrack track --camera ") && said("or --intrinsics ") && said("--readout-ms"),
        "{report}"
    );
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("written")).expect("json");
    let c = &written["calibration"];
    let number = |v: &serde_json::Value| v.as_f64().expect("a number");
    let (fx, fy, readout) = (number(&c["intrinsics"]["fx"]), number(&c["intrinsics"]["fy"]), number(&c["readout_s"]));
    let truth_file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(frames.join("ground_truth.json")).expect("truth")).expect("json");
    let k = &truth_file["intrinsics"];
    let true_readout = number(&truth_file["realism"]["readout_s"]);
    // Measured 0.01 % and 0.3 % on this recording; the targets are 0.3 % and 10 %.
    assert!((fx / number(&k["fx"]) - 1.0).abs() < 0.003, "fx {fx} against {}", k["fx"]);
    assert!((fy / number(&k["fy"]) - 1.0).abs() < 0.003, "fy {fy} against {}", k["fy"]);
    assert!((readout / true_readout - 1.0).abs() < 0.1, "readout {readout} against {true_readout}");
    assert!(number(&c["sigma"]["fx"]) > 0.0 && number(&c["sigma"]["readout_s"]) > 0.0, "{c}");
    // The printed flags are those written, and `track` takes them.
    let flags = written["track_flags"].as_str().expect("the flags");
    assert!(report.contains(flags), "{report}");
    let parts: Vec<&str> = flags.split(' ').collect();
    assert_eq!((parts[0], parts[2]), ("--intrinsics", "--readout-ms"));
    let track_out = dir.path().join("poses.jsonl");
    ok(&jawtrack(&[
        "track",
        parts[0],
        parts[1],
        parts[2],
        parts[3],
        "--fps",
        "15",
        "--out",
        s(&track_out),
        s(&frames),
    ]));

    // Never over an existing result unless --force.
    refused(&run(&[]), "add --force");
    ok(&run(&["--force"]));
    // Too few frames for what is asked: refused, saying what to do.
    refused(&run(&["--force", "--min-frames", "1000"]), "film longer");
}

#[test]
fn bad_flags_are_refused_by_name() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("camera.json");
    let out = s(&out);
    let frames = s(dir.path());
    refused(&jawtrack(&["calibrate-camera", "--out", out, frames]), "--fps is required");
    refused(&jawtrack(&["calibrate-camera", "--fps", "0", "--out", out, frames]), "--fps must be a positive");
    refused(
        &jawtrack(&["calibrate-camera", "--fps", "30", "--intrinsics", "1500,1500", "--out", out, frames]),
        "--intrinsics",
    );
    refused(
        &jawtrack(&["calibrate-camera", "--fps", "30", "--intrinsics", "-1,1500,959.5,539.5", "--out", out, frames]),
        "focal lengths must be positive",
    );
    refused(
        &jawtrack(&["calibrate-camera", "--fps", "30", "--max-rms-px", "-1", "--out", out, frames]),
        "--max-rms-px",
    );
    refused(&jawtrack(&["calibrate-camera", "--fps", "30", "--min-frames", "2", "--out", out, frames]), "--min-frames");
    refused(&jawtrack(&["calibrate-camera", "--fps", "30", frames]), "--out");
    refused(&jawtrack(&["calibrate-camera", "--fps", "30", "--out", out]), "<FRAMES>");
    assert!(!std::path::Path::new(out).exists(), "nothing written");
    let help = ok(&jawtrack(&["calibrate-camera", "--help"]));
    for flag in ["--video", "--fps", "--intrinsics", "--marker", "--out", "--force", "--min-frames", "--max-rms-px"] {
        assert!(help.contains(flag), "{flag} missing from:\n{help}");
    }
}
