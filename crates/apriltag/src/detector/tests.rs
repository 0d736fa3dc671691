//! The detector's unit tests on drawn tags: empty and odd frames, the four turns, a mirrored tag, a region of interest,
//! a motion-blurred tag.

use super::edges::{one_edge, ramp_extent};
use super::*;
use crate::config::Roi;

/// A tag drawn axis-aligned: `cell` px per cell, one white cell of quiet zone, on grey.
fn drawn_tag(id: u32, cell: usize, pad: usize) -> (Vec<u8>, usize) {
    let bm = TagFamily::TAG36H11.bitmap(id).expect("id");
    let side = 10 * cell + 2 * pad;
    let mut img = vec![128u8; side * side];
    for y in 0..10 * cell {
        for x in 0..10 * cell {
            let (cx, cy) = (x / cell, y / cell);
            let white = cx == 0 || cy == 0 || cx == 9 || cy == 9 || bm.is_white(cx - 1, cy - 1);
            img[(y + pad) * side + x + pad] = if white { 230 } else { 25 };
        }
    }
    (img, side)
}

fn rotate_cw(img: &[u8], n: usize) -> Vec<u8> {
    let mut out = vec![0u8; n * n];
    for y in 0..n {
        for x in 0..n {
            out[x * n + (n - 1 - y)] = img[y * n + x];
        }
    }
    out
}

fn detector() -> Detector {
    Detector::new(DetectorConfig::default()).expect("defaults")
}

#[test]
fn blank_noisy_tiny_and_odd_frames_give_nothing() {
    let d = detector();
    for (w, h) in [(1, 1), (2, 3), (3, 2), (5, 7), (17, 13), (64, 64)] {
        for fill in [0u8, 255] {
            let img = vec![fill; w * h];
            let v = ImageView::new(&img, w, h, w).expect("view");
            assert!(d.detect(&v).expect("runs").is_empty(), "{w}×{h} of {fill}");
        }
    }
    let mut x = 7u32;
    let noise: Vec<u8> = (0..320 * 240)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 24) as u8
        })
        .collect();
    let v = ImageView::new(&noise, 320, 240, 320).expect("view");
    assert!(d.detect(&v).expect("runs").is_empty(), "pure noise");
}

#[test]
fn all_four_turns_decode_with_corners_in_tag_order() {
    let (img, n) = drawn_tag(7, 8, 20);
    let d = detector();
    let mut turned = img.clone();
    let mut previous_bl: Option<[f64; 2]> = None;
    for turn in 0..4 {
        let v = ImageView::new(&turned, n, n, n).expect("view");
        let dets = d.detect(&v).expect("runs");
        assert_eq!(dets.len(), 1, "turn {turn}: {dets:?}");
        let det = dets[0];
        assert_eq!((det.id, det.hamming), (7, 0));
        // The black square spans pad + cell .. pad + 9·cell; its corners sit on pixel edges.
        let lo = 20.0 + 8.0 - 0.5;
        let hi = 20.0 + 72.0 - 0.5;
        for c in det.corners {
            assert!((c[0] - lo).abs() < 0.3 || (c[0] - hi).abs() < 0.3, "turn {turn}: {c:?}");
            assert!((c[1] - lo).abs() < 0.3 || (c[1] - hi).abs() < 0.3, "turn {turn}: {c:?}");
        }
        // Bottom-left of the upright tag moves a quarter turn clockwise with the image.
        if let Some(p) = previous_bl {
            let c = (n as f64 - 1.0) / 2.0;
            let expected = [c - (p[1] - c), c + (p[0] - c)];
            let bl = det.corners[0];
            assert!(
                (bl[0] - expected[0]).abs() < 0.5 && (bl[1] - expected[1]).abs() < 0.5,
                "turn {turn}: {bl:?} vs {expected:?}"
            );
        } else {
            // Upright: bottom-left is at low x, high y.
            assert!(det.corners[0][0] < 40.0 && det.corners[0][1] > 80.0, "{:?}", det.corners);
        }
        previous_bl = Some(det.corners[0]);
        turned = rotate_cw(&turned, n);
    }
}

#[test]
fn a_mirrored_tag_is_not_read() {
    let (img, n) = drawn_tag(7, 8, 20);
    let mirrored: Vec<u8> = (0..n * n).map(|i| img[(i / n) * n + (n - 1 - i % n)]).collect();
    let dets = detector().detect(&ImageView::new(&mirrored, n, n, n).expect("view")).expect("runs");
    assert!(dets.is_empty(), "{dets:?}");
}

