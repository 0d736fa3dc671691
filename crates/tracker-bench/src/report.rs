//! What was measured, its statistics and the Markdown tables: per scene and per camera view,
//! both marker files, ours beside the reference stack; the frames that flipped or lost a
//! body; PnP time per body; and the verdict against the target.

use jawtrack_pose::median;
use jawtrack_synth::SceneKind;
use jawtrack_synth::scenes::View;
use std::fmt::Write as _;

/// A frame counts as a flip when its orientation error exceeds this (degrees).
pub const FLIP_DEG: f64 = 1.0;

/// A frame this far off (degrees) has taken a wrong (mirror) solution rather than a biased
/// one: marker-model errors of 0.2 mm tilt a pose by about a degree, a mirror by tens.
pub const MIRROR_DEG: f64 = 5.0;

/// The target: ours at most this fraction of the reference's mean error.
pub const TARGET_RATIO: f64 = 0.5;

/// The two marker files, in the order of [`FrameOutcome::error`].
pub const MARKER_FILES: [&str; 2] = ["nominal", "as printed"];

/// The scenes the accuracy target names (chew is measured as an extra).
pub const TARGET_SCENES: [SceneKind; 3] = [SceneKind::Static, SceneKind::Hinge, SceneKind::Excursion];

pub use jawtrack_tracker_bench::chew::PoseError;

/// One frame, measured.
#[derive(Debug, Clone)]
pub struct FrameOutcome {
    /// Frame number in its scene.
    pub index: usize,
    /// Where the camera was.
    pub view: View,
    /// Per marker file (nominal, as printed): ours, the reference's; `None` without a pose.
    pub error: [[Option<PoseError>; 2]; 2],
    /// Per marker file, our tracker's flags.
    pub our_flags: [Vec<String>; 2],
    /// Tags of the maxilla and of the mandible the C library found.
    pub c_tags: [usize; 2],
    /// Per marker file, why the reference has no pose (a body without tags, OpenCV's error).
    pub reference_note: [Option<String>; 2],
    /// Under a rolling shutter, ours with the marker as printed and the readout ignored.
    pub ignored: Option<PoseError>,
    /// The lower incisor's speed relative to the upper jaw (mm/s), from the truth.
    pub speed_mm_s: f64,
}

/// One scene, measured.
#[derive(Debug, Clone)]
pub struct SceneOutcome {
    /// Which scene.
    pub scene: SceneKind,
    /// Its frames, in order.
    pub frames: Vec<FrameOutcome>,
}

/// PnP time of one body (µs, each the median of several calls), by how many tags it had.
#[derive(Debug, Clone, Copy)]
pub struct PnpTiming {
    /// Which marker file's corners (index into [`MARKER_FILES`]).
    pub marker: usize,
    /// Tags of the body.
    pub tags: usize,
    /// Our `solve_pnp`.
    pub ours_us: f64,
    /// Whether ours dropped a tag as inconsistent with the others.
    pub ours_dropped_tag: bool,
    /// OpenCV SQPnP, if it answered.
    pub sqpnp_us: Option<f64>,
    /// OpenCV ITERATIVE, if it answered.
    pub iterative_us: Option<f64>,
}

/// How the run was set up, for the table's header.
#[derive(Debug, Clone)]
pub struct RunInfo {
    /// One line saying what was rendered.
    pub frames: String,
    /// The reference's PnP (e.g. "OpenCV 4.12.0 SQPnP (python3)"), or why it was skipped.
    pub reference: Result<String, String>,
}

/// Mean, median, max of a set.
#[derive(Debug, Clone, Copy)]
struct Spread {
    mean: f64,
    median: f64,
    max: f64,
}

fn spread(mut v: Vec<f64>) -> Option<Spread> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    Some(Spread { mean, median: v[v.len() / 2], max: v[v.len() - 1] })
}

/// One stack's errors over a group of frames.
#[derive(Debug, Clone, Copy)]
struct Stats {
    frames: usize,
    poses: usize,
    mm: Option<Spread>,
    deg: Option<Spread>,
    flips: usize,
    mirrors: usize,
}

