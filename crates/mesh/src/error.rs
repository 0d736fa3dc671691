//! Why a mesh could not be read, written or used: one error for every file and check, each
//! naming the file.

use crate::PLAUSIBLE_EXTENT_MM;

/// Why a mesh could not be used.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
    /// The file's extension is not one we read.
    #[error("{path}: unknown mesh format (expected .stl, .ply or .obj)")]
    Format {
        /// The file.
        path: String,
    },
    /// The file's content is not a mesh of its format.
    #[error("{path}: not a readable {format} mesh: {reason}")]
    Corrupt {
        /// The file.
        path: String,
        /// STL, PLY or OBJ.
        format: &'static str,
        /// The parser's complaint.
        reason: String,
    },
    /// No triangles.
    #[error("{path}: the mesh has no triangles")]
    Empty {
        /// The file.
        path: String,
    },
    /// A coordinate is NaN or infinite, or an index points past the vertices.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// The bounding box is implausible for millimetres.
    #[error(
        "{path}: the mesh is {extent} across its largest side; a tooth scan in millimetres is {lo}-{hi} mm, so this looks like {guess} (convert the file to mm)",
        lo = PLAUSIBLE_EXTENT_MM.0, hi = PLAUSIBLE_EXTENT_MM.1
    )]
    Units {
        /// The file.
        path: String,
        /// The largest side of the bounding box, in the file's units.
        extent: f64,
        /// What the units look like.
        guess: &'static str,
    },
}
