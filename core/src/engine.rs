//! One PLC cycle, one function: inputs → observers → control → filter → outputs →
//! recorder (the diagnosers slot in after the filter, see `ARCHITECTURE.md`).

use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::constraints::Class;
use crate::filter::{Filter, FilterState, SpecError};
use crate::frame::Frame;
use crate::history::History;
use crate::observers::Observers;
use crate::symbols::{Space, Symbols};
use crate::time::Millis;
use serde::Serialize;

/// The control program seen from the engine: it reads the frame (inputs at t, at t-1,
/// observers) and writes the outputs it commands.
pub trait Control {
    /// One scan of the program at time `now`.
    fn scan(&mut self, now: Millis, frame: &Frame, outputs: &mut Bits);
}

/// A control whose outputs come from outside (a live PLC, a recorded trace).
#[derive(Clone, Debug, Default)]
pub struct Commanded(pub Bits);

impl Control for Commanded {
    fn scan(&mut self, _now: Millis, _frame: &Frame, outputs: &mut Bits) {
        outputs.copy_from(&self.0);
    }
}

/// What the filter does with a violation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub enum FilterMode {
    /// Trip, latch and apply the fallback (the paper's filter).
    Enforce,
    /// Record violations, never change the outputs (monitor mode on a live PLC).
    ReportOnly,
    /// No filter (to show what the plant does without it).
    Off,
}

/// The filter's action on one output during a trip.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Action {
    /// Commanded OFF, held ON by the filter.
    ForcedOn,
    /// Commanded ON, forced OFF by the filter.
    ForcedOff,
    /// Left as commanded.
    Unchanged,
}

/// One output in a trip record.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct OutputAction {
    /// Actuator id.
    pub output: String,
    /// What the control program commanded.
    pub commanded: bool,
    /// What the filter applied.
    pub applied: bool,
    /// The filter's action.
    pub action: Action,
}

/// One literal of a fired constraint with its value in the tripping cycle.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct LiteralValue {
    /// The literal in file notation (`/A4`, `A4*`).
    pub literal: String,
    /// Signal, observer or auxiliary name.
    pub name: String,
    /// Space of the variable.
    pub space: Space,
    /// True for the value at t-1.
    pub previous: bool,
    /// The variable's value.
    pub value: bool,
}

/// One constraint that fired.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct FiredConstraint {
    /// Constraint id.
    pub id: String,
    /// Simple or combined.
    pub class: Class,
    /// The constraint as written.
    pub notation: String,
    /// Literals of the product term that was true.
    pub literals: Vec<LiteralValue>,
}

/// A filter trip (or, in report-only mode, a reported violation).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct Trip {
    /// Time of the cycle.
    pub time_ms: u64,
    /// Cycle number since the start of the run.
    pub cycle: u64,
    /// Constraints that were true with the commanded outputs.
    pub constraints: Vec<FiredConstraint>,
    /// The filter's action on each output.
    pub actions: Vec<OutputAction>,
    /// The fallback vector (`A0=0 A1=0 …`), or everything 0 on a specification error.
    pub fallback: Vec<(String, bool)>,
    /// Set when no output vector satisfies every constraint.
    pub spec_error: Option<String>,
    /// True when the outputs were actually changed (enforce mode).
    pub enforced: bool,
}

/// Events of a cycle, for alarms and journals.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// A trip latched; index into [`Engine::trips`].
    Trip {
        /// Index of the trip.
        index: usize,
    },
    /// A violation was reported without acting (report-only mode).
    Violation {
        /// Index of the record in [`Engine::trips`].
        index: usize,
    },
    /// No fallback exists: every output was driven to 0.
    SpecificationError {
        /// The message.
        message: String,
    },
    /// The operator reset the latched trip.
    Reset,
}

/// What the engine takes as the values at t-1 in its first cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
pub enum FirstCycle {
    /// A cold start, as a PLC's first scan: every previous value is the signal's
    /// initial value (`initial` in `plant.ron`, 0 by default). The plant starts at rest.
    #[default]
    Cold,
    /// An attach to a running plant (a live link, a trace recorded mid-production): the
    /// previous values are the first observation, so the first cycle shows no edge.
    Attach,
}

