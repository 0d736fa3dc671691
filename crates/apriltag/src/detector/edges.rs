//! Edge refinement at full resolution: each side of a quad found on the decimated image is
//! re-fitted to the strongest gradient along its normal, C's way or in linear light with one
//! edge per window, widened to take in the whole ramp of a motion-blurred edge (see
//! [`DetectorConfig::linear_edges`](crate::DetectorConfig::linear_edges)).

use crate::image::ImageView;
use crate::quads::{Quad, intersect_lines};
use std::ops::RangeInclusive;

/// How far a window widened for a ramp reaches beyond the ramp's half-height points (px): the
/// gradient over 2 px adds 1, the lens blur's tails about 1 more.
const RAMP_MARGIN: f64 = 2.0;

/// One sample's fit along a side: its offset, whether it took one edge of several, whether the
/// edge ran on past its window (see [`SideFit::fit`]).
type Fit = Option<(f64, bool, bool)>;

/// C's `refine_edges`: each edge is re-fitted at full resolution to the points of strongest
/// gradient found along its normal, and the corners re-intersected. `lut` maps pixel values
/// before interpolation (identity for C's behaviour, sRGB → linear for unbiased edges);
/// `recentre` re-centres the search window on the edge (C does not); `ramps` widens it over
/// the ramp of an edge smeared by motion ([`crate::DetectorConfig::smeared_edges`]). `cells`
/// is the family's width at the border (8 for tag36h11): a cell is the quad's side over it, the
/// farthest a window may reach before it sees the next edge inside the tag.
pub(super) fn refine_edges(
    im: &ImageView<'_>,
    quad: &mut Quad,
    quad_decimate: f32,
    lut: &[f64; 256],
    recentre: bool,
    ramps: bool,
    cells: f64,
) {
    let range = (f64::from(quad_decimate) + 1.0) as i64;
    // Our windows reach at least 3 px: undecimated 4K frames blur edges wider than C's ±2 px.
    let base = if recentre { range.max(3) } else { range };
    let (w, h) = (im.width() as i64, im.height() as i64);
    let refine = Refine { im, lut, w, h, range, base, recentre, cells };
    let mut lines = [[0.0f64; 4]; 4];
    let mut points = Vec::new();
    // A side's summed gradient profile, per quarter pixel (only every other step is filled).
    let mut profile = Vec::new();
    for (edge, line) in lines.iter_mut().enumerate() {
        let mut side = SideFit { refine: &refine, side: Side::new(quad, edge, cells), bufs: Buffers::default() };
        *line = side.fit_side(ramps, &mut points, &mut profile);
    }
    for i in 0..4 {
        // C keeps the old corner when the refined edges are near parallel.
        let (det, corner) = intersect_lines(&lines[i], &lines[(i + 1) & 3]);
        if det.abs() > 0.001 {
            quad.p[(i + 1) & 3] = corner;
        }
    }
}

/// What every side's fit shares: the image (through `lut`) and the windows' extent.
struct Refine<'a> {
    im: &'a ImageView<'a>,
    lut: &'a [f64; 256],
    /// The image's size (px).
    w: i64,
    h: i64,
    /// How far a window's centre may sit from the quad's edge (px).
    range: i64,
    /// The usual window's half-width (px).
    base: i64,
    /// See `refine_edges`.
    recentre: bool,
    cells: f64,
}

impl Refine<'_> {
    /// Pixel (x, y) through the lookup table (0 off the image).
    fn px(&self, x: i64, y: i64) -> f64 {
        self.lut[usize::from(self.im.get(x as usize, y as usize).unwrap_or(0))]
    }
}

/// One side of the quad, from corner `pa` to corner `pb`, with the opposite side (from `qa`
/// along `u`) that cells are measured against.
struct Side {
    pa: [f64; 2],
    pb: [f64; 2],
    /// The unit normal.
    nx: f64,
    ny: f64,
    nsamples: i64,
    qa: [f64; 2],
    ux: f64,
    uy: f64,
    /// The widest cell along the side (px).
    widest_cell: f64,
}

