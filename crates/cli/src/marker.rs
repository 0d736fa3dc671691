//! `jawtrack marker`, `check-marker` and `harness`: the ideal marker file, a marker file
//! checked and listed, and the harness CAD (tag sheets, body STL) from `jawtrack_harness`.

use anyhow::Result;
use clap::Args;
use jawtrack_marker::{DEFAULT_EDGE_MM, Marker, SolidKind, TagFamily};
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack harness`.
#[derive(Args)]
pub(crate) struct HarnessArgs {
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Draw the harness of this marker file (its solid, family, edge and tag size) instead of
    /// one made from the flags below.
    #[arg(long, conflicts_with_all = ["edge", "tag_size", "solid", "family"])]
    marker: Option<PathBuf>,
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
    /// The solid each body is: `dodecahedron` (12 tags a body) or `cube` (6).
    #[arg(long, default_value = "dodecahedron", value_parser = parse_solid)]
    solid: SolidKind,
    /// The AprilTag family the tags are printed in: `tag36h11`, `tag25h9` or `tag16h5`.
    #[arg(long, default_value = "tag36h11", value_parser = parse_family)]
    family: TagFamily,
    /// Edge length of the solid (mm).
    #[arg(long, default_value_t = DEFAULT_EDGE_MM, allow_hyphen_values = true)]
    edge: f64,
    /// Side of each tag's black-border square (mm); default: the largest that leaves a
    /// one-cell white margin on the face.
    #[arg(long, allow_hyphen_values = true)]
    tag_size: Option<f64>,
}

fn parse_solid(name: &str) -> Result<SolidKind, String> {
    SolidKind::from_name(name).ok_or_else(|| {
        let known: Vec<&str> = SolidKind::ALL.iter().map(|k| k.name()).collect();
        format!("not a solid this build knows ({})", known.join(", "))
    })
}

fn parse_family(name: &str) -> Result<TagFamily, String> {
    TagFamily::named(name).ok_or_else(|| {
        let known: Vec<&str> = TagFamily::ALL.iter().map(|f| f.name).collect();
        format!("not a tag family this build reads ({})", known.join(", "))
    })
}

impl GeometryArgs {
    fn marker(&self) -> Result<Marker> {
        Ok(Marker::nominal_on(self.solid, self.family, self.edge, self.tag_size)?)
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
    a.force.write_file(&a.out, (m.to_json() + "\n").as_bytes())?;
    let size = m.bodies[0].tags[0].size;
    let what = match (m.solid, m.family == TagFamily::TAG36H11) {
        (SolidKind::Dodecahedron, true) => String::new(),
        (solid, _) => format!("{} on a {solid}, ", m.family.name),
    };
    say!("wrote {} ({what}edge {} mm, tag size {:.4} mm, {} tags)", a.out.display(), m.edge, size, m.tags().count());
    Ok(())
}

pub(crate) fn harness(a: &HarnessArgs) -> Result<()> {
    let marker = match &a.marker {
        Some(file) => {
            let m = Marker::load(file)?;
            m.require_both_bodies().map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
            m
        }
        None => a.geometry.marker()?,
    };
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
    m.describe(&file.display().to_string()).iter().for_each(|l| say!("{l}"));
    Ok(())
}
