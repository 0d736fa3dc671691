//! How a body's blur differs from tag to tag: by depth. A lens's defocus spreads a point over a
//! disc whose diameter is linear in inverse depth on either side of its focus, and a body's
//! visible tags lie millimetres apart in depth where a phone's depth of field is a few
//! millimetres deep. So each tag's σ is the body's plus one shared slope times how much nearer
//! than the tags' mean it is, in inverse depth: one parameter for the body, not one a tag (a
//! free blur per tag traded with the tags' sizes, `docs/dense.md`).

use crate::gather::TagPixels;
use jawtrack_pose::Pose;

/// Below this spread of the tags' inverse depths about their mean (a fraction), nothing in the
/// image tells how the blur grows with nearness ([`told`]).
const MIN_SPREAD: f64 = 1e-6;

/// Each tag's σ (px) at `pose`, `sigma_px + depth_blur · Δₖ` (at least `min_px`), and each
/// tag's Δₖ: its inverse depth over the tags' mean inverse depth, less 1 (so the Δ average 0
/// and σ's derivative by `depth_blur` is Δₖ). A tag at or behind the camera counts as at the
/// mean.
pub(crate) fn sigmas(
    tags: &[TagPixels],
    pose: &Pose,
    sigma_px: f64,
    depth_blur: f64,
    min_px: f64,
) -> (Vec<f64>, Vec<f64>) {
    let inverse: Vec<Option<f64>> = tags
        .iter()
        .map(|t| {
            let z = pose.transform_point(&t.centre.into()).z;
            (z > 0.0).then(|| 1.0 / z)
        })
        .collect();
    let ahead: Vec<f64> = inverse.iter().flatten().copied().collect();
    let mean = ahead.iter().sum::<f64>() / ahead.len().max(1) as f64;
    let delta: Vec<f64> = inverse.iter().map(|v| v.map_or(0.0, |v| v / mean - 1.0)).collect();
    let sigmas = delta.iter().map(|d| (sigma_px + depth_blur * d).max(min_px)).collect();
    (sigmas, delta)
}

/// Whether the tags' depths (their Δ from [`sigmas`]) differ enough to tell the slope.
pub(crate) fn told(delta: &[f64]) -> bool {
    delta.iter().any(|d| d.abs() > MIN_SPREAD)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Pattern;
    use jawtrack_tag_family::TagFamily;
    use nalgebra::{UnitQuaternion, Vector3};

    fn tag_at(centre: Vector3<f64>) -> TagPixels {
        TagPixels {
            pattern: Pattern::new(&TagFamily::TAG36H11.bitmap(0).expect("tag 0")).expect("fits"),
            centre,
            x: Vector3::x(),
            y: Vector3::y(),
            samples: Vec::new(),
        }
    }

    /// Two tags 190 and 210 mm away: the nearer is blurred more by a positive slope, by its
    /// share of the inverse-depth spread, and a lone tag tells nothing.
    #[test]
    fn a_nearer_tag_is_blurred_more_by_its_inverse_depth() {
        let pose = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.0, 200.0));
        let tags = [tag_at(Vector3::new(0.0, 0.0, -10.0)), tag_at(Vector3::new(5.0, 0.0, 10.0))];
        let (s, d) = sigmas(&tags, &pose, 1.0, 2.0, 0.1);
        let mean = (1.0 / 190.0 + 1.0 / 210.0) / 2.0;
        assert!((d[0] - (1.0 / 190.0 / mean - 1.0)).abs() < 1e-12, "{d:?}");
        assert!((d[0] + d[1]).abs() < 1e-12, "the Δ average 0: {d:?}");
        assert!((s[0] - (1.0 + 2.0 * d[0])).abs() < 1e-12 && s[0] > 1.0 && s[1] < 1.0, "{s:?}");
        assert!(told(&d));
        let (s, d) = sigmas(&tags[..1], &pose, 1.0, 2.0, 0.1);
        assert_eq!((s, told(&d)), (vec![1.0], false), "one tag: no slope");
        let (s, _) = sigmas(&tags, &pose, 0.05, -3.0, 0.1);
        assert!(s.iter().all(|&v| v >= 0.1), "never below the floor: {s:?}");
    }
}
