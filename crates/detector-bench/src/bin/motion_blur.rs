//! `motion-blur`: corner accuracy on motion-blurred frames, split by how far each tag is smeared
//! during the exposure (issue 22).
//!
//! `render` writes frames of a scene (PNG, `ground_truth.json`) and `smear.json`: for every tag,
//! how far its corners travel during the exposure (the truth at t ± exposure/2, from the same
//! scene's poses). `measure` detects the tags on one or more such folders and prints, per smear
//! band, tags found against the truth's detectable ones and the corner error (median, 90th
//! percentile, max); `--dump` writes every tag's errors for a before/after comparison, which
//! `--against` reads.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
use jawtrack_synth::{GroundTruth, SceneKind, SynthConfig, Synthesizer, scenes::Rig};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Parser)]
#[command(about = "Corner accuracy on motion-blurred rendered frames, by smear length")]
struct Args {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Renders frames with their truth and every tag's smear into a folder.
    Render(RenderArgs),
    /// Detects the tags of rendered folders and prints the corner error by smear.
    Measure(MeasureArgs),
}

#[derive(clap::Args)]
struct RenderArgs {
    /// static, hinge, excursion, chew or calibration.
    #[arg(long, default_value = "chew")]
    scene: String,
    /// Exposure (s); the rest of the realism is the default.
    #[arg(long, default_value_t = 1.0 / 120.0)]
    exposure: f64,
    /// Frames to render (from the first, every `--stride`-th).
    #[arg(long, default_value_t = 30)]
    frames: usize,
    /// Render every n-th frame of the scene.
    #[arg(long, default_value_t = 1)]
    stride: usize,
    /// Seed of the scene.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Chewing cycles (or cycles per movement) of the scene.
    #[arg(long, default_value_t = 2)]
    cycles: usize,
    /// Frames per view (static, calibration).
    #[arg(long, default_value_t = 1)]
    frames_per_view: usize,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

#[derive(clap::Args)]
struct MeasureArgs {
    /// Decimation of the quad image.
    #[arg(long, default_value_t = 2.0)]
    decimate: f32,
    /// The quad finder's contrast threshold (default: the detector's).
    #[arg(long)]
    min_white_black_diff: Option<u8>,
    /// The quad finder's largest line-fit error (px², default: the detector's).
    #[arg(long)]
    max_line_fit_mse: Option<f32>,
    /// Sharpening of the decoded bits (default: the detector's).
    #[arg(long)]
    sharpening: Option<f64>,
    /// Only tags seen at this many degrees from face-on or more.
    #[arg(long, default_value_t = 0.0)]
    min_view_deg: f64,
    /// Only tags seen at less than this many degrees from face-on.
    #[arg(long, default_value_t = 90.0)]
    max_view_deg: f64,
    /// Upper ends of the smear bands (px).
    #[arg(long, value_delimiter = ',', default_values_t = [1.0, 3.0, 5.0, 7.0, 9.0, 12.0])]
    bands: Vec<f64>,
    /// Writes every tag's result (JSON) here.
    #[arg(long)]
    dump: Option<PathBuf>,
    /// Reads a previous `--dump` and prints the change per band, tag by tag.
    #[arg(long)]
    against: Option<PathBuf>,
    /// Folders written by `render`.
    dirs: Vec<PathBuf>,
}

/// Per frame file, per tag id: how far its corners move during the exposure (px, the largest
/// of the four).
type Smear = BTreeMap<String, BTreeMap<u32, f64>>;

/// One truth tag's outcome.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct TagResult {
    dir: String,
    file: String,
    id: u32,
    smear_px: f64,
    side_px: f64,
    view_angle_deg: f64,
    /// Corner errors (px), `None` when not found.
    errors: Option<[f64; 4]>,
}

