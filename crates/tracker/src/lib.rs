//! The tracker: one camera frame in, the pose of the mandible relative to the maxilla out.
//!
//! Per frame: detect the tags, inside the region where the markers are expected ([`roi`]) once
//! they are being tracked; give each marker body every corner of its tags seen (the model's
//! body-frame corners against the detected pixels); solve each body's pose
//! ([`jawtrack_pose::solve_pnp`]) starting from its pose extrapolated from the previous frames;
//! and compose `maxilla_from_mandible = camera_from_maxilla⁻¹ · camera_from_mandible`, and with
//! a [`Registration`] the lower tooth scan in the upper one. Detected tag centres are not used:
//! a detector's centre is the corners' homography at (0, 0), so it adds no information and
//! would make the covariance overconfident.
//!
//! A body seen through one tag has two planar solutions; the tracker takes the one that keeps
//! the bodies' recent relative pose when the other body is solved (it follows the head and the
//! phone), else the one nearer the body's own recent pose (both no older than
//! [`TrackerConfig::prior_max_age_s`]), and otherwise flags the body `ambiguous` rather than
//! guess silently; the pose, fit and covariance reported are those of the solution taken. A
//! tag that appears beside tags already tracked and fits the pose far worse than they do is
//! dropped for that frame (a one-frame flicker, e.g. a misread glare patch). Quality flags say
//! what went wrong in a frame; a frame without tags is a result with flags, not an error, and
//! a pose that is not finite is never returned. New settings ([`Tracker::set_config`]) keep
//! the motion tracked so far. With a calibrated marker, a body whose pose uses a tag the
//! calibration left at its nominal place is flagged `uncalibrated_tag`
//! ([`Tracker::uncalibrated_tags`]); a nominal marker never is. Under a rolling shutter
//! ([`TrackerConfig::readout_s`]) every corner is carried from its row's time to the frame's
//! before the bodies are solved, so both are reported at the same instant.

mod dense;
mod flicker;
pub mod oblique;
mod result;
pub mod roi;
pub mod sharpness;
pub mod smoothing;

pub use dense::PoseRefinement;
pub use jawtrack_recording::Flag;
pub use result::{BodyResult, FrameResult, Timings, tone_record};
pub use sharpness::{DEFOCUSED_BLUR_PER_CELL, THIN_CELL_PX, THIN_RATIO};
pub use smoothing::{Smoother, SmootherConfig};

use jawtrack_apriltag::{DetectError, Detection, Detector, DetectorConfig, ImageView, Roi, Search, StageTimes};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::motion::to_frame_time;
use jawtrack_pose::{
    BodyPose, CameraIntrinsics, Observation, PnpError, PnpOptions, Pose, RollingShutter, Velocity, solve_pnp,
};
use jawtrack_registration::{
    Bite, BiteRefusal, BiteRule, BiteWindow, IntercuspationCalibration, Registration, calibrate_intercuspation,
};
use nalgebra::{Point2, Point3};
pub use roi::SearchConfig;
use roi::{BodyState, Timed};
use std::time::Instant;

/// Tracker settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerConfig {
    /// The tag detector's.
    pub detector: DetectorConfig,
    /// The pose solver's.
    pub pnp: PnpOptions,
    /// Where to search.
    pub search: SearchConfig,
    /// A body whose RMS reprojection error exceeds this (px) is flagged.
    pub max_rms_px: f64,
    /// A tag new to a tracked body is dropped when its RMS error (px) exceeds both this and
    /// three times that of the body's other tags.
    pub flicker_px: f64,
    /// A body's earlier pose, or the bodies' earlier relative pose, settles a single tag's
    /// ambiguity (and places the expected region) only if seen within this (s).
    pub prior_max_age_s: f64,
    /// Smooth `maxilla_from_mandible` (off by default: raw poses are the measurement).
    pub smoother: Option<SmootherConfig>,
    /// When the maximal-intercuspation step accepts a bite.
    pub bite: BiteRule,
    /// Time the camera takes to read a frame from its first row to its last (s); 0 for a
    /// global shutter. With a readout, each body's corners are carried to the frame's time (its
    /// centre row's) at the velocity its recent poses give, so both bodies are solved at the
    /// same instant ([`jawtrack_pose::motion`]).
    pub readout_s: f64,
    /// The frames' exposure (s), with the bodies' velocity predicting how far their tags
    /// smear; where that is 3 px or more the edges are fitted as motion ramps
    /// (`DetectorConfig::smeared_edges`). Default 1/120 s, a phone's indoor exposure.
    pub exposure_s: f64,
    /// A body whose edges are blurred (the detector's [`Detection::blur_px`], the median over
    /// its tags) by more than this fraction of its tags' cell is flagged `defocused`, and the
    /// frame gives no jaw pose: the lens was not focused on it (a phone held nearer than it
    /// can focus, or far from where its focus was locked). See [`DEFOCUSED_BLUR_PER_CELL`].
    pub max_blur_per_cell: f64,
    /// How each body's pose is finished once solved from its tags' corners.
    pub refine: PoseRefinement,
}

