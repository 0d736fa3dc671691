//! Harness CAD for the JawTrack marker: what the `jawtrack harness --out DIR` subcommand
//! writes so that a marker pair can be made by hand.
//!
//! * [`sheet`]: printable tag sheets, one per jaw body, as SVG in true millimetres — each tag
//!   printed on its face's polygon (a pentagon, or a cube's square), cut out and glued on.
//! * [`body`]: the marker's solid fused with a cylindrical mounting post that leaves the
//!   −Z vertex, as a closed triangle mesh ([`Mesh`], from [`jawtrack_mesh`]) written as binary STL.
//! * [`write_harness`]: writes all of it, plus the marker file, into one folder.
//!
//! The solid's geometry comes from [`jawtrack_marker`] and the tag patterns from
//! [`jawtrack_apriltag`]; nothing here recomputes either. All lengths are millimetres.

pub mod body;
pub mod sheet;

use jawtrack_marker::{BodyKind, Marker, MarkerError, SolidKind};
use std::path::{Path, PathBuf};

pub use body::{body_mesh, max_post_diameter};
pub use jawtrack_mesh::Mesh;
pub use sheet::{tag_sheet_svg, tag_sheet_svg_with_post};

/// File name of the default marker's body mesh written by [`write_harness`].
pub const BODY_STL_NAME: &str = "dodecahedron-with-post.stl";

/// File name of the body mesh [`write_harness`] writes for a marker on `solid`:
/// `dodecahedron-with-post.stl` ([`BODY_STL_NAME`]) or `cube-with-post.stl`.
pub fn body_stl_name(solid: SolidKind) -> String {
    format!("{}-with-post.stl", solid.name())
}

/// File name of the marker file written by [`write_harness`].
pub const MARKER_JSON_NAME: &str = "marker.json";

/// File name of a body's tag sheet written by [`write_harness`]: `tags-maxilla.svg` or
/// `tags-mandible.svg`.
pub fn sheet_file_name(body: BodyKind) -> String {
    format!("tags-{}.svg", body.name())
}

/// The mounting post's parameters (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarnessParams {
    /// Length of the post below the −Z vertex, measured along −Z from the vertex to the end
    /// cap (mm).
    pub post_length: f64,
    /// Diameter of the post (mm): the circumscribed diameter of its N-gon cross-section.
    pub post_diameter: f64,
    /// Number of sides N of the post's cross-section; a multiple of 3 so that three of its
    /// corners lie on the three edges leaving the −Z vertex.
    pub post_segments: usize,
}

impl Default for HarnessParams {
    /// A 25 mm long, 4 mm thick post with 48 sides.
    fn default() -> Self {
        HarnessParams { post_length: 25.0, post_diameter: 4.0, post_segments: 48 }
    }
}

/// Shortest post length and thinnest post diameter accepted (mm): below this no printer makes
/// it, and the mesh would be made of slivers.
pub const MIN_POST_MM: f64 = 0.1;

/// Longest post length and thickest post diameter accepted (mm): far beyond any harness, and
/// it keeps the single-precision STL coordinates exact to well under a micrometre.
pub const MAX_POST_MM: f64 = 1000.0;

/// Most sides a post may have: far more than any printer resolves, and it keeps a typo from
/// producing a gigabyte mesh.
pub const MAX_POST_SEGMENTS: usize = 3600;

impl HarnessParams {
    /// Checks each number on its own (the fit of the post on the faces is checked by
    /// [`body_mesh`]). Errors name the parameter.
    pub fn validate(&self) -> Result<(), HarnessError> {
        for (name, value) in [("post_length", self.post_length), ("post_diameter", self.post_diameter)] {
            if !value.is_finite() || value <= 0.0 {
                return Err(HarnessError::Param {
                    name,
                    reason: format!("must be a positive number of mm, got {value}"),
                });
            }
            if !(MIN_POST_MM..=MAX_POST_MM).contains(&value) {
                return Err(HarnessError::Param {
                    name,
                    reason: format!("must be between {MIN_POST_MM} and {MAX_POST_MM} mm, got {value}"),
                });
            }
        }
        let n = self.post_segments;
        if n < 3 || !n.is_multiple_of(3) || n > MAX_POST_SEGMENTS {
            return Err(HarnessError::Param {
                name: "post_segments",
                reason: format!(
                    "must be a multiple of 3 between 3 and {MAX_POST_SEGMENTS} (three corners of the post sit on the \
                     three edges leaving the vertex), got {n}"
                ),
            });
        }
        Ok(())
    }
}

