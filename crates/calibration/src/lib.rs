//! Marker calibration by bundle adjustment: where each tag really sits on its body, from a
//! short recording of the marker turned in front of the camera.
//!
//! Tags are printed, cut and glued by hand, so each sits a few tenths of a millimetre and up
//! to a degree from where the ideal solid puts it — enough for 0.1–1 mm of jaw error. Per body:
//!
//! 1. **Assembly check.** A tag glued turned by a quarter or half turn, or on another tag's
//!    face, pairs its image corners with the wrong model corners and throws the pose by
//!    degrees. Each tag is tried at its four turns on every face of its body, against the pose
//!    the body's other tags give in each view; a placement that fits many times better than
//!    the nominal one is taken, and said in plain words ([`Finding`]).
//! 2. **Bundle adjustment.** Every view's body pose and every well-seen tag's in-plane
//!    placement (shift along the tag's x and y, turn about the face normal: the
//!    [`PrintError`] model) are refined together by Levenberg–Marquardt on the reprojection
//!    error, with a weak prior toward the nominal placement. The prior fixes what views cannot:
//!    turning the whole body is absorbed by the poses, so the calibrated marker is the one
//!    nearest the nominal solid among those that fit.
//! 3. A tag seen in fewer than `min_views` views is kept where the model (or the assembly
//!    check) puts it and named, never invented.
//!
//! 4. The cameras' focal length is judged against the calibrated marker ([`check_focal`]): a
//!    wrong one leaves every view fitting badly in the same way, which no tag placement fixes.
//!
//! The calibrated marker has the nominal file's schema; the tracker loads it as it is. Each
//! body calibrated records its provenance: views and RMS error before and after, per body and
//! per tag, each tag `Calibrated` or left `Nominal` (with the views it had); name the
//! recordings with [`Calibration::name_recordings`]. A body no view showed keeps what it had.

mod adjust;
mod describe;
mod focal;
mod session;
mod views;

use adjust::{Adjustment, adjust};
pub use describe::Account;
pub use focal::{FOCUS_MOVED, FocalCheck, check_focal};
use jawtrack_marker::{BodyKind, BodyProvenance, Marker, MarkerError, PrintError, Tag, TagProvenance};
use jawtrack_pose::{CameraIntrinsics, Observation, PnpOptions, median, solve_pnp};
use nalgebra::{Isometry3, Matrix3, Point2, Point3, Rotation3, Unit, Vector2, Vector3};
pub use session::{BodyRefinement, Kept, Refinement, SessionOptions, refine};
pub use views::{BodyOutcome, MIN_TURN_DEG, ViewOutcome, ViewSelector};

/// A tag seen in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeenTag {
    /// tag36h11 id.
    pub id: u32,
    /// Corners (px) in detection order (bottom-left, bottom-right, top-right, top-left).
    pub corners: [[f64; 2]; 4],
}

/// One view of the marker.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationFrame {
    /// The camera that took it.
    pub camera: CameraIntrinsics,
    /// The tags detected.
    pub tags: Vec<SeenTag>,
}

/// Settings of the calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationOptions {
    /// Views a tag needs (beside at least one other tag of its body) to be calibrated.
    pub min_views: usize,
    /// Corner noise (px): the scale of the prior against the reprojection errors.
    pub corner_sigma_px: f64,
    /// Prior spread of a tag's shift on its face (mm).
    pub shift_prior_mm: f64,
    /// Prior spread of a tag's turn on its face (°).
    pub rotation_prior_deg: f64,
    /// Levenberg–Marquardt iterations at most.
    pub max_iterations: usize,
    /// Corner residual (px) beyond which the adjustment's loss grows linearly (Huber): a
    /// corner blurred or seen edge-on weighs less than one seen well.
    pub huber_px: f64,
    /// After a first adjustment, a tag's sighting in a view is dropped when its RMS error
    /// exceeds this many times the median sighting's …
    pub outlier_ratio: f64,
    /// … and this (px); the adjustment then runs again without it.
    pub outlier_px: f64,
    /// Another placement is taken when the nominal one misses by more than this (px RMS) …
    pub gross_min_px: f64,
    /// … and the other fits at least this many times better.
    pub gross_ratio: f64,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            min_views: 3,
            corner_sigma_px: 0.3,
            shift_prior_mm: 0.5,
            rotation_prior_deg: 2.0,
            max_iterations: 100,
            huber_px: 1.0,
            outlier_ratio: 4.0,
            outlier_px: 0.3,
            gross_min_px: 5.0,
            gross_ratio: 4.0,
        }
    }
}

