use super::*;
use crate::machine::actions::parse_actions;
use crate::symbols::Space;
use proptest::prelude::*;
use std::path::Path;

const DRILLING: &str = include_str!("../drilling.ron");

/// A monitor over a name table, with the frame a PLC would give it.
struct Bench {
    symbols: Symbols,
    frame: Frame,
    monitor: ActionMonitor,
}

impl Bench {
    fn new(actions: &[ElementaryAction], inputs: &[&str], outputs: &[&str]) -> Self {
        let mut symbols = Symbols::new();
        for name in inputs {
            symbols.declare(name, Space::Input).unwrap();
        }
        for name in outputs {
            symbols.declare(name, Space::Output).unwrap();
        }
        let monitor = ActionMonitor::new(actions, &symbols).unwrap();
        Self {
            frame: Frame::new(symbols.sizes()),
            symbols,
            monitor,
        }
    }

    fn set(&mut self, name: &str, value: bool) {
        let (space, index) = self.symbols.lookup(name).unwrap();
        self.frame.now_mut(space).set(index as usize, value);
    }

    /// One cycle at `t`, then the frame's values at t become those at t-1.
    fn step(&mut self, t: u64) -> Vec<ActionEvent> {
        let events = self.monitor.cycle(Millis(t), &self.frame);
        self.frame.shift();
        events
    }

    /// Cycles every `cycle_ms` from 0 to `end` (inclusive), applying at each cycle the
    /// changes of `script` (time, signal, value) whose time has come.
    fn run(&mut self, script: &[(u64, &str, bool)], cycle_ms: u64, end: u64) -> Vec<ActionEvent> {
        let mut script = script.to_vec();
        script.sort_by_key(|&(t, _, _)| t);
        let mut next = 0;
        let mut events = Vec::new();
        for t in (0..=end).step_by(cycle_ms as usize) {
            while next < script.len() && script[next].0 <= t {
                self.set(script[next].1, script[next].2);
                next += 1;
            }
            events.extend(self.step(t));
        }
        events
    }
}

/// Row C1's synthetic N2 = (b1, DPV, b2, T = 5000 ms, ΔT = 500 ms).
fn n2() -> ElementaryAction {
    ElementaryAction {
        id: "N2".into(),
        component: "head".into(),
        initial: "b1".into(),
        command: "DPV".into(),
        final_state: "b2".into(),
        t_ms: 5000,
        dt_ms: 500,
    }
}

fn n2_bench() -> Bench {
    Bench::new(&[n2()], &["b1", "b2"], &["DPV"])
}

/// The head rests at b1; the PLC orders DPV at t0 = 1000 ms.
const START: [(u64, &str, bool); 2] = [(0, "b1", true), (1000, "DPV", true)];

