//! Tag families as data: each family is its codewords, where each bit sits, and how many cells
//! the printed square spans ([`TagFamily`]). The detector, the renderer and the harness sheet
//! read a family only through this type, so a family is added here alone: its codebook in a
//! file of its own (`tag25h9.rs`) and one constant (see [`TagFamily::ALL`]).
//!
//! Supported layouts are the classic ones: the data cells inside a one-cell black border, itself
//! inside a white quiet zone. Built in: tag36h11 (JawTrack's), tag25h9 and tag16h5.
//!
//! Cell coordinates count cells inside the black-border square: x right, y down, both
//! 0..`width_at_border`, the outer ring being the black border. This is the upright tag image,
//! the orientation in which the reference library reports corners bottom-left, bottom-right,
//! top-right, top-left.

mod tag16h5;
mod tag25h9;
mod tag36h11;

/// One tag family: codewords and printed layout.
///
/// # Examples
///
/// ```
/// use jawtrack_tag_family::TagFamily;
///
/// let family = TagFamily::named("tag25h9").expect("built in");
/// assert_eq!((family.count(), family.nbits()), (35, 25));
/// let bitmap = family.bitmap(3).expect("tag 3 exists");
/// assert_eq!(bitmap.width(), 7);
/// assert_eq!(bitmap.code(), family.code(3).expect("tag 3 exists"));
/// ```
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct TagFamily {
    /// The family's name as the C library spells it, e.g. `tag36h11`.
    pub name: &'static str,
    /// The codewords, index = tag id. Bit `nbits - 1 - i` is the cell `bit_cells[i]`; 1 = white.
    pub codes: &'static [u64],
    /// The cell (x, y) of each data bit, most significant bit first (see the module doc).
    pub bit_cells: &'static [(u8, u8)],
    /// Minimum Hamming distance between any two codewords, under all four rotations.
    pub min_hamming: u32,
    /// Cells across the black-border square (the square whose side is the "tag size").
    pub width_at_border: usize,
    /// Cells across the whole printed tag including its white quiet zone.
    pub total_width: usize,
}

impl TagFamily {
    /// tag36h11: 587 tags of 36 bits, distance 11; JawTrack's markers.
    pub const TAG36H11: TagFamily = TagFamily {
        name: "tag36h11",
        codes: &tag36h11::CODES,
        bit_cells: &tag36h11::BIT_XY,
        min_hamming: 11,
        width_at_border: 8,
        total_width: 10,
    };
    /// tag25h9: 35 tags of 25 bits, distance 9.
    pub const TAG25H9: TagFamily = TagFamily {
        name: "tag25h9",
        codes: &tag25h9::CODES,
        bit_cells: &tag25h9::BIT_XY,
        min_hamming: 9,
        width_at_border: 7,
        total_width: 9,
    };
    /// tag16h5: 30 tags of 16 bits, distance 5 (small tags, many false positives in clutter).
    pub const TAG16H5: TagFamily = TagFamily {
        name: "tag16h5",
        codes: &tag16h5::CODES,
        bit_cells: &tag16h5::BIT_XY,
        min_hamming: 5,
        width_at_border: 6,
        total_width: 8,
    };
    /// Every built-in family.
    pub const ALL: [TagFamily; 3] = [Self::TAG36H11, Self::TAG25H9, Self::TAG16H5];

    /// The built-in family of this name (`tag36h11`, `tag25h9`, `tag16h5`).
    pub fn named(name: &str) -> Option<TagFamily> {
        Self::ALL.into_iter().find(|f| f.name == name)
    }

    /// Number of tags in the family.
    pub fn count(&self) -> usize {
        self.codes.len()
    }

    /// Data bits per tag.
    pub fn nbits(&self) -> usize {
        self.bit_cells.len()
    }

    /// The codeword of tag `id`, or `None` if the family has no such tag.
    pub fn code(&self, id: u32) -> Option<u64> {
        self.codes.get(id as usize).copied()
    }

    /// The printed pattern of tag `id` inside its black border, or `None` for an unknown id.
    pub fn bitmap(&self, id: u32) -> Option<TagBitmap> {
        let code = self.code(id)?;
        let n = self.width_at_border;
        let mut white = vec![false; n * n];
        for (i, &(x, y)) in self.bit_cells.iter().enumerate() {
            let bit = (code >> (self.nbits() - 1 - i)) & 1;
            white[usize::from(y) * n + usize::from(x)] = bit == 1;
        }
        Some(TagBitmap { id, family: *self, white })
    }

    /// For each bit of a codeword turned a quarter turn clockwise (as seen in the upright
    /// image), the bit of the unturned codeword it takes: turning moves the cell (x, y) to
    /// (n − 1 − y, x).
    pub fn rotation_cw(&self) -> Vec<u8> {
        let n = self.width_at_border as u8;
        self.bit_cells
            .iter()
            .map(|&(x, y)| {
                let from = (y, n - 1 - x);
                self.bit_cells.iter().position(|&c| c == from).map_or(u8::MAX, |i| i as u8)
            })
            .collect()
    }

    /// The codeword turned a quarter turn clockwise (as seen in the upright tag image).
    pub fn rotate_cw(&self, code: u64) -> u64 {
        permute(code, &self.rotation_cw())
    }

