//! The robust safety filter: constraint evaluation at the end of each PLC cycle and the
//! fallback output vector computed with priority to zero.
//!
//! ## Fallback rule
//! When a trip latches, every output is recomputed (the commanded values are ignored):
//! the fallback is an output vector that makes every constraint 0 in the current
//! context (inputs, observers, auxiliaries, previous outputs) and has as few outputs
//! away from their *safe value* as possible. The safe value of an output is declared in
//! `plant.ron` (`safe: Zero`, the paper's priority to zero and the default; `One`, for
//! an actuator that moves when its output is 0; `Hold`, the value applied in the
//! previous cycle). Among vectors with the same number of outputs away from their safe
//! value, the tie-break is lexicographic in output order, the safe value first: the
//! first output (A0) is kept at its safe value whenever some minimal vector allows it,
//! then the second, and so on. With every safe value `Zero` this is the minimum number
//! of outputs ON, then 0 before 1.
//!
//! When no vector satisfies every constraint (a specification error), every output
//! takes its safe value and the error names a smallest set of conflicting constraints
//! (no constraint can be left out of it and the rest still conflict).
//!
//! Each active product term gives a *nogood*: a partial output assignment that is
//! forbidden. Unit nogoods (simple constraints) fix an output directly; the rest is a
//! small minimum-ones search (DPLL with unit propagation and branch and bound) over
//! the outputs of the active combined terms.

use crate::bits::Bits;
use crate::constraints::{Class, ConstraintSet};
use crate::frame::Frame;
use crate::plant::SafeValue;
use crate::symbols::{Literal, Space};

/// A compiled product term: its context literals and its literals on outputs at t.
#[derive(Clone, Debug)]
struct Term {
    constraint: u32,
    context: Vec<Literal>,
    outputs: Vec<(u32, bool)>,
}

/// A literal compiled to a word and bit of one of the frame's eight tables.
#[derive(Clone, Copy, Debug)]
struct Packed {
    table: u8,
    bit: u8,
    positive: bool,
    word: u32,
}

impl Packed {
    fn new(l: Literal) -> Self {
        Self {
            table: l.var.space as u8 + if l.var.prev { 4 } else { 0 },
            bit: (l.var.index % 64) as u8,
            positive: l.positive,
            word: l.var.index / 64,
        }
    }

    #[inline]
    fn holds(self, tables: &[&[u64]; 8]) -> bool {
        let word = tables[usize::from(self.table & 7)]
            .get(self.word as usize)
            .copied()
            .unwrap_or(0);
        ((word >> self.bit) & 1 == 1) == self.positive
    }
}

