//! The lower incisor's clinical numbers over a session: widest opening, left and right
//! lateral excursion, protrusion and retrusion (with the teeth near contact: the backward swing
//! of an opening arc is not a retrusion), each with the frame where it happens, and the
//! envelopes of motion in the sagittal plane (anterior vs up) and the frontal plane (the
//! patient's left vs up), in each plane's axes as it is drawn ([`PlaneView`]), as the border is.

use crate::PlaneView;
use crate::envelope::Envelope;
use crate::point::Displacement;
use serde_json::{Value, json};

/// One frame of the path: its time (s), its `frame` number, the incisor's displacement.
pub type Sample = (f64, u64, Displacement);

/// The largest value of one displacement measure and where it happens.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extreme {
    /// The value (mm).
    pub mm: f64,
    /// The frame's `frame` number.
    pub frame: u64,
    /// The frame's time (s).
    pub t: f64,
}

impl Extreme {
    /// The first sample where `f` is largest (`None` for no samples).
    pub fn of(path: &[Sample], f: impl Fn(&Displacement) -> f64) -> Option<Self> {
        let mut best: Option<Extreme> = None;
        for (t, frame, d) in path {
            let mm = f(d);
            // Strictly greater: ties keep the earliest frame.
            if best.is_none_or(|b| mm > b.mm) {
                best = Some(Extreme { mm, frame: *frame, t: *t });
            }
        }
        best
    }

    /// As `metrics.json` holds it.
    pub fn to_json(self) -> Value {
        json!({ "mm": self.mm, "frame": self.frame, "t_s": self.t })
    }
}

/// A retrusion is measured with the incisors at most this far open (mm): the mandible pushed
/// back from rest with the teeth near contact (toward the retruded contact position), not the
/// backward swing of the incisor on an opening arc, which a hinge opening of 30 mm makes 4 mm.
pub const RETRUSION_OPENING_MM: f64 = 2.0;

/// The incisor's motion metrics over a path (displacements from rest, mm).
#[derive(Debug, Clone, PartialEq)]
pub struct Metrics {
    /// Frames in the path.
    pub frames: usize,
    /// Widest opening (down).
    pub max_opening: Extreme,
    /// Farthest excursion toward the patient's left (+lateral).
    pub max_left: Extreme,
    /// Farthest excursion toward the patient's right (−lateral), as a positive number.
    pub max_right: Extreme,
    /// Farthest forward.
    pub max_protrusion: Extreme,
    /// Farthest back (−protrusive), as a positive number, among the frames opened no more
    /// than [`RETRUSION_OPENING_MM`]; `None` when the jaw never came that near closed.
    pub max_retrusion: Option<Extreme>,
    /// Sagittal envelope: x anterior, y up ([`PlaneView::Sagittal`]).
    pub sagittal: Envelope,
    /// Frontal envelope: x toward the patient's left, y up ([`PlaneView::Frontal`]).
    pub frontal: Envelope,
}

impl Metrics {
    /// The metrics of `path`; `None` when it is empty.
    pub fn compute(path: &[Sample]) -> Option<Self> {
        let plane = |view: PlaneView| path.iter().map(|(_, _, d)| view.project(d)).collect::<Vec<_>>();
        Some(Metrics {
            frames: path.len(),
            max_opening: Extreme::of(path, |d| d.opening)?,
            max_left: Extreme::of(path, |d| d.lateral)?,
            max_right: Extreme::of(path, |d| -d.lateral)?,
            max_protrusion: Extreme::of(path, |d| d.protrusive)?,
            max_retrusion: {
                let near_closed: Vec<Sample> =
                    path.iter().copied().filter(|(_, _, d)| d.opening <= RETRUSION_OPENING_MM).collect();
                Extreme::of(&near_closed, |d| -d.protrusive)
            },
            sagittal: Envelope::of(&plane(PlaneView::Sagittal)),
            frontal: Envelope::of(&plane(PlaneView::Frontal)),
        })
    }

    /// As `metrics.json` holds it.
    pub fn to_json(&self) -> Value {
        json!({
            "frames_used": self.frames,
            "max_opening": self.max_opening.to_json(),
            "max_left_lateral": self.max_left.to_json(),
            "max_right_lateral": self.max_right.to_json(),
            "max_protrusion": self.max_protrusion.to_json(),
            "max_retrusion": self.max_retrusion.map(Extreme::to_json),
            "retrusion_max_opening_mm": RETRUSION_OPENING_MM,
            "envelope_sagittal": self.sagittal.to_json(PlaneView::Sagittal),
            "envelope_frontal": self.frontal.to_json(PlaneView::Frontal),
        })
    }
}

/// Openings in a sequence of incisor displacements: rises of the opening by at least 3 mm
/// from the lowest point since the last opening, each counted once it falls back by 3 mm or the
/// data ends — when at its widest the incisor went down more steeply than the teeth can guide
/// it ([`opens`]): a protrusion or a laterotrusion lowers it a few millimetres along the
/// teeth's guidance, and that is not an opening.
pub fn count_openings(path: &[Displacement]) -> usize {
    const STEP_MM: f64 = 3.0;
    let (mut n, mut low, mut open) = (0, f64::INFINITY, false);
    let mut high = Displacement { opening: f64::NEG_INFINITY, lateral: 0.0, protrusive: 0.0 };
    for d in path {
        if open {
            if d.opening > high.opening {
                high = *d;
            }
            if d.opening < high.opening - STEP_MM {
                (open, low) = (false, d.opening);
                n += usize::from(opens(&high));
            }
        } else {
            low = low.min(d.opening);
            if d.opening > low + STEP_MM {
                (open, high) = (true, *d);
            }
        }
    }
    n + usize::from(open && opens(&high))
}

