//! The written bytes read back field by field, with a parser of our own kept deliberately naive
//! (fixed offsets from the C3D manual), and every refusal.

use super::*;
use std::collections::HashMap;

fn track(label: &str, positions: Vec<Option<[f64; 3]>>) -> PointTrack {
    PointTrack { label: label.into(), description: format!("{label} point"), positions }
}

/// Three tracks over `frames` frames; the second is missing in frame 1.
fn three(frames: usize) -> Vec<PointTrack> {
    let at = |k: f64| (0..frames).map(|f| Some([k + f as f64, -k, 0.5 * k])).collect::<Vec<_>>();
    let mut condyle_left = at(20.0);
    condyle_left[1] = None;
    vec![track("lower_incisor", at(10.0)), track("condyle_left", condyle_left), track("condyle_right", at(30.0))]
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn i16_at(b: &[u8], at: usize) -> i16 {
    i16::from_le_bytes([b[at], b[at + 1]])
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

struct Param {
    kind: i8,
    dims: Vec<usize>,
    data: Vec<u8>,
    description: String,
}

/// The parameters by "GROUP:NAME", walking the records by their offsets as a reader does and
/// checking that the walk ends on a zero offset inside the section.
fn parameters(b: &[u8]) -> HashMap<String, Param> {
    let start = (b[0] as usize - 1) * 512;
    let end = start + b[start + 2] as usize * 512;
    let mut groups = HashMap::new();
    let mut params = Vec::new();
    let mut pos = start + 4;
    loop {
        assert!(pos + 4 <= end, "parameter records run past the section at byte {pos}");
        let name_len = (b[pos] as i8).unsigned_abs() as usize;
        let id = b[pos + 1] as i8;
        assert!(name_len > 0 && id != 0, "a record with no name or group id at byte {pos}");
        let name = String::from_utf8(b[pos + 2..pos + 2 + name_len].to_vec()).expect("ASCII name");
        let offset_at = pos + 2 + name_len;
        let offset = i16_at(b, offset_at);
        let body = &b[offset_at + 2..];
        if id < 0 {
            groups.insert(-id, name);
        } else {
            let kind = body[0] as i8;
            let dims: Vec<usize> = body[2..2 + body[1] as usize].iter().map(|&d| d as usize).collect();
            let data_at = 2 + dims.len();
            let len = dims.iter().product::<usize>() * kind.unsigned_abs() as usize;
            let desc_len = body[data_at + len] as usize;
            let description = &body[data_at + len + 1..data_at + len + 1 + desc_len];
            let description = String::from_utf8(description.to_vec()).expect("ASCII description");
            params.push((id, name, Param { kind, dims, data: body[data_at..data_at + len].to_vec(), description }));
            if offset != 0 {
                assert_eq!(offset as usize, 2 + data_at + len + 1 + desc_len, "offset of {}", params.len());
            }
        }
        if offset == 0 {
            break;
        }
        pos = offset_at + offset as usize;
    }
    params.into_iter().map(|(id, name, p)| (format!("{}:{name}", groups[&id]), p)).collect()
}

fn int(p: &HashMap<String, Param>, key: &str) -> u16 {
    let param = &p[key];
    assert_eq!((param.kind, param.dims.len()), (2, 0), "{key} is not a scalar int16");
    u16_at(&param.data, 0)
}

fn float(p: &HashMap<String, Param>, key: &str) -> f32 {
    let param = &p[key];
    assert_eq!((param.kind, param.dims.len()), (4, 0), "{key} is not a scalar float");
    f32_at(&param.data, 0)
}

/// Fixed-width strings, trailing spaces trimmed as readers do.
fn strings(p: &HashMap<String, Param>, key: &str) -> Vec<String> {
    let param = &p[key];
    assert_eq!(param.kind, -1, "{key} is not text");
    let width = param.dims[0];
    param.data.chunks(width).map(|c| String::from_utf8_lossy(c).trim_end().to_owned()).collect()
}

#[test]
fn header_fields() {
    let b = write(&three(50), 60.0).expect("valid tracks");
    assert_eq!(b.len() % 512, 0);
    assert_eq!(b[0], 2, "parameter section in block 2");
    assert_eq!(b[1], 0x50, "C3D key");
    assert_eq!(u16_at(&b, 2), 3, "point count");
    assert_eq!(u16_at(&b, 4), 0, "analog measurements per frame");
    assert_eq!(u16_at(&b, 6), 1, "first frame, 1-based");
    assert_eq!(u16_at(&b, 8), 50, "last frame");
    assert_eq!(u16_at(&b, 10), 0, "max interpolation gap");
    let scale = f32_at(&b, 12);
    assert!(scale < 0.0, "a negative scale marks float storage, got {scale}");
    assert_eq!(scale, -1.0);
    assert_eq!(u16_at(&b, 18), 0, "analog samples per frame");
    assert_eq!(f32_at(&b, 20), 60.0, "frame rate");
    assert!(b[24..298].iter().all(|&x| x == 0), "reserved words are zero");
    assert_eq!(u16_at(&b, 298), 0x3039, "4-character event label key");
    assert_eq!(u16_at(&b, 300), 0, "no events");
    assert!(b[302..512].iter().all(|&x| x == 0), "empty event table");

    let param_blocks = b[512 + 2] as usize;
    assert_eq!(&b[512..514], &[1, 0x50]);
    assert_eq!(b[512 + 3], 84, "Intel processor");
    let data_start = u16_at(&b, 16) as usize;
    assert_eq!(data_start, 2 + param_blocks, "data follows the parameters");
    assert_eq!(b.len(), (data_start - 1) * 512 + (50usize * 3 * 16).next_multiple_of(512));
}

#[test]
fn parameters_agree_with_header() {
    let b = write(&three(50), 59.94).expect("valid tracks");
    let p = parameters(&b);
    assert_eq!(int(&p, "POINT:USED"), 3);
    assert_eq!(float(&p, "POINT:SCALE"), f32_at(&b, 12));
    assert_eq!(float(&p, "POINT:RATE"), 59.94f32);
    assert_eq!(f32_at(&b, 20), 59.94f32);
    assert_eq!(int(&p, "POINT:DATA_START"), u16_at(&b, 16));
    assert_eq!(int(&p, "POINT:FRAMES"), 50);
    assert_eq!(p["POINT:LABELS"].dims, [LABEL_WIDTH, 3]);
    assert_eq!(strings(&p, "POINT:LABELS"), ["lower_incisor", "condyle_left", "condyle_right"]);
    assert_eq!(p["POINT:DESCRIPTIONS"].dims, ["condyle_right point".len(), 3]);
    assert_eq!(strings(&p, "POINT:DESCRIPTIONS")[1], "condyle_left point");
    assert_eq!(p["POINT:UNITS"].dims, [2]);
    assert_eq!(strings(&p, "POINT:UNITS"), ["mm"]);
    assert_eq!(int(&p, "ANALOG:USED"), 0);
    assert_eq!(float(&p, "ANALOG:RATE"), 0.0);
    assert_eq!(p["TRIAL:ACTUAL_END_FIELD"].data, [50, 0, 0, 0]);
    assert_eq!(p["TRIAL:ACTUAL_START_FIELD"].data, [1, 0, 0, 0]);
    assert_eq!(p["POINT:RATE"].description, "Frames per second");
}

#[test]
fn data_words_in_frame_then_point_order() {
    let tracks = three(4);
    let b = write(&tracks, 100.0).expect("valid tracks");
    let data = (u16_at(&b, 16) as usize - 1) * 512;
    for frame in 0..4 {
        for (point, t) in tracks.iter().enumerate() {
            let at = data + (frame * 3 + point) * 16;
            let words: Vec<f32> = (0..4).map(|k| f32_at(&b, at + 4 * k)).collect();
            match t.positions[frame] {
                Some(p) => assert_eq!(words, [p[0] as f32, p[1] as f32, p[2] as f32, 0.0], "frame {frame}"),
                None => {
                    assert_eq!(words, [0.0, 0.0, 0.0, -1.0], "frame {frame} point {point} is missing");
                    // ezc3d reads the word as two int16s: camera mask 0, residual -16512 (< 0).
                    assert_eq!(&b[at + 12..at + 16], &[0, 0, 0x80, 0xBF]);
                }
            }
        }
    }
    assert!(b[data + 4 * 3 * 16..].iter().all(|&x| x == 0), "the last block is zero-padded");
}

#[test]
fn frame_limit_is_65534() {
    let positions = vec![Some([1.0, 2.0, 3.0]); MAX_FRAMES];
    let b = write(&[track("p", positions.clone())], 1000.0).expect("65534 frames fit");
    assert_eq!(u16_at(&b, 8), 65534);
    let p = parameters(&b);
    assert_eq!(int(&p, "POINT:FRAMES"), 65534, "above 32767 as the unsigned bit pattern");
    assert_eq!(p["TRIAL:ACTUAL_END_FIELD"].data, [0xFE, 0xFF, 0, 0]);

    let mut longer = positions;
    longer.push(None);
    let err = write(&[track("p", longer)], 1000.0).expect_err("65535 frames");
    assert_eq!(err, C3dError::TooManyFrames { frames: 65535 });
    assert!(err.to_string().contains("split the recording into files of at most 65534 frames"), "{err}");
}

#[test]
fn track_limit_is_255() {
    let many: Vec<PointTrack> = (0..MAX_TRACKS).map(|i| track(&format!("p{i}"), vec![None])).collect();
    let b = write(&many, 30.0).expect("255 tracks fit");
    assert_eq!(u16_at(&b, 2), 255);
    assert_eq!(strings(&parameters(&b), "POINT:LABELS")[254], "p254");

    let mut more = many;
    more.push(track("extra", vec![None]));
    assert_eq!(write(&more, 30.0), Err(C3dError::TooManyTracks { count: 256 }));
}

#[test]
fn label_of_exactly_the_width_is_kept_whole() {
    let label = "a".repeat(LABEL_WIDTH);
    let b = write(&[track(&label, vec![Some([0.0; 3])])], 60.0).expect("32 characters fit");
    assert_eq!(strings(&parameters(&b), "POINT:LABELS"), [label]);
}

/// The error for `tracks`, and that its message contains `hint`.
fn refused(tracks: &[PointTrack], rate: f64, hint: &str) -> C3dError {
    let err = write(tracks, rate).expect_err(hint);
    assert!(err.to_string().contains(hint), "message {:?} lacks {hint:?}", err.to_string());
    err
}

#[test]
fn refuses_empty_input() {
    assert_eq!(refused(&[], 60.0, "pass at least one PointTrack"), C3dError::NoTracks);
    let none = [track("a", vec![]), track("b", vec![])];
    assert_eq!(refused(&none, 60.0, "at least one frame"), C3dError::NoFrames);
}

#[test]
fn refuses_tracks_of_different_lengths() {
    let tracks = [track("a", vec![None; 3]), track("b", vec![None; 3]), track("c", vec![None; 2])];
    let err = refused(&tracks, 60.0, "one entry per frame, with None where the point is missing");
    assert!(matches!(err, C3dError::LengthMismatch { index: 2, frames: 2, expected: 3, .. }), "{err:?}");
    assert!(err.to_string().contains("track 2 (\"c\") has 2 frames but track 0 (\"a\") has 3"), "{err}");
}

#[test]
fn refuses_bad_rates() {
    let t = [track("a", vec![None])];
    for rate in [0.0, -60.0, f64::NAN, f64::INFINITY, 1e300, 1e-300] {
        let err = refused(&t, rate, "pass the capture rate in hertz");
        assert!(matches!(err, C3dError::BadRate { .. }), "{rate}: {err:?}");
    }
}

#[test]
fn refuses_bad_labels() {
    let with = |label: &str| [track(label, vec![None])];
    let long = "a".repeat(LABEL_WIDTH + 1);
    let err = refused(&with(&long), 60.0, "shorten it to at most 32 characters");
    assert_eq!(err, C3dError::LabelTooLong { index: 0, label: long, len: 33 });
    for label in ["condyle_é", "tab\there", "new\nline"] {
        let err = refused(&with(label), 60.0, "use only ASCII letters");
        assert!(matches!(err, C3dError::LabelNotAscii { .. }), "{label:?}: {err:?}");
    }
    for label in ["", "   "] {
        assert_eq!(refused(&with(label), 60.0, "give every track a name"), C3dError::EmptyLabel { index: 0 });
    }
    let twins = [track("a", vec![None]), track("b", vec![None]), track("a ", vec![None])];
    let err = refused(&twins, 60.0, "give each track its own label");
    assert_eq!(err, C3dError::DuplicateLabel { label: "a".into(), first: 0, second: 2 });
}

#[test]
fn refuses_bad_descriptions() {
    let mut t = track("a", vec![None]);
    t.description = "d".repeat(MAX_DESCRIPTION_LEN + 1);
    let err = refused(std::slice::from_ref(&t), 60.0, "shorten it to at most 64 characters");
    assert!(matches!(err, C3dError::DescriptionTooLong { len: 65, .. }), "{err:?}");
    t.description = "Kondylus für links".into();
    let err = refused(&[t], 60.0, "use only ASCII letters");
    assert!(matches!(err, C3dError::DescriptionNotAscii { .. }), "{err:?}");
}

#[test]
fn refuses_non_finite_present_coordinates() {
    for (bad, axis) in [([f64::NAN, 0.0, 0.0], 'x'), ([0.0, f64::INFINITY, 0.0], 'y'), ([0.0, 0.0, 1e39], 'z')] {
        let t = [track("ok", vec![Some([1.0; 3]); 3]), track("jaw", vec![None, Some([1.0; 3]), Some(bad)])];
        let err = refused(&t, 60.0, "pass None for a missing position");
        assert!(
            matches!(err, C3dError::NonFiniteCoordinate { index: 1, frame: 2, axis: a, .. } if a == axis),
            "{err:?}"
        );
        assert!(err.to_string().contains("track 1 (\"jaw\") frame 2"), "{err}");
    }
}
