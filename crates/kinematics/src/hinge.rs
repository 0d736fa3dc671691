//! The kinematic hinge axis: the line fixed in the maxilla the mandible turns about in early
//! opening, before the condyles leave their fossae and slide forward. It is fitted to tracked
//! `maxilla_from_mandible` poses as the finite screw axis their displacements from the closed
//! pose share.
//!
//! Each displacement `D = maxilla_from_mandible · maxilla_from_mandible_closed⁻¹` moves a point
//! `x` of the closed mandible (maxilla frame) to `R x + t`. A turn by θ about the axis through
//! `p` along `u` has `R = rot(u, θ)` and `t = (I − R) p`, plus any slide along `u`. So:
//! - the direction is the mean of the displacements' rotation axes, each weighted by θ²
//!   (an axis taken from a turn of θ is uncertain as 1/θ);
//! - the point solves `(I − R_i) p = t_i − (u·t_i) u` over all displacements in least squares,
//!   with the point along the axis (which no displacement fixes) taken nearest a given point:
//!   by default the mandible marker at rest, which sits on the midline, so that the point lies
//!   about midway between the condyles.
//!
//! The uncertainties come from the scatter of the fit: the point's 1σ across the axis from the
//! residuals of the least squares, the direction's from the rotation axes' spread about their
//! mean. They say how well the poses agree with one fixed axis — what a noisy track or a
//! window reaching past pure rotation spoils.

use crate::KinematicsError;
use jawtrack_pose::Pose;
use nalgebra::{Matrix3, Point3, SymmetricEigen, Unit, Vector3};

/// What [`fit`] uses of a recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HingeOptions {
    /// Displacements turned further than this from the closed pose (°) are left out: past
    /// early opening the condyles translate and no axis is fixed. About 20 mm of incisal
    /// opening with the incisor 100 mm from the axis.
    pub max_rotation_deg: f64,
    /// Displacements turned less than this (°) carry no axis above the noise and are left out.
    pub min_rotation_deg: f64,
    /// The fit needs a turn of at least this (°) in its window.
    pub least_rotation_deg: f64,
}

impl Default for HingeOptions {
    fn default() -> Self {
        HingeOptions { max_rotation_deg: 12.0, min_rotation_deg: 0.5, least_rotation_deg: 4.0 }
    }
}

/// A kinematic hinge axis in the maxilla marker's frame (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HingeAxis {
    /// The point of the axis nearest the point the fit was asked to place it by.
    pub point: Point3<f64>,
    /// Unit direction; it points so that opening is a positive (right-handed) turn about it.
    pub direction: Unit<Vector3<f64>>,
    /// 1σ of the point across the axis (mm): the larger of its two principal deviations.
    pub point_sigma_mm: f64,
    /// 1σ of the direction (°).
    pub direction_sigma_deg: f64,
    /// RMS of the least squares' residuals (mm): how far the displacements are from turns
    /// about one fixed axis.
    pub rms_mm: f64,
    /// The largest turn used (°).
    pub max_rotation_deg: f64,
    /// Displacements used.
    pub poses: usize,
}

impl HingeAxis {
    /// The axis mapped by `to_from_maxilla` (e.g. `maxilla_scan_from_maxilla_marker`): point and
    /// direction in another frame.
    pub fn transformed(&self, to_from_maxilla: &Pose) -> (Point3<f64>, Unit<Vector3<f64>>) {
        let point = to_from_maxilla.transform_point(&self.point);
        (point, Unit::new_normalize(to_from_maxilla.rotation() * self.direction.into_inner()))
    }

    /// Distance (mm) from `q` to the axis line.
    pub fn distance_to(&self, q: &Point3<f64>) -> f64 {
        (q - self.project(q)).norm()
    }

    /// The point of the axis nearest `q`: a condyle moved onto the kinematic axis.
    pub fn project(&self, q: &Point3<f64>) -> Point3<f64> {
        let u = self.direction.into_inner();
        self.point + u * (q - self.point).dot(&u)
    }
}

/// One displacement from the closed pose: a turn by `angle` (rad) about unit `axis`, as the
/// map x ↦ r x + t.
struct Move {
    angle: f64,
    axis: Vector3<f64>,
    r: Matrix3<f64>,
    t: Vector3<f64>,
}

