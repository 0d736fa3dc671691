//! The app's settings and their valid ranges: the tracker's ([`Settings`]) and the whole
//! settings screen's ([`AppSettings`]). The Swift side persists them and shows the errors;
//! what is valid is decided here.

use crate::JawTrackError;
use crate::capture::check_readout;
use jawtrack_apriltag::DetectorConfig;
use jawtrack_tracker::{PoseRefinement, SearchConfig, SmootherConfig, TrackerConfig};

/// Decimations the detector accepts.
const DECIMATIONS: [f32; 5] = [1.0, 1.5, 2.0, 3.0, 4.0];

/// The tracker's settings.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct Settings {
    /// Decimation for quad finding: 1, 1.5, 2, 3 or 4.
    pub decimate: f32,
    /// Gaussian blur before quad finding (px), 0–0.8.
    pub quad_sigma: f32,
    /// Bit errors corrected, 0–2.
    pub max_hamming: u32,
    /// Detector threads, 1–8.
    pub threads: u32,
    /// Fit tag edges in linear light (frames are sRGB, as phones deliver them).
    pub linear_edges: bool,
    /// Search only where the markers are expected once tracked, and first where the poses
    /// predict each tag (`jawtrack track --predict-tags`, which is on by default too).
    pub region_search: bool,
    /// Smooth the jaw pose (One-Euro filter).
    pub smooth: bool,
    /// The camera's rolling-shutter readout, first row to last (s; 0: solve each frame as one
    /// instant): both jaws are then solved at the time of the frame's centre row. The app takes
    /// it from [`crate::readout_for`].
    pub readout_s: f64,
    /// Refine each jaw's pose from every pixel of its tags (`jawtrack track --refine dense`)
    /// rather than from their corners alone. Off by default: it takes 12–70 ms a body on a
    /// desktop core today (the most while chewing), too slow to run live (docs/dense.md).
    pub dense: bool,
}

/// The tracker's defaults: those of `jawtrack track`.
#[uniffi::export]
pub fn default_settings() -> Settings {
    let d = DetectorConfig::default();
    Settings {
        decimate: 2.0,
        quad_sigma: d.quad_sigma,
        max_hamming: d.max_hamming,
        threads: 1,
        linear_edges: true,
        region_search: true,
        smooth: false,
        readout_s: 0.0,
        dense: false,
    }
}

impl Settings {
    /// Checks every range, naming the setting that is out of it.
    pub fn validate(&self) -> Result<(), JawTrackError> {
        if !DECIMATIONS.contains(&self.decimate) {
            return Err(JawTrackError::setting(
                "decimate",
                format!("decimation must be 1, 1.5, 2, 3 or 4, got {}", self.decimate),
            ));
        }
        if !(0.0..=0.8).contains(&self.quad_sigma) {
            return Err(JawTrackError::setting(
                "quad_sigma",
                format!("quad sigma must be within 0–0.8, got {}", self.quad_sigma),
            ));
        }
        if self.max_hamming > 2 {
            return Err(JawTrackError::setting(
                "max_hamming",
                format!("max hamming must be 0, 1 or 2, got {}", self.max_hamming),
            ));
        }
        if !(1..=8).contains(&self.threads) {
            return Err(JawTrackError::setting("threads", format!("threads must be within 1–8, got {}", self.threads)));
        }
        check_readout(self.readout_s, "readout_s")
    }

    pub(crate) fn tracker_config(&self) -> Result<TrackerConfig, JawTrackError> {
        self.validate()?;
        Ok(TrackerConfig {
            detector: DetectorConfig {
                quad_decimate: self.decimate,
                quad_sigma: self.quad_sigma,
                max_hamming: self.max_hamming,
                nthreads: self.threads as usize,
                linear_edges: self.linear_edges,
                ..DetectorConfig::default()
            },
            search: SearchConfig { region_search: self.region_search, ..SearchConfig::default() },
            smoother: self.smooth.then(SmootherConfig::default),
            readout_s: self.readout_s,
            refine: if self.dense { PoseRefinement::Dense } else { PoseRefinement::Corners },
            ..TrackerConfig::default()
        })
    }
}

