//! The maximal-intercuspation ("bite") step's one acceptance rule, for every place that offers
//! the step: the tracker (and through it the phone app), the live viewer, and the tools.
//!
//! The patient bites and holds still; the mean jaw pose over the last moments becomes the
//! rest position every clinical number is measured from. A step taken while the jaw moves
//! makes a wrong rest silently (pressed mid-opening, the old rule gave a rest 15 mm off), so
//! the step is accepted only over a short window of enough frames, spanning enough time, in
//! which the jaw stayed within a small spread ([`BiteRule`]).

use crate::mean_pose;
use jawtrack_pose::Pose;
use std::collections::VecDeque;

/// When a bite is accepted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiteRule {
    /// The window looked at: the frames of the last this many seconds (s).
    pub window_s: f64,
    /// Frames with the jaw pose the window needs …
    pub min_frames: usize,
    /// … spanning at least this (s): a still jaw is one seen still for a while.
    pub min_span_s: f64,
    /// The farthest a frame's mandible-marker origin may be from the mean (mm) …
    pub max_spread_mm: f64,
    /// … and the farthest its rotation may be from the mean (°).
    pub max_spread_deg: f64,
}

impl Default for BiteRule {
    /// Half a second, at least 8 frames over 0.3 s, within 0.3 mm and 1°: tracking noise of a
    /// held bite is a few hundredths of a millimetre, while a jaw closing at 1 mm/s already
    /// spreads 0.25 mm over the window.
    fn default() -> Self {
        BiteRule { window_s: 0.5, min_frames: 8, min_span_s: 0.3, max_spread_mm: 0.3, max_spread_deg: 1.0 }
    }
}

impl BiteRule {
    /// Refuses a rule that could accept nothing or anything.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("window_s", self.window_s),
            ("min_span_s", self.min_span_s),
            ("max_spread_mm", self.max_spread_mm),
            ("max_spread_deg", self.max_spread_deg),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("bite rule: {name} must be a positive number, got {v}"));
            }
        }
        if self.min_span_s > self.window_s {
            return Err(format!("bite rule: min_span_s {} is longer than window_s {}", self.min_span_s, self.window_s));
        }
        if self.min_frames < 2 {
            return Err(format!("bite rule: min_frames must be at least 2, got {}", self.min_frames));
        }
        Ok(())
    }
}

/// An accepted bite: the rest position and how still the jaw was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bite {
    /// The time of the last frame of the window (s).
    pub t: f64,
    /// The mean `maxilla_from_mandible` over the window: the rest position.
    pub maxilla_from_mandible: Pose,
    /// Frames averaged.
    pub frames: usize,
    /// Time from the first to the last of them (s).
    pub span_s: f64,
    /// The farthest a frame's mandible-marker origin was from the mean (mm).
    pub spread_mm: f64,
    /// The farthest a frame's rotation was from the mean (°).
    pub spread_deg: f64,
}

/// Why a bite was not accepted; each says what to do.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum BiteRefusal {
    /// Too few frames with both jaws tracked in the window.
    #[error(
        "the bite step needs {needed} frames with both jaws tracked in the last {window_s} s, has {got}: \
         bite, hold still, and try again"
    )]
    TooFewFrames {
        /// Frames needed.
        needed: usize,
        /// Frames there are.
        got: usize,
        /// The window (s).
        window_s: f64,
    },
    /// The frames span too short a time.
    #[error(
        "the bite step needs the jaw seen still for {needed_s} s, has {span_s:.2} s: hold the bite a moment longer"
    )]
    TooShort {
        /// Span needed (s).
        needed_s: f64,
        /// Span there is (s).
        span_s: f64,
        /// Frames in it.
        frames: usize,
    },
    /// The jaw moved in the window.
    #[error(
        "the jaw moved during the bite step ({spread_mm:.2} mm and {spread_deg:.2}° from its mean; at most \
         {limit_mm} mm and {limit_deg}°): bite firmly, hold still, and try again"
    )]
    Moving {
        /// How far it moved (mm).
        spread_mm: f64,
        /// How far it turned (°).
        spread_deg: f64,
        /// The rule's limit (mm).
        limit_mm: f64,
        /// The rule's limit (°).
        limit_deg: f64,
    },
}

