//! The printable marker body: the marker's solid (the regular dodecahedron, or a cube standing
//! on a vertex) fused with a cylindrical mounting post that leaves its −Z vertex (the one
//! opposite the camera-facing +Z vertex) along −Z.
//!
//! The post is a right prism whose cross-section is a regular N-gon (N a multiple of 3) of
//! circumradius `post_diameter / 2` centred on the Z axis. Near the −Z vertex the solid's lower
//! surface is z = max of the three bottom faces' planes, piecewise linear with creases along
//! the three edges leaving the vertex, 120° apart in azimuth. The N-gon is turned so that
//! three of its corners lie on those creases; then each side of the N-gon lies over a single
//! face, every wall quad of the prism is planar with its top edge on that face, and the three
//! bottom faces keep their polygon with a notch cut round the vertex. The union's surface is:
//! the untouched faces (nine of a dodecahedron, three of a cube), the three notched faces, the
//! prism walls from the notch down to the end cap, and the N-gon end cap. Nothing of the prism inside the solid is kept, so the
//! mesh has no internal faces.

use crate::{HarnessError, HarnessParams, Mesh};
use jawtrack_marker::{BodyKind, Face, Marker, Solid, SolidKind, TagFamily};
use nalgebra::{Point3, Vector2, Vector3};
use std::f64::consts::TAU;

/// One of the three faces meeting at the −Z vertex and the part of the post's ring over it.
#[derive(Debug, Clone)]
struct BottomFace {
    /// Face number.
    face: usize,
    /// Position of the −Z vertex in the face's vertex list.
    at: usize,
    /// Ring corners over this face, from the one on the edge toward the face's vertex before
    /// the −Z vertex to the one on the edge toward the vertex after it.
    chain: Vec<usize>,
}

/// Where the post meets the solid, independent of the post's diameter.
#[derive(Debug, Clone)]
pub(crate) struct PostLayout {
    /// Index of the −Z vertex in `Solid::vertices()`.
    apex_index: usize,
    /// The −Z vertex (mm).
    apex: Vector3<f64>,
    /// Azimuth (rad) of ring corner 0, which lies on one of the edges leaving the vertex.
    theta0: f64,
    /// N, the number of ring corners.
    segments: usize,
    /// The three faces around the vertex.
    bottom: Vec<BottomFace>,
}

impl PostLayout {
    /// Finds the −Z vertex, its three faces and edges, and lays the N-gon's corners on them.
    fn new(solid: &Solid, segments: usize) -> Result<PostLayout, HarnessError> {
        let geometry = |msg: String| HarnessError::Geometry(msg);
        let edge = solid.edge();
        let tol = 1e-9 * edge;
        let (apex_index, apex) = solid
            .vertices()
            .iter()
            .copied()
            .enumerate()
            .min_by(|a, b| a.1.z.total_cmp(&b.1.z))
            .ok_or_else(|| geometry("the solid has no vertices".into()))?;
        if apex.x.abs() > tol || apex.y.abs() > tol {
            return Err(geometry(format!("the lowest vertex {apex:?} is not on the Z axis")));
        }
        let neighbours: Vec<Vector3<f64>> =
            solid.vertices().iter().copied().filter(|v| ((v - apex).norm() - edge).abs() < tol).collect();
        if neighbours.len() != 3 {
            return Err(geometry(format!("the −Z vertex has {} neighbours, not 3", neighbours.len())));
        }
        let theta0 = (neighbours[0].y - apex.y).atan2(neighbours[0].x - apex.x);
        let step = TAU / segments as f64;
        let ring_index = |p: &Vector3<f64>| -> Result<usize, HarnessError> {
            let theta = (p.y - apex.y).atan2(p.x - apex.x);
            let u = (theta - theta0).rem_euclid(TAU) / step;
            let k = u.round();
            if (u - k).abs() > 1e-6 {
                return Err(geometry(format!(
                    "an edge leaving the −Z vertex is not at a multiple of 360°/{segments} from the first"
                )));
            }
            Ok(k as usize % segments)
        };
        let third = segments / 3;
        let mut bottom = Vec::new();
        for face in solid.faces() {
            let Some(at) = face.vertices.iter().position(|v| (v - apex).norm() < tol) else { continue };
            let sides = face.vertices.len();
            let before = ring_index(&face.vertices[(at + sides - 1) % sides])?;
            let after = ring_index(&face.vertices[(at + 1) % sides])?;
            // Go the short way round (a third of the ring) from one edge to the other.
            let forward = (after + segments - before) % segments;
            let dir = if forward == third {
                1
            } else if forward == segments - third {
                segments - 1
            } else {
                return Err(geometry(format!("face {} spans {forward} of {segments} ring steps", face.index)));
            };
            let chain = (0..=third).map(|s| (before + s * dir) % segments).collect();
            bottom.push(BottomFace { face: face.index, at, chain });
        }
        if bottom.len() != 3 {
            return Err(geometry(format!("{} faces meet at the −Z vertex, not 3", bottom.len())));
        }
        Ok(PostLayout { apex_index, apex, theta0, segments, bottom })
    }

