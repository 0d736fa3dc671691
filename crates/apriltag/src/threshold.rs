//! The adaptive threshold of the AprilTag C library (`threshold` in apriltag_quad_thresh.c),
//! ported to give the same image bit for bit: each 4×4 tile's min and max, spread over its
//! 3×3 tile neighbourhood, set the tile's threshold at their midpoint; tiles with less contrast
//! than `min_white_black_diff` become 127 ("unknown") so flat areas make no regions. Pixels
//! right of or below the last whole tile use the nearest tile, without the contrast test, as
//! in C. The optional deglitch closes the result with 3×3 max then min filters.

use crate::gray::Gray;
use crate::image::ImageView;
use crate::workers::Workers;

const TILE: usize = 4;

/// Thresholds an image to 0 (dark), 255 (light) and 127 (too flat to tell).
pub fn threshold(im: &ImageView<'_>, min_white_black_diff: u8, deglitch: bool) -> Gray {
    let mut out = Gray::filled(0, 0, 0);
    threshold_into(im, min_white_black_diff, deglitch, &mut out);
    out
}

/// [`threshold`] into `out`, reusing its allocation.
pub fn threshold_into(im: &ImageView<'_>, min_white_black_diff: u8, deglitch: bool, out: &mut Gray) {
    threshold_with(im, min_white_black_diff, deglitch, out, &Workers::single());
}

/// [`threshold_into`] with the tiles' extremes and the pixels shared out over `workers` by
/// bands of rows.
pub fn threshold_with(im: &ImageView<'_>, min_white_black_diff: u8, deglitch: bool, out: &mut Gray, workers: &Workers) {
    let (w, h) = (im.width(), im.height());
    let (tw, th) = (w / TILE, h / TILE);
    if tw == 0 || th == 0 {
        // Smaller than one tile: nothing can be told apart.
        out.reset(w, h, 127);
        return;
    }
    // Every pixel is written below: the fill only sizes a buffer that is new or resized.
    out.width = w;
    out.height = h;
    out.data.resize(w * h, 127);
    // Each tile's (max, min).
    let mut extremes = vec![[0u8, 255u8]; tw * th];
    workers.rows_mut(&mut extremes, tw, |tile_rows, piece| {
        // Column-wise over the tile's 4 rows first (vectorises), then across each tile's 4 columns.
        let (mut col_hi, mut col_lo) = (vec![0u8; tw * TILE], vec![255u8; tw * TILE]);
        for (ty, tiles) in tile_rows.zip(piece.chunks_exact_mut(tw)) {
            col_hi.fill(0);
            col_lo.fill(255);
            for dy in 0..TILE {
                let row = &im.row(ty * TILE + dy)[..tw * TILE];
                for ((&v, hi), lo) in row.iter().zip(col_hi.iter_mut()).zip(col_lo.iter_mut()) {
                    *hi = (*hi).max(v);
                    *lo = (*lo).min(v);
                }
            }
            for ((t, hi), lo) in tiles.iter_mut().zip(col_hi.chunks_exact(TILE)).zip(col_lo.chunks_exact(TILE)) {
                *t = [hi[0].max(hi[1]).max(hi[2].max(hi[3])), lo[0].min(lo[1]).min(lo[2].min(lo[3]))];
            }
        }
    });
    let tmax: Vec<u8> = extremes.iter().map(|e| e[0]).collect();
    let tmin: Vec<u8> = extremes.iter().map(|e| e[1]).collect();
    // Spread over the 3×3 tile neighbourhood so thresholds do not jump between tiles (a
    // separable max and min: along rows, then down columns). Each tile's threshold is the
    // midpoint; `known` is 0 where the contrast is too low to tell.
    let spread = |v: &[u8], f: fn(u8, u8) -> u8| -> Vec<u8> {
        let mut across = vec![0u8; tw * th];
        for (src, dst) in v.chunks_exact(tw).zip(across.chunks_exact_mut(tw)) {
            for tx in 0..tw {
                let mut m = src[tx];
                if tx > 0 {
                    m = f(m, src[tx - 1]);
                }
                if tx + 1 < tw {
                    m = f(m, src[tx + 1]);
                }
                dst[tx] = m;
            }
        }
        let mut out = across.clone();
        for ty in 0..th {
            for ny in [ty.wrapping_sub(1), ty + 1] {
                if ny < th {
                    let (o, n) = (&mut out[ty * tw..][..tw], &across[ny * tw..][..tw]);
                    for (o, &n) in o.iter_mut().zip(n) {
                        *o = f(*o, n);
                    }
                }
            }
        }
        out
    };
    let (hi, lo) = (spread(&tmax, u8::max), spread(&tmin, u8::min));
    let cuts: Vec<u8> = hi.iter().zip(&lo).map(|(&hi, &lo)| lo + (hi - lo) / 2).collect();
    let known: Vec<u8> =
        hi.iter().zip(&lo).map(|(&hi, &lo)| if hi - lo >= min_white_black_diff { 0xff } else { 0 }).collect();
    let cut = |v: u8, t: u8| -> u8 { if v > t { 255 } else { 0 } };
    workers.rows_mut(&mut out.data[..th * TILE * w], w, |rows, piece| {
        // Per pixel of a tile row: its tile's threshold and whether it is known, so the pixel
        // loop is branch-free and vectorises.
        let (mut thr, mut mask) = (vec![0u8; tw * TILE], vec![0u8; tw * TILE]);
        let first = rows.start;
        for (y, out_row) in rows.zip(piece.chunks_exact_mut(w)) {
            if y % TILE == 0 || y == first {
                let tiles = (y / TILE) * tw..(y / TILE + 1) * tw;
                for ((t, m), (&c, &k)) in thr
                    .chunks_exact_mut(TILE)
                    .zip(mask.chunks_exact_mut(TILE))
                    .zip(cuts[tiles.clone()].iter().zip(&known[tiles]))
                {
                    t.fill(c);
                    m.fill(k);
                }
            }
            let (row, out_row) = (&im.row(y)[..tw * TILE], &mut out_row[..tw * TILE]);
            for (((o, &v), &t), &m) in out_row.iter_mut().zip(row).zip(&thr).zip(&mask) {
                // Known: 0 or 255 by the threshold; unknown: 127.
                *o = (cut(v, t) & m) | (127 & !m);
            }
        }
    });
    // Right of and below the last whole tile: the nearest tile, without the contrast test.
    for y in 0..h {
        let x0 = if y >= th * TILE { 0 } else { tw * TILE };
        let ty = (y / TILE).min(th - 1);
        let row = im.row(y);
        for (x, &v) in row.iter().enumerate().skip(x0) {
            let tx = (x / TILE).min(tw - 1);
            out.data[y * w + x] = cut(v, cuts[ty * tw + tx]);
        }
    }
    if deglitch {
        close_3x3(out);
    }
}

