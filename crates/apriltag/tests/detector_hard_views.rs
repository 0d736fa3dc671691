//! Tags C finds in awkward views (issue 24, item 19), drawn through a pinhole camera with
//! exact corners: a large tag seen at 80° from the viewing direction (long edges 170–220 px,
//! short ones 35–50 px) and an 18 px tag, both printed on paper darker than what lies behind
//! them (a tag in shade against a sunlit wall or the sky), at decimate 2.
//!
//! Their cells are 2–5 px across the foreshortened direction, so the edge refit's window
//! reaches the next edge out, from the white border to the brighter background. In linear
//! light that step weighs as much as the black border's own, and before the fix it pulled
//! the sides outward by 1–2 px. The refit now takes only the one edge nearest the quad's side,
//! within half a cell of it, told from the next one by a gradient over 1 px.
//!
//! Before the fix our refit either lost the tag (its decode failed, and only the fall-back to
//! C's fit read it, with C's corners, biased inward by the blur by 1–1.5 px here) or kept it
//! 2.5 px off. Now every view C finds is found, never more than 0.5 px farther from the truth
//! than C's corners, and the median worst corner is within 0.75 px of the truth.

use jawtrack_apriltag::{Detector, DetectorConfig, ImageView, TagFamily};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use std::io::Write as _;

/// Linear reflectances: the tag's ink and paper (in shade), the lit background behind it.
const BLACK: f64 = 0.03;
const PAPER: f64 = 0.35;
const BACKGROUND: f64 = 0.75;
/// The lens's blur (Gaussian σ, px) for the large tag, and for the small one (a sharp lens:
/// blurrier, neither C nor we can read 18 px tags at decimate 2).
const BLUR: f64 = 0.8;
const SHARP: f64 = 0.45;
/// Focal length (px) of a 640 × 480 camera.
const FOCAL: f64 = 600.0;
const W: usize = 640;
const H: usize = 480;

fn srgb(v: f64) -> u8 {
    let e = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (255.0 * e).round().clamp(0.0, 255.0) as u8
}

fn apply(h: &[f64; 9], x: f64, y: f64) -> [f64; 2] {
    let z = h[6] * x + h[7] * y + h[8];
    [(h[0] * x + h[1] * y + h[2]) / z, (h[3] * x + h[4] * y + h[5]) / z]
}

fn invert(m: &[f64; 9]) -> [f64; 9] {
    let det =
        m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
    [
        (m[4] * m[8] - m[5] * m[7]) / det,
        (m[2] * m[7] - m[1] * m[8]) / det,
        (m[1] * m[5] - m[2] * m[4]) / det,
        (m[5] * m[6] - m[3] * m[8]) / det,
        (m[0] * m[8] - m[2] * m[6]) / det,
        (m[2] * m[3] - m[0] * m[5]) / det,
        (m[3] * m[7] - m[4] * m[6]) / det,
        (m[1] * m[6] - m[0] * m[7]) / det,
        (m[0] * m[4] - m[1] * m[3]) / det,
    ]
}

/// The homography from tag cells (u right, v down, ±5 at the white border's outer edge) to
/// pixels (centre of the top-left pixel at (0, 0)) of a tag whose black square would be
/// `side` px wide face-on at its distance, turned away from the camera by `tilt` degrees about
/// its horizontal axis, then rolled by `roll` degrees, centred on the image's centre.
fn view(side: f64, tilt: f64, roll: f64) -> [f64; 9] {
    let z = 1.0;
    let cell = side * z / FOCAL / 8.0;
    let (st, ct) = tilt.to_radians().sin_cos();
    let (sr, cr) = roll.to_radians().sin_cos();
    let turn = |v: [f64; 3]| [cr * v[0] - sr * v[1], sr * v[0] + cr * v[1], v[2]];
    let (r1, r2) = (turn([cell, 0.0, 0.0]), turn([0.0, ct * cell, st * cell]));
    let (cx, cy) = ((W as f64 - 1.0) / 2.0 + 0.3, (H as f64 - 1.0) / 2.0 - 0.2);
    let k = |v: [f64; 3]| [FOCAL * v[0] + cx * v[2], FOCAL * v[1] + cy * v[2], v[2]];
    let (c1, c2, c3) = (k(r1), k(r2), k([0.0, 0.0, z]));
    [c1[0], c2[0], c3[0], c1[1], c2[1], c3[1], c1[2], c2[2], c3[2]]
}

