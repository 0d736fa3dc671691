//! `jawtrack contacts`: where the arches touch over a recording. Each frame's lower scan is
//! placed in the upper scan's frame by `maxilla_scan_from_mandible_scan` and checked by a
//! [`ContactSession`] (regions in contact, their areas and depths, the contact map over the
//! recording); this file reads the inputs, feeds the session and writes what it finds.
//!
//! Where the pose comes from: with `--registration`, from each frame's `maxilla_from_mandible`
//! through the registration; without, from the frames' recorded `maxilla_scan_from_mandible_scan`
//! when the recording was tracked with a registration. A poses file without a recording header
//! (written by hand, e.g. an identity pose for scans exported in occlusion) has its
//! `maxilla_from_mandible` taken as the scan pose itself; a tracked recording without scan poses
//! is refused, as its poses are the markers'.
//! Frames without the pose are skipped and counted.
//!
//! Outputs in `--out`: `contacts.jsonl` (a header line, then one line per frame, flushed as
//! written), per arch a PLY coloured by contact frequency and one by depth, PNG occlusal
//! views coloured by frequency, SVG contact maps a clinician reads (depth and frequency: the
//! patient's side, FDI and Universal tooth numbers, a scale bar, the colour scale in mm or %),
//! and `summary.json` with per-tooth totals.

use crate::flags::{SessionArg, load, registration};
use crate::numbers::{clean_json, fixed};
use anyhow::{Context, Result, bail};
use clap::{ArgAction, Args, ValueEnum};
use jawtrack_occlusion::contacts::{Arch, ContactSettings, THRESHOLD_RANGE_MM};
use jawtrack_occlusion::dynamics::{self, DynamicsOptions, StepSummary};
use jawtrack_occlusion::session::{ContactSession, SessionSummary};
use jawtrack_occlusion::teeth::{Tooth, ToothTotal, ToothTotals};
use jawtrack_pose::Pose;
use jawtrack_session::PoseSource;
use jawtrack_session::anatomy::upper_scan_left;
use jawtrack_session::arches::{ArchInput, load_arch, tooth_places};
use jawtrack_session::contacts::write_outputs;
use jawtrack_session::scan_pose::PosedFrame;
use nalgebra::Vector3;
use serde_json::{Value, json};
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// How the mandible is placed in each frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Mode {
    /// Where the recording puts it: the scans may interpenetrate, and the depth says how far.
    Kinematic,
    /// Slid over the maxillary teeth as a rigid body: pulled towards the recorded pose by a
    /// spring-damper, pushed out by contact forces, after the smallest correction that removes
    /// the interpenetration of the first frame.
    Dynamic,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Kinematic => "kinematic",
            Mode::Dynamic => "dynamic",
        }
    }
}

/// Arguments of `jawtrack contacts`.
#[derive(Args)]
pub(crate) struct ContactsArgs {
    #[command(flatten)]
    session: SessionArg,
    /// The upper arch's scan (STL, PLY or OBJ, mm). Several files: one mesh per tooth, named
    /// by `NN` when the file name holds `FDI=NN`, else by the file name's stem.
    #[arg(long, required = true, num_args = 1.., action = ArgAction::Append, value_name = "MESH")]
    maxilla: Vec<PathBuf>,
    /// The lower arch's scan, or one file per tooth, as for `--maxilla`.
    #[arg(long, required = true, num_args = 1.., action = ArgAction::Append, value_name = "MESH")]
    mandible: Vec<PathBuf>,
    /// The recording (JSON lines, from `track`, `receive` or the phone). A one-line file
    /// `{"frame":0,"t":0,"maxilla_from_mandible":[16 numbers, row-major]}` checks one pose.
    #[arg(long, value_name = "FILE")]
    poses: PathBuf,
    /// Where the markers sit in the scans; without it, the recording's poses are taken as the
    /// lower scan's pose in the upper scan's frame.
    #[arg(long, value_name = "FILE")]
    registration: Option<PathBuf>,
    /// The anatomical points file (`jawtrack points`): says where the patient's left is on the
    /// maps when the teeth are not named by FDI number.
    #[arg(long, value_name = "FILE")]
    points: Option<PathBuf>,
    /// kinematic: the mandible where the recording puts it; dynamic: slid to rest on the teeth.
    #[arg(long, value_enum, default_value_t = Mode::Kinematic)]
    mode: Mode,
    /// A vertex within this gap (mm) of the other arch, or penetrating it, is in contact
    /// (0.01 mm, shimstock, to 0.5 mm).
    #[arg(long, value_name = "MM", default_value_t = ContactSettings::default().threshold_mm, allow_hyphen_values = true)]
    threshold: f64,
    /// The deepest penetration (mm) measured; deeper points are not seen (an open scan has no
    /// "inside" far from its surface).
    #[arg(long, value_name = "MM", default_value_t = ContactSettings::default().max_depth_mm, allow_hyphen_values = true)]
    max_depth: f64,
    /// Output folder (created).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// Check every n-th frame with a pose.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    every: u64,
    /// No progress bar and no per-mesh lines; the final summary is still printed.
    #[arg(long)]
    quiet: bool,
    /// Dynamic mode: the lower arch's mass (kg).
    #[arg(long, value_name = "KG", default_value_t = DynamicsOptions::default().mass_kg, allow_hyphen_values = true)]
    mass: f64,
    /// Dynamic mode: natural frequency (Hz) of the spring-damper pulling the arch to the path.
    #[arg(long, value_name = "HZ", default_value_t = DynamicsOptions::default().natural_frequency_hz, allow_hyphen_values = true)]
    spring_hz: f64,
    /// Dynamic mode: integration step (s).
    #[arg(long, value_name = "S", default_value_t = DynamicsOptions::default().dt_s, allow_hyphen_values = true)]
    dt: f64,
}