impl Side {
    /// Side `edge` of `quad` (corners `edge` and `edge + 1`), for a family `cells` wide.
    fn new(quad: &Quad, edge: usize, cells: f64) -> Side {
        let (a, b) = (edge, (edge + 1) & 3);
        let (pa, pb) = (quad.p[a].map(f64::from), quad.p[b].map(f64::from));
        let mut nx = pb[1] - pa[1];
        let mut ny = -pb[0] + pa[0];
        let mag = (nx * nx + ny * ny).sqrt();
        nx /= mag;
        ny /= mag;
        let nsamples = 16.max((mag / 8.0) as i64);
        // Cells are the black square's width over 8, here measured to the opposite side.
        let (qa, qb) = (quad.p[(edge + 2) & 3].map(f64::from), quad.p[(edge + 3) & 3].map(f64::from));
        let (ux, uy) = (qb[0] - qa[0], qb[1] - qa[1]);
        let mut side = Side { pa, pb, nx, ny, nsamples, qa, ux, uy, widest_cell: 0.0 };
        side.widest_cell = side.across(pa[0], pa[1]).max(side.across(pb[0], pb[1])) / cells;
        side
    }

    /// The black square's width at (x0, y0): its distance to the opposite side.
    fn across(&self, x0: f64, y0: f64) -> f64 {
        let (ux, uy, qa) = (self.ux, self.uy, self.qa);
        ((ux * (y0 - qa[1]) - uy * (x0 - qa[0])) / ux.hypot(uy)).abs()
    }

    /// Where sample `s` looks from along the side.
    fn point(&self, s: i64) -> [f64; 2] {
        let (pa, pb) = (self.pa, self.pb);
        let alpha = (1.0 + s as f64) / (self.nsamples as f64 + 1.0);
        [alpha * pa[0] + (1.0 - alpha) * pb[0], alpha * pa[1] + (1.0 - alpha) * pb[1]]
    }
}

/// One sample's point: its index, where it looks from, the offset of the edge found along the
/// normal, and whether it took one edge of several.
struct EdgePoint {
    s: i64,
    at: [f64; 2],
    offset: f64,
    cut: bool,
}

/// Buffers reused from sample to sample along a side.
#[derive(Default)]
struct Buffers {
    /// The image along a sample's normal per quarter pixel (None = not yet read).
    cache: Vec<Option<Option<f64>>>,
    /// One window's image values per quarter pixel.
    vals: Vec<Option<f64>>,
    /// One window's gradient over 1 px per quarter pixel.
    grads: Vec<f64>,
}

/// One side being re-fitted.
struct SideFit<'r> {
    refine: &'r Refine<'r>,
    side: Side,
    bufs: Buffers,
}

