//! Level 4, the hypothesis: what the control should have done and what may have made it
//! do otherwise, derived from the fired constraint and the recorded cycles only.
//!
//! For each fired constraint, with R(t) the stopping cycle and R(t-1) the one before:
//! - (a) `X401`: sensors of the constraint that changed in the stopping cycle: the control
//!   did not evolve its outputs as that change required;
//! - (b) `X402`: when an actuator of the constraint changed in the stopping cycle, the
//!   sensors outside the constraint that changed in the same cycle, listed one by one:
//!   a receptivity or an output equation using one of them may have driven it;
//! - (c) `X403`: the expected action on each actuator of the constraint (stay / be ON or
//!   OFF, or for a combined constraint, one of several alternatives);
//! - (d) `X404`: an actuator of the constraint changed while no input changed at all: an
//!   internal timer or memory of the program is suspected;
//! - `X405`: nothing changed in the stopping cycle but an observer or another internal
//!   variable (the constraint became true through it).
//!
//! - `X419`: the term reads a mirror contact and its output at t-1 with opposite values:
//!   the contactor is welded or dead (the machine, not the program).
//!
//! Suspects are ordered: X419, then a suspect sensor (X414), then (a) and (b) items, in
//! the order the changes appear.

use super::{Highlight, Item, Level, Mark};
use crate::constraints::ConstraintSet;
use crate::diag::codes;
use crate::engine::{Engine, FiredConstraint, Trip};
use crate::history::CycleRecord;
use crate::symbols::Space;

/// The contactors a fired constraint shows at fault: its term reads a mirror contact and
/// the output it mirrors at t-1 with opposite values. Each as (actuator, mirror,
/// welded): released and still closed (welded), or commanded and still open (dead).
pub fn contactors_at_fault(
    symbols: &crate::symbols::Symbols,
    mirrors: &[(usize, usize)],
    c: &FiredConstraint,
) -> Vec<(String, String, bool)> {
    let mut out = Vec::new();
    for &(i, o) in mirrors {
        let (Some(mirror), Some(output)) = (
            symbols.names(Space::Input).get(i),
            symbols.names(Space::Output).get(o),
        ) else {
            continue;
        };
        let reads = c
            .literals
            .iter()
            .find(|l| l.space == Space::Input && !l.previous && &l.name == mirror);
        let was = c
            .literals
            .iter()
            .find(|l| l.space == Space::Output && l.previous && &l.name == output);
        if let (Some(reads), Some(was)) = (reads, was)
            && reads.value != was.value
        {
            out.push((output.clone(), mirror.clone(), reads.value));
        }
    }
    out
}

/// X419: the contactors the fired term shows at fault ([`contactors_at_fault`]). That is
/// the machine, not the program: it comes first, with the contactor to check.
fn contactor_disagrees(
    symbols: &crate::symbols::Symbols,
    mirrors: &[(usize, usize)],
    c: &FiredConstraint,
) -> Vec<(Item, Vec<Highlight>)> {
    let mut out = Vec::new();
    for (output, mirror, welded) in contactors_at_fault(symbols, mirrors, c) {
        let (state, text) = if welded {
            (
                "welded",
                format!(
                    "Hardware first: {output} was released and its mirror contact {mirror} still reads it closed ({}): its contactor is welded. Check {output}'s contactor on the machine; the program released it.",
                    c.id
                ),
            )
        } else {
            (
                "dead",
                format!(
                    "Hardware first: {output} was commanded and its mirror contact {mirror} reads it open ({}): it did not close (coil, fuse, wiring or the contactor itself). Check {output} on the machine; the program commanded it.",
                    c.id
                ),
            )
        };
        out.push((
            Item::new(
                codes::X_CONTACTOR_DISAGREES,
                text,
                &[
                    ("category", "hardware".into()),
                    ("constraint", c.id.clone()),
                    ("actuator", output.clone()),
                    ("mirror", mirror),
                    ("state", state.into()),
                    ("check", output.clone()),
                ],
            ),
            vec![Highlight {
                element: output,
                mark: Mark::Suspect,
            }],
        ));
    }
    out
}

