//! The five explanation levels of seed 004 (section 5, figures 13-17) for any trip,
//! generated from the trip record, the recorder and the constraint set: no
//! per-constraint table written by hand.
//!
//! | level | name          | what it shows                                                   |
//! |-------|---------------|-----------------------------------------------------------------|
//! | 0     | current state | the real state after the stop, the actuators the filter holds and why, boxes the observers infer |
//! | 1     | projection    | the state the plant would have reached without the filter (filled by the simulation, which owns the emulator) |
//! | 2     | before stop   | inputs and outputs just before the stop, the constraint's elements circled, the filter's action per actuator |
//! | 3     | advanced      | the last changes of sensors and actuators that led to the violation, with their times |
//! | 4     | hypothesis    | suspects: sensors of the constraint whose change the control ignored, sensors outside it that may have driven an actuator, the expected actuator actions, or an internal timer/memory when no input changed |
//!
//! Every item has a stable code (`X0nn` for level 0 … `X4nn` for level 4), structured
//! fields, the plant elements it concerns (for drawing on the synoptic) and an English
//! text. The catalogue of codes is `core/src/explain/codes.md` (included below).
//!
//! In emulator mode the hypothesis also names the chart elements (`X407`-`X413`, `X417`,
//! [`program_suspects`]); in live mode [`emulator_from_observation`] rebuilds a plant
//! for the projection from the observed inputs and observers.
//!
#![doc = include_str!("codes.md")]

mod hardware;
mod hypothesis;
mod observed;
mod program;

use crate::bits::Bits;
use crate::diag::codes::{self, Code};
use crate::engine::{Action, Engine, FiredConstraint, Trip};
use crate::history::CycleRecord;
use crate::symbols::{Space, Symbols};
use serde::Serialize;
use std::collections::BTreeMap;

pub use hardware::{HardwareFault, add_hardware_hypothesis, merge_identical};
pub use hypothesis::{case_count, contactors_at_fault, hypothesis, hypothesis_from};
pub use observed::emulator_from_observation;
pub use program::{add_program_hypothesis, program_suspects};

/// How an element is marked on the synoptic.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "mark", rename_all = "snake_case")]
pub enum Mark {
    /// Element of the fired constraint (circled in red).
    Circle,
    /// Held ON by the filter.
    ForcedOn,
    /// Forced OFF by the filter.
    ForcedOff,
    /// Changed value.
    Change {
        /// Value before.
        from: bool,
        /// Value after.
        to: bool,
    },
    /// Kept its value (e.g. an actuator that stays ON).
    Steady {
        /// The value.
        value: bool,
    },
    /// A suspect of the hypothesis level.
    Suspect,
    /// What the control should have commanded.
    Expected {
        /// The expected value.
        value: bool,
    },
    /// A box the observers infer.
    InferredBox,
    /// A sensor read from its estimate (degraded mode), marked live on the synoptic.
    Estimated,
}

/// One plant element to mark.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Highlight {
    /// Signal or observer id.
    pub element: String,
    /// The mark.
    #[serde(flatten)]
    pub mark: Mark,
}

/// One explanation item.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Item {
    /// Stable code.
    pub code: &'static str,
    /// Structured fields (sorted).
    pub fields: BTreeMap<String, String>,
    /// Rendered English text.
    pub text: String,
}

impl Item {
    pub(crate) fn new(code: Code, text: String, fields: &[(&str, String)]) -> Self {
        Self {
            code: code.id,
            fields: fields
                .iter()
                .map(|(k, v)| ((*k).to_string(), v.clone()))
                .collect(),
            text,
        }
    }
}

/// One level of explanation.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Level {
    /// Level title.
    pub title: String,
    /// Items, most important first.
    pub items: Vec<Item>,
    /// Elements to mark on the synoptic.
    pub highlights: Vec<Highlight>,
    /// Signal values to draw (id → value) at this level; empty means "as is".
    pub state: BTreeMap<String, bool>,
}

