//! `jawtrack-bench pipeline`: time per frame of the whole tracking pipeline and of its stages
//! (tag detection, pose), at 1080p and 4K, searching every frame whole and tracking in the
//! steady state (searching the region where the markers are expected, or looking for each tag
//! where the poses predict it), with 1 and 2 detector threads; the detector's own stages
//! (threshold, components, clusters, quads, tags); every frame of a long take, for the slowest
//! (a frame that pays for more than detection stalls the stream); and the PnP time per body,
//! ours beside OpenCV's solvePnP (SQPnP, ITERATIVE) on the same correspondences when Python
//! with OpenCV is installed.
//!
//! Frames are a hinge opening rendered with the default realism (noise, blur, sRGB), 30
//! frames/s, so consecutive frames move as a real recording does. Each pass over the frames
//! starts a fresh tracker; every frame's time is the median over `--repeat` passes, and the
//! table gives the median over frames. Machines here are noisy: read ratios and medians.

use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_apriltag::tone::{REFIT_EVERY_FRAMES, SETTLING_FRAMES};
use jawtrack_apriltag::{DetectorConfig, ImageView, StageTimes};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::{CameraIntrinsics, Observation, Pose, solve_pnp};
use jawtrack_synth::{Realism, Resolution, SceneKind, SceneOptions, SynthConfig, Synthesizer};
use jawtrack_tracker::{SearchConfig, Tracker, TrackerConfig};
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Instant;

