//! Decoding a sampled pattern to a tag id: a table of every codeword of a family and every
//! pattern within `max_hamming` bit flips of one (587 × 667 entries for tag36h11 at 2), looked
//! up for each of the pattern's four rotations. A family's minimum distance of 5 or more keeps
//! those balls disjoint.

use crate::DetectError;
use jawtrack_tag_family::{TagFamily, permute};
use std::collections::HashMap;

/// A decoded pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Decoded {
    /// Tag id.
    pub id: u32,
    /// Bits corrected.
    pub hamming: u32,
    /// Quarter turns clockwise that bring the sampled pattern upright (0–3).
    pub rotation: u32,
}

/// The lookup table of one family at one `max_hamming`.
#[derive(Debug, Clone)]
pub struct CodeTable {
    map: HashMap<u64, (u16, u8)>,
    max_hamming: u32,
    /// The family's quarter turn as a bit permutation ([`TagFamily::rotation_cw`]).
    turn: Vec<u8>,
    mask: u64,
}

impl CodeTable {
    /// Builds the table for `family`; `max_hamming` above 2, or above what the family's
    /// distance keeps unambiguous, is refused, as is a layout the detector cannot read.
    pub fn new(family: &TagFamily, max_hamming: u32) -> Result<Self, DetectError> {
        family.validate().map_err(DetectError::BadConfig)?;
        if max_hamming > 2 || 2 * max_hamming >= family.min_hamming {
            return Err(DetectError::BadConfig(format!(
                "max_hamming {max_hamming} is refused for {} (distance {}): at most 2, and under half the distance",
                family.name, family.min_hamming
            )));
        }
        let nbits = family.nbits();
        let per_code = [1, 1 + nbits, 1 + nbits + nbits * (nbits - 1) / 2][max_hamming as usize];
        let mut map = HashMap::with_capacity(family.count() * per_code);
        for (id, &code) in family.codes.iter().enumerate() {
            let id = id as u16;
            map.insert(code, (id, 0));
            if max_hamming >= 1 {
                for i in 0..nbits {
                    map.insert(code ^ (1 << i), (id, 1));
                    if max_hamming >= 2 {
                        for j in 0..i {
                            map.insert(code ^ (1 << i) ^ (1 << j), (id, 2));
                        }
                    }
                }
            }
        }
        let mask = if nbits == 64 { u64::MAX } else { (1 << nbits) - 1 };
        Ok(CodeTable { map, max_hamming, turn: family.rotation_cw(), mask })
    }

    /// The bit errors this table corrects.
    pub fn max_hamming(&self) -> u32 {
        self.max_hamming
    }

    /// Decodes a sampled pattern (read in the image's orientation), trying all four turns.
    pub fn decode(&self, sampled: u64) -> Option<Decoded> {
        let mut code = sampled & self.mask;
        for rotation in 0..4 {
            if let Some(&(id, hamming)) = self.map.get(&code) {
                return Some(Decoded { id: u32::from(id), hamming: u32::from(hamming), rotation });
            }
            code = permute(code, &self.turn);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_every_tag_in_every_turn_with_up_to_two_errors() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut checked = 0;
        for f in TagFamily::ALL {
            let table = CodeTable::new(&f, 2).expect("table");
            let nbits = f.nbits() as u64;
            for id in 0..f.count() as u32 {
                let code = f.code(id).expect("id");
                let (i, j) = ((next() % nbits) as u32, (next() % nbits) as u32);
                let damaged = code ^ (1 << i) ^ (1 << j);
                let hamming = if i == j { 0 } else { 2 };
                // As seen turned by r quarter turns counter-clockwise, i.e. needing r clockwise.
                let mut seen = damaged;
                for r in 0..4u32 {
                    let want = Decoded { id, hamming, rotation: r };
                    assert_eq!(table.decode(seen), Some(want), "{} {id}, turn {r}", f.name);
                    seen = f.rotate_cw(f.rotate_cw(f.rotate_cw(seen)));
                    checked += 1;
                }
            }
            // Three errors are beyond a table of two: never read as the tag, and not at all
            // where the distance (6 or more) keeps them out of every other tag's ball too.
            let code = f.code(5).expect("id");
            let three = table.decode(code ^ 0b111);
            assert_ne!(three.map(|d| d.id), Some(5), "{}", f.name);
            if f.min_hamming >= 6 {
                assert_eq!(three, None, "{}", f.name);
            }
            assert_eq!(CodeTable::new(&f, 0).expect("table").decode(code ^ 1), None);
        }
        assert_eq!(checked, 4 * (587 + 35 + 30));
        assert!(CodeTable::new(&TagFamily::TAG36H11, 3).is_err());
    }

    #[test]
    fn a_family_is_not_decoded_as_another() {
        let table = CodeTable::new(&TagFamily::TAG36H11, 2).expect("table");
        for f in [TagFamily::TAG25H9, TagFamily::TAG16H5] {
            let hits = f.codes.iter().filter(|&&c| table.decode(c).is_some()).count();
            assert_eq!(hits, 0, "{} codes read as tag36h11", f.name);
        }
    }

    #[test]
    fn random_patterns_rarely_decode() {
        let table = CodeTable::new(&TagFamily::TAG36H11, 2).expect("table");
        let mut x = 12345u64;
        let hits = (0..100_000)
            .filter(|_| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                table.decode(x >> 28).is_some()
            })
            .count();
        // 4 turns × 587 × 667 / 2^36 ≈ 2.3e-5 of all patterns.
        assert!(hits <= 10, "{hits} of 100000 random patterns decoded");
    }
}
