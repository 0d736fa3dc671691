//! Ties a scene, a marker, a camera and the realism settings into frames and their truth.

use crate::SynthError;
use crate::post::{self, Glare};
use crate::realism::{Pupil, Realism};
use crate::render::{self, Camera, LinearImage, PlacedBody, Plane, RenderScene, Shape, render_linear, sees_body_many};
use crate::scenes::{FrameSpec, Rig, SceneKind, SceneOptions, scene_frames};
use crate::shutter;
use crate::truth::{FrameTruth, GroundTruth, PrintErrorTruth, TagTruth};
use jawtrack_marker::{BodyKind, Marker, PrintError};
use jawtrack_pose::{CameraIntrinsics, Pose, median};
use nalgebra::{Point2, Point3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Frame sizes the renderer offers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resolution {
    /// 1920 × 1080.
    P1080,
    /// 3840 × 2160.
    P4k,
}

impl Resolution {
    /// Width and height (px).
    pub fn size(self) -> (u32, u32) {
        match self {
            Resolution::P1080 => (1920, 1080),
            Resolution::P4k => (3840, 2160),
        }
    }

    /// An iPhone wide camera's video intrinsics at this size (≈ 65° across the long side).
    pub fn default_intrinsics(self) -> CameraIntrinsics {
        let base = CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5);
        match self {
            Resolution::P1080 => base,
            Resolution::P4k => base.scaled(2.0),
        }
    }
}

impl std::str::FromStr for Resolution {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "1080p" => Ok(Resolution::P1080),
            "4k" | "2160p" => Ok(Resolution::P4k),
            _ => Err(format!("unknown resolution '{s}' (choose 1080p or 4k)")),
        }
    }
}

/// Everything that defines a rendered scene.
#[derive(Debug, Clone)]
pub struct SynthConfig {
    /// Which scene.
    pub scene: SceneKind,
    /// Frame size.
    pub resolution: Resolution,
    /// Intrinsics; `None` takes the resolution's default.
    pub intrinsics: Option<CameraIntrinsics>,
    /// Seed of everything random.
    pub seed: u64,
    /// Realism settings.
    pub realism: Realism,
    /// Scene shape.
    pub options: SceneOptions,
    /// The nominal marker (what the marker file says); print errors are added to it.
    pub marker: Marker,
    /// Render only every n-th frame of the scene (1 = all).
    pub stride: usize,
    /// Stop after this many frames.
    pub max_frames: Option<usize>,
}

impl SynthConfig {
    /// A scene with default everything.
    pub fn new(scene: SceneKind) -> Self {
        SynthConfig {
            scene,
            resolution: Resolution::P1080,
            intrinsics: None,
            seed: 1,
            realism: Realism::default(),
            options: SceneOptions::default(),
            marker: Marker::default(),
            stride: 1,
            max_frames: None,
        }
    }
}

/// A rendered frame.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Width (px).
    pub width: u32,
    /// Height (px).
    pub height: u32,
    /// 8-bit luma, row-major, stride = width.
    pub luma: Vec<u8>,
    /// Its ground truth.
    pub truth: FrameTruth,
}

/// Gray to BGRA (B = G = R = luma, A = 255), the iPhone's other pixel format.
pub fn to_bgra(luma: &[u8]) -> Vec<u8> {
    luma.iter().flat_map(|&v| [v, v, v, 255]).collect()
}

/// Renders the frames of a scene.
pub struct Synthesizer {
    config: SynthConfig,
    /// The frames' camera: the intrinsics given, zoomed and (with focus breathing) enlarged as
    /// the focused lens makes them.
    camera: Camera,
    /// The focal length (px) of the lens focused at infinity, zoomed: what its blur circles
    /// scale with.
    optics_fx: f64,
    rig: Rig,
    true_marker: Marker,
    print_errors: Vec<PrintErrorTruth>,
    frames: Vec<FrameSpec>,
    clutter: Vec<Shape>,
    gradient_dir: f64,
    light_head: Vector3<f64>,
}

const FACE_ALBEDO: f32 = 0.42;

/// Points of the face plane (head X, Y; mm) whose motion bounds the background's.
const FACE_PROBE: [[f64; 2]; 5] = [[0.0, 0.0], [-60.0, -60.0], [60.0, -60.0], [-60.0, 60.0], [60.0, 60.0]];

