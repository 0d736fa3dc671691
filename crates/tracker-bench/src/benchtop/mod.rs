//! The benchtop experiments of the 2020 thesis, rendered with exact ground truth: a static
//! grid (camera azimuth 0/30/60° × distance 80/100/120 mm, on a tripod and hand-held), an
//! articulator-style hinge (rounds of 10/20/30/40 mm openings) and excursions (left, right,
//! protrusive glides).
//!
//! The marker is first calibrated from a separate calibration recording of the same printed
//! marker (never from the frames it is judged on). Every frame then goes through our tracker
//! and, when the `reference` feature is on and OpenCV is installed, through the reference
//! stack (AprilTag C + OpenCV SQPnP), each with three marker files: the nominal one, the
//! calibrated one and the marker as printed (the limit calibration can reach). The tables are
//! pure functions of the run: per static view the mean and SD of the error along the head's
//! axes; per opening and per glide a regression of the tracked incisor path on the true one
//! (r², standard error); flips.
//!
//! Errors are of `maxilla_from_mandible` and are expressed along the head's axes (X the
//! patient's left, Y down, Z posterior). Orientation errors are the error rotation's
//! components about those axes. The thesis gave Z-Y-Z Euler angle differences, but at rest
//! the two markers are parallel, where Z-Y-Z angles are singular (β = 0 leaves α and γ
//! undefined). To first order, the components equal the Euler-angle errors about the same axes.

pub mod capture;
pub mod chew;
pub mod hinge_axis;
mod session;
mod stages;
mod tables;
pub mod tone;

pub use session::{SessionSummary, report as session_report};
pub use tables::*;

use crate::frames::Request;
#[cfg(feature = "reference")]
use crate::{opencv::OpenCv, reference};
use anyhow::{Context, Result, bail};
use jawtrack_apriltag::{Detection, DetectorConfig, ImageView};
#[cfg(feature = "reference")]
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use jawtrack_marker::Marker;
use jawtrack_pose::{CameraIntrinsics, Pose};
use jawtrack_synth::SceneKind;
use jawtrack_synth::scenes::{JawMotion, View};
use jawtrack_tracker::{Tracker, TrackerConfig};
use std::path::PathBuf;

/// An orientation error above this is a flip (°).
pub const FLIP_DEG: f64 = 1.0;

/// The bite step uses the calibration recording's level views within this of the front (°).
const BITE_AZIMUTH_DEG: f64 = 45.0;

/// Frame rate of the still scenes (static, calibration): it only spaces their frames in time.
const STILL_FPS: f64 = 30.0;

/// Which pipeline made an estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stack {
    /// Our detector and tracker.
    Ours,
    /// AprilTag C 3.4.5, then OpenCV's SQPnP per body.
    Reference,
}

/// Which marker file the pipeline was given.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerFile {
    /// The ideal dodecahedron: what a user has before calibrating.
    Nominal,
    /// Calibrated from the calibration recording.
    Calibrated,
    /// Calibrated, then the maximal-intercuspation step of the clinical workflow: the jaw is
    /// closed in the calibration recording, and the mean of the stack's own poses in its
    /// frontal views is mapped onto the scanned bite (the true rest pose). Removes the constant offset a
    /// calibration cannot see: where the tags sit, as a whole, on the solid.
    CalibratedBite,
    /// The marker as printed (the renderer's truth): what a perfect calibration would give.
    Printed,
    /// Calibrated from the calibration recording's front faces only (no face below the
    /// marker's equator): the tags a session then shows below are left nominal.
    FrontOnly,
    /// Calibrated, then refined from the judged scene itself (`jawtrack track --refine-marker`).
    Refined,
    /// Front faces only, then refined from the judged scene itself.
    FrontOnlyRefined,
}

impl MarkerFile {
    /// The four both stacks run, in the order of the columns.
    pub const ALL: [MarkerFile; 4] =
        [MarkerFile::Nominal, MarkerFile::Calibrated, MarkerFile::CalibratedBite, MarkerFile::Printed];

    /// The session-refinement cases, our stack only, after `ALL`.
    pub const SESSION: [MarkerFile; 3] = [MarkerFile::FrontOnly, MarkerFile::Refined, MarkerFile::FrontOnlyRefined];

