//! How sharp the tracker sees each marker, and what follows: a tag seen nearly edge-on is left
//! out while its body has others ([`THIN_CELL_PX`]); each body's edge blur is the median of its
//! tags' (the detector's `Detection::blur_px`) and is judged against their cells' width; a body
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

/// The default [`crate::TrackerConfig::max_blur_per_cell`]: measured on renders with a phone's
/// optics (`docs/accuracy.md`, "Capture"), a blur of this much of a cell leaves the jaw within TBD.
pub const DEFOCUSED_BLUR_PER_CELL: f64 = 0.2;

/// A tag whose cells are narrower than this (px, across its shortest side) is seen too
/// steeply to place its corners: its border and its data cells blur into one another (at 200
/// mm on a 1080p phone frame, a tag seen 83° from face-on has cells of 1 px across and its
/// corners land up to 1.25 px off, moving the jaw 0.19 mm; `docs/accuracy.md`, "Capture").
pub const THIN_CELL_PX: f64 = 2.0;

/// The lengths (px) of a detected tag's four sides.
fn sides_px(d: &Detection) -> [f64; 4] {
    let c = &d.corners;
    std::array::from_fn(|i| (c[i][0] - c[(i + 1) % 4][0]).hypot(c[i][1] - c[(i + 1) % 4][1]))
}

/// The width (px) of a detected tag's cells across its shortest side.
pub(crate) fn cell_px(d: &Detection) -> f64 {
    sides_px(d).into_iter().fold(f64::INFINITY, f64::min) / 8.0
}

/// The width (px) of a detected tag's cells along its longest side.
fn longest_cell_px(d: &Detection) -> f64 {
    sides_px(d).into_iter().fold(0.0, f64::max) / 8.0
}

/// Sets each solved body's blur and cell width from the detections its pose used, flags those
/// blurred beyond `max_blur_per_cell` of a cell `defocused`, and says whether any was.
pub(crate) fn judge(
    bodies: &mut [Option<BodyResult>; 2],
    detections: &[Detection],
    max_blur_per_cell: f64,
    flags: &mut Vec<Flag>,
) -> bool {
    let mut defocused = false;
    for (kind, body) in BodyKind::ALL.iter().zip(bodies.iter_mut()) {
        let Some(b) = body else { continue };
        let used: Vec<&Detection> = detections.iter().filter(|d| b.tags.contains(&d.id)).collect();
        b.blur_px = median(used.iter().filter_map(|d| d.blur_px));
        b.cell_px = median(used.iter().map(|d| longest_cell_px(d))).unwrap_or(0.0);
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
        // 16 px is two pixels a cell: kept.
        assert_eq!(tags(&[quad(0, 60.0, 60.0), quad(1, 60.0, 40.0), quad(2, 60.0, 16.0)]), [0, 1, 2]);
    }

    #[test]
    fn a_body_blurred_beyond_a_fifth_of_its_cells_is_defocused() {
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
            let defocused = judge(&mut bodies, &[d], DEFOCUSED_BLUR_PER_CELL, &mut flags);
            let b = bodies[0].clone().expect("kept");
            (defocused, flags, b.blur_px, b.cell_px)
        };
        // 80 px sides: cells of 10 px.
        assert_eq!(blurred(Some(1.5)), (false, vec![], Some(1.5), 10.0));
        let (defocused, flags, ..) = blurred(Some(10.0 * DEFOCUSED_BLUR_PER_CELL + 0.1));
        assert!(defocused && flags == [Flag::Defocused(BodyKind::Maxilla)], "{flags:?}");
        assert_eq!(blurred(None), (false, vec![], None, 10.0), "not measured: never flagged");
    }
}