impl Synthesizer {
    /// Prepares a scene: draws the print errors, the clutter and the frame list.
    pub fn new(config: SynthConfig) -> Result<Self, SynthError> {
        config.realism.validate().map_err(SynthError::Config)?;
        config.marker.validate()?;
        if config.stride == 0 {
            return Err(SynthError::Config("stride must be at least 1".into()));
        }
        if config.options.fps <= 0.0 || !config.options.fps.is_finite() {
            return Err(SynthError::Config("fps must be positive".into()));
        }
        let (width, height) = config.resolution.size();
        let given = config.intrinsics.unwrap_or_else(|| config.resolution.default_intrinsics());
        given.validate().map_err(|e| SynthError::Config(e.to_string()))?;
        let realism = &config.realism;
        let optics_fx = given.fx * realism.zoom;
        let scale = realism.zoom * realism.breathing(realism.focus_distance_mm);
        let intrinsics = CameraIntrinsics { fx: given.fx * scale, fy: given.fy * scale, ..given };
        let camera = Camera { intrinsics, width, height };
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed);

        let shift = Normal::new(0.0, config.realism.print_error_mm / 2f64.sqrt())
            .map_err(|e| SynthError::Config(e.to_string()))?;
        let turn = Normal::new(0.0, config.realism.print_error_deg).map_err(|e| SynthError::Config(e.to_string()))?;
        let mut errors = Vec::new();
        let mut print_errors = Vec::new();
        for (_, tag) in config.marker.tags() {
            let e = PrintError {
                shift_x: shift.sample(&mut rng),
                shift_y: shift.sample(&mut rng),
                rotation: turn.sample(&mut rng).to_radians(),
            };
            errors.push((tag.id, e));
            print_errors.push(PrintErrorTruth {
                id: tag.id,
                shift_x: e.shift_x,
                shift_y: e.shift_y,
                rotation_deg: e.rotation.to_degrees(),
            });
        }
        let true_marker = config.marker.with_print_errors(&errors)?;

