//! What `jawtrack contacts` leaves in its folder besides the per-frame lines: each arch as PLY
//! coloured by contact frequency and by depth, occlusal PNG views coloured by frequency, and the
//! SVG contact maps a clinician reads (the patient's side, tooth numbers, scale bar, colour scale);
//! and what the report reads back from such a folder ([`read_folder`]).

use crate::SessionError;
use crate::arches::UNSIDED;
use jawtrack_occlusion::contact_map;
use jawtrack_occlusion::contacts::Arch;
use jawtrack_occlusion::occlusal_view::{View, render, with_legend};
use jawtrack_occlusion::session::ContactSession;
use jawtrack_pose::Pose;
use nalgebra::{Point3, Vector3};
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
}
