//! A whole `jawtrack contacts` run: the frames with the scans' pose picked, both arches read and
//! indexed, the dynamic mode's simulated slide, every frame checked into `contacts.jsonl` (a
//! header line, then one line per frame, flushed as written), the meshes, views and maps
//! ([`write_outputs`]) and `summary.json` with per-tooth totals. What happens on the way is told
//! to a [`ContactEvents`], so the command can print it and draw its progress.

use crate::SessionError;
use crate::anatomy::upper_scan_left;
use crate::arches::{ArchInput, load_arch, tooth_places};
use crate::contacts::{fingerprint, write_outputs};
use crate::json::clean_json;
use crate::scan_pose::{PoseSource, PosedFrame};
use jawtrack_occlusion::Mesh;
use jawtrack_occlusion::contacts::{Arch, ContactSettings};
use jawtrack_occlusion::dynamics::{self, DynamicsOptions, PathSummary, StepSummary};
use jawtrack_occlusion::session::{ContactSession, SessionSummary};
use jawtrack_occlusion::teeth::{ToothTotal, ToothTotals};
use jawtrack_pose::Pose;
use jawtrack_recording::Recording;
use serde_json::{Value, json};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The files `jawtrack contacts` refuses to write over without `--force`.
pub const RESULT_FILES: [&str; 2] = ["contacts.jsonl", "summary.json"];

/// What a run is asked to do: its inputs, as named on the command line, and its settings.
#[derive(Debug, Clone)]
pub struct ContactJob<'a> {
    /// The upper arch's files (one, or one per tooth).
    pub maxilla: &'a [PathBuf],
    /// The lower arch's files.
    pub mandible: &'a [PathBuf],
    /// The recording the poses come from.
    pub poses: &'a Path,
    /// The registration file, when one was given (named in the header).
    pub registration: Option<&'a Path>,
    /// The anatomical points file: where the patient's left is on the maps.
    pub points: Option<&'a Path>,
    /// The contact threshold and deepest depth measured.
    pub settings: ContactSettings,
    /// The dynamic mode's options; `None` for the kinematic mode.
    pub dynamics: Option<DynamicsOptions>,
    /// Check every n-th frame with a pose (1 or more).
    pub every: u64,
    /// The output folder (created).
    pub out: &'a Path,
}

