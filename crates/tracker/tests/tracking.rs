//! The tracker through time: searching where the markers are expected on a rendered hinge
//! sequence, dropping a tag that flickers in, settling a lone tag's mirror ambiguity (and
//! reporting the covariance of the solution taken), new settings that keep the motion, and the
//! registration to the tooth scans; a marker printed in another tag family, and one on cubes,
//! each tracked from its file.

use jawtrack_apriltag::{Detection, ImageView, TagFamily};
use jawtrack_marker::{BodyKind, BodyProvenance, Marker, SolidKind, TagProvenance};
use jawtrack_pose::pnp::{pose_jacobian, projection_jacobian};
use jawtrack_pose::{CameraIntrinsics, Observation, PnpOptions, Pose, solve_pnp};
use jawtrack_registration::BiteRefusal;
use jawtrack_registration::Registration;
use jawtrack_synth::{Realism, SceneKind, SceneOptions, SynthConfig, Synthesizer};
use jawtrack_tracker::{Flag, FrameResult, SearchConfig, SmootherConfig, Tracker, TrackerConfig};
use nalgebra::{Matrix6, Point3, UnitQuaternion, Vector2, Vector3};

/// Rows of the frames the hand-made detections stand for (a global shutter ignores them).
const ROWS: usize = 1080;

#[test]
fn a_marker_in_another_family_is_tracked_from_its_file() {
    // The marker file names tag25h9: the renderer prints it, the tracker's detector reads it.
    let nominal = Marker::nominal_of(TagFamily::TAG25H9, 12.7, None).expect("tag25h9 marker");
    let marker = Marker::from_json(&nominal.to_json()).expect("its file reads");
    assert_eq!(marker.family, TagFamily::TAG25H9);
    let config = SynthConfig {
        realism: Realism::clean(),
        marker: marker.clone(),
        max_frames: Some(6),
        ..SynthConfig::new(SceneKind::Static)
    };
    let synth = Synthesizer::new(config).expect("scene");
    let camera = synth.header().intrinsics;
    let mut tracker = Tracker::new(marker, TrackerConfig::default()).expect("tracker");
    let mut as_36h11 = Tracker::new(Marker::default(), TrackerConfig::default()).expect("tracker");
    let (mut posed, mut tags) = (0, 0);
    for i in 0..synth.len() {
        let f = synth.render(i).expect("frame");
        let (w, h) = (f.width as usize, f.height as usize);
        let view = ImageView::new(&f.luma, w, h, w).expect("view");
        let r = tracker.track(&view, &camera, f.truth.t).expect("tracks");
        let m = r.maxilla_from_mandible.unwrap_or_else(|| panic!("frame {i}: no jaw pose"));
        let (angle, dist) = m.distance_to(&f.truth.maxilla_from_mandible);
        assert!(dist < 0.05 && angle.to_degrees() < 0.1, "frame {i}: {dist:.3} mm {:.3}°", angle.to_degrees());
        assert!(r.detections.iter().all(|d| d.id < 24), "frame {i}: an id off the marker");
        tags += r.detections.len();
        posed += 1;
        // Printed in tag25h9, the markers show a tag36h11 tracker nothing.
        assert!(as_36h11.track(&view, &camera, f.truth.t).expect("tracks").detections.is_empty(), "frame {i}");
    }
    assert_eq!(posed, 6, "frames posed");
    assert!(tags >= 6 * 6, "{tags} tags in 6 frames");
}

#[test]
fn a_cube_marker_is_rendered_and_tracked_from_its_file() {
    // The marker file names a cube: the renderer draws six square faces a body, the tracker
    // poses them from the file's tags alone.
    let nominal = Marker::nominal_on(SolidKind::Cube, TagFamily::TAG36H11, 12.7, None).expect("cube marker");
    let marker = Marker::from_json(&nominal.to_json()).expect("its file reads");
    assert_eq!((marker.solid, marker.tags().count()), (SolidKind::Cube, 12));
    // A cube shows each face more obliquely than a dodecahedron does, and the clean renderer's
    // linear output leaves those faces too dark to read: render as a phone encodes (sRGB, blur,
    // noise), the tags printed exactly so the file is the truth.
    let config = SynthConfig {
        realism: Realism { print_error_mm: 0.0, print_error_deg: 0.0, ..Realism::default() },
        marker: marker.clone(),
        max_frames: Some(6),
        ..SynthConfig::new(SceneKind::Static)
    };
    let synth = Synthesizer::new(config).expect("scene");
    let camera = synth.header().intrinsics;
    let mut tracker = Tracker::new(marker, TrackerConfig::default()).expect("tracker");
    let (mut posed, mut tags, mut worst) = (0, 0, (0.0f64, 0.0f64));
    for i in 0..synth.len() {
        let f = synth.render(i).expect("frame");
        let (w, h) = (f.width as usize, f.height as usize);
        let view = ImageView::new(&f.luma, w, h, w).expect("view");
        let r = tracker.track(&view, &camera, f.truth.t).expect("tracks");
        let m = r.maxilla_from_mandible.unwrap_or_else(|| panic!("frame {i}: no jaw pose"));
        let (angle, dist) = m.distance_to(&f.truth.maxilla_from_mandible);
        worst = (worst.0.max(dist), worst.1.max(angle.to_degrees()));
        assert!(r.detections.iter().all(|d| d.id < 6 || (12..18).contains(&d.id)), "frame {i}: an id off the cubes");
        tags += r.detections.len();
        posed += 1;
    }
    eprintln!("cube marker: {posed} frames posed from {tags} tags, worst {:.4} mm {:.4}°", worst.0, worst.1);
    assert_eq!(posed, 6, "frames posed");
    assert!(tags >= 6 * 4, "{tags} tags in 6 frames");
    assert!(worst.0 < 0.05 && worst.1 < 0.1, "worst {:.3} mm {:.3}°", worst.0, worst.1);
}

