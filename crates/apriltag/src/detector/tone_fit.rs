//! The camera's tone curve read off one frame's tags.
//!
//! Across a straight edge between ink and paper, each pixel holds the ink's light plus the
//! paper's share it covers; blurred by any symmetric spread — a Gaussian, a disc pupil's
//! defocus, the pixel's own square seen at any angle — that share at a distance `s` past the
//! edge and the share at `s` before it add up to one. In linear light, then, every pixel and
//! its mirror image across the edge sum to ink plus paper. Read through the wrong curve they
//! do not: the ramp is lopsided, compressed on one side and stretched on the other, and no
//! placement of the edge makes it symmetric — which is also why an edge fitted through the
//! wrong curve lands off by a share of its width. The exponent whose decoding leaves the least
//! asymmetry, over every tag side of the frame, is the estimate. The pixels are taken as they
//! are, at their centres' distances from the edge, over a side long enough that they fall at
//! every phase across it (a side along the pixel grid does not, and is left out).
//!
//! A lone edge is the simple case. Under a wide blur (a phone focused beyond the tags) the data
//! cells' edges, a cell inside the border, reach into its ramp; the tag being decoded, where it
//! prints ink is known, and the image across the side is the same spread's step summed over
//! each boundary, as linear in the spread's odd parts as one edge is. Only the quiet zone's
//! outer edge, to a level that is not the paper's, and the corners where two columns print
//! differently are kept out of reach.

use super::border::{ALONG_BLUR, BANDS, FixedSide, PIXEL_SIGMA_PX, Print, Profile, along, profiles};
use super::{Detection, Detector, shifted_homography};
use crate::image::ImageView;
use crate::tone::{FrameToneFit, GAMMA_SEARCH};
use jawtrack_tag_family::TagFamily;
use jawtrack_tone::ToneCurve;
use nalgebra::{SMatrix, SVector};
use std::cell::RefCell;
use std::rc::Rc;

/// Sides taken from one frame, those with the widest cells first (the most pixels, the best
/// fitted): enough to average the noise, few enough that a frame's fit costs about five
/// detections' time.
const MAX_SIDES: usize = 16;
/// Cells narrower than this (px) hold too few pixels per strip to tell a ramp's shape from
/// its neighbours': their sides are left out.
const MIN_CELL_PX: f64 = 6.0;
/// The side's fit must explain it within this share of the contrast: a side crossed by an
/// occluder, a glare or another tag is not a border's edge.
const MAX_START_MISFIT: f64 = 0.08;
/// The edge's pixels are taken this many σ (the edge's, the pixel's spread included) either
/// side of it, plus [`RAMP_PX`] (its ramp), and the [`PLATEAU_PX`] beyond (its levels).
const RAMP_SIGMAS: f64 = 2.5;
const RAMP_PX: f64 = 0.5;
const PLATEAU_PX: f64 = 1.5;
/// … and an edge not modelled (the quiet zone's end, a corner between columns that print
/// differently) must be this many σ beyond a pixel: its ramp's tail (a thousandth of the
/// contrast at 3.1σ) would lift one side's levels and not the other's.
const CLEAR_SIGMAS: f64 = 3.5;
/// The edge is placed (for each curve) within this many px of the side's fitted line.
const SHIFT_PX: f64 = 0.6;
/// The exponent: scanned at this many steps over [`GAMMA_SEARCH`], then refined by
/// golden-section steps to 0.01.
const GAMMA_SCAN: usize = 8;
const GOLDEN_STEPS: usize = 7;
/// The edge's place is first tried every this many px, then searched in steps of
/// [`FINE_STEP_PX`] (a sharp edge's misfit changes within a tenth of a pixel), at most
/// [`MAX_FINE_MOVES`] of them per curve.
const SHIFT_STEP_PX: f64 = 0.15;
const FINE_STEP_PX: f64 = 0.04;
const MAX_FINE_MOVES: usize = 16;