impl Default for TrackerConfig {
    fn default() -> Self {
        TrackerConfig {
            detector: DetectorConfig::default(),
            pnp: PnpOptions::default(),
            search: SearchConfig::default(),
            max_rms_px: 2.0,
            flicker_px: 2.0,
            prior_max_age_s: 0.5,
            smoother: None,
            bite: BiteRule::default(),
            readout_s: 0.0,
            exposure_s: 1.0 / 120.0,
            max_blur_per_cell: DEFOCUSED_BLUR_PER_CELL,
            refine: PoseRefinement::default(),
        }
    }
}

/// Why a frame could not be tracked at all.
#[derive(Debug, thiserror::Error)]
pub enum TrackError {
    /// The frame buffer or the detector settings are wrong.
    #[error(transparent)]
    Detect(#[from] DetectError),
    /// The intrinsics cannot describe a camera.
    #[error("camera intrinsics: {0}")]
    BadIntrinsics(String),
    /// A setting out of range.
    #[error("tracker setting: {0}")]
    BadConfig(String),
}

/// Fastest a marker is taken to move in the camera frame (mm/s; a chewing jaw's incisor peaks
/// at 60–150 mm/s, the head and the hand add less): poses that imply more are a cut in the
/// footage or a wrong pose, and their velocity would carry the corners anywhere, so the
/// frame is solved as seen.
const MAX_SPEED_MM_S: f64 = 1000.0;
/// Fastest a marker is taken to turn (rad/s), for the same reason.
const MAX_TURN_RAD_S: f64 = 20.0;

/// Tracks the two marker bodies through a sequence of frames.
#[derive(Debug)]
pub struct Tracker {
    detector: Detector,
    marker: Marker,
    config: TrackerConfig,
    registration: Option<Registration>,
    bodies: [BodyState; 2],
    /// The last `maxilla_from_mandible` solved, to settle a lone tag by the other body.
    last_relative: Option<Timed>,
    smoother: Option<Smoother>,
    /// Frames since the whole frame was last searched.
    since_full: usize,
    /// Whether the last frame held a tag too blurred to look for where predicted
    /// ([`roi::MAX_PREDICTED_BLUR_PX`]).
    blurred: bool,
    /// Each body's tag corners in its frame, for the expected region.
    corners: [Vec<Point3<f64>>; 2],
    /// Per tag id: frames it was detected in with its body solved, and frames it was dropped.
    tag_counts: std::collections::BTreeMap<u32, (usize, usize)>,
    /// The recent raw jaw poses, for the intercuspation step.
    bite: BiteWindow,
    /// Ids of the tags a calibrated marker left nominal, ascending (empty for a nominal marker).
    uncalibrated: Vec<u32>,
    /// Ids of the tags whose place was measured ([`Marker::measured_tags`]), ascending.
    measured: Vec<u32>,
    /// The tone curve the last frame was read through and the fits behind it (`None` before the
    /// first frame): a frame read through another, or after another fit, reports it
    /// ([`FrameResult::tone`]).
    tone_reported: Option<(jawtrack_apriltag::ToneCurve, usize)>,
}

fn slot(kind: BodyKind) -> usize {
    match kind {
        BodyKind::Maxilla => 0,
        BodyKind::Mandible => 1,
    }
}

impl Tracker {
    /// A tracker for `marker` (nominal or calibrated). Its detector finds the marker's tag
    /// family, whatever `config.detector.family` says.
    pub fn new(marker: Marker, mut config: TrackerConfig) -> Result<Self, TrackError> {
        config.detector.family = marker.family;
        validate(&config)?;
        let corners = BodyKind::ALL.map(|kind| {
            marker
                .body(kind)
                .map(|b| b.tags.iter().flat_map(|t| t.corners.iter().map(|c| Point3::from(*c))).collect())
                .unwrap_or_default()
        });
        let uncalibrated = marker.uncalibrated_tags().into_iter().map(|(_, id)| id).collect();
        let marker_measured = marker.measured_tags();
        Ok(Tracker {
            detector: Detector::new(config.detector)?,
            marker,
            smoother: config.smoother.map(Smoother::new),
            config,
            registration: None,
            bodies: Default::default(),
            last_relative: None,
            since_full: 0,
            blurred: false,
            corners,
            tag_counts: Default::default(),
            bite: BiteWindow::new(config.bite),
            uncalibrated,
            measured: marker_measured,
            tone_reported: None,
        })
    }

