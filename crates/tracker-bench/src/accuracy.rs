//! The benchtop accuracy run behind `jawtrack-bench accuracy` and the `bench-accuracy`
//! binary: the 2020 thesis's benchtop experiments on rendered frames with exact ground truth
//! (`crate::benchtop`), written as a report a clinician can read (`report.md` with PNG plots),
//! CSV tables, and the same tables for the reference stack on the same frames when OpenCV is
//! installed and the `reference` feature is on (in `bench-accuracy`, not in `jawtrack`, which
//! links no C). Both front-ends parse `AccuracyArgs` and call `run`, so they take the same
//! flags and write the same report.

use crate::benchtop::{
    self, Column, DynamicRow, FLIP_DEG, MarkerFile, MeanSd, Options, Regression, Run, Stack, StaticRow,
};
use anyhow::{Context, Result};
use clap::Args;
use jawtrack_plot::{self as plot, Series, Style};
use jawtrack_synth::SceneKind;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

mod markdown;

use markdown::report;

/// Static target: mean position error per view (mm).
const STATIC_MM: f64 = 0.05;
/// Static target: mean orientation error per view (°).
const STATIC_DEG: f64 = 0.1;
/// Dynamic target: standard error per opening (mm).
const DYNAMIC_SE_MM: f64 = 0.1;
/// Head axes, in the order of the error vectors.
const AXES: [&str; 3] = ["X (left)", "Y (down)", "Z (back)"];

/// Arguments of `jawtrack-bench accuracy` and of the `bench-accuracy` binary.
#[derive(Args)]
pub struct AccuracyArgs {
    /// Output folder: report.md, CSV tables, PNG and SVG plots. Rendered frames are cached in
    /// its `frames/` (rendering is most of a first run's time; later runs reuse them).
    #[arg(long, default_value = "out/bench-accuracy")]
    out: PathBuf,
    /// Seed of everything random (print errors, noise, tremor).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Frames per view of the calibration recording (18 views).
    #[arg(long, default_value_t = 2)]
    calibration_frames_per_view: usize,
    /// Frames per static view (3 angles × 3 distances × tripod and hand-held).
    #[arg(long, default_value_t = 3)]
    frames_per_view: usize,
    /// Rounds of the four hinge openings, 10/20/30/40 mm (the thesis ran 30 cycles).
    #[arg(long, default_value_t = 30)]
    hinge_cycles: usize,
    /// Glides per excursion direction (left, right, protrusive).
    #[arg(long, default_value_t = 10)]
    excursion_cycles: usize,
    /// Frame rate of the hinge and excursions (frames/s; each movement lasts 2 s).
    #[arg(long, default_value_t = 5.0)]
    fps: f64,
    /// A smoke run: one calibration frame per view, one round or glide, at most 4 frames per
    /// scene. Its tables are too small to judge anything by.
    #[arg(long)]
    quick: bool,
    /// Where rendered frames are cached (default: the `frames` folder inside `--out`).
    #[arg(long)]
    cache: Option<PathBuf>,
    /// The Python that runs OpenCV for the reference stack (skipped, and said so, without it).
    #[arg(long, default_value = "python3")]
    python: String,
    #[command(flatten)]
    chew: benchtop::chew::ChewArgs,
    #[command(flatten)]
    capture: benchtop::capture::CaptureArgs,
    /// Run the capture section alone (no calibration, static grid, hinge, excursions or chew
    /// at the rig's distances).
    #[arg(long, conflicts_with = "no_capture")]
    capture_only: bool,
    #[command(flatten)]
    tone: benchtop::tone::ToneArgs,
    /// Run the tone section alone (the static grid at 100 mm developed through phones' tone
    /// curves; nothing else).
    #[arg(long, conflicts_with_all = ["no_tone", "capture_only"])]
    tone_only: bool,
}

