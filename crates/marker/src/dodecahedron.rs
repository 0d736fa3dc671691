//! The regular dodecahedron's canonical coordinates and angles. [`crate::solid`] turns them into
//! the body frame every solid shares; this module is the only place that knows the shape.

use nalgebra::Vector3;

/// Dihedral angle between adjacent faces, arccos(−1/√5) in degrees (≈ 116.565°).
pub fn dihedral_angle_deg() -> f64 {
    (-1.0 / 5f64.sqrt()).acos().to_degrees()
}

/// The 20 vertices and 12 outward face normals of the dodecahedron of edge 2/φ centred on the
/// origin, and the factor that scales it to `edge`.
pub(crate) fn canonical(edge: f64) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>, f64) {
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
    (canon, face_normals, scale)
}

/// Distance from the centroid to each vertex of a dodecahedron of this edge (mm).
pub(crate) fn circumradius(edge: f64) -> f64 {
    edge * 3f64.sqrt() * (1.0 + 5f64.sqrt()) / 4.0
}

/// Distance from the centroid to each face (mm).
pub(crate) fn inradius(edge: f64) -> f64 {
    edge * 0.5 * (2.5 + 1.1 * 5f64.sqrt()).sqrt()
}

/// Volume (mm³): (15 + 7√5)/4 · a³.
pub(crate) fn volume(edge: f64) -> f64 {
    (15.0 + 7.0 * 5f64.sqrt()) / 4.0 * edge.powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::solid::{Solid, SolidKind};

    fn solid() -> Solid {
        Solid::new(SolidKind::Dodecahedron, 12.7)
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