fn with(extra: &[(u64, &'static str, bool)]) -> Vec<(u64, &'static str, bool)> {
    START.iter().chain(extra).copied().collect()
}

/// `(time, action, kind, elapsed)` of each event.
fn brief(events: &[ActionEvent]) -> Vec<(u64, &str, ActionEventKind, Option<u64>)> {
    events
        .iter()
        .map(|e| (e.time.0, e.action.as_str(), e.kind, e.elapsed_ms))
        .collect()
}

#[test]
fn c1_fault_free_completion_at_5_s() {
    let mut b = n2_bench();
    // The head leaves b1, reaches b2 5.0 s after t0; the PLC drops DPV in that cycle.
    let script = with(&[
        (1100, "b1", false),
        (6000, "b2", true),
        (6000, "DPV", false),
    ]);
    let events = b.run(&script, 100, 12_000);
    assert_eq!(
        brief(&events),
        [(6000, "N2", ActionEventKind::Completed, Some(5000))]
    );
    assert!(!events[0].is_fault());
    assert_eq!(events[0].started, Some(Millis(1000)));
    assert!(b.monitor.running().is_empty());
}

#[test]
fn c1_blocked_actuator_is_late_at_the_first_cycle_after_t_max() {
    let mut b = n2_bench();
    // Blocked: the head never leaves b1, DPV stays ordered. Reported once.
    let events = b.run(&with(&[]), 100, 30_000);
    assert_eq!(
        brief(&events),
        [(6500, "N2", ActionEventKind::Late, Some(5500))]
    );
    assert!(events[0].is_fault());
    // Freed later, the head reaches b2: the late arrival is not reported again as an
    // unexpected final state (the action stays overdue until then).
    let script = with(&[(20_000, "b1", false), (24_000, "b2", true)]);
    let mut b = n2_bench();
    let events = b.run(&script, 100, 30_000);
    assert_eq!(
        brief(&events),
        [(6500, "N2", ActionEventKind::Late, Some(5500))]
    );
    assert!(b.monitor.running().is_empty());
    // Cycles not aligned on T_MAX: the first cycle at or after 900 + 5500 = 6400.
    let mut b = n2_bench();
    let script = [(0, "b1", true), (900, "DPV", true)];
    let events = b.run(&script, 300, 12_000);
    assert_eq!(
        brief(&events),
        [(6600, "N2", ActionEventKind::Late, Some(5700))]
    );
    assert!(!events[0].reached, "a blocked head never reaches b2");
}

#[test]
fn c1_overspeed_is_early_at_4_s() {
    let mut b = n2_bench();
    // Speed ×1.25: τ = 4.0 s < T_MIN = 4.5 s.
    let script = with(&[
        (1100, "b1", false),
        (5000, "b2", true),
        (5000, "DPV", false),
    ]);
    let events = b.run(&script, 100, 12_000);
    assert_eq!(
        brief(&events),
        [(5000, "N2", ActionEventKind::Early, Some(4000))]
    );
}

#[test]
fn c1_b2_stuck_at_1_before_t0_is_unexpected_then_early_at_t0() {
    let mut b = n2_bench();
    let events = b.run(&with(&[(500, "b2", true)]), 100, 12_000);
    assert_eq!(
        brief(&events),
        [
            (500, "N2", ActionEventKind::Unexpected, None),
            (1000, "N2", ActionEventKind::Early, Some(0)),
        ]
    );
    assert_eq!(events[0].started, None);
    assert_eq!(events[1].started, Some(Millis(1000)));
    assert!(events.iter().all(ActionEvent::is_fault));
}

#[test]
fn a_final_state_reached_after_t_max_is_late() {
    // With 300 ms cycles from t0 = 900, b2 at 6500 is seen at 6600 > T_MAX = 6400.
    let mut b = n2_bench();
    let script = [
        (0, "b1", true),
        (900, "DPV", true),
        (1000, "b1", false),
        (6500, "b2", true),
    ];
    let events = b.run(&script, 300, 9_000);
    assert_eq!(
        brief(&events),
        [(6600, "N2", ActionEventKind::Late, Some(5700))]
    );
    assert!(events[0].reached, "b2 is there, late");
}

#[test]
fn a_command_dropped_before_completion_abandons_the_action() {
    let mut b = n2_bench();
    // The PLC stops DPV at 3000 (before T_MAX): no fault, nothing running.
    let script = with(&[(1100, "b1", false), (3000, "DPV", false)]);
    let events = b.run(&script, 100, 8_000);
    assert!(events.is_empty(), "{events:?}");
    assert!(b.monitor.running().is_empty());
    // The head then drifts to b2 with no order: check (d).
    b.set("b2", true);
    assert_eq!(
        brief(&b.step(8_100)),
        [(8100, "N2", ActionEventKind::Unexpected, None)]
    );
}

#[test]
fn after_a_completion_the_final_state_is_not_reported_again() {
    let mut b = n2_bench();
    let script = with(&[
        (1100, "b1", false),
        (6000, "b2", true),
        (6000, "DPV", false),
        (21_000, "b2", false),
        (22_000, "b2", true),
    ]);
    let events = b.run(&script, 100, 25_000);
    assert_eq!(
        brief(&events),
        [
            (6000, "N2", ActionEventKind::Completed, Some(5000)),
            (22_000, "N2", ActionEventKind::Unexpected, None),
        ]
    );
}

#[test]
fn actions_of_different_components_run_concurrently_and_report_in_id_order() {
    let action = |id: &str, component: &str, i: &str, c: &str, f: &str| ElementaryAction {
        id: id.into(),
        component: component.into(),
        initial: i.into(),
        command: c.into(),
        final_state: f.into(),
        t_ms: 1000,
        dt_ms: 100,
    };
    let actions = [
        action("Z1", "clamp", "c0", "CL", "c1"),
        action("A1", "slide", "s0", "SL", "s1"),
    ];
    let mut b = Bench::new(&actions, &["c0", "c1", "s0", "s1"], &["CL", "SL"]);
    let script = [
        (0, "c0", true),
        (0, "s0", true),
        (200, "CL", true),
        (300, "SL", true),
        (1300, "c1", true),
        (1300, "s1", true),
    ];
    b.run(&script[..4], 100, 300);
    assert_eq!(
        b.monitor.running(),
        [
            ("A1".to_string(), Millis(300)),
            ("Z1".to_string(), Millis(200))
        ]
    );
    // Both final states rise at 1300: Z1 after 1100 ms, A1 after 1000 ms.
    for &(_, name, value) in &script[4..] {
        b.set(name, value);
    }
    let events = b.step(1300);
    assert_eq!(
        brief(&events),
        [
            (1300, "A1", ActionEventKind::Completed, Some(1000)),
            (1300, "Z1", ActionEventKind::Completed, Some(1100)),
        ]
    );
    assert_eq!(events[0].component, "slide");
}

#[test]
fn reset_forgets_the_running_actions_and_the_previous_states() {
    let mut b = n2_bench();
    b.run(&with(&[]), 100, 2_000);
    assert_eq!(b.monitor.running(), [("N2".to_string(), Millis(1000))]);
    b.monitor.reset();
    assert!(b.monitor.running().is_empty());
    // V still holds: after a reset it counts as rising, timed from this cycle.
    assert!(b.step(2_100).is_empty());
    assert_eq!(b.monitor.running(), [("N2".to_string(), Millis(2100))]);
}

#[test]
fn the_localisation_names_the_actions_signals() {
    let a = n2();
    let event = |kind, elapsed_ms: Option<u64>| ActionEvent {
        time: Millis(0),
        action: "N2".into(),
        component: "head".into(),
        kind,
        started: elapsed_ms.map(|_| Millis(0)),
        elapsed_ms,
        reached: kind != ActionEventKind::Late,
    };
    let early = event(ActionEventKind::Early, Some(4000)).localisation(&a);
    assert_eq!(
        early,
        "N2 (head): final state `b2` reached after 4000 ms, before T_MIN = 4500 ms: sensor b2 stuck at its active value, or actuator overspeed under `DPV`"
    );
    let late = event(ActionEventKind::Late, Some(5500)).localisation(&a);
    assert_eq!(
        late,
        "N2 (head): final state `b2` not reached after 5500 ms (T_MAX = 5500 ms) under `DPV`: sensor b2 stuck inactive, actuator blocked or slow, or the link PLC->actuator of `DPV` broken"
    );
    // Seen late at a cycle past T_MAX, still absent: not reached (a blocked head).
    let missing = event(ActionEventKind::Late, Some(5590)).localisation(&a);
    assert!(missing.contains("not reached after 5590 ms"), "{missing}");
    let mut after = event(ActionEventKind::Late, Some(5700));
    after.reached = true;
    let after = after.localisation(&a);
    assert!(
        after.contains("reached only after 5700 ms, past T_MAX"),
        "{after}"
    );
    let unexpected = event(ActionEventKind::Unexpected, None).localisation(&a);
    assert_eq!(
        unexpected,
        "N2 (head): final state `b2` appeared with no validated action: sensor b2 stuck active, or actuator moving without order `DPV` (output link stuck at 1)"
    );
    let pseudo = ElementaryAction {
        final_state: "/d . e".into(),
        ..n2()
    };
    let text = event(ActionEventKind::Unexpected, None).localisation(&pseudo);
    assert!(text.contains("sensors d, e stuck active"), "{text}");
}

#[test]
fn bad_actions_are_refused_with_their_problems() {
    let mut symbols = Symbols::new();
    symbols.declare("b1", Space::Input).unwrap();
    symbols.declare("DPV", Space::Output).unwrap();
    let problems = ActionMonitor::new(&[n2(), n2()], &symbols).unwrap_err();
    let codes: Vec<&str> = problems.iter().map(|p| p.code).collect();
    assert_eq!(
        codes,
        [
            crate::diag::codes::MACHINE_ACTION_DUPLICATE.id,
            crate::diag::codes::MACHINE_ACTION_UNKNOWN_SIGNAL.id,
            crate::diag::codes::MACHINE_ACTION_UNKNOWN_SIGNAL.id,
        ]
    );
}

// ---------------------------------------------------------------------------------
// The drilling example (§2.12)
// ---------------------------------------------------------------------------------

fn drilling_bench() -> Bench {
    let actions = parse_actions(DRILLING, Path::new("drilling.ron")).unwrap();
    let mut b = Bench::new(
        &actions,
        &["h", "b1", "b2", "b3", "DY"],
        &["DGV", "DPV", "MGV"],
    );
    b.set("h", true);
    b
}

/// T of the segments of one drilling cycle, actions N1, N2, N3, N2, N4, N5, N3, N6.
const DRILL_T: [u64; 8] = [2000, 5000, 1500, 5000, 4000, 1500, 1500, 2000];
/// ΔT of the same segments.
const DRILL_DT: [u64; 8] = [200, 500, 150, 500, 400, 150, 150, 200];
/// The completions of one fault-free cycle (R1 splits both long moves).
const DRILL_SEQUENCE: [&str; 8] = ["N1", "N2", "N3", "N2", "N4", "N5", "N3", "N6"];

fn ceil_to(t: u64, cycle: u64) -> u64 {
    t.div_ceil(cycle) * cycle
}

/// One fault-free drilling cycle from `start` (a cycle time, head at rest at h): DY,
/// then DGV→b1, DPV→b2, MGV→b1, DPV→b3, MGV→h with the segment travel times `travel`
/// (real time, ms). The PLC switches its orders in the cycle it reads a stop's sensor;
/// a sensor passed on the way is on for one cycle. Returns the cycle that sees h.
fn drilling_cycle(
    start: u64,
    travel: &[u64; 8],
    cycle: u64,
    script: &mut Vec<(u64, &'static str, bool)>,
) -> u64 {
    let moves: [(&'static str, &[&'static str]); 5] = [
        ("DGV", &["b1"]),
        ("DPV", &["b2"]),
        ("MGV", &["b1"]),
        ("DPV", &["b2", "b3"]),
        ("MGV", &["b2", "b1", "h"]),
    ];
    script.extend([(start, "DY", true), (start + cycle, "DY", false)]);
    let (mut at, mut t, mut k) = ("h", start, 0);
    let mut previous: Option<&'static str> = None;
    for (order, stops) in moves {
        if let Some(p) = previous {
            script.push((t, p, false));
        }
        script.extend([(t, order, true), (t + 1, at, false)]);
        let mut real = t;
        for (j, &s) in stops.iter().enumerate() {
            real += travel[k];
            k += 1;
            script.push((real, s, true));
            if j + 1 < stops.len() {
                script.push((real + cycle, s, false));
            }
            at = s;
        }
        t = ceil_to(real, cycle);
        previous = Some(order);
    }
    script.push((t, "MGV", false));
    t
}

/// Runs `cycles` drilling cycles with the travel times `travel(k)` of cycle k.
fn run_drilling(
    cycle: u64,
    cycles: usize,
    travel: impl Fn(usize) -> [u64; 8],
) -> (Vec<ActionEvent>, u64) {
    let mut script = Vec::new();
    let mut t = 10 * cycle;
    for k in 0..cycles {
        t = drilling_cycle(t, &travel(k), cycle, &mut script) + 10 * cycle;
    }
    let mut b = drilling_bench();
    let events = b.run(&script, cycle, t);
    (events, t / cycle)
}

#[test]
fn the_fault_free_drilling_cycle_completes_n1_n2_n3_n2_n4_n5_n3_n6() {
    let (events, cycles) = run_drilling(100, 5, |_| DRILL_T);
    assert!(cycles >= 1000, "{cycles} cycles");
    assert!(events.iter().all(|e| !e.is_fault()), "{events:?}");
    let completed: Vec<&str> = events.iter().map(|e| e.action.as_str()).collect();
    let expected: Vec<&str> = DRILL_SEQUENCE.repeat(5);
    assert_eq!(completed, expected);
    // Each after exactly its T, the first cycle from t0 = 1000 ms.
    let first: Vec<_> = brief(&events[..3]);
    assert_eq!(
        first,
        [
            (3000, "N1", ActionEventKind::Completed, Some(2000)),
            (8000, "N2", ActionEventKind::Completed, Some(5000)),
            (9500, "N3", ActionEventKind::Completed, Some(1500)),
        ]
    );
}

#[test]
fn a_drilling_fault_is_localised_on_its_action() {
    // The feed is slow on the second descent to b2: N2 late at 9500 + 5500 = 15000.
    let mut travel = DRILL_T;
    travel[3] = 6000;
    let (events, _) = run_drilling(100, 1, |_| travel);
    let faults: Vec<_> = events.iter().filter(|e| e.is_fault()).collect();
    assert_eq!(faults.len(), 1, "{events:?}");
    assert_eq!(
        (faults[0].time.0, faults[0].action.as_str(), faults[0].kind),
        (15_000, "N2", ActionEventKind::Late)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Travel times within [T − ΔT + T_D, T + ΔT − T_D] never give a fault, whatever the
    /// cycle below ΔT_min = 150 ms.
    #[test]
    fn fault_free_timings_never_fault(
        cycle in 20u64..=140,
        fractions in proptest::collection::vec(0.0f64..=1.0, 16),
    ) {
        let travel = |k: usize| -> [u64; 8] {
            std::array::from_fn(|i| {
                let lo = DRILL_T[i] - DRILL_DT[i] + cycle;
                let hi = DRILL_T[i] + DRILL_DT[i] - cycle;
                lo + ((hi - lo) as f64 * fractions[k * 8 + i]) as u64
            })
        };
        let (events, _) = run_drilling(cycle, 2, travel);
        prop_assert!(events.iter().all(|e| !e.is_fault()), "{:?}", events);
        let completed: Vec<&str> = events.iter().map(|e| e.action.as_str()).collect();
        prop_assert_eq!(completed, DRILL_SEQUENCE.repeat(2));
    }

    /// A completion seen m cycles after validation is normal exactly when m·T_D lies in
    /// [T_MIN, T_MAX]; outside, it is always one fault (early before, late after).
    #[test]
    fn a_completion_outside_the_window_always_faults(
        cycle in 10u64..=200,
        dt in 1u64..=2000,
        extra in 1u64..=10_000,
        fraction in 0.0f64..=1.5,
    ) {
        let action = ElementaryAction { t_ms: dt + extra, dt_ms: dt, ..n2() };
        let (t_min, t_max) = (action.t_min_ms(), action.t_max_ms());
        let m = ((t_max as f64 * fraction) / cycle as f64).round() as u64;
        let seen = m * cycle;
        let t0 = cycle;
        let mut b = Bench::new(&[action], &["b1", "b2"], &["DPV"]);
        let script = [(0, "b1", true), (t0, "DPV", true), (t0 + seen, "b2", true)];
        let events = b.run(&script, cycle, t0 + seen.max(t_max) + 3 * cycle);
        let kinds: Vec<ActionEventKind> = events.iter().map(|e| e.kind).collect();
        let expected = if seen < t_min {
            ActionEventKind::Early
        } else if seen <= t_max {
            ActionEventKind::Completed
        } else {
            ActionEventKind::Late
        };
        prop_assert_eq!(kinds, vec![expected], "seen {} in [{}, {}]", seen, t_min, t_max);
    }
}
