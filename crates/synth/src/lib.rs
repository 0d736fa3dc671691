//! Synthetic rig renderer: frames of the two dodecahedron markers as an iPhone would film
//! them, with exact ground truth, for tests, fixtures and benchmarks. It is never linked into
//! the iOS library.
//!
//! The pipeline is [`render`] (exact anti-aliased geometry in linear light, motion blur over the
//! exposure, and a rolling shutter's row-by-row exposure when [`Realism::readout_s`] is set)
//! then [`post`] (defocus, glare, illumination, sensor noise, transfer curve), driven by a
//! [`scenes`] scene and the [`Realism`] settings; [`Synthesizer`] ties them together and
//! [`truth`] is the ground-truth file. [`selfcheck`] measures the renderer's own edge placement.

pub mod post;
pub mod realism;
pub mod render;
pub mod scenes;
pub mod selfcheck;
pub mod truth;

mod shutter;
mod synthesizer;
mod write;

pub use realism::{Pupil, Realism};
pub use render::{Camera, INK_ALBEDO, LinearImage, PAPER_ALBEDO, RenderScene};
pub use scenes::{Orientation, SceneKind, SceneOptions};
pub use synthesizer::{Frame, Resolution, SynthConfig, Synthesizer, to_bgra};
pub use truth::{FrameTruth, GroundTruth, TagTruth};
pub use write::{SceneSummary, write_scene};

/// Errors of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A setting that cannot be rendered.
    #[error("invalid setting: {0}")]
    Config(String),
    /// The marker is not usable.
    #[error(transparent)]
    Marker(#[from] jawtrack_marker::MarkerError),
    /// Writing output failed.
    #[error("{path}: {reason}")]
    Io {
        /// The file or folder.
        path: String,
        /// Why.
        reason: String,
    },
}
