//! Quad fitting (C: `fit_quad`, `quad_segment_maxima`, `fit_line`, `compute_lfps`, `ptsort`):
//! each cluster's points are sorted by angle around its centre, a weighted line-fit error is
//! computed over a sliding window, its four best maxima (the corners) are chosen by the
//! smallest total line-fit error, and the four fitted lines are intersected.
//!
//! Ported for identical results: C mixes `float` and `double` (`sqrtf` inside double maths,
//! `float` corners and angles) and sorts with a merge sort that is not stable; both are
//! reproduced, since ties and rounding decide which maxima win.

use crate::clusters::Pt;
use crate::config::QuadThreshold;
use crate::image::ImageView;
use crate::workers::Workers;

/// A quad in the coordinates of the image it was fitted on (decimated, C's pixel corners:
/// the centre of pixel (0, 0) at (0.5, 0.5)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quad {
    /// Corners, counter-clockwise in the image (y down), as C orders them.
    pub p: [[f32; 2]; 4],
}

/// Running sums of weighted point moments along the sorted cluster.
#[derive(Debug, Clone, Copy, Default)]
struct LineFitPt {
    mx: f64,
    my: f64,
    mxx: f64,
    myy: f64,
    mxy: f64,
    w: f64,
}

/// C's `sqrtf` applied to a double: computed in single precision.
fn sqrtf(v: f64) -> f64 {
    f64::from((v as f32).sqrt())
}

#[derive(Clone, Copy)]
struct LineFit {
    /// Point on the line (mean), and unit normal.
    params: [f64; 4],
    err: f64,
    mse: f64,
}

/// The moments of the points `i0..=i1` (wrapping past the end), and how many they are.
fn moments(lfps: &[LineFitPt], i0: usize, i1: usize) -> (LineFitPt, usize) {
    let sz = lfps.len();
    if i0 < i1 {
        let mut m = lfps[i1];
        if i0 > 0 {
            let a = lfps[i0 - 1];
            m = LineFitPt {
                mx: m.mx - a.mx,
                my: m.my - a.my,
                mxx: m.mxx - a.mxx,
                myy: m.myy - a.myy,
                mxy: m.mxy - a.mxy,
                w: m.w - a.w,
            };
        }
        (m, i1 - i0 + 1)
    } else {
        // Wrapped ranges sum as C does, (last − a) + b, left to right.
        let (last, a, b) = (lfps[sz - 1], lfps[i0 - 1], lfps[i1]);
        (
            LineFitPt {
                mx: last.mx - a.mx + b.mx,
                my: last.my - a.my + b.my,
                mxx: last.mxx - a.mxx + b.mxx,
                myy: last.myy - a.myy + b.myy,
                mxy: last.mxy - a.mxy + b.mxy,
                w: last.w - a.w + b.w,
            },
            sz - i0 + i1 + 1,
        )
    }
}

/// The points' mean, their covariance (xx, xy, yy) and its larger and smaller eigenvalues.
fn covariance(m: &LineFitPt) -> ([f64; 2], [f64; 3], f64, f64) {
    let ex = m.mx / m.w;
    let ey = m.my / m.w;
    let cxx = m.mxx / m.w - ex * ex;
    let cxy = m.mxy / m.w - ex * ey;
    let cyy = m.myy / m.w - ey * ey;
    let root = sqrtf((cxx - cyy) * (cxx - cyy) + 4.0 * cxy * cxy);
    ([ex, ey], [cxx, cxy, cyy], 0.5 * (cxx + cyy + root), 0.5 * (cxx + cyy - root))
}

/// [`fit_line`]'s error alone: what the sliding window along a cluster needs, without the
/// line.
fn line_err(lfps: &[LineFitPt], i0: usize, i1: usize) -> f64 {
    let (m, n) = moments(lfps, i0, i1);
    n as f64 * covariance(&m).3
}