fn stats<'a>(errors: impl Iterator<Item = &'a Option<PoseError>>) -> Stats {
    let (mut frames, mut mm, mut deg) = (0, Vec::new(), Vec::new());
    for e in errors {
        frames += 1;
        if let Some(e) = e {
            mm.push(e.mm);
            deg.push(e.deg);
        }
    }
    let flips = deg.iter().filter(|d| **d > FLIP_DEG).count();
    let mirrors = deg.iter().filter(|d| **d > MIRROR_DEG).count();
    Stats { frames, poses: mm.len(), mm: spread(mm), deg: spread(deg), flips, mirrors }
}

fn cell(s: Option<Spread>, digits: usize) -> String {
    s.map_or("–".into(), |s| format!("{:.d$} / {:.d$} / {:.d$}", s.mean, s.median, s.max, d = digits))
}

fn ratio(ours: Option<Spread>, reference: Option<Spread>) -> Option<f64> {
    Some(ours?.mean / reference?.mean)
}

fn ratio_cell(r: Option<f64>) -> String {
    r.map_or("–".into(), |r| if r <= TARGET_RATIO { format!("**{r:.3}**") } else { format!("{r:.3}") })
}

/// A view in words, e.g. "80 mm, 30°, hand".
pub fn view_label(v: &View) -> String {
    let el = if v.elevation_deg == 0.0 { String::new() } else { format!(", elevation {:.0}°", v.elevation_deg) };
    let mount = if v.hand_seed.is_some() { "hand" } else { "tripod" };
    format!("{:.0} mm, {:.0}°{el}, {mount}", v.distance_mm, v.azimuth_deg)
}

/// A scene's frames grouped by view, in order of first appearance.
fn views(s: &SceneOutcome) -> Vec<(String, Vec<&FrameOutcome>)> {
    let mut out: Vec<(String, Vec<&FrameOutcome>)> = Vec::new();
    for f in &s.frames {
        let label = view_label(&f.view);
        match out.iter_mut().find(|(l, _)| *l == label) {
            Some((_, v)) => v.push(f),
            None => out.push((label, vec![f])),
        }
    }
    out
}

/// A row of the accuracy table and what the verdict needs from it.
struct Row {
    scene: SceneKind,
    group: String,
    marker: usize,
    ours: Stats,
    reference: Stats,
}

fn rows(outcomes: &[SceneOutcome]) -> Vec<Row> {
    let mut out = Vec::new();
    for s in outcomes {
        let mut groups = vec![("all frames".to_string(), s.frames.iter().collect::<Vec<_>>())];
        let by_view = views(s);
        if by_view.len() > 1 {
            groups.extend(by_view);
        } else if let Some((label, _)) = by_view.first() {
            groups[0].0 = format!("all frames ({label})");
        }
        for (group, frames) in groups {
            for marker in 0..2 {
                out.push(Row {
                    scene: s.scene,
                    group: group.clone(),
                    marker,
                    ours: stats(frames.iter().map(|f| &f.error[marker][0])),
                    reference: stats(frames.iter().map(|f| &f.error[marker][1])),
                });
            }
        }
    }
    out
}

fn pose_error_cell(e: Option<PoseError>) -> String {
    e.map_or("no pose".into(), |e| format!("{:.3} mm / {:.2}°", e.mm, e.deg))
}

/// Every frame as a JSON line: scene, frame, view, and per marker file ours' and the
/// reference's error (mm, degrees; null without a pose), our flags and the C library's tags.
pub fn json_lines(outcomes: &[SceneOutcome]) -> String {
    let err = |e: Option<PoseError>| e.map(|e| serde_json::json!({"mm": e.mm, "deg": e.deg}));
    let mut out = String::new();
    for s in outcomes {
        for f in &s.frames {
            let markers: Vec<serde_json::Value> = MARKER_FILES
                .iter()
                .enumerate()
                .map(|(m, file)| {
                    serde_json::json!({
                        "marker_file": file,
                        "ours": err(f.error[m][0]),
                        "reference": err(f.error[m][1]),
                        "our_flags": f.our_flags[m],
                        "reference_note": f.reference_note[m],
                    })
                })
                .collect();
            let line = serde_json::json!({
                "scene": s.scene.name(),
                "frame": f.index,
                "view": view_label(&f.view),
                "c_tags": {"maxilla": f.c_tags[0], "mandible": f.c_tags[1]},
                "markers": markers,
            });
            let _ = writeln!(out, "{line}");
        }
    }
    out
}