impl SideFit<'_> {
    /// The side's line (a point on it, its direction), fitted to its samples' points.
    fn fit_side(&mut self, ramps: bool, points: &mut Vec<EdgePoint>, profile: &mut Vec<f64>) -> [f64; 4] {
        let r = self.refine;
        let mut ramp = 0.0;
        let flat = self.fit_all(points, ramp);
        // Motion blur smears an edge into a ramp as wide as the motion during the exposure (in
        // linear light the ramp is straight and its centre the edge at mid-exposure), and the
        // lens blurs a near or far tag's edges wider than the window too. A window inside the
        // ramp sees a flat gradient whose mean is wherever the window sits. Where the edge ran
        // past half the samples' windows, the ramp's width at half its height is read from the
        // side's summed profile (out to a cell), and the side fitted again with windows that
        // take it in whole. (A cell narrower than the usual window holds no ramp to widen for.)
        if ramps
            && r.recentre
            && !points.is_empty()
            && flat * 2 >= points.len()
            && self.side.widest_cell > r.base as f64 + 0.5
            && let Some(half_width) = self.ramp_width(points, profile)
        {
            ramp = half_width;
            self.fit_all(points, ramp);
        }
        self.unsplit(points, profile, ramp);
        fit_line(points, self.side.nx, self.side.ny)
    }

    /// Each sample's point into `points`; returns how many found the edge running past their
    /// window. A wide ramp is one edge: its windows are not split.
    fn fit_all(&mut self, points: &mut Vec<EdgePoint>, ramp: f64) -> usize {
        points.clear();
        let mut flat = 0;
        for s in 0..self.side.nsamples {
            let at = self.side.point(s);
            if let Some((offset, cut, f)) = self.fit(s, ramp <= 0.0, None, ramp) {
                points.push(EdgePoint { s, at, offset, cut });
                flat += usize::from(f);
            }
        }
        flat
    }

    /// The side's summed profile over 1 px, as far as its windows look, summed over every
    /// `step`-th sample.
    fn summed(&mut self, profile: &mut Vec<f64>, ramp: f64, step: usize) {
        let (range, base) = (self.refine.range, self.refine.base);
        let far = if ramp > 0.0 { base.max((ramp + RAMP_MARGIN).ceil() as i64) } else { base };
        profile.clear();
        profile.resize((8 * (range + far)) as usize + 1, 0.0);
        for s in (0..self.side.nsamples).step_by(step) {
            self.fit(s, false, Some(&mut profile[..]), ramp);
        }
    }

    /// The half-width of the ramp a smeared side's windows must take in, read from its summed
    /// profile around the samples' median offset; None when the usual window nearly takes it
    /// in, or when it does not fit in a cell.
    fn ramp_width(&mut self, points: &[EdgePoint], profile: &mut Vec<f64>) -> Option<f64> {
        let base = self.refine.base;
        let widest_cell = self.side.widest_cell;
        // Out to a cell (as far as windows for a ramp a cell wide look), over every sample,
        // then smoothed over a pixel: a wide ramp's gradient is low, and on a noisy frame (a
        // 2× sensor crop gathers a quarter of the light per pixel) one spike taken as its
        // height cut the ramp's width at half of it to a third (corners 3–5 px off).
        self.summed(profile, widest_cell, 1);
        smooth_even(profile, 2);
        let mut offsets: Vec<f64> = points.iter().map(|p| p.offset).collect();
        offsets.sort_by(f64::total_cmp);
        let at = (profile.len() / 2) as i64 + (4.0 * offsets[offsets.len() / 2]).round() as i64;
        let (lo, hi) = ramp_extent(profile, at, base)?;
        let half_width = 0.125 * (hi - lo) as f64;
        // A ramp the usual window nearly takes in is left to it; one that does not fit
        // in a cell is no lone edge (on a small tag, the next edges merge into it).
        let need = half_width + RAMP_MARGIN;
        (need > base as f64 + 0.5 && need <= widest_cell).then_some(half_width)
    }

    /// Refits the samples that took one edge of several with their whole windows, unless the
    /// side's summed profile shows two edges.
    fn unsplit(&mut self, points: &mut [EdgePoint], profile: &mut Vec<f64>, ramp: f64) {
        // One sample's profile is too noisy to tell a second edge from noise: on a dim, blurred
        // grazing tag (gradients of a few levels, wiggles of a level or two over a blur several
        // pixels wide) it dips by a tenth here and there, and taking one of the bumps moved the
        // side by 1–2 px. So the window stays split only where the side's summed profile shows
        // two edges; elsewhere every sample takes its whole window, fitted anew.
        let cuts = points.iter().filter(|p| p.cut).count();
        if !self.refine.recentre || cuts == 0 {
            return;
        }
        // (Fewer than a quarter of the samples split: noise, without summing.)
        let two = cuts * 4 >= points.len() && {
            // (Every other sample: half the work, and the noise still falls by a factor
            // of 3 or so.)
            self.summed(profile, ramp, 2);
            let half: Vec<f64> = profile.iter().copied().step_by(2).collect();
            lobes(&half).len() > 1
        };
        if !two {
            for p in points.iter_mut().filter(|p| p.cut) {
                if let Some((whole, _, _)) = self.fit(p.s, false, None, ramp) {
                    p.offset = whole;
                }
            }
        }
    }

    /// Sample `s`'s fit: the offset of the edge along the normal, whether it took one edge of
    /// several in its window (only with `split`), and whether the edge's gradient ran on past
    /// its window (a ramp wider than it); with `sum`, adds its gradient profile to it
    /// instead. `ramp` > 0 is the half-width of a wide ramp the side's windows must take in.
    fn fit(&mut self, s: i64, split: bool, sum: Option<&mut [f64]>, ramp: f64) -> Fit {
        let r = self.refine;
        let [x0, y0] = self.side.point(s);
        // The window stays within half a cell of the edge: on a small or steeply tilted
        // tag, a wider one takes in the next edge out. A wide ramp's window stays within a
        // cell: the next edge of the same sign lies a cell out at the nearest (beyond the
        // white border), as blurred as this one.
        let across = self.side.across(x0, y0);
        let mut reach = (r.base as f64).min((across / 16.0).max(1.0));
        if ramp > 0.0 {
            reach = reach.max((ramp + RAMP_MARGIN).min(across / r.cells));
        }
        // The image along the normal, sampled once per quarter pixel from −(range + far + 1)
        // to range + far + 1 px (windows of ±reach centred within ±range), as each window
        // needs it (`cache` holds them: None = not yet).
        let far = r.base.max(reach.ceil() as i64);
        let lowest = -((r.range + far) as f64) - 1.0;
        let Buffers { cache, vals, grads } = &mut self.bufs;
        cache.clear();
        cache.resize((4 * (2 * (r.range + far) + 2) + 1) as usize, None);
        let (nx, ny) = (self.side.nx, self.side.ny);
        let mut normal = Normal { refine: r, x0, y0, nx, ny, lowest, first: (4.0 * lowest) as i64, cache };
        if !r.recentre {
            return normal.c_mean(r.range);
        }
        // Cells wider than the farthest the window looks (its centre moves up to ±range,
        // gradients and blur reach ~3 px beyond it, the quad is off by ~1 px): one edge.
        let lone = across / r.cells > r.range as f64 + reach + 4.0;
        // The gradient profile over 1 px (what `one_edge` splits), to sum along the side.
        if let Some(profile) = sum {
            if !lone {
                normal.add_profile(profile, r.range, reach);
            }
            return None;
        }
        Window { normal, reach, lone, ramp, vals, grads }.recentred(r.range, split)
    }
}

