use super::*;
use crate::bundle::PlantBundle;
use crate::symbols::{Symbols, Var};
use crate::test_support::{frame_with, set_var, station, var};
use proptest::prelude::*;
use std::path::Path;

fn station_filter() -> (PlantBundle, Filter) {
    let b = station();
    let f = Filter::new(&b.constraints, b.plant.outputs.len());
    (b, f)
}

/// The paper's station (no device monitoring) and its filter: the space the exhaustive
/// checks enumerate (the shipped station's `CSk*` add 17 variables, covered by
/// `fallback_of_the_shipped_station_matches_brute_force`).
fn paper_filter() -> (PlantBundle, Filter) {
    let b = crate::test_support::paper_bundle();
    let f = Filter::new(&b.constraints, b.plant.outputs.len());
    (b, f)
}

fn ids(filter: &Filter, v: &[usize]) -> Vec<String> {
    v.iter().map(|&i| filter.id(i).to_string()).collect()
}

/// The minimal violating cycle of each constraint, written out for the sorting station:
/// the variables at 1 (everything else 0) and every constraint that fires there.
/// `fires_on_its_minimal_cycle_only` derives the same frames from the DNFs.
const MINIMAL_CYCLES: [(&str, &[&str], &[&str]); 33] = [
    ("CSs1", &["2P", "A0"], &["CSs1"]),
    ("CSs2", &["C3", "A1"], &["CSs2"]),
    ("CSs3", &["C3", "C4", "C6", "A1"], &["CSs3", "CSc2"]),
    ("CSs4", &["C3", "P36", "A1"], &["CSs2", "CSs4"]),
    ("CSs5", &["A3"], &["CSs5"]),
    ("CSs6", &["C4", "C6", "A2"], &["CSs6"]),
    ("CSs7", &["A2"], &["CSs7"]),
    ("CSs8", &["C5", "C6"], &["CSs8"]),
    ("CSs9", &["C8"], &["CSs9"]),
    ("CSs10", &["C7"], &["CSs10"]),
    ("CSs11", &["P67"], &["CSs11"]),
    ("CSs12", &["C5", "C7", "A2"], &["CSs10", "CSs12"]),
    ("CSs13", &["C4", "A4"], &["CSs13"]),
    ("CSs14", &["A4"], &["CSs14"]),
    ("CSs15", &["A4*"], &["CSs15"]),
    ("CSc1", &["C0", "A0"], &["CSc1"]),
    ("CSc2", &["C3", "C4", "A1"], &["CSc2"]),
    ("CSk1", &["KM0", "A0_fb"], &["CSk1"]),
    ("CSk2", &["KM0", "A0*"], &["CSk2"]),
    ("CSk3", &["KM0", "A1_fb"], &["CSk3"]),
    ("CSk4", &["KM0", "A1*"], &["CSk4"]),
    ("CSk5", &["KM0", "A2_fb"], &["CSk5"]),
    ("CSk6", &["KM0", "A2*"], &["CSk6"]),
    ("CSk7", &["KM0", "A3_fb"], &["CSk7"]),
    ("CSk8", &["KM0", "A3*"], &["CSk8"]),
    ("CSk9", &["YV0", "A4_fb"], &["CSk9"]),
    ("CSk10", &["YV0", "A4*"], &["CSs15", "CSk10"]),
    ("CSk11", &["KM0", "A5_fb"], &["CSk11"]),
    ("CSk12", &["KM0", "A5*"], &["CSk12"]),
    ("CSk13", &["KM0", "A6_fb"], &["CSk13"]),
    ("CSk14", &["KM0", "A6*"], &["CSk14"]),
    ("CSk15", &["KM0", "KM0*"], &["CSk15"]),
    ("CSk16", &["YV0", "YV0*"], &["CSk16"]),
];

