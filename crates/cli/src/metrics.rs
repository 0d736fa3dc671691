//! `jawtrack metrics`: the clinical numbers of a recording's lower-incisor motion
//! (`jawtrack_kinematics::Metrics`: widest opening, lateral excursions, protrusion and
//! retrusion (with the teeth near contact), each with its frame, Posselt's border as traced in
//! three planes, and the convex hulls), printed, as JSON, or with the borders and hulls plotted
//! and `metrics.json` written.
//!
//! The recording is read as `export` and `plot` read it (sequence order, displacements from the
//! rest position); frames without a jaw pose are skipped and counted.

use crate::flags::{SessionArg, load};
use crate::numbers::fixed;
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_kinematics::metrics::RETRUSION_OPENING_MM;
use jawtrack_kinematics::{Border, Incisor, Metrics, PlaneView, Sample};
use jawtrack_plot as plot;
use jawtrack_session::measures::metrics_json;
use jawtrack_session::{Rest, rest_of};
use nalgebra::Point3;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack metrics`.
#[derive(Args)]
pub(crate) struct MetricsArgs {
    /// The recording (JSON lines).
    recording: PathBuf,
    #[command(flatten)]
    session: SessionArg,
    /// The incisal point X,Y,Z in the mandible marker's frame (mm); default: the standard
    /// harness mounting's.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    incisor: Option<Point3<f64>>,
    /// The frame (its `frame` number) whose jaw pose is the rest position; default: the bite
    /// accepted while recording (a `bite` line), else the first frame with a jaw pose.
    #[arg(long)]
    rest_frame: Option<u64>,
    /// Output folder for the envelope plots (SVG and PNG) and metrics.json.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// Print one JSON object (the content of metrics.json) instead of the summary.
    #[arg(long)]
    json: bool,
}

/// Parses `X,Y,Z` (mm) into a point.
fn parse_point(s: &str) -> Result<Point3<f64>, String> {
    let v: Vec<f64> =
        s.split(',').map(|c| c.trim().parse::<f64>().map_err(|e| format!("'{c}': {e}"))).collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Point3::new(x, y, z)),
        [_, _, _] => Err("the coordinates must be finite".into()),
        _ => Err(format!("expected X,Y,Z (three numbers in mm), got {} numbers", v.len())),
    }
}

/// Runs `jawtrack metrics`.
pub(crate) fn run(a: &MetricsArgs) -> Result<()> {
    let name = a.recording.display();
    if let Some(out) = &a.out {
        a.force.check_folder(out, &["metrics.json"])?;
    }
    let rec = load(&a.recording, a.session)?;
    let Some(rest_at) = rest_of(&rec, a.rest_frame)? else {
        bail!("{name}: no frame has a jaw pose (both markers tracked), nothing to measure");
    };
    let rest = rest_at.pose();
    let incisor = a.incisor.map_or_else(Incisor::standard, Incisor::at);
    let path: Vec<Sample> = rec
        .frames
        .iter()
        .filter_map(|f| f.maxilla_from_mandible.map(|m| (f.t, f.frame, incisor.displacement(&m, &rest))))
        .collect();
    let skipped = rec.frames.len() - path.len();
    let metrics = Metrics::compute(&path).context("no frame has a jaw pose")?;
    let report = metrics_json(&metrics, &path, &rec, &a.recording, rest_at, &incisor, a.incisor.is_none());
    if skipped > 0 {
        eprintln!("{name}: {skipped} of {} frames have no jaw pose, skipped", rec.frames.len());
    }
    if let Some(out) = &a.out {
        write_outputs(out, &path, &metrics, &report)?;
    }
    if a.json {
        say!("{report}");
    } else {
        print_summary(&metrics, skipped, rest_at, &incisor, a.incisor.is_none());
        for view in PlaneView::ALL {
            let b = Border::of(view, &path, &metrics);
            say!(
                "{:<19} {:>7} mm²  (traced; {} outline points)",
                format!("{} border", view.name()),
                fixed(b.area_mm2, 2),
                b.outline.len()
            );
        }
    }
    Ok(())
}

fn print_summary(m: &Metrics, skipped: usize, rest: Rest, incisor: &Incisor, standard: bool) {
    let p = incisor.point_in_mandible_marker();
    say!(
        "frames              {} with a jaw pose, {skipped} skipped (no jaw pose); rest: {}",
        m.frames,
        rest.describe()
    );
    let mm = |v: f64| fixed(v, 2);
    say!(
        "incisal point       ({}, {}, {}) mm in the mandible marker's frame{}",
        mm(p.x),
        mm(p.y),
        mm(p.z),
        if standard { " (standard mounting)" } else { "" }
    );
    for (label, e) in [
        ("max opening", m.max_opening),
        ("max left lateral", m.max_left),
        ("max right lateral", m.max_right),
        ("max protrusion", m.max_protrusion),
    ] {
        say!("{label:<19} {:>7} mm   (frame {}, t {} s)", mm(e.mm), e.frame, fixed(e.t, 3));
    }
    let near = fixed(RETRUSION_OPENING_MM, 0);
    match m.max_retrusion {
        Some(e) => say!(
            "max retrusion       {:>7} mm   (frame {}, t {} s; opened at most {near} mm)",
            mm(e.mm),
            e.frame,
            fixed(e.t, 3)
        ),
        None => say!("max retrusion          none   (no frame opened {near} mm or less)"),
    }
    for (label, e) in [("sagittal hull", &m.sagittal), ("frontal hull", &m.frontal)] {
        say!("{label:<19} {:>7} mm²  (convex hull; {} vertices)", mm(e.area_mm2), e.hull.len());
    }
}

/// Writes the two envelope plots (path and hull outline) and metrics.json into `out`.
fn write_outputs(out: &Path, path: &[Sample], m: &Metrics, report: &Value) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    for (view, envelope) in [(PlaneView::Sagittal, &m.sagittal), (PlaneView::Frontal, &m.frontal)] {
        let doc = jawtrack_report::envelope_chart(view, envelope, path);
        for p in plot::save_svg_and_png(&doc, &out.join(format!("envelope_{}", view.name())))? {
            eprintln!("wrote {}", p.display());
        }
    }
    // Posselt's border as traced, in all three planes.
    for view in PlaneView::ALL {
        let doc = jawtrack_report::border_chart(&Border::of(view, path, m), path);
        for p in plot::save_svg_and_png(&doc, &out.join(format!("border_{}", view.name())))? {
            eprintln!("wrote {}", p.display());
        }
    }
    let json_path = out.join("metrics.json");
    let text = serde_json::to_string_pretty(report).context("metrics as JSON")?;
    // The folder was checked for an earlier metrics.json (--force) before any work.
    let replace = jawtrack_recording::Overwrite::Replace;
    jawtrack_recording::write_file_atomic(&json_path, (text + "\n").as_bytes(), replace)?;
    eprintln!("wrote {}", json_path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incisor_points_parse_and_bad_ones_say_why() {
        assert_eq!(parse_point("1,-2.5, 3"), Ok(Point3::new(1.0, -2.5, 3.0)));
        assert!(parse_point("1,2").is_err_and(|e| e.contains("three numbers")));
        assert!(parse_point("1,x,3").is_err_and(|e| e.contains("'x'")));
        assert!(parse_point("1,inf,3").is_err_and(|e| e.contains("finite")));
    }
}