    /// The marker tracked.
    pub fn marker(&self) -> &Marker {
        &self.marker
    }

    /// The tone curve frames are read through now, and how it was found
    /// ([`DetectorConfig::tone`]): with `Auto`, estimated from the tags of the frames so far.
    pub fn tone(&self) -> jawtrack_apriltag::tone::ToneSummary {
        self.detector.tone()
    }

    /// Cells across a tag's black border in the marker's family.
    fn cells(&self) -> f64 {
        self.marker.family.width_at_border as f64
    }

    /// The ids of the tags a calibrated marker left at their nominal place, ascending: a pose
    /// that uses one is flagged [`Flag::UncalibratedTag`]. Empty for a nominal marker (every
    /// tag nominal alike) and for one calibrated whole.
    pub fn uncalibrated_tags(&self) -> &[u32] {
        &self.uncalibrated
    }

    /// The settings.
    pub fn config(&self) -> &TrackerConfig {
        &self.config
    }

    /// Changes the settings and keeps the bodies' motion: their recent poses (the expected
    /// region, the starts of their PnP, what settles a lone tag), the last relative pose and
    /// the tag statistics. The smoother restarts only when its settings change, since its state
    /// was built under the old ones. Settings refused leave the tracker as it was.
    pub fn set_config(&mut self, mut config: TrackerConfig) -> Result<(), TrackError> {
        config.detector.family = self.marker.family;
        validate(&config)?;
        if config.detector != self.config.detector {
            self.detector = Detector::new(config.detector)?;
        }
        if config.smoother != self.config.smoother {
            self.smoother = config.smoother.map(Smoother::new);
        }
        if config.bite != self.config.bite {
            self.bite = BiteWindow::new(config.bite);
        }
        self.config = config;
        Ok(())
    }

    /// Sets (or clears) the registration to the tooth scans.
    pub fn set_registration(&mut self, registration: Option<Registration>) {
        self.registration = registration;
    }

    /// The registration to the tooth scans, if set.
    pub fn registration(&self) -> Option<&Registration> {
        self.registration.as_ref()
    }

    /// The maximal-intercuspation calibration step over the frames tracked last: if
    /// [`TrackerConfig::bite`] accepts them as a held bite, their mean jaw pose becomes the
    /// rest, and the mandible's registration (identity when none is set) is corrected so that
    /// the rest maps the lower scan onto its scanned intercuspal pose.
    pub fn calibrate_intercuspation(&mut self) -> Result<(Bite, IntercuspationCalibration), BiteRefusal> {
        let bite = self.bite.judge()?;
        let current = self.registration.unwrap_or_else(Registration::identity);
        let samples = self.bite.poses();
        let cal = calibrate_intercuspation(&current, &samples).map_err(|_| BiteRefusal::TooFewFrames {
            needed: self.config.bite.min_frames,
            got: samples.len(),
            window_s: self.config.bite.window_s,
        })?;
        self.registration = Some(cal.registration);
        Ok((bite, cal))
    }

    /// Where `kind` is expected at `t` (s), extrapolated from the frames before: the pose its
    /// PnP starts from.
    pub fn predicted(&self, kind: BodyKind, t: f64) -> Option<Pose> {
        self.bodies[slot(kind)].predict(t)
    }

    /// Tags whose corners disagreed with the marker file in most frames they were seen in (at
    /// least `min_frames` of them): a tag glued turned or on another face, or a marker file
    /// that is not this print's. Each as (id, frames seen, frames dropped).
    pub fn mismatched_tags(&self, min_frames: usize) -> Vec<(u32, usize, usize)> {
        self.tag_counts
            .iter()
            .filter(|(_, (seen, dropped))| *dropped >= min_frames.max(1) && 2 * dropped >= *seen)
            .map(|(&id, &(seen, dropped))| (id, seen, dropped))
            .collect()
    }

    /// Forgets the bodies' motion (a cut in the footage).
    pub fn reset(&mut self) {
        self.bodies = Default::default();
        self.last_relative = None;
        self.since_full = 0;
        self.blurred = false;
        self.bite.clear();
        if let Some(s) = &mut self.smoother {
            s.reset();
        }
    }