fn fit_line(lfps: &[LineFitPt], i0: usize, i1: usize) -> LineFit {
    let (m, n) = moments(lfps, i0, i1);
    let ([ex, ey], [cxx, cxy, cyy], eig, eig_small) = covariance(&m);
    let (nx1, ny1) = (cxx - eig, cxy);
    let m1 = nx1 * nx1 + ny1 * ny1;
    let (nx2, ny2) = (cxy, cyy - eig);
    let m2 = nx2 * nx2 + ny2 * ny2;
    let (nx, ny, mm) = if m1 > m2 { (nx1, ny1, m1) } else { (nx2, ny2, m2) };
    let length = sqrtf(mm);
    let (px, py) = if length.abs() < 1e-12 { (0.0, 0.0) } else { (nx / length, ny / length) };
    LineFit { params: [ex, ey, px, py], err: n as f64 * eig_small, mse: eig_small }
}

fn compute_lfps(pts: &[Pt], im: &ImageView<'_>) -> Vec<LineFitPt> {
    let mut out = Vec::with_capacity(pts.len());
    let mut acc = LineFitPt::default();
    let (w, h) = (im.width() as i64, im.height() as i64);
    for p in pts {
        let x = f64::from(p.x) * 0.5 + 0.5;
        let y = f64::from(p.y) * 0.5 + 0.5;
        let (ix, iy) = (x as i64, y as i64);
        let mut weight = 1.0;
        if ix > 0 && ix + 1 < w && iy > 0 && iy + 1 < h {
            let at = |x: i64, y: i64| i32::from(im.get(x as usize, y as usize).unwrap_or(0));
            let gx = at(ix + 1, iy) - at(ix - 1, iy);
            let gy = at(ix, iy + 1) - at(ix, iy - 1);
            weight = f64::from(gx * gx + gy * gy).sqrt() + 1.0;
        }
        acc.mx += weight * x;
        acc.my += weight * y;
        acc.mxx += weight * x * x;
        acc.mxy += weight * x * y;
        acc.myy += weight * y * y;
        acc.w += weight;
        out.push(acc);
    }
    out
}

/// Sorts `pts` by angle (their `f32` keys) into the order C's `ptsort` leaves them in, ties
/// included: ties decide which maxima win. C sorts leaves of at most five points (the first
/// halves of halves, down to five) by sorting networks, then merges them back taking from
/// the right on ties, so tied points end up by leaf from the last leaf to the first, and
/// within a leaf as its network left them. That order is written into each key's low bits
/// (the angle's order-preserving bits above), and the keys sorted as integers: the same
/// permutation without the merge sort's copies at every level (perf, the 1080p benchmark set
/// with C's parameters: the sorting 10 % of the time before, about 4 % after).
fn sort_by_angle(pts: &mut [(Pt, f32)], scratch: &mut Vec<(Pt, f32)>) {
    let n = pts.len();
    if pts.iter().any(|p| p.1.is_nan()) || n > u32::MAX as usize / 8 {
        // (C's comparisons with NaN are not an order; never the case with finite points.)
        scratch.clear();
        scratch.extend_from_slice(pts);
        return ptsort(pts, scratch);
    }
    let mut leaves = Vec::with_capacity(n / 3 + 1);
    leaf_ranges(0, n, &mut leaves);
    let last = leaves.len() - 1;
    // The point each (leaf from the last, place in its sorted leaf) code names.
    let mut named = vec![0u32; leaves.len() * 8];
    let mut keys = Vec::with_capacity(n);
    for (l, &(start, len)) in leaves.iter().enumerate() {
        let mut leaf = [(0.0f32, 0u32); 5];
        for (k, slot) in leaf[..len].iter_mut().enumerate() {
            *slot = (pts[start + k].1, (start + k) as u32);
        }
        network(&mut leaf[..len], |a, b| a.0 - b.0 > 0.0);
        for (place, &(key, index)) in leaf[..len].iter().enumerate() {
            let code = (last - l) * 8 + place;
            named[code] = index;
            keys.push((u64::from(ordered_bits(key)) << 32) | code as u64);
        }
    }
    keys.sort_unstable();
    scratch.clear();
    scratch.extend(keys.iter().map(|&k| pts[named[(k & 0xffff_ffff) as usize] as usize]));
    pts.copy_from_slice(scratch);
}

