//! Image formation after the ideal render: defocus, glare, illumination and sensor noise, in
//! that physical order and in linear light; then the phone's own processing ([`develop`]): a
//! local tone map, the tone curve, and sharpening of the encoded values.

use crate::realism::{Realism, Sharpen};
use crate::render::LinearImage;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_tone::ToneCurve;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A specular glare patch: added radiance with a Gaussian profile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Glare {
    /// Centre (px).
    pub center: [f64; 2],
    /// Standard deviation (px).
    pub sigma_px: f64,
    /// Added radiance at the centre (white paper ≈ 0.85).
    pub peak: f64,
}

/// The blur circle of a thin lens (its diameter, px): a point at depth d with the lens focused
/// at d_f spreads into a disc of diameter c = fx·A·|d − d_f| / (d·(d_f − f)) px, A = f/N the
/// entrance pupil and fx the focal length in pixels of the lens focused at infinity.
pub fn blur_circle_px(k: &CameraIntrinsics, f_number: f64, focal_mm: f64, focus_mm: f64, depth_mm: f64) -> f64 {
    if f_number <= 0.0 || !depth_mm.is_finite() || depth_mm <= 0.0 {
        return 0.0;
    }
    let aperture = focal_mm / f_number;
    k.fx * aperture * (depth_mm - focus_mm).abs() / (depth_mm * (focus_mm - focal_mm))
}

/// Depth-dependent Gaussian blur of a thin lens: the Gaussian with the variance of the blur
/// circle ([`blur_circle_px`]), σ = c/4.
pub fn defocus_sigma_px(k: &CameraIntrinsics, f_number: f64, focal_mm: f64, focus_mm: f64, depth_mm: f64) -> f64 {
    blur_circle_px(k, f_number, focal_mm, focus_mm, depth_mm) / 4.0
}

/// Blur levels (px): geometric from 0.3 px; a pixel blends the two levels around its σ.
fn levels(max_sigma: f64) -> Vec<f64> {
    let mut v = vec![0.0];
    let mut s = 0.3;
    while s < max_sigma * 1.25 {
        v.push(s);
        s *= 1.3;
    }
    v
}

fn gaussian_kernel(sigma: f64) -> Vec<f32> {
    let r = (3.0 * sigma).ceil() as usize;
    let k: Vec<f64> = (0..=2 * r).map(|i| (-((i as f64 - r as f64).powi(2)) / (2.0 * sigma * sigma)).exp()).collect();
    let s: f64 = k.iter().sum();
    k.iter().map(|v| (v / s) as f32).collect()
}

/// Separable Gaussian blur of the window [x0, x1) × [y0, y1) of `img` (edges clamped).
fn blur_window(img: &[f32], w: usize, h: usize, win: [usize; 4], sigma: f64) -> Vec<f32> {
    let [x0, y0, x1, y1] = win;
    let k = gaussian_kernel(sigma);
    let r = (k.len() / 2) as isize;
    let ww = x1 - x0;
    // Rows first over the window grown by r vertically, so the column pass has its input.
    let gy0 = y0.saturating_sub(r as usize);
    let gy1 = (y1 + r as usize).min(h);
    let tmp: Vec<f32> = (gy0..gy1)
        .into_par_iter()
        .flat_map_iter(|y| {
            let row = &img[y * w..(y + 1) * w];
            let k = &k;
            (x0..x1).map(move |x| {
                let mut acc = 0.0f32;
                for (i, kv) in k.iter().enumerate() {
                    let xx = (x as isize + i as isize - r).clamp(0, w as isize - 1) as usize;
                    acc += kv * row[xx];
                }
                acc
            })
        })
        .collect();
    (y0..y1)
        .into_par_iter()
        .flat_map_iter(|y| {
            let tmp = &tmp;
            let k = &k;
            (0..ww).map(move |x| {
                let mut acc = 0.0f32;
                for (i, kv) in k.iter().enumerate() {
                    let yy = (y as isize + i as isize - r).clamp(gy0 as isize, gy1 as isize - 1) as usize;
                    acc += kv * tmp[(yy - gy0) * ww + x];
                }
                acc
            })
        })
        .collect()
}

