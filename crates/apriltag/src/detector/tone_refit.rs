//! The tone curve's periodic refit, taken off the frame that is due it.
//!
//! Once the curve has settled ([`crate::tone`]), a frame is fitted every
//! [`REFIT_EVERY_FRAMES`](crate::tone::REFIT_EVERY_FRAMES) frames, and a fit costs five to
//! fifteen detections: 35–40 ms on a tracked 1080p frame of this machine, 45–60 ms on a 4K one,
//! on one thread whatever the detector's count. Paid on the frame, that stalls it past three
//! frames' budget at 60 frames/s. So the frame's tags and the pixels around them are copied out
//! and fitted on a thread of their own, and the fit is taken into the session a fixed number of
//! detections later ([`REFIT_LAG_DETECTIONS`]), waiting for it then if it is not done: which
//! curve a frame is read through depends on the frames, never on how fast the thread ran. The
//! settling fits stay on the frame: each reads its frame again through the curve it found.

use super::Detection;
use super::tone_fit::fit_tone_through;
use crate::gray::Gray;
use crate::image::ImageView;
use crate::tone::FrameToneFit;
use jawtrack_tag_family::TagFamily;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Arc, Condvar, Mutex};

/// Detections between the one whose tags are fitted and the one after which their fit is
/// taken: half a second at 60 frames/s, ten times the fit's time on this machine.
pub(super) const REFIT_LAG_DETECTIONS: usize = 30;

/// A frame's fit under way on its own thread.
#[derive(Debug, Clone)]
pub(super) struct PendingFit {
    /// Detections still to come before the fit is taken.
    left: usize,
    /// The fit once done (`Some(None)`: the tags told nothing), and the signal that it is.
    done: Arc<(Mutex<Option<Option<FrameToneFit>>>, Condvar)>,
}

impl PendingFit {
    /// Starts fitting the tone curve to `dets` (of `family`, found in `frame` through `lut`) on
    /// a thread of its own. `None` when no thread could be started: fit on the caller's then.
    pub(super) fn start(
        family: TagFamily,
        frame: &ImageView<'_>,
        dets: &[Detection],
        lut: Arc<[f64; 256]>,
    ) -> Option<PendingFit> {
        let patch = Patch::around(frame, dets);
        let done = Arc::new((Mutex::new(None), Condvar::new()));
        let signal = Arc::clone(&done);
        std::thread::Builder::new()
            .name("jawtrack-tone-fit".into())
            .spawn(move || {
                // A fit that panicked tells nothing; the detection waiting for it must not wait forever.
                let fit = catch_unwind(AssertUnwindSafe(|| patch.fit(&family, &lut))).unwrap_or(None);
                let (slot, ready) = &*signal;
                *slot.lock().unwrap_or_else(|p| p.into_inner()) = Some(fit);
                ready.notify_all();
            })
            .ok()?;
        Some(PendingFit { left: REFIT_LAG_DETECTIONS, done })
    }

    /// Counts a detection; once [`REFIT_LAG_DETECTIONS`] have passed, the fit (waiting for
    /// its thread if need be).
    pub(super) fn tick(&mut self) -> Option<Option<FrameToneFit>> {
        self.left = self.left.saturating_sub(1);
        if self.left > 0 {
            return None;
        }
        let (slot, ready) = &*self.done;
        let mut fit = slot.lock().unwrap_or_else(|p| p.into_inner());
        while fit.is_none() {
            fit = ready.wait(fit).unwrap_or_else(|p| p.into_inner());
        }
        *fit
    }
}

/// The pixels around a frame's tags, and the tags moved into its coordinates.
struct Patch {
    pixels: Gray,
    dets: Vec<Detection>,
}

impl Patch {
    /// The smallest box of `frame` holding every tag of `dets` and, around each, as far again
    /// as the widest tag's box plus 4 px: the border fit's windows reach at most four cells
    /// and 2 px beyond a side (a tag's box spans at least its eight cells), so every side the
    /// fit could read on the whole frame it reads here alike.
    fn around(frame: &ImageView<'_>, dets: &[Detection]) -> Patch {
        let (mut lo, mut hi, mut widest) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2], 0.0f64);
        for d in dets {
            let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in &d.corners {
                a = [a[0].min(p[0]), a[1].min(p[1])];
                b = [b[0].max(p[0]), b[1].max(p[1])];
            }
            widest = widest.max(b[0] - a[0]).max(b[1] - a[1]);
            lo = [lo[0].min(a[0]), lo[1].min(a[1])];
            hi = [hi[0].max(b[0]), hi[1].max(b[1])];
        }
        let grow = widest + 4.0;
        let clamp = |v: f64, n: usize| if v.is_finite() { v.clamp(0.0, (n - 1) as f64) as usize } else { 0 };
        let (x0, y0) = (clamp((lo[0] - grow).floor(), frame.width()), clamp((lo[1] - grow).floor(), frame.height()));
        let (x1, y1) = (clamp((hi[0] + grow).ceil(), frame.width()), clamp((hi[1] + grow).ceil(), frame.height()));
        let (w, h) = if dets.is_empty() { (0, 0) } else { ((x1 + 1).saturating_sub(x0), (y1 + 1).saturating_sub(y0)) };
        let mut pixels = Gray::filled(w, h, 0);
        for (y, row) in pixels.data.chunks_exact_mut(w.max(1)).enumerate() {
            row.copy_from_slice(&frame.row(y0 + y)[x0..x0 + w]);
        }
        let (ox, oy) = (x0 as f64, y0 as f64);
        let dets = dets.iter().map(|d| d.shifted(-ox, -oy)).collect();
        Patch { pixels, dets }
    }

    /// The tone fit of the tags in the patch, as on the whole frame.
    fn fit(&self, family: &TagFamily, lut: &[f64; 256]) -> Option<FrameToneFit> {
        let view = self.pixels.view().ok()?;
        fit_tone_through(family, &view, &self.dets, lut)
    }
}

