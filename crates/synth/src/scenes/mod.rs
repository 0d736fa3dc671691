//! The rig and its scenes: where the markers sit on the head, how the mandible moves, and
//! where the camera looks from.
//!
//! Head frame (mm): origin at the upper incisal point, X toward the patient's left, Y down,
//! Z posterior (into the head). The image is the phone's landscape sensor buffer, read out row
//! by row from the top (see [`Orientation`]); held upright (portrait, every scene but a
//! landscape chew), the head's vertical runs along the buffer's long side (image x = head down
//! at azimuth 0).
//!
//! Both markers sit 38 mm in front of the incisors, their camera-facing vertex (+Z of the body)
//! pointing anteriorly: the maxilla marker 22 mm above the incisal point, the mandible marker
//! 22 mm below it. The mandible hinges about a transverse axis 95 mm behind and 20 mm above
//! the incisal point (the condyles).

pub mod guided;

pub use guided::Guidance;
use jawtrack_kinematics::{Mounting, Side};
use jawtrack_pose::Pose;
use nalgebra::{Matrix3, Point3, Rotation3, Unit, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// The scenes `jawtrack synth` can render.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SceneKind {
    /// Jaw at rest; camera at 80/100/120 mm (or [`SceneOptions::distance_mm`]), azimuth
    /// 0/30/60°, on a tripod and hand-held.
    Static,
    /// Hinge opening about the condylar axis to 10/20/30/40 mm at the incisors, in rounds of
    /// the four openings.
    Hinge,
    /// Left, right and protrusive glides of 4–6 mm.
    Excursion,
    /// Fast chewing on a tripod 120 mm (or [`SceneOptions::distance_mm`]) straight in front of
    /// the markers: cycles of 0.6–0.8 s opening 15–25 mm with a 3–6 mm sideways swing, the first
    /// one fast enough that the incisor passes 100 mm/s; phone upright or landscape
    /// ([`SceneOptions::orientation`]).
    /// At 1080p (1080 rows, row 539.5 read at the frame's time), with the jaw closed, the
    /// markers' centres fall in these rows:
    /// - upright: both in row 539.5, read together; the swing moves the mandible marker
    ///   10–12.5 rows per mm of swing (at most ±75 rows at 6 mm);
    /// - landscape: the maxilla marker in row 89.5 and the mandible marker in row 639.5, read
    ///   0.51 of the readout later; a 25 mm opening lowers the mandible marker to row ≈ 990.
    Chew,
    /// A marker-calibration recording: the jaw at rest seen from every side the camera can
    /// reach (azimuth −75…75°, elevation −45…45°, 110 mm), so each tag is seen from several
    /// angles.
    Calibration,
    /// A camera-calibration recording: the head (jaw at rest) waved in front of a tripod
    /// camera, the markers swept over the whole image at 90–200 mm, tilted ±25°, at about 100
    /// mm/s (peaks near 180) so that a rolling shutter shears them ([`Wave`]); `cycles` × 2 s.
    Wave,
    /// Border movements guided by programmed condylar paths ([`Guidance::default`], see
    /// [`guided`]): a protrusion and laterotrusions toward the left and the right, each 6 mm of
    /// condylar travel out and back in 2 s (`cycles` rounds), filmed as the hinge is.
    Border,
}

impl SceneKind {
    /// All scenes.
    pub const ALL: [SceneKind; 7] = [
        SceneKind::Static,
        SceneKind::Hinge,
        SceneKind::Excursion,
        SceneKind::Chew,
        SceneKind::Calibration,
        SceneKind::Wave,
        SceneKind::Border,
    ];

    /// The scene's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Static => "static",
            SceneKind::Hinge => "hinge",
            SceneKind::Excursion => "excursion",
            SceneKind::Chew => "chew",
            SceneKind::Calibration => "calibration",
            SceneKind::Wave => "wave",
            SceneKind::Border => "border",
        }
    }
}

impl std::str::FromStr for SceneKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        SceneKind::ALL.into_iter().find(|k| k.name() == s).ok_or_else(|| {
            format!("unknown scene '{s}' (choose static, hinge, excursion, chew, calibration, wave or border)")
        })
    }
}

