//! `jawtrack register`: where a marker sits in the scan of its printed harness, by ICP of the
//! body's solid (the marker file's) onto the scan (`jawtrack_registration::icp`), written into the
//! registration file `jawtrack track --registration` reads. Each run fills in one body's
//! entry, keeping whatever else the file holds, so the maxilla and the mandible are
//! registered into one file one after the other.

use anyhow::{Context, Result};
use clap::Args;
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_occlusion::Mesh;
use jawtrack_pose::Pose;
use jawtrack_recording::Overwrite;
use jawtrack_registration::Registration;
use jawtrack_registration::icp::{
    Acceptance, IcpOptions, IcpResult, centred_init, marker_surface_samples, register, set_entry,
};
use nalgebra::Vector3;
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
    /// The scan of the printed harness (STL, PLY or OBJ in mm); the post, teeth and holes
    /// are fine.
    #[arg(long)]
    scan: PathBuf,
    /// Initial guess of scan_from_marker: "rx,ry,rz,tx,ty,tz" (rotation vector in degrees,
    /// translation in mm) or 16 numbers, a 4×4 row-major matrix as in the registration file.
    /// It must be within about 30° and 3 mm of the truth: the marker's solid looks the same
    /// turned 72° about a face, so the guess decides which face is which. Default: the
    /// marker's axes at the centre of the scan's surface, for a scan in the marker's
    /// orientation.
    #[arg(long, value_parser = parse_init, allow_hyphen_values = true)]
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

/// Parses an initial pose: six numbers (rotation vector in degrees, translation in mm) or 16
/// (row-major 4×4 matrix).
fn parse_init(s: &str) -> Result<Pose, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|c| c.trim().parse::<f64>().map_err(|e| format!("'{}': {e}", c.trim())))
        .collect::<Result<_, _>>()?;
    if !v.iter().all(|c| c.is_finite()) {
        return Err("the numbers must be finite".into());
    }
    match v.len() {
        6 => Ok(Pose::from_axis_angle(
            Vector3::new(v[0], v[1], v[2]).map(f64::to_radians),
            Vector3::new(v[3], v[4], v[5]),
        )),
        16 => {
            let m: [f64; 16] = std::array::from_fn(|i| v[i]);
            Pose::from_row_major(&m, "--init").map_err(|e| e.to_string())
        }
        n => Err(format!(
            "expected 6 numbers (rx,ry,rz in degrees, tx,ty,tz in mm) or 16 (a 4×4 row-major matrix), got {n}"
        )),
    }
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
    let scan = Mesh::load(&a.scan).context("--scan")?;
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
    report(a, &result);
    let limits = Acceptance {
        max_rms_mm: a.max_rms,
        min_overlap: a.min_overlap,
        // A guess within the first pairing distance leaves the centre that near the truth.
        max_shift_mm: 2.0 * a.max_distance,
        ..Acceptance::default()
    };
    result.check(&limits).with_context(|| format!("not written to {}", a.out.display()))?;

    let (field, kept) = set_entry(&mut registration, a.body, result.scan_from_marker);
    // The file was read above and its other entries kept: replacing it whole is the update.
    jawtrack_recording::write_file_atomic(&a.out, (registration.to_json() + "\n").as_bytes(), Overwrite::Replace)
        .with_context(|| format!("writing {}", a.out.display()))?;
    say!("wrote {}: {field} set, {kept} and the intercuspation pose kept", a.out.display());
    Ok(())
}

/// Prints the residual, the overlap and the pose.
fn report(a: &RegisterArgs, r: &IcpResult) {
    say!(
        "{}: {} {} in {} iterations",
        a.body,
        a.scan.display(),
        if r.converged { "registered" } else { "did not converge" },
        r.iterations
    );
    say!(
        "  residual {:.4} mm RMS over {} of {} model points ({:.0} % of the marker solid's surface found in the scan)",
        r.rms_mm,
        r.inliers,
        r.samples,
        100.0 * r.overlap()
    );
    if r.inside_out {
        say!("  note: the scan's triangles wind inward (normals point into the solid); used flipped");
    }
    let pose = &r.scan_from_marker;
    let rotvec = pose.rotation().scaled_axis().map(f64::to_degrees);
    let t = pose.translation();
    say!(
        "  {}_scan_from_{}_marker: rotation vector ({:.4}, {:.4}, {:.4})° ({:.4}°), translation ({:.4}, {:.4}, {:.4}) mm",
        a.body,
        a.body,
        rotvec.x,
        rotvec.y,
        rotvec.z,
        rotvec.norm(),
        t.x,
        t.y,
        t.z
    );
    let m = pose.to_row_major();
    for row in m.chunks(4) {
        say!("    [{:>10.6} {:>10.6} {:>10.6} {:>10.4}]", row[0], row[1], row[2], row[3]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn init_takes_six_or_sixteen_numbers() {
        let p = parse_init("0,0,90,1,-2,3").expect("six");
        assert!((p.rotation().angle().to_degrees() - 90.0).abs() < 1e-9);
        assert_eq!(p.translation(), Vector3::new(1.0, -2.0, 3.0));
        let m = p.to_row_major().map(|v| v.to_string()).join(",");
        let q = parse_init(&m).expect("sixteen");
        assert!(p.distance_to(&q).0 < 1e-12 && p.distance_to(&q).1 < 1e-12);
        for (bad, word) in [("1,2,3", "got 3"), ("1,2,3,4,5,x", "'x'"), ("0,0,0,0,0,NaN", "finite")] {
            let err = parse_init(bad).expect_err(bad);
            assert!(err.contains(word), "{err}");
        }
        assert!(parse_init("2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1").is_err(), "not a rotation");
    }
}
