//! Pose of one rigid body from its points seen by a calibrated camera (PnP).
//!
//! All visible points of the body are used at once (tag corners and centres from any number of
//! tags). Starting poses come from the previous frame when tracking and from IPPE on each
//! visible tag (its two planar solutions, `ippe`); each is scored on every point, and the
//! best are refined by Levenberg–Marquardt on the reprojection error in pixels with a Huber
//! loss, then polished by Gauss–Newton (near the minimum the cost's rounding hides the last
//! 1e-8 of the pose; the gradient does not). When tracking several tags, the previous pose
//! refined to a good fit is taken at once (15 µs per body instead of 75). From three tags up,
//! a tag the others disagree with (held out, it misses the pose they give by more than
//! `outlier_px` and four times their own error) is dropped and the pose solved again. With a
//! single tag the planar ambiguity is real: where the mirror solution is a minimum of its own
//! it is returned beside the best, with its own fit and covariance ([`BodyPose::alternative`]),
//! for the caller to settle with the other body or the previous frame — never silently flipped.
//! Near head-on, one 10 mm tag at 100 mm fixes orientation only to tens of degrees at 0.3 px
//! noise, and the covariance (a linearisation) understates that: a lone tag is a weak
//! measurement whatever the solver.
//!
//! The covariance is that of a left perturbation of `camera_from_body` in the camera frame,
//! (rotation vector \[rad\], translation \[mm\]), from the Gauss–Newton normal matrix scaled by the
//! residuals' variance (or by `corner_sigma_px`² when there are too few points to estimate it).

use crate::lm::{self, Damping, damped};
use crate::{CameraIntrinsics, Pose};
use nalgebra::{
    Isometry3, Matrix2x3, Matrix3, Matrix6, Point2, Point3, Rotation3, SMatrix, Translation3, UnitQuaternion, Vector2,
    Vector3, Vector6,
};

/// One point of the body and where it was seen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// The tag it belongs to (points of one tag are coplanar).
    pub tag: u32,
    /// The point in the body frame (mm).
    pub body: Point3<f64>,
    /// Where it was seen (px).
    pub pixel: Point2<f64>,
}

/// Settings of the solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PnpOptions {
    /// Residual (px) beyond which the Huber loss grows linearly instead of quadratically. At
    /// 1 px a corner spoiled by glare or blur weighs little; 3 px doubled the worst jaw error
    /// on our realistic fixtures (`crates/tracker/tests/fixtures.rs`), though it solves ~2×
    /// faster.
    pub huber_px: f64,
    /// From three tags up, a tag whose error (px) under the pose fitted to the other tags
    /// exceeds this and four times their own RMS error is dropped.
    pub outlier_px: f64,
    /// With several tags, a start that converges to an RMS error (px) within this is taken as
    /// the pose without refining the others: a wrong minimum misses whole tags by far more.
    pub good_fit_px: f64,
    /// Corner noise (px) assumed for the covariance when too few points estimate it.
    pub corner_sigma_px: f64,
    /// Levenberg–Marquardt iterations per refinement.
    pub max_iterations: usize,
}

impl Default for PnpOptions {
    fn default() -> Self {
        PnpOptions { huber_px: 1.0, outlier_px: 2.0, good_fit_px: 4.0, corner_sigma_px: 0.2, max_iterations: 50 }
    }
}

/// A solved body pose.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyPose {
    /// Maps body points into the camera frame (mm).
    pub camera_from_body: Pose,
    /// Covariance of (rotation vector \[rad\], translation \[mm\]) of a left perturbation in the
    /// camera frame.
    pub covariance: Matrix6<f64>,
    /// RMS reprojection error over the points used (px).
    pub rms_px: f64,
    /// Tags whose points were used, ascending.
    pub tags: Vec<u32>,
    /// Tags dropped as inconsistent with the others.
    pub rejected_tags: Vec<u32>,
    /// With a single tag: the other planar solution, refined.
    pub alternative: Option<Alternative>,
}