/// Runs the benchtop experiments and writes the report, tables, plots and calibrated marker
/// into `a.out`; prints a summary and the report's path.
pub fn run(a: &AccuracyArgs) -> Result<()> {
    let options = Options {
        seed: a.seed,
        calibration_frames_per_view: if a.quick { 1 } else { a.calibration_frames_per_view },
        frames_per_view: if a.quick { 1 } else { a.frames_per_view },
        hinge_cycles: if a.quick { 1 } else { a.hinge_cycles },
        excursion_cycles: if a.quick { 1 } else { a.excursion_cycles },
        fps: a.fps,
        max_frames: a.quick.then_some(4),
        cache: a.cache.clone().unwrap_or_else(|| a.out.join("frames")),
        python: vec![a.python.clone()],
    };
    options.validate()?;
    let chew = a.chew.options();
    if let Some(c) = &chew {
        c.validate()?;
    }
    let capture = a.capture.options(a.quick)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let started = std::time::Instant::now();
    let bar = jawtrack_progress::bar("", None, "");
    let mut stage = String::new();
    let mut progress = |what: &str, done: usize, total: usize| {
        if total == 0 {
            bar.println(what);
            return;
        }
        if what != stage {
            if !stage.is_empty() {
                bar.println(format!("{stage}: done, {:.0} s in all so far", started.elapsed().as_secs_f64()));
            }
            stage = what.to_owned();
            bar.set_message(stage.clone());
            bar.set_length(total as u64);
        }
        bar.set_position(done as u64);
    };
    if a.tone_only {
        let tones = benchtop::tone::run(&options, &a.tone, &mut progress)?;
        bar.finish_and_clear();
        let csv = benchtop::tone::write_csv(&tones, &a.out)?;
        let path = a.out.join("report.md");
        let text = format!(
            "# JawTrack: tone curves\n\nReproduce: `cargo run --release -p jawtrack-tracker-bench --bin bench-accuracy -- --tone-only --tone-frames-per-view {}{}` (seed {}). Table: {}.\n{}",
            a.tone.tone_frames_per_view,
            if a.quick { " --quick" } else { "" },
            a.seed,
            csv.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned()),
            benchtop::tone::markdown(&tones, a.tone.tone_frames_per_view)
        );
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
        crate::say(format_args!("report: {} ({:.0} s)", path.display(), started.elapsed().as_secs_f64()));
        return Ok(());
    }
    if a.capture_only {
        let Some(c) = &capture else { anyhow::bail!("--capture-only and --no-capture leave nothing to run") };
        let captures = benchtop::capture::run(&options, c, &mut progress)?;
        bar.finish_and_clear();
        let path = crate::capture::write_alone(&captures, c, &a.out)?;
        crate::say(format_args!("report: {} ({:.0} s)", path.display(), started.elapsed().as_secs_f64()));
        return Ok(());
    }
    let run = benchtop::run(&options, &mut progress)?;
    let chews = match &chew {
        Some(c) => benchtop::chew::run(&options, c, &mut progress)?,
        None => Vec::new(),
    };
    let captures = match &capture {
        Some(c) => benchtop::capture::run(&options, c, &mut progress)?,
        None => Vec::new(),
    };
    let tones = if a.tone.no_tone { Vec::new() } else { benchtop::tone::run(&options, &a.tone, &mut progress)? };
    bar.finish_and_clear();

    let marker = a.out.join("calibrated_marker.json");
    run.calibrated_marker.save(&marker).with_context(|| format!("writing {}", marker.display()))?;
    let mut markers = vec![("front_faces_marker.json".to_owned(), &run.front_only_marker)];
    for s in &run.sessions {
        for (case, m) in ["front_faces", "calibrated"].iter().zip(&s.markers) {
            markers.push((format!("{case}_refined_on_{}_marker.json", s.scene.name()), m));
        }
    }
    for (name, m) in markers {
        m.save(&a.out.join(&name)).with_context(|| format!("writing {name} in {}", a.out.display()))?;
    }
    let mut files = write_csv(&run, &a.out)?;
    files.extend(write_plots(&run, &a.out)?);
    files.extend(crate::chew::plots(&chews, &a.out)?);
    files.extend(crate::capture::write(&captures, &a.out)?);
    if !tones.is_empty() {
        files.push(benchtop::tone::write_csv(&tones, &a.out)?);
    }
    let mut report = report(&run, &options, &files, &a.out);
    // The chewing section goes with the other results, before the list of plots.
    let at = report.find("\n## Plots and tables").unwrap_or(report.len());
    report.insert_str(at, &crate::chew::markdown(&chews, run.reference.is_ok()));
    if let Some(c) = &capture {
        let at = report.find("\n## Plots and tables").unwrap_or(report.len());
        report.insert_str(at, &crate::capture::markdown(&captures, c));
    }
    if !tones.is_empty() {
        let at = report.find("\n## Plots and tables").unwrap_or(report.len());
        report.insert_str(at, &benchtop::tone::markdown(&tones, a.tone.tone_frames_per_view));
    }
    let path = a.out.join("report.md");
    std::fs::write(&path, &report).with_context(|| format!("writing {}", path.display()))?;
    crate::say(format_args!("{}", summary(&run)));
    for line in crate::chew::summary(&chews) {
        crate::say(format_args!("{line}"));
    }
    if let Some(c) = &capture {
        for line in crate::capture::summary(&captures, c) {
            crate::say(format_args!("{line}"));
        }
    }
    crate::say(format_args!("report: {} ({:.0} s)", path.display(), started.elapsed().as_secs_f64()));
    Ok(())
}

