//! `jawtrack points`: writes or checks the anatomical points file
//! (`jawtrack_kinematics::anatomy`), and the `--points` flag of the commands that read the
//! anatomy: with it and a registration the patient's own frame and points replace the standard
//! harness mounting.

use crate::numbers::{fixed, parse_numbers};
use crate::output::ForceArgs;
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_kinematics::anatomy::{BALKWILL_DEG, BONWILL_SIDE_MM, Condyles, OcclusalPlane};
use jawtrack_kinematics::{AnatomicalPoints, Mounting};
use jawtrack_pose::Pose;
use jawtrack_tracker::Registration;
use nalgebra::{Point3, Vector3};
use std::path::{Path, PathBuf};

fn parse_occlusal(s: &str) -> Result<OcclusalPlane, String> {
    let v = parse_numbers(s, 9, "IX,IY,IZ,LX,LY,LZ,RX,RY,RZ: the incisal point, the left and the right molar")?;
    Ok(OcclusalPlane { incisal: [v[0], v[1], v[2]], left_molar: [v[3], v[4], v[5]], right_molar: [v[6], v[7], v[8]] })
}

fn parse_point(s: &str) -> Result<[f64; 3], String> {
    let v = parse_numbers(s, 3, "X,Y,Z")?;
    Ok([v[0], v[1], v[2]])
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
        let p = read(file)?;
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
    std::fs::write(out, p.to_json() + "\n").with_context(|| format!("writing {}", out.display()))?;
    say!("wrote {}", out.display());
    describe(&p);
    Ok(())
}

/// Reads a points file, naming it in any error.
pub(crate) fn read(file: &Path) -> Result<AnatomicalPoints> {
    let text = std::fs::read_to_string(file).with_context(|| format!("reading the points file {}", file.display()))?;
    AnatomicalPoints::from_json(&text).with_context(|| format!("{}", file.display()))
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

/// The `--points` flag.
#[derive(Args, Clone, Debug)]
pub(crate) struct PointsArg {
    /// The anatomical points file (`jawtrack points`): the patient's occlusal plane, midline,
    /// lower incisal point and condyles, picked on the upper scan; needs --registration.
    /// Default: the standard harness mounting.
    #[arg(long, value_name = "FILE")]
    pub(crate) points: Option<PathBuf>,
}

/// The anatomy a command reads: the mounting, and what it came from, in words for its output.
pub(crate) struct Anatomy {
    pub(crate) mounting: Mounting,
    /// The reference plane angles are measured to.
    pub(crate) reference_plane: &'static str,
    /// Where the condyles and the incisal point came from.
    pub(crate) landmarks: &'static str,
    /// Whether the condyles were given (not assumed).
    pub(crate) condyles_given: bool,
}

/// The anatomy of `points` through `registration`, with the closed jaw at `rest`; the standard
/// harness mounting without `points`.
pub(crate) fn anatomy(points: Option<&Path>, registration: Option<&Registration>, rest: &Pose) -> Result<Anatomy> {
    let Some(file) = points else {
        return Ok(Anatomy {
            mounting: Mounting::default(),
            reference_plane: "the head frame's horizontal plane of the standard harness mounting",
            landmarks: "the standard harness mounting's condyles and lower incisal point",
            condyles_given: false,
        });
    };
    let Some(reg) = registration else {
        bail!(
            "--points needs --registration: the points are in the upper scan's frame, and the registration \
             (`jawtrack register`) places that scan on the maxilla marker"
        );
    };
    let p = read(file)?;
    let given = p.condyles.is_some();
    let mounting = p.mounting(&reg.maxilla_scan_from_maxilla_marker, rest);
    if mounting.head_from_maxilla.translation().y > 0.0 {
        eprintln!(
            "warning: in the frame of {} the maxilla marker sits below the occlusal plane: are the left and right \
             molar points swapped?",
            file.display()
        );
    }
    Ok(Anatomy {
        mounting,
        reference_plane: "the occlusal plane of the points file",
        landmarks: if given {
            "the points file's condyles and lower incisal point"
        } else {
            "the points file's lower incisal point, and the Bonwill triangle's condyles"
        },
        condyles_given: given,
    })
}

/// Reads `--registration`, naming the file in any error.
pub(crate) fn registration(path: Option<&Path>) -> Result<Option<Registration>> {
    path.map(|p| Registration::load(p).with_context(|| format!("registration file {}", p.display()))).transpose()
}
