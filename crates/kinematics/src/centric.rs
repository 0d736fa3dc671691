//! The discrepancy between centric occlusion and maximal intercuspation (CO–MI): how far the
//! condyles and the incisor slide from the first tooth contact with the condyles in centric
//! relation (the jaw guided back and closed on its hinge) into the full bite.

use crate::mounting::{Mounting, Side};
use crate::point::Displacement;
use jawtrack_pose::Pose;
use nalgebra::Vector3;

/// The slide from centric occlusion into maximal intercuspation, per point of the mandible.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoMi {
    /// The lower incisal point's slide (mm): `protrusive` forward, `opening` down, `lateral`
    /// toward the patient's left.
    pub incisor: Displacement,
    /// The condyles' slides, left then right.
    pub condyles: [Displacement; 2],
}

/// The slide from `co` to `mi`, both `maxilla_from_mandible` poses, of the mounting's incisal
/// point and condyles, in its head frame.
pub fn co_mi(mounting: &Mounting, co: &Pose, mi: &Pose) -> CoMi {
    let slide = |head_point: Vector3<f64>| {
        let on = mounting.on_mandible(&head_point);
        let at = |p: &Pose| (mounting.head_from_maxilla * *p).transform_point(&on);
        let d = at(mi) - at(co);
        Displacement { opening: d.y, lateral: d.x, protrusive: -d.z + 0.0 }
    };
    CoMi {
        incisor: slide(mounting.lower_incisal_point),
        condyles: [slide(mounting.condyle(Side::Left)), slide(mounting.condyle(Side::Right))],
    }
}

impl Displacement {
    /// Its length (mm).
    pub fn norm(&self) -> f64 {
        (self.opening * self.opening + self.lateral * self.lateral + self.protrusive * self.protrusive).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// The mandible moved by `jaw` in the head frame, as a tracked pose.
    fn tracked(m: &Mounting, jaw: Pose) -> Pose {
        m.head_from_maxilla.inverse() * jaw * m.head_from_mandible_rest
    }

    #[test]
    fn a_jaw_held_back_and_up_slides_forward_and_down_into_the_bite() {
        let m = Mounting::default();
        let mi = m.maxilla_from_mandible_rest();
        // Centric relation: 0.8 mm back (+Z) and 0.3 mm up (−Y) of the bite.
        let co = tracked(&m, Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, -0.3, 0.8)));
        let s = co_mi(&m, &co, &mi);
        for d in [s.incisor, s.condyles[0], s.condyles[1]] {
            assert!((d.protrusive - 0.8).abs() < 1e-12 && (d.opening - 0.3).abs() < 1e-12 && d.lateral.abs() < 1e-12);
            assert!((d.norm() - 0.8f64.hypot(0.3)).abs() < 1e-12);
        }
    }

    #[test]
    fn a_turn_about_the_hinge_moves_the_incisor_alone() {
        let m = Mounting::default();
        let mi = m.maxilla_from_mandible_rest();
        // First contact 1° open on the hinge axis: the condyles stay, the incisor closes by its
        // lever times the angle.
        let a = 1f64.to_radians();
        let r = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a);
        let h = m.hinge_point();
        let co = tracked(&m, Pose::from_parts(r, h - r * h));
        let s = co_mi(&m, &co, &mi);
        assert!(s.condyles.iter().all(|d| d.norm() < 1e-12), "{s:?}");
        let chord = 2.0 * (m.lower_incisal_point - h).norm() * (a / 2.0).sin();
        assert!((s.incisor.norm() - chord).abs() < 1e-12 && s.incisor.opening < 0.0, "{s:?}");
    }
}
