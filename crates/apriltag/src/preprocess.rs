//! Decimation before quad finding, as the AprilTag C library does it (`image_u8_decimate`):
//! integer factors keep every n-th pixel of every n-th row; 1.5 turns each 3×3 block into
//! 2×2 pixels with weights 4-2-2-1 (out of 9), favouring each output's own corner.

use crate::gray::Gray;
use crate::image::ImageView;

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
    let n = (factor as usize).max(1);
    let (sw, sh) = (1 + (w - 1) / n, 1 + (h - 1) / n);
    out.width = sw;
    out.height = sh;
    out.data.clear();
    for y in (0..h).step_by(n) {
        out.data.extend(im.row(y).iter().step_by(n));
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
}
