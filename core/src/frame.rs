//! The values every literal reads during one cycle: each space at t and at t-1.

use crate::bits::Bits;
use crate::symbols::{Literal, Space, Var};

/// Values at t and t-1 of inputs, outputs, observers and auxiliaries.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Frame {
    /// Values at t, indexed by [`Space`].
    pub now: [Bits; 4],
    /// Values at t-1, indexed by [`Space`].
    pub prev: [Bits; 4],
}

impl Frame {
    /// All-zero frame with the given space sizes.
    pub fn new(sizes: [usize; 4]) -> Self {
        Self {
            now: sizes.map(Bits::zeros),
            prev: sizes.map(Bits::zeros),
        }
    }

    /// Value of a variable.
    #[inline]
    pub fn get(&self, var: Var) -> bool {
        let table = if var.prev { &self.prev } else { &self.now };
        table[var.space as usize].get(var.index as usize)
    }

    /// Value of a literal.
    #[inline]
    pub fn literal(&self, lit: Literal) -> bool {
        self.get(lit.var) == lit.positive
    }

    /// The eight tables as word slices: spaces at t (0..4) then at t-1 (4..8).
    #[inline]
    pub fn tables(&self) -> [&[u64]; 8] {
        [
            self.now[0].words(),
            self.now[1].words(),
            self.now[2].words(),
            self.now[3].words(),
            self.prev[0].words(),
            self.prev[1].words(),
            self.prev[2].words(),
            self.prev[3].words(),
        ]
    }

    /// Values at t of a space.
    pub fn now(&self, space: Space) -> &Bits {
        &self.now[space as usize]
    }

    /// Mutable values at t of a space.
    pub fn now_mut(&mut self, space: Space) -> &mut Bits {
        &mut self.now[space as usize]
    }

    /// Values at t-1 of a space.
    pub fn prev(&self, space: Space) -> &Bits {
        &self.prev[space as usize]
    }

    /// Mutable values at t-1 of a space.
    pub fn prev_mut(&mut self, space: Space) -> &mut Bits {
        &mut self.prev[space as usize]
    }

    /// Ends a cycle: the values at t become the values at t-1.
    pub fn shift(&mut self) {
        for s in Space::ALL {
            let i = s as usize;
            let (now, prev) = (&self.now[i], &mut self.prev[i]);
            prev.copy_from(now);
        }
    }
}
