//! A whole `jawtrack track` run from plain options: which intrinsics, readout, exposure, marker
//! and registration apply (the flags, else the camera file, else the `--like` recording, else
//! the defaults), one pass or two with the marker refined from the first, every frame's line
//! written, and the counts and closing warnings. What the user sees (bars, notes, the
//! refinement's report, where the recording goes) is the caller's, through [`TrackEvents`].

use crate::{
    FocalViews, Kept, OfflineError, RecordedCapture, Summary, closing_warnings, first_pass, refine_marker, track_frame,
};
use jawtrack_apriltag::{DetectorConfig, ToneSetting};
use jawtrack_calibration::Refinement;
use jawtrack_camera_calibration::CameraFile;
use jawtrack_frames::{FrameSource, open_frames};
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_recording::{FrameRecord, RecordingHeader, RecordingWriter, ToneRecord};
use jawtrack_registration::Registration;
use jawtrack_tracker::{FrameResult, PoseRefinement, SearchConfig, SmootherConfig, Tracker, TrackerConfig};
use std::io::Write;
use std::path::{Path, PathBuf};

/// What a run tracks, and with what; each `None` falls back as its field says. The names are
/// `jawtrack track`'s flags, which the error messages name.
#[derive(Debug, Clone, Default)]
pub struct TrackOptions {
    /// The marker file; else the `like` recording's marker, else the nominal marker.
    pub marker: Option<PathBuf>,
    /// The intrinsics; else the `camera` file's, else the `like` recording's.
    pub intrinsics: Option<CameraIntrinsics>,
    /// A camera file (`jawtrack calibrate-camera`): intrinsics, readout, and where it was calibrated.
    pub camera: Option<PathBuf>,
    /// The lens position filmed at, checked against the camera file's.
    pub lens_position: Option<f64>,
    /// The zoom filmed at, checked likewise.
    pub zoom: Option<f64>,
    /// A recording whose capture to take what is not given from.
    pub like: Option<PathBuf>,
    /// The registration of the markers to the tooth scans.
    pub registration: Option<PathBuf>,
    /// The frame rate of image frames (a video's frames keep their times).
    pub fps: Option<f64>,
    /// The rolling-shutter readout (ms).
    pub readout_ms: Option<f64>,
    /// The exposure (ms).
    pub exposure_ms: Option<f64>,
    /// Decimation for quad finding.
    pub decimate: f32,
    /// Detector threads.
    pub threads: usize,
    /// Refine tag edges in linear light.
    pub linear_edges: bool,
    /// The camera's tone curve, undone to reach linear light (`auto`: estimated from the tags).
    pub tone: ToneSetting,
    /// Search only where the markers are expected once tracked.
    pub region_search: bool,
    /// … and look for each tag first where the poses predict it.
    pub predict_tags: bool,
    /// Smooth the jaw pose.
    pub smooth: bool,
    /// How each body's pose is finished: from its tags' corners, or refined from their pixels.
    pub refine: PoseRefinement,
    /// The output's name, for messages (the writer itself comes from [`TrackEvents::output`]).
    pub out: PathBuf,
    /// Refine the marker from a first pass and write it here.
    pub refine_marker: Option<PathBuf>,
    /// A video to track instead of images.
    pub video: Option<PathBuf>,
    /// Image files or folders of them.
    pub frames: Vec<PathBuf>,
}

/// Something a run has to tell the user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Said {
    /// Worth knowing (a `note:`).
    Note(String),
    /// Worth checking (a `warning:`).
    Warning(String),
    /// A file written, in words.
    Wrote(String),
}

/// A pass over the frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    /// The only pass.
    Only,
    /// The first of two (detections kept for refining the marker).
    First,
    /// The second of two, solved with the refined marker.
    Second,
}

