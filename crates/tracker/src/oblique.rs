//! Which tags a smeared frame does better without. Motion smears a tag seen face-on into
//! ramps the edge fit reads to a tenth of a pixel, but on a tag seen obliquely the smeared
//! edges merge with their neighbours and its corners land 0.3–3 px off
//! (`crates/detector-bench/BENCHMARKS.md`, "Motion blur"): one such tag beside two good ones
//! pulled a chewing jaw 0.1–0.2 mm.
//!
//! Dropping every oblique tag of a smeared frame is wrong too when the tags' places are only
//! assumed (the nominal model of a real print): each tag's placement error is its own, and
//! two tags average less of it than three — the nominal marker's chewing error grew by a fifth
//! when they were dropped (`crates/tracker-bench`, chew scene). So only where the face-on tags'
//! places were measured ([`Marker::measured_tags`]) is an oblique tag tried against the pose
//! of the face-on tags alone, and dropped when it misses that pose by more than
//! [`OBLIQUE_MISS_PX`] and by more than [`MISS_RATIO`] times what the face-on tags miss it by.

use jawtrack_marker::Marker;
use jawtrack_pose::{CameraIntrinsics, Observation, PnpOptions, Pose, solve_pnp};

/// Tags seen within this of face-on (°) are read well even smeared.
pub const FACE_ON_DEG: f64 = 50.0;
/// Tags seen beyond this (°) are tried against the face-on tags' pose in a smeared frame.
pub const OBLIQUE_DEG: f64 = 55.0;
/// Face-on tags a body must keep for its oblique ones to be tried.
const KEEP: usize = 2;
/// An oblique tag missing the face-on pose by less than this (RMS px) is kept.
pub const OBLIQUE_MISS_PX: f64 = 0.5;
/// … and one missing it by less than this many times the face-on tags' own RMS.
pub const MISS_RATIO: f64 = 3.0;

/// The angle (°) between tag `id`'s normal and the line of sight to its centre, seen through
/// `camera_from_body`; `None` for a tag not in the marker.
pub fn view_angle_deg(marker: &Marker, id: u32, camera_from_body: &Pose) -> Option<f64> {
    let (_, tag) = marker.find_tag(id)?;
    let [c0, c1, _, c3] = tag.corners;
    let normal = camera_from_body.rotation() * (c1 - c0).cross(&(c3 - c0)).normalize();
    let centre = camera_from_body.transform_point(&tag.center.into()).coords;
    Some((normal.dot(&centre).abs() / centre.norm()).clamp(0.0, 1.0).acos().to_degrees())
}

/// Of `tags` (one body's, solved as `camera_from_body`), the ones seen beyond [`OBLIQUE_DEG`]
/// when at least two are seen within [`FACE_ON_DEG`]; otherwise none.
pub fn oblique_tags(marker: &Marker, tags: &[u32], camera_from_body: &Pose) -> Vec<u32> {
    let angles: Vec<(u32, f64)> =
        tags.iter().filter_map(|&id| Some((id, view_angle_deg(marker, id, camera_from_body)?))).collect();
    if angles.iter().filter(|(_, a)| *a <= FACE_ON_DEG).count() < KEEP {
        return Vec::new();
    }
    angles.into_iter().filter(|(_, a)| *a > OBLIQUE_DEG).map(|(id, _)| id).collect()
}

/// Of one body's `tags` in a smeared frame (solved together as `camera_from_body` from
/// `observations`), the oblique ones that miss the pose of the others, when those others are
/// all among `measured` (ascending ids): see the module doc.
pub fn smeared_misfits(
    marker: &Marker,
    measured: &[u32],
    tags: &[u32],
    observations: &[Observation],
    camera_from_body: &Pose,
    camera: &CameraIntrinsics,
    pnp: &PnpOptions,
) -> Vec<u32> {
    let oblique = oblique_tags(marker, tags, camera_from_body);
    if oblique.is_empty() {
        return oblique;
    }
    let kept: Vec<u32> = tags.iter().copied().filter(|id| !oblique.contains(id)).collect();
    if !kept.iter().all(|id| measured.binary_search(id).is_ok()) {
        return Vec::new();
    }
    let others: Vec<Observation> = observations.iter().filter(|o| !oblique.contains(&o.tag)).cloned().collect();
    let Ok(face_on) = solve_pnp(&others, camera, Some(camera_from_body), pnp) else {
        return Vec::new();
    };
    let limit = OBLIQUE_MISS_PX.max(MISS_RATIO * tag_rms(&others, &kept, &face_on.camera_from_body, camera));
    oblique.into_iter().filter(|&id| tag_rms(observations, &[id], &face_on.camera_from_body, camera) > limit).collect()
}

