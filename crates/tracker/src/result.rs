//! What the tracker makes of one frame, and that frame's line in a recording.

use crate::Flag;
use jawtrack_apriltag::tone::ToneSummary;
use jawtrack_apriltag::{Detection, Roi};
use jawtrack_marker::BodyKind;
use jawtrack_pose::Pose;
use jawtrack_recording::{BodyRecord, FrameRecord, TimingsRecord, ToneFitRecord, ToneRecord};
use nalgebra::Matrix6;

/// One body's pose in a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyResult {
    /// Maps the body's marker frame into the camera frame (mm).
    pub camera_from_body: Pose,
    /// Tags used, ascending.
    pub tags: Vec<u32>,
    /// Tags seen but dropped (inconsistent with the others, or a one-frame flicker).
    pub rejected_tags: Vec<u32>,
    /// RMS reprojection error (px).
    pub rms_px: f64,
    /// Covariance of (rotation vector in rad, translation in mm) of a left perturbation in the
    /// camera frame.
    pub covariance: Matrix6<f64>,
    /// How blurred its tags' edges are by the lens (σ, px; their [`Detection::blur_px`]'s median
    /// less what the motion predicted over the exposure adds: the `sharpness` module), when
    /// measured.
    pub blur_px: Option<f64>,
    /// The width (px) of its tags' cells (the median, each tag's along its longest side: its
    /// scale at its distance, however steeply it is seen).
    pub cell_px: f64,
}

impl BodyResult {
    /// Whether its blur exceeds `max_blur_per_cell` of its cells ([`Flag::Defocused`]).
    pub fn defocused(&self, max_blur_per_cell: f64) -> bool {
        self.blur_px.is_some_and(|b| b > max_blur_per_cell * self.cell_px)
    }
}

/// Time spent on a frame's stages (s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Timings {
    /// Tag detection (both searches when a region search missed a body).
    pub detection_s: f64,
    /// Both bodies' PnP, ambiguity and flicker checks, composition (and the dense refinement).
    pub pose_s: f64,
    /// Of `pose_s`, the dense refinement of both bodies ([`crate::PoseRefinement::Dense`]).
    pub refine_s: f64,
    /// Detection stage by stage, summed over the frame's searches.
    pub stages: jawtrack_apriltag::StageTimes,
    /// The tags were taken where the poses predicted them, without searching the region
    /// ([`crate::SearchConfig::predicted`]).
    pub predicted: bool,
}

/// What the tracker made of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameResult {
    /// The frame's time (s), as given.
    pub t: f64,
    /// The upper jaw's marker, if solved.
    pub maxilla: Option<BodyResult>,
    /// The lower jaw's marker, if solved.
    pub mandible: Option<BodyResult>,
    /// The mandible marker in the maxilla marker's frame, when both are solved (smoothed when
    /// the tracker has a smoother).
    pub maxilla_from_mandible: Option<Pose>,
    /// The lower tooth scan in the upper one, when both are solved and a registration is set.
    pub maxilla_scan_from_mandible_scan: Option<Pose>,
    /// Quality flags.
    pub flags: Vec<Flag>,
    /// The marker's tags detected (other tag36h11 ids are ignored).
    pub detections: Vec<Detection>,
    /// The region searched, or `None` for the whole frame.
    pub searched: Option<Roi>,
    /// Time per stage.
    pub timings: Timings,
    /// The tone curve the frame was read through and how it was found, on the first frame, and
    /// wherever it changed or a fit added to its evidence
    /// ([`jawtrack_apriltag::DetectorConfig::tone`]); `None` otherwise.
    pub tone: Option<ToneSummary>,
}

impl FrameResult {
    /// The result for a body.
    pub fn body(&self, kind: BodyKind) -> Option<&BodyResult> {
        match kind {
            BodyKind::Maxilla => self.maxilla.as_ref(),
            BodyKind::Mandible => self.mandible.as_ref(),
        }
    }

