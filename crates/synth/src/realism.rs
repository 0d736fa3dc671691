//! Realism settings: everything that makes a rendered frame look like a phone's, each with a
//! default and drawn from the scene's seed so that a frame can be made again exactly.

use jawtrack_pose::RollingShutter;
use serde::{Deserialize, Serialize};

/// The shape a point out of focus spreads into.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pupil {
    /// A Gaussian with the disc's variance (σ = a quarter of the blur circle's diameter): smooth,
    /// kind to edge fits.
    #[default]
    Gaussian,
    /// The uniform disc a real circular aperture makes, as wide as the blur circle: edges
    /// blurred into straight ramps with hard ends.
    Disc,
}

/// How a frame departs from the ideal pinhole image. `Realism::default()` is a plausible iPhone
/// frame of the rig at 80–120 mm; `Realism::clean()` switches every effect off;
/// [`Realism::phone_wide`] is a current Pro iPhone's wide camera as it really is (a disc pupil
/// of 3.8 mm, focus that breathes, a lens that cannot focus nearer than 20 cm).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Realism {
    /// Lens f-number for defocus (0 = a pinhole, no defocus).
    pub f_number: f64,
    /// Physical focal length (mm); with the f-number it sets the aperture.
    pub focal_length_mm: f64,
    /// Distance the lens is focused at (mm along the optical axis): a lens locked there whatever
    /// the subject; `None` focuses on the median depth of the tags facing the camera, as
    /// autofocus would (no nearer than [`Realism::min_focus_distance_mm`]).
    pub focus_distance_mm: Option<f64>,
    /// The nearest the autofocus can focus (mm): a subject nearer than this is rendered with the
    /// lens stuck here, as on a phone held too close. `None`: no limit.
    pub min_focus_distance_mm: Option<f64>,
    /// The shape of the defocus blur.
    pub pupil: Pupil,
    /// Focus breathing: focusing at u moves the lens f²/(u − f) from the sensor, enlarging the
    /// image by u/(u − f) (3.5 % at 200 mm for 6.8 mm). The intrinsics given are then those of
    /// the lens focused at infinity, and the frames' (the truth's) are scaled by that factor.
    /// Needs a locked focus ([`Realism::focus_distance_mm`]).
    pub focus_breathing: bool,
    /// A centred crop of the sensor delivered at the frame's size (2 is the 48 MP sensors'
    /// native 2× crop): the focal lengths in pixels are multiplied by it and each pixel gathers
    /// 1/zoom² of the light, so [`Realism::full_well_e`] is per pixel at zoom 1.
    pub zoom: f64,
    /// The lens's own blur in focus (diffraction, aberrations): σ of a Gaussian on the sensor
    /// (µm), in pixels σ · fx / (1000 · focal length). 0: none.
    pub optics_sigma_um: f64,
    /// Exposure time (s) for motion blur; 0 renders an instant.
    pub exposure_s: f64,
    /// Most sub-frames averaged for motion blur with a global shutter (enough for ≤ 1 px
    /// motion between them). A rolling shutter places its rows' instants by motion alone.
    pub max_subframes: u32,
    /// Rolling-shutter readout (s): the time from the first to the last row of the delivered
    /// buffer; 0 is a global shutter. Row r is exposed centred at [`Realism::row_time`].
    pub readout_s: f64,
    /// Electrons collected at white paper in full light (shot noise); 0 = no noise at all.
    pub full_well_e: f64,
    /// Read noise (electrons, standard deviation).
    pub read_noise_e: f64,
    /// Encode with the sRGB transfer curve (as phone frames are); false writes linear light.
    pub gamma: bool,
    /// Fraction of light lost at the image corners (cos⁴-like fall-off).
    pub vignetting: f64,
    /// Largest fractional change of illumination across the image (a lighting gradient in a
    /// random direction).
    pub lighting_gradient: f64,
    /// RMS in-plane displacement of each printed tag on its face (mm); the marker file does
    /// not know it, the ground truth records it.
    pub print_error_mm: f64,
    /// Standard deviation of each printed tag's in-plane rotation (degrees).
    pub print_error_deg: f64,
    /// Chance that a frame has an occluder (a finger or lip) in front of part of a marker.
    pub occluder_probability: f64,
    /// Chance that a frame has a specular glare patch on a marker face.
    pub glare_probability: f64,
    /// Number of clutter shapes on the background, a third of them dark squares that are not
    /// tags.
    pub clutter: u32,
}

impl Default for Realism {
    fn default() -> Self {
        Realism {
            f_number: 1.8,
            focal_length_mm: 5.7,
            focus_distance_mm: None,
            exposure_s: 1.0 / 120.0,
            max_subframes: 24,
            readout_s: 0.0,
            // After the phone's own denoising: about 1.3 DN of noise at mid-grey.
            full_well_e: 8000.0,
            read_noise_e: 3.0,
            gamma: true,
            vignetting: 0.25,
            lighting_gradient: 0.2,
            print_error_mm: 0.2,
            print_error_deg: 0.5,
            occluder_probability: 0.1,
            glare_probability: 0.15,
            clutter: 40,
            min_focus_distance_mm: None,
            pupil: Pupil::Gaussian,
            focus_breathing: false,
            zoom: 1.0,
            optics_sigma_um: 0.0,
        }
    }
}

impl Realism {
    /// Every effect off: exact geometry, linear light, no noise, the nominal marker.
    pub fn clean() -> Self {
        Realism {
            f_number: 0.0,
            focus_distance_mm: None,
            exposure_s: 0.0,
            full_well_e: 0.0,
            read_noise_e: 0.0,
            gamma: false,
            vignetting: 0.0,
            lighting_gradient: 0.0,
            print_error_mm: 0.0,
            print_error_deg: 0.0,
            occluder_probability: 0.0,
            glare_probability: 0.0,
            clutter: 0,
            ..Realism::default()
        }
    }

