//! The report's sections, in order: each computes its numbers through `jawtrack_kinematics` and
//! lays them out. A section with nothing to show says why, and which flag would fill it.

use crate::html::{esc, facts, figure, not_measured, page, section, table};
use crate::{BLUE, GREEN, Inputs, Record, Report, Window};
use jawtrack_kinematics::articulator::name as side_name;
use jawtrack_kinematics::border::{Border, LANDMARK_MIN_MM, tag};

use jawtrack_kinematics::metrics::{RETRUSION_OPENING_MM, count_openings};
use jawtrack_kinematics::{
    ArticulatorOptions, ArticulatorValues, Displacement, HingeAxis, HingeOptions, Incisor, KinematicsError, Metrics,
    Movements, PlaneView, Sample, Side, co_mi, hinge,
};
use jawtrack_marker::BodyKind;
use jawtrack_plot::{Series, Style, chart, fixed};
use jawtrack_pose::{Pose, median};
use nalgebra::{Point3, Vector3};
use std::time::{Duration, UNIX_EPOCH};

/// Sections, by id and title, in page order.
const SECTIONS: [(&str, &str); 10] = [
    ("session", "Session and calibration"),
    ("quality", "Quality"),
    ("incisor", "Lower incisor"),
    ("border", "Border movements (Posselt)"),
    ("condyles", "Condylar paths"),
    ("hinge", "Kinematic hinge axis"),
    ("articulator", "Articulator values"),
    ("co-mi", "CO–MI"),
    ("contacts", "Occlusal contacts"),
    ("definitions", "Units, frames and definitions"),
];

/// `x` mm with `d` decimals, or a dash.
fn mm(x: Option<f64>, d: usize) -> String {
    x.map_or_else(|| "—".into(), |x| format!("{} mm", fixed(x, d)))
}

fn deg(x: Option<f64>) -> String {
    x.map_or_else(|| "—".into(), |x| format!("{}°", fixed(x, 1)))
}

fn when(unix_s: f64) -> String {
    if unix_s.is_finite() && unix_s > 0.0 {
        httpdate::fmt_http_date(UNIX_EPOCH + Duration::from_secs_f64(unix_s))
    } else {
        "unknown".into()
    }
}

fn window_words(w: &Window) -> String {
    format!("{}–{} s", fixed(w.from, 2), fixed(w.to, 2))
}

/// The poses in a window.
fn poses_in(inputs: &Inputs, w: Window) -> Vec<Pose> {
    inputs.recording.frames.iter().filter(|f| w.holds(f.t)).filter_map(|f| f.maxilla_from_mandible).collect()
}

/// The hinge axis fitted to the opening window, when one was given: the hinge section shows it
/// and a warning compares the condyles with it.
type HingeFit = Option<(Window, Result<HingeAxis, KinematicsError>)>;