/// The image along one sample's normal from (x0, y0), read per quarter pixel as windows need
/// it.
struct Normal<'r, 'c> {
    refine: &'r Refine<'r>,
    x0: f64,
    y0: f64,
    nx: f64,
    ny: f64,
    /// The offset (px) of the cache's first entry.
    lowest: f64,
    /// That offset in quarter-pixel steps.
    first: i64,
    cache: &'c mut [Option<Option<f64>>],
}

impl Normal<'_, '_> {
    /// The image (bilinearly interpolated) at `pos` px along the normal, on the quarter-pixel
    /// grid; None off the image.
    fn sample(&mut self, pos: f64) -> Option<f64> {
        // pos is on the quarter-pixel grid above `lowest`: round to its index.
        let j = ((pos - self.lowest) * 4.0 + 0.5) as usize;
        if self.cache[j].is_none() {
            self.cache[j] = Some(self.interpolate(pos));
        }
        self.cache[j].flatten()
    }

    /// The image at `pos` px along the normal, bilinearly interpolated; None off the image.
    fn interpolate(&self, pos: f64) -> Option<f64> {
        let r = self.refine;
        let (xi, yi, fa, fb) = self.footing(pos);
        if xi < 0 || xi + 1 >= r.w || yi < 0 || yi + 1 >= r.h {
            return None;
        }
        Some(blend(fa, fb, [r.px(xi, yi), r.px(xi + 1, yi), r.px(xi, yi + 1), r.px(xi + 1, yi + 1)]))
    }

