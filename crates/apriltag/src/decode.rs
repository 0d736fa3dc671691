//! Decoding a sampled 36-bit pattern to a tag id: a table of every codeword and every pattern
//! within `max_hamming` bit flips of one (587 × 667 entries at 2), looked up for each of the
//! pattern's four rotations. tag36h11's minimum distance of 11 keeps those balls disjoint.

use crate::DetectError;
use crate::family::Tag36h11;
use std::collections::HashMap;

const MASK: u64 = (1 << 36) - 1;

/// The codeword turned a quarter turn clockwise (as seen in the upright tag image): the bit
/// layout is four identical quadrants of 9 bits, so a turn moves each quadrant to the next.
pub fn rotate_cw(code: u64) -> u64 {
    ((code >> 9) | (code << 27)) & MASK
}

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
}

impl CodeTable {
    /// Builds the table for tag36h11; `max_hamming` above 2 is refused.
    pub fn new(max_hamming: u32) -> Result<Self, DetectError> {
        if max_hamming > 2 {
            return Err(DetectError::BadConfig(format!("max_hamming {max_hamming} is refused: at most 2")));
        }
        let per_code = [1, 1 + 36, 1 + 36 + 630][max_hamming as usize];
        let mut map = HashMap::with_capacity(Tag36h11::COUNT * per_code);
        for id in 0..Tag36h11::COUNT as u32 {
            let code = Tag36h11::code(id).unwrap_or_default();
            let id = id as u16;
            map.insert(code, (id, 0));
            if max_hamming >= 1 {
                for i in 0..36 {
                    map.insert(code ^ (1 << i), (id, 1));
                    if max_hamming >= 2 {
                        for j in 0..i {
                            map.insert(code ^ (1 << i) ^ (1 << j), (id, 2));
                        }
                    }
                }
            }
        }
        Ok(CodeTable { map, max_hamming })
    }

    /// The bit errors this table corrects.
    pub fn max_hamming(&self) -> u32 {
        self.max_hamming
    }

    /// Decodes a sampled pattern (read in the image's orientation), trying all four turns.
    pub fn decode(&self, sampled: u64) -> Option<Decoded> {
        let mut code = sampled & MASK;
        for rotation in 0..4 {
            if let Some(&(id, hamming)) = self.map.get(&code) {
                return Some(Decoded { id: u32::from(id), hamming: u32::from(hamming), rotation });
            }
            code = rotate_cw(code);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_matches_the_printed_pattern() {
        for id in [0, 1, 17, 586] {
            let bm = Tag36h11::bitmap(id).expect("id");
            assert_eq!(rotate_cw(bm.code()), bm.rotated_cw().code(), "tag {id}");
            let c = bm.code();
            assert_eq!(rotate_cw(rotate_cw(rotate_cw(rotate_cw(c)))), c);
        }
    }

    #[test]
    fn decodes_every_tag_in_every_turn_with_up_to_two_errors() {
        let table = CodeTable::new(2).expect("table");
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for id in 0..Tag36h11::COUNT as u32 {
            let code = Tag36h11::code(id).expect("id");
            let (i, j) = ((next() % 36) as u32, (next() % 36) as u32);
            let damaged = code ^ (1 << i) ^ (1 << j);
            let hamming = if i == j { 0 } else { 2 };
            // As seen turned by r quarter turns counter-clockwise, i.e. needing r clockwise.
            let mut seen = damaged;
            for r in 0..4u32 {
                let want = Decoded { id, hamming, rotation: r };
                assert_eq!(table.decode(seen), Some(want), "tag {id}, turn {r}");
                seen = rotate_cw(rotate_cw(rotate_cw(seen)));
            }
        }
        // Three errors are beyond a table of two.
        let code = Tag36h11::code(5).expect("id");
        assert_eq!(table.decode(code ^ 0b111), None);
        assert_eq!(CodeTable::new(0).expect("table").decode(code ^ 1), None);
        assert!(CodeTable::new(3).is_err());
    }

    #[test]
    fn random_patterns_rarely_decode() {
        let table = CodeTable::new(2).expect("table");
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
