//! `tracker-bench`: the accuracy of our tracker against the reference stack — the AprilTag C
//! library (3.4.5, vendored by `apriltag-sys`) then OpenCV's `solvePnP` with SQPnP per body —
//! on the same rendered frames in the same run.
//!
//! Each scene (static: 18 camera views; hinge; excursion; chew) is rendered once at 1080p
//! with the default realism (sensor noise, defocus and motion blur, sRGB, 0.2 mm / 0.5° print
//! error) and cached. Every frame goes, in order, through our tracker and through the
//! reference stack, each with two marker files: the nominal one a user has before
//! calibration, and the marker as printed (the oracle a perfect calibration would give).
//! Both report `maxilla_from_mandible`, compared with the truth: position and orientation
//! error per scene and per camera view, flips (frames more than 1° off), and the time of one
//! body's PnP, ours against OpenCV's on the same correspondences. OpenCV runs in Python
//! (`python/solve_pnp.py`); without it the reference columns are skipped, and said so.

mod report;

use anyhow::{Context, Result, bail};
use clap::Parser;
use jawtrack_apriltag::{DetectorConfig, ImageView};
use jawtrack_apriltag_reference::{ReferenceDetection, ReferenceDetector, ReferenceParams};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::{CameraIntrinsics, Observation, PnpOptions, Pose, solve_pnp};
use jawtrack_synth::{Orientation, SceneKind};
use jawtrack_tracker::{Flag, Tracker, TrackerConfig};
use jawtrack_tracker_bench::chew::{self, ChewFrame, ChewScene};
use jawtrack_tracker_bench::opencv::{self, BodyCase, OpenCv};
use jawtrack_tracker_bench::{frames, reference::correspondences};
use nalgebra::{Point2, Point3};
use report::{FrameOutcome, PnpTiming, PoseError, RunInfo, SceneOutcome};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Frames per scene in `--quick` mode.
const QUICK_FRAMES: usize = 4;

/// Calls of our `solve_pnp` per body when timing it (the median counts), as the script does
/// for OpenCV's.
const PNP_REPEATS: usize = 5;

#[derive(Parser)]
#[command(
    about = "Our tracker against the reference stack (AprilTag C + OpenCV SQPnP) on rendered frames: mandible-in-maxilla error, flips, PnP time"
)]
struct Args {
    /// Scenes to run (comma-separated): static, hinge, excursion, chew.
    #[arg(long, value_delimiter = ',', default_values = ["static", "hinge", "excursion", "chew"])]
    scenes: Vec<SceneKind>,
    /// Seed of everything random in the rendered frames.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Frames per camera view (static scene).
    #[arg(long, default_value_t = 2)]
    frames_per_view: usize,
    /// Cycles per opening (hinge), per glide (excursion), in all (chew).
    #[arg(long, default_value_t = 1)]
    cycles: usize,
    /// Frame rate of the dynamic scenes (frames/s). 10 keeps the first render within minutes
    /// (hand-held motion blur costs up to ~10 s a frame); 30 is a phone's, ~3× the frames.
    #[arg(long, default_value_t = 10.0)]
    fps: f64,
    /// At most this many frames per scene (the first ones).
    #[arg(long)]
    max_frames: Option<usize>,
    /// A smoke run: the first 4 frames of each scene (unless --max-frames says otherwise).
    #[arg(long)]
    quick: bool,
    /// Where rendered frames are cached (default: target/tracker-bench of this workspace).
    #[arg(long)]
    cache: Option<PathBuf>,
    /// Python with OpenCV (default: the first of python3, python that imports cv2).
    #[arg(long)]
    python: Option<String>,
    /// Also write the report (Markdown) to this file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write every frame's errors, flags and C tag counts to this file (JSON lines).
    #[arg(long)]
    per_frame: Option<PathBuf>,
    /// Exposures (ms, comma-separated) to render the chew scene with, each a scene of its own;
    /// default: the default realism's.
    #[arg(long, value_delimiter = ',', value_name = "MS")]
    chew_exposures_ms: Vec<f64>,
    /// Rolling-shutter readouts (ms, comma-separated) to render the chew scene with, each
    /// with every exposure; ours is told the readout, and measured with it ignored too.
    #[arg(long, value_delimiter = ',', value_name = "MS", default_values = ["0"])]
    chew_readouts_ms: Vec<f64>,
    /// Hold the phone in landscape for the chew scene (rows across the face, the upper marker
    /// read before the lower) instead of upright.
    #[arg(long)]
    landscape: bool,
}