pub(crate) fn render(inputs: &Inputs, record: &Record) -> Report {
    let rec = inputs.recording;
    let mounting = inputs.anatomy.mounting;
    let path: Vec<Sample> = jawtrack_session::incisor::path(&rec.frames, &Incisor::of(mounting), &inputs.rest);
    let metrics = Metrics::compute(&path);
    let fit: HingeFit = inputs
        .windows
        .opening
        .map(|w| (w, hinge::fit(&poses_in(inputs, w), &inputs.rest, None, &HingeOptions::default())));
    let mut warnings = quality_warnings(inputs, path.len());
    if let Some((_, Ok(axis))) = &fit {
        warnings.extend(crate::cautions::condyles_off_axis(inputs, axis));
    }
    let mut body = String::new();
    body += &section("session", SECTIONS[0].1, &session(inputs, record));
    body += &section("quality", SECTIONS[1].1, &quality(inputs, path.len(), &warnings));
    match &metrics {
        Some(m) => {
            body += &section("incisor", SECTIONS[2].1, &incisor_section(m, &path));
            body += &section("border", SECTIONS[3].1, &border_section(m, &path));
            body += &section("condyles", SECTIONS[4].1, &condyles_section(inputs));
        }
        None => {
            let none = not_measured("no frame has a jaw pose (both markers tracked)", "Track the session again.");
            warnings.push("no frame has a jaw pose: nothing could be measured".into());
            for (id, title) in &SECTIONS[2..5] {
                body += &section(id, title, &none);
            }
        }
    }
    body += &section("hinge", SECTIONS[5].1, &hinge_section(inputs, &fit));
    body += &section("articulator", SECTIONS[6].1, &articulator_section(inputs));
    body += &section("co-mi", SECTIONS[7].1, &co_mi_section(inputs));
    body += &section("contacts", SECTIONS[8].1, &contacts_section(inputs));
    body += &section("definitions", SECTIONS[9].1, &definitions(inputs));
    let header = format!(
        "<h1>JawTrack session report</h1><p>{} · made {} · JawTrack {}</p>",
        esc(&inputs.recording_name),
        when(inputs.made_unix_s),
        env!("CARGO_PKG_VERSION")
    );
    let html = page(&format!("JawTrack report: {}", inputs.recording_name), &header, &SECTIONS, &body);
    Report { html, sections: SECTIONS.iter().map(|(id, _)| *id).collect(), warnings }
}

fn session(inputs: &Inputs, record: &Record) -> String {
    let rec = inputs.recording;
    let h = rec.header.as_ref();
    let t: Vec<f64> = rec.frames.iter().map(|f| f.t).collect();
    let (first, last) =
        (t.iter().copied().fold(f64::INFINITY, f64::min), t.iter().copied().fold(f64::NEG_INFINITY, f64::max));
    let steps = t.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0);
    let fps = median(steps).map_or("—".into(), |d| format!("{} frames/s", fixed(1.0 / d, 1)));
    let camera = h.and_then(|h| h.intrinsics.as_ref()).map_or("not recorded".into(), |c| {
        format!(
            "fx {} px, fy {} px, principal point ({}, {}) px, k1 {}, k2 {}",
            fixed(c.fx, 1),
            fixed(c.fy, 1),
            fixed(c.cx, 1),
            fixed(c.cy, 1),
            fixed(c.k1, 4),
            fixed(c.k2, 4)
        )
    });
    let shutter = match h.and_then(|h| h.readout_s) {
        Some(r) if r > 0.0 => format!("rolling, readout {} ms", fixed(r * 1000.0, 2)),
        Some(_) => "global (readout 0)".into(),
        None => "not recorded".into(),
    };
    let a = &inputs.anatomy;
    let file = |f: &Option<String>| f.as_deref().map_or("none".into(), esc);
    let sessions = rec.sessions();
    let mut rows = crate::record::rows(record);
    rows.extend([
        ("Recording", esc(&inputs.recording_name)),
        ("Written by", h.map_or("unknown (no header)".into(), |h| esc(&h.source))),
        ("Device", esc(h.and_then(|h| h.device.as_deref()).unwrap_or("not recorded"))),
        ("Started", h.map_or("unknown".into(), |h| when(h.created_unix_s))),
        (
            "Session",
            match sessions.len() {
                0 => h.and_then(|h| h.session).map_or("not recorded".into(), |s| s.to_string()),
                1 => sessions[0].to_string(),
                n => format!("{n} sessions in one file (all are shown)"),
            },
        ),
        (
            "Frames",
            if t.is_empty() {
                "none".into()
            } else {
                format!("{} over {} s ({fps})", rec.frames.len(), fixed(last - first, 2))
            },
        ),
        ("Camera", camera),
        ("Shutter", shutter),
        ("Marker", marker_words(inputs)),
        ("Registration", file(&inputs.registration_file)),
        ("Anatomical points", file(&inputs.points_file)),
        ("Reference plane", esc(a.reference_plane)),
        ("Condyles and incisal point", esc(a.landmarks)),
        ("Closed jaw (rest)", esc(&inputs.rest_words)),
    ]);
    facts(&rows)
}

