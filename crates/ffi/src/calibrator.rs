//! Marker calibration on the phone: a [`Calibrator`] collects views of the marker from the
//! frames a [`Tracker`] tracks (their tags in pixels and their camera, kept by the tracker, so
//! the app hands no pixels over twice), says which tags still need views, solves with
//! `jawtrack_calibration::calibrate` and writes the calibrated marker file.
//!
//! Which frames are new views is the calibration library's rule
//! ([`jawtrack_calibration::ViewSelector`]): a body must have turned, or show a tag it had not.

use crate::engine::TrackedView;
use crate::error::invalid;
use crate::{JawTrackError, Tracker, lock};
use jawtrack_calibration::{
    Calibration, CalibrationFrame, CalibrationOptions, Finding, FocalCheck, MIN_TURN_DEG, ViewSelector, calibrate,
};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_recording::{Overwrite, RecordingError, write_file_atomic};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// What the last frame gave one body ([`jawtrack_calibration::ViewOutcome`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum ViewOutcome {
    /// A new view of the body.
    Added,
    /// Fewer than two of its tags: one tag alone says nothing about where the others sit.
    TooFewTags,
    /// Seen like this already: within [`CalibrationProgress::min_turn_deg`] of a view kept,
    /// which showed the same tags.
    SameView,
    /// Two tags or more, but the tracker did not solve the body, so its turn is unknown.
    NotTracked,
}

impl From<jawtrack_calibration::ViewOutcome> for ViewOutcome {
    fn from(o: jawtrack_calibration::ViewOutcome) -> Self {
        use jawtrack_calibration::ViewOutcome as V;
        match o {
            V::Added => ViewOutcome::Added,
            V::TooFewTags => ViewOutcome::TooFewTags,
            V::SameView => ViewOutcome::SameView,
            V::NotTracked => ViewOutcome::NotTracked,
        }
    }
}

/// One body's views so far.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct BodyViews {
    /// `"maxilla"` or `"mandible"`.
    pub body: String,
    /// Views of it kept.
    pub views: u32,
    /// What the last frame gave it; `None` before the first frame, or when the tracker had no
    /// frame to give (none tracked, or the last one failed).
    pub last: Option<ViewOutcome>,
    /// Its tags the last frame showed.
    pub last_tags: u32,
    /// Its tags with enough views.
    pub tags_ready: u32,
    /// Its tags.
    pub tags_total: u32,
    /// Its tags still short of views, by id.
    pub needs_views: Vec<u32>,
}

/// One tag's views so far.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct TagViews {
    /// tag36h11 id.
    pub id: u32,
    /// `"maxilla"` or `"mandible"`.
    pub body: String,
    /// The face it is glued on (0–11, as the marker file says).
    pub face: u32,
    /// Views that showed it beside another tag of its body.
    pub views: u32,
}

/// Where a calibration stands: what the views so far cover.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct CalibrationProgress {
    /// Frames that added a view of a body.
    pub views: u32,
    /// Views a tag needs to be calibrated.
    pub min_views: u32,
    /// How far (°) a marker must turn from every view of it kept for a frame to add a view.
    pub min_turn_deg: f64,
    /// The last frame added a view.
    pub added: bool,
    /// What the last frame did, in words ("" before the first frame).
    pub note: String,
    /// Per body of the marker.
    pub bodies: Vec<BodyViews>,
    /// Per tag of the marker, body by body, by id.
    pub tags: Vec<TagViews>,
    /// The tags still short of views, by id.
    pub needs_views: Vec<u32>,
    /// Some tag has enough views: solving calibrates it (the others stay nominal).
    pub can_solve: bool,
    /// Every tag has enough views.
    pub complete: bool,
}

/// One body's calibration, as the result screen shows it.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct BodyCalibrationResult {
    /// `"maxilla"` or `"mandible"`.
    pub body: String,
    /// Views that showed two of its tags or more.
    pub views: u32,
    /// RMS reprojection error (px) of its tags' corners with the marker calibrated from …
    pub rms_before_px: f64,
    /// … and with the calibrated one.
    pub rms_after_px: f64,
    /// Its tags the calibration placed.
    pub tags_calibrated: u32,
    /// Its tags.
    pub tags_total: u32,
}

/// One tag's calibration. The numbers are `None` for a tag left nominal.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct TagCalibrationResult {
    /// tag36h11 id.
    pub id: u32,
    /// `"maxilla"` or `"mandible"`.
    pub body: String,
    /// The face it is on (after any correction of the assembly).
    pub face: u32,
    /// Views it was seen in beside another tag of its body.
    pub views: u32,
    /// Placed by the calibration; `false`: seen too seldom, left where the model puts it.
    pub calibrated: bool,
    /// Its shift along the tag's x axis (mm) from where the model puts it.
    pub shift_x_mm: Option<f64>,
    /// … along its y axis (mm).
    pub shift_y_mm: Option<f64>,
    /// Its turn on its face (°, counter-clockwise seen from outside).
    pub turn_deg: Option<f64>,
    /// Its RMS reprojection error (px) before calibration …
    pub rms_before_px: Option<f64>,
    /// … and after.
    pub rms_after_px: Option<f64>,
}

