//! A tag's plane as the camera sees it: where a pixel's ray meets it, what the pixel sees
//! there under the blur (with its derivatives by the pose and the blur), whether it is near
//! enough an edge of the pattern to tell, and which pixels the tag's square may cover.

use crate::model::Pattern;
use jawtrack_pose::{CameraIntrinsics, Pose};
use nalgebra::{Matrix2, Matrix3, Point2, SVector, Vector2, Vector3};

/// Points per side of a square's outline: the lens's distortion bends a side, and between
/// these points it departs from its chord by a few hundredths of a pixel (k1 = −0.25, the test).
const OUTLINE_POINTS_PER_SIDE: usize = 8;
/// The columns taken on a row reach this far (px) beyond the outline: for the chords, and so
/// that a pixel on the outline is tested rather than left out by rounding.
const OUTLINE_PAD_PX: f64 = 1.0;

/// The tag's plane at one instant, in the camera frame: the map from a normalised direction
/// (n, 1) to tag coordinates (tx, ty, 1), up to scale.
pub(crate) struct Plane {
    pub(crate) to_tag: Matrix3<f64>,
}

/// A pixel's derivatives: by the pose's six and by the blur σ.
pub(crate) type Looked = SVector<f64, 7>;

/// One pixel's model: the paper it sees, averaged over its row's instants, and the average's
/// derivative by the pose's left perturbation and by the blur's σ (px).
#[derive(Clone, Copy)]
pub(crate) struct Seen {
    pub(crate) paper: f64,
    pub(crate) d: Looked,
}

/// The tag's plane under `pose`; `None` when it is seen edge-on.
pub(crate) fn plane(pose: &Pose, centre: &Vector3<f64>, x: &Vector3<f64>, y: &Vector3<f64>) -> Option<Plane> {
    let r = pose.rotation_matrix();
    let (centre, x, y) = (pose.transform_point(&(*centre).into()).coords, r * x, r * y);
    // A normalised direction n is the image of tag coordinates (tx, ty) where
    // centre + tx·x + ty·y ∝ (n, 1): the columns (x, y, centre) map (tx, ty, 1) to it.
    let to_tag = Matrix3::from_columns(&[x, y, centre]).try_inverse()?;
    Some(Plane { to_tag })
}

/// The tag coordinates (tx, ty) that the normalised direction `n` looks at on the plane whose
/// map is `to_tag`; `None` along the plane.
pub(crate) fn to_tag(to_tag: &Matrix3<f64>, n: &Vector2<f64>) -> Option<(f64, f64)> {
    let m = to_tag * Vector3::new(n.x, n.y, 1.0);
    (m.z.abs() > 1e-12).then(|| (m.x / m.z, m.y / m.z))
}

/// Whether the pixel looking along `n` sees a point of `plane` within `band` (normalised units)
/// of an edge of the pattern, each way along the tag's axes: whether the cells about it hold
/// both ink and paper. `false` where the plane is behind the camera.
pub(crate) fn near_edge(plane: &Plane, pattern: &Pattern, n: &Vector2<f64>, band: f64, half: f64) -> bool {
    let Some(l) = Local::at(plane, n) else { return false };
    let (ru, rv) = (half * band * l.j.row(0).norm(), half * band * l.j.row(1).norm());
    pattern.mixed((l.tx + 1.0) * half, (l.ty + 1.0) * half, ru, rv)
}

