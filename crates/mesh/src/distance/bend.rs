//! When a descent can stop: how steeply the surface bends towards either side around each
//! triangle ([`bend_towards`], found once per triangle when the [`Surface`] is made), and the
//! certificate it gives, without reading the neighbours, that none of them is nearer to a point
//! than the triangle's own closest point ([`Surface::certainly_nearest`]).

use super::surface::Surface;
use super::triangle::Feature;
use nalgebra::{Point3, Vector3};

impl Surface {
    /// Whether no triangle sharing a corner with `t` can be nearer to `p` than `t`'s closest
    /// point `c`, at squared distance `d2`, on `feature`. Where `c` is inside the face, the
    /// ball about `p` through `c` touches `t`'s plane at `c`, and a neighbour rising towards
    /// `p` with slope at most `bend` beyond `t` cannot reach into it while `c` is at least
    /// `bend · d / 2` inside every edge ([`bend_towards`]). This is the descent's question,
    /// answered without reading the neighbours.
    pub(super) fn certainly_nearest(
        &self,
        t: usize,
        p: &Point3<f64>,
        d2: f64,
        c: &Point3<f64>,
        feature: Feature,
    ) -> bool {
        if !matches!(feature, Feature::Face) {
            return false;
        }
        let g = &self.geometry[t];
        let [x, y, z, offset] = g.plane;
        let front = x * p.x + y * p.y + z * p.z - offset >= 0.0;
        let bend = f64::from(g.bend[usize::from(!front)]);
        if bend == 0.0 {
            return true;
        }
        // The distance from `c` to the nearest edge's line, a little under (rounding).
        let inside = (0..3)
            .map(|k| {
                let (a, b) = (g.corners[k], g.corners[(k + 1) % 3]);
                (c - a).cross(&(b - a)).norm() * f64::from(g.inverse_edges[k])
            })
            .fold(f64::INFINITY, f64::min)
            * (1.0 - 1e-9);
        2.0 * inside >= bend * d2.sqrt()
    }
}

/// How steeply the triangles `around` (each sharing a corner with the triangle `corners`,
/// whose own vertex ids are `own`) rise towards the side `normal` points to: the least `s`
/// such that, on each of them, the height above the triangle's plane is at most `s` times the
/// distance beyond a line through the shared corners that has the triangle on its other side
/// (the shared edge; at a shared corner, the best of its two edges and the bisector of their
/// outward normals).
/// 0 where none rises (convex from that side); infinite where one folds back over the
/// triangle, or for a degenerate triangle.
///
/// Why it bounds the nearest point: take `p` at distance `d` in front of an inner point `c`
/// of the triangle, `r` from its nearest edge. A point `q` of a neighbour at height `h` and
/// `l` beyond that neighbour's line lies at least `r + l` from `c` along the plane, so it is
/// inside the ball about `p` of radius `d` only if `(r + l)² < 2·d·h ≤ 2·d·s·l`; as
/// `(r + l)² ≥ 4·r·l`, none is when `2·r ≥ s·d`. Points below the plane (`h < 0`) are never
/// inside it.
pub(super) fn bend_towards(
    corners: &[Point3<f64>; 3],
    normal: Vector3<f64>,
    own: [u32; 3],
    around: &[[u32; 3]],
    vertices: &[Point3<f64>],
) -> f64 {
    if normal == Vector3::zeros() {
        return f64::INFINITY;
    }
    let offset = normal.dot(&corners[0].coords);
    // The outward unit normal, within the plane, of edge k (from corner k to corner k + 1).
    let outward = |k: usize| -> Option<Vector3<f64>> {
        let (a, b, other) = (corners[k], corners[(k + 1) % 3], corners[(k + 2) % 3]);
        let m = (b - a).cross(&normal).try_normalize(0.0)?;
        Some(if m.dot(&(other - a)) > 0.0 { -m } else { m })
    };
    // The least slope a neighbour needs against a line through `hinge` with outward normal
    // `m`, if its corners behind the line allow one.
    let slope = |tri: &[u32; 3], hinge: Point3<f64>, m: Vector3<f64>| -> Option<f64> {
        let (mut need, mut allow) = (0.0f64, f64::INFINITY);
        for &v in tri.iter().filter(|v| !own.contains(v)) {
            let u = vertices[v as usize].coords;
            let (h, l) = (normal.dot(&u) - offset, m.dot(&(u - hinge.coords)));
            if h > 0.0 {
                if l <= 0.0 {
                    return None;
                }
                need = need.max(h / l);
            } else if l < 0.0 {
                allow = allow.min(h / l);
            }
        }
        (need <= allow).then_some(need)
    };
    let mut steepest = 0.0f64;
    for tri in around {
        let shared: Vec<usize> = (0..3).filter(|&k| tri.contains(&own[k])).collect();
        // The lines through the shared corners that have the triangle on their other side: the
        // shared edge; at a shared corner, its two edges and the bisector of their normals.
        let lines: Vec<Vector3<f64>> = match shared[..] {
            [i, j] => outward(if (i + 1) % 3 == j { i } else { j }).into_iter().collect(),
            [i] => {
                let (m1, m2) = (outward(i), outward((i + 2) % 3));
                let bisector = m1.zip(m2).and_then(|(a, b)| (a + b).try_normalize(0.0));
                [m1, m2, bisector].into_iter().flatten().collect()
            }
            _ => Vec::new(),
        };
        let hinge = corners[shared.first().copied().unwrap_or(0)];
        match lines.iter().filter_map(|&m| slope(tri, hinge, m)).reduce(f64::min) {
            Some(need) => steepest = steepest.max(need),
            None => return f64::INFINITY,
        }
    }
    steepest
}
