//! Dynamic contacts: the mandible as a rigid body that slides over the maxillary teeth instead
//! of passing through them.
//!
//! A recorded jaw motion (or a registration at maximal intercuspation) places the lower scan a
//! little inside the upper one wherever tracking, registration or the scans themselves are off
//! by a few tenths of a millimetre. Kinematic contacts ([`crate::contacts`]) then report
//! penetrations that cannot happen. This module resolves them physically:
//!
//! 1. [`resolve_intercuspation`]: the smallest rigid correction of the lower scan's pose that
//!    leaves no vertex of either arch deeper than a tolerance inside the other;
//! 2. [`simulate`]: the lower arch as a rigid body (mass ≈ 100 g, inertia of its mesh) pulled
//!    toward the target path by a 6-DoF spring–damper, with contacts that push it back out, so
//!    that it slides over the upper teeth; one [`Step`] per target sample with the resolved
//!    pose, the contact force (N) and where it acts;
//! 3. [`interpolate_path`]: a target path from an initial to a final pose.
//!
//! # Method
//!
//! Everything is in the upper scan's frame ("world"), in mm, s and kg (forces internally in
//! kg·mm/s² = 1 mN, reported in N). The upper arch is fixed.
//!
//! *Contacts* are measured exactly, per vertex, with the arches' distance indexes: a lower
//! vertex behind the upper surface, or an upper vertex behind the lower surface, penetrates by
//! minus its signed distance. Each nearby vertex `i` gives a constraint linearised in the
//! 6-vector δ = (Δx, Δθ) — translation of the lower arch's centre of mass and small rotation
//! about it: `nᵢ·Δx + (rᵢ×nᵢ)·Δθ ≥ depthᵢ`, where `nᵢ` is the direction the lower arch must
//! move to separate (the upper surface's outward normal for a lower vertex, minus the lower
//! surface's for an upper vertex) and `rᵢ` the vertex's offset from the centre of mass.
//!
//! *Projection*: the smallest δ in the mass/inertia metric, min ½ δᵀMδ with
//! M = diag(m·1, I) subject to all constraints, solved by projected Gauss–Seidel on the dual
//! (one multiplier λᵢ ≥ 0 per vertex, δ = M⁻¹Jᵀλ), applied, and re-measured; rounds repeat
//! until the deepest penetration is within the tolerance. The linearisation is exact for a translation against a
//! flat surface, so this takes one or two rounds. In this metric a rotation costs its inertia:
//! |δ|² = m(|Δx|² + Δθᵀ(I/m)Δθ), i.e. rotations are weighted by the arch's radius of gyration
//! about each axis, so the correction is what moves the arch's mass least.
//!
//! *Dynamics*: position-based contact on a semi-implicit (symplectic) Euler integrator with a
//! fixed step. Each step applies the spring–damper to the velocities, moves the arch, then
//! projects out penetration as above; the velocity change that the projection implies (δ/h) is
//! added to the velocities, which removes the velocity into each contact (inelastic) and makes
//! the contact impulse exactly Jᵀλ/h. Contacts are frictionless (the normals are exact, so a
//! frictionless arch slides along the cusp slopes exactly as the surfaces dictate; friction
//! between wet enamel is small and not modelled). Penetration after each step is within the
//! tolerance by construction, and is checked: a step that cannot reach it is an error.
//!
//! *Cost*: every step measures every vertex of both arches whose distance to the other arch may
//! have changed enough to matter. A vertex measured at distance d is not measured again until
//! the lower arch has moved by d minus a margin (a rigid motion moves no point further than
//! |Δx| + |Δθ|·ρ, ρ the arch's largest distance from its centre of mass), so a step costs a
//! pass over a flag per vertex, exact queries of the vertices near contact, and a few 6×6 solves.
//!
//! Open scans have no inside far from their surface: penetration is only seen within the
//! distance indexes' reach ([`crate::SurfaceIndex::reach`]); a step that moves the arch by more
//! than half the reach is refused.

mod body;
mod error;
mod options;

pub use body::RigidBody;
pub use error::DynamicsError;
pub use options::{DynamicsOptions, MAX_DT_S};

use crate::contacts::{Arch, Side};
use jawtrack_pose::Pose;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use options::above;
use serde::Serialize;
use std::collections::BTreeMap;

/// Vertices within this distance (mm) of the other arch are kept as (possibly inactive)
/// constraints and re-measured after every projection round.
const MARGIN_MM: f64 = 0.05;

/// Projected Gauss–Seidel sweeps per solve, at most.
const MAX_SWEEPS: usize = 500;

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

