//! One detector configuration run over the same frames again and again, for profiling and for
//! A/B timings of one stage (`perf record`, `valgrind --tool=cachegrind`), without the C library
//! or the other rows of `detector-bench` in the profile.
//!
//! ```sh
//! cargo run --release -p jawtrack-detector-bench --example detect_loop -- c-params 3 fixtures/hinge-1080p/*.png
//! DUMP=1 target/release/examples/detect_loop ours 1 fixtures/*/*.png 2> detections.txt
//! ```
//!
//! The configuration is `c-work` (C's parameters and edge refit), `c-params` (C's parameters,
//! our edge refit) or `ours` (the defaults), as `detector-bench` names its rows; decimation 2 and
//! one thread unless `DECIMATE` says otherwise. It prints the mean time a frame; with `DUMP` set,
//! every detection to standard error (id, corrected bits, corners, margin; to the last bit), to
//! check a change leaves them as they were.

use anyhow::{Context, Result, bail};
use jawtrack_apriltag::{Detector, DetectorConfig, ImageView, QuadThreshold};
use std::time::Instant;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [which, passes, paths @ ..] = args.as_slice() else {
        bail!("usage: detect_loop c-work|c-params|ours PASSES FRAME...");
    };
    let passes: usize = passes.parse().with_context(|| format!("PASSES must be a count, got {passes:?}"))?;
    if paths.is_empty() {
        bail!("no frames given");
    }
    let decimate = match std::env::var("DECIMATE") {
        Ok(v) => v.parse().with_context(|| format!("DECIMATE must be a number, got {v:?}"))?,
        Err(_) => 2.0,
    };
    let base = DetectorConfig { quad_decimate: decimate, nthreads: 1, linear_edges: true, ..DetectorConfig::default() };
    let config = match which.as_str() {
        "c-work" => DetectorConfig { quad: QuadThreshold::reference(), linear_edges: false, ..base },
        "c-params" => DetectorConfig { quad: QuadThreshold::reference(), ..base },
        "ours" => base,
        other => bail!("unknown configuration {other:?}: c-work, c-params or ours"),
    };
    let frames: Vec<image::GrayImage> = paths
        .iter()
        .map(|p| image::open(p).with_context(|| format!("reading {p}")).map(|i| i.to_luma8()))
        .collect::<Result<_>>()?;
    let detector = Detector::new(config)?;
    let dump = std::env::var_os("DUMP").is_some();
    let (start, mut tags) = (Instant::now(), 0);
    for _ in 0..passes {
        for frame in &frames {
            let (w, h) = (frame.width() as usize, frame.height() as usize);
            let found = detector.detect(&ImageView::new(frame.as_raw(), w, h, w)?)?;
            tags += found.len();
            if dump {
                for t in &found {
                    eprintln!("{} {} {:?} {:?}", t.id, t.hamming, t.corners, t.decision_margin);
                }
            }
        }
    }
    let frames_run = passes * frames.len();
    let ms = start.elapsed().as_secs_f64() * 1e3 / frames_run.max(1) as f64;
    println!("{which}: {ms:.2} ms a frame over {frames_run} frames, {tags} tags");
    Ok(())
}
