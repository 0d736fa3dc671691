//! Where to look next: what the tracker remembers of each marker, its pose extrapolated to
//! the coming frame at constant velocity, the image region its tags will cover, and where each
//! of its tags is expected.

use crate::{Tracker, slot};
use jawtrack_apriltag::{Detection, Expected, ImageView, Roi};
use jawtrack_marker::{BodyKind, Tag};
use jawtrack_pose::{CameraIntrinsics, Pose, RollingShutter, Velocity};
use nalgebra::{Point3, UnitQuaternion};

/// How the tracker searches each frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchConfig {
    /// Search only where the markers are expected once both are tracked; and there, as in the
    /// whole frame searched periodically while both are, try only quads whose longest side is
    /// at least half the smallest tracked tag's, not the quads the tags' data cells make.
    pub region_search: bool,
    /// Search the whole frame at least every this many frames (new tags, a second pair).
    pub full_frame_every: usize,
    /// The expected region grows by this fraction of its larger side on each side.
    pub margin: f64,
    /// … and by at least this many pixels.
    pub min_margin_px: f64,
    /// Find quads in the expected region, and in the whole frame searched periodically while
    /// both bodies are tracked (with `region_search`), on a coarser image (decimated by 4)
    /// when every tag is predicted large enough to be found there with room to spare (70 px,
    /// or 110 px after a frame with a tag blurred more than 2 px); a tag it misses sends the
    /// search to the settings' decimation again. A tag that comes into view is of the size of
    /// the tracked ones.
    pub pyramid: bool,
    /// Before searching the expected region, look for the tags where the predicted poses put
    /// them ([`jawtrack_apriltag::Detector::confirm`]): every tag turned towards the camera
    /// (within 80° of face-on). The frame is taken from them when every tag the bodies were
    /// solved from in the last frame is confirmed; else the region is searched. Frames whose
    /// edges are fitted as motion ramps, or whose tags moved far since the last frame, are
    /// searched, and so is a frame after one with a tag blurred more than 2 px, where a refit
    /// follows its start, and a frame the tone curve is fitted in
    /// ([`jawtrack_apriltag::Detector::tone_fit_due`]), so that the curve is the search's. On
    /// by default: a tracked 1080p frame in about 60 % of the time, and on rendered hinge
    /// openings the jaw as near the truth or nearer (crates/detector-bench/BENCHMARKS.md).
    pub predicted: bool,
}

impl Default for SearchConfig {
    fn default() -> Self {
        SearchConfig {
            region_search: true,
            full_frame_every: 30,
            margin: 0.1,
            min_margin_px: 32.0,
            pyramid: true,
            predicted: true,
        }
    }
}

/// A pose seen at a time (s).
pub type Timed = (f64, Pose);

/// Predicted smear (px) from which a frame's edges are fitted as motion ramps
/// (`DetectorConfig::smeared_edges`): below it an edge stays within the fit's usual window.
pub(crate) const SMEAR_PX: f64 = 3.0;

/// The decimation a region search finds quads at when every tag is predicted large: a quarter
/// of the image stages' pixels of decimating by 2 (on the detector benchmark's 4K frames it is
/// as accurate, `crates/detector-bench/BENCHMARKS.md`).
pub(crate) const COARSE_DECIMATION: f32 = 4.0;
/// … when every tag's shortest side is predicted at least this long (px) after a frame with a
/// tag blurred more than [`MAX_PREDICTED_BLUR_PX`]: twice the smallest sharp tag found at that
/// decimation (49.5 px, `jawtrack-apriltag`'s `tests/detector_geometry.rs`), room for the
/// prediction's error, the tag's turn and the blur. At 70 px, a 4K chew through a 2× crop
/// (8 ms exposure, the mandible's blur 3–6 px) came out at a median of 0.35 mm against 0.12.
pub(crate) const COARSE_MIN_SIDE_PX: f64 = 110.0;
/// … or at least this long after a frame whose tags were all sharper: 1.4 times the smallest
/// found. On a 4K hinge opening (oblique tags 72–78 px, blur under 1.2 px) the region is then
/// searched in two thirds of the time, and the jaw came out nearer the truth (median 0.017
/// against 0.026 mm over 39 frames).
pub(crate) const COARSE_MIN_SIDE_SHARP_PX: f64 = 70.0;

