//! The checks a scan deserves before it is trusted: [`Mesh::validate`] refuses empty or
//! non-finite data, indices past the vertices and a size that says the units are not
//! millimetres; [`Mesh::report`] counts degenerate triangles, non-manifold edges, boundary
//! loops (holes; an intra-oral scan is an open surface, so at least one loop is normal) and
//! connected components.

use crate::{Mesh, MeshError};
use std::collections::HashMap;

/// The smallest and largest extent (mm) a dental scan or harness can have: below, the file is
/// in metres (an arch would be 0.06 long); above, in microns.
pub const PLAUSIBLE_EXTENT_MM: (f64, f64) = (1.0, 1000.0);

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

/// One line: counts, size (mm), area (mm²) and the checks, e.g. "7082 vertices, 14160
/// triangles, 6.0 × 6.0 × 6.0 mm, 113 mm², 1 component, 0 boundary loops, 0 degenerate
/// triangles, 0 non-manifold edges".
impl std::fmt::Display for MeshReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [lo, hi] = self.bounds;
        let (v, t) = (self.vertices, self.triangles);
        write!(
            f,
            "{v} vertices, {t} triangles, {:.1} × {:.1} × {:.1} mm",
            hi[0] - lo[0],
            hi[1] - lo[1],
            hi[2] - lo[2]
        )?;
        write!(f, ", {:.0} mm²", self.area_mm2)?;
        let counts = [
            (self.components, "component"),
            (self.boundary_loops, "boundary loop"),
            (self.degenerate_triangles, "degenerate triangle"),
            (self.non_manifold_edges, "non-manifold edge"),
        ];
        for (n, what) in counts {
            write!(f, ", {n} {what}{}", if n == 1 { "" } else { "s" })?;
        }
        Ok(())
    }
}

impl Mesh {
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
        // The surface's size, not the vertex list's: a vertex no triangle uses (a stray point
        // in a scan file) must not make a microscopic surface look millimetre-sized.
        let mut used = self.triangles.iter().flatten().map(|&i| self.vertices[i as usize].coords);
        let first = used.next().unwrap_or_default();
        let (lo, hi) = used.fold((first, first), |(lo, hi), p| (lo.inf(&p), hi.sup(&p)));
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
}

/// Union–find over indices `0..n`, for boundary loops and components here and for grouping
/// contact regions in `jawtrack-occlusion`. Each set's representative is its smallest index.
#[derive(Debug, Clone)]
pub struct DisjointSets(Vec<usize>);

impl DisjointSets {
    /// `n` singleton sets.
    pub fn new(n: usize) -> Self {
        DisjointSets((0..n).collect())
    }

    /// The representative of `i`'s set (compressing the path on the way).
    pub fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }

    /// Merges the sets of `a` and `b`.
    pub fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb)] = ra.min(rb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

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
    fn a_microscopic_surface_is_refused_whatever_stray_vertex_the_file_holds() {
        // Found by the `ply` fuzz target: a 10 mm vertex no triangle used made a surface
        // 1e-40 mm across pass as millimetre-sized.
        let mut tiny = square(1e-40);
        tiny.vertices.push(Point3::new(10.0, 0.0, 0.0));
        let err = tiny.validate("scan.ply").expect_err("the surface is not millimetre-sized").to_string();
        assert!(err.contains("metres"), "{err}");
        let mut fine = square(10.0);
        fine.vertices.push(Point3::new(1e-40, 0.0, 0.0));
        fine.validate("scan.ply").expect("a stray vertex does not spoil a good surface");
    }

    #[test]
    fn a_closed_cube_has_no_rim() {
        let r = crate::tests::cube().report();
        assert_eq!((r.boundary_edges, r.boundary_loops, r.components, r.non_manifold_edges), (0, 0, 1, 0));
    }

    #[test]
    fn a_report_reads_as_one_line() {
        let line = square(10.0).report().to_string();
        let checks = "1 component, 1 boundary loop, 0 degenerate triangles, 0 non-manifold edges";
        assert_eq!(line, format!("4 vertices, 2 triangles, 10.0 × 10.0 × 0.0 mm, 100 mm², {checks}"));
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
