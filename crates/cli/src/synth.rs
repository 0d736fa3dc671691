//! `jawtrack synth`: renders a scene of the synthetic rig (`jawtrack_synth`) with its ground
//! truth, or measures the renderer's own edge accuracy (`--self-check`).

use anyhow::{Context, Result, bail};
use clap::Args;
use clap::builder::{PossibleValue, TypedValueParser};
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_synth::{Orientation, Realism, Resolution, SceneKind, SceneOptions, SynthConfig};
use std::ffi::OsStr;
use std::path::PathBuf;

/// Arguments of `jawtrack synth`.
#[derive(Args)]
pub(crate) struct SynthArgs {
    /// Which scene.
    #[arg(long, value_parser = SceneParser)]
    scene: Option<SceneKind>,
    /// Output folder.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Frame size: 1080p or 4k.
    #[arg(long, default_value = "1080p")]
    resolution: Resolution,
    /// Seed of everything random (print errors, noise, tremor, clutter).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Camera intrinsics fx,fy,cx,cy or fx,fy,cx,cy,k1,k2 (px); default: an iPhone wide camera.
    #[arg(long, allow_hyphen_values = true)]
    intrinsics: Option<CameraIntrinsics>,
    /// Marker file (default: the nominal 12.7 mm pair).
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Realism settings as JSON; fields left out keep their defaults.
    #[arg(long, conflicts_with = "clean")]
    realism: Option<PathBuf>,
    /// Exact geometry: no blur, noise, gamma, print error, occluders or glare.
    #[arg(long)]
    clean: bool,
    /// Exposure time (ms), overriding the realism settings' (0 = an instant, no motion blur).
    #[arg(long, value_name = "MS", allow_hyphen_values = true)]
    exposure_ms: Option<f64>,
    /// Rolling-shutter readout (ms): the time from the first to the last row of the frame,
    /// overriding the realism settings' (0 = a global shutter). Row r of H is exposed centred at t
    /// + (r − (H−1)/2)/(H−1) × readout; the truth puts each tag corner where its own row saw it.
    #[arg(long, value_name = "MS", allow_hyphen_values = true)]
    readout_ms: Option<f64>,
    /// Chew scene: the phone held in landscape, so the rows run across the face and the
    /// readout reaches the lower marker about half a readout after the upper one (default:
    /// upright, both markers in the same rows).
    #[arg(long)]
    landscape: bool,
    /// A Pro iPhone's wide camera as it really is (6.8 mm f/1.78: a 3.8 mm disc pupil, focus
    /// breathing, the lens's own blur), its focus locked at --focus-mm, instead of the default
    /// realism's lens.
    #[arg(long, conflicts_with_all = ["clean", "realism"])]
    phone: bool,
    /// With --phone: where the lens is focused (mm), whatever the subject's distance (default:
    /// --distance-mm, else 200, the nearest a current Pro wide camera focuses).
    #[arg(long, value_name = "MM", requires = "phone")]
    focus_mm: Option<f64>,
    /// With --phone: the sensor crop (1, or 2 for a 48 MP sensor's native 2× crop); the
    /// intrinsics are zoomed with it.
    #[arg(long, default_value_t = 1.0, requires = "phone")]
    zoom: f64,
    /// Where the phone stands (mm from the markers): the static scene's one distance instead of
    /// its 80/100/120 mm, the chew scene's instead of 120 mm (current Pro iPhones focus from
    /// 15–20 cm).
    #[arg(long, value_name = "MM")]
    distance_mm: Option<f64>,
    /// Frames per camera view (static scene).
    #[arg(long, default_value_t = 2)]
    frames_per_view: usize,
    /// Cycles per opening / glide (hinge, excursion), chewing cycles in all (chew).
    #[arg(long, default_value_t = 2)]
    cycles: usize,
    /// Frame rate of the dynamic scenes (frames/s).
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
    /// Keep only every n-th frame.
    #[arg(long, default_value_t = 1)]
    stride: usize,
    /// Stop after this many frames.
    #[arg(long)]
    max_frames: Option<usize>,
    /// Instead of a scene, render a large tag and measure where its edges land (px).
    #[arg(long, conflicts_with_all = ["scene", "out"])]
    self_check: bool,
}

/// `--scene`: parsed by the synth crate, its values listed in the help from the crate's own
/// list, so neither can leave a scene out.
#[derive(Clone)]
struct SceneParser;

