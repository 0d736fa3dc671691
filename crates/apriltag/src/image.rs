//! Borrowed 8-bit grayscale frames: the detector reads the camera's luma plane in place.

use crate::DetectError;

/// The longest side the detector reads (px): cluster points are kept at half-pixel precision
/// in 16-bit signed arithmetic, as in the C library (a 48 MP phone frame is 8064 px wide).
pub const MAX_SIDE: usize = 16383;

/// A borrowed 8-bit gray image: `height` rows of `width` pixels, rows `stride` bytes apart.
/// Pixel (x, y) is `data[y * stride + x]`; its centre is at coordinates (x, y).
#[derive(Debug, Clone, Copy)]
pub struct ImageView<'a> {
    data: &'a [u8],
    width: usize,
    height: usize,
    stride: usize,
}

impl<'a> ImageView<'a> {
    /// Wraps a buffer, checking that it holds `height` rows of `width` pixels `stride` apart
    /// (the last row may end right after its last pixel).
    pub fn new(data: &'a [u8], width: usize, height: usize, stride: usize) -> Result<Self, DetectError> {
        if width == 0 || height == 0 {
            return Err(DetectError::BadImage(format!("the image is empty ({width}×{height})")));
        }
        if width > MAX_SIDE || height > MAX_SIDE {
            return Err(DetectError::BadImage(format!(
                "the image is {width}×{height} px; the detector reads images up to {MAX_SIDE} px a side"
            )));
        }
        if stride < width {
            return Err(DetectError::BadImage(format!("stride {stride} is less than the width {width}")));
        }
        let needed = stride
            .checked_mul(height - 1)
            .and_then(|n| n.checked_add(width))
            .ok_or_else(|| DetectError::BadImage(format!("{width}×{height} with stride {stride} overflows")))?;
        if data.len() < needed {
            return Err(DetectError::BadImage(format!(
                "the buffer holds {} bytes but {width}×{height} with stride {stride} needs {needed}",
                data.len()
            )));
        }
        Ok(ImageView { data, width, height, stride })
    }

    /// The luma (Y) plane of a 420f/NV12 frame, as delivered with its bytes-per-row: the same
    /// view, named for the call site.
    pub fn nv12_luma(
        y_plane: &'a [u8],
        width: usize,
        height: usize,
        bytes_per_row: usize,
    ) -> Result<Self, DetectError> {
        Self::new(y_plane, width, height, bytes_per_row)
    }

    /// Width (px).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height (px).
    pub fn height(&self) -> usize {
        self.height
    }

    /// Bytes from one row to the next.
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// The buffer as given: pixel (x, y) at `y * stride + x` (for a backend that reads it whole).
    pub fn data(&self) -> &'a [u8] {
        self.data
    }

    /// Row `y` (exactly `width` pixels). Panics past the last row, like slice indexing.
    pub fn row(&self, y: usize) -> &'a [u8] {
        &self.data[y * self.stride..y * self.stride + self.width]
    }

    /// The window of `width × height` pixels whose top-left pixel is (x, y), sharing the
    /// buffer.
    pub fn sub_view(&self, x: usize, y: usize, width: usize, height: usize) -> Result<ImageView<'a>, DetectError> {
        if x + width > self.width || y + height > self.height {
            return Err(DetectError::BadImage(format!(
                "window {width}×{height} at ({x}, {y}) leaves the {}×{} image",
                self.width, self.height
            )));
        }
        ImageView::new(&self.data[y * self.stride + x..], width, height, self.stride)
    }

    /// Pixel (x, y), or `None` outside the image.
    pub fn get(&self, x: usize, y: usize) -> Option<u8> {
        (x < self.width && y < self.height).then(|| self.data[y * self.stride + x])
    }
}

