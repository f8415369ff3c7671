//! XXH64 (Yann Collet's xxHash, 64 bit, seed 0): the scenario hash's function, streamed.
//!
//! Four lanes take 8 bytes each from every 32-byte stripe,
//!
//! ```text
//! round(acc, w) = rotl(acc + w·P2, 31)·P1
//! ```
//!
//! so the four multiply chains run side by side, where FNV-1a's one chain of `(h ^ b)·P`
//! waits about 4 cycles a byte (4 ms for a 2.9 MB program). Then the lanes merge, the
//! length and the tail (8, 4 and 1 bytes at a time) go in, and an avalanche mixes the bits.
//! The specification is in the xxHash repository (Cyan4973/xxHash, its `doc` folder); the
//! tests check the published values. Not for security.

const P1: u64 = 0x9E37_79B1_85EB_CA87;
const P2: u64 = 0xC2B2_AE3D_27D4_EB4F;
const P3: u64 = 0x1656_67B1_9E37_79F9;
const P4: u64 = 0x85EB_CA77_C2B2_AE63;
const P5: u64 = 0x27D4_EB2F_1656_67C5;

/// The running state: four lanes, the bytes of an unfinished stripe, the length so far.
pub struct Xxh64 {
    lanes: [u64; 4],
    stripe: [u8; 32],
    /// Bytes held in `stripe`.
    held: usize,
    /// Bytes written in all.
    length: u64,
}

impl Default for Xxh64 {
    fn default() -> Self {
        Xxh64::new()
    }
}

#[inline(always)]
fn round(acc: u64, word: u64) -> u64 {
    acc.wrapping_add(word.wrapping_mul(P2))
        .rotate_left(31)
        .wrapping_mul(P1)
}

#[inline(always)]
fn word(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
}

impl Xxh64 {
    /// The state for seed 0.
    pub fn new() -> Self {
        Xxh64 {
            lanes: [P1.wrapping_add(P2), P2, 0, P1.wrapping_neg()],
            stripe: [0; 32],
            held: 0,
            length: 0,
        }
    }

    /// Adds `bytes`; pieces of any size give the hash of their concatenation.
    pub fn write(&mut self, mut bytes: &[u8]) {
        self.length += bytes.len() as u64;
        if self.held > 0 {
            let take = (32 - self.held).min(bytes.len());
            self.stripe[self.held..self.held + take].copy_from_slice(&bytes[..take]);
            self.held += take;
            bytes = &bytes[take..];
            if self.held < 32 {
                return;
            }
            let stripe = self.stripe;
            self.stripes(&stripe);
            self.held = 0;
        }
        let whole = bytes.len() / 32 * 32;
        self.stripes(&bytes[..whole]);
        let rest = &bytes[whole..];
        self.stripe[..rest.len()].copy_from_slice(rest);
        self.held = rest.len();
    }

    /// The lanes over whole 32-byte stripes.
    fn stripes(&mut self, bytes: &[u8]) {
        let [mut v1, mut v2, mut v3, mut v4] = self.lanes;
        for s in bytes.chunks_exact(32) {
            v1 = round(v1, word(s, 0));
            v2 = round(v2, word(s, 8));
            v3 = round(v3, word(s, 16));
            v4 = round(v4, word(s, 24));
        }
        self.lanes = [v1, v2, v3, v4];
    }

    /// The hash of everything written.
    pub fn finish(&self) -> u64 {
        let [v1, v2, v3, v4] = self.lanes;
        let mut h = if self.length >= 32 {
            let mut h = v1
                .rotate_left(1)
                .wrapping_add(v2.rotate_left(7))
                .wrapping_add(v3.rotate_left(12))
                .wrapping_add(v4.rotate_left(18));
            for v in [v1, v2, v3, v4] {
                h = (h ^ round(0, v)).wrapping_mul(P1).wrapping_add(P4);
            }
            h
        } else {
            P5
        };
        h = h.wrapping_add(self.length);
        let tail = &self.stripe[..self.held];
        let mut at = 0;
        while at + 8 <= tail.len() {
            h = (h ^ round(0, word(tail, at)))
                .rotate_left(27)
                .wrapping_mul(P1)
                .wrapping_add(P4);
            at += 8;
        }
        if at + 4 <= tail.len() {
            let w = u32::from_le_bytes(tail[at..at + 4].try_into().expect("4 bytes"));
            h = (h ^ (w as u64).wrapping_mul(P1))
                .rotate_left(23)
                .wrapping_mul(P2)
                .wrapping_add(P3);
            at += 4;
        }
        for &b in &tail[at..] {
            h = (h ^ (b as u64).wrapping_mul(P5))
                .rotate_left(11)
                .wrapping_mul(P1);
        }
        h ^= h >> 33;
        h = h.wrapping_mul(P2);
        h ^= h >> 29;
        h = h.wrapping_mul(P3);
        h ^ (h >> 32)
    }
}

#[cfg(test)]
mod tests {
    use super::Xxh64;

    fn xxh64(bytes: &[u8]) -> u64 {
        let mut h = Xxh64::new();
        h.write(bytes);
        h.finish()
    }

    /// The values xxHash publishes (and its Python binding, `xxhash.xxh64(data, 0)`, gives).
    #[test]
    fn published_values() {
        assert_eq!(xxh64(b""), 0xef46_db37_51d8_e999);
        assert_eq!(xxh64(b"a"), 0xd24e_c4f1_a98c_6e5b);
        assert_eq!(xxh64(b"abc"), 0x44bc_2cf5_ad77_0999);
        // 39 bytes: one stripe, then 8-, 4- and 1-byte tails.
        assert_eq!(
            xxh64(b"Nobody inspects the spammish repetition"),
            0xfbce_a83c_8a37_8bf1
        );
        // 768 bytes 0, 1, ..., 255 three times (from the Python binding).
        let bytes: Vec<u8> = (0..768).map(|i| i as u8).collect();
        assert_eq!(xxh64(&bytes), 0x8e03_c838_c596_036f);
    }

    /// Written in pieces of every size from 1 to 70 bytes, 768 bytes hash as in one piece.
    #[test]
    fn pieces_of_any_size_hash_as_the_whole() {
        let bytes: Vec<u8> = (0..768).map(|i| i as u8).collect();
        for piece in 1..=70 {
            let mut h = Xxh64::new();
            for chunk in bytes.chunks(piece) {
                h.write(chunk);
            }
            assert_eq!(h.finish(), 0x8e03_c838_c596_036f, "pieces of {piece}");
        }
    }
}
