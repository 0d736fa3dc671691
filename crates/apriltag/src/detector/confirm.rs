//! Tags confirmed where a tracker predicts them: the per-quad work of a detection (edge refit,
//! decoding, border fit) on quads projected from the markers' predicted poses, without the
//! image stages that find quads (decimation, threshold, regions, clusters, quad fitting), which
//! are half of a tracked frame's time.

use super::edges::refine_edges;
use super::per_quad::finish;
use super::stages::StageTimes;
use super::{Detection, Detector, Search, longest_side_of};
use crate::DetectError;
use crate::config::Roi;
use crate::image::ImageView;
use crate::quads::Quad;
use crate::workers::Workers;
use std::time::Instant;

/// A tag a tracker expects in a frame: its id, and its corners where the tracker predicts
/// them, in the order and pixel convention of [`Detection::corners`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Expected {
    /// Id in the detector's family.
    pub id: u32,
    /// Predicted corners (px).
    pub corners: [[f64; 2]; 4],
    /// Find it by the image stages in a small box around the prediction rather than by
    /// refitting the predicted quad: for a tag seen steeply. On a hinge opening at 1080p the
    /// refitted quads of tags seen within 60° of face-on came out nearer the truth than the
    /// search's (corners 0.026 / 0.022 px against 0.029 / 0.028 px under 40° / 40–60°), those
    /// seen beyond it farther (0.102 against 0.084 px), however the first refit reached.
    pub search: bool,
}

/// How far (px) a predicted side may lie from the image's: the first edge refit of a predicted
/// quad reaches as far as one found at this decimation (its window's centre within
/// `decimate + 1` px of the side, C's reach), the second as far as the settings' decimation.
const PULL_IN_DECIMATE: f32 = 3.0;

/// A refitted quad whose side is longer or shorter than predicted by this fraction or more is
/// not taken: half a cell of tag36h11's eight (the prediction's own error in a side's length is
/// a few per cent at most).
const SIDE_CHANGE: f64 = 1.0 / 16.0;

/// A refitted side may lie this far (px) from its predicted corners: the first refit's windows
/// are centred within `PULL_IN_DECIMATE + 1` px of the predicted side. A side moved farther was
/// predicted beyond that reach, and the others, predicted as far off, may have stopped short:
/// in the static fixture, whose frames jump 20 mm in depth, a tag predicted 8–10 px off had
/// one side stop 5 px short while the others moved 10 px; its quad still decoded, a twentieth
/// short, and put the jaw 0.14 mm further off.
const SIDE_MOVE_PX: f64 = PULL_IN_DECIMATE as f64 + 1.0;

/// The box searched for a tag tries only the quads whose longest side is at least this share of
/// the tag's predicted longest side ([`Search::min_quad_px`]): a tag turning into view keeps at
/// least 0.7 of its face-on width along its longest side, and the prediction's own error in a
/// side is a few per cent, while the quads a tag's data cells make are a few cells of its
/// eight across. The tracker's region search passes them over by the same rule.
const MIN_QUAD_OF_PREDICTED: f64 = 0.5;

/// The box searched around a tag predicted for searching ([`Expected::search`]), or whose
/// refitted quad did not hold it, reaches this far beyond its predicted corners (px) …
const BOX_MARGIN_PX: f64 = 24.0;
/// … or this fraction of the box's larger side, if more: the quiet zone and the edge refit's
/// windows, and the prediction's error.
const BOX_MARGIN: f64 = 0.25;

