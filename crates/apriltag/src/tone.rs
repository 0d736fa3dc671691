//! The camera's tone curve, estimated from the tags over a session, so that edges are fitted in
//! the camera's own linear light rather than an assumed sRGB.
//!
//! Phones do not deliver sRGB: their video curves are steeper or flatter power laws, S-shaped,
//! and adapt to the scene. Every tag shows ink and paper and, once blurred, the ramps between
//! them, which are symmetric in linear light whatever the lens did; read through the wrong
//! curve they are lopsided. [`Detector::fit_tone`] finds the power law that leaves one frame's
//! ramps least lopsided; a [`ToneSession`]
//! pools those fits over frames — a robust, side-weighted median over the recent ones — and
//! keeps the curve while the scene is steady, fitting each frame until it has settled and then
//! only every [`REFIT_EVERY_FRAMES`] frames. Every [`Detector`] set to
//! [`ToneSetting::Auto`] (the default) keeps one over the frames it detects.
//!
//! # Examples
//!
//! ```no_run
//! use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
//!
//! # fn frames() -> Vec<Vec<u8>> { Vec::new() }
//! let detector = Detector::new(DetectorConfig::default())?;
//! for pixels in frames() {
//!     let frame = ImageView::new(&pixels, 1920, 1080, 1920)?;
//!     let tags = detector.detect(&frame)?;
//!     println!("{} tags, read through {}", tags.len(), detector.tone().curve);
//! }
//! # Ok::<(), jawtrack_apriltag::DetectError>(())
//! ```

#[cfg(doc)]
use crate::Detector;
use jawtrack_tone::{ToneCurve, ToneReason, ToneSetting};
use std::collections::VecDeque;

/// The exponents searched: every camera curve we know of lies well inside (phones' video:
/// 1.8–2.6; sRGB is close to 2.2).
pub const GAMMA_SEARCH: std::ops::RangeInclusive<f64> = 1.2..=3.6;
/// Frames fitted one after another at the start, before the curve is taken as settled: three
/// frames' tags (some 50 sides) pin a power law to ±0.05, and each fit costs about five
/// detections (docs/accuracy.md, "Tone curves").
pub const SETTLING_FRAMES: usize = 3;
/// Once settled, a frame is fitted every this many (2 s at 60 fps): a phone's curve adapts to
/// the scene over seconds, and a fit costs about five detections' time. A [`Detector`] makes
/// these refits on a thread of its own and takes each into the session a fixed number of
/// detections later, so that the frame due one is not stalled.
pub const REFIT_EVERY_FRAMES: usize = 120;
/// After a frame whose tags told nothing (too few, or too few phases across their edges), this
/// many frames pass before the next fit: a scene whose tags never tell (held square to the
/// pixel grid, say) would otherwise pay a fit, about five detections, on every frame.
pub const RETRY_AFTER_FRAMES: usize = 30;
/// Fits pooled: the most recent ones.
const POOLED_FITS: usize = 9;
/// sRGB is kept unless the best power law leaves the pooled edges less lopsided by more than
/// this share of sRGB's χ² (and by [`SRGB_MARGIN_CHI2`] at least, against noise): the two
/// curves are close, and on sRGB frames the power law nearest it fits no better than sRGB
/// (`jawtrack-bench accuracy --tone-only`); a phone's gamma 1.8 fits better by 4–10 %, 2.6 by
/// 0.6–1.2 % (at 1 %, waved markers filmed at 2.6 were read as sRGB and their focal length
/// came out 0.38 % short).
const SRGB_MARGIN: f64 = 0.005;
const SRGB_MARGIN_CHI2: f64 = 50.0;
/// … and unless the pooled fits hold this many tag sides (six tags' worth): a single tag's
/// sides, each a few hundred pixels, can favour a curve by a per cent through what the blurred
/// step's terms miss of its profile rather than through the curve.
pub const MIN_POOLED_SIDES: usize = 24;
/// … and unless the edges fit a blurred step at all: their lopsidedness per pixel, with the
/// best power law, within this many times their noise. Sharpened frames miss it (1.9–2.1
/// with an unsharp mask of amount 1, 1 px; 0.97–1.06 without): a phone sharpens after its
/// curve, so its halos are symmetric in the encoded values, and the search then drifts toward
/// a linear curve, which reads the edges worse than sRGB does.
pub const MAX_MISFIT: f64 = 1.3;
/// A curve differing from the one in use by less than this in exponent is not worth a change
/// (it moves an edge by under a thousandth of its blur).
const MIN_CHANGE: f64 = 0.02;

