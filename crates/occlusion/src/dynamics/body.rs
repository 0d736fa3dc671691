//! [`RigidBody`]: the lower arch as a thin shell with its mass spread evenly over its area (its
//! centre of mass, inertia and radius), and how a small motion about the centre of mass moves
//! the lower scan's pose.

use super::error::DynamicsError;
use super::options::above;
use crate::mesh::Mesh;
use jawtrack_pose::Pose;
use nalgebra::{Matrix3, Point3, UnitQuaternion, Vector3};

/// The lower arch as a rigid body: a thin shell over its triangles.
///
/// A scan is an open surface, so it has no volume to fill; its mass is spread evenly over its
/// area instead (each triangle's exact second moment of area, summed and scaled to the mass).
/// For a mandible that puts the centre of mass among the teeth rather than at the condyles,
/// which is right for how the teeth, not the whole bone, meet: the spring's pull then acts
/// where the contacts are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBody {
    /// Mass (kg).
    pub mass_kg: f64,
    /// Centre of mass, in the lower scan's frame (mm).
    pub centre_of_mass: Point3<f64>,
    /// Inertia tensor about the centre of mass, in the lower scan's axes (kg·mm²).
    pub inertia_kg_mm2: Matrix3<f64>,
    /// The largest distance of a vertex from the centre of mass (mm).
    pub radius_mm: f64,
}

impl RigidBody {
    /// The shell body of `mesh` with `mass_kg` spread evenly over its area.
    pub fn shell(mesh: &Mesh, mass_kg: f64) -> Result<RigidBody, DynamicsError> {
        let (mut area, mut moment) = (0.0, Vector3::zeros());
        for t in 0..mesh.triangles.len() {
            let a = mesh.area_normal(t).norm() / 2.0;
            let [p, q, r] = mesh.corners(t);
            area += a;
            moment += (p.coords + q.coords + r.coords) * (a / 3.0);
        }
        if !above(area, 0.0, f64::MAX) || !above(mass_kg, 0.0, f64::MAX) {
            return Err(DynamicsError::DegenerateMesh);
        }
        let c = moment / area;
        // ∫ (p−c)(p−c)ᵀ dA over a triangle = A/12 (Σ vᵢvᵢᵀ + s sᵀ), vᵢ its corners about c, s their sum.
        let mut second = Matrix3::zeros();
        for t in 0..mesh.triangles.len() {
            let a = mesh.area_normal(t).norm() / 2.0;
            let v = mesh.corners(t).map(|p| p.coords - c);
            let s = v[0] + v[1] + v[2];
            second += (v[0] * v[0].transpose() + v[1] * v[1].transpose() + v[2] * v[2].transpose() + s * s.transpose())
                * (a / 12.0);
        }
        let second = second * (mass_kg / area);
        let inertia = Matrix3::identity() * second.trace() - second;
        let radius = mesh.vertices.iter().map(|v| (v.coords - c).norm()).fold(0.0, f64::max);
        Ok(RigidBody { mass_kg, centre_of_mass: Point3::from(c), inertia_kg_mm2: inertia, radius_mm: radius })
    }

    /// The inertia tensor in the upper scan's axes with the lower scan at `pose`, and its inverse.
    pub(super) fn inertia_world(&self, pose: &Pose) -> (Matrix3<f64>, Matrix3<f64>) {
        let r = pose.rotation_matrix();
        let i = r * self.inertia_kg_mm2 * r.transpose();
        // A surface with area spans two directions, so every principal moment of its shell is
        // positive and the inverse exists; the fallback (no rotation) is never taken.
        let inv = i.try_inverse().unwrap_or_else(Matrix3::zeros);
        (i, inv)
    }

    /// Where `pose` puts the centre of mass (upper scan frame).
    pub(super) fn centre(&self, pose: &Pose) -> Point3<f64> {
        pose.transform_point(&self.centre_of_mass)
    }

    /// `pose` moved by `dx` (mm) and turned by the rotation vector `dtheta` (rad) about the
    /// centre of mass.
    pub(super) fn displaced(&self, pose: &Pose, dx: &Vector3<f64>, dtheta: &Vector3<f64>) -> Pose {
        let q = UnitQuaternion::from_scaled_axis(*dtheta) * pose.rotation();
        let com = self.centre(pose) + dx;
        Pose::from_parts(q, com.coords - q * self.centre_of_mass.coords)
    }

    /// How far at most any point of the arch moves under (dx, dtheta) about its centre of mass.
    pub(super) fn displacement_bound(&self, dx: &Vector3<f64>, dtheta: &Vector3<f64>) -> f64 {
        dx.norm() + dtheta.norm() * self.radius_mm
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes;

    #[test]
    fn a_spherical_shell_has_its_centre_and_two_thirds_m_r_squared() {
        let (c, r, m) = (Point3::new(1.0, -2.0, 3.0), 3.0, 0.1);
        let body = RigidBody::shell(&scenes::sphere(c, r, 60), m).expect("area");
        assert!((body.centre_of_mass - c).norm() < 1e-9, "{}", body.centre_of_mass);
        let expected = 2.0 / 3.0 * m * r * r;
        for i in 0..3 {
            assert!((body.inertia_kg_mm2[(i, i)] / expected - 1.0).abs() < 3e-3, "{}", body.inertia_kg_mm2);
        }
        let i = body.inertia_kg_mm2;
        assert!([i[(0, 1)], i[(0, 2)], i[(1, 2)]].iter().all(|x| x.abs() < 1e-3 * expected), "{i}");
        assert!((body.radius_mm - r).abs() < 1e-9);
    }

    #[test]
    fn a_flat_patch_has_the_inertia_of_a_plate() {
        // A square plate of side a: I = m a²/12 about in-plane axes, m a²/6 about the normal.
        let (a, m) = (10.0, 0.1);
        let body = RigidBody::shell(&scenes::patch(a, 8, 0.0, false), m).expect("area");
        let i = body.inertia_kg_mm2;
        let plate = m * a * a / 12.0;
        assert!((i[(0, 0)] / plate - 1.0).abs() < 1e-9 && (i[(2, 2)] / (2.0 * plate) - 1.0).abs() < 1e-9, "{i}");
    }
}
