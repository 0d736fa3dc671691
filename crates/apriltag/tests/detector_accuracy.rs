//! Corner accuracy against ground truth on the rendered fixtures, ours side by side with the
//! reference C library on the same frames (issue 3's target: median error no worse than C's on
//! rendered frames, and at most 0.1 px on sharp ones).

use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use jawtrack_synth::GroundTruth;
use jawtrack_test_support::{assert_every_fixture_frame, fixture_sets, set_name};
use std::io::Write as _;

/// The median of a list of errors (NaN for none).
fn median(v: &[f64]) -> f64 {
    jawtrack_pose::median(v.iter().copied()).unwrap_or(f64::NAN)
}

#[test]
fn corners_are_at_least_as_accurate_as_the_reference() {
    for decimate in [2.0f32, 1.0] {
        check_at(decimate);
    }
}

fn check_at(decimate: f32) {
    let mut c = ReferenceDetector::new(&ReferenceParams { quad_decimate: decimate, ..ReferenceParams::default() })
        .expect("reference");
    let mut checked = Vec::new();
    for set in fixture_sets() {
        let gt: GroundTruth =
            serde_json::from_str(&std::fs::read_to_string(set.join("ground_truth.json")).expect("truth"))
                .expect("json");
        // Frames encoded with sRGB are refined in linear light; linear frames as they are.
        let ours = Detector::new(DetectorConfig {
            quad_decimate: decimate,
            linear_edges: gt.realism.gamma,
            ..DetectorConfig::default()
        })
        .expect("detector");
        // Errors over every tag we find, and over the tags both find (the fair comparison).
        let (mut ours_all, mut ours_err, mut c_err) = (Vec::new(), Vec::new(), Vec::new());
        let (mut want, mut ours_found, mut c_found, mut frames) = (0, 0, 0, 0);
        for f in &gt.frames {
            let img = image::open(set.join(&f.file)).expect("png").to_luma8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            let mine = ours.detect(&ImageView::new(img.as_raw(), w, h, w).expect("view")).expect("detects");
            let theirs = c.detect(img.as_raw(), w, h, w).expect("reference");
            for t in f.tags.iter().filter(|t| t.should_be_detected()) {
                want += 1;
                let err = |corners: &[[f64; 2]; 4]| -> Vec<f64> {
                    corners.iter().zip(&t.corners).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).collect()
                };
                let (m, r) = (mine.iter().find(|d| d.id == t.id), theirs.iter().find(|d| d.id == t.id));
                ours_found += usize::from(m.is_some());
                c_found += usize::from(r.is_some());
                if let Some(m) = m {
                    ours_all.extend(err(&m.corners));
                }
                if let (Some(m), Some(r)) = (m, r) {
                    ours_err.extend(err(&m.corners));
                    c_err.extend(err(&r.corners));
                }
            }
            frames += 1;
        }
        let name = set_name(&set);
        let (mo, mc, all) = (median(&ours_err), median(&c_err), median(&ours_all));
        let _ = writeln!(
            std::io::stderr(),
            "decimate {decimate}: {name:24} recall ours {ours_found}/{want}, C {c_found}/{want}; median corner error on the tags both find ours {mo:.3} px, C {mc:.3} px (ours on all it finds {all:.3} px)"
        );
        // The medians below need tags that both detectors found.
        assert!(!ours_err.is_empty(), "{name}: no tag found by both of {want} detectable");
        assert!(ours_found >= c_found, "{name}: recall below the reference");
        assert!(mo <= mc + 1e-9, "{name}: median corner error {mo:.3} px worse than C's {mc:.3} px");
        if name.starts_with("clean-") {
            assert!(all <= 0.1, "{name}: {all:.3} px on sharp frames");
        }
        checked.push((name, frames));
    }
    assert_every_fixture_frame(&format!("decimate {decimate}"), &checked);
}
