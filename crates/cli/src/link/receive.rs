//! `jawtrack receive`: records the sealed pose datagrams the phone streams (one JSON line per
//! accepted frame, flushed as it arrives), counts what was lost, reordered, duplicated or
//! rejected, acknowledges so the phone can show the link is alive, and optionally serves the
//! live viewer.

use super::KeyArgs;
use crate::flags::ViewerArgs;
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_recording::RecordingWriter;
use jawtrack_viewer::{LiveServer, LiveState};
use jawtrack_wire::link::LinkConfig;
use jawtrack_wire::receiver::{Receiver, process_cpu_seconds, reachable_address, recording_header, run_summary};
use jawtrack_wire::{Key, Security, unix_ms};
use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Arguments of `jawtrack receive`.
#[derive(Args)]
pub(crate) struct ReceiveArgs {
    /// Address and UDP port to listen on, e.g. 0.0.0.0:5005 (all interfaces).
    #[arg(long, default_value = "0.0.0.0:5005")]
    listen: SocketAddr,
    #[command(flatten)]
    key: KeyArgs,
    /// The recording to write (JSON lines, the schema of `jawtrack track`).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// Serve the live viewer at this address, e.g. 127.0.0.1:8080.
    #[arg(long)]
    serve: Option<SocketAddr>,
    #[command(flatten)]
    viewer: ViewerArgs,
    /// Stop after this many seconds (default: run until Ctrl-C).
    #[arg(long)]
    duration: Option<f64>,
    /// Stop once nothing has arrived for this many seconds after the first datagram.
    #[arg(long)]
    idle_exit: Option<f64>,
    /// Refuse datagrams whose sender clock is further than this from ours (s); 0 turns the
    /// check off (e.g. to receive a replay of an old capture).
    #[arg(long, default_value_t = 60.0)]
    max_clock_skew: f64,
    /// Show a QR code with this computer's address, the port and the pairing key, for the
    /// phone's settings screen to scan. It shows the key: only where no one else can see.
    #[arg(long)]
    qr: bool,
}

fn show_pairing_qr(listen: SocketAddr, key: &Key) -> Result<()> {
    let uri = jawtrack_wire::pairing_uri(&reachable_address(listen).to_string(), listen.port(), key);
    let code = qrcode::QrCode::new(uri.as_bytes()).context("making the pairing QR code")?;
    let picture = code
        .render::<qrcode::render::unicode::Dense1x2>()
        .dark_color(qrcode::render::unicode::Dense1x2::Light)
        .light_color(qrcode::render::unicode::Dense1x2::Dark)
        .quiet_zone(true)
        .build();
    eprintln!(
        "{picture}\nscan with JawTrack on the phone (Settings → Pair): {}",
        uri.split("&key=").next().unwrap_or("")
    );
    Ok(())
}

/// Refuses times that cannot be, naming the flag.
fn check_times(a: &ReceiveArgs) -> Result<()> {
    if !(a.max_clock_skew.is_finite() && a.max_clock_skew >= 0.0) {
        bail!("--max-clock-skew must be a number of seconds ≥ 0, got {}", a.max_clock_skew);
    }
    for (name, v) in [("--duration", a.duration), ("--idle-exit", a.idle_exit)] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            bail!("{name} must be a positive number of seconds, got {v}");
        }
    }
    Ok(())
}