impl Detector {
    /// The `expected` tags that are where a tracker predicts them. Each predicted quad's edges
    /// are refitted twice (first reaching 4 px; then as a quad found at the settings'
    /// decimation), decoded, and kept when it decodes as its own id with its sides' lengths
    /// within a sixteenth of the predicted ones and none moved more than 4 px (the first
    /// refit's reach); a tag to be searched
    /// ([`Expected::search`]), or whose quad was not kept, is looked for in a box around its
    /// prediction as [`Detector::search`] looks in a region, among the quads at least half its
    /// predicted size. Then the border fit, as
    /// [`Detector::search`] does. A tag predicted off by more than the box's margin, hidden,
    /// or turned away is missing from the result: a tracker searches again
    /// ([`Detector::search`]) when a tag it needs is missing. Tags predicted with a corner
    /// outside the frame are not tried. The tone curve is estimated as in
    /// [`Detector::detect_in_with`]; `smeared` as in [`crate::Search`].
    ///
    /// # Examples
    ///
    /// ```
    /// use jawtrack_apriltag::{Detector, DetectorConfig, Expected, ImageView};
    ///
    /// let detector = Detector::new(DetectorConfig::default()).expect("valid settings");
    /// let frame = vec![128u8; 640 * 480];
    /// let view = ImageView::new(&frame, 640, 480, 640).expect("a frame");
    /// let corners = [[300.0, 260.0], [340.0, 260.0], [340.0, 220.0], [300.0, 220.0]];
    /// let tag = Expected { id: 3, corners, search: false };
    /// // A grey frame holds no tag where one was predicted.
    /// assert!(detector.confirm(&view, &[tag], false).expect("tried").is_empty());
    /// ```
    pub fn confirm(
        &self,
        frame: &ImageView<'_>,
        expected: &[Expected],
        smeared: bool,
    ) -> Result<Vec<Detection>, DetectError> {
        let (w, h) = (frame.width() as f64, frame.height() as f64);
        let inside = |e: &&Expected| {
            e.corners.iter().all(|p| {
                p[0].is_finite() && p[1].is_finite() && (0.0..w - 1.0).contains(&p[0]) && (0.0..h - 1.0).contains(&p[1])
            })
        };
        // C's pixel convention, as the quads the image stages find, and their order: the
        // corners at tag coordinates (−1,−1), (1,−1), (1,1), (−1,1), where a detection lists
        // (−1,1), (1,1), (1,−1), (−1,−1).
        let mut jobs: Vec<Job> = expected
            .iter()
            .filter(inside)
            .map(|e| {
                let c = |i: usize| [(e.corners[i][0] + 0.5) as f32, (e.corners[i][1] + 0.5) as f32];
                let quad = (!e.search).then(|| Quad { p: [c(3), c(2), c(1), c(0)] });
                Job { expected: *e, quad, around: around(e, frame) }
            })
            .collect();
        // The boxes to search first: each costs several refits, and a thread left with one at
        // the end keeps the other waiting. The tags are sorted by id at the end.
        jobs.sort_by_key(|j| j.quad.is_some());
        // Each box searched on one thread: the image stages of a box a few dozen pixels
        // across cost less than sharing them out.
        let serial = Workers::new(1);
        self.with_tone(frame, |lut| {
            let c = &self.config;
            let cells = c.family.width_at_border as f64;
            let done = self.workers.map_each(&jobs, |job| {
                let mut st = StageTimes::default();
                if let Some(q0) = job.quad {
                    let start = Instant::now();
                    let mut q = q0;
                    if c.refine_edges {
                        let ramps = c.linear_edges && smeared;
                        refine_edges(frame, &mut q, PULL_IN_DECIMATE, lut, c.linear_edges, ramps, cells);
                    }
                    let d = self.tag_from_quad(frame, &q, c.quad_decimate, lut, smeared);
                    let found = finish(d.into_iter().collect()).into_iter().find(|d| job.holds(d));
                    st = StageTimes { tags_s: start.elapsed().as_secs_f64(), quads: 1, ..st };
                    if found.is_some() {
                        return Ok((found, st));
                    }
                }
                let search = Search {
                    roi: Some(job.around),
                    smeared,
                    quad_decimate: c.quad_decimate,
                    min_quad_px: MIN_QUAD_OF_PREDICTED * longest_side_of(&job.expected.corners),
                };
                let (found, searched) = self.detect_region(frame, &search, lut, &serial)?;
                Ok((found.into_iter().find(|d| d.id == job.expected.id), st + searched))
            });
            let (mut dets, mut st) = (Vec::new(), StageTimes::default());
            for job in done {
                let (found, stages) = job?;
                dets.extend(found);
                st = st + stages;
            }
            dets.sort_by_key(|d| d.id);
            st.predicted = jobs.len();
            st.tags = dets.len();
            st.quad_decimate = if st.clusters > 0 { c.quad_decimate } else { 0.0 };
            *self.stages.lock().unwrap_or_else(|p| p.into_inner()) = st;
            Ok(dets)
        })
    }
}

