//! The tracker under a rolling shutter: corners seen where each body was when its row was read,
//! the jaw chewing fast, and the relative pose checked at the frame's time.

mod support;

use jawtrack_marker::Marker;
use jawtrack_pose::RollingShutter;
use jawtrack_tracker::{Tracker, TrackerConfig};
use nalgebra::Point3;
use support::{FPS, READOUT_S, ROWS, camera, detections, mandible, maxilla};

/// The worst error (mm) of `maxilla_from_mandible`'s incisor-region point over a second of
/// chewing, from the third frame on (the first two have no velocity yet), tracked with the
/// tracker told `readout_s`.
fn worst_error(told_readout_s: f64) -> f64 {
    let marker = Marker::default();
    let shutter = RollingShutter::new(READOUT_S, ROWS).expect("valid");
    let config = TrackerConfig { readout_s: told_readout_s, ..TrackerConfig::default() };
    let mut tracker = Tracker::new(marker.clone(), config).expect("tracker");
    let probe = Point3::new(0.0, -20.0, -30.0);
    let mut worst: f64 = 0.0;
    for i in 0..60 {
        let t = f64::from(i) / FPS;
        let r = tracker.solve(detections(&marker, t, &shutter), &camera(), t, ROWS);
        let got = r.maxilla_from_mandible.expect("both bodies");
        let truth = maxilla().inverse() * mandible(t);
        if i >= 2 {
            worst = worst.max((got.transform_point(&probe) - truth.transform_point(&probe)).norm());
        }
    }
    worst
}

#[test]
fn the_jaw_is_solved_at_the_frame_time_under_a_rolling_shutter() {
    let ignored = worst_error(0.0);
    let compensated = worst_error(READOUT_S);
    // Half a readout apart at ~90 mm/s: a few tenths of a millimetre when the shutter is
    // ignored; carried to the frame's time, the noise-free corners give the jaw to microns.
    assert!(ignored > 0.2, "ignoring a 10 ms readout should cost tenths of a mm, got {ignored} mm");
    assert!(compensated < 0.01, "compensated worst error {compensated} mm (ignored: {ignored} mm)");
}

#[test]
fn a_readout_out_of_range_is_refused_by_name() {
    for bad in [-0.001, f64::NAN, 2.0] {
        let config = TrackerConfig { readout_s: bad, ..TrackerConfig::default() };
        let e = Tracker::new(Marker::default(), config).expect_err("refused").to_string();
        assert!(e.contains("readout"), "{e}");
    }
}