/// A search while both bodies are tracked tries only quads whose longest side is at least
/// this fraction of the smallest tracked tag's longest side. A tag's data cells make quads a
/// few cells across (of its eight); a tag of the markers that turns into view keeps at least
/// 0.7 of its face-on width along its longest side, and the tracked tags have at most theirs.
/// On the 4K hinge, half the quads a tracked region holds are the data cells' (shortest sides
/// 10–50 px, the tags' 70 px and more), and each costs two edge refits and two decodings.
pub(crate) const MIN_QUAD_OF_SMALLEST_TAG: f64 = 0.5;

/// Tags seen within this angle of face-on (°) are looked for where they are predicted
/// ([`SearchConfig::predicted`]): beyond it their cells are too foreshortened to decode.
pub(crate) const MAX_VIEW_DEG: f64 = 80.0;
/// … and tags whose shortest side is predicted at least this long (px).
pub(crate) const MIN_SIDE_PX: f64 = 8.0;
/// A frame whose tags moved farther than this since the last frame (px, at the bodies' last
/// velocity) is searched, not looked for where predicted: on the demo's hinge (36 mm openings
/// in eight frames) the predictions missed, and the tags kept came out worse.
pub(crate) const MAX_PREDICTED_TRAVEL_PX: f64 = 20.0;
/// A frame after one with a tag whose edges were blurred by more than this (σ, px), or whose
/// tags found where predicted hold one, is searched: an edge refit's windows (±3 px) then hold
/// only part of the ramp, and the refit follows where it starts. Predicted quads started 2.3
/// and 4.1 px off were refitted onto the same corners (within 0.04 px) at 1.3–1.6 px of blur
/// (a phone at 200 mm, 1080p), and landed 1.7 and 3.6 px off at 6 px (4K through a 2× crop,
/// focus locked 30 mm behind the markers).
pub(crate) const MAX_PREDICTED_BLUR_PX: f64 = 2.0;

/// Whether any of `tags` is blurred more than [`MAX_PREDICTED_BLUR_PX`].
pub(crate) fn any_blurred<'a>(tags: impl IntoIterator<Item = &'a Detection>) -> bool {
    tags.into_iter().any(|d| d.blur_px.is_some_and(|px| px > MAX_PREDICTED_BLUR_PX))
}
/// Tags seen beyond this angle from face-on (°) are searched for in a box around their
/// prediction rather than refitted from it ([`Expected::search`]).
pub(crate) const SEARCH_BEYOND_DEG: f64 = 60.0;

/// Of a body's `tags`, those turned towards the camera at `camera_from_body` (within
/// [`MAX_VIEW_DEG`] of face-on, [`MIN_SIDE_PX`] long or more), each corner projected through
/// the pose `at_row` gives for the row it falls in (the body's pose when that row was exposed);
/// those beyond [`SEARCH_BEYOND_DEG`] to be searched for.
pub(crate) fn expected_tags(
    tags: &[Tag],
    camera_from_body: &Pose,
    at_row: impl Fn(f64) -> Option<Pose>,
    camera: &CameraIntrinsics,
) -> Vec<Expected> {
    let (facing, steep) = (MAX_VIEW_DEG.to_radians().cos(), SEARCH_BEYOND_DEG.to_radians().cos());
    let mut out = Vec::new();
    for tag in tags {
        let normal = camera_from_body.rotation() * tag.face_normal();
        let centre = camera_from_body.transform_point(&Point3::from(tag.center)).coords;
        let cos_view = -normal.dot(&centre) / centre.norm();
        if cos_view < facing {
            continue;
        }
        if !shortest_side_px(camera_from_body, &tag.corners, camera).is_some_and(|s| s >= MIN_SIDE_PX) {
            continue;
        }
        let corner = |c: &nalgebra::Vector3<f64>| {
            let first = camera.project(&camera_from_body.transform_point(&Point3::from(*c)))?;
            let px = camera.project(&at_row(first.y)?.transform_point(&Point3::from(*c)))?;
            Some([px.x, px.y])
        };
        if let [Some(a), Some(b), Some(c), Some(d)] = tag.corners.each_ref().map(corner) {
            out.push(Expected { id: tag.id, corners: [a, b, c, d], search: cos_view < steep });
        }
    }
    out
}

