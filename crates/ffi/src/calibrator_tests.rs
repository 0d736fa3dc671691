//! The calibrator on views made from a marker with known print errors, and on a tracker's
//! frames of the hinge fixture.

use super::*;
use crate::{Intrinsics, default_settings};
use jawtrack_calibration::SeenTag;
use jawtrack_marker::{PrintError, TagProvenance};
use jawtrack_pose::{CameraIntrinsics, Pose};
use nalgebra::{Point3, UnitQuaternion, Vector3};

fn camera() -> CameraIntrinsics {
    CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5)
}

/// The marker as printed: tag 13 shifted and turned, tag 2 shifted.
fn printed() -> Marker {
    Marker::default()
        .with_print_errors(&[
            (13, PrintError { shift_x: 0.3, shift_y: -0.2, rotation: 1.5f64.to_radians() }),
            (2, PrintError { shift_x: -0.25, shift_y: 0.0, rotation: 0.0 }),
        ])
        .expect("print errors")
}

/// Both bodies facing the camera, turned by `tilt_deg` about x and y.
fn poses(tilt_deg: (f64, f64)) -> Vec<(BodyKind, Pose)> {
    let facing = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
    let turn = UnitQuaternion::from_euler_angles(tilt_deg.0.to_radians(), tilt_deg.1.to_radians(), 0.0);
    vec![
        (BodyKind::Maxilla, Pose::from_parts(turn * facing, Vector3::new(-2.0, -16.0, 110.0))),
        (BodyKind::Mandible, Pose::from_parts(turn * facing, Vector3::new(2.0, 16.0, 112.0))),
    ]
}

/// What a tracker keeps of a frame of `marker` at `poses`: the tags facing the camera within
/// 70°, projected exactly.
fn view(marker: &Marker, poses: &[(BodyKind, Pose)]) -> TrackedView {
    let camera = camera();
    let mut tags = Vec::new();
    for (kind, pose) in poses {
        let Some(body) = marker.body(*kind) else { continue };
        for tag in &body.tags {
            let centre = pose.transform_point(&Point3::from(tag.center));
            let normal = pose.rotation() * tag.face_normal();
            if normal.dot(&-centre.coords.normalize()) < 70f64.to_radians().cos() {
                continue;
            }
            let corners = tag.corners.map(|c| {
                let p = camera.project(&pose.transform_point(&Point3::from(c))).expect("in front");
                [p.x, p.y]
            });
            tags.push(SeenTag { id: tag.id, corners });
        }
    }
    TrackedView { camera, tags, poses: poses.to_vec() }
}

fn last(p: &CalibrationProgress, body: &str) -> Option<ViewOutcome> {
    p.bodies.iter().find(|b| b.body == body).expect("body").last
}

fn views_of(p: &CalibrationProgress, id: u32) -> u32 {
    p.tags.iter().find(|t| t.id == id).expect("tag").views
}

/// A grid of turns, 20° apart.
fn tour() -> Vec<(f64, f64)> {
    let steps = [-40.0, -20.0, 0.0, 20.0, 40.0];
    steps.iter().flat_map(|&x| steps.iter().map(move |&y| (x, y))).collect()
}

