//! A contact session: the contacts of two arches over a motion, one frame at a time.
//!
//! [`ContactSession::check`] places the lower scan by a frame's
//! `maxilla_scan_from_mandible_scan` and returns that frame's [`FrameContacts`] (its regions,
//! areas and deepest contact: what a contacts log writes per frame). The session keeps what
//! the whole motion adds up to: the [`ContactMap`] (how often and how deep each vertex was in
//! contact), each frame's areas and depth, and the time of each contact query, summarised by
//! [`ContactSession::summary`].

use crate::contacts::{Arch, ContactMap, ContactSettings, Region, Side, contacts};
use crate::depth_cap::MeshEdges;
use jawtrack_pose::{Pose, median};
use serde::Serialize;
use std::time::Instant;

/// One value per arch, serialised as `{"maxilla": …, "mandible": …}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PerArch<T> {
    /// The upper arch's.
    pub maxilla: T,
    /// The lower arch's.
    pub mandible: T,
}

/// The contacts of one frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameContacts {
    /// The frame's number.
    pub frame: u64,
    /// Its time (s).
    pub t: f64,
    /// The deepest penetration over both arches (mm; negative: the smallest gap); `None`
    /// without any contact.
    pub max_depth_mm: Option<f64>,
    /// Total contact area on each arch (mm²).
    pub area_mm2: PerArch<f64>,
    /// The regions in contact on both arches, largest first.
    pub regions: Vec<Region>,
    /// Whether the arches pass deeper into each other than the depth measured
    /// ([`ContactSettings::max_depth_mm`]): `max_depth_mm` and the areas are then too small.
    /// Written only when true.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub beyond_max_depth: bool,
}

/// Statistics of one arch's total contact area per frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AreaStats {
    /// Frames with any contact area on the arch.
    pub frames_with_contact: usize,
    /// Mean area over the frames checked (mm²; 0 without frames).
    pub mean_mm2: f64,
    /// Median area (mm², the upper median for an even count).
    pub median_mm2: Option<f64>,
    /// Largest area (mm²).
    pub max_mm2: Option<f64>,
    /// The frame with the largest area (the last of equals).
    pub max_frame: Option<u64>,
    /// Its time (s).
    pub max_t: Option<f64>,
}

/// The deepest contact of a session.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Deepest {
    /// Deepest penetration (mm; negative: the smallest gap).
    pub depth_mm: f64,
    /// The frame where it was seen (the last of equals).
    pub frame: u64,
    /// Its time (s).
    pub t: f64,
}

/// What a session adds up to.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SessionSummary {
    /// Frames checked.
    pub frames: usize,
    /// Frames with any contact within the threshold.
    pub with_contact: usize,
    /// Frames where the arches interpenetrate.
    pub penetrating: usize,
    /// Per arch, its contact area per frame.
    pub contact_area: PerArch<AreaStats>,
    /// The deepest contact, if any.
    pub deepest: Option<Deepest>,
    /// Frames whose arches pass deeper into each other than the depth measured
    /// ([`FrameContacts::beyond_max_depth`]); [`SessionSummary::depth_warning`] says so.
    pub beyond_max_depth: usize,
    /// The depth shown in full red by [`ContactSession::depth_colours`] (mm): the deepest
    /// penetration, at least the threshold.
    pub depth_colour_full_scale_mm: f64,
    /// Median time of a frame's contact query (ms).
    pub query_ms_median: Option<f64>,
    /// Longest time of a frame's contact query (ms).
    pub query_ms_max: Option<f64>,
}

/// One frame as the session remembers it.
#[derive(Debug, Clone, Copy)]
struct Checked {
    frame: u64,
    t: f64,
    area_mm2: [f64; 2],
    max_depth_mm: Option<f64>,
    beyond_max_depth: bool,
}

/// The contacts of two arches over a motion; see the [module](self) documentation.
#[derive(Debug, Clone)]
pub struct ContactSession<'a> {
    upper: &'a Arch,
    lower: &'a Arch,
    settings: ContactSettings,
    /// Both arches' edges, to tell a contact cut off at the depth measured.
    edges: [MeshEdges; 2],
    map: ContactMap,
    checked: Vec<Checked>,
    query_ms: Vec<f64>,
}

