//! The ray caster: linear-light radiance of a scene of dodecahedron markers, a textured
//! background plane and occluders, with exact box-filter anti-aliasing.
//!
//! Each pixel integrates the radiance over its square (a sensor pixel with a full fill
//! factor). The scene is made of convex, constant-albedo regions (tag cells, white margins,
//! clutter shapes), so a pixel whose four corners see the same region is uniform and needs no
//! more rays; every other pixel is integrated with 128 samples stratified along both axes at
//! once (a rank-1 lattice, shifted per pixel), which places an edge of any direction to a few
//! hundredths of a pixel in one row and far better along a whole edge.

use jawtrack_apriltag::{TagBitmap, TagFamily};
use jawtrack_marker::{Body, Solid, SolidKind};
use jawtrack_pose::{CameraIntrinsics, Pose};
use nalgebra::{Point2, Vector2, Vector3};
use rayon::prelude::*;

/// Printed white paper (linear albedo).
pub const PAPER_ALBEDO: f32 = 0.85;
/// Printed black ink.
pub const INK_ALBEDO: f32 = 0.04;

/// A camera: intrinsics and image size (px).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Intrinsics (pixel centres at integers).
    pub intrinsics: CameraIntrinsics,
    /// Image width (px).
    pub width: u32,
    /// Image height (px).
    pub height: u32,
}

/// One marker body placed in the camera frame.
#[derive(Debug, Clone)]
pub struct PlacedBody<'a> {
    /// The body's tags (the true geometry, print errors included).
    pub body: &'a Body,
    /// The solid they are glued on (the marker's) …
    pub solid: SolidKind,
    /// … and its edge (mm).
    pub edge: f64,
    /// The family the tags are printed in (the marker's).
    pub family: TagFamily,
    /// Where the body is.
    pub camera_from_body: Pose,
}

/// A convex polygon of constant albedo on a plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    /// Vertices in the plane's 2-D coordinates (mm), counter-clockwise.
    pub polygon: Vec<[f64; 2]>,
    /// Linear albedo.
    pub albedo: f32,
}

/// A textured plane: the patient's face behind the markers, or an occluder in front.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    /// Maps the plane's frame (the plane is z = 0, its normal +z) into the camera frame.
    pub camera_from_plane: Pose,
    /// Albedo outside every shape; `None` makes the plane transparent there (an occluder is
    /// only its shapes).
    pub albedo: Option<f32>,
    /// Shapes drawn on it; the last one listed wins where they overlap.
    pub shapes: Vec<Shape>,
}

/// Everything needed to render one instant.
#[derive(Debug, Clone)]
pub struct RenderScene<'a> {
    /// The camera.
    pub camera: Camera,
    /// The markers.
    pub bodies: Vec<PlacedBody<'a>>,
    /// Background and occluder planes.
    pub planes: Vec<Plane>,
    /// Unit vector toward the light, camera frame.
    pub light_dir: Vector3<f64>,
    /// Fraction of light reaching surfaces facing away from the light.
    pub ambient: f64,
}

/// Linear radiance and depth of a rendered instant.
#[derive(Debug, Clone)]
pub struct LinearImage {
    /// Width (px).
    pub width: u32,
    /// Height (px).
    pub height: u32,
    /// Radiance per pixel, row-major, 1.0 = white paper fully lit is `PAPER_ALBEDO`.
    pub radiance: Vec<f32>,
    /// Camera-frame z (mm) of what each pixel sees (infinity where nothing).
    pub depth: Vec<f32>,
}

#[derive(Clone, Copy)]
struct Sample {
    id: u32,
    value: f32,
    depth: f32,
}

const NOTHING: Sample = Sample { id: 0, value: 0.0, depth: f32::INFINITY };

struct FaceC {
    normal: Vector3<f64>,
    offset: f64,
    shade: f32,
    tag: Option<TagC>,
}

struct TagC {
    center: Vector3<f64>,
    x: Vector3<f64>,
    y: Vector3<f64>,
    inv_half: f64,
    bitmap: TagBitmap,
}

struct BodyC {
    faces: Vec<FaceC>,
    /// Screen bounding box (px, inclusive) of the body's circumsphere, or None if off-screen.
    bbox: Option<[f64; 4]>,
}

struct ShapeC {
    edges: Vec<(Vector2<f64>, f64)>,
    bbox: [f64; 4],
    albedo: f32,
}

