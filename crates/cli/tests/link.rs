//! The phone link end to end on loopback: `jawtrack send` → `jawtrack receive`, with loss,
//! reordering and duplication whose counts must come out exact; forged, replayed and random
//! datagrams that must all be refused; and a receiver killed mid-session whose recording must
//! read back.

use jawtrack_pose::Pose;
use jawtrack_recording::read_recording;
use jawtrack_wire::{Key, PosePacket, Security, Session, encode_pose, unix_ms};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::net::UdpSocket;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const KEY: &str = "8f1e2d3c4b5a69788796a5b4c3d2e1f00112233445566778899aabbccddeeff0";

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_jawtrack"))
}

/// A receiver on a free port; returns the child and its port once it listens.
fn start_receiver(out: &std::path::Path, extra: &[&str]) -> (Child, u16) {
    // Let the OS pick a free port, then hand it over (a race only with other tests' sockets).
    let port = UdpSocket::bind("127.0.0.1:0").and_then(|s| s.local_addr()).expect("a free port").port();
    let mut child = bin()
        .args(["receive", "--listen", &format!("127.0.0.1:{port}"), "--key", KEY, "--out"])
        .arg(out)
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("receiver starts");
    // Wait for its "listening on" line.
    let mut err = BufReader::new(child.stderr.take().expect("stderr"));
    let mut line = String::new();
    err.read_line(&mut line).expect("receiver speaks");
    assert!(line.contains("listening on"), "{line}");
    std::thread::spawn(move || std::io::copy(&mut err, &mut std::io::sink()));
    (child, port)
}

fn summary(child: Child) -> Value {
    let out = child.wait_with_output().expect("receiver exits");
    assert!(out.status.success(), "receiver failed");
    let text = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(text.lines().last().expect("a summary line")).expect("summary JSON")
}

