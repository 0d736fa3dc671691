//! OpenSim files of a session: marker trajectories (`.trc`) of the lower incisal point and the
//! condyles, and the jaw's coordinates over time (`.mot`).
//!
//! OpenSim's ground axes are X anterior, Y up, Z to the right. They are the head frame's axes
//! turned ([`OPENSIM_FROM_HEAD`]): the head frame has X toward the patient's left, Y down and
//! Z posterior. The origin stays the head frame's (the upper incisal point).
//!
//! - `.trc`: the points' positions in mm (`Units mm`); a frame without a jaw pose has its
//!   markers blank, as OpenSim reads missing markers.
//! - `.mot`: per frame with a jaw pose, the mandible's motion from rest. Its turn is given as
//!   body-fixed X–Y–Z angles in degrees (`jaw_rx`, `jaw_ry`, `jaw_rz`; `inDegrees=yes`). Its
//!   shift is the displacement in metres of the point midway between the condyles (`jaw_tx`,
//!   `jaw_ty`, `jaw_tz`; OpenSim's translational coordinates are in metres).

use crate::mounting::{Mounting, Side};
use jawtrack_pose::Pose;
use nalgebra::{Matrix3, Point3, Rotation3, Vector3};
use std::fmt::Write as _;

/// OpenSim's axes from the head frame's: X anterior (−Z head), Y up (−Y head), Z right (−X
/// head). A proper rotation (determinant +1).
pub const OPENSIM_FROM_HEAD: [[f64; 3]; 3] = [[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]];

fn opensim_from_head() -> Rotation3<f64> {
    let r = OPENSIM_FROM_HEAD;
    Rotation3::from_matrix_unchecked(Matrix3::new(
        r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
    ))
}

/// `x` to `digits` decimals, without the minus sign of a value that rounds to zero.
fn num(x: f64, digits: usize) -> String {
    let s = format!("{x:.digits$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => s,
    }
}

/// The markers of the `.trc`, in column order.
pub const TRC_MARKERS: [&str; 3] = ["LowerIncisor", "CondyleL", "CondyleR"];

/// One frame: its time (s) and its `maxilla_from_mandible`, if it has one.
pub type Frame = (f64, Option<Pose>);

/// The head-frame motion of the mandible from `rest` to `m` (both `maxilla_from_mandible`).
fn jaw_in_head(mounting: &Mounting, rest: &Pose, m: &Pose) -> Pose {
    mounting.head_from_maxilla * *m * rest.inverse() * mounting.head_from_maxilla.inverse()
}

/// The `.trc` text of `frames` at `rate` (frames/s), the points being `mounting`'s with the
/// jaw at `rest`; `name` goes in its first line.
pub fn trc(mounting: &Mounting, rest: &Pose, frames: &[Frame], rate: f64, name: &str) -> String {
    let mut out = String::new();
    let n = frames.len();
    let _ = writeln!(out, "PathFileType\t4\t(X/Y/Z)\t{name}");
    let _ = writeln!(
        out,
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames"
    );
    let _ = writeln!(out, "{rate}\t{rate}\t{n}\t{}\tmm\t{rate}\t1\t{n}", TRC_MARKERS.len());
    // Each name heads its three columns (X, Y, Z), so two empty cells follow it, as OpenSim
    // writes the row.
    let _ = writeln!(out, "Frame#\tTime\t{}", TRC_MARKERS.map(|m| format!("{m}\t\t")).join("\t"));
    let axes: Vec<String> = (1..=TRC_MARKERS.len()).map(|k| format!("X{k}\tY{k}\tZ{k}")).collect();
    let _ = writeln!(out, "\t\t{}", axes.join("\t"));
    for (i, ((t, _), at)) in frames.iter().zip(marker_positions(mounting, rest, frames)).enumerate() {
        let _ = write!(out, "{}\t{t:.6}", i + 1);
        match at {
            Some(qs) => {
                for q in qs {
                    let _ = write!(out, "\t{}\t{}\t{}", num(q.x, 6), num(q.y, 6), num(q.z, 6));
                }
            }
            None => out.push_str(&"\t\t\t".repeat(TRC_MARKERS.len())),
        }
        out.push('\n');
    }
    out
}

