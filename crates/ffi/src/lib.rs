//! The JawTrack library as the iPhone app sees it.
//!
//! Two doors into the same trackers:
//! - a **uniffi** API for control and results ([`Tracker`], [`Settings`], [`FrameResult`],
//!   [`Recorder`], [`LinkEncoder`], [`AppSettings`], and the marker calibration's
//!   [`Calibrator`]), from which Swift (and, for the tests here, Python) bindings are generated;
//! - plain **C** entry points ([`c_api`], header `include/jawtrack.h` made by cbindgen) that
//!   track a camera frame in place: the luma plane's pointer, size and bytes per row go
//!   straight to the detector, no copy. Swift calls them inside
//!   `CVPixelBufferLockBaseAddress`, passing [`Tracker::frame_handle`], then reads the frame's full
//!   result with [`Tracker::last_result`].
//!
//! Everything the app decides that can be decided without UIKit lives here: settings ranges,
//! intrinsics scaled to the delivered frame, the overlay's geometry, the recording schema,
//! the link's datagrams, and the marker calibration: [`Calibrator::add_view`] takes the frame a
//! tracker tracked last (its tags in pixels and its camera, so no pixels go through twice),
//! [`CalibrationProgress`] says which tags still need views, [`Calibrator::solve`] gives the
//! per-tag result and [`Calibrator::save`] writes the marker file, never over one unless asked.
//! No panic crosses either door: uniffi turns one into an error, and the C functions catch it
//! and return [`c_api::JtStatus::Panic`].

pub mod c_api;
mod calibrator;
mod capture;
mod engine;
mod error;
mod plan;
mod settings;

pub use calibrator::{
    BodyCalibrationResult, BodyViews, CalibrationProgress, Calibrator, MarkerCalibrationResult, TagCalibrationResult,
    TagViews, ViewOutcome,
};
pub use capture::{ReadoutChoice, next_exposure_cap, readout_for};
pub use engine::{
    AxisOverlay, BodyResult, FrameResult, IntercuspationResult, Overlay, TagOverlay, intrinsics_from_camera_matrix,
};
pub use error::JawTrackError;
pub use plan::{CaptureFormat, CaptureGuidance, CapturePlanner, GuidanceKind, PlanChoice};
pub use settings::{
    AppSettings, Camera, FocusMode, Resolution, Settings, default_app_settings, default_settings, detector_threads,
    validate_app_settings, validate_settings,
};

use engine::Engine;
use error::invalid;
use jawtrack_apriltag::ImageView;
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_recording::{FrameRecord, Overwrite, RecordingHeader, RecordingWriter};
use jawtrack_wire::{Key, PosePacket, Security, Session};
use std::sync::{Arc, Mutex, MutexGuard};

uniffi::setup_scaffolding!("jawtrack");

/// Camera intrinsics in pixels of the delivered frame (pixel centres at integer coordinates).
#[derive(Debug, Clone, Copy, PartialEq, uniffi::Record)]
pub struct Intrinsics {
    /// Focal length along x (px).
    pub fx: f64,
    /// Focal length along y (px).
    pub fy: f64,
    /// Principal point x (px).
    pub cx: f64,
    /// Principal point y (px).
    pub cy: f64,
    /// Radial distortion k1.
    pub k1: f64,
    /// Radial distortion k2.
    pub k2: f64,
}

impl Intrinsics {
    pub(crate) fn camera(&self) -> Result<CameraIntrinsics, JawTrackError> {
        let c = CameraIntrinsics { fx: self.fx, fy: self.fy, cx: self.cx, cy: self.cy, k1: self.k1, k2: self.k2 };
        c.validate()?;
        Ok(c)
    }
}

/// Locks a mutex whose data stays consistent even if a holder panicked (every update is a
/// single assignment), so one caught panic does not disable the tracker for good.
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A tracker: frames in, the jaw pose out.
#[derive(uniffi::Object)]
pub struct Tracker {
    handle: u64,
    engine: Arc<Mutex<Engine>>,
}

