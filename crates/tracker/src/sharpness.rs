//! How sharp the tracker sees each marker, and what follows: a tag seen nearly edge-on is left
//! out while its body has others ([`THIN_CELL_PX`], [`THIN_RATIO`]); each body's edge blur is
//! the median of its tags' (the detector's `Detection::blur_px`) and is judged against their cells' width; a body
//! blurred beyond [`DEFOCUSED_BLUR_PER_CELL`] of a cell is flagged `defocused` and the frame
//! gives no jaw pose.
//!
//! Why against the cell: a blur spreads each edge into its neighbours one cell away, and the
//! pose's error follows from that overlap, not from the blur's pixels (a 2 px blur is nothing on
//! a 4K frame's 30 px cells and ruins a 1080p frame's 7 px ones). For a lens focused at d, a
//! marker at z is blurred (σ over the cell) by 2·A·|z − d| / ((d − f)·tag), whatever the zoom.

use crate::{BodyResult, Flag};
use jawtrack_apriltag::Detection;
use jawtrack_marker::BodyKind;
use jawtrack_pose::median;

/// The default [`crate::TrackerConfig::max_blur_per_cell`], from renders with a phone's optics
/// (`docs/accuracy.md`, "Capture"): markers in focus measure 0.02–0.10 of a cell (the most while
/// chewing at 8 ms, motion taken out) and keep the jaw within 0.03 mm median; a phone at 250 mm
/// focused at 200 mm blurs them 0.16 of a cell and puts the jaw 0.07–0.17 mm off (median), and
/// nearer than the lens focuses they blur 0.25–0.37 of a cell, millimetres off unflagged.
pub const DEFOCUSED_BLUR_PER_CELL: f64 = 0.14;

/// A tag whose cells are narrower than this (px, across its shortest side) is seen too
/// steeply or too small to place its corners: its border and its data cells blur into one
/// another (at 200 mm on a 1080p phone frame, a tag seen 83° from face-on has cells of 1 px
/// across and its corners land up to 1.25 px off, moving the jaw 0.19 mm) …
pub const THIN_CELL_PX: f64 = 2.0;
/// … and so is one whose shortest side is under this fraction of its longest (seen more than
/// about 73° from face-on), however many pixels: at 220 mm on the 2× crop the maxilla's tag seen
/// at 83° has cells of 3.5 px across and its corners land 0.6–0.8 px off, enough to flicker in
/// and out of the pose (`docs/accuracy.md`, "Capture").
pub const THIN_RATIO: f64 = 0.22;

/// Whether a detected tag is seen too edge-on to use while its body has others
/// ([`THIN_CELL_PX`], [`THIN_RATIO`]).
pub(crate) fn thin(d: &Detection, cells: f64) -> bool {
    let sides = sides_px(d);
    let (short, long) = sides.iter().fold((f64::INFINITY, 0.0f64), |(s, l), &v| (s.min(v), l.max(v)));
    short / cells < THIN_CELL_PX || short < THIN_RATIO * long
}

/// The lengths (px) of a detected tag's four sides.
fn sides_px(d: &Detection) -> [f64; 4] {
    let c = &d.corners;
    std::array::from_fn(|i| (c[i][0] - c[(i + 1) % 4][0]).hypot(c[i][1] - c[(i + 1) % 4][1]))
}

/// The width (px) of a detected tag's cells along its longest side, `cells` across its border.
fn longest_cell_px(d: &Detection, cells: f64) -> f64 {
    sides_px(d).into_iter().fold(0.0, f64::max) / cells
}

/// The lens's blur (σ, px) in a tag's measured blur `sigma_px` when the motion predicted over
/// the exposure smears it `smear_px`: a smear of length L along a side's normal adds L²/12 to its
/// σ², and of the two perpendicular sides (or the sharper two of four) the sharper has at most
/// L²/24 of it, what diagonal motion puts on both; so that much is taken out.
pub fn lens_blur(sigma_px: f64, smear_px: f64) -> f64 {
    (sigma_px * sigma_px - smear_px * smear_px / 24.0).max(0.0).sqrt()
}