/// The rendered rig: the patient's head with the harnesses mounted, in front of a face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rig {
    /// How the harnesses sit on the head and where the jaw's anatomy is (head frame, mm): the
    /// one the readouts use too.
    pub mounting: Mounting,
    /// Background (the face) as the plane z = this, facing the camera.
    pub face_plane_z: f64,
}

impl Default for Rig {
    fn default() -> Self {
        Rig { mounting: Mounting::default(), face_plane_z: -10.0 }
    }
}

/// How the mandible moves (head frame), as a function of time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum JawMotion {
    /// Closed.
    Rest,
    /// Hinge opening to `opening_mm` at the lower incisal point and back, once per period.
    Hinge {
        /// Peak incisal opening (mm, chord of the incisal point's arc).
        opening_mm: f64,
        /// When the cycle starts (s).
        start_s: f64,
        /// Cycle duration (s).
        period_s: f64,
    },
    /// A glide out and back: `direction` is "left", "right" or "protrusive".
    Glide {
        /// Which glide.
        direction: Glide,
        /// Peak incisal displacement (mm).
        amplitude_mm: f64,
        /// When it starts (s).
        start_s: f64,
        /// Out-and-back duration (s).
        period_s: f64,
    },
    /// A border movement out and back along programmed condylar paths ([`guided`]): a
    /// protrusion (`movement` "protrusive") or a laterotrusion toward `movement`'s side, the
    /// condyles travelling `travel_mm` at the peak (after the immediate side shift).
    Border {
        /// Which movement.
        movement: Glide,
        /// The condylar and incisal guidance.
        guidance: Guidance,
        /// Peak condylar travel (mm).
        travel_mm: f64,
        /// When it starts (s).
        start_s: f64,
        /// Out-and-back duration (s).
        period_s: f64,
    },
    /// Chewing: a raised-cosine hinge opening with a lateral loop (out to one side while
    /// opening, back on the other while closing), periodic from `start_s`.
    Chew {
        /// Peak incisal opening (mm).
        opening_mm: f64,
        /// Peak lateral displacement (mm).
        lateral_mm: f64,
        /// When a cycle starts, closed (s).
        #[serde(default)]
        start_s: f64,
        /// Cycle duration (s).
        period_s: f64,
    },
}

/// Direction of an excursive glide.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Glide {
    /// Toward the patient's left.
    Left,
    /// Toward the patient's right.
    Right,
    /// Forward.
    Protrusive,
}

/// Raised-cosine progress 0 → 1 → 0 over one period starting at `start`.
fn cycle(t: f64, start: f64, period: f64) -> f64 {
    let s = ((t - start) / period).clamp(0.0, 1.0);
    0.5 * (1.0 - (TAU * s).cos())
}

fn rotation_about(point: &Vector3<f64>, axis: &Unit<Vector3<f64>>, angle: f64) -> Pose {
    let r = UnitQuaternion::from_axis_angle(axis, angle);
    Pose::from_parts(r, point - r * point)
}

impl Rig {
    /// Hinge angle (rad) that moves the lower incisal point by `chord` mm.
    fn hinge_angle(&self, chord: f64) -> f64 {
        let r = (self.mounting.lower_incisal_point - self.mounting.hinge_point()).norm();
        2.0 * (chord / (2.0 * r)).clamp(-1.0, 1.0).asin()
    }

