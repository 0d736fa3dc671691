//! The rendered frames of each scene, cached under `<cache>/<scene>-<seed>/` and re-rendered
//! only when the cached ground truth does not describe the frames asked for (a longer cached
//! session whose first frames are the ones asked for serves).

use anyhow::{Context, Result};
use jawtrack_marker::Marker;
use jawtrack_synth::realism::Sharpen;
use jawtrack_synth::scenes::{FrameSpec, scene_frames};
use jawtrack_synth::{
    GroundTruth, Orientation, Realism, Resolution, SceneKind, SceneOptions, SynthConfig, Synthesizer,
};
use jawtrack_tone::ToneCurve;
use std::path::{Path, PathBuf};

/// A phone's camera filming from where it can focus ([`Realism::phone_wide`]): its format,
/// zoom, distance and where its lens is focused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phone {
    /// The frame size.
    pub resolution: Resolution,
    /// 1, or the sensor's native 2× crop.
    pub zoom: f64,
    /// Where the phone stands (mm from the markers).
    pub distance_mm: f64,
    /// Where its lens is locked (mm).
    pub focus_mm: f64,
}

/// How frames are developed when not as the default realism does (sRGB, no sharpening, no
/// local tone map): a phone's own tone curve and sharpening.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Development {
    /// The tone curve.
    pub curve: ToneCurve,
    /// The unsharp mask on the encoded values.
    pub sharpen: Option<Sharpen>,
    /// The strength of the scene-dependent local tone map (0: none).
    pub local_tone_map: f64,
}

impl Development {
    /// Its name in tables and folders: the curve, then `+sharpen A/R`, `+local T`.
    pub fn name(&self) -> String {
        let mut name = self.curve.to_string();
        if let Some(s) = self.sharpen {
            name += &format!("+sharpen {}/{} px", s.amount, s.radius_px);
        }
        if self.local_tone_map > 0.0 {
            name += &format!("+local {}", self.local_tone_map);
        }
        name
    }
}

/// What to render: one scene at 1080p, default realism (but for the exposure and shutter
/// asked for), the nominal marker; or with a phone's optics.
#[derive(Debug, Clone, Copy)]
pub struct Request {
    /// The scene.
    pub scene: SceneKind,
    /// Seed of everything random.
    pub seed: u64,
    /// Frames per camera view (static).
    pub frames_per_view: usize,
    /// Cycles per opening or glide (hinge, excursion, chew).
    pub cycles: usize,
    /// Frame rate of the dynamic scenes (frames/s).
    pub fps: f64,
    /// Keep at most this many frames.
    pub max_frames: Option<usize>,
    /// The exposure (s); `None` keeps the default realism's.
    pub exposure_s: Option<f64>,
    /// The rolling shutter's readout (s); 0 = a global shutter, as by default.
    pub readout_s: f64,
    /// How the phone is held (the chew scene's choice).
    pub orientation: Orientation,
    /// A phone's optics instead of the default realism's lens, and its distance.
    pub phone: Option<Phone>,
    /// The static grid at this one distance (mm), with the default realism's lens.
    pub distance_mm: Option<f64>,
    /// Developed otherwise than sRGB.
    pub development: Option<Development>,
}

impl Request {
    /// A scene with the default realism, global shutter, phone upright.
    pub fn new(scene: SceneKind, seed: u64, frames_per_view: usize, cycles: usize, fps: f64) -> Self {
        Request {
            scene,
            seed,
            frames_per_view,
            cycles,
            fps,
            max_frames: None,
            exposure_s: None,
            readout_s: 0.0,
            orientation: Orientation::Upright,
            phone: None,
            distance_mm: None,
            development: None,
        }
    }

    /// The cache folder's name: the scene and seed, and what departs from the defaults.
    pub(crate) fn folder(&self) -> String {
        let mut name = format!("{}-{}", self.scene.name(), self.seed);
        if let Some(e) = self.exposure_s {
            name += &format!("-exposure{}ms", e * 1000.0);
        }
        if self.readout_s > 0.0 {
            name += &format!("-readout{}ms", self.readout_s * 1000.0);
        }
        if self.orientation == Orientation::Landscape {
            name += "-landscape";
        }
        if let Some(p) = self.phone {
            let size = match p.resolution {
                Resolution::P1080 => "1080p",
                Resolution::P4k => "4k",
            };
            name += &format!("-phone-{size}-{}x-at{}mm-focus{}mm", p.zoom, p.distance_mm, p.focus_mm);
        }
        if let Some(d) = self.distance_mm {
            name += &format!("-at{d}mm");
        }
        if let Some(d) = self.development {
            let safe: String =
                d.name().chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' { c } else { '_' }).collect();
            name += &format!("-tone-{safe}");
        }
        name
    }

