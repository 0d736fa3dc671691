//! `jawtrack view`: a recording replayed in the web viewer (`jawtrack_viewer`), served until
//! Ctrl-C or `--duration`.

use crate::flags::{ViewerArgs, warn_if_exposed};
use anyhow::Result;
use clap::Args;
use jawtrack_session::measures::read_hinge_axis;
use jawtrack_viewer::{LiveServer, LiveState};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// Arguments of `jawtrack view`.
#[derive(Args)]
pub(crate) struct ViewArgs {
    /// The recording to replay (JSON lines).
    recording: PathBuf,
    #[command(flatten)]
    session: crate::flags::SessionArg,
    /// Address to serve the page at.
    #[arg(long, default_value = "127.0.0.1:8080")]
    serve: SocketAddr,
    #[command(flatten)]
    viewer: ViewerArgs,
    /// The anatomical points file (`jawtrack points`, with --registration): the head frame of the
    /// grid and the view buttons, the condyles whose paths are drawn and the incisal point.
    /// Default: the standard harness mounting.
    #[arg(long, value_name = "FILE")]
    points: Option<PathBuf>,
    /// A hinge axis to draw: the JSON `jawtrack hinge-axis --json` printed (its `point` and
    /// `direction`, in the maxilla marker's frame).
    #[arg(long, value_name = "FILE")]
    hinge_axis: Option<PathBuf>,
    /// Stop serving after this many seconds (default: until Ctrl-C).
    #[arg(long)]
    duration: Option<f64>,
}

pub(crate) fn view(a: &ViewArgs) -> Result<()> {
    warn_if_exposed(a.serve);
    let mut options = a.viewer.options()?;
    if let Some(p) = &a.points {
        if options.registration.is_none() {
            anyhow::bail!("--points needs --registration: the points are in the upper scan's frame");
        }
        options.points = Some(jawtrack_session::read_points(p)?);
    }
    options.hinge_axis = a.hinge_axis.as_deref().map(read_hinge_axis).transpose()?;
    let rec = crate::flags::load(&a.recording, a.session)?;
    options.marker = rec.header.as_ref().and_then(|h| h.tracked_marker()).and_then(Result::ok);
    let header = rec.header.as_ref().and_then(|h| serde_json::to_value(h).ok());
    // The one rest rule (`jawtrack_session::rest_of`), as every other command measures from.
    let rest = jawtrack_session::rest_of(&rec, None)?.map(|r| r.pose());
    let state = Arc::new(LiveState::replay(&options, header, &rec.frames, rest)?);
    LiveServer::start(a.serve, state)?;
    tell!("replaying {} frames at http://{}/ (Ctrl-C to stop)", rec.frames.len(), a.serve);
    let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, std::sync::atomic::Ordering::SeqCst))?;
    }
    let start = Instant::now();
    while !stop.load(std::sync::atomic::Ordering::SeqCst)
        && a.duration.is_none_or(|d| start.elapsed().as_secs_f64() < d)
    {
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    Ok(())
}
