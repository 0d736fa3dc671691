//! Kinematic contacts: with the lower scan placed by `maxilla_scan_from_mandible_scan`, every
//! vertex of each arch gets its signed distance to the other arch; vertices that penetrate or
//! come within the threshold are grouped into connected regions, and each region gets its
//! area, centroid, deepest penetration (or smallest gap) and tooth. [`ContactMap`] accumulates
//! how often and how deep each vertex was in contact over a motion.
//!
//! Depth is positive for penetration and negative for a gap (mm). Areas count the part of
//! each triangle where the distance, interpolated linearly between its corners, is within
//! the threshold, so a region's area does not jump with the mesh's resolution.

use crate::distance::{Lookup, Nearest, SurfaceIndex, nearest_brute_force};
use crate::mesh::{DisjointSets, Mesh};
use jawtrack_pose::Pose;
use nalgebra::{Point3, Vector3};
use serde::Serialize;

/// The range of contact thresholds that make sense, from shimstock (0.01 mm) to 0.5 mm.
pub const THRESHOLD_RANGE_MM: (f64, f64) = (0.01, 0.5);

/// Which arch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The upper arch.
    Maxilla,
    /// The lower arch.
    Mandible,
}

/// What counts as a contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSettings {
    /// A vertex within this gap (mm) of the other arch, or penetrating it, is in contact.
    pub threshold_mm: f64,
    /// The deepest penetration (mm) measured exactly; deeper vertices are not seen (an open
    /// scan has no "inside" far from its surface).
    pub max_depth_mm: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings { threshold_mm: 0.1, max_depth_mm: 0.5 }
    }
}

impl ContactSettings {
    /// Checks the threshold is within [`THRESHOLD_RANGE_MM`] and the depth positive.
    pub fn validate(&self) -> Result<(), String> {
        let (lo, hi) = THRESHOLD_RANGE_MM;
        if !(lo..=hi).contains(&self.threshold_mm) {
            return Err(format!("the contact threshold must be {lo}-{hi} mm, got {}", self.threshold_mm));
        }
        if !(self.max_depth_mm > 0.0 && self.max_depth_mm <= 10.0) {
            return Err(format!("the measured penetration depth must be 0-10 mm, got {}", self.max_depth_mm));
        }
        Ok(())
    }

    /// How far in front of each surface distances must be known: beyond the threshold too,
    /// so that areas interpolate to the true crossing.
    pub fn above_mm(&self) -> f64 {
        self.threshold_mm * 2.0 + 0.3
    }

    /// The grid spacing of the distance index (mm).
    pub const CELL_MM: f64 = 0.1;
}

/// One arch: its mesh (optionally one part per tooth) indexed for distance queries.
#[derive(Debug, Clone)]
pub struct Arch {
    /// The mesh (mm, in the arch's scan frame).
    pub mesh: Mesh,
    /// Distance queries against it.
    pub index: SurfaceIndex,
    /// Tooth names, when the arch was given one mesh per tooth.
    pub teeth: Vec<String>,
    /// Per triangle, its tooth (index into `teeth`).
    tooth_of_triangle: Vec<u16>,
    /// Per vertex, the triangles around it (CSR).
    vertex_triangle_starts: Vec<u32>,
    vertex_triangles: Vec<u32>,
    /// The vertices in the order they are queried: spatially coherent.
    query_order: Vec<u32>,
    /// Their positions in that order, read one after another.
    ordered_vertices: Vec<Point3<f64>>,
    /// Runs of `query_order` within one [`CLUSTER_MM`] cube, and a sphere holding each, so
    /// that runs far from the other arch are skipped whole.
    clusters: Vec<Cluster>,
}

/// The side of the cubes whose vertices form a cluster (mm).
const CLUSTER_MM: f64 = 1.0;

/// A run of the query order and a sphere holding its vertices.
#[derive(Debug, Clone)]
struct Cluster {
    centre: Point3<f64>,
    radius: f64,
    start: u32,
    end: u32,
}