/// The marker the frames were tracked with: calibrated (how many of its tags were measured, in
/// all and per body, out of the tags the marker has) or nominal.
fn marker_words(inputs: &Inputs) -> String {
    let Some(marker) = tracked_marker(inputs) else { return "not recorded".into() };
    let measured = marker.measured_tags();
    if measured.is_empty() {
        return "nominal (the ideal solid's tag places; not calibrated)".into();
    }
    let bodies: Vec<String> = BodyKind::ALL
        .iter()
        .filter_map(|&kind| {
            let tags = &marker.body(kind)?.tags;
            let n = tags.iter().filter(|t| measured.contains(&t.id)).count();
            Some(format!("{kind} {n} of {}", tags.len()))
        })
        .collect();
    format!("calibrated: {} of {} tags measured ({})", measured.len(), marker.tags().count(), bodies.join(", "))
}

fn tracked_marker(inputs: &Inputs) -> Option<jawtrack_marker::Marker> {
    inputs.recording.header.as_ref()?.tracked_marker()?.ok()
}

fn marker_measured(inputs: &Inputs) -> Option<usize> {
    Some(tracked_marker(inputs)?.measured_tags().len())
}

fn quality_warnings(inputs: &Inputs, with_pose: usize) -> Vec<String> {
    let rec = inputs.recording;
    let mut w = Vec::new();
    let total = rec.frames.len();
    if total > 0 && (with_pose as f64) < 0.9 * total as f64 {
        w.push(format!(
            "only {with_pose} of {total} frames ({} %) have a jaw pose: paths may miss extremes",
            fixed(100.0 * with_pose as f64 / total as f64, 0)
        ));
    }
    let is_defocused =
        |n: &String| matches!(jawtrack_recording::Flag::from_name(n), Some(jawtrack_recording::Flag::Defocused(_)));
    let defocused = rec.frames.iter().filter(|f| f.flags.iter().any(is_defocused)).count();
    if defocused > 0 {
        w.push(format!(
            "{defocused} of {total} frames had a marker out of focus (BODY:defocused) and give no jaw pose: the phone \
             was nearer than its lens focuses, or far from where focus was locked (jawtrack plan says where to hold it)"
        ));
    }
    let gap = longest_gap(inputs);
    if gap > 0.5 {
        w.push(format!("tracking paused for {} s at the longest: no path is drawn across a pause", fixed(gap, 2)));
    }
    if marker_measured(inputs) == Some(0) {
        w.push(
            "tracked with the nominal marker: on rendered sessions with a print's usual error, condylar inclinations \
             moved 7–22° and the hinge axis 2 mm; calibrate the marker (jawtrack calibrate-marker) and track again"
                .into(),
        );
    }
    if !rec.skipped.is_empty() {
        w.push(format!(
            "{} lines of the file were not frames and were skipped (a cut last line is one)",
            rec.skipped.len()
        ));
    }
    if inputs.points_file.is_none() {
        w.push(
            "no anatomical points: the standard harness mounting stands in for the patient's occlusal plane and \
             condyles (jawtrack points, then --points)"
                .into(),
        );
    }
    w
}

/// The longest time (s) between frames with a jaw pose.
fn longest_gap(inputs: &Inputs) -> f64 {
    let t: Vec<f64> =
        inputs.recording.frames.iter().filter(|f| f.maxilla_from_mandible.is_some()).map(|f| f.t).collect();
    t.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max)
}