fn resolve(scene: &mut Scene, pose: &Pose, at: &str) -> Result<Correction, DynamicsError> {
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
/// [`resolve_intercuspation`], moving with the target's velocity. Between samples the target
/// is interpolated linearly in translation and along the shortest rotation, and the interval is
/// split into equal steps of at most `options.dt_s`. `progress(done, total)` is called after
/// each target interval.
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

/// One vertex near or in contact, as a linearised constraint on δ = (Δx, Δθ).
#[derive(Debug, Clone, Copy)]
struct Constraint {
    /// (0 upper, 1 lower, vertex index).
    key: (u8, u32),
    /// Signed distance (mm): negative when penetrating.
    gap: f64,
    /// Unit direction (upper scan frame) the lower arch must move to separate.
    normal: Vector3<f64>,
    /// The vertex's offset from the lower arch's centre of mass × the normal.
    lever_normal: Vector3<f64>,
}

/// What one projection did.
#[derive(Debug, Clone)]
struct Projection {
    dx: Vector3<f64>,
    dtheta: Vector3<f64>,
    /// Per vertex, λ·n (kg·mm): the contact impulse times the step.
    impulses: Vec<((u8, u32), Vector3<f64>)>,
    iterations: usize,
    initial_depth: f64,
    residual_depth: f64,
}

/// A projection that did not reach the tolerance.
struct Unresolved {
    depth: f64,
    iterations: usize,
    tolerance: f64,
}

impl Unresolved {
    fn at(self, at: String) -> DynamicsError {
        DynamicsError::Unresolved {
            at,
            depth_mm: self.depth,
            iterations: self.iterations,
            tolerance_mm: self.tolerance,
        }
    }
}

/// The two arches, the body, and which vertices need measuring.
struct Scene<'a> {
    upper: &'a Arch,
    lower: &'a Arch,
    body: &'a RigidBody,
    tolerance: f64,
    max_iterations: usize,
    reach: f64,
    margin: f64,
    /// The sum of displacement bounds of every move so far (mm).
    travelled: f64,
    /// Per arch (upper, lower), per vertex: the value of `travelled` at which it must be
    /// measured again (its last distance minus the margin, spent).
    due: [Vec<f64>; 2],
}

impl<'a> Scene<'a> {
    fn new(
        upper: &'a Arch,
        lower: &'a Arch,
        body: &'a RigidBody,
        options: &DynamicsOptions,
    ) -> Result<Scene<'a>, DynamicsError> {
        let reach = upper.index.reach().min(lower.index.reach());
        // The margin must leave room for a tolerance's worth of residual and for a step's motion.
        let needed = 8.0 * options.tolerance_mm;
        if reach < needed {
            return Err(DynamicsError::ShortReach {
                reach_mm: reach,
                tolerance_mm: options.tolerance_mm,
                needed_mm: needed,
            });
        }
        Ok(Scene {
            upper,
            lower,
            body,
            tolerance: options.tolerance_mm,
            max_iterations: options.max_iterations,
            reach,
            margin: MARGIN_MM.min(reach / 4.0),
            travelled: 0.0,
            due: [
                vec![f64::NEG_INFINITY; upper.mesh.vertices.len()],
                vec![f64::NEG_INFINITY; lower.mesh.vertices.len()],
            ],
        })
    }

    /// Records a move of the lower arch by at most `bound` mm at any point.
    fn moved(&mut self, bound: f64) {
        self.travelled += bound;
    }

    /// Measures every vertex that may have come within the margin, and returns those that have.
    fn measure(&mut self, pose: &Pose) -> Vec<Constraint> {
        let to_lower = pose.inverse();
        let com = self.body.centre(pose);
        let mut near = Vec::new();
        let (travelled, margin, reach) = (self.travelled, self.margin, self.reach);
        // Upper vertices against the lower surface: the lower arch must move against its normal.
        for (v, q) in self.upper.mesh.vertices.iter().enumerate() {
            if self.due[0][v] > travelled {
                continue;
            }
            let found = self.lower.index.nearest(&to_lower.transform_point(q));
            let gap = found.map_or(reach, |n| n.distance);
            self.due[0][v] = travelled + gap - margin;
            if let Some(n) = found.filter(|n| n.distance < margin) {
                let normal = -pose.transform_vector(&n.normal);
                near.push(Constraint { key: (0, v as u32), gap, normal, lever_normal: (q - com).cross(&normal) });
            }
        }
        // Lower vertices against the upper surface: the lower arch must move along its normal.
        for (v, p) in self.lower.mesh.vertices.iter().enumerate() {
            if self.due[1][v] > travelled {
                continue;
            }
            let p = pose.transform_point(p);
            let found = self.upper.index.nearest(&p);
            let gap = found.map_or(reach, |n| n.distance);
            self.due[1][v] = travelled + gap - margin;
            if let Some(n) = found.filter(|n| n.distance < margin) {
                near.push(Constraint {
                    key: (1, v as u32),
                    gap,
                    normal: n.normal,
                    lever_normal: (p - com).cross(&n.normal),
                });
            }
        }
        near
    }

    /// Moves `pose` by the smallest rigid motion (mass/inertia metric) that leaves no
    /// penetration deeper than the tolerance.
    fn project(&mut self, pose: &mut Pose) -> Result<Projection, Unresolved> {
        let mut out = Projection {
            dx: Vector3::zeros(),
            dtheta: Vector3::zeros(),
            impulses: Vec::new(),
            iterations: 0,
            initial_depth: 0.0,
            residual_depth: 0.0,
        };
        loop {
            let near = self.measure(pose);
            let depth = near.iter().map(|c| -c.gap).fold(f64::NEG_INFINITY, f64::max);
            if out.iterations == 0 {
                out.initial_depth = depth;
            }
            out.residual_depth = depth;
            // Any penetration is removed (to first order) at once: leaving what is within the
            // tolerance would let it build up over steps and come out in bursts of force. Only
            // further rounds wait for the tolerance to be exceeded.
            let within = if out.iterations == 0 { depth <= 0.0 } else { depth <= self.tolerance };
            if within {
                return Ok(out);
            }
            if out.iterations == self.max_iterations {
                return Err(Unresolved { depth, iterations: out.iterations, tolerance: self.tolerance });
            }
            let (_, inertia_inv) = self.body.inertia_world(pose);
            let (dx, dtheta, lambda) = solve(&near, 1.0 / self.body.mass_kg, &inertia_inv, self.tolerance * 1e-3);
            *pose = self.body.displaced(pose, &dx, &dtheta);
            self.moved(self.body.displacement_bound(&dx, &dtheta));
            out.dx += dx;
            out.dtheta += dtheta;
            out.impulses
                .extend(near.iter().zip(&lambda).filter(|(_, l)| **l > 0.0).map(|(c, l)| (c.key, c.normal * *l)));
            out.iterations += 1;
        }
    }
}