#[test]
fn views_count_angles_not_frames() {
    let marker = printed();
    let cal = Calibrator::new(None, 3).expect("calibrator");
    let start = cal.progress();
    assert_eq!((start.views, start.added, start.note.as_str()), (0, false, ""));
    assert_eq!(start.tags.len(), 24);
    assert_eq!(start.needs_views.len(), 24);
    assert!(!start.can_solve && !start.complete);
    assert_eq!(last(&start, "maxilla"), None);

    let first = cal.add(Some(&view(&marker, &poses((0.0, 0.0)))));
    assert!(first.added, "{}", first.note);
    assert_eq!(first.views, 1);
    assert_eq!(last(&first, "maxilla"), Some(ViewOutcome::Added));
    assert_eq!(last(&first, "mandible"), Some(ViewOutcome::Added));
    let seen: Vec<u32> = first.tags.iter().filter(|t| t.views == 1).map(|t| t.id).collect();
    assert!(seen.len() >= 6 && seen.contains(&0) && seen.contains(&12), "{seen:?}");
    assert!(first.bodies.iter().all(|b| b.last_tags >= 3), "{:?}", first.bodies);

    // The same frame again, or the marker turned by 3°: nothing new.
    for tilt in [(0.0, 0.0), (3.0, 0.0)] {
        let again = cal.add(Some(&view(&marker, &poses(tilt))));
        assert!(!again.added, "{tilt:?}: {}", again.note);
        assert_eq!(again.views, 1);
        assert_eq!(last(&again, "mandible"), Some(ViewOutcome::SameView));
        assert!(again.note.contains("seen from this angle already"), "{}", again.note);
    }
    // Turned by 8°: a view of both.
    let turned = cal.add(Some(&view(&marker, &poses((8.0, 0.0)))));
    assert!(turned.added);
    assert_eq!(turned.views, 2);
    assert_eq!(views_of(&turned, 0), 2);
    assert!(turned.note.contains("maxilla: view 2 added"), "{}", turned.note);

    // One mandible tag alone: the maxilla's view counts, the mandible's does not.
    let mut lone = view(&marker, &poses((-20.0, 15.0)));
    let mandible_tags: Vec<u32> = lone.tags.iter().map(|t| t.id).filter(|&id| id >= 12).collect();
    lone.tags.retain(|t| t.id < 12 || t.id == mandible_tags[0]);
    let p = cal.add(Some(&lone));
    assert!(p.added);
    assert_eq!(last(&p, "maxilla"), Some(ViewOutcome::Added));
    assert_eq!(last(&p, "mandible"), Some(ViewOutcome::TooFewTags));
    assert_eq!(p.bodies[1].views, 2);
    assert!(p.note.contains("mandible: 1 tag(s) seen, a view needs two or more"), "{}", p.note);

    // Tags enough but no pose: the turn is unknown.
    let mut untracked = view(&marker, &poses((30.0, -30.0)));
    untracked.poses.retain(|(k, _)| *k == BodyKind::Maxilla);
    let p = cal.add(Some(&untracked));
    assert_eq!(last(&p, "mandible"), Some(ViewOutcome::NotTracked));

    // No frame at all.
    let none = cal.add(None);
    assert!(!none.added);
    assert!(none.note.contains("no frame to add"), "{}", none.note);
    assert!(none.bodies.iter().all(|b| b.last.is_none()));
    assert_eq!(none.views, 4, "kept views stay");

    cal.reset();
    assert_eq!(cal.progress().views, 0);
    assert_eq!(cal.progress().needs_views.len(), 24);
}

#[test]
fn a_new_tag_within_the_turn_is_a_new_view() {
    let marker = printed();
    let cal = Calibrator::new(None, 3).expect("calibrator");
    let mut partial = view(&marker, &poses((0.0, 0.0)));
    let dropped = partial.tags.iter().map(|t| t.id).filter(|&id| id < 12).max().expect("a maxilla tag");
    partial.tags.retain(|t| t.id != dropped);
    assert!(cal.add(Some(&partial)).added);
    let whole = cal.add(Some(&view(&marker, &poses((1.0, 0.0)))));
    assert_eq!(last(&whole, "maxilla"), Some(ViewOutcome::Added), "tag {dropped} is new");
    assert_eq!(last(&whole, "mandible"), Some(ViewOutcome::SameView));
    assert_eq!(views_of(&whole, dropped), 1);
}

