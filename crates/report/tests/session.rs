//! The report of a rehearsed clinical session with exact poses (`synth`'s `ClinicalSession`):
//! every section is on the page, and the numbers it prints are the programmed ones.

use jawtrack_kinematics::{Anatomy, Mounting, Window};
use jawtrack_recording::{Recording, RecordingHeader, read_recording};
use jawtrack_report::{Centric, ContactsResult, Inputs, Record, Windows, render, render_with};
use jawtrack_synth::scenes::guided::ClinicalSession;
use jawtrack_synth::scenes::{Guidance, Rig};
use serde_json::{Value, json};

const GUIDANCE: Guidance = Guidance {
    condylar_inclination_deg: 37.0,
    bennett_deg: 13.0,
    side_shift_mm: 0.7,
    protrusive_guidance_deg: 46.0,
    lateral_guidance_deg: 33.0,
};

fn recording(s: &ClinicalSession) -> Recording {
    let mut lines = vec![RecordingHeader::new("report test").to_line()];
    for (k, (t, pose)) in s.poses.iter().enumerate() {
        lines.push(
            json!({"frame": k, "t": t, "maxilla": null, "mandible": null, "maxilla_from_mandible": pose}).to_string(),
        );
    }
    read_recording((lines.join("\n") + "\n").as_bytes()).expect("a recording")
}

/// The inputs of `rec` with the standard mounting, the jaw closed at `rest`, nothing else
/// given.
fn inputs<'a>(rec: &'a Recording, name: &str, rest: jawtrack_pose::Pose) -> Inputs<'a> {
    Inputs {
        recording: rec,
        recording_name: name.into(),
        anatomy: Anatomy::standard(),
        points_file: None,
        registration_file: None,
        rest,
        rest_words: "frame 0".into(),
        windows: Windows::default(),
        centric: None,
        contacts: None,
        made_unix_s: 1.7e9,
    }
}

fn window((from, to): (f64, f64)) -> Option<Window> {
    Some(Window { from, to })
}

/// The section `id` of a page, from its tag to its end.
fn section<'a>(html: &'a str, id: &str) -> &'a str {
    let s = &html[html.find(&format!("<section id=\"{id}\">")).expect("the section")..];
    &s[..s.find("</section>").expect("its end")]
}

#[test]
fn the_report_prints_the_programmed_session() {
    let rig = Rig::default();
    let session = rig.clinical_session(&GUIDANCE, 20.0, 5.0);
    let rec = recording(&session);
    let rest = rec.frames[0].maxilla_from_mandible.expect("a pose");
    let co = session.poses.iter().find(|(t, _)| *t > session.co.0).expect("held").1;
    let inputs = Inputs {
        windows: Windows {
            opening: window(session.opening),
            protrusion: window(session.protrusion),
            left: window(session.left),
            right: window(session.right),
        },
        centric: Some(Centric { co, mi: rest, co_window: Window { from: session.co.0, to: session.co.1 } }),
        ..inputs(&rec, "session <1>.jsonl", rest)
    };
    let r = render(&inputs);
    for id in [
        "session",
        "quality",
        "incisor",
        "border",
        "condyles",
        "hinge",
        "articulator",
        "co-mi",
        "contacts",
        "definitions",
    ] {
        assert!(r.html.contains(&format!("<section id=\"{id}\">")), "section {id} missing");
    }
    assert_eq!(r.html.matches("Not measured").count(), 1, "every window was given; contacts were not");
    // The file name is text, not markup.
    assert!(r.html.contains("session &lt;1&gt;.jsonl") && !r.html.contains("session <1>"));
    // Articulator values, as the page prints them (one decimal).
    let g = GUIDANCE;
    for v in [g.condylar_inclination_deg, g.bennett_deg, g.protrusive_guidance_deg, g.lateral_guidance_deg] {
        let cell = format!("<td>{v:.1}°</td>");
        assert!(r.html.matches(&cell).count() >= 1, "{cell} not on the page");
    }
    assert_eq!(r.html.matches(&format!("<td>{:.2} mm</td>", g.side_shift_mm)).count(), 2, "both side shifts");
    // The CO–MI slide: the held offset reversed, for every point (forward 0.80, down 0.30).
    let back = -session.co_offset;
    let slide = format!("<td>{:.2} mm</td><td>{:.2} mm</td>", -back.z, back.y);
    assert_eq!(r.html.matches(&slide).count(), 3, "{slide}");
    // The hinge axis: the mounting's, along head X through the condyles (4 decimals).
    assert!(r.html.contains("(1.0000, 0.0000, 0.0000)"), "head-frame direction");
    let c = Mounting::default().condyles[0];
    assert!(r.html.contains(&format!("({:.2}, {:.2}, {:.2}) mm in the head frame, moved 0.00 mm", c.x, c.y, c.z)));
    // Maximum opening: the hinge opening's widest, as the incisor's displacement reads it.
    let incisor = jawtrack_kinematics::Incisor::standard();
    let widest = session.poses.iter().map(|(_, p)| incisor.displacement(p, &rest).opening).fold(0.0, f64::max);
    assert!(widest > 35.0, "{widest}");
    assert!(r.html.contains(&format!("<td>maximum opening</td><td>{widest:.1} mm</td>")), "{widest}");
    // Posselt: all three planes, with the sagittal border's movements named.
    assert_eq!(r.html.matches("<figure>").count(), 5, "three border plots and two condyle plots");
    assert!(r.html.contains("opening from protrusion (anterior border)"), "sagittal movements named");
    // No anatomy file and no marker in the header: both said, and nothing else.
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("standard harness mounting"));
}

