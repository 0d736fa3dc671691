//! Where recorded frames come from: image files (PNG, JPEG), folders of them in name order, or
//! a video decoded to luma by ffmpeg. Read by `jawtrack track`, `calibrate-marker`,
//! `calibrate-camera` and the demo, the calibrations through [`detect_marker_tags`].
//!
//! # Examples
//!
//! ```no_run
//! let mut frames = jawtrack_frames::open_frames(None, &["fixtures/hinge-1080p".into()], None)?;
//! while let Some(frame) = frames.next_frame()? {
//!     println!("{} at {} s: {}", frame.name, frame.t, if frame.image.is_ok() { "read" } else { "unreadable" });
//! }
//! # Ok::<(), jawtrack_frames::FramesError>(())
//! ```

use jawtrack_apriltag::{DetectError, Detector, DetectorConfig, ImageView, ToneSetting};
use jawtrack_calibration::SeenTag;
use jawtrack_marker::Marker;
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Why frames could not be read.
#[derive(Debug, thiserror::Error)]
pub enum FramesError {
    /// A file or folder named could not be read.
    #[error("{path}: {reason}")]
    Path {
        /// The file or folder, as given.
        path: String,
        /// Why.
        reason: String,
    },
    /// ffmpeg or ffprobe is missing, or failed.
    #[error("{0}")]
    Video(String),
    /// The detector refused a setting or an image.
    #[error("{0}")]
    Detect(#[from] DetectError),
    /// Frames of different sizes, or too large.
    #[error("{0}")]
    Size(String),
    /// No frame could be read.
    #[error("none of the frames could be read: nothing to calibrate from")]
    NothingReadable,
}

type Result<T, E = FramesError> = std::result::Result<T, E>;

fn path_error(path: &Path, reason: impl std::fmt::Display) -> FramesError {
    FramesError::Path { path: path.display().to_string(), reason: reason.to_string() }
}

/// The frames of a video (`--video`) or of image files and folders, `fps` (default 30 for
/// images) giving each image's time; a video's frames carry their own times.
pub fn open_frames(video: Option<&Path>, images: &[PathBuf], fps: Option<f64>) -> Result<Box<dyn FrameSource>> {
    Ok(match video {
        Some(v) => Box::new(VideoFrames::open(v, fps)?),
        None => Box::new(ImageFrames { files: frame_files(images)?, next: 0, fps: fps.unwrap_or(30.0) }),
    })
}

/// A frame as it came: its name, its time, and its pixels or why there are none.
pub struct Frame {
    /// The file, or the video and the frame's index (`video.mov#12`).
    pub name: String,
    /// Its time (s) from the first frame.
    pub t: f64,
    /// The decoded image, or why it could not be decoded (the run goes on without it).
    pub image: Result<Luma, String>,
}

/// 8-bit luma, tightly packed.
pub struct Luma {
    /// Width (px).
    pub width: usize,
    /// Height (px).
    pub height: usize,
    /// Row after row, `width` bytes each.
    pub pixels: Vec<u8>,
}

impl Luma {
    /// The image as the detector reads it.
    pub fn view(&self) -> Result<ImageView<'_>, DetectError> {
        ImageView::new(&self.pixels, self.width, self.height, self.width)
    }
}

/// The widest or tallest image file read as a frame (px): more than any phone records (a 48 MP
/// frame is 8064 px wide), and checked before decoding, so a small file that claims a huge
/// image is refused at once instead of decoded for seconds (found by the `image` fuzz target).
pub const MAX_FRAME_SIDE: u32 = 8192;

/// Decodes an image file's bytes (PNG or JPEG, told by their content) to luma, as every frame
/// read from a file is. An image over [`MAX_FRAME_SIDE`] a side is refused before decoding.
///
/// # Examples
///
/// ```
/// let err = jawtrack_frames::decode_image(b"not an image").err().expect("not an image");
/// assert!(err.contains("format"), "{err}");
/// ```
pub fn decode_image(bytes: &[u8]) -> std::result::Result<Luma, String> {
    let mut reader =
        image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format().map_err(|e| e.to_string())?;
    let mut limits = image::Limits::default();
    (limits.max_image_width, limits.max_image_height) = (Some(MAX_FRAME_SIDE), Some(MAX_FRAME_SIDE));
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| match e {
            image::ImageError::Limits(_) => {
                format!("the image is over {MAX_FRAME_SIDE} px a side, larger than any phone's frame")
            }
            e => e.to_string(),
        })?
        .to_luma8();
    Ok(Luma { width: img.width() as usize, height: img.height() as usize, pixels: img.into_raw() })
}

