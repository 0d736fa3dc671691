//! The regular dodecahedron in the body frame. This module is the only place that knows its
//! shape; everything else asks it.
//!
//! Body frame: origin at the centroid; +Z through one vertex (the one that faces the camera);
//! +X along the horizontal component of face 0's outward normal, so face 0 is one of the three
//! faces around the +Z vertex; Y = Z × X.
//!
//! Faces are numbered by height, then by azimuth: the outward normals fall into four rings of
//! three (around the +Z vertex, upper middle, lower middle, around the −Z vertex); within a
//! ring faces go counter-clockwise seen from +Z (from the camera), starting from the smallest
//! azimuth in [0°, 360°) measured from +X.
//!
//! Each face's vertices are listed counter-clockwise seen from outside, starting at its
//! *apex*: the face has a mirror plane containing the Z axis, which passes through exactly one
//! of its vertices (and the midpoint of the opposite edge); that vertex is the apex, and the
//! tag's +y axis points at it.

use nalgebra::{Rotation3, Unit, Vector3};

/// Dihedral angle between adjacent faces, arccos(−1/√5) in degrees (≈ 116.565°).
pub fn dihedral_angle_deg() -> f64 {
    (-1.0 / 5f64.sqrt()).acos().to_degrees()
}

/// One face of the dodecahedron.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Face {
    /// Face number, 0..12 (see the module doc for the order).
    pub index: usize,
    /// The five vertices (mm, body frame), counter-clockwise seen from outside, apex first.
    pub vertices: [Vector3<f64>; 5],
    /// Centre of the face (mm).
    pub center: Vector3<f64>,
    /// Outward unit normal.
    pub normal: Vector3<f64>,
    /// In-plane unit axis parallel to the edge opposite the apex; with `y` and `−normal` it
    /// forms the right-handed frame of an upright tag (x right, y down, z into the face).
    pub x_axis: Vector3<f64>,
    /// In-plane unit axis from the centre toward the apex.
    pub y_axis: Vector3<f64>,
}

impl Face {
    /// Distance from the face centre to each edge (the pentagon's inradius, mm).
    pub fn inradius(&self) -> f64 {
        (0.5 * (self.vertices[0] + self.vertices[1]) - self.center).norm()
    }

    /// The outward in-plane unit normals of the five edges, edge i joining vertex i and i+1.
    pub fn edge_normals(&self) -> [Vector3<f64>; 5] {
        std::array::from_fn(|i| {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % 5];
            (b - a).cross(&self.normal).normalize()
        })
    }

    /// Signed distance (mm) from an in-plane point to the pentagon's boundary: positive inside.
    pub fn distance_inside(&self, p: &Vector3<f64>) -> f64 {
        self.edge_normals().iter().enumerate().map(|(i, n)| (self.vertices[i] - p).dot(n)).fold(f64::INFINITY, f64::min)
    }
}

/// A regular dodecahedron of a given edge length, in the body frame of the module doc.
#[derive(Debug, Clone, PartialEq)]
pub struct Dodecahedron {
    edge: f64,
    vertices: [Vector3<f64>; 20],
    faces: [Face; 12],
}

