//! Tests of the scenes: their frame lists and the jaw motions.

use super::*;

#[test]
fn hinge_opens_the_incisors_by_the_requested_chord() {
    let rig = Rig::default();
    let motion = JawMotion::Hinge { opening_mm: 30.0, start_s: 0.0, period_s: 2.0 };
    let peak = rig.jaw(&motion, 1.0);
    let p = Point3::from(rig.mounting.lower_incisal_point);
    let moved = peak.transform_point(&p) - p;
    assert!((moved.norm() - 30.0).abs() < 1e-9);
    assert!(moved.y > 20.0, "opens downward: {moved:?}");
    assert!(rig.jaw(&motion, 0.0).distance_to(&Pose::identity()).1 < 1e-12);
    // Read back from the markers' relative pose, as a tracker would see it.
    let (maxilla, mandible) = rig.markers(&motion, 1.0);
    let seen = rig.mounting.lower_incisor(&(maxilla.inverse() * mandible));
    assert!((seen - peak.transform_point(&p)).norm() < 1e-9);
}

#[test]
fn glides_go_where_they_say() {
    let rig = Rig::default();
    let p = Point3::from(rig.mounting.lower_incisal_point);
    for (dir, check) in [
        (Glide::Left, Box::new(|d: Vector3<f64>| d.x > 3.9) as Box<dyn Fn(Vector3<f64>) -> bool>),
        (Glide::Right, Box::new(|d: Vector3<f64>| d.x < -3.9)),
        (Glide::Protrusive, Box::new(|d: Vector3<f64>| d.z < -4.9 && d.y > 0.0)),
    ] {
        let m = JawMotion::Glide { direction: dir, amplitude_mm: 5.0, start_s: 0.0, period_s: 2.0 };
        let d = rig.jaw(&m, 1.0).transform_point(&p) - p;
        assert!(check(d), "{dir:?}: {d:?}");
    }
}

#[test]
fn camera_looks_at_the_target_from_the_given_distance() {
    let v = View {
        distance_mm: 100.0,
        azimuth_deg: 30.0,
        elevation_deg: 10.0,
        target: [0.0, 0.0, -38.0],
        hand_seed: None,
        orientation: Orientation::Upright,
    };
    let c = v.camera_from_head(0.0);
    let target = c.transform_point(&Point3::new(0.0, 0.0, -38.0));
    assert!(target.x.abs() < 1e-9 && target.y.abs() < 1e-9 && (target.z - 100.0).abs() < 1e-9);
    // Head "down" appears toward image +x at azimuth 0.
    let v0 = View { azimuth_deg: 0.0, elevation_deg: 0.0, ..v };
    let c0 = v0.camera_from_head(0.0);
    assert!(c0.transform_vector(&Vector3::y()).x > 0.99);
    // Tremor stays small.
    let h = View { hand_seed: Some(7), ..v };
    let (a, d) = h.camera_from_head(0.3).distance_to(&c);
    assert!(a.to_degrees() < 2.0 && d < 4.0 && (a > 0.0 || d > 0.0));
}

#[test]
fn scenes_have_the_documented_shape() {
    let o = SceneOptions::default();
    assert_eq!(scene_frames(SceneKind::Static, &o, 1).len(), 2 * 9 * 2);
    assert_eq!(scene_frames(SceneKind::Hinge, &o, 1).len(), 4 * 2 * 60);
    assert_eq!(scene_frames(SceneKind::Excursion, &o, 1).len(), 3 * 2 * 60);
    assert_eq!(scene_frames(SceneKind::Calibration, &o, 1).len(), 3 * 6 * 2);
    assert_eq!(scene_frames(SceneKind::Wave, &o, 1).len(), 2 * 60);
}