/// What changed between two records.
struct Delta {
    inputs: Vec<(String, bool, bool)>,
    outputs: Vec<(String, bool, bool)>,
    observers: Vec<String>,
}

/// A mirror contact that changed to show the output applied the cycle before followed its
/// contactor: not a change of the plant, so not in the inputs' delta (`mirrors`: each
/// mirror's input and the output it mirrors).
fn delta(
    symbols: &crate::symbols::Symbols,
    mirrors: &[(usize, usize)],
    prev: &CycleRecord,
    cur: &CycleRecord,
) -> Delta {
    let diff = |space: Space, a: &crate::bits::Bits, b: &crate::bits::Bits| {
        symbols
            .names(space)
            .iter()
            .enumerate()
            .filter(|(i, _)| a.get(*i) != b.get(*i))
            .map(|(i, n)| (n.clone(), a.get(i), b.get(i)))
            .collect::<Vec<_>>()
    };
    Delta {
        inputs: diff(Space::Input, &prev.inputs, &cur.inputs)
            .into_iter()
            .filter(|(n, _, to)| {
                !mirrors.iter().any(|&(i, o)| {
                    symbols.names(Space::Input).get(i) == Some(n) && prev.applied.get(o) == *to
                })
            })
            .collect(),
        outputs: diff(Space::Output, &prev.commanded, &cur.commanded),
        observers: diff(Space::Observer, &prev.observers, &cur.observers)
            .into_iter()
            .map(|(n, _, _)| n)
            .collect(),
    }
}

fn edge(from: bool, to: bool) -> &'static str {
    match (from, to) {
        (false, true) => "rose (0→1)",
        (true, false) => "fell (1→0)",
        _ => "kept its value",
    }
}

/// The hypothesis level for `trip`.
pub fn hypothesis(engine: &Engine, trip: &Trip) -> Level {
    let cur = engine.history.iter().find(|r| r.time.0 == trip.time_ms);
    let prev = cur.and_then(|c| engine.history.iter().rev().find(|p| p.time < c.time));
    let (Some(cur), Some(prev)) = (cur, prev) else {
        let mut level = Level {
            title: "Hypothesis".into(),
            ..Level::default()
        };
        level.items.push(Item::new(
            codes::X_NO_RECORDED_CYCLES,
            "The cycles before the stop are no longer in the history: no hypothesis.".into(),
            &[],
        ));
        return level;
    };
    let mut level = hypothesis_from(&engine.symbols, engine.mirrors(), trip, prev, cur);
    let mut first = Vec::new();
    for (item, highlights) in unexpected_edges(engine, trip, prev, cur) {
        highlights.into_iter().for_each(|h| level.highlight(h));
        first.push(item);
    }
    level.items.splice(0..0, first);
    level
}

/// X418: the sensors of the fired terms that changed in the stopping cycle where the
/// plant's physics did not expect it (`rise_expected_when` / `fall_expected_when`).
fn unexpected_edges(
    engine: &Engine,
    trip: &Trip,
    prev: &CycleRecord,
    cur: &CycleRecord,
) -> Vec<(Item, Vec<Highlight>)> {
    let symbols = &engine.symbols;
    let mut frame = crate::frame::Frame::new(symbols.sizes());
    for (space, now, before) in [
        (Space::Input, &cur.inputs, &prev.inputs),
        (Space::Output, &cur.applied, &prev.applied),
        (Space::Observer, &cur.observers, &prev.observers),
        (Space::Aux, &cur.aux, &prev.aux),
    ] {
        frame.now_mut(space).copy_from(now);
        frame.prev_mut(space).copy_from(before);
    }
    let mut out: Vec<(Item, Vec<Highlight>)> = Vec::new();
    for l in trip.constraints.iter().flat_map(|c| &c.literals) {
        let Some((Space::Input, k)) = symbols.lookup(&l.name) else {
            continue;
        };
        let k = k as usize;
        let (from, to) = (prev.inputs.get(k), cur.inputs.get(k));
        if l.previous || from == to || out.iter().any(|(i, _)| i.fields["sensor"] == l.name) {
            continue;
        }
        let Some(expected) = engine.plausibility.unexpected_edge(k, to, &frame) else {
            continue;
        };
        let (ids, follows) = follows(engine, expected);
        out.push((
            Item::new(
                codes::X_UNEXPECTED_EDGE,
                format!(
                    "{} {} in the stopping cycle where the plant's physics did not expect it (only when {expected}: {follows}): no item could have reached it. Its reading, or the sensor that should have announced the item, is the first suspect: check {} on the machine before the program.",
                    l.name,
                    edge(from, to),
                    l.name
                ),
                &[
                    ("sensor", l.name.clone()),
                    ("from", u8::from(from).to_string()),
                    ("to", u8::from(to).to_string()),
                    ("expected", expected.to_string()),
                    ("follows", ids),
                ],
            ),
            vec![Highlight {
                element: l.name.clone(),
                mark: Mark::Suspect,
            }],
        ));
    }
    out
}