struct PlaneC {
    normal: Vector3<f64>,
    offset: f64,
    origin: Vector3<f64>,
    ex: Vector3<f64>,
    ey: Vector3<f64>,
    albedo: Option<f32>,
    shade: f32,
    shapes: Vec<ShapeC>,
}

/// The scene moved into the camera frame, ready for ray queries.
struct Prepared {
    bodies: Vec<BodyC>,
    planes: Vec<PlaneC>,
}

fn shade(normal: &Vector3<f64>, light: &Vector3<f64>, ambient: f64) -> f32 {
    (ambient + (1.0 - ambient) * normal.dot(light).max(0.0)) as f32
}

impl Prepared {
    fn new(scene: &RenderScene<'_>) -> Self {
        let light = scene.light_dir.normalize();
        let cam = &scene.camera;
        let bodies = scene
            .bodies
            .iter()
            .map(|pb| {
                let solid = Solid::new(pb.solid, pb.edge);
                let pose = &pb.camera_from_body;
                let faces = solid
                    .faces()
                    .iter()
                    .map(|f| {
                        let normal = pose.transform_vector(&f.normal);
                        let center = pose.transform_point(&f.center.into()).coords;
                        let tag = pb.body.tags.iter().find(|t| t.face == f.index).and_then(|t| {
                            let (x, y) = t.axes();
                            let size =
                                0.5 * ((t.corners[1] - t.corners[0]).norm() + (t.corners[2] - t.corners[3]).norm());
                            Some(TagC {
                                center: pose.transform_point(&t.center.into()).coords,
                                x: pose.transform_vector(&x),
                                y: pose.transform_vector(&y),
                                inv_half: 2.0 / size,
                                bitmap: pb.family.bitmap(t.id)?,
                            })
                        });
                        FaceC { normal, offset: normal.dot(&center), shade: shade(&normal, &light, scene.ambient), tag }
                    })
                    .collect();
                let c = pose.translation();
                let bbox = sphere_bbox(cam, &c, solid.circumradius());
                BodyC { faces, bbox }
            })
            .collect();
        let planes = scene
            .planes
            .iter()
            .map(|p| {
                let pose = &p.camera_from_plane;
                let normal = pose.transform_vector(&Vector3::z());
                let origin = pose.translation();
                let shapes = p
                    .shapes
                    .iter()
                    .filter(|s| s.polygon.len() >= 3)
                    .map(|s| {
                        let pts: Vec<Vector2<f64>> = s.polygon.iter().map(|q| Vector2::new(q[0], q[1])).collect();
                        let n = pts.len();
                        let edges = (0..n)
                            .map(|i| {
                                let a = pts[i];
                                let b = pts[(i + 1) % n];
                                // Inward normal of a counter-clockwise polygon.
                                let nrm = Vector2::new(-(b.y - a.y), b.x - a.x).normalize();
                                (nrm, nrm.dot(&a))
                            })
                            .collect();
                        let bbox = pts
                            .iter()
                            .fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, q| {
                                [b[0].min(q.x), b[1].min(q.y), b[2].max(q.x), b[3].max(q.y)]
                            });
                        ShapeC { edges, bbox, albedo: s.albedo }
                    })
                    .collect();
                // Seen from the camera side: light the side that faces the camera.
                let facing = if normal.dot(&origin) > 0.0 { -normal } else { normal };
                PlaneC {
                    normal,
                    offset: normal.dot(&origin),
                    origin,
                    ex: pose.transform_vector(&Vector3::x()),
                    ey: pose.transform_vector(&Vector3::y()),
                    albedo: p.albedo,
                    shade: shade(&facing, &light, scene.ambient),
                    shapes,
                }
            })
            .collect();
        Prepared { bodies, planes }
    }

    /// What the ray `dir` (camera frame, from the origin) sees. `px` is the image point the ray
    /// belongs to, used to skip bodies whose screen box does not contain it.
    fn trace(&self, dir: &Vector3<f64>, px: (f64, f64)) -> Sample {
        let mut best = NOTHING;
        let mut best_t = f64::INFINITY;
        for (bi, b) in self.bodies.iter().enumerate() {
            let Some(bb) = b.bbox else { continue };
            if px.0 < bb[0] || px.0 > bb[2] || px.1 < bb[1] || px.1 > bb[3] {
                continue;
            }
            // Slab test against the 12 half-spaces n·p ≤ h.
            let mut t_in = 0.0f64;
            let mut t_out = f64::INFINITY;
            let mut face_in = usize::MAX;
            for (fi, f) in b.faces.iter().enumerate() {
                let nd = f.normal.dot(dir);
                if nd < 0.0 {
                    let t = f.offset / nd;
                    if t > t_in {
                        t_in = t;
                        face_in = fi;
                    }
                } else if nd > 0.0 {
                    t_out = t_out.min(f.offset / nd);
                } else if f.offset < 0.0 {
                    t_out = -1.0;
                }
            }
            if face_in == usize::MAX || t_in > t_out || t_in >= best_t {
                continue;
            }
            let f = &b.faces[face_in];
            let p = dir * t_in;
            let (cell, albedo) = match &f.tag {
                Some(tag) => {
                    let d = p - tag.center;
                    let u = d.dot(&tag.x) * tag.inv_half;
                    let v = d.dot(&tag.y) * tag.inv_half;
                    if let Some((cx, cy, albedo)) = tag_texture(&tag.bitmap, u, v) {
                        ((cy * 8 + cx) as u32, albedo)
                    } else {
                        // The margin around the square is not convex: split it into the eight
                        // convex pieces of a 3×3 grid so the uniform-pixel shortcut stays exact.
                        let band = |t: f64| {
                            if t < -1.0 {
                                0
                            } else if t > 1.0 {
                                2
                            } else {
                                1
                            }
                        };
                        (64 + band(u) * 3 + band(v), PAPER_ALBEDO)
                    }
                }
                None => (64, PAPER_ALBEDO),
            };
            best_t = t_in;
            best = Sample {
                id: (1 << 28) | ((bi as u32) << 20) | ((face_in as u32) << 12) | cell,
                value: albedo * f.shade,
                depth: p.z as f32,
            };
        }
        for (pi, pl) in self.planes.iter().enumerate() {
            let nd = pl.normal.dot(dir);
            if nd.abs() < 1e-12 {
                continue;
            }
            let t = pl.offset / nd;
            if t <= 0.0 || t >= best_t {
                continue;
            }
            let p = dir * t;
            let d = p - pl.origin;
            let q = Vector2::new(d.dot(&pl.ex), d.dot(&pl.ey));
            let hit = pl.shapes.iter().enumerate().rev().find(|(_, s)| {
                q.x >= s.bbox[0]
                    && q.x <= s.bbox[2]
                    && q.y >= s.bbox[1]
                    && q.y <= s.bbox[3]
                    && s.edges.iter().all(|(n, o)| n.dot(&q) >= *o)
            });
            let (sid, albedo) = match (hit, pl.albedo) {
                (Some((si, s)), _) => (si as u32 + 1, s.albedo),
                (None, Some(a)) => (0, a),
                (None, None) => continue,
            };
            best_t = t;
            best = Sample { id: (2 << 28) | ((pi as u32) << 20) | sid, value: albedo * pl.shade, depth: p.z as f32 };
        }
        best
    }
}

