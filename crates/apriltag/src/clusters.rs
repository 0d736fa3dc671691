//! Gradient clusters (C: `gradient_clusters`): the boundary between each pair of touching
//! dark and light regions, as points between pixels with the gradient across them. Each
//! cluster is one candidate tag border. Points are kept in C's scan order (rows 1..h−1,
//! columns 1..w−1), and C's rule that a diagonal step is skipped right after a connected one
//! (`connected_last`) is kept too: without it, points are duplicated along staircase edges.

use crate::components::UnionFind;
use crate::gray::Gray;
use crate::workers::Workers;
use rustc_hash::FxHashMap;

/// Regions smaller than this take no part in clusters (hard-coded in C as well).
const MIN_REGION_PIXELS: u32 = 25;

/// A boundary point, in half-pixel units so it can sit between two pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pt {
    /// 2·x + dx: twice the column, plus the step to the other region.
    pub x: u16,
    /// 2·y + dy.
    pub y: u16,
    /// Gradient along x, from the dark side to the light side (±255 or 0).
    pub gx: i16,
    /// Gradient along y.
    pub gy: i16,
}

/// Marks a pixel that takes no part in clusters: unknown (127) or in a small region.
const NO_REGION: u32 = u32::MAX;
/// A pixel whose region has not been looked up yet.
const UNSET: u32 = u32::MAX - 1;

/// Boundary clusters of a threshold image whose regions are `uf`, in order of first
/// appearance in the scan.
pub fn gradient_clusters(t: &Gray, uf: &mut UnionFind) -> Vec<Vec<Pt>> {
    gradient_clusters_with(t, uf, &mut Vec::new())
}

/// [`gradient_clusters`] with a caller's buffer for each pixel's region.
pub fn gradient_clusters_with(t: &Gray, uf: &mut UnionFind, region: &mut Vec<u32>) -> Vec<Vec<Pt>> {
    gradient_clusters_par(t, uf, region, &Workers::single())
}

/// [`gradient_clusters_with`] with the rows shared out over `workers` by bands: each band
/// gathers its own clusters, and they are joined in band order, so every cluster holds the
/// same points in the same order as from one scan.
pub fn gradient_clusters_par(t: &Gray, uf: &mut UnionFind, region: &mut Vec<u32>, workers: &Workers) -> Vec<Vec<Pt>> {
    let (w, h) = (t.width, t.height);
    if w < 3 || h < 3 {
        return Vec::new();
    }
    // Each pixel's region, looked up once, and only for pixels on a boundary: most pixels
    // are inside a region or unknown and never need one.
    region.clear();
    region.resize(w * h, UNSET);
    let bands = workers.band_ranges(h);
    if bands.len() == 1 {
        let mut out = Clusters::default();
        scan_band(t, 0..h, region, &mut Regions::Own(uf), &mut out);
        return out.clusters;
    }
    let uf: &UnionFind = uf;
    let mut jobs = Vec::with_capacity(bands.len());
    let mut rest = &mut region[..];
    for rows in &bands {
        let (piece, tail) = rest.split_at_mut(rows.len() * w);
        jobs.push((rows.clone(), piece));
        rest = tail;
    }
    let results = workers.map(jobs, |(rows, piece)| {
        let mut clusters = Clusters::default();
        scan_band(t, rows, piece, &mut Regions::Shared(uf, Vec::new()), &mut clusters);
        clusters
    });
    let mut out = Clusters::default();
    for band in results {
        for (key, points) in band.keys.into_iter().zip(band.clusters) {
            out.extend(key, points);
        }
    }
    out.clusters
}

/// How a band finds a pixel's region.
enum Regions<'a> {
    /// The band is the whole image: finding shortens the paths.
    Own(&'a mut UnionFind),
    /// The sets are shared by the bands' threads, so their paths stay as they are; instead the
    /// band remembers the region of every pixel of its own that a search passes (the trail).
    Shared(&'a UnionFind, Vec<usize>),
}

impl Regions<'_> {
    /// The region of pixel `i` (or [`NO_REGION`]), `region` caching the pixels from `offset`.
    fn of(&mut self, i: usize, region: &mut [u32], offset: usize) -> u32 {
        let cached = |j: usize, region: &[u32]| region.get(j.wrapping_sub(offset)).copied().filter(|&c| c != UNSET);
        if let Some(c) = cached(i, region) {
            return c;
        }
        let value = match self {
            Regions::Own(uf) => {
                let rep = uf.find(i as u32);
                region_or_none(uf, rep)
            }
            Regions::Shared(uf, trail) => {
                let mut j = i;
                let value = loop {
                    if let Some(c) = cached(j, region) {
                        break c;
                    }
                    if j.wrapping_sub(offset) < region.len() {
                        trail.push(j);
                    }
                    let p = uf.parent_of(j as u32) as usize;
                    if p == j {
                        break region_or_none(uf, p as u32);
                    }
                    j = p;
                };
                for k in trail.drain(..) {
                    region[k - offset] = value;
                }
                return value;
            }
        };
        // The row below a band belongs to the next band's cache.
        if let Some(c) = region.get_mut(i.wrapping_sub(offset)) {
            *c = value;
        }
        value
    }
}

/// The region whose representative is `rep`, or [`NO_REGION`] when it is too small.
fn region_or_none(uf: &UnionFind, rep: u32) -> u32 {
    if uf.set_size(rep) < MIN_REGION_PIXELS { NO_REGION } else { rep }
}