struct Scene {
    image: Vec<u8>,
    /// The black square's corners, in the detector's order (bottom-left, bottom-right,
    /// top-right, top-left of the upright tag).
    corners: [[f64; 2]; 4],
}

/// Draws tag `id` through `h`: reflectance averaged over 8 × 8 points per pixel, blurred by
/// the lens in linear light, encoded as sRGB.
fn draw(id: u32, h: &[f64; 9], blur: f64) -> Scene {
    let bm = TagFamily::TAG36H11.bitmap(id).expect("id");
    let back = invert(h);
    let reflectance = |x: f64, y: f64| -> f64 {
        let [u, v] = apply(&back, x, y);
        let (i, j) = ((u + 5.0).floor(), (v + 5.0).floor());
        if !(0.0..10.0).contains(&i) || !(0.0..10.0).contains(&j) {
            return BACKGROUND;
        }
        let (i, j) = (i as usize, j as usize);
        let white = i == 0 || j == 0 || i == 9 || j == 9 || bm.is_white(i - 1, j - 1);
        if white { PAPER } else { BLACK }
    };
    let outline = [[-5.0, -5.0], [5.0, -5.0], [5.0, 5.0], [-5.0, 5.0]].map(|p| apply(h, p[0], p[1]));
    let bound = |f: fn(&[f64; 2]) -> f64, lo: bool, n: usize| {
        let v = outline
            .iter()
            .map(f)
            .fold(if lo { f64::INFINITY } else { f64::NEG_INFINITY }, |a, b| if lo { a.min(b) } else { a.max(b) });
        let v = if lo { v - 8.0 } else { v + 8.0 };
        (v.max(0.0) as usize).min(n)
    };
    let (x0, x1) = (bound(|p| p[0], true, W), bound(|p| p[0], false, W));
    let (y0, y1) = (bound(|p| p[1], true, H), bound(|p| p[1], false, H));
    let mut lin = vec![BACKGROUND; W * H];
    const S: usize = 8;
    for y in y0..y1 {
        for x in x0..x1 {
            let sum: f64 = (0..S * S)
                .map(|k| {
                    let (a, b) = ((k % S) as f64, (k / S) as f64);
                    reflectance(x as f64 + (a + 0.5) / S as f64 - 0.5, y as f64 + (b + 0.5) / S as f64 - 0.5)
                })
                .sum();
            lin[y * W + x] = sum / (S * S) as f64;
        }
    }
    let kernel: Vec<f64> = (-3..=3).map(|i| (-f64::from(i * i) / (2.0 * blur * blur)).exp()).collect();
    let norm: f64 = kernel.iter().sum();
    let at = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;
    let mut rows = lin.clone();
    for y in y0..y1 {
        for x in x0..x1 {
            rows[y * W + x] = kernel
                .iter()
                .enumerate()
                .map(|(k, w)| w * lin[y * W + at(x as isize + k as isize - 3, W)])
                .sum::<f64>()
                / norm;
        }
    }
    let mut image = vec![srgb(BACKGROUND); W * H];
    for y in y0..y1 {
        for x in x0..x1 {
            let v = kernel
                .iter()
                .enumerate()
                .map(|(k, w)| w * rows[at(y as isize + k as isize - 3, H) * W + x])
                .sum::<f64>()
                / norm;
            image[y * W + x] = srgb(v);
        }
    }
    let corners = [[-4.0, 4.0], [4.0, 4.0], [4.0, -4.0], [-4.0, -4.0]].map(|p| apply(h, p[0], p[1]));
    Scene { image, corners }
}

