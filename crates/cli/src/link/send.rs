//! `jawtrack send`: a phone simulator that replays a recording as datagrams, with deliberate
//! loss, reordering and duplication for tests and demos.

use super::KeyArgs;
use anyhow::{Result, bail};
use clap::Args;
use jawtrack_wire::replay::{ReplayOptions, send_recording};
use std::net::SocketAddr;
use std::path::PathBuf;

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
    let &SendArgs { rate, count, loss, reorder, duplicate, seed, .. } = a;
    let options = ReplayOptions { rate, count, loss, reorder, duplicate, seed };
    options.check()?;
    let recording = jawtrack_recording::open(&a.replay)?;
    for (line, why) in &recording.skipped {
        tell!("warning: {} line {line} skipped: {why}", a.replay.display());
    }
    if recording.frames.is_empty() {
        bail!("{} holds no frames to replay", a.replay.display());
    }
    let bar = crate::progress::bar("sending", Some(options.datagrams(recording.frames.len())), "datagrams");
    let sent = send_recording(&recording.frames, a.to, security, &options, |done| bar.set_position(done))?;
    bar.finish_and_clear();
    tell!("{}", sent.describe());
    say!("{}", sent.summary());
    Ok(())
}
