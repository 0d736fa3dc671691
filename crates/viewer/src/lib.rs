//! The web viewer's server: the page (`viewer/` in the repository, embedded in this library at
//! build time with the three.js modules it imports), the scene (the two meshes, or the marker
//! file's solid at its edge when no scan is given; the markers' tags; the head frame for the
//! grid and the view buttons; a hinge axis), live poses over a WebSocket for
//! `jawtrack receive --serve`, and a whole recording for `jawtrack view` (with each frame's
//! incisor and condyles).
//!
//! The readouts (opening, lateral and protrusive displacement of the lower incisor) are
//! computed here, not in the browser (`jawtrack_kinematics`), from the rest position, which
//! the "Calibrate" button sets to the mean of the last frames while the patient bites in
//! maximal intercuspation, if the tracker's one rule accepts them as a held bite
//! (`jawtrack_registration::bite`); the first frame until then. Replayed, the recording's own rest
//! (its last bite line) is used when it has one. Bites accepted live are handed to the
//! receiver ([`LiveState::take_bites`]) to be written into the recording.

use axum::Router;
use axum::extract::ws::{Message as WsMessage, WebSocket, WebSocketUpgrade};
use axum::extract::{Path as UrlPath, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Json, Response};
use axum::routing::get;
use jawtrack_kinematics::{AnatomicalPoints, Incisor, Mounting, Side};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::Pose;
use jawtrack_recording::{BiteRecord, FrameRecord, SessionId};
use jawtrack_registration::Registration;
use jawtrack_registration::{BiteRule, BiteWindow};
use jawtrack_wire::link::Counters;
use serde_json::{Value, json};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use tower_http::services::{ServeDir, ServeFile};

mod page {
    include!(concat!(env!("OUT_DIR"), "/page.rs"));
}

/// Why the viewer could not start.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    /// A scan the viewer cannot show.
    #[error("{path}: {reason}")]
    Mesh {
        /// The mesh file, as given.
        path: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A page folder given instead of the embedded page lacks a file.
    #[error("the viewer page is not ready in {dir}: {missing} is missing (give the repository's `viewer` folder)")]
    PageDirIncomplete {
        /// The folder.
        dir: String,
        /// The file it lacks.
        missing: String,
    },
    /// The address could not be served (taken, or not this machine's).
    #[error("serving the viewer on {addr}: {source}")]
    Bind {
        /// The address.
        addr: SocketAddr,
        /// What the system said.
        source: std::io::Error,
    },
    /// The server's thread or runtime could not start.
    #[error("starting the viewer's server: {0}")]
    Start(std::io::Error),
}

/// What the viewer shows besides the poses.
#[derive(Debug, Clone, Default)]
pub struct ViewerOptions {
    /// The upper arch's scan (STL, PLY or OBJ, mm) to show instead of the maxilla marker.
    pub maxilla: Option<PathBuf>,
    /// The lower arch's scan, placed by each frame's pose of the mandible in the maxilla.
    pub mandible: Option<PathBuf>,
    /// How each scan sits on its marker (`jawtrack register`): with it, each scan is drawn in
    /// its marker's frame through the inverse of its registration, so the lower scan sits
    /// against the upper as `Registration::maxilla_scan_from_mandible_scan` places it (in its
    /// bite at rest). Without it, the scans are drawn as if given in their markers' frames.
    pub registration: Option<Registration>,
    /// Serve the page from this folder (the repository's `viewer`, three.js in `vendor/three`) instead of the
    /// copy built into the program: for working on the page.
    pub page_dir: Option<PathBuf>,
    /// The anatomical points (`jawtrack points`), with `registration`: the head frame, the
    /// condyles and the incisal point of a replay. Default: the standard harness mounting.
    pub points: Option<AnatomicalPoints>,
    /// A hinge axis to draw (`jawtrack hinge-axis`): a point and a unit direction in the
    /// maxilla marker's frame (mm).
    pub hinge_axis: Option<([f64; 3], [f64; 3])>,
    /// The marker whose solid and tags are drawn; default: the nominal one.
    pub marker: Option<Marker>,
    /// The meshes carry per-vertex colours to show as they are (the contact maps `jawtrack
    /// contacts` writes), not the viewer's own.
    pub coloured: bool,
}