    /// Its name in tables.
    pub fn name(self) -> &'static str {
        match self {
            MarkerFile::Nominal => "nominal marker",
            MarkerFile::Calibrated => "calibrated marker",
            MarkerFile::CalibratedBite => "calibrated marker + bite step",
            MarkerFile::Printed => "marker as printed",
            MarkerFile::FrontOnly => "front-faces calibration",
            MarkerFile::Refined => "calibrated + session refinement",
            MarkerFile::FrontOnlyRefined => "front-faces calibration + session refinement",
        }
    }

    /// Its name in file names and CSV.
    pub fn slug(self) -> &'static str {
        match self {
            MarkerFile::Nominal => "nominal",
            MarkerFile::Calibrated => "calibrated",
            MarkerFile::CalibratedBite => "calibrated_bite",
            MarkerFile::Printed => "printed",
            MarkerFile::FrontOnly => "front_only",
            MarkerFile::Refined => "refined",
            MarkerFile::FrontOnlyRefined => "front_only_refined",
        }
    }
}

/// One pipeline with one marker file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Column {
    /// The pipeline.
    pub stack: Stack,
    /// The marker file.
    pub marker: MarkerFile,
}

impl Column {
    /// "ours, calibrated marker".
    pub fn name(&self) -> String {
        let stack = match self.stack {
            Stack::Ours => "ours",
            Stack::Reference => "reference",
        };
        format!("{stack}, {}", self.marker.name())
    }

    /// "ours_calibrated": for file names and CSV.
    pub fn slug(&self) -> String {
        let stack = match self.stack {
            Stack::Ours => "ours",
            Stack::Reference => "reference",
        };
        format!("{stack}_{}", self.marker.slug())
    }
}

/// What to render and run.
#[derive(Debug, Clone)]
pub struct Options {
    /// Seed of everything random (print errors, noise, tremor).
    pub seed: u64,
    /// Frames per view of the calibration recording (18 views).
    pub calibration_frames_per_view: usize,
    /// Frames per static view (18 views: 3 angles × 3 distances × tripod, hand).
    pub frames_per_view: usize,
    /// Rounds of the four hinge openings (the thesis: 30).
    pub hinge_cycles: usize,
    /// Glides per direction.
    pub excursion_cycles: usize,
    /// Frame rate of the hinge and excursions (frames/s).
    pub fps: f64,
    /// At most this many frames per judged scene (a smoke run).
    pub max_frames: Option<usize>,
    /// Where rendered frames are cached.
    pub cache: PathBuf,
    /// Pythons to try for OpenCV, in order.
    pub python: Vec<String>,
}

impl Options {
    /// Refuses options that cannot make a run.
    pub fn validate(&self) -> Result<()> {
        if self.calibration_frames_per_view == 0 || self.frames_per_view == 0 {
            bail!("frames per view must be at least 1");
        }
        if self.hinge_cycles == 0 || self.excursion_cycles == 0 {
            bail!("cycles must be at least 1");
        }
        if !(self.fps.is_finite() && self.fps > 0.0) {
            bail!("the frame rate must be a positive number of frames/s, got {}", self.fps);
        }
        if self.max_frames == Some(0) {
            bail!("at most 0 frames per scene leaves nothing to measure");
        }
        Ok(())
    }

    fn request(&self, scene: SceneKind) -> Request {
        let (frames_per_view, cycles, fps, max_frames) = match scene {
            SceneKind::Calibration => (self.calibration_frames_per_view, 1, STILL_FPS, None),
            SceneKind::Static => (self.frames_per_view, 1, STILL_FPS, self.max_frames),
            SceneKind::Hinge => (1, self.hinge_cycles, self.fps, self.max_frames),
            _ => (1, self.excursion_cycles, self.fps, self.max_frames),
        };
        Request { max_frames, ..Request::new(scene, self.seed, frames_per_view, cycles, fps) }
    }
}

