//! Tag families other than tag36h11: tag25h9 and tag16h5 tags drawn in perspective, sharp
//! and defocused, are found with their corners where they were drawn, by a detector set to
//! their family and by no other; the C library finds the same tags, and under C's settings our
//! corners are C's. The built-in codebooks are the C library's own.

use jawtrack_apriltag::{Detection, Detector, DetectorConfig, ImageView, TagFamily};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use jawtrack_synth::post::srgb_encode;
use nalgebra::{Matrix3, Vector3};

/// Linear reflectances of ink, paper and the background.
const BLACK: f64 = 0.04;
const WHITE: f64 = 0.8;
const BACKGROUND: f64 = 0.3;
const WIDTH: usize = 960;
const HEIGHT: usize = 640;

fn srgb(v: f64) -> u8 {
    (255.0 * srgb_encode(v)).round().clamp(0.0, 255.0) as u8
}

/// One tag to draw: its id, cell size (px), centre, turn (degrees clockwise), perspective
/// (the homography's bottom row, per cell) and the lens's blur (σ, px).
struct Placement {
    id: u32,
    cell: f64,
    centre: [f64; 2],
    deg: f64,
    perspective: [f64; 2],
    blur: f64,
}

/// Tag cells (origin at the tag's centre, y down) to pixels.
fn homography(p: &Placement) -> Matrix3<f64> {
    let (s, c) = p.deg.to_radians().sin_cos();
    let place = Matrix3::new(p.cell * c, -p.cell * s, p.centre[0], p.cell * s, p.cell * c, p.centre[1], 0.0, 0.0, 1.0);
    place * Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, p.perspective[0], p.perspective[1], 1.0)
}

fn apply(h: &Matrix3<f64>, x: f64, y: f64) -> [f64; 2] {
    let q = h * Vector3::new(x, y, 1.0);
    [q.x / q.z, q.y / q.z]
}

/// A drawn tag's id and corners.
type Truth = (u32, [[f64; 2]; 4]);

/// Draws each tag in linear light with 8×8 samples per pixel, blurs it by its lens, and
/// encodes the frame as sRGB. Returns the frame and each tag's corners (bottom-left,
/// bottom-right, top-right, top-left of the upright tag, as the detector reports them).
fn draw(family: &TagFamily, tags: &[Placement]) -> (Vec<u8>, Vec<Truth>) {
    let mut lin = vec![BACKGROUND; WIDTH * HEIGHT];
    let mut truth = Vec::new();
    let (n, total) = (family.width_at_border as f64, family.total_width as f64);
    for t in tags {
        let bm = family.bitmap(t.id).expect("id in the family");
        let h = homography(t);
        let inv = h.try_inverse().expect("invertible");
        let reflectance = |x: f64, y: f64| {
            let [u, v] = apply(&inv, x, y);
            let (i, j) = ((u + total / 2.0).floor(), (v + total / 2.0).floor());
            if !(0.0..total).contains(&i) || !(0.0..total).contains(&j) {
                return None;
            }
            let (i, j) = (i as usize, j as usize);
            let quiet = i == 0 || j == 0 || i + 1 == total as usize || j + 1 == total as usize;
            Some(if quiet || bm.is_white(i - 1, j - 1) { WHITE } else { BLACK })
        };
        let mut layer = vec![f64::NAN; WIDTH * HEIGHT];
        let r = t.cell * total;
        let (x0, x1) = ((t.centre[0] - r).max(0.0) as usize, ((t.centre[0] + r) as usize).min(WIDTH));
        let (y0, y1) = ((t.centre[1] - r).max(0.0) as usize, ((t.centre[1] + r) as usize).min(HEIGHT));
        for y in y0..y1 {
            for x in x0..x1 {
                let (mut sum, mut hits) = (0.0, 0);
                for k in 0..64 {
                    let (dx, dy) = ((f64::from(k % 8) + 0.5) / 8.0 - 0.5, (f64::from(k / 8) + 0.5) / 8.0 - 0.5);
                    let v = reflectance(x as f64 + dx, y as f64 + dy);
                    sum += v.unwrap_or(BACKGROUND);
                    hits += usize::from(v.is_some());
                }
                if hits > 0 {
                    layer[y * WIDTH + x] = sum / 64.0;
                }
            }
        }
        let blurred = gaussian(&layer, t.blur);
        for (out, (&b, &drawn)) in lin.iter_mut().zip(blurred.iter().zip(&layer)) {
            if drawn.is_finite() || b.is_finite() {
                *out = if b.is_finite() { b } else { drawn };
            }
        }
        let corner = |u: f64, v: f64| apply(&h, u * n / 2.0, v * n / 2.0);
        truth.push((t.id, [corner(-1.0, 1.0), corner(1.0, 1.0), corner(1.0, -1.0), corner(-1.0, -1.0)]));
    }
    (lin.iter().map(|&v| srgb(v)).collect(), truth)
}

