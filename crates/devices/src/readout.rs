//! Each phone's published sensor readout (the rolling shutter's first row to last), which
//! AVFoundation does not report but the tracker needs to solve both jaws at the same instant
//! (`jawtrack_tracker::TrackerConfig::readout_s`). A readout measured with `jawtrack
//! calibrate-camera` beats any of them.

use crate::Lens;

/// A published readout time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Readout {
    /// First row to last (s).
    pub readout_s: f64,
    /// The phone, in words.
    pub phone: &'static str,
    /// Where the figure comes from, and how far to trust it.
    pub source: &'static str,
}

/// Where the figures were gathered (2026-11-25); the project's notes keep the details.
const SENSOR_TESTS: &str = "published sensor readout tests, gathered in the project's shared/NOTES.md (2026-11-25)";
const INCONSISTENT: &str = "published sensor readout tests, repeats inconsistent (shared/NOTES.md, 2026-11-25)";
const VIDEO_720P30: &str = "published sensor readout test, 720p30 video (shared/NOTES.md, 2026-11-25)";
const VIDEO_1080P30: &str = "published sensor readout test, 1080p30 video (shared/NOTES.md, 2026-11-25)";

/// (identifiers, lens, readout in ms, phone, source).
const TABLE: &[(&[&str], Lens, f64, &str, &str)] = &[
    (&["iPhone17,2"], Lens::Wide, 2.4, "iPhone 16 Pro Max", SENSOR_TESTS),
    (&["iPhone17,2"], Lens::UltraWide, 5.8, "iPhone 16 Pro Max", SENSOR_TESTS),
    (&["iPhone17,2"], Lens::Tele, 5.5, "iPhone 16 Pro Max", SENSOR_TESTS),
    (&["iPhone17,2"], Lens::Front, 10.5, "iPhone 16 Pro Max", SENSOR_TESTS),
    (&["iPhone16,2"], Lens::Wide, 5.1, "iPhone 15 Pro Max", SENSOR_TESTS),
    (&["iPhone16,2"], Lens::UltraWide, 5.1, "iPhone 15 Pro Max", SENSOR_TESTS),
    (&["iPhone16,2"], Lens::Tele, 5.1, "iPhone 15 Pro Max", SENSOR_TESTS),
    (&["iPhone15,2"], Lens::Wide, 9.0, "iPhone 14 Pro", INCONSISTENT),
    (&["iPhone8,1"], Lens::Wide, 15.0, "iPhone 6s", VIDEO_720P30),
    (&["iPhone5,1", "iPhone5,2"], Lens::Wide, 27.4, "iPhone 5", VIDEO_1080P30),
    (&["iPhone4,1"], Lens::Wide, 26.0, "iPhone 4S", VIDEO_1080P30),
];

/// The published readout of `model`'s `lens`, if any.
pub fn readout(model: &str, lens: Lens) -> Option<Readout> {
    let model = model.trim();
    TABLE.iter().find(|(ids, l, ..)| *l == lens && ids.contains(&model)).map(|&(_, _, ms, phone, source)| Readout {
        readout_s: ms / 1e3,
        phone,
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listed_phones_give_their_figure_in_seconds() {
        let r = readout("iPhone16,2", Lens::Wide).expect("15 Pro Max listed");
        assert!((r.readout_s - 0.0051).abs() < 1e-12, "{}", r.readout_s);
        assert_eq!(r.phone, "iPhone 15 Pro Max");
        let ms = |model: &str| readout(model, Lens::Wide).map(|r| (r.readout_s * 1e3 * 10.0).round() / 10.0);
        assert_eq!(ms(" iPhone17,2 "), Some(2.4));
        assert_eq!(ms("iPhone5,2"), Some(27.4));
    }

    #[test]
    fn unmeasured_phones_and_lenses_have_none() {
        assert_eq!(readout("iPhone14,2", Lens::Wide), None, "no figure for the iPhone 13 Pro");
        assert_eq!(readout("iPhone15,2", Lens::Front), None, "only the 14 Pro's main camera was measured");
        assert_eq!(readout("", Lens::Wide), None);
    }

    #[test]
    fn every_entry_is_a_plausible_readout() {
        for &(ids, _, ms, phone, source) in TABLE {
            assert!(!ids.is_empty() && !phone.is_empty() && !source.is_empty());
            assert!((1.0..40.0).contains(&ms), "{phone}: {ms} ms");
        }
    }
}
