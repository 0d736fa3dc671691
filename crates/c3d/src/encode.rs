//! The bytes of a C3D file from tracks already checked by [`crate::write()`]: the header block,
//! the parameter section and the float data section, all little-endian (Intel, processor 84).

use crate::{LABEL_WIDTH, PointTrack};

/// Every section of a C3D file starts on a 512-byte block; blocks are numbered from 1.
pub(crate) const BLOCK: usize = 512;
/// The check byte after the parameter block number, in the header and the parameter section.
pub(crate) const KEY: u8 = 0x50;
/// The processor byte of the parameter section for Intel (little-endian IEEE) files.
pub(crate) const PROCESSOR_INTEL: u8 = 84;
/// The header's "4-character event labels" key (12345 = 0x3039).
pub(crate) const EVENT_LABELS_KEY: u16 = 0x3039;
/// A negative scale means float storage; its magnitude, 1, leaves residuals unscaled.
pub(crate) const POINT_SCALE: f32 = -1.0;
/// The parameter section follows the header, in block 2.
const PARAMETER_BLOCK: u8 = 2;
/// The 4th data word of a missing point. As a float it is -1 (py-c3d reads the float, truncates
/// it and takes a negative value as invalid); as two 16-bit words it is 0 then 0xBF80 = -16512,
/// which ezc3d reads as camera mask 0 and a negative residual, the Vicon/Qualisys "missing".
pub(crate) const MISSING_RESIDUAL: f32 = -1.0;

const GROUP_POINT: i8 = 1;
const GROUP_ANALOG: i8 = 2;
const GROUP_TRIAL: i8 = 3;

/// The whole file for `frames` frames of `tracks` at `rate` Hz.
pub(crate) fn file(tracks: &[PointTrack], frames: u16, rate: f32) -> Vec<u8> {
    // DATA_START is a fixed-size int16, so the section's length does not depend on its value:
    // lay it out once to count the blocks, then again with the real start.
    let blocks = parameter_section(tracks, frames, rate, 0).len() / BLOCK;
    // At most 255 blocks (see parameter_section), so the start block fits 16 bits.
    let data_start = (PARAMETER_BLOCK as usize + blocks) as u16;
    let points = tracks.len() as u16;

    let mut out = header(points, frames, data_start, rate);
    out.extend(parameter_section(tracks, frames, rate, data_start));
    debug_assert_eq!(out.len(), (data_start as usize - 1) * BLOCK);
    out.extend(data_section(tracks, frames));
    out
}

/// Block 1: where the parameters and data start, the point count, the frame range, the scale
/// and the rate. The rest (reserved words and an empty event table) stays zero.
fn header(points: u16, frames: u16, data_start: u16, rate: f32) -> Vec<u8> {
    let mut h = vec![0; BLOCK];
    h[0] = PARAMETER_BLOCK;
    h[1] = KEY;
    put(&mut h, 2, &points.to_le_bytes());
    // Word 3: analog measurements per frame, 0 (no analog data).
    put(&mut h, 6, &1u16.to_le_bytes()); // first frame, 1-based
    put(&mut h, 8, &frames.to_le_bytes()); // last frame
    // Word 6: maximum interpolation gap, 0 (this writer fills no gaps).
    put(&mut h, 12, &POINT_SCALE.to_le_bytes());
    put(&mut h, 16, &data_start.to_le_bytes());
    // Word 10: analog samples per point frame, 0, matching ANALOG:RATE = 0.
    put(&mut h, 20, &rate.to_le_bytes());
    put(&mut h, 298, &EVENT_LABELS_KEY.to_le_bytes());
    // Word 151 on: 0 events, so the event times, flags and labels stay zero.
    h
}

fn put(buf: &mut [u8], at: usize, bytes: &[u8]) {
    buf[at..at + bytes.len()].copy_from_slice(bytes);
}

/// The parameter section: its 4-byte header, the POINT, ANALOG and TRIAL groups, zero-padded
/// to whole blocks.
fn parameter_section(tracks: &[PointTrack], frames: u16, rate: f32, data_start: u16) -> Vec<u8> {
    let mut r = Records::default();
    let labels: Vec<&str> = tracks.iter().map(|t| t.label.as_str()).collect();
    let descriptions: Vec<&str> = tracks.iter().map(|t| t.description.as_str()).collect();
    let description_width = descriptions.iter().map(|d| d.len()).max().unwrap_or(0).max(1);

    r.group(GROUP_POINT, "POINT", "3-D point parameters");
    r.param(GROUP_POINT, "USED", "Number of points per frame", &Value::Int(&[tracks.len() as u16]));
    r.param(GROUP_POINT, "SCALE", "Negative: float storage", &Value::Float(POINT_SCALE));
    r.param(GROUP_POINT, "RATE", "Frames per second", &Value::Float(rate));
    r.param(GROUP_POINT, "DATA_START", "First block of the data", &Value::Int(&[data_start]));
    r.param(GROUP_POINT, "FRAMES", "Number of frames", &Value::Int(&[frames]));
    r.param(GROUP_POINT, "LABELS", "Point labels", &Value::Strings(LABEL_WIDTH, &labels));
    r.param(GROUP_POINT, "DESCRIPTIONS", "Point descriptions", &Value::Strings(description_width, &descriptions));
    r.param(GROUP_POINT, "UNITS", "Unit of the coordinates", &Value::Text("mm"));

    r.group(GROUP_ANALOG, "ANALOG", "Analog data parameters");
    r.param(GROUP_ANALOG, "USED", "Number of analog channels", &Value::Int(&[0]));
    r.param(GROUP_ANALOG, "RATE", "Analog samples per second", &Value::Float(0.0));

    // The frame range as two 16-bit words (low, high), which py-c3d prefers to the header's.
    r.group(GROUP_TRIAL, "TRIAL", "Trial parameters");
    r.param(GROUP_TRIAL, "ACTUAL_START_FIELD", "First frame", &Value::Int(&[1, 0]));
    r.param(GROUP_TRIAL, "ACTUAL_END_FIELD", "Last frame", &Value::Int(&[frames, 0]));

    let records = r.finish();
    let blocks = (4 + records.len()).div_ceil(BLOCK);
    // The track, label and description limits keep the section to a few dozen blocks.
    debug_assert!(blocks <= u8::MAX as usize);
    let mut out = Vec::with_capacity(blocks * BLOCK);
    out.extend([1, KEY, blocks as u8, PROCESSOR_INTEL]);
    out.extend(records);
    out.resize(blocks * BLOCK, 0);
    out
}