/// What the calibration found for one body.
#[derive(Debug, Clone)]
pub struct BodySummary {
    /// "maxilla" or "mandible".
    pub body: String,
    /// Views with at least two of its tags.
    pub views: usize,
    /// RMS reprojection error with the nominal marker (px).
    pub rms_before_px: f64,
    /// With the calibrated one (px).
    pub rms_after_px: f64,
    /// Tags placed by the calibration.
    pub calibrated_tags: usize,
    /// Assembly errors found and tags left nominal, in words.
    pub findings: Vec<String>,
}

/// One judged frame: the truth and every column's estimate of `maxilla_from_mandible`.
#[derive(Debug, Clone)]
pub struct FrameRecord {
    /// The scene.
    pub scene: SceneKind,
    /// Frame index in the scene.
    pub index: usize,
    /// Capture time (s).
    pub t: f64,
    /// The camera.
    pub view: View,
    /// The jaw's motion.
    pub motion: JawMotion,
    /// The true `maxilla_from_mandible`.
    pub truth: Pose,
    /// Each column's estimate (`None`: that column gave no jaw pose).
    pub estimates: Vec<Option<Pose>>,
}

/// A whole run.
#[derive(Debug, Clone)]
pub struct Run {
    /// The columns of `FrameRecord::estimates`.
    pub columns: Vec<Column>,
    /// The reference stack's description, or why it was skipped.
    pub reference: std::result::Result<String, String>,
    /// The calibration, per body.
    pub calibration: Vec<BodySummary>,
    /// The calibrated marker file.
    pub calibrated_marker: Marker,
    /// The calibration from the front faces only, per body.
    pub front_only: Vec<BodySummary>,
    /// The front-faces marker file.
    pub front_only_marker: Marker,
    /// Each judged scene's session refinements.
    pub sessions: Vec<SessionSummary>,
    /// The bite step per stack (ours, then the reference's), `None` when the stack had no
    /// closed-jaw pose.
    pub bite_steps: Vec<Option<BiteStep>>,
    /// Frames of the calibration recording.
    pub calibration_frames: usize,
    /// Every judged frame, scene after scene.
    pub frames: Vec<FrameRecord>,
}

/// Renders (or reads from the cache) the calibration recording and the three experiments,
/// calibrates, and runs every frame through every column. `progress(stage, done, total)`
/// reports rendering and tracking.
pub fn run(options: &Options, progress: &mut dyn FnMut(&str, usize, usize)) -> Result<Run> {
    options.validate()?;
    let (reference_stack, reference) = ReferenceStack::start(options, progress)?;
    let mut columns: Vec<Column> = MarkerFile::ALL.map(|marker| Column { stack: Stack::Ours, marker }).to_vec();
    columns.extend(MarkerFile::SESSION.map(|marker| Column { stack: Stack::Ours, marker }));
    if reference_stack.is_some() {
        columns.extend(MarkerFile::ALL.map(|marker| Column { stack: Stack::Reference, marker }));
    }
    let calibrated = stages::calibrate_markers(options, progress)?;
    let mut stacks = Stacks { reference: reference_stack };
    let bites = calibrated.bite_step(&mut stacks, progress)?;
    let judge = stages::Judge { options, calibrated: &calibrated, bites: &bites };
    let mut records = Vec::new();
    let mut sessions = Vec::new();
    for kind in [SceneKind::Static, SceneKind::Hinge, SceneKind::Excursion] {
        sessions.push(judge.scene(kind, &mut stacks, progress, &mut records)?);
    }
    let stages::Calibrated { scene, cal, front, .. } = calibrated;
    Ok(Run {
        columns,
        reference,
        calibration: stages::summarise(&cal),
        calibrated_marker: cal.marker,
        front_only: stages::summarise(&front),
        front_only_marker: front.marker,
        sessions,
        bite_steps: stages::bite_steps(&bites),
        calibration_frames: scene.truth.frames.len(),
        frames: records,
    })
}

/// What the bite step corrected for one stack.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiteStep {
    /// Closed-jaw frames with a pose.
    pub samples: usize,
    /// How far it moved the mandible (mm).
    pub translation_mm: f64,
    /// How far it turned it (°).
    pub rotation_deg: f64,
    /// The samples' largest distance from their mean (mm).
    pub spread_mm: f64,
}

