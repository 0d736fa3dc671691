//! The first half of a query, on the grid alone. [`SurfaceIndex::screen`] settles what the
//! live maps or the interpolated corner nodes can settle (far, or approximate) and leaves the
//! rest as a [`Search`]; [`SurfaceIndex::screen_many`] does so for a batch in stages,
//! [`SurfaceIndex::far_from`] for a whole ball at once; [`SurfaceIndex::find`],
//! [`SurfaceIndex::lookup`] and [`SurfaceIndex::nearest`] put the two halves together.

use super::Nearest;
use super::grid::{BLOCK, NODES, NONE, SUB, SurfaceIndex, extent};
use super::search::Search;
use nalgebra::{Point3, Vector3};

/// What a query found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lookup {
    /// Outside the band the index covers, or outside the asked-for range.
    Far,
    /// Beyond the refinement limit: the grid's interpolated signed distance (mm), good to
    /// about a micron on smooth surfaces.
    Approximate(f64),
    /// The exact nearest surface point.
    Exact(Nearest),
}

/// What [`SurfaceIndex::screen`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Screen {
    /// Settled by the grid alone: far or approximate.
    Answered(Lookup),
    /// An exact search is needed.
    Search(Search),
}

impl SurfaceIndex {
    /// Where `p` is in units of cells from the grid's first node.
    fn grid_coordinates(&self, p: &Point3<f64>) -> Vector3<f64> {
        // A multiplication: a division here was a tenth of a lookup's time.
        (p.coords - self.origin) * self.per_cell
    }

    /// Whether the sub-blocks' liveness holds for lookups in `lo..=hi`.
    fn focused_on(&self, lo: f64, hi: f64) -> bool {
        lo >= -self.below && hi <= self.focus
    }

    /// Whether [`SurfaceIndex::lookup`] for the range `lo..=hi` would answer [`Lookup::Far`]
    /// at every point within `radius` mm of `centre`: the range is within the focus and all
    /// those points lie outside the grid or in sub-blocks that are not live.
    pub fn far_from(&self, centre: &Point3<f64>, radius: f64, (lo, hi): (f64, f64)) -> bool {
        if !self.focused_on(lo, hi) {
            return false;
        }
        let g = self.grid_coordinates(centre);
        // A millionth of a cell more covers the rounding of moving and gridding the points, so
        // that a point on a sub-block's boundary is never counted on its nearer side.
        let r = radius * self.per_cell + 1e-6;
        let mut reach = 0usize;
        for k in 0..3 {
            // Wholly before or past the grid on one axis: every lookup there answers Far.
            if g[k] + r < 0.0 || g[k] - r >= (self.nodes[k] - 1) as f64 {
                return true;
            }
            if !(g[k] >= 0.0 && g[k] < self.nodes[k] as f64) {
                return false;
            }
            // A point's cell is named by its lowest node, whose sub-block is at most this many
            // sub-blocks from the centre's.
            let centre_sub = g[k] as usize / SUB;
            let low = (g[k] - r).max(0.0) as usize / SUB;
            let high = (g[k] + r) as usize / SUB;
            reach = reach.max(centre_sub - low).max(high - centre_sub);
        }
        let sub = self.sub_block([g.x as usize, g.y as usize, g.z as usize]);
        self.clearance.get(sub).is_some_and(|&c| c as usize > reach)
    }

    /// Whether the distance field is continuous across a cell with corner distances `d`: it
    /// changes by at most the cell's diagonal across a cell; more means the sign jumps there
    /// (beside an open scan's rim), where interpolating would be wrong.
    pub(super) fn continuous(d: &[f64; 8], cell: f64) -> bool {
        let (min, max) = extent(d);
        max - min <= 2.0 * cell
    }

    /// How far past a range's ends the interpolation must reach before it alone decides:
    /// borderline points are found exactly.
    fn margin(&self) -> f64 {
        0.25 * self.cell
    }

