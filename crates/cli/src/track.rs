//! `jawtrack track`: tracks recorded frames (image files, folders of them sorted by name, or a
//! video decoded by ffmpeg) and writes one JSON line per frame in the recording schema
//! (`jawtrack_recording`), after a header line naming the camera, marker and settings. Every
//! line is flushed as it is written, so a killed run leaves a readable file.

use crate::frames::{Frame, open_frames};
use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::ProgressBar;
use jawtrack_apriltag::Detection;
use jawtrack_apriltag::DetectorConfig;
use jawtrack_calibration::{CalibrationFrame, FocalCheck, SeenTag, SessionOptions, check_focal, refine};
use jawtrack_camera_calibration::CameraFile;
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_recording::{FrameRecord, RecordingHeader, RecordingWriter, create_file};
use jawtrack_tracker::{FrameResult, Registration, SearchConfig, SmootherConfig, Tracker, TrackerConfig};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::{Path, PathBuf};

/// What `--like` takes from a recording: its header's camera, timing and marker.
#[derive(Default)]
struct Like {
    intrinsics: Option<CameraIntrinsics>,
    readout_s: Option<f64>,
    exposure_s: Option<f64>,
    marker: Option<Marker>,
    /// Where focus was locked (the header's capture plan), else the frames' median lens position.
    lens_position: Option<f64>,
    /// The capture plan's zoom.
    zoom: Option<f64>,
}

