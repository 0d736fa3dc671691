//! The capture section of the benchtop report: the static grid and chewing as a real phone
//! films them ([`crate::benchtop::capture`]), as tables (the plan's choice in bold), the
//! issue's targets judged, a CSV of every frame and two plots: error against distance per
//! format, and error against the measured blur (what sets the `defocused` flag's threshold).

use crate::benchtop::capture::{CaptureOptions, CaseResult, Focus, READOUT_S};
use crate::chew::PoseError;
use anyhow::{Context, Result};
use jawtrack_plot::{self as plot, Series, Style};
use jawtrack_synth::SceneKind;
use jawtrack_tracker::DEFOCUSED_BLUR_PER_CELL;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The targets at the plan's geometry (mm): static median and max; chewing at 2 ms mean
/// and p95; at 8 ms mean and p95.
const PLAN_STATIC: (f64, f64) = (0.03, 0.08);
const PLAN_CHEW_2MS: (f64, f64) = (0.05, 0.08);
const PLAN_CHEW_8MS: (f64, f64) = (0.08, 0.15);
/// 200 mm at 1× on 1080p: static median (mm).
const ONE_X_200: f64 = 0.05;

/// Sorted copy.
fn sorted(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    v
}

/// The project's one median (the upper middle value).
fn median(v: &[f64]) -> Option<f64> {
    jawtrack_pose::median(v.iter().copied())
}

/// Nearest-rank percentile.
fn percentile(v: &[f64], p: f64) -> Option<f64> {
    let v = sorted(v.to_vec());
    (!v.is_empty()).then(|| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1])
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// A case's figures.
pub struct Figures {
    /// Frames in all.
    pub frames: usize,
    /// Frames with a jaw pose.
    pub posed: usize,
    /// Frames with a body solved but flagged `defocused`, and with a body solved at all.
    pub defocused: usize,
    /// Frames with a body solved.
    pub seen: usize,
    /// Position errors (mm) of the posed frames.
    pub mm: Vec<f64>,
    /// The median blur over the cells.
    pub blur_per_cell: Option<f64>,
}

impl Figures {
    /// Of a case.
    pub fn of(r: &CaseResult) -> Self {
        let mm: Vec<f64> = r.frames.iter().filter_map(|f| f.error.map(|e: PoseError| e.mm)).collect();
        let blur: Vec<f64> = r.frames.iter().filter_map(|f| f.blur_per_cell).collect();
        Figures {
            frames: r.frames.len(),
            posed: mm.len(),
            defocused: r.frames.iter().filter(|f| f.defocused == Some(true)).count(),
            seen: r.frames.iter().filter(|f| f.defocused.is_some()).count(),
            blur_per_cell: median(&blur),
            mm,
        }
    }

    /// Median / max (mm), or a dash.
    pub fn median_max(&self) -> String {
        match (median(&self.mm), self.mm.iter().copied().reduce(f64::max)) {
            (Some(m), Some(x)) => format!("{m:.3} / {x:.3}"),
            _ => "—".into(),
        }
    }

    /// Mean / p95 / max (mm), or a dash.
    pub fn mean_p95_max(&self) -> String {
        match (mean(&self.mm), percentile(&self.mm, 0.95), self.mm.iter().copied().reduce(f64::max)) {
            (Some(m), Some(p), Some(x)) => format!("{m:.3} / {p:.3} / {x:.3}"),
            _ => "—".into(),
        }
    }
}

fn focus_words(r: &CaseResult, o: &CaptureOptions) -> String {
    match r.case.focus {
        Focus::Focused => format!("locked at {:.0} mm", r.case.distance_mm),
        Focus::Stuck => format!("stuck at {:.0} mm", o.plan.min_focus_mm),
    }
}

fn bold(s: String, on: bool) -> String {
    if on { format!("**{s}**") } else { s }
}

