//! The rest position displacements are measured from: a chosen frame's jaw pose, else the
//! last bite the intercuspation step accepted while recording, else the first frame with a jaw
//! pose.

use crate::SessionError;
use jawtrack_pose::Pose;
use jawtrack_recording::{BiteRecord, Recording};

/// Where displacements are measured from.
#[derive(Debug, Clone, Copy)]
pub enum Rest {
    /// A frame's jaw pose (`--rest-frame`, or the first frame with one).
    Frame(u64, Pose),
    /// The bite the intercuspation step accepted while recording.
    Bite(BiteRecord),
}

impl Rest {
    /// The mandible in the maxilla at rest.
    pub fn pose(self) -> Pose {
        match self {
            Rest::Frame(_, p) => p,
            Rest::Bite(b) => b.maxilla_from_mandible,
        }
    }

    /// In words, for a summary.
    pub fn describe(self) -> String {
        match self {
            Rest::Frame(n, _) => format!("frame {n}"),
            Rest::Bite(b) => {
                format!("the bite accepted at t = {:.2} s ({} frames held within {:.2} mm)", b.t, b.frames, b.spread_mm)
            }
        }
    }

    /// As JSON, for `metrics --json`.
    pub fn to_json(self) -> serde_json::Value {
        match self {
            Rest::Frame(n, _) => serde_json::json!({"source": "frame", "frame": n}),
            Rest::Bite(b) => serde_json::json!({"source": "bite", "t": b.t, "frames": b.frames,
                "span_s": b.span_s, "spread_mm": b.spread_mm, "spread_deg": b.spread_deg}),
        }
    }
}

/// The rest position: frame `rest_frame`'s jaw pose (an error if it has none or is missing);
/// else the last bite the intercuspation step accepted in the recording; else the first
/// frame's jaw pose. `None` when there is none of these.
///
/// # Examples
///
/// ```
/// let rec = jawtrack_recording::read_recording("".as_bytes()).unwrap();
/// assert!(jawtrack_session::rest_of(&rec, None).unwrap().is_none());
/// ```
pub fn rest_of(rec: &Recording, rest_frame: Option<u64>) -> Result<Option<Rest>, SessionError> {
    match rest_frame {
        None => Ok(rec
            .rest(None)
            .map(|b| Rest::Bite(*b))
            .or_else(|| rec.frames.iter().find_map(|f| f.maxilla_from_mandible.map(|m| Rest::Frame(f.frame, m))))),
        Some(n) => match rec.frames.iter().find(|f| f.frame == n) {
            Some(f) => {
                f.maxilla_from_mandible.map(|m| Some(Rest::Frame(n, m))).ok_or(SessionError::RestFrameUnposed(n))
            }
            None => Err(SessionError::NoRestFrame(n)),
        },
    }
}

/// [`rest_of`], refusing a recording without any jaw pose (`what`: what the command does, for
/// the message).
pub fn require_rest(
    rec: &Recording,
    rest_frame: Option<u64>,
    path: &std::path::Path,
    what: &'static str,
) -> Result<Rest, SessionError> {
    rest_of(rec, rest_frame)?.ok_or_else(|| SessionError::NoJawPose { path: path.display().to_string(), what })
}
