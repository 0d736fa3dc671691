//! The rig and its scenes: where the markers sit on the head, how the mandible moves, and
//! where the camera looks from.
//!
//! Head frame (mm): origin at the upper incisal point, X toward the patient's left, Y down,
//! Z posterior (into the head). The phone faces the patient held in portrait, so the head's
//! vertical runs along the image's long side (image x = head down at azimuth 0).
//!
//! Both markers sit 38 mm in front of the incisors, their camera-facing vertex (+Z of the body)
//! pointing anteriorly: the maxilla marker 22 mm above the incisal point, the mandible marker
//! 22 mm below it. The mandible hinges about a transverse axis 95 mm behind and 20 mm above
//! the incisal point (the condyles).

use jawtrack_kinematics::Mounting;
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
    /// Jaw at rest; camera at 80/100/120 mm, azimuth 0/30/60°, on a tripod and hand-held.
    Static,
    /// Hinge opening about the condylar axis to 10/20/30/40 mm at the incisors, in rounds of
    /// the four openings.
    Hinge,
    /// Left, right and protrusive glides of 4–6 mm.
    Excursion,
    /// Fast chewing cycles with a long exposure (motion blur), hand-held.
    Chew,
    /// A marker-calibration recording: the jaw at rest seen from every side the camera can
    /// reach (azimuth −75…75°, elevation −45…45°, 110 mm), so each tag is seen from several
    /// angles.
    Calibration,
}

impl SceneKind {
    /// All scenes.
    pub const ALL: [SceneKind; 5] =
        [SceneKind::Static, SceneKind::Hinge, SceneKind::Excursion, SceneKind::Chew, SceneKind::Calibration];

    /// The scene's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Static => "static",
            SceneKind::Hinge => "hinge",
            SceneKind::Excursion => "excursion",
            SceneKind::Chew => "chew",
            SceneKind::Calibration => "calibration",
        }
    }
}

impl std::str::FromStr for SceneKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        SceneKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown scene '{s}' (choose static, hinge, excursion, chew or calibration)"))
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
    /// Chewing: opening with a lateral loop, repeated.
    Chew {
        /// Peak incisal opening (mm).
        opening_mm: f64,
        /// Peak lateral displacement (mm).
        lateral_mm: f64,
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
        let r = (self.mounting.lower_incisal_point - self.mounting.hinge_point).norm();
        2.0 * (chord / (2.0 * r)).clamp(-1.0, 1.0).asin()
    }

    /// Moves the mandible by the motion at time `t`: `head_from_mandible` (identity = closed).
    pub fn jaw(&self, motion: &JawMotion, t: f64) -> Pose {
        match *motion {
            JawMotion::Rest => Pose::identity(),
            JawMotion::Hinge { opening_mm, start_s, period_s } => {
                let a = self.hinge_angle(opening_mm) * cycle(t, start_s, period_s);
                // A positive turn about +X swings the chin down (+Y) and back.
                rotation_about(&self.mounting.hinge_point, &Vector3::x_axis(), a)
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
                        let side = if direction == Glide::Left { 1.0 } else { -1.0 };
                        let condyle = self.mounting.hinge_point
                            + Vector3::new(side * self.mounting.intercondylar_mm / 2.0, 0.0, 0.0);
                        let lever = self.mounting.lower_incisal_point - condyle;
                        let horizontal = (lever.x * lever.x + lever.z * lever.z).sqrt();
                        let angle = amplitude_mm * s / horizontal;
                        // Sign so that the incisal point moves toward `side`.
                        let probe = rotation_about(&condyle, &Vector3::y_axis(), angle);
                        let moved = probe.transform_point(&Point3::from(self.mounting.lower_incisal_point)).x
                            - self.mounting.lower_incisal_point.x;
                        let angle = if moved * side >= 0.0 { angle } else { -angle };
                        let open = rotation_about(
                            &self.mounting.hinge_point,
                            &Vector3::x_axis(),
                            self.hinge_angle(0.3 * amplitude_mm * s),
                        );
                        rotation_about(&condyle, &Vector3::y_axis(), angle) * open
                    }
                }
            }
            JawMotion::Chew { opening_mm, lateral_mm, period_s } => {
                let phase = TAU * t / period_s;
                let open = 0.5 * (1.0 - phase.cos());
                let hinge =
                    rotation_about(&self.mounting.hinge_point, &Vector3::x_axis(), self.hinge_angle(opening_mm * open));
                // Out on one side, back on the other: a loop in the frontal plane.
                let lateral = Pose::from_parts(
                    UnitQuaternion::identity(),
                    Vector3::new(lateral_mm * phase.sin() * open, 0.0, 0.0),
                );
                lateral * hinge
            }
        }
    }

    /// Maxilla and mandible marker poses in the head frame at time `t`.
    pub fn markers(&self, motion: &JawMotion, t: f64) -> (Pose, Pose) {
        (self.mounting.head_from_maxilla, self.jaw(motion, t) * self.mounting.head_from_mandible_rest)
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
        // Portrait: image x follows the head's "down" (+Y) as seen by the camera.
        let x = (Vector3::y() - forward * forward.y).normalize();
        let y = forward.cross(&x);
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

/// One frame to render: when, from where, and how the jaw moves around that time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameSpec {
    /// Capture time of the middle of the exposure (s).
    pub t: f64,
    /// The camera.
    pub view: View,
    /// The jaw.
    pub motion: JawMotion,
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
}

