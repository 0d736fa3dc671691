//! The solids a marker body can be: their faces in the body frame, the one frame every solid
//! shares. Harness, renderer, viewer and registration ask the marker for its [`Solid`] instead
//! of building a shape themselves; a new shape is a new [`SolidKind`] here (its canonical
//! vertices and face normals) and nothing else in this crate.
//!
//! Body frame: origin at the centroid; +Z through one vertex (the one that faces the camera);
//! +X along the horizontal component of face 0's outward normal, so face 0 is one of the faces
//! around the +Z vertex; Y = Z × X.
//!
//! Faces are numbered by height, then by azimuth: the outward normals fall into rings of three
//! (the dodecahedron has four: around the +Z vertex, upper middle, lower middle, around the −Z
//! vertex; the cube two: around the +Z and around the −Z vertex); within a ring faces go
//! counter-clockwise seen from +Z (from the camera), starting from the smallest azimuth in
//! [0°, 360°) measured from +X.
//!
//! Each face's vertices are listed counter-clockwise seen from outside, starting at its
//! *apex*, the vertex on the face's mirror plane that contains the Z axis. A pentagon has one
//! vertex on that plane (and the midpoint of the opposite edge); a square has two, and the
//! higher is its apex. The tag's +y axis points from the centre at the apex on a pentagon, and
//! at the middle of the edge from the apex to the next vertex on a square, so that a square tag
//! sits square with the square face.

use crate::dodecahedron;
use nalgebra::{Rotation3, Unit, Vector3};

/// The shape of a marker body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SolidKind {
    /// The regular dodecahedron: 12 pentagonal faces.
    Dodecahedron,
    /// The cube: 6 square faces, a body diagonal along Z.
    Cube,
}

impl SolidKind {
    /// Every solid this build knows.
    pub const ALL: [SolidKind; 2] = [SolidKind::Dodecahedron, SolidKind::Cube];

    /// The name used in marker files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SolidKind::Dodecahedron => "dodecahedron",
            SolidKind::Cube => "cube",
        }
    }

    /// The solid of a name, if this build knows it.
    pub fn from_name(name: &str) -> Option<SolidKind> {
        SolidKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Number of faces, and so of tags a body of this shape carries.
    pub fn face_count(self) -> usize {
        match self {
            SolidKind::Dodecahedron => 12,
            SolidKind::Cube => 6,
        }
    }

    /// What each face is, in words ("pentagon", "square").
    pub fn face_shape(self) -> &'static str {
        match self {
            SolidKind::Dodecahedron => "pentagon",
            SolidKind::Cube => "square",
        }
    }

    /// Vertices of each face.
    pub fn face_sides(self) -> usize {
        match self {
            SolidKind::Dodecahedron => 5,
            SolidKind::Cube => 4,
        }
    }
}

impl std::fmt::Display for SolidKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One face of a solid.
#[derive(Debug, Clone, PartialEq)]
pub struct Face {
    /// Face number (see the module doc for the order).
    pub index: usize,
    /// Its vertices (mm, body frame), counter-clockwise seen from outside, apex first.
    pub vertices: Vec<Vector3<f64>>,
    /// Centre of the face (mm).
    pub center: Vector3<f64>,
    /// Outward unit normal.
    pub normal: Vector3<f64>,
    /// In-plane unit axis; with `y` and `−normal` it forms the right-handed frame of an
    /// upright tag (x right, y down, z into the face). On a pentagon it is parallel to the
    /// edge opposite the apex.
    pub x_axis: Vector3<f64>,
    /// In-plane unit axis from the centre toward the apex (pentagon) or toward the middle of
    /// the edge leaving the apex (square).
    pub y_axis: Vector3<f64>,
}

impl Face {
    /// Distance from the face centre to each edge (the regular polygon's inradius, mm).
    pub fn inradius(&self) -> f64 {
        (0.5 * (self.vertices[0] + self.vertices[1]) - self.center).norm()
    }

