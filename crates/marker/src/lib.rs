//! The marker: the solid a body is ([`solid`], the dodecahedron by default, or a cube), the
//! tags laid on its faces and the two jaw bodies that carry them ([`model`]), and the versioned
//! JSON marker file ([`file`](mod@file)).
//!
//! All lengths are millimetres, all points in a body's frame (see [`solid`]).

mod describe;
pub mod dodecahedron;
pub mod file;
pub mod model;
pub mod solid;

pub use file::MARKER_FILE_VERSION;
/// The tag family a marker is printed in (re-exported: it is part of [`Marker`]).
pub use jawtrack_tag_family::TagFamily;
pub use model::{
    Body, BodyKind, BodyProvenance, DEFAULT_EDGE_MM, Marker, PrintError, TAG_CORNERS, TAGS_PER_BODY, Tag,
    TagProvenance, default_tag_size, default_tag_size_of,
};
pub use solid::{Face, Solid, SolidKind};

/// Errors from building, reading or checking a marker.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum MarkerError {
    /// The text is not JSON (NaN and Infinity are not JSON either).
    #[error("marker file is not valid JSON: {0}")]
    Json(String),
    /// The file's `version` is not one this build reads.
    #[error("unsupported marker file version {found} (this build reads versions 1 to 3)")]
    Version {
        /// The version found.
        found: String,
    },
    /// A field is missing or holds a value that cannot be right.
    #[error("{location}: `{field}` {reason}")]
    Field {
        /// Which body and tag.
        location: String,
        /// Which field.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// Parameters that cannot make a marker (negative edge, tag larger than its face, …).
    #[error("impossible marker parameters: {0}")]
    Params(String),
    /// The file could not be read or written.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// The system's reason.
        reason: String,
    },
    /// A body the job needs is not in the marker (a jaw pose needs both).
    #[error(
        "has no {missing} body; tracking the jaw needs both the maxilla and the mandible (`jawtrack marker` \
         writes a complete nominal file)"
    )]
    MissingBody {
        /// The bodies missing, in words ("mandible", "maxilla or mandible").
        missing: String,
    },
    /// An error inside a named file. Shown whole here and not chained as a source, or reports
    /// that print the chain would say it twice.
    #[error("{path}: {error}")]
    InFile {
        /// The file.
        path: String,
        /// The error.
        error: Box<MarkerError>,
    },
}

impl MarkerError {
    fn in_file(self, path: &std::path::Path) -> Self {
        MarkerError::InFile { path: path.display().to_string(), error: Box::new(self) }
    }
}
