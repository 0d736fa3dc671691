//! Kinematic contacts: with the lower scan placed by `maxilla_scan_from_mandible_scan`, the
//! vertices of each arch that penetrate the other arch or come within the threshold of it are
//! found with their exact signed distances, and grouped into connected regions; each region
//! gets its area, centroid, deepest penetration (or smallest gap) and tooth. [`ContactMap`]
//! accumulates how often and how deep each vertex was in contact over a motion. A frame's
//! work grows with its contacts, not with the arches' size: far vertices are rejected in
//! clusters, and nothing per vertex of the arch is cleared or scanned.
//!
//! Depth is positive for penetration and negative for a gap (mm). Areas count the part of
//! each triangle where the distance, interpolated linearly between its corners, is within
//! the threshold, so a region's area does not jump with the mesh's resolution.

use crate::distance::{Lookup, Nearest, Screen, Search, SurfaceIndex, nearest_brute_force};
use crate::mesh::{DisjointSets, Mesh};
use jawtrack_pose::Pose;
use nalgebra::{Point3, Vector3};
use serde::Serialize;
use std::path::Path;

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
    /// The mesh (mm, in the arch's scan frame), as given: results name its vertices.
    pub mesh: Mesh,
    /// Distance queries against it.
    pub index: SurfaceIndex,
    /// Tooth names, when the arch was given one mesh per tooth.
    pub teeth: Vec<String>,
    /// The same mesh renumbered for a frame's walks: vertices in the order they are queried
    /// (1 mm cubes in Z-order) and triangles by their first vertex, so that a patch of
    /// contact reads its vertices, triangles and bookkeeping from a few places in memory
    /// rather than from all over the arch.
    walk: Mesh,
    /// Per vertex of `walk`, its index in `mesh`.
    given_vertex: Vec<u32>,
    /// Per triangle of `walk`, its tooth (index into `teeth`).
    tooth_of_triangle: Vec<u16>,
    /// Per vertex of `walk`, the triangles around it (CSR).
    vertex_triangle_starts: Vec<u32>,
    vertex_triangles: Vec<u32>,
    /// Runs of `walk`'s vertices within one [`CLUSTER_MM`] cube, and a sphere holding each,
    /// so that runs far from the other arch are skipped whole.
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
        let (mesh, given_tooth) = Mesh::concat(&meshes);
        let teeth = if names.len() > 1 { names } else { Vec::new() };
        // Most lookups ask only whether a vertex is in contact: the index is focused on that.
        let index = SurfaceIndex::with_focus(
            &mesh,
            settings.max_depth_mm,
            settings.above_mm(),
            ContactSettings::CELL_MM,
            settings.threshold_mm,
        );
        let given_vertex = mesh.spatial_order(CLUSTER_MM);
        let mut walk_vertex = vec![0u32; mesh.vertices.len()];
        for (k, &v) in given_vertex.iter().enumerate() {
            walk_vertex[v as usize] = k as u32;
        }
        let mut triangles: Vec<([u32; 3], u16)> = mesh
            .triangles
            .iter()
            .zip(&given_tooth)
            .map(|(t, &tooth)| (t.map(|v| walk_vertex[v as usize]), tooth))
            .collect();
        triangles.sort_by_key(|(t, _)| t.iter().copied().min());
        let (triangles, tooth_of_triangle): (Vec<[u32; 3]>, Vec<u16>) = triangles.into_iter().unzip();
        let walk = Mesh { vertices: given_vertex.iter().map(|&v| mesh.vertices[v as usize]).collect(), triangles };
        let mut counts = vec![0u32; walk.vertices.len() + 1];
        for t in &walk.triangles {
            t.iter().for_each(|&v| counts[v as usize + 1] += 1);
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut vertex_triangles = vec![0u32; counts[walk.vertices.len()] as usize];
        for (k, t) in walk.triangles.iter().enumerate() {
            for &v in t {
                vertex_triangles[fill[v as usize] as usize] = k as u32;
                fill[v as usize] += 1;
            }
        }
        // Clusters are the vertices of one cube of the Z-order's cells.
        let [lo, _] = walk.bounds();
        let cube = |v: usize| ((walk.vertices[v].coords - lo) / CLUSTER_MM).map(|x| x.floor() as i64);
        let mut clusters = Vec::new();
        let mut start = 0;
        while start < walk.vertices.len() {
            let key = cube(start);
            let end = (start..walk.vertices.len()).find(|&k| cube(k) != key).unwrap_or(walk.vertices.len());
            let points = walk.vertices[start..end].iter().map(|p| p.coords);
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
        Arch {
            mesh,
            index,
            teeth,
            walk,
            given_vertex,
            tooth_of_triangle,
            vertex_triangle_starts: counts,
            vertex_triangles,
            clusters,
        }
    }

    /// The triangles of `walk` around its vertex `v`.
    fn triangles_around(&self, v: usize) -> &[u32] {
        &self.vertex_triangles[self.vertex_triangle_starts[v] as usize..self.vertex_triangle_starts[v + 1] as usize]
    }
}