    /// The pixel whose corner of four the point `pos` px along the normal is interpolated
    /// from, and its fractions: the integer parts toward zero (the casts, as C's `modf`),
    /// fractions with the value's sign.
    fn footing(&self, pos: f64) -> (i64, i64, f64, f64) {
        let x = self.x0 + pos * self.nx - 0.5;
        let y = self.y0 + pos * self.ny - 0.5;
        let (xi, yi) = (x as i64, y as i64);
        (xi, yi, x - xi as f64, y - yi as f64)
    }

    /// Reads every quarter-pixel step `lo..=hi` (the points k/4 px along the normal) not yet
    /// read. Where the steps at both ends lie inside the image so do all between (the point
    /// moves monotonically with k, and the pixels that qualify make an interval each way), and
    /// they are interpolated without a test each: the same values [`Normal::sample`] gives.
    /// A window's steps are read at once this way (per step, the cache's tests were a tenth
    /// of a detection with C's parameters).
    fn fill(&mut self, lo: i64, hi: i64) {
        let inside = |n: &Self, k: i64| {
            let (xi, yi, _, _) = n.footing(0.25 * k as f64);
            xi >= 0 && xi + 1 < n.refine.w && yi >= 0 && yi + 1 < n.refine.h
        };
        if !(inside(self, lo) && inside(self, hi)) {
            for k in lo..=hi {
                self.sample(0.25 * k as f64);
            }
            return;
        }
        let r = self.refine;
        let (data, stride, lut) = (r.im.data(), r.im.stride(), r.lut);
        for k in lo..=hi {
            let j = (k - self.first) as usize;
            if self.cache[j].is_some() {
                continue;
            }
            let (xi, yi, fa, fb) = self.footing(0.25 * k as f64);
            let at = yi as usize * stride + xi as usize;
            let (a, b) = (&data[at..at + 2], &data[at + stride..at + stride + 2]);
            let px = |v: u8| lut[usize::from(v)];
            self.cache[j] = Some(Some(blend(fa, fb, [px(a[0]), px(a[1]), px(b[0]), px(b[1])])));
        }
    }

    /// Step k's value once [`Normal::fill`] has read it.
    fn filled(&self, k: i64) -> Option<f64> {
        self.cache[(k - self.first) as usize].flatten()
    }

    /// C's fit: the squared-gradient-weighted mean offset over a window at the quad's edge,
    /// ±`range` px, every step in it whole.
    fn c_mean(&mut self, range: i64) -> Fit {
        let (mut mn, mut mcount) = (0.0, 0.0);
        self.fill(-4 * range - 4, 4 * range + 4);
        for k in -4 * range..=4 * range {
            let nn = 0.25 * k as f64;
            let Some(g1) = self.filled(k + 4) else { continue };
            let Some(g2) = self.filled(k - 4) else { continue };
            if g1 < g2 {
                continue; // the gradient runs backwards here
            }
            let weight = (g2 - g1) * (g2 - g1);
            mn += weight * nn;
            mcount += weight;
        }
        (mcount > 0.0).then(|| (mn / mcount, false, false))
    }

    /// Adds the gradient over 1 px along the normal to `profile` (centred on its middle), over
    /// as far as this sample's windows look.
    fn add_profile(&mut self, profile: &mut [f64], range: i64, reach: f64) {
        let kmax = (profile.len() / 2) as i64;
        // Every half pixel (even steps) is enough to see a dip between edges a cell
        // (2 px or more) apart.
        let far = ((((range as f64 + reach) * 2.0).ceil() as i64) * 2).min(kmax);
        for k in (-far..=far).step_by(2) {
            let (a, b) = (self.sample(0.25 * (k + 2) as f64), self.sample(0.25 * (k - 2) as f64));
            if let (Some(g1), Some(g2)) = (a, b) {
                profile[(k + kmax) as usize] += (g1 - g2).max(0.0);
            }
        }
    }
}

