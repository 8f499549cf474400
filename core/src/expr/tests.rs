use super::*;
use crate::frame::Frame;
use crate::symbols::Space;
use proptest::prelude::*;

/// A compact prefix rendering of the tree: `(+ (. (/ a) b) c)`, `RE(A4)`, `x*`.
fn show(e: &Expr) -> String {
    match e {
        Expr::Const(v) => u8::from(*v).to_string(),
        Expr::Leaf { name, kind, .. } => match kind {
            LeafKind::Now => name.clone(),
            LeafKind::Prev => format!("{name}*"),
            LeafKind::Rise => format!("RE({name})"),
            LeafKind::Fall => format!("FE({name})"),
            LeafKind::Estimate => format!("EST({name})"),
        },
        Expr::Not(inner) => format!("(/ {})", show(inner)),
        Expr::And(v) => format!("(. {})", v.iter().map(show).collect::<Vec<_>>().join(" ")),
        Expr::Or(v) => format!("(+ {})", v.iter().map(show).collect::<Vec<_>>().join(" ")),
    }
}

#[track_caller]
fn check(text: &str, expected: &str) {
    match parse_str(text) {
        Ok(e) => assert_eq!(show(&e), expected, "parsing {text:?}"),
        Err(err) => panic!(
            "parsing {text:?}: {} at column {}",
            err.message, err.span.column
        ),
    }
}

#[track_caller]
fn check_error(text: &str, message: &str, column: usize) {
    match parse_str(text) {
        Ok(e) => panic!("parsing {text:?} should fail, got {}", show(&e)),
        Err(err) => {
            assert_eq!(err.message, message, "parsing {text:?}");
            assert_eq!(
                err.span,
                Span { line: 1, column },
                "parsing {text:?}: {message}"
            );
        }
    }
}

#[test]
fn precedence_not_and_or() {
    check("a . b + c", "(+ (. a b) c)");
    check("a + b . c", "(+ a (. b c))");
    check("/a . b", "(. (/ a) b)");
    check("/a + /b . c", "(+ (/ a) (. (/ b) c))");
    check("/(a + b) . c", "(. (/ (+ a b)) c)");
    check("a . (b + c)", "(. a (+ b c))");
    check("a.b.c+d+e", "(+ (. a b c) d e)");
    check("//a", "(/ (/ a))");
    check("!a · ¬b", "(. (/ a) (/ b))");
}

#[test]
fn previous_values_and_edges() {
    check("x*", "x*");
    check("PRE(x)", "x*");
    check("/x* . y", "(. (/ x*) y)");
    check("RE(A4)", "RE(A4)");
    check("FE(A4)", "FE(A4)");
    check("RE ( A4 )", "RE(A4)");
    check("EST(C4)", "EST(C4)");
    // Without parentheses the function names are plain names.
    check("RE . FE", "(. RE FE)");
}

#[test]
fn names_constants_qualified_nesting() {
    check("2P . A0", "(. 2P A0)");
    check("def_C4", "def_C4");
    check("0", "0");
    check("1 + 0", "(+ 1 0)");
    check("turn:infeasible . a", "(. turn:infeasible a)");
    check("((a))", "a");
    check(
        "(((a + b) . (c + /(d . e))))",
        "(. (+ a b) (+ c (/ (. d e))))",
    );
    check("  a  ", "a");
}

#[test]
fn leaves_keep_their_position() {
    let e = parse("C3 . /C4 . RE(A4)", Span { line: 7, column: 9 }).unwrap();
    let leaves: Vec<_> = e
        .leaves()
        .into_iter()
        .map(|(n, k, s)| (n, k, s.line, s.column))
        .collect();
    assert_eq!(
        leaves,
        vec![
            ("C3", LeafKind::Now, 7, 9),
            ("C4", LeafKind::Now, 7, 15),
            ("A4", LeafKind::Rise, 7, 23),
        ]
    );
    assert_eq!(e.first_span(), Some(Span { line: 7, column: 9 }));
}

