//! Occlusal views of an arch: an orthographic software rendering (a z-buffer rasteriser with
//! per-vertex colours and Lambert shading) of the arch seen along its smallest principal axis
//! from the side of the other arch, plus a small legend of the contact-frequency colours.

use crate::Mesh;
use crate::contacts::{GREY, ramp};
use image::{Rgb, RgbImage};
use jawtrack_pose::Pose;
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};

/// Background colour.
const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
/// The share of the light that does not depend on the surface's orientation.
const AMBIENT: f64 = 0.35;
/// Height (px) of the legend strip added under a view by [`with_legend`].
pub const LEGEND_PX: u32 = 36;

/// An orthographic camera: image axes in the mesh's frame and the mm → pixel mapping.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// The image's x axis (unit, mesh frame).
    pub right: Vector3<f64>,
    /// The image's y axis, pointing down the image (unit, mesh frame).
    pub down: Vector3<f64>,
    /// The viewing direction, from the eye into the scene (unit): depth grows along it.
    pub forward: Vector3<f64>,
    /// The coordinates along `right` and `down` (mm) of the image's top-left corner.
    pub origin: [f64; 2],
    /// Scale (pixels per mm).
    pub px_per_mm: f64,
    /// Image width (px).
    pub width: u32,
    /// Image height (px).
    pub height: u32,
}