#[test]
fn steady_tracking_searches_only_the_expected_region() {
    let frames = 10;
    let config = SynthConfig {
        realism: Realism::clean(),
        options: SceneOptions { cycles: 1, ..SceneOptions::default() },
        max_frames: Some(frames),
        ..SynthConfig::new(SceneKind::Hinge)
    };
    let synth = Synthesizer::new(config).expect("scene");
    let camera = synth.header().intrinsics;
    let tracker_config = TrackerConfig {
        search: SearchConfig { full_frame_every: 4, ..SearchConfig::default() },
        ..TrackerConfig::default()
    };
    let mut tracker = Tracker::new(Marker::default(), tracker_config).expect("tracker");
    let mut searched = Vec::new();
    for i in 0..synth.len() {
        let f = synth.render(i).expect("frame");
        let (w, h) = (f.width as usize, f.height as usize);
        let view = ImageView::new(&f.luma, w, h, w).expect("view");
        let r = tracker.track(&view, &camera, f.truth.t).expect("tracks");
        let m = r.maxilla_from_mandible.expect("both bodies");
        let (angle, dist) = m.distance_to(&f.truth.maxilla_from_mandible);
        assert!(dist < 0.05 && angle.to_degrees() < 0.1, "frame {i}: {dist:.3} mm {:.3}°", angle.to_degrees());
        // Every tag found in the whole frame is found in the region too.
        let all = tracker_full_frame_ids(&view, &camera);
        let ids: Vec<u32> = r.detections.iter().map(|d| d.id).collect();
        assert_eq!(ids, all, "frame {i}");
        searched.push(r.searched.map(|s| (s.width * s.height) as f64 / (w * h) as f64));
    }
    // Every frame got a pose above; the scene is longer than `frames`, so all were tracked.
    assert_eq!(searched.len(), frames, "frames tracked");
    // The first frame and every 4th after are searched whole; the rest in under half the frame.
    for (i, s) in searched.iter().enumerate() {
        if i % 4 == 0 {
            assert_eq!(*s, None, "frame {i} should be a full search");
        } else {
            let share = s.unwrap_or_else(|| panic!("frame {i} searched the whole frame"));
            assert!(share < 0.5, "frame {i}: region is {:.0} % of the frame", share * 100.0);
        }
    }
}

#[test]
fn large_tags_are_searched_on_a_coarser_image_as_accurately() {
    // The markers held still 40 mm from the camera at 1080p: every tag seen (one a body) has
    // its shortest side over 110 px, large enough for the coarse image however blurred.
    let run = coarse_against_fine(40.0, Realism::clean(), 30);
    assert!(run.smallest > 110.0, "shortest side {} px", run.smallest);
    // The first frame is searched whole, at the settings' decimation; the rest coarsely.
    assert_eq!(run.coarse(), run.frames.len() - 1, "frames searched coarsely");
}

#[test]
fn sharp_tags_are_searched_coarsely_from_a_smaller_size_than_blurred_ones() {
    // At 60 mm an oblique tag's shortest side is 70–110 px: large enough for the coarse image
    // when every tag was sharp in the last frame, not when one was blurred more than 2 px
    // (the lens's own blur at 12 µm is 2.6 px, a phone focused well behind the markers).
    let sharp = coarse_against_fine(60.0, Realism::clean(), 30);
    assert!((70.0..110.0).contains(&sharp.smallest), "shortest side {} px", sharp.smallest);
    assert!(sharp.blur < 1.0, "sharp: blur {} px", sharp.blur);
    assert_eq!(sharp.coarse(), sharp.frames.len() - 1, "sharp: frames searched coarsely");
    let blurred = Realism { optics_sigma_um: 12.0, focal_length_mm: 6.8, ..Realism::clean() };
    let blurred = coarse_against_fine(60.0, blurred, 30);
    assert!((70.0..110.0).contains(&blurred.smallest), "shortest side {} px", blurred.smallest);
    assert!(blurred.blur > 2.0, "blurred: blur {} px", blurred.blur);
    assert_eq!((blurred.coarse(), blurred.frames.len()), (0, 6), "blurred: frames searched coarsely");
}

#[test]
fn the_whole_frame_searched_periodically_is_searched_coarsely_while_both_tracked_tags_are_large() {
    // The sharp still markers at 60 mm, the whole frame searched every other frame: once both
    // bodies are tracked, those searches find quads on the coarse image too.
    let run = coarse_against_fine(60.0, Realism::clean(), 2);
    let whole: Vec<(usize, bool)> =
        run.frames.iter().enumerate().filter(|(_, f)| f.whole).map(|(i, f)| (i, f.coarse)).collect();
    // Frames 0, 2 and 4 search the whole frame; the first, with nothing tracked yet, finely.
    assert_eq!(whole, [(0, false), (2, true), (4, true)], "whole-frame searches, and whether coarse");
}