/// One tracker per marker file.
fn new_trackers(markers: &[Marker; 3], truth: &jawtrack_synth::GroundTruth) -> Result<Vec<Tracker>> {
    let config = tracker_config(truth);
    Ok(markers.iter().map(|m| Tracker::new(m.clone(), config)).collect::<std::result::Result<Vec<_>, _>>()?)
}

/// One stack's `maxilla_from_mandible` with each of the nominal, calibrated and printed
/// marker files.
type PerMarker = [Option<Pose>; 3];

/// One frame through both pipelines.
struct Tracked {
    /// Our estimates.
    ours: PerMarker,
    /// Our calibrated tracker's detections.
    detections: Vec<Detection>,
    /// The reference stack's estimates, when it runs.
    theirs: Option<PerMarker>,
}

/// Both pipelines.
struct Stacks {
    reference: Option<ReferenceStack>,
}

impl Stacks {
    /// `maxilla_from_mandible` of one frame by our trackers (one per marker file), with the
    /// calibrated tracker's detections, and, when it runs, by the reference stack with the
    /// same marker files.
    fn frame(
        &mut self,
        trackers: &mut [Tracker],
        markers: &[Marker; 3],
        path: &std::path::Path,
        truth: &jawtrack_synth::GroundTruth,
        t: f64,
    ) -> Result<Tracked> {
        let img = read_luma(path)?;
        let camera = &truth.intrinsics;
        let mut ours = [None; 3];
        let mut detections = Vec::new();
        for (i, (tracker, out)) in trackers.iter_mut().zip(&mut ours).enumerate() {
            let r = tracker.track(&img.view()?, camera, t).with_context(|| format!("tracking {}", path.display()))?;
            *out = r.maxilla_from_mandible;
            if i == 1 {
                detections = r.detections;
            }
        }
        let theirs = match self.reference.as_mut() {
            Some(reference) => Some(reference.frame(&img, markers, path, camera)?),
            None => None,
        };
        Ok(Tracked { ours, detections, theirs })
    }
}

/// The reference stack: the AprilTag C library, then OpenCV's SQPnP per body.
#[cfg(feature = "reference")]
struct ReferenceStack {
    detector: ReferenceDetector,
    cv: OpenCv,
}

/// The reference stack is not built in (the `jawtrack` binary links no C): no value of this
/// type exists, so the run has our columns only.
#[cfg(not(feature = "reference"))]
enum ReferenceStack {}

/// Why a build without the `reference` feature has no reference columns, and how to get them.
#[cfg(not(feature = "reference"))]
const NOT_BUILT_IN: &str = "the AprilTag C library is not built into this binary (`jawtrack` links no C); \
     `cargo run --release -p jawtrack-tracker-bench --bin bench-accuracy -- <the same flags>` runs the same benchtop with it";

