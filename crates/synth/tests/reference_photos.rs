//! The renderer's tags against the reference C library's decoding of real photos.
//!
//! For every tag the reference library (AprilTag 3.3) found in the real photos of
//! `../shared/data/photos`, map the renderer's texture onto the detected corners and read the
//! photo back: every data cell must agree with the cell the renderer prints there, and no other
//! orientation of our pattern may fit. This pins the codebook, the bit layout and the corner
//! order to the reference's, independently of our own detector.

use jawtrack_apriltag::Tag36h11;
use jawtrack_synth::render::{INK_ALBEDO, tag_texture};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use std::path::PathBuf;

fn shared() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/photos")
}

/// The homography mapping tag coordinates to pixels through the four corners (DLT).
fn homography(corners: &[[f64; 2]; 4]) -> Matrix3<f64> {
    let tag = [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)];
    let mut a = SMatrix::<f64, 8, 8>::zeros();
    let mut b = SVector::<f64, 8>::zeros();
    for i in 0..4 {
        let (x, y) = tag[i];
        let [u, v] = corners[i];
        a.row_mut(2 * i).copy_from_slice(&[x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y]);
        a.row_mut(2 * i + 1).copy_from_slice(&[0.0, 0.0, 0.0, x, y, 1.0, -v * x, -v * y]);
        b[2 * i] = u;
        b[2 * i + 1] = v;
    }
    let h = a.lu().solve(&b).expect("four corners in general position");
    Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], 1.0)
}

fn bilinear(img: &image::GrayImage, x: f64, y: f64) -> Option<f64> {
    let (w, h) = img.dimensions();
    if x < 0.0 || y < 0.0 || x > f64::from(w - 1) || y > f64::from(h - 1) {
        return None;
    }
    let (x0, y0) = (x.floor() as u32, y.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - f64::from(x0), y - f64::from(y0));
    let p = |x, y| f64::from(img.get_pixel(x, y)[0]);
    Some(p(x0, y0) * (1.0 - fx) * (1.0 - fy) + p(x1, y0) * fx * (1.0 - fy) + p(x0, y1) * (1.0 - fx) * fy + p(x1, y1) * fx * fy)
}

/// Mean photo value over the central half of the cell around tag coordinates (u, v).
fn cell_mean(img: &image::GrayImage, h: &Matrix3<f64>, u: f64, v: f64) -> Option<f64> {
    let mut sum = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let (du, dv) = ((f64::from(i) - 1.0) * 0.06, (f64::from(j) - 1.0) * 0.06);
            let p = h * Vector3::new(u + du, v + dv, 1.0);
            sum += bilinear(img, p.x / p.z, p.y / p.z)?;
        }
    }
    Some(sum / 9.0)
}

#[test]
fn rendered_tags_match_the_reference_decoding_of_real_photos() {
    let dir = shared();
    let Ok(text) = std::fs::read_to_string(dir.join("reference_detections.jsonl")) else {
        eprintln!("SKIPPED: {} not present", dir.display());
        return;
    };
    let (mut checked, mut exact, mut best_is_upright) = (0usize, 0usize, 0usize);
    for line in text.lines() {
        let rec: serde_json::Value = serde_json::from_str(line).expect("jsonl");
        if rec["params"]["quad_decimate"].as_f64() != Some(1.0) {
            continue;
        }
        let path = dir.join(rec["path"].as_str().expect("path"));
        let img = image::open(&path).expect("photo decodes").to_luma8();
        for det in rec["detections"].as_array().expect("detections") {
            let id = det["id"].as_u64().expect("id") as u32;
            let hamming = det["hamming"].as_u64().expect("hamming") as usize;
            let corners: [[f64; 2]; 4] = serde_json::from_value(det["corners"].clone()).expect("corners");
            let h = homography(&corners);
            let ours = Tag36h11::bitmap(id).expect("tag36h11 id");
            // Read the 8×8 cells; the threshold sits between the black border and the white
            // quiet zone around it.
            let at = |cx: usize, cy: usize| cell_mean(&img, &h, -1.0 + (cx as f64 + 0.5) / 4.0, -1.0 + (cy as f64 + 0.5) / 4.0);
            let Some(cells) = (0..64).map(|i| at(i % 8, i / 8)).collect::<Option<Vec<f64>>>() else { continue };
            let quiet: Option<Vec<f64>> = (0..8)
                .flat_map(|i| {
                    let t = -1.0 + (i as f64 + 0.5) / 4.0;
                    [(t, -1.125), (t, 1.125), (-1.125, t), (1.125, t)]
                })
                .map(|(u, v)| cell_mean(&img, &h, u, v))
                .collect();
            let Some(quiet) = quiet else { continue };
            let border: Vec<f64> = (0..64).filter(|i| i % 8 == 0 || i % 8 == 7 || i / 8 == 0 || i / 8 == 7).map(|i| cells[i]).collect();
            let black = border.iter().sum::<f64>() / border.len() as f64;
            let white = quiet.iter().sum::<f64>() / quiet.len() as f64;
            let threshold = 0.5 * (black + white);
            // Compare with the renderer's texture in each of the four orientations.
            let mut mismatches = [0usize; 4];
            let mut pattern = ours;
            for m in mismatches.iter_mut() {
                for &(x, y) in Tag36h11::bit_cells() {
                    let (x, y) = (usize::from(x), usize::from(y));
                    let (_, _, albedo) = tag_texture(&pattern, -1.0 + (x as f64 + 0.5) / 4.0, -1.0 + (y as f64 + 0.5) / 4.0).expect("inside");
                    let printed_white = albedo > INK_ALBEDO;
                    if printed_white != (cells[y * 8 + x] > threshold) {
                        *m += 1;
                    }
                }
                pattern = pattern.rotated_cw();
            }
            checked += 1;
            if mismatches[0] <= hamming {
                exact += 1;
            }
            if mismatches[0] < mismatches[1..].iter().copied().min().unwrap_or(usize::MAX) {
                best_is_upright += 1;
            }
        }
    }
    eprintln!("checked {checked} reference detections: {exact} read back within their reported hamming, {best_is_upright} fit only upright");
    assert!(checked >= 100, "too few reference detections read: {checked}");
    assert!(exact as f64 >= 0.97 * checked as f64, "{exact}/{checked} match");
    assert_eq!(best_is_upright, checked, "the corner order must match the reference's");
}
