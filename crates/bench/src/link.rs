//! `jawtrack-bench link`: the phone link's targets measured on loopback against a real
//! `jawtrack receive` process (the `jawtrack` built beside this binary).
//!
//! 1. Soak: sealed pose datagrams at `--rate` for `--duration`; the receiver must accept every
//!    one sent, record each (the file read back), and its CPU time over the run is its share of
//!    one core.
//! 2. Garbage: `--random` datagrams of random bytes (a third starting with the right magic and
//!    version), forgeries under another key, bit-flipped genuine datagrams and replays; the
//!    receiver must stay up, count every one as rejected or duplicated, accept none of them,
//!    and still accept a genuine datagram afterwards.

use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_pose::Pose;
use jawtrack_recording::Recording;
use jawtrack_wire::replay::{ReplayOptions, send_packets};
use jawtrack_wire::{Key, PacketBody, PosePacket, Security, Session, encode_pose, unix_ms};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::net::{SocketAddr, UdpSocket};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// Arguments of `jawtrack-bench link`.
#[derive(Args)]
pub(crate) struct LinkBenchArgs {
    /// Datagrams per second in the soak.
    #[arg(long, default_value_t = 240.0)]
    rate: f64,
    /// Length of the soak (s).
    #[arg(long, default_value_t = 600.0)]
    duration: f64,
    /// Random datagrams in the garbage phase.
    #[arg(long, default_value_t = 1_000_000)]
    random: u64,
    /// A short run (10 s soak, 20 000 random datagrams) for CI.
    #[arg(long)]
    quick: bool,
    /// Folder for the receivers' recordings.
    #[arg(long, default_value = "target/bench-link")]
    out: PathBuf,
}

/// A `jawtrack receive` child listening on a free loopback port.
struct Receiver {
    child: Child,
    port: u16,
}

impl Receiver {
    fn start(key: &Key, out: &Path) -> Result<Receiver> {
        let port = UdpSocket::bind("127.0.0.1:0")?.local_addr()?.port();
        // The bench's own scratch recording, replaced on every run: hence --force.
        let mut child = Command::new(jawtrack()?)
            .args(["receive", "--listen", &format!("127.0.0.1:{port}"), "--idle-exit", "2", "--force", "--out"])
            .arg(out)
            .env("JAWTRACK_KEY", key.to_hex())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .context("starting `jawtrack receive`")?;
        let mut err = BufReader::new(child.stderr.take().context("the receiver's stderr")?);
        let mut line = String::new();
        err.read_line(&mut line)?;
        if !line.contains("listening on") {
            bail!("the receiver did not start: {line}");
        }
        std::thread::spawn(move || std::io::copy(&mut err, &mut std::io::sink()));
        Ok(Receiver { child, port })
    }

    fn to(&self) -> SocketAddr {
        SocketAddr::from(([127, 0, 0, 1], self.port))
    }

    /// Waits for the receiver to go idle and exit; its summary.
    fn finish(self) -> Result<Value> {
        let out = self.child.wait_with_output()?;
        if !out.status.success() {
            bail!("the receiver failed (exit {:?})", out.status.code());
        }
        let text = String::from_utf8_lossy(&out.stdout);
        serde_json::from_str(text.lines().last().context("no summary from the receiver")?)
            .context("the receiver's summary")
    }
}

/// The `jawtrack` binary built beside this one (`cargo build --release` builds both).
fn jawtrack() -> Result<PathBuf> {
    let me = std::env::current_exe().context("finding this program")?;
    let beside = me.with_file_name(format!("jawtrack{}", std::env::consts::EXE_SUFFIX));
    if !beside.is_file() {
        bail!(
            "no jawtrack binary beside {} to start `jawtrack receive` with: build it first (`cargo build --release`)",
            me.display()
        );
    }
    Ok(beside)
}

