//! `jawtrack articulator`: the articulator values of a recording's border movements
//! (`jawtrack_kinematics::articulator`). Each movement is given as a window of the recording: a
//! protrusion, and a laterotrusion toward each side. The output is printed, or given as one JSON
//! object.

use crate::export::{SessionArg, load, rest_of};
use crate::numbers::{clean_json, fixed};
use crate::points::{Anatomy, PointsArg, anatomy, registration};
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_kinematics::articulator::name;
use jawtrack_kinematics::{ArticulatorOptions, ArticulatorValues, CoMi, Displacement, Movements, Side, Window, co_mi};
use jawtrack_pose::Pose;
use jawtrack_recording::Recording;
use jawtrack_tracker::registration::mean_pose;
use serde_json::{Value, json};
use std::path::PathBuf;

/// Parses a window, `FROM:TO` in seconds of the frames' `t`.
pub(crate) fn parse_window(s: &str) -> Result<Window, String> {
    let (a, b) = s.split_once(':').ok_or_else(|| format!("expected FROM:TO in seconds, got '{s}'"))?;
    let num = |v: &str| v.trim().parse::<f64>().map_err(|e| format!("'{v}' in '{s}': {e}"));
    let (from, to) = (num(a)?, num(b)?);
    if !(from.is_finite() && to.is_finite() && from < to) {
        return Err(format!("'{s}': FROM must be before TO"));
    }
    Ok(Window { from, to })
}

/// Where each movement was made in a recording, FROM:TO in seconds of the frames' `t`: the
/// flags `articulator` and `report` share.
#[derive(Args, Clone, Copy, Debug)]
pub(crate) struct MovementArgs {
    /// The protrusion's window, FROM:TO (s): the condylar inclination per side and the
    /// protrusive incisal guidance.
    #[arg(long, value_name = "FROM:TO", value_parser = parse_window)]
    pub(crate) protrusion: Option<Window>,
    /// The laterotrusion toward the patient's left (s): the right condyle's Bennett angle and
    /// side shift, the lateral guidance toward the left.
    #[arg(long, value_name = "FROM:TO", value_parser = parse_window)]
    pub(crate) left: Option<Window>,
    /// The laterotrusion toward the patient's right (s): the left condyle's Bennett angle and
    /// side shift, the lateral guidance toward the right.
    #[arg(long, value_name = "FROM:TO", value_parser = parse_window)]
    pub(crate) right: Option<Window>,
    /// The jaw held in centric occlusion (s): guided back into centric relation and closed to
    /// the first tooth contact. With it, the CO–MI slide into the bite is measured.
    #[arg(long, value_name = "FROM:TO", value_parser = parse_window)]
    pub(crate) co: Option<Window>,
    /// The jaw held in maximal intercuspation (s), for --co; default: the closed jaw (--rest-frame,
    /// else the bite accepted while recording, else the first frame with a jaw pose).
    #[arg(long, value_name = "FROM:TO", value_parser = parse_window, requires = "co")]
    pub(crate) mi: Option<Window>,
}

/// The poses of each movement given.
pub(crate) struct MovementPoses {
    /// The protrusion, the laterotrusions toward the left and the right.
    pub(crate) border: [Option<Vec<Pose>>; 3],
    /// Centric occlusion and maximal intercuspation as held positions: each the mean pose of
    /// its window (`None` for MI without --mi: the closed jaw).
    pub(crate) co: Option<Pose>,
    pub(crate) mi: Option<Pose>,
}

impl MovementArgs {
    /// Whether a border movement is given.
    pub(crate) fn any_border(&self) -> bool {
        self.protrusion.is_some() || self.left.is_some() || self.right.is_some()
    }

    /// The poses of each window given in `rec` (named `name`), refusing a window without one.
    pub(crate) fn poses(&self, rec: &Recording, name: &str) -> Result<MovementPoses> {
        let windows = [
            ("--protrusion", self.protrusion),
            ("--left", self.left),
            ("--right", self.right),
            ("--co", self.co),
            ("--mi", self.mi),
        ];
        let mut poses: Vec<Option<Vec<Pose>>> = Vec::new();
        for (flag, w) in windows {
            let p = w.map(|w| poses_in(rec, w));
            if let (Some(w), Some(p)) = (w, &p)
                && p.is_empty()
            {
                bail!("{flag} {}:{}: no frame of {name} in that window has a jaw pose", w.from, w.to);
            }
            poses.push(p);
        }
        let held = |k: usize| poses[k].as_deref().and_then(mean_pose);
        let (co, mi) = (held(3), held(4));
        let mut it = poses.into_iter();
        Ok(MovementPoses { border: [it.next().flatten(), it.next().flatten(), it.next().flatten()], co, mi })
    }
}

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
    #[arg(long)]
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

/// Warns when `rec` was tracked with the nominal marker, whose tags sit where the ideal solid
/// puts them and not where the print did: on rendered border movements with a print's usual
/// error (0.2 mm RMS per tag), `what` (docs/kinematics.md).
pub(crate) fn warn_if_nominal(rec: &Recording, what: &str) {
    let marker = rec.header.as_ref().and_then(|h| h.marker.as_ref());
    let nominal = marker
        .and_then(|m| jawtrack_marker::Marker::from_json(&m.to_string()).ok())
        .is_some_and(|m| m.measured_tags().is_empty());
    if nominal {
        eprintln!(
            "warning: this recording was tracked with the nominal marker: against a print's tag errors, {what}; \
             calibrate the marker (`jawtrack calibrate-marker`) and track again with it"
        );
    }
}