    /// Tracks one frame taken at `t` (s) with `camera` (the intrinsics may change per frame).
    pub fn track(
        &mut self,
        frame: &ImageView<'_>,
        camera: &CameraIntrinsics,
        t: f64,
    ) -> Result<FrameResult, TrackError> {
        camera.validate().map_err(|e| TrackError::BadIntrinsics(e.to_string()))?;
        // Intrinsics of another resolution or of the turned frame put the principal point
        // off the image; every pose from them would be wrong.
        let (w, h) = (frame.width() as f64, frame.height() as f64);
        if !((-0.5..w - 0.5).contains(&camera.cx) && (-0.5..h - 0.5).contains(&camera.cy)) {
            return Err(TrackError::BadIntrinsics(format!(
                "the principal point ({}, {}) lies outside the {w}×{h} frame: are the intrinsics for another \
                 resolution, or for the frame turned upright? Frames are tracked as the camera stores them",
                camera.cx, camera.cy
            )));
        }
        if !t.is_finite() {
            return Err(TrackError::BadConfig(format!("frame time must be finite, got {t}")));
        }
        let start = Instant::now();
        let expected = self.expected_region(frame, camera, t);
        let mut searched = expected;
        // Either body's recent motion predicts a smear of `roi::SMEAR_PX` or more.
        let smeared = self.smears(camera, t).iter().any(|&s| s >= roi::SMEAR_PX);
        let (mut detections, mut stages, mut predicted) = (None, StageTimes::default(), false);
        // A frame whose edges are fitted as motion ramps keeps the region search: a ramp's fit
        // follows where its window starts, and predicted quads refitted as ramps landed up to
        // 1.5 mm off on rendered chewing (4K through a 2× crop, 8 ms exposure).
        let ramps = smeared || self.config.detector.smeared_edges;
        // … and so does a frame its tags moved far to, where the prediction is off by more.
        let since = |b: &BodyState| b.last().map_or(0.0, |l| t - l.0);
        let far = self.travel_px(camera, t, since).iter().any(|&px| px > roi::MAX_PREDICTED_TRAVEL_PX);
        // … and so does a frame the tone curve is fitted in: the curve is then fitted to the
        // tags the search finds, as without predicted tags. Fitted to confirmed tags too (a
        // frame confirmed, then searched, fitted twice), the curve of sRGB frames came out as a
        // power of 2.64 where the search's gave 2.30, and a still jaw 0.023 mm off, not 0.010.
        let tone_due = self.detector.tone_fit_due();
        if expected.is_some() && self.config.search.predicted && !ramps && !far && !self.blurred && !tone_due {
            let tags = self.expected_tags_at(frame, camera, t);
            if !tags.is_empty() {
                let mut d = self.detector.confirm(frame, &tags, false)?;
                d.retain(|d| self.marker.find_tag(d.id).is_some());
                stages = self.detector.last_stages();
                predicted = !roi::any_blurred(&d) && !self.lost_a_tag(&d);
                detections = predicted.then_some(d);
            }
        }
        let mut detections = match detections {
            Some(d) => d,
            None => {
                // The region, or the whole frame searched periodically while both bodies are
                // tracked: a tag that comes into view is of the size of those tracked.
                let tracked = expected.is_some() || (self.config.search.region_search && self.both_tracked(t));
                let (coarse, min_quad) = if tracked { self.tracked_search(camera, t) } else { (None, 0.0) };
                let mut d = self.detect(frame, expected, smeared, (coarse, min_quad))?;
                stages = stages + self.detector.last_stages();
                if coarse.is_some() && self.lost_a_tag(&d) {
                    // A tag the coarse image missed: search again at the settings' decimation.
                    d = self.detect(frame, expected, smeared, (None, min_quad))?;
                    stages = stages + self.detector.last_stages();
                }
                d
            }
        };
        // A body missing from its expected region, or a tag at the region's edge (the
        // prediction was off, and the edge fit there lacks its pixels): search everywhere.
        let missing = BodyKind::ALL.iter().any(|&k| !detections.iter().any(|d| self.body_of(d.id) == Some(k)));
        let at_edge = expected.is_some_and(|r| {
            detections
                .iter()
                .any(|d| roi::near_inner_edge(&d.corners, &r, frame, self.config.search.min_margin_px / 2.0))
        });
        if expected.is_some() && (missing || at_edge) {
            detections = self.detect(frame, None, smeared, (None, 0.0))?;
            stages = stages + self.detector.last_stages();
            searched = None;
            predicted = false;
        }
        self.since_full = if searched.is_none() { 0 } else { self.since_full + 1 };
        self.blurred = roi::any_blurred(detections.iter().filter(|d| self.marker.find_tag(d.id).is_some()));
        let detection_s = start.elapsed().as_secs_f64();
        let mut result = self.solve_in(detections, camera, t, frame.height(), Some(frame));
        result.searched = searched;
        result.timings.detection_s = detection_s;
        result.timings.stages = stages;
        result.timings.predicted = predicted;
        let tone = self.detector.tone();
        if self.tone_reported != Some((tone.curve, tone.frames_fitted)) {
            self.tone_reported = Some((tone.curve, tone.frames_fitted));
            result.tone = Some(tone);
        }
        Ok(result)
    }