impl Level {
    /// Marks `h` on the synoptic, once.
    pub fn highlight(&mut self, h: Highlight) {
        if !self.highlights.contains(&h) {
            self.highlights.push(h);
        }
    }
}

/// The five levels for one trip.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Explanation {
    /// Index of the trip in the engine's list.
    pub trip: usize,
    /// Time of the trip.
    pub time_ms: u64,
    /// The fired constraints in the paper's notation.
    pub constraints: Vec<String>,
    /// Level 0.
    pub current_state: Level,
    /// Level 1 (empty until a projection is computed).
    pub projection: Level,
    /// Level 2.
    pub before_stop: Level,
    /// Level 3.
    pub advanced: Level,
    /// Level 4.
    pub hypothesis: Level,
}

impl Explanation {
    /// The levels in order 0..=4.
    pub fn levels(&self) -> [&Level; 5] {
        [
            &self.current_state,
            &self.projection,
            &self.before_stop,
            &self.advanced,
            &self.hypothesis,
        ]
    }
}

/// Values of every signal in a record: inputs and, for outputs, the given table.
pub(crate) fn signal_state(
    symbols: &Symbols,
    inputs: &Bits,
    outputs: &Bits,
) -> BTreeMap<String, bool> {
    let mut state = BTreeMap::new();
    for (i, name) in symbols.names(Space::Input).iter().enumerate() {
        state.insert(name.clone(), inputs.get(i));
    }
    for (k, name) in symbols.names(Space::Output).iter().enumerate() {
        state.insert(name.clone(), outputs.get(k));
    }
    state
}

/// Renders a constraint in the paper's notation with overbars (combining U+0305) for
/// negations: `C7 . /A4` → `C7 · A̅4̅`.
pub fn overbar_notation(source: &str) -> String {
    let mut out = String::new();
    let mut negate = false;
    let mut depth_negated: Vec<bool> = Vec::new();
    let mut chars = source.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' | '!' => negate = true,
            '.' => out.push('·'),
            '(' => {
                depth_negated.push(negate);
                negate = false;
                out.push('(');
            }
            ')' => {
                out.push(')');
                if depth_negated.pop().unwrap_or(false) {
                    out.push_str(" (negated)");
                }
            }
            c if c.is_ascii_alphanumeric() || c == '_' || c == ':' || c == '*' => {
                out.push(c);
                if negate {
                    out.push('\u{0305}');
                }
                let in_name = chars.peek().is_some_and(|n| {
                    n.is_ascii_alphanumeric() || *n == '_' || *n == ':' || *n == '*'
                });
                if !in_name {
                    negate = false;
                }
            }
            c => out.push(c),
        }
    }
    out
}

/// Builds levels 0, 2, 3 and 4 for trip `index` of `engine`. Level 1 needs the plant
/// emulator and is filled by [`crate::sim`]. Returns `None` for an unknown trip.
pub fn explain(engine: &Engine, index: usize) -> Option<Explanation> {
    let trip = engine.trips.get(index)?;
    let at_trip = engine.history.iter().find(|r| r.time.0 == trip.time_ms);
    let before = at_trip.and_then(|r| engine.history.iter().rev().find(|p| p.time < r.time));
    Some(Explanation {
        trip: index,
        time_ms: trip.time_ms,
        constraints: trip
            .constraints
            .iter()
            .map(|c| format!("{} = {}", c.id, overbar_notation(&c.notation)))
            .collect(),
        current_state: current_state(engine, trip),
        projection: Level {
            title: "Projection".into(),
            ..Level::default()
        },
        before_stop: before_stop(engine, trip, at_trip),
        advanced: advanced(engine, trip, at_trip, before),
        hypothesis: hypothesis(engine, trip),
    })
}

fn constraint_elements(c: &FiredConstraint) -> Vec<String> {
    let mut names: Vec<String> = c.literals.iter().map(|l| l.name.clone()).collect();
    names.dedup();
    names
}

