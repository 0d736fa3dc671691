//! Printing several commands share: a calibration's and a session refinement's findings, the
//! warning about wrong intrinsics, a rendered scene's summary.

use jawtrack_calibration::{Account, Calibration, FocalCheck, Refinement};
use jawtrack_offline::intrinsics_warning;
use jawtrack_synth::{SceneKind, SceneSummary};
use std::path::Path;

/// Prints what the calibration found and each tag's correction, then the warnings.
pub(crate) fn print_report(cal: &Calibration) {
    print_account(&cal.account(), false);
    warn_focal(cal.focal, cal.bodies.iter().map(|b| b.rms_after_px));
}

/// Says what a session refinement changed, per body; on standard output, or on standard error
/// when standard output carries the recording.
pub(crate) fn print_refinement(r: &Refinement, seconds: f64, to_stderr: bool) {
    print_account(&r.account(seconds), to_stderr);
    warn_focal(r.focal, r.bodies.iter().map(|b| b.rms_after_px));
}

fn print_account(a: &Account, to_stderr: bool) {
    for l in &a.lines {
        if to_stderr {
            tell!("{l}");
        } else {
            say!("{l}");
        }
    }
    a.warnings.iter().for_each(|w| tell!("warning: {w}"));
}

/// Warns when the views say the camera's focal length is not the one given.
fn warn_focal(focal: Option<FocalCheck>, rms_px: impl Iterator<Item = f64>) {
    if let Some(focal) = focal.filter(FocalCheck::looks_wrong) {
        tell!("warning: {}", intrinsics_warning(&focal, rms_px));
    }
}

/// Says what a rendered scene holds.
pub(crate) fn print_scene_summary(scene: SceneKind, out: &Path, s: &SceneSummary) {
    say!("{}", s.describe(scene, out));
}
