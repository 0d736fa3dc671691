//! Camera calibration on rendered 1080p wave footage (not run in CI: minutes of rendering).
//!
//! For readouts of 5, 10 and 20 ms: renders the wave scene (the markers waved at 90–200 mm,
//! ≈ 100 mm/s) through a camera with radial distortion, with the renderer's noise, defocus and
//! sRGB encoding, detects the tags with the pure-Rust detector and calibrates; prints each
//! estimate's error against the truth beside its 1σ. The marker given is the one printed (its
//! print errors known, as after `calibrate-marker`). Exposure is an instant: motion blur with a
//! moving head renders every row at dozens of instants.
//!
//! `cargo bench -p jawtrack-camera-calibration --bench wave [-- FRAMES] [--encode CURVE]
//! [--readouts MS,MS,...]` (default 120 frames, 4 s at 30 fps, per readout; frames encoded as
//! sRGB; readouts 5, 10 and 20 ms). Each footage is calibrated twice: with the tags detected
//! as the CLI does (the tone curve estimated from them) and read as sRGB.

use jawtrack_apriltag::{Detector, DetectorConfig, ImageView, ToneCurve, ToneSetting};
use jawtrack_camera_calibration::{CameraCalibrationOptions, CameraFrame, SeenTag, calibrate_camera};
use jawtrack_pose::CameraIntrinsics;
use jawtrack_synth::{Realism, Resolution, SceneKind, SceneOptions, SynthConfig, Synthesizer};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let after = |flag: &str| args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1)).cloned();
    let frames: usize = args.iter().find_map(|a| a.parse().ok()).unwrap_or(120);
    let encode: ToneCurve = match after("--encode").map(|c| c.parse()).transpose() {
        Ok(c) => c.unwrap_or(ToneCurve::Srgb),
        Err(e) => {
            eprintln!("--encode: {e}");
            std::process::exit(2);
        }
    };
    let readouts: Vec<f64> = after("--readouts")
        .map_or(vec![5.0, 10.0, 20.0], |r| r.split(',').filter_map(|v| v.trim().parse().ok()).collect());
    let truth = CameraIntrinsics { fx: 1500.0, fy: 1495.0, cx: 962.5, cy: 537.5, k1: -0.05, k2: 0.02 };
    println!("wave scene, 1080p, 30 fps, {frames} frames per readout, encoded {encode}; camera {truth:?}");
    println!(
        "readout  tone read as    frames  rms px   fx err %  (1σ %)   fy err %  (1σ %)   cx err px (1σ)   \
         k1 err (1σ)        readout ms (1σ)     readout err %"
    );
    for (readout_ms, seed) in readouts.into_iter().zip(11..) {
        let config = SynthConfig {
            resolution: Resolution::P1080,
            intrinsics: Some(truth),
            seed,
            realism: Realism { readout_s: readout_ms / 1e3, exposure_s: 0.0, tone: encode, ..Realism::default() },
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
        let detector = |tone| match Detector::new(DetectorConfig { tone, ..DetectorConfig::default() }) {
            Ok(d) => d,
            Err(e) => {
                eprintln!("no detector: {e}");
                std::process::exit(1);
            }
        };
        let readings = [("auto", detector(ToneSetting::Auto)), ("srgb", detector(ToneSetting::Fixed(ToneCurve::Srgb)))];
        let started = Instant::now();
        let mut seen = [Vec::new(), Vec::new()];
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
            for ((_, detector), seen) in readings.iter().zip(&mut seen) {
                let view = ImageView::new(&frame.luma, width as usize, height as usize, width as usize);
                let tags = view
                    .and_then(|v| detector.detect(&v))
                    .map(|d| d.into_iter().map(|d| SeenTag { id: d.id, corners: d.corners }).collect())
                    .unwrap_or_default();
                seen.push(CameraFrame { t: frame.truth.t, tags });
            }
            eprint!("\rreadout {readout_ms} ms: rendered and detected {}/{}", i + 1, synth.len());
        }
        eprintln!(
            " in {:.0} s; auto read the frames through {}",
            started.elapsed().as_secs_f64(),
            readings[0].1.tone().curve
        );
        let marker = synth.true_marker().clone();
        for ((name, _), seen) in readings.iter().zip(&seen) {
            match calibrate_camera(seen, width, height, &marker, &CameraCalibrationOptions::default()) {
                Ok(c) => {
                    let (k, s) = (&c.intrinsics, &c.sigma);
                    let readout_err = 100.0 * (c.readout_s * 1e3 / readout_ms - 1.0);
                    println!(
                        "{readout_ms:5.0} ms  {name:13}  {:6}  {:6.3}   {:+7.3}  ({:.3})   {:+7.3}  ({:.3})   {:+6.2} ({:.2})     \
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
                Err(e) => println!("{readout_ms:5.0} ms  {name:13}  refused: {e}"),
            }
        }
    }
}
