//! `jawtrack contacts`: where the arches touch over a recording. For each frame, the lower
//! scan is placed in the upper scan's frame by `maxilla_scan_from_mandible_scan`; the vertices
//! of both arches that penetrate the other arch or come within the threshold are grouped into
//! regions (centroid, area, deepest penetration or smallest gap, tooth), and a contact map
//! counts how often each vertex was in contact.
//!
//! Where the pose comes from: with `--registration`, from each frame's `maxilla_from_mandible`
//! through the registration; without, from the frames' recorded `maxilla_scan_from_mandible_scan`
//! when the recording was tracked with a registration, else `maxilla_from_mandible` is taken
//! as the scan pose itself (scans exported in occlusion checked with an identity poses file).
//! Frames without the pose are skipped and counted.
//!
//! Outputs in `--out`: `contacts.jsonl` (a header line, then one line per frame, flushed as
//! written), per arch a PLY coloured by contact frequency and one by depth, PNG occlusal
//! views coloured by frequency, and `summary.json`.

use crate::export::load;
use anyhow::{Context, Result, bail};
use clap::{ArgAction, Args, ValueEnum};
use jawtrack_occlusion::Mesh;
use jawtrack_occlusion::contacts::{Arch, ContactMap, ContactSettings, Side, THRESHOLD_RANGE_MM, contacts, tooth_name};
use jawtrack_occlusion::dynamics::{self, DynamicsOptions};
use jawtrack_occlusion::occlusal_view::{self, View};
use jawtrack_pose::Pose;
use jawtrack_recording::FrameRecord;
use jawtrack_tracker::registration::Registration;
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

/// One frame to check: its `frame` number, its time (s) and the lower scan in the upper scan's
/// frame (`maxilla_scan_from_mandible_scan`).
pub(crate) type PosedFrame = (u64, f64, Pose);

/// One arch's input: its named parts and their mesh reports (JSON).
struct ArchInput {
    parts: Vec<(String, Mesh)>,
    reports: Vec<Value>,
}

fn side_name(side: Side) -> &'static str {
    match side {
        Side::Maxilla => "maxilla",
        Side::Mandible => "mandible",
    }
}

/// Reads one arch's files, printing a line per mesh unless `quiet`.
fn load_arch(side: Side, files: &[PathBuf], quiet: bool) -> Result<ArchInput> {
    let (mut parts, mut reports) = (Vec::new(), Vec::new());
    for file in files {
        let mesh = Mesh::load(file).with_context(|| format!("--{}", side_name(side)))?;
        let r = mesh.report();
        if !quiet {
            let [lo, hi] = r.bounds;
            let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
            say!(
                "{} {}: {} vertices, {} triangles, {:.1} × {:.1} × {:.1} mm, {:.0} mm², {}, {}, {}, {}",
                side_name(side),
                file.display(),
                r.vertices,
                r.triangles,
                hi[0] - lo[0],
                hi[1] - lo[1],
                hi[2] - lo[2],
                r.area_mm2,
                plural(r.components, "component"),
                plural(r.boundary_loops, "boundary loop"),
                plural(r.degenerate_triangles, "degenerate triangle"),
                plural(r.non_manifold_edges, "non-manifold edge"),
            );
        }
        let name = tooth_name(file);
        let tooth = (files.len() > 1).then(|| name.clone());
        reports.push(json!({ "file": file.display().to_string(), "tooth": tooth, "report": r }));
        parts.push((name, mesh));
    }
    Ok(ArchInput { parts, reports })
}

