//! Connected components of the threshold image (C: `connected_components` with
//! `do_unionfind_line2`): dark pixels join their 4-neighbours, light pixels their 8-neighbours,
//! 127 ("unknown") joins nothing. The scan, including its shortcuts and which edge pixels it
//! reaches, follows C exactly so the same regions come out.
//!
//! With worker threads the rows are split into bands ([`Workers::band_ranges`]): each band joins
//! its own pixels, writing only its own part of the sets, then the seams between bands are
//! joined on one thread. That makes exactly the joins of the single scan, in another order, so
//! the regions are the same (their representatives may differ, which nothing downstream reads).

use crate::gray::Gray;
use crate::workers::Workers;

/// Disjoint sets over the pixels (union by size, path halving).
#[derive(Debug, Clone)]
pub struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    /// `n` singleton sets.
    pub fn new(n: usize) -> Self {
        UnionFind { parent: (0..n as u32).collect(), size: vec![1; n] }
    }

    /// Makes this `n` singleton sets again, reusing the allocation.
    pub fn reset(&mut self, n: usize) {
        self.parent.clear();
        self.parent.extend(0..n as u32);
        self.size.clear();
        self.size.resize(n, 1);
    }

    fn sets(&mut self) -> Sets<'_> {
        Sets { parent: &mut self.parent, size: &mut self.size, offset: 0 }
    }

    /// The representative of `i`'s set.
    pub fn find(&mut self, i: u32) -> u32 {
        self.sets().find(i)
    }

    /// The element `i` points to (itself for a representative).
    pub fn parent_of(&self, i: u32) -> u32 {
        self.parent[i as usize]
    }

    /// Joins the sets of `a` and `b`.
    pub fn union(&mut self, a: u32, b: u32) {
        self.sets().union(a, b);
    }

    /// Number of elements in the set whose representative is `root`.
    pub fn set_size(&self, root: u32) -> u32 {
        self.size[root as usize]
    }
}

/// The sets of the elements `offset..offset + parent.len()`, every one of whose members lies in
/// that range: a band's own pixels, or (offset 0) all of them.
struct Sets<'a> {
    parent: &'a mut [u32],
    size: &'a mut [u32],
    offset: u32,
}

impl Sets<'_> {
    fn find(&mut self, mut i: u32) -> u32 {
        let o = self.offset;
        while self.parent[(i - o) as usize] != i {
            let p = self.parent[(i - o) as usize];
            self.parent[(i - o) as usize] = self.parent[(p - o) as usize];
            i = self.parent[(i - o) as usize];
        }
        i
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        let o = self.offset;
        let (big, small) =
            if self.size[(ra - o) as usize] >= self.size[(rb - o) as usize] { (ra, rb) } else { (rb, ra) };
        self.parent[(small - o) as usize] = big;
        self.size[(big - o) as usize] += self.size[(small - o) as usize];
    }
}

/// Labels the regions of a threshold image (values 0, 127, 255).
pub fn connected_components(t: &Gray) -> UnionFind {
    let mut uf = UnionFind::new(0);
    connected_components_into(t, &mut uf);
    uf
}

/// [`connected_components`] into `uf`, reusing its allocation.
pub fn connected_components_into(t: &Gray, uf: &mut UnionFind) {
    connected_components_with(t, uf, &Workers::single());
}

/// [`connected_components_into`] with the rows shared out over `workers` by bands.
pub fn connected_components_with(t: &Gray, uf: &mut UnionFind, workers: &Workers) {
    let (w, h) = (t.width, t.height);
    let n = w * h;
    uf.parent.resize(n, 0);
    uf.size.resize(n, 0);
    if w < 3 {
        uf.reset(n);
        return; // the scan covers columns 1..w-1 only, as in C
    }
    let bands = workers.band_ranges(h);
    let mut pieces = Vec::with_capacity(bands.len());
    let (mut parent, mut size) = (&mut uf.parent[..], &mut uf.size[..]);
    for rows in &bands {
        let (p, p_rest) = parent.split_at_mut(rows.len() * w);
        let (s, s_rest) = size.split_at_mut(rows.len() * w);
        pieces.push((rows.clone(), p, s));
        (parent, size) = (p_rest, s_rest);
    }
    workers.map(pieces, |(rows, parent, size)| {
        let offset = (rows.start * w) as u32;
        for (i, p) in parent.iter_mut().enumerate() {
            *p = offset + i as u32;
        }
        size.fill(1);
        let mut sets = Sets { parent, size, offset };
        for y in rows.clone() {
            // A band's first row joins the row above it later, at the seam.
            scan_row(t, y, &mut sets, Joins { left: true, up: y > 0 && y != rows.start });
        }
    });
    let mut sets = uf.sets();
    for rows in bands.iter().skip(1) {
        scan_row(t, rows.start, &mut sets, Joins { left: false, up: true });
    }
}

