//! The state graph and its analyses on nets whose answers are known by hand: a
//! deterministic cycle, a tie, the enabling memory's restart, and the write loss of
//! seed 002's producer (chapter 4: p = 0.005 from a tie, its MTFF in closed form).

use super::*;

fn net(text: &str) -> Net {
    let file: NetFile = crate::live::ron_options()
        .from_str(text)
        .unwrap_or_else(|e| panic!("{e}\n{text}"));
    file.check(Path::new("net.ron"), text)
        .unwrap_or_else(|p| panic!("{}", crate::diag::render(&p)))
}

fn q(n: i64, d: i64) -> Q {
    Q::new(BigInt::from(n), BigInt::from(d))
}

/// The producer of chapter 4 (PU-P): computes (80), writes, waits for the confirmation
/// (immediate), rests (420): a cycle of 500.
const PRODUCER: &str = r#"Net(
    places: ["calcul", "attend", "repos", "lost"],
    marking: [("calcul", 1)],
    transitions: [
        (name: "t1", pre: ["calcul"], post: ["attend"], delay: Dirac(80)),
        (name: "t2", pre: ["attend"], post: ["repos"], delay: Immediate),
        (name: "t3", pre: ["repos"], post: ["calcul"], delay: Dirac(420)),
        LOSS
    ],
)"#;

/// A deterministic cycle: three states, each holding the time share of its delay, and a
/// cycle of 500.
#[test]
fn a_deterministic_cycle_has_its_delays_as_time_shares() {
    let g = net(&PRODUCER.replace("LOSS", ""))
        .state_graph()
        .expect("graph");
    assert_eq!(g.states.len(), 3);
    assert!(g.sinks().is_empty());
    let c = g.terminal_components();
    assert_eq!(c.len(), 1, "home states: one terminal component");
    let (pi, cycle) = g.steady_state(&c[0]).expect("steady state");
    assert_eq!(cycle, q(500, 1));
    let share = |place: &str| -> Q {
        let p = g.states[0].marking.len();
        let k = ["calcul", "attend", "repos", "lost"][..p]
            .iter()
            .position(|x| x == &place)
            .expect("place");
        pi.iter()
            .filter(|(s, _)| g.states[*s].marking[k] > 0)
            .map(|(_, x)| x.clone())
            .sum()
    };
    assert_eq!(share("calcul"), q(80, 500));
    assert_eq!(share("attend"), q(0, 1), "a vanishing state holds no time");
    assert_eq!(share("repos"), q(420, 500));
}

/// Chapter 4's write loss: `t4` (0.01 δ(x−80) + 0.99 U[80, 81], here its atom at 81)
/// races `t1` (δ80): it fires first when it draws 80 and wins the tie, p = 1/100 · 1/2
/// = 0.005; the write, 0.995. Lost at 80 into a cycle with p each cycle, the mean time to
/// the loss is Σ_k (1−p)^k p (500k + 80) = 500 (1−p)/p + 80 = 99 580 exactly.
#[test]
fn the_write_loss_of_chapter_4_has_p_0_005_and_its_mttf_in_closed_form() {
    let text = PRODUCER.replace(
        "LOSS",
        r#"(name: "t4", pre: ["calcul"], post: ["lost"], delay: Discrete([(80, "0.01"), (81, "99/100")])),"#,
    );
    let n = net(&text);
    let g = n.state_graph().expect("graph");
    // From a computing state: the write (t1) with 199/200, the loss (t4) with 1/200.
    let from_calcul: Vec<(String, Q)> = g
        .arcs
        .iter()
        .filter(|a| g.initial.iter().any(|(s, _)| *s == a.from))
        .map(|a| {
            (
                n.transitions[a.transition].clone(),
                a.p.clone()
                    * &g.initial
                        .iter()
                        .find(|(s, _)| *s == a.from)
                        .expect("initial")
                        .1,
            )
        })
        .fold(Vec::new(), |mut acc: Vec<(String, Q)>, (t, p)| {
            match acc.iter_mut().find(|(x, _)| *x == t) {
                Some((_, x)) => *x += p,
                None => acc.push((t, p)),
            }
            acc
        });
    let p_of = |t: &str| {
        from_calcul
            .iter()
            .find(|(x, _)| x == t)
            .map(|(_, p)| p.clone())
            .unwrap_or_default()
    };
    assert_eq!(p_of("t1"), q(199, 200));
    assert_eq!(p_of("t4"), q(1, 200));
    let lost = g.marked(3);
    assert!(!lost.is_empty());
    assert_eq!(g.sinks(), lost, "the loss is absorbing here");
    assert_eq!(g.mttf(&lost), Some(q(99_580, 1)));
}

