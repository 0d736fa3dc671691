//! The JSON objects the measuring commands print and write (`jawtrack metrics`, `hinge-axis`,
//! `articulator`), each with the recording, the rest position and the settings it was measured
//! with, and no signed zero ([`clean_json`]); and which frames a hinge-axis fit takes.

use crate::SessionError;
use crate::json::clean_json;
use crate::movements::MovementWindows;
use crate::rest::{Rest, rest_of};
use jawtrack_kinematics::{
    Anatomy, ArticulatorOptions, ArticulatorValues, Border, CoMi, Displacement, HingeAxis, Incisor, Metrics, PlaneView,
    Sample, Side, Window,
};
use jawtrack_pose::Pose;
use jawtrack_recording::Recording;
use nalgebra::{Point3, Unit, Vector3};
use serde_json::{Value, json};
use std::path::Path;

/// `jawtrack metrics`'s object (`metrics.json`): the metrics of `path`, measured from `rest`
/// with `incisor` (`standard`: the standard mounting's), each plane's border, and the counts
/// of `rec`'s frames.
pub fn metrics_json(
    m: &Metrics,
    path: &[Sample],
    rec: &Recording,
    recording: &Path,
    rest: Rest,
    incisor: &Incisor,
    standard: bool,
) -> Value {
    let p = incisor.point_in_mandible_marker();
    let mut report = m.to_json();
    if let Value::Object(o) = &mut report {
        o.insert("recording".into(), json!(recording.to_string_lossy()));
        o.insert("frames_total".into(), json!(rec.frames.len()));
        o.insert("frames_skipped_no_pose".into(), json!(rec.frames.len() - path.len()));
        o.insert("rest_frame".into(), json!(if let Rest::Frame(n, _) = rest { Some(n) } else { None }));
        o.insert("rest".into(), rest.to_json());
        o.insert("incisor_in_mandible_marker_mm".into(), json!([p.x, p.y, p.z]));
        o.insert("incisor_standard".into(), json!(standard));
        for view in PlaneView::ALL {
            o.insert(format!("border_{}", view.name()), Border::of(view, path, m).to_json());
        }
    }
    clean_json(&mut report);
    report
}

/// The frames of a hinge-axis fit: those of `rec` between `from` and `to` (s; open-ended when
/// not given) with a jaw pose, and the closed jaw they turn from (`rest_frame`, else the bite
/// accepted while recording, else the window's first frame).
pub fn hinge_window(
    rec: &Recording,
    name: &str,
    (from, to): (Option<f64>, Option<f64>),
    rest_frame: Option<u64>,
) -> Result<(Vec<(u64, Pose)>, Rest), SessionError> {
    let inside = |t: f64| from.is_none_or(|f| t >= f) && to.is_none_or(|e| t <= e);
    let window: Vec<(u64, Pose)> =
        rec.frames.iter().filter(|f| inside(f.t)).filter_map(|f| Some((f.frame, f.maxilla_from_mandible?))).collect();
    if window.is_empty() {
        let words = match (from, to) {
            (None, None) => String::new(),
            (Some(f), None) => format!("from {f} s "),
            (None, Some(t)) => format!("up to {t} s "),
            (Some(f), Some(t)) => format!("between {f} s and {t} s "),
        };
        return Err(SessionError::EmptyWindow(format!(
            "{name}: no frame {words}has a jaw pose (both markers tracked)"
        )));
    }
    let rest = match (rest_frame, rec.rest(None)) {
        (None, None) => Rest::Frame(window[0].0, window[0].1),
        (n, _) => rest_of(rec, n)?.ok_or_else(|| SessionError::EmptyWindow("no rest pose".into()))?,
    };
    Ok((window, rest))
}

