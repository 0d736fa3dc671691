//! Opening a recording for the commands that read one: one session's frames, in capture order.
//!
//! Frames received over the link are written in arrival order; they are put back in sequence
//! order here. A file holding several sessions (a receiver that ran while the phone started
//! and stopped transmitting) is refused unless one is chosen, since their frames would mix.

use crate::SessionError;
use jawtrack_recording::{Recording, SessionId};
use std::path::Path;

/// Skipped lines named one by one; past that, counted (a foreign file has thousands).
const NAMED: usize = 10;

/// A recording opened for reading, and what the reader should be told about it.
#[derive(Debug)]
pub struct Opened {
    /// One session's frames, sorted by capture.
    pub recording: Recording,
    /// Lines that were skipped, in words (at most ten named, the rest counted).
    pub warnings: Vec<String>,
}

/// Reads `path`, keeps the frames and bites of `session` (needed when the file holds several)
/// and orders the frames by capture.
///
/// # Examples
///
/// ```no_run
/// let opened = jawtrack_session::open(std::path::Path::new("session.jsonl"), None)?;
/// for w in &opened.warnings {
///     eprintln!("warning: {w}");
/// }
/// # Ok::<(), jawtrack_session::SessionError>(())
/// ```
pub fn open(path: &Path, session: Option<SessionId>) -> Result<Opened, SessionError> {
    let mut rec = jawtrack_recording::open(path)?;
    select(&mut rec, &path.display().to_string(), session)?;
    let name = path.display();
    let mut warnings: Vec<String> =
        rec.skipped.iter().take(NAMED).map(|(line, why)| format!("{name} line {line} skipped: {why}")).collect();
    if rec.skipped.len() > NAMED {
        warnings.push(format!("{} more lines of {name} skipped", rec.skipped.len() - NAMED));
    }
    if rec.frames.is_empty() {
        return Err(SessionError::NoFrames { path: name.to_string(), skipped: rec.skipped.len(), warnings });
    }
    rec.sort_by_capture();
    Ok(Opened { recording: rec, warnings })
}

/// The session rule: keeps `wanted`'s frames and bites; without a choice, refuses a file that
/// holds more than one session.
pub fn select(rec: &mut Recording, path: &str, wanted: Option<SessionId>) -> Result<(), SessionError> {
    let sessions = rec.sessions();
    match wanted {
        Some(wanted) => {
            if !sessions.contains(&wanted) {
                let ids: Vec<String> = sessions.iter().map(ToString::to_string).collect();
                return Err(SessionError::NoSuchSession {
                    path: path.into(),
                    wanted: wanted.to_string(),
                    sessions: ids.join(", "),
                });
            }
            rec.frames.retain(|f| f.session == Some(wanted));
            rec.bites.retain(|b| b.session == Some(wanted));
        }
        None if sessions.len() > 1 => {
            let counts: Vec<String> = sessions
                .iter()
                .map(|&s| format!("{s} ({} frames)", rec.frames.iter().filter(|f| f.session == Some(s)).count()))
                .collect();
            return Err(SessionError::SeveralSessions {
                path: path.into(),
                count: sessions.len(),
                sessions: counts.join(", "),
            });
        }
        None => {}
    }
    Ok(())
}