/// Which camera films.
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum Camera {
    /// The back wide-angle camera.
    BackWide,
    /// The back telephoto camera.
    BackTele,
    /// The front camera.
    Front,
}

/// Capture resolution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum Resolution {
    /// 1280×720.
    Hd720,
    /// 1920×1080.
    Hd1080,
    /// 3840×2160.
    Uhd4k,
}

/// Focus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum FocusMode {
    /// Continuous autofocus.
    Auto,
    /// Locked at `lens_position`.
    Manual,
    /// The capture plan's ([`crate::CapturePlanner`]): the plan chooses the format and zoom
    /// (the resolution setting is not used), the phone is guided to the plan's distance,
    /// beyond where its lens can focus, and focus is locked there before recording starts.
    Planned,
}

/// Everything on the settings screen.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct AppSettings {
    /// The camera.
    pub camera: Camera,
    /// Capture resolution.
    pub resolution: Resolution,
    /// Frames per second: 30 or 60.
    pub fps: u32,
    /// Focus mode.
    pub focus: FocusMode,
    /// Lens position for manual focus, 0 (near) – 1 (far).
    pub lens_position: f32,
    /// Lock the exposure once set.
    pub exposure_locked: bool,
    /// The longest exposure automatic exposure may choose (s; 0: no limit), lifted up to 4×
    /// only when the room is too dark ([`crate::next_exposure_cap`]): 2 ms by default, so a
    /// chewing jaw does not smear.
    pub max_exposure_s: f64,
    /// The readout measured with `jawtrack calibrate-camera` (s), used instead of the device
    /// table's figure.
    pub calibrated_readout_s: Option<f64>,
    /// Capture BGRA instead of passing the luma plane (costs a conversion per frame).
    pub bgra: bool,
    /// The tracker.
    pub tracker: Settings,
    /// The receiver's host name or address.
    pub receiver_host: String,
    /// The receiver's UDP port.
    pub receiver_port: u32,
    /// The pairing key, 64 hex digits (empty: not paired).
    pub pairing_key: String,
    /// Record the video beside the poses (for re-tracking with `jawtrack track --video`).
    pub record_video: bool,
}

/// How many detector threads a phone with `performance_cores` performance cores should run
/// (the app reads the count from the system, `hw.perflevel0.physicalcpu` on iOS): one per
/// performance core, leaving the efficiency cores to the camera, the screen and the stream;
/// within 1–8 ([`Settings::threads`]), and 1 when the count is unknown (0). The detector splits
/// its image stages and its tags over them (`crates/detector-bench/BENCHMARKS.md`).
#[uniffi::export]
pub fn detector_threads(performance_cores: u32) -> u32 {
    performance_cores.clamp(1, 8)
}

/// The settings a fresh install starts with.
#[uniffi::export]
pub fn default_app_settings() -> AppSettings {
    AppSettings {
        camera: Camera::BackWide,
        resolution: Resolution::Hd1080,
        fps: 60,
        focus: FocusMode::Planned,
        lens_position: 0.5,
        exposure_locked: false,
        max_exposure_s: 0.002,
        calibrated_readout_s: None,
        bgra: false,
        tracker: default_settings(),
        receiver_host: String::new(),
        receiver_port: 5005,
        pairing_key: String::new(),
        record_video: false,
    }
}

