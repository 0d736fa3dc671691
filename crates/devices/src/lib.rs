//! What is known about phone cameras that no API reports, and what follows from it for
//! filming the markers: each model's sensor readout ([`readout()`]), its lenses' optics — focal
//! length, f-number, the nearest they focus, whether the sensor gives a native 2× crop
//! ([`optics()`]) — the capture plan those facts call for: camera, format, zoom and the distance
//! to hold the phone at, beyond where it can focus ([`plan()`]), and the guidance that keeps the
//! phone there while it films ([`guidance`]).
//!
//! Models are keyed by their hardware identifier (`uname().machine`, e.g. `iPhone16,2`), which
//! names the exact phone, where marketing names are ambiguous. Every figure carries its source;
//! a model not listed gets conservative defaults and says so. What the phone reports at run
//! time (AVFoundation's `minimumFocusDistance`, a format's field of view and native zoom
//! factors) beats the table.

pub mod guidance;
pub mod optics;
pub mod plan;
pub mod readout;

pub use guidance::{Guidance, GuidanceKind, guide};
pub use optics::{LensOptics, optics};
pub use plan::{CameraFacts, CapturePlan, FormatFacts, PlanRequest, plan};
pub use readout::{Readout, readout};

/// A phone's camera, by lens.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lens {
    /// The back wide-angle (main) camera.
    Wide,
    /// The back ultra-wide camera.
    UltraWide,
    /// The back telephoto camera.
    Tele,
    /// The front camera.
    Front,
}

/// Why no capture plan could be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeviceError {
    /// A number given is out of range.
    #[error("{0}")]
    Invalid(String),
    /// No format of the camera can film what is asked.
    #[error("{0}")]
    NoFormat(String),
}
