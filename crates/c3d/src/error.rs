//! Why a set of tracks cannot be written as a C3D file, each message naming what to change.

use crate::{LABEL_WIDTH, MAX_DESCRIPTION_LEN, MAX_FRAMES, MAX_TRACKS};

/// A reason [`write`](fn@crate::write) refused its input. Nothing is written in part: the input is
/// checked whole before the first byte is produced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum C3dError {
    /// The slice of tracks was empty.
    #[error("no point tracks to write: pass at least one PointTrack")]
    NoTracks,

    /// More tracks than one POINT:LABELS array holds.
    #[error(
        "{count} point tracks is more than the {MAX_TRACKS} a C3D POINT:LABELS array holds: \
         write at most {MAX_TRACKS} tracks per file"
    )]
    TooManyTracks {
        /// How many tracks were passed.
        count: usize,
    },

    /// The rate was zero, negative, not finite or outside the range of a 32-bit float.
    #[error("frame rate {rate_hz} Hz is not a finite positive 32-bit float: pass the capture rate in hertz, e.g. 60.0")]
    BadRate {
        /// The rate that was passed.
        rate_hz: f64,
    },

    /// A track's label was empty (or all spaces, which readers trim to nothing).
    #[error("track {index} has an empty label: give every track a name of 1 to {LABEL_WIDTH} ASCII characters")]
    EmptyLabel {
        /// The track's index in the slice.
        index: usize,
    },

    /// A label did not fit the fixed width of POINT:LABELS.
    #[error(
        "track {index} label {label:?} is {len} bytes, longer than the {LABEL_WIDTH} of C3D POINT:LABELS: \
         shorten it to at most {LABEL_WIDTH} characters"
    )]
    LabelTooLong {
        /// The track's index in the slice.
        index: usize,
        /// The label as given.
        label: String,
        /// Its length in bytes.
        len: usize,
    },

    /// A label held a character outside printable ASCII.
    #[error(
        "track {index} label {label:?} has characters outside printable ASCII, which C3D text cannot carry: \
         use only ASCII letters, digits, punctuation and spaces"
    )]
    LabelNotAscii {
        /// The track's index in the slice.
        index: usize,
        /// The label as given.
        label: String,
    },

    /// Two tracks had the same label (after the trailing spaces readers trim).
    #[error(
        "tracks {first} and {second} are both labelled {label:?}: give each track its own label, \
         since readers look points up by label"
    )]
    DuplicateLabel {
        /// The label the two tracks share.
        label: String,
        /// The earlier track's index.
        first: usize,
        /// The later track's index.
        second: usize,
    },

    /// A description did not fit POINT:DESCRIPTIONS.
    #[error(
        "track {index} ({label:?}) description is {len} bytes, longer than the {MAX_DESCRIPTION_LEN} this writer \
         allows: shorten it to at most {MAX_DESCRIPTION_LEN} characters"
    )]
    DescriptionTooLong {
        /// The track's index in the slice.
        index: usize,
        /// The track's label.
        label: String,
        /// The description's length in bytes.
        len: usize,
    },

    /// A description held a character outside printable ASCII.
    #[error(
        "track {index} ({label:?}) description has characters outside printable ASCII, which C3D text cannot \
         carry: use only ASCII letters, digits, punctuation and spaces"
    )]
    DescriptionNotAscii {
        /// The track's index in the slice.
        index: usize,
        /// The track's label.
        label: String,
    },

    /// Two tracks had different numbers of frames.
    #[error(
        "track {index} ({label:?}) has {frames} frames but track 0 ({first_label:?}) has {expected}: \
         give every track one entry per frame, with None where the point is missing"
    )]
    LengthMismatch {
        /// The index of the track that differs from track 0.
        index: usize,
        /// Its label.
        label: String,
        /// Its number of frames.
        frames: usize,
        /// Track 0's label.
        first_label: String,
        /// Track 0's number of frames.
        expected: usize,
    },

    /// The tracks had no frames.
    #[error("the tracks have no frames: a C3D file needs at least one frame (use None for a missing point)")]
    NoFrames,

    /// More frames than the 16-bit frame fields of a C3D file count (see [`MAX_FRAMES`]).
    #[error(
        "{frames} frames is more than the {MAX_FRAMES} that a C3D file's 16-bit frame fields count \
         unambiguously: split the recording into files of at most {MAX_FRAMES} frames"
    )]
    TooManyFrames {
        /// How many frames the tracks have.
        frames: usize,
    },

    /// A present position had a coordinate that is not a finite 32-bit float.
    #[error(
        "track {index} ({label:?}) frame {frame} has {axis} = {value}, which is not a finite 32-bit float: \
         pass None for a missing position, or finite millimetres"
    )]
    NonFiniteCoordinate {
        /// The track's index in the slice.
        index: usize,
        /// The track's label.
        label: String,
        /// The 0-based index into the track's positions.
        frame: usize,
        /// Which coordinate: 'x', 'y' or 'z'.
        axis: char,
        /// The value as given.
        value: f64,
    },
}
