//! The lower incisal point's path over a session: the one computation behind every opening,
//! lateral and protrusive number that `metrics`, `plot`, `export --csv`, the report, the
//! viewer's replay and the demo give (definitions: `docs/kinematics.md`). Which point: the one
//! given in the mandible marker's frame (`--incisor`), else the points file's lower incisal
//! point (`--points` with `--registration`), else the standard harness mounting's; the head
//! frame it is read in is the points file's when given, else the standard mounting's.

use jawtrack_kinematics::{Anatomy, Incisor, Sample};
use jawtrack_pose::Pose;
use jawtrack_recording::FrameRecord;
use nalgebra::Point3;

/// The point chosen, and how to name it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChosenIncisor {
    /// The point and the head frame it is read in.
    pub incisor: Incisor,
    /// Whether it is the standard harness mounting's point (no `--incisor`, no points file).
    pub standard: bool,
}

impl ChosenIncisor {
    /// The point `given` in the mandible marker's frame, else `anatomy`'s lower incisal point;
    /// read in `anatomy`'s head frame.
    ///
    /// # Examples
    ///
    /// ```
    /// let anatomy = jawtrack_kinematics::Anatomy::standard();
    /// let chosen = jawtrack_session::incisor::ChosenIncisor::of(&anatomy, None);
    /// assert!(chosen.standard);
    /// ```
    pub fn of(anatomy: &Anatomy, given: Option<[f64; 3]>) -> Self {
        let standard = given.is_none() && anatomy.is_standard();
        let incisor = match given {
            Some(p) => Incisor::on(anatomy.mounting, Point3::from(p)),
            None => Incisor::of(anatomy.mounting),
        };
        ChosenIncisor { incisor, standard }
    }

    /// Which point, in words, for the printed summaries.
    pub fn words(&self, given: bool) -> &'static str {
        match (self.standard, given) {
            (true, _) => "the standard harness mounting's lower incisal point",
            (false, true) => "the point given with --incisor",
            (false, false) => "the points file's lower incisal point",
        }
    }
}

/// The incisor's displacement from `rest` in each frame with a jaw pose, in the order of
/// `frames` (the frames without one are left out).
///
/// # Examples
///
/// ```
/// use jawtrack_kinematics::Incisor;
/// let rec = jawtrack_recording::read_recording(r#"{"frame":0,"t":0}"#.as_bytes()).unwrap();
/// let path = jawtrack_session::incisor::path(&rec.frames, &Incisor::standard(), &jawtrack_pose::Pose::identity());
/// assert!(path.is_empty(), "the frame has no jaw pose");
/// ```
pub fn path(frames: &[FrameRecord], incisor: &Incisor, rest: &Pose) -> Vec<Sample> {
    frames
        .iter()
        .filter_map(|f| f.maxilla_from_mandible.map(|m| (f.t, f.frame, incisor.displacement(&m, rest))))
        .collect()
}