/// The tooth name of a per-tooth mesh file, as scanners export them: `NN` when its stem
/// holds `FDI=NN`, else the stem.
pub fn tooth_name(path: &Path) -> String {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if let Some(at) = stem.find("FDI=") {
        let digits: String = stem[at + 4..].chars().take_while(char::is_ascii_digit).collect();
        if !digits.is_empty() {
            return digits;
        }
    }
    stem
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

/// The signed distances (mm) that one frame found for vertices of one arch, as (vertex,
/// distance): every vertex in contact (within the threshold) and the other corners of their
/// triangles, exact (those beyond the band left out), and some other vertices just beyond the
/// threshold found on the way. Only these are listed, in no
/// particular order, so that a frame costs what its contacts do and not what the arch's size
/// does. [`contacts_brute_force`] lists every vertex within the band.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct VertexDistances(pub Vec<(u32, f32)>);

impl VertexDistances {
    /// The distance of each of an arch's `n` vertices, NaN where none was found.
    pub fn dense(&self, n: usize) -> Vec<f32> {
        let mut d = vec![f32::NAN; n];
        for &(v, x) in &self.0 {
            if let Some(slot) = d.get_mut(v as usize) {
                *slot = x;
            }
        }
        d
    }
}

/// The contacts at one pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Contacts {
    /// Regions on both arches, largest first.
    pub regions: Vec<Region>,
    /// The signed distances (mm) found on the upper and the lower arch.
    pub distances: [VertexDistances; 2],
}

impl Contacts {
    /// The deepest penetration over both arches (negative: smallest gap), if any contact.
    pub fn max_depth_mm(&self) -> Option<f64> {
        self.regions.iter().map(|r| r.depth_mm).reduce(f64::max)
    }
}

/// The vertices of one arch that a frame looked up, with their signed distances (NaN: out of
/// the band), and where each vertex is in the list.
struct Found<'a> {
    vertices: Vec<u32>,
    values: Vec<f32>,
    slots: &'a mut Slots,
}

impl Found<'_> {
    fn push(&mut self, v: u32, value: f32) {
        self.slots.set(v as usize, self.vertices.len());
        self.vertices.push(v);
        self.values.push(value);
    }

    /// The distances found, naming the vertices of the mesh as given (`given_vertex`); the
    /// list's buffers go back to the slots for the next frame.
    fn finish(mut self, given_vertex: &[u32]) -> VertexDistances {
        let distances = VertexDistances(
            self.vertices
                .iter()
                .zip(&self.values)
                .filter(|(_, d)| !d.is_nan())
                .map(|(&v, &d)| (given_vertex[v as usize], d))
                .collect(),
        );
        self.vertices.clear();
        self.values.clear();
        self.slots.buffers = (self.vertices, self.values);
        distances
    }
}

/// Per vertex of an arch, where a frame's [`Found`] lists it; an entry holds only where its
/// stamp is the current epoch, so nothing of the arch's size is cleared per frame. One is
/// kept per thread and reused.
#[derive(Default)]
struct Slots {
    /// Per vertex: (stamp, place in the list).
    entries: Vec<(u32, u32)>,
    /// Per triangle: the stamp of the last list that walked it.
    walked: Vec<u32>,
    epoch: u32,
    /// A list's vertices and values, kept between frames so that they are not grown anew.
    buffers: (Vec<u32>, Vec<f32>),
}