/// The abstract view on the computing states of the producer with its write loss: from
/// computing to computing again, 199/200 in 500; to the loss, 1/200 in 80. Without the
/// loss, the view on its computing state is the cycle: 1 in 500.
#[test]
fn the_abstract_view_on_the_computing_states() {
    let text = PRODUCER.replace(
        "LOSS",
        r#"(name: "t4", pre: ["calcul"], post: ["lost"], delay: Discrete([(80, "0.01"), (81, "99/100")])),"#,
    );
    let g = net(&text).state_graph().expect("graph");
    let mut observed = g.marked(0);
    observed.extend(g.marked(3));
    observed.sort_unstable();
    let view = g.abstract_view(&observed).expect("view");
    let lost = g.marked(3)[0];
    // From the initial state where t4 drew 80 (p = 1/100): the tie, 1/2 and 1/2.
    let (drew_80, _) = g
        .initial
        .iter()
        .find(|(_, p)| *p == q(1, 100))
        .expect("the early draw");
    let from: Vec<(usize, Q, Q)> = view
        .iter()
        .filter(|(o, _, _, _)| o == drew_80)
        .map(|(_, to, f, t)| (*to, f.clone(), t.clone()))
        .collect();
    let to_lost = from
        .iter()
        .find(|(to, _, _)| *to == lost)
        .expect("to the loss");
    assert_eq!((to_lost.1.clone(), to_lost.2.clone()), (q(1, 2), q(80, 1)));
    let again: Q = from
        .iter()
        .filter(|(to, _, _)| *to != lost)
        .map(|(_, f, _)| f.clone())
        .sum();
    assert_eq!(again, q(1, 2));
    assert!(
        from.iter()
            .filter(|(to, _, _)| *to != lost)
            .all(|(_, _, t)| *t == q(500, 1))
    );
    // Every observable state leaves with probability 1 in the view, but the loss.
    for &o in observed.iter().filter(|&&o| o != lost) {
        let f: Q = view
            .iter()
            .filter(|(x, ..)| *x == o)
            .map(|(_, _, f, _)| f.clone())
            .sum();
        assert_eq!(f, Q::one(), "from {o}");
    }
    let cycle = net(&PRODUCER.replace("LOSS", ""))
        .state_graph()
        .expect("graph");
    let view = cycle.abstract_view(&cycle.marked(0)).expect("view");
    assert_eq!(view, [(0, 0, Q::one(), q(500, 1))]);
}

/// Two transitions of equal delay from one place tie: each fires with 1/2.
#[test]
fn a_tie_is_shared_equally() {
    let g = net(
        r#"Net(places: ["p", "q", "r"], marking: [("p", 1)], transitions: [
            (name: "a", pre: ["p"], post: ["q"], delay: Dirac(10)),
            (name: "b", pre: ["p"], post: ["r"], delay: Dirac(10)),
            (name: "c", pre: ["p"], post: ["r"], delay: Dirac(11)),
        ])"#,
    )
    .state_graph()
    .expect("graph");
    let ps: Vec<Q> = g.arcs.iter().map(|a| a.p.clone()).collect();
    assert_eq!(ps, [q(1, 2), q(1, 2)]);
    assert!(g.arcs.iter().all(|a| a.theta == 10));
}