impl Arch {
    /// An arch from one mesh per named part; with more than one part, the parts are teeth.
    pub fn new(parts: Vec<(String, Mesh)>, settings: &ContactSettings) -> Arch {
        let (names, meshes): (Vec<String>, Vec<Mesh>) = parts.into_iter().unzip();
        let (mesh, tooth_of_triangle) = Mesh::concat(&meshes);
        let teeth = if names.len() > 1 { names } else { Vec::new() };
        // Most lookups ask only whether a vertex is in contact: the index is focused on that.
        let index = SurfaceIndex::with_focus(
            &mesh,
            settings.max_depth_mm,
            settings.above_mm(),
            ContactSettings::CELL_MM,
            settings.threshold_mm,
        );
        let mut counts = vec![0u32; mesh.vertices.len() + 1];
        for t in &mesh.triangles {
            t.iter().for_each(|&v| counts[v as usize + 1] += 1);
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut vertex_triangles = vec![0u32; counts[mesh.vertices.len()] as usize];
        for (k, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                vertex_triangles[fill[v as usize] as usize] = k as u32;
                fill[v as usize] += 1;
            }
        }
        // Clusters are the vertices of one cube of the Z-order's cells.
        let query_order = mesh.spatial_order(CLUSTER_MM);
        let [lo, _] = mesh.bounds();
        let cube = |v: u32| ((mesh.vertices[v as usize].coords - lo) / CLUSTER_MM).map(|x| x.floor() as i64);
        let mut clusters = Vec::new();
        let mut start = 0;
        while start < query_order.len() {
            let key = cube(query_order[start]);
            let end = (start..query_order.len()).find(|&k| cube(query_order[k]) != key).unwrap_or(query_order.len());
            let points = query_order[start..end].iter().map(|&v| mesh.vertices[v as usize].coords);
            let (lo, hi) = points
                .clone()
                .fold((Vector3::repeat(f64::INFINITY), -Vector3::repeat(f64::INFINITY)), |(lo, hi), p| {
                    (lo.inf(&p), hi.sup(&p))
                });
            let centre = Point3::from((lo + hi) / 2.0);
            let radius = points.map(|p| (p - centre.coords).norm()).fold(0.0, f64::max);
            clusters.push(Cluster { centre, radius, start: start as u32, end: end as u32 });
            start = end;
        }
        let ordered_vertices = query_order.iter().map(|&v| mesh.vertices[v as usize]).collect();
        Arch {
            ordered_vertices,
            mesh,
            index,
            teeth,
            tooth_of_triangle,
            vertex_triangle_starts: counts,
            vertex_triangles,
            query_order,
            clusters,
        }
    }

    fn triangles_around(&self, v: usize) -> &[u32] {
        &self.vertex_triangles[self.vertex_triangle_starts[v] as usize..self.vertex_triangle_starts[v + 1] as usize]
    }
}

/// A connected patch of one arch in contact.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Region {
    /// The arch it lies on.
    pub arch: Side,
    /// Its tooth, when the arch was given per tooth (the tooth holding most of its area).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tooth: Option<String>,
    /// Area-weighted centre, in the upper scan's frame (mm).
    pub centroid: [f64; 3],
    /// Area within the threshold (mm²).
    pub area_mm2: f64,
    /// Deepest penetration (mm); negative when the region only comes near: minus the smallest
    /// gap.
    pub depth_mm: f64,
    /// Vertices in contact.
    pub vertices: usize,
}

/// The signed distance of each vertex of an arch to the other arch: exact for the vertices in
/// contact (within the threshold) and for the other corners of their triangles, NaN for the
/// rest.
#[derive(Debug, Clone, PartialEq)]
pub struct VertexDistances(pub Vec<f32>);

/// The contacts at one pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Contacts {
    /// Regions on both arches, largest first.
    pub regions: Vec<Region>,
    /// Per-vertex signed distances (mm) of the upper and the lower arch.
    pub distances: [VertexDistances; 2],
}

impl Contacts {
    /// The deepest penetration over both arches (negative: smallest gap), if any contact.
    pub fn max_depth_mm(&self) -> Option<f64> {
        self.regions.iter().map(|r| r.depth_mm).reduce(f64::max)
    }
}

