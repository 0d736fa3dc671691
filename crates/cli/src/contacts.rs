//! `jawtrack contacts`: where the arches touch over a recording. Each frame's lower scan is
//! placed in the upper scan's frame by `maxilla_scan_from_mandible_scan` and checked by a
//! [`ContactSession`](jawtrack_occlusion::session::ContactSession) (regions in contact, their
//! areas and depths, the contact map over the recording); the run itself is
//! `jawtrack_session::contact_run`, and this file gives it the flags and prints what it finds.
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
use anyhow::{Result, bail};
use clap::{ArgAction, Args, ValueEnum};
use jawtrack_occlusion::contacts::{ContactSettings, THRESHOLD_RANGE_MM};
use jawtrack_occlusion::dynamics::{DynamicsOptions, PathSummary};
use jawtrack_session::PoseSource;
use jawtrack_session::contact_run::{self, ContactEvents, ContactJob};
use nalgebra::Vector3;
use std::path::PathBuf;

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
    a.force.check_folder(&a.out, &contact_run::RESULT_FILES)?;
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

/// Prints what a run does as it goes, and draws its progress unless `--quiet`.
struct Printed {
    quiet: bool,
    bar: Option<jawtrack_progress::ProgressBar>,
}

impl ContactEvents for Printed {
    fn mesh(&mut self, line: &str) {
        if !self.quiet {
            say!("{line}");
        }
    }
    fn indexing(&mut self) {
        if !self.quiet {
            say!("indexing both arches for distance queries (a few seconds per 100k triangles)…");
        }
    }
    fn indexed(&mut self, seconds: f64) {
        if !self.quiet {
            say!("indexed in {seconds:.1} s");
        }
    }
    fn begin(&mut self, what: &'static str, total: usize) {
        self.bar =
            Some(if self.quiet { jawtrack_progress::ProgressBar::hidden() } else { crate::progress_bar(what, total) });
    }
    fn progress(&mut self, done: usize) {
        self.bar.iter().for_each(|b| b.set_position(done as u64));
    }
    fn end(&mut self) {
        self.bar.take().iter().for_each(jawtrack_progress::ProgressBar::finish_and_clear);
    }
    fn simulated(&mut self, s: &PathSummary) {
        let c = &s.intercuspation_correction;
        say!(
            "dynamic: intercuspation corrected by {:.3} mm and {:.3}°; peak contact force {:.3} N; largest offset from the recorded path {:.3} mm; residual penetration {:.4} mm",
            Vector3::from(c.shift_mm).norm(),
            c.rotation_deg,
            s.peak_force_n,
            s.max_target_offset_mm,
            s.max_residual_penetration_mm
        );
    }
    fn warning(&mut self, w: &str) {
        tell!("warning: {w}");
    }
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
    let job = ContactJob {
        maxilla: &a.maxilla,
        mandible: &a.mandible,
        poses: &a.poses,
        registration: a.registration.as_deref(),
        points: a.points.as_deref(),
        settings,
        dynamics: (a.mode == Mode::Dynamic).then(|| dynamics_options(a)),
        every: a.every,
        out: &a.out,
    };
    let found = contact_run::run(&job, &rec, &source, &mut Printed { quiet: a.quiet, bar: None })?;
    let (lines, warning) = jawtrack_report::contact_findings(&found, settings.threshold_mm, source.describe());
    lines.iter().for_each(|l| say!("{l}"));
    warning.iter().for_each(|w| tell!("warning: {w}"));
    let s = &found.summary;
    say!("median {:.1} ms per frame (index build {:.0} ms)", s.query_ms_median.unwrap_or(0.0), found.setup_ms);
    for p in &found.written {
        say!("wrote {}", p.display());
    }
    Ok(())
}
