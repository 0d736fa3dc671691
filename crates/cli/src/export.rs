//! `jawtrack export` and `jawtrack plot`: a recording (from `track`, `receive` or the phone)
//! turned into a time-ordered CSV or a clean JSON Lines file, and into plots of the lower
//! incisor's path in the sagittal, frontal and transverse planes.
//!
//! Frames received over the link are written in arrival order; both commands put them back in
//! sequence order. Displacements are measured from the rest position: `--rest-frame`'s jaw
//! pose, else the bite the intercuspation step accepted while recording, else the first frame
//! with a jaw pose.

use crate::flags::{SessionArg, load, registration};
use crate::numbers::fixed;
use anyhow::{Context, Result};
use clap::{ArgGroup, Args};
use jawtrack_kinematics::Metrics;
use jawtrack_plot as plot;
use jawtrack_session::export::{Format, Inputs};
use jawtrack_session::{rest::require_rest, rest_of};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `jawtrack export`.
#[derive(Args)]
#[command(group(ArgGroup::new("format").required(true).args(["csv", "jsonl", "transforms_csv", "transforms_json", "trc", "mot", "c3d"])))]
pub(crate) struct ExportArgs {
    /// The recording (JSON lines).
    recording: PathBuf,
    /// One row per frame: sequence, time, tags, RMS, the mandible in the maxilla (translation
    /// and quaternion), the incisor and its opening, lateral and protrusive displacement.
    #[arg(long)]
    csv: bool,
    /// The recording cleaned: a header line, then every readable frame in sequence order.
    #[arg(long)]
    jsonl: bool,
    /// For dental CAD: per frame, the lower scan in the upper scan's frame as a 4×4 row-major
    /// matrix (mm), one CSV row per frame with a jaw pose (`frame,t_s,m00,m01,…,m33`). Needs
    /// `--registration`, or a recording tracked with one.
    #[arg(long)]
    transforms_csv: bool,
    /// The same as one JSON object: `{"version":1,"units":"mm","transform":
    /// "maxilla_scan_from_mandible_scan","layout":"row-major 4x4","frames":[{"frame","t_s","matrix"}]}`.
    #[arg(long)]
    transforms_json: bool,
    /// For OpenSim: the lower incisal point's and both condyles' trajectories (mm), in OpenSim's
    /// axes (X anterior, Y up, Z right; origin the head frame's), the points the points file's
    /// (--points) or else the standard mounting's. Frames without a jaw pose have blank markers.
    #[arg(long)]
    trc: bool,
    /// For OpenSim: the jaw's coordinates over time from the rest position: body-fixed X–Y–Z
    /// angles (°) and the condylar midpoint's shift (m), in OpenSim's axes.
    #[arg(long)]
    mot: bool,
    /// For biomechanics tools (Visual3D, Mokka, ezc3d): the same three points as --trc, in the
    /// same axes (mm), as a C3D file at the recording's frame rate; a frame lost or without a
    /// jaw pose holds them as missing. Needs --out FILE.
    #[arg(long)]
    c3d: bool,
    /// The registration file (`jawtrack register`) the transforms are taken through; without
    /// it, the recording's own `maxilla_scan_from_mandible_scan` (tracked with a registration).
    #[arg(long)]
    registration: Option<PathBuf>,
    #[command(flatten)]
    points: crate::flags::PointsArg,
    /// The incisal point X,Y,Z in the mandible marker's frame (mm) for the CSV's incisor
    /// columns, in place of the points file's (--points) or the standard mounting's.
    #[arg(long, value_name = "X,Y,Z", value_parser = crate::numbers::parse_point, allow_hyphen_values = true)]
    incisor: Option<[f64; 3]>,
    /// Output file; `-` for standard output.
    #[arg(long, default_value = "-")]
    out: PathBuf,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    #[command(flatten)]
    session: SessionArg,
    /// The frame (its `frame` number) whose jaw pose is the rest position; default: the bite
    /// accepted while recording (a `bite` line), else the first frame with a jaw pose.
    #[arg(long, value_name = "FRAME", value_parser = crate::numbers::parse_frame, allow_hyphen_values = true)]
    rest_frame: Option<u64>,
}

