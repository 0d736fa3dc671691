//! A reader of a bad file, piped into `head -1` with its standard error
//! (`jawtrack metrics bad.jsonl 2>&1 | head -1`), writes to a pipe nobody reads. It must end
//! with its own status (1: the file is unusable), not a panic (101) from printing the
//! warning or the error. Every subcommand that reads a file is tried.

use std::process::{Command, Stdio};

#[test]
fn readers_of_a_bad_recording_end_quietly_on_a_closed_pipe() {
    let dir = tempfile::tempdir().expect("temp dir");
    let bad = dir.path().join("bad.jsonl");
    std::fs::write(&bad, "not json\n{\"frame\":\n").expect("writing the bad recording");
    let bad = bad.to_str().expect("utf-8 path");
    let (png, stl) = (dir.path().join("bad.png"), dir.path().join("bad.stl"));
    std::fs::write(&png, "not an image").expect("writing the bad image");
    std::fs::write(&stl, "solid nothing\n").expect("writing the bad mesh");
    let (png, stl) = (png.to_str().expect("utf-8 path"), stl.to_str().expect("utf-8 path"));
    let out = |name: &str| dir.path().join(name).to_str().expect("utf-8 path").to_owned();
    let (track_out, marker_out, camera_out, reg_out, contacts_out) =
        (out("t.jsonl"), out("m.json"), out("c.json"), out("r.json"), out("contacts"));
    let key = "00".repeat(32);
    let commands: [&[&str]; 16] = [
        &["metrics", bad],
        &["hinge-axis", bad],
        &["export", bad, "--csv", "--out", "-"],
        &["articulator", bad, "--protrusion", "0:1"],
        &["report", bad, "--out", "-"],
        &["plot", bad, "--out", "-"],
        &["view", bad],
        &["check-marker", bad],
        &["points", "--check", bad],
        &["detect", png],
        &["track", "--marker", bad, "--out", &track_out, png],
        &["calibrate-marker", "--intrinsics", "1500,1500,960,540", "--out", &marker_out, png],
        &["calibrate-camera", "--fps", "60", "--out", &camera_out, png],
        &["register", "--marker", bad, "--body", "maxilla", "--scan", stl, "--out", &reg_out],
        &["send", "--replay", bad, "--to", "127.0.0.1:9", "--key", &key],
        &["contacts", "--maxilla", stl, "--mandible", stl, "--poses", bad, "--out", &contacts_out],
    ];
    let mut checked = 0;
    for args in commands {
        // Both streams into one pipe whose reading end is already closed: every write fails.
        let (reader, writer) = std::io::pipe().expect("a pipe");
        drop(reader);
        let status = Command::new(env!("CARGO_BIN_EXE_jawtrack"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(writer.try_clone().expect("a second handle"))
            .stderr(writer)
            .status()
            .expect("the binary runs");
        // 1: the file is unusable; 2: the arguments are (track wants intrinsics first).
        assert!(matches!(status.code(), Some(1 | 2)), "jawtrack {}: {status}", args.join(" "));
        checked += 1;
    }
    assert_eq!(checked, commands.len());
}