impl CalibrationOptions {
    fn adjustment(&self) -> Adjustment {
        let per_mm = self.corner_sigma_px / self.shift_prior_mm;
        Adjustment {
            prior: Vector3::new(per_mm, per_mm, self.corner_sigma_px / self.rotation_prior_deg.to_radians()),
            huber_px: self.huber_px,
            max_iterations: self.max_iterations,
        }
    }
}

/// Something the calibration found about the assembly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Finding {
    /// The tag is on its face but turned by `quarter_turns` quarter turns counter-clockwise,
    /// seen from outside (3 is a quarter turn clockwise).
    Turned {
        /// The tag.
        id: u32,
        /// 1, 2 or 3.
        quarter_turns: u8,
    },
    /// The tag is glued on another face (turned by `quarter_turns` there).
    OnFace {
        /// The tag.
        id: u32,
        /// Where the model puts it.
        nominal_face: usize,
        /// Where it is.
        face: usize,
        /// Quarter turns counter-clockwise seen from outside, 0–3.
        quarter_turns: u8,
    },
    /// Seen in too few views: kept where the model puts it.
    Uncalibrated {
        /// The tag.
        id: u32,
        /// Views it was seen in (with another tag of its body).
        views: usize,
    },
}

fn turn_words(quarter_turns: u8) -> &'static str {
    match quarter_turns % 4 {
        0 => "upright",
        1 => "a quarter turn counter-clockwise",
        2 => "a half turn",
        _ => "a quarter turn clockwise",
    }
}

impl std::fmt::Display for Finding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Finding::Turned { id, quarter_turns } => {
                write!(f, "tag {id} is glued {} from upright (seen from outside); corrected", turn_words(quarter_turns))
            }
            Finding::OnFace { id, nominal_face, face, quarter_turns } => write!(
                f,
                "tag {id} is glued on face {face}, not face {nominal_face} ({}, seen from outside); corrected",
                turn_words(quarter_turns)
            ),
            Finding::Uncalibrated { id, views } => write!(
                f,
                "tag {id} was seen in {views} usable view(s), too few to calibrate: kept at its nominal place"
            ),
        }
    }
}

/// One tag's calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TagCorrection {
    /// The tag.
    pub id: u32,
    /// Views it was seen in.
    pub views: usize,
    /// Its estimated placement relative to the model (after any assembly correction).
    pub placement: PrintError,
    /// Its RMS reprojection error (px) with the nominal marker, each view's pose fitted.
    pub rms_before_px: f64,
    /// … and after calibration.
    pub rms_after_px: f64,
}

/// One body's calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyCalibration {
    /// The body.
    pub body: BodyKind,
    /// Views that saw two tags of it or more.
    pub views: usize,
    /// RMS reprojection error (px) over its tags' corners with the nominal marker.
    pub rms_before_px: f64,
    /// … and with the calibrated one.
    pub rms_after_px: f64,
    /// The calibrated tags.
    pub tags: Vec<TagCorrection>,
    /// What the assembly check found, and the tags left uncalibrated.
    pub findings: Vec<Finding>,
}

/// The outcome: the calibrated marker and what was learnt per body.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// Same schema as the nominal marker.
    pub marker: Marker,
    /// Bodies seen, in the marker's order.
    pub bodies: Vec<BodyCalibration>,
    /// What the views say about the cameras' focal length ([`check_focal`]), when some view
    /// shows three tags of a body.
    pub focal: Option<FocalCheck>,
}