#[test]
fn sections_without_their_movement_say_which_flag_fills_them() {
    let rig = Rig::default();
    let session = rig.clinical_session(&GUIDANCE, 10.0, 1.0);
    let rec = recording(&session);
    let rest = rec.frames[0].maxilla_from_mandible.expect("a pose");
    let inputs = inputs(&rec, "s.jsonl", rest);
    let r = render(&inputs);
    for flag in ["--opening FROM:TO", "--protrusion FROM:TO", "--co FROM:TO", "--contacts DIR"] {
        assert!(r.html.contains(flag), "{flag}");
    }
    assert_eq!(r.html.matches("Not measured").count(), 4);
}

#[test]
fn quality_numbers_are_the_recording_s() {
    // 20 frames at 20 frames/s; frames 8–18 lose the mandible (a 0.60 s pause, 9 of 20 with a
    // jaw pose); the maxilla's reprojection error is 0.01 px × (frame + 1); the nominal marker.
    let rig = Rig::default();
    let session = rig.clinical_session(&GUIDANCE, 20.0, 0.0);
    let mut header = RecordingHeader::new("quality test");
    header.marker = serde_json::from_str(&jawtrack_marker::Marker::default().to_json()).ok();
    let mut lines = vec![header.to_line()];
    for k in 0..20usize {
        let (t, pose) = session.poses[k];
        let body = json!({"camera_from_body": pose, "tags": [0, 1], "rms_px": 0.01 * (k + 1) as f64});
        let lost = (8..=18).contains(&k);
        let mut line = json!({"frame": k, "t": t, "maxilla": body, "mandible": if lost { Value::Null } else { body.clone() },
            "maxilla_from_mandible": if lost { Value::Null } else { json!(pose) },
            "flags": if lost { vec!["mandible:lost"] } else { vec![] }});
        // The tone curve: sRGB on the first frame, the estimate from frame 5 on.
        if k == 0 {
            line["tone"] = json!({"setting": "auto", "curve": "srgb", "frames_fitted": 0});
        } else if k == 5 {
            line["tone"] = json!({"setting": "auto", "curve": "gamma:1.84", "reason": "estimated", "frames_fitted": 5, "fit": {"gamma": 1.842,
                "gamma_spread": 0.06, "fits": 5, "sides": 80, "misfit": 1.003, "srgb_misfit": 1.034}});
        }
        lines.push(line.to_string());
    }
    let rec = read_recording((lines.join("\n") + "\n").as_bytes()).expect("a recording");
    let rest = session.poses[0].1;
    let mut inputs = inputs(&rec, "q.jsonl", rest);
    inputs.points_file = Some("points.json".into());
    inputs.registration_file = Some("reg.json".into());
    let r = render(&inputs);
    assert_eq!(r.warnings.len(), 3, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("only 9 of 20 frames (45 %)"), "{:?}", r.warnings);
    assert!(r.warnings[1].contains("paused for 0.60 s"), "{:?}", r.warnings);
    assert!(r.warnings[2].contains("nominal marker"), "{:?}", r.warnings);
    assert!(r.html.contains("<td>9 of 20 (45.0 %)</td>"));
    assert!(r.html.contains("<td>0.600 s</td>"), "the longest pause");
    // Sorted errors 0.01…0.20: the upper middle value and the nearest-rank 95th percentile.
    assert!(r.html.contains("<td>median 0.110 px, 95th percentile 0.190 px</td>"));
    // The mandible's, over the 9 frames it was seen: 0.01–0.08 and 0.20.
    assert!(r.html.contains("<td>median 0.050 px, 95th percentile 0.200 px</td>"));
    assert!(r.html.contains("<td>mandible:lost</td><td>11</td>"));
    assert!(r.html.contains("nominal (the ideal solid"), "the marker named");
    assert!(
        r.html.contains(
            "<th>Tone curve the tags were read through</th><td>gamma:1.84 (auto: estimated; power law 1.84 \
             ± 0.06 from 5 frames&#39; 80 tag sides, misfit 1.003 against sRGB&#39;s 1.034)</td>"
        ),
        "the last curve and how it was found"
    );
}