        let clutter = make_clutter(config.realism.clutter, &mut rng);
        let gradient_dir = rng.random_range(0.0..std::f64::consts::TAU);
        let mut frames = scene_frames(config.scene, &config.options, config.seed);
        frames = frames.into_iter().step_by(config.stride).collect();
        if let Some(n) = config.max_frames {
            frames.truncate(n);
        }
        Ok(Synthesizer {
            config,
            camera,
            optics_fx,
            rig: Rig::default(),
            true_marker,
            print_errors,
            frames,
            clutter,
            gradient_dir,
            light_head: Vector3::new(0.3, -1.0, -1.0).normalize(),
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether the scene has no frames.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The camera.
    pub fn camera(&self) -> Camera {
        self.camera
    }

    /// The marker as printed.
    pub fn true_marker(&self) -> &Marker {
        &self.true_marker
    }

    /// The ground truth without frames (fill `frames` from [`Frame::truth`]).
    pub fn header(&self) -> GroundTruth {
        GroundTruth {
            version: 1,
            scene: self.config.scene.name().into(),
            seed: self.config.seed,
            image_size: [self.camera.width, self.camera.height],
            intrinsics: self.camera.intrinsics,
            realism: self.config.realism,
            print_errors: self.print_errors.clone(),
            true_marker: serde_json::from_str(&self.true_marker.to_json()).unwrap_or(serde_json::Value::Null),
            frames: Vec::new(),
        }
    }

    fn poses_at(&self, spec: &FrameSpec, t: f64) -> (Pose, Pose, Pose) {
        let camera_from_head = spec.camera_from_head(t);
        let (head_from_maxilla, head_from_mandible) = self.rig.markers(&spec.motion, t);
        (camera_from_head, camera_from_head * head_from_maxilla, camera_from_head * head_from_mandible)
    }

    fn scene_at<'a>(
        &'a self,
        camera_from_head: &Pose,
        cam_max: Pose,
        cam_man: Pose,
        extra: &[Plane],
    ) -> RenderScene<'a> {
        let edge = self.true_marker.edge;
        let bodies = BodyKind::ALL
            .iter()
            .zip([cam_max, cam_man])
            .filter_map(|(k, pose)| {
                self.true_marker.body(*k).map(|body| PlacedBody {
                    body,
                    solid: self.true_marker.solid,
                    edge,
                    family: self.true_marker.family,
                    camera_from_body: pose,
                })
            })
            .collect();
        let head_from_plane =
            Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.0, self.rig.face_plane_z));
        let mut planes = vec![Plane {
            camera_from_plane: *camera_from_head * head_from_plane,
            albedo: Some(FACE_ALBEDO),
            shapes: self.clutter.clone(),
        }];
        planes.extend_from_slice(extra);
        RenderScene {
            camera: self.camera,
            bodies,
            planes,
            light_dir: camera_from_head.transform_vector(&self.light_head),
            ambient: 0.35,
        }
    }

    /// Renders frame `index` (0..len).
    pub fn render(&self, index: usize) -> Result<Frame, SynthError> {
        let spec = *self.frames.get(index).ok_or_else(|| SynthError::Config(format!("no frame {index}")))?;
        let realism = &self.config.realism;
        let mut rng = ChaCha8Rng::seed_from_u64(self.config.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ index as u64);
        let (cam_head, cam_max, cam_man) = self.poses_at(&spec, spec.t);
        let k = self.camera.intrinsics;

        // Occluder and glare are placed from the mid-exposure geometry.
        let tags_mid = self.facing_tags(&cam_max, &cam_man);
        let mut extra = Vec::new();
        let occluder = !tags_mid.is_empty() && rng.random_bool(realism.occluder_probability);
        if occluder {
            let (_, center, _) = tags_mid[rng.random_range(0..tags_mid.len())];
            extra.push(make_occluder(&center, &mut rng));
        }
        let mut glare = Vec::new();
        if rng.random_bool(realism.glare_probability) {
            let near: Vec<_> = tags_mid.iter().filter(|t| t.2 < 50.0).collect();
            if !near.is_empty() {
                let (_, center, _) = near[rng.random_range(0..near.len())];
                if let Some(px) = k.project(&Point3::from(*center)) {
                    let jitter = Vector3::new(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0), 0.0);
                    let c = k.project(&Point3::from(center + jitter)).unwrap_or(px);
                    glare.push(Glare {
                        center: [c.x, c.y],
                        sigma_px: rng.random_range(0.4..1.2) * k.fx / center.z,
                        peak: rng.random_range(0.4..1.2),
                    });
                }
            }
        }

        let (mut img, sub) = if realism.readout_s > 0.0 {
            self.render_rolling(&spec, &extra, &cam_head)
        } else {
            self.render_global(&spec, &extra, &cam_head)
        };

        // Autofocus locks on what has contrast: the tags facing the camera (median depth), but
        // no nearer than the lens can focus.
        let focus_mm = (realism.f_number > 0.0).then(|| {
            realism.focus_distance_mm.unwrap_or_else(|| {
                let subject = median(tags_mid.iter().filter(|t| t.2 < 60.0).map(|t| t.1.z))
                    .unwrap_or(0.5 * (cam_max.translation().z + cam_man.translation().z));
                subject.max(realism.min_focus_distance_mm.unwrap_or(0.0))
            })
        });
        // The lens's own blur (px).
        let optics_px = if realism.focal_length_mm > 0.0 {
            realism.optics_sigma_um * self.optics_fx / (1000.0 * realism.focal_length_mm)
        } else {
            0.0
        };
        let lens = CameraIntrinsics { fx: self.optics_fx, ..k };
        let circle =
            |focus: f64, d: f64| post::blur_circle_px(&lens, realism.f_number, realism.focal_length_mm, focus, d);
        match (focus_mm, realism.pupil) {
            (Some(focus), Pupil::Gaussian) => {
                post::defocus(&mut img, |d| (circle(focus, d) / 4.0).hypot(optics_px));
            }
            (Some(focus), Pupil::Disc) => {
                post::defocus_disc(&mut img, |d| circle(focus, d) / 2.0);
                post::gaussian_blur(&mut img, optics_px);
            }
            (None, _) => post::gaussian_blur(&mut img, optics_px),
        }
        post::add_glare(&mut img, &glare);
        post::illumination(&mut img, realism.vignetting, realism.lighting_gradient, self.gradient_dir);
        post::sensor_noise(&mut img, realism.pixel_full_well_e(), realism.read_noise_e, &mut rng);
        let luma = post::develop(&mut img, realism);

        let scene_mid = self.scene_at(&cam_head, cam_max, cam_man, &extra);
        let tags = self.tag_truth(&spec, &scene_mid, &extra);
        let truth = FrameTruth {
            index,
            file: format!("frame_{index:04}.png"),
            t: spec.t,
            camera_from_maxilla: cam_max,
            camera_from_mandible: cam_man,
            maxilla_from_mandible: cam_max.inverse() * cam_man,
            camera_from_head: cam_head,
            subframes: sub,
            incisor_speed_mm_s: self.rig.incisor_speed(&spec.motion, spec.t),
            focus_mm,
            glare,
            occluder,
            tags,
            spec,
        };
        Ok(Frame { width: self.camera.width, height: self.camera.height, luma, truth })
    }

    /// A global shutter's image: every row exposed over the same window, averaging sub-frames
    /// at the midpoints of equal slices of it, as a rolling shutter's rows do: enough that
    /// nothing moves more than [`shutter::STEP_PX`] between two, up to
    /// [`Realism::max_subframes`] (the blur stays symmetric about mid-exposure, so the true pose
    /// is its centre). Returns the image and the sub-frames.
    fn render_global(&self, spec: &FrameSpec, extra: &[Plane], cam_head: &Pose) -> (LinearImage, u32) {
        let realism = &self.config.realism;
        let e = realism.exposure_s;
        let moved = if e > 0.0 {
            let a = self.poses_at(spec, spec.t - e / 2.0);
            let b = self.poses_at(spec, spec.t + e / 2.0);
            shutter::largest_motion(&self.body_probe(&a), &self.body_probe(&b))
        } else {
            0.0
        };
        let times = shutter::slice_midpoints(spec.t, e, moved, shutter::STEP_PX, realism.max_subframes);
        let sub = times.len() as u32;
        let scenes: Vec<RenderScene<'_>> = times
            .iter()
            .map(|&t| {
                let (ch, cx, cm) = self.poses_at(spec, t);
                self.scene_at(&ch, cx, cm, extra)
            })
            .collect();
        let mid = sub as usize / 2;
        let mut img = render_linear(&scenes[mid]);
        if sub > 1 {
            // With the camera still (a tripod) only the markers move: re-render just their
            // window for each sub-frame. A moving camera moves everything.
            let still = times.iter().all(|&t| self.poses_at(spec, t).0.distance_to(cam_head) == (0.0, 0.0));
            let full = [0, 0, self.camera.width as usize, self.camera.height as usize];
            let win = if still {
                scenes.iter().filter_map(render::bodies_window).reduce(render::window_union)
            } else {
                Some(full)
            };
            if let Some(win) = win {
                let ww = win[2] - win[0];
                let mut acc = vec![0.0f32; ww * (win[3] - win[1])];
                for scene in &scenes {
                    let part = render::render_window(scene, win);
                    acc.iter_mut().zip(&part.radiance).for_each(|(a, b)| *a += b);
                }
                let inv = 1.0 / sub as f32;
                let w = self.camera.width as usize;
                for (row, chunk) in acc.chunks(ww).enumerate() {
                    let y = win[1] + row;
                    for (x, v) in chunk.iter().enumerate() {
                        img.radiance[y * w + win[0] + x] = v * inv;
                    }
                }
            }
        }
        (img, sub)
    }

    /// A rolling shutter's image (see [`shutter`]). Returns the image and the most instants a
    /// row averaged.
    fn render_rolling(&self, spec: &FrameSpec, extra: &[Plane], cam_head: &Pose) -> (LinearImage, u32) {
        let realism = &self.config.realism;
        let scene_at = |t: f64| {
            let (ch, cx, cm) = self.poses_at(spec, t);
            self.scene_at(&ch, cx, cm, extra)
        };
        // The markers bound the motion of everything with a still camera; a moving one moves the
        // face too, so it is probed as well.
        let probe_at = |t: f64| {
            let poses = self.poses_at(spec, t);
            let k = &self.camera.intrinsics;
            let mut pts = self.body_probe(&poses);
            pts.extend(FACE_PROBE.map(|[x, y]| {
                let p = poses.0.transform_point(&Point3::new(x, y, self.rig.face_plane_z));
                k.project(&p).unwrap_or(Point2::origin())
            }));
            pts
        };
        let height = self.camera.height;
        let span = [
            realism.row_time(spec.t, 0.0, height) - realism.exposure_s / 2.0,
            spec.t,
            realism.row_time(spec.t, f64::from(height - 1), height) + realism.exposure_s / 2.0,
        ];
        let still = span.iter().all(|&t| self.poses_at(spec, t).0.distance_to(cam_head) == (0.0, 0.0));
        let mut img = render_linear(&scene_at(spec.t));
        let rolling = shutter::Rolling {
            realism,
            t: spec.t,
            scene_at: &scene_at,
            probe_at: &probe_at,
            still,
            step_px: shutter::STEP_PX,
        };
        let most = rolling.render_into(&mut img);
        (img, most)
    }

    /// Image points (px) whose motion bounds the markers': each body's origin and points 15 mm
    /// along its axes.
    fn body_probe(&self, poses: &(Pose, Pose, Pose)) -> Vec<Point2<f64>> {
        let k = &self.camera.intrinsics;
        [poses.1, poses.2]
            .iter()
            .flat_map(|pose| {
                [
                    Vector3::new(15.0, 0.0, 0.0),
                    Vector3::new(0.0, 15.0, 0.0),
                    Vector3::new(0.0, 0.0, 15.0),
                    Vector3::zeros(),
                ]
                .map(|v| k.project(&pose.transform_point(&Point3::from(v))).unwrap_or(Point2::origin()))
            })
            .collect()
    }

    /// Tags facing the camera: (id, centre in camera frame, view angle in degrees).
    fn facing_tags(&self, cam_max: &Pose, cam_man: &Pose) -> Vec<(u32, Vector3<f64>, f64)> {
        let mut out = Vec::new();
        for (kind, tag) in self.true_marker.tags() {
            let pose = if kind == BodyKind::Maxilla { cam_max } else { cam_man };
            let c = pose.transform_point(&Point3::from(tag.center)).coords;
            let n = pose.transform_vector(&tag.face_normal());
            let cos = -n.dot(&c.normalize());
            if cos > 0.0 {
                out.push((tag.id, c, cos.acos().to_degrees()));
            }
        }
        out
    }

    /// The truth of every tag facing the camera at the frame's time. Each point is where it is
    /// seen: with a rolling shutter, at its own row's mid-exposure time.
    fn tag_truth(&self, spec: &FrameSpec, scene: &RenderScene<'_>, extra: &[Plane]) -> Vec<TagTruth> {
        let k = &self.camera.intrinsics;
        let realism = &self.config.realism;
        let (w, h) = (f64::from(self.camera.width), f64::from(self.camera.height));
        let mut out = Vec::new();
        for (bi, kind) in BodyKind::ALL.iter().enumerate() {
            let Some(body) = self.true_marker.body(*kind) else { continue };
            let body_at = |t: f64| {
                let (_, cam_max, cam_man) = self.poses_at(spec, t);
                if *kind == BodyKind::Maxilla { cam_max } else { cam_man }
            };
            let pose = &body_at(spec.t);
            let scene_index = scene.bodies.iter().position(|b| std::ptr::eq(b.body, body)).unwrap_or(bi);
            for tag in &body.tags {
                let c = pose.transform_point(&Point3::from(tag.center)).coords;
                let n = pose.transform_vector(&tag.face_normal());
                let cos = -n.dot(&c.normalize());
                if cos <= 0.0 {
                    continue;
                }
                let proj = |p: Vector3<f64>| {
                    let at = |t: f64| k.project(&body_at(t).transform_point(&Point3::from(p)));
                    shutter::seen_at(realism, spec.t, self.camera.height, at)
                };
                let Some(corners) = tag.corners.iter().map(|c| proj(*c)).collect::<Option<Vec<_>>>() else { continue };
                let Some(center) = proj(tag.center) else { continue };
                let inside = |p: &Point2<f64>| p.x >= 0.0 && p.y >= 0.0 && p.x <= w - 1.0 && p.y <= h - 1.0;
                // 9×9 points over the black square, the tag's own quiet zone excluded.
                let samples: Vec<Point2<f64>> = (0..9)
                    .flat_map(|i| (0..9).map(move |j| (f64::from(i) / 4.0 - 1.0, f64::from(j) / 4.0 - 1.0)))
                    .filter_map(|(u, v)| proj(tag.point_at(u * 0.98, v * 0.98)))
                    .collect();
                let seen = if realism.readout_s > 0.0 {
                    // Each sample against the scene at its own row's time.
                    samples
                        .iter()
                        .map(|p| {
                            let (ch, cx, cm) = self.poses_at(spec, realism.row_time(spec.t, p.y, self.camera.height));
                            let at_row = self.scene_at(&ch, cx, cm, extra);
                            sees_body_many(&at_row, scene_index, &[*p]).first().copied().unwrap_or(false)
                        })
                        .collect()
                } else {
                    sees_body_many(scene, scene_index, &samples)
                };
                let visible = samples.iter().zip(&seen).filter(|(p, s)| **s && inside(p)).count();
                let min_side = (0..4).map(|i| (corners[(i + 1) % 4] - corners[i]).norm()).fold(f64::INFINITY, f64::min);
                out.push(TagTruth {
                    id: tag.id,
                    body: kind.name().into(),
                    corners: std::array::from_fn(|i| [corners[i].x, corners[i].y]),
                    center: [center.x, center.y],
                    view_angle_deg: cos.clamp(-1.0, 1.0).acos().to_degrees(),
                    min_side_px: min_side,
                    in_image: corners.iter().all(inside),
                    occluded_fraction: 1.0 - visible as f64 / 81.0,
                });
            }
        }
        out
    }
}