/// Why a reset was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ResetRefused {
    /// Nothing to reset.
    #[error("the filter has not tripped")]
    NotTripped,
    /// Constraints would be violated again by the current commands.
    #[error("reset refused: {} still violated by the commanded outputs{}", constraints.join(", "), observers_hint(observers))]
    StillViolated {
        /// Ids of the constraints.
        constraints: Vec<String>,
        /// The observers at 1 in the violated terms, in index order (a box an observer
        /// still believes in after a transient shows here).
        observers: Vec<String>,
    },
}

fn observers_hint(observers: &[String]) -> String {
    if observers.is_empty() {
        String::new()
    } else {
        format!(" (with {} = 1)", observers.join(" = 1, "))
    }
}

/// The engine of one plant run: observers, filter and recorder around a control program.
pub struct Engine {
    /// Names of all variables.
    pub symbols: Symbols,
    /// Observers and their state.
    pub observers: Observers,
    /// The sensors' timed plausibility (the first stage of a cycle).
    pub plausibility: crate::plausibility::Plausibility,
    /// The plausibility stage runs (on by default).
    plausibility_on: bool,
    /// Outputs the safety function keeps ON whatever the control program
    /// (`held_on` in `plant.ron`: a safety contactor): only the fallback takes them off.
    held_on: Vec<usize>,
    /// Mirror contacts (`feedback_of`): (input, output). At an attach to a running
    /// plant, the output's previous value is what its mirror shows, not the command.
    mirrors: Vec<(usize, usize)>,
    /// Per entry of `mirrors`: how long a disagreement is read as agreement
    /// (`feedback_ms`), and since when the mirror has disagreed with its output.
    mirror_ms: Vec<(u64, Option<Millis>)>,
    /// Supplied drives: (drive, its supply) for each `supplies` of a safety contactor.
    /// The diagnosers read a drive as commanded only while its supply is ON.
    supplied: Vec<(usize, usize)>,
    /// Sensors the diagnosers estimate: (input, flag auxiliary, estimate auxiliary).
    estimates: Vec<(usize, usize, usize)>,
    /// Per entry of `estimates`: read from the estimate in the previous cycle.
    estimated: Vec<bool>,
    filter: Filter,
    filter_state: FilterState,
    /// The constraint set as loaded, kept to rebuild the filter without the bypassed
    /// constraints.
    constraints: crate::constraints::ConstraintSet,
    /// Constraints the filter does not enforce (a time-limited bypass, seed 004 section
    /// 7); their ids stay in place (a bypassed constraint has no term).
    bypassed: std::collections::BTreeSet<String>,
    notation: Vec<String>,
    mode: FilterMode,
    frame: Frame,
    commanded: Bits,
    scratch: Vec<usize>,
    previous_violations: Vec<usize>,
    latched: bool,
    hold: bool,
    /// The next cycle takes its observation as the previous values (an attach).
    attach_pending: bool,
    /// The next cycle takes the sensors as read and clears the observers (the
    /// operator's re-initialisation): `Some(true)` every observer (the plant emptied),
    /// `Some(false)` those whose `empty_when` holds.
    reinit_pending: Option<bool>,
    /// The observers the last re-initialisation cleared.
    pub reinit_cleared: Vec<String>,
    /// Per output, what the plant does when it is OFF (`off` in `plant.ron`).
    off_meanings: Vec<Option<String>>,
    /// The specification error reported last, while it lasts (reported once, not every cycle).
    spec_error: Option<String>,
    cycles: u64,
    now: Millis,
    /// Every trip and reported violation of the run, in order.
    pub trips: Vec<Trip>,
    /// Events not yet taken by [`Engine::drain_events`].
    events: Vec<Event>,
    /// The recorder.
    pub history: History,
}