    /// Moves the mandible by the motion at time `t`: `head_from_mandible` (identity = closed).
    pub fn jaw(&self, motion: &JawMotion, t: f64) -> Pose {
        match *motion {
            JawMotion::Rest => Pose::identity(),
            JawMotion::Hinge { opening_mm, start_s, period_s } => {
                let a = self.hinge_angle(opening_mm) * cycle(t, start_s, period_s);
                // A positive turn about +X swings the chin down (+Y) and back.
                rotation_about(&self.mounting.hinge_point(), &Vector3::x_axis(), a)
            }
            JawMotion::Glide { direction, amplitude_mm, start_s, period_s } => {
                let s = cycle(t, start_s, period_s);
                match direction {
                    Glide::Protrusive => {
                        // Forward with incisal guidance: down 0.4 mm per mm forward.
                        Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.4, -1.0) * (amplitude_mm * s))
                    }
                    Glide::Left | Glide::Right => {
                        // Rotation about the working condyle's vertical axis (Bennett movement)
                        // plus a slight opening from canine guidance.
                        let (side, working) =
                            if direction == Glide::Left { (1.0, Side::Left) } else { (-1.0, Side::Right) };
                        let condyle = self.mounting.condyle(working);
                        let lever = self.mounting.lower_incisal_point - condyle;
                        let horizontal = (lever.x * lever.x + lever.z * lever.z).sqrt();
                        let angle = amplitude_mm * s / horizontal;
                        // Sign so that the incisal point moves toward `side`.
                        let probe = rotation_about(&condyle, &Vector3::y_axis(), angle);
                        let moved = probe.transform_point(&Point3::from(self.mounting.lower_incisal_point)).x
                            - self.mounting.lower_incisal_point.x;
                        let angle = if moved * side >= 0.0 { angle } else { -angle };
                        let open = rotation_about(
                            &self.mounting.hinge_point(),
                            &Vector3::x_axis(),
                            self.hinge_angle(0.3 * amplitude_mm * s),
                        );
                        rotation_about(&condyle, &Vector3::y_axis(), angle) * open
                    }
                }
            }
            JawMotion::Border { movement, guidance, travel_mm, start_s, period_s } => {
                let out = cycle(t, start_s, period_s);
                match movement {
                    Glide::Protrusive => self.protrusion(&guidance, travel_mm * out),
                    // The side shift over the first part of the way out, then the path.
                    Glide::Left => self.laterotrusion(&guidance, Side::Left, out * (travel_mm + 1.0) - 1.0),
                    Glide::Right => self.laterotrusion(&guidance, Side::Right, out * (travel_mm + 1.0) - 1.0),
                }
            }
            JawMotion::Chew { opening_mm, lateral_mm, start_s, period_s } => {
                let phase = TAU * (t - start_s) / period_s;
                let open = 0.5 * (1.0 - phase.cos());
                let hinge = rotation_about(
                    &self.mounting.hinge_point(),
                    &Vector3::x_axis(),
                    self.hinge_angle(opening_mm * open),
                );
                // Out on one side, back on the other: a loop in the frontal plane. sin·(1 − cos)/2
                // peaks at 3√3/8, scaled out so that `lateral_mm` is the peak.
                let swing = phase.sin() * open / (3.0 * 3f64.sqrt() / 8.0);
                let lateral = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(lateral_mm * swing, 0.0, 0.0));
                lateral * hinge
            }
        }
    }

    /// Maxilla and mandible marker poses in the head frame at time `t`.
    pub fn markers(&self, motion: &JawMotion, t: f64) -> (Pose, Pose) {
        (self.mounting.head_from_maxilla, self.jaw(motion, t) * self.mounting.head_from_mandible_rest)
    }

    /// Speed (mm/s) at `t` of the lower incisal point relative to the maxilla, read from the
    /// markers' relative pose as a tracker would: a central difference over ±0.5 ms.
    pub fn incisor_speed(&self, motion: &JawMotion, t: f64) -> f64 {
        const HALF_STEP_S: f64 = 0.5e-3;
        let incisor = |t: f64| {
            let (maxilla, mandible) = self.markers(motion, t);
            self.mounting.lower_incisor(&(maxilla.inverse() * mandible))
        };
        (incisor(t + HALF_STEP_S) - incisor(t - HALF_STEP_S)).norm() / (2.0 * HALF_STEP_S)
    }
}

/// Where the camera is: on a circle about a target in the head's horizontal plane.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// Distance from the camera to the target (mm).
    pub distance_mm: f64,
    /// Azimuth (degrees): 0 in front of the face, positive toward the patient's left.
    pub azimuth_deg: f64,
    /// Elevation (degrees): positive above the face looking down.
    pub elevation_deg: f64,
    /// Point looked at (head frame, mm).
    pub target: [f64; 3],
    /// Hand-held: the seed of a smooth tremor; `None` is a tripod.
    pub hand_seed: Option<u64>,
    /// How the phone is held (absent in older files: upright).
    #[serde(default)]
    pub orientation: Orientation,
}

