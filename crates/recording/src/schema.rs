//! The header and frame lines of a recording, as types (the crate's doc shows the JSON).

use jawtrack_pose::{CameraIntrinsics, Pose};
use jawtrack_tone::{ToneCurve, ToneReason, ToneSetting};
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The header's `format` value: what a reader checks before trusting the rest.
pub const RECORDING_FORMAT: &str = "jawtrack-recording";
/// The only header version this build writes and reads.
pub const RECORDING_VERSION: u32 = 1;

/// A capture session's id: a random 64-bit number, fresh for every session, written as 16 hex
/// digits (JSON numbers above 2^53 would not survive a JavaScript reader). Frames of two
/// sessions in one file are told apart by it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SessionId(pub u64);

impl SessionId {
    /// A fresh random id.
    pub fn random() -> SessionId {
        SessionId(rand::random())
    }
}

impl std::fmt::Display for SessionId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:016x}", self.0)
    }
}

impl std::str::FromStr for SessionId {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.len() != 16 {
            return Err(format!("a session id has 16 hex digits, got {s:?}"));
        }
        u64::from_str_radix(s, 16).map(SessionId).map_err(|_| format!("a session id has 16 hex digits, got {s:?}"))
    }
}

impl Serialize for SessionId {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for SessionId {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

/// The first line of a recording, `{"recording": {…}}`: where the frames came from. It never
/// carries a key, only the key's id.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordingHeader {
    /// Always [`RECORDING_FORMAT`].
    pub format: String,
    /// Always [`RECORDING_VERSION`].
    pub version: u32,
    /// What wrote the file, e.g. `jawtrack track`, `jawtrack receive`, `JawTrack iOS`.
    pub source: String,
    /// The session the file records, when it records one (the writer stamps it on every
    /// frame); `None` for a receiver's file, whose frames carry the sessions they came from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub session: Option<SessionId>,
    /// The capturing device, when known (e.g. `iPhone15,2 back wide`).
    #[serde(default)]
    pub device: Option<String>,
    /// The camera, when known.
    #[serde(default)]
    pub intrinsics: Option<CameraIntrinsics>,
    /// The camera's rolling-shutter readout, first row to last (s; 0 = global shutter), as the
    /// frames were tracked with: re-tracking them takes the same. `None` when not known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub readout_s: Option<f64>,
    /// The exposure every frame was taken with (s), when it was one and known; a frame's own
    /// exposure, when it varies, is on its line ([`FrameRecord::exposure_s`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exposure_s: Option<f64>,
    /// The marker file's JSON, when known.
    #[serde(default)]
    pub marker: Option<Value>,
    /// How the phone was set to film: its capture plan and where its focus was locked, when the
    /// app planned it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capture: Option<CaptureRecord>,
    /// Settings of the writer (detector, search, smoothing, link), free-form.
    #[serde(default)]
    pub settings: Value,
    /// The id of the pairing key packets were sealed with (`wire`'s key id), never the key.
    #[serde(default)]
    pub key_id: Option<String>,
    /// Wall-clock time the file was started (s since the Unix epoch).
    pub created_unix_s: f64,
}

impl RecordingHeader {
    /// A header for `source`, started now, for one new session, with nothing else known.
    pub fn new(source: &str) -> Self {
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
        RecordingHeader {
            format: RECORDING_FORMAT.into(),
            version: RECORDING_VERSION,
            source: source.into(),
            session: Some(SessionId::random()),
            device: None,
            intrinsics: None,
            readout_s: None,
            exposure_s: None,
            marker: None,
            capture: None,
            settings: Value::Null,
            key_id: None,
            created_unix_s: now,
        }
    }

    /// The marker the frames were tracked with, read from its file's JSON: `None` when the
    /// header records none, an error when what it records is not a valid marker file.
    pub fn tracked_marker(&self) -> Option<Result<jawtrack_marker::Marker, jawtrack_marker::MarkerError>> {
        self.marker.as_ref().map(|m| jawtrack_marker::Marker::from_json(&m.to_string()))
    }

    /// The header as its JSON line (without the newline).
    pub fn to_line(&self) -> String {
        serde_json::json!({ "recording": self }).to_string()
    }
}

/// How a phone was set to film a session (`jawtrack_devices::plan`): camera, format, zoom,
/// distance, and where focus was locked.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaptureRecord {
    /// The plan in words ("hold the phone about 22 cm away: …").
    pub plan: String,
    /// Frame size (px).
    pub width: u32,
    /// Frame height (px).
    pub height: u32,
    /// Frames per second.
    pub fps: f64,
    /// The zoom: 1, or the sensor's native crop. Intrinsics belong to a zoom.
    pub zoom: f64,
    /// Where the phone was to be held, and focus locked (mm).
    pub distance_mm: f64,
    /// The nearest and farthest the markers stay sharp with focus locked there (mm).
    pub near_mm: f64,
    /// See `near_mm`.
    pub far_mm: f64,
    /// The nearest the lens focuses (mm).
    pub min_focus_mm: f64,
    /// AVFoundation's lens position (0 near – 1 far) focus was locked at, when known: intrinsics
    /// belong to a lens position too (focusing moves the lens, scaling the image).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lens_position: Option<f64>,
}

