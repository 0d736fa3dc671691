//! [`DynamicsError`]: why dynamics could not be computed.

/// Why dynamics could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// An option is out of range.
    #[error("invalid dynamics option: {0}")]
    Options(String),
    /// The target path has no samples.
    #[error("the target path is empty: it needs at least one (time, pose) sample")]
    EmptyTarget,
    /// A target sample is not after the one before it.
    #[error("target sample {index}: its time {time_s} s is not after the previous sample's {previous_s} s")]
    NonIncreasingTime {
        /// The sample.
        index: usize,
        /// Its time (s).
        time_s: f64,
        /// The previous sample's time (s).
        previous_s: f64,
    },
    /// A target sample's time or pose has a NaN or infinity.
    #[error("target sample {index}: its time or pose is not finite")]
    NonFinite {
        /// The sample.
        index: usize,
    },
    /// The starting pose has a NaN or infinity.
    #[error("the pose to resolve is not finite")]
    NonFinitePose,
    /// The lower arch's mesh has no area, hence no centre of mass or inertia.
    #[error("the lower arch has no area, so it has no centre of mass or inertia")]
    DegenerateMesh,
    /// The distance indexes do not reach far enough for the tolerance.
    #[error(
        "the arches' distance indexes reach {reach_mm} mm, too little for a {tolerance_mm} mm tolerance (build them with a reach of at least {needed_mm} mm)"
    )]
    ShortReach {
        /// The smaller of the two indexes' reach (mm).
        reach_mm: f64,
        /// The tolerance (mm).
        tolerance_mm: f64,
        /// The least reach that works (mm).
        needed_mm: f64,
    },
    /// One step moved the arch so far that penetration could go unseen.
    #[error(
        "at t = {t_s:.4} s the lower arch moved up to {moved_mm:.3} mm in one step, more than half the distance indexes' reach ({reach_mm} mm): use a shorter step or arches with a longer reach"
    )]
    TooFast {
        /// When (s).
        t_s: f64,
        /// The bound on any vertex's displacement in the step (mm).
        moved_mm: f64,
        /// The indexes' reach (mm).
        reach_mm: f64,
    },
    /// Penetration remained deeper than the tolerance after the allowed projection rounds.
    #[error(
        "{at}: {depth_mm:.4} mm of penetration remained after {iterations} projection rounds (tolerance {tolerance_mm} mm)"
    )]
    Unresolved {
        /// Where: "at maximal intercuspation" or "at t = … s".
        at: String,
        /// The deepest remaining penetration (mm).
        depth_mm: f64,
        /// Rounds done.
        iterations: usize,
        /// The tolerance (mm).
        tolerance_mm: f64,
    },
}
