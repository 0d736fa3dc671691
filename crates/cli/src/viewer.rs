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
    /// The upper arch's scan (STL, PLY or OBJ, mm) to show beside the maxilla marker.
    #[arg(long, requires = "mandible", conflicts_with = "contacts")]
    maxilla: Option<PathBuf>,
    /// The lower arch's scan, placed by each frame's pose of the mandible in the maxilla.
    #[arg(long, requires = "maxilla")]
    mandible: Option<PathBuf>,
    /// The folder `jawtrack contacts` wrote: shows its arches coloured by their deepest
    /// contact (maxilla_depth.ply, mandible_depth.ply) instead of --maxilla and --mandible.
    #[arg(long, value_name = "DIR", requires = "registration")]
    contacts: Option<PathBuf>,
    /// The registration file (`jawtrack register`): draws each scan on its marker through it,
    /// so the lower arch sits against the upper in its bite. Without it, the scans are drawn as
    /// if they were in their markers' frames.
    #[arg(long)]
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
        let coloured = self.contacts.as_ref().map(|d| [d.join("maxilla_depth.ply"), d.join("mandible_depth.ply")]);
        let (maxilla, mandible) = match &coloured {
            Some([u, l]) => (Some(u.clone()), Some(l.clone())),
            None => (self.maxilla.clone(), self.mandible.clone()),
        };
        if self.registration.is_some() && maxilla.is_none() {
            anyhow::bail!("--registration places scans: give --maxilla and --mandible, or --contacts DIR");
        }
        for (option, path) in [("--maxilla", &maxilla), ("--mandible", &mandible)] {
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
            maxilla,
            mandible,
            registration,
            page_dir: self.viewer_dir.clone(),
            coloured: coloured.is_some(),
            ..ViewerOptions::default()
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

/// The `point` and unit `direction` of `jawtrack hinge-axis --json`'s output.
fn read_hinge_axis(path: &std::path::Path) -> Result<([f64; 3], [f64; 3])> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading --hinge-axis {}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("--hinge-axis {}: not the JSON of `jawtrack hinge-axis --json`", path.display()))?;
    let xyz = |key: &str| -> Result<[f64; 3]> {
        let a: Vec<f64> =
            v[key].as_array().map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect()).unwrap_or_default();
        match a[..] {
            [x, y, z] if a.iter().all(|c| c.is_finite()) => Ok([x, y, z]),
            _ => anyhow::bail!(
                "--hinge-axis {}: no \"{key}\" of three numbers (the output of `jawtrack hinge-axis --json`)",
                path.display()
            ),
        }
    };
    let (point, d) = (xyz("point")?, xyz("direction")?);
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(n > 0.5 && n < 1.5) {
        anyhow::bail!("--hinge-axis {}: its direction is not a unit vector (length {n})", path.display());
    }
    Ok((point, d.map(|c| c / n)))
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
    let mut options = a.viewer.options()?;
    if let Some(p) = &a.points {
        if options.registration.is_none() {
            anyhow::bail!("--points needs --registration: the points are in the upper scan's frame");
        }
        options.points = Some(crate::points::read(p)?);
    }
    options.hinge_axis = a.hinge_axis.as_deref().map(read_hinge_axis).transpose()?;
    let rec = crate::export::load(&a.recording, a.session)?;
    options.marker = rec
        .header
        .as_ref()
        .and_then(|h| h.marker.as_ref())
        .and_then(|m| jawtrack_marker::Marker::from_json(&m.to_string()).ok());
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
