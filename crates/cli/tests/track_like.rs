//! `jawtrack track --like RECORDING`: a recording's header (intrinsics, readout, exposure,
//! marker) re-tracks frames the way the recording was made, as with the iPhone app's video
//! beside its poses.

mod common;
use common::{jawtrack, ok, refused, s, stderr};

fn lines(path: &std::path::Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .expect("recording written")
        .lines()
        .map(|l| serde_json::from_str(l).expect("json line"))
        .collect()
}

#[test]
fn like_takes_the_camera_timing_and_marker_from_a_recordings_header() {
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p");
    let dir = tempfile::tempdir().expect("temp dir");
    let (first, again) = (dir.path().join("first.jsonl"), dir.path().join("again.jsonl"));
    let k = "1500,1500,959.5,539.5";
    ok(&jawtrack(&["track", "--intrinsics", k, "--readout-ms", "5", "--exposure-ms", "2", "--out", s(&first), set]));
    let o = jawtrack(&["track", "--like", s(&first), "--out", s(&again), set]);
    ok(&o);
    let said = stderr(&o);
    assert!(said.contains("readout 5.00 ms") && said.contains("exposure 2.00 ms"), "{said}");
    let (first, again) = (lines(&first), lines(&again));
    let (h1, h2) = (&first[0]["recording"], &again[0]["recording"]);
    for key in ["intrinsics", "readout_s", "exposure_s", "marker"] {
        assert_eq!(h1[key], h2[key], "{key}");
    }
    assert_eq!(h2["readout_s"], 0.005);
    assert_eq!(first.len(), again.len());
    for (a, b) in first.iter().zip(&again).skip(1) {
        assert_eq!(a["maxilla_from_mandible"], b["maxilla_from_mandible"], "frame {}", a["frame"]);
    }
    // A flag given wins over the recording's.
    let global = dir.path().join("global.jsonl");
    ok(&jawtrack(&[
        "track",
        "--like",
        s(dir.path().join("first.jsonl").as_path()),
        "--readout-ms",
        "0",
        "--out",
        s(&global),
        set,
    ]));
    assert_eq!(lines(&global)[0]["recording"]["readout_s"], 0.0);
    // Neither --intrinsics nor --like: refused, naming the flag.
    refused(&jawtrack(&["track", "--out", s(&dir.path().join("x.jsonl")), set]), "--intrinsics");
    let headless = dir.path().join("headless.jsonl");
    std::fs::write(&headless, "").expect("written");
    refused(&jawtrack(&["track", "--like", s(&headless), "--out", s(&dir.path().join("y.jsonl")), set]), "header");
}
