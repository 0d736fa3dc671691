//! `jawtrack hinge-axis`: the kinematic hinge axis of a recorded opening
//! (`jawtrack_kinematics::hinge`), in the maxilla marker's frame and, given a registration, in
//! the upper scan's; printed, or as one JSON object other tools read.

use crate::flags::{PointsArg, SessionArg, anatomy, load, registration};
use crate::numbers::parse_numbers;
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_kinematics::{HingeOptions, hinge};
use jawtrack_pose::Pose;
use jawtrack_registration::Registration;
use jawtrack_session::measures::{HingeReport, hinge_condyles, hinge_window};
use nalgebra::Point3;
use std::path::PathBuf;

/// Arguments of `jawtrack hinge-axis`.
#[derive(Args)]
pub(crate) struct HingeAxisArgs {
    /// The recording (JSON lines) of an opening from the closed jaw: slow, 10–20 mm at the
    /// incisors is enough (the fit takes the pure turn of early opening).
    recording: PathBuf,
    #[command(flatten)]
    session: SessionArg,
    /// Use the frames from this time (s; the frames' `t`).
    #[arg(long, value_name = "S")]
    from: Option<f64>,
    /// Use the frames up to this time (s).
    #[arg(long, value_name = "S")]
    to: Option<f64>,
    /// The frame (its `frame` number) of the closed jaw the opening starts from; default: the
    /// bite accepted while recording, else the first frame of the window with a jaw pose.
    #[arg(long, value_name = "FRAME", value_parser = crate::numbers::parse_frame, allow_hyphen_values = true)]
    rest_frame: Option<u64>,
    /// Leave out frames turned further than this from the closed jaw (°): past early opening
    /// the condyles slide forward and no axis is fixed.
    #[arg(long, default_value_t = HingeOptions::default().max_rotation_deg, value_name = "DEG", value_parser = crate::numbers::parse_positive_deg, allow_hyphen_values = true)]
    max_rotation_deg: f64,
    /// The registration file (`jawtrack register`): also give the axis in the upper scan's frame.
    #[arg(long)]
    registration: Option<PathBuf>,
    /// The condyles, LX,LY,LZ,RX,RY,RZ in the maxilla marker's frame (mm; from a CBCT or by
    /// palpation, through the registration), to be moved onto the axis; default: the points
    /// file's (--points), else the standard harness mounting's.
    #[arg(long, value_name = "LX,LY,LZ,RX,RY,RZ", value_parser = parse_condyles, allow_hyphen_values = true)]
    condyles: Option<[Point3<f64>; 2]>,
    #[command(flatten)]
    points: PointsArg,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
}

/// Parses six numbers (mm) into the left and right condyle.
fn parse_condyles(s: &str) -> Result<[Point3<f64>; 2], String> {
    let v = parse_numbers(s, 6, "LX,LY,LZ,RX,RY,RZ")?;
    Ok([Point3::new(v[0], v[1], v[2]), Point3::new(v[3], v[4], v[5])])
}

/// The condyles (maxilla marker frame) and where they came from: `--condyles`, else the
/// points file's through the registration, else the standard mounting's.
fn condyles(a: &HingeAxisArgs, reg: Option<&Registration>, rest: &Pose) -> Result<([Point3<f64>; 2], &'static str)> {
    if let Some(c) = a.condyles {
        return Ok((c, "given"));
    }
    Ok(hinge_condyles(&anatomy(a.points.points.as_deref(), reg, rest)?, a.points.points.is_some()))
}

/// Runs `jawtrack hinge-axis`.
pub(crate) fn run(a: &HingeAxisArgs) -> Result<()> {
    let name = a.recording.display();
    if let (Some(from), Some(to)) = (a.from, a.to)
        && from >= to
    {
        bail!("--from {from} is not before --to {to}: the window is empty");
    }
    let registration = registration(a.registration.as_deref())?;
    let rec = load(&a.recording, a.session)?;
    crate::flags::warn_if_nominal(&rec, "the axis of a rendered 40 mm opening moved 1.7–2.4 mm and 2–3°");
    let (window, rest) = hinge_window(&rec, &name.to_string(), (a.from, a.to), a.rest_frame)?;
    let options = HingeOptions { max_rotation_deg: a.max_rotation_deg, ..HingeOptions::default() };
    let poses: Vec<Pose> = window.iter().map(|(_, p)| *p).collect();
    let axis = hinge::fit(&poses, &rest.pose(), None, &options).with_context(|| format!("{name}"))?;
    let scan = registration.as_ref().map(|r| axis.transformed(&r.maxilla_scan_from_maxilla_marker));
    let (condyles, whose) = condyles(a, registration.as_ref(), &rest.pose())?;
    let report = HingeReport {
        axis: &axis,
        scan,
        rest,
        frames: window.len(),
        window: [a.from, a.to],
        recording: &a.recording,
        condyles: (condyles, whose),
    };
    if a.json {
        say!("{}", report.to_json());
    } else {
        jawtrack_report::hinge_summary(&report).iter().for_each(|l| say!("{l}"));
    }
    Ok(())
}
