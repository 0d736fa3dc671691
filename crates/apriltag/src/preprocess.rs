//! The image for quad finding, prepared as the AprilTag C library does it: decimation
//! (`image_u8_decimate`) — integer factors keep every n-th pixel of every n-th row; 1.5 turns
//! each 3×3 block into 2×2 pixels with weights 4-2-2-1 (out of 9), favouring each output's own
//! corner — then the optional blur or sharpening of `quad_sigma`
//! (`image_u8_gaussian_blur_parallel`), with C's 8-bit kernel and untouched borders.

use crate::gray::Gray;
use crate::image::ImageView;
use crate::workers::Workers;

/// Decimates by 1.5, 2, 3 or 4 (any other factor is taken as its integer part, at least 1).
pub fn decimate(im: &ImageView<'_>, factor: f32) -> Gray {
    let mut out = Gray::filled(0, 0, 0);
    decimate_into(im, factor, &mut out);
    out
}

/// [`decimate`] into `out`, reusing its allocation.
pub fn decimate_into(im: &ImageView<'_>, factor: f32, out: &mut Gray) {
    let (w, h) = (im.width(), im.height());
    if factor == 1.5 {
        let (sw, sh) = (w / 3 * 2, h / 3 * 2);
        out.reset(sw, sh, 0);
        for sy in (0..sh).step_by(2) {
            let y = sy / 2 * 3;
            let (r0, r1, r2) = (im.row(y), im.row(y + 1), im.row(y + 2));
            for sx in (0..sw).step_by(2) {
                let x = sx / 2 * 3;
                let p = |r: &[u8], i: usize| u32::from(r[x + i]);
                let (a, b, c) = (p(r0, 0), p(r0, 1), p(r0, 2));
                let (d, e, f) = (p(r1, 0), p(r1, 1), p(r1, 2));
                let (g, hh, i) = (p(r2, 0), p(r2, 1), p(r2, 2));
                out.data[sy * sw + sx] = ((4 * a + 2 * b + 2 * d + e) / 9) as u8;
                out.data[sy * sw + sx + 1] = ((4 * c + 2 * b + 2 * f + e) / 9) as u8;
                out.data[(sy + 1) * sw + sx] = ((4 * g + 2 * d + 2 * hh + e) / 9) as u8;
                out.data[(sy + 1) * sw + sx + 1] = ((4 * i + 2 * f + 2 * hh + e) / 9) as u8;
            }
        }
        return;
    }
    decimate_with(im, factor, out, &Workers::single());
}

/// [`decimate_into`] with the rows shared out over `workers` (integer factors; 1.5 runs on one
/// thread).
pub fn decimate_with(im: &ImageView<'_>, factor: f32, out: &mut Gray, workers: &Workers) {
    if factor == 1.5 {
        return decimate_into(im, factor, out);
    }
    let n = (factor as usize).max(1);
    let (w, h) = (im.width(), im.height());
    let (sw, sh) = (1 + (w - 1) / n, 1 + (h - 1) / n);
    // Every pixel is written below: the fill only sizes a buffer that is new or resized.
    out.width = sw;
    out.height = sh;
    out.data.resize(sw * sh, 0);
    workers.rows_mut(&mut out.data, sw, |rows, piece| keep_every(im, n, piece, rows));
}

/// Output rows `rows` of decimating by `n` (every n-th pixel of every n-th row) into `out`.
fn keep_every(im: &ImageView<'_>, n: usize, out: &mut [u8], rows: std::ops::Range<usize>) {
    let sw = 1 + (im.width() - 1) / n;
    for (y, dst) in rows.zip(out.chunks_exact_mut(sw)) {
        let src = im.row(y * n);
        if n == 2 {
            // Pairs, so the loop vectorises; an odd width leaves its last pixel.
            for (d, pair) in dst.iter_mut().zip(src.chunks_exact(2)) {
                *d = pair[0];
            }
            if src.len() % 2 == 1 {
                dst[sw - 1] = src[src.len() - 1];
            }
        } else {
            for (d, &v) in dst.iter_mut().zip(src.iter().step_by(n)) {
                *d = v;
            }
        }
    }
}