fn current_state(engine: &Engine, trip: &Trip) -> Level {
    let symbols = &engine.symbols;
    let mut level = Level {
        title: "Current state".into(),
        ..Level::default()
    };
    let last = engine.history.last();
    let ids: Vec<&str> = trip.constraints.iter().map(|c| c.id.as_str()).collect();
    if !trip.enforced {
        return monitored_state(engine, trip, level, &ids);
    }
    level.items.push(Item::new(
        codes::X_FILTER_STOPPED,
        format!(
            "The safety filter stopped the plant at {} ms: {} would have been violated.",
            trip.time_ms,
            ids.join(", ")
        ),
        &[
            ("time_ms", trip.time_ms.to_string()),
            ("constraints", ids.join(",")),
        ],
    ));
    if let Some(rec) = last {
        level.state = signal_state(symbols, &rec.inputs, &rec.applied);
        // Outputs held ON: name the simple constraint that forces each one.
        let frame = engine.frame();
        for (k, name) in symbols.names(Space::Output).iter().enumerate() {
            if !rec.applied.get(k) {
                continue;
            }
            let reasons = engine.filter().forcing_on(k, frame, symbols);
            level.highlights.push(Highlight {
                element: name.clone(),
                mark: Mark::ForcedOn,
            });
            level.items.push(Item::new(
                codes::X_ACTUATOR_KEPT_ON,
                if reasons.is_empty() {
                    format!("{name} is kept ON.")
                } else {
                    format!("{name} is held ON by the filter: {}.", reasons.join("; "))
                },
                &[("output", name.clone()), ("reasons", reasons.join("; "))],
            ));
        }
        let off: Vec<&str> = symbols
            .names(Space::Output)
            .iter()
            .enumerate()
            .filter(|(k, _)| !rec.applied.get(*k))
            .map(|(_, n)| n.as_str())
            .collect();
        level.items.push(Item::new(
            codes::X_ACTUATORS_STOPPED,
            format!("Stopped (OFF): {}.", off.join(", ")),
            &[("outputs", off.join(","))],
        ));
        // An output OFF that moves something (a monostable actuator): say what.
        for (k, name) in symbols.names(Space::Output).iter().enumerate() {
            if let Some(m) = engine.off_meaning(k).filter(|_| !rec.applied.get(k)) {
                level.items.push(Item::new(
                    codes::X_OFF_MEANING,
                    format!("{name} OFF: {m}."),
                    &[("output", name.clone()), ("meaning", m.to_string())],
                ));
            }
        }
        for (o, def) in engine.observers.defs.iter().enumerate() {
            if rec.observers.get(o) {
                level.highlights.push(Highlight {
                    element: def.id.clone(),
                    mark: Mark::InferredBox,
                });
                level.items.push(Item::new(
                    codes::X_OBSERVER_SET,
                    format!(
                        "Observer {} is set: {}.",
                        def.id,
                        lowercase_first(&def.description)
                    ),
                    &[("observer", def.id.clone())],
                ));
            }
        }
    }
    level
}

/// Level 0 of a violation in monitor mode (the filter only reports): what the filter
/// would have done; the outputs are the PLC's own.
fn monitored_state(engine: &Engine, trip: &Trip, mut level: Level, ids: &[&str]) -> Level {
    level.items.push(Item::new(
        codes::X_FILTER_WOULD_STOP,
        format!(
            "Monitor mode: at {} ms {} became true; enforcing, the safety filter would have stopped the plant. The filter only reports: the PLC's outputs were not changed.",
            trip.time_ms,
            ids.join(", ")
        ),
        &[
            ("time_ms", trip.time_ms.to_string()),
            ("constraints", ids.join(",")),
        ],
    ));
    if let Some(rec) = engine.history.last() {
        level.state = signal_state(&engine.symbols, &rec.inputs, &rec.applied);
    }
    let commanded: BTreeMap<&str, bool> = trip
        .actions
        .iter()
        .map(|a| (a.output.as_str(), a.commanded))
        .collect();
    let changed = |on: bool| -> Vec<&str> {
        trip.fallback
            .iter()
            .filter(|(o, v)| *v == on && commanded.get(o.as_str()) != Some(&on))
            .map(|(o, _)| o.as_str())
            .collect()
    };
    let (held, stopped) = (changed(true), changed(false));
    level.items.push(Item::new(
        codes::X_FILTER_WOULD_APPLY,
        format!(
            "Enforcing, the filter would have held ON: {}; stopped: {}.",
            if held.is_empty() {
                "-".to_string()
            } else {
                held.join(", ")
            },
            if stopped.is_empty() {
                "-".to_string()
            } else {
                stopped.join(", ")
            }
        ),
        &[("held", held.join(",")), ("stopped", stopped.join(","))],
    ));
    level
}

