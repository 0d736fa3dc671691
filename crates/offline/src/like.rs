//! What re-tracking a recording's video takes from the recording (`jawtrack track --like`):
//! its header's camera, readout, exposure, marker and capture plan, so the video is measured
//! as the app measured it live.

use crate::OfflineError;
use jawtrack_marker::Marker;
use jawtrack_pose::CameraIntrinsics;
use jawtrack_recording::Recording;

/// A recording's camera, timing and marker, each `None` when it does not say.
#[derive(Debug, Clone, Default)]
pub struct RecordedCapture {
    /// The header's intrinsics.
    pub intrinsics: Option<CameraIntrinsics>,
    /// The header's rolling-shutter readout (s).
    pub readout_s: Option<f64>,
    /// The header's exposure (s), else the frames' median (the app records each frame's).
    pub exposure_s: Option<f64>,
    /// The header's marker.
    pub marker: Option<Marker>,
    /// Where focus was locked (the header's capture plan), else the frames' median lens position.
    pub lens_position: Option<f64>,
    /// The capture plan's zoom.
    pub zoom: Option<f64>,
    /// What the reader should know, e.g. that focus moved during the recording.
    pub warnings: Vec<String>,
}

impl RecordedCapture {
    /// Reads them from `recording`; refused without a header, or with a marker that is not valid.
    pub fn of(recording: &Recording) -> Result<Self, OfflineError> {
        let h = recording.header.as_ref().ok_or(OfflineError::NoHeader)?;
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied()
        };
        let marker = h.tracked_marker().transpose().map_err(OfflineError::Marker)?;
        let positions: Vec<f64> = recording.frames.iter().filter_map(|f| f.lens_position).collect();
        let mut warnings = Vec::new();
        let (lo, hi) = positions.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        if hi - lo > jawtrack_camera_calibration::LENS_POSITION_MOVED {
            warnings.push(format!(
                "the lens position moved from {lo:.3} to {hi:.3} during the recording: focus was not locked, so the \
                 focal length changed with it (up to 3.5 %); the app locks focus before recording"
            ));
        }
        Ok(RecordedCapture {
            intrinsics: h.intrinsics,
            readout_s: h.readout_s,
            exposure_s: h.exposure_s.or_else(|| median(recording.frames.iter().filter_map(|f| f.exposure_s).collect())),
            marker,
            lens_position: h.capture.as_ref().and_then(|c| c.lens_position).or_else(|| median(positions)),
            zoom: h.capture.as_ref().map(|c| c.zoom),
            warnings,
        })
    }

    /// What was taken, in words: "intrinsics taken, readout 5.10 ms, exposure not in it, …".
    pub fn describe(&self) -> String {
        let ms = |v: Option<f64>| v.map_or("not in it".into(), |s| format!("{:.2} ms", s * 1e3));
        format!(
            "intrinsics {}, readout {}, exposure {}, marker {}",
            if self.intrinsics.is_some() { "taken" } else { "not in it" },
            ms(self.readout_s),
            ms(self.exposure_s),
            if self.marker.is_some() { "taken" } else { "not in it" },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_recording::{RecordingHeader, read_recording};

    fn recording(header: bool, frames: &[(f64, f64)]) -> Recording {
        let mut lines: Vec<String> = Vec::new();
        if header {
            lines.push(RecordingHeader::new("test").to_line());
        }
        for (i, (exposure, lens)) in frames.iter().enumerate() {
            lines.push(format!(r#"{{"frame":{i},"t":{i},"exposure_s":{exposure},"lens_position":{lens},"flags":[]}}"#));
        }
        read_recording((lines.join("\n") + "\n").as_bytes()).expect("a recording")
    }

    #[test]
    fn takes_the_frames_medians_and_says_when_focus_moved() {
        let still =
            RecordedCapture::of(&recording(true, &[(0.004, 0.30), (0.002, 0.31), (0.008, 0.30)])).expect("read");
        assert_eq!((still.exposure_s, still.lens_position), (Some(0.004), Some(0.30)));
        assert!(still.warnings.is_empty(), "{:?}", still.warnings);
        assert!(still.describe().starts_with("intrinsics not in it, readout not in it, exposure 4.00 ms"));
        let moved = RecordedCapture::of(&recording(true, &[(0.004, 0.30), (0.004, 0.45)])).expect("read");
        assert_eq!(moved.warnings.len(), 1);
        assert!(moved.warnings[0].contains("moved from 0.300 to 0.450"), "{}", moved.warnings[0]);
    }

    #[test]
    fn a_recording_without_a_header_is_refused() {
        let e = RecordedCapture::of(&recording(false, &[(0.004, 0.3)])).expect_err("refused");
        assert_eq!(e.to_string(), "the recording has no header line to take the camera from");
    }
}
