//! Gradient clusters (C: `gradient_clusters`): the boundary between each pair of touching
//! dark and light regions, as points between pixels with the gradient across them. Each
//! cluster is one candidate tag border. Points are kept in C's scan order (rows 1..h−1,
//! columns 1..w−1), and C's rule that a diagonal step is skipped right after a connected one
//! (`connected_last`) is kept too: without it, points are duplicated along staircase edges.

use crate::components::UnionFind;
use crate::gray::Gray;
use std::collections::HashMap;

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

/// Boundary clusters of a threshold image whose regions are `uf`, in order of first
/// appearance in the scan.
pub fn gradient_clusters(t: &Gray, uf: &mut UnionFind) -> Vec<Vec<Pt>> {
    let (w, h) = (t.width, t.height);
    let mut index: HashMap<(u32, u32), usize> = HashMap::new();
    let mut clusters: Vec<Vec<Pt>> = Vec::new();
    if w < 3 || h < 3 {
        return clusters;
    }
    for y in 1..h - 1 {
        let mut connected_last = false;
        for x in 1..w - 1 {
            let v0 = t.data[y * w + x];
            if v0 == 127 {
                connected_last = false;
                continue;
            }
            let rep0 = uf.find((y * w + x) as u32);
            if uf.set_size(rep0) < MIN_REGION_PIXELS {
                connected_last = false;
                continue;
            }
            let mut conn = |dx: isize, dy: isize, uf: &mut UnionFind| -> bool {
                let (x1, y1) = ((x as isize + dx) as usize, (y as isize + dy) as usize);
                let v1 = t.data[y1 * w + x1];
                if u16::from(v0) + u16::from(v1) != 255 {
                    return false;
                }
                let rep1 = uf.find((y1 * w + x1) as u32);
                if uf.set_size(rep1) < MIN_REGION_PIXELS {
                    return false;
                }
                let key = (rep0.min(rep1), rep0.max(rep1));
                let i = *index.entry(key).or_insert_with(|| {
                    clusters.push(Vec::new());
                    clusters.len() - 1
                });
                let g = i16::from(v1) - i16::from(v0);
                clusters[i].push(Pt {
                    x: (2 * x as isize + dx) as u16,
                    y: (2 * y as isize + dy) as u16,
                    gx: dx as i16 * g,
                    gy: dy as i16 * g,
                });
                true
            };
            conn(1, 0, uf);
            conn(0, 1, uf);
            if !connected_last {
                conn(-1, 1, uf);
            }
            connected_last = conn(1, 1, uf);
        }
    }
    clusters
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