#[test]
fn each_constraint_fires_on_its_minimal_cycle_and_not_on_the_nearest_compliant_one() {
    let (b, filter) = station_filter();
    assert_eq!(filter.len(), MINIMAL_CYCLES.len());
    for (ci, c) in b.constraints.constraints.iter().enumerate() {
        let (id, ones, fired) = MINIMAL_CYCLES[ci];
        assert_eq!(c.id, id);
        for term in &c.dnf {
            // Only the term's literals are set to make it true.
            let mut frame = Frame::new(b.symbols.sizes());
            for l in term {
                set_var(&mut frame, l.var, l.positive);
            }
            if term == &c.dnf[0] {
                assert_eq!(
                    frame,
                    frame_with(&b.symbols, ones),
                    "{id}: documented cycle"
                );
                assert_eq!(ids(&filter, &filter.violations(&frame)), fired, "{id}");
            }
            assert!(filter.violations(&frame).contains(&ci), "{id} must fire");
            let true_term = filter.true_term(ci, &frame).unwrap();
            assert_eq!(&true_term, term, "{id}: the recorded term");
            // The nearest compliant cycle: flip one output literal at t.
            for l in term
                .iter()
                .filter(|l| l.var.space == Space::Output && !l.var.prev)
            {
                let mut compliant = frame.clone();
                set_var(&mut compliant, l.var, !l.positive);
                assert!(
                    !filter.violations(&compliant).contains(&ci),
                    "{id} must not fire once {} is flipped",
                    b.symbols.render_literal(*l)
                );
                assert_eq!(filter.true_term(ci, &compliant), None);
            }
        }
    }
    // The all-zero cycle fires nothing.
    let zero = Frame::new(b.symbols.sizes());
    assert!(filter.violations(&zero).is_empty());
}

/// Every output vector, as booleans, in lexicographic order (A0 first, 0 before 1).
fn all_vectors(n: usize) -> Vec<Vec<bool>> {
    (0..1u32 << n)
        .map(|v| (0..n).map(|k| v >> (n - 1 - k) & 1 == 1).collect())
        .collect()
}

/// The minimal-ones, lexicographically smallest compliant vector, by brute force.
fn brute_force(filter: &Filter, frame: &Frame, vectors: &[Vec<bool>]) -> Option<Vec<bool>> {
    let mut f = frame.clone();
    let mut best: Option<Vec<bool>> = None;
    for v in vectors {
        f.now[Space::Output as usize] = Bits::from_bools(v);
        if !filter.violations(&f).is_empty() {
            continue;
        }
        let ones = v.iter().filter(|x| **x).count();
        // Vectors come in lexicographic order: keep the first of each count.
        if best
            .as_ref()
            .is_none_or(|b| ones < b.iter().filter(|x| **x).count())
        {
            best = Some(v.clone());
        }
    }
    best
}

/// Checks the fallback against brute force in every assignment of `vars`; returns the
/// number of contexts and of specification errors.
fn exhaustive(b: &PlantBundle, filter: &Filter, vars: &[Var]) -> (usize, usize) {
    exhaustive_with(b, filter, vars, true)
}

