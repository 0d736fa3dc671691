//! The export formats: a recording turned into a time-ordered CSV, a clean JSON Lines file, the
//! scans' transforms for dental CAD (CSV or JSON), or OpenSim's `.trc` and `.mot`. A new format
//! is a variant of [`Format`] and an arm of [`export`].

use crate::anatomy::anatomy;
use crate::incisor::ChosenIncisor;
use crate::rest::Rest;
use crate::scan_pose::PoseSource;
use crate::{SessionError, scan_pose::PosedFrame};
use jawtrack_kinematics::{Incisor, Mounting};
use jawtrack_pose::Pose;
use jawtrack_recording::{Recording, RecordingHeader};
use jawtrack_registration::Registration;
use std::io::Write;
use std::path::Path;

/// An export format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// One row per frame: sequence, time, tags, RMS, the mandible in the maxilla (translation
    /// and quaternion), the incisor and its opening, lateral and protrusive displacement.
    Csv,
    /// The recording cleaned: a header line, then every readable frame in sequence order.
    Jsonl,
    /// Per frame with the scans' pose, the lower scan in the upper scan's frame as a 4×4
    /// row-major matrix (`frame,t_s,m00,…,m33`).
    TransformsCsv,
    /// The same as one JSON object.
    TransformsJson,
    /// OpenSim: the lower incisal point's and both condyles' trajectories (mm).
    Trc,
    /// OpenSim: the jaw's coordinates over time from the rest position.
    Mot,
    /// C3D (biomechanics tools): the `.trc`'s three points, on the recording's frame clock.
    C3d,
}

/// What an export reads besides the recording.
#[derive(Debug, Default)]
pub struct Inputs<'a> {
    /// Where displacements are measured from.
    pub rest: Option<Rest>,
    /// The registration the scans' transforms are taken through (else the recorded ones).
    pub registration: Option<Registration>,
    /// The anatomical points file (needs `registration`): the head frame and the lower incisal
    /// point of the CSV's incisor columns and the OpenSim formats.
    pub points: Option<&'a Path>,
    /// The incisal point in the mandible marker's frame (mm), for the CSV, in place of the
    /// points file's or the standard mounting's.
    pub incisor: Option<[f64; 3]>,
    /// The recording's name, for messages.
    pub recording: String,
    /// The name OpenSim files carry (the output file's name).
    pub name: String,
}

/// What an export wrote.
#[derive(Debug)]
pub struct Exported {
    /// In words: "12 frames as OpenSim .trc".
    pub summary: String,
    /// What the reader should check (from the anatomy).
    pub warnings: Vec<String>,
}

/// `v` as a plain decimal to 9 places (a nanometre, a nanosecond; far below what is measured),
/// trailing zeros dropped, and a value that rounds to zero without a sign: users read a sign as
/// a direction, and `1.8e-16` in full is 0.00000000000000018041….
pub fn full(v: f64) -> String {
    let text = format!("{v:.9}");
    let text = if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.') } else { &text };
    if text == "-0" { "0".to_owned() } else { text.to_owned() }
}