    /// The outward in-plane unit normals of the edges, edge i joining vertex i and i+1.
    pub fn edge_normals(&self) -> Vec<Vector3<f64>> {
        let n = self.vertices.len();
        (0..n)
            .map(|i| {
                let a = self.vertices[i];
                let b = self.vertices[(i + 1) % n];
                (b - a).cross(&self.normal).normalize()
            })
            .collect()
    }

    /// Signed distance (mm) from an in-plane point to the polygon's boundary: positive inside.
    pub fn distance_inside(&self, p: &Vector3<f64>) -> f64 {
        self.edge_normals().iter().enumerate().map(|(i, n)| (self.vertices[i] - p).dot(n)).fold(f64::INFINITY, f64::min)
    }
}

/// A solid of a given kind and edge length, in the body frame of the module doc.
///
/// # Examples
///
/// ```
/// use jawtrack_marker::{Solid, SolidKind};
///
/// let cube = Solid::new(SolidKind::Cube, 10.0);
/// assert_eq!((cube.faces().len(), cube.vertices().len()), (6, 8));
/// assert!((cube.volume() - 1000.0).abs() < 1e-9);
/// // Every solid stands on a vertex: the camera looks down +Z at its top one.
/// let top = cube.vertices().iter().map(|v| v.z).fold(f64::MIN, f64::max);
/// assert!((top - cube.circumradius()).abs() < 1e-9);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Solid {
    kind: SolidKind,
    edge: f64,
    vertices: Vec<Vector3<f64>>,
    faces: Vec<Face>,
}

impl Solid {
    /// Builds the solid; `edge` must be positive and finite (checked by the caller's API).
    pub fn new(kind: SolidKind, edge: f64) -> Solid {
        let (canon, face_normals, scale) = match kind {
            SolidKind::Dodecahedron => dodecahedron::canonical(edge),
            SolidKind::Cube => cube_canonical(edge),
        };

        // Turn vertex (1,1,1), which both canonical solids have, onto +Z.
        let to_z = Rotation3::rotation_between(&Vector3::new(1.0, 1.0, 1.0), &Vector3::z())
            .unwrap_or_else(Rotation3::identity);
        let canon: Vec<Vector3<f64>> = canon.iter().map(|v| to_z * v * scale).collect();
        let mut normals: Vec<Vector3<f64>> = face_normals.iter().map(|n| to_z * n).collect();

        // Rings by normal height, highest first.
        let ring = |n: &Vector3<f64>| -> i32 { (-n.z * 4.0).round() as i32 };
        // Fix X: the highest faces all have the same height; take the one with the smallest
        // azimuth as face 0 and turn it onto +X.
        normals.sort_by(|a, b| b.z.total_cmp(&a.z));
        let az0 = normals[0].y.atan2(normals[0].x);
        let yaw = Rotation3::from_axis_angle(&Vector3::z_axis(), -az0);
        let vertices: Vec<Vector3<f64>> = canon.iter().map(|v| yaw * v).collect();
        let mut normals: Vec<Vector3<f64>> = normals.iter().map(|n| yaw * n).collect();
        let azimuth = |n: &Vector3<f64>| {
            let a = n.y.atan2(n.x);
            // Snap tiny negatives (face 0 sits on +X) so it sorts first, not last.
            if a < -1e-9 { a + std::f64::consts::TAU } else { a.max(0.0) }
        };
        normals.sort_by(|a, b| ring(a).cmp(&ring(b)).then(azimuth(a).total_cmp(&azimuth(b))));

        let faces = normals.iter().enumerate().map(|(index, n)| make_face(index, *n, &vertices)).collect();
        Solid { kind, edge, vertices, faces }
    }

    /// Which solid.
    pub fn kind(&self) -> SolidKind {
        self.kind
    }

    /// Edge length (mm).
    pub fn edge(&self) -> f64 {
        self.edge
    }

    /// The vertices (mm).
    pub fn vertices(&self) -> &[Vector3<f64>] {
        &self.vertices
    }

