//! `jawtrack view` and the viewer flags `receive --serve` shares: a recording replayed in the
//! web viewer (`jawtrack_viewer`), served until Ctrl-C or `--duration`.

use anyhow::{Context, Result};
use clap::Args;
use jawtrack_occlusion::Mesh;
use jawtrack_tracker::Registration;
use jawtrack_viewer::{LiveServer, LiveState, ViewerOptions};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// Meshes and page location, shared by `receive` and `view`.
#[derive(Args, Clone)]
pub(crate) struct ViewerArgs {
    /// The upper arch's scan (STL, PLY or OBJ, mm) to show instead of the maxilla marker.
    #[arg(long, requires = "mandible")]
    maxilla: Option<PathBuf>,
    /// The lower arch's scan, placed by each frame's pose of the mandible in the maxilla.
    #[arg(long, requires = "maxilla")]
    mandible: Option<PathBuf>,
    /// The registration file (`jawtrack register`): draws each scan on its marker through it,
    /// so the lower arch sits against the upper in its bite. Without it, the scans are drawn as
    /// if they were in their markers' frames.
    #[arg(long, requires = "maxilla")]
    registration: Option<PathBuf>,
    /// Serve the page from this folder (with three.js installed by `npm ci --prefix viewer`)
    /// instead of the copy built into jawtrack: for working on the page.
    #[arg(long)]
    viewer_dir: Option<PathBuf>,
}

impl ViewerArgs {
    /// The viewer's options, once each mesh has been read as `contacts` reads it: a file the
    /// page could not draw is refused here, naming it, before anything is served.
    pub(crate) fn options(&self) -> Result<ViewerOptions> {
        for (option, path) in [("--maxilla", &self.maxilla), ("--mandible", &self.mandible)] {
            if let Some(p) = path {
                Mesh::load(p).with_context(|| option)?;
            }
        }
        let registration = match &self.registration {
            Some(p) => Some(Registration::load(p).with_context(|| format!("registration file {}", p.display()))?),
            None => None,
        };
        if self.maxilla.is_some() && registration.is_none() {
            eprintln!(
                "warning: --maxilla and --mandible without --registration: the scans are drawn as if they were in \
                 their markers' frames, so unless they were exported so, the lower arch will not sit in its bite; \
                 give the registration file `jawtrack register` wrote"
            );
        }
        Ok(ViewerOptions {
            maxilla: self.maxilla.clone(),
            mandible: self.mandible.clone(),
            registration,
            page_dir: self.viewer_dir.clone(),
        })
    }
}

/// Arguments of `jawtrack view`.
#[derive(Args)]
pub(crate) struct ViewArgs {
    /// The recording to replay (JSON lines).
    recording: PathBuf,
    #[command(flatten)]
    session: crate::export::SessionArg,
    /// Address to serve the page at.
    #[arg(long, default_value = "127.0.0.1:8080")]
    serve: SocketAddr,
    #[command(flatten)]
    viewer: ViewerArgs,
    /// Stop serving after this many seconds (default: until Ctrl-C).
    #[arg(long)]
    duration: Option<f64>,
}

/// Says so when the viewer is served beyond this computer: it has no password, so anyone who
/// can reach the address sees the patient's poses (and, live, can press Calibrate).
pub(crate) fn warn_if_exposed(addr: SocketAddr) {
    if !addr.ip().is_loopback() {
        eprintln!(
            "warning: the viewer at {addr} is open to the network with no password: anyone who can reach it \
             sees the poses (and, live, can press Calibrate); serve on 127.0.0.1 unless the network is trusted"
        );
    }
}

pub(crate) fn view(a: &ViewArgs) -> Result<()> {
    warn_if_exposed(a.serve);
    let options = a.viewer.options()?;
    let rec = crate::export::load(&a.recording, a.session)?;
    let header = rec.header.as_ref().and_then(|h| serde_json::to_value(h).ok());
    let rest = rec.rest(None).map(|b| b.maxilla_from_mandible);
    let state = Arc::new(LiveState::replay(&options, header, &rec.frames, rest)?);
    LiveServer::start(a.serve, state)?;
    eprintln!("replaying {} frames at http://{}/ (Ctrl-C to stop)", rec.frames.len(), a.serve);
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
