//! The interface every tag detector offers JawTrack: ours ([`Detector`]) and the AprilTag C
//! library's (`jawtrack-apriltag-reference`) both implement [`TagDetector`], so tests and
//! benchmarks run either (or a new backend) through the same calls and compare the same
//! [`Detection`]s. A new backend implements it in its own crate.

use crate::{DetectError, Detection, Detector, ImageView};

/// A tag detector backend.
///
/// # Examples
///
/// ```
/// use jawtrack_apriltag::{Detector, DetectorConfig, ImageView, TagDetector};
///
/// fn count(detector: &mut dyn TagDetector, frame: &ImageView<'_>) -> usize {
///     detector.detect_tags(frame).map_or(0, |tags| tags.len())
/// }
///
/// let mut ours = Detector::new(DetectorConfig::default()).expect("default settings are valid");
/// let blank = vec![255u8; 64 * 48];
/// let frame = ImageView::new(&blank, 64, 48, 64).expect("a 64×48 frame");
/// assert_eq!(count(&mut ours, &frame), 0);
/// assert_eq!(ours.backend_name(), "jawtrack");
/// ```
pub trait TagDetector {
    /// A short name for reports, e.g. `"jawtrack"` or `"apriltag-c"`.
    fn backend_name(&self) -> &'static str;

    /// The tags found in `frame`, in pixels (the centre of the top-left pixel at (0, 0)),
    /// corners bottom-left, bottom-right, top-right, top-left of the upright tag.
    fn detect_tags(&mut self, frame: &ImageView<'_>) -> Result<Vec<Detection>, DetectError>;
}

impl TagDetector for Detector {
    fn backend_name(&self) -> &'static str {
        "jawtrack"
    }

    fn detect_tags(&mut self, frame: &ImageView<'_>) -> Result<Vec<Detection>, DetectError> {
        self.detect(frame)
    }
}
