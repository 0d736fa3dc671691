//! What a contact query cannot measure, said rather than hidden. Distances are known only in a
//! band, `max_depth_mm` deep into the other arch ([`ContactSettings`]): a vertex deeper than
//! that is not seen at all, so where the teeth pass further into each other the deepest contact
//! stops at the cap and areas come out too small, with nothing in the numbers to show it.
//! [`MeshEdges::passes_cap`] finds such a frame; [`SessionSummary::depth_warning`] and
//! [`SessionSummary::no_contact_warning`] say, in words, what a session's numbers cannot.

use crate::Mesh;
use crate::contacts::{ContactSettings, VertexDistances};
use crate::session::SessionSummary;
use std::collections::HashMap;

/// Per vertex of a mesh, the vertices it shares a triangle with.
#[derive(Debug, Clone, Default)]
pub struct MeshEdges {
    /// Where each vertex's neighbours begin in `neighbours` (one more than the vertices).
    starts: Vec<u32>,
    /// The neighbours, vertex after vertex (an edge of two triangles is listed twice).
    neighbours: Vec<u32>,
}

impl MeshEdges {
    /// The edges of `mesh`'s triangles, from both ends.
    pub fn of(mesh: &Mesh) -> MeshEdges {
        let mut starts = vec![0u32; mesh.vertices.len() + 1];
        for t in &mesh.triangles {
            t.iter().for_each(|&v| starts[v as usize + 1] += 2);
        }
        for v in 0..mesh.vertices.len() {
            starts[v + 1] += starts[v];
        }
        let mut next = starts.clone();
        let mut neighbours = vec![0u32; starts[mesh.vertices.len()] as usize];
        for &[a, b, c] in &mesh.triangles {
            for (v, others) in [(a, [b, c]), (b, [c, a]), (c, [a, b])] {
                for u in others {
                    neighbours[next[v as usize] as usize] = u;
                    next[v as usize] += 1;
                }
            }
        }
        MeshEdges { starts, neighbours }
    }

    fn around(&self, v: u32) -> &[u32] {
        let v = v as usize;
        self.starts.get(v..v + 2).map_or(&[], |s| &self.neighbours[s[0] as usize..s[1] as usize])
    }

    /// Whether the contacts of this edges' arch (`mesh`, its distances `found` at one pose)
    /// pass deeper into the other arch than `settings.max_depth_mm`.
    ///
    /// Every corner of a triangle in contact is looked up over the whole band, and left out of
    /// `found` when it lies beyond it: a gap wider than [`ContactSettings::above_mm`], or a
    /// penetration deeper than the cap. The signed distance changes by at most an edge's length
    /// along the edge, so a missing neighbour of a vertex at distance `d` whose edge is shorter
    /// than `above_mm − d` cannot lie above the band: it lies below, past the cap.
    pub fn passes_cap(&self, mesh: &Mesh, found: &VertexDistances, settings: &ContactSettings) -> bool {
        let (cap, above, t) = (settings.max_depth_mm, settings.above_mm(), settings.threshold_mm);
        let known: HashMap<u32, f32> = found.0.iter().copied().collect();
        let beyond = |d: f64| d <= -cap;
        found.0.iter().filter(|&&(_, d)| d as f64 <= t).any(|&(v, d)| {
            let d = d as f64;
            beyond(d)
                || self.around(v).iter().any(|&u| match known.get(&u) {
                    Some(&x) => beyond(x as f64),
                    None => {
                        let (p, q) = (mesh.vertices.get(v as usize), mesh.vertices.get(u as usize));
                        p.zip(q).is_some_and(|(p, q)| (q - p).norm() < above - d)
                    }
                })
        })
    }
}

impl SessionSummary {
    /// When some frame's contacts passed deeper than `settings.max_depth_mm`: that the depths
    /// and areas are too small there, and what to change.
    pub fn depth_warning(&self, settings: &ContactSettings) -> Option<String> {
        if self.beyond_max_depth == 0 {
            return None;
        }
        let deepest = self.deepest.map_or(String::new(), |d| {
            format!("; deepest measured {:.3} mm at frame {} (t {:.3} s)", d.depth_mm, d.frame, d.t)
        });
        Some(format!(
            "deepest contact reached --max-depth {} mm in {} of {} frames{deepest}: the teeth pass further into \
             each other than measured, so those frames' depths and areas are too small; raise --max-depth or check \
             the registration",
            settings.max_depth_mm, self.beyond_max_depth, self.frames
        ))
    }