impl Engine {
    /// Builds an engine for a loaded plant folder (a cold start, see [`FirstCycle`]).
    pub fn new(bundle: &PlantBundle, mode: FilterMode, history_cycles: usize) -> Self {
        let n_out = bundle.plant.outputs.len();
        let mirrors = bundle.plant.mirrors();
        let mut frame = Frame::new(bundle.symbols.sizes());
        // The first cycle's shift makes these the values at t-1: the initial values.
        for (space, signals) in [
            (Space::Input, &bundle.plant.inputs),
            (Space::Output, &bundle.plant.outputs),
        ] {
            for (i, sig) in signals.iter().enumerate() {
                frame.now_mut(space).set(i, sig.initial);
            }
        }
        Self {
            symbols: bundle.symbols.clone(),
            observers: bundle.observers.clone(),
            plausibility: bundle.plausibility.clone(),
            plausibility_on: true,
            held_on: (0..n_out)
                .filter(|&k| bundle.plant.outputs[k].held_on)
                .collect(),
            mirror_ms: mirrors
                .iter()
                .map(|&(i, _)| (bundle.plant.inputs[i].feedback_ms, None))
                .collect(),
            mirrors,
            supplied: bundle
                .plant
                .supplies()
                .into_iter()
                .flat_map(|(s, drives)| drives.into_iter().map(move |k| (k, s)))
                .collect(),
            estimates: Vec::new(),
            estimated: Vec::new(),
            filter_state: Filter::new(&bundle.constraints, n_out).new_state(),
            constraints: bundle.constraints.clone(),
            bypassed: std::collections::BTreeSet::new(),
            filter: Filter::for_plant(&bundle.constraints, &bundle.plant),
            notation: bundle
                .constraints
                .constraints
                .iter()
                .map(|c| c.source.clone())
                .collect(),
            mode,
            frame,
            commanded: Bits::zeros(n_out),
            scratch: Vec::new(),
            previous_violations: Vec::new(),
            latched: false,
            hold: false,
            attach_pending: false,
            reinit_pending: None,
            reinit_cleared: Vec::new(),
            off_meanings: bundle.plant.outputs.iter().map(|s| s.off.clone()).collect(),
            spec_error: None,
            cycles: 0,
            now: Millis::ZERO,
            trips: Vec::new(),
            events: Vec::new(),
            history: History::new(history_cycles),
        }
    }

    /// Enforces every constraint but `ids` from the next cycle on (a bypass: each of
    /// them is as if it had no term; the others, the fallback and the trip are
    /// unchanged). An empty set restores the whole set.
    pub fn set_bypassed(&mut self, ids: std::collections::BTreeSet<String>) {
        let mut set = self.constraints.clone();
        for c in &mut set.constraints {
            if ids.contains(&c.id) {
                c.dnf.clear();
            }
        }
        let safe = self.filter.safe_values().to_vec();
        self.filter = Filter::new(&set, self.commanded.len()).with_safe_values(safe);
        self.filter_state = self.filter.new_state();
        self.bypassed = ids;
    }

    /// The constraints bypassed now.
    pub fn bypassed(&self) -> &std::collections::BTreeSet<String> {
        &self.bypassed
    }

    /// The filter mode.
    pub fn mode(&self) -> FilterMode {
        self.mode
    }

    /// Changes the filter mode (an operator or trainer decision, journaled by the caller).
    pub fn set_mode(&mut self, mode: FilterMode) {
        self.mode = mode;
        if mode != FilterMode::Enforce {
            self.latched = false;
        }
    }

    /// The operator's pause: while on, the outputs are the fallback (the safe stop with
    /// priority to zero, no trip recorded); the control program keeps scanning, so the
    /// plant resumes where it stopped when the pause ends. Ignored in report-only mode
    /// (Vigie does not drive the outputs there).
    pub fn set_hold(&mut self, on: bool) {
        self.hold = on;
    }

    /// True while the operator's pause holds the plant.
    pub fn is_held(&self) -> bool {
        self.hold
    }

    /// Chooses the first cycle's previous values (call before the first cycle).
    pub fn set_first_cycle(&mut self, first: FirstCycle) {
        self.attach_pending = first == FirstCycle::Attach;
    }

    /// Attaches at the next cycle: its inputs, observers and commanded outputs are
    /// also taken as the values at t-1 (no edge). A live link calls it when the plant
    /// is first read, its values until then unknown.
    pub fn attach_next_cycle(&mut self) {
        self.attach_pending = true;
    }