/// Enabling memory: a loop that takes and gives back the place of a timed transition
/// every 60 restarts its timer of 100, which never fires; every 200, it fires at 100.
#[test]
fn a_read_loop_restarts_the_timer_of_the_place_it_empties() {
    let text = |every: u64| {
        format!(
            r#"Net(places: ["p", "done", "tick"], marking: [("p", 1), ("tick", 1)], transitions: [
                (name: "t", pre: ["p"], post: ["done"], delay: Dirac(100)),
                (name: "loop", pre: ["p", "tick"], post: ["p", "tick"], delay: Dirac({every})),
            ])"#
        )
    };
    let g = net(&text(60)).state_graph().expect("graph");
    assert!(g.marked(1).is_empty(), "never done: {:?}", g.states);
    let g = net(&text(200)).state_graph().expect("graph");
    let done = g.marked(1);
    assert!(!done.is_empty());
    assert_eq!(g.mttf(&done), Some(q(100, 1)));
}

#[test]
fn a_net_with_unknown_places_or_probabilities_not_summing_to_one_is_refused() {
    let text = r#"Net(places: ["p"], marking: [("p", 1)], transitions: [
        (name: "t", pre: ["p"], post: ["x"], delay: Discrete([(1, "1/3"), (2, "1/3")])),
    ])"#;
    let file: NetFile = crate::live::ron_options().from_str(text).expect("parses");
    let err = file.check(Path::new("net.ron"), text).expect_err("refused");
    assert_eq!(err.len(), 2, "{err:?}");
    assert!(err.iter().all(|p| p.code == codes::STPN_INVALID.id));
    assert!(err.iter().any(|p| p.message.contains("`x`")));
    assert!(err.iter().any(|p| p.message.contains("sum to 2/3")));
    assert_eq!(err[0].location.as_ref().map(|l| l.line), Some(2));
}

mod property {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Whatever the delays and the loss probability, the arcs leaving each state that
        /// is not a sink carry a probability of 1, the initial distribution too, and the
        /// mean time to the loss is `Σ` over the cycles, computed exactly.
        #[test]
        fn every_state_leaves_with_probability_one(
            d1 in 1u64..200,
            d3 in 0u64..600,
            early in 1u64..200,
            k in 1i64..100,
        ) {
            let loss = format!(
                r#"(name: "t4", pre: ["calcul"], post: ["lost"], delay: Discrete([({early}, "{k}/100"), ({}, "{}/100")])),"#,
                d1 + 1,
                100 - k
            );
            let text = PRODUCER
                .replace("Dirac(80)", &format!("Dirac({d1})"))
                .replace("Dirac(420)", &format!("Dirac({d3})"))
                .replace("LOSS", &loss);
            let g = net(&text).state_graph().expect("graph");
            let total: Q = g.initial.iter().map(|(_, p)| p.clone()).sum();
            prop_assert_eq!(total, Q::one());
            let sinks = g.sinks();
            for s in 0..g.states.len() {
                let out: Q = g.arcs.iter().filter(|a| a.from == s).map(|a| a.p.clone()).sum();
                prop_assert_eq!(out.is_zero(), sinks.contains(&s));
                prop_assert!(out.is_zero() || out.is_one());
            }
            // The loss happens in a cycle when t4 draws its early atom and beats (or ties)
            // t1: p = k/100 (· 1/2 on a tie); it comes `early` into the cycle.
            let p = match early.cmp(&d1) {
                std::cmp::Ordering::Less => q(k, 100),
                std::cmp::Ordering::Equal => q(k, 200),
                std::cmp::Ordering::Greater => Q::zero(),
            };
            let lost = g.marked(3);
            if p.is_zero() {
                prop_assert!(lost.is_empty());
            } else {
                let cycle = Q::from_integer((d1 + d3).into());
                let want = cycle * (Q::one() - &p) / &p + Q::from_integer(early.into());
                prop_assert_eq!(g.mttf(&lost), Some(want));
            }
        }
    }
}
