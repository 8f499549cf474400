//! Convex polyhedra over the rationals (H-representation), with strict and non-strict
//! constraints, in exact arithmetic: what stopwatch time elapse needs (difference-bound
//! matrices are not closed under it, seed 000 §2.3).
//!
//! A polyhedron keeps, per *direction* `d` (a primitive integer vector whose first
//! non-zero entry is positive), the tightest lower and upper bound of `d·x`. Two
//! constraints on one direction are therefore merged on insertion, `d·x ≤ b ∧ d·x ≥ b`
//! is an equality, and crossed bounds make the polyhedron empty at once. Projection is
//! Fourier–Motzkin elimination (an equality is used as a substitution first), emptiness
//! eliminates every variable, and inclusion asks whether the negation of each bounding
//! half-space leaves nothing.

pub use super::rat::Q;
use std::collections::BTreeMap;
use std::fmt;

type BigInt = i128;

/// One bound of a direction: the value and whether it is strict.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Bound {
    /// The value.
    pub value: Q,
    /// `<` (or `>`) rather than `≤` (or `≥`).
    pub strict: bool,
}

/// The bounds of one direction `d·x`.
#[derive(Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Bounds {
    /// `d·x ≥ lo` (or `>`).
    pub lo: Option<Bound>,
    /// `d·x ≤ hi` (or `<`).
    pub hi: Option<Bound>,
}

/// A half-space `a·x ≤ b` (or `<` when strict), the unit of Fourier–Motzkin.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HalfSpace {
    /// Coefficients, one per dimension.
    pub a: Vec<Q>,
    /// Right-hand side.
    pub b: Q,
    /// `<` rather than `≤`.
    pub strict: bool,
}

impl HalfSpace {
    /// `a·x ≤ b`.
    pub fn le(a: Vec<Q>, b: Q) -> Self {
        HalfSpace {
            a,
            b,
            strict: false,
        }
    }

    /// The complement: `a·x > b` written as `−a·x < −b` (or `≥`).
    pub fn negation(&self) -> HalfSpace {
        HalfSpace {
            a: self.a.iter().map(|c| -c).collect(),
            b: -&self.b,
            strict: !self.strict,
        }
    }

    /// True when `v` satisfies it.
    pub fn holds(&self, v: &[Q]) -> bool {
        let lhs = dot(&self.a, v);
        if self.strict {
            lhs < self.b
        } else {
            lhs <= self.b
        }
    }
}

fn dot(a: &[Q], v: &[Q]) -> Q {
    a.iter()
        .zip(v)
        .filter(|(c, _)| !c.is_zero())
        .map(|(c, x)| c * x)
        .fold(Q::zero(), |s, t| s + t)
}

use super::rat::gcd as int_gcd;

/// A convex polyhedron of dimension `dim`.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Poly {
    dim: usize,
    empty: bool,
    dirs: BTreeMap<Vec<BigInt>, Bounds>,
}

/// Scales `a` to a primitive integer vector whose first non-zero entry is positive;
/// returns it with the positive factor `k` applied (`d = k·a`, `k > 0`) and the sign
/// (`false` when `a` was negated to get there).
fn direction(a: &[Q]) -> Option<(Vec<BigInt>, Q, bool)> {
    let first = a.iter().find(|c| !c.is_zero())?;
    let positive = first.is_positive();
    let lcm = a.iter().fold(Q::one(), |l, c| {
        let g = int_gcd(l.numer(), c.denom());
        l * Q::int(c.denom() / g)
    });
    let ints: Vec<BigInt> = a.iter().map(|c| (c * lcm).numer()).collect();
    let gcd = ints.iter().fold(0, |g, c| int_gcd(g, *c)).max(1);
    let d: Vec<BigInt> = ints
        .iter()
        .map(|c| if positive { c / gcd } else { -(c / gcd) })
        .collect();
    // k such that d = ±k·a, k > 0.
    let k = lcm / Q::int(gcd);
    Some((d, k, positive))
}

impl Poly {
    /// Every point of `R^dim`.
    pub fn universe(dim: usize) -> Self {
        Poly {
            dim,
            empty: false,
            dirs: BTreeMap::new(),
        }
    }

    /// No point.
    pub fn empty(dim: usize) -> Self {
        Poly {
            dim,
            empty: true,
            dirs: BTreeMap::new(),
        }
    }

