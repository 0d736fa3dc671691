//! What a run counts and keeps: the frames for judging the focal length at its end, the
//! counts for its closing line, and the warnings they call for.

use jawtrack_calibration::{CalibrationFrame, FocalCheck, SeenTag, check_focal};
use jawtrack_pose::CameraIntrinsics;
use jawtrack_tracker::{FrameResult, Tracker};
use std::collections::{BTreeMap, BTreeSet};

/// The marker's tags seen in frames spread over the run, for judging the focal length
/// ([`check_focal`]) at its end.
#[derive(Default)]
pub struct FocalViews {
    frames: Vec<CalibrationFrame>,
    offered: usize,
}

impl FocalViews {
    /// Views kept at most: the first `DENSE` frames with three tags of a body, then every
    /// `STRIDE`-th (a short recording needs them all to see a focus that moved).
    const MAX: usize = 200;
    const DENSE: usize = 40;
    const STRIDE: usize = 5;

    /// Offers a tracked frame.
    pub fn add(&mut self, r: &FrameResult, camera: &CameraIntrinsics) {
        let three = [&r.maxilla, &r.mandible].iter().any(|b| b.as_ref().is_some_and(|b| b.tags.len() >= 3));
        if !three || self.frames.len() >= Self::MAX {
            return;
        }
        self.offered += 1;
        if self.offered <= Self::DENSE || (self.offered - 1).is_multiple_of(Self::STRIDE) {
            let tags = r.detections.iter().map(|d| SeenTag { id: d.id, corners: d.corners }).collect();
            self.frames.push(CalibrationFrame { camera: *camera, tags });
        }
    }
}

/// Counts over a run, for the closing line.
#[derive(Default)]
pub struct Summary {
    /// Frames tracked (readable).
    pub read: usize,
    /// Frames skipped as unreadable.
    pub unreadable: usize,
    /// Frames with a jaw pose.
    pub both: usize,
    /// Frames with a body flagged `defocused`.
    pub defocused: usize,
    flags: BTreeMap<String, usize>,
    detection_s: Vec<f64>,
    /// Per body (maxilla, mandible): frames whose pose used a tag the calibrated marker left
    /// nominal (flagged `uncalibrated_tag`), and those tags.
    uncalibrated: [(usize, BTreeSet<u32>); 2],
}

impl Summary {
    /// Counts a tracked frame; `uncalibrated` are the marker's tags left nominal by its
    /// calibration ([`Tracker::uncalibrated_tags`]).
    pub fn add(&mut self, r: &FrameResult, uncalibrated: &[u32]) {
        self.read += 1;
        for (slot, body) in [&r.maxilla, &r.mandible].into_iter().enumerate() {
            let used: Vec<u32> = body
                .iter()
                .flat_map(|b| &b.tags)
                .copied()
                .filter(|id| uncalibrated.binary_search(id).is_ok())
                .collect();
            if !used.is_empty() {
                self.uncalibrated[slot].0 += 1;
                self.uncalibrated[slot].1.extend(used);
            }
        }
        self.both += usize::from(r.maxilla_from_mandible.is_some());
        self.defocused += usize::from(r.flags.iter().any(|f| matches!(f, jawtrack_tracker::Flag::Defocused(_))));
        for f in &r.flags {
            *self.flags.entry(f.name()).or_default() += 1;
        }
        self.detection_s.push(r.timings.detection_s + r.timings.pose_s);
    }

    /// Counts a skipped frame; the warning to print about it, for the first few.
    pub fn skip(&mut self, why: &str) -> Option<String> {
        const SAID: usize = 10;
        self.unreadable += 1;
        if self.unreadable <= SAID {
            Some(format!("{why}; skipped (its line is flagged `unreadable`)"))
        } else if self.unreadable == SAID + 1 {
            Some("more frames could not be read; the summary counts them".into())
        } else {
            None
        }
    }