/// The constraint set compiled for evaluation.
#[derive(Clone, Debug)]
pub struct Filter {
    terms: Vec<Term>,
    /// Every term's literals, outputs at t first (they reject most terms at once).
    packed: Vec<Packed>,
    /// Per term: start in `packed`, number of output literals, total length.
    spans: Vec<(u32, u16, u16)>,
    /// (id, class) per constraint, in file order.
    ids: Vec<(String, Class)>,
    n_outputs: usize,
    /// The safe value of every output (all `Zero` unless [`Filter::with_safe_values`]).
    safe: Vec<SafeValue>,
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
        let mut packed = Vec::new();
        let mut spans = Vec::with_capacity(terms.len());
        for t in &terms {
            let start = u32::try_from(packed.len()).unwrap_or(u32::MAX);
            for &(k, v) in &t.outputs {
                packed.push(Packed::new(Literal {
                    var: crate::symbols::Var {
                        space: Space::Output,
                        index: k,
                        prev: false,
                    },
                    positive: v,
                }));
            }
            packed.extend(t.context.iter().map(|&l| Packed::new(l)));
            let n_out = u16::try_from(t.outputs.len()).unwrap_or(u16::MAX);
            let len = u16::try_from(t.outputs.len() + t.context.len()).unwrap_or(u16::MAX);
            spans.push((start, n_out, len));
        }
        Self {
            terms,
            packed,
            spans,
            ids: set
                .constraints
                .iter()
                .map(|c| (c.id.clone(), c.class))
                .collect(),
            n_outputs,
            safe: vec![SafeValue::Zero; n_outputs],
            search_budget: 100_000,
        }
    }

    /// Compiles a constraint set for a plant's outputs, with their safe values.
    pub fn for_plant(set: &ConstraintSet, plant: &crate::plant::Plant) -> Self {
        Self::new(set, plant.outputs.len())
            .with_safe_values(plant.outputs.iter().map(|s| s.safe).collect())
    }

    /// Sets the safe value of every output (missing ones are `Zero`).
    #[must_use]
    pub fn with_safe_values(mut self, mut safe: Vec<SafeValue>) -> Self {
        safe.resize(self.n_outputs, SafeValue::Zero);
        self.safe = safe;
        self
    }

    /// The safe values.
    pub fn safe_values(&self) -> &[SafeValue] {
        &self.safe
    }

    /// The safe vector in the context of `frame`: each output at its safe value (`Hold`
    /// reads the output applied in the previous cycle). The fallback's preference, and
    /// the outputs when no fallback exists.
    pub fn safe_vector(&self, frame: &Frame) -> Bits {
        safe_vector(&self.safe, frame)
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
        let tables = frame.tables();
        for (t, &(start, _, len)) in self.terms.iter().zip(&self.spans) {
            let ci = t.constraint as usize;
            if out.last() == Some(&ci) {
                continue;
            }
            let start = start as usize;
            let lits = self
                .packed
                .get(start..start + usize::from(len))
                .unwrap_or(&[]);
            if lits.iter().all(|p| p.holds(&tables)) {
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

    /// The simple constraints that force output `k` ON in the context of `frame`, each
    /// rendered with the literals that make it act, e.g. `CSs10 (C7=1)`.
    pub fn forcing_on(
        &self,
        k: usize,
        frame: &Frame,
        symbols: &crate::symbols::Symbols,
    ) -> Vec<String> {
        let mut out = Vec::new();
        for t in &self.terms {
            if t.outputs.as_slice() != [(u32::try_from(k).unwrap_or(u32::MAX), false)] {
                continue;
            }
            if !t.context.iter().all(|&l| frame.literal(l)) {
                continue;
            }
            let why: Vec<String> = t
                .context
                .iter()
                .map(|l| {
                    let name = symbols.render_literal(Literal {
                        positive: true,
                        ..*l
                    });
                    format!("{name}={}", u8::from(l.positive))
                })
                .collect();
            let text = format!("{} ({})", self.id(t.constraint as usize), why.join(", "));
            if !out.contains(&text) {
                out.push(text);
            }
        }
        out
    }

    /// The fallback output vector for the context of `frame` (its outputs at t are
    /// ignored), see the module documentation.
    pub fn fallback(&self, frame: &Frame) -> Result<Bits, SpecError> {
        let tables = frame.tables();
        let mut active: Vec<&Term> = Vec::new();
        for (t, &(start, n_out, len)) in self.terms.iter().zip(&self.spans) {
            let from = start as usize + usize::from(n_out);
            let to = start as usize + usize::from(len);
            let context = self.packed.get(from..to).unwrap_or(&[]);
            // Branch-free conjunction: context literals are unpredictable, so one branch
            // per term beats one per literal.
            if context.iter().fold(true, |acc, p| acc & p.holds(&tables)) {
                active.push(t);
            }
        }
        self.solve_in(&active, frame)
    }

    /// The search on the active terms in the context of `frame` (priority to zero, the
    /// common case, without building the safe vector).
    fn solve_in(&self, active: &[&Term], frame: &Frame) -> Result<Bits, SpecError> {
        if self.safe.iter().all(|s| *s == SafeValue::Zero) {
            return solve_min_ones(self.n_outputs, active, self.search_budget)
                .ok_or_else(|| self.conflict(active));
        }
        self.solve(active, &self.safe_vector(frame))
    }

    /// The search on the active terms, with every output's literals read relative to
    /// its safe value (`prefer`): the fewest outputs away from it, then lexicographic.
    fn solve(&self, active: &[&Term], prefer: &Bits) -> Result<Bits, SpecError> {
        if prefer.count_ones() == 0 {
            return solve_min_ones(self.n_outputs, active, self.search_budget)
                .ok_or_else(|| self.conflict(active));
        }
        let flipped: Vec<Term> = active
            .iter()
            .map(|t| Term {
                constraint: t.constraint,
                context: Vec::new(),
                outputs: t
                    .outputs
                    .iter()
                    .map(|&(k, v)| (k, v != prefer.get(k as usize)))
                    .collect(),
            })
            .collect();
        let refs: Vec<&Term> = flipped.iter().collect();
        match solve_min_ones(self.n_outputs, &refs, self.search_budget) {
            Some(mut away) => {
                for k in 0..self.n_outputs {
                    away.set(k, away.get(k) != prefer.get(k));
                }
                Ok(away)
            }
            None => Err(self.conflict(&refs)),
        }
    }

    /// A smallest set of conflicting constraints among `active` (deletion: a term is
    /// left out whenever the rest still conflict), sorted by id.
    fn conflict(&self, active: &[&Term]) -> SpecError {
        let mut core: Vec<&Term> = active.to_vec();
        let mut i = 0;
        while i < core.len() {
            let mut without = core.clone();
            without.remove(i);
            if solve_min_ones(self.n_outputs, &without, self.search_budget).is_none() {
                core = without;
            } else {
                i += 1;
            }
        }
        let mut ids: Vec<String> = core
            .iter()
            .map(|t| self.id(t.constraint as usize).to_string())
            .collect();
        ids.sort();
        ids.dedup();
        SpecError { constraints: ids }
    }
}

/// Each output at its safe value in the context of `frame` (`Hold` reads the output
/// applied in the previous cycle).
pub fn safe_vector(safe: &[SafeValue], frame: &Frame) -> Bits {
    let mut out = Bits::zeros(safe.len());
    let prev = frame.prev(Space::Output);
    for (k, s) in safe.iter().enumerate() {
        let v = match s {
            SafeValue::Zero => false,
            SafeValue::One => true,
            SafeValue::Hold => prev.get(k),
        };
        out.set(k, v);
    }
    out
}

/// Incremental evaluation state for one [`Filter`]: the number of false context literals
/// of every term, updated from the bits that changed since the last cycle. A PLC cycle
/// changes few inputs, so large constraint sets cost what changed, not what exists.
#[derive(Clone, Debug, Default)]
pub struct FilterState {
    /// Copy of the frame's context tables (all but outputs at t) at the last sync.
    cache: [Vec<u64>; 8],
    /// Per term, the number of its context literals that are false.
    unsat: Vec<u16>,
    /// Terms whose context holds (unsat == 0), one bit per term.
    active: Bits,
    /// Occurrences of each context variable: per table, per variable index, the terms
    /// (and polarity) that read it.
    occurrences: [Vec<Vec<(u32, bool)>>; 8],
    ready: bool,
}

/// Index of the outputs-at-t table in [`Frame::tables`]; it is not context.
const OUTPUTS_NOW: usize = Space::Output as usize;

impl Filter {
    /// A fresh incremental state for this filter.
    pub fn new_state(&self) -> FilterState {
        let mut state = FilterState {
            unsat: vec![0; self.terms.len()],
            active: Bits::zeros(self.terms.len()),
            ..FilterState::default()
        };
        for (ti, t) in self.terms.iter().enumerate() {
            for l in &t.context {
                let table = l.var.space as usize + if l.var.prev { 4 } else { 0 };
                let occ = &mut state.occurrences[table];
                let i = l.var.index as usize;
                if occ.len() <= i {
                    occ.resize(i + 1, Vec::new());
                }
                occ[i].push((u32::try_from(ti).unwrap_or(u32::MAX), l.positive));
            }
        }
        state
    }

    /// Brings `state` up to date with the context of `frame` (everything but the
    /// outputs at t).
    pub fn sync(&self, state: &mut FilterState, frame: &Frame) {
        let tables = frame.tables();
        if !state.ready {
            for (ti, &(start, n_out, len)) in self.spans.iter().enumerate() {
                let from = start as usize + usize::from(n_out);
                let to = start as usize + usize::from(len);
                let false_count = self
                    .packed
                    .get(from..to)
                    .unwrap_or(&[])
                    .iter()
                    .filter(|p| !p.holds(&tables))
                    .count();
                state.unsat[ti] = u16::try_from(false_count).unwrap_or(u16::MAX);
                state.active.set(ti, false_count == 0);
            }
            for (t, words) in tables.iter().enumerate() {
                state.cache[t] = words.to_vec();
            }
            state.ready = true;
            return;
        }
        for (t, words) in tables.iter().enumerate() {
            if t == OUTPUTS_NOW {
                continue;
            }
            let cache = &mut state.cache[t];
            if cache.len() != words.len() {
                cache.resize(words.len(), 0);
            }
            for (w, (&new, old)) in words.iter().zip(cache.iter_mut()).enumerate() {
                let mut diff = new ^ *old;
                *old = new;
                while diff != 0 {
                    let b = diff.trailing_zeros() as usize;
                    diff &= diff - 1;
                    let index = w * 64 + b;
                    let value = (new >> b) & 1 == 1;
                    let Some(occ) = state.occurrences[t].get(index) else {
                        continue;
                    };
                    for &(term, positive) in occ {
                        let term = term as usize;
                        let Some(u) = state.unsat.get_mut(term) else {
                            continue;
                        };
                        if value == positive {
                            *u = u.saturating_sub(1);
                        } else {
                            *u = u.saturating_add(1);
                        }
                        state.active.set(term, *u == 0);
                    }
                }
            }
        }
    }

    /// [`Filter::violations_into`] using a synced state.
    pub fn violations_synced(&self, state: &FilterState, frame: &Frame, out: &mut Vec<usize>) {
        out.clear();
        let tables = frame.tables();
        for ti in state.active.ones_fast() {
            let (Some(t), Some(&(start, n_out, _))) = (self.terms.get(ti), self.spans.get(ti))
            else {
                continue;
            };
            let ci = t.constraint as usize;
            if out.last() == Some(&ci) {
                continue;
            }
            let start = start as usize;
            let outs = self
                .packed
                .get(start..start + usize::from(n_out))
                .unwrap_or(&[]);
            if outs.iter().all(|p| p.holds(&tables)) {
                out.push(ci);
            }
        }
    }

    /// [`Filter::fallback`] using a synced state (`frame` gives the previous outputs
    /// that `Hold` keeps).
    pub fn fallback_synced(&self, state: &FilterState, frame: &Frame) -> Result<Bits, SpecError> {
        let active: Vec<&Term> = state
            .active
            .ones_fast()
            .filter_map(|ti| self.terms.get(ti))
            .collect();
        self.solve_in(&active, frame)
    }
}

/// Largest support (number of context variables) for which [`check_fallback_exists`]
/// enumerates every context (of the whole set, or of one output component).
pub const EXHAUSTIVE_SUPPORT_LIMIT: usize = 22;

/// One product term as the ST export and the decomposed checks see it.
#[derive(Clone, Debug)]
pub struct TermView<'a> {
    /// Index of its constraint.
    pub constraint: usize,
    /// Its literals on everything but the outputs at t.
    pub context: &'a [Literal],
    /// Its literals on outputs at t: (output, positive).
    pub outputs: &'a [(u32, bool)],
}

impl Filter {
    /// Every product term, in file order.
    pub fn term_views(&self) -> impl Iterator<Item = TermView<'_>> {
        self.terms.iter().map(|t| TermView {
            constraint: t.constraint as usize,
            context: &t.context,
            outputs: &t.outputs,
        })
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.n_outputs
    }

    /// The outputs split into components: two outputs are in the same component when a
    /// term with several output literals names both. The fallback decomposes over them
    /// (fewest outputs away from their safe value overall is fewest in every
    /// component, and the lexicographic tie-break of the whole vector is that of each
    /// component in output order). Sorted, each component sorted.
    pub fn output_components(&self) -> Vec<Vec<usize>> {
        let n = self.n_outputs;
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for t in &self.terms {
            let mut it = t
                .outputs
                .iter()
                .map(|&(k, _)| k as usize)
                .filter(|&k| k < n);
            if let Some(first) = it.next() {
                for k in it {
                    let (a, b) = (find(&mut parent, first), find(&mut parent, k));
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
        let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for k in 0..n {
            let r = find(&mut parent, k);
            groups.entry(r).or_default().push(k);
        }
        groups.into_values().collect()
    }
}

/// What [`fallback_report`] proved about the existence of a fallback.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct FallbackReport {
    /// Number of variables the constraints read besides the outputs at t.
    pub support: usize,
    /// How the proof went: `whole` (every context of the support enumerated),
    /// `components` (every context of each output component's own support), or
    /// `not_proved`.
    pub method: &'static str,
    /// Contexts checked (summed over the components).
    pub contexts: u64,
    /// Per output component: its outputs, its support size, whether it was proved.
    pub components: Vec<ComponentReport>,
}

/// One output component in a [`FallbackReport`].
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ComponentReport {
    /// Its outputs, by name.
    pub outputs: Vec<String>,
    /// Variables read by its terms besides the outputs at t (and by the invariants that
    /// share one of them).
    pub support: usize,
    /// True when every context of its support was enumerated.
    pub proved: bool,
}

impl FallbackReport {
    /// True when a fallback was proved to exist in every reachable context.
    pub fn proved(&self) -> bool {
        self.method != "not_proved"
    }
}

/// The context variables (everything but outputs at t) read by the constraints, sorted.
pub fn support(filter: &Filter) -> Vec<crate::symbols::Var> {
    let mut vars: Vec<_> = filter
        .terms
        .iter()
        .flat_map(|t| t.context.iter().map(|l| l.var))
        .collect();
    vars.sort();
    vars.dedup();
    vars
}

/// Static check: a fallback exists in every reachable context. Enumerates every
/// assignment of the support when it has at most [`EXHAUSTIVE_SUPPORT_LIMIT`] variables,
/// skipping the situations an invariant excludes; returns the number of contexts checked
/// and the first failing context rendered as a witness.
pub fn check_fallback_exists(
    filter: &Filter,
    symbols: &crate::symbols::Symbols,
    invariants: &ConstraintSet,
) -> Result<u64, (SpecError, String)> {
    fallback_report(filter, symbols, invariants).map(|r| r.contexts)
}

/// [`check_fallback_exists`] with what was proved: every context of the support when it
/// has at most [`EXHAUSTIVE_SUPPORT_LIMIT`] variables; otherwise every context of each
/// output component's support (the variables its terms read, and those of the
/// invariants that share one of them), which is exact since the fallback decomposes
/// over the components; a component whose support is still larger is reported not
/// proved, with its size.
pub fn fallback_report(
    filter: &Filter,
    symbols: &crate::symbols::Symbols,
    invariants: &ConstraintSet,
) -> Result<FallbackReport, (SpecError, String)> {
    let vars = support(filter);
    let name = |k: usize| {
        symbols
            .name(Space::Output, u32::try_from(k).unwrap_or(0))
            .to_string()
    };
    if vars.len() <= EXHAUSTIVE_SUPPORT_LIMIT {
        let all: Vec<&crate::constraints::Constraint> = invariants.constraints.iter().collect();
        let contexts = enumerate_contexts(filter, symbols, &all, &vars, None)?;
        return Ok(FallbackReport {
            support: vars.len(),
            method: "whole",
            contexts,
            components: vec![ComponentReport {
                outputs: (0..filter.n_outputs).map(name).collect(),
                support: vars.len(),
                proved: true,
            }],
        });
    }
    let mut report = FallbackReport {
        support: vars.len(),
        method: "components",
        contexts: 0,
        components: Vec::new(),
    };
    for comp in filter.output_components() {
        let in_comp = |t: &Term| t.outputs.iter().any(|&(k, _)| comp.contains(&(k as usize)));
        let mut cvars: Vec<crate::symbols::Var> = filter
            .terms
            .iter()
            .filter(|t| in_comp(t))
            .flat_map(|t| t.context.iter().map(|l| l.var))
            .collect();
        cvars.sort();
        cvars.dedup();
        // The invariants that share a variable with the component, whole.
        let related: Vec<&crate::constraints::Constraint> = invariants
            .constraints
            .iter()
            .filter(|inv| {
                inv.dnf
                    .iter()
                    .flatten()
                    .any(|l| cvars.binary_search(&l.var).is_ok())
            })
            .collect();
        for inv in &related {
            cvars.extend(inv.dnf.iter().flatten().map(|l| l.var));
        }
        cvars.sort();
        cvars.dedup();
        let proved = cvars.len() <= EXHAUSTIVE_SUPPORT_LIMIT;
        if proved {
            report.contexts += enumerate_contexts(filter, symbols, &related, &cvars, Some(&comp))?;
        } else {
            report.method = "not_proved";
        }
        report.components.push(ComponentReport {
            outputs: comp.iter().map(|&k| name(k)).collect(),
            support: cvars.len(),
            proved,
        });
    }
    Ok(report)
}

/// Enumerates every assignment of `vars` (skipping those one of `invariants` excludes;
/// they read only `vars`) and searches a fallback in each, for the terms of the outputs
/// `only` (all terms when `None`); the number of contexts checked, or the first failing
/// one as a witness.
fn enumerate_contexts(
    filter: &Filter,
    symbols: &crate::symbols::Symbols,
    invariants: &[&crate::constraints::Constraint],
    vars: &[crate::symbols::Var],
    only: Option<&[usize]>,
) -> Result<u64, (SpecError, String)> {
    let sub;
    let filter = match only {
        None => filter,
        Some(comp) => {
            let mut f = filter.clone();
            f.terms
                .retain(|t| t.outputs.iter().any(|&(k, _)| comp.contains(&(k as usize))));
            sub = f;
            &sub
        }
    };
    let mut frame = Frame::new(symbols.sizes());
    let total = 1u64 << vars.len();
    let mut checked = 0;
    for assignment in 0..total {
        for (i, v) in vars.iter().enumerate() {
            let table = if v.prev {
                &mut frame.prev
            } else {
                &mut frame.now
            };
            table[v.space as usize].set(v.index as usize, (assignment >> i) & 1 == 1);
        }
        if invariants
            .iter()
            .any(|inv| crate::expr::eval_dnf(&inv.dnf, &frame))
        {
            continue;
        }
        checked += 1;
        if let Err(e) = filter.fallback(&frame) {
            let witness = vars
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    format!(
                        "{}={}",
                        symbols.render_literal(Literal {
                            var: *v,
                            positive: true
                        }),
                        (assignment >> i) & 1
                    )
                })
                .collect::<Vec<_>>()
                .join(" ");
            return Err((e, witness));
        }
    }
    Ok(checked)
}

