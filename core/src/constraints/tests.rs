use super::*;
use crate::diag::Severity;
use crate::test_support::{station, station_dir};

/// The paper's 17 constraints (seed 004, equations (9)-(25)): id, class, outputs at t,
/// and the sum of products the loader builds (edges expanded, literals sorted).
const PAPER: [(&str, Class, &[&str], &str); 17] = [
    ("CSs1", Class::Simple, &["A0"], "A0 . 2P"),
    ("CSs2", Class::Simple, &["A1"], "C3 . /C4 . A1"),
    ("CSs3", Class::Simple, &["A1"], "C3 . C4 . C6 . A1"),
    ("CSs4", Class::Simple, &["A1"], "C3 . A1 . P36"),
    ("CSs5", Class::Simple, &["A3"], "/C5 . A3"),
    ("CSs6", Class::Simple, &["A2"], "C4 . C6 . A2"),
    ("CSs7", Class::Simple, &["A2"], "/C4 . /C5 . A2"),
    ("CSs8", Class::Simple, &["A4"], "C5 . C6 . /A4"),
    ("CSs9", Class::Simple, &["A4"], "C8 . /A4"),
    ("CSs10", Class::Simple, &["A4"], "C7 . /A4"),
    ("CSs11", Class::Simple, &["A4"], "/A4 . P67"),
    ("CSs12", Class::Simple, &["A2"], "C5 . C7 . A2"),
    ("CSs13", Class::Simple, &["A4"], "C4 . /C6 . A4"),
    ("CSs14", Class::Simple, &["A4"], "/C4 . A4 . /A4*"),
    ("CSs15", Class::Simple, &["A4"], "/C5 . /A4 . A4*"),
    ("CSc1", Class::Combined, &["A0", "A1"], "C0 . A0 . /A1"),
    ("CSc2", Class::Combined, &["A1", "A2"], "C3 . C4 . A1 . /A2"),
];

#[test]
fn the_paper_set_loads_without_problems_and_classifies() {
    let b = station();
    let text = std::fs::read_to_string(station_dir().join("constraints.txt")).unwrap();
    let (set, problems) = ConstraintSet::parse(&text, Path::new("constraints.txt"), &b.symbols);
    assert!(problems.is_empty(), "{}", crate::diag::render(&problems));
    // The paper's equations (9) to (25); the device monitoring's CSk* follow them.
    let got: Vec<_> = set
        .constraints
        .iter()
        .filter(|c| !c.id.starts_with("CSk"))
        .map(|c| {
            let outs: Vec<&str> = c
                .outputs
                .iter()
                .map(|&k| b.symbols.name(Space::Output, k))
                .collect();
            (
                c.id.as_str(),
                c.class,
                outs,
                expr::render_dnf(&c.dnf, &b.symbols),
            )
        })
        .collect();
    let want: Vec<_> = PAPER
        .iter()
        .map(|&(id, class, outs, dnf)| (id, class, outs.to_vec(), dnf.to_string()))
        .collect();
    assert_eq!(got, want);
    let edm: Vec<_> = set
        .constraints
        .iter()
        .filter(|c| c.id.starts_with("CSk"))
        .collect();
    assert_eq!(edm.len(), 16);
    assert!(
        edm.iter().all(|c| c.class == Class::Simple),
        "each cuts one supply"
    );
    // Locations point at the id; sources are the text after `=`, comment removed.
    let c10 = set.get("CSs10").unwrap();
    assert_eq!(c10.location.to_string(), "constraints.txt:14:1");
    assert_eq!(c10.source, "C7 . /A4");
    // The comment is the operator's description, without the paper's equation number.
    assert_eq!(
        c10.description,
        "box leaving to the right: hold the rotation"
    );
}

#[test]
fn a_description_is_the_comment_without_a_leading_reference() {
    let (set, problems) = load(
        "K1 = C7 . /A4 # (18) box leaving: hold\n\
         K2 = C8 . /A4\n\
         K3 = C6 . A2   #   (a box on the table) rollers stop  \n\
         K4 = C5 . A3 # #3 no (ref)\n",
    );
    assert!(problems.is_empty(), "{problems:?}");
    let d: Vec<&str> = set
        .constraints
        .iter()
        .map(|c| c.description.as_str())
        .collect();
    assert_eq!(
        d,
        [
            "box leaving: hold",
            "",
            "(a box on the table) rollers stop",
            "#3 no (ref)"
        ]
    );
}

/// Parses `text` against the station's symbols (inputs, outputs, observers) and returns
/// the set and the problems rendered as `file:line:column: severity[code]: message`.
fn load(text: &str) -> (ConstraintSet, Vec<String>) {
    let b = station();
    let (set, problems) = ConstraintSet::parse(text, Path::new("c.txt"), &b.symbols);
    for p in &problems {
        assert!(!p.message.is_empty());
        assert!(p.location.is_some(), "{p}");
    }
    (set, problems.iter().map(ToString::to_string).collect())
}