/// [`exhaustive`]; with `reachable_only`, a specification error outside the situations
/// the station's invariants exclude fails the test.
fn exhaustive_with(
    b: &PlantBundle,
    filter: &Filter,
    vars: &[Var],
    reachable_only: bool,
) -> (usize, usize) {
    let n_out = b.plant.outputs.len();
    let vectors = all_vectors(n_out);
    let mut spec_errors = 0;
    let mut frame = Frame::new(b.symbols.sizes());
    for assignment in 0..1u64 << vars.len() {
        for (i, v) in vars.iter().enumerate() {
            set_var(&mut frame, *v, assignment >> i & 1 == 1);
        }
        let expected = brute_force(filter, &frame, &vectors);
        match (filter.fallback(&frame), expected) {
            (Ok(out), Some(best)) => {
                let mut f = frame.clone();
                f.now[Space::Output as usize] = out.clone();
                assert!(
                    filter.violations(&f).is_empty(),
                    "(a) fallback {out} violates in {assignment:b}"
                );
                assert_eq!(
                    out.count_ones(),
                    best.iter().filter(|x| **x).count(),
                    "(b) fallback {out} is not minimal in {assignment:b}"
                );
                assert_eq!(out.to_bools(), best, "(c) tie-break in {assignment:b}");
            }
            (Err(e), None) => {
                spec_errors += 1;
                assert!(e.constraints.len() >= 2, "{e}");
                // Only in situations the plant cannot reach under the filter.
                assert!(
                    !reachable_only
                        || b.invariants
                            .constraints
                            .iter()
                            .any(|inv| crate::expr::eval_dnf(&inv.dnf, &frame)),
                    "specification error in a reachable context {assignment:b}: {e}"
                );
            }
            (got, want) => panic!("context {assignment:b}: fallback {got:?}, brute force {want:?}"),
        }
    }
    (1 << vars.len(), spec_errors)
}

/// Number of assignments of `vars` that an invariant excludes.
fn excluded(b: &PlantBundle, vars: &[Var]) -> u64 {
    let mut frame = Frame::new(b.symbols.sizes());
    (0..1u64 << vars.len())
        .filter(|assignment| {
            for (i, v) in vars.iter().enumerate() {
                set_var(&mut frame, *v, assignment >> i & 1 == 1);
            }
            b.invariants
                .constraints
                .iter()
                .any(|inv| crate::expr::eval_dnf(&inv.dnf, &frame))
        })
        .count() as u64
}

/// The variables the constraints' context literals read, from the compiled terms.
fn support(filter: &Filter) -> Vec<Var> {
    let mut vars: Vec<Var> = filter
        .terms
        .iter()
        .flat_map(|t| t.context.iter().map(|l| l.var))
        .collect();
    vars.sort();
    vars.dedup();
    vars
}

#[test]
fn fallback_is_safe_minimal_and_lexicographic_on_the_support() {
    let (b, filter) = paper_filter();
    let vars = support(&filter);
    let names: Vec<String> = vars
        .iter()
        .map(|v| {
            b.symbols.render_literal(crate::symbols::Literal {
                var: *v,
                positive: true,
            })
        })
        .collect();
    assert_eq!(
        names,
        [
            "C0", "C3", "C4", "C5", "C6", "C7", "C8", "A4*", "P36", "P67", "2P", "sus_C3"
        ]
    );
    let (contexts, spec_errors) = exhaustive(&b, &filter, &vars);
    assert_eq!(contexts, 4096);
    // Exactly the contexts of the property (6) pairs, where A4 is forced both ways:
    // (C4./C6 + /C4./A4*) . (C5.C6 + C8 + C7 + P67 + /C5.A4*), true in 928 of the 2048
    // contexts of the 11 variables other than `sus_C3` (which no A4 term reads), every
    // one excluded by an invariant (checked in `exhaustive`).
    assert_eq!(spec_errors, 928 * 2);
    assert_eq!(
        check_fallback_exists(&filter, &b.symbols, &b.invariants),
        Ok(4096 - excluded(&b, &vars))
    );
}

#[test]
fn fallback_exhaustive_over_all_sensors_observers_and_a4_prev() {
    let (b, filter) = paper_filter();
    let mut vars: Vec<Var> = (0..b.plant.inputs.len())
        .map(|i| Var {
            space: Space::Input,
            index: i as u32,
            prev: false,
        })
        .chain((0..b.observers.len()).map(|i| Var {
            space: Space::Observer,
            index: i as u32,
            prev: false,
        }))
        .collect();
    vars.push(var(&b.symbols, "A4*"));
    assert_eq!(vars.len(), 15);
    let (contexts, spec_errors) = exhaustive(&b, &filter, &vars);
    assert_eq!((contexts, spec_errors), (1 << 15, 928 << 4));
}

