//! How the camera's timing is set and known: the readout the tracker is told (a calibrated
//! value, else the device table's figure, else none), and the exposure cap that keeps moving
//! tags sharp while the scene is bright enough.
//!
//! The trade-off the cap makes: a short exposure removes the smear a chewing jaw leaves (at
//! 100 mm/s and 8 ms the mandible marker moves 0.8 mm, about 10 px at 120 mm), at the price of
//! a higher ISO and so more noise. Measured on rendered chewing (`docs/accuracy.md`,
//! "Chewing"), 2 ms leaves 0.02–0.05 mm mean error where 8 ms leaves 0.06–0.09 mm with the
//! blur-aware edge fit; noise costs far less than that on the detector's corners. So the cap is
//! 2 ms by default, and is lifted step by step (to at most four times the setting) only while
//! the sensor's gain is at its limit, i.e. when the room is too dark for it.

use crate::{Camera, JawTrackError};
use jawtrack_devices::{Lens, readout};

/// Where the readout given to the tracker comes from.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct ReadoutChoice {
    /// The readout to put in [`crate::Settings::readout_s`] (s; 0 when unknown).
    pub readout_s: f64,
    /// Whether a figure was found (calibrated or published); false: the tracker solves each
    /// frame as one instant, and fast motion is measured less well.
    pub known: bool,
    /// Where it comes from, in words for the settings screen.
    pub source: String,
}

/// The readout for `model` (the hardware identifier, e.g. `iPhone16,2`) filming with
/// `camera`: `calibrated_readout_s` when given (from `jawtrack calibrate-camera`), else the
/// published figure, else 0 with a note saying how to measure it.
#[uniffi::export]
pub fn readout_for(
    model: String,
    camera: Camera,
    calibrated_readout_s: Option<f64>,
) -> Result<ReadoutChoice, JawTrackError> {
    if let Some(r) = calibrated_readout_s {
        check_readout(r, "calibrated_readout_s")?;
        return Ok(ReadoutChoice {
            readout_s: r,
            known: true,
            source: format!("calibrated: {:.2} ms (jawtrack calibrate-camera)", r * 1e3),
        });
    }
    let lens = match camera {
        Camera::BackWide => Lens::Wide,
        Camera::BackTele => Lens::Tele,
        Camera::Front => Lens::Front,
    };
    Ok(match readout(&model, lens) {
        Some(r) => ReadoutChoice {
            readout_s: r.readout_s,
            known: true,
            source: format!("{}: {:.1} ms, {}", r.phone, r.readout_s * 1e3, r.source),
        },
        None => ReadoutChoice {
            readout_s: 0.0,
            known: false,
            source: format!(
                "no published readout for {model} ({camera:?}): fast motion is measured as if the \
                 frame were one instant; measure it with `jawtrack calibrate-camera` and enter it in Settings"
            ),
        },
    })
}

/// Checks a readout time (s): 0 (a global shutter) up to 100 ms, beyond any phone's.
pub(crate) fn check_readout(r: f64, setting: &str) -> Result<(), JawTrackError> {
    if !(r.is_finite() && (0.0..=0.1).contains(&r)) {
        return Err(JawTrackError::setting(
            setting,
            format!(
                "{} must be within 0–100 ms (0: global shutter), got {} ms",
                if setting == "readout_s" { "readout" } else { "calibrated readout" },
                r * 1e3
            ),
        ));
    }
    Ok(())
}

/// The sensor's gain (ISO) as a fraction of its maximum above which the scene is too dark for
/// the cap, and below which a lifted cap is lowered again. The gap is wider than the factor 2 a
/// step changes the gain by, so one step never undoes the last.
const DARK: f64 = 0.95;
const BRIGHT: f64 = 0.4;
/// How far above the setting the cap may be lifted.
const MAX_LIFT: f64 = 4.0;

/// The exposure cap to apply next (s; 0: none, the camera's own automatic exposure), given the
/// setting `requested_s` (0: none), the cap in force `current_s`, and the sensor's gain `iso`
/// out of `max_iso` for the last frame. The cap doubles (up to 4× the setting) while the gain
/// is at its limit, and halves back (down to the setting) once it is well below.
#[uniffi::export]
pub fn next_exposure_cap(requested_s: f64, current_s: f64, iso: f64, max_iso: f64) -> f64 {
    if !(requested_s.is_finite() && requested_s > 0.0) {
        return 0.0;
    }
    let current = if current_s.is_finite() && current_s > 0.0 {
        current_s.clamp(requested_s, requested_s * MAX_LIFT)
    } else {
        requested_s
    };
    if !(iso.is_finite() && max_iso.is_finite() && max_iso > 0.0) {
        return current;
    }
    let gain = iso / max_iso;
    if gain >= DARK {
        (current * 2.0).min(requested_s * MAX_LIFT)
    } else if gain < BRIGHT {
        (current / 2.0).max(requested_s)
    } else {
        current
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calibrated_beats_the_table_which_beats_nothing() {
        let c = readout_for("iPhone16,2".into(), Camera::BackWide, Some(0.0062)).expect("valid");
        assert_eq!((c.readout_s, c.known), (0.0062, true));
        assert!(c.source.starts_with("calibrated: 6.20 ms"), "{}", c.source);
        let t = readout_for("iPhone16,2".into(), Camera::BackWide, None).expect("valid");
        assert!(t.known && (t.readout_s - 0.0051).abs() < 1e-12, "{t:?}");
        assert!(t.source.contains("iPhone 15 Pro Max"), "{}", t.source);
        let u = readout_for("iPhone14,2".into(), Camera::BackWide, None).expect("valid");
        assert_eq!((u.readout_s, u.known), (0.0, false));
        assert!(u.source.contains("calibrate-camera"), "{}", u.source);
        let e = readout_for("x".into(), Camera::Front, Some(-1e-3)).expect_err("negative").to_string();
        assert!(e.starts_with("calibrated readout must be within"), "{e}");
        assert!(readout_for("x".into(), Camera::Front, Some(f64::NAN)).is_err());
    }

    #[test]
    fn the_cap_lifts_only_in_the_dark_and_comes_back() {
        let cap = |current, iso| next_exposure_cap(0.002, current, iso, 3200.0);
        assert_eq!(cap(0.0, 800.0), 0.002, "starts at the setting");
        assert_eq!(cap(0.002, 3200.0), 0.004, "gain at its limit: lifted");
        assert_eq!(cap(0.004, 3100.0), 0.008);
        assert_eq!(cap(0.008, 3200.0), 0.008, "at most 4× the setting");
        assert_eq!(cap(0.004, 1700.0), 0.004, "the gain a lift leaves does not lower it again");
        assert_eq!(cap(0.008, 1000.0), 0.004, "bright again: back down");
        assert_eq!(cap(0.002, 100.0), 0.002, "never below the setting");
        assert_eq!(cap(0.004, f64::NAN), 0.004, "no gain known: unchanged");
        assert_eq!(next_exposure_cap(0.0, 0.004, 3200.0, 3200.0), 0.0, "no cap asked");
    }
}