fn quality(inputs: &Inputs, with_pose: usize, warnings: &[String]) -> String {
    let rec = inputs.recording;
    let total = rec.frames.len();
    let rms = |body: fn(&jawtrack_recording::FrameRecord) -> Option<f64>| {
        let mut v: Vec<f64> = rec.frames.iter().filter_map(body).collect();
        v.sort_by(f64::total_cmp);
        let Some(mid) = median(v.iter().copied()) else { return "—".into() };
        // The nearest rank.
        let p95 = v[((v.len() - 1) as f64 * 0.95).round() as usize];
        format!("median {} px, 95th percentile {} px", fixed(mid, 3), fixed(p95, 3))
    };
    let mut flags: Vec<(String, usize)> = Vec::new();
    for f in rec.frames.iter().flat_map(|f| &f.flags) {
        match flags.iter_mut().find(|(n, _)| n == f) {
            Some((_, c)) => *c += 1,
            None => flags.push((f.clone(), 1)),
        }
    }
    flags.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let mut s = String::new();
    if warnings.is_empty() {
        s += "<p class=\"ok\">No quality warning.</p>";
    }
    for w in warnings {
        s += &format!("<p class=\"warn\">{}</p>", esc(w));
    }
    s += &facts(&[
        (
            "Frames with a jaw pose",
            if total == 0 {
                "no frames".into()
            } else {
                format!("{with_pose} of {total} ({} %)", fixed(100.0 * with_pose as f64 / total as f64, 1))
            },
        ),
        ("Longest pause in tracking", format!("{} s", fixed(longest_gap(inputs), 3))),
        ("Reprojection error, maxilla", rms(|f| f.maxilla.as_ref().map(|b| b.rms_px))),
        ("Reprojection error, mandible", rms(|f| f.mandible.as_ref().map(|b| b.rms_px))),
        ("Lines skipped", rec.skipped.len().to_string()),
        ("Tone curve the tags were read through", esc(&tone_line(rec))),
    ]);
    if flags.is_empty() {
        s += "<p>No frame carries a quality flag.</p>";
    } else {
        let rows: Vec<Vec<String>> = flags.iter().map(|(n, c)| vec![esc(n), c.to_string()]).collect();
        s += "<p>Quality flags raised by the tracker (frames carrying each):</p>";
        s += &table(&["flag", "frames"], &rows);
    }
    s
}

/// The curve the last frames were read through and how it was found: the last frame that
/// says so (a frame does where the curve changed or a fit added to its evidence).
fn tone_line(rec: &jawtrack_recording::Recording) -> String {
    rec.frames.iter().rev().find_map(|f| f.tone.as_ref()).map_or_else(
        || "not recorded (tracked before JawTrack estimated it: read as sRGB)".into(),
        jawtrack_recording::ToneRecord::describe,
    )
}

fn incisor_section(m: &Metrics, path: &[Sample]) -> String {
    let row = |name: &str, e: Option<jawtrack_kinematics::Extreme>| {
        e.map_or_else(
            || vec![name.into(), "—".into(), "—".into(), "—".into()],
            |e| vec![name.into(), mm(Some(e.mm), 1), e.frame.to_string(), format!("{} s", fixed(e.t, 2))],
        )
    };
    let openings = count_openings(&path.iter().map(|(_, _, d)| *d).collect::<Vec<_>>());
    let mut s = table(
        &["measure (lower incisal point, from the closed jaw)", "value", "frame", "time"],
        &[
            row("maximum opening", Some(m.max_opening)),
            row("maximum laterotrusion toward the patient's left", Some(m.max_left)),
            row("maximum laterotrusion toward the patient's right", Some(m.max_right)),
            row("maximum protrusion", Some(m.max_protrusion)),
            row(&format!("maximum retrusion (opened ≤ {} mm)", fixed(RETRUSION_OPENING_MM, 0)), m.max_retrusion),
        ],
    );
    s += &format!(
        "<p>{} frames with a jaw pose; the jaw opened {openings} times (rises of 3 mm or more, steeper than the \
         teeth guide a glide).</p>",
        m.frames
    );
    let widest = path.iter().find(|(_, f, _)| *f == m.max_opening.frame).map(|s| s.2);
    if let Some(d) = widest.filter(|d| !jawtrack_kinematics::metrics::opens(d)) {
        s += &format!(
            "<p class=\"warn\">No opening was recorded: the largest downward move of the incisor, {}, came with a \
             glide ({} sideways, {} forward), as the teeth guide the jaw; record an opening to measure one.</p>",
            mm(Some(d.opening), 1),
            mm(Some(d.lateral.abs()), 1),
            mm(Some(d.protrusive), 1)
        );
    }
    s
}

