//! The tone part of `jawtrack-bench accuracy`: the static grid at 100 mm (0/30/60°, tripod
//! and hand) developed as phones develop video — power laws of 1.6–2.8, an S-curve, an unsharp
//! mask, a local tone map — and tracked three ways: as a new user would (`jawtrack track`'s
//! defaults: the curve estimated from the tags), told the true curve, and read as sRGB (what
//! the detector assumed before it estimated). Per development: the jaw's error (the mandible in
//! the maxilla's frame, mm) and the tags' corner error (px), with the curve estimated beside
//! the true one. Tracked with the marker as printed, so the optics and the curve are all that
//! is wrong. Then the same grid through a phone's own optics ([`phone_cases`]): in focus, and
//! nearer than the lens focuses, where the blur is widest and a wrong curve moves edges most.

use super::{Options, read_luma};
use crate::chew::PoseError;
use crate::frames::{self, Development, Phone, Request};
use anyhow::{Context, Result};
use clap::Args;
use jawtrack_apriltag::tone::{REFIT_EVERY_FRAMES, SETTLING_FRAMES};
use jawtrack_apriltag::{Detector, DetectorConfig, ToneSetting};
use jawtrack_marker::Marker;
use jawtrack_synth::realism::Sharpen;
use jawtrack_synth::{Resolution, SceneKind};
use jawtrack_tone::ToneCurve;
use jawtrack_tracker::{Tracker, TrackerConfig};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The distance of the grid (mm): the rig's middle distance.
pub const DISTANCE_MM: f64 = 100.0;

/// The tone flags of `jawtrack-bench accuracy`.
#[derive(Args, Debug, Clone)]
pub struct ToneArgs {
    /// Frames per static view of the tone section (6 views, at 100 mm and through a phone).
    #[arg(long, default_value_t = 2)]
    pub tone_frames_per_view: usize,
    /// Leave the tone section out.
    #[arg(long)]
    pub no_tone: bool,
}

/// How the tracker reads the frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reading {
    /// The default: the curve estimated from the tags.
    Auto,
    /// Told the curve the frames were encoded with (their global curve).
    True,
    /// As sRGB, whatever the frames are.
    Srgb,
}

impl Reading {
    /// All three, in the tables' order.
    pub const ALL: [Reading; 3] = [Reading::Auto, Reading::True, Reading::Srgb];

    /// Its name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Reading::Auto => "estimated (default)",
            Reading::True => "true curve given",
            Reading::Srgb => "read as sRGB",
        }
    }

    fn setting(self, development: &Development) -> ToneSetting {
        match self {
            Reading::Auto => ToneSetting::Auto,
            Reading::True => ToneSetting::Fixed(development.curve),
            Reading::Srgb => ToneSetting::Fixed(ToneCurve::Srgb),
        }
    }
}

/// The developments rendered: sRGB (every fixture's), the power laws and the S-curve of the
/// issue's targets, and sharpening (amount 1, radius 1 px) and a local tone map on a phone-like
/// gamma.
pub fn developments() -> Vec<Development> {
    let plain = |curve| Development { curve, sharpen: None, local_tone_map: 0.0 };
    let gamma = |g| plain(ToneCurve::Gamma { gamma: g });
    vec![
        plain(ToneCurve::Srgb),
        gamma(1.6),
        gamma(1.8),
        gamma(2.2),
        gamma(2.6),
        gamma(2.8),
        plain(ToneCurve::SCurve { gamma: 2.2, contrast: 0.5 }),
        Development { sharpen: Some(Sharpen { amount: 1.0, radius_px: 1.0 }), ..gamma(1.8) },
        Development { local_tone_map: 0.5, ..gamma(1.8) },
    ]
}

/// Where a phone's wide camera (2× native crop, 1080p) films the grid through its own optics,
/// focus locked at the nearest it reaches: nearer than it focuses, and in focus.
pub const PHONE_DISTANCES_MM: [f64; 2] = [170.0, 220.0];
/// Where its lens is locked (mm).
pub const PHONE_FOCUS_MM: f64 = 200.0;

