//! Tags a body's pose does better without, dropped after it is solved: a tag that flickers into
//! view fitting far worse than the tags tracked before, and in a smeared frame an oblique tag
//! that misses the face-on tags' pose ([`crate::oblique`]).

use crate::oblique::{self, tag_rms};
use crate::{Tracker, slot};
use jawtrack_marker::BodyKind;
use jawtrack_pose::{BodyPose, CameraIntrinsics, Observation, Pose, solve_pnp};

impl Tracker {
    /// Drops a tag that just appeared beside tags tracked in the frame before and fits far
    /// worse than they do, and in a `smeared` frame an oblique tag that misses the face-on
    /// ones' pose ([`oblique`]), and solves again without them. Returns the pose and every tag
    /// dropped.
    pub(crate) fn drop_flicker(
        &self,
        kind: BodyKind,
        pose: BodyPose,
        mut observations: Vec<Observation>,
        camera: &CameraIntrinsics,
        prior: Option<&Pose>,
        smeared: bool,
    ) -> (BodyPose, Vec<u32>) {
        let mut rejected = pose.rejected_tags.clone();
        let before = &self.bodies[slot(kind)].tags;
        let (new, kept): (Vec<u32>, Vec<u32>) = pose.tags.iter().partition(|id| !before.contains(id));
        let error = |ids: &[u32]| tag_rms(&observations, ids, &pose.camera_from_body, camera);
        let settled = error(&kept);
        let mut flickers: Vec<u32> = match kept.is_empty() {
            true => Vec::new(),
            false => new.into_iter().filter(|&id| error(&[id]) > self.config.flicker_px.max(3.0 * settled)).collect(),
        };
        if smeared {
            let (pnp, body) = (&self.config.pnp, &pose.camera_from_body);
            let misfits =
                oblique::smeared_misfits(&self.marker, &self.measured, &pose.tags, &observations, body, camera, pnp);
            flickers.extend(misfits);
            flickers.sort_unstable();
            flickers.dedup();
        }
        if flickers.is_empty() {
            return (pose, rejected);
        }
        observations.retain(|o| !flickers.contains(&o.tag));
        match solve_pnp(&observations, camera, prior, &self.config.pnp) {
            Ok(again) => {
                rejected.extend(again.rejected_tags.iter().copied());
                rejected.extend(flickers);
                rejected.sort_unstable();
                rejected.dedup();
                (again, rejected)
            }
            Err(_) => (pose, rejected),
        }
    }
}