#[test]
fn a_region_of_interest_keeps_full_frame_coordinates() {
    let (tag, n) = drawn_tag(3, 6, 10);
    let (w, h) = (300, 200);
    let mut img = vec![128u8; w * h];
    for y in 0..n {
        img[(y + 90) * w + 150..(y + 90) * w + 150 + n].copy_from_slice(&tag[y * n..(y + 1) * n]);
    }
    let full = detector().detect(&ImageView::new(&img, w, h, w).expect("view")).expect("runs");
    assert_eq!(full.len(), 1);
    let roi = Detector::new(DetectorConfig {
        roi: Some(Roi { x: 140, y: 80, width: 100, height: 100 }),
        ..DetectorConfig::default()
    })
    .expect("roi config");
    let part = roi.detect(&ImageView::new(&img, w, h, w).expect("view")).expect("runs");
    assert_eq!(part.len(), 1);
    for (a, b) in part[0].corners.iter().zip(&full[0].corners) {
        assert!((a[0] - b[0]).abs() < 0.05 && (a[1] - b[1]).abs() < 0.05, "{a:?} vs {b:?}");
    }
    let outside = Detector::new(DetectorConfig {
        roi: Some(Roi { x: 0, y: 0, width: 100, height: 100 }),
        ..DetectorConfig::default()
    })
    .expect("roi config");
    assert!(outside.detect(&ImageView::new(&img, w, h, w).expect("view")).expect("runs").is_empty());
    let too_big = Detector::new(DetectorConfig {
        roi: Some(Roi { x: 250, y: 0, width: 100, height: 100 }),
        ..DetectorConfig::default()
    })
    .expect("roi config");
    assert!(too_big.detect(&ImageView::new(&img, w, h, w).expect("view")).is_err());
    assert!(
        Detector::new(DetectorConfig { quad_sigma: 5.0, ..DetectorConfig::default() }).is_err(),
        "a blur wider than 4 px is refused"
    );
}

#[test]
fn the_refit_takes_one_edge_of_two() {
    // Two edges 12 steps (3 px) apart, the outer one stronger: the one nearest the centre.
    let bump = |k: f64, at: f64, h: f64| h * (-(k - at) * (k - at) / 8.0).exp();
    let g: Vec<f64> = (0..33).map(|k| bump(k as f64, 14.0, 1.0) + bump(k as f64, 26.0, 1.2)).collect();
    let (lo, hi) = one_edge(&g, 16);
    assert!(lo == 0 && (18..=22).contains(&hi), "{lo}..={hi}");
    let (lo, hi) = one_edge(&g, 25);
    assert!((18..=22).contains(&lo) && hi == 32, "{lo}..={hi}");
    // One edge with small wiggles on its tails: the whole profile.
    let g: Vec<f64> = (0..33).map(|k| bump(k as f64, 16.0, 1.0) + 0.04 * ((k % 3) as f64)).collect();
    assert_eq!(one_edge(&g, 16), (0, 32));
    assert_eq!(one_edge(&[0.0; 5], 2), (0, 4));
}

/// sRGB encoding of linear light in [0, 1].
fn srgb(v: f64) -> u8 {
    let e = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (255.0 * e).round().clamp(0.0, 255.0) as u8
}

