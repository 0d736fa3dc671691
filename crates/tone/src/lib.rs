//! Tone curves: how a camera turns the linear light on its sensor into the 8-bit values it
//! delivers, and back.
//!
//! The detector finds edges in linear light (a blurred edge is a symmetric ramp there and
//! nowhere else), so it must undo the curve the camera applied. sRGB is the standard's
//! answer; a phone's video is not sRGB: its curves are steeper or flatter power laws, S-shaped,
//! and adapt to the scene. This crate is the one home of those curves: the renderer encodes
//! with them, the detector decodes with them, and the settings name them the same way in the
//! CLI, the FFI and the recording (`srgb`, `gamma:1.8`, `s-curve:2.2:0.5`; `auto` for the
//! curve estimated from the tags themselves, see [`ToneSetting`]).
//!
//! # Examples
//!
//! ```
//! use jawtrack_tone::{ToneCurve, ToneSetting};
//!
//! let curve: ToneCurve = "gamma:1.8".parse().expect("a curve");
//! let mid = curve.encode(0.18);
//! assert!((curve.decode(mid) - 0.18).abs() < 1e-12);
//! // The detector's table: 8-bit value → linear light on the same 0–255 scale.
//! let table = curve.decode_table();
//! assert_eq!((table[0], table[255]), (0.0, 255.0));
//! assert_eq!("auto".parse::<ToneSetting>().expect("a setting"), ToneSetting::Auto);
//! ```

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;
use std::str::FromStr;

/// A curve from linear light to encoded values (both 0–1), strictly increasing, 0 ↦ 0 and
/// 1 ↦ 1.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum ToneCurve {
    /// The sRGB transfer curve (IEC 61966-2-1): a power law of 1/2.4 with a linear toe, close
    /// to a plain gamma of 2.2.
    #[default]
    Srgb,
    /// A plain power law: encoded = linear^(1/gamma). Gamma 1 is linear light.
    Gamma {
        /// The exponent that decodes (1–4).
        gamma: f64,
    },
    /// A power law followed by a contrast S-curve about mid-grey, as phones' video curves are:
    /// encoded = s(linear^(1/gamma)), s(x) = (1 − contrast)·x + contrast·(3x² − 2x³) — darker
    /// shadows, brighter highlights, steeper between.
    SCurve {
        /// The power law's exponent (1–4).
        gamma: f64,
        /// How much of the smoothstep is mixed in, 0 (none) to under 1 (flat at both ends).
        contrast: f64,
    },
}

/// A tone curve or setting that could not be read, and what was wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ToneError(String);

/// Gamma exponents accepted: wide enough for any camera's curve, narrow enough to refuse a
/// typo (a gamma of 22).
const GAMMA_RANGE: std::ops::RangeInclusive<f64> = 1.0..=4.0;

impl ToneCurve {
    /// Checks the numbers, naming the first bad one.
    pub fn validate(&self) -> Result<(), ToneError> {
        let gamma_ok = |g: f64| {
            if g.is_finite() && GAMMA_RANGE.contains(&g) {
                Ok(())
            } else {
                Err(ToneError(format!("a tone curve's gamma must be between 1 and 4, got {g}")))
            }
        };
        match *self {
            ToneCurve::Srgb => Ok(()),
            ToneCurve::Gamma { gamma } => gamma_ok(gamma),
            ToneCurve::SCurve { gamma, contrast } => {
                gamma_ok(gamma)?;
                if contrast.is_finite() && (0.0..0.95).contains(&contrast) {
                    Ok(())
                } else {
                    Err(ToneError(format!(
                        "an S-curve's contrast must be from 0 to under 0.95 (flat ends hide the shadows), got {contrast}"
                    )))
                }
            }
        }
    }

    /// Linear light (0–1, clamped) to the encoded value (0–1).
    pub fn encode(&self, linear: f64) -> f64 {
        let v = linear.clamp(0.0, 1.0);
        if v == 0.0 || v == 1.0 {
            return v; // exactly, whatever the formula's rounding
        }
        match *self {
            ToneCurve::Srgb => {
                if v <= 0.003_130_8 {
                    12.92 * v
                } else {
                    1.055 * v.powf(1.0 / 2.4) - 0.055
                }
            }
            ToneCurve::Gamma { gamma } => v.powf(1.0 / gamma),
            ToneCurve::SCurve { gamma, contrast } => smoothstep_mix(v.powf(1.0 / gamma), contrast),
        }
    }