#[test]
fn frames_out_of_focus_are_counted_and_explained() {
    // 10 frames at 20 frames/s; frames 2–4 have the maxilla flagged defocused, so no jaw pose.
    let rig = Rig::default();
    let session = rig.clinical_session(&GUIDANCE, 20.0, 0.0);
    let mut lines = vec![RecordingHeader::new("focus test").to_line()];
    for k in 0..10usize {
        let (t, pose) = session.poses[k];
        let body = json!({"camera_from_body": pose, "tags": [0, 1], "rms_px": 0.1, "blur_px": 5.0, "cell_px": 14.0});
        let blurred = (2..=4).contains(&k);
        lines.push(
            json!({"frame": k, "t": t, "maxilla": body, "mandible": body.clone(),
                "maxilla_from_mandible": if blurred { Value::Null } else { json!(pose) },
                "flags": if blurred { vec!["maxilla:defocused"] } else { vec![] }})
            .to_string(),
        );
    }
    let rec = read_recording((lines.join("\n") + "\n").as_bytes()).expect("a recording");
    let r = render(&inputs(&rec, "f.jsonl", session.poses[0].1));
    let focus: Vec<&String> = r.warnings.iter().filter(|w| w.contains("out of focus")).collect();
    assert_eq!(focus.len(), 1, "{:?}", r.warnings);
    assert!(focus[0].starts_with("3 of 10 frames had a marker out of focus") && focus[0].contains("jawtrack plan"));
    assert!(r.html.contains("<td>maxilla:defocused</td><td>3</td>"), "the flag's count in the table");
    assert!(r.html.contains("not recorded (tracked before JawTrack estimated it: read as sRGB)"), "an older recording");
}

#[test]
fn patient_operator_and_notes_head_the_page_and_blanks_are_lines_to_fill_in() {
    let rig = Rig::default();
    let session = rig.clinical_session(&GUIDANCE, 10.0, 1.0);
    let rec = recording(&session);
    let inputs = inputs(&rec, "s.jsonl", rec.frames[0].maxilla_from_mandible.expect("a pose"));
    let record = Record {
        patient: Some("Ana <Ruiz> & Co".into()),
        operator: None,
        notes: Some("clicks on opening\n<left> TMJ".into()),
    };
    let r = render_with(&inputs, &record);
    let first = section(&r.html, "session");
    let line = "_".repeat(40);
    // The first rows, escaped, the operator left as a line to write on.
    assert!(
        first.contains(&format!(
            "<tbody><tr><th>Patient</th><td>Ana &lt;Ruiz&gt; &amp; Co</td></tr>\
             <tr><th>Operator</th><td><span class=\"fill\">{line}</span></td></tr>\
             <tr><th>Notes</th><td>clicks on opening<br>&lt;left&gt; TMJ</td></tr>\
             <tr><th>Recording</th>"
        )),
        "{first}"
    );
    // Not given at all: three blanks, the notes with three lines of room.
    let blank = render(&inputs);
    let first = section(&blank.html, "session");
    assert!(first.contains(&format!("<tr><th>Patient</th><td><span class=\"fill\">{line}</span></td></tr>")));
    assert!(first.contains(&format!("<tr><th>Notes</th><td><span class=\"fill\">{line}<br>{line}<br>{line}</span>")));
    assert_eq!(r.warnings, blank.warnings, "the record changes no number");
}

/// A recording of the session's first 10 frames whose header carries `marker`.
fn with_marker(session: &ClinicalSession, marker: &jawtrack_marker::Marker) -> Recording {
    let mut header = RecordingHeader::new("marker test");
    header.marker = serde_json::from_str(&marker.to_json()).ok();
    let mut lines = vec![header.to_line()];
    for (k, (t, pose)) in session.poses.iter().take(10).enumerate() {
        lines.push(json!({"frame": k, "t": t, "maxilla_from_mandible": pose}).to_string());
    }
    read_recording((lines.join("\n") + "\n").as_bytes()).expect("a recording")
}