#[uniffi::export]
impl Tracker {
    /// A tracker with `settings`, for the marker file's JSON (`None`: the nominal 12.7 mm
    /// marker).
    #[uniffi::constructor]
    pub fn new(settings: Settings, marker_json: Option<String>) -> Result<Arc<Self>, JawTrackError> {
        let marker = match marker_json {
            Some(text) => Marker::from_json(&text)?,
            None => Marker::default(),
        };
        let engine = Arc::new(Mutex::new(Engine::new(marker, settings)?));
        let handle = c_api::register(engine.clone());
        Ok(Arc::new(Tracker { handle, engine }))
    }

    /// The number the C frame entry points take to reach this tracker. It is never reused and
    /// stops working when the tracker is released.
    pub fn frame_handle(&self) -> u64 {
        self.handle
    }

    /// Changes the settings; the bodies' motion is kept.
    pub fn update_settings(&self, settings: Settings) -> Result<(), JawTrackError> {
        lock(&self.engine).update_settings(settings)
    }

    /// The settings in use.
    pub fn settings(&self) -> Settings {
        lock(&self.engine).settings.clone()
    }

    /// Forgets the bodies' motion and the calibration step (a new session).
    pub fn reset(&self) {
        lock(&self.engine).reset();
    }

    /// Tracks a luma frame passed by value. It copies the frame (uniffi does): the app uses
    /// the C entry points instead; this is for tests and tools. `exposure_s`, the frame's
    /// exposure when known, is recorded with it.
    #[allow(clippy::too_many_arguments)]
    pub fn track_luma(
        &self,
        luma: Vec<u8>,
        width: u32,
        height: u32,
        bytes_per_row: u32,
        intrinsics: Intrinsics,
        t: f64,
        exposure_s: Option<f64>,
    ) -> Result<FrameResult, JawTrackError> {
        let mut engine = lock(&self.engine);
        match ImageView::new(&luma, width as usize, height as usize, bytes_per_row as usize) {
            Ok(view) => engine.track(&view, &intrinsics, t, exposure_s),
            Err(e) => {
                // A frame refused leaves no view for a calibration to take.
                engine.view = None;
                Err(e.into())
            }
        }
    }

    /// The lens position (AVFoundation's `lensPosition`, 0 near – 1 far) the camera reports
    /// from now on, stamped on each frame's result and recorded with it; `None` when unknown.
    /// Focusing moves the lens and scales the image: a recording whose lens position moved, or
    /// differs from the calibration's, is measured with the wrong focal length.
    pub fn set_lens_position(&self, lens_position: Option<f64>) -> Result<(), JawTrackError> {
        if let Some(p) = lens_position.filter(|p| !(p.is_finite() && (0.0..=1.0).contains(p))) {
            return Err(invalid(format!("a lens position is within 0–1, got {p}")));
        }
        lock(&self.engine).lens_position = lens_position;
        Ok(())
    }

    /// The result of the last frame tracked (by either door), if any.
    pub fn last_result(&self) -> Option<FrameResult> {
        lock(&self.engine).last.clone()
    }

    /// The maximal-intercuspation step: the patient bites; the mean of the last frames with
    /// both jaws tracked becomes the scanned intercuspal position.
    pub fn calibrate_intercuspation(&self) -> Result<IntercuspationResult, JawTrackError> {
        lock(&self.engine).calibrate_intercuspation()
    }

    /// The marker file tracked, as JSON (for the recording's header).
    pub fn marker_json(&self) -> String {
        lock(&self.engine).marker_json()
    }
}

impl Tracker {
    /// Frame `frame`'s line of the recording schema, converted once when it was tracked; it
    /// must be the last frame tracked, so that what is recorded and sent is what was shown.
    fn record_of_frame(&self, frame: u64) -> Result<FrameRecord, JawTrackError> {
        match &lock(&self.engine).last_record {
            Some(r) if r.frame == frame => Ok(r.clone()),
            Some(r) => Err(invalid(format!(
                "frame {frame} is not the last frame tracked ({}): record and send each frame right after tracking it",
                r.frame
            ))),
            None => Err(invalid(format!(
                "frame {frame}: the tracker holds no result (nothing tracked since it started or was reset, or the last frame failed)"
            ))),
        }
    }
}

impl Drop for Tracker {
    fn drop(&mut self) {
        c_api::unregister(self.handle);
    }
}

