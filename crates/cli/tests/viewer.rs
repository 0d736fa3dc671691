//! The live viewer in headless Chromium: `jawtrack receive --serve` fed by `jawtrack send`, and
//! `jawtrack view` replaying the recording on meshes read from STL files, each checked by `viewer/tests/check.mjs` (the page
//! loads, the mandible moves, no console error, the screenshot is not blank).
//!
//! Needs Chromium (`/usr/bin/chromium`, or `CHROMIUM`) and `npm ci --prefix viewer`; CI
//! installs both. Without them the test says SKIPPED and passes.

use std::io::{BufRead, BufReader};
use std::net::{TcpListener, UdpSocket};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

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
    for p in ["node_modules/three/build/three.module.js", "node_modules/playwright-core/package.json"] {
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

fn check(url: &str, mode: &str, screenshot: &Path) -> Output {
    Command::new("node")
        .arg(viewer_dir().join("tests/check.mjs"))
        .args(["--url", url, "--mode", mode, "--timeout", "60", "--screenshot"])
        .arg(screenshot)
        .output()
        .expect("node runs")
}

#[test]
fn the_viewer_moves_the_mandible_live_and_replays_the_recording() {
    if let Some(why) = missing() {
        eprintln!("SKIPPED: the viewer check: {why}");
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
    let live = check(&format!("http://127.0.0.1:{http}/"), "live", &dir.path().join("live.png"));
    sender.kill().ok();
    sender.wait().ok();
    receiver.kill().ok();
    receiver.wait().ok();
    assert!(live.status.success(), "live check failed:\n{}", String::from_utf8_lossy(&live.stderr));
    eprintln!("live: {}", String::from_utf8_lossy(&live.stdout).trim());

    let http = free_port();
    // The replay shows meshes from files: the harness body (STL) on both jaws.
    let stl = concat!(env!("CARGO_MANIFEST_DIR"), "/../../harness-cad/dodecahedron-with-post.stl");
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
    ]);
    let replay = check(&format!("http://127.0.0.1:{http}/"), "replay", &dir.path().join("replay.png"));
    viewer.kill().ok();
    viewer.wait().ok();
    assert!(replay.status.success(), "replay check failed:\n{}", String::from_utf8_lossy(&replay.stderr));
    eprintln!("replay: {}", String::from_utf8_lossy(&replay.stdout).trim());
}