fn render(a: &RenderArgs) -> Result<()> {
    let scene: SceneKind = a.scene.parse().map_err(|e: String| anyhow::anyhow!(e))?;
    let (exposure, out) = (a.exposure, a.out.as_path());
    let mut config = SynthConfig::new(scene);
    config.seed = a.seed;
    config.realism.exposure_s = exposure;
    config.options.cycles = a.cycles;
    config.options.frames_per_view = a.frames_per_view;
    config.stride = a.stride;
    config.max_frames = Some(a.frames);
    let synth = Synthesizer::new(config)?;
    std::fs::create_dir_all(out)?;
    let k = synth.camera().intrinsics;
    let marker = synth.true_marker();
    let rig = Rig::default();
    let mut truth = synth.header();
    let mut smear = Smear::new();
    for i in 0..synth.len() {
        let start = Instant::now();
        let frame = synth.render(i)?;
        image::GrayImage::from_raw(frame.width, frame.height, frame.luma.clone())
            .context("frame size")?
            .save(out.join(&frame.truth.file))?;
        let spec = frame.truth.spec;
        // Every tag's corners at time t, as the renderer's truth places them.
        let corners_at = |t: f64| -> BTreeMap<u32, [[f64; 2]; 4]> {
            let cam = spec.view.camera_from_head(t);
            let (max, man) = rig.markers(&spec.motion, t);
            let mut all = BTreeMap::new();
            for (kind, tag) in marker.tags() {
                let pose = cam * if kind.name() == "maxilla" { max } else { man };
                let p: Option<Vec<_>> = tag
                    .corners
                    .iter()
                    .map(|c| k.project(&(pose.transform_vector(c) + pose.translation()).into()))
                    .collect();
                if let Some(p) = p {
                    all.insert(tag.id, std::array::from_fn(|j| [p[j].x, p[j].y]));
                }
            }
            all
        };
        let (mid, a, b) =
            (corners_at(spec.t), corners_at(spec.t - exposure / 2.0), corners_at(spec.t + exposure / 2.0));
        let mut per_tag = BTreeMap::new();
        for t in &frame.truth.tags {
            // The poses reproduce the renderer's truth, or the smear would mean nothing.
            let m = mid.get(&t.id).context("a truth tag the poses do not place")?;
            let off = m.iter().zip(&t.corners).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max);
            if off > 1e-6 {
                bail!("frame {i}, tag {}: recomputed truth is {off} px off the renderer's", t.id);
            }
            if let (Some(a), Some(b)) = (a.get(&t.id), b.get(&t.id)) {
                let s = a.iter().zip(b).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max);
                per_tag.insert(t.id, s);
            }
        }
        let most = per_tag.values().copied().fold(0.0, f64::max);
        eprintln!(
            "frame {i}: {:.1} s, {} subframes, largest smear {most:.1} px",
            start.elapsed().as_secs_f64(),
            frame.truth.subframes
        );
        smear.insert(frame.truth.file.clone(), per_tag);
        truth.frames.push(frame.truth);
    }
    std::fs::write(out.join("smear.json"), serde_json::to_string_pretty(&smear)?)?;
    std::fs::write(out.join("ground_truth.json"), serde_json::to_string_pretty(&truth)?)?;
    Ok(())
}

fn detect_dir(dir: &Path, detector: &Detector) -> Result<Vec<TagResult>> {
    let gt: GroundTruth = serde_json::from_str(&std::fs::read_to_string(dir.join("ground_truth.json"))?)
        .with_context(|| format!("{}", dir.join("ground_truth.json").display()))?;
    let smear: Smear = serde_json::from_str(&std::fs::read_to_string(dir.join("smear.json"))?)?;
    let mut out = Vec::new();
    for f in &gt.frames {
        let img = image::open(dir.join(&f.file))?.to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let dets = detector.detect(&ImageView::new(img.as_raw(), w, h, w)?)?;
        for t in f.tags.iter().filter(|t| t.should_be_detected()) {
            let errors = dets.iter().find(|d| d.id == t.id).map(|d| {
                std::array::from_fn(|j| (d.corners[j][0] - t.corners[j][0]).hypot(d.corners[j][1] - t.corners[j][1]))
            });
            out.push(TagResult {
                dir: dir.display().to_string(),
                file: f.file.clone(),
                id: t.id,
                smear_px: smear.get(&f.file).and_then(|s| s.get(&t.id)).copied().unwrap_or(f64::NAN),
                side_px: t.min_side_px,
                view_angle_deg: t.view_angle_deg,
                errors,
            });
        }
    }
    Ok(out)
}

/// The q-quantile of sorted values (nearest rank).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