#[test]
fn solving_places_the_displaced_tags_and_leaves_the_unseen_nominal() {
    let marker = printed();
    let cal = Calibrator::new(None, 3).expect("calibrator");
    let refused = cal.solve().expect_err("no views");
    assert!(matches!(&refused, JawTrackError::Calibration { message } if message.contains("3 views")), "{refused:?}");
    cal.add(Some(&view(&marker, &poses((0.0, 0.0)))));
    cal.add(Some(&view(&marker, &poses((20.0, 0.0)))));
    let short = cal.solve().expect_err("two views");
    assert!(short.to_string().contains("the most seen has 2"), "{short}");

    let mut progress = cal.progress();
    for tilt in tour() {
        let p = cal.add(Some(&view(&marker, &poses(tilt))));
        assert!(p.views >= progress.views);
        progress = p;
    }
    assert_eq!(progress.views, 25, "the tour's 25 turns, two of them seen before");
    assert!(progress.can_solve);
    assert!(!progress.complete, "the faces looking away were never seen");
    let unseen: Vec<u32> = progress.tags.iter().filter(|t| t.views == 0).map(|t| t.id).collect();
    assert!(!unseen.is_empty());
    assert!(unseen.iter().all(|id| progress.needs_views.contains(id)));

    let result = cal.solve().expect("solved");
    assert_eq!(result.bodies.len(), 2);
    for b in &result.bodies {
        assert_eq!(b.views, 25, "{}", b.body);
        assert!(b.rms_after_px < 0.05 && b.rms_before_px > 0.2, "{b:?}");
        assert!(b.tags_calibrated > 0 && b.tags_calibrated < b.tags_total);
    }
    assert_eq!(result.tags.len(), 24);
    let row = |id: u32| result.tags.iter().find(|t| t.id == id).expect("row");
    let shifted = row(13);
    assert!(shifted.calibrated);
    assert_eq!(shifted.body, "mandible");
    assert!((shifted.shift_x_mm.expect("x") - 0.3).abs() < 0.03, "{shifted:?}");
    assert!((shifted.shift_y_mm.expect("y") + 0.2).abs() < 0.03, "{shifted:?}");
    assert!((shifted.turn_deg.expect("turn") - 1.5).abs() < 0.2, "{shifted:?}");
    assert!(shifted.rms_before_px.expect("before") > shifted.rms_after_px.expect("after") * 5.0, "{shifted:?}");
    assert!((row(2).shift_x_mm.expect("x") + 0.25).abs() < 0.03, "{:?}", row(2));
    assert!(row(0).shift_x_mm.expect("x").abs() < 0.03, "an upright tag stays: {:?}", row(0));
    let never = row(unseen[0]);
    assert!(!never.calibrated);
    assert_eq!((never.views, never.shift_x_mm, never.rms_after_px), (0, None, None));
    assert!(
        result.findings.iter().any(|f| f.starts_with(&format!("tag {} was seen in 0 usable view(s)", unseen[0]))),
        "{:?}",
        result.findings
    );
    assert_eq!(result.focal_warning, None, "the right focal length");
    let solved = Marker::from_json(&result.marker_json).expect("a marker file");
    let (_, tag) = solved.find_tag(13).expect("tag 13");
    let views = shifted.views;
    assert!(views >= 3 && views == views_of(&progress, 13), "{shifted:?}");
    assert!(
        matches!(tag.provenance, Some(TagProvenance::Calibrated { views: v, .. }) if v == views),
        "{:?}",
        tag.provenance
    );
}

#[test]
fn saving_never_replaces_a_file_unless_asked() {
    let marker = printed();
    let cal = Calibrator::new(None, 3).expect("calibrator");
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("marker.json");
    let text = |p: &Path| std::fs::read_to_string(p).expect("file");
    let e = cal.save(path.display().to_string(), false).expect_err("nothing solved");
    assert!(matches!(&e, JawTrackError::InvalidArgument { message } if message.contains("solve")), "{e:?}");
    for tilt in tour() {
        cal.add(Some(&view(&marker, &poses(tilt))));
    }
    let result = cal.solve().expect("solved");
    cal.save(path.display().to_string(), false).expect("saved");
    assert_eq!(text(&path), result.marker_json.clone() + "\n");
    let loaded = Marker::load(&path).expect("loads");
    assert!(loaded.is_calibrated());

    std::fs::write(&path, "precious").expect("writing");
    let e = cal.save(path.display().to_string(), false).expect_err("exists");
    assert!(matches!(&e, JawTrackError::Io { message, .. } if message.contains("already exists")), "{e:?}");
    assert_eq!(text(&path), "precious", "left alone");
    cal.save(path.display().to_string(), true).expect("replaced when asked");
    assert_eq!(text(&path), result.marker_json.clone() + "\n");
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into())
        .collect();
    assert_eq!(names, ["marker.json"], "no temporary file left");

    let missing = dir.path().join("no-such-folder").join("marker.json");
    let e = cal.save(missing.display().to_string(), false).expect_err("no folder");
    assert!(matches!(&e, JawTrackError::Io { path, .. } if path.ends_with("marker.json")), "{e:?}");

    // New views make the solve stale.
    cal.add(Some(&view(&marker, &poses((50.0, 50.0)))));
    let e = cal.save(path.display().to_string(), true).expect_err("stale");
    assert!(e.to_string().contains("solve again"), "{e}");
}

#[test]
fn bad_starts_are_refused_with_what_to_do() {
    let e = Calibrator::new(Some("{\"version\": 7}".into()), 3).err().expect("bad marker");
    assert!(matches!(&e, JawTrackError::InvalidMarker { message } if message.contains("version")), "{e:?}");
    let e = Calibrator::new(None, 0).err().expect("zero views");
    assert!(matches!(&e, JawTrackError::InvalidSetting { setting, .. } if setting == "min_views"), "{e:?}");
    let printed = Calibrator::new(Some(printed().to_json()), 2).expect("any marker file");
    assert_eq!(printed.progress().min_views, 2);
    assert_eq!(printed.marker, self::printed(), "an uncalibrated file is the start");
}

