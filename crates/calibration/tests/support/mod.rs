//! Views of a printed marker for the calibration tests and the session benchmark: print
//! errors, random poses of both bodies, projected corners with noise.

#![allow(dead_code)]

use jawtrack_calibration::{CalibrationFrame, SeenTag};
use jawtrack_marker::{Marker, PrintError};
use jawtrack_pose::{CameraIntrinsics, Pose};
use nalgebra::{Point3, Vector3};

/// A small deterministic generator.
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.next().max(1e-300), self.next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

pub fn camera() -> CameraIntrinsics {
    CameraIntrinsics { fx: 1500.0, fy: 1500.0, cx: 959.5, cy: 539.5, k1: 0.05, k2: -0.02 }
}

/// Print errors of 0.2 mm RMS and 0.5° on every tag.
pub fn printed(rng: &mut Lcg) -> Marker {
    let nominal = Marker::default();
    let errors: Vec<(u32, PrintError)> = nominal
        .tags()
        .map(|(_, t)| {
            let e = PrintError {
                shift_x: 0.2 * rng.normal(),
                shift_y: 0.2 * rng.normal(),
                rotation: 0.5f64.to_radians() * rng.normal(),
            };
            (t.id, e)
        })
        .collect();
    nominal.with_print_errors(&errors).expect("valid errors")
}

/// `n` views of both bodies turned every way at ~100 mm, their facing tags' corners with
/// `noise_px` of noise.
pub fn views(marker: &Marker, n: usize, noise_px: f64, rng: &mut Lcg) -> (Vec<CalibrationFrame>, Vec<[Pose; 2]>) {
    let cam = camera();
    let mut frames = Vec::new();
    let mut poses = Vec::new();
    for _ in 0..n {
        let pose_of = |rng: &mut Lcg, x: f64| {
            let axis = Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
            let angle = std::f64::consts::PI * rng.next();
            Pose::from_axis_angle(axis * angle, Vector3::new(x + 4.0 * rng.normal(), 3.0 * rng.normal(), 100.0))
        };
        let pair = [pose_of(rng, -25.0), pose_of(rng, 25.0)];
        let mut tags = Vec::new();
        for (b, body) in marker.bodies.iter().enumerate() {
            for tag in &body.tags {
                let c = pair[b].transform_point(&Point3::from(tag.center));
                let n = pair[b].transform_vector(&tag.face_normal());
                // Seen when facing the camera by more than ~20°.
                if n.dot(&c.coords.normalize()) > -0.35 {
                    continue;
                }
                let corners = tag.corners.map(|p| {
                    let px = cam.project(&pair[b].transform_point(&Point3::from(p))).expect("in front");
                    [px.x + noise_px * rng.normal(), px.y + noise_px * rng.normal()]
                });
                tags.push(SeenTag { id: tag.id, corners });
            }
        }
        frames.push(CalibrationFrame { camera: cam, tags });
        poses.push(pair);
    }
    (frames, poses)
}