impl View {
    /// A view along `forward` with `right` as the image's x axis (both unit and orthogonal),
    /// framing the whole mesh with its longer side `long_side_px` pixels (a small margin
    /// included). The image is not mirrored: (right, down, forward) is right-handed.
    pub fn fit(mesh: &Mesh, forward: Vector3<f64>, right: Vector3<f64>, long_side_px: u32) -> View {
        let down = forward.cross(&right);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for v in &mesh.vertices {
            let q = [v.coords.dot(&right), v.coords.dot(&down)];
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        if !(lo[0].is_finite() && lo[1].is_finite() && hi[0].is_finite() && hi[1].is_finite()) {
            (lo, hi) = ([0.0; 2], [1.0; 2]);
        }
        let long = f64::from(long_side_px.max(16));
        let margin = (long * 0.04).round();
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let px_per_mm = if extent > 0.0 { (long - 2.0 * margin) / extent } else { 1.0 };
        let size = |k: usize| (((hi[k] - lo[k]) * px_per_mm).round() + 2.0 * margin).max(1.0) as u32;
        View {
            right,
            down,
            forward,
            origin: [lo[0] - margin / px_per_mm, lo[1] - margin / px_per_mm],
            px_per_mm,
            width: size(0),
            height: size(1),
        }
    }

    /// The occlusal view of `mesh`: along its smallest principal axis (the normal of the
    /// occlusal plane), looking from the side where `toward` (the other arch's centroid) lies,
    /// with the largest principal axis (the arch's width) across the image. A mesh with no
    /// clearly flattest direction is looked at straight from `toward`.
    pub fn occlusal(mesh: &Mesh, toward: &Point3<f64>, long_side_px: u32) -> View {
        let n = mesh.vertices.len().max(1) as f64;
        let centroid = centroid(mesh);
        let cov = mesh.vertices.iter().fold(Matrix3::zeros(), |s, v| {
            let d = v.coords - centroid;
            s + d * d.transpose()
        }) / n;
        let eig = SymmetricEigen::new(cov);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let unit = |k: usize, fallback: Vector3<f64>| {
            let c: Vector3<f64> = eig.eigenvectors.column(k).into_owned();
            c.try_normalize(1e-12).unwrap_or(fallback)
        };
        let to_other = toward.coords - centroid;
        let mut forward = unit(order[0], Vector3::z());
        // Without a clearly flattest direction (a lone crown, a ball), look straight at the
        // mesh from the other arch.
        let (smallest, middle) = (eig.eigenvalues[order[0]], eig.eigenvalues[order[1]]);
        if smallest > 0.5 * middle
            && let Some(d) = to_other.try_normalize(1e-9)
        {
            forward = -d;
        }
        // The eye is on the other arch's side: looking from there, `forward` points away from it.
        if forward.dot(&to_other) > 0.0 {
            forward = -forward;
        }
        let right = unit(order[2], Vector3::x());
        // Orthogonalise against rounding (eigenvectors of a symmetric matrix are orthogonal).
        let right = (right - forward * forward.dot(&right)).try_normalize(1e-9).unwrap_or_else(|| {
            let any = if forward.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
            (any - forward * forward.dot(&any)).normalize()
        });
        View::fit(mesh, forward, right, long_side_px)
    }

    /// The occlusal views of both arches, `[upper, lower]`, each in its own scan's frame and
    /// seen from the other arch's side with the lower scan at `maxilla_scan_from_mandible_scan`.
    pub fn occlusal_pair(
        upper: &Mesh,
        lower: &Mesh,
        maxilla_scan_from_mandible_scan: &Pose,
        long_side_px: u32,
    ) -> [View; 2] {
        let lower_in_upper = maxilla_scan_from_mandible_scan.transform_point(&Point3::from(centroid(lower)));
        let upper_in_lower = maxilla_scan_from_mandible_scan.inverse().transform_point(&Point3::from(centroid(upper)));
        [View::occlusal(upper, &lower_in_upper, long_side_px), View::occlusal(lower, &upper_in_lower, long_side_px)]
    }

    /// Where a mesh point lands in the image (px; (0, 0) the top-left pixel's centre).
    pub fn pixel(&self, p: &Point3<f64>) -> [f64; 2] {
        let q = self.project(p);
        [q[0], q[1]]
    }

    /// A mesh point in pixels (x, y) and its depth along `forward` (mm).
    fn project(&self, p: &Point3<f64>) -> [f64; 3] {
        [
            (p.coords.dot(&self.right) - self.origin[0]) * self.px_per_mm,
            (p.coords.dot(&self.down) - self.origin[1]) * self.px_per_mm,
            p.coords.dot(&self.forward),
        ]
    }
}

/// The mean of a mesh's vertices.
fn centroid(mesh: &Mesh) -> Vector3<f64> {
    let n = mesh.vertices.len().max(1) as f64;
    mesh.vertices.iter().fold(Vector3::zeros(), |s, v| s + v.coords) / n
}

/// Renders `mesh` with per-vertex `colours` (missing ones grey) through `view`: orthographic,
/// z-buffered, every triangle drawn from both sides, colours shaded by Lambert's law with the
/// light at the eye and interpolated across triangles; white background.
pub fn render(mesh: &Mesh, colours: &[[u8; 3]], view: &View) -> RgbImage {
    let (w, h) = (view.width as usize, view.height as usize);
    let mut image = RgbImage::from_pixel(view.width, view.height, WHITE);
    let mut depth = vec![f64::INFINITY; w * h];
    let mut normals = vec![Vector3::zeros(); mesh.vertices.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let n = mesh.area_normal(t);
        tri.iter().for_each(|&i| normals[i as usize] += n);
    }
    // Shaded colour per vertex, as floats.
    let shaded: Vec<[f64; 3]> = normals
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let lambert = n.try_normalize(1e-300).map_or(1.0, |n| n.dot(&view.forward).abs());
            let shade = AMBIENT + (1.0 - AMBIENT) * lambert;
            colours.get(i).copied().unwrap_or(GREY).map(|c| f64::from(c) * shade)
        })
        .collect();
    let screen: Vec<[f64; 3]> = mesh.vertices.iter().map(|p| view.project(p)).collect();
    let edge = |a: [f64; 3], b: [f64; 3], x: f64, y: f64| (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
    for tri in &mesh.triangles {
        let [i0, i1, i2] = tri.map(|i| i as usize);
        let (p0, p1, p2) = (screen[i0], screen[i1], screen[i2]);
        let area = edge(p0, p1, p2[0], p2[1]);
        if !area.is_finite() || area.abs() < 1e-12 {
            continue;
        }
        let x_lo = p0[0].min(p1[0]).min(p2[0]).floor().max(0.0);
        let y_lo = p0[1].min(p1[1]).min(p2[1]).floor().max(0.0);
        let x_hi = p0[0].max(p1[0]).max(p2[0]).ceil().min(w as f64 - 1.0);
        let y_hi = p0[1].max(p1[1]).max(p2[1]).ceil().min(h as f64 - 1.0);
        if x_lo > x_hi || y_lo > y_hi {
            continue;
        }
        for y in y_lo as usize..=y_hi as usize {
            let cy = y as f64 + 0.5;
            for x in x_lo as usize..=x_hi as usize {
                let cx = x as f64 + 0.5;
                let b0 = edge(p1, p2, cx, cy) / area;
                let b1 = edge(p2, p0, cx, cy) / area;
                let b2 = 1.0 - b0 - b1;
                if b0 < 0.0 || b1 < 0.0 || b2 < 0.0 {
                    continue;
                }
                let z = b0 * p0[2] + b1 * p1[2] + b2 * p2[2];
                let k = y * w + x;
                if z < depth[k] {
                    depth[k] = z;
                    let c = |j: usize| {
                        (b0 * shaded[i0][j] + b1 * shaded[i1][j] + b2 * shaded[i2][j]).round().clamp(0.0, 255.0) as u8
                    };
                    image.put_pixel(x as u32, y as u32, Rgb([c(0), c(1), c(2)]));
                }
            }
        }
    }
    image
}

