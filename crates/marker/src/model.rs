//! Tags on a solid's faces and the two jaw bodies that carry them.
//!
//! A tag is the black-border square of side `size` (the "tag size" of AprilTag), centred on
//! its face, its +y axis toward the face's apex and its +x axis parallel to the opposite edge
//! (see [`crate::solid`]). Its corners are listed in the AprilTag reference library's
//! detection order: tag coordinates (−1,+1), (+1,+1), (+1,−1), (−1,−1) with y down in the
//! upright tag image — bottom-left, bottom-right, top-right, top-left.

use crate::MarkerError;
use crate::solid::{Face, Solid, SolidKind};
use jawtrack_tag_family::TagFamily;
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

/// Corners in tag coordinates, in detection order (bottom-left, bottom-right, top-right, top-left).
pub const TAG_CORNERS: [(f64, f64); 4] = [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)];

/// Default edge length of the printed dodecahedron (mm): half an inch.
pub const DEFAULT_EDGE_MM: f64 = 12.7;

/// Tag ids each body reserves: the mandible's nominal ids start here whatever the solid (the
/// dodecahedron's 12 faces fill them; a cube's 6 leave ids 6–11 and 18–23 unused).
pub const TAGS_PER_BODY: u32 = 12;

/// Which jaw a marker body is attached to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BodyKind {
    /// Upper jaw; nominal tag ids 0–11 on faces 0–11.
    Maxilla,
    /// Lower jaw; nominal tag ids 12–23 on faces 0–11.
    Mandible,
}

impl BodyKind {
    /// Both bodies, maxilla first.
    pub const ALL: [BodyKind; 2] = [BodyKind::Maxilla, BodyKind::Mandible];

    /// The name used in files: `maxilla` or `mandible`.
    pub fn name(self) -> &'static str {
        match self {
            BodyKind::Maxilla => "maxilla",
            BodyKind::Mandible => "mandible",
        }
    }

    /// Parses a file name of a body.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "maxilla" => Some(BodyKind::Maxilla),
            "mandible" => Some(BodyKind::Mandible),
            _ => None,
        }
    }

    /// The id of the tag on face 0 of the nominal marker.
    pub fn first_id(self) -> u32 {
        match self {
            BodyKind::Maxilla => 0,
            BodyKind::Mandible => TAGS_PER_BODY,
        }
    }
}

impl std::fmt::Display for BodyKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One tag on one face of a body, every point in the body frame (mm).
#[derive(Debug, Clone, PartialEq)]
pub struct Tag {
    /// Id in the marker's family.
    pub id: u32,
    /// Number of the face it is glued on (0 to the solid's faces − 1).
    pub face: usize,
    /// Side of the black-border square (mm).
    pub size: f64,
    /// Corners in detection order (see the module doc).
    pub corners: [Vector3<f64>; 4],
    /// Centre of the tag.
    pub center: Vector3<f64>,
    /// The face's polygon, apex first, counter-clockwise seen from outside.
    pub face_polygon: Vec<Vector3<f64>>,
    /// How its placement was established; `None` when unknown (a nominal marker, or a file
    /// from before marker file version 2).
    pub provenance: Option<TagProvenance>,
}

/// How a tag's placement was established by a marker calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TagProvenance {
    /// Kept where the model (or the assembly check) puts it: seen in too few views to be
    /// calibrated.
    Nominal {
        /// Views it was seen in beside another tag of its body (0 when never seen).
        views: u32,
    },
    /// Placed by the bundle adjustment.
    Calibrated {
        /// Views it was seen in.
        views: u32,
        /// Its RMS reprojection error (px) with the nominal placement, each view's pose fitted.
        rms_before_px: f64,
        /// … and with the calibrated one.
        rms_after_px: f64,
    },
}

impl TagProvenance {
    /// Views the tag was seen in during the calibration.
    pub fn views(&self) -> u32 {
        match *self {
            TagProvenance::Nominal { views } | TagProvenance::Calibrated { views, .. } => views,
        }
    }

