use super::interp::{self, Machine, Val};
use super::st;
use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::engine::{Commanded, Engine, FilterMode};
use crate::filter::Filter;
use crate::frame::Frame;
use crate::plant::Plant;
use crate::symbols::{Space, Var};
use crate::tasks::{FrameTasks, Monitor, TaskSet};
use crate::time::Millis;
use std::path::PathBuf;

fn station() -> (PlantBundle, TaskSet) {
    station_in(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station"))
}

fn station_in(dir: &std::path::Path) -> (PlantBundle, TaskSet) {
    let set = TaskSet::load(&dir.join("tasks.ron")).unwrap();
    let plant = Plant::load(&dir.join("plant.ron")).unwrap();
    let (bundle, problems) = PlantBundle::from_plant(dir, plant, &set.aux_names());
    // Property (6) findings (V0106) are static warnings about physically impossible
    // contexts of the paper's constraints; the fallback there is all-zero on both sides.
    assert!(
        problems.iter().all(|p| !p.is_error() || p.code == "V0106"),
        "{problems:#?}"
    );
    (bundle, set)
}

/// Deterministic xorshift generator for the traces.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn chance(&mut self, one_in: u64) -> bool {
        self.next().is_multiple_of(one_in)
    }
    /// Flips each bit with probability `1/one_in`.
    fn flip_some(&mut self, bits: &mut Bits, one_in: u64) {
        for k in 0..bits.len() {
            if self.chance(one_in) {
                bits.set(k, !bits.get(k));
            }
        }
    }
}

fn st_name(sym: &crate::symbols::Symbols, space: Space, k: usize, filter: bool) -> String {
    st::ident(
        sym,
        Var {
            space,
            index: k as u32,
            prev: false,
        },
        filter,
    )
}

/// One scan of the generated program at `now` with these inputs and commands.
fn scan_st(m: &mut Machine, bundle: &PlantBundle, now: u64, inputs: &Bits, cmd: &Bits) {
    let sym = &bundle.symbols;
    let rules = bundle.plausibility.export_rules();
    m.set("NOW_MS", Val::Int(now as i64)).unwrap();
    for k in 0..inputs.len() {
        m.set(&st::input_name(sym, &rules, k), Val::Bool(inputs.get(k)))
            .unwrap();
    }
    for k in 0..cmd.len() {
        m.set(&st_name(sym, Space::Output, k, true), Val::Bool(cmd.get(k)))
            .unwrap();
    }
    m.scan().unwrap();
}

fn b(m: &Machine, name: &str) -> bool {
    match m.get(name) {
        Ok(Val::Bool(v)) => v,
        other => panic!("{name}: {other:?}"),
    }
}

fn i(m: &Machine, name: &str) -> i64 {
    match m.get(name) {
        Ok(Val::Int(v)) => v,
        other => panic!("{name}: {other:?}"),
    }
}

#[test]
fn generated_st_parses_with_the_interpreter() {
    let (bundle, set) = station();
    let text = st::generate(&bundle, Some(&set)).unwrap();
    let unit = interp::parse(&text).unwrap();
    Machine::new(unit, "Vigie_Safety").unwrap();
    assert!(text.contains("FUNCTION_BLOCK FB_Tasks"));
    assert!(text.contains("T_turn_out_DX"));
    assert!(text.contains("X_turn_out_infeasible"));
}

/// The exported fallback equals the native fallback in every context (exhaustive over
/// the constraints' support, 12 variables on the paper's station: 11 and `sus_C3`, C3
/// being read as possibly on while it is suspect; the shipped station's device
/// monitoring is covered by the random traces of `st_conforms_to_the_native_engine`).
#[test]
fn fallback_is_exact_in_every_context() {
    let paper = crate::test_support::paper_station("export-paper");
    let (bundle, _) = station_in(&paper);
    let text = st::generate(&bundle, None).unwrap();
    let unit = interp::parse(&text).unwrap();
    let n_out = bundle.plant.outputs.len();
    let filter = Filter::new(&bundle.constraints, n_out);
    let mut support: Vec<Var> = bundle
        .constraints
        .constraints
        .iter()
        .flat_map(|c| c.dnf.iter().flatten())
        .filter(|l| l.var.space != Space::Output || l.var.prev)
        .map(|l| l.var)
        .collect();
    support.sort();
    support.dedup();
    assert_eq!(support.len(), 12);
    let mut m = Machine::new(unit, "FB_Filter").unwrap();
    m.set("LATCHED", Val::Bool(true)).unwrap();
    for ctx in 0..(1u32 << support.len()) {
        let mut frame = Frame::new(bundle.symbols.sizes());
        for (j, v) in support.iter().enumerate() {
            let on = ctx >> j & 1 == 1;
            let table = if v.prev {
                &mut frame.prev
            } else {
                &mut frame.now
            };
            table[v.space as usize].set(v.index as usize, on);
            m.set(&st::ident(&bundle.symbols, *v, true), Val::Bool(on))
                .unwrap();
        }
        m.scan().unwrap();
        let native = filter
            .fallback(&frame)
            .unwrap_or_else(|_| Bits::zeros(n_out));
        for k in 0..n_out {
            let q = st::ident(
                &bundle.symbols,
                Var {
                    space: Space::Output,
                    index: k as u32,
                    prev: false,
                },
                false,
            );
            assert_eq!(b(&m, &q), native.get(k), "context {ctx:#b}, output {q}");
        }
    }
}

