//! The chewing scene under each exposure and rolling shutter asked for: the jaw's error with
//! our tracker told the readout, ours with the readout ignored, and the reference stack (which
//! knows nothing of shutters), as mean, 95th percentile and max, overall and by incisor speed,
//! and plotted against the speed. Shared by `tracker-bench` and `jawtrack-bench accuracy`.

use anyhow::Result;
use jawtrack_plot::{self as plot, Series, Style};
use jawtrack_pose::Pose;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A mandible-in-maxilla pose against the truth.
#[derive(Debug, Clone, Copy)]
pub struct PoseError {
    /// Distance between the translations (mm).
    pub mm: f64,
    /// Rotation angle between the orientations (degrees).
    pub deg: f64,
}

impl PoseError {
    /// The error of `estimate` of `maxilla_from_mandible` against `truth`.
    pub fn of(estimate: &Pose, truth: &Pose) -> Self {
        let (angle, distance) = estimate.distance_to(truth);
        PoseError { mm: distance, deg: angle.to_degrees() }
    }
}

/// One chew frame, measured by each stack (`None`: no pose).
#[derive(Debug, Clone, Copy)]
pub struct ChewFrame {
    /// The lower incisor's speed relative to the upper jaw (mm/s), from the truth.
    pub speed_mm_s: f64,
    /// Ours, told the readout, with the marker as printed.
    pub ours: Option<PoseError>,
    /// Ours with the readout ignored (`None` also with a global shutter).
    pub ignored: Option<PoseError>,
    /// The reference stack, with the marker as printed.
    pub reference: Option<PoseError>,
}

/// One chew scene: how it was exposed and its frames.
#[derive(Debug, Clone)]
pub struct ChewScene {
    /// How its frames were exposed.
    pub shutter: Shutter,
    /// Its frames, in order.
    pub frames: Vec<ChewFrame>,
}

/// How a chew scene's frames were exposed.
#[derive(Debug, Clone, Copy)]
pub struct Shutter {
    /// Exposure (s).
    pub exposure_s: f64,
    /// Readout, first row to last (s).
    pub readout_s: f64,
    /// `upright` or `landscape`.
    pub orientation: &'static str,
}

/// Incisor speed bins (mm/s): lower bounds.
const SPEED_BINS: [f64; 4] = [0.0, 40.0, 80.0, 120.0];