fn border_section(m: &Metrics, path: &[Sample]) -> String {
    let mut s = format!(
        "<p>The border is the outermost path the lower incisal point traced, seen from inside the region it \
         covers (not a convex hull): it follows the path into concave parts. Landmarks are the extremes of \
         {} mm or more where that movement was made (a widest opening that is an opening, a farthest left, right \
         or forward that is a glide); the movements between neighbouring landmarks are named below each plot.</p>\
         <div class=\"plots\">",
        fixed(LANDMARK_MIN_MM, 1)
    );
    let mut rows = Vec::new();
    let mut landmarks = Vec::new();
    for view in PlaneView::ALL {
        let b = Border::of(view, path, m);
        let moves: Vec<String> = b.arcs().into_iter().map(|(n, _)| esc(&n)).collect();
        let caption = format!(
            "{}: area {} mm². Movements: {}.",
            esc(view.title()),
            fixed(b.area_mm2, 0),
            if moves.is_empty() { "none on the border".into() } else { moves.join("; ") }
        );
        s += &figure(&crate::border_chart(&b, path).to_string(), &caption);
        rows.push(vec![view.name().into(), format!("{} mm²", fixed(b.area_mm2, 1)), b.outline.len().to_string()]);
        for l in &b.landmarks {
            if !landmarks.iter().any(|(n, _, _)| *n == l.name) {
                landmarks.push((l.name, l.frame, l.t));
            }
        }
    }
    s += "</div>";
    s += &table(&["plane", "area inside the border", "border points"], &rows);
    // Where each landmark is, in all three coordinates.
    let d_at = |frame: u64| path.iter().find(|(_, f, _)| *f == frame).map(|(_, _, d)| *d);
    let rows: Vec<Vec<String>> = landmarks
        .iter()
        .map(|&(name, frame, t)| {
            let d = if t.is_finite() {
                d_at(frame)
            } else {
                Some(Displacement { opening: 0.0, lateral: 0.0, protrusive: 0.0 })
            };
            let cell = |f: fn(&Displacement) -> f64| mm(d.as_ref().map(f), 1);
            vec![
                tag(name).into(),
                name.into(),
                cell(|d| d.protrusive),
                cell(|d| d.opening),
                cell(|d| d.lateral),
                if t.is_finite() { format!("{} s", fixed(t, 2)) } else { "rest".into() },
            ]
        })
        .collect();
    s += &table(&["tag", "landmark", "forward", "down", "toward the patient's left", "time"], &rows);
    s
}

/// Each condyle's displacement from the closed jaw over the session.
fn condyle_paths(inputs: &Inputs) -> [Vec<Displacement>; 2] {
    let m = inputs.anatomy.mounting;
    [Side::Left, Side::Right].map(|side| {
        let point = Incisor::fixed_at(m, &m.condyle(side));
        inputs
            .recording
            .frames
            .iter()
            .filter_map(|f| f.maxilla_from_mandible.map(|p| point.displacement(&p, &inputs.rest)))
            .collect()
    })
}

