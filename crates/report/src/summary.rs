//! The words and figures of `jawtrack metrics`, `hinge-axis`, `articulator` and `contacts`:
//! the printed summary of a recording's lower-incisor metrics, the envelope and border charts
//! written beside `metrics.json`, the hinge axis, the articulator values and the CO–MI slide,
//! and what a contact run found; laid out here beside the report that shows the
//! same numbers.

use jawtrack_kinematics::articulator::name;
use jawtrack_kinematics::metrics::RETRUSION_OPENING_MM;
use jawtrack_kinematics::{
    Anatomy, ArticulatorOptions, ArticulatorValues, Border, CoMi, Incisor, Metrics, PlaneView, Sample, Side,
};
use jawtrack_occlusion::teeth::Tooth;
use jawtrack_plot::{Document, fixed};
use jawtrack_session::contact_run::ContactReport;
use jawtrack_session::measures::HingeReport;
use nalgebra::Vector3;

/// The summary `jawtrack metrics` prints: frames, the incisal point, the extreme positions
/// with their frames, the hulls and Posselt's border per plane. `rest` describes the rest
/// position; `standard` says the incisal point is the standard mounting's.
pub fn metrics_summary(
    m: &Metrics,
    path: &[Sample],
    skipped: usize,
    rest: &str,
    incisor: &Incisor,
    standard: bool,
) -> Vec<String> {
    let mm = |v: f64| fixed(v, 2);
    let p = incisor.point_in_mandible_marker();
    let mut lines = vec![
        format!("frames              {} with a jaw pose, {skipped} skipped (no jaw pose); rest: {rest}", m.frames),
        format!(
            "incisal point       ({}, {}, {}) mm in the mandible marker's frame{}",
            mm(p.x),
            mm(p.y),
            mm(p.z),
            if standard { " (standard mounting)" } else { "" }
        ),
    ];
    for (label, e) in [
        ("max opening", m.max_opening),
        ("max left lateral", m.max_left),
        ("max right lateral", m.max_right),
        ("max protrusion", m.max_protrusion),
    ] {
        lines.push(format!("{label:<19} {:>7} mm   (frame {}, t {} s)", mm(e.mm), e.frame, fixed(e.t, 3)));
    }
    let near = fixed(RETRUSION_OPENING_MM, 0);
    lines.push(match m.max_retrusion {
        Some(e) => format!(
            "max retrusion       {:>7} mm   (frame {}, t {} s; opened at most {near} mm)",
            mm(e.mm),
            e.frame,
            fixed(e.t, 3)
        ),
        None => format!("max retrusion          none   (no frame opened {near} mm or less)"),
    });
    for (label, e) in [("sagittal hull", &m.sagittal), ("frontal hull", &m.frontal)] {
        lines.push(format!("{label:<19} {:>7} mm²  (convex hull; {} vertices)", mm(e.area_mm2), e.hull.len()));
    }
    for view in PlaneView::ALL {
        let b = Border::of(view, path, m);
        let name = format!("{} border", view.name());
        lines.push(format!("{name:<19} {:>7} mm²  (traced; {} outline points)", fixed(b.area_mm2, 2), b.outline.len()));
    }
    lines
}

/// The figures `jawtrack metrics --out` writes, each with its file stem: the path and its hull
/// outline in the sagittal and frontal planes (`envelope_*`), and Posselt's border as traced in
/// all three planes (`border_*`).
pub fn metrics_figures(path: &[Sample], m: &Metrics) -> Vec<(String, Document)> {
    let mut figures = Vec::new();
    for (view, envelope) in [(PlaneView::Sagittal, &m.sagittal), (PlaneView::Frontal, &m.frontal)] {
        figures.push((format!("envelope_{}", view.name()), crate::envelope_chart(view, envelope, path)));
    }
    for view in PlaneView::ALL {
        figures.push((format!("border_{}", view.name()), crate::border_chart(&Border::of(view, path, m), path)));
    }
    figures
}

/// What `jawtrack contacts` found, as it prints it: frames checked, the deepest contact (or the
/// smallest gap), per-tooth totals; and a warning when the arches never came within
/// `threshold_mm`, naming where the poses came from (`source`).
pub fn contact_findings(found: &ContactReport, threshold_mm: f64, source: &str) -> (Vec<String>, Option<String>) {
    let (s, t) = (&found.summary, threshold_mm);
    let skipped = match found.skipped_no_pose {
        0 => String::new(),
        n => format!(", {n} without a pose skipped"),
    };
    let (checked, near, deep) = (s.frames, s.with_contact, s.penetrating);
    let mut lines =
        vec![format!("{checked} frames checked of {}{skipped}; {near} within {t} mm, {deep} penetrating", found.read)];
    let mut warning = None;
    match s.deepest {
        Some(d) if d.depth_mm > 0.0 => lines.push(format!(
            "deepest penetration {} mm at frame {} (t {} s)",
            fixed(d.depth_mm, 3),
            d.frame,
            fixed(d.t, 3)
        )),
        Some(d) => lines.push(format!(
            "no penetration; smallest gap {} mm at frame {} (t {} s)",
            fixed(-d.depth_mm, 3),
            d.frame,
            fixed(d.t, 3)
        )),
        None => {
            lines.push(format!("no contact within {t} mm"));
            warning = Some(format!(
                "the arches never came within {t} mm in any of the {checked} frames checked: a recording that \
                 includes the bite always touches; check that the scans and the poses ({source}) belong together"
            ));
        }
    }
    if !found.teeth.is_empty() {
        lines.push("tooth          frames in contact   largest area   deepest".to_owned());
        for t in &found.teeth {
            let label = t.fdi.and_then(Tooth::fdi).map_or_else(|| t.name.clone(), Tooth::label);
            lines.push(format!(
                "{label:<14} {:>17}   {:>9} mm²   {:>7} mm",
                t.frames_in_contact,
                fixed(t.max_area_mm2, 2),
                fixed(t.max_depth_mm, 3)
            ));
        }
    }
    (lines, warning)
}

