//! A small growable bit set used for I/O images (inputs, outputs, observers, auxiliaries).

use serde::{Deserialize, Serialize};

/// A fixed-length vector of booleans packed in 64-bit words.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Bits {
    len: usize,
    words: Vec<u64>,
}

impl Bits {
    /// `len` bits, all zero.
    pub fn zeros(len: usize) -> Self {
        Self {
            len,
            words: vec![0; len.div_ceil(64)],
        }
    }

    /// Builds a bit set from booleans.
    pub fn from_bools(values: &[bool]) -> Self {
        let mut bits = Self::zeros(values.len());
        for (i, &v) in values.iter().enumerate() {
            bits.set(i, v);
        }
        bits
    }

    /// Number of bits.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the set has no bits at all.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Value of bit `i`; bits past the end read as zero.
    #[inline]
    pub fn get(&self, i: usize) -> bool {
        self.words
            .get(i / 64)
            .is_some_and(|w| (w >> (i % 64)) & 1 == 1)
    }

    /// The packed 64-bit words, bit `i` at `words()[i / 64] >> (i % 64)`.
    #[inline]
    pub fn words(&self) -> &[u64] {
        &self.words
    }

    /// Sets bit `i`; writes past the end are ignored.
    #[inline]
    pub fn set(&mut self, i: usize, value: bool) {
        if i >= self.len {
            return;
        }
        if let Some(w) = self.words.get_mut(i / 64) {
            let mask = 1u64 << (i % 64);
            if value {
                *w |= mask;
            } else {
                *w &= !mask;
            }
        }
    }

    /// Sets every bit to zero.
    pub fn clear(&mut self) {
        self.words.iter_mut().for_each(|w| *w = 0);
    }

    /// Copies `other` into `self` without reallocating when the lengths match.
    pub fn copy_from(&mut self, other: &Self) {
        if self.len == other.len {
            self.words.copy_from_slice(&other.words);
        } else {
            self.clone_from(other);
        }
    }

    /// Number of bits set.
    pub fn count_ones(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// The bits as booleans.
    pub fn to_bools(&self) -> Vec<bool> {
        (0..self.len).map(|i| self.get(i)).collect()
    }

    /// Indices of the bits set, ascending, skipping zero words.
    pub fn ones_fast(&self) -> impl Iterator<Item = usize> + '_ {
        self.words.iter().enumerate().flat_map(|(w, &word)| {
            let mut rest = word;
            std::iter::from_fn(move || {
                if rest == 0 {
                    return None;
                }
                let b = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                Some(w * 64 + b)
            })
        })
    }

    /// Indices of the bits set, ascending.
    pub fn ones(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.len).filter(|&i| self.get(i))
    }
}

impl std::fmt::Display for Bits {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for i in 0..self.len {
            f.write_str(if self.get(i) { "1" } else { "0" })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Bits;

    #[test]
    fn set_get_and_bounds() {
        let mut b = Bits::zeros(130);
        b.set(0, true);
        b.set(64, true);
        b.set(129, true);
        b.set(500, true);
        assert!(b.get(0) && b.get(64) && b.get(129));
        assert!(!b.get(1) && !b.get(500));
        assert_eq!(b.count_ones(), 3);
        assert_eq!(b.ones().collect::<Vec<_>>(), vec![0, 64, 129]);
        b.set(64, false);
        assert_eq!(b.count_ones(), 2);
    }
}
