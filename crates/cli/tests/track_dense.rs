//! `jawtrack track --refine dense`: each body's pose refined from its tags' pixels, recorded in
//! the header; an unknown refinement refused with the choices.

mod common;
use common::{jawtrack, refused, stderr};

#[test]
fn track_refines_from_the_pixels_when_asked_and_says_so_in_the_header() {
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/clean-static-1080p");
    let frame = format!("{set}/frame_0000.png");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("dense.jsonl");
    let out = out.to_str().expect("utf-8 path");
    let k = "1500,1500,959.5,539.5";
    let o = jawtrack(&["track", "--intrinsics", k, "--refine", "dense", "--out", out, &frame]);
    assert!(o.status.success(), "{}", stderr(&o));
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(out)
        .expect("recording written")
        .lines()
        .map(|l| serde_json::from_str(l).expect("json line"))
        .collect();
    assert_eq!(lines.len(), 2, "a header and the frame");
    assert_eq!(lines[0]["recording"]["settings"]["refine"], "dense");
    assert_eq!(lines[1]["flags"], serde_json::json!([]), "refined, nothing to say");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{set}/ground_truth.json")).expect("truth"))
            .expect("json");
    let got: Vec<f64> = serde_json::from_value(lines[1]["maxilla_from_mandible"].clone()).expect("4x4 matrix");
    let want: Vec<f64> = serde_json::from_value(truth["frames"][0]["maxilla_from_mandible"].clone()).expect("truth");
    let d = ((got[3] - want[3]).powi(2) + (got[7] - want[7]).powi(2) + (got[11] - want[11]).powi(2)).sqrt();
    // A clean render of the nominal marker: the jaw within 0.05 mm.
    assert!(d < 0.05, "{d:.4} mm from the truth");
    refused(&jawtrack(&["track", "--intrinsics", k, "--refine", "pixels", "--out", out, &frame]), "corners or dense");
}