/// What a run tells as it goes; every method does nothing unless the caller wants it.
pub trait ContactEvents {
    /// A mesh was read: "maxilla FILE: REPORT".
    fn mesh(&mut self, _line: &str) {}
    /// Both arches are being indexed for distance queries.
    fn indexing(&mut self) {}
    /// Both arches were indexed in `_seconds`.
    fn indexed(&mut self, _seconds: f64) {}
    /// A stage over `_total` items begins: `"simulating"` (the dynamic mode) or `"contacts"`.
    fn begin(&mut self, _what: &'static str, _total: usize) {}
    /// `_done` items of the current stage are done.
    fn progress(&mut self, _done: usize) {}
    /// The current stage is over.
    fn end(&mut self) {}
    /// The dynamic mode resolved the recorded path.
    fn simulated(&mut self, _summary: &PathSummary) {}
    /// Something the reader should know (e.g. that the maps cannot tell left from right).
    fn warning(&mut self, _warning: &str) {}
}

/// What a run found and wrote.
#[derive(Debug)]
pub struct ContactReport {
    /// The session's totals: frames checked, with contact, penetrating, the deepest contact.
    pub summary: SessionSummary,
    /// Per tooth: frames in contact, largest area, deepest contact.
    pub teeth: Vec<ToothTotal>,
    /// Frames in the recording.
    pub read: usize,
    /// Frames without the scans' pose, skipped.
    pub skipped_no_pose: usize,
    /// Reading and indexing the arches (ms).
    pub setup_ms: f64,
    /// Every file written, in order.
    pub written: Vec<PathBuf>,
}

/// The frames of `rec` with the scans' pose, every `every`-th of them, and how many were left
/// out: without a pose, and between the strides. Refuses a recording with none, naming it.
pub fn select(
    rec: &Recording,
    source: &PoseSource,
    every: u64,
    poses: &Path,
) -> Result<(Vec<PosedFrame>, usize, usize), SessionError> {
    let with_pose = source.posed(rec);
    let posed: Vec<PosedFrame> = with_pose.iter().copied().step_by(every.max(1) as usize).collect();
    if posed.is_empty() {
        return Err(SessionError::NoScanPose(format!(
            "{}: none of its {} frames has a pose ({}); nothing to check",
            poses.display(),
            rec.frames.len(),
            source.describe()
        )));
    }
    let counts = (rec.frames.len() - with_pose.len(), with_pose.len() - posed.len());
    Ok((posed, counts.0, counts.1))
}

/// Builds both arches' distance indexes, side by side (they are independent).
pub fn index_arches(
    upper: Vec<(String, Mesh)>,
    lower: Vec<(String, Mesh)>,
    settings: &ContactSettings,
) -> Result<(Arch, Arch), SessionError> {
    let (upper, lower) = std::thread::scope(|scope| {
        let upper = scope.spawn(|| Arch::new(upper, settings));
        let lower = Arch::new(lower, settings);
        (upper.join(), lower)
    });
    let upper = upper.map_err(|_| SessionError::Setting("indexing the upper arch failed".into()))?;
    Ok((upper, lower))
}

/// Runs `job` over `rec`, the scans placed by `source`: see the [module](self) documentation.
///
/// # Examples
///
/// ```no_run
/// use jawtrack_session::contact_run::{ContactEvents, ContactJob, run};
/// use jawtrack_session::PoseSource;
/// use std::path::{Path, PathBuf};
/// struct Quiet;
/// impl ContactEvents for Quiet {}
/// # fn main() -> Result<(), jawtrack_session::SessionError> {
/// let opened = jawtrack_session::open(Path::new("session.jsonl"), None)?;
/// let source = PoseSource::required(&opened.recording, None)?;
/// let (upper, lower) = ([PathBuf::from("upper.stl")], [PathBuf::from("lower.stl")]);
/// let job = ContactJob {
///     maxilla: &upper,
///     mandible: &lower,
///     poses: Path::new("session.jsonl"),
///     registration: None,
///     points: None,
///     settings: Default::default(),
///     dynamics: None,
///     every: 1,
///     out: Path::new("contacts"),
/// };
/// let found = run(&job, &opened.recording, &source, &mut Quiet)?;
/// println!("{} frames checked, {} in contact", found.summary.frames, found.summary.with_contact);
/// # Ok(()) }
/// ```
pub fn run(
    job: &ContactJob,
    rec: &Recording,
    source: &PoseSource,
    events: &mut dyn ContactEvents,
) -> Result<ContactReport, SessionError> {
    let (posed, skipped_no_pose, outside_stride) = select(rec, source, job.every, job.poses)?;
    let first_pose = posed[0].2;
    let setup = Instant::now();
    let mut read_arch = |side, files| -> Result<ArchInput, SessionError> {
        let arch = load_arch(side, files)?;
        arch.lines.iter().for_each(|l| events.mesh(l));
        Ok(arch)
    };
    let ArchInput { parts: upper_parts, reports: upper_reports, .. } = read_arch("maxilla", job.maxilla)?;
    let ArchInput { parts: lower_parts, reports: lower_reports, .. } = read_arch("mandible", job.mandible)?;
    let teeth = [tooth_places(&upper_parts), tooth_places(&lower_parts)];
    let upper_left = upper_scan_left(job.points)?;
    events.indexing();
    let started = Instant::now();
    let (upper, lower) = index_arches(upper_parts, lower_parts, &job.settings)?;
    events.indexed(started.elapsed().as_secs_f64());
    let setup_ms = setup.elapsed().as_secs_f64() * 1e3;

    let (frames, extras, dynamics_summary) = match &job.dynamics {
        None => (posed, Vec::new(), Value::Null),
        Some(options) => resolve(&upper, &lower, &posed, options, events)?,
    };
    let run_settings = settings_json(job, source);
    let (path, per_tooth, session, total_s) =
        check_frames(job, &run_settings, ContactSession::new(&upper, &lower, job.settings), &frames, &extras, events)?;

    let s = session.summary();
    let warnings = run_warnings(&s, &job.settings, events);
    let more = write_outputs(job.out, &session, [&upper, &lower], &first_pose, [&teeth[0], &teeth[1]], upper_left)?;
    more.warnings.iter().for_each(|w| events.warning(w));
    let mut written = vec![path];
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
        "recording": fingerprint(rec, &file_name(job.poses)),
        "warnings": warnings,
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
    let p = job.out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).map_err(|e| write_error(&p, &e))?;
    std::fs::write(&p, text + "\n").map_err(|e| write_error(&p, &e))?;
    written.push(p);
    Ok(ContactReport { summary: s, teeth: teeth_totals, read: rec.frames.len(), skipped_no_pose, setup_ms, written })
}

