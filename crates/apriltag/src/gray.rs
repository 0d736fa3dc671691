//! An owned 8-bit gray image (stride = width), the detector's working buffers.

use crate::DetectError;
use crate::image::ImageView;

/// An owned gray image, rows packed.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Gray {
    /// Width (px).
    pub width: usize,
    /// Height (px).
    pub height: usize,
    /// Pixels, row-major, `width` per row.
    pub data: Vec<u8>,
}

impl Gray {
    /// A `width × height` image filled with `value`.
    pub fn filled(width: usize, height: usize, value: u8) -> Self {
        Gray { width, height, data: vec![value; width * height] }
    }

    /// Makes this a `width × height` image of `value`, reusing the allocation.
    pub fn reset(&mut self, width: usize, height: usize, value: u8) {
        self.width = width;
        self.height = height;
        self.data.clear();
        self.data.resize(width * height, value);
    }

    /// A view of it; an empty image (e.g. a 2×2 frame decimated by 1.5) has none.
    pub fn view(&self) -> Result<ImageView<'_>, DetectError> {
        ImageView::new(&self.data, self.width, self.height, self.width)
    }
}
