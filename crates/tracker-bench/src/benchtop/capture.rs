//! The capture part of `jawtrack-bench accuracy`: the static grid and the chew scene filmed as
//! a real phone can film them, from where its lens can focus. Rendered with a Pro iPhone's
//! wide camera ([`jawtrack_synth::Realism::phone_wide`]: a 3.8 mm disc pupil, focus that
//! breathes, the lens's own blur) at 120–300 mm, in each format (1080p, its native 2× crop, 4K),
//! with the lens locked at the phone's distance (focused) or stuck at its nearest focus, 20 cm
//! (a phone held too close, or one that drifted from where focus was locked), under each
//! exposure; the plan's choice ([`jawtrack_devices::plan()`]) among them. Tracked as a user
//! would: the exact marker (so only the optics are wrong), the true intrinsics (the frames',
//! breathing included), the readout and exposure told.

use super::{Options, read_luma};
use crate::chew::PoseError;
use crate::frames::{self, Phone, Request};
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_apriltag::DetectorConfig;
use jawtrack_devices::{CameraFacts, CapturePlan, FormatFacts, Lens, PlanRequest, optics, plan};
use jawtrack_marker::Marker;
use jawtrack_synth::{Resolution, SceneKind};
use jawtrack_tracker::{Flag, Tracker, TrackerConfig};

/// The rolling-shutter readout the chew scene is rendered and tracked with (s): a 14 Pro's wide
/// camera, the slowest current Pro. The static grid, whose views are single frames (no
/// velocity to carry a rolling shutter's rows to one instant), is filmed with a global shutter,
/// as the benchtop's own static grid is.
pub const READOUT_S: f64 = 0.010;
/// The chew scene's frame rate (frames/s).
pub const CHEW_FPS: f64 = 60.0;

/// A format the phone delivers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Format {
    /// Frame size.
    pub resolution: Resolution,
    /// 1, or the native 2× crop.
    pub zoom: f64,
}

impl Format {
    /// Its name in tables and flags: `1080p`, `1080p-2x`, `4k`, `4k-2x`.
    pub fn name(&self) -> String {
        let size = match self.resolution {
            Resolution::P1080 => "1080p",
            Resolution::P4k => "4k",
        };
        if self.zoom > 1.0 { format!("{size}-{}x", self.zoom) } else { size.into() }
    }
}

impl std::str::FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (size, zoom) = match s.split_once('-') {
            Some((size, "2x")) => (size, 2.0),
            None => (s, 1.0),
            Some(_) => return Err(format!("unknown format '{s}' (1080p, 1080p-2x, 4k or 4k-2x)")),
        };
        Ok(Format { resolution: size.parse()?, zoom })
    }
}

/// Where the lens is focused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Focus {
    /// Locked at the phone's distance.
    Focused,
    /// Stuck at the lens's nearest focus (20 cm), wherever the phone is.
    Stuck,
}

/// The capture flags of `jawtrack-bench accuracy`.
#[derive(Args, Debug, Clone)]
pub struct CaptureArgs {
    /// Distances (mm, comma-separated) of the phone for the static grid; the plan's distance is
    /// added.
    #[arg(long, value_delimiter = ',', default_values = ["120", "150", "200", "250", "300"], value_name = "MM")]
    pub capture_distances_mm: Vec<f64>,
    /// Distances (mm) for the chew scene (focused from the nearest focus on, stuck before it); the
    /// plan's is added.
    #[arg(long, value_delimiter = ',', default_values = ["120", "200", "250", "300"], value_name = "MM")]
    pub capture_chew_distances_mm: Vec<f64>,
    /// Formats: 1080p, 1080p-2x (the native 2× crop), 4k, 4k-2x.
    #[arg(long, value_delimiter = ',', default_values = ["1080p", "1080p-2x", "4k"])]
    pub capture_formats: Vec<String>,
    /// Exposures (ms, comma-separated).
    #[arg(long, value_delimiter = ',', default_values = ["2", "8"], value_name = "MS")]
    pub capture_exposures_ms: Vec<f64>,
    /// Frames per static view (6 views: 0/30/60°, tripod and hand).
    #[arg(long, default_value_t = 1)]
    pub capture_frames_per_view: usize,
    /// The phone whose optics and nearest focus are rendered and planned for (its hardware
    /// identifier).
    #[arg(long, default_value = "iPhone16,1")]
    pub capture_phone: String,
    /// Leave the capture section out (a first full run renders for about two hours).
    #[arg(long)]
    pub no_capture: bool,
}

