//! Camera calibration on rendered 1080p wave footage (not run in CI: minutes of rendering).
//!
//! For readouts of 5, 10 and 20 ms: renders the wave scene (the markers waved at 90–200 mm,
//! ≈ 100 mm/s) through a camera with radial distortion, with the renderer's noise, defocus and
//! sRGB encoding, detects the tags with the pure-Rust detector and calibrates; prints each
//! estimate's error against the truth beside its 1σ. The marker given is the one printed (its
//! print errors known, as after `calibrate-marker`). Exposure is an instant: motion blur with a
//! moving head renders every row at dozens of instants.
//!
//! `cargo bench -p jawtrack-camera-calibration --bench wave [-- FRAMES]` (default 120 frames,
//! 4 s at 30 fps, per readout).

use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
use jawtrack_camera_calibration::{CameraCalibrationOptions, CameraFrame, SeenTag, calibrate_camera};
use jawtrack_pose::CameraIntrinsics;
use jawtrack_synth::{Realism, Resolution, SceneKind, SceneOptions, SynthConfig, Synthesizer};
use std::time::Instant;

fn main() {
    let frames: usize = std::env::args().skip(1).find_map(|a| a.parse().ok()).unwrap_or(120);
    let truth = CameraIntrinsics { fx: 1500.0, fy: 1495.0, cx: 962.5, cy: 537.5, k1: -0.05, k2: 0.02 };
    println!("wave scene, 1080p, 30 fps, {frames} frames per readout; camera {truth:?}");
    println!(
        "readout  frames  rms px   fx err %  (1σ %)   fy err %  (1σ %)   cx err px (1σ)   k1 err (1σ)        \
         readout ms (1σ)     readout err %"
    );
    for (readout_ms, seed) in [(5.0, 11), (10.0, 12), (20.0, 13)] {
        let config = SynthConfig {
            resolution: Resolution::P1080,
            intrinsics: Some(truth),
            seed,
            realism: Realism { readout_s: readout_ms / 1e3, exposure_s: 0.0, ..Realism::default() },
            options: SceneOptions { cycles: frames.div_ceil(60), fps: 30.0, ..SceneOptions::default() },
            max_frames: Some(frames),
            ..SynthConfig::new(SceneKind::Wave)
        };
        let synth = match Synthesizer::new(config) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("cannot render: {e}");
                std::process::exit(1);
            }
        };
        let detector = match Detector::new(DetectorConfig::default()) {
            Ok(d) => d,
            Err(e) => {
                eprintln!("no detector: {e}");
                std::process::exit(1);
            }
        };
        let started = Instant::now();
        let mut seen = Vec::new();
        let (mut width, mut height) = (0, 0);
        for i in 0..synth.len() {
            let frame = match synth.render(i) {
                Ok(f) => f,
                Err(e) => {
                    eprintln!("frame {i}: {e}");
                    std::process::exit(1);
                }
            };
            (width, height) = (frame.width, frame.height);
            let view = ImageView::new(&frame.luma, width as usize, height as usize, width as usize);
            let tags = view
                .and_then(|v| detector.detect(&v))
                .map(|d| d.into_iter().map(|d| SeenTag { id: d.id, corners: d.corners }).collect())
                .unwrap_or_default();
            seen.push(CameraFrame { t: frame.truth.t, tags });
            eprint!("\rreadout {readout_ms} ms: rendered and detected {}/{}", i + 1, synth.len());
        }
        eprintln!(" in {:.0} s", started.elapsed().as_secs_f64());
        let marker = synth.true_marker().clone();
        match calibrate_camera(&seen, width, height, &marker, &CameraCalibrationOptions::default()) {
            Ok(c) => {
                let (k, s) = (&c.intrinsics, &c.sigma);
                let readout_err = 100.0 * (c.readout_s * 1e3 / readout_ms - 1.0);
                println!(
                    "{readout_ms:5.0} ms  {:6}  {:6.3}   {:+7.3}  ({:.3})   {:+7.3}  ({:.3})   {:+6.2} ({:.2})     \
                     {:+.4} ({:.4})   {:7.3} ({:.3})    {:+6.2}",
                    c.frames_used,
                    c.rms_px,
                    100.0 * (k.fx / truth.fx - 1.0),
                    100.0 * s.fx / k.fx,
                    100.0 * (k.fy / truth.fy - 1.0),
                    100.0 * s.fy / k.fy,
                    k.cx - truth.cx,
                    s.cx,
                    k.k1 - truth.k1,
                    s.k1,
                    c.readout_s * 1e3,
                    s.readout_s * 1e3,
                    readout_err
                );
            }
            Err(e) => println!("{readout_ms:5.0} ms  refused: {e}"),
        }
    }
}
