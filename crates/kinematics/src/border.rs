//! Border movements: Posselt's envelope in the sagittal, frontal and transverse planes as the
//! lower incisor traced it, not as a convex hull. The border is the path's outermost trace seen
//! from inside the region it covers: along each of [`RAYS`] directions from the region's centre,
//! the farthest point where the traced path crosses that direction. So it follows the path into
//! the concave parts a hull bridges (the notch between the retruded contact and intercuspation,
//! the gothic arch of the transverse plane), and every outline point lies on the path. The
//! border's extremes are labelled ([`Landmark`]), and so are the movements between them that
//! trace it ([`Border::arcs`]).
//!
//! Coordinates are those of the page ([`PlaneView::project`]): (right, up) in mm, with the side
//! each view puts the patient's left on.

use crate::envelope::{convex_hull, polygon_area};
use crate::metrics::{Metrics, Sample};
use crate::views::PlaneView;
use serde_json::{Value, json};
use std::f64::consts::TAU;

/// Directions the border is traced along: one a degree.
pub const RAYS: usize = 360;

/// An extreme smaller than this (mm) is not labelled: it is within three times the incisor's
/// error with a calibrated marker on rendered sessions (0.11–0.16 mm), so the wobble of a hinge
/// opening would otherwise be named a laterotrusion.
pub const LANDMARK_MIN_MM: f64 = 0.5;

/// Samples further apart in time than this (s) are not joined: a gap in tracking is not a path.
pub const GAP_S: f64 = 0.25;

/// A named extreme of the border.
#[derive(Debug, Clone, PartialEq)]
pub struct Landmark {
    /// What it is: "maximum opening", "intercuspal position", …
    pub name: &'static str,
    /// Where it is on the page (mm).
    pub at: (f64, f64),
    /// The frame it was reached in (its `frame` number).
    pub frame: u64,
    /// The time (s).
    pub t: f64,
}

/// The traced border of the incisor's path in one plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Border {
    /// The plane and the side it is seen from.
    pub view: PlaneView,
    /// The outline, counter-clockwise on the page, every point on the path (mm).
    pub outline: Vec<(f64, f64)>,
    /// The area it encloses (mm²).
    pub area_mm2: f64,
    /// The extremes the clinician reads, those the view shows, of [`LANDMARK_MIN_MM`] or more.
    pub landmarks: Vec<Landmark>,
}

/// The outermost trace of `paths` (polylines on the page), along [`RAYS`] directions from the
/// centre of their convex hull, counter-clockwise. Non-finite points break a polyline.
pub fn trace(paths: &[Vec<(f64, f64)>]) -> Vec<(f64, f64)> {
    let all: Vec<(f64, f64)> = paths.iter().flatten().copied().filter(|p| p.0.is_finite() && p.1.is_finite()).collect();
    let hull = convex_hull(&all);
    if hull.len() < 3 {
        return hull;
    }
    let c = centroid(&hull);
    let step = TAU / RAYS as f64;
    // The farthest crossing found along each ray: (distance, point).
    let mut far: Vec<Option<(f64, (f64, f64))>> = vec![None; RAYS];
    let mut offer = |k: usize, p: (f64, f64)| {
        let r = (p.0 - c.0).hypot(p.1 - c.1);
        if far[k].is_none_or(|(best, _)| r > best) {
            far[k] = Some((r, p));
        }
    };
    let angle = |p: (f64, f64)| (p.1 - c.1).atan2(p.0 - c.0);
    // Every point to its nearest ray as well: a stroke along a ray (an opening straight down
    // through the centre) crosses no ray, and its far end is the border there.
    for &p in &all {
        offer(((angle(p) / step).round() as i64).rem_euclid(RAYS as i64) as usize, p);
    }
    for path in paths {
        for w in path.windows(2) {
            let (p, q) = (w[0], w[1]);
            if ![p.0, p.1, q.0, q.1].iter().all(|v| v.is_finite()) {
                continue;
            }
            // The rays within the angle the segment subtends, the short way round.
            let a = angle(p);
            let span = (angle(q) - a + TAU / 2.0).rem_euclid(TAU) - TAU / 2.0;
            let (lo, hi) = if span >= 0.0 { (a, a + span) } else { (a + span, a) };
            let (first, last) = ((lo / step).ceil() as i64, (hi / step).floor() as i64);
            for k in first..=last {
                let th = k as f64 * step;
                let u = (th.cos(), th.sin());
                let d = (q.0 - p.0, q.1 - p.1);
                // c + r u = p + s d, by cross products.
                let denom = u.0 * d.1 - u.1 * d.0;
                if denom.abs() < 1e-12 {
                    continue;
                }
                let e = (p.0 - c.0, p.1 - c.1);
                let s = (u.1 * e.0 - u.0 * e.1) / denom;
                let s = s.clamp(0.0, 1.0);
                offer(k.rem_euclid(RAYS as i64) as usize, (p.0 + s * d.0, p.1 + s * d.1));
            }
        }
    }
    far.into_iter().flatten().map(|(_, p)| p).collect()
}

