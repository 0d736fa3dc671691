//! Triangle meshes in millimetres: reading STL (binary and ASCII), PLY and OBJ through their
//! crates, writing vertex-coloured PLY, and the checks a scan deserves before it is trusted:
//! empty or non-finite data, a size that says the units are not millimetres, degenerate
//! triangles, non-manifold edges and boundary loops (holes; an intra-oral scan is an open
//! surface, so at least one loop is normal).

use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use std::path::Path;

/// An indexed triangle mesh (mm). Triangles wind counter-clockwise seen from outside, so
/// their normals point out of the tooth.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Vertex positions (mm).
    pub vertices: Vec<Point3<f64>>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

/// The smallest and largest extent (mm) a dental scan or harness can have: below, the file is
/// in metres (an arch would be 0.06 long); above, in microns.
pub const PLAUSIBLE_EXTENT_MM: (f64, f64) = (1.0, 1000.0);

/// Why a mesh could not be used.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
    /// The file's extension is not one we read.
    #[error("{path}: unknown mesh format (expected .stl, .ply or .obj)")]
    Format {
        /// The file.
        path: String,
    },
    /// The file's content is not a mesh of its format.
    #[error("{path}: not a readable {format} mesh: {reason}")]
    Corrupt {
        /// The file.
        path: String,
        /// STL, PLY or OBJ.
        format: &'static str,
        /// The parser's complaint.
        reason: String,
    },
    /// No triangles.
    #[error("{path}: the mesh has no triangles")]
    Empty {
        /// The file.
        path: String,
    },
    /// A coordinate is NaN or infinite, or an index points past the vertices.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// The bounding box is implausible for millimetres.
    #[error(
        "{path}: the mesh is {extent} across its largest side; a tooth scan in millimetres is {lo}-{hi} mm, so this looks like {guess} (convert the file to mm)",
        lo = PLAUSIBLE_EXTENT_MM.0, hi = PLAUSIBLE_EXTENT_MM.1
    )]
    Units {
        /// The file.
        path: String,
        /// The largest side of the bounding box, in the file's units.
        extent: f64,
        /// What the units look like.
        guess: &'static str,
    },
}

/// What [`Mesh::report`] found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MeshReport {
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Bounding box minimum and maximum (mm).
    pub bounds: [[f64; 3]; 2],
    /// Surface area (mm²).
    pub area_mm2: f64,
    /// Triangles with (nearly) zero area or a repeated vertex.
    pub degenerate_triangles: usize,
    /// Edges shared by more than two triangles.
    pub non_manifold_edges: usize,
    /// Edges on one triangle only.
    pub boundary_edges: usize,
    /// Closed loops of boundary edges: the scan's rim and any holes in it.
    pub boundary_loops: usize,
    /// Connected pieces (e.g. one per tooth).
    pub components: usize,
}

impl Mesh {
    /// Reads a mesh by its extension (`.stl`, `.ply`, `.obj`) and checks it is usable in mm.
    pub fn load(path: &Path) -> Result<Mesh, MeshError> {
        let name = path.display().to_string();
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        let bytes = std::fs::read(path).map_err(|e| MeshError::Io { path: name.clone(), reason: e.to_string() })?;
        let mesh = match ext.as_deref() {
            Some("stl") => read_stl(&bytes),
            Some("ply") => read_ply(&bytes),
            Some("obj") => read_obj(&bytes),
            _ => return Err(MeshError::Format { path: name }),
        }
        .map_err(|(format, reason)| MeshError::Corrupt { path: name.clone(), format, reason })?;
        mesh.validate(&name)?;
        Ok(mesh)
    }