/// Random input/command traces (seeded) through the native engine + task monitor and
/// through the interpreted ST: identical decisions cycle by cycle.
#[test]
// A table of cases read top to bottom; split, it would hide which case failed.
#[allow(clippy::too_many_lines)]
fn st_conforms_to_the_native_engine() {
    let (station_bundle, set) = station();
    let (mut trips, mut task_changes, mut faults) = (0, 0, 0);
    let mut held = 0;
    // With the station's plausibility rules (random traces break its physics all the
    // time), and without them (the traces then reach the task monitors' states).
    // Third pass: every rule with `hold_until_back` (an edge inside its window holds
    // the sensor until the reading comes back). Fourth pass: every rule's rise waits
    // 300 ms after an event (`rise_not_after`). Fifth pass: every rule's conditions
    // must have held 200 ms (rise) and 500 ms (fall) in all since the last edge
    // (`_total_ms`).
    for (pass, with_rules) in [(0, true), (1, false), (2, true), (3, true), (4, true)] {
        let mut bundle = station_bundle.clone();
        if !with_rules {
            bundle.plausibility = Default::default();
        }
        if pass >= 2 {
            let first = bundle.plant.inputs[0].id.clone();
            for s in &mut bundle.plant.inputs {
                if let Some(r) = &mut s.plausible {
                    if pass == 2 {
                        r.hold_until_back = true;
                    } else if pass == 4 {
                        r.rise_when_total_ms = 200;
                        r.fall_when_total_ms = 500;
                    } else {
                        r.rise_not_after = Some(crate::plant::AfterEvent {
                            event: format!("FE({first}) + RE({})", s.id),
                            ms: 300,
                        });
                    }
                }
            }
            bundle.plausibility =
                crate::plausibility::Plausibility::new(&bundle.plant, &bundle.symbols).unwrap();
        }
        let text = st::generate(&bundle, Some(&set)).unwrap();
        let unit = interp::parse(&text).unwrap();
        let sym = &bundle.symbols;
        let n_in = bundle.plant.inputs.len();
        let n_out = bundle.plant.outputs.len();
        let frame_tasks = FrameTasks::compile(&set, sym).unwrap();
        let name = |space, k: usize, filter| st_name(sym, space, k, filter);
        let mirrors = bundle.plant.mirrors();
        for seed in 1..=120u64 {
            let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
            let mut engine = Engine::new(&bundle, FilterMode::Enforce, 1);
            let mut monitor = Monitor::new(&set, Millis(0));
            let mut m = Machine::new(unit.clone(), "Vigie_Safety").unwrap();
            let mut inputs = Bits::zeros(n_in);
            let mut cmd = Bits::zeros(n_out);
            let mut now = 0u64;
            // Quiet traces trip later, so the pre-trip behaviour is covered too.
            let (p_in, p_out) = if seed % 2 == 0 { (6, 5) } else { (12, 25) };
            let mut last_states = vec![0i64; set.tasks.len()];
            for cycle in 0..400 {
                now += 1 + rng.next() % 400;
                rng.flip_some(&mut inputs, p_in);
                rng.flip_some(&mut cmd, p_out);
                // Mirror contacts follow the outputs applied last cycle, except for a
                // rare weld or death (a `CSk*` trip); random, they trip every cycle.
                for &(i, o) in &mirrors {
                    if !rng.next().is_multiple_of(200) {
                        inputs.set(i, engine.applied().get(o));
                    }
                }
                engine.cycle(Millis(now), &inputs, &mut Commanded(cmd.clone()));
                frame_tasks.step(&mut monitor, Millis(now), engine.frame());
                frame_tasks.publish(&monitor, engine.frame_mut());

                scan_st(&mut m, &bundle, now, &inputs, &cmd);

                let at = format!("seed {seed}, cycle {cycle}, t = {now} ms");
                for k in 0..n_out {
                    assert_eq!(
                        b(&m, &name(Space::Output, k, false)),
                        engine.applied().get(k),
                        "{at}: output {k}"
                    );
                }
                assert_eq!(b(&m, "TRIPPED"), engine.is_tripped(), "{at}: trip");
                for k in 0..sym.len(Space::Observer) {
                    assert_eq!(
                        b(&m, &name(Space::Observer, k, false)),
                        engine.frame().now(Space::Observer).get(k),
                        "{at}: observer {k}"
                    );
                }
                for (ti, t) in set.tasks.iter().enumerate() {
                    let code = i(&m, &format!("T_{}_STATE", st::mangle(&t.id)));
                    let native = monitor.tasks[ti].state.st_code();
                    assert_eq!(
                        code, native,
                        "{at}: task {} ({:?})",
                        t.id, monitor.tasks[ti]
                    );
                    if code != last_states[ti] {
                        task_changes += 1;
                        if code == 4 {
                            faults += 1;
                        }
                    }
                    last_states[ti] = code;
                }
                for k in 0..sym.len(Space::Aux) {
                    assert_eq!(
                        b(&m, &name(Space::Aux, k, false)),
                        engine.frame().now(Space::Aux).get(k),
                        "{at}: aux {k}"
                    );
                }
                // The values the plausibility stage accepted.
                for k in 0..n_in {
                    assert_eq!(
                        b(&m, &name(Space::Input, k, false)),
                        engine.frame().now(Space::Input).get(k),
                        "{at}: input {k} as accepted"
                    );
                }
            }
            trips += usize::from(engine.is_tripped());
            held += engine.plausibility.held_edges;
        }
    }
    assert!(held > 1000, "held edges {held}");
    // The traces exercise what they claim to.
    assert!(trips > 30, "trips {trips}");
    assert!(task_changes > 1000, "task changes {task_changes}");
    assert!(faults > 20, "faults {faults}");
}