/// The whole report in Markdown.
pub fn markdown(info: &RunInfo, outcomes: &[SceneOutcome], timings: &[PnpTiming]) -> String {
    let with_reference = info.reference.is_ok();
    let mut md = String::new();
    let _ = writeln!(md, "# tracker-bench\n");
    let _ = writeln!(md, "- Frames: {}", info.frames);
    let _ = writeln!(
        md,
        "- Ours: `jawtrack_tracker::Tracker` at its defaults (linear-light edges), one tracker per scene and marker file, frames in order."
    );
    match &info.reference {
        Ok(r) => {
            let _ = writeln!(
                md,
                "- Reference: AprilTag C 3.4.5 at its defaults, then {r} per body on all its detected tag corners."
            );
        }
        Err(why) => {
            let _ = writeln!(md, "- Reference: **SKIPPED** — {why}. Its columns say so; ours alone below.");
        }
    }
    let _ = writeln!(
        md,
        "\nErrors of the mandible in the maxilla against the truth: position (mm) and orientation (°), each as mean / median / max over the frames with a pose; ours ÷ ref is the ratio of the means (bold when ≤ {TARGET_RATIO:.2}); a flip is a frame more than {FLIP_DEG}° off (the target's definition); frames more than {MIRROR_DEG}° off are counted apart, as that is a wrong (mirror) solution rather than a biased one.\n"
    );
    let _ = writeln!(
        md,
        "| scene | view | marker file | frames | poses ours / ref | position ours (mm) | position ref (mm) | ours ÷ ref | orientation ours (°) | orientation ref (°) | ours ÷ ref | flips ours / ref | > {MIRROR_DEG}° ours / ref |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let rows = rows(outcomes);
    for r in &rows {
        let refcol = |s: String| if with_reference { s } else { "skipped".into() };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} / {} | {} | {} | {} | {} | {} | {} | {} / {} | {} / {} |",
            r.scene.name(),
            r.group,
            MARKER_FILES[r.marker],
            r.ours.frames,
            r.ours.poses,
            refcol(r.reference.poses.to_string()),
            cell(r.ours.mm, 3),
            refcol(cell(r.reference.mm, 3)),
            ratio_cell(ratio(r.ours.mm, r.reference.mm)),
            cell(r.ours.deg, 3),
            refcol(cell(r.reference.deg, 3)),
            ratio_cell(ratio(r.ours.deg, r.reference.deg)),
            r.ours.flips,
            refcol(r.reference.flips.to_string()),
            r.ours.mirrors,
            refcol(r.reference.mirrors.to_string()),
        );
    }

    md.push_str(&timing_table(timings, with_reference));
    md.push_str(&notable_frames(outcomes, with_reference));
    md.push_str(&verdict(&rows, outcomes, with_reference));
    md
}

fn timing_table(timings: &[PnpTiming], with_reference: bool) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\nPnP time per body on the same correspondences (the C library's corners against the marker file's; no prior pose), median µs of per-body medians of 5 calls; OpenCV timed inside Python around `cv2.solvePnP`:\n"
    );
    let _ = writeln!(
        md,
        "| marker file | bodies | count | ours `solve_pnp` | OpenCV SQPnP | OpenCV ITERATIVE | ours dropped a tag |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    // Tag counts from..=to.
    let groups = [("all", 1, usize::MAX), ("1 tag", 1, 1), ("2 tags", 2, 2), ("3+ tags", 3, usize::MAX)];
    let us = |v: Option<f64>| v.map_or("–".into(), |v| format!("{v:.0}"));
    for (marker, (label, from, to)) in (0..2).flat_map(|m| groups.map(|g| (m, g))) {
        let sel: Vec<&PnpTiming> =
            timings.iter().filter(|t| t.marker == marker && (from..=to).contains(&t.tags)).collect();
        if sel.is_empty() {
            continue;
        }
        let ours = median(sel.iter().map(|t| t.ours_us));
        let (sq, it) = if with_reference {
            (us(median(sel.iter().filter_map(|t| t.sqpnp_us))), us(median(sel.iter().filter_map(|t| t.iterative_us))))
        } else {
            ("skipped".into(), "skipped".into())
        };
        let dropped = sel.iter().filter(|t| t.ours_dropped_tag).count();
        let _ = writeln!(
            md,
            "| {} | {label} | {} | {} | {sq} | {it} | {dropped} |",
            MARKER_FILES[marker],
            sel.len(),
            us(ours)
        );
    }
    md
}

