//! What to tell the person holding the phone, frame by frame, from how far the tracker sees
//! the markers and whether they are in focus: before focus is locked, bring the phone to the
//! plan's distance and hold it still there while the lens focuses; once it is locked, stay
//! within the band where the markers are sharp ([`CapturePlan::near_mm`]..[`CapturePlan::far_mm`]).
//! The app turns each kind into its status line; the decision and its words live here, once.

use crate::plan::{CapturePlan, cm};

/// What the phone should do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GuidanceKind {
    /// No marker seen: point the camera at them.
    NoMarkers,
    /// Nearer than the lens can focus (before locking), or than the locked focus stays sharp.
    TooClose,
    /// So far that the tags are too small, or past where the locked focus stays sharp.
    TooFar,
    /// In range, focus not yet locked: hold still while it focuses and locks.
    HoldStill,
    /// The tracker sees the markers blurred: out of focus.
    OutOfFocus,
    /// In range, focus locked, markers sharp: record.
    Ready,
}

/// The guidance for a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Guidance {
    /// What to do.
    pub kind: GuidanceKind,
    /// In words, for the screen.
    pub message: String,
}

/// The guidance for a frame in which the markers are `depth_mm` away (the tracked bodies'
/// mean depth; `None` when neither is seen), with focus locked or not, and the tracker flagging a
/// body `defocused` or not.
///
/// # Examples
///
/// ```
/// use jawtrack_devices::{CameraFacts, GuidanceKind, Lens, PlanRequest, guide, optics, plan};
/// let p = plan(&[CameraFacts::typical(Lens::Wide, optics("iPhone16,1", Lens::Wide))], &PlanRequest::chewing(10.6))
///     .expect("a plan");
/// let g = guide(&p, Some(120.0), false, true);
/// assert_eq!(g.kind, GuidanceKind::TooClose);
/// assert_eq!(g.message, "too close: this camera focuses from 20 cm; hold it about 22 cm away");
/// assert_eq!(guide(&p, Some(221.0), false, false).kind, GuidanceKind::HoldStill);
/// assert_eq!(guide(&p, Some(221.0), true, false).kind, GuidanceKind::Ready);
/// ```
pub fn guide(plan: &CapturePlan, depth_mm: Option<f64>, focus_locked: bool, defocused: bool) -> Guidance {
    let at = cm(plan.distance_mm);
    let say = |kind, message: String| Guidance { kind, message };
    let Some(depth) = depth_mm.filter(|d| d.is_finite() && *d > 0.0) else {
        return say(GuidanceKind::NoMarkers, format!("point the camera at the markers, about {at} cm away"));
    };
    if !focus_locked {
        if depth < plan.min_focus_mm {
            return say(
                GuidanceKind::TooClose,
                format!("too close: this camera focuses from {} cm; hold it about {at} cm away", cm(plan.min_focus_mm)),
            );
        }
        if depth > plan.far_mm {
            return say(GuidanceKind::TooFar, format!("too far: the tags are too small; come to about {at} cm"));
        }
        return say(GuidanceKind::HoldStill, format!("hold still at about {at} cm while focus locks"));
    }
    if depth < plan.near_mm {
        return say(GuidanceKind::TooClose, format!("too close: focus is locked at {at} cm; move back to it"));
    }
    if depth > plan.far_mm {
        return say(GuidanceKind::TooFar, format!("too far: focus is locked at {at} cm; come closer to it"));
    }
    if defocused {
        return say(GuidanceKind::OutOfFocus, format!("out of focus: hold the phone about {at} cm away"));
    }
    say(GuidanceKind::Ready, format!("{} cm: in focus", cm(depth)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CameraFacts, Lens, PlanRequest, optics, plan};

    fn pro() -> CapturePlan {
        plan(&[CameraFacts::typical(Lens::Wide, optics("iPhone17,1", Lens::Wide))], &PlanRequest::chewing(10.61))
            .expect("plan")
    }

    #[test]
    fn before_focus_locks_the_phone_is_brought_beyond_its_nearest_focus_and_held_still() {
        let p = pro();
        let kind = |d: Option<f64>| guide(&p, d, false, false).kind;
        assert_eq!(kind(None), GuidanceKind::NoMarkers);
        assert_eq!(kind(Some(150.0)), GuidanceKind::TooClose);
        assert_eq!(kind(Some(199.0)), GuidanceKind::TooClose);
        assert_eq!(kind(Some(205.0)), GuidanceKind::HoldStill);
        assert_eq!(kind(Some(400.0)), GuidanceKind::TooFar);
        assert_eq!(
            guide(&p, Some(400.0), false, false).message,
            "too far: the tags are too small; come to about 22 cm"
        );
        assert_eq!(kind(Some(f64::NAN)), GuidanceKind::NoMarkers);
    }

    #[test]
    fn once_locked_the_phone_stays_in_the_sharp_band_and_blur_is_named() {
        let p = pro();
        let kind = |d: f64, defocused| guide(&p, Some(d), true, defocused).kind;
        assert_eq!(kind(220.0, false), GuidanceKind::Ready);
        assert_eq!(guide(&p, Some(224.0), true, false).message, "22 cm: in focus");
        assert_eq!(kind(p.near_mm - 1.0, false), GuidanceKind::TooClose);
        assert_eq!(kind(p.far_mm + 1.0, false), GuidanceKind::TooFar);
        assert_eq!(kind(220.0, true), GuidanceKind::OutOfFocus);
        assert!(guide(&p, Some(120.0), true, true).message.starts_with("too close: focus is locked at 22 cm"));
    }
}
