//! Searching a line 8 bytes at a time (lines are short: a vectorised search spends more in
//! its set-up and reduction than in the search; docs/performance.md).
//!
//! With `v` a word XOR eight copies of the byte sought, a byte of
//!
//! ```text
//! (v − 0x01…01) & !v & 0x80…80
//! ```
//!
//! is set at every zero byte of `v`, so at every place the byte sought stands, and can be set
//! falsely only above a true one (the borrow runs upward): the lowest set byte is the first
//! place, and a word holds the byte when the result is nonzero.

/// Eight bytes of 1.
pub(crate) const ONES: u64 = 0x0101_0101_0101_0101;
/// The high bit of each of eight bytes.
pub(crate) const HIGHS: u64 = 0x8080_8080_8080_8080;

/// The 8 bytes of `chunk` as a little-endian word (byte 0 lowest).
#[inline(always)]
pub(crate) fn load(chunk: &[u8]) -> u64 {
    let mut word = [0u8; 8];
    word.copy_from_slice(chunk);
    u64::from_le_bytes(word)
}

/// The high bit set in each byte of `w` that equals `byte` (and, falsely, possibly above
/// one that does).
#[inline(always)]
pub(crate) fn bytes_equal(w: u64, byte: u8) -> u64 {
    let v = w ^ (ONES * byte as u64);
    v.wrapping_sub(ONES) & !v & HIGHS
}

/// The index (0-7) of the lowest set byte of a nonzero `found`.
#[inline(always)]
pub(crate) fn first_byte(found: u64) -> usize {
    (found.trailing_zeros() / 8) as usize
}

/// The bits of `w` below the lowest set bit of a nonzero `found` (its byte excluded).
#[inline(always)]
pub(crate) fn below_first(w: u64, found: u64) -> u64 {
    w & ((found & found.wrapping_neg()) - 1)
}
