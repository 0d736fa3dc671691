//! Exact signed distance from a point to a triangle surface, within a reach, fast enough to
//! ask for every vertex of an arch at every frame.
//!
//! The sign comes from angle-weighted pseudo-normals (Bærentzen & Aanæs): positive in front
//! of the surface (outside the tooth), negative behind it. On an open scan "behind" is only
//! meaningful near the surface, which is why every query has a reach, and a point off to the
//! side of the scan's rim counts as outside.
//!
//! [`SurfaceIndex`] buckets triangles in a uniform grid: a cell lists every triangle that can
//! be within the reach of some point in it, sorted by distance from the cell's centre, so a
//! query stops as soon as no remaining triangle can beat the best so far. It returns exactly
//! what [`nearest_brute_force`] returns (same triangle, same distance) for every point within
//! the reach; points farther away cost one array look-up.

use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};

/// The closest point of the surface to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nearest {
    /// Signed distance (mm): positive in front of the surface, negative behind it.
    pub distance: f64,
    /// The closest surface point.
    pub point: Point3<f64>,
    /// The triangle it lies on.
    pub triangle: u32,
    /// Unit outward normal at the closest feature (face, edge or vertex pseudo-normal).
    pub normal: Vector3<f64>,
}

/// Per-triangle data for distance queries: corners and the pseudo-normals of its face, edges
/// and corners.
#[derive(Debug, Clone)]
struct Tri {
    corners: [Point3<f64>; 3],
    face: Vector3<f64>,
    /// Edges ab, bc, ca.
    edges: [Vector3<f64>; 3],
    vertices: [Vector3<f64>; 3],
    /// Whether each edge, and each corner, lies on the scan's rim.
    rim_edges: [bool; 3],
    rim_vertices: [bool; 3],
}

/// Which feature of a triangle is closest to a point.
#[derive(Debug, Clone, Copy)]
enum Feature {
    Face,
    Edge(usize),
    Vertex(usize),
}

/// Precomputed triangles with their pseudo-normals.
#[derive(Debug, Clone)]
pub struct Surface {
    tris: Vec<Tri>,
}

impl Surface {
    /// Prepares `mesh` for distance queries.
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.triangles.len();
        let faces: Vec<Vector3<f64>> =
            (0..n).map(|t| mesh.area_normal(t).try_normalize(0.0).unwrap_or_else(Vector3::zeros)).collect();
        let mut vertex_normals = vec![Vector3::zeros(); mesh.vertices.len()];
        let mut edge_normals = std::collections::HashMap::<(u32, u32), (Vector3<f64>, u32)>::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = mesh.corners(t);
            for k in 0..3 {
                let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                let angle = e1.angle(&e2);
                if angle.is_finite() {
                    vertex_normals[tri[k] as usize] += faces[t] * angle;
                }
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let e = edge_normals.entry((a.min(b), a.max(b))).or_insert((Vector3::zeros(), 0));
                e.0 += faces[t];
                e.1 += 1;
            }
        }
        let mut rim_vertex = vec![false; mesh.vertices.len()];
        for (&(a, b), &(_, count)) in &edge_normals {
            if count == 1 {
                rim_vertex[a as usize] = true;
                rim_vertex[b as usize] = true;
            }
        }
        let unit = |v: Vector3<f64>, fallback: Vector3<f64>| v.try_normalize(1e-12).unwrap_or(fallback);
        let tris = (0..n)
            .map(|t| {
                let tri = mesh.triangles[t];
                let edge = |k: usize| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    edge_normals.get(&(a.min(b), a.max(b))).copied().unwrap_or((faces[t], 1))
                };
                Tri {
                    corners: mesh.corners(t),
                    face: faces[t],
                    edges: [0, 1, 2].map(|k| unit(edge(k).0, faces[t])),
                    vertices: tri.map(|v| unit(vertex_normals[v as usize], faces[t])),
                    rim_edges: [0, 1, 2].map(|k| edge(k).1 == 1),
                    rim_vertices: tri.map(|v| rim_vertex[v as usize]),
                }
            })
            .collect();
        Surface { tris }
    }

    /// Triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Squared unsigned distance from `p` to triangle `t`, its closest point and feature.
    fn closest(&self, t: usize, p: &Point3<f64>) -> (f64, Point3<f64>, Feature) {
        let (c, f) = closest_on_triangle(p, &self.tris[t].corners);
        ((p - c).norm_squared(), c, f)
    }

    /// The signed result for triangle `t` given its closest point and feature.
    fn signed(&self, t: usize, p: &Point3<f64>, d2: f64, c: Point3<f64>, f: Feature) -> Nearest {
        let tri = &self.tris[t];
        let (normal, on_rim) = match f {
            Feature::Face => (tri.face, false),
            Feature::Edge(k) => (tri.edges[k], tri.rim_edges[k]),
            Feature::Vertex(k) => (tri.vertices[k], tri.rim_vertices[k]),
        };
        let d = d2.sqrt();
        let offset = p - c;
        let along = offset.dot(&normal);
        // Past the rim of an open scan there is no inside: a point whose nearest surface point
        // is on the rim and lies off to the side of it is outside.
        let beside_rim = on_rim && (offset - normal * along).norm() > 1e-9;
        let sign = if along < 0.0 && !beside_rim { -1.0 } else { 1.0 };
        Nearest { distance: sign * d, point: c, triangle: t as u32, normal }
    }
}

