//! Our detector's stages against the AprilTag C library's, bit for bit. In debug mode the C
//! library writes each stage's image into the current directory; this binary (its own process,
//! one test, so changing directory is safe) runs it in a temporary folder and compares.

use jawtrack_apriltag::{ImageView, preprocess, threshold};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use jawtrack_tests::fixture_sets;

fn read_pnm(path: &std::path::Path) -> image::GrayImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_luma8()
}

#[test]
fn decimation_and_threshold_match_c_bit_for_bit() {
    let dir = tempfile_dir();
    std::env::set_current_dir(&dir).expect("enter the temporary folder");
    let mut frames = Vec::new();
    for set in fixture_sets() {
        let name = set.file_name().and_then(|n| n.to_str()).unwrap_or("").to_owned();
        if name.ends_with("-4k") {
            continue; // the C debug output of a 4K frame is slow to write; 1080p covers the logic
        }
        frames.push(set.join("frame_0000.png"));
    }
    assert!(frames.len() >= 4, "fixtures missing");
    let mut compared = 0;
    for path in &frames {
        let img = image::open(path).expect("png").to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        // An odd stride and an odd crop exercise the edges of the tiling.
        let crop_w = w - 3;
        let view = ImageView::new(img.as_raw(), crop_w, h - 1, w).expect("valid view");
        for (decimate, deglitch, diff) in
            [(1.0, false, 5), (1.5, false, 5), (2.0, false, 5), (2.0, true, 5), (3.0, false, 40), (4.0, false, 5)]
        {
            let params = ReferenceParams {
                quad_decimate: decimate,
                deglitch,
                min_white_black_diff: diff,
                debug: true,
                ..ReferenceParams::default()
            };
            let mut c = ReferenceDetector::new(&params).expect("reference");
            c.detect(img.as_raw(), crop_w, h - 1, w).expect("detects");
            let c_pre = read_pnm(&dir.join("debug_preprocess.pnm"));
            let c_thr = read_pnm(&dir.join("debug_threshold.pnm"));

            let ours_pre = if decimate == 1.0 {
                jawtrack_apriltag::Gray {
                    width: crop_w,
                    height: h - 1,
                    data: (0..h - 1).flat_map(|y| view.row(y).to_vec()).collect(),
                }
            } else {
                preprocess::decimate(&view, decimate)
            };
            let label = format!("{} decimate {decimate} deglitch {deglitch} diff {diff}", path.display());
            assert_eq!((ours_pre.width as u32, ours_pre.height as u32), c_pre.dimensions(), "{label}: preprocess size");
            assert!(ours_pre.data == *c_pre.as_raw(), "{label}: preprocess differs");
            let ours_thr = threshold::threshold(&ours_pre.view().expect("non-empty"), diff as u8, deglitch);
            let differing = ours_thr.data.iter().zip(c_thr.as_raw()).filter(|(a, b)| a != b).count();
            assert_eq!(differing, 0, "{label}: {differing} threshold pixels differ");
            compared += 1;
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "decimation and threshold equal C's on {compared} frame/setting pairs");
}

fn tempfile_dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("jawtrack-stages-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temporary folder");
    d
}
