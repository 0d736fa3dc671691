//! A body that moves while a rolling shutter reads the frame.
//!
//! A phone reads its sensor one row after another: row `y` of an `H`-row buffer is exposed
//! centred at `t + (y − (H−1)/2)/(H−1) · readout` ([`RollingShutter::offset_s`]), where `t`,
//! the frame's time, is that of its centre row. A corner of a moving body is therefore seen
//! where the body was at its own row's time, not at `t`. Over a few milliseconds a body moves
//! at constant velocity ([`Velocity`]), so each observation can be carried back to where it
//! would have been seen at `t` ([`to_frame_time`]) and the pose solved at `t` as usual; both
//! bodies are then solved at the same instant, and their relative pose is one of the jaw.
//!
//! Motion blur needs nothing here: a row integrates its exposure symmetrically about its own
//! time, so a smeared edge's centre is where the edge was at that time.

use crate::{CameraIntrinsics, GeometryError, Observation, Pose};
use nalgebra::{Point3, UnitQuaternion, Vector3};

/// How the rows of a frame were read: `readout_s` from the first row to the last of `rows`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RollingShutter {
    readout_s: f64,
    rows: usize,
}

impl RollingShutter {
    /// A shutter that reads `rows` rows in `readout_s` seconds (0 = a global shutter).
    pub fn new(readout_s: f64, rows: usize) -> Result<Self, GeometryError> {
        if !(readout_s.is_finite() && (0.0..1.0).contains(&readout_s)) {
            return Err(GeometryError::BadShutter(format!(
                "the readout time must be at least 0 and under 1 s, got {readout_s} s"
            )));
        }
        Ok(RollingShutter { readout_s, rows })
    }

    /// Every row at once.
    pub fn global() -> Self {
        RollingShutter { readout_s: 0.0, rows: 1 }
    }

    /// Time from the first row to the last (s).
    pub fn readout_s(&self) -> f64 {
        self.readout_s
    }

    /// Whether every row is exposed at the frame's time.
    pub fn is_global(&self) -> bool {
        self.readout_s == 0.0 || self.rows < 2
    }

    /// When the row through image y (px, fractional) was exposed, relative to the frame's
    /// time (the centre row's): negative above the centre, positive below.
    pub fn offset_s(&self, y: f64) -> f64 {
        if self.is_global() {
            return 0.0;
        }
        let last = (self.rows - 1) as f64;
        (y - last / 2.0) / last * self.readout_s
    }
}

/// A rigid body's velocity in the camera frame: its orientation turns at `angular` (rad/s,
/// rotation vector per second, applied on the left) and its origin moves at `linear` (mm/s).
/// The same model as the tracker's constant-velocity prediction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Velocity {
    /// Angular velocity (rad/s), camera frame.
    pub angular: Vector3<f64>,
    /// Velocity of the body's origin (mm/s), camera frame.
    pub linear: Vector3<f64>,
}

impl Velocity {
    /// At rest.
    pub const ZERO: Velocity = Velocity { angular: Vector3::new(0.0, 0.0, 0.0), linear: Vector3::new(0.0, 0.0, 0.0) };

    /// `pose` moved on by `dt` seconds at this velocity.
    pub fn advance(&self, pose: &Pose, dt: f64) -> Pose {
        let turn = UnitQuaternion::from_scaled_axis(self.angular * dt);
        Pose::from_parts(turn * pose.rotation(), pose.translation() + self.linear * dt)
    }

    /// The velocity at the newest of `history`'s timed poses (oldest first): see
    /// [`Velocity::at`].
    pub fn at_newest(history: &[(f64, Pose)]) -> Option<Velocity> {
        Velocity::at(history, history.last()?.0)
    }