    /// Azimuth (rad) of ring corner `k`.
    fn azimuth(&self, k: usize) -> f64 {
        self.theta0 + TAU * k as f64 / self.segments as f64
    }

    /// Ring corner `k` of a post of circumradius `r`, on the solid's lower surface.
    fn ring_point(&self, solid: &Solid, k: usize, r: f64) -> Vector3<f64> {
        let phi = self.azimuth(k);
        let (x, y) = (r * phi.cos(), r * phi.sin());
        let z = self
            .bottom
            .iter()
            .map(|b| {
                let f = &solid.faces()[b.face];
                // The face plane n·(p − c) = 0 solved for z; n.z is far from 0 on a bottom face.
                f.center.z - (f.normal.x * (x - f.center.x) + f.normal.y * (y - f.center.y)) / f.normal.z
            })
            .fold(f64::NEG_INFINITY, f64::max);
        Vector3::new(x, y, z)
    }

    /// The post's footprint on each bottom face: (face number, the −Z vertex followed by the
    /// ring corners over that face), all on the face's plane.
    pub(crate) fn footprints(&self, solid: &Solid, r: f64) -> Vec<(usize, Vec<Vector3<f64>>)> {
        self.bottom
            .iter()
            .map(|b| {
                let mut poly = vec![self.apex];
                poly.extend(b.chain.iter().map(|&k| self.ring_point(solid, k, r)));
                (b.face, poly)
            })
            .collect()
    }
}

/// Why a post of some diameter does not fit.
enum Misfit {
    /// The footprint reaches `overshoot` mm past a far edge of `face`.
    Face { face: usize, overshoot: f64 },
    /// The footprint reaches `depth` mm into the black square of the tag on `face`.
    Tag { face: usize, depth: f64 },
}

/// Coordinates of `p` in the face's 2D frame (x = tag x axis, y = tag y axis toward the apex).
pub(crate) fn face_2d(face: &Face, p: &Vector3<f64>) -> Vector2<f64> {
    let d = p - face.center;
    Vector2::new(d.dot(&face.x_axis), d.dot(&face.y_axis))
}

/// How deep two convex polygons overlap (mm): the least translation that separates them, by
/// the separating-axis theorem. Zero or negative when they are apart or just touch.
fn penetration(a: &[Vector2<f64>], b: &[Vector2<f64>]) -> f64 {
    let mut depth = f64::INFINITY;
    for poly in [a, b] {
        for i in 0..poly.len() {
            let e = poly[(i + 1) % poly.len()] - poly[i];
            let n = Vector2::new(-e.y, e.x).normalize();
            let proj = |q: &[Vector2<f64>]| {
                q.iter()
                    .map(|p| p.dot(&n))
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| (lo.min(s), hi.max(s)))
            };
            let (alo, ahi) = proj(a);
            let (blo, bhi) = proj(b);
            depth = depth.min((ahi - blo).min(bhi - alo));
        }
    }
    depth
}

/// Whether a post of circumradius `r` fits: its footprint inside every bottom face and clear
/// of the black square of the tag there.
fn check_fit(solid: &Solid, layout: &PostLayout, squares: &[[Vector3<f64>; 4]], r: f64) -> Result<(), Misfit> {
    for (b, (face_no, poly)) in layout.bottom.iter().zip(layout.footprints(solid, r)) {
        let face = &solid.faces()[face_no];
        let normals = &face.edge_normals();
        // The footprint is convex and lies in the angle of the two edges at the vertex, so it is
        // inside the face when its corners are inside the far edges.
        let sides = face.vertices.len();
        let far = (0..sides).filter(|&i| i != b.at && (i + 1) % sides != b.at);
        let clearance = far
            .flat_map(|i| poly.iter().map(move |p| (face.vertices[i] - p).dot(&normals[i])))
            .fold(f64::INFINITY, f64::min);
        if clearance <= 1e-9 * solid.edge() {
            return Err(Misfit::Face { face: face_no, overshoot: -clearance.min(0.0) });
        }
        let foot: Vec<Vector2<f64>> = poly.iter().map(|p| face_2d(face, p)).collect();
        let square: Vec<Vector2<f64>> = squares[face_no].iter().map(|p| face_2d(face, p)).collect();
        let depth = penetration(&foot, &square);
        if depth > 0.0 {
            return Err(Misfit::Tag { face: face_no, depth });
        }
    }
    Ok(())
}