/// How each frame was searched with the pyramid ([`coarse_against_fine`]).
struct Searched {
    /// The whole frame, not a region.
    whole: bool,
    /// At the coarse decimation.
    coarse: bool,
}

/// What [`coarse_against_fine`] found: each frame's search, the shortest side of a tag found
/// (px) and the largest blur of a tag found (px).
struct CoarseRun {
    frames: Vec<Searched>,
    smallest: f64,
    blur: f64,
}

impl CoarseRun {
    fn coarse(&self) -> usize {
        self.frames.iter().filter(|f| f.coarse).count()
    }
}

/// Tracks six frames of the still markers `distance_mm` from a 1080p camera, rendered with
/// `realism`, with and without the pyramid ([`SearchConfig::pyramid`]), the whole frame
/// searched at least every `full_frame_every` frames, and checks each frame searched alike and
/// as accurate either way.
fn coarse_against_fine(distance_mm: f64, realism: Realism, full_frame_every: usize) -> CoarseRun {
    let frames = 6;
    let config = SynthConfig {
        realism,
        options: SceneOptions { distance_mm: Some(distance_mm), frames_per_view: frames, ..SceneOptions::default() },
        max_frames: Some(frames),
        ..SynthConfig::new(SceneKind::Static)
    };
    let synth = Synthesizer::new(config).expect("scene");
    let camera = synth.header().intrinsics;
    let tracker_with = |pyramid: bool| {
        let search = SearchConfig { pyramid, predicted: false, full_frame_every, ..SearchConfig::default() };
        Tracker::new(Marker::default(), TrackerConfig { search, ..TrackerConfig::default() }).expect("tracker")
    };
    let (mut coarse, mut fine) = (tracker_with(true), tracker_with(false));
    let mut run = CoarseRun { frames: Vec::new(), smallest: f64::INFINITY, blur: 0.0 };
    for i in 0..synth.len() {
        let f = synth.render(i).expect("frame");
        let (w, h) = (f.width as usize, f.height as usize);
        let view = ImageView::new(&f.luma, w, h, w).expect("view");
        let a = coarse.track(&view, &camera, f.truth.t).expect("tracks");
        let b = fine.track(&view, &camera, f.truth.t).expect("tracks");
        assert_eq!(b.timings.stages.quad_decimate, 2.0, "frame {i}: without the pyramid");
        assert_eq!(a.searched.is_none(), b.searched.is_none(), "frame {i}: the same search");
        let (ea, eb) = same_tags_and_errors(&a, &b, &f.truth.maxilla_from_mandible, i);
        // As accurate: within 0.005 mm and 0.01° of the fine search (at 40 mm, 0.034 mm /
        // 0.065° against 0.035 mm / 0.059° when written).
        assert!(ea.0 < eb.0 + 0.005 && ea.1 < eb.1 + 0.01, "frame {i}: {ea:?} coarse, {eb:?} fine");
        for d in &b.detections {
            let side = |k: usize| {
                let (p, q) = (d.corners[k], d.corners[(k + 1) % 4]);
                (q[0] - p[0]).hypot(q[1] - p[1])
            };
            run.smallest = (0..4).map(side).fold(run.smallest, f64::min);
            run.blur = run.blur.max(d.blur_px.unwrap_or(0.0));
        }
        run.frames.push(Searched { whole: a.searched.is_none(), coarse: a.timings.stages.quad_decimate == 4.0 });
    }
    assert_eq!(run.frames.len(), frames);
    run
}

#[test]
fn predicted_tags_are_found_as_the_region_search_finds_them() {
    // A hinge opening with the default realism (defocus, noise, sRGB): tracked frames looked
    // for where the poses predict the tags, against the same frames searched in the region.
    let frames = 12;
    let config = SynthConfig {
        options: SceneOptions { cycles: 1, ..SceneOptions::default() },
        max_frames: Some(frames),
        ..SynthConfig::new(SceneKind::Hinge)
    };
    let synth = Synthesizer::new(config).expect("scene");
    let (mut confirmed, mut compared, mut sums) = (0, 0, [0.0; 4]);
    for (i, truth, a, b) in tracked_both_ways(&synth) {
        assert!(!b.timings.predicted && b.timings.stages.predicted == 0, "frame {i}: the region searched");
        // The tone curve is fitted to what the search finds in the frames it is fitted in (the
        // first three): the same curve either way, frame by frame.
        assert_eq!(a.tone, b.tone, "frame {i}: the tone curve");
        if i < jawtrack_apriltag::tone::SETTLING_FRAMES {
            assert!(!a.timings.predicted && a.timings.stages.predicted == 0, "frame {i}: tone fitted, not searched");
        }
        // Predicted and nothing searched: every tag the last frame was solved from was found.
        confirmed += usize::from(a.timings.predicted);
        let (ea, eb) = same_tags_and_errors(&a, &b, &truth, i);
        assert!(ea.0 < eb.0 + 0.015 && ea.1 < eb.1 + 0.02, "frame {i}: {ea:?} predicted, {eb:?} searched");
        sums = [sums[0] + ea.0, sums[1] + ea.1, sums[2] + eb.0, sums[3] + eb.1];
        compared += 1;
    }
    assert_eq!(compared, frames);
    // As accurate over the frames: when written, 0.024 mm / 0.019° predicted against
    // 0.029 mm / 0.022° searched (the refitted quads of the tags seen within 60° of face-on
    // land nearer the truth than the region's quads do, `Expected::search`).
    assert!(sums[0] <= sums[2] && sums[1] <= sums[3], "mean error: {sums:?} (predicted mm, °, searched mm, °)");
    // The first frame is searched whole, the next two for the tone curve; of the rest, one
    // (frame 9, when written) lost a tag the last frame was solved from and searched the
    // region again.
    assert!(confirmed >= frames - 4, "{confirmed} frames confirmed where predicted");
}