/// Per-vertex signed distances of `from`'s vertices (moved by `other_from_from`) to the
/// other arch, where `lookup` finds them; clusters that `far` says it would not are skipped
/// whole.
fn distances(
    from: &Arch,
    other_from_from: &Pose,
    far: impl Fn(&Point3<f64>, f64) -> bool,
    lookup: impl Fn(&Point3<f64>) -> Lookup,
) -> VertexDistances {
    let mut d = vec![f32::NAN; from.mesh.vertices.len()];
    // A matrix transforms points faster than the pose's quaternion.
    let (r, t) = (other_from_from.rotation_matrix(), other_from_from.translation());
    for cluster in &from.clusters {
        if far(&Point3::from(r * cluster.centre.coords + t), cluster.radius) {
            continue;
        }
        let run = cluster.start as usize..cluster.end as usize;
        for (&v, q) in from.query_order[run.clone()].iter().zip(&from.ordered_vertices[run]) {
            let p = Point3::from(r * q.coords + t);
            d[v as usize] = match lookup(&p) {
                Lookup::Far => f32::NAN,
                Lookup::Approximate(x) => x as f32,
                Lookup::Exact(n) => n.distance as f32,
            };
        }
    }
    VertexDistances(d)
}

/// The contacts between `upper` and `lower` with the lower scan at `maxilla_scan_from_mandible_scan`.
pub fn contacts(
    upper: &Arch,
    lower: &Arch,
    maxilla_scan_from_mandible_scan: &Pose,
    settings: &ContactSettings,
) -> Contacts {
    let to_upper = *maxilla_scan_from_mandible_scan;
    let to_lower = to_upper.inverse();
    let (lo, hi, t) = (-settings.max_depth_mm, settings.above_mm(), settings.threshold_mm);
    // First the vertices in contact, then the other corners of their triangles, which set the
    // areas.
    let mut d_upper =
        distances(upper, &to_lower, |c, r| lower.index.far_from(c, r, (lo, t)), |p| lower.index.lookup(p, lo, t, t));
    let mut d_lower =
        distances(lower, &to_upper, |c, r| upper.index.far_from(c, r, (lo, t)), |p| upper.index.lookup(p, lo, t, t));
    exact_around_contacts(upper, &mut d_upper, t, |p| lower.index.lookup(&to_lower.transform_point(p), lo, hi, hi));
    exact_around_contacts(lower, &mut d_lower, t, |p| upper.index.lookup(&to_upper.transform_point(p), lo, hi, hi));
    regions_from(upper, lower, &to_upper, [d_upper, d_lower], settings)
}

/// Finds the distances of the vertices sharing a triangle with a vertex in contact.
fn exact_around_contacts(
    arch: &Arch,
    d: &mut VertexDistances,
    threshold: f64,
    lookup: impl Fn(&Point3<f64>) -> Lookup,
) {
    let flagged: Vec<usize> = (0..d.0.len()).filter(|&v| d.0[v] as f64 <= threshold).collect();
    let mut done = vec![false; d.0.len()];
    for v in flagged {
        for &tri in arch.triangles_around(v) {
            for &corner in &arch.mesh.triangles[tri as usize] {
                let c = corner as usize;
                // Not yet known: every vertex with a value so far is in contact.
                if d.0[c].is_nan() && !std::mem::replace(&mut done[c], true) {
                    d.0[c] = match lookup(&arch.mesh.vertices[c]) {
                        Lookup::Exact(n) => n.distance as f32,
                        Lookup::Approximate(x) => x as f32,
                        Lookup::Far => f32::NAN,
                    };
                }
            }
        }
    }
}

/// The same as [`contacts`], testing every triangle for every vertex (and exact everywhere in
/// the band): the reference for tests.
pub fn contacts_brute_force(
    upper: &Arch,
    lower: &Arch,
    maxilla_scan_from_mandible_scan: &Pose,
    settings: &ContactSettings,
) -> Contacts {
    let (lo, hi) = (-settings.max_depth_mm, settings.above_mm());
    let within = |n: Option<Nearest>| match n {
        Some(n) if (lo..=hi).contains(&n.distance) => Lookup::Exact(n),
        _ => Lookup::Far,
    };
    let to_upper = *maxilla_scan_from_mandible_scan;
    let to_lower = to_upper.inverse();
    let never = |_: &Point3<f64>, _: f64| false;
    let d_upper = distances(upper, &to_lower, never, |p| within(nearest_brute_force(lower.index.surface(), p)));
    let d_lower = distances(lower, &to_upper, never, |p| within(nearest_brute_force(upper.index.surface(), p)));
    regions_from(upper, lower, &to_upper, [d_upper, d_lower], settings)
}

