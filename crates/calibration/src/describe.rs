//! A calibration and a session refinement in words, as `jawtrack calibrate-marker` and
//! `jawtrack track --refine-marker` print them: per body the views and reprojection error,
//! what the assembly showed, each tag's correction, and the warnings to act on.

use crate::{Calibration, Finding, Kept, Refinement, TagCorrection};

/// What to print: the lines of the account, and the warnings (each naming what to film).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Account {
    /// The account, one line each.
    pub lines: Vec<String>,
    /// Warnings, one line each, without the "warning: " prefix.
    pub warnings: Vec<String>,
}

impl Calibration {
    /// What the calibration found and each tag's correction; a warning per tag left nominal.
    pub fn account(&self) -> Account {
        let mut a = Account::default();
        for b in &self.bodies {
            a.lines.push(format!(
                "{}: {} views; reprojection error {:.3} px with the marker given, {:.3} px calibrated",
                b.body, b.views, b.rms_before_px, b.rms_after_px
            ));
            for f in &b.findings {
                match f {
                    Finding::Uncalibrated { .. } => {
                        a.warnings.push(format!("{f} (turn the marker to show that face from a few angles)"))
                    }
                    _ => a.lines.push(format!("  assembly: {f}")),
                }
            }
            a.lines.push("  tag  views  shift x mm  shift y mm  turn °   px before  px after".into());
            a.lines.extend(b.tags.iter().map(|t| correction_row(t, "tag".len())));
        }
        a
    }
}

impl Refinement {
    /// What the refinement changed, per body: the tags placed, those kept and why, and how
    /// long it took (`seconds`); a warning per tag left nominal for want of viewpoints.
    pub fn account(&self, seconds: f64) -> Account {
        let mut a = Account::default();
        for b in &self.bodies {
            a.lines.push(format!(
                "{}: {} views of the session; reprojection error {:.3} px with the marker given, {:.3} px refined",
                b.body, b.views, b.rms_before_px, b.rms_after_px
            ));
            a.lines.extend(b.findings.iter().map(|f| format!("  assembly: {f}")));
            a.lines.push(if b.placed.is_empty() {
                "  no tag moved".into()
            } else {
                "  placed  views  shift x mm  shift y mm  turn °   px before  px after".into()
            });
            a.lines.extend(b.placed.iter().map(|t| correction_row(t, "placed".len())));
            let gauge = b.kept.iter().filter(|k| matches!(k, Kept::Calibrated { .. })).count();
            if gauge > 0 {
                a.lines.push(format!("  {gauge} tags calibrated before kept as they were"));
            }
            for k in &b.kept {
                match k {
                    Kept::NotBetter { .. } => a.lines.push(format!("  {k}")),
                    Kept::TooFewViewpoints { .. } => {
                        a.warnings.push(format!("{k} (it stays nominal: film that face from a few angles)"))
                    }
                    Kept::Calibrated { .. } => {}
                }
            }
        }
        a.lines.push(format!("refined the marker from the session in {seconds:.1} s"));
        a
    }
}

/// One row of a table of tag corrections, under a header whose first column is `id_width` wide.
fn correction_row(t: &TagCorrection, id_width: usize) -> String {
    format!(
        "  {:>id_width$}  {:5}  {:10.3}  {:10.3}  {:6.2}   {:9.3}  {:8.3}",
        t.id,
        t.views,
        t.placement.shift_x,
        t.placement.shift_y,
        t.placement.rotation.to_degrees(),
        t.rms_before_px,
        t.rms_after_px
    )
}
