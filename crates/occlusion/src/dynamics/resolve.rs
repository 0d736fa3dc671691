//! [`resolve_path`]: a recorded path made physical, with what a report says about it: the
//! correction that frees its first pose, and the peak force, residual penetration and largest
//! departure from the recording over the simulated slide.

use super::error::DynamicsError;
use super::integrator::{Step, simulate_with_progress};
use super::intercuspation::{Correction, resolve_intercuspation};
use super::options::DynamicsOptions;
use crate::contacts::Arch;
use jawtrack_pose::Pose;

/// Why a recorded path could not be resolved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResolveError {
    /// The interpenetration of the path's first pose could not be removed.
    #[error("removing the interpenetration at the first frame")]
    Intercuspation(#[source] DynamicsError),
    /// The simulation along the path failed.
    #[error(transparent)]
    Simulation(DynamicsError),
}

/// A recorded path resolved by [`resolve_path`].
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedPath {
    /// The smallest correction that removes the interpenetration of the first pose (where the
    /// recording, the registration or the scans are off).
    pub correction: Correction,
    /// One step per target sample: the resolved pose, force and offset from the target.
    pub steps: Vec<Step>,
}

impl ResolvedPath {
    /// The largest contact force over the path (N; 0 without steps).
    pub fn peak_force_n(&self) -> f64 {
        self.steps.iter().map(|s| s.force_n).fold(0.0, f64::max)
    }

    /// The deepest penetration left after any step (mm; 0 without steps).
    pub fn max_residual_penetration_mm(&self) -> f64 {
        self.steps.iter().map(|s| s.max_penetration_mm).fold(0.0, f64::max)
    }

    /// The farthest the contacts held the arch from the target (mm; 0 without steps).
    pub fn max_target_offset_mm(&self) -> f64 {
        self.steps.iter().map(|s| s.target_offset_mm).fold(0.0, f64::max)
    }
}

/// The target path (time in s, `maxilla_scan_from_mandible_scan`) resolved: the intercuspation
/// correction of its first pose ([`resolve_intercuspation`]) and the simulated motion
/// ([`simulate_with_progress`], which reports `progress(done, total)`).
pub fn resolve_path(
    upper: &Arch,
    lower: &Arch,
    target: &[(f64, Pose)],
    options: &DynamicsOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<ResolvedPath, ResolveError> {
    let (_, first) = target.first().ok_or(ResolveError::Simulation(DynamicsError::EmptyTarget))?;
    let correction = resolve_intercuspation(upper, lower, first, options).map_err(ResolveError::Intercuspation)?;
    let steps = simulate_with_progress(upper, lower, target, options, progress).map_err(ResolveError::Simulation)?;
    Ok(ResolvedPath { correction, steps })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contacts::ContactSettings;
    use crate::dynamics::simulate;
    use crate::scenes;
    use nalgebra::{Point3, Vector3};

    /// A patch facing down at z = 0 and a 3 mm sphere whose top is 0.2 mm through it.
    fn sphere_through_patch() -> (Arch, Arch) {
        let settings = ContactSettings { threshold_mm: 0.05, max_depth_mm: 0.5 };
        let arch = |mesh| Arch::new(vec![("arch".to_owned(), mesh)], &settings);
        (arch(scenes::patch(10.0, 40, 0.0, true)), arch(scenes::sphere(Point3::new(0.0, 0.0, -2.8), 3.0, 24)))
    }

    #[test]
    fn a_held_path_is_corrected_then_simulated_and_summarised() {
        let (upper, lower) = sphere_through_patch();
        let target: Vec<(f64, Pose)> = (0..4).map(|k| (f64::from(k) / 30.0, Pose::identity())).collect();
        let options = DynamicsOptions::default();
        let mut calls = 0;
        let path = resolve_path(&upper, &lower, &target, &options, &mut |_, _| calls += 1).expect("resolved");
        assert_eq!(path.correction, resolve_intercuspation(&upper, &lower, &Pose::identity(), &options).expect("ok"));
        assert!((Vector3::from(path.correction.shift_mm).norm() - 0.2).abs() < 0.01, "{:?}", path.correction);
        assert_eq!(path.steps, simulate(&upper, &lower, &target, &options).expect("simulated"));
        assert_eq!(calls, 3, "one report per target interval");
        let peak = path.steps.iter().map(|s| s.force_n).fold(0.0, f64::max);
        assert!(peak > 0.0 && path.peak_force_n() == peak);
        assert!(path.max_residual_penetration_mm() <= options.tolerance_mm);
        assert!((path.max_target_offset_mm() - 0.2).abs() < 0.01, "{}", path.max_target_offset_mm());
    }

    #[test]
    fn failures_say_which_stage_failed() {
        let (upper, lower) = sphere_through_patch();
        let still = [(0.0, Pose::identity())];
        let bad = DynamicsOptions { dt_s: 0.5, ..Default::default() };
        let e = resolve_path(&upper, &lower, &still, &bad, &mut |_, _| {}).expect_err("a step too long");
        assert!(matches!(e, ResolveError::Intercuspation(DynamicsError::Options(_))), "{e:?}");
        assert_eq!(e.to_string(), "removing the interpenetration at the first frame");
        let e = resolve_path(&upper, &lower, &[], &DynamicsOptions::default(), &mut |_, _| {}).expect_err("empty");
        assert_eq!(e, ResolveError::Simulation(DynamicsError::EmptyTarget));
        let backwards = [(0.1, Pose::identity()), (0.0, Pose::identity())];
        let e = resolve_path(&upper, &lower, &backwards, &DynamicsOptions::default(), &mut |_, _| {})
            .expect_err("time runs backwards");
        assert_eq!(
            e.to_string(),
            DynamicsError::NonIncreasingTime { index: 1, time_s: 0.0, previous_s: 0.1 }.to_string()
        );
    }
}