    /// Whether the bundle adjustment placed the tag.
    pub fn is_calibrated(&self) -> bool {
        matches!(self, TagProvenance::Calibrated { .. })
    }
}

/// How a body's tags were calibrated: the whole body's reprojection error and its sources.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyProvenance {
    /// Views that showed two of its tags or more.
    pub views: u32,
    /// RMS reprojection error (px) over its tags' corners with the nominal marker …
    pub rms_before_px: f64,
    /// … and with the calibrated one.
    pub rms_after_px: f64,
    /// The recordings calibrated from (a frames folder, a video), as given.
    pub recordings: Vec<String>,
}

impl Tag {
    /// Outward unit normal of the face (Newell's method over the pentagon).
    pub fn face_normal(&self) -> Vector3<f64> {
        newell_normal(&self.face_polygon)
    }

    /// The tag's own unit axes in the body frame, from its corners: x right and y down in the
    /// upright tag image. For a nominal tag they equal the face's axes.
    pub fn axes(&self) -> (Vector3<f64>, Vector3<f64>) {
        let [bl, br, tr, tl] = self.corners;
        let x = ((br - bl) + (tr - tl)).normalize();
        let y = ((bl - tl) + (br - tr)).normalize();
        (x, y)
    }

    /// The point of the tag plane at tag coordinates (u, v) ∈ [−1, 1]² (bilinear in the
    /// corners, which is exact for the square of a nominal or print-displaced tag).
    pub fn point_at(&self, u: f64, v: f64) -> Vector3<f64> {
        let [bl, br, tr, tl] = self.corners;
        let s = (u + 1.0) / 2.0;
        let t = (1.0 - v) / 2.0; // 0 at the bottom edge (v = +1), 1 at the top (v = −1)
        let bottom = bl + (br - bl) * s;
        let top = tl + (tr - tl) * s;
        bottom + (top - bottom) * t
    }
}

/// A print or placement error of one tag: where the printed square really sits on its face
/// relative to where the nominal model puts it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PrintError {
    /// Shift along the tag's x axis (mm).
    pub shift_x: f64,
    /// Shift along the tag's y axis (mm).
    pub shift_y: f64,
    /// In-plane rotation about the outward normal (rad, counter-clockwise seen from outside).
    pub rotation: f64,
}

/// The tags of one jaw.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Which jaw.
    pub kind: BodyKind,
    /// Its tags (at most one per face).
    pub tags: Vec<Tag>,
    /// Its calibration; `None` when unknown (a nominal marker, an old file, or a body no
    /// calibration saw). Present exactly when its tags' provenance is.
    pub provenance: Option<BodyProvenance>,
}

/// Both bodies of a printed marker pair.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// The AprilTag family its tags are printed in (tag36h11 unless the file names another).
    pub family: TagFamily,
    /// The solid each body is (the dodecahedron unless the file names another).
    pub solid: SolidKind,
    /// Nominal edge length of the solid (mm).
    pub edge: f64,
    /// The bodies, at most one of each kind.
    pub bodies: Vec<Body>,
}

impl Default for Marker {
    fn default() -> Self {
        Marker::nominal(DEFAULT_EDGE_MM, None).expect("the default parameters are valid")
    }
}

/// The white margin a tag of side `size` leaves inside `face` (mm): the least distance from
/// the square to the pentagon's edges, the square being centred with the face's axes.
fn margin(face: &Face, size: f64) -> f64 {
    let r = face.inradius();
    face.edge_normals()
        .iter()
        .map(|e| r - 0.5 * size * (e.dot(&face.x_axis).abs() + e.dot(&face.y_axis).abs()))
        .fold(f64::INFINITY, f64::min)
}

/// The largest tag36h11 tag (mm) that leaves a white margin of one tag cell (size/8) inside a
/// face of a dodecahedron with this edge: size = min over edges of r / (½(|e·x| + |e·y|) + ⅛),
/// with r the pentagon's inradius and e each edge's in-plane normal.
pub fn default_tag_size(edge: f64) -> f64 {
    default_tag_size_of(SolidKind::Dodecahedron, &TagFamily::TAG36H11, edge)
}

