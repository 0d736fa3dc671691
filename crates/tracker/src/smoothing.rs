//! An optional smoother for the jaw pose: the One-Euro filter (Casiez et al., 2012) on SE(3).
//!
//! Translation is filtered per axis and rotation by slerp toward each new sample, both with
//! the same adaptive weight: the cutoff rises with the speed of the motion, so a still jaw is
//! smoothed hardest and a moving one follows closely. The cutoff never drops below
//! `fps / 2π`, which keeps each sample's weight at one half or more: a steady motion is then
//! followed with less than one frame of lag, whatever the settings.

use jawtrack_pose::Pose;
use nalgebra::Vector3;
use std::f64::consts::TAU;

/// Settings of the One-Euro filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmootherConfig {
    /// Cutoff (Hz) when still; raised to the frame rate / 2π if lower (see the module docs).
    pub min_cutoff_hz: f64,
    /// How fast the cutoff rises with speed (Hz per mm/s; rotation counts 1° as 1 mm).
    pub beta: f64,
    /// Cutoff (Hz) of the speed estimate.
    pub derivative_cutoff_hz: f64,
}

impl Default for SmootherConfig {
    fn default() -> Self {
        SmootherConfig { min_cutoff_hz: 1.0, beta: 0.5, derivative_cutoff_hz: 1.0 }
    }
}

/// The filter's state.
#[derive(Debug, Clone, PartialEq)]
pub struct Smoother {
    config: SmootherConfig,
    last: Option<(f64, Pose, f64)>,
}

/// The weight of a new sample for a first-order low-pass of cutoff `hz` after `dt` seconds.
fn alpha(hz: f64, dt: f64) -> f64 {
    let tau = 1.0 / (TAU * hz);
    1.0 / (1.0 + tau / dt)
}

impl Smoother {
    /// A filter with no history.
    pub fn new(config: SmootherConfig) -> Self {
        Smoother { config, last: None }
    }

    /// Forgets the history (a cut in the footage, a lost body).
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// Filters the pose sampled at `t` (s). A sample not after the previous one restarts the
    /// filter.
    pub fn filter(&mut self, t: f64, pose: &Pose) -> Pose {
        let Some((t0, previous, speed0)) = self.last else {
            self.last = Some((t, *pose, 0.0));
            return *pose;
        };
        let dt = t - t0;
        if !(dt > 0.0 && dt.is_finite()) {
            self.last = Some((t, *pose, 0.0));
            return *pose;
        }
        let (angle, distance) = previous.distance_to(pose);
        let raw_speed = (distance + angle.to_degrees()) / dt;
        let speed = speed0 + alpha(self.config.derivative_cutoff_hz, dt) * (raw_speed - speed0);
        let cutoff = (self.config.min_cutoff_hz + self.config.beta * speed).max(1.0 / (TAU * dt));
        let a = alpha(cutoff, dt);
        let translation: Vector3<f64> = previous.translation() + a * (pose.translation() - previous.translation());
        let rotation = previous.rotation().slerp(&pose.rotation(), a);
        let out = Pose::from_parts(rotation, translation);
        self.last = Some((t, out, speed));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f64) -> Pose {
        Pose::from_axis_angle(Vector3::new(x.to_radians(), 0.0, 0.0), Vector3::new(0.0, x, 40.0))
    }

    #[test]
    fn a_steady_motion_lags_less_than_a_frame() {
        for (speed_mm_s, fps) in [(0.5, 30.0), (20.0, 30.0), (150.0, 60.0), (3.0, 240.0)] {
            let mut s = Smoother::new(SmootherConfig::default());
            let step = speed_mm_s / fps;
            let mut worst = 0.0f64;
            for i in 0..(3.0 * fps) as usize {
                let out = s.filter(i as f64 / fps, &at(i as f64 * step));
                // How far back in time the output sits, in frames.
                worst = worst.max((i as f64 * step - out.translation().y) / step);
            }
            // At the slowest speeds the floor on the cutoff holds the lag at exactly one frame.
            assert!(worst <= 1.0 + 1e-9, "{speed_mm_s} mm/s at {fps} fps: lags {worst:.2} frames");
        }
    }

    #[test]
    fn a_still_pose_is_smoothed() {
        let mut s = Smoother::new(SmootherConfig::default());
        // Alternating ±0.05 mm noise around a still pose.
        let (mut raw, mut out) = (0.0, 0.0);
        for i in 0..300 {
            let noise = if i % 2 == 0 { 0.05 } else { -0.05 };
            let p = s.filter(i as f64 / 30.0, &at(noise));
            if i >= 30 {
                raw += noise * noise;
                out += p.translation().y.powi(2);
            }
        }
        assert!(out < 0.2 * raw, "smoothed power {out:.2e} vs raw {raw:.2e}");
    }

    #[test]
    fn time_going_backwards_restarts() {
        let mut s = Smoother::new(SmootherConfig::default());
        s.filter(1.0, &at(0.0));
        let p = s.filter(0.5, &at(10.0));
        assert_eq!(p, at(10.0));
    }
}
