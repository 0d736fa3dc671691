//! Detector settings. Names, meanings and defaults follow the AprilTag C library so results
//! and benchmarks compare like with like; each says what it trades.

use crate::DetectError;
use jawtrack_tag_family::TagFamily;
use jawtrack_tone::{ToneCurve, ToneSetting};

/// A rectangle of the full frame to search (px); detections keep full-frame coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Roi {
    /// Left column.
    pub x: usize,
    /// Top row.
    pub y: usize,
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
}

/// Settings of the quad finder (the C library's `apriltag_quad_thresh_params`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadThreshold {
    /// Smallest connected boundary (in pixels of the decimated image) considered a quad
    /// candidate. Lower finds smaller tags and costs time on noise.
    pub min_cluster_pixels: usize,
    /// Corner candidates examined per cluster. More survives odd shapes, costs time.
    pub max_nmaxima: usize,
    /// Cosine of the smallest corner angle a quad may have: rejects slivers; higher accepts
    /// only squarer quads (C: cos 10°).
    pub cos_critical_rad: f32,
    /// Largest mean squared error of a side's line fit (px²): lower rejects curved or
    /// blurred sides, higher accepts more false quads.
    pub max_line_fit_mse: f32,
    /// Smallest brightness difference (grey levels) over a 12 × 12 pixel neighbourhood for its
    /// pixels to be split into dark and light; flatter neighbourhoods take no part. Lower keeps
    /// fainter tags but lets sensor noise through, where every speck becomes a region to fit
    /// (C's 5 is 5–7× slower than 20 on noisy frames); higher is faster and drops faint tags.
    /// Default 20.
    pub min_white_black_diff: u8,
    /// Close and open the threshold image to repair broken edges (slow; for poor images).
    pub deglitch: bool,
}

impl QuadThreshold {
    /// The C library's defaults.
    pub fn reference() -> Self {
        QuadThreshold {
            min_cluster_pixels: 5,
            max_nmaxima: 10,
            cos_critical_rad: 10f32.to_radians().cos(),
            max_line_fit_mse: 10.0,
            min_white_black_diff: 5,
            deglitch: false,
        }
    }
}

impl Default for QuadThreshold {
    /// C's defaults except `min_white_black_diff` 20 (C: 5), for phone frames: sensor noise
    /// of a few grey levels makes every flat patch pass C's contrast test, and each speck
    /// becomes a region to cluster and fit, 5–7× slower. At 20 no tag of our rendered
    /// sets or of the real photos is lost (at 40 one faint photo tag is; see BENCHMARKS.md).
    fn default() -> Self {
        QuadThreshold { min_white_black_diff: 20, ..QuadThreshold::reference() }
    }
}

/// Detector settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorConfig {
    /// Decimation of the image for quad finding: 1, 1.5, 2, 3 or 4. Higher is faster and
    /// misses small tags; corners are refined at full resolution either way.
    pub quad_decimate: f32,
    /// Gaussian blur σ (px) before quad finding; negative sharpens. Helps on noisy frames,
    /// hurts tiny tags.
    pub quad_sigma: f32,
    /// Worker threads.
    pub nthreads: usize,
    /// Refine each edge at full resolution from the image gradient. Costs little, gains much
    /// corner accuracy, most of all with decimation.
    pub refine_edges: bool,
    /// JawTrack's edge fit instead of C's: (1) in linear light, reading the frame through
    /// [`DetectorConfig::tone`] — a blurred edge located in encoded values moves
    /// toward its dark side by a fraction of the blur, in linear light it stays put; (2) with
    /// the gradient's plain mean along the normal rather than the mean weighted by its square,
    /// which pulls toward pixel centres by up to 0.1 px; (3) with the search window re-centred
    /// on the edge found, so a wide blur (4K) is not cut off on one side; (4) with only the
    /// one edge nearest the quad's side, within half a cell of it: on small or steeply tilted
    /// tags the window otherwise takes in the next edge out (white border to a brighter
    /// background) and pulls the side outward by 1–2 px; the window is split so only on sides
    /// whose gradient profile, summed along the side, shows two edges (one sample's profile on
    /// a dim, blurred grazing tag dips by noise alone); (5) passing over the quads a decoded
    /// tag's data cells make. `false` reproduces the C library exactly.
    pub linear_edges: bool,
    /// With `linear_edges`, the curve the camera encoded frames with, undone to fit edges in
    /// linear light. A curve that is not the camera's moves every blurred edge toward one side
    /// by a share of its blur (a phone's gamma 1.8 read as sRGB: the jaw 6× further off).
    /// `Auto` (the default) estimates it from the tags over the frames a detector sees
    /// ([`crate::tone`]); a fixed curve is read through as given.
    pub tone: ToneSetting,
    /// With `linear_edges`, fit edges smeared by motion: where a side's edge runs past the
    /// window, the window is widened, up to a cell, over the whole ramp (motion blur smears an
    /// edge into a ramp as wide as the motion during the exposure, whose centre is the edge at
    /// mid-exposure; a window inside the ramp finds wherever it sits), taking the gradient
    /// above half the ramp's height only. Off for frames that are not moving: a defocused
    /// edge wider than the window is a ramp too, which this fit reads off its centre (a
    /// tripod 4K frame's jaw moved 0.04 mm). The tracker turns it on for the frames in which
    /// it predicts a smear ([`crate::Detector::detect_in_with`]).
    pub smeared_edges: bool,
    /// With `linear_edges`, re-fit each decoded tag's border by a model of its known pattern
    /// under a Gaussian blur (the data cells one cell inside the border and the quiet zone's
    /// edge one cell outside it, whose ramps overlap the border's once the blur nears a fifth
    /// of a cell), and measure that blur ([`crate::Detection::blur_px`]): a small, steeply
    /// tilted or defocused tag's corners then stay put. Costs a few Levenberg–Marquardt
    /// iterations per side.
    pub blur_aware_edges: bool,
    /// Sharpening of the decoded bit samples: helps small, blurred tags decode.
    pub decode_sharpening: f64,
    /// Bit errors corrected when decoding, 0–2. More recovers damaged tags and raises the
    /// false-positive rate; 3 or more is refused (the C library's table for 3 takes
    /// hundreds of MB and decodes noise).
    pub max_hamming: u32,
    /// Quad finder settings.
    pub quad: QuadThreshold,
    /// Search only this rectangle.
    pub roi: Option<Roi>,
    /// The tag family to find (tag36h11 by default; see [`TagFamily`]).
    pub family: TagFamily,
}