    /// The faces in the documented order.
    pub fn faces(&self) -> &[Face] {
        &self.faces
    }

    /// Distance from the centroid to each vertex (mm).
    pub fn circumradius(&self) -> f64 {
        match self.kind {
            SolidKind::Dodecahedron => dodecahedron::circumradius(self.edge),
            SolidKind::Cube => self.edge * 3f64.sqrt() / 2.0,
        }
    }

    /// Distance from the centroid to each face (mm).
    pub fn inradius(&self) -> f64 {
        match self.kind {
            SolidKind::Dodecahedron => dodecahedron::inradius(self.edge),
            SolidKind::Cube => self.edge / 2.0,
        }
    }

    /// Volume (mm³).
    pub fn volume(&self) -> f64 {
        match self.kind {
            SolidKind::Dodecahedron => dodecahedron::volume(self.edge),
            SolidKind::Cube => self.edge.powi(3),
        }
    }
}

/// The cube of edge 2 centred on the origin (vertices (±1, ±1, ±1)), its face normals, and the
/// factor that scales it to `edge`.
fn cube_canonical(edge: f64) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>, f64) {
    let mut vertices = Vec::with_capacity(8);
    for &sx in &[-1.0, 1.0] {
        for &sy in &[-1.0, 1.0] {
            for &sz in &[-1.0, 1.0] {
                vertices.push(Vector3::new(sx, sy, sz));
            }
        }
    }
    let normals = [Vector3::x(), -Vector3::x(), Vector3::y(), -Vector3::y(), Vector3::z(), -Vector3::z()];
    (vertices, normals.to_vec(), edge / 2.0)
}