impl TypedValueParser for SceneParser {
    type Value = SceneKind;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<SceneKind, clap::Error> {
        (|s: &str| s.parse::<SceneKind>()).parse_ref(cmd, arg, value)
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(SceneKind::ALL.into_iter().map(|k| PossibleValue::new(k.name()))))
    }
}

/// The realism settings: `--clean`, `--realism FILE` or the defaults, then `--exposure-ms` and
/// `--readout-ms` over them.
pub(crate) fn load_realism(a: &SynthArgs) -> Result<Realism> {
    let mut realism = if a.phone {
        let focus = a.focus_mm.or(a.distance_mm).unwrap_or(200.0);
        if !(focus.is_finite() && (20.0..=2000.0).contains(&focus)) {
            bail!("--focus-mm must be within 20–2000 mm, got {focus}");
        }
        if !(a.zoom.is_finite() && (1.0..=10.0).contains(&a.zoom)) {
            bail!("--zoom is a sensor crop from 1 to 10, got {}", a.zoom);
        }
        Realism::phone_wide(focus, a.zoom)
    } else if a.clean {
        Realism::clean()
    } else {
        match &a.realism {
            None => Realism::default(),
            Some(p) => {
                let text = std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
                serde_json::from_str(&text).with_context(|| format!("{}: not a realism settings file", p.display()))?
            }
        }
    };
    for (flag, ms, seconds) in [
        ("--exposure-ms", a.exposure_ms, &mut realism.exposure_s),
        ("--readout-ms", a.readout_ms, &mut realism.readout_s),
    ] {
        if let Some(ms) = ms {
            if !ms.is_finite() || ms < 0.0 {
                bail!("{flag} must be a non-negative number of milliseconds, got {ms}");
            }
            *seconds = ms / 1000.0;
        }
    }
    Ok(realism)
}

pub(crate) fn synth_config(a: &SynthArgs, scene: SceneKind) -> Result<SynthConfig> {
    if a.landscape && scene != SceneKind::Chew {
        bail!("--landscape applies to the chew scene only (the {} scene is filmed upright)", scene.name());
    }
    if let Some(d) = a.distance_mm {
        if !matches!(scene, SceneKind::Static | SceneKind::Chew) {
            bail!(
                "--distance-mm applies to the static and chew scenes only (the {} scene films from its own)",
                scene.name()
            );
        }
        if !(d.is_finite() && (30.0..=1000.0).contains(&d)) {
            bail!("--distance-mm must be between 30 and 1000 mm, got {d}");
        }
    }
    let marker = match &a.marker {
        Some(p) => Marker::load(p)?,
        None => Marker::default(),
    };
    Ok(SynthConfig {
        scene,
        resolution: a.resolution,
        intrinsics: a.intrinsics,
        seed: a.seed,
        realism: load_realism(a)?,
        options: SceneOptions {
            frames_per_view: a.frames_per_view,
            cycles: a.cycles,
            fps: a.fps,
            orientation: if a.landscape { Orientation::Landscape } else { Orientation::Upright },
            distance_mm: a.distance_mm,
        },
        marker,
        stride: a.stride,
        max_frames: a.max_frames,
    })
}

pub(crate) fn run(a: &SynthArgs) -> Result<()> {
    if a.self_check {
        say!("side_px roll_deg rows  max_err_px rms_err_px");
        let mut worst: f64 = 0.0;
        for roll in [0.0, 7.0, 30.0, 45.0] {
            let c = jawtrack_synth::selfcheck::edge_self_check(400.0, roll);
            say!("{:7.0} {:8.1} {:5} {:10.4} {:10.4}", c.tag_side_px, roll, c.samples, c.max_error_px, c.rms_error_px);
            worst = worst.max(c.max_error_px);
        }
        if worst >= 0.05 {
            bail!("edge error {worst:.4} px exceeds 0.05 px");
        }
        say!("ok: every edge within {worst:.4} px of its projection");
        return Ok(());
    }
    let Some(scene) = a.scene else {
        bail!("--scene is required ({})", SceneKind::ALL.map(SceneKind::name).join(", "))
    };
    let Some(out) = &a.out else { bail!("--out DIR is required") };
    let config = synth_config(a, scene)?;
    let summary = crate::progress::render_with_progress(config, out)?;
    crate::print::print_scene_summary(scene, out, &summary);
    Ok(())
}