/// The bilinear blend at fractions (`fa` across, `fb` down) of a pixel's corner of four: top
/// left, top right, bottom left, bottom right. One expression for both ways of reading, so
/// that they give the same values to the last bit.
fn blend(fa: f64, fb: f64, [tl, tr, bl, br]: [f64; 4]) -> f64 {
    (1.0 - fa) * (1.0 - fb) * tl + fa * (1.0 - fb) * tr + (1.0 - fa) * fb * bl + fa * fb * br
}

/// The windows of ±`reach` px one sample fits along its normal.
struct Window<'r, 'c> {
    normal: Normal<'r, 'c>,
    reach: f64,
    /// Whether the cells are wide enough that a window sees one edge only.
    lone: bool,
    /// See `SideFit::fit`.
    ramp: f64,
    vals: &'c mut Vec<Option<f64>>,
    grads: &'c mut Vec<f64>,
}

impl Window<'_, '_> {
    /// The fit of a window re-centred on the edge it finds.
    fn recentred(&mut self, range: i64, split: bool) -> Fit {
        // A window off-centre on the edge cuts one tail of the gradient and pulls the mean
        // toward its centre (up to 0.1 px, with the edge's sub-pixel phase): centre it
        // (within ±range of the quad's edge) on the edge found and measure again.
        let mut found = self.centroid(0.0, split)?;
        for _ in 0..3 {
            let c = found.0.clamp(-(range as f64), range as f64);
            let Some(next) = self.centroid(c, split) else { break };
            let moved = (next.0 - found.0).abs();
            found = next;
            if moved < 1e-3 {
                break;
            }
        }
        Some(found)
    }

    /// The gradient-weighted mean offset along the normal over the window [c − reach,
    /// c + reach], from quarter-pixel steps; each step counts by how much of its quarter
    /// pixel lies inside, so the mean moves smoothly with `c`.
    fn centroid(&mut self, c: f64, split: bool) -> Fit {
        let reach = self.reach;
        let (first, last) = (((c - reach) * 4.0).round() as i64, ((c + reach) * 4.0).round() as i64);
        // The image at every quarter pixel the window's gradients need, read once.
        let normal = &mut self.normal;
        self.vals.clear();
        normal.fill(first - 4, last + 4);
        self.vals.extend((first - 4..=last + 4).map(|k| normal.filled(k)));
        let steps = Steps { vals: self.vals, first, last, c, reach };
        // Only the one edge nearest the window's centre: a small or steeply tilted
        // tag's cells are a few pixels wide, and the window can reach the next edge
        // out, from the white border to a brighter background, which in linear light
        // weighs as much as the black border's own and would pull the line outward.
        // Edges are told apart on the gradient over 1 px, sharp enough to show the
        // dip between two edges a cell apart. With `split` false, the whole window (the
        // side's summed profile decides which is kept, `SideFit::unsplit`).
        let (lo, hi) = if self.lone || !split {
            (0, (last - first) as usize)
        } else {
            self.grads.clear();
            self.grads.extend((first..=last).map(|k| steps.grad(k, 2)));
            one_edge(self.grads, ((c * 4.0).round() as i64 - first) as usize)
        };
        let cut = lo > 0 || hi < (last - first) as usize;
        let span = first + lo as i64..=first + hi as i64;
        let floor = steps.floor(span.clone(), self.ramp);
        let (mn, mcount, peak) = steps.weighted(span, floor);
        // A blurred step's gradient at the ends of a window centred on it is a small
        // part of its peak; a ramp wider than the window keeps half of it at one end at
        // least (the window may sit off the ramp's centre).
        let flat = !cut && peak > 0.0 && steps.grad(first, 4).max(steps.grad(last, 4)) >= 0.5 * peak;
        (mcount > 0.0).then(|| (mn / mcount, cut, flat))
    }
}