    /// Detects the marker's tags in `roi`, finding quads at `decimate` (the settings' for `None`)
    /// and trying those whose longest side is `min_quad_px` or more.
    fn detect(
        &self,
        frame: &ImageView<'_>,
        roi: Option<Roi>,
        smeared: bool,
        (decimate, min_quad_px): (Option<f32>, f64),
    ) -> Result<Vec<Detection>, TrackError> {
        let search = Search {
            roi,
            smeared: smeared || self.config.detector.smeared_edges,
            quad_decimate: decimate.unwrap_or(self.config.detector.quad_decimate),
            min_quad_px,
        };
        let mut d = self.detector.search(frame, &search)?;
        d.retain(|d| self.marker.find_tag(d.id).is_some());
        Ok(d)
    }

    /// Whether a tag either body was solved from in the last frame is missing from `detections`.
    fn lost_a_tag(&self, detections: &[Detection]) -> bool {
        self.bodies.iter().flat_map(|b| &b.tags).any(|id| !detections.iter().any(|d| d.id == *id))
    }

    fn body_of(&self, id: u32) -> Option<BodyKind> {
        self.marker.find_tag(id).map(|(k, _)| k)
    }

    /// Whether a pose seen at `seen` (s) is recent enough to go by at `t`: the one age limit
    /// for a body's own poses and for the bodies' relative pose.
    fn recent(&self, seen: f64, t: f64) -> bool {
        t - seen <= self.config.prior_max_age_s
    }

    /// How far (px) each body's recent motion predicts its tags smear over the exposure of a
    /// frame at `t` (0 without a recent pose).
    fn smears(&self, camera: &CameraIntrinsics, t: f64) -> [f64; 2] {
        self.travel_px(camera, t, |_| self.config.exposure_s)
    }

    /// How far (px) each body's recent motion moves its tags over the time `over(body)` (s), 0
    /// without a recent pose.
    fn travel_px(&self, camera: &CameraIntrinsics, t: f64, over: impl Fn(&BodyState) -> f64) -> [f64; 2] {
        BodyKind::ALL.map(|k| {
            let (b, reach) = (&self.bodies[slot(k)], self.corners[slot(k)].iter().map(|p| p.coords.norm()));
            if b.last().is_some_and(|l| self.recent(l.0, t)) {
                b.smear_px(camera, over(b), reach.fold(0.0, f64::max))
            } else {
                0.0
            }
        })
    }

    /// Solves both bodies from detections already made (e.g. by a detector elsewhere) in a
    /// frame of `rows` rows taken at `t` (s): the time of its centre row. Without the frame's
    /// pixels the poses are the corners' whatever [`TrackerConfig::refine`] asks, and with
    /// [`PoseRefinement::Dense`] each body says so (`dense_failed`).
    pub fn solve(&mut self, detections: Vec<Detection>, camera: &CameraIntrinsics, t: f64, rows: usize) -> FrameResult {
        self.solve_in(detections, camera, t, rows, None)
    }

