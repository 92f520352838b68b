//! The one stable 64-bit hash of the project, FNV-1a (offset 0xcbf29ce484222325, prime
//! 0x100000001b3), computed by the `fnv` crate's `FnvHasher`: unlike `std`'s
//! `DefaultHasher` it is the same on every build and platform, so it names sweep rows and
//! keys cached stage results, synthesis results and Verilator builds across runs.
//!
//! (`hdl::exhaustive`'s 32-bit FNV fold is not this: it is a checksum the Verilog testbench
//! computes too.)

use ::fnv::FnvHasher;
use std::hash::Hasher;

/// FNV-1a offset basis.
pub const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// The hash of `bytes`.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    Fnv::new().bytes(bytes).finish()
}

/// The hash of `parts`, each followed by a separator byte (so `["ab", "c"]` and `["a", "bc"]`
/// differ): the key of synthesis and Verilator caches.
pub fn fnv1a_parts(parts: &[&[u8]]) -> u64 {
    parts.iter().fold(Fnv::new(), |h, p| h.part(p)).finish()
}

/// An incremental FNV-1a hash (a copyable value: `FnvHasher` is resumed from it per call).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv {
    /// An empty hash.
    pub const fn new() -> Self {
        Fnv(OFFSET)
    }
    /// Adds bytes.
    pub fn bytes(self, bytes: &[u8]) -> Self {
        let mut h = FnvHasher::with_key(self.0);
        h.write(bytes);
        Fnv(h.finish())
    }
    /// Adds a `u64` (little-endian bytes on every platform).
    pub fn u64(self, v: u64) -> Self {
        self.bytes(&v.to_le_bytes())
    }
    /// Adds bytes and a separator byte `0xff`.
    pub fn part(self, bytes: &[u8]) -> Self {
        self.bytes(bytes).bytes(&[0xff])
    }
    /// Adds a string and a separator (so `"ab", "c"` and `"a", "bc"` differ).
    pub fn str(self, s: &str) -> Self {
        self.part(s.as_bytes())
    }
    /// The hash.
    pub const fn finish(self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hand-written FNV-1a 64 the crate replaced: every id and key must stay the same.
    fn by_hand(bytes: &[u8]) -> u64 {
        bytes.iter().fold(OFFSET, |h, &b| {
            (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
        })
    }

    #[test]
    fn known_values() {
        // Published FNV-1a test vectors.
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
        assert_ne!(Fnv::new().str("ab").str("c"), Fnv::new().str("a").str("bc"));
    }

    #[test]
    fn same_as_the_hand_written_hash() {
        let text: Vec<u8> = (0..=255u8)
            .chain(b"igemu sweep row".iter().copied())
            .collect();
        for n in 0..text.len() {
            assert_eq!(fnv1a(&text[..n]), by_hand(&text[..n]));
        }
        assert_eq!(
            Fnv::new().u64(0x0123_4567_89ab_cdef).str("gamma").finish(),
            by_hand(b"\xef\xcd\xab\x89\x67\x45\x23\x01gamma\xff")
        );
        assert_eq!(
            fnv1a_parts(&[b"module", b"", b"W=8"]),
            by_hand(b"module\xff\xffW=8\xff")
        );
    }
}
