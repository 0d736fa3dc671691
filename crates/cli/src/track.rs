//! `jawtrack track`: tracks recorded frames (image files, folders of them sorted by name, or a
//! video decoded by ffmpeg) and writes one JSON line per frame in the tracker's recording
//! schema (`jawtrack_tracker::record`). Every line is flushed as it is written, so a killed
//! run leaves a readable file.

use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_apriltag::{DetectorConfig, ImageView};
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_tracker::record::frame_record;
use jawtrack_tracker::{FrameResult, Registration, SearchConfig, SmootherConfig, Tracker, TrackerConfig};
use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Arguments of `jawtrack track`.
#[derive(Args)]
pub(crate) struct TrackArgs {
    /// The marker file (nominal or calibrated); default: the nominal 12.7 mm marker.
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Camera intrinsics in pixels: fx,fy,cx,cy[,k1,k2] (pixel centres at integer coordinates).
    #[arg(long)]
    intrinsics: CameraIntrinsics,
    /// Registration of the markers to the tooth scans (JSON); adds
    /// `maxilla_scan_from_mandible_scan` to every line.
    #[arg(long)]
    registration: Option<PathBuf>,
    /// Frame rate, for each frame's time `t` (s); default 30 for images, the video's own rate.
    #[arg(long)]
    fps: Option<f64>,
    /// Decimation for quad finding: 1, 1.5, 2, 3 or 4.
    #[arg(long, default_value_t = 2.0)]
    decimate: f32,
    /// Detector threads.
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Refine tag edges in linear light, reading frames as sRGB (as phones deliver them).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    linear_edges: bool,
    /// Search only where the markers are expected once tracked (the whole frame every 30
    /// frames and whenever a body is missing); `false` searches every frame whole.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    roi: bool,
    /// Smooth the jaw pose (One-Euro filter; never more than one frame of lag).
    #[arg(long)]
    smooth: bool,
    /// Output file (JSON lines); `-` for standard output.
    #[arg(long)]
    out: PathBuf,
    /// A video file to track instead of images (needs ffmpeg and ffprobe on the PATH).
    #[arg(long, conflicts_with = "frames")]
    video: Option<PathBuf>,
    /// Frames: image files (PNG, JPEG) or folders of them, taken in name order.
    #[arg(required_unless_present = "video")]
    frames: Vec<PathBuf>,
}

pub(crate) fn run(a: &TrackArgs) -> Result<()> {
    if let Some(fps) = a.fps
        && !(fps.is_finite() && fps > 0.0)
    {
        bail!("--fps must be a positive number, got {fps}");
    }
    a.intrinsics.validate().context("--intrinsics")?;
    let marker = match &a.marker {
        Some(p) => Marker::load(p).with_context(|| format!("marker file {}", p.display()))?,
        None => {
            eprintln!("note: no --marker given; using the nominal 12.7 mm marker (calibrate yours for sub-0.1 mm)");
            Marker::default()
        }
    };
    let registration = match &a.registration {
        Some(p) => Some(Registration::load(p).with_context(|| format!("registration file {}", p.display()))?),
        None => None,
    };
    let mut source: Box<dyn FrameSource> = match &a.video {
        Some(v) => Box::new(VideoFrames::open(v, a.fps)?),
        None => Box::new(ImageFrames { files: frame_files(&a.frames)?, next: 0, fps: a.fps.unwrap_or(30.0) }),
    };
    let config = TrackerConfig {
        detector: DetectorConfig {
            quad_decimate: a.decimate,
            nthreads: a.threads,
            linear_edges: a.linear_edges,
            ..DetectorConfig::default()
        },
        search: SearchConfig { roi: a.roi, ..SearchConfig::default() },
        smoother: a.smooth.then(SmootherConfig::default),
        ..TrackerConfig::default()
    };
    let mut tracker = Tracker::new(marker, config)?;
    tracker.set_registration(registration);
    let mut out: Box<dyn Write> = if a.out.as_os_str() == "-" {
        Box::new(std::io::stdout())
    } else {
        Box::new(std::fs::File::create(&a.out).with_context(|| format!("creating {}", a.out.display()))?)
    };
    let bar = progress_bar(source.len());
    let mut summary = Summary::default();
    let mut index = 0;
    while let Some(frame) = source.next_frame()? {
        let view =
            ImageView::new(&frame.luma, frame.width, frame.height, frame.width).with_context(|| frame.name.clone())?;
        let r = tracker.track(&view, &a.intrinsics, frame.t).with_context(|| frame.name.clone())?;
        summary.add(&r);
        let line = frame_record(index, Some(&frame.name), &r);
        writeln!(out, "{line}").and_then(|()| out.flush()).context("writing the poses")?;
        bar.inc(1);
        index += 1;
    }
    bar.finish_and_clear();
    eprintln!("tracked {index} frames: {}; poses in {}", summary.describe(), a.out.display());
    Ok(())
}

/// Counts over a run, for the closing line.
#[derive(Default)]
struct Summary {
    both: usize,
    flags: BTreeMap<String, usize>,
    detection_s: Vec<f64>,
}

impl Summary {
    fn add(&mut self, r: &FrameResult) {
        self.both += usize::from(r.maxilla_from_mandible.is_some());
        for f in &r.flags {
            *self.flags.entry(f.name()).or_default() += 1;
        }
        self.detection_s.push(r.timings.detection_s + r.timings.pose_s);
    }

    fn describe(&mut self) -> String {
        let flags: Vec<String> = self.flags.iter().map(|(k, v)| format!("{k} ×{v}")).collect();
        self.detection_s.sort_by(f64::total_cmp);
        let median = self.detection_s.get(self.detection_s.len() / 2).copied().unwrap_or(0.0);
        format!(
            "jaw pose in {}; flags: {}; median {:.1} ms per frame",
            self.both,
            if flags.is_empty() { "none".to_owned() } else { flags.join(", ") },
            median * 1e3
        )
    }
}

