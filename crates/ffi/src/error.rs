//! The one error the app sees, and the one place every crate's own error is mapped to it
//! (`From`), so a call site only writes `?`. Variants say what the app can act on: which
//! setting to correct, that the frame or the camera is wrong, that the marker file or the
//! pairing key must be replaced, that a marker calibration needs other views, which file could
//! not be written.

use jawtrack_apriltag::DetectError;
use jawtrack_calibration::CalibrationError;
use jawtrack_marker::MarkerError;
use jawtrack_pose::GeometryError;
use jawtrack_recording::RecordingError;
use jawtrack_registration::BiteRefusal;
use jawtrack_registration::RegistrationError;
use jawtrack_tracker::TrackError;
use jawtrack_wire::{KeyError, WireError};

/// What went wrong, as the app sees it. Every variant's `message` is written for people.
#[derive(Debug, Clone, PartialEq, thiserror::Error, uniffi::Error)]
pub enum JawTrackError {
    /// A setting out of its range: `setting` names it (e.g. `decimate`, `receiver_port`), so
    /// the settings screen can point at the field.
    #[error("{message}")]
    InvalidSetting {
        /// The setting, by its field name.
        setting: String,
        /// What is wrong with it and what it may be.
        message: String,
    },
    /// The frame is not what its description says (empty, rows too short, buffer too small,
    /// time not a number).
    #[error("{message}")]
    InvalidFrame {
        /// What is wrong.
        message: String,
    },
    /// The camera intrinsics cannot describe a camera.
    #[error("{message}")]
    InvalidIntrinsics {
        /// What is wrong.
        message: String,
    },
    /// The marker file cannot be used: choose another one or the nominal marker.
    #[error("{message}")]
    InvalidMarker {
        /// What is wrong with it.
        message: String,
    },
    /// The pairing key or pairing code cannot be read: scan the receiver's QR code again.
    #[error("{message}")]
    InvalidKey {
        /// What is wrong with it.
        message: String,
    },
    /// The intercuspation step has too few recent frames with both jaws tracked, or they span
    /// too short a time: bite, hold still, and try again.
    #[error("{message}")]
    NotEnoughFrames {
        /// Frames the step needs.
        needed: u32,
        /// Frames it has.
        got: u32,
        /// The same, in words.
        message: String,
    },
    /// The jaw moved during the intercuspation step: bite firmly, hold still, and try again.
    #[error("{message}")]
    JawMoving {
        /// How far the frames spread about their mean (mm).
        spread_mm: f64,
        /// How far they turned about their mean (°).
        spread_deg: f64,
        /// The same, in words.
        message: String,
    },
    /// The marker calibration cannot be made from the views collected: show the marker's faces
    /// from more angles (or start again), then solve again.
    #[error("{message}")]
    Calibration {
        /// Why, and what to do.
        message: String,
    },
    /// Anything else the caller gave is not usable (a matrix, JSON, a closed recording); the
    /// message names it.
    #[error("{message}")]
    InvalidArgument {
        /// What is wrong.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{message}")]
    Io {
        /// The file.
        path: String,
        /// What failed, naming the file.
        message: String,
    },
    /// A datagram that is not a valid acknowledgement for this session.
    #[error("{message}")]
    Link {
        /// Why it was refused.
        message: String,
    },
}

impl JawTrackError {
    /// A setting out of range.
    pub(crate) fn setting(setting: &str, message: impl Into<String>) -> Self {
        JawTrackError::InvalidSetting { setting: setting.into(), message: message.into() }
    }

    /// Too few recent frames for the intercuspation step.
    pub(crate) fn not_enough_frames(needed: usize, got: usize) -> Self {
        JawTrackError::NotEnoughFrames {
            needed: needed as u32,
            got: got as u32,
            message: format!(
                "the intercuspation step needs at least {needed} recent frames with both jaws tracked, have {got}: \
                 bite, hold still, and try again"
            ),
        }
    }

