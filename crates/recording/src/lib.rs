//! The recording schema, its one writer and its one reader: how a tracked session is stored.
//! `jawtrack track`, the receiver, the demo and the phone app all write through
//! [`RecordingWriter`]; every command that reads a session reads through [`read_recording`] or
//! [`open`].
//!
//! A recording is a JSON Lines file. The first line is a header,
//! `{"recording": {"format": "jawtrack-recording", "version": 1, "source", "session", "device",
//! "intrinsics", "marker", "settings", "key_id", "created_unix_s"}}` ([`RecordingHeader`]).
//! Every later line is one frame ([`FrameRecord`]):
//!
//! ```text
//! {"frame": i, "session": "16 hex digits", "path": "…" | null, "t": seconds,
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
//! Frames received over the link carry `"seq"` and `"received_unix_s"` and no `cov` or
//! `timings_s`. Files written before session ids have none on their frames.
//!
//! When the maximal-intercuspation step accepts a bite, a line
//! `{"bite": {"session", "t", "maxilla_from_mandible": M, "frames", "span_s", "spread_mm",
//! "spread_deg"}}` ([`BiteRecord`]) records the rest position it chose.
//!
//! Every `M` is a 4×4 row-major matrix in mm; `cov` is the 6×6 covariance of (rotation vector
//! \[rad\], translation \[mm\]), row-major. No value is ever NaN: the tracker never returns a pose
//! that is not finite, and JSON cannot carry one.

mod flag;
mod read;
mod schema;
mod write;

pub use flag::Flag;
pub use read::{MAX_TRANSLATION_MM, Recording, open, read_recording};
pub use schema::{
    BiteRecord, BodyRecord, CaptureRecord, FrameRecord, RECORDING_FORMAT, RECORDING_VERSION, RecordingHeader,
    SessionId, TimingsRecord, ToneFitRecord, ToneRecord,
};
pub use write::{Overwrite, RecordingWriter, create_file, write_file_atomic};

/// Why a recording could not be read or written. Each message holds its cause's words and no
/// error is given as its source, so a caller that prints the chain of causes (`{:#}`) says
/// each thing once.
#[derive(Debug)]
pub enum RecordingError {
    /// Reading or writing the file failed, or the file is not text.
    Io {
        /// The file, as given.
        path: String,
        /// What the system said, or what the file looks like.
        source: std::io::Error,
    },
    /// The output exists and the writer was told not to replace it.
    Exists {
        /// The file, as given.
        path: String,
    },
    /// The header names another format or a version this build does not read.
    Header(String),
}

impl std::fmt::Display for RecordingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RecordingError::Io { path, source } => write!(f, "{path}: {source}"),
            RecordingError::Exists { path } => {
                write!(f, "{path} already exists: give another name, or say that it may be replaced")
            }
            RecordingError::Header(why) => write!(f, "line 1: {why}"),
        }
    }
}

impl std::error::Error for RecordingError {}

impl RecordingError {
    pub(crate) fn io(path: &str) -> impl FnOnce(std::io::Error) -> RecordingError + '_ {
        move |source| RecordingError::Io { path: path.to_owned(), source }
    }
}