    /// Whether a cell with corner distances `d` settles a lookup in `lo..=hi` as far without
    /// an exact search: a corner out of the band, or a continuous field whose interpolation,
    /// known to lie in `low..=high`, is beyond the range.
    pub(super) fn decides_far(
        &self,
        d: &[f64; 8],
        continuous: bool,
        (low, high): (f64, f64),
        lo: f64,
        hi: f64,
    ) -> bool {
        d.iter().any(|x| x.is_nan()) || (continuous && (high < lo - self.margin() || low > hi + self.margin()))
    }

    /// The nearest surface point to `p` if its signed distance is within the band.
    pub fn nearest(&self, p: &Point3<f64>) -> Option<Nearest> {
        match self.lookup(p, -self.below, self.above, self.above) {
            Lookup::Exact(n) => Some(n),
            _ => None,
        }
    }

    /// The signed distance of `p` if it lies in `lo..=hi` (mm, within the band): exact up to
    /// `exact_up_to`, the grid's interpolation above it.
    pub fn lookup(&self, p: &Point3<f64>, lo: f64, hi: f64, exact_up_to: f64) -> Lookup {
        match self.find(p, lo, hi, exact_up_to) {
            Lookup::Exact(n) if n.distance < lo || n.distance > hi => Lookup::Far,
            found => found,
        }
    }

    /// The same as [`SurfaceIndex::lookup`], except that a point the grid could not rule out
    /// is answered exactly even when it then lies outside `lo..=hi`: its distance costs
    /// nothing more there, and a caller may need it.
    pub fn find(&self, p: &Point3<f64>, lo: f64, hi: f64, exact_up_to: f64) -> Lookup {
        match self.screen(p, lo, hi, exact_up_to) {
            Screen::Answered(answer) => answer,
            Screen::Search(search) => Lookup::Exact(self.search(&search)),
        }
    }

    /// The first half of [`SurfaceIndex::find`]: what the grid alone settles, or the search
    /// left to do. A batch of points screened first and searched after lets the memory the
    /// searches read be fetched in parallel ([`SurfaceIndex::warm`]).
    pub fn screen(&self, p: &Point3<f64>, lo: f64, hi: f64, exact_up_to: f64) -> Screen {
        const FAR: Screen = Screen::Answered(Lookup::Far);
        let Some((g, i)) = self.cell_of(p) else { return FAR };
        let sub = self.sub_block(i);
        let focused = self.focused_on(lo, hi);
        if focused && self.live[sub / 64] & (1 << (sub % 64)) == 0 {
            return FAR;
        }
        let (b, local) = self.locate(i);
        let Some(&k) = self.block_of.get(b) else { return FAR };
        if k == NONE || (focused && self.live_cells[k as usize][local / 64] & (1 << (local % 64)) == 0) {
            return FAR;
        }
        self.screen_cell(p, &g, i, lo, hi, exact_up_to)
    }