fn make_face(index: usize, normal: Vector3<f64>, vertices: &[Vector3<f64>]) -> Face {
    let dmax = vertices.iter().map(|v| v.dot(&normal)).fold(f64::NEG_INFINITY, f64::max);
    let mut ring: Vec<Vector3<f64>> =
        vertices.iter().filter(|v| (v.dot(&normal) - dmax).abs() < 1e-9 * dmax.abs().max(1.0)).copied().collect();
    let sides = ring.len();
    let center = ring.iter().sum::<Vector3<f64>>() / sides as f64;
    // The mirror plane through Z meets the face along the projection of Z.
    let up = Unit::new_normalize(Vector3::z() - normal * normal.z);
    let apex_score = |v: &Vector3<f64>| {
        let d = (v - center).normalize();
        // An odd polygon has one vertex on the mirror plane, above or below the centre; an even
        // one has two, and the higher is the apex.
        if sides % 2 == 1 { d.dot(&up).abs() } else { d.dot(&up) }
    };
    let apex = ring.iter().copied().max_by(|a, b| apex_score(a).total_cmp(&apex_score(b))).unwrap_or(ring[0]);
    let toward_apex = (apex - center).normalize();
    let beside_apex = normal.cross(&toward_apex);
    // Counter-clockwise seen from outside = increasing angle about the outward normal, from the
    // apex turning toward n × (apex direction).
    let angle = |v: &Vector3<f64>| {
        let d = v - center;
        let a = d.dot(&beside_apex).atan2(d.dot(&toward_apex));
        if a < -1e-12 { a + std::f64::consts::TAU } else { a.max(0.0) }
    };
    ring.sort_by(|a, b| angle(a).total_cmp(&angle(b)));
    let y_axis = if sides % 2 == 1 { toward_apex } else { (0.5 * (ring[0] + ring[1]) - center).normalize() };
    let x_axis = normal.cross(&y_axis);
    Face { index, vertices: ring, center, normal, x_axis, y_axis }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Solid {
        Solid::new(SolidKind::Cube, 10.0)
    }

    #[test]
    fn cube_faces_are_squares_of_the_edge_at_the_inradius() {
        let c = cube();
        assert_eq!((c.faces().len(), c.vertices().len()), (6, 8));
        for f in c.faces() {
            assert_eq!(f.vertices.len(), 4);
            for i in 0..4 {
                let a = f.vertices[i];
                let b = f.vertices[(i + 1) % 4];
                assert!(((b - a).norm() - 10.0).abs() < 1e-9, "face {} side {i}", f.index);
                assert!(((a - f.center).dot(&f.normal)).abs() < 1e-12, "planar");
            }
            assert!((f.center.norm() - c.inradius()).abs() < 1e-9);
            assert!((f.inradius() - 5.0).abs() < 1e-9);
        }
        for v in c.vertices() {
            assert!((v.norm() - c.circumradius()).abs() < 1e-9);
        }
    }

    #[test]
    fn cube_frame_and_face_order_are_as_documented() {
        let c = cube();
        let top = c.vertices().iter().copied().max_by(|a, b| a.z.total_cmp(&b.z)).expect("8 vertices");
        assert!(top.x.abs() < 1e-9 && top.y.abs() < 1e-9 && (top.z - c.circumradius()).abs() < 1e-9);
        let f = c.faces();
        assert!(f[0].normal.y.abs() < 1e-12 && f[0].normal.x > 0.0, "face 0 normal on +X: {:?}", f[0].normal);
        for r in 0..2 {
            let ring = &f[3 * r..3 * r + 3];
            assert!((ring[0].normal.z - ring[2].normal.z).abs() < 1e-9);
            // Face 0 sits on +X up to rounding: read azimuths from just below it.
            let az: Vec<f64> =
                ring.iter().map(|x| (x.normal.y.atan2(x.normal.x) + 1e-9).rem_euclid(std::f64::consts::TAU)).collect();
            assert!(az[0] < az[1] && az[1] < az[2], "ring {r}: {az:?}");
        }
        assert!(f[2].normal.z > 0.5 && f[3].normal.z < -0.5, "three faces round each of ±Z");
        // The top vertex is the apex of the faces round it; the bottom one is the last vertex
        // of none but the opposite corner of each lower face.
        for face in &f[0..3] {
            assert!((face.vertices[0] - top).norm() < 1e-9);
        }
        for face in &f[3..6] {
            assert!((face.vertices[2].z + c.circumradius()).abs() < 1e-9, "−Z vertex opposite the apex");
        }
    }

    #[test]
    fn cube_tag_axes_run_along_the_edges_counter_clockwise() {
        for f in cube().faces() {
            assert!((f.x_axis.cross(&f.y_axis) + f.normal).norm() < 1e-12, "x × y = −n");
            let first_edge = (f.vertices[1] - f.vertices[0]).normalize();
            assert!(first_edge.cross(&f.x_axis).norm() < 1e-12, "x parallel to the edge leaving the apex");
            assert!((0.5 * (f.vertices[0] + f.vertices[1]) - f.center).normalize().dot(&f.y_axis) > 1.0 - 1e-12);
            for i in 0..4 {
                let a = f.vertices[i] - f.center;
                let b = f.vertices[(i + 1) % 4] - f.center;
                assert!(a.cross(&b).dot(&f.normal) > 0.0, "face {} counter-clockwise from outside", f.index);
            }
        }
    }

    #[test]
    fn volumes_match_the_polyhedra() {
        for kind in SolidKind::ALL {
            let s = Solid::new(kind, 12.7);
            assert_eq!((s.faces().len(), s.faces()[0].vertices.len()), (kind.face_count(), kind.face_sides()));
            // Divergence theorem over the faces (fan triangulation).
            let vol: f64 = s
                .faces()
                .iter()
                .flat_map(|f| (1..f.vertices.len() - 1).map(move |i| (f.vertices[0], f.vertices[i], f.vertices[i + 1])))
                .map(|(a, b, c)| a.dot(&b.cross(&c)) / 6.0)
                .sum();
            assert!((vol - s.volume()).abs() < 1e-9 * s.volume(), "{kind}: {vol} vs {}", s.volume());
            assert_eq!(SolidKind::from_name(kind.name()), Some(kind));
        }
        assert_eq!(SolidKind::from_name("sphere"), None);
    }
}
