//! [`resolve_path`]: a recorded path made physical, with what a report says about it: the
//! correction that frees its first pose, and the force, residual penetration and departure
//! from the recording over the simulated slide ([`PathSummary`], [`StepSummary`]).

use super::error::DynamicsError;
use super::integrator::{Step, simulate_with_progress};
use super::intercuspation::{Correction, resolve_intercuspation};
use super::options::DynamicsOptions;
use crate::contacts::Arch;
use jawtrack_pose::Pose;
use serde::Serialize;

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
    /// The options it was resolved with.
    pub options: DynamicsOptions,
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

    /// What a report says about the whole path.
    pub fn summary(&self) -> PathSummary {
        let (o, c) = (&self.options, &self.correction);
        PathSummary {
            mass_kg: o.mass_kg,
            natural_frequency_hz: o.natural_frequency_hz,
            dt_s: o.dt_s,
            tolerance_mm: o.tolerance_mm,
            intercuspation_correction: CorrectionSummary {
                shift_mm: c.shift_mm,
                rotation_deg: c.rotation_deg,
                initial_depth_mm: c.initial_depth_mm,
                residual_depth_mm: c.residual_depth_mm,
            },
            peak_force_n: self.peak_force_n(),
            max_residual_penetration_mm: self.max_residual_penetration_mm(),
            max_target_offset_mm: self.max_target_offset_mm(),
        }
    }
}

/// What a report says about a resolved path ([`ResolvedPath::summary`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PathSummary {
    /// [`DynamicsOptions::mass_kg`].
    pub mass_kg: f64,
    /// [`DynamicsOptions::natural_frequency_hz`].
    pub natural_frequency_hz: f64,
    /// [`DynamicsOptions::dt_s`].
    pub dt_s: f64,
    /// [`DynamicsOptions::tolerance_mm`].
    pub tolerance_mm: f64,
    /// The correction of the first pose.
    pub intercuspation_correction: CorrectionSummary,
    /// [`ResolvedPath::peak_force_n`].
    pub peak_force_n: f64,
    /// [`ResolvedPath::max_residual_penetration_mm`].
    pub max_residual_penetration_mm: f64,
    /// [`ResolvedPath::max_target_offset_mm`].
    pub max_target_offset_mm: f64,
}

/// A [`Correction`] as a report gives it: how far it moved the arch and how deep the
/// penetration was before and after.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CorrectionSummary {
    /// [`Correction::shift_mm`].
    pub shift_mm: [f64; 3],
    /// [`Correction::rotation_deg`].
    pub rotation_deg: f64,
    /// [`Correction::initial_depth_mm`].
    pub initial_depth_mm: f64,
    /// [`Correction::residual_depth_mm`].
    pub residual_depth_mm: f64,
}

/// A [`Step`] as a report gives it: the contact force and how far the contacts held the arch
/// from the target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepSummary {
    /// [`Step::force_n`].
    pub force_n: f64,
    /// [`Step::force`].
    pub force: [f64; 3],
    /// [`Step::target_offset_mm`].
    pub target_offset_mm: f64,
    /// [`Step::target_rotation_deg`].
    pub target_rotation_deg: f64,
    /// [`Step::max_penetration_mm`].
    pub max_penetration_mm: f64,
}

impl From<&Step> for StepSummary {
    fn from(s: &Step) -> Self {
        StepSummary {
            force_n: s.force_n,
            force: s.force,
            target_offset_mm: s.target_offset_mm,
            target_rotation_deg: s.target_rotation_deg,
            max_penetration_mm: s.max_penetration_mm,
        }
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
    Ok(ResolvedPath { options: *options, correction, steps })
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
        let summary = path.summary();
        assert_eq!((summary.mass_kg, summary.dt_s), (options.mass_kg, options.dt_s));
        assert_eq!(summary.intercuspation_correction.shift_mm, path.correction.shift_mm);
        assert_eq!(summary.peak_force_n, peak);
        let last = StepSummary::from(&path.steps[3]);
        assert_eq!((last.force, last.target_offset_mm), (path.steps[3].force, path.steps[3].target_offset_mm));
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