/// Arguments of `jawtrack-bench pipeline`.
#[derive(Args)]
pub struct PipelineArgs {
    /// Resolutions to run (comma-separated): 1080p, 4k.
    #[arg(long, value_delimiter = ',', default_value = "1080p,4k")]
    resolutions: Vec<Resolution>,
    /// Detector threads to run with (comma-separated), each a row of its own.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    threads: Vec<usize>,
    /// The lens's focal length times this (a 2 is a 2× crop of the sensor: tags twice as
    /// large, the markers nearer the frame's edges).
    #[arg(long, default_value_t = 1.0)]
    zoom: f64,
    /// Frames rendered per resolution (consecutive, 30 frames/s).
    #[arg(long, default_value_t = 20)]
    frames: usize,
    /// Passes over the frames; each frame's median counts.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Calls per body when timing our PnP (OpenCV's median is over 5 calls, in Python).
    #[arg(long, default_value_t = 200)]
    pnp_repeat: usize,
    /// The Python that runs OpenCV (skipped with a note when it cannot import cv2).
    #[arg(long, default_value = "python3")]
    python: String,
    /// Frames of the long take (the rendered ones played forth and back), which times every
    /// frame of a tracking run long enough to hold the tone curve's periodic refits.
    #[arg(long, default_value_t = 2 * REFIT_EVERY_FRAMES + 40)]
    long_take: usize,
    /// Also write the table (Markdown) here.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Median of a list (NaN when empty).
fn median(v: Vec<f64>) -> f64 {
    jawtrack_pose::median(v).unwrap_or(f64::NAN)
}

/// One body's PnP problem as the tracker met it.
struct PnpCase {
    observations: Vec<Observation>,
    prior: Option<Pose>,
}

/// Runs `jawtrack-bench pipeline`.
pub fn run(a: &PipelineArgs) -> Result<()> {
    if a.frames < 2 || a.repeat == 0 || a.pnp_repeat == 0 {
        bail!("--frames must be at least 2, --repeat and --pnp-repeat at least 1");
    }
    if a.long_take <= SETTLING_FRAMES {
        bail!("--long-take must be more than the {SETTLING_FRAMES} frames the tone curve settles over");
    }
    if !(a.zoom >= 1.0 && a.zoom <= 4.0) {
        bail!("--zoom must be between 1 and 4, got {}", a.zoom);
    }
    if a.threads.is_empty() || a.threads.iter().any(|&n| n == 0 || n > 64) {
        bail!("--threads takes thread counts from 1 to 64, e.g. --threads 1,2");
    }
    let mut table = String::new();
    let mut line = |s: String| {
        crate::say(format_args!("{s}"));
        table.push_str(&s);
        table.push('\n');
    };
    line(format!(
        "jawtrack-bench pipeline: hinge opening, default realism, {} frames per resolution, median of {} passes",
        a.frames, a.repeat
    ));
    line(String::new());
    line("| resolution | search | threads | frames | detection ms | pose ms | whole ms | frames/s | target |".into());
    line("|---|---|---|---|---|---|---|---|---|".into());
    let mut stage_rows = Vec::new();
    let mut cases: Vec<PnpCase> = Vec::new();
    let mut camera_for_cases = None;
    let mut rendered = Vec::new();
    for &resolution in &a.resolutions {
        let mut lens = resolution.default_intrinsics();
        (lens.fx, lens.fy) = (lens.fx * a.zoom, lens.fy * a.zoom);
        let synth = Synthesizer::new(SynthConfig {
            resolution,
            intrinsics: Some(lens),
            realism: Realism::default(),
            options: SceneOptions { cycles: 1, ..SceneOptions::default() },
            max_frames: Some(a.frames),
            ..SynthConfig::new(SceneKind::Hinge)
        })?;
        let camera = synth.header().intrinsics;
        let bar = jawtrack_progress::bar(
            &format!("rendering {}", resolution_name(resolution)),
            Some(synth.len() as u64),
            "frames",
        );
        let mut frames = Vec::with_capacity(synth.len());
        for i in 0..synth.len() {
            frames.push(synth.render(i)?);
            bar.inc(1);
        }
        bar.finish_and_clear();
        for search in [Searched::Whole, Searched::Region, Searched::Predicted] {
            for &threads in &a.threads {
                let run = Run { resolution, search, threads };
                let timed = time_frames(&frames, &camera, run, a.repeat, &mut cases)?;
                if !cases.is_empty() {
                    camera_for_cases.get_or_insert(camera);
                }
                let target = run.target(timed.whole_ms);
                let frames = match search {
                    Searched::Predicted => format!("{} ({} predicted)", timed.frames, timed.predicted),
                    _ => timed.frames.to_string(),
                };
                line(format!(
                    "| {} | {} | {threads} | {frames} | {:.2} | {:.3} | {:.2} | {:.0} | {target} |",
                    resolution_name(resolution),
                    run.search(),
                    timed.detection_ms,
                    timed.pose_ms,
                    timed.whole_ms,
                    1e3 / timed.whole_ms,
                ));
                stage_rows.push((run, timed.stages));
            }
        }
        rendered.push((resolution, frames, camera));
    }
    line(String::new());
    line(
        "Detection stage by stage (ms, the median over frames of each stage's median over passes; \
          `tags` is the edge refit, decoding and border fit of every quad):"
            .into(),
    );
    line(String::new());
    line("| resolution | search | threads | decimate | threshold | components | clusters | quads | tags | finish | clusters | quads | tags |".into());
    line("|---|---|---|---|---|---|---|---|---|---|---|---|---|".into());
    for (run, st) in &stage_rows {
        line(format!(
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.3} | {:.0} | {:.0} | {:.0} |",
            resolution_name(run.resolution),
            run.search(),
            run.threads,
            st[0],
            st[1],
            st[2],
            st[3],
            st[4],
            st[5],
            st[6],
            st[7],
            st[8],
            st[9]
        ));
    }
    line(String::new());
    line(format!(
        "A long take: the frames played forth and back for {} frames (the tone curve's refits \
         fall every {REFIT_EVERY_FRAMES} detections once it has settled), tracked once with tags where \
         predicted; each frame's detection and pose (ms) after the first {SETTLING_FRAMES}, which fit the \
         curve while it settles:",
        a.long_take
    ));
    line(String::new());
    line("| resolution | threads | frames | median ms | p99 ms | slowest ms | frames over 16.7 ms |".into());
    line("|---|---|---|---|---|---|---|".into());
    for (resolution, frames, camera) in &rendered {
        for &threads in &a.threads {
            let t = long_take(frames, camera, threads, a.long_take)?;
            line(format!(
                "| {} | {threads} | {} | {:.2} | {:.2} | {:.2} | {} |",
                resolution_name(*resolution),
                t.frames,
                t.median_ms,
                t.p99_ms,
                t.slowest_ms,
                t.over_budget
            ));
        }
    }
    if let Some(camera) = camera_for_cases {
        line(String::new());
        pnp_table(&cases, &camera, a, &mut line)?;
    }
    if let Some(out) = &a.out {
        std::fs::write(out, &table).with_context(|| format!("writing {}", out.display()))?;
    }
    Ok(())
}