/// How the phone is held, that is how its landscape sensor buffer lies on the face. The
/// readout sweeps the buffer's rows from the top (y = 0) down, so the orientation decides
/// which parts of the face are read when (see [`crate::Realism::row_time`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Orientation {
    /// Portrait: buffer x runs down the head, so the rows are vertical lines on the face and
    /// the readout sweeps across it, from the patient's left (row 0) to the right. The two
    /// markers, one above the other, lie in the same rows and are read at the same times.
    #[default]
    Upright,
    /// Landscape: buffer x runs across the face toward the patient's left, the rows are
    /// horizontal and the readout sweeps down the face, so the upper marker is read about
    /// half a readout before the lower one.
    Landscape,
}

/// Hand tremor amplitudes: about 1 mm and 0.5° in each axis, from 0.3 to 4 Hz.
const TREMOR_MM: f64 = 1.0;
const TREMOR_DEG: f64 = 0.5;

impl View {
    /// `camera_from_head` at time `t`.
    pub fn camera_from_head(&self, t: f64) -> Pose {
        let target = Vector3::from(self.target);
        let (az, el) = (self.azimuth_deg.to_radians(), self.elevation_deg.to_radians());
        let dir_from_target = Vector3::new(az.sin() * el.cos(), -el.sin(), -az.cos() * el.cos());
        let position = target + dir_from_target * self.distance_mm;
        let forward = (target - position).normalize();
        // Upright: image x follows the head's "down" (+Y) as seen by the camera; landscape
        // turns the phone a quarter turn about its optical axis so that image y does.
        let down = (Vector3::y() - forward * forward.y).normalize();
        let (x, y) = match self.orientation {
            Orientation::Upright => (down, forward.cross(&down)),
            Orientation::Landscape => (down.cross(&forward), down),
        };
        let r = Matrix3::from_rows(&[x.transpose(), y.transpose(), forward.transpose()]);
        let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
        let nominal = Pose::from_parts(rot, -(rot * position));
        match self.hand_seed {
            None => nominal,
            Some(seed) => tremor(seed, t) * nominal,
        }
    }
}

/// A smooth random rigid motion of the camera (camera frame), sum of sinusoids.
fn tremor(seed: u64, t: f64) -> Pose {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut v = [0.0; 6];
    for (axis, out) in v.iter_mut().enumerate() {
        let amp = if axis < 3 { TREMOR_MM } else { TREMOR_DEG.to_radians() };
        for _ in 0..3 {
            let f: f64 = rng.random_range(0.3..4.0);
            let phase: f64 = rng.random_range(0.0..TAU);
            *out += amp / 3f64.sqrt() * (TAU * f * t + phase).sin();
        }
    }
    Pose::from_axis_angle(Vector3::new(v[3], v[4], v[5]), Vector3::new(v[0], v[1], v[2]))
}

/// The head waved in front of a still camera: the markers' midpoint swept across the image and
/// in depth by sinusoids, the head tilted about it (camera frame, upright phone).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wave {
    /// Depth of the markers' midpoint (mm): the middle and the swing either side.
    pub depth_mm: [f64; 2],
    /// How far across the image the midpoint swings: its x/z and y/z at the extremes.
    pub reach: [f64; 2],
    /// Peak tilts (degrees) about the camera's x, y and z.
    pub tilt_deg: [f64; 3],
    /// Frequencies (Hz) of x, y, depth and the three tilts.
    pub hz: [f64; 6],
    /// Their phases (rad).
    pub phase: [f64; 6],
}

/// Where the wave scene's head is held from: the markers' midpoint (head frame, mm).
const WAVE_TARGET: [f64; 3] = [0.0, 0.0, -38.0];
/// Seconds of waving per `cycles`.
const WAVE_S: f64 = 2.0;