    /// The operator's re-initialisation, after a check of the plant: the next cycle
    /// takes the sensors as read (the plausibility stage restarts on the readings: its
    /// holds end, no edge is seen) and clears the observers ([`Engine::reinit_cleared`]):
    /// every one when the operator `emptied` the plant of its items (GEMMA's
    /// preparation for a restart after a failure), otherwise only those whose
    /// `empty_when` then holds (what the sensors show leaves no room for their item; the
    /// others keep their value, an item no sensor sees stays protected). A latched trip
    /// ends (the caller restarts the control program from its initial steps). The
    /// outputs at t-1 stay what was applied, so a constraint on an output's edge (a
    /// release the physics forbids) still holds, and the filter checks the next cycle's
    /// commands as any other. Returns false, and does nothing, when the filter is not
    /// tripped.
    pub fn reinitialise(&mut self, emptied: bool) -> bool {
        if !self.latched {
            return false;
        }
        self.reinit_pending = Some(emptied);
        self.latched = false;
        self.previous_violations.clear();
        self.events.push(Event::Reset);
        true
    }

    /// What the plant does when output `k` is OFF, when `plant.ron` says it (`off`):
    /// "the table returns to the loading position".
    pub fn off_meaning(&self, k: usize) -> Option<&str> {
        self.off_meanings.get(k).and_then(|m| m.as_deref())
    }

    /// True while a trip is latched.
    pub fn is_tripped(&self) -> bool {
        self.latched
    }

    /// True while the filter holds the outputs in its safe state (a latched trip, or
    /// the hold), the stage after the filter sees the filter's orders, not the
    /// controller's.
    pub fn holds_outputs(&self) -> bool {
        (self.latched && self.mode == FilterMode::Enforce)
            || (self.hold && self.mode != FilterMode::ReportOnly)
    }

    /// The compiled filter.
    pub fn filter(&self) -> &Filter {
        &self.filter
    }

    /// Values of the last cycle (at t) and the one before (at t-1).
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Mutable frame, for engines that publish auxiliary variables (diagnosers).
    pub fn frame_mut(&mut self) -> &mut Frame {
        &mut self.frame
    }

    /// The outputs commanded by the control program in the last cycle.
    pub fn commanded(&self) -> &Bits {
        &self.commanded
    }

    /// The outputs applied to the plant in the last cycle.
    pub fn applied(&self) -> &Bits {
        self.frame.now(Space::Output)
    }

    /// Time of the last cycle.
    pub fn now(&self) -> Millis {
        self.now
    }

    /// Number of cycles run.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// Takes the events produced since the last call.
    pub fn drain_events(&mut self) -> Vec<Event> {
        std::mem::take(&mut self.events)
    }

    /// Runs one PLC cycle: reads `inputs`, updates the observers, scans `control`,
    /// filters its outputs and records the cycle. Returns the outputs to apply.
    pub fn cycle(&mut self, now: Millis, inputs: &Bits, control: &mut dyn Control) -> &Bits {
        self.cycle_with(now, inputs, control, &mut |_, _, _| {})
    }