/// The eight bytes of `a` from `i` as one word.
fn word(a: &[u8], i: usize) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&a[i..i + 8]);
    u64::from_le_bytes(b)
}

/// Which of a row's joins to make: along the row, and to the row above.
#[derive(Clone, Copy)]
struct Joins {
    left: bool,
    up: bool,
}

/// C's scan of row `y`: each pixel joins its left neighbour, and (not in the first row) the
/// ones above it that C's shortcuts leave.
///
/// The joins along the row are made first, run by run: every pixel of a run of equal values
/// that C's scan would join one by one (from column 1 to `w` − 2, each to its left neighbour)
/// points straight at the run's first pixel. Each is still alone when this is done (only its
/// own row's joins reach it before), so no set is searched; then come the joins upward, which
/// inside a region C's shortcuts keep to about one per run.
fn scan_row(t: &Gray, y: usize, sets: &mut Sets<'_>, joins: Joins) {
    let w = t.width;
    let row = &t.data[y * w..(y + 1) * w];
    let idx = |x: usize, y: usize| (y * w + x) as u32;
    if joins.left {
        let o = sets.offset;
        let mut x = 1;
        while x < w - 1 {
            let v = row[x];
            if v == 127 || row[x - 1] != v {
                x += 1;
                continue;
            }
            // Columns x..end join x − 1, the run's head.
            let head = x - 1;
            let mut end = x + 1;
            while end < w - 1 && row[end] == v {
                end += 1;
            }
            let h = idx(head, y);
            for i in x..end {
                sets.parent[(idx(i, y) - o) as usize] = h;
            }
            sets.size[(h - o) as usize] += (end - x) as u32;
            x = end;
        }
    }
    if y == 0 || !joins.up {
        return;
    }
    let above = &t.data[(y - 1) * w..y * w];
    let mut x = 1;
    while x < w - 1 {
        // Eight pixels that join nothing upward are passed over at once: unknown ones, or ones
        // inside a region that fills both rows (the shortcuts skip all their joins).
        if x > 1 && x + 9 <= w {
            let all_v = u64::from(row[x]) * 0x0101_0101_0101_0101;
            if word(row, x) == all_v
                && (row[x] == 127
                    || (row[x - 1] == row[x] && word(above, x - 1) == all_v && word(above, x + 1) == all_v))
            {
                x += 8;
                continue;
            }
        }
        let (up_left, up, up_right) = (above[x - 1], above[x], above[x + 1]);
        let (left, v) = (row[x - 1], row[x]);
        if v != 127 {
            // The shortcuts skip unions that earlier ones already imply.
            if (x == 1 || !(left == up_left && up_left == up)) && up == v {
                sets.union(idx(x, y), idx(x, y - 1));
            }
            if v == 255 {
                if (x == 1 || !(left == up_left || up == up_left)) && up_left == v {
                    sets.union(idx(x, y), idx(x - 1, y - 1));
                }
                if up != up_right && up_right == v {
                    sets.union(idx(x, y), idx(x + 1, y - 1));
                }
            }
        }
        x += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(rows: &[&str]) -> Gray {
        let data = rows
            .iter()
            .flat_map(|r| {
                r.bytes().map(|b| match b {
                    b'#' => 0,
                    b'.' => 255,
                    _ => 127,
                })
            })
            .collect();
        Gray { width: rows[0].len(), height: rows.len(), data }
    }

    #[test]
    fn dark_joins_by_sides_light_also_by_corners() {
        let t = image(&[
            "......", //
            ".#.?..", "..#...", "......",
        ]);
        let mut uf = connected_components(&t);
        let w = t.width as u32;
        let at = |x: u32, y: u32| y * w + x;
        // The two dark pixels touch only at a corner: separate.
        assert_ne!(uf.find(at(1, 1)), uf.find(at(2, 2)));
        // Light pixels around them are one region, through corners too.
        assert_eq!(uf.find(at(2, 1)), uf.find(at(1, 2)));
        // The unknown pixel stays alone.
        let r = uf.find(at(3, 1));
        assert_eq!(uf.set_size(r), 1);
    }

    /// The regions by a plain flood fill over C's joins: along rows and columns between equal
    /// known pixels, diagonally upward between light ones, each from a pixel in columns
    /// 1..w − 1 (the shortcuts skip only joins already implied, but for one case below).
    fn flood(t: &Gray) -> Vec<usize> {
        let (w, h) = (t.width, t.height);
        let mut edges: Vec<Vec<usize>> = vec![Vec::new(); w * h];
        let mut join = |a: usize, b: usize| {
            edges[a].push(b);
            edges[b].push(a);
        };
        for y in 0..h {
            for x in 1..w - 1 {
                let (i, v) = (y * w + x, t.data[y * w + x]);
                if v == 127 {
                    continue;
                }
                if t.data[i - 1] == v {
                    join(i, i - 1);
                }
                if y > 0 {
                    let up = i - w;
                    if t.data[up] == v {
                        join(i, up);
                    }
                    if v == 255 && t.data[up - 1] == v {
                        join(i, up - 1);
                    }
                    // C joins up and to the right only where the pixel above differs: elsewhere
                    // the join is implied, except next to the last column, which C never
                    // joins to its left (so a region can end there).
                    if v == 255 && t.data[up + 1] == v && t.data[up] != v {
                        join(i, up + 1);
                    }
                }
            }
        }
        let mut label = vec![usize::MAX; w * h];
        for start in 0..w * h {
            if label[start] != usize::MAX {
                continue;
            }
            let mut stack = vec![start];
            label[start] = start;
            while let Some(i) = stack.pop() {
                for &j in &edges[i] {
                    if label[j] == usize::MAX {
                        label[j] = start;
                        stack.push(j);
                    }
                }
            }
        }
        label
    }

    #[test]
    fn runs_skips_and_bands_give_the_regions_of_a_flood_fill() {
        // A small generator, so the test needs no dependency: blobs of each value on a field
        // that is flat in places (the skips) and noisy in others (short runs).
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move |n: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % n
        };
        let mut checked = 0;
        for case in 0..60 {
            let (w, h) = (3 + next(61) as usize, 1 + next(150) as usize);
            let mut data = vec![[0u8, 127, 255][next(3) as usize]; w * h];
            for _ in 0..next(12) {
                let (x0, y0, x1, y1) = (next(w as u64), next(h as u64), next(w as u64), next(h as u64));
                let v = [0u8, 127, 255][next(3) as usize];
                for y in y0.min(y1)..=y0.max(y1) {
                    for x in x0.min(x1)..=x0.max(x1) {
                        data[y as usize * w + x as usize] = v;
                    }
                }
            }
            if case % 3 == 0 {
                for p in data.iter_mut() {
                    if next(4) == 0 {
                        *p = [0u8, 127, 255][next(3) as usize];
                    }
                }
            }
            let t = Gray { width: w, height: h, data };
            let want = flood(&t);
            for threads in [1, 3] {
                let mut uf = UnionFind::new(0);
                connected_components_with(&t, &mut uf, &Workers::new(threads));
                let (mut to_ours, mut to_flood) = (std::collections::HashMap::new(), std::collections::HashMap::new());
                for (i, &f) in want.iter().enumerate() {
                    let r = uf.find(i as u32);
                    assert_eq!(*to_ours.entry(f).or_insert(r), r, "case {case}, {threads} threads: a region split");
                    assert_eq!(*to_flood.entry(r).or_insert(f), f, "case {case}, {threads} threads: regions merged");
                }
                let size = |f: usize| want.iter().filter(|&&g| g == f).count() as u32;
                for (&f, &r) in &to_ours {
                    assert_eq!(uf.set_size(r), size(f), "case {case}, {threads} threads: a region's size");
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 120);
    }
}
