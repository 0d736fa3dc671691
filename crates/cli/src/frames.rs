//! Where recorded frames come from: image files (PNG, JPEG), folders of them in name order, or
//! a video decoded to luma by ffmpeg. Shared by `jawtrack track` and `jawtrack calibrate-marker`.

use anyhow::{Context, Result, bail};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The frames of a video (`--video`) or of image files and folders, `fps` (default 30 for
/// images, the video's own rate) giving each frame's time.
pub(crate) fn open_frames(video: Option<&Path>, images: &[PathBuf], fps: Option<f64>) -> Result<Box<dyn FrameSource>> {
    Ok(match video {
        Some(v) => Box::new(VideoFrames::open(v, fps)?),
        None => Box::new(ImageFrames { files: frame_files(images)?, next: 0, fps: fps.unwrap_or(30.0) }),
    })
}

/// A decoded frame: 8-bit luma, tightly packed.
pub(crate) struct Frame {
    pub name: String,
    pub t: f64,
    pub width: usize,
    pub height: usize,
    pub luma: Vec<u8>,
}

/// Where frames come from.
pub(crate) trait FrameSource {
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