impl Default for SceneOptions {
    fn default() -> Self {
        SceneOptions { frames_per_view: 2, cycles: 2, fps: 30.0 }
    }
}

/// The frames of one movement cycle of `period` seconds from `start`, `dt` apart.
fn one_cycle(start: f64, period: f64, dt: f64, view: View, motion: JawMotion) -> impl Iterator<Item = FrameSpec> {
    let n = (period / dt).round() as usize;
    (0..n).map(move |i| FrameSpec { t: start + i as f64 * dt, view, motion })
}

/// The frames of a scene. `seed` draws the hand tremor and the glide amplitudes.
pub fn scene_frames(kind: SceneKind, opts: &SceneOptions, seed: u64) -> Vec<FrameSpec> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0005_cee5);
    let dt = 1.0 / opts.fps;
    let mut frames = Vec::new();
    match kind {
        SceneKind::Static => {
            let mut t = 0.0;
            for hand in [false, true] {
                for distance in [80.0, 100.0, 120.0] {
                    for azimuth in [0.0, 30.0, 60.0] {
                        let view = View {
                            distance_mm: distance,
                            azimuth_deg: azimuth,
                            elevation_deg: 0.0,
                            target: [0.0, 0.0, -38.0],
                            hand_seed: hand.then(|| rng.random()),
                        };
                        for _ in 0..opts.frames_per_view {
                            frames.push(FrameSpec { t, view, motion: JawMotion::Rest });
                            t += dt;
                        }
                        // A second between views, as when the tripod is moved.
                        t += 1.0;
                    }
                }
            }
        }
        SceneKind::Hinge => {
            let view = View {
                distance_mm: 120.0,
                azimuth_deg: 30.0,
                elevation_deg: 0.0,
                target: [0.0, 20.0, -34.0],
                hand_seed: None,
            };
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
        }
        SceneKind::Excursion => {
            let period = 2.0;
            let mut start = 0.0;
            for (i, direction) in [Glide::Left, Glide::Right, Glide::Protrusive].into_iter().enumerate() {
                let view = View {
                    distance_mm: 100.0,
                    azimuth_deg: [0.0, 30.0, -30.0][i],
                    elevation_deg: 0.0,
                    target: [0.0, 2.0, -38.0],
                    hand_seed: None,
                };
                for _ in 0..opts.cycles {
                    let amplitude_mm = rng.random_range(4.0..6.0);
                    let motion = JawMotion::Glide { direction, amplitude_mm, start_s: start, period_s: period };
                    frames.extend(one_cycle(start, period, dt, view, motion));
                    start += period;
                }
            }
        }
        SceneKind::Chew => {
            let view = View {
                distance_mm: 110.0,
                azimuth_deg: 20.0,
                elevation_deg: 10.0,
                target: [0.0, 10.0, -36.0],
                hand_seed: Some(rng.random()),
            };
            let motion = JawMotion::Chew { opening_mm: 18.0, lateral_mm: 5.0, period_s: 0.8 };
            let n = (opts.cycles as f64 * 0.8 / dt).round() as usize;
            frames.extend((0..n).map(|k| FrameSpec { t: k as f64 * dt, view, motion }));
        }
        SceneKind::Calibration => {
            let mut t = 0.0;
            for elevation in [-45.0, 0.0, 45.0] {
                for azimuth in [-75.0, -45.0, -15.0, 15.0, 45.0, 75.0] {
                    let view = View {
                        distance_mm: 110.0,
                        azimuth_deg: azimuth,
                        elevation_deg: elevation,
                        target: [0.0, 0.0, -38.0],
                        hand_seed: None,
                    };
                    for _ in 0..opts.frames_per_view {
                        frames.push(FrameSpec { t, view, motion: JawMotion::Rest });
                        t += dt;
                    }
                    t += 1.0;
                }
            }
        }
    }
    frames
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hinge_opens_the_incisors_by_the_requested_chord() {
        let rig = Rig::default();
        let motion = JawMotion::Hinge { opening_mm: 30.0, start_s: 0.0, period_s: 2.0 };
        let peak = rig.jaw(&motion, 1.0);
        let p = Point3::from(rig.mounting.lower_incisal_point);
        let moved = peak.transform_point(&p) - p;
        assert!((moved.norm() - 30.0).abs() < 1e-9);
        assert!(moved.y > 20.0, "opens downward: {moved:?}");
        assert!(rig.jaw(&motion, 0.0).distance_to(&Pose::identity()).1 < 1e-12);
        // Read back from the markers' relative pose, as a tracker would see it.
        let (maxilla, mandible) = rig.markers(&motion, 1.0);
        let seen = rig.mounting.lower_incisor(&(maxilla.inverse() * mandible));
        assert!((seen - peak.transform_point(&p)).norm() < 1e-9);
    }

    #[test]
    fn glides_go_where_they_say() {
        let rig = Rig::default();
        let p = Point3::from(rig.mounting.lower_incisal_point);
        for (dir, check) in [
            (Glide::Left, Box::new(|d: Vector3<f64>| d.x > 3.9) as Box<dyn Fn(Vector3<f64>) -> bool>),
            (Glide::Right, Box::new(|d: Vector3<f64>| d.x < -3.9)),
            (Glide::Protrusive, Box::new(|d: Vector3<f64>| d.z < -4.9 && d.y > 0.0)),
        ] {
            let m = JawMotion::Glide { direction: dir, amplitude_mm: 5.0, start_s: 0.0, period_s: 2.0 };
            let d = rig.jaw(&m, 1.0).transform_point(&p) - p;
            assert!(check(d), "{dir:?}: {d:?}");
        }
    }

    #[test]
    fn camera_looks_at_the_target_from_the_given_distance() {
        let v = View {
            distance_mm: 100.0,
            azimuth_deg: 30.0,
            elevation_deg: 10.0,
            target: [0.0, 0.0, -38.0],
            hand_seed: None,
        };
        let c = v.camera_from_head(0.0);
        let target = c.transform_point(&Point3::new(0.0, 0.0, -38.0));
        assert!(target.x.abs() < 1e-9 && target.y.abs() < 1e-9 && (target.z - 100.0).abs() < 1e-9);
        // Head "down" appears toward image +x at azimuth 0.
        let v0 = View { azimuth_deg: 0.0, elevation_deg: 0.0, ..v };
        let c0 = v0.camera_from_head(0.0);
        assert!(c0.transform_vector(&Vector3::y()).x > 0.99);
        // Tremor stays small.
        let h = View { hand_seed: Some(7), ..v };
        let (a, d) = h.camera_from_head(0.3).distance_to(&c);
        assert!(a.to_degrees() < 2.0 && d < 4.0 && (a > 0.0 || d > 0.0));
    }

    #[test]
    fn scenes_have_the_documented_shape() {
        let o = SceneOptions::default();
        assert_eq!(scene_frames(SceneKind::Static, &o, 1).len(), 2 * 9 * 2);
        assert_eq!(scene_frames(SceneKind::Hinge, &o, 1).len(), 4 * 2 * 60);
        assert_eq!(scene_frames(SceneKind::Excursion, &o, 1).len(), 3 * 2 * 60);
        assert_eq!(scene_frames(SceneKind::Chew, &o, 1).len(), 48);
        assert_eq!(scene_frames(SceneKind::Calibration, &o, 1).len(), 3 * 6 * 2);
    }
}