impl Like {
    fn read(path: Option<&Path>) -> Result<Like> {
        let Some(path) = path else { return Ok(Like::default()) };
        let recording = jawtrack_recording::open(path)?;
        let Some(h) = recording.header else {
            bail!("--like {}: the recording has no header line to take the camera from", path.display())
        };
        // The app records each frame's exposure; the header's is a session-wide one.
        let mut exposures: Vec<f64> = recording.frames.iter().filter_map(|f| f.exposure_s).collect();
        exposures.sort_by(f64::total_cmp);
        let marker = match &h.marker {
            Some(m) => Some(
                Marker::from_json(&m.to_string()).with_context(|| format!("--like {}: its marker", path.display()))?,
            ),
            None => None,
        };
        let mut positions: Vec<f64> = recording.frames.iter().filter_map(|f| f.lens_position).collect();
        positions.sort_by(f64::total_cmp);
        if let (Some(lo), Some(hi)) = (positions.first(), positions.last())
            && hi - lo > jawtrack_camera_calibration::LENS_POSITION_MOVED
        {
            eprintln!(
                "warning: like {}: the lens position moved from {lo:.3} to {hi:.3} during the recording: focus was not \
                 locked, so the focal length changed with it (up to 3.5 %); the app locks focus before recording",
                path.display()
            );
        }
        let like = Like {
            intrinsics: h.intrinsics,
            readout_s: h.readout_s,
            exposure_s: h.exposure_s.or_else(|| exposures.get(exposures.len() / 2).copied()),
            marker,
            lens_position: h
                .capture
                .as_ref()
                .and_then(|c| c.lens_position)
                .or_else(|| positions.get(positions.len() / 2).copied()),
            zoom: h.capture.as_ref().map(|c| c.zoom),
        };
        eprintln!(
            "note: like {}: intrinsics {}, readout {}, exposure {}, marker {} (each unless given)",
            path.display(),
            if like.intrinsics.is_some() { "taken" } else { "not in it" },
            like.readout_s.map_or("not in it".into(), |r| format!("{:.2} ms", r * 1e3)),
            like.exposure_s.map_or("not in it".into(), |e| format!("{:.2} ms", e * 1e3)),
            if like.marker.is_some() { "taken" } else { "not in it" },
        );
        Ok(like)
    }
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
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    roi: bool,
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

pub(crate) fn run(a: &TrackArgs) -> Result<()> {
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
    let like = Like::read(a.like.as_deref())?;
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
            crate::marker::require_both_bodies(&m, p)?;
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
        search: SearchConfig { roi: a.roi, ..SearchConfig::default() },
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
    let (mut tracker, passes) = match &a.refine_marker {
        None => (tracker, None),
        Some(path) => {
            let mut kept = Vec::new();
            let bar = crate::progress::bar("tracking (1 of 2)", source.len().map(|n| n as u64), "frames");
            while let Some(frame) = source.next_frame()? {
                let tracked = track_frame(&mut tracker, &frame, &intrinsics);
                let rows = frame.image.as_ref().map_or(0, |i| i.height);
                kept.push(Kept { name: frame.name, t: frame.t, tracked: tracked.map(|r| Detected::of(r, rows)) });
                bar.inc(1);
            }
            bar.finish_and_clear();
            let recording = match &a.video {
                Some(v) => v.display().to_string(),
                None => a.frames.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
            };
            let refined =
                refine_marker(tracker.marker(), &kept, &intrinsics, path, &recording, a.out.as_os_str() == "-")?;
            let mut again = Tracker::new(refined, config)?;
            again.set_registration(tracker.registration().cloned());
            (again, Some(kept))
        }
    };
    let out: Box<dyn Write> = if a.out.as_os_str() == "-" {
        Box::new(std::io::stdout())
    } else {
        Box::new(create_file(&a.out, a.force.overwrite()).map_err(|e| a.force.explain(e))?)
    };
    let mut header = RecordingHeader::new("jawtrack track");
    header.intrinsics = Some(intrinsics);
    header.readout_s = Some(readout_s);
    header.exposure_s = exposure_s;
    header.marker = serde_json::from_str(&tracker.marker().to_json()).ok();
    header.settings = serde_json::json!({
        "decimate": a.decimate, "threads": a.threads, "linear_edges": a.linear_edges, "roi": a.roi,
        "smooth": a.smooth, "registration": a.registration.as_ref().map(|p| p.display().to_string()),
        "refine_marker": a.refine_marker.as_ref().map(|p| p.display().to_string()),
    });
    let mut out = RecordingWriter::new(out, header, &a.out.display().to_string())?;
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
                    bar.suspend(|| summary.unreadable(name, &why));
                    FrameRecord::unreadable(index as u64, Some(name), t)
                }
            };
            index += 1;
            out.append(&record)
        };
    match passes {
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
            let bar = crate::progress::bar("tracking", source.len().map(|n| n as u64), "frames");
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
    for line in summary.uncalibrated_lines() {
        eprintln!("warning: {line}");
    }
    if summary.defocused > 0 {
        eprintln!(
            "warning: {} of {} frames had a marker out of focus (flagged BODY:defocused: its tags' edges blurred by more \
             than 0.14 of their cells' width) and give no jaw pose: the phone was nearer than its lens focuses, or far from \
             where its focus was locked; `jawtrack plan --phone MODEL` says where to hold it",
            summary.defocused, summary.read
        );
    }
    let check = check_focal(tracker.marker(), &views.frames);
    let focal = check.filter(FocalCheck::looks_wrong);
    if let Some(focal) = &focal {
        eprintln!("warning: {}", crate::calibrate::intrinsics_warning(focal, []));
    }
    // A few per cent is what a focus moved since calibration does; only a measured marker (its
    // print errors known) can tell it.
    if let Some(moved) =
        check.filter(|c| focal.is_none() && c.focus_moved() && !tracker.marker().measured_tags().is_empty())
    {
        eprintln!(
            "warning: the focal length that fits is {:.3}× the one given ({moved}): did the focus or the zoom change \
             since the camera was calibrated? Focusing moves a phone's lens and scales the image (3.5 % between \
             infinity and 20 cm); every distance is off by about that factor. Calibrate at the focus you record with, \
             or lock focus where `jawtrack plan` says",
            moved.best_scale
        );
    }
    for (id, seen, dropped) in tracker.mismatched_tags(5) {
        if focal.is_some() {
            eprintln!(
                "warning: tag {id} disagreed with the marker file in {dropped} of {seen} frames (first check the intrinsics)"
            );
            continue;
        }
        eprintln!(
            "warning: tag {id} disagreed with the marker file in {dropped} of the {seen} frames it was seen in and was \
             left out: is it glued turned or on another face, or is the marker file another print's? \
             `jawtrack calibrate-marker` finds and corrects such errors"
        );
    }
    Ok(())
}