    /// The frame's line in a recording ([`jawtrack_recording`]): frame `index` of its source,
    /// read from `path` if it came from a file. The writer stamps the session.
    pub fn to_record(&self, index: usize, path: Option<&str>) -> FrameRecord {
        let body = |b: &BodyResult| BodyRecord {
            camera_from_body: b.camera_from_body,
            tags: b.tags.clone(),
            rejected_tags: b.rejected_tags.clone(),
            rms_px: b.rms_px,
            cov: Some(b.covariance.transpose().iter().copied().collect()),
            blur_px: b.blur_px,
            cell_px: Some(b.cell_px),
        };
        FrameRecord {
            frame: index as u64,
            session: None,
            path: path.map(str::to_owned),
            t: self.t,
            exposure_s: None,
            lens_position: None,
            maxilla: self.maxilla.as_ref().map(body),
            mandible: self.mandible.as_ref().map(body),
            maxilla_from_mandible: self.maxilla_from_mandible,
            maxilla_scan_from_mandible_scan: self.maxilla_scan_from_mandible_scan,
            flags: self.flags.iter().map(Flag::name).collect(),
            searched: self.searched.map(|s| [s.x, s.y, s.width, s.height]),
            timings_s: Some(TimingsRecord { detection: self.timings.detection_s, pose: self.timings.pose_s }),
            seq: None,
            received_unix_s: None,
            tone: self.tone.as_ref().map(tone_record),
        }
    }
}

/// A tone summary as the recording keeps it (and describes it: [`ToneRecord::describe`]).
pub fn tone_record(t: &ToneSummary) -> ToneRecord {
    ToneRecord {
        setting: t.setting,
        curve: t.curve,
        reason: t.reason,
        frames_fitted: t.frames_fitted,
        fit: t.pooled.map(|p| ToneFitRecord {
            gamma: p.gamma,
            gamma_spread: p.gamma_spread,
            fits: p.fits,
            sides: p.sides,
            misfit: p.misfit,
            srgb_misfit: p.srgb_misfit,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn a_record_carries_every_field_in_row_major_order() {
        let pose = Pose::from_axis_angle(Vector3::new(0.0, 0.1, 0.0), Vector3::new(1.0, 2.0, 100.0));
        let mut cov = Matrix6::zeros();
        cov[(0, 1)] = 7.0;
        let r = FrameResult {
            t: 0.5,
            maxilla: Some(BodyResult {
                camera_from_body: pose,
                tags: vec![0, 1],
                rejected_tags: vec![5],
                rms_px: 0.3,
                covariance: cov,
                blur_px: Some(0.4),
                cell_px: 9.5,
            }),
            mandible: None,
            maxilla_from_mandible: None,
            maxilla_scan_from_mandible_scan: None,
            flags: vec![Flag::Lost(BodyKind::Mandible)],
            detections: Vec::new(),
            searched: None,
            timings: Timings { detection_s: 0.004, pose_s: 0.0001, ..Timings::default() },
            tone: None,
        };
        let v: serde_json::Value = serde_json::from_str(&r.to_record(3, Some("f.png")).to_line()).expect("JSON");
        assert_eq!(v["frame"], 3);
        assert_eq!(v["path"], "f.png");
        assert_eq!(v["maxilla"]["camera_from_body"][3], 1.0);
        assert_eq!(v["maxilla"]["camera_from_body"][11], 100.0);
        assert_eq!(v["maxilla"]["cov"][1], 7.0, "row-major: (0, 1) is the second number");
        assert_eq!(v["maxilla"]["rejected_tags"][0], 5);
        assert!(v["mandible"].is_null() && v["maxilla_from_mandible"].is_null());
        assert!(v.get("maxilla_scan_from_mandible_scan").is_none());
        assert_eq!(v["flags"][0], "mandible:lost");
        assert_eq!(v["timings_s"]["detection"], 0.004);
    }
}
