//! The per-action monitor of seed 003 (part II ch. III): run once per PLC cycle, it
//! validates each elementary action when V = C·E^I holds and then checks
//!
//! - (a) the final state is not reached before T_MIN = T − ΔT (`Early`);
//! - (b)/(c) the final state is reached by T_MAX = T + ΔT (`Completed`), else `Late`;
//! - (d) no final state appears without a validated action having it (`Unexpected`).
//!
//! It is organised as Structure 2 (Fig. III.8, III.10): a table of the distinct
//! controlled states (every initial and final state expression, evaluated once per
//! cycle) and, per initial state, the actions possible from it; only actions from
//! occupied states are validated, and the final states of all actions, validated or
//! not, are watched for check (d).
//!
//! Decisions (the thesis leaves them to the implementation):
//!
//! - **Which outputs validate.** V = C·E^I reads the inputs of this cycle and the
//!   outputs computed this cycle, `frame.now(Space::Output)`: they are what the PLC
//!   applies at the end of the cycle, so they drive the plant during the coming
//!   period (Fig. III.6: outputs applied only after the acquisition). A validation seen
//!   at the cycle of time t0 starts the timing at t0.
//! - **Validation is on the rising edge of V.** An action is validated at a cycle where
//!   V holds and did not hold at the previous cycle; so an action that faulted while V
//!   stays true (a blocked actuator still commanded) is reported once, not once per
//!   T_MAX. Before the first cycle (and after [`ActionMonitor::reset`]) V counts as
//!   false: an action commanded at the first cycle is timed from that cycle.
//! - **Completion and faults.** While running, a final state present at elapsed time e
//!   gives `Early` if e < T_MIN, `Completed` if e ≤ T_MAX, `Late` beyond; a final state
//!   still absent at the first cycle with e ≥ T_MAX gives `Late`. A final state already
//!   present at validation (a sensor stuck at its active value) gives `Early` at t0.
//!   Every event ends the run; an action found late without its final state stays
//!   *overdue* until its final state appears or its command drops, so that a late
//!   arrival is not reported a second time as an unexpected final state.
//! - **Abandon.** A running action whose command drops before its final state appears
//!   and before T_MAX was stopped by the PLC: it is abandoned silently, not faulted.
//!   The final state is checked first (a PLC usually drops the command in the very
//!   cycle it reads the final state), and late takes precedence over abandon (the plant
//!   was commanded through the whole window).
//! - **Check (d)** fires on the rising edge of a final state expression when no action
//!   having it was running at the start of the cycle or validated in it; one
//!   `Unexpected` event per action having that final state (each names its own command
//!   in its localisation). After a completion the final state stays true: being an
//!   edge check, (d) does not report it again. The first cycle only records the states
//!   (Structure 2's initialisation of the occupied states), so it has no edge.
//! - Events of one cycle are sorted by action id, then kind.

use super::actions::{ElementaryAction, check_actions};
use crate::diag::{Problem, codes};
use crate::expr::{Dnf, eval_dnf, parse_str, simplify};
use crate::frame::Frame;
use crate::symbols::Symbols;
use crate::time::Millis;
use serde::Serialize;
use std::collections::BTreeMap;

/// An action compiled for the monitor.
#[derive(Clone, Debug)]
struct Compiled {
    id: String,
    component: String,
    /// Index of E^I in the state table.
    initial: usize,
    /// Index of E^f in the state table.
    final_state: usize,
    /// C over the outputs at t.
    command: Dnf,
    t_min: u64,
    t_max: u64,
}

/// The per-action monitor (checks a-d of seed 003, III.1) over a set of elementary
/// actions, one [`ActionMonitor::cycle`] call per PLC cycle.
#[derive(Clone, Debug)]
pub struct ActionMonitor {
    /// Actions sorted by id.
    actions: Vec<Compiled>,
    /// Structure 2's controlled-state table: the distinct state expressions.
    states: Vec<Dnf>,
    /// Per state, the actions possible from it (their initial state).
    from_state: Vec<Vec<usize>>,
    /// Per state, the actions ending in it (their final state).
    to_state: Vec<Vec<usize>>,
    /// Values of the states at the previous cycle, `None` before the first cycle.
    states_prev: Option<Vec<bool>>,
    /// V of each action at the previous cycle.
    valid_prev: Vec<bool>,
    /// What each action is doing.
    runs: Vec<Run>,
}

