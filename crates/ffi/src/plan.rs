//! The capture plan and the live guidance for the app ([`jawtrack_devices`]), converted once:
//! the app describes the camera as AVFoundation lists it ([`CaptureFormat`], the device's
//! `minimumFocusDistance`), gets a [`CapturePlanner`] holding the plan, shows its
//! [`PlanChoice`], applies it to the camera, asks it for each frame's [`CaptureGuidance`], and
//! hands it to the [`crate::Recorder`], which writes the plan into the recording's header.

use crate::error::invalid;
use crate::{Camera, JawTrackError};
use jawtrack_devices::{
    CameraFacts, CapturePlan, DeviceError, FormatFacts, GuidanceKind as Kind, Lens, PlanRequest, guide, optics, plan,
};
use jawtrack_marker::Marker;
use jawtrack_recording::CaptureRecord;
use std::sync::Arc;

/// One of the camera's formats, as AVFoundation lists it (`AVCaptureDevice.Format`).
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct CaptureFormat {
    /// Frame size (px), landscape as the sensor delivers it.
    pub width: u32,
    /// Frame height (px).
    pub height: u32,
    /// The highest frame rate it supports (frames/s).
    pub max_fps: f64,
    /// `videoFieldOfView`: the horizontal field of view at zoom 1 (°).
    pub fov_deg: f64,
    /// `secondaryNativeResolutionZoomFactors` (iOS 16): zooms with a native-resolution crop.
    pub native_zooms: Vec<f64>,
}

/// The plan as the app shows and applies it.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct PlanChoice {
    /// The format's frame size (px): choose the format of this size that runs at `fps`.
    pub width: u32,
    /// The format's frame height (px).
    pub height: u32,
    /// Frames per second.
    pub fps: u32,
    /// `videoZoomFactor` to set: 1, or the native crop.
    pub zoom: f64,
    /// Where to hold the phone and lock the focus (mm from the markers).
    pub distance_mm: f64,
    /// The band the markers stay sharp in once focus is locked there (mm).
    pub near_mm: f64,
    /// See `near_mm`.
    pub far_mm: f64,
    /// The nearest the lens focuses (mm).
    pub min_focus_mm: f64,
    /// The tags' cells at the distance (px).
    pub cell_px: f64,
    /// The plan in words ("hold the phone about 22 cm away: …").
    pub summary: String,
    /// What the user should know (figures assumed, a target out of reach).
    pub notes: Vec<String>,
}

/// What the guidance asks of the person holding the phone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum GuidanceKind {
    /// No marker in view.
    NoMarkers,
    /// Nearer than the lens focuses, or than the locked focus stays sharp.
    TooClose,
    /// The tags too small, or past where the locked focus stays sharp.
    TooFar,
    /// In range: hold still while focus locks (the app locks it now).
    HoldStill,
    /// The markers are blurred: out of focus.
    OutOfFocus,
    /// In focus, in range: record.
    Ready,
}

/// A frame's guidance.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct CaptureGuidance {
    /// What to do.
    pub kind: GuidanceKind,
    /// In words, for the status line.
    pub message: String,
}

impl From<DeviceError> for JawTrackError {
    fn from(e: DeviceError) -> Self {
        invalid(e.to_string())
    }
}

/// The capture plan for one camera of one phone.
#[derive(Debug, uniffi::Object)]
pub struct CapturePlanner {
    plan: CapturePlan,
}

#[uniffi::export]
impl CapturePlanner {
    /// The plan for filming chewing (`fps` frames/s) with `camera` of `model` (the hardware
    /// identifier, e.g. `iPhone16,1`), whose formats are `formats` and whose nearest focus the
    /// device reports as `reported_min_focus_mm` (AVFoundation's `minimumFocusDistance`; `None`
    /// or negative when unknown: the device table's, else 20 cm, is taken and the plan says so),
    /// for the marker file's JSON (`None`: the nominal 12.7 mm marker).
    #[uniffi::constructor]
    pub fn new(
        model: String,
        camera: Camera,
        reported_min_focus_mm: Option<f64>,
        formats: Vec<CaptureFormat>,
        fps: u32,
        marker_json: Option<String>,
    ) -> Result<Arc<Self>, JawTrackError> {
        let marker = match marker_json {
            Some(text) => Marker::from_json(&text)?,
            None => Marker::default(),
        };
        let tag_mm = marker
            .tags()
            .next()
            .map(|(_, t)| t.size)
            .ok_or_else(|| invalid("the marker file has no tags to plan for"))?;
        let lens = match camera {
            Camera::BackWide => Lens::Wide,
            Camera::BackTele => Lens::Tele,
            Camera::Front => Lens::Front,
        };
        let facts = CameraFacts {
            lens,
            optics: optics(&model, lens),
            reported_min_focus_mm: reported_min_focus_mm.filter(|m| m.is_finite() && *m > 0.0),
            formats: formats
                .into_iter()
                .map(|f| FormatFacts {
                    width: f.width,
                    height: f.height,
                    max_fps: f.max_fps,
                    fov_deg: f.fov_deg,
                    native_zooms: f.native_zooms,
                })
                .collect(),
        };
        let request = PlanRequest { fps: f64::from(fps), ..PlanRequest::chewing(tag_mm) };
        Ok(Arc::new(CapturePlanner { plan: plan(&[facts], &request)? }))
    }

