//! Articulator values from border movements: the sagittal condylar inclination per side, the
//! Bennett angle and immediate side shift per side, and the protrusive and lateral incisal
//! guidance. Each is read off the path of an anatomical point carried by the tracked poses.
//!
//! Frames: the head frame of the [`Mounting`] (X the patient's left, Y down, Z posterior). The
//! reference plane is its horizontal (X–Z) plane, and forward is −Z. A point's path is its
//! displacement from where it is at rest.
//!
//! Definitions, over the first [`ArticulatorOptions::over_mm`] of travel (5 mm, as condylography
//! reports; Ahlers et al. 2015):
//! - **Sagittal condylar inclination** (per side, from a protrusion): the angle below the
//!   reference plane of the condyle's path projected on the sagittal plane. The path is taken
//!   as the line through rest that fits it best (total least squares).
//! - **Bennett angle and immediate side shift** (per side, from the laterotrusion that makes
//!   that side's condyle the non-working one, i.e. toward the other side). The non-working
//!   condyle's path is projected on the horizontal plane, and its medial displacement is fitted
//!   against its forward travel: `medial = shift + tan(bennett) · forward`. The slope is the
//!   progressive Bennett angle. The intercept is the medial shift made before the condyle
//!   advanced: the immediate side shift. Points with less than [`ArticulatorOptions::from_mm`]
//!   of forward travel are left out, since the shift itself is made there.
//! - **Protrusive incisal guidance**: the angle below the reference plane of the lower incisal
//!   point's protrusive path in the sagittal plane.
//! - **Lateral incisal guidance** (per working side): the angle below the horizontal of the
//!   lower incisal point's path in the frontal plane, toward the working side.

use crate::KinematicsError;
use crate::mounting::{Mounting, Side};
use jawtrack_pose::Pose;
use nalgebra::{Matrix2, Point3, SymmetricEigen, Vector2, Vector3};

/// Over how much of a movement the values are read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArticulatorOptions {
    /// The values are read from the path's first this many mm.
    pub over_mm: f64,
    /// Points with less travel than this (mm) are left out of the fits. In the Bennett fit,
    /// this is forward travel.
    pub from_mm: f64,
}

impl Default for ArticulatorOptions {
    fn default() -> Self {
        ArticulatorOptions { over_mm: 5.0, from_mm: 0.5 }
    }
}

/// The unit vector toward `side` in the head frame.
pub fn toward(side: Side) -> Vector3<f64> {
    match side {
        Side::Left => Vector3::x(),
        Side::Right => -Vector3::x(),
    }
}

/// The displacements from rest (head frame, mm) of `point` (head frame, with the jaw at
/// `rest`) as the mandible moves through `poses`. Both `rest` and `poses` are
/// `maxilla_from_mandible`, and the head is placed by `mounting`'s maxilla marker.
pub fn point_path(mounting: &Mounting, rest: &Pose, poses: &[Pose], point: &Vector3<f64>) -> Vec<Vector3<f64>> {
    let head_from_maxilla = mounting.head_from_maxilla;
    let at_rest = head_from_maxilla.inverse().transform_point(&Point3::from(*point));
    let rest_inverse = rest.inverse();
    poses
        .iter()
        .map(|m| head_from_maxilla.transform_point(&(*m * rest_inverse).transform_point(&at_rest)).coords - point)
        .collect()
}

/// The angle (°) below the horizontal axis of the line through the origin that best fits
/// `points` (2-D: horizontal, down). Only points at distances within [`from`, `over`] count.
/// The line is oriented along positive horizontal travel.
fn inclination(
    points: impl Iterator<Item = Vector2<f64>>,
    from: f64,
    over: f64,
    what: &str,
) -> Result<f64, KinematicsError> {
    let used: Vec<Vector2<f64>> = points.filter(|p| (from..=over).contains(&p.norm())).collect();
    if used.len() < 3 {
        return Err(KinematicsError::TooLittlePath {
            what: what.into(),
            points: used.len(),
            from_mm: from,
            over_mm: over,
        });
    }
    let scatter: Matrix2<f64> = used.iter().map(|p| p * p.transpose()).sum();
    let eig = SymmetricEigen::new(scatter);
    let k = if eig.eigenvalues[0] >= eig.eigenvalues[1] { 0 } else { 1 };
    let mut dir: Vector2<f64> = eig.eigenvectors.column(k).into();
    if dir.x < 0.0 {
        dir = -dir;
    }
    Ok(dir.y.atan2(dir.x).to_degrees())
}

/// The sagittal inclination (°) below the reference plane of a path going forward (a condyle's
/// or the incisor's in protrusion).
pub fn sagittal_inclination(path: &[Vector3<f64>], o: &ArticulatorOptions, what: &str) -> Result<f64, KinematicsError> {
    inclination(path.iter().map(|d| Vector2::new(-d.z, d.y)), o.from_mm, o.over_mm, what)
}

