//! Our tracker against the reference stack — the AprilTag C library then OpenCV's SQPnP — on
//! the same rendered frames, as a library: the `tracker-bench` binary's per-view comparison
//! and the benchtop experiments in the 2020 thesis's form (`jawtrack-bench accuracy`) both
//! stand on it. `jawtrack-bench pipeline`'s timing of the tracking pipeline lives here too
//! ([`pipeline`]): it needs no C, but it is benchmark code, not the product's.
//!
//! The reference stack is the `reference` feature (on by default): it alone links C. Without
//! it, as in the `jawtrack` binary, the benchtop runs our stack only and says where the
//! reference columns come from.

pub mod accuracy;
pub mod benchtop;
pub mod capture;
pub mod chew;
pub mod dense;
pub mod frames;
pub mod opencv;
pub mod pipeline;
#[cfg(feature = "reference")]
pub mod reference;

/// Prints a line, ending the program quietly when stdout is closed (`… | head`) instead of
/// panicking, as the `jawtrack` command does.
pub(crate) fn say(line: std::fmt::Arguments<'_>) {
    use std::io::Write as _;
    if writeln!(std::io::stdout(), "{line}").is_err() {
        std::process::exit(0);
    }
}