/// Reads one arch's meshes, printing a line per mesh unless `quiet`.
fn read_arch(side: &'static str, files: &[PathBuf], quiet: bool) -> Result<ArchInput> {
    let arch = load_arch(side, files)?;
    if !quiet {
        arch.lines.iter().for_each(|l| say!("{l}"));
    }
    Ok(arch)
}

/// The dynamic mode: the recorded path resolved by the rigid-body simulation; per frame the
/// resolved pose and what its line adds, and the summary.
fn dynamic_frames(
    a: &ContactsArgs,
    upper: &Arch,
    lower: &Arch,
    posed: &[PosedFrame],
) -> Result<(Vec<PosedFrame>, Vec<Value>, Value)> {
    let options = dynamics_options(a);
    let target: Vec<(f64, Pose)> = posed.iter().map(|&(_, t, p)| (t, p)).collect();
    let bar = if a.quiet { indicatif::ProgressBar::hidden() } else { crate::progress_bar("simulating", posed.len()) };
    let path = dynamics::resolve_path(upper, lower, &target, &options, &mut |done, _| bar.set_position(done as u64))
        .context("dynamic mode")?;
    bar.finish_and_clear();
    let s = path.summary();
    let c = &s.intercuspation_correction;
    say!(
        "dynamic: intercuspation corrected by {:.3} mm and {:.3}°; peak contact force {:.3} N; largest offset from the recorded path {:.3} mm; residual penetration {:.4} mm",
        Vector3::from(c.shift_mm).norm(),
        c.rotation_deg,
        s.peak_force_n,
        s.max_target_offset_mm,
        s.max_residual_penetration_mm
    );
    let frames = posed.iter().zip(&path.steps).map(|(&(frame, t, _), s)| (frame, t, s.maxilla_scan_from_mandible_scan));
    let extras = path.steps.iter().map(|s| json!(StepSummary::from(s))).collect();
    Ok((frames.collect(), extras, json!(s)))
}

/// The dynamic mode's options from the flags.
fn dynamics_options(a: &ContactsArgs) -> DynamicsOptions {
    DynamicsOptions { mass_kg: a.mass, natural_frequency_hz: a.spring_hz, dt_s: a.dt, ..Default::default() }
}

/// The checks that need no input file, made before anything is read or indexed (indexing two
/// arches takes seconds to tens of seconds): the output folder and the dynamic mode's options,
/// each refusal naming the flag to change.
fn check_options(a: &ContactsArgs) -> Result<()> {
    if a.out.exists() && !a.out.is_dir() {
        bail!("--out {}: exists and is not a folder (contacts writes a folder of results)", a.out.display());
    }
    a.force.check_folder(&a.out, &["contacts.jsonl", "summary.json"])?;
    if a.mode == Mode::Dynamic {
        let options = dynamics_options(a);
        if let Err(e) = options.validate() {
            // The flag whose value alone fails, with the others at their defaults; else the pair.
            let d = DynamicsOptions::default();
            let flag = if (DynamicsOptions { mass_kg: a.mass, ..d }).validate().is_err() {
                "--mass"
            } else if (DynamicsOptions { natural_frequency_hz: a.spring_hz, ..d }).validate().is_err() {
                "--spring-hz"
            } else if (DynamicsOptions { dt_s: a.dt, ..d }).validate().is_err() {
                "--dt"
            } else {
                "--dt with --spring-hz"
            };
            bail!("{flag}: {e}");
        }
    }
    Ok(())
}