/// One frame tracked, or why it could not be decoded or tracked.
fn track_frame(tracker: &mut Tracker, frame: &Frame, camera: &CameraIntrinsics) -> Result<FrameResult, String> {
    let image = frame.image.as_ref().map_err(Clone::clone)?;
    let view = image.view().map_err(|e| e.to_string())?;
    tracker.track(&view, camera, frame.t).map_err(|e| e.to_string())
}

/// A frame of the first pass of `--refine-marker`: its detections, or why it was unreadable.
struct Kept {
    name: String,
    t: f64,
    tracked: Result<Detected, String>,
}

/// What the first pass detected in a frame, and how.
struct Detected {
    detections: Vec<Detection>,
    /// The frame's height (px): its rows' times under a rolling shutter.
    rows: usize,
    detection_s: f64,
    searched: Option<jawtrack_apriltag::Roi>,
}

impl Detected {
    fn of(r: FrameResult, rows: usize) -> Self {
        Detected { detection_s: r.timings.detection_s, searched: r.searched, detections: r.detections, rows }
    }

    /// The frame solved again by `tracker`, keeping the first pass's detection figures.
    fn solve(self, tracker: &mut Tracker, camera: &CameraIntrinsics, t: f64) -> FrameResult {
        let mut r = tracker.solve(self.detections, camera, t, self.rows);
        r.timings.detection_s = self.detection_s;
        r.searched = self.searched;
        r
    }
}

/// Refines `marker` from the first pass's detections, says what changed, writes it to `path`
/// and returns it.
fn refine_marker(
    marker: &Marker,
    kept: &[Kept],
    camera: &CameraIntrinsics,
    path: &std::path::Path,
    recording: &str,
    to_stderr: bool,
) -> Result<Marker> {
    let frames: Vec<CalibrationFrame> = kept
        .iter()
        .filter_map(|k| k.tracked.as_ref().ok())
        .map(|d| CalibrationFrame {
            camera: *camera,
            tags: d.detections.iter().map(|d| SeenTag { id: d.id, corners: d.corners }).collect(),
        })
        .collect();
    let started = std::time::Instant::now();
    let mut refinement = refine(marker, &frames, &SessionOptions::default()).context("refining the marker")?;
    refinement.name_recording(recording);
    // With `--out -` the recording is standard output: the report goes to standard error.
    crate::calibrate::print_refinement(&refinement, started.elapsed().as_secs_f64(), to_stderr);
    refinement.marker.save(path).with_context(|| format!("writing {}", path.display()))?;
    eprintln!("wrote the refined marker to {}", path.display());
    Ok(refinement.marker)
}

/// The marker's tags seen in frames spread over the run, for judging the focal length
/// ([`check_focal`]) at its end.
#[derive(Default)]
struct FocalViews {
    frames: Vec<CalibrationFrame>,
    offered: usize,
}

impl FocalViews {
    /// Views kept at most: the first `DENSE` frames with three tags of a body, then every
    /// `STRIDE`-th (a short recording needs them all to see a focus that moved).
    const MAX: usize = 200;
    const DENSE: usize = 40;
    const STRIDE: usize = 5;

