//! Geometry shared by everything that reasons about where things are: rigid transforms in
//! millimetres ([`Pose`]), the pinhole camera with radial distortion ([`CameraIntrinsics`]),
//! the pose of a rigid body from its points in an image ([`pnp`]), a body moving while a rolling
//! shutter reads the frame ([`motion`]), and the median its users
//! share ([`median`]).
//!
//! Conventions: camera frame x right, y down, z forward (OpenCV); pixel centres at integer
//! coordinates, (0, 0) the centre of the top-left pixel. A transform is named for what it maps:
//! `camera_from_maxilla` maps maxilla-frame points into the camera frame.

mod camera;
pub mod lm;
pub mod motion;
pub mod pnp;
mod rigid;
pub mod stats;

pub use camera::CameraIntrinsics;
pub use motion::{RollingShutter, Velocity};
pub use pnp::{Alternative, BodyPose, Observation, PnpError, PnpOptions, solve_pnp};
pub use rigid::Pose;
pub use stats::median;

/// Errors from building geometry out of untrusted numbers.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GeometryError {
    /// A value that must be finite was NaN or infinite.
    #[error("{what} is not finite")]
    NotFinite {
        /// Which value.
        what: String,
    },
    /// A 4×4 matrix whose last row is not (0, 0, 0, 1).
    #[error("{what}: last row must be 0 0 0 1")]
    NotAffine {
        /// Which matrix.
        what: String,
    },
    /// A rotation block that is not orthonormal with determinant +1.
    #[error("{what}: rotation block is not a proper rotation (orthonormality error {error:.2e})")]
    NotRotation {
        /// Which matrix.
        what: String,
        /// Largest deviation of RᵀR from the identity, or of det R from 1.
        error: f64,
    },
    /// Intrinsics that cannot describe a camera.
    #[error("intrinsics: {0}")]
    BadIntrinsics(String),
    /// A rolling shutter that cannot be.
    #[error("rolling shutter: {0}")]
    BadShutter(String),
    /// A pose written as text that does not read as one ([`Pose`]'s `FromStr`).
    #[error("{0}")]
    BadText(String),
}
