//! Tags drawn under a known blur, and the border fit measured on them.

use crate::{Detection, Detector, DetectorConfig, ImageView, TagFamily, ToneCurve};

/// Tag `id` drawn flat with `cell` px cells, turned `deg`, its quiet zone `margin` cells
/// wide on a background of reflectance `beyond`, blurred by a Gaussian of σ `blur` px (in
/// linear light, exact pixel coverage), encoded as sRGB; and its true corners.
fn drawn(id: u32, cell: f64, deg: f64, margin: f64, beyond: f64, blur: f64) -> (Vec<u8>, usize, [[f64; 2]; 4]) {
    drawn_through(id, cell, deg, margin, beyond, blur, ToneCurve::Srgb)
}

/// As [`drawn`], encoded through `curve`.
pub(in crate::detector) fn drawn_through(
    id: u32,
    cell: f64,
    deg: f64,
    margin: f64,
    beyond: f64,
    blur: f64,
    curve: ToneCurve,
) -> (Vec<u8>, usize, [[f64; 2]; 4]) {
    let bm = TagFamily::TAG36H11.bitmap(id).expect("id");
    let n = (cell * (8.0 + 2.0 * margin) * 1.5 + 12.0 * blur + 40.0) as usize;
    let centre = [n as f64 / 2.0 + 0.31, n as f64 / 2.0 - 0.17];
    let (s, c) = deg.to_radians().sin_cos();
    let reflectance = |x: f64, y: f64| {
        let (dx, dy) = ((x - centre[0]) / cell, (y - centre[1]) / cell);
        let (u, v) = (c * dx + s * dy + 4.0, -s * dx + c * dy + 4.0);
        if u < -margin || v < -margin || u >= 8.0 + margin || v >= 8.0 + margin {
            return beyond;
        }
        if u < 0.0 || v < 0.0 || u >= 8.0 || v >= 8.0 {
            return 0.8;
        }
        if bm.is_white(u as usize, v as usize) { 0.8 } else { 0.03 }
    };
    const SUB: usize = 8;
    let mut lin = vec![0.0f64; n * n];
    for y in 0..n {
        for x in 0..n {
            let mut acc = 0.0;
            for i in 0..SUB {
                for j in 0..SUB {
                    let (ox, oy) = ((i as f64 + 0.5) / SUB as f64 - 0.5, (j as f64 + 0.5) / SUB as f64 - 0.5);
                    acc += reflectance(x as f64 + ox, y as f64 + oy);
                }
            }
            lin[y * n + x] = acc / (SUB * SUB) as f64;
        }
    }
    if blur > 0.0 {
        let r = (4.0 * blur).ceil() as isize;
        let k: Vec<f64> = (-r..=r).map(|i| (-((i * i) as f64) / (2.0 * blur * blur)).exp()).collect();
        let norm: f64 = k.iter().sum();
        let clamp = |i: isize| i.clamp(0, n as isize - 1) as usize;
        let rows: Vec<f64> = (0..n * n)
            .map(|i| {
                let (y, x) = (i / n, (i % n) as isize);
                k.iter().enumerate().map(|(j, w)| w * lin[y * n + clamp(x + j as isize - r)]).sum::<f64>() / norm
            })
            .collect();
        lin = (0..n * n)
            .map(|i| {
                let (y, x) = ((i / n) as isize, i % n);
                k.iter().enumerate().map(|(j, w)| w * rows[clamp(y + j as isize - r) * n + x]).sum::<f64>() / norm
            })
            .collect();
    }
    let to_px = |u: f64, v: f64| {
        let (du, dv) = (u - 4.0, v - 4.0);
        [centre[0] + cell * (c * du - s * dv), centre[1] + cell * (s * du + c * dv)]
    };
    let corners = [to_px(0.0, 8.0), to_px(8.0, 8.0), to_px(8.0, 0.0), to_px(0.0, 0.0)];
    (lin.iter().map(|&v| (255.0 * curve.encode(v)).round() as u8).collect(), n, corners)
}

fn detect(img: &[u8], n: usize, border: bool) -> Vec<Detection> {
    let config = DetectorConfig { blur_aware_edges: border, ..DetectorConfig::default() };
    Detector::new(config).expect("valid").detect(&ImageView::new(img, n, n, n).expect("view")).expect("runs")
}

fn worst(d: &Detection, truth: &[[f64; 2]; 4]) -> f64 {
    d.corners.iter().zip(truth).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max)
}

/// Tags drawn flat with cells of 3–20 px under blurs of 0–5 px: where the blur nears a
/// sixth of a cell the gradient fit is pulled off by the neighbouring cells (to 0.7 px),
/// the model fit is not; and the blur is read back.
#[test]
fn blurred_small_tags_keep_their_corners_and_their_blur_is_read() {
    // (cell px, blur σ px, quiet zone cells, reflectance beyond it, worst corner error
    // allowed (px), the gradient fit's own at least (px): the case is a real test of it).
    let cases = [
        (7.0, 0.0, 1.0, 0.8, 0.02, 0.0),
        (7.0, 1.0, 1.0, 0.8, 0.02, 0.0),
        (20.0, 1.0, 1.0, 0.2, 0.02, 0.0),
        (7.0, 1.3, 1.0, 0.2, 0.02, 0.02),
        (7.0, 1.6, 1.0, 0.2, 0.02, 0.05),
        (7.0, 2.0, 1.0, 0.2, 0.03, 0.2),
        (4.0, 0.7, 1.0, 0.2, 0.02, 0.05),
        (4.0, 1.0, 1.0, 0.2, 0.02, 0.1),
        (3.0, 0.7, 1.0, 0.2, 0.04, 0.15),
        (7.0, 2.6, 1.0, 0.8, 0.06, 0.4),
        (7.0, 2.6, 1.0, 0.2, 0.08, 0.6),
        (7.0, 2.6, 3.0, 0.2, 0.06, 0.4),
        (14.0, 5.0, 1.0, 0.2, 0.3, 3.0),
    ];
    for (cell, blur, margin, beyond, allowed, gradient_at_least) in cases {
        let (img, n, truth) = drawn(7, cell, 12.0, margin, beyond, blur);
        let [gradient] = detect(&img, n, false)[..] else { panic!("cell {cell}, blur {blur}: one tag") };
        let [model] = detect(&img, n, true)[..] else { panic!("cell {cell}, blur {blur}: one tag") };
        let (g, m) = (worst(&gradient, &truth), worst(&model, &truth));
        let read = model.blur_px.expect("measured");
        let case =
            format!("cell {cell} px, blur {blur} px: gradient {g:.3} px, model {m:.3} px, blur read {read:.2} px");
        assert!(m <= allowed && g >= gradient_at_least, "{case}");
        assert!((read - blur).abs() <= 0.15 + 0.05 * blur, "{case}");
        assert_eq!(gradient.blur_px, None, "not measured without the model fit");
    }
}