/// [`default_tag_size`] for a tag of `family`, whose cell is size / (cells across its border),
/// on a face of `solid`.
pub fn default_tag_size_of(solid: SolidKind, family: &TagFamily, edge: f64) -> f64 {
    let cell = 1.0 / family.width_at_border as f64;
    let d = Solid::new(solid, edge);
    let face = &d.faces()[0];
    let r = face.inradius();
    face.edge_normals()
        .iter()
        .map(|e| r / (0.5 * (e.dot(&face.x_axis).abs() + e.dot(&face.y_axis).abs()) + cell))
        .fold(f64::INFINITY, f64::min)
}

impl Marker {
    /// The ideal marker pair in tag36h11: `edge` (mm) and tag side `tag_size` (mm, default
    /// [`default_tag_size`]), maxilla ids 0–11 and mandible ids 12–23 on faces 0–11.
    pub fn nominal(edge: f64, tag_size: Option<f64>) -> Result<Marker, MarkerError> {
        Marker::nominal_of(TagFamily::TAG36H11, edge, tag_size)
    }

    /// [`Marker::nominal`] printed in `family` (its default tag size: [`default_tag_size_of`]).
    pub fn nominal_of(family: TagFamily, edge: f64, tag_size: Option<f64>) -> Result<Marker, MarkerError> {
        Marker::nominal_on(SolidKind::Dodecahedron, family, edge, tag_size)
    }

    /// The ideal marker pair on `solid` printed in `family`: one tag centred on each face,
    /// maxilla ids from 0 and mandible ids from [`TAGS_PER_BODY`] in face order.
    ///
    /// # Examples
    ///
    /// ```
    /// use jawtrack_marker::{BodyKind, Marker, SolidKind};
    /// use jawtrack_tag_family::TagFamily;
    ///
    /// let cube = Marker::nominal_on(SolidKind::Cube, TagFamily::TAG36H11, 12.7, None)?;
    /// let ids: Vec<u32> = cube.body(BodyKind::Mandible).unwrap().tags.iter().map(|t| t.id).collect();
    /// assert_eq!(ids, [12, 13, 14, 15, 16, 17]);
    /// // The largest tag that keeps one cell of white margin: 8 cells of 10 across the face.
    /// assert!((cube.tags().next().unwrap().1.size - 0.8 * 12.7).abs() < 1e-9);
    /// # Ok::<(), jawtrack_marker::MarkerError>(())
    /// ```
    pub fn nominal_on(
        solid: SolidKind,
        family: TagFamily,
        edge: f64,
        tag_size: Option<f64>,
    ) -> Result<Marker, MarkerError> {
        let faces = solid.face_count() as u32;
        let last_id = BodyKind::Mandible.first_id() + faces - 1;
        if family.count() <= last_id as usize {
            return Err(MarkerError::Params(format!(
                "{} has {} tags; a marker pair on a {solid} needs ids 0–{last_id}",
                family.name,
                family.count(),
            )));
        }
        if !edge.is_finite() || edge <= 0.0 {
            return Err(MarkerError::Params(format!("the edge length must be a positive number of mm, got {edge}")));
        }
        let shape = Solid::new(solid, edge);
        let largest = default_tag_size_of(solid, &family, edge);
        let cells = family.width_at_border as f64;
        let size = tag_size.unwrap_or(largest);
        if !size.is_finite() || size <= 0.0 {
            return Err(MarkerError::Params(format!("the tag size must be a positive number of mm, got {size}")));
        }
        let face0 = &shape.faces()[0];
        let polygon = solid.face_shape();
        if margin(face0, size) < 0.0 {
            return Err(MarkerError::Params(format!(
                "a {size} mm tag is larger than its face: it does not fit inside a {polygon} of edge {edge} mm \
                 (the largest tag that keeps a one-cell white margin is {largest:.3} mm)"
            )));
        }
        if margin(face0, size) < size / cells - 1e-9 {
            return Err(MarkerError::Params(format!(
                "a {size} mm tag leaves less than one cell ({:.3} mm) of white margin inside its face, which the \
                 detector needs; the largest tag with that margin on a {edge} mm face is {largest:.3} mm",
                size / cells
            )));
        }
        let bodies = BodyKind::ALL
            .iter()
            .map(|&kind| Body {
                kind,
                tags: shape.faces().iter().map(|f| nominal_tag(f, kind.first_id() + f.index as u32, size)).collect(),
                provenance: None,
            })
            .collect();
        Ok(Marker { family, solid, edge, bodies })
    }

