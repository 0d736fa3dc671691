//! The capture plan: from what a phone's cameras can do, which camera, format and zoom to film
//! the markers with, and where to hold the phone.
//!
//! The rules, each from the capture benchmark (`jawtrack-bench accuracy`, "Capture";
//! `docs/accuracy.md`):
//! - **Distance.** The lens must focus on the markers, so the phone stands beyond its nearest
//!   focus, with a margin ([`FOCUS_MARGIN`], at least [`FOCUS_MARGIN_MM`]): a hand drifts, and a
//!   lens at its end stop hunts. That is the nearest, so the largest tags, the camera allows.
//! - **Tag size.** At that distance the tags' cells must be at least [`MIN_CELL_PX`] wide: below
//!   it the corners' noise and the steep tags' bias grow faster than the pose can stand.
//! - **Format and zoom.** Of the camera's formats that run at the frame rate asked and frame
//!   the face at that distance ([`PlanRequest::field_mm`]), at zoom 1 or at a native crop
//!   (never an upscaled digital zoom, which adds pixels but no detail), the fewest pixels that
//!   still give cells of [`MIN_CELL_PX`]: a 48 MP phone's native 2× crop at 1080p gives the
//!   same cells as 4K at 1× for a quarter of the pixels to search. With none large enough, the
//!   largest cells, and the plan says so.
//! - **Focus.** Locked at the distance before recording (so the focal length does not breathe
//!   during it); [`CapturePlan::near_mm`] and [`CapturePlan::far_mm`] bound where the markers'
//!   blur stays under [`GUIDANCE_BLUR_PER_CELL`] of a cell (the depth of field, relative to the
//!   cells: it does not depend on the zoom) and their cells over three quarters of the minimum.

use crate::optics::LensOptics;
use crate::{DeviceError, Lens};

/// How far beyond the nearest focus the phone stands: 10 % …
pub const FOCUS_MARGIN: f64 = 0.1;
/// … and at least this (mm).
pub const FOCUS_MARGIN_MM: f64 = 20.0;
/// The narrowest cells (px) a plan accepts at its distance.
pub const MIN_CELL_PX: f64 = 14.0;
/// The blur (σ over the cell's width) at the edges of the band the guidance keeps the phone in:
/// well inside the tracker's `defocused` flag.
pub const GUIDANCE_BLUR_PER_CELL: f64 = 0.1;

/// One of a camera's formats, as the phone lists it.
#[derive(Debug, Clone, PartialEq)]
pub struct FormatFacts {
    /// Frame size (px), landscape as the sensor delivers it.
    pub width: u32,
    /// Frame height (px).
    pub height: u32,
    /// The highest frame rate it runs at (frames/s).
    pub max_fps: f64,
    /// Horizontal field of view at zoom 1 (degrees).
    pub fov_deg: f64,
    /// Zoom factors with a native-resolution crop (AVFoundation's
    /// `secondaryNativeResolutionZoomFactors`; empty: none).
    pub native_zooms: Vec<f64>,
}

impl FormatFacts {
    /// The focal length (px) at `zoom`.
    pub fn fx_px(&self, zoom: f64) -> f64 {
        zoom * f64::from(self.width) / 2.0 / (self.fov_deg.to_radians() / 2.0).tan()
    }
}

/// What is known of one camera.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraFacts {
    /// Which.
    pub lens: Lens,
    /// Its optics (the table's, [`crate::optics()`]).
    pub optics: LensOptics,
    /// The nearest it focuses (mm), as the phone reports it; `None` takes the table's.
    pub reported_min_focus_mm: Option<f64>,
    /// Its formats.
    pub formats: Vec<FormatFacts>,
}

impl CameraFacts {
    /// The nearest focus (mm) the plan goes by: the phone's report, else the table's.
    pub fn min_focus_mm(&self) -> f64 {
        self.reported_min_focus_mm.filter(|m| m.is_finite() && *m > 0.0).unwrap_or(self.optics.min_focus_mm)
    }

