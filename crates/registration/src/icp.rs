//! Registration of a marker to a scan of its printed harness: where the marker's frame sits in
//! the scan's frame (`scan_from_marker`, what the registration file's
//! `maxilla_scan_from_maxilla_marker` and `mandible_scan_from_mandible_marker` hold), found by
//! point-to-plane ICP of the body's solid (the marker's: a dodecahedron or a cube) onto the
//! scanned surface.
//!
//! The model is the ideal solid of the marker's kind and edge, sampled evenly over its faces
//! ([`marker_surface_samples`]). The scan is any triangle mesh in mm showing (part of) the
//! printed body, with the mounting post, teeth or anything else around it. [`register`] starts
//! from an initial guess; each iteration pairs every sample with its nearest scan point, keeps
//! the pairs that are close (within a distance that shrinks with the residual) and whose
//! normals agree, and solves the linearised point-to-plane least squares. Scan parts that are
//! not on the model (the post, teeth) and model faces the scanner did not see then simply find
//! no partner, which is what makes it work on partial scans.
//!
//! The dodecahedron looks the same after 60 different rotations (a cube after 24), so its
//! surface alone cannot say which face is which: the initial guess must be within about 30°
//! (and a few mm) of the truth, and ICP lands on the symmetric copy nearest to it. [`centred_init`] is a guess for a
//! scan that is already in the marker's orientation; otherwise the caller supplies one (for
//! instance by placing the harness STL roughly on the scan in a mesh editor).
//!
//! A converged fit still needs judging: [`IcpResult::check`] refuses one that ended far from
//! the guess (reached from too far off, possibly a copy with other faces), fits badly, or
//! found too little of the surface in the scan.

use jawtrack_marker::{BodyKind, Marker};
use jawtrack_mesh::Mesh;
use jawtrack_mesh::distance::SurfaceIndex;
use jawtrack_pose::Pose;
use nalgebra::{Matrix6, Point3, UnitQuaternion, Vector3, Vector6};

/// A point of the model surface and its outward unit normal (marker frame, mm).
pub type SurfaceSample = (Point3<f64>, Vector3<f64>);

/// Most samples [`marker_surface_samples`] makes: a spacing typo must not eat the memory.
pub const MAX_SAMPLES: usize = 500_000;

/// How far (mm) a tag's face polygon in the marker file may be from the regular solid's
/// face before the file is refused as describing a different solid.
const FACE_TOLERANCE_MM: f64 = 0.05;

/// Settings of [`register`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IcpOptions {
    /// The farthest a model point may be from the scan to be paired (mm), in the first
    /// iteration; also the reach of the scan's distance index. The initial guess must bring
    /// most of the model within it.
    pub max_distance_mm: f64,
    /// The floor (mm) of the pairing distance, which after the first iteration is three times
    /// the previous residual: scan noise must not shrink it to nothing.
    pub min_distance_mm: f64,
    /// Pairs whose scan normal and model normal differ by more than this (°) are left out.
    pub max_normal_angle_deg: f64,
    /// Iterations before giving up (the result then says `converged: false`).
    pub max_iterations: usize,
    /// Converged when an update moves by less than this (mm, and rad).
    pub tolerance: f64,
    /// Fewest pairs an iteration may have.
    pub min_correspondences: usize,
}

impl Default for IcpOptions {
    /// 3 mm first pairing distance shrinking to no less than 0.2 mm, 45° normal agreement,
    /// 100 iterations, 1e-7 mm / rad, at least 30 pairs.
    fn default() -> Self {
        IcpOptions {
            max_distance_mm: 3.0,
            min_distance_mm: 0.2,
            max_normal_angle_deg: 45.0,
            max_iterations: 100,
            tolerance: 1e-7,
            min_correspondences: 30,
        }
    }
}

