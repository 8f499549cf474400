use super::*;
use crate::diag::codes;
use proptest::prelude::*;
use std::path::PathBuf;

const DRILLING: &str = include_str!("../drilling.ron");

fn file() -> PathBuf {
    PathBuf::from("actions.ron")
}

/// The drilling example's name table: inputs h, b1, b2, b3, DY; outputs DGV, DPV, MGV.
fn drilling_symbols() -> Symbols {
    let mut s = Symbols::new();
    for name in ["h", "b1", "b2", "b3", "DY"] {
        s.declare(name, Space::Input).unwrap();
    }
    for name in ["DGV", "DPV", "MGV"] {
        s.declare(name, Space::Output).unwrap();
    }
    s
}

fn action(id: &str, i: &str, c: &str, f: &str, t_ms: u64, dt_ms: u64) -> ElementaryAction {
    ElementaryAction {
        id: id.into(),
        component: "c".into(),
        initial: i.into(),
        command: c.into(),
        final_state: f.into(),
        t_ms,
        dt_ms,
    }
}

fn triple(a: &ElementaryAction) -> (&str, &str, &str, &str) {
    (&a.id, &a.initial, &a.command, &a.final_state)
}

/// `file:line:col code` of each problem, for exact comparisons.
fn located(problems: &[Problem]) -> Vec<String> {
    problems
        .iter()
        .map(|p| match &p.location {
            Some(l) => format!("{l} {}", p.code),
            None => p.code.to_string(),
        })
        .collect()
}

#[test]
fn the_drilling_file_reproduces_fig_ii6() {
    let actions = parse_actions(DRILLING, &file()).unwrap();
    let table: Vec<_> = actions.iter().map(triple).collect();
    assert_eq!(
        table,
        [
            ("N1", "h", "DGV", "b1"),
            ("N2", "b1", "DPV", "b2"),
            ("N3", "b2", "MGV", "b1"),
            ("N4", "b2", "DPV", "b3"),
            ("N5", "b3", "MGV", "b2"),
            ("N6", "b1", "MGV", "h"),
        ]
    );
    assert!(actions.iter().all(|a| a.component == "head"));
    assert_eq!((actions[1].t_min_ms(), actions[1].t_max_ms()), (4500, 5500));
    let problems = check_actions(&actions, &drilling_symbols(), Some((&file(), DRILLING)));
    assert!(problems.is_empty(), "{}", crate::diag::render(&problems));
    assert!(!actions.iter().any(ElementaryAction::is_pseudo_controlled));
}

