//! AprilTag detection for JawTrack, after the AprilRobotics C library's structure: the
//! tag36h11 family ([`family`]), borrowed frames ([`image`]), the detector's settings
//! ([`config`]), decoding sampled patterns to ids ([`decode`]), and the pipeline's stages
//! ported one by one and checked against C: [`preprocess`] (decimation), [`threshold`],
//! [`components`], [`clusters`], [`quads`], and in [`detector`] edge refinement, decoding
//! and removal of overlapping duplicates. [`Detector`] runs them: on our fixtures and the
//! real photos it returns exactly the C library's tags and corners (`tests/detector_vs_c.rs`).
//!
//! Where it departs from C on purpose: edges are refined in linear light by default
//! (`linear_edges`), reading phone frames as sRGB — on our rendered frames this takes the
//! median corner error from C's 0.5–0.8 px to 0.03 px (`tests/detector_accuracy.rs`);
//! `linear_edges: false` reproduces C exactly.
//!
//! With `nthreads` > 1, quad fitting and decoding run on a thread pool ([`workers`]), with the
//! same results as one thread.
//!
//! Not yet: `quad_sigma` other than 0 (refused).

mod codes;

pub mod clusters;
pub mod components;
pub mod config;
pub mod decode;
pub mod detector;
pub mod family;
pub mod gray;
pub mod image;
pub mod preprocess;
pub mod quads;
pub mod threshold;
pub mod workers;

pub use config::{DetectorConfig, QuadThreshold, Roi};
pub use decode::{CodeTable, Decoded};
pub use detector::{Detection, Detector};
pub use family::{Tag36h11, TagBitmap};
pub use gray::Gray;
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
