//! Refinement of a marker from a tracked session: every frame of a session shows the tags a
//! calibration recording missed beside tags it placed, so the session itself can place them.
//!
//! Per body, the tags the marker file says were calibrated are the gauge: they stay where they
//! are, and the views' poses rest on them. The other tags (nominal, or of unknown provenance)
//! seen well enough (below) are placed by the same bundle adjustment as a
//! calibration (assembly check first, then Huber loss, the weak prior toward where they
//! started, and outlier sightings dropped). A body with no calibrated tag has no gauge: every
//! tag is free, as in a first calibration.
//!
//! A session is not a calibration recording: at 30–60 fps its frames repeat one another, and a
//! marker that hardly turns (the upper jaw, on a still head) shows each tag from one side only.
//! Frame counts say little; what a tag is placed from is its directions of view. Seen edge-on,
//! a tag's corners carry systematic errors no number of frames averages away: measured on the
//! rendered hinge, counting frames, a tag seen obliquely in 396 frames of one view landed
//! 0.163 mm from where it is printed, its nominal place being 0.120 mm off. So sightings more
//! than `max_obliquity_deg` from face-on are left out, and a tag must be seen from
//! `min_viewpoints` directions `min_turn_deg` apart. One direction is the default: face-on,
//! one view places a tag well (the same hinge's upper tag 1: 0.174 mm off nominal, 0.048 mm
//! placed), and the upper jaw of a session is rarely seen from more; raise it to be stricter.
//!
//! Never worse: a new placement is taken only when the tag's RMS reprojection error over the
//! session's views is lower with it than with its old placement, each view's pose fitted
//! anew for the old; otherwise the tag keeps its old placement and the reason is reported
//! ([`Kept`]). What changed is listed per tag ([`BodyRefinement`]), and the marker file's
//! provenance records it.

use crate::{
    BodyCalibration, CalibrationError, CalibrationFrame, CalibrationOptions, Finding, TagCorrection, TagModel, View,
    calibrate_body, check_focal, fit_pose, record_provenance, tag_sse, views_of,
};
use jawtrack_marker::{BodyKind, Marker, TagProvenance};
use nalgebra::{Point3, Vector3};

/// Settings of a session refinement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionOptions {
    /// The adjustment's settings (its `min_views` is not used: see `min_viewpoints`).
    pub calibration: CalibrationOptions,
    /// Frames used at most, spread evenly over the session: neighbouring frames of a 30–60 fps
    /// session repeat one another, and the adjustment's time grows with the views.
    pub max_frames: usize,
    /// Directions a tag must be seen from to be placed …
    pub min_viewpoints: usize,
    /// … each this far (°) from the others, seen from the tag.
    pub min_turn_deg: f64,
    /// Sightings whose line of sight is further than this (°) from the tag's normal are left
    /// out: near edge-on, a tag's corners are where blur biases them most.
    pub max_obliquity_deg: f64,
}

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            calibration: CalibrationOptions::default(),
            max_frames: 600,
            min_viewpoints: 1,
            min_turn_deg: 5.0,
            max_obliquity_deg: 60.0,
        }
    }
}

/// Why a tag kept its old placement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kept {
    /// The marker file says it was calibrated: it is part of the gauge.
    Calibrated {
        /// The tag.
        id: u32,
    },
    /// Seen from too few directions in the session (with another tag of its body, and not
    /// edge-on).
    TooFewViewpoints {
        /// The tag.
        id: u32,
        /// Directions it was seen from.
        viewpoints: usize,
    },
    /// The new placement did not fit the session better than the old one.
    NotBetter {
        /// The tag.
        id: u32,
        /// Its RMS error (px) over the session with the old placement …
        rms_old_px: f64,
        /// … and with the new one.
        rms_new_px: f64,
    },
}

impl std::fmt::Display for Kept {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Kept::Calibrated { id } => write!(f, "tag {id}: calibrated before, kept as it was"),
            Kept::TooFewViewpoints { id, viewpoints } => write!(
                f,
                "tag {id}: seen from {viewpoints} direction(s) in the session, too few to place: kept as it was"
            ),
            Kept::NotBetter { id, rms_old_px, rms_new_px } => write!(
                f,
                "tag {id}: a new placement fitted no better ({rms_new_px:.3} px against {rms_old_px:.3} px): kept as it was"
            ),
        }
    }
}