/// One body in a frame's record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyRecord {
    /// Maps the body's marker frame into the camera frame.
    pub camera_from_body: Pose,
    /// Tags used, ascending.
    pub tags: Vec<u32>,
    /// Tags seen but dropped.
    #[serde(default)]
    pub rejected_tags: Vec<u32>,
    /// RMS reprojection error (px).
    pub rms_px: f64,
    /// 6×6 covariance of (rotation vector \[rad\], translation \[mm\]), row-major; absent when the
    /// frame came over the link (packets do not carry it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cov: Option<Vec<f64>>,
    /// How blurred its tags' edges were (σ, px): the lens's defocus (a body blurred beyond 0.14
    /// of its cells' width is flagged `defocused`); absent when not measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blur_px: Option<f64>,
    /// The width (px) of its tags' cells, what its blur is judged against.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell_px: Option<f64>,
}

/// Time spent on a frame (s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimingsRecord {
    /// Tag detection.
    pub detection: f64,
    /// Pose estimation.
    pub pose: f64,
}

/// One frame's line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// The frame's index in its source.
    pub frame: u64,
    /// The session the frame belongs to; `None` only in files written before session ids.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub session: Option<SessionId>,
    /// The image file the frame came from, if any.
    #[serde(default)]
    pub path: Option<String>,
    /// Capture time (s): that of the frame's centre row.
    pub t: f64,
    /// The frame's exposure (s), when the camera reported it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exposure_s: Option<f64>,
    /// AVFoundation's lens position (0 near – 1 far) while the frame was taken, when reported:
    /// a change means focus moved, and with it the focal length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lens_position: Option<f64>,
    /// The upper jaw's marker.
    pub maxilla: Option<BodyRecord>,
    /// The lower jaw's marker.
    pub mandible: Option<BodyRecord>,
    /// The mandible marker in the maxilla marker's frame.
    pub maxilla_from_mandible: Option<Pose>,
    /// The lower scan in the upper scan's frame (only with a registration).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub maxilla_scan_from_mandible_scan: Option<Pose>,
    /// Quality flags by name ([`crate::Flag::name`]; a reader keeps names it does not know).
    #[serde(default)]
    pub flags: Vec<String>,
    /// The region searched, `[x, y, width, height]`, or `None` for the whole frame.
    #[serde(default)]
    pub searched: Option<[usize; 4]>,
    /// Time per stage, when measured here.
    #[serde(default)]
    pub timings_s: Option<TimingsRecord>,
    /// The packet's sequence number, for frames received over the link.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seq: Option<u64>,
    /// When the packet arrived (s since the Unix epoch), for frames received over the link.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub received_unix_s: Option<f64>,
    /// The tone curve this frame and the ones after it were read through, and how it was found:
    /// on the first frame, and wherever it changed or a fit of the tags added to its evidence
    /// (the estimate settling over the first frames, then a refit every few seconds), so the
    /// last one is what the whole take ended with.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tone: Option<ToneRecord>,
}

/// The tone curve frames were read through, and how it was found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ToneRecord {
    /// What was asked for: `auto` (estimated from the tags) or a curve.
    pub setting: ToneSetting,
    /// The curve (`srgb`, `gamma:1.83`, …).
    pub curve: ToneCurve,
    /// Why (recordings from before it was recorded read as not yet told).
    #[serde(default)]
    pub reason: ToneReason,
    /// Frames whose tags were fitted so far.
    pub frames_fitted: usize,
    /// With an estimate: the power law pooled over the recent fits, the spread of their
    /// exponents, their tag sides, and how lopsided the edges are read through it and through
    /// sRGB.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<ToneFitRecord>,
}

