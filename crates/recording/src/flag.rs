//! Quality flags and their names: the one place a flag is named, for the tracker that raises
//! it, the recording that stores it and the datagram that carries it as a bit.

use jawtrack_marker::BodyKind;

/// Something to know about a frame's result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flag {
    /// No tag of the marker was found.
    NoTags,
    /// A body has no tag in view (or too few points): no pose.
    Lost(BodyKind),
    /// A body is seen through a single tag: its pose rests on four points.
    SingleTag(BodyKind),
    /// A body's single-tag pose has a mirror solution and nothing to choose by.
    Ambiguous(BodyKind),
    /// A body's reprojection error is above the tracker's `max_rms_px`.
    HighReprojectionError(BodyKind),
    /// Some of a body's tags disagreed with the rest and were dropped.
    RejectedTags(BodyKind),
    /// The frame could not be decoded or tracked (a damaged image file, a frame of another
    /// size): it was skipped, and its line holds no pose.
    Unreadable,
    /// A body's pose rests on a tag that the marker's calibration left at its nominal place
    /// (raised only with a calibrated marker: with a nominal one every tag is nominal alike).
    UncalibratedTag(BodyKind),
    /// A body's tags are out of focus: their edges are blurred beyond what its pose can stand
    /// (the phone is nearer than its lens can focus, or far from where focus was locked). The
    /// frame gives no jaw pose.
    Defocused(BodyKind),
    /// A body's dense (photometric) refinement was asked for and failed (did not converge, or
    /// strayed from the corner pose): its pose is the corners'.
    DenseFailed(BodyKind),
}

impl Flag {
    /// Every flag, in the order of their datagram bits (`docs/wire.md`): a flag added later
    /// goes at the end.
    pub const ALL: [Flag; 18] = [
        Flag::NoTags,
        Flag::Lost(BodyKind::Maxilla),
        Flag::Lost(BodyKind::Mandible),
        Flag::SingleTag(BodyKind::Maxilla),
        Flag::SingleTag(BodyKind::Mandible),
        Flag::Ambiguous(BodyKind::Maxilla),
        Flag::Ambiguous(BodyKind::Mandible),
        Flag::HighReprojectionError(BodyKind::Maxilla),
        Flag::HighReprojectionError(BodyKind::Mandible),
        Flag::RejectedTags(BodyKind::Maxilla),
        Flag::RejectedTags(BodyKind::Mandible),
        Flag::Unreadable,
        Flag::UncalibratedTag(BodyKind::Maxilla),
        Flag::UncalibratedTag(BodyKind::Mandible),
        Flag::Defocused(BodyKind::Maxilla),
        Flag::Defocused(BodyKind::Mandible),
        Flag::DenseFailed(BodyKind::Maxilla),
        Flag::DenseFailed(BodyKind::Mandible),
    ];

    /// A short machine-readable name, e.g. `mandible:lost`.
    pub fn name(&self) -> String {
        match self {
            Flag::NoTags => "no_tags".into(),
            Flag::Lost(b) => format!("{b}:lost"),
            Flag::SingleTag(b) => format!("{b}:single_tag"),
            Flag::Ambiguous(b) => format!("{b}:ambiguous"),
            Flag::HighReprojectionError(b) => format!("{b}:high_reprojection_error"),
            Flag::RejectedTags(b) => format!("{b}:rejected_tags"),
            Flag::Unreadable => "unreadable".into(),
            Flag::UncalibratedTag(b) => format!("{b}:uncalibrated_tag"),
            Flag::Defocused(b) => format!("{b}:defocused"),
            Flag::DenseFailed(b) => format!("{b}:dense_failed"),
        }
    }

    /// The flag of a name, or `None` for a name this build does not know (from a newer writer).
    pub fn from_name(name: &str) -> Option<Flag> {
        Flag::ALL.into_iter().find(|f| f.name() == name)
    }
}

impl std::fmt::Display for Flag {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_is_unique_and_reads_back() {
        for f in Flag::ALL {
            assert_eq!(Flag::from_name(&f.name()), Some(f), "{f}");
        }
        let mut names: Vec<String> = Flag::ALL.iter().map(Flag::name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), Flag::ALL.len());
        assert_eq!(Flag::from_name("maxilla:from_the_future"), None);
    }

    #[test]
    fn names_are_the_recorded_ones() {
        assert_eq!(Flag::NoTags.name(), "no_tags");
        assert_eq!(Flag::Lost(BodyKind::Mandible).name(), "mandible:lost");
        assert_eq!(Flag::HighReprojectionError(BodyKind::Maxilla).name(), "maxilla:high_reprojection_error");
        assert_eq!(Flag::UncalibratedTag(BodyKind::Mandible).name(), "mandible:uncalibrated_tag");
        // Bits are never renumbered: the newest flags come last.
        assert_eq!(Flag::ALL[11], Flag::Unreadable);
        assert_eq!(Flag::ALL[12..14], [BodyKind::Maxilla, BodyKind::Mandible].map(Flag::UncalibratedTag));
        assert_eq!(Flag::ALL[14..16], [BodyKind::Maxilla, BodyKind::Mandible].map(Flag::Defocused));
        assert_eq!(Flag::ALL[16..], [BodyKind::Maxilla, BodyKind::Mandible].map(Flag::DenseFailed));
        assert_eq!(Flag::Defocused(BodyKind::Maxilla).name(), "maxilla:defocused");
    }
}