/// The poses in `w`.
fn poses_in(rec: &Recording, w: Window) -> Vec<Pose> {
    rec.frames.iter().filter(|f| w.holds(f.t)).filter_map(|f| f.maxilla_from_mandible).collect()
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
    let moved = a.moves.poses(&rec, &name_of.to_string())?;
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
    let mut report = to_json(&v, a, &options, &anatomy, rest.to_json());
    if let (Some(s), Value::Object(o)) = (slide, &mut report) {
        o.insert("co_mi".into(), co_mi_json(&s));
    }
    clean_json(&mut report);
    if a.json {
        say!("{report}");
    } else {
        if a.moves.any_border() {
            print_summary(&v, &options, &anatomy, &rest.describe());
        }
        if let Some(s) = slide {
            let mi = if a.moves.mi.is_some() { "the --mi window".to_string() } else { rest.describe() };
            print_co_mi(&s, &mi);
        }
    }
    Ok(())
}

/// The CO–MI slide as JSON: each point's components and length (mm).
pub(crate) fn co_mi_json(s: &CoMi) -> Value {
    let d = |d: &Displacement| json!({"forward_mm": d.protrusive, "down_mm": d.opening, "toward_left_mm": d.lateral, "length_mm": d.norm()});
    json!({
        "from": "centric occlusion",
        "to": "maximal intercuspation",
        "lower_incisal_point": d(&s.incisor),
        "left_condyle": d(&s.condyles[0]),
        "right_condyle": d(&s.condyles[1]),
    })
}

fn print_co_mi(s: &CoMi, mi: &str) {
    let mm = |x: f64| fixed(x, 2);
    say!("CO–MI slide, from centric occlusion into maximal intercuspation ({mi}), mm:");
    say!("                          forward     down   toward left   length");
    for (name, d) in
        [("lower incisal point", s.incisor), ("left condyle", s.condyles[0]), ("right condyle", s.condyles[1])]
    {
        say!("{name:<22} {:>10} {:>8} {:>13} {:>8}", mm(d.protrusive), mm(d.opening), mm(d.lateral), mm(d.norm()));
    }
}

fn to_json(
    v: &ArticulatorValues,
    a: &ArticulatorArgs,
    o: &ArticulatorOptions,
    anatomy: &Anatomy,
    rest: Value,
) -> Value {
    let side = |k: usize| {
        json!({
            "condylar_inclination_deg": v.condylar_inclination_deg[k],
            "bennett_deg": v.bennett_deg[k],
            "immediate_side_shift_mm": v.side_shift_mm[k],
        })
    };
    let window = |w: Option<Window>| w.map(|w| [w.from, w.to]);
    json!({
        "version": 1,
        "units": {"angles": "deg", "lengths": "mm"},
        "reference_plane": anatomy.reference_plane,
        "landmarks": anatomy.landmarks,
        "read_over_mm": o.over_mm,
        "left_condyle": side(0),
        "right_condyle": side(1),
        "protrusive_incisal_guidance_deg": v.protrusive_guidance_deg,
        "lateral_incisal_guidance_deg": {"toward_left": v.lateral_guidance_deg[0], "toward_right": v.lateral_guidance_deg[1]},
        "windows_s": {
            "protrusion": window(a.moves.protrusion), "left": window(a.moves.left), "right": window(a.moves.right),
            "co": window(a.moves.co), "mi": window(a.moves.mi),
        },
        "rest": rest,
        "recording": a.recording.to_string_lossy(),
    })
}

fn print_summary(v: &ArticulatorValues, o: &ArticulatorOptions, anatomy: &Anatomy, rest: &str) {
    let deg = |x: Option<f64>| x.map_or("—".to_string(), |x| format!("{}°", fixed(x, 1)));
    let mm = |x: Option<f64>| x.map_or("—".to_string(), |x| format!("{} mm", fixed(x, 2)));
    say!("read over the first {} mm of each path, from {rest}", fixed(o.over_mm, 1));
    say!("                         left condyle   right condyle");
    say!(
        "condylar inclination     {:>12}   {:>13}",
        deg(v.condylar_inclination_deg[0]),
        deg(v.condylar_inclination_deg[1])
    );
    say!("Bennett angle            {:>12}   {:>13}", deg(v.bennett_deg[0]), deg(v.bennett_deg[1]));
    say!("immediate side shift     {:>12}   {:>13}", mm(v.side_shift_mm[0]), mm(v.side_shift_mm[1]));
    say!("protrusive incisal guidance {}", deg(v.protrusive_guidance_deg));
    for (k, side) in [Side::Left, Side::Right].iter().enumerate() {
        say!("lateral incisal guidance toward the {} {}", name(*side), deg(v.lateral_guidance_deg[k]));
    }
    say!("angles are to {}; the landmarks are {}", anatomy.reference_plane, anatomy.landmarks);
}
