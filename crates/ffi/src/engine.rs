//! One tracker behind both doors: runs a frame, turns the tracker's result into the records
//! the app reads (with the overlay already in the preview's coordinates), keeps the frame's
//! detections for a marker calibration ([`TrackedView`]), offers the tracker's intercuspation
//! step, and keeps each result's line of the recording schema (the tracker's one conversion)
//! for the recorder and the link, which take it here rather than back from the app.

use crate::error::invalid;
use crate::{Intrinsics, JawTrackError, Settings};
use jawtrack_apriltag::ImageView;
use jawtrack_calibration::SeenTag;
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::{CameraIntrinsics, Pose};
use jawtrack_recording::{BiteRecord, FrameRecord};
use jawtrack_tracker::{Flag, Tracker, TrackerConfig};
use nalgebra::{Point3, Vector3};
use std::collections::VecDeque;

/// Length of the axes drawn on each body (mm).
const AXIS_MM: f64 = 10.0;

/// One body in a frame's result (the tracker's `BodyResult`, for the app).
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct BodyResult {
    /// Maps the body's marker frame into the camera frame: 4×4 row-major, mm.
    pub camera_from_body: Vec<f64>,
    /// 6×6 covariance of (rotation vector \[rad\], translation \[mm\]), row-major.
    pub covariance: Vec<f64>,
    /// Tags used.
    pub tags: Vec<u32>,
    /// Tags seen but dropped.
    pub rejected_tags: Vec<u32>,
    /// RMS reprojection error (px).
    pub rms_px: f64,
    /// How blurred its tags' edges are (σ, px), when measured: the lens's defocus.
    #[uniffi(default)]
    pub blur_px: Option<f64>,
    /// The width (px) of its tags' cells, what its blur is judged against (`defocused` beyond 0.14
    /// of it).
    #[uniffi(default)]
    pub cell_px: f64,
}

/// A detected tag for the overlay.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct TagOverlay {
    /// tag36h11 id.
    pub id: u32,
    /// `"maxilla"` or `"mandible"`.
    pub body: String,
    /// Corners (bottom-left, bottom-right, top-right, top-left of the upright tag) as x, y
    /// pairs in capture-device coordinates: (0, 0) the frame's top-left corner, (1, 1) its
    /// bottom-right, as `AVCaptureVideoPreviewLayer.layerPointConverted(fromCaptureDevicePoint:)`
    /// takes them.
    pub corners: Vec<f64>,
    /// The tag's centre, same coordinates.
    pub center: Vec<f64>,
}

/// A body's axes for the overlay, in capture-device coordinates.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct AxisOverlay {
    /// `"maxilla"` or `"mandible"`.
    pub body: String,
    /// The body's origin (the dodecahedron's centre).
    pub origin: Vec<f64>,
    /// The ends of its x, y and z axes (10 mm long): six numbers, x then y for each.
    pub ends: Vec<f64>,
}

/// What the overlay draws over the preview.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct Overlay {
    /// The tags detected.
    pub tags: Vec<TagOverlay>,
    /// Each tracked body's axes (those in front of the camera).
    pub axes: Vec<AxisOverlay>,
}

/// What the tracker made of one frame.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct FrameResult {
    /// The frame's index since the tracker started (or was reset).
    pub frame: u64,
    /// The frame's time (s), as given.
    pub t: f64,
    /// How long the sensor exposed the frame (s), when the camera said; recorded with it.
    pub exposure_s: Option<f64>,
    /// The upper jaw's marker, if solved.
    pub maxilla: Option<BodyResult>,
    /// The lower jaw's marker, if solved.
    pub mandible: Option<BodyResult>,
    /// The mandible marker in the maxilla marker's frame, 4×4 row-major.
    pub maxilla_from_mandible: Option<Vec<f64>>,
    /// The lower scan in the upper scan (after the intercuspation step), 4×4 row-major.
    pub maxilla_scan_from_mandible_scan: Option<Vec<f64>>,
    /// Quality flags by name, e.g. `mandible:single_tag`.
    pub flags: Vec<String>,
    /// How far the markers are from the camera (mm): the mean depth of the bodies solved, for
    /// the capture guidance ([`crate::CapturePlanner::guide`]).
    #[uniffi(default)]
    pub depth_mm: Option<f64>,
    /// Whether a body is flagged `defocused` (its tags blurred beyond what its pose can stand):
    /// the frame gives no jaw pose, and the guidance says the phone is out of focus.
    #[uniffi(default)]
    pub defocused: bool,
    /// The lens position the camera reported for the frame ([`crate::Tracker::set_lens_position`]).
    #[uniffi(default)]
    pub lens_position: Option<f64>,
    /// The overlay's geometry.
    pub overlay: Overlay,
    /// Tag detection time (ms).
    pub detection_ms: f64,
    /// Pose time (ms).
    pub pose_ms: f64,
    /// Frames per second over the last second of frame times (0 until there are two).
    pub fps: f64,
}

