//! The stages of [`run`](super::run): calibrating the marker from the calibration recording,
//! the bite step on its closed-jaw frames, and judging each experiment's frames.

use super::{
    BITE_AZIMUTH_DEG, BiteStep, BodySummary, FrameRecord, MarkerFile, Options, PerMarker, Stacks, new_trackers,
    read_luma, session, tracker_config,
};
use crate::frames::{self, Scene};
use anyhow::{Context, Result};
use jawtrack_apriltag::{Detection, Detector};
use jawtrack_calibration::{Calibration, CalibrationFrame, CalibrationOptions, SeenTag, calibrate};
use jawtrack_marker::Marker;
use jawtrack_pose::Pose;
use jawtrack_registration::{IntercuspationCalibration, Registration, calibrate_intercuspation};
use jawtrack_synth::SceneKind;

/// The calibration recording and the markers calibrated from it.
pub(super) struct Calibrated {
    pub(super) scene: Scene,
    pub(super) nominal: Marker,
    /// From every view.
    pub(super) cal: Calibration,
    /// From the views of the front faces only.
    pub(super) front: Calibration,
}

/// Renders (or reads) the calibration recording, detects its tags, and calibrates the marker
/// from every view and from the front faces only.
pub(super) fn calibrate_markers(options: &Options, progress: &mut dyn FnMut(&str, usize, usize)) -> Result<Calibrated> {
    let req = options.request(SceneKind::Calibration);
    let scene = frames::scene(&options.cache, &req, &mut |d, t| progress("rendering the calibration recording", d, t))?;
    let config = tracker_config(&scene.truth);
    let detector = Detector::new(config.detector)?;
    let nominal = Marker::default();
    let mut views = Vec::new();
    for (i, f) in scene.truth.frames.iter().enumerate() {
        progress("detecting tags in the calibration recording", i, scene.truth.frames.len());
        let img = read_luma(&scene.dir.join(&f.file))?;
        let tags = detector
            .detect(&img.view()?)?
            .into_iter()
            .filter(|d| nominal.find_tag(d.id).is_some())
            .map(|d| SeenTag { id: d.id, corners: d.corners })
            .collect();
        views.push(CalibrationFrame { camera: scene.truth.intrinsics, tags });
    }
    let cal = calibrate(&nominal, &views, &CalibrationOptions::default()).context("calibrating the marker")?;
    let front = calibrate(&nominal, &session::front_faces_only(&views, &nominal), &CalibrationOptions::default())
        .context("calibrating the marker from its front faces")?;
    Ok(Calibrated { scene, nominal, cal, front })
}

/// Each body's calibration, for the report.
pub(super) fn summarise(c: &Calibration) -> Vec<BodySummary> {
    c.bodies
        .iter()
        .map(|b| BodySummary {
            body: b.body.to_string(),
            views: b.views,
            rms_before_px: b.rms_before_px,
            rms_after_px: b.rms_after_px,
            calibrated_tags: b.tags.len(),
            findings: b.findings.iter().map(ToString::to_string).collect(),
        })
        .collect()
}

impl Calibrated {
    /// The bite step: each stack's poses of the closed jaw in the calibration recording,
    /// mapped onto the scanned bite (here the true rest pose, as a bite scan would give it).
    /// One per stack (ours, then the reference's), `None` without a closed-jaw pose.
    pub(super) fn bite_step(
        &self,
        stacks: &mut Stacks,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Vec<Option<IntercuspationCalibration>>> {
        let scene = &self.scene;
        let printed = Marker::from_json(&scene.truth.true_marker.to_string())
            .context("calibration: the marker as printed in its ground truth")?;
        let markers = [self.nominal.clone(), self.cal.marker.clone(), printed];
        let mut trackers = new_trackers(&markers, &scene.truth)?;
        let mut closed: [Vec<Pose>; 2] = [Vec::new(), Vec::new()];
        // A bite is filmed as a clinician films the patient, from the front: the recording's
        // views at the face's level within 45° of straight ahead. (The oblique views see tags
        // that stay nominal, which would bias the mean.)
        let bite_frames: Vec<_> = scene
            .truth
            .frames
            .iter()
            .filter(|f| f.spec.view.elevation_deg == 0.0 && f.spec.view.azimuth_deg.abs() <= BITE_AZIMUTH_DEG)
            .collect();
        for (i, f) in bite_frames.iter().enumerate() {
            progress("tracking the closed jaw for the bite step", i, bite_frames.len());
            let r = stacks.frame(&mut trackers, &markers, &scene.dir.join(&f.file), &scene.truth, f.t)?;
            closed[0].extend(r.ours[1]);
            closed[1].extend(r.theirs.and_then(|t| t[1]));
        }
        let bite =
            scene.truth.frames.first().map(|f| f.maxilla_from_mandible).context("an empty calibration recording")?;
        let scanned =
            Registration { maxilla_scan_from_mandible_scan_at_intercuspation: bite, ..Registration::identity() };
        let mut bites = Vec::new();
        for samples in &closed {
            bites.push(calibrate_intercuspation(&scanned, samples).ok());
        }
        Ok(bites)
    }
}

/// What each stack's bite step corrected, for the report.
pub(super) fn bite_steps(bites: &[Option<IntercuspationCalibration>]) -> Vec<Option<BiteStep>> {
    bites
        .iter()
        .map(|b| {
            b.as_ref().map(|b| BiteStep {
                samples: b.samples,
                translation_mm: b.translation_mm,
                rotation_deg: b.rotation_deg,
                spread_mm: b.spread_mm,
            })
        })
        .collect()
}

/// What judging the experiments needs: the run's options, the calibrated markers and each
/// stack's bite step.
pub(super) struct Judge<'a> {
    pub(super) options: &'a Options,
    pub(super) calibrated: &'a Calibrated,
    pub(super) bites: &'a [Option<IntercuspationCalibration>],
}

