//! The patient's anatomical frame and points, picked on the upper scan: the occlusal plane and
//! the midline (from three points), the lower incisal point, and the condyles (given, from a
//! CBCT or by palpation, or else the Bonwill triangle's). The points file (`points.json`,
//! [`AnatomicalPoints`]) holds them in the upper scan's frame. With the registration of the
//! upper scan to the maxilla marker and the closed jaw's pose they make the [`Mounting`] every
//! other module reads, in place of the standard harness mounting.
//!
//! The head frame they define: origin at the occlusal plane's incisal point; X toward the
//! patient's left, along the line from the right to the left molar point laid in the occlusal
//! plane; Z posterior in that plane; Y = Z × X, down (toward the lower jaw). The occlusal plane
//! is the head frame's horizontal (XZ) plane, and the midline its sagittal (YZ) plane.

use crate::{KinematicsError, Mounting};
use jawtrack_pose::Pose;
use nalgebra::{Matrix3, Point3, Rotation3, UnitQuaternion, Vector3};

/// The anatomy a measure is read in: the mounting, and in words what it came from, for every
/// output that prints a number measured in it (`jawtrack_session::anatomy` chooses it).
#[derive(Debug, Clone)]
pub struct Anatomy {
    /// The head frame, condyles and incisal point on the maxilla marker.
    pub mounting: Mounting,
    /// The reference plane angles are measured to.
    pub reference_plane: &'static str,
    /// Where the condyles and the incisal point came from.
    pub landmarks: &'static str,
    /// Whether the condyles were given (not assumed).
    pub condyles_given: bool,
    /// What the reader should check (e.g. swapped molar points).
    pub warnings: Vec<String>,
}

impl Anatomy {
    /// The standard harness mounting, for a session without the patient's points.
    pub fn standard() -> Self {
        Anatomy {
            mounting: Mounting::default(),
            reference_plane: "the head frame's horizontal plane of the standard harness mounting",
            landmarks: "the standard harness mounting's condyles and lower incisal point",
            condyles_given: false,
            warnings: Vec::new(),
        }
    }

    /// Whether this is the standard harness mounting (no patient's points).
    pub fn is_standard(&self) -> bool {
        self.mounting == Mounting::default()
    }
}
use serde::{Deserialize, Serialize};

/// The version of the points file this crate reads and writes.
pub const POINTS_VERSION: u32 = 1;

/// The side of the Bonwill triangle (mm): 4 inches between the condyles, and from each condyle to
/// the lower incisal point (Bonwill, 1858). The mean of adult skulls it was drawn from, and what
/// average-value articulators are built to.
pub const BONWILL_SIDE_MM: f64 = 101.6;

/// The Balkwill angle (°): between the Bonwill triangle and the occlusal plane, the condyles
/// above it. Balkwill (1866) measured 26°; later skull studies give means of 22–26°, so a
/// condyle placed by it is uncertain by a few millimetres vertically.
pub const BALKWILL_DEG: f64 = 26.0;

/// Three points of the occlusal plane on the upper scan, named so that they also fix the
/// midline and the sides.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OcclusalPlane {
    /// The incisal point: between the upper central incisors' incisal edges.
    pub incisal: [f64; 3],
    /// The left first molar's mesiobuccal cusp tip (the patient's left).
    pub left_molar: [f64; 3],
    /// The right first molar's mesiobuccal cusp tip.
    pub right_molar: [f64; 3],
}

/// The condyles' centres with the jaw closed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Condyles {
    /// The patient's left condyle.
    pub left: [f64; 3],
    /// The right condyle.
    pub right: [f64; 3],
}

/// The points file: every point in the upper scan's frame (mm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnatomicalPoints {
    /// Always [`POINTS_VERSION`].
    pub version: u32,
    /// Always `"mm"`.
    pub units: String,
    /// Always `"upper scan"`: the frame the points are in.
    pub frame: String,
    /// The occlusal plane, and with it the midline.
    pub occlusal_plane: OcclusalPlane,
    /// The lower incisal point (between the lower central incisors' incisal edges) with the jaw
    /// in maximal intercuspation: the point whose path `metrics` and the envelopes read.
    pub lower_incisal_point: [f64; 3],
    /// The condyles; absent, the Bonwill triangle's ([`AnatomicalPoints::condyles`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condyles: Option<Condyles>,
}