/// The RMS reprojection error (px) of the corners of tags `ids` among `observations` through
/// `camera_from_body`; 0 for none, infinite when one falls behind the camera.
pub(crate) fn tag_rms(
    observations: &[Observation],
    ids: &[u32],
    camera_from_body: &Pose,
    camera: &CameraIntrinsics,
) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for o in observations.iter().filter(|o| ids.contains(&o.tag)) {
        let e = camera
            .project(&camera_from_body.transform_point(&o.body))
            .map_or(f64::INFINITY, |p| (p - o.pixel).norm_squared());
        sum += e;
        n += 1;
    }
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_marker::{BodyKind, PrintError};
    use nalgebra::{Point3, Vector2, Vector3};

    /// A mandible pose 120 mm ahead showing tags within 50° and beyond 55° of face-on, with
    /// its tags seen (below 75°) sorted by view angle.
    fn view(marker: &Marker) -> (Pose, Vec<(u32, f64)>) {
        for i in 0..400 {
            let a = f64::from(i);
            let rotvec = Vector3::new((a * 0.37).sin(), (a * 0.61).cos(), (a * 0.23).sin()) * (0.2 + (a * 0.013) % 2.5);
            let pose = Pose::from_axis_angle(rotvec, Vector3::new(0.0, 0.0, 120.0));
            let mut seen: Vec<(u32, f64)> = marker
                .body(BodyKind::Mandible)
                .expect("a mandible")
                .tags
                .iter()
                .map(|t| (t.id, view_angle_deg(marker, t.id, &pose).expect("its tag")))
                .filter(|(_, a)| *a < 75.0)
                .collect();
            seen.sort_by(|x, y| x.1.total_cmp(&y.1));
            let face_on = seen.iter().filter(|(_, a)| *a <= FACE_ON_DEG).count();
            if face_on >= 2 && seen.iter().any(|(_, a)| *a > OBLIQUE_DEG + 3.0) {
                return (pose, seen);
            }
        }
        panic!("no view of the mandible shows face-on and oblique tags");
    }

    fn observations(marker: &Marker, pose: &Pose, camera: &CameraIntrinsics, tags: &[u32]) -> Vec<Observation> {
        tags.iter()
            .flat_map(|&id| {
                let (_, tag) = marker.find_tag(id).expect("its tag");
                tag.corners.map(|c| {
                    let body = Point3::from(c);
                    let pixel = camera.project(&pose.transform_point(&body)).expect("in front");
                    Observation { tag: id, body, pixel }
                })
            })
            .collect()
    }

    #[test]
    fn an_oblique_tag_read_off_is_dropped_only_beside_measured_tags() {
        let camera = CameraIntrinsics::pinhole(1500.0, 1500.0, 959.5, 539.5);
        let nominal = Marker::default();
        let shift = PrintError { shift_x: 0.002, ..PrintError::default() };
        let ids: Vec<(u32, PrintError)> = (12..24).map(|id| (id, shift)).collect();
        let measured_marker = nominal.with_print_errors(&ids).expect("ids exist");
        let (pose, seen) = view(&measured_marker);
        let tags: Vec<u32> = seen.iter().map(|(id, _)| *id).collect();
        let (oblique, _) = *seen.last().expect("seen tags");
        let beyond: Vec<u32> = seen.iter().filter(|(_, a)| *a > OBLIQUE_DEG).map(|(id, _)| *id).collect();
        assert_eq!(oblique_tags(&measured_marker, &tags, &pose), beyond, "{seen:?}");
        let pnp = PnpOptions::default();
        let mut obs = observations(&measured_marker, &pose, &camera, &tags);
        let misfits =
            |m: &Marker, obs: &[Observation]| smeared_misfits(m, &m.measured_tags(), &tags, obs, &pose, &camera, &pnp);
        assert!(misfits(&measured_marker, &obs).is_empty(), "an exact read is kept");
        // Read 1.5 px off along x, as a smeared oblique tag is: dropped.
        for o in obs.iter_mut().filter(|o| o.tag == oblique) {
            o.pixel += Vector2::new(1.5, 0.0);
        }
        assert_eq!(misfits(&measured_marker, &obs), vec![oblique]);
        // The same read beside tags whose places are only assumed: kept.
        let assumed = observations(&nominal, &pose, &camera, &tags)
            .into_iter()
            .zip(&obs)
            .map(|(a, o)| Observation { pixel: o.pixel, ..a })
            .collect::<Vec<_>>();
        assert!(misfits(&nominal, &assumed).is_empty(), "a nominal marker keeps its oblique tags");
        // Read 0.2 px off: within what a good read misses by, kept.
        let mut slight = observations(&measured_marker, &pose, &camera, &tags);
        for o in slight.iter_mut().filter(|o| o.tag == oblique) {
            o.pixel += Vector2::new(0.2, 0.0);
        }
        assert!(misfits(&measured_marker, &slight).is_empty());
    }

    #[test]
    fn a_tag_facing_the_camera_is_seen_at_zero_degrees() {
        let marker = Marker::default();
        let (_, tag) = marker.find_tag(12).expect("tag 12");
        let [c0, c1, _, c3] = tag.corners;
        let normal = (c1 - c0).cross(&(c3 - c0)).normalize();
        // Turn the tag's normal onto the camera's axis and put its centre on that axis.
        let turn = nalgebra::UnitQuaternion::rotation_between(&normal, &-Vector3::z()).expect("not opposite");
        let centre = turn * tag.center;
        let pose = Pose::from_parts(turn, Vector3::new(0.0, 0.0, 100.0) - centre);
        assert!(view_angle_deg(&marker, 12, &pose).expect("tag 12") < 1e-6);
        assert!(view_angle_deg(&marker, 99, &pose).is_none());
    }
}