pub(crate) fn run(a: &ReceiveArgs) -> Result<()> {
    let security = a.key.security()?;
    if security == Security::Plaintext {
        eprintln!("warning: --insecure-plaintext: datagrams are neither authenticated nor encrypted");
    }
    check_times(a)?;
    let viewer = a.viewer.options()?;
    if let Some(addr) = a.serve {
        crate::flags::warn_if_exposed(addr);
    }
    let socket = UdpSocket::bind(a.listen).with_context(|| format!("listening on {}", a.listen))?;
    if a.qr {
        match &security {
            Security::Sealed(key) => show_pairing_qr(socket.local_addr()?, key)?,
            Security::Plaintext => bail!("--qr shows the pairing key: there is none with --insecure-plaintext"),
        }
    }
    socket.set_read_timeout(Some(Duration::from_millis(100)))?;
    // The viewer's port before the file: a run that cannot start leaves no empty recording.
    let live = Arc::new(LiveState::new(&viewer, "live")?);
    let _server = match a.serve {
        Some(addr) => Some(LiveServer::start(addr, live.clone())?),
        None => None,
    };
    let mut out =
        RecordingWriter::create(&a.out, recording_header(a.listen, a.max_clock_skew, &security), a.force.overwrite())
            .map_err(|e| a.force.explain(e))?;
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst)).context("installing the Ctrl-C handler")?;
    }
    eprintln!(
        "listening on {} ({}); recording to {}{}",
        socket.local_addr()?,
        security.key_id().map_or_else(|| "PLAINTEXT".into(), |id| format!("key id {id}")),
        a.out.display(),
        a.serve.map(|s| format!("; viewer at http://{s}/")).unwrap_or_default()
    );

    let config = LinkConfig {
        max_clock_skew_ms: (a.max_clock_skew > 0.0).then_some((a.max_clock_skew * 1e3) as u64),
        ..LinkConfig::default()
    };
    let mut receiver = Receiver::new(config, security, rand::random());
    let started = Instant::now();
    let (mut last_status, mut last_live, mut last_arrival) = (Instant::now(), Instant::now(), None::<Instant>);
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    // Longer than any datagram, so an oversized one shows as a wrong length, not a cut one.
    let mut buf = [0u8; 2048];
    while !stop.load(Ordering::SeqCst) {
        if a.duration.is_some_and(|d| started.elapsed().as_secs_f64() >= d)
            || a.idle_exit.zip(last_arrival).is_some_and(|(idle, t)| t.elapsed().as_secs_f64() >= idle)
        {
            break;
        }
        // The viewer's Calibrate accepted a held bite: its rest goes into the recording (checked
        // every pass: the socket's read timeout keeps passes short when no datagram comes).
        for bite in live.take_bites() {
            out.append_bite(&bite)?;
            eprintln!(
                "bite accepted at t = {:.3} s ({} frames, held within {:.2} mm)",
                bite.t, bite.frames, bite.spread_mm
            );
        }
        if last_live.elapsed() >= Duration::from_millis(500) {
            last_live = Instant::now();
            live.status(&receiver.link().counters(), last_arrival);
        }
        if last_status.elapsed() >= Duration::from_secs(if tty { 1 } else { 10 }) {
            last_status = Instant::now();
            let c = receiver.link().counters();
            if tty {
                eprint!("\r\x1b[K{}", c.describe());
            } else {
                eprintln!("{}", c.describe());
            }
        }
        let (n, from) = match socket.recv_from(&mut buf) {
            Ok(x) => x,
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => continue,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            // ICMP errors from earlier acknowledgements (the phone went away) surface here.
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => continue,
            Err(e) => return Err(e).context("receiving"),
        };
        let now = Instant::now();
        last_arrival = Some(now);
        let got = receiver.datagram(&buf[..n], from, unix_ms(), now);
        if let Some((record, seq)) = got.frame {
            out.append(&record)?;
            live.pose(&record, Some(seq));
        }
        // A phone that vanished is not an error for the receiver.
        if let Some(ack) = got.ack
            && socket.send_to(&ack, from).is_ok()
        {
            receiver.ack_sent(from, now);
        }
    }
    if tty {
        eprintln!();
    }
    let c = receiver.link().counters();
    eprintln!(
        "stopped after {:.1} s: {}; recording in {}",
        started.elapsed().as_secs_f64(),
        c.describe(),
        a.out.display()
    );
    for (reason, n) in &c.rejected {
        eprintln!("  rejected as {reason}: {n}");
    }
    let elapsed = started.elapsed().as_secs_f64();
    say!("{}", run_summary(&c, receiver.acks_sent(), elapsed, process_cpu_seconds()));
    Ok(())
}
