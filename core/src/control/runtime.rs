//! The scan-cycle runtime: one PLC scan per engine cycle.

use super::program::{CompiledProgram, CounterKind, DelayKind, Qualifier};
use crate::bits::Bits;
use crate::engine::Control;
use crate::frame::Frame;
use crate::symbols::Space;
use crate::time::Millis;
use std::sync::Arc;

/// Number of evolutions kept by [`ProgramRuntime::evolutions`].
pub const EVOLUTION_RING: usize = 32;

/// One evolution of the program: the transitions fired in one scan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Evolution {
    /// Time of the scan.
    pub time: Millis,
    /// Scan number (1 for the first scan).
    pub scan: u64,
    /// Ids of the transitions fired, in program order.
    pub fired: Vec<String>,
}

#[derive(Clone, Debug)]
struct Slot {
    time: Millis,
    scan: u64,
    fired: Vec<u16>,
}

/// Why the program drives an output or a memory to 1 (see [`ProgramRuntime::drivers`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Driver {
    /// A non-stored action (`N`, `L`, `D`, `P`) of an active step that is true now.
    Action {
        /// The step.
        step: String,
        /// The qualifier.
        qualifier: Qualifier,
    },
    /// The stored value set by an `S` action and not reset since.
    Stored {
        /// Steps that carry an `S` action on the target.
        set_by: Vec<String>,
    },
    /// The target's equation is true.
    Equation {
        /// The equation as written.
        expression: String,
    },
}

/// A panel name the program does not declare.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the program has no panel input `{0}`")]
pub struct UnknownPanel(pub String);

/// The state of a standard timer: when its time started, its input at the last scan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct DelayState {
    since: Option<Millis>,
    prev_in: bool,
}

impl DelayState {
    /// One call with input `input` at `now`: the output Q (IEC 61131-3 TON, TOF, TP).
    fn call(&mut self, kind: DelayKind, ms: u64, input: bool, now: Millis) -> bool {
        let elapsed = |s: Millis| now.saturating_sub(s).0;
        let q = match kind {
            DelayKind::On => {
                if input {
                    let s = *self.since.get_or_insert(now);
                    elapsed(s) >= ms
                } else {
                    self.since = None;
                    false
                }
            }
            DelayKind::Off => {
                if input {
                    self.since = None;
                    true
                } else {
                    if self.prev_in {
                        self.since = Some(now);
                    }
                    self.since.is_some_and(|s| elapsed(s) < ms)
                }
            }
            DelayKind::Pulse => {
                match self.since {
                    None if input && !self.prev_in => self.since = Some(now),
                    Some(s) if elapsed(s) >= ms && !input => self.since = None,
                    _ => {}
                }
                self.since.is_some_and(|s| elapsed(s) < ms)
            }
        };
        self.prev_in = input;
        q
    }
}

/// The state of a standard counter: its value CV and its count input at the last scan
/// (the counter counts the input's rising edges).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct CounterState {
    cv: i16,
    prev: bool,
}

impl CounterState {
    /// One call with count input `input` and reset (R of a CTU, LD of a CTD) `reset`:
    /// the output Q (IEC 61131-3 CTU, CTD).
    fn call(&mut self, kind: CounterKind, preset: i16, input: bool, reset: bool) -> bool {
        let rose = input && !self.prev;
        self.prev = input;
        match kind {
            CounterKind::Up => {
                if reset {
                    self.cv = 0;
                } else if rose {
                    self.cv = self.cv.saturating_add(1);
                }
                self.cv >= preset
            }
            CounterKind::Down => {
                if reset {
                    self.cv = preset;
                } else if rose {
                    self.cv = self.cv.saturating_sub(1);
                }
                self.cv <= 0
            }
        }
    }
}