/// The chew cycles' motions, in order.
fn chew_cycles(frames: &[FrameSpec]) -> Vec<(f64, f64, f64, f64)> {
    let mut cycles: Vec<(f64, f64, f64, f64)> = Vec::new();
    for f in frames {
        let JawMotion::Chew { opening_mm, lateral_mm, start_s, period_s } = f.motion else {
            panic!("not a chewing frame: {:?}", f.motion)
        };
        if cycles.last().is_none_or(|c| c.2 != start_s) {
            cycles.push((opening_mm, lateral_mm, start_s, period_s));
        }
    }
    cycles
}

#[test]
fn chew_is_fast_chewing_on_a_tripod() {
    let rig = Rig::default();
    for seed in 1..=8 {
        for fps in [30.0, 60.0] {
            let opts = SceneOptions { fps, cycles: 3, ..SceneOptions::default() };
            let frames = scene_frames(SceneKind::Chew, &opts, seed);
            assert!(frames.iter().all(|f| f.view.hand_seed.is_none()
                && f.view.distance_mm == 120.0
                && f.view.azimuth_deg == 0.0
                && f.view.orientation == Orientation::Upright));
            let cycles = chew_cycles(&frames);
            assert_eq!(cycles.len(), 3, "seed {seed}");
            let mut end = 0.0;
            for &(opening, lateral, start, period) in &cycles {
                assert!((15.0..=25.0).contains(&opening) && (3.0..=6.0).contains(&lateral), "{cycles:?}");
                assert!((0.6..=0.8).contains(&period) && start == end, "{cycles:?}");
                end += period;
            }
            assert_eq!(frames.len(), (end * fps).round() as usize);
            assert!(frames.windows(2).all(|w| (w[1].t - w[0].t - 1.0 / fps).abs() < 1e-9), "a steady frame rate");
            let peak = frames.iter().map(|f| rig.incisor_speed(&f.motion, f.t)).fold(0.0, f64::max);
            assert!(peak >= 100.0, "seed {seed} at {fps} fps: the incisor peaks at {peak:.0} mm/s");
        }
    }
}

#[test]
fn a_chewing_cycle_opens_and_swings_as_far_as_it_says() {
    let rig = Rig::default();
    let p = Point3::from(rig.mounting.lower_incisal_point);
    let motion = JawMotion::Chew { opening_mm: 20.0, lateral_mm: 4.0, start_s: 1.0, period_s: 0.7 };
    let moved = |t: f64| rig.jaw(&motion, t).transform_point(&p) - p;
    assert!(moved(1.0).norm() < 1e-12 && moved(1.7).norm() < 1e-9, "closed at each cycle's ends");
    // The opening's chord at mid-cycle (the swing is zero there), the swing's peak anywhere.
    assert!((moved(1.35).norm() - 20.0).abs() < 1e-9);
    let swing = (0..=7000).map(|i| moved(1.0 + 0.7 * f64::from(i) / 7000.0).x).fold(0.0f64, |a, x| a.max(x.abs()));
    assert!((swing - 4.0).abs() < 1e-3, "peak swing {swing}");
}

/// The rows the scene documents for the markers ([`Orientation`]).
#[test]
fn chew_markers_fall_in_the_documented_rows() {
    let k = crate::Resolution::P1080.default_intrinsics();
    let rig = Rig::default();
    let rows = |orientation: Orientation| {
        let opts = SceneOptions { orientation, cycles: 1, fps: 240.0, ..SceneOptions::default() };
        let frames = scene_frames(SceneKind::Chew, &opts, 1);
        let centre_rows: Vec<(f64, f64)> = frames
            .iter()
            .map(|f| {
                let (maxilla, mandible) = rig.markers(&f.motion, f.t);
                let camera_from_head = f.view.camera_from_head(f.t);
                let row = |body: Pose| {
                    k.project(&(camera_from_head * body).transform_point(&Point3::origin())).map_or(f64::NAN, |p| p.y)
                };
                (row(maxilla), row(mandible))
            })
            .collect();
        let mandible = centre_rows.iter().map(|r| r.1);
        let range = (mandible.clone().fold(f64::INFINITY, f64::min), mandible.fold(f64::NEG_INFINITY, f64::max));
        let swing = chew_cycles(&frames)[0].1;
        (centre_rows[0], range, swing)
    };
    let ((maxilla, mandible), range, swing) = rows(Orientation::Upright);
    eprintln!("upright: centre rows {maxilla:.1} and {mandible:.1}; mandible {range:.1?} while chewing");
    assert!((maxilla - 539.5).abs() < 1e-6 && (mandible - 539.5).abs() < 1e-6);
    let per_mm = [539.5 - range.0, range.1 - 539.5].map(|d| d / swing);
    assert!(per_mm.iter().all(|r| (10.0..=12.5).contains(r)), "{per_mm:?} rows per mm of swing");
    let ((maxilla, mandible), range, _) = rows(Orientation::Landscape);
    eprintln!("landscape: centre rows {maxilla:.1} and {mandible:.1}; mandible {range:.1?} while chewing");
    assert!((maxilla - 89.5).abs() < 1e-6 && (mandible - 639.5).abs() < 1e-6);
    assert!(range.0 > 639.0 && range.1 < 1000.0, "{range:?}");
}

