//! The work a detection does on each quad at full resolution, whoever found the quad (the
//! image stages of [`Detector::search`], or a tracker's prediction in [`Detector::confirm`]):
//! edge refit, decoding, the border fit; and the finish of a frame's tags — duplicates removed,
//! sorted, moved to JawTrack's pixel convention.

use super::edges::refine_edges;
use super::{Detection, Detector, IDENTITY, decode_quad, homography, with_border_fit};
use crate::image::ImageView;
use crate::quads::Quad;

impl Detector {
    /// The tag the quad `q0` (C's pixel convention; found at `decimate`, which sizes the edge
    /// refit's reach) holds, if it decodes: its edges refitted, and with the settings' border
    /// fit.
    pub(super) fn tag_from_quad(
        &self,
        im: &ImageView<'_>,
        q0: &Quad,
        decimate: f32,
        lut: &[f64; 256],
        smeared: bool,
    ) -> Option<Detection> {
        let c = &self.config;
        let cells = c.family.width_at_border as f64;
        let decode = |q: &Quad| decode_quad(im, &homography(q)?, &c.family, &self.table, c.decode_sharpening);
        let mut q = *q0;
        if c.refine_edges {
            refine_edges(im, &mut q, decimate, lut, c.linear_edges, c.linear_edges && smeared, cells);
        }
        let d = decode(&q).or_else(|| {
            // Our fit can be pulled off by a bright edge near a small tag (linear light
            // weighs bright gradients most); C's fit may still read it, and then we
            // report what C would: never fewer tags than C.
            if !(c.refine_edges && c.linear_edges) {
                return None;
            }
            let mut q = *q0;
            refine_edges(im, &mut q, decimate, &IDENTITY, false, false, cells);
            decode(&q)
        })?;
        Some(if c.linear_edges && c.blur_aware_edges { with_border_fit(im, lut, &c.family, d, !smeared) } else { d })
    }
}

/// A frame's tags as a detection reports them: of overlapping duplicates the one C keeps
/// ([`reconcile`]), sorted by id (ties by position), in JawTrack's pixel convention.
pub(super) fn finish(dets: Vec<Detection>) -> Vec<Detection> {
    let mut dets = reconcile(dets);
    // C sorts by id; ties keep a deterministic order here (by position).
    dets.sort_by(|a, b| {
        a.id.cmp(&b.id).then(a.center[0].total_cmp(&b.center[0])).then(a.center[1].total_cmp(&b.center[1]))
    });
    // JawTrack's pixel convention.
    dets.iter().map(|d| d.shifted(-0.5, -0.5)).collect()
}

/// C's reconciliation: of two detections of the same id whose quads overlap, keep the one with
/// fewer corrected bits, then the larger margin, then the smaller corner coordinates.
fn reconcile(mut dets: Vec<Detection>) -> Vec<Detection> {
    let mut i0 = 0;
    while i0 < dets.len() {
        let mut i1 = i0 + 1;
        let mut removed_i0 = false;
        while i1 < dets.len() {
            let (a, b) = (&dets[i0], &dets[i1]);
            if a.id != b.id || !convex_quads_overlap(&a.corners, &b.corners) {
                i1 += 1;
                continue;
            }
            let mut pref = prefer_smaller(0, f64::from(a.hamming), f64::from(b.hamming));
            pref = prefer_smaller(pref, -f64::from(a.decision_margin), -f64::from(b.decision_margin));
            for i in 0..4 {
                pref = prefer_smaller(pref, a.corners[i][0], b.corners[i][0]);
                pref = prefer_smaller(pref, a.corners[i][1], b.corners[i][1]);
            }
            if pref < 0 {
                dets.remove(i1);
            } else {
                dets.remove(i0);
                removed_i0 = true;
                break;
            }
        }
        if !removed_i0 {
            i0 += 1;
        }
    }
    dets
}

fn prefer_smaller(pref: i32, q0: f64, q1: f64) -> i32 {
    if pref != 0 {
        pref
    } else if q0 < q1 {
        -1
    } else if q1 < q0 {
        1
    } else {
        0
    }
}

/// Whether two convex quadrilaterals share any area (separating-axis test).
fn convex_quads_overlap(a: &[[f64; 2]; 4], b: &[[f64; 2]; 4]) -> bool {
    for poly in [a, b] {
        for i in 0..4 {
            let (p, q) = (poly[i], poly[(i + 1) % 4]);
            let axis = [q[1] - p[1], p[0] - q[0]];
            let proj = |pts: &[[f64; 2]; 4]| {
                pts.iter()
                    .map(|c| c[0] * axis[0] + c[1] * axis[1])
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
            };
            let (a0, a1) = proj(a);
            let (b0, b1) = proj(b);
            if a1 < b0 || b1 < a0 {
                return false;
            }
        }
    }
    true
}