/// A running program: the compiled program (shared) and its state.
///
/// # Scan semantics
///
/// Each [`Control::scan`]:
/// 1. reads the inputs at t and t-1 from the engine frame and the panel (buttons
///    pressed since the last scan are true for this one scan, switches hold);
/// 2. computes the step timers (`now - activation time >= ms`);
/// 3. evaluates every transition enabled by the current situation (all its upstream
///    steps active) against inputs, steps, timers, memories, panel and the outputs of
///    the previous scan (`A0` and `A0*` both read the previous scan's command here);
/// 4. fires all of them simultaneously (GRAFCET rule 4: upstream steps deactivated,
///    then downstream steps activated; a step both deactivated and activated stays
///    active and keeps its activation time). **At most one evolution per scan**:
///    transitions enabled by the new situation are evaluated in the next scan
///    (no search for stability), as a PLC SFC does;
/// 5. recomputes the timers, then the actions of the new situation: `S` then `R`
///    on the stored values (reset wins), then `N`, `L(ms)` (while active less than
///    ms), `D(ms)` (active at least ms) and `P` (the scan of activation);
/// 6. evaluates the equations top-down, like Ladder rungs: each target becomes
///    `actions OR equation` and later rungs see its new value (`A1` after its rung is
///    this scan's value, `A1*` always the previous scan's);
/// 7. writes the outputs.
///
/// A scan allocates nothing.
#[derive(Clone, Debug)]
pub struct ProgramRuntime {
    program: Arc<CompiledProgram>,
    state: Vec<u64>,
    activated_at: Vec<Millis>,
    just_activated: Bits,
    stored: Bits,
    values: Bits,
    fired: Vec<u16>,
    ring: Vec<Slot>,
    ring_head: usize,
    ring_len: usize,
    pulses: Bits,
    switches: Bits,
    delays: Vec<DelayState>,
    counters: Vec<CounterState>,
    /// Per action, when its own time started (SD and SL run on after their step).
    timed: Vec<Option<Millis>>,
    scans: u64,
    now: Millis,
    /// The state words (t and t-1) before the evolution of the last evaluated scan.
    last_pre: Vec<u64>,
    /// Stored values before the last evaluated scan.
    last_stored: Bits,
    /// The last evaluated scan changed nothing (no firing, same values): a scan that
    /// starts from the same state would compute the same outputs again.
    stable: bool,
    /// The program has no timer and no L/D action: a scan depends on the state only.
    time_free: bool,
}

impl ProgramRuntime {
    /// A runtime in the initial situation.
    pub fn new(program: Arc<CompiledProgram>) -> Self {
        let n_slots = program.n_outputs + program.memory_aux.len();
        let n_trans = program.transitions.len();
        let n_panel = program.panel_aux.len();
        let n_steps = program.steps.len();
        let mut rt = Self {
            state: vec![0; 2 * program.layout.half],
            activated_at: vec![Millis::ZERO; n_steps],
            just_activated: Bits::zeros(n_steps),
            stored: Bits::zeros(n_slots),
            values: Bits::zeros(n_slots),
            fired: Vec::with_capacity(n_trans),
            ring: (0..EVOLUTION_RING)
                .map(|_| Slot {
                    time: Millis::ZERO,
                    scan: 0,
                    fired: Vec::with_capacity(n_trans),
                })
                .collect(),
            ring_head: 0,
            ring_len: 0,
            pulses: Bits::zeros(n_panel),
            switches: Bits::zeros(n_panel),
            delays: vec![DelayState::default(); program.delays.len()],
            counters: vec![CounterState::default(); program.counters.len()],
            timed: vec![None; program.actions.len()],
            scans: 0,
            now: Millis::ZERO,
            last_pre: vec![0; 2 * program.layout.half],
            last_stored: Bits::zeros(n_slots),
            stable: false,
            // A counter's state is not in the state words: every scan is evaluated.
            time_free: program.timers.is_empty()
                && program.delays.is_empty()
                && program.counters.is_empty()
                && program.actions.iter().all(|a| !a.qualifier.is_timed()),
            program,
        };
        rt.reset();
        rt
    }