/// The printed tag at tag coordinates (u, v) ∈ [−1, 1]² (x right, y down in the upright tag,
/// the black-border square spanning the range): the cell (column, row) and its albedo, or
/// `None` outside the square.
pub fn tag_texture(bitmap: &TagBitmap, u: f64, v: f64) -> Option<(usize, usize, f32)> {
    if u.abs() > 1.0 || v.abs() > 1.0 {
        return None;
    }
    let n = bitmap.width();
    let half = n as f64 / 2.0;
    let cx = (((u + 1.0) * half) as usize).min(n - 1);
    let cy = (((v + 1.0) * half) as usize).min(n - 1);
    Some((cx, cy, if bitmap.is_white(cx, cy) { PAPER_ALBEDO } else { INK_ALBEDO }))
}

fn sphere_bbox(cam: &Camera, c: &Vector3<f64>, r: f64) -> Option<[f64; 4]> {
    if c.z - r <= 1e-6 {
        // The sphere reaches behind the camera: no useful box, test every ray.
        return Some([f64::NEG_INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::INFINITY]);
    }
    // Project the sphere's bounding cube corners; pad for distortion.
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                let p = c + Vector3::new(sx, sy, sz) * r;
                let q = cam.intrinsics.project(&p.into())?;
                b = [b[0].min(q.x), b[1].min(q.y), b[2].max(q.x), b[3].max(q.y)];
            }
        }
    }
    let pad = 2.0 + 0.05 * (b[2] - b[0]).max(b[3] - b[1]);
    let b = [b[0] - pad, b[1] - pad, b[2] + pad, b[3] + pad];
    let off = b[2] < -1.0 || b[3] < -1.0 || b[0] > cam.width as f64 || b[1] > cam.height as f64;
    (!off).then_some(b)
}