/// Asserts that two trackers' results for frame `i` hold the same tags, and returns each one's
/// jaw error against `truth` (mm, °).
fn same_tags_and_errors(a: &FrameResult, b: &FrameResult, truth: &Pose, i: usize) -> ((f64, f64), (f64, f64)) {
    let ids = |r: &jawtrack_tracker::FrameResult| r.detections.iter().map(|d| d.id).collect::<Vec<_>>();
    assert_eq!(ids(a), ids(b), "frame {i}: the same tags");
    let error = |r: &jawtrack_tracker::FrameResult| {
        let (angle, dist) = r.maxilla_from_mandible.expect("both bodies").distance_to(truth);
        (dist, angle.to_degrees())
    };
    (error(a), error(b))
}

fn tracker_full_frame_ids(view: &ImageView<'_>, camera: &CameraIntrinsics) -> Vec<u32> {
    let config = TrackerConfig {
        search: SearchConfig { region_search: false, ..SearchConfig::default() },
        ..TrackerConfig::default()
    };
    let mut t = Tracker::new(Marker::default(), config).expect("tracker");
    let r = t.track(view, camera, 0.0).expect("tracks");
    r.detections.iter().map(|d| d.id).collect()
}

/// A camera looking at both markers from 100 mm, their camera-facing vertex toward it.
fn scene() -> (CameraIntrinsics, Pose, Pose) {
    let camera = CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5);
    let facing = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI)
        * UnitQuaternion::from_scaled_axis(Vector3::new(0.25, 0.15, 0.0));
    let maxilla = Pose::from_parts(facing, Vector3::new(2.0, -22.0, 100.0));
    let mandible = Pose::from_parts(
        facing * UnitQuaternion::from_scaled_axis(Vector3::new(0.2, 0.0, 0.0)),
        Vector3::new(1.0, 22.0, 104.0),
    );
    (camera, maxilla, mandible)
}

/// Noise-free detections of `ids` seen through `camera_from_body`.
fn detections(marker: &Marker, ids: &[u32], camera_from_body: &Pose, camera: &CameraIntrinsics) -> Vec<Detection> {
    ids.iter()
        .map(|&id| {
            let (_, tag) = marker.find_tag(id).expect("marker tag");
            let corners = tag.corners.map(|c| {
                let p = camera.project(&camera_from_body.transform_point(&Point3::from(c))).expect("in front");
                [p.x, p.y]
            });
            let center =
                [corners.iter().map(|c| c[0]).sum::<f64>() / 4.0, corners.iter().map(|c| c[1]).sum::<f64>() / 4.0];
            Detection { id, hamming: 0, decision_margin: 100.0, center, corners, homography: [0.0; 9], blur_px: None }
        })
        .collect()
}

#[test]
fn a_tag_that_flickers_in_with_a_large_error_is_dropped() {
    let marker = Marker::default();
    let (camera, maxilla, mandible) = scene();
    let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    let both = |max_ids: &[u32], man_ids: &[u32]| {
        let mut d = detections(&marker, max_ids, &maxilla, &camera);
        d.extend(detections(&marker, man_ids, &mandible, &camera));
        d
    };
    let r = tracker.solve(both(&[0, 1, 2], &[12, 13, 14]), &camera, 0.0, ROWS);
    assert!(r.flags.is_empty(), "{:?}", r.flags);
    // Tag 3 appears, misread 4 px off: dropped, and the pose stays exact.
    let mut d = both(&[0, 1, 2, 3], &[12, 13, 14]);
    for c in &mut d.iter_mut().find(|d| d.id == 3).expect("tag 3").corners {
        c[0] += 4.0;
    }
    let r = tracker.solve(d, &camera, 1.0 / 30.0, ROWS);
    let body = r.maxilla.as_ref().expect("maxilla");
    assert_eq!(body.tags, vec![0, 1, 2]);
    assert_eq!(body.rejected_tags, vec![3]);
    assert!(r.flags.contains(&Flag::RejectedTags(BodyKind::Maxilla)));
    let (angle, dist) = body.camera_from_body.distance_to(&maxilla);
    assert!(angle < 1e-9 && dist < 1e-9);
    // Seen correctly, the same newcomer is kept.
    let r = tracker.solve(both(&[0, 1, 2, 3], &[12, 13, 14]), &camera, 2.0 / 30.0, ROWS);
    assert_eq!(r.maxilla.as_ref().expect("maxilla").tags, vec![0, 1, 2, 3]);
    assert!(r.flags.is_empty(), "{:?}", r.flags);
}