/// The area centroid of a convex polygon.
fn centroid(poly: &[(f64, f64)]) -> (f64, f64) {
    let (mut a, mut x, mut y) = (0.0, 0.0, 0.0);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let w = p.0 * q.1 - q.0 * p.1;
        a += w;
        x += (p.0 + q.0) * w;
        y += (p.1 + q.1) * w;
    }
    (x / (3.0 * a), y / (3.0 * a))
}

impl Border {
    /// The border of `path` (displacements from rest) in `view`, with the extremes of
    /// `metrics` that the view shows as landmarks.
    pub fn of(view: PlaneView, path: &[Sample], metrics: &Metrics) -> Self {
        // Polylines broken where tracking paused.
        let mut lines: Vec<Vec<(f64, f64)>> = Vec::new();
        let mut last_t = f64::NEG_INFINITY;
        for (t, _, d) in path {
            if t - last_t > GAP_S || lines.is_empty() {
                lines.push(Vec::new());
            }
            last_t = *t;
            if let Some(l) = lines.last_mut() {
                l.push(view.project(d));
            }
        }
        let outline = trace(&lines);
        let area_mm2 = polygon_area(&outline);
        let at = |e: crate::Extreme| {
            let (t, frame, d) = path.iter().find(|(_, f, _)| *f == e.frame).copied().unwrap_or((e.t, e.frame, ZERO));
            (view.project(&d), frame, t)
        };
        let displacement = |e: &crate::Extreme| path.iter().find(|(_, f, _)| *f == e.frame).map_or(ZERO, |s| s.2);
        let mut landmarks = Vec::new();
        let mut add = |name: &'static str, e: Option<crate::Extreme>| {
            if let Some(e) = e.filter(|e| e.mm >= LANDMARK_MIN_MM && recorded(name, &displacement(e))) {
                let (p, frame, t) = at(e);
                landmarks.push(Landmark { name, at: p, frame, t });
            }
        };
        let m = metrics;
        match view {
            PlaneView::Sagittal => {
                add(MAX_PROTRUSION, Some(m.max_protrusion));
                add(MAX_OPENING, Some(m.max_opening));
                add(RETRUDED, m.max_retrusion);
            }
            PlaneView::Frontal => {
                add(MAX_LEFT, Some(m.max_left));
                add(MAX_OPENING, Some(m.max_opening));
                add(MAX_RIGHT, Some(m.max_right));
            }
            PlaneView::Transverse => {
                add(MAX_LEFT, Some(m.max_left));
                add(MAX_PROTRUSION, Some(m.max_protrusion));
                add(MAX_RIGHT, Some(m.max_right));
                add(RETRUDED, m.max_retrusion);
            }
        }
        landmarks.push(Landmark { name: INTERCUSPAL, at: view.project(&ZERO), frame: 0, t: f64::NAN });
        Border { view, outline, area_mm2, landmarks }
    }

    /// The movements that trace the border: for each pair of landmarks next to each other
    /// around the outline (those within 1 mm of it), the movement's name and the outline's
    /// points from one to the other.
    pub fn arcs(&self) -> Vec<(String, Vec<(f64, f64)>)> {
        let n = self.outline.len();
        if n < 3 {
            return Vec::new();
        }
        let nearest = |p: (f64, f64)| {
            (0..n)
                .map(|i| (i, (self.outline[i].0 - p.0).hypot(self.outline[i].1 - p.1)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .filter(|&(_, d)| d <= 1.0)
                .map(|(i, _)| i)
        };
        let mut on: Vec<(usize, &Landmark)> = self.landmarks.iter().filter_map(|l| Some((nearest(l.at)?, l))).collect();
        on.sort_by_key(|(i, _)| *i);
        on.dedup_by_key(|(i, _)| *i);
        if on.len() < 2 {
            return Vec::new();
        }
        (0..on.len())
            .map(|k| {
                let ((i, a), (j, b)) = (on[k], on[(k + 1) % on.len()]);
                let len = (j + n - i) % n;
                let points = (0..=len).map(|s| self.outline[(i + s) % n]).collect();
                (movement(a.name, b.name), points)
            })
            .collect()
    }

    /// As the report and `metrics.json` hold it.
    pub fn to_json(&self) -> Value {
        let (x, y) = self.view.axes();
        json!({
            "plane": self.view.name(),
            "seen": self.view.title(),
            "axes": [x, y],
            "area_mm2": self.area_mm2,
            "outline_mm": self.outline.iter().map(|&(a, b)| [a, b]).collect::<Vec<_>>(),
            "landmarks": self.landmarks.iter().map(|l| json!({
                "name": l.name, "at_mm": [l.at.0, l.at.1],
                "frame": if l.name == INTERCUSPAL { None } else { Some(l.frame) },
                "t_s": if l.t.is_finite() { Some(l.t) } else { None },
            })).collect::<Vec<_>>(),
            "movements": self.arcs().iter().map(|(name, _)| name.clone()).collect::<Vec<_>>(),
        })
    }
}

const ZERO: crate::Displacement = crate::Displacement { opening: 0.0, lateral: 0.0, protrusive: 0.0 };

/// The landmarks' names.
pub const INTERCUSPAL: &str = "intercuspal position";
/// The widest opening.
pub const MAX_OPENING: &str = "maximum opening";
/// The farthest forward.
pub const MAX_PROTRUSION: &str = "maximum protrusion";
/// The farthest toward the patient's left.
pub const MAX_LEFT: &str = "maximum left laterotrusion";
/// The farthest toward the patient's right.
pub const MAX_RIGHT: &str = "maximum right laterotrusion";
/// The farthest back with the teeth near contact.
pub const RETRUDED: &str = "retruded contact position";

/// Whether the movement a landmark names was made where the extreme is: the widest opening is
/// an opening ([`crate::metrics::opens`]); the farthest left, right or forward is a glide, down
/// no more than [`GUIDANCE_RATIO`](crate::metrics::GUIDANCE_RATIO) times as far as it went that
/// way. A hinge opening's 1 mm sway at 35 mm open is not a laterotrusion, nor a protrusion's
/// 4 mm along the guidance an opening.
fn recorded(name: &str, d: &crate::Displacement) -> bool {
    let steepest = crate::metrics::GUIDANCE_RATIO;
    match name {
        MAX_OPENING => crate::metrics::opens(d),
        MAX_LEFT | MAX_RIGHT => steepest * d.lateral.abs() >= d.opening,
        MAX_PROTRUSION => steepest * d.protrusive >= d.opening,
        _ => true,
    }
}

/// A landmark's short tag for plots: IP, RCP, MO, MP, ML, MR.
pub fn tag(name: &str) -> &'static str {
    match name {
        INTERCUSPAL => "IP",
        RETRUDED => "RCP",
        MAX_OPENING => "MO",
        MAX_PROTRUSION => "MP",
        MAX_LEFT => "ML",
        MAX_RIGHT => "MR",
        _ => "?",
    }
}

