//! The report's contact survey: the occlusal contacts of a few frames spread evenly over a
//! session, with their maps and per-tooth totals (`jawtrack contacts` checks every frame).

use crate::SessionError;
use crate::arches::{UNSIDED, tooth_places};
use crate::scan_pose::PosedFrame;
use jawtrack_occlusion::Mesh;
use jawtrack_occlusion::contact_map;
use jawtrack_occlusion::contacts::{Arch, ContactSettings};
use jawtrack_occlusion::session::ContactSession;
use jawtrack_occlusion::teeth::ToothTotals;
use nalgebra::Vector3;
use serde_json::{Value, json};

/// What a survey found.
#[derive(Debug)]
pub struct Survey {
    /// Settings, frame counts, the deepest contact and the per-tooth totals (JSON, in the
    /// shape of `jawtrack contacts`'s `summary.json`).
    pub summary: Value,
    /// Each contact map's caption and SVG.
    pub maps: Vec<(String, String)>,
    /// Which frames were checked, in words.
    pub checked: String,
    /// What the reader should know (e.g. that the maps cannot tell left from right).
    pub warnings: Vec<String>,
}

/// Checks the contacts of at most `at_most` frames of `posed` spread over the session
/// (`progress(done, total)` after each), the arches given as named parts; `upper_left` is the
/// patient's left in the upper scan's frame, when known.
pub fn survey(
    upper_parts: Vec<(String, Mesh)>,
    lower_parts: Vec<(String, Mesh)>,
    posed: &[PosedFrame],
    at_most: usize,
    upper_left: Option<Vector3<f64>>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Survey, SessionError> {
    if at_most == 0 {
        return Err(SessionError::Setting("--contact-frames must be 1 or more".into()));
    }
    let Some(&(_, _, first_pose)) = posed.first() else {
        return Err(SessionError::NoScanPose(
            "--maxilla and --mandible need the scans' poses: give --registration (`jawtrack register`), or a \
             recording tracked with one"
                .into(),
        ));
    };
    let stride = posed.len().div_ceil(at_most);
    let settings = ContactSettings::default();
    let teeth = [tooth_places(&upper_parts), tooth_places(&lower_parts)];
    let (upper, lower) = (Arch::new(upper_parts, &settings), Arch::new(lower_parts, &settings));
    let mut session = ContactSession::new(&upper, &lower, settings);
    let mut per_tooth = ToothTotals::default();
    let checked: Vec<&PosedFrame> = posed.iter().step_by(stride).collect();
    for (k, (frame, t, pose)) in checked.iter().enumerate() {
        per_tooth.add(&session.check(*frame, *t, pose).regions);
        progress(k + 1, checked.len());
    }
    let maps = contact_map::session_maps(&session, [&upper, &lower], &first_pose, [&teeth[0], &teeth[1]], upper_left);
    let s = session.summary();
    let mut warnings: Vec<String> =
        s.depth_warning(&settings).into_iter().chain(s.no_contact_warning(&settings)).collect();
    if maps.iter().any(|m| !m.sided) {
        warnings.push(UNSIDED.to_string());
    }
    let summary = json!({
        "settings": {"mode": "kinematic", "threshold_mm": settings.threshold_mm},
        "frames": {"checked": s.frames, "with_contact": s.with_contact, "penetrating": s.penetrating},
        "deepest": s.deepest,
        "teeth": per_tooth.totals(),
    });
    Ok(Survey {
        summary,
        maps: maps.into_iter().map(|m| (m.caption, m.svg)).collect(),
        checked: format!("checked here: {} of {} frames with a scan pose, every {stride}", s.frames, posed.len()),
        warnings,
    })
}
