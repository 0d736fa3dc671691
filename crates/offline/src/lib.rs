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
mod summary;

pub use like::RecordedCapture;
pub use passes::{Detected, Kept, first_pass, refine_marker, track_frame};
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
}