fn condyles_section(inputs: &Inputs) -> String {
    let paths = condyle_paths(inputs);
    let mut s = String::from("<div class=\"plots\">");
    for view in [PlaneView::Sagittal, PlaneView::Transverse] {
        let series: Vec<Series> = [(Side::Left, BLUE), (Side::Right, GREEN)]
            .iter()
            .zip(&paths)
            .map(|((side, color), p)| Series {
                name: if *side == Side::Left { "left condyle" } else { "right condyle" },
                color,
                style: Style::Line,
                points: p.iter().map(|d| view.project(d)).collect(),
            })
            .collect();
        let (x, y) = view.axes();
        let svg = chart(&format!("Condyles, {}", view.title()), x, y, &series, true).to_string();
        s += &figure(&svg, &format!("Both condyles' paths from the closed jaw, {}.", esc(view.title())));
    }
    s += "</div>";
    let max = |p: &[Displacement], f: fn(&Displacement) -> f64| p.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
    let rows: Vec<Vec<String>> = [Side::Left, Side::Right]
        .iter()
        .zip(&paths)
        .map(|(side, p)| {
            vec![
                side_name(*side).into(),
                mm(Some(max(p, |d| d.protrusive)), 2),
                mm(Some(max(p, |d| d.opening)), 2),
                mm(Some(max(p, |d| d.lateral.abs())), 2),
                mm(Some(max(p, Displacement::norm)), 2),
            ]
        })
        .collect();
    s += &table(&["condyle", "farthest forward", "farthest down", "farthest sideways", "farthest travel"], &rows);
    s
}

fn hinge_section(inputs: &Inputs, fit: &HingeFit) -> String {
    let Some((w, fitted)) = fit else {
        return not_measured(
            "the hinge axis",
            "Give the window of a slow opening from the closed jaw: <code>--opening FROM:TO</code> (s).",
        );
    };
    let axis = match fitted {
        Ok(a) => a,
        Err(e) => return format!("<p class=\"warn\">The opening {}: {}</p>", window_words(w), esc(&e.to_string())),
    };
    let m = inputs.anatomy.mounting;
    let head_from_maxilla = m.head_from_maxilla;
    let v3 = |v: &Vector3<f64>, d: usize| format!("({}, {}, {})", fixed(v.x, d), fixed(v.y, d), fixed(v.z, d));
    let point_head = head_from_maxilla.transform_point(&axis.point).coords;
    let dir_head = head_from_maxilla.rotation() * axis.direction.into_inner();
    let maxilla_from_head = head_from_maxilla.inverse();
    let mut rows = vec![
        (
            "Window",
            format!(
                "{} ({} poses used, turned up to {}°)",
                window_words(w),
                axis.poses,
                fixed(axis.max_rotation_deg, 1)
            ),
        ),
        ("Point, maxilla marker's frame", format!("{} mm", v3(&axis.point.coords, 2))),
        ("Direction, maxilla marker's frame", v3(&axis.direction, 4)),
        ("Point, head frame", format!("{} mm", v3(&point_head, 2))),
        ("Direction, head frame", v3(&dir_head, 4)),
        (
            "Uncertainty (1σ)",
            format!(
                "{} mm across the axis, {}° in direction; residual RMS {} mm (scatter only: a bias common to the \
                 frames does not show)",
                fixed(axis.point_sigma_mm, 2),
                fixed(axis.direction_sigma_deg, 2),
                fixed(axis.rms_mm, 3)
            ),
        ),
    ];
    for side in [Side::Left, Side::Right] {
        let c = maxilla_from_head.transform_point(&Point3::from(m.condyle(side)));
        rows.push((
            if side == Side::Left { "Left condyle moved onto the axis" } else { "Right condyle moved onto the axis" },
            format!(
                "{} mm in the head frame, moved {} mm",
                v3(&head_from_maxilla.transform_point(&axis.project(&c)).coords, 2),
                fixed(axis.distance_to(&c), 2)
            ),
        ));
    }
    facts(&rows)
}