    /// [`Tracker::solve`], with the frame the detections came from for the dense refinement.
    fn solve_in(
        &mut self,
        detections: Vec<Detection>,
        camera: &CameraIntrinsics,
        t: f64,
        rows: usize,
        frame: Option<&ImageView<'_>>,
    ) -> FrameResult {
        let start = Instant::now();
        // The readout was validated with the settings.
        let shutter = RollingShutter::new(self.config.readout_s, rows).unwrap_or_else(|_| RollingShutter::global());
        let mut flags = Vec::new();
        if detections.is_empty() {
            flags.push(Flag::NoTags);
        }
        let smears = self.smears(camera, t);
        let smeared = smears.iter().any(|&s| s >= roi::SMEAR_PX);
        let mut solved: [Option<(BodyPose, Vec<u32>)>; 2] = [None, None];
        let mut seen: [Option<Pose>; 2] = [None, None];
        for kind in BodyKind::ALL {
            let observations = self.observations(kind, &detections);
            let prior = self.predicted(kind, t);
            let Ok((pose, observations, raw)) = self.solve_at(kind, observations, camera, prior.as_ref(), t, &shutter)
            else {
                continue;
            };
            seen[slot(kind)] = raw;
            solved[slot(kind)] = Some(self.drop_flicker(kind, pose, observations, camera, prior.as_ref(), smeared));
        }
        let mut bodies: [Option<BodyResult>; 2] = [None, None];
        // Settle each lone tag by the other body first: its pose this frame carries any motion
        // of the head or the phone since the bodies were last seen together, which the lone
        // body's own extrapolated pose does not; both are no older than `prior_max_age_s`.
        for kind in BodyKind::ALL {
            let Some((pose, rejected)) = solved[slot(kind)].clone() else { continue };
            let own = self.bodies[slot(kind)]
                .last()
                .filter(|l| self.recent(l.0, t))
                .and_then(|_| self.bodies[slot(kind)].predict(t));
            let relative = self.last_relative.filter(|r| self.recent(r.0, t));
            let other = match (kind, &solved[1 - slot(kind)], relative) {
                (_, Some((o, _)), Some((_, rel))) if o.alternative.is_none() => Some(match kind {
                    BodyKind::Maxilla => o.camera_from_body * rel.inverse(),
                    BodyKind::Mandible => o.camera_from_body * rel,
                }),
                _ => None,
            };
            bodies[slot(kind)] = self.accept(kind, pose, rejected, other.or(own).as_ref(), &mut flags);
        }
        let refining = Instant::now();
        if self.config.refine == PoseRefinement::Dense {
            self.refine_dense(&mut bodies, &detections, camera, t, &shutter, frame, &mut flags);
        }
        let refine_s = refining.elapsed().as_secs_f64();
        let defocused =
            sharpness::judge(&mut bodies, &detections, smears, self.config.max_blur_per_cell, self.cells(), &mut flags);
        for kind in BodyKind::ALL {
            match &bodies[slot(kind)] {
                Some(b) => self.bodies[slot(kind)].remember(t, b.camera_from_body, seen[slot(kind)], &b.tags),
                None => {
                    flags.push(Flag::Lost(kind));
                    self.bodies[slot(kind)].tags.clear();
                    self.bodies[slot(kind)].seen.clear();
                }
            }
        }
        for b in bodies.iter().flatten() {
            for &id in &b.tags {
                self.tag_counts.entry(id).or_default().0 += 1;
            }
            for &id in &b.rejected_tags {
                let c = self.tag_counts.entry(id).or_default();
                c.0 += 1;
                c.1 += 1;
            }
        }
        let [maxilla, mandible] = bodies;
        // A defocused body's pose may be millimetres off: the frame gives no jaw pose.
        let raw = match (&maxilla, &mandible) {
            (Some(a), Some(b)) if !defocused => {
                Some(a.camera_from_body.inverse() * b.camera_from_body).filter(Pose::is_finite)
            }
            _ => None,
        };
        if let Some(r) = raw {
            self.last_relative = Some((t, r));
        }
        self.bite.push(t, raw);
        let maxilla_from_mandible = match (raw, &mut self.smoother) {
            (Some(r), Some(s)) => Some(s.filter(t, &r)).filter(Pose::is_finite),
            (None, Some(s)) => {
                s.reset();
                None
            }
            (r, None) => r,
        };
        let maxilla_scan_from_mandible_scan = match (&self.registration, &maxilla_from_mandible) {
            (Some(reg), Some(m)) => Some(reg.maxilla_scan_from_mandible_scan(m)).filter(Pose::is_finite),
            _ => None,
        };
        FrameResult {
            t,
            maxilla,
            mandible,
            maxilla_from_mandible,
            maxilla_scan_from_mandible_scan,
            flags,
            detections,
            searched: None,
            timings: Timings { pose_s: start.elapsed().as_secs_f64(), refine_s, ..Timings::default() },
            tone: None,
        }
    }