/// The columns by what they are.
fn column(run: &Run, stack: Stack, marker: MarkerFile) -> Option<usize> {
    run.columns.iter().position(|c| c.stack == stack && c.marker == marker)
}

/// The columns the main tables show: each stack with the calibrated marker, without and
/// with the bite step.
fn main_columns(run: &Run) -> Vec<usize> {
    [Stack::Ours, Stack::Reference]
        .into_iter()
        .flat_map(|s| [MarkerFile::Calibrated, MarkerFile::CalibratedBite].map(|m| column(run, s, m)))
        .flatten()
        .collect()
}

fn fmt_ms(m: Option<MeanSd>, digits: usize) -> String {
    m.map_or("—".into(), |m| format!("{:.*} ± {:.*}", digits, m.mean, digits, m.sd))
}

fn fmt_regression(r: Option<Regression>) -> String {
    match r {
        None => "—".into(),
        Some(r) => match r.r2 {
            Some(r2) => format!("{r2:.5} / {:.3}", r.se_mm),
            None => format!("still / {:.3}", r.se_mm),
        },
    }
}

fn mount(row: &StaticRow) -> &'static str {
    if row.hand_held { "hand" } else { "tripod" }
}

/// How a column fares against the targets.
struct Verdict {
    /// Worst view's mean position error (mm) and its name.
    static_mm: (f64, String),
    /// Worst view's mean orientation error (°) and its name.
    static_deg: (f64, String),
    /// Views with no jaw pose in any frame.
    static_lost: usize,
    /// Worst standard error over hinge openings and glides (mm) and where.
    dynamic_se: (f64, String),
    /// Frames over `FLIP_DEG` in all scenes, and the worst angle.
    flips: (usize, f64),
    /// Judged frames without a jaw pose.
    lost: usize,
}

