//! The live viewer in headless Chromium: `jawtrack receive --serve` fed by `jawtrack send`, and
//! `jawtrack view` replaying the recording on meshes read from STL files, each checked by `viewer/tests/check.mjs` (the page
//! loads, the mandible moves, no console error, the screenshot is not blank).
//!
//! Needs Chromium (`/usr/bin/chromium`, or `CHROMIUM`) and `npm ci --prefix viewer` (playwright-core,
//! which drives it; three.js is vendored in the page); CI
//! installs both. Without them the test says SKIPPED and passes.

use std::io::{BufRead, BufReader};
use std::net::{TcpListener, UdpSocket};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
mod common;
use common::{identity_bite, jawtrack, refused, s};

/// Each scan a few millimetres and degrees off its marker (row-major 4x4 poses).
const REGISTRATION: &str = r#"{"version": 1, "units": "mm",
    "maxilla_scan_from_maxilla_marker": [0.9950041652780258, -0.09983341664682815, 0, 3, 0.09983341664682815, 0.9950041652780258, 0, -2, 0, 0, 1, 5, 0, 0, 0, 1],
    "mandible_scan_from_mandible_marker": [1, 0, 0, -4, 0, 0.9800665778412416, -0.19866933079506122, 1, 0, 0.19866933079506122, 0.9800665778412416, 2, 0, 0, 0, 1]}"#;

const KEY: &str = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";

fn viewer_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../viewer")
}

/// Why the check cannot run here, if it cannot.
fn missing() -> Option<String> {
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    if !Path::new(&chromium).is_file() {
        return Some(format!("no Chromium at {chromium}"));
    }
    for p in ["node_modules/playwright-core/package.json"] {
        if !viewer_dir().join(p).is_file() {
            return Some(format!("viewer/{p} missing (run `npm ci --prefix viewer`)"));
        }
    }
    Command::new("node").arg("--version").output().err().map(|e| format!("no node: {e}"))
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").and_then(|l| l.local_addr()).expect("a free port").port()
}

