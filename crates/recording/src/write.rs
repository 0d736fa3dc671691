//! The one writer of recordings: a header, then one line per frame, each written in one call
//! and flushed, so a killed process leaves every frame written before the kill and at most the
//! last line cut short (which the reader reports and skips).

use crate::{BiteRecord, FrameRecord, RecordingError, RecordingHeader};
use std::io::Write;
use std::path::Path;

/// What [`RecordingWriter::create`] does when the file exists.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Overwrite {
    /// Refuse: a recording is never replaced unless the user said so.
    Refuse,
    /// Replace the file.
    Replace,
}

/// Creates `path` for writing, refusing an existing file unless `overwrite` says to replace
/// it: for a writer over something other than a plain file (e.g. a boxed file-or-stdout).
pub fn create_file(path: &Path, overwrite: Overwrite) -> Result<std::fs::File, RecordingError> {
    let name = path.display().to_string();
    let mut options = std::fs::OpenOptions::new();
    options.write(true);
    match overwrite {
        Overwrite::Refuse => options.create_new(true),
        Overwrite::Replace => options.create(true).truncate(true),
    };
    options.open(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::AlreadyExists => RecordingError::Exists { path: name },
        _ => RecordingError::Io { path: name, source: e },
    })
}

/// Writes `bytes` to `path` whole or not at all: through a temporary file beside it, renamed
/// over an existing file when `overwrite` says to replace it, else linked into place only if
/// nothing is there (atomic where the file system has hard links). A failure, or a process
/// killed midway, leaves the old file or none — never half of the new one. The one writer of
/// every output that is not a recording (results, calibrations, exports).
///
/// # Examples
///
/// ```
/// use jawtrack_recording::{Overwrite, write_file_atomic};
/// let dir = std::env::temp_dir().join(format!("jawtrack-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("result.json");
/// let _ = std::fs::remove_file(&path);
/// write_file_atomic(&path, b"{}", Overwrite::Refuse).unwrap();
/// assert!(write_file_atomic(&path, b"[]", Overwrite::Refuse).is_err());
/// write_file_atomic(&path, b"[]", Overwrite::Replace).unwrap();
/// assert_eq!(std::fs::read(&path).unwrap(), b"[]");
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn write_file_atomic(path: &Path, bytes: &[u8], overwrite: Overwrite) -> Result<(), RecordingError> {
    let shown = path.display().to_string();
    let exists = || RecordingError::Exists { path: shown.clone() };
    let io = |source: std::io::Error| RecordingError::Io { path: shown.clone(), source };
    if overwrite == Overwrite::Refuse && path.exists() {
        return Err(exists());
    }
    let Some(name) = path.file_name() else {
        return Err(io(std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name")));
    };
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let temp = folder.join(format!(".{}.{}-{nanos}.tmp", name.to_string_lossy(), std::process::id()));
    let written = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .and_then(|mut f| f.write_all(bytes).and_then(|()| f.sync_all()));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&temp);
        return Err(io(e));
    }
    let placed = match overwrite {
        Overwrite::Replace => std::fs::rename(&temp, path).map_err(io),
        Overwrite::Refuse => match std::fs::hard_link(&temp, path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(exists()),
            // No hard links here: the check above must do.
            Err(_) => std::fs::rename(&temp, path).map_err(io),
        },
    };
    let _ = std::fs::remove_file(&temp);
    placed?;
    if let Ok(dir) = std::fs::File::open(&folder) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// Writes one recording.
pub struct RecordingWriter<W: Write> {
    out: W,
    header: RecordingHeader,
    frames: u64,
    name: String,
}

impl RecordingWriter<std::fs::File> {
    /// Creates `path` (see [`Overwrite`]) and writes the header.
    pub fn create(path: &Path, header: RecordingHeader, overwrite: Overwrite) -> Result<Self, RecordingError> {
        RecordingWriter::new(create_file(path, overwrite)?, header, &path.display().to_string())
    }

    /// Syncs the file to storage.
    pub fn sync(&self) -> Result<(), RecordingError> {
        self.out.sync_all().map_err(RecordingError::io(&self.name))
    }
}

impl<W: Write> RecordingWriter<W> {
    /// Writes the header to `out`; `name` names the output in errors.
    pub fn new(out: W, header: RecordingHeader, name: &str) -> Result<Self, RecordingError> {
        let mut w = RecordingWriter { out, header, frames: 0, name: name.to_owned() };
        let line = w.header.to_line();
        w.write_line(&line)?;
        Ok(w)
    }

    /// Appends a frame, stamped with the header's session when it carries none of its own
    /// (frames received over the link carry the phone's).
    pub fn append(&mut self, frame: &FrameRecord) -> Result<(), RecordingError> {
        let line = if frame.session.is_none() && self.header.session.is_some() {
            FrameRecord { session: self.header.session, ..frame.clone() }.to_line()
        } else {
            frame.to_line()
        };
        self.write_line(&line)?;
        self.frames += 1;
        Ok(())
    }

    /// Appends the rest position the intercuspation step accepted, stamped with the header's
    /// session when it carries none.
    pub fn append_bite(&mut self, bite: &BiteRecord) -> Result<(), RecordingError> {
        let line = BiteRecord { session: bite.session.or(self.header.session), ..*bite }.to_line();
        self.write_line(&line)
    }

    /// The header written.
    pub fn header(&self) -> &RecordingHeader {
        &self.header
    }

    /// Frames appended so far.
    pub fn frames_written(&self) -> u64 {
        self.frames
    }

    /// The output, for a writer over memory or a caller that closes it itself.
    pub fn into_inner(self) -> W {
        self.out
    }

    /// One `write` per line, then a flush.
    fn write_line(&mut self, line: &str) -> Result<(), RecordingError> {
        let mut bytes = Vec::with_capacity(line.len() + 1);
        bytes.extend_from_slice(line.as_bytes());
        bytes.push(b'\n');
        self.out.write_all(&bytes).and_then(|()| self.out.flush()).map_err(RecordingError::io(&self.name))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{SessionId, read_recording};

    fn frame(i: u64) -> FrameRecord {
        FrameRecord {
            frame: i,
            session: None,
            path: None,
            t: i as f64 / 30.0,
            exposure_s: None,
            lens_position: None,
            maxilla: None,
            mandible: None,
            maxilla_from_mandible: None,
            maxilla_scan_from_mandible_scan: None,
            flags: vec!["no_tags".into()],
            searched: None,
            timings_s: None,
            seq: None,
            received_unix_s: None,
            tone: None,
        }
    }

    #[test]
    fn every_frame_carries_the_session_and_reads_back() {
        let header = RecordingHeader::new("test");
        let session = header.session.expect("a new header starts a session");
        let mut w = RecordingWriter::new(Vec::new(), header, "memory").expect("header");
        w.append(&frame(0)).expect("frame");
        let other = SessionId(7);
        w.append(&FrameRecord { session: Some(other), ..frame(1) }).expect("frame");
        assert_eq!(w.frames_written(), 2);
        let bytes = w.into_inner();
        let rec = read_recording(bytes.as_slice()).expect("readable");
        assert_eq!(rec.frames[0].session, Some(session), "stamped with the header's");
        assert_eq!(rec.frames[1].session, Some(other), "a frame's own session is kept");
        assert_eq!(rec.sessions(), vec![session, other]);
    }

    #[test]
    fn a_bite_is_written_stamped_and_read_back_as_the_rest_in_force() {
        use jawtrack_pose::Pose;
        use nalgebra::Vector3;
        let header = RecordingHeader::new("test");
        let session = header.session;
        let mut w = RecordingWriter::new(Vec::new(), header, "memory").expect("header");
        let rest = |y: f64| BiteRecord {
            session: None,
            t: y / 10.0,
            maxilla_from_mandible: Pose::from_axis_angle(Vector3::zeros(), Vector3::new(0.0, y, 0.0)),
            frames: 15,
            span_s: 0.47,
            spread_mm: 0.02,
            spread_deg: 0.05,
        };
        w.append(&frame(0)).expect("frame");
        w.append_bite(&rest(40.0)).expect("bite");
        w.append(&frame(1)).expect("frame");
        w.append_bite(&rest(41.0)).expect("bite");
        let rec = read_recording(w.into_inner().as_slice()).expect("readable");
        assert_eq!(rec.frames.len(), 2, "bites are not frames");
        assert!(rec.skipped.is_empty(), "{:?}", rec.skipped);
        assert_eq!(rec.bites.len(), 2);
        assert!(rec.bites.iter().all(|b| b.session == session), "stamped with the header's session");
        let in_force = rec.rest(session).expect("a rest");
        assert_eq!(in_force.maxilla_from_mandible.translation().y, 41.0, "the last one");
        assert!(rec.rest(Some(SessionId(3))).is_none());
    }

    #[test]
    fn an_existing_file_is_refused_unless_replacing_is_asked_for() {
        let dir = std::env::temp_dir().join(format!("jawtrack-recording-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("session.jsonl");
        std::fs::write(&path, "precious\n").expect("write");
        let err =
            RecordingWriter::create(&path, RecordingHeader::new("test"), Overwrite::Refuse).err().expect("refused");
        assert!(matches!(err, RecordingError::Exists { .. }), "{err}");
        assert!(err.to_string().contains("already exists"), "{err}");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "precious\n", "left as it was");
        let mut w = RecordingWriter::create(&path, RecordingHeader::new("test"), Overwrite::Replace).expect("replaced");
        w.append(&frame(0)).expect("frame");
        w.sync().expect("sync");
        let rec = crate::open(&path).expect("readable");
        assert_eq!(rec.frames.len(), 1);
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
