//! The lower incisor's motion read from tracked poses: where the incisal point is and how far
//! it has moved from its rest position, as opening, lateral and protrusive displacement. The
//! incisal point and the head's axes are those of the standard harness mounting
//! (`jawtrack_synth::scenes::Rig`); one place, for the viewer, `export`, `plot` and `metrics`.
//! `metrics` may name another incisal point (fixed to the mandible marker); the head's axes
//! stay those of the standard mounting.

use jawtrack_pose::Pose;
use jawtrack_synth::scenes::Rig;
use nalgebra::Point3;

/// Reads incisor motion from `maxilla_from_mandible` poses.
pub(crate) struct Incisor {
    rig: Rig,
    /// The incisal point in the mandible marker's frame (mm): it is fixed to the mandible, so
    /// this is all a tracked `maxilla_from_mandible` pose needs to carry it.
    on_mandible: Point3<f64>,
}

/// Displacement from rest (mm): opening (down), lateral (toward the patient's left),
/// protrusive (forward).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Displacement {
    pub opening: f64,
    pub lateral: f64,
    pub protrusive: f64,
}

impl Incisor {
    /// The standard harness mounting's lower incisal point.
    pub(crate) fn standard() -> Self {
        let rig = Rig::default();
        // As `Rig::lower_incisor` does: the closed jaw's incisal point carried into the marker.
        let on_mandible = rig.head_from_mandible_rest.inverse().transform_point(&Point3::from(rig.lower_incisal_point));
        Incisor { rig, on_mandible }
    }

    /// Another incisal point, given in the mandible marker's frame (mm); the head frame is
    /// still the standard mounting's (placed by the maxilla marker).
    pub(crate) fn at(point_in_mandible_marker: Point3<f64>) -> Self {
        Incisor { rig: Rig::default(), on_mandible: point_in_mandible_marker }
    }

    /// The incisal point in the mandible marker's frame (mm).
    pub(crate) fn point_in_mandible_marker(&self) -> Point3<f64> {
        self.on_mandible
    }

    /// The incisal point in the head frame (X the patient's left, Y down, Z posterior).
    pub(crate) fn in_head(&self, maxilla_from_mandible: &Pose) -> Point3<f64> {
        (self.rig.head_from_maxilla * *maxilla_from_mandible).transform_point(&self.on_mandible)
    }

    /// The incisal point in the maxilla marker's frame (the viewer's scene frame).
    pub(crate) fn in_maxilla(&self, maxilla_from_mandible: &Pose) -> Point3<f64> {
        self.rig.head_from_maxilla.inverse().transform_point(&self.in_head(maxilla_from_mandible))
    }

    /// How far the incisor is from where it is at `rest`.
    pub(crate) fn displacement(&self, maxilla_from_mandible: &Pose, rest: &Pose) -> Displacement {
        let d = self.in_head(maxilla_from_mandible) - self.in_head(rest);
        // `+ 0.0` turns a negative zero (no motion) into a plain one.
        Displacement { opening: d.y, lateral: d.x, protrusive: -d.z + 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_synth::scenes::{Glide, JawMotion};

    #[test]
    fn a_hinge_opening_reads_as_opening_and_a_protrusion_as_protrusion() {
        let (incisor, rig) = (Incisor::standard(), Rig::default());
        let rest = rig.head_from_maxilla.inverse() * rig.head_from_mandible_rest;
        let at = |motion: &JawMotion, t: f64| {
            let (maxilla, mandible) = rig.markers(motion, t);
            incisor.displacement(&(maxilla.inverse() * mandible), &rest)
        };
        let open = at(&JawMotion::Hinge { opening_mm: 30.0, start_s: 0.0, period_s: 2.0 }, 1.0);
        assert!((open.opening.hypot(open.protrusive) - 30.0).abs() < 1e-6, "{open:?}");
        assert!(open.opening > 25.0 && open.lateral.abs() < 1e-9, "{open:?}");
        let forward =
            at(&JawMotion::Glide { direction: Glide::Protrusive, amplitude_mm: 8.0, start_s: 0.0, period_s: 2.0 }, 1.0);
        assert!((forward.protrusive - 8.0).abs() < 1e-6 && forward.opening > 0.0, "{forward:?}");
    }

    #[test]
    fn the_standard_point_reads_as_the_rig_reads_it() {
        let rig = Rig::default();
        let (maxilla, mandible) = rig.markers(&JawMotion::Hinge { opening_mm: 30.0, start_s: 0.0, period_s: 2.0 }, 0.7);
        let m = maxilla.inverse() * mandible;
        let standard = Incisor::standard();
        assert_eq!(standard.in_head(&m), rig.lower_incisor(&m));
        let same = Incisor::at(standard.point_in_mandible_marker());
        assert_eq!(same.in_head(&m), standard.in_head(&m));
    }

    #[test]
    fn a_custom_point_on_the_hinge_axis_does_not_move_in_a_hinge_opening() {
        let rig = Rig::default();
        let rest = rig.head_from_maxilla.inverse() * rig.head_from_mandible_rest;
        let on_axis = rig.head_from_mandible_rest.inverse().transform_point(&Point3::from(rig.hinge_point));
        let (condyle, incisor) = (Incisor::at(on_axis), Incisor::standard());
        let (maxilla, mandible) = rig.markers(&JawMotion::Hinge { opening_mm: 30.0, start_s: 0.0, period_s: 2.0 }, 1.0);
        let m = maxilla.inverse() * mandible;
        let d = condyle.displacement(&m, &rest);
        assert!(d.opening.abs() < 1e-9 && d.lateral.abs() < 1e-9 && d.protrusive.abs() < 1e-9, "{d:?}");
        assert!(incisor.displacement(&m, &rest).opening > 25.0);
        assert!((condyle.in_head(&rest) - Point3::from(rig.hinge_point)).norm() < 1e-9);
    }
}
