//! `jawtrack points`: writes a points file from coordinates, checks it, describes the head frame
//! and the Bonwill condyles it makes, and refuses what no arch can be.

use std::path::Path;
mod common;
use common::{jawtrack, ok, refused, s};

/// An arch in a scan frame that is the head frame moved by (10, 20, 30) mm.
const OCCLUSAL: &str = "10,20,30,35,20,65,-15,20,65";
const LOWER_INCISAL: &str = "10,21.5,31";

fn write(file: &Path, extra: &[&str]) -> String {
    let mut args = vec!["points", "--occlusal", OCCLUSAL, "--lower-incisal", LOWER_INCISAL, "--out", s(file)];
    args.extend(extra);
    ok(&jawtrack(&args))
}

#[test]
fn a_file_is_written_described_and_read_back() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("points.json");
    let text = write(&file, &[]);
    // The molars sit 25 mm to each side and 35 mm behind the incisal point; the Bonwill
    // condyles 50.8 mm to each side of the lower incisal point, 38.6 mm above it and 79.1 mm
    // behind it (101.6 mm sides, 26°).
    assert!(text.contains("left (25.0, 0.0, 35.0)") && text.contains("right (-25.0, 0.0, 35.0)"), "{text}");
    assert!(text.contains("left (50.8, -37.1, 80.1)") && text.contains("Bonwill"), "{text}");
    assert!(text.contains("intercondylar        101.6 mm"), "{text}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&file).expect("read")).expect("JSON");
    assert_eq!(
        (v["version"].as_u64(), v["units"].as_str(), v["frame"].as_str()),
        (Some(1), Some("mm"), Some("upper scan"))
    );
    assert!(v.get("condyles").is_none(), "{v}");
    let check = ok(&jawtrack(&["points", "--check", s(&file)]));
    assert!(check.contains("is a valid points file") && check.contains("Bonwill"), "{check}");
    // Never over an existing file unless asked; given condyles are kept.
    refused(
        &jawtrack(&["points", "--occlusal", OCCLUSAL, "--lower-incisal", LOWER_INCISAL, "--out", s(&file)]),
        "--force",
    );
    let text = write(&file, &["--condyles", "60,0,100,-40,0,100", "--force"]);
    assert!(text.contains("(given)") && text.contains("intercondylar        100.0 mm"), "{text}");
}

#[test]
fn what_no_arch_can_be_is_refused_by_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("p.json");
    let bad = |occlusal: &str, needle: &str| {
        refused(&jawtrack(&["points", "--occlusal", occlusal, "--lower-incisal", "0,0,0", "--out", s(&file)]), needle);
    };
    bad("0,0,0,25,0,35,50,0,70", "nearly on a line");
    bad("0,0,0,0.025,0,0.035,-0.025,0,0.035", "other units");
    bad("0,0,0,25,0,35", "9 numbers");
    refused(&jawtrack(&["points", "--out", s(&file)]), "--occlusal");
    assert!(!file.exists());
    std::fs::write(&file, r#"{"version": 2}"#).expect("write");
    refused(&jawtrack(&["points", "--check", s(&file)]), "not a points file");
}
