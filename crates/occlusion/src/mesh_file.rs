//! Reading a scan with the checks [`Mesh::load`] leaves to its parsers, whose complaints
//! ("failed to fill whole buffer") say nothing a user can act on: an empty file, an ASCII STL
//! as exporters really write it (`solid` without a name, CRLF line ends, upper-case keywords,
//! several solids in one file, no `endsolid`), a binary STL cut short, a text file that is not
//! an STL, and a mesh whose triangles all have zero area. Each error names the file.

use crate::{Mesh, MeshError};
use nalgebra::Point3;
use std::collections::HashMap;
use std::path::Path;

/// A binary STL's 80-byte header and its triangle count (bytes).
const STL_HEADER: usize = 84;
/// A binary STL's record of one triangle: normal, three corners, attribute (bytes).
const STL_TRIANGLE: usize = 50;

/// Reads a mesh as [`Mesh::load`] does (STL, PLY, OBJ by extension, checked to be usable in
/// mm), reading STL itself so that every ASCII STL is read and an empty or cut-short file is
/// named as such, and refuses a mesh whose triangles all have zero area.
///
/// # Examples
///
/// ```no_run
/// let mesh = jawtrack_occlusion::load_mesh(std::path::Path::new("upper.stl"))?;
/// println!("{} triangles", mesh.triangles.len());
/// # Ok::<(), jawtrack_occlusion::MeshError>(())
/// ```
pub fn load_mesh(path: &Path) -> Result<Mesh, MeshError> {
    let name = path.display().to_string();
    let io = |e: std::io::Error| MeshError::Io { path: name.clone(), reason: e.to_string() };
    if std::fs::metadata(path).map_err(io)?.len() == 0 {
        return Err(MeshError::Invalid { path: name, reason: "empty file (0 bytes): export or copy it again".into() });
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if ext.as_deref() != Some("stl") {
        let mesh = Mesh::load(path)?;
        refuse_flat(&mesh, &name)?;
        return Ok(mesh);
    }
    let bytes = std::fs::read(path).map_err(io)?;
    let mesh = read_stl(&bytes).map_err(|reason| MeshError::Corrupt { path: name.clone(), format: "STL", reason })?;
    // Zero area before the size check: a mesh collapsed to a point would read as metres.
    if !mesh.triangles.is_empty() {
        refuse_flat(&mesh, &name)?;
    }
    mesh.validate(&name)?;
    Ok(mesh)
}

/// Whether triangle `t` of `mesh` has (nearly) zero area: a repeated vertex, or an area
/// negligible against its longest edge² (the rule of [`Mesh::report`]).
fn zero_area(mesh: &Mesh, t: usize) -> bool {
    let [i, j, k] = mesh.triangles[t];
    let [a, b, c] = mesh.corners(t);
    let longest = (b - a).norm_squared().max((c - b).norm_squared()).max((a - c).norm_squared());
    i == j || j == k || k == i || mesh.area_normal(t).norm() <= 1e-9 * longest.max(f64::MIN_POSITIVE)
}

/// Refuses a mesh whose every triangle has zero area: a point cloud saved as triangles or a
/// broken export, on which no contact or distance means anything. A few such triangles in a
/// scan are normal, and [`Mesh::report`] counts them.
fn refuse_flat(mesh: &Mesh, name: &str) -> Result<(), MeshError> {
    let n = mesh.triangles.len();
    if n == 0 || (0..n).any(|t| !zero_area(mesh, t)) {
        return Ok(());
    }
    let which = if n == 1 { "its only triangle has".to_string() } else { format!("all {n} triangles have") };
    Err(MeshError::Invalid {
        path: name.to_owned(),
        reason: format!("{which} zero area: is it a point cloud or a broken export?"),
    })
}

/// An STL, binary or ASCII; the error says what is wrong with the file.
fn read_stl(bytes: &[u8]) -> Result<Mesh, String> {
    let declared = bytes.get(80..STL_HEADER).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize);
    let expected = declared.map(|n| STL_HEADER as u64 + STL_TRIANGLE as u64 * n as u64);
    // An exact size is binary even when its header begins with "solid", as some exporters write.
    if expected == Some(bytes.len() as u64) {
        return Ok(read_binary(bytes, declared.unwrap_or(0)));
    }
    let start = &bytes[..bytes.len().min(512)];
    let text = start.iter().all(|&b| b >= 0x20 || b"\t\n\r".contains(&b));
    let trimmed = String::from_utf8_lossy(start);
    let trimmed = trimmed.trim_start_matches('\u{feff}').trim_start();
    if text && trimmed.get(..5).is_some_and(|s| s.eq_ignore_ascii_case("solid")) {
        return read_ascii(&String::from_utf8_lossy(bytes));
    }
    if text {
        return Err("the file is text but does not start with `solid` as an ASCII STL does: is it another \
                    format named .stl?"
            .into());
    }
    match (declared, expected) {
        (Some(n), Some(expected)) if (bytes.len() as u64) < expected => Err(format!(
            "truncated binary STL: its header declares {n} triangles ({expected} bytes) but the file holds {} \
             bytes; export or copy it again",
            bytes.len()
        )),
        (Some(n), _) => Ok(read_binary(bytes, n)),
        (None, _) => Err(format!(
            "truncated binary STL: {} bytes, shorter than the {STL_HEADER}-byte header; export or copy it again",
            bytes.len()
        )),
    }
}

