//! The time of a session refinement (issue 25's target: 1,500 frames in ≤ 10 s on one core),
//! beside a full calibration from the same frames, in the same run: a marker calibrated from
//! 40 views that never showed tags 5–9 and 19–23, then a session of random views of both
//! bodies showing every tag. Medians of `--repeat` runs.
//!
//! `cargo bench -p jawtrack-calibration --bench session [-- --frames N --repeat N]`

#[path = "../tests/support/mod.rs"]
mod support;

use jawtrack_calibration::{CalibrationOptions, SessionOptions, calibrate, refine};
use jawtrack_marker::Marker;
use jawtrack_pose::median;
use std::time::Instant;
use support::{Lcg, printed, views};

fn arg(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn main() {
    let (frames, repeat) = (arg("--frames", 1500), arg("--repeat", 5).max(1));
    let mut rng = Lcg(11);
    let truth = printed(&mut rng);
    let (mut calibration, _) = views(&truth, 40, 0.2, &mut rng);
    for f in &mut calibration {
        f.tags.retain(|t| !((5..=9).contains(&t.id) || (19..=23).contains(&t.id)));
    }
    let marker = calibrate(&Marker::default(), &calibration, &CalibrationOptions::default())
        .expect("the calibration views calibrate")
        .marker;
    let (session, _) = views(&truth, frames, 0.2, &mut rng);
    let time = |f: &mut dyn FnMut()| {
        median((0..repeat).map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        }))
        .unwrap_or(f64::NAN)
    };
    let mut placed = 0;
    let refine_s = time(&mut || {
        let r = refine(&marker, &session, &SessionOptions::default()).expect("refines");
        placed = r.bodies.iter().map(|b| b.placed.len()).sum();
    });
    let calibrate_s = time(&mut || {
        calibrate(&Marker::default(), &session, &CalibrationOptions::default()).expect("calibrates");
    });
    println!("session of {frames} frames, median of {repeat} runs, one core:");
    println!(
        "  refine (at most {} frames used): {refine_s:.3} s, {placed} tags placed",
        SessionOptions::default().max_frames
    );
    println!("  calibrate from every frame:      {calibrate_s:.3} s ({:.1}× the refinement)", calibrate_s / refine_s);
}