    /// [`Engine::cycle`] with a stage run after the filter and before the recorder (the
    /// diagnosers): it reads the applied outputs and writes auxiliary variables.
    pub fn cycle_with(
        &mut self,
        now: Millis,
        inputs: &Bits,
        control: &mut dyn Control,
        after_filter: &mut dyn FnMut(Millis, &mut Frame, bool),
    ) -> &Bits {
        self.now = now;
        self.cycles += 1;
        let attach = std::mem::take(&mut self.attach_pending);
        let reinit_mode = self.reinit_pending.take();
        let reinit = reinit_mode.is_some();
        self.frame.shift();
        self.frame.now_mut(Space::Input).copy_from(inputs);
        if attach || reinit {
            self.frame.prev_mut(Space::Input).copy_from(inputs);
        }
        if self.plausibility_on {
            self.plausibility
                .step(now, &mut self.frame, attach || reinit || self.cycles == 1);
        }
        self.hold_mirrors(now, attach || reinit);
        self.read_estimates();
        if let Some(emptied) = reinit_mode {
            let cleared = self.observers.clear_at_reinit(&self.frame, emptied);
            self.reinit_cleared = cleared
                .iter()
                .map(|&i| self.observers.defs[i].id.clone())
                .collect();
        }
        self.observers.update(&mut self.frame);
        if attach || reinit {
            let observed = self.frame.now(Space::Observer).clone();
            self.frame.prev_mut(Space::Observer).copy_from(&observed);
        }
        control.scan(now, &self.frame, &mut self.commanded);
        for &k in &self.held_on {
            self.commanded.set(k, true);
        }
        self.frame.now_mut(Space::Output).copy_from(&self.commanded);
        if attach {
            self.frame
                .prev_mut(Space::Output)
                .copy_from(&self.commanded);
            // A contactor with a mirror contact is observed: the running plant's
            // previous value is what the mirror shows (a safety contactor not yet
            // closed by the link is not taken for a dead one).
            for &(i, o) in &self.mirrors {
                if i < inputs.len() && o < self.commanded.len() {
                    self.frame.prev_mut(Space::Output).set(o, inputs.get(i));
                }
            }
        }

        if self.mode != FilterMode::Off {
            let mut violations = std::mem::take(&mut self.scratch);
            self.filter.sync(&mut self.filter_state, &self.frame);
            self.filter
                .violations_synced(&self.filter_state, &self.frame, &mut violations);
            match self.mode {
                FilterMode::Enforce => {
                    if !violations.is_empty() && !self.latched {
                        self.latched = true;
                        let trip = self.trip_record(&violations, true);
                        self.trips.push(trip);
                        self.events.push(Event::Trip {
                            index: self.trips.len() - 1,
                        });
                    }
                    if self.latched {
                        self.apply_fallback();
                    }
                }
                FilterMode::ReportOnly => {
                    if !violations.is_empty() && violations != self.previous_violations {
                        let trip = self.trip_record(&violations, false);
                        self.trips.push(trip);
                        self.events.push(Event::Violation {
                            index: self.trips.len() - 1,
                        });
                    }
                }
                FilterMode::Off => {}
            }
            std::mem::swap(&mut self.previous_violations, &mut violations);
            self.scratch = violations;
        }
        if self.hold && !self.latched && self.mode != FilterMode::ReportOnly {
            self.apply_fallback();
        }

        let held = self.holds_outputs();
        self.with_diagnosers_view(|frame| after_filter(now, frame, held));
        let tripped = self.latched;
        let frame = &self.frame;
        let commanded = &self.commanded;
        self.history.push_with(|r| {
            r.time = now;
            r.inputs.copy_from(frame.now(Space::Input));
            r.commanded.copy_from(commanded);
            r.applied.copy_from(frame.now(Space::Output));
            r.observers.copy_from(frame.now(Space::Observer));
            r.aux.copy_from(frame.now(Space::Aux));
            r.tripped = tripped;
        });
        self.frame.now(Space::Output)
    }

    /// Sets the outputs the safety function holds ON (`held_on`: a safety contactor),
    /// as every cycle does after the control's scan: for a projection that runs the
    /// program without the engine.
    pub fn hold_on(&self, outputs: &mut Bits) {
        for &k in &self.held_on {
            if k < outputs.len() {
                outputs.set(k, true);
            }
        }
    }

    /// After [`Engine::cycle`]: the outputs the plant really received in this cycle when
    /// they differ from the filter's (a live gateway's safe outputs for a lost peer or
    /// stale inputs; the outputs a followed live run applied). The frame (read as the
    /// outputs at t-1 next cycle) and the recorder's last record take them. Ignored
    /// when the length is not the number of outputs.
    pub fn set_applied(&mut self, applied: &Bits) {
        if applied.len() != self.frame.now(Space::Output).len() {
            return;
        }
        self.frame.now_mut(Space::Output).copy_from(applied);
        if let Some(r) = self.history.last_mut() {
            r.applied.copy_from(applied);
        }
    }

    /// After [`Engine::cycle`] (and [`Engine::set_applied`]): the stage that follows the
    /// filter (the diagnosers of a live link, which follow the outputs really applied),
    /// run on the frame at the cycle's time; the recorder's last record takes the
    /// auxiliaries it wrote, as [`Engine::cycle_with`] records them.
    pub fn after_filter(&mut self, stage: &mut dyn FnMut(Millis, &mut Frame, bool)) {
        let held = self.holds_outputs();
        let now = self.now;
        self.with_diagnosers_view(|frame| stage(now, frame, held));
        if let Some(r) = self.history.last_mut() {
            r.aux.copy_from(self.frame.now(Space::Aux));
        }
    }

