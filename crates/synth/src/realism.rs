//! Realism settings: everything that makes a rendered frame look like a phone's, each with a
//! default and drawn from the scene's seed so that a frame can be made again exactly.

use jawtrack_pose::RollingShutter;
use jawtrack_tone::ToneCurve;
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

/// An unsharp mask on the encoded values, as phones sharpen after their tone curve:
/// e' = e + amount·(e − G∗e), clipped to 0–1, G a Gaussian of σ = `radius_px`. Edges gain the
/// halos (overshoot either side) that real phone frames show and a linear-light edge fit must
/// survive.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sharpen {
    /// How much of the detail (e − G∗e) is added back (0–4; phones use about 0.5–1.5).
    pub amount: f64,
    /// σ of the Gaussian the detail is taken against (px, 0.3–5): the halo's width.
    pub radius_px: f64,
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
    /// Most sub-frames averaged for motion blur with a global shutter: enough for ≤ ¼ px of
    /// motion between two up to this many (64: a 16 px smear), coarser beyond. A rolling
    /// shutter places its rows' instants by motion alone.
    pub max_subframes: u32,
    /// Rolling-shutter readout (s): the time from the first to the last row of the delivered
    /// buffer; 0 is a global shutter. Row r is exposed centred at [`Realism::row_time`].
    pub readout_s: f64,
    /// Electrons collected at white paper in full light (shot noise); 0 = no noise at all.
    pub full_well_e: f64,
    /// Read noise (electrons, standard deviation).
    pub read_noise_e: f64,
    /// Encode with the tone curve [`Realism::tone`] (as phone frames are); false writes linear
    /// light.
    pub gamma: bool,
    /// The curve frames are encoded with when [`Realism::gamma`] is set: sRGB by default (and in
    /// every settings file written before phones' own curves were rendered), or a phone's
    /// steeper, flatter or S-shaped curve, so the detector's decoding can be tested against it.
    pub tone: ToneCurve,
    /// Sharpening of the encoded values before they are rounded to 8 bits; `None`: none.
    pub sharpen: Option<Sharpen>,
    /// Strength (0–1; 0 is off) of a local tone map in linear light before encoding, as phones'
    /// "smart HDR" video applies: L' = L·(m/B)^strength, B the radiance blurred over a sixteenth
    /// of the image's diagonal and m its mean. Dark regions are lifted and bright ones lowered,
    /// so the curve a frame was encoded with varies (smoothly) across it.
    pub local_tone_map: f64,
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
            max_subframes: 64,
            readout_s: 0.0,
            // After the phone's own denoising: about 1.3 DN of noise at mid-grey.
            full_well_e: 8000.0,
            read_noise_e: 3.0,
            gamma: true,
            tone: ToneCurve::Srgb,
            sharpen: None,
            local_tone_map: 0.0,
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

    /// The electrons a pixel of the delivered frame holds when full: [`Realism::full_well_e`]
    /// over the [`Realism::zoom`]'s crop, whose pixel gathers 1/zoom² of a whole-sensor pixel's
    /// light. The renderer's shot noise, and any bound on what a frame can tell, start here.
    pub fn pixel_full_well_e(&self) -> f64 {
        self.full_well_e / (self.zoom * self.zoom)
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

    /// The curve frames are encoded with: [`Realism::tone`] when [`Realism::gamma`] is set,
    /// `None` (linear light) otherwise.
    pub fn encoding(&self) -> Option<ToneCurve> {
        self.gamma.then_some(self.tone)
    }

    /// Checks the numbers, naming the first bad one.
    pub fn validate(&self) -> Result<(), String> {
        self.validate_optics()?;
        self.validate_processing()
    }

    /// Checks the lens, sensor and scene settings.
    fn validate_optics(&self) -> Result<(), String> {
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

    /// Checks the phone's processing: the tone curve, the sharpening and the local tone map.
    fn validate_processing(&self) -> Result<(), String> {
        self.tone.validate().map_err(|e| format!("realism.tone: {e}"))?;
        if !self.gamma && self.tone != ToneCurve::Srgb {
            return Err(format!(
                "realism.tone is {} but realism.gamma is false: a linear frame has no tone curve \
                 (set realism.gamma to true, or leave realism.tone at srgb)",
                self.tone
            ));
        }
        if let Some(Sharpen { amount, radius_px }) = self.sharpen {
            if !(amount.is_finite() && (0.0..=4.0).contains(&amount)) {
                return Err(format!("realism.sharpen.amount must be from 0 to 4, got {amount}"));
            }
            if !(radius_px.is_finite() && (0.3..=5.0).contains(&radius_px)) {
                return Err(format!("realism.sharpen.radius_px must be from 0.3 to 5 px, got {radius_px}"));
            }
        }
        if !(self.local_tone_map.is_finite() && (0.0..=1.0).contains(&self.local_tone_map)) {
            return Err(format!("realism.local_tone_map is a strength from 0 to 1, got {}", self.local_tone_map));
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

    #[test]
    fn settings_from_before_tone_curves_load_as_srgb_without_processing() {
        let old: Realism = serde_json::from_str(r#"{"exposure_s": 0.004, "gamma": true}"#).expect("reads");
        assert_eq!((old.tone, old.sharpen, old.local_tone_map), (ToneCurve::Srgb, None, 0.0));
        assert_eq!(old.encoding(), Some(ToneCurve::Srgb));
        assert_eq!(Realism::clean().encoding(), None, "clean frames are linear light");
        let phone: Realism = serde_json::from_str(
            r#"{"tone": "s-curve:2.2:0.5", "sharpen": {"amount": 1.2, "radius_px": 1.5}, "local_tone_map": 0.4}"#,
        )
        .expect("reads");
        assert_eq!(phone.encoding(), Some(ToneCurve::SCurve { gamma: 2.2, contrast: 0.5 }));
        assert_eq!(phone.sharpen, Some(Sharpen { amount: 1.2, radius_px: 1.5 }));
        assert_eq!(phone.local_tone_map, 0.4);
        assert_eq!(phone.validate(), Ok(()));
        let back: Realism = serde_json::from_str(&serde_json::to_string(&phone).expect("writes")).expect("reads");
        assert_eq!(back, phone);
        for bad in [r#"{"tone": "gamma:22"}"#, r#"{"sharpen": {"amount": 1, "radius_px": 1, "sigma": 2}}"#] {
            assert!(serde_json::from_str::<Realism>(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn validation_names_each_bad_processing_field() {
        let sharpen =
            |amount, radius_px| Realism { sharpen: Some(Sharpen { amount, radius_px }), ..Realism::default() };
        let cases = [
            (Realism { gamma: false, tone: ToneCurve::Gamma { gamma: 1.8 }, ..Realism::default() }, "realism.gamma"),
            (Realism { tone: ToneCurve::Gamma { gamma: 22.0 }, ..Realism::default() }, "realism.tone: "),
            (sharpen(-0.1, 1.0), "realism.sharpen.amount"),
            (sharpen(4.5, 1.0), "realism.sharpen.amount"),
            (sharpen(f64::NAN, 1.0), "realism.sharpen.amount"),
            (sharpen(1.0, 0.2), "realism.sharpen.radius_px"),
            (sharpen(1.0, 5.5), "realism.sharpen.radius_px"),
            (sharpen(1.0, f64::INFINITY), "realism.sharpen.radius_px"),
            (Realism { local_tone_map: -0.1, ..Realism::default() }, "realism.local_tone_map"),
            (Realism { local_tone_map: 1.5, ..Realism::default() }, "realism.local_tone_map"),
            (Realism { local_tone_map: f64::NAN, ..Realism::default() }, "realism.local_tone_map"),
        ];
        for (r, says) in cases {
            let e = r.validate().expect_err(says);
            assert!(e.contains(says), "{says}: {e}");
        }
        // A linear frame names both fields; with sRGB (the default) it is fine.
        let e = cases[0].0.validate().expect_err("linear with a curve");
        assert!(e.contains("realism.tone is gamma:1.8"), "{e}");
        assert_eq!(Realism::clean().validate(), Ok(()));
        assert_eq!(sharpen(4.0, 0.3).validate(), Ok(()), "the ends of the ranges are allowed");
        assert_eq!(sharpen(0.0, 5.0).validate(), Ok(()));
    }
}
