//! Scans and harness bodies as `contacts`, `register` and `report` read them: STL (binary and
//! ASCII), PLY (ASCII and binary) and OBJ. A mesh that loads must keep the loader's promise
//! (triangles, finite coordinates, indices in range) and survive the one STL writer: written
//! and read back, the same triangles in single precision.

use crate::run::Verdict;
use crate::targets::files::refused;
use jawtrack_mesh::{Mesh, MeshFormat};

const TETRAHEDRON: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]];
const FACES: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

pub fn stl_seeds() -> Vec<Vec<u8>> {
    let mut ascii = String::from("solid tetra\n");
    for f in FACES {
        ascii += "facet normal 0 0 0\nouter loop\n";
        for v in f.map(|i| TETRAHEDRON[i as usize]) {
            ascii += &format!("vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        ascii += "endloop\nendfacet\n";
    }
    ascii += "endsolid tetra\n";
    let mut seeds = vec![ascii.into_bytes()];
    if let Ok(body) = std::fs::read(crate::targets::fixtures().join("../harness-cad/dodecahedron-with-post.stl")) {
        seeds.push(body);
    }
    seeds
}

pub fn ply_seeds() -> Vec<Vec<u8>> {
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\ncomment a tetrahedron\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let mut ascii = header("ascii");
    for v in TETRAHEDRON {
        ascii += &format!("{} {} {}\n", v[0], v[1], v[2]);
    }
    for f in FACES {
        ascii += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    let mut binary = header("binary_little_endian").into_bytes();
    for v in TETRAHEDRON {
        v.iter().for_each(|c| binary.extend_from_slice(&c.to_le_bytes()));
    }
    for f in FACES {
        binary.push(3);
        f.iter().for_each(|i| binary.extend_from_slice(&(*i as i32).to_le_bytes()));
    }
    vec![ascii.into_bytes(), binary]
}

pub fn obj_seeds() -> Vec<Vec<u8>> {
    let triangles = "# a tetrahedron\no tetra\nv 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\nvn 0 0 1\nvt 0 0\n\
                     f 1 3 2\nf 1//1 2//1 4//1\nf 1/1 4/1 3/1\nf -3 -2 -1\n";
    let quads = "o cube\nv 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nv 0 0 10\nv 10 0 10\nv 10 10 10\nv 0 10 10\n\
                 f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\ng second\nl 1 2\np 3\n";
    vec![triangles.as_bytes().to_vec(), quads.as_bytes().to_vec()]
}

fn read(input: &[u8], format: MeshFormat) -> Result<Verdict, String> {
    let mesh = match Mesh::from_bytes(input, format, "scan") {
        Ok(m) => m,
        Err(e) => return refused(e),
    };
    if mesh.triangles.is_empty() {
        return Err("a mesh without triangles loaded".into());
    }
    if let Some(p) = mesh.vertices.iter().find(|p| !p.coords.iter().all(|c| c.is_finite())) {
        return Err(format!("a vertex is not finite: {p}"));
    }
    let n = mesh.vertices.len();
    if let Some(t) = mesh.triangles.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
        return Err(format!("triangle {t:?} indexes past the {n} vertices"));
    }
    let mut stl = Vec::new();
    mesh.write_stl(&mut stl).map_err(|e| format!("the STL writer failed: {e}"))?;
    let back = Mesh::from_bytes(&stl, MeshFormat::Stl, "written")
        .map_err(|e| format!("what the STL writer wrote does not read back: {e}"))?;
    if corners(&back) != corners(&mesh) {
        return Err(format!("written as STL and read back, the {} triangles changed", mesh.triangles.len()));
    }
    Ok(Verdict::Accepted)
}

/// Every triangle's corners in single precision, as STL keeps them.
fn corners(mesh: &Mesh) -> Vec<[[f32; 3]; 3]> {
    mesh.triangles
        .iter()
        .map(|t| {
            t.map(|i| {
                let p = mesh.vertices[i as usize];
                [p.x as f32, p.y as f32, p.z as f32]
            })
        })
        .collect()
}

pub fn stl(input: &[u8]) -> Result<Verdict, String> {
    read(input, MeshFormat::Stl)
}

pub fn ply(input: &[u8]) -> Result<Verdict, String> {
    read(input, MeshFormat::Ply)
}

pub fn obj(input: &[u8]) -> Result<Verdict, String> {
    read(input, MeshFormat::Obj)
}