    /// The solid of this marker's kind and nominal edge, in the body frame: what harness,
    /// renderer, viewer and registration draw.
    pub fn geometry(&self) -> Solid {
        Solid::new(self.solid, self.edge)
    }

    /// Refuses a marker without both bodies: a file describing one body reads, but can never
    /// track a jaw. The CLI's `track` and `check-marker` and the FFI's tracker apply it.
    pub fn require_both_bodies(&self) -> Result<(), MarkerError> {
        let missing: Vec<&str> = BodyKind::ALL.iter().filter(|&&k| self.body(k).is_none()).map(|k| k.name()).collect();
        if missing.is_empty() { Ok(()) } else { Err(MarkerError::MissingBody { missing: missing.join(" or ") }) }
    }

    /// The body of a kind, if the marker has it.
    pub fn body(&self, kind: BodyKind) -> Option<&Body> {
        self.bodies.iter().find(|b| b.kind == kind)
    }

    /// The body and tag carrying `id`.
    pub fn find_tag(&self, id: u32) -> Option<(BodyKind, &Tag)> {
        self.bodies.iter().find_map(|b| b.tags.iter().find(|t| t.id == id).map(|t| (b.kind, t)))
    }

    /// The same marker with some tags displaced on their faces (print and placement errors).
    /// Errors name an id the marker does not have.
    pub fn with_print_errors(&self, errors: &[(u32, PrintError)]) -> Result<Marker, MarkerError> {
        let mut out = self.clone();
        for &(id, e) in errors {
            let tag = out
                .bodies
                .iter_mut()
                .flat_map(|b| b.tags.iter_mut())
                .find(|t| t.id == id)
                .ok_or_else(|| MarkerError::Params(format!("no tag with id {id} to displace")))?;
            // No error leaves the tag bit-for-bit where it was (not re-rounded through a rotation).
            if e == PrintError::default() {
                continue;
            }
            let n = tag.face_normal();
            let (x, y) = tag.axes();
            let rot = Rotation3::from_axis_angle(&Unit::new_normalize(n), e.rotation);
            let new_center = tag.center + x * e.shift_x + y * e.shift_y;
            let old_center = tag.center;
            for c in tag.corners.iter_mut() {
                *c = new_center + rot * (*c - old_center);
            }
            tag.center = new_center;
        }
        Ok(out)
    }

    /// All tags of all bodies.
    pub fn tags(&self) -> impl Iterator<Item = (BodyKind, &Tag)> {
        self.bodies.iter().flat_map(|b| b.tags.iter().map(move |t| (b.kind, t)))
    }

    /// Whether a calibration placed at least one of its tags.
    pub fn is_calibrated(&self) -> bool {
        self.tags().any(|(_, t)| t.provenance.is_some_and(|p| p.is_calibrated()))
    }

    /// The ids of the tags whose place was measured rather than assumed, ascending: placed by a
    /// calibration, or anywhere but where the ideal solid of this edge puts a tag of its size
    /// on its face (a calibrated file of version 1, or a print's true geometry). A tag of the
    /// nominal model is not.
    pub fn measured_tags(&self) -> Vec<u32> {
        let solid = self.geometry();
        let moved = |t: &Tag| {
            solid.faces().get(t.face).is_none_or(|face| {
                let ideal = nominal_tag(face, t.id, t.size);
                ideal.corners.iter().zip(&t.corners).any(|(a, b)| (a - b).norm() > MEASURED_MM)
            })
        };
        let mut ids: Vec<u32> = self
            .tags()
            .filter(|(_, t)| t.provenance.is_some_and(|p| p.is_calibrated()) || moved(t))
            .map(|(_, t)| t.id)
            .collect();
        ids.sort_unstable();
        ids
    }