impl IcpOptions {
    /// Checks each setting; errors name it.
    pub fn validate(&self) -> Result<(), RegisterError> {
        let bad = |name: &str, reason: String| Err(RegisterError::Options(format!("`{name}` {reason}")));
        let d = self.max_distance_mm;
        if !(d.is_finite() && d > 0.0 && d <= 100.0) {
            return bad("max_distance_mm", format!("must be between 0 and 100 mm, got {d}"));
        }
        let m = self.min_distance_mm;
        if !(m.is_finite() && m > 0.0 && m <= d) {
            return bad("min_distance_mm", format!("must be positive and at most max_distance_mm ({d}), got {m}"));
        }
        let a = self.max_normal_angle_deg;
        if !(a.is_finite() && a > 0.0 && a < 90.0) {
            return bad("max_normal_angle_deg", format!("must be between 0 and 90°, got {a}"));
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1".into());
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad("tolerance", format!("must be positive, got {}", self.tolerance));
        }
        if self.min_correspondences < 6 {
            return bad(
                "min_correspondences",
                format!("must be at least 6 (six unknowns), got {}", self.min_correspondences),
            );
        }
        Ok(())
    }
}

/// What [`register`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IcpResult {
    /// Maps marker-frame points into the scan's frame.
    pub scan_from_marker: Pose,
    /// RMS point-to-plane residual (mm) of the paired model points at that pose: how far they
    /// are from the scan surface along its normal.
    pub rms_mm: f64,
    /// Model points paired with the scan at that pose.
    pub inliers: usize,
    /// Model points in all.
    pub samples: usize,
    /// Iterations run.
    pub iterations: usize,
    /// Whether the last update was below the tolerance; if not, the pose is where the
    /// iterations stopped, not a solution.
    pub converged: bool,
    /// Size of the last update: translation (mm) and rotation (rad).
    pub last_step: (f64, f64),
    /// How far the fit moved the marker's centre from the initial guess (mm) and how far it
    /// turned it (rad).
    pub moved: (f64, f64),
    /// Whether the scan's triangles wind inward (normals pointing into the solid); the
    /// normals were then flipped for the comparison.
    pub inside_out: bool,
}

impl IcpResult {
    /// The fraction of the model surface paired with the scan (0–1).
    pub fn overlap(&self) -> f64 {
        if self.samples == 0 { 0.0 } else { self.inliers as f64 / self.samples as f64 }
    }

    /// Accepts the result only if it converged, stayed near the initial guess and fits well
    /// enough by `limits`; the error says which test failed.
    pub fn check(&self, limits: &Acceptance) -> Result<(), RegisterError> {
        if !self.converged {
            return Err(RegisterError::NotConverged {
                iterations: self.iterations,
                step_mm: self.last_step.0,
                step_deg: self.last_step.1.to_degrees(),
            });
        }
        let (shift_mm, turn_deg) = (self.moved.0, self.moved.1.to_degrees());
        if !(at_most(shift_mm, limits.max_shift_mm) && at_most(turn_deg, limits.max_turn_deg)) {
            return Err(RegisterError::Wandered {
                shift_mm,
                turn_deg,
                max_shift_mm: limits.max_shift_mm,
                max_turn_deg: limits.max_turn_deg,
            });
        }
        if !at_most(self.rms_mm, limits.max_rms_mm) {
            return Err(RegisterError::Residual { rms_mm: self.rms_mm, max_mm: limits.max_rms_mm });
        }
        if !at_most(limits.min_overlap, self.overlap()) {
            return Err(RegisterError::Overlap { fraction: self.overlap(), min: limits.min_overlap });
        }
        Ok(())
    }

    /// What the fit found, as `jawtrack register` prints it: whether it converged, the
    /// residual and overlap, and `scan_from_marker` as a rotation vector and translation and
    /// as the matrix the registration file holds; `scan` names the scan file.
    pub fn describe(&self, body: BodyKind, scan: &str) -> String {
        let verdict = if self.converged { "registered" } else { "did not converge" };
        let mut text = format!("{body}: {scan} {verdict} in {} iterations\n", self.iterations);
        text += &format!(
            "  residual {:.4} mm RMS over {} of {} model points ({:.0} % of the marker solid's surface found in the scan)\n",
            self.rms_mm,
            self.inliers,
            self.samples,
            100.0 * self.overlap()
        );
        if self.inside_out {
            text += "  note: the scan's triangles wind inward (normals point into the solid); used flipped\n";
        }
        let (r, t) =
            (self.scan_from_marker.rotation().scaled_axis().map(f64::to_degrees), self.scan_from_marker.translation());
        text += &format!(
            "  {body}_scan_from_{body}_marker: rotation vector ({:.4}, {:.4}, {:.4})° ({:.4}°), translation ({:.4}, {:.4}, {:.4}) mm",
            r.x,
            r.y,
            r.z,
            r.norm(),
            t.x,
            t.y,
            t.z
        );
        for row in self.scan_from_marker.to_row_major().chunks(4) {
            text += &format!("\n    [{:>10.6} {:>10.6} {:>10.6} {:>10.4}]", row[0], row[1], row[2], row[3]);
        }
        text
    }
}

