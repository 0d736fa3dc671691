//! The report of a rehearsed clinical session with exact poses (`synth`'s `ClinicalSession`):
//! every section is on the page, and the numbers it prints are the programmed ones.

use jawtrack_kinematics::{Anatomy, Mounting, Window};
use jawtrack_recording::{Recording, RecordingHeader, read_recording};
use jawtrack_report::{Centric, Inputs, Windows, render};
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
        lines.push(
            json!({"frame": k, "t": t, "maxilla": body, "mandible": if lost { Value::Null } else { body.clone() },
                "maxilla_from_mandible": if lost { Value::Null } else { json!(pose) },
                "flags": if lost { vec!["mandible:lost"] } else { vec![] }})
            .to_string(),
        );
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
}
