//! The camera model: pinhole with two-term radial (Brown) distortion.
//!
//! A camera-frame point (X, Y, Z), Z > 0, has normalised coordinates x = X/Z, y = Y/Z; with
//! r² = x² + y² and d = 1 + k1 r² + k2 r⁴ it lands at pixel (fx·x·d + cx, fy·y·d + cy), in the
//! convention where (0, 0) is the centre of the top-left pixel.

use crate::GeometryError;
use nalgebra::{Point2, Point3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Camera intrinsics in pixels, with radial distortion coefficients.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraIntrinsics {
    /// Focal length along x (px).
    pub fx: f64,
    /// Focal length along y (px).
    pub fy: f64,
    /// Principal point x (px, top-left pixel centre = 0).
    pub cx: f64,
    /// Principal point y (px).
    pub cy: f64,
    /// First radial distortion coefficient.
    #[serde(default)]
    pub k1: f64,
    /// Second radial distortion coefficient.
    #[serde(default)]
    pub k2: f64,
}

impl CameraIntrinsics {
    /// A distortion-free camera.
    pub fn pinhole(fx: f64, fy: f64, cx: f64, cy: f64) -> Self {
        CameraIntrinsics { fx, fy, cx, cy, k1: 0.0, k2: 0.0 }
    }

    /// Checks that the numbers can describe a camera.
    pub fn validate(&self) -> Result<(), GeometryError> {
        let all =
            [("fx", self.fx), ("fy", self.fy), ("cx", self.cx), ("cy", self.cy), ("k1", self.k1), ("k2", self.k2)];
        for (name, v) in all {
            if !v.is_finite() {
                return Err(GeometryError::BadIntrinsics(format!("{name} is not finite")));
            }
        }
        if self.fx <= 0.0 || self.fy <= 0.0 {
            return Err(GeometryError::BadIntrinsics(format!(
                "focal lengths must be positive (fx={}, fy={})",
                self.fx, self.fy
            )));
        }
        Ok(())
    }

    /// The distortion factor d(r²) = 1 + k1 r² + k2 r⁴.
    fn radial(&self, r2: f64) -> f64 {
        1.0 + r2 * (self.k1 + r2 * self.k2)
    }

    /// Applies distortion to normalised coordinates.
    pub fn distort(&self, n: Vector2<f64>) -> Vector2<f64> {
        n * self.radial(n.norm_squared())
    }

    /// Removes distortion from distorted normalised coordinates (Newton on the radius).
    /// Returns `None` where the distortion model is not invertible (beyond its fold).
    pub fn undistort(&self, nd: Vector2<f64>) -> Option<Vector2<f64>> {
        let rd = nd.norm();
        if rd == 0.0 || (self.k1 == 0.0 && self.k2 == 0.0) {
            return Some(nd);
        }
        // Solve f(r) = r (1 + k1 r² + k2 r⁴) - rd = 0.
        let mut r = rd;
        for _ in 0..50 {
            let r2 = r * r;
            let f = r * self.radial(r2) - rd;
            let df = 1.0 + 3.0 * self.k1 * r2 + 5.0 * self.k2 * r2 * r2;
            if df <= 0.0 {
                return None;
            }
            let step = f / df;
            r -= step;
            if step.abs() < 1e-15 * (1.0 + r.abs()) {
                break;
            }
        }
        let ok = r.is_finite() && r >= 0.0 && (r * self.radial(r * r) - rd).abs() < 1e-12 * (1.0 + rd);
        ok.then(|| nd * (r / rd))
    }

    /// Projects a camera-frame point (mm) to pixels; `None` if it is not in front of the camera.
    pub fn project(&self, p: &Point3<f64>) -> Option<Point2<f64>> {
        if p.z <= 0.0 {
            return None;
        }
        let d = self.distort(Vector2::new(p.x / p.z, p.y / p.z));
        Some(Point2::new(self.fx * d.x + self.cx, self.fy * d.y + self.cy))
    }

    /// The distorted normalised coordinates of a pixel.
    pub fn pixel_to_distorted(&self, px: &Point2<f64>) -> Vector2<f64> {
        Vector2::new((px.x - self.cx) / self.fx, (px.y - self.cy) / self.fy)
    }

    /// The viewing ray of a pixel as a camera-frame direction with z = 1.
    pub fn unproject(&self, px: &Point2<f64>) -> Option<Vector3<f64>> {
        let n = self.undistort(self.pixel_to_distorted(px))?;
        Some(Vector3::new(n.x, n.y, 1.0))
    }

    /// The same camera for an image resampled by `factor` (2.0 = twice the pixels per side),
    /// keeping the pixel-centre convention: c' = (c + 0.5)·factor − 0.5.
    pub fn scaled(&self, factor: f64) -> Self {
        CameraIntrinsics {
            fx: self.fx * factor,
            fy: self.fy * factor,
            cx: (self.cx + 0.5) * factor - 0.5,
            cy: (self.cy + 0.5) * factor - 0.5,
            k1: self.k1,
            k2: self.k2,
        }
    }
}

impl std::str::FromStr for CameraIntrinsics {
    type Err = GeometryError;

    /// Parses `fx,fy,cx,cy` or `fx,fy,cx,cy,k1,k2`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let vals: Vec<f64> = s
            .split(',')
            .map(|t| {
                t.trim()
                    .parse::<f64>()
                    .map_err(|_| GeometryError::BadIntrinsics(format!("'{}' is not a number", t.trim())))
            })
            .collect::<Result<_, _>>()?;
        let cam = match vals[..] {
            [fx, fy, cx, cy] => CameraIntrinsics::pinhole(fx, fy, cx, cy),
            [fx, fy, cx, cy, k1, k2] => CameraIntrinsics { fx, fy, cx, cy, k1, k2 },
            _ => {
                return Err(GeometryError::BadIntrinsics(format!(
                    "expected fx,fy,cx,cy or fx,fy,cx,cy,k1,k2 (4 or 6 numbers), got {}",
                    vals.len()
                )));
            }
        };
        cam.validate()?;
        Ok(cam)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_unproject_round_trip_with_distortion() {
        let cam = CameraIntrinsics { fx: 1500.0, fy: 1498.0, cx: 959.5, cy: 539.5, k1: 0.08, k2: -0.02 };
        for &(x, y, z) in &[(0.0, 0.0, 100.0), (30.0, -20.0, 90.0), (-40.0, 25.0, 110.0)] {
            let p = Point3::new(x, y, z);
            let px = cam.project(&p).expect("in front");
            let ray = cam.unproject(&px).expect("invertible");
            let back = ray * z;
            assert!((back - p.coords).norm() < 1e-9, "{back:?} vs {p:?}");
        }
        assert!(cam.project(&Point3::new(0.0, 0.0, -1.0)).is_none());
    }

    #[test]
    fn principal_point_follows_the_pixel_centre_convention() {
        let cam = CameraIntrinsics::pinhole(1000.0, 1000.0, 959.5, 539.5);
        let px = cam.project(&Point3::new(0.0, 0.0, 1.0)).expect("in front");
        assert_eq!((px.x, px.y), (959.5, 539.5));
        let half = cam.scaled(0.5);
        assert_eq!((half.cx, half.cy), (479.5, 269.5));
    }

    #[test]
    fn parses_and_rejects() {
        let c: CameraIntrinsics = "1500,1500,959.5,539.5".parse().expect("four numbers");
        assert_eq!(c.k1, 0.0);
        let c: CameraIntrinsics = "1500,1500,959.5,539.5,0.1,-0.01".parse().expect("six numbers");
        assert_eq!(c.k2, -0.01);
        assert!("1500,1500,959.5".parse::<CameraIntrinsics>().is_err());
        assert!("1500,x,959.5,539.5".parse::<CameraIntrinsics>().is_err());
        assert!("-1,1500,959.5,539.5".parse::<CameraIntrinsics>().is_err());
        assert!("nan,1500,959.5,539.5".parse::<CameraIntrinsics>().is_err());
    }
}