/// What [`IcpResult::check`] accepts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Acceptance {
    /// Largest RMS residual (mm).
    pub max_rms_mm: f64,
    /// Smallest fraction of the model surface paired with the scan (0–1).
    pub min_overlap: f64,
    /// Farthest the marker's centre may have moved from the initial guess (mm).
    pub max_shift_mm: f64,
    /// Most the marker may have turned from the initial guess (°).
    pub max_turn_deg: f64,
}

impl Default for Acceptance {
    /// 0.2 mm RMS, 30 % of the surface, 6 mm (twice the default first pairing distance) and
    /// 36°: half of the 72° turn about a face that maps the dodecahedron onto itself, beyond
    /// which the guess was as near another copy, with other faces, as the one found (a cube's
    /// 90° turn would allow 45°; 36° is kept for both, the stricter).
    fn default() -> Self {
        Acceptance { max_rms_mm: 0.2, min_overlap: 0.3, max_shift_mm: 6.0, max_turn_deg: 36.0 }
    }
}

impl Acceptance {
    /// The limits for a fit whose first pairing reached `max_distance_mm`: a guess within that
    /// distance leaves the centre that near the truth, so the centre may move twice it; the
    /// turn keeps its default.
    pub fn for_pairing(max_distance_mm: f64, max_rms_mm: f64, min_overlap: f64) -> Self {
        Acceptance { max_rms_mm, min_overlap, max_shift_mm: 2.0 * max_distance_mm, ..Acceptance::default() }
    }
}

