//! The parts a row's exposure is cut into: a moving body is modelled at each part's middle
//! instant, with the sweep over the part taken as a blur along it. Fewer parts than instants
//! sampled one per half pixel of smear (`docs/dense.md`): a part may sweep twice the blur.

use crate::{Motion, Options};

/// A smear (px over the exposure) below this is not modelled: the exposure is taken as an
/// instant, and the body may be fitted as still.
const MIN_SMEAR_PX: f64 = 0.5;
/// The exposure is cut into parts that each sweep the tags by at most this many blur σ, each
/// modelled at its middle instant with its sweep as a blur along it ([`crate::plane::look`]).
/// At 2σ a straight edge is read within 0.002 of the contrast of the sweep's true average; on
/// the bench 1σ was 1.2–1.4× slower and no better, 4σ took chewing's p95 from 0.037 to 0.046 mm.
const SWEEP_SIGMAS: f64 = 2.0;

/// The equal parts a row's exposure is cut into, each modelled at its middle instant, with the
/// sweep over it as a blur ([`crate::plane::look`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Parts {
    /// Each part's middle (s, relative to the row's own time).
    pub(crate) middles: Vec<f64>,
    /// Each part's length (s); 0 where the exposure is taken as an instant.
    pub(crate) length_s: f64,
}

impl Parts {
    /// The exposure as one instant, the row's own.
    pub(crate) fn instant() -> Self {
        Parts { middles: vec![0.0], length_s: 0.0 }
    }

    /// The parts for a `smear` (px) over the exposure and a blur of `sigma_px`: each sweeps
    /// the tags by at most [`SWEEP_SIGMAS`] σ, and there are at most `max_subframes`; none
    /// under [`MIN_SMEAR_PX`].
    pub(crate) fn of(smear: f64, sigma_px: f64, motion: Option<&Motion>, o: &Options) -> Self {
        let Some(m) = motion else { return Parts::instant() };
        if !(smear >= MIN_SMEAR_PX && m.exposure_s > 0.0) {
            return Parts::instant();
        }
        let k = ((smear / (SWEEP_SIGMAS * sigma_px)).ceil() as usize).clamp(1, o.max_subframes);
        let middles = (0..k).map(|i| ((i as f64 + 0.5) / k as f64 - 0.5) * m.exposure_s).collect();
        Parts { middles, length_s: m.exposure_s / k as f64 }
    }

    /// Whether the exposure's sweep is modelled.
    pub(crate) fn smeared(&self) -> bool {
        self.length_s > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_pose::{RollingShutter, Velocity};

    fn motion(exposure_s: f64) -> Motion {
        Motion { velocity: Velocity::ZERO, shutter: RollingShutter::global(), exposure_s }
    }

    #[test]
    fn no_motion_or_a_small_smear_is_one_instant() {
        let o = Options::default();
        assert_eq!(Parts::of(10.0, 1.0, None, &o), Parts::instant());
        assert_eq!(Parts::of(MIN_SMEAR_PX * 0.99, 1.0, Some(&motion(0.008)), &o), Parts::instant());
        assert_eq!(Parts::of(10.0, 1.0, Some(&motion(0.0)), &o), Parts::instant());
        assert_eq!(Parts::of(f64::NAN, 1.0, Some(&motion(0.008)), &o), Parts::instant());
        assert!(!Parts::instant().smeared());
    }

    #[test]
    fn each_part_sweeps_at_most_twice_the_blur_and_the_parts_tile_the_exposure() {
        let o = Options::default();
        let exposure = 0.008;
        let mut checked = 0;
        for (smear, sigma, want) in
            [(0.6, 1.0, 1), (2.0, 1.0, 1), (2.1, 1.0, 2), (10.0, 1.0, 5), (10.0, 2.5, 2), (100.0, 1.0, 8)]
        {
            let p = Parts::of(smear, sigma, Some(&motion(exposure)), &o);
            assert_eq!(p.middles.len(), want, "smear {smear}, σ {sigma}");
            assert!(p.smeared());
            assert!((p.length_s * want as f64 - exposure).abs() < 1e-15);
            // Centred on the row's time, a part's length apart, the first half a part in.
            assert!((p.middles[0] + exposure / 2.0 - p.length_s / 2.0).abs() < 1e-15);
            for w in p.middles.windows(2) {
                assert!((w[1] - w[0] - p.length_s).abs() < 1e-15);
            }
            assert!(p.middles.iter().sum::<f64>().abs() < 1e-15);
            checked += 1;
        }
        assert_eq!(checked, 6);
        assert_eq!(o.max_subframes, 8, "the last case is capped at the default");
    }
}
