// The truth tables are written as the formulas they test (a majority is "ab + ac +
// bc"), not in the minimal form clippy would prefer.
#![allow(clippy::nonminimal_bool)]

use super::*;
use std::path::Path;

/// Truth table from an on-set (index = 8X1 + 4X2 + 2X3 + X4 for n = 4).
fn table(n: usize, on: &[u64]) -> Vec<bool> {
    (0..1u64 << n).map(|x| on.contains(&x)).collect()
}

fn from_fn(n: usize, f: impl Fn(&[bool]) -> bool) -> Vec<bool> {
    (0..1u64 << n)
        .map(|x| {
            let b: Vec<bool> = (0..n).map(|i| x >> (n - 1 - i) & 1 == 1).collect();
            f(&b)
        })
        .collect()
}

fn figures(n: usize, f: &[bool], w: Tests) -> (usize, usize, f64) {
    let t = build(n, f, w);
    for x in 0..1u64 << n {
        assert_eq!(t.eval(x), f[x as usize], "tree differs from F at {x}");
    }
    let s = t.stats();
    assert_eq!(s.leaves, s.internal + 1, "l = k + 1");
    (s.internal, s.depth, s.mean)
}

fn close(a: (usize, usize, f64), b: (usize, usize, f64)) {
    assert_eq!((a.0, a.1), (b.0, b.1), "{a:?} vs {b:?}");
    assert!((a.2 - b.2).abs() < 1e-9, "{a:?} vs {b:?}");
}

#[test]
fn majority_of_three() {
    let f = from_fn(3, |x| (x[0] && x[1]) || (x[0] && x[2]) || (x[1] && x[2]));
    assert_eq!(
        f.iter()
            .enumerate()
            .filter(|(_, v)| **v)
            .map(|(i, _)| i)
            .collect::<Vec<_>>(),
        vec![3, 5, 6, 7]
    );
    close(figures(3, &f, Tests::Single), (5, 3, 2.5));
    close(figures(3, &f, Tests::Pairs), (3, 3, 2.375));
    for (_, h) in root_entropies(3, &f, Tests::Single) {
        assert!((h - 0.8113).abs() < 1e-4);
    }
}

#[test]
fn chapter_three_examples() {
    let ex1 = from_fn(4, |x| x[0] || x[1] || (x[2] && x[3]));
    let ex2 = table(4, &[7, 8]);
    let ex3 = table(4, &[4, 7, 9, 10, 12, 13, 14, 15]);
    let ex4 = from_fn(4, |x| (x[0] && x[1]) || (x[1] && x[2]) || (x[0] && x[2]));
    close(figures(4, &ex1, Tests::Single), (4, 4, 1.875));
    close(figures(4, &ex1, Tests::Pairs), (2, 2, 1.25));
    close(figures(4, &ex2, Tests::Single), (7, 4, 2.75));
    close(figures(4, &ex2, Tests::Pairs), (3, 3, 1.75));
    close(figures(4, &ex3, Tests::Single), (9, 4, 3.0));
    close(figures(4, &ex3, Tests::Pairs), (5, 4, 2.75));
    close(figures(4, &ex4, Tests::Single), (5, 3, 2.5));
    close(figures(4, &ex4, Tests::Pairs), (3, 3, 2.375));
    // Why example 3 is not minimal: X1, X2 beat X3, X4 at the root.
    let h = root_entropies(4, &ex3, Tests::Single);
    let hv: Vec<f64> = h.iter().map(|(_, h)| *h).collect();
    assert!((hv[0] - 0.8113).abs() < 1e-4 && (hv[1] - 0.8113).abs() < 1e-4);
    assert!((hv[2] - 1.0).abs() < 1e-9 && (hv[3] - 1.0).abs() < 1e-9);
    // Ex. 2 with pair tests: X1⊕X2 at the root.
    let t = build(4, &ex2, Tests::Pairs);
    assert!(matches!(
        t.rows[0],
        Row::Test {
            test: Test::Xor(0, 1),
            ..
        }
    ));
}

#[test]
fn pla_and_sequential_examples() {
    let pla1 = table(4, &[0, 1, 4, 5, 6, 7, 8, 10, 12, 13, 14, 15]);
    let pla2 = table(4, &[0, 1, 2, 3, 7, 11, 15]);
    let pla3 = table(4, &[0, 2, 8, 10, 14, 15]);
    let i8 = table(4, &[6, 7, 8, 9, 12, 13, 14]);
    close(figures(4, &pla1, Tests::Single), (6, 4, 2.25));
    close(figures(4, &pla1, Tests::Pairs), (4, 3, 2.125));
    close(figures(4, &pla2, Tests::Single), (6, 4, 2.625));
    close(figures(4, &pla2, Tests::Pairs), (2, 2, 1.75));
    close(figures(4, &pla3, Tests::Single), (7, 4, 2.75));
    close(figures(4, &pla3, Tests::Pairs), (3, 3, 1.9375));
    close(figures(4, &i8, Tests::Single), (6, 4, 2.625));
    close(figures(4, &i8, Tests::Pairs), (3, 3, 2.0));
}