/// Minimum-ones assignment avoiding every nogood; `None` when none exists.
fn solve_min_ones(n_outputs: usize, active: &[&Term], budget: usize) -> Option<Bits> {
    let mut fixed: Vec<Option<bool>> = vec![None; n_outputs];
    // Unit nogoods fix their output to the opposite value.
    for t in active {
        if let [(k, v)] = t.outputs.as_slice() {
            match fixed.get_mut(*k as usize) {
                Some(Some(x)) if *x == *v => return None,
                Some(slot) => *slot = Some(!*v),
                None => {}
            }
        }
    }
    let mut open: Vec<&[(u32, bool)]> = active
        .iter()
        .filter(|t| t.outputs.len() > 1)
        .map(|t| t.outputs.as_slice())
        .collect();
    // Propagate to a fixpoint: drop satisfied nogoods; one whose literals are all
    // matched by fixed outputs is a conflict; one with a single free literal fixes it.
    loop {
        let mut changed = false;
        let mut conflict = false;
        open.retain(|ng| {
            let mut free = None;
            let mut n_free = 0;
            for &(k, v) in *ng {
                match fixed.get(k as usize).copied().flatten() {
                    Some(x) if x != v => return false,
                    Some(_) => {}
                    None => {
                        n_free += 1;
                        free = Some((k, v));
                    }
                }
            }
            match (n_free, free) {
                (0, _) => {
                    conflict = true;
                    false
                }
                (1, Some((k, v))) => {
                    if let Some(slot) = fixed.get_mut(k as usize) {
                        *slot = Some(!v);
                    }
                    changed = true;
                    false
                }
                _ => true,
            }
        });
        if conflict {
            return None;
        }
        if !changed {
            break;
        }
    }
    let mut result = Bits::zeros(n_outputs);
    for (k, f) in fixed.iter().enumerate() {
        result.set(k, f.unwrap_or(false));
    }
    if open.is_empty() {
        return Some(result);
    }
    // Free outputs default to 0: if no open nogood is made only of `= 0` literals on free
    // outputs, that completion satisfies them all and adds no ON, so it is optimal.
    let zero_completion_ok = open.iter().all(|ng| {
        ng.iter()
            .any(|&(k, v)| v && fixed.get(k as usize).copied().flatten().is_none())
    });
    if zero_completion_ok {
        return Some(result);
    }
    // The remaining nogoods only name free outputs: search over those, renumbered.
    let is_free = |k: u32| fixed.get(k as usize).copied().flatten().is_none();
    let mut vars: Vec<u32> = open
        .iter()
        .flat_map(|ng| ng.iter())
        .map(|&(k, _)| k)
        .filter(|&k| is_free(k))
        .collect();
    vars.sort_unstable();
    vars.dedup();
    let local: Vec<Vec<(usize, bool)>> = open
        .iter()
        .map(|ng| {
            ng.iter()
                .filter(|&&(k, _)| is_free(k))
                .map(|&(k, v)| (vars.binary_search(&k).unwrap_or(0), v))
                .collect()
        })
        .collect();
    let mut search = Search {
        nogoods: local,
        best: None,
        best_ones: usize::MAX,
        nodes: 0,
        budget,
    };
    search.dfs(&mut vec![None; vars.len()]);
    let best = search.best?;
    for (i, v) in best.iter().enumerate() {
        result.set(vars[i] as usize, v.unwrap_or(false));
    }
    Some(result)
}