/// The nominal tag square (corners, body frame) on each face for this edge and tag size.
fn tag_squares(marker: &Marker) -> Result<Vec<[Vector3<f64>; 4]>, HarnessError> {
    let body = marker.body(BodyKind::Maxilla).ok_or(HarnessError::MissingBody(BodyKind::Maxilla))?;
    let mut squares = vec![[Vector3::zeros(); 4]; marker.solid.face_count()];
    for t in &body.tags {
        if let Some(s) = squares.get_mut(t.face) {
            *s = t.corners;
        }
    }
    Ok(squares)
}

/// The largest circumradius (mm) that fits, by bisection (the footprint grows with r).
fn largest_radius(solid: &Solid, layout: &PostLayout, squares: &[[Vector3<f64>; 4]]) -> f64 {
    let (mut lo, mut hi) = (0.0, solid.circumradius());
    if check_fit(solid, layout, squares, hi).is_ok() {
        return hi;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if check_fit(solid, layout, squares, mid).is_ok() { lo = mid } else { hi = mid }
    }
    lo
}

/// Everything needed to build the post, after every check has passed.
pub(crate) struct CheckedPost {
    /// The solid (nominal, of the marker's kind and edge).
    pub(crate) solid: Solid,
    /// Where the post meets it.
    pub(crate) layout: PostLayout,
    /// The post's circumradius (mm).
    pub(crate) radius: f64,
}

/// The nominal marker of this solid, edge and tag size: where the post must not reach. The tag
/// family only sets the white margin checked here, and tag36h11's (a cell of size/8) is the
/// narrowest of the families, so no marker of another family is refused by it.
fn squares_of(solid: SolidKind, marker_edge: f64, tag_size: f64) -> Result<Marker, HarnessError> {
    Ok(Marker::nominal_on(solid, TagFamily::TAG36H11, marker_edge, Some(tag_size))?)
}

/// Checks the parameters, the marker's solid, edge and tag size, and the fit of the post.
pub(crate) fn checked_post(
    kind: SolidKind,
    marker_edge: f64,
    tag_size: f64,
    params: &HarnessParams,
) -> Result<CheckedPost, HarnessError> {
    params.validate()?;
    let marker = squares_of(kind, marker_edge, tag_size)?;
    let solid = marker.geometry();
    let layout = PostLayout::new(&solid, params.post_segments)?;
    let squares = tag_squares(&marker)?;
    let radius = params.post_diameter / 2.0;
    match check_fit(&solid, &layout, &squares, radius) {
        Ok(()) => Ok(CheckedPost { solid, layout, radius }),
        Err(misfit) => {
            let max_diameter = 2.0 * largest_radius(&solid, &layout, &squares);
            Err(match misfit {
                Misfit::Face { face, overshoot } => {
                    HarnessError::PostTooWide { diameter: params.post_diameter, face, overshoot, max_diameter }
                }
                Misfit::Tag { face, depth } => HarnessError::PostCoversTag {
                    diameter: params.post_diameter,
                    face,
                    maxilla_id: BodyKind::Maxilla.first_id() + face as u32,
                    mandible_id: BodyKind::Mandible.first_id() + face as u32,
                    depth,
                    max_diameter,
                },
            })
        }
    }
}

/// The largest post diameter (mm) whose footprint stays inside the bottom faces and clear of
/// their tags' black squares, for a marker of this solid, edge and tag size and a post of
/// `post_segments` sides.
pub fn max_post_diameter(
    kind: SolidKind,
    marker_edge: f64,
    tag_size: f64,
    post_segments: usize,
) -> Result<f64, HarnessError> {
    HarnessParams { post_segments, ..HarnessParams::default() }.validate()?;
    let marker = squares_of(kind, marker_edge, tag_size)?;
    let solid = marker.geometry();
    let layout = PostLayout::new(&solid, post_segments)?;
    Ok(2.0 * largest_radius(&solid, &layout, &tag_squares(&marker)?))
}

/// Collects triangles, turning each so that its right-hand normal points along a known
/// outward direction: the construction knows which way is out for every piece, which is
/// simpler and surer than tracking the winding of each triangulation.
struct Builder {
    mesh: Mesh,
}

impl Builder {
    fn point(&self, i: u32) -> Vector3<f64> {
        self.mesh.vertices[i as usize].coords
    }

