//! A recording written by the iPhone app's own Swift: JawTrackKit's `RecordingTests` record the
//! `static-1080p` fixture through the app's frame pipeline and leave the file in
//! `target/swift/out/` (`bash ios/swift-on-linux.sh test`, which CI runs before `cargo test`).
//! `jawtrack export` must read it like any other recording.

use std::path::Path;
mod common;
use common::{jawtrack, ok};

const RECORDING: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../target/swift/out/swift-session.jsonl");

#[test]
fn the_swift_apps_recording_exports() {
    if !Path::new(RECORDING).is_file() {
        jawtrack_test_support::say_skipped(
            "no recording from the Swift tests (run `bash ios/swift-on-linux.sh test` first; CI does)",
        );
        return;
    }
    let csv = ok(&jawtrack(&["export", RECORDING, "--csv"]));
    let mut reader = csv::Reader::from_reader(csv.as_bytes());
    let headers = reader.headers().expect("header row").clone();
    let opening = headers.iter().position(|h| h == "opening_mm").expect("an opening_mm column");
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
    assert_eq!(rows.len(), 6, "the six frames of static-1080p");
    for row in &rows {
        let value: f64 = row[opening].parse().expect("a number");
        assert!(value.is_finite(), "{row:?}");
    }
    let jsonl = ok(&jawtrack(&["export", RECORDING, "--jsonl"]));
    let frames: Vec<serde_json::Value> =
        jsonl.lines().filter(|l| l.contains("\"frame\"")).map(|l| serde_json::from_str(l).expect("json")).collect();
    assert_eq!(frames.len(), 6);
    let sessions: std::collections::BTreeSet<&str> = frames.iter().filter_map(|f| f["session"].as_str()).collect();
    assert_eq!(sessions.len(), 1, "one session, stamped by the library's recorder: {sessions:?}");
    assert!(frames.iter().all(|f| f["maxilla_from_mandible"].is_array()), "both jaws in every frame");
}