fn band_label(bands: &[f64], i: usize) -> String {
    match i {
        0 => format!("< {}", bands[0]),
        _ if i == bands.len() => format!("≥ {}", bands[i - 1]),
        _ => format!("{}–{}", bands[i - 1], bands[i]),
    }
}

fn band_of(bands: &[f64], smear: f64) -> usize {
    bands.iter().position(|&b| smear < b).unwrap_or(bands.len())
}

fn measure(a: &MeasureArgs) -> Result<()> {
    let (bands, dirs) = (&a.bands, &a.dirs);
    if dirs.is_empty() {
        bail!("give at least one rendered folder");
    }
    let decimate = a.decimate;
    // The smeared-edge fit is what is measured (the tracker turns it on for moving frames).
    let mut config = DetectorConfig { quad_decimate: decimate, smeared_edges: true, ..DetectorConfig::default() };
    if let Some(v) = a.min_white_black_diff {
        config.quad.min_white_black_diff = v;
    }
    if let Some(v) = a.max_line_fit_mse {
        config.quad.max_line_fit_mse = v;
    }
    if let Some(v) = a.sharpening {
        config.decode_sharpening = v;
    }
    let detector = Detector::new(config)?;
    let mut all = Vec::new();
    let start = Instant::now();
    for d in dirs {
        all.extend(detect_dir(d, &detector)?);
    }
    eprintln!("detected in {:.1} s", start.elapsed().as_secs_f64());
    all.retain(|r| (a.min_view_deg..a.max_view_deg).contains(&r.view_angle_deg));
    println!("| smear (px) | found / truth | median | p90 | max (px) |\n|---|---|---|---|---|");
    let mut rows: Vec<(String, Vec<&TagResult>)> =
        (0..=bands.len()).map(|i| (band_label(bands, i), Vec::new())).collect();
    for r in &all {
        rows[band_of(bands, r.smear_px)].1.push(r);
    }
    rows.push(("all".into(), all.iter().collect()));
    for (label, rs) in &rows {
        if rs.is_empty() {
            continue;
        }
        let mut e: Vec<f64> = rs.iter().filter_map(|r| r.errors).flatten().collect();
        e.sort_by(f64::total_cmp);
        let found = rs.iter().filter(|r| r.errors.is_some()).count();
        println!(
            "| {label} | {found} / {} | {:.3} | {:.3} | {:.3} |",
            rs.len(),
            quantile(&e, 0.5),
            quantile(&e, 0.9),
            e.last().copied().unwrap_or(f64::NAN)
        );
    }
    if let Some(path) = &a.against {
        let before: Vec<TagResult> = serde_json::from_str(&std::fs::read_to_string(path)?)?;
        let key = |r: &TagResult| (r.dir.clone(), r.file.clone(), r.id);
        let old: BTreeMap<_, _> = before.iter().map(|r| (key(r), r)).collect();
        println!("\nAgainst {}: tag by tag (worst corner)\n", path.display());
        println!(concat!(
            "| smear (px) | both found | lost | gained | worse by > 0.1 px | better by > 0.1 px ",
            "| largest worsening (px) |\n|---|---|---|---|---|---|---|"
        ));
        for (label, rs) in rows.iter().filter(|r| !r.1.is_empty()) {
            let (mut both, mut lost, mut gained, mut worse, mut better, mut worst) = (0, 0, 0, 0, 0, 0.0f64);
            for r in rs {
                let Some(o) = old.get(&key(r)) else { continue };
                let top = |e: &[f64; 4]| e.iter().copied().fold(0.0, f64::max);
                match (o.errors, r.errors) {
                    (Some(a), Some(b)) => {
                        both += 1;
                        let d = top(&b) - top(&a);
                        worse += usize::from(d > 0.1);
                        better += usize::from(d < -0.1);
                        worst = worst.max(d);
                    }
                    (Some(_), None) => lost += 1,
                    (None, Some(_)) => gained += 1,
                    (None, None) => {}
                }
            }
            println!("| {label} | {both} | {lost} | {gained} | {worse} | {better} | {worst:.3} |");
        }
    }
    if let Some(path) = &a.dump {
        std::fs::write(path, serde_json::to_string(&all)?)?;
    }
    Ok(())
}

fn main() -> Result<()> {
    match Args::parse().command {
        Cmd::Render(a) => render(&a),
        Cmd::Measure(a) => measure(&a),
    }
}