/// The wave sweeps the markers over the image at 90–200 mm and 50–150 mm/s or so.
#[test]
fn wave_sweeps_the_markers_across_the_image() {
    let k = crate::Resolution::P1080.default_intrinsics();
    let rig = Rig::default();
    let opts = SceneOptions { cycles: 2, ..SceneOptions::default() };
    let frames = scene_frames(SceneKind::Wave, &opts, 1);
    assert_eq!(frames.len(), 120);
    let (maxilla, mandible) = rig.markers(&JawMotion::Rest, 0.0);
    let centres = |f: &FrameSpec, t: f64| {
        let c = f.camera_from_head(t);
        [maxilla, mandible].map(|m| (c * m).translation())
    };
    let (mut x, mut y, mut z) = ((f64::MAX, f64::MIN), (f64::MAX, f64::MIN), (f64::MAX, f64::MIN));
    let mut speeds = Vec::new();
    for f in &frames {
        for (p, q) in centres(f, f.t).iter().zip(centres(f, f.t + 1e-4)) {
            let px = k.project(&Point3::from(*p)).expect("in front");
            x = (x.0.min(px.x), x.1.max(px.x));
            y = (y.0.min(px.y), y.1.max(px.y));
            z = (z.0.min(p.z), z.1.max(p.z));
            speeds.push((q - p).norm() / 1e-4);
        }
    }
    speeds.sort_by(f64::total_cmp);
    let (median, top) = (speeds[speeds.len() / 2], speeds[speeds.len() - 1]);
    assert!(x.0 < 150.0 && x.1 > 1770.0 && y.0 < 200.0 && y.1 > 880.0, "{x:?} {y:?}");
    assert!(z.0 > 80.0 && z.0 < 100.0 && z.1 > 180.0 && z.1 < 210.0, "{z:?}");
    assert!((50.0..150.0).contains(&median) && top < 200.0, "speed median {median} mm/s, top {top}");
    let flat = Wave { tilt_deg: [0.0; 3], ..frames[0].wave.expect("a wave") };
    assert!(flat.camera_from_head(0.7).rotation().angle_to(&frames[0].view.camera_from_head(0.0).rotation()) < 1e-12);
    // The other scenes' frames say nothing of a wave.
    let still = scene_frames(SceneKind::Static, &opts, 1);
    assert!(!serde_json::to_string(&still[0]).expect("json").contains("wave"));
    assert_eq!(still[0].camera_from_head(0.3), still[0].view.camera_from_head(0.3));
}

