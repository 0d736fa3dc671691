//! The jaw tracked in the rendered session with each marker file and compared with the ground
//! truth; the incisor's motion, its plotted path and the session's report.

use crate::{DemoError, pick};
use jawtrack_apriltag::{DetectorConfig, ImageView};
use jawtrack_kinematics::metrics::count_openings;
use jawtrack_kinematics::{Incisor, Metrics, Sample};
use jawtrack_marker::Marker;
use jawtrack_plot::{self as plot, Series, Style};
use jawtrack_pose::Pose;
use jawtrack_recording::{Overwrite, RecordingHeader, RecordingWriter};
use jawtrack_synth::GroundTruth;
use jawtrack_tracker::{Tracker, TrackerConfig};
use std::fmt;
use std::path::{Path, PathBuf};

/// The marker files the demo tracks with, each with its label and the recording it writes:
/// the nominal one (what a user has before calibration), the `calibrated` one, and the marker
/// as printed (the truth's: the limit of calibration).
pub fn markers(
    truth: &GroundTruth,
    calibrated: Marker,
) -> Result<[(&'static str, Marker, &'static str); 3], DemoError> {
    let printed = Marker::from_json(&truth.true_marker.to_string()).map_err(DemoError::PrintedMarker)?;
    Ok([
        ("nominal marker file", Marker::default(), "poses.jsonl"),
        ("calibrated marker file", calibrated, "poses_calibrated.jsonl"),
        ("marker as printed (truth)", printed, "poses_printed_marker.jsonl"),
    ])
}

/// One marker file's tracking of the session against the truth.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackingCheck {
    /// Which marker file.
    pub label: &'static str,
    /// Frames with a jaw pose.
    pub posed: usize,
    /// Frames in the session.
    pub frames: usize,
    /// The mandible-in-maxilla error (mm): median and worst.
    pub error_mm: [f64; 2],
    /// The same in rotation (°): median and worst.
    pub error_deg: [f64; 2],
    /// Detection and pose time per frame (ms, median).
    pub ms_median: f64,
    /// The recording written.
    pub poses: PathBuf,
}

impl fmt::Display for TrackingCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "tracking, {}: jaw pose in {} of {} frames; mandible-in-maxilla error median {:.3} mm / {:.3}°, worst {:.3} mm / {:.3}°; {:.1} ms per frame; poses in {}",
            self.label,
            self.posed,
            self.frames,
            self.error_mm[0],
            self.error_deg[0],
            self.error_mm[1],
            self.error_deg[1],
            self.ms_median,
            self.poses.display()
        )
    }
}

/// Tracks the rendered session in `dir` with `marker`, writes the poses to `file` in `dir`
/// (replacing an earlier run's) and compares the mandible in the maxilla with the `truth`.
pub fn track_against_truth(
    dir: &Path,
    truth: &GroundTruth,
    label: &'static str,
    marker: Marker,
    file: &str,
) -> Result<TrackingCheck, DemoError> {
    let config = TrackerConfig {
        detector: DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() },
        ..TrackerConfig::default()
    };
    let mut tracker = Tracker::new(marker, config)?;
    let poses = dir.join(file);
    let mut header = RecordingHeader::new("jawtrack demo");
    header.intrinsics = Some(truth.intrinsics);
    header.marker = serde_json::from_str(&tracker.marker().to_json()).ok();
    // The demo's own output folder: a second run replaces the first's files.
    let mut out = RecordingWriter::create(&poses, header, Overwrite::Replace)?;
    let (mut dt, mut dr, mut ms) = (Vec::new(), Vec::new(), Vec::new());
    for (i, f) in truth.frames.iter().enumerate() {
        let img = image::open(dir.join(&f.file))?.to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let r = tracker.track(&ImageView::new(img.as_raw(), w, h, w)?, &truth.intrinsics, f.t)?;
        ms.push((r.timings.detection_s + r.timings.pose_s) * 1e3);
        out.append(&r.to_record(i, Some(&f.file)))?;
        if let Some(m) = r.maxilla_from_mandible {
            let (angle, dist) = m.distance_to(&f.maxilla_from_mandible);
            dt.push(dist);
            dr.push(angle.to_degrees());
        }
    }
    for v in [&mut dt, &mut dr, &mut ms] {
        v.sort_by(f64::total_cmp);
    }
    Ok(TrackingCheck {
        label,
        posed: dt.len(),
        frames: truth.frames.len(),
        error_mm: [pick(&dt, 0.5), pick(&dt, 1.0)],
        error_deg: [pick(&dr, 0.5), pick(&dr, 1.0)],
        ms_median: pick(&ms, 0.5),
        poses,
    })
}

/// The lower incisor's path in the truth: the standard incisal point's displacement from the
/// first frame's jaw (closed), as [`jawtrack_session::incisor::path`] measures a recording.
fn truth_path(truth: &GroundTruth) -> Vec<Sample> {
    let incisor = Incisor::standard();
    let Some(rest) = truth.frames.first().map(|f| f.maxilla_from_mandible) else {
        return Vec::new();
    };
    truth
        .frames
        .iter()
        .enumerate()
        .map(|(i, f)| (f.t, i as u64, incisor.displacement(&f.maxilla_from_mandible, &rest)))
        .collect()
}