/// `image` with a [`LEGEND_PX`] strip added below: a grey swatch (never in contact), then the
/// blue → red ramp of the share of frames in contact, labelled 0 % and 100 %.
pub fn with_legend(image: &RgbImage) -> RgbImage {
    let (w, h) = image.dimensions();
    let mut out = RgbImage::from_pixel(w, h + LEGEND_PX, WHITE);
    for (x, y, p) in image.enumerate_pixels() {
        out.put_pixel(x, y, *p);
    }
    let mut set = |x: u32, y: u32, c: [u8; 3]| {
        if x < w {
            out.put_pixel(x, h + y, Rgb(c));
        }
    };
    let (bar_y, bar_h) = (6, 12);
    for y in bar_y..bar_y + bar_h {
        for x in 10..34 {
            set(x, y, GREY);
        }
        for x in 0..200u32 {
            set(44 + x, y, ramp(f64::from(x) / 199.0));
        }
    }
    let text_y = bar_y + bar_h + 4;
    for (label, x) in [("0%", 44), ("50%", 44 + 100 - 11), ("100%", 44 + 200 - 30)] {
        for (k, ch) in label.chars().enumerate() {
            let Some(glyph) = glyph(ch) else { continue };
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..3u32 {
                    if bits >> (2 - col) & 1 == 1 {
                        // Each font pixel is 2 × 2 image pixels; glyphs 8 px apart.
                        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                            set(x + 8 * k as u32 + 2 * col + dx, text_y + 2 * row as u32 + dy, [60, 60, 60]);
                        }
                    }
                }
            }
        }
    }
    out
}