    /// When no frame had any contact within `settings.threshold_mm`: the arches are never in
    /// occlusion, which a recording that includes the bite always is.
    pub fn no_contact_warning(&self, settings: &ContactSettings) -> Option<String> {
        (self.frames > 0 && self.with_contact == 0).then(|| {
            format!(
                "the arches never came within {} mm of each other in any of the {} frames checked: they are never in \
                 occlusion, yet a recording that includes the bite always touches; check that the scans and the poses \
                 belong together",
                settings.threshold_mm, self.frames
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contacts::{Arch, contacts};
    use crate::scenes;
    use crate::session::ContactSession;
    use jawtrack_pose::Pose;
    use nalgebra::{Point3, Vector3};

    /// A 3 mm ball pushed `depth` mm up through a downward-facing patch at z = 0, checked
    /// with a cap of `cap` mm; per frame, whether it passed the cap, and the session.
    fn pushed(depths: &[f64], cap: f64) -> (Vec<bool>, SessionSummary, ContactSettings) {
        let settings = ContactSettings { max_depth_mm: cap, ..ContactSettings::default() };
        let upper = Arch::new(vec![("patch".into(), scenes::patch(10.0, 60, 0.0, true))], &settings);
        let lower = Arch::new(vec![("ball".into(), scenes::sphere(Point3::new(0.0, 0.0, -3.0), 3.0, 60))], &settings);
        let mut session = ContactSession::new(&upper, &lower, settings);
        let frames = depths
            .iter()
            .enumerate()
            .map(|(k, &depth)| {
                let pose = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 0.0, depth));
                session.check(k as u64, k as f64 * 0.25, &pose).beyond_max_depth
            })
            .collect();
        (frames, session.summary(), settings)
    }

    #[test]
    fn edges_list_each_vertex_neighbours() {
        let square = Mesh {
            vertices: vec![
                Point3::origin(),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let edges = MeshEdges::of(&square);
        let mut around0 = edges.around(0).to_vec();
        around0.sort_unstable();
        assert_eq!(around0, [1, 2, 2, 3]);
        assert_eq!(edges.around(1), [2, 0]);
        assert!(edges.around(9).is_empty());
    }

    #[test]
    fn a_ball_through_the_plane_past_the_cap_is_flagged_and_one_within_it_is_not() {
        let (frames, summary, settings) = pushed(&[0.2, 0.45, 0.8, 1.5], 0.5);
        assert_eq!(frames, [false, false, true, true]);
        assert_eq!((summary.beyond_max_depth, summary.frames), (2, 4));
        let w = summary.depth_warning(&settings).expect("a warning");
        assert!(
            w.starts_with("deepest contact reached --max-depth 0.5 mm in 2 of 4 frames; deepest measured 0.")
                && w.ends_with(
                    "the teeth pass further into each other than measured, so those frames' depths and areas are \
                     too small; raise --max-depth or check the registration"
                ),
            "{w}"
        );
        // The same motion with a deeper cap measures it all.
        let (frames, summary, settings) = pushed(&[0.2, 0.45, 0.8, 1.5], 2.0);
        assert_eq!(frames, [false; 4]);
        assert_eq!(summary.depth_warning(&settings), None);
        assert!(summary.deepest.is_some_and(|d| (d.depth_mm - 1.5).abs() < 0.01), "{:?}", summary.deepest);
    }

    #[test]
    fn arches_never_in_contact_are_said_to_be_so() {
        let (_, apart, settings) = pushed(&[-1.0, -2.0], 0.5);
        let w = apart.no_contact_warning(&settings).expect("a warning");
        assert_eq!(
            w,
            "the arches never came within 0.1 mm of each other in any of the 2 frames checked: they are never in \
             occlusion, yet a recording that includes the bite always touches; check that the scans and the poses \
             belong together"
        );
        assert_eq!(apart.depth_warning(&settings), None);
        let (_, touching, settings) = pushed(&[-1.0, 0.05], 0.5);
        assert_eq!(touching.no_contact_warning(&settings), None);
        let (_, empty, settings) = pushed(&[], 0.5);
        assert_eq!(empty.no_contact_warning(&settings), None);
    }

    #[test]
    fn a_contact_within_the_cap_has_no_missing_deep_neighbour() {
        let settings = ContactSettings::default();
        let upper = Arch::new(vec![("patch".into(), scenes::patch(10.0, 60, 0.0, true))], &settings);
        let lower = Arch::new(vec![("ball".into(), scenes::sphere(Point3::new(0.0, 0.0, -3.0), 3.0, 60))], &settings);
        let edges = [MeshEdges::of(&upper.mesh), MeshEdges::of(&lower.mesh)];
        let pose = |depth| Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 0.0, depth));
        let passes = |depth| {
            let c = contacts(&upper, &lower, &pose(depth), &settings);
            [(&edges[0], &upper), (&edges[1], &lower)]
                .iter()
                .zip(&c.distances)
                .map(|((e, a), found)| e.passes_cap(&a.mesh, found, &settings))
                .collect::<Vec<_>>()
        };
        assert_eq!(passes(0.3), [false, false]);
        assert!(passes(1.0).contains(&true), "a millimetre through a 0.5 mm cap");
    }

    #[test]
    fn scan_like_arches_are_flagged_only_when_pushed_past_the_cap() {
        // Open surfaces with walls and rims, cells longer than the band is deep: 0.1 mm of
        // interpenetration at identity, 0.9 mm raised by 0.8 mm.
        let (u, l) = scenes::arch_pair_with_walls(8_000, 8.0);
        let settings = ContactSettings::default();
        let (upper, lower) = (Arch::new(vec![("u".into(), u)], &settings), Arch::new(vec![("l".into(), l)], &settings));
        let mut session = ContactSession::new(&upper, &lower, settings);
        let raised = |z: f64| Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 0.0, z));
        let flagged: Vec<bool> =
            [0.0, 0.3, 0.8].iter().map(|&z| session.check(0, 0.0, &raised(z)).beyond_max_depth).collect();
        assert_eq!(flagged, [false, false, true]);
    }
}