/// Blurs each pixel by the σ its own depth calls for (a gather approximation of defocus: exact
/// for surfaces at one depth, approximate at depth discontinuities).
pub fn defocus(img: &mut LinearImage, sigma_of_depth: impl Fn(f64) -> f64 + Sync) {
    let sig: Vec<f64> = img.depth.par_iter().map(|&d| sigma_of_depth(f64::from(d)).min(12.0)).collect();
    defocus_sigmas(img, &sig);
}

/// Blurs each pixel by its own σ (px), by blending Gaussian blurs at geometric levels.
fn defocus_sigmas(img: &mut LinearImage, sig: &[f64]) {
    let (w, h) = (img.width as usize, img.height as usize);
    let max_sigma = sig.iter().copied().fold(0.0, f64::max);
    if max_sigma < 0.15 {
        return;
    }
    let lv = levels(max_sigma);
    let mut out = img.radiance.clone();
    // For each level pair, the pixels whose σ falls between them.
    for li in 0..lv.len() - 1 {
        let (lo, hi) = (lv[li], lv[li + 1]);
        let mut bb = [usize::MAX, usize::MAX, 0, 0];
        for y in 0..h {
            for x in 0..w {
                let s = sig[y * w + x];
                if s >= lo && s < hi && s >= 0.15 {
                    bb = [bb[0].min(x), bb[1].min(y), bb[2].max(x + 1), bb[3].max(y + 1)];
                }
            }
        }
        if bb[0] == usize::MAX {
            continue;
        }
        let a = if lo > 0.0 { Some(blur_window(&img.radiance, w, h, bb, lo)) } else { None };
        let b = blur_window(&img.radiance, w, h, bb, hi);
        let ww = bb[2] - bb[0];
        for y in bb[1]..bb[3] {
            for x in bb[0]..bb[2] {
                let s = sig[y * w + x];
                if !(s >= lo && s < hi && s >= 0.15) {
                    continue;
                }
                let i = (y - bb[1]) * ww + (x - bb[0]);
                let va = a.as_ref().map_or(img.radiance[y * w + x], |a| a[i]);
                let t = ((s - lo) / (hi - lo)) as f32;
                out[y * w + x] = va * (1.0 - t) + b[i] * t;
            }
        }
    }
    img.radiance = out;
}

/// Blurs each pixel by the disc its own depth calls for (radius px; a gather approximation of
/// defocus, like [`defocus`]): each row of the disc, as wide as the disc is at that row's
/// centre line, summed from row prefix sums of the box-filtered pixels (so a fraction of a pixel
/// counts by its fraction), edges clamped. Radii under a pixel, which a disc of whole rows
/// cannot draw, get the Gaussian of the same variance (σ = radius/2).
pub fn defocus_disc(img: &mut LinearImage, radius_of_depth: impl Fn(f64) -> f64 + Sync) {
    let (w, h) = (img.width as usize, img.height as usize);
    let radius: Vec<f64> = img.depth.par_iter().map(|&d| radius_of_depth(f64::from(d)).min(24.0)).collect();
    let largest = radius.iter().copied().fold(0.0, f64::max);
    if largest < 0.3 {
        return;
    }
    // Below a pixel: the Gaussian.
    let mut small =
        LinearImage { width: img.width, height: img.height, radiance: img.radiance.clone(), depth: img.depth.clone() };
    let sigma: Vec<f64> = radius.iter().map(|&r| if r < 1.0 { r / 2.0 } else { 0.0 }).collect();
    defocus_sigmas(&mut small, &sigma);
    let mut out = small.radiance;
    if largest < 1.0 {
        img.radiance = out;
        return;
    }
    // Prefix sums of every row, padded either side by the largest radius (edges clamped):
    // `prefix[y][i]` sums the padded row's first i pixels.
    let pad = largest.ceil() as usize + 1;
    let stride = w + 2 * pad + 1;
    let radiance = &img.radiance;
    let prefix: Vec<f64> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            let row = &radiance[y * w..(y + 1) * w];
            let mut acc = 0.0;
            std::iter::once(0.0).chain((0..w + 2 * pad).map(move |i| {
                let x = (i as isize - pad as isize).clamp(0, w as isize - 1) as usize;
                acc += f64::from(row[x]);
                acc
            }))
        })
        .collect();
    // ∫ of row y (box pixels) up to image coordinate `at`: pixel i covers [i − 0.5, i + 0.5].
    let integral = |y: usize, at: f64| {
        let p = &prefix[y * stride..(y + 1) * stride];
        let u = at + 0.5 + pad as f64;
        let i = (u.floor().max(0.0) as usize).min(stride - 2);
        let f = u - i as f64;
        p[i] + f * (p[i + 1] - p[i])
    };
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, v) in row.iter_mut().enumerate() {
            let r = radius[y * w + x];
            if r < 1.0 {
                continue;
            }
            let reach = r.ceil() as isize;
            let (mut acc, mut total) = (0.0, 0.0);
            for dy in -reach..=reach {
                let half = (r * r - (dy * dy) as f64).max(0.0).sqrt();
                if half <= 0.0 {
                    continue;
                }
                let yy = (y as isize + dy).clamp(0, h as isize - 1) as usize;
                acc += integral(yy, x as f64 + half) - integral(yy, x as f64 - half);
                total += 2.0 * half;
            }
            *v = (acc / total) as f32;
        }
    });
    img.radiance = out;
}

