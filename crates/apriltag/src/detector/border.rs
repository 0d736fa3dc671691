//! The black border's four sides fitted by a model of the decoded tag under the lens's blur,
//! and that blur measured.
//!
//! The gradient-centroid fit ([`super::edges`]) finds an isolated edge exactly in linear light,
//! whatever its blur. A tag's border is not isolated: one cell inside it the data cells begin
//! (white where their bit is 1), one cell outside it the white quiet zone ends. When the blur
//! reaches a sixth of a cell or so (a small tag: 1× at 20 cm has cells of 7 px; a tag seen at a
//! grazing angle; a lens focused elsewhere), the neighbours' ramps overlap the border's and
//! pull the centroid off, by tenths of a pixel to whole pixels. Once decoded, the tag's pattern
//! is known, so each side is fitted here by the profile that pattern makes under a Gaussian
//! blur: across the side, at the centre of each of its six inner cells (away from the
//! corners, where the other sides' edges come in), the image along the side's normal is
//! `L + Σ_b Δ_b Φ((t − e − t_b)/s)`, one term per cell boundary b the normal crosses — the
//! quiet zone's outer edge (its distance free, from one cell out: a printed margin may be
//! wider), the border itself, and each boundary between data cells whose colours differ —
//! with the levels (paper, ink, beyond the quiet zone), the blur σ `s` and the side's line
//! (offset and slope) fitted together by Levenberg–Marquardt over all six profiles.
//!
//! The blur found is the edge's: the lens's defocus, motion across the side, and the pixel's own
//! spread (its area and the interpolation between pixels, [`PIXEL_SIGMA_PX`], taken out). A
//! side along the motion is not smeared, so a tag's blur is the second-sharpest of its sides:
//! what the lens did, which is what [`crate::Detection::blur_px`] reports.

use crate::gauss::{LIMIT, cdf_pdf};
use crate::image::ImageView;
use jawtrack_tag_family::TagBitmap;
use nalgebra::{SMatrix, SVector};

/// The spread (σ, px) an ideal, perfectly sharp edge shows in this fit: the pixel's area
/// (a box of 1 px, σ² = 1/12) and the bilinear interpolation between pixel centres the
/// profiles are read with. Measured on a clean render of a large tag with a pinhole lens
/// (`tests::a_sharp_edge_reads_as_no_blur`).
pub const PIXEL_SIGMA_PX: f64 = 0.5;

/// Parameters of one side's fit: the line's offset and slope along the normal (px), the blur
/// σ (px), the paper's and the ink's level, the level beyond the quiet zone, and how many cells
/// wide the quiet zone is.
const NP: usize = 7;
type Params = SVector<f64, NP>;

/// Profiles are read every this many pixels along the normal (every third of the blur's σ
/// when that is longer) …
const STEP_PX: f64 = 0.5;
/// … at eight places along the side, from a cell in from either end (the corners' other side
/// comes in nearer), to fit the side's line …
const ALONG: [f64; 8] = [1.25, 2.0, 2.75, 3.5, 4.5, 5.25, 6.0, 6.75];
/// … or at six of those places, to measure the side's blur alone. Both are for an 8-cell
/// square; other widths place them alike between one cell in from either end ([`along`]).
pub(super) const ALONG_BLUR: [f64; 6] = [1.75, 2.75, 3.75, 4.25, 5.25, 6.25];
/// A window reaches this many σ (plus [`REACH_PX`]) either side of the side's edge.
const REACH_SIGMAS: f64 = 4.0;
const REACH_PX: f64 = 2.0;
/// Levenberg–Marquardt iterations at most per window.
const ITERATIONS: usize = 10;

/// Cells across the widest black-border square the model holds (tag36h11's).
pub(super) const MAX_CELLS: usize = 8;
/// Bands across the side, going inward: beyond the quiet zone, the quiet zone, then the black
/// border square's rows (a narrower square leaves bands of no width before its last row).
pub(super) const BANDS: usize = MAX_CELLS + 2;
/// Columns along the side: the quiet zone before the first, the square's cells, the quiet
/// zone after (a narrower square leaves columns of no width before the quiet zone).
pub(super) const COLUMNS: usize = MAX_CELLS + 2;

/// What a cell prints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Print {
    Beyond,
    Paper,
    Ink,
}

