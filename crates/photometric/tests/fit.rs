//! The refinement's refusals and its bound, on tags drawn from the model itself.

use jawtrack_apriltag::ImageView;
use jawtrack_photometric::{Body, Image, Motion, Options, Pattern, RefineError, Refined, Tag, bound, refine};
use jawtrack_pose::{CameraIntrinsics, Pose, RollingShutter, Velocity};
use jawtrack_tag_family::{TagBitmap, TagFamily};
use nalgebra::{UnitQuaternion, Vector3};

/// A 10 mm tag in the body's x–y plane, centred on its origin, printing `bitmap`.
fn square(bitmap: &TagBitmap) -> [Tag<'_>; 1] {
    [Tag { corners: [[-5.0, 5.0, 0.0], [5.0, 5.0, 0.0], [5.0, -5.0, 0.0], [-5.0, -5.0, 0.0]], bitmap }]
}

fn refine_at(z: f64, blur_px: f64) -> Result<Refined, RefineError> {
    let luma = vec![128u8; 64 * 48];
    let frame = ImageView::new(&luma, 64, 48, 64).expect("frame");
    let linear: [f64; 256] = std::array::from_fn(|v| v as f64);
    let bitmap = TagFamily::TAG36H11.bitmap(0).expect("tag 0");
    let tags = square(&bitmap);
    let camera = CameraIntrinsics::pinhole(60.0, 60.0, 31.5, 23.5);
    // Shifted far to the side: off the frame.
    let pose = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(500.0, 0.0, z));
    let body = Body { image: Image { frame, linear: &linear }, camera: &camera, tags: &tags, blur_px, motion: None };
    refine(&body, &pose, &Options::default())
}

#[test]
fn a_tag_off_the_frame_or_behind_the_camera_has_no_pixels() {
    assert_eq!(refine_at(100.0, 0.5), Err(RefineError::NoPixels));
    assert_eq!(refine_at(-100.0, 0.5), Err(RefineError::NoPixels));
}

/// Tag 0, 10 mm across, drawn 100 mm in front of a 300 px pinhole (64 × 48): ink where the
/// pattern is, under a blur of 0.05 cells.
fn drawn_tag() -> (Vec<u8>, usize, usize, TagBitmap) {
    drawn_tag_by(300.0, 64, 48)
}

/// [`drawn_tag`] through a pinhole of `f` px, `w` × `h`, centred.
fn drawn_tag_by(f: f64, w: usize, h: usize) -> (Vec<u8>, usize, usize, TagBitmap) {
    let bitmap = TagFamily::TAG36H11.bitmap(0).expect("tag 0");
    let pattern = Pattern::new(&bitmap).expect("8 cells");
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let luma: Vec<u8> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 - cx, (i / w) as f64 - cy);
            let (tx, ty) = (x * 100.0 / f / 5.0, y * 100.0 / f / 5.0);
            let paper = pattern.paper((tx + 1.0) * 4.0, (ty + 1.0) * 4.0, 0.05, 0.05).value;
            (20.0 + 200.0 * paper) as u8
        })
        .collect();
    (luma, w, h, bitmap)
}

#[test]
fn a_fit_given_no_room_to_settle_is_refused_as_not_converged() {
    // The drawn tag posed a little off: one linearisation cannot settle it.
    let (luma, w, h, bitmap) = drawn_tag();
    let camera = CameraIntrinsics::pinhole(300.0, 300.0, 31.5, 23.5);
    let frame = ImageView::new(&luma, w, h, w).expect("frame");
    let linear: [f64; 256] = std::array::from_fn(|v| v as f64);
    let tags = square(&bitmap);
    let body =
        Body { image: Image { frame, linear: &linear }, camera: &camera, tags: &tags, blur_px: 0.3, motion: None };
    let start = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.2, -0.1, 100.0));
    let one = Options { max_iterations: 1, ..Options::default() };
    assert_eq!(refine(&body, &start, &one), Err(RefineError::NotConverged { iterations: 1 }));
    let settled = refine(&body, &start, &Options::default()).expect("settles with room");
    assert!(settled.iterations < Options::default().max_iterations, "{} steps", settled.iterations);
    let off = (settled.camera_from_body.translation() - Vector3::new(0.0, 0.0, 100.0)).norm();
    assert!(off < 0.02, "{off:.4} mm from where the tag was drawn");
}

