//! [`SurfaceIndex`] and how it is built: a narrow-band grid of sparse 8³-node blocks whose
//! nodes hold their exact signed distance and nearest triangle, filled outward from the
//! surface, and the maps made from it once (which cells, and which 4³-cell sub-blocks, a lookup
//! within the focus may find anything in) that let a query skip most of it.

use super::surface::Surface;
use crate::Mesh;
use nalgebra::{Point3, Vector3};

/// Nodes per block edge of the sparse grid.
pub(super) const BLOCK: usize = 8;
/// Cells per sub-block edge: the grain at which far regions are known in advance.
pub(super) const SUB: usize = 4;
pub(super) const NODES: usize = BLOCK * BLOCK * BLOCK;
pub(super) const NONE: u32 = u32::MAX;
/// A node outside the band.
const OUT_OF_BAND: i16 = i16::MIN;
/// Offsets of a cell's eight corners from its lowest one within a block, x fastest.
const CORNER_OFFSETS: [usize; 8] =
    [0, 1, BLOCK, BLOCK + 1, BLOCK * BLOCK, BLOCK * BLOCK + 1, BLOCK * BLOCK + BLOCK, BLOCK * BLOCK + BLOCK + 1];

/// The least and greatest of `d`, passing over NaN.
pub(super) fn extent(d: &[f64; 8]) -> (f64, f64) {
    d.iter().fold((d[0], d[0]), |(lo, hi), &x| (lo.min(x), hi.max(x)))
}

/// A narrow-band signed-distance grid over a surface: each node holds its exact signed
/// distance and nearest triangle. A query interpolates the grid to decide whether the point
/// is in the range asked for, then finds the exact nearest point from the corner nodes'
/// nearest triangles and a descent over their neighbours.
#[derive(Debug, Clone)]
pub struct SurfaceIndex {
    pub(super) surface: Surface,
    pub(super) below: f64,
    pub(super) above: f64,
    /// The top of the ranges that sub-blocks are judged for (mm, within the band).
    pub(super) focus: f64,
    pub(super) cell: f64,
    /// The inverse of `cell`.
    pub(super) per_cell: f64,
    pub(super) origin: Vector3<f64>,
    /// Nodes along each axis.
    pub(super) nodes: [usize; 3],
    /// Blocks along each axis.
    blocks: [usize; 3],
    /// Per block position, its index among the stored blocks or [`NONE`].
    pub(super) block_of: Vec<u32>,
    /// Per node of the stored blocks (block `k`'s nodes at `k * NODES..`), its signed
    /// distance in units of `quantum` ([`OUT_OF_BAND`] outside the band): apart from the
    /// triangles, and small, because most queries read only these and memory is their cost.
    pub(super) node_distances: Vec<i16>,
    /// Millimetres per unit of `node_distances`: the band over the range of an `i16`, some
    /// tens of nanometres.
    quantum: f64,
    /// Per node of the stored blocks, its nearest triangle or [`NONE`].
    pub(super) node_triangles: Vec<u32>,
    /// Sub-blocks ([`SUB`]³ cells, named by their lowest node) along each axis.
    subs: [usize; 3],
    /// Per sub-block, how many sub-blocks away (Chebyshev, at most 255) the nearest live one
    /// is: 0 for a live one, one holding a cell where a lookup within `-below..=focus` may
    /// answer other than [`Lookup::Far`](super::Lookup::Far). Rejects far points, and whole
    /// clusters of them, at once.
    pub(super) clearance: Vec<u8>,
    /// Per sub-block, one bit: whether it is live (its clearance is 0), 64 to a word so that
    /// the test each lookup makes stays in cache.
    pub(super) live: Vec<u64>,
    /// Per stored block, one bit per cell named by its lowest node (a word per z-layer, x
    /// fastest): whether the cell is live. In one cache line per block, it rejects the points
    /// in dead cells of live sub-blocks, half of those the grid is read for, without reading
    /// it.
    pub(super) live_cells: Vec<[u64; BLOCK]>,
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

    /// The sub-block holding the cell whose lowest node is `i`.
    pub(super) fn sub_block(&self, i: [usize; 3]) -> usize {
        ((i[2] / SUB) * self.subs[1] + i[1] / SUB) * self.subs[0] + i[0] / SUB
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

    pub(super) fn locate(&self, [x, y, z]: [usize; 3]) -> (usize, usize) {
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
    pub(super) fn distance_at(&self, k: usize) -> f64 {
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
    pub(super) fn corners_at(&self, i: [usize; 3]) -> Option<[usize; 8]> {
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
}