/// A separable Gaussian blur of the drawn layer (`NaN` where nothing was drawn counts as
/// background); `NaN` stays where the blurred tag does not reach.
fn gaussian(layer: &[f64], sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f64> = (-r..=r).map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp()).collect();
    let norm: f64 = kernel.iter().sum();
    let pass = |src: &[f64], step: (isize, isize)| -> Vec<f64> {
        let mut out = vec![f64::NAN; WIDTH * HEIGHT];
        for y in 0..HEIGHT as isize {
            for x in 0..WIDTH as isize {
                let mut any = false;
                let mut acc = 0.0;
                for (k, w) in kernel.iter().enumerate() {
                    let d = k as isize - r;
                    let (xx, yy) =
                        ((x + d * step.0).clamp(0, WIDTH as isize - 1), (y + d * step.1).clamp(0, HEIGHT as isize - 1));
                    let v = src[yy as usize * WIDTH + xx as usize];
                    any |= v.is_finite();
                    acc += w * if v.is_finite() { v } else { BACKGROUND };
                }
                if any {
                    out[y as usize * WIDTH + x as usize] = acc / norm;
                }
            }
        }
        out
    };
    pass(&pass(layer, (1, 0)), (0, 1))
}

/// Four tags of `family`: upright and sharp; turned and tilted; steeply tilted and small; and
/// large and defocused (blur over a fifth of a cell, where the border model takes over).
fn scene(family: &TagFamily) -> Vec<Placement> {
    let last = family.count() as u32 - 1;
    vec![
        Placement { id: 0, cell: 14.0, centre: [180.0, 160.0], deg: 0.0, perspective: [0.0, 0.0], blur: 0.7 },
        Placement { id: 7, cell: 12.0, centre: [520.0, 170.0], deg: 33.0, perspective: [0.03, -0.02], blur: 0.8 },
        Placement { id: last, cell: 9.0, centre: [200.0, 470.0], deg: 160.0, perspective: [-0.05, 0.04], blur: 0.7 },
        Placement { id: 13, cell: 20.0, centre: [640.0, 450.0], deg: 250.0, perspective: [0.01, 0.02], blur: 4.0 },
    ]
}

fn detect(config: DetectorConfig, image: &[u8]) -> Vec<Detection> {
    let view = ImageView::new(image, WIDTH, HEIGHT, WIDTH).expect("view");
    Detector::new(config).expect("detector").detect(&view).expect("detect")
}

fn worst_corner_error(found: &[[f64; 2]; 4], truth: &[[f64; 2]; 4]) -> f64 {
    found.iter().zip(truth).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max)
}

#[test]
fn other_families_are_found_where_they_were_drawn() {
    let mut checked = 0;
    for family in [TagFamily::TAG25H9, TagFamily::TAG16H5] {
        let (image, truth) = draw(&family, &scene(&family));
        let ours = detect(DetectorConfig { family, ..DetectorConfig::default() }, &image);
        let ids: Vec<u32> = ours.iter().map(|d| d.id).collect();
        let mut want: Vec<u32> = truth.iter().map(|t| t.0).collect();
        want.sort_unstable();
        assert_eq!(ids, want, "{}: ids found", family.name);
        for (id, corners) in &truth {
            let d = ours.iter().find(|d| d.id == *id).expect("found");
            let err = worst_corner_error(&d.corners, corners);
            println!("{} tag {id}: worst corner {err:.3} px, blur {:?}", family.name, d.blur_px);
            assert!(err < 0.15, "{} tag {id}: a corner is {err:.3} px from where it was drawn", family.name);
            checked += 1;
        }
        // The defocused tag's blur is measured through its own family's border.
        let defocused = ours.iter().find(|d| d.id == 13).and_then(|d| d.blur_px).expect("blur measured");
        assert!((defocused - 4.0).abs() < 0.4, "{}: blur {defocused:.2} px read for 4 px", family.name);
        // A tag36h11 detector finds none of them.
        let as_36h11 = detect(DetectorConfig::default(), &image);
        assert!(
            as_36h11.is_empty(),
            "{} read as tag36h11: {:?}",
            family.name,
            as_36h11.iter().map(|d| d.id).collect::<Vec<_>>()
        );
    }
    assert_eq!(checked, 8);
}