/// The scan of rows `rows` (those of them inside the border), `region` being their pixels'
/// region cache.
fn scan_band(
    t: &Gray,
    rows: std::ops::Range<usize>,
    region: &mut [u32],
    regions: &mut Regions<'_>,
    out: &mut Clusters,
) {
    let (w, h) = (t.width, t.height);
    let offset = rows.start * w;
    let d = &t.data;
    let mut region_of = |i: usize, region: &mut [u32]| regions.of(i, region, offset);
    // Per row, whether each pixel can start a point: not unknown (127), with an opposite
    // neighbour to the right or below (values summing to 255, i.e. differing in every bit).
    // Computed for the whole row at once, so it vectorises, leaving the scan to the few
    // pixels on a boundary.
    let mut starts = vec![0u8; w];
    for y in rows.start.max(1)..rows.end.min(h - 1) {
        let (row, next) = (&d[y * w..(y + 1) * w], &d[(y + 1) * w..(y + 2) * w]);
        for (x, s) in starts.iter_mut().enumerate().take(w - 1).skip(1) {
            let v = row[x];
            let any = ((v ^ row[x + 1]) == 255)
                | ((v ^ next[x - 1]) == 255)
                | ((v ^ next[x]) == 255)
                | ((v ^ next[x + 1]) == 255);
            *s = u8::from(any & (v != 127));
        }
        let mut connected_last = false;
        let mut next_x = 1;
        while next_x < w - 1 {
            let x = next_x;
            if x + 8 < w && starts[x..x + 8] == [0; 8] {
                connected_last = false;
                next_x += 8;
                continue;
            }
            next_x += 1;
            if starts[x] == 0 {
                connected_last = false;
                continue;
            }
            let i0 = y * w + x;
            let v0 = d[i0];
            let below = i0 + w;
            let opposite = |i: usize| (v0 ^ d[i]) == 255;
            let rep0 = region_of(i0, region);
            if rep0 == NO_REGION {
                connected_last = false;
                continue;
            }
            let mut conn = |i1: usize, dx: i16, dy: i16| -> bool {
                if !opposite(i1) {
                    return false;
                }
                let rep1 = region_of(i1, region);
                if rep1 == NO_REGION {
                    return false;
                }
                let g = i16::from(d[i1]) - i16::from(v0);
                let p = Pt { x: (2 * x as i16 + dx) as u16, y: (2 * y as i16 + dy) as u16, gx: dx * g, gy: dy * g };
                out.push(rep0, rep1, p);
                true
            };
            conn(i0 + 1, 1, 0);
            conn(below, 0, 1);
            if !connected_last {
                conn(below - 1, -1, 1);
            }
            connected_last = conn(below + 1, 1, 1);
        }
    }
}

/// Clusters keyed by their pair of regions, in order of creation.
#[derive(Default)]
struct Clusters {
    index: FxHashMap<u64, usize>,
    /// The last key and its cluster: runs of points share one, so most lookups are skipped.
    last: Option<(u64, usize)>,
    clusters: Vec<Vec<Pt>>,
    /// Each cluster's key.
    keys: Vec<u64>,
}

impl Clusters {
    /// The cluster of `key`, made if new.
    fn slot(&mut self, key: u64) -> usize {
        match self.last {
            Some((k, i)) if k == key => i,
            _ => {
                let n = self.clusters.len();
                let i = *self.index.entry(key).or_insert(n);
                if i == n {
                    self.clusters.push(Vec::new());
                    self.keys.push(key);
                }
                self.last = Some((key, i));
                i
            }
        }
    }

    #[inline(always)]
    fn push(&mut self, rep0: u32, rep1: u32, p: Pt) {
        let key = (u64::from(rep0.min(rep1)) << 32) | u64::from(rep0.max(rep1));
        let i = self.slot(key);
        self.clusters[i].push(p);
    }

    /// Appends a later band's points of `key`.
    fn extend(&mut self, key: u64, points: Vec<Pt>) {
        let i = self.slot(key);
        if self.clusters[i].is_empty() {
            self.clusters[i] = points;
        } else {
            self.clusters[i].extend(points);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::components::connected_components;

    #[test]
    fn a_dark_square_on_light_makes_one_cluster_around_it() {
        let (w, h) = (20, 20);
        let mut data = vec![255u8; w * h];
        for y in 5..15 {
            for x in 5..15 {
                data[y * w + x] = 0;
            }
        }
        let t = Gray { width: w, height: h, data };
        let mut uf = connected_components(&t);
        let clusters = gradient_clusters(&t, &mut uf);
        assert_eq!(clusters.len(), 1);
        let c = &clusters[0];
        // Every point lies on the square's border, gradients point outward (dark → light).
        for p in c {
            let (x, y) = (f64::from(p.x) / 2.0, f64::from(p.y) / 2.0);
            assert!((4.5..=14.5).contains(&x) && (4.5..=14.5).contains(&y), "{p:?}");
            let to_border = [(x - 4.5).abs(), (x - 14.5).abs(), (y - 4.5).abs(), (y - 14.5).abs()];
            assert!(to_border.iter().copied().fold(f64::INFINITY, f64::min) <= 0.5, "{p:?} off the border");
            let outward = f64::from(p.gx) * (x - 9.5) + f64::from(p.gy) * (y - 9.5);
            assert!(outward >= 0.0, "gradient points from dark to light: {p:?}");
        }
        // Four sides of 10 pixels, each seen along its normal at least once per pixel.
        assert!(c.len() >= 40, "{} points", c.len());
    }

    #[test]
    fn small_regions_make_no_clusters() {
        let (w, h) = (12, 12);
        let mut data = vec![255u8; w * h];
        for y in 5..8 {
            for x in 5..8 {
                data[y * w + x] = 0; // 9 pixels < 25
            }
        }
        let t = Gray { width: w, height: h, data };
        let mut uf = connected_components(&t);
        assert!(gradient_clusters(&t, &mut uf).is_empty());
    }
}
