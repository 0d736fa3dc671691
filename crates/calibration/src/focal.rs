//! Judging the camera's focal length from views of the marker: a focal length off by tens of
//! per cent (intrinsics of another resolution or another lens) leaves every view fitting
//! badly in the same way, and a calibration or a tracked recording made with it is wrong in
//! scale throughout (a 2× focal length made a 36.3 mm opening read 26.9 mm). Single views of a
//! solid marker constrain the focal length through perspective: the faces nearer the camera
//! look larger than the far ones by the ratio of their depths, which only the right focal
//! length reproduces.
//!
//! [`check_focal`] fits every view's body pose with the focal lengths scaled by a common
//! factor, and finds the factor that fits best. Intrinsics look wrong when another factor
//! fits clearly better than 1 ([`FocalCheck::looks_wrong`]). With a marker whose tags were
//! measured (calibrated), the factor is found to a few tenths of a per cent, enough to see the
//! few per cent a phone's focal length changes by when its focus moves
//! ([`FocalCheck::focus_moved`]).

use crate::{CalibrationFrame, SeenTag};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::{CameraIntrinsics, Observation, PnpOptions, median, solve_pnp};
use nalgebra::Point2;

/// Views used at most (evenly spread over those given): enough for a stable median.
const MAX_VIEWS: usize = 40;
/// Tags of one body a view needs: three faces at different depths show the perspective.
const MIN_TAGS: usize = 3;
/// The factors tried first, log-spaced from a third to three times the given focal length.
const COARSE_STEPS: usize = 25;
const MIN_SCALE: f64 = 1.0 / 3.0;
const MAX_SCALE: f64 = 3.0;

/// What the views say about the focal length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FocalCheck {
    /// Views (of one body, with at least three of its tags) the judgement rests on.
    pub views: usize,
    /// Median RMS reprojection error (px) of the views with the focal length given.
    pub given_px: f64,
    /// The factor on the focal length that fits best.
    pub best_scale: f64,
    /// Median RMS reprojection error (px) with it.
    pub best_px: f64,
}

/// The smallest change of the focal length [`FocalCheck::focus_moved`] names (a fraction):
/// focusing a 6.8 mm lens from 300 to 200 mm changes it by 1.2 %, from infinity to 200 mm by
/// 3.5 %; with the marker as printed, 24 views of the static grid at 220 mm (2× crop) find the
/// right focal length within 0.1 % and a 3 % error within 0.3 %.
pub const FOCUS_MOVED: f64 = 0.015;

impl FocalCheck {
    /// With a marker whose tags were measured (calibrated: a nominal marker's print errors move
    /// the optimum by up to 12 %), another focal length fits clearly better by what focusing
    /// elsewhere, or another zoom, changes it by: off by [`FOCUS_MOVED`] or more (and less than
    /// [`FocalCheck::looks_wrong`]'s 10 %), with a median error at least a fifth smaller.
    pub fn focus_moved(&self) -> bool {
        let off = (self.best_scale - 1.0).abs();
        (FOCUS_MOVED..=0.1).contains(&off) && self.best_px < 0.8 * self.given_px
    }

    /// Another focal length fits clearly better: off by more than 10 %, with a median error
    /// at most two thirds of the given one's and at least 0.3 px smaller. With a calibrated
    /// marker right intrinsics give 1.00 and focal lengths 20 % or 2× off are found to 2 %;
    /// the nominal marker's print errors (0.2 mm) move the optimum by up to 12 % but lower its
    /// error by a tenth at most (`crates/calibration/tests/calibration.rs`).
    pub fn looks_wrong(&self) -> bool {
        (self.best_scale - 1.0).abs() > 0.1
            && self.best_px < self.given_px * 2.0 / 3.0
            && self.given_px - self.best_px > 0.3
    }
}

impl std::fmt::Display for FocalCheck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "over {} views, focal lengths {:.2}× those given fit with a median {:.2} px against {:.2} px",
            self.views, self.best_scale, self.best_px, self.given_px
        )
    }
}

/// Judges the focal length of `frames`' cameras against `marker` (the file's placements:
/// small print errors barely move the optimum); `None` without a view showing three tags of
/// one body.
pub fn check_focal(marker: &Marker, frames: &[CalibrationFrame]) -> Option<FocalCheck> {
    let mut views: Vec<(CameraIntrinsics, Vec<Observation>)> = Vec::new();
    for f in frames {
        for kind in [BodyKind::Maxilla, BodyKind::Mandible] {
            let seen: Vec<&SeenTag> =
                f.tags.iter().filter(|s| marker.find_tag(s.id).is_some_and(|(k, _)| k == kind)).collect();
            if seen.len() < MIN_TAGS {
                continue;
            }
            let observations = seen
                .iter()
                .filter_map(|s| marker.find_tag(s.id).map(|(_, tag)| (s, tag)))
                .flat_map(|(s, tag)| {
                    (0..4).map(move |i| Observation {
                        tag: s.id,
                        body: tag.corners[i].into(),
                        pixel: Point2::new(s.corners[i][0], s.corners[i][1]),
                    })
                })
                .collect();
            views.push((f.camera, observations));
        }
    }
    if views.is_empty() {
        return None;
    }
    let step = views.len().div_ceil(MAX_VIEWS);
    let views: Vec<_> = views.into_iter().step_by(step).collect();
    // Every tag counts: dropping the ones that disagree would hide the disagreement.
    let options = PnpOptions { outlier_px: f64::INFINITY, ..PnpOptions::default() };
    let error = |scale: f64| -> f64 {
        let errors = views.iter().filter_map(|(camera, observations)| {
            let camera = CameraIntrinsics { fx: camera.fx * scale, fy: camera.fy * scale, ..*camera };
            solve_pnp(observations, &camera, None, &options).ok().map(|p| p.rms_px)
        });
        median(errors).unwrap_or(f64::INFINITY)
    };
    let log_scale = |i: usize| {
        let (lo, hi) = (MIN_SCALE.ln(), MAX_SCALE.ln());
        (lo + (hi - lo) * i as f64 / (COARSE_STEPS - 1) as f64).exp()
    };
    let coarse: Vec<(f64, f64)> = (0..COARSE_STEPS).map(|i| (log_scale(i), error(log_scale(i)))).collect();
    let best = (0..COARSE_STEPS).min_by(|&a, &b| coarse[a].1.total_cmp(&coarse[b].1)).unwrap_or(0);
    // Golden-section search between the best factor's neighbours.
    let (mut lo, mut hi) = (coarse[best.saturating_sub(1)].0, coarse[(best + 1).min(COARSE_STEPS - 1)].0);
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
    let (mut fa, mut fb) = (error(a), error(b));
    for _ in 0..20 {
        if fa < fb {
            (hi, b, fb) = (b, a, fa);
            a = hi - ratio * (hi - lo);
            fa = error(a);
        } else {
            (lo, a, fa) = (a, b, fb);
            b = lo + ratio * (hi - lo);
            fb = error(b);
        }
    }
    let (best_scale, best_px) =
        [(a, fa), (b, fb), coarse[best]].into_iter().min_by(|x, y| x.1.total_cmp(&y.1)).unwrap_or(coarse[best]);
    Some(FocalCheck { views: views.len(), given_px: error(1.0), best_scale, best_px })
}