    /// Checks the mesh is non-empty, finite, well indexed and millimetre-sized; `name` names it
    /// in the error.
    pub fn validate(&self, name: &str) -> Result<(), MeshError> {
        if self.triangles.is_empty() {
            return Err(MeshError::Empty { path: name.to_owned() });
        }
        if let Some(i) = self.vertices.iter().position(|v| !v.coords.iter().all(|c| c.is_finite())) {
            return Err(MeshError::Invalid { path: name.to_owned(), reason: format!("vertex {i} is not finite") });
        }
        let n = self.vertices.len();
        if let Some(t) = self.triangles.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
            return Err(MeshError::Invalid {
                path: name.to_owned(),
                reason: format!("triangle {t} refers to a vertex past the {n} there are"),
            });
        }
        let [lo, hi] = self.bounds();
        let extent = (hi - lo).max();
        let guess = if extent < PLAUSIBLE_EXTENT_MM.0 {
            "metres"
        } else if extent > PLAUSIBLE_EXTENT_MM.1 {
            "microns"
        } else {
            return Ok(());
        };
        Err(MeshError::Units { path: name.to_owned(), extent, guess })
    }

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

    /// Twice-area normal of triangle `t` (not normalised; zero for a degenerate one).
    pub fn area_normal(&self, t: usize) -> Vector3<f64> {
        let [a, b, c] = self.corners(t);
        (b - a).cross(&(c - a))
    }

    /// Surface area (mm²).
    pub fn area(&self) -> f64 {
        (0..self.triangles.len()).map(|t| self.area_normal(t).norm() / 2.0).sum()
    }

    /// The mesh moved by `f`.
    pub fn transformed(&self, f: impl Fn(&Point3<f64>) -> Point3<f64>) -> Mesh {
        Mesh { vertices: self.vertices.iter().map(f).collect(), triangles: self.triangles.clone() }
    }

    /// Several meshes as one (indices shifted); also returns, per triangle, which part it came
    /// from.
    pub fn concat(parts: &[Mesh]) -> (Mesh, Vec<u16>) {
        let mut out = Mesh { vertices: Vec::new(), triangles: Vec::new() };
        let mut part_of = Vec::new();
        for (k, m) in parts.iter().enumerate() {
            let base = out.vertices.len() as u32;
            out.vertices.extend_from_slice(&m.vertices);
            out.triangles.extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
            part_of.extend(std::iter::repeat_n(k as u16, m.triangles.len()));
        }
        (out, part_of)
    }

    /// Counts degenerate triangles, non-manifold and boundary edges, boundary loops and
    /// connected components.
    pub fn report(&self) -> MeshReport {
        let [lo, hi] = self.bounds();
        // A triangle is degenerate when its area is negligible against its longest edge².
        let degenerate_triangles = (0..self.triangles.len())
            .filter(|&t| {
                let [a, b, c] = self.corners(t);
                let longest = (b - a).norm_squared().max((c - b).norm_squared()).max((a - c).norm_squared());
                let [i, j, k] = self.triangles[t];
                i == j || j == k || k == i || self.area_normal(t).norm() <= 1e-9 * longest.max(f64::MIN_POSITIVE)
            })
            .count();
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &self.triangles {
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let non_manifold_edges = edges.values().filter(|&&n| n > 2).count();
        let boundary: Vec<(u32, u32)> = edges.iter().filter(|e| *e.1 == 1).map(|e| *e.0).collect();
        let boundary_loops = {
            let mut sets = DisjointSets::new(self.vertices.len());
            let mut on_boundary = vec![false; self.vertices.len()];
            for &(a, b) in &boundary {
                sets.union(a as usize, b as usize);
                on_boundary[a as usize] = true;
                on_boundary[b as usize] = true;
            }
            (0..self.vertices.len()).filter(|&v| on_boundary[v] && sets.find(v) == v).count()
        };
        let components = {
            let mut sets = DisjointSets::new(self.vertices.len());
            let mut used = vec![false; self.vertices.len()];
            for t in &self.triangles {
                sets.union(t[0] as usize, t[1] as usize);
                sets.union(t[1] as usize, t[2] as usize);
                t.iter().for_each(|&i| used[i as usize] = true);
            }
            (0..self.vertices.len()).filter(|&v| used[v] && sets.find(v) == v).count()
        };
        MeshReport {
            vertices: self.vertices.len(),
            triangles: self.triangles.len(),
            bounds: [[lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]],
            area_mm2: self.area(),
            degenerate_triangles,
            non_manifold_edges,
            boundary_edges: boundary.len(),
            boundary_loops,
            components,
        }
    }

    /// Writes the mesh as binary PLY with one RGB colour per vertex.
    pub fn write_coloured_ply(&self, path: &Path, colours: &[[u8; 3]]) -> Result<(), MeshError> {
        use ply_rs_bw::ply::{
            Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType, ScalarType,
        };
        let io = |e: std::io::Error| MeshError::Io { path: path.display().to_string(), reason: e.to_string() };
        let mut ply = Ply::<DefaultElement>::new();
        ply.header.encoding = Encoding::BinaryLittleEndian;
        ply.header.comments.push("JawTrack contact map, units mm".to_owned());
        let mut vertex = ElementDef::new("vertex".to_owned());
        for name in ["x", "y", "z"] {
            vertex.properties.add(PropertyDef::new(name.to_owned(), PropertyType::Scalar(ScalarType::Float)));
        }
        for name in ["red", "green", "blue"] {
            vertex.properties.add(PropertyDef::new(name.to_owned(), PropertyType::Scalar(ScalarType::UChar)));
        }
        ply.header.elements.add(vertex);
        let mut face = ElementDef::new("face".to_owned());
        face.properties.add(PropertyDef::new(
            "vertex_indices".to_owned(),
            PropertyType::List(ScalarType::UChar, ScalarType::UInt),
        ));
        ply.header.elements.add(face);
        let vertices = self
            .vertices
            .iter()
            .zip(colours.iter().chain(std::iter::repeat(&[200, 200, 200])))
            .map(|(v, c)| {
                let mut e = DefaultElement::new();
                for (name, x) in ["x", "y", "z"].into_iter().zip(v.iter()) {
                    e.insert(name.to_owned(), Property::Float(*x as f32));
                }
                for (name, x) in ["red", "green", "blue"].into_iter().zip(c) {
                    e.insert(name.to_owned(), Property::UChar(*x));
                }
                e
            })
            .collect();
        ply.payload.insert("vertex".to_owned(), vertices);
        let faces = self
            .triangles
            .iter()
            .map(|t| {
                let mut e = DefaultElement::new();
                e.insert("vertex_indices".to_owned(), Property::ListUInt(t.to_vec()));
                e
            })
            .collect();
        ply.payload.insert("face".to_owned(), faces);
        let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
        ply_rs_bw::writer::Writer::new().write_ply(&mut out, &mut ply).map_err(io)?;
        std::io::Write::flush(&mut out).map_err(io)
    }

    /// Writes the mesh as binary STL.
    pub fn write_stl(&self, path: &Path) -> Result<(), MeshError> {
        let io = |e: std::io::Error| MeshError::Io { path: path.display().to_string(), reason: e.to_string() };
        let tris: Vec<stl_io::Triangle> = (0..self.triangles.len())
            .map(|t| {
                let n = self.area_normal(t).try_normalize(0.0).unwrap_or_else(Vector3::zeros);
                let v = self.corners(t).map(|p| stl_io::Vertex::new([p.x as f32, p.y as f32, p.z as f32]));
                stl_io::Triangle { normal: stl_io::Normal::new([n.x as f32, n.y as f32, n.z as f32]), vertices: v }
            })
            .collect();
        let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
        stl_io::write_stl(&mut out, tris.iter()).map_err(io)?;
        std::io::Write::flush(&mut out).map_err(io)
    }
}