    /// A frame that is not what it claims to be.
    pub(crate) fn frame(message: impl Into<String>) -> Self {
        JawTrackError::InvalidFrame { message: message.into() }
    }
}

/// Anything else the caller gave that is not usable.
pub(crate) fn invalid(message: impl Into<String>) -> JawTrackError {
    JawTrackError::InvalidArgument { message: message.into() }
}

impl From<MarkerError> for JawTrackError {
    fn from(e: MarkerError) -> Self {
        JawTrackError::InvalidMarker { message: format!("marker file: {e}") }
    }
}

impl From<GeometryError> for JawTrackError {
    fn from(e: GeometryError) -> Self {
        match e {
            GeometryError::BadIntrinsics(_) => JawTrackError::InvalidIntrinsics { message: format!("camera {e}") },
            _ => invalid(e.to_string()),
        }
    }
}

impl From<DetectError> for JawTrackError {
    fn from(e: DetectError) -> Self {
        match e {
            DetectError::BadImage(_) => JawTrackError::frame(format!("frame: {e}")),
            DetectError::BadConfig(_) => JawTrackError::setting("detector", e.to_string()),
        }
    }
}

impl From<TrackError> for JawTrackError {
    fn from(e: TrackError) -> Self {
        match e {
            TrackError::Detect(d) => d.into(),
            TrackError::BadIntrinsics(_) => JawTrackError::InvalidIntrinsics { message: e.to_string() },
            TrackError::BadConfig(_) => JawTrackError::setting("tracker", e.to_string()),
        }
    }
}

impl From<BiteRefusal> for JawTrackError {
    fn from(e: BiteRefusal) -> Self {
        let message = e.to_string();
        match e {
            BiteRefusal::TooFewFrames { needed, got, .. } => {
                JawTrackError::NotEnoughFrames { needed: needed as u32, got: got as u32, message }
            }
            // Frames enough but too brief: the frames the needed span holds at their rate.
            BiteRefusal::TooShort { needed_s, span_s, frames } => {
                let rate = if span_s > 0.0 { (frames - 1) as f64 / span_s } else { 0.0 };
                let needed = ((needed_s * rate).ceil() as usize + 1).max(frames + 1);
                JawTrackError::NotEnoughFrames { needed: needed as u32, got: frames as u32, message }
            }
            BiteRefusal::Moving { spread_mm, spread_deg, .. } => {
                JawTrackError::JawMoving { spread_mm, spread_deg, message }
            }
        }
    }
}

impl From<RegistrationError> for JawTrackError {
    fn from(e: RegistrationError) -> Self {
        match e {
            RegistrationError::TooFewSamples { needed, got } => JawTrackError::not_enough_frames(needed, got),
            _ => invalid(e.to_string()),
        }
    }
}

impl From<CalibrationError> for JawTrackError {
    fn from(e: CalibrationError) -> Self {
        match e {
            CalibrationError::NoViews => JawTrackError::Calibration {
                message: "no view shows two tags of one marker: nothing to calibrate from. Turn the marker so that \
                          two faces or more face the camera, from several angles"
                    .into(),
            },
            CalibrationError::BadFrame { .. } => JawTrackError::InvalidIntrinsics { message: e.to_string() },
            // The calibrated marker failed its checks: views that contradict each other.
            _ => JawTrackError::Calibration {
                message: format!("{e}. The views contradict each other: start again and show each face steadily"),
            },
        }
    }
}

impl From<KeyError> for JawTrackError {
    fn from(e: KeyError) -> Self {
        JawTrackError::InvalidKey { message: e.to_string() }
    }
}

impl From<WireError> for JawTrackError {
    fn from(e: WireError) -> Self {
        JawTrackError::Link { message: e.to_string() }
    }
}

impl From<RecordingError> for JawTrackError {
    fn from(e: RecordingError) -> Self {
        match &e {
            RecordingError::Io { path, .. } | RecordingError::Exists { path } => {
                JawTrackError::Io { path: path.clone(), message: e.to_string() }
            }
            RecordingError::Header(_) => invalid(e.to_string()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_crate_error_lands_on_the_variant_a_caller_can_act_on() {
        let e: JawTrackError = DetectError::BadImage("too short".into()).into();
        assert!(matches!(e, JawTrackError::InvalidFrame { .. }), "{e:?}");
        let e: JawTrackError = TrackError::BadIntrinsics("fx".into()).into();
        assert!(matches!(e, JawTrackError::InvalidIntrinsics { .. }), "{e:?}");
        let e: JawTrackError = MarkerError::Json("eof".into()).into();
        assert!(matches!(e, JawTrackError::InvalidMarker { .. }) && e.to_string().starts_with("marker file"));
        let e: JawTrackError = "nope".parse::<jawtrack_wire::Key>().expect_err("not a key").into();
        assert!(matches!(e, JawTrackError::InvalidKey { .. }), "{e:?}");
        let e: JawTrackError = CalibrationError::NoViews.into();
        assert!(matches!(&e, JawTrackError::Calibration { message } if message.contains("Turn the marker")), "{e:?}");
        let e: JawTrackError = CalibrationError::BadFrame { frame: 2, reason: "fx is 0".into() }.into();
        assert!(matches!(e, JawTrackError::InvalidIntrinsics { .. }), "{e:?}");
        let e: JawTrackError = RecordingError::Exists { path: "/tmp/s.jsonl".into() }.into();
        assert!(matches!(&e, JawTrackError::Io { path, .. } if path == "/tmp/s.jsonl"), "{e:?}");
        let e: JawTrackError = BiteRefusal::TooShort { needed_s: 0.3, span_s: 0.1, frames: 7 }.into();
        // 7 frames over 0.1 s: 0.3 s holds 19 at that rate.
        assert!(matches!(e, JawTrackError::NotEnoughFrames { needed: 19, got: 7, .. }), "{e:?}");
        let moving = BiteRefusal::Moving { spread_mm: 15.4, spread_deg: 9.0, limit_mm: 0.3, limit_deg: 1.0 };
        let e: JawTrackError = moving.into();
        assert!(matches!(e, JawTrackError::JawMoving { spread_mm: 15.4, .. }) && e.to_string().contains("15.40 mm"));
    }
}
