//! `jawtrack track`: tracks recorded frames (image files, folders of them sorted by name, or a
//! video decoded by ffmpeg) and writes one JSON line per frame in the recording schema
//! (`jawtrack_recording`), after a header line naming the camera, marker and settings. Every
//! line is flushed as it is written, so a killed run leaves a readable file.

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::ProgressBar;
use jawtrack_apriltag::DetectorConfig;
use jawtrack_camera_calibration::CameraFile;
use jawtrack_frames::{FrameSource, open_frames};
use jawtrack_marker::Marker;
use jawtrack_offline::{FocalViews, Kept, RecordedCapture, Summary, closing_warnings, refine_marker, track_frame};
use jawtrack_pose::CameraIntrinsics;
use jawtrack_recording::{FrameRecord, RecordingHeader, RecordingWriter, create_file};
use jawtrack_registration::Registration;
use jawtrack_tracker::{FrameResult, SearchConfig, SmootherConfig, Tracker, TrackerConfig};
use std::io::Write;
use std::path::{Path, PathBuf};

/// What `--like` takes from a recording, said on standard error.
fn like(path: Option<&Path>) -> Result<RecordedCapture> {
    let Some(path) = path else { return Ok(RecordedCapture::default()) };
    let recording = jawtrack_recording::open(path)?;
    let like = RecordedCapture::of(&recording).with_context(|| format!("--like {}", path.display()))?;
    like.warnings.iter().for_each(|w| eprintln!("warning: like {}: {w}", path.display()));
    eprintln!("note: like {}: {} (each unless given)", path.display(), like.describe());
    Ok(like)
}

/// Arguments of `jawtrack track`.
#[derive(Args)]
pub(crate) struct TrackArgs {
    /// The marker file (nominal or calibrated); default: the --like recording's marker, else
    /// the nominal 12.7 mm marker.
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Camera intrinsics in pixels: fx,fy,cx,cy[,k1,k2] (pixel centres at integer coordinates);
    /// default: the --camera file's, else the --like recording's.
    #[arg(long, allow_hyphen_values = true, required_unless_present_any = ["like", "camera"])]
    intrinsics: Option<CameraIntrinsics>,
    /// The camera file `jawtrack calibrate-camera` wrote: its intrinsics and readout (each
    /// unless given), and the lens position and zoom it was calibrated at, which the
    /// recording's are checked against (--lens-position, --zoom, or the --like recording's).
    #[arg(long, value_name = "CAMERA_JSON")]
    camera: Option<PathBuf>,
    /// The lens position (AVFoundation's 0 near – 1 far) the frames were filmed at, to check
    /// against the --camera file's; default: the --like recording's.
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    lens_position: Option<f64>,
    /// The zoom the frames were filmed at (1, or a native crop), to check likewise.
    #[arg(long, value_name = "Z", allow_hyphen_values = true)]
    zoom: Option<f64>,
    /// Track as a recording was made: its header's intrinsics, readout, exposure (else its
    /// frames' median exposure) and marker, each unless given here. For re-tracking the video
    /// the iPhone app recorded beside its poses (`--video session.mov --like session.jsonl`).
    #[arg(long, value_name = "RECORDING")]
    like: Option<PathBuf>,
    /// Registration of the markers to the tooth scans (JSON); adds
    /// `maxilla_scan_from_mandible_scan` to every line.
    #[arg(long)]
    registration: Option<PathBuf>,
    /// Frame rate, timing frame `i` at `i / fps` s; default 30 for images, while a video's
    /// frames keep their own presentation times (right for variable frame rates too).
    #[arg(long)]
    fps: Option<f64>,
    /// The camera's rolling-shutter readout, first row to last (ms; 0 = a global shutter):
    /// each corner is then carried from its row's time to the frame's, so both markers are
    /// solved at the same instant. iPhone main cameras read in about 2.4 ms (16 Pro Max) to
    /// 9 ms (14 Pro); on rendered chewing, ignoring a 5 ms readout made the error 13× larger.
    /// Frames are taken as the camera stored them (rows as read), as with --video. Recorded
    /// in the header. Default: the --like recording's, else 0.
    #[arg(long, value_name = "MS", allow_hyphen_values = true)]
    readout_ms: Option<f64>,
    /// The exposure the frames were taken with (ms; default 8.3, a phone's indoor 1/120 s),
    /// recorded in the header: with the markers' tracked velocity it predicts how far their
    /// tags smear, and frames smeared 3 px or more have their edges fitted as motion ramps.
    /// Keep exposures short while the jaw moves: 2 ms leaves a chewing jaw nearly sharp.
    #[arg(long, value_name = "MS", allow_hyphen_values = true)]
    exposure_ms: Option<f64>,
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
    #[arg(long, alias = "roi", default_value_t = true, action = clap::ArgAction::Set)]
    region_search: bool,
    /// Smooth the jaw pose (One-Euro filter; never more than one frame of lag).
    #[arg(long)]
    smooth: bool,
    /// Output file (JSON lines); `-` for standard output.
    #[arg(long)]
    out: PathBuf,
    /// After tracking, place the tags the marker's calibration left nominal (or every tag, for
    /// a nominal marker) from this session's own frames, keeping calibrated tags as they are;
    /// write the refined marker here and the recording from the refined marker. A tag keeps
    /// its place unless the session fits a new one better. An existing file here is replaced
    /// only with --force, as --out is.
    #[arg(long, value_name = "MARKER_OUT")]
    refine_marker: Option<PathBuf>,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    /// A video file to track instead of images (needs ffmpeg and ffprobe on the PATH). Frames
    /// are read as stored, whatever rotation the file asks players to show them with.
    #[arg(long, conflicts_with = "frames")]
    video: Option<PathBuf>,
    /// Frames: image files (PNG, JPEG) or folders of them, taken in name order.
    #[arg(required_unless_present = "video")]
    frames: Vec<PathBuf>,
}

