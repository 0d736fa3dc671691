//! The chewing part of `jawtrack-bench accuracy`: the chew scene (60 fps) rendered under each
//! exposure and rolling-shutter readout asked for, and on the same frames our tracker told the
//! readout, ours told nothing of it, and the reference stack when it runs, each with the marker
//! as printed (the exact geometry, so that only the motion is wrong), against the truth at each
//! frame's time (its centre row's).

use super::{Options, ReferenceStack, read_luma};
use crate::chew::{ChewFrame, ChewScene, PoseError, Shutter};
use crate::frames::{self, Request};
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_apriltag::DetectorConfig;
use jawtrack_marker::Marker;
use jawtrack_synth::{Orientation, SceneKind};
use jawtrack_tracker::{Tracker, TrackerConfig};

/// What to render the chew scene with.
#[derive(Debug, Clone, PartialEq)]
pub struct ChewOptions {
    /// Exposures (s), one scene each (with each readout).
    pub exposures_s: Vec<f64>,
    /// Readouts, first row to last (s); 0 is a global shutter.
    pub readouts_s: Vec<f64>,
    /// How the phone is held.
    pub orientation: Orientation,
    /// Frame rate (frames/s).
    pub fps: f64,
}

impl ChewOptions {
    /// Refuses what cannot be rendered, naming the value.
    pub fn validate(&self) -> Result<()> {
        if let Some(e) = self.exposures_s.iter().find(|e| !(e.is_finite() && **e > 0.0 && **e < 1.0)) {
            bail!("a chew exposure must be above 0 and under 1000 ms, got {} ms", e * 1e3);
        }
        if let Some(r) = self.readouts_s.iter().find(|r| !(r.is_finite() && (0.0..1.0).contains(*r))) {
            bail!("a chew readout must be from 0 to under 1000 ms, got {} ms", r * 1e3);
        }
        if !(self.fps.is_finite() && self.fps > 0.0) {
            bail!("the chew frame rate must be a positive number of frames/s, got {}", self.fps);
        }
        Ok(())
    }
}

/// Every chew scene asked for, rendered (or read from the cache) and measured, in the order of
/// the exposures, then the readouts. `progress` gets (stage, done, total), or a message with
/// total 0.
pub fn run(
    options: &Options,
    chew: &ChewOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Vec<ChewScene>> {
    chew.validate()?;
    let (mut reference, _) = ReferenceStack::start(options, progress)?;
    let mut scenes = Vec::new();
    for &exposure_s in &chew.exposures_s {
        for &readout_s in &chew.readouts_s {
            let req = Request {
                max_frames: options.max_frames,
                exposure_s: Some(exposure_s),
                readout_s,
                orientation: chew.orientation,
                ..Request::new(SceneKind::Chew, options.seed, 1, 1, chew.fps)
            };
            let stage =
                format!("chew {:.0} ms exposure, {:.0} ms readout: rendering", exposure_s * 1e3, readout_s * 1e3);
            let scene = frames::scene(&options.cache, &req, &mut |done, total| progress(&stage, done, total))?;
            let truth = &scene.truth;
            let printed = Marker::from_json(&truth.true_marker.to_string())
                .context("chew: the marker as printed in ground_truth.json")?;
            let config = TrackerConfig {
                detector: DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() },
                readout_s,
                exposure_s,
                ..TrackerConfig::default()
            };
            let mut ours = Tracker::new(printed.clone(), config)?;
            let mut ignoring = (readout_s > 0.0)
                .then(|| Tracker::new(printed.clone(), TrackerConfig { readout_s: 0.0, ..config }))
                .transpose()?;
            let markers = [printed.clone(), printed.clone(), printed];
            let stage = stage.replace("rendering", "tracking");
            let mut frames = Vec::new();
            for (i, f) in truth.frames.iter().enumerate() {
                progress(&stage, i, truth.frames.len());
                let path = scene.dir.join(&f.file);
                let img = read_luma(&path)?;
                let view = img.view()?;
                let error =
                    |pose: Option<jawtrack_pose::Pose>| pose.map(|p| PoseError::of(&p, &f.maxilla_from_mandible));
                let tracked = |t: &mut Tracker| -> Result<_> {
                    let r = t
                        .track(&view, &truth.intrinsics, f.t)
                        .with_context(|| format!("tracking {}", path.display()))?;
                    Ok(error(r.maxilla_from_mandible))
                };
                let ours = tracked(&mut ours)?;
                let ignored = ignoring.as_mut().map(tracked).transpose()?.flatten();
                let reference = match reference.as_mut() {
                    Some(r) => error(r.frame(&img, &markers, &path, &truth.intrinsics)?[0]),
                    None => None,
                };
                frames.push(ChewFrame { speed_mm_s: f.incisor_speed_mm_s, ours, ignored, reference });
            }
            progress(&stage, truth.frames.len(), truth.frames.len());
            let orientation = match chew.orientation {
                Orientation::Upright => "upright",
                Orientation::Landscape => "landscape",
            };
            scenes.push(ChewScene { shutter: Shutter { exposure_s, readout_s, orientation }, frames });
        }
    }
    Ok(scenes)
}

/// The chew flags of `jawtrack-bench accuracy`.
#[derive(Args, Debug, Clone)]
pub struct ChewArgs {
    /// Exposures to render the chew scene with (ms, comma-separated), each with every readout.
    #[arg(long, value_delimiter = ',', default_values = ["2", "8"], value_name = "MS")]
    pub chew_exposures_ms: Vec<f64>,
    /// Rolling-shutter readouts (ms, comma-separated; 0 = a global shutter).
    #[arg(long, value_delimiter = ',', default_values = ["0", "5", "10"], value_name = "MS")]
    pub chew_readouts_ms: Vec<f64>,
    /// Hold the phone in landscape for the chew scene (rows across the face); by default it is
    /// upright, as a clinician holds it.
    #[arg(long)]
    pub chew_landscape: bool,
    /// Frame rate of the chew scene (frames/s).
    #[arg(long, default_value_t = 60.0)]
    pub chew_fps: f64,
    /// Leave the chew scene out (it renders one scene per exposure and readout, 37 frames each).
    #[arg(long)]
    pub no_chew: bool,
}

impl ChewArgs {
    /// The options, or `None` with --no-chew.
    pub fn options(&self) -> Option<ChewOptions> {
        (!self.no_chew).then(|| ChewOptions {
            exposures_s: self.chew_exposures_ms.iter().map(|ms| ms / 1e3).collect(),
            readouts_s: self.chew_readouts_ms.iter().map(|ms| ms / 1e3).collect(),
            orientation: if self.chew_landscape { Orientation::Landscape } else { Orientation::Upright },
            fps: self.chew_fps,
        })
    }
}