/// Luma of a BGRA frame (bytes B, G, R, A per pixel, rows `stride` bytes apart) with the
/// BT.601 weights in fixed point: Y = (29·B + 150·G + 77·R + 128) / 256. BGRA frames are
/// converted once; the luma plane of an NV12 frame needs no conversion at all.
pub fn luma_from_bgra(bgra: &[u8], width: usize, height: usize, stride: usize) -> Result<Vec<u8>, DetectError> {
    let mut out = Vec::new();
    luma_from_bgra_into(bgra, width, height, stride, &mut out)?;
    Ok(out)
}

/// [`luma_from_bgra`] into `out` (cleared first), so a caller that converts every frame
/// reuses one buffer.
pub fn luma_from_bgra_into(
    bgra: &[u8],
    width: usize,
    height: usize,
    stride: usize,
    out: &mut Vec<u8>,
) -> Result<(), DetectError> {
    let row_bytes = width.checked_mul(4).ok_or_else(|| DetectError::BadImage(format!("width {width} overflows")))?;
    // Validate the layout as a view of bytes, 4 per pixel.
    ImageView::new(bgra, row_bytes, height, stride)?;
    out.clear();
    out.reserve(width * height);
    for y in 0..height {
        let row = &bgra[y * stride..y * stride + row_bytes];
        out.extend(
            row.chunks_exact(4)
                .map(|p| ((29 * u32::from(p[0]) + 150 * u32::from(p[1]) + 77 * u32::from(p[2]) + 128) >> 8) as u8),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_wider_than_the_detector_reads_is_refused_not_wrapped() {
        // Found by the `c-door` fuzz target: a 51912 px wide frame overflowed the clusters'
        // 16-bit half-pixel coordinates (a panic in a debug build, wrapped points in release).
        let data = vec![0u8; 2 * (MAX_SIDE + 1)];
        let err = ImageView::new(&data, MAX_SIDE + 1, 2, MAX_SIDE + 1).expect_err("too wide").to_string();
        assert!(err.contains("up to 16383 px a side"), "{err}");
        assert!(ImageView::new(&data, 2, MAX_SIDE + 1, 2).is_err(), "too tall");
        let view = ImageView::new(&data, MAX_SIDE, 2, MAX_SIDE).expect("the widest image read");
        let detector =
            crate::Detector::new(crate::DetectorConfig { quad_decimate: 1.0, ..Default::default() }).expect("settings");
        assert_eq!(detector.detect(&view).expect("a blank frame").len(), 0);
    }

    #[test]
    fn views_check_their_layout() {
        let buf = vec![7u8; 10 * 4];
        let v = ImageView::new(&buf, 8, 4, 10).expect("fits");
        assert_eq!(v.row(3).len(), 8);
        assert_eq!(v.get(7, 3), Some(7));
        assert_eq!(v.get(8, 3), None);
        // The last row may stop right after its pixels.
        assert!(ImageView::new(&buf[..38], 8, 4, 10).is_ok());
        for (w, h, s, why) in [
            (0, 4, 10, "empty"),
            (8, 4, 7, "stride"),
            (8, 5, 10, "needs"),
            (3, 3, usize::MAX, "overflows"),
            (usize::MAX, 3, usize::MAX, "a side"),
        ] {
            let e = ImageView::new(&buf, w, h, s).expect_err("bad layout").to_string();
            assert!(e.contains(why), "{e}");
        }
    }

    #[test]
    fn bgra_to_luma_uses_bt601_weights() {
        // white, black, pure blue, green, red; padded rows.
        let px = [[255, 255, 255, 255], [0, 0, 0, 255], [255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]];
        let mut buf = Vec::new();
        for p in &px {
            buf.extend_from_slice(p);
        }
        buf.extend_from_slice(&[9; 4]); // padding to a 24-byte stride
        let y = luma_from_bgra(&buf, 5, 1, 24).expect("valid");
        assert_eq!(y, vec![255, 0, 29, 149, 77]); // (150·255 + 128) >> 8 = 149
        assert!(luma_from_bgra(&buf, 5, 2, 24).is_err(), "short buffer");
        assert!(luma_from_bgra(&buf, 7, 1, 24).is_err(), "stride < 4·width");
    }
}