fn verdict(run: &Run, c: usize) -> Verdict {
    let mut v = Verdict {
        static_mm: (0.0, String::new()),
        static_deg: (0.0, String::new()),
        static_lost: 0,
        dynamic_se: (0.0, String::new()),
        flips: (0, 0.0),
        lost: 0,
    };
    for row in benchtop::static_rows(run, c) {
        let name = format!("{} {:.0}° {:.0} mm", mount(&row), row.azimuth_deg, row.distance_mm);
        match (row.mm(), row.deg()) {
            (Some(mm), Some(deg)) => {
                if mm.mean > v.static_mm.0 {
                    v.static_mm = (mm.mean, name.clone());
                }
                if deg.mean > v.static_deg.0 {
                    v.static_deg = (deg.mean, name);
                }
            }
            _ => v.static_lost += 1,
        }
    }
    for scene in [SceneKind::Hinge, SceneKind::Excursion] {
        for row in benchtop::dynamic_rows(run, scene, c) {
            if let Some(se) = row.worst_se_mm().filter(|se| *se > v.dynamic_se.0) {
                v.dynamic_se = (se, format!("{} {}", scene.name(), row.label));
            }
        }
    }
    for scene in [SceneKind::Static, SceneKind::Hinge, SceneKind::Excursion] {
        let f = benchtop::flips(run, scene, c);
        v.flips.0 += f.flips;
        v.flips.1 = v.flips.1.max(f.worst_deg);
        v.lost += f.frames - f.posed;
    }
    v
}

fn met(ok: bool) -> &'static str {
    if ok { "**met**" } else { "**not met**" }
}

/// A few lines for the terminal.
fn summary(run: &Run) -> String {
    let mut s = String::new();
    for (c, col) in run.columns.iter().enumerate() {
        let v = verdict(run, c);
        let _ = writeln!(
            s,
            "{:34} static worst view {:.3} mm / {:.3}°; hinge and excursion worst SE {:.3} mm; {} frames > {FLIP_DEG}° (worst {:.2}°); {} frames without a pose",
            col.name(),
            v.static_mm.0,
            v.static_deg.0,
            v.dynamic_se.0,
            v.flips.0,
            v.flips.1,
            v.lost
        );
    }
    if let Err(why) = &run.reference {
        let _ = writeln!(s, "SKIPPED: the reference stack's columns — {why}");
    }
    s.trim_end().to_owned()
}

fn csv_err(path: &Path) -> impl Fn(csv::Error) -> anyhow::Error + '_ {
    move |e| anyhow::anyhow!("writing {}: {e}", path.display())
}