    /// Checks that the layout is one the detector reads: at most 64 bits, each on a distinct
    /// cell strictly inside the black border, a ring of quiet zone, and a bit layout that a
    /// quarter turn maps onto itself.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.width_at_border;
        if !(4..=16).contains(&n) || self.total_width != n + 2 {
            return Err(format!(
                "{}: {n} cells at the border in {} in all is not a classic layout",
                self.name, self.total_width
            ));
        }
        if self.nbits() == 0 || self.nbits() > 64 {
            return Err(format!("{}: {} bits (1 to 64 are readable)", self.name, self.nbits()));
        }
        let mut seen = vec![false; n * n];
        for &(x, y) in self.bit_cells {
            let (x, y) = (usize::from(x), usize::from(y));
            if !(1..n - 1).contains(&x) || !(1..n - 1).contains(&y) || std::mem::replace(&mut seen[y * n + x], true) {
                return Err(format!("{}: bit cell ({x}, {y}) is on the border or used twice", self.name));
            }
        }
        if self.rotation_cw().contains(&u8::MAX) {
            return Err(format!("{}: the bit layout does not map onto itself under a quarter turn", self.name));
        }
        Ok(())
    }
}

/// A family shows as its name: its codebook is data, not a message.
impl std::fmt::Debug for TagFamily {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "TagFamily({})", self.name)
    }
}

/// `code` with bit `i` (most significant first) taken from bit `from[i]`.
pub fn permute(code: u64, from: &[u8]) -> u64 {
    let n = from.len();
    from.iter().fold(0u64, |acc, &j| (acc << 1) | ((code >> (n - 1 - usize::from(j))) & 1))
}

/// The cells of one tag's black-border square, in the upright tag image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TagBitmap {
    /// The tag id.
    pub id: u32,
    /// The family it belongs to.
    pub family: TagFamily,
    /// Row-major, `width()` cells across: true where the cell prints white.
    white: Vec<bool>,
}

impl TagBitmap {
    /// Cells across the black-border square.
    pub fn width(&self) -> usize {
        self.family.width_at_border
    }

    /// Whether the cell at column `x`, row `y` (0..`width()`, inside the black border) is
    /// white; cells outside the square are not.
    pub fn is_white(&self, x: usize, y: usize) -> bool {
        let n = self.width();
        x < n && y < n && self.white[y * n + x]
    }

    /// The data bits read back from the pattern, in codeword order.
    pub fn code(&self) -> u64 {
        self.family
            .bit_cells
            .iter()
            .fold(0u64, |acc, &(x, y)| (acc << 1) | u64::from(self.is_white(x.into(), y.into())))
    }

    /// The pattern turned a quarter turn clockwise (as seen in the upright image).
    pub fn rotated_cw(&self) -> TagBitmap {
        let n = self.width();
        let white = (0..n * n).map(|i| self.is_white(i / n, n - 1 - i % n)).collect();
        TagBitmap { id: self.id, family: self.family, white }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn every_family_is_a_valid_layout_with_a_black_border() {
        assert_eq!(TagFamily::ALL.len(), 3);
        for f in TagFamily::ALL {
            f.validate().unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(TagFamily::named(f.name), Some(f));
            let n = f.width_at_border;
            for id in 0..f.count() as u32 {
                let bm = f.bitmap(id).expect("known id");
                for i in 0..n {
                    assert!(!bm.is_white(i, 0) && !bm.is_white(i, n - 1), "{} {id} border row", f.name);
                    assert!(!bm.is_white(0, i) && !bm.is_white(n - 1, i), "{} {id} border column", f.name);
                }
                assert_eq!(bm.code(), f.code(id).expect("known id"));
            }
            assert!(f.bitmap(f.count() as u32).is_none());
        }
        assert_eq!(TagFamily::named("tagStandard41h12"), None);
    }

    #[test]
    fn a_broken_layout_is_refused() {
        let mut f = TagFamily::TAG25H9;
        f.total_width = 10;
        assert!(f.validate().is_err());
        let mut f = TagFamily::TAG16H5;
        f.bit_cells = &[(1, 1), (1, 1)];
        assert!(f.validate().expect_err("a cell used twice").contains("used twice"));
        f.bit_cells = &[(1, 1), (2, 1)];
        assert!(f.validate().expect_err("a layout a turn breaks").contains("quarter turn"));
    }

    #[test]
    fn tag36h11_turns_by_moving_whole_quadrants() {
        // tag36h11's layout is four quadrants of 9 bits, as the C library's rotate90 assumes.
        let f = TagFamily::TAG36H11;
        for id in [0, 1, 17, 586] {
            let c = f.code(id).expect("id");
            assert_eq!(f.rotate_cw(c), ((c >> 9) | (c << 27)) & ((1 << 36) - 1), "tag {id}");
        }
    }

    #[test]
    fn codes_are_at_least_min_hamming_apart_under_rotation() {
        for f in TagFamily::ALL {
            let rotations: Vec<[u64; 4]> = (0..f.count() as u32)
                .map(|id| {
                    let b0 = f.bitmap(id).expect("known id");
                    let b1 = b0.rotated_cw();
                    let b2 = b1.rotated_cw();
                    let b3 = b2.rotated_cw();
                    assert_eq!(f.rotate_cw(b0.code()), b1.code(), "{} {id}", f.name);
                    assert_eq!(b3.rotated_cw(), b0);
                    [b0.code(), b1.code(), b2.code(), b3.code()]
                })
                .collect();
            for (i, ri) in rotations.iter().enumerate() {
                // A tag must not look like itself turned, either.
                for r in &ri[1..] {
                    assert!((ri[0] ^ r).count_ones() >= f.min_hamming, "{} {i} self-rotation", f.name);
                }
                for rj in &rotations[i + 1..] {
                    for r in rj {
                        assert!((ri[0] ^ r).count_ones() >= f.min_hamming, "{} {i}", f.name);
                    }
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
            assert_eq!(TagFamily::TAG36H11.code(id), Some(code), "tag {id}");
            n += 1;
        }
        assert_eq!(n, TagFamily::TAG36H11.count());
    }
}
