//! The lower scan in the upper scan's frame (`maxilla_scan_from_mandible_scan`) per frame, from
//! one rule: through a registration when one is given, else as the recording carries it (a
//! recording tracked with a registration); a hand-written poses file without a recording
//! header may give the scans' pose directly as its `maxilla_from_mandible`.

use crate::SessionError;
use jawtrack_pose::Pose;
use jawtrack_recording::{FrameRecord, Recording};
use jawtrack_registration::Registration;

/// One frame with the scans' pose: its `frame` number, its time (s) and
/// `maxilla_scan_from_mandible_scan`.
pub type PosedFrame = (u64, f64, Pose);

/// Where each frame's `maxilla_scan_from_mandible_scan` comes from.
#[derive(Debug, Clone)]
pub enum PoseSource {
    /// `maxilla_from_mandible` through a registration.
    Registration(Box<Registration>),
    /// The frames' recorded `maxilla_scan_from_mandible_scan`.
    Recorded,
    /// `maxilla_from_mandible` taken as the scan pose (a header-less poses file only).
    Direct,
}

impl PoseSource {
    /// The source for `rec`: `registration` when given, else the recorded scan poses; `None`
    /// when neither is there (the recording was tracked without a registration).
    pub fn of(rec: &Recording, registration: Option<Registration>) -> Option<PoseSource> {
        match registration {
            Some(r) => Some(PoseSource::Registration(Box::new(r))),
            None if rec.frames.iter().any(|f| f.maxilla_scan_from_mandible_scan.is_some()) => {
                Some(PoseSource::Recorded)
            }
            None => None,
        }
    }

    /// [`PoseSource::of`], refusing a recording without scan poses when no registration is
    /// given, naming the flag that would give them.
    pub fn required(rec: &Recording, registration: Option<Registration>) -> Result<PoseSource, SessionError> {
        PoseSource::of(rec, registration).ok_or_else(|| {
            SessionError::NoScanPose(
                "no frame carries maxilla_scan_from_mandible_scan (the recording was tracked without a \
                 registration): give --registration reg.json (`jawtrack register` writes it)"
                    .into(),
            )
        })
    }

    /// [`PoseSource::of`] for a poses file (`jawtrack contacts --poses`): a file without a
    /// recording header (written by hand, e.g. an identity pose for scans exported in
    /// occlusion) gives the scans' pose as its `maxilla_from_mandible`; a tracked recording
    /// without scan poses is refused, since its poses are the markers'.
    pub fn for_poses_file(
        rec: &Recording,
        registration: Option<Registration>,
        path: &std::path::Path,
    ) -> Result<PoseSource, SessionError> {
        match PoseSource::of(rec, registration) {
            Some(s) => Ok(s),
            // Marker poses taken as scan poses put the arches tens of millimetres apart and
            // report "no contact" as a finding.
            None if rec.header.is_some() => Err(SessionError::NoScanPose(format!(
                "{}: its poses place the mandible's marker in the maxilla's marker, not the scans in occlusion; give \
                 --registration FILE (from `jawtrack register`), or track with --registration so that every frame \
                 carries maxilla_scan_from_mandible_scan",
                path.display()
            ))),
            None => Ok(PoseSource::Direct),
        }
    }

    /// The scans' pose at frame `f`, if it has one.
    pub fn pose(&self, f: &FrameRecord) -> Option<Pose> {
        match self {
            PoseSource::Registration(r) => f.maxilla_from_mandible.map(|m| r.maxilla_scan_from_mandible_scan(&m)),
            PoseSource::Recorded => f.maxilla_scan_from_mandible_scan,
            PoseSource::Direct => f.maxilla_from_mandible,
        }
    }

    /// Every frame of `rec` that has the scans' pose, in order.
    pub fn posed(&self, rec: &Recording) -> Vec<PosedFrame> {
        rec.frames.iter().filter_map(|f| self.pose(f).map(|p| (f.frame, f.t, p))).collect()
    }

    /// In words, for a summary.
    pub fn describe(&self) -> &'static str {
        match self {
            PoseSource::Registration(_) => "maxilla_from_mandible through the registration",
            PoseSource::Recorded => "the recorded maxilla_scan_from_mandible_scan",
            PoseSource::Direct => "maxilla_from_mandible as the lower scan's pose",
        }
    }
}