/// The intercuspation step's outcome: the bite accepted (by the tracker's one rule,
/// `jawtrack_registration::bite`) and the registration correction it made.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct IntercuspationResult {
    /// The time of the last frame of the held bite (s, the frames' clock).
    pub t: f64,
    /// The rest position: the mean mandible marker in the maxilla marker's frame, 4×4
    /// row-major, mm. [`crate::Recorder::append_bite`] writes it into the recording.
    pub maxilla_from_mandible: Vec<f64>,
    /// Frames averaged.
    pub frames: u32,
    /// Time they spanned (s).
    pub span_s: f64,
    /// How far the correction moved the lower scan's origin (mm).
    pub translation_mm: f64,
    /// How far it turned the lower scan (°).
    pub rotation_deg: f64,
    /// How far the frames spread about their mean (mm): how still the patient held the bite.
    pub spread_mm: f64,
    /// How far they turned about their mean (°).
    pub spread_deg: f64,
}

impl IntercuspationResult {
    /// The bite as a recording line.
    pub(crate) fn record(&self) -> Result<BiteRecord, JawTrackError> {
        if !(self.t.is_finite() && self.span_s.is_finite() && self.spread_mm.is_finite() && self.spread_deg.is_finite())
        {
            return Err(invalid("bite: its time and spreads must be numbers"));
        }
        Ok(BiteRecord {
            session: None,
            t: self.t,
            maxilla_from_mandible: pose_of(&self.maxilla_from_mandible, "bite maxilla_from_mandible")?,
            frames: u64::from(self.frames),
            span_s: self.span_s,
            spread_mm: self.spread_mm,
            spread_deg: self.spread_deg,
        })
    }
}

/// The last frame tracked as a marker calibration takes it ([`crate::Calibrator`]): the
/// marker's tags in pixels, the camera, and the bodies' poses.
#[derive(Debug, Clone)]
pub(crate) struct TrackedView {
    /// The frame's camera.
    pub(crate) camera: CameraIntrinsics,
    /// The marker's tags detected, corners in pixels.
    pub(crate) tags: Vec<SeenTag>,
    /// The bodies the tracker solved, with their camera-from-body poses.
    pub(crate) poses: Vec<(BodyKind, Pose)>,
}

/// A tracker with what the app needs around it.
pub(crate) struct Engine {
    tracker: Tracker,
    pub(crate) settings: Settings,
    frame: u64,
    pub(crate) last: Option<FrameResult>,
    /// The last frame's line of the recording schema, `None` when the last frame failed.
    pub(crate) last_record: Option<FrameRecord>,
    /// The last frame's detections, `None` when the last frame could not be tracked.
    pub(crate) view: Option<TrackedView>,
    times: VecDeque<f64>,
    /// Luma of BGRA frames, reused between frames.
    pub(crate) luma: Vec<u8>,
    /// The lens position the camera last reported, stamped on each frame.
    pub(crate) lens_position: Option<f64>,
}

fn kind_name(kind: BodyKind) -> String {
    kind.name().to_owned()
}

impl Engine {
    pub(crate) fn new(marker: Marker, settings: Settings) -> Result<Self, JawTrackError> {
        marker.require_both_bodies()?;
        let tracker = Tracker::new(marker, settings.tracker_config()?)?;
        Ok(Engine {
            tracker,
            settings,
            frame: 0,
            last: None,
            last_record: None,
            view: None,
            times: VecDeque::new(),
            luma: Vec::new(),
            lens_position: None,
        })
    }