/// The phone's cases: each distance with sRGB and a flat and a steep phone curve.
pub fn phone_cases() -> Vec<(Phone, Development)> {
    let plain = |curve| Development { curve, sharpen: None, local_tone_map: 0.0 };
    let curves = [ToneCurve::Srgb, ToneCurve::Gamma { gamma: 1.8 }, ToneCurve::Gamma { gamma: 2.6 }];
    PHONE_DISTANCES_MM
        .iter()
        .flat_map(|&distance_mm| {
            let phone = Phone { resolution: Resolution::P1080, zoom: 2.0, distance_mm, focus_mm: PHONE_FOCUS_MM };
            curves.map(|c| (phone, plain(c)))
        })
        .collect()
}

/// One development tracked one way.
#[derive(Debug, Clone)]
pub struct ToneResult {
    /// Filmed through a phone's optics ([`phone_cases`]), else the default realism's lens at
    /// [`DISTANCE_MM`].
    pub phone: Option<Phone>,
    /// How the frames were developed.
    pub development: Development,
    /// How they were read.
    pub reading: Reading,
    /// Frames rendered.
    pub frames: usize,
    /// The jaw's error in each frame that gave a jaw pose.
    pub errors: Vec<PoseError>,
    /// Every corner's error (px) of every tag the renderer says should be found and was.
    pub corner_px: Vec<f64>,
    /// The curve the tracker read the last frame through, and how it was found.
    pub curve: String,
    /// Each frame's detection time (s) by the corner detector…
    pub detect_s: Vec<f64>,
    /// … and (read as sRGB) the time of a tone fit of its tags.
    pub fit_s: Vec<f64>,
}

impl ToneResult {
    /// Mean and largest jaw position error (mm).
    pub fn jaw_mm(&self) -> Option<(f64, f64)> {
        let n = self.errors.len();
        (n > 0).then(|| {
            let mean = self.errors.iter().map(|e| e.mm).sum::<f64>() / n as f64;
            (mean, self.errors.iter().map(|e| e.mm).fold(0.0, f64::max))
        })
    }

    /// Median corner error (px).
    pub fn median_corner_px(&self) -> Option<f64> {
        let mut v = self.corner_px.clone();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    }
}

/// Renders (or reads from the cache) each development and tracks it each way.
pub fn run(
    options: &Options,
    args: &ToneArgs,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Vec<ToneResult>> {
    let mut results = Vec::new();
    let cases =
        developments().into_iter().map(|d| (None, d)).chain(phone_cases().into_iter().map(|(p, d)| (Some(p), d)));
    for (phone, development) in cases {
        let req = Request {
            max_frames: options.max_frames,
            distance_mm: phone.is_none().then_some(DISTANCE_MM),
            phone,
            development: Some(development),
            ..Request::new(SceneKind::Static, options.seed, args.tone_frames_per_view.max(1), 1, 30.0)
        };
        let stage = format!("tone, {}{}: rendering", development.name(), phone.map_or(String::new(), |p| at(&p)));
        let scene = frames::scene(&options.cache, &req, &mut |done, total| progress(&stage, done, total))?;
        let truth = &scene.truth;
        let printed = Marker::from_json(&truth.true_marker.to_string())
            .context("tone: the marker as printed in ground_truth.json")?;
        for reading in Reading::ALL {
            let detector = DetectorConfig { tone: reading.setting(&development), ..DetectorConfig::default() };
            let mut tracker = Tracker::new(printed.clone(), TrackerConfig { detector, ..TrackerConfig::default() })?;
            let corners = Detector::new(detector)?;
            let stage = format!(
                "tone, {}{}, {}: tracking",
                development.name(),
                phone.map_or(String::new(), |p| at(&p)),
                reading.name()
            );
            let mut result = ToneResult {
                phone,
                development,
                reading,
                frames: truth.frames.len(),
                errors: Vec::new(),
                corner_px: Vec::new(),
                curve: String::new(),
                detect_s: Vec::new(),
                fit_s: Vec::new(),
            };
            for (i, f) in truth.frames.iter().enumerate() {
                progress(&stage, i, truth.frames.len());
                let path = scene.dir.join(&f.file);
                let img = read_luma(&path)?;
                let view = img.view()?;
                let r = tracker
                    .track(&view, &truth.intrinsics, f.t)
                    .with_context(|| format!("tracking {}", path.display()))?;
                result.errors.extend(r.maxilla_from_mandible.map(|p| PoseError::of(&p, &f.maxilla_from_mandible)));
                let started = Instant::now();
                let dets = corners.detect(&view)?;
                result.detect_s.push(started.elapsed().as_secs_f64());
                if reading == Reading::Srgb {
                    let started = Instant::now();
                    corners.fit_tone(&view, &dets);
                    result.fit_s.push(started.elapsed().as_secs_f64());
                }
                for d in dets {
                    if let Some(t) = f.tags.iter().find(|t| t.id == d.id && t.should_be_detected()) {
                        result
                            .corner_px
                            .extend(d.corners.iter().zip(&t.corners).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])));
                    }
                }
            }
            progress(&stage, truth.frames.len(), truth.frames.len());
            result.curve = describe(&tracker);
            results.push(result);
        }
    }
    Ok(results)
}

