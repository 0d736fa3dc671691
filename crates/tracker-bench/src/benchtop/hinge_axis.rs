//! The kinematic hinge axis fitted to each rendered opening of the hinge scene
//! (`jawtrack_kinematics::hinge`, what `jawtrack hinge-axis` runs), against the axis the renderer
//! turned the jaw about: the mounting's hinge axis. Two windows: early opening (the fit's
//! default, turns up to 12°, what a real jaw allows) and the whole opening (the renderer's jaw
//! turns about the axis to the end, so it shows what the full arc adds).
//!
//! Errors: the distance from the true axis's midpoint (between the condyles) to the fitted line,
//! the larger distance from the two true condyles to it, and the angle between the lines.

use super::Run;
use jawtrack_kinematics::{HingeOptions, Mounting, Side, hinge};
use jawtrack_pose::Pose;
use jawtrack_synth::SceneKind;
use jawtrack_synth::scenes::JawMotion;
use nalgebra::{Point3, Vector3};
use std::fmt::Write as _;

/// A turn wider than any opening: the window that takes the whole arc (°).
const WHOLE_DEG: f64 = 90.0;

/// One opening's fit by one column.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisRow {
    /// Incisal opening of the cycle (mm).
    pub opening_mm: f64,
    /// When the cycle started (s), with the jaw closed.
    pub start_s: f64,
    /// Whether the window took the whole opening rather than early opening.
    pub whole: bool,
    /// The errors, or why there is no fit.
    pub fit: Result<AxisError, String>,
}

/// How far a fitted axis is from the true one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisError {
    /// From the true midpoint between the condyles to the fitted line (mm).
    pub mid_mm: f64,
    /// The larger of the two condyles' distances to the fitted line (mm).
    pub condyles_mm: f64,
    /// Between the lines (°).
    pub deg: f64,
    /// The fit's own 1σ across the axis (mm).
    pub sigma_mm: f64,
    /// The fit's own 1σ of its direction (°).
    pub sigma_deg: f64,
    /// Poses used.
    pub poses: usize,
    /// The widest turn among them (°).
    pub widest_deg: f64,
}

/// The true axis in the maxilla marker's frame: the midpoint, the two condyles, the direction.
fn truth(m: &Mounting) -> (Point3<f64>, [Point3<f64>; 2], Vector3<f64>) {
    let maxilla_from_head = m.head_from_maxilla.inverse();
    let at = |p: Vector3<f64>| maxilla_from_head.transform_point(&Point3::from(p));
    let dir = maxilla_from_head.rotation() * Vector3::x();
    (at(m.hinge_point()), [at(m.condyle(Side::Left)), at(m.condyle(Side::Right))], dir)
}

/// Every hinge opening of `run`, fitted from `column`'s poses, in both windows.
pub fn axis_rows(run: &Run, column: usize) -> Vec<AxisRow> {
    let mounting = Mounting::default();
    let (mid, condyles, dir) = truth(&mounting);
    // Per cycle: its opening, its start, and the column's poses in time order.
    let mut cycles: Vec<(f64, f64, Vec<Option<Pose>>)> = Vec::new();
    for f in run.frames.iter().filter(|f| f.scene == SceneKind::Hinge) {
        let JawMotion::Hinge { opening_mm, start_s, .. } = f.motion else { continue };
        match cycles.iter_mut().find(|c| c.1 == start_s) {
            Some(c) => c.2.push(f.estimates[column]),
            None => cycles.push((opening_mm, start_s, vec![f.estimates[column]])),
        }
    }
    let mut rows = Vec::new();
    for (opening_mm, start_s, frames) in cycles {
        for whole in [false, true] {
            // The closed jaw: the cycle's first frame with a pose (the cycle starts closed; a
            // pose slightly open still turns about the same axis, only the window shifts).
            let poses: Vec<Pose> = frames.iter().flatten().copied().collect();
            let options = HingeOptions {
                max_rotation_deg: if whole { WHOLE_DEG } else { HingeOptions::default().max_rotation_deg },
                ..HingeOptions::default()
            };
            let closed = poses.first().copied().unwrap_or_else(Pose::identity);
            let fit = hinge::fit(&poses, &closed, None, &options).map_err(|e| e.to_string()).map(|axis| {
                let deg = axis.direction.angle(&dir).to_degrees();
                AxisError {
                    mid_mm: axis.distance_to(&mid),
                    condyles_mm: condyles.iter().map(|c| axis.distance_to(c)).fold(0.0, f64::max),
                    deg: deg.min(180.0 - deg),
                    sigma_mm: axis.point_sigma_mm,
                    sigma_deg: axis.direction_sigma_deg,
                    poses: axis.poses,
                    widest_deg: axis.max_rotation_deg,
                }
            });
            rows.push(AxisRow { opening_mm, start_s, whole, fit });
        }
    }
    rows
}