    /// Makes `self` a copy of `other`'s situation (same program) reusing `self`'s
    /// allocations: steps, step times, memories, values, panel, scan count. The ring of
    /// past evolutions is not copied (`evolutions()` of the copy is stale). The closed
    /// loop keeps the situation before each scan this way, for the explanations, without
    /// allocating every cycle.
    pub fn copy_state_from(&mut self, other: &Self) {
        if !Arc::ptr_eq(&self.program, &other.program)
            || self.state.len() != other.state.len()
            || self.ring.len() != other.ring.len()
        {
            *self = other.clone();
            return;
        }
        self.state.copy_from_slice(&other.state);
        self.activated_at.clone_from(&other.activated_at);
        self.just_activated.copy_from(&other.just_activated);
        self.stored.copy_from(&other.stored);
        self.values.copy_from(&other.values);
        self.fired.clone_from(&other.fired);
        self.pulses.copy_from(&other.pulses);
        self.switches.copy_from(&other.switches);
        self.delays.clone_from(&other.delays);
        self.counters.clone_from(&other.counters);
        self.timed.clone_from(&other.timed);
        self.scans = other.scans;
        self.now = other.now;
        self.last_pre.copy_from_slice(&other.last_pre);
        self.last_stored.copy_from(&other.last_stored);
        self.stable = other.stable;
        self.time_free = other.time_free;
    }

    /// True when `other` is in the same situation: the same steps, step times,
    /// values (now and at the previous scan), stored values and timers, leaving out the
    /// state bits `ignore` lists as (word, mask); the scan count and the history of
    /// evolutions are not part of it.
    pub fn same_situation(&self, other: &Self, ignore: &[(usize, u64)]) -> bool {
        Arc::ptr_eq(&self.program, &other.program)
            && self.state.len() == other.state.len()
            && self
                .state
                .iter()
                .zip(&other.state)
                .enumerate()
                .all(|(w, (a, b))| {
                    let skip = ignore
                        .iter()
                        .filter(|(iw, _)| *iw == w)
                        .fold(0u64, |m, (_, bit)| m | bit);
                    a & !skip == b & !skip
                })
            && self.stored == other.stored
            && self.delays == other.delays
            && self.counters == other.counters
            && self.timed == other.timed
            && self.just_activated == other.just_activated
            && self.program.steps.iter().enumerate().all(|(i, s)| {
                !self.step_active(s.aux) || self.activated_at[i] == other.activated_at[i]
            })
    }

    /// The state bits (word, mask) of the panel's values, now and at the previous scan.
    pub fn panel_bits(&self) -> Vec<(usize, u64)> {
        let p = &self.program;
        p.panel_aux
            .iter()
            .flat_map(|&a| [false, true].map(|prev| p.layout.locate(Space::Aux, a as usize, prev)))
            .collect()
    }

    /// Evaluates every scan, even when the quiescence rule would skip it (for tests
    /// comparing both behaviours).
    #[cfg(test)]
    pub(crate) fn always_evaluate(&mut self) {
        self.time_free = false;
    }

    /// Back to the initial situation: stored values, memories and history cleared,
    /// switches kept.
    pub fn reset(&mut self) {
        self.state.iter_mut().for_each(|w| *w = 0);
        let program = Arc::clone(&self.program);
        for s in &program.steps {
            self.set(Space::Aux, s.aux as usize, s.initial);
        }
        self.stored.clear();
        self.values.clear();
        self.pulses.clear();
        self.delays
            .iter_mut()
            .for_each(|d| *d = DelayState::default());
        self.counters
            .iter_mut()
            .for_each(|c| *c = CounterState::default());
        self.timed.iter_mut().for_each(|t| *t = None);
        let n_out = program.n_outputs;
        for &slot in &program.initial {
            if slot < n_out {
                self.set(Space::Output, slot, true);
            } else if let Some(&aux) = program.memory_aux.get(slot - n_out) {
                self.set(Space::Aux, aux as usize, true);
            }
            if program
                .actions
                .iter()
                .any(|a| a.slot == slot && matches!(a.qualifier, Qualifier::S | Qualifier::R))
            {
                self.stored.set(slot, true);
            }
        }
        self.ring_len = 0;
        self.ring_head = 0;
        self.stable = false;
        self.scans = 0;
    }

    /// The compiled program.
    pub fn program(&self) -> &Arc<CompiledProgram> {
        &self.program
    }

    fn panel_index(&self, name: &str) -> Result<usize, UnknownPanel> {
        self.program
            .panel_aux
            .iter()
            .position(|&aux| self.program.symbols.name(Space::Aux, aux) == name)
            .ok_or_else(|| UnknownPanel(name.to_string()))
    }