/// The movement that runs between two landmarks next to each other on a border.
pub fn movement(a: &str, b: &str) -> String {
    let pair = |x: &str, y: &str| (a == x && b == y) || (a == y && b == x);
    let name = if pair(INTERCUSPAL, MAX_PROTRUSION) || pair(RETRUDED, MAX_PROTRUSION) {
        "protrusion in contact (incisal guidance)"
    } else if pair(MAX_PROTRUSION, MAX_OPENING) {
        "opening from protrusion (anterior border)"
    } else if pair(MAX_OPENING, RETRUDED) || pair(MAX_OPENING, INTERCUSPAL) {
        "retruded opening: hinge, then translation (posterior border)"
    } else if pair(RETRUDED, INTERCUSPAL) {
        "retruded contact to intercuspation"
    } else if pair(MAX_LEFT, MAX_OPENING) {
        "opening from the left"
    } else if pair(MAX_RIGHT, MAX_OPENING) {
        "opening from the right"
    } else if pair(MAX_LEFT, INTERCUSPAL) || pair(MAX_LEFT, RETRUDED) {
        "left laterotrusion in contact"
    } else if pair(MAX_RIGHT, INTERCUSPAL) || pair(MAX_RIGHT, RETRUDED) {
        "right laterotrusion in contact"
    } else if pair(MAX_LEFT, MAX_PROTRUSION) {
        "left lateroprotrusion"
    } else if pair(MAX_RIGHT, MAX_PROTRUSION) {
        "right lateroprotrusion"
    } else {
        return format!("{a} to {b}");
    };
    name.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Displacement;

    /// A shield with a notch at the top (Posselt's sagittal shape, drawn on the page): not convex.
    fn shield() -> Vec<(f64, f64)> {
        vec![(-2.0, 0.0), (1.0, -1.5), (8.0, -1.0), (9.0, -8.0), (2.0, -45.0), (-6.0, -20.0)]
    }

    /// Distance from `p` to the closed polygon's boundary.
    fn off(poly: &[(f64, f64)], p: (f64, f64)) -> f64 {
        (0..poly.len())
            .map(|i| {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                let d = (b.0 - a.0, b.1 - a.1);
                let s = (((p.0 - a.0) * d.0 + (p.1 - a.1) * d.1) / (d.0 * d.0 + d.1 * d.1)).clamp(0.0, 1.0);
                (p.0 - a.0 - s * d.0).hypot(p.1 - a.1 - s * d.1)
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn the_trace_follows_a_concave_border_and_ignores_the_inside() {
        let poly = shield();
        let mut closed = poly.clone();
        closed.push(poly[0]);
        // A chewing scribble inside, as a second polyline.
        let inside: Vec<(f64, f64)> = (0..200)
            .map(|k| {
                let a = f64::from(k) * 0.37;
                (2.0 + 2.5 * a.cos(), -15.0 + 9.0 * (1.3 * a).sin())
            })
            .collect();
        let outline = trace(&[inside, closed]);
        assert!(outline.len() > 300, "{}", outline.len());
        for p in &outline {
            assert!(off(&poly, *p) < 1e-9, "{p:?} is not on the border");
        }
        let (area, true_area) = (polygon_area(&outline), polygon_area(&poly));
        // One-degree rays cut the polygon's corners only: within 0.5 %.
        assert!((area - true_area).abs() < 0.005 * true_area, "{area} vs {true_area}");
        // The hull bridges the notch, a triangle of 6 mm².
        let hull = polygon_area(&convex_hull(&poly));
        assert!((hull - true_area - 6.0).abs() < 1e-9, "{hull} vs {true_area}");
    }

    fn sample(t: f64, frame: u64, protrusive: f64, opening: f64, lateral: f64) -> Sample {
        (t, frame, Displacement { opening, lateral, protrusive })
    }

    #[test]
    fn posselt_s_sagittal_border_is_labelled_with_its_movements() {
        // Intercuspation, retruded contact 1 mm back, a retruded opening to 45 mm, back up along
        // the anterior border to maximum protrusion 9 mm forward, and home along the guidance.
        let mut path = vec![sample(0.0, 0, 0.0, 0.0, 0.0), sample(0.1, 1, -1.0, 0.5, 0.0)];
        let mut push = |p: f64, o: f64| {
            let k = path.len() as u64;
            path.push(sample(0.1 * k as f64, k, p, o, 0.0));
        };
        for i in 1..=20 {
            let s = f64::from(i) / 20.0;
            push(-1.0 + 5.0 * s, 0.5 + 44.5 * s);
        }
        for i in 1..=20 {
            let s = f64::from(i) / 20.0;
            push(4.0 + 5.0 * s, 45.0 - 44.0 * s);
        }
        for i in 1..=10 {
            let s = f64::from(i) / 10.0;
            push(9.0 * (1.0 - s), 1.0 * (1.0 - s));
        }
        let m = Metrics::compute(&path).expect("a path");
        let b = Border::of(PlaneView::Sagittal, &path, &m);
        let names: Vec<&str> = b.landmarks.iter().map(|l| l.name).collect();
        assert_eq!(names, [MAX_PROTRUSION, MAX_OPENING, RETRUDED, INTERCUSPAL]);
        let opening = &b.landmarks[1];
        assert_eq!((opening.at, opening.frame), ((4.0, -45.0), 21));
        let movements: Vec<String> = b.arcs().into_iter().map(|(name, _)| name).collect();
        for want in [
            "protrusion in contact (incisal guidance)",
            "opening from protrusion (anterior border)",
            "retruded opening: hinge, then translation (posterior border)",
            "retruded contact to intercuspation",
        ] {
            assert!(movements.iter().any(|m| m == want), "{want} not in {movements:?}");
        }
        // The triangle's area: the shape is the path, closed.
        let poly: Vec<(f64, f64)> = path.iter().map(|(_, _, d)| PlaneView::Sagittal.project(d)).collect::<Vec<_>>();
        assert!((b.area_mm2 - polygon_area(&poly)).abs() < 0.01 * polygon_area(&poly), "{}", b.area_mm2);
    }

    #[test]
    fn a_hinge_opening_s_wobble_is_not_named_a_laterotrusion() {
        // Straight down 40 mm and back, 0.2 mm to the left at the bottom.
        let path: Vec<Sample> = (0..=40u32)
            .map(|k| {
                let o = 40.0 - (f64::from(k) - 20.0).abs() * 2.0;
                sample(0.05 * f64::from(k), u64::from(k), 0.0, o, 0.2 * o / 40.0)
            })
            .collect();
        let m = Metrics::compute(&path).expect("a path");
        let names: Vec<&str> = Border::of(PlaneView::Frontal, &path, &m).landmarks.iter().map(|l| l.name).collect();
        assert_eq!(names, [MAX_OPENING, INTERCUSPAL]);
    }

    #[test]
    fn a_wide_hinge_opening_s_sway_is_not_named_a_laterotrusion_nor_a_glide_an_opening() {
        // Straight down 36 mm and back, 1.2 mm to the left at the bottom (over the 0.5 mm floor).
        let hinge: Vec<Sample> = (0..=40u32)
            .map(|k| {
                let o = 36.0 - (f64::from(k) - 20.0).abs() * 1.8;
                sample(0.05 * f64::from(k), u64::from(k), -0.1 * o, o, 1.2 * o / 36.0)
            })
            .collect();
        let m = Metrics::compute(&hinge).expect("a path");
        let names: Vec<&str> = Border::of(PlaneView::Frontal, &hinge, &m).landmarks.iter().map(|l| l.name).collect();
        assert_eq!(names, [MAX_OPENING, INTERCUSPAL]);
        // A protrusion along the guidance: 8 mm forward and 4.6 mm down is no opening.
        let glide: Vec<Sample> = (0..=20u32)
            .map(|k| {
                let s = 1.0 - (f64::from(k) - 10.0).abs() / 10.0;
                sample(0.05 * f64::from(k), u64::from(k), 8.0 * s, 4.6 * s, 0.0)
            })
            .collect();
        let m = Metrics::compute(&glide).expect("a path");
        let names: Vec<&str> = Border::of(PlaneView::Sagittal, &glide, &m).landmarks.iter().map(|l| l.name).collect();
        assert_eq!(names, [MAX_PROTRUSION, INTERCUSPAL]);
    }

    #[test]
    fn a_stroke_along_a_ray_reaches_its_far_end() {
        // A frontal-plane opening straight down the middle of a lateral loop: its end is the
        // border's lowest point.
        let opening: Vec<(f64, f64)> = (0..=40).map(|k| (0.0, -f64::from(k))).collect();
        let mut lateral: Vec<(f64, f64)> = (0..=72)
            .map(|k| {
                let a = f64::from(k) * TAU / 72.0;
                (8.0 * a.sin(), -4.0 + 4.0 * a.cos())
            })
            .collect();
        lateral.push(lateral[0]);
        let outline = trace(&[opening, lateral]);
        let lowest = outline.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        assert_eq!(lowest, -40.0, "{outline:?}");
    }

    #[test]
    fn a_gap_in_tracking_is_not_drawn_as_a_path() {
        // Two strokes 1 s apart: joined, they would bridge the notch between them.
        let a: Vec<Sample> =
            (0..=10u32).map(|k| sample(0.02 * f64::from(k), u64::from(k), 0.0, f64::from(k), 0.0)).collect();
        let b: Vec<Sample> = (0..=10u32)
            .map(|k| sample(1.5 + 0.02 * f64::from(k), 20 + u64::from(k), 5.0, 10.0 - f64::from(k), 0.0))
            .collect();
        let path: Vec<Sample> = a.into_iter().chain(b).collect();
        let m = Metrics::compute(&path).expect("a path");
        let b = Border::of(PlaneView::Sagittal, &path, &m);
        // Only two parallel lines: nothing crosses the rays between them, no area to enclose
        // beyond the lines' own trace.
        assert!(b.outline.iter().all(|&(x, _)| x.abs() < 1e-9 || (x - 5.0).abs() < 1e-9), "{:?}", b.outline);
    }
}