/// The report's section: one table per column.
pub fn markdown(run: &Run, columns: &[usize]) -> String {
    let mut md = String::from(
        "\n## Hinge axis\n\nThe kinematic hinge axis fitted to each opening (`jawtrack hinge-axis`, \
         `jawtrack_kinematics::hinge`) against the axis the renderer turned the jaw about. *Early*: the \
         fit's default window, turns up to 12° from the closed jaw; *whole*: the whole arc. Errors: from \
         the true midpoint between the condyles to the fitted line, the worse condyle, the angle between \
         the lines; the fit's own 1σ beside them.\n",
    );
    for &c in columns {
        let _ = writeln!(md, "\n### {}\n", run.columns[c].name());
        let _ = writeln!(
            md,
            "| opening | window | poses (widest turn) | midpoint mm | condyles mm | direction ° | 1σ mm / ° |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|");
        for r in axis_rows(run, c) {
            let window = if r.whole { "whole" } else { "early" };
            let cells = match &r.fit {
                Ok(e) => format!(
                    "{} ({:.1}°) | {:.3} | {:.3} | {:.3} | {:.3} / {:.3}",
                    e.poses, e.widest_deg, e.mid_mm, e.condyles_mm, e.deg, e.sigma_mm, e.sigma_deg
                ),
                Err(why) => format!("no fit: {} | | | | ", why.replace('|', "/")),
            };
            let _ = writeln!(md, "| {:.0} mm at {:.0} s | {window} | {cells} |", r.opening_mm, r.start_s);
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::benchtop::{Column, FrameRecord, MarkerFile, Stack};
    use jawtrack_synth::scenes::{Rig, SceneOptions, scene_frames};

    /// A run of the hinge scene whose one column reports the truth, every third frame lost.
    fn exact_run() -> Run {
        let rig = Rig::default();
        let opts = SceneOptions { cycles: 1, fps: 10.0, ..SceneOptions::default() };
        let frames = scene_frames(SceneKind::Hinge, &opts, 1)
            .into_iter()
            .enumerate()
            .map(|(index, spec)| {
                let (maxilla, mandible) = rig.markers(&spec.motion, spec.t);
                let truth = maxilla.inverse() * mandible;
                let lost = index % 3 == 2;
                FrameRecord {
                    scene: SceneKind::Hinge,
                    index,
                    t: spec.t,
                    view: spec.view,
                    motion: spec.motion,
                    truth,
                    estimates: vec![(!lost).then_some(truth)],
                }
            })
            .collect();
        Run::judged(vec![Column { stack: Stack::Ours, marker: MarkerFile::Printed }], Err("not run".into()), frames)
    }

    #[test]
    fn exact_poses_give_the_renderer_s_axis_for_every_opening() {
        let run = exact_run();
        let rows = axis_rows(&run, 0);
        assert_eq!(rows.len(), 8, "four openings, two windows");
        for r in &rows {
            let e = r.fit.as_ref().unwrap_or_else(|why| panic!("{r:?}: {why}"));
            assert!(e.mid_mm < 1e-6 && e.condyles_mm < 1e-6 && e.deg < 1e-6, "{r:?}");
            assert!(e.widest_deg <= if r.whole { WHOLE_DEG } else { 12.0 + 1e-9 });
        }
        // The 40 mm opening turns past 12°: the whole arc takes more poses than early opening.
        let forty: Vec<&AxisRow> = rows.iter().filter(|r| r.opening_mm == 40.0).collect();
        let poses = |w: bool| forty.iter().find(|r| r.whole == w).and_then(|r| r.fit.as_ref().ok()).map(|e| e.poses);
        assert!(poses(true) > poses(false), "{forty:?}");
        let md = markdown(&run, &[0]);
        assert!(md.contains("## Hinge axis") && md.contains("| 40 mm at 6 s | whole |"), "{md}");
    }

    #[test]
    fn an_opening_without_poses_says_why_it_has_no_fit() {
        let mut run = exact_run();
        for f in run.frames.iter_mut().filter(|f| f.t < 2.0) {
            f.estimates[0] = None;
        }
        let rows = axis_rows(&run, 0);
        for r in rows.iter().filter(|r| r.start_s == 0.0) {
            assert!(r.fit.as_ref().is_err_and(|why| why.contains("0 poses")), "{r:?}");
        }
        assert!(rows.iter().filter(|r| r.start_s > 0.0).all(|r| r.fit.is_ok()));
        assert!(markdown(&run, &[0]).contains("| 10 mm at 0 s | early | no fit: the hinge axis needs an opening"));
    }
}