impl Detector {
    /// Estimates the tone curve `frame` was encoded with from its tags `dets` (as
    /// [`Detector::detect`] returned them): the plain power law whose decoding leaves their
    /// border edges least lopsided, and how lopsided that and sRGB leave them. `None` when no
    /// tag side can tell (too small, cut by the frame, along the pixel grid, or not explained
    /// by a border's edge).
    pub fn fit_tone(&self, frame: &ImageView<'_>, dets: &[Detection]) -> Option<FrameToneFit> {
        let lut = self.tone_state().lut.clone();
        fit_tone_through(&self.config().family, frame, dets, &lut)
    }
}

/// As [`Detector::fit_tone`], the tags (of `family`) having been detected through `start`.
pub(super) fn fit_tone_through(
    family: &TagFamily,
    frame: &ImageView<'_>,
    dets: &[Detection],
    start: &[f64; 256],
) -> Option<FrameToneFit> {
    let mut sides: Vec<(f64, Edge)> = Vec::new();
    for d in dets {
        let Some(bitmap) = family.bitmap(d.id) else { continue };
        // The border model works in C's pixel convention, the detections in ours.
        let h = shifted_homography(&d.homography, 0.5, 0.5);
        let places = along(bitmap.width(), &ALONG_BLUR);
        for k in 0..4 {
            let Some(profiles) = profiles(&h, &bitmap, k, &places) else { continue };
            let Some(side) = FixedSide::new(frame, start, profiles) else { continue };
            if side.cell_px < MIN_CELL_PX || side.misfit > MAX_START_MISFIT {
                continue;
            }
            if let Some(edge) = Edge::new(&side) {
                sides.push((side.cell_px, edge));
            }
        }
    }
    if sides.is_empty() {
        return None;
    }
    sides.sort_by(|a, b| b.0.total_cmp(&a.0));
    sides.truncate(MAX_SIDES);
    let blur_px = {
        let mut s: Vec<f64> = sides.iter().map(|s| s.1.sigma_px).collect();
        s.sort_by(f64::total_cmp);
        let median = s[s.len() / 2];
        (median * median - PIXEL_SIGMA_PX * PIXEL_SIGMA_PX).max(0.0).sqrt()
    };
    let edges: Vec<Edge> = sides.into_iter().map(|s| s.1).collect();
    // Each strip's edge place, carried from curve to curve as the search moves.
    let mut places: Vec<Vec<f64>> = edges.iter().map(|e| e.places(start)).collect();
    let chi2 = |curve: ToneCurve, places: &mut Vec<Vec<f64>>| {
        let lut = curve.decode_table();
        edges
            .iter()
            .zip(places.iter_mut())
            .map(|(e, p)| e.asymmetry(&lut, p))
            .fold((0.0, 0), |(c, n), (ci, ni)| (c + ci, n + ni))
    };
    // sRGB from the places found through the curve the tags were detected with (sRGB,
    // until an estimate replaces it), before the search carries them off.
    let (srgb, _) = chi2(ToneCurve::Srgb, &mut places.clone());
    // Far from the camera's curve the lopsidedness may dip again (a crushed end weighs
    // little): the best of a scan, refined. The scan runs from sRGB's neighbourhood out
    // both ways, so the places move in small steps.
    let (lo, hi) = (*GAMMA_SEARCH.start(), *GAMMA_SEARCH.end());
    let step = (hi - lo) / GAMMA_SCAN as f64;
    let mut scanned: Vec<(f64, f64, Vec<Vec<f64>>)> = Vec::new();
    let middle = ((2.2 - lo) / step).round() as usize;
    for half in [(middle..=GAMMA_SCAN).collect::<Vec<_>>(), (0..middle).rev().collect()] {
        let mut p = places.clone();
        for i in half {
            let g = lo + step * i as f64;
            let (c, _) = chi2(ToneCurve::Gamma { gamma: g }, &mut p);
            scanned.push((g, c, p.clone()));
        }
    }
    let (best, _, best_places) =
        scanned.into_iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap_or((2.2, f64::INFINITY, places.clone()));
    places = best_places;
    let (gamma, _) = golden((best - step).max(lo), (best + step).min(hi), GOLDEN_STEPS, |g| {
        chi2(ToneCurve::Gamma { gamma: g }, &mut places).0
    });
    let (best, residuals) = chi2(ToneCurve::Gamma { gamma }, &mut places);
    (residuals > 0).then_some(FrameToneFit {
        gamma,
        chi2: best,
        srgb_chi2: srgb,
        residuals,
        sides: edges.len(),
        blur_px,
    })
}