/// The bits of `v` as an unsigned integer in the order of the values (−0 as 0).
fn ordered_bits(v: f32) -> u32 {
    let bits = (v + 0.0).to_bits();
    if bits >> 31 == 1 { !bits } else { bits | 1 << 31 }
}

/// The leaves of C's merge sort over `len` points from `start`: halves (the first the
/// smaller) halved again down to at most five points, left to right.
fn leaf_ranges(start: usize, len: usize, out: &mut Vec<(usize, usize)>) {
    if len <= 5 {
        out.push((start, len));
    } else {
        let half = len / 2;
        leaf_ranges(start, half, out);
        leaf_ranges(start + half, len - half, out);
    }
}

/// C's sorting networks for up to five items, swapping a pair when `after(a, b)`.
fn network<T>(a: &mut [T], after: impl Fn(&T, &T) -> bool) {
    let pairs: &[(usize, usize)] = match a.len() {
        2 => &[(0, 1)],
        3 => &[(0, 1), (1, 2), (0, 1)],
        4 => &[(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)],
        5 => &[(0, 1), (3, 4), (1, 2), (0, 1), (0, 3), (2, 4), (1, 2), (2, 3), (1, 2)],
        _ => &[],
    };
    for &(i, j) in pairs {
        if after(&a[i], &a[j]) {
            a.swap(i, j);
        }
    }
}

/// C's `ptsort`: sorting networks up to 5, then a merge sort that takes from the right half
/// on ties (so not stable). `scratch` is as long as `pts`; C allocates at every level instead,
/// with the same result.
fn ptsort(pts: &mut [(Pt, f32)], scratch: &mut [(Pt, f32)]) {
    let sz = pts.len();
    if sz <= 5 {
        return network(pts, |a, b| a.1 - b.1 > 0.0);
    }
    // Sort copies of both halves (with `pts` as their scratch), then merge back.
    let tmp = &mut scratch[..sz];
    tmp.copy_from_slice(pts);
    let asz = sz / 2;
    let (a, b) = tmp.split_at_mut(asz);
    let (sa, sb) = pts.split_at_mut(asz);
    ptsort(a, sa);
    ptsort(b, sb);
    let (mut ai, mut bi, mut out) = (0, 0, 0);
    while ai < a.len() && bi < b.len() {
        if a[ai].1 - b[bi].1 < 0.0 {
            pts[out] = a[ai];
            ai += 1;
        } else {
            pts[out] = b[bi];
            bi += 1;
        }
        out += 1;
    }
    for &v in a[ai..].iter().chain(&b[bi..]) {
        pts[out] = v;
        out += 1;
    }
}

