//! The detector on tags drawn with exact corners: large tags turned by awkward angles at 4K
//! (where a published pure-Rust port loses most of them), tags at and across the frame's
//! border, and the smallest tag found at each decimation.
//!
//! Tags are drawn as a camera sees them: in linear light with exact pixel coverage, blurred
//! by a sharp lens (σ = 0.7 px) and encoded as sRGB, so the default linear-light edge
//! refinement applies. (On perfectly sharp, pixel-aligned edges, which no lens makes, the
//! gradient-peak refinement is off by up to 0.25 px.)

use jawtrack_apriltag::{Detection, Detector, DetectorConfig, ImageView, TagFamily};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use std::io::Write as _;

/// Linear reflectances of the tag's ink, paper and the background around it.
const BLACK: f64 = 0.03;
const WHITE: f64 = 0.8;
const BACKGROUND: f64 = 0.25;
/// The lens's blur (Gaussian σ, px): a sharp phone camera's.
const BLUR: f64 = 0.7;

fn srgb(v: f64) -> u8 {
    let e = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (255.0 * e).round().clamp(0.0, 255.0) as u8
}

/// A drawn tag: its 10-cell outline (white border included) `side` px wide, centred at
/// `centre`, turned `deg` clockwise on screen.
struct Drawn {
    image: Vec<u8>,
    width: usize,
    height: usize,
    /// Outer corners of the black square in the detector's order: bottom-left, bottom-right,
    /// top-right, top-left of the upright tag.
    corners: [[f64; 2]; 4],
}

fn draw(width: usize, height: usize, id: u32, side: f64, centre: [f64; 2], deg: f64) -> Drawn {
    draw_on(BACKGROUND, width, height, id, side, centre, deg)
}

/// [`draw`] on a background of the given linear reflectance.
fn draw_on(background: f64, width: usize, height: usize, id: u32, side: f64, centre: [f64; 2], deg: f64) -> Drawn {
    let bm = TagFamily::TAG36H11.bitmap(id).expect("id");
    let cell = side / 10.0;
    let (s, c) = deg.to_radians().sin_cos();
    // Tag cells (u right, v down, origin at the centre) to pixels and back.
    let to_px = |u: f64, v: f64| [centre[0] + cell * (c * u - s * v), centre[1] + cell * (s * u + c * v)];
    let to_tag = |x: f64, y: f64| {
        let (dx, dy) = ((x - centre[0]) / cell, (y - centre[1]) / cell);
        (c * dx + s * dy, -s * dx + c * dy)
    };
    let reflectance = |u: f64, v: f64| -> f64 {
        let (i, j) = ((u + 5.0).floor(), (v + 5.0).floor());
        if !(0.0..10.0).contains(&i) || !(0.0..10.0).contains(&j) {
            return background;
        }
        let (i, j) = (i as usize, j as usize);
        let white = i == 0 || j == 0 || i == 9 || j == 9 || bm.is_white(i - 1, j - 1);
        if white { WHITE } else { BLACK }
    };
    // Linear light over the tag's box, then the lens: a Gaussian blur of σ = BLUR px.
    let r = side * std::f64::consts::FRAC_1_SQRT_2 + 6.0;
    let span = |c: f64, n: usize| ((c - r).floor().max(0.0) as usize, ((c + r).ceil().max(0.0) as usize).min(n));
    let ((x0, x1), (y0, y1)) = (span(centre[0], width), span(centre[1], height));
    let (bw, bh) = (x1.saturating_sub(x0), y1.saturating_sub(y0));
    let mut lin = vec![background; bw * bh];
    for y in 0..bh {
        for x in 0..bw {
            let (px, py) = ((x0 + x) as f64, (y0 + y) as f64);
            let at = |dx: f64, dy: f64| {
                let (u, v) = to_tag(px + dx, py + dy);
                reflectance(u, v)
            };
            let centre = at(0.0, 0.0);
            let corners = [at(-0.5, -0.5), at(0.5, -0.5), at(-0.5, 0.5), at(0.5, 0.5)];
            // Cells are several pixels wide: a pixel whose corners agree with its centre is
            // uniform; the others are covered by a 64-point lattice (positions in 1/64 px
            // steps along both axes, so an edge's coverage is exact to 1/64).
            lin[y * bw + x] = if corners.iter().all(|&c| c == centre) {
                centre
            } else {
                (0..64)
                    .map(|k| at((f64::from(k) + 0.5) / 64.0 - 0.5, f64::from((k * 27) % 64) / 64.0 - 0.5 + 1.0 / 128.0))
                    .sum::<f64>()
                    / 64.0
            };
        }
    }
    let kernel: Vec<f64> = (-3..=3).map(|i| (-f64::from(i * i) / (2.0 * BLUR * BLUR)).exp()).collect();
    let norm: f64 = kernel.iter().sum();
    let blur = |at: &dyn Fn(isize) -> f64| -> f64 {
        kernel.iter().enumerate().map(|(k, w)| w * at(k as isize - 3)).sum::<f64>() / norm
    };
    let clamp = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;
    let rows: Vec<f64> =
        (0..bw * bh).map(|i| blur(&|d| lin[(i / bw) * bw + clamp((i % bw) as isize + d, bw)])).collect();
    let mut image = vec![srgb(background); width * height];
    for y in 0..bh {
        for x in 0..bw {
            image[(y0 + y) * width + x0 + x] = srgb(blur(&|d| rows[clamp(y as isize + d, bh) * bw + x]));
        }
    }
    let corners = [to_px(-4.0, 4.0), to_px(4.0, 4.0), to_px(4.0, -4.0), to_px(-4.0, -4.0)];
    Drawn { image, width, height, corners }
}