/// The least of `f` over [lo, hi] by golden-section search (one minimum assumed), and where.
fn golden(mut lo: f64, mut hi: f64, steps: usize, mut f: impl FnMut(f64) -> f64) -> (f64, f64) {
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let mut a = hi - ratio * (hi - lo);
    let mut b = lo + ratio * (hi - lo);
    let (mut fa, mut fb) = (f(a), f(b));
    for _ in 0..steps {
        if fa <= fb {
            hi = b;
            (b, fb) = (a, fa);
            a = hi - ratio * (hi - lo);
            fa = f(a);
        } else {
            lo = a;
            (a, fa) = (b, fb);
            b = lo + ratio * (hi - lo);
            fb = f(b);
        }
    }
    if fa <= fb { (a, fa) } else { (b, fb) }
}

/// One side's pixels about its edge, strip by strip along it (each placed on its own: the
/// side's fitted line may bend or tilt by tenths of a pixel over its length, which would blur
/// a sharp edge's profile if the strips were pooled).
struct Edge {
    /// Its strips.
    strips: Vec<Strip>,
    /// The edge's blur σ (px, the pixel's spread included).
    sigma_px: f64,
    /// The variance of the plateaus' pixel values (grey levels²): the side's noise.
    noise: f64,
}

/// A strip of an edge: its pixels' distances from the side's fitted line (px), values, and
/// where, across the side from that line, the tag prints ink about each ([`InkSpans`]).
struct Strip {
    distances: Vec<f64>,
    values: Vec<u8>,
    ink: Vec<InkSpans>,
    /// The pixels' terms ([`step_terms`]) with the edge at each place tried: the search of
    /// the curves comes back to the same few places, and only the data change with the curve.
    terms: RefCell<Vec<(f64, Rc<Vec<StepVector>>)>>,
}

/// The stretches (px from the side's line, inward; open ends infinite) the tag prints ink
/// along a pixel's row across the side: the border, and the data cells next to it where they
/// are ink. Each boundary is a blurred step of its own, so the image across them is a sum of
/// one spread's steps: as linear in the spread's odd parts as a lone edge, and the data cells'
/// edge, a cell in, need not be clear of the border's ramp (a defocused tag, a phone too
/// close).
type InkSpans = Vec<(f64, f64)>;

