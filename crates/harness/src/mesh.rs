//! An indexed triangle mesh (mm) and its binary STL output.

use std::io::Write;

/// A triangle mesh: shared vertices and triangles indexing them, each triangle
/// counter-clockwise seen from outside (its right-hand normal points out of the solid).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Vertex positions (mm, body frame).
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Mesh {
    /// The three corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [[f64; 3]; 3] {
        self.triangles[i].map(|v| self.vertices[v as usize])
    }

    /// Twice the area vector of triangle `i` (right-hand normal, length = 2 × area).
    pub fn area_vector(&self, i: usize) -> [f64; 3] {
        let [a, b, c] = self.triangle(i);
        cross(sub(b, a), sub(c, a))
    }

    /// Enclosed volume (mm³) by the divergence theorem: the sum of the signed volumes of the
    /// tetrahedra joining the origin to each triangle. Positive for a closed mesh oriented
    /// outward.
    pub fn volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|i| {
                let [a, b, c] = self.triangle(i);
                dot(a, cross(b, c)) / 6.0
            })
            .sum()
    }

    /// Writes the mesh as binary STL (single-precision coordinates, unit facet normals).
    pub fn write_stl(&self, mut w: impl Write) -> std::io::Result<()> {
        let tris: Vec<stl_io::Triangle> = (0..self.triangles.len())
            .map(|i| {
                let n = self.area_vector(i);
                let len = dot(n, n).sqrt();
                // A zero-area triangle has no normal; readers recompute it from the winding anyway.
                let n = if len > 0.0 { n.map(|c| c / len) } else { [0.0; 3] };
                stl_io::Triangle {
                    normal: stl_io::Normal::new(n.map(|c| c as f32)),
                    vertices: self.triangle(i).map(|p| stl_io::Vertex::new(p.map(|c| c as f32))),
                }
            })
            .collect();
        stl_io::write_stl(&mut w, tris.iter())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube as 12 outward triangles.
    fn cube() -> Mesh {
        let vertices = (0..8).map(|i| [f64::from(i & 1), f64::from((i >> 1) & 1), f64::from((i >> 2) & 1)]).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        Mesh { vertices, triangles }
    }

    #[test]
    fn cube_volume_and_stl_round_trip() {
        let m = cube();
        assert!((m.volume() - 1.0).abs() < 1e-12);
        let mut bytes = Vec::new();
        m.write_stl(&mut bytes).expect("write to memory");
        assert_eq!(bytes.len(), 84 + 50 * 12);
        let back = stl_io::read_stl(&mut std::io::Cursor::new(bytes)).expect("reads back");
        assert_eq!(back.faces.len(), 12);
        back.validate().expect("closed");
    }
}