    /// The velocity at time `at` of a body whose poses `history` gives (oldest first): the
    /// derivative at `at` of the parabola through the last three (exact for constant
    /// acceleration), or of the line through the last two. `None` with fewer than two poses,
    /// or times that do not increase.
    pub fn at(history: &[(f64, Pose)], at: f64) -> Option<Velocity> {
        let n = history.len();
        if n < 2 || !at.is_finite() {
            return None;
        }
        let (t0, p0) = history[n - 1];
        // Nodes as (offset from the newest, turn and shift from the newest pose).
        let nodes: Vec<(f64, Vector3<f64>, Vector3<f64>)> = history[n.saturating_sub(3)..]
            .iter()
            .map(|(t, p)| {
                let turn = (p.rotation() * p0.rotation().inverse()).scaled_axis();
                (t - t0, turn, p.translation() - p0.translation())
            })
            .collect();
        let increasing = nodes.windows(2).all(|w| w[0].0 < w[1].0);
        if !increasing || nodes.iter().any(|(s, _, _)| !s.is_finite()) {
            return None;
        }
        // The derivative at `s` of the Lagrange polynomial through the nodes: node j weighs
        // Σ_{m≠j} Π_{l≠j,m} (s − s_l) / Π_{l≠j} (s_j − s_l).
        let s = at - t0;
        let mut v = Velocity::ZERO;
        for (j, (sj, turn, shift)) in nodes.iter().enumerate() {
            let denominator: f64 = nodes.iter().enumerate().filter(|(l, _)| *l != j).map(|(_, n)| sj - n.0).product();
            let numerator: f64 = (0..nodes.len())
                .filter(|m| *m != j)
                .map(|m| {
                    nodes.iter().enumerate().filter(|(l, _)| *l != j && *l != m).map(|(_, n)| s - n.0).product::<f64>()
                })
                .sum();
            let w = numerator / denominator;
            v.angular += turn * w;
            v.linear += shift * w;
        }
        Some(v)
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.angular.iter().chain(self.linear.iter()).all(|v| v.is_finite())
    }
}

/// The observations of a body moving at `velocity`, each carried from its own row's time to
/// the frame's: where it would have been seen had every row been exposed at once. `pose` is
/// the body's pose at the frame's time as far as it is known (the correction is a difference
/// of two projections through it, so its error matters only to second order). A point that
/// does not project is left as it was.
pub fn to_frame_time(
    observations: &[Observation],
    shutter: &RollingShutter,
    camera: &CameraIntrinsics,
    pose: &Pose,
    velocity: &Velocity,
) -> Vec<Observation> {
    if shutter.is_global() {
        return observations.to_vec();
    }
    observations
        .iter()
        .map(|o| {
            let dt = shutter.offset_s(o.pixel.y);
            let at_frame = camera.project(&pose.transform_point(&o.body));
            let at_row = camera.project(&velocity.advance(pose, dt).transform_point(&o.body));
            match (at_frame, at_row) {
                (Some(f), Some(r)) => Observation { pixel: o.pixel + (f - r), ..*o },
                _ => *o,
            }
        })
        .collect()
}

