//! The robust safety filter: constraint evaluation at the end of each PLC cycle and the
//! fallback output vector computed with priority to zero.
//!
//! ## Fallback rule
//! When a trip latches, every output is recomputed (the commanded values are ignored):
//! the fallback is an output vector that makes every constraint 0 in the current
//! context (inputs, observers, auxiliaries, previous outputs) and has as few outputs ON
//! as possible. Among vectors with the same number of ONs, the tie-break is
//! lexicographic in output order with 0 before 1: the first output (A0) is kept OFF
//! whenever some minimal vector allows it, then the second, and so on.
//!
//! Each active product term gives a *nogood*: a partial output assignment that is
//! forbidden. Unit nogoods (simple constraints) fix an output directly; the rest is a
//! small minimum-ones search (DPLL with unit propagation and branch and bound) over
//! the outputs of the active combined terms.

use crate::bits::Bits;
use crate::constraints::{Class, ConstraintSet};
use crate::frame::Frame;
use crate::symbols::{Literal, Space};

/// A compiled product term: its context literals and its literals on outputs at t.
#[derive(Clone, Debug)]
struct Term {
    constraint: u32,
    context: Vec<Literal>,
    outputs: Vec<(u32, bool)>,
}

/// The constraint set compiled for evaluation.
#[derive(Clone, Debug)]
pub struct Filter {
    terms: Vec<Term>,
    /// (id, class) per constraint, in file order.
    ids: Vec<(String, Class)>,
    n_outputs: usize,
    /// Largest number of search nodes for one fallback before the best vector found so far
    /// is used.
    pub search_budget: usize,
}

/// Why no fallback vector exists.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("no output vector satisfies every constraint: {}", constraints.join(", "))]
pub struct SpecError {
    /// Ids of the constraints whose active terms conflict.
    pub constraints: Vec<String>,
}

impl Filter {
    /// Compiles a constraint set for `n_outputs` outputs.
    pub fn new(set: &ConstraintSet, n_outputs: usize) -> Self {
        let mut terms = Vec::new();
        for (ci, c) in set.constraints.iter().enumerate() {
            for term in &c.dnf {
                let mut context = Vec::new();
                let mut outputs = Vec::new();
                for l in term {
                    if l.var.space == Space::Output && !l.var.prev {
                        outputs.push((l.var.index, l.positive));
                    } else {
                        context.push(*l);
                    }
                }
                terms.push(Term {
                    constraint: u32::try_from(ci).unwrap_or(u32::MAX),
                    context,
                    outputs,
                });
            }
        }
        Self {
            terms,
            ids: set
                .constraints
                .iter()
                .map(|c| (c.id.clone(), c.class))
                .collect(),
            n_outputs,
            search_budget: 100_000,
        }
    }

    /// Number of constraints.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when there is no constraint.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Id of constraint `i`.
    pub fn id(&self, i: usize) -> &str {
        self.ids.get(i).map_or("?", |(id, _)| id.as_str())
    }

    /// Class of constraint `i`.
    pub fn class(&self, i: usize) -> Class {
        self.ids.get(i).map_or(Class::Simple, |(_, c)| *c)
    }

    /// Indices of the constraints that are true in `frame` (outputs at t read from
    /// `frame.now[Output]`), ascending, appended to `out`.
    pub fn violations_into(&self, frame: &Frame, out: &mut Vec<usize>) {
        out.clear();
        let outs = frame.now(Space::Output);
        for t in &self.terms {
            let ci = t.constraint as usize;
            if out.last() == Some(&ci) {
                continue;
            }
            if t.outputs.iter().all(|&(k, v)| outs.get(k as usize) == v)
                && t.context.iter().all(|&l| frame.literal(l))
            {
                out.push(ci);
            }
        }
    }

    /// Indices of the constraints that are true in `frame`.
    pub fn violations(&self, frame: &Frame) -> Vec<usize> {
        let mut v = Vec::new();
        self.violations_into(frame, &mut v);
        v
    }

    /// The literals of the first true product term of constraint `ci`, if it is true.
    pub fn true_term(&self, ci: usize, frame: &Frame) -> Option<Vec<Literal>> {
        let outs = frame.now(Space::Output);
        self.terms
            .iter()
            .filter(|t| t.constraint as usize == ci)
            .find(|t| {
                t.outputs.iter().all(|&(k, v)| outs.get(k as usize) == v)
                    && t.context.iter().all(|&l| frame.literal(l))
            })
            .map(|t| {
                let mut lits = t.context.clone();
                lits.extend(t.outputs.iter().map(|&(k, v)| Literal {
                    var: crate::symbols::Var {
                        space: Space::Output,
                        index: k,
                        prev: false,
                    },
                    positive: v,
                }));
                lits.sort();
                lits
            })
    }

