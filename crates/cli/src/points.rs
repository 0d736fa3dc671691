//! `jawtrack points`: writes or checks the anatomical points file
//! (`jawtrack_kinematics::anatomy`); with it and a registration the patient's own frame and
//! points replace the standard harness mounting (`jawtrack_session::anatomy`).

use crate::numbers::{fixed, parse_numbers, parse_point};
use crate::output::ForceArgs;
use anyhow::{Result, bail};
use clap::Args;
use jawtrack_kinematics::AnatomicalPoints;
use jawtrack_kinematics::anatomy::{BALKWILL_DEG, BONWILL_SIDE_MM, Condyles, OcclusalPlane};
use nalgebra::{Point3, Vector3};
use std::path::PathBuf;

fn parse_occlusal(s: &str) -> Result<OcclusalPlane, String> {
    let v = parse_numbers(s, 9, "IX,IY,IZ,LX,LY,LZ,RX,RY,RZ: the incisal point, the left and the right molar")?;
    Ok(OcclusalPlane { incisal: [v[0], v[1], v[2]], left_molar: [v[3], v[4], v[5]], right_molar: [v[6], v[7], v[8]] })
}

fn parse_condyles(s: &str) -> Result<Condyles, String> {
    let v = parse_numbers(s, 6, "LX,LY,LZ,RX,RY,RZ: the left and the right condyle")?;
    Ok(Condyles { left: [v[0], v[1], v[2]], right: [v[3], v[4], v[5]] })
}

/// Arguments of `jawtrack points`.
#[derive(Args)]
#[command(
    after_help = "Every point is in the upper scan's frame (mm), as a mesh viewer shows it when picking points on \
                  the scan (MeshLab: Edit > PickPoints). Write a file with --occlusal, --lower-incisal and --out; \
                  check one with --check."
)]
pub(crate) struct PointsArgs {
    /// Check and describe this points file instead of writing one.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["occlusal", "lower_incisal", "condyles", "out"])]
    check: Option<PathBuf>,
    /// The occlusal plane: the incisal point (between the upper central incisors' edges), then
    /// the left and the right first molar's mesiobuccal cusp tip.
    #[arg(long, value_name = "IX,IY,IZ,LX,LY,LZ,RX,RY,RZ", value_parser = parse_occlusal, allow_hyphen_values = true)]
    occlusal: Option<OcclusalPlane>,
    /// The lower incisal point (between the lower central incisors' edges) with the jaw in
    /// maximal intercuspation, on the lower scan placed in its bite.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true)]
    lower_incisal: Option<[f64; 3]>,
    /// The condyles' centres (from a CBCT, or by palpation); default: the Bonwill triangle's.
    #[arg(long, value_name = "LX,LY,LZ,RX,RY,RZ", value_parser = parse_condyles, allow_hyphen_values = true)]
    condyles: Option<Condyles>,
    /// The points file to write.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    #[command(flatten)]
    force: ForceArgs,
}

/// Runs `jawtrack points`.
pub(crate) fn run(a: &PointsArgs) -> Result<()> {
    if let Some(file) = &a.check {
        let p = jawtrack_session::read_points(file)?;
        say!("{} is a valid points file", file.display());
        describe(&p);
        return Ok(());
    }
    let (Some(occlusal), Some(lower_incisal), Some(out)) = (a.occlusal, a.lower_incisal, &a.out) else {
        bail!(
            "give --occlusal IX,IY,IZ,LX,LY,LZ,RX,RY,RZ, --lower-incisal X,Y,Z and --out FILE to write a points file, \
             or --check FILE to check one"
        );
    };
    a.force.check_file(out)?;
    let p = AnatomicalPoints::new(occlusal, lower_incisal, a.condyles)?;
    a.force.write_file(out, (p.to_json() + "\n").as_bytes())?;
    say!("wrote {}", out.display());
    describe(&p);
    Ok(())
}

/// What the points make, in the head frame they define.
fn describe(p: &AnatomicalPoints) {
    let h = p.head_from_scan();
    let at = |v: Vector3<f64>| h.transform_point(&Point3::from(v)).coords;
    let show = |v: Vector3<f64>| format!("({}, {}, {})", fixed(v.x, 1), fixed(v.y, 1), fixed(v.z, 1));
    let ([l, r], given) = p.condyles();
    let incisor = at(Vector3::from(p.lower_incisal_point));
    say!("head frame: origin at the incisal point; X the patient's left, Y down, Z posterior (mm)");
    let o = &p.occlusal_plane;
    say!(
        "molars               left {}  right {}",
        show(at(Vector3::from(o.left_molar))),
        show(at(Vector3::from(o.right_molar)))
    );
    say!("lower incisal point  {}", show(incisor));
    let whose = if given {
        "given".to_string()
    } else {
        format!("the Bonwill triangle's: {BONWILL_SIDE_MM} mm sides, {BALKWILL_DEG}° to the occlusal plane")
    };
    say!("condyles             left {}  right {} ({whose})", show(at(l)), show(at(r)));
    say!("intercondylar        {} mm", fixed((l - r).norm(), 1));
}