fn segment_maxima(lfps: &[LineFitPt], q: &QuadThreshold) -> Option<[usize; 4]> {
    let sz = lfps.len();
    let ksz = (sz / 12).min(20);
    if ksz < 2 {
        return None;
    }
    let errs: Vec<f64> = (0..sz).map(|i| line_err(lfps, (i + sz - ksz) % sz, (i + ksz) % sz)).collect();
    // Smooth with a Gaussian of σ = 1 cut at 5 % (7 taps, single-precision weights as in C).
    let sigma = 1.0f64;
    let fsz = 2 * (((-(0.05f64.ln()) * 2.0 * sigma * sigma).sqrt() + 1.0) as usize) + 1;
    let f: Vec<f32> = (0..fsz)
        .map(|i| {
            let j = i as i64 - (fsz / 2) as i64;
            ((-(j * j) as f64) / (2.0 * sigma * sigma)).exp() as f32
        })
        .collect();
    // The errors with the filter's half-width wrapped on at either end, so the taps need no
    // modulo (an integer division) each.
    let half = fsz / 2;
    let wrapped: Vec<f64> = (0..sz + 2 * half).map(|k| errs[(k + sz - half) % sz]).collect();
    let smoothed: Vec<f64> = wrapped
        .windows(fsz)
        .map(|w| {
            let mut acc = 0.0f64;
            for (e, fi) in w.iter().zip(&f) {
                acc += e * f64::from(*fi);
            }
            acc
        })
        .collect();
    let mut maxima: Vec<(usize, f64)> = (0..sz)
        .filter(|&i| smoothed[i] > smoothed[(i + 1) % sz] && smoothed[i] > smoothed[(i + sz - 1) % sz])
        .map(|i| (i, smoothed[i]))
        .collect();
    if maxima.len() < 4 {
        return None;
    }
    if maxima.len() > q.max_nmaxima {
        let mut sorted: Vec<f64> = maxima.iter().map(|m| m.1).collect();
        sorted.sort_by(|a, b| b.total_cmp(a));
        let thresh = sorted[q.max_nmaxima];
        maxima.retain(|m| m.1 > thresh);
    }
    let n = maxima.len();
    let max_dot = f64::from(q.cos_critical_rad);
    let max_mse = f64::from(q.max_line_fit_mse);
    // Each line between two maxima, fitted once however many combinations try it.
    let mut fits: Vec<Option<LineFit>> = std::iter::repeat_with(|| None).take(n * n).collect();
    let mut line = |a: usize, b: usize| -> LineFit {
        *fits[a * n + b].get_or_insert_with(|| fit_line(lfps, maxima[a].0, maxima[b].0))
    };
    let mut best = None;
    let mut best_error = f64::from(f32::INFINITY);
    for m0 in 0..n.saturating_sub(3) {
        for m1 in m0 + 1..n.saturating_sub(2) {
            let l01 = line(m0, m1);
            if l01.mse > max_mse {
                continue;
            }
            for m2 in m1 + 1..n.saturating_sub(1) {
                let l12 = line(m1, m2);
                if l12.mse > max_mse {
                    continue;
                }
                let dot = l01.params[2] * l12.params[2] + l01.params[3] * l12.params[3];
                if dot.abs() > max_dot {
                    continue;
                }
                for m3 in m2 + 1..n {
                    let l23 = line(m2, m3);
                    if l23.mse > max_mse {
                        continue;
                    }
                    let l30 = line(m3, m0);
                    if l30.mse > max_mse {
                        continue;
                    }
                    let err = l01.err + l12.err + l23.err + l30.err;
                    if err < best_error {
                        best_error = err;
                        best = Some([maxima[m0].0, maxima[m1].0, maxima[m2].0, maxima[m3].0]);
                    }
                }
            }
        }
    }
    let best = best?;
    (best_error / (sz as f64) < max_mse).then_some(best)
}

/// Where two lines (point, unit normal: `[x, y, nx, ny]`) meet, as C computes it, with the
/// determinant of the system so each caller can apply its own test of near-parallel lines.
pub(crate) fn intersect_lines(a: &[f64; 4], b: &[f64; 4]) -> (f64, [f32; 2]) {
    let (a00, a01, a10, a11) = (a[3], -b[3], -a[2], b[2]);
    let (b0, b1) = (-a[0] + b[0], -a[1] + b[1]);
    let det = a00 * a11 - a10 * a01;
    let (w00, w01) = (a11 / det, -a01 / det);
    let l0 = w00 * b0 + w01 * b1;
    (det, [(a[0] + l0 * a00) as f32, (a[1] + l0 * a10) as f32])
}