/// Fits the hinge axis to `poses` (`maxilla_from_mandible`, any order) as displacements from
/// `closed`, the jaw's closed pose; the point is placed nearest `near` (maxilla frame; `None`:
/// the mandible marker at rest, `closed`'s origin). Refuses too few poses or too little turn in
/// the window, naming what to record.
pub fn fit(
    poses: &[Pose],
    closed: &Pose,
    near: Option<Point3<f64>>,
    options: &HingeOptions,
) -> Result<HingeAxis, KinematicsError> {
    let check = |what: &str, v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(KinematicsError::Options(format!("{what} must be a non-negative number of degrees, got {v}")))
        }
    };
    check("the largest turn", options.max_rotation_deg)?;
    check("the smallest turn", options.min_rotation_deg)?;
    check("the least turn", options.least_rotation_deg)?;
    if options.min_rotation_deg >= options.max_rotation_deg {
        return Err(KinematicsError::Options(format!(
            "the smallest turn ({}°) must be below the largest ({}°)",
            options.min_rotation_deg, options.max_rotation_deg
        )));
    }
    let closed_inverse = closed.inverse();
    // The displacements within the window of turns.
    let moves: Vec<Move> = poses
        .iter()
        .filter_map(|p| {
            let d = *p * closed_inverse;
            let (axis, angle) = d.rotation().axis_angle()?;
            let deg = angle.to_degrees();
            // Inclusive, to a rounding of the angle.
            (deg >= options.min_rotation_deg - 1e-9 && deg <= options.max_rotation_deg + 1e-9).then(|| Move {
                angle,
                axis: axis.into_inner(),
                r: d.rotation().to_rotation_matrix().into_inner(),
                t: d.translation(),
            })
        })
        .collect();
    let widest = moves.iter().map(|m| m.angle).fold(0.0, f64::max).to_degrees();
    if moves.len() < 3 || widest < options.least_rotation_deg {
        return Err(KinematicsError::TooLittleTurn {
            poses: moves.len(),
            widest_deg: widest,
            least_deg: options.least_rotation_deg,
            window_deg: options.max_rotation_deg,
        });
    }
    // The axes of an opening turn the same way; a turn's axis from nalgebra may come either
    // way, so each is signed to agree with the widest turn's.
    let reference = moves.iter().max_by(|a, b| a.angle.total_cmp(&b.angle)).map(|m| m.axis).expect("three moves");
    let signed: Vec<(f64, Vector3<f64>)> =
        moves.iter().map(|m| (m.angle, if m.axis.dot(&reference) < 0.0 { -m.axis } else { m.axis })).collect();
    let weight_sum: f64 = signed.iter().map(|(a, _)| a * a).sum();
    let mean: Vector3<f64> = signed.iter().map(|(a, u)| u * (a * a)).sum::<Vector3<f64>>() / weight_sum;
    let u = Unit::new_normalize(mean);
    // Spread of the axes about the mean, as the standard error of a weighted mean.
    let spread: f64 =
        signed.iter().map(|(a, v)| (a * a).powi(2) * v.angle(&u).powi(2)).sum::<f64>().sqrt() / weight_sum;
    // The point: normal equations of (I − R_i) p = t_i⊥, plus p·u = near·u.
    let near = near.unwrap_or_else(|| Point3::from(closed.translation()));
    let (mut ata, mut atb) = (Matrix3::zeros(), Vector3::zeros());
    for Move { r, t, .. } in &moves {
        let a = Matrix3::identity() - r;
        let across = t - u.into_inner() * t.dot(&u);
        ata += a.transpose() * a;
        atb += a.transpose() * across;
    }
    let uu = u.into_inner() * u.transpose();
    let scale = ata.trace().max(f64::MIN_POSITIVE);
    let system = ata + uu * scale;
    let rhs = atb + u.into_inner() * (near.coords.dot(&u) * scale);
    let p = system.lu().solve(&rhs).ok_or(KinematicsError::Degenerate)?;
    let mut sum_sq = 0.0;
    for Move { r, t, .. } in &moves {
        let a = Matrix3::identity() - r;
        let across = t - u.into_inner() * t.dot(&u);
        sum_sq += (a * p - across).norm_squared();
    }
    // Two equations a displacement across the axis, two unknowns across it.
    let dof = (2 * moves.len()).saturating_sub(2).max(1) as f64;
    let sigma2 = sum_sq / dof;
    // The point's covariance across the axis: σ² (AᵀA)⁻¹ on the plane normal to u.
    let eig = SymmetricEigen::new(ata);
    let across_var = eig
        .eigenvalues
        .iter()
        .zip(eig.eigenvectors.column_iter())
        .filter(|(_, v)| v.dot(&u).abs() < 0.5)
        .map(|(l, _)| sigma2 / l.max(f64::MIN_POSITIVE))
        .fold(0.0, f64::max);
    if !(p.iter().all(|c| c.is_finite()) && across_var.is_finite()) {
        return Err(KinematicsError::Degenerate);
    }
    Ok(HingeAxis {
        point: Point3::from(p),
        direction: u,
        point_sigma_mm: across_var.sqrt(),
        direction_sigma_deg: spread.to_degrees(),
        rms_mm: (sum_sq / moves.len() as f64).sqrt(),
        max_rotation_deg: widest,
        poses: moves.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// A turn by `deg` about the axis through `p` along `u`, then a slide of `slide` along it.
    fn turn(p: &Vector3<f64>, u: &Unit<Vector3<f64>>, deg: f64, slide: f64) -> Pose {
        let r = UnitQuaternion::from_axis_angle(u, deg.to_radians());
        Pose::from_parts(r, p - r * p + u.into_inner() * slide)
    }

    /// Closed pose of the mandible marker in the maxilla's frame, and the true axis.
    fn rig() -> (Pose, Vector3<f64>, Unit<Vector3<f64>>) {
        let closed = Pose::from_axis_angle(Vector3::new(0.05, -0.02, 0.01), Vector3::new(2.0, 44.0, 1.0));
        let point = Vector3::new(-3.0, -40.0, 130.0);
        let dir = Unit::new_normalize(Vector3::new(1.0, 0.03, -0.05));
        (closed, point, dir)
    }

    fn opening(closed: &Pose, p: &Vector3<f64>, u: &Unit<Vector3<f64>>, degs: &[f64]) -> Vec<Pose> {
        degs.iter().map(|&d| turn(p, u, d, 0.0) * *closed).collect()
    }

    #[test]
    fn an_exact_hinge_opening_gives_its_axis() {
        let (closed, p, u) = rig();
        let degs: Vec<f64> = (0..=20).map(|i| f64::from(i) * 0.6).collect();
        let axis = fit(&opening(&closed, &p, &u, &degs), &closed, None, &HingeOptions::default()).expect("fits");
        assert!(axis.direction.angle(&u).to_degrees() < 1e-9, "{axis:?}");
        assert!(axis.distance_to(&Point3::from(p)) < 1e-9, "{axis:?}");
        // The point is the axis's nearest to the mandible marker at rest.
        let rest = closed.translation();
        assert!((axis.point.coords - rest).dot(&u).abs() < 1e-9);
        assert!(axis.rms_mm < 1e-9 && axis.point_sigma_mm < 1e-6 && axis.direction_sigma_deg < 1e-6);
        assert_eq!(axis.poses, 20, "the closed pose itself carries no axis");
        assert!((axis.max_rotation_deg - 12.0).abs() < 1e-9);
    }

    #[test]
    fn the_direction_points_so_that_opening_turns_positively_and_a_slide_along_it_is_ignored() {
        let (closed, p, u) = rig();
        let poses: Vec<Pose> = (1..=10).map(|i| turn(&p, &u, -f64::from(i), 0.05 * f64::from(i)) * closed).collect();
        let axis = fit(&poses, &closed, None, &HingeOptions::default()).expect("fits");
        assert!((axis.direction.angle(&u).to_degrees() - 180.0).abs() < 1e-9, "opening turns about −u here");
        assert!(axis.distance_to(&Point3::from(p)) < 1e-9);
    }

    #[test]
    fn a_noisy_track_lands_near_the_axis_and_says_how_near() {
        let (closed, p, u) = rig();
        // Poses off by about what the tracker reaches (0.03 mm, 0.03°), deterministically.
        let poses: Vec<Pose> = (1..=40)
            .map(|i| {
                let k = f64::from(i);
                let wobble = Pose::from_axis_angle(
                    Vector3::new((k * 1.7).sin(), (k * 2.3).cos(), (k * 0.7).sin()) * 0.0005,
                    Vector3::new((k * 1.1).cos(), (k * 0.9).sin(), (k * 1.3).cos()) * 0.03,
                );
                wobble * turn(&p, &u, k * 0.3, 0.0) * closed
            })
            .collect();
        let axis = fit(&poses, &closed, None, &HingeOptions::default()).expect("fits");
        let (angle, off) = (axis.direction.angle(&u).to_degrees(), axis.distance_to(&Point3::from(p)));
        assert!(angle < 0.5 && off < 1.0, "{angle}° {off} mm: {axis:?}");
        assert!(axis.point_sigma_mm > 0.0 && axis.direction_sigma_deg > 0.0);
        // The stated 1σ is of the size of the errors made, not orders off either way.
        assert!(off < 5.0 * axis.point_sigma_mm && axis.point_sigma_mm < 20.0 * off.max(0.05), "{off} {axis:?}");
    }

    #[test]
    fn past_the_window_the_translating_condyle_is_left_out() {
        let (closed, p, u) = rig();
        let mut poses = opening(&closed, &p, &u, &[2.0, 4.0, 6.0, 8.0, 10.0, 12.0]);
        // Beyond 12°, the jaw also slides 5 mm forward: not a turn about the hinge axis.
        poses.extend((13..=25).map(|d| {
            Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.0, -5.0))
                * turn(&p, &u, f64::from(d), 0.0)
                * closed
        }));
        let axis = fit(&poses, &closed, None, &HingeOptions::default()).expect("fits");
        assert_eq!(axis.poses, 6);
        assert!(axis.distance_to(&Point3::from(p)) < 1e-9);
    }

    #[test]
    fn too_little_turn_or_bad_options_are_refused_with_what_to_do() {
        let (closed, p, u) = rig();
        let small = opening(&closed, &p, &u, &[0.6, 1.0, 1.5, 2.0]);
        let e = fit(&small, &closed, None, &HingeOptions::default()).expect_err("2° is too little").to_string();
        assert!(e.contains("2.0°") && e.contains("open"), "{e}");
        let e = fit(&small[..2], &closed, None, &HingeOptions { least_rotation_deg: 0.0, ..HingeOptions::default() })
            .expect_err("two poses")
            .to_string();
        assert!(e.contains("2 poses"), "{e}");
        let bad = HingeOptions { max_rotation_deg: f64::NAN, ..HingeOptions::default() };
        assert!(fit(&small, &closed, None, &bad).expect_err("NaN").to_string().contains("largest turn"));
        let bad = HingeOptions { min_rotation_deg: 20.0, ..HingeOptions::default() };
        assert!(fit(&small, &closed, None, &bad).expect_err("inverted").to_string().contains("below"));
    }

    #[test]
    fn a_condyle_moved_onto_the_axis_lands_on_it_at_its_nearest_point() {
        let (closed, p, u) = rig();
        let axis =
            fit(&opening(&closed, &p, &u, &[2.0, 5.0, 9.0]), &closed, None, &HingeOptions::default()).expect("fits");
        let off = Vector3::new(0.0, 3.0, 4.0).cross(&u).normalize() * 5.0;
        let condyle = Point3::from(p + u.into_inner() * 48.0 + off);
        let moved = axis.project(&condyle);
        assert!(axis.distance_to(&moved) < 1e-9 && ((condyle - moved).norm() - 5.0).abs() < 1e-9);
        assert!((axis.distance_to(&condyle) - 5.0).abs() < 1e-9);
    }

    #[test]
    fn the_axis_moves_with_the_frame_it_is_given_in() {
        let (closed, p, u) = rig();
        let axis =
            fit(&opening(&closed, &p, &u, &[2.0, 5.0, 9.0]), &closed, None, &HingeOptions::default()).expect("fits");
        let scan_from_maxilla = Pose::from_axis_angle(Vector3::new(0.0, 0.3, 0.0), Vector3::new(10.0, 0.0, -5.0));
        let (q, v) = axis.transformed(&scan_from_maxilla);
        assert!((q - scan_from_maxilla.transform_point(&axis.point)).norm() < 1e-12);
        assert!((v.into_inner() - scan_from_maxilla.rotation() * axis.direction.into_inner()).norm() < 1e-12);
    }
}