pub(crate) fn run(a: &ContactsArgs) -> Result<()> {
    check_options(a)?;
    let settings = ContactSettings { threshold_mm: a.threshold, max_depth_mm: a.max_depth };
    if let Err(e) = settings.validate() {
        let (lo, hi) = THRESHOLD_RANGE_MM;
        let flag = if (lo..=hi).contains(&settings.threshold_mm) { "--max-depth" } else { "--threshold" };
        bail!("{flag}: {e}");
    }
    let registration = registration(a.registration.as_deref())?;
    let rec = load(&a.poses, a.session)?;
    let source = PoseSource::for_poses_file(&rec, registration, &a.poses)?;
    let with_pose = source.posed(&rec);
    let posed: Vec<PosedFrame> = with_pose.iter().copied().step_by(a.every as usize).collect();
    let (skipped_no_pose, outside_stride) = (rec.frames.len() - with_pose.len(), with_pose.len() - posed.len());
    let Some(&(_, _, first_pose)) = posed.first() else {
        bail!(
            "{}: none of its {} frames has a pose ({}); nothing to check",
            a.poses.display(),
            rec.frames.len(),
            source.describe()
        );
    };

    let setup = Instant::now();
    let ArchInput { parts: upper_parts, reports: upper_reports, .. } = read_arch("maxilla", &a.maxilla, a.quiet)?;
    let ArchInput { parts: lower_parts, reports: lower_reports, .. } = read_arch("mandible", &a.mandible, a.quiet)?;
    let teeth = [tooth_places(&upper_parts), tooth_places(&lower_parts)];
    let upper_left = upper_scan_left(a.points.as_deref())?;
    let (upper, lower) = index_arches(upper_parts, lower_parts, &settings, a.quiet)?;
    let setup_ms = setup.elapsed().as_secs_f64() * 1e3;

    let (frames, extras, dynamics_summary) = match a.mode {
        Mode::Kinematic => (posed, Vec::new(), Value::Null),
        Mode::Dynamic => dynamic_frames(a, &upper, &lower, &posed)?,
    };

    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let path = a.out.join("contacts.jsonl");
    let mut out =
        std::io::BufWriter::new(std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?);
    // The header holds the settings that summary.json repeats, and the inputs.
    let run_settings = json!({
        "mode": a.mode.name(),
        "threshold_mm": settings.threshold_mm,
        "max_depth_mm": settings.max_depth_mm,
        "every": a.every,
        "registration": a.registration.as_ref().map(|p| p.display().to_string()),
        "poses": a.poses.display().to_string(),
        "pose_source": source.describe(),
    });
    let mut header = run_settings.clone();
    let files = |v: &[PathBuf]| json!(v.iter().map(|p| p.display().to_string()).collect::<Vec<_>>());
    (header["version"], header["units"]) = (json!(1), json!("mm"));
    (header["maxilla"], header["mandible"]) = (files(&a.maxilla), files(&a.mandible));
    let mut write_line = |line: &Value| {
        writeln!(out, "{line}").and_then(|()| out.flush()).with_context(|| format!("writing {}", path.display()))
    };
    write_line(&json!({ "contacts": header }))?;

    let bar = if a.quiet { indicatif::ProgressBar::hidden() } else { crate::progress_bar("contacts", frames.len()) };
    let started = Instant::now();
    let mut session = ContactSession::new(&upper, &lower, settings);
    let mut per_tooth = ToothTotals::default();
    for (k, (frame, t, pose)) in frames.iter().enumerate() {
        let found = session.check(*frame, *t, pose);
        per_tooth.add(&found.regions);
        let mut line = json!(found);
        if let Some(extra) = extras.get(k) {
            line["dynamics"] = extra.clone();
        }
        write_line(&line)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    let total_s = started.elapsed().as_secs_f64();

    let s = session.summary();
    let more = write_outputs(&a.out, &session, [&upper, &lower], &first_pose, [&teeth[0], &teeth[1]], upper_left)?;
    more.warnings.iter().for_each(|w| eprintln!("warning: {w}"));
    let mut written = vec![path.clone()];
    written.extend(more.files);
    let teeth_totals = per_tooth.totals();
    let mut summary = json!({
        "frames": {
            "read": rec.frames.len(),
            "checked": s.frames,
            "skipped_no_pose": skipped_no_pose,
            "outside_stride": outside_stride,
            "unreadable_lines": rec.skipped.len(),
            "with_contact": s.with_contact,
            "penetrating": s.penetrating,
        },
        "settings": run_settings,
        "meshes": { "maxilla": upper_reports, "mandible": lower_reports },
        "contact_area": s.contact_area,
        "teeth": teeth_totals,
        "dynamics": dynamics_summary,
        "deepest": s.deepest,
        "depth_colour_full_scale_mm": s.depth_colour_full_scale_mm,
        "timing": {
            "setup_ms": setup_ms,
            "ms_per_frame_median": s.query_ms_median,
            "ms_per_frame_max": s.query_ms_max,
            "total_s": total_s,
        },
    });
    clean_json(&mut summary);
    let p = a.out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).context("summary")?;
    std::fs::write(&p, text + "\n").with_context(|| format!("writing {}", p.display()))?;
    written.push(p);

    print_findings(&s, &teeth_totals, rec.frames.len(), skipped_no_pose, settings.threshold_mm, source.describe());
    say!("median {:.1} ms per frame (index build {:.0} ms)", s.query_ms_median.unwrap_or(0.0), setup_ms);
    for p in &written {
        say!("wrote {}", p.display());
    }
    Ok(())
}