/// Both `start`s give the stack (or none) and its description (or why there is none); both
/// `frame`s give its `maxilla_from_mandible` of one frame with each marker file.
#[cfg(feature = "reference")]
impl ReferenceStack {
    fn start(
        options: &Options,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<(Option<ReferenceStack>, std::result::Result<String, String>)> {
        match OpenCv::start(&options.python)? {
            Ok(cv) => {
                let description = format!("AprilTag C 3.4.5, then OpenCV {} `solvePnP` SQPnP per body", cv.version);
                let detector =
                    ReferenceDetector::new(&ReferenceParams::default()).map_err(|e| anyhow::anyhow!("{e}"))?;
                Ok((Some(ReferenceStack { detector, cv }), Ok(description)))
            }
            Err(why) => {
                progress(&format!("SKIPPED: the reference stack — {why}"), 0, 0);
                Ok((None, Err(format!("no Python with OpenCV was found (`{}`)", crate::opencv::INSTALL_HINT))))
            }
        }
    }

    fn frame(
        &mut self,
        img: &Luma,
        markers: &[Marker; 3],
        path: &std::path::Path,
        camera: &CameraIntrinsics,
    ) -> Result<PerMarker> {
        let detections = self
            .detector
            .detect(&img.luma, img.width, img.height, img.width)
            .map_err(|e| anyhow::anyhow!("C library on {}: {e}", path.display()))?;
        let refs: Vec<&Marker> = markers.iter().collect();
        let mut theirs = [None; 3];
        for (pose, out) in
            reference::maxilla_from_mandible(&mut self.cv, &refs, &detections, camera)?.into_iter().zip(&mut theirs)
        {
            *out = pose.ok();
        }
        Ok(theirs)
    }
}

#[cfg(not(feature = "reference"))]
impl ReferenceStack {
    fn start(
        _: &Options,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<(Option<ReferenceStack>, std::result::Result<String, String>)> {
        progress(&format!("SKIPPED: the reference stack — {NOT_BUILT_IN}"), 0, 0);
        Ok((None, Err(NOT_BUILT_IN.to_owned())))
    }

    fn frame(&mut self, _: &Luma, _: &[Marker; 3], _: &std::path::Path, _: &CameraIntrinsics) -> Result<PerMarker> {
        match *self {}
    }
}

fn tracker_config(truth: &jawtrack_synth::GroundTruth) -> TrackerConfig {
    TrackerConfig {
        detector: DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() },
        exposure_s: truth.realism.exposure_s,
        ..TrackerConfig::default()
    }
}

/// A frame's luma plane.
struct Luma {
    luma: Vec<u8>,
    width: usize,
    height: usize,
}

impl Luma {
    fn view(&self) -> Result<ImageView<'_>> {
        Ok(ImageView::new(&self.luma, self.width, self.height, self.width)?)
    }
}

fn read_luma(path: &std::path::Path) -> Result<Luma> {
    let img = image::open(path).with_context(|| format!("reading {}", path.display()))?.to_luma8();
    let (width, height) = (img.width() as usize, img.height() as usize);
    Ok(Luma { luma: img.into_raw(), width, height })
}

