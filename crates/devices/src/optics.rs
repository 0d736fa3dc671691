//! Each phone's lenses as they matter for filming the markers: focal length and f-number (the
//! entrance pupil, so the depth of field), the nearest the lens focuses, and whether its sensor
//! gives a native-resolution 2× crop (the 48 MP sensors: AVFoundation lists it in a format's
//! `secondaryNativeResolutionZoomFactors`).
//!
//! The nearest focus is the figure that decides where a clinician can hold the phone: current
//! Pro models cannot focus their wide camera nearer than about 20 cm. AVFoundation reports it
//! per device (`AVCaptureDevice.minimumFocusDistance`, iOS 15), and the app passes that in,
//! beating this table ([`crate::plan::CameraFacts`]); the table is for the CLI, for older iOS
//! and for judging recordings. Focal lengths and f-numbers are Apple's nominal ones as the
//! photos' metadata states them; the focus limits are app developers' readings (the research
//! notes of 2026-11-26 in the project's `shared/NOTES.md` list the sources).

use crate::Lens;

/// What a lens is, and where the figures come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LensOptics {
    /// The phone, in words ("iPhone 15 Pro"), or "an unlisted iPhone".
    pub phone: &'static str,
    /// Physical focal length (mm).
    pub focal_length_mm: f64,
    /// f-number.
    pub f_number: f64,
    /// The nearest the lens focuses (mm).
    pub min_focus_mm: f64,
    /// Whether `min_focus_mm` is a reported figure; false: nobody has reported this lens's,
    /// and [`CONSERVATIVE_MIN_FOCUS_MM`] stands in (the phone's own report beats it).
    pub min_focus_known: bool,
    /// Zoom factors at which the sensor delivers a native-resolution crop (empty: none).
    pub native_zooms: &'static [f64],
    /// Where the figures come from.
    pub source: &'static str,
    /// Whether the model and lens are in the table at all (false: every figure a default).
    pub listed: bool,
}

impl LensOptics {
    /// The entrance pupil's diameter (mm): focal length over f-number.
    pub fn pupil_mm(&self) -> f64 {
        self.focal_length_mm / self.f_number
    }
}

/// The nearest focus assumed for a lens nobody has reported (mm): current Pro wide cameras'
/// (about 20 cm), the farthest of any listed, so a plan made with it never asks a phone to
/// focus nearer than it can.
pub const CONSERVATIVE_MIN_FOCUS_MM: f64 = 200.0;

/// A 48 MP sensor's native 2× crop.
const NATIVE_2X: &[f64] = &[2.0];
const NONE: &[f64] = &[];

const EXIF: &str = "focal length and f-number: Apple's lens metadata in the phone's photos";
const WWDC21: &str = "focal length and f-number: photo metadata; nearest focus 12 cm (12 Pro) and 15 cm (12 Pro Max): Apple, WWDC 2021 session 10047";
const HALIDE_13: &str = "focal length and f-number: photo metadata; nearest focus 15 cm (Halide's readout), app developers report 16–19 cm (expo/expo #19472): the farther taken";
const HALIDE_14: &str =
    "focal length and f-number: photo metadata; nearest focus 20 cm (Halide's readout; 16–19 cm in expo/expo #19472)";
const LATER_PRO: &str = "focal length and f-number: photo metadata; nearest focus about 20 cm, as app developers report for Pro models after the 14 Pro (react-native-vision-camera #4194), not measured on this model";

/// (identifiers, lens, phone, focal mm, f-number, nearest focus mm or none known, native crops,
/// source).
type Row = (&'static [&'static str], Lens, &'static str, f64, f64, Option<f64>, &'static [f64], &'static str);

const TABLE: &[Row] = &[
    (&["iPhone13,3"], Lens::Wide, "iPhone 12 Pro", 4.2, 1.6, Some(120.0), NONE, WWDC21),
    (&["iPhone13,4"], Lens::Wide, "iPhone 12 Pro Max", 5.1, 1.6, Some(150.0), NONE, WWDC21),
    (&["iPhone14,5"], Lens::Wide, "iPhone 13", 5.1, 1.6, None, NONE, EXIF),
    (&["iPhone14,2"], Lens::Wide, "iPhone 13 Pro", 5.7, 1.5, Some(190.0), NONE, HALIDE_13),
    (&["iPhone14,3"], Lens::Wide, "iPhone 13 Pro Max", 5.7, 1.5, Some(190.0), NONE, HALIDE_13),
    (&["iPhone14,2", "iPhone14,3"], Lens::Tele, "iPhone 13 Pro", 9.0, 2.8, None, NONE, EXIF),
    (&["iPhone14,7"], Lens::Wide, "iPhone 14", 5.7, 1.5, None, NONE, EXIF),
    (&["iPhone15,2"], Lens::Wide, "iPhone 14 Pro", 6.86, 1.78, Some(200.0), NATIVE_2X, HALIDE_14),
    (&["iPhone15,3"], Lens::Wide, "iPhone 14 Pro Max", 6.86, 1.78, Some(200.0), NATIVE_2X, HALIDE_14),
    (&["iPhone15,2", "iPhone15,3"], Lens::Tele, "iPhone 14 Pro", 9.0, 2.8, None, NONE, EXIF),
    (&["iPhone15,4"], Lens::Wide, "iPhone 15", 5.96, 1.6, None, NATIVE_2X, EXIF),
    (&["iPhone15,5"], Lens::Wide, "iPhone 15 Plus", 5.96, 1.6, None, NATIVE_2X, EXIF),
    (&["iPhone16,1"], Lens::Wide, "iPhone 15 Pro", 6.765, 1.78, Some(200.0), NATIVE_2X, LATER_PRO),
    (&["iPhone16,2"], Lens::Wide, "iPhone 15 Pro Max", 6.765, 1.78, Some(200.0), NATIVE_2X, LATER_PRO),
    (&["iPhone16,1"], Lens::Tele, "iPhone 15 Pro", 9.0, 2.8, None, NONE, EXIF),
    (&["iPhone16,2"], Lens::Tele, "iPhone 15 Pro Max", 15.66, 2.8, None, NONE, EXIF),
    (&["iPhone17,3"], Lens::Wide, "iPhone 16", 5.96, 1.6, None, NATIVE_2X, EXIF),
    (&["iPhone17,4"], Lens::Wide, "iPhone 16 Plus", 5.96, 1.6, None, NATIVE_2X, EXIF),
    (&["iPhone17,1"], Lens::Wide, "iPhone 16 Pro", 6.765, 1.78, Some(200.0), NATIVE_2X, LATER_PRO),
    (&["iPhone17,2"], Lens::Wide, "iPhone 16 Pro Max", 6.765, 1.78, Some(200.0), NATIVE_2X, LATER_PRO),
    (&["iPhone17,1", "iPhone17,2"], Lens::Tele, "iPhone 16 Pro", 15.66, 2.8, None, NONE, EXIF),
    (&["iPhone18,3"], Lens::Wide, "iPhone 17", 5.96, 1.6, None, NATIVE_2X, EXIF),
    (&["iPhone18,1"], Lens::Wide, "iPhone 17 Pro", 6.765, 1.78, Some(200.0), NATIVE_2X, LATER_PRO),
    (&["iPhone18,2"], Lens::Wide, "iPhone 17 Pro Max", 6.765, 1.78, Some(200.0), NATIVE_2X, LATER_PRO),
];

