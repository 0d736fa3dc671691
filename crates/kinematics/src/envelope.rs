//! Envelopes of motion: the convex hull of a path projected on one plane (Posselt's envelope
//! is the sagittal one), with its area.

use serde_json::{Value, json};

/// The convex hull of the path in one plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Envelope {
    /// The hull's corners (mm), counter-clockwise, no point repeated, no collinear corners.
    pub hull: Vec<(f64, f64)>,
    /// Its area (mm²); 0 when the path is a point or a line.
    pub area_mm2: f64,
}

impl Envelope {
    /// The envelope of `points`.
    pub fn of(points: &[(f64, f64)]) -> Self {
        let hull = convex_hull(points);
        let area_mm2 = polygon_area(&hull);
        Envelope { hull, area_mm2 }
    }

    /// As `metrics.json` holds it, in `view`'s axes (as its border is).
    pub fn to_json(&self, view: crate::PlaneView) -> Value {
        let (x, y) = view.axes();
        json!({
            "axes": [x, y],
            "area_mm2": self.area_mm2,
            "vertices": self.hull.len(),
            "hull_mm": self.hull.iter().map(|&(a, b)| [a, b]).collect::<Vec<_>>(),
        })
    }
}

/// (b − a) × (c − a): positive when a → b → c turns counter-clockwise.
pub(crate) fn cross(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> f64 {
    (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
}

/// The convex hull (Andrew's monotone chain): corners counter-clockwise from the lowest-x
/// point, collinear points and duplicates dropped, non-finite points ignored. One or two
/// corners when the points are all equal or all on a line.
pub fn convex_hull(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points.iter().copied().filter(|q| q.0.is_finite() && q.1.is_finite()).collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    // Lower chain left to right, upper chain right to left; each drops any corner that does not
    // turn left.
    let chain = |iter: &mut dyn Iterator<Item = (f64, f64)>| {
        let mut h: Vec<(f64, f64)> = Vec::new();
        for q in iter {
            while h.len() >= 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        // The last point starts the other chain.
        h.pop();
        h
    };
    let mut hull = chain(&mut p.iter().copied());
    hull.extend(chain(&mut p.iter().rev().copied()));
    hull
}

/// The area of a simple polygon (shoelace formula), whatever its orientation.
pub fn polygon_area(corners: &[(f64, f64)]) -> f64 {
    let n = corners.len();
    if n < 3 {
        return 0.0;
    }
    let twice: f64 = (0..n)
        .map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum();
    twice.abs() / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `q` is inside or on the counter-clockwise polygon `hull`.
    fn inside(hull: &[(f64, f64)], q: (f64, f64)) -> bool {
        (0..hull.len()).all(|i| cross(hull[i], hull[(i + 1) % hull.len()], q) >= -1e-12)
    }

    #[test]
    fn a_square_with_interior_and_edge_points_has_four_corners() {
        let mut pts = vec![(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)];
        pts.extend([(1.0, 1.0), (0.5, 1.5), (1.0, 0.0), (2.0, 1.0), (0.0, 0.0), (1.9, 0.1)]);
        let hull = convex_hull(&pts);
        assert_eq!(hull, vec![(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)], "counter-clockwise, no edge points");
        assert_eq!(polygon_area(&hull), 4.0);
        assert!(pts.iter().all(|&q| inside(&hull, q)));
    }

    #[test]
    fn a_random_cloud_is_inside_its_convex_hull() {
        // A fixed pseudo-random cloud (LCG), so the test needs no seed crate.
        let mut s: u64 = 12345;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 10.0 - 5.0
        };
        let pts: Vec<(f64, f64)> = (0..200).map(|_| (next(), next())).collect();
        let hull = convex_hull(&pts);
        assert!(hull.len() >= 3 && pts.iter().all(|&q| inside(&hull, q)));
        for i in 0..hull.len() {
            let (a, b, c) = (hull[i], hull[(i + 1) % hull.len()], hull[(i + 2) % hull.len()]);
            assert!(cross(a, b, c) > 0.0, "strictly convex at {b:?}");
            assert!(pts.contains(&b), "corners are input points");
        }
        assert!(polygon_area(&hull) > 0.0 && polygon_area(&hull) <= 100.0);
    }

    #[test]
    fn collinear_points_give_the_two_ends_and_no_area() {
        let pts = [(1.0, 1.0), (3.0, 3.0), (2.0, 2.0), (0.0, 0.0), (3.0, 3.0)];
        assert_eq!(convex_hull(&pts), vec![(0.0, 0.0), (3.0, 3.0)]);
        assert_eq!(polygon_area(&convex_hull(&pts)), 0.0);
        let vertical = [(0.0, 2.0), (0.0, -1.0), (0.0, 0.5)];
        assert_eq!(convex_hull(&vertical), vec![(0.0, -1.0), (0.0, 2.0)]);
    }

    #[test]
    fn fewer_than_three_points_are_their_own_hull() {
        assert!(convex_hull(&[]).is_empty());
        assert_eq!(convex_hull(&[(1.0, 2.0)]), vec![(1.0, 2.0)]);
        assert_eq!(convex_hull(&[(1.0, 2.0), (1.0, 2.0)]), vec![(1.0, 2.0)]);
        assert_eq!(convex_hull(&[(3.0, 0.0), (1.0, 2.0)]), vec![(1.0, 2.0), (3.0, 0.0)]);
        assert_eq!(convex_hull(&[(f64::NAN, 0.0), (1.0, 2.0)]), vec![(1.0, 2.0)], "NaN ignored");
        assert_eq!(polygon_area(&[(0.0, 0.0), (1.0, 1.0)]), 0.0);
    }
}
