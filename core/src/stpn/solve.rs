//! Sparse exact linear systems: the first-passage and stationary equations of a state
//! graph have a few terms per row, so Gaussian elimination on sparse rows (the pivot row
//! with the fewest terms first) keeps the fill-in small where a dense elimination
//! would cost `n³` rational operations.

use super::Q;
use num_traits::{One, Zero};
use std::collections::{BTreeMap, BTreeSet};

/// A sparse row: column → coefficient (no zero stored).
pub(crate) type Row = BTreeMap<usize, Q>;

/// Adds `v` at `(c)` of `row`, removing the entry when it cancels.
pub(crate) fn add(row: &mut Row, c: usize, v: Q) {
    if v.is_zero() {
        return;
    }
    let e = row.entry(c).or_insert_with(Q::zero);
    *e += v;
    if e.is_zero() {
        row.remove(&c);
    }
}

/// Solves `a·x = b` for a square system over the rationals; `None` when singular.
pub(crate) fn solve(a: Vec<Row>, b: Vec<Q>) -> Option<Vec<Q>> {
    let n = b.len();
    let mut rows: Vec<(Row, Q)> = a.into_iter().zip(b).collect();
    let mut col_rows: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    for (r, (row, _)) in rows.iter().enumerate() {
        for &c in row.keys() {
            col_rows[c].insert(r);
        }
    }
    let mut done = vec![false; n];
    let mut order = Vec::with_capacity(n);
    for c in 0..n {
        let r = *col_rows[c]
            .iter()
            .filter(|&&r| !done[r])
            .min_by_key(|&&r| rows[r].0.len())?;
        done[r] = true;
        let pivot = rows[r].0[&c].clone();
        if !pivot.is_one() {
            let inv = Q::one() / pivot;
            for v in rows[r].0.values_mut() {
                *v *= &inv;
            }
            rows[r].1 *= &inv;
        }
        let (prow, pb) = rows[r].clone();
        let others: Vec<usize> = col_rows[c]
            .iter()
            .copied()
            .filter(|&o| o != r && !done[o])
            .collect();
        for o in others {
            let f = rows[o].0[&c].clone();
            for (&k, v) in &prow {
                let before = rows[o].0.contains_key(&k);
                add(&mut rows[o].0, k, -(&f * v));
                let after = rows[o].0.contains_key(&k);
                if before && !after {
                    col_rows[k].remove(&o);
                } else if !before && after {
                    col_rows[k].insert(o);
                }
            }
            let v = &f * &pb;
            rows[o].1 -= v;
        }
        order.push((c, r));
    }
    let mut x = vec![Q::zero(); n];
    for &(c, r) in order.iter().rev() {
        let (row, b) = &rows[r];
        let mut v = b.clone();
        for (&k, a) in row.range(c + 1..) {
            v -= a * &x[k];
        }
        x[c] = v;
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_bigint::BigInt;
    use proptest::prelude::*;

    fn q(n: i64) -> Q {
        Q::from_integer(BigInt::from(n))
    }

    #[test]
    fn a_singular_system_has_no_solution() {
        let row: Row = [(0, q(1)), (1, q(1))].into_iter().collect();
        assert_eq!(solve(vec![row.clone(), row], vec![q(1), q(2)]), None);
    }

    proptest! {
        /// Whatever the sparse matrix, a solution found satisfies every equation, and a
        /// diagonally dominant matrix always has one.
        #[test]
        fn a_solution_satisfies_the_system(
            entries in proptest::collection::vec((0usize..6, 0usize..6, -5i64..6), 0..20),
            rhs in proptest::collection::vec(-9i64..10, 6),
        ) {
            let n = 6;
            let mut a: Vec<Row> = vec![Row::new(); n];
            for (r, c, v) in entries {
                add(&mut a[r], c, q(v));
            }
            for (i, row) in a.iter_mut().enumerate() {
                let off: i64 = row.iter().filter(|(c, _)| **c != i).map(|(_, v)| {
                    let v: i64 = v.to_integer().try_into().unwrap_or(0);
                    v.abs()
                }).sum();
                add(row, i, q(off + 1) - row.get(&i).cloned().unwrap_or_else(Q::zero));
            }
            let b: Vec<Q> = rhs.into_iter().map(q).collect();
            let x = solve(a.clone(), b.clone());
            prop_assert!(x.is_some());
            let x = x.unwrap_or_default();
            for (row, bi) in a.iter().zip(&b) {
                let lhs: Q = row.iter().map(|(c, v)| v * &x[*c]).sum();
                prop_assert_eq!(&lhs, bi);
            }
        }
    }
}