    /// The tags of a calibrated marker that no calibration placed (left nominal, or of a body
    /// the calibration never saw), ascending by id; none for a marker that is not calibrated,
    /// whose tags are all nominal alike.
    pub fn uncalibrated_tags(&self) -> Vec<(BodyKind, u32)> {
        if !self.is_calibrated() {
            return Vec::new();
        }
        let mut ids: Vec<(BodyKind, u32)> = self
            .tags()
            .filter(|(_, t)| !t.provenance.is_some_and(|p| p.is_calibrated()))
            .map(|(k, t)| (k, t.id))
            .collect();
        ids.sort_unstable_by_key(|&(_, id)| id);
        ids
    }
}

/// A tag this close to its ideal place (mm, each corner) is taken for an unmeasured one: well
/// under a print's errors, well over a JSON round trip's.
const MEASURED_MM: f64 = 1e-6;

fn nominal_tag(face: &Face, id: u32, size: f64) -> Tag {
    let h = size / 2.0;
    Tag {
        id,
        face: face.index,
        size,
        corners: TAG_CORNERS.map(|(u, v)| face.center + face.x_axis * (u * h) + face.y_axis * (v * h)),
        center: face.center,
        face_polygon: face.vertices.clone(),
        provenance: None,
    }
}

/// Newell's normal of a polygon (unit length; outward when the polygon is counter-clockwise
/// seen from outside).
pub(crate) fn newell_normal(poly: &[Vector3<f64>]) -> Vector3<f64> {
    let mut n = Vector3::zeros();
    for i in 0..poly.len() {
        let a = poly[i];
        let b = poly[(i + 1) % poly.len()];
        n += a.cross(&b);
    }
    n.normalize()
}

/// Largest distance (mm) of `points` from the plane through their mean with normal `n`.
pub(crate) fn plane_deviation(points: &[Vector3<f64>], n: &Vector3<f64>) -> f64 {
    let mean = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    points.iter().map(|p| (p - mean).dot(n).abs()).fold(0.0, f64::max)
}

