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
mod surface;
#[cfg(test)]
mod tests;
mod triangle;

pub use brute_force::nearest_brute_force;
pub use surface::Surface;

use crate::mesh::Mesh;
use nalgebra::{Point3, Vector3};
use triangle::Feature;

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

/// Nodes per block edge of the sparse grid.
const BLOCK: usize = 8;
/// Cells per sub-block edge: the grain at which far regions are known in advance.
const SUB: usize = 4;
const NODES: usize = BLOCK * BLOCK * BLOCK;
const NONE: u32 = u32::MAX;
/// A node outside the band.
const OUT_OF_BAND: i16 = i16::MIN;
/// Offsets of a cell's eight corners from its lowest one within a block, x fastest.
const CORNER_OFFSETS: [usize; 8] =
    [0, 1, BLOCK, BLOCK + 1, BLOCK * BLOCK, BLOCK * BLOCK + 1, BLOCK * BLOCK + BLOCK, BLOCK * BLOCK + BLOCK + 1];

/// The least and greatest of `d`, passing over NaN.
fn extent(d: &[f64; 8]) -> (f64, f64) {
    d.iter().fold((d[0], d[0]), |(lo, hi), &x| (lo.min(x), hi.max(x)))
}

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

/// An exact search still to do: the point and the nearest triangles of the grid nodes
/// around it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Search {
    point: Point3<f64>,
    candidates: [u32; 8],
}

/// A narrow-band signed-distance grid over a surface: each node holds its exact signed
/// distance and nearest triangle. A query interpolates the grid to decide whether the point
/// is in the range asked for, then finds the exact nearest point from the corner nodes'
/// nearest triangles and a descent over their neighbours.
#[derive(Debug, Clone)]
pub struct SurfaceIndex {
    surface: Surface,
    below: f64,
    above: f64,
    /// The top of the ranges that sub-blocks are judged for (mm, within the band).
    focus: f64,
    cell: f64,
    /// The inverse of `cell`.
    per_cell: f64,
    origin: Vector3<f64>,
    /// Nodes along each axis.
    nodes: [usize; 3],
    /// Blocks along each axis.
    blocks: [usize; 3],
    /// Per block position, its index among the stored blocks or [`NONE`].
    block_of: Vec<u32>,
    /// Per node of the stored blocks (block `k`'s nodes at `k * NODES..`), its signed
    /// distance in units of `quantum` ([`OUT_OF_BAND`] outside the band): apart from the
    /// triangles, and small, because most queries read only these and memory is their cost.
    node_distances: Vec<i16>,
    /// Millimetres per unit of `node_distances`: the band over the range of an `i16`, some
    /// tens of nanometres.
    quantum: f64,
    /// Per node of the stored blocks, its nearest triangle or [`NONE`].
    node_triangles: Vec<u32>,
    /// Sub-blocks ([`SUB`]³ cells, named by their lowest node) along each axis.
    subs: [usize; 3],
    /// Per sub-block, how many sub-blocks away (Chebyshev, at most 255) the nearest live one
    /// is: 0 for a live one, one holding a cell where a lookup within `-below..=focus` may
    /// answer other than [`Lookup::Far`]. Rejects far points, and whole clusters of them, at
    /// once.
    clearance: Vec<u8>,
    /// Per sub-block, one bit: whether it is live (its clearance is 0), 64 to a word so that
    /// the test each lookup makes stays in cache.
    live: Vec<u64>,
    /// Per stored block, one bit per cell named by its lowest node (a word per z-layer, x
    /// fastest): whether the cell is live. In one cache line per block, it rejects the points
    /// in dead cells of live sub-blocks, half of those the grid is read for, without reading
    /// it.
    live_cells: Vec<[u64; BLOCK]>,
}

// A word of `live_cells` per z-layer of a block.
const _: () = assert!(NODES == 64 * BLOCK);

impl SurfaceIndex {
    /// Indexes `mesh` for exact queries out to `reach` mm on either side of the surface.
    pub fn new(mesh: &Mesh, reach: f64) -> Self {
        let cell = (reach / 10.0).clamp(0.05, 0.3);
        Self::with_band(mesh, reach, reach, cell)
    }