/// The optics of `model`'s `lens`: the table's figures, or for a model or lens it does not list
/// the conservative defaults of a current Pro wide camera (6.8 mm f/1.78, the shallowest depth
/// of field; focusing from [`CONSERVATIVE_MIN_FOCUS_MM`]; no native crop), saying so.
///
/// # Examples
///
/// ```
/// use jawtrack_devices::{Lens, optics};
/// let o = optics("iPhone15,2", Lens::Wide);
/// assert_eq!((o.phone, o.min_focus_mm, o.native_zooms), ("iPhone 14 Pro", 200.0, &[2.0][..]));
/// assert!((o.pupil_mm() - 3.85).abs() < 0.01);
/// assert!(!optics("iPhone99,9", Lens::Wide).listed);
/// ```
pub fn optics(model: &str, lens: Lens) -> LensOptics {
    let model = model.trim();
    match TABLE.iter().find(|(ids, l, ..)| *l == lens && ids.contains(&model)) {
        Some(&(_, _, phone, focal, n, min_focus, native, source)) => LensOptics {
            phone,
            focal_length_mm: focal,
            f_number: n,
            min_focus_mm: min_focus.unwrap_or(CONSERVATIVE_MIN_FOCUS_MM),
            min_focus_known: min_focus.is_some(),
            native_zooms: native,
            source,
            listed: true,
        },
        None => LensOptics {
            phone: "an unlisted iPhone",
            focal_length_mm: 6.8,
            f_number: 1.78,
            min_focus_mm: CONSERVATIVE_MIN_FOCUS_MM,
            min_focus_known: false,
            native_zooms: NONE,
            source: "not in the table: a current Pro wide camera's figures assumed (6.8 mm f/1.78, focusing from 20 cm, no native crop)",
            listed: false,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pro_models_from_the_14_pro_focus_from_20_cm_and_crop_natively() {
        for id in ["iPhone15,2", "iPhone16,1", "iPhone17,2", "iPhone18,1"] {
            let o = optics(id, Lens::Wide);
            assert!(o.listed && o.min_focus_known, "{id}");
            assert_eq!((o.min_focus_mm, o.native_zooms), (200.0, NATIVE_2X), "{id}");
            assert!((3.7..3.9).contains(&o.pupil_mm()), "{id}: a 3.8 mm pupil, {}", o.pupil_mm());
        }
        let thirteen = optics("iPhone14,2", Lens::Wide);
        assert_eq!((thirteen.phone, thirteen.native_zooms), ("iPhone 13 Pro", NONE));
    }

    #[test]
    fn an_unreported_focus_limit_and_an_unknown_phone_are_conservative_and_say_so() {
        let fifteen = optics("iPhone15,4", Lens::Wide);
        assert!(fifteen.listed && !fifteen.min_focus_known);
        assert_eq!(fifteen.min_focus_mm, CONSERVATIVE_MIN_FOCUS_MM);
        let unknown = optics("iPhone99,1", Lens::Wide);
        assert!(!unknown.listed && unknown.source.contains("not in the table"));
        assert_eq!(optics("iPhone15,2", Lens::Front).phone, "an unlisted iPhone", "front cameras are not listed");
    }

    #[test]
    fn every_row_is_plausible_and_no_model_lens_is_listed_twice() {
        for (i, &(ids, lens, phone, focal, n, min_focus, _, source)) in TABLE.iter().enumerate() {
            assert!((1.0..20.0).contains(&focal) && (1.4..3.0).contains(&n), "{phone}");
            assert!(min_focus.is_none_or(|m| (50.0..1000.0).contains(&m)), "{phone}");
            assert!(!ids.is_empty() && !source.is_empty());
            for &(other, l, ..) in &TABLE[i + 1..] {
                assert!(l != lens || !other.iter().any(|id| ids.contains(id)), "{phone} listed twice");
            }
        }
    }
}