/// Frames where either stack is more than `FLIP_DEG` off or has no pose, with either marker
/// file.
fn notable_frames(outcomes: &[SceneOutcome], with_reference: bool) -> String {
    const MAX_LISTED: usize = 40;
    let mut md = String::new();
    let mut lines = Vec::new();
    for s in outcomes {
        for f in &s.frames {
            for (marker, file) in MARKER_FILES.iter().enumerate() {
                let bad = |e: Option<PoseError>| e.is_none_or(|e| e.deg > FLIP_DEG);
                let [ours, reference] = f.error[marker];
                if !(bad(ours) || with_reference && bad(reference)) {
                    continue;
                }
                let reference = if with_reference {
                    match (&reference, &f.reference_note[marker]) {
                        (None, Some(note)) => format!("no pose: {note}"),
                        _ => pose_error_cell(reference),
                    }
                } else {
                    "skipped".into()
                };
                let flags = if f.our_flags[marker].is_empty() { "–".into() } else { f.our_flags[marker].join(", ") };
                lines.push(format!(
                    "| {} | {} | {} | {} | {} | {reference} | {} / {} | {flags} |",
                    s.scene.name(),
                    f.index,
                    view_label(&f.view),
                    file,
                    pose_error_cell(ours),
                    f.c_tags[0],
                    f.c_tags[1],
                ));
            }
        }
    }
    let _ = writeln!(md, "\nFrames more than {FLIP_DEG}° off or without a pose (either stack, either marker file):\n");
    if lines.is_empty() {
        let _ = writeln!(md, "none.");
        return md;
    }
    let _ = writeln!(
        md,
        "| scene | frame | view | marker file | ours | reference | C's tags maxilla / mandible | our flags |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for l in lines.iter().take(MAX_LISTED) {
        let _ = writeln!(md, "{l}");
    }
    if lines.len() > MAX_LISTED {
        let _ = writeln!(md, "\n… and {} more.", lines.len() - MAX_LISTED);
    }
    md
}

