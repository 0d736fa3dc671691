//! The AprilTag C library (AprilRobotics, 3.4.5 as vendored by `apriltag-sys`) behind a safe
//! wrapper, for tests and benchmarks only: it is the reference our detector must match or
//! beat, and an independent check of the renderer. Nothing in the product depends on it.
//!
//! Results are converted to JawTrack's pixel convention (centre of the top-left pixel at
//! (0, 0); the C library reports +0.5 px) and keep the library's corner order (bottom-left,
//! bottom-right, top-right, top-left of the upright tag). [`ReferenceDetector`] is a
//! [`TagDetector`] backend, so it runs through the same calls as ours.

// The one crate allowed to call C: every unsafe block below says why it is sound.
#![allow(unsafe_code)]

use apriltag_sys as sys;
use jawtrack_apriltag::{DetectError, Detection, ImageView, TagDetector, TagFamily};

/// Detector settings with the C library's meaning.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceParams {
    /// Decimation before quad detection (1, 1.5, 2, 3, 4).
    pub quad_decimate: f32,
    /// Gaussian blur before quad detection (px, 0 = none).
    pub quad_sigma: f32,
    /// Worker threads.
    pub nthreads: i32,
    /// Refine edges at full resolution.
    pub refine_edges: bool,
    /// Sharpening of the decoded samples.
    pub decode_sharpening: f64,
    /// Bit errors corrected (0–2 here; the library allows 3 at a large memory cost).
    pub max_hamming: i32,
    /// Minimum difference between a quad's white and black (the C default is 5).
    pub min_white_black_diff: i32,
    /// Close and open the threshold image (the C `deglitch`).
    pub deglitch: bool,
    /// The library's debug mode: it writes its stage images (`debug_preprocess.pnm`,
    /// `debug_threshold.pnm`, …) into the current directory. For stage-by-stage comparisons.
    pub debug: bool,
}

impl Default for ReferenceParams {
    /// The C library's own defaults (decimate 2, no blur, 1 thread, refine edges, sharpening
    /// 0.25), with max_hamming 2.
    fn default() -> Self {
        ReferenceParams {
            quad_decimate: 2.0,
            quad_sigma: 0.0,
            nthreads: 1,
            refine_edges: true,
            decode_sharpening: 0.25,
            max_hamming: 2,
            min_white_black_diff: 5,
            deglitch: false,
            debug: false,
        }
    }
}

/// One tag found by the C library.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceDetection {
    /// Id in the detector's family.
    pub id: u32,
    /// Bits corrected.
    pub hamming: u32,
    /// The library's decision margin.
    pub margin: f32,
    /// Centre (px, our convention).
    pub center: [f64; 2],
    /// Corners (px, our convention) in the library's order.
    pub corners: [[f64; 2]; 4],
    /// Homography from tag coordinates ([−1, 1]², y down) to pixels (our convention),
    /// row-major 3×3.
    pub homography: [f64; 9],
}

/// Why the C library was not called.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReferenceError {
    /// Width, height or stride that cannot describe the buffer.
    BadImage(String),
    /// The library could not be set up.
    Setup(&'static str),
}

impl std::fmt::Display for ReferenceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReferenceError::BadImage(s) => write!(f, "bad image: {s}"),
            ReferenceError::Setup(s) => write!(f, "reference detector: {s}"),
        }
    }
}

impl std::error::Error for ReferenceError {}

/// A detector of the C library, for one tag family.
pub struct ReferenceDetector {
    td: *mut sys::apriltag_detector_t,
    family: *mut sys::apriltag_family_t,
    destroy: unsafe extern "C" fn(*mut sys::apriltag_family_t),
}

type FamilyCalls =
    (unsafe extern "C" fn() -> *mut sys::apriltag_family_t, unsafe extern "C" fn(*mut sys::apriltag_family_t));

/// The C library's constructor and destructor of the family that has this name.
fn family_calls(name: &str) -> Option<FamilyCalls> {
    match name {
        "tag36h11" => Some((sys::tag36h11_create, sys::tag36h11_destroy)),
        "tag25h9" => Some((sys::tag25h9_create, sys::tag25h9_destroy)),
        "tag16h5" => Some((sys::tag16h5_create, sys::tag16h5_destroy)),
        _ => None,
    }
}

