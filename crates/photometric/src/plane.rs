//! A tag's plane as the camera sees it: where a pixel's ray meets it, what the pixel sees
//! there under the blur (with its derivatives by the pose and the blur), and whether it is
//! near enough an edge of the pattern to tell.

use crate::model::Pattern;
use jawtrack_pose::Pose;
use nalgebra::{Matrix2, Matrix3, SVector, Vector2, Vector3};

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
pub(crate) fn look(
    plane: &Plane,
    pattern: &Pattern,
    n: &Vector2<f64>,
    sigma: f64,
    half: f64,
    jacobian: bool,
) -> Option<Seen> {
    let l = Local::at(plane, n)?;
    // The blur carried onto the plane, per axis, in cells.
    let su = half * sigma * l.j.row(0).norm();
    let sv = half * sigma * l.j.row(1).norm();
    let m = pattern.paper((l.tx + 1.0) * half, (l.ty + 1.0) * half, su, sv);
    let mut d = Looked::zeros();
    if jacobian && (m.du != 0.0 || m.dv != 0.0 || m.dsu != 0.0 || m.dsv != 0.0) {
        // The paper's slope by the direction looked along, in cells.
        let by_n = l.j.transpose() * Vector2::new(m.du, m.dv) * half;
        // Moving the plane's point x by dx moves the point a fixed pixel sees as turning the
        // ray by −Dπ·dx would (π the projection); the blur carried onto the plane also grows
        // with the point's depth (nearly as it: the plane's tilt changes little over a step).
        let blur = m.dsu * su + m.dsv * sv;
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

#[cfg(test)]
mod tests {
    use super::*;
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
            let seen = look(&p, &pattern, &n, sigma, half, true).expect("seen");
            for i in 0..6 {
                let mut d = Vector6::zeros();
                d[i] = h;
                let at = |s: f64| {
                    let q = Pose::from_isometry(perturb(pose.isometry(), &(d * s)));
                    look(&plane(&q, &centre, &x, &y).expect("plane"), &pattern, &n, sigma, half, false)
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
}