#[test]
fn syntax_errors_name_the_token_and_column() {
    // Unexpected character (columns count characters, not bytes).
    check_error("C0 & C1", "unexpected character `&`", 4);
    check_error("C0 · C1 & C2", "unexpected character `&`", 9);
    check_error("C0 . é", "unexpected character `é`", 6);
    check_error("a:", "unexpected character `:`", 2);
    // Missing `)`.
    check_error("(C0 . C1", "expected `)`, found end of expression", 9);
    check_error("(C0 . C1 C2)", "expected `)`, found `C2`", 10);
    check_error("RE(A4", "expected `)`, found end of expression", 6);
    check_error("RE(A4*)", "expected `)`, found `*`", 6);
    // Dangling operators.
    check_error(
        "C0 .",
        "expected a name, `/` or `(`, found end of expression",
        5,
    );
    check_error("C0 + + C1", "expected a name, `/` or `(`, found `+`", 6);
    check_error(". C0", "expected a name, `/` or `(`, found `.`", 1);
    check_error(
        "C0 /",
        "expected `.`, `+` or end of expression, found `/`",
        4,
    );
    check_error(
        "/",
        "expected a name, `/` or `(`, found end of expression",
        2,
    );
    check_error("*", "expected a name, `/` or `(`, found `*`", 1);
    // Empty expression.
    check_error(
        "",
        "expected a name, `/` or `(`, found end of expression",
        1,
    );
    check_error(
        "   ",
        "expected a name, `/` or `(`, found end of expression",
        4,
    );
    check_error("()", "expected a name, `/` or `(`, found `)`", 2);
    // Edge without a name.
    check_error("RE()", "expected a name inside `RE(…)`, found `)`", 4);
    check_error("FE(/A4)", "expected a name inside `FE(…)`, found `/`", 4);
    check_error(
        "PRE(",
        "expected a name inside `PRE(…)`, found end of expression",
        5,
    );
    // Numbers other than 0 and 1.
    check_error("2", "`2` is not a name nor the constant 0 or 1", 1);
    check_error("a . 01", "`01` is not a name nor the constant 0 or 1", 5);
    // Trailing garbage.
    check_error(
        "C0 C1",
        "expected `.`, `+` or end of expression, found `C1`",
        4,
    );
    check_error(
        "C0)",
        "expected `.`, `+` or end of expression, found `)`",
        3,
    );
    check_error(
        "x**",
        "expected `.`, `+` or end of expression, found `*`",
        3,
    );
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let deep = format!("{}a{}", "(".repeat(10_000), ")".repeat(10_000));
    let err = parse_str(&deep).unwrap_err();
    assert_eq!(err.message, "expression nested too deeply");
    let nots = format!("{}a", "/".repeat(10_000));
    assert_eq!(
        parse_str(&nots).unwrap_err().message,
        "expression nested too deeply"
    );
    // 60 levels are fine.
    check(&format!("{}a{}", "(".repeat(60), ")".repeat(60)), "a");
}

/// Inputs C0..C3, output A0, auxiliary `EST(C1)` (a diagnoser's estimate).
fn symbols() -> Symbols {
    let mut s = Symbols::new();
    for n in ["C0", "C1", "C2", "C3"] {
        s.declare(n, Space::Input).unwrap();
    }
    s.declare("A0", Space::Output).unwrap();
    s.declare(&crate::symbols::estimate_name("C1"), Space::Aux)
        .unwrap();
    s
}

#[track_caller]
fn check_dnf(text: &str, expected: &str) {
    let s = symbols();
    let dnf = parse_str(text).unwrap().to_dnf(&s).unwrap();
    assert_eq!(render_dnf(&dnf, &s), expected, "DNF of {text:?}");
}

#[track_caller]
fn check_name_error(text: &str, message: &str, column: usize) {
    let err = parse_str(text).unwrap().to_dnf(&symbols()).unwrap_err();
    assert_eq!(
        (err.message.as_str(), err.span.column),
        (message, column),
        "{text:?}"
    );
}

#[test]
fn edges_expand_as_in_the_paper() {
    check_dnf("RE(C0)", "C0 . /C0*");
    check_dnf("FE(C0)", "/C0 . C0*");
    check_dnf("/RE(C0)", "/C0 + C0*");
    check_dnf("/FE(C0)", "C0 + /C0*");
    check_dnf("C0* . PRE(C1)", "C0* . C1*");
    check_dnf("0", "0");
    check_dnf("1", "1");
    check_dnf("/(C0 + C1)", "/C0 . /C1");
    check_dnf("(C0 + C1) . C2", "C0 . C2 + C1 . C2");
    // Contradictions are kept by to_dnf (static checks report them), dropped by simplify.
    check_dnf("C0 . /C0", "/C0 . C0");
    let s = symbols();
    let d = parse_str("C0 . /C0 + C1 + C1 . C2")
        .unwrap()
        .to_dnf(&s)
        .unwrap();
    assert_eq!(render_dnf(&simplify(&d), &s), "C1");
}

#[test]
fn name_errors_point_at_the_name() {
    check_name_error("C0 . X9", "unknown signal `X9`", 6);
    check_name_error("RE(  X9)", "unknown signal `X9`", 6);
    check_name_error(
        "EST(A0)",
        "`EST(A0)` needs a sensor, and `A0` is not one",
        5,
    );
    check_name_error("EST(Z)", "unknown signal `Z`", 5);
    check_name_error(
        "C1 . EST(C2)",
        "no diagnoser provides the estimate `EST(C2)`",
        10,
    );
    check_dnf("EST(C1) . C0", "C0 . EST(C1)");
}