/// Why a registration failed.
#[derive(Debug, thiserror::Error)]
pub enum RegisterError {
    /// The marker file has no body of that kind.
    #[error("the marker has no {0} body")]
    MissingBody(BodyKind),
    /// The marker describes a solid that is not the regular solid of its kind and edge.
    #[error("the marker's {body} body does not lie on the regular solid its file names, of edge {edge} mm: {reason}")]
    MarkerGeometry {
        /// Which body.
        body: BodyKind,
        /// The marker's edge (mm).
        edge: f64,
        /// What does not fit.
        reason: String,
    },
    /// The sample spacing is not usable.
    #[error("the sample spacing must be a positive number of mm giving at most {MAX_SAMPLES} samples, got {0} mm")]
    Spacing(f64),
    /// A setting of [`IcpOptions`] is out of range, or there are no samples.
    #[error("invalid registration setting: {0}")]
    Options(String),
    /// The initial guess is not a finite transform.
    #[error("the initial pose is not finite")]
    Init,
    /// Too few model points found the scan surface to fit a pose.
    #[error(
        "only {found} of {samples} model points found the scan surface within {within_mm:.2} mm with a matching \
         normal in iteration {iteration} (at least {needed} needed): the initial guess is probably too far off, or \
         the scan does not show the marker's body; give a closer initial guess (`jawtrack register --init`)"
    )]
    TooFewCorrespondences {
        /// Pairs found.
        found: usize,
        /// Model points.
        samples: usize,
        /// Pairs needed.
        needed: usize,
        /// The pairing distance (mm).
        within_mm: f64,
        /// The iteration (1 = the initial guess).
        iteration: usize,
    },
    /// The paired scan surface does not pin the pose down (only flat, or only cylindrical,
    /// parts of the scan matched).
    #[error(
        "in iteration {iteration} the matched scan surface does not determine the pose (it lets the model slide \
         or turn freely, as a single plane or a cylinder would): the scan shows too little of the marker's solid near \
         the initial guess"
    )]
    Degenerate {
        /// The iteration.
        iteration: usize,
    },
    /// ICP did not settle within the iteration limit.
    #[error(
        "ICP did not converge in {iterations} iterations (the last update still moved {step_mm:.2e} mm and \
         {step_deg:.2e}°); the pose is not trustworthy: try a closer initial guess"
    )]
    NotConverged {
        /// Iterations run.
        iterations: usize,
        /// The last update's translation (mm).
        step_mm: f64,
        /// The last update's rotation (°).
        step_deg: f64,
    },
    /// The fit ended far from the initial guess.
    #[error(
        "ICP moved the marker {shift_mm:.1} mm and turned it {turn_deg:.1}° away from the initial guess (at most \
         {max_shift_mm} mm and {max_turn_deg}° accepted): the guess was too far off, and since the marker's solid \
         looks the same turned 72° about a face, a fit found that far away may have its faces mislabelled; give a \
         closer initial guess"
    )]
    Wandered {
        /// How far the centre moved (mm).
        shift_mm: f64,
        /// How far it turned (°).
        turn_deg: f64,
        /// The farthest accepted (mm).
        max_shift_mm: f64,
        /// The most accepted (°).
        max_turn_deg: f64,
    },
    /// The fit converged but the model stays too far from the scan.
    #[error(
        "the residual is {rms_mm:.3} mm RMS, above the {max_mm} mm accepted: the scan does not match the \
         marker's solid well here (wrong marker edge, a deformed print, or a wrong local fit from a poor initial guess)"
    )]
    Residual {
        /// The residual (mm).
        rms_mm: f64,
        /// The largest accepted (mm).
        max_mm: f64,
    },
    /// The fit converged on too small a part of the model.
    #[error(
        "only {:.0} % of the marker solid's surface matched the scan (at least {:.0} % required): the fit \
         probably locked onto something else; check the scan shows the body and give a closer initial guess",
        fraction * 100.0, min * 100.0
    )]
    Overlap {
        /// The matched fraction (0–1).
        fraction: f64,
        /// The least accepted (0–1).
        min: f64,
    },
}

/// Points and outward normals spread evenly (a square grid of `spacing_mm`, kept half a
/// spacing inside the edges) over the faces of `body`'s solid, in the marker's frame: the
/// model [`register`] fits to a scan.
///
/// The solid is the marker's ([`Marker::geometry`]: its kind and nominal edge); the marker
/// file's face polygons of the body must agree with it (a calibrated file refines where the
/// tags sit on their faces, not the faces). Edges are left out because a print rounds them.
pub fn marker_surface_samples(
    marker: &Marker,
    body: BodyKind,
    spacing_mm: f64,
) -> Result<Vec<SurfaceSample>, RegisterError> {
    let tags = &marker.body(body).ok_or(RegisterError::MissingBody(body))?.tags;
    let edge = marker.edge;
    if !(edge.is_finite() && edge > 0.0) {
        return Err(RegisterError::MarkerGeometry { body, edge, reason: "the edge is not a positive length".into() });
    }
    let solid = marker.geometry();
    let faces = solid.faces().len();
    for tag in tags {
        let face = solid.faces().get(tag.face).ok_or_else(|| RegisterError::MarkerGeometry {
            body,
            edge,
            reason: format!(
                "tag {} is on face {}, but a {} has {faces} faces (0–{})",
                tag.id,
                tag.face,
                solid.kind(),
                faces - 1
            ),
        })?;
        let off = tag.face_polygon.iter().zip(&face.vertices).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        if tag.face_polygon.len() != face.vertices.len() || !at_most(off, FACE_TOLERANCE_MM) {
            return Err(RegisterError::MarkerGeometry {
                body,
                edge,
                reason: format!("the face polygon of tag {} is {off:.3} mm from face {}", tag.id, tag.face),
            });
        }
    }
    // A regular n-gon's area: (n/4)·e²·cot(180°/n).
    let area: f64 = solid
        .faces()
        .iter()
        .map(|f| {
            let n = f.vertices.len() as f64;
            0.25 * n * edge * edge / (std::f64::consts::PI / n).tan()
        })
        .sum();
    if !(spacing_mm.is_finite() && spacing_mm > 0.0) || area / (spacing_mm * spacing_mm) > MAX_SAMPLES as f64 {
        return Err(RegisterError::Spacing(spacing_mm));
    }
    let mut samples = Vec::new();
    for face in solid.faces() {
        // Keeps at least the centre when the spacing is coarser than the face.
        let inset = (0.5 * spacing_mm).min(0.5 * face.inradius());
        let reach = (face.vertices[0] - face.center).norm();
        let n = (reach / spacing_mm).ceil() as i64;
        for j in -n..=n {
            for i in -n..=n {
                let p = face.center + face.x_axis * (i as f64 * spacing_mm) + face.y_axis * (j as f64 * spacing_mm);
                if face.distance_inside(&p) >= inset {
                    samples.push((Point3::from(p), face.normal));
                }
            }
        }
    }
    Ok(samples)
}

