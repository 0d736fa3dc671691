//! `jawtrack export` and `jawtrack plot`: a recording (from `track`, `receive` or the phone)
//! turned into a time-ordered CSV or a clean JSON Lines file, and into plots of the lower
//! incisor's path in the sagittal, frontal and transverse planes.
//!
//! Frames received over the link are written in arrival order; both commands put them back in
//! sequence order. Displacements are measured from the rest position: the first frame with a
//! jaw pose, or `--rest-frame`.

use anyhow::{Context, Result, bail};
use clap::{ArgGroup, Args};
use jawtrack_kinematics::{Displacement, Incisor};
use jawtrack_plot::{self as plot, Series, Style};
use jawtrack_pose::Pose;
use jawtrack_recording::{FrameRecord, Recording, RecordingHeader, SessionId};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack export`.
#[derive(Args)]
#[command(group(ArgGroup::new("format").required(true).args(["csv", "jsonl"])))]
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
    /// Output file; `-` for standard output.
    #[arg(long, default_value = "-")]
    out: PathBuf,
    #[command(flatten)]
    session: SessionArg,
    /// The frame (its `frame` number) whose jaw pose is the rest position; default: the first
    /// frame with one.
    #[arg(long)]
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
    /// The frame whose jaw pose is the rest position; default: the first frame with one.
    #[arg(long)]
    rest_frame: Option<u64>,
    #[command(flatten)]
    session: SessionArg,
}

/// Reads a recording, warns about unreadable lines, orders the frames by sequence.
/// `--session`, for the commands that read a recording: one session's frames. A file holding
/// several sessions (a receiver that ran while the phone started and stopped transmitting) is
/// refused without it, since their frames would mix.
#[derive(clap::Args, Clone, Copy, Debug)]
pub(crate) struct SessionArg {
    /// Read only this session's frames (its 16-hex-digit id, as `"session"` in every frame);
    /// needed when the file holds several.
    #[arg(long, value_name = "ID")]
    pub(crate) session: Option<SessionId>,
}

pub(crate) fn load(path: &Path, only: SessionArg) -> Result<Recording> {
    /// Skipped lines named one by one; past that, counted (a foreign file has thousands).
    const NAMED: usize = 10;
    let mut rec = jawtrack_recording::open(path)?;
    let sessions = rec.sessions();
    match only.session {
        Some(wanted) => {
            if !sessions.contains(&wanted) {
                let ids: Vec<String> = sessions.iter().map(ToString::to_string).collect();
                bail!("{}: no frame of session {wanted}; its sessions: {}", path.display(), ids.join(", "));
            }
            rec.frames.retain(|f| f.session == Some(wanted));
        }
        None if sessions.len() > 1 => {
            let counts: Vec<String> = sessions
                .iter()
                .map(|&s| format!("{s} ({} frames)", rec.frames.iter().filter(|f| f.session == Some(s)).count()))
                .collect();
            bail!(
                "{}: holds {} sessions, whose frames must not be mixed: {}; choose one with --session ID \
                 (`jawtrack export FILE --session ID --jsonl --out ONE.jsonl` writes it alone)",
                path.display(),
                sessions.len(),
                counts.join(", ")
            );
        }
        None => {}
    }
    for (line, why) in rec.skipped.iter().take(NAMED) {
        eprintln!("warning: {} line {line} skipped: {why}", path.display());
    }
    if rec.skipped.len() > NAMED {
        eprintln!("warning: {} more lines of {} skipped", rec.skipped.len() - NAMED, path.display());
    }
    if rec.frames.is_empty() {
        bail!(
            "{}: the file has no frames that could be read ({} lines skipped): is it a recording of `jawtrack track`, `receive` or the phone?",
            path.display(),
            rec.skipped.len()
        );
    }
    rec.sort_by_capture();
    Ok(rec)
}

/// The rest position's jaw pose: frame `rest_frame`'s (an error if it has none), or the first
/// frame's that has one; `None` when no frame has a jaw pose.
pub(crate) fn rest_pose(frames: &[FrameRecord], rest_frame: Option<u64>) -> Result<Option<Pose>> {
    match rest_frame {
        None => Ok(frames.iter().find_map(|f| f.maxilla_from_mandible)),
        Some(n) => match frames.iter().find(|f| f.frame == n) {
            Some(f) => f.maxilla_from_mandible.map(Some).with_context(|| format!("frame {n} has no jaw pose")),
            None => bail!("--rest-frame {n}: no such frame in the recording"),
        },
    }
}

/// A frame's time and the incisor's displacement.
type Timed = (f64, Displacement);

/// The incisor's displacement per frame with a jaw pose.
fn displacements(frames: &[FrameRecord], rest: &Pose) -> Vec<Timed> {
    let incisor = Incisor::standard();
    frames.iter().filter_map(|f| f.maxilla_from_mandible.map(|m| (f.t, incisor.displacement(&m, rest)))).collect()
}

pub(crate) fn export(a: &ExportArgs) -> Result<()> {
    let rec = load(&a.recording, a.session)?;
    let rest = rest_pose(&rec.frames, a.rest_frame)?;
    let mut out: Box<dyn Write> = if a.out.as_os_str() == "-" {
        Box::new(std::io::stdout().lock())
    } else {
        Box::new(std::io::BufWriter::new(
            std::fs::File::create(&a.out).with_context(|| format!("creating {}", a.out.display()))?,
        ))
    };
    if a.jsonl {
        let header = rec.header.clone().unwrap_or_else(|| RecordingHeader::new("jawtrack export"));
        writeln!(out, "{}", header.to_line())?;
        for f in &rec.frames {
            writeln!(out, "{}", f.to_line())?;
        }
        // Dropping a BufWriter swallows its last write's error: a full disk must not pass.
        out.flush()?;
    } else {
        let incisor = Incisor::standard();
        let mut w = csv::Writer::from_writer(out);
        w.write_record([
            "frame",
            "seq",
            "t",
            "received_unix_s",
            "maxilla_tags",
            "mandible_tags",
            "maxilla_rms_px",
            "mandible_rms_px",
            "flags",
            "tx_mm",
            "ty_mm",
            "tz_mm",
            "qw",
            "qx",
            "qy",
            "qz",
            "incisor_x_mm",
            "incisor_y_mm",
            "incisor_z_mm",
            "opening_mm",
            "lateral_mm",
            "protrusive_mm",
        ])?;
        let opt = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
        for f in &rec.frames {
            let mut row = vec![
                f.frame.to_string(),
                f.seq.map(|s| s.to_string()).unwrap_or_default(),
                f.t.to_string(),
                opt(f.received_unix_s),
                f.maxilla.as_ref().map(|b| b.tags.len().to_string()).unwrap_or_default(),
                f.mandible.as_ref().map(|b| b.tags.len().to_string()).unwrap_or_default(),
                opt(f.maxilla.as_ref().map(|b| b.rms_px)),
                opt(f.mandible.as_ref().map(|b| b.rms_px)),
                f.flags.join(";"),
            ];
            match &f.maxilla_from_mandible {
                Some(m) => {
                    let (t, q) = (m.translation(), m.rotation());
                    let p = incisor.in_head(m);
                    row.extend([t.x, t.y, t.z, q.w, q.i, q.j, q.k, p.x, p.y, p.z].map(|v| v.to_string()));
                    let d = rest.map(|r| incisor.displacement(m, &r));
                    row.extend([d.map(|d| d.opening), d.map(|d| d.lateral), d.map(|d| d.protrusive)].map(opt));
                }
                None => row.extend(std::iter::repeat_n(String::new(), 13)),
            }
            w.write_record(&row)?;
        }
        w.flush()?;
    }
    eprintln!(
        "exported {} frames{}",
        rec.frames.len(),
        if a.out.as_os_str() == "-" { String::new() } else { format!(" to {}", a.out.display()) }
    );
    Ok(())
}

pub(crate) fn plot(a: &PlotArgs) -> Result<()> {
    let rec = load(&a.recording, a.session)?;
    let Some(rest) = rest_pose(&rec.frames, a.rest_frame)? else {
        bail!("{}: no frame has a jaw pose (both markers tracked), nothing to plot", a.recording.display());
    };
    let path = displacements(&rec.frames, &rest);
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let series = |f: &dyn Fn(&Timed) -> (f64, f64)| {
        vec![Series {
            name: "lower incisor",
            color: "#d62728",
            style: Style::Line,
            points: path.iter().map(f).collect(),
        }]
    };
    let charts = [
        (
            "incisor_sagittal",
            plot::chart(
                "Lower incisor, sagittal plane (patient facing right)",
                "protrusive (mm)",
                "up (mm)",
                &series(&|(_, d)| (d.protrusive, -d.opening)),
                true,
            ),
        ),
        (
            "incisor_frontal",
            plot::chart(
                "Lower incisor, frontal plane (seen from the front)",
                "patient's left (mm)",
                "up (mm)",
                &series(&|(_, d)| (d.lateral, -d.opening)),
                true,
            ),
        ),
        (
            "incisor_transverse",
            plot::chart(
                "Lower incisor, transverse plane (seen from above)",
                "patient's left (mm)",
                "protrusive (mm)",
                &series(&|(_, d)| (d.lateral, d.protrusive)),
                true,
            ),
        ),
        (
            "incisor_opening",
            plot::chart(
                "Lower incisor opening over time",
                "time (s)",
                "opening (mm)",
                &series(&|(t, d)| (*t, d.opening)),
                false,
            ),
        ),
    ];
    for (stem, doc) in &charts {
        let [svg, png] = plot::save_svg_and_png(doc, &a.out.join(stem))?;
        say!("{}\n{}", svg.display(), png.display());
    }
    let peak = |f: &dyn Fn(&Displacement) -> f64| path.iter().map(|(_, d)| f(d)).fold(f64::NEG_INFINITY, f64::max);
    eprintln!(
        "{} frames with a jaw pose of {}; widest opening {:.1} mm, left {:.1} mm, right {:.1} mm, protrusion {:.1} mm",
        path.len(),
        rec.frames.len(),
        peak(&|d| d.opening),
        peak(&|d| d.lateral),
        peak(&|d| -d.lateral),
        peak(&|d| d.protrusive)
    );
    Ok(())
}
