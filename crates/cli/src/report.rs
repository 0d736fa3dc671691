//! `jawtrack report`: one self-contained HTML report of a session (`jawtrack_report`), and a PDF
//! of it through headless Chromium when asked.

use crate::flags::{MovementArgs, PointsArg, SessionArg, anatomy, load, registration};
use crate::output::ForceArgs;
use anyhow::{Context, Result, bail};
use clap::{ArgAction, Args};
use jawtrack_kinematics::Window;
use jawtrack_recording::Recording;
use jawtrack_registration::Registration;
use jawtrack_report::{Centric, ContactsResult, Inputs, Record, Windows};
use jawtrack_session::anatomy::upper_scan_left;
use jawtrack_session::arches::load_arch;
use jawtrack_session::contacts::read_folder;
use jawtrack_session::survey::survey;
use jawtrack_session::{PoseSource, rest_of};
use std::path::{Path, PathBuf};

/// Arguments of `jawtrack report`.
#[derive(Args)]
#[command(after_help = "Sections whose movement is not given say so on the page, naming the flag that would \
                        measure them. Windows are FROM:TO in seconds of the frames' t.")]
pub(crate) struct ReportArgs {
    /// The recording (JSON lines).
    recording: PathBuf,
    #[command(flatten)]
    session: SessionArg,
    /// The report to write (HTML).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// Also print it to this PDF, through headless Chromium (`CHROMIUM`, else `chromium`,
    /// `chromium-browser` or `google-chrome` on the PATH).
    #[arg(long, value_name = "FILE")]
    pdf: Option<PathBuf>,
    /// The registration file (`jawtrack register`): places the scans, for --points and for
    /// --maxilla/--mandible.
    #[arg(long, value_name = "FILE")]
    registration: Option<PathBuf>,
    #[command(flatten)]
    points: PointsArg,
    /// The frame (its `frame` number) of the closed jaw; default: the bite accepted while
    /// recording, else the first frame with a jaw pose.
    #[arg(long, value_name = "FRAME", value_parser = crate::numbers::parse_frame, allow_hyphen_values = true)]
    rest_frame: Option<u64>,
    /// A slow opening from the closed jaw: the hinge axis.
    #[arg(long, value_name = "FROM:TO", value_parser = Window::parse)]
    opening: Option<Window>,
    #[command(flatten)]
    moves: MovementArgs,
    /// The upper arch's scan (STL, PLY or OBJ, mm), or one file per tooth (`FDI=NN` in the
    /// names gives the tooth numbers): the report checks the occlusal contacts of
    /// --contact-frames frames through --registration, and shows their maps and per-tooth
    /// totals. Indexing real scans takes seconds.
    #[arg(long, num_args = 1.., action = ArgAction::Append, value_name = "MESH", requires = "mandible", conflicts_with = "contacts")]
    maxilla: Vec<PathBuf>,
    /// The lower arch's scan, or one file per tooth, as for --maxilla.
    #[arg(long, num_args = 1.., action = ArgAction::Append, value_name = "MESH", requires = "maxilla")]
    mandible: Vec<PathBuf>,
    /// How many frames, evenly spread over the session, --maxilla and --mandible check.
    #[arg(long, default_value_t = 120, value_name = "N")]
    contact_frames: usize,
    /// Instead of --maxilla and --mandible: the folder `jawtrack contacts` wrote for this
    /// session (every frame checked, in any mode).
    #[arg(long, value_name = "DIR")]
    contacts: Option<PathBuf>,
    /// The patient's name or file number, printed at the top of the report (one line, at most
    /// 200 characters); without it the report leaves a line to write it on.
    #[arg(long, value_name = "TEXT")]
    patient: Option<String>,
    /// Who recorded the session, printed under the patient (one line, at most 200 characters);
    /// without it, a line to write on.
    #[arg(long, value_name = "TEXT")]
    operator: Option<String>,
    /// Notes printed under the operator (at most 2000 characters; line breaks are kept);
    /// without them, lines to write on.
    #[arg(long, value_name = "TEXT")]
    notes: Option<String>,
    #[command(flatten)]
    force: ForceArgs,
}