/// One window [c − reach, c + reach] (quarter-pixel steps `first..=last`), with the image at
/// every step from `first − 4` to `last + 4`.
struct Steps<'v> {
    vals: &'v [Option<f64>],
    first: i64,
    last: i64,
    c: f64,
    reach: f64,
}

impl Steps<'_> {
    /// The gradient at step k over ±d quarter pixels (0 where it runs backwards or leaves the
    /// image).
    fn grad(&self, k: i64, d: i64) -> f64 {
        let at = |k: i64| self.vals[(k - self.first + 4) as usize];
        match (at(k + d), at(k - d)) {
            (Some(g1), Some(g2)) if g1 >= g2 => g1 - g2,
            _ => 0.0,
        }
    }

    /// The gradient below which a step of `span` does not count. Across a wide ramp only the
    /// gradient above half the ramp's height counts (its height: the largest gradient within
    /// its half-width of the window's centre). The top half of a symmetric ramp is centred on
    /// it whatever its width; the shoulder of a neighbouring edge merged into its foot at a
    /// grazing view, and noise on the flats either side, would pull the mean toward them.
    fn floor(&self, span: RangeInclusive<i64>, ramp: f64) -> f64 {
        if ramp > 0.0 {
            let near = span.filter(|&k| (0.25 * k as f64 - self.c).abs() <= ramp);
            0.5 * near.map(|k| self.grad(k, 4)).fold(0.0, f64::max)
        } else {
            0.0
        }
    }

    /// Over the steps of `span`: the sum of weight × offset, the sum of weights, and the
    /// largest gradient.
    fn weighted(&self, span: RangeInclusive<i64>, floor: f64) -> (f64, f64, f64) {
        let (c, reach) = (self.c, self.reach);
        let (mut mn, mut mcount) = (0.0, 0.0);
        let mut peak = 0.0f64;
        for k in span {
            let nn = 0.25 * k as f64;
            // Each step counts by how much of its quarter pixel lies inside.
            let inside = if k == self.first || k == self.last {
                let (a, b) = ((nn - 0.125).max(c - reach), (nn + 0.125).min(c + reach));
                ((b - a) * 4.0).clamp(0.0, 1.0)
            } else {
                1.0
            };
            // Within that edge, weights are the gradient over 2 px, as C's (less noisy).
            // C squares the gradient, which pulls the mean toward pixel centres by up
            // to 0.1 px on edges along the pixel grid; the plain gradient's mean is the
            // edge at which the areas balance, exact for a linearly interpolated edge.
            let g = self.grad(k, 4);
            peak = peak.max(g);
            let weight = inside * (g - floor).max(0.0);
            mn += weight * nn;
            mcount += weight;
        }
        (mn, mcount, peak)
    }
}