/// 3×3 max then 3×3 min over the interior, as C does it: the intermediate image's border is
/// 0, and the min pass reads it, so pixels next to the border can only darken.
fn close_3x3(im: &mut Gray) {
    let (w, h) = (im.width, im.height);
    if w < 3 || h < 3 {
        return;
    }
    let mut dilated = vec![0u8; w * h];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let mut m = 0u8;
            for yy in y - 1..=y + 1 {
                for xx in x - 1..=x + 1 {
                    m = m.max(im.data[yy * w + xx]);
                }
            }
            dilated[y * w + x] = m;
        }
    }
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let mut m = 255u8;
            for yy in y - 1..=y + 1 {
                for xx in x - 1..=x + 1 {
                    m = m.min(dilated[yy * w + xx]);
                }
            }
            im.data[y * w + x] = m;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_areas_are_unknown_and_edges_split_at_the_midpoint() {
        let (w, h) = (16, 8);
        let data: Vec<u8> = (0..w * h).map(|i| if i % w < 8 { 40 } else { 200 }).collect();
        let t = threshold(&ImageView::new(&data, w, h, w).expect("valid"), 5, false);
        // Tiles near the edge see both levels: dark → 0, light → 255.
        assert_eq!(t.data[3 * w + 7], 0);
        assert_eq!(t.data[3 * w + 8], 255);
        // Far from it, with the neighbourhood holding one level only: unknown.
        let flat = vec![100u8; 64];
        let t = threshold(&ImageView::new(&flat, 8, 8, 8).expect("valid"), 5, false);
        assert!(t.data.iter().all(|&v| v == 127));
        // Tiny images are all unknown rather than an error.
        let t = threshold(&ImageView::new(&[0, 255, 0], 3, 1, 3).expect("valid"), 5, false);
        assert_eq!(t.data, vec![127; 3]);
    }

    #[test]
    fn deglitch_fills_single_pixel_holes() {
        let (w, h) = (12, 12);
        let mut data = vec![0u8; w * h];
        for y in 2..10 {
            for x in 2..10 {
                data[y * w + x] = 255;
            }
        }
        data[5 * w + 5] = 0;
        let mut g = Gray { width: w, height: h, data };
        close_3x3(&mut g);
        assert_eq!(g.data[5 * w + 5], 255, "the hole is closed");
        assert_eq!(g.data[w + 1], 0, "next to the border the zero border leaks in");
    }
}