/// The least a side of the occlusal triangle may be (mm): the molars of any adult arch are 35 mm
/// or more apart and from the incisors, so shorter means a point picked on the wrong tooth.
const LEAST_SIDE_MM: f64 = 20.0;
/// The least height of the occlusal triangle over its longest side (mm): below it the three
/// points are too near a line to fix a plane.
const LEAST_HEIGHT_MM: f64 = 10.0;
/// The least distance between given condyles (mm).
const LEAST_INTERCONDYLAR_MM: f64 = 60.0;
/// The farthest the lower incisal point may be from the upper with the teeth together (mm):
/// overjet and overbite are 2–4 mm in most adults and beyond 10 mm only in severe malocclusion
/// (Proffit, Contemporary Orthodontics, ch. 6), so 20 mm means a point picked off the teeth.
const MOST_INCISAL_GAP_MM: f64 = 20.0;
/// The condyle-to-lower-incisor distance accepted (mm): Bonwill's triangle has 101.6 mm sides,
/// and measured adults range about 85–115 mm; wider bounds leave room for picking error.
const CONDYLE_REACH_MM: (f64, f64) = (70.0, 140.0);
/// The least a condyle lies behind the upper incisal point (mm), along the occlusal plane's
/// posterior axis: about 80 mm in an adult.
const LEAST_CONDYLE_BEHIND_MM: f64 = 50.0;

