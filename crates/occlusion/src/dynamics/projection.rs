//! The contact constraints and their projection (*Contacts*, *Projection* and *Cost* in the
//! `dynamics` documentation): which vertices of either arch are near or inside the other,
//! each measured again only once the lower arch may have moved far enough to matter, and the
//! least rigid motion of the lower arch, round after round, that leaves no penetration deeper
//! than the tolerance.

use super::body::RigidBody;
use super::error::DynamicsError;
use super::options::DynamicsOptions;
use super::solver::solve;
use crate::contacts::Arch;
use jawtrack_pose::Pose;
use nalgebra::Vector3;

/// Vertices within this distance (mm) of the other arch are kept as (possibly inactive)
/// constraints and re-measured after every projection round.
const MARGIN_MM: f64 = 0.05;

/// One vertex near or in contact, as a linearised constraint on δ = (Δx, Δθ).
#[derive(Debug, Clone, Copy)]
pub(super) struct Constraint {
    /// (0 upper, 1 lower, vertex index).
    pub(super) key: (u8, u32),
    /// Signed distance (mm): negative when penetrating.
    pub(super) gap: f64,
    /// Unit direction (upper scan frame) the lower arch must move to separate.
    pub(super) normal: Vector3<f64>,
    /// The vertex's offset from the lower arch's centre of mass × the normal.
    pub(super) lever_normal: Vector3<f64>,
}

/// What one projection did.
#[derive(Debug, Clone)]
pub(super) struct Projection {
    pub(super) dx: Vector3<f64>,
    pub(super) dtheta: Vector3<f64>,
    /// Per vertex, λ·n (kg·mm): the contact impulse times the step.
    pub(super) impulses: Vec<((u8, u32), Vector3<f64>)>,
    pub(super) iterations: usize,
    pub(super) initial_depth: f64,
    pub(super) residual_depth: f64,
}

/// A projection that did not reach the tolerance.
pub(super) struct Unresolved {
    depth: f64,
    iterations: usize,
    tolerance: f64,
}

impl Unresolved {
    pub(super) fn at(self, at: String) -> DynamicsError {
        DynamicsError::Unresolved {
            at,
            depth_mm: self.depth,
            iterations: self.iterations,
            tolerance_mm: self.tolerance,
        }
    }
}

/// The two arches, the body, and which vertices need measuring.
pub(super) struct Scene<'a> {
    upper: &'a Arch,
    lower: &'a Arch,
    pub(super) body: &'a RigidBody,
    tolerance: f64,
    max_iterations: usize,
    pub(super) reach: f64,
    margin: f64,
    /// The sum of displacement bounds of every move so far (mm).
    travelled: f64,
    /// Per arch (upper, lower), per vertex: the value of `travelled` at which it must be
    /// measured again (its last distance minus the margin, spent).
    due: [Vec<f64>; 2],
}

impl<'a> Scene<'a> {
    pub(super) fn new(
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
    pub(super) fn moved(&mut self, bound: f64) {
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
    pub(super) fn project(&mut self, pose: &mut Pose) -> Result<Projection, Unresolved> {
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