/// What a run reports as it goes, and the steps its caller owns: its last refusals before any
/// work, printing the refinement, and the writer the recording goes to.
pub trait TrackEvents {
    /// Says something to the user.
    fn said(&mut self, said: Said);
    /// A pass begins over `frames` frames (when known).
    fn pass(&mut self, pass: Pass, frames: Option<u64>);
    /// One frame of the pass done.
    fn frame(&mut self);
    /// The pass is over.
    fn pass_done(&mut self);
    /// The frames are open and the settings read: the caller's checks before any work (e.g.
    /// refusing outputs that exist).
    fn ready(&mut self) -> Result<(), OfflineError>;
    /// The marker was refined from the first pass in `seconds`.
    fn refined(&mut self, refinement: &Refinement, seconds: f64);
    /// Where the recording goes, opened once the tracking marker is final.
    fn output(&mut self) -> Result<Box<dyn Write>, OfflineError>;
}

/// How a run went.
pub struct Tracked {
    /// Frames written (tracked or flagged `unreadable`).
    pub frames: usize,
    /// The counts for the closing line.
    pub summary: Summary,
    /// The warnings the run calls for ([`closing_warnings`]).
    pub warnings: Vec<String>,
    /// The tone curve the last frames were read through, and how it was found.
    pub tone: ToneRecord,
}

/// What a run tracks with, resolved from the options.
struct Setup {
    intrinsics: CameraIntrinsics,
    readout_s: f64,
    exposure_s: Option<f64>,
    marker: Marker,
    registration: Option<Registration>,
}

/// Refuses what cannot be.
fn refused(message: String) -> OfflineError {
    OfflineError::Refused(message)
}

/// What `like` takes from a recording, said through `events`.
fn like(path: Option<&Path>, events: &mut dyn TrackEvents) -> Result<RecordedCapture, OfflineError> {
    let Some(path) = path else { return Ok(RecordedCapture::default()) };
    let recording = jawtrack_recording::open(path)?;
    let like = RecordedCapture::of(&recording)
        .map_err(|e| OfflineError::Like { path: path.display().to_string(), source: Box::new(e) })?;
    like.warnings.iter().for_each(|w| events.said(Said::Warning(format!("like {}: {w}", path.display()))));
    events.said(Said::Note(format!("like {}: {} (each unless given)", path.display(), like.describe())));
    Ok(like)
}

/// The ranges the numeric options must be in.
fn check_ranges(o: &TrackOptions) -> Result<(), OfflineError> {
    if let Some(fps) = o.fps
        && !(fps.is_finite() && fps > 0.0)
    {
        return Err(refused(format!("--fps must be a positive number, got {fps}")));
    }
    if let Some(r) = o.readout_ms
        && !(r.is_finite() && (0.0..1000.0).contains(&r))
    {
        return Err(refused(format!("--readout-ms must be at least 0 and under 1000 ms, got {r}")));
    }
    if let Some(e) = o.exposure_ms
        && !(e.is_finite() && e > 0.0 && e < 1000.0)
    {
        return Err(refused(format!("--exposure-ms must be a number of milliseconds above 0 and under 1000, got {e}")));
    }
    Ok(())
}