    /// This polyhedron in a space of dimension `dim`, its variable `k` becoming
    /// `map[k]` (a component's clocks in the product, a group's in the whole).
    pub fn embed(&self, map: &[usize], dim: usize) -> Poly {
        if self.empty {
            return Poly::empty(dim);
        }
        let mut out = Poly::universe(dim);
        for h in self.half_spaces() {
            let mut a = vec![Q::zero(); dim];
            for (k, c) in h.a.into_iter().enumerate() {
                a[map[k]] = c;
            }
            out.add(HalfSpace {
                a,
                b: h.b,
                strict: h.strict,
            });
        }
        out
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The directions and their bounds (empty when the polyhedron is empty).
    pub fn directions(&self) -> impl Iterator<Item = (&Vec<BigInt>, &Bounds)> {
        self.dirs.iter()
    }

    /// True when it is known empty without a search (crossed bounds). See
    /// [`Poly::is_empty`] for the exact test.
    pub fn trivially_empty(&self) -> bool {
        self.empty
    }

    /// Adds `a·x ≤ b` (or `<`).
    pub fn add(&mut self, h: HalfSpace) {
        debug_assert_eq!(h.a.len(), self.dim);
        if self.empty {
            return;
        }
        let Some((d, k, positive)) = direction(&h.a) else {
            // 0 ≤ b (or 0 < b).
            let ok = if h.strict {
                h.b.is_positive()
            } else {
                !h.b.is_negative()
            };
            if !ok {
                self.set_empty();
            }
            return;
        };
        let value = h.b * k;
        let entry = self.dirs.entry(d).or_default();
        if positive {
            let new = Bound {
                value,
                strict: h.strict,
            };
            if entry.hi.as_ref().is_none_or(|old| tighter_hi(&new, old)) {
                entry.hi = Some(new);
            }
        } else {
            let new = Bound {
                value: -value,
                strict: h.strict,
            };
            if entry.lo.as_ref().is_none_or(|old| tighter_lo(&new, old)) {
                entry.lo = Some(new);
            }
        }
        if let (Some(lo), Some(hi)) = (&entry.lo, &entry.hi)
            && (lo.value > hi.value || (lo.value == hi.value && (lo.strict || hi.strict)))
        {
            self.set_empty();
        }
    }

    /// Adds `a·x = b`.
    pub fn add_eq(&mut self, a: Vec<Q>, b: Q) {
        let neg = HalfSpace::le(a.iter().map(|c| -c).collect(), -&b);
        self.add(HalfSpace::le(a, b));
        self.add(neg);
    }

    fn set_empty(&mut self) {
        self.empty = true;
        self.dirs.clear();
    }

    /// The bounding half-spaces.
    pub fn half_spaces(&self) -> Vec<HalfSpace> {
        let mut out = Vec::new();
        for (d, b) in &self.dirs {
            let a: Vec<Q> = d.iter().map(|c| Q::int(*c)).collect();
            if let Some(hi) = &b.hi {
                out.push(HalfSpace {
                    a: a.clone(),
                    b: hi.value,
                    strict: hi.strict,
                });
            }
            if let Some(lo) = &b.lo {
                out.push(HalfSpace {
                    a: a.iter().map(|c| -c).collect(),
                    b: -&lo.value,
                    strict: lo.strict,
                });
            }
        }
        out
    }

    /// The intersection.
    pub fn intersect(&self, other: &Poly) -> Poly {
        let mut p = self.clone();
        if other.empty {
            p.set_empty();
        }
        for h in other.half_spaces() {
            p.add(h);
        }
        p
    }

    /// True when `v` is in it.
    pub fn contains(&self, v: &[Q]) -> bool {
        !self.empty && self.half_spaces().iter().all(|h| h.holds(v))
    }

    /// `∃ x_k`: the projection along variable `k` (the dimension is kept; `x_k` is then
    /// unconstrained).
    pub fn exists(&self, k: usize) -> Poly {
        if self.empty {
            return self.clone();
        }
        let hs = self.half_spaces();
        let mut out = Poly::universe(self.dim);
        // An equality on x_k: substitute it.
        if let Some((d, b)) = self.dirs.iter().find(|(d, b)| {
            d[k] != 0 && matches!((&b.lo, &b.hi), (Some(lo), Some(hi)) if lo.value == hi.value)
        }) {
            let e: Vec<Q> = d.iter().map(|c| Q::int(*c)).collect();
            let ev = b.hi.as_ref().map(|h| h.value).unwrap_or_default();
            for h in hs {
                if h.a[k].is_zero() {
                    out.add(h);
                    continue;
                }
                let f = h.a[k] / e[k];
                let a: Vec<Q> = h.a.iter().zip(&e).map(|(x, y)| x - f * y).collect();
                let rhs = h.b - f * ev;
                out.add(HalfSpace {
                    a,
                    b: rhs,
                    strict: h.strict,
                });
            }
            return out;
        }
        let (mut pos, mut neg) = (Vec::new(), Vec::new());
        for h in hs {
            if h.a[k].is_positive() {
                pos.push(h);
            } else if h.a[k].is_negative() {
                neg.push(h);
            } else {
                out.add(h);
            }
        }
        for p in &pos {
            for n in &neg {
                // (−n_k)·p + p_k·n eliminates x_k; both factors are positive.
                let fp = -&n.a[k];
                let fn_ = p.a[k];
                let a: Vec<Q> =
                    p.a.iter()
                        .zip(&n.a)
                        .map(|(x, y)| fp * x + fn_ * y)
                        .collect();
                out.add(HalfSpace {
                    a,
                    b: fp * p.b + fn_ * n.b,
                    strict: p.strict || n.strict,
                });
                if out.empty {
                    return out;
                }
            }
        }
        out
    }

    /// `∃ x_k` for every `k` of `vars`.
    pub fn exists_all(&self, vars: &[usize]) -> Poly {
        vars.iter().fold(self.clone(), |p, &k| p.exists(k))
    }

    /// True when no point satisfies it (exact simplex, [`super::lp`]).
    pub fn is_empty(&self) -> bool {
        self.empty || !super::lp::satisfiable(&self.half_spaces(), self.dim)
    }

    /// The same question answered by Fourier–Motzkin (every variable eliminated): the
    /// independent check of the simplex in the tests.
    pub fn is_empty_fm(&self) -> bool {
        let mut p = self.clone();
        loop {
            if p.empty {
                return true;
            }
            // Eliminate the variable with the fewest combinations.
            let mut best: Option<(usize, usize)> = None;
            for k in 0..p.dim {
                let (mut np, mut nn) = (0usize, 0usize);
                for (d, b) in &p.dirs {
                    if d[k] == 0 {
                        continue;
                    }
                    let sides = usize::from(b.lo.is_some()) + usize::from(b.hi.is_some());
                    np += sides;
                    nn += sides;
                }
                if np == 0 {
                    continue;
                }
                let cost = np * nn;
                if best.is_none_or(|(_, c)| cost < c) {
                    best = Some((k, cost));
                }
            }
            let Some((k, _)) = best else {
                return false;
            };
            p = p.exists(k);
        }
    }

    /// True when every point of `self` is in `other`.
    pub fn is_subset(&self, other: &Poly) -> bool {
        if self.empty || self.is_empty() {
            return true;
        }
        if other.empty {
            return false;
        }
        other.half_spaces().iter().all(|h| {
            if self.implies_syntactically(h) {
                return true;
            }
            let mut p = self.clone();
            p.add(h.negation());
            p.is_empty()
        })
    }

    /// True when a bound of `self` on `h`'s direction is at least as tight as `h`.
    fn implies_syntactically(&self, h: &HalfSpace) -> bool {
        let Some((d, k, positive)) = direction(&h.a) else {
            return false;
        };
        let Some(b) = self.dirs.get(&d) else {
            return false;
        };
        let value = h.b * k;
        if positive {
            b.hi.as_ref().is_some_and(|hi| {
                hi.value < value || (hi.value == value && (hi.strict || !h.strict))
            })
        } else {
            let value = -value;
            b.lo.as_ref().is_some_and(|lo| {
                lo.value > value || (lo.value == value && (lo.strict || !h.strict))
            })
        }
    }

    /// The bound of `d·x` over the polyhedron: `None` when empty, `Some(None)` when
    /// unbounded, else the supremum and whether it is attained (`false`: strict).
    pub fn sup(&self, d: &[Q]) -> Option<Option<(Q, bool)>> {
        if self.is_empty() {
            return None;
        }
        let s = super::lp::sup(&self.half_spaces(), self.dim, d)?;
        let Some(v) = s else {
            return Some(None);
        };
        let mut at = self.clone();
        at.add(HalfSpace::le(d.iter().map(|c| -*c).collect(), -v));
        Some(Some((v, !at.is_empty())))
    }

    /// Mutual inclusion.
    pub fn same_set(&self, other: &Poly) -> bool {
        self.is_subset(other) && other.is_subset(self)
    }

    /// Removes the bounds implied by the others (and normalises an empty polyhedron).
    pub fn minimize(&self) -> Poly {
        if self.empty || self.is_empty() {
            return Poly::empty(self.dim);
        }
        let mut hs = self.half_spaces();
        let mut i = 0;
        while i < hs.len() {
            let mut rest = Poly::universe(self.dim);
            for (j, h) in hs.iter().enumerate() {
                if j != i {
                    rest.add(h.clone());
                }
            }
            rest.add(hs[i].negation());
            if rest.is_empty() {
                hs.remove(i);
            } else {
                i += 1;
            }
        }
        let mut p = Poly::universe(self.dim);
        for h in hs {
            p.add(h);
        }
        p
    }

    /// Points reached from `self` by letting time flow with `rates` (`sign = 1`, the
    /// continuous successor without invariant) or from which `self` is reached
    /// (`sign = −1`, the predecessor): `{v ± t·r : v ∈ self, t ≥ 0}`.
    pub fn elapse(&self, rates: &[Q], forward: bool) -> Poly {
        if self.empty {
            return self.clone();
        }
        // Variable t is dimension `dim`; x_old = x_new ∓ t·r.
        let n = self.dim;
        let mut p = Poly::universe(n + 1);
        for h in self.half_spaces() {
            let ar = dot(&h.a, rates);
            let mut a = h.a.clone();
            a.push(if forward { -ar } else { ar });
            p.add(HalfSpace {
                a,
                b: h.b,
                strict: h.strict,
            });
        }
        let mut t = vec![Q::zero(); n + 1];
        t[n] = -Q::one();
        p.add(HalfSpace::le(t, Q::zero()));
        let q = p.exists(n);
        let mut out = Poly::universe(n);
        if q.empty {
            out.set_empty();
            return out;
        }
        for mut h in q.half_spaces() {
            h.a.pop();
            out.add(h);
        }
        out
    }

    /// `∃R. self`, then `x_r = 0` for every `r` of `resets`.
    pub fn reset(&self, resets: &[usize]) -> Poly {
        let mut p = self.exists_all(resets);
        for &r in resets {
            let mut a = vec![Q::zero(); self.dim];
            a[r] = Q::one();
            p.add_eq(a, Q::zero());
        }
        p
    }
}

fn tighter_hi(new: &Bound, old: &Bound) -> bool {
    new.value < old.value || (new.value == old.value && new.strict && !old.strict)
}

fn tighter_lo(new: &Bound, old: &Bound) -> bool {
    new.value > old.value || (new.value == old.value && new.strict && !old.strict)
}

/// Prints a polyhedron with variable names, one conjunct per direction:
/// `0 <= x - y < 2000 ∧ y <= 10000`, `x == 0`, `true`, `false`.
pub struct Display<'a> {
    /// The polyhedron.
    pub poly: &'a Poly,
    /// A name per dimension.
    pub names: &'a [String],
}

