//! The elementary-action monitor of the simulation (seed 003, part II, ch. III): the
//! plant's `actions.ron`, or the actions its components allow (rule R1), checked every
//! cycle on the frame the filter leaves (the outputs as applied, the inputs read).
//!
//! A detection (early, late, unexpected final state) raises an alarm with the
//! localisation of Fig. III.3 and a journal entry, and, with the filter enforcing,
//! stops the plant in the fallback from the next cycle (seed 003, III.1: "the monitor
//! runs an emergency procedure that puts the system in a safe state"): a dead position
//! sensor is only seen as an action that does not end, and the only timely reaction
//! is to stop. The stop holds until the operator's Reset, which restarts the program
//! from its initial steps (the mechanism is then brought back by hand). Every event,
//! completions included, is kept for the run's report, so that a campaign can compare
//! the sequence of actions with the plant's expected cycle.

use super::{Simulation, fields};
use crate::alarms::{AlarmKind, AlarmText};
use crate::diag::Problem;
use crate::machine::actions::{ElementaryAction, check_actions, load_actions, timing_check};
use crate::machine::monitor::{ActionEvent, ActionMonitor};
use crate::time::Millis;

/// The file of a plant folder that declares its elementary actions.
pub const ACTIONS_FILE: &str = "actions.ron";

/// The monitor, its actions and what it found.
#[derive(Clone, Debug)]
pub struct ActionMonitoring {
    /// The actions watched.
    pub actions: Vec<ElementaryAction>,
    /// The running monitor.
    pub monitor: ActionMonitor,
    /// Every event so far, completions included, in time order.
    pub events: Vec<ActionEvent>,
    /// Where the actions come from: `actions.ron`, or `components` (derived).
    pub source: &'static str,
    /// The timing check against the PLC cycle is done (at the first cycle, when the
    /// scenario has set the cycle).
    timing_checked: bool,
}

/// The actions of a plant folder: `actions.ron` when there is one (checked against the
/// plant), else those the components allow; `None` for a plant without either (a
/// sorting layout).
pub fn plant_actions(
    sim: &Simulation,
) -> Result<Option<(Vec<ElementaryAction>, &'static str)>, Vec<Problem>> {
    let path = sim.bundle.dir.join(ACTIONS_FILE);
    if path.exists() {
        let actions = load_actions(&path)?;
        let text = crate::diag::read_text(&path).map_err(|p| vec![p])?;
        let problems = check_actions(&actions, &sim.engine.symbols, Some((&path, &text)));
        if problems.iter().any(Problem::is_error) {
            return Err(problems);
        }
        return Ok(Some((actions, "actions.ron")));
    }
    let Some(c) = sim.emulator.as_components() else {
        return Ok(None);
    };
    let actions: Vec<ElementaryAction> = c
        .derived_actions()
        .into_iter()
        .map(|d| ElementaryAction {
            id: d.id,
            component: d.component,
            initial: d.initial,
            command: d.command,
            final_state: d.final_state,
            t_ms: d.t_ms,
            dt_ms: d.dt_ms,
        })
        .collect();
    Ok((!actions.is_empty()).then_some((actions, "components")))
}

/// Compares the declared actions with those the components allow: a declared action
/// no component performs, or whose window does not contain the allowed one, is a
/// warning (V0746) located at its id in `file`.
pub fn compare_with_components(
    declared: &[ElementaryAction],
    derived: &[crate::machine::derive::DerivedAction],
    file: &std::path::Path,
    text: &str,
) -> Vec<Problem> {
    let mut out = Vec::new();
    for a in declared {
        let at = Some(crate::diag::Location::of_nth(
            file,
            text,
            &format!("\"{}\"", a.id),
            0,
        ));
        let what = format!(
            "`{}` ({} -> {} under {})",
            a.id, a.initial, a.final_state, a.command
        );
        let Some(d) = derived.iter().find(|d| {
            d.initial == a.initial.trim()
                && d.command == a.command.trim()
                && d.final_state == a.final_state.trim()
        }) else {
            out.push(Problem::warning(
                crate::diag::codes::ACTION_NOT_ALLOWED.id,
                format!("action {what}: no component performs it"),
                at,
            ));
            continue;
        };
        let (lo, hi) = (d.t_ms.saturating_sub(d.dt_ms), d.t_ms + d.dt_ms);
        if a.t_min_ms() > lo || a.t_max_ms() < hi {
            out.push(Problem::warning(
                crate::diag::codes::ACTION_NOT_ALLOWED.id,
                format!(
                    "action {what}: its window [{}, {}] ms does not contain [{lo}, {hi}] ms, \
                     what the components allow",
                    a.t_min_ms(),
                    a.t_max_ms()
                ),
                at,
            ));
        }
    }
    out
}

