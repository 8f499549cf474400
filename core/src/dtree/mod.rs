//! Compilation of a Boolean function (the filter's sum of monomials) into a binary
//! decision tree with seed 003's criterion, emitted as a flat decision table, and the
//! bit-mask evaluator of seed 003 Fig. I.12.
//!
//! The builder works top-down, depth first: at each node it chooses, among the tests
//! that split the node's minterms, the one minimising the conditional entropy
//! H(F | f) (II.15) with uniform minterm weights; ties go to the lowest test index.
//! Tests are single variables (w = 1), the five two-variable functions per pair
//! (X̄iXj, XiX̄j, X̄iX̄j, XiXj, Xi⊕Xj, in that order, pairs i < j lexicographic), or both
//! (projections first). Variable 0 is X1, the most significant bit of a minterm index.

use crate::constraints::ConstraintSet;
use crate::diag::Problem;
use crate::diag::codes;
use crate::expr;
use crate::frame::Frame;
use crate::symbols::{Space, Var};
use serde::Serialize;

/// A test on one or two variables (indices into the function's variables).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Test {
    /// Xi.
    Var(u8),
    /// X̄i·Xj.
    NotAB(u8, u8),
    /// Xi·X̄j.
    ANotB(u8, u8),
    /// X̄i·X̄j.
    NotANotB(u8, u8),
    /// Xi·Xj.
    AB(u8, u8),
    /// Xi ⊕ Xj.
    Xor(u8, u8),
}

impl Test {
    /// Value on a minterm of `n` variables (X1 = most significant bit).
    #[inline]
    pub fn eval(self, n: usize, x: u64) -> bool {
        let bit = |i: u8| x >> (n - 1 - usize::from(i)) & 1 == 1;
        match self {
            Test::Var(i) => bit(i),
            Test::NotAB(i, j) => !bit(i) && bit(j),
            Test::ANotB(i, j) => bit(i) && !bit(j),
            Test::NotANotB(i, j) => !bit(i) && !bit(j),
            Test::AB(i, j) => bit(i) && bit(j),
            Test::Xor(i, j) => bit(i) != bit(j),
        }
    }
}

/// Which tests the builder may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tests {
    /// w = 1: the variables.
    Single,
    /// w = 2, the thesis's set: five functions per pair.
    Pairs,
    /// w ≤ 2: the variables, then the pair functions.
    SingleAndPairs,
}

fn test_set(n: usize, which: Tests) -> Vec<Test> {
    let mut v = Vec::new();
    if which != Tests::Pairs {
        v.extend((0..n as u8).map(Test::Var));
    }
    if which != Tests::Single {
        for i in 0..n as u8 {
            for j in i + 1..n as u8 {
                v.extend([
                    Test::NotAB(i, j),
                    Test::ANotB(i, j),
                    Test::NotANotB(i, j),
                    Test::AB(i, j),
                    Test::Xor(i, j),
                ]);
            }
        }
    }
    v
}

/// One row of the decision table (seed 003 Fig. III.2): a test with the rows to go to,
/// or an output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Row {
    /// TEST: evaluate and jump.
    Test {
        /// The test.
        test: Test,
        /// Next row when true.
        if_true: u32,
        /// Next row when false.
        if_false: u32,
    },
    /// SORTIE: the value of F.
    Out(bool),
}

/// A compiled decision tree as a flat table (row 0 is the root).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct DecisionTable {
    /// Number of variables.
    pub n: usize,
    /// Rows.
    pub rows: Vec<Row>,
}

/// Size figures of a tree.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TreeStats {
    /// Internal (test) nodes.
    pub internal: usize,
    /// Leaves.
    pub leaves: usize,
    /// Longest path, tests.
    pub depth: usize,
    /// Expected number of tests with equiprobable minterms.
    pub mean: f64,
}

fn entropy2(a: usize, b: usize) -> f64 {
    let t = (a + b) as f64;
    let h = |x: usize| {
        if x == 0 {
            0.0
        } else {
            let p = x as f64 / t;
            -p * p.log2()
        }
    };
    h(a) + h(b)
}

/// H(F | f) on a node set, with uniform weights (II.15); `None` when `f` does not split.
fn cond_entropy(n: usize, set: &[u64], f: &[bool], test: Test) -> Option<f64> {
    let mut c = [[0usize; 2]; 2]; // [alpha][beta]
    for &x in set {
        c[usize::from(test.eval(n, x))][usize::from(f[x as usize])] += 1;
    }
    let n1 = c[1][0] + c[1][1];
    let n0 = c[0][0] + c[0][1];
    if n1 == 0 || n0 == 0 {
        return None;
    }
    let t = set.len() as f64;
    Some(n1 as f64 / t * entropy2(c[1][0], c[1][1]) + n0 as f64 / t * entropy2(c[0][0], c[0][1]))
}

