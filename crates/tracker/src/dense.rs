//! How a body's pose is finished once solved from its tags' corners ([`PoseRefinement`]), and the
//! dense refinement's call ([`jawtrack_photometric`]) with what the tracker knows of the frame:
//! the tags the body was solved from, their edges' blur, the tone curve and the body's motion.

use crate::BodyResult;
use jawtrack_apriltag::Detection;
use jawtrack_marker::Marker;
use jawtrack_photometric::{Body, Image, Motion, Options, RefineError, Refined, Tag, refine};
use jawtrack_pose::{CameraIntrinsics, Pose, median};
use nalgebra::Point3;

/// How each body's pose is finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PoseRefinement {
    /// The pose that fits the tags' corners (PnP refined by Levenberg–Marquardt).
    #[default]
    Corners,
    /// That pose refined from every pixel of the body's tags ([`jawtrack_photometric`]): the
    /// tags' patterns, blurred by the lens and smeared by the body's motion over each row's
    /// exposure, compared with the image in linear light. A body whose refinement fails keeps
    /// its corner pose and is flagged `dense_failed`.
    Dense,
}

impl PoseRefinement {
    /// Every choice, as named on the command line.
    pub const ALL: [PoseRefinement; 2] = [PoseRefinement::Corners, PoseRefinement::Dense];

    /// Its name: `corners` or `dense`.
    pub fn name(self) -> &'static str {
        match self {
            PoseRefinement::Corners => "corners",
            PoseRefinement::Dense => "dense",
        }
    }
}

impl std::fmt::Display for PoseRefinement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for PoseRefinement {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        PoseRefinement::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| format!("unknown pose refinement '{s}' (choose corners or dense)"))
    }
}

/// The body's motion is modelled (its velocity smearing the tags over the exposure, its rows
/// read at their own times) only when its recent poses predicted this frame's within this (px,
/// the farthest tag corner): a jump between views, or a cut, misses by more. Chewing through a
/// 2× crop at 60 frames/s misses by more than 5 px at times (with 5 px, 12 of 74 bodies lost
/// their motion model and the chewing p95 grew fivefold, `jawtrack-bench dense`); a view jump
/// that happens to continue the last one's step is left to the image ([`jawtrack_photometric::refine`]
/// fits the body as still too and keeps the better fit).
pub(crate) const FORETOLD_PX: f64 = 20.0;

/// The farthest (px) any corner of `tags` lies between `predicted` and `solved`; infinite when
/// one cannot be projected.
pub(crate) fn miss_px(
    marker: &Marker,
    tags: &[u32],
    predicted: &Pose,
    solved: &Pose,
    camera: &CameraIntrinsics,
) -> f64 {
    let mut most: f64 = 0.0;
    for (_, tag) in tags.iter().filter_map(|&id| marker.find_tag(id)) {
        for c in &tag.corners {
            let p = Point3::from(*c);
            match (camera.project(&predicted.transform_point(&p)), camera.project(&solved.transform_point(&p))) {
                (Some(a), Some(b)) => most = most.max((a - b).norm()),
                _ => return f64::INFINITY,
            }
        }
    }
    most
}

/// `body`'s pose refined from its tags' pixels in `image`, each pass over them shared out tag by tag
/// over `threads` (the pool the call runs in, [`Options::threads`]).
pub(crate) fn refine_body(
    marker: &Marker,
    image: Image<'_>,
    camera: &CameraIntrinsics,
    body: &BodyResult,
    detections: &[Detection],
    motion: Option<Motion>,
    threads: usize,
) -> Result<Refined, RefineError> {
    let bitmaps: Vec<_> = body.tags.iter().filter_map(|&id| Some((id, marker.family.bitmap(id)?))).collect();
    let tags: Vec<Tag<'_>> = bitmaps
        .iter()
        .filter_map(|(id, bitmap)| {
            let (_, tag) = marker.find_tag(*id)?;
            Some(Tag { corners: tag.corners.map(|c| [c.x, c.y, c.z]), bitmap })
        })
        .collect();
    let blur_px = median(detections.iter().filter(|d| body.tags.contains(&d.id)).filter_map(|d| d.blur_px));
    let seen = Body { image, camera, tags: &tags, blur_px: blur_px.unwrap_or(0.0), motion };
    refine(&seen, &body.camera_from_body, &Options { threads, ..Options::default() })
}