#[test]
fn load_actions_reads_the_file_and_reports_a_missing_one() {
    let dir = std::env::temp_dir().join(format!("vigie-actions-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("actions.ron");
    std::fs::write(&path, DRILLING).unwrap();
    assert_eq!(load_actions(&path).unwrap().len(), 6);
    std::fs::remove_dir_all(&dir).unwrap();
    let missing = load_actions(&path).unwrap_err();
    assert_eq!(missing[0].code, codes::FILE_UNREADABLE.id);
}

#[test]
fn ron_errors_are_located() {
    let text = "Actions(actions: [\n  (id: \"N1\", component: \"c\", initial: \"h\", command: \"D\", final: \"b\", t_ms: 10, dt_ms: 1, colour: 3),\n])\n";
    let p = parse_actions(text, &file()).unwrap_err();
    assert_eq!(p.len(), 1);
    assert_eq!(p[0].code, codes::RON_INVALID.id);
    assert_eq!(p[0].location.as_ref().map(|l| l.line), Some(2));
}

#[test]
fn ids_duplicates_and_timing_are_located_at_their_values() {
    let text = "Actions(actions: [
  (id: \"N1\", component: \"c\", initial: \"h\", command: \"D\", final: \"b\", t_ms: 100, dt_ms: 100),
  (id: \"N1\", component: \"c\", initial: \"b\", command: \"E\", final: \"h\", t_ms: 100, dt_ms: 0),
  (id: \"N-3\", component: \"c\", initial: \"b\", command: \"E\", final: \"h\", t_ms: 100, dt_ms: 10),
])
";
    let p = parse_actions(text, &file()).unwrap_err();
    assert_eq!(
        located(&p),
        [
            "actions.ron:2:88 V1103",
            "actions.ron:3:8 V1102",
            "actions.ron:3:88 V1103",
            "actions.ron:4:8 V1101",
        ]
    );
    assert!(
        p[0].message
            .contains("T = 100 ms must be greater than ΔT = 100 ms")
    );
    assert!(p[2].message.contains("ΔT = 0 ms"));
}

#[test]
fn expression_problems_point_at_the_name() {
    let text = "Actions(actions: [
  (id: \"N1\", component: \"c\", initial: \"h . x\", command: \"DGV . b1\", final: \"DPV\", t_ms: 100, dt_ms: 10),
  (id: \"N2\", component: \"c\", initial: \"h\", command: \"RE(DGV)\", final: \"b1 +\", t_ms: 100, dt_ms: 10),
])
";
    // Without names: syntax and kinds only.
    let p = parse_actions(text, &file()).unwrap_err();
    assert_eq!(
        located(&p),
        ["actions.ron:3:57 V1104", "actions.ron:3:76 V1104"]
    );
    // With names (the second action's faults fixed): one problem per name.
    let text = text.replace("RE(DGV)", "DGV").replace("b1 +", "b1");
    let actions: ActionFile = ron::from_str(&text).unwrap();
    let p = check_actions(
        &actions.actions,
        &drilling_symbols(),
        Some((&file(), &text)),
    );
    assert_eq!(
        located(&p),
        [
            "actions.ron:2:44 V1105",
            "actions.ron:2:64 V1106",
            "actions.ron:2:77 V1106",
        ]
    );
    assert_eq!(
        p[0].message,
        "action `N1`, initial state: unknown signal `x`"
    );
    assert!(
        p[1].message.contains("`b1` is an input"),
        "{}",
        p[1].message
    );
    assert!(
        p[2].message.contains("`DPV` is an output"),
        "{}",
        p[2].message
    );
    // In memory: the same problems, without locations.
    let p = check_actions(&actions.actions, &drilling_symbols(), None);
    assert_eq!(located(&p), ["V1105", "V1106", "V1106"]);
}

#[test]
fn initial_equal_to_final_is_refused_until_split() {
    let a = action("cam", "d", "R", "d", 3000, 300);
    let p = check_actions(&[a], &Symbols::new(), None);
    assert!(
        p.iter()
            .any(|p| p.code == codes::MACHINE_ACTION_NOT_ELEMENTARY.id)
    );
    let same = action("x", "a . b", "R", "b . a", 3000, 300);
    assert!(
        check_actions(&[same], &Symbols::new(), None)
            .iter()
            .any(|p| p.code == codes::MACHINE_ACTION_NOT_ELEMENTARY.id)
    );
}

fn raw(id: &str, i: Option<&str>, c: Option<&str>, f: Option<&str>) -> RawAction {
    RawAction {
        id: id.into(),
        component: "m".into(),
        initial: i.map(Into::into),
        command: c.map(Into::into),
        final_state: f.map(Into::into),
        t_ms: 3000,
        dt_ms: 300,
        ..RawAction::default()
    }
}

#[test]
fn the_cam_is_split_by_r2_into_two_pseudo_controlled_actions() {
    // §2.13: (d, R, d) → N^I = (d, R, /d, T_I, ΔT_I) and N^II = (/d, R, d, T_II, ΔT_II).
    let cam = RawAction {
        first_part: Some((200, 120)),
        ..raw("cam", Some("d"), Some("R"), Some("d"))
    };
    let (actions, problems) = decompose(std::slice::from_ref(&cam));
    assert!(problems.is_empty(), "{}", crate::diag::render(&problems));
    let table: Vec<_> = actions
        .iter()
        .map(|a| (triple(a), a.t_ms, a.dt_ms))
        .collect();
    assert_eq!(
        table,
        [
            (("cam_I", "d", "R", "/d"), 200, 120),
            (("cam_II", "/d", "R", "d"), 2800, 300),
        ]
    );
    assert!(actions.iter().all(ElementaryAction::is_pseudo_controlled));
    // Without the first part's timing, R2 cannot apply.
    let (actions, problems) = decompose(&[RawAction {
        first_part: None,
        ..cam
    }]);
    assert!(actions.is_empty());
    assert_eq!(located(&problems), ["V1107"]);
}

#[test]
fn the_monostable_gets_its_implicit_command() {
    // Fig. II.8: N1 = (C1, D, C2), N2 = (C2, ∅, C1) → N2 = (C2, /D, C1).
    let (actions, problems) = decompose(&[
        raw("N1", Some("C1"), Some("D"), Some("C2")),
        raw("N2", Some("C2"), None, Some("C1")),
    ]);
    assert!(problems.is_empty(), "{}", crate::diag::render(&problems));
    let table: Vec<_> = actions.iter().map(triple).collect();
    assert_eq!(table, [("N1", "C1", "D", "C2"), ("N2", "C2", "/D", "C1")]);
    // A compound command is negated in parentheses.
    let (actions, _) = decompose(&[
        raw("N1", Some("C1"), Some("D . E"), Some("C2")),
        raw("N2", Some("C2"), None, Some("C1")),
    ]);
    assert_eq!(actions[1].command, "/(D . E)");
    // No earlier command on the component: an error, the action is dropped.
    let (actions, problems) = decompose(&[raw("N2", Some("C2"), None, Some("C1"))]);
    assert!(actions.is_empty());
    assert_eq!(located(&problems), ["V1107"]);
}

#[test]
fn undefined_states_become_pseudo_controlled() {
    // Case a: E^I := ¬E^f; case b: E^f := ¬E^I.
    let (actions, problems) = decompose(&[
        raw("Na", None, Some("R"), Some("d")),
        raw("Nb", Some("e . g"), Some("S"), None),
        raw("Nx", None, Some("T"), None),
    ]);
    let table: Vec<_> = actions.iter().map(triple).collect();
    assert_eq!(
        table,
        [("Na", "/d", "R", "d"), ("Nb", "e . g", "S", "/(e . g)")]
    );
    assert!(actions.iter().all(ElementaryAction::is_pseudo_controlled));
    assert_eq!(located(&problems), ["V1107"]);
    assert!(problems[0].message.contains("`Nx`"));
}

#[test]
fn r1_splits_the_descent_at_every_controlled_state_it_passes() {
    // Drilling: b1 –DPV→ b3 passes b2, so it stops at b2 (N2) and goes on (N4); the
    // ascent b3 –MGV→ h passes b2 and b1 (N5, N3, N6). Phase 2 keeps N2 and N3 once.
    let way = |id: &str, state: &str, t_ms: u64, dt_ms: u64| Waypoint {
        id: id.into(),
        state: state.into(),
        t_ms,
        dt_ms,
    };
    let raws = [
        RawAction {
            t_ms: 2000,
            dt_ms: 200,
            ..raw("N1", Some("h"), Some("DGV"), Some("b1"))
        },
        RawAction {
            t_ms: 5000,
            dt_ms: 500,
            ..raw("N2", Some("b1"), Some("DPV"), Some("b2"))
        },
        RawAction {
            t_ms: 1500,
            dt_ms: 150,
            ..raw("N3", Some("b2"), Some("MGV"), Some("b1"))
        },
        RawAction {
            via: vec![way("N2", "b2", 5000, 500)],
            t_ms: 4000,
            dt_ms: 400,
            ..raw("N4", Some("b1"), Some("DPV"), Some("b3"))
        },
        RawAction {
            via: vec![way("N5", "b2", 1500, 150), way("N3", "b1", 1500, 150)],
            t_ms: 2000,
            dt_ms: 200,
            ..raw("N6", Some("b3"), Some("MGV"), Some("h"))
        },
    ];
    let (actions, problems) = decompose(&raws);
    assert!(problems.is_empty(), "{}", crate::diag::render(&problems));
    let table: Vec<_> = actions.iter().map(triple).collect();
    assert_eq!(
        table,
        [
            ("N1", "h", "DGV", "b1"),
            ("N2", "b1", "DPV", "b2"),
            ("N3", "b2", "MGV", "b1"),
            ("N4", "b2", "DPV", "b3"),
            ("N5", "b3", "MGV", "b2"),
            ("N6", "b1", "MGV", "h"),
        ]
    );
    let mut expected = parse_actions(DRILLING, &file()).unwrap();
    expected.iter_mut().for_each(|a| a.component = "m".into());
    assert_eq!(actions, expected);
    // Found again with other times: an error.
    let mut clash = raws.to_vec();
    clash[3].via[0].t_ms = 4000;
    let (_, problems) = decompose(&clash);
    assert_eq!(located(&problems), ["V1102"]);
}

#[test]
fn phase_3_merges_actions_differing_only_by_their_final_state_with_a_warning() {
    let (actions, problems) = decompose(&[
        RawAction {
            t_ms: 1000,
            dt_ms: 100,
            ..raw("N7", Some("p0"), Some("T"), Some("p1"))
        },
        RawAction {
            t_ms: 2000,
            dt_ms: 300,
            ..raw("N8", Some("p0"), Some("T"), Some("p1 . q"))
        },
    ]);
    assert_eq!(actions.len(), 1);
    let merged = &actions[0];
    assert_eq!(triple(merged), ("N7", "p0", "T", "p1 + (p1 . q)"));
    // The window covers both: [900, 2300].
    assert_eq!((merged.t_min_ms(), merged.t_max_ms()), (900, 2300));
    assert_eq!(problems.len(), 1);
    assert_eq!(problems[0].code, codes::MACHINE_ACTIONS_MERGED.id);
    assert!(!problems[0].is_error());
    assert!(problems[0].message.contains("safety is reduced"));
    assert!(problems[0].message.contains("`N7`, `N8`"));
}

fn deltas(dts: &[u64], ts: &[u64]) -> Vec<ElementaryAction> {
    dts.iter()
        .zip(ts)
        .enumerate()
        .map(|(k, (&dt, &t))| {
            action(
                &format!("N{}", k + 1),
                &format!("s{k}"),
                "R",
                &format!("s{}", k + 1),
                t,
                dt,
            )
        })
        .collect()
}

#[test]
fn c5_the_cycle_must_be_below_the_smallest_tolerance() {
    // Row C5: ΔT = {500, 300, 800} ms.
    let actions = deltas(&[500, 300, 800], &[5000, 2000, 4000]);
    assert!(timing_check(&actions, 200).is_empty());
    let issues = timing_check(&actions, 350);
    assert_eq!(issues.len(), 1, "{issues:?}");
    assert_eq!(issues[0].action, "N2");
    assert_eq!(
        issues[0].kind,
        TimingIssueKind::CycleNotBelowTolerance { regime: Regime::B }
    );
    assert!(
        issues[0].message.contains("ΔT = 300 ms"),
        "{}",
        issues[0].message
    );
    assert_eq!(
        issues[0].to_problem().code,
        codes::MACHINE_CYCLE_TOO_LONG.id
    );
}

#[test]
fn c5_short_pseudo_controlled_actions_need_ii4() {
    // Row C5: T = 200, ΔT = 120 (the cam's N^I): T − ΔT = 80.
    let short = action("cam_I", "d", "R", "/d", 200, 120);
    assert!(short.is_pseudo_controlled());
    assert!(timing_check(std::slice::from_ref(&short), 50).is_empty());
    let issues = timing_check(std::slice::from_ref(&short), 100);
    assert_eq!(issues.len(), 1, "{issues:?}");
    assert_eq!(
        issues[0].kind,
        TimingIssueKind::TooShort {
            pseudo_controlled: true
        }
    );
    assert!(issues[0].message.contains("(II.4)"));
    // T_D < ΔT still holds: regime c.
    assert_eq!(regime(&short, 100), Regime::C);
}

#[test]
fn regimes_follow_iii_3_2() {
    let a = action("N", "x", "R", "y", 1000, 200);
    assert_eq!(regime(&a, 199), Regime::C);
    assert_eq!(regime(&a, 200), Regime::B);
    assert_eq!(regime(&a, 799), Regime::B);
    assert_eq!(regime(&a, 800), Regime::A);
    assert_eq!(regime(&a, 1199), Regime::A);
    assert_eq!(regime(&a, 1200), Regime::Blind);
    let kinds: Vec<_> = timing_check(&[a], 900)
        .into_iter()
        .map(|i| i.kind)
        .collect();
    assert_eq!(
        kinds,
        [
            TimingIssueKind::CycleNotBelowTolerance { regime: Regime::A },
            TimingIssueKind::TooShort {
                pseudo_controlled: false
            },
        ]
    );
}

/// §2.15: τ (s) and α = 3.
const TAU: [f64; 10] = [2.0, 2.2, 1.9, 2.1, 2.3, 1.8, 2.0, 2.2, 2.1, 1.9];

#[test]
fn batch_learning_matches_section_2_15() {
    let w = learn_batch(&TAU, 3.0).unwrap();
    for (got, want) in [
        (w.t, 2.05),
        (w.sigma, 0.15),
        (w.dt, 0.45),
        (w.t_min(), 1.6),
        (w.t_max(), 2.5),
    ] {
        assert!((got - want).abs() < 1e-6, "{got} != {want}");
    }
    assert_eq!(learn_batch(&[], 3.0), None);
    assert_eq!(learn_batch(&[1.0, f64::NAN], 3.0), None);
    assert_eq!(learn_batch(&[1.0], -1.0), None);
}

#[test]
fn recursive_learning_matches_section_2_15_after_each_measure() {
    let expected = [
        (2, 2.100000, 0.100000),
        (3, 2.033333, 0.124722),
        (4, 2.050000, 0.111803),
        (5, 2.100000, 0.141421),
        (6, 2.050000, 0.170783),
        (7, 2.042857, 0.159079),
        (8, 2.062500, 0.157619),
        (9, 2.066667, 0.149071),
        (10, 2.050000, 0.150000),
    ];
    let mut e = WindowEstimator::new();
    assert_eq!(e.window(3.0), None);
    let mut got = Vec::new();
    for tau in TAU {
        assert!(e.push(tau));
        got.push((e.count(), e.mean(), e.sigma()));
    }
    assert_eq!((got[0].1, got[0].2), (2.0, 0.0));
    for ((n, mean, sigma), (j, m, s)) in got[1..].iter().zip(expected) {
        assert_eq!(*n, j);
        assert!((mean - m).abs() < 1e-6, "j={j}: mean {mean} != {m}");
        assert!((sigma - s).abs() < 1e-6, "j={j}: σ {sigma} != {s}");
    }
    assert!(!e.push(f64::INFINITY));
    assert_eq!(e.count(), 10);
    let w = e.window(3.0).unwrap();
    assert!((w.dt - 0.45).abs() < 1e-6);
}

#[test]
fn a_learned_window_sets_t_and_dt_in_ms() {
    let w = learn_batch(&TAU.map(|s| s * 1000.0), 3.0).unwrap();
    let a = action("N", "x", "R", "y", 1, 1).with_window(&w);
    assert_eq!((a.t_ms, a.dt_ms), (2050, 450));
}

proptest! {
    #[test]
    fn recursive_learning_equals_batch(taus in proptest::collection::vec(0.0f64..10_000.0, 1..60)) {
        let mut e = WindowEstimator::new();
        for &t in &taus {
            e.push(t);
        }
        let b = learn_batch(&taus, 2.0).unwrap();
        let r = e.window(2.0).unwrap();
        prop_assert!((b.t - r.t).abs() < 1e-6 * b.t.max(1.0));
        prop_assert!((b.sigma - r.sigma).abs() < 1e-3, "{} vs {}", b.sigma, r.sigma);
    }
}