/// Root conditional entropies of every test (regression figures of the notes).
pub fn root_entropies(n: usize, f: &[bool], which: Tests) -> Vec<(Test, f64)> {
    let all: Vec<u64> = (0..1u64 << n).collect();
    test_set(n, which)
        .into_iter()
        .filter_map(|t| cond_entropy(n, &all, f, t).map(|h| (t, h)))
        .collect()
}

/// Builds the entropy tree of `f` (truth table of 2^n entries, X1 = most significant).
pub fn build(n: usize, f: &[bool], which: Tests) -> DecisionTable {
    let tests = test_set(n, which);
    let mut rows = Vec::new();
    let all: Vec<u64> = (0..1u64 << n).collect();
    node(n, f, &tests, all, &mut rows);
    DecisionTable { n, rows }
}

fn node(n: usize, f: &[bool], tests: &[Test], set: Vec<u64>, rows: &mut Vec<Row>) -> u32 {
    let me = rows.len() as u32;
    let first = set.first().is_some_and(|&x| f[x as usize]);
    if set.iter().all(|&x| f[x as usize] == first) {
        rows.push(Row::Out(first));
        return me;
    }
    let mut best: Option<(Test, f64)> = None;
    for &t in tests {
        if let Some(h) = cond_entropy(n, &set, f, t)
            && best.is_none_or(|(_, b)| h < b - 1e-12)
        {
            best = Some((t, h));
        }
    }
    let Some((test, _)) = best else {
        // No test splits (cannot happen for an impure set with the variables available).
        rows.push(Row::Out(first));
        return me;
    };
    rows.push(Row::Out(false));
    let (yes, no): (Vec<u64>, Vec<u64>) = set.into_iter().partition(|&x| test.eval(n, x));
    let if_true = node(n, f, tests, yes, rows);
    let if_false = node(n, f, tests, no, rows);
    rows[me as usize] = Row::Test {
        test,
        if_true,
        if_false,
    };
    me
}

impl DecisionTable {
    /// Evaluates on a minterm (X1 = most significant of the `n` low bits).
    #[inline]
    pub fn eval(&self, x: u64) -> bool {
        let mut r = 0usize;
        loop {
            match self.rows.get(r) {
                Some(Row::Test {
                    test,
                    if_true,
                    if_false,
                }) => {
                    r = if test.eval(self.n, x) {
                        *if_true as usize
                    } else {
                        *if_false as usize
                    };
                }
                Some(Row::Out(v)) => return *v,
                None => return true, // malformed table: fail safe (constraint true)
            }
        }
    }

    /// Size, depth and mean number of tests.
    pub fn stats(&self) -> TreeStats {
        let internal = self
            .rows
            .iter()
            .filter(|r| matches!(r, Row::Test { .. }))
            .count();
        let mut depth = 0;
        let mut total = 0u64;
        for x in 0..1u64 << self.n {
            let mut r = 0usize;
            let mut d = 0;
            while let Some(Row::Test {
                test,
                if_true,
                if_false,
            }) = self.rows.get(r)
            {
                d += 1;
                r = if test.eval(self.n, x) {
                    *if_true as usize
                } else {
                    *if_false as usize
                };
            }
            depth = depth.max(d);
            total += d as u64;
        }
        TreeStats {
            internal,
            leaves: self.rows.len() - internal,
            depth,
            mean: total as f64 / (1u64 << self.n) as f64,
        }
    }
}

/// The mask table of seed 003 Fig. I.12: F = 1 iff `x & mask == test` for some row.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct MaskTable {
    /// (mask, test) per monomial.
    pub rows: Vec<(u64, u64)>,
}

impl MaskTable {
    /// Evaluates on a packed input.
    #[inline]
    pub fn eval(&self, x: u64) -> bool {
        self.rows.iter().any(|&(m, t)| x & m == t)
    }
}

/// A constraint set compiled over its support: variable order, the entropy tree (when
/// the support is small enough to enumerate) and the mask table.
#[derive(Clone, Debug, Serialize)]
pub struct CompiledFilter {
    /// Support variables, bit k of the packed input = variable k (the last is X1, the
    /// most significant bit of a minterm index).
    #[serde(skip)]
    pub vars: Vec<Var>,
    /// Entropy tree of "some constraint is true".
    pub tree: Option<DecisionTable>,
    /// Mask table, bit k of the packed input = variable k.
    pub masks: MaskTable,
}

/// Largest support the tree builder enumerates.
pub const MAX_TREE_VARS: usize = 20;

