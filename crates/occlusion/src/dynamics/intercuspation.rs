//! One pose made free of penetration: [`resolve_intercuspation`], the smallest rigid correction
//! of the lower scan's pose that leaves no vertex of either arch deeper than the tolerance
//! inside the other (also where a simulation starts).

use super::body::RigidBody;
use super::error::DynamicsError;
use super::options::DynamicsOptions;
use super::projection::Scene;
use crate::contacts::Arch;
use jawtrack_pose::Pose;
use serde::Serialize;

/// The smallest rigid correction of a penetrating pose, from [`resolve_intercuspation`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Correction {
    /// The corrected pose of the lower scan.
    pub maxilla_scan_from_mandible_scan: Pose,
    /// How far the lower arch's centre of mass moved (mm, upper scan frame).
    pub shift_mm: [f64; 3],
    /// How far the lower arch turned (degrees, about its centre of mass).
    pub rotation_deg: f64,
    /// Projection rounds used (0 when nothing penetrated).
    pub iterations: usize,
    /// The deepest penetration before (mm; 0 when none).
    pub initial_depth_mm: f64,
    /// The deepest penetration after, either direction (mm; 0 when none).
    pub residual_depth_mm: f64,
}

/// The smallest rigid correction of `maxilla_scan_from_mandible_scan` that leaves no vertex of
/// either arch more than `options.tolerance_mm` inside the other.
///
/// "Smallest" is in the mass/inertia metric (see the module documentation): translation of the
/// centre of mass, plus rotation about it weighted by the radius of gyration about each axis.
/// Penetration deeper than the distance indexes' reach is not seen.
pub fn resolve_intercuspation(
    upper: &Arch,
    lower: &Arch,
    maxilla_scan_from_mandible_scan: &Pose,
    options: &DynamicsOptions,
) -> Result<Correction, DynamicsError> {
    options.validate()?;
    if !maxilla_scan_from_mandible_scan.is_finite() {
        return Err(DynamicsError::NonFinitePose);
    }
    let body = RigidBody::shell(&lower.mesh, options.mass_kg)?;
    let mut scene = Scene::new(upper, lower, &body, options)?;
    resolve(&mut scene, maxilla_scan_from_mandible_scan, "at maximal intercuspation")
}

pub(super) fn resolve(scene: &mut Scene, pose: &Pose, at: &str) -> Result<Correction, DynamicsError> {
    let mut resolved = *pose;
    let projection = scene.project(&mut resolved).map_err(|e| e.at(at.to_owned()))?;
    let shift = scene.body.centre(&resolved) - scene.body.centre(pose);
    Ok(Correction {
        maxilla_scan_from_mandible_scan: resolved,
        shift_mm: shift.into(),
        rotation_deg: resolved.rotation().angle_to(&pose.rotation()).to_degrees(),
        iterations: projection.iterations,
        initial_depth_mm: projection.initial_depth.max(0.0),
        residual_depth_mm: projection.residual_depth.max(0.0),
    })
}