/// What a recording's header says about where it came from.
#[derive(Debug, Clone, uniffi::Record)]
pub struct RecordingInfo {
    /// The device and camera, e.g. "iPhone15,2 back wide".
    pub device: Option<String>,
    /// The camera at the start of the recording.
    pub intrinsics: Option<Intrinsics>,
    /// The marker file's JSON.
    pub marker_json: Option<String>,
    /// The app's settings as JSON.
    pub settings_json: Option<String>,
    /// The pairing key's id when streaming (never the key).
    pub key_id: Option<String>,
    /// The camera's rolling-shutter readout the tracker was told (s), so that `jawtrack track`
    /// re-tracks the session's video the same way.
    pub readout_s: Option<f64>,
    /// The capture plan the camera was set by, if any: written into the header.
    #[uniffi(default)]
    pub plan: Option<Arc<CapturePlanner>>,
    /// The lens position focus was locked at (0 near – 1 far), when it was.
    #[uniffi(default)]
    pub locked_lens_position: Option<f64>,
}

/// Writes a session as JSON Lines in the schema of `jawtrack track`: a header line, then one
/// line per frame, each flushed to the file as it is appended, so a killed app leaves a
/// readable recording.
#[derive(uniffi::Object)]
pub struct Recorder {
    writer: Mutex<Option<RecordingWriter<std::fs::File>>>,
    frames: Mutex<u64>,
    path: String,
}

#[uniffi::export]
impl Recorder {
    /// Creates `path` and writes the header, which starts a new session. An existing file is
    /// refused, never replaced: the app picks a free name.
    #[uniffi::constructor]
    pub fn open(path: String, info: RecordingInfo) -> Result<Arc<Self>, JawTrackError> {
        let mut header = RecordingHeader::new("JawTrack iOS");
        header.device = info.device;
        header.intrinsics = info.intrinsics.map(|i| i.camera()).transpose()?;
        header.marker = match info.marker_json {
            Some(m) => Some(serde_json::from_str(&m).map_err(|e| invalid(format!("marker JSON: {e}")))?),
            None => None,
        };
        header.settings = match info.settings_json {
            Some(s) => serde_json::from_str(&s).map_err(|e| invalid(format!("settings JSON: {e}")))?,
            None => serde_json::Value::Null,
        };
        header.key_id = info.key_id;
        if let Some(r) = info.readout_s {
            capture::check_readout(r, "readout_s")?;
        }
        header.readout_s = info.readout_s;
        if let Some(p) = info.locked_lens_position.filter(|p| !(p.is_finite() && (0.0..=1.0).contains(p))) {
            return Err(invalid(format!("a lens position is within 0–1, got {p}")));
        }
        header.capture = info.plan.map(|p| p.record(info.locked_lens_position));
        let writer = RecordingWriter::create(std::path::Path::new(&path), header, Overwrite::Refuse)?;
        Ok(Arc::new(Recorder { writer: Mutex::new(Some(writer)), frames: Mutex::new(0), path }))
    }

    /// Appends frame `frame` as `tracker` tracked it: its last result, taken inside the
    /// library (the app never hands a result back to be re-read). Refused when `frame` is not
    /// the tracker's last frame, or that frame failed.
    pub fn append(&self, tracker: &Tracker, frame: u64) -> Result<(), JawTrackError> {
        let record = tracker.record_of_frame(frame)?;
        let mut writer = lock(&self.writer);
        let w = writer.as_mut().ok_or_else(|| invalid(format!("{}: the recording is closed", self.path)))?;
        w.append(&record)?;
        *lock(&self.frames) = w.frames_written();
        Ok(())
    }

    /// Appends the rest position the intercuspation step accepted
    /// ([`Tracker::calibrate_intercuspation`]'s result), so that readers measure from it.
    pub fn append_bite(&self, bite: IntercuspationResult) -> Result<(), JawTrackError> {
        let record = bite.record()?;
        let mut writer = lock(&self.writer);
        let w = writer.as_mut().ok_or_else(|| invalid(format!("{}: the recording is closed", self.path)))?;
        w.append_bite(&record)?;
        Ok(())
    }

    /// Frames appended so far.
    pub fn frames_written(&self) -> u64 {
        *lock(&self.frames)
    }