/// A tag (black square `8 · cell` px wide, turned `deg`) on a `size`² grey frame, smeared by
/// `smear` px as if it moved at constant speed during the exposure: linear light averaged over
/// the exposure (steps of 1/16 px along the motion, 4 points per pixel across it), sRGB-encoded.
/// Returns the image and the black square's corners at mid-exposure.
fn smeared_tag(id: u32, size: usize, cell: f64, deg: f64, smear: [f64; 2]) -> (Vec<u8>, [[f64; 2]; 4]) {
    let bm = TagFamily::TAG36H11.bitmap(id).expect("id");
    let centre = (size as f64 - 1.0) / 2.0;
    let (s, c) = deg.to_radians().sin_cos();
    let reflectance = |x: f64, y: f64| -> f64 {
        let (dx, dy) = ((x - centre) / cell, (y - centre) / cell);
        let (u, v) = (c * dx + s * dy + 5.0, -s * dx + c * dy + 5.0);
        if !(0.0..10.0).contains(&u) || !(0.0..10.0).contains(&v) {
            return 0.3;
        }
        let (i, j) = (u as usize, v as usize);
        let white = i == 0 || j == 0 || i == 9 || j == 9 || bm.is_white(i - 1, j - 1);
        if white { 0.8 } else { 0.04 }
    };
    let length = smear[0].hypot(smear[1]);
    let steps = (length * 16.0).ceil().max(1.0) as usize;
    let mut img = vec![0u8; size * size];
    for (i, p) in img.iter_mut().enumerate() {
        let (x, y) = ((i % size) as f64, (i / size) as f64);
        let mut sum = 0.0;
        for k in 0..steps {
            let t = (k as f64 + 0.5) / steps as f64 - 0.5;
            for (ox, oy) in [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)] {
                sum += reflectance(x + ox - t * smear[0], y + oy - t * smear[1]);
            }
        }
        *p = srgb(sum / (4 * steps) as f64);
    }
    let corner = |u: f64, v: f64| [centre + cell * (c * u - s * v), centre + cell * (s * u + c * v)];
    (img, [corner(-4.0, 4.0), corner(4.0, 4.0), corner(4.0, -4.0), corner(-4.0, -4.0)])
}

/// The farthest a detected corner lies from the nearest truth corner.
fn worst_corner(found: &[[f64; 2]; 4], truth: &[[f64; 2]; 4]) -> f64 {
    found
        .iter()
        .map(|p| truth.iter().map(|q| (p[0] - q[0]).hypot(p[1] - q[1])).fold(f64::INFINITY, f64::min))
        .fold(0.0, f64::max)
}

#[test]
fn a_motion_blurred_tag_is_found_where_it_was_at_mid_exposure() {
    // Smeared 8 and 12 px across cells of 10–15 px: ramps wider than the ±3 px window, whose
    // corners the fit used to leave 0.35–2.55 px off (wherever the quad put the window); now
    // within 0.02 px.
    let d = Detector::new(DetectorConfig { smeared_edges: true, ..DetectorConfig::default() }).expect("valid");
    // The gradient fit alone: the model fit of the border would take over the blurred sides.
    let plain = Detector::new(DetectorConfig { blur_aware_edges: false, ..DetectorConfig::default() }).expect("valid");
    let cases = [
        (12.0, 0.0, 8.0, 0.0),
        (12.0, 17.0, 8.0, 30.0),
        (12.0, 40.0, 8.0, 75.0),
        (10.0, 17.0, 8.0, 0.0),
        (12.0, 17.0, 12.0, 50.0),
        (15.0, 40.0, 12.0, 50.0),
    ];
    let mut worst: f64 = 0.0;
    for (cell, deg, length, dir) in cases {
        let a = f64::to_radians(dir);
        let (img, truth) = smeared_tag(5, 180, cell, deg, [length * a.cos(), length * a.sin()]);
        let dets = d.detect(&ImageView::new(&img, 180, 180, 180).expect("view")).expect("runs");
        assert_eq!(dets.len(), 1, "cell {cell}, {deg}°, smear {length} px at {dir}°");
        let e = worst_corner(&dets[0].corners, &truth);
        assert!(e < 0.05, "cell {cell}, {deg}°, smear {length} px at {dir}°: {e:.3} px");
        // Without the smeared-edge fit (or the border's model), the window stays where the quad
        // put it.
        let old = plain.detect(&ImageView::new(&img, 180, 180, 180).expect("view")).expect("runs");
        if let Some(o) = old.first() {
            worst = worst.max(worst_corner(&o.corners, &truth));
        }
    }
    assert!(
        worst > 0.3,
        "the plain fit was expected to miss a smeared corner by tenths of a pixel, worst {worst:.3} px"
    );
}

#[test]
fn a_ramp_is_read_at_half_its_height() {
    // A plateau on even steps 10..=30 with a shoulder below half its height out to 40.
    let mut p = vec![0.0; 49];
    for k in (10..=30).step_by(2) {
        p[k] = 10.0;
    }
    for k in (32..=40).step_by(2) {
        p[k] = 4.0;
    }
    assert_eq!(ramp_extent(&p, 20, 3), Some((10, 30)));
    // From beside it, within reach.
    assert_eq!(ramp_extent(&p, 35, 3), Some((10, 30)));
    assert_eq!(ramp_extent(&[0.0; 9], 4, 3), None);
}