/// One readable frame's tags of the marker, as the detector saw them.
pub struct TaggedFrame {
    /// As [`Frame::name`].
    pub name: String,
    /// As [`Frame::t`].
    pub t: f64,
    /// Width and height (px).
    pub size: (usize, usize),
    /// The marker's tags seen.
    pub tags: Vec<SeenTag>,
}

/// What [`detect_marker_tags`] reports as it goes.
#[derive(Debug)]
pub enum Progress<'a> {
    /// One more frame read (detected or left out).
    Frame,
    /// A frame that could not be read, left out: its name and why.
    Unreadable(&'a str, &'a str),
}

/// Detects `marker`'s tags in every frame of `source` (`progress` after each); a frame that
/// cannot be read is reported and left out. Refuses a source with no readable frame.
pub fn detect_marker_tags(
    mut source: Box<dyn FrameSource>,
    marker: &Marker,
    (linear_edges, tone): (bool, ToneSetting),
    progress: &mut dyn FnMut(Progress),
) -> Result<Vec<TaggedFrame>> {
    // Without the border model's sides: a marker turned in the hand is smeared by motion no
    // tracker predicts here, and the model (a Gaussian blur) makes smeared sightings plausible
    // enough to escape the calibration's outlier rule and bias its placements (the fixtures'
    // jaw 0.081 mm off after calibrating with them, 0.025 mm without; crates/cli/tests/calibrate.rs).
    let detector = Detector::new(DetectorConfig {
        linear_edges,
        tone,
        blur_aware_edges: false,
        family: marker.family,
        ..DetectorConfig::default()
    })?;
    let mut frames = Vec::new();
    while let Some(frame) = source.next_frame()? {
        progress(Progress::Frame);
        let image = match frame.image {
            Ok(image) => image,
            Err(why) => {
                progress(Progress::Unreadable(&frame.name, &why));
                continue;
            }
        };
        let tags = detector
            .detect(&image.view()?)?
            .into_iter()
            .filter(|d| marker.find_tag(d.id).is_some())
            .map(|d| SeenTag { id: d.id, corners: d.corners })
            .collect();
        frames.push(TaggedFrame { name: frame.name, t: frame.t, size: (image.width, image.height), tags });
    }
    if frames.is_empty() {
        return Err(FramesError::NothingReadable);
    }
    Ok(frames)
}

/// The one size (px) of `frames`, as a camera calibration needs it: refused when a frame
/// differs from the first (one calibration is of one camera at one resolution) or when there
/// is no frame.
pub fn one_size(frames: &[TaggedFrame]) -> Result<(u32, u32)> {
    let first = frames.first().ok_or(FramesError::NothingReadable)?;
    let (w, h) = first.size;
    if let Some(f) = frames.iter().find(|f| f.size != (w, h)) {
        return Err(FramesError::Size(format!(
            "{} is {}×{}, {} is {w}×{h}: one calibration is of one camera at one resolution",
            f.name, f.size.0, f.size.1, first.name
        )));
    }
    match (u32::try_from(w), u32::try_from(h)) {
        (Ok(w), Ok(h)) => Ok((w, h)),
        _ => Err(FramesError::Size(format!("frames of {w}×{h} px are too large"))),
    }
}

/// Where frames come from.
pub trait FrameSource: Send {
    /// How many frames, when known.
    fn frame_count(&self) -> Option<usize>;
    /// The next frame, or `None` at the end; an error only when nothing more can be read.
    fn next_frame(&mut self) -> Result<Option<Frame>>;
}

struct ImageFrames {
    files: Vec<PathBuf>,
    next: usize,
    fps: f64,
}

impl FrameSource for ImageFrames {
    fn frame_count(&self) -> Option<usize> {
        Some(self.files.len())
    }

    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let Some(path) = self.files.get(self.next) else { return Ok(None) };
        let image = std::fs::read(path).map_err(|e| e.to_string()).and_then(|bytes| decode_image(&bytes));
        let frame = Frame { name: path.display().to_string(), t: self.next as f64 / self.fps, image };
        self.next += 1;
        Ok(Some(frame))
    }
}

/// A video decoded to luma by an ffmpeg child process. Frames are read as stored, not turned
/// by the file's rotation flag: the camera's intrinsics describe the sensor's buffers. Each
/// frame's time is its presentation time (so variable frame rates are timed right), which
/// ffmpeg's `showinfo` filter reports on stderr as the frame passes.
struct VideoFrames {
    child: std::process::Child,
    stdout: std::process::ChildStdout,
    /// Presentation times (s) from the stderr reader, one per frame, in output order.
    times: std::sync::mpsc::Receiver<f64>,
    /// ffmpeg's other stderr lines, for the error message if it fails.
    log: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
    width: usize,
    height: usize,
    /// `--fps`: times `index / fps` instead of the stored ones.
    fps: Option<f64>,
    /// The first frame's presentation time: times count from the first frame.
    start: Option<f64>,
    frames: Option<usize>,
    next: usize,
    name: String,
}