/// The unit normal of the least-squares plane of `points`.
pub(crate) fn fitted_normal(points: &[Vector3<f64>]) -> Vector3<f64> {
    let mean = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let cov: Matrix3<f64> = points.iter().map(|p| (p - mean) * (p - mean).transpose()).sum();
    let eig = cov.symmetric_eigen();
    let i = eig.eigenvalues.imin();
    eig.eigenvectors.column(i).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_tag_size_leaves_exactly_one_cell() {
        let size = default_tag_size(DEFAULT_EDGE_MM);
        let d = Solid::new(SolidKind::Dodecahedron, DEFAULT_EDGE_MM);
        let m = margin(&d.faces()[0], size);
        assert!((m - size / 8.0).abs() < 1e-12, "margin {m} vs cell {}", size / 8.0);
        // Sanity: between the pentagon's inscribed-circle square and its inradius.
        let r = d.faces()[0].inradius();
        assert!(size > r * 2f64.sqrt() * 0.8 && size < 2.0 * r, "{size}");
        // It scales with the edge.
        assert!((default_tag_size(2.0 * DEFAULT_EDGE_MM) - 2.0 * size).abs() < 1e-9);
    }

    #[test]
    fn corners_lie_inside_their_face_with_the_margin() {
        let m = Marker::default();
        let d = m.geometry();
        for (_, t) in m.tags() {
            let face = &d.faces()[t.face];
            for c in &t.corners {
                let inside = face.distance_inside(c);
                assert!(inside >= t.size / 8.0 - 1e-9, "tag {} corner {inside} mm inside", t.id);
                assert!(((c - face.center).dot(&face.normal)).abs() < 1e-12, "corner on the face plane");
            }
        }
    }

    #[test]
    fn ids_are_unique_and_laid_out_per_body() {
        let m = Marker::default();
        let mut ids: Vec<u32> = m.tags().map(|(_, t)| t.id).collect();
        ids.sort_unstable();
        assert_eq!(ids, (0..24).collect::<Vec<_>>());
        for (kind, t) in m.tags() {
            assert_eq!(t.id, kind.first_id() + t.face as u32);
        }
        assert_eq!(m.find_tag(13).map(|(k, t)| (k, t.face)), Some((BodyKind::Mandible, 1)));
    }

    #[test]
    fn corner_winding_matches_the_outward_normal() {
        for (_, t) in Marker::default().tags() {
            let n = t.face_normal();
            assert!(n.dot(&t.center) > 0.0, "outward");
            for i in 0..4 {
                let a = t.corners[(i + 1) % 4] - t.corners[i];
                let b = t.corners[(i + 2) % 4] - t.corners[(i + 1) % 4];
                assert!(a.cross(&b).dot(&n) > 0.0, "tag {} counter-clockwise from outside", t.id);
            }
            let (x, y) = t.axes();
            assert!((x.cross(&y) + n).norm() < 1e-12, "x right, y down, z into the face");
            assert!((t.point_at(-1.0, 1.0) - t.corners[0]).norm() < 1e-12);
            assert!((t.point_at(0.0, 0.0) - t.center).norm() < 1e-12);
        }
    }

    #[test]
    fn print_errors_move_the_square_within_its_plane() {
        let m = Marker::default();
        let e = PrintError { shift_x: 0.2, shift_y: -0.1, rotation: 1f64.to_radians() };
        let moved = m.with_print_errors(&[(5, e)]).expect("id 5 exists");
        let (_, a) = m.find_tag(5).expect("tag 5");
        let (_, b) = moved.find_tag(5).expect("tag 5");
        assert!(((b.center - a.center).norm() - 0.2236).abs() < 1e-3);
        let (xa, _) = a.axes();
        let (xb, _) = b.axes();
        assert!((xa.angle(&xb).to_degrees() - 1.0).abs() < 1e-9);
        for c in &b.corners {
            assert!(((c - a.center).dot(&a.face_normal())).abs() < 1e-12);
        }
        assert!(m.with_print_errors(&[(99, e)]).is_err());
    }

    #[test]
    fn impossible_parameters_say_why() {
        for (edge, size, word) in [
            (-1.0, None, "edge"),
            (f64::NAN, None, "edge"),
            (12.7, Some(0.0), "tag size"),
            (12.7, Some(30.0), "larger than its face"),
            (12.7, Some(11.5), "margin"),
        ] {
            let err = Marker::nominal(edge, size).expect_err("invalid").to_string();
            assert!(err.contains(word), "{err}");
        }
        assert!(Marker::nominal(12.7, Some(8.0)).is_ok());
    }

    #[test]
    fn measured_tags_are_the_moved_and_the_calibrated() {
        let m = Marker::default();
        assert!(m.measured_tags().is_empty(), "the ideal solid is assumed, not measured");
        let again = Marker::from_json(&m.to_json()).expect("round trip");
        assert!(again.measured_tags().is_empty(), "a nominal file read back is still nominal");
        let shift = PrintError { shift_x: 0.01, ..PrintError::default() };
        let mut printed = m.with_print_errors(&[(14, shift), (3, shift)]).expect("ids exist");
        assert_eq!(printed.measured_tags(), vec![3, 14]);
        printed.bodies[0].tags[7].provenance =
            Some(TagProvenance::Calibrated { views: 9, rms_before_px: 1.0, rms_after_px: 0.1 });
        let id = printed.bodies[0].tags[7].id;
        assert!(printed.measured_tags().contains(&id), "a tag a calibration placed where the model had it");
        printed.bodies[0].tags[8].provenance = Some(TagProvenance::Nominal { views: 2 });
        assert!(!printed.measured_tags().contains(&printed.bodies[0].tags[8].id));
    }
}
