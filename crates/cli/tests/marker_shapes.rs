//! A marker of another solid and family from the command line: `marker --solid --family` writes
//! it, `check-marker` names it, `harness --marker` draws it, `synth --marker` renders it and
//! `track --marker` poses it.

mod common;
use common::{jawtrack, ok, refused, s};

#[test]
fn a_cube_marker_in_tag25h9_is_written_checked_drawn_rendered_and_tracked() {
    let dir = tempfile::tempdir().expect("temp dir");
    let marker = dir.path().join("cube.json");
    let out = ok(&jawtrack(&["marker", "--solid", "cube", "--family", "tag25h9", "--edge", "15", "--out", s(&marker)]));
    assert!(out.contains("tag25h9 on a cube, edge 15 mm") && out.contains("12 tags"), "{out}");
    let out = ok(&jawtrack(&["check-marker", s(&marker)]));
    assert!(out.contains("tag25h9 on a cube") && out.contains("maxilla: 6 tags, ids 0 1 2 3 4 5"), "{out}");

    // The harness of the file: its solid's STL, sheets in its family. A cube's one-cell
    // margins leave room for a thin post only, and the refusal says how thin.
    let harness = dir.path().join("harness");
    refused(&jawtrack(&["harness", "--marker", s(&marker), "--out", s(&harness)]), "at most");
    assert!(!harness.exists(), "nothing written on refusal");
    ok(&jawtrack(&["harness", "--marker", s(&marker), "--out", s(&harness), "--post-diameter", "2"]));
    assert!(harness.join("cube-with-post.stl").is_file());
    let sheet = std::fs::read_to_string(harness.join("tags-maxilla.svg")).expect("sheet");
    assert!(sheet.contains("tag25h9 ids 0–5 · cube edge 15 mm"), "the sheet's heading names family and solid");
    refused(&jawtrack(&["harness", "--marker", s(&marker), "--edge", "9", "--out", s(&harness)]), "cannot be used");

    let frames = dir.path().join("frames");
    ok(&jawtrack(&["synth", "--scene", "static", "--marker", s(&marker), "--max-frames", "3", "--out", s(&frames)]));
    let poses = dir.path().join("poses.jsonl");
    let intrinsics = "1500,1500,959.5,539.5"; // the renderer's default camera
    let out =
        ok(&jawtrack(&["track", s(&frames), "--marker", s(&marker), "--intrinsics", intrinsics, "--out", s(&poses)]));
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(&poses)
        .expect("recording")
        .lines()
        .skip(1)
        .map(|l| serde_json::from_str(l).expect("json line"))
        .collect();
    assert_eq!(lines.len(), 3, "three frames recorded: {out}");
    let posed = lines.iter().filter(|l| !l["maxilla_from_mandible"].is_null()).count();
    assert_eq!(posed, 3, "every frame posed: {out}");

    refused(&jawtrack(&["marker", "--solid", "sphere", "--out", s(&dir.path().join("x.json"))]), "dodecahedron, cube");
    refused(&jawtrack(&["marker", "--family", "tag99h1", "--out", s(&dir.path().join("x.json"))]), "tag25h9");
}
