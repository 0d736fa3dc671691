//! Warnings that compare two sections' numbers: what neither section shows alone.

use crate::Inputs;
use jawtrack_kinematics::{HingeAxis, Side};
use jawtrack_plot::fixed;
use nalgebra::Point3;

/// Farther than this (mm) from the fitted axis, an assumed condyle's path is mostly the jaw's
/// turn about the axis: a few times a palpated condyle's error, well under the 20–25 mm the
/// standard and Bonwill condyles were seen off a real hinge.
const OFF_AXIS_MM: f64 = 5.0;

/// The condyles' distances (mm, left then right) from the fitted hinge axis.
fn condyle_distances(inputs: &Inputs, axis: &HingeAxis) -> [f64; 2] {
    let m = inputs.anatomy.mounting;
    let maxilla_from_head = m.head_from_maxilla.inverse();
    [Side::Left, Side::Right]
        .map(|side| axis.distance_to(&maxilla_from_head.transform_point(&Point3::from(m.condyle(side)))))
}

/// A warning when the condyles the condylar paths are drawn for were assumed (no points file
/// gave them) and one lies more than [`OFF_AXIS_MM`] from the fitted hinge axis: their paths
/// then show travel a condyle on the axis would not make.
pub(crate) fn condyles_off_axis(inputs: &Inputs, axis: &HingeAxis) -> Option<String> {
    if inputs.anatomy.condyles_given {
        return None;
    }
    let [left, right] = condyle_distances(inputs, axis);
    (left.max(right) > OFF_AXIS_MM).then(|| {
        format!(
            "the condyles assumed for the condylar paths are {} mm (left) and {} mm (right) from the fitted hinge \
             axis: their paths show the jaw's turn about the axis as travel; give the condyles in a points file \
             (jawtrack points --condyles) or read the hinge axis section",
            fixed(left, 1),
            fixed(right, 1)
        )
    })
}