/// `static.csv`, `dynamic.csv` and `frames.csv`; returns their paths.
fn write_csv(run: &Run, out: &Path) -> Result<Vec<PathBuf>> {
    let num = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6}"));
    let path = out.join("static.csv");
    let mut w = csv::Writer::from_path(&path).map_err(csv_err(&path))?;
    let mut header = ["column", "mount", "azimuth_deg", "distance_mm", "frames", "poses"].map(String::from).to_vec();
    for what in ["x_mm", "y_mm", "z_mm", "about_x_deg", "about_y_deg", "about_z_deg", "position_mm", "orientation_deg"]
    {
        header.push(format!("{what}_mean"));
        header.push(format!("{what}_sd"));
    }
    w.write_record(&header).map_err(csv_err(&path))?;
    for (c, col) in run.columns.iter().enumerate() {
        for row in benchtop::static_rows(run, c) {
            let mut rec = vec![
                col.slug(),
                mount(&row).into(),
                format!("{}", row.azimuth_deg),
                format!("{}", row.distance_mm),
                row.frames.to_string(),
                row.errors.len().to_string(),
            ];
            for m in [0, 1, 2]
                .map(|a| row.position(a))
                .into_iter()
                .chain([0, 1, 2].map(|a| row.rotation(a)))
                .chain([row.mm(), row.deg()])
            {
                rec.push(num(m.map(|m| m.mean)));
                rec.push(num(m.map(|m| m.sd)));
            }
            w.write_record(&rec).map_err(csv_err(&path))?;
        }
    }
    w.flush()?;
    let mut files = vec![path];

    let path = out.join("dynamic.csv");
    let mut w = csv::Writer::from_path(&path).map_err(csv_err(&path))?;
    let mut header = ["column", "scene", "movement", "frames", "poses"].map(String::from).to_vec();
    for axis in ["x", "y", "z"] {
        header.extend([format!("{axis}_slope"), format!("{axis}_r2"), format!("{axis}_se_mm")]);
    }
    header.extend(["incisor_error_mm_mean", "incisor_error_mm_sd"].map(String::from));
    w.write_record(&header).map_err(csv_err(&path))?;
    for (c, col) in run.columns.iter().enumerate() {
        for scene in [SceneKind::Hinge, SceneKind::Excursion] {
            for row in benchtop::dynamic_rows(run, scene, c) {
                let mut rec = vec![
                    col.slug(),
                    scene.name().into(),
                    row.label.clone(),
                    row.frames.to_string(),
                    row.errors.len().to_string(),
                ];
                for a in 0..3 {
                    let r = row.regression(a);
                    rec.extend([num(r.and_then(|r| r.slope)), num(r.and_then(|r| r.r2)), num(r.map(|r| r.se_mm))]);
                }
                let m = row.incisor_mm();
                rec.extend([num(m.map(|m| m.mean)), num(m.map(|m| m.sd))]);
                w.write_record(&rec).map_err(csv_err(&path))?;
            }
        }
    }
    w.flush()?;
    files.push(path);

    let path = out.join("frames.csv");
    let mut w = csv::Writer::from_path(&path).map_err(csv_err(&path))?;
    w.write_record([
        "scene",
        "frame",
        "t",
        "column",
        "x_mm",
        "y_mm",
        "z_mm",
        "about_x_deg",
        "about_y_deg",
        "about_z_deg",
    ])
    .map_err(csv_err(&path))?;
    let head_from_maxilla = jawtrack_kinematics::Mounting::default().head_from_maxilla;
    for f in &run.frames {
        for (col, estimate) in run.columns.iter().zip(&f.estimates) {
            let e = estimate.map(|e| benchtop::error_parts(&e, &f.truth, &head_from_maxilla));
            let mut rec = vec![f.scene.name().to_owned(), f.index.to_string(), format!("{:.4}", f.t), col.slug()];
            for a in 0..3 {
                rec.push(num(e.map(|e| e.position_mm[a])));
            }
            for a in 0..3 {
                rec.push(num(e.map(|e| e.rotation_deg[a])));
            }
            w.write_record(&rec).map_err(csv_err(&path))?;
        }
    }
    w.flush()?;
    files.push(path);
    Ok(files)
}

const COLORS: [&str; 6] = ["#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"];