/// How much further down than sideways or forward a glide along the teeth can take the
/// incisor: 2, a descent of 63° from the horizontal, beyond the steepest anterior and canine
/// guidance (commonly 40–60°). An opening swings the incisor back, not forward.
pub const GUIDANCE_RATIO: f64 = 2.0;

/// Whether a displacement is an opening rather than a glide along the teeth: down more than
/// [`GUIDANCE_RATIO`] times as far as sideways or forward.
pub fn opens(d: &Displacement) -> bool {
    d.opening > GUIDANCE_RATIO * d.lateral.abs().max(d.protrusive.max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envelope::{cross, polygon_area};

    fn d(opening: f64, lateral: f64, protrusive: f64) -> Displacement {
        Displacement { opening, lateral, protrusive }
    }

    /// Whether `q` is inside or on the counter-clockwise polygon `hull`.
    fn inside(hull: &[(f64, f64)], q: (f64, f64)) -> bool {
        (0..hull.len()).all(|i| cross(hull[i], hull[(i + 1) % hull.len()], q) >= -1e-12)
    }

    #[test]
    fn metrics_pick_each_extreme_and_its_frame() {
        let path: Vec<Sample> = vec![
            (0.0, 10, d(0.0, 0.0, 0.0)),
            (0.1, 11, d(30.0, 0.5, -4.0)),
            (0.2, 12, d(1.0, 6.0, 0.0)),
            (0.3, 14, d(1.0, -5.0, 0.5)),
            (0.4, 15, d(3.2, 0.0, 8.0)),
            (0.5, 16, d(30.0, 0.0, 0.0)),
            (0.6, 17, d(0.8, 0.0, -1.1)),
        ];
        let m = Metrics::compute(&path).expect("a path");
        assert_eq!(m.frames, 7);
        assert_eq!(m.max_opening, Extreme { mm: 30.0, frame: 11, t: 0.1 }, "ties keep the first frame");
        assert_eq!(m.max_left, Extreme { mm: 6.0, frame: 12, t: 0.2 });
        assert_eq!(m.max_right, Extreme { mm: 5.0, frame: 14, t: 0.3 });
        assert_eq!(m.max_protrusion, Extreme { mm: 8.0, frame: 15, t: 0.4 });
        // Frame 11 swings 4 mm back while 30 mm open: an opening arc, not a retrusion.
        assert_eq!(m.max_retrusion, Some(Extreme { mm: 1.1, frame: 17, t: 0.6 }));
        // Sagittal (anterior, up): corners (-4,-30) (0,-30) (8,-3.2) (0,0) (-1.1,-0.8).
        assert_eq!(m.sagittal.hull.len(), 5);
        let corners = [(-4.0, -30.0), (0.0, -30.0), (8.0, -3.2), (0.0, 0.0), (-1.1, -0.8)];
        assert!((m.sagittal.area_mm2 - polygon_area(&corners)).abs() < 1e-12);
        assert!(path.iter().all(|(_, _, x)| inside(&m.frontal.hull, PlaneView::Frontal.project(x))));
        assert!(path.iter().all(|(_, _, x)| inside(&m.sagittal.hull, PlaneView::Sagittal.project(x))));
        assert_eq!(j_axes(&m), ["anterior (mm)", "up (mm)"], "the border's axes");
        let j = m.to_json();
        assert_eq!(j["max_right_lateral"]["mm"], 5.0);
        assert_eq!(j["envelope_sagittal"]["vertices"], 5);
        assert_eq!(j["max_retrusion"]["frame"], 17);
        let open_only = Metrics::compute(&[(0.0, 0, d(5.0, 0.0, -3.0))]).expect("a path");
        assert_eq!(open_only.max_retrusion, None, "never near closed");
        assert!(open_only.to_json()["max_retrusion"].is_null());
    }

    fn j_axes(m: &Metrics) -> Vec<String> {
        m.to_json()["envelope_sagittal"]["axes"]
            .as_array()
            .expect("axes")
            .iter()
            .map(|a| a.to_string().replace('"', ""))
            .collect()
    }

    #[test]
    fn a_path_at_rest_has_zero_metrics_and_no_path_has_none() {
        let m = Metrics::compute(&[(0.0, 0, d(0.0, 0.0, 0.0)), (0.1, 1, d(0.0, 0.0, 0.0))]).expect("a path");
        assert_eq!((m.max_opening.mm, m.max_left.mm, m.max_right.mm), (0.0, 0.0, 0.0));
        assert_eq!((m.sagittal.area_mm2, m.sagittal.hull.len()), (0.0, 1));
        assert!(Metrics::compute(&[]).is_none());
    }

    #[test]
    fn openings_are_counted_however_small_the_first() {
        let cycle = |peak: f64| [0.0, peak / 2.0, peak, peak / 2.0, 0.0];
        let v: Vec<f64> = [10.0, 20.0, 30.0, 40.0].iter().flat_map(|&p| cycle(p)).collect();
        let down = |v: &[f64]| v.iter().map(|&o| d(o, 0.0, 0.0)).collect::<Vec<_>>();
        assert_eq!(count_openings(&down(&v)), 4);
        assert_eq!(count_openings(&down(&[0.0, 1.0, 0.5, 1.5, 0.2])), 0, "tremor is not an opening");
        assert_eq!(count_openings(&down(&[0.0, 5.0, 10.0])), 1, "still open at the end");
        // Three protrusions along the incisal guidance: 8 mm forward, 4.6 mm down.
        let glide: Vec<Displacement> =
            (0..3).flat_map(|_| [0.0, 0.5, 1.0, 0.5, 0.0]).map(|k| d(4.6 * k, 0.0, 8.0 * k)).collect();
        assert_eq!(count_openings(&glide), 0, "a protrusion is not an opening");
    }
}