/// Sets each solved body's blur (the lens's: its tags' median, less the motion `smears_px` it
/// was predicted to smear over the exposure) and cell width from the detections its pose used,
/// flags those blurred beyond `max_blur_per_cell` of a cell `defocused`, and says whether any
/// was.
pub(crate) fn judge(
    bodies: &mut [Option<BodyResult>; 2],
    detections: &[Detection],
    smears_px: [f64; 2],
    max_blur_per_cell: f64,
    cells: f64,
    flags: &mut Vec<Flag>,
) -> bool {
    let mut defocused = false;
    for ((kind, body), smear) in BodyKind::ALL.iter().zip(bodies.iter_mut()).zip(smears_px) {
        let Some(b) = body else { continue };
        let used: Vec<&Detection> = detections.iter().filter(|d| b.tags.contains(&d.id)).collect();
        b.blur_px = median(used.iter().filter_map(|d| d.blur_px)).map(|blur| lens_blur(blur, smear));
        b.cell_px = median(used.iter().map(|d| longest_cell_px(d, cells))).unwrap_or(0.0);
        if b.defocused(max_blur_per_cell) {
            flags.push(Flag::Defocused(*kind));
            defocused = true;
        }
    }
    defocused
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Tracker, TrackerConfig};
    use jawtrack_marker::Marker;
    use jawtrack_pose::Pose;
    use nalgebra::Matrix6;

    /// A detection of `id` whose quad is `w` × `h` px at (100, 100).
    fn quad(id: u32, w: f64, h: f64) -> Detection {
        let corners = [[100.0, 100.0 + h], [100.0 + w, 100.0 + h], [100.0 + w, 100.0], [100.0, 100.0]];
        let center = [100.0 + w / 2.0, 100.0 + h / 2.0];
        Detection { id, hamming: 0, decision_margin: 50.0, center, corners, homography: [0.0; 9], blur_px: None }
    }

    #[test]
    fn a_tag_seen_edge_on_is_left_out_while_two_others_remain() {
        let tracker = Tracker::new(Marker::default(), TrackerConfig::default()).expect("valid");
        let tags = |d: &[Detection]| {
            let mut ids: Vec<u32> = tracker.observations(BodyKind::Maxilla, d).iter().map(|o| o.tag).collect();
            ids.dedup();
            ids
        };
        // Tag 2's cells are 1 px across (an 8 px short side): seen at ~83°.
        let seen = [quad(0, 60.0, 60.0), quad(1, 60.0, 40.0), quad(2, 60.0, 8.0), quad(12, 60.0, 8.0)];
        assert_eq!(tags(&seen), [0, 1]);
        // With one other tag only, it is kept: four more points beat a lone tag's mirror.
        assert_eq!(tags(&seen[1..3]), [1, 2]);
        // 16 px is two pixels a cell: kept; 15 px is not.
        assert_eq!(tags(&[quad(0, 60.0, 60.0), quad(1, 60.0, 40.0), quad(2, 60.0, 16.0)]), [0, 1, 2]);
        assert_eq!(tags(&[quad(0, 60.0, 60.0), quad(1, 60.0, 40.0), quad(2, 60.0, 15.0)]), [0, 1]);
        // At 2× a steep tag's cells are wide enough, but its sides say how steeply it is seen:
        // 28 px of 140 (0.2) is too steep, 32 px (0.23) is not.
        assert_eq!(tags(&[quad(0, 140.0, 130.0), quad(1, 140.0, 100.0), quad(2, 140.0, 28.0)]), [0, 1]);
        assert_eq!(tags(&[quad(0, 140.0, 130.0), quad(1, 140.0, 100.0), quad(2, 140.0, 32.0)]), [0, 1, 2]);
    }

    #[test]
    fn a_body_blurred_beyond_a_seventh_of_its_cells_is_defocused() {
        let blurred = |blur: Option<f64>| {
            let mut d = quad(0, 80.0, 80.0);
            d.blur_px = blur;
            let body = BodyResult {
                camera_from_body: Pose::identity(),
                tags: vec![0],
                rejected_tags: vec![],
                rms_px: 0.1,
                covariance: Matrix6::identity(),
                blur_px: None,
                cell_px: 0.0,
            };
            let mut bodies = [Some(body), None];
            let mut flags = Vec::new();
            let defocused = judge(&mut bodies, &[d], [0.0; 2], DEFOCUSED_BLUR_PER_CELL, 8.0, &mut flags);
            let b = bodies[0].clone().expect("kept");
            (defocused, flags, b.blur_px, b.cell_px)
        };
        // 80 px sides: cells of 10 px.
        assert_eq!(blurred(Some(1.2)), (false, vec![], Some(1.2), 10.0));
        let (defocused, flags, ..) = blurred(Some(10.0 * DEFOCUSED_BLUR_PER_CELL + 0.1));
        assert!(defocused && flags == [Flag::Defocused(BodyKind::Maxilla)], "{flags:?}");
        assert_eq!(blurred(None), (false, vec![], None, 10.0), "not measured: never flagged");
    }

    #[test]
    fn the_motion_predicted_over_the_exposure_is_taken_out_of_the_blur() {
        // A box smear of 14.6 px at 45° to a tag's sides puts σ = 14.6 / √24 = 2.98 px on both.
        let smear = 14.6;
        let motion = smear / 24f64.sqrt();
        assert!(lens_blur(motion, smear) < 1e-6);
        // With 1 px of lens blur besides, that is what remains.
        assert!((lens_blur(motion.hypot(1.0), smear) - 1.0).abs() < 1e-6);
        assert_eq!(lens_blur(2.0, 0.0), 2.0, "a still body keeps its blur");
    }
}