/// One profile across a side: where it runs, and the tag's pattern around it. The image along
/// the normal is modelled as the pattern blurred by a Gaussian, separably: each cell weighs by
/// the Gaussian's mass between its boundaries across the side (`bands`) times that between its
/// boundaries along it (`columns`), exact for a square grid seen straight and close to it for
/// the few cells around the profile under perspective.
pub(super) struct Profile {
    /// The point on the side's current line (px, C's convention), the unit normal inward and
    /// the unit tangent the columns run along.
    origin: [f64; 2],
    normal: [f64; 2],
    pub(super) tangent: [f64; 2],
    /// Where along the side it sits, from −1 (a cell in from the first corner) to 1, for the slope.
    along: f64,
    /// Distance (px) along the normal from `origin` to each band boundary: the quiet zone's outer
    /// edge (one cell out, scaled by the fitted quiet-zone width), the border, and the rows
    /// inside it.
    pub(super) across: [f64; BANDS - 1],
    /// Distance (px) along the side from `origin` to each column boundary.
    pub(super) columns: [f64; COLUMNS - 1],
    /// What each (band, column) prints.
    pub(super) print: [[Print; COLUMNS]; BANDS],
}

/// What the fit found for one side.
#[derive(Debug, Clone, Copy)]
pub(super) struct SideFit {
    /// Two points (px) on the fitted side.
    pub line: [[f64; 2]; 2],
    /// The edge's blur σ (px), the pixel's own spread included.
    pub sigma_px: f64,
    /// The cell's width (px) across the side, at its narrowest.
    pub cell_px: f64,
    /// How far the model misses the image: the RMS residual over the paper–ink contrast.
    pub misfit: f64,
    /// The fitted parameters, a start for fitting the side again at other places.
    params: Params,
}

/// The fit of a tag's border: its four sides (top, right, bottom, left of the upright tag, C's
/// pixel convention) when it was blurred enough to fit them, and its blur.
#[derive(Debug, Clone, Copy)]
pub(super) struct BorderFit {
    pub sides: Option<[SideFit; 4]>,
    /// The lens's blur σ (px), the pixel's own spread taken out: the second-sharpest side's, or
    /// of the two sides measured the sharper.
    pub blur_px: f64,
}

fn project(h: &[f64; 9], x: f64, y: f64) -> [f64; 2] {
    let z = h[6] * x + h[7] * y + h[8];
    [(h[0] * x + h[1] * y + h[2]) / z, (h[3] * x + h[4] * y + h[5]) / z]
}

/// Tag coordinates ([−1, 1]², y down) of the point `u` cells along side `side` (0 top, 1 right,
/// 2 bottom, 3 left, running clockwise in the upright tag) and `v` cells inward from it, in a
/// square `n` cells across.
fn side_point(n: usize, side: usize, u: f64, v: f64) -> (f64, f64) {
    let half = n as f64 / 2.0;
    let (a, b) = (u / half, v / half);
    match side {
        0 => (-1.0 + a, -1.0 + b),
        1 => (1.0 - b, -1.0 + a),
        2 => (1.0 - a, 1.0 - b),
        _ => (-1.0 + b, 1.0 - a),
    }
}

/// What the cell `c` cells along side `side` and `j` cells inward prints (both may be −1, the
/// quiet zone; a band further out is beyond it).
fn print(bitmap: &TagBitmap, side: usize, c: i32, j: i32) -> Print {
    let n = bitmap.width();
    if j < -1 {
        return Print::Beyond;
    }
    if !(0..n as i32).contains(&j) || !(0..n as i32).contains(&c) {
        return Print::Paper;
    }
    let (tx, ty) = side_point(n, side, f64::from(c) + 0.5, f64::from(j) + 0.5);
    let half = n as f64 / 2.0;
    let x = (((tx + 1.0) * half).floor() as usize).min(n - 1);
    let y = (((ty + 1.0) * half).floor() as usize).min(n - 1);
    if bitmap.is_white(x, y) { Print::Paper } else { Print::Ink }
}