/// The two marker files: nominal, as printed.
type Markers = [Marker; 2];

/// Error of an estimate of `maxilla_from_mandible` against the truth.
fn pose_error(estimate: &Pose, truth: &Pose) -> PoseError {
    PoseError::of(estimate, truth)
}

/// Median time (µs) of our `solve_pnp` on a body's correspondences, cold (no prior), and
/// whether it dropped a tag as inconsistent with the others.
fn time_our_pnp(case: &BodyCase, camera: &CameraIntrinsics) -> (f64, bool) {
    // The points come four per tag, tag after tag: the index gives the tag.
    let observations: Vec<Observation> = case
        .object
        .iter()
        .zip(&case.image)
        .enumerate()
        .map(|(i, (o, p))| Observation { tag: (i / 4) as u32, body: Point3::from(*o), pixel: Point2::new(p[0], p[1]) })
        .collect();
    let options = PnpOptions::default();
    let mut dropped = false;
    let mut times: Vec<f64> = (0..PNP_REPEATS)
        .map(|_| {
            let start = Instant::now();
            let solved = solve_pnp(&observations, camera, None, &options);
            let us = start.elapsed().as_secs_f64() * 1e6;
            dropped = std::hint::black_box(solved).is_ok_and(|p| !p.rejected_tags.is_empty());
            us
        })
        .collect();
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], dropped)
}

/// The reference stack on one frame's C detections, for both marker files: the error of its
/// `maxilla_from_mandible` (or why it has none). Every body with a tag is also timed with our
/// `solve_pnp` on the same correspondences, and with OpenCV's when `cv` is there; without it
/// the errors are `None` and the notes empty.
fn reference_frame(
    cv: Option<&mut OpenCv>,
    markers: &Markers,
    detections: &[ReferenceDetection],
    camera: &CameraIntrinsics,
    truth: &Pose,
    timings: &mut Vec<PnpTiming>,
) -> Result<[(Option<PoseError>, Option<String>); 2]> {
    let mut cases = Vec::new();
    let mut slots = Vec::new();
    let mut notes: [Vec<String>; 2] = [Vec::new(), Vec::new()];
    for (m, marker) in markers.iter().enumerate() {
        for (b, kind) in BodyKind::ALL.into_iter().enumerate() {
            let case = correspondences(marker, kind, detections);
            if case.object.len() < 4 {
                notes[m].push(format!("{kind}: no tag"));
                continue;
            }
            slots.push((m, b));
            cases.push(case);
        }
    }
    let first = timings.len();
    for (&(m, _), case) in slots.iter().zip(&cases) {
        let (ours_us, ours_dropped_tag) = time_our_pnp(case, camera);
        timings.push(PnpTiming {
            marker: m,
            tags: case.object.len() / 4,
            ours_us,
            ours_dropped_tag,
            sqpnp_us: None,
            iterative_us: None,
        });
    }
    let Some(cv) = cv else { return Ok([(None, None), (None, None)]) };
    let solved = cv.solve(camera, &cases)?;
    let mut poses: [[Option<Pose>; 2]; 2] = [[None; 2]; 2];
    for ((&(m, b), timing), s) in slots.iter().zip(&mut timings[first..]).zip(solved) {
        match s {
            Ok(s) => {
                poses[m][b] = Some(s.camera_from_body);
                timing.sqpnp_us = Some(s.sqpnp_us);
                timing.iterative_us = Some(s.iterative_us);
            }
            Err(e) => notes[m].push(format!("{}: OpenCV: {e}", BodyKind::ALL[b])),
        }
    }
    Ok(std::array::from_fn(|m| match poses[m] {
        [Some(camera_from_maxilla), Some(camera_from_mandible)] => {
            let estimate = camera_from_maxilla.inverse().compose(&camera_from_mandible);
            (Some(pose_error(&estimate, truth)), None)
        }
        _ => (None, Some(notes[m].join("; "))),
    }))
}