/// An initial guess for a scan in the marker's orientation: no rotation, and the marker's
/// centre (its frame's origin) on the centre of the scan surface nearest the scan's middle —
/// mean shift from the area-weighted centroid of the whole scan, each step averaging the
/// surface within the marker solid's circumradius. Good for a scan of the harness alone
/// exported in (or near) the body frame; a scan with teeth, or turned, needs a real guess.
/// `None` when the scan has no area.
pub fn centred_init(scan: &Mesh, marker: &Marker) -> Option<Pose> {
    let radius = marker.geometry().circumradius();
    let pieces: Vec<(Vector3<f64>, f64)> = (0..scan.triangles.len())
        .map(|t| {
            let [a, b, c] = scan.corners(t);
            ((a.coords + b.coords + c.coords) / 3.0, scan.area_normal(t).norm() / 2.0)
        })
        .filter(|(p, w)| p.iter().all(|v| v.is_finite()) && w.is_finite() && *w > 0.0)
        .collect();
    let mean = |near: &dyn Fn(&Vector3<f64>) -> bool| {
        let (sum, weight) =
            pieces.iter().filter(|(p, _)| near(p)).fold((Vector3::zeros(), 0.0), |(s, w), (p, a)| (s + p * *a, w + a));
        (weight > 0.0).then(|| sum / weight)
    };
    let mut centre = mean(&|_| true)?;
    for _ in 0..100 {
        let Some(next) = mean(&|p| (p - centre).norm() <= radius) else { break };
        let moved = (next - centre).norm();
        centre = next;
        if moved < 1e-6 {
            break;
        }
    }
    Some(Pose::from_parts(UnitQuaternion::identity(), centre))
}

/// `x ≤ limit`, false when either is NaN: a NaN fails every test it meets.
fn at_most(x: f64, limit: f64) -> bool {
    x <= limit
}

/// One model point paired with the scan: where it is now (scan frame), its distance to the
/// surface, the surface normal there and the point-to-plane residual.
struct Pair {
    q: Point3<f64>,
    distance: f64,
    normal: Vector3<f64>,
    residual: f64,
}