/// What to render and run.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureOptions {
    /// Static grid distances (mm), the plan's among them.
    pub static_distances_mm: Vec<f64>,
    /// Chew distances (mm), the plan's among them.
    pub chew_distances_mm: Vec<f64>,
    /// Formats.
    pub formats: Vec<Format>,
    /// Exposures (s).
    pub exposures_s: Vec<f64>,
    /// Frames per static view.
    pub frames_per_view: usize,
    /// The phone's model.
    pub phone: String,
    /// The plan for that phone.
    pub plan: CapturePlan,
    /// Only the plan's own cases (a smoke run).
    pub only_planned: bool,
}

impl CaptureArgs {
    /// The options, or `None` with --no-capture; a smoke run (`quick`) takes the plan's geometry
    /// only, at one exposure.
    pub fn options(&self, quick: bool) -> Result<Option<CaptureOptions>> {
        if self.no_capture {
            return Ok(None);
        }
        let mut formats = Vec::new();
        for f in &self.capture_formats {
            formats.push(f.parse::<Format>().map_err(anyhow::Error::msg)?);
        }
        let plan = phone_plan(&self.capture_phone)?;
        let with_plan = |d: &[f64]| {
            let mut v = d.to_vec();
            v.push(plan.distance_mm);
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        };
        let planned = Format {
            resolution: if plan.width == 3840 { Resolution::P4k } else { Resolution::P1080 },
            zoom: plan.zoom,
        };
        let o = if quick {
            CaptureOptions {
                static_distances_mm: vec![plan.distance_mm],
                chew_distances_mm: vec![plan.distance_mm],
                formats: vec![planned],
                exposures_s: vec![0.008],
                frames_per_view: 1,
                phone: self.capture_phone.clone(),
                plan,
                only_planned: true,
            }
        } else {
            if !formats.contains(&planned) {
                formats.push(planned);
            }
            CaptureOptions {
                static_distances_mm: with_plan(&self.capture_distances_mm),
                chew_distances_mm: with_plan(&self.capture_chew_distances_mm),
                formats,
                exposures_s: self.capture_exposures_ms.iter().map(|ms| ms / 1e3).collect(),
                frames_per_view: self.capture_frames_per_view,
                phone: self.capture_phone.clone(),
                plan,
                only_planned: false,
            }
        };
        o.validate()?;
        Ok(Some(o))
    }
}

impl CaptureOptions {
    /// Refuses what cannot be rendered, naming the value.
    pub fn validate(&self) -> Result<()> {
        let distances = self.static_distances_mm.iter().chain(&self.chew_distances_mm);
        if let Some(d) = distances.into_iter().find(|d| !(d.is_finite() && (60.0..=1000.0).contains(*d))) {
            bail!("a capture distance must be within 60–1000 mm, got {d}");
        }
        if let Some(e) = self.exposures_s.iter().find(|e| !(e.is_finite() && **e > 0.0 && **e < 0.1)) {
            bail!("a capture exposure must be above 0 and under 100 ms, got {} ms", e * 1e3);
        }
        if self.frames_per_view == 0 || self.formats.is_empty() || self.exposures_s.is_empty() {
            bail!("the capture section needs a format, an exposure and a frame per view");
        }
        Ok(())
    }