/// The dynamic mode: the recorded path resolved by the rigid-body simulation; per frame the
/// resolved pose and what the line adds (force in N, offset from the recorded pose, residual
/// penetration), and a summary with the intercuspation correction.
fn resolve_path(
    upper: &Arch,
    lower: &Arch,
    posed: &[PosedFrame],
    options: &DynamicsOptions,
    quiet: bool,
) -> Result<(Vec<PosedFrame>, Vec<Value>, Value)> {
    let target: Vec<(f64, Pose)> = posed.iter().map(|&(_, t, p)| (t, p)).collect();
    let bar = if quiet { indicatif::ProgressBar::hidden() } else { crate::progress_bar("simulating", posed.len()) };
    let path = dynamics::resolve_path(upper, lower, &target, options, &mut |done, _| bar.set_position(done as u64))
        .context("dynamic mode")?;
    bar.finish_and_clear();
    let (correction, steps) = (&path.correction, &path.steps);
    let frames =
        posed.iter().zip(steps).map(|(&(frame, t, _), s)| (frame, t, s.maxilla_scan_from_mandible_scan)).collect();
    let extras = steps
        .iter()
        .map(|s| {
            json!({
                "force_n": s.force_n,
                "force": s.force,
                "target_offset_mm": s.target_offset_mm,
                "target_rotation_deg": s.target_rotation_deg,
                "max_penetration_mm": s.max_penetration_mm,
            })
        })
        .collect();
    let peak = path.peak_force_n();
    let residual = path.max_residual_penetration_mm();
    let offset = path.max_target_offset_mm();
    say!(
        "dynamic: intercuspation corrected by {:.3} mm and {:.3}°; peak contact force {peak:.3} N; largest offset from the recorded path {offset:.3} mm; residual penetration {residual:.4} mm",
        Vector3::from(correction.shift_mm).norm(),
        correction.rotation_deg
    );
    let summary = json!({
        "mass_kg": options.mass_kg,
        "natural_frequency_hz": options.natural_frequency_hz,
        "dt_s": options.dt_s,
        "tolerance_mm": options.tolerance_mm,
        "intercuspation_correction": {
            "shift_mm": correction.shift_mm,
            "rotation_deg": correction.rotation_deg,
            "initial_depth_mm": correction.initial_depth_mm,
            "residual_depth_mm": correction.residual_depth_mm,
        },
        "peak_force_n": peak,
        "max_residual_penetration_mm": residual,
        "max_target_offset_mm": offset,
    });
    Ok((frames, extras, summary))
}

/// Where each frame's `maxilla_scan_from_mandible_scan` comes from.
enum PoseSource {
    /// `maxilla_from_mandible` through a registration.
    Registration(Box<Registration>),
    /// The frames' recorded `maxilla_scan_from_mandible_scan`.
    Recorded,
    /// `maxilla_from_mandible` taken as the scan pose.
    Direct,
}

impl PoseSource {
    fn pose(&self, f: &FrameRecord) -> Option<Pose> {
        match self {
            PoseSource::Registration(r) => f.maxilla_from_mandible.map(|m| r.maxilla_scan_from_mandible_scan(&m)),
            PoseSource::Recorded => f.maxilla_scan_from_mandible_scan,
            PoseSource::Direct => f.maxilla_from_mandible,
        }
    }

    fn describe(&self) -> &'static str {
        match self {
            PoseSource::Registration(_) => "maxilla_from_mandible through the registration",
            PoseSource::Recorded => "the recorded maxilla_scan_from_mandible_scan",
            PoseSource::Direct => "maxilla_from_mandible as the lower scan's pose",
        }
    }
}

/// What [`check_frames`] gathered.
pub(crate) struct Tally {
    /// Frames in contact per vertex and deepest depth per vertex.
    pub map: ContactMap,
    /// Per frame checked: `frame`, t, total contact area on the maxilla and the mandible (mm²),
    /// deepest depth (mm; `None` without any region).
    pub frames: Vec<(u64, f64, [f64; 2], Option<f64>)>,
    /// Time of each frame's contact query (ms).
    pub ms: Vec<f64>,
}

/// Checks each frame, writes its line to `out` (flushed) and adds it to the map: the part of
/// the command shared by every mode; `frames` yields the poses to check, and `extras` (when
/// given, one per frame) what the dynamic mode adds to each line.
pub(crate) fn check_frames(
    upper: &Arch,
    lower: &Arch,
    settings: &ContactSettings,
    frames: impl IntoIterator<Item = PosedFrame>,
    extras: Option<&[Value]>,
    out: &mut impl Write,
    bar: &indicatif::ProgressBar,
) -> Result<Tally> {
    let mut tally = Tally { map: ContactMap::new(upper, lower), frames: Vec::new(), ms: Vec::new() };
    for (k, (frame, t, pose)) in frames.into_iter().enumerate() {
        let start = Instant::now();
        let c = contacts(upper, lower, &pose, settings);
        tally.ms.push(start.elapsed().as_secs_f64() * 1e3);
        tally.map.add(&c, settings);
        let area = |side: Side| c.regions.iter().filter(|r| r.arch == side).map(|r| r.area_mm2).sum::<f64>();
        let areas = [area(Side::Maxilla), area(Side::Mandible)];
        let mut line = json!({
            "frame": frame,
            "t": t,
            "max_depth_mm": c.max_depth_mm(),
            "area_mm2": { "maxilla": areas[0], "mandible": areas[1] },
            "regions": c.regions,
        });
        if let Some(extra) = extras.and_then(|e| e.get(k)) {
            line["dynamics"] = extra.clone();
        }
        writeln!(out, "{line}")?;
        out.flush()?;
        tally.frames.push((frame, t, areas, c.max_depth_mm()));
        bar.inc(1);
    }
    Ok(tally)
}