type ParseResult = Result<Mesh, (&'static str, String)>;

fn read_stl(bytes: &[u8]) -> ParseResult {
    let indexed = stl_io::read_stl(&mut std::io::Cursor::new(bytes)).map_err(|e| ("STL", e.to_string()))?;
    let vertices = indexed.vertices.iter().map(|v| Point3::new(v[0] as f64, v[1] as f64, v[2] as f64)).collect();
    let triangles = indexed.faces.iter().map(|f| f.vertices.map(|i| i as u32)).collect();
    Ok(Mesh { vertices, triangles })
}

fn read_obj(bytes: &[u8]) -> ParseResult {
    let options =
        tobj::LoadOptions { triangulate: true, ignore_points: true, ignore_lines: true, ..Default::default() };
    let (models, _) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| Err(tobj::LoadError::MaterialParseError))
            .map_err(|e| ("OBJ", e.to_string()))?;
    let mut parts = Vec::with_capacity(models.len());
    for model in models {
        let m = model.mesh;
        let vertices =
            m.positions.chunks_exact(3).map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
        let triangles = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        parts.push(Mesh { vertices, triangles });
    }
    Ok(Mesh::concat(&parts).0)
}

/// A PLY vertex: any of float/double x, y, z; other properties ignored.
struct PlyVertex([f64; 3]);
/// A PLY face: its index list, triangulated as a fan.
struct PlyFace(Vec<u32>);

impl ply_rs_bw::ply::PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex([f64::NAN; 3])
    }
    fn set_property(&mut self, key: &str, property: ply_rs_bw::ply::Property) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::{Property, PropertyAccessResult};
        let i = match key {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return PropertyAccessResult::Ignored,
        };
        self.0[i] = match property {
            Property::Float(v) => v as f64,
            Property::Double(v) => v,
            Property::Int(v) => v as f64,
            Property::Short(v) => v as f64,
            _ => return PropertyAccessResult::Ignored,
        };
        PropertyAccessResult::Set
    }
}

