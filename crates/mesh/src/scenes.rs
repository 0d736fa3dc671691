//! Test scenes with known answers, and synthetic arches of any size for benchmarks.
//!
//! - a flat square patch and a sphere pressed into it: the penetration depth, the cap area on
//!   the sphere and the disc area on the patch are known in closed form;
//! - a pair of horseshoe "arches" with cusps, the lower one a wavy copy of the upper, so that
//!   much of their occlusal surfaces is within a fraction of a millimetre: alone, a worst
//!   case for the contact query; on crowns with buccal and lingual walls, closer to a scan.

use crate::Mesh;
use nalgebra::Point3;

/// A flat square of side `size` (mm) at height `z`, centred on the z axis, `n` × `n` cells,
/// facing down (−z) when `facing_down`, else up.
pub fn patch(size: f64, n: usize, z: f64, facing_down: bool) -> Mesh {
    grid(n, n, facing_down, |i, j| {
        Point3::new(size * (i as f64 / n as f64 - 0.5), size * (j as f64 / n as f64 - 0.5), z)
    })
}

/// A UV sphere of radius `r` (mm) about `centre`, normals outward; `n` latitude bands.
pub fn sphere(centre: Point3<f64>, r: f64, n: usize) -> Mesh {
    let (rings, segments) = (n, 2 * n);
    let mut vertices = vec![centre + nalgebra::Vector3::new(0.0, 0.0, r)];
    for i in 1..rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            vertices.push(
                centre + nalgebra::Vector3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()) * r,
            );
        }
    }
    vertices.push(centre - nalgebra::Vector3::new(0.0, 0.0, r));
    let bottom = (vertices.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * segments + j % segments) as u32;
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
        triangles.push([bottom, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    Mesh { vertices, triangles }
}

/// A synthetic upper and lower arch of about `triangles` triangles each, in occlusion: the
/// upper occlusal surface (cusps 0.8 mm high) faces down and the lower one faces up,
/// following it at a gap that varies smoothly from 1.6 mm to a 0.1 mm interpenetration at
/// a few contacts along the arch. Only the occlusal surfaces: a worst case, with most of
/// both surfaces within reach of the other.
pub fn arch_pair(triangles: usize) -> (Mesh, Mesh) {
    arch_pair_with_walls(triangles, 0.0)
}

/// The same occlusal surfaces carried on crowns: buccal and lingual walls `wall_mm` high
/// run from the occlusal edges away from the other arch (up for the upper, down for the
/// lower), as on an intra-oral scan, where most of the surface is far from the other arch.
/// The triangles are spread evenly over the whole surface.
pub fn arch_pair_with_walls(triangles: usize, wall_mm: f64) -> (Mesh, Mesh) {
    // A horseshoe about 50 mm wide and 45 mm deep, 10 mm across its occlusal surface.
    let section = 10.0 + 2.0 * wall_mm.max(0.0);
    // Cells about twice as long along the arch as across.
    let across = (triangles as f64 / 2.0 * section / 75.0).sqrt().round().max(2.0) as usize;
    let along = (triangles / 2 / across).max(2);
    // `away` is +1 for the upper arch (its walls rise) and -1 for the lower.
    let place = |i: usize, j: usize, away: f64| {
        let s = i as f64 / along as f64;
        // Across the section: the occlusal surface for |u| <= 5, the walls beyond.
        let u = section * (j as f64 / across as f64 - 0.5);
        let v = u.clamp(-5.0, 5.0);
        let up = u.abs() - 5.0;
        // Half an ellipse (radii 25 and 45 mm, radius of curvature at least 13.9 mm, so the
        // 5 mm offset to either side never folds the surface).
        let angle = std::f64::consts::PI * (s - 0.5) * 1.1;
        let (cx, cy) = (25.0 * angle.sin(), 45.0 * angle.cos() - 25.0);
        let normal = nalgebra::Vector2::new(45.0 * angle.sin(), 25.0 * angle.cos()).normalize();
        let (nx, ny) = (normal.x, normal.y);
        let arc = s * 120.0;
        let cusp = 0.8 * (arc * 0.9).sin() * (v * 0.6).cos();
        let closeness = (arc * 0.2 + 1.0).sin() * (v * 0.25).cos();
        let gap = 0.75 - 0.85 * closeness;
        let (lateral, height) = if up > 0.0 { (v + v.signum() * 0.15 * up, away * up) } else { (v, 0.0) };
        let z = if away > 0.0 { cusp } else { cusp - gap };
        Point3::new(cx + nx * lateral, cy + ny * lateral, z + height)
    };
    let upper = grid(along, across, true, |i, j| place(i, j, 1.0));
    let lower = grid(along, across, false, |i, j| place(i, j, -1.0));
    (upper, lower)
}

/// A height-field style grid of `nu` × `nv` cells through `at(i, j)`, two triangles a cell.
fn grid(nu: usize, nv: usize, facing_down: bool, at: impl Fn(usize, usize) -> Point3<f64>) -> Mesh {
    let mut vertices = Vec::with_capacity((nu + 1) * (nv + 1));
    for j in 0..=nv {
        for i in 0..=nu {
            vertices.push(at(i, j));
        }
    }
    let id = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    let mut triangles = Vec::with_capacity(2 * nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if facing_down {
                triangles.push([a, c, b]);
                triangles.push([a, d, c]);
            } else {
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
    }
    Mesh { vertices, triangles }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_face_the_way_they_say() {
        let down = patch(10.0, 4, 0.0, true);
        assert!(down.area_normal(0).z < 0.0);
        let ball = sphere(Point3::origin(), 2.0, 16);
        let r = ball.report();
        assert_eq!((r.boundary_edges, r.non_manifold_edges, r.components), (0, 0, 1));
        // Outward normals: the first triangle is at the top.
        assert!(ball.area_normal(0).z > 0.0);
        let (upper, lower) = arch_pair(20_000);
        assert!(upper.triangles.len().abs_diff(20_000) < 1000, "{}", upper.triangles.len());
        assert!(upper.area_normal(0).z < 0.0 && lower.area_normal(0).z > 0.0);
        let extent = {
            let [lo, hi] = upper.bounds();
            hi - lo
        };
        assert!(extent.x > 40.0 && extent.y > 30.0, "{extent}");
        // With walls: as many triangles, still one consistently oriented sheet, 8 mm taller.
        let (upper, lower) = arch_pair_with_walls(20_000, 8.0);
        assert!(upper.triangles.len().abs_diff(20_000) < 1000, "{}", upper.triangles.len());
        let r = upper.report();
        assert_eq!((r.non_manifold_edges, r.components, r.boundary_loops), (0, 1, 1));
        assert!(
            upper.area_normal(upper.triangles.len() / 2).z < 0.0
                && lower.area_normal(lower.triangles.len() / 2).z > 0.0
        );
        let [lo, hi] = upper.bounds();
        assert!(hi.z - lo.z > 8.0, "{}", hi.z - lo.z);
    }
}
