//! Teeth as clinicians number them, and each tooth's contacts over a session. Two systems are
//! in use: FDI (ISO 3950: quadrant then position, 11 the upper right central incisor) and the
//! Universal (ADA) numbers 1–32, from the upper right third molar round the upper arch to the
//! upper left and back along the lower arch from the lower left third molar. Scanners name
//! per-tooth meshes by FDI ([`crate::contacts::tooth_name`] reads `FDI=NN`).

use crate::contacts::{Region, Side};
use serde::Serialize;

/// A permanent tooth, by its FDI number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Tooth(u8);

impl Tooth {
    /// The tooth of FDI number `fdi`: quadrant 1–4, position 1–8; `None` otherwise (deciduous
    /// teeth, 51–85, are not numbered here).
    pub fn fdi(fdi: u8) -> Option<Tooth> {
        ((1..=4).contains(&(fdi / 10)) && (1..=8).contains(&(fdi % 10))).then_some(Tooth(fdi))
    }

    /// The tooth a name holds: its FDI number, written alone ("36").
    pub fn from_name(name: &str) -> Option<Tooth> {
        name.trim().parse::<u8>().ok().and_then(Tooth::fdi)
    }

    /// Its FDI number.
    pub fn fdi_number(self) -> u8 {
        self.0
    }

    /// Its Universal number (1–32).
    pub fn universal(self) -> u8 {
        let (q, p) = (self.0 / 10, self.0 % 10);
        match q {
            1 => 9 - p,
            2 => 8 + p,
            3 => 25 - p,
            _ => 24 + p,
        }
    }

    /// Whether it is in the upper arch.
    pub fn upper(self) -> bool {
        self.0 / 10 <= 2
    }

    /// Whether it is on the patient's left (quadrants 2 and 3).
    pub fn on_patients_left(self) -> bool {
        matches!(self.0 / 10, 2 | 3)
    }

    /// "36 (Univ. 19)": FDI, then Universal spelt out, since "U19" reads as "upper 19" and
    /// a lower tooth's "41 (U25)" as an upper one.
    pub fn label(self) -> String {
        format!("{} (Univ. {})", self.0, self.universal())
    }
}

/// One tooth's contacts over the frames added.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ToothTotal {
    /// The arch.
    pub arch: Side,
    /// Its name as given (the FDI number for scanners' per-tooth meshes).
    pub name: String,
    /// Its FDI number, when the name is one.
    pub fdi: Option<u8>,
    /// Its Universal number, when the name is an FDI number.
    pub universal: Option<u8>,
    /// Frames in which it was in contact.
    pub frames_in_contact: usize,
    /// Its largest contact area in one frame (mm²).
    pub max_area_mm2: f64,
    /// Its contact area summed over the frames (mm² · frames): where the load was borne.
    pub area_frames_mm2: f64,
    /// Its deepest contact (mm; negative: the smallest gap).
    pub max_depth_mm: f64,
}

/// Per-tooth contact totals over a session.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ToothTotals {
    totals: Vec<ToothTotal>,
}

impl ToothTotals {
    /// Adds one frame's regions; regions without a tooth (a whole-arch mesh) are not counted.
    pub fn add(&mut self, regions: &[Region]) {
        let mut seen: Vec<(Side, &str, f64, f64)> = Vec::new();
        for r in regions {
            let Some(name) = r.tooth.as_deref() else { continue };
            match seen.iter_mut().find(|(a, n, _, _)| *a == r.arch && *n == name) {
                Some(s) => {
                    s.2 += r.area_mm2;
                    s.3 = s.3.max(r.depth_mm);
                }
                None => seen.push((r.arch, name, r.area_mm2, r.depth_mm)),
            }
        }
        for (arch, name, area, depth) in seen {
            let i = match self.totals.iter().position(|t| t.arch == arch && t.name == name) {
                Some(i) => i,
                None => {
                    let tooth = Tooth::from_name(name);
                    self.totals.push(ToothTotal {
                        arch,
                        name: name.to_string(),
                        fdi: tooth.map(Tooth::fdi_number),
                        universal: tooth.map(Tooth::universal),
                        frames_in_contact: 0,
                        max_area_mm2: 0.0,
                        area_frames_mm2: 0.0,
                        max_depth_mm: f64::NEG_INFINITY,
                    });
                    self.totals.len() - 1
                }
            };
            let t = &mut self.totals[i];
            t.frames_in_contact += 1;
            t.max_area_mm2 = t.max_area_mm2.max(area);
            t.area_frames_mm2 += area;
            t.max_depth_mm = t.max_depth_mm.max(depth);
        }
    }

