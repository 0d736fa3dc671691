//! Pose time per body with the rolling shutter compensated, beside today's solve of the same
//! scene's global-shutter frames, in the same run (issue 22's target: at most 2× today's).
//! The frames are exact detections of a jaw chewing at up to ~90 mm/s (three tags per body,
//! 1080 rows, 60 fps): no detection runs, so only the pose work is timed. Each frame's
//! `Tracker::solve` is timed whole and halved (two bodies); medians over `--repeat` passes of
//! `--frames` frames.
//!
//! `cargo bench -p jawtrack-tracker --bench pose_time [-- --frames N --repeat N --readout-ms MS]`

#[path = "../tests/support/mod.rs"]
mod support;

use jawtrack_marker::Marker;
use jawtrack_pose::{RollingShutter, median};
use jawtrack_tracker::{Tracker, TrackerConfig};
use std::time::Instant;
use support::{FPS, ROWS, camera, detections};

fn arg(name: &str, default: f64) -> f64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Per-body pose times (µs) of every frame after the first two, `repeat` passes.
fn times(readout_s: f64, frames: usize, repeat: usize) -> (Vec<f64>, Vec<f64>) {
    let marker = Marker::default();
    let shutter = RollingShutter::new(readout_s, ROWS).expect("valid readout");
    let scene: Vec<_> = (0..frames).map(|i| (i as f64 / FPS, detections(&marker, i as f64 / FPS, &shutter))).collect();
    let config = TrackerConfig { readout_s, ..TrackerConfig::default() };
    let (mut wall, mut inside) = (Vec::new(), Vec::new());
    for _ in 0..repeat {
        let mut tracker = Tracker::new(marker.clone(), config).expect("tracker");
        for (i, (t, dets)) in scene.iter().enumerate() {
            let dets = dets.clone();
            let start = Instant::now();
            let r = tracker.solve(dets, &camera(), *t, ROWS);
            let us = start.elapsed().as_secs_f64() * 1e6;
            assert!(r.maxilla_from_mandible.is_some(), "frame {i}: both bodies solved");
            // The first two frames have no velocity yet: the compensated path starts at the third.
            if i >= 2 {
                wall.push(us / 2.0);
                inside.push(r.timings.pose_s * 1e6 / 2.0);
            }
        }
    }
    (wall, inside)
}

fn main() {
    let frames = (arg("--frames", 120.0) as usize).max(3);
    let repeat = (arg("--repeat", 20.0) as usize).max(1);
    let readout_s = arg("--readout-ms", 10.0) / 1e3;
    println!("pose time per body, {frames} frames × {repeat} passes, median (µs)");
    println!("{:<44} {:>10} {:>16}", "", "solve", "timings.pose_s");
    let (w0, p0) = times(0.0, frames, repeat);
    let (w1, p1) = times(readout_s, frames, repeat);
    let med = |v: &[f64]| median(v.iter().copied()).expect("timed frames");
    let (m0, m1) = (med(&w0), med(&w1));
    println!("{:<44} {:>10.1} {:>16.1}", "global shutter, readout 0 (today's path)", m0, med(&p0));
    println!("{:<44} {:>10.1} {:>16.1}", format!("rolling shutter, {} ms compensated", readout_s * 1e3), m1, med(&p1));
    println!("ratio compensated / today: {:.2} (target ≤ 2)", m1 / m0);
}