/// A 3 × 5 bitmap glyph (rows top to bottom, 3 bits each, leftmost the highest).
fn glyph(ch: char) -> Option<[u8; 5]> {
    Some(match ch {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '%' => [0b101, 0b001, 0b010, 0b100, 0b101],
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Looking down −z at the xy plane, 1 px per mm, x right and y down, a 20 × 20 image.
    fn plan_view() -> View {
        View {
            right: Vector3::x(),
            down: Vector3::y(),
            forward: Vector3::z(),
            origin: [0.0, 0.0],
            px_per_mm: 1.0,
            width: 20,
            height: 20,
        }
    }

    fn triangle(corners: [[f64; 3]; 3]) -> Mesh {
        Mesh { vertices: corners.iter().map(|c| Point3::from(*c)).collect(), triangles: vec![[0, 1, 2]] }
    }

    #[test]
    fn a_triangle_covers_the_pixels_whose_centres_it_contains() {
        let mesh = triangle([[2.0, 2.0, 0.0], [12.0, 2.0, 0.0], [2.0, 12.0, 0.0]]);
        let image = render(&mesh, &[[200, 0, 0]; 3], &plan_view());
        let mut covered = 0;
        for (x, y, p) in image.enumerate_pixels() {
            let (cx, cy) = (f64::from(x) + 0.5 - 2.0, f64::from(y) + 0.5 - 2.0);
            let inside = cx >= 0.0 && cy >= 0.0 && cx + cy <= 10.0;
            // Facing the eye: full light, the exact colour.
            assert_eq!(*p, if inside { Rgb([200, 0, 0]) } else { WHITE }, "pixel {x},{y}");
            covered += usize::from(inside);
        }
        // 10 + 9 + … + 1 pixel centres (those on the hypotenuse included) for 50 px² of area.
        assert_eq!(covered, 55);
    }

    #[test]
    fn a_nearer_triangle_hides_a_farther_one_whatever_the_order() {
        let far = [[0.0, 0.0, 5.0], [20.0, 0.0, 5.0], [0.0, 20.0, 5.0]];
        let near = [[0.0, 0.0, 1.0], [20.0, 0.0, 1.0], [0.0, 20.0, 1.0]];
        for order in [[far, near], [near, far]] {
            let mut mesh = triangle(order[0]);
            mesh.vertices.extend(order[1].iter().map(|c| Point3::from(*c)));
            mesh.triangles.push([3, 4, 5]);
            let mut colours = vec![[0, 0, 255]; 6];
            let near_first = order[0][0][2] < 5.0;
            let near_range = if near_first { 0..3 } else { 3..6 };
            colours[near_range].iter_mut().for_each(|c| *c = [0, 255, 0]);
            let image = render(&mesh, &colours, &plan_view());
            assert_eq!(*image.get_pixel(3, 3), Rgb([0, 255, 0]));
        }
    }

    #[test]
    fn a_tilted_surface_is_darker_but_never_black() {
        // 60° from the view: Lambert gives half the diffuse light.
        let s = 3f64.sqrt();
        let mesh = triangle([[0.0, 0.0, 0.0], [20.0, 0.0, 20.0 * s], [0.0, 20.0, 0.0]]);
        let image = render(&mesh, &[[200, 200, 200]; 3], &plan_view());
        let expected = (200.0 * (AMBIENT + (1.0 - AMBIENT) * 0.5)).round() as u8;
        assert_eq!(*image.get_pixel(2, 2), Rgb([expected; 3]));
    }

    #[test]
    fn the_occlusal_view_looks_at_a_flat_arch_from_the_other_arch() {
        let patch = crate::scenes::patch(10.0, 4, 0.0, true);
        let below = View::occlusal(&patch, &Point3::new(0.0, 0.0, -3.0), 800);
        assert!((below.forward - Vector3::z()).norm() < 1e-9, "{:?}", below.forward);
        let above = View::occlusal(&patch, &Point3::new(0.0, 0.0, 3.0), 800);
        assert!((above.forward + Vector3::z()).norm() < 1e-9, "{:?}", above.forward);
        assert_eq!(below.width.max(below.height), 800);
        // Right-handed image axes: the view is not mirrored.
        assert!((below.right.cross(&below.down) - below.forward).norm() < 1e-9);
    }

    #[test]
    fn a_round_mesh_is_seen_from_the_other_arch() {
        let ball = crate::scenes::sphere(Point3::new(1.0, 0.0, 0.0), 3.0, 24);
        let view = View::occlusal(&ball, &Point3::new(1.0, 0.0, 10.0), 400);
        assert!((view.forward + Vector3::z()).norm() < 1e-9, "{:?}", view.forward);
    }

    #[test]
    fn each_arch_of_a_pair_is_seen_from_the_other() {
        let (patch, ball) =
            (crate::scenes::patch(10.0, 4, 0.0, true), crate::scenes::sphere(Point3::origin(), 3.0, 24));
        // The ball's scan frame 5 mm below the patch's: the patch is seen from below, the
        // ball from above.
        let pose = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 0.0, -5.0));
        let [upper, lower] = View::occlusal_pair(&patch, &ball, &pose, 400);
        assert!((upper.forward - Vector3::z()).norm() < 1e-9, "{:?}", upper.forward);
        assert!((lower.forward + Vector3::z()).norm() < 1e-9, "{:?}", lower.forward);
        assert_eq!(lower.width.max(lower.height), 400);
    }

    #[test]
    fn the_legend_adds_a_strip_with_the_ramp() {
        let image = RgbImage::from_pixel(300, 10, WHITE);
        let out = with_legend(&image);
        assert_eq!(out.dimensions(), (300, 10 + LEGEND_PX));
        assert_eq!(*out.get_pixel(44 + 199, 10 + 8), Rgb(ramp(1.0)));
        assert_eq!(*out.get_pixel(20, 10 + 8), Rgb(GREY));
    }
}