    /// The usual formats of a phone's wide camera (1080p and 4K at 60 frames/s, 70° across),
    /// with the native crops its optics list: for the CLI, which has no phone to ask.
    pub fn typical(lens: Lens, optics: LensOptics) -> Self {
        let format = |width, height| FormatFacts {
            width,
            height,
            max_fps: 60.0,
            fov_deg: 70.0,
            native_zooms: optics.native_zooms.to_vec(),
        };
        CameraFacts { lens, optics, reported_min_focus_mm: None, formats: vec![format(1920, 1080), format(3840, 2160)] }
    }
}

/// What the plan must deliver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanRequest {
    /// The tags' black square (mm): the marker file's tag size.
    pub tag_mm: f64,
    /// Frames per second (60 for chewing).
    pub fps: f64,
    /// The scene the frame must hold at the distance (mm): along its long side (the head's
    /// height, with the phone upright: both markers and the jaw open) and its short side.
    pub field_mm: [f64; 2],
}

impl PlanRequest {
    /// The rig's markers (tags of `tag_mm`) filmed chewing: 60 frames/s, a field of 120 × 70 mm
    /// (both markers 44 mm apart, a 40 mm opening, a 6 mm swing either side).
    pub fn chewing(tag_mm: f64) -> Self {
        PlanRequest { tag_mm, fps: 60.0, field_mm: [120.0, 70.0] }
    }
}

/// How to film.
#[derive(Debug, Clone, PartialEq)]
pub struct CapturePlan {
    /// The camera.
    pub lens: Lens,
    /// The format's frame size (px).
    pub width: u32,
    /// The format's frame height (px).
    pub height: u32,
    /// Frames per second.
    pub fps: f64,
    /// The zoom: 1, or a native crop.
    pub zoom: f64,
    /// The focal length (px) at that zoom, as the format's field of view gives it.
    pub fx_px: f64,
    /// Where to hold the phone, and lock the focus (mm from the markers).
    pub distance_mm: f64,
    /// The nearest and farthest the markers may be once focus is locked there (mm).
    pub near_mm: f64,
    /// See [`CapturePlan::near_mm`].
    pub far_mm: f64,
    /// The nearest the lens focuses (mm), and whether the phone reported it.
    pub min_focus_mm: f64,
    /// Whether [`CapturePlan::min_focus_mm`] came from the phone itself.
    pub min_focus_reported: bool,
    /// The tags' cells at the distance (px).
    pub cell_px: f64,
    /// What the user should know: figures assumed, a target the camera cannot reach.
    pub notes: Vec<String>,
}

impl CapturePlan {
    /// The plan in words, for the app's screen and the CLI.
    pub fn summary(&self) -> String {
        format!(
            "hold the phone about {} cm away: {} camera, {}×{} at {} frames/s{}, focus locked at {} cm (it focuses from {} cm); tags' cells {:.0} px",
            cm(self.distance_mm),
            lens_name(self.lens),
            self.width,
            self.height,
            self.fps,
            if self.zoom > 1.0 { format!(", {}× native crop", self.zoom) } else { String::new() },
            cm(self.distance_mm),
            cm(self.min_focus_mm),
            self.cell_px
        )
    }
}

/// A distance in whole centimetres, for people.
pub(crate) fn cm(mm: f64) -> String {
    format!("{:.0}", mm / 10.0)
}

/// A lens's name for people.
pub(crate) fn lens_name(lens: Lens) -> &'static str {
    match lens {
        Lens::Wide => "wide",
        Lens::UltraWide => "ultra-wide",
        Lens::Tele => "telephoto",
        Lens::Front => "front",
    }
}