fn verdict(rows: &[Row], outcomes: &[SceneOutcome], with_reference: bool) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "\n## Verdict\n");
    let names: Vec<&str> =
        TARGET_SCENES.iter().filter(|k| outcomes.iter().any(|o| o.scene == **k)).map(|k| k.name()).collect();
    for (marker, file) in MARKER_FILES.iter().enumerate() {
        let target: Vec<&Row> =
            rows.iter().filter(|r| r.marker == marker && TARGET_SCENES.contains(&r.scene)).collect();
        let label = if marker == 0 { "" } else { " (for information: what a calibrated marker file gives)" };
        if !with_reference {
            let _ = writeln!(
                md,
                "- Errors at most half the reference's, {file} marker file: **not evaluated** (the reference was skipped)."
            );
            continue;
        }
        if target.is_empty() {
            let _ = writeln!(
                md,
                "- Errors at most half the reference's, {file} marker file: **not evaluated** (no static, hinge or excursion frames)."
            );
            continue;
        }
        for (what, pick) in [
            ("position", (|r: &Row| ratio(r.ours.mm, r.reference.mm)) as fn(&Row) -> Option<f64>),
            ("orientation", |r: &Row| ratio(r.ours.deg, r.reference.deg)),
        ] {
            let failing: Vec<String> = target
                .iter()
                .filter(|r| pick(r).is_none_or(|x| x > TARGET_RATIO))
                .map(|r| {
                    format!(
                        "{} {} ({})",
                        r.scene.name(),
                        r.group,
                        pick(r).map_or("no poses".into(), |x| format!("{x:.3}"))
                    )
                })
                .collect();
            let worst = target.iter().filter_map(|r| pick(r)).fold(0.0, f64::max);
            let verdict = match (marker, failing.is_empty()) {
                (0, true) => "**met**",
                (0, false) => "**not met**",
                (_, true) => "would be met",
                (_, false) => "would not be met",
            };
            let _ = writeln!(
                md,
                "- {what} error at most half the reference's, {file} marker file{label} ({}; every view and scene total): {verdict} — {} of {} rows at ≤ {TARGET_RATIO:.2}, worst ratio {worst:.3}{}",
                names.join(", "),
                target.len() - failing.len(),
                target.len(),
                if failing.is_empty() { String::new() } else { format!("; above it: {}", failing.join("; ")) },
            );
        }
        let totals: Vec<&&Row> = target.iter().filter(|r| r.group.starts_with("all frames")).collect();
        let frames: usize = totals.iter().map(|r| r.ours.frames).sum();
        let ours: usize = totals.iter().map(|r| r.ours.poses).sum();
        let reference: usize = totals.iter().map(|r| r.reference.poses).sum();
        let _ = writeln!(
            md,
            "- Frames with a pose in those scenes, {file} marker file: ours {ours} of {frames}, reference {reference} of {frames}."
        );
    }
    // Whether the hard cases the flip target names occurred at all.
    let frames: Vec<&FrameOutcome> = outcomes.iter().flat_map(|s| &s.frames).collect();
    let ours_single = frames.iter().filter(|f| f.our_flags[0].iter().any(|n| n.ends_with(":single_tag"))).count();
    let c_single = frames.iter().filter(|f| f.c_tags.contains(&1)).count();
    let at_60 = frames.iter().filter(|f| f.view.azimuth_deg.abs() >= 60.0).count();
    let _ = writeln!(
        md,
        "- Hard cases present: {ours_single} frames where our tracker saw a body through a single tag (nominal marker file), {c_single} where the C library found a single tag of a body; {at_60} frames at 60° azimuth."
    );
    for (marker, file) in MARKER_FILES.iter().enumerate() {
        let (mut flips, mut mirrors, mut lost) = (0, 0, 0);
        let mut worst: Option<(f64, String)> = None;
        for s in outcomes {
            for f in &s.frames {
                let Some(e) = f.error[marker][0] else {
                    lost += 1;
                    continue;
                };
                flips += usize::from(e.deg > FLIP_DEG);
                mirrors += usize::from(e.deg > MIRROR_DEG);
                if worst.as_ref().is_none_or(|w| e.deg > w.0) {
                    worst = Some((e.deg, format!("{} frame {}, {}", s.scene.name(), f.index, view_label(&f.view))));
                }
            }
        }
        let worst = worst.map_or("no poses".into(), |(d, w)| format!("largest {d:.3}° ({w})"));
        let all: Vec<&str> = outcomes.iter().map(|o| o.scene.name()).collect();
        let reference = if with_reference {
            let errors = outcomes.iter().flat_map(|s| &s.frames).filter_map(|f| f.error[marker][1]);
            let (above, mirrored) = errors
                .fold((0, 0), |(a, m), e| (a + usize::from(e.deg > FLIP_DEG), m + usize::from(e.deg > MIRROR_DEG)));
            format!(" (reference: {above} above {FLIP_DEG}°, {mirrored} above {MIRROR_DEG}°)")
        } else {
            String::new()
        };
        let verdict = match (marker, flips) {
            (0, 0) => "**met**",
            (0, _) => "**not met**",
            _ => "(for information)",
        };
        let _ = writeln!(
            md,
            "- No flips, {} marker file ({}): {verdict} — {flips} frames of ours above {FLIP_DEG}°, {mirrors} of them above {MIRROR_DEG}°{reference}; {worst}; {lost} frames without a pose.",
            file,
            all.join(", "),
        );
    }
    md
}