    /// Refines each solved body's pose from its tags' pixels ([`PoseRefinement::Dense`]); a body
    /// whose refinement fails, or that has no frame to refine from, keeps its corner pose and is
    /// flagged `dense_failed`.
    #[allow(clippy::too_many_arguments)]
    fn refine_dense(
        &self,
        bodies: &mut [Option<BodyResult>; 2],
        detections: &[Detection],
        camera: &CameraIntrinsics,
        t: f64,
        shutter: &RollingShutter,
        frame: Option<&ImageView<'_>>,
        flags: &mut Vec<Flag>,
    ) {
        let linear = frame.map(|_| self.detector.tone().curve.decode_table());
        let mut jobs = Vec::new();
        for kind in BodyKind::ALL {
            let Some(body) = bodies[slot(kind)].as_ref() else { continue };
            let (Some(frame), Some(linear)) = (frame, linear.as_ref()) else {
                flags.push(Flag::DenseFailed(kind));
                continue;
            };
            let state = &self.bodies[slot(kind)];
            // The motion is modelled only where the body's recent poses foretold this one: after
            // a jump (a cut, frames timed wrongly) the velocity they give would smear sharp tags.
            let foretold =
                state.last().filter(|l| self.recent(l.0, t)).and_then(|_| state.predict(t)).is_some_and(|p| {
                    dense::miss_px(&self.marker, &body.tags, &p, &body.camera_from_body, camera) <= dense::FORETOLD_PX
                });
            let velocity = foretold
                .then(|| state.velocity_at(t, body.camera_from_body))
                .flatten()
                .filter(|v| v.is_finite() && v.linear.norm() <= MAX_SPEED_MM_S && v.angular.norm() <= MAX_TURN_RAD_S);
            let motion = velocity.map(|velocity| jawtrack_photometric::Motion {
                velocity,
                shutter: *shutter,
                exposure_s: self.config.exposure_s,
            });
            let image = jawtrack_photometric::Image { frame: *frame, linear };
            jobs.push((kind, body, image, motion));
        }
        // The bodies are refined independently: over the detector's threads when it has two,
        // and within each its tags' pixels on the same threads, so that a thread done with the
        // quicker body (a still one's single fit) helps with the other.
        let workers = self.detector.workers();
        let threads = workers.threads();
        let refined = workers.map(jobs, |(kind, body, image, motion)| {
            (kind, dense::refine_body(&self.marker, image, camera, body, detections, motion, threads))
        });
        for (kind, result) in refined {
            match (result, bodies[slot(kind)].as_mut()) {
                (Ok(r), Some(body)) => {
                    body.camera_from_body = r.camera_from_body;
                    body.covariance = r.covariance;
                }
                _ => flags.push(Flag::DenseFailed(kind)),
            }
        }
    }

    /// Every corner of `kind`'s tags among the detections: the correspondences its PnP
    /// solves (for benchmarks and diagnostics). A tag seen so steeply that its cells are under
    /// [`THIN_CELL_PX`] across, or whose shortest side is under [`THIN_RATIO`] of its longest, is
    /// left out while the body has two others.
    pub fn observations(&self, kind: BodyKind, detections: &[Detection]) -> Vec<Observation> {
        let mine: Vec<&Detection> =
            detections.iter().filter(|d| self.marker.find_tag(d.id).is_some_and(|(b, _)| b == kind)).collect();
        let skip_thin = mine.iter().filter(|d| !sharpness::thin(d, self.cells())).count() >= 2;
        let mut out = Vec::new();
        for d in mine {
            let Some((_, tag)) = self.marker.find_tag(d.id) else { continue };
            if skip_thin && sharpness::thin(d, self.cells()) {
                continue;
            }
            for (corner, pixel) in tag.corners.iter().zip(&d.corners) {
                out.push(Observation {
                    tag: d.id,
                    body: Point3::from(*corner),
                    pixel: Point2::new(pixel[0], pixel[1]),
                });
            }
        }
        out
    }