/// What one frame's tags tell of the curve ([`Detector::fit_tone`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameToneFit {
    /// The exponent of the power law that leaves the edges least lopsided.
    pub gamma: f64,
    /// How lopsided it leaves them: Σ over the edges' ramp pixels of (the pixel + its mirror
    /// image across the edge − ink − paper)², in grey levels over the noise.
    pub chi2: f64,
    /// The same with the frame read as sRGB.
    pub srgb_chi2: f64,
    /// Terms in those sums.
    pub residuals: usize,
    /// Tag sides fitted.
    pub sides: usize,
    /// Their median blur (σ, px, the pixel's own spread taken out).
    pub blur_px: f64,
}

/// What a session's curve is, and how it was found: for the recording's header and the report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToneSummary {
    /// What was asked for.
    pub setting: ToneSetting,
    /// The curve frames are being read through.
    pub curve: ToneCurve,
    /// Why.
    pub reason: ToneReason,
    /// Frames whose tags were fitted, in all.
    pub frames_fitted: usize,
    /// Of the pooled fits: their tag sides in all, the side-weighted mean misfit of the
    /// estimated power law and of sRGB, and the spread (median absolute deviation) of their
    /// exponents. `None` before any fit.
    pub pooled: Option<PooledFit>,
}

/// The pooled fits behind an estimated curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PooledFit {
    /// Fits pooled.
    pub fits: usize,
    /// Tag sides in them.
    pub sides: usize,
    /// The fits' lopsidedness per term with their own best power laws, √(Σχ²/Σn): about 1
    /// when only noise is left…
    pub misfit: f64,
    /// … and with sRGB.
    pub srgb_misfit: f64,
    /// The exponent pooled (the side-weighted median).
    pub gamma: f64,
    /// Median absolute deviation of the fits' exponents.
    pub gamma_spread: f64,
}

/// The tone curve over a session of frames: fixed, or estimated and kept ([`ToneSetting`]).
#[derive(Debug, Clone)]
pub struct ToneSession {
    setting: ToneSetting,
    curve: ToneCurve,
    reason: ToneReason,
    recent: VecDeque<FrameToneFit>,
    frames_fitted: usize,
    since_fit: usize,
    /// Frames to pass before fitting again, after a frame whose tags told nothing.
    retry_in: usize,
}

impl ToneSession {
    /// A session reading frames as `setting` says: a fixed curve, or (`Auto`) sRGB until the
    /// tags have told their curve.
    pub fn new(setting: ToneSetting) -> Self {
        let (curve, reason) = match setting {
            ToneSetting::Auto => (ToneCurve::Srgb, ToneReason::NotYetTold),
            ToneSetting::Fixed(c) => (c, ToneReason::Given),
        };
        ToneSession { setting, curve, reason, recent: VecDeque::new(), frames_fitted: 0, since_fit: 0, retry_in: 0 }
    }

    /// The curve frames are to be read through now.
    pub fn curve(&self) -> ToneCurve {
        self.curve
    }

    /// What was asked for.
    pub fn setting(&self) -> ToneSetting {
        self.setting
    }

    /// Whether the next frame is to be fitted: always while settling, then every
    /// [`REFIT_EVERY_FRAMES`]; never with a fixed curve; and not within
    /// [`RETRY_AFTER_FRAMES`] of a frame whose tags told nothing.
    pub fn due(&self) -> bool {
        self.setting == ToneSetting::Auto
            && self.retry_in == 0
            && (self.frames_fitted < SETTLING_FRAMES || self.since_fit + 1 >= REFIT_EVERY_FRAMES)
    }

