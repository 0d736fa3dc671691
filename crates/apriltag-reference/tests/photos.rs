//! The renderer's tags against the reference C library's decoding of real photos.
//!
//! For every tag the reference library (AprilTag 3.3) found in the real photos of
//! `../shared/data/photos`, map the renderer's texture onto the detected corners and read the
//! photo back: every data cell must agree with the cell the renderer prints there, and no other
//! orientation of our pattern may fit. This pins the codebook, the bit layout and the corner
//! order to the reference's, independently of our own detector.

use jawtrack_apriltag::TagFamily;
use jawtrack_synth::render::{INK_ALBEDO, tag_texture};
use jawtrack_test_support::{read_tag, say_skipped, shared_data};

#[test]
fn rendered_tags_match_the_reference_decoding_of_real_photos() {
    let Some(data) = shared_data() else {
        say_skipped("rendered tags vs reference photos: ../shared/data is not present");
        return;
    };
    let dir = data.join("photos");
    let text =
        std::fs::read_to_string(dir.join("reference_detections.jsonl")).expect("reference detections in ../shared");
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
            let ours = TagFamily::TAG36H11.bitmap(id).expect("tag36h11 id");
            let Some(reading) = read_tag(&img, &corners) else { continue };
            // Compare with the renderer's texture in each of the four orientations.
            let mut mismatches = [0usize; 4];
            let mut pattern = ours;
            for m in mismatches.iter_mut() {
                for &(x, y) in TagFamily::TAG36H11.bit_cells {
                    let (x, y) = (usize::from(x), usize::from(y));
                    let (_, _, albedo) =
                        tag_texture(&pattern, -1.0 + (x as f64 + 0.5) / 4.0, -1.0 + (y as f64 + 0.5) / 4.0)
                            .expect("inside");
                    let printed_white = albedo > INK_ALBEDO;
                    if printed_white != reading.is_white(x, y) {
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
    eprintln!(
        "checked {checked} reference detections: {exact} read back within their reported hamming, {best_is_upright} fit only upright"
    );
    assert!(checked >= 100, "too few reference detections read: {checked}");
    assert!(exact as f64 >= 0.97 * checked as f64, "{exact}/{checked} match");
    assert_eq!(best_is_upright, checked, "the corner order must match the reference's");
}
