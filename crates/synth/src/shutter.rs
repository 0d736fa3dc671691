//! Rolling shutter: each row of the buffer integrates its own exposure window, centred at
//! [`Realism::row_time`], and the ground truth places each point where it is seen.
//!
//! Rows are rendered one at a time (a one-row window of the ray caster gives pixels exactly as
//! a full render). A row averages n instants at the midpoints of n equal slices of its own
//! window, so its blur is centred on the row's time, with n large enough that no probe point
//! moves more than a quarter pixel between neighbouring instants. With a still camera only the
//! markers move, so only the rows and columns a moving marker crosses during the frame are
//! rendered per row; the rest keeps the single render at the frame's time.

use crate::realism::Realism;
use crate::render::{self, LinearImage, RenderScene};
use nalgebra::Point2;
use rayon::prelude::*;

/// Largest motion (px) of anything between neighbouring instants of a row.
pub(crate) const STEP_PX: f64 = 0.25;

/// Most instants a row averages: a bound on the cost of absurd settings (a 1/30 s exposure of
/// a jaw at 100 mm/s at 120 mm takes about 170).
const MAX_INSTANTS: u32 = 1024;

/// A rolling-shutter frame to render.
pub(crate) struct Rolling<'s, 'a> {
    /// Exposure and readout.
    pub realism: &'s Realism,
    /// The frame's time: the centre row's mid-exposure (s).
    pub t: f64,
    /// The scene at an instant.
    pub scene_at: &'s (dyn Fn(f64) -> RenderScene<'a> + Sync),
    /// Image points (px) at an instant whose motion bounds the motion of everything.
    pub probe_at: &'s (dyn Fn(f64) -> Vec<Point2<f64>> + Sync),
    /// Whether the camera stands still over the frame, so that only the markers move.
    pub still: bool,
    /// Largest motion (px) between neighbouring instants of a row.
    pub step_px: f64,
}

impl Rolling<'_, '_> {
    /// The instants a row exposed centred at `c` averages: midpoints of equal slices of its
    /// window, enough that nothing moves more than `step_px` from one to the next.
    fn instants(&self, c: f64) -> Vec<f64> {
        let e = self.realism.exposure_s;
        let moved =
            if e > 0.0 { largest_motion(&(self.probe_at)(c - e / 2.0), &(self.probe_at)(c + e / 2.0)) } else { 0.0 };
        slice_midpoints(c, e, moved, self.step_px, MAX_INSTANTS)
    }

    /// The window `[x0, y0, x1, y1)` to render row by row: with a still camera, where the
    /// markers that move pass during the frame (`None` if none moves on screen: the render at
    /// the frame's time is exact), else the whole image.
    fn window(&self, width: u32, height: u32) -> Option<[usize; 4]> {
        if !self.still {
            return Some([0, 0, width as usize, height as usize]);
        }
        let e = self.realism.exposure_s;
        let t0 = self.realism.row_time(self.t, 0.0, height) - e / 2.0;
        let t1 = self.realism.row_time(self.t, f64::from(height.saturating_sub(1)), height) + e / 2.0;
        // Sample the span finely enough that the markers move under a pixel between samples
        // (their windows are padded by 2 px): a coarse pass measures the speed.
        const COARSE: u32 = 8;
        let at = |i: u32, n: u32| t0 + (t1 - t0) * f64::from(i) / f64::from(n);
        let coarse: Vec<Vec<Point2<f64>>> = (0..=COARSE).map(|i| (self.probe_at)(at(i, COARSE))).collect();
        let step = coarse.windows(2).map(|w| largest_motion(&w[0], &w[1])).fold(0.0, f64::max);
        let n = COARSE * (step.ceil() as u32).clamp(1, MAX_INSTANTS);
        // A marker that stands still keeps its pixels from the render at the frame's time.
        let first: Vec<_> = (self.scene_at)(t0).bodies.iter().map(|b| b.camera_from_body).collect();
        let mut moving = vec![false; first.len()];
        let mut windows = vec![None; first.len()];
        for i in 0..=n {
            let scene = (self.scene_at)(at(i, n));
            for (j, body) in scene.bodies.iter().enumerate().take(first.len()) {
                moving[j] |= body.camera_from_body != first[j];
                if let Some(w) = render::body_window(&scene, j) {
                    windows[j] = Some(windows[j].map_or(w, |u| render::window_union(u, w)));
                }
            }
        }
        windows.into_iter().zip(moving).filter_map(|(w, m)| w.filter(|_| m)).reduce(render::window_union)
    }

