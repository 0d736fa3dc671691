//! A tag's plane as the camera sees it: where a pixel's ray meets it, what the pixel sees
//! there under the blur (with its derivatives by the pose and the blur), and whether it is
//! near enough an edge of the pattern to tell.

use crate::model::Pattern;
use jawtrack_pose::Pose;
use nalgebra::{Matrix2, Matrix2x3, Matrix2x6, Matrix3, Matrix3x2, Matrix3x6, SVector, Vector2, Vector3};

/// The tag's plane at one instant, in the camera frame, with the map from a normalised
/// direction to tag coordinates.
pub(crate) struct Plane {
    pub(crate) centre: Vector3<f64>,
    pub(crate) x: Vector3<f64>,
    pub(crate) y: Vector3<f64>,
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
    Some(Plane { centre, x, y, to_tag })
}

/// The tag coordinates (tx, ty) that the normalised direction `n` looks at on the plane whose
/// map is `to_tag`; `None` along the plane.
pub(crate) fn to_tag(to_tag: &Matrix3<f64>, n: &Vector2<f64>) -> Option<(f64, f64)> {
    let m = to_tag * Vector3::new(n.x, n.y, 1.0);
    (m.z.abs() > 1e-12).then(|| (m.x / m.z, m.y / m.z))
}

/// Whether the point at tag coordinates (tx, ty) on `plane` is within `band` (normalised units)
/// of an edge of the pattern, each way along the tag's axes: whether the cells about it hold
/// both ink and paper. `false` where the plane is behind the camera or edge-on.
pub(crate) fn near_edge(plane: &Plane, pattern: &Pattern, tx: f64, ty: f64, band: f64, half: f64) -> bool {
    let Some((_, _, j)) = local(plane, tx, ty) else { return false };
    let (ru, rv) = (half * band * j.row(0).norm(), half * band * j.row(1).norm());
    pattern.mixed((tx + 1.0) * half, (ty + 1.0) * half, ru, rv)
}

/// The plane's point at tag coordinates (tx, ty) in the camera frame, d(normalised)/d(camera
/// point) there, and the map from a normalised direction's change to the tag coordinates'
/// change; `None` behind the camera or edge-on.
fn local(plane: &Plane, tx: f64, ty: f64) -> Option<(Vector3<f64>, Matrix2x3<f64>, Matrix2<f64>)> {
    let x = plane.centre + plane.x * tx + plane.y * ty;
    if x.z <= 0.0 {
        return None;
    }
    let iz = 1.0 / x.z;
    let dpi = Matrix2x3::new(iz, 0.0, -x.x * iz * iz, 0.0, iz, -x.y * iz * iz);
    let j = (dpi * Matrix3x2::from_columns(&[plane.x, plane.y])).try_inverse()?;
    Some((x, dpi, j))
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
    let (tx, ty) = to_tag(&plane.to_tag, n)?;
    let (x, dpi, j) = local(plane, tx, ty)?;
    // The blur carried onto the plane, per axis, in cells.
    let su = half * sigma * j.row(0).norm();
    let sv = half * sigma * j.row(1).norm();
    let (u, v) = ((tx + 1.0) * half, (ty + 1.0) * half);
    let m = pattern.paper(u, v, su, sv);
    let mut d = Looked::zeros();
    if jacobian && (m.du != 0.0 || m.dv != 0.0 || m.dsu != 0.0 || m.dsv != 0.0) {
        // The point on the plane a fixed pixel sees moves by −J·Dπ·dx when the plane's point x
        // moves by dx; a left perturbation moves x by −[x]×·ω + τ.
        let mut dx = Matrix3x6::zeros();
        dx.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-x.cross_matrix()));
        dx.fixed_view_mut::<3, 3>(0, 3).copy_from(&Matrix3::identity());
        let d_tag: Matrix2x6<f64> = -(j * dpi * dx) * half;
        // The blur carried onto the plane grows with the point's depth (nearly as it: the
        // plane's tilt changes little over a step).
        let d_depth = dx.row(2) / x.z;
        let d_pose = d_tag.transpose() * Vector2::new(m.du, m.dv) + (d_depth * (m.dsu * su + m.dsv * sv)).transpose();
        d.fixed_rows_mut::<6>(0).copy_from(&d_pose);
        // By σ (normalised units): the spreads grow in proportion.
        d[6] = (m.dsu * su + m.dsv * sv) / sigma;
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