/// A single tag's other planar solution, with its own fit and covariance: a caller that takes
/// it must report its covariance, not the best solution's.
#[derive(Debug, Clone, PartialEq)]
pub struct Alternative {
    /// Maps body points into the camera frame (mm).
    pub camera_from_body: Pose,
    /// Covariance at this pose, as [`BodyPose::covariance`].
    pub covariance: Matrix6<f64>,
    /// RMS reprojection error over the points used (px).
    pub rms_px: f64,
}

/// Why no pose could be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PnpError {
    /// Fewer than four usable points.
    #[error("PnP needs at least 4 points, got {0}")]
    TooFewPoints(usize),
    /// A coordinate was NaN or infinite.
    #[error("observation {index} has a non-finite coordinate")]
    NotFinite {
        /// Index of the observation.
        index: usize,
    },
    /// Intrinsics that cannot describe a camera.
    #[error("{0}")]
    BadIntrinsics(String),
    /// The points do not determine a pose (collinear, or every start failed).
    #[error("the points do not determine a pose: {0}")]
    Degenerate(&'static str),
}

/// A point with its undistorted normalised observation.
#[derive(Debug, Clone, Copy)]
struct Point {
    tag: u32,
    body: Point3<f64>,
    seen: Vector2<f64>,
}

/// Solves the pose of one body. `prior` (e.g. the previous frame's pose) is tried as a start
/// alongside the per-tag IPPE starts.
pub fn solve_pnp(
    observations: &[Observation],
    camera: &CameraIntrinsics,
    prior: Option<&Pose>,
    options: &PnpOptions,
) -> Result<BodyPose, PnpError> {
    camera.validate().map_err(|e| PnpError::BadIntrinsics(e.to_string()))?;
    let mut points = Vec::with_capacity(observations.len());
    for (index, o) in observations.iter().enumerate() {
        let finite = o.body.coords.iter().chain(o.pixel.coords.iter()).all(|v| v.is_finite());
        if !finite {
            return Err(PnpError::NotFinite { index });
        }
        // Points beyond the distortion model's fold cannot be used.
        if let Some(ray) = camera.unproject(&o.pixel) {
            points.push(Point { tag: o.tag, body: o.body, seen: ray.xy() });
        }
    }
    if points.len() < 4 {
        return Err(PnpError::TooFewPoints(points.len()));
    }
    let focal = Vector2::new(camera.fx, camera.fy);
    let mut rejected = Vec::new();
    loop {
        let (best, alternative) = best_pose(&points, prior, &focal, options)?;
        let per_tag = tag_rms(&points, &best.0, &focal);
        if let Some(bad) = inconsistent_tag(&points, &best, &per_tag, &focal, options) {
            rejected.push(bad);
            points.retain(|p| p.tag != bad);
            continue;
        }
        let (pose, rms) = best;
        let alternative = alternative.map(|(p, rms_px)| Alternative {
            camera_from_body: Pose::from_isometry(p),
            covariance: covariance(&points, &p, &focal, options),
            rms_px,
        });
        let covariance = covariance(&points, &pose, &focal, options);
        let mut tags: Vec<u32> = per_tag.iter().map(|t| t.0).collect();
        tags.sort_unstable();
        rejected.sort_unstable();
        return Ok(BodyPose {
            camera_from_body: Pose::from_isometry(pose),
            covariance,
            rms_px: rms,
            tags,
            rejected_tags: rejected,
            alternative,
        });
    }
}

type Solution = (Isometry3<f64>, f64);