/// The recent jaw poses the bite step judges, kept as frames arrive.
#[derive(Debug, Clone)]
pub struct BiteWindow {
    rule: BiteRule,
    samples: VecDeque<(f64, Pose)>,
    latest: Option<f64>,
}

impl BiteWindow {
    /// An empty window judged by `rule` (see [`BiteRule::validate`]).
    pub fn new(rule: BiteRule) -> Self {
        BiteWindow { rule, samples: VecDeque::new(), latest: None }
    }

    /// The rule it judges by.
    pub fn rule(&self) -> &BiteRule {
        &self.rule
    }

    /// A frame at `t` (s) and its jaw pose, if both jaws were tracked. Frames older than the
    /// window are forgotten; a frame without the pose still moves the window on.
    pub fn push(&mut self, t: f64, maxilla_from_mandible: Option<Pose>) {
        if !t.is_finite() {
            return;
        }
        self.latest = Some(self.latest.map_or(t, |l| l.max(t)));
        if let Some(p) = maxilla_from_mandible.filter(Pose::is_finite) {
            self.samples.push_back((t, p));
        }
        let start = self.latest.unwrap_or(t) - self.rule.window_s;
        while self.samples.front().is_some_and(|&(s, _)| s < start) {
            self.samples.pop_front();
        }
    }

    /// The jaw poses in the window, oldest first.
    pub fn poses(&self) -> Vec<Pose> {
        self.samples.iter().map(|&(_, p)| p).collect()
    }

    /// Forgets every frame (a new session).
    pub fn clear(&mut self) {
        self.samples.clear();
        self.latest = None;
    }

    /// The bite over the window, if the rule accepts it.
    pub fn judge(&self) -> Result<Bite, BiteRefusal> {
        let samples: Vec<(f64, Pose)> = self.samples.iter().copied().collect();
        judge_held(&self.rule, &samples)
    }
}