/// The shortest side (px) of the tag whose corners (body frame) are `corners`, seen through
/// `camera_from_body`; `None` when a corner does not project.
pub(crate) fn shortest_side_px(
    camera_from_body: &Pose,
    corners: &[nalgebra::Vector3<f64>; 4],
    camera: &CameraIntrinsics,
) -> Option<f64> {
    Some(sides_px(camera_from_body, corners, camera)?.into_iter().fold(f64::INFINITY, f64::min))
}

/// The four sides' lengths (px) of the tag whose corners (body frame) are `corners`, seen
/// through `camera_from_body`; `None` when a corner does not project.
fn sides_px(
    camera_from_body: &Pose,
    corners: &[nalgebra::Vector3<f64>; 4],
    camera: &CameraIntrinsics,
) -> Option<[f64; 4]> {
    let mut px = [nalgebra::Point2::origin(); 4];
    for (p, c) in px.iter_mut().zip(corners) {
        *p = camera.project(&camera_from_body.transform_point(&Point3::from(*c)))?;
    }
    Some([0, 1, 2, 3].map(|i| (px[(i + 1) % 4] - px[i]).norm()))
}

/// `last` moved on to time `t` with the velocity it had since `previous`: the body's origin
/// at constant linear velocity, its orientation at constant angular velocity. `last` itself
/// when the times do not allow it.
pub fn extrapolate(previous: Option<&Timed>, last: &Timed, t: f64) -> Pose {
    let Some((t0, p0)) = previous else { return last.1 };
    let (t1, p1) = last;
    let span = t1 - t0;
    let ahead = t - t1;
    if !(span > 0.0 && ahead >= 0.0 && span.is_finite() && ahead.is_finite()) {
        return *p1;
    }
    let k = ahead / span;
    let turn = p1.rotation() * p0.rotation().inverse();
    let rotation = UnitQuaternion::from_scaled_axis(turn.scaled_axis() * k) * p1.rotation();
    let translation = p1.translation() + (p1.translation() - p0.translation()) * k;
    Pose::from_parts(rotation, translation)
}

/// What the tracker remembers of one body.
#[derive(Debug, Clone, Default)]
pub(crate) struct BodyState {
    /// The last two times and poses it was solved, newest last.
    pub(crate) history: Vec<Timed>,
    /// Under a rolling shutter, the last three poses solved from the corners of two tags or more
    /// as seen (not carried to the frame's time), newest last: what its velocity is taken from.
    pub(crate) seen: Vec<Timed>,
    /// The tags used the last time it was solved in the frame before.
    pub(crate) tags: Vec<u32>,
}

impl BodyState {
    pub(crate) fn last(&self) -> Option<&Timed> {
        self.history.last()
    }

    pub(crate) fn remember(&mut self, t: f64, pose: Pose, seen: Option<Pose>, tags: &[u32]) {
        self.history.push((t, pose));
        if self.history.len() > 2 {
            self.history.remove(0);
        }
        match seen {
            // A lone tag holds the body's depth and turn too loosely to take a velocity from
            // (one such pose put the next frame's chewing jaw 0.19 mm off): the poses around it serve.
            Some(_) if tags.len() < 2 => {}
            Some(p) => self.seen.push((t, p)),
            None => self.seen.clear(),
        }
        if self.seen.len() > 3 {
            self.seen.remove(0);
        }
        self.tags = tags.to_vec();
    }