/// One scene through both stacks, frames in order.
fn run_scene(
    req: &frames::Request,
    cache: &Path,
    mut cv: Option<&mut OpenCv>,
    timings: &mut Vec<PnpTiming>,
) -> Result<SceneOutcome> {
    let name = req.scene.name();
    let render_start = Instant::now();
    let mut announced = false;
    let scene = frames::scene(cache, req, &mut |done, total| {
        if !announced {
            eprintln!(
                "{name}: rendering {total} frames into {} (seconds each; cached for next time)…",
                cache.display()
            );
            announced = true;
        } else if done % (total / 10).max(1) == 0 || done == total {
            eprintln!("{name}:   {done}/{total} rendered, {:.0} s", render_start.elapsed().as_secs_f64());
        }
    })?;
    let truth = &scene.truth;
    let start = Instant::now();
    let printed = Marker::from_json(&truth.true_marker.to_string())
        .with_context(|| format!("{name}: the marker as printed in ground_truth.json"))?;
    let markers: Markers = [Marker::default(), printed];
    let config = TrackerConfig {
        detector: DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() },
        readout_s: truth.realism.readout_s,
        exposure_s: truth.realism.exposure_s,
        ..TrackerConfig::default()
    };
    let mut trackers = [Tracker::new(markers[0].clone(), config)?, Tracker::new(markers[1].clone(), config)?];
    // Under a rolling shutter, the printed marker's tracker once more, told nothing of it.
    let mut ignoring = (config.readout_s > 0.0)
        .then(|| Tracker::new(markers[1].clone(), TrackerConfig { readout_s: 0.0, ..config }))
        .transpose()?;
    let mut c = ReferenceDetector::new(&ReferenceParams::default()).map_err(|e| anyhow::anyhow!("{e}"))?;
    let camera = &truth.intrinsics;
    let mut out = SceneOutcome { scene: req.scene, frames: Vec::new() };
    for f in &truth.frames {
        let path = scene.dir.join(&f.file);
        let img = image::open(&path).with_context(|| format!("reading {}", path.display()))?.to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let view = ImageView::new(img.as_raw(), w, h, w)?;
        let mut error = [[None; 2]; 2];
        let mut our_flags: [Vec<String>; 2] = [Vec::new(), Vec::new()];
        for (m, tracker) in trackers.iter_mut().enumerate() {
            let r = tracker.track(&view, camera, f.t).with_context(|| format!("tracking {}", path.display()))?;
            error[m][0] = r.maxilla_from_mandible.map(|p| pose_error(&p, &f.maxilla_from_mandible));
            our_flags[m] = r.flags.iter().map(Flag::name).collect();
        }
        let ignored = match &mut ignoring {
            Some(t) => t
                .track(&view, camera, f.t)
                .with_context(|| format!("tracking {}", path.display()))?
                .maxilla_from_mandible
                .map(|p| pose_error(&p, &f.maxilla_from_mandible)),
            None => None,
        };
        let detections: Vec<ReferenceDetection> = c
            .detect(img.as_raw(), w, h, w)
            .map_err(|e| anyhow::anyhow!("C library on {}: {e}", path.display()))?
            .into_iter()
            .filter(|d| markers[0].find_tag(d.id).is_some())
            .collect();
        let c_tags = BodyKind::ALL
            .map(|k| detections.iter().filter(|d| markers[0].find_tag(d.id).map(|t| t.0) == Some(k)).count());
        let mut reference_note = [None, None];
        let r = reference_frame(cv.as_deref_mut(), &markers, &detections, camera, &f.maxilla_from_mandible, timings)?;
        for (m, (e, note)) in r.into_iter().enumerate() {
            error[m][1] = e;
            reference_note[m] = note;
        }
        out.frames.push(FrameOutcome {
            index: f.index,
            view: f.spec.view,
            error,
            our_flags,
            c_tags,
            reference_note,
            ignored,
            speed_mm_s: f.incisor_speed_mm_s,
        });
    }
    let summary = |m: usize, s: usize| {
        let e: Vec<&PoseError> = out.frames.iter().filter_map(|f| f.error[m][s].as_ref()).collect();
        let flips = e.iter().filter(|e| e.deg > report::FLIP_DEG).count();
        let worst = e.iter().map(|e| e.deg).fold(0.0, f64::max);
        format!("{}/{} poses, {flips} flips, worst {worst:.2}°", e.len(), out.frames.len())
    };
    eprintln!(
        "{name}: {} frames{} measured in {:.0} s — nominal marker: ours {}; reference {}",
        out.frames.len(),
        if scene.rendered { "" } else { " (cached)" },
        start.elapsed().as_secs_f64(),
        summary(0, 0),
        if cv.is_some() { summary(0, 1) } else { "skipped".into() },
    );
    Ok(out)
}

