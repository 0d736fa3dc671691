//! The reference answer: the nearest surface point found by testing every triangle, which the
//! index's answers are checked against.

use super::Nearest;
use super::surface::Surface;
use super::triangle::Feature;
use nalgebra::Point3;

/// The nearest surface point to `p` by testing every triangle: the reference the index is
/// checked against. Ties go to the triangle held first.
pub fn nearest_brute_force(surface: &Surface, p: &Point3<f64>) -> Option<Nearest> {
    let mut best: Option<(f64, usize, Point3<f64>, Feature)> = None;
    for t in 0..surface.len() {
        let (d2, c, f) = surface.closest(t, p);
        if best.is_none_or(|b| d2 < b.0) {
            best = Some((d2, t, c, f));
        }
    }
    best.map(|(d2, t, c, f)| surface.signed(t, p, d2, c, f))
}