/// The refined best pose over all starts, and for a single tag the best one that is a
/// distinct (mirror) solution.
fn best_pose(
    points: &[Point],
    prior: Option<&Pose>,
    focal: &Vector2<f64>,
    options: &PnpOptions,
) -> Result<(Solution, Option<Solution>), PnpError> {
    let mut tags: Vec<u32> = points.iter().map(|p| p.tag).collect();
    tags.sort_unstable();
    tags.dedup();
    // Tracking several tags: the prior refined to a good fit is the pose (see below), and the
    // planar starts are not needed.
    if let (Some(prior), true) = (prior, tags.len() > 1)
        && let Some(p) = refine(points, prior.isometry(), focal, options)
    {
        let fit = rms(points, &p, focal);
        if fit <= options.good_fit_px {
            return Ok(((p, fit), None));
        }
    }
    let mut starts: Vec<Isometry3<f64>> = prior.map(|p| *p.isometry()).into_iter().collect();
    for &tag in &tags {
        let on_tag: Vec<&Point> = points.iter().filter(|p| p.tag == tag).collect();
        if on_tag.len() >= 4 {
            starts.extend(planar_starts(&on_tag));
        }
    }
    if starts.is_empty() {
        return Err(PnpError::Degenerate("no tag with 4 points and no prior pose"));
    }
    // Score every start on all points; refine the best ones. With several tags a start that
    // converges to a good fit is the pose, so the rest are not refined; a single tag refines
    // them all, for its mirror.
    let mut scored: Vec<(f64, Isometry3<f64>)> = starts.iter().map(|s| (cost(points, s, focal, options), *s)).collect();
    scored.retain(|s| s.0.is_finite());
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut refined: Vec<Solution> = Vec::new();
    for (_, s) in scored.iter().take(4) {
        let Some(p) = refine(points, s, focal, options) else { continue };
        let fit = rms(points, &p, focal);
        refined.push((p, fit));
        if tags.len() > 1 && fit <= options.good_fit_px {
            break;
        }
    }
    refined.sort_by(|a, b| a.1.total_cmp(&b.1));
    let Some(&best) = refined.first() else {
        return Err(PnpError::Degenerate("every starting pose failed to converge"));
    };
    let alternative =
        (tags.len() == 1).then(|| refined.iter().find(|s| rotation_angle(&s.0, &best.0) > 1e-3).copied()).flatten();
    Ok((best, alternative))
}

/// The angle (rad) between two poses' rotations.
fn rotation_angle(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    a.rotation.angle_to(&b.rotation)
}

/// Both IPPE poses of one tag's points (camera_from_body).
fn planar_starts(on_tag: &[&Point]) -> Vec<Isometry3<f64>> {
    // A frame in the tag's plane: origin at the centroid, z along the normal.
    let n = on_tag.len() as f64;
    let centroid = on_tag.iter().fold(Vector3::zeros(), |a, p| a + p.body.coords) / n;
    let mut scatter = Matrix3::zeros();
    for p in on_tag {
        let d = p.body.coords - centroid;
        scatter += d * d.transpose();
    }
    let eig = scatter.symmetric_eigen();
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let (ex, ey) = (eig.eigenvectors.column(order[0]).into_owned(), eig.eigenvectors.column(order[1]).into_owned());
    let ez = ex.cross(&ey);
    // body_from_plane: plane (u, v, 0) → body.
    let basis = Matrix3::from_columns(&[ex, ey, ez]);
    // Eigenvectors of a symmetric matrix are orthonormal, and ez = ex × ey makes it proper.
    let rot = Rotation3::from_matrix_unchecked(basis);
    let body_from_plane =
        Isometry3::from_parts(Translation3::from(centroid), UnitQuaternion::from_rotation_matrix(&rot));
    let plane: Vec<(Vector2<f64>, Vector2<f64>)> = on_tag
        .iter()
        .map(|p| {
            let q = body_from_plane.inverse_transform_point(&p.body);
            (q.coords.xy(), p.seen)
        })
        .collect();
    let Some(h) = homography(&plane) else { return Vec::new() };
    ippe(&h)
        .into_iter()
        .filter_map(|r| {
            let t = translation_for(&r, &plane)?;
            let camera_from_plane = Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_matrix(&r));
            Some(camera_from_plane * body_from_plane.inverse())
        })
        .collect()
}