impl Slots {
    /// Starts a new list over `n` vertices and `m` triangles.
    fn begin(&mut self, n: usize, m: usize) {
        if self.entries.len() < n {
            self.entries.resize(n, (0, 0));
        }
        if self.walked.len() < m {
            self.walked.resize(m, 0);
        }
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.entries.fill((0, 0));
            self.walked.fill(0);
            self.epoch = 1;
        }
    }

    /// Whether triangle `t` is walked for the first time in this list; marks it walked.
    fn first_walk(&mut self, t: usize) -> bool {
        let first = self.walked[t] != self.epoch;
        self.walked[t] = self.epoch;
        first
    }

    fn get(&self, v: usize) -> Option<usize> {
        let (stamp, k) = self.entries[v];
        (stamp == self.epoch).then_some(k as usize)
    }

    fn set(&mut self, v: usize, k: usize) {
        self.entries[v] = (self.epoch, k as u32);
    }
}

thread_local! {
    static SLOTS: std::cell::RefCell<Slots> = std::cell::RefCell::default();
}

/// Runs `f` with this thread's [`Slots`], begun over `n` vertices and `m` triangles.
fn with_slots<R>(n: usize, m: usize, f: impl FnOnce(&mut Slots) -> R) -> R {
    SLOTS.with_borrow_mut(|slots| {
        slots.begin(n, m);
        f(slots)
    })
}

/// Adds to `found` the vertices of `from` (moved by `other_from_from`) that `screen_many` finds
/// near the other arch, `index`; clusters that `far` says it would not are skipped whole.
fn distances(
    from: &Arch,
    other_from_from: &Pose,
    far: impl Fn(&Point3<f64>, f64) -> bool,
    screen_many: impl Fn(&[Point3<f64>], &mut dyn FnMut(usize, Screen)),
    index: &SurfaceIndex,
    found: &mut Found,
) {
    // Exact searches wait in batches, each holding its place in the list: see
    // `SurfaceIndex::warm`.
    const BATCH: usize = 32;
    let mut waiting: Vec<(usize, Search)> = Vec::with_capacity(BATCH);
    let search = |waiting: &mut Vec<(usize, Search)>, found: &mut Found| {
        std::hint::black_box(waiting.iter().map(|(_, s)| index.warm(s)).sum::<f64>());
        for (at, s) in waiting.drain(..) {
            found.values[at] = index.search(&s).distance as f32;
        }
    };
    // A matrix transforms points faster than the pose's quaternion.
    let (r, t) = (other_from_from.rotation_matrix(), other_from_from.translation());
    // Points of several clusters are screened together, so that more of their reads overlap:
    // see `SurfaceIndex::screen_many`.
    const GATHER: usize = 64;
    let (mut points, mut ids) = (Vec::with_capacity(2 * GATHER), Vec::with_capacity(2 * GATHER));
    let mut screen = |points: &mut Vec<Point3<f64>>, ids: &mut Vec<u32>, waiting: &mut Vec<(usize, Search)>| {
        screen_many(points, &mut |j, screened| {
            let v = ids[j];
            match screened {
                Screen::Answered(Lookup::Far) => {}
                Screen::Answered(Lookup::Approximate(x)) => found.push(v, x as f32),
                Screen::Answered(Lookup::Exact(n)) => found.push(v, n.distance as f32),
                Screen::Search(s) => {
                    found.push(v, f32::NAN);
                    waiting.push((found.vertices.len() - 1, s));
                    if waiting.len() == BATCH {
                        search(waiting, found);
                    }
                }
            }
        });
        points.clear();
        ids.clear();
    };
    for cluster in &from.clusters {
        if far(&Point3::from(r * cluster.centre.coords + t), cluster.radius) {
            continue;
        }
        let (start, end) = (cluster.start as usize, cluster.end as usize);
        points.extend(from.walk.vertices[start..end].iter().map(|q| Point3::from(r * q.coords + t)));
        ids.extend(cluster.start..cluster.end);
        if points.len() >= GATHER {
            screen(&mut points, &mut ids, &mut waiting);
        }
    }
    screen(&mut points, &mut ids, &mut waiting);
    search(&mut waiting, found);
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
    // Vertices just beyond the threshold that were found exactly on the way are kept: some
    // are corners of triangles in contact, which need not be found again.
    let find = |arch: &Arch, other: &Arch, other_from_arch: &Pose, found: &mut Found| {
        let far = |c: &Point3<f64>, r: f64| other.index.far_from(c, r, (lo, t));
        distances(
            arch,
            other_from_arch,
            far,
            |points: &[Point3<f64>], answer: &mut dyn FnMut(usize, Screen)| {
                other.index.screen_many(points, lo, t, t, answer)
            },
            &other.index,
            found,
        );
    };
    // The other corners of triangles in contact are looked up over the whole band, since
    // they set the areas.
    let corner = |other: &Arch, other_from_arch: &Pose, p: &Point3<f64>| {
        other.index.lookup(&other_from_arch.transform_point(p), lo, hi, hi)
    };
    both_arches(
        arch_contacts(
            upper,
            Side::Maxilla,
            &Pose::identity(),
            settings,
            |f| find(upper, lower, &to_lower, f),
            |p| corner(lower, &to_lower, p),
        ),
        arch_contacts(
            lower,
            Side::Mandible,
            &to_upper,
            settings,
            |f| find(lower, upper, &to_upper, f),
            |p| corner(upper, &to_upper, p),
        ),
    )
}

