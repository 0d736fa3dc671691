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

    /// The representative of `i`'s set, leaving the sets as they are (so threads can share them).
    pub fn root(&self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            i = self.parent[i as usize];
        }
        i
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
    workers.each(pieces, |(rows, parent, size)| {
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

/// Which of a row's joins to make: along the row, and to the row above.
#[derive(Clone, Copy)]
struct Joins {
    left: bool,
    up: bool,
}

/// C's scan of row `y`: each pixel joins its left neighbour, and (not in the first row) the
/// ones above it that C's shortcuts leave.
fn scan_row(t: &Gray, y: usize, sets: &mut Sets<'_>, joins: Joins) {
    let w = t.width;
    let px = |x: usize, y: usize| t.data[y * w + x];
    let idx = |x: usize, y: usize| (y * w + x) as u32;
    if y == 0 || !joins.up {
        if joins.left {
            for x in 1..w - 1 {
                let v = px(x, y);
                if v != 127 && px(x - 1, y) == v {
                    sets.union(idx(x, y), idx(x - 1, y));
                }
            }
        }
        return;
    }
    let (mut up, mut up_right, mut v) = (px(0, y - 1), px(1, y - 1), px(0, y));
    for x in 1..w - 1 {
        let up_left = up;
        up = up_right;
        up_right = px(x + 1, y - 1);
        let left = v;
        v = px(x, y);
        if v == 127 {
            continue;
        }
        if joins.left && left == v {
            sets.union(idx(x, y), idx(x - 1, y));
        }
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
}
