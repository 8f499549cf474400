//! Packed evaluation of sums of products over one flat word array holding every
//! program variable at t and at t-1 (the per-scan hot path).

use crate::expr::Dnf;
use crate::symbols::{Space, Var};

/// Where each space sits in the flat state: all spaces at t, then all at t-1.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    off: [[usize; 4]; 2],
    /// Words at t (the state is twice this long).
    pub(crate) half: usize,
}

impl Layout {
    pub(crate) fn new(sizes: [usize; 4]) -> Self {
        let mut off = [[0; 4]; 2];
        let mut at = 0;
        for (o, size) in off[0].iter_mut().zip(sizes) {
            *o = at;
            at += size.div_ceil(64);
        }
        let now = off[0];
        for (o, n) in off[1].iter_mut().zip(now) {
            *o = n + at;
        }
        Self { off, half: at }
    }

    /// Word index and mask of a variable.
    #[inline]
    pub(crate) fn locate(&self, space: Space, index: usize, prev: bool) -> (usize, u64) {
        (
            self.off[usize::from(prev)][space as usize] + index / 64,
            1u64 << (index % 64),
        )
    }

    fn var(&self, v: Var) -> (usize, u64) {
        self.locate(v.space, v.index as usize, v.prev)
    }
}

/// One word test of a product term: the `ones` bits set and the `zeros` bits clear.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Check {
    word: u32,
    ones: u64,
    zeros: u64,
}

/// A compiled expression: a range of terms in [`Conds`].
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Cond {
    start: u32,
    end: u32,
}

/// Every compiled expression of a program, flattened.
#[derive(Clone, Debug, Default)]
pub(crate) struct Conds {
    terms: Vec<(u32, u32)>,
    checks: Vec<Check>,
}

impl Conds {
    /// Compiles a sum of products.
    pub(crate) fn add(&mut self, dnf: &Dnf, layout: &Layout) -> Cond {
        let start = self.terms.len();
        for term in dnf {
            let first = self.checks.len();
            for lit in term {
                let (word, mask) = layout.var(lit.var);
                let word = u32::try_from(word).unwrap_or(u32::MAX);
                let k = match self.checks[first..].iter().position(|c| c.word == word) {
                    Some(k) => first + k,
                    None => {
                        self.checks.push(Check {
                            word,
                            ones: 0,
                            zeros: 0,
                        });
                        self.checks.len() - 1
                    }
                };
                if lit.positive {
                    self.checks[k].ones |= mask;
                } else {
                    self.checks[k].zeros |= mask;
                }
            }
            self.terms.push((to_u32(first), to_u32(self.checks.len())));
        }
        Cond {
            start: to_u32(start),
            end: to_u32(self.terms.len()),
        }
    }

    /// A product of positive variables at t (an enabling condition).
    pub(crate) fn add_all(&mut self, vars: &[(usize, u64)]) -> Cond {
        let start = self.terms.len();
        let first = self.checks.len();
        for &(word, mask) in vars {
            self.checks.push(Check {
                word: to_u32(word),
                ones: mask,
                zeros: 0,
            });
        }
        self.terms.push((to_u32(first), to_u32(self.checks.len())));
        Cond {
            start: to_u32(start),
            end: to_u32(self.terms.len()),
        }
    }

    /// Evaluates a compiled expression over the flat state.
    #[inline]
    pub(crate) fn eval(&self, c: Cond, state: &[u64]) -> bool {
        let terms = self
            .terms
            .get(c.start as usize..c.end as usize)
            .unwrap_or(&[]);
        terms.iter().any(|&(a, b)| {
            self.checks
                .get(a as usize..b as usize)
                .unwrap_or(&[])
                .iter()
                .all(|k| {
                    let w = state.get(k.word as usize).copied().unwrap_or(0);
                    w & k.ones == k.ones && w & k.zeros == 0
                })
        })
    }
}

fn to_u32(x: usize) -> u32 {
    u32::try_from(x).unwrap_or(u32::MAX)
}
