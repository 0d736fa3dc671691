//! `jawtrack detect`: runs the tag36h11 detector on image files and prints one JSON line per
//! image, in JawTrack's pixel convention (centre of the top-left pixel at (0, 0)).

use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_apriltag::{Detector, DetectorConfig, QuadThreshold};
use std::path::PathBuf;

/// Arguments of `jawtrack detect`.
#[derive(Args)]
pub(crate) struct DetectArgs {
    /// Decimation for quad finding: 1, 1.5, 2, 3 or 4.
    #[arg(long, default_value_t = 2.0)]
    decimate: f32,
    /// Gaussian blur σ before quad finding (px, up to 4); negative sharpens. Helps on noisy
    /// frames, loses the smallest tags.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    sigma: f32,
    /// Bit errors corrected, 0–2.
    #[arg(long, default_value_t = 2)]
    max_hamming: u32,
    /// Worker threads.
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Smallest contrast (grey levels) around a pixel for quad finding; the C library's
    /// default is 5, which makes noisy frames several times slower.
    #[arg(long, default_value_t = QuadThreshold::default().min_white_black_diff)]
    min_white_black_diff: u8,
    /// Refine edges at full resolution.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    refine_edges: bool,
    #[command(flatten)]
    edges: crate::flags::EdgeArgs,
    /// Run each image this many times and report the median time.
    #[arg(long, default_value_t = 1)]
    repeat: usize,
    /// Images (PNG or JPEG; colour is converted to gray).
    #[arg(required = true)]
    images: Vec<PathBuf>,
}

pub(crate) fn run(a: &DetectArgs) -> Result<()> {
    if a.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    let detector = Detector::new(DetectorConfig {
        quad_decimate: a.decimate,
        quad_sigma: a.sigma,
        nthreads: a.threads,
        refine_edges: a.refine_edges,
        linear_edges: a.edges.linear_edges,
        tone: a.edges.tone,
        max_hamming: a.max_hamming,
        quad: QuadThreshold { min_white_black_diff: a.min_white_black_diff, ..QuadThreshold::default() },
        ..DetectorConfig::default()
    })?;
    for path in &a.images {
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        let img =
            jawtrack_frames::decode_image(&bytes).map_err(|e| anyhow::anyhow!("reading {}: {e}", path.display()))?;
        let (w, h) = (img.width, img.height);
        let view = img.view().with_context(|| format!("{}", path.display()))?;
        let mut times = Vec::with_capacity(a.repeat);
        let mut dets = Vec::new();
        for _ in 0..a.repeat {
            let t = std::time::Instant::now();
            dets = detector.detect(&view)?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        times.sort_by(f64::total_cmp);
        let line = serde_json::json!({
            "path": path.display().to_string(),
            "width": w,
            "height": h,
            "detect_ms": times[times.len() / 2],
            "detections": dets.iter().map(|d| serde_json::json!({
                "id": d.id,
                "hamming": d.hamming,
                "margin": d.decision_margin,
                "center": d.center,
                "corners": d.corners,
            })).collect::<Vec<_>>(),
        });
        say!("{line}");
    }
    Ok(())
}