/// The curve a tracker reads through, and how it was found.
fn describe(tracker: &Tracker) -> String {
    jawtrack_tracker::tone_record(&tracker.tone()).describe()
}

/// The tone section of the report: per development, each reading's jaw and corner errors.
pub fn markdown(results: &[ToneResult], frames_per_view: usize) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "\n## Tone curves: the static grid at {DISTANCE_MM} mm as phones develop it\n");
    let _ = writeln!(
        s,
        "The static grid at {DISTANCE_MM} mm (0/30/60°, tripod and hand, {frames_per_view} frame(s) per view; the default \
         realism otherwise), encoded through each curve before 8-bit rounding; sharpening is an unsharp mask on the \
         encoded values, the local tone map a scene-dependent gain in linear light. Tracked with the marker as \
         printed, one tracker over all the frames as `jawtrack track` runs. Jaw: the mandible's position in the \
         maxilla's frame against the truth, over the frames with a jaw pose. Corners: every corner of every tag that \
         should be found, from a detector read the same way.\n"
    );
    let grid: Vec<&ToneResult> = results.iter().filter(|r| r.phone.is_none()).collect();
    let phone: Vec<&ToneResult> = results.iter().filter(|r| r.phone.is_some()).collect();
    table(&mut s, &grid);
    if !phone.is_empty() {
        let _ = writeln!(
            s,
            "\n### Through a phone's optics\n\nThe same grid filmed by a Pro iPhone's wide camera (6.8 mm f/1.78: a disc \
             pupil, focus breathing, the lens's own blur), its 2× native crop at 1080p, the focus locked at \
             {PHONE_FOCUS_MM} mm, the nearest it reaches: from nearer than that, and from where it is in focus. A \
             frame whose bodies the tracker flags `defocused` gives no jaw pose.\n"
        );
        table(&mut s, &phone);
    }
    let grid: Vec<ToneResult> = grid.into_iter().cloned().collect();
    let (detect, fit, share) = cost(&grid, TAKE_FRAMES);
    let (_, _, short) = cost(&grid, 300);
    let _ = writeln!(
        s,
        "\nCost: a frame's detection (read as sRGB) takes {:.1} ms (median), a tone fit of its tags {:.1} ms. With \
         {SETTLING_FRAMES} fits while the estimate settles and one every {REFIT_EVERY_FRAMES} frames after (and a \
         detection again for each of two changes of curve), a 30 s take at 60 fps ({TAKE_FRAMES} frames) spends \
         {:.1} % more time detecting; a 300-frame one {:.1} %.",
        detect * 1e3,
        fit * 1e3,
        100.0 * share,
        100.0 * short
    );
    s
}

/// Where a phone films from, for tables: ` at 170 mm (focus 200 mm)`.
fn at(p: &Phone) -> String {
    format!(" at {} mm (focus {} mm)", p.distance_mm, p.focus_mm)
}

/// One table of results, a row per development and reading.
fn table(s: &mut String, results: &[&ToneResult]) {
    let _ = writeln!(s, "| development | read | jaw poses | jaw mean | jaw max | median corner | curve read through |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for r in results {
        let (mean, max) =
            r.jaw_mm().map_or(("–".into(), "–".into()), |(m, x)| (format!("{m:.3} mm"), format!("{x:.3} mm")));
        let corner = r.median_corner_px().map_or("–".into(), |c| format!("{c:.3} px"));
        let _ = writeln!(
            s,
            "| {}{} | {} | {}/{} | {mean} | {max} | {corner} | {} |",
            r.development.name(),
            r.phone.map_or(String::new(), |p| at(&p)),
            r.reading.name(),
            r.errors.len(),
            r.frames,
            r.curve
        );
    }
}

