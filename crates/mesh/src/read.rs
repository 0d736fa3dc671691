//! Reading meshes: [`Mesh::load`] picks the format by extension (STL binary or ASCII through
//! `stl_io`, PLY through `ply-rs-bw`, OBJ through `tobj`) and validates the result, so a mesh
//! that loads is non-empty, finite, well indexed and millimetre-sized.

use crate::{Mesh, MeshError};
use nalgebra::Point3;
use std::path::Path;

/// A mesh file's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// STL, binary or ASCII.
    Stl,
    /// PLY, ASCII or binary.
    Ply,
    /// Wavefront OBJ (triangulated; materials ignored).
    Obj,
}

impl MeshFormat {
    /// The format a file's extension names (any case), if one we read.
    pub fn from_path(path: &Path) -> Option<MeshFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "stl" => Some(MeshFormat::Stl),
            "ply" => Some(MeshFormat::Ply),
            "obj" => Some(MeshFormat::Obj),
            _ => None,
        }
    }
}

impl Mesh {
    /// Reads a mesh by its extension (`.stl`, `.ply`, `.obj`) and checks it is usable in mm.
    pub fn load(path: &Path) -> Result<Mesh, MeshError> {
        let name = path.display().to_string();
        let format = MeshFormat::from_path(path).ok_or_else(|| MeshError::Format { path: name.clone() })?;
        let bytes = std::fs::read(path).map_err(|e| MeshError::Io { path: name.clone(), reason: e.to_string() })?;
        Mesh::from_bytes(&bytes, format, &name)
    }

    /// Reads a mesh from a file's bytes in `format`, checked as [`Mesh::load`] checks it;
    /// errors name the file as `name`.
    ///
    /// # Examples
    ///
    /// ```
    /// use jawtrack_mesh::{Mesh, MeshFormat};
    /// let obj = b"v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n";
    /// let mesh = Mesh::from_bytes(obj, MeshFormat::Obj, "triangle.obj").unwrap();
    /// assert_eq!(mesh.triangles.len(), 1);
    /// ```
    pub fn from_bytes(bytes: &[u8], format: MeshFormat, name: &str) -> Result<Mesh, MeshError> {
        let mesh = match format {
            MeshFormat::Stl => read_stl(bytes),
            MeshFormat::Ply => read_ply(bytes),
            MeshFormat::Obj => read_obj(bytes),
        }
        .map_err(|(format, reason)| MeshError::Corrupt { path: name.to_owned(), format, reason })?;
        mesh.validate(name)?;
        Ok(mesh)
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
    let bytes = positions_only(bytes);
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

/// The OBJ without its texture coordinates and normals (`vt`, `vn` lines, and the `/vt/vn` of
/// each face corner), which a mesh here never uses: tobj 4.0.5 multiplies their indices
/// unchecked, so a hostile index overflowed (found by the `obj` fuzz target).
fn positions_only(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len());
    for line in bytes.split_inclusive(|&b| b == b'\n') {
        let text = line.trim_ascii_start();
        if text.starts_with(b"vt") || text.starts_with(b"vn") {
            continue;
        }
        if !text.starts_with(b"f ") && !text.starts_with(b"f\t") {
            out.extend_from_slice(line);
            continue;
        }
        out.push(b'f');
        for token in text[1..].split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty()) {
            out.push(b' ');
            out.extend(token.iter().take_while(|&&b| b != b'/'));
        }
        out.push(b'\n');
    }
    out
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
    // Every element takes at least a byte, in any encoding: a count the file cannot hold would
    // have the parser loop that many times (a binary face count of 2⁶⁴ − 1 hung it; found by
    // the `ply` fuzz target).
    let end = bytes.windows(10).position(|w| w == b"end_header").unwrap_or(0);
    let body = bytes[end..].iter().position(|&b| b == b'\n').map_or(0, |nl| bytes.len() - end - nl - 1);
    if let Some(e) = header.elements.values().find(|e| e.count > body) {
        return Err((
            "PLY",
            format!("element {} claims {} entries, but only {body} bytes follow the header", e.name, e.count),
        ));
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_obj_with_a_hostile_normal_index_loads_its_triangles() {
        // Found by the `obj` fuzz target: tobj multiplied the normal index -31 (relative, before
        // any normal) unchecked, an overflow; normals are now never handed to it.
        let obj = b"v 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\nvn 0 0 1 1\nvt 0 0\nf 1/1 4/1 3/1\nf 1//1 2//1 4//-31\n";
        let mesh = Mesh::from_bytes(obj, MeshFormat::Obj, "scan.obj").expect("two triangles");
        assert_eq!(mesh.triangles.len(), 2);
        assert_eq!(positions_only(b"vt 1 2\nf 3/1/2\t4//5 6\n"), b"f 3 4 6\n");
    }

    #[test]
    fn a_ply_claiming_more_entries_than_it_holds_is_refused_at_once() {
        // Found by the `ply` fuzz target: a binary face count of 2^64 - 1 had the parser loop.
        let ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 18446744073709551615\nproperty list uchar int vertex_indices\n\
                    end_header\n\0\0\0\0\0\0\0\0\0\0\0\0";
        let err = Mesh::from_bytes(ply, MeshFormat::Ply, "scan.ply").expect_err("a count it cannot hold").to_string();
        assert!(err.contains("element face claims 18446744073709551615 entries, but only 12 bytes follow"), "{err}");
    }
}