impl Wave {
    /// A wave with phases drawn from `rng`: midpoint at 97–193 mm, up to 0.38 × its depth
    /// across and 0.22 × down from the optical axis (the outer marker reaches the image's
    /// edges), tilted ±25° (±15° about the optical axis).
    fn draw(rng: &mut ChaCha8Rng) -> Self {
        Wave {
            depth_mm: [145.0, 48.0],
            reach: [0.38, 0.22],
            tilt_deg: [25.0, 25.0, 15.0],
            hz: [0.33, 0.45, 0.2, 0.3, 0.35, 0.25],
            phase: std::array::from_fn(|_| rng.random_range(0.0..TAU)),
        }
    }

    /// `camera_from_head` at time `t`.
    pub fn camera_from_head(&self, t: f64) -> Pose {
        let s = |i: usize| (TAU * self.hz[i] * t + self.phase[i]).sin();
        let z = self.depth_mm[0] + self.depth_mm[1] * s(2);
        let at = Vector3::new(z * self.reach[0] * s(0), z * self.reach[1] * s(1), z);
        let tilt = Vector3::new(self.tilt_deg[0] * s(3), self.tilt_deg[1] * s(4), self.tilt_deg[2] * s(5));
        // Facing the camera as the upright front view does (image x = head down, image y = the
        // patient's right), turned about the midpoint.
        let front = Matrix3::new(0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let front = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(front));
        let turn = UnitQuaternion::from_scaled_axis(tilt.map(f64::to_radians)) * front;
        Pose::from_parts(turn, at - turn * Vector3::from(WAVE_TARGET))
    }
}

/// One frame to render: when, from where, and how the jaw moves around that time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameSpec {
    /// Capture time of the middle of the exposure (s).
    pub t: f64,
    /// The camera (in the wave scene, where the head is held on average).
    pub view: View,
    /// The jaw.
    pub motion: JawMotion,
    /// The wave scene's motion of the head, which replaces the view's (absent elsewhere).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wave: Option<Wave>,
}

impl FrameSpec {
    /// `camera_from_head` at time `t`: the wave's, or else the view's.
    pub fn camera_from_head(&self, t: f64) -> Pose {
        match &self.wave {
            Some(wave) => wave.camera_from_head(t),
            None => self.view.camera_from_head(t),
        }
    }
}

/// Options that shape a scene's frame list.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneOptions {
    /// Frames per camera view in the static scene.
    pub frames_per_view: usize,
    /// Cycles per opening (hinge) or per glide direction (excursion) or in all (chew).
    pub cycles: usize,
    /// Frame rate (frames/s) of the dynamic scenes.
    pub fps: f64,
    /// How the phone is held in the chew scene (the others are filmed upright).
    pub orientation: Orientation,
    /// Where the phone stands (mm from the markers): the static scene's one distance in place
    /// of its 80/100/120 mm, the chew scene's in place of 120 mm; `None` keeps the scenes' own.
    /// A phone that cannot focus closer than 15–20 cm films from there.
    pub distance_mm: Option<f64>,
}

impl Default for SceneOptions {
    fn default() -> Self {
        SceneOptions { frames_per_view: 2, cycles: 2, fps: 30.0, orientation: Orientation::Upright, distance_mm: None }
    }
}

/// The static scene's distances (mm) when [`SceneOptions::distance_mm`] does not set one.
const STATIC_DISTANCES_MM: [f64; 3] = [80.0, 100.0, 120.0];
/// The chew scene's distance (mm) when [`SceneOptions::distance_mm`] does not set one.
const CHEW_DISTANCE_MM: f64 = 120.0;

/// The frames of one movement cycle of `period` seconds from `start`, `dt` apart.
fn one_cycle(start: f64, period: f64, dt: f64, view: View, motion: JawMotion) -> impl Iterator<Item = FrameSpec> {
    let n = (period / dt).round() as usize;
    (0..n).map(move |i| FrameSpec { t: start + i as f64 * dt, view, motion, wave: None })
}

/// Where the chew scene's camera looks (head frame, mm): the markers' depth, 14 mm below the
/// incisal point. Landscape frames only 86 mm of the face's height at 120 mm, less than the
/// markers span with the jaw open; this keeps at least two tags of each marker detectable
/// through 25 mm openings (the maxilla marker's upper tag stays out of the frame).
const CHEW_TARGET: [f64; 3] = [0.0, 14.0, -38.0];

