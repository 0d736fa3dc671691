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
//! 3. [`interpolate_path`]: a target path from an initial to a final pose;
//! 4. [`resolve_path`]: a recorded path through 1 and 2, with the peak force, residual
//!    penetration and largest offset from the recording that a report gives.
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
mod integrator;
mod intercuspation;
mod options;
mod path;
mod projection;
mod resolve;
mod solver;

pub use body::RigidBody;
pub use error::DynamicsError;
pub use integrator::{ContactForce, Step, simulate, simulate_with_progress};
pub use intercuspation::{Correction, resolve_intercuspation};
pub use options::{DynamicsOptions, MAX_DT_S};
pub use path::interpolate_path;
pub use resolve::{CorrectionSummary, PathSummary, ResolveError, ResolvedPath, StepSummary, resolve_path};
