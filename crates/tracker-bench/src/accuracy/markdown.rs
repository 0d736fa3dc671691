//! `report.md` of the benchtop accuracy run, section by section: the setup, the verdict
//! against the targets, the calibration and bite step, the static, hinge and excursion tables,
//! flips, and the plots and tables written beside it.

use super::{
    AXES, DYNAMIC_SE_MM, STATIC_DEG, STATIC_MM, column, fmt_ms, fmt_regression, main_columns, met, mount, verdict,
};
use crate::benchtop::{self, FLIP_DEG, MarkerFile, MeanSd, Options, Run, Stack, StaticRow};
use jawtrack_synth::{Realism, SceneKind};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The report a clinician reads (`report.md`); `files` are the plots and tables written in
/// `out`, linked from it.
pub(super) fn report(run: &Run, o: &Options, files: &[PathBuf], out: &Path) -> String {
    let mut md = String::new();
    intro(&mut md, run, o);
    targets(&mut md, run);
    calibration(&mut md, run);
    static_tables(&mut md, run);
    static_overview(&mut md, run);
    dynamic_tables(&mut md, run);
    md.push_str(&benchtop::hinge_axis::markdown(run, &main_columns(run)));
    md.push_str(&benchtop::session_report(run));
    flips(&mut md, run);
    plots_and_reproduce(&mut md, run, o, files, out);
    md
}

/// The title, what was rendered and how, the reference stack (or why it was skipped), and
/// how errors are measured.
fn intro(md: &mut String, run: &Run, o: &Options) {
    let realism = Realism::default();
    let count = |k: SceneKind| run.frames.iter().filter(|f| f.scene == k).count();
    let _ = writeln!(md, "# JawTrack benchtop accuracy: the thesis's experiments, rendered\n");
    let _ = writeln!(
        md,
        "Rendered frames with exact ground truth (seed {}, 1080p, the default realism: sensor noise, defocus and motion blur, sRGB, a print error of {} mm / {}° per tag). \
         The marker was calibrated from a separate recording of the same printed marker ({} frames from 18 angles), never from the frames judged here: \
         static grid {} frames ({} per view), hinge {} frames ({} rounds of 10/20/30/40 mm at {} frames/s), excursions {} frames ({} glides per direction).\n",
        o.seed,
        realism.print_error_mm,
        realism.print_error_deg,
        run.calibration_frames,
        count(SceneKind::Static),
        o.frames_per_view,
        count(SceneKind::Hinge),
        o.hinge_cycles,
        o.fps,
        count(SceneKind::Excursion),
        o.excursion_cycles,
    );
    match &run.reference {
        Ok(r) => {
            let _ = writeln!(md, "Reference stack, on the same frames with the same marker files: {r}.\n");
        }
        Err(why) => {
            let _ = writeln!(md, "**The reference stack was skipped**: {why}. Only our columns are shown.\n");
        }
    }
    let _ = writeln!(
        md,
        "Errors are those of the mandible marker's pose in the maxilla marker's frame, along the head's axes: X toward the patient's left, Y down, Z back. \
         Orientation errors are the error rotation's components about those axes. \
         (The thesis gave Z-Y-Z Euler angle errors, but these are singular at rest, where the two markers are parallel. To first order, the components equal Euler-angle errors about the same axes.) \
         The hinge and excursion tables regress the tracked lower-incisor displacement on the true one, axis by axis, and give r² and the standard error of the estimate in mm.\n"
    );
}