/// Checks the options and reads the camera, marker and registration they name.
fn setup(o: &TrackOptions, events: &mut dyn TrackEvents) -> Result<Setup, OfflineError> {
    check_ranges(o)?;
    let like = like(o.like.as_deref(), events)?;
    let camera = o.camera.as_deref().map(CameraFile::load).transpose()?;
    let intrinsics = match (o.intrinsics, &camera, like.intrinsics) {
        (Some(k), ..) => k,
        (None, Some(c), _) => c.calibration.intrinsics,
        (None, None, Some(k)) => k,
        (None, None, None) => {
            return Err(refused("--like's header names no intrinsics: give --intrinsics fx,fy,cx,cy[,k1,k2]".into()));
        }
    };
    let what = if o.intrinsics.is_some() { "--intrinsics" } else { "the intrinsics" };
    intrinsics.validate().map_err(|source| OfflineError::Intrinsics { what, source })?;
    let readout_s = o
        .readout_ms
        .map(|r| r / 1000.0)
        .or(camera.as_ref().map(|c| c.calibration.readout_s.max(0.0)))
        .or(like.readout_s)
        .unwrap_or(0.0);
    for (flag, v, ok) in [
        ("--lens-position", o.lens_position, o.lens_position.is_none_or(|p| p.is_finite() && (0.0..=1.0).contains(&p))),
        ("--zoom", o.zoom, o.zoom.is_none_or(|z| z.is_finite() && z >= 1.0)),
    ] {
        if !ok {
            return Err(refused(format!(
                "{flag} is out of range (lens position 0–1, zoom at least 1), got {}",
                v.unwrap_or(f64::NAN)
            )));
        }
    }
    if let Some(c) = &camera {
        let lens = o.lens_position.or(like.lens_position);
        for d in c.calibrated_at.differences(lens, o.zoom.or(like.zoom)) {
            events.said(Said::Warning(format!(
                "{d}: the camera file's intrinsics do not hold for these frames; calibrate at the focus and zoom you \
                 record with (lock focus where `jawtrack plan` says)"
            )));
        }
    }
    let exposure_s = o.exposure_ms.map(|e| e / 1000.0).or(like.exposure_s);
    let marker = match (&o.marker, like.marker) {
        (Some(p), _) => {
            let m = Marker::load(p).map_err(OfflineError::MarkerFile)?;
            m.require_both_bodies().map_err(|e| refused(format!("{}: {e}", p.display())))?;
            m
        }
        (None, Some(m)) => m,
        (None, None) => {
            events.said(Said::Note(
                "no --marker given; using the nominal 12.7 mm marker (calibrate yours for sub-0.1 mm)".into(),
            ));
            Marker::default()
        }
    };
    let registration = match &o.registration {
        Some(p) => Some(
            Registration::load(p)
                .map_err(|source| OfflineError::Registration { path: p.display().to_string(), source })?,
        ),
        None => None,
    };
    Ok(Setup { intrinsics, readout_s, exposure_s, marker, registration })
}

/// The tracker's settings from the options and the resolved timing.
fn tracker_config(o: &TrackOptions, readout_s: f64, exposure_s: Option<f64>) -> TrackerConfig {
    TrackerConfig {
        detector: DetectorConfig {
            quad_decimate: o.decimate,
            nthreads: o.threads,
            linear_edges: o.linear_edges,
            tone: o.tone,
            ..DetectorConfig::default()
        },
        search: SearchConfig { region_search: o.region_search, predicted: o.predict_tags, ..SearchConfig::default() },
        smoother: o.smooth.then(SmootherConfig::default),
        refine: o.refine,
        readout_s,
        exposure_s: exposure_s.unwrap_or(TrackerConfig::default().exposure_s),
        ..TrackerConfig::default()
    }
}

/// The recording's header: the camera, the marker tracked with and the settings.
fn header(o: &TrackOptions, tracker: &Tracker, s: &Setup) -> RecordingHeader {
    let mut header = RecordingHeader::new("jawtrack track");
    header.intrinsics = Some(s.intrinsics);
    header.readout_s = Some(s.readout_s);
    header.exposure_s = s.exposure_s;
    header.marker = serde_json::from_str(&tracker.marker().to_json()).ok();
    header.settings = serde_json::json!({
        "decimate": o.decimate, "threads": o.threads, "linear_edges": o.linear_edges, "tone": o.tone.to_string(),
        "region_search": o.region_search, "predict_tags": o.predict_tags,
        "smooth": o.smooth, "refine": o.refine.name(), "registration": o.registration.as_ref().map(|p| p.display().to_string()),
        "refine_marker": o.refine_marker.as_ref().map(|p| p.display().to_string()),
    });
    header
}

