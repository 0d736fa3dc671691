//! `jawtrack receive`: records the sealed pose datagrams the phone streams (one JSON line per
//! accepted frame, flushed as it arrives), counts what was lost, reordered, duplicated or
//! rejected, acknowledges so the phone can show the link is alive, and optionally serves the
//! live viewer.

use super::KeyArgs;
use crate::flags::ViewerArgs;
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_recording::{FrameRecord, RecordingWriter};
use jawtrack_viewer::{LiveServer, LiveState};
use jawtrack_wire::link::Counters;
use jawtrack_wire::receiver::{
    ReceiveOptions, ReceiveSink, process_cpu_seconds, reachable_address, receive, recording_header,
};
use jawtrack_wire::{Key, Security};
use std::io::Write as _;
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
    tell!("{picture}\nscan with JawTrack on the phone (Settings → Pair): {}", uri.split("&key=").next().unwrap_or(""));
    Ok(())
}

/// Where `receive` puts what the link gives: the recording, the live viewer and stderr.
struct Sink<'a> {
    out: RecordingWriter<std::fs::File>,
    live: &'a LiveState,
    tty: bool,
}

impl ReceiveSink for Sink<'_> {
    type Error = anyhow::Error;

    fn frame(&mut self, record: &FrameRecord, seq: u64) -> Result<()> {
        self.out.append(record)?;
        self.live.pose(record, Some(seq));
        Ok(())
    }

    /// The viewer's Calibrate accepted a held bite: its rest goes into the recording.
    fn poll(&mut self) -> Result<()> {
        for bite in self.live.take_bites() {
            self.out.append_bite(&bite)?;
            tell!(
                "bite accepted at t = {:.3} s ({} frames, held within {:.2} mm)",
                bite.t,
                bite.frames,
                bite.spread_mm
            );
        }
        Ok(())
    }

    fn live(&mut self, counters: &Counters, last_arrival: Option<Instant>) {
        self.live.status(counters, last_arrival);
    }

    fn report(&mut self, counters: &Counters) {
        if self.tty {
            let _ = write!(std::io::stderr(), "\r\x1b[K{}", counters.describe());
        } else {
            tell!("{}", counters.describe());
        }
    }
}

pub(crate) fn run(a: &ReceiveArgs) -> Result<()> {
    let security = a.key.security()?;
    if security == Security::Plaintext {
        tell!("warning: --insecure-plaintext: datagrams are neither authenticated nor encrypted");
    }
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let &ReceiveArgs { max_clock_skew, duration, idle_exit, .. } = a;
    let report_every = Duration::from_secs(if tty { 1 } else { 10 });
    let options = ReceiveOptions { max_clock_skew, duration, idle_exit, report_every };
    options.check()?;
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
    // The viewer's port before the file: a run that cannot start leaves no empty recording.
    let live = Arc::new(LiveState::new(&viewer, "live")?);
    let _server = a.serve.map(|addr| LiveServer::start(addr, live.clone())).transpose()?;
    let out =
        RecordingWriter::create(&a.out, recording_header(a.listen, a.max_clock_skew, &security), a.force.overwrite())
            .map_err(|e| a.force.explain(e))?;
    let stop = Arc::new(AtomicBool::new(false));
    let on_ctrl_c = stop.clone();
    ctrlc::set_handler(move || on_ctrl_c.store(true, Ordering::SeqCst)).context("installing the Ctrl-C handler")?;
    tell!(
        "listening on {} ({}); recording to {}{}",
        socket.local_addr()?,
        security.key_id().map_or_else(|| "PLAINTEXT".into(), |id| format!("key id {id}")),
        a.out.display(),
        a.serve.map(|s| format!("; viewer at http://{s}/")).unwrap_or_default()
    );
    let got = receive(&socket, security, &options, &stop, &mut Sink { out, live: &live, tty })?;
    if tty {
        tell!();
    }
    let c = &got.counters;
    tell!("stopped after {:.1} s: {}; recording in {}", got.elapsed_s, c.describe(), a.out.display());
    for (reason, n) in &c.rejected {
        tell!("  rejected as {reason}: {n}");
    }
    say!("{}", got.summary(process_cpu_seconds()));
    Ok(())
}