    /// The same as [`SurfaceIndex::screen`] for many points, calling `answer` with the index
    /// of each point not settled as far, and what screening found, in the points' order. For
    /// a range within the focus the grid is read in stages over chunks of points, each
    /// stage's reads independent of one another, so that the processor fetches them side by
    /// side instead of each point waiting for its own in turn.
    pub fn screen_many(
        &self,
        points: &[Point3<f64>],
        lo: f64,
        hi: f64,
        exact_up_to: f64,
        mut answer: impl FnMut(usize, Screen),
    ) {
        if !self.focused_on(lo, hi) {
            for (j, p) in points.iter().enumerate() {
                match self.screen(p, lo, hi, exact_up_to) {
                    Screen::Answered(Lookup::Far) => {}
                    found => answer(j, found),
                }
            }
            return;
        }
        const CHUNK: usize = 64;
        for (c, chunk) in points.chunks(CHUNK).enumerate() {
            // Points in live sub-blocks: (index in chunk, block position, place in block).
            let mut waiting = [(0u32, 0u32, 0u32); CHUNK];
            let mut n = 0;
            for (j, p) in chunk.iter().enumerate() {
                if let Some((_, i)) = self.cell_of(p) {
                    let sub = self.sub_block(i);
                    if self.live[sub / 64] & (1 << (sub % 64)) != 0 {
                        let (b, local) = self.locate(i);
                        waiting[n] = (j as u32, b as u32, local as u32);
                        n += 1;
                    }
                }
            }
            let mut blocks = [NONE; CHUNK];
            for (k, &(_, b, _)) in blocks.iter_mut().zip(&waiting[..n]) {
                *k = self.block_of[b as usize];
            }
            // Those in live cells, now with their stored block.
            let mut m = 0;
            for s in 0..n {
                let (j, _, local) = waiting[s];
                let k = blocks[s];
                if k != NONE && self.live_cells[k as usize][local as usize / 64] & (1 << (local % 64)) != 0 {
                    waiting[m] = (j, k, local);
                    m += 1;
                }
            }
            // A cell's corners lie in two z-layers of its block, the second a layer up.
            let warm: i64 = waiting[..m]
                .iter()
                .map(|&(_, k, local)| {
                    let at = k as usize * NODES + local as usize;
                    let up = (at + BLOCK * BLOCK).min(self.node_distances.len() - 1);
                    i64::from(self.node_distances[at])
                        + i64::from(self.node_triangles[at])
                        + i64::from(self.node_distances[up])
                        + i64::from(self.node_triangles[up])
                })
                .sum();
            std::hint::black_box(warm);
            for &(j, _, _) in &waiting[..m] {
                let p = &chunk[j as usize];
                if let Some((g, i)) = self.cell_of(p) {
                    match self.screen_cell(p, &g, i, lo, hi, exact_up_to) {
                        Screen::Answered(Lookup::Far) => {}
                        found => answer(c * CHUNK + j as usize, found),
                    }
                }
            }
        }
    }

    /// Where `p` is in grid units and the lowest node of its cell, if the cell is in the grid.
    fn cell_of(&self, p: &Point3<f64>) -> Option<(Vector3<f64>, [usize; 3])> {
        let g = self.grid_coordinates(p);
        if !(g.x >= 0.0 && g.y >= 0.0 && g.z >= 0.0) {
            return None;
        }
        // Through u32, which converts from f64 in fewer instructions than usize; a point too
        // far for it saturates, and is then past the grid's end.
        let i = [g.x as u32 as usize, g.y as u32 as usize, g.z as u32 as usize];
        if i[0] + 1 >= self.nodes[0] || i[1] + 1 >= self.nodes[1] || i[2] + 1 >= self.nodes[2] {
            return None;
        }
        Some((g, i))
    }

    /// The rest of [`SurfaceIndex::screen`] once the cell, lowest node `i`, is known to
    /// matter: reads its corners and interpolates.
    fn screen_cell(
        &self,
        p: &Point3<f64>,
        g: &Vector3<f64>,
        i: [usize; 3],
        lo: f64,
        hi: f64,
        exact_up_to: f64,
    ) -> Screen {
        const FAR: Screen = Screen::Answered(Lookup::Far);
        let Some(at) = self.corners_at(i) else { return FAR };
        let mut d = [0.0; 8];
        for (slot, &k) in d.iter_mut().zip(&at) {
            *slot = self.distance_at(k);
        }
        let f = Vector3::new(g.x - i[0] as f64, g.y - i[1] as f64, g.z - i[2] as f64);
        let (x0, y0, z0) = (1.0 - f.x, 1.0 - f.y, 1.0 - f.z);
        let interpolated = z0 * (y0 * (x0 * d[0] + f.x * d[1]) + f.y * (x0 * d[2] + f.x * d[3]))
            + f.z * (y0 * (x0 * d[4] + f.x * d[5]) + f.y * (x0 * d[6] + f.x * d[7]));
        let continuous = Self::continuous(&d, self.cell);
        if self.decides_far(&d, continuous, (interpolated, interpolated), lo, hi) {
            return FAR;
        }
        if continuous && interpolated > exact_up_to + self.margin() {
            return Screen::Answered(Lookup::Approximate(interpolated));
        }
        let mut candidates = [NONE; 8];
        for (slot, &k) in candidates.iter_mut().zip(&at) {
            *slot = self.node_triangles[k];
        }
        Screen::Search(Search { point: *p, candidates })
    }
}
