//! The integrator (*Dynamics* in the `dynamics` documentation): [`simulate`] drives the lower
//! arch toward a target path with a spring–damper on a semi-implicit Euler step, projects
//! penetration out after every step, and reports one [`Step`] per target sample with the
//! contact force and the vertices that carried it.

use super::body::RigidBody;
use super::error::DynamicsError;
use super::intercuspation::resolve;
use super::options::DynamicsOptions;
use super::projection::Scene;
use crate::contacts::{Arch, Side};
use jawtrack_pose::Pose;
use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;
use std::collections::BTreeMap;

/// The resolved motion at one target sample, from [`simulate`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    /// Time (s), the target sample's.
    pub t: f64,
    /// The resolved pose of the lower scan.
    pub maxilla_scan_from_mandible_scan: Pose,
    /// Distance (mm) between where the resolved and the target pose put the lower arch's centre
    /// of mass: how far the contacts held it off the target.
    pub target_offset_mm: f64,
    /// Angle (degrees) between the resolved and the target rotation.
    pub target_rotation_deg: f64,
    /// Total contact force on the lower arch (N, upper scan frame), averaged over the interval
    /// since the previous sample (zero at the first sample, where nothing has moved yet).
    pub force: [f64; 3],
    /// Its magnitude (N).
    pub force_n: f64,
    /// Deepest penetration left after any integration step in the interval, either direction
    /// (mm; 0 when nothing touched). Within the tolerance by construction.
    pub max_penetration_mm: f64,
    /// The vertices that carried force in the interval, largest force first.
    pub contacts: Vec<ContactForce>,
}

/// The force carried by one vertex in contact, averaged over a step's interval.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactForce {
    /// The arch the vertex belongs to.
    pub arch: Side,
    /// The vertex (index into that arch's mesh).
    pub vertex: u32,
    /// Where it is at the step's time (mm, upper scan frame).
    pub point: [f64; 3],
    /// Unit direction of the force on the lower arch (upper scan frame).
    pub direction: [f64; 3],
    /// The mean force (N).
    pub force_n: f64,
}

/// [`simulate_with_progress`] without progress reports.
pub fn simulate(
    upper: &Arch,
    lower: &Arch,
    target: &[(f64, Pose)],
    options: &DynamicsOptions,
) -> Result<Vec<Step>, DynamicsError> {
    simulate_with_progress(upper, lower, target, options, &mut |_, _| {})
}

