//! The recorded frame fixtures in `fixtures/`: complete, self-consistent, in agreement with
//! their images, and reproducible from the command in `fixtures/README.md`.

use jawtrack_apriltag::TagFamily;
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_synth::{GroundTruth, Realism, Resolution, SceneKind, SceneOptions, SynthConfig, Synthesizer};
use jawtrack_test_support::{assert_every_fixture_frame, fixture_sets, read_tag, set_name};
use nalgebra::Point3;
use std::path::Path;

fn load(set: &Path) -> GroundTruth {
    let text = std::fs::read_to_string(set.join("ground_truth.json")).expect("ground truth readable");
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", set.display()))
}

fn is_clean(set: &Path) -> bool {
    set.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("clean-"))
}

#[test]
fn fixture_sets_are_complete_and_within_budget() {
    let sets = fixture_sets();
    assert!(sets.len() >= 6, "fixture sets missing: {sets:?}");
    let (mut hd, mut uhd, mut bytes) = (0, 0, 0u64);
    let mut listed = Vec::new();
    for set in &sets {
        let gt = load(set);
        assert!(!gt.frames.is_empty(), "{}", set.display());
        // The folder holds exactly the frames its truth lists.
        let pngs = std::fs::read_dir(set)
            .expect("set folder")
            .filter(|e| e.as_ref().is_ok_and(|e| e.path().extension().is_some_and(|x| x == "png")))
            .count();
        assert_eq!(pngs, gt.frames.len(), "{}: frames on disk and in the truth", set.display());
        listed.push((set_name(set), gt.frames.len()));
        for f in &gt.frames {
            let path = set.join(&f.file);
            let (w, h) = image::image_dimensions(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert_eq!([w, h], gt.image_size, "{}", path.display());
            bytes += std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        }
        match gt.image_size {
            [1920, 1080] => hd += gt.frames.len(),
            [3840, 2160] => uhd += gt.frames.len(),
            other => panic!("unexpected size {other:?}"),
        }
    }
    assert!(hd >= 24 && uhd >= 2, "{hd} 1080p and {uhd} 4K frames");
    // The list the other tests count their fixture frames against is the folders'.
    assert_every_fixture_frame("ground truths", &listed);
    assert!(bytes < 20 * 1024 * 1024, "fixtures take {:.1} MB", bytes as f64 / 1048576.0);
}

#[test]
fn ground_truth_is_self_consistent() {
    let mut checked = Vec::new();
    for set in fixture_sets() {
        let gt = load(&set);
        let mut frames = 0;
        let marker = Marker::from_json(&gt.true_marker.to_string()).expect("the true marker is a valid marker file");
        assert_eq!(gt.print_errors.len(), 24);
        if is_clean(&set) {
            assert!(gt.print_errors.iter().all(|e| e.shift_x == 0.0 && e.shift_y == 0.0 && e.rotation_deg == 0.0));
            assert_eq!(marker, Marker::default(), "a clean set uses the nominal marker");
        } else {
            let rms =
                (gt.print_errors.iter().map(|e| e.shift_x.powi(2) + e.shift_y.powi(2)).sum::<f64>() / 24.0).sqrt();
            assert!(rms > 0.05 && rms < 0.5, "print error RMS {rms} mm");
        }
        for f in &gt.frames {
            let composed = f.camera_from_maxilla * f.maxilla_from_mandible;
            let (a, d) = composed.distance_to(&f.camera_from_mandible);
            assert!(a < 1e-12 && d < 1e-9, "{} {}", set.display(), f.file);
            // A frame without tags would check no corner below.
            assert!(!f.tags.is_empty(), "{} {}: no tags in the truth", set.display(), f.file);
            // Stored corners are the projection of the true marker under the stored poses.
            for t in &f.tags {
                let (kind, tag) = marker.find_tag(t.id).expect("tag in marker");
                assert_eq!(kind.name(), t.body);
                let pose = if kind == BodyKind::Maxilla { f.camera_from_maxilla } else { f.camera_from_mandible };
                for (c, stored) in tag.corners.iter().zip(&t.corners) {
                    let p = gt.intrinsics.project(&pose.transform_point(&Point3::from(*c))).expect("in front");
                    assert!((p.x - stored[0]).abs() < 1e-6 && (p.y - stored[1]).abs() < 1e-6);
                }
            }
            frames += 1;
        }
        checked.push((set_name(&set), frames));
    }
    assert_every_fixture_frame("self-consistency", &checked);
}

/// Every tag the truth says a detector should find is in the image where the truth says,
/// with the right code: the images and the ground truth agree.
#[test]
fn images_show_the_tags_where_the_truth_puts_them() {
    let mut checked = Vec::new();
    for set in fixture_sets() {
        let gt = load(&set);
        let (mut tags, mut decoded, mut frames) = (0usize, 0usize, 0usize);
        for f in &gt.frames {
            frames += 1;
            let img = image::open(set.join(&f.file)).expect("png decodes").to_luma8();
            for t in f.tags.iter().filter(|t| t.should_be_detected()) {
                let reading = read_tag(&img, &t.corners).expect("detectable tags lie inside the image");
                let bm = TagFamily::TAG36H11.bitmap(t.id).expect("id");
                let errors = TagFamily::TAG36H11
                    .bit_cells
                    .iter()
                    .filter(|&&(x, y)| bm.is_white(x.into(), y.into()) != reading.is_white(x.into(), y.into()))
                    .count();
                tags += 1;
                assert!(
                    reading.white - reading.black > 30.0,
                    "{} {} tag {}: contrast {:?}",
                    set.display(),
                    f.file,
                    t.id,
                    reading
                );
                if errors <= if is_clean(&set) { 0 } else { 2 } {
                    decoded += 1;
                }
            }
        }
        let need = if is_clean(&set) { tags } else { (tags * 9).div_ceil(10) };
        assert!(tags > 0, "{}: no detectable tag to read", set.display());
        assert!(decoded >= need, "{}: {decoded}/{tags} detectable tags read back", set.display());
        eprintln!("{}: {decoded}/{tags} detectable tags read back", set.display());
        checked.push((set_name(&set), frames));
    }
    assert_every_fixture_frame("tags read back", &checked);
}

/// The first frame of two sets, rendered again with the parameters of `fixtures/regenerate.sh`,
/// is byte for byte the committed frame.
#[test]
fn fixtures_regenerate_bit_for_bit() {
    let cases = [("clean-static-1080p", Realism::clean(), 1), ("static-1080p", Realism::default(), 3)];
    for (name, realism, stride) in cases {
        let set = jawtrack_test_support::fixtures_dir().join(name);
        let config = SynthConfig {
            scene: SceneKind::Static,
            resolution: Resolution::P1080,
            intrinsics: None,
            seed: 7,
            realism,
            options: SceneOptions { frames_per_view: 1, ..SceneOptions::default() },
            marker: Marker::default(),
            stride,
            max_frames: Some(1),
        };
        let frame = Synthesizer::new(config).expect("valid config").render(0).expect("renders");
        let stored = image::open(set.join("frame_0000.png")).expect("fixture").to_luma8();
        let differing = frame.luma.iter().zip(stored.as_raw()).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{name}: {differing} pixels differ from a fresh render");
    }
}