    fn config(&self) -> SynthConfig {
        let realism = match self.phone {
            // A 4K frame's pixel covers a quarter of the sensor a 1080p pixel does, and gathers a
            // quarter of its light (the zoom's crop is the realism's own).
            Some(p) => {
                let r = Realism::phone_wide(p.focus_mm, p.zoom);
                let (w, _) = p.resolution.size();
                Realism { full_well_e: r.full_well_e * (1920.0 / f64::from(w)).powi(2), ..r }
            }
            None => Realism::default(),
        };
        SynthConfig {
            seed: self.seed,
            resolution: self.phone.map_or(Resolution::P1080, |p| p.resolution),
            realism: Realism {
                exposure_s: self.exposure_s.unwrap_or(realism.exposure_s),
                readout_s: self.readout_s,
                tone: self.development.map_or(realism.tone, |d| d.curve),
                sharpen: self.development.map_or(realism.sharpen, |d| d.sharpen),
                local_tone_map: self.development.map_or(realism.local_tone_map, |d| d.local_tone_map),
                ..realism
            },
            options: SceneOptions {
                frames_per_view: self.frames_per_view,
                cycles: self.cycles,
                fps: self.fps,
                orientation: self.orientation,
                distance_mm: self.phone.map(|p| p.distance_mm).or(self.distance_mm),
            },
            marker: Marker::default(),
            max_frames: self.max_frames,
            ..SynthConfig::new(self.scene)
        }
    }

    /// The frames the renderer will make, as it lists them.
    fn specs(&self) -> Vec<FrameSpec> {
        let c = self.config();
        let mut specs = scene_frames(c.scene, &c.options, c.seed);
        if let Some(n) = c.max_frames {
            specs.truncate(n);
        }
        specs
    }
}

/// A scene's frames on disk and their truth.
pub struct Scene {
    /// Folder of the frames and `ground_truth.json`.
    pub dir: PathBuf,
    /// The truth, limited to the frames asked for.
    pub truth: GroundTruth,
    /// Whether they were rendered in this run (else read from the cache).
    pub rendered: bool,
}

/// The cached truth if it holds the frames asked for (as its first frames), with the same
/// settings, and every image is present.
fn cached(dir: &Path, req: &Request) -> Option<GroundTruth> {
    let text = std::fs::read_to_string(dir.join("ground_truth.json")).ok()?;
    let mut truth: GroundTruth = serde_json::from_str(&text).ok()?;
    let config = req.config();
    let specs = req.specs();
    let (w, h) = config.resolution.size();
    // The frames' intrinsics (zoomed, breathing) as the renderer makes them.
    let intrinsics = Synthesizer::new(config.clone()).ok()?.header().intrinsics;
    let same = truth.scene == config.scene.name()
        && truth.seed == config.seed
        && truth.realism == config.realism
        && truth.image_size == [w, h]
        && truth.intrinsics == intrinsics
        && truth.frames.len() >= specs.len()
        && truth.frames.iter().zip(&specs).all(|(f, s)| f.spec == *s);
    if !same {
        return None;
    }
    truth.frames.truncate(specs.len());
    truth.frames.iter().all(|f| dir.join(&f.file).is_file()).then_some(truth)
}

/// The scene's frames from `cache_root`, rendering them first when the cache lacks them;
/// `progress(done, total)` is called as frames are rendered (not at all when cached).
pub fn scene(cache_root: &Path, req: &Request, progress: &mut dyn FnMut(usize, usize)) -> Result<Scene> {
    let name = req.scene.name();
    let dir = cache_root.join(req.folder());
    if let Some(truth) = cached(&dir, req) {
        return Ok(Scene { dir, truth, rendered: false });
    }
    // A stale truth must not outlive an interrupted render: the renderer writes it last.
    let stale = dir.join("ground_truth.json");
    if stale.exists() {
        std::fs::remove_file(&stale).with_context(|| format!("removing {}", stale.display()))?;
    }
    progress(0, req.specs().len());
    jawtrack_synth::write_scene(req.config(), &dir, progress)
        .with_context(|| format!("rendering {name} into {}", dir.display()))?;
    let truth =
        cached(&dir, req).with_context(|| format!("{}: the rendered frames do not read back", dir.display()))?;
    Ok(Scene { dir, truth, rendered: true })
}