/// The widest half-widths (cells, along u and v) that [`near_edge`] gives a pixel looking at
/// any point of the square centre ± x ± y (body frame) on `plane` (made from that square's
/// plane at `pose`): a bound for ruling out the pixels well inside a cell before their own is
/// worked out. d(tag)/d(direction) is (A − t·a₃ᵀ) times the depth ([`Local::at`]); each row's
/// norm is convex in the tag coordinates t and the depth affine in them, so neither exceeds
/// its largest value at the square's corners. `None` where a corner is not in front.
pub(crate) fn widest_band(
    plane: &Plane,
    pose: &Pose,
    (centre, x, y): (&Vector3<f64>, &Vector3<f64>, &Vector3<f64>),
    band: f64,
    half: f64,
) -> Option<(f64, f64)> {
    let (mut by_u, mut by_v, mut depth): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let p = pose.transform_point(&(centre + x * sx + y * sy).into());
        if p.z <= 0.0 {
            return None;
        }
        let l = Local::at(plane, &Vector2::new(p.x / p.z, p.y / p.z))?;
        by_u = by_u.max(l.j.row(0).norm() / l.x.z);
        by_v = by_v.max(l.j.row(1).norm() / l.x.z);
        depth = depth.max(l.x.z);
    }
    // A hair wider, so that rounding never makes a bound narrower than a pixel's own.
    let widen = half * band * depth * (1.0 + 1e-9);
    Some((by_u * widen, by_v * widen))
}

/// Where a pixel's ray meets the plane, and how that point moves as the ray turns.
struct Local {
    /// Tag coordinates.
    tx: f64,
    ty: f64,
    /// The point in the camera frame.
    x: Vector3<f64>,
    /// d(tx, ty)/d(normalised direction).
    j: Matrix2<f64>,
}

impl Local {
    /// Where the ray along `n` meets `plane`; `None` behind the camera or along the plane.
    fn at(plane: &Plane, n: &Vector2<f64>) -> Option<Local> {
        // m = to_tag·(n, 1) is (tx, ty, 1) scaled by 1/depth: the columns of to_tag's inverse
        // take (tx, ty, 1) to the point, and the point is (n, 1) times its depth.
        let a = &plane.to_tag;
        let m = a * Vector3::new(n.x, n.y, 1.0);
        if m.z <= 1e-12 || m.z.is_nan() {
            return None;
        }
        let depth = 1.0 / m.z;
        let (tx, ty) = (m.x * depth, m.y * depth);
        // The homography's own derivative.
        let j = Matrix2::new(
            (a[(0, 0)] - tx * a[(2, 0)]) * depth,
            (a[(0, 1)] - tx * a[(2, 1)]) * depth,
            (a[(1, 0)] - ty * a[(2, 0)]) * depth,
            (a[(1, 1)] - ty * a[(2, 1)]) * depth,
        );
        Some(Local { tx, ty, x: Vector3::new(n.x, n.y, 1.0) * depth, j })
    }
}