fn articulator_section(inputs: &Inputs) -> String {
    let w = inputs.windows;
    if w.protrusion.is_none() && w.left.is_none() && w.right.is_none() {
        return not_measured(
            "articulator values",
            "Give the windows of the border movements: <code>--protrusion FROM:TO</code>, <code>--left FROM:TO</code>, \
             <code>--right FROM:TO</code> (s), each made slowly from the closed jaw with the teeth in contact.",
        );
    }
    let get = |w: Option<Window>| w.map(|w| poses_in(inputs, w));
    let (p, l, r) = (get(w.protrusion), get(w.left), get(w.right));
    let movements = Movements { protrusion: p.as_deref(), toward_left: l.as_deref(), toward_right: r.as_deref() };
    let o = ArticulatorOptions::default();
    let v = match ArticulatorValues::measure(&inputs.anatomy.mounting, &inputs.rest, &movements, &o) {
        Ok(v) => v,
        Err(e) => return format!("<p class=\"warn\">{}</p>", esc(&e.to_string())),
    };
    let windows: Vec<String> =
        [("protrusion", w.protrusion), ("toward the left", w.left), ("toward the right", w.right)]
            .iter()
            .filter_map(|(n, w)| w.map(|w| format!("{n} {}", window_words(&w))))
            .collect();
    let mut s = table(
        &["value", "left condyle", "right condyle"],
        &[
            vec![
                "sagittal condylar inclination".into(),
                deg(v.condylar_inclination_deg[0]),
                deg(v.condylar_inclination_deg[1]),
            ],
            vec!["Bennett angle".into(), deg(v.bennett_deg[0]), deg(v.bennett_deg[1])],
            vec!["immediate side shift".into(), mm(v.side_shift_mm[0], 2), mm(v.side_shift_mm[1], 2)],
        ],
    );
    s += &table(
        &["incisal guidance", "angle"],
        &[
            vec!["protrusive".into(), deg(v.protrusive_guidance_deg)],
            vec!["lateral, toward the patient's left".into(), deg(v.lateral_guidance_deg[0])],
            vec!["lateral, toward the patient's right".into(), deg(v.lateral_guidance_deg[1])],
        ],
    );
    s += &format!(
        "<p>Read over the first {} mm of each path ({}), to {}. A condyle's Bennett angle and side shift come \
         from the laterotrusion toward the other side. A dash: that movement was not given.</p>",
        fixed(o.over_mm, 0),
        esc(&windows.join(", ")),
        esc(inputs.anatomy.reference_plane)
    );
    s
}

fn co_mi_section(inputs: &Inputs) -> String {
    let Some(c) = inputs.centric else {
        return not_measured(
            "the CO–MI slide",
            "Give the window the jaw was held in centric occlusion: <code>--co FROM:TO</code> (s), and the bite's \
             with <code>--mi FROM:TO</code> if it is not the closed jaw.",
        );
    };
    let s = co_mi(&inputs.anatomy.mounting, &c.co, &c.mi);
    let row = |name: &str, d: &Displacement| {
        vec![
            name.into(),
            mm(Some(d.protrusive), 2),
            mm(Some(d.opening), 2),
            mm(Some(d.lateral), 2),
            mm(Some(d.norm()), 2),
        ]
    };
    let mut out = table(
        &["point", "forward", "down", "toward the patient's left", "length"],
        &[
            row("lower incisal point", &s.incisor),
            row("left condyle", &s.condyles[0]),
            row("right condyle", &s.condyles[1]),
        ],
    );
    out += &format!(
        "<p>The slide from centric occlusion (held {}) into maximal intercuspation, each point's displacement in \
         the head frame.</p>",
        window_words(&c.co_window)
    );
    out
}