/// Where the hinge and border scenes film the jaw from: a tripod 120 mm away, 30° to the side,
/// aimed below the incisors so that the opening jaw stays in the frame.
const OPENING_VIEW: View = View {
    distance_mm: 120.0,
    azimuth_deg: 30.0,
    elevation_deg: 0.0,
    target: [0.0, 20.0, -34.0],
    hand_seed: None,
    orientation: Orientation::Upright,
};

/// Peak condylar travel of the border scene's movements (mm).
pub const BORDER_TRAVEL_MM: f64 = 6.0;

/// The frames of a scene. `seed` draws the hand tremor, the glide amplitudes and the chewing
/// cycles.
pub fn scene_frames(kind: SceneKind, opts: &SceneOptions, seed: u64) -> Vec<FrameSpec> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0005_cee5);
    let dt = 1.0 / opts.fps;
    match kind {
        SceneKind::Static => static_frames(opts, dt, &mut rng),
        SceneKind::Hinge => hinge_frames(opts, dt),
        SceneKind::Excursion => excursion_frames(opts, dt, &mut rng),
        SceneKind::Chew => chew_frames(opts, dt, &mut rng),
        SceneKind::Calibration => calibration_frames(opts, dt),
        SceneKind::Border => border_frames(opts, dt),
        SceneKind::Wave => wave_frames(opts, dt, &mut rng),
    }
}

/// The static scene: the jaw at rest, seen from each distance and azimuth on a tripod, then
/// hand-held (each hand-held view's tremor seeded from `rng`).
fn static_frames(opts: &SceneOptions, dt: f64, rng: &mut ChaCha8Rng) -> Vec<FrameSpec> {
    let mut frames = Vec::new();
    let mut t = 0.0;
    let distances = opts.distance_mm.map_or(STATIC_DISTANCES_MM.to_vec(), |d| vec![d]);
    for hand in [false, true] {
        for &distance in &distances {
            for azimuth in [0.0, 30.0, 60.0] {
                let view = View {
                    distance_mm: distance,
                    azimuth_deg: azimuth,
                    elevation_deg: 0.0,
                    target: [0.0, 0.0, -38.0],
                    hand_seed: hand.then(|| rng.random()),
                    orientation: Orientation::Upright,
                };
                for _ in 0..opts.frames_per_view {
                    frames.push(FrameSpec { t, view, motion: JawMotion::Rest, wave: None });
                    t += dt;
                }
                // A second between views, as when the tripod is moved.
                t += 1.0;
            }
        }
    }
    frames
}

/// The hinge scene: rounds of 10/20/30/40 mm openings, 2 s each.
fn hinge_frames(opts: &SceneOptions, dt: f64) -> Vec<FrameSpec> {
    let mut frames = Vec::new();
    let view = OPENING_VIEW;
    let period = 2.0;
    let mut start = 0.0;
    // Rounds of the four openings, so that the first rounds of a long session are a
    // shorter session (a cached render serves both).
    for _ in 0..opts.cycles {
        for opening in [10.0, 20.0, 30.0, 40.0] {
            let motion = JawMotion::Hinge { opening_mm: opening, start_s: start, period_s: period };
            frames.extend(one_cycle(start, period, dt, view, motion));
            start += period;
        }
    }
    frames
}

/// The excursion scene: left, right and protrusive glides, each filmed from its own side,
/// with amplitudes drawn from `rng`.
fn excursion_frames(opts: &SceneOptions, dt: f64, rng: &mut ChaCha8Rng) -> Vec<FrameSpec> {
    let mut frames = Vec::new();
    let period = 2.0;
    let mut start = 0.0;
    for (i, direction) in [Glide::Left, Glide::Right, Glide::Protrusive].into_iter().enumerate() {
        let view = View {
            distance_mm: 100.0,
            azimuth_deg: [0.0, 30.0, -30.0][i],
            elevation_deg: 0.0,
            target: [0.0, 2.0, -38.0],
            hand_seed: None,
            orientation: Orientation::Upright,
        };
        for _ in 0..opts.cycles {
            let amplitude_mm = rng.random_range(4.0..6.0);
            let motion = JawMotion::Glide { direction, amplitude_mm, start_s: start, period_s: period };
            frames.extend(one_cycle(start, period, dt, view, motion));
            start += period;
        }
    }
    frames
}

