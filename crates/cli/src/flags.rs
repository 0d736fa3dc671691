//! Flags several commands share (`--session`, `--points`, the movement windows, the viewer's),
//! and the glue that turns them into the libraries' calls and prints their warnings.

use anyhow::{Context, Result};
use jawtrack_kinematics::Anatomy;
use jawtrack_kinematics::Window;
use jawtrack_pose::Pose;
use jawtrack_recording::{Recording, SessionId};
use jawtrack_registration::Registration;
use jawtrack_session::SessionError;
use jawtrack_session::incisor::ChosenIncisor;
use jawtrack_session::movements::MovementWindows;
use std::path::{Path, PathBuf};

/// `--session`, for the commands that read a recording: one session's frames. A file holding
/// several sessions (a receiver that ran while the phone started and stopped transmitting) is
/// refused without it, since their frames would mix.
#[derive(clap::Args, Clone, Copy, Debug)]
pub(crate) struct SessionArg {
    /// Read only this session's frames (its 16-hex-digit id, as `"session"` in every frame);
    /// needed when the file holds several.
    #[arg(long, value_name = "ID")]
    pub(crate) session: Option<SessionId>,
}

/// How tag edges are fitted, for the commands that detect tags.
#[derive(clap::Args, Clone, Copy, Debug)]
pub(crate) struct EdgeArgs {
    /// Fit tag edges in linear light, JawTrack's way; false fits them as the C library does,
    /// in the frames' own values.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub(crate) linear_edges: bool,
    /// The camera's tone curve, undone to reach linear light: auto (estimated from the tags' edges,
    /// sRGB until they tell), srgb, gamma:G (a plain power law, e.g. gamma:1.8) or s-curve:G:C.
    #[arg(long, default_value = "auto", value_name = "CURVE")]
    pub(crate) tone: jawtrack_apriltag::ToneSetting,
}

/// The `--points` flag.
#[derive(clap::Args, Clone, Debug)]
pub(crate) struct PointsArg {
    /// The anatomical points file (`jawtrack points`): the patient's occlusal plane, midline,
    /// lower incisal point and condyles, picked on the upper scan; needs --registration.
    /// Default: the standard harness mounting.
    #[arg(long, value_name = "FILE")]
    pub(crate) points: Option<PathBuf>,
}

/// Which lower incisal point the displacements are of, for `metrics` and `plot` (the report
/// and `view` take `--points` and `--registration` too; `export` has its own).
#[derive(clap::Args, Clone, Debug)]
pub(crate) struct IncisorArgs {
    /// The anatomical points file (`jawtrack points`): its lower incisal point and its head
    /// frame (occlusal plane, midline); needs --registration. Default: the standard mounting.
    #[arg(long, value_name = "FILE", requires = "registration")]
    pub(crate) points: Option<PathBuf>,
    /// The registration file (`jawtrack register`) that places the points file's upper scan on
    /// the maxilla marker.
    #[arg(long, value_name = "FILE", requires = "points")]
    pub(crate) registration: Option<PathBuf>,
    /// The incisal point X,Y,Z in the mandible marker's frame (mm), in place of the points
    /// file's or the standard harness mounting's.
    #[arg(long, value_name = "X,Y,Z", value_parser = crate::numbers::parse_point, allow_hyphen_values = true)]
    pub(crate) incisor: Option<[f64; 3]>,
}

impl IncisorArgs {
    /// The point chosen (`jawtrack_session::incisor::ChosenIncisor`), its head frame placed
    /// with the jaw at `rest`; prints the anatomy's warnings.
    pub(crate) fn choose(&self, rest: &Pose) -> Result<ChosenIncisor> {
        let reg = registration(self.registration.as_deref())?;
        let a = anatomy(self.points.as_deref(), reg.as_ref(), rest)?;
        Ok(ChosenIncisor::of(&a, self.incisor)?)
    }
}

/// Opens `path`'s session (`jawtrack_session::open`), printing the skipped lines.
pub(crate) fn load(path: &Path, only: SessionArg) -> Result<Recording> {
    let opened = jawtrack_session::open(path, only.session).inspect_err(|e| {
        if let SessionError::NoFrames { warnings, .. } = e {
            warnings.iter().for_each(|w| tell!("warning: {w}"));
        }
    })?;
    for w in &opened.warnings {
        tell!("warning: {w}");
    }
    Ok(opened.recording)
}