/// A jaw opening and closing once a second, both bodies tracked.
fn packet(i: u64, rate: f64) -> PosePacket {
    let t = i as f64 / rate;
    let angle = 0.2 * (0.5 - 0.5 * (std::f64::consts::TAU * t).cos());
    let body = |y: f64| PacketBody {
        camera_from_body: Pose::from_axis_angle(Vector3::new(0.0, 0.3, 0.0), Vector3::new(0.0, y, 100.0)),
        tags_mask: 0b111,
        tag_count: 3,
        rms_px: 0.2,
    };
    PosePacket {
        t,
        frame: i,
        maxilla: Some(body(-22.0)),
        mandible: Some(body(22.0)),
        maxilla_from_mandible: Some(Pose::from_axis_angle(Vector3::new(angle, 0.0, 0.0), Vector3::new(0.0, 44.0, 0.0))),
        flags: 0,
    }
}

pub(crate) fn run(a: &LinkBenchArgs) -> Result<()> {
    let (duration, random) = if a.quick { (10.0, 20_000) } else { (a.duration, a.random) };
    if !(a.rate.is_finite() && a.rate > 0.0 && duration.is_finite() && duration > 0.0) {
        bail!("--rate and --duration must be positive");
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let key = Key::generate();
    let soak = soak(&key, &a.out.join("soak.jsonl"), a.rate, duration)?;
    let garbage = garbage(&key, &a.out.join("garbage.jsonl"), random)?;
    print_table(a.rate, duration, random, &soak, &garbage);
    if !(soak.ok() && garbage.ok()) {
        bail!("the link missed a target (see the table)");
    }
    if soak.cpu_share.is_some_and(|c| c >= 0.05) {
        bail!("the receiver used {:.1}% of a core (target < 5%)", soak.cpu_share.unwrap_or(0.0) * 100.0);
    }
    Ok(())
}

/// What the soak gave: the datagrams sent, the receiver's summary and recording, the
/// acknowledgements heard and the receiver's share of one core.
struct Soak {
    total: u64,
    summary: Value,
    recorded: Recording,
    acks: u64,
    cpu_share: Option<f64>,
}

impl Soak {
    /// Every datagram accepted and recorded, none lost.
    fn ok(&self) -> bool {
        self.summary["accepted"].as_u64() == Some(self.total)
            && self.summary["lost"] == 0
            && self.recorded.frames.len() as u64 == self.total
            && self.recorded.skipped.is_empty()
    }
}

/// Phase 1, the soak: sealed pose datagrams at `rate` for `duration` (s) to a receiver
/// recording to `file`.
fn soak(key: &Key, file: &Path, rate: f64, duration: f64) -> Result<Soak> {
    let receiver = Receiver::start(key, file)?;
    let total = (rate * duration).round() as u64;
    let bar = crate::progress_bar("soak", total, "datagrams");
    let options = ReplayOptions { rate, ..ReplayOptions::default() };
    let security = Security::Sealed(key.clone());
    let sent = send_packets(receiver.to(), security, &options, total, |i| packet(i, rate), |n| bar.set_position(n))?;
    bar.finish_and_clear();
    let summary = receiver.finish()?;
    let recorded = jawtrack_recording::open(file)?;
    // Over the soak itself: the receiver's idle second before it exits adds no CPU time.
    let cpu_share = summary["cpu_s"].as_f64().map(|c| c / duration);
    Ok(Soak { total, summary, recorded, acks: sent.acks.read, cpu_share })
}

/// What the garbage phase gave: the receiver's summary, the datagrams that must have been
/// rejected, the replays sent, and how many of those were refused as stale.
struct Garbage {
    summary: Value,
    sent: u64,
    rejected: u64,
    replays: u64,
    stale: u64,
}

impl Garbage {
    /// The genuine datagrams accepted, everything else counted as rejected or duplicated.
    fn ok(&self) -> bool {
        let g = &self.summary;
        g["accepted"] == 101
            && g["duplicated"].as_u64().map(|d| d + self.stale) == Some(self.replays)
            && g["rejected"].as_u64() == Some(self.rejected + self.stale)
            && g["received"].as_u64() == Some(self.sent)
    }
}

/// Phase 2: `random` datagrams of garbage, forgeries and replays, then a genuine one, to a
/// receiver recording to `file`.
fn garbage(key: &Key, file: &Path, random: u64) -> Result<Garbage> {
    let socket = UdpSocket::bind("127.0.0.1:0")?;
    socket.set_nonblocking(true)?;
    let receiver = Receiver::start(key, file)?;
    let mut session = Session::new(Security::Sealed(key.clone()));
    let genuine: Vec<Vec<u8>> = (0..100).map(|i| session.pose_datagram(&packet(i, 30.0))).collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let (mut rejected, mut replays, mut sent) = (0u64, 0u64, 0u64);
    let bar = crate::progress_bar("garbage", random, "datagrams");
    let send = |d: &[u8], sent: &mut u64| -> Result<()> {
        // Paced so that loopback's queue never overflows: a datagram the kernel drops would
        // never be counted, and the comparison in `Garbage::ok` would fail.
        if sent.is_multiple_of(20) {
            std::thread::sleep(Duration::from_millis(1));
        }
        *sent += 1;
        socket.send_to(d, receiver.to()).map(|_| ()).context("sending")
    };
    for d in &genuine {
        send(d, &mut sent)?;
    }
    let other = Security::Sealed(Key::generate());
    for i in 0..random {
        send(&garbage_datagram(i, &mut rng, &session, &genuine, &other), &mut sent)?;
        rejected += 1;
        if i % 1000 == 0 {
            send(&genuine[(i / 1000 % 100) as usize], &mut sent)?;
            replays += 1;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    std::thread::sleep(Duration::from_millis(100));
    socket.send_to(&session.pose_datagram(&packet(100, 30.0)), receiver.to())?;
    sent += 1;
    let summary = receiver.finish()?;
    // A replay is refused as a duplicate, or as stale once its datagram is older than the
    // receiver's clock-skew bound (a long garbage phase outlasts it).
    let stale = summary["rejected_by_reason"]["stale"].as_u64().unwrap_or(0);
    Ok(Garbage { summary, sent, rejected, replays, stale })
}

/// The `i`th datagram the receiver must reject: random bytes (a third starting with the right
/// magic and version), or, one in a hundred, a forgery under `other` key or one of the
/// `genuine` datagrams with one bit flipped.
fn garbage_datagram(i: u64, rng: &mut impl Rng, session: &Session, genuine: &[Vec<u8>], other: &Security) -> Vec<u8> {
    let n = rng.random_range(0..600);
    let mut d: Vec<u8> = (0..n).map(|_| rng.random()).collect();
    if i.is_multiple_of(3) && n >= 5 {
        d[..5].copy_from_slice(b"JAWT\x01");
    }
    if i.is_multiple_of(100) {
        d = encode_pose((session.id(), 1000 + i, unix_ms()), &packet(i, 30.0), other);
        if i.is_multiple_of(200) {
            d = genuine[(i / 200 % 100) as usize].clone();
            let bit = rng.random_range(0..d.len() * 8);
            d[bit / 8] ^= 1 << (bit % 8);
        }
    }
    d
}

/// The results as a Markdown table on stdout.
fn print_table(rate: f64, duration: f64, random: u64, soak: &Soak, garbage: &Garbage) {
    let (total, s, acks) = (soak.total, &soak.summary, soak.acks);
    let (g, replays, rejected, stale) = (&garbage.summary, garbage.replays, garbage.rejected, garbage.stale);
    println!("| measure | target | result |");
    println!("|---|---|---|");
    println!(
        "| soak: {total} sealed datagrams at {rate} /s for {duration:.0} s | all accepted and recorded | sent {total}, accepted {}, lost {}, recorded {} frames ({} unreadable lines); {acks} acknowledgements |",
        s["accepted"],
        s["lost"],
        soak.recorded.frames.len(),
        soak.recorded.skipped.len()
    );
    println!(
        "| receiver CPU during the soak | < 5% of one core | {} ({} s CPU over the {duration:.0} s soak) |",
        soak.cpu_share.map_or("unknown (no /proc)".into(), |c| format!("{:.2}%", c * 100.0)),
        s["cpu_s"],
    );
    println!(
        "| {random} random datagrams (1% forged or bit-flipped) + {replays} replays | 0 accepted, all counted | accepted {} (the 101 genuine); the replays refused as duplicates ({}) or stale ({stale}); rejected {} = {rejected} + {stale}; by reason {} |",
        g["accepted"], g["duplicated"], g["rejected"], g["rejected_by_reason"]
    );
}
