//! Exact rationals on `i128`, checked: the synthesis's numbers are small (milliseconds
//! and coefficients of a few units), so big integers would only cost time (they made
//! the workshop's synthesis 20 times slower). Every operation is checked; one that
//! overflows raises a per-thread flag that [`overflowed`] reads and clears, and the
//! synthesis then reports the overflow instead of a result: exact when it answers.

use std::cell::Cell;
use std::cmp::Ordering;
use std::fmt;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

thread_local! {
    static OVERFLOW: Cell<bool> = const { Cell::new(false) };
}

/// True when an operation overflowed on this thread since the last call (and clears it).
pub fn overflowed() -> bool {
    OVERFLOW.with(|f| f.replace(false))
}

fn poison() -> Q {
    OVERFLOW.with(|f| f.set(true));
    Q { n: 0, d: 1 }
}

/// The greatest common divisor of `|a|` and `|b|`.
pub(crate) fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// An exact rational `n/d`, `d > 0`, in lowest terms.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Q {
    n: i128,
    d: i128,
}

impl Q {
    /// `n/d` (`d ≠ 0`), reduced.
    pub fn new(n: i128, d: i128) -> Q {
        if d == 1 {
            return Q::int(n);
        }
        if d == 0 || n == i128::MIN || d == i128::MIN {
            return poison();
        }
        let g = gcd(n, d).max(1);
        let s = if d < 0 { -1 } else { 1 };
        Q {
            n: s * n / g,
            d: s * d / g,
        }
    }

    /// The integer `n`.
    pub const fn int(n: i128) -> Q {
        Q { n, d: 1 }
    }

    /// 0.
    pub const fn zero() -> Q {
        Q::int(0)
    }

    /// 1.
    pub const fn one() -> Q {
        Q::int(1)
    }

    /// Numerator.
    pub fn numer(&self) -> i128 {
        self.n
    }

    /// Denominator (positive).
    pub fn denom(&self) -> i128 {
        self.d
    }

    /// True for 0.
    pub fn is_zero(&self) -> bool {
        self.n == 0
    }

    /// True above 0.
    pub fn is_positive(&self) -> bool {
        self.n > 0
    }

    /// True below 0.
    pub fn is_negative(&self) -> bool {
        self.n < 0
    }

    /// True when the denominator is 1.
    pub fn is_integer(&self) -> bool {
        self.d == 1
    }

    /// The nearest integer at or above.
    pub fn ceil(&self) -> i128 {
        self.n.div_euclid(self.d) + i128::from(self.n.rem_euclid(self.d) != 0)
    }

    /// The nearest integer at or below.
    pub fn floor(&self) -> i128 {
        self.n.div_euclid(self.d)
    }

    /// An approximation, for display.
    #[allow(clippy::cast_precision_loss)]
    pub fn to_f64(&self) -> f64 {
        self.n as f64 / self.d as f64
    }
}

fn add(a: Q, b: Q) -> Q {
    if a.d == 1 && b.d == 1 {
        return a.n.checked_add(b.n).map_or_else(poison, Q::int);
    }
    let g = gcd(a.d, b.d);
    let (Some(l), Some(r), Some(d)) = (
        a.n.checked_mul(b.d / g),
        b.n.checked_mul(a.d / g),
        a.d.checked_mul(b.d / g),
    ) else {
        return poison();
    };
    match l.checked_add(r) {
        Some(n) => Q::new(n, d),
        None => poison(),
    }
}

fn mul(a: Q, b: Q) -> Q {
    if a.n == 0 || b.n == 0 {
        return Q::zero();
    }
    if a.d == 1 && b.d == 1 {
        return a.n.checked_mul(b.n).map_or_else(poison, Q::int);
    }
    let g1 = gcd(a.n, b.d).max(1);
    let g2 = gcd(b.n, a.d).max(1);
    match (
        (a.n / g1).checked_mul(b.n / g2),
        (a.d / g2).checked_mul(b.d / g1),
    ) {
        (Some(n), Some(d)) => Q::new(n, d),
        _ => poison(),
    }
}

