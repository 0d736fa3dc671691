//! The detector's entry point on arbitrary input: the first bytes choose the image's width,
//! height and stride (unchecked, so bad sizes are tried too) and one of 60 detectors
//! (decimation × max_hamming × contrast threshold and blur or sharpening); the rest are the pixels. Anything may be
//! returned, an error included, but nothing may panic.

#![no_main]

use jawtrack_apriltag::{Detector, DetectorConfig, ImageView, QuadThreshold};
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

/// Built once: a max_hamming 2 table takes longer than many detections.
fn detectors() -> &'static [Detector] {
    static D: OnceLock<Vec<Detector>> = OnceLock::new();
    D.get_or_init(|| {
        let mut v = Vec::new();
        for quad_decimate in [1.0, 1.5, 2.0, 3.0, 4.0] {
            for max_hamming in 0..3 {
                for (min_white_black_diff, quad_sigma) in [(5, 0.0), (20, 0.0), (20, 0.8), (5, -1.2)] {
                    let config = DetectorConfig {
                        quad_decimate,
                        quad_sigma,
                        max_hamming,
                        quad: QuadThreshold { min_white_black_diff, ..QuadThreshold::default() },
                        ..DetectorConfig::default()
                    };
                    v.push(Detector::new(config).expect("valid settings"));
                }
            }
        }
        v
    })
}

fuzz_target!(|data: &[u8]| {
    let [w, h, s, which, rest @ ..] = data else { return };
    let (width, height) = (usize::from(*w), usize::from(*h));
    let stride = width + usize::from(*s % 8);
    let detectors = detectors();
    let detector = &detectors[usize::from(*which) % detectors.len()];
    // Bad sizes must come back as errors from `new`, never as a panic.
    let Ok(view) = ImageView::new(rest, width, height, stride) else { return };
    let _ = detector.detect(&view);
});