/// Checks the whole settings screen, naming the first setting that is wrong. Streaming
/// settings are checked only when `streaming`.
#[uniffi::export]
pub fn validate_app_settings(settings: AppSettings, streaming: bool) -> Result<(), JawTrackError> {
    let s = &settings;
    if s.fps != 30 && s.fps != 60 {
        return Err(JawTrackError::setting("fps", format!("frame rate must be 30 or 60, got {}", s.fps)));
    }
    if !(0.0..=1.0).contains(&s.lens_position) {
        return Err(JawTrackError::setting(
            "lens_position",
            format!("lens position must be within 0–1, got {}", s.lens_position),
        ));
    }
    if !(s.max_exposure_s == 0.0 || (0.0005..=0.0334).contains(&s.max_exposure_s)) {
        return Err(JawTrackError::setting(
            "max_exposure_s",
            format!("exposure limit must be 0 (none) or within 0.5–33.4 ms, got {} ms", s.max_exposure_s * 1e3),
        ));
    }
    if let Some(r) = s.calibrated_readout_s {
        check_readout(r, "calibrated_readout_s")?;
    }
    s.tracker.validate()?;
    if streaming {
        let host = s.receiver_host.trim();
        if host.is_empty() || host.contains(char::is_whitespace) {
            return Err(JawTrackError::setting(
                "receiver_host",
                "receiver host: give the computer's name or address, e.g. 192.168.1.20",
            ));
        }
        if !(1..=65535).contains(&s.receiver_port) {
            return Err(JawTrackError::setting(
                "receiver_port",
                format!("receiver port must be within 1–65535, got {}", s.receiver_port),
            ));
        }
        crate::pairing_key_id(s.pairing_key.clone()).map_err(|e| {
            JawTrackError::setting("pairing_key", format!("{e} (scan the QR code `jawtrack receive` shows)"))
        })?;
    }
    Ok(())
}

/// Checks the tracker's settings alone.
#[uniffi::export]
pub fn validate_settings(settings: Settings) -> Result<(), JawTrackError> {
    settings.validate()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_phone_runs_a_detector_thread_per_performance_core() {
        assert_eq!(detector_threads(0), 1, "unknown");
        assert_eq!(detector_threads(2), 2, "an iPhone's A-series chip");
        assert_eq!(detector_threads(64), 8, "at most the settings' limit");
        for cores in 0..20 {
            let s = Settings { threads: detector_threads(cores), ..default_settings() };
            assert!(s.validate().is_ok(), "{cores} cores");
        }
    }

    #[test]
    fn defaults_are_valid_and_each_range_names_its_setting() {
        assert!(validate_app_settings(default_app_settings(), false).is_ok());
        let bad = |f: &dyn Fn(&mut AppSettings), streaming: bool, needle: &str| {
            let mut s = default_app_settings();
            f(&mut s);
            let e = validate_app_settings(s, streaming).expect_err(needle).to_string();
            assert!(e.contains(needle), "{e}");
        };
        bad(&|s| s.fps = 24, false, "frame rate");
        bad(&|s| s.lens_position = 1.5, false, "lens position");
        bad(&|s| s.tracker.decimate = 2.5, false, "decimation");
        bad(&|s| s.tracker.quad_sigma = 0.9, false, "quad sigma");
        bad(&|s| s.tracker.max_hamming = 3, false, "max hamming");
        bad(&|s| s.tracker.threads = 0, false, "threads");
        bad(&|s| s.tracker.readout_s = 0.2, false, "readout must be within 0–100 ms");
        bad(&|s| s.tracker.readout_s = f64::NAN, false, "readout must be");
        bad(&|s| s.calibrated_readout_s = Some(-0.001), false, "calibrated readout must be");
        bad(&|s| s.max_exposure_s = 0.0001, false, "exposure limit");
        bad(&|s| s.max_exposure_s = f64::INFINITY, false, "exposure limit");
        bad(&|_| {}, true, "receiver host");
        bad(&|s| s.receiver_host = "10.0.0.2".into(), true, "pairing key");
        let mut ok = default_app_settings();
        ok.receiver_host = "10.0.0.2".into();
        ok.pairing_key = "ab".repeat(32);
        assert!(validate_app_settings(ok, true).is_ok());
    }
}