/// The lateral guidance (°) below the horizontal in the frontal plane of the incisor's path
/// toward `working`.
pub fn frontal_inclination(
    path: &[Vector3<f64>],
    working: Side,
    o: &ArticulatorOptions,
    what: &str,
) -> Result<f64, KinematicsError> {
    let w = toward(working);
    inclination(path.iter().map(|d| Vector2::new(d.dot(&w), d.y)), o.from_mm, o.over_mm, what)
}

/// The Bennett angle (°) and immediate side shift (mm) of a non-working condyle's path,
/// `working` being the side the jaw moves toward. See the module doc.
pub fn bennett(path: &[Vector3<f64>], working: Side, o: &ArticulatorOptions) -> Result<(f64, f64), KinematicsError> {
    let w = toward(working);
    let used: Vec<(f64, f64)> = path
        .iter()
        .map(|d| (-d.z, d.dot(&w)))
        .filter(|(forward, _)| (o.from_mm..=o.over_mm).contains(forward))
        .collect();
    if used.len() < 3 {
        return Err(KinematicsError::TooLittlePath {
            what: "the non-working condyle's forward travel".into(),
            points: used.len(),
            from_mm: o.from_mm,
            over_mm: o.over_mm,
        });
    }
    let n = used.len() as f64;
    let (mf, mm) = (used.iter().map(|u| u.0).sum::<f64>() / n, used.iter().map(|u| u.1).sum::<f64>() / n);
    let sff: f64 = used.iter().map(|u| (u.0 - mf).powi(2)).sum();
    let sfm: f64 = used.iter().map(|u| (u.0 - mf) * (u.1 - mm)).sum();
    if sff <= f64::EPSILON {
        return Err(KinematicsError::Degenerate);
    }
    let slope = sfm / sff;
    Ok((slope.atan().to_degrees(), mm - slope * mf))
}

/// The articulator values of a session: protrusion and laterotrusions as the poses of each
/// movement (`maxilla_from_mandible`, from rest). A value whose movement is missing is `None`;
/// a movement too short to read is an error naming it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArticulatorValues {
    /// Sagittal condylar inclination (°), left and right condyle.
    pub condylar_inclination_deg: [Option<f64>; 2],
    /// Bennett angle (°) of the left and right condyle (each from the laterotrusion toward the
    /// other side).
    pub bennett_deg: [Option<f64>; 2],
    /// Immediate side shift (mm) of the left and right condyle.
    pub side_shift_mm: [Option<f64>; 2],
    /// Protrusive incisal guidance (°).
    pub protrusive_guidance_deg: Option<f64>,
    /// Lateral incisal guidance (°) toward the left and toward the right.
    pub lateral_guidance_deg: [Option<f64>; 2],
}

/// The movements a session's articulator values are read from.
#[derive(Debug, Clone, Copy, Default)]
pub struct Movements<'a> {
    /// A protrusion.
    pub protrusion: Option<&'a [Pose]>,
    /// A laterotrusion toward the patient's left (working side left).
    pub toward_left: Option<&'a [Pose]>,
    /// A laterotrusion toward the patient's right.
    pub toward_right: Option<&'a [Pose]>,
}

impl ArticulatorValues {
    /// The values of `movements`, each measured from `rest`, the condyles and incisal point
    /// being `mounting`'s.
    pub fn measure(
        mounting: &Mounting,
        rest: &Pose,
        movements: &Movements<'_>,
        o: &ArticulatorOptions,
    ) -> Result<Self, KinematicsError> {
        let path = |poses: &[Pose], p: &Vector3<f64>| point_path(mounting, rest, poses, p);
        let mut v = ArticulatorValues {
            condylar_inclination_deg: [None; 2],
            bennett_deg: [None; 2],
            side_shift_mm: [None; 2],
            protrusive_guidance_deg: None,
            lateral_guidance_deg: [None; 2],
        };
        let sides = [Side::Left, Side::Right];
        if let Some(poses) = movements.protrusion {
            for (i, side) in sides.iter().enumerate() {
                let what = format!("the {} condyle's protrusive path", name(*side));
                v.condylar_inclination_deg[i] =
                    Some(sagittal_inclination(&path(poses, &mounting.condyle(*side)), o, &what)?);
            }
            let incisor = path(poses, &mounting.lower_incisal_point);
            v.protrusive_guidance_deg = Some(sagittal_inclination(&incisor, o, "the incisor's protrusive path")?);
        }
        for (working, poses) in [(Side::Left, movements.toward_left), (Side::Right, movements.toward_right)] {
            let Some(poses) = poses else { continue };
            let non_working = if working == Side::Left { Side::Right } else { Side::Left };
            let k = if non_working == Side::Left { 0 } else { 1 };
            let (angle, shift) = bennett(&path(poses, &mounting.condyle(non_working)), working, o)?;
            v.bennett_deg[k] = Some(angle);
            v.side_shift_mm[k] = Some(shift);
            let what = format!("the incisor's path toward the {}", name(working));
            let incisor = path(poses, &mounting.lower_incisal_point);
            v.lateral_guidance_deg[if working == Side::Left { 0 } else { 1 }] =
                Some(frontal_inclination(&incisor, working, o, &what)?);
        }
        Ok(v)
    }
}