/// How a row's tracker looks for the tags.
#[derive(Clone, Copy, PartialEq)]
enum Searched {
    /// The whole frame, every frame.
    Whole,
    /// Once tracked, the region where the markers are expected.
    Region,
    /// Once tracked, each tag where the poses predict it, the region when one is missing.
    Predicted,
}

/// One row of the table.
#[derive(Clone, Copy)]
struct Run {
    resolution: Resolution,
    search: Searched,
    threads: usize,
}

impl Run {
    fn search(&self) -> &'static str {
        match self.search {
            Searched::Whole => "whole frame",
            Searched::Region => "tracked region (steady state)",
            Searched::Predicted => "tracked, tags where predicted (steady state)",
        }
    }

    fn tracked(&self) -> bool {
        self.search != Searched::Whole
    }

    /// The targets for this row, met or not.
    fn target(&self, whole_ms: f64) -> String {
        let limit = match (self.resolution, self.tracked(), self.threads) {
            (Resolution::P1080, true, 2) => Some(1.5),
            (Resolution::P4k, true, 2) => Some(3.0),
            (Resolution::P4k, false, 2) => Some(8.0),
            (Resolution::P1080, true, _) => Some(8.0),
            (Resolution::P4k, true, _) => Some(20.0),
            _ => None,
        };
        match limit {
            Some(l) => format!("≤ {l} ms: {}", if whole_ms <= l { "met" } else { "not met" }),
            None => "—".into(),
        }
    }
}

/// A row's medians (ms), and its detector stages (ms, then counts).
struct Timed {
    frames: usize,
    /// Of `frames`, those whose tags were taken where predicted (in every pass).
    predicted: usize,
    detection_ms: f64,
    pose_ms: f64,
    whole_ms: f64,
    stages: [f64; 10],
}

/// Tracks `frames` `repeat` times after a warm-up pass (which, for the 1080p tracked run with
/// one thread, also collects the PnP problems into `cases`).
fn time_frames(
    frames: &[jawtrack_synth::Frame],
    camera: &CameraIntrinsics,
    run: Run,
    repeat: usize,
    cases: &mut Vec<PnpCase>,
) -> Result<Timed> {
    let config = TrackerConfig {
        detector: DetectorConfig { nthreads: run.threads, ..DetectorConfig::default() },
        search: SearchConfig {
            region_search: run.tracked(),
            predicted: run.search == Searched::Predicted,
            // The whole frame at the settings' decimation: the detector's own speed, whatever
            // the tracked tags' size.
            pyramid: run.tracked(),
            ..SearchConfig::default()
        },
        ..TrackerConfig::default()
    };
    let collect = run.tracked() && run.resolution == Resolution::P1080 && cases.is_empty();
    // times[frame] = (detection, pose, stages) per pass
    let mut times: Vec<Vec<(f64, f64, StageTimes)>> = vec![Vec::new(); frames.len()];
    let mut steady = vec![true; frames.len()];
    let mut predicted = vec![true; frames.len()];
    for pass in 0..=repeat {
        let mut tracker = Tracker::new(Marker::default(), config)?;
        for (i, f) in frames.iter().enumerate() {
            let (w, h) = (f.width as usize, f.height as usize);
            let view = ImageView::new(&f.luma, w, h, w)?;
            let priors = BodyKind::ALL.map(|k| tracker.predicted(k, f.truth.t));
            let r = tracker.track(&view, camera, f.truth.t)?;
            // Pass 0 warms the caches and collects the PnP problems.
            if pass == 0 {
                if collect {
                    for (k, prior) in BodyKind::ALL.into_iter().zip(priors) {
                        let observations = tracker.observations(k, &r.detections);
                        if observations.len() >= 4 {
                            cases.push(PnpCase { observations, prior });
                        }
                    }
                }
                continue;
            }
            steady[i] &= !run.tracked() || r.searched.is_some();
            predicted[i] &= r.timings.predicted;
            times[i].push((r.timings.detection_s, r.timings.pose_s, r.timings.stages));
        }
    }
    let used: Vec<&Vec<(f64, f64, StageTimes)>> =
        times.iter().zip(&steady).filter(|(_, s)| **s).map(|(t, _)| t).collect();
    let per_frame = |pick: &dyn Fn(&(f64, f64, StageTimes)) -> f64| -> f64 {
        median(used.iter().map(|t| median(t.iter().map(pick).collect())).collect())
    };
    let ms = |pick: &dyn Fn(&StageTimes) -> f64| per_frame(&|t| pick(&t.2) * 1e3);
    let count = |pick: &dyn Fn(&StageTimes) -> usize| per_frame(&|t| pick(&t.2) as f64);
    Ok(Timed {
        frames: used.len(),
        predicted: steady.iter().zip(&predicted).filter(|(s, p)| **s && **p).count(),
        detection_ms: per_frame(&|t| t.0) * 1e3,
        pose_ms: per_frame(&|t| t.1) * 1e3,
        whole_ms: per_frame(&|t| t.0 + t.1) * 1e3,
        stages: [
            ms(&|s| s.decimate_s),
            ms(&|s| s.threshold_s),
            ms(&|s| s.components_s),
            ms(&|s| s.clusters_s),
            ms(&|s| s.quads_s),
            ms(&|s| s.tags_s),
            ms(&|s| s.finish_s),
            count(&|s| s.clusters),
            count(&|s| s.quads),
            count(&|s| s.tags),
        ],
    })
}

