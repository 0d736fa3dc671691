//! The charts the commands draw beside the report: the lower incisor's path in each plane and
//! its opening over time (`jawtrack plot`), and a path's convex hull (`jawtrack metrics`).

use jawtrack_kinematics::{Displacement, Envelope, PlaneView, Sample};
use jawtrack_plot::{self as plot, Document, Series, Style};

/// A frame's time (s) and the incisor's displacement from rest.
type Timed = (f64, Displacement);

/// The file stems [`incisor_charts`] saves its charts under, in its order: the path in each
/// plane (`incisor_sagittal`, …), then `incisor_opening`.
pub fn incisor_chart_stems() -> [String; 4] {
    let [a, b, c] = PlaneView::ALL.map(|v| format!("incisor_{}", v.name()));
    [a, b, c, "incisor_opening".into()]
}

/// The lower incisor's path (time in s, displacement from rest) in each plane, then its opening
/// over time; each chart with the file stem it is saved under.
pub fn incisor_charts(path: &[Timed]) -> Vec<(String, Document)> {
    let [sagittal, frontal, transverse, opening] = incisor_chart_stems();
    let series = |f: &dyn Fn(&Timed) -> (f64, f64)| {
        vec![Series {
            name: "lower incisor",
            color: "#d62728",
            style: Style::Line,
            points: path.iter().map(f).collect(),
        }]
    };
    let mut charts: Vec<(String, _)> = PlaneView::ALL
        .iter()
        .zip([sagittal, frontal, transverse])
        .map(|(&v, stem)| {
            let (x, y) = v.axes();
            let title = format!("Lower incisor, {}", v.title());
            (stem, plot::chart(&title, x, y, &series(&|(_, d)| v.project(d)), true))
        })
        .collect();
    charts.push((
        opening,
        plot::chart(
            "Lower incisor opening over time",
            "time (s)",
            "opening (mm)",
            &series(&|(t, d)| (*t, d.opening)),
            false,
        ),
    ));
    charts
}

/// The convex hull `envelope` of `path` in `view`, with the path over it.
pub fn envelope_chart(view: PlaneView, envelope: &Envelope, path: &[Sample]) -> Document {
    // The hull is in the view's axes; closed back to its first corner.
    let outline = envelope.hull.iter().chain(envelope.hull.first()).copied().collect();
    // The hull first, so the path stays visible where it runs along the outline.
    let series = [
        Series { name: "envelope (convex hull)", color: "#1f77b4", style: Style::Line, points: outline },
        Series {
            name: "lower incisor",
            color: "#d62728",
            style: Style::Line,
            points: path.iter().map(|(_, _, d)| view.project(d)).collect(),
        },
    ];
    let (x_label, y_label) = view.axes();
    plot::chart(&format!("Convex hull of the path, {}", view.title()), x_label, y_label, &series, true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_incisor_charts_are_the_three_planes_then_the_opening() {
        let at = |opening| Displacement { opening, lateral: 0.0, protrusive: 0.0 };
        let path = [(0.0, at(0.0)), (1.0, at(10.0))];
        let names: Vec<String> = incisor_charts(&path).into_iter().map(|(n, _)| n).collect();
        let planes = PlaneView::ALL.map(|v| format!("incisor_{}", v.name()));
        assert_eq!(names[..3], planes);
        assert_eq!(names[3], "incisor_opening");
    }
}
