//! [`DynamicsOptions`]: the numbers that set up the rigid body, its spring and the contact
//! resolution, and the check that they are usable.

use super::error::DynamicsError;
use serde::Serialize;

/// Numbers that set up the rigid body, its spring and the contact resolution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DynamicsOptions {
    /// Mass of the lower arch (kg); a mandible with its teeth is about 0.1 kg.
    pub mass_kg: f64,
    /// Natural frequency (Hz) of the spring–damper pulling the arch toward the target, the same
    /// for every translational and rotational mode: the stiffness is (2π f)² times the mass
    /// (translation) or the inertia tensor (rotation).
    pub natural_frequency_hz: f64,
    /// Damping ratio of the spring–damper (1: critical, no overshoot). Damping acts on the
    /// velocity relative to the target's, so a moving target is followed without lag.
    pub damping_ratio: f64,
    /// Integration step (s), at most 0.01 and at most 0.5 / (2π f) so that the explicit
    /// spring stays accurate; target intervals are split into equal steps no longer than this.
    pub dt_s: f64,
    /// Deepest penetration (mm) allowed after each step, in either direction.
    pub tolerance_mm: f64,
    /// Most projection rounds (measure, solve, move) per step before giving up with an error.
    pub max_iterations: usize,
}

impl Default for DynamicsOptions {
    fn default() -> Self {
        DynamicsOptions {
            mass_kg: 0.1,
            natural_frequency_hz: 15.0,
            damping_ratio: 1.0,
            dt_s: 1e-3,
            // Half the 0.01 mm target, so that a reported path is well inside it.
            tolerance_mm: 0.005,
            max_iterations: 30,
        }
    }
}

impl DynamicsOptions {
    /// Checks every number is usable.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        let bad = |message: String| Err(DynamicsError::Options(message));
        if !above(self.mass_kg, 0.0, f64::MAX) {
            return bad(format!("the mass must be positive, got {} kg", self.mass_kg));
        }
        if !above(self.natural_frequency_hz, 0.0, f64::MAX) {
            return bad(format!("the natural frequency must be positive, got {} Hz", self.natural_frequency_hz));
        }
        if !(0.0..=f64::MAX).contains(&self.damping_ratio) {
            return bad(format!("the damping ratio must be 0 or more, got {}", self.damping_ratio));
        }
        if !above(self.dt_s, 0.0, MAX_DT_S) {
            return bad(format!("the time step must be more than 0 and at most {MAX_DT_S} s, got {} s", self.dt_s));
        }
        let omega = std::f64::consts::TAU * self.natural_frequency_hz;
        if omega * self.dt_s > MAX_OMEGA_DT {
            return bad(format!(
                "a {} s step is too long for a {} Hz spring (the step must be at most {:.2e} s)",
                self.dt_s,
                self.natural_frequency_hz,
                MAX_OMEGA_DT / omega
            ));
        }
        if !above(self.tolerance_mm, 0.0, 0.1) {
            return bad(format!(
                "the penetration tolerance must be more than 0 and at most 0.1 mm, got {}",
                self.tolerance_mm
            ));
        }
        if self.max_iterations == 0 {
            return bad("at least one projection round is needed".to_owned());
        }
        Ok(())
    }
}

/// Whether `lo < x ≤ hi` (false for NaN).
pub(super) fn above(x: f64, lo: f64, hi: f64) -> bool {
    x > lo && x <= hi
}

/// The longest step accepted (s).
pub const MAX_DT_S: f64 = 0.01;

/// The largest ω·dt accepted: semi-implicit Euler on a critically damped spring is unstable
/// past about 0.83 and loses accuracy well before.
const MAX_OMEGA_DT: f64 = 0.5;
