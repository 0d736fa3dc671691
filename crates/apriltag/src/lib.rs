//! AprilTag detection for JawTrack, after the AprilRobotics C library's structure: the
//! tag36h11 family ([`family`]), borrowed frames ([`image`]), the detector's settings
//! ([`config`]) and decoding sampled patterns to ids ([`decode`]). The quad-finding pipeline
//! (threshold, connected components, gradient clusters, quad fit, sampling, edge refinement)
//! is being ported stage by stage onto these.

mod codes;

pub mod config;
pub mod decode;
pub mod family;
pub mod image;

pub use config::{DetectorConfig, QuadThreshold, Roi};
pub use decode::{CodeTable, Decoded};
pub use family::{Tag36h11, TagBitmap};
pub use image::{ImageView, luma_from_bgra};

/// Why detection could not run.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DetectError {
    /// The buffer does not hold the image it claims to.
    #[error("bad image: {0}")]
    BadImage(String),
    /// A setting out of range.
    #[error("bad detector setting: {0}")]
    BadConfig(String),
}