/// The section's markdown.
pub fn markdown(results: &[CaseResult], o: &CaptureOptions) -> String {
    if results.is_empty() {
        return String::new();
    }
    let mut md = String::new();
    let p = &o.plan;
    let _ = writeln!(
        md,
        "\n## Capture: where a phone can focus\n\n\
         Rendered as the wide camera of a Pro iPhone ({}) films: 6.8 mm at f/1.78 (a 3.8 mm disc pupil), focus breathing (the focal length grows by u/(u − f) when focused at u), the lens's own blur of 0.7 µm; a {:.0} ms rolling-shutter readout while chewing (the static grid's single-frame views with a global shutter); the lens cannot focus nearer than {:.0} mm. \
         *Focused*: locked at the phone's distance; *stuck*: at {:.0} mm, as on a phone held nearer than it focuses. \
         Tracked as a user would: the marker as printed (only the optics are wrong), the frames' true intrinsics, the readout and exposure told. \
         Errors: the mandible in the maxilla against the truth (mm). *Defocused*: frames with a body flagged `defocused` (the blur of its tags' edges over their cells above {DEFOCUSED_BLUR_PER_CELL}: no jaw pose is given) out of those with a body solved.\n\n\
         **The plan** for this phone: {}.\n",
        o.phone,
        READOUT_S * 1e3,
        p.min_focus_mm,
        p.min_focus_mm,
        p.summary(),
    );
    for scene in [SceneKind::Static, SceneKind::Chew] {
        let rows: Vec<&CaseResult> = results.iter().filter(|r| r.case.scene == scene).collect();
        if rows.is_empty() {
            continue;
        }
        let (title, errors) = match scene {
            SceneKind::Static => ("Static grid (0/30/60°, tripod and hand)", "median / max (mm)"),
            _ => ("Chewing (60 frames/s, phone upright)", "mean / p95 / max (mm)"),
        };
        let _ = writeln!(md, "### {title}\n");
        let _ = writeln!(
            md,
            "| distance | format | fx (px) | focus | exposure | frames with a jaw pose | defocused | blur / cell | {errors} |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|");
        for r in rows {
            let f = Figures::of(r);
            let c = &r.case;
            let cells = [
                format!("{:.0} mm", c.distance_mm),
                c.format.name(),
                format!("{:.0}", r.fx_px),
                focus_words(r, o),
                format!("{:.0} ms", c.exposure_s * 1e3),
                format!("{}/{}", f.posed, f.frames),
                format!("{}/{}", f.defocused, f.seen),
                f.blur_per_cell.map_or("—".into(), |b| format!("{b:.3}")),
                if scene == SceneKind::Static { f.median_max() } else { f.mean_p95_max() },
            ];
            let cells: Vec<String> = cells.into_iter().map(|s| bold(s, c.planned)).collect();
            let _ = writeln!(md, "| {} |", cells.join(" | "));
        }
        md.push('\n');
    }
    let _ = writeln!(md, "### Against the targets\n");
    for line in verdicts(results, o) {
        let _ = writeln!(md, "- {line}");
    }
    md
}

fn met(ok: bool) -> &'static str {
    if ok { "**met**" } else { "**not met**" }
}

/// The targets, judged on the cases that hold them (none judged when a case is absent).
pub fn verdicts(results: &[CaseResult], o: &CaptureOptions) -> Vec<String> {
    let mut out = Vec::new();
    let find = |scene: SceneKind, pick: &dyn Fn(&CaseResult) -> bool| -> Vec<&CaseResult> {
        results.iter().filter(|r| r.case.scene == scene && pick(r)).collect()
    };
    for r in find(SceneKind::Static, &|r| r.case.planned) {
        let f = Figures::of(r);
        let (m, x) = (median(&f.mm).unwrap_or(f64::INFINITY), f.mm.iter().copied().fold(0.0, f64::max));
        let all = f.posed == f.frames;
        out.push(format!(
            "the plan, static grid, {:.0} ms: median {m:.3} mm ≤ {}, max {x:.3} mm ≤ {}, a pose in {}/{} frames: {}",
            r.case.exposure_s * 1e3,
            PLAN_STATIC.0,
            PLAN_STATIC.1,
            f.posed,
            f.frames,
            met(all && m <= PLAN_STATIC.0 && x <= PLAN_STATIC.1)
        ));
    }
    for r in find(SceneKind::Chew, &|r| r.case.planned) {
        let f = Figures::of(r);
        let target = if r.case.exposure_s <= 0.004 { PLAN_CHEW_2MS } else { PLAN_CHEW_8MS };
        let (m, p) = (mean(&f.mm).unwrap_or(f64::INFINITY), percentile(&f.mm, 0.95).unwrap_or(f64::INFINITY));
        out.push(format!(
            "the plan, chewing, {:.0} ms: mean {m:.3} mm ≤ {}, p95 {p:.3} mm ≤ {}, a pose in {}/{} frames: {}",
            r.case.exposure_s * 1e3,
            target.0,
            target.1,
            f.posed,
            f.frames,
            met(f.posed == f.frames && m <= target.0 && p <= target.1)
        ));
    }
    for r in find(SceneKind::Static, &|r| {
        r.case.distance_mm == 200.0 && r.case.format.zoom == 1.0 && r.case.format.resolution.size().0 == 1920
    }) {
        let f = Figures::of(r);
        let m = median(&f.mm).unwrap_or(f64::INFINITY);
        out.push(format!(
            "200 mm at 1× on 1080p, {:.0} ms: median {m:.3} mm ≤ {ONE_X_200}: {}",
            r.case.exposure_s * 1e3,
            met(m <= ONE_X_200)
        ));
    }
    let too_close: Vec<&CaseResult> =
        results.iter().filter(|r| r.case.focus == Focus::Stuck && r.case.distance_mm <= 120.0).collect();
    if !too_close.is_empty() {
        let (seen, flagged): (usize, usize) =
            too_close.iter().map(|r| Figures::of(r)).fold((0, 0), |(s, d), f| (s + f.seen, d + f.defocused));
        let posed: usize = too_close.iter().map(|r| Figures::of(r).posed).sum();
        out.push(format!(
            "phone at 120 mm, focus stuck at {:.0} mm: {flagged} of the {seen} frames with a body flagged `defocused`, {posed} jaw poses given: {}",
            o.plan.min_focus_mm,
            met(flagged == seen && posed == 0)
        ));
    }
    out
}