#[test]
fn a_calibrated_marker_starts_afresh_from_its_nominal_solid() {
    let marker = printed();
    let first = Calibrator::new(None, 3).expect("calibrator");
    for tilt in tour() {
        first.add(Some(&view(&marker, &poses(tilt))));
    }
    let calibrated = first.solve().expect("solved").marker_json;
    let again = Calibrator::new(Some(calibrated.clone()), 3).expect("from the calibrated file");
    assert_eq!(again.marker, Marker::default(), "the nominal marker of its size, no provenance");
    // A file of another size starts from its own nominal marker.
    let mut small = Marker::nominal(10.0, None).expect("10 mm");
    small.bodies.truncate(1);
    let small_calibrated = Calibrator::new(Some(small.to_json()), 3).expect("calibrator");
    for tilt in tour() {
        small_calibrated.add(Some(&view(&small, &poses(tilt))));
    }
    let text = small_calibrated.solve().expect("solved").marker_json;
    let from = Calibrator::new(Some(text), 3).expect("from the small calibrated file");
    assert_eq!(from.marker, small);
    // Tags that a nominal marker of its size does not have cannot start afresh.
    let mut odd = Marker::from_json(&calibrated).expect("calibrated");
    odd.bodies[0].tags.retain(|t| t.id != 5);
    let e = Calibrator::new(Some(odd.to_json()), 3).err().expect("refused");
    assert!(matches!(&e, JawTrackError::InvalidMarker { message } if message.contains("nominal marker file")), "{e:?}");
}

#[test]
fn a_calibrated_marker_of_another_solid_and_family_starts_from_its_own_nominal() {
    use jawtrack_marker::{BodyProvenance, SolidKind, TagFamily};
    let nominal = Marker::nominal_on(SolidKind::Cube, TagFamily::TAG25H9, 15.0, None).expect("cube marker");
    let mut calibrated = nominal.clone();
    for body in &mut calibrated.bodies {
        body.provenance =
            Some(BodyProvenance { views: 9, rms_before_px: 1.0, rms_after_px: 0.2, recordings: vec!["r".into()] });
        for t in &mut body.tags {
            t.provenance = Some(TagProvenance::Calibrated { views: 9, rms_before_px: 1.0, rms_after_px: 0.2 });
        }
    }
    assert!(calibrated.is_calibrated());
    let again = Calibrator::new(Some(calibrated.to_json()), 3).expect("from the calibrated cube file");
    assert_eq!(again.marker, nominal, "the nominal cube in tag25h9, not a tag36h11 dodecahedron");
}

#[test]
fn a_wrong_focal_length_is_named() {
    let focal = FocalCheck { views: 12, given_px: 3.1, best_scale: 1.52, best_px: 0.4 };
    let text = focal_warning(&focal, [0.2, 0.9]);
    assert!(text.starts_with("the camera's focal length looks wrong: over 12 views, focal lengths 1.52×"), "{text}");
    assert!(text.contains("the marker fits with 0.90 px"), "{text}");
}

/// The hinge fixture tracked by a real tracker, each frame handed to the calibrator.
#[test]
fn a_trackers_frames_feed_the_calibrator() {
    let folder = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/hinge-1080p");
    let mut paths: Vec<_> = std::fs::read_dir(folder)
        .expect("fixture")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    paths.sort();
    let tracker = Tracker::new(default_settings(), None).expect("tracker");
    let cal = Calibrator::new(Some(tracker.marker_json()), 3).expect("calibrator");
    assert!(cal.add_view(&tracker).note.contains("no frame to add"));
    let intrinsics = Intrinsics { fx: 1500.0, fy: 1500.0, cx: 959.5, cy: 539.5, k1: 0.0, k2: 0.0 };
    let mut counts = Vec::new();
    for (i, p) in paths.iter().enumerate() {
        let img = image::open(p).expect("frame").to_luma8();
        let (w, h) = img.dimensions();
        tracker.track_luma(img.into_raw(), w, h, w, intrinsics, i as f64 / 30.0, None).expect("tracked");
        let progress = cal.add_view(&tracker);
        counts.push((progress.bodies[0].views, progress.bodies[1].views));
    }
    // The upper jaw holds still: one view. The lower one opens by 18° over the frames.
    assert_eq!(counts[0], (1, 1));
    assert!(counts.iter().all(|&(maxilla, _)| maxilla == 1), "{counts:?}");
    assert!(counts.windows(2).all(|w| w[1].1 >= w[0].1), "{counts:?}");
    assert!(counts[4].1 >= 3, "{counts:?}");
    // A frame that fails leaves nothing to add twice.
    assert!(tracker.track_luma(vec![0; 10], 4, 4, 4, intrinsics, 1.0, None).is_err());
    assert!(cal.add_view(&tracker).note.contains("no frame to add"));
}