/// Samples per mixed pixel.
const SAMPLES: usize = 128;
/// Generator of the rank-1 lattice: of all for 128 points, the one whose worst half-plane
/// coverage error over every edge direction and offset is smallest (0.022 of a pixel).
const GENERATOR: usize = 59;

/// Sample offsets within a pixel: the lattice (i/128, 59·i/128 mod 1). Each of the 128
/// columns and rows holds exactly one sample, so axis-aligned edges land within 1/256 px.
fn sample_offsets() -> [(f64, f64); SAMPLES] {
    std::array::from_fn(|i| {
        let j = (i * GENERATOR) % SAMPLES;
        (i as f64 / SAMPLES as f64, j as f64 / SAMPLES as f64)
    })
}

/// A per-pixel toroidal shift of the lattice (Cranley–Patterson rotation) from a hash of the
/// pixel: it keeps the stratification and turns the lattice's small coverage errors into
/// zero-mean noise, so they average out along an edge instead of biasing it.
fn pixel_shift(x: usize, y: usize) -> (f64, f64) {
    let mut h = (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (y as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    h ^= h >> 31;
    h = h.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h ^= h >> 29;
    let a = (h >> 40) as f64 / (1u64 << 24) as f64;
    let b = (h & 0xff_ffff) as f64 / (1u64 << 24) as f64;
    (a / SAMPLES as f64, b / SAMPLES as f64)
}

/// Viewing rays through the pixel corners of the window `[x0, y0, x1, y1)`: (x1−x0+1)×(y1−y0+1)
/// directions with z = 1, corner (i, j) being the image point (i − ½, j − ½). Rays inside a
/// pixel are interpolated from these, exactly without distortion and to ~1e-6 px with it.
fn corner_rays(cam: &Camera, win: [usize; 4]) -> Vec<Vector3<f64>> {
    let k = &cam.intrinsics;
    (win[1]..=win[3])
        .into_par_iter()
        .flat_map_iter(|j| {
            (win[0]..=win[2]).map(move |i| {
                let p = Point2::new(i as f64 - 0.5, j as f64 - 0.5);
                // Beyond the distortion model's fold the ray is meaningless; look nowhere.
                k.unproject(&p).unwrap_or_else(|| Vector3::new(0.0, 0.0, -1.0))
            })
        })
        .collect()
}

/// The pixel window `[x0, y0, x1, y1)` that holds every body of the scene, or `None` if no
/// body is on screen.
pub fn bodies_window(scene: &RenderScene<'_>) -> Option<[usize; 4]> {
    (0..scene.bodies.len()).filter_map(|i| body_window(scene, i)).reduce(window_union)
}

/// The pixel window `[x0, y0, x1, y1)` that holds body `index` of the scene, or `None` if it
/// is off screen (or there is no such body).
pub fn body_window(scene: &RenderScene<'_>, index: usize) -> Option<[usize; 4]> {
    let cam = &scene.camera;
    let (w, h) = (f64::from(cam.width), f64::from(cam.height));
    let b = scene.bodies.get(index)?;
    let b = sphere_bbox(cam, &b.camera_from_body.translation(), Solid::new(b.solid, b.edge).circumradius())?;
    let x0 = b[0].floor().clamp(0.0, w) as usize;
    let y0 = b[1].floor().clamp(0.0, h) as usize;
    let x1 = (b[2].ceil() + 1.0).clamp(0.0, w) as usize;
    let y1 = (b[3].ceil() + 1.0).clamp(0.0, h) as usize;
    (x1 > x0 && y1 > y0).then_some([x0, y0, x1, y1])
}

/// The smallest window holding both.
pub fn window_union(a: [usize; 4], b: [usize; 4]) -> [usize; 4] {
    [a[0].min(b[0]), a[1].min(b[1]), a[2].max(b[2]), a[3].max(b[3])]
}

/// Renders the linear radiance and depth of one instant.
pub fn render_linear(scene: &RenderScene<'_>) -> LinearImage {
    let cam = scene.camera;
    render_window(scene, [0, 0, cam.width as usize, cam.height as usize])
}

/// Renders only the pixels of the window `[x0, y0, x1, y1)`; the result has the window's size.
/// A pixel comes out exactly as in a full render.
pub fn render_window(scene: &RenderScene<'_>, win: [usize; 4]) -> LinearImage {
    let cam = scene.camera;
    let prepared = Prepared::new(scene);
    let rays = corner_rays(&cam, win);
    let gw = win[2] - win[0] + 1;
    let corners: Vec<Sample> = rays
        .par_iter()
        .enumerate()
        .map(|(idx, d)| {
            let (i, j) = (win[0] + idx % gw, win[1] + idx / gw);
            if d.z <= 0.0 { NOTHING } else { prepared.trace(d, (i as f64 - 0.5, j as f64 - 0.5)) }
        })
        .collect();
    let offsets = sample_offsets();
    let w = win[2] - win[0];
    let rows: Vec<(Vec<f32>, Vec<f32>)> = (0..win[3] - win[1])
        .into_par_iter()
        .map(|y| {
            let mut rad = Vec::with_capacity(w);
            let mut dep = Vec::with_capacity(w);
            for x in 0..w {
                let c = [
                    corners[y * gw + x],
                    corners[y * gw + x + 1],
                    corners[(y + 1) * gw + x],
                    corners[(y + 1) * gw + x + 1],
                ];
                if c.iter().all(|s| s.id == c[0].id) {
                    rad.push(c[0].value);
                    dep.push(c.iter().map(|s| s.depth).fold(f32::INFINITY, f32::min));
                    continue;
                }
                let r00 = rays[y * gw + x];
                let r10 = rays[y * gw + x + 1];
                let r01 = rays[(y + 1) * gw + x];
                let r11 = rays[(y + 1) * gw + x + 1];
                let mut sum = 0.0f64;
                let mut near = f32::INFINITY;
                let (sx, sy) = pixel_shift(win[0] + x, win[1] + y);
                for &(ox, oy) in &offsets {
                    let (ox, oy) = ((ox + sx) % 1.0, (oy + sy) % 1.0);
                    let d = r00 * ((1.0 - ox) * (1.0 - oy))
                        + r10 * (ox * (1.0 - oy))
                        + r01 * ((1.0 - ox) * oy)
                        + r11 * (ox * oy);
                    let s = if d.z <= 0.0 {
                        NOTHING
                    } else {
                        prepared.trace(&d, ((win[0] + x) as f64 - 0.5 + ox, (win[1] + y) as f64 - 0.5 + oy))
                    };
                    sum += f64::from(s.value);
                    near = near.min(s.depth);
                }
                rad.push((sum / offsets.len() as f64) as f32);
                dep.push(near);
            }
            (rad, dep)
        })
        .collect();
    let mut radiance = Vec::with_capacity(w * (win[3] - win[1]));
    let mut depth = Vec::with_capacity(w * (win[3] - win[1]));
    for (r, d) in rows {
        radiance.extend(r);
        depth.extend(d);
    }
    LinearImage { width: w as u32, height: (win[3] - win[1]) as u32, radiance, depth }
}

fn sees_body_prepared(prepared: &Prepared, cam: &Camera, body: usize, px: &Point2<f64>) -> bool {
    let Some(d) = cam.intrinsics.unproject(px) else { return false };
    let s = prepared.trace(&d, (px.x, px.y));
    (s.id >> 28) == 1 && ((s.id >> 20) & 0xff) as usize == body
}

/// Whether the ray through each image point meets the given body (index into
/// `scene.bodies`) before anything else. Used for the occlusion ground truth.
pub(crate) fn sees_body_many(scene: &RenderScene<'_>, body: usize, pts: &[Point2<f64>]) -> Vec<bool> {
    let prepared = Prepared::new(scene);
    pts.iter().map(|p| sees_body_prepared(&prepared, &scene.camera, body, p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_marker::{BodyKind, Marker};
    use nalgebra::{Point3, UnitQuaternion};

    /// With strong radial distortion, the pixel where the camera model projects a cell's centre
    /// shows that cell's colour: rendering and projection agree on the distortion.
    #[test]
    fn distorted_rendering_agrees_with_the_projection() {
        let marker = Marker::default();
        let body = marker.body(BodyKind::Maxilla).expect("maxilla");
        let k = CameraIntrinsics { fx: 900.0, fy: 900.0, cx: 319.5, cy: 239.5, k1: -0.25, k2: 0.08 };
        let cam = Camera { intrinsics: k, width: 640, height: 480 };
        // Off-centre, where distortion moves points by several pixels.
        let pose = Pose::from_parts(UnitQuaternion::from_euler_angles(2.8, 0.3, 0.4), Vector3::new(28.0, 14.0, 110.0));
        let scene = RenderScene {
            camera: cam,
            bodies: vec![PlacedBody {
                body,
                solid: marker.solid,
                edge: marker.edge,
                family: marker.family,
                camera_from_body: pose,
            }],
            planes: vec![],
            light_dir: Vector3::new(0.0, 0.0, -1.0),
            ambient: 0.35,
        };
        let img = render_linear(&scene);
        let solid = marker.geometry();
        let (mut checked, mut moved) = (0, 0.0f64);
        for tag in &body.tags {
            let face = &solid.faces()[tag.face];
            let n = pose.transform_vector(&face.normal);
            let c = pose.transform_point(&Point3::from(tag.center));
            if n.dot(&c.coords.normalize()) > -0.5 {
                continue; // keep faces seen within 60° of head-on
            }
            let shade = (0.35 + 0.65 * n.dot(&Vector3::new(0.0, 0.0, -1.0)).max(0.0)) as f32;
            let bm = TagFamily::TAG36H11.bitmap(tag.id).expect("id");
            for cy in 0..8 {
                for cx in 0..8 {
                    let (u, v) = (-1.0 + (cx as f64 + 0.5) / 4.0, -1.0 + (cy as f64 + 0.5) / 4.0);
                    let p = pose.transform_point(&Point3::from(tag.point_at(u, v)));
                    let px = k.project(&p).expect("in front");
                    let pinhole = CameraIntrinsics { k1: 0.0, k2: 0.0, ..k }.project(&p).expect("in front");
                    moved = moved.max((px - pinhole).norm());
                    if px.x < 1.0 || px.y < 1.0 || px.x > 638.0 || px.y > 478.0 {
                        continue;
                    }
                    let (x, y) = (px.x.round() as usize, px.y.round() as usize);
                    let want = if bm.is_white(cx, cy) { PAPER_ALBEDO } else { INK_ALBEDO } * shade;
                    let got = img.radiance[y * 640 + x];
                    assert!((got - want).abs() < 1e-4, "tag {} cell ({cx},{cy}) at {px:?}: {got} vs {want}", tag.id);
                    checked += 1;
                }
            }
        }
        assert!(checked >= 96, "{checked} cells checked");
        assert!(moved > 5.0, "distortion moved cells by only {moved} px");
    }

    #[test]
    fn a_window_renders_exactly_as_the_full_frame() {
        let marker = Marker::default();
        let body = marker.body(BodyKind::Mandible).expect("mandible");
        let cam = Camera { intrinsics: CameraIntrinsics::pinhole(800.0, 800.0, 159.5, 119.5), width: 320, height: 240 };
        let scene = RenderScene {
            camera: cam,
            bodies: vec![PlacedBody {
                body,
                solid: marker.solid,
                edge: marker.edge,
                family: marker.family,
                camera_from_body: Pose::from_axis_angle(Vector3::new(2.9, 0.2, 0.1), Vector3::new(0.0, 0.0, 120.0)),
            }],
            planes: vec![],
            light_dir: Vector3::new(0.2, -0.5, -1.0),
            ambient: 0.35,
        };
        let full = render_linear(&scene);
        let win = bodies_window(&scene).expect("on screen");
        let part = render_window(&scene, win);
        for y in win[1]..win[3] {
            for x in win[0]..win[2] {
                assert_eq!(part.radiance[(y - win[1]) * (win[2] - win[0]) + (x - win[0])], full.radiance[y * 320 + x]);
            }
        }
        assert!(full.radiance.iter().any(|&v| v > 0.0), "something was rendered");
    }
}