    fn add(&mut self, r: &FrameResult, camera: &CameraIntrinsics) {
        let three = [&r.maxilla, &r.mandible].iter().any(|b| b.as_ref().is_some_and(|b| b.tags.len() >= 3));
        if !three || self.frames.len() >= Self::MAX {
            return;
        }
        self.offered += 1;
        if self.offered <= Self::DENSE || (self.offered - 1).is_multiple_of(Self::STRIDE) {
            let tags = r.detections.iter().map(|d| SeenTag { id: d.id, corners: d.corners }).collect();
            self.frames.push(CalibrationFrame { camera: *camera, tags });
        }
    }
}

/// Counts over a run, for the closing line.
#[derive(Default)]
struct Summary {
    /// Frames tracked (readable).
    read: usize,
    /// Frames skipped as unreadable.
    unreadable: usize,
    both: usize,
    /// Frames with a body flagged `defocused`.
    defocused: usize,
    flags: BTreeMap<String, usize>,
    detection_s: Vec<f64>,
    /// Per body (maxilla, mandible): frames whose pose used a tag the calibrated marker left
    /// nominal (flagged `uncalibrated_tag`), and those tags.
    uncalibrated: [(usize, BTreeSet<u32>); 2],
}

impl Summary {
    /// Counts a tracked frame; `uncalibrated` are the marker's tags left nominal by its
    /// calibration ([`Tracker::uncalibrated_tags`]).
    fn add(&mut self, r: &FrameResult, uncalibrated: &[u32]) {
        self.read += 1;
        for (slot, body) in [&r.maxilla, &r.mandible].into_iter().enumerate() {
            let used: Vec<u32> = body
                .iter()
                .flat_map(|b| &b.tags)
                .copied()
                .filter(|id| uncalibrated.binary_search(id).is_ok())
                .collect();
            if !used.is_empty() {
                self.uncalibrated[slot].0 += 1;
                self.uncalibrated[slot].1.extend(used);
            }
        }
        self.both += usize::from(r.maxilla_from_mandible.is_some());
        self.defocused += usize::from(r.flags.iter().any(|f| matches!(f, jawtrack_tracker::Flag::Defocused(_))));
        for f in &r.flags {
            *self.flags.entry(f.name()).or_default() += 1;
        }
        self.detection_s.push(r.timings.detection_s + r.timings.pose_s);
    }

    /// Counts a skipped frame and says why, for the first few.
    fn unreadable(&mut self, name: &str, why: &str) {
        const SAID: usize = 10;
        self.unreadable += 1;
        if self.unreadable <= SAID {
            eprintln!("warning: {name}: {why}; skipped (its line is flagged `unreadable`)");
        } else if self.unreadable == SAID + 1 {
            eprintln!("warning: more frames could not be read; the summary counts them");
        }
    }

    /// One line per body whose poses rested on nominal tags of a calibrated marker.
    fn uncalibrated_lines(&self) -> Vec<String> {
        jawtrack_marker::BodyKind::ALL
            .iter()
            .zip(&self.uncalibrated)
            .filter(|(_, (frames, _))| *frames > 0)
            .map(|(kind, (frames, ids))| {
                let ids: Vec<String> = ids.iter().map(u32::to_string).collect();
                format!(
                    "{kind}: {frames} frames rest on nominal tag{} {} (flagged {kind}:uncalibrated_tag): \
                     `--refine-marker` places them from this session, or calibrate with a recording that shows them",
                    if ids.len() == 1 { "" } else { "s" },
                    ids.join(", ")
                )
            })
            .collect()
    }

    fn describe(&mut self) -> String {
        let flags: Vec<String> = self.flags.iter().map(|(k, v)| format!("{k} ×{v}")).collect();
        self.detection_s.sort_by(f64::total_cmp);
        let median = self.detection_s.get(self.detection_s.len() / 2).copied().unwrap_or(0.0);
        format!(
            "{}jaw pose in {}; flags: {}; median {:.1} ms per frame",
            match self.unreadable {
                0 => String::new(),
                n => format!("{n} unreadable and skipped; "),
            },
            self.both,
            if flags.is_empty() { "none".to_owned() } else { flags.join(", ") },
            median * 1e3
        )
    }
}