#[cfg(test)]
mod tests {
    use super::{PendingFit, REFIT_LAG_DETECTIONS};
    use crate::detector::border::tests::drawn_through;
    use crate::tone::{REFIT_EVERY_FRAMES, SETTLING_FRAMES};
    use crate::{Detector, DetectorConfig, ImageView, ToneCurve, ToneSetting};
    use std::sync::Arc;

    /// A blurred tag drawn through a gamma of 1.8 inside a larger frame (so that the patch
    /// around it is a box of its own): the pixels and the frame's size.
    fn framed_tag() -> (Vec<u8>, usize, usize) {
        let (img, n, _) = drawn_through(7, 9.0, 14.0, 1.5, 1.2, 1.0, ToneCurve::Gamma { gamma: 1.8 });
        let (w, h) = (n + 260, n + 200);
        let mut frame = vec![200u8; w * h];
        for y in 0..n {
            frame[(y + 90) * w + 110..(y + 90) * w + 110 + n].copy_from_slice(&img[y * n..(y + 1) * n]);
        }
        (frame, w, h)
    }

    /// A fit on its own thread, from the pixels around the tags, is the fit of the whole
    /// frame, and is given after exactly [`REFIT_LAG_DETECTIONS`] detections.
    #[test]
    fn a_fit_on_its_own_thread_is_the_whole_frames_and_comes_when_due() {
        let (frame, w, h) = framed_tag();
        let view = ImageView::new(&frame, w, h, w).expect("view");
        // Read through sRGB throughout, as the fit on its thread is.
        let config = DetectorConfig { tone: ToneSetting::Fixed(ToneCurve::Srgb), ..DetectorConfig::default() };
        let detector = Detector::new(config).expect("valid");
        let dets = detector.detect(&view).expect("runs");
        assert_eq!(dets.len(), 1, "the drawn tag");
        let lut = ToneCurve::Srgb.decode_table();
        let whole = detector.fit_tone(&view, &dets);
        let whole = whole.expect("a blurred tag tells its curve");
        let mut pending = PendingFit::start(config.family, &view, &dets, Arc::new(lut)).expect("a thread");
        for k in 1..REFIT_LAG_DETECTIONS {
            assert_eq!(pending.tick(), None, "detection {k}: not yet due");
        }
        let fit = pending.tick().expect("due").expect("told");
        assert!((fit.gamma - whole.gamma).abs() < 1e-9, "γ {} on its thread, {} on the frame", fit.gamma, whole.gamma);
        assert!((fit.chi2 / whole.chi2 - 1.0).abs() < 1e-9, "χ² {} against {}", fit.chi2, whole.chi2);
        assert_eq!((fit.sides, fit.residuals), (whole.sides, whole.residuals));
    }

    /// While the curve settles each detection is fitted on the frame; once settled, the
    /// detection a refit is due starts it, and the session takes it [`REFIT_LAG_DETECTIONS`]
    /// detections later, not before.
    #[test]
    fn a_settled_curve_is_refitted_off_the_frame_and_taken_a_fixed_number_of_detections_later() {
        let (frame, w, h) = framed_tag();
        let view = ImageView::new(&frame, w, h, w).expect("view");
        let detector = Detector::new(DetectorConfig::default()).expect("valid");
        let (mut due, mut fitted, mut last) = (Vec::new(), Vec::new(), 0);
        let detections = SETTLING_FRAMES + REFIT_EVERY_FRAMES + REFIT_LAG_DETECTIONS + 5;
        for k in 0..detections {
            if detector.tone_fit_due() {
                due.push(k);
            }
            assert_eq!(detector.detect(&view).expect("runs").len(), 1, "detection {k}: the tag");
            let now = detector.tone().frames_fitted;
            if now != last {
                fitted.push(k);
                last = now;
            }
        }
        // The last settling fit at detection 2; the refit due when 120 detections have passed
        // unfitted since (3 … 121), and taken 30 after it.
        let refit = SETTLING_FRAMES - 1 + REFIT_EVERY_FRAMES;
        assert_eq!(due, [0, 1, 2, refit], "fits due");
        assert_eq!(fitted, [0, 1, 2, refit + REFIT_LAG_DETECTIONS], "fits taken");
    }
}