/// Fits a quad to one cluster, or `None` if it is not a plausible tag border. `im` is the image
/// the clusters were found on; `min_tag_width` is the smallest tag (in its pixels) to keep.
pub fn fit_quad(cluster: &[Pt], im: &ImageView<'_>, q: &QuadThreshold, min_tag_width: i32) -> Option<Quad> {
    let sz = cluster.len();
    if sz < 24 {
        return None;
    }
    let (mut xmin, mut xmax, mut ymin, mut ymax) = (cluster[0].x, cluster[0].x, cluster[0].y, cluster[0].y);
    for p in &cluster[1..] {
        xmax = xmax.max(p.x);
        xmin = xmin.min(p.x);
        ymax = ymax.max(p.y);
        ymin = ymin.min(p.y);
    }
    if (i32::from(xmax) - i32::from(xmin)) * (i32::from(ymax) - i32::from(ymin)) < min_tag_width {
        return None;
    }
    let cx = ((f64::from(xmin) + f64::from(xmax)) * 0.5 + 0.05118) as f32;
    let cy = ((f64::from(ymin) + f64::from(ymax)) * 0.5 - 0.028581) as f32;
    let mut dot = 0.0f32;
    // C's quadrant offsets (2 << 15 = 65536) keep the four quadrants' slopes apart.
    let quadrants = [[-65536.0f32, 0.0], [131072.0, 65536.0]];
    let mut pts: Vec<(Pt, f32)> = Vec::with_capacity(sz);
    for p in cluster {
        let mut dx = f32::from(p.x) - cx;
        let mut dy = f32::from(p.y) - cy;
        dot += dx * f32::from(p.gx) + dy * f32::from(p.gy);
        let quadrant = quadrants[usize::from(dy > 0.0)][usize::from(dx > 0.0)];
        if dy < 0.0 {
            dy = -dy;
            dx = -dx;
        }
        if dx < 0.0 {
            let t = dx;
            dx = dy;
            dy = -t;
        }
        pts.push((*p, quadrant + dy / dx));
    }
    // tag36h11 has a normal (dark outside light) border: reject reversed ones.
    if dot < 0.0 {
        return None;
    }
    let mut scratch = Vec::with_capacity(sz);
    sort_by_angle(&mut pts, &mut scratch);
    let sorted: Vec<Pt> = pts.iter().map(|p| p.0).collect();
    let lfps = compute_lfps(&sorted, im);
    let idx = segment_maxima(&lfps, q)?;
    let mut lines = [[0.0f64; 4]; 4];
    for i in 0..4 {
        let l = fit_line(&lfps, idx[i], idx[(i + 1) & 3]);
        if l.mse > f64::from(q.max_line_fit_mse) {
            return None;
        }
        lines[i] = l.params;
    }
    let mut p = [[0.0f32; 2]; 4];
    for i in 0..4 {
        let (det, corner) = intersect_lines(&lines[i], &lines[(i + 1) & 3]);
        if det.abs() < 0.001 {
            return None;
        }
        p[i] = corner;
    }
    let pd = |i: usize| [f64::from(p[i][0]), f64::from(p[i][1])];
    let dist = |i: usize, j: usize| ((pd(j)[0] - pd(i)[0]).powi(2) + (pd(j)[1] - pd(i)[1]).powi(2)).sqrt();
    let heron = |a: f64, b: f64, c: f64| {
        let s = (a + b + c) / 2.0;
        (s * (s - a) * (s - b) * (s - c)).sqrt()
    };
    let area = heron(dist(0, 1), dist(1, 2), dist(2, 0)) + heron(dist(2, 3), dist(3, 0), dist(0, 2));
    if area < 0.95 * f64::from(min_tag_width) * f64::from(min_tag_width) {
        return None;
    }
    let cos_crit = f64::from(q.cos_critical_rad);
    for i in 0..4 {
        let (p0, p1, p2) = (pd(i), pd((i + 1) & 3), pd((i + 2) & 3));
        let (dx1, dy1) = (p1[0] - p0[0], p1[1] - p0[1]);
        let (dx2, dy2) = (p2[0] - p1[0], p2[1] - p1[1]);
        let cos = (dx1 * dx2 + dy1 * dy2) / ((dx1 * dx1 + dy1 * dy1) * (dx2 * dx2 + dy2 * dy2)).sqrt();
        if cos > cos_crit || cos < -cos_crit || dx1 * dy2 < dy1 * dx2 {
            return None;
        }
    }
    Some(Quad { p })
}