    /// A current Pro iPhone's wide camera (iPhone 14 Pro to 16 Pro: 6.8 mm f/1.78, a 3.8 mm
    /// entrance pupil): a disc pupil, focus that breathes, locked at `focus_mm`, and `zoom` (1,
    /// or 2 for the native crop); the lens's own blur 0.7 µm (diffraction at f/1.78 is 0.4 µm,
    /// aberrations add to it). Everything else as [`Realism::default`]. Give it the intrinsics
    /// of the lens focused at infinity, at zoom 1.
    pub fn phone_wide(focus_mm: f64, zoom: f64) -> Self {
        Realism {
            f_number: 1.78,
            focal_length_mm: 6.8,
            focus_distance_mm: Some(focus_mm),
            pupil: Pupil::Disc,
            focus_breathing: true,
            zoom,
            optics_sigma_um: 0.7,
            ..Realism::default()
        }
    }

    /// The factor the image is enlarged by with the lens focused at `focus_mm` rather than at
    /// infinity: the lens sits f²/(u − f) further from the sensor, so u/(u − f) (1 without
    /// focus breathing, or without a focus distance).
    pub fn breathing(&self, focus_mm: Option<f64>) -> f64 {
        match focus_mm {
            Some(u) if self.focus_breathing && u > self.focal_length_mm => u / (u - self.focal_length_mm),
            _ => 1.0,
        }
    }

    /// Centre of the exposure of image row `y` (0-based, fractional rows allowed) in a frame of
    /// `height` rows whose centre row is exposed at `t`: the readout sweeps the rows top to
    /// bottom, row 0 at `t − readout_s/2` and the last row at `t + readout_s/2` (the tracker's
    /// own rule, [`RollingShutter::offset_s`], so renders and tracking agree by construction).
    pub fn row_time(&self, t: f64, y: f64, height: u32) -> f64 {
        let shutter = RollingShutter::new(self.readout_s, height as usize).unwrap_or_else(|_| RollingShutter::global());
        t + shutter.offset_s(y)
    }

    /// Checks the numbers, naming the first bad one.
    pub fn validate(&self) -> Result<(), String> {
        let fields = [
            ("f_number", self.f_number),
            ("focal_length_mm", self.focal_length_mm),
            ("exposure_s", self.exposure_s),
            ("readout_s", self.readout_s),
            ("full_well_e", self.full_well_e),
            ("read_noise_e", self.read_noise_e),
            ("vignetting", self.vignetting),
            ("lighting_gradient", self.lighting_gradient),
            ("print_error_mm", self.print_error_mm),
            ("print_error_deg", self.print_error_deg),
            ("occluder_probability", self.occluder_probability),
            ("glare_probability", self.glare_probability),
            ("optics_sigma_um", self.optics_sigma_um),
        ];
        for (name, v) in fields {
            if !v.is_finite() || v < 0.0 {
                return Err(format!("realism.{name} must be a non-negative number, got {v}"));
            }
        }
        for (name, v) in [
            ("vignetting", self.vignetting),
            ("occluder_probability", self.occluder_probability),
            ("glare_probability", self.glare_probability),
        ] {
            if v > 1.0 {
                return Err(format!("realism.{name} must be at most 1, got {v}"));
            }
        }
        if self.focal_length_mm == 0.0 && self.f_number > 0.0 {
            return Err("realism.focal_length_mm must be positive when f_number is set".into());
        }
        if let Some(d) = self.focus_distance_mm
            && (!d.is_finite() || d <= self.focal_length_mm)
        {
            return Err(format!("realism.focus_distance_mm must exceed the focal length, got {d}"));
        }
        if let Some(d) = self.min_focus_distance_mm
            && (!d.is_finite() || d <= self.focal_length_mm)
        {
            return Err(format!("realism.min_focus_distance_mm must exceed the focal length, got {d}"));
        }
        if self.focus_breathing && self.focus_distance_mm.is_none() {
            return Err("realism.focus_breathing needs a locked focus: set realism.focus_distance_mm".into());
        }
        if !(self.zoom.is_finite() && (1.0..=10.0).contains(&self.zoom)) {
            return Err(format!("realism.zoom is a sensor crop from 1 to 10, got {}", self.zoom));
        }
        if self.readout_s >= 1.0 {
            return Err(format!("realism.readout_s must be under 1 s, got {}", self.readout_s));
        }
        if self.max_subframes == 0 {
            return Err("realism.max_subframes must be at least 1".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_read_top_to_bottom_over_the_readout() {
        let r = Realism { readout_s: 0.010, ..Realism::default() };
        assert_eq!(r.row_time(2.0, 0.0, 1080), 2.0 - 0.005);
        assert_eq!(r.row_time(2.0, 539.5, 1080), 2.0);
        assert!((r.row_time(2.0, 1079.0, 1080) - 2.005).abs() < 1e-15);
        // A global shutter exposes every row at the frame's time.
        assert_eq!(Realism::default().row_time(2.0, 17.0, 1080), 2.0);
        assert_eq!(Realism::default().readout_s, 0.0, "renders stay global-shutter by default");
        // Settings files written before the readout existed read as a global shutter.
        let old: Realism = serde_json::from_str(r#"{"exposure_s": 0.004}"#).expect("reads");
        assert_eq!((old.exposure_s, old.readout_s), (0.004, 0.0));
    }
}