/// What the session's numbers cannot say, for `summary.json`; those the command does not
/// already print (the depth cut off at `--max-depth`) are told to `events` too.
fn run_warnings(s: &SessionSummary, settings: &ContactSettings, events: &mut dyn ContactEvents) -> Vec<String> {
    let depth = s.depth_warning(settings);
    depth.iter().for_each(|w| events.warning(w));
    // The command prints its own warning when nothing came within the threshold
    // (`jawtrack_report::contact_findings`); the report reads this one from the folder.
    depth.into_iter().chain(s.no_contact_warning(settings)).collect()
}

/// A path's file name, else the path as given.
fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(|| path.display().to_string(), |f| f.to_string_lossy().into_owned())
}

/// The settings that the header and `summary.json` both hold, and the inputs.
fn settings_json(job: &ContactJob, source: &PoseSource) -> Value {
    json!({
        "mode": if job.dynamics.is_some() { "dynamic" } else { "kinematic" },
        "threshold_mm": job.settings.threshold_mm,
        "max_depth_mm": job.settings.max_depth_mm,
        "every": job.every,
        "registration": job.registration.map(|p| p.display().to_string()),
        "poses": job.poses.display().to_string(),
        "pose_source": source.describe(),
    })
}

/// `contacts.jsonl`'s first line: the run's settings, the schema's version and units, the files.
fn header_json(job: &ContactJob, run_settings: &Value) -> Value {
    let mut header = run_settings.clone();
    let files = |v: &[PathBuf]| json!(v.iter().map(|p| p.display().to_string()).collect::<Vec<_>>());
    (header["version"], header["units"]) = (json!(1), json!("mm"));
    (header["maxilla"], header["mandible"]) = (files(job.maxilla), files(job.mandible));
    json!({ "contacts": header })
}

fn write_error(path: &Path, e: &dyn std::fmt::Display) -> SessionError {
    SessionError::Write { path: path.display().to_string(), reason: e.to_string() }
}

/// The dynamic mode: the recorded path resolved by the rigid-body simulation; per frame the
/// resolved pose and what its line adds, and the summary.
fn resolve(
    upper: &Arch,
    lower: &Arch,
    posed: &[PosedFrame],
    options: &DynamicsOptions,
    events: &mut dyn ContactEvents,
) -> Result<(Vec<PosedFrame>, Vec<Value>, Value), SessionError> {
    let target: Vec<(f64, Pose)> = posed.iter().map(|&(_, t, p)| (t, p)).collect();
    events.begin("simulating", posed.len());
    let path = dynamics::resolve_path(upper, lower, &target, options, &mut |done, _| events.progress(done))
        .map_err(SessionError::Dynamics)?;
    events.end();
    let s = path.summary();
    events.simulated(&s);
    let frames = posed.iter().zip(&path.steps).map(|(&(frame, t, _), s)| (frame, t, s.maxilla_scan_from_mandible_scan));
    let extras = path.steps.iter().map(|s| json!(StepSummary::from(s))).collect();
    Ok((frames.collect(), extras, json!(s)))
}