/// The homography taking plane points to normalised image points (DLT with Hartley
/// normalisation), scaled so that h₃₃ = 1; `None` if degenerate.
fn homography(pairs: &[(Vector2<f64>, Vector2<f64>)]) -> Option<Matrix3<f64>> {
    let normaliser = |pts: &mut dyn Iterator<Item = Vector2<f64>>| -> Matrix3<f64> {
        let v: Vec<Vector2<f64>> = pts.collect();
        let c = v.iter().fold(Vector2::zeros(), |a, p| a + p) / v.len() as f64;
        let d = v.iter().map(|p| (p - c).norm()).sum::<f64>() / v.len() as f64;
        let s = if d > 0.0 { std::f64::consts::SQRT_2 / d } else { 1.0 };
        Matrix3::new(s, 0.0, -s * c.x, 0.0, s, -s * c.y, 0.0, 0.0, 1.0)
    };
    let ta = normaliser(&mut pairs.iter().map(|p| p.0));
    let tb = normaliser(&mut pairs.iter().map(|p| p.1));
    let mut a = nalgebra::DMatrix::<f64>::zeros(2 * pairs.len().max(5), 9);
    for (i, (p, q)) in pairs.iter().enumerate() {
        let p = ta * Vector3::new(p.x, p.y, 1.0);
        let q = tb * Vector3::new(q.x, q.y, 1.0);
        let (x, y) = (q.x / q.z, q.y / q.z);
        let row0 = [p.x, p.y, p.z, 0.0, 0.0, 0.0, -x * p.x, -x * p.y, -x * p.z];
        let row1 = [0.0, 0.0, 0.0, p.x, p.y, p.z, -y * p.x, -y * p.y, -y * p.z];
        for j in 0..9 {
            a[(2 * i, j)] = row0[j];
            a[(2 * i + 1, j)] = row1[j];
        }
    }
    let svd = a.svd(false, true);
    let vt = svd.v_t?;
    let (imin, _) = svd.singular_values.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    let h = vt.row(imin);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let h = tb.try_inverse()? * hn * ta;
    (h[(2, 2)].abs() > 1e-12).then(|| h / h[(2, 2)])
}

/// IPPE (Collins & Bartoli 2014, algorithm 1): the two rotations of a plane whose homography
/// to normalised image points is `h`, from its value and Jacobian at the plane's origin.
fn ippe(h: &Matrix3<f64>) -> Vec<Matrix3<f64>> {
    let v = Vector2::new(h[(0, 2)], h[(1, 2)]);
    let j = nalgebra::Matrix2::new(
        h[(0, 0)] - h[(2, 0)] * v.x,
        h[(0, 1)] - h[(2, 1)] * v.x,
        h[(1, 0)] - h[(2, 0)] * v.y,
        h[(1, 1)] - h[(2, 1)] * v.y,
    );
    // Rv turns the optical axis onto the ray through v.
    let t = v.norm();
    let s = (1.0 + t * t).sqrt();
    let rv = if t > 0.0 {
        let (costh, sinth) = (1.0 / s, (1.0 - 1.0 / (s * s)).max(0.0).sqrt());
        let k = Matrix3::new(0.0, 0.0, v.x, 0.0, 0.0, v.y, -v.x, -v.y, 0.0) / t;
        Matrix3::identity() + sinth * k + (1.0 - costh) * k * k
    } else {
        Matrix3::identity()
    };
    let proj = Matrix2x3::new(1.0, 0.0, -v.x, 0.0, 1.0, -v.y);
    let b = proj * rv.fixed_view::<3, 2>(0, 0);
    let Some(binv) = b.try_inverse() else { return Vec::new() };
    let a = binv * j;
    let aat = a * a.transpose();
    let gamma = (0.5
        * (aat[(0, 0)] + aat[(1, 1)] + ((aat[(0, 0)] - aat[(1, 1)]).powi(2) + 4.0 * aat[(0, 1)].powi(2)).sqrt()))
    .sqrt();
    if gamma.is_nan() || gamma <= 0.0 {
        return Vec::new();
    }
    let r22 = a / gamma;
    let hh = nalgebra::Matrix2::identity() - r22.transpose() * r22;
    let mut bv = Vector2::new(hh[(0, 0)].max(0.0).sqrt(), hh[(1, 1)].max(0.0).sqrt());
    if hh[(0, 1)] < 0.0 {
        bv.y = -bv.y;
    }
    let c1 = Vector3::new(r22[(0, 0)], r22[(1, 0)], bv.x);
    let c2 = Vector3::new(r22[(0, 1)], r22[(1, 1)], bv.y);
    let d = c1.cross(&c2);
    let make = |sign: f64| {
        rv * Matrix3::new(
            r22[(0, 0)],
            r22[(0, 1)],
            sign * d.x,
            r22[(1, 0)],
            r22[(1, 1)],
            sign * d.y,
            sign * bv.x,
            sign * bv.y,
            d.z,
        )
    };
    vec![make(1.0), make(-1.0)]
}