/// Fits quads to every cluster of a `w × h` image, with C's size limits per cluster.
pub fn fit_quads(
    clusters: &[Vec<Pt>],
    im: &ImageView<'_>,
    q: &QuadThreshold,
    quad_decimate: f32,
    workers: &Workers,
) -> Vec<Quad> {
    // The smallest tag border is 8 cells; C divides it by the decimation (as an int) and keeps
    // at least 3.
    let mut min_tag_width = (8.0 / quad_decimate) as i32;
    if quad_decimate <= 1.0 {
        min_tag_width = 8;
    }
    let min_tag_width = min_tag_width.max(3);
    let max_points = 2 * (2 * im.width() + 2 * im.height());
    let candidates: Vec<&[Pt]> = clusters
        .iter()
        .filter(|c| c.len() >= q.min_cluster_pixels && c.len() <= max_points)
        .map(Vec::as_slice)
        .collect();
    workers.filter_map(&candidates, |c| fit_quad(c, im, q, min_tag_width))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clusters::gradient_clusters;
    use crate::components::connected_components;
    use crate::threshold::threshold;

    /// The integer sort leaves points in C's merge sort's order, ties included, whatever
    /// their number and however many tie: every length to 300 and some longer, with keys from
    /// a handful of values (most tie) to all distinct, negative zeros among them.
    #[test]
    fn points_sort_as_cs_merge_sort_leaves_them() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut checked = 0;
        for n in (0..=300).chain([511, 512, 513, 1000, 4097]) {
            for distinct in [1u64, 3, 17, 1 << 20] {
                let pts: Vec<(Pt, f32)> = (0..n)
                    .map(|i| {
                        let v = (next() % distinct) as f32 - (distinct / 2) as f32;
                        let key = if v == 0.0 && next() % 2 == 0 { -0.0 } else { v * 0.25 };
                        (Pt { x: i as u16, y: (i >> 16) as u16, gx: 0, gy: 0 }, key)
                    })
                    .collect();
                let (mut c, mut scratch) = (pts.clone(), pts.clone());
                ptsort(&mut c, &mut scratch);
                let mut ours = pts.clone();
                sort_by_angle(&mut ours, &mut Vec::new());
                assert!(ours == c, "{n} points of {distinct} values: another order than C's");
                checked += 1;
            }
        }
        assert_eq!(checked, 306 * 4);
    }

    #[test]
    fn a_dark_square_gives_its_four_corners() {
        let (w, h) = (60, 60);
        let mut data = vec![230u8; w * h];
        for y in 15..45 {
            for x in 15..45 {
                data[y * w + x] = 20;
            }
        }
        let im = ImageView::new(&data, w, h, w).expect("valid");
        let t = threshold(&im, 5, false);
        let mut uf = connected_components(&t);
        let clusters = gradient_clusters(&t, &mut uf);
        let quads = fit_quads(&clusters, &im, &QuadThreshold::default(), 1.0, &Workers::single());
        assert_eq!(quads.len(), 1, "{quads:?}");
        // The boundary runs between pixels 14|15 and 44|45, i.e. at 15 and 45 in C's
        // corner-origin coordinates.
        let mut corners: Vec<[f32; 2]> = quads[0].p.to_vec();
        corners.sort_by(|a, b| (a[0] + 3.0 * a[1]).total_cmp(&(b[0] + 3.0 * b[1])));
        for (c, want) in corners.iter().zip([[15.0, 15.0], [45.0, 15.0], [15.0, 45.0], [45.0, 45.0]]) {
            assert!((c[0] - want[0]).abs() < 0.6 && (c[1] - want[1]).abs() < 0.6, "{c:?} vs {want:?}");
        }
    }
}
