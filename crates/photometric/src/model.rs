//! What a tag prints, seen through a Gaussian blur: the fraction of paper at a point of the tag
//! plane, with its slope.
//!
//! A tag's square is `n` × `n` cells (tag36h11: 8, the black border included) inside a quiet
//! zone of paper. Cell coordinates (u, v) run from 0 to `n` across the square, u along its rows
//! and v down its columns, as the tag's upright image is drawn. A Gaussian blur whose spread is
//! `su` cells along u and `sv` along v (the image's blur carried onto the tag plane, where a
//! straight edge stays straight) turns each cell into the product of two differences of Φ,
//! so the paper seen at (u, v) is one minus the sum of the ink cells' weights; only the cells
//! within a few spreads of the point are summed.

use arrayvec::ArrayVec;
use jawtrack_apriltag::gauss::cdf_pdf;
use jawtrack_tag_family::TagBitmap;

/// Cells farther than this many spreads from a point add nothing measurable to it
/// (Φ(−5) = 3·10⁻⁷ of the contrast).
const REACH: f64 = 5.0;
/// The narrowest spread (cells) the model evaluates: a sharper edge is a step at this scale.
const MIN_SPREAD: f64 = 1e-3;
/// The most cells one point can sum along each axis: a square of up to 16 cells.
const MAX_CELLS: usize = 16;

/// The ink of one tag's square: the cells that print black.
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    n: usize,
    ink: Vec<bool>,
}

impl Pattern {
    /// The pattern of `bitmap`; `None` for a square wider than the model holds.
    pub fn new(bitmap: &TagBitmap) -> Option<Self> {
        let n = bitmap.width();
        if n == 0 || n > MAX_CELLS {
            return None;
        }
        let ink = (0..n * n).map(|i| !bitmap.is_white(i % n, i / n)).collect();
        Some(Pattern { n, ink })
    }

    /// Cells across the square.
    pub fn cells(&self) -> usize {
        self.n
    }

    /// Whether the rectangle of half-widths `ru` × `rv` cells about (u, v) holds both ink and
    /// paper (the quiet zone about the square is paper): whether (u, v) is within that of an
    /// edge along each axis.
    pub fn mixed(&self, u: f64, v: f64, ru: f64, rv: f64) -> bool {
        if !(u.is_finite() && v.is_finite() && ru.is_finite() && rv.is_finite()) {
            return false;
        }
        let n = self.n as i64;
        // Cells from one beyond the square on each side: all paper farther out.
        let span = |x: f64, r: f64| (floor(x - r).clamp(-1, n), floor(x + r).clamp(-1, n));
        let ((i0, i1), (j0, j1)) = (span(u, ru), span(v, rv));
        let (mut ink, mut paper) = (false, false);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let inside = (0..n).contains(&i) && (0..n).contains(&j);
                if inside && self.ink[(j * n + i) as usize] {
                    ink = true;
                } else {
                    paper = true;
                }
                if ink && paper {
                    return true;
                }
            }
        }
        false
    }

    /// The paper seen at (u, v) under the blur (`su`, `sv`), from 0 (ink) to 1 (paper), with
    /// its derivatives.
    pub fn paper(&self, u: f64, v: f64, su: f64, sv: f64) -> Paper {
        let (su, sv) = (su.max(MIN_SPREAD), sv.max(MIN_SPREAD));
        let white = Paper { value: 1.0, du: 0.0, dv: 0.0, dsu: 0.0, dsv: 0.0 };
        let (mut a, mut b) = (ArrayVec::new(), ArrayVec::new());
        let Some(i0) = cells(u, su, self.n, &mut a) else { return white };
        let Some(j0) = cells(v, sv, self.n, &mut b) else { return white };
        let (mut ink, mut ink_u, mut ink_v, mut ink_su, mut ink_sv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (k, b) in b.iter().enumerate() {
            let start = (j0 + k) * self.n + i0;
            let row = &self.ink[start..start + a.len()];
            let (mut w, mut w_x, mut w_s) = (0.0, 0.0, 0.0);
            for (a, _) in a.iter().zip(row).filter(|(_, ink)| **ink) {
                w += a.w;
                w_x += a.dx;
                w_s += a.ds;
            }
            ink += w * b.w;
            ink_u += w_x * b.w;
            ink_su += w_s * b.w;
            ink_v += w * b.dx;
            ink_sv += w * b.ds;
        }
        Paper { value: 1.0 - ink, du: -ink_u, dv: -ink_v, dsu: -ink_su, dsv: -ink_sv }
    }
}