impl CompiledFilter {
    /// Compiles a constraint set: F = sum of every constraint's monomials.
    pub fn new(set: &ConstraintSet, which: Tests) -> Result<Self, Problem> {
        let mut vars: Vec<Var> = set
            .constraints
            .iter()
            .flat_map(|c| c.dnf.iter().flatten().map(|l| l.var))
            .collect();
        vars.sort();
        vars.dedup();
        if vars.len() > 64 {
            return Err(Problem::error(
                codes::DTREE_SUPPORT_TOO_LARGE.id,
                format!(
                    "support of {} variables: the compiled forms take at most 64",
                    vars.len()
                ),
                None,
            ));
        }
        let n = vars.len();
        let pos = |v: &Var| vars.iter().position(|w| w == v).unwrap_or(0);
        let masks = MaskTable {
            rows: set
                .constraints
                .iter()
                .flat_map(|c| c.dnf.iter())
                .filter(|t| !expr::is_contradictory(t))
                .map(|t| {
                    t.iter().fold((0u64, 0u64), |(m, x), l| {
                        let b = 1u64 << pos(&l.var);
                        (m | b, if l.positive { x | b } else { x })
                    })
                })
                .collect(),
        };
        let tree = (n <= MAX_TREE_VARS).then(|| {
            // The minterm index is the packed input: X1 is the last support variable.
            let f: Vec<bool> = (0..1u64 << n).map(|idx| masks.eval(idx)).collect();
            build(n, &f, which)
        });
        Ok(Self { vars, tree, masks })
    }

    /// Packs the support variables' values from a frame.
    pub fn pack(&self, frame: &Frame) -> u64 {
        self.vars
            .iter()
            .enumerate()
            .fold(0, |p, (k, v)| p | u64::from(frame.get(*v)) << k)
    }

    /// Writes a packed input into a frame (support variables only).
    pub fn unpack_into(&self, packed: u64, frame: &mut Frame) {
        for (k, v) in self.vars.iter().enumerate() {
            let table = if v.prev {
                &mut frame.prev
            } else {
                &mut frame.now
            };
            table[v.space as usize].set(v.index as usize, packed >> k & 1 == 1);
        }
    }

    /// Tree evaluation on a frame (falls back to the masks without a tree).
    pub fn eval_tree(&self, frame: &Frame) -> bool {
        let p = self.pack(frame);
        match &self.tree {
            Some(t) => t.eval(p),
            None => self.masks.eval(p),
        }
    }

    /// Mask evaluation on a frame.
    pub fn eval_masks(&self, frame: &Frame) -> bool {
        self.masks.eval(self.pack(frame))
    }
}

/// The mask table over a whole frame, for supports too large to pack in one word:
/// per monomial, a (table, word, mask, test) quadruple per word it reads.
#[derive(Clone, Debug, Default)]
pub struct SparseMasks {
    words: Vec<(u8, u32, u64, u64)>,
    /// End of each monomial in `words`.
    ends: Vec<u32>,
    support: usize,
}

impl SparseMasks {
    /// Compiles every monomial of a set.
    pub fn new(set: &ConstraintSet) -> Self {
        let mut s = Self::default();
        let mut vars = std::collections::BTreeSet::new();
        for t in set.constraints.iter().flat_map(|c| c.dnf.iter()) {
            if expr::is_contradictory(t) {
                continue;
            }
            let mut ws: Vec<(u8, u32, u64, u64)> = Vec::new();
            for l in t {
                vars.insert(l.var);
                let table = l.var.space as u8 + if l.var.prev { 4 } else { 0 };
                let word = l.var.index / 64;
                let b = 1u64 << (l.var.index % 64);
                match ws.iter_mut().find(|w| w.0 == table && w.1 == word) {
                    Some(w) => {
                        w.2 |= b;
                        if l.positive {
                            w.3 |= b;
                        }
                    }
                    None => ws.push((table, word, b, if l.positive { b } else { 0 })),
                }
            }
            s.words.extend(ws);
            s.ends.push(s.words.len() as u32);
        }
        s.support = vars.len();
        s
    }

    /// Number of distinct variables read.
    pub fn support(&self) -> usize {
        self.support
    }

    /// True when some monomial holds in `frame`.
    pub fn eval(&self, frame: &Frame) -> bool {
        let tables = frame.tables();
        let mut start = 0usize;
        for &end in &self.ends {
            let end = end as usize;
            if self.words[start..end].iter().all(|&(t, w, m, x)| {
                tables[usize::from(t & 7)]
                    .get(w as usize)
                    .copied()
                    .unwrap_or(0)
                    & m
                    == x
            }) {
                return true;
            }
            start = end;
        }
        false
    }
}

/// Space sizes a frame needs for the variables of a set.
pub fn frame_sizes(vars: &[Var]) -> [usize; 4] {
    let mut s = [0usize; 4];
    for v in vars {
        let i = v.space as usize;
        s[i] = s[i].max(v.index as usize + 1);
    }
    let _ = Space::ALL;
    s
}

#[cfg(test)]
mod tests;
