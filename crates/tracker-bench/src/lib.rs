//! Our tracker against the reference stack — the AprilTag C library then OpenCV's SQPnP — on
//! the same rendered frames, as a library: the `tracker-bench` binary's per-view comparison
//! and the benchtop experiments in the 2020 thesis's form (`jawtrack bench accuracy`) both
//! stand on it.
//!
//! The reference stack is the `reference` feature (on by default): it alone links C. Without
//! it, as in the `jawtrack` binary, the benchtop runs our stack only and says where the
//! reference columns come from.

pub mod accuracy;
pub mod benchtop;
pub mod frames;
pub mod opencv;
#[cfg(feature = "reference")]
pub mod reference;