/// Triangle soup to an indexed mesh, vertices merged when bit for bit equal (as `stl_io`
/// merges them, so a binary STL reads exactly as [`Mesh::load`] reads it).
#[derive(Default)]
struct Merged {
    mesh: Mesh,
    index: HashMap<[u32; 3], u32>,
}

impl Merged {
    fn add(&mut self, corners: [[f32; 3]; 3]) {
        let ids = corners.map(|p| {
            *self.index.entry(p.map(f32::to_bits)).or_insert_with(|| {
                self.mesh.vertices.push(Point3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                self.mesh.vertices.len() as u32 - 1
            })
        });
        self.mesh.triangles.push(ids);
    }
}

/// The first `n` triangles of a binary STL of at least that size.
fn read_binary(bytes: &[u8], n: usize) -> Mesh {
    let mut merged = Merged::default();
    for record in bytes[STL_HEADER..].chunks_exact(STL_TRIANGLE).take(n) {
        let f = |k: usize| f32::from_le_bytes([record[k], record[k + 1], record[k + 2], record[k + 3]]);
        // The normal (bytes 0-11) is recomputed from the corners wherever it is needed.
        merged.add([0, 1, 2].map(|c| [0, 1, 2].map(|i| f(12 + 12 * c + 4 * i))));
    }
    merged.mesh
}

/// An ASCII STL, keywords in any case: `solid`, `facet normal`, `outer loop`, `vertex x y z`,
/// `endloop`, `endfacet`, `endsolid`. A facet of more than three vertices is split as a fan.
fn read_ascii(text: &str) -> Result<Mesh, String> {
    let mut merged = Merged::default();
    let mut facet: Option<(usize, Vec<[f32; 3]>)> = None;
    for (i, line) in text.lines().enumerate() {
        let tokens: Vec<&str> = line.split_whitespace().collect();
        let Some(keyword) = tokens.first().map(|k| k.to_ascii_lowercase()) else { continue };
        let at = i + 1;
        match (keyword.as_str(), &mut facet) {
            ("solid" | "endsolid", None) => {}
            ("facet", None) => facet = Some((at, Vec::new())),
            ("outer" | "endloop", Some(_)) => {}
            ("vertex", Some((_, corners))) => corners.push(vertex(&tokens, at)?),
            ("endfacet", Some((start, corners))) => {
                if corners.len() < 3 {
                    return Err(format!("line {start}: a facet of {} vertices (a triangle has 3)", corners.len()));
                }
                (2..corners.len()).for_each(|k| merged.add([corners[0], corners[k - 1], corners[k]]));
                facet = None;
            }
            _ => {
                let shown: String = line.trim().chars().take(60).collect();
                return Err(format!("line {at}: `{shown}` is not ASCII STL where {}", wanted_here(&facet)));
            }
        }
    }
    match facet {
        Some((start, _)) => Err(format!("truncated ASCII STL: it ends inside the facet begun on line {start}")),
        None => Ok(merged.mesh),
    }
}

/// What an ASCII STL may hold at a place: inside a facet or between facets.
fn wanted_here<T>(facet: &Option<T>) -> &'static str {
    match facet {
        Some(_) => "a facet's `vertex x y z` or `endfacet` is expected",
        None => "`facet normal`, `solid` or `endsolid` is expected",
    }
}