impl Dodecahedron {
    /// Builds the solid; `edge` must be positive and finite (checked by the caller's API).
    pub fn new(edge: f64) -> Self {
        let phi = (1.0 + 5f64.sqrt()) / 2.0;
        // Canonical coordinates have edge 2/φ.
        let scale = edge * phi / 2.0;
        let mut canon: Vec<Vector3<f64>> = Vec::with_capacity(20);
        for &sx in &[-1.0, 1.0] {
            for &sy in &[-1.0, 1.0] {
                for &sz in &[-1.0, 1.0] {
                    canon.push(Vector3::new(sx, sy, sz));
                }
            }
        }
        for &a in &[-1.0, 1.0] {
            for &b in &[-1.0, 1.0] {
                canon.push(Vector3::new(0.0, a / phi, b * phi));
                canon.push(Vector3::new(a / phi, b * phi, 0.0));
                canon.push(Vector3::new(a * phi, 0.0, b / phi));
            }
        }
        let mut face_normals: Vec<Vector3<f64>> = Vec::with_capacity(12);
        for &a in &[-1.0, 1.0] {
            for &b in &[-1.0, 1.0] {
                face_normals.push(Vector3::new(0.0, a * phi, b).normalize());
                face_normals.push(Vector3::new(a, 0.0, b * phi).normalize());
                face_normals.push(Vector3::new(a * phi, b, 0.0).normalize());
            }
        }

        // Turn vertex (1,1,1) onto +Z.
        let to_z = Rotation3::rotation_between(&Vector3::new(1.0, 1.0, 1.0), &Vector3::z())
            .unwrap_or_else(Rotation3::identity);
        let canon: Vec<Vector3<f64>> = canon.iter().map(|v| to_z * v * scale).collect();
        let mut normals: Vec<Vector3<f64>> = face_normals.iter().map(|n| to_z * n).collect();

        // Rings by normal height (four distinct values), highest first.
        let ring = |n: &Vector3<f64>| -> i32 { (-n.z * 4.0).round() as i32 };
        // Fix X: the highest faces all have the same height; take the one with the smallest
        // azimuth as face 0 and turn it onto +X.
        normals.sort_by(|a, b| b.z.total_cmp(&a.z));
        let az0 = normals[0].y.atan2(normals[0].x);
        let yaw = Rotation3::from_axis_angle(&Vector3::z_axis(), -az0);
        let vertices_vec: Vec<Vector3<f64>> = canon.iter().map(|v| yaw * v).collect();
        let mut normals: Vec<Vector3<f64>> = normals.iter().map(|n| yaw * n).collect();
        let azimuth = |n: &Vector3<f64>| {
            let a = n.y.atan2(n.x);
            // Snap tiny negatives (face 0 sits on +X) so it sorts first, not last.
            if a < -1e-9 { a + std::f64::consts::TAU } else { a.max(0.0) }
        };
        normals.sort_by(|a, b| ring(a).cmp(&ring(b)).then(azimuth(a).total_cmp(&azimuth(b))));

        let vertices: [Vector3<f64>; 20] = std::array::from_fn(|i| vertices_vec[i]);
        let faces: [Face; 12] = std::array::from_fn(|index| Self::make_face(index, normals[index], &vertices));
        Dodecahedron { edge, vertices, faces }
    }

    fn make_face(index: usize, normal: Vector3<f64>, vertices: &[Vector3<f64>; 20]) -> Face {
        let dmax = vertices.iter().map(|v| v.dot(&normal)).fold(f64::NEG_INFINITY, f64::max);
        let mut ring: Vec<Vector3<f64>> =
            vertices.iter().filter(|v| (v.dot(&normal) - dmax).abs() < 1e-9 * dmax.abs().max(1.0)).copied().collect();
        debug_assert_eq!(ring.len(), 5);
        let center = ring.iter().sum::<Vector3<f64>>() / 5.0;
        // The mirror plane through Z meets the face along the projection of Z.
        let up = Unit::new_normalize(Vector3::z() - normal * normal.z);
        let apex_score = |v: &Vector3<f64>| {
            let d = (v - center).normalize();
            d.dot(&up).abs()
        };
        let apex = ring.iter().copied().max_by(|a, b| apex_score(a).total_cmp(&apex_score(b))).unwrap_or(ring[0]);
        let y_axis = (apex - center).normalize();
        let x_axis = normal.cross(&y_axis);
        // Counter-clockwise seen from outside = increasing angle about the outward normal.
        let angle = |v: &Vector3<f64>| {
            let d = v - center;
            // From the apex, turning from +y toward +x: x = n × y, so this is a positive turn
            // about the outward normal.
            let a = d.dot(&x_axis).atan2(d.dot(&y_axis));
            if a < -1e-12 { a + std::f64::consts::TAU } else { a.max(0.0) }
        };
        ring.sort_by(|a, b| angle(a).total_cmp(&angle(b)));
        Face { index, vertices: std::array::from_fn(|i| ring[i]), center, normal, x_axis, y_axis }
    }

    /// Edge length (mm).
    pub fn edge(&self) -> f64 {
        self.edge
    }

    /// The 20 vertices (mm).
    pub fn vertices(&self) -> &[Vector3<f64>; 20] {
        &self.vertices
    }

    /// The 12 faces in the documented order.
    pub fn faces(&self) -> &[Face; 12] {
        &self.faces
    }

    /// Distance from the centroid to each vertex (mm).
    pub fn circumradius(&self) -> f64 {
        self.edge * 3f64.sqrt() * (1.0 + 5f64.sqrt()) / 4.0
    }

    /// Distance from the centroid to each face (mm).
    pub fn inradius(&self) -> f64 {
        self.edge * 0.5 * (2.5 + 1.1 * 5f64.sqrt()).sqrt()
    }