impl ply_rs_bw::ply::PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace(Vec::new())
    }
    fn set_property(&mut self, key: &str, property: ply_rs_bw::ply::Property) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::{Property, PropertyAccessResult};
        if key != "vertex_indices" && key != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        // Negative indices become u32::MAX, which validation then reports as out of range.
        self.0 = match property {
            Property::ListInt(v) => v.into_iter().map(|i| u32::try_from(i).unwrap_or(u32::MAX)).collect(),
            Property::ListUInt(v) => v,
            Property::ListShort(v) => v.into_iter().map(|i| u32::try_from(i).unwrap_or(u32::MAX)).collect(),
            Property::ListUShort(v) => v.into_iter().map(u32::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(u32::from).collect(),
            _ => return PropertyAccessResult::Ignored,
        };
        PropertyAccessResult::Set
    }
}

fn read_ply(bytes: &[u8]) -> ParseResult {
    use ply_rs_bw::parser::{Parser, Reader};
    let err = |e: ply_rs_bw::parser::ParseError| ("PLY", e.to_string());
    let mut reader = Reader::new(std::io::BufReader::new(std::io::Cursor::new(bytes)));
    let vertex_parser = Parser::<PlyVertex>::new();
    let face_parser = Parser::<PlyFace>::new();
    let header = vertex_parser.read_header(&mut reader).map_err(err)?;
    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    for element in header.elements.values() {
        match element.name.as_str() {
            "vertex" => {
                vertices = vertex_parser.read_payload_for_element(&mut reader, element, &header).map_err(err)?
            }
            "face" => faces = face_parser.read_payload_for_element(&mut reader, element, &header).map_err(err)?,
            // Later elements (edges, materials) cannot be skipped without parsing them.
            _ => break,
        }
    }
    let vertices = vertices.into_iter().map(|v| Point3::from(v.0)).collect();
    let triangles = faces
        .into_iter()
        .flat_map(|f| (2..f.0.len()).map(move |k| [f.0[0], f.0[k - 1], f.0[k]]).collect::<Vec<_>>())
        .collect();
    Ok(Mesh { vertices, triangles })
}

/// Union–find over indices, for loops and components.
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

pub(crate) struct DisjointSets(Vec<usize>);

impl DisjointSets {
    pub(crate) fn new(n: usize) -> Self {
        DisjointSets((0..n).collect())
    }
    pub(crate) fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    pub(crate) fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb)] = ra.min(rb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(size: f64) -> Mesh {
        let v = |x: f64, y: f64| Point3::new(x * size, y * size, 0.0);
        Mesh { vertices: vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)], triangles: vec![[0, 1, 2], [0, 2, 3]] }
    }

    #[test]
    fn an_open_square_has_one_rim_and_no_defects() {
        let r = square(10.0).report();
        assert_eq!((r.boundary_edges, r.boundary_loops, r.components, r.non_manifold_edges), (4, 1, 1, 0));
        assert_eq!(r.degenerate_triangles, 0);
        assert!((r.area_mm2 - 100.0).abs() < 1e-12);
    }

    #[test]
    fn defects_are_counted() {
        let mut m = square(10.0);
        m.vertices.push(Point3::new(5.0, 5.0, 3.0));
        m.triangles.push([0, 2, 4]); // a third triangle on the diagonal: non-manifold
        m.triangles.push([1, 1, 3]); // repeated vertex: degenerate
        let r = m.report();
        assert_eq!(r.non_manifold_edges, 1);
        assert_eq!(r.degenerate_triangles, 1);
    }

    #[test]
    fn sizes_in_metres_or_microns_are_refused_with_a_guess() {
        assert!(square(10.0).validate("a").is_ok());
        let m = square(0.06).validate("arch.stl");
        assert!(matches!(&m, Err(MeshError::Units { guess: "metres", .. })), "{m:?}");
        assert!(m.err().is_some_and(|e| e.to_string().contains("arch.stl")));
        assert!(matches!(square(60000.0).validate("a"), Err(MeshError::Units { guess: "microns", .. })));
        let empty = Mesh { vertices: vec![], triangles: vec![] };
        assert!(matches!(empty.validate("a"), Err(MeshError::Empty { .. })));
        let mut nan = square(10.0);
        nan.vertices[1].x = f64::NAN;
        assert!(matches!(nan.validate("a"), Err(MeshError::Invalid { .. })));
        let mut bad_index = square(10.0);
        bad_index.triangles[0][2] = 9;
        assert!(matches!(bad_index.validate("a"), Err(MeshError::Invalid { .. })));
    }
}
