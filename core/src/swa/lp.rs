//! An exact simplex (two phases, Bland's rule, dense dictionary over [`Q`]) for the one
//! question the polyhedra ask most: is a system of strict and non-strict linear
//! inequalities satisfiable? Fourier–Motzkin answers it too, with a cost that grows
//! with the product of the bounds at each elimination; the simplex is polynomial in
//! practice (it made the liquid supply's synthesis, 81 locations and 8 clocks, finish).
//!
//! Strictness: `a·x < b` becomes `a·x + ε ≤ b` and the program maximises `ε ≤ 1`; the
//! system is satisfiable when the optimum is positive (or when nothing is strict and
//! the program is feasible). Free variables are split, `x = x⁺ − x⁻`.

use super::poly::{HalfSpace, Q};

struct Dict {
    /// Row `i`: `x_basic[i] + Σ_j row[i][j]·x_j = rhs[i]`.
    row: Vec<Vec<Q>>,
    rhs: Vec<Q>,
    basic: Vec<usize>,
    /// Objective `v + Σ c_j x_j`, maximised.
    c: Vec<Q>,
    v: Q,
    /// Variables that may not enter (the auxiliary one in phase 2).
    banned: Vec<bool>,
}

impl Dict {
    fn pivot(&mut self, r: usize, e: usize) {
        let p = self.row[r][e];
        let inv = Q::one() / p;
        for x in &mut self.row[r] {
            *x = *x * inv;
        }
        self.rhs[r] = self.rhs[r] * inv;
        let pivot_row = self.row[r].clone();
        let pivot_rhs = self.rhs[r];
        for i in 0..self.row.len() {
            if i == r {
                continue;
            }
            let f = self.row[i][e];
            if f.is_zero() {
                continue;
            }
            for (x, y) in self.row[i].iter_mut().zip(&pivot_row) {
                if !y.is_zero() {
                    *x -= f * y;
                }
            }
            self.rhs[i] -= f * pivot_rhs;
        }
        let ce = self.c[e];
        if !ce.is_zero() {
            self.v += ce * pivot_rhs;
            for (x, y) in self.c.iter_mut().zip(&pivot_row) {
                if !y.is_zero() {
                    *x -= ce * y;
                }
            }
        }
        self.basic[r] = e;
    }

    /// Runs to the optimum; `false` when unbounded.
    fn solve(&mut self) -> bool {
        loop {
            let Some(e) = (0..self.c.len()).find(|&j| self.c[j].is_positive() && !self.banned[j])
            else {
                return true;
            };
            let mut best: Option<(usize, Q)> = None;
            for i in 0..self.row.len() {
                let a = self.row[i][e];
                if !a.is_positive() {
                    continue;
                }
                let ratio = self.rhs[i] / a;
                let better = match &best {
                    None => true,
                    Some((bi, br)) => {
                        ratio < *br || (ratio == *br && self.basic[i] < self.basic[*bi])
                    }
                };
                if better {
                    best = Some((i, ratio));
                }
            }
            let Some((r, _)) = best else {
                return false;
            };
            self.pivot(r, e);
        }
    }
}

/// Maximises `c·z` over `A z ≤ b`, `z ≥ 0`: `None` when infeasible, `Some(None)` when
/// unbounded, `Some(Some(optimum))` otherwise.
fn maximize(a: &[Vec<Q>], b: &[Q], c: &[Q]) -> Option<Option<Q>> {
    let (m, n) = (a.len(), c.len());
    let x0 = n + m;
    let width = n + m + 1;
    let mut d = Dict {
        row: Vec::with_capacity(m),
        rhs: b.to_vec(),
        basic: (n..n + m).collect(),
        c: vec![Q::zero(); width],
        v: Q::zero(),
        banned: vec![false; width],
    };
    for (i, ai) in a.iter().enumerate() {
        let mut r = vec![Q::zero(); width];
        r[..n].copy_from_slice(ai);
        r[n + i] = Q::one();
        r[x0] = -Q::one();
        d.row.push(r);
    }
    // Phase 1: maximise −x0 from the most violated row.
    let worst = (0..m).min_by(|&i, &j| d.rhs[i].cmp(&d.rhs[j]).then(i.cmp(&j)));
    if let Some(l) = worst
        && d.rhs[l].is_negative()
    {
        d.c[x0] = -Q::one();
        d.pivot(l, x0);
        d.solve();
        if d.v.is_negative() {
            return None;
        }
        if let Some(r) = d.basic.iter().position(|&x| x == x0) {
            // Degenerate: x0 = 0 is basic; pivot it out on any non-zero column.
            if let Some(e) = (0..x0).find(|&j| !d.row[r][j].is_zero()) {
                d.pivot(r, e);
            }
        }
    }
    d.banned[x0] = true;
    for r in &mut d.row {
        r[x0] = Q::zero();
    }
    // Phase 2: the objective in terms of the non-basic variables.
    d.c = vec![Q::zero(); width];
    d.c[..n].copy_from_slice(c);
    d.v = Q::zero();
    for i in 0..m {
        let bv = d.basic[i];
        let cb = d.c[bv];
        if cb.is_zero() {
            continue;
        }
        d.v += cb * d.rhs[i];
        let row = d.row[i].clone();
        for (x, y) in d.c.iter_mut().zip(&row) {
            *x -= cb * y;
        }
        d.c[bv] = Q::zero();
    }
    if d.solve() {
        Some(Some(d.v))
    } else {
        Some(None)
    }
}

