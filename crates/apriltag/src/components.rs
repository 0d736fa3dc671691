//! Connected components of the threshold image (C: `connected_components` with
//! `do_unionfind_line2`): dark pixels join their 4-neighbours, light pixels their 8-neighbours,
//! 127 ("unknown") joins nothing. The scan, including its shortcuts and which edge pixels it
//! reaches, follows C exactly so the same regions come out.

use crate::gray::Gray;

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

    /// The representative of `i`'s set.
    pub fn find(&mut self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            let p = self.parent[i as usize];
            self.parent[i as usize] = self.parent[p as usize];
            i = self.parent[i as usize];
        }
        i
    }

    /// Joins the sets of `a` and `b`.
    pub fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        let (big, small) = if self.size[ra as usize] >= self.size[rb as usize] { (ra, rb) } else { (rb, ra) };
        self.parent[small as usize] = big;
        self.size[big as usize] += self.size[small as usize];
    }

    /// Number of elements in the set whose representative is `root`.
    pub fn set_size(&self, root: u32) -> u32 {
        self.size[root as usize]
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
    let (w, h) = (t.width, t.height);
    uf.reset(w * h);
    if w < 3 {
        return; // the scan covers columns 1..w-1 only, as in C
    }
    let px = |x: usize, y: usize| t.data[y * w + x];
    let idx = |x: usize, y: usize| (y * w + x) as u32;
    for x in 1..w - 1 {
        let v = px(x, 0);
        if v != 127 && px(x - 1, 0) == v {
            uf.union(idx(x, 0), idx(x - 1, 0));
        }
    }
    for y in 1..h {
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
            if left == v {
                uf.union(idx(x, y), idx(x - 1, y));
            }
            // The shortcuts skip unions that earlier ones already imply.
            if (x == 1 || !(left == up_left && up_left == up)) && up == v {
                uf.union(idx(x, y), idx(x, y - 1));
            }
            if v == 255 {
                if (x == 1 || !(left == up_left || up == up_left)) && up_left == v {
                    uf.union(idx(x, y), idx(x - 1, y - 1));
                }
                if up != up_right && up_right == v {
                    uf.union(idx(x, y), idx(x + 1, y - 1));
                }
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