    /// Indexes `mesh` for points from `below` mm behind the surface to `above` mm in front of
    /// it, with grid nodes `cell` mm apart.
    pub fn with_band(mesh: &Mesh, below: f64, above: f64, cell: f64) -> Self {
        Self::with_focus(mesh, below, above, cell, above)
    }

    /// The same, with lookups for ranges within `-below..=focus` made fastest: far points
    /// for them, and clusters of such points ([`SurfaceIndex::far_from`]), are rejected
    /// without reading the grid.
    pub fn with_focus(mesh: &Mesh, below: f64, above: f64, cell: f64, focus: f64) -> Self {
        let surface = Surface::new(mesh);
        let (below, above, cell) = (below.max(0.0), above.max(0.0), cell.max(1e-3));
        let focus = focus.clamp(-below, above);
        let margin = below.max(above) + 3.0 * cell;
        let [lo, hi] = mesh.bounds();
        let origin = lo - Vector3::repeat(margin);
        let span = (hi - lo + Vector3::repeat(2.0 * margin)) / cell;
        let nodes = [0, 1, 2].map(|k| span[k].ceil().max(1.0) as usize + 2);
        let blocks = nodes.map(|n| n.div_ceil(BLOCK));
        let mut index = SurfaceIndex {
            surface,
            below,
            above,
            focus,
            cell,
            per_cell: 1.0 / cell,
            origin,
            nodes,
            blocks,
            block_of: vec![NONE; blocks[0] * blocks[1] * blocks[2]],
            node_distances: Vec::new(),
            quantum: (below.max(above) + 3.0 * cell) / f64::from(i16::MAX - 1),
            node_triangles: Vec::new(),
            subs: nodes.map(|n| n.div_ceil(SUB)),
            clearance: Vec::new(),
            live: Vec::new(),
            live_cells: Vec::new(),
        };
        index.fill();
        index.live_cells = index.live_cells();
        index.clearance = index.sub_block_clearance();
        index.live = vec![0; index.clearance.len().div_ceil(64)];
        for (k, _) in index.clearance.iter().enumerate().filter(|(_, c)| **c == 0) {
            index.live[k / 64] |= 1 << (k % 64);
        }
        index
    }

    /// Per stored block, which cells are live: their eight corners are in the band and
    /// [`SurfaceIndex::decides_far`] does not settle them for `-below..=focus`.
    fn live_cells(&self) -> Vec<[u64; BLOCK]> {
        let mut cells = vec![[0u64; BLOCK]; self.node_triangles.len() / NODES];
        for (i, k, local) in self.stored_cells() {
            if let Some(d) = self.corner_distances(i) {
                // Interpolation stays between the corners' least and greatest values.
                if !self.decides_far(&d, Self::continuous(&d, self.cell), extent(&d), -self.below, self.focus) {
                    cells[k][local / 64] |= 1 << (local % 64);
                }
            }
        }
        cells
    }

