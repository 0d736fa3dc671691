//! `jawtrack send`: a phone simulator that replays a recording as datagrams, with deliberate
//! loss, reordering and duplication for tests and demos.

use super::KeyArgs;
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_recording::FrameRecord;
use jawtrack_wire::replay::{AckTally, Impairment, replay_summary};
use jawtrack_wire::{PosePacket, Session};
use rand::SeedableRng;
use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Arguments of `jawtrack send`.
#[derive(Args)]
pub(crate) struct SendArgs {
    /// The recording to replay (JSON lines from `jawtrack track`, `receive` or the phone).
    #[arg(long)]
    replay: PathBuf,
    /// Where the receiver listens.
    #[arg(long)]
    to: SocketAddr,
    #[command(flatten)]
    key: KeyArgs,
    /// Datagrams per second.
    #[arg(long, default_value_t = 30.0)]
    rate: f64,
    /// Send this many datagrams, cycling through the recording (default: each frame once).
    #[arg(long)]
    count: Option<u64>,
    /// Probability of dropping a datagram (its sequence number is used, so the receiver sees
    /// a gap). The last datagram is always sent, so every loss is visible.
    #[arg(long, default_value_t = 0.0)]
    loss: f64,
    /// Probability of holding a datagram back and sending it after the next one.
    #[arg(long, default_value_t = 0.0)]
    reorder: f64,
    /// Probability of sending a datagram twice.
    #[arg(long, default_value_t = 0.0)]
    duplicate: f64,
    /// Seed of the loss, reorder and duplicate draws.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub(crate) fn run(a: &SendArgs) -> Result<()> {
    let security = a.key.security()?;
    for (name, p) in [("--loss", a.loss), ("--reorder", a.reorder), ("--duplicate", a.duplicate)] {
        if !(0.0..1.0).contains(&p) {
            bail!("{name} must be a probability in [0, 1), got {p}");
        }
    }
    if !(a.rate.is_finite() && a.rate > 0.0) {
        bail!("--rate must be a positive number of datagrams per second, got {}", a.rate);
    }
    let recording = jawtrack_recording::open(&a.replay)?;
    for (line, why) in &recording.skipped {
        eprintln!("warning: {} line {line} skipped: {why}", a.replay.display());
    }
    let frames: Vec<FrameRecord> = recording.frames;
    if frames.is_empty() {
        bail!("{} holds no frames to replay", a.replay.display());
    }
    let total = a.count.unwrap_or(frames.len() as u64);
    let socket =
        UdpSocket::bind(if a.to.is_ipv4() { "0.0.0.0:0" } else { "[::]:0" }).context("opening a UDP socket")?;
    socket.set_nonblocking(true)?;
    let mut session = Session::new(security);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(a.seed);
    let bar = crate::progress::bar("sending", Some(total), "datagrams");
    let mut impairment = Impairment::new(a.loss, a.reorder, a.duplicate);
    let mut acks = AckTally::default();
    let period = Duration::from_secs_f64(1.0 / a.rate);
    let start = Instant::now();
    let mut buf = [0u8; 2048];
    let transmit = |d: &[u8]| {
        // Loopback drops nothing; a full socket buffer is retried rather than lost.
        while let Err(e) = socket.send_to(d, a.to) {
            if e.kind() != std::io::ErrorKind::WouldBlock {
                return Err(e);
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        Ok(())
    };
    for i in 0..total {
        let due = start + period.mul_f64(i as f64);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let mut record = frames[(i % frames.len() as u64) as usize].clone();
        // Cycled frames keep counting up, as a live session would.
        record.frame = i;
        record.t = i as f64 / a.rate;
        let datagram = session.pose_datagram(&PosePacket::from_record(&record));
        for d in impairment.pass(datagram, i + 1 == total, &mut rng) {
            transmit(&d).context("sending")?;
        }
        while let Ok((n, _)) = socket.recv_from(&mut buf) {
            acks.read(&session, &buf[..n]);
        }
        bar.inc(1);
    }
    // Late acknowledgements of the last datagrams.
    let until = Instant::now() + Duration::from_millis(300);
    while Instant::now() < until {
        match socket.recv_from(&mut buf) {
            Ok((n, _)) => acks.read(&session, &buf[..n]),
            Err(_) => std::thread::sleep(Duration::from_millis(10)),
        }
    }
    bar.finish_and_clear();
    let elapsed = start.elapsed().as_secs_f64();
    let i = &impairment;
    eprintln!(
        "sent {total} frames as {} datagrams in {elapsed:.1} s (session {:#018x}): dropped {}, reordered {}, duplicated {}; {}",
        i.sent,
        session.id(),
        i.dropped,
        i.reordered,
        i.duplicated,
        acks.describe()
    );
    say!("{}", replay_summary(session.id(), total, i, &acks, elapsed));
    Ok(())
}
