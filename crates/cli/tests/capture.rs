//! Capture as a real phone can deliver it, through the command (issue 36): `jawtrack plan`; a
//! phone held nearer than its lens focuses, whose every frame is flagged `defocused` and gives
//! no jaw pose; a focal length 3 % off (focus moved since calibration), named; a recording's
//! lens position or zoom that differs from the camera file's, named. Frames are rendered with a
//! Pro iPhone's wide camera (`jawtrack synth --phone`) and tracked with the marker as printed.

mod common;
use common::{jawtrack, ok, refused, s, stderr};
use std::path::Path;

/// Renders the static grid's first `frames` views with a phone at `distance` mm, its lens locked
/// at `focus` mm with `zoom`; the frames' true intrinsics as `fx,fy,cx,cy`, scaled by `scale`,
/// and the marker as printed, written beside them.
fn render(dir: &Path, name: &str, distance: f64, focus: f64, zoom: f64, frames: usize) -> (String, String) {
    let out = dir.join(name);
    let args = [
        "synth",
        "--scene",
        "static",
        "--phone",
        "--distance-mm",
        &distance.to_string(),
        "--focus-mm",
        &focus.to_string(),
        "--zoom",
        &zoom.to_string(),
        "--frames-per-view",
        "1",
        "--max-frames",
        &frames.to_string(),
        "--out",
        s(&out),
    ];
    ok(&jawtrack(&args));
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("ground_truth.json")).expect("truth")).expect("json");
    let marker = dir.join(format!("{name}_marker.json"));
    std::fs::write(&marker, truth["true_marker"].to_string()).expect("marker");
    let k = &truth["intrinsics"];
    let fx = k["fx"].as_f64().expect("fx");
    assert!((fx / (1500.0 * zoom) - focus / (focus - 6.8)).abs() < 1e-9, "the frames' focal length breathes: {fx}");
    (s(&out).to_owned(), s(&marker).to_owned())
}

fn intrinsics(frames: &str, scale: f64) -> String {
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(Path::new(frames).join("ground_truth.json")).expect("truth"))
            .expect("json");
    let k = &truth["intrinsics"];
    let v = |key: &str| k[key].as_f64().expect("number");
    format!("{},{},{},{}", v("fx") * scale, v("fy") * scale, v("cx"), v("cy"))
}

#[test]
fn the_plan_says_where_to_hold_the_phone_and_refuses_nonsense() {
    let text = ok(&jawtrack(&["plan", "--phone", "iPhone16,1"]));
    assert!(text.starts_with("iPhone 15 Pro (iPhone16,1): hold the phone about 22 cm away"), "{text}");
    assert!(text.contains("1920×1080 at 60 frames/s, 2× native crop, focus locked at 22 cm"), "{text}");
    let json: serde_json::Value =
        serde_json::from_str(&ok(&jawtrack(&["plan", "--phone", "iPhone14,2", "--json"]))).expect("JSON");
    assert_eq!((json["width"].as_u64(), json["zoom"].as_f64()), (Some(3840), Some(1.0)), "no native crop: 4K");
    let unknown = ok(&jawtrack(&["plan", "--phone", "iPhone1,1"]));
    assert!(unknown.contains("not in the table"), "{unknown}");
    let told = ok(&jawtrack(&["plan", "--phone", "iPhone15,4", "--min-focus-mm", "120"]));
    assert!(!told.contains("not known"), "the phone's own figure was given: {told}");
    refused(&jawtrack(&["plan", "--phone", "iPhone16,1", "--min-focus-mm", "-5"]), "--min-focus-mm");
    refused(&jawtrack(&["plan", "--phone", "iPhone16,1", "--fps", "240"]), "240 frames/s");
}