    /// Whether the curve has settled: the fits due from now on are the periodic refits.
    pub fn settled(&self) -> bool {
        self.frames_fitted >= SETTLING_FRAMES
    }

    /// Counts a frame that was not fitted.
    pub fn skip(&mut self) {
        self.since_fit += 1;
        self.retry_in = self.retry_in.saturating_sub(1);
    }

    /// Takes a frame's fit (`None`: its tags told nothing) into the estimate. Returns the new
    /// curve when it changed: read frames through it from now on.
    pub fn record(&mut self, fit: Option<FrameToneFit>) -> Option<ToneCurve> {
        let Some(fit) = fit else {
            self.skip();
            self.retry_in = RETRY_AFTER_FRAMES;
            return None;
        };
        self.since_fit = 0;
        self.frames_fitted += 1;
        if self.recent.len() == POOLED_FITS {
            self.recent.pop_front();
        }
        self.recent.push_back(fit);
        let pooled = self.pooled()?;
        let (chi2, srgb_chi2) = self.recent.iter().fold((0.0, 0.0), |(a, b), f| (a + f.chi2, b + f.srgb_chi2));
        self.reason = if pooled.sides < MIN_POOLED_SIDES {
            ToneReason::TooFewSides
        } else if pooled.misfit > MAX_MISFIT {
            ToneReason::NotBlurredSteps
        } else if srgb_chi2 - chi2 <= SRGB_MARGIN_CHI2.max(SRGB_MARGIN * srgb_chi2) {
            ToneReason::SrgbFitsAsWell
        } else {
            ToneReason::Estimated
        };
        let next = if self.reason == ToneReason::Estimated {
            ToneCurve::Gamma { gamma: pooled.gamma }
        } else {
            ToneCurve::Srgb
        };
        let changed = match (self.curve, next) {
            (ToneCurve::Gamma { gamma: a }, ToneCurve::Gamma { gamma: b }) => (a - b).abs() >= MIN_CHANGE,
            (a, b) => a != b,
        };
        changed.then(|| {
            self.curve = next;
            next
        })
    }

    /// The pooled fits: the side-weighted median exponent, the weighted mean misfits.
    fn pooled(&self) -> Option<PooledFit> {
        let sides: usize = self.recent.iter().map(|f| f.sides).sum();
        if sides == 0 {
            return None;
        }
        let mut by_gamma: Vec<&FrameToneFit> = self.recent.iter().collect();
        by_gamma.sort_by(|a, b| a.gamma.total_cmp(&b.gamma));
        let mut acc = 0;
        let gamma = by_gamma
            .iter()
            .find(|f| {
                acc += f.sides;
                2 * acc >= sides
            })
            .map_or(by_gamma[0].gamma, |f| f.gamma);
        let mut deviations: Vec<f64> = by_gamma.iter().map(|f| (f.gamma - gamma).abs()).collect();
        deviations.sort_by(f64::total_cmp);
        let n = self.recent.iter().map(|f| f.residuals).sum::<usize>().max(1) as f64;
        let per_term = |m: fn(&FrameToneFit) -> f64| (self.recent.iter().map(m).sum::<f64>() / n).sqrt();
        Some(PooledFit {
            fits: self.recent.len(),
            sides,
            misfit: per_term(|f| f.chi2),
            srgb_misfit: per_term(|f| f.srgb_chi2),
            gamma,
            gamma_spread: deviations[deviations.len() / 2],
        })
    }