/// The closest point of triangle `abc` to `p` and the feature it lies on (Ericson, Real-Time
/// Collision Detection, 5.1.5).
fn closest_on_triangle(p: &Point3<f64>, [a, b, c]: &[Point3<f64>; 3]) -> (Point3<f64>, Feature) {
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

/// The nearest surface point to `p` by testing every triangle: the reference the index is
/// checked against. Ties go to the lowest triangle index.
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

/// A grid over a surface answering signed-distance queries exactly within `reach`.
#[derive(Debug, Clone)]
pub struct SurfaceIndex {
    surface: Surface,
    reach: f64,
    cell: f64,
    origin: Vector3<f64>,
    dims: [usize; 3],
    /// Per cell, the range of `items` holding its triangles.
    starts: Vec<u32>,
    /// (triangle, distance from the cell centre to it), sorted by distance within a cell.
    items: Vec<(u32, f32)>,
}

impl SurfaceIndex {
    /// Indexes `mesh` for queries out to `reach` mm from the surface (on either side).
    pub fn new(mesh: &Mesh, reach: f64) -> Self {
        let surface = Surface::new(mesh);
        let reach = reach.max(1e-6);
        // A cell near the reach keeps the lists short without making the grid huge.
        let cell = reach.clamp(0.25, 2.0);
        let [lo, hi] = mesh.bounds();
        let origin = lo - Vector3::repeat(reach + cell);
        let dims = ((hi + Vector3::repeat(reach + cell) - origin) / cell).map(|x| x.ceil().max(1.0) as usize);
        let dims = [dims.x, dims.y, dims.z];
        let half_diagonal = cell * 3f64.sqrt() / 2.0;
        let mut pairs: Vec<(u32, u32, f32)> = Vec::new();
        for t in 0..surface.len() {
            let corners = &surface.tris[t].corners;
            let (mut tlo, mut thi) = (corners[0].coords, corners[0].coords);
            for c in &corners[1..] {
                tlo = tlo.inf(&c.coords);
                thi = thi.sup(&c.coords);
            }
            let first = ((tlo - Vector3::repeat(reach) - origin) / cell).map(|x| x.floor().max(0.0) as usize);
            let last = ((thi + Vector3::repeat(reach) - origin) / cell).map(|x| x.floor() as usize);
            for z in first.z..=last.z.min(dims[2] - 1) {
                for y in first.y..=last.y.min(dims[1] - 1) {
                    for x in first.x..=last.x.min(dims[0] - 1) {
                        let centre =
                            Point3::from(origin + Vector3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) * cell);
                        let d = surface.closest(t, &centre).0.sqrt();
                        // Some point of the cell may be within reach of the triangle.
                        if d <= reach + half_diagonal {
                            let id = (z * dims[1] + y) * dims[0] + x;
                            // Rounded down so that the bound stays a lower bound in f32.
                            pairs.push((id as u32, t as u32, next_down(d as f32)));
                        }
                    }
                }
            }
        }
        pairs.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.2.total_cmp(&b.2)).then(a.1.cmp(&b.1)));
        let mut starts = vec![0u32; dims[0] * dims[1] * dims[2] + 1];
        for &(id, _, _) in &pairs {
            starts[id as usize + 1] += 1;
        }
        for i in 1..starts.len() {
            starts[i] += starts[i - 1];
        }
        let items = pairs.into_iter().map(|(_, t, d)| (t, d)).collect();
        SurfaceIndex { surface, reach, cell, origin, dims, starts, items }
    }

    /// How far from the surface queries are answered (mm).
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The indexed surface.
    pub fn surface(&self) -> &Surface {
        &self.surface
    }

    /// The nearest surface point to `p` if it is within the reach (`None` beyond it).
    pub fn nearest(&self, p: &Point3<f64>) -> Option<Nearest> {
        let g = (p.coords - self.origin) / self.cell;
        if !(g.x >= 0.0 && g.y >= 0.0 && g.z >= 0.0) {
            return None;
        }
        let [x, y, z] = [g.x as usize, g.y as usize, g.z as usize];
        if x >= self.dims[0] || y >= self.dims[1] || z >= self.dims[2] {
            return None;
        }
        let id = (z * self.dims[1] + y) * self.dims[0] + x;
        let (start, end) = (self.starts[id] as usize, self.starts[id + 1] as usize);
        if start == end {
            return None;
        }
        let centre = self.origin + Vector3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) * self.cell;
        let offset = (p.coords - centre).norm();
        let mut best: Option<(f64, usize, Point3<f64>, Feature)> = None;
        let mut best_d = self.reach;
        for &(t, from_centre) in &self.items[start..end] {
            // |p - T| >= |c - T| - |p - c|, and the list is sorted by |c - T|.
            if from_centre as f64 - offset > best_d {
                break;
            }
            let (d2, c, f) = self.surface.closest(t as usize, p);
            let better = match best {
                None => d2 <= best_d * best_d,
                Some(b) => d2 < b.0 || (d2 == b.0 && (t as usize) < b.1),
            };
            if better {
                best = Some((d2, t as usize, c, f));
                best_d = d2.sqrt();
            }
        }
        best.map(|(d2, t, c, f)| self.surface.signed(t, p, d2, c, f))
    }
}

