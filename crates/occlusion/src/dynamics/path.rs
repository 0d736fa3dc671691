//! [`interpolate_path`]: a target path between two poses, at rest at both ends.

use super::options::above;
use jawtrack_pose::Pose;
use nalgebra::UnitQuaternion;

/// A path of `rate_hz` samples from `from` to `to` over `duration_s`, both ends included.
///
/// The motion follows the minimum-jerk profile s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ (translation along
/// the straight line, rotation about the fixed shortest axis), so that it starts and ends at
/// rest, as a voluntary jaw movement does, rather than jolting the spring at both ends. With a
/// duration that is not positive and finite, the path is the single sample (0, `to`); with a
/// rate that is not, it is the two end samples.
pub fn interpolate_path(from: &Pose, to: &Pose, duration_s: f64, rate_hz: f64) -> Vec<(f64, Pose)> {
    if !above(duration_s, 0.0, f64::MAX) {
        return vec![(0.0, *to)];
    }
    let intervals = if above(rate_hz, 0.0, f64::MAX) {
        (duration_s * rate_hz * (1.0 - 1e-12)).ceil().clamp(1.0, 1e7) as usize
    } else {
        1
    };
    let turn = (to.rotation() * from.rotation().inverse()).scaled_axis();
    let shift = to.translation() - from.translation();
    (0..=intervals)
        .map(|i| {
            let tau = i as f64 / intervals as f64;
            let s = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
            let pose = if i == intervals {
                *to
            } else {
                Pose::from_parts(
                    UnitQuaternion::from_scaled_axis(turn * s) * from.rotation(),
                    from.translation() + shift * s,
                )
            };
            (duration_s * tau, pose)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn the_path_starts_and_ends_at_rest_on_the_end_poses() {
        let from = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(1.0, 0.0, 0.0));
        let to = Pose::from_axis_angle(Vector3::new(0.0, 0.1, 0.0), Vector3::new(3.0, 0.0, 0.0));
        let path = interpolate_path(&from, &to, 0.5, 60.0);
        assert_eq!(path.len(), 31);
        assert_eq!(path[0], (0.0, from));
        assert_eq!(path[30], (0.5, to));
        let x: Vec<f64> = path.iter().map(|(_, p)| p.translation().x).collect();
        assert!(x.windows(2).all(|w| w[1] >= w[0]));
        // At rest at the ends: the first step is tiny against the middle one.
        assert!(x[1] - x[0] < 0.01 * (x[16] - x[15]), "{x:?}");
        assert_eq!(interpolate_path(&from, &to, 0.0, 60.0), vec![(0.0, to)]);
        assert_eq!(interpolate_path(&from, &to, 1.0, f64::NAN).len(), 2);
    }
}