/// The markers' positions ([`TRC_MARKERS`], mm, OpenSim's axes) in each frame, `None` in a
/// frame without a jaw pose: what the `.trc` and a C3D file hold.
pub fn marker_positions(mounting: &Mounting, rest: &Pose, frames: &[Frame]) -> Vec<Option<[Vector3<f64>; 3]>> {
    let c = opensim_from_head();
    let points = [mounting.lower_incisal_point, mounting.condyle(Side::Left), mounting.condyle(Side::Right)];
    frames
        .iter()
        .map(|(_, pose)| {
            let jaw = jaw_in_head(mounting, rest, pose.as_ref()?);
            Some(points.map(|p| c * jaw.transform_point(&Point3::from(p)).coords))
        })
        .collect()
}

/// The `.mot` columns after `time`.
pub const MOT_COLUMNS: [&str; 6] = ["jaw_rx", "jaw_ry", "jaw_rz", "jaw_tx", "jaw_ty", "jaw_tz"];

/// The jaw's coordinates of one pose: body-fixed X–Y–Z angles (°) and the condylar
/// midpoint's displacement (m), in OpenSim's axes (see the module doc).
pub fn jaw_coordinates(mounting: &Mounting, rest: &Pose, m: &Pose) -> [f64; 6] {
    let c = opensim_from_head();
    let jaw = jaw_in_head(mounting, rest, m);
    let turn = c * jaw.rotation().to_rotation_matrix() * c.inverse();
    let r = turn.matrix();
    // R = Rx(a) Ry(b) Rz(g): r02 = sin b, r12 = −sin a cos b, r22 = cos a cos b,
    // r01 = −cos b sin g, r00 = cos b cos g.
    let b = r[(0, 2)].clamp(-1.0, 1.0).asin();
    let a = (-r[(1, 2)]).atan2(r[(2, 2)]);
    let g = (-r[(0, 1)]).atan2(r[(0, 0)]);
    let mid = mounting.hinge_point();
    let shift: Vector3<f64> = c * (jaw.transform_point(&Point3::from(mid)).coords - mid) / 1000.0;
    [a.to_degrees(), b.to_degrees(), g.to_degrees(), shift.x, shift.y, shift.z]
}