#[track_caller]
fn check_fallback(ones: &[&str], expected_on: &[&str]) {
    let (b, filter) = station_filter();
    let frame = frame_with(&b.symbols, ones);
    let out = filter.fallback(&frame).unwrap();
    let on: Vec<&str> = out
        .ones()
        .map(|k| b.symbols.name(Space::Output, k as u32))
        .collect();
    assert_eq!(on, expected_on, "fallback with {ones:?} at 1");
}

#[test]
fn fallback_in_the_papers_situations() {
    // CSs10: box at C7, table in unloading position, A4 held before, A4 released now:
    // the fallback keeps A4 ON, everything else OFF (the paper's figure 13).
    check_fallback(&["C5", "C7", "A4*"], &["A4"]);
    // Same with the command still given: outputs are recomputed, not copied.
    check_fallback(&["C5", "C7", "A4*", "A4", "A0", "A2"], &["A4"]);
    // CSs15: between positions (neither C4 nor C5) with A4 ON before: hold it.
    check_fallback(&["A4*"], &["A4"]);
    // Between positions with A4 OFF before: A4 stays OFF (CSs14 forbids the rising edge).
    check_fallback(&[], &[]);
    // CSc1 alone needs nothing ON: A0 OFF suffices.
    check_fallback(&["C0", "A0", "A1"], &[]);
    // A box at C0 with two boxes in the zone: A0 OFF.
    check_fallback(&["C0", "2P"], &[]);
}

fn filter_for(text: &str) -> (PlantBundle, Filter) {
    let mut b = station();
    let (set, problems) = ConstraintSet::parse(text, Path::new("c.txt"), &b.symbols);
    assert!(problems.is_empty(), "{}", crate::diag::render(&problems));
    b.constraints = set;
    let f = Filter::new(&b.constraints, b.plant.outputs.len());
    (b, f)
}

#[test]
fn combined_nogoods_are_searched_with_the_tie_break() {
    // Either A0 or A1 must be ON: A0 stays OFF (first output), A1 ON.
    let (b, f) = filter_for("X = C0 . /A0 . /A1");
    let out = f.fallback(&frame_with(&b.symbols, &["C0"])).unwrap();
    assert_eq!(out.to_string(), "010000000");
    // A0 forced ON by a simple constraint, then A0 . /A2 forces A2 ON by propagation;
    // one of A3, A4, A5 must be ON: the last one, so that the earlier ones stay OFF.
    let (b, f) = filter_for("S = C0 . /A0\nX = C0 . A0 . /A2\nY = C1 . /A3 . /A4 . /A5");
    assert_eq!(
        f.fallback(&frame_with(&b.symbols, &["C0", "C1"]))
            .unwrap()
            .to_string(),
        "101001000"
    );
    assert_eq!(
        f.fallback(&frame_with(&b.symbols, &["C1"]))
            .unwrap()
            .to_string(),
        "000001000"
    );
}

#[test]
fn conflicting_constraints_are_a_specification_error() {
    // Z is active too but takes no part in the conflict: the error names the smallest
    // set of conflicting constraints, not every active one.
    let (b, f) = filter_for("X = C0 . /A0\nY = C0 . A0\nZ = C1 . A1");
    let err = f
        .fallback(&frame_with(&b.symbols, &["C0", "C1"]))
        .unwrap_err();
    assert_eq!(err.constraints, ["X", "Y"]);
    assert_eq!(
        err.to_string(),
        "no output vector satisfies every constraint: X, Y"
    );
    assert!(f.fallback(&frame_with(&b.symbols, &["C1"])).is_ok());
    // Combined nogoods only: every value of (A0, A1) is forbidden.
    let (b, f) =
        filter_for("W = C0 . /A0 . /A1\nX = C0 . A0 . A1\nY = C0 . A0 . /A1\nZ = C0 . /A0 . A1");
    let err = f.fallback(&frame_with(&b.symbols, &["C0"])).unwrap_err();
    assert_eq!(err.constraints, ["W", "X", "Y", "Z"]);
    // A unit nogood and combined ones that leave no room.
    let (b, f) = filter_for("U = C0 . /A2\nX = C0 . A2 . A3\nY = C0 . A2 . /A3");
    assert_eq!(
        f.fallback(&frame_with(&b.symbols, &["C0"]))
            .unwrap_err()
            .constraints,
        ["U", "X", "Y"]
    );
}

