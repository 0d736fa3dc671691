//! Time to make the report of a 60 s session at 60 frames/s (issue 26's target: at most 5 s):
//! reading the recording's JSON lines and rendering the page with every section measured, on a
//! rehearsed clinical session with exact poses (`synth`'s `ClinicalSession`, chewing after the
//! border movements). Medians over `--repeat` runs.
//!
//! `cargo bench -p jawtrack-report --bench report_time [-- --seconds S --fps F --repeat N]`

use jawtrack_kinematics::{Anatomy, Window};
use jawtrack_pose::median;
use jawtrack_recording::{RecordingHeader, read_recording};
use jawtrack_report::{Centric, Inputs, Windows, render};
use jawtrack_synth::scenes::{Guidance, Rig};
use serde_json::json;
use std::time::Instant;

fn arg(name: &str, default: f64) -> f64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn main() {
    let (seconds, fps, repeat) = (arg("--seconds", 60.0), arg("--fps", 60.0), arg("--repeat", 5.0) as usize);
    let rig = Rig::default();
    let session = rig.clinical_session(&Guidance::default(), fps, (seconds - 15.0).max(0.0));
    // Lines as `jawtrack track` writes them: both bodies, their tags, error and covariance.
    let body = |pose: &jawtrack_pose::Pose| json!({"camera_from_body": pose, "tags": [0, 1, 2], "rejected_tags": [], "rms_px": 0.12, "cov": vec![0.0; 36]});
    let mut text = RecordingHeader::new("report bench").to_line() + "\n";
    for (k, (t, pose)) in session.poses.iter().enumerate() {
        let line = json!({"frame": k, "t": t, "maxilla": body(&rig.mounting.head_from_maxilla), "mandible": body(pose),
            "maxilla_from_mandible": pose, "flags": []});
        text += &(line.to_string() + "\n");
    }
    let w = |(from, to): (f64, f64)| Some(Window { from, to });
    let mut times = Vec::new();
    let mut size = 0;
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        let rec = read_recording(text.as_bytes()).expect("the session reads");
        let rest = rec.frames[0].maxilla_from_mandible.expect("a jaw pose");
        let co = session.poses.iter().find(|(t, _)| *t > session.co.0).expect("held").1;
        let inputs = Inputs {
            recording: &rec,
            recording_name: "bench.jsonl".into(),
            anatomy: Anatomy::standard(),
            points_file: None,
            registration_file: None,
            rest,
            rest_words: "frame 0".into(),
            windows: Windows {
                opening: w(session.opening),
                protrusion: w(session.protrusion),
                left: w(session.left),
                right: w(session.right),
            },
            centric: Some(Centric { co, mi: rest, co_window: Window { from: session.co.0, to: session.co.1 } }),
            contacts: None,
            made_unix_s: 0.0,
        };
        let report = render(&inputs);
        times.push(start.elapsed().as_secs_f64());
        size = report.html.len();
    }
    let m = median(times.iter().copied()).unwrap_or(f64::NAN);
    println!(
        "report of a {seconds} s session at {fps} frames/s ({} frames, {} MB of JSON lines, page {} kB): \
         median {:.0} ms over {} runs (min {:.0} ms); target ≤ 5000 ms: {}",
        session.poses.len(),
        text.len() / 1_000_000,
        size / 1024,
        m * 1e3,
        times.len(),
        times.iter().copied().fold(f64::INFINITY, f64::min) * 1e3,
        if m <= 5.0 { "met" } else { "MISSED" }
    );
}
