//! `kill -9` of a writer at any moment: `jawtrack track` and `jawtrack receive` killed at
//! several points must leave a file that every reader (the library's, `export`, `metrics`)
//! reads with exactly the whole frame lines written before the kill, never more. A file killed
//! before its first frame holds nothing to measure, and the readers say so.

use jawtrack_pose::Pose;
use jawtrack_wire::{PosePacket, Security, Session};
use nalgebra::Vector3;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};
mod common;
use common::{jawtrack, s, stderr};

const KEY: &str = "8f1e2d3c4b5a69788796a5b4c3d2e1f00112233445566778899aabbccddeeff0";

/// Lines of the file that are whole frames: complete (newline-terminated) JSON lines with a
/// `frame` field.
fn whole_frames(path: &Path) -> usize {
    let bytes = std::fs::read(path).expect("the file is there");
    let complete = match bytes.iter().rposition(|&b| b == b'\n') {
        Some(end) => &bytes[..=end],
        None => &bytes[..0],
    };
    String::from_utf8_lossy(complete)
        .lines()
        .filter(|l| serde_json::from_str::<Value>(l).is_ok_and(|v| v.get("frame").is_some()))
        .count()
}

/// Checks every reader against the file a killed writer left.
fn readers_agree(path: &Path, label: &str) {
    let whole = whole_frames(path);
    let file = std::fs::File::open(path).expect("open");
    let rec = jawtrack_recording::read_recording(BufReader::new(file)).expect("the library reads it");
    assert_eq!(rec.frames.len(), whole, "{label}: the library reads every whole frame, and no more");
    assert!(rec.skipped.len() <= 1, "{label}: at most the line being written is cut: {:?}", rec.skipped);
    let export = jawtrack(&["export", s(path), "--jsonl"]);
    let metrics = jawtrack(&["metrics", s(path), "--json"]);
    if whole == 0 {
        for (name, o) in [("export", &export), ("metrics", &metrics)] {
            assert!(!o.status.success(), "{label}: {name} makes nothing of a file without frames");
            assert!(stderr(o).contains("no frames"), "{label}: {name} says why: {}", stderr(o));
        }
        return;
    }
    assert!(export.status.success(), "{label}: export reads it: {}", stderr(&export));
    let exported = String::from_utf8_lossy(&export.stdout).lines().skip(1).count();
    assert_eq!(exported, whole, "{label}: export writes every whole frame, and no more");
    assert!(stderr(&export).contains(&format!("exported {whole} frames")), "{label}: {}", stderr(&export));
    // Metrics need a jaw pose; every frame here has one.
    assert!(metrics.status.success(), "{label}: metrics reads it: {}", stderr(&metrics));
    let m: Value = serde_json::from_slice(&metrics.stdout).expect("metrics JSON");
    assert_eq!(m["frames_total"].as_u64(), Some(whole as u64), "{label}: metrics counts the whole frames: {m}");
}

fn killed(mut child: Child) -> Output {
    child.kill().expect("kill -9");
    child.wait_with_output().expect("reaped")
}

#[test]
fn track_killed_at_any_moment_leaves_a_file_every_reader_reads_exactly() {
    let set = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p"));
    let dir = tempfile::tempdir().expect("temp dir");
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).expect("frames dir");
    // Enough frames that the run is still going at the last kill.
    for i in 0..120 {
        std::fs::copy(set.join(format!("frame_{:04}.png", i % 6)), frames.join(format!("f{i:03}.png"))).expect("copy");
    }
    for delay_ms in [0, 30, 200, 600, 1500] {
        let out = dir.path().join(format!("killed-{delay_ms}.jsonl"));
        let child = Command::new(env!("CARGO_BIN_EXE_jawtrack"))
            .args(["track", "--intrinsics", "1500,1500,959.5,539.5", "--out", s(&out), s(&frames)])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("track starts");
        std::thread::sleep(Duration::from_millis(delay_ms));
        let o = killed(child);
        assert!(!o.status.success(), "still running when killed at {delay_ms} ms: {}", stderr(&o));
        if !out.exists() {
            // Killed before the file was created: nothing was written, nothing lost.
            continue;
        }
        let label = format!("track killed at {delay_ms} ms ({} whole frames)", whole_frames(&out));
        eprintln!("{label}");
        readers_agree(&out, &label);
    }
}

#[test]
fn receive_killed_at_any_moment_leaves_a_file_every_reader_reads_exactly() {
    let dir = tempfile::tempdir().expect("temp dir");
    let jaw = Pose::from_axis_angle(Vector3::new(0.05, 0.0, 0.0), Vector3::new(0.0, 44.0, 2.0));
    for send_ms in [0, 50, 400] {
        let out = dir.path().join(format!("received-{send_ms}.jsonl"));
        let port = UdpSocket::bind("127.0.0.1:0").and_then(|s| s.local_addr()).expect("a free port").port();
        let mut child = Command::new(env!("CARGO_BIN_EXE_jawtrack"))
            .args(["receive", "--listen", &format!("127.0.0.1:{port}"), "--key", KEY, "--out", s(&out)])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("receiver starts");
        let mut err = BufReader::new(child.stderr.take().expect("stderr"));
        let mut line = String::new();
        err.read_line(&mut line).expect("receiver speaks");
        assert!(line.contains("listening on"), "{line}");
        std::thread::spawn(move || std::io::copy(&mut err, &mut std::io::sink()));
        let socket = UdpSocket::bind("127.0.0.1:0").expect("socket");
        let mut session = Session::new(Security::Sealed(KEY.parse().expect("key")));
        let start = Instant::now();
        let mut i = 0u64;
        while start.elapsed() < Duration::from_millis(send_ms) {
            let packet = PosePacket {
                t: i as f64 / 60.0,
                frame: i,
                maxilla: None,
                mandible: None,
                maxilla_from_mandible: Some(jaw),
                flags: 0,
            };
            socket.send_to(&session.pose_datagram(&packet), format!("127.0.0.1:{port}")).expect("send");
            i += 1;
            std::thread::sleep(Duration::from_micros(500));
        }
        killed(child);
        let label = format!("receive killed after {send_ms} ms of sending ({i} sent)");
        eprintln!("{label}: {} whole frames", whole_frames(&out));
        readers_agree(&out, &label);
    }
}