fn progress_bar(len: Option<usize>) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len.unwrap_or(0) as u64);
    let template = if len.is_some() {
        "tracking [{bar:30}] {pos}/{len} frames, {elapsed} elapsed, ~{eta} left"
    } else {
        "tracking {pos} frames, {elapsed} elapsed"
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(template)
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar
}

/// A decoded frame: 8-bit luma, tightly packed.
struct Frame {
    name: String,
    t: f64,
    width: usize,
    height: usize,
    luma: Vec<u8>,
}

/// Where frames come from.
trait FrameSource {
    /// How many frames, when known.
    fn len(&self) -> Option<usize>;
    /// The next frame, or `None` at the end.
    fn next_frame(&mut self) -> Result<Option<Frame>>;
}

struct ImageFrames {
    files: Vec<PathBuf>,
    next: usize,
    fps: f64,
}

impl FrameSource for ImageFrames {
    fn len(&self) -> Option<usize> {
        Some(self.files.len())
    }

    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let Some(path) = self.files.get(self.next) else { return Ok(None) };
        let img = image::open(path).with_context(|| format!("reading {}", path.display()))?.to_luma8();
        let frame = Frame {
            name: path.display().to_string(),
            t: self.next as f64 / self.fps,
            width: img.width() as usize,
            height: img.height() as usize,
            luma: img.into_raw(),
        };
        self.next += 1;
        Ok(Some(frame))
    }
}

/// A video decoded to luma by an ffmpeg child process.
struct VideoFrames {
    child: std::process::Child,
    stdout: std::process::ChildStdout,
    width: usize,
    height: usize,
    fps: f64,
    frames: Option<usize>,
    next: usize,
    name: String,
}

impl VideoFrames {
    fn open(path: &Path, fps: Option<f64>) -> Result<Self> {
        if !path.is_file() {
            bail!("{}: no such video file", path.display());
        }
        let probe = Command::new("ffprobe")
            .args(["-v", "error", "-select_streams", "v:0", "-show_entries"])
            .arg("stream=width,height,avg_frame_rate,nb_frames")
            .args(["-of", "json"])
            .arg(path)
            .output()
            .map_err(|e| {
                anyhow::anyhow!("--video needs ffprobe and ffmpeg on the PATH (e.g. apt-get install ffmpeg): {e}")
            })?;
        if !probe.status.success() {
            bail!("ffprobe could not read {}: {}", path.display(), String::from_utf8_lossy(&probe.stderr).trim());
        }
        let info: serde_json::Value = serde_json::from_slice(&probe.stdout).context("ffprobe's output")?;
        let stream = &info["streams"][0];
        let (Some(width), Some(height)) = (stream["width"].as_u64(), stream["height"].as_u64()) else {
            bail!("{} has no video stream", path.display());
        };
        let rate = stream["avg_frame_rate"].as_str().and_then(|r| {
            let (n, d) = r.split_once('/')?;
            let (n, d): (f64, f64) = (n.parse().ok()?, d.parse().ok()?);
            (n > 0.0 && d > 0.0).then(|| n / d)
        });
        let Some(fps) = fps.or(rate) else {
            bail!("{}: the video does not say its frame rate; give --fps", path.display());
        };
        let frames = stream["nb_frames"].as_str().and_then(|n| n.parse().ok());
        let mut child = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-i"])
            .arg(path)
            .args(["-f", "rawvideo", "-pix_fmt", "gray", "-"])
            .stdout(Stdio::piped())
            .spawn()
            .context("starting ffmpeg")?;
        let stdout = child.stdout.take().context("ffmpeg's output")?;
        Ok(VideoFrames {
            child,
            stdout,
            width: width as usize,
            height: height as usize,
            fps,
            frames,
            next: 0,
            name: path.display().to_string(),
        })
    }
}

impl FrameSource for VideoFrames {
    fn len(&self) -> Option<usize> {
        self.frames
    }

    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let mut luma = vec![0u8; self.width * self.height];
        let mut filled = 0;
        while filled < luma.len() {
            match self.stdout.read(&mut luma[filled..]).context("reading ffmpeg's frames")? {
                0 => break,
                n => filled += n,
            }
        }
        if filled == 0 {
            let status = self.child.wait().context("waiting for ffmpeg")?;
            if !status.success() {
                bail!("ffmpeg failed decoding {} ({status})", self.name);
            }
            return Ok(None);
        }
        if filled < luma.len() {
            bail!("{}: frame {} is cut short ({filled} of {} bytes)", self.name, self.next, luma.len());
        }
        let frame = Frame {
            name: format!("{}#{}", self.name, self.next),
            t: self.next as f64 / self.fps,
            width: self.width,
            height: self.height,
            luma,
        };
        self.next += 1;
        Ok(Some(frame))
    }
}

/// The image files named, folders expanded to their images in name order.
pub(crate) fn frame_files(args: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let is_image = |p: &Path| {
        p.extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg"))
    };
    let mut out = Vec::new();
    for a in args {
        if a.is_dir() {
            let mut v: Vec<PathBuf> = std::fs::read_dir(a)
                .with_context(|| format!("reading {}", a.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| is_image(p))
                .collect();
            if v.is_empty() {
                bail!("{} holds no PNG or JPEG frames", a.display());
            }
            v.sort();
            out.extend(v);
        } else if a.is_file() {
            out.push(a.clone());
        } else {
            bail!("{}: no such file or folder", a.display());
        }
    }
    Ok(out)
}