/// The rule applied to a held position: the frames `samples` (time, jaw pose; oldest first),
/// all of them, whether the last moments of a live bite step or a window marked afterwards in
/// a recording (centric occlusion, maximal intercuspation).
///
/// # Examples
///
/// ```
/// use jawtrack_registration::bite::{BiteRule, judge_held};
/// let still: Vec<_> = (0..10).map(|i| (f64::from(i) * 0.05, jawtrack_pose::Pose::identity())).collect();
/// assert!(judge_held(&BiteRule::default(), &still).is_ok());
/// ```
pub fn judge_held(rule: &BiteRule, samples: &[(f64, Pose)]) -> Result<Bite, BiteRefusal> {
    let r = rule;
    let got = samples.len();
    if got < r.min_frames {
        return Err(BiteRefusal::TooFewFrames { needed: r.min_frames, got, window_s: r.window_s });
    }
    let (first, last) = (samples[0].0, samples[got - 1].0);
    let span_s = last - first;
    if span_s < r.min_span_s {
        return Err(BiteRefusal::TooShort { needed_s: r.min_span_s, span_s, frames: got });
    }
    let poses: Vec<Pose> = samples.iter().map(|&(_, p)| p).collect();
    let Some(mean) = mean_pose(&poses) else {
        return Err(BiteRefusal::TooFewFrames { needed: r.min_frames, got: 0, window_s: r.window_s });
    };
    let spread_mm = poses.iter().map(|p| (p.translation() - mean.translation()).norm()).fold(0.0, f64::max);
    let spread_deg = poses.iter().map(|p| p.rotation().angle_to(&mean.rotation()).to_degrees()).fold(0.0, f64::max);
    if spread_mm > r.max_spread_mm || spread_deg > r.max_spread_deg {
        return Err(BiteRefusal::Moving {
            spread_mm,
            spread_deg,
            limit_mm: r.max_spread_mm,
            limit_deg: r.max_spread_deg,
        });
    }
    Ok(Bite { t: last, maxilla_from_mandible: mean, frames: got, span_s, spread_mm, spread_deg })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn jaw(opening_mm: f64) -> Pose {
        Pose::from_axis_angle(Vector3::new(0.01 * opening_mm, 0.0, 0.0), Vector3::new(0.0, 40.0 + opening_mm, 5.0))
    }

    /// Frames at 30 fps from `t0` for `n` frames, the jaw opening at `speed` mm/s.
    fn window(t0: f64, n: usize, speed: f64) -> BiteWindow {
        let mut w = BiteWindow::new(BiteRule::default());
        for i in 0..n {
            let t = t0 + i as f64 / 30.0;
            w.push(t, Some(jaw(speed * (t - t0))));
        }
        w
    }

    #[test]
    fn a_still_bite_is_accepted_with_its_mean() {
        let b = window(3.0, 30, 0.0).judge().expect("still");
        // Half a second at 30 fps: 15 or 16 frames, whichever side of the edge rounding puts.
        assert!((15..=16).contains(&b.frames), "{b:?}");
        assert!(b.spread_mm < 1e-9 && b.spread_deg < 1e-9);
        assert!((b.t - (3.0 + 29.0 / 30.0)).abs() < 1e-12);
        assert!(b.maxilla_from_mandible.distance_to(&jaw(0.0)).1 < 1e-9);
    }

    #[test]
    fn a_jaw_moving_at_chewing_speed_is_refused() {
        // Pressed mid-opening: 90 mm/s.
        let e = window(0.0, 30, 90.0).judge().expect_err("moving");
        assert!(matches!(e, BiteRefusal::Moving { spread_mm, .. } if spread_mm > 10.0), "{e:?}");
        assert!(e.to_string().contains("hold still"), "{e}");
        // Even a slow close is too much.
        assert!(matches!(window(0.0, 30, 2.0).judge(), Err(BiteRefusal::Moving { .. })));
    }

    #[test]
    fn too_few_or_too_brief_frames_are_refused() {
        let e = window(0.0, 5, 0.0).judge().expect_err("five frames");
        assert_eq!(e, BiteRefusal::TooFewFrames { needed: 8, got: 5, window_s: 0.5 });
        // Eight frames at 120 fps span 58 ms.
        let mut w = BiteWindow::new(BiteRule::default());
        for i in 0..8 {
            w.push(i as f64 / 120.0, Some(jaw(0.0)));
        }
        assert!(matches!(w.judge(), Err(BiteRefusal::TooShort { .. })), "{:?}", w.judge());
    }

    #[test]
    fn frames_without_the_jaw_move_the_window_on() {
        let mut w = window(0.0, 30, 0.0);
        assert!(w.judge().is_ok());
        // A second with the jaw lost: the old frames are no longer recent.
        for i in 1..=30 {
            w.push(1.0 + i as f64 / 30.0, None);
        }
        assert!(matches!(w.judge(), Err(BiteRefusal::TooFewFrames { got: 0, .. })));
        w.push(f64::NAN, Some(jaw(0.0)));
        assert!(matches!(w.judge(), Err(BiteRefusal::TooFewFrames { got: 0, .. })), "a NaN time is ignored");
    }

    #[test]
    fn a_rule_that_accepts_nothing_is_refused() {
        assert!(BiteRule::default().validate().is_ok());
        assert!(BiteRule { min_span_s: 1.0, ..BiteRule::default() }.validate().is_err());
        assert!(BiteRule { max_spread_mm: f64::NAN, ..BiteRule::default() }.validate().is_err());
        assert!(BiteRule { min_frames: 1, ..BiteRule::default() }.validate().is_err());
    }
}
