//! `jawtrack articulator`: the articulator values of a recording's border movements
//! (`jawtrack_kinematics::articulator`). Each movement is given as a window of the recording: a
//! protrusion, and a laterotrusion toward each side. The output is printed, or given as one JSON
//! object.

use crate::flags::{MovementArgs, PointsArg, SessionArg, anatomy, load, registration, warn_if_nominal};
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_kinematics::{ArticulatorOptions, ArticulatorValues, Movements, co_mi};
use jawtrack_report::{articulator_summary, co_mi_summary};
use jawtrack_session::measures::articulator_json;
use jawtrack_session::rest_of;
use std::path::PathBuf;

/// Arguments of `jawtrack articulator`.
#[derive(Args)]
pub(crate) struct ArticulatorArgs {
    /// The recording (JSON lines) holding the border movements, each made slowly from the
    /// closed jaw with the teeth in light contact.
    recording: PathBuf,
    #[command(flatten)]
    session: SessionArg,
    #[command(flatten)]
    moves: MovementArgs,
    /// The frame (its `frame` number) of the closed jaw every movement is measured from;
    /// default: the bite accepted while recording, else the first frame with a jaw pose.
    #[arg(long, value_name = "FRAME", value_parser = crate::numbers::parse_frame, allow_hyphen_values = true)]
    rest_frame: Option<u64>,
    /// Read each value over this much of its path's travel (mm).
    #[arg(long, default_value_t = ArticulatorOptions::default().over_mm, value_name = "MM")]
    over_mm: f64,
    /// The registration file (`jawtrack register`), for --points.
    #[arg(long, value_name = "FILE")]
    registration: Option<PathBuf>,
    #[command(flatten)]
    points: PointsArg,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
}

/// Runs `jawtrack articulator`.
pub(crate) fn run(a: &ArticulatorArgs) -> Result<()> {
    let name_of = a.recording.display();
    if !a.moves.any_border() && a.moves.co.is_none() {
        bail!(
            "give the window of at least one movement: --protrusion FROM:TO, --left FROM:TO or --right FROM:TO (s), \
             or of centric occlusion: --co FROM:TO"
        );
    }
    if !(a.over_mm.is_finite() && a.over_mm > 1.0) {
        bail!("--over-mm must be a number of mm above 1, got {}", a.over_mm);
    }
    let reg = registration(a.registration.as_deref())?;
    let rec = load(&a.recording, a.session)?;
    warn_if_nominal(&rec, "the condylar inclinations moved 7–22° and the side shifts 1–1.5 mm");
    let rest = rest_of(&rec, a.rest_frame)?
        .with_context(|| format!("{name_of}: no frame has a jaw pose (both markers tracked)"))?;
    let moved = a.moves.windows().poses(&rec, &name_of.to_string())?;
    let movements = Movements {
        protrusion: moved.border[0].as_deref(),
        toward_left: moved.border[1].as_deref(),
        toward_right: moved.border[2].as_deref(),
    };
    let options = ArticulatorOptions { over_mm: a.over_mm, ..ArticulatorOptions::default() };
    let anatomy = anatomy(a.points.points.as_deref(), reg.as_ref(), &rest.pose())?;
    let v = ArticulatorValues::measure(&anatomy.mounting, &rest.pose(), &movements, &options)
        .with_context(|| format!("{name_of}"))?;
    let slide = moved.co.map(|co| co_mi(&anatomy.mounting, &co, &moved.mi.unwrap_or_else(|| rest.pose())));
    let report = articulator_json(&v, &options, &anatomy, a.moves.windows(), rest, &a.recording, slide.as_ref());
    if a.json {
        say!("{report}");
    } else {
        if a.moves.any_border() {
            articulator_summary(&v, &options, &anatomy, &rest.describe()).iter().for_each(|l| say!("{l}"));
        }
        if let Some(s) = slide {
            let mi = if a.moves.mi.is_some() { "the --mi window".to_string() } else { rest.describe() };
            co_mi_summary(&s, &mi).iter().for_each(|l| say!("{l}"));
        }
    }
    Ok(())
}
