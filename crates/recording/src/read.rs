//! The one reader of recordings: every line that is a frame, and for every other line where
//! and why it was skipped.

use crate::{BiteRecord, FrameRecord, RECORDING_FORMAT, RECORDING_VERSION, RecordingError, RecordingHeader, SessionId};
use serde_json::Value;
use std::io::BufRead;
use std::path::Path;

/// A recording read back.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// The header line, if the file has one (files from before headers have none).
    pub header: Option<RecordingHeader>,
    /// The frames, in file order.
    pub frames: Vec<FrameRecord>,
    /// The rest positions the intercuspation step accepted, in file order (the last is in force).
    pub bites: Vec<BiteRecord>,
    /// Lines that were not frames: (1-based line number, why). A last line cut short by a
    /// killed writer shows up here.
    pub skipped: Vec<(usize, String)>,
}

impl Recording {
    /// The sessions the frames belong to, in order of first appearance (files written before
    /// session ids give none).
    pub fn sessions(&self) -> Vec<SessionId> {
        let mut seen = Vec::new();
        for s in self.frames.iter().filter_map(|f| f.session) {
            if !seen.contains(&s) {
                seen.push(s);
            }
        }
        seen
    }

    /// The rest position in force: the last bite accepted in `session` (any session when `None`).
    pub fn rest(&self, session: Option<SessionId>) -> Option<&BiteRecord> {
        self.bites.iter().rev().find(|b| session.is_none() || b.session == session)
    }

    /// Puts the frames in capture order: by sequence number where the link gave one (datagrams
    /// may arrive reordered), else by frame index.
    pub fn sort_by_capture(&mut self) {
        self.frames.sort_by_key(|f| (f.seq.unwrap_or(f.frame), f.frame));
    }
}

/// Reads a recording. Lines that are not frames are collected in [`Recording::skipped`] (so a
/// file cut off mid-line by a killed writer reads up to its last whole line); only a header
/// this build cannot read, or a file that is not text (an image or a video given by mistake),
/// is an error.
pub fn read_recording(reader: impl BufRead) -> Result<Recording, RecordingError> {
    read_named(reader, "the recording")
}

/// Opens and reads the recording at `path` (see [`read_recording`]).
pub fn open(path: &Path) -> Result<Recording, RecordingError> {
    let name = path.display().to_string();
    let file = std::fs::File::open(path).map_err(RecordingError::io(&name))?;
    read_named(std::io::BufReader::new(file), &name)
}

fn read_named(mut reader: impl BufRead, name: &str) -> Result<Recording, RecordingError> {
    let head = reader.fill_buf().map_err(RecordingError::io(name))?;
    if let Some(what) = binary_kind(head) {
        let why = format!("not a recording (JSON lines): it looks like a binary file{what}");
        return Err(RecordingError::Io { path: name.to_owned(), source: std::io::Error::other(why) });
    }
    let mut rec = Recording::default();
    let mut bytes = Vec::new();
    for number in 1.. {
        bytes.clear();
        if reader.read_until(b'\n', &mut bytes).map_err(RecordingError::io(name))? == 0 {
            break;
        }
        match std::str::from_utf8(&bytes) {
            Ok(line) => read_line(&mut rec, number, line.trim_end_matches(['\n', '\r']))?,
            // A line garbled on disk costs that line, as any other unreadable line does.
            Err(_) => rec.skipped.push((number, "not text (invalid UTF-8)".into())),
        }
    }
    Ok(rec)
}

/// Whether the start of a file (`head`) is not text, and, when its magic number says, what it
/// is (" (PNG image?)"): what users give by mistake for a recording, such as a frame or the
/// video. Text has no NUL byte, and its first line is UTF-8.
fn binary_kind(head: &[u8]) -> Option<&'static str> {
    let magic: [(&[u8], usize, &str); 6] = [
        (b"\x89PNG\r\n\x1a\n", 0, " (PNG image?)"),
        (b"\xff\xd8\xff", 0, " (JPEG image?)"),
        (b"ftypqt", 4, " (MOV video?)"),
        (b"ftypheic", 4, " (HEIC image?)"),
        (b"ftyp", 4, " (MP4 video?)"),
        (b"moov", 4, " (MOV video?)"),
    ];
    if let Some(&(_, _, what)) = magic.iter().find(|(m, at, _)| head.get(*at..*at + m.len()) == Some(*m)) {
        return Some(what);
    }
    let first_line = head.split(|&b| b == b'\n').next().unwrap_or_default();
    let utf8 = match std::str::from_utf8(first_line) {
        Ok(_) => true,
        // A first line longer than the buffer may end in a character cut in two: that is text.
        Err(e) => e.error_len().is_none() && first_line.len() == head.len(),
    };
    (head.contains(&0) || !utf8).then_some("")
}

