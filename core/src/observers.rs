//! Observers: sequential functions of the inputs that rebuild what no sensor sees
//! (seed 004, section 6.2), declared in `observers.ron`.
//!
//! Two rules exist:
//! - `Memory(set, reset)`: a set-dominant memory. If `set` and `reset` are true in the
//!   same cycle the memory is set: for a box-presence observer, believing a box is there
//!   is the conservative side.
//! - `Counter(up, down, clear, at_least)`: counts events, saturating at 0; `clear`
//!   forces the count to 0 (and wins); the observer is true while the count is at least
//!   `at_least`.
//!
//! The sorting station's `2P` is a counter of the boxes touching the zone between C0 and
//! C1: a box enters on `RE(C0)` (its front reaches C0) and leaves on `FE(C1)` (its rear
//! leaves C1). As the gap between C0 and C1 is shorter than any box, a box in the zone
//! always covers C0 or C1, so `/C0 . /C1` means the zone is empty and clears the count.
//! `2P` is `count >= 2`: two boxes, not one box straddling both sensors.

use crate::diag::codes;
use crate::diag::{Location, Problem, ron_problem};
use crate::expr::{self, Dnf};
use crate::frame::Frame;
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How an observer evolves.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Rule {
    /// Set-dominant memory.
    Memory {
        /// Sets the memory.
        set: String,
        /// Resets it.
        reset: String,
    },
    /// Event counter compared with a threshold.
    Counter {
        /// Adds one.
        up: String,
        /// Removes one (not below zero).
        down: String,
        /// Forces the count to zero.
        #[serde(default)]
        clear: Option<String>,
        /// The observer is true while the count is at least this.
        at_least: u32,
    },
}

impl Rule {
    /// Its expressions as written: set and reset, or up, down and clear.
    pub fn expressions(&self) -> Vec<&str> {
        match self {
            Self::Memory { set, reset } => vec![set, reset],
            Self::Counter {
                up, down, clear, ..
            } => {
                let mut v = vec![up.as_str(), down.as_str()];
                v.extend(clear.as_deref());
                v
            }
        }
    }
}

/// One observer as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserverDef {
    /// Identifier (`P36`).
    pub id: String,
    /// What it means.
    #[serde(default)]
    pub description: String,
    /// How it evolves.
    pub rule: Rule,
    /// At the operator's re-initialisation (after a check of the plant), the observer
    /// is cleared when this holds over the sensors as read: what the sensors then show
    /// leaves no room for the item it believes in (a box under C3 or at C6 fills the
    /// zone between them, shorter than any box). Otherwise it keeps its value: an item
    /// no sensor sees stays protected. Reads what a rule reads (inputs, previous
    /// outputs, auxiliaries).
    #[serde(default)]
    pub empty_when: Option<String>,
}

/// The observers file.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserversFile {
    /// Observers in evaluation order.
    pub observers: Vec<ObserverDef>,
}

#[derive(Clone, Debug)]
enum Compiled {
    Memory {
        set: Dnf,
        reset: Dnf,
    },
    Counter {
        up: Dnf,
        down: Dnf,
        clear: Dnf,
        at_least: u32,
    },
}

/// Runtime state of the observers.
#[derive(Clone, Debug)]
pub struct Observers {
    /// Definitions, in index order.
    pub defs: Vec<ObserverDef>,
    compiled: Vec<Compiled>,
    /// `empty_when`, compiled (None: kept at a re-initialisation).
    empty: Vec<Option<Dnf>>,
    counts: Vec<u32>,
}

/// Counters saturate here, so a stuck sensor cannot overflow them.
const COUNTER_MAX: u32 = 1_000;

impl Observers {
    /// No observers.
    pub fn empty() -> Self {
        Self {
            defs: Vec::new(),
            compiled: Vec::new(),
            empty: Vec::new(),
            counts: Vec::new(),
        }
    }

    /// Parses `observers.ron` text and declares every observer in `symbols`.
    /// Observer expressions may read inputs, previous outputs and auxiliaries.
    pub fn from_ron(text: &str, file: &Path, symbols: &mut Symbols) -> (Self, Vec<Problem>) {
        let parsed: ObserversFile = match ron::from_str(text) {
            Ok(p) => p,
            Err(e) => return (Self::empty(), vec![ron_problem(file, &e)]),
        };
        Self::from_defs(parsed.observers, file, symbols)
    }

    /// Loads `observers.ron` from disk; a missing file means no observers.
    pub fn load(path: &Path, symbols: &mut Symbols) -> (Self, Vec<Problem>) {
        match crate::diag::read_text_optional(path) {
            Ok(Some(text)) => Self::from_ron(&text, path, symbols),
            Ok(None) => (Self::empty(), Vec::new()),
            Err(p) => (Self::empty(), vec![Problem::error(p.code, p.message, None)]),
        }
    }