#[test]
fn a_phone_held_nearer_than_it_focuses_gives_no_unflagged_pose() {
    let dir = tempfile::tempdir().expect("temp dir");
    // 120 mm away, the lens stuck at 200 mm.
    let (frames, marker) = render(dir.path(), "close", 120.0, 200.0, 1.0, 3);
    let out = dir.path().join("close.jsonl");
    let o =
        jawtrack(&["track", "--intrinsics", &intrinsics(&frames, 1.0), "--marker", &marker, "--out", s(&out), &frames]);
    ok(&o);
    let text = std::fs::read_to_string(&out).expect("recording");
    let mut checked = 0;
    for line in text.lines().skip(1) {
        let f: serde_json::Value = serde_json::from_str(line).expect("JSON line");
        let flags: Vec<&str> = f["flags"].as_array().expect("flags").iter().filter_map(|v| v.as_str()).collect();
        for body in ["maxilla", "mandible"] {
            if !f[body].is_null() {
                assert!(flags.contains(&format!("{body}:defocused").as_str()), "{body} unflagged: {flags:?}");
                assert!(f[body]["blur_px"].as_f64().expect("blur") > 4.0, "{}", f[body]);
            }
        }
        assert!(f["maxilla_from_mandible"].is_null(), "a jaw pose from a defocused frame: {line}");
        checked += 1;
    }
    assert_eq!(checked, 3);
    let e = stderr(&o);
    assert!(e.contains("3 of 3 frames had a marker out of focus") && e.contains("jawtrack plan"), "{e}");
}

#[test]
fn a_focal_length_three_percent_off_is_named_as_focus_moved() {
    let dir = tempfile::tempdir().expect("temp dir");
    // The plan's geometry: 220 mm, the 2× crop, focus locked there.
    let (frames, marker) = render(dir.path(), "plan", 220.0, 220.0, 2.0, 4);
    let track = |scale: f64| {
        let o = jawtrack(&[
            "track",
            "--intrinsics",
            &intrinsics(&frames, scale),
            "--marker",
            &marker,
            "--out",
            "-",
            &frames,
        ]);
        ok(&o);
        stderr(&o)
    };
    let right = track(1.0);
    assert!(!right.contains("focus or the zoom change"), "{right}");
    assert!(right.contains("jaw pose in 4"), "{right}");
    for (scale, factor) in [(1.03, "0.97"), (0.97, "1.03")] {
        let e = track(scale);
        assert!(e.contains(&format!("the focal length that fits is {factor}")), "× {scale}: {e}");
        assert!(e.contains("did the focus or the zoom change since the camera was calibrated"), "{e}");
    }
}

#[test]
fn a_recordings_lens_position_or_zoom_unlike_the_calibrations_is_named() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (frames, marker) = render(dir.path(), "plan", 220.0, 220.0, 2.0, 1);
    let k = intrinsics(&frames, 1.0);
    let v: Vec<f64> = k.split(',').map(|x| x.parse().expect("number")).collect();
    let camera = dir.path().join("camera.json");
    let file = serde_json::json!({
        "version": 1,
        "calibration": {
            "image_size": [1920, 1080],
            "intrinsics": {"fx": v[0], "fy": v[1], "cx": v[2], "cy": v[3], "k1": 0.0, "k2": 0.0},
            "readout_s": 0.0101,
            "sigma": {"fx": 1.0, "fy": 1.0, "cx": 0.5, "cy": 0.5, "k1": 0.001, "k2": 0.001, "readout_s": 0.0001,
                      "corner_distortion_px": 0.1},
            "rms_px": 0.05, "frames_used": 100, "views_used": 180, "corners_used": 2000,
            "sightings_dropped": 0, "coverage": 0.7
        },
        "track_flags": "",
        "calibrated_at": {"lens_position": 0.81, "zoom": 2.0}
    });
    std::fs::write(&camera, file.to_string()).expect("camera file");
    let track = |extra: &[&str]| {
        let args =
            [&["track", "--camera", s(&camera), "--marker", &marker, "--out", "-"][..], extra, &[frames.as_str()]];
        let o = jawtrack(&args.concat());
        ok(&o);
        stderr(&o)
    };
    let same = track(&["--lens-position", "0.812", "--zoom", "2"]);
    assert!(!same.contains("while calibrating"), "{same}");
    let moved = track(&["--lens-position", "0.6"]);
    assert!(moved.contains("the lens position was 0.600 while recording and 0.810 while calibrating"), "{moved}");
    let zoomed = track(&["--zoom", "1"]);
    assert!(zoomed.contains("the zoom was 1× while recording and 2× while calibrating"), "{zoomed}");
    refused(
        &jawtrack(&["track", "--camera", s(&camera), "--lens-position", "2", "--out", "-", &frames]),
        "--lens-position",
    );
    std::fs::write(&camera, "{}").expect("write");
    refused(&jawtrack(&["track", "--camera", s(&camera), "--out", "-", &frames]), "not a camera file");
}