impl Edge {
    /// The side's pixels within its ramp and plateaus, each with what the tag prints about it;
    /// `None` when it has too few pixels off the ramps to tell its noise (a synthetic,
    /// noiseless side is given the 8-bit rounding's). A pixel is left out when the quiet
    /// zone's outer edge (beyond which the level is not the paper's) is within the spread's
    /// reach, or when it lies that near a column whose print differs (the image there is no
    /// longer one row's).
    fn new(side: &FixedSide) -> Option<Edge> {
        let sigma = side.sigma_px;
        let ramp = RAMP_SIGMAS * sigma + RAMP_PX;
        let reach = ramp + PLATEAU_PX + SHIFT_PX;
        let clear = CLEAR_SIGMAS * sigma;
        let quiet_cells = side.start[6];
        let mut pixels: Vec<(usize, f64, u8, InkSpans)> = Vec::new();
        for (k, t, u, v) in side.edge_pixels() {
            if t.abs() > reach {
                continue;
            }
            let p = &side.profiles[k];
            if let Some(ink) = ink_spans(p, quiet_cells, t, u, clear) {
                pixels.push((k, t, v, ink));
            }
        }
        // The plateaus: pixels off every ramp by the edge's reach, ink or paper by where they lie.
        let off_ramps = ramp + SHIFT_PX;
        let plateau = |inside: bool| -> Vec<f64> {
            pixels
                .iter()
                .filter(|p| {
                    let flat =
                        p.3.iter().flat_map(|s| [s.0, s.1]).all(|x| !x.is_finite() || (p.1 - x).abs() > off_ramps);
                    flat && p.3.iter().any(|s| (s.0..s.1).contains(&p.1)) == inside
                })
                .map(|p| f64::from(p.2))
                .collect()
        };
        let variance = |v: &[f64]| {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64
        };
        // Either plateau tells the noise; a quiet zone a cell wide under a wide blur leaves the
        // paper's none, its outer edge (to a level not the paper's) too near.
        let told: Vec<f64> =
            [plateau(true), plateau(false)].iter().filter(|p| p.len() >= 8).map(|p| variance(p)).collect();
        if told.is_empty() {
            return None;
        }
        // 8-bit rounding alone: 1/12 level².
        let noise = (told.iter().sum::<f64>() / told.len() as f64).max(1.0 / 12.0);
        let strips_n = pixels.iter().map(|p| p.0 + 1).max().unwrap_or(0);
        let mut strips: Vec<Strip> = (0..strips_n)
            .map(|_| Strip { distances: Vec::new(), values: Vec::new(), ink: Vec::new(), terms: RefCell::default() })
            .collect();
        for (k, t, v, ink) in pixels {
            strips[k].distances.push(t);
            strips[k].values.push(v);
            strips[k].ink.push(ink);
        }
        // A strip needs more pixels than the blurred step has numbers.
        strips.retain(|s| s.values.len() > 3 * STEP_TERMS);
        (!strips.is_empty()).then_some(Edge { strips, sigma_px: sigma, noise })
    }

    /// How lopsided the edge is read through `lut`: the least χ² of the pixels' values (in
    /// grey levels, each linear-light residual divided by the curve's slope at its pixel, over
    /// the noise) against any blurred step ([`step_basis`]: a level plus odd parts, which take
    /// in any symmetric spread — a Gaussian, a disc, the pixel's square at any angle — but
    /// nothing lopsided), each strip's edge placed where it fits best. And how many pixels.
    ///
    /// `places` holds each strip's edge place (px from the side's line), searched from there
    /// in steps of [`FINE_STEP_PX`] and left where the misfit is least: the place moves little
    /// between nearby curves, so a search of the curves carries it along.
    fn asymmetry(&self, lut: &[f64; 256], places: &mut [f64]) -> (f64, usize) {
        let (mut chi2, mut n) = (0.0, 0);
        for (strip, place) in self.strips.iter().zip(places.iter_mut()) {
            let data = weighed(lut, &strip.values, self.noise);
            let f = |d: f64| strip.chi2(&data, d, self.sigma_px);
            let h = FINE_STEP_PX;
            let (mut d, mut at) = (*place, [f(*place - h), f(*place), f(*place + h)]);
            for _ in 0..MAX_FINE_MOVES {
                if at[0] < at[1] && at[0] <= at[2] {
                    d -= h;
                    at = [f(d - h), at[0], at[1]];
                } else if at[2] < at[1] {
                    d += h;
                    at = [at[1], at[2], f(d + h)];
                } else {
                    break;
                }
            }
            *place = d.clamp(-SHIFT_PX, SHIFT_PX);
            chi2 += least_between(&at);
            n += data.len();
        }
        (chi2, n)
    }

