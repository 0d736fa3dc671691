//! Quads nested inside a tag: a tag36h11's data cells make quads of their own (a block of dark
//! cells inside the light ones), each of which costs the per-quad work of a tag (two edge
//! refits, two decodings) and never decodes as one. A detection with JawTrack's edge fit tries
//! the quads that lie inside no larger quad first, and then only those nested quads that no
//! decoded tag holds. The tags found are the same; C's edge fit tries every quad, as C does.

use super::{Detection, longest_side_of};
use crate::quads::Quad;

/// A quad is nested in another when its longest side is at most this share of the other's:
/// a tag's data cells span at most 6 of its 8 cells (0.75), while two quads found for one tag
/// differ by a pixel or two and are not nested.
const NESTED_SIDE_SHARE: f64 = 0.8;

/// A quad's corners with what the nesting test reads first: its longest side and its box.
struct Outline {
    c: [[f64; 2]; 4],
    longest: f64,
    lo: [f64; 2],
    hi: [f64; 2],
}

impl Outline {
    fn of(c: [[f64; 2]; 4]) -> Outline {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &c {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        Outline { c, longest: longest_side_of(&c), lo, hi }
    }

    fn of_quad(q: &Quad) -> Outline {
        Outline::of(q.p.map(|p| p.map(f64::from)))
    }

    /// Whether every corner of `self` lies inside `outer` (convex, either winding) and its
    /// longest side is at most [`NESTED_SIDE_SHARE`] of `outer`'s. The sides and boxes rule
    /// out most pairs before the corners are tested: with C's contrast threshold a 4K frame
    /// holds some 540 quads.
    fn nested_in(&self, outer: &Outline) -> bool {
        if self.longest > NESTED_SIDE_SHARE * outer.longest
            || self.lo[0] < outer.lo[0]
            || self.lo[1] < outer.lo[1]
            || self.hi[0] > outer.hi[0]
            || self.hi[1] > outer.hi[1]
        {
            return false;
        }
        let o = &outer.c;
        let cross =
            |a: [f64; 2], b: [f64; 2], p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let winding = (0..4).map(|i| cross(o[i], o[(i + 1) % 4], o[(i + 2) % 4])).sum::<f64>().signum();
        winding != 0.0 && self.c.iter().all(|&p| (0..4).all(|i| winding * cross(o[i], o[(i + 1) % 4], p) > 0.0))
    }
}

/// The indices of `quads` split into those nested in no other quad, to be tried first, and
/// those nested in one.
pub(super) fn split(quads: &[Quad]) -> (Vec<usize>, Vec<usize>) {
    let all: Vec<Outline> = quads.iter().map(Outline::of_quad).collect();
    (0..quads.len()).partition(|&i| !all.iter().enumerate().any(|(j, outer)| j != i && all[i].nested_in(outer)))
}

/// Whether quad `q` lies inside one of the tags `found` (the detections' corners in the quads'
/// pixel convention).
pub(super) fn held_by_a_tag(q: &Quad, found: &[(usize, Detection)]) -> bool {
    let inner = Outline::of_quad(q);
    found.iter().any(|(_, d)| inner.nested_in(&Outline::of(d.corners)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x: f32, y: f32, side: f32) -> Quad {
        Quad { p: [[x, y], [x + side, y], [x + side, y + side], [x, y + side]] }
    }

    #[test]
    fn a_small_quad_inside_a_larger_one_is_nested_and_a_near_twin_is_not() {
        let tag = square(100.0, 100.0, 80.0);
        let cells = square(130.0, 120.0, 30.0);
        let twin = square(101.0, 101.0, 78.0);
        let beside = square(200.0, 100.0, 30.0);
        let across = square(170.0, 120.0, 30.0); // straddles the tag's right side
        let quads = [tag, cells, twin, beside, across];
        let (first, nested) = split(&quads);
        assert_eq!((first, nested), (vec![0, 2, 3, 4], vec![1]));
        // Either winding.
        let mut reversed = tag;
        reversed.p.reverse();
        assert!(Outline::of_quad(&cells).nested_in(&Outline::of_quad(&reversed)));
        // A quad as large as 0.8 of the tag's side is nested; a larger one is not.
        assert!(Outline::of_quad(&square(105.0, 105.0, 64.0)).nested_in(&Outline::of_quad(&tag)));
        assert!(!Outline::of_quad(&square(105.0, 105.0, 65.0)).nested_in(&Outline::of_quad(&tag)));
    }
}