/// A Gaussian blur of σ (px) over the whole image (the lens's own blur, the same everywhere).
pub fn gaussian_blur(img: &mut LinearImage, sigma: f64) {
    if sigma < 0.1 {
        return;
    }
    let (w, h) = (img.width as usize, img.height as usize);
    img.radiance = blur_window(&img.radiance, w, h, [0, 0, w, h], sigma);
}

/// Adds glare patches.
pub fn add_glare(img: &mut LinearImage, glare: &[Glare]) {
    let w = img.width as usize;
    for g in glare {
        let r = (4.0 * g.sigma_px).ceil() as isize;
        let (cx, cy) = (g.center[0].round() as isize, g.center[1].round() as isize);
        for y in (cy - r).max(0)..(cy + r + 1).min(img.height as isize) {
            for x in (cx - r).max(0)..(cx + r + 1).min(w as isize) {
                let d2 = (x as f64 - g.center[0]).powi(2) + (y as f64 - g.center[1]).powi(2);
                img.radiance[y as usize * w + x as usize] +=
                    (g.peak * (-d2 / (2.0 * g.sigma_px * g.sigma_px)).exp()) as f32;
            }
        }
    }
}

/// Multiplies by vignetting (1 − v·r⁴ with r the distance from the centre over the half
/// diagonal) and a linear lighting gradient of the given strength and direction (rad).
pub fn illumination(img: &mut LinearImage, vignetting: f64, gradient: f64, gradient_dir: f64) {
    let (w, h) = (img.width as usize, img.height as usize);
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let half_diag = (cx * cx + cy * cy).sqrt().max(1.0);
    let (gx, gy) = (gradient_dir.cos(), gradient_dir.sin());
    img.radiance.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, v) in row.iter_mut().enumerate() {
            let dx = (x as f64 - cx) / half_diag;
            let dy = (y as f64 - cy) / half_diag;
            let r2 = dx * dx + dy * dy;
            let f = (1.0 - vignetting * r2 * r2) * (1.0 + gradient * (gx * dx + gy * dy));
            *v *= f.max(0.0) as f32;
        }
    });
}

/// Poisson–Gaussian sensor noise (shot noise as a Gaussian of equal variance, plus read noise),
/// with values clipped at saturation. `full_well` electrons make a radiance of 1.0.
pub fn sensor_noise(img: &mut LinearImage, full_well: f64, read_noise: f64, rng: &mut impl Rng) {
    if full_well <= 0.0 {
        return;
    }
    for v in img.radiance.iter_mut() {
        let e = f64::from(v.clamp(0.0, 1.0)) * full_well;
        let n: f64 = StandardNormal.sample(rng);
        *v = ((e + n * (e + read_noise * read_noise).sqrt()) / full_well) as f32;
    }
}

/// The sRGB transfer curve (linear → encoded, both in 0..1): [`ToneCurve::Srgb`], the one
/// definition, under the name tests of other crates draw their frames with.
pub fn srgb_encode(v: f64) -> f64 {
    ToneCurve::Srgb.encode(v)
}