#[track_caller]
fn check(text: &str, expected: &[&str]) {
    let (_, problems) = load(text);
    assert_eq!(problems, expected, "problems of {text:?}");
}

#[test]
fn file_errors_have_file_line_column_and_message() {
    check(
        "A = C0 . X9 . A0",
        &["c.txt:1:10: error[V0101]: unknown signal `X9`"],
    );
    check(
        "\n  A  = RE(Zz) . A0",
        &["c.txt:2:11: error[V0101]: unknown signal `Zz`"],
    );
    check(
        "B = C0 & A0",
        &["c.txt:1:8: error[V0101]: unexpected character `&`"],
    );
    check(
        "B = (C0 . A0",
        &["c.txt:1:13: error[V0101]: expected `)`, found end of expression"],
    );
    check(
        "B = C0 . # comment hides the rest: A0",
        &["c.txt:1:10: error[V0101]: expected a name, `/` or `(`, found end of expression"],
    );
    check(
        "# header\n   C0 . A0",
        &["c.txt:2:4: error[V0108]: expected `ID = expression`, found `C0 . A0`"],
    );
    check(
        "C-1 = C0 . A0",
        &["c.txt:1:1: error[V0108]: `C-1` is not a valid constraint id"],
    );
    check(
        " = C0 . A0",
        &["c.txt:1:2: error[V0108]: `` is not a valid constraint id"],
    );
    check(
        "X = C0 . A0\n\nX = C1 . A1",
        &["c.txt:3:1: error[V0102]: constraint `X` is already defined on line 1"],
    );
    check(
        "D = C0 . C1 + A0",
        &[
            "c.txt:1:1: error[V0103]: constraint `D` has a term with no output at t (C0 . C1): the filter cannot enforce it",
        ],
    );
    check(
        "D = RE(C0) . A0*",
        &[
            "c.txt:1:1: error[V0103]: constraint `D` has a term with no output at t (C0 . /C0* . A0*): the filter cannot enforce it",
        ],
    );
    check(
        "E = A0 + /A0",
        &[
            "c.txt:1:1: error[V0105]: constraint `E` is always true: the filter would stop the plant at once",
        ],
    );
    check(
        "  E = 1",
        &[
            "c.txt:1:3: error[V0105]: constraint `E` is always true: the filter would stop the plant at once",
        ],
    );
    check(
        "F = C0 . /C0 . A0",
        &["c.txt:1:1: warning[V0104]: constraint `F` can never be true: it never acts"],
    );
    check(
        "F = 0",
        &["c.txt:1:1: warning[V0104]: constraint `F` can never be true: it never acts"],
    );
}

#[test]
fn one_bad_line_does_not_hide_the_others() {
    let (set, problems) = load("A = C0 . A0\nB = C0 &\nC = X . A1\nD = C1 . A1\nA = C2 . A2");
    assert_eq!(
        problems,
        [
            "c.txt:2:8: error[V0101]: unexpected character `&`",
            "c.txt:3:5: error[V0101]: unknown signal `X`",
            "c.txt:5:1: error[V0102]: constraint `A` is already defined on line 1",
        ]
    );
    let ids: Vec<_> = set.constraints.iter().map(|c| c.id.as_str()).collect();
    assert_eq!(ids, ["A", "D"]);
}

#[test]
fn warnings_keep_the_constraint() {
    let (set, _) = load("F = C0 . /C0 . A0");
    assert_eq!(set.constraints.len(), 1);
    assert!(set.constraints[0].dnf.is_empty());
}

fn property_6(text: &str) -> Vec<String> {
    let b = station();
    let (set, problems) = ConstraintSet::parse(text, Path::new("c.txt"), &b.symbols);
    assert!(problems.is_empty(), "{}", crate::diag::render(&problems));
    let found = set
        .check_property_6(&b.symbols, &ConstraintSet::default())
        .0;
    assert!(
        found
            .iter()
            .all(|p| p.severity == Severity::Error && p.code == "V0106")
    );
    found.iter().map(ToString::to_string).collect()
}

#[test]
fn property_6_violation_names_both_constraints_the_output_and_a_witness() {
    assert_eq!(
        property_6("X = C7 . A4\nY = C7 . /A4"),
        [
            "c.txt:2:1: error[V0106]: property (6) violated for output A4: X forces it to 0 and Y forces it to 1 when C7=1"
        ]
    );
    assert_eq!(
        property_6("X = A4\nY = /A4 . C0"),
        [
            "c.txt:2:1: error[V0106]: property (6) violated for output A4: X forces it to 0 and Y forces it to 1 when C0=1"
        ]
    );
    assert_eq!(
        property_6("X = A4\nY = /A4"),
        [
            "c.txt:2:1: error[V0106]: property (6) violated for output A4: X forces it to 0 and Y forces it to 1 when any state"
        ]
    );
    // Contexts that exclude each other, and combined constraints, are not checked.
    assert!(property_6("X = C7 . A4\nY = /C7 . /A4\nZ = C7 . /A4 . A0").is_empty());
}