/// How one expected tag is looked for: its predicted quad refitted (`quad`, C's pixel
/// convention), and where that is not asked for or does not hold the tag, the box `around` it
/// searched.
struct Job {
    expected: Expected,
    quad: Option<Quad>,
    around: Roi,
}

impl Job {
    /// Whether `d` (JawTrack's pixel convention) is the expected tag, its sides within
    /// [`SIDE_CHANGE`] of the predicted sides' lengths (a quad pulled onto the next edge in or
    /// out, the data cells' or the quiet zone's, still decodes, a cell short or long) and each
    /// within [`SIDE_MOVE_PX`] of the predicted side.
    fn holds(&self, d: &Detection) -> bool {
        let p = &self.expected.corners;
        let side = |c: &[[f64; 2]; 4], i: usize| (c[(i + 1) % 4][0] - c[i][0]).hypot(c[(i + 1) % 4][1] - c[i][1]);
        // The distance of predicted corner `j` from the line through `d`'s side `i`.
        let off = |i: usize, j: usize| {
            let (a, b) = (d.corners[i], d.corners[(i + 1) % 4]);
            ((b[0] - a[0]) * (p[j][1] - a[1]) - (b[1] - a[1]) * (p[j][0] - a[0])).abs() / side(&d.corners, i)
        };
        d.id == self.expected.id
            && (0..4).all(|i| {
                (side(&d.corners, i) / side(p, i) - 1.0).abs() < SIDE_CHANGE
                    && off(i, i) <= SIDE_MOVE_PX
                    && off(i, (i + 1) % 4) <= SIDE_MOVE_PX
            })
    }
}

/// The box around `e`'s predicted corners that a search for it looks in, within `frame`.
fn around(e: &Expected, frame: &ImageView<'_>) -> Roi {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &e.corners {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    let grow = BOX_MARGIN_PX.max(BOX_MARGIN * (hi[0] - lo[0]).max(hi[1] - lo[1]));
    let (x0, y0) = ((lo[0] - grow).floor().max(0.0) as usize, (lo[1] - grow).floor().max(0.0) as usize);
    let x1 = ((hi[0] + grow).ceil() as usize).min(frame.width() - 1);
    let y1 = ((hi[1] + grow).ceil() as usize).min(frame.height() - 1);
    Roi { x: x0, y: y0, width: x1 - x0 + 1, height: y1 - y0 + 1 }
}

#[cfg(test)]
mod tests {
    use super::{Expected, around};
    use crate::detector::border::tests::drawn_through;
    use crate::{Detection, Detector, DetectorConfig, ImageView, Search, ToneCurve};