/// What a run tracks with, from the flags (and `--camera`, `--like`).
struct Setup {
    intrinsics: CameraIntrinsics,
    readout_s: f64,
    exposure_s: Option<f64>,
    marker: Marker,
    registration: Option<Registration>,
}

/// Checks the flags and reads the camera, marker and registration they name.
fn setup(a: &TrackArgs) -> Result<Setup> {
    if let Some(fps) = a.fps
        && !(fps.is_finite() && fps > 0.0)
    {
        bail!("--fps must be a positive number, got {fps}");
    }
    if let Some(r) = a.readout_ms
        && !(r.is_finite() && (0.0..1000.0).contains(&r))
    {
        bail!("--readout-ms must be at least 0 and under 1000 ms, got {r}");
    }
    if let Some(e) = a.exposure_ms
        && !(e.is_finite() && e > 0.0 && e < 1000.0)
    {
        bail!("--exposure-ms must be a number of milliseconds above 0 and under 1000, got {e}");
    }
    let like = like(a.like.as_deref())?;
    let camera = a.camera.as_deref().map(CameraFile::load).transpose()?;
    let intrinsics = match (a.intrinsics, &camera, like.intrinsics) {
        (Some(k), ..) => k,
        (None, Some(c), _) => c.calibration.intrinsics,
        (None, None, Some(k)) => k,
        (None, None, None) => bail!("--like's header names no intrinsics: give --intrinsics fx,fy,cx,cy[,k1,k2]"),
    };
    intrinsics.validate().context(if a.intrinsics.is_some() { "--intrinsics" } else { "the intrinsics" })?;
    let readout_s = a
        .readout_ms
        .map(|r| r / 1000.0)
        .or(camera.as_ref().map(|c| c.calibration.readout_s.max(0.0)))
        .or(like.readout_s)
        .unwrap_or(0.0);
    for (flag, v, ok) in [
        ("--lens-position", a.lens_position, a.lens_position.is_none_or(|p| p.is_finite() && (0.0..=1.0).contains(&p))),
        ("--zoom", a.zoom, a.zoom.is_none_or(|z| z.is_finite() && z >= 1.0)),
    ] {
        if !ok {
            bail!("{flag} is out of range (lens position 0–1, zoom at least 1), got {}", v.unwrap_or(f64::NAN));
        }
    }
    if let Some(c) = &camera {
        let lens = a.lens_position.or(like.lens_position);
        for d in c.calibrated_at.differences(lens, a.zoom.or(like.zoom)) {
            eprintln!(
                "warning: {d}: the camera file's intrinsics do not hold for these frames; calibrate at the focus and zoom you \
                 record with (lock focus where `jawtrack plan` says)"
            );
        }
    }
    let exposure_s = a.exposure_ms.map(|e| e / 1000.0).or(like.exposure_s);
    let marker = match (&a.marker, like.marker) {
        (Some(p), _) => {
            let m = Marker::load(p)?;
            m.require_both_bodies().map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
            m
        }
        (None, Some(m)) => m,
        (None, None) => {
            eprintln!("note: no --marker given; using the nominal 12.7 mm marker (calibrate yours for sub-0.1 mm)");
            Marker::default()
        }
    };
    let registration = match &a.registration {
        Some(p) => Some(Registration::load(p).with_context(|| format!("registration file {}", p.display()))?),
        None => None,
    };
    Ok(Setup { intrinsics, readout_s, exposure_s, marker, registration })
}