    /// Compiles definitions; bad ones are reported and skipped.
    pub fn from_defs(
        defs: Vec<ObserverDef>,
        file: &Path,
        symbols: &mut Symbols,
    ) -> (Self, Vec<Problem>) {
        let mut problems = Vec::new();
        let mut kept = Vec::new();
        let mut compiled = Vec::new();
        let mut empties = Vec::new();
        // Expressions are resolved before any observer is declared: observers read
        // inputs, not each other.
        let resolve = |what: &str, id: &str, text: &str, problems: &mut Vec<Problem>| {
            resolve_expr(symbols, file, what, id, text, problems)
        };
        for def in defs {
            let c = match &def.rule {
                Rule::Memory { set, reset } => {
                    match (
                        resolve("set", &def.id, set, &mut problems),
                        resolve("reset", &def.id, reset, &mut problems),
                    ) {
                        (Some(set), Some(reset)) => Some(Compiled::Memory { set, reset }),
                        _ => None,
                    }
                }
                Rule::Counter {
                    up,
                    down,
                    clear,
                    at_least,
                } => {
                    let clear = match clear {
                        Some(text) => resolve("clear", &def.id, text, &mut problems),
                        None => Some(Vec::new()),
                    };
                    match (
                        resolve("up", &def.id, up, &mut problems),
                        resolve("down", &def.id, down, &mut problems),
                        clear,
                    ) {
                        (Some(up), Some(down), Some(clear)) => Some(Compiled::Counter {
                            up,
                            down,
                            clear,
                            at_least: *at_least,
                        }),
                        _ => None,
                    }
                }
            };
            let Some(c) = c else { continue };
            let empty = match &def.empty_when {
                Some(text) => match resolve("empty_when", &def.id, text, &mut problems) {
                    Some(d) => Some(d),
                    None => continue,
                },
                None => None,
            };
            if !crate::plant::is_valid_name(&def.id) {
                problems.push(Problem::error(
                    codes::OBSERVER_ID_INVALID.id,
                    format!("observer id `{}` must be letters, digits and `_`", def.id),
                    Some(Location::new(file, 1, 1)),
                ));
                continue;
            }
            compiled.push(c);
            empties.push(empty);
            kept.push(def);
        }
        let mut defs = Vec::new();
        let mut comp = Vec::new();
        let mut empty = Vec::new();
        for ((def, c), e) in kept.into_iter().zip(compiled).zip(empties) {
            if symbols.declare(&def.id, Space::Observer).is_err() {
                problems.push(Problem::error(
                    codes::OBSERVER_NAME_TAKEN.id,
                    format!("observer `{}` has the name of another signal", def.id),
                    Some(Location::new(file, 1, 1)),
                ));
                continue;
            }
            defs.push(def);
            comp.push(c);
            empty.push(e);
        }
        let n = defs.len();
        (
            Self {
                defs,
                compiled: comp,
                empty,
                counts: vec![0; n],
            },
            problems,
        )
    }

    /// Number of observers.
    pub fn len(&self) -> usize {
        self.defs.len()
    }

    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.defs.is_empty()
    }

    /// Updates every observer from the inputs of `frame` and writes their values at t
    /// into `frame.now[Observer]`.
    pub fn update(&mut self, frame: &mut Frame) {
        for (i, c) in self.compiled.iter().enumerate() {
            let count = &mut self.counts[i];
            let value = match c {
                Compiled::Memory { set, reset } => {
                    let was = *count > 0;
                    let now = if expr::eval_dnf(set, frame) {
                        true
                    } else if expr::eval_dnf(reset, frame) {
                        false
                    } else {
                        was
                    };
                    *count = u32::from(now);
                    now
                }
                Compiled::Counter {
                    up,
                    down,
                    clear,
                    at_least,
                } => {
                    if expr::eval_dnf(clear, frame) {
                        *count = 0;
                    } else {
                        if expr::eval_dnf(up, frame) {
                            *count = (*count + 1).min(COUNTER_MAX);
                        }
                        if expr::eval_dnf(down, frame) {
                            *count = count.saturating_sub(1);
                        }
                    }
                    *count >= *at_least
                }
            };
            frame.now_mut(Space::Observer).set(i, value);
        }
    }

    /// The operator's re-initialisation: clears every observer when the plant was
    /// `emptied`, otherwise those whose `empty_when` holds over `frame` (the sensors as
    /// read; the others keep their value). Returns the indices of those that were set.
    pub fn clear_at_reinit(&mut self, frame: &Frame, emptied: bool) -> Vec<usize> {
        let mut cleared = Vec::new();
        for (i, (count, e)) in self.counts.iter_mut().zip(&self.empty).enumerate() {
            let clear = emptied || e.as_ref().is_some_and(|d| expr::eval_dnf(d, frame));
            if clear && *count > 0 {
                *count = 0;
                cleared.push(i);
            }
        }
        cleared
    }

    /// Internal state (memory bit or count) of each observer, for the history and the
    /// explanations.
    pub fn counts(&self) -> &[u32] {
        &self.counts
    }

    /// Restores internal state, e.g. when initialising from a recorded cycle.
    pub fn set_counts(&mut self, counts: &[u32]) {
        for (c, v) in self.counts.iter_mut().zip(counts) {
            *c = *v;
        }
    }
}

/// Parses one observer expression to a simplified DNF, rejecting forbidden reads.
fn resolve_expr(
    symbols: &Symbols,
    file: &Path,
    what: &str,
    id: &str,
    text: &str,
    problems: &mut Vec<Problem>,
) -> Option<Dnf> {
    let dnf = expr::parse_str(text).and_then(|e| e.to_dnf(symbols));
    match dnf {
        Ok(d) => {
            if d.iter().flatten().any(|l| {
                (l.var.space == Space::Output && !l.var.prev) || l.var.space == Space::Observer
            }) {
                problems.push(Problem::error(
                        codes::OBSERVER_READS_FORBIDDEN.id,
                        format!("observer `{id}`: `{what}` may read inputs, previous outputs and auxiliaries only"),
                        Some(Location::new(file, 1, 1)),
                    ));
                None
            } else {
                Some(expr::simplify(&d))
            }
        }
        Err(e) => {
            problems.push(Problem::error(
                codes::OBSERVER_EXPRESSION_INVALID.id,
                format!(
                    "observer `{id}`: `{what}`: {} (column {})",
                    e.message, e.span.column
                ),
                Some(Location::new(file, 1, 1)),
            ));
            None
        }
    }
}

#[cfg(test)]
mod tests;