/// What an expectation reads: the names (`P36`), and in words each with its observer's
/// description (`P36 = A box between C3 and C6`).
fn follows(engine: &Engine, expected: &str) -> (String, String) {
    let names: Vec<String> = crate::expr::parse_str(expected)
        .map(|e| {
            e.leaves()
                .iter()
                .map(|(n, _, _)| (*n).to_string())
                .collect()
        })
        .unwrap_or_default();
    let mut out: Vec<String> = Vec::new();
    let mut ids: Vec<String> = Vec::new();
    for n in names {
        if ids.contains(&n) {
            continue;
        }
        ids.push(n.clone());
        let described = engine
            .observers
            .defs
            .iter()
            .find(|d| d.id == n)
            .map(|d| d.description.clone());
        out.push(match described {
            Some(d) if !d.is_empty() => format!("{n} = {d}"),
            _ => n,
        });
    }
    (ids.join(","), out.join("; "))
}

/// The hypothesis level from the two cycles around the stop (`mirrors`: the plant's
/// mirror contacts, [`crate::plant::Plant::mirrors`]).
pub fn hypothesis_from(
    symbols: &crate::symbols::Symbols,
    mirrors: &[(usize, usize)],
    trip: &Trip,
    prev: &CycleRecord,
    cur: &CycleRecord,
) -> Level {
    let mut level = Level {
        title: "Hypothesis".into(),
        ..Level::default()
    };
    let d = delta(symbols, mirrors, prev, cur);
    for c in &trip.constraints {
        for (item, highlights) in contactor_disagrees(symbols, mirrors, c) {
            highlights.into_iter().for_each(|h| level.highlight(h));
            level.items.push(item);
        }
    }
    for c in &trip.constraints {
        for item in constraint_hypothesis(c, &d, prev) {
            let (item, highlights) = item;
            highlights.into_iter().for_each(|h| level.highlight(h));
            level.items.push(item);
        }
    }
    // Suspects first, then expected actions.
    let rank = |code: &str| {
        if code == codes::X_CONTACTOR_DISAGREES.id {
            0
        } else if code == codes::X_SUSPECT_SENSOR.id {
            1
        } else if [
            codes::X_SENSOR_CHANGED_NO_EVOLUTION.id,
            codes::X_SENSOR_OUTSIDE_CHANGED.id,
        ]
        .contains(&code)
        {
            2
        } else if [
            codes::X_ACTUATOR_CHANGED_NO_INPUT.id,
            codes::X_OBSERVER_CHANGE.id,
        ]
        .contains(&code)
        {
            3
        } else {
            4
        }
    };
    level.items.sort_by_key(|i| rank(i.code));
    super::merge_identical(&mut level.items);
    level
}

type Produced = (Item, Vec<Highlight>);

