//! The guards on what users give by mistake, through the binary: an image as a recording, an
//! ASCII STL without a name, an empty or flat mesh, teeth pushed further into each other than
//! `--max-depth` measures, and the recording a contacts folder was made from.

use jawtrack_occlusion::scenes;
use nalgebra::Point3;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
mod common;
use common::{jawtrack, ok, refused, s};

/// A frame line whose `maxilla_from_mandible` raises the lower scan by `dz` mm.
fn frame(frame: u64, dz: f64) -> String {
    let pose = [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., dz, 0., 0., 0., 1.];
    json!({"frame": frame, "t": frame as f64 * 0.25, "maxilla_from_mandible": pose}).to_string()
}

/// A 10 mm patch facing down at z = 0 as an ASCII STL that begins with a bare `solid`.
fn ascii_patch(dir: &Path) -> PathBuf {
    let mesh = scenes::patch(10.0, 30, 0.0, true);
    let mut text = String::from("solid\n");
    for t in 0..mesh.triangles.len() {
        text += "facet normal 0 0 -1\nouter loop\n";
        for p in mesh.corners(t) {
            text += &format!("vertex {} {} {}\n", p.x, p.y, p.z);
        }
        text += "endloop\nendfacet\n";
    }
    let p = dir.join("upper.stl");
    std::fs::write(&p, text + "endsolid\n").expect("written");
    p
}

/// A 3 mm ball whose top is at z = 0, as binary STL.
fn ball(dir: &Path) -> PathBuf {
    let p = dir.join("lower.stl");
    scenes::sphere(Point3::new(0.0, 0.0, -3.0), 3.0, 40).write_stl_file(&p).expect("written");
    p
}

#[test]
fn an_image_given_as_a_recording_is_named_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let png = dir.path().join("frame.png");
    std::fs::write(&png, b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x01").expect("written");
    let o = jawtrack(&["metrics", s(&png)]);
    refused(&o, &format!("{}: not a recording (JSON lines): it looks like a binary file (PNG image?)", s(&png)));
    let e = common::stderr(&o);
    assert_eq!(e.matches("not a recording").count(), 1, "{e}");
    assert!(!e.contains("UTF-8"), "{e}");
}

#[test]
fn contacts_read_an_ascii_stl_and_warn_when_the_teeth_pass_the_depth_measured() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (upper, lower) = (ascii_patch(dir.path()), ball(dir.path()));
    let poses = dir.path().join("pushed.jsonl");
    std::fs::write(&poses, [frame(0, 0.2), frame(1, 1.0)].join("\n") + "\n").expect("written");
    let out = dir.path().join("contacts");
    let args = ["contacts", "--maxilla", s(&upper), "--mandible", s(&lower), "--poses", s(&poses), "--out", s(&out)];
    let o = jawtrack(&args);
    ok(&o);
    let e = common::stderr(&o);
    assert!(e.contains("warning: deepest contact reached --max-depth 0.5 mm in 1 of 2 frames"), "{e}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).expect("summary")).expect("JSON");
    assert_eq!(
        (summary["recording"]["name"].as_str(), summary["recording"]["frames"].as_u64()),
        (Some("pushed.jsonl"), Some(2))
    );
}

#[test]
fn contacts_refuse_an_empty_or_flat_mesh_naming_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lower = ball(dir.path());
    let poses = dir.path().join("bite.jsonl");
    std::fs::write(&poses, frame(0, 0.0) + "\n").expect("written");
    let run = |upper: &Path| {
        let out = dir.path().join("out");
        jawtrack(&["contacts", "--maxilla", s(upper), "--mandible", s(&lower), "--poses", s(&poses), "--out", s(&out)])
    };
    let empty = dir.path().join("empty.stl");
    std::fs::write(&empty, "").expect("written");
    refused(&run(&empty), &format!("--maxilla: {}: empty file (0 bytes)", s(&empty)));
    let flat = dir.path().join("flat.stl");
    let facet = "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 5 5 5\nvertex 10 10 10\nendloop\nendfacet\n";
    std::fs::write(&flat, format!("solid flat\n{facet}{facet}endsolid flat\n")).expect("written");
    refused(&run(&flat), "all 2 triangles have zero area: is it a point cloud or a broken export?");
}