#[test]
fn a_noisy_smear_nearly_a_cell_wide_is_still_read_as_one_ramp() {
    // A noisy frame (a 2× sensor crop gathers a quarter of the light per pixel): 4 grey levels
    // of noise (sRGB), on a tag smeared 14 px over cells of 18 px (a chewing jaw at 130 mm/s,
    // 220 mm away, at 8 ms). The ramp's width, read from the side's summed gradient over every
    // fourth sample, came out narrower than it is on a noise spike (worst corner 1.06 px off
    // here; 3–5 px on rendered chewing).
    let d = Detector::new(DetectorConfig { smeared_edges: true, ..DetectorConfig::default() }).expect("valid");
    let mut x = 12345u32;
    let mut noise = || {
        // The sum of four uniform numbers (σ = 1/√3), scaled: near-Gaussian with σ = 4 levels.
        (0..4)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                f64::from(x % 1000) / 1000.0 - 0.5
            })
            .sum::<f64>()
            * 4.0
            * 3f64.sqrt()
    };
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for (deg, dir) in [(3.0, 0.0), (10.0, 0.0), (3.0, 20.0)] {
        let a = f64::to_radians(dir);
        let (mut img, truth) = smeared_tag(5, 260, 18.0, deg, [14.0 * a.cos(), 14.0 * a.sin()]);
        for p in &mut img {
            *p = (f64::from(*p) + noise()).round().clamp(0.0, 255.0) as u8;
        }
        let dets = d.detect(&ImageView::new(&img, 260, 260, 260).expect("view")).expect("runs");
        assert_eq!(dets.len(), 1, "{deg}°, smear at {dir}°");
        worst = worst.max(worst_corner(&dets[0].corners, &truth));
        checked += 1;
    }
    assert_eq!(checked, 3);
    assert!(worst < 0.8, "a noisy ramp's corners {worst:.2} px off (1.06 px before the fix)");
}

#[test]
fn quads_shorter_than_asked_are_not_tried() {
    // Tag 7 with 12 px cells (its black square 96 px across) and, beside it, tag 3 with 5 px
    // cells (40 px).
    let (big, nb) = drawn_tag(7, 12, 0);
    let (small, ns) = drawn_tag(3, 5, 0);
    let (w, h) = (nb + ns + 90, nb + 60);
    let mut img = vec![128u8; w * h];
    for y in 0..nb {
        img[(y + 30) * w + 30..(y + 30) * w + 30 + nb].copy_from_slice(&big[y * nb..(y + 1) * nb]);
    }
    for y in 0..ns {
        img[(y + 60) * w + nb + 60..(y + 60) * w + nb + 60 + ns].copy_from_slice(&small[y * ns..(y + 1) * ns]);
    }
    let view = ImageView::new(&img, w, h, w).expect("view");
    let d = detector();
    let search = |min_quad_px: f64| Search { roi: None, smeared: false, quad_decimate: 2.0, min_quad_px };
    let all = d.search(&view, &search(0.0)).expect("runs");
    let tried_all = d.last_stages().quads;
    assert_eq!(all.iter().map(|t| t.id).collect::<Vec<_>>(), [3, 7], "both tags, every quad tried");
    let large = d.search(&view, &search(48.0)).expect("runs");
    let tried_large = d.last_stages().quads;
    assert_eq!(large, all[1..], "the large tag alone, its corners as before, from 48 px");
    assert_eq!((tried_all, tried_large), (2, 1), "quads tried");
    assert!(d.search(&view, &search(130.0)).expect("runs").is_empty(), "none as long as 130 px");
    assert_eq!(d.last_stages().quads, 0);
}

#[test]
fn the_quads_a_decoded_tags_data_cells_make_are_passed_over() {
    // Tag 0 with 12 px cells: a block of its data cells makes a quad of its own.
    let (img, n, _) = super::border::tests::drawn_through(0, 12.0, 12.0, 1.0, 0.8, 1.0, crate::ToneCurve::Srgb);
    let view = ImageView::new(&img, n, n, n).expect("view");
    let mut tried = Vec::new();
    for linear_edges in [false, true] {
        let d = Detector::new(DetectorConfig { linear_edges, ..DetectorConfig::default() }).expect("valid");
        let found = d.detect(&view).expect("runs");
        assert_eq!(found.iter().map(|t| t.id).collect::<Vec<_>>(), [0], "linear edges {linear_edges}");
        tried.push(d.last_stages().quads);
    }
    assert_eq!(tried, [2, 1], "quads tried: C's edge fit tries every quad, ours not the data cells'");
}