    /// A predicted quad a few pixels off is pulled onto the tag and reads as the search reads
    /// it; one five or more pixels off, or one asked to be searched, is found in the box around
    /// it; a prediction of another id, or leaving the frame, finds nothing.
    #[test]
    fn a_predicted_tag_is_found_as_the_search_finds_it() {
        let (img, n, _) = drawn_through(7, 7.0, 12.0, 1.0, 0.8, 1.0, ToneCurve::Srgb);
        let view = ImageView::new(&img, n, n, n).expect("view");
        let detector = Detector::new(DetectorConfig::default()).expect("valid");
        let [found] = detector.detect(&view).expect("runs")[..] else { panic!("one tag") };
        let worst = |d: &Detection| {
            d.corners.iter().zip(&found.corners).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max)
        };
        let moved = |dx: f64, dy: f64, turn_deg: f64, scale: f64| {
            let (s, c) = turn_deg.to_radians().sin_cos();
            found.corners.map(|p| {
                let (x, y) = ((p[0] - found.center[0]) * scale, (p[1] - found.center[1]) * scale);
                [found.center[0] + c * x - s * y + dx, found.center[1] + s * x + c * y + dy]
            })
        };
        let mut checked = 0;
        for (dx, dy, turn, scale) in
            [(0.0, 0.0, 0.0, 1.0), (1.5, -1.0, 0.0, 1.0), (-2.5, 2.0, 1.0, 1.0), (0.8, 0.3, -1.5, 1.03)]
        {
            let expected = Expected { id: 7, corners: moved(dx, dy, turn, scale), search: false };
            let [got] = detector.confirm(&view, &[expected], false).expect("runs")[..] else {
                panic!("predicted ({dx}, {dy}) px, {turn}°, ×{scale}: one tag")
            };
            let off = worst(&got);
            assert!(
                got.id == 7 && off < 0.01,
                "predicted ({dx}, {dy}) px, {turn}°: corners {off} px from the search's"
            );
            assert_eq!(got.blur_px.is_some(), found.blur_px.is_some());
            checked += 1;
        }
        assert_eq!(checked, 4);
        let stages = detector.last_stages();
        assert_eq!((stages.predicted, stages.quads, stages.tags, stages.clusters), (1, 1, 1, 0));
        let other = Expected { id: 8, corners: found.corners, search: false };
        assert!(detector.confirm(&view, &[other], false).expect("runs").is_empty(), "another id");
        // Five or eight pixels off, beyond the first refit's reach: eight pixels off it stops
        // half a pixel short on one side and the quad still decodes; the box is searched.
        for dx in [5.0, 8.0] {
            let e = Expected { id: 7, corners: moved(dx, 0.0, 0.0, 1.0), search: false };
            let [got] = detector.confirm(&view, &[e], false).expect("runs")[..] else { panic!("{dx} px off: one tag") };
            assert!(worst(&got) < 0.05, "{dx} px off: corners {} px from the search's", worst(&got));
            assert!(detector.last_stages().clusters > 0, "{dx} px off: found by the image stages");
        }
        // Nine pixels off, the refit takes the next edge or none: the box around it is searched.
        let far = Expected { id: 7, corners: moved(9.0, 0.0, 0.0, 1.0), search: false };
        let [got] = detector.confirm(&view, &[far], false).expect("runs")[..] else { panic!("far: one tag") };
        assert!(worst(&got) < 0.05, "far: corners {} px from the whole frame's", worst(&got));
        assert!(detector.last_stages().clusters > 0, "found by the image stages");
        let searched = Expected { id: 7, corners: moved(2.0, -1.5, 1.0, 1.0), search: true };
        let [got] = detector.confirm(&view, &[searched], false).expect("runs")[..] else { panic!("searched: one tag") };
        assert!(worst(&got) < 0.05, "searched around: corners {} px from the whole frame's", worst(&got));
        assert!(detector.last_stages().clusters > 0, "found by the image stages");
        let outside = Expected { id: 7, corners: moved(-found.center[0] - 5.0, 0.0, 0.0, 1.0), search: false };
        assert!(detector.confirm(&view, &[outside], false).expect("runs").is_empty());
        assert_eq!(detector.last_stages().quads, 0, "a quad leaving the frame is not tried");
    }

    /// A box searched for a predicted tag passes over the quads its data cells make (tag 0's
    /// make one at 12 px cells), and finds the tag as the same box searched with every quad
    /// tried. Run with C's edge fit, which tries the quads a decoded tag holds, so that only
    /// the floor passes them over.
    #[test]
    fn a_box_searched_for_a_tag_tries_no_quad_under_half_its_size() {
        let (img, n, _) = drawn_through(0, 12.0, 12.0, 1.0, 0.8, 1.0, ToneCurve::Srgb);
        let view = ImageView::new(&img, n, n, n).expect("view");
        let config = DetectorConfig { linear_edges: false, ..DetectorConfig::default() };
        let detector = Detector::new(config).expect("valid");
        let [found] = detector.detect(&view).expect("runs")[..] else { panic!("one tag") };
        let expected = Expected { id: 0, corners: found.corners, search: true };
        let [boxed] = detector.confirm(&view, &[expected], false).expect("runs")[..] else { panic!("boxed: one tag") };
        let tried = detector.last_stages().quads;
        let every =
            Search { roi: Some(around(&expected, &view)), smeared: false, quad_decimate: 2.0, min_quad_px: 0.0 };
        let all = detector.search(&view, &every).expect("runs");
        let all_tried = detector.last_stages().quads;
        assert_eq!(tried, 1, "the tag's quad only");
        assert!(all_tried > tried, "the data cells make quads of their own: {all_tried} tried");
        assert_eq!(all.iter().filter(|d| d.id == 0).collect::<Vec<_>>(), [&boxed]);
    }
}