    /// The sensors the diagnosers estimate, as [`crate::sim::diagnosis::estimate_map`]
    /// gives them: while a sensor's flag is set, the observers, the control program and
    /// the constraints read its estimate (the cooperation, seed 004 section 4).
    pub fn set_estimates(&mut self, estimates: Vec<(usize, usize, usize)>) {
        self.estimated = vec![false; estimates.len()];
        self.estimates = estimates;
    }

    /// Runs the sensors' plausibility stage or not (a trace or a test peer that moves
    /// the plant faster than its physics: every edge is then taken as read). On by
    /// default; the rules are `plausible` in `plant.ron`.
    pub fn set_plausibility(&mut self, on: bool) {
        self.plausibility_on = on;
    }

    /// True when the plausibility stage runs.
    pub fn plausibility_on(&self) -> bool {
        self.plausibility_on
    }

    /// The sensors the diagnosers estimate (see [`Engine::set_estimates`]).
    pub fn estimates(&self) -> &[(usize, usize, usize)] {
        &self.estimates
    }

    /// Replaces each flagged sensor by its estimate (the flags and estimates the
    /// diagnosers wrote at the end of the previous cycle). Switching between the
    /// reading and the estimate is not an edge: the value at t-1 takes the value at t
    /// in that cycle, so an observer never counts a box the switch made up.
    fn read_estimates(&mut self) {
        for (k, &(input, def, est)) in self.estimates.iter().enumerate() {
            let aux = self.frame.now(Space::Aux);
            if def >= aux.len() || est >= aux.len() || input >= self.frame.now(Space::Input).len() {
                continue;
            }
            let flagged = aux.get(def);
            if flagged {
                let v = aux.get(est);
                self.frame.now_mut(Space::Input).set(input, v);
            }
            if flagged != self.estimated[k] {
                let v = self.frame.now(Space::Input).get(input);
                self.frame.prev_mut(Space::Input).set(input, v);
                self.estimated[k] = flagged;
            }
        }
    }

    /// Runs `f` (the diagnosers' stage) on the frame as the plant is: the sensors as
    /// read ([`Engine::with_raw_inputs`]), and each supplied drive OFF while its supply
    /// is. The outputs are put back afterwards.
    fn with_diagnosers_view(&mut self, f: impl FnOnce(&mut Frame)) {
        // A drive whose supply is cut does not act, whatever its own output: the
        // diagnosers read it OFF (else a table frozen by its safety valve, its rotation
        // still ordered, reads as a sensor that failed to see it arrive).
        // Only the drives ON under a cut supply change, and only they are put back (the
        // stage writes no output): nothing to do while every supply is ON.
        let mut cut = Vec::new();
        for &(k, s) in &self.supplied {
            for prev in [false, true] {
                let bits = if prev {
                    self.frame.prev_mut(Space::Output)
                } else {
                    self.frame.now_mut(Space::Output)
                };
                if k < bits.len() && s < bits.len() && !bits.get(s) && bits.get(k) {
                    bits.set(k, false);
                    cut.push((k, prev));
                }
            }
        }
        self.with_raw_inputs(f);
        for (k, prev) in cut {
            if prev {
                self.frame.prev_mut(Space::Output).set(k, true);
            } else {
                self.frame.now_mut(Space::Output).set(k, true);
            }
        }
    }

    /// Runs `f` on the frame with the inputs as read (at t and t-1), before the
    /// plausibility stage held any edge: the diagnosers diagnose the sensors from what
    /// they really read. The held values are put back afterwards.
    fn with_raw_inputs(&mut self, f: impl FnOnce(&mut Frame)) {
        if self.plausibility.is_empty() || !self.plausibility_on {
            f(&mut self.frame);
            return;
        }
        let held = (
            self.frame.now(Space::Input).clone(),
            self.frame.prev(Space::Input).clone(),
        );
        let (raw, raw_prev) = self.plausibility.raw();
        self.frame.now_mut(Space::Input).copy_from(raw);
        self.frame.prev_mut(Space::Input).copy_from(raw_prev);
        f(&mut self.frame);
        self.frame.now_mut(Space::Input).copy_from(&held.0);
        self.frame.prev_mut(Space::Input).copy_from(&held.1);
    }