/// The lower arch driven toward `target` (time in s, `maxilla_scan_from_mandible_scan`) as a
/// rigid body in contact with the fixed upper arch; one [`Step`] per target sample.
///
/// The body starts at the first target pose with penetration resolved by
/// [`resolve_intercuspation`](super::resolve_intercuspation), moving with the target's
/// velocity. Between samples the target is interpolated linearly in translation and along the
/// shortest rotation, and the interval is split into equal steps of at most `options.dt_s`.
/// `progress(done, total)` is called after each target interval.
pub fn simulate_with_progress(
    upper: &Arch,
    lower: &Arch,
    target: &[(f64, Pose)],
    options: &DynamicsOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<Step>, DynamicsError> {
    options.validate()?;
    validate_target(target)?;
    let body = RigidBody::shell(&lower.mesh, options.mass_kg)?;
    let mut scene = Scene::new(upper, lower, &body, options)?;
    let (t0, first) = target[0];
    let start = resolve(&mut scene, &first, "at the first target pose")?;
    let mut pose = start.maxilla_scan_from_mandible_scan;
    let (mut v, mut w) = match target.get(1) {
        Some(next) => Segment::new(&target[0], next).velocity(&body, 0.0),
        None => (Vector3::zeros(), Vector3::zeros()),
    };
    let omega = std::f64::consts::TAU * options.natural_frequency_hz;
    let (stiffness, damping) = (omega * omega, 2.0 * options.damping_ratio * omega);
    let mut steps = Vec::with_capacity(target.len());
    steps.push(step_at(&body, t0, &pose, &first, Vector3::zeros(), start.residual_depth_mm, Vec::new()));
    let total = target.len() - 1;
    for k in 1..target.len() {
        let segment = Segment::new(&target[k - 1], &target[k]);
        let span = segment.duration;
        let n = ((span / options.dt_s) * (1.0 - 1e-12)).ceil().max(1.0) as usize;
        let h = span / n as f64;
        let mut impulses: BTreeMap<(u8, u32), Vector3<f64>> = BTreeMap::new();
        let mut worst: f64 = 0.0;
        for s in 0..n {
            let fraction = s as f64 / n as f64;
            let t = segment.t0 + span * fraction;
            // Spring–damper toward the target, per unit mass / inertia (the same ω for every mode).
            let goal = segment.pose(fraction);
            let (goal_v, goal_w) = segment.velocity(&body, fraction);
            let (inertia, inertia_inv) = body.inertia_world(&pose);
            let accel = (body.centre(&goal) - body.centre(&pose)) * stiffness + (goal_v - v) * damping;
            let turn = (goal.rotation() * pose.rotation().inverse()).scaled_axis();
            // Euler's equations: the gyroscopic torque ω × Iω is there for a spinning arch.
            let angular = turn * stiffness + (goal_w - w) * damping - inertia_inv * w.cross(&(inertia * w));
            v += accel * h;
            w += angular * h;
            let (dx, dtheta) = (v * h, w * h);
            let moved = body.displacement_bound(&dx, &dtheta);
            if moved > scene.reach / 2.0 {
                return Err(DynamicsError::TooFast { t_s: t + h, moved_mm: moved, reach_mm: scene.reach });
            }
            pose = body.displaced(&pose, &dx, &dtheta);
            scene.moved(moved);
            let projection = scene.project(&mut pose).map_err(|e| e.at(format!("at t = {:.4} s", t + h)))?;
            // The velocity the projection implies: the contact impulse is M·δ/h.
            v += projection.dx / h;
            w += projection.dtheta / h;
            worst = worst.max(projection.residual_depth);
            for (key, lambda_n) in projection.impulses {
                *impulses.entry(key).or_insert_with(Vector3::zeros) += lambda_n / h;
            }
        }
        // Impulse (kg·mm/s) over the interval → mean force (kg·mm/s² = 1e-3 N).
        let to_newtons = 1e-3 / span;
        let (_, goal) = target[k];
        let mut contacts: Vec<ContactForce> = impulses
            .iter()
            .filter_map(|(&(arch, vertex), impulse)| {
                let force = impulse * to_newtons;
                let direction = force.try_normalize(0.0)?;
                let point = if arch == 0 {
                    upper.mesh.vertices[vertex as usize]
                } else {
                    pose.transform_point(&lower.mesh.vertices[vertex as usize])
                };
                Some(ContactForce {
                    arch: if arch == 0 { Side::Maxilla } else { Side::Mandible },
                    vertex,
                    point: point.coords.into(),
                    direction: direction.into(),
                    force_n: force.norm(),
                })
            })
            .collect();
        contacts.sort_by(|a, b| b.force_n.total_cmp(&a.force_n));
        let force = impulses.values().sum::<Vector3<f64>>() * to_newtons;
        steps.push(step_at(&body, target[k].0, &pose, &goal, force, worst.max(0.0), contacts));
        progress(k, total);
    }
    Ok(steps)
}

fn step_at(
    body: &RigidBody,
    t: f64,
    pose: &Pose,
    goal: &Pose,
    force: Vector3<f64>,
    max_penetration_mm: f64,
    contacts: Vec<ContactForce>,
) -> Step {
    Step {
        t,
        maxilla_scan_from_mandible_scan: *pose,
        target_offset_mm: (body.centre(pose) - body.centre(goal)).norm(),
        target_rotation_deg: pose.rotation().angle_to(&goal.rotation()).to_degrees(),
        force: force.into(),
        force_n: force.norm(),
        max_penetration_mm,
        contacts,
    }
}

fn validate_target(target: &[(f64, Pose)]) -> Result<(), DynamicsError> {
    if target.is_empty() {
        return Err(DynamicsError::EmptyTarget);
    }
    for (index, (t, pose)) in target.iter().enumerate() {
        if !t.is_finite() || !pose.is_finite() {
            return Err(DynamicsError::NonFinite { index });
        }
        if index > 0 && *t <= target[index - 1].0 {
            return Err(DynamicsError::NonIncreasingTime { index, time_s: *t, previous_s: target[index - 1].0 });
        }
    }
    Ok(())
}

/// The target between two samples: translation linear, rotation at a constant rate about a
/// fixed axis (the shortest way), so that its velocity is exact and constant.
struct Segment {
    t0: f64,
    duration: f64,
    from: Pose,
    translation_rate: Vector3<f64>,
    /// Rotation vector (rad, upper scan frame) from the first sample's rotation to the second's.
    turn: Vector3<f64>,
}

impl Segment {
    fn new((t0, from): &(f64, Pose), (t1, to): &(f64, Pose)) -> Segment {
        let duration = t1 - t0;
        let turn = (to.rotation() * from.rotation().inverse()).scaled_axis();
        Segment {
            t0: *t0,
            duration,
            from: *from,
            translation_rate: (to.translation() - from.translation()) / duration,
            turn,
        }
    }

    /// The target pose a fraction `s` (0..1) of the way.
    fn pose(&self, s: f64) -> Pose {
        let q = UnitQuaternion::from_scaled_axis(self.turn * s) * self.from.rotation();
        Pose::from_parts(q, self.from.translation() + self.translation_rate * (self.duration * s))
    }

    /// The target's centre-of-mass velocity (mm/s) and angular velocity (rad/s) a fraction `s`
    /// of the way.
    fn velocity(&self, body: &RigidBody, s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let w = self.turn / self.duration;
        let arm = self.pose(s).rotation() * body.centre_of_mass.coords;
        (self.translation_rate + w.cross(&arm), w)
    }
}
