//! Shared by the binding tests: building the library as C and Python load it, and the Rust
//! results they are compared with.

use jawtrack_apriltag::{DetectorConfig, ImageView};
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_tracker::{SearchConfig, Tracker, TrackerConfig};
use std::path::PathBuf;
use std::process::Command;

/// The fixture the binding tests track, and its camera.
pub const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/hinge-1080p");
pub const INTRINSICS: [f64; 4] = [1500.0, 1500.0, 959.5, 539.5];

/// The fixture's frames in name order.
pub fn frames() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(FIXTURE)
        .expect("fixture folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    v.sort();
    v
}

/// `maxilla_from_mandible` per frame (row-major) from the Rust tracker with `jawtrack track`'s
/// defaults, frame i at t = i / 30 s.
pub fn rust_poses() -> Vec<Option<[f64; 16]>> {
    let config = TrackerConfig {
        detector: DetectorConfig { quad_decimate: 2.0, nthreads: 1, linear_edges: true, ..DetectorConfig::default() },
        search: SearchConfig { region_search: true, ..SearchConfig::default() },
        ..TrackerConfig::default()
    };
    let mut tracker = Tracker::new(Marker::default(), config).expect("tracker");
    let [fx, fy, cx, cy] = INTRINSICS;
    let camera = CameraIntrinsics::pinhole(fx, fy, cx, cy);
    frames()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let img = image::open(p).expect("frame").to_luma8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            let r = tracker.track(&ImageView::new(img.as_raw(), w, h, w).expect("view"), &camera, i as f64 / 30.0);
            r.expect("tracked").maxilla_from_mandible.map(|m| m.to_row_major())
        })
        .collect()
}

/// Builds the library's `staticlib` and `cdylib` in release (cargo test builds only the
/// `lib`) and returns the folder they are in. Release, whatever this test's profile: it is the
/// build the app links and the Swift step has already made (`ios/swift-on-linux.sh`, the same
/// command, so CI builds it once), where a dev build with this package's features alone would
/// rebuild the dependencies a second time.
pub fn build_library() -> PathBuf {
    let exe = std::env::current_exe().expect("test path");
    let target_dir = exe.ancestors().nth(3).expect("target/<profile>/deps/<test>").to_path_buf();
    let mut cargo = Command::new(env!("CARGO"));
    cargo.args(["build", "--release", "-q", "-p", "jawtrack-ffi", "--lib", "--target-dir"]).arg(&target_dir);
    let status = cargo.status().expect("cargo runs");
    assert!(status.success(), "building jawtrack-ffi failed");
    target_dir.join("release")
}

/// Whether `program` can be run.
pub fn have(program: &str, arg: &str) -> bool {
    Command::new(program).arg(arg).output().is_ok_and(|o| o.status.success())
}
