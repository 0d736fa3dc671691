//! The tag25h9 codebook and bit layout, as in the AprilTag C library 3.3 (`tag25h9.c`, BSD-2):
//! 35 codewords of 25 bits, minimum Hamming distance 9, 7 cells across the black
//! border square, 9 with the white quiet zone.

/// The codewords, index = tag id. Bit `24 - i` of a code is the cell at `BIT_XY[i]`; 1 = white.
pub(super) const CODES: [u64; 35] = [
    0x156f1f4, 0x1f28cd5, 0x16ce32c, 0x1ea379c, 0x1390f89, 0x34fad0, 0x7dcdb5, 0x119ba95, 0x1ae9daa, 0xdf02aa,
    0x82fc15, 0x465123, 0xceee98, 0x1f17260, 0x14429cd, 0x17248a8, 0x16ad452, 0x9670ad, 0x16f65b2, 0xb8322b, 0x5d715b,
    0x1a1c7e7, 0xd7890d, 0x1813522, 0x1c9c611, 0x99e4a4, 0x855234, 0x17b81c0, 0xc294bb, 0x89fae3, 0x44df5f, 0x1360159,
    0xec31e8, 0x1bcc0f6, 0xa64f8d,
];

/// The cell (x, y) of each bit inside the black-border square, most significant bit first.
pub(super) const BIT_XY: [(u8, u8); 25] = [
    (1, 1),
    (2, 1),
    (3, 1),
    (4, 1),
    (2, 2),
    (3, 2),
    (5, 1),
    (5, 2),
    (5, 3),
    (5, 4),
    (4, 2),
    (4, 3),
    (5, 5),
    (4, 5),
    (3, 5),
    (2, 5),
    (4, 4),
    (3, 4),
    (1, 5),
    (1, 4),
    (1, 3),
    (1, 2),
    (2, 4),
    (2, 3),
    (3, 3),
];