fn detect(d: &Drawn, config: DetectorConfig) -> Vec<Detection> {
    Detector::new(config)
        .expect("detector")
        .detect(&ImageView::new(&d.image, d.width, d.height, d.width).expect("view"))
        .expect("detects")
}

fn worst_corner_error(det: &Detection, truth: &[[f64; 2]; 4]) -> f64 {
    det.corners.iter().zip(truth).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max)
}

#[test]
fn large_tags_at_4k_are_found_at_any_turn() {
    for side in [400.0, 1500.0] {
        for deg in [0.0, 10.0, 45.0, 100.0, 225.0, 317.0] {
            let d = draw(3840, 2160, 7, side, [1900.3, 1080.6], deg);
            let dets = detect(&d, DetectorConfig::default());
            assert_eq!(dets.len(), 1, "side {side} px at {deg}°: {} detections", dets.len());
            assert_eq!(dets[0].id, 7);
            let e = worst_corner_error(&dets[0], &d.corners);
            assert!(e < 0.05, "side {side} px at {deg}°: corner off by {e:.3} px");
        }
    }
}

#[test]
fn tags_touching_the_border_are_found_and_cut_ones_never_reported_outside() {
    let (w, h) = (640, 480);
    let side = 100.0;
    // The white border (one cell, 10 px) just inside each edge: found.
    for centre in [[50.5, 240.0], [589.5, 240.0], [320.0, 50.5], [320.0, 429.5]] {
        let d = draw(w, h, 3, side, centre, 0.0);
        let dets = detect(&d, DetectorConfig::default());
        assert_eq!(dets.len(), 1, "tag at {centre:?}");
        assert!(worst_corner_error(&dets[0], &d.corners) < 0.1, "tag at {centre:?}");
    }
    // Cut by an edge or a corner of the frame: not reported, or only with every corner inside.
    for centre in [[20.0, 240.0], [-10.0, 240.0], [630.0, 200.0], [320.0, 475.0], [15.0, 15.0], [600.0, 470.0]] {
        for deg in [0.0, 30.0] {
            let d = draw(w, h, 3, side, centre, deg);
            for det in detect(&d, DetectorConfig::default()) {
                for p in det.corners {
                    assert!(
                        (0.0..=(w - 1) as f64).contains(&p[0]) && (0.0..=(h - 1) as f64).contains(&p[1]),
                        "tag at {centre:?}, {deg}°: corner {p:?} outside the frame"
                    );
                }
            }
        }
    }
}

/// The smallest tag found at decimate 1, 2 and 4, ours against C on the same drawings: every
/// size from 30 px (60 px at decimate 4) down to the first one lost, upright and turned by
/// 30°, printed on white paper. Found means the right id with every corner within 1 px.
#[test]
fn smallest_tags_found_are_no_larger_than_cs() {
    let smallest = |from_px: u32, found: &dyn Fn(&Drawn) -> bool| -> f64 {
        let mut s = f64::NAN;
        // Black-square sides of `from_px` down to 4 px, by half pixels.
        for half_px in (8..=2 * from_px).rev() {
            let black = f64::from(half_px) / 2.0;
            let all = [0.0, 30.0]
                .iter()
                .all(|&deg| found(&draw_on(WHITE, 160, 160, 11, black * 10.0 / 8.0, [80.3, 79.6], deg)));
            if !all {
                break;
            }
            s = black;
        }
        s
    };
    for (decimate, from_px) in [(1.0f32, 30), (2.0, 30), (4.0, 60)] {
        let ours = smallest(from_px, &|d| {
            detect(d, DetectorConfig { quad_decimate: decimate, ..DetectorConfig::default() })
                .iter()
                .any(|t| t.id == 11 && worst_corner_error(t, &d.corners) < 1.0)
        });
        let mut reference =
            ReferenceDetector::new(&ReferenceParams { quad_decimate: decimate, ..ReferenceParams::default() })
                .expect("reference");
        let reference = std::cell::RefCell::new(&mut reference);
        let c = smallest(from_px, &|d| {
            let found = reference.borrow_mut().detect(&d.image, d.width, d.height, d.width).expect("reference");
            found.iter().any(|t| {
                t.id == 11 && t.corners.iter().zip(&d.corners).all(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]) < 1.0)
            })
        });
        let _ = writeln!(
            std::io::stderr(),
            "decimate {decimate}: every tag whose black square is {ours} px or more is found (C: {c} px)"
        );
        assert!(ours.is_finite() && ours <= c, "decimate {decimate}: ours loses tags below {ours} px, C below {c} px");
    }
}