fn regions_from(
    upper: &Arch,
    lower: &Arch,
    maxilla_scan_from_mandible_scan: &Pose,
    distances: [VertexDistances; 2],
    settings: &ContactSettings,
) -> Contacts {
    let mut regions = arch_regions(upper, Side::Maxilla, &distances[0], &Pose::identity(), settings);
    regions.extend(arch_regions(lower, Side::Mandible, &distances[1], maxilla_scan_from_mandible_scan, settings));
    regions.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
    Contacts { regions, distances }
}

/// Regions of one arch from its per-vertex distances.
fn arch_regions(
    arch: &Arch,
    side: Side,
    d: &VertexDistances,
    to_upper: &Pose,
    settings: &ContactSettings,
) -> Vec<Region> {
    let t = settings.threshold_mm;
    let reach = settings.above_mm();
    let in_contact = |v: usize| d.0[v] as f64 <= t; // NaN compares false
    let flagged: Vec<usize> = (0..d.0.len()).filter(|&v| in_contact(v)).collect();
    if flagged.is_empty() {
        return Vec::new();
    }
    let mut sets = DisjointSets::new(arch.mesh.vertices.len());
    let mut seen = vec![false; arch.mesh.triangles.len()];
    let mut triangles = Vec::new();
    for &v in &flagged {
        for &tri in arch.triangles_around(v) {
            if !std::mem::replace(&mut seen[tri as usize], true) {
                triangles.push(tri as usize);
                let ids = arch.mesh.triangles[tri as usize];
                for k in 0..3 {
                    let (a, b) = (ids[k] as usize, ids[(k + 1) % 3] as usize);
                    if in_contact(a) && in_contact(b) {
                        sets.union(a, b);
                    }
                }
            }
        }
    }
    struct Acc {
        area: f64,
        moment: Vector3<f64>,
        depth: f64,
        vertices: usize,
        tooth_area: Vec<(u16, f64)>,
    }
    // Per region root, its accumulator's place, in order of first appearance.
    let mut slot_of = vec![u32::MAX; arch.mesh.vertices.len()];
    let mut accs: Vec<Acc> = Vec::new();
    for &v in &flagged {
        let root = sets.find(v);
        if slot_of[root] == u32::MAX {
            slot_of[root] = accs.len() as u32;
            accs.push(Acc {
                area: 0.0,
                moment: Vector3::zeros(),
                depth: f64::NEG_INFINITY,
                vertices: 0,
                tooth_area: Vec::new(),
            });
        }
        let acc = &mut accs[slot_of[root] as usize];
        acc.depth = acc.depth.max(-(d.0[v] as f64));
        acc.vertices += 1;
    }
    for tri in triangles {
        let ids = arch.mesh.triangles[tri];
        let Some(&v) = ids.iter().find(|&&v| in_contact(v as usize)) else { continue };
        let values = ids.map(|i| {
            let x = d.0[i as usize] as f64;
            if x.is_nan() { reach } else { x }
        });
        let (area, centroid) = clipped_area(&arch.mesh.corners(tri), &values, t);
        let acc = &mut accs[slot_of[sets.find(v as usize)] as usize];
        acc.area += area;
        acc.moment += centroid.coords * area;
        let tooth = arch.tooth_of_triangle[tri];
        match acc.tooth_area.iter_mut().find(|x| x.0 == tooth) {
            Some(x) => x.1 += area,
            None => acc.tooth_area.push((tooth, area)),
        }
    }
    accs.into_iter()
        .map(|acc| {
            let local = if acc.area > 0.0 { Point3::from(acc.moment / acc.area) } else { Point3::origin() };
            let c = to_upper.transform_point(&local);
            let tooth = acc
                .tooth_area
                .iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .and_then(|(k, _)| arch.teeth.get(*k as usize).cloned());
            Region {
                arch: side,
                tooth,
                centroid: [c.x, c.y, c.z],
                area_mm2: acc.area,
                depth_mm: acc.depth,
                vertices: acc.vertices,
            }
        })
        .collect()
}

