//! Recorded frames tracked into a recording, as `jawtrack track` does it: every frame keeps its
//! line (a frame that cannot be decoded or tracked is flagged `unreadable` and the run goes on);
//! with a refined marker, a first pass keeps every frame's detections, the marker is refined
//! from them (`jawtrack_calibration::refine`), and a second pass solves them again with it.
//! Over the run, frames are kept for judging the focal length ([`FocalViews`]) and counted
//! ([`Summary`]); [`closing_warnings`] says what the counts call for. [`RecordedCapture`] is
//! what re-tracking a recording's video takes from the recording.
//!
//! # Examples
//!
//! ```no_run
//! use jawtrack_offline::{Summary, track_frame};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let mut tracker = jawtrack_tracker::Tracker::new(Default::default(), Default::default())?;
//! let camera = jawtrack_pose::CameraIntrinsics::pinhole(1400.0, 1400.0, 959.5, 539.5);
//! let mut frames = jawtrack_frames::open_frames(None, &["fixtures/hinge-1080p".into()], None)?;
//! let mut summary = Summary::default();
//! while let Some(frame) = frames.next_frame()? {
//!     match track_frame(&mut tracker, &frame, &camera) {
//!         Ok(r) => summary.add(&r, tracker.uncalibrated_tags()),
//!         Err(why) => {
//!             if let Some(warning) = summary.skip(&why) {
//!                 eprintln!("warning: {}: {warning}", frame.name);
//!             }
//!         }
//!     }
//! }
//! println!("{}", summary.describe());
//! # Ok(()) }
//! ```

mod like;
mod passes;
mod run;
mod summary;

pub use like::RecordedCapture;
pub use passes::{Detected, Kept, first_pass, refine_marker, track_frame};
pub use run::{Pass, Said, TrackEvents, TrackOptions, Tracked, track};
pub use summary::{FocalViews, Summary, closing_warnings, intrinsics_warning};

/// Why a run could not go on.
#[derive(Debug, thiserror::Error)]
pub enum OfflineError {
    /// The frames could not be read.
    #[error(transparent)]
    Frames(#[from] jawtrack_frames::FramesError),
    /// The marker could not be refined from the first pass.
    #[error("refining the marker: {0}")]
    Refine(#[from] jawtrack_calibration::CalibrationError),
    /// A recording to take the camera from has no header.
    #[error("the recording has no header line to take the camera from")]
    NoHeader,
    /// A recording's marker is not a valid marker file.
    #[error("its marker: {0}")]
    Marker(jawtrack_marker::MarkerError),
    /// An option out of range, or a combination that cannot be; the message names the flag.
    #[error("{0}")]
    Refused(String),
    /// A recording could not be read, or the recording not written.
    #[error(transparent)]
    Recording(#[from] jawtrack_recording::RecordingError),
    /// The `like` recording gives nothing to track with.
    #[error("--like {path}")]
    Like {
        /// The recording, as given.
        path: String,
        /// Why.
        #[source]
        source: Box<OfflineError>,
    },
    /// The camera file could not be read.
    #[error(transparent)]
    Camera(#[from] jawtrack_camera_calibration::CameraFileError),
    /// The intrinsics are not a camera.
    #[error("{what}")]
    Intrinsics {
        /// Whose: the flag's, or those taken from elsewhere.
        what: &'static str,
        /// Why not.
        #[source]
        source: jawtrack_pose::GeometryError,
    },
    /// The marker file could not be read.
    #[error(transparent)]
    MarkerFile(jawtrack_marker::MarkerError),
    /// The registration file could not be read.
    #[error("registration file {path}")]
    Registration {
        /// The file, as given.
        path: String,
        /// Why.
        #[source]
        source: jawtrack_registration::RegistrationError,
    },
    /// The tracker could not be made.
    #[error(transparent)]
    Tracker(#[from] jawtrack_tracker::TrackError),
    /// The refined marker could not be written.
    #[error("writing {path}")]
    SaveMarker {
        /// The file, as given.
        path: String,
        /// Why.
        #[source]
        source: jawtrack_recording::RecordingError,
    },
    /// Not one frame could be read or tracked.
    #[error(
        "none of the {frames} frames could be read{}: nothing tracked ({out} lists them, flagged `unreadable`)",
        if *frames == 0 { "" } else { " or tracked" }
    )]
    NothingTracked {
        /// Frames written, each flagged `unreadable`.
        frames: usize,
        /// The recording's name.
        out: String,
    },
    /// The caller refused to go on (e.g. an output that exists), or could not open the output.
    #[error(transparent)]
    Caller(Box<dyn std::error::Error + Send + Sync + 'static>),
}
