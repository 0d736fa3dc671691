//! Printing several commands share: a calibration's and a session refinement's findings, the
//! warning about wrong intrinsics, a rendered scene's summary.

use jawtrack_calibration::{Calibration, Finding, FocalCheck, Kept, Refinement, TagCorrection};
use jawtrack_offline::intrinsics_warning;
use jawtrack_synth::{SceneKind, SceneSummary};
use std::fmt::Write as _;
use std::path::Path;

/// Prints what the calibration found and each tag's correction; warns about tags left nominal.
pub(crate) fn print_report(cal: &Calibration) {
    for b in &cal.bodies {
        say!(
            "{}: {} views; reprojection error {:.3} px with the marker given, {:.3} px calibrated",
            b.body,
            b.views,
            b.rms_before_px,
            b.rms_after_px
        );
        for f in b.findings.iter().filter(|f| !matches!(f, Finding::Uncalibrated { .. })) {
            say!("  assembly: {f}");
        }
        say!("  tag  views  shift x mm  shift y mm  turn °   px before  px after");
        for t in &b.tags {
            say!("{}", correction_row(t, "tag".len()));
        }
        for f in b.findings.iter().filter(|f| matches!(f, Finding::Uncalibrated { .. })) {
            eprintln!("warning: {f} (turn the marker to show that face from a few angles)");
        }
    }
    if let Some(focal) = cal.focal.filter(FocalCheck::looks_wrong) {
        eprintln!("warning: {}", intrinsics_warning(&focal, cal.bodies.iter().map(|b| b.rms_after_px)));
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

/// Says what a session refinement changed, per body: the tags placed, those kept and why; on
/// standard output, or on standard error when standard output carries the recording.
pub(crate) fn print_refinement(r: &Refinement, seconds: f64, to_stderr: bool) {
    let mut text = String::new();
    for b in &r.bodies {
        let _ = writeln!(
            text,
            "{}: {} views of the session; reprojection error {:.3} px with the marker given, {:.3} px refined",
            b.body, b.views, b.rms_before_px, b.rms_after_px
        );
        for f in &b.findings {
            let _ = writeln!(text, "  assembly: {f}");
        }
        if b.placed.is_empty() {
            let _ = writeln!(text, "  no tag moved");
        } else {
            let _ = writeln!(text, "  placed  views  shift x mm  shift y mm  turn °   px before  px after");
        }
        for t in &b.placed {
            let _ = writeln!(text, "{}", correction_row(t, "placed".len()));
        }
        let gauge = b.kept.iter().filter(|k| matches!(k, Kept::Calibrated { .. })).count();
        if gauge > 0 {
            let _ = writeln!(text, "  {gauge} tags calibrated before kept as they were");
        }
        for k in b.kept.iter().filter(|k| matches!(k, Kept::NotBetter { .. })) {
            let _ = writeln!(text, "  {k}");
        }
    }
    let _ = write!(text, "refined the marker from the session in {seconds:.1} s");
    if to_stderr {
        eprintln!("{text}");
    } else {
        say!("{text}");
    }
    for k in r.bodies.iter().flat_map(|b| &b.kept).filter(|k| matches!(k, Kept::TooFewViewpoints { .. })) {
        eprintln!("warning: {k} (it stays nominal: film that face from a few angles)");
    }
    if let Some(focal) = r.focal.filter(FocalCheck::looks_wrong) {
        eprintln!("warning: {}", intrinsics_warning(&focal, r.bodies.iter().map(|b| b.rms_after_px)));
    }
}

/// Says what a rendered scene holds.
pub(crate) fn print_scene_summary(scene: SceneKind, out: &Path, s: &SceneSummary) {
    say!(
        "{} scene: {} frames in {} ({:.1} s, {:.2} s/frame)",
        scene.name(),
        s.frames,
        out.display(),
        s.seconds,
        s.seconds / s.frames.max(1) as f64
    );
    say!(
        "  tags a detector should find per frame: min {}, mean {:.1}, max {}; median tag side {:.0} px",
        s.detectable_tags.0,
        s.detectable_tags.1,
        s.detectable_tags.2,
        s.median_tag_side_px
    );
    say!("  mandible marker travel relative to the maxilla: up to {:.1} mm", s.max_mandible_travel_mm);
    say!("  ground truth: {}", out.join("ground_truth.json").display());
}
