//! The tracker: one camera frame in, the pose of the mandible relative to the maxilla out.
//!
//! Per frame: detect the tags; give each marker body every corner of its tags seen (the
//! model's body-frame corners against the detected pixels); solve each body's pose
//! ([`jawtrack_pose::solve_pnp`]), starting from its pose in the previous frame; and compose
//! `maxilla_from_mandible = camera_from_maxilla⁻¹ · camera_from_mandible`. Detected tag centres
//! are not used: a detector's centre is the corners' homography at (0, 0), so it adds no
//! information and would make the covariance overconfident.
//!
//! A body seen through one tag has two planar solutions; the tracker takes the one nearer
//! its previous pose, and without one flags the body `ambiguous` rather than guess. Quality
//! flags say what went wrong in a frame; a frame without tags is a result with flags, not an
//! error, and a pose that is not finite is never returned.

use jawtrack_apriltag::{DetectError, Detection, Detector, DetectorConfig, ImageView};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::{BodyPose, CameraIntrinsics, Observation, PnpOptions, Pose, solve_pnp};
use nalgebra::{Matrix6, Point2, Point3};

/// Tracker settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerConfig {
    /// The tag detector's.
    pub detector: DetectorConfig,
    /// The pose solver's.
    pub pnp: PnpOptions,
    /// A body whose RMS reprojection error exceeds this (px) is flagged.
    pub max_rms_px: f64,
}

impl Default for TrackerConfig {
    fn default() -> Self {
        TrackerConfig { detector: DetectorConfig::default(), pnp: PnpOptions::default(), max_rms_px: 1.0 }
    }
}

/// Something to know about a frame's result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flag {
    /// No tag of the marker was found.
    NoTags,
    /// A body has no tag in view (or too few points): no pose.
    Lost(BodyKind),
    /// A body is seen through a single tag: its pose rests on four points.
    SingleTag(BodyKind),
    /// A body's single-tag pose has a mirror solution and no previous pose to choose by.
    Ambiguous(BodyKind),
    /// A body's reprojection error is above `max_rms_px`.
    HighReprojectionError(BodyKind),
    /// A body's tags disagreed and some were dropped.
    RejectedTags(BodyKind),
}

impl Flag {
    /// A short machine-readable name, e.g. `mandible:lost`.
    pub fn name(&self) -> String {
        match self {
            Flag::NoTags => "no_tags".into(),
            Flag::Lost(b) => format!("{b}:lost"),
            Flag::SingleTag(b) => format!("{b}:single_tag"),
            Flag::Ambiguous(b) => format!("{b}:ambiguous"),
            Flag::HighReprojectionError(b) => format!("{b}:high_reprojection_error"),
            Flag::RejectedTags(b) => format!("{b}:rejected_tags"),
        }
    }
}

/// One body's pose in a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyResult {
    /// Maps the body's marker frame into the camera frame (mm).
    pub camera_from_body: Pose,
    /// Tags used, ascending.
    pub tags: Vec<u32>,
    /// RMS reprojection error (px).
    pub rms_px: f64,
    /// Covariance of (rotation vector [rad], translation [mm]) of a left perturbation in the
    /// camera frame.
    pub covariance: Matrix6<f64>,
}

/// What the tracker made of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameResult {
    /// The upper jaw's marker, if solved.
    pub maxilla: Option<BodyResult>,
    /// The lower jaw's marker, if solved.
    pub mandible: Option<BodyResult>,
    /// The mandible marker in the maxilla marker's frame, when both are solved.
    pub maxilla_from_mandible: Option<Pose>,
    /// Quality flags.
    pub flags: Vec<Flag>,
    /// The marker's tags detected (other tag36h11 ids are ignored).
    pub detections: Vec<Detection>,
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
}

/// Tracks the two marker bodies through a sequence of frames.
#[derive(Debug)]
pub struct Tracker {
    detector: Detector,
    marker: Marker,
    config: TrackerConfig,
    /// Each body's pose in the previous frame where it was solved.
    previous: [Option<Pose>; 2],
}

