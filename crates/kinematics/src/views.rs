//! How an incisor path is drawn in each anatomical plane: which way is up on the page and on
//! which side the patient's left falls, said in every title. One home for it, so that the
//! plots of `plot`, `metrics` and the report agree, and none is mirrored.
//!
//! - Sagittal, seen from the patient's right: anterior to the right, up up.
//! - Frontal, seen from the front (facing the patient): the patient's left on the right, up up.
//! - Transverse, seen from above: anterior up, the patient's left on the left.

use crate::point::Displacement;

/// A plane and the side it is seen from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlaneView {
    /// Sagittal plane seen from the patient's right.
    Sagittal,
    /// Frontal plane seen from the front.
    Frontal,
    /// Transverse (horizontal) plane seen from above.
    Transverse,
}

impl PlaneView {
    /// The three views.
    pub const ALL: [PlaneView; 3] = [PlaneView::Sagittal, PlaneView::Frontal, PlaneView::Transverse];

    /// The plane and how it is seen, for a title: "sagittal plane (seen from …)".
    pub fn title(self) -> &'static str {
        match self {
            PlaneView::Sagittal => "sagittal plane (seen from the patient's right: facing right)",
            PlaneView::Frontal => "frontal plane (seen from the front: the patient's left on the right)",
            PlaneView::Transverse => "transverse plane (seen from above: the patient's left on the left)",
        }
    }

    /// The horizontal and vertical axis labels (mm).
    pub fn axes(self) -> (&'static str, &'static str) {
        match self {
            PlaneView::Sagittal => ("anterior (mm)", "up (mm)"),
            PlaneView::Frontal => ("toward the patient's left (mm)", "up (mm)"),
            PlaneView::Transverse => ("toward the patient's right (mm)", "anterior (mm)"),
        }
    }

    /// Where a displacement from rest lands on the page: (right, up) in mm.
    pub fn project(self, d: &Displacement) -> (f64, f64) {
        match self {
            PlaneView::Sagittal => (d.protrusive, -d.opening),
            PlaneView::Frontal => (d.lateral, -d.opening),
            PlaneView::Transverse => (-d.lateral, d.protrusive),
        }
    }

    /// A short name for file names: "sagittal", "frontal", "transverse".
    pub fn name(self) -> &'static str {
        match self {
            PlaneView::Sagittal => "sagittal",
            PlaneView::Frontal => "frontal",
            PlaneView::Transverse => "transverse",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(opening: f64, lateral: f64, protrusive: f64) -> Displacement {
        Displacement { opening, lateral, protrusive }
    }

    #[test]
    fn each_view_puts_the_patient_s_left_where_its_title_says() {
        let left = d(0.0, 5.0, 0.0);
        // Facing the patient, their left is on the viewer's right.
        assert!(PlaneView::Frontal.project(&left).0 > 0.0 && PlaneView::Frontal.title().contains("left on the right"));
        // From above, anterior up, their left is on the left: the view the transverse plot was
        // once drawn mirrored in.
        assert!(
            PlaneView::Transverse.project(&left).0 < 0.0 && PlaneView::Transverse.title().contains("left on the left")
        );
        // Sagittal: no left or right on the page, anterior to the right.
        assert_eq!(PlaneView::Sagittal.project(&left), (0.0, 0.0));
        assert!(PlaneView::Sagittal.project(&d(0.0, 0.0, 3.0)).0 > 0.0);
    }

    #[test]
    fn opening_is_drawn_downward_and_protrusion_forward() {
        let open = d(20.0, 0.0, 0.0);
        assert!(PlaneView::Sagittal.project(&open).1 < 0.0 && PlaneView::Frontal.project(&open).1 < 0.0);
        assert!(PlaneView::Transverse.project(&d(0.0, 0.0, 4.0)).1 > 0.0);
        for v in PlaneView::ALL {
            assert!(v.title().starts_with(v.name()), "{}", v.title());
        }
    }
}