/// Every frame's time over a long take ([`long_take`]).
struct LongTake {
    frames: usize,
    median_ms: f64,
    p99_ms: f64,
    slowest_ms: f64,
    /// Frames over a 60 frames/s budget.
    over_budget: usize,
}

/// Tracks `take` frames — `frames` forth, back, forth… so the motion runs on — with tags
/// where predicted and `threads` detector threads, once, and times each (detection and
/// pose) after the tone curve's settling frames.
fn long_take(
    frames: &[jawtrack_synth::Frame],
    camera: &CameraIntrinsics,
    threads: usize,
    take: usize,
) -> Result<LongTake> {
    let config = TrackerConfig {
        detector: DetectorConfig { nthreads: threads, ..DetectorConfig::default() },
        search: SearchConfig { region_search: true, predicted: true, ..SearchConfig::default() },
        ..TrackerConfig::default()
    };
    let mut tracker = Tracker::new(Marker::default(), config)?;
    let order = (0..frames.len()).chain((1..frames.len() - 1).rev()).cycle().take(take);
    let period = frames.last().map_or(0.0, |f| f.truth.t) - frames[0].truth.t;
    let step = period / (frames.len() - 1) as f64;
    let mut ms = Vec::with_capacity(take);
    for (k, i) in order.enumerate() {
        let f = &frames[i];
        let (w, h) = (f.width as usize, f.height as usize);
        let view = ImageView::new(&f.luma, w, h, w)?;
        // Time runs on as the frames go back and forth.
        let r = tracker.track(&view, camera, frames[0].truth.t + k as f64 * step)?;
        if k >= SETTLING_FRAMES {
            ms.push((r.timings.detection_s + r.timings.pose_s) * 1e3);
        }
    }
    ms.sort_by(f64::total_cmp);
    let at = |q: f64| ms[((ms.len() - 1) as f64 * q).round() as usize];
    Ok(LongTake {
        frames: ms.len(),
        median_ms: at(0.5),
        p99_ms: at(0.99),
        slowest_ms: at(1.0),
        over_budget: ms.iter().filter(|&&t| t > 1e3 / 60.0).count(),
    })
}

fn resolution_name(r: Resolution) -> &'static str {
    match r {
        Resolution::P1080 => "1080p",
        Resolution::P4k => "4K",
    }
}