/// "left" or "right".
pub fn name(side: Side) -> &'static str {
    match side {
        Side::Left => "left",
        Side::Right => "right",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight path of `n` points out to `length` mm along `dir`, after `offset`.
    fn line(offset: Vector3<f64>, dir: Vector3<f64>, length: f64, n: usize) -> Vec<Vector3<f64>> {
        (0..=n).map(|i| offset + dir.normalize() * (length * i as f64 / n as f64)).collect()
    }

    #[test]
    fn a_straight_forward_path_reads_its_angle_below_the_reference_plane() {
        let o = ArticulatorOptions::default();
        for deg in [0.0f64, 25.0, 40.0, 60.0] {
            let r = deg.to_radians();
            let path = line(Vector3::zeros(), Vector3::new(0.3, r.sin(), -r.cos()), 8.0, 40);
            let got = sagittal_inclination(&path, &o, "path").expect("reads");
            assert!((got - deg).abs() < 1e-9, "{deg} -> {got}");
        }
        // Going up (negative): an eminence cannot, but a wrong reference plane can.
        let up = line(Vector3::zeros(), Vector3::new(0.0, -0.2, -1.0), 8.0, 40);
        assert!(sagittal_inclination(&up, &o, "path").expect("reads") < 0.0);
    }

    #[test]
    fn the_bennett_fit_separates_the_immediate_shift_from_the_progressive_angle() {
        let o = ArticulatorOptions::default();
        for working in [Side::Left, Side::Right] {
            let w = toward(working);
            let (shift, deg) = (0.8, 9.0f64);
            // First the shift, straight toward the working side, then the progressive path.
            let mut path = line(Vector3::zeros(), w, shift, 8);
            path.extend(line(w * shift, w * deg.to_radians().tan() + Vector3::new(0.0, 0.8, -1.0), 8.0, 40));
            let (b, s) = bennett(&path, working, &o).expect("reads");
            assert!((b - deg).abs() < 1e-9 && (s - shift).abs() < 1e-9, "{b}° {s} mm");
        }
    }

    #[test]
    fn the_lateral_guidance_is_read_toward_the_working_side() {
        let o = ArticulatorOptions::default();
        let r = 30f64.to_radians();
        let left = line(Vector3::zeros(), Vector3::new(r.cos(), r.sin(), -0.1), 6.0, 30);
        assert!((frontal_inclination(&left, Side::Left, &o, "path").expect("reads") - 30.0).abs() < 1e-6);
        let right = line(Vector3::zeros(), Vector3::new(-r.cos(), r.sin(), -0.1), 6.0, 30);
        assert!((frontal_inclination(&right, Side::Right, &o, "path").expect("reads") - 30.0).abs() < 1e-6);
    }

    #[test]
    fn a_point_path_is_the_displacement_the_poses_give_it() {
        let m = Mounting::default();
        let rest = m.maxilla_from_mandible_rest();
        // The mandible slid 2 mm forward (head −Z): every point moves by the same.
        let forward = Pose::from_parts(Default::default(), nalgebra::Vector3::new(0.0, 0.0, -2.0));
        let moved = m.head_from_maxilla.inverse() * forward * m.head_from_maxilla * rest;
        let path = point_path(&m, &rest, &[rest, moved], &m.condyle(Side::Left));
        assert!(path[0].norm() < 1e-12 && (path[1] - Vector3::new(0.0, 0.0, -2.0)).norm() < 1e-12, "{path:?}");
    }

    #[test]
    fn a_movement_too_short_is_refused_naming_it() {
        let o = ArticulatorOptions::default();
        let short = line(Vector3::zeros(), Vector3::new(0.0, 0.5, -1.0), 0.6, 10);
        let e = sagittal_inclination(&short, &o, "the left condyle's protrusive path").expect_err("0.6 mm");
        assert!(e.to_string().contains("the left condyle's protrusive path") && e.to_string().contains("5 mm long"));
        let e = bennett(&short, Side::Left, &o).expect_err("too short").to_string();
        assert!(e.contains("non-working condyle"), "{e}");
    }
}