fn main() -> Result<()> {
    let args = Args::parse();
    if args.frames_per_view == 0 || args.cycles == 0 {
        bail!("--frames-per-view and --cycles must be at least 1");
    }
    if !(args.fps.is_finite() && args.fps > 0.0) {
        bail!("--fps must be a positive number of frames/s, got {}", args.fps);
    }
    if args.max_frames == Some(0) {
        bail!("--max-frames must be at least 1");
    }
    let max_frames = if args.quick { Some(args.max_frames.unwrap_or(QUICK_FRAMES)) } else { args.max_frames };
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).ancestors().nth(2).context("the workspace folder")?;
    let cache = args.cache.clone().unwrap_or_else(|| workspace.join("target/tracker-bench"));
    let candidates = match &args.python {
        Some(p) => vec![p.clone()],
        None => vec!["python3".to_string(), "python".to_string()],
    };
    let mut cv = match OpenCv::start(&candidates)? {
        Ok(cv) => Some(cv),
        Err(why) => {
            eprintln!("SKIPPED: the reference stack's PnP — {why}. Reporting ours alone.");
            None
        }
    };
    let reference = match &cv {
        Some(cv) => Ok(format!("OpenCV {} `solvePnP` SQPnP (through {})", cv.version, cv.python)),
        None => Err(format!(
            "no Python with OpenCV was found (install it with `{}`, or give --python)",
            opencv::INSTALL_HINT
        )),
    };
    let realism = jawtrack_synth::Realism::default();
    let frames = format!(
        "seed {}, 1080p, default realism (noise, defocus and motion blur, sRGB, print error {} mm / {}°), {} frames per static view, {} cycle(s) at {} frames/s{}.",
        args.seed,
        realism.print_error_mm,
        realism.print_error_deg,
        args.frames_per_view,
        args.cycles,
        args.fps,
        max_frames.map_or(String::new(), |n| format!(", at most {n} frames per scene")),
    );
    for (flag, values) in
        [("--chew-exposures-ms", &args.chew_exposures_ms), ("--chew-readouts-ms", &args.chew_readouts_ms)]
    {
        if let Some(bad) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0 && **v < 1000.0)) {
            bail!("{flag} takes milliseconds from 0 to under 1000, got {bad}");
        }
    }
    if args.chew_exposures_ms.contains(&0.0) {
        bail!("--chew-exposures-ms must be positive (an exposure of 0 ms is not a frame)");
    }
    let orientation = if args.landscape { Orientation::Landscape } else { Orientation::Upright };
    let mut outcomes = Vec::new();
    let mut timings = Vec::new();
    for &scene in &args.scenes {
        let base = frames::Request {
            max_frames,
            ..frames::Request::new(scene, args.seed, args.frames_per_view, args.cycles, args.fps)
        };
        if scene != SceneKind::Chew {
            outcomes.push((run_scene(&base, &cache, cv.as_mut(), &mut timings)?, None));
            continue;
        }
        let exposures: Vec<Option<f64>> = if args.chew_exposures_ms.is_empty() {
            vec![None]
        } else {
            args.chew_exposures_ms.iter().map(|e| Some(e / 1000.0)).collect()
        };
        for exposure_s in exposures {
            for &readout_ms in &args.chew_readouts_ms {
                let req = frames::Request { exposure_s, readout_s: readout_ms / 1000.0, orientation, ..base };
                let shutter = chew::Shutter {
                    exposure_s: exposure_s.unwrap_or(realism.exposure_s),
                    readout_s: req.readout_s,
                    orientation: if args.landscape { "landscape" } else { "upright" },
                };
                outcomes.push((run_scene(&req, &cache, cv.as_mut(), &mut timings)?, Some(shutter)));
            }
        }
    }
    let with_reference = reference.is_ok();
    let scenes: Vec<SceneOutcome> = outcomes.iter().map(|(o, _)| o.clone()).collect();
    let mut md = report::markdown(&RunInfo { frames, reference }, &scenes, &timings);
    // The chew table reads the marker as printed (the targets are for a calibrated or
    // exact marker): index 1 of each frame's errors.
    let chews: Vec<ChewScene> = outcomes
        .iter()
        .filter_map(|(o, shutter)| {
            Some(ChewScene {
                shutter: (*shutter)?,
                frames: o
                    .frames
                    .iter()
                    .map(|f| ChewFrame {
                        speed_mm_s: f.speed_mm_s,
                        ours: f.error[1][0],
                        ignored: f.ignored,
                        reference: f.error[1][1],
                    })
                    .collect(),
            })
        })
        .collect();
    md.push_str(&chew::markdown(&chews, with_reference));
    let outcomes = scenes;
    print!("{md}");
    if let Some(path) = &args.out {
        std::fs::write(path, &md).with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &args.per_frame {
        std::fs::write(path, report::json_lines(&outcomes)).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