/// Smallest local mean the local tone map divides by (white paper ≈ 0.85): black regions, and
/// noise below zero, are not lifted without bound.
const LOCAL_MEAN_FLOOR: f64 = 1e-3;

/// A Gaussian blur of a large σ (px), fast at any size: box-averaged down by a factor f that
/// leaves σ 4–8 cells, blurred there and interpolated back. The boxes add f²/12 px² of
/// variance, under 1 % of σ², and the result is smooth by construction.
fn wide_blur(img: &[f32], w: usize, h: usize, sigma: f64) -> Vec<f32> {
    let f = ((sigma / 4.0).floor() as usize).max(1);
    if f == 1 {
        return blur_window(img, w, h, [0, 0, w, h], sigma);
    }
    let (sw, sh) = (w.div_ceil(f), h.div_ceil(f));
    let small: Vec<f32> = (0..sh)
        .into_par_iter()
        .flat_map_iter(|sy| {
            let (y0, y1) = (sy * f, ((sy + 1) * f).min(h));
            (0..sw).map(move |sx| {
                let (x0, x1) = (sx * f, ((sx + 1) * f).min(w));
                let sum: f64 = (y0..y1).flat_map(|y| &img[y * w + x0..y * w + x1]).map(|&v| f64::from(v)).sum();
                (sum / ((x1 - x0) * (y1 - y0)) as f64) as f32
            })
        })
        .collect();
    let blurred = blur_window(&small, sw, sh, [0, 0, sw, sh], sigma / f as f64);
    // A cell's centre is at (s + 0.5)·f − 0.5 px: each pixel's two cells either side, and how
    // far it is from the first, along one axis of `n` cells.
    let cells = |p: usize, n: usize| {
        let u = ((p as f64 + 0.5) / f as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let i = u.floor() as usize;
        (i, (i + 1).min(n - 1), (u - i as f64) as f32)
    };
    let columns: Vec<_> = (0..w).map(|x| cells(x, sw)).collect();
    (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            let (r0, r1, ty) = cells(y, sh);
            let (above, below) = (&blurred[r0 * sw..(r0 + 1) * sw], &blurred[r1 * sw..(r1 + 1) * sw]);
            columns.iter().map(move |&(c0, c1, tx)| {
                let top = above[c0] + tx * (above[c1] - above[c0]);
                let bottom = below[c0] + tx * (below[c1] - below[c0]);
                top + ty * (bottom - top)
            })
        })
        .collect()
}

/// A local tone map in linear light, as phones' "smart HDR" video applies before its curve:
/// L' = L·(m/B)^strength, B the radiance blurred by a Gaussian of σ = 1/16 of the image's
/// diagonal (floored at 0.001, so black is not lifted without bound) and m the mean of B. Dark
/// regions are lifted and bright ones lowered, smoothly over a scale far larger than a tag, so
/// a tag's edges keep their shape while the frame's effective curve varies across it.
/// Strength 0 changes nothing.
pub fn local_tone_map(img: &mut LinearImage, strength: f64) {
    if strength <= 0.0 || img.radiance.is_empty() {
        return;
    }
    let (w, h) = (img.width as usize, img.height as usize);
    let local = wide_blur(&img.radiance, w, h, (w as f64).hypot(h as f64) / 16.0);
    let floored = |b: f32| f64::from(b).max(LOCAL_MEAN_FLOOR);
    let mean = local.par_iter().map(|&b| floored(b)).sum::<f64>() / local.len() as f64;
    img.radiance.par_iter_mut().zip(local.par_iter()).for_each(|(v, &b)| {
        *v *= (mean / floored(b)).powf(strength) as f32;
    });
}

/// Encodes linear light to 8 bits: through `curve` (`None`: linear light), then sharpened
/// ([`Sharpen`], on the encoded values as a phone does, so its halos are in the curve's
/// units), rounded and clipped.
pub fn encode_u8(img: &LinearImage, curve: Option<ToneCurve>, sharpen: Option<Sharpen>) -> Vec<u8> {
    let encode = |v: f32| {
        let v = f64::from(v).clamp(0.0, 1.0);
        curve.map_or(v, |c| c.encode(v))
    };
    let to_u8 = |e: f64| (e.clamp(0.0, 1.0) * 255.0).round() as u8;
    let Some(Sharpen { amount, radius_px }) = sharpen else {
        return img.radiance.par_iter().map(|&v| to_u8(encode(v))).collect();
    };
    let (w, h) = (img.width as usize, img.height as usize);
    let encoded: Vec<f32> = img.radiance.par_iter().map(|&v| encode(v) as f32).collect();
    let blurred = blur_window(&encoded, w, h, [0, 0, w, h], radius_px);
    encoded.par_iter().zip(blurred.par_iter()).map(|(&e, &b)| to_u8(f64::from(e) + amount * f64::from(e - b))).collect()
}

