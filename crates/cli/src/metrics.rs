//! `jawtrack metrics`: the clinical numbers of a recording's lower-incisor motion — widest
//! opening, left and right lateral excursion, protrusion and retrusion, each with the frame
//! where it happens — and the envelope of motion (Posselt): the convex hull of the incisor's
//! path in the sagittal plane (protrusive vs opening) and in the frontal plane (lateral vs
//! opening), its area and vertices. Optionally plots both envelopes and writes `metrics.json`.
//!
//! The recording is read as `export` and `plot` read it (sequence order, displacements from the
//! rest position); frames without a jaw pose are skipped and counted.

use crate::export::{load, rest_pose};
use crate::motion::{Displacement, Incisor};
use crate::plot::{self, Series, Style};
use anyhow::{Context, Result, bail};
use clap::Args;
use nalgebra::Point3;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack metrics`.
#[derive(Args)]
pub(crate) struct MetricsArgs {
    /// The recording (JSON lines).
    recording: PathBuf,
    /// The incisal point X,Y,Z in the mandible marker's frame (mm); default: the standard
    /// harness mounting's.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    incisor: Option<Point3<f64>>,
    /// The frame (its `frame` number) whose jaw pose is the rest position; default: the first
    /// frame with one.
    #[arg(long)]
    rest_frame: Option<u64>,
    /// Output folder for the envelope plots (SVG and PNG) and metrics.json.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print one JSON object (the content of metrics.json) instead of the summary.
    #[arg(long)]
    json: bool,
}

/// Parses `X,Y,Z` (mm) into a point.
fn parse_point(s: &str) -> Result<Point3<f64>, String> {
    let v: Vec<f64> =
        s.split(',').map(|c| c.trim().parse::<f64>().map_err(|e| format!("'{c}': {e}"))).collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Point3::new(x, y, z)),
        [_, _, _] => Err("the coordinates must be finite".into()),
        _ => Err(format!("expected X,Y,Z (three numbers in mm), got {} numbers", v.len())),
    }
}

/// One frame of the path: its time (s), its `frame` number, the incisor's displacement.
pub(crate) type Sample = (f64, u64, Displacement);

/// The largest value of one displacement measure and where it happens.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Extreme {
    /// The value (mm).
    pub mm: f64,
    /// The frame's `frame` number.
    pub frame: u64,
    /// The frame's time (s).
    pub t: f64,
}

impl Extreme {
    /// The first sample where `f` is largest (`None` for no samples).
    fn of(path: &[Sample], f: impl Fn(&Displacement) -> f64) -> Option<Self> {
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

    fn to_json(self) -> Value {
        json!({ "mm": self.mm, "frame": self.frame, "t_s": self.t })
    }
}

/// The convex hull of the path in one plane.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Envelope {
    /// The hull's corners (mm), counter-clockwise, no point repeated, no collinear corners.
    pub hull: Vec<(f64, f64)>,
    /// Its area (mm²); 0 when the path is a point or a line.
    pub area_mm2: f64,
}

impl Envelope {
    fn of(points: &[(f64, f64)]) -> Self {
        let hull = convex_hull(points);
        let area_mm2 = polygon_area(&hull);
        Envelope { hull, area_mm2 }
    }

    fn to_json(&self, x: &str, y: &str) -> Value {
        json!({
            "axes": [x, y],
            "area_mm2": self.area_mm2,
            "vertices": self.hull.len(),
            "hull_mm": self.hull.iter().map(|&(a, b)| [a, b]).collect::<Vec<_>>(),
        })
    }
}

/// The incisor's motion metrics over a path (displacements from rest, mm).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Metrics {
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
    /// Farthest back (−protrusive), as a positive number.
    pub max_retrusion: Extreme,
    /// Sagittal envelope: x protrusive, y opening.
    pub sagittal: Envelope,
    /// Frontal envelope: x lateral (patient's left), y opening.
    pub frontal: Envelope,
}

impl Metrics {
    /// The metrics of `path`; `None` when it is empty.
    pub(crate) fn compute(path: &[Sample]) -> Option<Self> {
        let plane = |f: fn(&Displacement) -> (f64, f64)| path.iter().map(|(_, _, d)| f(d)).collect::<Vec<_>>();
        Some(Metrics {
            frames: path.len(),
            max_opening: Extreme::of(path, |d| d.opening)?,
            max_left: Extreme::of(path, |d| d.lateral)?,
            max_right: Extreme::of(path, |d| -d.lateral)?,
            max_protrusion: Extreme::of(path, |d| d.protrusive)?,
            max_retrusion: Extreme::of(path, |d| -d.protrusive)?,
            sagittal: Envelope::of(&plane(sagittal)),
            frontal: Envelope::of(&plane(frontal)),
        })
    }

    fn to_json(&self) -> Value {
        json!({
            "frames_used": self.frames,
            "max_opening": self.max_opening.to_json(),
            "max_left_lateral": self.max_left.to_json(),
            "max_right_lateral": self.max_right.to_json(),
            "max_protrusion": self.max_protrusion.to_json(),
            "max_retrusion": self.max_retrusion.to_json(),
            "envelope_sagittal": self.sagittal.to_json("protrusive_mm", "opening_mm"),
            "envelope_frontal": self.frontal.to_json("lateral_mm", "opening_mm"),
        })
    }
}

/// A displacement in the sagittal plane: (protrusive, opening).
fn sagittal(d: &Displacement) -> (f64, f64) {
    (d.protrusive, d.opening)
}

/// A displacement in the frontal plane: (lateral, opening).
fn frontal(d: &Displacement) -> (f64, f64) {
    (d.lateral, d.opening)
}

/// (b − a) × (c − a): positive when a → b → c turns counter-clockwise.
fn cross(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> f64 {
    (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
}

/// The convex hull (Andrew's monotone chain): corners counter-clockwise from the lowest-x
/// point, collinear points and duplicates dropped, non-finite points ignored. One or two
/// corners when the points are all equal or all on a line.
pub(crate) fn convex_hull(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points.iter().copied().filter(|q| q.0.is_finite() && q.1.is_finite()).collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    // Lower chain left to right, upper chain right to left; each drops any corner that does not
    // turn left.
    let chain = |iter: &mut dyn Iterator<Item = (f64, f64)>| {
        let mut h: Vec<(f64, f64)> = Vec::new();
        for q in iter {
            while h.len() >= 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        // The last point starts the other chain.
        h.pop();
        h
    };
    let mut hull = chain(&mut p.iter().copied());
    hull.extend(chain(&mut p.iter().rev().copied()));
    hull
}

/// The area of a simple polygon (shoelace formula), whatever its orientation.
pub(crate) fn polygon_area(corners: &[(f64, f64)]) -> f64 {
    let n = corners.len();
    if n < 3 {
        return 0.0;
    }
    let twice: f64 = (0..n)
        .map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum();
    twice.abs() / 2.0
}

/// Runs `jawtrack metrics`.
pub(crate) fn run(a: &MetricsArgs) -> Result<()> {
    let name = a.recording.display();
    let rec = load(&a.recording)?;
    if rec.frames.is_empty() {
        bail!("{name}: the recording has no frames ({} unreadable lines skipped)", rec.skipped.len());
    }
    let Some(rest) = rest_pose(&rec.frames, a.rest_frame)? else {
        bail!("{name}: no frame has a jaw pose (both markers tracked), nothing to measure");
    };
    let rest_frame =
        a.rest_frame.or_else(|| rec.frames.iter().find(|f| f.maxilla_from_mandible.is_some()).map(|f| f.frame));
    let incisor = a.incisor.map_or_else(Incisor::standard, Incisor::at);
    let path: Vec<Sample> = rec
        .frames
        .iter()
        .filter_map(|f| f.maxilla_from_mandible.map(|m| (f.t, f.frame, incisor.displacement(&m, &rest))))
        .collect();
    let skipped = rec.frames.len() - path.len();
    let metrics = Metrics::compute(&path).context("no frame has a jaw pose")?;
    let p = incisor.point_in_mandible_marker();
    let mut report = metrics.to_json();
    if let Value::Object(o) = &mut report {
        o.insert("recording".into(), json!(a.recording.to_string_lossy()));
        o.insert("frames_total".into(), json!(rec.frames.len()));
        o.insert("frames_skipped_no_pose".into(), json!(skipped));
        o.insert("rest_frame".into(), json!(rest_frame));
        o.insert("incisor_in_mandible_marker_mm".into(), json!([p.x, p.y, p.z]));
        o.insert("incisor_standard".into(), json!(a.incisor.is_none()));
    }
    if skipped > 0 {
        eprintln!("{name}: {skipped} of {} frames have no jaw pose, skipped", rec.frames.len());
    }
    if let Some(out) = &a.out {
        write_outputs(out, &path, &metrics, &report)?;
    }
    if a.json {
        say!("{report}");
    } else {
        print_summary(&metrics, skipped, rest_frame, &incisor, a.incisor.is_none());
    }
    Ok(())
}

fn print_summary(m: &Metrics, skipped: usize, rest_frame: Option<u64>, incisor: &Incisor, standard: bool) {
    let p = incisor.point_in_mandible_marker();
    let rest = rest_frame.map_or_else(|| "?".to_owned(), |n| n.to_string());
    say!("frames              {} with a jaw pose, {skipped} skipped (no jaw pose); rest: frame {rest}", m.frames);
    // Rounding noise of the standard point's zero would print as "-0.00".
    let mm = |v: f64| match format!("{v:.2}") {
        s if s == "-0.00" => "0.00".to_owned(),
        s => s,
    };
    say!(
        "incisal point       ({}, {}, {}) mm in the mandible marker's frame{}",
        mm(p.x),
        mm(p.y),
        mm(p.z),
        if standard { " (standard mounting)" } else { "" }
    );
    for (label, e) in [
        ("max opening", m.max_opening),
        ("max left lateral", m.max_left),
        ("max right lateral", m.max_right),
        ("max protrusion", m.max_protrusion),
        ("max retrusion", m.max_retrusion),
    ] {
        say!("{label:<19} {:7.2} mm   (frame {}, t {:.3} s)", e.mm, e.frame, e.t);
    }
    for (label, e) in [("sagittal envelope", &m.sagittal), ("frontal envelope", &m.frontal)] {
        say!("{label:<19} {:7.2} mm²  ({} hull vertices)", e.area_mm2, e.hull.len());
    }
}

/// Writes the two envelope plots (path and hull outline) and metrics.json into `out`.
fn write_outputs(out: &Path, path: &[Sample], m: &Metrics, report: &Value) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    // Plotted with "up" upward, as `plot` draws the incisor's path.
    let up = |(x, y): (f64, f64)| (x, -y);
    let charts = [
        (
            "envelope_sagittal",
            "Envelope of motion, sagittal plane (patient facing right)",
            "protrusive (mm)",
            sagittal as fn(&Displacement) -> (f64, f64),
            &m.sagittal,
        ),
        (
            "envelope_frontal",
            "Envelope of motion, frontal plane (seen from the front)",
            "patient's left (mm)",
            frontal,
            &m.frontal,
        ),
    ];
    for (stem, title, x_label, project, envelope) in charts {
        // The hull closed back to its first corner.
        let outline = envelope.hull.iter().chain(envelope.hull.first()).map(|&q| up(q)).collect();
        // The hull first, so the path stays visible where it runs along the outline.
        let series = [
            Series { name: "envelope (convex hull)", color: "#1f77b4", style: Style::Line, points: outline },
            Series {
                name: "lower incisor",
                color: "#d62728",
                style: Style::Line,
                points: path.iter().map(|(_, _, d)| up(project(d))).collect(),
            },
        ];
        let doc = plot::chart(title, x_label, "up (mm)", &series, true);
        for p in plot::save_svg_and_png(&doc, &out.join(stem))? {
            eprintln!("wrote {}", p.display());
        }
    }
    let json_path = out.join("metrics.json");
    let text = serde_json::to_string_pretty(report).context("metrics as JSON")?;
    std::fs::write(&json_path, text + "\n").with_context(|| format!("writing {}", json_path.display()))?;
    eprintln!("wrote {}", json_path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(opening: f64, lateral: f64, protrusive: f64) -> Displacement {
        Displacement { opening, lateral, protrusive }
    }

    /// Whether `q` is inside or on the counter-clockwise polygon `hull`.
    fn inside(hull: &[(f64, f64)], q: (f64, f64)) -> bool {
        (0..hull.len()).all(|i| cross(hull[i], hull[(i + 1) % hull.len()], q) >= -1e-12)
    }

    #[test]
    fn a_square_with_interior_and_edge_points_has_four_corners() {
        let mut pts = vec![(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)];
        pts.extend([(1.0, 1.0), (0.5, 1.5), (1.0, 0.0), (2.0, 1.0), (0.0, 0.0), (1.9, 0.1)]);
        let hull = convex_hull(&pts);
        assert_eq!(hull, vec![(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)], "counter-clockwise, no edge points");
        assert_eq!(polygon_area(&hull), 4.0);
        assert!(pts.iter().all(|&q| inside(&hull, q)));
    }

    #[test]
    fn a_random_cloud_is_inside_its_convex_hull() {
        // A fixed pseudo-random cloud (LCG), so the test needs no seed crate.
        let mut s: u64 = 12345;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 10.0 - 5.0
        };
        let pts: Vec<(f64, f64)> = (0..200).map(|_| (next(), next())).collect();
        let hull = convex_hull(&pts);
        assert!(hull.len() >= 3 && pts.iter().all(|&q| inside(&hull, q)));
        for i in 0..hull.len() {
            let (a, b, c) = (hull[i], hull[(i + 1) % hull.len()], hull[(i + 2) % hull.len()]);
            assert!(cross(a, b, c) > 0.0, "strictly convex at {b:?}");
            assert!(pts.contains(&b), "corners are input points");
        }
        assert!(polygon_area(&hull) > 0.0 && polygon_area(&hull) <= 100.0);
    }

    #[test]
    fn collinear_points_give_the_two_ends_and_no_area() {
        let pts = [(1.0, 1.0), (3.0, 3.0), (2.0, 2.0), (0.0, 0.0), (3.0, 3.0)];
        assert_eq!(convex_hull(&pts), vec![(0.0, 0.0), (3.0, 3.0)]);
        assert_eq!(polygon_area(&convex_hull(&pts)), 0.0);
        let vertical = [(0.0, 2.0), (0.0, -1.0), (0.0, 0.5)];
        assert_eq!(convex_hull(&vertical), vec![(0.0, -1.0), (0.0, 2.0)]);
    }

    #[test]
    fn fewer_than_three_points_are_their_own_hull() {
        assert!(convex_hull(&[]).is_empty());
        assert_eq!(convex_hull(&[(1.0, 2.0)]), vec![(1.0, 2.0)]);
        assert_eq!(convex_hull(&[(1.0, 2.0), (1.0, 2.0)]), vec![(1.0, 2.0)]);
        assert_eq!(convex_hull(&[(3.0, 0.0), (1.0, 2.0)]), vec![(1.0, 2.0), (3.0, 0.0)]);
        assert_eq!(convex_hull(&[(f64::NAN, 0.0), (1.0, 2.0)]), vec![(1.0, 2.0)], "NaN ignored");
        assert_eq!(polygon_area(&[(0.0, 0.0), (1.0, 1.0)]), 0.0);
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
        ];
        let m = Metrics::compute(&path).expect("a path");
        assert_eq!(m.frames, 6);
        assert_eq!(m.max_opening, Extreme { mm: 30.0, frame: 11, t: 0.1 }, "ties keep the first frame");
        assert_eq!(m.max_left, Extreme { mm: 6.0, frame: 12, t: 0.2 });
        assert_eq!(m.max_right, Extreme { mm: 5.0, frame: 14, t: 0.3 });
        assert_eq!(m.max_protrusion, Extreme { mm: 8.0, frame: 15, t: 0.4 });
        assert_eq!(m.max_retrusion, Extreme { mm: 4.0, frame: 11, t: 0.1 });
        // Sagittal (protrusive, opening): corners (-4,30) (0,0) (8,3.2) (0,30).
        assert_eq!(m.sagittal.hull.len(), 4);
        assert!(
            (m.sagittal.area_mm2 - polygon_area(&[(0.0, 0.0), (8.0, 3.2), (0.0, 30.0), (-4.0, 30.0)])).abs() < 1e-12
        );
        assert!(path.iter().all(|(_, _, x)| inside(&m.frontal.hull, frontal(x))));
        assert!(path.iter().all(|(_, _, x)| inside(&m.sagittal.hull, sagittal(x))));
        let j = m.to_json();
        assert_eq!(j["max_right_lateral"]["mm"], 5.0);
        assert_eq!(j["envelope_sagittal"]["vertices"], 4);
    }

    #[test]
    fn a_path_at_rest_has_zero_metrics_and_no_path_has_none() {
        let m = Metrics::compute(&[(0.0, 0, d(0.0, 0.0, 0.0)), (0.1, 1, d(0.0, 0.0, 0.0))]).expect("a path");
        assert_eq!((m.max_opening.mm, m.max_left.mm, m.max_right.mm), (0.0, 0.0, 0.0));
        assert_eq!((m.sagittal.area_mm2, m.sagittal.hull.len()), (0.0, 1));
        assert!(Metrics::compute(&[]).is_none());
    }

    #[test]
    fn incisor_points_parse_and_bad_ones_say_why() {
        assert_eq!(parse_point("1,-2.5, 3"), Ok(Point3::new(1.0, -2.5, 3.0)));
        assert!(parse_point("1,2").is_err_and(|e| e.contains("three numbers")));
        assert!(parse_point("1,x,3").is_err_and(|e| e.contains("'x'")));
        assert!(parse_point("1,inf,3").is_err_and(|e| e.contains("finite")));
    }
}