/// The first pass and the refined marker, written to `path`; the tracker for the second pass.
fn refine_pass(
    o: &TrackOptions,
    tracker: &mut Tracker,
    source: &mut dyn FrameSource,
    (intrinsics, config): (&CameraIntrinsics, TrackerConfig),
    path: &Path,
    events: &mut dyn TrackEvents,
) -> Result<Vec<Kept>, OfflineError> {
    events.pass(Pass::First, source.frame_count().map(|n| n as u64));
    let kept = first_pass(tracker, source, intrinsics, &mut || events.frame())?;
    events.pass_done();
    // The refined marker names the session it came from: the video, or the frames as given.
    let recording = match &o.video {
        Some(v) => v.display().to_string(),
        None => o.frames.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
    };
    let started = std::time::Instant::now();
    let refinement = refine_marker(tracker.marker(), &kept, intrinsics, &recording)?;
    events.refined(&refinement, started.elapsed().as_secs_f64());
    // `ready` refused an existing file unless replacing was asked for: written whole or not at all.
    let text = refinement.marker.to_json() + "\n";
    jawtrack_recording::write_file_atomic(path, text.as_bytes(), jawtrack_recording::Overwrite::Replace)
        .map_err(|source| OfflineError::SaveMarker { path: path.display().to_string(), source })?;
    events.said(Said::Wrote(format!("wrote the refined marker to {}", path.display())));
    let mut again = Tracker::new(refinement.marker, config)?;
    again.set_registration(tracker.registration().cloned());
    *tracker = again;
    Ok(kept)
}