/// Where body point `body` is seen under a rolling shutter when the body is at `pose` at the
/// frame's time and moves at `velocity`: the image point whose row's time puts the body where
/// it projects onto that row (a fixed point, found by iteration). For tests and renderers.
pub fn seen_at_row_time(
    body: &Point3<f64>,
    shutter: &RollingShutter,
    camera: &CameraIntrinsics,
    pose: &Pose,
    velocity: &Velocity,
) -> Option<nalgebra::Point2<f64>> {
    let mut p = camera.project(&pose.transform_point(body))?;
    for _ in 0..20 {
        let next = camera.project(&velocity.advance(pose, shutter.offset_s(p.y)).transform_point(body))?;
        let moved = (next - p).norm();
        p = next;
        if moved < 1e-10 {
            break;
        }
    }
    Some(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    fn moving(t: f64) -> Pose {
        // Constant acceleration and a turn that speeds up: a parabola in time.
        Pose::from_axis_angle(
            Vector3::new(0.2 * t + 0.5 * t * t, -0.1 * t, 0.3 * t),
            Vector3::new(90.0 * t - 400.0 * t * t, 40.0 * t, 120.0 + 5.0 * t),
        )
    }

    #[test]
    fn row_times_run_from_minus_half_to_plus_half_a_readout() {
        let s = RollingShutter::new(0.010, 1080).expect("valid");
        assert!((s.offset_s(0.0) + 0.005).abs() < 1e-15);
        assert!((s.offset_s(1079.0) - 0.005).abs() < 1e-15);
        assert_eq!(s.offset_s(539.5), 0.0);
        assert_eq!(RollingShutter::global().offset_s(0.0), 0.0);
        assert!(RollingShutter::new(-0.001, 1080).is_err());
        assert!(RollingShutter::new(f64::NAN, 1080).is_err());
    }

    #[test]
    fn velocity_from_three_poses_is_second_order() {
        let h = 1.0 / 60.0;
        let history: Vec<(f64, Pose)> = (0..3).map(|i| (i as f64 * h, moving(i as f64 * h))).collect();
        let v = Velocity::at_newest(&history).expect("three poses");
        // The translation is exactly quadratic: its derivative at 2h is exact.
        let exact = Vector3::new(90.0 - 800.0 * 2.0 * h, 40.0, 5.0);
        assert!((v.linear - exact).norm() < 1e-9, "{:?}", v.linear);
        // The rotation's angular velocity, to the small error of a non-commuting turn.
        let dt = 1e-6;
        let turn = (moving(2.0 * h + dt).rotation() * moving(2.0 * h - dt).rotation().inverse()).scaled_axis() / 2e-6;
        assert!((v.angular - turn).norm() < 2e-3, "{:?} vs {turn:?}", v.angular);
        // Earlier on the parabola too.
        let earlier = Velocity::at(&history, 2.0 * h - 0.004).expect("three poses");
        assert!((earlier.linear.x - (90.0 - 800.0 * (2.0 * h - 0.004))).abs() < 1e-9);
        // Two poses give the secant's slope; one gives nothing.
        let two = Velocity::at_newest(&history[1..]).expect("two poses");
        assert!((two.linear.x - (90.0 - 400.0 * 3.0 * h)).abs() < 1e-9);
        assert!(Velocity::at_newest(&history[2..]).is_none());
        let backwards = [history[1], history[0]];
        assert!(Velocity::at_newest(&backwards).is_none());
    }

    #[test]
    fn observations_carried_to_the_frame_time_project_from_the_frame_pose() {
        let camera =
            CameraIntrinsics { k1: -0.05, k2: 0.01, ..CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5) };
        let shutter = RollingShutter::new(0.010, 1080).expect("valid");
        let pose = Pose::from_axis_angle(Vector3::new(0.1, 0.2, 0.0), Vector3::new(5.0, 30.0, 120.0));
        let velocity = Velocity { angular: Vector3::new(0.5, -1.0, 0.2), linear: Vector3::new(0.0, 90.0, -20.0) };
        let points: Vec<Point3<f64>> =
            (0..8).map(|i| Point3::new(f64::from(i) * 3.0 - 10.0, f64::from(i % 3) * 4.0, 2.0)).collect();
        let observations: Vec<Observation> = points
            .iter()
            .map(|b| Observation {
                tag: 0,
                body: *b,
                pixel: seen_at_row_time(b, &shutter, &camera, &pose, &velocity).expect("in view"),
            })
            .collect();
        // Seen under the rolling shutter, the points are pixels away from the frame-time image.
        let frame_time: Vec<Point2<f64>> =
            points.iter().map(|b| camera.project(&pose.transform_point(b)).expect("in view")).collect();
        let worst_before = observations.iter().zip(&frame_time).map(|(o, f)| (o.pixel - f).norm()).fold(0.0, f64::max);
        assert!(worst_before > 1.0, "the shutter should move the points, by {worst_before} px");
        // Carried back with the true velocity, they land on it to well under a thousandth.
        let carried = to_frame_time(&observations, &shutter, &camera, &pose, &velocity);
        for (o, f) in carried.iter().zip(&frame_time) {
            assert!((o.pixel - f).norm() < 1e-3, "{:?} vs {f:?}", o.pixel);
        }
        // A global shutter changes nothing.
        assert_eq!(to_frame_time(&observations, &RollingShutter::global(), &camera, &pose, &velocity), observations);
    }
}
