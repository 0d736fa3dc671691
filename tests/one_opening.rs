//! One number means one thing: the same recording's maximum opening as each door gives it —
//! the demo's motion line, `jawtrack metrics` (its JSON), `export --csv`, the report's page and
//! the viewer's replay — equal, since each reads the lower incisor through
//! `jawtrack_session::incisor::path` (definitions: `docs/kinematics.md`). The recording holds
//! the rendered hinge fixture's true poses, with the jaw's first frame closed.

use jawtrack_session::export::{Format, Inputs};
use jawtrack_synth::GroundTruth;

/// The fixture's truth, and a recording of its poses written to `dir`.
fn truth_recording(dir: &std::path::Path) -> (GroundTruth, std::path::PathBuf) {
    let set = jawtrack_test_support::fixtures_dir().join("hinge-1080p");
    let truth: GroundTruth =
        serde_json::from_str(&std::fs::read_to_string(set.join("ground_truth.json")).expect("truth"))
            .expect("the truth's schema");
    let mut text = String::new();
    for (i, f) in truth.frames.iter().enumerate() {
        let pose = serde_json::to_value(f.maxilla_from_mandible).expect("a pose as JSON");
        text += &serde_json::json!({"frame": i, "t": f.t, "maxilla_from_mandible": pose}).to_string();
        text.push('\n');
    }
    let path = dir.join("session.jsonl");
    std::fs::write(&path, text).expect("writing the recording");
    (truth, path)
}

/// The number printed after `label` in the report's table cell ("36.3 mm").
fn report_value(html: &str, label: &str) -> f64 {
    let at = html.find(&format!("{label}</td>")).unwrap_or_else(|| panic!("no '{label}' row in the report"));
    let cell = &html[at + label.len()..];
    let start = cell.find("<td>").expect("a value cell") + 4;
    let end = cell[start..].find(" mm").expect("a value in mm") + start;
    cell[start..end].parse().unwrap_or_else(|e| panic!("'{}': {e}", &cell[start..end]))
}

#[test]
fn every_door_gives_the_same_maximum_opening() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (truth, path) = truth_recording(dir.path());
    let rec = jawtrack_session::open(&path, None).expect("opening").recording;
    assert_eq!(rec.frames.len(), truth.frames.len(), "every frame read back");
    let rest_at = jawtrack_session::rest_of(&rec, None).expect("rest").expect("a posed frame");
    let rest = rest_at.pose();
    let anatomy = jawtrack_session::anatomy(None, None, &rest).expect("the standard anatomy");
    let chosen = jawtrack_session::incisor::ChosenIncisor::of(&anatomy, None).expect("the standard point");

    // `jawtrack metrics --json`.
    let samples = jawtrack_session::incisor::path(&rec.frames, &chosen.incisor, &rest);
    let metrics = jawtrack_kinematics::Metrics::compute(&samples).expect("metrics");
    let json =
        jawtrack_session::measures::metrics_json(&metrics, &samples, &rec, &path, rest_at, &chosen.incisor, true);
    let from_metrics = json["max_opening"]["mm"].as_f64().expect("max_opening.mm");
    assert!(from_metrics > 20.0, "the fixture opens wide: {from_metrics} mm");

    // The demo's motion line, from the same file.
    let demo = jawtrack_demo::Motion::of(&truth, &path).expect("the demo's motion");
    assert_eq!(demo.max_opening_mm, from_metrics, "demo");
    assert!((demo.truth_max_opening_mm - from_metrics).abs() < 1e-9, "the truth is the recording here");

    // `jawtrack export --csv`: the largest `opening_mm`.
    let mut csv = Vec::new();
    let inputs = Inputs { rest: Some(rest_at), recording: "session.jsonl".into(), ..Inputs::default() };
    jawtrack_session::export::export(Format::Csv, &rec, inputs, &mut csv).expect("the CSV");
    let csv = String::from_utf8(csv).expect("UTF-8");
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let column = head.iter().position(|c| *c == "opening_mm").expect("an opening_mm column");
    let openings: Vec<f64> =
        lines.map(|l| l.split(',').nth(column).expect("the column").parse().expect("a number")).collect();
    assert_eq!(openings.len(), truth.frames.len(), "one CSV row per frame");
    let from_csv = openings.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!((from_csv - from_metrics).abs() < 1e-8, "CSV {from_csv} vs metrics {from_metrics}");

    // The viewer's replay: the largest `opening_mm` of its frames.
    let options = jawtrack_viewer::ViewerOptions::default();
    let state = jawtrack_viewer::LiveState::replay(&options, None, &rec.frames, Some(rest)).expect("the replay");
    let frames = state.replay_json().expect("a replay")["frames"].as_array().expect("frames").clone();
    assert_eq!(frames.len(), truth.frames.len(), "one replay frame per recorded frame");
    let from_viewer = frames.iter().filter_map(|f| f["opening_mm"].as_f64()).fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(from_viewer, from_metrics, "viewer");

    // The report's page, to its printed 0.1 mm.
    let inputs = jawtrack_report::Inputs {
        recording: &rec,
        recording_name: "session.jsonl".into(),
        anatomy,
        points_file: None,
        registration_file: None,
        rest,
        rest_words: rest_at.describe(),
        windows: jawtrack_report::Windows::default(),
        centric: None,
        contacts: None,
        made_unix_s: 0.0,
    };
    let from_report = report_value(&jawtrack_report::render(&inputs).html, "maximum opening");
    assert!((from_report - from_metrics).abs() <= 0.05 + 1e-9, "report {from_report} vs metrics {from_metrics}");
}
