//! Rigid transforms (rotation + translation in mm).

use crate::GeometryError;
use nalgebra::{Isometry3, Matrix3, Matrix4, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// A rigid transform: `to_from` maps points of frame `from` into frame `to` (mm).
///
/// Serialised as a 4×4 row-major matrix (16 numbers), the form every JawTrack file uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose(Isometry3<f64>);

/// A pose typed by a user (a command-line flag): six numbers `rx,ry,rz,tx,ty,tz` (rotation
/// vector in degrees, translation in mm) or 16, a row-major 4×4 matrix as in JawTrack's files.
///
/// # Examples
///
/// ```
/// use jawtrack_pose::Pose;
/// let p: Pose = "0,0,90,1,-2,3".parse().unwrap();
/// assert!((p.rotation().angle().to_degrees() - 90.0).abs() < 1e-9);
/// assert!("1,2,3".parse::<Pose>().is_err());
/// ```
impl std::str::FromStr for Pose {
    type Err = GeometryError;

    fn from_str(s: &str) -> Result<Self, GeometryError> {
        let bad = GeometryError::BadText;
        let v: Vec<f64> = s
            .split(',')
            .map(|c| c.trim().parse::<f64>().map_err(|e| bad(format!("'{}': {e}", c.trim()))))
            .collect::<Result<_, _>>()?;
        if !v.iter().all(|c| c.is_finite()) {
            return Err(bad("the numbers must be finite".into()));
        }
        match v.len() {
            6 => Ok(Pose::from_axis_angle(
                Vector3::new(v[0], v[1], v[2]).map(f64::to_radians),
                Vector3::new(v[3], v[4], v[5]),
            )),
            16 => Pose::from_row_major(&std::array::from_fn(|i| v[i]), "the matrix"),
            n => Err(bad(format!(
                "expected 6 numbers (rx,ry,rz in degrees, tx,ty,tz in mm) or 16 (a 4×4 row-major matrix), got {n}"
            ))),
        }
    }
}

/// Largest accepted deviation of a deserialised rotation from orthonormality. Files written
/// with 17 significant digits are far inside it; a hand-typed 4-decimal matrix still passes.
const ROTATION_TOLERANCE: f64 = 1e-4;

impl Pose {
    /// The identity transform.
    pub fn identity() -> Self {
        Pose(Isometry3::identity())
    }

    /// From a rotation and a translation (mm).
    pub fn from_parts(rotation: UnitQuaternion<f64>, translation: Vector3<f64>) -> Self {
        Pose(Isometry3::from_parts(Translation3::from(translation), rotation))
    }

    /// From a rotation vector (axis × angle, rad) and a translation (mm).
    pub fn from_axis_angle(rotvec: Vector3<f64>, translation: Vector3<f64>) -> Self {
        Self::from_parts(UnitQuaternion::from_scaled_axis(rotvec), translation)
    }

    /// Wraps a nalgebra isometry.
    pub fn from_isometry(iso: Isometry3<f64>) -> Self {
        Pose(iso)
    }

    /// The underlying nalgebra isometry.
    pub fn isometry(&self) -> &Isometry3<f64> {
        &self.0
    }

    /// The rotation part.
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        self.0.rotation
    }

    /// The rotation part as a 3×3 matrix.
    pub fn rotation_matrix(&self) -> Matrix3<f64> {
        *self.0.rotation.to_rotation_matrix().matrix()
    }

    /// The translation part (mm): where the `from` frame's origin lies in the `to` frame.
    pub fn translation(&self) -> Vector3<f64> {
        self.0.translation.vector
    }

    /// Maps a point of the `from` frame into the `to` frame.
    pub fn transform_point(&self, p: &Point3<f64>) -> Point3<f64> {
        self.0.transform_point(p)
    }

    /// Rotates a direction of the `from` frame into the `to` frame.
    pub fn transform_vector(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.0.transform_vector(v)
    }

    /// The inverse: `from_to` given `to_from`.
    pub fn inverse(&self) -> Self {
        Pose(self.0.inverse())
    }

    /// Composition: `a_from_b.compose(&b_from_c)` (also `a_from_b * b_from_c`) is `a_from_c`.
    pub fn compose(&self, rhs: &Pose) -> Self {
        Pose(self.0 * rhs.0)
    }

    /// Rotation angle between two poses (rad) and distance between their translations (mm).
    pub fn distance_to(&self, other: &Pose) -> (f64, f64) {
        let angle = self.0.rotation.angle_to(&other.0.rotation);
        let dist = (self.translation() - other.translation()).norm();
        (angle, dist)
    }

    /// The 4×4 homogeneous matrix.
    pub fn to_matrix(&self) -> Matrix4<f64> {
        self.0.to_homogeneous()
    }

    /// The 4×4 matrix as 16 numbers, row-major.
    pub fn to_row_major(&self) -> [f64; 16] {
        let m = self.to_matrix();
        std::array::from_fn(|i| m[(i / 4, i % 4)])
    }

    /// From 16 row-major numbers, checking that they form a rigid transform.
    /// `what` names the matrix in errors. The rotation is re-orthonormalised.
    pub fn from_row_major(m: &[f64; 16], what: &str) -> Result<Self, GeometryError> {
        if m.iter().any(|v| !v.is_finite()) {
            return Err(GeometryError::NotFinite { what: what.to_owned() });
        }
        if m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || (m[15] - 1.0).abs() > 1e-12 {
            return Err(GeometryError::NotAffine { what: what.to_owned() });
        }
        let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
        let error = (r.transpose() * r - Matrix3::identity()).abs().max().max((r.determinant() - 1.0).abs());
        if error > ROTATION_TOLERANCE {
            return Err(GeometryError::NotRotation { what: what.to_owned(), error });
        }
        let rot = Rotation3::from_matrix(&r);
        Ok(Self::from_parts(UnitQuaternion::from_rotation_matrix(&rot), Vector3::new(m[3], m[7], m[11])))
    }

    /// Whether every number of the transform is finite.
    pub fn is_finite(&self) -> bool {
        self.to_row_major().iter().all(|v| v.is_finite())
    }
}