    /// The renders, in the order of the tables: the static grid, then the chew scene; by
    /// distance, format, focus and exposure.
    pub fn cases(&self) -> Vec<Case> {
        let mfd = self.plan.min_focus_mm;
        let mut out = Vec::new();
        for (scene, distances) in
            [(SceneKind::Static, &self.static_distances_mm), (SceneKind::Chew, &self.chew_distances_mm)]
        {
            for &distance_mm in distances {
                for &format in &self.formats {
                    // The static grid shows both at every distance (where they differ); chewing is
                    // filmed as a phone can: focused from its nearest focus on, stuck before it.
                    let focuses: Vec<Focus> = match scene {
                        SceneKind::Static if distance_mm == mfd => vec![Focus::Focused],
                        SceneKind::Static => vec![Focus::Focused, Focus::Stuck],
                        _ if distance_mm < mfd => vec![Focus::Stuck],
                        _ => vec![Focus::Focused],
                    };
                    for focus in focuses {
                        for &exposure_s in &self.exposures_s {
                            let planned = distance_mm == self.plan.distance_mm
                                && format.zoom == self.plan.zoom
                                && format.resolution.size().0 == self.plan.width
                                && focus == Focus::Focused;
                            if planned || !self.only_planned {
                                out.push(Case { scene, distance_mm, format, focus, exposure_s, planned });
                            }
                        }
                    }
                }
            }
        }
        out
    }
}

/// The plan for `model`'s wide camera filming the rig's chewing, with the renderer's formats
/// (its 1× focal lengths, the 48 MP sensors' native 2× crop).
pub fn phone_plan(model: &str) -> Result<CapturePlan> {
    let lens = optics(model, Lens::Wide);
    let format = |r: Resolution| {
        let (w, h) = r.size();
        let fx = r.default_intrinsics().fx;
        FormatFacts {
            width: w,
            height: h,
            max_fps: 60.0,
            fov_deg: 2.0 * (f64::from(w) / 2.0 / fx).atan().to_degrees(),
            native_zooms: lens.native_zooms.to_vec(),
        }
    };
    let camera = CameraFacts {
        lens: Lens::Wide,
        optics: lens,
        reported_min_focus_mm: None,
        formats: vec![format(Resolution::P1080), format(Resolution::P4k)],
    };
    let tag_mm = Marker::default().body(jawtrack_marker::BodyKind::Maxilla).map_or(0.0, |b| b.tags[0].size);
    Ok(plan(&[camera], &PlanRequest::chewing(tag_mm))?)
}

/// One render.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Case {
    /// Static grid or chewing.
    pub scene: SceneKind,
    /// Where the phone stands (mm).
    pub distance_mm: f64,
    /// Its format.
    pub format: Format,
    /// Where its lens is.
    pub focus: Focus,
    /// The exposure (s).
    pub exposure_s: f64,
    /// Whether it is the plan's choice.
    pub planned: bool,
}

/// One frame of a case.
#[derive(Debug, Clone, Copy)]
pub struct CaptureFrame {
    /// The jaw's error, when the frame gave a jaw pose.
    pub error: Option<PoseError>,
    /// Whether a body was solved and none flagged `defocused`, or one was (`Some(true)`).
    pub defocused: Option<bool>,
    /// The blurrier body's blur over its cells.
    pub blur_per_cell: Option<f64>,
    /// The lower incisor's speed (mm/s).
    pub speed_mm_s: f64,
}

/// A case and what the tracker made of it.
#[derive(Debug, Clone)]
pub struct CaseResult {
    /// The case.
    pub case: Case,
    /// The frames' focal length (px): breathing and zoom in.
    pub fx_px: f64,
    /// Its frames.
    pub frames: Vec<CaptureFrame>,
}

