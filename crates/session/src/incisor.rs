//! The lower incisal point's path over a session: the one computation behind every opening,
//! lateral and protrusive number that `metrics`, `plot`, `export --csv`, the report, the
//! viewer's replay and the demo give (definitions: `docs/kinematics.md`). Which point: the one
//! given in the mandible marker's frame (`--incisor`), else the points file's lower incisal
//! point (`--points` with `--registration`), else the standard harness mounting's; the head
//! frame it is read in is the points file's when given, else the standard mounting's.

use crate::SessionError;
use jawtrack_kinematics::{Anatomy, Incisor, Sample};
use jawtrack_pose::Pose;
use jawtrack_recording::FrameRecord;
use nalgebra::Point3;

/// The farthest a point given in the mandible marker's frame may be from the marker (mm): the
/// condyles, the farthest points of the jaw from a harness on the front teeth, are about
/// 140 mm from it.
pub const MOST_FROM_MARKER_MM: f64 = 200.0;

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
    /// read in `anatomy`'s head frame. A given point farther than [`MOST_FROM_MARKER_MM`] from
    /// the marker is refused: no point of a jaw is.
    ///
    /// # Examples
    ///
    /// ```
    /// use jawtrack_session::incisor::ChosenIncisor;
    /// let anatomy = jawtrack_kinematics::Anatomy::standard();
    /// assert!(ChosenIncisor::of(&anatomy, None).unwrap().standard);
    /// assert!(ChosenIncisor::of(&anatomy, Some([0.0, -20.5, -39000.0])).is_err(), "39 m from the marker");
    /// ```
    pub fn of(anatomy: &Anatomy, given: Option<[f64; 3]>) -> Result<Self, SessionError> {
        let standard = given.is_none() && anatomy.is_standard();
        let incisor = match given {
            Some(p) => {
                let far = Point3::from(p).coords.norm();
                if far > MOST_FROM_MARKER_MM {
                    return Err(SessionError::Setting(format!(
                        "--incisor {},{},{} is {far:.0} mm from the mandible marker; the harness holds it within a \
                         few centimetres of the teeth, so every point of the jaw is within {MOST_FROM_MARKER_MM} mm \
                         (the standard incisal point is 44 mm away): give the point in mm, in the mandible marker's \
                         frame",
                        p[0], p[1], p[2]
                    )));
                }
                Incisor::on(anatomy.mounting, Point3::from(p))
            }
            None => Incisor::of(anatomy.mounting),
        };
        Ok(ChosenIncisor { incisor, standard })
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