impl Calibration {
    /// Records the recordings calibrated from (a frames folder, a video path, as the user
    /// gave them) in the provenance of every body this calibration placed.
    pub fn name_recordings(&mut self, recordings: &[String]) {
        for report in &self.bodies {
            if let Some(p) =
                self.marker.bodies.iter_mut().find(|b| b.kind == report.body).and_then(|b| b.provenance.as_mut())
            {
                p.recordings = recordings.to_vec();
            }
        }
    }
}

fn count(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// The provenance of a body just calibrated and of each of its tags.
fn record_provenance(body: &mut jawtrack_marker::Body, report: &BodyCalibration) {
    body.provenance = Some(BodyProvenance {
        views: count(report.views),
        rms_before_px: report.rms_before_px,
        rms_after_px: report.rms_after_px,
        recordings: Vec::new(),
    });
    for tag in &mut body.tags {
        let calibrated = report.tags.iter().find(|c| c.id == tag.id).map(|c| TagProvenance::Calibrated {
            views: count(c.views),
            rms_before_px: c.rms_before_px,
            rms_after_px: c.rms_after_px,
        });
        let views = report.findings.iter().find_map(|f| match *f {
            Finding::Uncalibrated { id, views } if id == tag.id => Some(views),
            _ => None,
        });
        tag.provenance = Some(calibrated.unwrap_or(TagProvenance::Nominal { views: count(views.unwrap_or(0)) }));
    }
}

/// Why no calibration came out.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// No frame saw two tags of one body.
    #[error("no frame shows two tags of one body: nothing to calibrate from")]
    NoViews,
    /// A frame's intrinsics cannot describe a camera.
    #[error("frame {frame}: {reason}")]
    BadFrame {
        /// Its index.
        frame: usize,
        /// Why.
        reason: String,
    },
    /// The calibrated marker failed validation (a bug, or views that contradict each other).
    #[error("the calibrated marker is not valid: {0}")]
    Marker(#[from] MarkerError),
}

/// A tag's corners seen in one view: their undistorted normalised rays.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Seen {
    tag: usize,
    rays: [Vector2<f64>; 4],
}

/// One view of one body.
#[derive(Debug, Clone)]
pub(crate) struct View {
    focal: Vector2<f64>,
    seen: Vec<Seen>,
    pose: Isometry3<f64>,
}

/// A tag's geometry as the adjustment moves it: the base placement and the in-plane change.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TagModel {
    center: Vector3<f64>,
    x: Vector3<f64>,
    y: Vector3<f64>,
    normal: Vector3<f64>,
    offsets: [Vector3<f64>; 4],
    /// (shift x, shift y, turn) being estimated.
    e: Vector3<f64>,
}

impl TagModel {
    fn of(tag: &Tag) -> Self {
        let (x, y) = tag.axes();
        TagModel {
            center: tag.center,
            x,
            y,
            normal: tag.face_normal(),
            offsets: tag.corners.map(|c| c - tag.center),
            e: Vector3::zeros(),
        }
    }

    fn turn(&self) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Unit::new_unchecked(self.normal), self.e.z)
    }

    fn corner(&self, i: usize) -> Point3<f64> {
        Point3::from(self.center + self.x * self.e.x + self.y * self.e.y + self.turn() * self.offsets[i])
    }

    /// d corner / d e (3×3).
    fn corner_jacobian(&self, i: usize) -> Matrix3<f64> {
        let turned = self.turn() * self.offsets[i];
        Matrix3::from_columns(&[self.x, self.y, self.normal.cross(&turned)])
    }
}

/// Calibrates every body seen in `frames`, starting from `marker` (usually the nominal one).
pub fn calibrate(
    marker: &Marker,
    frames: &[CalibrationFrame],
    options: &CalibrationOptions,
) -> Result<Calibration, CalibrationError> {
    for (i, f) in frames.iter().enumerate() {
        f.camera.validate().map_err(|e| CalibrationError::BadFrame { frame: i, reason: e.to_string() })?;
    }
    let mut out = marker.clone();
    let mut bodies = Vec::new();
    for b in 0..marker.bodies.len() {
        if let Some((tags, report, _)) =
            calibrate_body(&marker.bodies[b].tags, marker.bodies[b].kind, frames, options, &[])
        {
            out.bodies[b].tags = tags;
            record_provenance(&mut out.bodies[b], &report);
            bodies.push(report);
        }
    }
    if bodies.is_empty() {
        return Err(CalibrationError::NoViews);
    }
    out.validate()?;
    // Judged with the calibrated marker: the nominal one's print errors blur the optimum.
    let focal = check_focal(&out, frames);
    Ok(Calibration { marker: out, bodies, focal })
}