/// PnP per body: ours from the tracker's starting pose and cold, OpenCV's on the same points.
fn pnp_table(
    cases: &[PnpCase],
    camera: &CameraIntrinsics,
    a: &PipelineArgs,
    line: &mut dyn FnMut(String),
) -> Result<()> {
    let options = jawtrack_pose::PnpOptions::default();
    let time = |prior: bool| -> Result<f64> {
        let mut per_case = Vec::new();
        for c in cases {
            let p = if prior { c.prior.as_ref() } else { None };
            let mut t = Vec::with_capacity(a.pnp_repeat);
            for _ in 0..a.pnp_repeat {
                let start = Instant::now();
                let r = solve_pnp(&c.observations, camera, p, &options);
                t.push(start.elapsed().as_secs_f64());
                std::hint::black_box(r)?;
            }
            per_case.push(median(t));
        }
        Ok(median(per_case) * 1e6)
    };
    let tracking = time(true)?;
    let cold = time(false)?;
    let points = median(cases.iter().map(|c| c.observations.len() as f64).collect());
    line(format!(
        "PnP per body, {} bodies from the 1080p tracked run ({points:.0} points median); ours the median of {} calls, OpenCV's of 5 (timed inside Python):",
        cases.len(),
        a.pnp_repeat
    ));
    line(String::new());
    line("| solver | µs per body | × ours (tracking) |".into());
    line("|---|---|---|".into());
    line(format!("| ours, from the predicted pose (tracking) | {tracking:.1} | 1.0 |"));
    line(format!("| ours, cold (IPPE starts on every tag) | {cold:.1} | {:.2} |", cold / tracking));
    match opencv_times(cases, camera, a) {
        Ok((sqpnp, iterative)) => {
            line(format!("| OpenCV SQPnP | {sqpnp:.1} | {:.2} |", sqpnp / tracking));
            line(format!("| OpenCV ITERATIVE | {iterative:.1} | {:.2} |", iterative / tracking));
        }
        Err(e) => line(format!("| OpenCV | skipped: {e:#} | — |")),
    }
    line(String::new());
    line(format!("target: PnP ≤ 50 µs per body: {}", if tracking <= 50.0 { "met" } else { "not met" }));
    Ok(())
}

/// Median µs per body of OpenCV's SQPnP and ITERATIVE, run by Python on the same cases
/// through the tracker bench's script (one protocol for every OpenCV comparison; each time is
/// the median of its calls inside Python).
fn opencv_times(cases: &[PnpCase], camera: &CameraIntrinsics, a: &PipelineArgs) -> Result<(f64, f64)> {
    let has_cv2 = Command::new(&a.python).args(["-c", "import cv2"]).output().is_ok_and(|o| o.status.success());
    if !has_cv2 {
        bail!("{} cannot import cv2 (pip install opencv-python-headless)", a.python);
    }
    let mut child = Command::new(&a.python)
        .args(["-c", include_str!("../python/solve_pnp.py")])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .context("starting Python")?;
    let mut input = child.stdin.take().context("Python's stdin")?;
    let bodies: Vec<serde_json::Value> = cases
        .iter()
        .map(|c| {
            let object: Vec<[f64; 3]> = c.observations.iter().map(|o| [o.body.x, o.body.y, o.body.z]).collect();
            let image: Vec<[f64; 2]> = c.observations.iter().map(|o| [o.pixel.x, o.pixel.y]).collect();
            serde_json::json!({"object": object, "image": image})
        })
        .collect();
    let k = camera;
    let request = serde_json::json!({"camera": [k.fx, k.fy, k.cx, k.cy, k.k1, k.k2], "bodies": bodies});
    writeln!(input, "{request}").context("feeding Python")?;
    drop(input);
    let mut lines = BufReader::new(child.stdout.take().context("Python's stdout")?).lines();
    let _hello = lines.next().context("no answer from the OpenCV helper")??;
    let reply: serde_json::Value =
        serde_json::from_str(&lines.next().context("no poses from the OpenCV helper")??).context("its answer")?;
    let status = child.wait()?;
    let poses = reply["poses"].as_array().context("its answer has no poses")?;
    let times = |key: &str| -> Vec<f64> { poses.iter().filter_map(|p| p[key].as_f64()).collect() };
    let (sqpnp, iterative) = (times("sqpnp_us"), times("iterative_us"));
    if !status.success() || sqpnp.len() != cases.len() {
        bail!("the OpenCV helper failed ({status}, {} of {} bodies solved)", sqpnp.len(), cases.len());
    }
    Ok((median(sqpnp), median(iterative)))
}
