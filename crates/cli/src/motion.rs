//! The lower incisor's motion read from tracked poses: where the incisal point is and how far
//! it has moved from its rest position, as opening, lateral and protrusive displacement. The
//! incisal point and the head's axes are those of the standard harness mounting
//! (`jawtrack_synth::scenes::Rig`); one place, for the viewer, `export` and `plot`.

use jawtrack_pose::Pose;
use jawtrack_synth::scenes::Rig;
use nalgebra::Point3;

/// Reads incisor motion from `maxilla_from_mandible` poses.
pub(crate) struct Incisor {
    rig: Rig,
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
    pub(crate) fn standard() -> Self {
        Incisor { rig: Rig::default() }
    }

    /// The incisal point in the head frame (X the patient's left, Y down, Z posterior).
    pub(crate) fn in_head(&self, maxilla_from_mandible: &Pose) -> Point3<f64> {
        self.rig.lower_incisor(maxilla_from_mandible)
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
}