#[test]
fn measured_tags_are_counted_out_of_the_marker_s_own() {
    use jawtrack_marker::{Marker, PrintError, SolidKind, TagFamily};
    let session = Rig::default().clinical_session(&GUIDANCE, 20.0, 0.0);
    let moved = PrintError { shift_x: 0.2, ..PrintError::default() };
    let marker_row = |marker: &Marker| {
        let rec = with_marker(&session, marker);
        let html = render(&inputs(&rec, "m.jsonl", session.poses[0].1)).html;
        let row = "<tr><th>Marker</th><td>";
        let at = html.find(row).expect("the marker's row") + row.len();
        html[at..at + html[at..].find("</td>").expect("its end")].to_string()
    };
    // Three tags of the dodecahedron pair placed by a calibration: two on the maxilla.
    let dodecahedron = Marker::default().with_print_errors(&[(0, moved), (5, moved), (12, moved)]).expect("ids");
    assert_eq!(marker_row(&dodecahedron), "calibrated: 3 of 24 tags measured (maxilla 2 of 12, mandible 1 of 12)");
    // A cube pair has 6 tags a body: the totals are the marker's, not the dodecahedron's.
    let cube = Marker::nominal_on(SolidKind::Cube, TagFamily::TAG36H11, 12.7, None).expect("a cube pair");
    let cube = cube.with_print_errors(&[(12, moved)]).expect("id 12");
    assert_eq!(marker_row(&cube), "calibrated: 1 of 12 tags measured (maxilla 0 of 6, mandible 1 of 6)");
    assert_eq!(marker_row(&Marker::default()), "nominal (the ideal solid's tag places; not calibrated)");
}

#[test]
fn assumed_condyles_far_from_the_fitted_hinge_axis_are_warned_of() {
    let rig = Rig::default();
    let session = rig.clinical_session(&GUIDANCE, 20.0, 5.0);
    let rec = recording(&session);
    let rest = rec.frames[0].maxilla_from_mandible.expect("a pose");
    // The session opens about the standard mounting's condylar axis (head X through the
    // condyles); move the condyles 20 mm and 25 mm off it (the right one also 5 mm along it,
    // which does not count).
    let mut mounting = Mounting::default();
    mounting.condyles[0] += nalgebra::Vector3::new(0.0, 12.0, -16.0);
    mounting.condyles[1] += nalgebra::Vector3::new(5.0, -15.0, 20.0);
    let report = |mounting: Mounting, condyles_given: bool, opening: Option<Window>| {
        let anatomy = Anatomy { mounting, condyles_given, ..Anatomy::standard() };
        let inputs =
            Inputs { anatomy, windows: Windows { opening, ..Windows::default() }, ..inputs(&rec, "h.jsonl", rest) };
        render(&inputs)
    };
    let off = |r: &jawtrack_report::Report| {
        r.warnings.iter().filter(|w| w.contains("hinge axis")).cloned().collect::<Vec<_>>()
    };
    let r = report(mounting, false, window(session.opening));
    assert_eq!(
        off(&r),
        ["the condyles assumed for the condylar paths are 20.0 mm (left) and 25.0 mm (right) from the fitted hinge \
          axis: their paths show the jaw's turn about the axis as travel; give the condyles in a points file \
          (jawtrack points --condyles) or read the hinge axis section"]
    );
    assert!(
        section(&r.html, "quality").contains("are 20.0 mm (left) and 25.0 mm (right) from the fitted"),
        "on the page"
    );
    assert!(
        section(&r.html, "hinge").contains("moved 20.00 mm") && section(&r.html, "hinge").contains("moved 25.00 mm"),
        "as the hinge section says"
    );
    // Given in a points file, or no axis fitted: nothing to warn of.
    assert!(off(&report(mounting, true, window(session.opening))).is_empty());
    assert!(off(&report(mounting, false, None)).is_empty());
    // 3 mm off the axis is within what a palpated condyle misses by.
    let mut near = Mounting::default();
    near.condyles[0].y += 3.0;
    assert!(off(&report(near, false, window(session.opening))).is_empty());
}

#[test]
fn contact_maps_take_a_row_each() {
    let rig = Rig::default();
    let session = rig.clinical_session(&GUIDANCE, 10.0, 1.0);
    let rec = recording(&session);
    // As `jawtrack contacts` draws them: up to 960 units wide, labels 12 units high.
    let map = |n: &str| {
        (
            format!("map {n}"),
            format!(
                "<svg viewBox=\"0 0 960 800\" width=\"960\" height=\"800\" font-size=\"12\"><text>{n}</text></svg>"
            ),
        )
    };
    let contacts = ContactsResult { folder: "c".into(), summary: json!({}), maps: vec![map("36"), map("46")] };
    let inputs = Inputs {
        contacts: Some(contacts),
        ..inputs(&rec, "c.jsonl", rec.frames[0].maxilla_from_mandible.expect("a pose"))
    };
    let html = render(&inputs).html;
    let maps = section(&html, "contacts");
    let grid = &maps[maps.find("<div class=\"plots maps\">").expect("the maps' grid")..];
    assert_eq!(grid.matches("<figure><svg viewBox=\"0 0 960 800\"").count(), 2, "both maps, as they are");
    // One column on screen and in print (two classes outweigh the print rule's `.plots`): the
    // full 182 mm of an A4 page, not half of it.
    assert!(html.contains(".plots.maps{grid-template-columns:1fr}"));
}