    /// The encoded value (0–1, clamped) to linear light (0–1): the inverse of
    /// [`ToneCurve::encode`].
    pub fn decode(&self, encoded: f64) -> f64 {
        let v = encoded.clamp(0.0, 1.0);
        if v == 0.0 || v == 1.0 {
            return v;
        }
        match *self {
            ToneCurve::Srgb => {
                if v <= 0.040_45 {
                    v / 12.92
                } else {
                    ((v + 0.055) / 1.055).powf(2.4)
                }
            }
            ToneCurve::Gamma { gamma } => v.powf(gamma),
            ToneCurve::SCurve { gamma, contrast } => inverse_smoothstep_mix(v, contrast).powf(gamma),
        }
    }

    /// The decoding of every 8-bit value, on the same 0–255 scale: what the detector reads
    /// pixels through.
    pub fn decode_table(&self) -> [f64; 256] {
        std::array::from_fn(|i| 255.0 * self.decode(i as f64 / 255.0))
    }
}

/// (1 − c)·x + c·(3x² − 2x³): increasing for c < 1 (its slope is at least 1 − c).
fn smoothstep_mix(x: f64, c: f64) -> f64 {
    (1.0 - c) * x + c * x * x * (3.0 - 2.0 * x)
}

/// The inverse of [`smoothstep_mix`] on [0, 1], by bisection (it is monotone; 60 halvings
/// reach the last bit).
fn inverse_smoothstep_mix(y: f64, c: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if smoothstep_mix(mid, c) < y {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

impl fmt::Display for ToneCurve {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ToneCurve::Srgb => write!(f, "srgb"),
            ToneCurve::Gamma { gamma } => write!(f, "gamma:{}", round3(gamma)),
            ToneCurve::SCurve { gamma, contrast } => write!(f, "s-curve:{}:{}", round3(gamma), round3(contrast)),
        }
    }
}

/// Three decimals are what any fit of a curve can tell; more is noise in a file or a report.
fn round3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

const CURVE_FORMS: &str = "srgb, gamma:G (G from 1 to 4, e.g. gamma:1.8) or s-curve:G:C (e.g. s-curve:2.2:0.5)";

impl FromStr for ToneCurve {
    type Err = ToneError;

    fn from_str(s: &str) -> Result<Self, ToneError> {
        let number = |what: &str, v: &str| {
            v.trim().parse::<f64>().map_err(|_| {
                ToneError(format!("'{v}' in tone curve '{s}' is not a number ({what}); expected {CURVE_FORMS}"))
            })
        };
        let parts: Vec<&str> = s.trim().split(':').collect();
        let curve = match parts.as_slice() {
            [name] if name.eq_ignore_ascii_case("srgb") => ToneCurve::Srgb,
            [name] if name.eq_ignore_ascii_case("linear") => ToneCurve::Gamma { gamma: 1.0 },
            [name, g] if name.eq_ignore_ascii_case("gamma") => ToneCurve::Gamma { gamma: number("the gamma", g)? },
            [name, g, c] if name.eq_ignore_ascii_case("s-curve") => {
                ToneCurve::SCurve { gamma: number("the gamma", g)?, contrast: number("the contrast", c)? }
            }
            _ => return Err(ToneError(format!("unknown tone curve '{s}': expected {CURVE_FORMS}"))),
        };
        curve.validate()?;
        Ok(curve)
    }
}

/// Serialised as the names flags take ([`fmt::Display`] and [`FromStr`]), so a file says
/// `"gamma:1.8"` as a user types it.
macro_rules! serde_as_name {
    ($($t:ty),*) => {$(
        impl Serialize for $t {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.collect_str(self)
            }
        }

        impl<'de> Deserialize<'de> for $t {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let s = String::deserialize(d)?;
                s.parse().map_err(serde::de::Error::custom)
            }
        }
    )*};
}

serde_as_name!(ToneCurve, ToneSetting);

/// Which curve the detector decodes frames with.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum ToneSetting {
    /// Estimated from the tags themselves (their edges must be symmetric ramps in linear
    /// light), starting from sRGB until enough blurred edges were seen: the default.
    #[default]
    Auto,
    /// This curve, whatever the frames show.
    Fixed(ToneCurve),
}

impl fmt::Display for ToneSetting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ToneSetting::Auto => write!(f, "auto"),
            ToneSetting::Fixed(c) => c.fmt(f),
        }
    }
}

impl FromStr for ToneSetting {
    type Err = ToneError;