/// Writes `rec` as `format` to `out`, and says what it wrote. Nothing is written when the
/// inputs are refused.
///
/// # Examples
///
/// ```
/// use jawtrack_session::export::{Format, Inputs, export};
/// let rec = jawtrack_recording::read_recording(r#"{"frame":0,"t":0}"#.as_bytes()).unwrap();
/// let mut out = Vec::new();
/// export(Format::Csv, &rec, Inputs::default(), &mut out).unwrap();
/// assert!(String::from_utf8(out).unwrap().starts_with("frame,seq,t_s,"));
/// ```
pub fn export(format: Format, rec: &Recording, inputs: Inputs, out: &mut dyn Write) -> Result<Exported, SessionError> {
    let written = |e: &dyn std::fmt::Display| SessionError::Write { path: inputs.name.clone(), reason: e.to_string() };
    let no_pose = || SessionError::NoJawPose { path: inputs.recording.clone(), what: "export" };
    let mut warnings = Vec::new();
    let summary = match format {
        Format::Trc | Format::Mot | Format::C3d => {
            let Some(rest) = inputs.rest.map(Rest::pose) else {
                return Err(no_pose());
            };
            let a = anatomy(inputs.points, inputs.registration.as_ref(), &rest)?;
            warnings.extend(a.warnings);
            let frames: Vec<(f64, Option<Pose>)> = rec.frames.iter().map(|f| (f.t, f.maxilla_from_mandible)).collect();
            let rate = frame_rate(&frames);
            let (bytes, what) = match format {
                Format::Trc => {
                    let text = jawtrack_kinematics::opensim::trc(&a.mounting, &rest, &frames, rate, &inputs.name);
                    (text.into_bytes(), "OpenSim .trc".to_owned())
                }
                Format::Mot => {
                    let text = jawtrack_kinematics::opensim::mot(&a.mounting, &rest, &frames, &inputs.name);
                    (text.into_bytes(), "OpenSim .mot".to_owned())
                }
                _ => {
                    let (bytes, slots) = c3d(&a.mounting, &rest, &frames, rate)?;
                    (bytes, format!("C3D at {rate} frames/s ({slots} frames on its clock)"))
                }
            };
            out.write_all(&bytes).map_err(|e| written(&e))?;
            format!("{} frames as {what}", rec.frames.len())
        }
        Format::TransformsCsv | Format::TransformsJson => {
            let has_registration = inputs.registration.is_some();
            let transforms = PoseSource::required(rec, inputs.registration)?.posed(rec);
            if transforms.is_empty() {
                debug_assert!(has_registration, "recorded scan poses exist, so some frame has one");
                return Err(no_pose());
            }
            if format == Format::TransformsCsv {
                transforms_csv(&transforms, out).map_err(|e| written(&e))?;
            } else {
                transforms_json(&transforms, out).map_err(|e| written(&e))?;
            }
            format!("{} transforms of {} frames", transforms.len(), rec.frames.len())
        }
        Format::Jsonl => {
            let header = rec.header.clone().unwrap_or_else(|| RecordingHeader::new("jawtrack export"));
            writeln!(out, "{}", header.to_line()).map_err(|e| written(&e))?;
            for f in &rec.frames {
                writeln!(out, "{}", f.to_line()).map_err(|e| written(&e))?;
            }
            format!("{} frames", rec.frames.len())
        }
        Format::Csv => {
            let rest = inputs.rest.map(Rest::pose);
            if rest.is_none() && inputs.points.is_some() {
                return Err(no_pose());
            }
            // Without a jaw pose there is no rest, and then no points file (refused above).
            let a = anatomy(inputs.points, inputs.registration.as_ref(), &rest.unwrap_or_else(Pose::identity))?;
            warnings.extend(a.warnings.iter().cloned());
            let incisor = ChosenIncisor::of(&a, inputs.incisor)?.incisor;
            csv(rec, &incisor, rest, out).map_err(|e| written(&e))?;
            format!("{} frames", rec.frames.len())
        }
    };
    // Dropping a BufWriter swallows its last write's error: a full disk must not pass.
    out.flush().map_err(|e| written(&e))?;
    Ok(Exported { summary, warnings })
}

/// The C3D file of `frames` at `rate`, and how many frames it holds. C3D frames are evenly
/// spaced, so each recorded frame goes to the slot of its time; slots no frame reached (frames
/// lost on the link) and frames without a jaw pose hold the points as missing.
fn c3d(
    mounting: &Mounting,
    rest: &Pose,
    frames: &[(f64, Option<Pose>)],
    rate: f64,
) -> Result<(Vec<u8>, usize), SessionError> {
    let positions = jawtrack_kinematics::opensim::marker_positions(mounting, rest, frames);
    let t0 = frames.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
    let slot = |t: f64| ((t - t0) * rate).round();
    let last = frames.iter().map(|f| slot(f.0)).fold(0.0, f64::max);
    if last.is_nan() || last >= jawtrack_c3d::MAX_FRAMES as f64 {
        return Err(jawtrack_c3d::C3dError::TooManyFrames { frames: last as usize + 1 }.into());
    }
    let mut tracks: Vec<jawtrack_c3d::PointTrack> = jawtrack_kinematics::opensim::TRC_MARKERS
        .iter()
        .zip(["lower incisal point", "left condyle", "right condyle"])
        .map(|(label, what)| jawtrack_c3d::PointTrack {
            label: (*label).into(),
            description: format!("{what}; mm, X anterior, Y up, Z right"),
            positions: vec![None; last as usize + 1],
        })
        .collect();
    for ((t, _), at) in frames.iter().zip(positions) {
        let k = slot(*t) as usize;
        for (track, q) in tracks.iter_mut().zip(at.iter().flatten()) {
            track.positions[k] = Some([q.x, q.y, q.z]);
        }
    }
    Ok((jawtrack_c3d::write(&tracks, rate)?, last as usize + 1))
}