#[test]
fn the_fit_is_the_same_on_any_number_of_threads() {
    // Drawn 150 px wide, the tag has pixels enough for several pieces of work.
    let (f, w, h) = (1500.0, 200, 200);
    let (luma, w, h, bitmap) = drawn_tag_by(f, w, h);
    let camera = CameraIntrinsics::pinhole(f, f, (w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let frame = ImageView::new(&luma, w, h, w).expect("frame");
    let linear: [f64; 256] = std::array::from_fn(|v| v as f64);
    let tags = square(&bitmap);
    let body =
        Body { image: Image { frame, linear: &linear }, camera: &camera, tags: &tags, blur_px: 0.5, motion: None };
    let start = Pose::from_parts(
        UnitQuaternion::from_scaled_axis(Vector3::new(0.01, -0.02, 0.0)),
        Vector3::new(0.05, -0.03, 100.2),
    );
    let one = refine(&body, &start, &Options::default()).expect("settles");
    assert!(one.pixels > 4000, "only {} pixels: too few to share out", one.pixels);
    for threads in [2, 3] {
        let many = refine(&body, &start, &Options { threads, ..Options::default() }).expect("settles");
        assert_eq!(many, one, "{threads} threads");
    }
    let none = refine(&body, &start, &Options { threads: 0, ..Options::default() }).expect_err("refused");
    assert!(none.to_string().contains("threads"), "{none}");
}

#[test]
fn the_bound_is_that_of_the_blur_the_image_has_not_of_the_one_given() {
    let (frame_luma, w, h, bitmap) = drawn_tag();
    let frame = ImageView::new(&frame_luma, w, h, w).expect("frame");
    let linear: [f64; 256] = std::array::from_fn(|v| v as f64);
    let tags = square(&bitmap);
    let camera = CameraIntrinsics::pinhole(300.0, 300.0, 31.5, 23.5);
    let pose = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.0, 100.0));
    let depth_sd = |blur_px: f64| {
        let body =
            Body { image: Image { frame, linear: &linear }, camera: &camera, tags: &tags, blur_px, motion: None };
        bound(&body, &pose, &Options::default(), &|_| 1.0).expect("a bound")[(5, 5)].sqrt()
    };
    // Started from the right blur and from one four times too wide, the nuisance fit finds
    // the image's: a bound taken at the wide blur as given would be far looser.
    let (right, wide) = (depth_sd(0.2), depth_sd(0.8));
    assert!(right > 0.0 && (wide / right - 1.0).abs() < 0.05, "{right} vs {wide}");
}

#[test]
fn a_blur_that_is_not_one_is_refused_by_name() {
    for blur in [f64::NAN, -1.0, f64::INFINITY] {
        let e = refine_at(100.0, blur).expect_err("refused").to_string();
        assert!(e.contains("blur"), "{blur}: {e}");
    }
}

/// Tag 0 as [`drawn_tag`] draws it, moving along x at `speed` (mm/s) through a global shutter
/// open for `exposure_s`: each pixel the average of 400 instants, the tag where it is at the
/// exposure's middle at x = 0.
fn drawn_moving_tag(speed: f64, exposure_s: f64) -> Vec<u8> {
    let pattern = Pattern::new(&TagFamily::TAG36H11.bitmap(0).expect("tag 0")).expect("8 cells");
    let (w, h, instants) = (64, 48, 400);
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 - 31.5, (i / w) as f64 - 23.5);
            let paper = (0..instants)
                .map(|k| {
                    let t = ((k as f64 + 0.5) / instants as f64 - 0.5) * exposure_s;
                    let (tx, ty) = ((x * 100.0 / 300.0 - speed * t) / 5.0, y * 100.0 / 300.0 / 5.0);
                    pattern.paper((tx + 1.0) * 4.0, (ty + 1.0) * 4.0, 0.05, 0.05).value
                })
                .sum::<f64>()
                / instants as f64;
            (20.0 + 200.0 * paper).round() as u8
        })
        .collect()
}

#[test]
fn a_smeared_tag_is_refined_to_its_place_at_the_exposures_middle_with_its_motion() {
    // 250 mm/s over 8 ms: 2 mm, a smear of 6 px (a fifth of the tag) along x.
    let (speed, exposure_s) = (250.0, 0.008);
    let luma = drawn_moving_tag(speed, exposure_s);
    let frame = ImageView::new(&luma, 64, 48, 64).expect("frame");
    let linear: [f64; 256] = std::array::from_fn(|v| v as f64);
    let bitmap = TagFamily::TAG36H11.bitmap(0).expect("tag 0");
    let tags = square(&bitmap);
    let camera = CameraIntrinsics::pinhole(300.0, 300.0, 31.5, 23.5);
    let motion = Motion {
        velocity: Velocity { angular: Vector3::zeros(), linear: Vector3::new(speed, 0.0, 0.0) },
        shutter: RollingShutter::global(),
        exposure_s,
    };
    let start = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.2, -0.1, 100.0));
    // The detector's blur of a smeared edge is wide: 1.5 px, where the lens's is 0.2.
    let body =
        |motion| Body { image: Image { frame, linear: &linear }, camera: &camera, tags: &tags, blur_px: 1.5, motion };
    let moving = refine(&body(Some(motion)), &start, &Options::default()).expect("the moving fit settles");
    let still = refine(&body(None), &start, &Options::default()).expect("the still fit settles");
    let off = |r: &Refined| (r.camera_from_body.translation() - Vector3::new(0.0, 0.0, 100.0)).norm();
    assert!(moving.motion, "the still fit was kept over the motion");
    // The motion models the image: a still tag misfits by 15 % of the contrast here.
    assert!(moving.rms_contrast < 0.25 * still.rms_contrast, "{} against {}", moving.rms_contrast, still.rms_contrast);
    // Measured: 0.047 mm, nearly all in depth (0.05 %, the tag's width read 0.014 px short),
    // against 0.142 mm for the still fit. The exposure is cut in two parts of 3 px each (the
    // detector's 1.5 px blur sets them), each taken as a Gaussian sweep, where this drawing's
    // own blur is 0.2 px: the parts' box is not a Gaussian at that scale (docs/dense.md, the
    // sweep's box in closed form).
    assert!(off(&moving) < 0.06 && off(&moving) < 0.5 * off(&still), "{} mm, still {} mm", off(&moving), off(&still));
    let across = moving.camera_from_body.translation().xy().norm();
    assert!(across < 0.005, "{across} mm off across the view: the smear is centred on the frame's time");
}