    /// `auto`, or a curve ([`ToneCurve`]'s forms).
    fn from_str(s: &str) -> Result<Self, ToneError> {
        if s.trim().eq_ignore_ascii_case("auto") {
            return Ok(ToneSetting::Auto);
        }
        s.parse().map(ToneSetting::Fixed).map_err(|e| {
            if e.0.starts_with("unknown") {
                ToneError(format!("unknown tone setting '{s}': expected auto, {CURVE_FORMS}"))
            } else {
                e
            }
        })
    }
}

/// Why frames are read through the curve they are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ToneReason {
    /// The curve was given.
    Given,
    /// Auto, and no tag edge has told the curve yet: sRGB meanwhile.
    #[default]
    NotYetTold,
    /// Auto, and too few tag sides have told it to leave sRGB.
    TooFewSides,
    /// Auto, and the tags' edges fit no blurred step (sharpened frames): sRGB kept.
    NotBlurredSteps,
    /// Auto, and sRGB fits the edges as well as the best power law: sRGB kept.
    SrgbFitsAsWell,
    /// Auto: the power law the edges told.
    Estimated,
}

#[cfg(test)]
mod tests {
    use super::*;

    const CURVES: [ToneCurve; 5] = [
        ToneCurve::Srgb,
        ToneCurve::Gamma { gamma: 1.0 },
        ToneCurve::Gamma { gamma: 1.6 },
        ToneCurve::Gamma { gamma: 2.8 },
        ToneCurve::SCurve { gamma: 2.2, contrast: 0.5 },
    ];

    #[test]
    fn every_curve_round_trips_and_rises_from_black_to_white() {
        for c in CURVES {
            assert_eq!((c.encode(0.0), c.encode(1.0)), (0.0, 1.0), "{c}");
            let mut last = -1.0;
            for i in 0..=1000 {
                let v = i as f64 / 1000.0;
                let e = c.encode(v);
                assert!(e > last, "{c} is not increasing at {v}");
                last = e;
                assert!((c.decode(e) - v).abs() < 1e-9, "{c} at {v}: {}", c.decode(e));
            }
        }
    }

    #[test]
    fn srgb_is_the_standard_and_the_s_curve_steepens_mid_tones() {
        // IEC 61966-2-1's mid-grey: linear 0.214 04 encodes to 0.5.
        assert!((ToneCurve::Srgb.encode(0.214_041_140_5) - 0.5).abs() < 1e-6);
        let plain = ToneCurve::Gamma { gamma: 2.2 };
        let s = ToneCurve::SCurve { gamma: 2.2, contrast: 0.5 };
        assert!(s.encode(0.02) < plain.encode(0.02), "shadows darker");
        assert!(s.encode(0.8) > plain.encode(0.8), "highlights brighter");
        let t = s.decode_table();
        assert_eq!((t[0], t[255]), (0.0, 255.0));
        assert!(t.windows(2).all(|w| w[1] > w[0]));
    }

    #[test]
    fn names_parse_print_and_bad_ones_say_what_is_expected() {
        for c in CURVES {
            let text = c.to_string();
            assert_eq!(text.parse::<ToneCurve>().expect("prints what parses"), c, "{text}");
            let json = serde_json::to_string(&c).expect("serialises");
            assert_eq!(serde_json::from_str::<ToneCurve>(&json).expect("reads back"), c);
        }
        assert_eq!("gamma:1".parse::<ToneCurve>(), Ok(ToneCurve::Gamma { gamma: 1.0 }));
        assert_eq!("LINEAR".parse::<ToneCurve>(), Ok(ToneCurve::Gamma { gamma: 1.0 }));
        assert_eq!("auto".parse::<ToneSetting>(), Ok(ToneSetting::Auto));
        assert_eq!("gamma:2.6".parse::<ToneSetting>(), Ok(ToneSetting::Fixed(ToneCurve::Gamma { gamma: 2.6 })));
        for (bad, says) in [
            ("gamma:22", "between 1 and 4, got 22"),
            ("gamma:x", "'x' in tone curve 'gamma:x' is not a number"),
            ("s-curve:2.2:1", "contrast must be from 0 to under 0.95"),
            ("rec709", "unknown tone setting 'rec709': expected auto, srgb, gamma:G"),
            ("gamma:NaN", "between 1 and 4"),
        ] {
            let e = bad.parse::<ToneSetting>().expect_err(bad).to_string();
            assert!(e.contains(says), "{bad}: {e}");
        }
        assert!(serde_json::from_str::<ToneCurve>("\"gamma:0.5\"").is_err());
    }
}
