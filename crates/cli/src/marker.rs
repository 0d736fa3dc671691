//! `jawtrack marker`, `check-marker` and `harness`: the ideal marker file, a marker file
//! checked and listed, and the harness CAD (tag sheets, body STL) from `jawtrack_harness`.

use anyhow::Result;
use clap::Args;
use jawtrack_marker::{DEFAULT_EDGE_MM, Marker};
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack harness`.
#[derive(Args)]
pub(crate) struct HarnessArgs {
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    geometry: GeometryArgs,
    /// Length of the mounting post below the body's bottom vertex (mm).
    #[arg(long, default_value_t = 25.0, allow_hyphen_values = true)]
    post_length: f64,
    /// Diameter of the mounting post (mm).
    #[arg(long, default_value_t = 4.0, allow_hyphen_values = true)]
    post_diameter: f64,
}

/// The marker's printed geometry, shared by the commands that make a marker.
#[derive(Args)]
struct GeometryArgs {
    /// Edge length of the dodecahedron (mm).
    #[arg(long, default_value_t = DEFAULT_EDGE_MM, allow_hyphen_values = true)]
    edge: f64,
    /// Side of each tag's black-border square (mm); default: the largest that leaves a
    /// one-cell white margin on the face.
    #[arg(long, allow_hyphen_values = true)]
    tag_size: Option<f64>,
}

impl GeometryArgs {
    fn marker(&self) -> Result<Marker> {
        Ok(Marker::nominal(self.edge, self.tag_size)?)
    }
}

/// Arguments of `jawtrack marker`.
#[derive(Args)]
pub(crate) struct MarkerArgs {
    /// Where to write the marker file (JSON).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    force: crate::output::ForceArgs,
    #[command(flatten)]
    geometry: GeometryArgs,
}

pub(crate) fn marker(a: &MarkerArgs) -> Result<()> {
    a.force.check_file(&a.out)?;
    let m = a.geometry.marker()?;
    m.save(&a.out)?;
    let size = m.bodies[0].tags[0].size;
    say!("wrote {} (edge {} mm, tag size {:.4} mm, {} tags)", a.out.display(), m.edge, size, m.tags().count());
    Ok(())
}

pub(crate) fn harness(a: &HarnessArgs) -> Result<()> {
    let marker = a.geometry.marker()?;
    let params = jawtrack_harness::HarnessParams {
        post_length: a.post_length,
        post_diameter: a.post_diameter,
        ..jawtrack_harness::HarnessParams::default()
    };
    let written = jawtrack_harness::write_harness(&a.out, &marker, &params)?;
    for p in &written {
        say!("wrote {}", p.display());
    }
    say!("print the sheets at 100 % and check the 10 mm bar; see harness-cad/README.md for assembly");
    Ok(())
}

pub(crate) fn check_marker(file: &Path) -> Result<()> {
    let m = Marker::load(file)?;
    m.require_both_bodies().map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    say!("{}: valid marker file, edge {} mm", file.display(), m.edge);
    let calibrated = m.is_calibrated();
    if !calibrated {
        say!("  calibration: none recorded (a nominal marker, or a file from before marker file version 2)");
    }
    for b in &m.bodies {
        let ids: Vec<String> = b.tags.iter().map(|t| t.id.to_string()).collect();
        say!("  {}: {} tags, ids {}", b.kind, b.tags.len(), ids.join(" "));
        if calibrated {
            print_provenance(b);
        }
    }
    Ok(())
}

/// A calibrated marker's body: how it was calibrated, each tag's residuals, and the tags left
/// nominal that the tracker flags a pose on.
fn print_provenance(b: &jawtrack_marker::Body) {
    use jawtrack_marker::TagProvenance;
    match &b.provenance {
        Some(p) => {
            let from = if p.recordings.is_empty() { String::new() } else { format!(" of {}", p.recordings.join(", ")) };
            say!(
                "    calibrated from {} views{from}: reprojection error {:.3} px nominal, {:.3} px calibrated",
                p.views,
                p.rms_before_px,
                p.rms_after_px
            );
            say!("    tag  status      views  px before  px after");
            for t in &b.tags {
                match t.provenance {
                    Some(TagProvenance::Calibrated { views, rms_before_px, rms_after_px }) => {
                        say!("    {:3}  calibrated  {views:5}  {rms_before_px:9.3}  {rms_after_px:8.3}", t.id)
                    }
                    Some(TagProvenance::Nominal { views }) => say!("    {:3}  nominal     {views:5}", t.id),
                    None => say!("    {:3}  unknown", t.id),
                }
            }
        }
        None => say!("    not calibrated: every tag at its nominal place"),
    }
    let nominal: Vec<String> =
        b.tags.iter().filter(|t| !t.provenance.is_some_and(|p| p.is_calibrated())).map(|t| t.id.to_string()).collect();
    if !nominal.is_empty() {
        say!("    nominal tags {}: a pose that uses them is flagged {}:uncalibrated_tag", nominal.join(", "), b.kind);
    }
}
