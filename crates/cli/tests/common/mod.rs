//! Helpers the command-line tests share: running the built binary and reading its outcome.
#![allow(dead_code)] // each test file uses its own subset

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `jawtrack` binary built for these tests.
pub fn jawtrack(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_jawtrack")).args(args).output().expect("the binary runs")
}

/// Its standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts the command succeeded (showing its standard error if not); returns its output.
pub fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", stderr(o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Asserts the command failed with `needle` in its message, and without a panic.
pub fn refused(o: &Output, needle: &str) {
    let e = stderr(o);
    assert!(!o.status.success() && e.contains(needle) && !e.contains("panicked"), "wanted '{needle}': {e}");
}

/// A path as the `&str` an argument list wants.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A one-frame poses file in `dir` whose lower scan sits where the upper scan's frame puts it
/// (the identity pose): scans exported in occlusion, for `contacts`.
pub fn identity_bite(dir: &Path) -> std::path::PathBuf {
    let p = dir.join("identity.jsonl");
    std::fs::write(&p, "{\"frame\":0,\"t\":0,\"maxilla_from_mandible\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}\n")
        .expect("write poses");
    p
}