    /// Keeps the bodies' motion, the registration and the recent jaw poses: a settings change
    /// mid-session must not make the next lone tag ambiguous.
    pub(crate) fn update_settings(&mut self, settings: Settings) -> Result<(), JawTrackError> {
        self.tracker.set_config(settings.tracker_config()?)?;
        self.settings = settings;
        Ok(())
    }

    pub(crate) fn reset(&mut self) {
        self.tracker.reset();
        self.tracker.set_registration(None);
        self.frame = 0;
        self.last = None;
        self.last_record = None;
        self.view = None;
        self.times.clear();
    }

    pub(crate) fn marker_json(&self) -> String {
        self.tracker.marker().to_json()
    }

    pub(crate) fn track(
        &mut self,
        view: &ImageView<'_>,
        intrinsics: &Intrinsics,
        t: f64,
        exposure_s: Option<f64>,
    ) -> Result<FrameResult, JawTrackError> {
        // A frame that fails leaves no view and no result: a calibration must not take the one
        // before twice, nor a recording or the link send it again.
        self.view = None;
        self.last = None;
        self.last_record = None;
        if !t.is_finite() {
            return Err(JawTrackError::frame(format!("frame time {t} is not a number")));
        }
        if let Some(e) = exposure_s.filter(|e| !(e.is_finite() && *e > 0.0 && *e < 1.0)) {
            return Err(JawTrackError::frame(format!(
                "exposure {e} s is not an exposure time: give the frame's exposure in seconds (0–1 s), or none"
            )));
        }
        let camera = intrinsics.camera()?;
        // The frame's exposure, with the tracked velocity, says whether its tags are smeared.
        if let Some(e) = exposure_s
            && e != self.tracker.config().exposure_s
        {
            self.tracker.set_config(TrackerConfig { exposure_s: e, ..*self.tracker.config() })?;
        }
        let r = self.tracker.track(view, &camera, t)?;
        self.times.push_back(t);
        while self.times.len() > 2 && self.times.front().is_some_and(|&first| t - first > 1.0) {
            self.times.pop_front();
        }
        let fps = match (self.times.front(), self.times.len()) {
            (Some(&first), n) if n >= 2 && t > first => (n - 1) as f64 / (t - first),
            _ => 0.0,
        };
        let (w, h) = (view.width() as f64, view.height() as f64);
        let device = |p: [f64; 2]| vec![(p[0] + 0.5) / w, (p[1] + 0.5) / h];
        let tags = r
            .detections
            .iter()
            .filter_map(|d| {
                let (kind, _) = self.tracker.marker().find_tag(d.id)?;
                Some(TagOverlay {
                    id: d.id,
                    body: kind_name(kind),
                    corners: d.corners.iter().flat_map(|&c| device(c)).collect(),
                    center: device(d.center),
                })
            })
            .collect();
        let axes = BodyKind::ALL
            .iter()
            .filter_map(|&kind| {
                let b = r.body(kind)?;
                let project = |p: Vector3<f64>| {
                    camera.project(&b.camera_from_body.transform_point(&Point3::from(p))).map(|q| device([q.x, q.y]))
                };
                let origin = project(Vector3::zeros())?;
                let ends: Option<Vec<Vec<f64>>> =
                    [Vector3::x(), Vector3::y(), Vector3::z()].iter().map(|a| project(a * AXIS_MM)).collect();
                Some(AxisOverlay { body: kind_name(kind), origin, ends: ends?.concat() })
            })
            .collect();
        let body = |b: &jawtrack_tracker::BodyResult| BodyResult {
            camera_from_body: b.camera_from_body.to_row_major().to_vec(),
            covariance: b.covariance.transpose().iter().copied().collect(),
            tags: b.tags.clone(),
            rejected_tags: b.rejected_tags.clone(),
            rms_px: b.rms_px,
            blur_px: b.blur_px,
            cell_px: b.cell_px,
        };
        let result = FrameResult {
            frame: self.frame,
            t,
            exposure_s,
            maxilla: r.maxilla.as_ref().map(body),
            mandible: r.mandible.as_ref().map(body),
            maxilla_from_mandible: r.maxilla_from_mandible.map(|p| p.to_row_major().to_vec()),
            maxilla_scan_from_mandible_scan: r.maxilla_scan_from_mandible_scan.map(|p| p.to_row_major().to_vec()),
            flags: r.flags.iter().map(Flag::name).collect(),
            depth_mm: {
                let z: Vec<f64> = [&r.maxilla, &r.mandible]
                    .into_iter()
                    .flatten()
                    .map(|b| b.camera_from_body.translation().z)
                    .collect();
                (!z.is_empty()).then(|| z.iter().sum::<f64>() / z.len() as f64)
            },
            defocused: r.flags.iter().any(|f| matches!(f, Flag::Defocused(_))),
            lens_position: self.lens_position,
            overlay: Overlay { tags, axes },
            detection_ms: r.timings.detection_s * 1e3,
            pose_ms: r.timings.pose_s * 1e3,
            fps,
        };
        let mut record = r.to_record(0, None);
        record.frame = self.frame;
        record.exposure_s = exposure_s;
        record.lens_position = self.lens_position;
        self.last_record = Some(record);
        self.frame += 1;
        self.view = Some(TrackedView {
            camera,
            tags: r.detections.iter().map(|d| SeenTag { id: d.id, corners: d.corners }).collect(),
            poses: BodyKind::ALL.iter().filter_map(|&k| Some((k, r.body(k)?.camera_from_body))).collect(),
        });
        self.last = Some(result.clone());
        Ok(result)
    }

