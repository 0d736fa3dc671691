//! `detector-bench`: our tag36h11 detector side by side with the reference C library (3.4.5,
//! vendored by `apriltag-sys`) on the same frames in the same run.
//!
//! For each image set, decimation and thread count it runs four detectors — the C library
//! at its defaults; ours doing C's work (C's parameters and C's edge refit, so C's tags and
//! corners, within 10⁻³ px in the parity tests: see the "median Δ to C" column); ours with
//! C's parameters but our edge refit (in linear light, and each tag's border by its model);
//! and ours at its own defaults — each in a child process of its own so that peak memory is
//! measured cleanly and one cannot warm the other's caches. Each reports frames/s (from the
//! median time of `--repeat` runs per frame), recall and false positives against the ground
//! truth of rendered frames, the median corner error against that truth, agreement with C
//! (tags C found that it also found, and the median corner distance to C's), and the peak
//! memory added by detection (resident set high-water mark above the level after the images
//! were loaded).
//!
//! This crate is the only one besides the tests that links the C library; the product never
//! does.

use anyhow::{Context, Result, bail};
use clap::Parser;
use jawtrack_apriltag::{Detector, DetectorConfig, ImageView, QuadThreshold};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use jawtrack_synth::{GroundTruth, TagTruth};
use serde::{Deserialize, Serialize};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[derive(Parser)]
#[command(about = "Our tag36h11 detector against the reference C library: speed, recall, accuracy, memory")]
struct Args {
    /// Decimations to run (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1.0f32, 2.0, 4.0])]
    decimate: Vec<f32>,
    /// Thread counts to run (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 2])]
    threads: Vec<usize>,
    /// Runs per frame; the median time counts.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Image sets to run (by name; default all): 1080p, 1080p-sharp, 4k, 4k-sharp, photos.
    #[arg(long, value_delimiter = ',')]
    sets: Vec<String>,
    /// The rendered fixtures (default: `fixtures/` of this repository).
    #[arg(long)]
    fixtures: Option<PathBuf>,
    /// Real photos with `reference_detections.jsonl` (default: `../shared/data/photos` when present).
    #[arg(long)]
    photos: Option<PathBuf>,
    /// Our `min_white_black_diff` for the "ours" rows (default: the detector's default).
    #[arg(long)]
    min_white_black_diff: Option<u8>,
    /// Also write the table (Markdown) to this file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Internal: run one job (JSON) and print its result.
    #[arg(long, hide = true)]
    child: Option<String>,
}

/// Which detector a job runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
enum Which {
    /// The C library at its defaults (decimation and threads as the job says).
    C,
    /// Ours doing C's work: C's parameters and C's edge refit (`linear_edges` off), which
    /// gives C's tags with C's corners; no tone curve, no border model.
    OursCWork,
    /// Ours with every parameter as C's defaults, but refining edges our way on
    /// gamma-encoded frames: in linear light, and each decoded tag's border by its model.
    OursCParams,
    /// Ours at its defaults.
    Ours,
}