fn v(p: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

fn points_error(msg: impl Into<String>) -> KinematicsError {
    KinematicsError::Points(msg.into())
}

impl AnatomicalPoints {
    /// A points file from its parts, checked.
    pub fn new(
        occlusal_plane: OcclusalPlane,
        lower_incisal_point: [f64; 3],
        condyles: Option<Condyles>,
    ) -> Result<Self, KinematicsError> {
        let p = AnatomicalPoints {
            version: POINTS_VERSION,
            units: "mm".into(),
            frame: "upper scan".into(),
            occlusal_plane,
            lower_incisal_point,
            condyles,
        };
        p.check()?;
        Ok(p)
    }

    /// Reads and checks a points file's text.
    pub fn from_json(text: &str) -> Result<Self, KinematicsError> {
        let p: AnatomicalPoints =
            serde_json::from_str(text).map_err(|e| points_error(format!("not a points file: {e}")))?;
        p.check()?;
        Ok(p)
    }

    /// The file's text (pretty JSON).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Refuses what no patient's points can be: another version or unit, a point not finite,
    /// occlusal points too close or near a line, condyles too close.
    fn check(&self) -> Result<(), KinematicsError> {
        if self.version != POINTS_VERSION {
            return Err(points_error(format!(
                "version {} is not one this program reads ({POINTS_VERSION}): write the file again with `jawtrack points`",
                self.version
            )));
        }
        if self.units != "mm" {
            return Err(points_error(format!(
                "units \"{}\": the points must be in mm (\"units\": \"mm\")",
                self.units
            )));
        }
        if self.frame != "upper scan" {
            return Err(points_error(format!(
                "frame \"{}\": the points must be in the upper scan's frame (\"frame\": \"upper scan\")",
                self.frame
            )));
        }
        let o = &self.occlusal_plane;
        let mut named = vec![
            ("occlusal_plane.incisal", o.incisal),
            ("occlusal_plane.left_molar", o.left_molar),
            ("occlusal_plane.right_molar", o.right_molar),
            ("lower_incisal_point", self.lower_incisal_point),
        ];
        if let Some(c) = &self.condyles {
            named.extend([("condyles.left", c.left), ("condyles.right", c.right)]);
        }
        if let Some((name, _)) = named.iter().find(|(_, p)| p.iter().any(|c| !c.is_finite())) {
            return Err(points_error(format!("{name} is not a finite point")));
        }
        let (a, l, r) = (v(&o.incisal), v(&o.left_molar), v(&o.right_molar));
        for (what, d) in
            [("incisal to left molar", l - a), ("incisal to right molar", r - a), ("molar to molar", l - r)]
        {
            if d.norm() < LEAST_SIDE_MM {
                return Err(points_error(format!(
                    "the occlusal plane's points are {:.1} mm apart {what}; an adult arch puts them 35 mm or more apart, \
                     so a point is on the wrong tooth or in other units",
                    d.norm()
                )));
            }
        }
        let longest = [(l - a).norm(), (r - a).norm(), (l - r).norm()].into_iter().fold(0.0, f64::max);
        let height = (l - a).cross(&(r - a)).norm() / longest;
        if height < LEAST_HEIGHT_MM {
            return Err(points_error(format!(
                "the occlusal plane's three points are nearly on a line ({height:.1} mm from it): pick the incisal point \
                 and a first molar's cusp tip on each side"
            )));
        }
        if let Some(c) = &self.condyles
            && (v(&c.left) - v(&c.right)).norm() < LEAST_INTERCONDYLAR_MM
        {
            return Err(points_error(format!(
                "the condyles are {:.1} mm apart; an adult's are 80–120 mm apart",
                (v(&c.left) - v(&c.right)).norm()
            )));
        }
        self.check_in_head()
    }

    /// The points where a head puts them, read in the head frame the occlusal plane fixes (X the
    /// patient's left, Y down, Z posterior, origin the upper incisal point).
    fn check_in_head(&self) -> Result<(), KinematicsError> {
        let head = self.head_from_scan();
        let at = |p: &[f64; 3]| head.transform_point(&nalgebra::Point3::from(v(p))).coords;
        let lower = at(&self.lower_incisal_point);
        if lower.norm() > MOST_INCISAL_GAP_MM {
            let (ahead, up) = (-lower.z, -lower.y);
            return Err(points_error(format!(
                "the lower incisal point is {:.1} mm from the upper ({ahead:.1} mm in front of it, {up:.1} mm above, \
                 {:.1} mm to the patient's left); with the teeth together the lower incisal edge is within a few mm \
                 of the upper (overjet and overbite 2–4 mm, rarely over 10 mm): pick it with the lower scan in its \
                 bite",
                lower.norm(),
                lower.x
            )));
        }
        let Some(c) = &self.condyles else { return Ok(()) };
        for (side, p, sign) in [("left", at(&c.left), 1.0), ("right", at(&c.right), -1.0)] {
            let reach = (p - lower).norm();
            if sign * p.x <= 0.0
                || p.z < LEAST_CONDYLE_BEHIND_MM
                || !(CONDYLE_REACH_MM.0..=CONDYLE_REACH_MM.1).contains(&reach)
            {
                return Err(points_error(format!(
                    "the {side} condyle is {reach:.1} mm from the lower incisal point, {:.1} mm behind the upper \
                     incisors and {:.1} mm to the patient's left: a condyle lies 80–120 mm behind the incisors on its \
                     own side (Bonwill's triangle, 101.6 mm a side): are the condyles swapped, or in another frame?",
                    p.z, p.x
                )));
            }
        }
        Ok(())
    }

    /// The head frame in the upper scan's frame: maps upper-scan points into the head frame
    /// (module doc).
    pub fn head_from_scan(&self) -> Pose {
        let o = &self.occlusal_plane;
        let (a, l, r) = (v(&o.incisal), v(&o.left_molar), v(&o.right_molar));
        // Normal of the plane, then X along right → left in it, Z toward the molars in it.
        let n = (l - a).cross(&(r - a)).normalize();
        let across = l - r;
        let x = (across - n * n.dot(&across)).normalize();
        let back = (l + r) / 2.0 - a;
        let z0 = back - n * n.dot(&back);
        let z = (z0 - x * x.dot(&z0)).normalize();
        let y = z.cross(&x);
        // Rows are the head axes in scan coordinates: head = R (scan − a).
        let r = Rotation3::from_matrix_unchecked(Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()]));
        let q = UnitQuaternion::from_rotation_matrix(&r);
        Pose::from_parts(q, -(q * a))
    }

    /// The condyles in the upper scan's frame, left then right, and whether they were given
    /// (`false`: the Bonwill triangle's).
    pub fn condyles(&self) -> ([Vector3<f64>; 2], bool) {
        if let Some(c) = &self.condyles {
            return ([v(&c.left), v(&c.right)], true);
        }
        let scan_from_head = self.head_from_scan().inverse();
        let incisor = self.head_from_scan().transform_point(&Point3::from(v(&self.lower_incisal_point))).coords;
        let at = |head: Vector3<f64>| scan_from_head.transform_point(&Point3::from(incisor + head)).coords;
        let [l, r] = bonwill_condyles();
        ([at(l), at(r)], false)
    }

    /// The mounting these points make: `maxilla_scan_from_maxilla_marker` from the registration,
    /// and the closed jaw's `maxilla_from_mandible` from the recording.
    pub fn mounting(&self, maxilla_scan_from_maxilla_marker: &Pose, maxilla_from_mandible_rest: &Pose) -> Mounting {
        let head_from_scan = self.head_from_scan();
        let head_from_maxilla = head_from_scan * *maxilla_scan_from_maxilla_marker;
        let in_head = |p: Vector3<f64>| head_from_scan.transform_point(&Point3::from(p)).coords;
        let ([l, r], _) = self.condyles();
        Mounting {
            head_from_maxilla,
            head_from_mandible_rest: head_from_maxilla * *maxilla_from_mandible_rest,
            condyles: [in_head(l), in_head(r)],
            lower_incisal_point: in_head(v(&self.lower_incisal_point)),
        }
    }
}