    /// Syncs the file to storage and closes it; later appends are refused.
    pub fn close(&self) -> Result<(), JawTrackError> {
        if let Some(w) = lock(&self.writer).take() {
            w.sync()?;
        }
        Ok(())
    }
}

/// The receiver's acknowledgement, as the app shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Record)]
pub struct LinkAck {
    /// The highest sequence number the receiver has.
    pub highest_seq: u64,
    /// Datagrams of this session it accepted.
    pub accepted: u64,
    /// Sequence numbers of this session it is missing.
    pub lost: u64,
    /// Datagrams it rejected since it started.
    pub rejected: u64,
}

/// Seals frames into datagrams for the receiver (`docs/wire.md`) and reads its
/// acknowledgements: one link session.
#[derive(uniffi::Object)]
pub struct LinkEncoder {
    session: Mutex<Session>,
    key_id: Option<String>,
}

#[uniffi::export]
impl LinkEncoder {
    /// A session sealed under the pairing key (64 hex digits). `key_hex` `None` with
    /// `insecure_plaintext` sends in clear, for development only.
    #[uniffi::constructor]
    pub fn new(key_hex: Option<String>, insecure_plaintext: bool) -> Result<Arc<Self>, JawTrackError> {
        let (security, key_id) = match (key_hex, insecure_plaintext) {
            (Some(k), false) => {
                let key: Key = k.parse()?;
                let id = key.id();
                (Security::Sealed(key), Some(id))
            }
            (None, true) => (Security::Plaintext, None),
            (Some(_), true) => return Err(invalid("a pairing key and plaintext are exclusive")),
            (None, false) => return Err(invalid("a pairing key is needed (or plaintext, for development only)")),
        };
        Ok(Arc::new(LinkEncoder { session: Mutex::new(Session::new(security)), key_id }))
    }

    /// The session's id (random).
    pub fn session_id(&self) -> u64 {
        lock(&self.session).id()
    }

    /// The pairing key's id, for the recording header and the settings screen.
    pub fn key_id(&self) -> Option<String> {
        self.key_id.clone()
    }

    /// The next datagram, carrying frame `frame` as `tracker` tracked it (its last result,
    /// taken inside the library). Refused when `frame` is not the tracker's last frame.
    pub fn encode(&self, tracker: &Tracker, frame: u64) -> Result<Vec<u8>, JawTrackError> {
        let packet = PosePacket::from_record(&tracker.record_of_frame(frame)?);
        Ok(lock(&self.session).pose_datagram(&packet))
    }

    /// Reads a datagram from the receiver; only a valid acknowledgement of this session passes.
    pub fn read_ack(&self, datagram: Vec<u8>) -> Result<LinkAck, JawTrackError> {
        let ack = lock(&self.session).read_ack(&datagram)?;
        Ok(LinkAck { highest_seq: ack.highest_seq, accepted: ack.accepted, lost: ack.lost, rejected: ack.rejected })
    }
}

/// What a pairing QR code (shown by `jawtrack receive --qr`) or a typed key gives the app.
#[derive(Debug, Clone, PartialEq, Eq, uniffi::Record)]
pub struct Pairing {
    /// The receiver's address, when the code names it.
    pub host: Option<String>,
    /// The receiver's UDP port, when the code names it.
    pub port: Option<u32>,
    /// The pairing key, 64 hex digits.
    pub key_hex: String,
    /// The key's id.
    pub key_id: String,
}

/// Reads a scanned or typed pairing: a bare key (64 hex digits) or the receiver's
/// `jawtrack://pair?host=H&port=P&key=K` (`jawtrack_wire::pairing_uri`).
#[uniffi::export]
pub fn parse_pairing(text: String) -> Result<Pairing, JawTrackError> {
    let p = jawtrack_wire::parse_pairing_uri(text.trim())?;
    Ok(Pairing { host: p.host, port: p.port.map(u32::from), key_id: p.key.id(), key_hex: p.key.to_hex() })
}

/// Checks a pairing key typed or scanned (64 hex digits, surrounding blanks ignored); its id.
#[uniffi::export]
pub fn pairing_key_id(text: String) -> Result<String, JawTrackError> {
    Ok(text.trim().parse::<Key>()?.id())
}
