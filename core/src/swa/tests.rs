use super::linear::parse;
use super::poly::{Poly, Q};
use super::synth;
use super::*;
use super::{from_tasks, regions};
use std::path::Path;

fn names(n: &[&str]) -> Vec<String> {
    n.iter().map(|s| (*s).to_string()).collect()
}

fn p(text: &str, vars: &[String]) -> Poly {
    parse(text, vars).unwrap_or_else(|e| panic!("{text}: {e:?}"))
}

fn q(n: i64) -> Q {
    Q::int(n.into())
}

#[test]
fn fig_2_4_succ_t() {
    let v = names(&["x1", "x2"]);
    let e1 = p("1 <= x1 <= 2 && 0 <= x2 <= 1", &v);
    let inv = p("x1 <= 5 && x2 <= 2", &v);
    let got = e1.elapse(&[q(1), q(1)], true).intersect(&inv);
    let want = p("0 <= x1 - x2 <= 2 && 1 <= x1 && 0 <= x2 <= 2", &v);
    assert!(
        got.same_set(&want),
        "{}",
        poly::Display {
            poly: &got.minimize(),
            names: &v
        }
    );
}

#[test]
fn fig_2_4_succ_d() {
    let v = names(&["x1", "x2", "x3"]);
    let e2 = p("0 <= x1 - x2 <= 3 && x1 >= 1", &v);
    let guard = p("1 <= x2 <= 2", &v);
    let got = e2.intersect(&guard).reset(&[2]);
    let want = p(
        "0 <= x1 - x2 <= 3 && x1 >= 1 && 1 <= x2 <= 2 && x3 == 0",
        &v,
    );
    assert!(got.same_set(&want));
}

#[test]
fn fig_2_4_pre_t_is_the_corrected_set() {
    let v = names(&["x1", "x2", "x3"]);
    let e3 = p("2 <= x1 <= 3 && 2 <= x2 <= 3 && 0 <= x3 <= 1", &v);
    let inv = p("x1 <= 6 && x2 <= 3 && x3 <= 1", &v);
    let clocks = p("x1 >= 0 && x2 >= 0 && x3 >= 0", &v);
    let got = e3
        .elapse(&[q(1), q(1), q(1)], false)
        .intersect(&inv)
        .intersect(&clocks);
    let printed = p(
        "0 <= x1 <= 3 && 0 <= x2 <= 3 && 0 <= x3 <= 1 && -1 <= x1 - x2 <= 1 && 1 <= x2 - x3 <= 3",
        &v,
    );
    let corrected = printed.intersect(&p("1 <= x1 - x3 <= 3", &v));
    assert!(
        got.same_set(&corrected),
        "{}",
        poly::Display {
            poly: &got.minimize(),
            names: &v
        }
    );
    assert!(!got.same_set(&printed));
    // The notes' counter-example: (0, 1, 0) is in the printed set, not in Pre_t.
    let cx = [q(0), q(1), q(0)];
    assert!(printed.contains(&cx) && !got.contains(&cx));
}

#[test]
fn strict_bounds_and_emptiness() {
    let v = names(&["x", "y"]);
    assert!(p("x < 1 && x > 1", &v).is_empty());
    assert!(p("x <= 1 && x >= 1", &v).contains(&[q(1), q(7)]));
    assert!(p("x - y < 0 && y - x < 0", &v).is_empty());
    assert!(
        p("x - y <= 0 && y - x <= 0 && x < 2 && y > 1", &v).contains(&[Q::new(3, 2), Q::new(3, 2)])
    );
    // Found by FM only: x < y, y < z, z < x.
    let w = names(&["x", "y", "z"]);
    assert!(p("x - y < 0 && y - z < 0 && z - x < 0", &w).is_empty());
    assert!(!p("x - y <= 0 && y - z <= 0 && z - x <= 0", &w).is_empty());
    assert!(Poly::universe(2).contains(&[Q::zero(), Q::zero()]));
}

pub(crate) const WORKSHOP: &str = r#"(
    tasks: [
        (id: "conveyor", start: "d", end: "b", interrupt: Some("s_c"), resume: Some("r_c"),
         alpha_ms: 3000, beta_ms: 4000, gamma_ms: 5000),
        (id: "robot", start: "e", end: "R", interrupt: Some("s_R"), resume: Some("r_R"),
         alpha_ms: 2000, beta_ms: 3000, gamma_ms: 4000),
    ],
    windows: [(id: "d_window", open: ["e"], close: ["d"], open_at_start: true, max_ms: 2000)],
)"#;

pub(crate) fn task_swa(text: &str) -> Swa {
    let set = crate::tasks::TaskSet::from_ron(text, Path::new("tasks.ron")).expect("tasks");
    from_tasks::automata(&set)
        .compile(Path::new("tasks.ron"), "")
        .expect("swa")
}

fn workshop_thesis() -> Swa {
    let path = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../layouts/workshop/workshop.swa.ron"
    ));
    SwaFile::load(path).expect("workshop.swa.ron")
}

