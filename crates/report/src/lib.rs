//! The session report: one self-contained, print-friendly HTML page of a recording's jaw
//! kinematics, for the patient's file. Every number on it comes from `jawtrack_kinematics`
//! (each function there has its unit test against a closed form or the renderer's truth); this
//! crate only chooses what to show and lays it out: the patient, operator and notes, the
//! session and its calibration, quality flags, the lower incisor's metrics, Posselt's border
//! movements as traced, the condylar paths, and, for the windows the caller names, the hinge
//! axis, the articulator values and the CO–MI slide. Plots are inline SVG, the page has no
//! script and loads nothing, so it prints and archives as it is.

mod cautions;
mod charts;
mod html;
mod pdf;
mod record;
mod sections;
mod summary;

pub use charts::{envelope_chart, incisor_chart_stems, incisor_charts};
use jawtrack_kinematics::Anatomy;
pub use jawtrack_kinematics::Window;
use jawtrack_pose::Pose;
use jawtrack_recording::Recording;
pub use pdf::{ReportError, chromium, print_pdf};
pub use record::{Record, RecordField};
pub use summary::{
    articulator_summary, co_mi_summary, contact_findings, hinge_summary, metrics_figures, metrics_summary,
};

/// The movements the caller located in the recording; what is not given is not measured, and
/// the report says which flag would measure it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Windows {
    /// A slow opening from the closed jaw: the hinge axis.
    pub opening: Option<Window>,
    /// A protrusion: condylar inclination, protrusive guidance.
    pub protrusion: Option<Window>,
    /// A laterotrusion toward the patient's left.
    pub left: Option<Window>,
    /// A laterotrusion toward the patient's right.
    pub right: Option<Window>,
}

/// What the report is made from.
#[derive(Debug, Clone)]
pub struct Inputs<'a> {
    /// The recording, read.
    pub recording: &'a Recording,
    /// Its file name, as the report names it.
    pub recording_name: String,
    /// The anatomy the numbers are read in.
    pub anatomy: Anatomy,
    /// The points file, if one was given.
    pub points_file: Option<String>,
    /// The registration file, if one was given.
    pub registration_file: Option<String>,
    /// The closed jaw every displacement is measured from (`maxilla_from_mandible`).
    pub rest: Pose,
    /// Where the closed jaw came from, in words ("the bite accepted at 1.20 s").
    pub rest_words: String,
    /// The movements located in the recording.
    pub windows: Windows,
    /// Centric occlusion and maximal intercuspation as held positions (each the mean pose of
    /// its window), and the windows in words, for the CO–MI slide.
    pub centric: Option<Centric>,
    /// The occlusal contacts found over the session by `jawtrack contacts`, if given.
    pub contacts: Option<ContactsResult>,
    /// When the report was made (s since the Unix epoch), printed on it.
    pub made_unix_s: f64,
}

/// What `jawtrack contacts` wrote: its `summary.json` and its contact maps (SVG), which the
/// report shows as they are.
#[derive(Debug, Clone)]
pub struct ContactsResult {
    /// Where it was read from, as the report names it.
    pub folder: String,
    /// `summary.json`.
    pub summary: serde_json::Value,
    /// The maps: (what, SVG text), e.g. ("upper arch, deepest contact", "<svg …").
    pub maps: Vec<(String, String)>,
}

/// The held positions of the CO–MI slide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Centric {
    /// Centric occlusion (`maxilla_from_mandible`).
    pub co: Pose,
    /// Maximal intercuspation.
    pub mi: Pose,
    /// The window CO was held in.
    pub co_window: Window,
}

/// A made report.
#[derive(Debug, Clone)]
pub struct Report {
    /// The page.
    pub html: String,
    /// The sections' ids, in order (every one is always on the page, saying why when it has
    /// nothing to show).
    pub sections: Vec<&'static str>,
    /// The quality warnings, as the page lists them.
    pub warnings: Vec<String>,
}

const BLUE: &str = "#1f77b4";
const RED: &str = "#d62728";
const GREY: &str = "#b0b0b0";
const GREEN: &str = "#2ca02c";

/// The incisor's path and its traced border in one view, each landmark marked with its tag:
/// the plot the report and `jawtrack metrics` draw.
pub fn border_chart(b: &jawtrack_kinematics::Border, path: &[jawtrack_kinematics::Sample]) -> jawtrack_plot::Document {
    use jawtrack_kinematics::border::tag;
    use jawtrack_plot::{Series, Style};
    let mut closed = b.outline.clone();
    closed.extend(b.outline.first());
    let mut series = vec![
        Series {
            name: "path",
            color: GREY,
            style: Style::Line,
            points: path.iter().map(|(_, _, d)| b.view.project(d)).collect(),
        },
        Series { name: "border (traced)", color: BLUE, style: Style::Line, points: closed },
    ];
    for l in &b.landmarks {
        series.push(Series { name: tag(l.name), color: RED, style: Style::Marked, points: vec![l.at] });
    }
    let (x, y) = b.view.axes();
    jawtrack_plot::chart(&format!("Lower incisor, {}", b.view.title()), x, y, &series, true)
}

/// Makes the report of `inputs`, its patient, operator and notes left to fill in by hand.
pub fn render(inputs: &Inputs) -> Report {
    render_with(inputs, &Record::default())
}

/// Makes the report of `inputs` headed with `record` (kept apart from [`Inputs`] so that every
/// caller that does not name a patient builds its inputs as before).
pub fn render_with(inputs: &Inputs, record: &Record) -> Report {
    sections::render(inputs, record)
}