/// Reads line `number` of a recording into `rec`.
fn read_line(rec: &mut Recording, number: usize, line: &str) -> Result<(), RecordingError> {
    if line.trim().is_empty() {
        return Ok(());
    }
    let value: Value = match serde_json::from_str(line) {
        Ok(v) => v,
        Err(e) => {
            rec.skipped.push((number, format!("not JSON ({e})")));
            return Ok(());
        }
    };
    if let Some(h) = value.get("recording") {
        let h: RecordingHeader = serde_json::from_value(h.clone())
            .map_err(|e| RecordingError::Header(format!("not a recording header: {e}")))?;
        if h.format != RECORDING_FORMAT || h.version != RECORDING_VERSION {
            return Err(RecordingError::Header(format!(
                "format {} version {} (this build reads {RECORDING_FORMAT} version {RECORDING_VERSION})",
                h.format, h.version
            )));
        }
        rec.header = Some(h);
        return Ok(());
    }
    if let Some(b) = value.get("bite") {
        match serde_path_to_error::deserialize::<_, BiteRecord>(b.clone()) {
            Ok(b) if b.maxilla_from_mandible.translation().norm() <= MAX_TRANSLATION_MM && b.t.is_finite() => {
                rec.bites.push(b)
            }
            Ok(_) => rec.skipped.push((number, "implausible bite: its rest position or time is absurd".into())),
            Err(e) => rec.skipped.push((number, format!("not a bite: field `{}`: {}", e.path(), e.inner()))),
        }
        return Ok(());
    }
    match serde_path_to_error::deserialize::<_, FrameRecord>(value) {
        Ok(f) => match implausible(&f) {
            None => rec.frames.push(f),
            Some(why) => rec.skipped.push((number, why)),
        },
        Err(e) => rec.skipped.push((number, format!("not a frame: field `{}`: {}", e.path(), e.inner()))),
    }
    Ok(())
}

/// Farther than any camera films a jaw from, or any jaw moves (mm): a pose beyond it comes from a
/// corrupt or foreign line, and every number computed from it would be infinite or NaN.
pub const MAX_TRANSLATION_MM: f64 = 10_000.0;

