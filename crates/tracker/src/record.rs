//! The recording schema: one JSON object per tracked frame, written as one line of a JSON
//! Lines file by `jawtrack track` (and, through the same code, by the app and the receiver).
//!
//! ```text
//! {"frame": i, "path": "…" | null, "t": seconds,
//!  "maxilla":  {"camera_from_body": M, "tags": [ids], "rejected_tags": [ids], "rms_px": …,
//!               "cov": [36 numbers]} | null,
//!  "mandible": {…} | null,
//!  "maxilla_from_mandible": M | null,
//!  "maxilla_scan_from_mandible_scan": M | null,   (only with a registration)
//!  "flags": ["mandible:single_tag", …],
//!  "searched": [x, y, width, height] | null,       (null: the whole frame)
//!  "timings_s": {"detection": …, "pose": …}}
//! ```
//!
//! The first line is a header, `{"recording": {"format": "jawtrack-recording", "version": 1,
//! "source", "device", "intrinsics", "marker", "settings", "key_id", "created_unix_s"}}`
//! ([`RecordingHeader`]). Frames received over the link carry `"seq"` and `"received_unix_s"`
//! and no `cov` or `timings_s`.
//!
//! Every `M` is a 4×4 row-major matrix in mm; `cov` is the 6×6 covariance of (rotation vector
//! [rad], translation [mm]), row-major. No value is ever NaN: the tracker never returns a
//! pose that is not finite, and JSON cannot carry one.

use crate::{BodyResult, Flag, FrameResult};
use jawtrack_pose::{CameraIntrinsics, Pose};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::io::BufRead;

/// The header's `format` value: what a reader checks before trusting the rest.
pub const RECORDING_FORMAT: &str = "jawtrack-recording";
/// The only header version this build writes and reads.
pub const RECORDING_VERSION: u32 = 1;

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
    /// The capturing device, when known (e.g. `iPhone15,2 back wide`).
    #[serde(default)]
    pub device: Option<String>,
    /// The camera, when known.
    #[serde(default)]
    pub intrinsics: Option<CameraIntrinsics>,
    /// The marker file's JSON, when known.
    #[serde(default)]
    pub marker: Option<Value>,
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
    /// A header for `source`, started now, with nothing else known.
    pub fn new(source: &str) -> Self {
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
        RecordingHeader {
            format: RECORDING_FORMAT.into(),
            version: RECORDING_VERSION,
            source: source.into(),
            device: None,
            intrinsics: None,
            marker: None,
            settings: Value::Null,
            key_id: None,
            created_unix_s: now,
        }
    }

    /// The header as its JSON line (without the newline).
    pub fn to_line(&self) -> String {
        serde_json::json!({ "recording": self }).to_string()
    }
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
    /// 6×6 covariance of (rotation vector [rad], translation [mm]), row-major; absent when the
    /// frame came over the link (packets do not carry it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cov: Option<Vec<f64>>,
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
    /// The image file the frame came from, if any.
    #[serde(default)]
    pub path: Option<String>,
    /// Capture time (s).
    pub t: f64,
    /// The upper jaw's marker.
    pub maxilla: Option<BodyRecord>,
    /// The lower jaw's marker.
    pub mandible: Option<BodyRecord>,
    /// The mandible marker in the maxilla marker's frame.
    pub maxilla_from_mandible: Option<Pose>,
    /// The lower scan in the upper scan's frame (only with a registration).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub maxilla_scan_from_mandible_scan: Option<Pose>,
    /// Quality flags by name (e.g. `mandible:single_tag`).
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
}

impl FrameRecord {
    /// The record of a tracked frame.
    pub fn from_result(index: usize, path: Option<&str>, r: &FrameResult) -> Self {
        let body = |b: &BodyResult| BodyRecord {
            camera_from_body: b.camera_from_body,
            tags: b.tags.clone(),
            rejected_tags: b.rejected_tags.clone(),
            rms_px: b.rms_px,
            cov: Some(b.covariance.transpose().iter().copied().collect()),
        };
        FrameRecord {
            frame: index as u64,
            path: path.map(str::to_owned),
            t: r.t,
            maxilla: r.maxilla.as_ref().map(body),
            mandible: r.mandible.as_ref().map(body),
            maxilla_from_mandible: r.maxilla_from_mandible,
            maxilla_scan_from_mandible_scan: r.maxilla_scan_from_mandible_scan,
            flags: r.flags.iter().map(Flag::name).collect(),
            searched: r.searched.map(|s| [s.x, s.y, s.width, s.height]),
            timings_s: Some(TimingsRecord { detection: r.timings.detection_s, pose: r.timings.pose_s }),
            seq: None,
            received_unix_s: None,
        }
    }

    /// The record as its JSON line (without the newline).
    pub fn to_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| unreachable!("a frame record always serialises: {e}"))
    }
}

/// One frame's record as JSON.
pub fn frame_record(index: usize, path: Option<&str>, r: &FrameResult) -> Value {
    serde_json::to_value(FrameRecord::from_result(index, path, r))
        .unwrap_or_else(|e| unreachable!("a frame record always serialises: {e}"))
}

/// A recording read back.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// The header line, if the file has one (files from before headers have none).
    pub header: Option<RecordingHeader>,
    /// The frames, in file order.
    pub frames: Vec<FrameRecord>,
    /// Lines that were not frames: (1-based line number, why). A last line cut short by a
    /// killed writer shows up here.
    pub skipped: Vec<(usize, String)>,
}