/// Fits the model `samples` (marker frame) to `scan` by point-to-plane ICP from `init`
/// (`scan_from_marker`).
///
/// Only the scan within reach of the model at the initial guess is indexed, so a full arch
/// scan with the harness on it costs no more than the harness. Pairs are weighted by Tukey's
/// biweight of their distance over the current pairing distance, so a pair fades out as it
/// nears the cut-off instead of dropping out abruptly (which would keep the pose flickering
/// between two inlier sets).
///
/// Errors when an iteration has too few pairs or the pairs do not determine the pose; a run
/// that hits the iteration limit returns `converged: false`. A converged fit is not yet a
/// good one: [`IcpResult::check`] says whether to trust it.
pub fn register(
    samples: &[SurfaceSample],
    scan: &Mesh,
    init: &Pose,
    options: &IcpOptions,
) -> Result<IcpResult, RegisterError> {
    options.validate()?;
    if samples.is_empty() {
        return Err(RegisterError::Options("there are no model points to fit".into()));
    }
    if !init.is_finite() {
        return Err(RegisterError::Init);
    }
    let middle = Point3::from(samples.iter().map(|(p, _)| p.coords).sum::<Vector3<f64>>() / samples.len() as f64);
    let extent = samples.iter().map(|(p, _)| (p - middle).norm()).fold(0.0, f64::max);
    // The model can drift a little during the fit; the reach around it covers that.
    let local = crop(scan, &init.transform_point(&middle), extent + 2.0 * options.max_distance_mm);
    let too_few = |found: usize, within_mm: f64, iteration: usize| RegisterError::TooFewCorrespondences {
        found,
        samples: samples.len(),
        needed: options.min_correspondences,
        within_mm,
        iteration,
    };
    if local.triangles.is_empty() {
        return Err(too_few(0, options.max_distance_mm, 1));
    }
    let index = SurfaceIndex::new(&local, options.max_distance_mm);
    let cos_max = options.max_normal_angle_deg.to_radians().cos();

    // A scan whose triangles wind inward pairs (nearly) only with flipped normals.
    let count = |sign: f64| pairs(samples, &index, init, options.max_distance_mm, cos_max, sign).len();
    let (forward, backward) = (count(1.0), count(-1.0));
    let inside_out = backward > 2 * forward && backward >= options.min_correspondences;
    let sign = if inside_out { -1.0 } else { 1.0 };

    let mut pose = *init;
    let mut within = options.max_distance_mm;
    let mut converged = false;
    let mut last_step = (f64::INFINITY, f64::INFINITY);
    let mut iterations = 0;
    for iteration in 1..=options.max_iterations {
        iterations = iteration;
        let found = pairs(samples, &index, &pose, within, cos_max, sign);
        if found.len() < options.min_correspondences {
            return Err(too_few(found.len(), within, iteration));
        }
        let rms = rms_residual(&found);
        let (step, t, w) = solve(&found, within).ok_or(RegisterError::Degenerate { iteration })?;
        pose = step * pose;
        last_step = (t, w);
        // Three sigmas of the current residual keep the true pairs and drop the rest.
        within = (3.0 * rms).clamp(options.min_distance_mm, options.max_distance_mm);
        if t < options.tolerance && w < options.tolerance {
            converged = true;
            break;
        }
    }
    let found = pairs(samples, &index, &pose, within, cos_max, sign);
    if found.len() < options.min_correspondences {
        return Err(too_few(found.len(), within, iterations + 1));
    }
    Ok(IcpResult {
        scan_from_marker: pose,
        rms_mm: rms_residual(&found),
        inliers: found.len(),
        samples: samples.len(),
        iterations,
        converged,
        last_step,
        moved: (
            (pose.transform_point(&middle) - init.transform_point(&middle)).norm(),
            pose.rotation().angle_to(&init.rotation()),
        ),
        inside_out,
    })
}

/// The triangles of `mesh` that may come within `radius` of `centre`, with only their vertices.
fn crop(mesh: &Mesh, centre: &Point3<f64>, radius: f64) -> Mesh {
    let mut new_index = vec![u32::MAX; mesh.vertices.len()];
    let mut out = Mesh { vertices: Vec::new(), triangles: Vec::new() };
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let corners = mesh.corners(t);
        let mid = Point3::from((corners[0].coords + corners[1].coords + corners[2].coords) / 3.0);
        let size = corners.iter().map(|c| (c - mid).norm()).fold(0.0, f64::max);
        // The triangle lies within its centroid's sphere of radius `size`.
        if !at_most((mid - centre).norm() - size, radius) {
            continue;
        }
        out.triangles.push(tri.map(|i| {
            let slot = &mut new_index[i as usize];
            if *slot == u32::MAX {
                *slot = out.vertices.len() as u32;
                out.vertices.push(mesh.vertices[i as usize]);
            }
            *slot
        }));
    }
    out
}

