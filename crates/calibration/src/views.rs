//! Which frames of a marker turned before the camera are new views of it, for a calibration
//! fed live (the phone's) rather than from a chosen set of frames.
//!
//! At 30–60 fps neighbouring frames repeat one another, and a view counted per frame would
//! make "three views" a tenth of a second of the marker held still. So a frame adds a view of a
//! body only when the body has turned by at least [`MIN_TURN_DEG`] from every view of it kept
//! so far, or shows a tag that no view kept within that turn showed: views count the angles a
//! tag was seen from, which is what places it.

use crate::{CalibrationFrame, SeenTag};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::CameraIntrinsics;
use nalgebra::UnitQuaternion;

/// How far a body must turn (°) from every view of it kept for a frame to add another view
/// (unless it shows a tag those views did not).
pub const MIN_TURN_DEG: f64 = 5.0;

/// What a frame gave one body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewOutcome {
    /// A new view of the body.
    Added,
    /// Fewer than two of its tags: one tag alone says nothing about where the others sit.
    TooFewTags,
    /// Seen like this already: within [`MIN_TURN_DEG`] of a view kept, which showed the same
    /// tags.
    SameView,
    /// Two tags or more, but the body was not solved, so its turn is unknown.
    NotTracked,
}

/// A frame's outcome for one body of the marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BodyOutcome {
    /// The body.
    pub body: BodyKind,
    /// What the frame gave it.
    pub outcome: ViewOutcome,
    /// Its tags the frame showed.
    pub tags_seen: usize,
}

/// A view of one body kept: its turn and the tags it showed (sorted).
#[derive(Debug, Clone)]
struct KeptView {
    rotation: UnitQuaternion<f64>,
    ids: Vec<u32>,
}

/// The views kept so far of each body of a marker.
///
/// # Examples
///
/// ```
/// use jawtrack_calibration::{SeenTag, ViewOutcome, ViewSelector};
/// use jawtrack_marker::{BodyKind, Marker};
/// use jawtrack_pose::CameraIntrinsics;
/// use nalgebra::UnitQuaternion;
///
/// let marker = Marker::default();
/// let mut views = ViewSelector::new(&marker);
/// let camera = CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5);
/// let tags = [SeenTag { id: 0, corners: [[0.0; 2]; 4] }, SeenTag { id: 1, corners: [[0.0; 2]; 4] }];
/// let turned = |deg: f64| [(BodyKind::Maxilla, UnitQuaternion::from_euler_angles(0.0, deg.to_radians(), 0.0))];
/// let (first, frame) = views.offer(camera, &tags, &turned(0.0));
/// assert_eq!(first[0].outcome, ViewOutcome::Added);
/// assert_eq!(frame.map(|f| f.tags.len()), Some(2));
/// // Two degrees on, the same two tags: the same view.
/// assert_eq!(views.offer(camera, &tags, &turned(2.0)).0[0].outcome, ViewOutcome::SameView);
/// assert_eq!(views.offer(camera, &tags, &turned(6.0)).0[0].outcome, ViewOutcome::Added);
/// assert_eq!(views.tag_views(BodyKind::Maxilla, 0), 2);
/// ```
#[derive(Debug, Clone)]
pub struct ViewSelector {
    /// The marker's bodies, in its order, with their tags' ids.
    bodies: Vec<(BodyKind, Vec<u32>)>,
    /// Per body, the views kept.
    kept: Vec<Vec<KeptView>>,
}

impl ViewSelector {
    /// No views yet of `marker`'s bodies.
    pub fn new(marker: &Marker) -> Self {
        let bodies: Vec<(BodyKind, Vec<u32>)> =
            marker.bodies.iter().map(|b| (b.kind, b.tags.iter().map(|t| t.id).collect())).collect();
        ViewSelector { kept: vec![Vec::new(); bodies.len()], bodies }
    }

    /// Offers a frame: `tags` detected by `camera`, with the turn of each body solved in it.
    /// Returns what it gave each body (in the marker's order) and, when it added a view of any,
    /// the calibration frame of those bodies' tags.
    pub fn offer(
        &mut self,
        camera: CameraIntrinsics,
        tags: &[SeenTag],
        rotations: &[(BodyKind, UnitQuaternion<f64>)],
    ) -> (Vec<BodyOutcome>, Option<CalibrationFrame>) {
        let mut added = Vec::new();
        let mut outcomes = Vec::new();
        for ((kind, body_ids), kept) in self.bodies.iter().zip(&mut self.kept) {
            let mut seen: Vec<&SeenTag> = tags.iter().filter(|s| body_ids.contains(&s.id)).collect();
            seen.sort_by_key(|s| s.id);
            seen.dedup_by_key(|s| s.id);
            let ids: Vec<u32> = seen.iter().map(|s| s.id).collect();
            let rotation = rotations.iter().find(|(k, _)| k == kind).map(|(_, r)| r);
            let outcome = match rotation {
                _ if ids.len() < 2 => ViewOutcome::TooFewTags,
                None => ViewOutcome::NotTracked,
                Some(rotation) => {
                    let near = |k: &KeptView| k.rotation.angle_to(rotation).to_degrees() < MIN_TURN_DEG;
                    let covered = |k: &KeptView| ids.iter().all(|id| k.ids.binary_search(id).is_ok());
                    if kept.iter().any(|k| near(k) && covered(k)) {
                        ViewOutcome::SameView
                    } else {
                        kept.push(KeptView { rotation: *rotation, ids: ids.clone() });
                        added.extend(seen.iter().map(|s| **s));
                        ViewOutcome::Added
                    }
                }
            };
            outcomes.push(BodyOutcome { body: *kind, outcome, tags_seen: ids.len() });
        }
        let frame = (!added.is_empty()).then_some(CalibrationFrame { camera, tags: added });
        (outcomes, frame)
    }

    /// Views kept of `body`.
    pub fn views(&self, body: BodyKind) -> usize {
        self.index(body).map_or(0, |b| self.kept[b].len())
    }

    /// Views kept of `body` that showed tag `id`.
    pub fn tag_views(&self, body: BodyKind, id: u32) -> usize {
        self.index(body).map_or(0, |b| self.kept[b].iter().filter(|k| k.ids.binary_search(&id).is_ok()).count())
    }

    fn index(&self, body: BodyKind) -> Option<usize> {
        self.bodies.iter().position(|(k, _)| *k == body)
    }
}