/// A body's views: frames showing two of its tags or more, with poses from the model.
fn views_of(tags: &[Tag], frames: &[CalibrationFrame]) -> Vec<View> {
    let mut views = Vec::new();
    for f in frames {
        let seen: Vec<Seen> = f
            .tags
            .iter()
            .filter_map(|s| {
                let tag = tags.iter().position(|t| t.id == s.id)?;
                let mut rays = [Vector2::zeros(); 4];
                for (r, c) in rays.iter_mut().zip(&s.corners) {
                    let finite = c.iter().all(|v| v.is_finite());
                    *r = finite.then(|| f.camera.unproject(&Point2::new(c[0], c[1]))).flatten()?.xy();
                }
                Some(Seen { tag, rays })
            })
            .collect();
        if seen.len() < 2 {
            continue;
        }
        views.push(View { focal: Vector2::new(f.camera.fx, f.camera.fy), seen, pose: Isometry3::identity() });
    }
    views
}

/// The pose of a view from the given tags' placements (all seen tags but `without`).
fn fit_pose(view: &View, models: &[TagModel], without: Option<usize>) -> Option<Isometry3<f64>> {
    let camera = CameraIntrinsics::pinhole(view.focal.x, view.focal.y, 0.0, 0.0);
    let observations: Vec<Observation> = view
        .seen
        .iter()
        .filter(|s| Some(s.tag) != without)
        .flat_map(|s| {
            (0..4).map(move |i| Observation {
                tag: s.tag as u32,
                body: models[s.tag].corner(i),
                pixel: Point2::new(s.rays[i].x * view.focal.x, s.rays[i].y * view.focal.y),
            })
        })
        .collect();
    solve_pnp(&observations, &camera, None, &PnpOptions::default()).ok().map(|p| *p.camera_from_body.isometry())
}

/// Squared reprojection error (px²) of one seen tag's corners under `pose`.
fn tag_sse(view: &View, seen: &Seen, model: &TagModel, pose: &Isometry3<f64>, order: [usize; 4]) -> f64 {
    (0..4)
        .map(|i| {
            let c = pose * model.corner(order[i]);
            if c.z <= 1e-9 {
                return 1e12;
            }
            ((c.coords.xy() / c.z - seen.rays[i]).component_mul(&view.focal)).norm_squared()
        })
        .sum()
}