    /// How far (px) its tags should move across the image during `exposure_s` at the velocity
    /// of its last two poses (0 without two): its origin's motion off the line of sight plus
    /// its turn at `reach_mm`, how far its tags lie from the origin.
    pub(crate) fn smear_px(&self, camera: &CameraIntrinsics, exposure_s: f64, reach_mm: f64) -> f64 {
        let (Some(&(_, pose)), Some(v)) = (self.last(), Velocity::at_newest(&self.history)) else { return 0.0 };
        let z = pose.translation().z;
        if !(v.is_finite() && z > 0.0) {
            return 0.0;
        }
        let across = v.linear.xy().norm() + v.angular.norm() * reach_mm;
        camera.fx.max(camera.fy) * across / z * exposure_s
    }

    /// Its velocity at `t`, where it is at `pose`: from its last poses before `t` and that one
    /// (`None` without an earlier pose).
    pub(crate) fn velocity_at(&self, t: f64, pose: Pose) -> Option<Velocity> {
        let mut timed: Vec<Timed> = self.history.iter().filter(|(s, _)| *s < t).copied().collect();
        timed.push((t, pose));
        Velocity::at(&timed, t)
    }

    /// The pose expected at `t`.
    pub(crate) fn predict(&self, t: f64) -> Option<Pose> {
        let last = self.last()?;
        let previous = (self.history.len() == 2).then(|| &self.history[0]);
        Some(extrapolate(previous, last, t))
    }
}

/// The box around `points` (body frame) seen through `camera_from_body`, grown by `margin`
/// (a fraction of its larger side) and at least `min_margin_px` on each side, clipped to the
/// frame. `None` when a point is behind the camera or the box misses the frame.
pub fn region(
    groups: &[(&Pose, &[Point3<f64>])],
    camera: &CameraIntrinsics,
    width: usize,
    height: usize,
    margin: f64,
    min_margin_px: f64,
) -> Option<Roi> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for (camera_from_body, points) in groups {
        for p in points.iter() {
            let px = camera.project(&camera_from_body.transform_point(p))?;
            lo = [lo[0].min(px.x), lo[1].min(px.y)];
            hi = [hi[0].max(px.x), hi[1].max(px.y)];
        }
    }
    if !(lo[0].is_finite() && hi[0].is_finite() && lo[1].is_finite() && hi[1].is_finite()) {
        return None;
    }
    let grow = (margin * (hi[0] - lo[0]).max(hi[1] - lo[1])).max(min_margin_px);
    let x0 = (lo[0] - grow).floor().max(0.0);
    let y0 = (lo[1] - grow).floor().max(0.0);
    let x1 = (hi[0] + grow).ceil().min(width as f64 - 1.0);
    let y1 = (hi[1] + grow).ceil().min(height as f64 - 1.0);
    if x1 <= x0 || y1 <= y0 {
        return None;
    }
    Some(Roi { x: x0 as usize, y: y0 as usize, width: (x1 - x0) as usize + 1, height: (y1 - y0) as usize + 1 })
}

/// Whether a corner lies within `distance` (px) of an edge of `roi` that is not the frame's.
pub(crate) fn near_inner_edge(corners: &[[f64; 2]; 4], roi: &Roi, frame: &ImageView<'_>, distance: f64) -> bool {
    let (x0, y0) = (roi.x as f64, roi.y as f64);
    let (x1, y1) = ((roi.x + roi.width) as f64 - 1.0, (roi.y + roi.height) as f64 - 1.0);
    corners.iter().any(|c| {
        (roi.x > 0 && c[0] - x0 < distance)
            || (roi.y > 0 && c[1] - y0 < distance)
            || (roi.x + roi.width < frame.width() && x1 - c[0] < distance)
            || (roi.y + roi.height < frame.height() && y1 - c[1] < distance)
    })
}