fn lowercase_first(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_lowercase().chain(c).collect(),
        None => String::new(),
    }
}

fn before_stop(engine: &Engine, trip: &Trip, at_trip: Option<&CycleRecord>) -> Level {
    let symbols = &engine.symbols;
    let mut level = Level {
        title: "Before stop".into(),
        ..Level::default()
    };
    if let Some(rec) = at_trip {
        level.state = signal_state(symbols, &rec.inputs, &rec.commanded);
    }
    for c in &trip.constraints {
        let elements = constraint_elements(c);
        for e in &elements {
            if !level
                .highlights
                .iter()
                .any(|h| &h.element == e && h.mark == Mark::Circle)
            {
                level.highlights.push(Highlight {
                    element: e.clone(),
                    mark: Mark::Circle,
                });
            }
        }
        let values: Vec<String> = c
            .literals
            .iter()
            .map(|l| {
                format!(
                    "{}={}",
                    l.literal.trim_start_matches('/'),
                    u8::from(l.value)
                )
            })
            .collect();
        // A constraint of several terms is told by the term that became true (a
        // diagnosers' stop has one per component state: the whole sum hides it).
        let term: Vec<&str> = c.literals.iter().map(|l| l.literal.as_str()).collect();
        let term = term.join(" . ");
        let multi = c.notation.contains('+');
        let text = if multi {
            format!(
                "{}: its term {} became true: {}.",
                c.id,
                overbar_notation(&term),
                values.join(", ")
            )
        } else {
            format!(
                "{} = {} became true: {}.",
                c.id,
                overbar_notation(&c.notation),
                values.join(", ")
            )
        };
        level.items.push(Item::new(
            codes::X_CONSTRAINT_BECAME_TRUE,
            text,
            &[
                ("constraint", c.id.clone()),
                ("notation", c.notation.clone()),
                ("term", term),
                ("multi", if multi { "yes" } else { "no" }.to_string()),
                ("elements", elements.join(",")),
                ("values", values.join(",")),
            ],
        ));
    }
    for a in &trip.actions {
        let (mark, code, verb) = match a.action {
            Action::ForcedOn => (Mark::ForcedOn, codes::X_HELD_ON, "held ON (commanded OFF)"),
            Action::ForcedOff => (
                Mark::ForcedOff,
                codes::X_FORCED_OFF,
                "forced OFF (commanded ON)",
            ),
            Action::Unchanged => continue,
        };
        level.highlights.push(Highlight {
            element: a.output.clone(),
            mark,
        });
        // What the program's command would have done, when the plant says it.
        let meaning = symbols
            .lookup(&a.output)
            .and_then(|(_, k)| engine.off_meaning(k as usize))
            .filter(|_| !a.commanded);
        let text = match meaning {
            Some(m) => format!("The filter {verb} {} ({} OFF: {m}).", a.output, a.output),
            None => format!("The filter {verb} {}.", a.output),
        };
        level.items.push(Item::new(
            code,
            text,
            &[
                ("output", a.output.clone()),
                ("meaning", meaning.unwrap_or_default().to_string()),
            ],
        ));
    }
    level
}

/// A change of one signal, found in the recorder.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Change {
    /// Signal id.
    pub signal: String,
    /// Value before.
    pub from: bool,
    /// Value after.
    pub to: bool,
    /// Time of the cycle where the new value was first seen.
    pub time_ms: u64,
    /// Cycles between that cycle and the trip (0 = the trip cycle).
    pub cycles_before_trip: usize,
}

