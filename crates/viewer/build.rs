//! Embeds the viewer page into the library: our files from `viewer/` and the three.js modules
//! the page imports, vendored in `viewer/vendor/three` (three.js 0.187.0 under its MIT licence,
//! `viewer/vendor/README.md`), so every build serves a working page with nothing installed.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The page's own files, served at `/NAME`.
const PAGE: [&str; 5] = ["index.html", "viewer.js", "anatomy.js", "pick.js", "style.css"];
/// The three.js files the page imports (its import map and their own imports), under
/// `viewer/vendor/three`, served at `/vendor/three/…`.
const THREE: [&str; 7] = [
    "build/three.module.js",
    "build/three.core.js",
    "examples/jsm/controls/OrbitControls.js",
    "examples/jsm/loaders/STLLoader.js",
    "examples/jsm/loaders/PLYLoader.js",
    "examples/jsm/loaders/OBJLoader.js",
    "examples/jsm/utils/BufferGeometryUtils.js",
];

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let viewer = manifest.join("../../viewer");
    let three = viewer.join("vendor/three");
    let mut files: Vec<(String, PathBuf)> = PAGE.iter().map(|name| (format!("/{name}"), viewer.join(name))).collect();
    files.extend(THREE.iter().map(|f| (format!("/vendor/three/{f}"), three.join(f))));
    let mut code = String::from("/// The embedded page: (URL path, content type, bytes).\n");
    code.push_str("pub(crate) static FILES: &[(&str, &str, &[u8])] = &[\n");
    for (url, path) in &files {
        println!("cargo:rerun-if-changed={}", path.display());
        assert!(path.is_file(), "the viewer page file {} is missing", path.display());
        let _ = writeln!(code, "    ({url:?}, {:?}, include_bytes!({:?})),", content_type(path), absolute(path));
    }
    code.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("page.rs");
    std::fs::write(&out, code).expect("writing the embedded page's table");
}

fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()) {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        _ => "application/octet-stream",
    }
}

fn absolute(path: &Path) -> PathBuf {
    path.canonicalize().unwrap_or_else(|_| path.to_path_buf())
}