impl Which {
    fn label(self) -> &'static str {
        match self {
            Which::C => "C 3.4.5",
            Which::OursCWork => "ours, C's work",
            Which::OursCParams => "ours, C's parameters",
            Which::Ours => "ours",
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Job {
    which: Which,
    set: String,
    fixtures: PathBuf,
    photos: Option<PathBuf>,
    decimate: f32,
    threads: usize,
    repeat: usize,
    min_white_black_diff: Option<u8>,
}

/// Ids and corners of one frame's detections.
type Found = Vec<(u32, [[f64; 2]; 4])>;

/// Either detector, behind one signature.
type DetectFn = dyn FnMut(&image::GrayImage) -> Result<Found>;

/// What one job measured.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Outcome {
    frames: usize,
    /// Sum over frames of the median detection time (s).
    seconds: f64,
    /// Tags the truth calls detectable, found, and detections that are not on the marker.
    want: usize,
    found: usize,
    false_positives: usize,
    /// Corner errors against the truth (px).
    errors: Vec<f64>,
    /// Per frame: (id, corners) of every detection.
    detections: Vec<Found>,
    /// Resident memory added by detection (MB), if the kernel lets us reset the high-water mark.
    peak_mb: Option<f64>,
}

/// One frame of a set, with its truth when rendered.
struct Frame {
    path: PathBuf,
    truth: Option<Vec<TagTruth>>,
    /// Encoded with sRGB (refine edges in linear light).
    gamma: bool,
}

const SETS: [&str; 5] = ["1080p", "1080p-sharp", "4k", "4k-sharp", "photos"];

fn set_frames(name: &str, fixtures: &Path, photos: Option<&Path>) -> Result<Vec<Frame>> {
    if name == "photos" {
        let Some(dir) = photos else { return Ok(Vec::new()) };
        let list = std::fs::read_to_string(dir.join("reference_detections.jsonl"))
            .with_context(|| format!("reading {}", dir.join("reference_detections.jsonl").display()))?;
        let mut paths: Vec<String> = Vec::new();
        for line in list.lines().filter(|l| !l.trim().is_empty()) {
            let v: serde_json::Value = serde_json::from_str(line).context("reference_detections.jsonl")?;
            let p = v["path"].as_str().context("a line of reference_detections.jsonl has no path")?.to_owned();
            if !paths.contains(&p) {
                paths.push(p);
            }
        }
        return Ok(paths.into_iter().map(|p| Frame { path: dir.join(p), truth: None, gamma: true }).collect());
    }
    let sharp = name.ends_with("-sharp");
    let res = if name.starts_with("4k") { "4k" } else { "1080p" };
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(fixtures)
        .with_context(|| format!("reading {}", fixtures.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let n = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            p.join("ground_truth.json").is_file() && n.ends_with(&format!("-{res}")) && n.starts_with("clean-") == sharp
        })
        .collect();
    dirs.sort();
    let mut frames = Vec::new();
    for d in dirs {
        let gt: GroundTruth = serde_json::from_str(&std::fs::read_to_string(d.join("ground_truth.json"))?)
            .with_context(|| format!("{}", d.join("ground_truth.json").display()))?;
        for f in gt.frames {
            frames.push(Frame { path: d.join(&f.file), truth: Some(f.tags), gamma: gt.realism.gamma });
        }
    }
    Ok(frames)
}

/// A line of /proc/self/status, in kB.
fn status_kb(key: &str) -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn median_of(v: &[f64]) -> f64 {
    jawtrack_pose::median(v.iter().copied()).unwrap_or(f64::NAN)
}

fn run_job(job: &Job) -> Result<Outcome> {
    let frames = set_frames(&job.set, &job.fixtures, job.photos.as_deref())?;
    let images: Vec<image::GrayImage> = frames
        .iter()
        .map(|f| image::open(&f.path).with_context(|| format!("reading {}", f.path.display())).map(|i| i.to_luma8()))
        .collect::<Result<_>>()?;
    // Reset the high-water mark so it measures detection, not image loading.
    let reset = std::fs::write("/proc/self/clear_refs", "5").is_ok();
    let base_kb = status_kb("VmRSS:");
    let gamma = frames.iter().all(|f| f.gamma);
    let ours_config = |which: Which| {
        let base = DetectorConfig {
            quad_decimate: job.decimate,
            nthreads: job.threads,
            linear_edges: gamma,
            ..DetectorConfig::default()
        };
        if which == Which::OursCWork {
            DetectorConfig { quad: QuadThreshold::reference(), linear_edges: false, ..base }
        } else if which == Which::OursCParams {
            DetectorConfig { quad: QuadThreshold::reference(), ..base }
        } else {
            let mut c = base;
            if let Some(v) = job.min_white_black_diff {
                c.quad.min_white_black_diff = v;
            }
            c
        }
    };
    let mut detect: Box<DetectFn> = match job.which {
        Which::C => {
            let mut c = ReferenceDetector::new(&ReferenceParams {
                quad_decimate: job.decimate,
                nthreads: job.threads as i32,
                ..ReferenceParams::default()
            })
            .map_err(|e| anyhow::anyhow!("{e}"))?;
            Box::new(move |img| {
                let (w, h) = (img.width() as usize, img.height() as usize);
                let d = c.detect(img.as_raw(), w, h, w).map_err(|e| anyhow::anyhow!("{e}"))?;
                Ok(d.iter().map(|d| (d.id, d.corners)).collect())
            })
        }
        Which::OursCWork | Which::OursCParams | Which::Ours => {
            let det = Detector::new(ours_config(job.which))?;
            Box::new(move |img| {
                let (w, h) = (img.width() as usize, img.height() as usize);
                let d = det.detect(&ImageView::new(img.as_raw(), w, h, w)?)?;
                Ok(d.iter().map(|d| (d.id, d.corners)).collect())
            })
        }
    };
    let mut out = Outcome {
        frames: frames.len(),
        seconds: 0.0,
        want: 0,
        found: 0,
        false_positives: 0,
        errors: Vec::new(),
        detections: Vec::new(),
        peak_mb: None,
    };
    // Untimed first detections: ours settles its tone curve in its first fits (one a frame),
    // each costing several detections; the refits after (one in 120 frames) are timed.
    for img in images.iter().cycle().take(jawtrack_apriltag::tone::SETTLING_FRAMES) {
        detect(img)?;
    }
    for (f, img) in frames.iter().zip(&images) {
        let mut times = Vec::with_capacity(job.repeat);
        let mut dets = Vec::new();
        for _ in 0..job.repeat.max(1) {
            let t = Instant::now();
            dets = detect(img)?;
            times.push(t.elapsed().as_secs_f64());
        }
        out.seconds += median_of(&times);
        if let Some(truth) = &f.truth {
            out.false_positives += dets.iter().filter(|d| !truth.iter().any(|t| t.id == d.0)).count();
            for t in truth.iter().filter(|t| t.should_be_detected()) {
                out.want += 1;
                if let Some(d) = dets.iter().find(|d| d.0 == t.id) {
                    out.found += 1;
                    out.errors.extend(d.1.iter().zip(&t.corners).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])));
                }
            }
        }
        out.detections.push(dets);
    }
    if reset && let (Some(base), Some(hwm)) = (base_kb, status_kb("VmHWM:")) {
        out.peak_mb = Some((hwm - base).max(0.0) / 1024.0);
    }
    Ok(out)
}