fn constraint_hypothesis(c: &FiredConstraint, d: &Delta, prev: &CycleRecord) -> Vec<Produced> {
    let mut out: Vec<Produced> = Vec::new();
    let sensors: Vec<&str> = c
        .literals
        .iter()
        .filter(|l| l.space == Space::Input)
        .map(|l| l.name.as_str())
        .collect();
    let outputs: Vec<(&str, bool)> = c
        .literals
        .iter()
        .filter(|l| l.space == Space::Output && !l.previous)
        .map(|l| (l.name.as_str(), l.value))
        .collect();
    let observers_in: Vec<&str> = c
        .literals
        .iter()
        .filter(|l| l.space == Space::Observer)
        .map(|l| l.name.as_str())
        .collect();
    let outputs_changed: Vec<&(String, bool, bool)> = d
        .outputs
        .iter()
        .filter(|(n, _, _)| outputs.iter().any(|(o, _)| o == n))
        .collect();
    let expected_text = expected_actions(&outputs, prev, &c.id);

    // A sensor of the term the plausibility stage holds (read as possibly either value
    // by the constraint): the sensor's reading, not the program, is the first suspect.
    suspect_sensor_items(c, &mut out);
    // (a) sensors of the constraint that changed.
    for (name, from, to) in d
        .inputs
        .iter()
        .filter(|(n, _, _)| sensors.contains(&n.as_str()))
    {
        out.push((
            Item::new(
                codes::X_SENSOR_CHANGED_NO_EVOLUTION,
                format!(
                    "{name} {} in the stopping cycle and is part of {}; the control did not make the evolution this change requires: {expected_text}.",
                    edge(*from, *to),
                    c.id
                ),
                &[
                    ("category", "a".into()),
                    ("constraint", c.id.clone()),
                    ("sensor", name.clone()),
                    ("from", u8::from(*from).to_string()),
                    ("to", u8::from(*to).to_string()),
                    ("expected", expected_field(&outputs)),
                ],
            ),
            vec![Highlight {
                element: name.clone(),
                mark: Mark::Suspect,
            }],
        ));
    }
    // (b) sensors outside the constraint that changed with an actuator of it.
    changed_with_actuators(c, d, &sensors, &outputs_changed, &mut out);
    if !d.observers.is_empty() && d.inputs.is_empty() {
        out.push((
            Item::new(
                codes::X_OBSERVER_CHANGE,
                format!(
                    "Observer {} changed without a direct input change; {} became true through it.",
                    d.observers.join(", "),
                    c.id
                ),
                &[
                    ("category", "e".into()),
                    ("observers", d.observers.join(",")),
                ],
            ),
            observers_in
                .iter()
                .map(|o| Highlight {
                    element: (*o).to_string(),
                    mark: Mark::Suspect,
                })
                .collect(),
        ));
    }
    // (c) expected actions.
    let mut highlights = Vec::new();
    for (name, value) in &outputs {
        if outputs.len() == 1 {
            highlights.push(Highlight {
                element: (*name).to_string(),
                mark: Mark::Expected { value: !value },
            });
        }
    }
    out.push((
        Item::new(
            codes::X_EXPECTED_ACTION,
            format!("Expected from the control: {expected_text}."),
            &[
                ("category", "c".into()),
                ("constraint", c.id.clone()),
                ("expected", expected_field(&outputs)),
            ],
        ),
        highlights,
    ));
    out
}

/// Items for sensors of the constraint held by the plausibility stage.
fn suspect_sensor_items(c: &FiredConstraint, out: &mut Vec<Produced>) {
    for l in c
        .literals
        .iter()
        .filter(|l| l.space == Space::Aux && !l.previous && l.value)
    {
        let Some(sensor) = crate::plausibility::suspect_sensor(&l.name) else {
            continue;
        };
        out.push((
            Item::new(
                codes::X_SUSPECT_SENSOR,
                format!(
                    "{sensor} is suspect: its reading made an edge the plant's physics does not allow, the plausibility stage holds its last plausible value and {} reads it as possibly either value. Check {sensor} (beam, reflector, cable) before the program.",
                    c.id
                ),
                &[
                    ("category", "sensor".into()),
                    ("constraint", c.id.clone()),
                    ("sensor", sensor.to_string()),
                ],
            ),
            vec![Highlight {
                element: sensor.to_string(),
                mark: Mark::Suspect,
            }],
        ));
    }
}