/// The places along a side of an `n`-cell square that `places` name on an 8-cell one, mapped
/// so that one cell in from either end stays one cell in.
pub(super) fn along(n: usize, places: &[f64]) -> Vec<f64> {
    let scale = (n as f64 - 2.0) / (MAX_CELLS as f64 - 2.0);
    places.iter().map(|&u| 1.0 + (u - 1.0) * scale).collect()
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// The profiles of side `side` of the tag `h` maps, across it at each of `along` (cells).
pub(super) fn profiles(h: &[f64; 9], bitmap: &TagBitmap, side: usize, along: &[f64]) -> Option<Vec<Profile>> {
    let n = bitmap.width();
    if !(4..=MAX_CELLS).contains(&n) {
        return None;
    }
    let at = |u: f64, v: f64| {
        let (x, y) = side_point(n, side, u, v);
        project(h, x, y)
    };
    let mut print_of = [[Print::Paper; COLUMNS]; BANDS];
    for (b, row) in print_of.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            // The last band is everything inward of the last boundary: the square's last row.
            let j = (b as i32 - 2).min(n as i32 - 1);
            *cell = print(bitmap, side, c as i32 - 1, j);
        }
    }
    let half = n as f64 / 2.0;
    let mut out = Vec::with_capacity(along.len());
    for &u in along {
        let origin = at(u, 0.0);
        let (a, b) = (at(u - 0.25, 0.0), at(u + 0.25, 0.0));
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = d[0].hypot(d[1]);
        if !(len.is_finite() && len > 1e-9) {
            return None;
        }
        let tangent = [d[0] / len, d[1] / len];
        let mut normal = [-tangent[1], tangent[0]];
        let inward = at(u, 0.5);
        if normal[0] * (inward[0] - origin[0]) + normal[1] * (inward[1] - origin[1]) < 0.0 {
            normal = [-normal[0], -normal[1]];
        }
        let mut across = [0.0; BANDS - 1];
        for (k, t) in across.iter_mut().enumerate() {
            // Where the normal meets the image of the line v = k − 1 (the last row's inner
            // boundary repeated past a narrower square's).
            let v = k.min(n) as f64 - 1.0;
            let (p, q) = (at(0.0, v), at(n as f64, v));
            let dir = [q[0] - p[0], q[1] - p[1]];
            let denom = cross(normal, dir);
            if denom.abs() < 1e-12 {
                return None;
            }
            *t = cross([p[0] - origin[0], p[1] - origin[1]], dir) / denom;
        }
        // Column boundaries along the side, half a cell in (where the profile's data cells are).
        let mut columns = [0.0; COLUMNS - 1];
        for (k, t) in columns.iter_mut().enumerate() {
            let p = at(k.min(n) as f64, 0.5);
            let here = at(u, 0.5);
            *t = (p[0] - here[0]) * tangent[0] + (p[1] - here[1]) * tangent[1];
        }
        let rising = |t: &[f64]| t[..=n].windows(2).all(|w| w[1] > w[0]);
        if !rising(&across) || !rising(&columns) {
            return None;
        }
        out.push(Profile {
            origin,
            normal,
            tangent,
            along: (u - half) / (half - 1.25),
            across,
            columns,
            print: print_of,
        });
    }
    Some(out)
}

/// A profile's columns under the current blur: each band's value (the columns' prints weighed
/// by the Gaussian's mass over each column), and its derivatives in paper, ink, beyond and σ.
struct Rows {
    /// 1/σ (multiplied by rather than divided by: a division's latency was a third of the
    /// model's time).
    inv_s: f64,
    value: [f64; BANDS],
    d_levels: [[f64; 3]; BANDS],
    d_sigma: [f64; BANDS],
}

fn rows(p: &Profile, q: &Params) -> Rows {
    let inv_s = 1.0 / q[2];
    // Mass of the Gaussian (centred on the profile) below each column boundary.
    let mut below = [0.0; COLUMNS + 1];
    let mut d_below = [0.0; COLUMNS + 1];
    below[COLUMNS] = 1.0;
    for (k, &t) in p.columns.iter().enumerate() {
        let z = t * inv_s;
        let (cdf, pdf) = cdf_pdf(z);
        below[k + 1] = cdf;
        d_below[k + 1] = -pdf * z * inv_s;
    }
    let mut r = Rows { inv_s, value: [0.0; BANDS], d_levels: [[0.0; 3]; BANDS], d_sigma: [0.0; BANDS] };
    let levels = [q[3], q[4], q[5]];
    for b in 0..BANDS {
        for c in 0..COLUMNS {
            let (w, dw) = (below[c + 1] - below[c], d_below[c + 1] - d_below[c]);
            let which = match p.print[b][c] {
                Print::Paper => 0,
                Print::Ink => 1,
                Print::Beyond => 2,
            };
            r.value[b] += levels[which] * w;
            r.d_levels[b][which] += w;
            r.d_sigma[b] += levels[which] * dw;
        }
    }
    r
}