fn div(a: Q, b: Q) -> Q {
    if b.n == 0 {
        return poison();
    }
    mul(a, Q::new(b.d, b.n))
}

impl Neg for Q {
    type Output = Q;
    fn neg(self) -> Q {
        Q {
            n: self.n.checked_neg().unwrap_or_else(|| poison().n),
            d: self.d,
        }
    }
}

impl Neg for &Q {
    type Output = Q;
    fn neg(self) -> Q {
        -*self
    }
}

macro_rules! binop {
    ($tr:ident, $m:ident, $f:ident) => {
        impl $tr<Q> for Q {
            type Output = Q;
            fn $m(self, o: Q) -> Q {
                $f(self, o)
            }
        }
        impl $tr<&Q> for Q {
            type Output = Q;
            fn $m(self, o: &Q) -> Q {
                $f(self, *o)
            }
        }
        impl $tr<Q> for &Q {
            type Output = Q;
            fn $m(self, o: Q) -> Q {
                $f(*self, o)
            }
        }
        impl $tr<&Q> for &Q {
            type Output = Q;
            fn $m(self, o: &Q) -> Q {
                $f(*self, *o)
            }
        }
    };
}

fn sub(a: Q, b: Q) -> Q {
    add(a, -b)
}

binop!(Add, add, add);
binop!(Sub, sub, sub);
binop!(Mul, mul, mul);
binop!(Div, div, div);

impl AddAssign for Q {
    fn add_assign(&mut self, o: Q) {
        *self = add(*self, o);
    }
}

impl SubAssign for Q {
    fn sub_assign(&mut self, o: Q) {
        *self = sub(*self, o);
    }
}

impl MulAssign<&Q> for Q {
    fn mul_assign(&mut self, o: &Q) {
        *self = mul(*self, *o);
    }
}

impl Ord for Q {
    fn cmp(&self, o: &Q) -> Ordering {
        if self.d == 1 && o.d == 1 {
            return self.n.cmp(&o.n);
        }
        match (self.n.checked_mul(o.d), o.n.checked_mul(self.d)) {
            (Some(l), Some(r)) => l.cmp(&r),
            _ => {
                poison();
                Ordering::Equal
            }
        }
    }
}

impl PartialOrd for Q {
    fn partial_cmp(&self, o: &Q) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl fmt::Display for Q {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.d == 1 {
            write!(f, "{}", self.n)
        } else {
            write!(f, "{}/{}", self.n, self.d)
        }
    }
}

/// Parses `12`, `-2.5`, `5/2`.
pub fn parse(text: &str) -> Option<Q> {
    let q = if let Some((n, d)) = text.split_once('/') {
        let d: i128 = d.parse().ok()?;
        let n: i128 = n.parse().ok()?;
        if d == 0 {
            return None;
        }
        Q::new(n, d)
    } else if let Some((i, f)) = text.split_once('.') {
        let n: i128 = format!("{i}{f}").parse().ok()?;
        Q::new(n, 10i128.checked_pow(u32::try_from(f.len()).ok()?)?)
    } else {
        Q::int(text.parse().ok()?)
    };
    (!overflowed()).then_some(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_is_exact_and_overflow_is_reported() {
        let a = Q::new(1, 3);
        let b = Q::new(1, 6);
        assert_eq!(a + b, Q::new(1, 2));
        assert_eq!(a - b, Q::new(1, 6));
        assert_eq!(a * b, Q::new(1, 18));
        assert_eq!(a / b, Q::int(2));
        assert!(Q::new(-1, 2) < Q::zero());
        assert_eq!(Q::new(3, -6), Q::new(-1, 2));
        assert_eq!(Q::new(7, 2).ceil(), 4);
        assert_eq!(Q::new(-7, 2).ceil(), -3);
        assert!(!overflowed());
        let big = Q::int(i128::MAX / 2);
        let _ = big * Q::int(3);
        assert!(overflowed());
        assert!(!overflowed());
        assert_eq!(parse("2.5"), Some(Q::new(5, 2)));
        assert_eq!(parse("5/0"), None);
    }
}
