//! The exact closest point of one triangle to a point, and which of its features (face, edge or
//! corner) that point lies on: the geometry every answer ends in.

use nalgebra::Point3;

/// Which feature of a triangle is closest to a point.
#[derive(Debug, Clone, Copy)]
pub(super) enum Feature {
    Face,
    Edge(usize),
    Vertex(usize),
}

/// The closest point of triangle `abc` to `p` and the feature it lies on (Ericson, Real-Time
/// Collision Detection, 5.1.5).
pub(super) fn closest_on_triangle(p: &Point3<f64>, [a, b, c]: &[Point3<f64>; 3]) -> (Point3<f64>, Feature) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, Feature::Vertex(0));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, Feature::Edge(0));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, Feature::Edge(1));
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE {
        // A degenerate triangle: its closest point is on one of its edges.
        let edges = [(a, b, 0), (b, c, 1), (c, a, 2)];
        let on = |(s, e, _): &(&Point3<f64>, &Point3<f64>, usize)| {
            let d = *e - *s;
            let t = if d.norm_squared() > 0.0 { ((p - *s).dot(&d) / d.norm_squared()).clamp(0.0, 1.0) } else { 0.0 };
            *s + d * t
        };
        let best = edges
            .iter()
            .map(|e| (on(e), e.2))
            .min_by(|x, y| (p - x.0).norm_squared().total_cmp(&(p - y.0).norm_squared()));
        return best.map_or((*a, Feature::Vertex(0)), |(q, k)| (q, Feature::Edge(k)));
    }
    let (v, w) = (vb / denom, vc / denom);
    (a + ab * v + ac * w, Feature::Face)
}
