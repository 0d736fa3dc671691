//! Writing meshes: binary STL ([`Mesh::write_stl`] to any writer, [`Mesh::write_stl_file`] to
//! a path; the one STL writer, for the harness body and for scans alike) and binary PLY with
//! one colour per vertex (contact maps).

use crate::{Mesh, MeshError};
use nalgebra::Vector3;
use std::io::Write;
use std::path::Path;

impl Mesh {
    /// Writes the mesh as binary STL: an 80-byte zero header, then per triangle its unit
    /// facet normal and corners in single precision. The normal is (b − a) × (c − a)
    /// normalised in double precision, then rounded; a zero-area triangle gets a zero normal
    /// (readers recompute it from the winding anyway).
    pub fn write_stl(&self, mut w: impl Write) -> std::io::Result<()> {
        let tris: Vec<stl_io::Triangle> = (0..self.triangles.len())
            .map(|t| {
                let n = self.area_normal(t).try_normalize(0.0).unwrap_or_else(Vector3::zeros);
                let v = self.corners(t).map(|p| stl_io::Vertex::new([p.x as f32, p.y as f32, p.z as f32]));
                stl_io::Triangle { normal: stl_io::Normal::new([n.x as f32, n.y as f32, n.z as f32]), vertices: v }
            })
            .collect();
        stl_io::write_stl(&mut w, tris.iter())
    }

    /// Writes the mesh as binary STL ([`Mesh::write_stl`]) to the file at `path`.
    pub fn write_stl_file(&self, path: &Path) -> Result<(), MeshError> {
        let io = |e: std::io::Error| MeshError::Io { path: path.display().to_string(), reason: e.to_string() };
        let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
        self.write_stl(&mut out).map_err(io)?;
        out.flush().map_err(io)
    }

    /// Writes the mesh as binary PLY with one RGB colour per vertex; vertices past the end of
    /// `colours` are light grey.
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
        out.flush().map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    /// A closed box turned about an oblique axis, so that no normal is axis-aligned and no
    /// coordinate rounds evenly, plus a zero-area triangle (a repeated corner) and a sliver.
    fn awkward() -> Mesh {
        let turn =
            nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::new(1.0, -2.0, 0.7)), 0.917);
        let mut m = crate::tests::cube().transformed(|p| {
            let q = Point3::new(p.x * 10.0 / 3.0 + 0.1, p.y * 7.0 / 9.0 - 1e-3, p.z * std::f64::consts::PI);
            turn * q + Vector3::new(0.0, 0.0, 12.345_678_9)
        });
        let k = m.vertices.len() as u32;
        m.vertices.push(Point3::new(1.0 / 3.0, 2.0 / 7.0, 1e-7));
        m.vertices.push(Point3::new(2.0 / 3.0, 4.0 / 7.0, 2e-7 + 1e-12));
        m.triangles.push([k, k + 1, k + 1]);
        m.triangles.push([0, k, k + 1]);
        m
    }

    /// Binary STL assembled by hand, with the facet normal computed on plain arrays as the
    /// harness's writer did: (b − a) × (c − a) in f64, divided by its length, 0 when the
    /// length is 0, then cast to f32.
    fn stl_by_hand(m: &Mesh) -> Vec<u8> {
        let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let mut bytes = vec![0u8; 80];
        bytes.extend((m.triangles.len() as u32).to_le_bytes());
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| {
                let p = m.vertices[i as usize];
                [p.x, p.y, p.z]
            });
            let n = cross(sub(b, a), sub(c, a));
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let n = if len > 0.0 { n.map(|x| x / len) } else { [0.0; 3] };
            for x in [n, a, b, c].into_iter().flatten() {
                bytes.extend((x as f32).to_le_bytes());
            }
            bytes.extend([0, 0]);
        }
        bytes
    }

    #[test]
    fn stl_bytes_are_pinned_normals_included() {
        let m = awkward();
        let mut bytes = Vec::new();
        m.write_stl(&mut bytes).expect("write to memory");
        assert_eq!(bytes.len(), 84 + 50 * m.triangles.len());
        assert_eq!(bytes, stl_by_hand(&m));
        // The degenerate triangle's normal is written as zeros.
        let degenerate = 84 + 50 * (m.triangles.len() - 2);
        assert_eq!(&bytes[degenerate..degenerate + 12], &[0u8; 12]);
    }

    #[test]
    fn stl_file_reads_back() {
        let m = crate::tests::cube().transformed(|p| Point3::from(p.coords * 10.0));
        let path = std::env::temp_dir().join(format!("jawtrack-mesh-cube-{}.stl", std::process::id()));
        m.write_stl_file(&path).expect("writes");
        let mut in_memory = Vec::new();
        m.write_stl(&mut in_memory).expect("write to memory");
        assert_eq!(std::fs::read(&path).expect("reads"), in_memory, "the file holds what write_stl writes");
        let back = Mesh::load(&path).expect("loads");
        std::fs::remove_file(&path).expect("clean up");
        assert_eq!((back.vertices.len(), back.triangles.len()), (8, 12));
        assert!((back.volume() - 1000.0).abs() < 1e-9);
        assert_eq!(back.report().boundary_edges, 0, "closed");
    }

    #[test]
    fn coloured_ply_reads_back() {
        let m = crate::tests::cube().transformed(|p| Point3::from(p.coords * 10.0));
        let path = std::env::temp_dir().join(format!("jawtrack-mesh-cube-{}.ply", std::process::id()));
        m.write_coloured_ply(&path, &[[255, 0, 0]]).expect("writes");
        let back = Mesh::load(&path).expect("loads");
        std::fs::remove_file(&path).expect("clean up");
        assert_eq!(back, m);
    }
}