    /// The totals, upper arch first, each arch in FDI order (named teeth after numbered ones).
    pub fn totals(&self) -> Vec<ToothTotal> {
        let mut v = self.totals.clone();
        v.sort_by(|a, b| {
            (a.arch != Side::Maxilla, a.fdi.is_none(), a.fdi, &a.name).cmp(&(
                b.arch != Side::Maxilla,
                b.fdi.is_none(),
                b.fdi,
                &b.name,
            ))
        });
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fdi_and_universal_numbers_agree_tooth_by_tooth() {
        // ADA Universal: 1 is the upper right third molar (FDI 18), 8 the upper right central
        // incisor (11), 9 the upper left central (21), 16 the upper left third molar (28),
        // 17 the lower left third molar (38), 24 the lower left central (31), 25 the lower
        // right central (41), 32 the lower right third molar (48).
        let pairs = [(18, 1), (11, 8), (21, 9), (28, 16), (38, 17), (31, 24), (41, 25), (48, 32), (36, 19), (46, 30)];
        for (fdi, universal) in pairs {
            assert_eq!(Tooth::fdi(fdi).map(Tooth::universal), Some(universal), "FDI {fdi}");
        }
        // All 32 map one to one onto 1..=32.
        let mut all: Vec<u8> = (1..=4)
            .flat_map(|q| (1..=8).map(move |p| q * 10 + p))
            .filter_map(Tooth::fdi)
            .map(Tooth::universal)
            .collect();
        all.sort_unstable();
        assert_eq!(all, (1..=32).collect::<Vec<u8>>());
        assert!(Tooth::fdi(19).is_none() && Tooth::fdi(51).is_none() && Tooth::fdi(10).is_none());
        assert!(Tooth::fdi(26).is_some_and(|t| t.upper() && t.on_patients_left()));
        assert!(Tooth::fdi(46).is_some_and(|t| !t.upper() && !t.on_patients_left()));
        assert_eq!(Tooth::from_name("36").map(Tooth::label).as_deref(), Some("36 (Univ. 19)"));
        assert_eq!(Tooth::from_name("41").map(Tooth::label).as_deref(), Some("41 (Univ. 25)"));
        assert_eq!(Tooth::from_name("molar"), None);
    }

    fn region(arch: Side, tooth: &str, area_mm2: f64, depth_mm: f64) -> Region {
        Region { arch, tooth: Some(tooth.into()), centroid: [0.0; 3], area_mm2, depth_mm, vertices: 3 }
    }

    #[test]
    fn totals_count_each_tooth_once_per_frame() {
        let mut t = ToothTotals::default();
        // Frame 1: two regions on 36, one on 26. Frame 2: one on 36.
        t.add(&[
            region(Side::Mandible, "36", 1.0, 0.02),
            region(Side::Mandible, "36", 0.5, 0.05),
            region(Side::Maxilla, "26", 2.0, -0.01),
        ]);
        t.add(&[region(Side::Mandible, "36", 0.7, 0.01)]);
        let v = t.totals();
        assert_eq!(v.len(), 2);
        assert_eq!((v[0].name.as_str(), v[0].frames_in_contact, v[0].universal), ("26", 1, Some(14)));
        let lower = &v[1];
        assert_eq!((lower.frames_in_contact, lower.fdi), (2, Some(36)));
        assert!((lower.max_area_mm2 - 1.5).abs() < 1e-12 && (lower.area_frames_mm2 - 2.2).abs() < 1e-12);
        assert!((lower.max_depth_mm - 0.05).abs() < 1e-12);
    }
}