fn spawn(args: &[&str]) -> Child {
    let mut child = Command::new(env!("CARGO_BIN_EXE_jawtrack"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("jawtrack starts");
    // Wait until it says where it listens or serves.
    let mut err = BufReader::new(child.stderr.take().expect("stderr"));
    let mut line = String::new();
    err.read_line(&mut line).expect("it speaks");
    assert!(line.contains("http://"), "{line}");
    std::thread::spawn(move || std::io::copy(&mut err, &mut std::io::sink()));
    child
}

fn check(url: &str, mode: &str, screenshot: &Path, expect: &[&str]) -> Output {
    Command::new("node")
        .arg(viewer_dir().join("tests/check.mjs"))
        .args(["--url", url, "--mode", mode, "--timeout", "60", "--screenshot"])
        .arg(screenshot)
        .args(expect)
        .output()
        .expect("node runs")
}

#[test]
fn the_viewer_moves_the_mandible_live_and_replays_the_recording() {
    if let Some(why) = missing() {
        jawtrack_test_support::say_skipped(&format!("the viewer check: {why}"));
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let poses = dir.path().join("hinge.jsonl");
    let set = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/hinge-1080p");
    let o = Command::new(env!("CARGO_BIN_EXE_jawtrack"))
        .args(["track", "--intrinsics", "1500,1500,959.5,539.5", "--out"])
        .arg(&poses)
        .arg(set)
        .output()
        .expect("track");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let udp = UdpSocket::bind("127.0.0.1:0").and_then(|s| s.local_addr()).expect("a free UDP port").port();
    let http = free_port();
    let recording = dir.path().join("received.jsonl");
    let recording_str = recording.to_str().expect("utf-8");
    let mut receiver = spawn(&[
        "receive",
        "--listen",
        &format!("127.0.0.1:{udp}"),
        "--key",
        KEY,
        "--out",
        recording_str,
        "--serve",
        &format!("127.0.0.1:{http}"),
        "--duration",
        "120",
    ]);
    let mut sender = Command::new(env!("CARGO_BIN_EXE_jawtrack"))
        .args(["send", "--replay", poses.to_str().expect("utf-8"), "--to", &format!("127.0.0.1:{udp}")])
        .args(["--key", KEY, "--rate", "60", "--count", "6000"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("send starts");
    let live = check(&format!("http://127.0.0.1:{http}/"), "live", &dir.path().join("live.png"), &[]);
    sender.kill().ok();
    sender.wait().ok();
    receiver.kill().ok();
    receiver.wait().ok();
    assert!(live.status.success(), "live check failed:\n{}", String::from_utf8_lossy(&live.stderr));
    eprintln!("live: {}", String::from_utf8_lossy(&live.stdout).trim());

    let http = free_port();
    // The replay shows meshes from files: the harness body (STL) on both jaws, each placed on
    // its marker by a registration (check.mjs checks each is drawn where it says).
    let stl = concat!(env!("CARGO_MANIFEST_DIR"), "/../../harness-cad/dodecahedron-with-post.stl");
    let registration = dir.path().join("registration.json");
    std::fs::write(&registration, REGISTRATION).expect("write");
    // A hinge axis as `jawtrack hinge-axis --json` prints it.
    let axis = dir.path().join("axis.json");
    std::fs::write(&axis, r#"{"point": [0, 2, -133], "direction": [-1, 0, 0], "frame": "maxilla marker"}"#)
        .expect("write");
    let mut viewer = spawn(&[
        "view",
        recording_str,
        "--serve",
        &format!("127.0.0.1:{http}"),
        "--duration",
        "120",
        "--maxilla",
        stl,
        "--mandible",
        stl,
        "--registration",
        s(&registration),
        "--hinge-axis",
        s(&axis),
    ]);
    let replay =
        check(&format!("http://127.0.0.1:{http}/"), "replay", &dir.path().join("replay.png"), &["--expect-hinge-axis"]);
    viewer.kill().ok();
    viewer.wait().ok();
    assert!(replay.status.success(), "replay check failed:\n{}", String::from_utf8_lossy(&replay.stderr));
    eprintln!("replay: {}", String::from_utf8_lossy(&replay.stdout).trim());
    if let Ok(keep) = std::env::var("JAWTRACK_KEEP_REPORT") {
        std::fs::copy(dir.path().join("replay.png"), Path::new(&keep).join("viewer-replay.png")).expect("copy");
    }

    // The arches `jawtrack contacts` coloured by their deepest contact.
    let found = contacts_folder(dir.path());
    let http = free_port();
    let mut viewer = spawn(&[
        "view",
        recording_str,
        "--serve",
        &format!("127.0.0.1:{http}"),
        "--duration",
        "120",
        "--contacts",
        s(&found),
        "--registration",
        s(&registration),
    ]);
    let coloured =
        check(&format!("http://127.0.0.1:{http}/"), "replay", &dir.path().join("contacts.png"), &["--expect-coloured"]);
    viewer.kill().ok();
    viewer.wait().ok();
    assert!(coloured.status.success(), "contacts check failed:\n{}", String::from_utf8_lossy(&coloured.stderr));
}

/// A `jawtrack contacts` folder: a ball pressed 0.2 mm into a flat patch.
fn contacts_folder(dir: &Path) -> PathBuf {
    use jawtrack_occlusion::scenes;
    let upper = dir.join("upper.ply");
    scenes::patch(10.0, 60, 0.0, true).write_coloured_ply(&upper, &[]).expect("write");
    let lower = dir.join("lower.ply");
    scenes::sphere(nalgebra::Point3::new(0.0, 0.0, -1.8), 2.0, 30).write_coloured_ply(&lower, &[]).expect("write");
    let poses = identity_bite(dir);
    let out = dir.join("contacts");
    let o = jawtrack(&[
        "contacts",
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&lower),
        "--poses",
        s(&poses),
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

/// A short recording of a still jaw, enough for `view` to serve.
fn still_recording(dir: &Path) -> PathBuf {
    let path = dir.join("still.jsonl");
    let identity = "[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]";
    let lines: Vec<String> = (0..3)
        .map(|k| {
            format!(r#"{{"frame":{k},"t":{k},"maxilla":null,"mandible":null,"maxilla_from_mandible":{identity}}}"#)
        })
        .collect();
    std::fs::write(&path, lines.join("\n") + "\n").expect("write");
    path
}

#[test]
fn view_refuses_a_mesh_it_cannot_show_before_serving() {
    let dir = tempfile::tempdir().expect("temp dir");
    let recording = still_recording(dir.path());
    let good = concat!(env!("CARGO_MANIFEST_DIR"), "/../../harness-cad/dodecahedron-with-post.stl");
    let photo = dir.path().join("photo.stl");
    let frame = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/hinge-1080p/frame_0000.png");
    std::fs::copy(frame, &photo).expect("a photo renamed .stl");
    let empty = dir.path().join("empty.ply");
    std::fs::write(&empty, "").expect("write");
    // One triangle 20 units across: a tooth scan exported in metres would be 20 km.
    let metres = dir.path().join("metres.stl");
    std::fs::write(
        &metres,
        "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 20000 0 0\nvertex 0 20000 0\nendloop\nendfacet\nendsolid t\n",
    )
    .expect("write");
    let serve = format!("127.0.0.1:{}", free_port());
    let missing = dir.path().join("missing-registration.json");
    let o = jawtrack(&[
        "view",
        s(&recording),
        "--serve",
        &serve,
        "--duration",
        "1",
        "--maxilla",
        good,
        "--mandible",
        good,
        "--registration",
        s(&missing),
    ]);
    refused(&o, "missing-registration.json");
    for (option, bad, why) in [
        ("--maxilla", &photo, "not a readable STL mesh"),
        ("--mandible", &empty, "empty.ply"),
        ("--mandible", &metres, "convert the file to mm"),
    ] {
        let other = if option == "--maxilla" { "--mandible" } else { "--maxilla" };
        let serve = format!("127.0.0.1:{}", free_port());
        let o = jawtrack(&["view", s(&recording), "--serve", &serve, "--duration", "1", option, s(bad), other, good]);
        refused(&o, why);
        let e = common::stderr(&o);
        assert!(e.contains(option) && e.contains(s(bad)) && !e.contains("replaying"), "{e}");
        let o = jawtrack(&[
            "receive",
            "--listen",
            "127.0.0.1:0",
            "--key",
            KEY,
            "--out",
            s(&dir.path().join("r.jsonl")),
            "--serve",
            &serve,
            "--duration",
            "1",
            option,
            s(bad),
            other,
            good,
        ]);
        refused(&o, why);
        assert!(common::stderr(&o).contains(option), "{}", common::stderr(&o));
    }
}