    /// The plan.
    pub fn choice(&self) -> PlanChoice {
        let p = &self.plan;
        PlanChoice {
            width: p.width,
            height: p.height,
            fps: p.fps.round() as u32,
            zoom: p.zoom,
            distance_mm: p.distance_mm,
            near_mm: p.near_mm,
            far_mm: p.far_mm,
            min_focus_mm: p.min_focus_mm,
            cell_px: p.cell_px,
            summary: p.summary(),
            notes: p.notes.clone(),
        }
    }

    /// The guidance for a frame whose markers are `depth_mm` away ([`crate::FrameResult::depth_mm`]),
    /// with focus locked or not, and a body flagged `defocused` or not
    /// ([`crate::FrameResult::defocused`]).
    pub fn guide(&self, depth_mm: Option<f64>, focus_locked: bool, defocused: bool) -> CaptureGuidance {
        let g = guide(&self.plan, depth_mm, focus_locked, defocused);
        let kind = match g.kind {
            Kind::NoMarkers => GuidanceKind::NoMarkers,
            Kind::TooClose => GuidanceKind::TooClose,
            Kind::TooFar => GuidanceKind::TooFar,
            Kind::HoldStill => GuidanceKind::HoldStill,
            Kind::OutOfFocus => GuidanceKind::OutOfFocus,
            Kind::Ready => GuidanceKind::Ready,
        };
        CaptureGuidance { kind, message: g.message }
    }
}

impl CapturePlanner {
    /// The plan as the recording's header keeps it, with the lens position focus was locked at.
    pub(crate) fn record(&self, lens_position: Option<f64>) -> CaptureRecord {
        let p = &self.plan;
        CaptureRecord {
            plan: p.summary(),
            width: p.width,
            height: p.height,
            fps: p.fps,
            zoom: p.zoom,
            distance_mm: p.distance_mm,
            near_mm: p.near_mm,
            far_mm: p.far_mm,
            min_focus_mm: p.min_focus_mm,
            lens_position,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn formats() -> Vec<CaptureFormat> {
        [(1920, 1080), (3840, 2160)]
            .map(|(width, height)| CaptureFormat {
                width,
                height,
                max_fps: 60.0,
                fov_deg: 70.0,
                native_zooms: vec![2.0],
            })
            .to_vec()
    }

    #[test]
    fn a_pro_phone_is_planned_from_what_it_reports_and_guided_there() {
        let p = CapturePlanner::new("iPhone16,1".into(), Camera::BackWide, Some(200.0), formats(), 60, None)
            .expect("a plan");
        let c = p.choice();
        assert_eq!((c.width, c.height, c.fps, c.zoom, c.distance_mm), (1920, 1080, 60, 2.0, 220.0));
        assert!(c.notes.is_empty(), "the phone reported its nearest focus: {:?}", c.notes);
        assert!(c.summary.starts_with("hold the phone about 22 cm away"), "{}", c.summary);
        let g = p.guide(Some(120.0), false, true);
        assert_eq!(g.kind, GuidanceKind::TooClose);
        assert!(g.message.contains("this camera focuses from 20 cm"), "{}", g.message);
        assert_eq!(p.guide(Some(221.0), true, false).kind, GuidanceKind::Ready);
        let r = p.record(Some(0.81));
        assert_eq!((r.distance_mm, r.zoom, r.lens_position), (220.0, 2.0, Some(0.81)));
    }

    #[test]
    fn an_unknown_focus_limit_is_said_and_a_bad_camera_refused() {
        let p = CapturePlanner::new("iPhone99,9".into(), Camera::BackWide, Some(-1.0), formats(), 60, None)
            .expect("a plan");
        assert!(p.choice().notes.iter().any(|n| n.contains("not in the table")), "{:?}", p.choice().notes);
        let e = CapturePlanner::new("iPhone16,1".into(), Camera::BackWide, None, formats(), 240, None)
            .expect_err("no 240 fps format");
        assert!(e.to_string().contains("240 frames/s"), "{e}");
        let mut bad = formats();
        bad[0].fov_deg = f64::NAN;
        assert!(CapturePlanner::new("iPhone16,1".into(), Camera::BackWide, None, bad, 60, None).is_err());
    }
}
