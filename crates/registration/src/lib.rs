//! Registration: where each marker sits in its arch's intra-oral scan, so that the tracked jaw
//! motion (marker against marker) becomes the motion of the lower tooth scan against the upper.
//!
//! - `file`, re-exported here: the registration file ([`Registration`], written by `jawtrack
//!   register`, read by `track --registration`, the clinical commands, the viewer and the app),
//!   its maths (`maxilla_from_mandible` to `maxilla_scan_from_mandible_scan`) and the
//!   maximal-intercuspation correction ([`calibrate_intercuspation`]);
//! - [`bite`]: the one rule for what counts as a held bite (maximal intercuspation), used by
//!   the tracker's intercuspation step, the app and the live viewer;
//! - [`icp`] (feature `icp`, on by default): the marker-to-scan ICP that finds where a marker's
//!   frame sits in a scan of its printed harness, and judges the fit.
//!
//! The tracker applies a registration and the readers of recordings (session, viewer) use one,
//! so this crate sits below them and links no tag detector. The ICP needs `jawtrack-mesh`; the
//! tracker, and through it the iPhone library, depend on this crate without the `icp` feature
//! and so link no mesh code.

pub mod bite;
mod file;
#[cfg(feature = "icp")]
pub mod icp;

pub use bite::{Bite, BiteRefusal, BiteRule, BiteWindow};
pub use file::{
    IntercuspationCalibration, REGISTRATION_VERSION, Registration, RegistrationError, Units, calibrate_intercuspation,
    mean_pose,
};