impl VideoFrames {
    fn open(path: &Path, fps: Option<f64>) -> Result<Self> {
        if !path.is_file() {
            return Err(path_error(path, "no such video file"));
        }
        let probe = Command::new("ffprobe")
            .args(["-v", "error", "-select_streams", "v:0", "-show_entries"])
            .arg("stream=width,height,nb_frames:stream_tags=rotate:stream_side_data=rotation")
            .args(["-of", "json"])
            .arg(path)
            .output()
            .map_err(|e| {
                FramesError::Video(format!(
                    "--video needs ffprobe and ffmpeg on the PATH (e.g. apt-get install ffmpeg): {e}"
                ))
            })?;
        if !probe.status.success() {
            let why = String::from_utf8_lossy(&probe.stderr);
            return Err(FramesError::Video(format!("ffprobe could not read {}: {}", path.display(), why.trim())));
        }
        let info: serde_json::Value = serde_json::from_slice(&probe.stdout)
            .map_err(|e| FramesError::Video(format!("ffprobe's output for {}: {e}", path.display())))?;
        let stream = &info["streams"][0];
        let (Some(width), Some(height)) = (stream["width"].as_u64(), stream["height"].as_u64()) else {
            return Err(path_error(path, "has no video stream"));
        };
        if let Some(degrees) = rotation(stream).filter(|d| d.rem_euclid(360.0) != 0.0) {
            // Not `eprintln!`, which panics when standard error is closed (`… 2>&1 | head -1`).
            use std::io::Write as _;
            let _ = writeln!(
                std::io::stderr(),
                "note: {} is flagged to be shown turned {degrees}°; its frames are tracked as stored \
                 ({width}×{height}), which is what --intrinsics must describe",
                path.display()
            );
        }
        let frames = stream["nb_frames"].as_str().and_then(|n| n.parse().ok());
        let mut child = Command::new("ffmpeg")
            .args(["-hide_banner", "-nostats", "-nostdin", "-v", "info", "-noautorotate", "-i"])
            .arg(path)
            .args(["-map", "0:v:0", "-vf", "showinfo", "-fps_mode", "passthrough"])
            .args(["-f", "rawvideo", "-pix_fmt", "gray", "-"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| FramesError::Video(format!("starting ffmpeg: {e}")))?;
        let (Some(stdout), Some(stderr)) = (child.stdout.take(), child.stderr.take()) else {
            return Err(FramesError::Video("ffmpeg's output could not be read".into()));
        };
        let (send, times) = std::sync::mpsc::channel();
        let log = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let kept = log.clone();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines().map_while(std::result::Result::ok) {
                match showinfo_time(&line) {
                    // A frame without a readable time still gets its turn: NaN says so.
                    Some(t) if send.send(t.unwrap_or(f64::NAN)).is_err() => break,
                    Some(_) => {}
                    None if !line.contains("Parsed_showinfo") => {
                        if let Ok(mut log) = kept.lock() {
                            log.push(line);
                        }
                    }
                    None => {}
                }
            }
        });
        Ok(VideoFrames {
            child,
            stdout,
            times,
            log,
            width: width as usize,
            height: height as usize,
            fps,
            start: None,
            frames,
            next: 0,
            name: path.display().to_string(),
        })
    }

    /// ffmpeg's last lines that are errors or warnings, for a failure's message.
    fn complaint(&self) -> String {
        let log = self.log.lock().map(|l| l.clone()).unwrap_or_default();
        let bad: Vec<&String> =
            log.iter().filter(|l| l.to_ascii_lowercase().contains("error") || l.contains("Invalid")).collect();
        let lines = if bad.is_empty() { log.iter().rev().take(3).rev().collect() } else { bad };
        lines.into_iter().map(String::as_str).collect::<Vec<_>>().join("; ")
    }
}

/// The rotation a video stream is flagged with (degrees), from its display matrix or, in older
/// files, its `rotate` tag.
fn rotation(stream: &serde_json::Value) -> Option<f64> {
    let side = stream["side_data_list"].as_array().into_iter().flatten().find_map(|d| d["rotation"].as_f64());
    side.or_else(|| stream["tags"]["rotate"].as_str().and_then(|r| r.parse().ok()))
}