/// What the pixel looking along `n` sees of a tag on `plane`: the paper, and (with
/// `jacobian`) its derivative by a left perturbation of the pose (rotation, translation).
///
/// `sweep` is how far (tag units, each axis) the point the pixel sees moves over the part of
/// the exposure that `plane` stands for (zero for an instant). The sweep, a box, is taken as a
/// Gaussian of the same variance along each axis, beside the blur. At a straight edge of the
/// pattern only the sweep across it counts, and a sweep of twice the blur is read within
/// 0.002 of the contrast (the test). At the cells' corners, where the two axes' sweeps are
/// correlated, it is about as far off as leaving the sweep out; there are few such pixels. The
/// sweep's own change with the pose is left out of the derivative: it follows the velocity.
pub(crate) fn look(
    plane: &Plane,
    pattern: &Pattern,
    n: &Vector2<f64>,
    sigma: f64,
    half: f64,
    sweep: &Vector2<f64>,
    jacobian: bool,
) -> Option<Seen> {
    let l = Local::at(plane, n)?;
    // The blur carried onto the plane, per axis, in cells, widened by the sweep; with each
    // spread's derivative by the blur's, times the blur's (σ ∂s/∂σ).
    let widen = |blur: f64, sweep: f64| {
        if sweep == 0.0 {
            (blur, blur)
        } else {
            let s = (blur * blur + sweep * sweep / 12.0).sqrt();
            (s, blur * blur / s)
        }
    };
    let (su, su_by_blur) = widen(half * sigma * l.j.row(0).norm(), half * sweep.x);
    let (sv, sv_by_blur) = widen(half * sigma * l.j.row(1).norm(), half * sweep.y);
    let m = pattern.paper((l.tx + 1.0) * half, (l.ty + 1.0) * half, su, sv);
    let mut d = Looked::zeros();
    if jacobian && (m.du != 0.0 || m.dv != 0.0 || m.dsu != 0.0 || m.dsv != 0.0) {
        // The paper's slope by the direction looked along, in cells.
        let by_n = l.j.transpose() * Vector2::new(m.du, m.dv) * half;
        // Moving the plane's point x by dx moves the point a fixed pixel sees as turning the
        // ray by −Dπ·dx would (π the projection); the blur carried onto the plane also grows
        // with the point's depth (nearly as it: the plane's tilt changes little over a step).
        let blur = m.dsu * su_by_blur + m.dsv * sv_by_blur;
        let iz = 1.0 / l.x.z;
        let by_x = Vector3::new(-by_n.x * iz, -by_n.y * iz, (by_n.x * n.x + by_n.y * n.y + blur) * iz);
        // A left perturbation (ω, τ) moves x by ω × x + τ.
        d.fixed_rows_mut::<3>(0).copy_from(&l.x.cross(&by_x));
        d.fixed_rows_mut::<3>(3).copy_from(&by_x);
        // By σ (normalised units): the spreads grow in proportion.
        d[6] = blur / sigma;
    }
    Some(Seen { paper: m.value, d })
}

/// A square of the tag's plane as the image shows it: its outline in pixels, for the pixels
/// it may cover.
pub(crate) struct Outline {
    points: Vec<Point2<f64>>,
}

impl Outline {
    /// The square centre ± x ± y (body frame) at `pose`; `None` where a point of it is not in
    /// front of the camera.
    pub(crate) fn new(
        camera: &CameraIntrinsics,
        pose: &Pose,
        centre: &Vector3<f64>,
        x: &Vector3<f64>,
        y: &Vector3<f64>,
    ) -> Option<Outline> {
        let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        let mut points = Vec::with_capacity(4 * OUTLINE_POINTS_PER_SIDE);
        for (k, &(ax, ay)) in corners.iter().enumerate() {
            let (bx, by) = corners[(k + 1) % 4];
            for i in 0..OUTLINE_POINTS_PER_SIDE {
                let f = i as f64 / OUTLINE_POINTS_PER_SIDE as f64;
                let (sx, sy) = (ax + (bx - ax) * f, ay + (by - ay) * f);
                points.push(camera.project(&pose.transform_point(&(centre + x * sx + y * sy).into()))?);
            }
        }
        Some(Outline { points })
    }