/// The largest f32 below `x` (for a lower bound that survives rounding).
fn next_down(x: f32) -> f32 {
    if x <= 0.0 { 0.0 } else { f32::from_bits(x.to_bits() - 1) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bumpy(n: usize) -> Mesh {
        // A height field z = sin·cos over 10 × 10 mm, normals up (+z).
        let mut vertices = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (10.0 * i as f64 / n as f64, 10.0 * j as f64 / n as f64);
                vertices.push(Point3::new(x, y, 0.8 * (x * 0.9).sin() * (y * 0.7).cos()));
            }
        }
        let mut triangles = Vec::new();
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Mesh { vertices, triangles }
    }

    #[test]
    fn the_index_returns_exactly_what_brute_force_returns_within_its_reach() {
        let mesh = bumpy(30);
        let index = SurfaceIndex::new(&mesh, 0.6);
        let mut state = 12345u64;
        let mut rnd = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut within, mut beyond) = (0, 0);
        for _ in 0..20000 {
            let p = Point3::new(rnd() * 12.0 - 1.0, rnd() * 12.0 - 1.0, rnd() * 4.0 - 2.0);
            let reference = nearest_brute_force(index.surface(), &p).expect("non-empty");
            match index.nearest(&p) {
                Some(n) => {
                    within += 1;
                    assert!((n.distance - reference.distance).abs() < 1e-12, "{p}: {n:?} vs {reference:?}");
                    assert!(n.distance.abs() <= 0.6);
                }
                None => {
                    beyond += 1;
                    assert!(reference.distance.abs() > 0.6, "{p}: missed {reference:?}");
                }
            }
        }
        assert!(within > 2000 && beyond > 2000, "{within} {beyond}");
    }

    #[test]
    fn the_sign_is_positive_in_front_and_negative_behind() {
        let mesh = bumpy(10);
        let index = SurfaceIndex::new(&mesh, 1.0);
        let top = mesh.vertices[60];
        let above = index.nearest(&(top + Vector3::new(0.0, 0.0, 0.3))).expect("near");
        let below = index.nearest(&(top - Vector3::new(0.0, 0.0, 0.3))).expect("near");
        assert!(above.distance > 0.0 && below.distance < 0.0, "{above:?} {below:?}");
    }
}