/// (b) sensors outside the constraint that changed with an actuator of it, and (d) no
/// input change at all.
fn changed_with_actuators(
    c: &FiredConstraint,
    d: &Delta,
    sensors: &[&str],
    outputs_changed: &[&(String, bool, bool)],
    out: &mut Vec<Produced>,
) {
    if outputs_changed.is_empty() {
        return;
    }
    let acts: Vec<String> = outputs_changed
        .iter()
        .map(|(n, f, t)| format!("{n} {}", edge(*f, *t)))
        .collect();
    let outside: Vec<&(String, bool, bool)> = d
        .inputs
        .iter()
        .filter(|(n, _, _)| !sensors.contains(&n.as_str()))
        .collect();
    for (name, from, to) in &outside {
        out.push((
            Item::new(
                codes::X_SENSOR_OUTSIDE_CHANGED,
                format!(
                    "{name} {} in the same cycle as {}; {name} is not part of {}: a receptivity or an output equation using {name} may have driven the actuator.",
                    edge(*from, *to),
                    acts.join(", "),
                    c.id
                ),
                &[
                    ("category", "b".into()),
                    ("constraint", c.id.clone()),
                    ("sensor", name.clone()),
                    ("actuators", acts.join(",")),
                ],
            ),
            vec![Highlight {
                element: name.clone(),
                mark: Mark::Suspect,
            }],
        ));
    }
    // (d) no input change at all.
    if d.inputs.is_empty() && d.observers.is_empty() {
        out.push((
            Item::new(
                codes::X_ACTUATOR_CHANGED_NO_INPUT,
                format!(
                    "{} while no input changed: an internal timer or memory of the program probably drove it.",
                    acts.join(", ")
                ),
                &[
                    ("category", "d".into()),
                    ("constraint", c.id.clone()),
                    ("actuators", acts.join(",")),
                ],
            ),
            outputs_changed
                .iter()
                .map(|(n, _, _)| Highlight {
                    element: n.clone(),
                    mark: Mark::Suspect,
                })
                .collect(),
        ));
    }
}

/// The `expected` field: `A4=1`, or the alternatives `A2=0 or A3=0`.
fn expected_field(outputs: &[(&str, bool)]) -> String {
    outputs
        .iter()
        .map(|(n, v)| format!("{n}={}", u8::from(!v)))
        .collect::<Vec<_>>()
        .join(" or ")
}

/// "A4 should have stayed ON", or for several outputs the alternatives.
fn expected_actions(outputs: &[(&str, bool)], prev: &CycleRecord, _id: &str) -> String {
    let _ = prev;
    let phrase = |(name, value): &(&str, bool)| {
        let want = if *value { "OFF" } else { "ON" };
        format!("{name} should have been {want}")
    };
    match outputs {
        [one] => phrase(one),
        many => format!(
            "one of: {}",
            many.iter().map(phrase).collect::<Vec<_>>().join(", or ")
        ),
    }
}

/// Number of situations the generator distinguishes for a constraint set: for each
/// product term, every subset of its sensors changing in the stopping cycle, every
/// subset of its actuators changing, and whether a sensor outside it changes.
/// (The paper studied 122 cases by hand for the sorting station.)
pub fn case_count(set: &ConstraintSet) -> u64 {
    set.constraints
        .iter()
        .flat_map(|c| &c.dnf)
        .map(|term| {
            let mut sensors: Vec<u32> = term
                .iter()
                .filter(|l| l.var.space == Space::Input || l.var.space == Space::Observer)
                .map(|l| {
                    l.var.index
                        + if l.var.space == Space::Observer {
                            1 << 20
                        } else {
                            0
                        }
                })
                .collect();
            sensors.sort_unstable();
            sensors.dedup();
            let outputs = term
                .iter()
                .filter(|l| l.var.space == Space::Output && !l.var.prev)
                .count();
            1u64 << (sensors.len() + outputs + 1).min(40)
        })
        .sum()
}