/// The translation that best places plane points (z = 0) rotated by `r` on their rays
/// (linear least squares).
fn translation_for(r: &Matrix3<f64>, plane: &[(Vector2<f64>, Vector2<f64>)]) -> Option<Vector3<f64>> {
    let (mut ata, mut atb) = (Matrix3::zeros(), Vector3::zeros());
    for (p, seen) in plane {
        let q = r * Vector3::new(p.x, p.y, 0.0);
        // x·(q.z + tz) = q.x + tx  →  tx − x·tz = x·q.z − q.x (and likewise for y).
        for (row, rhs) in [
            (Vector3::new(1.0, 0.0, -seen.x), seen.x * q.z - q.x),
            (Vector3::new(0.0, 1.0, -seen.y), seen.y * q.z - q.y),
        ] {
            ata += row * row.transpose();
            atb += row * rhs;
        }
    }
    let t = ata.try_inverse()? * atb;
    (t.z > 0.0).then_some(t)
}

/// Residual (px) of one point: projected minus seen, or `None` behind the camera.
fn residual(p: &Point, pose: &Isometry3<f64>, focal: &Vector2<f64>) -> Option<Vector2<f64>> {
    let c = pose * p.body;
    (c.z > 1e-9).then(|| (Vector2::new(c.x / c.z, c.y / c.z) - p.seen).component_mul(focal))
}

/// Huber cost over all points; infinite if any is behind the camera.
fn cost(points: &[Point], pose: &Isometry3<f64>, focal: &Vector2<f64>, options: &PnpOptions) -> f64 {
    let k = options.huber_px;
    points
        .iter()
        .map(|p| match residual(p, pose, focal) {
            Some(r) => {
                let e = r.norm();
                if e <= k { 0.5 * e * e } else { k * (e - 0.5 * k) }
            }
            None => f64::INFINITY,
        })
        .sum()
}

/// RMS reprojection error (px).
fn rms(points: &[Point], pose: &Isometry3<f64>, focal: &Vector2<f64>) -> f64 {
    let sum: f64 = points.iter().map(|p| residual(p, pose, focal).map_or(f64::INFINITY, |r| r.norm_squared())).sum();
    (sum / points.len() as f64).sqrt()
}

/// Each tag's RMS error (px), by tag id.
fn tag_rms(points: &[Point], pose: &Isometry3<f64>, focal: &Vector2<f64>) -> Vec<(u32, f64)> {
    let mut out: Vec<(u32, f64, usize)> = Vec::new();
    for p in points {
        let e2 = residual(p, pose, focal).map_or(f64::INFINITY, |r| r.norm_squared());
        match out.iter_mut().find(|t| t.0 == p.tag) {
            Some(t) => {
                t.1 += e2;
                t.2 += 1;
            }
            None => out.push((p.tag, e2, 1)),
        }
    }
    out.into_iter().map(|(t, s, n)| (t, (s / n as f64).sqrt())).collect()
}