/// The paper a point sees, and its derivatives by the point's cell coordinates and by the
/// blur's spreads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paper {
    /// 0 (ink) to 1 (paper).
    pub value: f64,
    /// ∂/∂u.
    pub du: f64,
    /// ∂/∂v.
    pub dv: f64,
    /// ∂/∂su.
    pub dsu: f64,
    /// ∂/∂sv.
    pub dsv: f64,
}

/// One cell's weight along one axis, with its derivatives by the point and by the spread.
#[derive(Clone, Copy)]
struct Cell {
    w: f64,
    dx: f64,
    ds: f64,
}

/// Pushes onto `out` the weight of each cell `i0..=i1` at `x` under the spread `s` (the
/// Gaussian's mass over [i, i + 1)), and gives `i0`; `None` when no cell of the square is
/// within reach. The cells are pushed rather than written into a zeroed array: zeroing two
/// arrays for every pixel was a tenth of the refinement's time.
fn cells(x: f64, s: f64, n: usize, out: &mut ArrayVec<Cell, MAX_CELLS>) -> Option<usize> {
    if x.is_nan() {
        return None; // a point at no place
    }
    let (first, last) = (floor(x - REACH * s), floor(x + REACH * s));
    let (lo, hi) = (first.max(0), last.min(n as i64 - 1));
    if lo > hi {
        return None;
    }
    let (i0, i1) = (lo as usize, hi as usize);
    // A boundary of the window beyond the reach adds nothing: Φ there is taken as 0 (below)
    // or 1 (above) and φ as 0. Only the boundaries within reach are looked up: those
    // between the cells, and the square's own edges where the window meets them.
    let boundary = |b: usize, beyond: bool, f: f64| {
        if beyond {
            (f, 0.0, 0.0)
        } else {
            let z = (b as f64 - x) / s;
            let (f, p) = cdf_pdf(z);
            (f, p, z)
        }
    };
    let (mut f0, mut p0, mut z0) = boundary(i0, first >= 0, 0.0);
    for i in i0..=i1 {
        let (f1, p1, z1) = boundary(i + 1, i == i1 && last < n as i64, 1.0);
        out.push(Cell { w: f1 - f0, dx: (p0 - p1) / s, ds: (p0 * z0 - p1 * z1) / s });
        (f0, p0, z0) = (f1, p1, z1);
    }
    Some(i0)
}

/// Whether [x − r, x + r] lies within one cell: then no rectangle that wide about x is mixed.
pub(crate) fn within_one_cell(x: f64, r: f64) -> bool {
    floor(x - r) == floor(x + r)
}