/// min ½ δᵀMδ subject to nᵢ·Δx + (rᵢ×nᵢ)·Δθ ≥ −gapᵢ, by projected Gauss–Seidel on the dual:
/// returns Δx, Δθ and the multipliers λᵢ ≥ 0 (with Mδ = Σ λᵢ Jᵢᵀ). Stops when a sweep changes
/// no constraint's value by more than `stop` mm.
fn solve(
    constraints: &[Constraint],
    inverse_mass: f64,
    inverse_inertia: &Matrix3<f64>,
    stop: f64,
) -> (Vector3<f64>, Vector3<f64>, Vec<f64>) {
    // Deepest first: the sweep then starts from the constraints that decide the answer.
    let mut order: Vec<usize> = (0..constraints.len()).collect();
    order.sort_by(|&a, &b| constraints[a].gap.total_cmp(&constraints[b].gap));
    let rows: Vec<(Vector3<f64>, Vector3<f64>, f64)> = constraints
        .iter()
        .map(|c| {
            let (b_lin, b_rot) = (c.normal * inverse_mass, inverse_inertia * c.lever_normal);
            (b_lin, b_rot, c.normal.dot(&b_lin) + c.lever_normal.dot(&b_rot))
        })
        .collect();
    let (mut dx, mut dtheta) = (Vector3::zeros(), Vector3::zeros());
    let mut lambda = vec![0.0; constraints.len()];
    for _ in 0..MAX_SWEEPS {
        let mut largest: f64 = 0.0;
        for &i in &order {
            let (c, (b_lin, b_rot, diagonal)) = (&constraints[i], &rows[i]);
            let violation = -c.gap - (c.normal.dot(&dx) + c.lever_normal.dot(&dtheta));
            let updated = (lambda[i] + violation / diagonal).max(0.0);
            let change = updated - lambda[i];
            if change != 0.0 {
                dx += b_lin * change;
                dtheta += b_rot * change;
                lambda[i] = updated;
                largest = largest.max((change * diagonal).abs());
            }
        }
        if largest <= stop {
            break;
        }
    }
    (dx, dtheta, lambda)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_constraint_is_met_by_the_least_motion() {
        // A contact on the axis through the centre: pure translation along its normal.
        let n = Vector3::new(0.0, 0.0, -1.0);
        let c = Constraint { key: (1, 0), gap: -0.2, normal: n, lever_normal: Vector3::zeros() };
        let (dx, dtheta, lambda) = solve(&[c], 10.0, &Matrix3::identity(), 1e-12);
        assert!((dx - n * 0.2).norm() < 1e-12 && dtheta.norm() < 1e-15, "{dx} {dtheta}");
        assert!((lambda[0] - 0.02).abs() < 1e-12, "{lambda:?}");
        // Two opposite levers: translation only, split between them.
        let lever = Vector3::new(1.0, 0.0, 0.0);
        let a = Constraint { lever_normal: lever, ..c };
        let b = Constraint { lever_normal: -lever, key: (1, 1), ..c };
        let (dx, dtheta, _) = solve(&[a, b], 10.0, &Matrix3::identity(), 1e-12);
        assert!((dx - n * 0.2).norm() < 1e-9 && dtheta.norm() < 1e-9, "{dx} {dtheta}");
    }

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