/// What the viewer shows, and the poses it moves by.
pub struct LiveState {
    mode: &'static str,
    page_dir: Option<PathBuf>,
    meshes: [Option<(PathBuf, &'static str)>; 2],
    /// Per mesh, its marker's frame from the scan's (the inverse of its registration).
    marker_from_scan: [Option<Pose>; 2],
    tx: tokio::sync::broadcast::Sender<Arc<str>>,
    inner: Mutex<Inner>,
    recording: Option<Value>,
    /// The head frame, condyles and incisal point the readouts and paths use.
    mounting: Mounting,
    incisor: Incisor,
    /// The condyles, carried like the incisor, left then right.
    condyles: [Incisor; 2],
    /// What the scene adds to the meshes: tags, hinge axis, colours.
    marker: Marker,
    hinge_axis: Option<([f64; 3], [f64; 3])>,
    coloured: bool,
}

struct Inner {
    bite: BiteWindow,
    /// The session of the last frame, for the bites accepted.
    session: Option<SessionId>,
    /// Bites accepted and not yet taken by the receiver.
    accepted: Vec<BiteRecord>,
    rest: Option<Pose>,
    /// The last status's time and accepted count, for the rate.
    last_status: Option<(Instant, u64)>,
}

fn mesh_format(path: &Path) -> Result<&'static str, ViewerError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("stl") => Ok("stl"),
        Some("ply") => Ok("ply"),
        Some("obj") => Ok("obj"),
        _ => Err(ViewerError::Mesh {
            path: path.display().to_string(),
            reason: "the viewer reads STL, PLY or OBJ meshes (by file extension)".into(),
        }),
    }
}

impl LiveState {
    /// A state for `mode` (`live` or `replay`), checking the meshes it is to show.
    pub fn new(options: &ViewerOptions, mode: &'static str) -> Result<Self, ViewerError> {
        let mut meshes = [None, None];
        for (slot, path) in meshes.iter_mut().zip([&options.maxilla, &options.mandible]) {
            if let Some(p) = path {
                let format = mesh_format(p)?;
                if !p.is_file() {
                    return Err(ViewerError::Mesh {
                        path: p.display().to_string(),
                        reason: "no such mesh file".into(),
                    });
                }
                *slot = Some((p.clone(), format));
            }
        }
        let marker_from_scan = options.registration.as_ref().map_or([None, None], |r| {
            [Some(r.maxilla_scan_from_maxilla_marker.inverse()), Some(r.mandible_scan_from_mandible_marker.inverse())]
        });
        Ok(LiveState {
            mode,
            page_dir: options.page_dir.clone(),
            meshes,
            marker_from_scan,
            tx: tokio::sync::broadcast::channel(256).0,
            inner: Mutex::new(Inner {
                bite: BiteWindow::new(BiteRule::default()),
                session: None,
                accepted: Vec::new(),
                rest: None,
                last_status: None,
            }),
            recording: None,
            mounting: Mounting::default(),
            incisor: Incisor::standard(),
            condyles: condyles_of(Mounting::default()),
            marker: options.marker.clone().unwrap_or_default(),
            hinge_axis: options.hinge_axis,
            coloured: options.coloured,
        })
    }

    /// A state for replaying `frames` (`jawtrack view`), measured from `rest` (the caller's
    /// rest position: `jawtrack_session::rest_of`); without one, nothing is measured until the
    /// Calibrate step sets it.
    pub fn replay(
        options: &ViewerOptions,
        header: Option<Value>,
        frames: &[FrameRecord],
        rest: Option<Pose>,
    ) -> Result<Self, ViewerError> {
        let mut state = LiveState::new(options, "replay")?;
        // The patient's anatomy needs the closed jaw, known only when replaying.
        if let (Some(points), Some(reg), Some(r)) = (&options.points, &options.registration, rest) {
            state.mounting = points.mounting(&reg.maxilla_scan_from_maxilla_marker, &r);
            state.incisor = Incisor::of(state.mounting);
            state.condyles = condyles_of(state.mounting);
        }
        state.inner.get_mut().unwrap_or_else(std::sync::PoisonError::into_inner).rest = rest;
        let list: Vec<Value> = frames.iter().map(|f| state.frame_message(f, f.seq, rest.as_ref())).collect();
        state.recording = Some(json!({ "header": header, "frames": list }));
        Ok(state)
    }