impl Default for DetectorConfig {
    /// The C library's defaults (decimate 2, no blur, one thread, refine edges, sharpening
    /// 0.25, max_hamming 2), with edges refined in linear light and the quad finder's
    /// contrast threshold raised for noisy frames (see [`QuadThreshold::default`]).
    fn default() -> Self {
        DetectorConfig {
            quad_decimate: 2.0,
            quad_sigma: 0.0,
            nthreads: 1,
            refine_edges: true,
            linear_edges: true,
            tone: ToneSetting::Auto,
            smeared_edges: false,
            blur_aware_edges: true,
            decode_sharpening: 0.25,
            max_hamming: 2,
            quad: QuadThreshold::default(),
            roi: None,
            family: TagFamily::TAG36H11,
        }
    }
}

impl DetectorConfig {
    /// The C library's defaults exactly, edges refined as C does (in encoded values): the
    /// settings under which this detector returns the C library's results.
    pub fn reference() -> Self {
        DetectorConfig {
            linear_edges: false,
            tone: ToneSetting::Fixed(ToneCurve::Srgb),
            quad: QuadThreshold::reference(),
            ..DetectorConfig::default()
        }
    }

    /// Checks every setting, naming the first bad one.
    pub fn validate(&self) -> Result<(), DetectError> {
        let bad = |s: String| Err(DetectError::BadConfig(s));
        if ![1.0, 1.5, 2.0, 3.0, 4.0].contains(&self.quad_decimate) {
            return bad(format!("quad_decimate must be 1, 1.5, 2, 3 or 4, got {}", self.quad_decimate));
        }
        if !self.quad_sigma.is_finite() || self.quad_sigma.abs() > 4.0 {
            return bad(format!("quad_sigma must be between -4 and 4 px, got {}", self.quad_sigma));
        }
        if self.nthreads == 0 {
            return bad("nthreads must be at least 1".into());
        }
        if !self.decode_sharpening.is_finite() || self.decode_sharpening < 0.0 {
            return bad(format!("decode_sharpening must be a non-negative number, got {}", self.decode_sharpening));
        }
        if self.max_hamming > 2 {
            return bad(format!(
                "max_hamming {} is refused: at most 2 (3 needs a very large table and accepts noise as tags)",
                self.max_hamming
            ));
        }
        self.family.validate().map_err(DetectError::BadConfig)?;
        if let ToneSetting::Fixed(curve) = self.tone {
            curve.validate().map_err(|e| DetectError::BadConfig(e.to_string()))?;
        }
        let q = &self.quad;
        if q.max_nmaxima == 0 {
            return bad("quad.max_nmaxima must be at least 1".into());
        }
        if !q.cos_critical_rad.is_finite() || !(-1.0..=1.0).contains(&q.cos_critical_rad) {
            return bad(format!("quad.cos_critical_rad is a cosine, in [-1, 1]; got {}", q.cos_critical_rad));
        }
        if !q.max_line_fit_mse.is_finite() || q.max_line_fit_mse <= 0.0 {
            return bad(format!("quad.max_line_fit_mse must be positive, got {}", q.max_line_fit_mse));
        }
        if let Some(r) = self.roi
            && (r.width == 0 || r.height == 0)
        {
            return bad(format!("roi must not be empty, got {}×{}", r.width, r.height));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_settings_named() {
        assert!(DetectorConfig::default().validate().is_ok());
        let d = DetectorConfig::default();
        let cases: Vec<(DetectorConfig, &str)> = vec![
            (DetectorConfig { quad_decimate: 2.5, ..d }, "quad_decimate"),
            (DetectorConfig { quad_sigma: f32::NAN, ..d }, "quad_sigma"),
            (DetectorConfig { nthreads: 0, ..d }, "nthreads"),
            (DetectorConfig { decode_sharpening: -1.0, ..d }, "decode_sharpening"),
            (DetectorConfig { max_hamming: 3, ..d }, "max_hamming 3 is refused"),
            (DetectorConfig { quad: QuadThreshold { cos_critical_rad: 2.0, ..d.quad }, ..d }, "cos_critical_rad"),
            (DetectorConfig { quad: QuadThreshold { max_line_fit_mse: 0.0, ..d.quad }, ..d }, "max_line_fit_mse"),
            (DetectorConfig { roi: Some(Roi { x: 0, y: 0, width: 0, height: 5 }), ..d }, "roi"),
        ];
        for (c, word) in cases {
            let e = c.validate().expect_err(word).to_string();
            assert!(e.contains(word), "{e}");
        }
        // The cosine, not the angle, as the C library expects.
        assert!((d.quad.cos_critical_rad - 0.984_807_7).abs() < 1e-6);
    }
}