/// The plan for filming with one of `cameras` (see the module doc for the rules).
///
/// # Examples
///
/// ```
/// use jawtrack_devices::{CameraFacts, Lens, PlanRequest, optics, plan};
/// // An iPhone 15 Pro's wide camera, which focuses from 20 cm and crops 2× natively.
/// let wide = CameraFacts::typical(Lens::Wide, optics("iPhone16,1", Lens::Wide));
/// let p = plan(&[wide], &PlanRequest::chewing(10.6)).expect("a plan");
/// assert_eq!((p.width, p.zoom, p.distance_mm), (1920, 2.0, 220.0));
/// assert!(p.summary().starts_with("hold the phone about 22 cm away"));
/// ```
pub fn plan(cameras: &[CameraFacts], request: &PlanRequest) -> Result<CapturePlan, DeviceError> {
    let r = request;
    if !(r.tag_mm.is_finite() && r.tag_mm > 0.0) {
        return Err(DeviceError::Invalid(format!("the tag size must be a positive number of mm, got {}", r.tag_mm)));
    }
    if !(r.fps.is_finite() && r.fps > 0.0) {
        return Err(DeviceError::Invalid(format!("the frame rate must be positive, got {}", r.fps)));
    }
    if !r.field_mm.iter().all(|f| f.is_finite() && *f >= 0.0) {
        return Err(DeviceError::Invalid(format!("the field must be non-negative mm, got {:?}", r.field_mm)));
    }
    let cell_mm = r.tag_mm / 8.0;
    // Every (camera, format, zoom) that runs fast enough: its distance, cells and pixels.
    let mut candidates = Vec::new();
    for camera in cameras {
        let min_focus = camera.min_focus_mm();
        let focus_distance = (min_focus * (1.0 + FOCUS_MARGIN)).max(min_focus + FOCUS_MARGIN_MM);
        for format in &camera.formats {
            if !(format.max_fps + 1e-6 >= r.fps && format.width > 0 && format.height > 0) {
                continue;
            }
            if !(format.fov_deg.is_finite() && format.fov_deg > 1.0 && format.fov_deg < 179.0) {
                return Err(DeviceError::Invalid(format!(
                    "a field of view must be within 1–179°, got {}",
                    format.fov_deg
                )));
            }
            let zooms = std::iter::once(1.0).chain(format.native_zooms.iter().copied().filter(|z| *z > 1.0));
            for zoom in zooms {
                let fx = format.fx_px(zoom);
                // Nearest distance at which the frame holds the field.
                let framing =
                    (r.field_mm[0] * fx / f64::from(format.width)).max(r.field_mm[1] * fx / f64::from(format.height));
                let distance = focus_distance.max(framing).round();
                let cell = fx * cell_mm / distance;
                let pixels = u64::from(format.width) * u64::from(format.height);
                candidates.push((camera, format, zoom, fx, distance, cell, pixels));
            }
        }
    }
    let enough = |c: &&(&CameraFacts, &FormatFacts, f64, f64, f64, f64, u64)| c.5 >= MIN_CELL_PX;
    // The fewest pixels with cells large enough (then the larger cells); else the largest cells.
    let chosen = candidates
        .iter()
        .filter(enough)
        .min_by(|a, b| a.6.cmp(&b.6).then(b.5.total_cmp(&a.5)))
        .or_else(|| candidates.iter().max_by(|a, b| a.5.total_cmp(&b.5)));
    let Some(&(camera, format, zoom, fx, distance, cell, _)) = chosen else {
        return Err(DeviceError::NoFormat(format!(
            "no camera format runs at {} frames/s: choose a lower frame rate",
            r.fps
        )));
    };
    let o = &camera.optics;
    let mut notes = Vec::new();
    if cell < MIN_CELL_PX {
        notes.push(format!(
            "the tags' cells are only {cell:.0} px at {} cm with this camera (at least {MIN_CELL_PX:.0} px measure to the \
             plan's accuracy): expect larger errors, or use a phone with a 4K or 2× native-crop format",
            cm(distance)
        ));
    }
    if camera.reported_min_focus_mm.is_none() {
        notes.push(if o.min_focus_known {
            format!("nearest focus {} cm from the device table ({})", cm(o.min_focus_mm), o.phone)
        } else {
            format!(
                "nearest focus not known for {}: {} cm assumed (the phone's own report replaces it)",
                o.phone,
                cm(o.min_focus_mm)
            )
        });
    }
    if !o.listed {
        notes.push(o.source.to_owned());
    }
    // The depth band: blur σ over the cell is 2·A·|z − d| / ((d − f)·tag), the same at any zoom.
    let depth = GUIDANCE_BLUR_PER_CELL * (distance - o.focal_length_mm) * r.tag_mm / (2.0 * o.pupil_mm());
    // Cells shrink as 1/z: three quarters of the minimum at most this far.
    let small = fx * cell_mm / (0.75 * MIN_CELL_PX.min(cell));
    Ok(CapturePlan {
        lens: camera.lens,
        width: format.width,
        height: format.height,
        fps: r.fps,
        zoom,
        fx_px: fx,
        distance_mm: distance,
        near_mm: (distance - depth).max(camera.min_focus_mm().min(distance)).min(distance),
        far_mm: (distance + depth).min(small.max(distance)),
        min_focus_mm: camera.min_focus_mm(),
        min_focus_reported: camera.reported_min_focus_mm.is_some(),
        cell_px: cell,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics;

    fn wide(model: &str) -> CameraFacts {
        CameraFacts::typical(Lens::Wide, optics(model, Lens::Wide))
    }

    /// The default marker's tag (mm).
    const TAG: f64 = 10.61;

    #[test]
    fn a_pro_phone_films_from_22_cm_with_its_native_crop_at_1080p() {
        let p = plan(&[wide("iPhone17,1")], &PlanRequest::chewing(TAG)).expect("plan");
        assert_eq!((p.lens, p.width, p.height, p.zoom, p.distance_mm), (Lens::Wide, 1920, 1080, 2.0, 220.0));
        // 70° across 1920 px: fx 1371 at 1×, 2742 at 2×; cells 2742 · 1.326 / 220 = 16.5 px.
        assert!((p.fx_px - 2742.0).abs() < 1.0 && (p.cell_px - 16.5).abs() < 0.1, "{p:?}");
        // The band: 0.1 · (220 − 6.765) · 10.61 / (2 · 3.80) = 29.8 mm either side, no nearer
        // than the lens focuses.
        assert!((p.far_mm - 249.8).abs() < 0.5 && (p.near_mm - 200.0).abs() < 1e-9, "{} {}", p.near_mm, p.far_mm);
        assert_eq!(p.notes, ["nearest focus 20 cm from the device table (iPhone 16 Pro)"]);
    }

    #[test]
    fn without_a_native_crop_4k_keeps_the_cells_large_enough() {
        // A 13 Pro: no 48 MP sensor, focusing from 19 cm.
        let p = plan(&[wide("iPhone14,2")], &PlanRequest::chewing(TAG)).expect("plan");
        assert_eq!((p.width, p.zoom, p.distance_mm), (3840, 1.0, 210.0));
        assert!(p.cell_px >= MIN_CELL_PX, "{p:?}");
    }

    #[test]
    fn the_phones_own_report_beats_the_table_and_a_closer_focus_brings_it_closer() {
        let mut camera = wide("iPhone15,4");
        assert!(plan(&[camera.clone()], &PlanRequest::chewing(TAG)).expect("plan").notes[0].contains("not known"));
        camera.reported_min_focus_mm = Some(100.0);
        let p = plan(&[camera], &PlanRequest::chewing(TAG)).expect("plan");
        // 110 mm would cut the face (120 mm across 1920 px at fx 1371·2 needs 171 mm): the
        // framing sets the distance.
        assert!(p.min_focus_reported && p.notes.is_empty(), "{p:?}");
        assert!(p.distance_mm >= 120.0 && p.distance_mm < 200.0, "{p:?}");
    }

    #[test]
    fn a_camera_that_cannot_reach_the_cells_says_so_and_bad_requests_are_refused() {
        let mut camera = wide("iPhone14,2");
        camera.formats.retain(|f| f.width == 1920);
        let p = plan(&[camera.clone()], &PlanRequest::chewing(TAG)).expect("plan");
        assert!(p.cell_px < MIN_CELL_PX && p.notes[0].contains("only"), "{p:?}");
        assert!(plan(&[camera.clone()], &PlanRequest { fps: 240.0, ..PlanRequest::chewing(TAG) }).is_err());
        assert!(plan(&[camera], &PlanRequest::chewing(f64::NAN)).is_err());
    }
}