/// A tag the others disagree with: with three tags or more, a fit worse than the noise and a
/// tag that fits 1.5× worse than the others, the two tags the joint fit misses most are each
/// held out in turn and the pose refitted to the rest; the one whose own error under that pose
/// is larger is dropped if it exceeds both `outlier_px` and four times the rest's RMS error. The
/// test is relative so that a nominal marker's print errors (a few px on every tag) drop few
/// tags: on the reference stack's corners it dropped a tag in 46 of 363 bodies, against 357
/// with a factor of two (`crates/tracker-bench`). With two tags there is no majority to say
/// which one is wrong.
fn inconsistent_tag(
    points: &[Point],
    best: &Solution,
    per_tag: &[(u32, f64)],
    focal: &Vector2<f64>,
    options: &PnpOptions,
) -> Option<u32> {
    if per_tag.len() < 3 || best.1 <= 0.5 * options.outlier_px {
        return None;
    }
    let mut suspects = per_tag.to_vec();
    suspects.sort_by(|a, b| b.1.total_cmp(&a.1));
    // Nothing to drop unless some tag already stands out in the joint fit: held out, a tag
    // misses by more than it does in the fit, but not by four times the rest when it fits like them.
    let others = suspects[1..].iter().map(|t| t.1 * t.1).sum::<f64>() / (suspects.len() - 1) as f64;
    if suspects[0].1 <= 1.5 * others.sqrt() {
        return None;
    }
    let mut worst: Option<(u32, f64)> = None;
    for &(tag, _) in suspects.iter().take(2) {
        let (held, rest): (Vec<Point>, Vec<Point>) = points.iter().partition(|p| p.tag == tag);
        let Some(pose) = refine(&rest, &best.0, focal, options) else { continue };
        let error = rms(&held, &pose, focal);
        let limit = options.outlier_px.max(4.0 * rms(&rest, &pose, focal));
        if error > limit && worst.is_none_or(|w| error > w.1) {
            worst = Some((tag, error));
        }
    }
    worst.map(|w| w.0)
}

/// d(residual)/d(left perturbation (ω, v)) of one point (2×6, px per rad / mm).
fn jacobian(p: &Point, pose: &Isometry3<f64>, focal: &Vector2<f64>) -> Option<SMatrix<f64, 2, 6>> {
    let c = pose * p.body;
    let dproj = projection_jacobian(&c, focal)?;
    Some(pose_jacobian(&c, &dproj))
}

/// d(pixel residual)/d(camera-frame point) of the normalised projection scaled by the focal
/// lengths (2×3, px per mm); `None` behind the camera. (Shared with bundle adjustment.)
pub fn projection_jacobian(c: &Point3<f64>, focal: &Vector2<f64>) -> Option<Matrix2x3<f64>> {
    if c.z <= 1e-9 {
        return None;
    }
    let iz = 1.0 / c.z;
    Some(Matrix2x3::new(focal.x * iz, 0.0, -focal.x * c.x * iz * iz, 0.0, focal.y * iz, -focal.y * c.y * iz * iz))
}

/// d(pixel residual)/d(left perturbation (ω, v)) of a camera-frame point `c`, given its
/// projection Jacobian (2×6, px per rad / mm).
pub fn pose_jacobian(c: &Point3<f64>, dproj: &Matrix2x3<f64>) -> SMatrix<f64, 2, 6> {
    // d c / d ω = −[c]×, d c / d v = I.
    let skew = Matrix3::new(0.0, c.z, -c.y, -c.z, 0.0, c.x, c.y, -c.x, 0.0);
    let mut j = SMatrix::<f64, 2, 6>::zeros();
    j.fixed_view_mut::<2, 3>(0, 0).copy_from(&(dproj * skew));
    j.fixed_view_mut::<2, 3>(0, 3).copy_from(dproj);
    j
}