/// Every column's worst view and scene, then each calibrated column of ours against the targets.
fn targets(md: &mut String, run: &Run) {
    let _ = writeln!(md, "## Against the targets\n");
    let _ = writeln!(
        md,
        "| column | static: worst view, mean position error | static: worst view, mean orientation error | views without a pose | hinge and excursions: worst SE | frames > {FLIP_DEG}° | frames without a pose |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    for (c, col) in run.columns.iter().enumerate() {
        let v = verdict(run, c);
        let _ = writeln!(
            md,
            "| {} | {:.3} mm ({}) | {:.3}° ({}) | {} | {:.3} mm ({}) | {} (worst {:.2}°) | {} |",
            col.name(),
            v.static_mm.0,
            v.static_mm.1,
            v.static_deg.0,
            v.static_deg.1,
            v.static_lost,
            v.dynamic_se.0,
            v.dynamic_se.1,
            v.flips.0,
            v.flips.1,
            v.lost
        );
    }
    for c in
        [MarkerFile::Calibrated, MarkerFile::CalibratedBite].into_iter().filter_map(|m| column(run, Stack::Ours, m))
    {
        let v = verdict(run, c);
        let _ = writeln!(md, "\n{}:\n", run.columns[c].name());
        let _ = writeln!(
            md,
            "- Static, mean position error ≤ {STATIC_MM} mm and orientation error ≤ {STATIC_DEG}° at every view, tripod and hand: {} (worst {:.3} mm, {:.3}°{}).",
            met(v.static_mm.0 <= STATIC_MM && v.static_deg.0 <= STATIC_DEG && v.static_lost == 0),
            v.static_mm.0,
            v.static_deg.0,
            if v.static_lost > 0 { format!("; {} views without a pose", v.static_lost) } else { String::new() }
        );
        let _ = writeln!(
            md,
            "- Dynamic, standard error ≤ {DYNAMIC_SE_MM} mm at every opening and glide: {} (worst {:.3} mm, {}).",
            met(v.dynamic_se.0 <= DYNAMIC_SE_MM),
            v.dynamic_se.0,
            v.dynamic_se.1
        );
        let _ = writeln!(
            md,
            "- No flips, no frame more than {FLIP_DEG}° off in any scene: {} ({} frames; worst {:.2}°).\n",
            met(v.flips.0 == 0),
            v.flips.0,
            v.flips.1
        );
    }
}

/// Each body's calibration, and each stack's bite step.
fn calibration(md: &mut String, run: &Run) {
    let _ = writeln!(md, "## Calibration\n");
    for b in &run.calibration {
        let _ = writeln!(
            md,
            "- {}: {} views, {} tags placed; reprojection error {:.2} px with the nominal marker, {:.2} px calibrated.{}",
            b.body,
            b.views,
            b.calibrated_tags,
            b.rms_before_px,
            b.rms_after_px,
            if b.findings.is_empty() { String::new() } else { format!(" {}.", b.findings.join("; ")) }
        );
    }

    let _ = writeln!(
        md,
        "\nThe calibration places the tags relative to each other. Where they sit, as a whole, on the printed solid is set only by a weak pull toward the nominal places. That leaves each body a small rigid offset, about the print error over the square root of the tags seen. \
         In the clinic, this offset is removed by the maximal-intercuspation (bite) step: the patient bites, and the mean of the tracked closed-jaw poses is mapped onto the scanned bite. \
         Here, the jaw is closed in the calibration recording, so each stack takes that step from its own poses of that recording:\n"
    );
    // A skipped reference stack took no step: "no closed-jaw pose" would misread as a failure.
    let stacks_run = if run.reference.is_ok() { 2 } else { 1 };
    for (stack, b) in ["ours", "reference"].iter().zip(&run.bite_steps).take(stacks_run) {
        match b {
            Some(b) => {
                let _ = writeln!(
                    md,
                    "- {stack}: {} closed-jaw frames (spread {:.3} mm); the correction moved the mandible {:.3} mm and turned it {:.3}°.",
                    b.samples, b.spread_mm, b.translation_mm, b.rotation_deg
                );
            }
            None => {
                let _ = writeln!(md, "- {stack}: no closed-jaw pose, so no bite step.");
            }
        }
    }
}

