//! `jawtrack report` on a rehearsed clinical session with exact poses (`synth`'s
//! `ClinicalSession`): the page is written, refuses to overwrite, names the flags of what it
//! could not measure; in headless Chromium (`viewer/tests/report.mjs`) it shows every section
//! with no console error; and it prints to PDF.
//!
//! The Chromium checks need Chromium (`/usr/bin/chromium`, or `CHROMIUM`) and
//! `npm ci --prefix viewer`; without them they say SKIPPED and the rest still runs.

use jawtrack_synth::scenes::{Guidance, Rig};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::Command;
mod common;
use common::{identity_bite, jawtrack, ok, refused, s};

const SECTIONS: &str = "session,quality,incisor,border,condyles,hinge,articulator,co-mi,contacts,definitions";

/// The session as a recording in `dir`, and its windows as flags.
fn session(dir: &Path) -> (PathBuf, Vec<String>) {
    let c = Rig::default().clinical_session(&Guidance::default(), 20.0, 5.0);
    let mut lines = vec![jawtrack_recording::RecordingHeader::new("report test").to_line()];
    for (k, (t, pose)) in c.poses.iter().enumerate() {
        lines.push(
            json!({"frame": k, "t": t, "maxilla": null, "mandible": null, "maxilla_from_mandible": pose}).to_string(),
        );
    }
    let file = dir.join("session.jsonl");
    std::fs::write(&file, lines.join("\n") + "\n").expect("write");
    let w = |flag: &str, (a, b): (f64, f64)| [flag.to_string(), format!("{a}:{b}")];
    let flags = [
        w("--opening", c.opening),
        w("--protrusion", c.protrusion),
        w("--left", c.left),
        w("--right", c.right),
        w("--co", c.co),
    ]
    .concat();
    (file, flags)
}

fn chromium() -> Option<String> {
    let c = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    Path::new(&c).is_file().then_some(c)
}

fn viewer_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../viewer")
}

#[test]
fn the_report_is_written_and_chromium_shows_every_section() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (rec, flags) = session(dir.path());
    let out = dir.path().join("report.html");
    let mut args = vec!["report", s(&rec), "--out", s(&out)];
    args.extend(flags.iter().map(String::as_str));
    let said = ok(&jawtrack(&args));
    assert!(said.contains("10 sections"), "{said}");
    let html = std::fs::read_to_string(&out).expect("the report");
    assert!(html.starts_with("<!doctype html>") && html.contains("40.0°"), "the programmed inclination");
    assert!(!html.contains("<script") && !html.contains("src=\"http"), "self-contained, no script");
    refused(&jawtrack(&args), "--force");
    let Some(browser) = chromium() else {
        jawtrack_test_support::say_skipped("the Chromium check of the report: no Chromium (set CHROMIUM)");
        return;
    };
    if !viewer_dir().join("node_modules/playwright-core/package.json").is_file() {
        jawtrack_test_support::say_skipped("the Chromium check of the report: run `npm ci --prefix viewer`");
        return;
    }
    let shot = dir.path().join("report.png");
    let check = Command::new("node")
        .arg(viewer_dir().join("tests/report.mjs"))
        .args(["--file", s(&out), "--sections", SECTIONS, "--screenshot", s(&shot), "--chromium", &browser])
        .output()
        .expect("node runs");
    assert!(check.status.success(), "{}", String::from_utf8_lossy(&check.stderr));
    let summary = String::from_utf8_lossy(&check.stdout);
    assert!(summary.contains("\"sections\":10") && summary.contains("\"figures\":5"), "{summary}");
    if let Ok(keep) = std::env::var("JAWTRACK_KEEP_REPORT") {
        std::fs::copy(&shot, Path::new(&keep).join("report.png")).expect("copy the screenshot");
        std::fs::copy(&out, Path::new(&keep).join("report.html")).expect("copy the report");
    }
    // Printed to PDF through the same Chromium.
    let pdf = dir.path().join("report.pdf");
    let mut args = vec!["report", s(&rec), "--out", s(&out), "--force", "--pdf", s(&pdf)];
    args.extend(flags.iter().map(String::as_str));
    let printed =
        Command::new(env!("CARGO_BIN_EXE_jawtrack")).args(&args).env("CHROMIUM", &browser).output().expect("runs");
    assert!(printed.status.success(), "{}", String::from_utf8_lossy(&printed.stderr));
    let bytes = std::fs::read(&pdf).expect("the PDF");
    assert!(bytes.starts_with(b"%PDF-") && bytes.len() > 20_000, "{} bytes", bytes.len());
}

#[test]
fn bad_windows_and_missing_poses_are_refused_by_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (rec, _) = session(dir.path());
    let out = dir.path().join("r.html");
    refused(&jawtrack(&["report", s(&rec), "--out", s(&out), "--co", "100:101"]), "--co 100:101");
    refused(&jawtrack(&["report", s(&rec), "--out", s(&out), "--opening", "3:2"]), "FROM must be before TO");
    refused(&jawtrack(&["report", s(&rec), "--out", s(&out), "--mi", "0:1"]), "--co");
    assert!(!out.exists());
    // Frames, but never both markers.
    let lost = dir.path().join("lost.jsonl");
    let line = json!({"frame": 0, "t": 0.0, "maxilla": null, "mandible": null, "maxilla_from_mandible": null});
    std::fs::write(&lost, format!("{line}\n")).expect("write");
    refused(&jawtrack(&["report", s(&lost), "--out", s(&out)]), "nothing to report");
}