/// Task outputs are literals of the notation (`turn_out:infeasible`), and the monitor
/// publishes them: a table rotation stopped (A4 released) long enough becomes infeasible.
#[test]
fn task_outputs_are_constraint_literals() {
    let (bundle, set) = station();
    let (cs, problems) = crate::constraints::ConstraintSet::parse(
        "CSt1 = turn_out:infeasible . A4\n",
        std::path::Path::new("extra.txt"),
        &bundle.symbols,
    );
    assert!(problems.is_empty(), "{problems:#?}");
    let ft = FrameTasks::compile(&set, &bundle.symbols).unwrap();
    let mut monitor = Monitor::new(&set, Millis(0));
    let mut frame = Frame::new(bundle.symbols.sizes());
    let c4 = bundle.plant.input("C4").unwrap();
    let a4 = bundle.plant.output("A4").unwrap();
    // Table at C4, rotation ordered at t = 0; it leaves C4 at 100 ms; A4 released at 1 s.
    let steps: [(u64, bool, bool); 4] = [
        (0, true, true),
        (100, false, true),
        (1000, false, false),
        (4700, false, false),
    ];
    let mut infeasible_at = None;
    for (t, c4v, a4v) in steps {
        frame.shift();
        frame.now_mut(Space::Input).set(c4, c4v);
        frame.now_mut(Space::Output).set(a4, a4v);
        ft.step(&mut monitor, Millis(t), &frame);
        ft.publish(&monitor, &mut frame);
        frame.now_mut(Space::Output).set(a4, true);
        if crate::expr::eval_dnf(&cs.constraints[0].dnf, &frame) && infeasible_at.is_none() {
            infeasible_at = Some(t);
        }
    }
    // Tolerance γ − α = 3.6 s of interruption from 1 s: alarm at 4.6 s, seen at 4.7 s.
    assert_eq!(infeasible_at, Some(4700));
    // (The first record is a T007 warning: RE(C4) at t = 0 ends turn_back, which never started.)
    let alarm = monitor
        .alarms
        .iter()
        .find(|a| a.severity == crate::tasks::Severity::Alarm)
        .unwrap();
    assert_eq!(
        (alarm.code, alarm.time, alarm.subject.as_str()),
        (crate::tasks::AlarmCode::T001, Millis(4600), "turn_out")
    );
    assert_eq!(alarm.earlier_by_ms, Some(1500));
}