impl fmt::Display for Display<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.poly.empty {
            return f.write_str("false");
        }
        if self.poly.dirs.is_empty() {
            return f.write_str("true");
        }
        let parts: Vec<String> = self
            .poly
            .dirs
            .iter()
            .map(|(d, b)| conjunct(d, b, self.names))
            .collect();
        f.write_str(&parts.join(" && "))
    }
}

/// Prints a rational as an integer or `p/q`.
pub fn show_q(q: &Q) -> String {
    q.to_string()
}

fn conjunct(d: &[BigInt], b: &Bounds, names: &[String]) -> String {
    let mut expr = String::new();
    for (c, name) in d.iter().zip(names) {
        if *c == 0 {
            continue;
        }
        let mag = c.abs();
        let sign = if *c < 0 { "-" } else { "+" };
        if expr.is_empty() {
            if *c < 0 {
                expr.push('-');
            }
        } else {
            expr.push_str(&format!(" {sign} "));
        }
        if mag == 1 {
            expr.push_str(name);
        } else {
            expr.push_str(&format!("{mag}*{name}"));
        }
    }
    match (&b.lo, &b.hi) {
        (Some(lo), Some(hi)) if lo.value == hi.value => format!("{expr} == {}", show_q(&lo.value)),
        (Some(lo), Some(hi)) => format!(
            "{} {} {expr} {} {}",
            show_q(&lo.value),
            if lo.strict { "<" } else { "<=" },
            if hi.strict { "<" } else { "<=" },
            show_q(&hi.value)
        ),
        (Some(lo), None) => format!(
            "{expr} {} {}",
            if lo.strict { ">" } else { ">=" },
            show_q(&lo.value)
        ),
        (None, Some(hi)) => format!(
            "{expr} {} {}",
            if hi.strict { "<" } else { "<=" },
            show_q(&hi.value)
        ),
        (None, None) => "true".into(),
    }
}