    pub(crate) fn calibrate_intercuspation(&mut self) -> Result<IntercuspationResult, JawTrackError> {
        let (bite, cal) = self.tracker.calibrate_intercuspation()?;
        Ok(IntercuspationResult {
            t: bite.t,
            maxilla_from_mandible: bite.maxilla_from_mandible.to_row_major().to_vec(),
            frames: bite.frames as u32,
            span_s: bite.span_s,
            translation_mm: cal.translation_mm,
            rotation_deg: cal.rotation_deg,
            spread_mm: bite.spread_mm,
            spread_deg: bite.spread_deg,
        })
    }
}

fn pose_of(m: &[f64], what: &str) -> Result<Pose, JawTrackError> {
    let m: [f64; 16] =
        m.try_into().map_err(|_| invalid(format!("{what}: a 4×4 matrix has 16 numbers, got {}", m.len())))?;
    Ok(Pose::from_row_major(&m, what)?)
}

/// The camera from AVFoundation's intrinsic matrix (`matrix_float3x3`, column-major: fx at
/// \[0\], fy at \[4\], the principal point at \[6\] and \[7\]) given for `reference` dimensions,
/// scaled to the delivered frame. AVFoundation's pixel coordinates start at the top-left
/// corner of the top-left pixel; ours at its centre, hence the half pixel.
#[uniffi::export]
pub fn intrinsics_from_camera_matrix(
    matrix: Vec<f32>,
    reference_width: u32,
    reference_height: u32,
    width: u32,
    height: u32,
) -> Result<Intrinsics, JawTrackError> {
    if matrix.len() != 9 {
        return Err(JawTrackError::InvalidIntrinsics {
            message: format!("the intrinsic matrix has 9 numbers, got {}", matrix.len()),
        });
    }
    if reference_width == 0 || reference_height == 0 || width == 0 || height == 0 {
        return Err(JawTrackError::InvalidIntrinsics {
            message: format!(
                "frame sizes must be positive: reference {reference_width}×{reference_height}, frame {width}×{height}"
            ),
        });
    }
    let (sx, sy) = (f64::from(width) / f64::from(reference_width), f64::from(height) / f64::from(reference_height));
    let m = |i: usize| f64::from(matrix[i]);
    let i = Intrinsics { fx: m(0) * sx, fy: m(4) * sy, cx: m(6) * sx - 0.5, cy: m(7) * sy - 0.5, k1: 0.0, k2: 0.0 };
    i.camera()?;
    Ok(i)
}