/// The `.mot` text of the frames of `frames` that have a jaw pose (a `.mot` has no blanks).
pub fn mot(mounting: &Mounting, rest: &Pose, frames: &[Frame], name: &str) -> String {
    let rows: Vec<(f64, [f64; 6])> =
        frames.iter().filter_map(|(t, p)| Some((*t, jaw_coordinates(mounting, rest, p.as_ref()?)))).collect();
    let mut out = String::new();
    let _ = writeln!(out, "{name}\nversion=1\nnRows={}\nnColumns={}\ninDegrees=yes\nendheader", rows.len(), 7);
    let _ = writeln!(out, "time\t{}", MOT_COLUMNS.join("\t"));
    for (t, v) in rows {
        // Degrees to 1e-6, metres to 1e-9 (a micrometre's thousandth).
        let cells: Vec<String> = v.iter().enumerate().map(|(k, x)| num(*x, if k < 3 { 6 } else { 9 })).collect();
        let _ = writeln!(out, "{t:.6}\t{}", cells.join("\t"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// `maxilla_from_mandible` after moving the jaw by `jaw` (head frame) from rest.
    fn tracked(m: &Mounting, jaw: Pose) -> Pose {
        m.head_from_maxilla.inverse() * jaw * m.head_from_mandible_rest
    }

    #[test]
    fn numbers_that_round_to_zero_carry_no_minus_sign() {
        assert_eq!(num(-1e-19, 6), "0.000000");
        assert_eq!(num(-0.0000004, 6), "0.000000");
        assert_eq!(num(-0.0000006, 6), "-0.000001");
        assert_eq!(num(2.5, 3), "2.500");
    }

    #[test]
    fn the_opensim_axes_are_a_proper_rotation_of_the_head_frame() {
        let c = opensim_from_head();
        assert!((c.matrix().determinant() - 1.0).abs() < 1e-12);
        // Head −Z (anterior) is OpenSim +X; head −Y (up) is +Y; the patient's right (head −X) is +Z.
        assert!((c * Vector3::new(0.0, 0.0, -1.0) - Vector3::x()).norm() < 1e-12);
        assert!((c * Vector3::new(0.0, -1.0, 0.0) - Vector3::y()).norm() < 1e-12);
        assert!((c * Vector3::new(-1.0, 0.0, 0.0) - Vector3::z()).norm() < 1e-12);
    }

    #[test]
    fn a_hinge_opening_is_a_turn_about_opensim_z_and_a_protrusion_a_shift_along_x() {
        let m = Mounting::default();
        let rest = m.maxilla_from_mandible_rest();
        // Opening: a positive turn about head +X (chin down and back) is about OpenSim −Z.
        let h = m.hinge_point();
        let r = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.2);
        let open = tracked(&m, Pose::from_parts(r, h - r * h));
        let v = jaw_coordinates(&m, &rest, &open);
        assert!((v[2] + 0.2f64.to_degrees()).abs() < 1e-9 && v[0].abs() < 1e-9 && v[1].abs() < 1e-9, "{v:?}");
        assert!(v[3..].iter().all(|x| x.abs() < 1e-12), "the condyles stay: {v:?}");
        // A 3 mm protrusion: +0.003 m along OpenSim X.
        let forward = tracked(&m, Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.0, -3.0)));
        let v = jaw_coordinates(&m, &rest, &forward);
        assert!((v[3] - 0.003).abs() < 1e-12 && v[4].abs() < 1e-12 && v[5].abs() < 1e-12, "{v:?}");
    }

    #[test]
    fn the_files_have_opensim_s_headers_and_one_row_per_frame() {
        let m = Mounting::default();
        let rest = m.maxilla_from_mandible_rest();
        let frames = [(0.0, Some(rest)), (0.1, None), (0.2, Some(rest))];
        let t = trc(&m, &rest, &frames, 10.0, "s.trc");
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines.len(), 5 + 3);
        assert!(lines[0].starts_with("PathFileType\t4") && lines[2].starts_with("10\t10\t3\t3\tmm"));
        assert!(lines[3].contains("LowerIncisor") && lines[4].contains("X3\tY3\tZ3"));
        // Each marker's name stands over its X column.
        let (names, axes): (Vec<&str>, Vec<&str>) = (lines[3].split('\t').collect(), lines[4].split('\t').collect());
        for (k, marker) in TRC_MARKERS.iter().enumerate() {
            let at = names.iter().position(|c| c == marker).expect("the marker's name");
            assert_eq!(axes[at], format!("X{}", k + 1), "{marker} over its X column");
        }
        // At rest the incisor sits where the mounting puts it, in OpenSim axes.
        let p = m.lower_incisal_point;
        let row: Vec<f64> = lines[5].split('\t').skip(2).take(3).map(|v| v.parse().expect("a number")).collect();
        assert!((row[0] + p.z).abs() < 1e-12 && (row[1] + p.y).abs() < 1e-12 && (row[2] + p.x).abs() < 1e-12);
        assert_eq!(lines[6].split('\t').filter(|c| c.is_empty()).count(), 9, "the lost frame's markers are blank");
        let mo = mot(&m, &rest, &frames, "s.mot");
        assert!(mo.contains("nRows=2\n") && mo.contains("inDegrees=yes\nendheader\ntime\tjaw_rx"), "{mo}");
        assert_eq!(mo.lines().count(), 6 + 1 + 2);
    }
}
