//! A small C3D writer: JawTrack's point tracks (millimetres, one entry per frame) as a C3D file,
//! the binary motion-capture format of biomechanics tools (<https://www.c3d.org/>). Its files are
//! checked against two independent readers, ezc3d and py-c3d (`tests/python_readers.rs`).
//!
//! What it writes, and no more:
//!
//! - Intel byte order (processor 84) and float storage (a negative scale, -1), in 512-byte blocks:
//!   the header in block 1, the parameters from block 2, then the data.
//! - Points only: no analog channels (`ANALOG:USED` = 0, `ANALOG:RATE` = 0) and no events.
//! - Parameters `POINT:USED`, `SCALE`, `RATE`, `DATA_START`, `FRAMES`, `LABELS` (fixed width
//!   [`LABEL_WIDTH`]), `DESCRIPTIONS`, `UNITS` = "mm", and `TRIAL:ACTUAL_START_FIELD` /
//!   `ACTUAL_END_FIELD`. Frames are numbered from 1.
//! - Each point of each frame as X, Y, Z and a residual word: 0 for a present point, -1 with
//!   zero coordinates for a missing one, which ezc3d reads as NaN coordinates and py-c3d as a
//!   residual of -1.
//!
//! Only the residuals 0 and -1 are written because they are the only ones the two common readers
//! agree on: py-c3d reads the 4th float and truncates it to an integer, while ezc3d reads the
//! same four bytes as two 16-bit integers (camera mask, then residual).
//!
//! [`write()`] checks its input whole and refuses, naming what to change, anything a C3D file
//! cannot hold faithfully: see [`C3dError`].
//!
//! # Examples
//!
//! ```
//! use jawtrack_c3d::{PointTrack, write};
//!
//! let incisor = PointTrack {
//!     label: "lower_incisor".into(),
//!     description: "Lower incisor tip".into(),
//!     positions: vec![Some([1.0, 2.0, 3.0]), None, Some([1.5, 2.0, 3.0])],
//! };
//! let bytes = write(&[incisor], 60.0)?;
//! assert_eq!(bytes.len() % 512, 0);
//! assert_eq!(bytes[1], 0x50); // the C3D key
//! assert_eq!(u16::from_le_bytes([bytes[8], bytes[9]]), 3); // last frame, 1-based
//!
//! let err = write(&[], 60.0).unwrap_err();
//! assert!(err.to_string().contains("pass at least one PointTrack"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod encode;
mod error;

pub use error::C3dError;

/// The fixed width of `POINT:LABELS`: every label is padded with spaces to this many characters.
pub const LABEL_WIDTH: usize = 32;
/// The longest description accepted; `POINT:DESCRIPTIONS` is as wide as the longest one given.
pub const MAX_DESCRIPTION_LEN: usize = 64;
/// The most tracks in one file: a C3D array dimension is one byte.
pub const MAX_TRACKS: usize = 255;
/// The most frames in one file. The header's last-frame field is 16 bits, and its top value is
/// out too: `POINT:FRAMES` = 65535 is the int16 -1 that ezc3d takes for "more frames than fit,
/// read to the end of the file", which then reads the final block's zero padding as extra
/// frames with present points at the origin.
pub const MAX_FRAMES: usize = 65534;

/// One named point over a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct PointTrack {
    /// The point's name in `POINT:LABELS`: 1 to [`LABEL_WIDTH`] printable ASCII characters,
    /// unique within a file.
    pub label: String,
    /// A longer human-readable name for `POINT:DESCRIPTIONS`: up to [`MAX_DESCRIPTION_LEN`]
    /// printable ASCII characters, possibly empty.
    pub description: String,
    /// The position in millimetres at each frame, `None` where the point was not seen.
    pub positions: Vec<Option<[f64; 3]>>,
}

/// The bytes of a C3D file holding `tracks`, sampled at `rate_hz` frames per second.
///
/// Every track must have the same number of frames (1 to [`MAX_FRAMES`]); coordinates are
/// stored as 32-bit floats, so a present coordinate must be finite as one.
///
/// # Errors
///
/// A [`C3dError`] naming the first problem found, before anything is encoded.
pub fn write(tracks: &[PointTrack], rate_hz: f64) -> Result<Vec<u8>, C3dError> {
    let frames = validate(tracks, rate_hz)?;
    Ok(encode::file(tracks, frames, rate_hz as f32))
}

/// The number of frames, once every limit of the format has been checked.
fn validate(tracks: &[PointTrack], rate_hz: f64) -> Result<u16, C3dError> {
    let Some(first) = tracks.first() else {
        return Err(C3dError::NoTracks);
    };
    if tracks.len() > MAX_TRACKS {
        return Err(C3dError::TooManyTracks { count: tracks.len() });
    }
    let rate32 = rate_hz as f32;
    if !(rate_hz.is_finite() && rate_hz > 0.0 && rate32.is_finite() && rate32 > 0.0) {
        return Err(C3dError::BadRate { rate_hz });
    }
    for (index, track) in tracks.iter().enumerate() {
        check_text(index, track)?;
    }
    check_unique_labels(tracks)?;
    let frames = first.positions.len();
    for (index, track) in tracks.iter().enumerate() {
        if track.positions.len() != frames {
            return Err(C3dError::LengthMismatch {
                index,
                label: track.label.clone(),
                frames: track.positions.len(),
                first_label: first.label.clone(),
                expected: frames,
            });
        }
    }
    if frames == 0 {
        return Err(C3dError::NoFrames);
    }
    if frames > MAX_FRAMES {
        return Err(C3dError::TooManyFrames { frames });
    }
    for (index, track) in tracks.iter().enumerate() {
        check_coordinates(index, track)?;
    }
    Ok(frames as u16)
}

/// Printable ASCII: C3D text is one byte a character, and readers trim it as ASCII.
fn printable(s: &str) -> bool {
    s.bytes().all(|b| b == b' ' || b.is_ascii_graphic())
}

fn check_text(index: usize, track: &PointTrack) -> Result<(), C3dError> {
    let label = &track.label;
    if !printable(label) {
        return Err(C3dError::LabelNotAscii { index, label: label.clone() });
    }
    if label.trim().is_empty() {
        return Err(C3dError::EmptyLabel { index });
    }
    if label.len() > LABEL_WIDTH {
        return Err(C3dError::LabelTooLong { index, label: label.clone(), len: label.len() });
    }
    let description = &track.description;
    if !printable(description) {
        return Err(C3dError::DescriptionNotAscii { index, label: label.clone() });
    }
    if description.len() > MAX_DESCRIPTION_LEN {
        return Err(C3dError::DescriptionTooLong { index, label: label.clone(), len: description.len() });
    }
    Ok(())
}

/// Readers drop the padding spaces, so labels that differ only in trailing spaces collide.
fn check_unique_labels(tracks: &[PointTrack]) -> Result<(), C3dError> {
    for (second, track) in tracks.iter().enumerate() {
        let label = track.label.trim_end();
        if let Some(first) = tracks[..second].iter().position(|t| t.label.trim_end() == label) {
            return Err(C3dError::DuplicateLabel { label: label.to_owned(), first, second });
        }
    }
    Ok(())
}

fn check_coordinates(index: usize, track: &PointTrack) -> Result<(), C3dError> {
    for (frame, position) in track.positions.iter().enumerate() {
        let Some(p) = position else { continue };
        for (axis, &value) in ['x', 'y', 'z'].into_iter().zip(p) {
            if !(value as f32).is_finite() {
                return Err(C3dError::NonFiniteCoordinate { index, label: track.label.clone(), frame, axis, value });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