/// Static errors per view, the hinge's sagittal incisor path and the excursions' horizontal
/// path (SVG and PNG); returns the files.
fn write_plots(run: &Run, out: &Path) -> Result<Vec<PathBuf>> {
    // Nominal-marker errors are ten times the others: left out so the calibrated ones show.
    let shown: Vec<(usize, &Column)> =
        run.columns.iter().enumerate().filter(|(_, c)| c.marker != MarkerFile::Nominal).collect();
    let names: Vec<String> = shown.iter().map(|(_, c)| c.name()).collect();
    let mut files = Vec::new();
    for (stem, title, y_label, pick) in [
        ("static_position", "Static grid: mean position error per view", "mm", 0),
        ("static_orientation", "Static grid: mean orientation error per view", "degrees", 1),
    ] {
        let series: Vec<Series<'_>> = shown
            .iter()
            .zip(&names)
            .zip(COLORS)
            .map(|(((c, _), name), color)| Series {
                name,
                color,
                style: Style::Dots,
                points: benchtop::static_rows(run, *c)
                    .iter()
                    .enumerate()
                    .filter_map(|(i, r)| {
                        let m = if pick == 0 { r.mm() } else { r.deg() };
                        m.map(|m| ((i + 1) as f64, m.mean))
                    })
                    .collect(),
            })
            .collect();
        let doc = plot::chart(
            title,
            "view (1–9 tripod, 10–18 hand; by distance, then angle 0/30/60°)",
            y_label,
            &series,
            false,
        );
        files.extend(plot::save_svg_and_png(&doc, &out.join(stem))?);
    }
    let main = main_columns(run);
    for (scene, stem, title, axes) in [
        (
            SceneKind::Hinge,
            "hinge_sagittal",
            "Hinge: lower incisor, sagittal plane (seen from the patient's right: facing right)",
            [2usize, 1],
        ),
        (
            SceneKind::Excursion,
            "excursion_horizontal",
            "Excursions: lower incisor, horizontal plane (seen from below: the patient's left on the right)",
            [0, 2],
        ),
    ] {
        let flip = |axis: usize, v: f64| if axis == 0 { v } else { -v };
        let to_xy = |v: &nalgebra::Vector3<f64>| (flip(axes[0], v[axes[0]]), flip(axes[1], v[axes[1]]));
        let rows: Vec<Vec<DynamicRow>> = main.iter().map(|&c| benchtop::dynamic_rows(run, scene, c)).collect();
        let Some(first) = rows.first() else { continue };
        let main_names: Vec<String> = main.iter().map(|&c| run.columns[c].name()).collect();
        let mut series = vec![Series {
            name: "truth",
            color: "#222",
            style: Style::Dots,
            points: first.iter().flat_map(|r| r.truth.iter().map(to_xy)).collect(),
        }];
        for ((r, name), color) in rows.iter().zip(&main_names).zip(COLORS) {
            series.push(Series {
                name,
                color,
                style: Style::Dots,
                points: r.iter().flat_map(|r| r.tracked.iter().map(to_xy)).collect(),
            });
        }
        let (xl, yl) = if scene == SceneKind::Hinge {
            ("anterior (mm)", "up (mm)")
        } else {
            ("toward the patient's left (mm)", "anterior (mm)")
        };
        let doc = plot::chart(title, xl, yl, &series, true);
        files.extend(plot::save_svg_and_png(&doc, &out.join(stem))?);
        // The paths overlap at this scale: the error against the incisor's travel shows more.
        let series: Vec<Series<'_>> = rows
            .iter()
            .zip(&main_names)
            .zip(COLORS)
            .map(|((r, name), color)| Series {
                name,
                color,
                style: Style::Dots,
                points: r
                    .iter()
                    .flat_map(|r| r.truth.iter().zip(&r.tracked).map(|(t, k)| (t.norm(), (t - k).norm())))
                    .collect(),
            })
            .collect();
        let doc = plot::chart(
            &format!("{}: lower incisor error against its travel", scene.name()),
            "true incisor travel from closed (mm)",
            "incisor error (mm)",
            &series,
            false,
        );
        files.extend(plot::save_svg_and_png(&doc, &out.join(format!("{stem}_error")))?);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run with one column of ours and no frames: enough for the report's prose.
    fn empty_run(reference: std::result::Result<String, String>) -> Run {
        Run::judged(vec![Column { stack: Stack::Ours, marker: MarkerFile::Calibrated }], reference, Vec::new())
    }

    fn options() -> Options {
        Options {
            seed: 1,
            calibration_frames_per_view: 1,
            frames_per_view: 1,
            hinge_cycles: 1,
            excursion_cycles: 1,
            fps: 5.0,
            max_frames: None,
            cache: PathBuf::from("frames"),
            python: Vec::new(),
        }
    }

    #[test]
    fn the_report_names_the_command_that_reproduces_its_columns() {
        let out = Path::new("out");
        let skipped = report(&empty_run(Err("not built in".into())), &options(), &[], out);
        assert!(skipped.contains("**The reference stack was skipped**: not built in."), "{skipped}");
        assert!(!skipped.contains("- reference:"), "no bite step is reported for a stack that did not run");
        assert!(skipped.contains("Reproduce: `jawtrack-bench accuracy --seed 1 "), "{skipped}");

        let with = report(&empty_run(Ok("the C library".into())), &options(), &[], out);
        assert!(with.contains("- reference: no closed-jaw pose, so no bite step."), "{with}");
        assert!(
            with.contains(
                "Reproduce: `cargo run --release -p jawtrack-tracker-bench --bin bench-accuracy -- --seed 1 "
            ),
            "{with}"
        );
    }
}