/// What a solve found.
#[derive(Debug, Clone, PartialEq, uniffi::Record)]
pub struct MarkerCalibrationResult {
    /// The bodies the views showed, in the marker's order.
    pub bodies: Vec<BodyCalibrationResult>,
    /// Their tags, body by body, by id.
    pub tags: Vec<TagCalibrationResult>,
    /// What the calibration found, as sentences: tags glued turned or on another face
    /// (corrected), then tags left nominal.
    pub findings: Vec<String>,
    /// The views say the camera's focal length is wrong: what to check.
    pub focal_warning: Option<String>,
    /// The calibrated marker file.
    pub marker_json: String,
}

/// Everything behind the lock.
#[derive(Debug, Clone)]
struct State {
    /// The views: each frame's tags of the bodies it added a view of.
    frames: Vec<CalibrationFrame>,
    /// Which frames were new views of each body.
    selector: ViewSelector,
    /// Per body, what the last frame gave it and how many of its tags it showed.
    last: Vec<Option<(ViewOutcome, u32)>>,
    /// The last frame added a view.
    added: bool,
    /// What the last frame did.
    note: String,
    /// Bumped by every change of the views: a solve of older views is not kept.
    generation: u64,
    /// The last solve, of the views as they are.
    solved: Option<(u64, Calibration, MarkerCalibrationResult)>,
}

impl State {
    fn new(marker: &Marker) -> Self {
        State {
            frames: Vec::new(),
            selector: ViewSelector::new(marker),
            last: vec![None; marker.bodies.len()],
            added: false,
            note: String::new(),
            generation: 0,
            solved: None,
        }
    }
}

/// A marker calibration in progress: views in, a calibrated marker file out.
#[derive(uniffi::Object)]
pub struct Calibrator {
    marker: Marker,
    min_views: usize,
    state: Mutex<State>,
}

fn body_name(kind: BodyKind) -> String {
    kind.name().to_owned()
}