/// True when some point satisfies every half-space (of dimension `dim`).
pub fn satisfiable(hs: &[HalfSpace], dim: usize) -> bool {
    if hs.is_empty() {
        return true;
    }
    let strict = hs.iter().any(|h| h.strict);
    let (a, b, eps, n) = program(hs, dim, true);
    let mut cap = vec![Q::zero(); n];
    cap[eps] = Q::one();
    match maximize(&a, &b, &cap) {
        None => false,
        Some(None) => true,
        Some(Some(opt)) => !strict || opt.is_positive(),
    }
}

/// The supremum of `d·x` over the closure of the half-spaces: `None` when they are
/// infeasible, `Some(None)` when unbounded.
pub fn sup(hs: &[HalfSpace], dim: usize, d: &[Q]) -> Option<Option<Q>> {
    let (a, b, _, n) = program(hs, dim, false);
    let mut c = vec![Q::zero(); n];
    let split = split_columns(hs, dim);
    for (k, dk) in d.iter().enumerate() {
        c[k] = *dk;
        if let Some(m) = split[k] {
            c[m] = -*dk;
        }
    }
    maximize(&a, &b, &c)
}

/// The column of `x_k⁻` for each variable that is not bounded below by 0.
fn split_columns(hs: &[HalfSpace], dim: usize) -> Vec<Option<usize>> {
    let nonneg: Vec<bool> = (0..dim)
        .map(|k| {
            hs.iter().any(|h| {
                h.a[k].is_negative()
                    && !h.b.is_positive()
                    && h.a.iter().enumerate().all(|(j, c)| j == k || c.is_zero())
            })
        })
        .collect();
    let mut minus = vec![None; dim];
    let mut n = dim;
    for k in 0..dim {
        if !nonneg[k] {
            minus[k] = Some(n);
            n += 1;
        }
    }
    minus
}

type Program = (Vec<Vec<Q>>, Vec<Q>, usize, usize);

/// The rows `A z ≤ b` of the half-spaces over the split columns, with `ε` (the last
/// column) added to the strict rows when `with_eps` (and capped at 1).
fn program(hs: &[HalfSpace], dim: usize, with_eps: bool) -> Program {
    // Columns: x_k (or x_k⁺), then x_k⁻ for the free ones (a clock bounded below by 0
    // needs no split), then ε.
    let minus = split_columns(hs, dim);
    let eps = dim + minus.iter().flatten().count();
    let n = eps + 1;
    let mut a = Vec::with_capacity(hs.len() + 1);
    let mut b = Vec::with_capacity(hs.len() + 1);
    for h in hs {
        let mut r = vec![Q::zero(); n];
        for (k, c) in h.a.iter().enumerate() {
            r[k] = *c;
            if let Some(m) = minus[k] {
                r[m] = -*c;
            }
        }
        if h.strict && with_eps {
            r[eps] = Q::one();
        }
        a.push(r);
        b.push(h.b);
    }
    let mut cap = vec![Q::zero(); n];
    cap[eps] = Q::one();
    a.push(cap);
    b.push(Q::one());
    (a, b, eps, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn h(a: &[i128], b: i128, strict: bool) -> HalfSpace {
        HalfSpace {
            a: a.iter().map(|&x| Q::int(x)).collect(),
            b: Q::int(b),
            strict,
        }
    }

    #[test]
    fn small_systems() {
        // x ≤ 1 ∧ x ≥ 1: one point.
        assert!(satisfiable(&[h(&[1], 1, false), h(&[-1], -1, false)], 1));
        // x < 1 ∧ x ≥ 1: none.
        assert!(!satisfiable(&[h(&[1], 1, true), h(&[-1], -1, false)], 1));
        // x < y < z < x: none; with ≤: the diagonal.
        let cyc = |s| {
            [
                h(&[1, -1, 0], 0, s),
                h(&[0, 1, -1], 0, s),
                h(&[-1, 0, 1], 0, s),
            ]
        };
        assert!(!satisfiable(&cyc(true), 3));
        assert!(satisfiable(&cyc(false), 3));
        // Negative values: x ≤ −5 ∧ x ≥ −6.
        assert!(satisfiable(&[h(&[1], -5, false), h(&[-1], 6, false)], 1));
        // 2x + 3y ≥ 13 ∧ x ≤ 2 ∧ y ≤ 3: only (2, 3).
        assert!(satisfiable(
            &[
                h(&[-2, -3], -13, false),
                h(&[1, 0], 2, false),
                h(&[0, 1], 3, false)
            ],
            2
        ));
        assert!(!satisfiable(
            &[
                h(&[-2, -3], -13, true),
                h(&[1, 0], 2, false),
                h(&[0, 1], 3, false)
            ],
            2
        ));
    }
}
