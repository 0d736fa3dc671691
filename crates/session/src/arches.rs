//! The tooth scans of one arch: a whole-arch mesh, or one mesh per tooth named by its FDI
//! number (`FDI=NN` in the file name) or its file name.

use crate::SessionError;
use jawtrack_occlusion::contacts::tooth_name;
use jawtrack_occlusion::{Mesh, load_mesh};
use nalgebra::{Point3, Vector3};
use serde_json::{Value, json};
use std::path::PathBuf;

/// Why a map cannot say where the patient's left is, and what to give.
pub const UNSIDED: &str = "the maps cannot say where the patient's left is: name the per-tooth meshes by FDI \
     number (FDI=NN in the file name) or give --points";

/// One arch read: its named parts, each mesh's report (JSON), and a line per mesh in words.
#[derive(Debug)]
pub struct ArchInput {
    /// Each part's name and mesh.
    pub parts: Vec<(String, Mesh)>,
    /// Per file: its name, its tooth and the mesh checks, for `summary.json`.
    pub reports: Vec<Value>,
    /// Per file: "maxilla FILE: REPORT", for the command's output.
    pub lines: Vec<String>,
}

/// Reads one arch's files (`side`: `maxilla` or `mandible`, the flag that gave them).
pub fn load_arch(side: &'static str, files: &[PathBuf]) -> Result<ArchInput, SessionError> {
    let mut input = ArchInput { parts: Vec::new(), reports: Vec::new(), lines: Vec::new() };
    for file in files {
        let mesh = load_mesh(file).map_err(|source| SessionError::Mesh { side, source })?;
        let r = mesh.report();
        input.lines.push(format!("{side} {}: {r}", file.display()));
        let name = tooth_name(file);
        let tooth = (files.len() > 1).then(|| name.clone());
        input.reports.push(json!({ "file": file.display().to_string(), "tooth": tooth, "report": r }));
        input.parts.push((name, mesh));
    }
    Ok(input)
}

/// Each part's name and centroid: where its number goes on the map (none for a whole arch).
pub fn tooth_places(parts: &[(String, Mesh)]) -> Vec<(String, Point3<f64>)> {
    if parts.len() < 2 {
        return Vec::new();
    }
    parts
        .iter()
        .map(|(name, m)| {
            let n = m.vertices.len().max(1) as f64;
            (name.clone(), Point3::from(m.vertices.iter().map(|v| v.coords).sum::<Vector3<f64>>() / n))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_ascii_stl_without_a_name_reads_and_an_empty_file_is_named() {
        let dir = tempfile::tempdir().expect("temporary folder");
        let facet = |a: &str, b: &str, c: &str| {
            format!("facet normal 0 0 1\nouter loop\nvertex {a}\nvertex {b}\nvertex {c}\nendloop\nendfacet\n")
        };
        let text =
            format!("solid\n{}{}endsolid\n", facet("0 0 0", "10 0 0", "10 10 0"), facet("0 0 0", "10 10 0", "0 10 0"));
        let ascii = dir.path().join("upper.stl");
        std::fs::write(&ascii, text).expect("written");
        let arch = load_arch("maxilla", std::slice::from_ref(&ascii)).expect("an ASCII STL reads");
        assert_eq!((arch.parts[0].1.vertices.len(), arch.parts[0].1.triangles.len()), (4, 2));
        let empty = dir.path().join("lower.stl");
        std::fs::write(&empty, "").expect("written");
        let err = load_arch("mandible", std::slice::from_ref(&empty)).expect_err("empty");
        assert_eq!(
            err.to_string(),
            format!("--mandible: {}: empty file (0 bytes): export or copy it again", empty.display())
        );
    }
}