/// Arguments of `jawtrack plot`.
#[derive(Args)]
pub(crate) struct PlotArgs {
    /// The recording (JSON lines).
    recording: PathBuf,
    /// Output folder for the SVG and PNG plots.
    #[arg(long, default_value = "plots")]
    out: PathBuf,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// The frame whose jaw pose is the rest position; default: the bite accepted while
    /// recording, else the first frame with a jaw pose.
    #[arg(long, value_name = "FRAME", value_parser = crate::numbers::parse_frame, allow_hyphen_values = true)]
    rest_frame: Option<u64>,
    #[command(flatten)]
    incisor: crate::flags::IncisorArgs,
    #[command(flatten)]
    session: SessionArg,
}

pub(crate) fn export(a: &ExportArgs) -> Result<()> {
    a.force.check_file(&a.out)?;
    let rec = load(&a.recording, a.session)?;
    let format = [
        (a.csv, Format::Csv),
        (a.jsonl, Format::Jsonl),
        (a.transforms_csv, Format::TransformsCsv),
        (a.transforms_json, Format::TransformsJson),
        (a.trc, Format::Trc),
        (a.mot, Format::Mot),
        (a.c3d, Format::C3d),
    ]
    .into_iter()
    .find_map(|(given, f)| given.then_some(f))
    .context("give one of --csv, --jsonl, --transforms-csv, --transforms-json, --trc, --mot, --c3d")?;
    let to_stdout = a.out.as_os_str() == "-";
    if to_stdout && format == Format::C3d && std::io::IsTerminal::is_terminal(&std::io::stdout()) {
        anyhow::bail!("--c3d writes a binary file: give --out FILE.c3d");
    }
    let named = if to_stdout { &a.recording } else { &a.out };
    let inputs = Inputs {
        rest: rest_of(&rec, a.rest_frame)?,
        registration: registration(a.registration.as_deref())?,
        points: a.points.points.as_deref(),
        incisor: a.incisor,
        recording: a.recording.display().to_string(),
        name: named.file_name().map_or_else(|| "jawtrack".into(), |n| n.to_string_lossy().into_owned()),
    };
    // Written in memory first: a refused or failed export leaves no file behind.
    let mut text = Vec::new();
    let done = jawtrack_session::export::export(format, &rec, inputs, &mut text)?;
    for w in &done.warnings {
        tell!("warning: {w}");
    }
    if to_stdout {
        let mut out = std::io::stdout().lock();
        out.write_all(&text).and_then(|()| out.flush()).context("writing to standard output")?;
        tell!("exported {}", done.summary);
    } else {
        a.force.write_file(&a.out, &text)?;
        tell!("exported {} to {}", done.summary, a.out.display());
    }
    Ok(())
}

pub(crate) fn plot(a: &PlotArgs) -> Result<()> {
    // The charts `plot` writes, each as SVG and PNG.
    let stems = jawtrack_report::incisor_chart_stems();
    let files: Vec<String> = stems.iter().flat_map(|p| [format!("{p}.svg"), format!("{p}.png")]).collect();
    a.force.check_folder(&a.out, &files.iter().map(String::as_str).collect::<Vec<_>>())?;
    let rec = load(&a.recording, a.session)?;
    let rest = require_rest(&rec, a.rest_frame, &a.recording, "plot")?.pose();
    let incisor = a.incisor.choose(&rest)?.incisor;
    let path = jawtrack_session::incisor::path(&rec.frames, &incisor, &rest);
    let metrics = Metrics::compute(&path).context("no frame has a jaw pose")?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let timed: Vec<_> = path.iter().map(|(t, _, d)| (*t, *d)).collect();
    let charts = jawtrack_report::incisor_charts(&timed);
    for (stem, doc) in &charts {
        let [svg, png] = plot::save_svg_and_png(doc, &a.out.join(stem))?;
        say!("{}\n{}", svg.display(), png.display());
    }
    tell!(
        "{} frames with a jaw pose of {}; widest opening {} mm, left {} mm, right {} mm, protrusion {} mm",
        path.len(),
        rec.frames.len(),
        fixed(metrics.max_opening.mm, 1),
        fixed(metrics.max_left.mm, 1),
        fixed(metrics.max_right.mm, 1),
        fixed(metrics.max_protrusion.mm, 1)
    );
    Ok(())
}