/// The chew scene: chewing cycles drawn from `rng`, filmed straight on at a steady rate.
fn chew_frames(opts: &SceneOptions, dt: f64, rng: &mut ChaCha8Rng) -> Vec<FrameSpec> {
    let view = View {
        distance_mm: opts.distance_mm.unwrap_or(CHEW_DISTANCE_MM),
        azimuth_deg: 0.0,
        elevation_deg: 0.0,
        target: CHEW_TARGET,
        hand_seed: None,
        orientation: opts.orientation,
    };
    let mut cycles = Vec::with_capacity(opts.cycles);
    let mut start_s = 0.0;
    for i in 0..opts.cycles {
        // The first cycle fast: 23–25 mm in 0.60–0.62 s peaks above 115 mm/s.
        let (opening_mm, period_s) = if i == 0 {
            (rng.random_range(23.0..25.0), rng.random_range(0.60..0.62))
        } else {
            (rng.random_range(15.0..25.0), rng.random_range(0.6..0.8))
        };
        let lateral_mm = rng.random_range(3.0..6.0);
        cycles.push(JawMotion::Chew { opening_mm, lateral_mm, start_s, period_s });
        start_s += period_s;
    }
    // The camera runs at a steady rate through the cycles; each frame moves as the cycle
    // it falls in.
    let n = (start_s / dt).round() as usize;
    (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            let motion = cycles
                .iter()
                .copied()
                .rfind(|m| matches!(m, JawMotion::Chew { start_s, .. } if *start_s <= t))
                .unwrap_or(JawMotion::Rest);
            FrameSpec { t, view, motion, wave: None }
        })
        .collect()
}

/// The calibration recording: the jaw at rest (closed), seen from 18 angles.
fn calibration_frames(opts: &SceneOptions, dt: f64) -> Vec<FrameSpec> {
    let mut frames = Vec::new();
    let mut t = 0.0;
    for elevation in [-45.0, 0.0, 45.0] {
        for azimuth in [-75.0, -45.0, -15.0, 15.0, 45.0, 75.0] {
            let view = View {
                distance_mm: 110.0,
                azimuth_deg: azimuth,
                elevation_deg: elevation,
                target: [0.0, 0.0, -38.0],
                hand_seed: None,
                orientation: Orientation::Upright,
            };
            for _ in 0..opts.frames_per_view {
                frames.push(FrameSpec { t, view, motion: JawMotion::Rest, wave: None });
                t += dt;
            }
            t += 1.0;
        }
    }
    frames
}

/// The border scene: rounds of protrusive, left and right border movements, 2 s each.
fn border_frames(opts: &SceneOptions, dt: f64) -> Vec<FrameSpec> {
    let mut frames = Vec::new();
    let view = OPENING_VIEW;
    let (period, mut start) = (2.0, 0.0);
    for _ in 0..opts.cycles {
        for movement in [Glide::Protrusive, Glide::Left, Glide::Right] {
            let motion = JawMotion::Border {
                movement,
                guidance: Guidance::default(),
                travel_mm: BORDER_TRAVEL_MM,
                start_s: start,
                period_s: period,
            };
            frames.extend(one_cycle(start, period, dt, view, motion));
            start += period;
        }
    }
    frames
}

/// The wave scene: the jaw at rest while the camera moves as a wave drawn from `rng`.
fn wave_frames(opts: &SceneOptions, dt: f64, rng: &mut ChaCha8Rng) -> Vec<FrameSpec> {
    let wave = Wave::draw(rng);
    let view = View {
        distance_mm: wave.depth_mm[0],
        azimuth_deg: 0.0,
        elevation_deg: 0.0,
        target: WAVE_TARGET,
        hand_seed: None,
        orientation: Orientation::Upright,
    };
    let n = (opts.cycles as f64 * WAVE_S / dt).round() as usize;
    (0..n).map(|k| FrameSpec { t: k as f64 * dt, view, motion: JawMotion::Rest, wave: Some(wave) }).collect()
}

#[cfg(test)]
mod tests;