    /// The replay as `/api/recording` serves it (`None` live): `{"header", "frames": [{"type":
    /// "pose", "frame", "t", "opening_mm", "lateral_mm", "protrusive_mm", …}]}`.
    pub fn replay_json(&self) -> Option<&Value> {
        self.recording.as_ref()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A panic elsewhere cannot leave these few poses inconsistent: keep serving.
        self.inner.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The lower incisor in the scene (maxilla) frame, and its displacement from `rest` as
    /// (opening, lateral toward the patient's left, protrusive) in mm.
    fn readouts(&self, m: &Pose, rest: Option<&Pose>) -> (Value, [Option<f64>; 3]) {
        let p = self.incisor.in_maxilla(m);
        let d = rest.map(|r| self.incisor.displacement(m, r));
        (json!([p.x, p.y, p.z]), [d.map(|d| d.opening), d.map(|d| d.lateral), d.map(|d| d.protrusive)])
    }

    fn frame_message(&self, f: &FrameRecord, seq: Option<u64>, rest: Option<&Pose>) -> Value {
        let tags = |b: &Option<jawtrack_recording::BodyRecord>| b.as_ref().map_or(0, |b| b.tags.len());
        let (incisor, [opening, lateral, protrusive]) = match &f.maxilla_from_mandible {
            Some(m) => self.readouts(m, rest),
            None => (Value::Null, [None; 3]),
        };
        let condyles = f.maxilla_from_mandible.map(|m| {
            self.condyles.map(|c| {
                let p = c.in_maxilla(&m);
                [p.x, p.y, p.z]
            })
        });
        json!({
            "type": "pose",
            "frame": f.frame,
            "seq": seq,
            "t": f.t,
            "maxilla_from_mandible": f.maxilla_from_mandible,
            "incisor": incisor,
            "condyles": condyles,
            "opening_mm": opening,
            "lateral_mm": lateral,
            "protrusive_mm": protrusive,
            "tags": {"maxilla": tags(&f.maxilla), "mandible": tags(&f.mandible)},
        })
    }

    /// A frame arrived: remember it and show it.
    pub fn pose(&self, f: &FrameRecord, seq: Option<u64>) {
        let rest = {
            let mut inner = self.lock();
            if let Some(m) = f.maxilla_from_mandible {
                inner.rest.get_or_insert(m);
            }
            inner.bite.push(f.t, f.maxilla_from_mandible);
            inner.session = f.session;
            inner.rest
        };
        if self.tx.receiver_count() > 0 {
            // Only an absent viewer makes this fail.
            let _ = self.tx.send(self.frame_message(f, seq, rest.as_ref()).to_string().into());
        }
    }

    /// The link's counts, for the status badge.
    pub fn status(&self, c: &Counters, last_arrival: Option<Instant>) {
        let link = match last_arrival.map(|t| t.elapsed().as_secs_f64()) {
            None => "waiting",
            Some(s) if s < 1.0 => "up",
            Some(_) => "stale",
        };
        let expected = c.accepted + c.lost;
        let now = Instant::now();
        let rate = self.lock().last_status.replace((now, c.accepted)).map_or(0.0, |(then, accepted)| {
            (c.accepted - accepted) as f64 / now.duration_since(then).as_secs_f64().max(1e-3)
        });
        let mut message = c.to_json();
        message["type"] = "status".into();
        message["link"] = link.into();
        message["rate_hz"] = rate.into();
        message["loss_percent"] = (if expected > 0 { 100.0 * c.lost as f64 / expected as f64 } else { 0.0 }).into();
        if self.tx.receiver_count() > 0 {
            let _ = self.tx.send(message.to_string().into());
        }
    }

    /// The maximal-intercuspation step: if the last frames are a held bite, their mean becomes
    /// the rest position, and the bite is queued for the recording.
    fn calibrate(&self) -> Value {
        let mut inner = self.lock();
        match inner.bite.judge() {
            Ok(bite) => {
                let mean = bite.maxilla_from_mandible;
                let moved = inner.rest.map(|r| (self.incisor.in_head(&mean) - self.incisor.in_head(&r)).norm());
                inner.rest = Some(mean);
                let session = inner.session;
                inner.accepted.push(BiteRecord {
                    session,
                    t: bite.t,
                    maxilla_from_mandible: mean,
                    frames: bite.frames as u64,
                    span_s: bite.span_s,
                    spread_mm: bite.spread_mm,
                    spread_deg: bite.spread_deg,
                });
                json!({"type": "calibrated", "ok": true, "message": format!(
                    "rest position set from {} frames over {:.2} s, held within {:.2} mm{}",
                    bite.frames, bite.span_s, bite.spread_mm,
                    moved.map(|d| format!(" (the incisor's rest moved {d:.2} mm)")).unwrap_or_default())})
            }
            Err(refusal) => json!({"type": "calibrated", "ok": false, "message": refusal.to_string()}),
        }
    }

    /// The bites accepted since the last call, for the receiver to write into the recording.
    pub fn take_bites(&self) -> Vec<BiteRecord> {
        std::mem::take(&mut self.lock().accepted)
    }

    fn scene(&self) -> Value {
        let mesh = |i: usize, name: &str| match &self.meshes[i] {
            Some((_, format)) => json!({
                "format": format, "url": format!("/api/mesh/{name}"), "marker_from_mesh": self.marker_from_scan[i],
                "coloured": self.coloured,
            }),
            None => solid_mesh(&self.marker),
        };
        let tags = |kind: BodyKind| -> Vec<Value> {
            self.marker
                .tags()
                .filter(|(k, _)| *k == kind)
                .map(|(_, t)| {
                    let n = t.face_normal();
                    json!({
                        "id": t.id,
                        "corners": t.corners.iter().map(|c| [c.x, c.y, c.z]).collect::<Vec<_>>(),
                        "centre": [t.center.x, t.center.y, t.center.z],
                        "normal": [n.x, n.y, n.z],
                    })
                })
                .collect()
        };
        json!({
            "mode": self.mode,
            "maxilla": mesh(0, "maxilla"),
            "mandible": mesh(1, "mandible"),
            "maxilla_from_mandible_rest": self.lock().rest,
            "marker_solid": solid_mesh(&self.marker),
            "tags": {"maxilla": tags(BodyKind::Maxilla), "mandible": tags(BodyKind::Mandible)},
            "maxilla_from_head": self.mounting.head_from_maxilla.inverse(),
            "hinge_axis": self.hinge_axis.map(|(p, d)| json!({"point": p, "direction": d})),
        })
    }
}

/// The condyles of `m` as points of the mandible, left then right.
fn condyles_of(m: Mounting) -> [Incisor; 2] {
    [Side::Left, Side::Right].map(|side| Incisor::fixed_at(m, &m.condyle(side)))
}

/// The marker's solid (its kind and edge) as inline triangles (body frame, mm).
fn solid_mesh(marker: &Marker) -> Value {
    let solid = marker.geometry();
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    for face in solid.faces() {
        let base = positions.len() / 3;
        for v in &face.vertices {
            positions.extend([v.x, v.y, v.z]);
        }
        // Each face is convex: a fan from its first corner.
        for k in 1..face.vertices.len() - 1 {
            indices.extend([base, base + k, base + k + 1]);
        }
    }
    json!({"format": "mesh", "positions": positions, "indices": indices})
}

/// The running web server (on its own thread; it ends with the process).
pub struct LiveServer;

impl LiveServer {
    /// Binds `addr` now (so a taken port is reported at once) and serves on a thread.
    pub fn start(addr: SocketAddr, state: Arc<LiveState>) -> Result<LiveServer, ViewerError> {
        let mut app = Router::new();
        match &state.page_dir {
            Some(dir) => {
                for needed in
                    ["index.html", "viewer.js", "anatomy.js", "style.css", "vendor/three/build/three.module.js"]
                {
                    if !dir.join(needed).is_file() {
                        return Err(ViewerError::PageDirIncomplete {
                            dir: dir.display().to_string(),
                            missing: needed.into(),
                        });
                    }
                }
                app = app
                    .route_service("/", ServeFile::new(dir.join("index.html")))
                    .route_service("/viewer.js", ServeFile::new(dir.join("viewer.js")))
                    .route_service("/anatomy.js", ServeFile::new(dir.join("anatomy.js")))
                    .route_service("/pick.js", ServeFile::new(dir.join("pick.js")))
                    .route_service("/style.css", ServeFile::new(dir.join("style.css")))
                    .nest_service("/vendor/three", ServeDir::new(dir.join("vendor/three")));
            }
            None => {
                for &(url, content_type, bytes) in page::FILES {
                    let serve = move || async move { ([(header::CONTENT_TYPE, content_type)], bytes) };
                    app = app.route(url, get(serve));
                    if url == "/index.html" {
                        app = app.route("/", get(serve));
                    }
                }
            }
        }
        let app = app
            .route("/api/scene", get(|State(s): State<Arc<LiveState>>| async move { Json(s.scene()) }))
            .route("/api/mesh/{body}", get(mesh))
            .route("/api/recording", get(recording))
            .route("/ws", get(socket))
            .with_state(state);
        let listener = std::net::TcpListener::bind(addr).map_err(|source| ViewerError::Bind { addr, source })?;
        listener.set_nonblocking(true).map_err(ViewerError::Start)?;
        let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().map_err(ViewerError::Start)?;
        std::thread::Builder::new()
            .name("viewer".into())
            .spawn(move || {
                // Not `eprintln!`: it panics when standard error is closed.
                use std::io::Write as _;
                runtime.block_on(async move {
                    match tokio::net::TcpListener::from_std(listener) {
                        Ok(l) => {
                            if let Err(e) = axum::serve(l, app).await {
                                let _ = writeln!(std::io::stderr(), "viewer server stopped: {e}");
                            }
                        }
                        Err(e) => {
                            let _ = writeln!(std::io::stderr(), "viewer server could not start: {e}");
                        }
                    }
                });
            })
            .map_err(ViewerError::Start)?;
        Ok(LiveServer)
    }
}

async fn mesh(State(s): State<Arc<LiveState>>, UrlPath(body): UrlPath<String>) -> Response {
    let slot = match body.as_str() {
        "maxilla" => 0,
        "mandible" => 1,
        _ => return (StatusCode::NOT_FOUND, "no such body").into_response(),
    };
    match &s.meshes[slot] {
        Some((path, _)) => match tokio::fs::read(path).await {
            Ok(bytes) => ([(header::CONTENT_TYPE, "application/octet-stream")], bytes).into_response(),
            Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, format!("{}: {e}", path.display())).into_response(),
        },
        None => (StatusCode::NOT_FOUND, "no mesh file given for this body").into_response(),
    }
}