/// The condyles (maxilla marker frame) that a hinge axis moves onto itself, from `anatomy`,
/// and whose they are (`points`: a points file gave the anatomy).
pub fn hinge_condyles(anatomy: &Anatomy, points: bool) -> ([Point3<f64>; 2], &'static str) {
    let m = &anatomy.mounting;
    let at = |side| m.head_from_maxilla.inverse().transform_point(&Point3::from(m.condyle(side)));
    let whose = match (points, anatomy.condyles_given) {
        (false, _) => "the standard mounting's",
        (true, true) => "the points file's",
        (true, false) => "the points file's Bonwill triangle's",
    };
    ([at(Side::Left), at(Side::Right)], whose)
}

/// What `jawtrack hinge-axis --json` prints.
#[derive(Debug, Clone, Copy)]
pub struct HingeReport<'a> {
    /// The axis, in the maxilla marker's frame.
    pub axis: &'a HingeAxis,
    /// Its point and direction in the upper scan's frame, given a registration.
    pub scan: Option<(Point3<f64>, Unit<Vector3<f64>>)>,
    /// The closed jaw.
    pub rest: Rest,
    /// Frames with a jaw pose in the window.
    pub frames: usize,
    /// The window (s), as given.
    pub window: [Option<f64>; 2],
    /// The recording.
    pub recording: &'a Path,
    /// The condyles moved onto the axis, and whose they are ([`hinge_condyles`], or `"given"`).
    pub condyles: ([Point3<f64>; 2], &'a str),
}

fn xyz(v: &Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

impl HingeReport<'_> {
    /// The report as one JSON object.
    pub fn to_json(&self) -> Value {
        let axis = self.axis;
        let mut o = json!({
            "version": 1,
            "units": "mm",
            "frame": "maxilla marker",
            "point": xyz(&axis.point.coords),
            "direction": xyz(&axis.direction),
            "uncertainty": {
                "point_mm": axis.point_sigma_mm,
                "direction_deg": axis.direction_sigma_deg,
                "rms_mm": axis.rms_mm,
            },
            "poses_used": axis.poses,
            "frames_in_window": self.frames,
            "max_rotation_deg": axis.max_rotation_deg,
            "window_s": self.window,
            "rest": self.rest.to_json(),
            "recording": self.recording.to_string_lossy(),
        });
        if let (Some((p, d)), Value::Object(m)) = (self.scan, &mut o) {
            m.insert("point_scan".into(), xyz(&p.coords));
            m.insert("direction_scan".into(), xyz(&d));
        }
        if let Value::Object(m) = &mut o {
            let moved =
                |c: &Point3<f64>| json!({"point": xyz(&axis.project(c).coords), "moved_mm": axis.distance_to(c)});
            let ([l, r], whose) = self.condyles;
            m.insert(
                "condyles_on_axis".into(),
                json!({"left": moved(&l), "right": moved(&r), "given": whose == "given" || whose == "the points file's", "source": whose}),
            );
        }
        clean_json(&mut o);
        o
    }
}

/// The CO–MI slide as JSON: each point's components and length (mm).
pub fn co_mi_json(s: &CoMi) -> Value {
    let d = |d: &Displacement| json!({"forward_mm": d.protrusive, "down_mm": d.opening, "toward_left_mm": d.lateral, "length_mm": d.norm()});
    json!({
        "from": "centric occlusion",
        "to": "maximal intercuspation",
        "lower_incisal_point": d(&s.incisor),
        "left_condyle": d(&s.condyles[0]),
        "right_condyle": d(&s.condyles[1]),
    })
}

/// `jawtrack articulator --json`'s object: the values `v` read with `o` on `anatomy`, the
/// windows, the rest position and the recording, and the CO–MI `slide` when measured.
pub fn articulator_json(
    v: &ArticulatorValues,
    o: &ArticulatorOptions,
    anatomy: &Anatomy,
    windows: MovementWindows,
    rest: Rest,
    recording: &Path,
    slide: Option<&CoMi>,
) -> Value {
    let side = |k: usize| {
        json!({
            "condylar_inclination_deg": v.condylar_inclination_deg[k],
            "bennett_deg": v.bennett_deg[k],
            "immediate_side_shift_mm": v.side_shift_mm[k],
        })
    };
    let window = |w: Option<Window>| w.map(|w| [w.from, w.to]);
    let w = windows;
    let mut report = json!({
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
            "protrusion": window(w.protrusion), "left": window(w.left), "right": window(w.right),
            "co": window(w.co), "mi": window(w.mi),
        },
        "rest": rest.to_json(),
        "recording": recording.to_string_lossy(),
    });
    if let (Some(s), Value::Object(o)) = (slide, &mut report) {
        o.insert("co_mi".into(), co_mi_json(s));
    }
    clean_json(&mut report);
    report
}

