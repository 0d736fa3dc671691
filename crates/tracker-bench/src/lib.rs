//! Our tracker against the reference stack — the AprilTag C library then OpenCV's SQPnP — on
//! the same rendered frames, as a library: the `tracker-bench` binary's per-view comparison
//! and `jawtrack bench accuracy`'s benchtop experiments in the 2020 thesis's form both stand
//! on it.

pub mod accuracy;
pub mod benchtop;
pub mod frames;
pub mod opencv;
pub mod reference;