/// For a `showinfo` line describing a frame (`… n:   3 pts:   3000 pts_time:0.1 …`), its
/// presentation time if readable; `None` for every other line (showinfo writes several per
/// frame).
fn showinfo_time(line: &str) -> Option<Option<f64>> {
    if !(line.contains("Parsed_showinfo") && line.contains(" n:") && line.contains(" pts:")) {
        return None;
    }
    let time = line
        .split_once(" pts_time:")
        .and_then(|(_, rest)| rest.split_whitespace().next()?.parse::<f64>().ok())
        .filter(|t| t.is_finite());
    Some(time)
}

impl FrameSource for VideoFrames {
    fn frame_count(&self) -> Option<usize> {
        self.frames
    }

    fn next_frame(&mut self) -> Result<Option<Frame>> {
        let mut pixels = vec![0u8; self.width * self.height];
        let mut filled = 0;
        while filled < pixels.len() {
            let read = self.stdout.read(&mut pixels[filled..]);
            match read.map_err(|e| FramesError::Video(format!("reading ffmpeg's frames of {}: {e}", self.name)))? {
                0 => break,
                n => filled += n,
            }
        }
        if filled == 0 {
            let status = self.child.wait().map_err(|e| FramesError::Video(format!("waiting for ffmpeg: {e}")))?;
            if !status.success() {
                return Err(FramesError::Video(format!(
                    "ffmpeg failed decoding {} after {} frames ({status}): {}",
                    self.name,
                    self.next,
                    self.complaint()
                )));
            }
            return Ok(None);
        }
        // showinfo reports a frame before ffmpeg writes it, so its time is already sent.
        let stored = self.times.recv().ok();
        let t = match (self.fps, stored) {
            (Some(fps), _) => self.next as f64 / fps,
            (None, Some(pts)) if pts.is_finite() => pts - *self.start.get_or_insert(pts),
            _ => {
                return Err(FramesError::Video(format!(
                    "{}: frame {} carries no time; give --fps to time frames by their index",
                    self.name, self.next
                )));
            }
        };
        let image = if filled < pixels.len() {
            Err(format!("cut short ({filled} of {} bytes)", pixels.len()))
        } else {
            Ok(Luma { width: self.width, height: self.height, pixels })
        };
        let frame = Frame { name: format!("{}#{}", self.name, self.next), t, image };
        self.next += 1;
        Ok(Some(frame))
    }
}

/// The image files named, folders expanded to their images in name order.
pub fn frame_files(args: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let is_image = |p: &Path| {
        p.extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg"))
    };
    let mut out = Vec::new();
    for a in args {
        if a.is_dir() {
            let mut v: Vec<PathBuf> = std::fs::read_dir(a)
                .map_err(|e| path_error(a, e))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| is_image(p))
                .collect();
            if v.is_empty() {
                return Err(path_error(a, "holds no PNG or JPEG frames"));
            }
            v.sort();
            out.extend(v);
        } else if a.is_file() {
            out.push(a.clone());
        } else {
            return Err(path_error(a, "no such file or folder"));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_file_claiming_a_huge_image_is_refused_before_decoding() {
        // Found by the `image` fuzz target: a 6 kB JPEG claiming 59346 × 3770 px was decoded
        // (224 MB) for over a second before the detector refused it.
        let mut jpeg = std::io::Cursor::new(Vec::new());
        image::GrayImage::new(8, 8).write_to(&mut jpeg, image::ImageFormat::Jpeg).expect("a JPEG");
        let mut jpeg = jpeg.into_inner();
        let sof = jpeg.windows(2).position(|w| w == [0xff, 0xc0]).expect("a baseline frame header");
        jpeg[sof + 5..sof + 9].copy_from_slice(&[0x0e, 0xba, 0xe7, 0xd2]);
        let err = decode_image(&jpeg).err().expect("refused");
        assert!(err.contains("over 8192 px a side"), "{err}");
        jpeg[sof + 5..sof + 9].copy_from_slice(&[0x00, 0x08, 0x00, 0x08]);
        assert_eq!(decode_image(&jpeg).map(|l| (l.width, l.height)), Ok((8, 8)));
    }

    fn frame(name: &str, size: (usize, usize)) -> TaggedFrame {
        TaggedFrame { name: name.into(), t: 0.0, size, tags: Vec::new() }
    }

    #[test]
    fn a_calibration_takes_frames_of_one_size() {
        assert_eq!(one_size(&[frame("a", (1920, 1080)), frame("b", (1920, 1080))]).expect("one size"), (1920, 1080));
        let mixed = one_size(&[frame("a", (1920, 1080)), frame("b", (1280, 720))]).expect_err("two sizes");
        assert_eq!(
            mixed.to_string(),
            "b is 1280×720, a is 1920×1080: one calibration is of one camera at one resolution"
        );
        assert!(matches!(one_size(&[]), Err(FramesError::NothingReadable)));
    }
}