/// The default marker as a calibration leaves it when tags 3 and 15 were seen too rarely.
fn calibrated_but_3_and_15() -> Marker {
    let mut marker = Marker::default();
    for body in &mut marker.bodies {
        body.provenance =
            Some(BodyProvenance { views: 20, rms_before_px: 1.5, rms_after_px: 0.2, recordings: vec!["cal".into()] });
        for t in &mut body.tags {
            t.provenance = Some(match t.id {
                3 | 15 => TagProvenance::Nominal { views: 1 },
                _ => TagProvenance::Calibrated { views: 8, rms_before_px: 1.5, rms_after_px: 0.2 },
            });
        }
    }
    marker.validate().expect("a valid calibrated marker");
    marker
}

#[test]
fn a_pose_on_a_nominal_tag_of_a_calibrated_marker_is_flagged() {
    let (camera, maxilla, mandible) = scene();
    let marker = calibrated_but_3_and_15();
    let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    assert_eq!(tracker.uncalibrated_tags(), [3, 15]);
    let both = |max_ids: &[u32], man_ids: &[u32]| {
        let mut d = detections(&marker, max_ids, &maxilla, &camera);
        d.extend(detections(&marker, man_ids, &mandible, &camera));
        d
    };
    let uncalibrated = |r: &jawtrack_tracker::FrameResult| -> Vec<Flag> {
        r.flags.iter().copied().filter(|f| matches!(f, Flag::UncalibratedTag(_))).collect()
    };
    // Every tag used calibrated: no flag.
    let r = tracker.solve(both(&[0, 1, 2], &[12, 13, 14]), &camera, 0.0, ROWS);
    assert!(r.flags.is_empty(), "{:?}", r.flags);
    // The mandible's pose rests partly on nominal tag 15 (one seen face-on enough to use).
    let r = tracker.solve(both(&[0, 1, 2], &[12, 13, 15]), &camera, 1.0 / 30.0, ROWS);
    assert_eq!(r.mandible.as_ref().expect("mandible").tags, [12, 13, 15]);
    assert_eq!(uncalibrated(&r), [Flag::UncalibratedTag(BodyKind::Mandible)]);
    // Both bodies on a nominal tag.
    let r = tracker.solve(both(&[0, 2, 3], &[13, 15]), &camera, 2.0 / 30.0, ROWS);
    assert_eq!(uncalibrated(&r), [BodyKind::Maxilla, BodyKind::Mandible].map(Flag::UncalibratedTag));
    assert_eq!(r.to_record(2, None).flags.last().map(String::as_str), Some("mandible:uncalibrated_tag"));
}

#[test]
fn a_nominal_marker_never_flags_uncalibrated_tags() {
    let (camera, maxilla, mandible) = scene();
    for marker in [Marker::default(), {
        // A version 1 calibrated file: provenance unknown, nothing to flag.
        let mut m = calibrated_but_3_and_15();
        m = Marker::from_json(&m.to_json().replacen("\"version\": 3", "\"version\": 1", 1)).expect("version 1 reads");
        m
    }] {
        let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
        assert!(tracker.uncalibrated_tags().is_empty());
        let mut d = detections(&marker, &[0, 3], &maxilla, &camera);
        d.extend(detections(&marker, &[13, 15], &mandible, &camera));
        let r = tracker.solve(d, &camera, 0.0, ROWS);
        assert!(r.maxilla.is_some() && r.mandible.is_some());
        assert!(!r.flags.iter().any(|f| matches!(f, Flag::UncalibratedTag(_))), "{:?}", r.flags);
    }
}

#[test]
fn a_lone_tag_is_settled_by_history_or_the_other_body_and_flagged_otherwise() {
    let marker = Marker::default();
    let (camera, maxilla, mandible) = scene();
    // A tag whose pose alone has a mirror solution.
    let probe = |id: u32| {
        let mut t = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
        let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
        d.extend(detections(&marker, &[id], &mandible, &camera));
        t.solve(d, &camera, 0.0, ROWS).flags.contains(&Flag::Ambiguous(BodyKind::Mandible))
    };
    let lone = (12..24).find(|&id| probe(id)).expect("some single tag is ambiguous");
    let close = |p: &Pose, q: &Pose| p.distance_to(q).0.to_degrees() < 0.01;

    // Settled beside the other body: both were seen together once, within the age limit (a
    // stale relative pose settles nothing: `a_stale_relative_pose_does_not_settle_a_lone_tag`).
    let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
    d.extend(detections(&marker, &[12, 13, 14], &mandible, &camera));
    tracker.solve(d, &camera, 0.0, ROWS);
    let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
    d.extend(detections(&marker, &[lone], &mandible, &camera));
    let r = tracker.solve(d, &camera, 0.4, ROWS);
    assert!(!r.flags.contains(&Flag::Ambiguous(BodyKind::Mandible)), "{:?}", r.flags);
    assert!(r.flags.contains(&Flag::SingleTag(BodyKind::Mandible)));
    assert!(close(&r.mandible.expect("mandible").camera_from_body, &mandible));

    // Settled by its own recent pose, the other body out of view.
    let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    tracker.solve(detections(&marker, &[12, 13, 14], &mandible, &camera), &camera, 0.0, ROWS);
    let r = tracker.solve(detections(&marker, &[lone], &mandible, &camera), &camera, 1.0 / 30.0, ROWS);
    assert!(!r.flags.contains(&Flag::Ambiguous(BodyKind::Mandible)), "{:?}", r.flags);
    assert!(close(&r.mandible.expect("mandible").camera_from_body, &mandible));
}