/// The regions and distances of one arch, from the distances `find` adds to its list and
/// those `lookup` gives for the other corners of triangles in contact.
fn arch_contacts(
    arch: &Arch,
    side: Side,
    upper_from_arch: &Pose,
    settings: &ContactSettings,
    find: impl FnOnce(&mut Found),
    lookup: impl Fn(&Point3<f64>) -> Lookup,
) -> (Vec<Region>, VertexDistances) {
    with_slots(arch.walk.vertices.len(), arch.walk.triangles.len(), |slots| {
        let (vertices, values) = std::mem::take(&mut slots.buffers);
        let mut found = Found { vertices, values, slots };
        find(&mut found);
        let regions = arch_regions(arch, side, &mut found, upper_from_arch, settings, lookup);
        (regions, found.finish(&arch.given_vertex))
    })
}

/// Both arches' results together, regions largest first.
fn both_arches(upper: (Vec<Region>, VertexDistances), lower: (Vec<Region>, VertexDistances)) -> Contacts {
    let mut regions = upper.0;
    regions.extend(lower.0);
    regions.sort_by(|a, b| b.area_mm2.total_cmp(&a.area_mm2));
    Contacts { regions, distances: [upper.1, lower.1] }
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
    let find = |arch: &Arch, other: &Arch, other_from_arch: &Pose, found: &mut Found| {
        let screen = |p: &Point3<f64>| Screen::Answered(within(nearest_brute_force(other.index.surface(), p)));
        let screen_many = |points: &[Point3<f64>], answer: &mut dyn FnMut(usize, Screen)| {
            points.iter().enumerate().for_each(|(j, p)| answer(j, screen(p)))
        };
        distances(arch, other_from_arch, never, screen_many, &other.index, found);
    };
    // Everything in the band was found: other corners are out of it.
    let out_of_band = |_: &Point3<f64>| Lookup::Far;
    both_arches(
        arch_contacts(
            upper,
            Side::Maxilla,
            &Pose::identity(),
            settings,
            |f| find(upper, lower, &to_lower, f),
            out_of_band,
        ),
        arch_contacts(lower, Side::Mandible, &to_upper, settings, |f| find(lower, upper, &to_upper, f), out_of_band),
    )
}

/// Regions of one arch from the distances found on it. The corners of triangles in contact
/// that were not found are looked up with `lookup` (in the arch's own frame) and added to
/// `found` on the way.
fn arch_regions(
    arch: &Arch,
    side: Side,
    found: &mut Found,
    to_upper: &Pose,
    settings: &ContactSettings,
    lookup: impl Fn(&Point3<f64>) -> Lookup,
) -> Vec<Region> {
    let t = settings.threshold_mm;
    let reach = settings.above_mm();
    // NaN (out of the band) compares false: not in contact.
    let in_contact = |x: f32| x as f64 <= t;
    let (triangles, joins) = contact_triangles(arch, found, t, lookup);
    let flagged: Vec<usize> = (0..found.vertices.len()).filter(|&k| in_contact(found.values[k])).collect();
    if flagged.is_empty() {
        return Vec::new();
    }
    // Union-find over places in the list.
    let mut sets = DisjointSets::new(found.vertices.len());
    joins.into_iter().for_each(|(a, b)| sets.union(a, b));
    // Per region root, its accumulator's place, in order of first appearance.
    let mut slot_of = vec![u32::MAX; found.vertices.len()];
    let mut accs: Vec<Acc> = Vec::new();
    for &k in &flagged {
        let root = sets.find(k);
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
        acc.depth = acc.depth.max(-(found.values[k] as f64));
        acc.vertices += 1;
    }
    for (tri, places) in triangles {
        let Some(&first) = places.iter().find(|&&at| in_contact(found.values[at])) else { continue };
        let values = places.map(|at| match found.values[at] {
            x if x.is_nan() => reach,
            x => x as f64,
        });
        let (area, centroid) = clipped_area(&arch.walk.corners(tri), &values, t);
        let acc = &mut accs[slot_of[sets.find(first)] as usize];
        acc.area += area;
        acc.moment += centroid.coords * area;
        let tooth = arch.tooth_of_triangle[tri];
        match acc.tooth_area.iter_mut().find(|x| x.0 == tooth) {
            Some(x) => x.1 += area,
            None => acc.tooth_area.push((tooth, area)),
        }
    }
    accs.into_iter().map(|acc| acc.region(arch, side, to_upper)).collect()
}