/// Applies a left perturbation (ω \[rad\], v \[mm\]) in the `to` frame: p ↦ exp(ω)·(pose·p) + v.
pub fn perturb(pose: &Isometry3<f64>, d: &Vector6<f64>) -> Isometry3<f64> {
    let r = UnitQuaternion::from_scaled_axis(Vector3::new(d[0], d[1], d[2]));
    let t = r * pose.translation.vector + Vector3::new(d[3], d[4], d[5]);
    Isometry3::from_parts(Translation3::from(t), r * pose.rotation)
}

/// Levenberg–Marquardt with Huber weights (IRLS) from `start`.
fn refine(
    points: &[Point],
    start: &Isometry3<f64>,
    focal: &Vector2<f64>,
    options: &PnpOptions,
) -> Option<Isometry3<f64>> {
    let mut pose = *start;
    let mut current = cost(points, &pose, focal, options);
    if !current.is_finite() {
        return None;
    }
    let normal_equations = |pose: &Isometry3<f64>| -> Option<(Matrix6<f64>, Vector6<f64>)> {
        let (mut h, mut g) = (Matrix6::zeros(), Vector6::zeros());
        for p in points {
            let (r, j) = (residual(p, pose, focal)?, jacobian(p, pose, focal)?);
            let e = r.norm();
            let w = if e <= options.huber_px { 1.0 } else { options.huber_px / e };
            h += w * j.transpose() * j;
            g += w * j.transpose() * r;
        }
        Some((h, g))
    };
    let damping = Damping {
        initial: 1e-3,
        diagonal_floor: 1e-12,
        relative_tolerance: 1e-6,
        max_iterations: options.max_iterations,
    };
    lm::minimise(
        &mut pose,
        &mut current,
        &damping,
        &normal_equations,
        |pose, (h, g), lambda| {
            let step = damped(h, lambda, damping.diagonal_floor).cholesky().map(|c| c.solve(&(-g)))?;
            Some(perturb(pose, &step))
        },
        |candidate| cost(points, candidate, focal, options),
    )?;
    // Polish with plain Gauss–Newton steps: near the minimum the cost changes by the square of
    // the distance and rounding hides the last 1e-8 of the pose, the gradient does not.
    for _ in 0..3 {
        let (h, g) = normal_equations(&pose)?;
        let Some(step) = h.cholesky().map(|c| c.solve(&(-g))) else { break };
        if step.norm().is_nan() || step.norm() >= 1e-4 {
            break; // not close enough for an undamped step to be safe
        }
        pose = perturb(&pose, &step);
        if step.norm() < 1e-14 {
            break;
        }
    }
    Some(pose)
}

/// Covariance of the left perturbation at `pose` (see the module docs).
fn covariance(points: &[Point], pose: &Isometry3<f64>, focal: &Vector2<f64>, options: &PnpOptions) -> Matrix6<f64> {
    let mut h = Matrix6::zeros();
    let mut sum2 = 0.0;
    for p in points {
        if let (Some(r), Some(j)) = (residual(p, pose, focal), jacobian(p, pose, focal)) {
            h += j.transpose() * j;
            sum2 += r.norm_squared();
        }
    }
    let dof = 2 * points.len() as i64 - 6;
    // Per-coordinate variance from the residuals when they are enough to tell, else assumed.
    let sigma2 = if dof >= 6 {
        (sum2 / dof as f64).max(1e-6 * options.corner_sigma_px.powi(2))
    } else {
        options.corner_sigma_px.powi(2)
    };
    h.try_inverse().map_or(Matrix6::from_element(f64::INFINITY), |inv| inv * sigma2)
}
