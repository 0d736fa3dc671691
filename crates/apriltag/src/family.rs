//! The tag36h11 family: 587 codewords of 36 bits on a 6×6 data grid inside a one-cell black
//! border, itself inside a one-cell white border (10 cells across in all).
//!
//! Cell coordinates here count cells inside the black-border square: x right, y down, both
//! 0..8, with rows and columns 0 and 7 being the black border. This is the upright tag image,
//! the orientation in which the reference library reports corners bottom-left, bottom-right,
//! top-right, top-left.

use crate::codes::{BIT_XY, CODES};

/// The tag36h11 family.
#[derive(Debug, Clone, Copy, Default)]
pub struct Tag36h11;

impl Tag36h11 {
    /// Number of tags in the family.
    pub const COUNT: usize = CODES.len();
    /// Data bits per tag.
    pub const NBITS: usize = 36;
    /// Minimum Hamming distance between any two codewords (under all four rotations).
    pub const MIN_HAMMING: u32 = 11;
    /// Cells across the black-border square (the square whose side is the "tag size").
    pub const WIDTH_AT_BORDER: usize = 8;
    /// Cells across the whole printed tag including its white quiet border.
    pub const TOTAL_WIDTH: usize = 10;

    /// The codeword of tag `id`, or `None` if the family has no such tag.
    pub fn code(id: u32) -> Option<u64> {
        CODES.get(id as usize).copied()
    }

    /// The cell of each data bit, most significant bit first (see the module doc).
    pub fn bit_cells() -> &'static [(u8, u8); 36] {
        &BIT_XY
    }

    /// The printed pattern of tag `id` inside its black border, or `None` for an unknown id.
    pub fn bitmap(id: u32) -> Option<TagBitmap> {
        let code = Self::code(id)?;
        let mut white = [[false; 8]; 8];
        for (i, &(x, y)) in BIT_XY.iter().enumerate() {
            let bit = (code >> (Self::NBITS - 1 - i)) & 1;
            white[y as usize][x as usize] = bit == 1;
        }
        Some(TagBitmap { id, white })
    }
}

/// The 8×8 cells of one tag's black-border square, in the upright tag image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TagBitmap {
    /// The tag id.
    pub id: u32,
    /// `white[y][x]`: true where the cell prints white. The outer ring is always black.
    pub white: [[bool; 8]; 8],
}

impl TagBitmap {
    /// Whether the cell at column `x`, row `y` (0..8, inside the black border) is white.
    pub fn is_white(&self, x: usize, y: usize) -> bool {
        self.white[y][x]
    }

    /// The 36 data bits read back from the pattern, in codeword order.
    pub fn code(&self) -> u64 {
        BIT_XY.iter().fold(0u64, |acc, &(x, y)| (acc << 1) | u64::from(self.white[y as usize][x as usize]))
    }

    /// The pattern turned a quarter turn clockwise (as seen in the upright image).
    pub fn rotated_cw(&self) -> TagBitmap {
        let mut white = [[false; 8]; 8];
        for (y, row) in white.iter_mut().enumerate() {
            for (x, cell) in row.iter_mut().enumerate() {
                *cell = self.white[7 - x][y];
            }
        }
        TagBitmap { id: self.id, white }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn border_is_black_and_bits_round_trip() {
        for id in 0..Tag36h11::COUNT as u32 {
            let bm = Tag36h11::bitmap(id).expect("known id");
            for i in 0..8 {
                assert!(!bm.is_white(i, 0) && !bm.is_white(i, 7), "tag {id} border row");
                assert!(!bm.is_white(0, i) && !bm.is_white(7, i), "tag {id} border column");
            }
            assert_eq!(bm.code(), Tag36h11::code(id).expect("known id"));
        }
        assert!(Tag36h11::bitmap(587).is_none());
    }

    #[test]
    fn bit_cells_cover_the_data_grid_once() {
        let mut seen = [[false; 8]; 8];
        for &(x, y) in Tag36h11::bit_cells() {
            assert!((1..=6).contains(&x) && (1..=6).contains(&y));
            assert!(!seen[y as usize][x as usize], "cell ({x},{y}) twice");
            seen[y as usize][x as usize] = true;
        }
    }

    #[test]
    fn codes_are_at_least_min_hamming_apart_under_rotation() {
        let rotations: Vec<[u64; 4]> = (0..Tag36h11::COUNT as u32)
            .map(|id| {
                let b0 = Tag36h11::bitmap(id).expect("known id");
                let b1 = b0.rotated_cw();
                let b2 = b1.rotated_cw();
                let b3 = b2.rotated_cw();
                [b0.code(), b1.code(), b2.code(), b3.code()]
            })
            .collect();
        for (i, ri) in rotations.iter().enumerate() {
            // A tag must not look like itself turned, either.
            for r in &ri[1..] {
                assert!((ri[0] ^ r).count_ones() >= Tag36h11::MIN_HAMMING, "tag {i} self-rotation");
            }
            for rj in &rotations[i + 1..] {
                for r in rj {
                    assert!((ri[0] ^ r).count_ones() >= Tag36h11::MIN_HAMMING);
                }
            }
        }
    }

    /// The embedded table must equal the dump from the C library in `../shared` (when present).
    #[test]
    fn matches_shared_codebook_dump() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tag36h11/codes.txt");
        let Ok(text) = std::fs::read_to_string(&path) else {
            use std::io::Write as _;
            // Straight to the handle: cargo would hide an eprintln! from a passing test.
            let _ = writeln!(std::io::stderr(), "SKIPPED: codebook check, {} not present", path.display());
            return;
        };
        let mut n = 0;
        for line in text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()) {
            let mut parts = line.split_whitespace();
            let id: u32 = parts.next().and_then(|s| s.parse().ok()).expect("id column");
            let hex = parts.next().expect("code column").trim_start_matches("0x");
            let code = u64::from_str_radix(hex, 16).expect("hex code");
            assert_eq!(Tag36h11::code(id), Some(code), "tag {id}");
            n += 1;
        }
        assert_eq!(n, Tag36h11::COUNT);
    }
}
