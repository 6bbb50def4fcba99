//! FNV-1a: the one mix behind every state hash of the workspace (the sim's,
//! and the referee's, which folds the sim's in). Fixed and
//! platform-independent: the recordings and the shipped evaluations store
//! its values, so changing it changes every stored hash.

/// An FNV-1a 64-bit hasher over bytes; words go in little-endian.
#[derive(Debug, Clone)]
pub struct StateHasher(u64);

impl Default for StateHasher {
    fn default() -> Self {
        StateHasher::new()
    }
}

impl StateHasher {
    pub fn new() -> StateHasher {
        StateHasher(0xcbf2_9ce4_8422_2325)
    }

    pub fn byte(&mut self, b: u8) {
        self.0 ^= u64::from(b);
        self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
    }

    pub fn u64(&mut self, v: u64) {
        for b in v.to_le_bytes() {
            self.byte(b);
        }
    }

    /// The raw bits of each value.
    pub fn f32s(&mut self, v: &[f32]) {
        for x in v {
            for b in x.to_bits().to_le_bytes() {
                self.byte(b);
            }
        }
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The published FNV-1a 64 test vectors: the mix is the standard one.
    #[test]
    fn fnv1a_64_reference_values() {
        assert_eq!(StateHasher::new().finish(), 0xcbf2_9ce4_8422_2325);
        let mut h = StateHasher::new();
        h.byte(b'a');
        assert_eq!(h.finish(), 0xaf63_dc4c_8601_ec8c);
        let mut h = StateHasher::new();
        for b in *b"foobar" {
            h.byte(b);
        }
        assert_eq!(h.finish(), 0x8594_4171_f739_67e8);
    }
}
