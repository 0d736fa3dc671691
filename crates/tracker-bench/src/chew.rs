//! The chewing scene under each exposure and rolling shutter asked for: the jaw's error with
//! our tracker told the readout, ours with the readout ignored, and the reference stack (which
//! knows nothing of shutters), as mean, 95th percentile and max, overall and by incisor speed.

use crate::report::{PoseError, SceneOutcome};
use std::fmt::Write as _;

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

/// The marker file the chew table is read with: the marker as printed (the targets are
/// for a calibrated or exact marker).
const PRINTED: usize = 1;

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

/// The chewing section of the report (empty when no chew scene ran).
pub fn markdown(outcomes: &[(SceneOutcome, Option<Shutter>)], with_reference: bool) -> String {
    let chews: Vec<_> = outcomes.iter().filter_map(|(o, s)| s.map(|s| (o, s))).collect();
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
    for (o, s) in &chews {
        let ours: Vec<PoseError> = o.frames.iter().filter_map(|f| f.error[PRINTED][0]).collect();
        let ignored: Vec<PoseError> = o.frames.iter().filter_map(|f| f.ignored).collect();
        let reference: Vec<PoseError> = o.frames.iter().filter_map(|f| f.error[PRINTED][1]).collect();
        let peak = o.frames.iter().map(|f| f.speed_mm_s).fold(0.0, f64::max);
        let refcell = |pick, d| if with_reference { cell(&reference, pick, d) } else { "skipped".into() };
        let _ = writeln!(
            md,
            "| {:.1} ms | {:.1} ms | {} | {} | {peak:.0} mm/s | {} | {} | {} | {} | {} | {} |",
            s.exposure_s * 1000.0,
            s.readout_s * 1000.0,
            s.orientation,
            o.frames.len(),
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
    for (o, s) in &chews {
        let cells: Vec<String> = SPEED_BINS
            .iter()
            .enumerate()
            .map(|(i, lo)| {
                let hi = SPEED_BINS.get(i + 1).copied().unwrap_or(f64::INFINITY);
                let frames: Vec<_> = o.frames.iter().filter(|f| (*lo..hi).contains(&f.speed_mm_s)).collect();
                let mean = |v: Vec<f64>| {
                    if v.is_empty() {
                        "—".to_string()
                    } else {
                        format!("{:.3}", v.iter().sum::<f64>() / v.len() as f64)
                    }
                };
                let ours = mean(frames.iter().filter_map(|f| f.error[PRINTED][0].map(|e| e.mm)).collect());
                let ignored = mean(frames.iter().filter_map(|f| f.ignored.map(|e| e.mm)).collect());
                let reference = if with_reference {
                    mean(frames.iter().filter_map(|f| f.error[PRINTED][1].map(|e| e.mm)).collect())
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
}