/// A 30 s take at 60 frames/s.
pub const TAKE_FRAMES: usize = 1800;

/// The median of `v` (0 for none).
fn median(v: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = v.collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// What estimating the curve costs: the median detection of a frame read as sRGB and of a
/// tone fit, and the share a take of `frames` frames spends on fits ([`SETTLING_FRAMES`]
/// fits, then one every [`REFIT_EVERY_FRAMES`]; a fit that changes the curve adds a
/// detection, counted too).
pub fn cost(results: &[ToneResult], frames: usize) -> (f64, f64, f64) {
    let read_as_srgb = || results.iter().filter(|r| r.reading == Reading::Srgb);
    let detect = median(read_as_srgb().flat_map(|r| r.detect_s.iter().copied()));
    let fit = median(read_as_srgb().flat_map(|r| r.fit_s.iter().copied()));
    let fits = SETTLING_FRAMES + frames / REFIT_EVERY_FRAMES;
    let extra = fits as f64 * fit + 2.0 * detect;
    (detect, fit, extra / (frames as f64 * detect))
}

/// The table as CSV, one row per development and reading.
pub fn write_csv(results: &[ToneResult], out: &Path) -> Result<PathBuf> {
    let path = out.join("tone.csv");
    let mut text =
        String::from("development,phone_at_mm,read,frames,jaw_poses,jaw_mean_mm,jaw_max_mm,median_corner_px,curve\n");
    for r in results {
        let (mean, max) =
            r.jaw_mm().map_or((String::new(), String::new()), |(m, x)| (format!("{m:.4}"), format!("{x:.4}")));
        let _ = writeln!(
            text,
            "{},{},{},{},{},{mean},{max},{},\"{}\"",
            r.development.name(),
            r.phone.map_or(String::new(), |p| p.distance_mm.to_string()),
            r.reading.name(),
            r.frames,
            r.errors.len(),
            r.median_corner_px().map_or(String::new(), |c| format!("{c:.4}")),
            r.curve.replace('"', "'")
        );
    }
    std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn developments_are_named_for_their_folders_and_tables() {
        let names: Vec<String> = developments().iter().map(Development::name).collect();
        assert_eq!(names.len(), 9);
        assert!(
            names.contains(&"gamma:1.8+sharpen 1/1 px".to_owned()) && names.contains(&"s-curve:2.2:0.5".to_owned())
        );
        let mut unique = names.clone();
        unique.dedup();
        assert_eq!(unique, names, "each development its own folder");
    }

    #[test]
    fn the_phone_films_each_curve_from_each_distance_into_its_own_folder() {
        let cases = phone_cases();
        assert_eq!(cases.len(), PHONE_DISTANCES_MM.len() * 3);
        let folders: std::collections::BTreeSet<String> = cases
            .iter()
            .map(|&(phone, development)| {
                let req = Request {
                    phone: Some(phone),
                    development: Some(development),
                    ..Request::new(SceneKind::Static, 1, 2, 1, 30.0)
                };
                req.folder()
            })
            .collect();
        assert_eq!(folders.len(), cases.len(), "{folders:?}");
        assert!(cases.iter().all(|(p, _)| p.focus_mm == PHONE_FOCUS_MM && p.zoom == 2.0));
    }

    #[test]
    fn the_cost_counts_the_settling_fits_the_refits_and_two_detections_again() {
        let result = |reading, detect_s: f64, fit_s: Vec<f64>| ToneResult {
            phone: None,
            development: developments()[0],
            reading,
            frames: 3,
            errors: Vec::new(),
            corner_px: Vec::new(),
            curve: String::new(),
            detect_s: vec![detect_s; 3],
            fit_s,
        };
        // 10 ms detections and 60 ms fits: over 1 200 frames, 3 + 10 fits and two detections.
        let results = [result(Reading::Srgb, 0.010, vec![0.060; 3]), result(Reading::Auto, 0.5, Vec::new())];
        let (detect, fit, share) = cost(&results, 1200);
        assert_eq!((detect, fit), (0.010, 0.060));
        let want = (f64::from(SETTLING_FRAMES as u32 + 10) * 0.060 + 0.020) / 12.0;
        assert!((share - want).abs() < 1e-12, "{share} against {want}");
    }
}