/// The C library's own description of a family: what [`TagFamily`] must equal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReferenceFamily {
    /// The codewords, index = tag id.
    pub codes: Vec<u64>,
    /// The cell of each bit, most significant first.
    pub bit_cells: Vec<(u8, u8)>,
    /// Minimum Hamming distance.
    pub min_hamming: u32,
    /// Cells across the black-border square.
    pub width_at_border: usize,
    /// Cells across the whole tag.
    pub total_width: usize,
    /// Whether the border is light inside dark.
    pub reversed_border: bool,
}

impl ReferenceDetector {
    /// Creates a detector for tag36h11 with these settings.
    pub fn new(params: &ReferenceParams) -> Result<Self, ReferenceError> {
        Self::with_family(params, &TagFamily::TAG36H11)
    }

    /// Creates a detector for `family` (tag36h11, tag25h9 or tag16h5) with these settings.
    pub fn with_family(params: &ReferenceParams, family: &TagFamily) -> Result<Self, ReferenceError> {
        let Some((create, destroy)) = family_calls(family.name) else {
            return Err(ReferenceError::Setup("the C library is wrapped for tag36h11, tag25h9 and tag16h5 only"));
        };
        if !(0..=2).contains(&params.max_hamming) {
            return Err(ReferenceError::Setup("max_hamming must be 0, 1 or 2"));
        }
        // SAFETY: plain constructors; null results are checked before any use, and both objects
        // are owned by the returned value, which frees them once in Drop.
        unsafe {
            let td = sys::apriltag_detector_create();
            if td.is_null() {
                return Err(ReferenceError::Setup("apriltag_detector_create failed"));
            }
            let family = create();
            if family.is_null() {
                sys::apriltag_detector_destroy(td);
                return Err(ReferenceError::Setup("the family's constructor failed"));
            }
            sys::apriltag_detector_add_family_bits(td, family, params.max_hamming);
            (*td).quad_decimate = params.quad_decimate;
            (*td).quad_sigma = params.quad_sigma;
            (*td).nthreads = params.nthreads.max(1);
            (*td).refine_edges = params.refine_edges;
            (*td).decode_sharpening = params.decode_sharpening;
            (*td).qtp.min_white_black_diff = params.min_white_black_diff;
            (*td).qtp.deglitch = i32::from(params.deglitch);
            (*td).debug = params.debug;
            Ok(ReferenceDetector { td, family, destroy })
        }
    }

    /// The family as the C library holds it.
    pub fn family(&self) -> ReferenceFamily {
        // SAFETY: `family` was created in `new` and lives until Drop; its arrays hold `ncodes`
        // codes and `nbits` coordinates, as the library's constructors allocate them.
        unsafe {
            let f = &*self.family;
            let codes = std::slice::from_raw_parts(f.codes, f.ncodes as usize).to_vec();
            let xs = std::slice::from_raw_parts(f.bit_x, f.nbits as usize);
            let ys = std::slice::from_raw_parts(f.bit_y, f.nbits as usize);
            ReferenceFamily {
                codes,
                bit_cells: xs.iter().zip(ys).map(|(&x, &y)| (x as u8, y as u8)).collect(),
                min_hamming: f.h,
                width_at_border: f.width_at_border as usize,
                total_width: f.total_width as usize,
                reversed_border: f.reversed_border,
            }
        }
    }