async fn recording(State(s): State<Arc<LiveState>>) -> Response {
    match &s.recording {
        Some(r) => Json(r.clone()).into_response(),
        None => (StatusCode::NOT_FOUND, "live mode: poses come over /ws").into_response(),
    }
}

async fn socket(State(s): State<Arc<LiveState>>, upgrade: WebSocketUpgrade) -> Response {
    upgrade.on_upgrade(move |ws| session(ws, s))
}

async fn session(mut ws: WebSocket, s: Arc<LiveState>) {
    let mut poses = s.tx.subscribe();
    loop {
        tokio::select! {
            out = poses.recv() => match out {
                Ok(text) => if ws.send(WsMessage::Text(text.as_ref().into())).await.is_err() { return },
                // A slow browser skips frames rather than holding the receiver back.
                Err(tokio::sync::broadcast::error::RecvError::Lagged(_)) => continue,
                Err(tokio::sync::broadcast::error::RecvError::Closed) => return,
            },
            incoming = ws.recv() => match incoming {
                Some(Ok(WsMessage::Text(text))) => {
                    let asked: Value = serde_json::from_str(text.as_str()).unwrap_or(Value::Null);
                    if asked["type"] == "calibrate_intercuspation" {
                        let reply = s.calibrate().to_string();
                        if ws.send(WsMessage::Text(reply.into())).await.is_err() { return }
                    }
                }
                Some(Ok(_)) => {}
                Some(Err(_)) | None => return,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn options() -> ViewerOptions {
        ViewerOptions::default()
    }

    fn frame(opening_rad: f64) -> FrameRecord {
        timed(opening_rad, 0.0)
    }

    /// A frame at `t` (s) with the jaw opened by `opening_rad`.
    fn timed(opening_rad: f64, t: f64) -> FrameRecord {
        let m = Pose::from_axis_angle(Vector3::new(opening_rad, 0.0, 0.0), Vector3::new(0.0, 44.0, 0.0));
        FrameRecord {
            frame: 0,
            session: None,
            path: None,
            t,
            exposure_s: None,
            lens_position: None,
            maxilla: None,
            mandible: None,
            maxilla_from_mandible: Some(m),
            maxilla_scan_from_mandible_scan: None,
            flags: Vec::new(),
            searched: None,
            timings_s: None,
            seq: None,
            received_unix_s: None,
            tone: None,
        }
    }

    #[test]
    fn the_calibration_step_sets_the_rest_only_from_a_held_bite_and_queues_it_for_the_recording() {
        let state = LiveState::new(&options(), "live").expect("state");
        state.pose(&timed(0.2, 0.0), Some(0));
        state.pose(&timed(0.0, 1.0 / 30.0), Some(1));
        let refused = state.calibrate();
        assert_eq!(refused["ok"], false, "{refused}");
        assert!(refused["message"].as_str().is_some_and(|m| m.contains("needs 8 frames")), "{refused}");
        // Pressed while the jaw closes: refused, and the rest stays where it was.
        for i in 2u32..20 {
            state.pose(&timed(0.3 - 0.015 * f64::from(i), f64::from(i) / 30.0), Some(u64::from(i)));
        }
        let moving = state.calibrate();
        assert_eq!(moving["ok"], false, "{moving}");
        assert!(moving["message"].as_str().is_some_and(|m| m.contains("jaw moved")), "{moving}");
        assert!(state.take_bites().is_empty());
        for i in 20u32..40 {
            state.pose(&timed(0.0, f64::from(i) / 30.0), Some(u64::from(i)));
        }
        let done = state.calibrate();
        assert_eq!(done["ok"], true, "{done}");
        let bites = state.take_bites();
        assert_eq!(bites.len(), 1, "queued for the recording once");
        assert!(bites[0].frames >= 8 && bites[0].spread_mm < 1e-9, "{:?}", bites[0]);
        assert!(state.take_bites().is_empty());
        // The first frame was open: the rest moved to the closed position.
        let rest = state.lock().rest.expect("rest");
        let (angle, _) = rest.distance_to(&frame(0.0).maxilla_from_mandible.expect("pose"));
        assert!(angle < 1e-12);
        let (_, [opening, lateral, _]) = state.readouts(&frame(0.0).maxilla_from_mandible.expect("pose"), Some(&rest));
        assert_eq!((opening, lateral), (Some(0.0), Some(0.0)));
    }

    #[test]
    fn the_scene_falls_back_to_the_marker_solids_and_refuses_unknown_meshes() {
        let state = LiveState::new(&options(), "live").expect("state");
        let scene = state.scene();
        assert_eq!(scene["maxilla"]["format"], "mesh");
        assert_eq!(
            scene["maxilla"]["indices"].as_array().map(Vec::len),
            Some(12 * 3 * 3),
            "12 pentagons, 3 triangles each"
        );
        // A cube marker's file is drawn as a cube of its edge, with its own tags.
        let cube =
            Marker::nominal_on(jawtrack_marker::SolidKind::Cube, jawtrack_marker::TagFamily::TAG36H11, 20.0, None)
                .expect("cube marker");
        let state = LiveState::new(&ViewerOptions { marker: Some(cube), ..options() }, "live").expect("state");
        let scene = state.scene();
        assert_eq!(scene["marker_solid"]["indices"].as_array().map(Vec::len), Some(6 * 2 * 3), "6 squares, 2 each");
        let positions: Vec<f64> = serde_json::from_value(scene["marker_solid"]["positions"].clone()).expect("numbers");
        assert_eq!(positions.len(), 6 * 4 * 3);
        let reach = positions.chunks(3).map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()).fold(0.0, f64::max);
        assert!((reach - 20.0 * 3f64.sqrt() / 2.0).abs() < 1e-9, "corners at the 20 mm cube's circumradius: {reach}");
        assert_eq!(scene["tags"]["mandible"].as_array().map(Vec::len), Some(6));
        let bad = ViewerOptions { maxilla: Some("a.dxf".into()), mandible: Some("b.stl".into()), ..options() };
        assert!(LiveState::new(&bad, "live").is_err_and(|e| e.to_string().contains("STL, PLY or OBJ")));
    }

    #[test]
    fn with_a_registration_the_scans_sit_against_each_other_as_it_places_them() {
        let stl = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../harness-cad/dodecahedron-with-post.stl"));
        let registration = Registration {
            maxilla_scan_from_maxilla_marker: Pose::from_axis_angle(
                Vector3::new(0.1, 0.2, -0.3),
                Vector3::new(5.0, -40.0, 2.0),
            ),
            mandible_scan_from_mandible_marker: Pose::from_axis_angle(
                Vector3::new(-0.2, 0.0, 0.1),
                Vector3::new(1.0, 3.0, -44.0),
            ),
            ..Registration::identity()
        };
        let scans = ViewerOptions { maxilla: Some(stl.clone()), mandible: Some(stl), ..options() };
        let with = ViewerOptions { registration: Some(registration), ..scans.clone() };
        let placed = LiveState::new(&with, "replay").expect("state").scene();
        let pose = |v: &Value| serde_json::from_value::<Pose>(v.clone()).expect("a row-major 4x4");
        let (upper, lower) =
            (pose(&placed["maxilla"]["marker_from_mesh"]), pose(&placed["mandible"]["marker_from_mesh"]));
        // The page draws both in the maxilla marker's frame: the lower scan at
        // maxilla_from_mandible · lower, seen from the upper scan.
        let m = frame(0.2).maxilla_from_mandible.expect("pose");
        let (angle, dist) =
            (upper.inverse() * m * lower).distance_to(&registration.maxilla_scan_from_mandible_scan(&m));
        assert!(angle < 1e-12 && dist < 1e-9, "{angle} {dist}");
        // Without one, the scans are drawn as given (and the command says so).
        let plain = LiveState::new(&scans, "replay").expect("state").scene();
        assert!(plain["maxilla"]["marker_from_mesh"].is_null() && plain["mandible"]["marker_from_mesh"].is_null());
    }

    /// A GET over a plain socket: (status line, content type, body length).
    fn get(addr: SocketAddr, path: &str) -> (String, String, usize) {
        use std::io::{Read as _, Write as _};
        let mut stream = std::net::TcpStream::connect(addr).expect("connect");
        write!(stream, "GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n").expect("request");
        let mut response = Vec::new();
        stream.read_to_end(&mut response).expect("response");
        let text = String::from_utf8_lossy(&response);
        let (head, body) = text.split_once("\r\n\r\n").expect("a head and a body");
        let status = head.lines().next().unwrap_or_default().to_owned();
        let content_type = head
            .lines()
            .find_map(|l| l.to_ascii_lowercase().strip_prefix("content-type: ").map(str::to_owned))
            .unwrap_or_default();
        (status, content_type, body.len())
    }

    #[test]
    fn the_page_is_served_from_the_program_itself() {
        let state = Arc::new(LiveState::new(&options(), "live").expect("state"));
        // A free port: bound, then released for the server.
        let addr = std::net::TcpListener::bind("127.0.0.1:0").and_then(|l| l.local_addr()).expect("a free port");
        LiveServer::start(addr, state).expect("serving");
        let (status, content_type, len) = get(addr, "/");
        assert!(
            status.contains("200") && content_type.starts_with("text/html") && len > 100,
            "{status} {content_type}"
        );
        for path in [
            "/viewer.js",
            "/anatomy.js",
            "/pick.js",
            "/style.css",
            "/vendor/three/build/three.module.js",
            "/vendor/three/build/three.core.js",
        ] {
            let (status, _, len) = get(addr, path);
            assert!(status.contains("200") && len > 100, "{path}: {status}");
        }
        assert!(get(addr, "/vendor/three/package.json").0.contains("404"), "only what the page imports");
        // Every module the page imports is in the program.
        for script in ["/viewer.js", "/anatomy.js", "/pick.js"] {
            let page = String::from_utf8_lossy(page::FILES.iter().find(|f| f.0 == script).expect("the script").2);
            for line in page.lines().filter(|l| l.starts_with("import ")) {
                let Some(module) = line.split('\'').nth(1) else { continue };
                let url = module.replace("three/addons/", "/vendor/three/examples/jsm/");
                let url = match url.as_str() {
                    "three" => "/vendor/three/build/three.module.js".to_owned(),
                    local => local.strip_prefix('.').unwrap_or(local).to_owned(),
                };
                assert!(page::FILES.iter().any(|f| f.0 == url), "{module} is imported by {script} but not embedded");
            }
        }
    }
}