/// The `point` and unit `direction` of `jawtrack hinge-axis --json`'s output in `path` (the
/// viewer draws it), refusing a file without them, naming `--hinge-axis`.
pub fn read_hinge_axis(path: &Path) -> Result<([f64; 3], [f64; 3]), SessionError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| SessionError::Io { context: format!("reading --hinge-axis {}", path.display()), source })?;
    let v: Value = serde_json::from_str(&text).map_err(|source| SessionError::Json {
        context: format!("--hinge-axis {}: not the JSON of `jawtrack hinge-axis --json`", path.display()),
        source,
    })?;
    let xyz = |key: &str| -> Result<[f64; 3], SessionError> {
        let a: Vec<f64> = v[key].as_array().map(|a| a.iter().filter_map(Value::as_f64).collect()).unwrap_or_default();
        match a[..] {
            [x, y, z] if a.iter().all(|c| c.is_finite()) => Ok([x, y, z]),
            _ => Err(SessionError::Setting(format!(
                "--hinge-axis {}: no \"{key}\" of three numbers (the output of `jawtrack hinge-axis --json`)",
                path.display()
            ))),
        }
    };
    let (point, d) = (xyz("point")?, xyz("direction")?);
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(n > 0.5 && n < 1.5) {
        return Err(SessionError::Setting(format!(
            "--hinge-axis {}: its direction is not a unit vector (length {n})",
            path.display()
        )));
    }
    Ok((point, d.map(|c| c / n)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_recording::FrameRecord;

    fn frame(n: u64, t: f64, posed: bool) -> FrameRecord {
        let mut f = FrameRecord::unreadable(n, None, t);
        f.maxilla_from_mandible = posed.then(Pose::identity);
        f
    }

    #[test]
    fn a_hinge_window_keeps_the_posed_frames_inside_and_says_which_when_none() {
        let rec = Recording {
            frames: vec![frame(0, 0.0, true), frame(1, 1.0, false), frame(2, 2.0, true), frame(3, 3.0, true)],
            ..Recording::default()
        };
        let (window, rest) = hinge_window(&rec, "r.jsonl", (Some(0.5), None), None).expect("frames");
        assert_eq!(window.iter().map(|w| w.0).collect::<Vec<_>>(), [2, 3]);
        assert!(matches!(rest, Rest::Frame(2, _)));
        let err = hinge_window(&rec, "r.jsonl", (Some(0.5), Some(1.5)), None).expect_err("none");
        assert_eq!(err.to_string(), "r.jsonl: no frame between 0.5 s and 1.5 s has a jaw pose (both markers tracked)");
    }

    #[test]
    fn a_hinge_axis_file_gives_its_point_and_unit_direction() {
        let dir = tempfile::tempdir().expect("temporary folder");
        let (good, bad) = (dir.path().join("axis.json"), dir.path().join("bad.json"));
        std::fs::write(&good, r#"{"point":[1,2,3],"direction":[0,0,1.1]}"#).expect("written");
        std::fs::write(&bad, r#"{"point":[1,2],"direction":[0,0,1]}"#).expect("written");
        let (p, d) = read_hinge_axis(&good).expect("read");
        assert_eq!(p, [1.0, 2.0, 3.0]);
        assert!((d[2] - 1.0).abs() < 1e-12);
        assert!(read_hinge_axis(&bad).expect_err("two numbers").to_string().contains(r#"no "point" of three"#));
    }

    #[test]
    fn the_standard_condyles_are_the_mountings() {
        let (_, whose) = hinge_condyles(&Anatomy::standard(), false);
        assert_eq!(whose, "the standard mounting's");
    }
}
