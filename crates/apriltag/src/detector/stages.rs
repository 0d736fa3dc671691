//! Where a detection's time goes, stage by stage: what a profile of the detector needs
//! ([`super::Detector::last_stages`]).

/// Where one detection's time went (s), stage by stage, and how much each stage passed on:
/// what a profile needs, kept by the detector for its last detection
/// ([`super::Detector::last_stages`]). Timing costs a clock read per stage. For tags looked for
/// where a tracker predicts them ([`super::Detector::confirm`]), each stage's time is summed
/// over the tags, whichever thread each ran on.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Decimation (and `quad_sigma`'s blur).
    pub decimate_s: f64,
    /// The adaptive threshold.
    pub threshold_s: f64,
    /// Connected components.
    pub components_s: f64,
    /// Gradient clusters.
    pub clusters_s: f64,
    /// Quad fitting.
    pub quads_s: f64,
    /// Per quad at full resolution: edge refit, decoding, the border fit.
    pub tags_s: f64,
    /// Removing duplicates, sorting, moving to JawTrack's pixel convention.
    pub finish_s: f64,
    /// Clusters found.
    pub clusters: usize,
    /// Quads tried (given the per-quad work), or predicted: those fitted but for the ones
    /// passed over (shorter than [`super::Search::min_quad_px`], or a decoded tag's data cells).
    pub quads: usize,
    /// Of `quads`, those a tracker predicted ([`super::Detector::confirm`]) rather than the
    /// image stages found.
    pub predicted: usize,
    /// Tags decoded.
    pub tags: usize,
    /// The decimation quads were found at (of the later search, summed; 0 for predicted quads).
    pub quad_decimate: f32,
}

impl std::ops::Add for StageTimes {
    type Output = StageTimes;

    fn add(self, o: StageTimes) -> StageTimes {
        StageTimes {
            decimate_s: self.decimate_s + o.decimate_s,
            threshold_s: self.threshold_s + o.threshold_s,
            components_s: self.components_s + o.components_s,
            clusters_s: self.clusters_s + o.clusters_s,
            quads_s: self.quads_s + o.quads_s,
            tags_s: self.tags_s + o.tags_s,
            finish_s: self.finish_s + o.finish_s,
            clusters: self.clusters + o.clusters,
            quads: self.quads + o.quads,
            predicted: self.predicted + o.predicted,
            tags: self.tags + o.tags,
            quad_decimate: o.quad_decimate,
        }
    }
}

impl StageTimes {
    /// All stages.
    pub fn total_s(&self) -> f64 {
        self.decimate_s
            + self.threshold_s
            + self.components_s
            + self.clusters_s
            + self.quads_s
            + self.tags_s
            + self.finish_s
    }
}

/// Lap times.
pub(super) struct Clock(std::time::Instant);

impl Clock {
    pub(super) fn start() -> Self {
        Clock(std::time::Instant::now())
    }

    /// Seconds since the last lap (or the start).
    pub(super) fn lap(&mut self) -> f64 {
        let now = std::time::Instant::now();
        let s = (now - self.0).as_secs_f64();
        self.0 = now;
        s
    }
}