/// What the session changed on one body.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyRefinement {
    /// The body.
    pub body: BodyKind,
    /// Views of the session that showed two of its tags or more.
    pub views: usize,
    /// RMS reprojection error (px) over its tags' corners with the marker given …
    pub rms_before_px: f64,
    /// … and with the refined one.
    pub rms_after_px: f64,
    /// Tags placed anew (their `rms_before_px` is with the old placement, each view's pose
    /// fitted to it).
    pub placed: Vec<TagCorrection>,
    /// Tags that kept their placement, and why.
    pub kept: Vec<Kept>,
    /// Assembly errors found among the placed tags.
    pub findings: Vec<Finding>,
}

/// A refined marker and what changed.
#[derive(Debug, Clone, PartialEq)]
pub struct Refinement {
    /// The marker: the input with the placed tags moved and the provenance updated.
    pub marker: Marker,
    /// Bodies the session showed, in the marker's order.
    pub bodies: Vec<BodyRefinement>,
    /// What the views say about the focal length, judged with the refined marker.
    pub focal: Option<crate::FocalCheck>,
}

impl Refinement {
    /// Whether any tag moved.
    pub fn changed(&self) -> bool {
        self.bodies.iter().any(|b| !b.placed.is_empty())
    }

    /// Adds `recording` to the recordings named in the provenance of every body the session
    /// changed.
    pub fn name_recording(&mut self, recording: &str) {
        for report in self.bodies.iter().filter(|b| !b.placed.is_empty()) {
            if let Some(p) =
                self.marker.bodies.iter_mut().find(|b| b.kind == report.body).and_then(|b| b.provenance.as_mut())
            {
                p.recordings.push(recording.to_owned());
            }
        }
    }
}

/// Refines `marker` from the tags detected in a session's frames (see the module docs).
pub fn refine(
    marker: &Marker,
    frames: &[CalibrationFrame],
    options: &SessionOptions,
) -> Result<Refinement, CalibrationError> {
    for (i, f) in frames.iter().enumerate() {
        f.camera.validate().map_err(|e| CalibrationError::BadFrame { frame: i, reason: e.to_string() })?;
    }
    let stride = frames.len().div_ceil(options.max_frames.max(1)).max(1);
    let used: Vec<CalibrationFrame> = frames.iter().step_by(stride).cloned().collect();
    let mut out = marker.clone();
    let mut bodies = Vec::new();
    for (b, body) in marker.bodies.iter().enumerate() {
        let held: Vec<usize> = (0..body.tags.len())
            .filter(|&t| matches!(body.tags[t].provenance, Some(TagProvenance::Calibrated { .. })))
            .collect();
        let (screened, viewpoints) = screen(body, &used, &held, options);
        let calibration = CalibrationOptions { min_views: 1, ..options.calibration };
        let Some((tags, report, views)) = calibrate_body(&body.tags, body.kind, &screened, &calibration, &held) else {
            continue;
        };
        let old: Vec<TagModel> = body.tags.iter().map(TagModel::of).collect();
        let old_rms = old_fit(&views, &old);
        let mut refined = body.tags.clone();
        let mut placed = Vec::new();
        let mut kept: Vec<Kept> = held.iter().map(|&t| Kept::Calibrated { id: body.tags[t].id }).collect();
        for (t, tag) in body.tags.iter().enumerate() {
            if !held.contains(&t) && !report.tags.iter().any(|c| c.id == tag.id) {
                kept.push(Kept::TooFewViewpoints { id: tag.id, viewpoints: viewpoints[t] });
            }
        }
        for c in &report.tags {
            let Some(t) = body.tags.iter().position(|t| t.id == c.id) else { continue };
            let rms_old_px = old_rms[t];
            if c.rms_after_px < rms_old_px {
                refined[t] = tags[t].clone();
                placed.push(TagCorrection { rms_before_px: rms_old_px, ..*c });
            } else {
                kept.push(Kept::NotBetter { id: c.id, rms_old_px, rms_new_px: c.rms_after_px });
            }
        }
        let findings: Vec<Finding> = report
            .findings
            .iter()
            .copied()
            .filter(|f| match *f {
                Finding::Turned { id, .. } | Finding::OnFace { id, .. } => placed.iter().any(|p| p.id == id),
                Finding::Uncalibrated { .. } => false,
            })
            .collect();
        let models: Vec<TagModel> = refined.iter().map(TagModel::of).collect();
        let (rms_before_px, rms_after_px) = (overall(&views, &old), overall(&views, &models));
        let refinement = BodyRefinement {
            body: body.kind,
            views: report.views,
            rms_before_px,
            rms_after_px,
            placed,
            kept,
            findings,
        };
        if !refinement.placed.is_empty() {
            out.bodies[b].tags = refined;
            record(&mut out.bodies[b], body, &refinement, &report);
        }
        bodies.push(refinement);
    }
    if bodies.is_empty() {
        return Err(CalibrationError::NoViews);
    }
    out.validate()?;
    let focal = check_focal(&out, &used);
    Ok(Refinement { marker: out, bodies, focal })
}