fn count(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

#[uniffi::export]
impl Calibrator {
    /// A calibration starting from the marker file's JSON (`None`: the nominal 12.7 mm marker;
    /// a calibrated file: the nominal marker of its size, see `starting_marker`); a tag needs
    /// `min_views` views (1–100; 3 is the command line's default) to be placed.
    #[uniffi::constructor]
    pub fn new(marker_json: Option<String>, min_views: u32) -> Result<Arc<Self>, JawTrackError> {
        if !(1..=100).contains(&min_views) {
            return Err(JawTrackError::setting(
                "min_views",
                format!("a tag needs 1 to 100 views to be calibrated, got {min_views}"),
            ));
        }
        let marker = match marker_json {
            Some(text) => starting_marker(Marker::from_json(&text)?)?,
            None => Marker::default(),
        };
        let state = Mutex::new(State::new(&marker));
        Ok(Arc::new(Calibrator { marker, min_views: min_views as usize, state }))
    }

    /// Adds the frame `tracker` tracked last (by either door) as a view of each body it shows
    /// from a new angle; the progress says what it added, or why nothing.
    pub fn add_view(&self, tracker: &Tracker) -> CalibrationProgress {
        let view = lock(&tracker.engine).view.clone();
        self.add(view.as_ref())
    }

    /// Where the calibration stands.
    pub fn progress(&self) -> CalibrationProgress {
        self.progress_of(&lock(&self.state))
    }

    /// Forgets the views and the solve: a new calibration.
    pub fn reset(&self) {
        *lock(&self.state) = State::new(&self.marker);
    }

    /// Calibrates the marker from the views so far. Refused while no tag has enough views
    /// (nothing would be calibrated). Adding views afterwards discards the result.
    pub fn solve(&self) -> Result<MarkerCalibrationResult, JawTrackError> {
        let (frames, generation) = {
            let state = lock(&self.state);
            let progress = self.progress_of(&state);
            if !progress.can_solve {
                let most = progress.tags.iter().map(|t| t.views).max().unwrap_or(0);
                return Err(JawTrackError::Calibration {
                    message: format!(
                        "no tag has been seen in {} views yet (the most seen has {most}): keep turning the marker \
                         slowly so that each face is seen from several angles beside another face",
                        self.min_views
                    ),
                });
            }
            (state.frames.clone(), state.generation)
        };
        // The adjustment runs without the lock: progress stays readable meanwhile.
        let options = CalibrationOptions { min_views: self.min_views, ..CalibrationOptions::default() };
        let calibration = calibrate(&self.marker, &frames, &options)?;
        let result = result_of(&calibration);
        let mut state = lock(&self.state);
        if state.generation == generation {
            state.solved = Some((generation, calibration, result.clone()));
        }
        Ok(result)
    }

    /// Writes the marker file of the last solve to `path`, through a temporary file in the same
    /// folder renamed into place (a crash leaves the old file or the new one, never half of
    /// one). An existing file is replaced only with `overwrite`.
    pub fn save(&self, path: String, overwrite: bool) -> Result<(), JawTrackError> {
        let json = {
            let state = lock(&self.state);
            match &state.solved {
                Some((generation, calibration, _)) if *generation == state.generation => calibration.marker.to_json(),
                Some(_) => return Err(invalid("views were added since the last solve: solve again, then save")),
                None => return Err(invalid("nothing to save yet: solve the calibration first")),
            }
        };
        write_new_file(Path::new(&path), &(json + "\n"), overwrite)
    }
}

impl Calibrator {
    /// Adds `view` (the tracker's last frame, `None` when it has none).
    fn add(&self, view: Option<&TrackedView>) -> CalibrationProgress {
        let mut state = lock(&self.state);
        let Some(view) = view else {
            state.last = vec![None; self.marker.bodies.len()];
            state.added = false;
            state.note = "no frame to add: the tracker has tracked none, or its last frame failed".into();
            return self.progress_of(&state);
        };
        let rotations: Vec<_> = view.poses.iter().map(|(k, p)| (*k, p.rotation())).collect();
        let (outcomes, frame) = state.selector.offer(view.camera, &view.tags, &rotations);
        let mut words = Vec::new();
        for (b, o) in outcomes.iter().enumerate() {
            state.last[b] = Some((o.outcome.into(), count(o.tags_seen)));
            let name = o.body.name();
            words.push(match o.outcome {
                jawtrack_calibration::ViewOutcome::Added => {
                    format!("{name}: view {} added", state.selector.views(o.body))
                }
                jawtrack_calibration::ViewOutcome::TooFewTags => {
                    format!("{name}: {} tag(s) seen, a view needs two or more", o.tags_seen)
                }
                jawtrack_calibration::ViewOutcome::SameView => format!("{name}: seen from this angle already"),
                jawtrack_calibration::ViewOutcome::NotTracked => format!("{name}: not tracked in this frame"),
            });
        }
        state.added = frame.is_some();
        if let Some(frame) = frame {
            state.frames.push(frame);
            state.generation += 1;
        }
        state.note = words.join("; ");
        self.progress_of(&state)
    }

    fn progress_of(&self, state: &State) -> CalibrationProgress {
        let mut tags = Vec::new();
        let mut bodies = Vec::new();
        for (b, body) in self.marker.bodies.iter().enumerate() {
            let mut body_tags: Vec<TagViews> = body
                .tags
                .iter()
                .map(|t| TagViews {
                    id: t.id,
                    body: body_name(body.kind),
                    face: count(t.face),
                    views: count(state.selector.tag_views(body.kind, t.id)),
                })
                .collect();
            body_tags.sort_by_key(|t| t.id);
            let needs_views: Vec<u32> =
                body_tags.iter().filter(|t| (t.views as usize) < self.min_views).map(|t| t.id).collect();
            bodies.push(BodyViews {
                body: body_name(body.kind),
                views: count(state.selector.views(body.kind)),
                last: state.last[b].map(|(o, _)| o),
                last_tags: state.last[b].map_or(0, |(_, n)| n),
                tags_ready: count(body_tags.len() - needs_views.len()),
                tags_total: count(body_tags.len()),
                needs_views,
            });
            tags.extend(body_tags);
        }
        let needs_views: Vec<u32> = bodies.iter().flat_map(|b| b.needs_views.iter().copied()).collect();
        CalibrationProgress {
            views: count(state.frames.len()),
            min_views: count(self.min_views),
            min_turn_deg: MIN_TURN_DEG,
            added: state.added,
            note: state.note.clone(),
            can_solve: tags.iter().any(|t| t.views as usize >= self.min_views),
            complete: needs_views.is_empty(),
            needs_views,
            bodies,
            tags,
        }
    }
}

/// The marker a calibration starts from: `marker` itself, unless it is calibrated, which starts
/// afresh from the nominal marker of its edge and tag size (its bodies only). A calibration
/// keeps a tag it sees too seldom where the file put it but records it as nominal, which for a
/// tag an earlier calibration placed would be false; refining a calibrated marker with more
/// views, keeping what it placed, is `jawtrack calibrate-marker --marker`'s.
fn starting_marker(marker: Marker) -> Result<Marker, JawTrackError> {
    if !marker.is_calibrated() {
        return Ok(marker);
    }
    let size = marker.tags().next().map(|(_, t)| t.size);
    let mut nominal = Marker::nominal_on(marker.solid, marker.family, marker.edge, size)?;
    nominal.bodies.retain(|b| marker.body(b.kind).is_some());
    let tags = |m: &Marker| {
        let mut v: Vec<(u32, u64)> = m.tags().map(|(_, t)| (t.id, (t.size * 1e6).round() as u64)).collect();
        v.sort_unstable();
        v
    };
    if tags(&nominal) != tags(&marker) {
        return Err(JawTrackError::InvalidMarker {
            message: "the marker file is calibrated and its tags are not those of a nominal marker of its size, \
                      which a new calibration starts from: start from the nominal marker file it was calibrated from"
                .into(),
        });
    }
    Ok(nominal)
}

/// The result screen's rows from a calibration.
fn result_of(cal: &Calibration) -> MarkerCalibrationResult {
    let mut bodies = Vec::new();
    let mut tags = Vec::new();
    let mut assembly = Vec::new();
    let mut nominal = Vec::new();
    for report in &cal.bodies {
        let Some(body) = cal.marker.body(report.body) else { continue };
        let mut rows: Vec<TagCalibrationResult> = body
            .tags
            .iter()
            .map(|t| {
                let correction = report.tags.iter().find(|c| c.id == t.id);
                let nominal_views = report.findings.iter().find_map(|f| match *f {
                    Finding::Uncalibrated { id, views } if id == t.id => Some(views),
                    _ => None,
                });
                TagCalibrationResult {
                    id: t.id,
                    body: body_name(report.body),
                    face: count(t.face),
                    views: count(correction.map(|c| c.views).or(nominal_views).unwrap_or(0)),
                    calibrated: correction.is_some(),
                    shift_x_mm: correction.map(|c| c.placement.shift_x),
                    shift_y_mm: correction.map(|c| c.placement.shift_y),
                    turn_deg: correction.map(|c| c.placement.rotation.to_degrees()),
                    rms_before_px: correction.map(|c| c.rms_before_px),
                    rms_after_px: correction.map(|c| c.rms_after_px),
                }
            })
            .collect();
        rows.sort_by_key(|r| r.id);
        bodies.push(BodyCalibrationResult {
            body: body_name(report.body),
            views: count(report.views),
            rms_before_px: report.rms_before_px,
            rms_after_px: report.rms_after_px,
            tags_calibrated: count(report.tags.len()),
            tags_total: count(rows.len()),
        });
        tags.extend(rows);
        for f in &report.findings {
            match f {
                Finding::Uncalibrated { .. } => {
                    nominal.push(format!("{f} (show that face from a few angles, beside another face)"));
                }
                _ => assembly.push(f.to_string()),
            }
        }
    }
    assembly.extend(nominal);
    MarkerCalibrationResult {
        focal_warning: cal
            .focal
            .filter(FocalCheck::looks_wrong)
            .map(|f| focal_warning(&f, cal.bodies.iter().map(|b| b.rms_after_px))),
        bodies,
        tags,
        findings: assembly,
        marker_json: cal.marker.to_json(),
    }
}

/// What to say when the views point to another focal length than the camera's (the words of
/// `jawtrack calibrate-marker`, for a phone, whose intrinsics come from the camera).
fn focal_warning(focal: &FocalCheck, residuals_px: impl IntoIterator<Item = f64>) -> String {
    let worst = residuals_px.into_iter().fold(0.0, f64::max);
    format!(
        "the camera's focal length looks wrong: {focal}{}. Intrinsics for another resolution or another lens make \
         every distance wrong by about that factor; a calibrated marker's residual is normally 0.1-0.5 px. Check \
         the camera and resolution chosen, and calibrate again",
        if worst > 0.0 { format!(", and the marker fits with {worst:.2} px") } else { String::new() }
    )
}

fn io_error(path: &Path, what: &str, e: &std::io::Error) -> JawTrackError {
    let shown = path.display().to_string();
    JawTrackError::Io { message: format!("{shown}: {what}: {e}"), path: shown }
}

/// Writes `text` to `path` whole or not at all (`jawtrack_recording::write_file_atomic`).
fn write_new_file(path: &Path, text: &str, overwrite: bool) -> Result<(), JawTrackError> {
    let how = if overwrite { Overwrite::Replace } else { Overwrite::Refuse };
    write_file_atomic(path, text.as_bytes(), how).map_err(|e| match e {
        RecordingError::Exists { path } => JawTrackError::Io {
            message: format!("{path} already exists: not replaced (save again and say that it may be replaced)"),
            path,
        },
        RecordingError::Io { source, .. } => io_error(path, "cannot be written", &source),
        other => JawTrackError::Io { message: other.to_string(), path: path.display().to_string() },
    })
}

#[cfg(test)]
#[path = "calibrator_tests.rs"]
mod tests;
