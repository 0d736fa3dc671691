//! Occlusal contacts on intra-oral scans.
//!
//! - [`mesh`]: the triangle mesh, reading STL/PLY/OBJ in millimetres and checking them: the
//!   `jawtrack-mesh` crate, re-exported under its old path with its items at the top level;
//!   [`load_mesh`] reads a scan with clear errors for empty, cut-short or flat files and any
//!   ASCII STL;
//! - [`distance`]: exact signed distances from points to a scan surface, within a reach, and
//!   [`scenes`], test meshes with known answers: both now `jawtrack-mesh`'s, re-exported under
//!   their old paths;
//! - [`contacts`]: where two arches touch or come within a threshold at one pose, grouped into
//!   regions, and the contact-frequency map over a motion;
//! - [`session`]: the contacts of a motion frame by frame, with the tallies and statistics
//!   over all its frames; [`depth_cap`]: what they cannot measure (contacts deeper than the
//!   depth measured, arches never in occlusion), in words;
//! - [`occlusal_view`]: an arch rendered in its occlusal view with per-vertex colours, and
//!   the legend of the contact-frequency colours;
//! - [`teeth`]: FDI and Universal tooth numbers, each tooth's contacts over a session;
//! - [`contact_map`]: an occlusal view as an SVG a clinician reads (side, tooth numbers, scale
//!   bar, colour scale in mm);
//! - [`dynamics`]: the mandible as a rigid body sliding over the maxillary teeth.
//!
//! Everything is in the upper scan's frame unless a name says otherwise, in mm.

pub mod contact_map;
pub mod contacts;
pub mod depth_cap;
pub mod dynamics;
mod mesh_file;
pub mod occlusal_view;
pub mod session;
pub mod teeth;

pub use mesh_file::load_mesh;

pub use distance::{Nearest, Surface, SurfaceIndex, nearest_brute_force};
pub use jawtrack_mesh as mesh;
pub use jawtrack_mesh::{Mesh, MeshError, MeshReport, PLAUSIBLE_EXTENT_MM};
pub use jawtrack_mesh::{distance, scenes};