/// Where the tracker looks in the coming frame.
impl Tracker {
    /// Where both markers are expected, when both are tracked and a full search is not due.
    pub(crate) fn expected_region(&self, frame: &ImageView<'_>, camera: &CameraIntrinsics, t: f64) -> Option<Roi> {
        let s = &self.config.search;
        if !s.region_search || self.since_full + 1 >= s.full_frame_every || !self.both_tracked(t) {
            return None;
        }
        let poses = [self.bodies[0].predict(t)?, self.bodies[1].predict(t)?];
        let groups = [(&poses[0], self.corners[0].as_slice()), (&poses[1], self.corners[1].as_slice())];
        region(&groups, camera, frame.width(), frame.height(), s.margin, s.min_margin_px)
    }

    /// Whether both bodies were solved recently enough to go by at `t`, each from tags.
    pub(crate) fn both_tracked(&self, t: f64) -> bool {
        self.bodies.iter().all(|b| b.last().is_some_and(|l| self.recent(l.0, t)) && !b.tags.is_empty())
    }

    /// The tags the bodies' predicted poses turn towards the camera at `t`, each corner where
    /// its own row sees it under the rolling shutter ([`expected_tags`]).
    pub(crate) fn expected_tags_at(&self, frame: &ImageView<'_>, camera: &CameraIntrinsics, t: f64) -> Vec<Expected> {
        let rows = frame.height();
        let shutter = RollingShutter::new(self.config.readout_s, rows).unwrap_or_else(|_| RollingShutter::global());
        let mut out = Vec::new();
        for kind in BodyKind::ALL {
            let (Some(body), state) = (self.marker.body(kind), &self.bodies[slot(kind)]) else { continue };
            let Some(pose) = state.predict(t) else { continue };
            let at_row = |row: f64| state.predict(t + shutter.offset_s(row));
            out.extend(expected_tags(&body.tags, &pose, at_row, camera));
        }
        out
    }

    /// How a search while the bodies are tracked finds quads, judged by the tags the bodies
    /// were solved from in the last frame, predicted at `t`: at the coarser decimation
    /// ([`COARSE_DECIMATION`]) when every such tag's shortest side is at least
    /// [`COARSE_MIN_SIDE_SHARP_PX`] ([`COARSE_MIN_SIDE_PX`] after a frame with a tag blurred
    /// more than [`MAX_PREDICTED_BLUR_PX`]) and the settings' decimation is finer; trying only
    /// the quads whose longest side is at least [`MIN_QUAD_OF_SMALLEST_TAG`] of the smallest
    /// longest side among those tags ([`jawtrack_apriltag::Search::min_quad_px`]). `(None,
    /// 0.0)`, the settings' decimation and every quad, when a tag cannot be predicted.
    pub(crate) fn tracked_search(&self, camera: &CameraIntrinsics, t: f64) -> (Option<f32>, f64) {
        let Some((shortest, longest)) = self.smallest_sides(camera, t) else { return (None, 0.0) };
        let min_side = if self.blurred { COARSE_MIN_SIDE_PX } else { COARSE_MIN_SIDE_SHARP_PX };
        let coarse = self.config.search.pyramid
            && self.config.detector.quad_decimate < COARSE_DECIMATION
            && shortest >= min_side;
        (coarse.then_some(COARSE_DECIMATION), MIN_QUAD_OF_SMALLEST_TAG * longest)
    }

