//! Kalibr AprilGrid photos (tags with a 2-cell border: a standard detector should see none):
//! no more false detections than the reference C library, which finds nothing at max_hamming 0
//! and three hamming-2 decodes at max_hamming 2 (EuRoC.png id 7, two_boards.png ids 0, 24).

use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
use jawtrack_test_support::{say_skipped, shared_data};

#[test]
fn aprilgrid_negatives_give_no_more_than_the_reference() {
    let Some(data) = shared_data() else {
        say_skipped("negatives: ../shared/data is not present");
        return;
    };
    let dir = data.join("negatives/kalibr-aprilgrid");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("negatives folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 9);
    for max_hamming in [0, 2] {
        let d = Detector::new(DetectorConfig { max_hamming, ..DetectorConfig::default() }).expect("detector");
        let mut found = Vec::new();
        for f in &files {
            let img = image::open(f).expect("png").to_luma8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            for det in d.detect(&ImageView::new(img.as_raw(), w, h, w).expect("view")).expect("runs") {
                found.push((f.file_name().and_then(|n| n.to_str()).unwrap_or("?").to_owned(), det.id, det.hamming));
            }
        }
        found.sort();
        match max_hamming {
            0 => assert!(found.is_empty(), "{found:?}"),
            _ => assert!(found.len() <= 3 && found.iter().all(|f| f.2 == 2), "{found:?}"),
        }
    }
}