/// The phone's processing of a sensor frame, in its order: the local tone map
/// ([`Realism::local_tone_map`]) in linear light, the tone curve ([`Realism::encoding`]), then
/// sharpening ([`Realism::sharpen`]) and 8 bits.
pub fn develop(img: &mut LinearImage, realism: &Realism) -> Vec<u8> {
    local_tone_map(img, realism.local_tone_map);
    encode_u8(img, realism.encoding(), realism.sharpen)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defocus_sigma_is_zero_in_focus_and_grows_away() {
        let k = CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5);
        assert_eq!(defocus_sigma_px(&k, 1.8, 5.7, 100.0, 100.0), 0.0);
        let near = defocus_sigma_px(&k, 1.8, 5.7, 100.0, 110.0);
        let far = defocus_sigma_px(&k, 1.8, 5.7, 100.0, 130.0);
        assert!(near > 0.1 && far > near, "{near} {far}");
        assert_eq!(defocus_sigma_px(&k, 0.0, 5.7, 100.0, 130.0), 0.0);
    }

    #[test]
    fn blur_preserves_a_constant_and_the_mean_of_an_edge() {
        let (w, h) = (64, 32);
        let mut img = LinearImage {
            width: w as u32,
            height: h as u32,
            radiance: (0..w * h).map(|i| if i % w < 32 { 0.1 } else { 0.8 }).collect(),
            depth: vec![150.0; w * h],
        };
        let before: f32 = img.radiance.iter().sum();
        defocus(&mut img, |_| 1.5);
        let after: f32 = img.radiance.iter().sum();
        assert!((before - after).abs() / before < 1e-3);
        // Far from the edge nothing changes; at the edge the value sits halfway.
        assert!((img.radiance[5] - 0.1).abs() < 1e-6);
        let mid = 0.5 * (img.radiance[16 * w + 31] + img.radiance[16 * w + 32]);
        assert!((mid - 0.45).abs() < 1e-3, "{mid}");
    }

    #[test]
    fn a_disc_blur_makes_a_straight_ramp_as_wide_as_the_disc() {
        let (w, h) = (80, 40);
        let mut img = LinearImage {
            width: w as u32,
            height: h as u32,
            radiance: (0..w * h).map(|i| if i % w < 40 { 0.1 } else { 0.8 }).collect(),
            depth: vec![150.0; w * h],
        };
        let before: f32 = img.radiance.iter().sum();
        defocus_disc(&mut img, |_| 5.0);
        let after: f32 = img.radiance.iter().sum();
        assert!((before - after).abs() / before < 1e-3, "energy kept");
        let row = |x: usize| img.radiance[20 * w + x];
        // The edge lies between pixels 39 and 40 (x = 39.5): its halfway point stays there.
        let mid = 0.5 * (row(39) + row(40));
        assert!((mid - 0.45).abs() < 2e-3, "{mid}");
        // A disc of radius 5 reaches 5 px either side and no further (a Gaussian of the same
        // variance, σ = 2.5, would still be 2 % short of the plateau 5 px out).
        assert!((row(33) - 0.1).abs() < 1e-6 && (row(46) - 0.8).abs() < 1e-6, "{} {}", row(33), row(46));
        assert!(row(35) > 0.1 + 1e-4 && row(44) < 0.8 - 1e-4);
        // Between, the ramp: the edge-spread function of a disc (a circular segment's area).
        let quarter = row(37) - 0.1;
        let expected = 0.7 * {
            let d: f64 = 2.5 / 5.0;
            ((d.acos() - d * (1.0 - d * d).sqrt()) / std::f64::consts::PI) as f32
        };
        assert!((quarter - expected).abs() < 0.02, "{quarter} against {expected}");
    }
}