    /// Detects tags in an 8-bit gray image of `width × height` pixels, rows `stride` bytes apart.
    pub fn detect(
        &mut self,
        pixels: &[u8],
        width: usize,
        height: usize,
        stride: usize,
    ) -> Result<Vec<ReferenceDetection>, ReferenceError> {
        if width == 0 || height == 0 {
            return Err(ReferenceError::BadImage(format!("empty image {width}×{height}")));
        }
        if stride < width {
            return Err(ReferenceError::BadImage(format!("stride {stride} < width {width}")));
        }
        let needed = stride * (height - 1) + width;
        if pixels.len() < needed {
            return Err(ReferenceError::BadImage(format!("buffer of {} bytes, {needed} needed", pixels.len())));
        }
        let to_i32 = |v: usize, what: &str| {
            i32::try_from(v).map_err(|_| ReferenceError::BadImage(format!("{what} {v} too large")))
        };
        // With a blur and no decimation the library blurs its input in place: give it a copy.
        // SAFETY (of reading `self.td`): created in `new`, valid until Drop.
        let writes_input = unsafe { (*self.td).quad_sigma != 0.0 && (*self.td).quad_decimate <= 1.0 };
        let mut copy = Vec::new();
        let buf = if writes_input {
            copy.extend_from_slice(&pixels[..needed]);
            copy.as_mut_ptr()
        } else {
            // Otherwise the library only reads it; *mut is what its C signature asks.
            pixels.as_ptr().cast_mut()
        };
        let mut image = sys::image_u8 {
            width: to_i32(width, "width")?,
            height: to_i32(height, "height")?,
            stride: to_i32(stride, "stride")?,
            buf,
        };
        let mut out = Vec::new();
        // SAFETY: `image` describes `pixels` exactly (bounds checked above) and outlives the call;
        // the returned zarray holds `size` pointers to detections, read before it is destroyed.
        unsafe {
            let dets = sys::apriltag_detector_detect(self.td, &mut image);
            if dets.is_null() {
                return Ok(out);
            }
            let n = usize::try_from((*dets).size).unwrap_or(0);
            let items = (*dets).data.cast::<*mut sys::apriltag_detection_t>();
            for i in 0..n {
                let d = &**items.add(i);
                // The library's H maps to its pixels (+0.5); shifting its first two rows by half
                // its third maps to ours. H is a 3×3 row-major matd_t when present.
                let mut homography = [0.0; 9];
                if let Some(h) = d.H.as_ref().filter(|h| h.nrows == 3 && h.ncols == 3 && !h.data.is_null()) {
                    let c = std::slice::from_raw_parts(h.data, 9);
                    for col in 0..3 {
                        homography[col] = c[col] - 0.5 * c[6 + col];
                        homography[3 + col] = c[3 + col] - 0.5 * c[6 + col];
                        homography[6 + col] = c[6 + col];
                    }
                }
                out.push(ReferenceDetection {
                    id: u32::try_from(d.id).unwrap_or(u32::MAX),
                    hamming: u32::try_from(d.hamming).unwrap_or(u32::MAX),
                    margin: d.decision_margin,
                    center: [d.c[0] - 0.5, d.c[1] - 0.5],
                    corners: d.p.map(|p| [p[0] - 0.5, p[1] - 0.5]),
                    homography,
                });
            }
            sys::apriltag_detections_destroy(dets);
        }
        Ok(out)
    }
}

impl Drop for ReferenceDetector {
    fn drop(&mut self) {
        // SAFETY: both pointers were created in `new` and are freed exactly once here.
        unsafe {
            sys::apriltag_detector_destroy(self.td);
            (self.destroy)(self.family);
        }
    }
}

impl TagDetector for ReferenceDetector {
    fn backend_name(&self) -> &'static str {
        "apriltag-c"
    }

    /// The library's tags as [`Detection`]s; it measures no blur (`blur_px` is `None`).
    fn detect_tags(&mut self, frame: &ImageView<'_>) -> Result<Vec<Detection>, DetectError> {
        let found = self.detect(frame.data(), frame.width(), frame.height(), frame.stride()).map_err(|e| match e {
            ReferenceError::BadImage(s) => DetectError::BadImage(s),
            ReferenceError::Setup(s) => DetectError::BadConfig(s.to_owned()),
        })?;
        Ok(found
            .into_iter()
            .map(|d| Detection {
                id: d.id,
                hamming: d.hamming,
                decision_margin: d.margin,
                center: d.center,
                corners: d.corners,
                homography: d.homography,
                blur_px: None,
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_buffers_are_refused_not_read() {
        let mut d = ReferenceDetector::new(&ReferenceParams::default()).expect("detector");
        assert!(d.detect(&[0; 10], 4, 4, 4).is_err());
        assert!(d.detect(&[0; 16], 4, 4, 3).is_err());
        assert!(d.detect(&[], 0, 0, 0).is_err());
        assert_eq!(d.detect(&[128; 64 * 64], 64, 64, 64), Ok(vec![]));
        assert!(ReferenceDetector::new(&ReferenceParams { max_hamming: 3, ..ReferenceParams::default() }).is_err());
    }
}