    /// Presses a button: `name` reads true during the next scan only.
    pub fn press(&mut self, name: &str) -> Result<(), UnknownPanel> {
        let i = self.panel_index(name)?;
        self.pulses.set(i, true);
        Ok(())
    }

    /// Sets a switch: `name` reads `on` from the next scan until changed.
    pub fn set_switch(&mut self, name: &str, on: bool) -> Result<(), UnknownPanel> {
        let i = self.panel_index(name)?;
        self.switches.set(i, on);
        Ok(())
    }

    /// Number of scans run since the start or the last reset.
    pub fn scans(&self) -> u64 {
        self.scans
    }

    /// The program's own frame after the last scan (inputs, outputs, and in the Aux
    /// space steps, memories, timers and panel), indexed by [`CompiledProgram::symbols`].
    /// Built on demand.
    pub fn frame(&self) -> Frame {
        let sym = &self.program.symbols;
        let mut f = Frame::new(sym.sizes());
        for space in Space::ALL {
            for i in 0..sym.len(space) {
                f.now[space as usize].set(i, self.get(space, i, false));
                f.prev[space as usize].set(i, self.get(space, i, true));
            }
        }
        f
    }

    #[inline]
    fn get(&self, space: Space, index: usize, prev: bool) -> bool {
        let (w, m) = self.program.layout.locate(space, index, prev);
        self.state.get(w).is_some_and(|x| x & m != 0)
    }

    #[inline]
    fn set(&mut self, space: Space, index: usize, value: bool) {
        let (w, m) = self.program.layout.locate(space, index, false);
        if let Some(x) = self.state.get_mut(w) {
            if value {
                *x |= m;
            } else {
                *x &= !m;
            }
        }
    }

    /// The value after the last scan of any program name (input, output, step,
    /// memory, timer, panel input).
    pub fn value(&self, name: &str) -> Option<bool> {
        let (space, index) = self.program.symbols.lookup(name)?;
        Some(self.get(space, index as usize, false))
    }

    /// The value before the last scan of any program name (the previous cycle's).
    pub fn previous_value(&self, name: &str) -> Option<bool> {
        let (space, index) = self.program.symbols.lookup(name)?;
        Some(self.get(space, index as usize, true))
    }

    /// True when `step` is active.
    pub fn is_active(&self, step: &str) -> bool {
        self.program
            .steps
            .iter()
            .any(|s| s.id == step && self.step_active(s.aux))
    }

    fn step_active(&self, aux: u32) -> bool {
        self.get(Space::Aux, aux as usize, false)
    }

    /// True in the initial situation: exactly the initial steps active (a program
    /// waiting for its start, or back at rest after its stop).
    pub fn at_initial_situation(&self) -> bool {
        self.program
            .steps
            .iter()
            .all(|s| self.step_active(s.aux) == s.initial)
    }

    /// Ids of the active steps, in program order.
    pub fn active_steps(&self) -> Vec<&str> {
        self.program
            .steps
            .iter()
            .filter(|s| self.step_active(s.aux))
            .map(|s| s.id.as_str())
            .collect()
    }

    /// How long `step` has been active at the last scan, if it is.
    pub fn step_time(&self, step: &str) -> Option<Millis> {
        let i = self.program.steps.iter().position(|s| s.id == step)?;
        let s = &self.program.steps[i];
        self.step_active(s.aux)
            .then(|| self.now.saturating_sub(self.activated_at[i]))
    }

    /// Ids of the transitions fired in the last scan.
    pub fn fired_last_scan(&self) -> Vec<&str> {
        self.fired
            .iter()
            .filter_map(|&t| self.program.transitions.get(t as usize))
            .map(|t| t.id.as_str())
            .collect()
    }

    /// The last [`EVOLUTION_RING`] evolutions (scans that fired at least one
    /// transition), oldest first.
    pub fn evolutions(&self) -> Vec<Evolution> {
        let n = self.ring.len();
        (0..self.ring_len)
            .map(|k| {
                let slot = &self.ring[(self.ring_head + n - self.ring_len + k) % n];
                Evolution {
                    time: slot.time,
                    scan: slot.scan,
                    fired: slot
                        .fired
                        .iter()
                        .filter_map(|&t| self.program.transitions.get(t as usize))
                        .map(|t| t.id.clone())
                        .collect(),
                }
            })
            .collect()
    }