fn median(v: &[f64]) -> Option<f64> {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

/// Statistics of one arch's total contact area per frame.
fn area_stats(tally: &Tally, arch: usize) -> Value {
    let areas: Vec<f64> = tally.frames.iter().map(|f| f.2[arch]).collect();
    let n = areas.len().max(1) as f64;
    let largest = tally.frames.iter().max_by(|a, b| a.2[arch].total_cmp(&b.2[arch]));
    json!({
        "frames_with_contact": areas.iter().filter(|&&a| a > 0.0).count(),
        "mean_mm2": areas.iter().sum::<f64>() / n,
        "median_mm2": median(&areas),
        "max_mm2": largest.map(|f| f.2[arch]),
        "max_frame": largest.map(|f| f.0),
        "max_t": largest.map(|f| f.1),
    })
}

pub(crate) fn run(a: &ContactsArgs) -> Result<()> {
    let settings = ContactSettings { threshold_mm: a.threshold, max_depth_mm: a.max_depth };
    if let Err(e) = settings.validate() {
        let (lo, hi) = THRESHOLD_RANGE_MM;
        let flag = if (lo..=hi).contains(&settings.threshold_mm) { "--max-depth" } else { "--threshold" };
        bail!("{flag}: {e}");
    }
    let source = match &a.registration {
        Some(p) => PoseSource::Registration(Box::new(
            Registration::load(p).with_context(|| format!("reading the registration {}", p.display()))?,
        )),
        None => PoseSource::Direct,
    };
    let rec = load(&a.poses)?;
    if rec.frames.is_empty() {
        bail!(
            "{}: no frames (each line should be a frame such as {{\"frame\":0,\"t\":0,\"maxilla_from_mandible\":[16 numbers]}})",
            a.poses.display()
        );
    }
    let source = match source {
        PoseSource::Direct if rec.frames.iter().any(|f| f.maxilla_scan_from_mandible_scan.is_some()) => {
            PoseSource::Recorded
        }
        s => s,
    };
    let (mut posed, mut skipped_no_pose, mut outside_stride) = (Vec::<PosedFrame>::new(), 0usize, 0usize);
    let mut with_pose = 0u64;
    for f in &rec.frames {
        match source.pose(f) {
            None => skipped_no_pose += 1,
            Some(p) => {
                if with_pose.is_multiple_of(a.every) {
                    posed.push((f.frame, f.t, p));
                } else {
                    outside_stride += 1;
                }
                with_pose += 1;
            }
        }
    }
    let Some(&(_, _, first_pose)) = posed.first() else {
        bail!(
            "{}: none of its {} frames has a pose ({}); nothing to check",
            a.poses.display(),
            rec.frames.len(),
            source.describe()
        );
    };

    let setup = Instant::now();
    let upper_in = load_arch(Side::Maxilla, &a.maxilla, a.quiet)?;
    let lower_in = load_arch(Side::Mandible, &a.mandible, a.quiet)?;
    let (upper_reports, lower_reports) = (upper_in.reports, lower_in.reports);
    if !a.quiet {
        say!("indexing both arches for distance queries (a few seconds per 100k triangles)…");
    }
    // The two indexes are independent: build them side by side.
    let (upper, lower) = std::thread::scope(|scope| {
        let upper = scope.spawn(|| Arch::new(upper_in.parts, &settings));
        let lower = Arch::new(lower_in.parts, &settings);
        (upper.join(), lower)
    });
    let upper = upper.map_err(|_| anyhow::anyhow!("indexing the upper arch failed"))?;
    let setup_ms = setup.elapsed().as_secs_f64() * 1e3;
    if !a.quiet {
        say!("indexed in {:.1} s", setup_ms / 1e3);
    }

    let (frames, extras, dynamics_summary) = match a.mode {
        Mode::Kinematic => (posed, None, Value::Null),
        Mode::Dynamic => {
            let options = DynamicsOptions {
                mass_kg: a.mass,
                natural_frequency_hz: a.spring_hz,
                dt_s: a.dt,
                ..Default::default()
            };
            let (frames, extras, summary) = resolve_path(&upper, &lower, &posed, &options, a.quiet)?;
            (frames, Some(extras), summary)
        }
    };
    let checked = frames.len();

    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let path = a.out.join("contacts.jsonl");
    let mut out =
        std::io::BufWriter::new(std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?);
    let files = |v: &[PathBuf]| v.iter().map(|p| p.display().to_string()).collect::<Vec<_>>();
    let header = json!({ "contacts": {
        "version": 1,
        "units": "mm",
        "mode": a.mode.name(),
        "threshold_mm": settings.threshold_mm,
        "max_depth_mm": settings.max_depth_mm,
        "maxilla": files(&a.maxilla),
        "mandible": files(&a.mandible),
        "registration": a.registration.as_ref().map(|p| p.display().to_string()),
        "poses": a.poses.display().to_string(),
        "pose_source": source.describe(),
        "every": a.every,
    }});
    writeln!(out, "{header}").and_then(|()| out.flush()).with_context(|| format!("writing {}", path.display()))?;

    let bar = if a.quiet { indicatif::ProgressBar::hidden() } else { crate::progress_bar("contacts", checked) };
    let started = Instant::now();
    let tally = check_frames(&upper, &lower, &settings, frames, extras.as_deref(), &mut out, &bar)
        .with_context(|| format!("writing {}", path.display()))?;
    bar.finish_and_clear();
    let total_s = started.elapsed().as_secs_f64();

    // Depth colours run up to the deepest penetration seen, at least the threshold.
    let deepest = tally.frames.iter().filter_map(|f| f.3.map(|d| (d, f.0, f.1))).max_by(|a, b| a.0.total_cmp(&b.0));
    let full_depth = deepest.map_or(0.0, |d| d.0).max(settings.threshold_mm);
    let mut written = vec![path.clone()];
    for (k, (arch, name)) in [(&upper, "maxilla"), (&lower, "mandible")].into_iter().enumerate() {
        for (what, colours) in [
            ("frequency", tally.map.frequency_colours(k)),
            ("depth", tally.map.depth_colours(k, &settings, full_depth)),
        ] {
            let p = a.out.join(format!("{name}_{what}.ply"));
            arch.mesh.write_coloured_ply(&p, &colours)?;
            written.push(p);
        }
    }
    // Occlusal views, each from the other arch's side at the first frame's pose.
    let views = View::occlusal_pair(&upper.mesh, &lower.mesh, &first_pose, 800);
    for (k, (arch, name)) in [(&upper, "maxilla"), (&lower, "mandible")].into_iter().enumerate() {
        let image =
            occlusal_view::with_legend(&occlusal_view::render(&arch.mesh, &tally.map.frequency_colours(k), &views[k]));
        let p = a.out.join(format!("{name}_occlusal.png"));
        image.save(&p).with_context(|| format!("writing {}", p.display()))?;
        written.push(p);
    }

    let with_contact = tally.frames.iter().filter(|f| f.3.is_some()).count();
    let penetrating = tally.frames.iter().filter(|f| f.3.is_some_and(|d| d > 0.0)).count();
    let ms_median = median(&tally.ms);
    let summary = json!({
        "frames": {
            "read": rec.frames.len(),
            "checked": checked,
            "skipped_no_pose": skipped_no_pose,
            "outside_stride": outside_stride,
            "unreadable_lines": rec.skipped.len(),
            "with_contact": with_contact,
            "penetrating": penetrating,
        },
        "settings": {
            "mode": a.mode.name(),
            "threshold_mm": settings.threshold_mm,
            "max_depth_mm": settings.max_depth_mm,
            "every": a.every,
            "registration": a.registration.as_ref().map(|p| p.display().to_string()),
            "poses": a.poses.display().to_string(),
            "pose_source": source.describe(),
        },
        "meshes": { "maxilla": upper_reports, "mandible": lower_reports },
        "contact_area": { "maxilla": area_stats(&tally, 0), "mandible": area_stats(&tally, 1) },
        "dynamics": dynamics_summary,
        "deepest": deepest.map(|(d, frame, t)| json!({ "depth_mm": d, "frame": frame, "t": t })),
        "depth_colour_full_scale_mm": full_depth,
        "timing": {
            "setup_ms": setup_ms,
            "ms_per_frame_median": ms_median,
            "ms_per_frame_max": tally.ms.iter().copied().reduce(f64::max),
            "total_s": total_s,
        },
    });
    let p = a.out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).context("summary")?;
    std::fs::write(&p, text + "\n").with_context(|| format!("writing {}", p.display()))?;
    written.push(p);

    let skipped =
        if skipped_no_pose > 0 { format!(", {skipped_no_pose} without a pose skipped") } else { String::new() };
    say!(
        "{checked} frames checked of {}{skipped}; {with_contact} within {} mm, {penetrating} penetrating",
        rec.frames.len(),
        settings.threshold_mm
    );
    match deepest {
        Some((d, frame, t)) if d > 0.0 => say!("deepest penetration {d:.3} mm at frame {frame} (t {t:.3} s)"),
        Some((d, frame, t)) => say!("no penetration; smallest gap {:.3} mm at frame {frame} (t {t:.3} s)", -d),
        None => say!("no contact within {} mm", settings.threshold_mm),
    }
    say!("median {:.1} ms per frame (index build {:.0} ms)", ms_median.unwrap_or(0.0), setup_ms);
    for p in &written {
        say!("wrote {}", p.display());
    }
    Ok(())
}