impl ToneRecord {
    /// The curve and how it was found, in a line: what `jawtrack track` prints and the report
    /// states. The misfits are the edges' lopsidedness per pixel in units of their noise (1:
    /// only noise is left).
    pub fn describe(&self) -> String {
        let evidence = |f: &ToneFitRecord| {
            format!(
                "power law {:.2} ± {:.2} from {} frames' {} tag sides, misfit {:.3} against sRGB's {:.3}",
                f.gamma, f.gamma_spread, self.frames_fitted, f.sides, f.misfit, f.srgb_misfit
            )
        };
        let why = match self.reason {
            ToneReason::Given => return format!("{} (as given)", self.curve),
            ToneReason::NotYetTold => "auto: no tag edge has told the curve yet",
            ToneReason::TooFewSides => "auto: kept, too few tag sides to leave sRGB",
            ToneReason::NotBlurredSteps => "auto: kept, the tags' edges fit no blurred step (sharpened frames?)",
            ToneReason::SrgbFitsAsWell => "auto: kept, sRGB fits the edges as well",
            ToneReason::Estimated => "auto: estimated",
        };
        match &self.fit {
            Some(f) => format!("{} ({why}; {})", self.curve, evidence(f)),
            None => format!("{} ({why})", self.curve),
        }
    }
}

/// The fits behind an estimated curve ([`ToneRecord::fit`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ToneFitRecord {
    /// The pooled exponent.
    pub gamma: f64,
    /// Median absolute deviation of the pooled fits' exponents.
    pub gamma_spread: f64,
    /// Fits pooled.
    pub fits: usize,
    /// Tag sides in them.
    pub sides: usize,
    /// How lopsided the tags' edges are read through the fits' own best power laws, per pixel
    /// in units of the noise (1: only noise is left)…
    pub misfit: f64,
    /// … and through sRGB.
    pub srgb_misfit: f64,
}

/// The rest position the maximal-intercuspation step accepted, `{"bite": {…}}`: every clinical
/// number after it is measured from it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BiteRecord {
    /// The session it belongs to (stamped by the writer like a frame's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub session: Option<SessionId>,
    /// The time of the last frame of the held bite (s, the frames' clock).
    pub t: f64,
    /// The rest position: the mean mandible marker in the maxilla marker's frame.
    pub maxilla_from_mandible: Pose,
    /// Frames averaged.
    pub frames: u64,
    /// Time they spanned (s).
    pub span_s: f64,
    /// How far the frames spread about their mean (mm) …
    pub spread_mm: f64,
    /// … and turned (°).
    pub spread_deg: f64,
}

impl BiteRecord {
    /// The record as its JSON line (without the newline).
    pub fn to_line(&self) -> String {
        serde_json::json!({ "bite": self }).to_string()
    }
}

impl FrameRecord {
    /// The line of a frame that could not be decoded or tracked: it keeps the frame's place,
    /// name and time, holds no pose, and is flagged [`Flag::Unreadable`](crate::Flag::Unreadable).
    pub fn unreadable(frame: u64, path: Option<&str>, t: f64) -> FrameRecord {
        FrameRecord {
            frame,
            session: None,
            path: path.map(str::to_owned),
            t,
            exposure_s: None,
            lens_position: None,
            maxilla: None,
            mandible: None,
            maxilla_from_mandible: None,
            maxilla_scan_from_mandible_scan: None,
            flags: vec![crate::Flag::Unreadable.name()],
            searched: None,
            timings_s: None,
            seq: None,
            received_unix_s: None,
            tone: None,
        }
    }

    /// The record as its JSON line (without the newline).
    pub fn to_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| unreachable!("a frame record always serialises: {e}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tracked_marker_reads_from_the_header() {
        let mut h = RecordingHeader::new("test");
        assert!(h.tracked_marker().is_none(), "none recorded");
        let cube = jawtrack_marker::Marker::nominal_on(
            jawtrack_marker::SolidKind::Cube,
            jawtrack_marker::TagFamily::TAG25H9,
            12.7,
            None,
        )
        .expect("marker");
        h.marker = Some(serde_json::from_str(&cube.to_json()).expect("json"));
        assert_eq!(h.tracked_marker().map(|m| m.expect("valid")), Some(cube));
        h.marker = Some(serde_json::json!({"version": 99}));
        assert!(h.tracked_marker().is_some_and(|m| m.is_err()), "an invalid marker is an error, not none");
    }

    #[test]
    fn a_session_id_is_sixteen_hex_digits_both_ways() {
        let id = SessionId(0x00ab_cdef_0123_4567);
        assert_eq!(id.to_string(), "00abcdef01234567");
        assert_eq!(serde_json::to_value(id).expect("serialises"), "00abcdef01234567");
        assert_eq!("00abcdef01234567".parse::<SessionId>(), Ok(id));
        let err = serde_json::from_value::<SessionId>(serde_json::json!("12")).expect_err("too short");
        assert!(err.to_string().contains("16 hex digits"), "{err}");
        assert!("zzzzzzzzzzzzzzzz".parse::<SessionId>().is_err());
    }
}