    /// Renders the rows that move into `img` (a render at the frame's time, which the other
    /// rows keep) and returns the most instants a row averaged. Depth comes from each row's
    /// middle instant, as the global shutter's from its middle sub-frame.
    pub fn render_into(&self, img: &mut LinearImage) -> u32 {
        let (width, height) = (img.width, img.height);
        let Some(win) = self.window(width, height) else { return 1 };
        let rows: Vec<(Vec<f32>, Vec<f32>, u32)> = (win[1]..win[3])
            .into_par_iter()
            .map(|y| {
                let times = self.instants(self.realism.row_time(self.t, y as f64, height));
                let mut radiance = vec![0.0f32; win[2] - win[0]];
                let mut depth = Vec::new();
                for (i, &ti) in times.iter().enumerate() {
                    let part = render::render_window(&(self.scene_at)(ti), [win[0], y, win[2], y + 1]);
                    radiance.iter_mut().zip(&part.radiance).for_each(|(a, b)| *a += b);
                    if i == times.len() / 2 {
                        depth = part.depth;
                    }
                }
                let inv = 1.0 / times.len() as f32;
                radiance.iter_mut().for_each(|v| *v *= inv);
                (radiance, depth, times.len() as u32)
            })
            .collect();
        let w = width as usize;
        let mut most = 1;
        for (row, (radiance, depth, n)) in rows.into_iter().enumerate() {
            let start = (win[1] + row) * w + win[0];
            img.radiance[start..start + radiance.len()].copy_from_slice(&radiance);
            img.depth[start..start + depth.len()].copy_from_slice(&depth);
            most = most.max(n);
        }
        most
    }
}

/// The instants that stand for an exposure of `e` s centred at `c` over which the image moves
/// `moved` px: the midpoints of n equal slices, n the fewest (at most `most`) that keep
/// neighbouring instants within `step_px`. Both shutters average these, so a smear is drawn
/// the same way whichever renders it; one instant (the centre) when nothing moves.
pub(crate) fn slice_midpoints(c: f64, e: f64, moved: f64, step_px: f64, most: u32) -> Vec<f64> {
    let n = if e > 0.0 { ((moved / step_px).ceil() as u32).clamp(1, most.max(1)) } else { 1 };
    (0..n).map(|s| c + e * ((f64::from(s) + 0.5) / f64::from(n) - 0.5)).collect()
}

