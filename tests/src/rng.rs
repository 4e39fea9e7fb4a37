//! A tiny seeded generator (Marsaglia's xorshift64), so that every test is deterministic
//! without the `rand` crate.

/// xorshift64 (Marsaglia 2003, shifts 13, 7, 17).
#[derive(Debug, Clone)]
pub struct XorShift64 {
    state: u64,
}

impl XorShift64 {
    /// A generator from `seed` (0 is replaced: xorshift needs a non-zero state).
    pub fn new(seed: u64) -> Self {
        XorShift64 {
            state: if seed == 0 {
                0x9E37_79B9_7F4A_7C15
            } else {
                seed
            },
        }
    }

    /// The next 64 bits.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.state;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.state = x;
        x
    }

    /// A value in `0..=max`, uniform (multiply-and-shift; the bias is below 2⁻³² for the
    /// ranges used here).
    pub fn up_to(&mut self, max: u64) -> u64 {
        let span = u128::from(max) + 1;
        ((u128::from(self.next_u64()) * span) >> 64) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_and_in_range() {
        let mut a = XorShift64::new(7);
        let mut b = XorShift64::new(7);
        let xs: Vec<u64> = (0..1000).map(|_| a.up_to(9)).collect();
        let ys: Vec<u64> = (0..1000).map(|_| b.up_to(9)).collect();
        assert_eq!(xs, ys);
        assert!(xs.iter().all(|&x| x <= 9));
        // Every value of a small range comes up.
        for v in 0..=9 {
            assert!(xs.contains(&v), "{v}");
        }
        assert_ne!(XorShift64::new(0).next_u64(), 0);
    }
}