/// Everything that can go wrong while making the harness files.
#[derive(Debug, thiserror::Error)]
pub enum HarnessError {
    /// A parameter is out of range on its own.
    #[error("invalid `{name}`: {reason}")]
    Param {
        /// The parameter's name (`post_length`, `post_diameter`, `post_segments`).
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The post's footprint on a bottom face reaches past that face's far edges.
    #[error(
        "`post_diameter` {diameter} mm is wider than face {face} can hold: the post's footprint reaches {overshoot:.3} mm \
         past the face's edge (at most {max_diameter:.3} mm fits this marker)"
    )]
    PostTooWide {
        /// The requested diameter (mm).
        diameter: f64,
        /// The face it does not fit on.
        face: usize,
        /// How far the footprint reaches past the face (mm).
        overshoot: f64,
        /// The largest diameter that fits (mm).
        max_diameter: f64,
    },
    /// The post's footprint on a bottom face cuts into the black square of the tag there.
    #[error(
        "`post_diameter` {diameter} mm is too thick: the post's footprint on face {face} cuts {depth:.3} mm into the \
         black square of the tag there (id {maxilla_id} on the maxilla, id {mandible_id} on the mandible); at most \
         {max_diameter:.3} mm fits (smaller tags, `jawtrack marker --tag-size`, leave room for a thicker post)"
    )]
    PostCoversTag {
        /// The requested diameter (mm).
        diameter: f64,
        /// The face.
        face: usize,
        /// Id of the nominal maxilla tag on that face.
        maxilla_id: u32,
        /// Id of the nominal mandible tag on that face.
        mandible_id: u32,
        /// How deep the footprint reaches into the square (mm): the least shift that would
        /// separate them.
        depth: f64,
        /// The largest diameter that clears the tags (mm).
        max_diameter: f64,
    },
    /// The marker's edge or tag size is impossible, or the marker is otherwise unusable.
    #[error("marker: {0}")]
    Marker(#[from] MarkerError),
    /// The marker has no body of the requested kind.
    #[error("the marker has no {0} body")]
    MissingBody(BodyKind),
    /// The marker has no tags at all.
    #[error("the marker has no tags to print")]
    NoTags,
    /// The tags differ in size, so no single body and sheet layout fits them all.
    #[error(
        "the marker's tags are not all the same size: tag {first_id} is {first} mm but tag {other_id} is {other} mm"
    )]
    MixedTagSizes {
        /// A tag id.
        first_id: u32,
        /// Its size (mm).
        first: f64,
        /// Another tag id.
        other_id: u32,
        /// Its different size (mm).
        other: f64,
    },
    /// A tag id the marker's family does not have.
    #[error("tag id {id} is not in the {family} family (ids 0–{last})")]
    UnknownTag {
        /// The id.
        id: u32,
        /// The marker's family.
        family: &'static str,
        /// Its last id.
        last: usize,
    },
    /// A tag on a face number the marker's solid does not have.
    #[error("tag {id} is on face {face}, but the marker's solid has faces 0–{last}")]
    BadFace {
        /// The tag id.
        id: u32,
        /// Its face number.
        face: usize,
        /// The solid's last face number.
        last: usize,
    },
    /// The tags are too large for one A4 sheet.
    #[error("the tags of a marker with edge {edge} mm do not fit on one A4 sheet (210 × 297 mm)")]
    SheetTooSmall {
        /// The marker edge (mm).
        edge: f64,
    },
    /// A file could not be written.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// The system's reason.
        reason: String,
    },
    /// The construction found the solid not as documented; a bug, not bad input.
    #[error("internal geometry error (please report): {0}")]
    Geometry(String),
}

/// The common size of all the marker's tags (mm); errors if there are none or they differ.
pub fn common_tag_size(marker: &Marker) -> Result<f64, HarnessError> {
    let mut tags = marker.tags().map(|(_, t)| t);
    let first = tags.next().ok_or(HarnessError::NoTags)?;
    for t in tags {
        if (t.size - first.size).abs() > 1e-9 * first.size.abs().max(1.0) {
            return Err(HarnessError::MixedTagSizes {
                first_id: first.id,
                first: first.size,
                other_id: t.id,
                other: t.size,
            });
        }
    }
    Ok(first.size)
}

