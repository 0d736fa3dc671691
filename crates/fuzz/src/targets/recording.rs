//! Recordings as every reader takes them: the one reader (header, frame and bite lines,
//! sessions), then what `metrics`, `export` and `report` compute from what it accepted (the
//! session rule, the rest position, the incisor's path and the clinical measures).

use crate::run::Verdict;
use crate::targets::files::{refused, same_json};
use jawtrack_kinematics::{Anatomy, Metrics};
use jawtrack_recording::{Recording, read_recording};
use jawtrack_session::incisor::{ChosenIncisor, path};
use jawtrack_session::measures::metrics_json;
use jawtrack_session::open::select;
use jawtrack_session::rest_of;
use std::path::Path;

pub fn seeds() -> Vec<Vec<u8>> {
    let file = crate::targets::fixtures().join("fuzz/recording.jsonl");
    std::fs::read(&file).map(|b| vec![b]).unwrap_or_default()
}

pub fn run(input: &[u8]) -> Result<Verdict, String> {
    let rec = match read_recording(std::io::Cursor::new(input)) {
        Ok(rec) => rec,
        Err(e) => return refused(e),
    };
    round_trip(&rec)?;
    for session in rec.sessions().into_iter().map(Some).chain([None]) {
        let mut chosen = rec.clone();
        // More than one session without a choice is refused, clearly: that is the rule.
        if select(&mut chosen, "fuzz.jsonl", session).is_ok() {
            measure(chosen)?;
        }
    }
    Ok(Verdict::Accepted)
}

/// Writes what was read as the writer writes it and reads it again: the same records, and no
/// line skipped.
fn round_trip(rec: &Recording) -> Result<(), String> {
    let mut text = String::new();
    if let Some(h) = &rec.header {
        text += &(h.to_line() + "\n");
    }
    for f in &rec.frames {
        text += &(f.to_line() + "\n");
    }
    for b in &rec.bites {
        text += &(b.to_line() + "\n");
    }
    let again = read_recording(std::io::Cursor::new(text.as_bytes()))
        .map_err(|e| format!("what was read does not read back: {e}\n{text}"))?;
    if !again.skipped.is_empty() {
        return Err(format!("written back, lines are skipped: {:?}\n{text}", again.skipped));
    }
    let lines = |r: &Recording| -> Vec<String> {
        let header = r.header.iter().map(|h| h.to_line());
        header.chain(r.frames.iter().map(|f| f.to_line())).chain(r.bites.iter().map(|b| b.to_line())).collect()
    };
    let (first, second) = (lines(rec), lines(&again));
    if first.len() != second.len() {
        return Err(format!("written back, {} records read as {}:\n{text}", first.len(), second.len()));
    }
    if let Some((a, b)) = first.iter().zip(&second).find(|(a, b)| a != b && !same_json(a, b)) {
        return Err(format!("written back, a record reads differently:\n{a}\nas\n{b}"));
    }
    Ok(())
}

/// The measures `metrics` prints, from the standard incisor.
fn measure(mut rec: Recording) -> Result<(), String> {
    rec.sort_by_capture();
    let Ok(Some(rest)) = rest_of(&rec, None) else { return Ok(()) };
    let chosen = ChosenIncisor::of(&Anatomy::standard(), None).map_err(|e| format!("the standard incisor: {e}"))?;
    let samples = path(&rec.frames, &chosen.incisor, &rest.pose());
    if let Some(m) = Metrics::compute(&samples) {
        let json = metrics_json(&m, &samples, &rec, Path::new("fuzz.jsonl"), rest, &chosen.incisor, chosen.standard);
        if json.is_null() {
            return Err("the metrics' JSON is empty".into());
        }
    }
    Ok(())
}
