//! AprilTag detection for JawTrack, after the AprilRobotics C library's structure: the
//! tag families as data (tag36h11, tag25h9, tag16h5: [`family`]), borrowed frames ([`image`]), the detector's settings
//! ([`config`]), decoding sampled patterns to ids ([`decode`]), and the pipeline's stages
//! ported one by one and checked against C: [`preprocess`] (decimation), [`threshold`],
//! [`components`], [`clusters`], [`quads`], and in [`detector`] edge refinement, decoding
//! and removal of overlapping duplicates. [`Detector`] runs them: on our fixtures and the
//! real photos it returns exactly the C library's tags and corners (`tests/detector_vs_c.rs`).
//!
//! Where it departs from C on purpose (`DetectorConfig::reference()` undoes both):
//! - edges are refined JawTrack's way (`linear_edges`): in linear light, reading frames
//!   through the camera's tone curve as estimated from the tags ([`tone`]; sRGB until they
//!   tell), with unsquared gradient weights and a re-centred window. On our rendered frames
//!   the median corner error goes from C's 0.5–0.8 px (1080p) and 1.04 px (4K) to 0.02–0.04
//!   px (`tests/detector_accuracy.rs`); large drawn tags at any angle are within 0.011 px
//!   (`tests/detector_geometry.rs`).
//! - `min_white_black_diff` is 20, not 5: noisy frames are 5–7× faster, no tag is lost.
//!
//! Smallest tags found (black square, on white paper, upright and at 30°): 17 px at decimate
//! 1, 27.5 px at decimate 2, 49.5 px at decimate 4 — the same as C
//! (`tests/detector_geometry.rs`). Speed, recall, accuracy and memory against C:
//! `crates/detector-bench/BENCHMARKS.md`.
//!
//! With `nthreads` > 1, the image stages (decimation, threshold, regions, clusters) run by bands
//! of rows and quad fitting and decoding by cluster and quad on a thread pool ([`workers`]),
//! with the same results as one thread.
//!
//! [`TagDetector`] is what any detector backend offers; ours and the C library's
//! (`jawtrack-apriltag-reference`) implement it.

mod backend;

pub mod clusters;
pub mod components;
pub mod config;
pub mod decode;
pub mod detector;
pub mod gauss;
pub mod gray;
pub mod image;
pub mod preprocess;
pub mod quads;
pub mod threshold;
pub mod tone;
pub mod workers;

pub use backend::TagDetector;
pub use config::{DetectorConfig, QuadThreshold, Roi};
pub use decode::{CodeTable, Decoded};
pub use detector::{Detection, Detector, Expected, Search, StageTimes};
pub use gray::Gray;
pub use image::{ImageView, luma_from_bgra, luma_from_bgra_into};
pub use jawtrack_tag_family::{self as family, TagBitmap, TagFamily};
pub use jawtrack_tone::{ToneCurve, ToneReason, ToneSetting};

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
