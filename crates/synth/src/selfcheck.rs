//! The renderer checks itself: it renders one large tag facing the camera and measures, by a
//! sub-pixel edge fit, where the black square's edges landed against where the projection
//! says they are.
//!
//! The fit uses the box filter the renderer integrates with: along a pixel row crossing an
//! edge from pure black to pure white, the sum of the normalised intensities (I − B)/(W − B)
//! equals the length of the row's white part, so the edge position follows exactly.

use crate::render::{Camera, INK_ALBEDO, PAPER_ALBEDO, PlacedBody, RenderScene, render_linear};
use jawtrack_marker::Marker;
use jawtrack_pose::{CameraIntrinsics, Pose};
use nalgebra::{Matrix3, Point2, Point3, Rotation3, UnitQuaternion, Vector3};

/// The result of a self-check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeCheck {
    /// Side of the rendered tag (px).
    pub tag_side_px: f64,
    /// Rows or columns fitted.
    pub samples: usize,
    /// Largest distance between a fitted edge point and the projected edge (px).
    pub max_error_px: f64,
    /// RMS of the same (px).
    pub rms_error_px: f64,
}

/// Renders tag 0 facing the camera, `side_px` across, turned `roll_deg` about the optical axis
/// and offset by a fraction of a pixel, and measures its four edges.
pub fn edge_self_check(side_px: f64, roll_deg: f64) -> EdgeCheck {
    let marker = Marker::default();
    let body = marker.body(jawtrack_marker::BodyKind::Maxilla).expect("the default marker has a maxilla");
    let tag = &body.tags[0];
    let solid = marker.geometry();
    let face = &solid.faces()[0];
    let (w, h) = (800u32, 800u32);
    let k = CameraIntrinsics::pinhole(1500.0, 1500.0, 399.5, 399.5);
    let z = k.fx * tag.size / side_px;
    // Camera axes in the body frame: x along the tag's x, y along its y, z into the face.
    let r = Matrix3::from_rows(&[face.x_axis.transpose(), face.y_axis.transpose(), (-face.normal).transpose()]);
    let roll = Rotation3::from_axis_angle(&Vector3::z_axis(), roll_deg.to_radians());
    let rot = UnitQuaternion::from_rotation_matrix(&(roll * Rotation3::from_matrix_unchecked(r)));
    // Put the tag centre on a sub-pixel position off the principal point.
    let target = Vector3::new(0.37 * z / k.fx, -0.21 * z / k.fx, z);
    let t = target - rot * tag.center;
    let pose = Pose::from_parts(rot, t);
    let cam = Camera { intrinsics: k, width: w, height: h };
    let scene = RenderScene {
        camera: cam,
        bodies: vec![PlacedBody {
            body,
            solid: marker.solid,
            edge: marker.edge,
            family: marker.family,
            camera_from_body: pose,
        }],
        planes: vec![],
        light_dir: Vector3::new(0.0, 0.0, -1.0),
        ambient: 0.35,
    };
    let img = render_linear(&scene);
    let at = |x: i64, y: i64| f64::from(img.radiance[(y as usize) * w as usize + x as usize]);
    // Fronto-parallel, lit head-on: every face point has the same shading.
    let shade = (pose.transform_vector(&face.normal).dot(&Vector3::new(0.0, 0.0, -1.0))).max(0.0) * 0.65 + 0.35;
    let black = f64::from(INK_ALBEDO) * shade;
    let white = f64::from(PAPER_ALBEDO) * shade;

    let corners: Vec<Point2<f64>> =
        tag.corners.iter().map(|c| k.project(&pose.transform_point(&Point3::from(*c))).expect("in front")).collect();
    let centre = k.project(&pose.transform_point(&Point3::from(tag.center))).expect("in front");
    let cell = side_px / 8.0;
    let half_window = (0.45 * cell).floor() as i64;
    let mut errors = Vec::new();
    for i in 0..4 {
        let (a, b) = (corners[i], corners[(i + 1) % 4]);
        let d = b - a;
        let vertical = d.y.abs() > d.x.abs();
        // Central 70 % of the edge, away from the corners.
        let steps = if vertical { d.y.abs() } else { d.x.abs() };
        let n = steps.floor() as i64;
        for s in 0..=n {
            let frac = s as f64 / steps;
            if !(0.15..=0.85).contains(&frac) {
                continue;
            }
            let p = a + d * frac;
            // Work in (along, across) coordinates: across the edge runs x for a near-vertical
            // edge (fit along a row), y otherwise (fit along a column).
            let swap = |v: Point2<f64>| if vertical { (v.y, v.x) } else { (v.x, v.y) };
            let ((pa, _), (aa, ac), (da, dc), (_, cc)) = (swap(p), swap(a), swap(Point2::from(d)), swap(centre));
            let line = pa.round() as i64;
            let edge_true = ac + dc * (line as f64 - aa) / da;
            let mid = edge_true.round() as i64;
            let (lo, hi) = (mid - half_window, mid + half_window);
            let value = |k: i64| if vertical { at(k, line) } else { at(line, k) };
            let sum: f64 = (lo..=hi).map(|k| (value(k) - black) / (white - black)).sum();
            let e = if cc < edge_true { hi as f64 + 0.5 - sum } else { lo as f64 - 0.5 + sum };
            errors.push(e - edge_true);
        }
    }
    let max = errors.iter().map(|e| e.abs()).fold(0.0, f64::max);
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len().max(1) as f64).sqrt();
    EdgeCheck { tag_side_px: side_px, samples: errors.len(), max_error_px: max, rms_error_px: rms }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_fronto_parallel_tag_has_its_edges_where_the_projection_says() {
        for roll in [0.0, 7.0, 30.0] {
            let c = edge_self_check(400.0, roll);
            assert!(c.samples > 800, "{c:?}");
            assert!(c.max_error_px < 0.05, "roll {roll}°: {c:?}");
        }
    }
}