#[test]
fn registration_maps_the_jaw_into_the_scans() {
    let marker = Marker::default();
    let (camera, maxilla, mandible) = scene();
    let registration = Registration {
        maxilla_scan_from_maxilla_marker: Pose::from_axis_angle(
            Vector3::new(0.0, 0.1, 0.0),
            Vector3::new(0.0, 22.0, 38.0),
        ),
        mandible_scan_from_mandible_marker: Pose::from_axis_angle(
            Vector3::new(0.0, 0.1, 0.0),
            Vector3::new(0.0, -22.0, 38.0),
        ),
        ..Registration::identity()
    };
    let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    tracker.set_registration(Some(registration));
    let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
    d.extend(detections(&marker, &[12, 13, 14], &mandible, &camera));
    let r = tracker.solve(d.clone(), &camera, 0.0, ROWS);
    let want = registration.maxilla_scan_from_mandible_scan(&(maxilla.inverse() * mandible));
    let got = r.maxilla_scan_from_mandible_scan.expect("registered");
    let (angle, dist) = got.distance_to(&want);
    assert!(angle < 1e-9 && dist < 1e-9);
    // One frame is not a held bite.
    assert!(matches!(tracker.calibrate_intercuspation(), Err(BiteRefusal::TooFewFrames { got: 1, .. })));
    // Held for 0.4 s, the intercuspation step makes this bite the scanned intercuspal pose
    // (identity here).
    for i in 1..=12 {
        tracker.solve(d.clone(), &camera, f64::from(i) / 30.0, ROWS);
    }
    let (bite, cal) = tracker.calibrate_intercuspation().expect("calibrates");
    assert_eq!(bite.frames, 13);
    assert!(bite.maxilla_from_mandible.distance_to(&(maxilla.inverse() * mandible)).1 < 1e-9, "{bite:?}");
    assert!(cal.translation_mm > 1.0, "the registration above is not the bite: {cal:?}");
    let r = tracker.solve(d, &camera, 13.0 / 30.0, ROWS);
    let (angle, dist) = r.maxilla_scan_from_mandible_scan.expect("registered").distance_to(&Pose::identity());
    assert!(angle < 1e-9 && dist < 1e-9, "{angle} rad {dist} mm");
}

#[test]
fn a_tag_that_never_fits_the_marker_file_is_reported() {
    let marker = Marker::default();
    let (camera, maxilla, mandible) = scene();
    let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    for i in 0..8 {
        let mut d = detections(&marker, &[0, 1, 2, 3], &maxilla, &camera);
        d.extend(detections(&marker, &[12, 13, 14], &mandible, &camera));
        // Tag 3 glued a quarter turn off: its corners pair with the wrong model corners.
        let t3 = d.iter_mut().find(|d| d.id == 3).expect("tag 3");
        t3.corners = [t3.corners[1], t3.corners[2], t3.corners[3], t3.corners[0]];
        let r = tracker.solve(d, &camera, i as f64 / 30.0, ROWS);
        assert_eq!(r.maxilla.expect("maxilla").rejected_tags, vec![3], "frame {i}");
    }
    assert_eq!(tracker.mismatched_tags(5), vec![(3, 8, 8)]);
    assert!(tracker.mismatched_tags(9).is_empty(), "too few frames to say");
}

/// A mandible tag whose pose alone has a mirror solution, and that mirror.
fn lone_tag_with_mirror(marker: &Marker, mandible: &Pose, camera: &CameraIntrinsics) -> (u32, Pose) {
    let tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    (12..24)
        .find_map(|id| {
            let d = detections(marker, &[id], mandible, camera);
            let obs = tracker.observations(BodyKind::Mandible, &d);
            let pose = solve_pnp(&obs, camera, None, &PnpOptions::default()).ok()?;
            pose.alternative.map(|a| (id, a.camera_from_body))
        })
        .expect("some single tag has a mirror solution")
}

/// The covariance the solver gives a single tag's corners at `pose`: the inverse Gauss–Newton
/// normal matrix times the assumed corner variance (four points are too few to estimate it).
fn covariance_at(observations: &[Observation], camera: &CameraIntrinsics, pose: &Pose) -> Matrix6<f64> {
    let focal = Vector2::new(camera.fx, camera.fy);
    let mut h = Matrix6::zeros();
    for o in observations {
        let c = pose.transform_point(&o.body);
        let j = pose_jacobian(&c, &projection_jacobian(&c, &focal).expect("in front"));
        h += j.transpose() * j;
    }
    h.try_inverse().expect("invertible") * PnpOptions::default().corner_sigma_px.powi(2)
}