/// A parameter's value, by C3D type.
enum Value<'a> {
    /// Type 2 (16-bit integers): one is a scalar (no dimensions), more a 1-D array. Stored as bit
    /// patterns so 32768..=65534 frames keep the unsigned reading of the C3D manual.
    Int(&'a [u16]),
    /// Type 4, a scalar 32-bit float.
    Float(f32),
    /// Type -1, one string: 1 dimension, its length.
    Text(&'a str),
    /// Type -1, strings space-padded to a fixed width: dimensions (width, count).
    Strings(usize, &'a [&'a str]),
}

/// The group and parameter records, each pointing to the next by its offset field.
#[derive(Default)]
struct Records {
    bytes: Vec<u8>,
    /// Where the last record's offset field is, to zero it at the end.
    last_offset_at: usize,
}

impl Records {
    /// A group record: a negative id, the name, the offset to the next record, the description.
    fn group(&mut self, id: i8, name: &str, description: &str) {
        self.start(-id, name);
        let offset = 2 + 1 + description.len();
        self.bytes.extend((offset as i16).to_le_bytes());
        self.description(description);
    }

    /// A parameter record: its group's positive id, the name, the offset to the next record,
    /// the type, the dimensions, the data and the description.
    fn param(&mut self, group: i8, name: &str, description: &str, value: &Value) {
        let (kind, dims, data): (i8, Vec<u8>, Vec<u8>) = match value {
            Value::Int(values) => {
                let dims = if values.len() == 1 { vec![] } else { vec![values.len() as u8] };
                (2, dims, values.iter().flat_map(|v| v.to_le_bytes()).collect())
            }
            Value::Float(v) => (4, vec![], v.to_le_bytes().to_vec()),
            Value::Text(s) => (-1, vec![s.len() as u8], s.as_bytes().to_vec()),
            Value::Strings(width, items) => {
                let mut data = Vec::with_capacity(width * items.len());
                for s in *items {
                    data.extend(s.bytes());
                    data.resize(data.len() + width - s.len(), b' ');
                }
                (-1, vec![*width as u8, items.len() as u8], data)
            }
        };
        self.start(group, name);
        let offset = 2 + 1 + 1 + dims.len() + data.len() + 1 + description.len();
        debug_assert!(offset <= i16::MAX as usize);
        self.bytes.extend((offset as i16).to_le_bytes());
        self.bytes.push(kind as u8);
        self.bytes.push(dims.len() as u8);
        self.bytes.extend(dims);
        self.bytes.extend(data);
        self.description(description);
    }

    /// The name length (positive: not locked), the id and the name; remembers the offset field.
    fn start(&mut self, id: i8, name: &str) {
        self.bytes.push(name.len() as u8);
        self.bytes.push(id as u8);
        self.bytes.extend(name.as_bytes());
        self.last_offset_at = self.bytes.len();
    }

    fn description(&mut self, description: &str) {
        self.bytes.push(description.len() as u8);
        self.bytes.extend(description.as_bytes());
    }

    /// The records, the last one's offset zeroed: that is what marks the end of the section.
    fn finish(mut self) -> Vec<u8> {
        let at = self.last_offset_at;
        self.bytes[at..at + 2].fill(0);
        self.bytes
    }
}

/// Frame after frame, point after point: X, Y, Z and the residual word as 32-bit floats,
/// zero-padded to whole blocks.
fn data_section(tracks: &[PointTrack], frames: u16) -> Vec<u8> {
    let len = frames as usize * tracks.len() * 16;
    let mut out = Vec::with_capacity(len.next_multiple_of(BLOCK));
    for frame in 0..frames as usize {
        for track in tracks {
            let (xyz, residual) = match track.positions[frame] {
                Some(p) => (p.map(|c| c as f32), 0.0f32),
                None => ([0.0f32; 3], MISSING_RESIDUAL),
            };
            for word in [xyz[0], xyz[1], xyz[2], residual] {
                out.extend(word.to_le_bytes());
            }
        }
    }
    out.resize(len.next_multiple_of(BLOCK), 0);
    out
}