    /// Each strip's edge place read through `lut`: the best of the shifts ±[`SHIFT_PX`] every
    /// [`SHIFT_STEP_PX`].
    fn places(&self, lut: &[f64; 256]) -> Vec<f64> {
        self.strips
            .iter()
            .map(|strip| {
                let data = weighed(lut, &strip.values, self.noise);
                let n = (SHIFT_PX / SHIFT_STEP_PX).round() as i32;
                (-n..=n)
                    .map(|i| f64::from(i) * SHIFT_STEP_PX)
                    .map(|d| (d, strip.chi2(&data, d, self.sigma_px)))
                    .fold((0.0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
                    .0
            })
            .collect()
    }
}

impl Strip {
    /// The least weighted squared misfit of `data` (value, weight, per pixel) to a blurred step
    /// whose edge is `d` px from the side's line ([`step_basis`]), by linear least squares.
    fn chi2(&self, data: &[(f64, f64)], d: f64, sigma_px: f64) -> f64 {
        let terms = self.terms_at(d, sigma_px);
        let mut ata = StepMatrix::zeros();
        let mut atb = StepVector::zeros();
        for (&(v, w), r) in data.iter().zip(terms.iter()) {
            ata.syger(w, r, r, 1.0);
            atb.axpy(w * v, r, 1.0);
        }
        ata.fill_upper_triangle_with_lower_triangle();
        let Some(x) = (ata + StepMatrix::identity() * 1e-9 * ata.trace()).cholesky().map(|c| c.solve(&atb)) else {
            return f64::INFINITY;
        };
        data.iter().zip(terms.iter()).map(|(&(v, w), r)| w * (r.dot(&x) - v).powi(2)).sum()
    }

    /// The pixels' terms with the edge `d` px from the side's line, from the cache when that
    /// place (to a billionth of a pixel: places are reached by steps that round differently)
    /// was tried before.
    fn terms_at(&self, d: f64, sigma_px: f64) -> Rc<Vec<StepVector>> {
        if let Some((_, t)) = self.terms.borrow().iter().find(|(at, _)| (at - d).abs() < 1e-9) {
            return Rc::clone(t);
        }
        let t: Rc<Vec<StepVector>> =
            Rc::new(self.distances.iter().zip(&self.ink).map(|(&x, ink)| step_terms(x - d, ink, sigma_px)).collect());
        self.terms.borrow_mut().push((d, Rc::clone(&t)));
        t
    }
}

/// Pixel values read through `lut`, each with its weight: one over its variance in linear
/// light (the noise in grey levels, times the curve's slope there, squared).
fn weighed(lut: &[f64; 256], values: &[u8], noise: f64) -> Vec<(f64, f64)> {
    values
        .iter()
        .map(|&v| {
            let i = usize::from(v).clamp(1, 254);
            let slope = ((lut[i + 1] - lut[i - 1]) / 2.0).max(1e-9);
            (lut[usize::from(v)], 1.0 / (slope * slope * noise))
        })
        .collect()
}

/// The least of values sampled at equal steps, refined by the parabola through the least
/// sample and its neighbours (the sample itself at either end).
fn least_between(c: &[f64]) -> f64 {
    let (i, &m) = c.iter().enumerate().fold((0, &f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    if i == 0 || i + 1 >= c.len() {
        return m;
    }
    let (a, b) = (c[i - 1], c[i + 1]);
    let curvature = a + b - 2.0 * m;
    if curvature <= 0.0 { m } else { m - (b - a).powi(2) / (8.0 * curvature) }
}

/// Numbers of a blurred step: a level, and the weights of its odd parts.
const STEP_TERMS: usize = 1 + RAMP_WIDTHS.len() + ERF_WIDTHS.len();
type StepMatrix = SMatrix<f64, STEP_TERMS, STEP_TERMS>;
type StepVector = SVector<f64, STEP_TERMS>;
/// Half-widths (in units of the edge's σ) of the straight ramps a blurred step is mixed from:
/// a symmetric spread that falls away from its centre is a mix of centred boxes, and its step
/// a mix of such ramps; the pixel's square seen at an angle is one.
const RAMP_WIDTHS: [f64; 7] = [0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0];
/// … and of error functions (σ·√2 units), which the ramps alone would only approximate.
const ERF_WIDTHS: [f64; 2] = [0.7, 1.0];
/// Beyond this many σ from its edge every odd term of a step is at its end.
const SATURATED_SIGMAS: f64 = 5.0;

/// The terms of the image `x` px inward of a side's edge ([`step_basis`] summed over the
/// steps in and out of each of the pixel's `ink` spans, placed as the edge is): 1, then each
/// odd part's sum. A lone edge's span runs on inward for ever, and its terms are the step's
/// own, shifted by a constant.
fn step_terms(x: f64, ink: &[(f64, f64)], sigma_px: f64) -> StepVector {
    let mut terms = StepVector::zeros();
    for &(lo, hi) in ink {
        terms += step_basis(x - lo, sigma_px) - step_basis(x - hi, sigma_px);
    }
    terms[0] = 1.0;
    terms
}

/// The ink spans ([`InkSpans`]) about a pixel `t` px inward of the side's edge and `u` px
/// along the profile `p` whose strip it is in, the quiet zone fitted `quiet_cells` wide;
/// `None` when the quiet zone's outer edge is within `clear` px of it, or a column boundary
/// is whose two columns print differently in a band within `clear` of it.
fn ink_spans(p: &Profile, quiet_cells: f64, t: f64, u: f64, clear: f64) -> Option<InkSpans> {
    // Band b lies between boundaries b − 1 and b: 0 beyond the quiet zone, 1 the quiet zone,
    // 2 the border, then the data rows, the last running on inward.
    let bound = |k: usize| -> f64 {
        match k {
            0 => quiet_cells * p.across[0],
            k if k < BANDS - 1 => p.across[k],
            _ => f64::INFINITY,
        }
    };
    if t - bound(0) < clear {
        return None;
    }
    let column = p.columns.iter().filter(|&&c| c <= u).count();
    let near = |b: usize| bound(b - 1) < t + clear && bound(b) > t - clear;
    for (k, &c) in p.columns.iter().enumerate() {
        if (u - c).abs() < clear && (1..BANDS).any(|b| near(b) && p.print[b][k] != p.print[b][k + 1]) {
            return None;
        }
    }
    let mut spans: InkSpans = Vec::new();
    for b in 1..BANDS {
        if p.print[b][column] != Print::Ink {
            continue;
        }
        match spans.last_mut() {
            Some(last) if last.1 == bound(b - 1) => last.1 = bound(b),
            _ => spans.push((bound(b - 1), bound(b))),
        }
    }
    Some(spans)
}

/// The terms of a blurred step at distance `x` from its edge: 1, then odd functions of `x`.
fn step_basis(x: f64, sigma_px: f64) -> StepVector {
    // Past 5σ every term is ±1 (the ramps exactly, the widest error function, erf(x / σ√2),
    // within 6e-7: a ten-thousandth of a grey level): the far boundaries of a pixel's spans
    // cost nothing.
    if x.abs() > SATURATED_SIGMAS * sigma_px {
        return StepVector::from_fn(|k, _| if k == 0 { 1.0 } else { x.signum() });
    }
    StepVector::from_fn(|k, _| {
        if k == 0 {
            1.0
        } else if k <= RAMP_WIDTHS.len() {
            (x / (RAMP_WIDTHS[k - 1] * sigma_px)).clamp(-1.0, 1.0)
        } else {
            libm::erf(x / (ERF_WIDTHS[k - 1 - RAMP_WIDTHS.len()] * sigma_px * std::f64::consts::SQRT_2))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::super::border::tests::drawn_through;
    use crate::{Detector, DetectorConfig, ImageView, ToneCurve, ToneSetting};

    /// One tag with 14 px cells turned `deg`, drawn in linear light under a Gaussian blur and
    /// encoded through `curve`; its fit, by a detector reading it as sRGB.
    fn fit(curve: ToneCurve, blur: f64, deg: f64) -> Option<super::FrameToneFit> {
        let (img, n, _) = drawn_through(7, 14.0, deg, 1.0, 0.3, blur, curve);
        let frame = ImageView::new(&img, n, n, n).expect("view");
        let config = DetectorConfig { tone: ToneSetting::Fixed(ToneCurve::Srgb), ..DetectorConfig::default() };
        let detector = Detector::new(config).expect("valid");
        let dets = detector.detect(&frame).expect("runs");
        assert_eq!(dets.len(), 1, "{curve}, blur {blur}: the tag is found");
        detector.fit_tone(&frame, &dets)
    }

    #[test]
    fn one_tag_tells_its_power_law_best_when_sharp() {
        // A single tag's four sides, 8-bit rounding the only noise. Sharp or slightly blurred
        // (σ up to 1 px besides the pixel's own), the exponent to 0.15: the partly covered
        // pixels sample the curve at every share of ink and paper. Blurred by 1.3 px its ramp
        // is smooth and the odd terms take in more of a wrong curve's lopsidedness: the
        // estimate keeps to the right side of sRGB but falls short, by up to 0.5 at gamma 2.8
        // (a frame's many tags and the session's pooling do better: docs/accuracy.md).
        let mut checked = 0;
        for (gamma, blur, within) in [
            (1.6, 0.3, 0.15),
            (1.8, 0.3, 0.15),
            (1.8, 0.6, 0.15),
            (1.8, 1.0, 0.15),
            (2.8, 0.6, 0.15),
            (1.6, 1.3, 0.15),
            (1.8, 1.3, 0.15),
            (2.8, 1.3, 0.5),
        ] {
            let found = fit(ToneCurve::Gamma { gamma }, blur, 12.0).expect("tells");
            assert!((found.gamma - gamma).abs() <= within, "gamma {gamma}, blur {blur}: {found:?}");
            assert!(found.chi2 < found.srgb_chi2, "gamma {gamma}, blur {blur}: {found:?}");
            assert_eq!(found.sides, 4);
            assert!((found.blur_px - blur).abs() < 0.25 + 0.05 * blur, "gamma {gamma}, blur {blur}: {found:?}");
            checked += 1;
        }
        assert_eq!(checked, 8);
    }

    #[test]
    fn a_defocused_tag_tells_its_power_law_through_its_data_cells_edges() {
        // Blurred by a seventh to a sixth of its 14 px cell (a phone focused beyond the tags),
        // the data cells' edges a cell in reach into the border's ramp, and the quiet zone's
        // end, a cell out, leaves the paper no plateau: the data cells' edges are modelled, the
        // paper's side taken as far as it is clear. Each of these was refused before. The
        // exponent to 0.2 and better than sRGB.
        let mut checked = 0;
        for (gamma, blur) in [(1.8, 2.0), (1.8, 2.4), (2.6, 2.4), (1.6, 2.4)] {
            let found = fit(ToneCurve::Gamma { gamma }, blur, 12.0).expect("tells");
            assert!((found.gamma - gamma).abs() <= 0.2, "gamma {gamma}, blur {blur}: {found:?}");
            assert!(found.chi2 < found.srgb_chi2, "gamma {gamma}, blur {blur}: {found:?}");
            assert_eq!(found.sides, 4);
            checked += 1;
        }
        assert_eq!(checked, 4);
    }

    #[test]
    fn a_tag_along_the_pixel_grid_tells_nothing() {
        // Every pixel of a side at the same distance from its edge: one phase of the ramp,
        // which any curve fits.
        assert_eq!(fit(ToneCurve::Gamma { gamma: 1.8 }, 0.3, 0.0), None);
    }
}
