//! `jawtrack metrics`: the clinical numbers of a recording's lower-incisor motion
//! (`jawtrack_kinematics::Metrics`: widest opening, lateral excursions, protrusion and
//! retrusion (with the teeth near contact), each with its frame, Posselt's border as traced in
//! three planes, and the convex hulls), printed, as JSON, or with the borders and hulls plotted
//! and `metrics.json` written.
//!
//! The recording is read as `export` and `plot` read it (sequence order, displacements from the
//! rest position); frames without a jaw pose are skipped and counted.

use crate::flags::{SessionArg, load};
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_kinematics::{Metrics, Sample};
use jawtrack_plot as plot;
use jawtrack_session::measures::metrics_json;
use jawtrack_session::rest_of;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack metrics`.
#[derive(Args)]
pub(crate) struct MetricsArgs {
    /// The recording (JSON lines).
    recording: PathBuf,
    #[command(flatten)]
    session: SessionArg,
    #[command(flatten)]
    incisor: crate::flags::IncisorArgs,
    /// The frame (its `frame` number) whose jaw pose is the rest position; default: the bite
    /// accepted while recording (a `bite` line), else the first frame with a jaw pose.
    #[arg(long, value_name = "FRAME", value_parser = crate::numbers::parse_frame, allow_hyphen_values = true)]
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
    let chosen = a.incisor.choose(&rest)?;
    let (incisor, standard) = (chosen.incisor, chosen.standard);
    let path = jawtrack_session::incisor::path(&rec.frames, &incisor, &rest);
    let skipped = rec.frames.len() - path.len();
    let metrics = Metrics::compute(&path).context("no frame has a jaw pose")?;
    let report = metrics_json(&metrics, &path, &rec, &a.recording, rest_at, &incisor, standard);
    if skipped > 0 {
        tell!("{name}: {skipped} of {} frames have no jaw pose, skipped", rec.frames.len());
    }
    if let Some(out) = &a.out {
        write_outputs(out, &path, &metrics, &report)?;
    }
    if a.json {
        say!("{report}");
    } else {
        for line in jawtrack_report::metrics_summary(&metrics, &path, skipped, &rest_at.describe(), &incisor, standard)
        {
            say!("{line}");
        }
    }
    Ok(())
}

/// Writes the envelope and border plots and metrics.json into `out`.
fn write_outputs(out: &Path, path: &[Sample], m: &Metrics, report: &Value) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    for (stem, doc) in jawtrack_report::metrics_figures(path, m) {
        for p in plot::save_svg_and_png(&doc, &out.join(stem))? {
            tell!("wrote {}", p.display());
        }
    }
    let json_path = out.join("metrics.json");
    let text = serde_json::to_string_pretty(report).context("metrics as JSON")?;
    // The folder was checked for an earlier metrics.json (--force) before any work.
    let replace = jawtrack_recording::Overwrite::Replace;
    jawtrack_recording::write_file_atomic(&json_path, (text + "\n").as_bytes(), replace)?;
    tell!("wrote {}", json_path.display());
    Ok(())
}