/// A small recording to replay.
fn recording(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("poses.jsonl");
    let o = bin()
        .args(["track", "--intrinsics", "1500,1500,959.5,539.5", "--out"])
        .arg(&path)
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/static-1080p"))
        .output()
        .expect("track runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    path
}

#[test]
fn losses_reordering_and_duplicates_are_counted_exactly() {
    let dir = tempfile::tempdir().expect("temp dir");
    let poses = recording(dir.path());
    let out = dir.path().join("received.jsonl");
    let (receiver, port) = start_receiver(&out, &["--idle-exit", "1"]);
    let sent = bin()
        .args(["send", "--replay"])
        .arg(&poses)
        .args(["--to", &format!("127.0.0.1:{port}"), "--key", KEY, "--rate", "1500", "--count", "3000"])
        .args(["--loss", "0.2", "--reorder", "0.05", "--duplicate", "0.05", "--seed", "7"])
        .output()
        .expect("send runs");
    assert!(sent.status.success(), "{}", String::from_utf8_lossy(&sent.stderr));
    let sent: Value = serde_json::from_slice(&sent.stdout).expect("send summary");
    let got = summary(receiver);
    eprintln!("sent {sent}\nreceived {got}");
    assert!(sent["dropped"].as_u64().expect("dropped") > 400, "about 20% of 3000 dropped");
    for (theirs, ours) in [("dropped", "lost"), ("reordered", "reordered"), ("duplicated", "duplicated")] {
        assert_eq!(sent[theirs], got[ours], "{ours}");
    }
    assert_eq!(got["received"], sent["datagrams_sent"]);
    assert_eq!(got["rejected"], 0);
    assert!(sent["acks"].as_u64().is_some_and(|n| n > 0), "the sender heard acknowledgements");
    // Every accepted frame is in the file once, in the track schema, behind a header.
    let rec = read_recording(BufReader::new(std::fs::File::open(&out).expect("recording"))).expect("readable");
    assert!(rec.skipped.is_empty(), "{:?}", rec.skipped);
    assert_eq!(rec.frames.len() as u64, got["accepted"].as_u64().expect("accepted"));
    let header = rec.header.expect("a header line");
    assert_eq!(header.key_id.as_deref(), Some(KEY.parse::<Key>().expect("key").id().as_str()));
    assert!(!std::fs::read_to_string(&out).expect("text").contains(KEY), "the key never reaches the file");
    let mut seqs: Vec<u64> = rec.frames.iter().map(|f| f.seq.expect("seq")).collect();
    seqs.sort_unstable();
    seqs.dedup();
    assert_eq!(seqs.len(), rec.frames.len(), "no sequence number twice");
}

fn packet(i: u64) -> PosePacket {
    let pose = Pose::from_axis_angle(Vector3::new(0.1 * i as f64, 0.0, 0.0), Vector3::new(0.0, 40.0, 0.0));
    PosePacket {
        t: i as f64 / 30.0,
        frame: i,
        maxilla: None,
        mandible: None,
        maxilla_from_mandible: Some(pose),
        flags: 0,
    }
}

#[test]
fn forged_replayed_and_random_datagrams_are_all_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("received.jsonl");
    let (receiver, port) = start_receiver(&out, &["--idle-exit", "1.5"]);
    let to = format!("127.0.0.1:{port}");
    let socket = UdpSocket::bind("127.0.0.1:0").expect("socket");
    let key: Key = KEY.parse().expect("key");
    let mut session = Session::new(Security::Sealed(key.clone()));
    let genuine: Vec<Vec<u8>> = (0..10).map(|i| session.pose_datagram(&packet(i))).collect();
    for d in &genuine {
        socket.send_to(d, &to).expect("send");
    }
    std::thread::sleep(Duration::from_millis(100));
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut rejected = 0u64;
    // Replays of what was accepted: duplicates, never recorded again.
    for d in &genuine {
        socket.send_to(d, &to).expect("send");
    }
    // Forgeries: another key; a genuine datagram with one bit flipped; plaintext.
    let other = Security::Sealed(Key::from_bytes([7; 32]));
    for i in 0..200u64 {
        let mut forged = encode_pose((session.id(), 100 + i, unix_ms()), &packet(i), &other);
        if i % 2 == 0 {
            forged = genuine[(i % 10) as usize].clone();
            let bit = rng.random_range(0..forged.len() * 8);
            forged[bit / 8] ^= 1 << (bit % 8);
        }
        socket.send_to(&forged, &to).expect("send");
        rejected += 1;
        let clear = encode_pose((session.id(), 500 + i, unix_ms()), &packet(i), &Security::Plaintext);
        socket.send_to(&clear, &to).expect("send");
        rejected += 1;
        std::thread::sleep(Duration::from_micros(100));
    }
    // Random bytes of every length, some with the right magic and version.
    for i in 0..20_000u32 {
        let n = rng.random_range(0..600);
        let mut d: Vec<u8> = (0..n).map(|_| rng.random()).collect();
        if i % 3 == 0 && n >= 8 {
            d[..5].copy_from_slice(b"JAWT\x01");
        }
        socket.send_to(&d, &to).expect("send");
        rejected += 1;
        if i % 20 == 0 {
            // Keep loopback's queue from overflowing (a datagram the kernel drops is never seen).
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    // Still alive and still accepting.
    std::thread::sleep(Duration::from_millis(100));
    socket.send_to(&session.pose_datagram(&packet(10)), &to).expect("send");
    let got = summary(receiver);
    eprintln!("{got}");
    assert_eq!(got["accepted"], 11, "the genuine datagrams and nothing else");
    assert_eq!(got["duplicated"], 10, "the replays");
    assert_eq!(got["rejected"], rejected, "every forgery and random datagram counted as rejected");
    assert_eq!(got["received"], 21 + rejected);
    let rec = read_recording(BufReader::new(std::fs::File::open(&out).expect("recording"))).expect("readable");
    assert_eq!(rec.frames.len(), 11);
}

#[test]
fn a_receiver_killed_mid_session_leaves_a_readable_recording() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("received.jsonl");
    let (mut receiver, port) = start_receiver(&out, &[]);
    let socket = UdpSocket::bind("127.0.0.1:0").expect("socket");
    let mut session = Session::new(Security::Sealed(KEY.parse().expect("key")));
    let start = Instant::now();
    let mut i = 0;
    while start.elapsed() < Duration::from_millis(700) {
        socket.send_to(&session.pose_datagram(&packet(i)), format!("127.0.0.1:{port}")).expect("send");
        i += 1;
        std::thread::sleep(Duration::from_micros(300));
    }
    // SIGKILL: no chance to flush or close anything.
    receiver.kill().expect("kill -9");
    receiver.wait().expect("reaped");
    let rec = read_recording(BufReader::new(std::fs::File::open(&out).expect("recording"))).expect("readable");
    assert!(rec.header.is_some());
    assert!(rec.frames.len() > 100, "{} of {i} frames on disk", rec.frames.len());
    assert!(rec.skipped.len() <= 1, "at most the line being written is cut: {:?}", rec.skipped);
    assert!(
        rec.frames.iter().enumerate().all(|(k, f)| f.seq == Some(k as u64)),
        "every frame up to the kill, in order"
    );
}

#[test]
fn the_link_commands_refuse_bad_input_clearly() {
    let run = |args: &[&str]| bin().args(args).output().expect("runs");
    let check = |o: std::process::Output, needle: &str| {
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success() && e.contains(needle) && !e.contains("panicked"), "wanted '{needle}': {e}");
    };
    check(run(&["receive", "--out", "/tmp/x.jsonl"]), "jawtrack keygen");
    check(run(&["receive", "--out", "/tmp/x.jsonl", "--key", "abc"]), "64 hex digits");
    check(run(&["send", "--replay", "/nonexistent.jsonl", "--to", "127.0.0.1:9", "--key", KEY]), "/nonexistent.jsonl");
    check(run(&["send", "--replay", "x", "--to", "127.0.0.1:9", "--key", KEY, "--loss", "1.5"]), "--loss");
    let key = run(&["keygen"]);
    assert!(key.status.success());
    let hex = String::from_utf8_lossy(&key.stdout).trim().to_owned();
    assert!(hex.parse::<Key>().is_ok(), "keygen prints a key: {hex}");
}