/// Table 4.2's intersection column (1 u.t. = 1000 ms), per product location. In l5 and
/// l6 the table omits `x4 − y4 < 2`, which the notes show is not implied (x4 = 2,
/// y4 = 0 cannot finish); it is added.
const TABLE_4_2: [(&str, &str); 12] = [
    (
        "A1:wait_d A2:idle",
        "x2 == 0 && x4 == 0 && y2 == 0 && y4 == 0 && 0 <= x1 <= 2000",
    ),
    (
        "A1:run A2:idle",
        "x4 == 0 && y4 == 0 && 0 <= x2 - y2 < 2000 && x2 < 5000 && y2 <= 4000 && 0 <= x1 <= 2000",
    ),
    (
        "A1:int A2:idle",
        "x4 == 0 && y4 == 0 && 0 <= x2 - y2 < 2000 && x2 < 5000 && y2 <= 4000 && 0 <= x1 <= 2000",
    ),
    (
        "A1:at_b A2:idle",
        "x2 == 0 && x4 == 0 && y2 == 0 && y4 == 0 && 0 <= x1 <= 2000",
    ),
    (
        "A1:wait_d A2:run",
        "x1 - x4 == 0 && x2 == 0 && y2 == 0 && x1 <= 2000 && 0 <= y4 && 0 <= x4 - y4 < 2000",
    ),
    (
        "A1:wait_d A2:int",
        "x1 - x4 == 0 && x2 == 0 && y2 == 0 && x1 <= 2000 && 0 <= y4 && 0 <= x4 - y4 < 2000",
    ),
    (
        "A1:run A2:run",
        "x1 + x2 - x4 == 0 && 0 <= x2 - y2 < 2000 && 0 <= x4 - y4 < 2000 && 0 <= x4 - x2 <= 2000 && y2 >= 0 && x4 < 4000 && 0 <= y4 <= 3000",
    ),
    (
        "A1:int A2:run",
        "x1 + x2 - x4 == 0 && 0 <= x2 - y2 < 2000 && 0 <= x4 - y4 < 2000 && 0 <= x4 - x2 <= 2000 && y2 >= 0 && x4 < 4000 && 0 <= y4 <= 3000",
    ),
    (
        "A1:run A2:int",
        "x1 + x2 - x4 == 0 && 0 <= x2 - y2 < 2000 && 0 <= x4 - y4 < 2000 && 0 <= x4 - x2 <= 2000 && y2 >= 0 && x4 < 4000 && 0 <= y4 <= 3000",
    ),
    (
        "A1:int A2:int",
        "x1 + x2 - x4 == 0 && 0 <= x2 - y2 < 2000 && 0 <= x4 - y4 < 2000 && 0 <= x4 - x2 <= 2000 && y2 >= 0 && x4 < 4000 && 0 <= y4 <= 3000",
    ),
    (
        "A1:at_b A2:run",
        "x2 == 0 && y2 == 0 && 0 <= x1 && 0 <= x4 - y4 < 2000 && 3000 <= x4 - x1 && x4 < 4000 && y4 <= 3000",
    ),
    (
        "A1:at_b A2:int",
        "x2 == 0 && y2 == 0 && 0 <= x1 && 0 <= x4 - y4 < 2000 && 3000 <= x4 - x1 && x4 < 4000 && y4 <= 3000",
    ),
];

#[test]
fn workshop_product_has_the_thesis_12_locations() {
    let swa = workshop_thesis();
    assert_eq!(swa.locations.len(), 12);
    assert_eq!(swa.clocks, ["A1.x1", "A1.x2", "A1.y2", "A2.x4", "A2.y4"]);
}

#[test]
fn workshop_synthesis_is_table_4_2() {
    let swa = workshop_thesis();
    let s = synthesize(&swa, Limits::default()).expect("synthesis");
    let short: Vec<String> = swa
        .clocks
        .iter()
        .map(|c| c.split('.').nth(1).unwrap_or(c).to_string())
        .collect();
    for (name, table) in TABLE_4_2 {
        let l = swa
            .location(name)
            .unwrap_or_else(|| panic!("no location {name}"));
        // Stopwatches are non-negative (Def. 2.3.1); the table leaves it implicit.
        let nonneg = short
            .iter()
            .map(|c| format!("{c} >= 0"))
            .collect::<Vec<_>>()
            .join(" && ");
        let want = p(table, &short).intersect(&p(&nonneg, &short));
        let got: Vec<String> = s.regions[l]
            .iter()
            .map(|r| {
                poly::Display {
                    poly: r,
                    names: &short,
                }
                .to_string()
            })
            .collect();
        assert!(
            synth::same_union(&s.regions[l], std::slice::from_ref(&want)),
            "{name}: synthesised {got:?}, table {table}"
        );
    }
}