/// Why a frame that parses cannot be a tracked frame, if it cannot.
fn implausible(f: &FrameRecord) -> Option<String> {
    let poses = [
        ("maxilla.camera_from_body", f.maxilla.as_ref().map(|b| b.camera_from_body)),
        ("mandible.camera_from_body", f.mandible.as_ref().map(|b| b.camera_from_body)),
        ("maxilla_from_mandible", f.maxilla_from_mandible),
        ("maxilla_scan_from_mandible_scan", f.maxilla_scan_from_mandible_scan),
    ];
    for (name, pose) in poses {
        let distance = pose.map_or(0.0, |p| p.translation().norm());
        if !distance.is_finite() || distance > MAX_TRANSLATION_MM {
            return Some(format!(
                "implausible pose: field `{name}` moves {distance:.3e} mm (more than {MAX_TRANSLATION_MM} mm)"
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RecordingWriter;
    use jawtrack_pose::Pose;
    use nalgebra::Vector3;

    fn frame(i: u64, pose: Option<Pose>) -> FrameRecord {
        FrameRecord {
            frame: i,
            session: None,
            path: None,
            t: 0.25,
            exposure_s: None,
            lens_position: None,
            maxilla: None,
            mandible: None,
            maxilla_from_mandible: pose,
            maxilla_scan_from_mandible_scan: None,
            flags: vec![],
            searched: None,
            timings_s: None,
            seq: None,
            received_unix_s: None,
            tone: None,
        }
    }

    #[test]
    fn a_recording_reads_back_up_to_a_line_cut_short() {
        let pose = Pose::from_axis_angle(Vector3::new(0.1, 0.0, 0.0), Vector3::new(0.0, 40.0, 0.0));
        let mut header = RecordingHeader::new("test");
        header.key_id = Some("abcd".into());
        let mut w = RecordingWriter::new(Vec::new(), header, "memory").expect("header");
        let first = frame(0, Some(pose));
        w.append(&first).expect("frame");
        w.append(&first).expect("frame");
        let whole = String::from_utf8(w.into_inner()).expect("utf-8");
        // A writer killed mid-line leaves part of the last one.
        let cut = &whole[..whole.len() - 20];
        let rec = read_recording(cut.as_bytes()).expect("readable");
        assert_eq!(rec.header.as_ref().and_then(|h| h.key_id.as_deref()), Some("abcd"));
        assert_eq!(rec.frames.len(), 1);
        let back = &rec.frames[0];
        let (a, d) = back.maxilla_from_mandible.expect("pose").distance_to(&pose);
        assert!(a < 1e-12 && d < 1e-12, "the pose survives the round trip: {a} rad, {d} mm");
        assert_eq!((back.frame, back.t, &back.flags, back.timings_s), (0, 0.25, &first.flags, first.timings_s));
        assert_eq!(rec.skipped.len(), 1);
        assert_eq!(rec.skipped[0].0, 3);
    }

    #[test]
    fn a_header_of_another_version_is_an_error_naming_it() {
        let mut header = RecordingHeader::new("test");
        header.version = 99;
        let err = read_recording(header.to_line().as_bytes()).expect_err("refused");
        assert!(err.to_string().contains("version 99"), "{err}");
    }

    #[test]
    fn a_file_from_before_session_ids_still_reads() {
        let old = r#"{"frame":4,"path":null,"t":0.1,"maxilla":null,"mandible":null,"maxilla_from_mandible":null}"#;
        let rec = read_recording(old.as_bytes()).expect("readable");
        assert_eq!(rec.frames.len(), 1);
        assert_eq!(rec.frames[0].session, None);
        assert!(rec.sessions().is_empty());
    }

    #[test]
    fn a_missing_file_is_named() {
        let err = open(Path::new("/nonexistent/session.jsonl")).expect_err("no such file");
        assert!(err.to_string().contains("/nonexistent/session.jsonl"), "{err}");
    }

    #[test]
    fn capture_order_follows_the_link_sequence() {
        let mut rec = Recording {
            frames: vec![
                FrameRecord { seq: Some(2), ..frame(0, None) },
                FrameRecord { seq: Some(1), ..frame(5, None) },
            ],
            ..Recording::default()
        };
        rec.sort_by_capture();
        assert_eq!(rec.frames.iter().map(|f| f.frame).collect::<Vec<_>>(), vec![5, 0]);
    }

    #[test]
    fn a_frame_with_an_absurd_pose_is_skipped_with_the_reason() {
        let good = frame(0, Some(Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, 40.0, 0.0))));
        let far = frame(1, Some(Pose::from_axis_angle(Vector3::zeros(), Vector3::new(1e308, 0.0, 0.0))));
        let text = format!("{}\n{}\n", good.to_line(), far.to_line());
        let rec = read_recording(text.as_bytes()).expect("reads");
        assert_eq!(rec.frames.len(), 1, "only the plausible frame");
        assert_eq!(rec.skipped.len(), 1);
        assert_eq!(rec.skipped[0].0, 2);
        assert!(rec.skipped[0].1.contains("implausible pose: field `maxilla_from_mandible`"), "{}", rec.skipped[0].1);
    }

    #[test]
    fn an_image_or_a_video_given_as_a_recording_is_named_once() {
        let dir = std::env::temp_dir().join(format!("jawtrack-recording-binary-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a folder");
        let cases: [(&str, &[u8], &str); 4] = [
            ("frame.png", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR", " (PNG image?)"),
            ("frame.jpg", b"\xff\xd8\xff\xe0\0\x10JFIF\0", " (JPEG image?)"),
            ("clip.mov", b"\0\0\0\x14ftypqt  \0\0\0\0", " (MOV video?)"),
            ("data.bin", b"{\"frame\":0}\0\0\0", ""),
        ];
        for (file, bytes, what) in cases {
            let path = dir.join(file);
            std::fs::write(&path, bytes).expect("written");
            let err = open(&path).expect_err("not a recording");
            let name = path.display();
            assert_eq!(
                err.to_string(),
                format!("{name}: not a recording (JSON lines): it looks like a binary file{what}")
            );
            // Nothing further down the chain repeats it (the CLI prints the chain).
            assert!(std::error::Error::source(&err).is_none(), "{file}");
        }
        let mp4 = read_recording(&b"\0\0\0\x18ftypmp42\0\0\0\0"[..]).expect_err("a video");
        assert!(mp4.to_string().ends_with("(MP4 video?)"), "{mp4}");
        std::fs::remove_dir_all(&dir).expect("removed");
    }

    #[test]
    fn a_garbled_line_after_the_first_is_skipped_like_any_unreadable_line() {
        let good = frame(0, None).to_line();
        let text = [good.as_bytes(), b"\n\xff\xfe garbled\n", good.as_bytes(), b"\r\n"].concat();
        let rec = read_recording(&text[..]).expect("reads");
        assert_eq!(rec.frames.len(), 2);
        assert_eq!(rec.skipped, [(2, "not text (invalid UTF-8)".to_string())]);
    }

    #[test]
    fn a_missing_file_is_named_once() {
        let err = open(Path::new("/nonexistent/session.jsonl")).expect_err("no such file");
        assert!(std::error::Error::source(&err).is_none(), "the reason is in the message: {err}");
    }
}