/// Writes the harness files for `marker` into `dir` (created if missing): one tag sheet per
/// body the marker has (`tags-maxilla.svg`, `tags-mandible.svg`, with the post's notch
/// marked on the bottom faces), the body with its post ([`body_stl_name`]:
/// `dodecahedron-with-post.stl` or `cube-with-post.stl`) and the marker file (`marker.json`).
/// Returns the written paths in that order.
///
/// The solid, edge and tag size are the marker's (`marker.solid`, `marker.edge`, the tags'
/// common size); the
/// sheets print every tag centred on its face, as the nominal marker has it.
pub fn write_harness(dir: &Path, marker: &Marker, params: &HarnessParams) -> Result<Vec<PathBuf>, HarnessError> {
    let tag_size = common_tag_size(marker)?;
    // Build everything before writing anything, so bad parameters leave no half-written folder.
    let mesh = body_mesh(marker.solid, marker.edge, tag_size, params)?;
    let mut sheets = Vec::new();
    for body in &marker.bodies {
        sheets.push((sheet_file_name(body.kind), tag_sheet_svg_with_post(marker, body.kind, params)?));
    }
    let io_err =
        |path: &Path, e: std::io::Error| HarnessError::Io { path: path.display().to_string(), reason: e.to_string() };
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;

    let mut written = Vec::new();
    for (name, svg) in sheets {
        let path = dir.join(name);
        std::fs::write(&path, svg).map_err(|e| io_err(&path, e))?;
        written.push(path);
    }
    let stl_path = dir.join(body_stl_name(marker.solid));
    let file = std::fs::File::create(&stl_path).map_err(|e| io_err(&stl_path, e))?;
    mesh.write_stl(file).map_err(|e| io_err(&stl_path, e))?;
    written.push(stl_path);
    let json_path = dir.join(MARKER_JSON_NAME);
    marker.save(&json_path)?;
    written.push(json_path);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("jawtrack-harness-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// The checked-in body (`harness-cad/`) is what the defaults write, byte for byte: a
    /// change to the geometry or the STL writer shows here, and the file is regenerated with
    /// `jawtrack harness --out harness-cad`.
    #[test]
    fn the_checked_in_body_stl_is_what_the_defaults_write() {
        let checked_in = include_bytes!("../../../harness-cad/dodecahedron-with-post.stl");
        let marker = Marker::default();
        let size = common_tag_size(&marker).expect("one tag size");
        let mesh = body_mesh(marker.solid, marker.edge, size, &HarnessParams::default()).expect("defaults fit");
        let mut bytes = Vec::new();
        mesh.write_stl(&mut bytes).expect("write to memory");
        assert!(bytes == checked_in, "harness-cad/{BODY_STL_NAME} differs from what the defaults write");
    }

    #[test]
    fn write_harness_writes_the_four_files() {
        let dir = temp_dir("write");
        let marker = Marker::default();
        let paths = write_harness(&dir, &marker, &HarnessParams::default()).expect("writes");
        let names: Vec<String> =
            paths.iter().map(|p| p.file_name().expect("file").to_string_lossy().into_owned()).collect();
        assert_eq!(names, ["tags-maxilla.svg", "tags-mandible.svg", "dodecahedron-with-post.stl", "marker.json"]);
        for p in &paths {
            assert!(std::fs::metadata(p).expect("exists").len() > 0, "{}", p.display());
        }
        let back = Marker::load(&dir.join(MARKER_JSON_NAME)).expect("marker file reads back");
        assert_eq!(back.edge, marker.edge);
        let mut f = std::fs::File::open(dir.join(BODY_STL_NAME)).expect("stl");
        let stl = stl_io::read_stl(&mut f).expect("reads back");
        stl.validate().expect("stl_io finds it closed");
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn bad_parameters_write_nothing() {
        let dir = temp_dir("bad");
        let params = HarnessParams { post_diameter: -1.0, ..HarnessParams::default() };
        let err = write_harness(&dir, &Marker::default(), &params).expect_err("invalid").to_string();
        assert!(err.contains("post_diameter"), "{err}");
        assert!(!dir.exists());
    }

    #[test]
    fn mixed_tag_sizes_are_refused() {
        let mut marker = Marker::default();
        marker.bodies[1].tags[3].size *= 0.9;
        let err = common_tag_size(&marker).expect_err("mixed").to_string();
        assert!(err.contains("tag 15"), "{err}");
        let dir = temp_dir("mixed");
        assert!(write_harness(&dir, &marker, &HarnessParams::default()).is_err());
        assert!(!dir.exists());
    }

    #[test]
    fn parameters_are_checked_by_name() {
        let base = HarnessParams::default();
        assert!(base.validate().is_ok());
        for (p, word) in [
            (HarnessParams { post_length: 0.0, ..base }, "post_length"),
            (HarnessParams { post_length: f64::NAN, ..base }, "post_length"),
            (HarnessParams { post_length: f64::INFINITY, ..base }, "post_length"),
            (HarnessParams { post_diameter: -2.0, ..base }, "post_diameter"),
            (HarnessParams { post_diameter: f64::NAN, ..base }, "post_diameter"),
            (HarnessParams { post_diameter: 1e-300, ..base }, "post_diameter"),
            (HarnessParams { post_length: 1e6, ..base }, "post_length"),
            (HarnessParams { post_segments: 47, ..base }, "post_segments"),
            (HarnessParams { post_segments: 0, ..base }, "post_segments"),
            (HarnessParams { post_segments: 3603, ..base }, "post_segments"),
        ] {
            let err = p.validate().expect_err("invalid").to_string();
            assert!(err.contains(word), "{err}");
        }
    }
}