    /// The fallback output vector for the context of `frame` (its outputs at t are
    /// ignored), see the module documentation.
    pub fn fallback(&self, frame: &Frame) -> Result<Bits, SpecError> {
        let active: Vec<&Term> = self
            .terms
            .iter()
            .filter(|t| t.context.iter().all(|&l| frame.literal(l)))
            .collect();
        solve_min_ones(self.n_outputs, &active, self.search_budget).ok_or_else(|| {
            let mut ids: Vec<String> = active
                .iter()
                .map(|t| self.id(t.constraint as usize).to_string())
                .collect();
            ids.sort();
            ids.dedup();
            SpecError { constraints: ids }
        })
    }
}

/// Minimum-ones assignment avoiding every nogood; `None` when none exists.
fn solve_min_ones(n_outputs: usize, active: &[&Term], budget: usize) -> Option<Bits> {
    let mut fixed: Vec<Option<bool>> = vec![None; n_outputs];
    // Unit nogoods first: they fix outputs directly.
    for t in active {
        if let [(k, v)] = t.outputs.as_slice() {
            let k = *k as usize;
            let want = !*v;
            match fixed.get(k).copied().flatten() {
                Some(prev) if prev != want => return None,
                _ => {
                    if let Some(slot) = fixed.get_mut(k) {
                        *slot = Some(want);
                    }
                }
            }
        }
    }
    // Remaining nogoods not already satisfied by the fixed outputs.
    let rest: Vec<&[(u32, bool)]> = active
        .iter()
        .filter(|t| t.outputs.len() > 1)
        .map(|t| t.outputs.as_slice())
        .filter(|ng| {
            !ng.iter()
                .any(|&(k, v)| fixed.get(k as usize).copied().flatten() == Some(!v))
        })
        .collect();
    let mut result = Bits::zeros(n_outputs);
    if rest.is_empty() {
        for (k, f) in fixed.iter().enumerate() {
            result.set(k, f.unwrap_or(false));
        }
        return Some(result);
    }
    let mut search = Search {
        nogoods: rest,
        best: None,
        best_ones: usize::MAX,
        nodes: 0,
        budget,
    };
    search.dfs(&mut fixed);
    let best = search.best?;
    for (k, f) in best.iter().enumerate() {
        result.set(k, f.unwrap_or(false));
    }
    Some(result)
}

struct Search<'a> {
    nogoods: Vec<&'a [(u32, bool)]>,
    best: Option<Vec<Option<bool>>>,
    best_ones: usize,
    nodes: usize,
    budget: usize,
}

impl Search<'_> {
    /// Unit propagation; returns false on conflict. Unassigned outputs not named in any
    /// open nogood are left unassigned (they default to 0).
    fn propagate(&self, a: &mut [Option<bool>]) -> bool {
        loop {
            let mut changed = false;
            for ng in &self.nogoods {
                let mut unassigned = None;
                let mut open = 0;
                let mut satisfied = false;
                for &(k, v) in *ng {
                    match a.get(k as usize).copied().flatten() {
                        Some(x) if x != v => {
                            satisfied = true;
                            break;
                        }
                        Some(_) => {}
                        None => {
                            open += 1;
                            unassigned = Some((k, v));
                        }
                    }
                }
                if satisfied {
                    continue;
                }
                match (open, unassigned) {
                    (0, _) => return false,
                    (1, Some((k, v))) => {
                        if let Some(slot) = a.get_mut(k as usize) {
                            *slot = Some(!v);
                            changed = true;
                        }
                    }
                    _ => {}
                }
            }
            if !changed {
                return true;
            }
        }
    }

    fn dfs(&mut self, a: &mut [Option<bool>]) {
        let a: &[Option<bool>] = a;
        self.nodes += 1;
        if self.nodes > self.budget && self.best.is_some() {
            return;
        }
        let mut local = a.to_vec();
        if !self.propagate(&mut local) {
            return;
        }
        let ones = local.iter().filter(|x| **x == Some(true)).count();
        if ones >= self.best_ones {
            return;
        }
        // Branch on the lowest output named by a nogood that is still open.
        let next = self
            .nogoods
            .iter()
            .filter(|ng| {
                !ng.iter()
                    .any(|&(k, v)| local.get(k as usize).copied().flatten() == Some(!v))
            })
            .flat_map(|ng| ng.iter().map(|&(k, _)| k as usize))
            .filter(|&k| local.get(k).copied().flatten().is_none())
            .min();
        let Some(k) = next else {
            // Every nogood is satisfied: unassigned outputs default to 0, which cannot
            // complete an open nogood since none is open.
            self.best_ones = ones;
            self.best = Some(local);
            return;
        };
        for value in [false, true] {
            let mut branch = local.clone();
            branch[k] = Some(value);
            self.dfs(&mut branch);
        }
    }
}

#[cfg(test)]
mod tests;
