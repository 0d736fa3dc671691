//! The uniffi API from Python: builds the library and `uniffi-bindgen`, generates the Python
//! bindings (the generated Swift is the same interface in another language), and runs
//! `tests/python/test_bindings.py` on the hinge fixture against the Rust tracker's poses.
//! Says SKIPPED without python3.

mod support;

use std::process::Command;

#[test]
fn python_drives_the_tracker_recorder_and_link_encoder() {
    if !support::have("python3", "--version") {
        jawtrack_test_support::say_skipped("no python3 for the uniffi binding test");
        return;
    }
    let lib_dir = support::build_library();
    let target_dir = lib_dir.parent().expect("target dir");
    let mut cargo = Command::new(env!("CARGO"));
    cargo.args(["build", "--release", "-q", "-p", "uniffi-bindgen", "--target-dir"]).arg(target_dir);
    assert!(cargo.status().expect("cargo runs").success(), "building uniffi-bindgen failed");

    let dir = tempfile::tempdir().expect("temp dir");
    let (bindings, frames, out) = (dir.path().join("bindings"), dir.path().join("frames"), dir.path().join("out"));
    for d in [&bindings, &frames, &out] {
        std::fs::create_dir_all(d).expect("folder");
    }
    let library = lib_dir.join("libjawtrack_ffi.so");
    let generated = Command::new(lib_dir.join("uniffi-bindgen"))
        .args(["generate", "--library"])
        .arg(&library)
        .args(["--language", "python", "--no-format", "--out-dir"])
        .arg(&bindings)
        .output()
        .expect("uniffi-bindgen runs");
    assert!(generated.status.success(), "{}", String::from_utf8_lossy(&generated.stderr));
    // The generated module loads the library from its own folder.
    std::fs::copy(&library, bindings.join("libjawtrack_ffi.so")).expect("copying the library");

    for (i, png) in support::frames().iter().enumerate() {
        let img = image::open(png).expect("frame").to_luma8();
        let mut pgm = format!("P5\n{} {}\n255\n", img.width(), img.height()).into_bytes();
        pgm.extend_from_slice(img.as_raw());
        std::fs::write(frames.join(format!("frame_{i:04}.pgm")), pgm).expect("writing a PGM");
    }
    let expected = dir.path().join("expected.json");
    let poses: Vec<Option<Vec<f64>>> = support::rust_poses().into_iter().map(|m| m.map(|m| m.to_vec())).collect();
    std::fs::write(&expected, serde_json::to_string(&poses).expect("json")).expect("writing the expected poses");

    let run = Command::new("python3")
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/test_bindings.py"))
        .args([&bindings, &frames, &expected, &out])
        .output()
        .expect("python3 runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    eprintln!("{}{stderr}", String::from_utf8_lossy(&run.stdout));
    assert!(run.status.success(), "the Python binding tests failed");
    assert!(stderr.contains("OK"), "unittest reports OK");
}