impl<'a> ContactSession<'a> {
    /// An empty session of `upper` and `lower` (indexed with `settings`).
    pub fn new(upper: &'a Arch, lower: &'a Arch, settings: ContactSettings) -> Self {
        ContactSession {
            upper,
            lower,
            settings,
            edges: [MeshEdges::of(&upper.mesh), MeshEdges::of(&lower.mesh)],
            map: ContactMap::new(upper, lower),
            checked: Vec::new(),
            query_ms: Vec::new(),
        }
    }

    /// The contacts of frame `frame` at time `t` (s), with the lower scan at
    /// `maxilla_scan_from_mandible_scan`, added to the session.
    pub fn check(&mut self, frame: u64, t: f64, maxilla_scan_from_mandible_scan: &Pose) -> FrameContacts {
        let start = Instant::now();
        let c = contacts(self.upper, self.lower, maxilla_scan_from_mandible_scan, &self.settings);
        self.query_ms.push(start.elapsed().as_secs_f64() * 1e3);
        self.map.add(&c, &self.settings);
        let area = |side: Side| c.regions.iter().filter(|r| r.arch == side).map(|r| r.area_mm2).sum::<f64>();
        let area_mm2 = [area(Side::Maxilla), area(Side::Mandible)];
        let max_depth_mm = c.max_depth_mm();
        let arches = [(&self.edges[0], self.upper), (&self.edges[1], self.lower)];
        let beyond_max_depth =
            arches.iter().zip(&c.distances).any(|((e, a), found)| e.passes_cap(&a.mesh, found, &self.settings));
        self.checked.push(Checked { frame, t, area_mm2, max_depth_mm, beyond_max_depth });
        FrameContacts {
            frame,
            t,
            max_depth_mm,
            area_mm2: PerArch { maxilla: area_mm2[0], mandible: area_mm2[1] },
            regions: c.regions,
            beyond_max_depth,
        }
    }

    /// What counts as a contact.
    pub fn settings(&self) -> &ContactSettings {
        &self.settings
    }

    /// How often and how deep each vertex was in contact over the frames checked.
    pub fn map(&self) -> &ContactMap {
        &self.map
    }

    /// Per-vertex colours of one arch (0: upper, 1: lower) by how often it was in contact.
    pub fn frequency_colours(&self, arch: usize) -> Vec<[u8; 3]> {
        self.map.frequency_colours(arch)
    }

    /// Per-vertex colours of one arch (0: upper, 1: lower) by its deepest contact, full red at
    /// [`SessionSummary::depth_colour_full_scale_mm`].
    pub fn depth_colours(&self, arch: usize) -> Vec<[u8; 3]> {
        self.map.depth_colours(arch, &self.settings, self.full_depth_mm())
    }

    /// The deepest contact over the frames checked.
    fn deepest(&self) -> Option<Deepest> {
        self.checked
            .iter()
            .filter_map(|c| c.max_depth_mm.map(|depth_mm| Deepest { depth_mm, frame: c.frame, t: c.t }))
            .max_by(|a, b| a.depth_mm.total_cmp(&b.depth_mm))
    }

    /// Depth colours run up to the deepest penetration seen, at least the threshold, so that
    /// shallow contacts are not all full red.
    fn full_depth_mm(&self) -> f64 {
        self.deepest().map_or(0.0, |d| d.depth_mm).max(self.settings.threshold_mm)
    }

    /// Statistics of one arch's (0: upper, 1: lower) total contact area per frame.
    fn area_stats(&self, arch: usize) -> AreaStats {
        let areas: Vec<f64> = self.checked.iter().map(|c| c.area_mm2[arch]).collect();
        let n = areas.len().max(1) as f64;
        let largest = self.checked.iter().max_by(|a, b| a.area_mm2[arch].total_cmp(&b.area_mm2[arch]));
        AreaStats {
            frames_with_contact: areas.iter().filter(|&&a| a > 0.0).count(),
            mean_mm2: areas.iter().sum::<f64>() / n,
            median_mm2: median(areas.iter().copied()),
            max_mm2: largest.map(|c| c.area_mm2[arch]),
            max_frame: largest.map(|c| c.frame),
            max_t: largest.map(|c| c.t),
        }
    }

