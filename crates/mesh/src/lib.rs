//! The one triangle mesh of JawTrack, in millimetres: tooth scans read by
//! `jawtrack-occlusion` and `jawtrack-registration` and the printable marker body built by
//! `jawtrack-harness` are all a [`Mesh`].
//!
//! - this file: the [`Mesh`] type and its geometry (corners, area normals, area, volume,
//!   bounds, transforms, concatenation, Z-order);
//! - `read`: [`Mesh::load`], STL (binary and ASCII), PLY and OBJ through their crates;
//! - `check`: [`Mesh::validate`] (empty, non-finite, badly indexed, not millimetre-sized) and
//!   [`Mesh::report`] (degenerate triangles, non-manifold and boundary edges, boundary loops,
//!   components);
//! - `write`: binary STL to any writer ([`Mesh::write_stl`]) or file, vertex-coloured PLY;
//! - `error`: [`MeshError`], why a mesh could not be read, written or used;
//! - [`distance`]: exact signed distances from points to a mesh's surface, within a reach
//!   (the contact queries of `jawtrack-occlusion`, the marker-to-scan ICP of
//!   `jawtrack-registration`);
//! - [`scenes`]: test meshes with known answers, and synthetic arches for benchmarks.

mod check;
pub mod distance;
mod error;
mod read;
pub mod scenes;
mod write;

pub use check::{DisjointSets, MeshReport, PLAUSIBLE_EXTENT_MM};
pub use error::MeshError;
pub use read::MeshFormat;

use nalgebra::{Point3, Vector3};

/// An indexed triangle mesh (mm). Triangles wind counter-clockwise seen from outside, so
/// their right-hand normals point out of the solid (the tooth, the marker body).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Vertex positions (mm).
    pub vertices: Vec<Point3<f64>>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// The axis-aligned bounding box (min, max).
    pub fn bounds(&self) -> [Vector3<f64>; 2] {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for v in &self.vertices {
            lo = lo.inf(&v.coords);
            hi = hi.sup(&v.coords);
        }
        [lo, hi]
    }

    /// The vertex indices in Z-order of `cell`-mm cells: consecutive vertices in this order
    /// are near each other, so queries made in it reuse what the cache already holds
    /// whatever order the scanner wrote them in.
    pub fn spatial_order(&self, cell: f64) -> Vec<u32> {
        z_order(&self.vertices, cell)
    }

    /// The three corners of triangle `t`.
    pub fn corners(&self, t: usize) -> [Point3<f64>; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Twice-area normal of triangle `t`: (b − a) × (c − a), the right-hand normal whose
    /// length is twice the area (not normalised; zero for a degenerate triangle).
    pub fn area_normal(&self, t: usize) -> Vector3<f64> {
        let [a, b, c] = self.corners(t);
        (b - a).cross(&(c - a))
    }

    /// Surface area (mm²).
    pub fn area(&self) -> f64 {
        (0..self.triangles.len()).map(|t| self.area_normal(t).norm() / 2.0).sum()
    }

    /// Enclosed volume (mm³) by the divergence theorem: the sum of the signed volumes of the
    /// tetrahedra joining the origin to each triangle. Positive for a closed mesh oriented
    /// outward; meaningless for an open one (a scan).
    pub fn volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                a.coords.dot(&b.coords.cross(&c.coords)) / 6.0
            })
            .sum()
    }

    /// The mesh moved by `f`.
    pub fn transformed(&self, f: impl Fn(&Point3<f64>) -> Point3<f64>) -> Mesh {
        Mesh { vertices: self.vertices.iter().map(f).collect(), triangles: self.triangles.clone() }
    }

    /// Several meshes as one (indices shifted); also returns, per triangle, which part it came
    /// from.
    pub fn concat(parts: &[Mesh]) -> (Mesh, Vec<u16>) {
        let mut out = Mesh::default();
        let mut part_of = Vec::new();
        for (k, m) in parts.iter().enumerate() {
            let base = out.vertices.len() as u32;
            out.vertices.extend_from_slice(&m.vertices);
            out.triangles.extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
            part_of.extend(std::iter::repeat_n(k as u16, m.triangles.len()));
        }
        (out, part_of)
    }
}

/// The indices of `points` in Z-order (Morton order) of `cell`-mm cells.
pub fn z_order(points: &[Point3<f64>], cell: f64) -> Vec<u32> {
    let lo = points.iter().fold(Vector3::repeat(f64::INFINITY), |lo, p| lo.inf(&p.coords));
    let spread = |x: u64| {
        // Interleave the low 21 bits with two zero bits each.
        let mut x = x & 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    };
    let code = |p: &Point3<f64>| {
        let q = ((p.coords - lo) / cell.max(1e-9)).map(|x| x.max(0.0) as u64);
        spread(q.x) | spread(q.y) << 1 | spread(q.z) << 2
    };
    let mut keyed: Vec<(u64, u32)> = points.iter().enumerate().map(|(i, p)| (code(p), i as u32)).collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A unit cube as 12 outward triangles.
    pub(crate) fn cube() -> Mesh {
        let vertices =
            (0..8).map(|i| Point3::new(f64::from(i & 1), f64::from((i >> 1) & 1), f64::from((i >> 2) & 1))).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        Mesh { vertices, triangles }
    }

    #[test]
    fn cube_volume_area_and_outward_normals() {
        let m = cube();
        assert!((m.volume() - 1.0).abs() < 1e-12);
        assert!((m.area() - 6.0).abs() < 1e-12);
        let centre = Point3::new(0.5, 0.5, 0.5);
        for t in 0..m.triangles.len() {
            let [a, b, c] = m.corners(t);
            let centroid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            assert!(m.area_normal(t).dot(&(centroid - centre)) > 0.0, "triangle {t} faces in");
        }
        let moved = m.transformed(|p| p + Vector3::new(5.0, -2.0, 1.0));
        assert!((moved.volume() - 1.0).abs() < 1e-12, "the volume does not depend on the origin");
    }

    #[test]
    fn concat_shifts_indices_and_tells_the_parts() {
        let (m, part_of) = Mesh::concat(&[cube(), cube()]);
        assert_eq!((m.vertices.len(), m.triangles.len()), (16, 24));
        assert_eq!(m.triangles[12], cube().triangles[0].map(|i| i + 8));
        assert_eq!(part_of.iter().filter(|&&k| k == 1).count(), 12);
    }
}
