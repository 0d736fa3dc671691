//! Our detector against the AprilTag C library end to end: on every fixture frame and every
//! real photo, at decimate 1 and 2, the same tags with the same corners.

use jawtrack_apriltag::{Detector, DetectorConfig, ImageView};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use jawtrack_test_support::{
    FIXTURE_FRAMES, assert_every_fixture_frame, fixture_sets, say_skipped, set_name, shared_data,
};
use std::io::Write as _;
use std::path::PathBuf;

fn frames() -> Vec<PathBuf> {
    let mut checked = Vec::new();
    let mut v: Vec<PathBuf> = fixture_sets()
        .iter()
        .flat_map(|s| {
            let mut f: Vec<PathBuf> = std::fs::read_dir(s)
                .map(|rd| {
                    rd.filter_map(|e| e.ok().map(|e| e.path()))
                        .filter(|p| p.extension().is_some_and(|e| e == "png"))
                        .collect()
                })
                .unwrap_or_default();
            f.sort();
            checked.push((set_name(s), f.len()));
            f
        })
        .collect();
    assert_every_fixture_frame("fixture frames", &checked);
    match shared_data() {
        Some(d) => {
            for sub in
                ["photos/swatbotics-mapping", "photos/duckietown", "photos/apriltags-jl", "negatives/kalibr-aprilgrid"]
            {
                // With ../shared/data present, each of its folders is expected whole.
                let rd = std::fs::read_dir(d.join(sub)).unwrap_or_else(|e| panic!("{sub}: {e}"));
                let mut f: Vec<PathBuf> = rd
                    .filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.extension().is_some_and(|e| matches!(e.to_str(), Some("png" | "jpg" | "JPG"))))
                    .collect();
                assert!(!f.is_empty(), "no images in {sub}");
                f.sort();
                v.extend(f);
            }
        }
        None => say_skipped("detector vs C on real photos: ../shared/data is not present"),
    }
    v
}

/// The fixture frames of [`frames`], all of which a test that takes them alone must check.
fn fixture_frames() -> Vec<PathBuf> {
    let v: Vec<PathBuf> =
        frames().into_iter().filter(|p| p.starts_with(jawtrack_test_support::fixtures_dir())).collect();
    assert_eq!(v.len(), FIXTURE_FRAMES.iter().map(|s| s.1).sum::<usize>(), "fixture frames");
    v
}

#[test]
fn same_tags_and_corners_as_c() {
    let (mut images, mut tags, mut worst) = (0, 0, 0.0f64);
    for decimate in [2.0f32, 1.0] {
        // C's behaviour exactly: edges refined on the encoded values.
        let ours =
            Detector::new(DetectorConfig { quad_decimate: decimate, ..DetectorConfig::reference() }).expect("detector");
        let mut c = ReferenceDetector::new(&ReferenceParams { quad_decimate: decimate, ..ReferenceParams::default() })
            .expect("reference");
        for path in frames() {
            let img = image::open(&path).expect("image").to_luma8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            let view = ImageView::new(img.as_raw(), w, h, w).expect("view");
            let mine = ours.detect(&view).expect("detects");
            let mut theirs = c.detect(img.as_raw(), w, h, w).expect("reference detects");
            theirs.sort_by(|a, b| a.id.cmp(&b.id).then(a.center[0].total_cmp(&b.center[0])));
            let ids = |v: &mut Vec<u32>| {
                v.sort_unstable();
                v.clone()
            };
            let (mut a, mut b): (Vec<u32>, Vec<u32>) =
                (mine.iter().map(|d| d.id).collect(), theirs.iter().map(|d| d.id).collect());
            assert_eq!(ids(&mut a), ids(&mut b), "{} decimate {decimate}: ids differ", path.display());
            for t in &theirs {
                let m = mine
                    .iter()
                    .filter(|d| d.id == t.id)
                    .min_by(|x, y| {
                        let dx = (x.center[0] - t.center[0]).hypot(x.center[1] - t.center[1]);
                        let dy = (y.center[0] - t.center[0]).hypot(y.center[1] - t.center[1]);
                        dx.total_cmp(&dy)
                    })
                    .expect("same ids");
                assert_eq!(m.hamming, t.hamming, "{} tag {}", path.display(), t.id);
                for (p, q) in m.corners.iter().zip(&t.corners) {
                    let e = (p[0] - q[0]).hypot(p[1] - q[1]);
                    worst = worst.max(e);
                    assert!(e < 1e-3, "{} decimate {decimate} tag {}: corner {p:?} vs C {q:?}", path.display(), t.id);
                }
                tags += 1;
            }
            images += 1;
        }
    }
    let _ = writeln!(
        std::io::stderr(),
        "detector vs C: {images} image/setting pairs, {tags} tags, worst corner difference {worst:.2e} px"
    );
    assert!(tags > 500, "too few tags compared: {tags}");
}

#[test]
fn two_threads_find_exactly_what_one_does() {
    let one = Detector::new(DetectorConfig::default()).expect("detector");
    let two = Detector::new(DetectorConfig { nthreads: 2, ..DetectorConfig::default() }).expect("detector");
    let mut tags = 0;
    for path in &fixture_frames() {
        let img = image::open(path).expect("image").to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let view = ImageView::new(img.as_raw(), w, h, w).expect("view");
        let a = one.detect(&view).expect("detects");
        assert_eq!(a, two.detect(&view).expect("detects"), "{}", path.display());
        tags += a.len();
    }
    assert!(tags > 200, "too few tags compared: {tags}");
}

#[test]
fn blurred_and_sharpened_quad_images_give_cs_tags_and_corners() {
    let mut tags = 0;
    for (decimate, sigma) in [(2.0f32, 0.8f32), (2.0, -0.8), (1.0, 1.2), (1.5, 0.8)] {
        let ours =
            Detector::new(DetectorConfig { quad_decimate: decimate, quad_sigma: sigma, ..DetectorConfig::reference() })
                .expect("detector");
        let mut c = ReferenceDetector::new(&ReferenceParams {
            quad_decimate: decimate,
            quad_sigma: sigma,
            ..ReferenceParams::default()
        })
        .expect("reference");
        for path in &fixture_frames() {
            let img = image::open(path).expect("image").to_luma8();
            let (w, h) = (img.width() as usize, img.height() as usize);
            let mine = ours.detect(&ImageView::new(img.as_raw(), w, h, w).expect("view")).expect("detects");
            let theirs = c.detect(img.as_raw(), w, h, w).expect("reference detects");
            let label = format!("{} decimate {decimate} sigma {sigma}", path.display());
            assert_eq!(mine.len(), theirs.len(), "{label}: {} tags, C {}", mine.len(), theirs.len());
            for t in &theirs {
                let close = |d: &&jawtrack_apriltag::Detection| {
                    d.id == t.id
                        && d.corners.iter().zip(&t.corners).all(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]) < 1e-3)
                };
                assert!(mine.iter().any(|d| close(&d)), "{label}: C's tag {} not matched", t.id);
                tags += 1;
            }
        }
    }
    assert!(tags > 500, "too few tags compared: {tags}");
}
