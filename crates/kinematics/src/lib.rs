//! Jaw kinematics: what a stream of tracked `maxilla_from_mandible` poses means for the
//! patient's jaw. Where the recording, the viewer, `export`, `plot` and `metrics` read the
//! incisor's opening, they read it here.
//!
//! - [`mounting`]: how the harnesses sit on the head ([`Mounting`]): the head frame, the
//!   markers' rest poses, the hinge axis, the condyles and the lower incisal point.
//! - [`point`]: a point fixed to the mandible (the incisor by default, or a condyle) carried
//!   by tracked poses, and its [`Displacement`] from rest.
//! - [`metrics`]: the incisor's clinical extremes over a session ([`Metrics`]), and how many
//!   times the jaw opened.
//! - [`envelope`]: envelopes of motion as convex hulls in one plane ([`Envelope`]).
//!
//! The head frame: X toward the patient's left, Y down, Z posterior (mm).

pub mod envelope;
pub mod metrics;
pub mod mounting;
pub mod point;

pub use envelope::{Envelope, convex_hull, polygon_area};
pub use metrics::{Extreme, Metrics, Sample};
pub use mounting::{Mounting, Side};
pub use point::{Displacement, Incisor};