impl From<&CameraIntrinsics> for Intrinsics {
    fn from(c: &CameraIntrinsics) -> Self {
        Intrinsics { fx: c.fx, fy: c.fy, cx: c.cx, cy: c.cy, k1: c.k1, k2: c.k2 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::default_settings;
    use jawtrack_apriltag::Detection;
    use nalgebra::UnitQuaternion;

    /// Noise-free detections of `ids` seen through `camera_from_body`.
    fn detections(marker: &Marker, ids: &[u32], camera_from_body: &Pose, camera: &CameraIntrinsics) -> Vec<Detection> {
        ids.iter()
            .map(|&id| {
                let (_, tag) = marker.find_tag(id).expect("marker tag");
                let corners = tag.corners.map(|c| {
                    let p = camera.project(&camera_from_body.transform_point(&Point3::from(c))).expect("in front");
                    [p.x, p.y]
                });
                let center =
                    [corners.iter().map(|c| c[0]).sum::<f64>() / 4.0, corners.iter().map(|c| c[1]).sum::<f64>() / 4.0];
                Detection {
                    id,
                    hamming: 0,
                    decision_margin: 100.0,
                    center,
                    corners,
                    homography: [0.0; 9],
                    blur_px: None,
                }
            })
            .collect()
    }

    #[test]
    fn new_settings_keep_the_motion() {
        let marker = Marker::default();
        let camera = CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5);
        let facing = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI)
            * UnitQuaternion::from_scaled_axis(Vector3::new(0.25, 0.15, 0.0));
        let maxilla = Pose::from_parts(facing, Vector3::new(2.0, -22.0, 100.0));
        let mandible = Pose::from_parts(
            facing * UnitQuaternion::from_scaled_axis(Vector3::new(0.2, 0.0, 0.0)),
            Vector3::new(1.0, 22.0, 104.0),
        );
        let frame = |mandible_ids: &[u32]| {
            let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
            d.extend(detections(&marker, mandible_ids, &mandible, &camera));
            d
        };
        // Flags of a lone mandible tag's frame after two frames with three tags per body, with
        // the settings changed in between or not (`None`).
        let lone_frame = |lone: u32, new: Option<Settings>| {
            let mut engine = Engine::new(marker.clone(), default_settings()).expect("engine");
            for i in 0..2 {
                engine.tracker.solve(frame(&[12, 13, 14]), &camera, f64::from(i) / 30.0, 1080);
            }
            if let Some(settings) = new {
                engine.update_settings(settings).expect("valid settings");
            }
            engine.tracker.solve(frame(&[lone]), &camera, 2.0 / 30.0, 1080).flags
        };
        // A tag whose pose alone has a mirror solution: ambiguous on a fresh tracker.
        let ambiguous = Flag::Ambiguous(BodyKind::Mandible);
        let lone = (12..24)
            .find(|&id| {
                let mut engine = Engine::new(marker.clone(), default_settings()).expect("engine");
                engine.tracker.solve(frame(&[id]), &camera, 0.0, 1080).flags.contains(&ambiguous)
            })
            .expect("some single tag is ambiguous");
        let kept = lone_frame(lone, None);
        assert!(!kept.contains(&ambiguous), "{kept:?}");
        let changed = Settings { decimate: 1.0, threads: 2, region_search: false, smooth: true, ..default_settings() };
        assert_eq!(lone_frame(lone, Some(changed)), kept, "the settings change lost the motion");
    }

    #[test]
    fn each_frames_exposure_is_told_to_the_tracker_and_recorded() {
        let mut engine = Engine::new(Marker::default(), default_settings()).expect("engine");
        let blank = vec![128u8; 64 * 48];
        let view = ImageView::new(&blank, 64, 48, 64).expect("view");
        let intrinsics = Intrinsics { fx: 60.0, fy: 60.0, cx: 31.5, cy: 23.5, k1: 0.0, k2: 0.0 };
        let default_exposure = engine.tracker.config().exposure_s;
        let r = engine.track(&view, &intrinsics, 0.0, None).expect("tracked");
        assert_eq!((r.exposure_s, engine.tracker.config().exposure_s), (None, default_exposure));
        let r = engine.track(&view, &intrinsics, 0.1, Some(0.002)).expect("tracked");
        assert_eq!((r.exposure_s, engine.tracker.config().exposure_s), (Some(0.002), 0.002));
        let record = engine.last_record.as_ref().expect("a record");
        assert_eq!((record.frame, record.exposure_s), (r.frame, Some(0.002)));
        let e = engine.track(&view, &intrinsics, 0.2, Some(-1.0)).expect_err("refused").to_string();
        assert!(e.contains("exposure"), "{e}");
        assert!(engine.last.is_none() && engine.last_record.is_none(), "a failed frame leaves nothing to record");
    }
}