fn worst_corner_error(found: &[[f64; 2]; 4], truth: &[[f64; 2]; 4]) -> f64 {
    found.iter().zip(truth).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max)
}

fn side_lengths(c: &[[f64; 2]; 4]) -> [f64; 4] {
    std::array::from_fn(|i| (c[i][0] - c[(i + 1) % 4][0]).hypot(c[i][1] - c[(i + 1) % 4][1]))
}

/// For each view: ours and C's worst corner error (px; infinite when the tag is not found).
fn errors(id: u32, views: &[[f64; 9]], blur: f64) -> Vec<(f64, f64, [f64; 4])> {
    let ours = Detector::new(DetectorConfig::default()).expect("detector");
    let mut c = ReferenceDetector::new(&ReferenceParams::default()).expect("reference");
    views
        .iter()
        .map(|h| {
            let s = draw(id, h, blur);
            let best = |found: &mut dyn Iterator<Item = [[f64; 2]; 4]>| {
                found.map(|corners| worst_corner_error(&corners, &s.corners)).fold(f64::INFINITY, f64::min)
            };
            let frame = ImageView::new(&s.image, W, H, W).expect("view");
            let o =
                best(&mut ours.detect(&frame).expect("detects").into_iter().filter(|d| d.id == id).map(|d| d.corners));
            let r = best(
                &mut c
                    .detect(&s.image, W, H, W)
                    .expect("reference")
                    .into_iter()
                    .filter(|d| d.id == id)
                    .map(|d| d.corners),
            );
            (o, r, side_lengths(&s.corners))
        })
        .collect()
}

/// Checks that every view C finds (its corners within 2 px of the truth) we find too, no more
/// than 0.5 px farther from the truth than C's, and that over those views our median worst
/// corner is within 0.75 px of the truth. C must find at least half of the views.
fn check(what: &str, id: u32, views: &[(f64, [f64; 9])], blur: f64) {
    let hs: Vec<[f64; 9]> = views.iter().map(|v| v.1).collect();
    let (mut ours_errors, mut bad) = (Vec::new(), Vec::new());
    for ((roll, _), (ours, c, sides)) in views.iter().zip(errors(id, &hs, blur)) {
        let _ = writeln!(
            std::io::stderr(),
            "{what}, roll {roll:>3}°, sides {:.0?} px: worst corner ours {ours:.2} px, C {c:.2} px",
            sides
        );
        if c < 2.0 {
            ours_errors.push(ours);
            if !(ours < 2.0 && ours <= c + 0.5) {
                bad.push(format!("roll {roll}°: ours {ours:.2} px from the truth, C {c:.2} px"));
            }
        }
    }
    assert!(bad.is_empty(), "{what}: {bad:?}");
    let n = ours_errors.len();
    assert!(n * 2 >= views.len(), "{what}: C finds only {n} of {} views", views.len());
    ours_errors.sort_by(f64::total_cmp);
    let median = ours_errors[n / 2];
    assert!(median <= 0.75, "{what}: our median worst corner is {median:.2} px from the truth");
}

#[test]
fn a_tag_at_80_degrees_to_the_view_is_found_where_it_is() {
    // Black square 195 px face-on: long edges 170–220 px at 80°, short ones 35–50 px.
    let rolls = [0.0, 20.0, 45.0, 70.0, 100.0, 160.0, 210.0, 250.0, 300.0, 340.0];
    let views: Vec<(f64, [f64; 9])> = rolls.iter().map(|&r| (r, view(195.0, 80.0, r))).collect();
    check("80° to the view", 5, &views, BLUR);
}

#[test]
fn an_18_px_tag_is_found_where_it_is() {
    let rolls = [0.0, 15.0, 30.0, 60.0, 100.0, 135.0, 200.0, 290.0];
    let views: Vec<(f64, [f64; 9])> = rolls.iter().map(|&r| (r, view(18.0, 15.0, r))).collect();
    check("18 px", 11, &views, SHARP);
}
