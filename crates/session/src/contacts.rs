//! What `jawtrack contacts` leaves in its folder besides the per-frame lines: each arch as PLY
//! coloured by contact frequency and by depth, occlusal PNG views coloured by frequency, and the
//! SVG contact maps a clinician reads (the patient's side, tooth numbers, scale bar, colour scale);
//! and what the report reads back from such a folder ([`read_folder`]), with the check that it
//! was made from the recording reported ([`check_matches`], against what [`fingerprint`] put in
//! its `summary.json`).

use crate::SessionError;
use crate::arches::UNSIDED;
use jawtrack_occlusion::contact_map;
use jawtrack_occlusion::contacts::Arch;
use jawtrack_occlusion::occlusal_view::{View, render, with_legend};
use jawtrack_occlusion::session::ContactSession;
use jawtrack_pose::Pose;
use jawtrack_recording::{FrameRecord, Recording};
use nalgebra::{Point3, Vector3};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The files written, and what the reader should know.
#[derive(Debug, Default)]
pub struct Written {
    /// Every file, in the order written.
    pub files: Vec<PathBuf>,
    /// E.g. that the maps cannot say where the patient's left is.
    pub warnings: Vec<String>,
}

/// Writes the meshes, views and maps of `session` into `dir`: the arches (upper, lower) seen at
/// `first_pose`, their teeth's names and places, the patient's left in the upper scan's frame
/// when known.
pub fn write_outputs(
    dir: &Path,
    session: &ContactSession,
    arches: [&Arch; 2],
    first_pose: &Pose,
    teeth: [&[(String, Point3<f64>)]; 2],
    upper_left: Option<Vector3<f64>>,
) -> Result<Written, SessionError> {
    let failed = |p: &Path, e: &dyn std::fmt::Display| SessionError::Write {
        path: p.display().to_string(),
        reason: e.to_string(),
    };
    let mut out = Written::default();
    let named = [(arches[0], "maxilla"), (arches[1], "mandible")];
    for (k, (arch, name)) in named.into_iter().enumerate() {
        for (what, colours) in [("frequency", session.frequency_colours(k)), ("depth", session.depth_colours(k))] {
            let p = dir.join(format!("{name}_{what}.ply"));
            arch.mesh.write_coloured_ply(&p, &colours).map_err(|e| failed(&p, &e))?;
            out.files.push(p);
        }
    }
    // Occlusal views, each from the other arch's side at the first frame's pose.
    let views = View::occlusal_pair(&arches[0].mesh, &arches[1].mesh, first_pose, 800);
    for (k, (arch, name)) in named.into_iter().enumerate() {
        let p = dir.join(format!("{name}_occlusal.png"));
        let image = with_legend(&render(&arch.mesh, &session.frequency_colours(k), &views[k]));
        image.save(&p).map_err(|e| failed(&p, &e))?;
        out.files.push(p);
    }
    // The maps a clinician reads: each arch's occlusal view with its side, teeth and scales.
    let maps = contact_map::session_maps(session, arches, first_pose, teeth, upper_left);
    for m in &maps {
        let p = dir.join(format!("{}_{}_map.svg", m.arch, m.what));
        std::fs::write(&p, &m.svg).map_err(|e| failed(&p, &e))?;
        out.files.push(p);
    }
    if maps.iter().any(|m| !m.sided) {
        out.warnings.push(UNSIDED.to_string());
    }
    Ok(out)
}

/// The contact maps a folder of `jawtrack contacts` holds, each file's name and caption.
pub const MAPS: [(&str, &str); 4] = [
    ("maxilla_depth_map.svg", "Upper arch, deepest contact over the session"),
    ("mandible_depth_map.svg", "Lower arch, deepest contact over the session"),
    ("maxilla_frequency_map.svg", "Upper arch, share of frames in contact"),
    ("mandible_frequency_map.svg", "Lower arch, share of frames in contact"),
];