/// The model's value and its gradient for a point `t` px along `p`'s normal, `rows` being the
/// profile's columns under `q`.
fn model(p: &Profile, rows: &Rows, t: f64, q: &Params) -> (f64, Params) {
    let [e0, e1, margin] = [q[0], q[1], q[6]];
    let inv_s = rows.inv_s;
    let e = e0 + e1 * p.along;
    // Each band weighs by the Gaussian's mass across the side between its boundaries: the mass
    // inward of its outer boundary (Φ(z) of that boundary, 1 for the outermost band) less that
    // inward of its inner one (0 for the innermost), with their derivatives in the offset, σ
    // and the quiet zone's width. The boundaries run inward, so z falls as k grows: those where
    // z ≥ LIMIT lie wholly inward of the blur (Φ = 1, φ = 0) and, from the first where
    // z ≤ −LIMIT, wholly outward (Φ = 0, φ = 0). So only the bands from the one just outward
    // of the first boundary the blur reaches to the one just inward of the last weigh (or,
    // when it reaches none, the band holding t, wholly).
    let (mut value, mut g0, mut g2, mut g3, mut g4, mut g5, mut g6) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let mut add = |b: usize, w: f64, we: f64, ws: f64, wm: f64| {
        value += rows.value[b] * w;
        g0 += rows.value[b] * we;
        g2 += rows.value[b] * ws + rows.d_sigma[b] * w;
        g3 += rows.d_levels[b][0] * w;
        g4 += rows.d_levels[b][1] * w;
        g5 += rows.d_levels[b][2] * w;
        g6 += rows.value[b] * wm;
    };
    // The mass inward of the current band's outer boundary and its derivatives.
    let (mut above, mut d_e, mut d_s, mut d_m) = (1.0, 0.0, 0.0, 0.0);
    // The innermost band the blur reaches (its inner boundary's mass is 0).
    let mut band = BANDS - 1;
    for k in 0..BANDS - 1 {
        let pos = if k == 0 { e + margin * p.across[0] } else { e + p.across[k] };
        let z = (t - pos) * inv_s;
        if z >= LIMIT {
            continue;
        }
        if z <= -LIMIT {
            band = k;
            break;
        }
        // The share of the blur (centred at t) lying inward of the boundary: Φ(z).
        let (phi, dens) = cdf_pdf(z);
        let (inner_e, inner_s) = (-dens * inv_s, -dens * z * inv_s);
        let inner_m = if k == 0 { -dens * p.across[0] * inv_s } else { 0.0 };
        add(k, above - phi, d_e - inner_e, d_s - inner_s, d_m - inner_m);
        (above, d_e, d_s, d_m) = (phi, inner_e, inner_s, inner_m);
    }
    add(band, above, d_e, d_s, d_m);
    (value, Params::from([g0, g0 * p.along, g2, g3, g4, g5, g6]))
}