/// The anatomy (`jawtrack_session::anatomy`), printing its warnings.
pub(crate) fn anatomy(points: Option<&Path>, registration: Option<&Registration>, rest: &Pose) -> Result<Anatomy> {
    let a = jawtrack_session::anatomy(points, registration, rest)?;
    for w in &a.warnings {
        tell!("warning: {w}");
    }
    Ok(a)
}

/// Reads `--registration` when given.
pub(crate) fn registration(path: Option<&Path>) -> Result<Option<Registration>> {
    Ok(jawtrack_session::read_registration(path)?)
}

/// Where each movement was made in a recording, FROM:TO in seconds of the frames' `t`: the
/// flags `articulator` and `report` share.
#[derive(clap::Args, Clone, Copy, Debug)]
pub(crate) struct MovementArgs {
    /// The protrusion's window, FROM:TO (s): the condylar inclination per side and the
    /// protrusive incisal guidance.
    #[arg(long, value_name = "FROM:TO", value_parser = Window::parse)]
    pub(crate) protrusion: Option<Window>,
    /// The laterotrusion toward the patient's left (s): the right condyle's Bennett angle and
    /// side shift, the lateral guidance toward the left.
    #[arg(long, value_name = "FROM:TO", value_parser = Window::parse)]
    pub(crate) left: Option<Window>,
    /// The laterotrusion toward the patient's right (s): the left condyle's Bennett angle and
    /// side shift, the lateral guidance toward the right.
    #[arg(long, value_name = "FROM:TO", value_parser = Window::parse)]
    pub(crate) right: Option<Window>,
    /// The jaw held in centric occlusion (s): guided back into centric relation and closed to
    /// the first tooth contact. With it, the CO–MI slide into the bite is measured.
    #[arg(long, value_name = "FROM:TO", value_parser = Window::parse)]
    pub(crate) co: Option<Window>,
    /// The jaw held in maximal intercuspation (s), for --co; default: the closed jaw (--rest-frame,
    /// else the bite accepted while recording, else the first frame with a jaw pose).
    #[arg(long, value_name = "FROM:TO", value_parser = Window::parse, requires = "co")]
    pub(crate) mi: Option<Window>,
}

impl MovementArgs {
    /// The windows, for `jawtrack_session::movements`.
    pub(crate) fn windows(self) -> MovementWindows {
        MovementWindows { protrusion: self.protrusion, left: self.left, right: self.right, co: self.co, mi: self.mi }
    }

    /// Whether a border movement is given.
    pub(crate) fn any_border(self) -> bool {
        self.windows().any_border()
    }
}

/// Prints a warning when `rec` was tracked with the nominal marker (`what`: what moved).
pub(crate) fn warn_if_nominal(rec: &Recording, what: &str) {
    if let Some(w) = jawtrack_session::movements::nominal_marker_warning(rec, what) {
        tell!("warning: {w}");
    }
}

/// Meshes and page location, shared by `receive` and `view`.
#[derive(clap::Args, Clone)]
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
    /// Serve the page from this folder (the repository's `viewer`, with three.js vendored)
    /// instead of the copy built into jawtrack: for working on the page.
    #[arg(long)]
    viewer_dir: Option<PathBuf>,
}

impl ViewerArgs {
    /// The viewer's options, once each mesh has been read as `contacts` reads it: a file the
    /// page could not draw is refused here, naming it, before anything is served.
    pub(crate) fn options(&self) -> Result<jawtrack_viewer::ViewerOptions> {
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
                jawtrack_occlusion::load_mesh(p).with_context(|| option)?;
            }
        }
        let registration = registration(self.registration.as_deref())?;
        if self.maxilla.is_some() && registration.is_none() {
            tell!(
                "warning: --maxilla and --mandible without --registration: the scans are drawn as if they were in \
                 their markers' frames, so unless they were exported so, the lower arch will not sit in its bite; \
                 give the registration file `jawtrack register` wrote"
            );
        }
        Ok(jawtrack_viewer::ViewerOptions {
            maxilla,
            mandible,
            registration,
            page_dir: self.viewer_dir.clone(),
            coloured: coloured.is_some(),
            ..jawtrack_viewer::ViewerOptions::default()
        })
    }
}

/// Says so when the viewer is served beyond this computer: it has no password, so anyone who
/// can reach the address sees the patient's poses (and, live, can press Calibrate).
pub(crate) fn warn_if_exposed(addr: std::net::SocketAddr) {
    if !addr.ip().is_loopback() {
        tell!(
            "warning: the viewer at {addr} is open to the network with no password: anyone who can reach it \
             sees the poses (and, live, can press Calibrate); serve on 127.0.0.1 unless the network is trusted"
        );
    }
}