/// The last change of every input and commanded output at or before the trip record,
/// searching back at most `window` cycles.
pub(crate) fn last_changes(engine: &Engine, trip_time: u64, window: usize) -> Vec<Change> {
    let symbols = &engine.symbols;
    let records: Vec<&CycleRecord> = engine
        .history
        .iter()
        .filter(|r| r.time.0 <= trip_time)
        .collect();
    let mut changes = Vec::new();
    let n_in = symbols.len(Space::Input);
    let n_out = symbols.len(Space::Output);
    for (space, n) in [(Space::Input, n_in), (Space::Output, n_out)] {
        for i in 0..n {
            let value = |r: &CycleRecord| match space {
                Space::Input => r.inputs.get(i),
                _ => r.commanded.get(i),
            };
            for (back, pair) in records.windows(2).rev().enumerate().take(window) {
                let (prev, cur) = (pair[0], pair[1]);
                if value(prev) != value(cur) {
                    changes.push(Change {
                        signal: symbols
                            .name(space, u32::try_from(i).unwrap_or(0))
                            .to_string(),
                        from: value(prev),
                        to: value(cur),
                        time_ms: cur.time.0,
                        cycles_before_trip: back,
                    });
                    break;
                }
            }
        }
    }
    changes.sort_by(|a, b| {
        a.cycles_before_trip
            .cmp(&b.cycles_before_trip)
            .then(a.signal.cmp(&b.signal))
    });
    changes
}

fn advanced(
    engine: &Engine,
    trip: &Trip,
    at_trip: Option<&CycleRecord>,
    before: Option<&CycleRecord>,
) -> Level {
    let symbols = &engine.symbols;
    let mut level = Level {
        title: "Advanced state".into(),
        ..Level::default()
    };
    let Some(rec) = at_trip else {
        return level;
    };
    level.state = signal_state(symbols, &rec.inputs, &rec.commanded);
    let elements: Vec<String> = trip
        .constraints
        .iter()
        .flat_map(constraint_elements)
        .collect();
    // Every change in the trip cycle, and the last change of each element of the
    // constraint within the last 10 s of history.
    let changes = last_changes(engine, trip.time_ms, 1000);
    for ch in &changes {
        let in_constraint = elements.contains(&ch.signal);
        if ch.cycles_before_trip > 0 && !in_constraint {
            continue;
        }
        level.highlights.push(Highlight {
            element: ch.signal.clone(),
            mark: Mark::Change {
                from: ch.from,
                to: ch.to,
            },
        });
        let when = if ch.cycles_before_trip == 0 {
            "in the stopping cycle".to_string()
        } else {
            format!(
                "{} ms before the stop",
                trip.time_ms.saturating_sub(ch.time_ms)
            )
        };
        level.items.push(Item::new(
            codes::X_LAST_CHANGE,
            format!(
                "{} changed {}→{} at {} ms ({when}){}.",
                ch.signal,
                u8::from(ch.from),
                u8::from(ch.to),
                ch.time_ms,
                if in_constraint {
                    ", element of the constraint"
                } else {
                    ""
                }
            ),
            &[
                ("signal", ch.signal.clone()),
                ("from", u8::from(ch.from).to_string()),
                ("to", u8::from(ch.to).to_string()),
                ("time_ms", ch.time_ms.to_string()),
                (
                    "ms_before",
                    trip.time_ms.saturating_sub(ch.time_ms).to_string(),
                ),
                ("in_constraint", in_constraint.to_string()),
            ],
        ));
    }
    // Outputs commanded ON in both cycles: they stay ON.
    if let Some(prev) = before {
        for (k, name) in symbols.names(Space::Output).iter().enumerate() {
            if prev.commanded.get(k) && rec.commanded.get(k) {
                level.highlights.push(Highlight {
                    element: name.clone(),
                    mark: Mark::Steady { value: true },
                });
                level.items.push(Item::new(
                    codes::X_STAYS_ON,
                    format!("{name} stays ON."),
                    &[("output", name.clone())],
                ));
            }
        }
    }
    level
}

#[cfg(test)]
mod tests;
