//! `jawtrack synth` with a rolling shutter: the exposure and readout flags, the phone's
//! orientation in the chew scene, and what they refuse.

mod common;
use common::{jawtrack, ok, refused, s};

fn truth(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("ground_truth.json")).expect("truth")).expect("json")
}

#[test]
fn synth_renders_a_rolling_shutter_chew_and_refuses_bad_timing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("chew");
    let args = ["synth", "--scene", "chew", "--fps", "60", "--cycles", "1", "--exposure-ms", "2", "--readout-ms", "5"];
    ok(&jawtrack(&[&args[..], &["--max-frames", "1", "--out", s(&out)]].concat()));
    let gt = truth(&out);
    assert_eq!(gt["realism"]["exposure_s"], 0.002);
    assert_eq!(gt["realism"]["readout_s"], 0.005);
    let frame = &gt["frames"][0];
    assert!(frame["incisor_speed_mm_s"].is_number(), "{frame}");
    assert_eq!(frame["spec"]["view"]["orientation"], "upright");

    let landscape = dir.path().join("landscape");
    ok(&jawtrack(&[&args[..], &["--clean", "--landscape", "--max-frames", "1", "--out", s(&landscape)]].concat()));
    let gt = truth(&landscape);
    assert_eq!(gt["frames"][0]["spec"]["view"]["orientation"], "landscape");
    assert_eq!(gt["realism"]["readout_s"], 0.005, "the flags override --clean too");

    let x = dir.path().join("x");
    refused(&jawtrack(&["synth", "--scene", "chew", "--readout-ms", "-1", "--out", s(&x)]), "--readout-ms must be");
    refused(&jawtrack(&["synth", "--scene", "chew", "--exposure-ms", "NaN", "--out", s(&x)]), "--exposure-ms must be");
    refused(&jawtrack(&["synth", "--scene", "hinge", "--landscape", "--out", s(&x)]), "chew scene only");
    assert!(!x.exists(), "nothing written on refusal");
}
