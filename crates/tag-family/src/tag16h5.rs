//! The tag16h5 codebook and bit layout, as in the AprilTag C library 3.3 (`tag16h5.c`, BSD-2):
//! 30 codewords of 16 bits, minimum Hamming distance 5, 6 cells across the black
//! border square, 8 with the white quiet zone.

/// The codewords, index = tag id. Bit `15 - i` of a code is the cell at `BIT_XY[i]`; 1 = white.
pub(super) const CODES: [u64; 30] = [
    0x27c8, 0x31b6, 0x3859, 0x569c, 0x6c76, 0x7ddb, 0xaf09, 0xf5a1, 0xfb8b, 0x1cb9, 0x28ca, 0xe8dc, 0x1426, 0x5770,
    0x9253, 0xb702, 0x63a, 0x8f34, 0xb4c0, 0x51ec, 0xe6f0, 0x5fa4, 0xdd43, 0x1aaa, 0xe62f, 0x6dbc, 0xb6eb, 0xde10,
    0x154d, 0xb57a,
];

/// The cell (x, y) of each bit inside the black-border square, most significant bit first.
pub(super) const BIT_XY: [(u8, u8); 16] = [
    (1, 1),
    (2, 1),
    (3, 1),
    (2, 2),
    (4, 1),
    (4, 2),
    (4, 3),
    (3, 2),
    (4, 4),
    (3, 4),
    (2, 4),
    (3, 3),
    (1, 4),
    (1, 3),
    (1, 2),
    (2, 3),
];