    /// Every cell named by a node of a stored block: its lowest node, the block's place
    /// among the stored ones and the node's within the block.
    fn stored_cells(&self) -> impl Iterator<Item = ([usize; 3], usize, usize)> + '_ {
        let [bx, by, _] = self.blocks;
        self.block_of.iter().enumerate().filter(|(_, k)| **k != NONE).flat_map(move |(b, &k)| {
            let first = [b % bx, (b / bx) % by, b / (bx * by)].map(|x| x * BLOCK);
            (0..NODES).filter_map(move |local| {
                let i =
                    [first[0] + local % BLOCK, first[1] + (local / BLOCK) % BLOCK, first[2] + local / (BLOCK * BLOCK)];
                (0..3).all(|a| i[a] + 1 < self.nodes[a]).then_some((i, k as usize, local))
            })
        })
    }

    /// Which sub-blocks are live: hold a live cell.
    fn live_sub_blocks(&self) -> Vec<bool> {
        let mut live = vec![false; self.subs[0] * self.subs[1] * self.subs[2]];
        for (i, k, local) in self.stored_cells() {
            if self.live_cells[k][local / 64] & (1 << (local % 64)) != 0 {
                live[self.sub_block(i)] = true;
            }
        }
        live
    }

    /// The Chebyshev distance, in sub-blocks, from each sub-block to the nearest live one, by
    /// a breadth-first sweep outward from the live ones.
    fn sub_block_clearance(&self) -> Vec<u8> {
        let [sx, sy, sz] = self.subs;
        let mut clearance: Vec<u8> = self.live_sub_blocks().iter().map(|&l| if l { 0 } else { u8::MAX }).collect();
        let mut frontier: Vec<usize> = (0..clearance.len()).filter(|&b| clearance[b] == 0).collect();
        let mut level = 0u8;
        while !frontier.is_empty() && level < u8::MAX - 1 {
            level += 1;
            let mut next = Vec::new();
            for b in frontier {
                let (x, y, z) = (b % sx, (b / sx) % sy, b / (sx * sy));
                for dz in z.saturating_sub(1)..=(z + 1).min(sz - 1) {
                    for dy in y.saturating_sub(1)..=(y + 1).min(sy - 1) {
                        for dx in x.saturating_sub(1)..=(x + 1).min(sx - 1) {
                            let n = (dz * sy + dy) * sx + dx;
                            if clearance[n] > level {
                                clearance[n] = level;
                                next.push(n);
                            }
                        }
                    }
                }
            }
            frontier = next;
        }
        clearance
    }

    /// Where `p` is in units of cells from the grid's first node.
    fn grid_coordinates(&self, p: &Point3<f64>) -> Vector3<f64> {
        // A multiplication: a division here was a tenth of a lookup's time.
        (p.coords - self.origin) * self.per_cell
    }

    /// Whether the sub-blocks' liveness holds for lookups in `lo..=hi`.
    fn focused_on(&self, lo: f64, hi: f64) -> bool {
        lo >= -self.below && hi <= self.focus
    }

    /// The sub-block holding the cell whose lowest node is `i`.
    fn sub_block(&self, i: [usize; 3]) -> usize {
        ((i[2] / SUB) * self.subs[1] + i[1] / SUB) * self.subs[0] + i[0] / SUB
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

    /// Computes the nodes: exactly near each triangle, then spread outward through the band,
    /// each node trying its neighbours' nearest triangles.
    fn fill(&mut self) {
        let mut queue = std::collections::VecDeque::new();
        let seed = 1.5 * self.cell;
        for t in 0..self.surface.len() {
            let corners = self.surface.geometry[t].corners;
            let (mut lo, mut hi) = (corners[0].coords, corners[0].coords);
            for c in &corners[1..] {
                lo = lo.inf(&c.coords);
                hi = hi.sup(&c.coords);
            }
            let first = ((lo - Vector3::repeat(seed) - self.origin) / self.cell).map(|x| x.ceil().max(0.0) as usize);
            let last = ((hi + Vector3::repeat(seed) - self.origin) / self.cell).map(|x| x.floor().max(0.0) as usize);
            for z in first.z..=last.z.min(self.nodes[2] - 1) {
                for y in first.y..=last.y.min(self.nodes[1] - 1) {
                    for x in first.x..=last.x.min(self.nodes[0] - 1) {
                        if self.offer([x, y, z], t as u32) {
                            queue.push_back([x, y, z]);
                        }
                    }
                }
            }
        }
        while let Some(node) = queue.pop_front() {
            let Some((_, t)) = self.node(node) else { continue };
            for (axis, step) in [(0, -1i64), (0, 1), (1, -1), (1, 1), (2, -1), (2, 1)] {
                let next = node[axis] as i64 + step;
                if next < 0 || next >= self.nodes[axis] as i64 {
                    continue;
                }
                let mut m = node;
                m[axis] = next as usize;
                if self.offer(m, t) {
                    queue.push_back(m);
                }
            }
        }
    }

    /// Stores triangle `t` at `node` if it is nearer than what the node holds and the node is
    /// in the band; says whether it did.
    fn offer(&mut self, node: [usize; 3], t: u32) -> bool {
        let p = self.position(node);
        let (d2, c, f) = self.surface.closest(t as usize, &p);
        let held = self.node(node);
        // Only a clear improvement, by more than the stored value's rounding, replaces a
        // node's triangle: equally near triangles (on a shared edge) would otherwise trade
        // places forever through it.
        if held.is_some_and(|(d, held_t)| held_t == t || d2.sqrt() >= d.abs() - self.quantum - 1e-6) {
            return false;
        }
        // The band is tested on the unsigned distance: a neighbour's triangle may give the
        // other sign (on an open scan) and must not leave a hole where the node's own
        // triangle, found later, is in band.
        if d2.sqrt() > self.below.max(self.above) + 2.0 * self.cell {
            return false;
        }
        let signed = self.surface.signed(t as usize, &p, d2, c, f).distance;
        let (b, local) = self.locate(node);
        let block = match self.block_of[b] {
            NONE => {
                let k = self.node_triangles.len() / NODES;
                self.block_of[b] = k as u32;
                self.node_distances.resize((k + 1) * NODES, OUT_OF_BAND);
                self.node_triangles.resize((k + 1) * NODES, NONE);
                k
            }
            k => k as usize,
        };
        self.node_distances[block * NODES + local] = (signed / self.quantum).round() as i16;
        self.node_triangles[block * NODES + local] = t;
        true
    }

    fn position(&self, [x, y, z]: [usize; 3]) -> Point3<f64> {
        Point3::from(self.origin + Vector3::new(x as f64, y as f64, z as f64) * self.cell)
    }

    fn locate(&self, [x, y, z]: [usize; 3]) -> (usize, usize) {
        let b = ((z / BLOCK) * self.blocks[1] + y / BLOCK) * self.blocks[0] + x / BLOCK;
        let local = ((z % BLOCK) * BLOCK + y % BLOCK) * BLOCK + x % BLOCK;
        (b, local)
    }

    /// A node's signed distance and nearest triangle, if it is in the band.
    fn node(&self, node: [usize; 3]) -> Option<(f64, u32)> {
        let k = self.stored(node)?;
        let t = self.node_triangles[k];
        (t != NONE).then_some((self.distance_at(k), t))
    }

    /// The signed distance stored at `k`, NaN outside the band.
    fn distance_at(&self, k: usize) -> f64 {
        match self.node_distances[k] {
            OUT_OF_BAND => f64::NAN,
            q => f64::from(q) * self.quantum,
        }
    }

    /// Where `node`'s values are stored, if its block is.
    fn stored(&self, node: [usize; 3]) -> Option<usize> {
        let (b, local) = self.locate(node);
        match *self.block_of.get(b)? {
            NONE => None,
            k => Some(k as usize * NODES + local),
        }
    }

    /// How far behind and in front of the surface queries are answered (mm).
    pub fn band(&self) -> (f64, f64) {
        (self.below, self.above)
    }

    /// The larger side of the band (mm).
    pub fn reach(&self) -> f64 {
        self.below.max(self.above)
    }

    /// The indexed surface.
    pub fn surface(&self) -> &Surface {
        &self.surface
    }

    /// Bytes held by the grid.
    pub fn grid_bytes(&self) -> usize {
        self.node_triangles.len() * 6 + self.block_of.len() * 5 + self.live_cells.len() * NODES / 8
    }

    /// Where the eight corners of the cell whose lowest node is `i` are stored, x fastest, if
    /// all are; side by side unless the cell straddles blocks.
    fn corners_at(&self, i: [usize; 3]) -> Option<[usize; 8]> {
        if i.iter().all(|&x| x % BLOCK < BLOCK - 1) {
            let base = self.stored(i)?;
            let mut at = CORNER_OFFSETS;
            at.iter_mut().for_each(|k| *k += base);
            return Some(at);
        }
        let mut at = [0usize; 8];
        for (k, slot) in at.iter_mut().enumerate() {
            *slot = self.stored([i[0] + (k & 1), i[1] + ((k >> 1) & 1), i[2] + ((k >> 2) & 1)])?;
        }
        Some(at)
    }

    /// The signed distances at the corners of the cell whose lowest node is `i`, if all are
    /// stored (NaN where out of the band).
    fn corner_distances(&self, i: [usize; 3]) -> Option<[f64; 8]> {
        self.corners_at(i).map(|at| at.map(|k| self.distance_at(k)))
    }

    /// Whether the distance field is continuous across a cell with corner distances `d`: it
    /// changes by at most the cell's diagonal across a cell; more means the sign jumps there
    /// (beside an open scan's rim), where interpolating would be wrong.
    fn continuous(d: &[f64; 8], cell: f64) -> bool {
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
    fn decides_far(&self, d: &[f64; 8], continuous: bool, (low, high): (f64, f64), lo: f64, hi: f64) -> bool {
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
