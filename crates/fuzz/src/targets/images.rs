//! What the detector is handed: image files as `detect`, `track` and the calibrations decode
//! them (`jawtrack_frames::decode_image`), and raw luma planes of any size and stride as the
//! phone passes them. A detection must be a tag of the family within the detector's Hamming
//! limit, with finite corners, centre, homography and margins.

use crate::run::Verdict;
use crate::targets::files::refused;
use jawtrack_apriltag::{Detection, Detector, DetectorConfig, ImageView, QuadThreshold};
use std::sync::OnceLock;

/// The detectors tried, built once (a Hamming-2 table takes longer than many detections):
/// ours at its defaults, at C's, and two corners of the settings (fine and blurred with no
/// Hamming tolerance and a low contrast threshold; coarse and sharpened on two threads).
fn detectors() -> &'static [Detector] {
    static D: OnceLock<Vec<Detector>> = OnceLock::new();
    D.get_or_init(|| {
        let fine = DetectorConfig {
            quad_decimate: 1.0,
            quad_sigma: 0.8,
            max_hamming: 0,
            smeared_edges: true,
            quad: QuadThreshold { min_white_black_diff: 5, ..QuadThreshold::default() },
            ..DetectorConfig::default()
        };
        let coarse = DetectorConfig { quad_decimate: 3.0, quad_sigma: -1.2, nthreads: 2, ..DetectorConfig::default() };
        [DetectorConfig::default(), DetectorConfig::reference(), fine, coarse]
            .into_iter()
            .filter_map(|c| Detector::new(c).ok())
            .collect()
    })
}

/// Windows of the fixture frames around their tags (the detector's own finds place them).
fn crops() -> Vec<image::GrayImage> {
    let dir = crate::targets::fixtures();
    let mut out = Vec::new();
    for (set, size) in [("static-1080p/frame_0000.png", 320), ("hinge-1080p/frame_0002.png", 200)] {
        let Ok(bytes) = std::fs::read(dir.join(set)) else { continue };
        let Ok(luma) = jawtrack_frames::decode_image(&bytes) else { continue };
        let Some(detector) = detectors().first() else { continue };
        let Ok(view) = luma.view() else { continue };
        let Some(c) = detector.detect(&view).ok().and_then(|d| d.first().map(|d| d.center)) else { continue };
        let Some(img) = image::GrayImage::from_raw(luma.width as u32, luma.height as u32, luma.pixels) else {
            continue;
        };
        let x = (c[0] as u32).saturating_sub(size / 2).min(img.width().saturating_sub(size));
        let y = (c[1] as u32).saturating_sub(size / 2).min(img.height().saturating_sub(size));
        out.push(image::imageops::crop_imm(&img, x, y, size, size).to_image());
    }
    out
}

pub fn image_seeds() -> Vec<Vec<u8>> {
    let mut seeds = Vec::new();
    for img in crops() {
        for format in [image::ImageFormat::Png, image::ImageFormat::Jpeg] {
            let mut bytes = std::io::Cursor::new(Vec::new());
            if img.write_to(&mut bytes, format).is_ok() {
                seeds.push(bytes.into_inner());
            }
        }
    }
    seeds
}

pub fn image(input: &[u8]) -> Result<Verdict, String> {
    let luma = match jawtrack_frames::decode_image(input) {
        Ok(l) => l,
        Err(e) => return refused(e),
    };
    // A small file may claim a frame of up to 8192² px, which decodes in a fraction of a second
    // but takes the detectors longer than a hang's limit: that is their speed, not a hang, and
    // `frame` fuzzes the detectors on the pixels. Frames up to 4 MP (twice 1080p) are detected here.
    if luma.pixels.len() > 1 << 22 {
        return Ok(Verdict::Accepted);
    }
    let view = match luma.view() {
        Ok(v) => v,
        Err(e) => return refused(e),
    };
    let which = input.iter().fold(0usize, |a, &b| a.wrapping_add(b as usize));
    detect(which, &view)
}

/// A frame's layout ahead of its pixels: width and height (u16, little-endian), bytes of
/// padding per row, and which detector.
const LAYOUT: usize = 6;

pub fn frame_seeds() -> Vec<Vec<u8>> {
    crops()
        .into_iter()
        .enumerate()
        .map(|(k, img)| {
            let (w, h) = (img.width() as u16, img.height() as u16);
            let mut seed = [w.to_le_bytes(), h.to_le_bytes()].concat();
            seed.extend([0, k as u8]);
            seed.extend(img.into_raw());
            seed
        })
        .collect()
}

pub fn frame(input: &[u8]) -> Result<Verdict, String> {
    let Some((head, pixels)) = input.split_first_chunk::<LAYOUT>() else { return Ok(Verdict::Refused) };
    let width = usize::from(u16::from_le_bytes([head[0], head[1]]));
    let height = usize::from(u16::from_le_bytes([head[2], head[3]]));
    // Unchecked on purpose: a stride or size the buffer cannot hold must be refused by `new`.
    let stride = width + usize::from(head[4] % 16);
    let view = match ImageView::new(pixels, width, height, stride) {
        Ok(v) => v,
        Err(e) => return refused(e),
    };
    detect(usize::from(head[5]), &view)
}

fn detect(which: usize, view: &ImageView<'_>) -> Result<Verdict, String> {
    let detectors = detectors();
    let detector = &detectors[which % detectors.len()];
    match detector.detect(view) {
        Ok(found) => found.iter().try_for_each(|d| sound(detector, d)).map(|()| Verdict::Accepted),
        Err(e) => refused(e),
    }
}

/// A detection's promises.
fn sound(detector: &Detector, d: &Detection) -> Result<(), String> {
    let config = detector.config();
    if d.id as usize >= config.family.count() {
        return Err(format!("tag id {} is not in the family ({} codes)", d.id, config.family.count()));
    }
    if d.hamming > config.max_hamming {
        return Err(format!("tag {} decoded with {} bits wrong (limit {})", d.id, d.hamming, config.max_hamming));
    }
    let finite = d.corners.iter().flatten().chain(&d.center).chain(&d.homography).all(|v| v.is_finite())
        && d.decision_margin.is_finite()
        && d.blur_px.is_none_or(|b| b.is_finite() && b >= 0.0);
    if !finite {
        return Err(format!("tag {} has a value that is not finite: {d:?}", d.id));
    }
    Ok(())
}