/// The line through the edge points (their mean, and the direction of their principal axis)
/// as C fits it, each point `offset` along the normal (nx, ny) from where it looked from.
fn fit_line(points: &[EdgePoint], nx: f64, ny: f64) -> [f64; 4] {
    let (mut mx, mut my, mut mxx, mut mxy, mut myy, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for p in points {
        let (bx, by) = (p.at[0] + p.offset * nx, p.at[1] + p.offset * ny);
        mx += bx;
        my += by;
        mxx += bx * bx;
        mxy += bx * by;
        myy += by * by;
        n += 1.0;
    }
    let (ex, ey) = (mx / n, my / n);
    let cxx = mxx / n - ex * ex;
    let cxy = mxy / n - ex * ey;
    let cyy = myy / n - ey * ey;
    let theta = 0.5 * ((-2.0 * cxy) as f32).atan2((cyy - cxx) as f32);
    [ex, ey, f64::from(theta.cos()), f64::from(theta.sin())]
}

/// A profile filled on even steps, averaged over `half` even steps either way (edges kept).
pub(super) fn smooth_even(profile: &mut [f64], half: usize) {
    let values: Vec<f64> = profile.iter().copied().step_by(2).collect();
    for (i, v) in profile.iter_mut().step_by(2).enumerate() {
        let (lo, hi) = (i.saturating_sub(half), (i + half).min(values.len() - 1));
        *v = values[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
    }
}

/// The extent (first and last quarter-pixel step) of the edge around step `at` of a summed
/// gradient profile filled on even steps: from the step nearest `at` at half the edge's height
/// or more (its height: the largest value within `near` px of `at`), walking out on either side
/// while the profile stays there. `None` when there is no gradient there.
pub(super) fn ramp_extent(profile: &[f64], at: i64, near: i64) -> Option<(i64, i64)> {
    let n = profile.len() as i64;
    let at = at.clamp(0, n - 1) & !1;
    let peak = (at - 4 * near..=at + 4 * near)
        .step_by(2)
        .filter(|k| (0..n).contains(k))
        .map(|k| profile[k as usize])
        .fold(0.0, f64::max);
    if peak <= 0.0 {
        return None;
    }
    let above = |k: i64| (0..n).contains(&k) && profile[k as usize] >= 0.5 * peak;
    let start = (0..=4 * near).step_by(2).flat_map(|d| [at - d, at + d]).find(|&k| above(k))?;
    let (mut lo, mut hi) = (start, start);
    while above(lo - 2) {
        lo -= 2;
    }
    while above(hi + 2) {
        hi += 2;
    }
    Some((lo, hi))
}

/// The edges in a gradient profile (non-negative, one per quarter pixel), as (first step, last
/// step, peak's step, peak's value). Edges are told apart by the dip between them: the gradient
/// falls from a peak and rises again, each by more than a tenth of the profile's largest value
/// (smaller wiggles split nothing). An all-zero profile is one edge.
fn lobes(g: &[f64]) -> Vec<(usize, usize, usize, f64)> {
    let n = g.len();
    let top = g.iter().copied().fold(0.0, f64::max);
    if n == 0 || top <= 0.0 {
        return vec![(0, n.saturating_sub(1), 0, 0.0)];
    }
    let delta = 0.1 * top;
    // Peak and valley detection with hysteresis `delta`: a valley counts once the profile has
    // fallen by `delta` from the peak before it and risen by `delta` after it.
    let mut found = Vec::new();
    let (mut peak, mut peak_at, mut valley, mut valley_at, mut lo) = (g[0], 0, g[0], 0, 0);
    let mut falling = false;
    for (i, &v) in g.iter().enumerate() {
        if falling {
            if v < valley {
                (valley, valley_at) = (v, i);
            } else if v > valley + delta {
                // A new edge rises: the previous one ends at the valley.
                found.push((lo, valley_at, peak_at, peak));
                lo = valley_at;
                (peak, peak_at, falling) = (v, i, false);
            }
        } else if v > peak {
            (peak, peak_at) = (v, i);
        } else if v < peak - delta {
            (valley, valley_at, falling) = (v, i, true);
        }
    }
    found.push((lo, n - 1, peak_at, peak));
    found
}

/// The steps `lo..=hi` of a gradient profile that make up the one edge (of `lobes`) whose peak
/// is nearest step `centre`, the higher of two as near. A lone edge keeps the whole profile.
pub(super) fn one_edge(g: &[f64], centre: usize) -> (usize, usize) {
    let edges = lobes(g);
    let mut chosen = edges[0];
    for &e in &edges[1..] {
        let (d, best) = (e.2.abs_diff(centre), chosen.2.abs_diff(centre));
        if d < best || (d == best && e.3 > chosen.3) {
            chosen = e;
        }
    }
    (chosen.0, chosen.1)
}