fn contacts_section(inputs: &Inputs) -> String {
    let Some(c) = &inputs.contacts else {
        return not_measured(
            "occlusal contacts",
            "Run <code>jawtrack contacts --maxilla UPPER --mandible LOWER --poses session.jsonl --registration reg.json \
             --out DIR</code> (per-tooth meshes named FDI=NN give tooth numbers), then give <code>--contacts DIR</code>.",
        );
    };
    let sm = &c.summary;
    let num = |v: &serde_json::Value| v.as_f64();
    let deepest = match num(&sm["deepest"]["depth_mm"]) {
        Some(d) if d > 0.0 => format!(
            "{} mm penetration at {} s",
            fixed(d, 3),
            num(&sm["deepest"]["t"]).map_or("—".into(), |t| fixed(t, 2))
        ),
        Some(d) => format!("no penetration; smallest gap {} mm", fixed(-d, 3)),
        None => "no contact".into(),
    };
    let mut s = facts(&[
        ("Results", esc(&c.folder)),
        ("Mode", esc(sm["settings"]["mode"].as_str().unwrap_or("—"))),
        ("Contact threshold", mm(num(&sm["settings"]["threshold_mm"]), 2)),
        (
            "Frames checked",
            format!(
                "{} ({} within the threshold, {} penetrating)",
                sm["frames"]["checked"], sm["frames"]["with_contact"], sm["frames"]["penetrating"]
            ),
        ),
        ("Deepest", deepest),
    ]);
    // One map per row: see `html::STYLE` for what that does to their text's printed size.
    s += "<div class=\"plots maps\">";
    for (what, svg) in &c.maps {
        s += &figure(svg, &esc(what));
    }
    s += "</div>";
    let rows: Vec<Vec<String>> = sm["teeth"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|t| {
            vec![
                esc(t["arch"].as_str().unwrap_or("")),
                t["fdi"].as_u64().map_or_else(|| esc(t["name"].as_str().unwrap_or("")), |n| n.to_string()),
                t["universal"].as_u64().map_or("—".into(), |n| n.to_string()),
                t["frames_in_contact"].to_string(),
                format!("{} mm²", fixed(num(&t["max_area_mm2"]).unwrap_or(f64::NAN), 2)),
                mm(num(&t["max_depth_mm"]), 3),
            ]
        })
        .collect();
    if rows.is_empty() {
        s += "<p>No per-tooth totals: the arches were given as whole meshes, not one mesh per tooth.</p>";
    } else {
        s += &table(&["arch", "FDI", "Universal", "frames in contact", "largest area", "deepest"], &rows);
    }
    s
}

fn definitions(inputs: &Inputs) -> String {
    let a = &inputs.anatomy;
    format!(
        "<ul>\
         <li>Lengths in millimetres, angles in degrees, times in seconds of the recording's clock (a frame's time is \
         that of its centre row).</li>\
         <li><b>Head frame</b>: X toward the patient's left, Y down, Z posterior; its horizontal (XZ) plane is {}. \
         Displacements are from the closed jaw ({}): <i>forward</i> is −Z, <i>down</i> (opening) +Y, \
         <i>toward the patient's left</i> +X.</li>\
         <li><b>Landmarks</b>: {}.</li>\
         <li><b>Plots</b>: sagittal seen from the patient's right (anterior to the right); frontal seen from the \
         front (the patient's left on the right); transverse seen from above (anterior up, the patient's left on \
         the left). One millimetre is as long on both axes.</li>\
         <li><b>Sagittal condylar inclination</b>: the condyle's protrusive path below the reference plane; \
         <b>Bennett angle</b>: the non-working condyle's path medial of straight ahead, seen from above; \
         <b>immediate side shift</b>: its medial travel before it moves forward; <b>incisal guidance</b>: the \
         incisal point's path below the reference plane. Methods and measured accuracy: docs/kinematics.md.</li>\
         <li><b>Kinematic hinge axis</b>: the finite screw axis shared by the displacements of early opening \
         (turns ≤ 12° from the closed jaw).</li>\
         </ul>",
        esc(a.reference_plane),
        esc(&inputs.rest_words),
        esc(a.landmarks)
    )
}