#[test]
fn tag36h11_is_not_read_as_another_family() {
    let (image, truth) = draw(&TagFamily::TAG36H11, &scene(&TagFamily::TAG36H11));
    assert_eq!(detect(DetectorConfig::default(), &image).len(), truth.len());
    let other = detect(DetectorConfig { family: TagFamily::TAG25H9, ..DetectorConfig::default() }, &image);
    assert!(other.is_empty(), "tag36h11 read as tag25h9: {:?}", other.iter().map(|d| d.id).collect::<Vec<_>>());
    // tag16h5's distance of 5 with two bits corrected leaves 16-bit patterns that the inside
    // of a larger tag can match: the C library reads the same tags there, as ours does.
    let family = TagFamily::TAG16H5;
    let ours = detect(DetectorConfig { family, ..DetectorConfig::reference() }, &image);
    let mut c = ReferenceDetector::with_family(&ReferenceParams::default(), &family).expect("C detector");
    let theirs = c.detect(&image, WIDTH, HEIGHT, WIDTH).expect("C detect");
    println!(
        "tag36h11 frame read as tag16h5: ours {:?}, C {:?}",
        ours.iter().map(|d| d.id).collect::<Vec<_>>(),
        theirs.iter().map(|d| d.id).collect::<Vec<_>>()
    );
    assert_eq!(ours.iter().map(|d| d.id).collect::<Vec<_>>(), theirs.iter().map(|d| d.id).collect::<Vec<_>>());
}

#[test]
fn the_c_library_agrees_on_other_families() {
    let mut compared = 0;
    for family in [TagFamily::TAG25H9, TagFamily::TAG16H5] {
        let (image, truth) = draw(&family, &scene(&family));
        let mut c = ReferenceDetector::with_family(&ReferenceParams::default(), &family).expect("C detector");
        let theirs = c.detect(&image, WIDTH, HEIGHT, WIDTH).expect("C detect");
        let ours = detect(DetectorConfig { family, ..DetectorConfig::reference() }, &image);
        let ids = |v: Vec<u32>| {
            let mut v = v;
            v.sort_unstable();
            v
        };
        assert_eq!(
            ids(theirs.iter().map(|d| d.id).collect()),
            ids(truth.iter().map(|t| t.0).collect()),
            "{}",
            family.name
        );
        assert_eq!(ours.len(), theirs.len(), "{}", family.name);
        for t in &theirs {
            let o = ours.iter().find(|d| d.id == t.id).expect("same tag");
            let err = worst_corner_error(&o.corners, &t.corners);
            assert!(err < 1e-6, "{} tag {}: ours under C's settings is {err:e} px from C's", family.name, t.id);
            compared += 1;
        }
    }
    assert_eq!(compared, 8);
}

#[test]
fn built_in_codebooks_are_the_c_librarys() {
    for family in TagFamily::ALL {
        let c = ReferenceDetector::with_family(&ReferenceParams::default(), &family).expect("C family").family();
        assert_eq!(c.codes, family.codes, "{} codes", family.name);
        assert_eq!(c.bit_cells, family.bit_cells, "{} bit cells", family.name);
        assert_eq!(c.min_hamming, family.min_hamming, "{}", family.name);
        assert_eq!((c.width_at_border, c.total_width), (family.width_at_border, family.total_width), "{}", family.name);
        assert!(!c.reversed_border, "{}", family.name);
    }
}