/// Background clutter on the face plane (mm, head X/Y): blobs, bars, and dark squares that are
/// not tags, some with a light square inside like a tag's data area.
fn make_clutter(n: u32, rng: &mut ChaCha8Rng) -> Vec<Shape> {
    let mut shapes = Vec::new();
    for i in 0..n {
        let c = [rng.random_range(-70.0..70.0), rng.random_range(-90.0..90.0)];
        let rot: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let poly = |half_w: f64, half_h: f64| -> Vec<[f64; 2]> {
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .iter()
                .map(|(u, v)| {
                    let (x, y) = (u * half_w, v * half_h);
                    [c[0] + x * rot.cos() - y * rot.sin(), c[1] + x * rot.sin() + y * rot.cos()]
                })
                .collect()
        };
        match i % 3 {
            0 => {
                let s = rng.random_range(1.5..5.0);
                shapes.push(Shape { polygon: poly(s, s), albedo: rng.random_range(0.02..0.08) });
                if rng.random_bool(0.5) {
                    shapes.push(Shape { polygon: poly(s * 0.6, s * 0.6), albedo: rng.random_range(0.5..0.85) });
                }
            }
            1 => {
                let m = rng.random_range(3..7);
                let r = rng.random_range(3.0..12.0);
                let polygon = (0..m)
                    .map(|j| {
                        let a = rot + std::f64::consts::TAU * f64::from(j) / f64::from(m);
                        [c[0] + r * a.cos(), c[1] + r * a.sin()]
                    })
                    .collect();
                shapes.push(Shape { polygon, albedo: rng.random_range(0.1..0.8) });
            }
            _ => shapes.push(Shape {
                polygon: poly(rng.random_range(6.0..20.0), rng.random_range(0.4..1.5)),
                albedo: rng.random_range(0.05..0.3),
            }),
        }
    }
    shapes
}