/// The run of one action.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Run {
    /// Not validated.
    Idle,
    /// Validated at this time, timed.
    Running(Millis),
    /// Reported late without its final state: still expected (its final state's arrival
    /// is not check (d)'s), no longer timed.
    Overdue,
}

/// What the monitor found about an action at a cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum ActionEventKind {
    /// The final state was reached within [T_MIN, T_MAX]: normal completion.
    Completed,
    /// Check (a): the final state was reached before T_MIN (or was already there at
    /// validation).
    Early,
    /// Checks (b)/(c): the final state was not reached by T_MAX (or reached after).
    Late,
    /// Check (d): the final state rose with no validated action having that final
    /// state.
    Unexpected,
}

impl ActionEventKind {
    /// Short lowercase name for messages and reports.
    pub fn as_str(self) -> &'static str {
        match self {
            ActionEventKind::Completed => "completed",
            ActionEventKind::Early => "early",
            ActionEventKind::Late => "late",
            ActionEventKind::Unexpected => "unexpected final state",
        }
    }
}

/// One finding of the monitor, at the cycle it was made.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ActionEvent {
    /// The cycle's time.
    pub time: Millis,
    /// The action's id.
    pub action: String,
    /// The action's component.
    pub component: String,
    /// What happened.
    pub kind: ActionEventKind,
    /// When the action was validated (t0); `None` for `Unexpected`.
    pub started: Option<Millis>,
    /// Time since validation at this cycle, ms; `None` for `Unexpected`.
    pub elapsed_ms: Option<u64>,
    /// The final state holds at this cycle (a `Late` is either a final state reached
    /// after T_MAX, or none by T_MAX).
    pub reached: bool,
}

impl ActionEvent {
    /// True for a detection (every kind but `Completed`): the thesis then runs the
    /// emergency procedure, raises an alarm and emits [`ActionEvent::localisation`].
    pub fn is_fault(&self) -> bool {
        self.kind != ActionEventKind::Completed
    }

    /// The localisation message (C2, Fig. III.3 and III.2's actuator and link rules),
    /// naming the action's signals: `action` is the elementary action the event names.
    pub fn localisation(&self, action: &ElementaryAction) -> String {
        let head = format!(
            "{} ({}): final state `{}`",
            action.id, action.component, action.final_state
        );
        let sensors = sensor_names(&action.final_state);
        let command = &action.command;
        let elapsed = self.elapsed_ms.unwrap_or(0);
        match self.kind {
            ActionEventKind::Completed => format!(
                "{head} reached after {elapsed} ms, within [{}, {}] ms",
                action.t_min_ms(),
                action.t_max_ms()
            ),
            ActionEventKind::Early => format!(
                "{head} reached after {elapsed} ms, before T_MIN = {} ms: {sensors} stuck at its active value, or actuator overspeed under `{command}`",
                action.t_min_ms()
            ),
            ActionEventKind::Late => {
                let when = if self.reached {
                    format!(
                        "reached only after {elapsed} ms, past T_MAX = {} ms",
                        action.t_max_ms()
                    )
                } else {
                    format!(
                        "not reached after {elapsed} ms (T_MAX = {} ms)",
                        action.t_max_ms()
                    )
                };
                format!(
                    "{head} {when} under `{command}`: {sensors} stuck inactive, actuator blocked or slow, or the link PLC->actuator of `{command}` broken"
                )
            }
            ActionEventKind::Unexpected => format!(
                "{head} appeared with no validated action: {sensors} stuck active, or actuator moving without order `{command}` (output link stuck at 1)"
            ),
        }
    }
}