#[test]
fn landscape_turns_the_phone_a_quarter_turn() {
    let v = View {
        distance_mm: 120.0,
        azimuth_deg: 0.0,
        elevation_deg: 0.0,
        target: CHEW_TARGET,
        hand_seed: None,
        orientation: Orientation::Landscape,
    };
    let c = v.camera_from_head(0.0);
    // Image x toward the patient's left, image y down the head.
    assert!(c.transform_vector(&Vector3::x()).x > 0.999 && c.transform_vector(&Vector3::y()).y > 0.999);
    let upright = View { orientation: Orientation::Upright, ..v }.camera_from_head(0.0);
    let place = |p: Pose| p.inverse().translation();
    assert!((place(upright) - place(c)).norm() < 1e-9, "same place, only turned");
    // Files written before the field existed are upright.
    let old = r#"{"distance_mm": 100.0, "azimuth_deg": 0.0, "elevation_deg": 0.0, "target": [0, 0, 0],
        "hand_seed": null}"#;
    let view: View = serde_json::from_str(old).expect("an old view reads");
    assert_eq!(view.orientation, Orientation::Upright);
    let old = r#"{"kind": "chew", "opening_mm": 18.0, "lateral_mm": 5.0, "period_s": 0.8}"#;
    let motion: JawMotion = serde_json::from_str(old).expect("an old chew reads");
    assert!(matches!(motion, JawMotion::Chew { start_s, .. } if start_s == 0.0));
}

#[test]
fn the_border_scene_runs_each_guided_movement_out_and_back() {
    let rig = Rig::default();
    let opts = SceneOptions { cycles: 1, fps: 10.0, ..SceneOptions::default() };
    let frames = scene_frames(SceneKind::Border, &opts, 1);
    assert_eq!(frames.len(), 3 * 20, "three movements of 2 s at 10 fps");
    let g = Guidance::default();
    let condyle = |side| Point3::from(rig.mounting.condyle(side));
    // At each movement's peak (1 s in), the condyles are where the guided motion puts them.
    for (k, f) in frames.iter().enumerate().filter(|(k, _)| k % 20 == 10) {
        let jaw = rig.jaw(&f.motion, f.t);
        let (want, side) = match k / 20 {
            0 => (rig.protrusion(&g, BORDER_TRAVEL_MM), Side::Left),
            1 => (rig.laterotrusion(&g, Side::Left, BORDER_TRAVEL_MM), Side::Right),
            _ => (rig.laterotrusion(&g, Side::Right, BORDER_TRAVEL_MM), Side::Left),
        };
        let off = (jaw.transform_point(&condyle(side)) - want.transform_point(&condyle(side))).norm();
        assert!(off < 1e-9, "frame {k}: {off}");
        let travelled = (jaw.transform_point(&condyle(side)) - condyle(side)).norm();
        assert!(travelled > BORDER_TRAVEL_MM - 1e-6, "frame {k}: {travelled}");
    }
    // Each starts and ends closed.
    for f in frames.iter().step_by(20) {
        assert!(rig.jaw(&f.motion, f.t).translation().norm() < 1e-9);
    }
}

#[test]
fn a_distance_puts_the_static_grid_and_the_chew_camera_there() {
    let at = |d| SceneOptions { frames_per_view: 1, distance_mm: d, ..SceneOptions::default() };
    let grid = scene_frames(SceneKind::Static, &at(Some(220.0)), 1);
    // Azimuth 0/30/60°, tripod and hand: six views, all at 220 mm.
    assert_eq!(grid.len(), 6);
    assert!(grid.iter().all(|f| f.view.distance_mm == 220.0));
    let azimuths: Vec<f64> = grid.iter().map(|f| f.view.azimuth_deg).collect();
    assert_eq!(azimuths, [0.0, 30.0, 60.0, 0.0, 30.0, 60.0]);
    assert_eq!(scene_frames(SceneKind::Static, &at(None), 1).len(), 18, "80/100/120 mm without one");
    let chew = scene_frames(SceneKind::Chew, &SceneOptions { distance_mm: Some(250.0), ..SceneOptions::default() }, 1);
    assert!(!chew.is_empty() && chew.iter().all(|f| f.view.distance_mm == 250.0));
    let chew = scene_frames(SceneKind::Chew, &SceneOptions::default(), 1);
    assert!(!chew.is_empty() && chew.iter().all(|f| f.view.distance_mm == 120.0));
}