    fn slot_of(&self, name: &str) -> Option<usize> {
        (0..self.values.len()).find(|&s| self.program.slot_name(s) == name)
    }

    /// Why an output or a memory is 1 after the last scan (empty when it is 0), or
    /// `None` for an unknown name. Computed from the current state.
    pub fn drivers(&self, target: &str) -> Option<Vec<Driver>> {
        let slot = self.slot_of(target)?;
        let p = &*self.program;
        let mut out = Vec::new();
        for (i, a) in p.actions.iter().enumerate().filter(|(_, a)| a.slot == slot) {
            let step = &p.steps[a.step as usize];
            // A time-limited stored action runs on after its step.
            if let (Qualifier::SL(ms), Some(t0)) = (a.qualifier, self.timed[i])
                && self.now.saturating_sub(t0).0 < ms
            {
                out.push(Driver::Action {
                    step: step.id.clone(),
                    qualifier: a.qualifier,
                });
                continue;
            }
            if !self.step_active(step.aux) {
                continue;
            }
            if self.action_true(a.step as usize, a.qualifier)
                && !matches!(a.qualifier, Qualifier::S | Qualifier::R)
            {
                out.push(Driver::Action {
                    step: step.id.clone(),
                    qualifier: a.qualifier,
                });
            }
        }
        if self.stored.get(slot) {
            out.push(Driver::Stored {
                set_by: p
                    .actions
                    .iter()
                    .filter(|a| {
                        a.slot == slot
                            && matches!(
                                a.qualifier,
                                Qualifier::S | Qualifier::SD(_) | Qualifier::DS(_)
                            )
                    })
                    .map(|a| p.steps[a.step as usize].id.clone())
                    .collect(),
            });
        }
        for eq in &p.equations {
            if eq.slot == slot && p.conds.eval(eq.cond, &self.state) {
                out.push(Driver::Equation {
                    expression: p
                        .program
                        .equations
                        .get(eq.index)
                        .map(|e| e.1.clone())
                        .unwrap_or_default(),
                });
            }
        }
        Some(out)
    }

    #[inline]
    fn action_true(&self, step: usize, q: Qualifier) -> bool {
        let elapsed = self.now.saturating_sub(self.activated_at[step]).0;
        match q {
            Qualifier::N | Qualifier::S => true,
            // Stored, or running on their own time: see `stored_actions`.
            Qualifier::R | Qualifier::SD(_) | Qualifier::DS(_) | Qualifier::SL(_) => false,
            Qualifier::L(ms) => elapsed < ms,
            Qualifier::D(ms) => elapsed >= ms,
            Qualifier::P => self.just_activated.get(step),
        }
    }

    fn update_timers(&mut self) {
        let program = &*self.program;
        for t in &program.timers {
            let s = t.step as usize;
            let active = program.steps.get(s).is_some_and(|st| {
                let (w, m) = program.layout.locate(Space::Aux, st.aux as usize, false);
                self.state.get(w).is_some_and(|x| x & m != 0)
            });
            let on = active && self.now.saturating_sub(self.activated_at[s]).0 >= t.ms;
            let (w, m) = program.layout.locate(Space::Aux, t.aux as usize, false);
            if let Some(x) = self.state.get_mut(w) {
                if on { *x |= m } else { *x &= !m }
            }
        }
    }