/// The area and centroid of the part of triangle `p` where the linear interpolation of
/// `values` is at most `t`.
pub fn clipped_area(p: &[Point3<f64>; 3], values: &[f64; 3], t: f64) -> (f64, Point3<f64>) {
    // A triangle cut by a plane keeps at most four corners.
    let (mut poly, mut n) = ([p[0]; 4], 0);
    for k in 0..3 {
        let (a, b) = (k, (k + 1) % 3);
        let (fa, fb) = (values[a] - t, values[b] - t);
        if fa <= 0.0 {
            poly[n] = p[a];
            n += 1;
        }
        if (fa <= 0.0) != (fb <= 0.0) {
            let s = fa / (fa - fb);
            poly[n] = p[a] + (p[b] - p[a]) * s;
            n += 1;
        }
    }
    let poly = &poly[..n];
    if poly.len() < 3 {
        return (0.0, p[0]);
    }
    let (mut area, mut moment) = (0.0, Vector3::zeros());
    for k in 1..poly.len() - 1 {
        let a = (poly[k] - poly[0]).cross(&(poly[k + 1] - poly[0])).norm() / 2.0;
        area += a;
        moment += (poly[0].coords + poly[k].coords + poly[k + 1].coords) / 3.0 * a;
    }
    let centroid = if area > 0.0 { Point3::from(moment / area) } else { poly[0] };
    (area, centroid)
}

/// How often and how deeply each vertex was in contact over a motion.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactMap {
    /// Frames added.
    pub frames: u32,
    /// Per arch (upper, lower), per vertex: frames in contact.
    pub hits: [Vec<u32>; 2],
    /// Per arch, per vertex: deepest penetration seen (mm; negative: closest gap), counting
    /// the frames where it was in contact or the corner of a triangle in contact; -inf if
    /// never.
    pub max_depth: [Vec<f32>; 2],
}

impl ContactMap {
    /// An empty map for two arches.
    pub fn new(upper: &Arch, lower: &Arch) -> Self {
        let n = [upper.mesh.vertices.len(), lower.mesh.vertices.len()];
        ContactMap { frames: 0, hits: n.map(|n| vec![0; n]), max_depth: n.map(|n| vec![f32::NEG_INFINITY; n]) }
    }

    /// Adds one frame's contacts.
    pub fn add(&mut self, contacts: &Contacts, settings: &ContactSettings) {
        self.frames += 1;
        for arch in 0..2 {
            for (v, &d) in contacts.distances[arch].0.iter().enumerate() {
                if d.is_nan() {
                    continue;
                }
                if d as f64 <= settings.threshold_mm {
                    self.hits[arch][v] += 1;
                }
                self.max_depth[arch][v] = self.max_depth[arch][v].max(-d);
            }
        }
    }

    /// Per-vertex colours of one arch: grey where never in contact, then blue → green →
    /// yellow → red with the fraction of frames in contact.
    pub fn frequency_colours(&self, arch: usize) -> Vec<[u8; 3]> {
        let frames = self.frames.max(1) as f64;
        self.hits[arch].iter().map(|&h| if h == 0 { GREY } else { ramp(h as f64 / frames) }).collect()
    }

    /// Per-vertex colours of one arch by deepest contact: grey beyond the threshold, blue at
    /// the threshold's gap through green (touching) to red at `full_depth_mm` penetration.
    pub fn depth_colours(&self, arch: usize, settings: &ContactSettings, full_depth_mm: f64) -> Vec<[u8; 3]> {
        let t = settings.threshold_mm;
        self.max_depth[arch]
            .iter()
            .map(|&d| {
                let d = d as f64;
                if d < -t {
                    GREY
                } else if d <= 0.0 {
                    ramp(0.5 * (d + t) / t)
                } else {
                    ramp(0.5 + 0.5 * (d / full_depth_mm).min(1.0))
                }
            })
            .collect()
    }
}

/// Colour of vertices never in contact.
pub const GREY: [u8; 3] = [205, 200, 190];

/// Blue → cyan → green → yellow → red for `x` in 0..1.
pub fn ramp(x: f64) -> [u8; 3] {
    let x = x.clamp(0.0, 1.0) * 4.0;
    let (r, g, b) = match x {
        x if x < 1.0 => (0.0, x, 1.0),
        x if x < 2.0 => (0.0, 1.0, 2.0 - x),
        x if x < 3.0 => (x - 2.0, 1.0, 0.0),
        x => (1.0, 4.0 - x, 0.0),
    };
    [(r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8]
}