/// What `jawtrack contacts` wrote into `dir` (`jawtrack_session::contacts::read_folder`).
/// The folder `jawtrack contacts` wrote, refused when it was made from another recording.
fn read_contacts(dir: &Path, rec: &Recording, rec_name: &str) -> Result<ContactsResult> {
    let (summary, maps) = read_folder(dir)?;
    let context = || format!("--contacts {}", dir.display());
    if let Some(w) = jawtrack_session::contacts::check_matches(&summary, rec, rec_name).with_context(context)? {
        tell!("warning: {}: {w}", context());
    }
    Ok(ContactsResult { folder: dir.display().to_string(), summary, maps })
}

/// Runs `jawtrack report`.
pub(crate) fn run(a: &ReportArgs) -> Result<()> {
    let record = Record { patient: a.patient.clone(), operator: a.operator.clone(), notes: a.notes.clone() };
    if let Err((field, why)) = record.check() {
        bail!("--{}: {why}", field.name());
    }
    let name = a.recording.display();
    a.force.check_file(&a.out)?;
    if let Some(pdf) = &a.pdf {
        a.force.check_file(pdf)?;
    }
    let reg = registration(a.registration.as_deref())?;
    let rec = load(&a.recording, a.session)?;
    let rest = rest_of(&rec, a.rest_frame)?
        .with_context(|| format!("{name}: no frame has a jaw pose (both markers tracked): nothing to report"))?;
    let moved = a.moves.windows().poses(&rec, &name.to_string())?;
    let centric = match (a.moves.co, moved.co) {
        (Some(co_window), Some(co)) => Some(Centric { co, mi: moved.mi.unwrap_or_else(|| rest.pose()), co_window }),
        _ => None,
    };
    let contacts = match &a.contacts {
        Some(dir) => Some(read_contacts(dir, &rec, &name.to_string())?),
        None if !a.maxilla.is_empty() => Some(survey_contacts(a, &rec, reg)?),
        None => None,
    };
    let anatomy_of = anatomy(a.points.points.as_deref(), reg.as_ref(), &rest.pose())?;
    let file = |p: &Option<PathBuf>| p.as_ref().map(|p| p.display().to_string());
    let inputs = Inputs {
        recording: &rec,
        recording_name: a.recording.file_name().map_or_else(|| name.to_string(), |f| f.to_string_lossy().into()),
        anatomy: anatomy_of,
        points_file: file(&a.points.points),
        registration_file: file(&a.registration),
        rest: rest.pose(),
        rest_words: rest.describe(),
        windows: Windows {
            opening: a.opening,
            protrusion: a.moves.protrusion,
            left: a.moves.left,
            right: a.moves.right,
        },
        centric,
        contacts,
        made_unix_s: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64()),
    };
    let report = jawtrack_report::render_with(&inputs, &record);
    a.force.write_file(&a.out, report.html.as_bytes())?;
    for w in &report.warnings {
        tell!("warning: {w}");
    }
    say!("wrote {} ({} sections, {} kB)", a.out.display(), report.sections.len(), report.html.len() / 1024);
    if let Some(pdf) = &a.pdf {
        jawtrack_report::print_pdf(&a.out, pdf)?;
        say!("wrote {}", pdf.display());
    }
    Ok(())
}

/// Checks the occlusal contacts of up to `--contact-frames` frames spread over the session
/// (`jawtrack_session::survey`).
fn survey_contacts(a: &ReportArgs, rec: &Recording, reg: Option<Registration>) -> Result<ContactsResult> {
    let posed = PoseSource::of(rec, reg).map(|s| s.posed(rec)).unwrap_or_default();
    let upper = load_arch("maxilla", &a.maxilla)?.parts;
    let lower = load_arch("mandible", &a.mandible)?.parts;
    let upper_left = upper_scan_left(a.points.points.as_deref())?;
    tell!("indexing both arches for the contacts (a few seconds per 100k triangles)…");
    let bar = crate::progress_bar("contacts", a.contact_frames.min(posed.len()));
    let found = survey(upper, lower, &posed, a.contact_frames, upper_left, &mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    for w in &found.warnings {
        tell!("warning: {w}");
    }
    Ok(ContactsResult { folder: found.checked, summary: found.summary, maps: found.maps })
}