/// Why a recording could not be read at all.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// Reading failed.
    #[error("reading the recording: {0}")]
    Io(#[from] std::io::Error),
    /// The header names another format or a version this build does not read.
    #[error("line 1: {0}")]
    Header(String),
}

/// Reads a recording. Lines that are not frames are collected in [`Recording::skipped`] (so a
/// file cut off mid-line by a killed writer reads up to its last whole line); only a header
/// this build cannot read is an error.
pub fn read_recording(reader: impl BufRead) -> Result<Recording, RecordingError> {
    let mut rec = Recording::default();
    for (i, line) in reader.lines().enumerate() {
        let line = line?;
        if line.trim().is_empty() {
            continue;
        }
        let value: Value = match serde_json::from_str(&line) {
            Ok(v) => v,
            Err(e) => {
                rec.skipped.push((i + 1, format!("not JSON ({e})")));
                continue;
            }
        };
        if let Some(h) = value.get("recording") {
            let h: RecordingHeader = serde_json::from_value(h.clone())
                .map_err(|e| RecordingError::Header(format!("not a recording header: {e}")))?;
            if h.format != RECORDING_FORMAT || h.version != RECORDING_VERSION {
                return Err(RecordingError::Header(format!(
                    "format {} version {} (this build reads {RECORDING_FORMAT} version {RECORDING_VERSION})",
                    h.format, h.version
                )));
            }
            rec.header = Some(h);
            continue;
        }
        match serde_path_to_error::deserialize::<_, FrameRecord>(value) {
            Ok(f) => rec.frames.push(f),
            Err(e) => rec.skipped.push((i + 1, format!("not a frame: field `{}`: {}", e.path(), e.inner()))),
        }
    }
    Ok(rec)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Timings;
    use nalgebra::{Matrix6, Vector3};

    #[test]
    fn a_record_carries_every_field_in_row_major_order() {
        let pose = Pose::from_axis_angle(Vector3::new(0.0, 0.1, 0.0), Vector3::new(1.0, 2.0, 100.0));
        let mut cov = Matrix6::zeros();
        cov[(0, 1)] = 7.0;
        let r = FrameResult {
            t: 0.5,
            maxilla: Some(BodyResult {
                camera_from_body: pose,
                tags: vec![0, 1],
                rejected_tags: vec![5],
                rms_px: 0.3,
                covariance: cov,
            }),
            mandible: None,
            maxilla_from_mandible: None,
            maxilla_scan_from_mandible_scan: None,
            flags: vec![Flag::Lost(jawtrack_marker::BodyKind::Mandible)],
            detections: Vec::new(),
            searched: None,
            timings: Timings { detection_s: 0.004, pose_s: 0.0001 },
        };
        let v = frame_record(3, Some("f.png"), &r);
        assert_eq!(v["frame"], 3);
        assert_eq!(v["path"], "f.png");
        assert_eq!(v["maxilla"]["camera_from_body"][3], 1.0);
        assert_eq!(v["maxilla"]["camera_from_body"][11], 100.0);
        assert_eq!(v["maxilla"]["cov"][1], 7.0, "row-major: (0, 1) is the second number");
        assert_eq!(v["maxilla"]["rejected_tags"][0], 5);
        assert!(v["mandible"].is_null() && v["maxilla_from_mandible"].is_null());
        assert!(v.get("maxilla_scan_from_mandible_scan").is_none());
        assert_eq!(v["flags"][0], "mandible:lost");
        assert_eq!(v["timings_s"]["detection"], 0.004);
    }

    #[test]
    fn a_recording_reads_back_up_to_a_line_cut_short() {
        let r = FrameResult {
            t: 0.25,
            maxilla: None,
            mandible: None,
            maxilla_from_mandible: Some(Pose::from_axis_angle(
                Vector3::new(0.1, 0.0, 0.0),
                Vector3::new(0.0, 40.0, 0.0),
            )),
            maxilla_scan_from_mandible_scan: None,
            flags: vec![],
            detections: Vec::new(),
            searched: None,
            timings: Timings::default(),
        };
        let mut header = RecordingHeader::new("test");
        header.key_id = Some("abcd".into());
        let first = FrameRecord::from_result(0, None, &r);
        let whole = format!("{}\n{}\n{}\n", header.to_line(), first.to_line(), first.to_line());
        // A writer killed mid-line leaves part of the last one.
        let cut = &whole[..whole.len() - 20];
        let rec = read_recording(cut.as_bytes()).expect("readable");
        assert_eq!(rec.header.as_ref().and_then(|h| h.key_id.as_deref()), Some("abcd"));
        assert_eq!(rec.frames.len(), 1);
        let back = &rec.frames[0];
        let (a, d) = back.maxilla_from_mandible.expect("pose").distance_to(&first.maxilla_from_mandible.expect("pose"));
        assert!(a < 1e-12 && d < 1e-12, "the pose survives the round trip: {a} rad, {d} mm");
        assert_eq!((back.frame, back.t, &back.flags, back.timings_s), (0, 0.25, &first.flags, first.timings_s));
        assert_eq!(rec.skipped.len(), 1);
        assert_eq!(rec.skipped[0].0, 3);
    }

    #[test]
    fn a_header_of_another_version_is_an_error_naming_it() {
        let mut header = RecordingHeader::new("test");
        header.version = 99;
        let err = read_recording(header.to_line().as_bytes()).expect_err("refused");
        assert!(err.to_string().contains("version 99"), "{err}");
    }
}