/// ⌊v⌋, saturating at the integers' ends. `f64::floor` is a library call on x86-64 without
/// SSE4.1 (the baseline), and was a twentieth of the refinement's time.
fn floor(v: f64) -> i64 {
    let t = v as i64;
    if (t as f64) > v { t.saturating_sub(1) } else { t }
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_tag_family::TagFamily;

    fn pattern() -> Pattern {
        Pattern::new(&TagFamily::TAG36H11.bitmap(5).expect("tag 5")).expect("8 cells")
    }

    #[test]
    fn floor_rounds_down_and_saturates() {
        let cases = [(2.5, 2), (-2.5, -3), (-0.0, 0), (3.0, 3), (-3.0, -3), (1e300, i64::MAX), (-1e300, i64::MIN)];
        for (v, want) in cases {
            assert_eq!(floor(v), want, "{v}");
        }
    }

    #[test]
    fn sharp_cells_read_as_printed() {
        let (p, bm) = (pattern(), TagFamily::TAG36H11.bitmap(5).expect("tag 5"));
        let mut checked = 0;
        for y in 0..8 {
            for x in 0..8 {
                let value = p.paper(x as f64 + 0.5, y as f64 + 0.5, 0.01, 0.01).value;
                assert_eq!(value, if bm.is_white(x, y) { 1.0 } else { 0.0 }, "cell ({x}, {y})");
                checked += 1;
            }
        }
        assert_eq!(checked, 64);
        assert_eq!(p.paper(-0.5, 4.0, 0.01, 0.01).value, 1.0, "the quiet zone is paper");
    }

    #[test]
    fn a_rectangle_is_mixed_where_it_crosses_an_edge() {
        let p = pattern();
        // The border is ink, the quiet zone beyond it paper: the outer edge is at u = 0.
        assert!(p.mixed(0.05, 4.0, 0.1, 0.1), "across the outer edge");
        assert!(p.mixed(-0.05, 4.0, 0.1, 0.1), "across it from outside");
        assert!(!p.mixed(0.5, 4.0, 0.1, 0.1), "inside the border's ink");
        assert!(!p.mixed(-0.5, 4.0, 0.1, 0.1), "in the quiet zone");
        assert!(!p.mixed(-3.0, 4.0, 0.5, 0.5), "far outside: paper only");
        assert!(!p.mixed(f64::NAN, 4.0, 0.1, 0.1), "at no place");
        // Along v only: the border's top edge at v = 0, with a narrow u extent.
        assert!(p.mixed(4.0, 0.02, 0.01, 0.05));
        assert!(!p.mixed(4.0, 0.5, 0.01, 0.05));
        // Every cell boundary between ink and paper inside the square is found from both sides.
        let bm = TagFamily::TAG36H11.bitmap(5).expect("tag 5");
        let mut checked = 0;
        for y in 1..7 {
            for x in 1..6 {
                if bm.is_white(x, y) != bm.is_white(x + 1, y) {
                    let edge = (x + 1) as f64;
                    assert!(p.mixed(edge - 0.05, y as f64 + 0.5, 0.1, 0.1), "({x}, {y}) left side");
                    assert!(p.mixed(edge + 0.05, y as f64 + 0.5, 0.1, 0.1), "({x}, {y}) right side");
                    assert!(!p.mixed(edge - 0.5, y as f64 + 0.5, 0.1, 0.1), "({x}, {y}) mid-cell");
                    checked += 1;
                }
            }
        }
        assert!(checked > 5, "only {checked} edges");
    }

    #[test]
    fn an_edge_under_blur_is_half_way_and_its_slopes_are_the_derivatives() {
        let p = pattern();
        // The border's outer edge at u = 0, mid-side: half ink, half paper (to the Gaussian's
        // tail beyond the reach, Φ(−5)).
        let edge = p.paper(0.0, 4.0, 0.2, 0.2);
        assert!((edge.value - 0.5).abs() < 1e-6, "{}", edge.value);
        assert!(edge.du < 0.0, "paper gives way to ink going in: {}", edge.du);
        let h = 1e-6;
        let mut checked = 0;
        for &(u, v) in &[(0.1, 3.3), (2.7, 1.2), (5.05, 6.9), (7.9, 0.2), (3.0, 3.0)] {
            let (su, sv) = (0.3, 0.45);
            let m = p.paper(u, v, su, sv);
            let at = |du: f64, dv: f64, dsu: f64, dsv: f64| p.paper(u + du, v + dv, su + dsu, sv + dsv).value;
            let numeric = [
                (at(h, 0.0, 0.0, 0.0) - at(-h, 0.0, 0.0, 0.0)) / (2.0 * h),
                (at(0.0, h, 0.0, 0.0) - at(0.0, -h, 0.0, 0.0)) / (2.0 * h),
                (at(0.0, 0.0, h, 0.0) - at(0.0, 0.0, -h, 0.0)) / (2.0 * h),
                (at(0.0, 0.0, 0.0, h) - at(0.0, 0.0, 0.0, -h)) / (2.0 * h),
            ];
            for (analytic, numeric) in [m.du, m.dv, m.dsu, m.dsv].iter().zip(numeric) {
                assert!((analytic - numeric).abs() < 1e-6, "({u}, {v}): {analytic} vs {numeric}");
            }
            checked += 1;
        }
        assert_eq!(checked, 5);
    }
}