#[test]
fn too_many_terms_is_an_error() {
    // (C0 + /C0 + C1) repeated 8 times expands to 3^8 = 6561 terms.
    let text = ["(C0 + /C0 + C1)"; 8].join(" . ");
    let err = parse_str(&text).unwrap().to_dnf(&symbols()).unwrap_err();
    assert_eq!(
        err.message,
        format!("expression expands to more than {MAX_TERMS} product terms")
    );
    assert_eq!(err.span.column, 2);
}

/// Reference semantics: evaluate the tree directly.
fn eval(e: &Expr, now: &[bool], prev: &[bool]) -> bool {
    let idx = |name: &str| name[1..].parse::<usize>().unwrap();
    match e {
        Expr::Const(v) => *v,
        Expr::Leaf { name, kind, .. } => {
            let i = idx(name);
            match kind {
                LeafKind::Now | LeafKind::Estimate => now[i],
                LeafKind::Prev => prev[i],
                LeafKind::Rise => !prev[i] && now[i],
                LeafKind::Fall => prev[i] && !now[i],
            }
        }
        Expr::Not(inner) => !eval(inner, now, prev),
        Expr::And(v) => v.iter().all(|x| eval(x, now, prev)),
        Expr::Or(v) => v.iter().any(|x| eval(x, now, prev)),
    }
}

fn arb_expr() -> impl Strategy<Value = Expr> {
    let leaf = prop_oneof![
        any::<bool>().prop_map(Expr::Const),
        (0..4usize, 0..4usize).prop_map(|(i, k)| Expr::Leaf {
            name: format!("C{i}"),
            kind: [
                LeafKind::Now,
                LeafKind::Prev,
                LeafKind::Rise,
                LeafKind::Fall
            ][k],
            span: Span { line: 1, column: 1 },
        }),
    ];
    leaf.prop_recursive(4, 24, 3, |inner| {
        prop_oneof![
            inner.clone().prop_map(|e| Expr::Not(Box::new(e))),
            prop::collection::vec(inner.clone(), 2..4).prop_map(Expr::And),
            prop::collection::vec(inner, 2..4).prop_map(Expr::Or),
        ]
    })
}

fn frame_for(bits: u32) -> (Frame, Vec<bool>, Vec<bool>) {
    let s = symbols();
    let mut f = Frame::new(s.sizes());
    let now: Vec<bool> = (0..4).map(|i| bits >> i & 1 == 1).collect();
    let prev: Vec<bool> = (0..4).map(|i| bits >> (i + 4) & 1 == 1).collect();
    f.now[Space::Input as usize] = crate::bits::Bits::from_bools(&now);
    f.prev[Space::Input as usize] = crate::bits::Bits::from_bools(&prev);
    (f, now, prev)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// The DNF, its simplification and its re-parsed rendering all agree with the tree on
    /// every one of the 2^8 assignments of C0..C3 at t and t-1.
    #[test]
    fn dnf_agrees_with_direct_evaluation(e in arb_expr()) {
        let s = symbols();
        let dnf = e.to_dnf(&s).unwrap();
        let simple = simplify(&dnf);
        let reparsed = parse_str(&render_dnf(&dnf, &s)).unwrap().to_dnf(&s).unwrap();
        for bits in 0..256u32 {
            let (frame, now, prev) = frame_for(bits);
            let want = eval(&e, &now, &prev);
            prop_assert_eq!(eval_dnf(&dnf, &frame), want, "dnf {}", render_dnf(&dnf, &s));
            prop_assert_eq!(eval_dnf(&simple, &frame), want, "simplified {}", render_dnf(&simple, &s));
            prop_assert_eq!(eval_dnf(&reparsed, &frame), want);
        }
        // simplify keeps no contradictory term and no absorbed term.
        prop_assert!(simple.iter().all(|t| !is_contradictory(t)));
        for (i, a) in simple.iter().enumerate() {
            for (j, b) in simple.iter().enumerate() {
                prop_assert!(i == j || !a.iter().all(|l| b.contains(l)));
            }
        }
    }

    /// Parsing never panics, whatever the text.
    #[test]
    fn parse_never_panics(text in "[ ()/!.+*a-zA-Z0-9_:·¬&é]{0,40}") {
        if let Ok(e) = parse_str(&text) {
            let _ = e.to_dnf(&symbols());
        }
    }
}