/// (mean, 95th percentile, max) of `v`, or `None` when empty.
fn spread(mut v: Vec<f64>) -> Option<(f64, f64, f64)> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    // Nearest rank.
    let p95 = v[((0.95 * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    Some((mean, p95, v[v.len() - 1]))
}

fn cell(errors: &[PoseError], pick: fn(&PoseError) -> f64, digits: usize) -> String {
    match spread(errors.iter().map(pick).collect()) {
        Some((mean, p95, max)) => format!("{mean:.digits$} / {p95:.digits$} / {max:.digits$}"),
        None => "—".into(),
    }
}

/// The chewing section of a report (empty when no chew scene ran).
pub fn markdown(chews: &[ChewScene], with_reference: bool) -> String {
    if chews.is_empty() {
        return String::new();
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n## Chewing: exposure and rolling shutter\n\nThe marker as printed; mandible in maxilla against the truth at each frame's time (its centre row's), as mean / 95th percentile / max over the frames with a pose. *Ours* is told the readout; *ours, shutter ignored* is the same tracker told 0; the reference (C + OpenCV) knows no shutter.\n"
    );
    let _ = writeln!(
        md,
        "| exposure | readout | phone | frames | peak incisor speed | ours (mm) | ours (°) | ours, shutter ignored (mm) | ours, shutter ignored (°) | reference (mm) | reference (°) |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|");
    for ChewScene { shutter: s, frames } in chews {
        let ours: Vec<PoseError> = frames.iter().filter_map(|f| f.ours).collect();
        let ignored: Vec<PoseError> = frames.iter().filter_map(|f| f.ignored).collect();
        let reference: Vec<PoseError> = frames.iter().filter_map(|f| f.reference).collect();
        let peak = frames.iter().map(|f| f.speed_mm_s).fold(0.0, f64::max);
        let refcell = |pick, d| if with_reference { cell(&reference, pick, d) } else { "skipped".into() };
        let _ = writeln!(
            md,
            "| {:.1} ms | {:.1} ms | {} | {} | {peak:.0} mm/s | {} | {} | {} | {} | {} | {} |",
            s.exposure_s * 1000.0,
            s.readout_s * 1000.0,
            s.orientation,
            frames.len(),
            cell(&ours, |e| e.mm, 3),
            cell(&ours, |e| e.deg, 3),
            cell(&ignored, |e| e.mm, 3),
            cell(&ignored, |e| e.deg, 3),
            refcell(|e: &PoseError| e.mm, 3),
            refcell(|e: &PoseError| e.deg, 3),
        );
    }
    let _ = writeln!(md, "\nBy incisor speed (mean position error, mm: ours / shutter ignored / reference; frames):\n");
    let header: Vec<String> = SPEED_BINS
        .iter()
        .enumerate()
        .map(|(i, lo)| match SPEED_BINS.get(i + 1) {
            Some(hi) => format!("{lo:.0}–{hi:.0} mm/s"),
            None => format!("≥ {lo:.0} mm/s"),
        })
        .collect();
    let _ = writeln!(md, "| exposure | readout | phone | {} |", header.join(" | "));
    let _ = writeln!(md, "|---|---|---|{}", "---|".repeat(SPEED_BINS.len()));
    for ChewScene { shutter: s, frames: all } in chews {
        let cells: Vec<String> = SPEED_BINS
            .iter()
            .enumerate()
            .map(|(i, lo)| {
                let hi = SPEED_BINS.get(i + 1).copied().unwrap_or(f64::INFINITY);
                let frames: Vec<_> = all.iter().filter(|f| (*lo..hi).contains(&f.speed_mm_s)).collect();
                let mean = |v: Vec<f64>| {
                    if v.is_empty() {
                        "—".to_string()
                    } else {
                        format!("{:.3}", v.iter().sum::<f64>() / v.len() as f64)
                    }
                };
                let ours = mean(frames.iter().filter_map(|f| f.ours.map(|e| e.mm)).collect());
                let ignored = mean(frames.iter().filter_map(|f| f.ignored.map(|e| e.mm)).collect());
                let reference = if with_reference {
                    mean(frames.iter().filter_map(|f| f.reference.map(|e| e.mm)).collect())
                } else {
                    "skipped".into()
                };
                format!("{ours} / {ignored} / {reference} ({})", frames.len())
            })
            .collect();
        let _ = writeln!(
            md,
            "| {:.1} ms | {:.1} ms | {} | {} |",
            s.exposure_s * 1000.0,
            s.readout_s * 1000.0,
            s.orientation,
            cells.join(" | ")
        );
    }
    md
}

/// One line per scene for the terminal: ours told the readout against ours told nothing.
pub fn summary(chews: &[ChewScene]) -> Vec<String> {
    chews
        .iter()
        .map(|ChewScene { shutter: s, frames }| {
            let mm = |pick: fn(&ChewFrame) -> Option<PoseError>| {
                cell(&frames.iter().filter_map(pick).collect::<Vec<_>>(), |e| e.mm, 3)
            };
            format!(
                "chew, {:.1} ms exposure, {:.1} ms readout, phone {}: mean / p95 / max {} mm (shutter ignored: {} mm)",
                s.exposure_s * 1e3,
                s.readout_s * 1e3,
                s.orientation,
                mm(|f| f.ours),
                mm(|f| f.ignored),
            )
        })
        .collect()
}

/// One plot per scene of the position error against the incisor's speed, each stack a set of
/// dots, saved as `chew_<exposure>ms_<readout>ms_<orientation>.svg/.png` in `out`.
pub fn plots(chews: &[ChewScene], out: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for ChewScene { shutter: s, frames } in chews {
        let dots = |pick: fn(&ChewFrame) -> Option<PoseError>| -> Vec<(f64, f64)> {
            frames.iter().filter_map(|f| pick(f).map(|e| (f.speed_mm_s, e.mm))).collect()
        };
        let series = [
            ("ours", "#1f77b4", dots(|f| f.ours)),
            ("ours, shutter ignored", "#ff7f0e", dots(|f| f.ignored)),
            ("reference (C + OpenCV)", "#2ca02c", dots(|f| f.reference)),
        ];
        let series: Vec<Series<'_>> = series
            .into_iter()
            .filter(|(_, _, points)| !points.is_empty())
            .map(|(name, color, points)| Series { name, color, style: Style::Dots, points })
            .collect();
        let (exposure_ms, readout_ms) = (s.exposure_s * 1e3, s.readout_s * 1e3);
        let title =
            format!("Chewing, {exposure_ms:.1} ms exposure, {readout_ms:.1} ms readout, phone {}", s.orientation);
        let doc = plot::chart(
            &title,
            "lower incisor speed (mm/s)",
            "mandible in maxilla, position error (mm)",
            &series,
            false,
        );
        let stem = format!("chew_{exposure_ms:.0}ms_{readout_ms:.0}ms_{}", s.orientation);
        files.extend(plot::save_svg_and_png(&doc, &out.join(stem))?);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_mean_nearest_rank_95th_and_max() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(spread(v), Some((50.5, 95.0, 100.0)));
        assert_eq!(spread(vec![2.0]), Some((2.0, 2.0, 2.0)));
        assert_eq!(spread(Vec::new()), None);
    }

    fn scene() -> ChewScene {
        let e = |mm| Some(PoseError { mm, deg: mm });
        let frame =
            |speed_mm_s, ours, ignored| ChewFrame { speed_mm_s, ours: e(ours), ignored: e(ignored), reference: None };
        ChewScene {
            shutter: Shutter { exposure_s: 0.002, readout_s: 0.005, orientation: "upright" },
            frames: vec![frame(10.0, 0.01, 0.02), frame(90.0, 0.03, 0.3), frame(130.0, 0.02, 0.5)],
        }
    }

    #[test]
    fn the_tables_and_plots_say_what_each_stack_measured() {
        let md = markdown(&[scene()], false);
        assert!(md.contains("| 2.0 ms | 5.0 ms | upright | 3 | 130 mm/s | 0.020 / 0.030 / 0.030 |"), "{md}");
        assert!(
            md.contains("| 0.010 / 0.020 / skipped (1) | — / — / skipped (0) | 0.030 / 0.300 / skipped (1) |"),
            "{md}"
        );
        assert_eq!(markdown(&[], true), "");
        let line = &summary(&[scene()])[0];
        assert!(line.contains("0.020 / 0.030 / 0.030 mm (shutter ignored: 0.273 / 0.500 / 0.500 mm)"), "{line}");
        let dir = std::env::temp_dir().join(format!("chew-plots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let files = plots(&[scene()], &dir).expect("plots written");
        let names: Vec<String> = files.iter().filter_map(|f| Some(f.file_name()?.to_str()?.to_owned())).collect();
        assert_eq!(names, ["chew_2ms_5ms_upright.svg", "chew_2ms_5ms_upright.png"]);
        assert!(files.iter().all(|f| f.metadata().is_ok_and(|m| m.len() > 500)));
        std::fs::remove_dir_all(&dir).expect("cleaned up");
    }
}
