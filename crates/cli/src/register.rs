//! `jawtrack register`: where a marker sits in the scan of its printed harness, by ICP of the
//! body's solid (the marker file's) onto the scan (`jawtrack_registration::icp`), written into the
//! registration file `jawtrack track --registration` reads. Each run fills in one body's
//! entry, keeping whatever else the file holds, so the maxilla and the mandible are
//! registered into one file one after the other.

use anyhow::{Context, Result};
use clap::Args;
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::Pose;
use jawtrack_recording::Overwrite;
use jawtrack_registration::Registration;
use jawtrack_registration::icp::{Acceptance, IcpOptions, centred_init, marker_surface_samples, register, set_entry};
use std::path::PathBuf;

/// Arguments of `jawtrack register`.
#[derive(Args)]
pub(crate) struct RegisterArgs {
    /// The marker file (its solid and edge give the model's shape and size).
    #[arg(long)]
    marker: PathBuf,
    /// Which body the scan shows: maxilla or mandible.
    #[arg(long, value_parser = parse_body)]
    body: BodyKind,
    /// The scan of the printed harness (STL, PLY or OBJ in mm); the post, teeth and holes are fine.
    #[arg(long)]
    scan: PathBuf,
    /// Initial guess of scan_from_marker: "rx,ry,rz,tx,ty,tz" (rotation vector in degrees,
    /// translation in mm) or 16 numbers, a 4×4 row-major matrix as in the registration file. It
    /// must be within about 30° and 3 mm of the truth: the marker's solid looks the same turned 72°
    /// about a face, so the guess decides which face is which. Default: the marker's axes at the
    /// centre of the scan's surface, for a scan in the marker's orientation.
    #[arg(long, allow_hyphen_values = true)]
    init: Option<Pose>,
    /// The registration file to write; if it exists, only this body's entry changes.
    #[arg(long)]
    out: PathBuf,
    /// Farthest a model point may be from the scan to be paired in the first iteration (mm);
    /// the fit is refused if it moves the marker's centre more than twice this from the
    /// guess, or turns it more than 36°.
    #[arg(long, default_value_t = 3.0)]
    max_distance: f64,
    /// Largest accepted RMS residual (mm).
    #[arg(long, default_value_t = 0.2)]
    max_rms: f64,
    /// Smallest accepted fraction of the marker solid's surface found in the scan (0–1).
    #[arg(long, default_value_t = 0.3)]
    min_overlap: f64,
    /// Spacing of the model points on the faces (mm).
    #[arg(long, default_value_t = 0.5)]
    spacing: f64,
}

/// Parses `maxilla` or `mandible`.
fn parse_body(s: &str) -> Result<BodyKind, String> {
    BodyKind::from_name(s).ok_or_else(|| format!("expected maxilla or mandible, got '{s}'"))
}

pub(crate) fn run(a: &RegisterArgs) -> Result<()> {
    let marker = Marker::load(&a.marker)?;
    let samples = marker_surface_samples(&marker, a.body, a.spacing).context("--marker/--body/--spacing")?;
    // Read the registration first: a file we cannot update is refused before any work.
    let mut registration = if a.out.exists() {
        Registration::load(&a.out).with_context(|| {
            format!("--out {} exists but is not a registration file; refusing to overwrite it", a.out.display())
        })?
    } else {
        Registration::identity()
    };
    let scan = jawtrack_occlusion::load_mesh(&a.scan).context("--scan")?;
    let init = match a.init {
        Some(p) => p,
        None => {
            let p = centred_init(&scan, &marker).context("--scan: the scan has no surface area")?;
            say!("no --init: starting with the marker's axes at the centre of the scan's surface");
            p
        }
    };
    let options = IcpOptions { max_distance_mm: a.max_distance, ..IcpOptions::default() };
    let result = register(&samples, &scan, &init, &options).context("registration failed; nothing written")?;
    say!("{}", result.describe(a.body, &a.scan.display().to_string()));
    let limits = Acceptance::for_pairing(a.max_distance, a.max_rms, a.min_overlap);
    result.check(&limits).with_context(|| format!("not written to {}", a.out.display()))?;

    let (field, kept) = set_entry(&mut registration, a.body, result.scan_from_marker);
    // The file was read above and its other entries kept: replacing it whole is the update.
    jawtrack_recording::write_file_atomic(&a.out, (registration.to_json() + "\n").as_bytes(), Overwrite::Replace)
        .with_context(|| format!("writing {}", a.out.display()))?;
    say!("wrote {}: {field} set, {kept} and the intercuspation pose kept", a.out.display());
    Ok(())
}