#[cfg(test)]
impl Run {
    /// A run of `columns` over `frames` alone (no calibration, no sessions, neither stack with
    /// a bite step): what the report's tables and prose are tested on.
    pub(crate) fn judged(
        columns: Vec<Column>,
        reference: std::result::Result<String, String>,
        frames: Vec<FrameRecord>,
    ) -> Run {
        Run {
            bite_steps: vec![None, None],
            columns,
            reference,
            calibration: Vec::new(),
            calibrated_marker: Marker::default(),
            front_only: Vec::new(),
            front_only_marker: Marker::default(),
            sessions: Vec::new(),
            calibration_frames: 0,
            frames,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_kinematics::Mounting;
    use nalgebra::UnitQuaternion;
    use nalgebra::Vector3;

    #[test]
    fn regression_recovers_a_line_and_its_scatter() {
        let truth: Vec<f64> = (0..50).map(|i| i as f64 * 0.8).collect();
        // Slope 1.02, offset 0.3, residuals ±0.05 alternating: SE = 0.05·√(n/(n−2)).
        let tracked: Vec<f64> =
            truth.iter().enumerate().map(|(i, x)| 0.3 + 1.02 * x + if i % 2 == 0 { 0.05 } else { -0.05 }).collect();
        let r = regress(&truth, &tracked).expect("enough points");
        assert!((r.slope.expect("moving") - 1.02).abs() < 1e-3, "{r:?}");
        assert!((r.se_mm - 0.05 * (50.0f64 / 48.0).sqrt()).abs() < 2e-3, "{r:?}");
        assert!(r.r2.expect("moving") > 0.999 && r.r2.expect("moving") < 1.0);
        // An axis that does not move: the SD of the tracked values, no slope.
        let still = regress(&[1.0; 4], &[0.0, 0.2, 0.0, 0.2]).expect("enough points");
        assert_eq!((still.slope, still.r2), (None, None));
        assert!((still.se_mm - (0.04f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!(regress(&[1.0, 2.0], &[1.0, 2.0]).is_none());
    }

    #[test]
    fn errors_are_read_along_the_head_axes() {
        let mounting = Mounting::default();
        let truth = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 44.0, 0.0));
        // 0.1 mm along maxilla +X and 0.2° about maxilla +Z: the maxilla marker faces forward
        // (a half turn about Y from the head), so that is head −X and about head −Z.
        let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.2f64.to_radians());
        let estimate = Pose::from_parts(turn, Vector3::new(0.1, 44.0, 0.0));
        let e = error_parts(&estimate, &truth, &mounting.head_from_maxilla);
        assert!((e.position_mm - Vector3::new(-0.1, 0.0, 0.0)).norm() < 1e-12, "{e:?}");
        assert!((e.rotation_deg - Vector3::new(0.0, 0.0, -0.2)).norm() < 1e-9, "{e:?}");
        assert!((e.mm() - 0.1).abs() < 1e-12 && (e.deg() - 0.2).abs() < 1e-9);
    }

    /// A run of two static frames from one view and a hinge opening, one column, with
    /// estimates off by known amounts.
    fn tiny_run() -> Run {
        let rig = jawtrack_synth::scenes::Rig::default();
        let rest = rig.mounting.maxilla_from_mandible_rest();
        let view = View {
            distance_mm: 100.0,
            azimuth_deg: 30.0,
            elevation_deg: 0.0,
            target: [0.0; 3],
            hand_seed: None,
            orientation: Default::default(),
        };
        // 0.04 mm along maxilla +Y is 0.04 mm along head +Y (the half turn is about Y).
        let off = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.04, 0.0));
        let flip =
            Pose::from_parts(UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 2f64.to_radians()), Vector3::zeros());
        let mut frames = vec![
            FrameRecord {
                scene: SceneKind::Static,
                index: 0,
                t: 0.0,
                view,
                motion: JawMotion::Rest,
                truth: rest,
                estimates: vec![Some(off * rest)],
            },
            FrameRecord {
                scene: SceneKind::Static,
                index: 1,
                t: 0.1,
                view,
                motion: JawMotion::Rest,
                truth: rest,
                estimates: vec![None],
            },
        ];
        let motion = JawMotion::Hinge { opening_mm: 20.0, start_s: 0.0, period_s: 2.0 };
        for i in 0..10 {
            let t = i as f64 * 0.2;
            let (maxilla, mandible) = rig.markers(&motion, t);
            let truth = maxilla.inverse() * mandible;
            let estimate = if i == 5 { rest * flip } else { truth };
            frames.push(FrameRecord {
                scene: SceneKind::Hinge,
                index: i,
                t,
                view,
                motion,
                truth,
                estimates: vec![Some(estimate)],
            });
        }
        Run::judged(vec![Column { stack: Stack::Ours, marker: MarkerFile::Calibrated }], Err("not run".into()), frames)
    }

    #[test]
    fn tables_group_frames_and_count_what_is_missing() {
        let run = tiny_run();
        let rows = static_rows(&run, 0);
        assert_eq!(rows.len(), 1);
        let row = &rows[0];
        assert_eq!((row.frames, row.errors.len(), row.hand_held), (2, 1, false));
        assert!((row.position(1).expect("a pose").mean - 0.04).abs() < 1e-9, "{row:?}");
        assert!(row.mm().expect("a pose").mean < 0.041 && row.deg().expect("a pose").mean < 1e-9);

        let hinge = dynamic_rows(&run, SceneKind::Hinge, 0);
        assert_eq!(hinge.len(), 1);
        assert_eq!((hinge[0].label.as_str(), hinge[0].frames, hinge[0].errors.len()), ("20 mm", 10, 10));
        // The one wild frame (the jaw shown closed and turned at peak opening) spoils the fit.
        assert!(hinge[0].worst_se_mm().expect("fits") > 1.0);

        let f = flips(&run, SceneKind::Hinge, 0);
        assert_eq!((f.frames, f.posed, f.flips), (10, 10, 1));
        let s = flips(&run, SceneKind::Static, 0);
        assert_eq!((s.frames, s.posed, s.flips), (2, 1, 0));
    }

    #[test]
    fn mean_and_sd() {
        let m = MeanSd::of([1.0, 2.0, 3.0]).expect("values");
        assert!((m.mean - 2.0).abs() < 1e-12 && (m.sd - 1.0).abs() < 1e-12);
        assert_eq!(MeanSd::of([5.0]).map(|m| m.sd), Some(0.0));
        assert!(MeanSd::of(std::iter::empty()).is_none());
    }
}