/// Runs a job in a child process (this binary with `--child`).
fn spawn(job: &Job) -> Result<Outcome> {
    let exe = std::env::current_exe().context("finding this program")?;
    let out = Command::new(exe).arg("--child").arg(serde_json::to_string(job)?).output().context("running a job")?;
    if !out.status.success() {
        bail!("{} on {} failed: {}", job.which.label(), job.set, String::from_utf8_lossy(&out.stderr).trim());
    }
    serde_json::from_slice(&out.stdout).context("reading a job's result")
}

/// Tags C found that `ours` found too (same frame, same id), and the median corner distance.
fn agreement(ours: &Outcome, c: &Outcome) -> (usize, usize, f64) {
    let (mut both, mut c_total, mut dist) = (0, 0, Vec::new());
    for (o, r) in ours.detections.iter().zip(&c.detections) {
        for (id, rc) in r {
            c_total += 1;
            if let Some((_, oc)) = o.iter().find(|d| d.0 == *id) {
                both += 1;
                dist.extend(oc.iter().zip(rc).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])));
            }
        }
    }
    (both, c_total, median_of(&dist))
}

fn main() -> Result<()> {
    let args = Args::parse();
    if let Some(job) = &args.child {
        let job: Job = serde_json::from_str(job).context("bad --child job")?;
        let out = run_job(&job)?;
        println!("{}", serde_json::to_string(&out)?);
        return Ok(());
    }
    if args.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let fixtures = args.fixtures.clone().unwrap_or_else(|| root.join("fixtures"));
    let photos = args.photos.clone().or_else(|| {
        let p = root.join("../shared/data/photos");
        p.join("reference_detections.jsonl").is_file().then_some(p)
    });
    if photos.is_none() {
        eprintln!("SKIPPED: real photos (../shared/data/photos is not present; give --photos)");
    }
    let sets: Vec<String> =
        if args.sets.is_empty() { SETS.iter().map(|s| s.to_string()).collect() } else { args.sets.clone() };
    for s in &sets {
        if !SETS.contains(&s.as_str()) {
            bail!("unknown set {s:?}: choose from {}", SETS.join(", "));
        }
    }
    let mut table = String::new();
    let head = "| set | frames | decimate | threads | detector | frames/s | × C | recall | false + | median corner error (px) | C's tags found, median Δ to C (px) | peak memory (MB) |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    table.push_str(head);
    print!("{head}");
    let total = sets.len() * args.decimate.len() * args.threads.len() * 4;
    let mut done = 0;
    for set in &sets {
        if set == "photos" && photos.is_none() {
            continue;
        }
        for &decimate in &args.decimate {
            for &threads in &args.threads {
                let mut c_out: Option<Outcome> = None;
                for which in [Which::C, Which::OursCWork, Which::OursCParams, Which::Ours] {
                    done += 1;
                    eprintln!("[{done}/{total}] {set}, decimate {decimate}, {threads} thread(s): {}", which.label());
                    let job = Job {
                        which,
                        set: set.clone(),
                        fixtures: fixtures.clone(),
                        photos: photos.clone(),
                        decimate,
                        threads,
                        repeat: args.repeat,
                        min_white_black_diff: args.min_white_black_diff,
                    };
                    let o = spawn(&job)?;
                    if o.frames == 0 {
                        eprintln!("SKIPPED: set {set} has no frames");
                        break;
                    }
                    let fps = o.frames as f64 / o.seconds;
                    let c_fps = c_out.as_ref().map(|c| c.frames as f64 / c.seconds);
                    let recall = if o.want > 0 { format!("{}/{}", o.found, o.want) } else { "–".into() };
                    let fp = if o.want > 0 { o.false_positives.to_string() } else { "–".into() };
                    let err = if o.errors.is_empty() { "–".into() } else { format!("{:.3}", median_of(&o.errors)) };
                    let agree = match &c_out {
                        Some(c) => {
                            let (both, n, d) = agreement(&o, c);
                            format!("{both}/{n}, {d:.3}")
                        }
                        None => "–".into(),
                    };
                    let row = format!(
                        "| {set} | {} | {decimate} | {threads} | {} | {fps:.1} | {} | {recall} | {fp} | {err} | {agree} | {} |\n",
                        o.frames,
                        which.label(),
                        c_fps.map_or("1.00".into(), |c| format!("{:.2}", fps / c)),
                        o.peak_mb.map_or("n/a".into(), |m| format!("{m:.1}")),
                    );
                    print!("{row}");
                    let _ = std::io::stdout().flush();
                    table.push_str(&row);
                    if which == Which::C {
                        c_out = Some(o);
                    }
                }
            }
        }
    }
    if let Some(path) = &args.out {
        std::fs::write(path, &table).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