/// A line per judged target, for the terminal.
pub fn summary(results: &[CaseResult], o: &CaptureOptions) -> Vec<String> {
    if results.is_empty() {
        return Vec::new();
    }
    let mut lines = vec![format!("capture: the plan for {}: {}", o.phone, o.plan.summary())];
    lines.extend(verdicts(results, o).into_iter().map(|v| format!("capture: {}", v.replace("**", ""))));
    lines
}

/// The capture section run alone (`--capture-only`): its CSV and plots, and a `report.md` with
/// the section; prints the summary and returns the report's path.
pub fn write_alone(results: &[CaseResult], o: &CaptureOptions, out: &Path) -> Result<PathBuf> {
    let files = write(results, out)?;
    let mut report = String::from("# JawTrack benchtop accuracy: capture only\n");
    report += &markdown(results, o);
    report += "\n## Plots and tables\n\n";
    for f in &files {
        report += &format!("- `{}`\n", f.strip_prefix(out).unwrap_or(f).display());
    }
    let path = out.join("report.md");
    std::fs::write(&path, &report).with_context(|| format!("writing {}", path.display()))?;
    for line in summary(results, o) {
        crate::say(format_args!("{line}"));
    }
    Ok(path)
}

/// `capture.csv` (a row per frame) and the two plots.
pub fn write(results: &[CaseResult], out: &Path) -> Result<Vec<PathBuf>> {
    if results.is_empty() {
        return Ok(Vec::new());
    }
    let path = out.join("capture.csv");
    let mut w = csv::Writer::from_path(&path).with_context(|| format!("writing {}", path.display()))?;
    let num = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6}"));
    w.write_record([
        "scene",
        "distance_mm",
        "format",
        "focus",
        "exposure_ms",
        "planned",
        "frame",
        "incisor_speed_mm_s",
        "defocused",
        "blur_per_cell",
        "error_mm",
        "error_deg",
    ])
    .with_context(|| format!("writing {}", path.display()))?;
    for r in results {
        let c = &r.case;
        for (i, f) in r.frames.iter().enumerate() {
            w.write_record([
                c.scene.name().to_owned(),
                format!("{}", c.distance_mm),
                c.format.name(),
                match c.focus {
                    Focus::Focused => "focused".into(),
                    Focus::Stuck => "stuck".into(),
                },
                format!("{}", c.exposure_s * 1e3),
                c.planned.to_string(),
                i.to_string(),
                format!("{:.1}", f.speed_mm_s),
                f.defocused.map_or(String::new(), |d| d.to_string()),
                num(f.blur_per_cell),
                num(f.error.map(|e| e.mm)),
                num(f.error.map(|e| e.deg)),
            ])
            .with_context(|| format!("writing {}", path.display()))?;
        }
    }
    w.flush().with_context(|| format!("writing {}", path.display()))?;
    let mut files = vec![path];
    // Static, focused: median error against distance, a line per format and exposure.
    let colors = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"];
    let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in results.iter().filter(|r| r.case.scene == SceneKind::Static && r.case.focus == Focus::Focused) {
        let name = format!("{}, {:.0} ms", r.case.format.name(), r.case.exposure_s * 1e3);
        let Some(m) = median(&Figures::of(r).mm) else { continue };
        match lines.iter_mut().find(|(n, _)| *n == name) {
            Some((_, points)) => points.push((r.case.distance_mm, m)),
            None => lines.push((name, vec![(r.case.distance_mm, m)])),
        }
    }
    let series: Vec<Series<'_>> = lines
        .iter()
        .enumerate()
        .map(|(i, (name, points))| Series {
            name,
            color: colors[i % colors.len()],
            style: Style::Line,
            points: points.clone(),
        })
        .collect();
    if !series.is_empty() {
        let doc = plot::chart(
            "Static grid, focused: median error against distance",
            "phone distance (mm)",
            "mandible in maxilla, median position error (mm)",
            &series,
            false,
        );
        files.extend(plot::save_svg_and_png(&doc, &out.join("capture_distance"))?);
    }
    // Every static frame with a pose and a blur: error against blur over the cell, focused and not.
    let dots = |focus: Focus| -> Vec<(f64, f64)> {
        results
            .iter()
            .filter(|r| r.case.scene == SceneKind::Static && r.case.focus == focus)
            .flat_map(|r| &r.frames)
            .filter_map(|f| Some((f.blur_per_cell?, f.error?.mm)))
            .collect()
    };
    let series = [
        Series { name: "focused", color: "#1f77b4", style: Style::Dots, points: dots(Focus::Focused) },
        Series { name: "stuck at the nearest focus", color: "#d62728", style: Style::Dots, points: dots(Focus::Stuck) },
    ];
    let series: Vec<Series<'_>> = series.into_iter().filter(|s| !s.points.is_empty()).collect();
    if !series.is_empty() {
        let doc = plot::chart(
            "Static grid: error against the blur the tracker measures",
            "blurrier body's edge blur over its cells (σ / cell)",
            "mandible in maxilla, position error (mm)",
            &series,
            false,
        );
        files.extend(plot::save_svg_and_png(&doc, &out.join("capture_blur"))?);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::benchtop::capture::{CaptureFrame, Case, Format};

    fn frame(mm: Option<f64>, defocused: bool) -> CaptureFrame {
        CaptureFrame {
            error: mm.map(|mm| PoseError { mm, deg: 0.0 }),
            defocused: Some(defocused),
            blur_per_cell: Some(if defocused { 0.4 } else { 0.05 }),
            speed_mm_s: 0.0,
        }
    }

    #[test]
    fn targets_are_judged_on_the_cases_that_hold_them() {
        let o = crate::benchtop::capture::CaptureArgs {
            capture_distances_mm: vec![120.0, 200.0],
            capture_chew_distances_mm: vec![],
            capture_formats: vec!["1080p".into()],
            capture_exposures_ms: vec![2.0],
            capture_frames_per_view: 1,
            capture_phone: "iPhone16,1".into(),
            no_capture: false,
        }
        .options(false)
        .expect("valid")
        .expect("on");
        let case = |distance_mm, format: &str, focus, planned| Case {
            scene: SceneKind::Static,
            distance_mm,
            format: format.parse::<Format>().expect("format"),
            focus,
            exposure_s: 0.002,
            planned,
        };
        let results = vec![
            CaseResult {
                case: case(220.0, "1080p-2x", Focus::Focused, true),
                fx_px: 3100.0,
                frames: vec![frame(Some(0.01), false), frame(Some(0.02), false), frame(Some(0.09), false)],
            },
            CaseResult {
                case: case(200.0, "1080p", Focus::Focused, false),
                fx_px: 1550.0,
                frames: vec![frame(Some(0.04), false), frame(Some(0.05), false)],
            },
            CaseResult {
                case: case(120.0, "1080p", Focus::Stuck, false),
                fx_px: 1550.0,
                frames: vec![frame(None, true), frame(None, true)],
            },
        ];
        let v = verdicts(&results, &o);
        assert_eq!(v.len(), 3, "{v:?}");
        assert!(
            v[0].contains("median 0.020") && v[0].contains("max 0.090") && v[0].ends_with("**not met**"),
            "{}",
            v[0]
        );
        assert!(v[1].contains("median 0.050") && v[1].ends_with("**met**"), "{}", v[1]);
        assert!(
            v[2].contains("2 of the 2 frames") && v[2].contains("0 jaw poses") && v[2].ends_with("**met**"),
            "{}",
            v[2]
        );
        let md = markdown(&results, &o);
        assert!(md.contains("| **220 mm** | **1080p-2x** | **3100** | **locked at 220 mm** |"), "{md}");
        assert!(md.contains("| 120 mm | 1080p | 1550 | stuck at 200 mm | 2 ms | 0/2 | 2/2 | 0.400 | — |"), "{md}");
    }
}