#[test]
fn property_6_holds_for_edges_the_papers_sufficient_condition() {
    // CSs14 (rising edge) and CSs15 (falling edge): /A4* and A4* exclude each other.
    assert!(property_6("CSs14 = /C4 . RE(A4)\nCSs15 = /C5 . FE(A4)").is_empty());
    // Written without the edge, the same pair conflicts.
    assert_eq!(
        property_6("CSs14 = /C4 . A4\nCSs15 = /C5 . FE(A4)"),
        [
            "c.txt:2:1: error[V0106]: property (6) violated for output A4: CSs14 forces it to 0 and CSs15 forces it to 1 when C4=0, C5=0, A4*=1"
        ]
    );
}

/// On the paper's own set the check is purely logical: it reports the pairs of A4
/// constraints whose contexts can be true together as formulas, although the plant
/// cannot reach them (the table at C4 while a box leaves at C7 or C8, …); the paper
/// validates those with the model checker. The edge pair CSs14/CSs15 is not among them.
#[test]
fn property_6_on_the_paper_set_reports_only_physically_unreachable_pairs() {
    let b = station();
    let found: Vec<String> = b
        .constraints
        .check_property_6(&b.symbols, &ConstraintSet::default())
        .0
        .iter()
        .map(|p| p.message.clone())
        .collect();
    let pairs = [
        ("CSs13", "CSs9", "C4=1, C6=0, C8=1"),
        ("CSs13", "CSs10", "C4=1, C6=0, C7=1"),
        ("CSs13", "CSs11", "C4=1, C6=0, P67=1"),
        ("CSs13", "CSs15", "C4=1, C5=0, C6=0, A4*=1"),
        ("CSs14", "CSs8", "C4=0, C5=1, C6=1, A4*=0"),
        ("CSs14", "CSs9", "C4=0, C8=1, A4*=0"),
        ("CSs14", "CSs10", "C4=0, C7=1, A4*=0"),
        ("CSs14", "CSs11", "C4=0, A4*=0, P67=1"),
    ];
    let want: Vec<String> = pairs
        .iter()
        .map(|(a, b, w)| {
            format!("property (6) violated for output A4: {a} forces it to 0 and {b} forces it to 1 when {w}")
        })
        .collect();
    assert_eq!(found, want);
    assert!(
        !found
            .iter()
            .any(|m| m.contains("CSs14 forces it to 0 and CSs15"))
    );
}

#[test]
fn load_reports_a_missing_file() {
    let b = station();
    let (set, problems) =
        ConstraintSet::load(Path::new("/nonexistent/constraints.txt"), &b.symbols);
    assert!(set.constraints.is_empty());
    assert_eq!(problems.len(), 1);
    assert_eq!(problems[0].code, "V0002");
    assert!(
        problems[0]
            .message
            .starts_with("cannot read /nonexistent/constraints.txt: ")
    );
}

/// With the station's invariants (`invariants.txt`: situations the plant cannot reach
/// under the filter), every one of those logical conflicts is discharged, each by the
/// invariant naming its situation, and no error remains.
#[test]
fn property_6_on_the_paper_set_holds_modulo_the_invariants() {
    let b = station();
    let (errors, discharged) = b.constraints.check_property_6(&b.symbols, &b.invariants);
    assert!(errors.is_empty(), "{}", crate::diag::render(&errors));
    let got: Vec<(String, String, String)> = discharged
        .iter()
        .map(|d| {
            (
                d.forces_zero.clone(),
                d.forces_one.clone(),
                d.invariant.clone(),
            )
        })
        .collect();
    let want = [
        ("CSs13", "CSs9", "INV3"),
        ("CSs13", "CSs10", "INV2"),
        ("CSs13", "CSs11", "INV4"),
        ("CSs13", "CSs15", "INV5"),
        ("CSs14", "CSs8", "INV6"),
        ("CSs14", "CSs9", "INV8"),
        ("CSs14", "CSs10", "INV7"),
        ("CSs14", "CSs11", "INV9"),
    ]
    .map(|(a, b, c)| (a.to_string(), b.to_string(), c.to_string()));
    assert_eq!(got, want);
    // An invariant that reads an output at t is refused.
    let (_, problems) =
        ConstraintSet::parse_invariants("I = C4 . A4", Path::new("i.txt"), &b.symbols);
    assert_eq!(problems[0].code, "V0109");
}