#[test]
fn mask_table_of_fig_i12() {
    // F = X1X2 + X1X3 + X2X3 on 7-bit words, X1 the most significant.
    let m = MaskTable {
        rows: vec![
            (0b1100000, 0b1100000),
            (0b1010000, 0b1010000),
            (0b0110000, 0b0110000),
        ],
    };
    for x in 0..128u64 {
        let (a, b, c) = (x >> 6 & 1 == 1, x >> 5 & 1 == 1, x >> 4 & 1 == 1);
        assert_eq!(m.eval(x), (a && b) || (a && c) || (b && c));
    }
}

/// The paper's station's filter compiled both ways equals the direct evaluation of the
/// monomials on every assignment of its support (the shipped station's device
/// monitoring makes its support too large for a tree:
/// `shipped_station_masks_are_exact_on_random_frames`).
#[test]
fn station_filter_compiled_forms_are_exact() {
    let b = crate::test_support::paper_bundle();
    let c = CompiledFilter::new(&b.constraints, Tests::Single).expect("compile");
    let n = c.vars.len();
    assert!(n <= MAX_TREE_VARS, "support {n}");
    let tree = c.tree.as_ref().expect("tree");
    let mut frame = Frame::new(b.symbols.sizes());
    let dnfs: Vec<&expr::Dnf> = b.constraints.constraints.iter().map(|c| &c.dnf).collect();
    for x in 0..1u64 << n {
        c.unpack_into(x, &mut frame);
        let direct = dnfs.iter().any(|d| expr::eval_dnf(d, &frame));
        assert_eq!(tree.eval(x), direct, "tree at {x:#x}");
        assert_eq!(c.eval_masks(&frame), direct, "masks at {x:#x}");
        assert_eq!(c.eval_tree(&frame), direct);
    }
    let s = tree.stats();
    assert!(s.depth <= n);
}

/// The shipped station (36 variables with its device monitoring: no tree, the mask
/// table) equals the direct evaluation on random frames.
#[test]
fn shipped_station_masks_are_exact_on_random_frames() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
    let (b, _) = crate::bundle::PlantBundle::load(&dir).expect("bundle");
    let c = CompiledFilter::new(&b.constraints, Tests::Single).expect("compile");
    assert!(c.vars.len() > MAX_TREE_VARS && c.tree.is_none());
    let dnfs: Vec<&expr::Dnf> = b.constraints.constraints.iter().map(|c| &c.dnf).collect();
    let mut frame = Frame::new(b.symbols.sizes());
    let mut rng = crate::synthetic::SplitMix64::new(36);
    let mut violated = 0;
    for _ in 0..200_000 {
        c.unpack_into(rng.next_u64(), &mut frame);
        let direct = dnfs.iter().any(|d| expr::eval_dnf(d, &frame));
        assert_eq!(c.eval_masks(&frame), direct);
        assert_eq!(c.eval_tree(&frame), direct);
        violated += usize::from(direct);
    }
    assert!(violated > 1_000 && violated < 199_000, "{violated}");
}

proptest::proptest! {
    /// On the synthetic plant (support too large to enumerate) the mask table equals the
    /// direct evaluation on random frames.
    #[test]
    fn synthetic_masks_equal_direct(seed in 0u64..1000) {
        let syn = crate::synthetic::generate(40, 60, 7);
        let c = CompiledFilter::new(&syn.constraints, Tests::Single);
        if let Ok(c) = c {
            let mut rng = crate::synthetic::SplitMix64::new(seed);
            let mut frame = Frame::new(syn.symbols.sizes());
            let x = rng.next_u64();
            c.unpack_into(x, &mut frame);
            let direct = syn.constraints.constraints.iter().any(|k| expr::eval_dnf(&k.dnf, &frame));
            proptest::prop_assert_eq!(c.eval_masks(&frame), direct);
            proptest::prop_assert_eq!(SparseMasks::new(&syn.constraints).eval(&frame), direct);
            proptest::prop_assert_eq!(c.eval_tree(&frame), direct);
        }
    }
}