impl std::ops::Mul for Pose {
    type Output = Pose;
    fn mul(self, rhs: Pose) -> Pose {
        self.compose(&rhs)
    }
}

impl Serialize for Pose {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.to_row_major().serialize(s)
    }
}

impl<'de> Deserialize<'de> for Pose {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let m = <[f64; 16]>::deserialize(d)?;
        Pose::from_row_major(&m, "pose").map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Pose {
        Pose::from_axis_angle(Vector3::new(0.3, -0.2, 0.9), Vector3::new(10.0, -4.0, 120.0))
    }

    #[test]
    fn text_takes_six_or_sixteen_numbers() {
        let p: Pose = "0,0,90,1,-2,3".parse().expect("six");
        assert!((p.rotation().angle().to_degrees() - 90.0).abs() < 1e-9);
        assert_eq!(p.translation(), Vector3::new(1.0, -2.0, 3.0));
        let q: Pose = p.to_row_major().map(|v| v.to_string()).join(",").parse().expect("sixteen");
        assert!(p.distance_to(&q).0 < 1e-12 && p.distance_to(&q).1 < 1e-12);
        for (bad, word) in [("1,2,3", "got 3"), ("1,2,3,4,5,x", "'x'"), ("0,0,0,0,0,NaN", "finite")] {
            let err = bad.parse::<Pose>().expect_err(bad).to_string();
            assert!(err.contains(word), "{err}");
        }
        assert!("2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1".parse::<Pose>().is_err(), "not a rotation");
    }

    #[test]
    fn row_major_round_trip_and_layout() {
        let p = sample();
        let m = p.to_row_major();
        assert_eq!(m[3], 10.0);
        assert_eq!(m[7], -4.0);
        assert_eq!(m[11], 120.0);
        assert_eq!(&m[12..], &[0.0, 0.0, 0.0, 1.0]);
        let q = Pose::from_row_major(&m, "p").expect("valid");
        let (a, d) = p.distance_to(&q);
        assert!(a < 1e-12 && d < 1e-12);
    }

    #[test]
    fn inverse_and_composition() {
        let p = sample();
        let x = Point3::new(1.0, 2.0, 3.0);
        let back = p.inverse().transform_point(&p.transform_point(&x));
        assert!((back - x).norm() < 1e-12);
        let id = p * p.inverse();
        let (a, d) = id.distance_to(&Pose::identity());
        assert!(a < 1e-12 && d < 1e-12);
    }

    #[test]
    fn rejects_non_rigid_matrices() {
        let mut m = sample().to_row_major();
        m[0] *= 1.1;
        assert!(matches!(Pose::from_row_major(&m, "x"), Err(GeometryError::NotRotation { .. })));
        let mut m = sample().to_row_major();
        m[5] = f64::NAN;
        assert!(matches!(Pose::from_row_major(&m, "x"), Err(GeometryError::NotFinite { .. })));
        let mut m = sample().to_row_major();
        m[12] = 1.0;
        assert!(matches!(Pose::from_row_major(&m, "x"), Err(GeometryError::NotAffine { .. })));
        // A mirror is orthonormal but not a rotation.
        let m = [-1.0, 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.];
        assert!(matches!(Pose::from_row_major(&m, "x"), Err(GeometryError::NotRotation { .. })));
    }

    #[test]
    fn serde_as_sixteen_numbers() {
        let p = sample();
        let s = serde_json::to_string(&p).expect("serialise");
        let q: Pose = serde_json::from_str(&s).expect("deserialise");
        assert!(p.distance_to(&q).0 < 1e-12);
        assert!(serde_json::from_str::<Pose>("[1,0,0,0]").is_err());
    }
}