/// The Bonwill triangle's condyles relative to the lower incisal point, in the head frame, left
/// then right: [`BONWILL_SIDE_MM`] from each other and from the incisal point, the triangle
/// tilted up by [`BALKWILL_DEG`] from the occlusal plane about the transverse axis.
pub fn bonwill_condyles() -> [Vector3<f64>; 2] {
    let half = BONWILL_SIDE_MM / 2.0;
    let reach = (BONWILL_SIDE_MM * BONWILL_SIDE_MM - half * half).sqrt();
    let tilt = BALKWILL_DEG.to_radians();
    let (up, back) = (reach * tilt.sin(), reach * tilt.cos());
    [Vector3::new(half, -up, back), Vector3::new(-half, -up, back)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scan frame turned and moved arbitrarily from the head frame.
    fn scan_from_head() -> Pose {
        Pose::from_axis_angle(Vector3::new(0.3, -1.1, 0.4), Vector3::new(12.0, -40.0, 7.5))
    }

    fn arr(p: Vector3<f64>) -> [f64; 3] {
        [p.x, p.y, p.z]
    }

    /// Points placed in the head frame, written in the scan's.
    fn points(condyles: Option<[Vector3<f64>; 2]>) -> AnatomicalPoints {
        placed(Vector3::new(0.0, 1.5, 1.0), condyles).expect("the points are an arch's")
    }

    /// The same, with the lower incisal point and the condyles placed in the head frame.
    fn placed(lower: Vector3<f64>, condyles: Option<[Vector3<f64>; 2]>) -> Result<AnatomicalPoints, KinematicsError> {
        let s = scan_from_head();
        let at = |h: Vector3<f64>| arr(s.transform_point(&Point3::from(h)).coords);
        AnatomicalPoints::new(
            OcclusalPlane {
                incisal: at(Vector3::zeros()),
                left_molar: at(Vector3::new(24.0, 0.0, 34.0)),
                right_molar: at(Vector3::new(-23.0, 0.0, 34.0)),
            },
            at(lower),
            condyles.map(|[l, r]| Condyles { left: at(l), right: at(r) }),
        )
    }

    #[test]
    fn points_no_head_has_are_refused_by_what_is_wrong() {
        let [l, r] = bonwill_condyles();
        let near = Vector3::new(0.0, -2.0, 3.0);
        assert!(placed(near, Some([l, r])).is_ok(), "an ordinary arch");
        let said = |p: Result<AnatomicalPoints, KinematicsError>| p.expect_err("refused").to_string();
        let ahead = said(placed(Vector3::new(0.0, -2.0, -30.0), None));
        assert!(ahead.contains("30.0 mm in front of it") && ahead.contains("in its bite"), "{ahead}");
        let swapped = said(placed(near, Some([r, l])));
        assert!(swapped.contains("left condyle") && swapped.contains("swapped"), "{swapped}");
        let forward = |c: Vector3<f64>| Vector3::new(c.x, c.y, -c.z);
        let in_front = said(placed(near, Some([forward(l), forward(r)])));
        assert!(in_front.contains("behind the upper incisors"), "{in_front}");
    }

    #[test]
    fn the_head_frame_is_the_one_the_points_were_placed_in() {
        let got = points(None).head_from_scan() * scan_from_head();
        let (dt, dr) = got.distance_to(&Pose::identity());
        assert!(dt < 1e-9 && dr < 1e-12, "{dt} mm, {dr} rad");
    }

    #[test]
    fn the_bonwill_triangle_is_equilateral_and_tilted_by_the_balkwill_angle() {
        let [l, r] = bonwill_condyles();
        assert!(((l - r).norm() - BONWILL_SIDE_MM).abs() < 1e-9);
        assert!((l.norm() - BONWILL_SIDE_MM).abs() < 1e-9 && (r.norm() - BONWILL_SIDE_MM).abs() < 1e-9);
        // The triangle's plane holds the transverse axis; its normal is tilted from the
        // occlusal plane's (Y) by the Balkwill angle, with the condyles above (−Y).
        let n = l.cross(&r).normalize();
        assert!((n.y.abs().acos().to_degrees() - BALKWILL_DEG).abs() < 1e-9, "{n}");
        assert!(l.y < 0.0 && r.y < 0.0 && l.z > 0.0 && l.x > 0.0 && r.x < 0.0);
    }

    #[test]
    fn default_condyles_are_the_bonwill_ones_from_the_lower_incisal_point() {
        let p = points(None);
        let ([l, r], given) = p.condyles();
        assert!(!given);
        let h = p.head_from_scan();
        let at = |q: Vector3<f64>| h.transform_point(&Point3::from(q)).coords;
        let [bl, br] = bonwill_condyles();
        let incisor = Vector3::new(0.0, 1.5, 1.0);
        assert!((at(l) - incisor - bl).norm() < 1e-9 && (at(r) - incisor - br).norm() < 1e-9);
    }

    #[test]
    fn the_mounting_of_the_standard_points_is_the_standard_mounting() {
        let m = Mounting::default();
        let p = points(Some(m.condyles));
        // Any registration: the maxilla marker sits where the standard mounting puts it.
        let scan_from_maxilla = scan_from_head() * m.head_from_maxilla;
        let got = p.mounting(&scan_from_maxilla, &m.maxilla_from_mandible_rest());
        let close = |a: &Pose, b: &Pose| {
            let (dt, dr) = a.distance_to(b);
            dt < 1e-9 && dr < 1e-12
        };
        assert!(close(&got.head_from_maxilla, &m.head_from_maxilla));
        assert!(close(&got.head_from_mandible_rest, &m.head_from_mandible_rest));
        assert!((got.condyles[0] - m.condyles[0]).norm() < 1e-9 && (got.condyles[1] - m.condyles[1]).norm() < 1e-9);
        assert!((got.lower_incisal_point - m.lower_incisal_point).norm() < 1e-9);
    }

    #[test]
    fn a_file_round_trips_and_bad_ones_are_refused_by_name() {
        let p = points(None);
        assert_eq!(AnatomicalPoints::from_json(&p.to_json()).expect("its own file"), p);
        let o = p.occlusal_plane;
        let on_a_line = OcclusalPlane { right_molar: arr(v(&o.incisal) * 2.0 - v(&o.left_molar)), ..o };
        let e = AnatomicalPoints::new(on_a_line, p.lower_incisal_point, None).expect_err("refused").to_string();
        assert!(e.contains("nearly on a line"), "{e}");
        let close = OcclusalPlane { left_molar: arr(v(&o.incisal) + Vector3::new(1.0, 2.0, 3.0)), ..o };
        let e = AnatomicalPoints::new(close, p.lower_incisal_point, None).expect_err("refused").to_string();
        assert!(e.contains("incisal to left molar"), "{e}");
        let e = AnatomicalPoints::from_json(&p.to_json().replace("\"mm\"", "\"m\"")).expect_err("refused").to_string();
        assert!(e.contains("units"), "{e}");
        let e = AnatomicalPoints::new(o, [f64::NAN, 0.0, 0.0], None).expect_err("refused").to_string();
        assert!(e.contains("lower_incisal_point"), "{e}");
        let same = Condyles { left: [0.0, 0.0, 90.0], right: [10.0, 0.0, 90.0] };
        let e = AnatomicalPoints::new(o, p.lower_incisal_point, Some(same)).expect_err("refused").to_string();
        assert!(e.contains("condyles"), "{e}");
    }
}
