//! The movements a clinician marks in a recording as windows of time (a protrusion, a
//! laterotrusion toward each side, centric occlusion, maximal intercuspation), and the poses
//! each window holds.

use crate::SessionError;
use jawtrack_kinematics::Window;
use jawtrack_pose::Pose;
use jawtrack_recording::Recording;
use jawtrack_registration::bite::{BiteRefusal, BiteRule, judge_held};

/// The windows given, each with the flag that gave it (for messages).
#[derive(Debug, Clone, Copy, Default)]
pub struct MovementWindows {
    /// The protrusion.
    pub protrusion: Option<Window>,
    /// The laterotrusion toward the patient's left.
    pub left: Option<Window>,
    /// The laterotrusion toward the patient's right.
    pub right: Option<Window>,
    /// The jaw held in centric occlusion.
    pub co: Option<Window>,
    /// The jaw held in maximal intercuspation.
    pub mi: Option<Window>,
}

/// The poses of each movement given.
#[derive(Debug)]
pub struct MovementPoses {
    /// The protrusion, the laterotrusions toward the left and the right.
    pub border: [Option<Vec<Pose>>; 3],
    /// Centric occlusion as a held position: the mean pose of its window.
    pub co: Option<Pose>,
    /// Maximal intercuspation as a held position (`None` without its window: the closed jaw).
    pub mi: Option<Pose>,
}

impl MovementWindows {
    /// Whether a border movement is given.
    pub fn any_border(&self) -> bool {
        self.protrusion.is_some() || self.left.is_some() || self.right.is_some()
    }

    /// The poses of each window given in `rec` (named `name`), refusing a window without one.
    pub fn poses(&self, rec: &Recording, name: &str) -> Result<MovementPoses, SessionError> {
        let windows = [
            ("--protrusion", self.protrusion),
            ("--left", self.left),
            ("--right", self.right),
            ("--co", self.co),
            ("--mi", self.mi),
        ];
        let mut poses: Vec<Option<Vec<Pose>>> = Vec::new();
        for (flag, w) in windows {
            let p = w.map(|w| poses_in(rec, w));
            if let (Some(w), Some(p)) = (w, &p)
                && p.is_empty()
            {
                return Err(SessionError::Setting(format!(
                    "{flag} {}:{}: no frame of {name} in that window has a jaw pose",
                    w.from, w.to
                )));
            }
            poses.push(p);
        }
        let (co, mi) = (self.held(rec, name, "--co", self.co)?, self.held(rec, name, "--mi", self.mi)?);
        let mut it = poses.into_iter();
        Ok(MovementPoses { border: [it.next().flatten(), it.next().flatten(), it.next().flatten()], co, mi })
    }
}

impl MovementWindows {
    /// A held position's window (CO or MI) as its mean pose, when the jaw was held still in it
    /// by the bite step's rule ([`BiteRule`]): a window over a moving jaw gives a mean that is
    /// no position at all (a 29.6 mm "CO–MI slide" on a hinge opening).
    fn held(&self, rec: &Recording, name: &str, flag: &str, w: Option<Window>) -> Result<Option<Pose>, SessionError> {
        let Some(w) = w else { return Ok(None) };
        let samples: Vec<(f64, Pose)> =
            rec.frames.iter().filter(|f| w.holds(f.t)).filter_map(|f| Some((f.t, f.maxilla_from_mandible?))).collect();
        // The live step's spread and span; of frames, any three, since a window marked
        // afterwards is read whole, at whatever rate the phone recorded.
        let rule = BiteRule { min_frames: 3, ..BiteRule::default() };
        match judge_held(&rule, &samples) {
            Ok(bite) => Ok(Some(bite.maxilla_from_mandible)),
            Err(BiteRefusal::Moving { spread_mm, spread_deg, .. }) => Err(SessionError::Setting(format!(
                "{flag} {}:{}: the jaw is not held still in that window of {name} ({spread_mm:.2} mm and \
                 {spread_deg:.2}° from its mean; a held position stays within {} mm and {}°): choose the seconds \
                 where the jaw is held",
                w.from, w.to, rule.max_spread_mm, rule.max_spread_deg
            ))),
            Err(BiteRefusal::TooFewFrames { got, .. } | BiteRefusal::TooShort { frames: got, .. }) => {
                Err(SessionError::Setting(format!(
                    "{flag} {}:{}: {got} frames of {name} with a jaw pose in that window; a held position needs at \
                     least {} over {} s: widen the window over the held jaw",
                    w.from, w.to, rule.min_frames, rule.min_span_s
                )))
            }
        }
    }
}

/// The jaw poses in `w`.
fn poses_in(rec: &Recording, w: Window) -> Vec<Pose> {
    rec.frames.iter().filter(|f| w.holds(f.t)).filter_map(|f| f.maxilla_from_mandible).collect()
}

/// A warning when `rec` was tracked with the nominal marker, whose tags sit where the ideal
/// solid puts them and not where the print did: on rendered border movements with a print's
/// usual error (0.2 mm RMS per tag), `what` moved (docs/kinematics.md).
pub fn nominal_marker_warning(rec: &Recording, what: &str) -> Option<String> {
    let marker = rec.header.as_ref().and_then(|h| h.tracked_marker()).and_then(Result::ok);
    let nominal = marker.is_some_and(|m| m.measured_tags().is_empty());
    nominal.then(|| {
        format!(
            "this recording was tracked with the nominal marker: against a print's tag errors, {what}; calibrate \
             the marker (`jawtrack calibrate-marker`) and track again with it"
        )
    })
}
