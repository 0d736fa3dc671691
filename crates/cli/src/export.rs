//! `jawtrack export` and `jawtrack plot`: a recording (from `track`, `receive` or the phone)
//! turned into a time-ordered CSV or a clean JSON Lines file, and into plots of the lower
//! incisor's path in the sagittal, frontal and transverse planes.
//!
//! Frames received over the link are written in arrival order; both commands put them back in
//! sequence order. Displacements are measured from the rest position: `--rest-frame`'s jaw
//! pose, else the bite the intercuspation step accepted while recording, else the first frame
//! with a jaw pose.

use crate::numbers::{fixed, full};
use anyhow::{Context, Result, bail};
use clap::{ArgGroup, Args};
use jawtrack_kinematics::{Displacement, Incisor, PlaneView};
use jawtrack_plot::{self as plot, Series, Style};
use jawtrack_pose::Pose;
use jawtrack_recording::{BiteRecord, FrameRecord, Recording, RecordingHeader, SessionId};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack export`.
#[derive(Args)]
#[command(group(ArgGroup::new("format").required(true).args(["csv", "jsonl", "transforms_csv", "transforms_json", "trc", "mot"])))]
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
    /// For OpenSim: the lower incisal point's and both condyles' trajectories (mm), in
    /// OpenSim's axes (X anterior, Y up, Z right; origin the head frame's), the points the
    /// points file's (--points) or else the standard mounting's. Frames without a jaw pose have
    /// blank markers.
    #[arg(long)]
    trc: bool,
    /// For OpenSim: the jaw's coordinates over time from the rest position: body-fixed X–Y–Z
    /// angles (°) and the condylar midpoint's shift (m), in OpenSim's axes.
    #[arg(long)]
    mot: bool,
    /// The registration file (`jawtrack register`) the transforms are taken through; without
    /// it, the recording's own `maxilla_scan_from_mandible_scan` (tracked with a registration).
    #[arg(long)]
    registration: Option<PathBuf>,
    #[command(flatten)]
    points: crate::points::PointsArg,
    /// Output file; `-` for standard output.
    #[arg(long, default_value = "-")]
    out: PathBuf,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    #[command(flatten)]
    session: SessionArg,
    /// The frame (its `frame` number) whose jaw pose is the rest position; default: the bite
    /// accepted while recording (a `bite` line), else the first frame with a jaw pose.
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
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// The frame whose jaw pose is the rest position; default: the bite accepted while
    /// recording, else the first frame with a jaw pose.
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
            rec.bites.retain(|b| b.session == Some(wanted));
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

/// Where displacements are measured from.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Rest {
    /// A frame's jaw pose (`--rest-frame`, or the first frame with one).
    Frame(u64, Pose),
    /// The bite the intercuspation step accepted while recording.
    Bite(BiteRecord),
}

impl Rest {
    pub(crate) fn pose(self) -> Pose {
        match self {
            Rest::Frame(_, p) => p,
            Rest::Bite(b) => b.maxilla_from_mandible,
        }
    }

    /// In words, for a summary.
    pub(crate) fn describe(self) -> String {
        match self {
            Rest::Frame(n, _) => format!("frame {n}"),
            Rest::Bite(b) => format!(
                "the bite accepted at t = {} s ({} frames held within {} mm)",
                fixed(b.t, 2),
                b.frames,
                fixed(b.spread_mm, 2)
            ),
        }
    }

    /// As JSON, for `metrics --json`.
    pub(crate) fn to_json(self) -> serde_json::Value {
        match self {
            Rest::Frame(n, _) => serde_json::json!({"source": "frame", "frame": n}),
            Rest::Bite(b) => serde_json::json!({"source": "bite", "t": b.t, "frames": b.frames,
                "span_s": b.span_s, "spread_mm": b.spread_mm, "spread_deg": b.spread_deg}),
        }
    }
}

/// The rest position: frame `rest_frame`'s jaw pose (an error if it has none); else the last
/// bite the intercuspation step accepted in the recording; else the first frame's jaw pose.
/// `None` when there is none of these.
pub(crate) fn rest_of(rec: &Recording, rest_frame: Option<u64>) -> Result<Option<Rest>> {
    match rest_frame {
        None => Ok(rec
            .rest(None)
            .map(|b| Rest::Bite(*b))
            .or_else(|| rec.frames.iter().find_map(|f| f.maxilla_from_mandible.map(|m| Rest::Frame(f.frame, m))))),
        Some(n) => match rec.frames.iter().find(|f| f.frame == n) {
            Some(f) => f
                .maxilla_from_mandible
                .map(|m| Some(Rest::Frame(n, m)))
                .with_context(|| format!("frame {n} has no jaw pose")),
            None => bail!("--rest-frame {n}: no such frame in the recording"),
        },
    }
}

/// The frames' rate (frames/s): the inverse of the median interval, 30 when unknown.
fn frame_rate(frames: &[(f64, Option<Pose>)]) -> f64 {
    let mut dt: Vec<f64> = frames.windows(2).map(|w| w[1].0 - w[0].0).filter(|d| *d > 0.0).collect();
    dt.sort_by(f64::total_cmp);
    dt.get(dt.len() / 2).map_or(30.0, |d| (1.0 / d * 1000.0).round() / 1000.0)
}

/// Per frame with a jaw pose: (frame, t, the lower scan in the upper scan's frame), through
/// `registration`, else the recording's own transforms; refused when there are neither.
fn scan_transforms(rec: &Recording, registration: Option<&Path>) -> Result<Vec<(u64, f64, Pose)>> {
    let through = match registration {
        Some(p) => Some(
            jawtrack_tracker::Registration::load(p).with_context(|| format!("registration file {}", p.display()))?,
        ),
        None => None,
    };
    let out: Vec<(u64, f64, Pose)> = rec
        .frames
        .iter()
        .filter_map(|f| {
            let m = match &through {
                Some(r) => r.maxilla_scan_from_mandible_scan(&f.maxilla_from_mandible?),
                None => f.maxilla_scan_from_mandible_scan?,
            };
            Some((f.frame, f.t, m))
        })
        .collect();
    if out.is_empty() {
        match through {
            Some(_) => bail!("no frame has a jaw pose (both markers tracked): nothing to export"),
            None => bail!(
                "no frame carries maxilla_scan_from_mandible_scan (the recording was tracked without a registration): \
                 give --registration reg.json (`jawtrack register` writes it)"
            ),
        }
    }
    Ok(out)
}

/// A frame's time and the incisor's displacement.
type Timed = (f64, Displacement);

/// The incisor's displacement per frame with a jaw pose.
fn displacements(frames: &[FrameRecord], rest: &Pose) -> Vec<Timed> {
    let incisor = Incisor::standard();
    frames.iter().filter_map(|f| f.maxilla_from_mandible.map(|m| (f.t, incisor.displacement(&m, rest)))).collect()
}

pub(crate) fn export(a: &ExportArgs) -> Result<()> {
    a.force.check_file(&a.out)?;
    let rec = load(&a.recording, a.session)?;
    let rest = rest_of(&rec, a.rest_frame)?.map(|r| r.pose());
    let mut out: Box<dyn Write> = if a.out.as_os_str() == "-" {
        Box::new(std::io::stdout().lock())
    } else {
        Box::new(std::io::BufWriter::new(
            std::fs::File::create(&a.out).with_context(|| format!("creating {}", a.out.display()))?,
        ))
    };
    if a.trc || a.mot {
        let Some(rest) = rest else {
            bail!("{}: no frame has a jaw pose (both markers tracked), nothing to export", a.recording.display());
        };
        let reg = crate::points::registration(a.registration.as_deref())?;
        let mounting = crate::points::anatomy(a.points.points.as_deref(), reg.as_ref(), &rest)?.mounting;
        let frames: Vec<(f64, Option<Pose>)> = rec.frames.iter().map(|f| (f.t, f.maxilla_from_mandible)).collect();
        let named = if a.out.as_os_str() == "-" { &a.recording } else { &a.out };
        let name = named.file_name().map_or_else(|| "jawtrack".into(), |n| n.to_string_lossy().into_owned());
        let text = if a.trc {
            jawtrack_kinematics::opensim::trc(&mounting, &rest, &frames, frame_rate(&frames), &name)
        } else {
            jawtrack_kinematics::opensim::mot(&mounting, &rest, &frames, &name)
        };
        out.write_all(text.as_bytes())?;
        out.flush()?;
        eprintln!("exported {} frames as {}", rec.frames.len(), if a.trc { "OpenSim .trc" } else { "OpenSim .mot" });
        return Ok(());
    }
    if a.transforms_csv || a.transforms_json {
        let transforms = scan_transforms(&rec, a.registration.as_deref())?;
        if a.transforms_csv {
            let mut w = csv::Writer::from_writer(out);
            let mut head = vec!["frame".to_string(), "t_s".to_string()];
            head.extend((0..16).map(|k| format!("m{}{}", k / 4, k % 4)));
            w.write_record(&head)?;
            for (frame, t, m) in &transforms {
                let mut row = vec![frame.to_string(), full(*t)];
                row.extend(m.to_row_major().iter().map(|v| full(*v)));
                w.write_record(&row)?;
            }
            w.flush()?;
        } else {
            let frames: Vec<serde_json::Value> = transforms
                .iter()
                .map(|(frame, t, m)| serde_json::json!({"frame": frame, "t_s": t, "matrix": m.to_row_major()}))
                .collect();
            let doc = serde_json::json!({
                "version": 1,
                "units": "mm",
                "transform": "maxilla_scan_from_mandible_scan",
                "description": "the lower scan placed in the upper scan's frame at each frame: p_upper = M · [p_lower, 1]",
                "layout": "row-major 4x4",
                "frames": frames,
            });
            writeln!(out, "{doc}")?;
            out.flush()?;
        }
        eprintln!("exported {} transforms of {} frames", transforms.len(), rec.frames.len());
        return Ok(());
    }
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
        let opt = |v: Option<f64>| v.map(full).unwrap_or_default();
        for f in &rec.frames {
            let mut row = vec![
                f.frame.to_string(),
                f.seq.map(|s| s.to_string()).unwrap_or_default(),
                full(f.t),
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
                    row.extend([t.x, t.y, t.z, q.w, q.i, q.j, q.k, p.x, p.y, p.z].map(full));
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

/// The plots `plot` writes, each as SVG and PNG.
const PLOTS: [&str; 4] = ["incisor_sagittal", "incisor_frontal", "incisor_transverse", "incisor_opening"];

pub(crate) fn plot(a: &PlotArgs) -> Result<()> {
    let files: Vec<String> = PLOTS.iter().flat_map(|p| [format!("{p}.svg"), format!("{p}.png")]).collect();
    a.force.check_folder(&a.out, &files.iter().map(String::as_str).collect::<Vec<_>>())?;
    let rec = load(&a.recording, a.session)?;
    let Some(rest) = rest_of(&rec, a.rest_frame)?.map(|r| r.pose()) else {
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
    let mut charts: Vec<(String, _)> = PlaneView::ALL
        .iter()
        .map(|&v| {
            let (x, y) = v.axes();
            let title = format!("Lower incisor, {}", v.title());
            (format!("incisor_{}", v.name()), plot::chart(&title, x, y, &series(&|(_, d)| v.project(d)), true))
        })
        .collect();
    charts.push((
        "incisor_opening".into(),
        plot::chart(
            "Lower incisor opening over time",
            "time (s)",
            "opening (mm)",
            &series(&|(t, d)| (*t, d.opening)),
            false,
        ),
    ));
    for (stem, doc) in &charts {
        let [svg, png] = plot::save_svg_and_png(doc, &a.out.join(stem))?;
        say!("{}\n{}", svg.display(), png.display());
    }
    let peak = |f: &dyn Fn(&Displacement) -> f64| path.iter().map(|(_, d)| f(d)).fold(f64::NEG_INFINITY, f64::max);
    eprintln!(
        "{} frames with a jaw pose of {}; widest opening {} mm, left {} mm, right {} mm, protrusion {} mm",
        path.len(),
        rec.frames.len(),
        fixed(peak(&|d| d.opening), 1),
        fixed(peak(&|d| d.lateral), 1),
        fixed(peak(&|d| -d.lateral), 1),
        fixed(peak(&|d| d.protrusive), 1)
    );
    Ok(())
}