/// Random contexts (inputs at t, outputs at t-1) of a synthetic plant.
fn random_frame(symbols: &Symbols, seed: u64) -> Frame {
    let mut rng = crate::synthetic::SplitMix64::new(seed);
    let mut f = Frame::new(symbols.sizes());
    for s in [Space::Input, Space::Output] {
        for i in 0..symbols.len(s) {
            f.now[s as usize].set(i, rng.chance(1, 2));
            f.prev[s as usize].set(i, rng.chance(1, 2));
        }
    }
    f
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn fallback_on_synthetic_plants(plant_seed in 0u64..40, frame_seed: u64) {
        let syn = crate::synthetic::generate(40, 60, plant_seed);
        let n_out = syn.plant.outputs.len();
        let filter = Filter::new(&syn.constraints, n_out);
        let frame = random_frame(&syn.symbols, frame_seed);
        let result = filter.fallback(&frame);
        if let Ok(out) = &result {
            let mut f = frame.clone();
            f.now[Space::Output as usize] = out.clone();
            prop_assert!(filter.violations(&f).is_empty(), "fallback {} violates", out);
        }
        // Brute force over the outputs the active terms name, others at 0.
        let active: Vec<usize> = filter
            .terms
            .iter()
            .filter(|t| t.context.iter().all(|&l| frame.literal(l)))
            .flat_map(|t| t.outputs.iter().map(|&(k, _)| k as usize))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        if active.len() <= 12 {
            let mut f = frame.clone();
            let mut best: Option<Bits> = None;
            for v in all_vectors(active.len()) {
                let mut out = Bits::zeros(n_out);
                for (j, &k) in active.iter().enumerate() {
                    out.set(k, v[j]);
                }
                f.now[Space::Output as usize] = out.clone();
                if filter.violations(&f).is_empty()
                    && best.as_ref().is_none_or(|b| out.count_ones() < b.count_ones())
                {
                    best = Some(out);
                }
            }
            match (&result, best) {
                (Ok(out), Some(best)) => prop_assert_eq!(out, &best),
                (Err(_), None) => {}
                (got, want) => prop_assert!(false, "fallback {:?}, brute force {:?}", got, want),
            }
        }
    }
}