/// The frames' rate (frames/s): the inverse of the median interval, 30 when unknown.
fn frame_rate(frames: &[(f64, Option<Pose>)]) -> f64 {
    let mut dt: Vec<f64> = frames.windows(2).map(|w| w[1].0 - w[0].0).filter(|d| *d > 0.0).collect();
    dt.sort_by(f64::total_cmp);
    dt.get(dt.len() / 2).map_or(30.0, |d| (1.0 / d * 1000.0).round() / 1000.0)
}

fn transforms_csv(transforms: &[PosedFrame], out: &mut dyn Write) -> Result<(), csv::Error> {
    let mut w = csv::Writer::from_writer(out);
    let mut head = vec!["frame".to_string(), "t_s".to_string()];
    head.extend((0..16).map(|k| format!("m{}{}", k / 4, k % 4)));
    w.write_record(&head)?;
    for (frame, t, m) in transforms {
        let mut row = vec![frame.to_string(), full(*t)];
        row.extend(m.to_row_major().iter().map(|v| full(*v)));
        w.write_record(&row)?;
    }
    w.flush()?;
    Ok(())
}

fn transforms_json(transforms: &[PosedFrame], out: &mut dyn Write) -> std::io::Result<()> {
    let frames: Vec<serde_json::Value> = transforms
        .iter()
        .map(|(frame, t, m)| serde_json::json!({"frame": frame, "t_s": t, "matrix": m.to_row_major()}))
        .collect();
    let doc = serde_json::json!({
        "version": 1,
        "units": "mm",
        "transform": "maxilla_scan_from_mandible_scan",
        "description": "the lower scan placed in the upper scan's frame at each frame: p_upper = M · [p_lower, 1]",
        "layout": "row-major 4x4",
        "frames": frames,
    });
    writeln!(out, "{doc}")
}

/// The CSV's columns.
const CSV_COLUMNS: [&str; 22] = [
    "frame",
    "seq",
    "t_s",
    "received_unix_s",
    "maxilla_tags",
    "mandible_tags",
    "maxilla_rms_px",
    "mandible_rms_px",
    "flags",
    "tx_mm",
    "ty_mm",
    "tz_mm",
    "qw",
    "qx",
    "qy",
    "qz",
    "incisor_x_mm",
    "incisor_y_mm",
    "incisor_z_mm",
    "opening_mm",
    "lateral_mm",
    "protrusive_mm",
];

fn csv(rec: &Recording, incisor: &Incisor, rest: Option<Pose>, out: &mut dyn Write) -> Result<(), csv::Error> {
    let mut w = csv::Writer::from_writer(out);
    w.write_record(CSV_COLUMNS)?;
    let opt = |v: Option<f64>| v.map(full).unwrap_or_default();
    for f in &rec.frames {
        let mut row = vec![
            f.frame.to_string(),
            f.seq.map(|s| s.to_string()).unwrap_or_default(),
            full(f.t),
            opt(f.received_unix_s),
            f.maxilla.as_ref().map(|b| b.tags.len().to_string()).unwrap_or_default(),
            f.mandible.as_ref().map(|b| b.tags.len().to_string()).unwrap_or_default(),
            opt(f.maxilla.as_ref().map(|b| b.rms_px)),
            opt(f.mandible.as_ref().map(|b| b.rms_px)),
            f.flags.join(";"),
        ];
        match &f.maxilla_from_mandible {
            Some(m) => {
                let (t, q) = (m.translation(), m.rotation());
                let p = incisor.in_head(m);
                row.extend([t.x, t.y, t.z, q.w, q.i, q.j, q.k, p.x, p.y, p.z].map(full));
                let d = rest.map(|r| incisor.displacement(m, &r));
                row.extend([d.map(|d| d.opening), d.map(|d| d.lateral), d.map(|d| d.protrusive)].map(opt));
            }
            None => row.extend(std::iter::repeat_n(String::new(), CSV_COLUMNS.len() - 9)),
        }
        w.write_record(&row)?;
    }
    w.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::full;

    #[test]
    fn full_numbers_drop_trailing_zeros_and_zero_s_sign() {
        assert_eq!([full(-0.0), full(-0.001), full(2.5), full(1.8e-16)], ["0", "-0.001", "2.5", "0"]);
    }
}