struct Search {
    nogoods: Vec<Vec<(usize, bool)>>,
    best: Option<Vec<Option<bool>>>,
    best_ones: usize,
    nodes: usize,
    budget: usize,
}

impl Search {
    /// Unit propagation; returns false on conflict. Unassigned variables not named in any
    /// open nogood are left unassigned (they default to 0).
    fn propagate(&self, a: &mut [Option<bool>]) -> bool {
        loop {
            let mut changed = false;
            for ng in &self.nogoods {
                let mut unassigned = None;
                let mut open = 0;
                let mut satisfied = false;
                for &(k, v) in ng {
                    match a.get(k).copied().flatten() {
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
                        if let Some(slot) = a.get_mut(k) {
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
        self.nodes += 1;
        if self.nodes > self.budget && self.best.is_some() {
            return;
        }
        if !self.propagate(a) {
            return;
        }
        let ones = a.iter().filter(|x| **x == Some(true)).count();
        if ones >= self.best_ones {
            return;
        }
        // Branch on the lowest variable named by a nogood that is still open.
        let next = self
            .nogoods
            .iter()
            .filter(|ng| {
                !ng.iter()
                    .any(|&(k, v)| a.get(k).copied().flatten() == Some(!v))
            })
            .flat_map(|ng| ng.iter().map(|&(k, _)| k))
            .filter(|&k| a.get(k).copied().flatten().is_none())
            .min();
        let Some(k) = next else {
            // Every nogood is satisfied; unassigned variables default to 0, which cannot
            // complete a nogood since none is open.
            self.best_ones = ones;
            self.best = Some(a.to_vec());
            return;
        };
        for value in [false, true] {
            let mut branch = a.to_vec();
            branch[k] = Some(value);
            self.dfs(&mut branch);
        }
    }
}

#[cfg(test)]
mod tests;
