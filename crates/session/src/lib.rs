//! A recorded session read the way the clinical commands need it — one library that the CLI,
//! the viewer, the report and the FFI share, so that each rule has one home:
//!
//! - [`open()`]: a recording's frames of one session, in capture order (several sessions in one
//!   file are refused unless one is chosen, since their frames would mix);
//! - [`rest`]: where displacements are measured from (a chosen frame, else the bite accepted
//!   while recording, else the first frame with a jaw pose);
//! - [`anatomy()`]: the patient's points through a registration, else the standard mounting;
//! - [`scan_pose`]: the lower scan in the upper scan's frame — through a registration, else as
//!   recorded;
//! - [`arches`] and [`survey`]: the tooth scans read and their contacts checked over frames;
//!   [`contact_run`]: a whole `jawtrack contacts` run and the files it writes;
//! - [`incisor`]: the lower incisal point chosen, and its path from the rest position (every
//!   opening, lateral and protrusive number);
//! - [`export`]: the export formats (CSV, JSON Lines, scan transforms, OpenSim);
//! - [`measures`]: the measuring commands' JSON, and the frames a hinge-axis fit takes.
//!
//! # Examples
//!
//! ```no_run
//! use jawtrack_session::{open, rest};
//! # fn main() -> Result<(), jawtrack_session::SessionError> {
//! let opened = open::open(std::path::Path::new("session.jsonl"), None)?;
//! let rest = rest::rest_of(&opened.recording, None)?;
//! println!("{} frames; rest at {}", opened.recording.frames.len(), rest.map_or("none".into(), |r| r.describe()));
//! # Ok(()) }
//! ```

pub mod anatomy;
pub mod arches;
pub mod contact_run;
pub mod contacts;
pub mod export;
pub mod incisor;
pub mod json;
pub mod measures;
pub mod movements;
pub mod open;
pub mod rest;
pub mod scan_pose;
pub mod survey;

pub use anatomy::{anatomy, read_points, read_registration};
pub use open::{Opened, open};
pub use rest::{Rest, rest_of};
pub use scan_pose::PoseSource;

/// Why a session could not be read or used; each names the file or the choice to change.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The recording could not be read.
    #[error(transparent)]
    Recording(#[from] jawtrack_recording::RecordingError),
    /// The file holds several sessions and none was chosen.
    #[error(
        "{path}: holds {count} sessions, whose frames must not be mixed: {sessions}; choose one with --session ID \
         (`jawtrack export FILE --session ID --jsonl --out ONE.jsonl` writes it alone)"
    )]
    SeveralSessions {
        /// The recording.
        path: String,
        /// How many sessions.
        count: usize,
        /// Each session's id and frame count, in words.
        sessions: String,
    },
    /// The chosen session is not in the file.
    #[error("{path}: no frame of session {wanted}; its sessions: {sessions}")]
    NoSuchSession {
        /// The recording.
        path: String,
        /// The session asked for.
        wanted: String,
        /// The sessions the file holds.
        sessions: String,
    },
    /// No line of the file is a frame.
    #[error(
        "{path}: the file has no frames that could be read ({skipped} lines skipped): is it a recording of \
         `jawtrack track`, `receive` or the phone?"
    )]
    NoFrames {
        /// The recording.
        path: String,
        /// Lines that were not frames.
        skipped: usize,
        /// Why, line by line (as [`Opened::warnings`]), for the reader to print.
        warnings: Vec<String>,
    },
    /// A C3D file cannot hold the session as it is (`jawtrack export --c3d`).
    #[error("C3D: {0}")]
    C3d(#[from] jawtrack_c3d::C3dError),
    /// The chosen rest frame is not in the recording.
    #[error("--rest-frame {0}: no such frame in the recording")]
    NoRestFrame(u64),
    /// The chosen rest frame has no jaw pose.
    #[error("--rest-frame {0}: frame {0} has no jaw pose")]
    RestFrameUnposed(u64),
    /// No frame has a jaw pose.
    #[error("{path}: no frame has a jaw pose (both markers tracked): nothing to {what}")]
    NoJawPose {
        /// The recording.
        path: String,
        /// What the command would have done.
        what: &'static str,
    },
    /// The registration file could not be read.
    #[error("registration file {path}: {source}")]
    Registration {
        /// The file.
        path: String,
        /// Why.
        source: jawtrack_registration::RegistrationError,
    },
    /// The points file could not be read.
    #[error("the points file {path}: {reason}")]
    Points {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
    /// `--points` without a registration.
    #[error(
        "--points needs --registration: the points are in the upper scan's frame, and the registration \
         (`jawtrack register`) places that scan on the maxilla marker"
    )]
    PointsNeedRegistration,
    /// The window chosen holds no frame with a jaw pose.
    #[error("{0}")]
    EmptyWindow(String),
    /// No frame carries the scans' pose.
    #[error("{0}")]
    NoScanPose(String),
    /// A mesh could not be read.
    #[error("--{side}: {source}")]
    Mesh {
        /// `maxilla` or `mandible`.
        side: &'static str,
        /// Why.
        source: jawtrack_occlusion::MeshError,
    },
    /// A setting out of range, naming its flag.
    #[error("{0}")]
    Setting(String),
    /// The dynamic mode could not resolve the recorded path.
    #[error("dynamic mode")]
    Dynamics(#[source] jawtrack_occlusion::dynamics::ResolveError),
    /// Creating or writing an output failed (`context` says which).
    #[error("{context}")]
    Io {
        /// What was being done, naming the file.
        context: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A JSON file could not be read (`context` names it).
    #[error("{context}")]
    Json {
        /// What was being read, naming the file.
        context: String,
        /// Why.
        #[source]
        source: serde_json::Error,
    },
    /// Writing an output failed.
    #[error("writing {path}: {reason}")]
    Write {
        /// The output.
        path: String,
        /// Why.
        reason: String,
    },
    /// A contacts folder made from another recording than the one it is used with.
    #[error(
        "the contacts folder was made from {made_from}, not from {recording}: {differs}; run `jawtrack contacts` on \
         this recording (or give --contacts the folder made from it)"
    )]
    OtherRecording {
        /// The recording the folder was made from, in words.
        made_from: String,
        /// The recording it is used with, in words.
        recording: String,
        /// How they differ, in words.
        differs: String,
    },
}