fn calibrate_body(
    tags: &[Tag],
    kind: BodyKind,
    frames: &[CalibrationFrame],
    options: &CalibrationOptions,
    held: &[usize],
) -> Option<(Vec<Tag>, BodyCalibration, Vec<View>)> {
    let mut views = views_of(tags, frames);
    if views.is_empty() {
        return None;
    }
    let nominal: Vec<TagModel> = tags.iter().map(TagModel::of).collect();
    for v in &mut views {
        v.pose = fit_pose(v, &nominal, None).unwrap_or_else(Isometry3::identity);
    }
    let counts = views_per_tag(&views, tags.len());
    let per_tag_rms = |models: &[TagModel], views: &[View], t: usize| -> f64 {
        let (mut sum, mut n) = (0.0, 0);
        for v in views {
            for s in v.seen.iter().filter(|s| s.tag == t) {
                sum += tag_sse(v, s, &models[t], &v.pose, [0, 1, 2, 3]);
                n += 4;
            }
        }
        if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
    };
    let rms_before: Vec<f64> = (0..tags.len()).map(|t| per_tag_rms(&nominal, &views, t)).collect();
    let overall_before = overall_rms(&nominal, &views);

    // 1. Assembly check.
    let (mut fixed, findings_assembly) = assembly_check(tags, &views, options, held);
    let mut models: Vec<TagModel> = fixed.iter().map(TagModel::of).collect();
    for v in &mut views {
        if let Some(p) = fit_pose(v, &models, None) {
            v.pose = p;
        }
    }
    // 2. Bundle adjustment of the poses and the well-seen tags.
    let placeable = |t: usize, counts: &[usize]| !held.contains(&t) && counts[t] >= options.min_views;
    let mut free: Vec<usize> = (0..tags.len()).filter(|&t| placeable(t, &counts)).collect();
    adjust(&mut views, &mut models, &free, &options.adjustment());
    // 3. A tag seen badly in one view (glare, the other marker's edge across it, a grazing
    //    angle) pulls every placement, Huber loss or not: drop such sightings, adjust again.
    // A tag left in place is reported with the views it was seen in, outliers or not: a
    // misplaced tag's sightings are outliers because it is misplaced.
    let seen = counts.clone();
    let mut counts = counts;
    for _ in 0..2 {
        if drop_outlier_sightings(&mut views, &models, options) == 0 {
            break;
        }
        counts = views_per_tag(&views, tags.len());
        free = (0..tags.len()).filter(|&t| placeable(t, &counts)).collect();
        for (t, m) in models.iter_mut().enumerate() {
            if !free.contains(&t) {
                m.e = Vector3::zeros();
            }
        }
        adjust(&mut views, &mut models, &free, &options.adjustment());
    }

    let mut findings = findings_assembly;
    let mut corrections = Vec::new();
    let mut placements = Vec::new();
    for t in 0..tags.len() {
        let views_seen = counts[t];
        if free.contains(&t) {
            let e = models[t].e;
            let placement = PrintError { shift_x: e.x, shift_y: e.y, rotation: e.z };
            placements.push((tags[t].id, placement));
            corrections.push(TagCorrection {
                id: tags[t].id,
                views: views_seen,
                placement,
                rms_before_px: rms_before[t],
                rms_after_px: per_tag_rms(&models, &views, t),
            });
        } else if !held.contains(&t) {
            findings.push(Finding::Uncalibrated { id: tags[t].id, views: seen[t] });
        }
    }
    // The adjusted placements, written the way the marker model displaces a tag.
    let displaced = Marker {
        edge: 0.0,
        bodies: vec![jawtrack_marker::Body { kind, tags: fixed.clone(), provenance: None }],
        ..Marker::default()
    }
    .with_print_errors(&placements)
    .ok()?;
    fixed = displaced.bodies.into_iter().next()?.tags;
    let report = BodyCalibration {
        body: kind,
        views: views.len(),
        rms_before_px: overall_before,
        rms_after_px: overall_rms(&models, &views),
        tags: corrections,
        findings,
    };
    Some((fixed, report, views))
}

/// Drops the sightings whose RMS error is past `options.outlier_ratio` × the median
/// sighting's and past `options.outlier_px`, and the views left with fewer than two tags,
/// unless that would leave a tag uncalibrated. Returns how many sightings went.
fn drop_outlier_sightings(views: &mut Vec<View>, models: &[TagModel], options: &CalibrationOptions) -> usize {
    let rms = |v: &View, s: &Seen| (tag_sse(v, s, &models[s.tag], &v.pose, [0, 1, 2, 3]) / 4.0).sqrt();
    let all: Vec<f64> = views.iter().flat_map(|v| v.seen.iter().map(move |s| rms(v, s))).collect();
    if all.is_empty() {
        return 0;
    }
    let limit = (median(all).unwrap_or(0.0) * options.outlier_ratio).max(options.outlier_px);
    // A tag that would be left in too few views (its sightings all oblique, or its views
    // emptied of other tags) keeps its sightings rather than being left nominal: a place
    // fitted to poor sightings is nearer the truth than none.
    let count = |views: &[View]| {
        let mut n = vec![0usize; models.len()];
        for v in views {
            for s in &v.seen {
                n[s.tag] += 1;
            }
        }
        n
    };
    let before = count(views);
    let mut spared = vec![false; models.len()];
    loop {
        let kept: Vec<View> = views
            .iter()
            .map(|v| View {
                seen: v.seen.iter().copied().filter(|s| spared[s.tag] || rms(v, s) <= limit).collect(),
                ..v.clone()
            })
            .filter(|v| v.seen.len() >= 2)
            .collect();
        let after = count(&kept);
        let starved: Vec<usize> = (0..models.len())
            .filter(|&t| !spared[t] && before[t] >= options.min_views && after[t] < options.min_views)
            .collect();
        if starved.is_empty() {
            *views = kept;
            return before.iter().sum::<usize>() - after.iter().sum::<usize>();
        }
        for t in starved {
            spared[t] = true;
        }
    }
}

