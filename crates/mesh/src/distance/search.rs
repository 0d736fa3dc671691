//! The second half of a query: the exact nearest point, from the corner nodes' nearest
//! triangles and a descent over neighbouring triangles until none is nearer
//! ([`SurfaceIndex::search`]), and the read-ahead that lets a batch's searches fetch their
//! memory side by side ([`SurfaceIndex::warm`]).

use super::Nearest;
use super::grid::{NONE, SurfaceIndex};
use super::triangle::Feature;
use nalgebra::Point3;

/// An exact search still to do: the point and the nearest triangles of the grid nodes
/// around it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Search {
    pub(super) point: Point3<f64>,
    pub(super) candidates: [u32; 8],
}

impl SurfaceIndex {
    /// Reads the first memory that searching `search` needs and returns a value from it:
    /// done for every search of a batch before any is searched, so that the processor
    /// fetches them side by side instead of each search waiting for its own in turn.
    pub fn warm(&self, search: &Search) -> f64 {
        let g = &self.surface.geometry[search.candidates[0] as usize];
        g.plane[3] + g.corners[2].z
    }

    /// The second half of [`SurfaceIndex::find`]: the exact nearest point, from the corner
    /// nodes' nearest triangles and a descent over their neighbours.
    pub fn search(&self, search: &Search) -> Nearest {
        let (p, candidates) = (&search.point, &search.candidates);
        let mut best = (f64::INFINITY, NONE, *p, Feature::Face);
        for (k, &t) in candidates.iter().enumerate() {
            // Neighbouring nodes mostly share their nearest triangle: test each once.
            if !candidates[..k].contains(&t) && !self.surface.beyond_plane(t as usize, p, best.0) {
                let (d2, q, f) = self.surface.closest(t as usize, p);
                if d2 < best.0 || (d2 == best.0 && t < best.1) {
                    best = (d2, t, q, f);
                }
            }
        }
        // Descend over neighbouring triangles until none is nearer. Two cheap tests rule out
        // most neighbours without finding their closest point: a triangle whose own plane is
        // farther than the nearest point so far (one bending towards `p`), and a triangle with
        // no corner on `p`'s side of the plane through that point square to `p` (one bending
        // away), since the open ball about `p` through that point lies wholly on that side.
        // There is no descent at all where the surface around the nearest triangle is known
        // not to reach nearer ([`Surface::certainly_nearest`]).
        // Corners shared with the nearest triangle lie on the plane, up to rounding: a
        // nanometre's slack lets them count as on it, and costs at most a nanometre.
        let tangent = |best: &(f64, u32, Point3<f64>, Feature)| (p - best.2, 1e-9 * best.0.sqrt());
        while !self.surface.certainly_nearest(best.1 as usize, p, best.0, &best.2, best.3) {
            let mut improved = false;
            let (mut towards, mut slack) = tangent(&best);
            for &t in self.surface.neighbours(best.1 as usize) {
                if self.surface.beyond_plane(t as usize, p, best.0) {
                    continue;
                }
                if self.surface.geometry[t as usize].corners.iter().all(|c| (c - best.2).dot(&towards) <= slack) {
                    continue;
                }
                let (d2, q, f) = self.surface.closest(t as usize, p);
                if d2 < best.0 || (d2 == best.0 && t < best.1) {
                    best = (d2, t, q, f);
                    (towards, slack) = tangent(&best);
                    improved = true;
                }
            }
            if !improved {
                break;
            }
        }
        let (d2, t, c, feature) = best;
        self.surface.signed(t as usize, p, d2, c, feature)
    }
}