/// The lower incisor's path in a recording, measured as `jawtrack metrics FILE` measures it
/// with its defaults (the standard incisal point, from the rest position).
pub fn recorded_path(poses: &Path) -> Result<Vec<Sample>, DemoError> {
    let rec = jawtrack_session::open(poses, None)?.recording;
    let Some(rest) = jawtrack_session::rest_of(&rec, None)? else {
        return Err(DemoError::NoJawPose(poses.display().to_string()));
    };
    Ok(jawtrack_session::incisor::path(&rec.frames, &Incisor::standard(), &rest.pose()))
}

/// The lower incisor's motion in plain numbers, tracked against the truth, each measure as
/// `docs/kinematics.md` defines it (the numbers `jawtrack metrics` and the report give).
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// The recording measured.
    pub recording: PathBuf,
    /// How many times it opened.
    pub openings: usize,
    /// Maximum opening (mm): the incisal point's largest downward displacement from rest.
    pub max_opening_mm: f64,
    /// The same in the truth (mm).
    pub truth_max_opening_mm: f64,
    /// How far back it swung (mm) about the condyles: the largest backward displacement.
    pub back_mm: f64,
}

impl Motion {
    /// The motion of the lower incisor in `tracked` (a recording file), and the truth's
    /// maximum opening.
    pub fn of(truth: &GroundTruth, tracked: &Path) -> Result<Motion, DemoError> {
        let path = recorded_path(tracked)?;
        let measured = Metrics::compute(&path).ok_or_else(|| DemoError::NoJawPose(tracked.display().to_string()))?;
        let real = Metrics::compute(&truth_path(truth)).map_or(0.0, |m| m.max_opening.mm);
        Ok(Motion {
            recording: tracked.to_path_buf(),
            openings: count_openings(&path.iter().map(|(_, _, d)| *d).collect::<Vec<_>>()),
            max_opening_mm: measured.max_opening.mm,
            truth_max_opening_mm: real,
            back_mm: path.iter().map(|(_, _, d)| -d.protrusive).fold(0.0, f64::max),
        })
    }
}

impl fmt::Display for Motion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "The jaw, measured from {} as `jawtrack metrics` and the report measure it: the lower incisor opened {} times, maximum opening {:.1} mm (downward from the closed jaw; truth {:.1} mm), and it swung back by up to {:.1} mm about the condyles.",
            self.recording.display(),
            self.openings,
            self.max_opening_mm,
            self.truth_max_opening_mm,
            self.back_mm,
        )
    }
}

/// Writes the incisor's opening over time and its sagittal path (SVG), the truth and each
/// tracking, each measured from its own closed jaw as [`Motion`] measures it; returns the files.
pub fn plot_incisor(dir: &Path, truth: &GroundTruth, tracked: &[TrackingCheck]) -> Result<Vec<PathBuf>, DemoError> {
    let truth = truth_path(truth);
    let paths = tracked.iter().map(|c| recorded_path(&c.poses)).collect::<Result<Vec<_>, _>>()?;
    let colors = ["#d62728", "#2ca02c", "#1f77b4"];
    let series = |f: &dyn Fn(&Sample) -> (f64, f64)| {
        let mut v =
            vec![Series { name: "truth", color: "#222", style: Style::Line, points: truth.iter().map(f).collect() }];
        for ((c, path), color) in tracked.iter().zip(&paths).zip(colors) {
            v.push(Series { name: c.label, color, style: Style::Dots, points: path.iter().map(f).collect() });
        }
        v
    };
    let opening = plot::chart(
        "Lower incisor: opening (downward from the closed jaw)",
        "time (s)",
        "opening (mm)",
        &series(&|(t, _, d)| (*t, d.opening)),
        false,
    );
    let sagittal = plot::chart(
        "Lower incisor path, sagittal plane (seen from the patient's right: facing right)",
        "protrusive (mm)",
        "up (mm)",
        &series(&|(_, _, d)| (d.protrusive, -d.opening)),
        true,
    );
    let mut written = Vec::new();
    for (name, doc) in [("incisor_opening.svg", opening), ("incisor_sagittal.svg", sagittal)] {
        let p = dir.join(name);
        svg::save(&p, &doc).map_err(|source| DemoError::Io { context: format!("writing {}", p.display()), source })?;
        written.push(p);
    }
    Ok(written)
}

/// The session report of the calibrated marker's tracking, with the hinge axis of its
/// openings (`jawtrack report` on the same file does the same).
pub fn write_report(dir: &Path) -> Result<PathBuf, DemoError> {
    let poses = dir.join("poses_calibrated.jsonl");
    let rec = jawtrack_recording::open(&poses)?;
    let posed: Vec<(f64, Pose)> = rec.frames.iter().filter_map(|f| Some((f.t, f.maxilla_from_mandible?))).collect();
    let (Some(&(from, rest)), Some(&(to, _))) = (posed.first(), posed.last()) else {
        return Err(DemoError::NoJawPose(poses.display().to_string()));
    };
    let standard = jawtrack_session::anatomy(None, None, &rest)?;
    let inputs = jawtrack_report::Inputs {
        recording: &rec,
        recording_name: "poses_calibrated.jsonl".into(),
        anatomy: standard,
        points_file: None,
        registration_file: None,
        rest,
        rest_words: "the first frame (the jaw closed)".into(),
        windows: jawtrack_report::Windows {
            opening: Some(jawtrack_kinematics::Window { from, to }),
            ..jawtrack_report::Windows::default()
        },
        centric: None,
        contacts: None,
        made_unix_s: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64()),
    };
    let path = dir.join("report.html");
    std::fs::write(&path, jawtrack_report::render(&inputs).html)
        .map_err(|source| DemoError::Io { context: format!("writing {}", path.display()), source })?;
    Ok(path)
}