/// How many views see each of `tags` tags.
fn views_per_tag(views: &[View], tags: usize) -> Vec<usize> {
    (0..tags).map(|t| views.iter().filter(|v| v.seen.iter().any(|s| s.tag == t)).count()).collect()
}

/// RMS reprojection error (px) over every corner of every view.
fn overall_rms(models: &[TagModel], views: &[View]) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for v in views {
        for s in &v.seen {
            sum += tag_sse(v, s, &models[s.tag], &v.pose, [0, 1, 2, 3]);
            n += 4;
        }
    }
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}

/// Tries every tag at its four turns on every face of the body, against the poses the other
/// tags give in views of four tags or more; returns the corrected tags and what was corrected.
fn assembly_check(
    tags: &[Tag],
    views: &[View],
    options: &CalibrationOptions,
    held: &[usize],
) -> (Vec<Tag>, Vec<Finding>) {
    let models: Vec<TagModel> = tags.iter().map(TagModel::of).collect();
    let mut fixed = tags.to_vec();
    let mut findings = Vec::new();
    for t in (0..tags.len()).filter(|t| !held.contains(t)) {
        // Views where the tag and three others are seen: the others fix the pose, and the PnP
        // drops one of them that is itself misplaced.
        let poses: Vec<(&View, &Seen, Isometry3<f64>)> = views
            .iter()
            .filter(|v| v.seen.len() >= 4)
            .filter_map(|v| {
                let seen = v.seen.iter().find(|s| s.tag == t)?;
                Some((v, seen, fit_pose(v, &models, Some(t))?))
            })
            .collect();
        if poses.is_empty() {
            continue;
        }
        // The median over views of the tag's RMS error: a view whose pose a second misplaced
        // tag spoiled does not decide.
        let rms = |face_tag: usize, turns: usize| -> f64 {
            let order = [turns % 4, (turns + 1) % 4, (turns + 2) % 4, (turns + 3) % 4];
            median(poses.iter().map(|(v, s, p)| (tag_sse(v, s, &models[face_tag], p, order) / 4.0).sqrt()))
                .unwrap_or(0.0)
        };
        let nominal = rms(t, 0);
        if nominal <= options.gross_min_px {
            continue;
        }
        let mut best = (t, 0usize, nominal);
        for other in 0..tags.len() {
            for turns in 0..4 {
                let e = rms(other, turns);
                if e < best.2 {
                    best = (other, turns, e);
                }
            }
        }
        let (face_tag, turns, error) = best;
        if error * options.gross_ratio > nominal {
            continue;
        }
        let template = &tags[face_tag];
        let order = [turns % 4, (turns + 1) % 4, (turns + 2) % 4, (turns + 3) % 4];
        fixed[t] = Tag {
            face: template.face,
            corners: order.map(|i| template.corners[i]),
            center: template.center,
            face_polygon: template.face_polygon.clone(),
            ..tags[t].clone()
        };
        let quarter_turns = turns as u8;
        findings.push(if face_tag == t {
            Finding::Turned { id: tags[t].id, quarter_turns }
        } else {
            Finding::OnFace { id: tags[t].id, nominal_face: tags[t].face, face: template.face, quarter_turns }
        });
    }
    (fixed, findings)
}