/// "sensor b2" or "sensors b1, b2": the names an expression reads.
fn sensor_names(expression: &str) -> String {
    let names: Vec<String> = parse_str(expression).map_or_else(
        |_| vec![expression.to_string()],
        |e| {
            let mut v: Vec<String> = Vec::new();
            for (name, _, _) in e.leaves() {
                if !v.iter().any(|n| n == name) {
                    v.push(name.to_string());
                }
            }
            v
        },
    );
    match names.as_slice() {
        [one] => format!("sensor {one}"),
        _ => format!("sensors {}", names.join(", ")),
    }
}

impl ActionMonitor {
    /// Compiles the actions against the plant's name table: every expression resolved
    /// ([`check_actions`]: ids, duplicates, timing, names, spaces), equal state
    /// expressions shared in the controlled-state table.
    pub fn new(actions: &[ElementaryAction], symbols: &Symbols) -> Result<Self, Vec<Problem>> {
        let problems: Vec<Problem> = check_actions(actions, symbols, None)
            .into_iter()
            .filter(Problem::is_error)
            .collect();
        if !problems.is_empty() {
            return Err(problems);
        }
        let mut sorted: Vec<&ElementaryAction> = actions.iter().collect();
        sorted.sort_by(|a, b| a.id.cmp(&b.id));
        let mut table: BTreeMap<Dnf, usize> = BTreeMap::new();
        let mut states: Vec<Dnf> = Vec::new();
        let mut problems = Vec::new();
        let mut compiled = Vec::new();
        for a in sorted {
            let mut state = |text: &str| -> Option<usize> {
                let dnf = simplify(&compile(&a.id, text, symbols, &mut problems)?);
                Some(*table.entry(dnf.clone()).or_insert_with(|| {
                    states.push(dnf);
                    states.len() - 1
                }))
            };
            let (Some(initial), Some(final_state)) = (state(&a.initial), state(&a.final_state))
            else {
                continue;
            };
            let Some(command) = compile(&a.id, &a.command, symbols, &mut problems) else {
                continue;
            };
            compiled.push(Compiled {
                id: a.id.clone(),
                component: a.component.clone(),
                initial,
                final_state,
                command,
                t_min: a.t_min_ms(),
                t_max: a.t_max_ms(),
            });
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        let mut from_state = vec![Vec::new(); states.len()];
        let mut to_state = vec![Vec::new(); states.len()];
        for (i, a) in compiled.iter().enumerate() {
            from_state[a.initial].push(i);
            to_state[a.final_state].push(i);
        }
        let n = compiled.len();
        Ok(Self {
            actions: compiled,
            states,
            from_state,
            to_state,
            states_prev: None,
            valid_prev: vec![false; n],
            runs: vec![Run::Idle; n],
        })
    }

    /// One PLC cycle: `now` the cycle's time, `frame` the cycle's frame (inputs read
    /// this cycle, outputs computed this cycle in `now(Space::Output)`, which validate:
    /// see the module's decisions). Returns the cycle's events sorted by action id.
    pub fn cycle(&mut self, now: Millis, frame: &Frame) -> Vec<ActionEvent> {
        let occupied: Vec<bool> = self.states.iter().map(|d| eval_dnf(d, frame)).collect();
        let rose: Vec<bool> = match &self.states_prev {
            Some(prev) => occupied.iter().zip(prev).map(|(&n, &p)| n && !p).collect(),
            None => vec![false; occupied.len()],
        };
        let mut events = Vec::new();
        // States some action was expected to reach this cycle (for check (d)).
        let mut expected = vec![false; self.states.len()];
        let was_running: Vec<bool> = self.runs.iter().map(|r| *r != Run::Idle).collect();
        self.check_running(now, frame, &occupied, &mut expected, &mut events);
        // Validation, Structure 2: only actions possible from occupied states.
        let mut valid = vec![false; self.actions.len()];
        for (s, list) in self.from_state.iter().enumerate() {
            if occupied[s] {
                for &i in list {
                    valid[i] = eval_dnf(&self.actions[i].command, frame);
                }
            }
        }
        for (i, a) in self.actions.iter().enumerate() {
            if !valid[i] || self.valid_prev[i] || was_running[i] {
                continue;
            }
            expected[a.final_state] = true;
            if occupied[a.final_state] {
                // Check (a) at t0: the final state is already there.
                events.push(event(a, now, ActionEventKind::Early, Some(now)));
            } else {
                self.runs[i] = Run::Running(now);
            }
        }
        // Check (d): a final state rose that no action was expected to reach.
        for (s, list) in self.to_state.iter().enumerate() {
            if rose[s] && !expected[s] {
                for &i in list {
                    events.push(event(
                        &self.actions[i],
                        now,
                        ActionEventKind::Unexpected,
                        None,
                    ));
                }
            }
        }
        self.valid_prev = valid;
        self.states_prev = Some(occupied);
        events.sort_by(|x, y| (&x.action, x.kind).cmp(&(&y.action, y.kind)));
        events
    }

    /// Checks (a)-(c) and the abandon rule for the actions running at the cycle's start.
    fn check_running(
        &mut self,
        now: Millis,
        frame: &Frame,
        occupied: &[bool],
        expected: &mut [bool],
        events: &mut Vec<ActionEvent>,
    ) {
        for (i, a) in self.actions.iter().enumerate() {
            let t0 = match self.runs[i] {
                Run::Idle => continue,
                Run::Overdue => {
                    expected[a.final_state] = true;
                    if occupied[a.final_state] || !eval_dnf(&a.command, frame) {
                        self.runs[i] = Run::Idle;
                    }
                    continue;
                }
                Run::Running(t0) => t0,
            };
            expected[a.final_state] = true;
            let elapsed = now.saturating_sub(t0).0;
            let (kind, next) = if occupied[a.final_state] {
                let kind = if elapsed < a.t_min {
                    ActionEventKind::Early
                } else if elapsed <= a.t_max {
                    ActionEventKind::Completed
                } else {
                    ActionEventKind::Late
                };
                (Some(kind), Run::Idle)
            } else if elapsed >= a.t_max {
                (Some(ActionEventKind::Late), Run::Overdue)
            } else if !eval_dnf(&a.command, frame) {
                // Abandoned: the PLC stopped it before its end.
                (None, Run::Idle)
            } else {
                (None, Run::Running(t0))
            };
            if let Some(kind) = kind {
                let mut e = event(a, now, kind, Some(t0));
                e.reached = occupied[a.final_state];
                events.push(e);
            }
            self.runs[i] = next;
        }
    }

    /// The running (validated and timed) actions and their start times, sorted by
    /// action id; an overdue action (already reported late) is not listed.
    pub fn running(&self) -> Vec<(String, Millis)> {
        self.actions
            .iter()
            .zip(&self.runs)
            .filter_map(|(a, r)| match r {
                Run::Running(t0) => Some((a.id.clone(), *t0)),
                _ => None,
            })
            .collect()
    }

    /// Forgets every running action and every previous value: the next cycle is a first
    /// cycle (after the emergency procedure and the repair, the plant restarts at rest).
    pub fn reset(&mut self) {
        self.runs.iter_mut().for_each(|r| *r = Run::Idle);
        self.valid_prev.iter_mut().for_each(|v| *v = false);
        self.states_prev = None;
    }
}

/// An event about action `a` at `now`.
fn event(a: &Compiled, now: Millis, kind: ActionEventKind, started: Option<Millis>) -> ActionEvent {
    ActionEvent {
        time: now,
        action: a.id.clone(),
        component: a.component.clone(),
        kind,
        started,
        elapsed_ms: started.map(|t0| now.saturating_sub(t0).0),
        reached: true,
    }
}

/// Parses and resolves one expression of action `id`, or records why not.
fn compile(id: &str, text: &str, symbols: &Symbols, problems: &mut Vec<Problem>) -> Option<Dnf> {
    match parse_str(text).and_then(|e| e.to_dnf(symbols)) {
        Ok(d) => Some(d),
        Err(e) => {
            problems.push(Problem::error(
                codes::MACHINE_ACTION_EXPRESSION.id,
                format!("action `{id}`: `{text}`: {}", e.message),
                None,
            ));
            None
        }
    }
}

#[cfg(test)]
mod tests;