impl Tracker {
    /// A tracker for `marker` (nominal or calibrated).
    pub fn new(marker: Marker, config: TrackerConfig) -> Result<Self, TrackError> {
        Ok(Tracker { detector: Detector::new(config.detector)?, marker, config, previous: [None, None] })
    }

    /// The marker tracked.
    pub fn marker(&self) -> &Marker {
        &self.marker
    }

    /// Forgets the previous poses (a cut in the footage).
    pub fn reset(&mut self) {
        self.previous = [None, None];
    }

    /// Tracks one frame seen with `camera`.
    pub fn track(&mut self, frame: &ImageView<'_>, camera: &CameraIntrinsics) -> Result<FrameResult, TrackError> {
        camera.validate().map_err(|e| TrackError::BadIntrinsics(e.to_string()))?;
        let detections: Vec<Detection> =
            self.detector.detect(frame)?.into_iter().filter(|d| self.marker.find_tag(d.id).is_some()).collect();
        Ok(self.solve(detections, camera))
    }

    /// Solves both bodies from detections already made (e.g. by a detector elsewhere).
    pub fn solve(&mut self, detections: Vec<Detection>, camera: &CameraIntrinsics) -> FrameResult {
        let mut flags = Vec::new();
        if detections.is_empty() {
            flags.push(Flag::NoTags);
        }
        let mut bodies: [Option<BodyResult>; 2] = [None, None];
        for (slot, kind) in BodyKind::ALL.into_iter().enumerate() {
            let observations = self.observations(kind, &detections);
            let prior = self.previous[slot];
            match solve_pnp(&observations, camera, prior.as_ref(), &self.config.pnp) {
                Ok(pose) => {
                    if let Some(result) = self.accept(kind, pose, prior.as_ref(), &mut flags) {
                        self.previous[slot] = Some(result.camera_from_body);
                        bodies[slot] = Some(result);
                    } else {
                        flags.push(Flag::Lost(kind));
                    }
                }
                Err(_) => flags.push(Flag::Lost(kind)),
            }
        }
        let [maxilla, mandible] = bodies;
        let maxilla_from_mandible = match (&maxilla, &mandible) {
            (Some(a), Some(b)) => {
                Some(a.camera_from_body.inverse().compose(&b.camera_from_body)).filter(Pose::is_finite)
            }
            _ => None,
        };
        FrameResult { maxilla, mandible, maxilla_from_mandible, flags, detections }
    }

    /// Every corner of `kind`'s tags among the detections.
    fn observations(&self, kind: BodyKind, detections: &[Detection]) -> Vec<Observation> {
        let mut out = Vec::new();
        for d in detections {
            let Some((body, tag)) = self.marker.find_tag(d.id) else { continue };
            if body != kind {
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

    /// Settles a single tag's mirror ambiguity, flags what is worth knowing, and refuses a
    /// pose that is not finite.
    fn accept(
        &self,
        kind: BodyKind,
        pose: BodyPose,
        prior: Option<&Pose>,
        flags: &mut Vec<Flag>,
    ) -> Option<BodyResult> {
        let mut chosen = pose.camera_from_body;
        let mut rms = pose.rms_px;
        if pose.tags.len() == 1 {
            flags.push(Flag::SingleTag(kind));
        }
        if let Some((alternative, alt_rms)) = pose.alternative {
            match prior {
                Some(p) => {
                    let angle = |q: &Pose| q.rotation().angle_to(&p.rotation());
                    if angle(&alternative) < angle(&chosen) {
                        chosen = alternative;
                        rms = alt_rms;
                    }
                }
                None => flags.push(Flag::Ambiguous(kind)),
            }
        }
        if !pose.rejected_tags.is_empty() {
            flags.push(Flag::RejectedTags(kind));
        }
        if rms > self.config.max_rms_px {
            flags.push(Flag::HighReprojectionError(kind));
        }
        let finite = chosen.is_finite() && rms.is_finite();
        finite.then_some(BodyResult {
            camera_from_body: chosen,
            tags: pose.tags,
            rms_px: rms,
            covariance: pose.covariance,
        })
    }
}