pub(crate) fn run(a: &TrackArgs) -> Result<()> {
    let Setup { intrinsics, readout_s, exposure_s, marker, registration } = setup(a)?;
    let mut source = open_frames(a.video.as_deref(), &a.frames, a.fps)?;
    if a.video.is_none() && a.fps.is_none() {
        eprintln!("note: image files carry no time: frame times assume 30 fps (--fps sets the rate)");
    }
    let config = TrackerConfig {
        detector: DetectorConfig {
            quad_decimate: a.decimate,
            nthreads: a.threads,
            linear_edges: a.linear_edges,
            ..DetectorConfig::default()
        },
        search: SearchConfig { region_search: a.region_search, ..SearchConfig::default() },
        smoother: a.smooth.then(SmootherConfig::default),
        readout_s,
        exposure_s: exposure_s.unwrap_or(TrackerConfig::default().exposure_s),
        ..TrackerConfig::default()
    };
    if a.out.as_os_str() != "-" {
        a.force.check_file(&a.out)?;
    }
    if let Some(path) = &a.refine_marker {
        a.force.check_file(path)?;
    }
    let mut tracker = Tracker::new(marker, config)?;
    tracker.set_registration(registration);
    // With --refine-marker, a first pass keeps every frame's detections; the refined marker
    // then solves them again, and only that second pass is written.
    let kept = match &a.refine_marker {
        None => None,
        Some(path) => {
            let kept = first_pass(&mut tracker, source.as_mut(), &intrinsics)?;
            let refined = refine(a, tracker.marker(), &kept, &intrinsics, path)?;
            let mut again = Tracker::new(refined, config)?;
            again.set_registration(tracker.registration().cloned());
            tracker = again;
            Some(kept)
        }
    };
    let out: Box<dyn Write> = if a.out.as_os_str() == "-" {
        Box::new(std::io::stdout())
    } else {
        Box::new(create_file(&a.out, a.force.overwrite()).map_err(|e| a.force.explain(e))?)
    };
    let mut out = RecordingWriter::new(
        out,
        header(a, &tracker, intrinsics, readout_s, exposure_s),
        &a.out.display().to_string(),
    )?;
    let mut summary = Summary::default();
    let mut views = FocalViews::default();
    let mut index = 0;
    let mut write =
        |bar: &ProgressBar, tracker: &mut Tracker, name: &str, t: f64, tracked: Result<FrameResult, String>| {
            let record = match tracked {
                Ok(r) => {
                    summary.add(&r, tracker.uncalibrated_tags());
                    views.add(&r, &intrinsics);
                    r.to_record(index, Some(name))
                }
                Err(why) => {
                    if let Some(w) = summary.skip(&why) {
                        bar.suspend(|| eprintln!("warning: {name}: {w}"));
                    }
                    FrameRecord::unreadable(index as u64, Some(name), t)
                }
            };
            index += 1;
            out.append(&record)
        };
    match kept {
        Some(kept) => {
            let bar = crate::progress::bar("tracking (2 of 2)", Some(kept.len() as u64), "frames");
            for k in kept {
                let tracked = k.tracked.map(|d| d.solve(&mut tracker, &intrinsics, k.t));
                write(&bar, &mut tracker, &k.name, k.t, tracked)?;
                bar.inc(1);
            }
            bar.finish_and_clear();
        }
        None => {
            let bar = crate::progress::bar("tracking", source.frame_count().map(|n| n as u64), "frames");
            while let Some(frame) = source.next_frame()? {
                // A frame that cannot be decoded or tracked keeps its line, flagged, and the run goes on.
                let tracked = track_frame(&mut tracker, &frame, &intrinsics);
                write(&bar, &mut tracker, &frame.name, frame.t, tracked)?;
                bar.inc(1);
            }
            bar.finish_and_clear();
        }
    }
    if summary.read == 0 {
        bail!(
            "none of the {index} frames could be read{}: nothing tracked ({} lists them, flagged `unreadable`)",
            if index == 0 { "" } else { " or tracked" },
            a.out.display()
        );
    }
    eprintln!("tracked {index} frames: {}; poses in {}", summary.describe(), a.out.display());
    for w in closing_warnings(&summary, &views, &tracker) {
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// The recording's header: the camera, the marker tracked with and the settings.
fn header(
    a: &TrackArgs,
    tracker: &Tracker,
    intrinsics: CameraIntrinsics,
    readout_s: f64,
    exposure_s: Option<f64>,
) -> RecordingHeader {
    let mut header = RecordingHeader::new("jawtrack track");
    header.intrinsics = Some(intrinsics);
    header.readout_s = Some(readout_s);
    header.exposure_s = exposure_s;
    header.marker = serde_json::from_str(&tracker.marker().to_json()).ok();
    header.settings = serde_json::json!({
        "decimate": a.decimate, "threads": a.threads, "linear_edges": a.linear_edges, "region_search": a.region_search,
        "smooth": a.smooth, "registration": a.registration.as_ref().map(|p| p.display().to_string()),
        "refine_marker": a.refine_marker.as_ref().map(|p| p.display().to_string()),
    });
    header
}

/// The first pass of `--refine-marker`, with a bar.
fn first_pass(tracker: &mut Tracker, source: &mut dyn FrameSource, intrinsics: &CameraIntrinsics) -> Result<Vec<Kept>> {
    let bar = crate::progress::bar("tracking (1 of 2)", source.frame_count().map(|n| n as u64), "frames");
    let kept = jawtrack_offline::first_pass(tracker, source, intrinsics, &mut || bar.inc(1))?;
    bar.finish_and_clear();
    Ok(kept)
}

/// Refines `marker` from the first pass, says what changed, writes it to `path` and returns it.
fn refine(
    a: &TrackArgs,
    marker: &Marker,
    kept: &[Kept],
    intrinsics: &CameraIntrinsics,
    path: &std::path::Path,
) -> Result<Marker> {
    let recording = match &a.video {
        Some(v) => v.display().to_string(),
        None => a.frames.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
    };
    let started = std::time::Instant::now();
    let refinement = refine_marker(marker, kept, intrinsics, &recording)?;
    // With `--out -` the recording is standard output: the report goes to standard error.
    crate::print::print_refinement(&refinement, started.elapsed().as_secs_f64(), a.out.as_os_str() == "-");
    refinement.marker.save(path).with_context(|| format!("writing {}", path.display()))?;
    eprintln!("wrote the refined marker to {}", path.display());
    Ok(refinement.marker)
}