/// What `jawtrack contacts` wrote into `dir` (given as `--contacts`): its `summary.json`, and
/// each contact map's caption and SVG; a folder without maps is refused.
pub fn read_folder(dir: &Path) -> Result<(serde_json::Value, Vec<(String, String)>), SessionError> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|source| SessionError::Io {
        context: format!(
            "--contacts {}: reading {} (is it a `jawtrack contacts` folder?)",
            dir.display(),
            path.display()
        ),
        source,
    })?;
    let summary = serde_json::from_str(&text)
        .map_err(|source| SessionError::Json { context: format!("{}", path.display()), source })?;
    let mut maps = Vec::new();
    for (file, what) in MAPS {
        let p = dir.join(file);
        if p.is_file() {
            let svg = std::fs::read_to_string(&p)
                .map_err(|source| SessionError::Io { context: format!("reading {}", p.display()), source })?;
            maps.push((what.to_string(), svg));
        }
    }
    if maps.is_empty() {
        return Err(SessionError::Setting(format!(
            "--contacts {}: no contact maps in it; run `jawtrack contacts` again with this version to write them",
            dir.display()
        )));
    }
    Ok((summary, maps))
}

/// What `summary.json` records of the recording a folder was made from (`name` as given): its
/// session, frame count, first and last frames, and a sum of its poses' translations, which
/// another recording or the same frames tracked again do not share. Cheap, and stable across
/// versions: frame numbers, times and poses read back bit for bit.
pub fn fingerprint(rec: &Recording, name: &str) -> Value {
    let at = |f: Option<&FrameRecord>| f.map(|f| json!({ "frame": f.frame, "t": f.t }));
    let poses = rec.frames.iter().flat_map(|f| [f.maxilla_from_mandible, f.maxilla_scan_from_mandible_scan]).flatten();
    let (count, sum) = poses.fold((0usize, Vector3::zeros()), |(n, s), p| (n + 1, s + p.translation()));
    json!({
        "name": name,
        "session": rec.frames.first().and_then(|f| f.session).map(|s| s.to_string()),
        "frames": rec.frames.len(),
        "first": at(rec.frames.first()),
        "last": at(rec.frames.last()),
        "poses": count,
        "translation_sum_mm": [sum.x, sum.y, sum.z],
    })
}

/// Checks that the folder whose `summary.json` is `summary` was made from `rec` (named
/// `rec_name` in the messages): `Ok(None)` when it was, `Ok(Some(warning))` for a folder
/// written before folders recorded their recording (it cannot be checked), and
/// [`SessionError::OtherRecording`] when it was made from another recording, or from this one
/// tracked again.
pub fn check_matches(summary: &Value, rec: &Recording, rec_name: &str) -> Result<Option<String>, SessionError> {
    let made = &summary["recording"];
    if !made.is_object() {
        return Ok(Some(format!(
            "the contacts folder does not say which recording it was made from (it was written by an older \
             jawtrack), so it cannot be checked against {rec_name}; run `jawtrack contacts` on this recording to be \
             sure"
        )));
    }
    let here = fingerprint(rec, rec_name);
    let differs = differences(made, &here);
    if differs.is_empty() {
        return Ok(None);
    }
    Err(SessionError::OtherRecording {
        made_from: describe(made),
        recording: describe(&here),
        differs: differs.join("; "),
    })
}

/// A fingerprint in words: "session.jsonl (240 frames, t 0 to 59.75 s)".
fn describe(f: &Value) -> String {
    let name = f["name"].as_str().unwrap_or("a recording");
    match (f["first"]["t"].as_f64(), f["last"]["t"].as_f64()) {
        (Some(a), Some(b)) => format!("{name} ({} frames, t {a} to {b} s)", f["frames"]),
        _ => format!("{name} ({} frames)", f["frames"]),
    }
}