/// A triangle and its corners' places in `found`.
type Placed = (usize, [usize; 3]);

/// The triangles around the vertices in contact (within `t`), each as (triangle, its corners'
/// places in `found`), and the edges joining two vertices in contact (as places). One walk,
/// including the vertices that the lookups of missing corners add; each triangle is kept once.
fn contact_triangles(
    arch: &Arch,
    found: &mut Found,
    t: f64,
    lookup: impl Fn(&Point3<f64>) -> Lookup,
) -> (Vec<Placed>, Vec<(usize, usize)>) {
    // NaN (out of the band) compares false: not in contact.
    let in_contact = |x: f32| x as f64 <= t;
    let (mut triangles, mut joins) = (Vec::new(), Vec::new());
    let mut k = 0;
    while k < found.vertices.len() {
        if !in_contact(found.values[k]) {
            k += 1;
            continue;
        }
        let v = found.vertices[k];
        for &tri in arch.triangles_around(v as usize) {
            // Each triangle once.
            if !found.slots.first_walk(tri as usize) {
                continue;
            }
            let ids = arch.walk.triangles[tri as usize];
            let mut places = [0usize; 3];
            for (place, &c) in places.iter_mut().zip(&ids) {
                *place = match found.slots.get(c as usize) {
                    Some(at) => at,
                    None => {
                        let d = match lookup(&arch.walk.vertices[c as usize]) {
                            Lookup::Exact(n) => n.distance as f32,
                            Lookup::Approximate(x) => x as f32,
                            Lookup::Far => f32::NAN,
                        };
                        found.push(c, d);
                        found.vertices.len() - 1
                    }
                };
            }
            let contact = places.map(|at| in_contact(found.values[at]));
            triangles.push((tri as usize, places));
            for a in 0..3 {
                let b = (a + 1) % 3;
                if contact[a] && contact[b] {
                    joins.push((places[a], places[b]));
                }
            }
        }
        k += 1;
    }
    (triangles, joins)
}

/// One region's sums while `arch_regions` gathers it.
struct Acc {
    area: f64,
    moment: Vector3<f64>,
    depth: f64,
    vertices: usize,
    tooth_area: Vec<(u16, f64)>,
}

impl Acc {
    /// The region: its centroid in the upper arch's frame, on the tooth with most of its area.
    fn region(self, arch: &Arch, side: Side, to_upper: &Pose) -> Region {
        let local = if self.area > 0.0 { Point3::from(self.moment / self.area) } else { Point3::origin() };
        let c = to_upper.transform_point(&local);
        let tooth = self
            .tooth_area
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .and_then(|(k, _)| arch.teeth.get(*k as usize).cloned());
        Region {
            arch: side,
            tooth,
            centroid: [c.x, c.y, c.z],
            area_mm2: self.area,
            depth_mm: self.depth,
            vertices: self.vertices,
        }
    }
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
            for &(v, d) in &contacts.distances[arch].0 {
                let v = v as usize;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tooth_names_come_from_fdi_tags_or_stems() {
        assert_eq!(tooth_name(Path::new("dir/lower_FDI=36.stl")), "36");
        assert_eq!(tooth_name(Path::new("FDI=11_upper.obj")), "11");
        assert_eq!(tooth_name(Path::new("molar.ply")), "molar");
        assert_eq!(tooth_name(Path::new("odd_FDI=.ply")), "odd_FDI=");
    }
}