    /// The stored values of the new situation: `SD` and `SL` start their time at their
    /// step's activation; `S`, `DS` (active long enough) and `SD` (its time run) set;
    /// then `R` resets (reset wins) and cancels the times of `SD` and `SL` on its target.
    fn stored_actions(&mut self, p: &CompiledProgram, now: Millis) {
        for (i, a) in p.actions.iter().enumerate() {
            if !matches!(
                a.qualifier,
                Qualifier::S | Qualifier::SD(_) | Qualifier::DS(_) | Qualifier::SL(_)
            ) {
                continue;
            }
            let s = a.step as usize;
            let active = self.get(Space::Aux, p.steps[s].aux as usize, false);
            let elapsed = now.saturating_sub(self.activated_at[s]).0;
            if matches!(a.qualifier, Qualifier::SD(_) | Qualifier::SL(_))
                && self.just_activated.get(s)
            {
                self.timed[i] = Some(now);
            }
            let set = match a.qualifier {
                Qualifier::S => active,
                Qualifier::DS(ms) => active && elapsed >= ms,
                Qualifier::SD(ms) => match self.timed[i] {
                    Some(t0) if now.saturating_sub(t0).0 >= ms => {
                        self.timed[i] = None;
                        true
                    }
                    _ => false,
                },
                _ => false,
            };
            if set {
                self.stored.set(a.slot, true);
            }
        }
        for a in p.actions.iter().filter(|a| a.qualifier == Qualifier::R) {
            if self.get(Space::Aux, p.steps[a.step as usize].aux as usize, false) {
                self.stored.set(a.slot, false);
                for (j, b) in p.actions.iter().enumerate() {
                    if b.slot == a.slot
                        && matches!(b.qualifier, Qualifier::SD(_) | Qualifier::SL(_))
                    {
                        self.timed[j] = None;
                    }
                }
            }
        }
    }

    /// Fires the transitions in `fired` simultaneously: deactivates their sources,
    /// activates their targets, logs them in the ring and refreshes the timers.
    fn fire(&mut self, p: &CompiledProgram, now: Millis) {
        let half = p.layout.half;
        for &ti in &self.fired {
            for &s in &p.transitions[ti as usize].from {
                let a = p.steps[s as usize].aux as usize;
                let (w, m) = p.layout.locate(Space::Aux, a, false);
                if let Some(x) = self.state.get_mut(w) {
                    *x &= !m;
                }
            }
        }
        for &ti in &self.fired {
            for &s in &p.transitions[ti as usize].to {
                let a = p.steps[s as usize].aux as usize;
                let (w, m) = p.layout.locate(Space::Aux, a, false);
                let was = self.state.get(w + half).is_some_and(|x| x & m != 0);
                let is = self.state.get(w).is_some_and(|x| x & m != 0);
                if !is && !was {
                    self.activated_at[s as usize] = now;
                    self.just_activated.set(s as usize, true);
                }
                if let Some(x) = self.state.get_mut(w) {
                    *x |= m;
                }
            }
        }
        let n = self.ring.len();
        if n > 0 {
            let slot = &mut self.ring[self.ring_head];
            slot.time = now;
            slot.scan = self.scans;
            slot.fired.clear();
            slot.fired.extend_from_slice(&self.fired);
            self.ring_head = (self.ring_head + 1) % n;
            self.ring_len = (self.ring_len + 1).min(n);
        }
        if !p.timers.is_empty() {
            self.update_timers();
        }
    }

