//! [`Surface`]: a mesh's triangles prepared for distance queries. Each triangle's plane and
//! corners sit side by side in two cache lines, with the bend of the surface around it; beside
//! them, the triangles sharing a corner with each, and the pseudo-normals of its edges and
//! corners that give an answer its sign.

use super::Nearest;
use super::bend::bend_towards;
use super::triangle::{Feature, closest_on_triangle};
use crate::Mesh;
use nalgebra::{Point3, Vector3};

/// Per-triangle data for the sign where the nearest point is on an edge or a corner: their
/// pseudo-normals (the face's normal is its plane's).
#[derive(Debug, Clone)]
struct Tri {
    /// Edges ab, bc, ca.
    edges: [Vector3<f64>; 3],
    vertices: [Vector3<f64>; 3],
    /// Whether each edge, and each corner, lies on the scan's rim.
    rim_edges: [bool; 3],
    rim_vertices: [bool; 3],
}

/// What a nearest-point search reads of a triangle, in two cache lines: its plane (unit
/// normal, offset along it), since no point of the triangle is nearer to a point than the
/// plane is, which rules out most neighbours in a descent; then its corners.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub(super) struct Geometry {
    pub(super) plane: [f64; 4],
    pub(super) corners: [Point3<f64>; 3],
    /// Per side of the plane (front, behind), how steeply the triangles around rise towards
    /// that side, as a slope over the distance beyond this triangle
    /// ([`bend_towards`]; 0 where the surface is convex from that side, infinite where it
    /// folds over): rounded up, and small, to fit in the padding of the second cache line.
    pub(super) bend: [f32; 2],
    /// The inverse lengths of the edges ab, bc, ca, rounded down.
    pub(super) inverse_edges: [f32; 3],
    /// Its index in the mesh: answers name the mesh's own triangles.
    original: u32,
}

// Two cache lines, no more.
const _: () = assert!(std::mem::size_of::<Geometry>() == 128);

/// Precomputed triangles with their pseudo-normals.
#[derive(Debug, Clone)]
pub struct Surface {
    /// Per triangle, what a search reads: its plane and corners, side by side.
    pub(super) geometry: Vec<Geometry>,
    tris: Vec<Tri>,
    /// Per triangle, the triangles sharing a corner with it (CSR).
    neighbour_starts: Vec<u32>,
    neighbours: Vec<u32>,
}

impl Surface {
    /// Prepares `mesh` for distance queries.
    pub fn new(mesh: &Mesh) -> Self {
        // Triangles are held in Z-order of their centres, so that a query's candidates, and
        // successive queries', sit together in memory; answers give the mesh's own indices.
        let centres: Vec<Point3<f64>> = (0..mesh.triangles.len())
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                Point3::from((a.coords + b.coords + c.coords) / 3.0)
            })
            .collect();
        let original = crate::z_order(&centres, 0.5);
        let reordered = Mesh {
            vertices: mesh.vertices.clone(),
            triangles: original.iter().map(|&t| mesh.triangles[t as usize]).collect(),
        };
        let mesh = &reordered;
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
                    edges: [0, 1, 2].map(|k| unit(edge(k).0, faces[t])),
                    vertices: tri.map(|v| unit(vertex_normals[v as usize], faces[t])),
                    rim_edges: [0, 1, 2].map(|k| edge(k).1 == 1),
                    rim_vertices: tri.map(|v| rim_vertex[v as usize]),
                }
            })
            .collect();
        let (neighbour_starts, neighbours) = corner_neighbours(mesh);
        let geometry = (0..n)
            .map(|t| {
                let (corners, face) = (mesh.corners(t), faces[t]);
                let around = &neighbours[neighbour_starts[t] as usize..neighbour_starts[t + 1] as usize];
                let around: Vec<[u32; 3]> = around.iter().map(|&k| mesh.triangles[k as usize]).collect();
                let bend = |side: f64| {
                    let b = bend_towards(&corners, face * side, mesh.triangles[t], &around, &mesh.vertices);
                    let rounded = b as f32;
                    if f64::from(rounded) < b { rounded.next_up() } else { rounded }
                };
                let inverse_edges = [0, 1, 2].map(|k| {
                    let inverse = 1.0 / (corners[(k + 1) % 3] - corners[k]).norm();
                    let rounded = inverse as f32;
                    if !inverse.is_finite() {
                        0.0
                    } else if f64::from(rounded) > inverse {
                        rounded.next_down()
                    } else {
                        rounded
                    }
                });
                Geometry {
                    plane: [face.x, face.y, face.z, face.dot(&corners[0].coords)],
                    corners,
                    bend: [bend(1.0), bend(-1.0)],
                    inverse_edges,
                    original: original[t],
                }
            })
            .collect();
        Surface { geometry, tris, neighbour_starts, neighbours }
    }

    /// The triangles sharing a corner with triangle `t`.
    pub(super) fn neighbours(&self, t: usize) -> &[u32] {
        &self.neighbours[self.neighbour_starts[t] as usize..self.neighbour_starts[t + 1] as usize]
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
    pub(super) fn closest(&self, t: usize, p: &Point3<f64>) -> (f64, Point3<f64>, Feature) {
        let (c, f) = closest_on_triangle(p, &self.geometry[t].corners);
        ((p - c).norm_squared(), c, f)
    }

    /// Whether triangle `t` is certainly farther from `p` than `d2` (squared), judged by its
    /// plane.
    pub(super) fn beyond_plane(&self, t: usize, p: &Point3<f64>, d2: f64) -> bool {
        let [x, y, z, offset] = self.geometry[t].plane;
        let s = x * p.x + y * p.y + z * p.z - offset;
        s * s > d2
    }

    /// The signed result for triangle `t` given its closest point and feature.
    pub(super) fn signed(&self, t: usize, p: &Point3<f64>, d2: f64, c: Point3<f64>, f: Feature) -> Nearest {
        // Most nearest points are inside a face, whose normal is at hand in its plane.
        let g = &self.geometry[t];
        let (normal, on_rim) = match f {
            Feature::Face => (Vector3::new(g.plane[0], g.plane[1], g.plane[2]), false),
            Feature::Edge(k) => (self.tris[t].edges[k], self.tris[t].rim_edges[k]),
            Feature::Vertex(k) => (self.tris[t].vertices[k], self.tris[t].rim_vertices[k]),
        };
        let d = d2.sqrt();
        let offset = p - c;
        let along = offset.dot(&normal);
        // Past the rim of an open scan there is no inside: a point whose nearest surface point
        // is on the rim and lies off to the side of it is outside.
        let beside_rim = on_rim && (offset - normal * along).norm() > 1e-9;
        let sign = if along < 0.0 && !beside_rim { -1.0 } else { 1.0 };
        Nearest { distance: sign * d, point: c, triangle: g.original, normal }
    }
}

/// Per triangle, the other triangles sharing a corner with it, as (starts, items).
fn corner_neighbours(mesh: &Mesh) -> (Vec<u32>, Vec<u32>) {
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); mesh.vertices.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        tri.iter().for_each(|&v| around[v as usize].push(t as u32));
    }
    let (mut starts, mut items) = (vec![0u32], Vec::new());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let begin = items.len();
        for &v in tri {
            items.extend(around[v as usize].iter().copied().filter(|&n| n != t as u32));
        }
        items[begin..].sort_unstable();
        let mut unique = begin;
        for k in begin..items.len() {
            if unique == begin || items[k] != items[unique - 1] {
                items[unique] = items[k];
                unique += 1;
            }
        }
        items.truncate(unique);
        starts.push(items.len() as u32);
    }
    (starts, items)
}