/// The model points at `pose` that have scan surface within `within` mm whose normal (times
/// `sign`) is within the angle of theirs.
fn pairs(
    samples: &[SurfaceSample],
    index: &SurfaceIndex,
    pose: &Pose,
    within: f64,
    cos_max: f64,
    sign: f64,
) -> Vec<Pair> {
    samples
        .iter()
        .filter_map(|(p, n)| {
            let q = pose.transform_point(p);
            let near = index.nearest(&q)?;
            let distance = near.distance.abs();
            let normal = near.normal * sign;
            (distance < within && normal.dot(&pose.transform_vector(n)) >= cos_max).then(|| Pair {
                q,
                distance,
                normal,
                residual: normal.dot(&(q - near.point)),
            })
        })
        .collect()
}

/// RMS point-to-plane residual: a model point past the rim of a hole in the scan is paired
/// off to the side of the rim, at a distance that says nothing about the fit.
fn rms_residual(pairs: &[Pair]) -> f64 {
    (pairs.iter().map(|p| p.residual * p.residual).sum::<f64>() / pairs.len() as f64).sqrt()
}

/// One Gauss–Newton step of the point-to-plane objective: the small rotation ω about the
/// pairs' weighted centroid c and translation t minimising Σ wᵢ (nᵢ·(qᵢ + ω×(qᵢ−c) + t − sᵢ))².
/// Returns the update (applied on the scan side) and its size (mm, rad); `None` when the
/// normal equations are (nearly) singular.
fn solve(pairs: &[Pair], within: f64) -> Option<(Pose, f64, f64)> {
    let weight = |p: &Pair| {
        let u = p.distance / within;
        (1.0 - u * u).max(0.0).powi(2)
    };
    let total: f64 = pairs.iter().map(weight).sum();
    if !at_most(f64::MIN_POSITIVE, total) {
        return None;
    }
    let c = pairs.iter().map(|p| p.q.coords * weight(p)).sum::<Vector3<f64>>() / total;
    // Rotation columns scaled by the spread so the conditioning test compares like with like.
    let spread = (pairs.iter().map(|p| weight(p) * (p.q.coords - c).norm_squared()).sum::<f64>() / total).sqrt();
    if !at_most(f64::MIN_POSITIVE, spread) {
        return None;
    }
    let (mut h, mut g) = (Matrix6::<f64>::zeros(), Vector6::<f64>::zeros());
    for p in pairs {
        let a = (p.q.coords - c).cross(&p.normal) / spread;
        let j = Vector6::new(a.x, a.y, a.z, p.normal.x, p.normal.y, p.normal.z);
        let w = weight(p);
        h += j * j.transpose() * w;
        g += j * (w * p.residual);
    }
    let eigen = h.symmetric_eigen();
    let (lo, hi) = (eigen.eigenvalues.min(), eigen.eigenvalues.max());
    if !at_most(1e-6 * hi, lo) {
        return None;
    }
    let x = -h.cholesky()?.solve(&g);
    let omega = Vector3::new(x[0], x[1], x[2]) / spread;
    let t = Vector3::new(x[3], x[4], x[5]);
    let rotation = UnitQuaternion::from_scaled_axis(omega);
    // q' = c + R (q − c) + t.
    let step = Pose::from_parts(rotation, c + t - rotation * c);
    Some((step, t.norm(), omega.norm()))
}