    fn run_scan(&mut self, now: Millis, engine: &Frame) {
        self.now = now;
        self.scans += 1;
        let program = Arc::clone(&self.program);
        let p = &*program;
        let half = p.layout.half;
        // Shift: values at t become values at t-1.
        self.state.copy_within(0..half, half);
        let n_in = p.symbols.len(Space::Input);
        for i in 0..n_in {
            let (w, m) = p.layout.locate(Space::Input, i, false);
            let now_v = engine.now(Space::Input).get(i);
            let prev_v = engine.prev(Space::Input).get(i);
            if let Some(x) = self.state.get_mut(w) {
                if now_v { *x |= m } else { *x &= !m }
            }
            if let Some(x) = self.state.get_mut(w + half) {
                if prev_v { *x |= m } else { *x &= !m }
            }
        }
        for (i, &a) in p.panel_aux.iter().enumerate() {
            let v = self.pulses.get(i) || self.switches.get(i);
            self.set(Space::Aux, a as usize, v);
        }
        self.pulses.clear();
        // Quiescence: the last scan changed nothing and this one starts from the very
        // same state (inputs at t and t-1, steps, memories, outputs, panel): its result
        // would be identical, so it is skipped. Only for programs without time-dependent
        // elements (timers, L and D actions).
        if self.time_free && self.stable && self.state == self.last_pre && self.scans > 1 {
            self.fired.clear();
            self.just_activated.clear();
            return;
        }
        self.last_pre.copy_from_slice(&self.state);
        self.last_stored.copy_from(&self.stored);
        self.just_activated.clear();
        if self.scans == 1 {
            for (i, s) in p.steps.iter().enumerate() {
                if self.get(Space::Aux, s.aux as usize, false) {
                    self.activated_at[i] = now;
                    self.just_activated.set(i, true);
                }
            }
        }
        if !p.timers.is_empty() {
            self.update_timers();
        }

        // Evaluate every enabled transition against the situation before evolution.
        self.fired.clear();
        for (i, t) in p.transitions.iter().enumerate() {
            if p.conds.eval(t.enable, &self.state) && p.conds.eval(t.cond, &self.state) {
                self.fired.push(u16::try_from(i).unwrap_or(u16::MAX));
            }
        }
        // Fire them simultaneously.
        if !self.fired.is_empty() {
            self.fire(p, now);
        }

        // Actions of the new situation.
        self.stored_actions(p, now);
        self.values.copy_from(&self.stored);
        for (i, a) in p.actions.iter().enumerate() {
            if let Qualifier::SL(ms) = a.qualifier {
                match self.timed[i] {
                    Some(t0) if now.saturating_sub(t0).0 < ms => self.values.set(a.slot, true),
                    Some(_) => self.timed[i] = None,
                    None => {}
                }
                continue;
            }
            if matches!(
                a.qualifier,
                Qualifier::S | Qualifier::R | Qualifier::SD(_) | Qualifier::DS(_)
            ) {
                continue;
            }
            let s = a.step as usize;
            if self.get(Space::Aux, p.steps[s].aux as usize, false)
                && self.action_true(s, a.qualifier)
            {
                self.values.set(a.slot, true);
            }
        }
        let n_out = p.n_outputs;
        for k in 0..n_out {
            let v = self.values.get(k);
            self.set(Space::Output, k, v);
        }
        for (m, &a) in p.memory_aux.iter().enumerate() {
            let v = self.values.get(n_out + m);
            self.set(Space::Aux, a as usize, v);
        }
        self.run_equations(p, now);
        let half = p.layout.half;
        self.stable = self.fired.is_empty()
            && self.just_activated.count_ones() == 0
            && self.stored == self.last_stored
            && self.state[..half] == self.last_pre[..half];
    }

    /// The equations, top-down: each target becomes its actions' value OR its
    /// equation; a standard timer's equation is its input, and the timer is called; a
    /// counter's reset, then its count input, and the counter is called.
    fn run_equations(&mut self, p: &CompiledProgram, now: Millis) {
        let n_out = p.n_outputs;
        let n_slots = self.values.len();
        let n_delays = p.delays.len();
        let n_counters = p.counters.len();
        let mut reset = false;
        for eq in &p.equations {
            if eq.slot >= n_slots {
                let input = p.conds.eval(eq.cond, &self.state);
                let d = eq.slot - n_slots;
                if d < n_delays {
                    // A standard timer's input: the timer is called here.
                    if let (Some(info), Some(st)) = (p.delays.get(d), self.delays.get_mut(d)) {
                        let q = st.call(info.kind, info.ms, input, now);
                        self.set(Space::Aux, info.aux as usize, q);
                    }
                } else if d - n_delays >= n_counters {
                    // A counter's reset, just before its count input.
                    reset = input;
                } else {
                    let c = d - n_delays;
                    if let (Some(info), Some(st)) = (p.counters.get(c), self.counters.get_mut(c)) {
                        let q = st.call(info.kind, info.preset, input, reset);
                        self.set(Space::Aux, info.aux as usize, q);
                    }
                    reset = false;
                }
                continue;
            }
            let v = self.values.get(eq.slot) || p.conds.eval(eq.cond, &self.state);
            if eq.slot < n_out {
                self.set(Space::Output, eq.slot, v);
            } else if let Some(&a) = p.memory_aux.get(eq.slot - n_out) {
                self.set(Space::Aux, a as usize, v);
            }
        }
    }
}

impl Control for ProgramRuntime {
    fn scan(&mut self, now: Millis, frame: &Frame, outputs: &mut Bits) {
        self.run_scan(now, frame);
        let n_out = self.program.n_outputs;
        if outputs.len() != n_out {
            *outputs = Bits::zeros(n_out);
        }
        for k in 0..n_out {
            outputs.set(k, self.get(Space::Output, k, false));
        }
    }
}