    /// Volume (mm³): (15 + 7√5)/4 · a³.
    pub fn volume(&self) -> f64 {
        (15.0 + 7.0 * 5f64.sqrt()) / 4.0 * self.edge.powi(3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solid() -> Dodecahedron {
        Dodecahedron::new(12.7)
    }

    #[test]
    fn edges_all_have_the_given_length() {
        let d = solid();
        for f in d.faces() {
            for i in 0..5 {
                let len = (f.vertices[(i + 1) % 5] - f.vertices[i]).norm();
                assert!((len - 12.7).abs() < 1e-9, "face {} edge {i}: {len}", f.index);
            }
        }
        // 30 distinct edges, each of the given length: count vertex pairs at edge distance.
        let v = d.vertices();
        let n = (0..20)
            .flat_map(|i| (i + 1..20).map(move |j| (i, j)))
            .filter(|&(i, j)| ((v[i] - v[j]).norm() - 12.7).abs() < 1e-9)
            .count();
        assert_eq!(n, 30);
    }

    #[test]
    fn faces_are_planar_and_at_the_inradius() {
        let d = solid();
        for f in d.faces() {
            for v in &f.vertices {
                assert!(((v - f.center).dot(&f.normal)).abs() < 1e-12);
            }
            assert!((f.center.norm() - d.inradius()).abs() < 1e-9);
            assert!((f.center.normalize() - f.normal).norm() < 1e-12);
        }
        for v in d.vertices() {
            assert!((v.norm() - d.circumradius()).abs() < 1e-9);
        }
    }

    #[test]
    fn dihedral_angle_is_116_565() {
        assert!((dihedral_angle_deg() - 116.565).abs() < 1e-3);
        let d = solid();
        // Faces sharing an edge have normals 180° − dihedral apart.
        let mut adjacent = 0;
        for a in d.faces() {
            for b in d.faces() {
                let shared = a.vertices.iter().filter(|v| b.vertices.iter().any(|w| (*v - w).norm() < 1e-9)).count();
                if a.index < b.index && shared == 2 {
                    adjacent += 1;
                    let between = a.normal.angle(&b.normal).to_degrees();
                    assert!((180.0 - between - dihedral_angle_deg()).abs() < 1e-9);
                }
            }
        }
        assert_eq!(adjacent, 30);
    }

    #[test]
    fn body_frame_and_face_order_are_as_documented() {
        let d = solid();
        let top = d.vertices().iter().copied().max_by(|a, b| a.z.total_cmp(&b.z)).expect("20 vertices");
        assert!(top.x.abs() < 1e-9 && top.y.abs() < 1e-9 && (top.z - d.circumradius()).abs() < 1e-9);
        let f = d.faces();
        assert!(f[0].normal.y.abs() < 1e-12 && f[0].normal.x > 0.0, "face 0 normal on +X: {:?}", f[0].normal);
        // Rings of three, descending in height; azimuth increasing within a ring.
        for r in 0..4 {
            let ring = &f[3 * r..3 * r + 3];
            assert!((ring[0].normal.z - ring[2].normal.z).abs() < 1e-9);
            if r > 0 {
                assert!(f[3 * r - 1].normal.z > ring[0].normal.z + 0.1);
            }
            let az: Vec<f64> =
                ring.iter().map(|x| x.normal.y.atan2(x.normal.x).rem_euclid(std::f64::consts::TAU)).collect();
            assert!(az[0] < az[1] && az[1] < az[2], "ring {r}: {az:?}");
        }
        // The three faces around the top vertex each have it as their apex.
        for face in &f[0..3] {
            assert!((face.vertices[0] - top).norm() < 1e-9);
        }
    }

    #[test]
    fn face_frames_are_right_handed_and_vertices_counter_clockwise() {
        for f in solid().faces() {
            assert!((f.x_axis.cross(&f.y_axis) + f.normal).norm() < 1e-12, "x × y = −n");
            assert!((f.vertices[0] - f.center).normalize().dot(&f.y_axis) > 1.0 - 1e-12, "apex on +y");
            for i in 0..5 {
                let a = f.vertices[i] - f.center;
                let b = f.vertices[(i + 1) % 5] - f.center;
                assert!(a.cross(&b).dot(&f.normal) > 0.0, "face {} counter-clockwise from outside", f.index);
            }
            // The edge opposite the apex (vertices 2 and 3) is parallel to x.
            let opp = (f.vertices[3] - f.vertices[2]).normalize();
            assert!(opp.cross(&f.x_axis).norm() < 1e-12);
        }
    }

    #[test]
    fn volume_formula_matches_the_polyhedron() {
        let d = solid();
        // Divergence theorem over the faces (fan triangulation).
        let vol: f64 = d
            .faces()
            .iter()
            .flat_map(|f| (1..4).map(move |i| (f.vertices[0], f.vertices[i], f.vertices[i + 1])))
            .map(|(a, b, c)| a.dot(&b.cross(&c)) / 6.0)
            .sum();
        assert!((vol - d.volume()).abs() < 1e-9 * d.volume());
    }
}