    fn push(&mut self, a: u32, b: u32, c: u32, outward: &Vector3<f64>) {
        let n = (self.point(b) - self.point(a)).cross(&(self.point(c) - self.point(a)));
        self.mesh.triangles.push(if n.dot(outward) >= 0.0 { [a, b, c] } else { [a, c, b] });
    }
}

/// The marker body (the solid `kind` of edge `marker_edge`) fused with its mounting post, as
/// a closed, outward-oriented triangle mesh in the body frame (mm).
///
/// `tag_size` is only used to check that the post's footprint on the three bottom faces stays
/// clear of their tags' black squares. Errors name the parameter that is out of range, or
/// the face and tag a too-thick post would cover.
pub fn body_mesh(
    kind: SolidKind,
    marker_edge: f64,
    tag_size: f64,
    params: &HarnessParams,
) -> Result<Mesh, HarnessError> {
    let CheckedPost { solid, layout, radius } = checked_post(kind, marker_edge, tag_size, params)?;
    let n = layout.segments;
    let to_u32 = |i: usize| u32::try_from(i).map_err(|_| HarnessError::Geometry("mesh too large".into()));

    // Vertex table: the solid's vertices but the −Z one, the ring on the surface, the ring at
    // the end, the end cap's centre.
    let solid_index = |j: usize| if j < layout.apex_index { j } else { j - 1 };
    let kept = solid.vertices().len() - 1;
    let top = |k: usize| kept + k;
    let low = |k: usize| kept + n + k;
    let centre = kept + 2 * n;
    let z_end = layout.apex.z - params.post_length;

    let mut vertices: Vec<Point3<f64>> = solid
        .vertices()
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != layout.apex_index)
        .map(|(_, v)| Point3::from(*v))
        .collect();
    let ring: Vec<Vector3<f64>> = (0..n).map(|k| layout.ring_point(&solid, k, radius)).collect();
    vertices.extend(ring.iter().map(|p| Point3::from(*p)));
    vertices.extend(ring.iter().map(|p| Point3::new(p.x, p.y, z_end)));
    vertices.push(Point3::new(0.0, 0.0, z_end));
    let mut b = Builder { mesh: Mesh { vertices, triangles: Vec::with_capacity(3 * solid.faces().len() + 4 * n) } };

    // Mesh index of each of the solid's vertices (the −Z one has none).
    let vertex_ids: Vec<Option<usize>> =
        solid.vertices().iter().enumerate().map(|(j, _)| (j != layout.apex_index).then(|| solid_index(j))).collect();
    let id_of = |p: &Vector3<f64>| -> Result<usize, HarnessError> {
        solid
            .vertices()
            .iter()
            .position(|v| (v - p).norm() < 1e-9 * solid.edge())
            .and_then(|j| vertex_ids[j])
            .ok_or_else(|| HarnessError::Geometry(format!("face vertex {p:?} not found")))
    };

    for face in solid.faces() {
        if let Some(bf) = layout.bottom.iter().find(|bf| bf.face == face.index) {
            // The notched face: the polygon's other corners, then the ring corners from the
            // edge before the −Z vertex to the edge after it. Not convex, so ear-clipped in the
            // face's own plane.
            let sides = face.vertices.len();
            let mut poly: Vec<usize> =
                (1..sides).map(|s| id_of(&face.vertices[(bf.at + s) % sides])).collect::<Result<_, _>>()?;
            poly.extend(bf.chain.iter().map(|&k| top(k)));
            let flat: Vec<f64> = poly
                .iter()
                .flat_map(|&i| {
                    let q = face_2d(face, &b.mesh.vertices[i].coords);
                    [q.x, q.y]
                })
                .collect();
            let tris = earcutr::earcut(&flat, &[], 2)
                .map_err(|e| HarnessError::Geometry(format!("triangulating face {}: {e}", face.index)))?;
            if tris.len() != 3 * (poly.len() - 2) {
                return Err(HarnessError::Geometry(format!(
                    "face {} triangulated into {} triangles, not {}",
                    face.index,
                    tris.len() / 3,
                    poly.len() - 2
                )));
            }
            for t in tris.chunks_exact(3) {
                b.push(to_u32(poly[t[0]])?, to_u32(poly[t[1]])?, to_u32(poly[t[2]])?, &face.normal);
            }
        } else {
            // An untouched face: a convex polygon, fanned from its first corner.
            let ids: Vec<u32> = face.vertices.iter().map(|v| id_of(v).and_then(to_u32)).collect::<Result<_, _>>()?;
            for s in 1..ids.len() - 1 {
                b.push(ids[0], ids[s], ids[s + 1], &face.normal);
            }
        }
    }

    for k in 0..n {
        let k1 = (k + 1) % n;
        let mid = 0.5 * (layout.azimuth(k) + layout.azimuth(k + 1));
        let out = Vector3::new(mid.cos(), mid.sin(), 0.0);
        let (t0, t1, l0, l1) = (to_u32(top(k))?, to_u32(top(k1))?, to_u32(low(k))?, to_u32(low(k1))?);
        b.push(t0, l0, l1, &out);
        b.push(t0, l1, t1, &out);
        b.push(to_u32(centre)?, l0, l1, &-Vector3::z());
    }
    Ok(b.mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_marker::{DEFAULT_EDGE_MM, default_tag_size};
    use std::collections::HashMap;

    fn default_mesh() -> Mesh {
        body_mesh(
            SolidKind::Dodecahedron,
            DEFAULT_EDGE_MM,
            default_tag_size(DEFAULT_EDGE_MM),
            &HarnessParams::default(),
        )
        .expect("defaults fit")
    }

    fn v3(p: Point3<f64>) -> Vector3<f64> {
        p.coords
    }

    /// Every edge is used by exactly two triangles, once in each direction; the surface is a
    /// single sheet round each vertex and a sphere (Euler characteristic 2); every vertex is
    /// used and no two coincide.
    fn assert_closed_manifold(m: &Mesh) {
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in &m.triangles {
            assert!(t[0] != t[1] && t[1] != t[2] && t[2] != t[0], "repeated corner in {t:?}");
            for i in 0..3 {
                *directed.entry((t[i], t[(i + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(count, 1, "edge {a}->{b} used {count} times in the same direction");
            assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}->{b} has no opposite partner");
        }
        let edges = directed.len() / 2;
        let euler = m.vertices.len() as i64 - edges as i64 + m.triangles.len() as i64;
        assert_eq!(euler, 2, "V − E + F");
        // Round each vertex, following "next edge" must visit all its triangles in one cycle.
        let mut next: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &m.triangles {
            for i in 0..3 {
                // Triangle (v, a, b) round v: from edge v->a to edge v->b.
                next.insert((t[i], t[(i + 1) % 3]), t[(i + 2) % 3]);
            }
        }
        let mut fan_size = vec![0usize; m.vertices.len()];
        for t in &m.triangles {
            for &v in t {
                fan_size[v as usize] += 1;
            }
        }
        for (v, &size) in fan_size.iter().enumerate() {
            assert!(size >= 3, "vertex {v} used by {size} triangles");
            let v = v as u32;
            let start = *next.keys().find(|k| k.0 == v).expect("vertex has an edge");
            let (mut cur, mut steps) = (start.1, 0);
            loop {
                cur = next[&(v, cur)];
                steps += 1;
                if cur == start.1 {
                    break;
                }
                assert!(steps <= size, "vertex {v}: fan does not close");
            }
            assert_eq!(steps, size, "vertex {v}: more than one fan (pinched)");
        }
        for i in 0..m.vertices.len() {
            for j in i + 1..m.vertices.len() {
                assert!((v3(m.vertices[i]) - v3(m.vertices[j])).norm() > 1e-6, "vertices {i} and {j} coincide");
            }
        }
    }

    fn assert_no_degenerate_triangles(m: &Mesh) {
        for i in 0..m.triangles.len() {
            let area = 0.5 * m.area_normal(i).norm();
            let [a, b, c] = m.corners(i).map(v3);
            let longest = (b - a).norm().max((c - b).norm()).max((a - c).norm());
            // Height over the longest side: a sliver is as bad as a zero area for a slicer.
            assert!(
                2.0 * area / longest > 1e-3,
                "triangle {i} is degenerate: area {area} mm², longest side {longest} mm"
            );
        }
    }

    /// Independent model of the union: inside the solid (all 12 face planes), or inside the
    /// prism under the centroid (regular N-gon with a corner on a bottom edge's azimuth).
    struct Union {
        planes: Vec<(Vector3<f64>, f64)>,
        /// The three planes whose normals point down the most: the faces round the −Z vertex.
        bottom: Vec<(Vector3<f64>, f64)>,
        r: f64,
        n: usize,
        theta0: f64,
        z_end: f64,
    }

    impl Union {
        fn new(kind: SolidKind, edge: f64, params: &HarnessParams) -> Union {
            let d = Solid::new(kind, edge);
            let planes: Vec<(Vector3<f64>, f64)> =
                d.faces().iter().map(|f| (f.normal, f.normal.dot(&f.center))).collect();
            let mut bottom = planes.clone();
            bottom.sort_by(|a, b| a.0.z.total_cmp(&b.0.z));
            bottom.truncate(3);
            let low = d.vertices().iter().copied().min_by(|a, b| a.z.total_cmp(&b.z)).expect("vertices");
            let nb = d.vertices().iter().find(|v| ((*v - low).norm() - edge).abs() < 1e-9).expect("a neighbour");
            Union {
                planes,
                bottom,
                r: params.post_diameter / 2.0,
                n: params.post_segments,
                theta0: nb.y.atan2(nb.x),
                z_end: low.z - params.post_length,
            }
        }

        /// Whether (x, y) is inside the N-gon: within the chord of the side its azimuth falls on.
        fn in_ngon(&self, x: f64, y: f64) -> bool {
            let step = TAU / self.n as f64;
            let phi = (y.atan2(x) - self.theta0).rem_euclid(TAU);
            let side = (phi / step).floor();
            let mid = (side + 0.5) * step;
            x.hypot(y) * (phi - mid).cos() <= self.r * (step / 2.0).cos()
        }

        fn contains(&self, p: &Vector3<f64>) -> bool {
            let in_solid = self.planes.iter().all(|(n, d)| n.dot(p) <= *d);
            let in_post = p.z >= self.z_end && p.z <= 0.0 && self.in_ngon(p.x, p.y);
            in_solid || in_post
        }

        /// Height of the solid's lower surface over (x, y) near the −Z vertex: the highest of
        /// the three bottom planes.
        fn lower_surface(&self, x: f64, y: f64) -> f64 {
            self.bottom.iter().map(|(n, d)| (d - n.x * x - n.y * y) / n.z).fold(f64::NEG_INFINITY, f64::max)
        }
    }

    #[test]
    fn the_mesh_is_a_closed_outward_manifold_without_slivers() {
        for params in [
            HarnessParams::default(),
            HarnessParams { post_segments: 3, ..HarnessParams::default() },
            HarnessParams { post_segments: 6, post_diameter: 7.0, post_length: 3.0 },
            HarnessParams { post_segments: 99, post_diameter: 0.5, post_length: 60.0 },
        ] {
            let m = body_mesh(SolidKind::Dodecahedron, DEFAULT_EDGE_MM, default_tag_size(DEFAULT_EDGE_MM), &params)
                .expect("fits");
            assert_closed_manifold(&m);
            assert_no_degenerate_triangles(&m);
            assert_eq!(m.triangles.len(), 36 + 4 * params.post_segments);
            assert!(m.volume() > 0.0);
        }
    }

    /// No internal faces, and every normal points out: just off each triangle's centroid along
    /// its normal is outside the union, just behind it is inside.
    fn assert_on_the_surface(m: &Mesh, u: &Union) {
        for i in 0..m.triangles.len() {
            let [a, b, c] = m.corners(i).map(v3);
            let centroid = (a + b + c) / 3.0;
            let n = m.area_normal(i).normalize();
            assert!(!u.contains(&(centroid + n * 1e-6)), "triangle {i}: outside side is inside the union");
            assert!(u.contains(&(centroid - n * 1e-6)), "triangle {i}: inside side is outside the union");
        }
    }

    #[test]
    fn every_triangle_lies_on_the_union_s_surface_facing_out() {
        let params = HarnessParams::default();
        let m = default_mesh();
        let u = Union::new(SolidKind::Dodecahedron, DEFAULT_EDGE_MM, &params);
        assert_on_the_surface(&m, &u);
    }

    #[test]
    fn volume_is_the_solid_plus_the_post_below_it() {
        for params in
            [HarnessParams::default(), HarnessParams { post_segments: 12, post_diameter: 6.0, post_length: 10.0 }]
        {
            let edge = DEFAULT_EDGE_MM;
            let m = body_mesh(SolidKind::Dodecahedron, edge, default_tag_size(edge), &params).expect("fits");
            let u = Union::new(SolidKind::Dodecahedron, edge, &params);
            let apex_z = u.z_end + params.post_length;
            // Prism from the vertex down: N-gon area × length, in closed form.
            let n = params.post_segments as f64;
            let r = params.post_diameter / 2.0;
            let prism = 0.5 * n * r * r * (TAU / n).sin() * params.post_length;
            // The part between the vertex's height and the lower surface, integrated on a grid
            // (midpoint rule, 2000 cells across).
            let h = r / 1000.0;
            let cells = (2.0 * r / h).ceil() as i64;
            let mut cone = 0.0;
            for i in 0..cells {
                let x = -r + (i as f64 + 0.5) * h;
                for j in 0..cells {
                    let y = -r + (j as f64 + 0.5) * h;
                    if u.in_ngon(x, y) {
                        cone += (u.lower_surface(x, y) - apex_z) * h * h;
                    }
                }
            }
            let solid = Solid::new(SolidKind::Dodecahedron, edge).volume();
            let expected = solid + prism + cone;
            let got = m.volume();
            let post_got = got - solid;
            let post_expected = prism + cone;
            eprintln!(
                "N={} d={} L={}: mesh {got:.6} mm³, expected {expected:.6} mm³ (solid {solid:.6} + prism {prism:.6} + \
                 cone {cone:.6}); total rel. error {:.2e}, post part rel. error {:.2e}",
                params.post_segments,
                params.post_diameter,
                params.post_length,
                (got - expected).abs() / expected,
                (post_got - post_expected).abs() / post_expected
            );
            assert!((got - expected).abs() < 1e-3 * expected, "total volume {got} vs {expected}");
            // The post alone must agree to 0.1 % too, so a lost cone or cap would show.
            assert!(
                (post_got - post_expected).abs() < 1e-3 * post_expected,
                "post volume {post_got} vs {post_expected}"
            );
        }
    }

    #[test]
    fn the_post_leaves_the_minus_z_vertex_of_faces_9_10_11() {
        let solid = Solid::new(SolidKind::Dodecahedron, DEFAULT_EDGE_MM);
        let layout = PostLayout::new(&solid, 48).expect("layout");
        let mut faces: Vec<usize> = layout.bottom.iter().map(|b| b.face).collect();
        faces.sort_unstable();
        assert_eq!(faces, [9, 10, 11]);
        assert!((layout.apex.z + solid.circumradius()).abs() < 1e-9);
        // The −Z vertex is each bottom face's apex (the mirror plane through Z passes through it).
        assert!(layout.bottom.iter().all(|b| b.at == 0));
        let m = default_mesh();
        let lowest = m.vertices.iter().map(|v| v.z).fold(f64::INFINITY, f64::min);
        assert!((lowest - (layout.apex.z - 25.0)).abs() < 1e-9, "the end cap is 25 mm below the vertex");
    }

    #[test]
    fn a_cube_body_is_a_closed_manifold_on_the_union_of_cube_and_post() {
        let edge = DEFAULT_EDGE_MM;
        let size = jawtrack_marker::default_tag_size_of(SolidKind::Cube, &TagFamily::TAG36H11, edge);
        let max = max_post_diameter(SolidKind::Cube, edge, size, 48).expect("valid");
        eprintln!("cube of {edge} mm, {size:.3} mm tags: the post may be up to {max:.3} mm across");
        assert!(max > 1.0 && max < edge, "{max}");
        let params = HarnessParams { post_diameter: 0.9 * max, ..HarnessParams::default() };
        let m = body_mesh(SolidKind::Cube, edge, size, &params).expect("fits");
        assert_closed_manifold(&m);
        assert_no_degenerate_triangles(&m);
        // Six squares fanned into two triangles each, the notches adding one per ring corner,
        // and the post's walls and cap: F·(sides − 2) + 4N.
        assert_eq!(m.triangles.len(), 6 * 2 + 4 * params.post_segments);
        let u = Union::new(SolidKind::Cube, edge, &params);
        assert_on_the_surface(&m, &u);
        let post = m.volume() - edge.powi(3);
        assert!(post > 0.0 && post < params.post_diameter.powi(2) * (params.post_length + edge), "{post}");
        let layout = PostLayout::new(&Solid::new(SolidKind::Cube, edge), 48).expect("layout");
        let mut faces: Vec<usize> = layout.bottom.iter().map(|b| b.face).collect();
        faces.sort_unstable();
        assert_eq!(faces, [3, 4, 5], "the post leaves the −Z vertex of the lower ring");
        let err = body_mesh(SolidKind::Cube, edge, size, &HarnessParams { post_diameter: 1.05 * max, ..params })
            .expect_err("too thick");
        assert!(err.to_string().contains("post_diameter"), "{err}");
    }

    #[test]
    fn the_stl_reads_back_with_the_same_triangles() {
        let m = default_mesh();
        let mut bytes = Vec::new();
        m.write_stl(&mut bytes).expect("write to memory");
        assert_eq!(&bytes[80..84], &(m.triangles.len() as u32).to_le_bytes());
        let back = stl_io::read_stl(&mut std::io::Cursor::new(bytes)).expect("reads back");
        assert_eq!(back.faces.len(), m.triangles.len());
        assert_eq!(back.vertices.len(), m.vertices.len(), "no vertices merged or split in single precision");
        back.validate().expect("stl_io finds it closed, consistently wound, without zero-area faces");
        for (i, f) in back.faces.iter().enumerate() {
            let n = m.area_normal(i).normalize();
            let stored = Vector3::new(f.normal[0] as f64, f.normal[1] as f64, f.normal[2] as f64);
            assert!((stored - n).norm() < 1e-6, "stored normal agrees with the winding");
        }
    }

    #[test]
    fn bad_parameters_name_what_is_wrong() {
        let size = default_tag_size(DEFAULT_EDGE_MM);
        let base = HarnessParams::default();
        for (edge, size, params, word) in [
            (DEFAULT_EDGE_MM, size, HarnessParams { post_length: -1.0, ..base }, "post_length"),
            (DEFAULT_EDGE_MM, size, HarnessParams { post_length: f64::NAN, ..base }, "post_length"),
            (DEFAULT_EDGE_MM, size, HarnessParams { post_diameter: 0.0, ..base }, "post_diameter"),
            (DEFAULT_EDGE_MM, size, HarnessParams { post_diameter: f64::NAN, ..base }, "post_diameter"),
            (DEFAULT_EDGE_MM, size, HarnessParams { post_segments: 50, ..base }, "post_segments"),
            (f64::NAN, size, base, "edge"),
            (-3.0, size, base, "edge"),
            (DEFAULT_EDGE_MM, -1.0, base, "tag size"),
        ] {
            let err = body_mesh(SolidKind::Dodecahedron, edge, size, &params).expect_err("invalid").to_string();
            assert!(err.contains(word), "{err}");
        }
    }

    #[test]
    fn a_post_too_thick_names_the_tag_it_would_cover() {
        let size = default_tag_size(DEFAULT_EDGE_MM);
        let max = max_post_diameter(SolidKind::Dodecahedron, DEFAULT_EDGE_MM, size, 48).expect("valid");
        assert!(max > 4.0 && max < 12.0, "{max}");
        assert!(
            body_mesh(
                SolidKind::Dodecahedron,
                DEFAULT_EDGE_MM,
                size,
                &HarnessParams { post_diameter: max * 0.999, ..Default::default() }
            )
            .is_ok()
        );
        let err = body_mesh(
            SolidKind::Dodecahedron,
            DEFAULT_EDGE_MM,
            size,
            &HarnessParams { post_diameter: max * 1.05, ..Default::default() },
        )
        .expect_err("too thick");
        match &err {
            HarnessError::PostCoversTag { face, maxilla_id, mandible_id, depth, max_diameter, .. } => {
                assert!((9..12).contains(face));
                assert_eq!((*maxilla_id, *mandible_id), (*face as u32, *face as u32 + 12));
                assert!(*depth > 0.0 && *depth < 1.0, "{depth}");
                assert!((max_diameter - max).abs() < 1e-9);
            }
            other => panic!("expected PostCoversTag, got {other}"),
        }
        let text = err.to_string();
        assert!(text.contains("post_diameter") && text.contains("black square") && text.contains("maxilla"), "{text}");
    }

    #[test]
    fn a_post_wider_than_the_face_is_refused_even_with_small_tags() {
        // With a small tag the face itself is the limit.
        let err = body_mesh(
            SolidKind::Dodecahedron,
            DEFAULT_EDGE_MM,
            2.0,
            &HarnessParams { post_diameter: 40.0, ..Default::default() },
        )
        .expect_err("too wide");
        assert!(matches!(err, HarnessError::PostTooWide { .. }), "{err}");
        assert!(err.to_string().contains("post_diameter"), "{err}");
        let max = max_post_diameter(SolidKind::Dodecahedron, DEFAULT_EDGE_MM, 2.0, 48).expect("valid");
        assert!(
            body_mesh(
                SolidKind::Dodecahedron,
                DEFAULT_EDGE_MM,
                2.0,
                &HarnessParams { post_diameter: 0.99 * max, ..Default::default() }
            )
            .is_ok()
        );
    }

    #[test]
    fn penetration_of_squares() {
        let sq = |x: f64, y: f64| {
            vec![Vector2::new(x, y), Vector2::new(x + 1.0, y), Vector2::new(x + 1.0, y + 1.0), Vector2::new(x, y + 1.0)]
        };
        assert!((penetration(&sq(0.0, 0.0), &sq(0.75, 0.5)) - 0.25).abs() < 1e-12);
        assert!(penetration(&sq(0.0, 0.0), &sq(1.5, 0.0)) < 0.0);
        assert!(penetration(&sq(0.0, 0.0), &sq(1.0, 0.0)).abs() < 1e-12);
    }
}