/// A convex occluder (a fingertip or lip edge) halfway between the camera and a tag.
fn make_occluder(tag_center: &Vector3<f64>, rng: &mut ChaCha8Rng) -> Plane {
    let depth = tag_center.z * rng.random_range(0.5..0.75);
    let p = tag_center * (depth / tag_center.z)
        + Vector3::new(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0), 0.0) * (depth / tag_center.z);
    let r = rng.random_range(2.0..4.5) * depth / tag_center.z;
    let stretch = rng.random_range(1.0..2.5);
    let rot: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let polygon = (0..12)
        .map(|j| {
            let a = std::f64::consts::TAU * f64::from(j) / 12.0;
            let (x, y) = (r * stretch * a.cos(), r * a.sin());
            [x * rot.cos() - y * rot.sin(), x * rot.sin() + y * rot.cos()]
        })
        .collect();
    Plane {
        camera_from_plane: Pose::from_parts(UnitQuaternion::identity(), p),
        albedo: None,
        shapes: vec![Shape { polygon, albedo: rng.random_range(0.2..0.5) }],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bgra_repeats_luma_with_opaque_alpha() {
        assert_eq!(to_bgra(&[0, 7, 255]), vec![0, 0, 0, 255, 7, 7, 7, 255, 255, 255, 255, 255]);
    }

    #[test]
    fn bad_settings_are_refused_by_name() {
        let mut c = SynthConfig::new(SceneKind::Static);
        c.realism.f_number = -1.0;
        let e = Synthesizer::new(c).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("f_number"), "{e}");
        let mut c = SynthConfig::new(SceneKind::Static);
        c.stride = 0;
        assert!(Synthesizer::new(c).is_err());
        let c = SynthConfig::new(SceneKind::Static);
        let s = Synthesizer::new(c).expect("defaults are valid");
        assert!(s.render(s.len()).is_err(), "a frame past the end is an error, not a panic");
    }

    #[test]
    fn readout_must_be_a_non_negative_number() {
        for bad in [-0.001, f64::NAN, f64::INFINITY] {
            let mut c = SynthConfig::new(SceneKind::Chew);
            c.realism.readout_s = bad;
            let e = Synthesizer::new(c).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(e.contains("readout_s"), "{bad}: {e}");
        }
    }

    /// A fast chewing frame with a 10 ms readout: the truth's corners are each at its own
    /// row's time (rows read later are seen later), the poses at the frame's time, and the
    /// incisor's speed recorded.
    #[test]
    fn rolling_shutter_truth_is_seen_at_each_row_time() {
        let mut c = SynthConfig::new(SceneKind::Chew);
        c.realism = Realism { readout_s: 0.010, ..Realism::clean() };
        c.options.orientation = crate::scenes::Orientation::Landscape;
        let synth = Synthesizer::new(c).expect("valid");
        let global =
            Synthesizer::new(SynthConfig { realism: Realism::clean(), ..synth.config.clone() }).expect("valid");
        // A quarter of the first, fast cycle: the jaw opens at full speed.
        let spec = synth.frames[5];
        let speed = synth.rig.incisor_speed(&spec.motion, spec.t);
        assert!(speed > 100.0, "{speed} mm/s");
        let (ch, cx, cm) = synth.poses_at(&spec, spec.t);
        let scene = synth.scene_at(&ch, cx, cm, &[]);
        let rolled = synth.tag_truth(&spec, &scene, &[]);
        let still = global.tag_truth(&spec, &scene, &[]);
        assert_eq!(rolled.len(), still.len());
        let k = synth.camera.intrinsics;
        let mut moved: f64 = 0.0;
        for (r, s) in rolled.iter().zip(&still) {
            let (kind, tag) = synth.true_marker.find_tag(r.id).expect("tag");
            for (corner, seen) in tag.corners.iter().zip(&r.corners) {
                let t = synth.config.realism.row_time(spec.t, seen[1], synth.camera.height);
                let pose = synth.poses_at(&spec, t);
                let pose = if kind == BodyKind::Maxilla { pose.1 } else { pose.2 };
                let p = k.project(&pose.transform_point(&Point3::from(*corner))).expect("in front");
                assert!((p.x - seen[0]).abs() < 1e-8 && (p.y - seen[1]).abs() < 1e-8, "tag {}", r.id);
            }
            let shift = (0..4).map(|i| (r.corners[i][1] - s.corners[i][1]).abs()).fold(0.0, f64::max);
            if kind == BodyKind::Maxilla {
                assert!(shift < 1e-9, "the maxilla does not move");
            } else {
                moved = moved.max(shift);
            }
        }
        // Opening at > 100 mm/s ≈ 1000 px/s down the rows, read up to 4 ms from the centre row.
        assert!(moved > 1.0, "the mandible's corners moved only {moved} px");
    }

    /// A rolling-shutter frame end to end: rendered row by row, and every tag the truth calls
    /// detectable reads back at the truth's corners.
    #[test]
    fn a_rolling_shutter_frame_shows_its_tags_at_the_truths_corners() {
        let mut c = SynthConfig::new(SceneKind::Chew);
        c.realism = Realism { readout_s: 0.010, exposure_s: 0.002, ..Realism::clean() };
        c.options.orientation = crate::scenes::Orientation::Landscape;
        c.stride = 5;
        c.max_frames = Some(2);
        let synth = Synthesizer::new(c).expect("valid");
        let frame = synth.render(1).expect("renders");
        assert!(frame.truth.subframes > 1 && frame.truth.incisor_speed_mm_s > 100.0, "{:?}", frame.truth.subframes);
        let img = image::GrayImage::from_raw(frame.width, frame.height, frame.luma).expect("size");
        let mut read = 0;
        for t in frame.truth.tags.iter().filter(|t| t.should_be_detected()) {
            let reading = jawtrack_test_support::read_tag(&img, &t.corners).expect("inside");
            let bm = jawtrack_apriltag::TagFamily::TAG36H11.bitmap(t.id).expect("id");
            let wrong = jawtrack_apriltag::TagFamily::TAG36H11
                .bit_cells
                .iter()
                .filter(|&&(x, y)| bm.is_white(x.into(), y.into()) != reading.is_white(x.into(), y.into()))
                .count();
            assert_eq!(wrong, 0, "tag {} misread at the truth's corners", t.id);
            read += 1;
        }
        assert!(read >= 4, "{read} tags read");
    }

    /// What the chew scene's framing promises ([`crate::scenes`]): in either orientation at
    /// least two tags of each marker are detectable in every frame, through 25 mm openings.
    #[test]
    fn chew_keeps_two_tags_of_each_marker_in_view() {
        for orientation in [crate::scenes::Orientation::Upright, crate::scenes::Orientation::Landscape] {
            for seed in 1..=3 {
                let mut c = SynthConfig::new(SceneKind::Chew);
                c.seed = seed;
                c.realism = Realism::clean();
                c.options = SceneOptions { orientation, cycles: 4, ..SceneOptions::default() };
                let synth = Synthesizer::new(c).expect("valid");
                let mut checked = 0;
                for spec in &synth.frames {
                    let (ch, cx, cm) = synth.poses_at(spec, spec.t);
                    let tags = synth.tag_truth(spec, &synth.scene_at(&ch, cx, cm, &[]), &[]);
                    for body in ["maxilla", "mandible"] {
                        let n = tags.iter().filter(|t| t.body == body && t.should_be_detected()).count();
                        assert!(n >= 2, "{orientation:?}, seed {seed}, t = {:.3}: {n} {body} tags", spec.t);
                    }
                    checked += 1;
                }
                // Four cycles of at least 0.6 s each were checked frame by frame.
                let least = (4.0 * 0.6 * synth.config.options.fps) as usize;
                assert!(checked >= least, "{orientation:?}, seed {seed}: {checked} frames checked");
            }
        }
    }

    /// A phone's wide camera held at 120 mm with its lens unable to focus nearer than 200 mm:
    /// the focus is stuck there, the frame's focal length breathes by u/(u − f) and zooms.
    #[test]
    fn a_lens_that_cannot_focus_near_enough_stays_at_its_limit_and_breathes() {
        let base = Resolution::P1080.default_intrinsics();
        let mut c = SynthConfig::new(SceneKind::Static);
        c.options = SceneOptions { frames_per_view: 1, distance_mm: Some(120.0), ..SceneOptions::default() };
        c.realism = Realism {
            focus_distance_mm: None,
            focus_breathing: false,
            min_focus_distance_mm: Some(200.0),
            ..Realism::phone_wide(200.0, 2.0)
        };
        c.max_frames = Some(1);
        let synth = Synthesizer::new(c.clone()).expect("valid");
        assert_eq!(synth.camera().intrinsics.fx, 2.0 * base.fx, "zoomed");
        let frame = synth.render(0).expect("renders");
        assert_eq!(frame.truth.focus_mm, Some(200.0), "stuck at the nearest focus");
        // Locked at 200 mm with breathing: 200 / (200 − 6.8) = 1.0352.
        c.realism = Realism::phone_wide(200.0, 1.0);
        let synth = Synthesizer::new(c.clone()).expect("valid");
        let k = synth.header().intrinsics;
        assert!((k.fx / base.fx - 200.0 / 193.2).abs() < 1e-12 && k.cx == base.cx, "{k:?}");
        // Breathing needs a locked focus.
        c.realism.focus_distance_mm = None;
        let e = Synthesizer::new(c).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("focus_breathing"), "{e}");
    }
}
