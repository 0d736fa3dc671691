//! What the app's frame path costs beyond the Rust pipeline: a 1080p luma frame through the C
//! entry point `jt_track_luma` (the call Swift makes inside `CVPixelBufferLockBaseAddress`,
//! reading the plane in place) plus `Tracker::last_result()` lowered the way uniffi hands it
//! to Swift, against `jawtrack_tracker::Tracker::track` alone on the same frames.
//!
//! `cargo bench -p jawtrack-ffi --bench frame_path [-- --passes N]`. Each pass tracks the
//! fixture's frames with a fresh tracker on each path, the two paths taking turns to go first;
//! the table gives per-frame medians over passes and their difference. Target: the C path costs
//! no more than the Rust pipeline plus 0.1 ms.

use jawtrack_apriltag::{DetectorConfig, ImageView};
use jawtrack_ffi::c_api::{JtIntrinsics, JtStatus, jt_track_luma};
use jawtrack_ffi::{FrameResult, Tracker, UniFfiTag, default_settings};
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_tracker::{SearchConfig, TrackerConfig};
use std::time::Instant;

/// The median of a list of times (NaN for none).
fn median(v: &[f64]) -> f64 {
    jawtrack_pose::median(v.iter().copied()).unwrap_or(f64::NAN)
}

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/hinge-1080p");

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let passes: usize = args
        .iter()
        .position(|a| a == "--passes")
        .and_then(|i| args.get(i + 1))
        .and_then(|n| n.parse().ok())
        .unwrap_or(30);
    let mut paths: Vec<_> = std::fs::read_dir(FIXTURE)
        .expect("the hinge fixture")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    paths.sort();
    let frames: Vec<(Vec<u8>, u32, u32)> = paths
        .iter()
        .map(|p| {
            let img = image::open(p).expect("frame").to_luma8();
            let (w, h) = (img.width(), img.height());
            (img.into_raw(), w, h)
        })
        .collect();
    let camera = CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5);
    let k = JtIntrinsics { fx: 1500.0, fy: 1500.0, cx: 959.5, cy: 539.5, k1: 0.0, k2: 0.0 };
    let config = TrackerConfig {
        detector: DetectorConfig { quad_decimate: 2.0, nthreads: 1, linear_edges: true, ..DetectorConfig::default() },
        search: SearchConfig { region_search: true, ..SearchConfig::default() },
        ..TrackerConfig::default()
    };
    let n = frames.len();
    // Whole call, and the part outside the tracker's own detection and pose timers: the two
    // paths run the same tracker code, so the difference of the outside parts is the C path's
    // added cost, free of the detector's frame-to-frame noise.
    let (mut rust_ms, mut c_ms) = (vec![Vec::new(); n], vec![Vec::new(); n]);
    let (mut rust_outside, mut c_outside) = (vec![Vec::new(); n], vec![Vec::new(); n]);
    for pass in 0..passes {
        let mut rust = jawtrack_tracker::Tracker::new(Marker::default(), config).expect("tracker");
        let ffi = Tracker::new(default_settings(), None).expect("tracker");
        let mut run_rust = |i: usize| {
            let (data, w, h) = &frames[i];
            let view = ImageView::new(data, *w as usize, *h as usize, *w as usize).expect("view");
            let start = Instant::now();
            let r = rust.track(&view, &camera, i as f64 / 30.0).expect("tracked");
            let ms = start.elapsed().as_secs_f64() * 1e3;
            assert!(r.maxilla_from_mandible.is_some());
            (ms, ms - (r.timings.detection_s + r.timings.pose_s) * 1e3)
        };
        let run_c = |i: usize| {
            let (data, w, h) = &frames[i];
            let start = Instant::now();
            // SAFETY: `data` holds w × h bytes with rows w apart; `k` is a valid JtIntrinsics.
            #[allow(unsafe_code)]
            let status = unsafe {
                jt_track_luma(
                    ffi.frame_handle(),
                    data.as_ptr(),
                    data.len(),
                    *w,
                    *h,
                    *w,
                    &k,
                    i as f64 / 30.0,
                    0.002,
                    std::ptr::null_mut(),
                )
            };
            // What Swift receives: the result lowered into a RustBuffer by uniffi.
            let result = ffi.last_result();
            let inside = result.as_ref().map_or(0.0, |r| r.detection_ms + r.pose_ms);
            let lowered = <Option<FrameResult> as uniffi::Lower<UniFfiTag>>::lower(result);
            let ms = start.elapsed().as_secs_f64() * 1e3;
            assert_eq!(status, JtStatus::Ok);
            assert!(!lowered.is_empty());
            lowered.destroy();
            (ms, ms - inside)
        };
        for i in 0..n {
            let (r, c) = if pass % 2 == 0 {
                let r = run_rust(i);
                (r, run_c(i))
            } else {
                let c = run_c(i);
                (run_rust(i), c)
            };
            rust_ms[i].push(r.0);
            rust_outside[i].push(r.1);
            c_ms[i].push(c.0);
            c_outside[i].push(c.1);
        }
    }
    println!("1080p luma frames of {FIXTURE}, {passes} passes, one detector thread; medians per frame (ms)");
    println!(
        "| frame | Rust pipeline | C entry + uniffi result | outside the tracker's timers: Rust | C path | added by the C path |"
    );
    println!("|---|---|---|---|---|---|");
    let mut added = Vec::new();
    for i in 0..n {
        let (r, c) = (median(&rust_ms[i]), median(&c_ms[i]));
        let (ro, co) = (median(&rust_outside[i]), median(&c_outside[i]));
        added.push(co - ro);
        println!("| {i} | {r:.3} | {c:.3} | {ro:.3} | {co:.3} | {:+.3} |", co - ro);
    }
    let worst = added.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    println!("added by the C path: median {:+.3} ms, worst frame {worst:+.3} ms (target ≤ +0.1 ms)", median(&added));
}