/// The four pixels around `p` (C's convention: pixel centres at +0.5) and their bilinear
/// weights; `None` outside the image.
fn taps(im: &ImageView<'_>, p: [f64; 2]) -> Option<Taps> {
    let (x, y) = (p[0] - 0.5, p[1] - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    if x0 < 0.0 || y0 < 0.0 || x0 + 1.0 >= im.width() as f64 || y0 + 1.0 >= im.height() as f64 {
        return None;
    }
    let (fx, fy) = (x - x0, y - y0);
    let (xi, yi) = (x0 as usize, y0 as usize);
    let (top, bottom) = (im.row(yi), im.row(yi + 1));
    Some([
        (top[xi], (1.0 - fx) * (1.0 - fy)),
        (top[xi + 1], fx * (1.0 - fy)),
        (bottom[xi], (1.0 - fx) * fy),
        (bottom[xi + 1], fx * fy),
    ])
}

/// Four pixel values and their weights.
type Taps = [(u8, f64); 4];

/// The linear-light value the taps interpolate, read through `lut`.
fn through(lut: &[f64; 256], taps: &Taps) -> f64 {
    taps.iter().map(|&(v, w)| w * lut[usize::from(v)]).sum()
}

/// Reads each profile's samples (profile, t, value) over its window: from just inside the quiet
/// zone's outer edge to two cells in, at most `reach` px from the side's current edge (offset
/// and slope in `q`) either way; `None` when a window leaves the image.
fn read(
    im: &ImageView<'_>,
    lut: &[f64; 256],
    profiles: &[Profile],
    q: &Params,
    reach: f64,
) -> Option<Vec<(usize, f64, f64)>> {
    Some(read_taps(im, profiles, q, reach)?.iter().map(|(pi, t, taps)| (*pi, *t, through(lut, taps))).collect())
}

/// As [`read`], each sample's pixels and weights rather than its value.
fn read_taps(im: &ImageView<'_>, profiles: &[Profile], q: &Params, reach: f64) -> Option<Vec<(usize, f64, Taps)>> {
    let mut data = Vec::new();
    for (pi, p) in profiles.iter().enumerate() {
        let e = q[0] + q[1] * p.along;
        let lo = (0.8 * p.across[0]).max(-reach) + e;
        let hi = p.across[3].min(reach) + e;
        let step = STEP_PX.max(q[2] / 3.0);
        let n = ((hi - lo) / step).floor() as usize;
        for k in 0..=n {
            let t = lo + k as f64 * step;
            let at = [p.origin[0] + t * p.normal[0], p.origin[1] + t * p.normal[1]];
            data.push((pi, t, taps(im, at)?));
        }
    }
    Some(data)
}

/// A first guess of the blur (px) from the steepest rise of each profile: a Gaussian edge of
/// height H rises at most H / (σ·√(2π)) per pixel. The median over the profiles.
fn blur_guess(data: &[(usize, f64, f64)], contrast: f64) -> Option<f64> {
    let mut steepest: Vec<f64> = Vec::new();
    for run in data.chunk_by(|a, b| a.0 == b.0) {
        // Over 1 px (two steps), against noise.
        let slope = run.windows(3).map(|w| (w[2].2 - w[0].2).abs() / (w[2].1 - w[0].1)).fold(0.0, f64::max);
        if slope > 0.0 {
            steepest.push(contrast / (slope * (2.0 * std::f64::consts::PI).sqrt()));
        }
    }
    steepest.sort_by(f64::total_cmp);
    steepest.get(steepest.len() / 2).copied()
}

/// Fits one side; `None` when its profiles leave the image, the fit does not converge, or what
/// it finds cannot be a border (no contrast, a blur wider than the cells). The windows are sized
/// by a first guess of the blur, and sized again when the fit finds it a third different.
/// From `start`, the same side's fit at other places, the fit starts there instead of from a
/// first look and a guess: it ends where it would (within its tolerance), sooner.
pub(super) fn fit_side(
    im: &ImageView<'_>,
    lut: &[f64; 256],
    profiles: &[Profile],
    start: Option<&SideFit>,
) -> Option<SideFit> {
    let (q, data, cell) = fit_side_params(im, lut, profiles, start.map(|s| s.params))?;
    let point = |along: f64| {
        // The profile nearest `along` carries its normal; the line runs through the fitted
        // points of the first and last profiles.
        let p = if along < 0.0 { &profiles[0] } else { &profiles[profiles.len() - 1] };
        let e = q[0] + q[1] * p.along;
        [p.origin[0] + e * p.normal[0], p.origin[1] + e * p.normal[1]]
    };
    let misfit = misfit_of(profiles, &data, &q);
    Some(SideFit { line: [point(-1.0), point(1.0)], sigma_px: q[2], cell_px: cell, misfit, params: q })
}

/// Samples along profiles: (profile, distance along its normal (px), value).
type Samples = Vec<(usize, f64, f64)>;

/// The fit behind [`fit_side`]: the parameters, the samples they were fitted to, the cell (px).
fn fit_side_params(
    im: &ImageView<'_>,
    lut: &[f64; 256],
    profiles: &[Profile],
    start: Option<Params>,
) -> Option<(Params, Samples, f64)> {
    let cell = profiles.iter().map(|p| p.across[2] - p.across[1]).fold(f64::INFINITY, f64::min);
    if !(cell.is_finite() && cell > 1.0) {
        return None;
    }
    let mut q = match start {
        Some(q) => q,
        None => {
            let mut q = Params::from([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.2]);
            // A first look, half a cell either way (at most 10 px): the levels and a guess of the blur.
            let first = read(im, lut, profiles, &q, (0.5 * cell).clamp(3.0, 10.0))?;
            let (ink, paper) = levels(&first)?;
            (q[3], q[4], q[5]) = (paper, ink, paper);
            q[2] = blur_guess(&first, paper - ink)?.clamp(0.3, cell);
            q
        }
    };
    let mut data = Vec::new();
    for round in 0..2 {
        let guess = q[2];
        data = read(im, lut, profiles, &q, REACH_SIGMAS * guess + REACH_PX)?;
        q = levenberg_marquardt(profiles, &data, q, cell)?;
        if round == 0 && (q[2] - guess).abs() < guess / 3.0 {
            break;
        }
    }
    (q[3] - q[4] > 1.0 && q.iter().all(|v| v.is_finite())).then_some((q, data, cell))
}

/// Ink and paper: the darkest and the brightest eighth of the samples; `None` without
/// contrast.
fn levels(data: &[(usize, f64, f64)]) -> Option<(f64, f64)> {
    let mut v: Vec<f64> = data.iter().map(|d| d.2).collect();
    v.sort_by(f64::total_cmp);
    let (ink, paper) = (v[v.len() / 8], v[v.len() - 1 - v.len() / 8]);
    (paper - ink >= 1.0).then_some((ink, paper))
}

/// How far the model `q` misses `data`: the RMS residual over the paper–ink contrast.
fn misfit_of(profiles: &[Profile], data: &[(usize, f64, f64)], q: &Params) -> f64 {
    let rs: Vec<Rows> = profiles.iter().map(|p| rows(p, q)).collect();
    let sum: f64 = data.iter().map(|&(pi, t, v)| (model(&profiles[pi], &rs[pi], t, q).0 - v).powi(2)).sum();
    (sum / data.len() as f64).sqrt() / (q[3] - q[4])
}

/// A side fitted once and its pixels kept, each at its centre's distance from the fitted edge:
/// what the tone fit ([`super::tone_fit`]) reads the curve from. Pixels as they are, not
/// interpolated: interpolating between pixels read through a curve bends a ramp by the curve's
/// own curvature, and the exponent that best straightens it back is 20–30 % low at blurs under
/// 1.5 px.
pub(super) struct FixedSide {
    pub(super) profiles: Vec<Profile>,
    /// The fit: line, blur, levels, and (`start[6]`) the quiet zone's width in cells.
    pub(super) start: Params,
    /// (profile, distance along its normal (px), along its tangent (px), pixel value).
    pixels: Vec<(usize, f64, f64, u8)>,
    /// The fit's blur σ (px, the pixel's own spread included) and misfit (RMS residual over
    /// the paper–ink contrast).
    pub sigma_px: f64,
    pub misfit: f64,
    /// The cell's width (px) across the side, at its narrowest.
    pub cell_px: f64,
}

/// Pixels kept per side at most (taken evenly along it): enough to sample every phase of the
/// edge, few enough that a large tag costs no more than a small one.
const MAX_SIDE_PIXELS: usize = 800;
/// A side tells a curve only when its pixels' centres fall at this many of eight phases across
/// the edge (a side along the pixel grid samples its ramp at one phase, which any curve fits).
const MIN_PHASES: usize = 6;

impl FixedSide {
    /// Fits the side through `lut` ([`fit_side`]) and keeps the pixels of its windows: the
    /// strip each profile stands for along the side (to halfway to its neighbours, half a cell
    /// at the ends). `None` when the fit fails, a window leaves the image, or the pixels sample
    /// the edge at too few phases ([`MIN_PHASES`]).
    pub(super) fn new(im: &ImageView<'_>, lut: &[f64; 256], profiles: Vec<Profile>) -> Option<Self> {
        let (q, data, cell) = fit_side_params(im, lut, &profiles, None)?;
        let misfit = misfit_of(&profiles, &data, &q);
        let reach = REACH_SIGMAS * q[2] + REACH_PX;
        let n = profiles.len();
        let gap = |a: &Profile, b: &Profile| (b.origin[0] - a.origin[0]).hypot(b.origin[1] - a.origin[1]);
        // Pixels per unit of a profile's `along`; and how far along the side (px) each strip
        // reaches back and forth from its profile.
        let px_per_along = gap(&profiles[0], &profiles[n - 1]) / (profiles[n - 1].along - profiles[0].along);
        let cell_along = px_per_along * (profiles[1].along - profiles[0].along);
        let reaches: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let back = if k == 0 { cell_along * 0.5 } else { gap(&profiles[k - 1], &profiles[k]) / 2.0 };
                let forth = if k == n - 1 { cell_along * 0.5 } else { gap(&profiles[k], &profiles[k + 1]) / 2.0 };
                (back, forth)
            })
            .collect();
        let mut pixels = Vec::new();
        for (pi, p) in profiles.iter().enumerate() {
            let e = q[0] + q[1] * p.along;
            let (lo, hi) = ((0.8 * p.across[0]).max(-reach) + e, p.across[3].min(reach) + e);
            let tangent = [-p.normal[1], p.normal[0]];
            let (back, forth) = reaches[pi];
            let corners = [(lo, -back), (lo, forth), (hi, -back), (hi, forth)].map(|(t, u)| {
                [p.origin[0] + t * p.normal[0] + u * tangent[0], p.origin[1] + t * p.normal[1] + u * tangent[1]]
            });
            let span = |k: usize| {
                let (a, b) =
                    corners.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| (a.min(c[k]), b.max(c[k])));
                ((a - 1.0).floor().max(0.0) as usize, (b + 1.0).ceil().max(0.0) as usize)
            };
            let ((x0, x1), (y0, y1)) = (span(0), span(1));
            if x1 >= im.width() || y1 >= im.height() {
                return None;
            }
            for y in y0..=y1 {
                for x in x0..=x1 {
                    // C's convention: the pixel's centre is at +0.5.
                    let d = [x as f64 + 0.5 - p.origin[0], y as f64 + 0.5 - p.origin[1]];
                    let (t, u) = (d[0] * p.normal[0] + d[1] * p.normal[1], d[0] * tangent[0] + d[1] * tangent[1]);
                    if (-back..forth).contains(&u) && (lo..=hi).contains(&t) {
                        // The side's tilt (its fitted slope) carried from the profile to the pixel.
                        let along = d[0] * p.tangent[0] + d[1] * p.tangent[1];
                        pixels.push((pi, t - q[1] * u / px_per_along, along, im.row(y)[x]));
                    }
                }
            }
        }
        if pixels.len() > MAX_SIDE_PIXELS {
            let stride = pixels.len().div_ceil(MAX_SIDE_PIXELS);
            pixels = pixels.into_iter().step_by(stride).collect();
        }
        let mut phases = [false; 8];
        for &(pi, t, _, _) in &pixels {
            let from_edge = t - (q[0] + q[1] * profiles[pi].along);
            if from_edge.abs() < 2.0 * q[2] {
                phases[(from_edge.rem_euclid(1.0) * 8.0) as usize % 8] = true;
            }
        }
        if phases.iter().filter(|&&b| b).count() < MIN_PHASES {
            return None;
        }
        Some(FixedSide { profiles, start: q, pixels, sigma_px: q[2], misfit, cell_px: cell })
    }

    /// The kept pixels as (the profile whose strip they are in; distance from the fitted edge
    /// along the normal, px, positive inward; along the profile's tangent from it, px, as its
    /// `columns` are; pixel value).
    pub(super) fn edge_pixels(&self) -> Vec<(usize, f64, f64, u8)> {
        let q = self.start;
        self.pixels.iter().map(|&(pi, t, u, v)| (pi, t - (q[0] + q[1] * self.profiles[pi].along), u, v)).collect()
    }
}

