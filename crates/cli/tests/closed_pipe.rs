//! A reader of a bad recording, piped into `head -1` with its standard error
//! (`jawtrack metrics bad.jsonl 2>&1 | head -1`), writes to a pipe nobody reads. It must end
//! with its own status (1: the file has no frames), not a panic (101) from printing the
//! warning or the error.

use std::process::{Command, Stdio};

#[test]
fn readers_of_a_bad_recording_end_quietly_on_a_closed_pipe() {
    let dir = tempfile::tempdir().expect("temp dir");
    let bad = dir.path().join("bad.jsonl");
    std::fs::write(&bad, "not json\n{\"frame\":\n").expect("writing the bad recording");
    let bad = bad.to_str().expect("utf-8 path");
    let commands: [&[&str]; 6] = [
        &["metrics", bad],
        &["hinge-axis", bad],
        &["export", bad, "--csv", "--out", "-"],
        &["articulator", bad, "--protrusion", "0:1"],
        &["report", bad, "--out", "-"],
        &["plot", bad, "--out", "-"],
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
        assert_eq!(status.code(), Some(1), "jawtrack {}: {status}", args.join(" "));
        checked += 1;
    }
    assert_eq!(checked, commands.len());
}
