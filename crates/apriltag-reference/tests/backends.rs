//! Our detector and the C library through the one backend interface, `TagDetector`: on every
//! fixture frame both find the tags the ground truth says are there (and hardly any other), and each backend's homography
//! maps the tag's corners in tag coordinates onto the corners it reports, so a caller can use
//! either backend's detections alike.

use jawtrack_apriltag::{Detection, Detector, DetectorConfig, ImageView, TagDetector};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use jawtrack_synth::GroundTruth;
use jawtrack_test_support::{FIXTURE_FRAMES, assert_every_fixture_frame, fixture_sets, set_name};

/// The tag-coordinate corners in the detection order (bottom-left, bottom-right, top-right,
/// top-left of the upright tag; y down).
const TAG_CORNERS: [[f64; 2]; 4] = [[-1.0, 1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, -1.0]];

fn project(h: &[f64; 9], [x, y]: [f64; 2]) -> [f64; 2] {
    let w = h[6] * x + h[7] * y + h[8];
    [(h[0] * x + h[1] * y + h[2]) / w, (h[3] * x + h[4] * y + h[5]) / w]
}

/// The largest distance (px) between a detection's corners and its homography's image of the
/// tag's corners.
fn homography_gap(d: &Detection) -> f64 {
    TAG_CORNERS
        .iter()
        .zip(&d.corners)
        .map(|(&t, c)| {
            let p = project(&d.homography, t);
            (p[0] - c[0]).hypot(p[1] - c[1])
        })
        .fold(0.0, f64::max)
}

#[test]
fn both_backends_detect_the_fixture_tags_through_one_interface() {
    let mut ours = Detector::new(DetectorConfig::default()).expect("our detector");
    let mut c = ReferenceDetector::new(&ReferenceParams::default()).expect("the C detector");
    let mut backends: [&mut dyn TagDetector; 2] = [&mut ours, &mut c];
    assert_eq!(backends.each_ref().map(|b| b.backend_name()), ["jawtrack", "apriltag-c"]);
    let (mut per_set, mut checked) = (Vec::new(), [0usize; 2]);
    let (mut wanted, mut found_wanted, mut false_positives) = ([0usize; 2], [0usize; 2], [0usize; 2]);
    for set in fixture_sets() {
        let mut frames = 0;
        let gt: GroundTruth =
            serde_json::from_str(&std::fs::read_to_string(set.join("ground_truth.json")).expect("truth"))
                .expect("json");
        for f in &gt.frames {
            let img = image::open(set.join(&f.file)).expect("png").to_luma8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            let frame = ImageView::new(img.as_raw(), w, h, w).expect("view");
            for (b, backend) in backends.iter_mut().enumerate() {
                let name = backend.backend_name();
                let found = backend.detect_tags(&frame).expect("a valid frame");
                for d in &found {
                    false_positives[b] += usize::from(!f.tags.iter().any(|t| t.id == d.id));
                    let gap = homography_gap(d);
                    assert!(gap < 0.01, "{name}: tag {} in {}: homography {gap:.4} px from its corners", d.id, f.file);
                    checked[b] += 1;
                }
                for t in f.tags.iter().filter(|t| t.should_be_detected()) {
                    wanted[b] += 1;
                    found_wanted[b] += usize::from(found.iter().any(|d| d.id == t.id));
                }
            }
            frames += 1;
        }
        per_set.push((set_name(&set), frames));
    }
    assert_every_fixture_frame("both backends", &per_set);
    let total: usize = FIXTURE_FRAMES.iter().map(|(_, n)| n).sum();
    assert!(checked.iter().all(|&n| n >= 2 * total), "detections checked per backend: {checked:?}");
    // Both find nearly every tag the truth calls detectable (their recall is compared in
    // detail by tests/c_on_fixtures.rs and the apriltag crate's detector_vs_c.rs).
    for b in 0..2 {
        let recall = found_wanted[b] as f64 / wanted[b] as f64;
        println!(
            "backend {b}: {} of {} detectable tags found ({recall:.3}), {} false positives in {} detections",
            found_wanted[b], wanted[b], false_positives[b], checked[b]
        );
        assert!(recall > 0.9, "backend {b}: recall {recall:.3}");
        assert!(false_positives[b] * 100 < checked[b], "backend {b}: {} false positives", false_positives[b]);
    }
}
