//! Jaw kinematics: what a stream of tracked `maxilla_from_mandible` poses means for the
//! patient's jaw. Where the recording, the viewer, `export`, `plot` and `metrics` read the
//! incisor's opening, they read it here.
//!
//! - [`mounting`]: how the harnesses sit on the head ([`Mounting`]): the head frame, the
//!   markers' rest poses, the hinge axis, the condyles and the lower incisal point.
//! - [`anatomy`]: the patient's frame and points from the upper scan ([`AnatomicalPoints`]):
//!   the occlusal plane, the midline, the lower incisal point, the condyles (given or Bonwill's).
//! - [`point`]: a point fixed to the mandible (the incisor by default, or a condyle) carried
//!   by tracked poses, and its [`Displacement`] from rest.
//! - [`metrics`]: the incisor's clinical extremes over a session ([`Metrics`]), and how many
//!   times the jaw opened.
//! - [`centric`]: the slide from centric occlusion into maximal intercuspation ([`CoMi`]).
//! - [`envelope`]: envelopes of motion as convex hulls in one plane ([`Envelope`]).
//! - [`border`]: Posselt's envelope as the incisor traced it, with its landmarks and
//!   movements labelled ([`Border`]).
//! - [`hinge`]: the kinematic hinge axis fitted to an opening ([`HingeAxis`]).
//! - [`articulator`]: condylar inclination, Bennett angle, immediate side shift and incisal
//!   guidance from border movements ([`ArticulatorValues`]).
//! - [`opensim`]: OpenSim marker trajectories (`.trc`) and jaw coordinates (`.mot`).
//! - [`views`]: how each anatomical plane is drawn, and where the patient's left falls
//!   ([`PlaneView`]).
//!
//! The head frame: X toward the patient's left, Y down, Z posterior (mm).

pub mod anatomy;
pub mod articulator;
pub mod border;
pub mod centric;
pub mod envelope;
pub mod hinge;
pub mod metrics;
pub mod mounting;
pub mod opensim;
pub mod point;
pub mod views;

pub use anatomy::{AnatomicalPoints, Anatomy};
pub use articulator::{ArticulatorOptions, ArticulatorValues, Movements};
pub use border::Border;
pub use centric::{CoMi, co_mi};
pub use envelope::{Envelope, convex_hull, polygon_area};
pub use hinge::{HingeAxis, HingeOptions};
pub use metrics::{Extreme, Metrics, Sample};
pub use mounting::{Mounting, Side};
pub use point::{Displacement, Incisor};
pub use views::PlaneView;

/// A window of a recording, in seconds of the frames' `t`: where a movement was made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// From (s).
    pub from: f64,
    /// To (s), after `from`.
    pub to: f64,
}

impl Window {
    /// Whether `t` lies in the window, ends included.
    pub fn holds(&self, t: f64) -> bool {
        (self.from..=self.to).contains(&t)
    }

    /// A window written `FROM:TO` in seconds (the CLI's movement flags), each end a finite
    /// number and FROM before TO; the error names what is wrong.
    ///
    /// # Examples
    ///
    /// ```
    /// use jawtrack_kinematics::Window;
    /// assert_eq!(Window::parse("1.5:3"), Ok(Window { from: 1.5, to: 3.0 }));
    /// assert!(Window::parse("NaN:1").is_err_and(|e| e.contains("'NaN' in 'NaN:1' is not a number of seconds")));
    /// assert!(Window::parse("2:1").is_err_and(|e| e.contains("FROM must be before TO")));
    /// assert!(Window::parse("2").is_err_and(|e| e.contains("expected FROM:TO")));
    /// ```
    pub fn parse(s: &str) -> Result<Window, String> {
        let (a, b) = s.split_once(':').ok_or_else(|| format!("expected FROM:TO in seconds, got '{s}'"))?;
        let num = |v: &str| match v.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(format!("'{v}' in '{s}' is not a number of seconds")),
        };
        let (from, to) = (num(a)?, num(b)?);
        if from >= to {
            return Err(format!("'{s}': FROM must be before TO"));
        }
        Ok(Window { from, to })
    }
}

/// What the kinematics refuses.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// A setting out of range.
    #[error("{0}")]
    Options(String),
    /// The hinge fit's window holds too few poses or too small a turn.
    #[error(
        "the hinge axis needs an opening: the window holds {poses} poses turned between the closed jaw and \
         {window_deg}° (the widest {widest_deg:.1}°), and the fit needs 3 or more turned at least {least_deg}°; \
         record the jaw opening slowly from closed by 10–20 mm at the incisors, or choose the window with the opening"
    )]
    TooLittleTurn {
        /// Poses in the window.
        poses: usize,
        /// The widest turn among them (°).
        widest_deg: f64,
        /// The turn the fit needs (°).
        least_deg: f64,
        /// The largest turn the window takes (°).
        window_deg: f64,
    },
    /// A movement's path has too few points within the travel its value is read over.
    #[error(
        "{what} has {points} points between {from_mm} and {over_mm} mm of travel, and the value needs 3 or more: \
         record the movement slowly and at least {over_mm} mm long, or choose its window"
    )]
    TooLittlePath {
        /// The path, in words.
        what: String,
        /// Its points within the travel.
        points: usize,
        /// The least travel counted (mm).
        from_mm: f64,
        /// The travel the value is read over (mm).
        over_mm: f64,
    },
    /// A points file that is not one, or holds points no patient has.
    #[error("points file: {0}")]
    Points(String),
    /// The poses do not fix an axis (e.g. all turns about different axes cancel out).
    #[error("the poses do not fix a hinge axis: their turns share no axis")]
    Degenerate,
}