    /// One line per body whose poses rested on nominal tags of a calibrated marker.
    pub fn uncalibrated_lines(&self) -> Vec<String> {
        jawtrack_marker::BodyKind::ALL
            .iter()
            .zip(&self.uncalibrated)
            .filter(|(_, (frames, _))| *frames > 0)
            .map(|(kind, (frames, ids))| {
                let ids: Vec<String> = ids.iter().map(u32::to_string).collect();
                format!(
                    "{kind}: {frames} frames rest on nominal tag{} {} (flagged {kind}:uncalibrated_tag): \
                     `--refine-marker` places them from this session, or calibrate with a recording that shows them",
                    if ids.len() == 1 { "" } else { "s" },
                    ids.join(", ")
                )
            })
            .collect()
    }

    /// The closing line's counts: jaw poses, flags, the median time per frame.
    pub fn describe(&mut self) -> String {
        let flags: Vec<String> = self.flags.iter().map(|(k, v)| format!("{k} ×{v}")).collect();
        self.detection_s.sort_by(f64::total_cmp);
        let median = self.detection_s.get(self.detection_s.len() / 2).copied().unwrap_or(0.0);
        format!(
            "{}jaw pose in {}; flags: {}; median {:.1} ms per frame",
            match self.unreadable {
                0 => String::new(),
                n => format!("{n} unreadable and skipped; "),
            },
            self.both,
            if flags.is_empty() { "none".to_owned() } else { flags.join(", ") },
            median * 1e3
        )
    }
}

/// The warnings a finished run calls for, in order: poses on nominal tags, markers out of
/// focus, a focal length that does not fit (wrong intrinsics, or a focus moved since
/// calibration), tags that disagreed with the marker file.
pub fn closing_warnings(summary: &Summary, views: &FocalViews, tracker: &Tracker) -> Vec<String> {
    let mut out = summary.uncalibrated_lines();
    if summary.defocused > 0 {
        out.push(format!(
            "{} of {} frames had a marker out of focus (flagged BODY:defocused: its tags' edges blurred by more than \
             0.14 of their cells' width) and give no jaw pose: the phone was nearer than its lens focuses, or far from \
             where its focus was locked; `jawtrack plan --phone MODEL` says where to hold it",
            summary.defocused, summary.read
        ));
    }
    let check = check_focal(tracker.marker(), &views.frames);
    let focal = check.filter(FocalCheck::looks_wrong);
    if let Some(focal) = &focal {
        out.push(intrinsics_warning(focal, []));
    }
    // A few per cent is what a focus moved since calibration does; only a measured marker (its
    // print errors known) can tell it.
    if let Some(moved) =
        check.filter(|c| focal.is_none() && c.focus_moved() && !tracker.marker().measured_tags().is_empty())
    {
        out.push(format!(
            "the focal length that fits is {:.3}× the one given ({moved}): did the focus or the zoom change since the \
             camera was calibrated? Focusing moves a phone's lens and scales the image (3.5 % between infinity and \
             20 cm); every distance is off by about that factor. Calibrate at the focus you record with, or lock focus \
             where `jawtrack plan` says",
            moved.best_scale
        ));
    }
    for (id, seen, dropped) in tracker.mismatched_tags(5) {
        out.push(if focal.is_some() {
            format!(
                "tag {id} disagreed with the marker file in {dropped} of {seen} frames (first check the intrinsics)"
            )
        } else {
            format!(
                "tag {id} disagreed with the marker file in {dropped} of the {seen} frames it was seen in and was left \
                 out: is it glued turned or on another face, or is the marker file another print's? \
                 `jawtrack calibrate-marker` finds and corrects such errors"
            )
        });
    }
    out
}

/// What to say when the views point to another focal length than the one given: shared by
/// `calibrate-marker` and `track`.
pub fn intrinsics_warning(focal: &FocalCheck, residuals_px: impl IntoIterator<Item = f64>) -> String {
    let worst = residuals_px.into_iter().fold(0.0, f64::max);
    format!(
        "check --intrinsics: {focal}{}. Intrinsics for another resolution or another lens make every \
         distance wrong by about that factor; a calibrated marker's residual is normally 0.1-0.5 px",
        if worst > 0.0 { format!(", and the marker fits with {worst:.2} px") } else { String::new() }
    )
}