#[test]
fn a_contacts_folder_puts_its_maps_and_teeth_in_the_report() {
    use jawtrack_occlusion::scenes;
    use nalgebra::Point3;
    let dir = tempfile::tempdir().expect("tempdir");
    let (rec, _) = session(dir.path());
    // Two lower molars, left and right, pressing 0.2 mm into a flat upper patch.
    let upper = dir.path().join("upper.ply");
    scenes::patch(10.0, 100, 0.0, true).write_coloured_ply(&upper, &[]).expect("write");
    let tooth = |name: &str, x: f64| {
        let p = dir.path().join(name);
        scenes::sphere(Point3::new(x, 0.0, 0.2 - 2.0), 2.0, 40).write_coloured_ply(&p, &[]).expect("write");
        p
    };
    let (t36, t46) = (tooth("lower_FDI=36.ply", -2.5), tooth("lower_FDI=46.ply", 2.5));
    let poses = identity_bite(dir.path());
    let found = dir.path().join("contacts");
    ok(&jawtrack(&[
        "contacts",
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&t36),
        s(&t46),
        "--poses",
        s(&poses),
        "--out",
        s(&found),
        "--quiet",
    ]));
    let out = dir.path().join("report.html");
    // A folder made from another recording is refused, naming both, and writes nothing.
    let o = jawtrack(&["report", s(&rec), "--out", s(&out), "--contacts", s(&found)]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("was made from") && e.contains("run `jawtrack contacts` on this"), "{e}");
    assert!(!out.exists(), "a refused report leaves no file");
    ok(&jawtrack(&["report", s(&poses), "--out", s(&out), "--contacts", s(&found)]));
    let html = std::fs::read_to_string(&out).expect("the report");
    let section = &html[html.find("<section id=\"contacts\">").expect("the section")..];
    let section = &section[..section.find("</section>").expect("its end")];
    assert_eq!(section.matches("<figure>").count(), 4, "two maps per arch");
    assert!(section.contains(">36 (Univ. 19)<") && section.contains(">46 (Univ. 30)<"), "tooth numbers on the maps");
    assert!(section.contains("<td>36</td><td>19</td><td>1</td>"), "the per-tooth table");
    assert!(section.contains("0.200 mm penetration"), "the deepest contact");
    // The same contacts checked by the report itself, the scans placed through a registration
    // that puts the lower scan in its bite at the closed jaw.
    let rest = Rig::default().mounting.maxilla_from_mandible_rest();
    let reg = jawtrack_registration::Registration {
        mandible_scan_from_mandible_marker: rest,
        ..jawtrack_registration::Registration::identity()
    };
    let reg_file = dir.path().join("registration.json");
    std::fs::write(&reg_file, reg.to_json()).expect("write");
    let said = ok(&jawtrack(&[
        "report",
        s(&rec),
        "--out",
        s(&out),
        "--force",
        "--registration",
        s(&reg_file),
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&t36),
        s(&t46),
        "--contact-frames",
        "50",
    ]));
    assert!(said.contains("wrote"), "{said}");
    let html = std::fs::read_to_string(&out).expect("the report");
    let section = &html[html.find("<section id=\"contacts\">").expect("the section")..];
    let section = &section[..section.find("</section>").expect("its end")];
    assert_eq!(section.matches("<figure>").count(), 4, "two maps per arch");
    assert!(section.contains("checked here: 50 of 400 frames"), "every 8th of the session's frames");
    assert!(section.contains("<td>36</td><td>19</td>") && section.contains("<td>46</td><td>30</td>"), "both teeth");
    // The bite presses 0.2 mm at the closed jaw; moving, the ball rolls deeper into the patch.
    assert!(section.contains("mm penetration at") && !section.contains("<td>0 ("), "{:.1000}", section);
    refused(
        &jawtrack(&["report", s(&rec), "--out", s(&out), "--force", "--maxilla", s(&upper), "--mandible", s(&t36)]),
        "--registration",
    );
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).expect("mkdir");
    refused(&jawtrack(&["report", s(&rec), "--out", s(&out), "--force", "--contacts", s(&empty)]), "summary.json");
}

#[test]
fn patient_operator_and_notes_are_printed_escaped_and_checked() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (rec, _) = session(dir.path());
    let out = dir.path().join("report.html");
    let run = |extra: &[&str]| {
        let mut args = vec!["report", s(&rec), "--out", s(&out), "--force"];
        args.extend(extra);
        jawtrack(&args)
    };
    ok(&run(&["--patient", "Ana <Ruiz>", "--notes", "clicks on opening\nleft side"]));
    let html = std::fs::read_to_string(&out).expect("the report");
    assert!(html.contains("<tr><th>Patient</th><td>Ana &lt;Ruiz&gt;</td></tr>"), "escaped");
    assert!(html.contains("<tr><th>Operator</th><td><span class=\"fill\">____"), "a line to fill in");
    assert!(html.contains("<td>clicks on opening<br>left side</td>"), "line breaks kept");
    // Refused by flag, before anything is written.
    std::fs::remove_file(&out).expect("rm");
    let long = "x".repeat(201);
    refused(&run(&["--patient", &long]), "--patient: 201 characters; at most 200 are accepted");
    refused(&run(&["--notes", &"x".repeat(2001)]), "--notes: 2001 characters; at most 2000 are accepted");
    refused(
        &run(&["--operator", "Dr A\nB"]),
        "--operator: control character U+000A at character 5: it must be one line without control characters",
    );
    refused(
        &run(&["--notes", "a\tb"]),
        "--notes: control character U+0009 at character 2: the notes may hold line breaks but no other control \
         character",
    );
    assert!(!out.exists(), "a refused report leaves no file");
}