/// Renders (or reads from the cache) every case and tracks it.
pub fn run(
    options: &Options,
    capture: &CaptureOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Vec<CaseResult>> {
    capture.validate()?;
    let mut results = Vec::new();
    for case in capture.cases() {
        let focus_mm = match case.focus {
            Focus::Focused => case.distance_mm,
            Focus::Stuck => capture.plan.min_focus_mm,
        };
        let phone = Phone {
            resolution: case.format.resolution,
            zoom: case.format.zoom,
            distance_mm: case.distance_mm,
            focus_mm,
        };
        let (frames_per_view, fps, readout_s) = match case.scene {
            SceneKind::Static => (capture.frames_per_view, 30.0, 0.0),
            _ => (1, CHEW_FPS, READOUT_S),
        };
        let req = Request {
            max_frames: options.max_frames,
            exposure_s: Some(case.exposure_s),
            readout_s,
            phone: Some(phone),
            ..Request::new(case.scene, options.seed, frames_per_view, 1, fps)
        };
        let stage = format!(
            "capture, {} at {:.0} mm, {}, focus at {:.0} mm, {:.0} ms: rendering",
            case.scene.name(),
            case.distance_mm,
            case.format.name(),
            focus_mm,
            case.exposure_s * 1e3
        );
        let scene = frames::scene(&options.cache, &req, &mut |done, total| progress(&stage, done, total))?;
        let truth = &scene.truth;
        let printed = Marker::from_json(&truth.true_marker.to_string())
            .context("capture: the marker as printed in ground_truth.json")?;
        let config = TrackerConfig {
            detector: DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() },
            readout_s,
            exposure_s: case.exposure_s,
            ..TrackerConfig::default()
        };
        let mut tracker = Tracker::new(printed, config)?;
        let stage = stage.replace("rendering", "tracking");
        let mut frames = Vec::new();
        for (i, f) in truth.frames.iter().enumerate() {
            progress(&stage, i, truth.frames.len());
            let path = scene.dir.join(&f.file);
            let img = read_luma(&path)?;
            let r = tracker
                .track(&img.view()?, &truth.intrinsics, f.t)
                .with_context(|| format!("tracking {}", path.display()))?;
            let bodies: Vec<_> = [&r.maxilla, &r.mandible].into_iter().flatten().collect();
            frames.push(CaptureFrame {
                error: r.maxilla_from_mandible.map(|p| PoseError::of(&p, &f.maxilla_from_mandible)),
                defocused: (!bodies.is_empty()).then(|| r.flags.iter().any(|f| matches!(f, Flag::Defocused(_)))),
                blur_per_cell: bodies
                    .iter()
                    .filter_map(|b| b.blur_px.map(|blur| blur / b.cell_px))
                    .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v)))),
                speed_mm_s: f.incisor_speed_mm_s,
            });
        }
        progress(&stage, truth.frames.len(), truth.frames.len());
        results.push(CaseResult { case, fx_px: truth.intrinsics.fx, frames });
    }
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_read_and_name_themselves() {
        for name in ["1080p", "1080p-2x", "4k", "4k-2x"] {
            assert_eq!(name.parse::<Format>().expect("known").name(), name);
        }
        assert!("1080p-3x".parse::<Format>().is_err() && "720p".parse::<Format>().is_err());
    }

    #[test]
    fn a_pro_phone_is_planned_at_22_cm_with_its_2x_crop_and_the_cases_follow_it() {
        let args = CaptureArgs {
            capture_distances_mm: vec![120.0, 200.0, 300.0],
            capture_chew_distances_mm: vec![120.0, 250.0],
            capture_formats: vec!["1080p".into()],
            capture_exposures_ms: vec![2.0, 8.0],
            capture_frames_per_view: 1,
            capture_phone: "iPhone16,1".into(),
            no_capture: false,
        };
        let o = args.options(false).expect("valid").expect("on");
        assert_eq!((o.plan.distance_mm, o.plan.zoom, o.plan.width), (220.0, 2.0, 1920));
        assert_eq!(o.static_distances_mm, [120.0, 200.0, 220.0, 300.0]);
        assert_eq!(o.formats, ["1080p".parse().expect("f"), "1080p-2x".parse().expect("f")], "the plan's format added");
        let cases = o.cases();
        // Static: 4 distances × 2 formats × (2 focus states, 1 at 200 mm) × 2 exposures; chew:
        // 120 stuck, 220 and 250 focused, × 2 formats × 2 exposures.
        let count = |s| cases.iter().filter(|c| c.scene == s).count();
        assert_eq!((count(SceneKind::Static), count(SceneKind::Chew)), (28, 12));
        let planned: Vec<&Case> = cases.iter().filter(|c| c.planned).collect();
        assert_eq!(planned.len(), 4, "static and chew, both exposures");
        assert!(planned.iter().all(|c| c.distance_mm == 220.0 && c.format.zoom == 2.0 && c.focus == Focus::Focused));
        assert!(cases.iter().any(|c| c.scene == SceneKind::Chew && c.distance_mm == 120.0 && c.focus == Focus::Stuck));
        let quick = args.options(true).expect("valid").expect("on");
        assert_eq!(quick.cases().len(), 2, "the plan's geometry, static and chew, one exposure");
    }
}