/// The hinge axis as `jawtrack hinge-axis` prints it: the poses used, the axis in the maxilla
/// marker's frame (and the upper scan's, given a registration), its uncertainty, and each
/// condyle moved onto it.
pub fn hinge_summary(r: &HingeReport) -> Vec<String> {
    let axis = r.axis;
    let v = |v: &Vector3<f64>, digits: usize| {
        format!("({}, {}, {})", fixed(v.x, digits), fixed(v.y, digits), fixed(v.z, digits))
    };
    let mut lines = vec![
        format!(
            "poses              {} of {} in the window, turned up to {}° from the closed jaw ({})",
            axis.poses,
            r.frames,
            fixed(axis.max_rotation_deg, 1),
            r.rest.describe()
        ),
        format!("point              {} mm in the maxilla marker's frame", v(&axis.point.coords, 2)),
        format!("direction          {}", v(&axis.direction, 4)),
    ];
    if let Some((p, d)) = r.scan {
        lines.push(format!("point (upper scan) {} mm", v(&p.coords, 2)));
        lines.push(format!("direction (scan)   {}", v(&d, 4)));
    }
    lines.push(format!(
        "uncertainty (1σ)   {} mm across the axis, {}° in direction; residual RMS {} mm",
        fixed(axis.point_sigma_mm, 2),
        fixed(axis.direction_sigma_deg, 2),
        fixed(axis.rms_mm, 3)
    ));
    lines.push(
        "the point is the axis's nearest to the mandible marker at rest, about midway between the condyles".into(),
    );
    let ([l, rt], whose) = r.condyles;
    for (name, c) in [("left", l), ("right", rt)] {
        let p = axis.project(&c).coords;
        let moved = fixed(axis.distance_to(&c), 2);
        lines.push(format!("{name} condyle on the axis {} mm, moved {moved} mm ({whose})", v(&p, 2)));
    }
    lines
}

/// The articulator values as `jawtrack articulator` prints them: per condyle the inclination,
/// Bennett angle and immediate side shift, then the incisal guidances, read over `o.over_mm`
/// from `rest`; "—" where a movement was not given.
pub fn articulator_summary(
    v: &ArticulatorValues,
    o: &ArticulatorOptions,
    anatomy: &Anatomy,
    rest: &str,
) -> Vec<String> {
    let deg = |x: Option<f64>| x.map_or("—".to_string(), |x| format!("{}°", fixed(x, 1)));
    let mm = |x: Option<f64>| x.map_or("—".to_string(), |x| format!("{} mm", fixed(x, 2)));
    let pair = |label: &str, [l, r]: [String; 2]| format!("{label:<24} {l:>12}   {r:>13}");
    let mut lines = vec![
        format!("read over the first {} mm of each path, from {rest}", fixed(o.over_mm, 1)),
        "                         left condyle   right condyle".to_owned(),
        pair("condylar inclination", v.condylar_inclination_deg.map(deg)),
        pair("Bennett angle", v.bennett_deg.map(deg)),
        pair("immediate side shift", v.side_shift_mm.map(mm)),
        format!("protrusive incisal guidance {}", deg(v.protrusive_guidance_deg)),
    ];
    for (k, side) in [Side::Left, Side::Right].iter().enumerate() {
        lines.push(format!("lateral incisal guidance toward the {} {}", name(*side), deg(v.lateral_guidance_deg[k])));
    }
    lines.push(format!("angles are to {}; the landmarks are {}", anatomy.reference_plane, anatomy.landmarks));
    lines
}

/// The CO–MI slide as `jawtrack articulator --co` prints it: how far the lower incisal point
/// and each condyle moved from centric occlusion into maximal intercuspation (`mi` says which).
pub fn co_mi_summary(s: &CoMi, mi: &str) -> Vec<String> {
    let mm = |x: f64| fixed(x, 2);
    let mut lines = vec![
        format!("CO–MI slide, from centric occlusion into maximal intercuspation ({mi}), mm:"),
        "                          forward     down   toward left   length".to_owned(),
    ];
    for (name, d) in
        [("lower incisal point", s.incisor), ("left condyle", s.condyles[0]), ("right condyle", s.condyles[1])]
    {
        lines.push(format!(
            "{name:<22} {:>10} {:>8} {:>13} {:>8}",
            mm(d.protrusive),
            mm(d.opening),
            mm(d.lateral),
            mm(d.norm())
        ));
    }
    lines
}