/// C's `quad_sigma` step, in place: a Gaussian blur of σ = `quad_sigma` px, or for negative
/// values a sharpening (2 × image − blur). The kernel spans ±2σ (odd width `4σ`, at least 3,
/// or nothing happens), its weights are C's 8-bit ones (they sum to a little under 256), and
/// the `width/2` pixels at each end of every row and column are left as they were.
pub fn blur_or_sharpen(img: &mut Gray, quad_sigma: f32) {
    let sigma = quad_sigma.abs();
    let mut ksz = (4.0 * sigma) as usize;
    if ksz.is_multiple_of(2) {
        ksz += 1;
    }
    if ksz <= 1 {
        return;
    }
    let sigma = f64::from(sigma);
    let dk: Vec<f64> = (0..ksz)
        .map(|i| {
            let x = i as f64 - (ksz / 2) as f64;
            (-0.5 * (x / sigma) * (x / sigma)).exp()
        })
        .collect();
    let total: f64 = dk.iter().sum();
    let k: Vec<u32> = dk.iter().map(|v| (v / total * 255.0) as u8 as u32).collect();
    // C convolves small images with a variant that leaves one more pixel at the far end.
    let small = img.width * img.height < 65536;
    let orig = (quad_sigma < 0.0).then(|| img.data.clone());
    let (w, h) = (img.width, img.height);
    let mut line = vec![0u8; w.max(h)];
    let mut out = vec![0u8; w.max(h)];
    for y in 0..h {
        line[..w].copy_from_slice(&img.data[y * w..(y + 1) * w]);
        convolve(&line[..w], &mut out[..w], &k, small);
        img.data[y * w..(y + 1) * w].copy_from_slice(&out[..w]);
    }
    for x in 0..w {
        for (l, row) in line.iter_mut().zip(img.data.chunks_exact(w)) {
            *l = row[x];
        }
        convolve(&line[..h], &mut out[..h], &k, small);
        for (o, row) in out.iter().zip(img.data.chunks_exact_mut(w)) {
            row[x] = *o;
        }
    }
    if let Some(orig) = orig {
        for (v, &o) in img.data.iter_mut().zip(&orig) {
            *v = (2 * i32::from(o) - i32::from(*v)).clamp(0, 255) as u8;
        }
    }
}

/// One row or column through the 8-bit kernel `k` (C's `convolve`).
fn convolve(x: &[u8], y: &mut [u8], k: &[u32], small: bool) {
    let (sz, ksz) = (x.len(), k.len());
    let half = ksz / 2;
    y.copy_from_slice(x);
    let n = if small { sz.saturating_sub(ksz) } else { (sz + 1).saturating_sub(ksz) };
    for i in 0..n {
        let acc: u32 = k.iter().zip(&x[i..i + ksz]).map(|(&k, &v)| k * u32::from(v)).sum();
        y[half + i] = (acc >> 8) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_decimation_keeps_every_nth_pixel() {
        let data: Vec<u8> = (0..7 * 5).map(|v| v as u8).collect();
        let im = ImageView::new(&data, 7, 5, 7).expect("valid");
        let d = decimate(&im, 2.0);
        assert_eq!((d.width, d.height), (4, 3));
        assert_eq!(d.data, vec![0, 2, 4, 6, 14, 16, 18, 20, 28, 30, 32, 34]);
        assert_eq!(decimate(&im, 1.0).data, data);
    }

    #[test]
    fn decimation_by_one_and_a_half_weights_the_corners() {
        let data = vec![90u8; 6 * 6];
        let im = ImageView::new(&data, 6, 6, 6).expect("valid");
        let d = decimate(&im, 1.5);
        assert_eq!((d.width, d.height), (4, 4));
        assert!(d.data.iter().all(|&v| v == 90), "a flat image stays flat");
        let mut data = vec![0u8; 9];
        data[0] = 9; // a: weight 4 of 9 for the top-left output only
        let d = decimate(&ImageView::new(&data, 3, 3, 3).expect("valid"), 1.5);
        assert_eq!(d.data, vec![4, 0, 0, 0]);
    }

    #[test]
    fn blur_spreads_a_step_and_sharpening_steepens_it() {
        let (w, h) = (300, 300); // above C's small-image size: its full-width variant
        let data: Vec<u8> = (0..w * h).map(|i| if i % w < 150 { 50 } else { 200 }).collect();
        let mut blurred = Gray { width: w, height: h, data: data.clone() };
        blur_or_sharpen(&mut blurred, 1.0);
        let row = &blurred.data[100 * w..101 * w];
        // Flat areas lose a little to the 8-bit kernel (its weights sum to under 256).
        assert!((45..=50).contains(&row[50]), "{}", row[50]);
        assert!(row[149] > 50 && row[149] < 200 && row[150] > row[149], "{:?}", &row[146..154]);
        // The 2 pixels at each end of a row or column (ksz 5) are left alone by that pass, so
        // the frame's corners keep their values.
        let d = &blurred.data;
        assert_eq!((d[0], d[w + 1], d[w - 1], d[(h - 1) * w + w - 1]), (50, 50, 200, 200));
        let mut sharp = Gray { width: w, height: h, data };
        blur_or_sharpen(&mut sharp, -1.0);
        let row = &sharp.data[100 * w..101 * w];
        assert!(row[149] < 50 && row[150] > 200, "{:?}", &row[146..154]);
        // Below σ 0.5 the kernel is one tap wide: nothing changes.
        let mut same = Gray { width: 4, height: 4, data: vec![7; 16] };
        blur_or_sharpen(&mut same, 0.4);
        assert_eq!(same.data, vec![7; 16]);
    }
}