/// A random set of nogoods with mixed polarities (`C1 . /A0 . /A3` forces one of A0, A3
/// ON), so that the search meets ties and backtracking that the station never needs.
fn random_nogoods() -> impl Strategy<Value = String> {
    let literal = |prefix: &'static str, n: usize| {
        (0..n, any::<bool>())
            .prop_map(move |(i, pos)| format!("{}{prefix}{i}", if pos { "" } else { "/" }))
    };
    let constraint = (
        prop::collection::vec(literal("C", 3), 0..3),
        prop::collection::vec(literal("A", 7), 1..4),
    )
        .prop_map(|(ctx, outs)| ctx.into_iter().chain(outs).collect::<Vec<_>>().join(" . "));
    prop::collection::vec(constraint, 1..14).prop_map(|cs| {
        cs.iter()
            .enumerate()
            .map(|(i, c)| format!("R{i} = {c}\n"))
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn fallback_matches_brute_force_on_random_nogoods(text in random_nogoods()) {
        let mut b = station();
        let (set, problems) = ConstraintSet::parse(&text, Path::new("r.txt"), &b.symbols);
        prop_assert!(problems.iter().all(|p| !p.is_error()), "{}", crate::diag::render(&problems));
        b.constraints = set;
        let filter = Filter::new(&b.constraints, b.plant.outputs.len());
        let vars: Vec<Var> = (0..3).map(|i| Var { space: Space::Input, index: i, prev: false }).collect();
        exhaustive_with(&b, &filter, &vars, false);
    }
}

#[test]
fn the_fallback_prefers_each_outputs_safe_value() {
    use crate::plant::SafeValue::{Hold, One, Zero};
    // A1 is a monostable lift held up by its output (safe value One): a trip drives A0
    // OFF and keeps A1 ON, where priority to zero would let the lift drop.
    let (b, f) = filter_for("X = C0 . A0");
    let f = f.with_safe_values(vec![Zero, One, Zero, Zero, Zero, Zero, Zero]);
    let out = f.fallback(&frame_with(&b.symbols, &["C0"])).unwrap();
    assert_eq!(out.to_string(), "010000000");
    // A constraint that forbids the safe value wins over it.
    let (b, f) = filter_for("X = C0 . A1");
    let f = f.with_safe_values(vec![Zero, One, Zero, Zero, Zero, Zero, Zero]);
    assert_eq!(
        f.fallback(&frame_with(&b.symbols, &["C0"]))
            .unwrap()
            .to_string(),
        "000000000"
    );
    // Hold keeps the previous applied value, in either direction.
    let (b, f) = filter_for("X = C0 . A0");
    let f = f.with_safe_values(vec![Zero, Hold, Hold, Zero, Zero, Zero, Zero]);
    let mut frame = frame_with(&b.symbols, &["C0"]);
    frame.prev_mut(Space::Output).set(1, true);
    assert_eq!(f.fallback(&frame).unwrap().to_string(), "010000000");
    frame.prev_mut(Space::Output).set(1, false);
    frame.prev_mut(Space::Output).set(2, true);
    assert_eq!(f.fallback(&frame).unwrap().to_string(), "001000000");
    // Combined: one of A0, A1 must leave its safe value; with A0 safe at 1 and A1 safe
    // at 0, "A0 . A1 forbidden" keeps A0 (first output) and moves nothing else.
    let (b, f) = filter_for("X = C0 . A0 . /A1");
    let f = f.with_safe_values(vec![One, Zero, Zero, Zero, Zero, Zero, Zero]);
    assert_eq!(
        f.fallback(&frame_with(&b.symbols, &["C0"]))
            .unwrap()
            .to_string(),
        "110000000"
    );
    // On a conflict, every output takes its safe value.
    let (b, f) = filter_for("X = C0 . /A0\nY = C0 . A0");
    let f = f.with_safe_values(vec![Zero, One, Hold, Zero, Zero, Zero, Zero]);
    let mut frame = frame_with(&b.symbols, &["C0"]);
    frame.prev_mut(Space::Output).set(2, true);
    assert!(f.fallback(&frame).is_err());
    assert_eq!(f.safe_vector(&frame).to_string(), "011000000");
}

/// The priority to the safe values is the priority to zero read relative to them:
/// exhaustive over every safe-value assignment of three outputs and every context of
/// a small combined set, against brute force over all output vectors.
#[test]
fn safe_value_fallback_matches_brute_force() {
    use crate::plant::SafeValue::{self, Hold, One, Zero};
    let (b, f0) =
        filter_for("X = C0 . /A0 . /A1\nY = C1 . A1 . A2\nZ = C2 . /A2\nW = C0 . C1 . A0 . /A2");
    let kinds = [Zero, One, Hold];
    for a in kinds {
        for bb in kinds {
            for c in kinds {
                let safe: Vec<SafeValue> = vec![a, bb, c, Zero, Zero, Zero, Zero];
                let f = f0.clone().with_safe_values(safe.clone());
                for ctx in 0..(1u32 << 6) {
                    let mut frame = Frame::new(b.symbols.sizes());
                    for i in 0..3 {
                        frame.now_mut(Space::Input).set(i, ctx >> i & 1 == 1);
                        frame
                            .prev_mut(Space::Output)
                            .set(i, ctx >> (i + 3) & 1 == 1);
                    }
                    let pref = f.safe_vector(&frame);
                    // Brute force: the satisfying vector with the fewest outputs away
                    // from their safe value, then lexicographic (A0 first, safe first).
                    let mut best: Option<(u32, Vec<bool>, crate::bits::Bits)> = None;
                    for v in 0..(1u32 << 7) {
                        let mut fr = frame.clone();
                        for k in 0..7 {
                            fr.now_mut(Space::Output).set(k, v >> k & 1 == 1);
                        }
                        if !f.violations(&fr).is_empty() {
                            continue;
                        }
                        let away: Vec<bool> =
                            (0..7).map(|k| (v >> k & 1 == 1) != pref.get(k)).collect();
                        let n = away.iter().filter(|x| **x).count() as u32;
                        let key = (n, away.clone());
                        if best
                            .as_ref()
                            .is_none_or(|(bn, ba, _)| key < (*bn, ba.clone()))
                        {
                            best = Some((n, away, fr.now(Space::Output).clone()));
                        }
                    }
                    match (f.fallback(&frame), best) {
                        (Ok(out), Some((_, _, want))) => {
                            assert_eq!(out, want, "safe {safe:?} context {ctx:#b}");
                        }
                        (Err(_), None) => {}
                        (got, want) => {
                            panic!("safe {safe:?} context {ctx:#b}: {got:?} vs {want:?}")
                        }
                    }
                }
            }
        }
    }
}

/// The shipped station's fallback (with its safe values: KM0 and YV0 at One) against
/// brute force over its 512 output vectors, in random contexts of the constraints'
/// whole support (29 variables: too many to enumerate): the satisfying vector with the
/// fewest outputs away from their safe value, then lexicographic.
#[test]
fn fallback_of_the_shipped_station_matches_brute_force() {
    let b = station();
    let f = Filter::for_plant(&b.constraints, &b.plant);
    let vars = support(&f);
    assert_eq!(vars.len(), 29, "the support grew: widen the sample");
    let n = b.plant.outputs.len();
    let mut rng = crate::synthetic::SplitMix64::new(17);
    let (mut cut, mut conflicts) = (0, 0);
    for case in 0..4_000 {
        let mut frame = Frame::new(b.symbols.sizes());
        for v in &vars {
            set_var(&mut frame, *v, rng.next_u64() & 1 == 1);
        }
        let pref = f.safe_vector(&frame);
        let mut best: Option<(usize, Vec<bool>, Bits)> = None;
        for v in 0..1u32 << n {
            let mut fr = frame.clone();
            for k in 0..n {
                fr.now_mut(Space::Output).set(k, v >> k & 1 == 1);
            }
            if !f.violations(&fr).is_empty() {
                continue;
            }
            let away: Vec<bool> = (0..n).map(|k| (v >> k & 1 == 1) != pref.get(k)).collect();
            let key = (away.iter().filter(|x| **x).count(), away);
            if best
                .as_ref()
                .is_none_or(|(bn, ba, _)| (key.0, &key.1) < (*bn, ba))
            {
                best = Some((key.0, key.1, fr.now(Space::Output).clone()));
            }
        }
        match (f.fallback(&frame), best) {
            (Ok(out), Some((_, _, want))) => {
                assert_eq!(out, want, "case {case}");
                let km0 = b.symbols.lookup("KM0").expect("KM0").1 as usize;
                cut += usize::from(!out.get(km0));
            }
            (Err(_), None) => conflicts += 1,
            (got, want) => panic!("case {case}: {got:?} vs {want:?}"),
        }
    }
    // The sample reaches both sides: contexts where a welded or dead drive cuts KM0.
    assert!(cut > 1_000, "{cut}");
    assert!(conflicts < 4_000, "{conflicts}");
}