    /// What the frames checked so far add up to.
    pub fn summary(&self) -> SessionSummary {
        SessionSummary {
            frames: self.checked.len(),
            with_contact: self.checked.iter().filter(|c| c.max_depth_mm.is_some()).count(),
            penetrating: self.checked.iter().filter(|c| c.max_depth_mm.is_some_and(|d| d > 0.0)).count(),
            contact_area: PerArch { maxilla: self.area_stats(0), mandible: self.area_stats(1) },
            deepest: self.deepest(),
            beyond_max_depth: self.checked.iter().filter(|c| c.beyond_max_depth).count(),
            depth_colour_full_scale_mm: self.full_depth_mm(),
            query_ms_median: median(self.query_ms.iter().copied()),
            query_ms_max: self.query_ms.iter().copied().reduce(f64::max),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes;
    use nalgebra::{Point3, Vector3};

    /// A 3 mm sphere whose top is 0.2 mm through a downward-facing patch at z = 0, lowered
    /// by each `dz` in turn.
    fn lowered(dz: &[f64]) -> (Vec<FrameContacts>, SessionSummary, [Vec<[u8; 3]>; 2]) {
        let settings = ContactSettings::default();
        let upper = Arch::new(vec![("patch".into(), scenes::patch(10.0, 60, 0.0, true))], &settings);
        let lower = Arch::new(vec![("ball".into(), scenes::sphere(Point3::new(0.0, 0.0, -2.8), 3.0, 40))], &settings);
        let mut session = ContactSession::new(&upper, &lower, settings);
        let frames = dz
            .iter()
            .enumerate()
            .map(|(k, &dz)| {
                let pose = Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 0.0, dz));
                session.check(k as u64 + 10, k as f64 * 0.1, &pose)
            })
            .collect();
        (frames, session.summary(), [session.depth_colours(0), session.frequency_colours(1)])
    }

    #[test]
    fn a_sphere_lowered_out_of_a_plane_is_tallied_frame_by_frame() {
        let (frames, summary, _) = lowered(&[0.0, -0.1, -0.25, -0.5]);
        let depth: Vec<Option<f64>> = frames.iter().map(|f| f.max_depth_mm).collect();
        assert!((depth[0].unwrap_or_default() - 0.2).abs() < 1e-3, "{depth:?}");
        assert!((depth[2].unwrap_or_default() + 0.05).abs() < 1e-3, "{depth:?}");
        assert_eq!(depth[3], None);
        let areas: Vec<f64> = frames.iter().map(|f| f.area_mm2.mandible).collect();
        assert!(areas.windows(2).all(|w| w[1] < w[0]) && areas[3] == 0.0, "{areas:?}");
        for f in &frames {
            let on_patch: f64 = f.regions.iter().filter(|r| r.arch == Side::Maxilla).map(|r| r.area_mm2).sum();
            assert_eq!(f.area_mm2.maxilla, on_patch);
        }

        assert_eq!((summary.frames, summary.with_contact, summary.penetrating), (4, 3, 2));
        let deepest = summary.deepest.expect("a contact");
        assert_eq!((deepest.frame, deepest.t), (10, 0.0));
        assert_eq!(summary.depth_colour_full_scale_mm, deepest.depth_mm);
        let ball = summary.contact_area.mandible;
        assert_eq!((ball.frames_with_contact, ball.max_frame, ball.max_mm2), (3, Some(10), Some(areas[0])));
        assert_eq!(ball.mean_mm2, areas.iter().sum::<f64>() / 4.0);
        assert_eq!(ball.median_mm2, Some(areas[1]));
        assert!(summary.query_ms_median.is_some_and(|ms| ms >= 0.0));
    }

    #[test]
    fn without_penetration_depth_colours_run_up_to_the_threshold() {
        let (_, summary, [patch_depth, ball_frequency]) = lowered(&[-0.25]);
        assert_eq!(summary.penetrating, 0);
        assert_eq!(summary.depth_colour_full_scale_mm, ContactSettings::default().threshold_mm);
        assert!(patch_depth.iter().all(|&c| c == crate::contacts::GREY || c[0] == 0), "no red without penetration");
        assert!(ball_frequency.contains(&crate::contacts::ramp(1.0)), "in contact in the only frame");
    }

    #[test]
    fn an_empty_session_has_no_statistics() {
        let (frames, summary, _) = lowered(&[]);
        assert!(frames.is_empty());
        assert_eq!((summary.frames, summary.deepest, summary.query_ms_median), (0, None, None));
        assert_eq!(summary.contact_area.maxilla.mean_mm2, 0.0);
        assert_eq!(summary.contact_area.maxilla.max_frame, None);
    }
}
