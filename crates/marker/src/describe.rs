//! A marker file described for a person (`jawtrack check-marker`): its family, solid and edge,
//! each body's tags, and for a calibrated file how each body was calibrated, each tag's
//! residuals and the tags left nominal, which the tracker flags a pose on.

use crate::{Body, Marker, TagProvenance};

impl Marker {
    /// The description's lines, starting with `name` (the file): "valid marker file, tag36h11
    /// on a dodecahedron, edge 12.7 mm", then per body its tags and, when calibrated, where
    /// each tag came from.
    ///
    /// # Examples
    ///
    /// ```
    /// let lines = jawtrack_marker::Marker::default().describe("marker.json");
    /// assert!(lines[0].starts_with("marker.json: valid marker file, tag36h11 on a dodecahedron"));
    /// ```
    pub fn describe(&self, name: &str) -> Vec<String> {
        let mut lines =
            vec![format!("{name}: valid marker file, {} on a {}, edge {} mm", self.family.name, self.solid, self.edge)];
        let calibrated = self.is_calibrated();
        if !calibrated {
            lines.push(
                "  calibration: none recorded (a nominal marker, or a file from before marker file version 2)".into(),
            );
        }
        for b in &self.bodies {
            let ids: Vec<String> = b.tags.iter().map(|t| t.id.to_string()).collect();
            lines.push(format!("  {}: {} tags, ids {}", b.kind, b.tags.len(), ids.join(" ")));
            if calibrated {
                provenance(b, &mut lines);
            }
        }
        lines
    }
}

/// A calibrated marker's body: how it was calibrated, each tag's residuals, and the tags left
/// nominal.
fn provenance(b: &Body, lines: &mut Vec<String>) {
    match &b.provenance {
        Some(p) => {
            let from = if p.recordings.is_empty() { String::new() } else { format!(" of {}", p.recordings.join(", ")) };
            lines.push(format!(
                "    calibrated from {} views{from}: reprojection error {:.3} px nominal, {:.3} px calibrated",
                p.views, p.rms_before_px, p.rms_after_px
            ));
            lines.push("    tag  status      views  px before  px after".into());
            for t in &b.tags {
                lines.push(match t.provenance {
                    Some(TagProvenance::Calibrated { views, rms_before_px, rms_after_px }) => {
                        format!("    {:3}  calibrated  {views:5}  {rms_before_px:9.3}  {rms_after_px:8.3}", t.id)
                    }
                    Some(TagProvenance::Nominal { views }) => format!("    {:3}  nominal     {views:5}", t.id),
                    None => format!("    {:3}  unknown", t.id),
                });
            }
        }
        None => lines.push("    not calibrated: every tag at its nominal place".into()),
    }
    let nominal: Vec<String> =
        b.tags.iter().filter(|t| !t.provenance.is_some_and(|p| p.is_calibrated())).map(|t| t.id.to_string()).collect();
    if !nominal.is_empty() {
        lines.push(format!(
            "    nominal tags {}: a pose that uses them is flagged {}:uncalibrated_tag",
            nominal.join(", "),
            b.kind
        ));
    }
}
