//! Exact signed distance from a point to a triangle surface, within a reach, fast enough to
//! ask for every vertex of an arch at every frame.
//!
//! The sign comes from angle-weighted pseudo-normals (Bærentzen & Aanæs): positive in front
//! of the surface (outside the tooth), negative behind it. On an open scan "behind" is only
//! meaningful near the surface, which is why every query has a reach, and a point off to the
//! side of the scan's rim counts as outside.
//!
//! [`SurfaceIndex`] is a narrow-band signed-distance grid (sparse 8³ blocks) whose nodes hold
//! their exact signed distance and nearest triangle. Most vertices of an arch are out of
//! range: a map of 4³-cell sub-blocks, made once, rejects most of those without reading the
//! grid, and a bit per cell, one cache line per block, many of the rest; for the others, a
//! query interpolates the eight nodes around the point to decide
//! cheaply whether it is in range, and only then finds the exact nearest point: the corner
//! nodes' nearest triangles, then a descent over neighbouring triangles until none is
//! nearer. That is the brute-force
//! answer ([`nearest_brute_force`]) wherever the nearest triangle is reachable by descent
//! from the nodes' ones, which the tests check on every test scene; it is not a proof for
//! arbitrary meshes.

mod bend;
mod brute_force;
mod grid;
mod screen;
mod search;
mod surface;
#[cfg(test)]
mod tests;
mod triangle;

pub use brute_force::nearest_brute_force;
pub use grid::SurfaceIndex;
pub use screen::{Lookup, Screen};
pub use search::Search;
pub use surface::Surface;

use nalgebra::{Point3, Vector3};

/// The closest point of the surface to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nearest {
    /// Signed distance (mm): positive in front of the surface, negative behind it.
    pub distance: f64,
    /// The closest surface point.
    pub point: Point3<f64>,
    /// The triangle it lies on.
    pub triangle: u32,
    /// Unit outward normal at the closest feature (face, edge or vertex pseudo-normal).
    pub normal: Vector3<f64>,
}