    fn apply_fallback(&mut self) {
        let fallback = if self.mode == FilterMode::Off {
            self.filter.fallback(&self.frame)
        } else {
            self.filter.fallback_synced(&self.filter_state, &self.frame)
        };
        match fallback {
            Ok(out) => {
                self.frame.now_mut(Space::Output).copy_from(&out);
                self.spec_error = None;
            }
            Err(err) => {
                // No vector satisfies every constraint: each output at its safe value.
                let safe = self.filter.safe_vector(&self.frame);
                self.frame.now_mut(Space::Output).copy_from(&safe);
                self.report_spec_error(&err);
            }
        }
    }

    fn report_spec_error(&mut self, err: &SpecError) {
        let message = err.to_string();
        if self.spec_error.as_ref() != Some(&message) {
            self.spec_error = Some(message.clone());
            if let Some(last) = self.trips.last_mut()
                && last.spec_error.is_none()
            {
                last.spec_error = Some(message.clone());
            }
            self.events.push(Event::SpecificationError { message });
        }
    }

    fn trip_record(&self, violations: &[usize], enforced: bool) -> Trip {
        let fallback = self.filter.fallback(&self.frame);
        let safe = self.filter.safe_vector(&self.frame);
        let applied_bits = match (&fallback, enforced) {
            (Ok(b), true) => b.clone(),
            (Err(_), true) => safe.clone(),
            (_, false) => self.commanded.clone(),
        };
        let fallback_bits = fallback.as_ref().map_or(safe, Clone::clone);
        let n_out = self.commanded.len();
        let out_name = |k: usize| {
            self.symbols
                .name(Space::Output, u32::try_from(k).unwrap_or(0))
                .to_string()
        };
        let actions = (0..n_out)
            .map(|k| {
                let c = self.commanded.get(k);
                let a = applied_bits.get(k);
                OutputAction {
                    output: out_name(k),
                    commanded: c,
                    applied: a,
                    action: match (c, a) {
                        (false, true) => Action::ForcedOn,
                        (true, false) => Action::ForcedOff,
                        _ => Action::Unchanged,
                    },
                }
            })
            .collect();
        Trip {
            time_ms: self.now.0,
            cycle: self.cycles,
            constraints: violations.iter().map(|&ci| self.fired(ci)).collect(),
            actions,
            fallback: (0..n_out)
                .map(|k| (out_name(k), fallback_bits.get(k)))
                .collect(),
            spec_error: fallback.err().map(|e| e.to_string()),
            enforced,
        }
    }

    fn fired(&self, ci: usize) -> FiredConstraint {
        self.fired_in(ci, &self.frame)
    }

    /// The safety devices (`held_on`) are driven by someone else, the PLC a monitor
    /// watches: their commanded values are taken as observed, never held ON (Vigie
    /// writes no output there; holding them would report a contactor the PLC left open
    /// as commanded and dead).
    pub fn observe_safety_devices(&mut self) {
        self.held_on.clear();
    }

    /// A mirror contact that disagrees with the output applied at t-1 for less than its
    /// `feedback_ms` is read as agreeing (the contactor is still switching, or the link
    /// has not yet brought its new state); past it, as it reads. `fresh`: an attach or a
    /// re-initialisation, which starts every count again.
    fn hold_mirrors(&mut self, now: Millis, fresh: bool) {
        for (k, &(i, o)) in self.mirrors.iter().enumerate() {
            let Some((ms, since)) = self.mirror_ms.get_mut(k) else {
                continue;
            };
            let (n_in, n_out) = (
                self.frame.now(Space::Input).len(),
                self.frame.prev(Space::Output).len(),
            );
            if *ms == 0 || fresh || i >= n_in || o >= n_out {
                *since = None;
                continue;
            }
            let expected = self.frame.prev(Space::Output).get(o);
            if self.frame.now(Space::Input).get(i) == expected {
                *since = None;
                continue;
            }
            let from = *since.get_or_insert(now);
            if now.0.saturating_sub(from.0) < *ms {
                self.frame.now_mut(Space::Input).set(i, expected);
            }
        }
    }

