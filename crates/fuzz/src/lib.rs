//! Fuzzing on the stable toolchain: every parser and door a user's input reaches, fed a
//! stream of mutants of valid inputs (`fixtures/`), with panics caught, hangs timed and each
//! target's invariants checked (a value read is written back and read again unchanged; a
//! refusal says why; the C door never panics). `jawtrack-fuzz --list` names the targets;
//! docs/fuzzing.md records the long runs.
//!
//! It needs no compiler instrumentation, so it runs wherever `cargo test` does; it has no
//! coverage feedback either, which the structure-aware mutators and the pool of accepted
//! mutants stand in for.
//!
//! # Examples
//!
//! ```
//! use jawtrack_fuzz::run::{Options, fuzz};
//! let target = jawtrack_fuzz::targets::all().into_iter().find(|t| t.name == "points").unwrap();
//! let options = Options { runs: 200, seed: 1, time_limit: std::time::Duration::from_secs(1) };
//! let tally = fuzz(&target, &options, Box::new(|_, _, _| std::process::exit(1)), |_| {}).unwrap();
//! assert_eq!(tally.inputs, 200);
//! ```

pub mod mutate;
pub mod run;
pub mod targets;