impl Simulation {
    /// Starts the elementary-action monitor on the plant's actions (see
    /// [`plant_actions`]); at its first cycle, the timing check (T_D < ΔT_min, (II.4))
    /// goes to the journal. Returns false when the plant has no actions to watch.
    pub fn enable_action_monitor(&mut self) -> Result<bool, Vec<Problem>> {
        let Some((actions, source)) = plant_actions(self)? else {
            return Ok(false);
        };
        let monitor = ActionMonitor::new(&actions, &self.engine.symbols)?;
        self.action_monitor = Some(ActionMonitoring {
            actions,
            monitor,
            events: Vec::new(),
            source,
            timing_checked: false,
        });
        Ok(true)
    }

    /// One cycle of the action monitor, after the filter.
    pub(super) fn step_actions(&mut self, now: Millis) {
        let Some(m) = self.action_monitor.as_mut() else {
            return;
        };
        if !m.timing_checked {
            m.timing_checked = true;
            let issues = timing_check(&m.actions, self.cycle.0);
            for issue in issues {
                self.log("actions", format!("timing check: {}", issue.message));
            }
            return self.step_actions(now);
        }
        let events = m.monitor.cycle(now, self.engine.frame());
        let mut found = Vec::new();
        for e in events {
            if e.is_fault()
                && let Some(a) = m.actions.iter().find(|a| a.id == e.action)
            {
                found.push((e.clone(), a.clone()));
            }
            m.events.push(e);
        }
        let stops = self.engine.mode() == crate::engine::FilterMode::Enforce && !self.is_live();
        for (e, a) in found {
            let text = action_alarm(&e, &a);
            let key = format!("action:{}:{}", e.action, e.kind.as_str());
            self.alarms
                .raise(now, &key, AlarmKind::Diagnosis, text.clone());
            self.log_coded(
                "actions",
                text.detail.clone(),
                "alarm-action",
                text.fields.clone(),
            );
            if stops && self.action_stop.is_none() {
                self.engine.set_hold(true);
                self.action_stop = Some(text.message.clone());
                self.log(
                    "action_stop",
                    format!(
                        "the action monitor stopped the plant in its fallback: {}; repair, \
                         then Reset (the program restarts from its initial steps)",
                        text.message
                    ),
                );
            }
        }
    }

    /// The operator's Reset of the action monitor's stop: the filter's own trip is
    /// reset too when there is one (refused while the constraints still forbid the
    /// commands), the program restarts from its initial steps and the monitor forgets
    /// its running actions.
    pub(super) fn reset_action_stop(&mut self) -> Result<(), String> {
        if self.engine.is_tripped() {
            self.engine.reset().map_err(|e| e.to_string())?;
        }
        self.action_stop = None;
        self.engine.set_hold(false);
        self.restart_program(self.program.program().clone());
        if let Some(m) = self.action_monitor.as_mut() {
            m.monitor.reset();
        }
        self.log(
            "action_stop",
            "operator reset of the action monitor's stop: the program restarts from its \
             initial steps"
                .into(),
        );
        Ok(())
    }

    /// Why the action monitor holds the plant stopped, if it does.
    pub fn action_stop(&self) -> Option<&str> {
        self.action_stop.as_deref()
    }

    /// The plant's production so far: the items out of a plant's conveyors (into a
    /// sink, or taken at an exit end), the elementary actions completed on a plant
    /// without items (what the campaigns count to tell that production runs again after
    /// a fault).
    pub fn produced(&self) -> u64 {
        match &self.emulator {
            crate::machine::Physical::Components(c) if c.carries_items() => {
                u64::from(c.items_out())
            }
            crate::machine::Physical::Components(_) => self
                .action_events()
                .iter()
                .filter(|e| e.kind == crate::machine::monitor::ActionEventKind::Completed)
                .count() as u64,
        }
    }

    /// The monitor's events so far (none without a monitor).
    pub fn action_events(&self) -> &[ActionEvent] {
        self.action_monitor
            .as_ref()
            .map_or(&[][..], |m| m.events.as_slice())
    }
}

/// The alarm of a detection: the action, what went wrong, and the localisation.
fn action_alarm(e: &ActionEvent, a: &ElementaryAction) -> AlarmText {
    AlarmText {
        message: format!(
            "Action {} ({} -> {} under {}): {}",
            a.id,
            a.initial,
            a.final_state,
            a.command,
            e.kind.as_str()
        ),
        detail: e.localisation(a),
        ..AlarmText::default()
    }
    .with(
        "action",
        fields([
            ("action", a.id.clone()),
            ("component", a.component.clone()),
            ("initial", a.initial.clone()),
            ("final", a.final_state.clone()),
            ("command", a.command.clone()),
            ("kind", format!("{:?}", e.kind).to_lowercase()),
            ("elapsed_ms", e.elapsed_ms.unwrap_or(0).to_string()),
            ("t_min_ms", a.t_min_ms().to_string()),
            ("t_max_ms", a.t_max_ms().to_string()),
        ]),
    )
}