/// Builds both arches' distance indexes, side by side (they are independent).
fn index_arches(
    upper: Vec<(String, jawtrack_occlusion::Mesh)>,
    lower: Vec<(String, jawtrack_occlusion::Mesh)>,
    settings: &ContactSettings,
    quiet: bool,
) -> Result<(Arch, Arch)> {
    if !quiet {
        say!("indexing both arches for distance queries (a few seconds per 100k triangles)…");
    }
    let started = Instant::now();
    let (upper, lower) = std::thread::scope(|scope| {
        let upper = scope.spawn(|| Arch::new(upper, settings));
        let lower = Arch::new(lower, settings);
        (upper.join(), lower)
    });
    let upper = upper.map_err(|_| anyhow::anyhow!("indexing the upper arch failed"))?;
    if !quiet {
        say!("indexed in {:.1} s", started.elapsed().as_secs_f64());
    }
    Ok((upper, lower))
}

/// Prints what the run found: frames checked, the deepest contact, per-tooth totals.
fn print_findings(
    s: &SessionSummary,
    teeth: &[ToothTotal],
    read: usize,
    skipped_no_pose: usize,
    threshold_mm: f64,
    source: &str,
) {
    let skipped =
        if skipped_no_pose > 0 { format!(", {skipped_no_pose} without a pose skipped") } else { String::new() };
    let (checked, near, deep) = (s.frames, s.with_contact, s.penetrating);
    let t = threshold_mm;
    say!("{checked} frames checked of {read}{skipped}; {near} within {t} mm, {deep} penetrating");
    match s.deepest {
        Some(d) if d.depth_mm > 0.0 => {
            say!("deepest penetration {} mm at frame {} (t {} s)", fixed(d.depth_mm, 3), d.frame, fixed(d.t, 3))
        }
        Some(d) => {
            say!(
                "no penetration; smallest gap {} mm at frame {} (t {} s)",
                fixed(-d.depth_mm, 3),
                d.frame,
                fixed(d.t, 3)
            )
        }
        None => {
            say!("no contact within {t} mm");
            eprintln!(
                "warning: the arches never came within {t} mm in any of the {checked} frames checked: a recording \
                 that includes the bite always touches; check that the scans and the poses ({}) belong together",
                source
            );
        }
    }
    if !teeth.is_empty() {
        say!("tooth          frames in contact   largest area   deepest");
        for t in teeth {
            let label = t.fdi.and_then(Tooth::fdi).map_or_else(|| t.name.clone(), Tooth::label);
            say!(
                "{label:<14} {:>17}   {:>9} mm²   {:>7} mm",
                t.frames_in_contact,
                fixed(t.max_area_mm2, 2),
                fixed(t.max_depth_mm, 3)
            );
        }
    }
}