#[test]
fn a_lone_tag_on_its_mirror_solution_reports_that_solutions_covariance() {
    let marker = Marker::default();
    let (camera, _, mandible) = scene();
    let (lone, mirror) = lone_tag_with_mirror(&marker, &mandible, &camera);
    // The body was last seen (through three tags) at the mirror pose, so the lone tag's frame
    // takes the mirror over the better-fitting true pose.
    let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    tracker.solve(detections(&marker, &[12, 13, 14], &mirror, &camera), &camera, 0.0, ROWS);
    let d = detections(&marker, &[lone], &mandible, &camera);
    let observations = tracker.observations(BodyKind::Mandible, &d);
    let r = tracker.solve(d, &camera, 1.0 / 30.0, ROWS);
    assert!(!r.flags.contains(&Flag::Ambiguous(BodyKind::Mandible)), "{:?}", r.flags);
    let body = r.mandible.expect("mandible");
    assert!(body.camera_from_body.distance_to(&mirror).0 < 1e-6, "the mirror is taken");
    let chosen = covariance_at(&observations, &camera, &body.camera_from_body);
    let rejected = covariance_at(&observations, &camera, &mandible);
    let gap = |a: &Matrix6<f64>, b: &Matrix6<f64>| (a - b).norm() / b.norm();
    assert!(gap(&rejected, &chosen) > 0.01, "the two solutions' covariances differ");
    assert!(
        gap(&body.covariance, &chosen) < 1e-6,
        "reported covariance is not the chosen pose's ({:.2e} off; {:.2e} off the rejected one's)",
        gap(&body.covariance, &chosen),
        gap(&body.covariance, &rejected)
    );
}

#[test]
fn a_lone_tag_follows_the_other_body_when_the_head_moves() {
    let marker = Marker::default();
    let (camera, maxilla, mandible) = scene();
    let (lone, mirror) = lone_tag_with_mirror(&marker, &mandible, &camera);
    // Both bodies are seen with the mandible at the lone tag's mirror pose; then the head turns
    // so that the mandible sits at the true pose, and only the lone tag of it is seen. Its own
    // last pose points to the mirror; the maxilla, seen this frame, points to the truth.
    let head = mandible * mirror.inverse();
    let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
    let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
    d.extend(detections(&marker, &[12, 13, 14], &mirror, &camera));
    tracker.solve(d, &camera, 0.0, ROWS);
    let mut d = detections(&marker, &[0, 1, 2], &(head * maxilla), &camera);
    d.extend(detections(&marker, &[lone], &mandible, &camera));
    let r = tracker.solve(d, &camera, 0.1, ROWS);
    assert!(!r.flags.contains(&Flag::Ambiguous(BodyKind::Mandible)), "{:?}", r.flags);
    let taken = r.mandible.expect("mandible").camera_from_body;
    assert!(taken.distance_to(&mandible).0.to_degrees() < 0.01, "the head's motion is followed, not the old pose");
}

#[test]
fn a_stale_relative_pose_does_not_settle_a_lone_tag() {
    let marker = Marker::default();
    let (camera, maxilla, mandible) = scene();
    let (lone, _) = lone_tag_with_mirror(&marker, &mandible, &camera);
    let limit = TrackerConfig::default().prior_max_age_s;
    let lone_frame_after = |age: f64| {
        let mut tracker = Tracker::new(marker.clone(), TrackerConfig::default()).expect("tracker");
        let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
        d.extend(detections(&marker, &[12, 13, 14], &mandible, &camera));
        tracker.solve(d, &camera, 0.0, ROWS);
        let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
        d.extend(detections(&marker, &[lone], &mandible, &camera));
        tracker.solve(d, &camera, age, ROWS)
    };
    // Long after both bodies were last seen together the relative pose no longer chooses.
    let r = lone_frame_after(20.0 * limit);
    assert!(r.flags.contains(&Flag::Ambiguous(BodyKind::Mandible)), "a stale pose chose: {:?}", r.flags);
    // Within the limit it still does, and picks the true pose.
    let r = lone_frame_after(0.8 * limit);
    assert!(!r.flags.contains(&Flag::Ambiguous(BodyKind::Mandible)), "{:?}", r.flags);
    assert!(r.mandible.expect("mandible").camera_from_body.distance_to(&mandible).0 < 1e-6);
}