    /// The plant's mirror contacts: each one's input and the output it mirrors.
    pub fn mirrors(&self) -> &[(usize, usize)] {
        &self.mirrors
    }

    /// The constraints that `outputs` would violate if applied at the next cycle, the
    /// inputs and observers staying as they are now (the check of a manual request),
    /// each with its true term. A mirror contact follows its contactor into the next
    /// cycle, keeping the disagreement it shows now: a healthy contactor reads as the
    /// output applied now, a welded or dead one stays welded or dead.
    pub fn check_request(&self, outputs: &Bits) -> Vec<FiredConstraint> {
        let mut frame = self.frame.clone();
        let next: Vec<(usize, bool)> = self
            .mirrors
            .iter()
            .filter(|&&(i, o)| i < frame.now(Space::Input).len() && o < outputs.len())
            .map(|&(i, o)| {
                let fault = frame.now(Space::Input).get(i) != frame.prev(Space::Output).get(o);
                (i, frame.now(Space::Output).get(o) != fault)
            })
            .collect();
        frame.shift();
        for (i, v) in next {
            frame.now_mut(Space::Input).set(i, v);
        }
        frame.now_mut(Space::Output).copy_from(outputs);
        self.filter
            .violations(&frame)
            .into_iter()
            .map(|ci| self.fired_in(ci, &frame))
            .collect()
    }

    fn fired_in(&self, ci: usize, frame: &Frame) -> FiredConstraint {
        let literals = self
            .filter
            .true_term(ci, frame)
            .unwrap_or_default()
            .into_iter()
            .map(|l| LiteralValue {
                literal: self.symbols.render_literal(l),
                name: self.symbols.name(l.var.space, l.var.index).to_string(),
                space: l.var.space,
                previous: l.var.prev,
                value: frame.get(l.var),
            })
            .collect();
        FiredConstraint {
            id: self.filter.id(ci).to_string(),
            class: self.filter.class(ci),
            notation: self.notation.get(ci).cloned().unwrap_or_default(),
            literals,
        }
    }

    /// Latches `trip`, a trip of an earlier run of the same plant that was never reset
    /// (a live gateway restarted after a crash): from the next cycle on the outputs are
    /// the fallback until the operator's reset, as if the trip had just happened. No
    /// [`Event::Trip`] is raised (the caller reports the restoration). Enforce mode only.
    pub fn restore_trip(&mut self, trip: Trip) {
        if self.mode != FilterMode::Enforce {
            return;
        }
        self.latched = true;
        self.trips.push(trip);
    }

    /// The operator's reset after a trip. Refused while a constraint is still violated
    /// by the outputs the control program commands.
    pub fn reset(&mut self) -> Result<(), ResetRefused> {
        self.reset_check()?;
        self.latched = false;
        self.events.push(Event::Reset);
        Ok(())
    }

    /// What [`Engine::reset`] would answer now, changing nothing (the console's
    /// next-step panel says whether Reset is possible before it is pressed).
    pub fn reset_check(&self) -> Result<(), ResetRefused> {
        if !self.latched {
            return Err(ResetRefused::NotTripped);
        }
        let mut frame = self.frame.clone();
        frame.now_mut(Space::Output).copy_from(&self.commanded);
        let violations = self.filter.violations(&frame);
        if !violations.is_empty() {
            return Err(ResetRefused::StillViolated {
                constraints: violations
                    .iter()
                    .map(|&i| self.filter.id(i).to_string())
                    .collect(),
                observers: self.observers_in(&violations, &frame),
            });
        }
        Ok(())
    }

    /// The observers at 1 in the true terms of `violations` (evaluated with the
    /// commanded outputs in the frame), in index order.
    fn observers_in(&self, violations: &[usize], frame: &Frame) -> Vec<String> {
        let mut idx: Vec<usize> = violations
            .iter()
            .filter_map(|&ci| self.filter.true_term(ci, frame))
            .flatten()
            .filter(|l| l.var.space == Space::Observer && !l.var.prev && l.positive)
            .map(|l| l.var.index as usize)
            .collect();
        idx.sort_unstable();
        idx.dedup();
        idx.into_iter()
            .map(|i| self.symbols.name(Space::Observer, i as u32).to_string())
            .collect()
    }
}

#[cfg(test)]
mod tests;