/// Tracks the frames `options` name into the recording `events` opens: one line per frame,
/// flushed as written, a frame that cannot be decoded or tracked flagged `unreadable`. With
/// `refine_marker`, a first pass keeps every frame's detections, the marker refined from them
/// is written there, and only the second pass, solved with it, is recorded. Refused when no
/// frame could be read.
///
/// # Examples
///
/// ```no_run
/// # use jawtrack_offline::{OfflineError, Pass, Said, TrackEvents, TrackOptions, track};
/// struct Quiet;
/// impl TrackEvents for Quiet {
///     fn said(&mut self, said: Said) { eprintln!("{said:?}") }
///     fn pass(&mut self, _: Pass, _: Option<u64>) {}
///     fn frame(&mut self) {}
///     fn pass_done(&mut self) {}
///     fn ready(&mut self) -> Result<(), OfflineError> { Ok(()) }
///     fn refined(&mut self, _: &jawtrack_calibration::Refinement, _: f64) {}
///     fn output(&mut self) -> Result<Box<dyn std::io::Write>, OfflineError> { Ok(Box::new(std::io::sink())) }
/// }
/// let options = TrackOptions {
///     intrinsics: Some(jawtrack_pose::CameraIntrinsics::pinhole(1400.0, 1400.0, 959.5, 539.5)),
///     frames: vec!["fixtures/hinge-1080p".into()],
///     decimate: 2.0,
///     threads: 1,
///     ..TrackOptions::default()
/// };
/// let mut tracked = track(&options, &mut Quiet)?;
/// println!("{} frames: {}", tracked.frames, tracked.summary.describe());
/// # Ok::<(), OfflineError>(())
/// ```
pub fn track(o: &TrackOptions, events: &mut dyn TrackEvents) -> Result<Tracked, OfflineError> {
    let mut setup = setup(o, events)?;
    let mut source = open_frames(o.video.as_deref(), &o.frames, o.fps)?;
    if o.video.is_none() && o.fps.is_none() {
        events.said(Said::Note("image files carry no time: frame times assume 30 fps (--fps sets the rate)".into()));
    }
    let config = tracker_config(o, setup.readout_s, setup.exposure_s);
    events.ready()?;
    let intrinsics = setup.intrinsics;
    let mut tracker = Tracker::new(std::mem::take(&mut setup.marker), config)?;
    tracker.set_registration(setup.registration.take());
    let kept = match &o.refine_marker {
        None => None,
        Some(path) => Some(refine_pass(o, &mut tracker, source.as_mut(), (&intrinsics, config), path, events)?),
    };
    let mut out = RecordingWriter::new(events.output()?, header(o, &tracker, &setup), &o.out.display().to_string())?;
    let (mut summary, mut views, mut index) = (Summary::default(), FocalViews::default(), 0);
    let mut write = |events: &mut dyn TrackEvents,
                     tracker: &mut Tracker,
                     name: &str,
                     t: f64,
                     tracked: Result<FrameResult, String>| {
        let record = match tracked {
            Ok(r) => {
                summary.add(&r, tracker.uncalibrated_tags());
                views.add(&r, &intrinsics);
                r.to_record(index, Some(name))
            }
            Err(why) => {
                if let Some(w) = summary.skip(&why) {
                    events.said(Said::Warning(format!("{name}: {w}")));
                }
                FrameRecord::unreadable(index as u64, Some(name), t)
            }
        };
        index += 1;
        events.frame();
        out.append(&record)
    };
    match kept {
        Some(kept) => {
            events.pass(Pass::Second, Some(kept.len() as u64));
            for k in kept {
                let tracked = k.tracked.map(|d| d.solve(&mut tracker, &intrinsics, k.t));
                write(events, &mut tracker, &k.name, k.t, tracked)?;
            }
        }
        None => {
            events.pass(Pass::Only, source.frame_count().map(|n| n as u64));
            while let Some(frame) = source.next_frame()? {
                // A frame that cannot be decoded or tracked keeps its line, flagged, and the run goes on.
                let tracked = track_frame(&mut tracker, &frame, &intrinsics);
                write(events, &mut tracker, &frame.name, frame.t, tracked)?;
            }
        }
    }
    events.pass_done();
    if summary.read == 0 {
        return Err(OfflineError::NothingTracked { frames: index, out: o.out.display().to_string() });
    }
    let warnings = closing_warnings(&summary, &views, &tracker);
    Ok(Tracked { frames: index, summary, warnings, tone: jawtrack_tracker::tone_record(&tracker.tone()) })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Keeps what is said; refuses nothing; writes nowhere.
    #[derive(Default)]
    struct Heard(Vec<Said>);

    impl TrackEvents for Heard {
        fn said(&mut self, said: Said) {
            self.0.push(said);
        }
        fn pass(&mut self, _: Pass, _: Option<u64>) {}
        fn frame(&mut self) {}
        fn pass_done(&mut self) {}
        fn ready(&mut self) -> Result<(), OfflineError> {
            Ok(())
        }
        fn refined(&mut self, _: &Refinement, _: f64) {}
        fn output(&mut self) -> Result<Box<dyn Write>, OfflineError> {
            Ok(Box::new(std::io::sink()))
        }
    }

    fn options() -> TrackOptions {
        TrackOptions {
            intrinsics: Some(CameraIntrinsics::pinhole(1400.0, 1400.0, 959.5, 539.5)),
            decimate: 2.0,
            threads: 1,
            ..TrackOptions::default()
        }
    }

    #[test]
    fn out_of_range_timing_is_refused_naming_the_flag() {
        for (o, flag) in [
            (TrackOptions { fps: Some(0.0), ..options() }, "--fps"),
            (TrackOptions { readout_ms: Some(1000.0), ..options() }, "--readout-ms"),
            (TrackOptions { exposure_ms: Some(-1.0), ..options() }, "--exposure-ms"),
            (TrackOptions { zoom: Some(0.5), ..options() }, "--zoom"),
        ] {
            let e = setup(&o, &mut Heard::default()).err().expect("refused");
            assert!(e.to_string().starts_with(flag), "{e}");
        }
    }

    #[test]
    fn without_a_marker_the_nominal_one_is_used_and_said() {
        let mut said = Heard::default();
        let s = setup(&TrackOptions { readout_ms: Some(5.0), ..options() }, &mut said).expect("set up");
        assert_eq!((s.readout_s, s.exposure_s), (0.005, None));
        assert_eq!(s.marker.to_json(), Marker::default().to_json());
        assert!(matches!(&said.0[..], [Said::Note(n)] if n.starts_with("no --marker given")), "{:?}", said.0);
        let none = TrackOptions { intrinsics: None, ..options() };
        assert!(setup(&none, &mut Heard::default()).err().expect("refused").to_string().contains("--intrinsics"));
    }
}