/// The session's frames as the refinement of `body` uses them: its sightings, less those
/// seen near edge-on and those of tags not calibrated that are seen from fewer than
/// `min_viewpoints` directions; and per tag the directions it was seen from.
fn screen(
    body: &jawtrack_marker::Body,
    frames: &[CalibrationFrame],
    held: &[usize],
    options: &SessionOptions,
) -> (Vec<CalibrationFrame>, Vec<usize>) {
    let models: Vec<TagModel> = body.tags.iter().map(TagModel::of).collect();
    let facing = options.max_obliquity_deg.to_radians().cos();
    let distinct = options.min_turn_deg.to_radians().cos();
    let mut directions: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); models.len()];
    let mut kept: Vec<CalibrationFrame> = Vec::new();
    for f in frames {
        let Some(view) = views_of(&body.tags, std::slice::from_ref(f)).pop() else { continue };
        let Some(pose) = fit_pose(&view, &models, None) else { continue };
        let camera_in_body = pose.inverse_transform_point(&Point3::origin());
        let mut ids = Vec::new();
        for s in &view.seen {
            let m = &models[s.tag];
            let towards = (camera_in_body.coords - m.center).normalize();
            if towards.dot(&m.normal) < facing {
                continue;
            }
            ids.push(body.tags[s.tag].id);
            if directions[s.tag].iter().all(|d| d.dot(&towards) < distinct) {
                directions[s.tag].push(towards);
            }
        }
        let tags = f.tags.iter().copied().filter(|t| ids.contains(&t.id)).collect();
        kept.push(CalibrationFrame { camera: f.camera, tags });
    }
    let viewpoints: Vec<usize> = directions.iter().map(Vec::len).collect();
    let placeable = |id: u32| {
        let t = body.tags.iter().position(|t| t.id == id);
        t.is_some_and(|t| held.contains(&t) || viewpoints[t] >= options.min_viewpoints)
    };
    for f in &mut kept {
        f.tags.retain(|t| placeable(t.id));
    }
    (kept, viewpoints)
}

/// Each tag's RMS error (px) over `views` with the placements `models`, each view's pose
/// fitted to them.
fn old_fit(views: &[View], models: &[TagModel]) -> Vec<f64> {
    let mut sums = vec![(0.0, 0usize); models.len()];
    for v in views {
        let Some(pose) = fit_pose(v, models, None) else { continue };
        for s in &v.seen {
            sums[s.tag].0 += tag_sse(v, s, &models[s.tag], &pose, [0, 1, 2, 3]);
            sums[s.tag].1 += 4;
        }
    }
    sums.into_iter().map(|(sum, n)| if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }).collect()
}

/// RMS error (px) over every corner of `views`, each view's pose fitted to `models`.
fn overall(views: &[View], models: &[TagModel]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in views {
        let Some(pose) = fit_pose(v, models, None) else { continue };
        for s in &v.seen {
            sum += tag_sse(v, s, &models[s.tag], &pose, [0, 1, 2, 3]);
            n += 4;
        }
    }
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}

/// The refined body's provenance: placed tags say so; tags kept keep theirs (a nominal tag's
/// view count is the session's when that is more); the body's figures are the session's.
fn record(
    body: &mut jawtrack_marker::Body,
    input: &jawtrack_marker::Body,
    refinement: &BodyRefinement,
    report: &BodyCalibration,
) {
    let recordings = input.provenance.as_ref().map(|p| p.recordings.clone()).unwrap_or_default();
    let mut session = report.clone();
    session.tags = refinement.placed.clone();
    session.rms_before_px = refinement.rms_before_px;
    session.rms_after_px = refinement.rms_after_px;
    record_provenance(body, &session);
    if let Some(p) = body.provenance.as_mut() {
        p.recordings = recordings;
    }
    for (tag, old) in body.tags.iter_mut().zip(&input.tags) {
        if refinement.placed.iter().any(|p| p.id == tag.id) {
            continue;
        }
        tag.provenance = match (old.provenance, tag.provenance) {
            (Some(TagProvenance::Calibrated { .. }), _) => old.provenance,
            (Some(TagProvenance::Nominal { views: a }), Some(TagProvenance::Nominal { views: b })) => {
                Some(TagProvenance::Nominal { views: a.max(b) })
            }
            (_, now) => now,
        };
    }
}