/// The largest distance between corresponding points (px).
pub(crate) fn largest_motion(a: &[Point2<f64>], b: &[Point2<f64>]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

/// Where a point is seen in a frame of `height` rows at time `t`: the image point p that
/// `project_at` gives at p's own row time, `p = project_at(row_time(p.y))`, found by fixed-point
/// iteration from the projection at `t` (it contracts by the point's motion per row time, far
/// below 1). With a global shutter it is the projection at `t`. `None` where the projection is.
pub(crate) fn seen_at(
    realism: &Realism,
    t: f64,
    height: u32,
    project_at: impl Fn(f64) -> Option<Point2<f64>>,
) -> Option<Point2<f64>> {
    let mut p = project_at(t)?;
    if realism.readout_s == 0.0 {
        return Some(p);
    }
    for _ in 0..20 {
        let q = project_at(realism.row_time(t, p.y, height))?;
        let settled = (q.y - p.y).abs() < 1e-10;
        p = q;
        if settled {
            break;
        }
    }
    Some(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Camera, INK_ALBEDO, PAPER_ALBEDO, PlacedBody, render_linear};
    use jawtrack_marker::{BodyKind, Marker};
    use jawtrack_pose::{CameraIntrinsics, Pose};
    use nalgebra::{Matrix3, Point3, Rotation3, UnitQuaternion, Vector3};

    const FX: f64 = 1500.0;
    /// A strip 48 × 64 px across the left edge of a tag 96 px tall: the edge crosses every row.
    const W: u32 = 48;
    const H: u32 = 64;

    /// Tag 0 of the maxilla facing the camera, its centre 48 px right of the principal point
    /// at t = 0, moving by `velocity` (mm/s) and `accel` (mm/s²) in the camera frame.
    struct MovingTag {
        marker: Marker,
        rot: UnitQuaternion<f64>,
        start: Vector3<f64>,
        velocity: Vector3<f64>,
        accel: Vector3<f64>,
    }

    impl MovingTag {
        fn new(velocity: Vector3<f64>, accel: Vector3<f64>) -> Self {
            let marker = Marker::default();
            let tag = marker.body(BodyKind::Maxilla).expect("maxilla").tags[0].clone();
            let solid = marker.geometry();
            let face = &solid.faces()[tag.face];
            let r = Matrix3::from_rows(&[face.x_axis.transpose(), face.y_axis.transpose(), (-face.normal).transpose()]);
            let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
            let z = FX * tag.size / 96.0;
            let start = Vector3::new(48.0 * z / FX, 0.0, z) - rot * tag.center;
            MovingTag { marker, rot, start, velocity, accel }
        }

        fn camera(&self) -> Camera {
            let cy = f64::from(H - 1) / 2.0;
            Camera { intrinsics: CameraIntrinsics::pinhole(FX, FX, f64::from(W) / 2.0 - 0.5, cy), width: W, height: H }
        }

        fn pose(&self, t: f64) -> Pose {
            Pose::from_parts(self.rot, self.start + self.velocity * t + self.accel * (0.5 * t * t))
        }

        fn scene(&self, t: f64) -> RenderScene<'_> {
            RenderScene {
                camera: self.camera(),
                bodies: vec![PlacedBody {
                    body: self.marker.body(BodyKind::Maxilla).expect("maxilla"),
                    solid: self.marker.solid,
                    edge: self.marker.edge,
                    family: self.marker.family,
                    camera_from_body: self.pose(t),
                }],
                planes: vec![],
                light_dir: Vector3::new(0.0, 0.0, -1.0),
                ambient: 0.35,
            }
        }

        /// Corner `i` of the tag projected from `pose`.
        fn corner(&self, i: usize, pose: &Pose) -> Option<Point2<f64>> {
            let tag = &self.marker.body(BodyKind::Maxilla).expect("maxilla").tags[0];
            self.camera().intrinsics.project(&pose.transform_point(&Point3::from(tag.corners[i])))
        }

        /// The left edge's two corners (top first) as the truth places them.
        fn left_corners(&self, realism: &Realism) -> [Point2<f64>; 2] {
            let mut c: Vec<Point2<f64>> = (0..4)
                .map(|i| seen_at(realism, 0.0, H, |t| self.corner(i, &self.pose(t))).expect("in front"))
                .collect();
            c.sort_by(|a, b| a.x.total_cmp(&b.x));
            let (a, b) = (c[0], c[1]);
            if a.y < b.y { [a, b] } else { [b, a] }
        }

        /// Renders the frame at t = 0 with a rolling shutter.
        fn render(&self, realism: &Realism, step_px: f64) -> (LinearImage, u32) {
            let scene_at = |t: f64| self.scene(t);
            let probe_at = |t: f64| (0..4).filter_map(|i| self.corner(i, &self.pose(t))).collect();
            let mut img = render_linear(&self.scene(0.0));
            let rolling = Rolling { realism, t: 0.0, scene_at: &scene_at, probe_at: &probe_at, still: true, step_px };
            let most = rolling.render_into(&mut img);
            (img, most)
        }
    }

    /// Where the white-to-black edge of each row lies (px): the box-filter sum over a window
    /// about `near(y)` that holds the whole (blurred) edge is the length of its white part.
    fn left_edges(img: &LinearImage, near: impl Fn(f64) -> f64, half: i64) -> Vec<f64> {
        let (white, black) = (f64::from(PAPER_ALBEDO), f64::from(INK_ALBEDO));
        (0..H as usize)
            .map(|y| {
                let mid = near(y as f64).round() as i64;
                let (lo, hi) = (mid - half, mid + half);
                assert!(lo >= 0 && hi < i64::from(W), "row {y}: window {lo}..{hi} leaves the strip");
                let sum: f64 = (lo..=hi)
                    .map(|x| (f64::from(img.radiance[y * W as usize + x as usize]) - black) / (white - black))
                    .sum();
                lo as f64 - 0.5 + sum
            })
            .collect()
    }

    fn line_x(a: Point2<f64>, b: Point2<f64>, y: f64) -> f64 {
        a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y)
    }

    /// With an instant per row (E = 0) and a 10 ms readout, the tag's edge lies on the line
    /// through the corners the truth gives (each at its own row's time), and several pixels
    /// from the line through the corners at the frame's time.
    #[test]
    fn the_truth_puts_rolling_shutter_corners_where_the_rows_see_them() {
        // 100 mm/s across the image and 40 mm/s down: about 1000 and 400 px/s here.
        let moving = MovingTag::new(Vector3::new(100.0, 40.0, 0.0), Vector3::zeros());
        let realism = Realism { exposure_s: 0.0, readout_s: 0.010, ..Realism::clean() };
        let (img, most) = moving.render(&realism, STEP_PX);
        assert_eq!(most, 1, "an instant per row");
        let [top, bottom] = moving.left_corners(&realism);
        let global = Realism { readout_s: 0.0, ..realism };
        let [top0, bottom0] = moving.left_corners(&global);
        let edges = left_edges(&img, |y| line_x(top, bottom, y), 5);
        let (mut truth_err, mut centre_err) = (0.0f64, 0.0f64);
        for (y, e) in edges.iter().enumerate() {
            truth_err = truth_err.max((e - line_x(top, bottom, y as f64)).abs());
            centre_err = centre_err.max((e - line_x(top0, bottom0, y as f64)).abs());
        }
        eprintln!(
            "rolling shutter, E = 0: edge vs truth {truth_err:.4} px, vs centre-time projection {centre_err:.2} px"
        );
        assert!(truth_err < 0.02, "edge {truth_err} px from the truth's corners");
        assert!(centre_err > 3.0, "the readout should shear the edge by pixels: {centre_err}");
        // Each corner is the projection at its own row's time.
        for p in [top, bottom] {
            let at_row = (0..4)
                .filter_map(|i| moving.corner(i, &moving.pose(realism.row_time(0.0, p.y, H))))
                .map(|q| (q - p).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(at_row < 1e-9, "corner {p} is not where its row sees it ({at_row})");
        }
    }

    /// A fast, accelerating tag (100 mm/s, 8 ms exposure, 10 ms readout): rendering each row
    /// with 4× the instants moves no row's edge by more than a hundredth of a pixel, and every
    /// row's edge sits at the mean of its own exposure window.
    #[test]
    fn rolling_shutter_blur_is_converged_and_centred_on_each_row() {
        let moving = MovingTag::new(Vector3::new(100.0, 20.0, 0.0), Vector3::new(2000.0, 0.0, 0.0));
        let realism = Realism { exposure_s: 0.008, readout_s: 0.010, ..Realism::clean() };
        let (a, n) = moving.render(&realism, STEP_PX);
        let (b, n4) = moving.render(&realism, STEP_PX / 4.0);
        assert!(n >= 20 && n4 >= 4 * n - 4, "{n} and {n4} instants per row");
        // The edge at the row's own time, plus the blur's mean offset from the acceleration
        // (the mean of ½at² over the window is at·E²/24 beyond its centre value).
        let [top, bottom] = moving.left_corners(&Realism { exposure_s: 0.0, ..realism });
        let z = moving.start.z;
        let curvature = FX / z * 2000.0 * realism.exposure_s.powi(2) / 24.0;
        let near = |y: f64| line_x(top, bottom, y);
        let (ea, eb) = (left_edges(&a, near, 7), left_edges(&b, near, 7));
        let (mut shift, mut centre, mut profile) = (0.0f64, 0.0f64, 0.0f64);
        let contrast = f64::from(PAPER_ALBEDO - INK_ALBEDO);
        for y in 0..H as usize {
            shift = shift.max((ea[y] - eb[y]).abs());
            let expected = moving_edge_x(&moving, &realism, y as f64) + curvature;
            centre = centre.max((eb[y] - expected).abs());
            let row = y * W as usize..(y + 1) * W as usize;
            let diff: f64 =
                a.radiance[row.clone()].iter().zip(&b.radiance[row]).map(|(p, q)| f64::from((p - q).abs())).sum();
            profile = profile.max(diff / contrast);
        }
        eprintln!(
            "{n} vs {n4} instants per row: edge shift ≤ {shift:.5} px, blur profile ≤ {profile:.4} px, \
             edge vs mean of the row's window ≤ {centre:.4} px"
        );
        assert!(shift < 0.01, "edges moved by {shift} px with 4× the instants");
        assert!(profile < 0.05, "the blur profile changed by {profile} px with 4× the instants");
        assert!(centre < 0.02, "an edge is {centre} px from its row's mean position");
    }

    /// The tag's left edge (px) in row `y` at the row's own time: the tag faces the camera
    /// squarely and only translates, so the edge stays vertical in the image.
    fn moving_edge_x(moving: &MovingTag, realism: &Realism, y: f64) -> f64 {
        let c = realism.row_time(0.0, y, H);
        (0..4).filter_map(|i| moving.corner(i, &moving.pose(c))).map(|p| p.x).fold(f64::INFINITY, f64::min)
    }

    /// A smear under a pixel is still drawn (three instants for 0.6 px at quarter-pixel steps,
    /// the global shutter's old rule drew one), the instants are the slices' midpoints, centred
    /// on the frame's time, and the cap and a still scene give what they say.
    #[test]
    fn instants_are_slice_midpoints_a_quarter_pixel_apart() {
        let (c, e) = (1.0, 0.008);
        let t = slice_midpoints(c, e, 0.6, STEP_PX, 64);
        assert_eq!(t.len(), 3, "{t:?}");
        for (i, ti) in t.iter().enumerate() {
            let want = c - e / 2.0 + e * (i as f64 + 0.5) / 3.0;
            assert!((ti - want).abs() < 1e-15, "instant {i}: {ti} for {want}");
        }
        assert!((t.iter().sum::<f64>() / 3.0 - c).abs() < 1e-15, "centred on the frame's time");
        assert_eq!(slice_midpoints(c, e, 0.0, STEP_PX, 64), vec![c], "nothing moves: the centre alone");
        assert_eq!(slice_midpoints(c, 0.0, 5.0, STEP_PX, 64), vec![c], "no exposure: the centre alone");
        assert_eq!(slice_midpoints(c, e, 100.0, STEP_PX, 64).len(), 64, "capped");
        assert_eq!(slice_midpoints(c, e, 1.0, STEP_PX, 0).len(), 1, "a cap of 0 still gives an instant");
    }
}