    /// The smallest shortest side and the smallest longest side (px) among the tags the
    /// bodies were solved from in the last frame, predicted at `t`; `None` when there are
    /// none or one cannot be predicted.
    fn smallest_sides(&self, camera: &CameraIntrinsics, t: f64) -> Option<(f64, f64)> {
        let (mut shortest, mut longest) = (f64::INFINITY, f64::INFINITY);
        for b in &self.bodies {
            let pose = b.predict(t)?;
            for &id in &b.tags {
                let (_, tag) = self.marker.find_tag(id)?;
                let sides = sides_px(&pose, &tag.corners, camera)?;
                shortest = shortest.min(sides.into_iter().fold(f64::INFINITY, f64::min));
                longest = longest.min(sides.into_iter().fold(0.0, f64::max));
            }
        }
        shortest.is_finite().then_some((shortest, longest))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn the_smear_is_the_motion_across_the_image_during_the_exposure() {
        let camera = CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5);
        let at =
            |x: f64, z: f64, turn: f64| Pose::from_axis_angle(Vector3::new(turn, 0.0, 0.0), Vector3::new(x, 0.0, z));
        let mut body = BodyState::default();
        body.remember(0.0, at(0.0, 120.0, 0.0), None, &[]);
        assert_eq!(body.smear_px(&camera, 1.0 / 120.0, 18.0), 0.0, "one pose: no velocity");
        body.remember(1.0 / 60.0, at(0.0, 120.0, 0.0), None, &[]);
        assert_eq!(body.smear_px(&camera, 1.0 / 120.0, 18.0), 0.0, "still");
        // 120 mm/s across, now at 119 mm: 1500 × 120 / 119 px/s; the 60 mm/s toward the
        // camera adds nothing.
        body.remember(2.0 / 60.0, at(2.0, 119.0, 0.0), None, &[]);
        let px_s = 1500.0 * 120.0 / 119.0;
        assert!((body.smear_px(&camera, 1.0 / 120.0, 18.0) - px_s / 120.0).abs() < 1e-6);
        assert!((body.smear_px(&camera, 0.002, 18.0) - px_s * 0.002).abs() < 1e-6);
        // Turning at 1 rad/s moves tags 18 mm out at 18 mm/s: 225 px/s.
        let mut turning = BodyState::default();
        turning.remember(0.0, at(0.0, 120.0, 0.0), None, &[]);
        turning.remember(0.1, at(0.0, 120.0, 0.1), None, &[]);
        assert!((turning.smear_px(&camera, 0.01, 18.0) - 2.25).abs() < 1e-6);
    }

    #[test]
    fn constant_velocity_is_continued() {
        let p = |t: f64| Pose::from_axis_angle(Vector3::new(0.0, 0.3 * t, 0.1 * t), Vector3::new(5.0 * t, 0.0, 100.0));
        let got = extrapolate(Some(&(0.5, p(0.5))), &(1.0, p(1.0)), 2.0);
        let (angle, dist) = got.distance_to(&p(2.0));
        assert!(angle < 1e-12 && dist < 1e-12, "{angle} rad {dist} mm");
        // Without a history, or with time standing still, the last pose is kept.
        assert_eq!(extrapolate(None, &(1.0, p(1.0)), 2.0), p(1.0));
        assert_eq!(extrapolate(Some(&(1.0, p(0.0))), &(1.0, p(1.0)), 2.0), p(1.0));
    }

    #[test]
    fn region_covers_the_projected_points_with_a_margin() {
        let camera = CameraIntrinsics::pinhole(1000.0, 1000.0, 959.5, 539.5);
        let pose = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 0.0, 100.0));
        let pts = [Point3::new(-10.0, -5.0, 0.0), Point3::new(10.0, 5.0, 0.0)];
        let r = region(&[(&pose, &pts)], &camera, 1920, 1080, 0.25, 10.0).expect("in view");
        // Points at x 859.5..1059.5, y 489.5..589.5; grown by 50 px.
        assert_eq!((r.x, r.y, r.width, r.height), (809, 439, 302, 202));
        // Clipped at the frame's edge.
        let left = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(-95.0, 0.0, 100.0));
        let r = region(&[(&left, &pts)], &camera, 1920, 1080, 0.25, 10.0).expect("partly in view");
        assert_eq!(r.x, 0);
        // Behind the camera: no region.
        let behind = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 0.0, -100.0));
        assert!(region(&[(&behind, &pts)], &camera, 1920, 1080, 0.25, 10.0).is_none());
    }
}
