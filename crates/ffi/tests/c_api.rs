//! The C API from C: `tests/c/track_frames.c` is compiled against the checked-in header and
//! linked with the static library, tracks the hinge fixture, and must give the Rust tracker's
//! poses exactly; then it checks that every misuse (null pointers, short buffers, rows shorter
//! than the width, freed and made-up handles, bad settings) returns an error code and a
//! message. Needs a C compiler (`cc`); says SKIPPED without one.

mod support;

use std::process::Command;

#[test]
fn c_tracks_the_fixture_as_rust_does_and_misuse_is_refused() {
    if !support::have("cc", "--version") {
        jawtrack_test_support::say_skipped("no C compiler (cc) to build the C API test");
        return;
    }
    let lib_dir = support::build_library();
    let dir = tempfile::tempdir().expect("temp dir");
    let exe = dir.path().join("track_frames");
    let manifest = env!("CARGO_MANIFEST_DIR");
    let cc = Command::new("cc")
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-O2", "-I"])
        .arg(format!("{manifest}/include"))
        .arg(format!("{manifest}/tests/c/track_frames.c"))
        .arg(lib_dir.join("libjawtrack_ffi.a"))
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&exe)
        .output()
        .expect("cc runs");
    assert!(cc.status.success(), "compiling the C test failed:\n{}", String::from_utf8_lossy(&cc.stderr));

    let mut pgms = Vec::new();
    for (i, png) in support::frames().iter().enumerate() {
        let img = image::open(png).expect("frame").to_luma8();
        let p = dir.path().join(format!("frame_{i:04}.pgm"));
        let mut pgm = format!("P5\n{} {}\n255\n", img.width(), img.height()).into_bytes();
        pgm.extend_from_slice(img.as_raw());
        std::fs::write(&p, pgm).expect("writing a PGM");
        pgms.push(p);
    }
    let [fx, fy, cx, cy] = support::INTRINSICS.map(|v| v.to_string());
    let run = Command::new(&exe).args([fx, fy, cx, cy]).args(&pgms).output().expect("the C test runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "the C test failed:\n{stdout}\n{}", String::from_utf8_lossy(&run.stderr));
    assert!(stdout.lines().any(|l| l == "misuse: ok"), "{stdout}");

    let from_c: Vec<Option<Vec<f64>>> = stdout
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).expect("a JSON line");
            serde_json::from_value(v["maxilla_from_mandible"].clone()).expect("16 numbers or null")
        })
        .collect();
    let from_rust = support::rust_poses();
    assert_eq!(from_c.len(), from_rust.len());
    assert!(from_rust.iter().all(Option::is_some), "the fixture's jaw is tracked in every frame");
    for (i, (c, r)) in from_c.iter().zip(&from_rust).enumerate() {
        // %.17g round-trips doubles exactly: the same computation must give the same bits.
        assert_eq!(c.as_deref(), r.as_ref().map(|m| &m[..]), "frame {i}: C and Rust differ");
    }
}