    /// `kind`'s pose at the frame's time `t` from its observations `seen`, the observations it
    /// was solved from, and (under a rolling shutter) its pose solved from them as seen. With a
    /// global shutter, the pose as seen. Under a rolling shutter, the observations are carried
    /// to `t` at the body's velocity, taken at `t` from its poses as seen in this frame and the
    /// two before: those are a function of the observations alone, so an error in one
    /// frame's velocity never feeds the next (velocities from the carried poses do, and at a
    /// 10 ms readout that loop rang). Without a recent pose, or with poses that imply an
    /// implausible speed, the velocity is unknown and the frame is solved as seen.
    fn solve_at(
        &self,
        kind: BodyKind,
        seen: Vec<Observation>,
        camera: &CameraIntrinsics,
        prior: Option<&Pose>,
        t: f64,
        shutter: &RollingShutter,
    ) -> Result<(BodyPose, Vec<Observation>, Option<Pose>), PnpError> {
        let as_seen = solve_pnp(&seen, camera, prior, &self.config.pnp)?;
        if shutter.is_global() {
            return Ok((as_seen, seen, None));
        }
        // A lone tag's mirror solution would make a velocity of nothing: take the one nearer
        // the prior.
        let raw = match (&as_seen.alternative, prior) {
            (Some(alt), Some(p))
                if alt.camera_from_body.rotation().angle_to(&p.rotation())
                    < as_seen.camera_from_body.rotation().angle_to(&p.rotation()) =>
            {
                alt.camera_from_body
            }
            _ => as_seen.camera_from_body,
        };
        let mut timed: Vec<Timed> =
            self.bodies[slot(kind)].seen.iter().filter(|(s, _)| *s < t && self.recent(*s, t)).copied().collect();
        timed.push((t, raw));
        // Seen as a whole, the body is where it was at its corners' mean row time, so its poses
        // as seen run that much ahead of the frame times they are filed under.
        let ahead = seen.iter().map(|o| shutter.offset_s(o.pixel.y)).sum::<f64>() / seen.len().max(1) as f64;
        let plausible =
            |v: &Velocity| v.is_finite() && v.linear.norm() <= MAX_SPEED_MM_S && v.angular.norm() <= MAX_TURN_RAD_S;
        let Some(velocity) = Velocity::at(&timed, t - ahead).filter(plausible) else {
            return Ok((as_seen, seen, Some(raw)));
        };
        let carried = to_frame_time(&seen, shutter, camera, &raw, &velocity);
        let pose = solve_pnp(&carried, camera, Some(&raw), &self.config.pnp)?;
        Ok((pose, carried, Some(raw)))
    }

    /// Settles a single tag's mirror ambiguity by `expected`, flags what is worth knowing, and
    /// refuses a pose that is not finite.
    fn accept(
        &self,
        kind: BodyKind,
        pose: BodyPose,
        rejected_tags: Vec<u32>,
        expected: Option<&Pose>,
        flags: &mut Vec<Flag>,
    ) -> Option<BodyResult> {
        let (mut chosen, mut rms, mut covariance) = (pose.camera_from_body, pose.rms_px, pose.covariance);
        if pose.tags.len() == 1 {
            flags.push(Flag::SingleTag(kind));
        }
        if let Some(alternative) = pose.alternative {
            match expected {
                Some(p) => {
                    let angle = |q: &Pose| q.rotation().angle_to(&p.rotation());
                    if angle(&alternative.camera_from_body) < angle(&chosen) {
                        chosen = alternative.camera_from_body;
                        rms = alternative.rms_px;
                        covariance = alternative.covariance;
                    }
                }
                None => flags.push(Flag::Ambiguous(kind)),
            }
        }
        if !rejected_tags.is_empty() {
            flags.push(Flag::RejectedTags(kind));
        }
        if rms > self.config.max_rms_px {
            flags.push(Flag::HighReprojectionError(kind));
        }
        if pose.tags.iter().any(|id| self.uncalibrated.binary_search(id).is_ok()) {
            flags.push(Flag::UncalibratedTag(kind));
        }
        let finite = chosen.is_finite() && rms.is_finite() && covariance.iter().all(|v| !v.is_nan());
        finite.then_some(BodyResult {
            camera_from_body: chosen,
            tags: pose.tags,
            rejected_tags,
            rms_px: rms,
            covariance,
            blur_px: None,
            cell_px: 0.0,
        })
    }
}

/// Refuses settings out of range.
fn validate(c: &TrackerConfig) -> Result<(), TrackError> {
    c.bite.validate().map_err(TrackError::BadConfig)?;
    let positive = [
        ("max_rms_px", c.max_rms_px),
        ("flicker_px", c.flicker_px),
        ("prior_max_age_s", c.prior_max_age_s),
        ("max_blur_per_cell", c.max_blur_per_cell),
    ];
    for (name, v) in positive {
        if !(v.is_finite() && v > 0.0) {
            return Err(TrackError::BadConfig(format!("{name} must be a positive number, got {v}")));
        }
    }
    RollingShutter::new(c.readout_s, 2).map_err(|e| TrackError::BadConfig(e.to_string()))?;
    if !(c.exposure_s.is_finite() && c.exposure_s > 0.0 && c.exposure_s < 1.0) {
        return Err(TrackError::BadConfig(format!("exposure_s must be within 0–1 s, got {}", c.exposure_s)));
    }
    let s = &c.search;
    if !(s.margin.is_finite() && s.margin >= 0.0 && s.min_margin_px.is_finite() && s.min_margin_px >= 0.0) {
        return Err(TrackError::BadConfig(format!(
            "search margin must be non-negative (margin {}, min_margin_px {})",
            s.margin, s.min_margin_px
        )));
    }
    if s.full_frame_every == 0 {
        return Err(TrackError::BadConfig("full_frame_every must be at least 1".into()));
    }
    Ok(())
}