/// The model at `q` against every sample of `data`: the sum of squared residuals, and each
/// sample's residual and gradient, kept so that an accepted step's normal equations are built
/// from the evaluation that judged it rather than a second one.
fn evaluate(profiles: &[Profile], data: &[(usize, f64, f64)], q: &Params, out: &mut Vec<(f64, Params)>) -> f64 {
    let rs: Vec<Rows> = profiles.iter().map(|p| rows(p, q)).collect();
    out.clear();
    out.extend(data.iter().map(|&(pi, t, v)| {
        let (m, g) = model(&profiles[pi], &rs[pi], t, q);
        (m - v, g)
    }));
    out.iter().map(|(r, _)| r * r).sum()
}

/// Levenberg–Marquardt on the squared residuals of `data` (profile, t, value); the blur is kept
/// within [0.2 px, a cell], the quiet zone from 1 to 3 cells wide.
fn levenberg_marquardt(profiles: &[Profile], data: &[(usize, f64, f64)], start: Params, cell: f64) -> Option<Params> {
    let clamp = |mut q: Params| {
        q[2] = q[2].clamp(0.2, cell);
        q[5] = q[5].clamp(0.0, 1.5 * q[3].max(0.0));
        q[6] = q[6].clamp(1.0, 3.0);
        q
    };
    let mut q = start;
    let (mut here, mut trial) = (Vec::with_capacity(data.len()), Vec::with_capacity(data.len()));
    let mut current = evaluate(profiles, data, &q, &mut here);
    let mut lambda = 1e-3;
    for _ in 0..ITERATIONS {
        let mut jtj = SMatrix::<f64, NP, NP>::zeros();
        let mut jtr = Params::zeros();
        for (r, g) in &here {
            // The lower triangle only (the normal matrix is symmetric), mirrored below.
            for j in 0..NP {
                for i in j..NP {
                    jtj[(i, j)] += g[i] * g[j];
                }
            }
            jtr += g * *r;
        }
        for j in 0..NP {
            for i in j + 1..NP {
                jtj[(j, i)] = jtj[(i, j)];
            }
        }
        let mut improved = false;
        for _ in 0..8 {
            let mut a = jtj;
            for i in 0..NP {
                a[(i, i)] += lambda * (jtj[(i, i)] + 1e-9);
            }
            let Some(step) = a.cholesky().map(|c| c.solve(&jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let next = clamp(q - step);
            let c = evaluate(profiles, data, &next, &mut trial);
            if c.is_finite() && c < current {
                // Settled: the line moved under 0.001 px, the blur under 0.1 %, and the misfit
                // fell by under a millionth.
                let moved = (next[0] - q[0]).abs() + (next[1] - q[1]).abs();
                let settled = moved < 1e-3 && (next[2] - q[2]).abs() < 1e-3 * q[2] || current - c < 1e-6 * current;
                q = next;
                current = c;
                std::mem::swap(&mut here, &mut trial);
                lambda = (lambda / 3.0).max(1e-9);
                improved = true;
                if settled {
                    return Some(q);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    q.iter().all(|v| v.is_finite()).then_some(q)
}

/// Where two lines, each through two points, cross; `None` for (near) parallel ones.
pub(super) fn intersect(a: &[[f64; 2]; 2], b: &[[f64; 2]; 2]) -> Option<[f64; 2]> {
    let (da, db) = ([a[1][0] - a[0][0], a[1][1] - a[0][1]], [b[1][0] - b[0][0], b[1][1] - b[0][1]]);
    let denom = cross(da, db);
    if denom.abs() < 1e-9 * da[0].hypot(da[1]) * db[0].hypot(db[1]) {
        return None;
    }
    let t = cross([b[0][0] - a[0][0], b[0][1] - a[0][1]], db) / denom;
    Some([a[0][0] + t * da[0], a[0][1] + t * da[1]])
}

/// A side whose blur is under this fraction of its cell is sharp enough that the gradient
/// fit's line stands ([`super::MODEL_SIDE_BLUR_PER_CELL`] is where the model's takes over):
/// when the two sides measured first are both under it, the other two are not fitted.
const SHARP_BLUR_PER_CELL: f64 = 0.12;

/// The border of the tag `bitmap` prints, decoded with homography `h` (tag coordinates to pixels in C's
/// convention, upright) in `im` read through `lut`: its blur, and each side's line where the
/// blur calls for the model (`None` for a side the gradient fit keeps). The top and right sides
/// are measured first, at six places each; only when either is blurred by
/// [`SHARP_BLUR_PER_CELL`] or more, and `want_lines`, are all four fitted at eight, for their
/// lines. `None` when a
/// side cannot be fitted (the tag is cut by the frame's edge, too small, or not what it was
/// decoded as).
pub(super) fn fit_border(
    im: &ImageView<'_>,
    lut: &[f64; 256],
    bitmap: &TagBitmap,
    h: &[f64; 9],
    want_lines: bool,
) -> Option<BorderFit> {
    let (places, places_blur) = (along(bitmap.width(), &ALONG), along(bitmap.width(), &ALONG_BLUR));
    let side = |k: usize, along: &[f64], start| fit_side(im, lut, &profiles(h, bitmap, k, along)?, start);
    let sharp = |s: &SideFit| s.sigma_px < SHARP_BLUR_PER_CELL * s.cell_px;
    let (top, right) = (side(0, &places_blur, None)?, side(1, &places_blur, None)?);
    let lens = |sigma: f64| (sigma * sigma - PIXEL_SIGMA_PX * PIXEL_SIGMA_PX).max(0.0).sqrt();
    if !want_lines || (sharp(&top) && sharp(&right)) {
        // Motion smears at most one of two perpendicular sides: the sharper is the lens's.
        return Some(BorderFit { sides: None, blur_px: lens(top.sigma_px.min(right.sigma_px)) });
    }
    let sides = [
        side(0, &places, Some(&top))?,
        side(1, &places, Some(&right))?,
        side(2, &places, None)?,
        side(3, &places, None)?,
    ];
    let mut sigmas = sides.map(|s| s.sigma_px);
    sigmas.sort_by(f64::total_cmp);
    Some(BorderFit { sides: Some(sides), blur_px: lens(sigmas[1]) })
}

#[cfg(test)]
#[path = "border_tests.rs"]
pub(super) mod tests;