impl Judge<'_> {
    /// With a stack's estimates for [nominal, calibrated, printed], the columns' estimates.
    fn expand(&self, estimates: PerMarker, stack: usize) -> Vec<Option<Pose>> {
        MarkerFile::ALL
            .map(|m| match m {
                MarkerFile::Nominal => estimates[0],
                MarkerFile::Calibrated => estimates[1],
                MarkerFile::CalibratedBite => self.bites[stack]
                    .as_ref()
                    .and_then(|b| estimates[1].map(|e| b.registration.maxilla_scan_from_mandible_scan(&e))),
                MarkerFile::Printed => estimates[2],
                // Not in `ALL`: the session columns come from `session::judge`.
                MarkerFile::FrontOnly | MarkerFile::Refined | MarkerFile::FrontOnlyRefined => None,
            })
            .to_vec()
    }

    /// Renders (or reads) one experiment, runs its frames through every column, and adds them
    /// to `records`; returns the session cases' summary.
    pub(super) fn scene(
        &self,
        kind: SceneKind,
        stacks: &mut Stacks,
        progress: &mut dyn FnMut(&str, usize, usize),
        records: &mut Vec<FrameRecord>,
    ) -> Result<session::SessionSummary> {
        let (options, cal, front) = (self.options, &self.calibrated.cal, &self.calibrated.front);
        let name = kind.name();
        let req = options.request(kind);
        let scene =
            frames::scene(&options.cache, &req, &mut |d, t| progress(&format!("rendering the {name} scene"), d, t))?;
        let printed = Marker::from_json(&scene.truth.true_marker.to_string())
            .with_context(|| format!("{name}: the marker as printed in its ground truth"))?;
        let markers = [self.calibrated.nominal.clone(), cal.marker.clone(), printed];
        let mut trackers = new_trackers(&markers, &scene.truth)?;
        let total = scene.truth.frames.len();
        let mut tracked = Vec::with_capacity(total);
        for (i, f) in scene.truth.frames.iter().enumerate() {
            progress(&format!("tracking the {name} scene"), i, total);
            tracked.push(stacks.frame(&mut trackers, &markers, &scene.dir.join(&f.file), &scene.truth, f.t)?);
        }
        // The session cases need the whole scene's detections before judging any frame.
        let detections: Vec<&[Detection]> = tracked.iter().map(|r| r.detections.as_slice()).collect();
        let (session, summary) = session::judge(
            kind,
            &detections,
            &scene.truth,
            [&front.marker, &cal.marker],
            &tracker_config(&scene.truth),
        )?;
        for ((f, r), extra) in scene.truth.frames.iter().zip(tracked).zip(session) {
            let mut estimates = self.expand(r.ours, 0);
            estimates.extend(extra);
            if let Some(theirs) = r.theirs {
                estimates.extend(self.expand(theirs, 1));
            }
            records.push(FrameRecord {
                scene: kind,
                index: f.index,
                t: f.t,
                view: f.spec.view,
                motion: f.spec.motion,
                truth: f.maxilla_from_mandible,
                estimates,
            });
        }
        progress(&format!("tracking the {name} scene"), total, total);
        Ok(summary)
    }
}