/// Sets `body`'s entry of `registration` to `scan_from_marker` (what [`register`] found),
/// keeping the other body's entry and the intercuspation pose; the field set and the field kept,
/// by name.
pub fn set_entry(
    registration: &mut crate::Registration,
    body: BodyKind,
    scan_from_marker: Pose,
) -> (&'static str, &'static str) {
    match body {
        BodyKind::Maxilla => {
            registration.maxilla_scan_from_maxilla_marker = scan_from_marker;
            ("maxilla_scan_from_maxilla_marker", "mandible_scan_from_mandible_marker")
        }
        BodyKind::Mandible => {
            registration.mandible_scan_from_mandible_marker = scan_from_marker;
            ("mandible_scan_from_mandible_marker", "maxilla_scan_from_maxilla_marker")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_lie_on_the_faces_and_cover_them_evenly() {
        let marker = Marker::default();
        let samples = marker_surface_samples(&marker, BodyKind::Maxilla, 0.5).expect("samples");
        let solid = marker.geometry();
        let face_area = 1.25 * marker.edge * marker.edge / 36f64.to_radians().tan();
        let mut per_face = [0usize; 12];
        for (p, n) in &samples {
            let face = solid.faces().iter().position(|f| (f.normal - n).norm() < 1e-12).expect("a face normal");
            per_face[face] += 1;
            let f = &solid.faces()[face];
            assert!((p.coords - f.center).dot(&f.normal).abs() < 1e-9, "on the plane");
            assert!(f.distance_inside(&p.coords) >= 0.25 - 1e-9, "inside, away from the edges");
        }
        for count in per_face {
            // The grid, less its rim, holds about (area − perimeter·inset) / spacing² points.
            let expected = (face_area - 5.0 * marker.edge * 0.25) / 0.25;
            assert!((count as f64 / expected - 1.0).abs() < 0.05, "{count} vs {expected}");
        }
        assert!(matches!(marker_surface_samples(&marker, BodyKind::Maxilla, 0.0), Err(RegisterError::Spacing(_))));
        assert!(matches!(marker_surface_samples(&marker, BodyKind::Maxilla, 1e-4), Err(RegisterError::Spacing(_))));
        // A cube marker is sampled on its six squares.
        let cube = Marker::nominal_on(jawtrack_marker::SolidKind::Cube, marker.family, 12.0, None).expect("cube");
        let samples = marker_surface_samples(&cube, BodyKind::Mandible, 0.5).expect("samples");
        let solid = cube.geometry();
        let mut per_face = [0usize; 6];
        for (p, n) in &samples {
            let face = solid.faces().iter().position(|f| (f.normal - n).norm() < 1e-12).expect("a cube face");
            per_face[face] += 1;
            assert!(solid.faces()[face].distance_inside(&p.coords) >= 0.25 - 1e-9, "inside, away from the edges");
        }
        for count in per_face {
            let expected = (12.0 * 12.0 - 4.0 * 12.0 * 0.25) / 0.25;
            assert!((count as f64 / expected - 1.0).abs() < 0.05, "{count} vs {expected}");
        }
        let only_upper = Marker { bodies: vec![marker.bodies[0].clone()], ..marker.clone() };
        let err = marker_surface_samples(&only_upper, BodyKind::Mandible, 0.5).expect_err("no mandible");
        assert!(err.to_string().contains("no mandible body"), "{err}");
    }

    #[test]
    fn a_marker_file_on_another_solid_is_refused() {
        let mut marker = Marker::default();
        for v in &mut marker.bodies[0].tags[4].face_polygon {
            *v *= 1.02;
        }
        let err = marker_surface_samples(&marker, BodyKind::Maxilla, 0.5).expect_err("not the solid").to_string();
        assert!(err.contains("tag 4") && err.contains("face 4"), "{err}");
    }

    #[test]
    fn bad_options_are_named() {
        for (options, word) in [
            (IcpOptions { max_distance_mm: f64::NAN, ..Default::default() }, "max_distance_mm"),
            (IcpOptions { min_distance_mm: 5.0, ..Default::default() }, "min_distance_mm"),
            (IcpOptions { max_normal_angle_deg: 90.0, ..Default::default() }, "max_normal_angle_deg"),
            (IcpOptions { max_iterations: 0, ..Default::default() }, "max_iterations"),
            (IcpOptions { min_correspondences: 3, ..Default::default() }, "min_correspondences"),
        ] {
            let err = options.validate().expect_err("invalid").to_string();
            assert!(err.contains(word), "{err}");
        }
    }

    #[test]
    fn setting_one_bodys_entry_keeps_the_other() {
        let mut r = crate::Registration::identity();
        let moved = Pose::from_axis_angle(nalgebra::Vector3::zeros(), nalgebra::Vector3::new(1.0, 2.0, 3.0));
        let (set, kept) = set_entry(&mut r, BodyKind::Mandible, moved);
        assert_eq!((set, kept), ("mandible_scan_from_mandible_marker", "maxilla_scan_from_maxilla_marker"));
        assert_eq!(r.mandible_scan_from_mandible_marker, moved);
        assert_eq!(r.maxilla_scan_from_maxilla_marker, Pose::identity());
    }
}
