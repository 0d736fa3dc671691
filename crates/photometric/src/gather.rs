//! The pixels a tag covers: gathered once at the fit's starting pose, those near an edge of its
//! pattern (where the pose's information is) and a sparse grid of the rest (for its levels).

use crate::model::{Pattern, within_one_cell};
use crate::plane::{Outline, near_edge, plane, to_tag, widest_band};
use crate::{Image, Options, Tag};
use jawtrack_pose::{CameraIntrinsics, Pose};
use nalgebra::{Point2, Vector2, Vector3};

/// Away from the edges, every this many pixels each way are compared, for the tag's levels.
const FLAT_STRIDE: usize = 4;

/// One pixel of a tag: where it is, what it reads (linear light, 0–255) and the undistorted
/// normalised direction it looks along.
pub(crate) struct Sample {
    pub(crate) row: usize,
    pub(crate) normalised: Vector2<f64>,
    pub(crate) linear: f64,
}

/// A tag's plane and its pixels.
pub(crate) struct TagPixels {
    pub(crate) pattern: Pattern,
    /// The square's centre and half-axes in the body frame: the point at tag coordinates
    /// (tx, ty) ∈ [−1, 1]² is centre + tx·x + ty·y.
    pub(crate) centre: Vector3<f64>,
    pub(crate) x: Vector3<f64>,
    pub(crate) y: Vector3<f64>,
    pub(crate) samples: Vec<Sample>,
}

/// The pixels `tag` covers at `start` (its square and `quiet_zone_cells` around it), inside the
/// frame, not saturated, that tell: those within `band_px` of an edge of its pattern (the
/// pose's information is there), and every [`FLAT_STRIDE`]th pixel each way elsewhere (for the
/// tag's levels); edge pixels thinned to about `max_pixels_per_tag`, scattered. `None` when it
/// has none or faces away.
pub(crate) fn gather(
    image: &Image<'_>,
    camera: &CameraIntrinsics,
    start: &Pose,
    tag: &Tag<'_>,
    band_px: f64,
    o: &Options,
) -> Option<TagPixels> {
    let pattern = Pattern::new(tag.bitmap)?;
    let c = tag.corners.map(Vector3::from);
    let centre = (c[0] + c[1] + c[2] + c[3]) / 4.0;
    let (x, y) = ((c[1] - c[0]) / 2.0, (c[0] - c[3]) / 2.0);
    let reach = 1.0 + 2.0 * o.quiet_zone_cells / pattern.cells() as f64;
    let plane = plane(start, &centre, &x, &y)?;
    // The square with its quiet zone, in pixels: only the columns of each row it may cover
    // are looked at (a tilted tag covers a fraction of its box).
    let outline = Outline::new(camera, start, &centre, &(x * reach), &(y * reach))?;
    let (lo, hi) = outline.bounds();
    let (w, h) = (image.frame.width() as f64, image.frame.height() as f64);
    let (x0, y0) = (lo.x.ceil().max(0.0) as usize, lo.y.ceil().max(0.0) as usize);
    let (x1, y1) = (hi.x.floor().min(w - 1.0), hi.y.floor().min(h - 1.0));
    if x1 < x0 as f64 || y1 < y0 as f64 {
        return None;
    }
    let half = pattern.cells() as f64 / 2.0;
    let band = band_px / (camera.fx * camera.fy).sqrt();
    // Most pixels lie well inside a cell, where even the widest band any pixel of the tag gets
    // reaches no edge: they are ruled out before their own band is worked out.
    let (widest_u, widest_v) = widest_band(&plane, start, (&centre, &(x * reach), &(y * reach)), band, half)?;
    let mut edge = Vec::new();
    let mut flat = Vec::new();
    for row in y0..=y1 as usize {
        let (from, to) = outline.columns(row as f64);
        let (first, last) = (from.ceil().max(x0 as f64), to.floor().min(x1));
        if last < first {
            continue;
        }
        let values = image.frame.row(row);
        for (col, &v) in values.iter().enumerate().take(last as usize + 1).skip(first as usize) {
            if v == u8::MAX {
                continue; // clipped: glare, or paper brighter than the sensor holds
            }
            let Some(n) = camera.undistort(camera.pixel_to_distorted(&Point2::new(col as f64, row as f64))) else {
                continue;
            };
            let Some((tx, ty)) = to_tag(&plane.to_tag, &n) else { continue };
            if tx.abs() > reach || ty.abs() > reach {
                continue;
            }
            let sample = (col, Sample { row, normalised: n, linear: image.linear[usize::from(v)] });
            let clear = within_one_cell((tx + 1.0) * half, widest_u) && within_one_cell((ty + 1.0) * half, widest_v);
            let near = !clear && near_edge(&plane, &pattern, &n, band, half);
            if near {
                edge.push(sample);
            } else if col.is_multiple_of(FLAT_STRIDE) && row.is_multiple_of(FLAT_STRIDE) {
                flat.push(sample);
            }
        }
    }
    // One pixel in `stride`, scattered (a regular grid beats against the cells' own).
    let stride = (edge.len() as f64 / o.max_pixels_per_tag as f64).ceil().max(1.0) as u64;
    let mut samples: Vec<Sample> =
        edge.into_iter().filter(|(col, s)| scatter(*col, s.row).is_multiple_of(stride)).map(|(_, s)| s).collect();
    samples.extend(flat.into_iter().map(|(_, s)| s));
    samples.sort_by_key(|s| s.row);
    (!samples.is_empty()).then_some(TagPixels { pattern, centre, x, y, samples })
}

/// A hash of a pixel's place, to thin pixels without a pattern.
fn scatter(col: usize, row: usize) -> u64 {
    let mut h = (col as u64) << 32 | row as u64;
    h = (h ^ (h >> 33)).wrapping_mul(0xff51_afd7_ed55_8ccd);
    h = (h ^ (h >> 33)).wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}
