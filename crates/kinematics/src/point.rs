//! A point fixed to the mandible — the lower incisal point by default, or any other (a
//! condyle, a molar cusp) — carried by tracked `maxilla_from_mandible` poses: where it is in
//! the head frame and how far it has moved from where it is at rest, as opening, lateral and
//! protrusive displacement. The head frame is placed by the maxilla marker through the
//! [`Mounting`].

use crate::mounting::Mounting;
use jawtrack_pose::Pose;
use nalgebra::Point3;

/// Reads a mandible point's motion from `maxilla_from_mandible` poses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incisor {
    mounting: Mounting,
    /// The point in the mandible marker's frame (mm): it is fixed to the mandible, so this is
    /// all a tracked `maxilla_from_mandible` pose needs to carry it.
    on_mandible: Point3<f64>,
}

/// Displacement from rest (mm): opening (down), lateral (toward the patient's left),
/// protrusive (forward).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Displacement {
    /// Down.
    pub opening: f64,
    /// Toward the patient's left.
    pub lateral: f64,
    /// Forward.
    pub protrusive: f64,
}

impl Incisor {
    /// The standard harness mounting's lower incisal point.
    pub fn standard() -> Self {
        Incisor::of(Mounting::default())
    }

    /// The lower incisal point of `mounting`.
    pub fn of(mounting: Mounting) -> Self {
        Incisor { mounting, on_mandible: mounting.on_mandible(&mounting.lower_incisal_point) }
    }

    /// The point of the mandible that sits at `head_point` (head frame) with the jaw closed,
    /// carried as `mounting` carries it: a condyle, say.
    pub fn fixed_at(mounting: Mounting, head_point: &nalgebra::Vector3<f64>) -> Self {
        Incisor { mounting, on_mandible: mounting.on_mandible(head_point) }
    }

    /// Another point, given in the mandible marker's frame (mm); the head frame is still the
    /// standard mounting's (placed by the maxilla marker).
    pub fn at(point_in_mandible_marker: Point3<f64>) -> Self {
        Incisor { mounting: Mounting::default(), on_mandible: point_in_mandible_marker }
    }

    /// A point given in the mandible marker's frame (mm), its displacement read in the head
    /// frame of `mounting` (a patient's points file's, say).
    pub fn on(mounting: Mounting, point_in_mandible_marker: Point3<f64>) -> Self {
        Incisor { mounting, on_mandible: point_in_mandible_marker }
    }

    /// The point in the mandible marker's frame (mm).
    pub fn point_in_mandible_marker(&self) -> Point3<f64> {
        self.on_mandible
    }

    /// The point in the head frame (X the patient's left, Y down, Z posterior).
    pub fn in_head(&self, maxilla_from_mandible: &Pose) -> Point3<f64> {
        (self.mounting.head_from_maxilla * *maxilla_from_mandible).transform_point(&self.on_mandible)
    }

    /// The point in the maxilla marker's frame (the viewer's scene frame).
    pub fn in_maxilla(&self, maxilla_from_mandible: &Pose) -> Point3<f64> {
        self.mounting.head_from_maxilla.inverse().transform_point(&self.in_head(maxilla_from_mandible))
    }

    /// How far the point is from where it is at `rest`.
    pub fn displacement(&self, maxilla_from_mandible: &Pose, rest: &Pose) -> Displacement {
        let d = self.in_head(maxilla_from_mandible) - self.in_head(rest);
        // `+ 0.0` turns a negative zero (no motion) into a plain one.
        Displacement { opening: d.y, lateral: d.x, protrusive: -d.z + 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Side;
    use nalgebra::{UnitQuaternion, Vector3};

    /// The tracked pose after the mandible turns by `angle` about the hinge axis (head X).
    fn hinge(m: &Mounting, angle: f64) -> Pose {
        let r = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), angle);
        let jaw = Pose::from_parts(r, m.hinge_point() - r * m.hinge_point());
        m.head_from_maxilla.inverse() * jaw * m.head_from_mandible_rest
    }

    #[test]
    fn a_hinge_opening_reads_as_opening_and_a_shift_forward_as_protrusion() {
        let m = Mounting::default();
        let (incisor, rest) = (Incisor::standard(), m.maxilla_from_mandible_rest());
        let lever = (m.lower_incisal_point - m.hinge_point()).norm();
        // A positive turn about +X swings the chin down (+Y) and back: a 30 mm chord.
        let open = incisor.displacement(&hinge(&m, 2.0 * (15.0 / lever).asin()), &rest);
        assert!((open.opening.hypot(open.protrusive) - 30.0).abs() < 1e-9, "{open:?}");
        assert!(open.opening > 25.0 && open.lateral.abs() < 1e-9, "{open:?}");
        let forward = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.0, -8.0));
        let moved = m.head_from_maxilla.inverse() * forward * m.head_from_mandible_rest;
        let d = incisor.displacement(&moved, &rest);
        assert!((d.protrusive - 8.0).abs() < 1e-9 && d.opening.abs() < 1e-9 && d.lateral.abs() < 1e-9, "{d:?}");
    }

    #[test]
    fn the_standard_point_reads_as_the_mounting_reads_it() {
        let m = Mounting::default();
        let pose = hinge(&m, 0.3);
        let standard = Incisor::standard();
        assert_eq!(standard.in_head(&pose), m.lower_incisor(&pose));
        let same = Incisor::at(standard.point_in_mandible_marker());
        assert_eq!(same.in_head(&pose), standard.in_head(&pose));
        let in_maxilla = m.head_from_maxilla.inverse().transform_point(&standard.in_head(&pose));
        assert!((standard.in_maxilla(&pose) - in_maxilla).norm() < 1e-12);
    }

    #[test]
    fn a_condyle_does_not_move_in_a_hinge_opening() {
        let m = Mounting::default();
        let rest = m.maxilla_from_mandible_rest();
        let condyle = Incisor::at(m.on_mandible(&m.condyle(Side::Left)));
        let d = condyle.displacement(&hinge(&m, 0.4), &rest);
        assert!(d.opening.abs() < 1e-9 && d.lateral.abs() < 1e-9 && d.protrusive.abs() < 1e-9, "{d:?}");
        assert!(Incisor::standard().displacement(&hinge(&m, 0.4), &rest).opening > 25.0);
        assert!((condyle.in_head(&rest).coords - m.condyle(Side::Left)).norm() < 1e-9);
    }
}