/// The point of a `vertex x y z` line.
fn vertex(tokens: &[&str], at: usize) -> Result<[f32; 3], String> {
    let numbers: Vec<f32> = tokens[1..].iter().filter_map(|t| t.parse().ok()).collect();
    match numbers[..] {
        [x, y, z] if tokens.len() == 4 => Ok([x, y, z]),
        _ => Err(format!("line {at}: `{}` is not `vertex x y z` with three numbers", tokens.join(" "))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A folder of its own for each test, removed when dropped.
    struct Folder(PathBuf);

    impl Folder {
        fn new(test: &str) -> Folder {
            let dir = std::env::temp_dir().join(format!("jawtrack-mesh-file-{test}-{}", std::process::id()));
            std::fs::create_dir_all(&dir).expect("a folder");
            Folder(dir)
        }

        fn file(&self, name: &str, bytes: &[u8]) -> PathBuf {
            let p = self.0.join(name);
            std::fs::write(&p, bytes).expect("written");
            p
        }
    }

    impl Drop for Folder {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// Two triangles of a 10 mm square, and the same as binary STL.
    fn square() -> (Mesh, Vec<u8>) {
        let mesh = Mesh {
            vertices: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(10.0, 0.0, 0.0),
                Point3::new(10.0, 10.0, 0.5),
                Point3::new(0.0, 10.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let mut binary = Vec::new();
        mesh.write_stl(&mut binary).expect("in memory");
        (mesh, binary)
    }

    const FACETS: &str = "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 10 0 0\n      \
                          vertex 10 10 0.5\n    endloop\n  endfacet\n  facet normal 0 0 1\n    outer loop\n      \
                          vertex 0 0 0\n      vertex 10 10 0.5\n      vertex 0 10 0\n    endloop\n  endfacet\n";

    #[test]
    fn an_empty_file_is_named_as_empty() {
        let dir = Folder::new("empty");
        for name in ["upper.stl", "upper.ply"] {
            let p = dir.file(name, b"");
            let err = load_mesh(&p).expect_err("empty");
            assert_eq!(err.to_string(), format!("{}: empty file (0 bytes): export or copy it again", p.display()));
        }
    }

    #[test]
    fn ascii_stl_reads_as_exporters_write_it_and_as_its_binary_twin() {
        let dir = Folder::new("ascii");
        let (mesh, binary) = square();
        let from_binary = load_mesh(&dir.file("binary.stl", &binary)).expect("binary");
        assert_eq!(from_binary, Mesh::load(&dir.0.join("binary.stl")).expect("as Mesh::load reads it"));
        assert_eq!(from_binary, mesh);
        let variants = [
            format!("solid named\n{FACETS}endsolid named\n"),
            // Without a name after `solid` (what `stl_io` took for binary: "failed to fill whole buffer").
            format!("solid\n{FACETS}endsolid\n"),
            format!("solid\r\n{}endsolid\r\n", FACETS.replace('\n', "\r\n")),
            format!("SOLID Scan\n{}ENDSOLID\n", FACETS.to_uppercase()),
            format!("  solid\n{FACETS}"),
        ];
        for (k, text) in variants.iter().enumerate() {
            let read = load_mesh(&dir.file(&format!("ascii{k}.stl"), text.as_bytes()));
            assert_eq!(read.expect("read"), mesh, "{text}");
        }
        // Two solids in one file: both kept.
        let two = format!("solid a\n{FACETS}endsolid a\nsolid b\n{FACETS}endsolid b\n");
        let read = load_mesh(&dir.file("two.stl", two.as_bytes())).expect("two solids");
        assert_eq!((read.vertices.len(), read.triangles.len()), (4, 4));
        // A binary STL whose header begins with "solid", as some exporters write it.
        let mut solid_header = binary.clone();
        solid_header[..11].copy_from_slice(b"solid scan ");
        assert_eq!(load_mesh(&dir.file("solid_header.stl", &solid_header)).expect("binary"), mesh);
    }

    #[test]
    fn a_cut_short_or_foreign_stl_says_what_is_wrong() {
        let dir = Folder::new("broken");
        let (_, binary) = square();
        let refused = |name: &str, bytes: &[u8]| {
            let p = dir.file(name, bytes);
            let err = load_mesh(&p).expect_err("refused").to_string();
            let prefix = format!("{}: not a readable STL mesh: ", p.display());
            assert!(err.starts_with(&prefix), "{err}");
            err[prefix.len()..].to_string()
        };
        assert_eq!(
            refused("cut.stl", &binary[..120]),
            "truncated binary STL: its header declares 2 triangles (184 bytes) but the file holds 120 bytes; export \
             or copy it again"
        );
        assert_eq!(
            refused("tiny.stl", &binary[..40]),
            "truncated binary STL: 40 bytes, shorter than the 84-byte header; export or copy it again"
        );
        let ascii = format!("solid\n{FACETS}endsolid\n");
        assert_eq!(
            refused("cut_ascii.stl", &ascii.as_bytes()[..60]),
            "truncated ASCII STL: it ends inside the facet begun on line 2"
        );
        assert_eq!(
            refused("typo.stl", ascii.replace("vertex 10 0 0", "vertx 10 0 0").as_bytes()),
            "line 5: `vertx 10 0 0` is not ASCII STL where a facet's `vertex x y z` or `endfacet` is expected"
        );
        assert_eq!(
            refused("comma.stl", ascii.replace("vertex 10 0 0", "vertex 10,5 0 0").as_bytes()),
            "line 5: `vertex 10,5 0 0` is not `vertex x y z` with three numbers"
        );
        assert!(refused("scan.stl", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").starts_with("the file is text but"));
    }

    #[test]
    fn a_mesh_without_area_is_refused_and_a_few_flat_triangles_are_not() {
        let dir = Folder::new("flat");
        let points = "solid\n  facet normal 0 0 0\n    outer loop\n      vertex 0 0 0\n      vertex 0 0 0\n      \
                      vertex 0 0 0\n    endloop\n  endfacet\n  facet normal 0 0 0\n    outer loop\n      vertex 5 5 \
                      5\n      vertex 5 5 5\n      vertex 5 5 5\n    endloop\n  endfacet\n  facet normal 0 0 0\n    \
                      outer loop\n      vertex 0 0 0\n      vertex 5 5 5\n      vertex 10 10 10\n    endloop\n  \
                      endfacet\nendsolid\n";
        let p = dir.file("cloud.stl", points.as_bytes());
        let err = load_mesh(&p).expect_err("no area");
        assert_eq!(
            err.to_string(),
            format!("{}: all 3 triangles have zero area: is it a point cloud or a broken export?", p.display())
        );
        let (mut mesh, _) = square();
        mesh.triangles.push([0, 0, 1]);
        let mut binary = Vec::new();
        mesh.write_stl(&mut binary).expect("in memory");
        let read = load_mesh(&dir.file("partly.stl", &binary)).expect("one flat triangle of three is fine");
        assert_eq!((read.triangles.len(), read.report().degenerate_triangles), (3, 1));
        let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                   element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n5 5 5\n10 10 10\n3 0 1 2\n";
        let p = dir.file("line.ply", ply.as_bytes());
        let err = load_mesh(&p).expect_err("collinear");
        assert_eq!(
            err.to_string(),
            format!("{}: its only triangle has zero area: is it a point cloud or a broken export?", p.display())
        );
    }
}