/// Writes the header and every frame's contacts into `contacts.jsonl`, each line flushed as
/// written; the file, the per-tooth totals, the session and the time it took (s).
fn check_frames<'a>(
    job: &ContactJob,
    run_settings: &Value,
    mut session: ContactSession<'a>,
    frames: &[PosedFrame],
    extras: &[Value],
    events: &mut dyn ContactEvents,
) -> Result<(PathBuf, ToothTotals, ContactSession<'a>, f64), SessionError> {
    let create =
        |p: &Path, e: std::io::Error| SessionError::Io { context: format!("creating {}", p.display()), source: e };
    std::fs::create_dir_all(job.out).map_err(|e| create(job.out, e))?;
    let path = job.out.join("contacts.jsonl");
    let mut out = std::io::BufWriter::new(std::fs::File::create(&path).map_err(|e| create(&path, e))?);
    let mut write_line = |line: &Value| {
        writeln!(out, "{line}")
            .and_then(|()| out.flush())
            .map_err(|e| SessionError::Io { context: format!("writing {}", path.display()), source: e })
    };
    write_line(&header_json(job, run_settings))?;
    events.begin("contacts", frames.len());
    let started = Instant::now();
    let mut per_tooth = ToothTotals::default();
    for (k, (frame, t, pose)) in frames.iter().enumerate() {
        let found = session.check(*frame, *t, pose);
        per_tooth.add(&found.regions);
        let mut line = json!(found);
        if let Some(extra) = extras.get(k) {
            line["dynamics"] = extra.clone();
        }
        write_line(&line)?;
        events.progress(k + 1);
    }
    events.end();
    Ok((path, per_tooth, session, started.elapsed().as_secs_f64()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_header_repeats_the_settings_and_names_the_inputs() {
        let (upper, lower) = ([PathBuf::from("u.stl")], [PathBuf::from("a.stl"), PathBuf::from("b.stl")]);
        let job = ContactJob {
            maxilla: &upper,
            mandible: &lower,
            poses: Path::new("p.jsonl"),
            registration: Some(Path::new("reg.json")),
            points: None,
            settings: ContactSettings::default(),
            dynamics: Some(DynamicsOptions::default()),
            every: 2,
            out: Path::new("out"),
        };
        let settings = settings_json(&job, &PoseSource::Direct);
        assert_eq!(settings["mode"], "dynamic");
        assert_eq!(settings["every"], 2);
        assert_eq!(settings["registration"], "reg.json");
        let header = header_json(&job, &settings);
        let h = &header["contacts"];
        assert_eq!((h["version"].as_u64(), h["units"].as_str()), (Some(1), Some("mm")));
        assert_eq!(h["mandible"], json!(["a.stl", "b.stl"]));
        assert_eq!(h["pose_source"], PoseSource::Direct.describe());
    }

    #[test]
    fn a_recording_without_the_scans_pose_is_refused_naming_the_file() {
        let rec = Recording::default();
        let err = select(&rec, &PoseSource::Recorded, 1, Path::new("p.jsonl")).expect_err("no frames");
        assert!(err.to_string().starts_with("p.jsonl: none of its 0 frames has a pose"), "{err}");
    }

    /// Warnings told as a run goes.
    #[derive(Default)]
    struct Told(Vec<String>);

    impl ContactEvents for Told {
        fn warning(&mut self, warning: &str) {
            self.0.push(warning.to_string());
        }
    }

    #[test]
    fn a_run_past_the_depth_measured_warns_and_its_summary_names_the_recording() {
        use jawtrack_occlusion::scenes;
        use nalgebra::Point3;
        let dir = tempfile::tempdir().expect("temporary folder");
        let (upper, lower) = ([dir.path().join("patch.stl")], [dir.path().join("ball.stl")]);
        scenes::patch(10.0, 40, 0.0, true).write_stl_file(&upper[0]).expect("written");
        scenes::sphere(Point3::new(0.0, 0.0, -3.0), 3.0, 40).write_stl_file(&lower[0]).expect("written");
        // The ball's top 0.2 mm, then 1 mm, through the patch: past the 0.5 mm measured.
        let lines: Vec<String> = [(0, 0.2), (1, 1.0)]
            .iter()
            .map(|(i, z)| {
                format!(r#"{{"frame":{i},"t":{i},"maxilla":null,"mandible":null,"maxilla_from_mandible":[1,0,0,0,0,1,0,0,0,0,1,{z},0,0,0,1]}}"#)
            })
            .collect();
        let rec = jawtrack_recording::read_recording(lines.join("\n").as_bytes()).expect("a recording");
        let out = dir.path().join("contacts");
        let job = ContactJob {
            maxilla: &upper,
            mandible: &lower,
            poses: Path::new("pushed.jsonl"),
            registration: None,
            points: None,
            settings: ContactSettings::default(),
            dynamics: None,
            every: 1,
            out: &out,
        };
        let mut told = Told::default();
        let found = run(&job, &rec, &PoseSource::Direct, &mut told).expect("a run");
        assert_eq!((found.summary.frames, found.summary.beyond_max_depth), (2, 1));
        let depth =
            told.0.iter().find(|w| w.starts_with("deepest contact reached --max-depth 0.5 mm in 1 of 2 frames"));
        assert!(depth.is_some_and(|w| w.ends_with("raise --max-depth or check the registration")), "{:?}", told.0);
        let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
        let summary: Value = serde_json::from_str(&text).expect("JSON");
        assert_eq!(summary["warnings"][0].as_str(), depth.map(String::as_str));
        assert_eq!(summary["recording"]["name"], "pushed.jsonl");
        assert_eq!(crate::contacts::check_matches(&summary, &rec, "pushed.jsonl").expect("the same recording"), None);
        let lines = std::fs::read_to_string(out.join("contacts.jsonl")).expect("contacts.jsonl");
        let flags: Vec<Option<bool>> = lines
            .lines()
            .skip(1)
            .map(|l| serde_json::from_str::<Value>(l).expect("JSON")["beyond_max_depth"].as_bool())
            .collect();
        assert_eq!(flags, [None, Some(true)]);
    }
}
