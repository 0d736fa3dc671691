//! The harness mounting: where the two markers sit on the head, and the anatomy the
//! kinematics needs (the condyles, whose line is the hinge axis, and the lower incisal point), all in the head frame.
//! [`Mounting::default`] is the standard harness mounting; the renderer's rig embeds the same
//! one, so rendered sessions and their readouts agree by construction.

use jawtrack_pose::Pose;
use nalgebra::{Point3, UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// A side of the patient.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The patient's left (+X in the head frame).
    Left,
    /// The patient's right (−X).
    Right,
}

/// How the harnesses sit on the head (head frame: X the patient's left, Y down, Z posterior;
/// mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mounting {
    /// Pose of the maxilla marker.
    pub head_from_maxilla: Pose,
    /// Pose of the mandible marker with the jaw closed.
    pub head_from_mandible_rest: Pose,
    /// The condyles with the jaw closed, left then right: the ends of the hinge (condylar)
    /// axis.
    pub condyles: [Vector3<f64>; 2],
    /// The lower incisal point with the jaw closed.
    pub lower_incisal_point: Vector3<f64>,
}

impl Default for Mounting {
    /// The standard harness mounting.
    fn default() -> Self {
        // Body +Z anterior (−Z head), body Y = head Y: a half turn about Y.
        let facing = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI);
        Mounting {
            head_from_maxilla: Pose::from_parts(facing, Vector3::new(0.0, -22.0, -38.0)),
            head_from_mandible_rest: Pose::from_parts(facing, Vector3::new(0.0, 22.0, -38.0)),
            // 100 mm apart on a transverse line through (0, −20, 95).
            condyles: [Vector3::new(50.0, -20.0, 95.0), Vector3::new(-50.0, -20.0, 95.0)],
            lower_incisal_point: Vector3::new(0.0, 1.5, 1.0),
        }
    }
}

impl Mounting {
    /// The mandible marker in the maxilla marker's frame with the jaw closed.
    pub fn maxilla_from_mandible_rest(&self) -> Pose {
        self.head_from_maxilla.inverse() * self.head_from_mandible_rest
    }

    /// The condyle of `side` with the jaw closed (head frame).
    pub fn condyle(&self, side: Side) -> Vector3<f64> {
        match side {
            Side::Left => self.condyles[0],
            Side::Right => self.condyles[1],
        }
    }

    /// The midpoint of the condyles: the hinge axis's point on the midline.
    pub fn hinge_point(&self) -> Vector3<f64> {
        (self.condyles[0] + self.condyles[1]) / 2.0
    }

    /// The distance between the condyles (mm).
    pub fn intercondylar_mm(&self) -> f64 {
        (self.condyles[0] - self.condyles[1]).norm()
    }

    /// A head-frame point of the closed jaw, in the mandible marker's frame: where a point
    /// fixed to the mandible sits for the tracked poses to carry it.
    pub fn on_mandible(&self, head_point: &Vector3<f64>) -> Point3<f64> {
        self.head_from_mandible_rest.inverse().transform_point(&Point3::from(*head_point))
    }

    /// Where the lower incisal point is (head frame) when the mandible marker sits at
    /// `maxilla_from_mandible` in the maxilla marker's frame: how a tracked pose reads as the
    /// incisor's motion.
    pub fn lower_incisor(&self, maxilla_from_mandible: &Pose) -> Point3<f64> {
        (self.head_from_maxilla * *maxilla_from_mandible).transform_point(&self.on_mandible(&self.lower_incisal_point))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_rest_the_incisor_is_where_the_mounting_puts_it() {
        let m = Mounting::default();
        let p = m.lower_incisor(&m.maxilla_from_mandible_rest());
        assert!((p.coords - m.lower_incisal_point).norm() < 1e-12, "{p}");
    }

    #[test]
    fn the_condyles_straddle_the_hinge_point_along_the_axis() {
        let m = Mounting::default();
        let (l, r) = (m.condyle(Side::Left), m.condyle(Side::Right));
        assert!((l - r - Vector3::new(m.intercondylar_mm(), 0.0, 0.0)).norm() < 1e-12);
        assert!(((l + r) / 2.0 - m.hinge_point()).norm() < 1e-12);
    }
}