#[test]
fn new_settings_keep_the_motion() {
    let marker = Marker::default();
    let (camera, maxilla, mandible) = scene();
    let (lone, _) = lone_tag_with_mirror(&marker, &mandible, &camera);
    // The jaw opening a little each frame, so that the smoother lags behind it.
    let opened =
        |i: u32| mandible * Pose::from_axis_angle(Vector3::new(0.02 * f64::from(i), 0.0, 0.0), Vector3::zeros());
    let frame = |i: u32, mandible_ids: &[u32]| {
        let mut d = detections(&marker, &[0, 1, 2], &maxilla, &camera);
        d.extend(detections(&marker, mandible_ids, &opened(i), &camera));
        d
    };
    let smoothing = TrackerConfig { smoother: Some(SmootherConfig::default()), ..TrackerConfig::default() };
    // Three frames with three tags per body, the settings changed (or not: `None`), then a
    // frame with a lone mandible tag.
    let lone_frame = |new: Option<TrackerConfig>| {
        let mut tracker = Tracker::new(marker.clone(), smoothing).expect("tracker");
        for i in 0..3 {
            tracker.solve(frame(i, &[12, 13, 14]), &camera, f64::from(i) / 30.0, ROWS);
        }
        if let Some(config) = new {
            let bad = TrackerConfig { flicker_px: -1.0, ..config };
            assert!(tracker.set_config(bad).is_err(), "a refused setting");
            assert_eq!(tracker.config(), &smoothing, "a refused setting changes nothing");
            tracker.set_config(config).expect("valid settings");
            assert_eq!(tracker.config(), &config);
        }
        tracker.solve(frame(3, &[lone]), &camera, 3.0 / 30.0, ROWS)
    };
    let raw = maxilla.inverse() * opened(3);
    let unchanged = lone_frame(None);
    assert!(!unchanged.flags.contains(&Flag::Ambiguous(BodyKind::Mandible)), "{:?}", unchanged.flags);
    let smoothed = unchanged.maxilla_from_mandible.expect("both bodies");
    assert!(smoothed.distance_to(&raw).0 > 1e-3, "the smoother lags");

    // Other settings, the same smoother: the motion and the smoother's state are kept.
    let mut other = smoothing;
    other.detector.nthreads = 2;
    other.pnp.max_iterations = 60;
    other.search.region_search = false;
    other.max_rms_px = 3.0;
    let r = lone_frame(Some(other));
    assert_eq!(r.flags, unchanged.flags);
    assert_eq!(r.mandible, unchanged.mandible);
    assert_eq!(r.maxilla_from_mandible, Some(smoothed));

    // A new smoother setting restarts the smoother (its first sample is passed through); the
    // bodies' motion is still kept.
    let retuned = TrackerConfig { smoother: Some(SmootherConfig { beta: 1.0, ..SmootherConfig::default() }), ..other };
    let r = lone_frame(Some(retuned));
    assert_eq!(r.flags, unchanged.flags);
    let (angle, dist) = r.maxilla_from_mandible.expect("both bodies").distance_to(&raw);
    assert!(angle < 1e-6 && dist < 1e-6, "{angle} rad {dist} mm");
}

#[test]
fn blurred_tags_are_searched_not_refitted_where_predicted() {
    // A phone's wide camera 160 mm away with its focus locked at 250 mm: edges blurred beyond
    // what an edge refit's windows hold, so a refit would follow where it starts. Still, so that
    // only the blur keeps the frames from being looked for where predicted.
    let config = SynthConfig {
        realism: Realism {
            occluder_probability: 0.0,
            glare_probability: 0.0,
            print_error_mm: 0.0,
            print_error_deg: 0.0,
            ..Realism::phone_wide(250.0, 1.0)
        },
        options: SceneOptions { frames_per_view: 5, distance_mm: Some(160.0), ..SceneOptions::default() },
        max_frames: Some(5),
        ..SynthConfig::new(SceneKind::Static)
    };
    let synth = Synthesizer::new(config).expect("scene");
    let mut checked = 0;
    for (i, _, a, b) in tracked_both_ways(&synth) {
        // When written: 4.3–4.6 px in every frame (without the rule, frames 1–4 were refitted
        // where predicted).
        let blur: Vec<f64> = [&a.maxilla, &a.mandible].into_iter().flatten().filter_map(|b| b.blur_px).collect();
        assert!(blur.len() == 2 && blur.iter().all(|&px| px > 3.0), "frame {i}: blur {blur:?} px");
        assert!(!a.timings.predicted && a.timings.stages.predicted == 0, "frame {i}: looked for where predicted");
        let tags = |r: &FrameResult| [&r.maxilla, &r.mandible].map(|b| b.as_ref().map(|b| b.tags.clone()));
        assert_eq!((tags(&a), a.maxilla_from_mandible), (tags(&b), b.maxilla_from_mandible), "frame {i}");
        checked += 1;
    }
    assert_eq!(checked, 5);
}

/// `synth`'s frames tracked twice, looking for tags where predicted and searching the region:
/// each frame's index, true jaw pose and the two results.
fn tracked_both_ways(synth: &Synthesizer) -> Vec<(usize, Pose, FrameResult, FrameResult)> {
    let camera = synth.header().intrinsics;
    let tracker_with = |predicted: bool| {
        let search = SearchConfig { predicted, ..SearchConfig::default() };
        Tracker::new(synth.true_marker().clone(), TrackerConfig { search, ..TrackerConfig::default() })
            .expect("tracker")
    };
    let (mut predicting, mut searching) = (tracker_with(true), tracker_with(false));
    (0..synth.len())
        .map(|i| {
            let f = synth.render(i).expect("frame");
            let (w, h) = (f.width as usize, f.height as usize);
            let view = ImageView::new(&f.luma, w, h, w).expect("view");
            let a = predicting.track(&view, &camera, f.truth.t).expect("tracks");
            let b = searching.track(&view, &camera, f.truth.t).expect("tracks");
            (i, f.truth.maxilla_from_mandible, a, b)
        })
        .collect()
}