/// The static grid, per view, for each main column.
fn static_tables(md: &mut String, run: &Run) {
    let _ = writeln!(md, "\n## Static grid\n");
    for c in main_columns(run) {
        let _ = writeln!(md, "### {}\n", run.columns[c].name());
        let _ = writeln!(
            md,
            "| mount | angle | distance | poses | {} | {} | {} | about {} | about {} | about {} | position | orientation |",
            AXES[0], AXES[1], AXES[2], AXES[0], AXES[1], AXES[2]
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|");
        for row in benchtop::static_rows(run, c) {
            let _ = writeln!(
                md,
                "| {} | {:.0}° | {:.0} mm | {}/{} | {} | {} | {} | {} | {} | {} | {} mm | {}° |",
                mount(&row),
                row.azimuth_deg,
                row.distance_mm,
                row.errors.len(),
                row.frames,
                fmt_ms(row.position(0), 3),
                fmt_ms(row.position(1), 3),
                fmt_ms(row.position(2), 3),
                fmt_ms(row.rotation(0), 3),
                fmt_ms(row.rotation(1), 3),
                fmt_ms(row.rotation(2), 3),
                fmt_ms(row.mm(), 3),
                fmt_ms(row.deg(), 3),
            );
        }
        let _ = writeln!(md, "\nMean ± SD over the view's frames; position and angle errors in mm and °.\n");
    }
}

/// Every column's mean position and orientation error per view, side by side.
fn static_overview(md: &mut String, run: &Run) {
    let _ = writeln!(md, "### Every column: mean position / orientation error per view\n");
    let mut header = "| mount | angle | distance |".to_owned();
    for col in &run.columns {
        let _ = write!(header, " {} |", col.name());
    }
    let _ = writeln!(md, "{header}\n|---|---|---|{}", "---|".repeat(run.columns.len()));
    let tables: Vec<Vec<StaticRow>> = (0..run.columns.len()).map(|c| benchtop::static_rows(run, c)).collect();
    for (i, row) in tables[0].iter().enumerate() {
        let mut line = format!("| {} | {:.0}° | {:.0} mm |", mount(row), row.azimuth_deg, row.distance_mm);
        for t in &tables {
            let cell = match (t[i].mm(), t[i].deg()) {
                (Some(mm), Some(deg)) => format!(" {:.3} mm / {:.3}° |", mm.mean, deg.mean),
                _ => " no pose |".into(),
            };
            line.push_str(&cell);
        }
        let _ = writeln!(md, "{line}");
    }
}

/// The hinge and excursion regressions, per opening or glide, for each main column.
fn dynamic_tables(md: &mut String, run: &Run) {
    for (scene, title, what) in [(SceneKind::Hinge, "Hinge", "opening"), (SceneKind::Excursion, "Excursions", "glide")]
    {
        let _ = writeln!(md, "\n## {title}: the tracked lower incisor regressed on the truth\n");
        for c in main_columns(run) {
            let _ = writeln!(md, "### {}\n", run.columns[c].name());
            let _ = writeln!(
                md,
                "| {what} | poses | {} r² / SE mm | {} r² / SE mm | {} r² / SE mm | incisor error mm | orientation error ° |",
                AXES[0], AXES[1], AXES[2]
            );
            let _ = writeln!(md, "|---|---|---|---|---|---|---|");
            for row in benchtop::dynamic_rows(run, scene, c) {
                let _ = writeln!(
                    md,
                    "| {} | {}/{} | {} | {} | {} | {} | {} |",
                    row.label,
                    row.errors.len(),
                    row.frames,
                    fmt_regression(row.regression(0)),
                    fmt_regression(row.regression(1)),
                    fmt_regression(row.regression(2)),
                    fmt_ms(row.incisor_mm(), 3),
                    fmt_ms(MeanSd::of(row.errors.iter().map(benchtop::ErrorParts::deg)), 3),
                );
            }
            let _ = writeln!(md);
        }
        let _ = writeln!(
            md,
            "\"still\": the truth does not move along that axis; the SE is then the tracked values' SD.\n"
        );
    }
}

/// Each column's flips, per scene.
fn flips(md: &mut String, run: &Run) {
    let _ = writeln!(md, "## Flips (frames more than {FLIP_DEG}° off)\n");
    let _ = writeln!(md, "| column | static | hinge | excursion |\n|---|---|---|---|");
    for (c, col) in run.columns.iter().enumerate() {
        let cells: Vec<String> = [SceneKind::Static, SceneKind::Hinge, SceneKind::Excursion]
            .map(|s| {
                let f = benchtop::flips(run, s, c);
                format!("{} of {} posed ({} frames), worst {:.2}°", f.flips, f.posed, f.frames, f.worst_deg)
            })
            .to_vec();
        let _ = writeln!(md, "| {} | {} |", col.name(), cells.join(" | "));
    }
}

/// Links to the plots and tables in `out`, and the command that reproduces the run.
fn plots_and_reproduce(md: &mut String, run: &Run, o: &Options, files: &[PathBuf], out: &Path) {
    let _ = writeln!(md, "\n## Plots and tables\n");
    for f in files {
        let name = f.strip_prefix(out).unwrap_or(f).display().to_string();
        if name.ends_with(".png") {
            let _ = writeln!(md, "![{name}]({name})\n");
        } else if name.ends_with(".csv") {
            let _ = writeln!(md, "- [{name}]({name})");
        }
    }
    // The reference columns come only from the binary that links the C library.
    let command = if run.reference.is_ok() {
        "cargo run --release -p jawtrack-tracker-bench --bin bench-accuracy --"
    } else {
        "jawtrack-bench accuracy"
    };
    let _ = writeln!(
        md,
        "\nReproduce: `{command} --seed {} --frames-per-view {} --hinge-cycles {} --excursion-cycles {} --fps {}`.",
        o.seed, o.frames_per_view, o.hinge_cycles, o.excursion_cycles, o.fps
    );
}
