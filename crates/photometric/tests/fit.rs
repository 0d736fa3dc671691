//! The refinement's refusals and its bound, on tags drawn from the model itself.

use jawtrack_apriltag::ImageView;
use jawtrack_photometric::{Body, Image, Options, Pattern, RefineError, Refined, Tag, bound, refine};
use jawtrack_pose::{CameraIntrinsics, Pose};
use jawtrack_tag_family::TagFamily;
use nalgebra::{UnitQuaternion, Vector3};

fn refine_at(z: f64, blur_px: f64) -> Result<Refined, RefineError> {
    let luma = vec![128u8; 64 * 48];
    let frame = ImageView::new(&luma, 64, 48, 64).expect("frame");
    let linear: [f64; 256] = std::array::from_fn(|v| v as f64);
    let bitmap = TagFamily::TAG36H11.bitmap(0).expect("tag 0");
    let tags =
        [Tag { corners: [[-5.0, 5.0, 0.0], [5.0, 5.0, 0.0], [5.0, -5.0, 0.0], [-5.0, -5.0, 0.0]], bitmap: &bitmap }];
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
fn drawn_tag() -> (Vec<u8>, usize, usize, jawtrack_tag_family::TagBitmap) {
    let bitmap = TagFamily::TAG36H11.bitmap(0).expect("tag 0");
    let pattern = Pattern::new(&bitmap).expect("8 cells");
    let (w, h) = (64, 48);
    let luma: Vec<u8> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 - 31.5, (i / w) as f64 - 23.5);
            let (tx, ty) = (x * 100.0 / 300.0 / 5.0, y * 100.0 / 300.0 / 5.0);
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
    let tags =
        [Tag { corners: [[-5.0, 5.0, 0.0], [5.0, 5.0, 0.0], [5.0, -5.0, 0.0], [-5.0, -5.0, 0.0]], bitmap: &bitmap }];
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
fn the_bound_is_that_of_the_blur_the_image_has_not_of_the_one_given() {
    let (frame_luma, w, h, bitmap) = drawn_tag();
    let frame = ImageView::new(&frame_luma, w, h, w).expect("frame");
    let linear: [f64; 256] = std::array::from_fn(|v| v as f64);
    let tags =
        [Tag { corners: [[-5.0, 5.0, 0.0], [5.0, 5.0, 0.0], [5.0, -5.0, 0.0], [-5.0, -5.0, 0.0]], bitmap: &bitmap }];
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