/// A plant of 120 signals (support far past any enumeration), outputs with every kind
/// of safe value, combined constraints chaining outputs into components of several,
/// and conflicting constraints: the interpreted ST and the engine decide the same
/// outputs on every cycle of random traces, fallbacks and specification errors
/// included.
#[test]
fn st_conforms_to_the_engine_on_a_large_plant_with_safe_values() {
    use crate::plant::SafeValue;
    let syn = crate::synthetic::generate(120, 150, 11);
    let mut plant = syn.plant.clone();
    for (k, s) in plant.outputs.iter_mut().enumerate() {
        s.safe = match k % 5 {
            1 => SafeValue::One,
            3 => SafeValue::Hold,
            _ => SafeValue::Zero,
        };
    }
    // Chains of combined constraints (components of three and four outputs) and pairs
    // of simple constraints that force one output both ways in some contexts.
    let mut text = syn.text.clone();
    text.push_str("CSx1 = C1 . /A2 . /A3\nCSx2 = C2 . A3 . /A4\nCSx3 = C3 . A4 . A5\n");
    text.push_str("CSx4 = C5 . /A11 . A12\nCSx5 = C6 . A12 . A13\nCSx6 = C7 . /A13 . /A14\nCSx7 = C8 . A14 . /A11\n");
    text.push_str("CSx8 = C9 . C10 . A21\nCSx9 = C9 . C10 . /A21\n");
    let (constraints, problems) = crate::constraints::ConstraintSet::parse(
        &text,
        std::path::Path::new("big.txt"),
        &syn.symbols,
    );
    assert!(problems.iter().all(|p| !p.is_error()), "{problems:#?}");
    let bundle = PlantBundle {
        dir: PathBuf::from("."),
        plant,
        symbols: syn.symbols.clone(),
        observers: crate::observers::Observers::empty(),
        constraints,
        invariants: crate::constraints::ConstraintSet::default(),
        discharged: Vec::new(),
        fallback: None,
        tasks: None,
        plausibility: Default::default(),
    };
    let filter = Filter::for_plant(&bundle.constraints, &bundle.plant);
    assert!(crate::filter::support(&filter).len() > 40);
    assert!(filter.output_components().iter().any(|c| c.len() >= 4));
    let text = st::generate(&bundle, None).unwrap();
    let unit = interp::parse(&text).unwrap();
    let sym = &bundle.symbols;
    let (n_in, n_out) = (bundle.plant.inputs.len(), bundle.plant.outputs.len());
    let name = |space, k: usize, filter| st_name(sym, space, k, filter);
    let (mut tripped_cycles, mut away_from_zero, mut spec_errors) = (0, 0, 0);
    for seed in 1..=40u64 {
        let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        let mut engine = Engine::new(&bundle, FilterMode::Enforce, 1);
        let mut m = Machine::new(unit.clone(), "Vigie_Safety").unwrap();
        let mut inputs = Bits::zeros(n_in);
        let mut cmd = Bits::zeros(n_out);
        for cycle in 0..150 {
            rng.flip_some(&mut inputs, 8);
            rng.flip_some(&mut cmd, 6);
            engine.cycle(Millis(cycle * 10), &inputs, &mut Commanded(cmd.clone()));
            let errors = engine
                .drain_events()
                .iter()
                .filter(|e| matches!(e, crate::engine::Event::SpecificationError { .. }))
                .count();
            spec_errors += errors;
            scan_st(&mut m, &bundle, cycle * 10, &inputs, &cmd);
            let at = format!("seed {seed}, cycle {cycle}");
            for k in 0..n_out {
                assert_eq!(
                    b(&m, &name(Space::Output, k, false)),
                    engine.applied().get(k),
                    "{at}: output {}",
                    sym.name(Space::Output, k as u32)
                );
            }
            assert_eq!(b(&m, "TRIPPED"), engine.is_tripped(), "{at}: trip");
            if engine.is_tripped() {
                tripped_cycles += 1;
                away_from_zero += engine.applied().count_ones();
            }
        }
    }
    // The traces exercise the fallback, the safe values and the conflicts.
    assert!(tripped_cycles > 2000, "tripped cycles {tripped_cycles}");
    assert!(
        away_from_zero > 1000,
        "outputs ON under the fallback {away_from_zero}"
    );
    assert!(spec_errors > 5, "specification errors {spec_errors}");
}
