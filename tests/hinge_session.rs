//! The whole chain on a recorded fixture, as a clinician's session goes through it: the frames
//! of `fixtures/hinge-1080p` tracked into a recording file (`jawtrack_offline::track`, what
//! `jawtrack track` runs), the file opened as the clinical commands open it
//! (`jawtrack_session::open`, the rest position), and the lower incisor's path and metrics
//! measured from it (`jawtrack_kinematics`) — each compared with the rendered truth. The
//! marker is the one as printed (the truth's), so what is left is the chain's own error.

use jawtrack_kinematics::{Incisor, Metrics, Sample};
use jawtrack_offline::{OfflineError, Pass, Said, TrackEvents, TrackOptions};
use jawtrack_synth::GroundTruth;
use std::io::Write;
use std::path::PathBuf;

/// Runs quietly, writing the recording to a file.
struct Quiet(PathBuf);

impl TrackEvents for Quiet {
    fn said(&mut self, _: Said) {}
    fn pass(&mut self, _: Pass, _: Option<u64>) {}
    fn frame(&mut self) {}
    fn pass_done(&mut self) {}
    fn ready(&mut self) -> Result<(), OfflineError> {
        Ok(())
    }
    fn refined(&mut self, _: &jawtrack_calibration::Refinement, _: f64) {}
    fn output(&mut self) -> Result<Box<dyn Write>, OfflineError> {
        Ok(Box::new(std::fs::File::create(&self.0).expect("creating the recording")))
    }
}

#[test]
fn a_tracked_hinge_session_measures_as_its_truth() {
    let set = jawtrack_test_support::fixtures_dir().join("hinge-1080p");
    let truth: GroundTruth =
        serde_json::from_str(&std::fs::read_to_string(set.join("ground_truth.json")).expect("truth"))
            .expect("the truth's schema");
    let dir = tempfile::tempdir().expect("temp dir");
    let (marker, recording) = (dir.path().join("printed_marker.json"), dir.path().join("session.jsonl"));
    std::fs::write(&marker, truth.true_marker.to_string()).expect("writing the printed marker");

    let options = TrackOptions {
        marker: Some(marker),
        intrinsics: Some(truth.intrinsics),
        fps: Some(30.0),
        decimate: 2.0,
        threads: 1,
        linear_edges: truth.realism.gamma,
        region_search: true,
        out: recording.clone(),
        frames: vec![set.clone()],
        ..TrackOptions::default()
    };
    let tracked = jawtrack_offline::track(&options, &mut Quiet(recording.clone())).expect("tracking the fixture");
    assert_eq!(tracked.frames, truth.frames.len(), "every frame written");

    let rec = jawtrack_session::open(&recording, None).expect("opening the recording").recording;
    assert_eq!(rec.frames.len(), truth.frames.len(), "every frame read back");
    let rest = jawtrack_session::rest_of(&rec, None).expect("rest").expect("a posed frame").pose();
    let rest_frame = rec.frames.iter().position(|f| f.maxilla_from_mandible.is_some()).expect("a posed frame");
    let true_rest = truth.frames[rest_frame].maxilla_from_mandible;

    let incisor = Incisor::standard();
    let (mut tracked_path, mut true_path): (Vec<Sample>, Vec<Sample>) = (Vec::new(), Vec::new());
    for (f, t) in rec.frames.iter().zip(&truth.frames) {
        let Some(pose) = f.maxilla_from_mandible else { continue };
        let (angle, distance) = pose.distance_to(&t.maxilla_from_mandible);
        assert!(
            distance < 0.1 && angle.to_degrees() < 0.1,
            "frame {}: mandible in maxilla {distance:.3} mm / {:.3}° from the truth",
            f.frame,
            angle.to_degrees()
        );
        tracked_path.push((f.t, f.frame, incisor.displacement(&pose, &rest)));
        true_path.push((f.t, f.frame, incisor.displacement(&t.maxilla_from_mandible, &true_rest)));
    }
    assert_eq!(tracked_path.len(), truth.frames.len(), "every frame has a jaw pose");
    for ((_, frame, got), (_, _, want)) in tracked_path.iter().zip(&true_path) {
        let off = [got.opening - want.opening, got.lateral - want.lateral, got.protrusive - want.protrusive];
        assert!(off.iter().all(|d| d.abs() < 0.15), "frame {frame}: incisor {off:?} mm off the truth");
    }
    let (got, want) = (Metrics::compute(&tracked_path).expect("metrics"), Metrics::compute(&true_path).expect("truth"));
    assert!(want.max_opening.mm > 20.0, "the fixture opens wide: {} mm", want.max_opening.mm);
    assert!(
        (got.max_opening.mm - want.max_opening.mm).abs() < 0.15 && got.max_opening.frame == want.max_opening.frame,
        "max opening {:.3} mm at frame {}, truth {:.3} mm at frame {}",
        got.max_opening.mm,
        got.max_opening.frame,
        want.max_opening.mm,
        want.max_opening.frame
    );
}