/// How the fingerprint `made` (the folder's) differs from `here` (the recording's), in words.
fn differences(made: &Value, here: &Value) -> Vec<String> {
    let mut differs = Vec::new();
    let frame = |v: &Value| match (v["frame"].as_u64(), v["t"].as_f64()) {
        (Some(n), Some(t)) => format!("frame {n} at t {t} s"),
        _ => "none".to_string(),
    };
    if made["session"] != here["session"] {
        let id = |v: &Value| v["session"].as_str().unwrap_or("none").to_string();
        differs.push(format!("session {} there, {} here", id(made), id(here)));
    }
    if made["frames"] != here["frames"] {
        differs.push(format!("{} frames there, {} here", made["frames"], here["frames"]));
    }
    for end in ["first", "last"] {
        if made[end] != here[end] {
            differs.push(format!("{end} {} there, {} here", frame(&made[end]), frame(&here[end])));
        }
    }
    let sum =
        |v: &Value| -> Option<Vec<f64>> { v["translation_sum_mm"].as_array()?.iter().map(Value::as_f64).collect() };
    let same_poses = match (sum(made), sum(here)) {
        (Some(a), Some(b)) => a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-6 * (1.0 + x.abs().max(y.abs()))),
        _ => false,
    };
    if differs.is_empty() && (made["poses"] != here["poses"] || !same_poses) {
        differs.push("the same frames with other poses (tracked again since?)".to_string());
    }
    differs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_is_read_with_its_maps_and_one_without_is_refused() {
        let dir = tempfile::tempdir().expect("temporary folder");
        let err = read_folder(dir.path()).expect_err("no summary");
        assert!(err.to_string().contains("is it a `jawtrack contacts` folder?"), "{err}");
        std::fs::write(dir.path().join("summary.json"), r#"{"frames":{"checked":3}}"#).expect("written");
        let err = read_folder(dir.path()).expect_err("no maps");
        assert!(err.to_string().contains("no contact maps in it"), "{err}");
        std::fs::write(dir.path().join("mandible_depth_map.svg"), "<svg/>").expect("written");
        let (summary, maps) = read_folder(dir.path()).expect("read");
        assert_eq!(summary["frames"]["checked"], 3);
        assert_eq!(maps, [(MAPS[1].1.to_string(), "<svg/>".to_string())]);
    }

    fn frame(i: u64, t: f64, x: f64) -> FrameRecord {
        let line = format!(
            r#"{{"frame":{i},"t":{t},"maxilla":null,"mandible":null,"maxilla_from_mandible":[1,0,0,{x},0,1,0,40,0,0,1,0,0,0,0,1]}}"#
        );
        serde_json::from_str(&line).expect("a frame")
    }

    fn recording(frames: &[(u64, f64, f64)]) -> Recording {
        Recording { frames: frames.iter().map(|&(i, t, x)| frame(i, t, x)).collect(), ..Recording::default() }
    }

    #[test]
    fn a_folder_made_from_this_recording_passes_and_one_from_another_is_refused_naming_both() {
        let rec = recording(&[(0, 0.0, 0.0), (1, 0.25, 0.5), (2, 0.5, 1.0)]);
        let summary = json!({ "recording": fingerprint(&rec, "today.jsonl") });
        let back: Value = serde_json::from_str(&summary.to_string()).expect("JSON");
        assert_eq!(check_matches(&back, &rec, "today.jsonl").expect("the same"), None);
        assert_eq!(check_matches(&back, &rec, "renamed.jsonl").expect("names are not compared"), None);

        let other = recording(&[(0, 0.0, 0.0), (1, 0.25, 0.5)]);
        let err = check_matches(&back, &other, "yesterday.jsonl").expect_err("another recording");
        assert_eq!(
            err.to_string(),
            "the contacts folder was made from today.jsonl (3 frames, t 0 to 0.5 s), not from yesterday.jsonl (2 \
             frames, t 0 to 0.25 s): 3 frames there, 2 here; last frame 2 at t 0.5 s there, frame 1 at t 0.25 s \
             here; run `jawtrack contacts` on this recording (or give --contacts the folder made from it)"
        );
        let tracked_again = recording(&[(0, 0.0, 0.0), (1, 0.25, 0.6), (2, 0.5, 1.0)]);
        let err = check_matches(&back, &tracked_again, "today.jsonl").expect_err("other poses");
        assert!(err.to_string().contains("the same frames with other poses (tracked again since?)"), "{err}");
    }

    #[test]
    fn a_folder_from_before_fingerprints_is_a_warning_not_a_refusal() {
        let rec = recording(&[(0, 0.0, 0.0)]);
        let warning = check_matches(&json!({ "frames": { "checked": 1 } }), &rec, "s.jsonl").expect("not refused");
        let w = warning.expect("a warning");
        assert!(w.contains("cannot be checked against s.jsonl") && w.contains("run `jawtrack contacts`"), "{w}");
    }
}