#[test]
fn receive_never_overwrites_and_a_run_that_cannot_start_leaves_no_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let existing = dir.path().join("session.jsonl");
    std::fs::write(&existing, "a patient's session\n").expect("write");
    let o = bin()
        .args(["receive", "--listen", "127.0.0.1:0", "--key", KEY, "--duration", "0.2", "--out"])
        .arg(&existing)
        .output()
        .expect("runs");
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("already exists") && e.contains("--force"), "{e}");
    assert_eq!(std::fs::read_to_string(&existing).expect("read"), "a patient's session\n", "left as it was");

    // The viewer's port is taken: the receiver cannot serve it and must not leave a recording.
    let busy = std::net::TcpListener::bind("127.0.0.1:0").expect("a port");
    let port = busy.local_addr().expect("address").port();
    let fresh = dir.path().join("fresh.jsonl");
    let o = bin()
        .args(["receive", "--listen", "127.0.0.1:0", "--key", KEY, "--duration", "0.2"])
        .args(["--serve", &format!("127.0.0.1:{port}"), "--out"])
        .arg(&fresh)
        .output()
        .expect("runs");
    assert!(!o.status.success(), "a busy viewer port is an error: {}", String::from_utf8_lossy(&o.stderr));
    assert!(!fresh.exists(), "no header-only recording left behind");
}

#[test]
fn a_key_that_cannot_be_written_is_an_error() {
    // /dev/full takes nothing: every write fails with "no space left on device".
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        jawtrack_test_support::say_skipped("no /dev/full here: the full-disk check of keygen");
        return;
    };
    let o = bin().arg("keygen").stdout(full).output().expect("runs");
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "keygen on a full disk must fail: {e}");
    assert!(e.contains("writing to standard output"), "{e}");
}

#[test]
fn a_viewer_served_beyond_this_computer_is_warned_about() {
    let dir = tempfile::tempdir().expect("temp dir");
    let o = bin()
        .args(["receive", "--listen", "127.0.0.1:0", "--key", KEY, "--duration", "0.2", "--serve", "0.0.0.0:0"])
        .arg("--out")
        .arg(dir.path().join("session.jsonl"))
        .output()
        .expect("runs");
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("open to the network with no password"), "{e}");
    let o = bin()
        .args(["receive", "--listen", "127.0.0.1:0", "--key", KEY, "--duration", "0.2", "--serve", "127.0.0.1:0"])
        .arg("--out")
        .arg(dir.path().join("local.jsonl"))
        .output()
        .expect("runs");
    assert!(!String::from_utf8_lossy(&o.stderr).contains("open to the network"), "no warning on loopback");
}