    /// The smallest box holding the outline: its least and greatest pixel coordinates.
    pub(crate) fn bounds(&self) -> (Vector2<f64>, Vector2<f64>) {
        let (mut lo, mut hi) = (Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY));
        for p in &self.points {
            lo = lo.inf(&p.coords);
            hi = hi.sup(&p.coords);
        }
        (lo, hi)
    }

    /// The columns of row `y` that may lie inside: from the leftmost to the rightmost crossing
    /// of the outline, widened by [`OUTLINE_PAD_PX`]. Empty (from > to) where the row misses it.
    pub(crate) fn columns(&self, y: f64) -> (f64, f64) {
        let (mut from, mut to) = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, a) in self.points.iter().enumerate() {
            let b = &self.points[(k + 1) % self.points.len()];
            if (a.y - y) * (b.y - y) > 0.0 {
                continue; // both ends on one side of the row
            }
            let x = if a.y == b.y { [a.x, b.x] } else { [a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y); 2] };
            from = from.min(x[0].min(x[1]));
            to = to.max(x[0].max(x[1]));
        }
        (from - OUTLINE_PAD_PX, to + OUTLINE_PAD_PX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plane::to_tag as to_tag_of;
    use jawtrack_pose::pnp::perturb;
    use jawtrack_tag_family::TagFamily;
    use nalgebra::{UnitQuaternion, Vector6};

    #[test]
    fn the_pose_derivative_is_the_models_slope() {
        let bitmap = TagFamily::TAG36H11.bitmap(3).expect("tag 3");
        let pattern = Pattern::new(&bitmap).expect("8 cells");
        let (centre, x, y) = (Vector3::new(1.0, 2.0, 0.5), Vector3::new(5.0, 0.0, 0.0), Vector3::new(0.0, -5.0, 0.3));
        let pose = Pose::from_parts(
            UnitQuaternion::from_scaled_axis(Vector3::new(0.3, 2.9, 0.1)),
            Vector3::new(4.0, -3.0, 150.0),
        );
        let p = plane(&pose, &centre, &x, &y).expect("plane");
        let (sigma, half, h) = (1.2 / 1500.0, 4.0, 1e-7);
        let mut checked = 0;
        for k in 0..40 {
            let n = Vector2::new(0.02 + 0.0011 * f64::from(k % 7), -0.015 + 0.0013 * f64::from(k / 7));
            let seen = look(&p, &pattern, &n, sigma, half, &Vector2::zeros(), true).expect("seen");
            for i in 0..6 {
                let mut d = Vector6::zeros();
                d[i] = h;
                let at = |s: f64| {
                    let q = Pose::from_isometry(perturb(pose.isometry(), &(d * s)));
                    look(
                        &plane(&q, &centre, &x, &y).expect("plane"),
                        &pattern,
                        &n,
                        sigma,
                        half,
                        &Vector2::zeros(),
                        false,
                    )
                    .expect("seen")
                    .paper
                };
                let numeric = (at(1.0) - at(-1.0)) / (2.0 * h);
                // The blur's change with the plane's tilt is left out of the derivative.
                let (analytic, numeric) = (seen.d[i], numeric);
                assert!(
                    (numeric - analytic).abs() <= 1e-4 + 0.02 * numeric.abs(),
                    "pixel {k}, {i}: {numeric} vs {analytic}"
                );
            }
            checked += 1;
        }
        assert_eq!(checked, 40);
    }

    /// A tag seen at 150 mm, tilted: its pattern, its plane, the normalised directions of a
    /// 61 × 61 grid over it and a little beyond, a blur σ (normalised) and the half-width in
    /// cells.
    fn tilted_tag() -> (Pattern, Plane, Vec<Vector2<f64>>, f64, f64) {
        let pattern = Pattern::new(&TagFamily::TAG36H11.bitmap(3).expect("tag 3")).expect("8 cells");
        let (centre, x, y) = (Vector3::new(1.0, 2.0, 0.5), Vector3::new(5.0, 0.0, 0.0), Vector3::new(0.0, -5.0, 0.3));
        let pose = Pose::from_parts(
            UnitQuaternion::from_scaled_axis(Vector3::new(0.3, 2.9, 0.1)),
            Vector3::new(4.0, -3.0, 150.0),
        );
        let p = plane(&pose, &centre, &x, &y).expect("plane");
        let mut pixels = Vec::new();
        for i in 0..=60 {
            for k in 0..=60 {
                let (tx, ty) = (f64::from(i) / 27.0 - 1.1, f64::from(k) / 27.0 - 1.1);
                let q = pose.transform_point(&(centre + x * tx + y * ty).into());
                pixels.push(Vector2::new(q.x / q.z, q.y / q.z));
            }
        }
        (pattern, p, pixels, 1.2 / 1500.0, 4.0)
    }

    #[test]
    fn a_sweep_is_read_as_the_average_of_the_instants_it_spans() {
        let (pattern, p, pixels, _, half) = tilted_tag();
        // A sharp lens (0.4 px at 1500 px): a cell's corners are then few of its pixels.
        let sigma = 0.4 / 1500.0;
        let (mut checked, mut swept_matters, mut off) = (0, 0, 0);
        let (mut worst_edge, mut worst_unswept) = (0.0f64, 0.0f64);
        for n in &pixels {
            let l = Local::at(&p, n).expect("in front");
            let (su, sv) = (half * sigma * l.j.row(0).norm(), half * sigma * l.j.row(1).norm());
            let (u, v) = ((l.tx + 1.0) * half, (l.ty + 1.0) * half);
            // Twice the blur along u and 1.5 times it along v (cells): a diagonal sweep.
            let (du, dv) = (2.0 * su, -1.5 * sv);
            let steps = 400;
            let boxed = (0..steps)
                .map(|i| {
                    let t = (f64::from(i) + 0.5) / f64::from(steps) - 0.5;
                    pattern.paper(u + t * du, v + t * dv, su, sv).value
                })
                .sum::<f64>()
                / f64::from(steps);
            let swept = look(&p, &pattern, n, sigma, half, &Vector2::new(du / half, dv / half), false).expect("seen");
            let unswept = look(&p, &pattern, n, sigma, half, &Vector2::zeros(), false).expect("seen");
            let (error, unswept) = ((swept.paper - boxed).abs(), (unswept.paper - boxed).abs());
            // Near a cell boundary along both axes: a corner, where the axes' sweeps correlate.
            let near = |x: f64, s: f64, d: f64| (x - x.round()).abs() < 5.0 * s + d.abs() / 2.0;
            if !(near(u, su, du) && near(v, sv, dv)) {
                worst_edge = worst_edge.max(error);
                worst_unswept = worst_unswept.max(unswept);
            }
            if unswept > 0.01 {
                swept_matters += 1;
                off += usize::from(error > 0.01);
            }
            checked += 1;
        }
        assert_eq!(checked, 61 * 61);
        assert!(worst_edge < 0.003, "{worst_edge} of the contrast off the sweep's average at a straight edge");
        assert!(worst_unswept > 10.0 * worst_edge, "the sweep left out is only {worst_unswept} off: no test");
        // At the corners the model is only as good as leaving the sweep out; they are few.
        assert!(swept_matters > 300, "the sweep matters at only {swept_matters} pixels");
        assert!(off * 20 < swept_matters, "{off} of {swept_matters} pixels off by over 1 %");
    }

    #[test]
    fn with_a_sweep_the_derivatives_are_still_the_models_slopes() {
        let (pattern, p, pixels, sigma, half) = tilted_tag();
        let sweep = Vector2::new(0.02, -0.015);
        let h = 1e-9;
        let mut checked = 0;
        for n in pixels.iter().step_by(7) {
            let seen = look(&p, &pattern, n, sigma, half, &sweep, true).expect("seen");
            let at = |s: f64| look(&p, &pattern, n, s, half, &sweep, false).expect("seen").paper;
            let numeric = (at(sigma + h) - at(sigma - h)) / (2.0 * h) * sigma;
            assert!(
                (numeric - seen.d[6] * sigma).abs() <= 1e-5 + 1e-3 * numeric.abs(),
                "σ ∂/∂σ at {n}: {numeric} vs {}",
                seen.d[6] * sigma
            );
            checked += 1;
        }
        assert!(checked > 500, "only {checked}");
    }

    #[test]
    fn every_pixel_a_tilted_square_covers_is_within_its_outlines_columns_under_distortion() {
        // A strongly distorting lens, and a square tilted 50° about a diagonal-ish axis, off
        // the image's centre where the distortion bends its sides most.
        let camera =
            CameraIntrinsics { k1: -0.25, k2: 0.08, ..CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5) };
        let pose = Pose::from_parts(
            UnitQuaternion::from_scaled_axis(Vector3::new(0.6, 0.55, 0.3)),
            Vector3::new(45.0, 20.0, 110.0),
        );
        let (centre, x, y) = (Vector3::zeros(), Vector3::new(6.0, 0.0, 0.0), Vector3::new(0.0, -6.0, 0.0));
        let outline = Outline::new(&camera, &pose, &centre, &x, &y).expect("in front");
        let to_tag = plane(&pose, &centre, &x, &y).expect("plane").to_tag;
        let (lo, hi) = outline.bounds();
        let (mut inside, mut boxed, mut taken) = (0, 0, 0);
        for row in (lo.y.floor() as i64 - 3)..=(hi.y.ceil() as i64 + 3) {
            let (from, to) = outline.columns(row as f64);
            for col in (lo.x.floor() as i64 - 3)..=(hi.x.ceil() as i64 + 3) {
                let pixel = Point2::new(col as f64, row as f64);
                let n = camera.undistort(camera.pixel_to_distorted(&pixel)).expect("undistorted");
                let covered = to_tag_of(&to_tag, &n).is_some_and(|(tx, ty)| tx.abs() <= 1.0 && ty.abs() <= 1.0);
                let listed = (from..=to).contains(&(col as f64));
                assert!(!covered || listed, "pixel ({col}, {row}) is covered but not listed ({from}..{to})");
                inside += usize::from(covered);
                boxed += usize::from((lo.x..=hi.x).contains(&pixel.x) && (lo.y..=hi.y).contains(&pixel.y));
                taken += usize::from(listed && (lo.x..=hi.x).contains(&pixel.x) && (lo.y..=hi.y).contains(&pixel.y));
            }
        }
        assert!(inside > 2000, "only {inside} pixels covered");
        // The columns hold little more than the square (the pad), where its box holds far more.
        assert!((taken as f64) < 1.15 * inside as f64, "{taken} listed for {inside} covered");
        assert!((boxed as f64) > 1.4 * inside as f64, "the box holds {boxed} pixels for {inside}: not tilted enough");
    }

    #[test]
    fn no_pixel_of_a_tilted_square_gets_a_wider_band_than_the_widest() {
        let pose = Pose::from_parts(
            UnitQuaternion::from_scaled_axis(Vector3::new(0.7, -0.5, 0.2)),
            Vector3::new(-20.0, 10.0, 90.0),
        );
        let (centre, x, y) = (Vector3::new(1.0, 2.0, 0.5), Vector3::new(6.0, 0.0, 0.0), Vector3::new(0.0, -6.0, 0.4));
        let p = plane(&pose, &centre, &x, &y).expect("plane");
        let (band, half) = (1.2 / 1500.0, 4.0);
        let (ru, rv) = widest_band(&p, &pose, (&centre, &x, &y), band, half).expect("in front");
        let (mut checked, mut widest_u, mut widest_v) = (0, 0.0f64, 0.0f64);
        for i in 0..=40 {
            for k in 0..=40 {
                let (tx, ty) = (f64::from(i) / 20.0 - 1.0, f64::from(k) / 20.0 - 1.0);
                let q = pose.transform_point(&(centre + x * tx + y * ty).into());
                let l = Local::at(&p, &Vector2::new(q.x / q.z, q.y / q.z)).expect("seen");
                let (u, v) = (half * band * l.j.row(0).norm(), half * band * l.j.row(1).norm());
                assert!(u <= ru && v <= rv, "({tx}, {ty}): {u}, {v} beyond {ru}, {rv}");
                (widest_u, widest_v) = (widest_u.max(u), widest_v.max(v));
                checked += 1;
            }
        }
        assert_eq!(checked, 41 * 41);
        // A bound, and not a loose one: the widest pixel comes within a fifth of it.
        assert!(widest_u > 0.8 * ru && widest_v > 0.8 * rv, "{widest_u} of {ru}, {widest_v} of {rv}");
    }
}