#[test]
fn regions_file_round_trips_and_a_stale_one_is_refused() {
    let set = crate::tasks::TaskSet::from_ron(WORKSHOP, Path::new("tasks.ron")).unwrap();
    let file = from_tasks::automata(&set);
    let swa = task_swa(WORKSHOP);
    let s = synthesize(&swa, Limits::default()).unwrap();
    let regions = regions::RegionsFile::new("tasks.ron", &file, &swa, &s);
    let dir = std::env::temp_dir().join(format!("vigie-swa-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("regions.ron");
    std::fs::write(&path, regions.to_ron()).unwrap();
    let loaded = regions::RegionsFile::load(&path, &file, &swa).expect("loads");
    assert_eq!(loaded.len(), swa.locations.len());
    for (l, r) in loaded.iter().enumerate() {
        assert!(
            synth::same_union(&r.all, &s.regions[l]),
            "{}",
            swa.locations[l].name
        );
    }
    // The conveyor's γ changed since: the regions describe another system.
    let changed = WORKSHOP.replace("gamma_ms: 5000", "gamma_ms: 6000");
    let set2 = crate::tasks::TaskSet::from_ron(&changed, Path::new("tasks.ron")).unwrap();
    let file2 = from_tasks::automata(&set2);
    let swa2 = task_swa(&changed);
    let err = regions::RegionsFile::load(&path, &file2, &swa2).unwrap_err();
    assert_eq!(err.code, "V1503");
    assert!(err.message.contains("vigie synthesize"), "{}", err.message);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn single_task_regions_are_the_closed_form() {
    // Any (α, β, γ): E* of an interruptible task in run and int is
    // 0 <= x − y < γ − α ∧ x < γ ∧ y <= β (the thesis's closed form).
    for (a, b, g) in [
        (10, 10, 12),
        (3, 4, 5),
        (2, 3, 4),
        (5, 6, 8),
        (1, 1, 2),
        (0, 2, 3),
    ] {
        let text = format!(
            r#"(tasks: [(id: "t", start: "d", end: "b", interrupt: Some("s"), resume: Some("r"),
                alpha_ms: {a}, beta_ms: {b}, gamma_ms: {g})])"#
        );
        let swa = task_swa(&text);
        let s = synthesize(&swa, Limits::default()).unwrap();
        let want = p(
            &format!("0 <= t.x - t.y < {} && t.x < {g} && 0 <= t.y <= {b}", g - a),
            &swa.clocks,
        );
        for name in ["t:run", "t:int"] {
            let l = swa.location(name).unwrap();
            assert!(
                synth::same_union(&s.regions[l], std::slice::from_ref(&want)),
                "({a}, {b}, {g}) {name}"
            );
        }
        assert!(s.approximate.is_empty());
    }
}

proptest::proptest! {
    /// The simplex and Fourier–Motzkin agree on emptiness, strict bounds included.
    #[test]
    fn simplex_and_fourier_motzkin_agree(
        rows in proptest::collection::vec(
            (proptest::collection::vec(-2i128..=2, 3), -4i128..=4, proptest::bool::ANY), 1..8)
    ) {
        let mut p = Poly::universe(3);
        for (a, b, strict) in rows {
            p.add(poly::HalfSpace { a: a.into_iter().map(Q::int).collect(), b: Q::int(b), strict });
        }
        proptest::prop_assert_eq!(p.is_empty(), p.is_empty_fm());
    }

    /// Time elapse then its inverse contains the start, and every successor point is
    /// reached from a start point (checked on the vertices' grid).
    #[test]
    fn elapse_contains_its_start(lo in 0i128..5, w in 0i128..4, rates in proptest::collection::vec(0i128..=1, 2)) {
        let v = names(&["x", "y"]);
        let e = p(&format!("{lo} <= x <= {} && {lo} <= y <= {}", lo + w, lo + w + 1), &v);
        let r: Vec<Q> = rates.into_iter().map(Q::int).collect();
        let fwd = e.elapse(&r, true);
        proptest::prop_assert!(e.is_subset(&fwd));
        proptest::prop_assert!(e.is_subset(&fwd.elapse(&r, false)));
    }
}

#[test]
fn independent_tasks_are_synthesised_apart_and_give_the_conjunction_of_closed_forms() {
    let set = crate::tasks::synthetic(3);
    let swa = from_tasks::automata(&set)
        .compile(Path::new("<synthetic>"), "")
        .unwrap();
    assert_eq!(synth::independent_groups(&swa).len(), 3);
    assert_eq!(synth::independent_groups(&task_swa(WORKSHOP)).len(), 1);
    let s = synthesize(&swa, Limits::default()).unwrap();
    assert_eq!(s.regions.len(), 27);
    assert_eq!(s.approximate.len(), 27, "the decomposition is reported");
    // Every task in progress: 0 <= x - y < 2 s, x < 5 s, y <= 4 s; every idle task at 0.
    for (l, loc) in swa.locations.iter().enumerate() {
        let mut want = Vec::new();
        for (i, part) in loc.parts.iter().enumerate() {
            let t = format!("t{i}");
            want.push(if *part == 0 {
                format!("{t}.x == 0 && {t}.y == 0")
            } else {
                format!("0 <= {t}.x - {t}.y < 2000 && {t}.x < 5000 && 0 <= {t}.y <= 4000")
            });
        }
        let want = p(&want.join(" && "), &swa.clocks);
        assert!(
            synth::same_union(&s.regions[l], std::slice::from_ref(&want)),
            "{}",
            loc.name
        );
    }
}