    /// The curve in use and how it was found.
    pub fn summary(&self) -> ToneSummary {
        ToneSummary {
            setting: self.setting,
            curve: self.curve,
            reason: self.reason,
            frames_fitted: self.frames_fitted,
            pooled: self.pooled(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame's fit with `sides` sides of 100 terms each, at `misfit` and `srgb_misfit` per term.
    fn fit(gamma: f64, misfit: f64, srgb_misfit: f64, sides: usize) -> Option<FrameToneFit> {
        let residuals = 100 * sides;
        let chi2 = |m: f64| m * m * residuals as f64;
        Some(FrameToneFit { gamma, chi2: chi2(misfit), srgb_chi2: chi2(srgb_misfit), residuals, sides, blur_px: 1.0 })
    }

    #[test]
    fn a_fixed_curve_is_never_fitted() {
        let curve = ToneCurve::Gamma { gamma: 1.8 };
        let s = ToneSession::new(ToneSetting::Fixed(curve));
        assert!(!s.due());
        assert_eq!(s.curve(), curve);
        assert_eq!(s.summary().pooled, None);
    }

    #[test]
    fn auto_settles_on_the_pooled_exponent_and_then_refits_now_and_then() {
        let mut s = ToneSession::new(ToneSetting::Auto);
        assert_eq!(s.curve(), ToneCurve::Srgb, "sRGB until the tags tell");
        // A frame that told nothing does not count toward settling, and the next fit waits.
        assert_eq!(s.record(None), None);
        for _ in 0..RETRY_AFTER_FRAMES {
            assert!(!s.due(), "no fit on every frame of a scene whose tags tell nothing");
            s.skip();
        }
        assert!(s.due());
        assert_eq!(s.record(fit(1.8, 0.3, 0.5, 8)), None, "8 sides are too few to leave sRGB");
        assert_eq!(s.record(fit(1.8, 0.3, 0.5, 24)), Some(ToneCurve::Gamma { gamma: 1.8 }));
        // An outlier (a glare) is outvoted by the side-weighted median.
        assert_eq!(s.record(fit(2.9, 0.3, 0.5, 2)), None);
        assert!(!s.due(), "settled after {SETTLING_FRAMES} fits: not every frame");
        // A refit.
        assert_eq!(s.record(fit(1.81, 0.3, 0.5, 8)), None, "a change under 0.02 is not made");
        for _ in 0..REFIT_EVERY_FRAMES - 2 {
            s.skip();
        }
        assert!(!s.due());
        s.skip();
        assert!(s.due(), "the {REFIT_EVERY_FRAMES}th frame after a fit is fitted");
        let summary = s.summary();
        assert_eq!(summary.frames_fitted, 4);
        let pooled = summary.pooled.expect("pooled");
        assert_eq!((pooled.fits, pooled.sides), (4, 42));
        assert!((pooled.gamma - 1.8).abs() < 0.011, "{pooled:?}");
        assert!((pooled.misfit - 0.3).abs() < 1e-12 && (pooled.srgb_misfit - 0.5).abs() < 1e-12, "{pooled:?}");
    }

    #[test]
    fn srgb_is_kept_unless_a_power_law_fits_clearly_better() {
        let mut s = ToneSession::new(ToneSetting::Auto);
        // 2 400 terms: χ² 2 400 against 2 448, within the margin (50).
        assert_eq!(s.record(fit(2.2, 1.0, 1.01, 24)), None, "within the margin: sRGB stays");
        assert_eq!(s.curve(), ToneCurve::Srgb);
        // 80 000 terms (pooled with the first): 80 000 against 80 359, within 0.5 %.
        assert_eq!(s.record(fit(2.2, 1.0, 1.002, 776)), None, "within 0.5 %: sRGB stays");
        assert_eq!(s.record(fit(2.2, 1.0, 1.1, 8)), Some(ToneCurve::Gamma { gamma: 2.2 }));
    }

    #[test]
    fn edges_that_fit_no_blurred_step_leave_srgb() {
        // Sharpened frames: the best power law still leaves twice the noise.
        let mut s = ToneSession::new(ToneSetting::Auto);
        assert_eq!(s.record(fit(1.2, 2.0, 2.3, 40)), None);
        assert_eq!((s.curve(), s.summary().reason), (ToneCurve::Srgb, ToneReason::NotBlurredSteps));
    }
}
