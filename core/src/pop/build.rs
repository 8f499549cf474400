//! Compiling the component models: signal values of every state, intervals, the
//! generated fault behaviours (the diagnoser automaton with unobservable fault events)
//! and the unexpected evolutions, pruned by the filter's constraints.

use super::model::{Behaviour, Bound, ComponentDef, DiagnoserFile, locate};
use crate::constraints::{ConstraintSet, implies};
use crate::diag::codes;
use crate::diag::{Location, Problem};
use crate::expr::{Dnf, parse_str};
use crate::symbols::{Literal, Space, Symbols, Var};
use std::collections::BTreeMap;
use std::path::Path;

/// A signal of a component.
#[derive(Clone, Debug)]
pub struct Sig {
    /// Name.
    pub name: String,
    /// Variable at t.
    pub var: Var,
}

/// An observable event symbol of a component.
#[derive(Clone, Debug)]
pub struct Symbol {
    /// Name (`FE(C4)`, `RE(C3) . A1*`, `tmo(I2)`, `tmo(pulse)`).
    pub name: String,
    /// The edge: signal index and direction; None for time-outs.
    pub edge: Option<(usize, bool)>,
    /// Extra condition of a guarded symbol.
    pub guard: Option<Dnf>,
    /// For a time-out: the interval whose end passed (None: the spurious pulse).
    pub timeout: Option<usize>,
}

/// A resolved interval.
#[derive(Clone, Debug)]
pub struct Interval {
    /// Identifier (an auxiliary variable). After those of the file come the windows of
    /// the early copies, lower bound moved back by their lead (`I9-260`, not published).
    pub id: String,
    /// Clock event index (into [`Component::clocks`]).
    pub clock: usize,
    /// Lower bound, ms.
    pub lo: u64,
    /// Upper bound (exclusive), ms; None for ever.
    pub hi: Option<u64>,
}

/// What a state of the diagnoser automaton does with time and sensors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    /// Follows the model with its windows (an early copy, `early<lead>`, whose clock
    /// event came after its motion started: lower bounds moved back by the lead).
    Timed,
    /// Follows the model, timing unknown (an unexpected motion, until the next order).
    Untimed,
    /// The fault's first edge must be observed now.
    Pending,
    /// A spurious value is shown; it must end within the pulse limit.
    Spur,
    /// The plant does not evolve any more.
    Blocked,
}

/// A state of the diagnoser automaton (normal states first, index = normal state).
#[derive(Clone, Debug)]
pub struct GState {
    /// Readable name (`x1`, `F2/x1/timed`).
    pub name: String,
    /// Fault label index, None for normal.
    pub mode: Option<usize>,
    /// The plant's normal state it follows.
    pub x: usize,
    /// Phase.
    pub phase: Phase,
    /// Observable transitions: symbol, target, window interval.
    pub obs: Vec<(usize, usize, Option<usize>)>,
    /// Unobservable plant transitions (edges hidden by a faulty sensor).
    pub silent: Vec<usize>,
    /// Unobservable fault events (normal states only): fault, target.
    pub spawn: Vec<(usize, usize)>,
    /// The interval whose end kills this state (None: time does not matter).
    pub deadline: Option<usize>,
    /// Untimed states (after an unexpected motion): the longest the plant may stay here
    /// before one of its expected sensor edges, ms, counted from entering the state (the
    /// largest upper bound of the windows of its sensor evolutions); None when an
    /// actuator event or an unbounded window leaves it.
    pub hold_ms: Option<u64>,
}

/// A fault partition.
#[derive(Clone, Debug)]
pub struct Partition {
    /// Identifier.
    pub id: String,
    /// Fault indices.
    pub faults: Vec<usize>,
    /// Estimated sensor.
    pub sensor: Option<String>,
    /// Stops the system when certain.
    pub stop: bool,
}

/// An unexpected evolution generated from the expected ones.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Unexpected {
    /// Normal state.
    pub state: String,
    /// Event symbol.
    pub event: String,
    /// The filter's constraint that makes it impossible, when pruned.
    pub pruned_by: Option<String>,
}

/// One compiled component.
#[derive(Clone, Debug)]
pub struct Component {
    /// Identifier.
    pub id: String,
    /// Signals.
    pub signals: Vec<Sig>,
    /// Normal state names.
    pub states: Vec<String>,
    /// Signal values of each normal state (bit i = signal i).
    pub values: Vec<u64>,
    /// Initial normal state.
    pub initial: usize,
    /// Fault labels.
    pub faults: Vec<String>,
    /// Per fault: it stops items (a `Blocked` behaviour: a dead drive, a jammed table).
    pub blocking: Vec<bool>,
    /// Partitions.
    pub partitions: Vec<Partition>,
    /// Clock events: signal index, rising.
    pub clocks: Vec<(usize, bool)>,
    /// Clock assumed at the start.
    pub initial_clock: Option<usize>,
    /// Intervals.
    pub intervals: Vec<Interval>,
    /// Observable symbols (edges first, then guarded, then time-outs).
    pub symbols: Vec<Symbol>,
    /// The diagnoser automaton.
    pub g: Vec<GState>,
    /// Estimates: auxiliary name and expression over the auxiliaries.
    pub estimates: Vec<(String, Dnf)>,
    /// Keeps following the plant while the filter holds the outputs (else suspended).
    pub follows_safe_state: bool,
    /// Edges of one cycle: sensors before orders.
    pub sensors_first: bool,
    /// Sensors of other components this model takes as true.
    pub assumes: Vec<String>,
    /// Sensors of other components this model takes as saying an item is there (its
    /// sensor partitions wait on them).
    pub assumes_item: Vec<String>,
    /// How long a certain decision waits for those neighbours at least, ms.
    pub settle_ms: u64,
    /// See [`super::model::ComponentDef::confirm_ms`].
    pub confirm_ms: Option<u64>,
    /// See [`super::model::ComponentDef::doubt_ms`].
    pub doubt_ms: Option<u64>,
    /// Generated unexpected evolutions.
    pub unexpected: Vec<Unexpected>,
    /// The symbol `tmo(pulse)`: a spurious value lasted longer than `pulse_max_ms`.
    pub pulse_sym: usize,
    /// The symbol `tmo(motion)`: an unexpected motion did not end within its hold.
    pub motion_sym: usize,
}

impl Component {
    /// The order in which the edges of one cycle are taken.
    pub fn edge_order(&self) -> [Space; 2] {
        if self.sensors_first {
            [Space::Input, Space::Output]
        } else {
            [Space::Output, Space::Input]
        }
    }
}

/// Every compiled component, with the run-time settings.
#[derive(Clone, Debug)]
pub struct Compiled {
    /// Components.
    pub components: Vec<Component>,
    /// Window slack, ms.
    pub margin_ms: u64,
    /// Longest spurious pulse, ms.
    pub pulse_max_ms: u64,
}

/// The auxiliary names the diagnosers publish (declare them before the constraints).
pub fn aux_names(file: &DiagnoserFile) -> Vec<String> {
    let mut out = Vec::new();
    for c in &file.components {
        for p in &c.partitions {
            out.push(format!("def_{}", p.id));
        }
        for i in &c.intervals {
            out.push(i.id.clone());
        }
        for e in &c.estimates {
            out.push(crate::symbols::estimate_name(&e.sensor));
        }
    }
    out
}

/// Parses an expression into one product term over the symbols.
fn term_of(text: &str, symbols: &Symbols) -> Result<Vec<Literal>, String> {
    let e = parse_str(text).map_err(|e| format!("`{text}`: {}", e.message))?;
    let d = e
        .to_dnf(symbols)
        .map_err(|e| format!("`{text}`: {}", e.message))?;
    match d.as_slice() {
        [t] => Ok(t.clone()),
        _ => Err(format!("`{text}` must be a single product (no `+`)")),
    }
}

struct Ctx<'a> {
    text: &'a str,
    file: &'a Path,
    problems: Vec<Problem>,
}

impl Ctx<'_> {
    fn err(&mut self, code: &'static str, near: &str, msg: String) {
        let at = locate(self.text, self.file, near);
        self.problems.push(Problem::error(code, msg, Some(at)));
    }
}

/// Compiles the file `text` (already parsed as `file_def`) against `symbols`; the
/// unexpected actuator evolutions a constraint of `filter` forbids are pruned.
pub fn compile(
    file_def: &DiagnoserFile,
    text: &str,
    file: &Path,
    symbols: &Symbols,
    filter: Option<&ConstraintSet>,
) -> Result<Compiled, Vec<Problem>> {
    let mut ctx = Ctx {
        text,
        file,
        problems: Vec::new(),
    };
    let mut ids = BTreeMap::new();
    let mut components = Vec::new();
    for c in &file_def.components {
        if ids.insert(c.id.clone(), ()).is_some() {
            ctx.err(
                codes::DIAGNOSER_DUPLICATE_COMPONENT.id,
                &c.id,
                format!("duplicate component `{}`", c.id),
            );
            continue;
        }
        if let Some(comp) = compile_one(c, symbols, filter, file_def.margin_ms, &mut ctx) {
            components.push(comp);
        }
    }
    if ctx.problems.is_empty() {
        Ok(Compiled {
            components,
            margin_ms: file_def.margin_ms,
            pulse_max_ms: file_def.pulse_max_ms,
        })
    } else {
        Err(ctx.problems)
    }
}

/// An expected evolution: from a state, on one of its symbols, to a state, within an
/// interval, on an edge of a signal.
struct Ev {
    from: usize,
    syms: Vec<usize>,
    to: usize,
    window: Option<usize>,
    sig: usize,
    rise: bool,
}

/// Compiles one component: its signals, states, symbols, intervals and expected
/// evolutions, then the diagnoser automaton, the estimates and the unexpected evolutions.
fn compile_one(
    c: &ComponentDef,
    symbols: &Symbols,
    filter: Option<&ConstraintSet>,
    margin: u64,
    ctx: &mut Ctx<'_>,
) -> Option<Component> {
    let before = ctx.problems.len();
    // Signals.
    let signals = component_signals(c, symbols, ctx);
    let states: Vec<String> = c.states.iter().map(|s| s.id.clone()).collect();
    let Some(initial) = states.iter().position(|s| s == &c.initial) else {
        ctx.err(
            codes::DIAGNOSER_UNKNOWN_STATE.id,
            &c.initial,
            format!("unknown initial state `{}`", c.initial),
        );
        return None;
    };
    // Initial values.
    let init_val = initial_values(c, symbols, &signals, ctx);
    // Symbols: bare edges, then guarded.
    let mut syms = edge_symbols(&signals);
    // Intervals.
    let (clocks, mut intervals) = component_intervals(c, symbols, &signals, ctx);
    let initial_clock = initial_clock(c, symbols, &signals, &clocks, ctx);
    // Expected evolutions: (from, symbols matched, to, window, edge).
    let evs = expected_evolutions(c, symbols, &signals, &intervals, &mut syms, ctx);
    // Time-out symbols: one per interval used as a window, then the pulse.
    let (first_tmo, pulse_sym, motion_sym) = timeout_symbols(&mut syms, &intervals, &evs);
    // Values of every state.
    let values = state_values(c, &signals, &evs, initial, init_val, ctx);
    // Faults and partitions.
    let faults: Vec<String> = c.faults.iter().map(|f| f.id.clone()).collect();
    let blocking = fault_blocking(c);
    let partitions = component_partitions(c, symbols, ctx);
    if ctx.problems.len() > before {
        return None;
    }
    // The automaton. Normal states first.
    let mut a = Automaton {
        c,
        symbols,
        signals: &signals,
        states: &states,
        faults: &faults,
        values: &values,
        evs: &evs,
        intervals: &intervals,
        syms: &syms,
        first_tmo,
        pulse_sym,
        motion_sym,
        margin,
        max_lo: intervals.iter().map(|i| i.lo).max().unwrap_or(0),
        g: Vec::new(),
        pending: Vec::new(),
        index: BTreeMap::new(),
        beh_of: Vec::new(),
        relaxed: Vec::new(),
    };
    a.normal_states();
    // Fault copies, built from a work list.
    a.spawn_faults(ctx);
    a.expand();
    let (g, relaxed) = a.finish();
    intervals.extend(relaxed);
    // Estimates.
    let estimates = component_estimates(c, symbols, ctx);
    // Unexpected evolutions, pruned by the filter.
    let unexpected =
        unexpected_evolutions(&states, &signals, &values, &evs, filter, &g, &intervals);
    if ctx.problems.len() > before {
        return None;
    }
    check_assumptions(c, symbols, &signals, ctx);
    if ctx.problems.len() > before {
        return None;
    }
    Some(Component {
        follows_safe_state: c.follows_safe_state,
        sensors_first: c.sensors_first,
        assumes: c.assumes.clone(),
        assumes_item: c.assumes_item.clone(),
        settle_ms: c.settle_ms,
        confirm_ms: c.confirm_ms,
        doubt_ms: c.doubt_ms,
        id: c.id.clone(),
        signals,
        states,
        values,
        initial,
        faults,
        blocking,
        partitions,
        clocks,
        initial_clock,
        intervals,
        symbols: syms,
        g,
        estimates,
        unexpected,
        pulse_sym,
        motion_sym,
    })
}

/// The bare edge symbols: a rise and a fall of every signal.
fn edge_symbols(signals: &[Sig]) -> Vec<Symbol> {
    let mut syms: Vec<Symbol> = Vec::new();
    for (i, s) in signals.iter().enumerate() {
        for rise in [true, false] {
            syms.push(Symbol {
                name: format!("{}({})", if rise { "RE" } else { "FE" }, s.name),
                edge: Some((i, rise)),
                guard: None,
                timeout: None,
            });
        }
    }
    syms
}

/// The clock assumed at the start (`initial_clock`), among the component's clocks.
fn initial_clock(
    c: &ComponentDef,
    symbols: &Symbols,
    signals: &[Sig],
    clocks: &[(usize, bool)],
    ctx: &mut Ctx<'_>,
) -> Option<usize> {
    match &c.initial_clock {
        None => None,
        Some(t) => match edge_in(t, symbols, signals) {
            Ok((i, r, _)) => clocks.iter().position(|&e| e == (i, r)),
            Err(m) => {
                ctx.err(codes::DIAGNOSER_CLOCK_EVENT.id, t, m);
                None
            }
        },
    }
}

/// Adds the time-out symbols: one per interval used as a window, then `tmo(pulse)` and
/// `tmo(motion)`. Returns the first time-out symbol, `tmo(pulse)` and `tmo(motion)`.
fn timeout_symbols(
    syms: &mut Vec<Symbol>,
    intervals: &[Interval],
    evs: &[Ev],
) -> (usize, usize, usize) {
    let first_tmo = syms.len();
    for (k, iv) in intervals.iter().enumerate() {
        if iv.hi.is_some() && evs.iter().any(|e| e.window == Some(k)) {
            syms.push(Symbol {
                name: format!("tmo({})", iv.id),
                edge: None,
                guard: None,
                timeout: Some(k),
            });
        }
    }
    syms.push(Symbol {
        name: "tmo(pulse)".into(),
        edge: None,
        guard: None,
        timeout: None,
    });
    let pulse_sym = syms.len() - 1;
    syms.push(Symbol {
        name: "tmo(motion)".into(),
        edge: None,
        guard: None,
        timeout: None,
    });
    let motion_sym = syms.len() - 1;
    (first_tmo, pulse_sym, motion_sym)
}

/// Per fault: it stops items (one of its behaviours is `Blocked`).
fn fault_blocking(c: &ComponentDef) -> Vec<bool> {
    c.faults
        .iter()
        .map(|f| {
            f.behaviours
                .iter()
                .any(|b| matches!(b, Behaviour::Blocked(_)))
        })
        .collect()
}

/// An observable transition of the automaton: symbol, target, window interval.
type Obs = (usize, usize, Option<usize>);

/// A fault copy's key: fault, behaviour, normal state, phase, lead of an early copy.
type CopyKey = (usize, usize, usize, Phase, Option<u64>);

/// The diagnoser automaton of one component while it is built: the normal states, then
/// the fault copies, from a work list.
struct Automaton<'a> {
    c: &'a ComponentDef,
    symbols: &'a Symbols,
    signals: &'a [Sig],
    states: &'a [String],
    faults: &'a [String],
    values: &'a [u64],
    evs: &'a [Ev],
    /// The intervals of the file (the early copies' windows come after them).
    intervals: &'a [Interval],
    syms: &'a [Symbol],
    /// The first time-out symbol.
    first_tmo: usize,
    pulse_sym: usize,
    motion_sym: usize,
    margin: u64,
    /// The largest lower bound of the intervals.
    max_lo: u64,
    g: Vec<GState>,
    /// Fault copies still to build.
    pending: Vec<usize>,
    index: BTreeMap<CopyKey, usize>,
    /// Per state: its behaviour and the lead of an early copy.
    beh_of: Vec<(usize, Option<u64>)>,
    /// Windows of the early copies: the lower bound moved back by the lead (`I9-270`).
    relaxed: Vec<Interval>,
}

impl Automaton<'_> {
    fn state_of(&self, n: &str) -> Option<usize> {
        self.states.iter().position(|s| s == n)
    }

    /// The interval whose end kills a state with these windows (None when one of them
    /// is unbounded).
    fn deadline_of(&self, ws: &[Option<usize>]) -> Option<usize> {
        let intervals = self.intervals;
        if ws.is_empty()
            || ws
                .iter()
                .any(|w| w.is_none_or(|k| intervals[k].hi.is_none()))
        {
            return None;
        }
        ws.iter()
            .flatten()
            .copied()
            .max_by_key(|&k| intervals[k].hi)
    }

    /// The time-out symbols a state ignores (all but its own deadline's when it dies
    /// of it, and the pulse's and the motion's).
    fn tmo_loops(&self, deadline: Option<usize>, own_dies: bool) -> Vec<usize> {
        let syms = self.syms;
        (self.first_tmo..syms.len())
            .filter(|&s| {
                !(own_dies
                    && deadline.is_some()
                    && syms[s].timeout == deadline
                    && s < self.pulse_sym)
            })
            .collect()
    }

    /// The symbols of an edge (bare and guarded).
    fn edge_syms(&self, sig: usize, rise: bool) -> Vec<usize> {
        self.syms
            .iter()
            .enumerate()
            .filter(|(_, s)| s.edge == Some((sig, rise)))
            .map(|(k, _)| k)
            .collect()
    }

    /// The normal states, with their expected evolutions and deadlines.
    fn normal_states(&mut self) {
        let (states, evs) = (self.states, self.evs);
        for (x, name) in states.iter().enumerate() {
            let out: Vec<_> = evs.iter().filter(|e| e.from == x).collect();
            let deadline = self.deadline_of(&out.iter().map(|e| e.window).collect::<Vec<_>>());
            let mut obs = Vec::new();
            for e in &out {
                for &s in &e.syms {
                    obs.push((s, e.to, e.window));
                }
            }
            for s in self.tmo_loops(deadline, true) {
                obs.push((s, x, None));
            }
            self.g.push(GState {
                name: name.clone(),
                mode: None,
                x,
                phase: Phase::Timed,
                obs,
                silent: Vec::new(),
                spawn: Vec::new(),
                deadline,
                hold_ms: None,
            });
        }
        self.beh_of = vec![(0, None); self.g.len()];
    }

    /// The fault copy of fault `f`, behaviour `b`, following normal state `x` in phase
    /// `ph`; created (and put on the work list) the first time.
    fn copy_of(&mut self, f: usize, b: usize, x: usize, ph: Phase, early: Option<u64>) -> usize {
        if let Some(&k) = self.index.get(&(f, b, x, ph, early)) {
            return k;
        }
        self.beh_of.push((b, early));
        // A timed copy whose clock event came up to `lead` ms after its motion
        // started is `early<lead>`.
        let phase = match early {
            Some(lead) => format!("early{lead}"),
            None => format!("{ph:?}").to_lowercase(),
        };
        self.g.push(GState {
            // Behaviours of one fault are told apart in the name (`F6.2/x2/untimed`).
            name: if self.c.faults[f].behaviours.len() > 1 {
                format!("{}.{}/{}/{phase}", self.faults[f], b + 1, self.states[x])
            } else {
                format!("{}/{}/{phase}", self.faults[f], self.states[x])
            },
            mode: Some(f),
            x,
            phase: ph,
            obs: Vec::new(),
            silent: Vec::new(),
            spawn: Vec::new(),
            deadline: None,
            hold_ms: None,
        });
        self.pending.push(self.g.len() - 1);
        self.index.insert((f, b, x, ph, early), self.g.len() - 1);
        self.g.len() - 1
    }

    /// The unobservable fault events of the normal states, per fault and behaviour.
    fn spawn_faults(&mut self, ctx: &mut Ctx<'_>) {
        let c = self.c;
        for (f, fd) in c.faults.iter().enumerate() {
            for (b, beh) in fd.behaviours.iter().enumerate() {
                match beh {
                    Behaviour::StuckAt(s, v) | Behaviour::Spurious(s, v) => {
                        let spur = matches!(beh, Behaviour::Spurious(..));
                        self.spawn_sensor(f, b, s, *v, spur, ctx);
                    }
                    Behaviour::Blocked(list) => {
                        for n in list {
                            match self.state_of(n) {
                                Some(x) => {
                                    let t = self.copy_of(f, b, x, Phase::Blocked, None);
                                    self.g[x].spawn.push((f, t));
                                }
                                None => ctx.err(
                                    codes::DIAGNOSER_UNKNOWN_STATE.id,
                                    n,
                                    format!("fault `{}`: unknown state `{n}`", fd.id),
                                ),
                            }
                        }
                    }
                    Behaviour::Jumps(n, m) => match (self.state_of(n), self.state_of(m)) {
                        (Some(x), Some(y)) => {
                            let t = self.copy_of(f, b, y, Phase::Untimed, None);
                            self.g[x].spawn.push((f, t));
                        }
                        _ => ctx.err(
                            codes::DIAGNOSER_UNKNOWN_STATE.id,
                            n,
                            format!("fault `{}`: `Jumps({n}, {m})` needs two states", fd.id),
                        ),
                    },
                    Behaviour::Unguarded => {
                        for x in 0..self.states.len() {
                            let t = self.copy_of(f, b, x, Phase::Timed, None);
                            self.g[x].spawn.push((f, t));
                        }
                    }
                    Behaviour::Moves(n, act) => self.spawn_moves(f, b, n, act, ctx),
                }
            }
        }
    }

    /// The fault events of a sensor stuck at `v`, or showing `v` spuriously (`spur`).
    fn spawn_sensor(
        &mut self,
        f: usize,
        b: usize,
        s: &str,
        v: bool,
        spur: bool,
        ctx: &mut Ctx<'_>,
    ) {
        let c = self.c;
        let Some(si) = self.signals.iter().position(|x| x.name == s) else {
            ctx.err(
                codes::DIAGNOSER_FAULT.id,
                s,
                format!(
                    "fault `{}`: `{s}` is not a signal of `{}`",
                    c.faults[f].id, c.id
                ),
            );
            return;
        };
        for x in 0..self.states.len() {
            let cur = (self.values[x] >> si) & 1 == 1;
            // A pulse may also start with an edge the model expects: its end
            // (the sensor going back within the pulse limit) tells it apart.
            let t = if cur == v {
                // A pulse that starts while the sensor already shows its value
                // is invisible, and changes nothing unless the plant makes its
                // own edge of that sensor meanwhile: the pulse hides it, and its
                // end shows it late. Only where the model expects such an edge.
                let masks = self.evs.iter().any(|e| e.from == x && e.sig == si);
                if spur && !masks {
                    continue;
                }
                let ph = if spur { Phase::Spur } else { Phase::Timed };
                self.copy_of(f, b, x, ph, None)
            } else {
                let p = self.copy_of(f, b, x, Phase::Pending, None);
                let ph = if spur { Phase::Spur } else { Phase::Timed };
                let after = self.copy_of(f, b, x, ph, None);
                let obs = self
                    .edge_syms(si, v)
                    .into_iter()
                    .map(|sy| (sy, after, None))
                    .collect();
                self.g[p].obs = obs;
                p
            };
            self.g[x].spawn.push((f, t));
        }
    }

    /// The fault event of an unexpected motion `act` from state `n`.
    fn spawn_moves(&mut self, f: usize, b: usize, n: &str, act: &str, ctx: &mut Ctx<'_>) {
        let fd = &self.c.faults[f];
        let (Some(x), Ok((i, r, _))) = (self.state_of(n), edge_in(act, self.symbols, self.signals))
        else {
            ctx.err(
                codes::DIAGNOSER_FAULT.id,
                n,
                format!(
                    "fault `{}`: `Moves({n}, {act})` needs a state and an edge",
                    fd.id
                ),
            );
            return;
        };
        match self
            .evs
            .iter()
            .find(|e| e.from == x && e.sig == i && e.rise == r)
        {
            Some(e) => {
                let t = self.copy_of(f, b, e.to, Phase::Untimed, None);
                self.g[x].spawn.push((f, t));
            }
            None => ctx.err(
                codes::DIAGNOSER_FAULT.id,
                n,
                format!("fault `{}`: `{act}` is not expected in `{n}`", fd.id),
            ),
        }
    }

    /// The next order of the controller ends an unexpected motion: where the fault
    /// blocks the plant (a stuck actuator), it stays blocked; elsewhere the order restarts
    /// the clock and the plant follows its windows again. (behaviour, phase, lead)
    fn after_order(&self, f: usize, b: usize, to: usize) -> (usize, Phase, Option<u64>) {
        self.c.faults[f]
            .behaviours
            .iter()
            .position(|bb| matches!(bb, Behaviour::Blocked(l) if l.contains(&self.states[to])))
            .map_or((b, Phase::Timed, None), |bb| (bb, Phase::Blocked, None))
    }

    /// The longest the plant may stay in a state during an unexpected motion before one
    /// of its expected sensor edges, counted from entering it (the largest upper bound of
    /// the windows of its sensor evolutions); None when an order (counted with `orders`)
    /// or an unbounded window leaves it.
    fn hold_with(&self, y: usize, orders: bool) -> Option<u64> {
        let (signals, intervals) = (self.signals, self.intervals);
        let mut hold = Some(0u64);
        for e in self.evs.iter().filter(|e| {
            e.from == y
                && ((orders && !self.c.timed_orders) || signals[e.sig].var.space == Space::Input)
        }) {
            let bound = (signals[e.sig].var.space == Space::Input)
                .then(|| e.window.and_then(|k| intervals[k].hi))
                .flatten();
            hold = match (hold, bound) {
                (Some(h), Some(b)) => Some(h.max(b)),
                _ => None,
            };
        }
        hold.filter(|&h| h > 0)
    }

    fn hold_of(&self, y: usize) -> Option<u64> {
        self.hold_with(y, true)
    }

    /// The state an unexpected motion (`Moves`, `Jumps`) starts in.
    fn entry_of(&self, f: usize, b: usize) -> Option<usize> {
        match &self.c.faults[f].behaviours[b] {
            Behaviour::Jumps(_, m) => self.state_of(m),
            Behaviour::Moves(n, act) => {
                let (x, (i, r, _)) = (
                    self.state_of(n)?,
                    edge_in(act, self.symbols, self.signals).ok()?,
                );
                self.evs
                    .iter()
                    .find(|e| e.from == x && e.sig == i && e.rise == r)
                    .map(|e| e.to)
            }
            _ => None,
        }
    }

    /// How long an unexpected motion that started in `entry` may have been under way in
    /// `y` without showing its next sensor edge: the holds (and margins) along the way.
    /// Capped at the largest lower bound of the windows (from there on, every window
    /// opens at 0).
    fn lead_to(&self, entry: Option<usize>, y: usize) -> u64 {
        let max_lo = self.max_lo;
        let Some(entry) = entry else { return max_lo };
        let here = |z: usize| {
            self.hold_of(z)
                .map_or(max_lo, |h| h + self.margin)
                .min(max_lo)
        };
        let mut lead: Vec<Option<u64>> = vec![None; self.states.len()];
        lead[entry] = Some(here(entry));
        let mut work = vec![entry];
        while let Some(a) = work.pop() {
            let la = lead[a].unwrap_or(max_lo);
            for e in self
                .evs
                .iter()
                .filter(|e| e.from == a && self.signals[e.sig].var.space == Space::Input)
            {
                let l = (la + here(e.to)).min(max_lo);
                if lead[e.to].is_none_or(|o| o < l) {
                    lead[e.to] = Some(l);
                    work.push(e.to);
                }
            }
        }
        lead[y].unwrap_or(max_lo)
    }

    /// Builds the fault copies on the work list, each by its behaviour and phase.
    fn expand(&mut self) {
        while let Some(gi) = self.pending.pop() {
            let (f, x, ph) = (self.g[gi].mode.unwrap_or(0), self.g[gi].x, self.g[gi].phase);
            let (b, early) = self.beh_of[gi];
            if ph == Phase::Pending {
                continue;
            }
            let beh = self.c.faults[f].behaviours[b].clone();
            let (mut obs, silent) = match (&beh, ph) {
                (Behaviour::StuckAt(s, _), _) => self.expand_stuck(gi, f, b, x, s),
                (Behaviour::Spurious(s, v), Phase::Spur) => {
                    self.expand_spurious(gi, f, b, x, s, *v)
                }
                (Behaviour::Unguarded, _) => (self.expand_unguarded(gi, f, b, x), Vec::new()),
                (Behaviour::Blocked(list), Phase::Blocked) => {
                    (self.expand_blocked(gi, f, b, x, list), Vec::new())
                }
                (_, Phase::Untimed) => (self.expand_untimed(gi, f, b, x), Vec::new()),
                (_, _) => (self.expand_timed(gi, f, b, x, early), Vec::new()),
            };
            obs.sort_unstable();
            obs.dedup();
            self.g[gi].obs = obs;
            self.g[gi].silent = silent;
        }
    }

    /// A stuck sensor: its edges are hidden, the rest follows the model.
    fn expand_stuck(
        &mut self,
        gi: usize,
        f: usize,
        b: usize,
        x: usize,
        s: &str,
    ) -> (Vec<Obs>, Vec<usize>) {
        let evs = self.evs;
        let si = self
            .signals
            .iter()
            .position(|z| z.name == s)
            .unwrap_or(usize::MAX);
        let (mut obs, mut silent, mut windows) = (Vec::new(), Vec::new(), Vec::new());
        for e in evs.iter().filter(|e| e.from == x) {
            let t = self.copy_of(f, b, e.to, Phase::Timed, None);
            windows.push(e.window);
            if e.sig == si {
                silent.push(t);
            } else {
                obs.extend(e.syms.iter().map(|&sy| (sy, t, e.window)));
            }
        }
        let d = self.deadline_of(&windows);
        obs.extend(self.tmo_loops(d, true).into_iter().map(|s| (s, gi, None)));
        self.g[gi].deadline = d;
        (obs, silent)
    }

    /// A spurious value shown: the sensor's edges are hidden until it goes back.
    fn expand_spurious(
        &mut self,
        gi: usize,
        f: usize,
        b: usize,
        x: usize,
        s: &str,
        v: bool,
    ) -> (Vec<Obs>, Vec<usize>) {
        let evs = self.evs;
        let si = self
            .signals
            .iter()
            .position(|z| z.name == s)
            .unwrap_or(usize::MAX);
        let (mut obs, mut silent) = (Vec::new(), Vec::new());
        for e in evs.iter().filter(|e| e.from == x) {
            let t = self.copy_of(f, b, e.to, Phase::Spur, None);
            if e.sig == si {
                silent.push(t);
            } else {
                obs.extend(e.syms.iter().map(|&sy| (sy, t, None)));
            }
        }
        let back = self.copy_of(f, b, x, Phase::Timed, None);
        if ((self.values[x] >> si) & 1 == 1) == v {
            silent.push(back);
        } else {
            obs.extend(
                self.edge_syms(si, !v)
                    .into_iter()
                    .map(|sy| (sy, back, None)),
            );
        }
        obs.extend(
            (self.first_tmo..self.syms.len())
                .filter(|&s| s != self.pulse_sym)
                .map(|s| (s, gi, None)),
        );
        (obs, silent)
    }

    /// An unguarded evolution: every symbol of an expected edge, guard or not.
    fn expand_unguarded(&mut self, gi: usize, f: usize, b: usize, x: usize) -> Vec<Obs> {
        let evs = self.evs;
        let (mut obs, mut windows) = (Vec::new(), Vec::new());
        for e in evs.iter().filter(|e| e.from == x) {
            let t = self.copy_of(f, b, e.to, Phase::Timed, None);
            obs.extend(
                self.edge_syms(e.sig, e.rise)
                    .into_iter()
                    .map(|sy| (sy, t, e.window)),
            );
            windows.push(e.window);
        }
        let d = self.deadline_of(&windows);
        obs.extend(self.tmo_loops(d, true).into_iter().map(|s| (s, gi, None)));
        self.g[gi].deadline = d;
        obs
    }

    /// A blocked plant.
    fn expand_blocked(
        &mut self,
        gi: usize,
        f: usize,
        b: usize,
        x: usize,
        list: &[String],
    ) -> Vec<Obs> {
        let (c, signals, evs, states) = (self.c, self.signals, self.evs, self.states);
        let mut obs = Vec::new();
        // Orders, and the edges of a part the fault does not stop
        // (`independent`), go on as expected; the plant stays blocked.
        for e in evs.iter().filter(|e| e.from == x).filter(|e| {
            signals[e.sig].var.space == Space::Output
                || c.independent.contains(&signals[e.sig].name)
        }) {
            let t = self.copy_of(f, b, e.to, Phase::Blocked, None);
            obs.extend(e.syms.iter().map(|&sy| (sy, t, None)));
        }
        // An order the model does not foresee here starts a new motion of the
        // plant (the next box, while the previous one is stuck): it goes on as
        // from wherever the model foresees that order, untimed, and stops again
        // where the fault blocks the plant.
        for (si, sig) in signals.iter().enumerate() {
            if sig.var.space != Space::Output {
                continue;
            }
            for rise in [true, false] {
                for sy in self.edge_syms(si, rise) {
                    if obs.iter().any(|&(o, _, _)| o == sy) {
                        continue;
                    }
                    let targets: Vec<usize> = evs
                        .iter()
                        .filter(|e| e.syms.contains(&sy))
                        .map(|e| e.to)
                        .collect();
                    if targets.is_empty() {
                        obs.push((sy, gi, None));
                    }
                    for to in targets {
                        let ph = if list.contains(&states[to]) {
                            Phase::Blocked
                        } else {
                            Phase::Untimed
                        };
                        let t = self.copy_of(f, b, to, ph, None);
                        obs.push((sy, t, None));
                    }
                }
            }
        }
        obs.extend((self.first_tmo..self.syms.len()).map(|s| (s, gi, None)));
        obs
    }

    /// An unexpected motion under way, until the next order.
    fn expand_untimed(&mut self, gi: usize, f: usize, b: usize, x: usize) -> Vec<Obs> {
        let (c, signals, evs, states) = (self.c, self.signals, self.evs, self.states);
        let mut obs = Vec::new();
        // The motion goes on with the plant's own dynamics: a sensor edge it
        // expects comes at the latest at the upper bound of its window, counted
        // from entering the state (a bound that can only be generous).
        for e in evs.iter().filter(|e| e.from == x) {
            let (tb, tph, te) = if signals[e.sig].var.space == Space::Output {
                self.after_order(f, b, e.to)
            } else if matches!(&c.faults[f].behaviours[b],
                Behaviour::Blocked(l) if l.contains(&states[e.to]))
            {
                // A motion restarted on a blocked plant stops where it blocks.
                (b, Phase::Blocked, None)
            } else {
                (b, Phase::Untimed, None)
            };
            let t = self.copy_of(f, tb, e.to, tph, te);
            obs.extend(e.syms.iter().map(|&sy| (sy, t, None)));
        }
        // A motion without its order (`Moves`): the controller never gave that
        // order, so it cannot take it back either; only the sensor windows
        // bound the hold.
        let hold = self.hold_with(
            x,
            !matches!(c.faults[f].behaviours[b], Behaviour::Moves(..)),
        );
        // The controller's order may catch up with a motion already under way
        // (the plant left without its order, or went back while the order
        // stayed): an actuator edge to the value this state already has. From
        // that clock event on, the plant's edges come within the windows, but
        // early by as much as the motion may have been under way: an early
        // timed copy, with that lead.
        let lead = self.lead_to(self.entry_of(f, b), x);
        for (i, sg) in signals.iter().enumerate() {
            if sg.var.space == Space::Output {
                let rise = (self.values[x] >> i) & 1 == 1;
                let t = self.copy_of(f, b, x, Phase::Timed, Some(lead));
                obs.extend(self.edge_syms(i, rise).into_iter().map(|sy| (sy, t, None)));
            }
        }
        obs.extend(
            (self.first_tmo..self.syms.len())
                .filter(|&s| !(hold.is_some() && s == self.motion_sym))
                .map(|s| (s, gi, None)),
        );
        self.g[gi].hold_ms = hold;
        obs
    }

    /// Normal-like copy after a spurious pulse or a move. An early copy (its clock event
    /// came up to `lead` ms after its motion started) has the lower bounds of its windows
    /// moved back by the lead, the upper ones stay (its deadline), until the next order.
    fn expand_timed(
        &mut self,
        gi: usize,
        f: usize,
        b: usize,
        x: usize,
        early: Option<u64>,
    ) -> Vec<Obs> {
        let (signals, evs, intervals) = (self.signals, self.evs, self.intervals);
        let (mut obs, mut windows) = (Vec::new(), Vec::new());
        for e in evs.iter().filter(|e| e.from == x) {
            let order = signals[e.sig].var.space == Space::Output;
            let (tb, tph, te) = if early.is_some() && order {
                self.after_order(f, b, e.to)
            } else {
                (b, Phase::Timed, early)
            };
            let t = self.copy_of(f, tb, e.to, tph, te);
            windows.push(e.window);
            let w = match (early, e.window) {
                (Some(lead), Some(k)) if intervals[k].lo > 0 && lead > 0 => {
                    Some(self.relaxed_window(k, lead))
                }
                (_, w) => w,
            };
            obs.extend(e.syms.iter().map(|&sy| (sy, t, w)));
        }
        let d = self.deadline_of(&windows);
        obs.extend(self.tmo_loops(d, true).into_iter().map(|s| (s, gi, None)));
        self.g[gi].deadline = d;
        obs
    }

    /// The window of interval `k` with its lower bound moved back by `lead` (`I9-270`),
    /// as an index after the intervals of the file.
    fn relaxed_window(&mut self, k: usize, lead: u64) -> usize {
        let intervals = self.intervals;
        let iv = &intervals[k];
        let id = format!("{}-{lead}", iv.id);
        let j = self
            .relaxed
            .iter()
            .position(|r| r.id == id)
            .unwrap_or_else(|| {
                self.relaxed.push(Interval {
                    id,
                    clock: iv.clock,
                    lo: iv.lo.saturating_sub(lead),
                    hi: iv.hi,
                });
                self.relaxed.len() - 1
            });
        intervals.len() + j
    }

    /// The automaton (transitions sorted) and the early copies' windows.
    fn finish(self) -> (Vec<GState>, Vec<Interval>) {
        let mut g = self.g;
        for st in &mut g {
            st.obs.sort_unstable();
            st.spawn.sort_unstable();
        }
        (g, self.relaxed)
    }
}

/// The expected evolutions; a guarded one adds its symbol, an unguarded one matches
/// every symbol of its edge.
fn expected_evolutions(
    c: &ComponentDef,
    symbols: &Symbols,
    signals: &[Sig],
    intervals: &[Interval],
    syms: &mut Vec<Symbol>,
    ctx: &mut Ctx<'_>,
) -> Vec<Ev> {
    let edge_of = |text: &str| edge_in(text, symbols, signals);
    let state_of = |n: &str| c.states.iter().position(|s| s.id == n);
    let interval_of = |n: &str| intervals.iter().position(|i| i.id == n);
    let mut evs: Vec<Ev> = Vec::new();
    let mut guarded_specs = Vec::new();
    for e in &c.expected {
        let (Some(from), Some(to)) = (state_of(&e.from), state_of(&e.to)) else {
            ctx.err(
                codes::DIAGNOSER_UNKNOWN_STATE.id,
                if state_of(&e.from).is_none() {
                    &e.from
                } else {
                    &e.to
                },
                format!("unknown state in evolution `{}` → `{}`", e.from, e.to),
            );
            continue;
        };
        let window = match &e.within {
            None => None,
            Some(w) => match interval_of(w) {
                Some(k) => Some(k),
                None => {
                    ctx.err(
                        codes::DIAGNOSER_INTERVAL.id,
                        w,
                        format!("unknown interval `{w}`"),
                    );
                    continue;
                }
            },
        };
        match edge_of(&e.event) {
            Ok((i, rise, guard)) => {
                let sym = if let Some(guard) = guard {
                    let name = e.event.split_whitespace().collect::<Vec<_>>().join(" ");
                    let k = syms.iter().position(|s| s.name == name).unwrap_or_else(|| {
                        syms.push(Symbol {
                            name,
                            edge: Some((i, rise)),
                            guard: Some(guard.clone()),
                            timeout: None,
                        });
                        syms.len() - 1
                    });
                    Some(k)
                } else {
                    None
                };
                guarded_specs.push(sym);
                evs.push(Ev {
                    from,
                    syms: sym.map_or_else(Vec::new, |k| vec![k]),
                    to,
                    window,
                    sig: i,
                    rise,
                });
            }
            Err(m) => ctx.err(codes::DIAGNOSER_EDGE.id, &e.event, m),
        }
    }
    // Unguarded evolutions match every symbol of their edge.
    for ev in &mut evs {
        if ev.syms.is_empty() {
            ev.syms = syms
                .iter()
                .enumerate()
                .filter(|(_, s)| s.edge == Some((ev.sig, ev.rise)))
                .map(|(k, _)| k)
                .collect();
        }
    }
    evs
}

/// The component's clocks (the bare edges that start its intervals) and its intervals,
/// bounds resolved.
fn component_intervals(
    c: &ComponentDef,
    symbols: &Symbols,
    signals: &[Sig],
    ctx: &mut Ctx<'_>,
) -> (Vec<(usize, bool)>, Vec<Interval>) {
    let edge_of = |text: &str| edge_in(text, symbols, signals);
    let mut clocks: Vec<(usize, bool)> = Vec::new();
    let mut raw: Vec<(String, usize, Bound, Bound)> = Vec::new();
    for iv in &c.intervals {
        match edge_of(&iv.after) {
            Ok((i, r, None)) => {
                let k = clocks.iter().position(|&e| e == (i, r)).unwrap_or_else(|| {
                    clocks.push((i, r));
                    clocks.len() - 1
                });
                raw.push((iv.id.clone(), k, iv.lo.clone(), iv.hi.clone()));
            }
            Ok(_) => ctx.err(
                codes::DIAGNOSER_CLOCK_EVENT.id,
                &iv.after,
                format!("clock event `{}` must be a bare edge", iv.after),
            ),
            Err(m) => ctx.err(codes::DIAGNOSER_CLOCK_EVENT.id, &iv.after, m),
        }
    }
    let resolve = |b: &Bound, depth: usize| -> Result<Option<u64>, String> {
        fn go(
            b: &Bound,
            raw: &[(String, usize, Bound, Bound)],
            depth: usize,
        ) -> Result<Option<u64>, String> {
            if depth > 16 {
                return Err("interval bounds refer to each other in a cycle".into());
            }
            let find = |n: &str| {
                raw.iter()
                    .find(|r| r.0 == n)
                    .ok_or_else(|| format!("unknown interval `{n}`"))
            };
            match b {
                Bound::Ms(v) => Ok(Some(*v)),
                Bound::Never => Ok(None),
                Bound::LoOf(n) => go(&find(n)?.2, raw, depth + 1),
                Bound::HiOf(n) => go(&find(n)?.3, raw, depth + 1),
            }
        }
        go(b, &raw, depth)
    };
    let mut intervals = Vec::new();
    for (id, clock, lo, hi) in &raw {
        match (resolve(lo, 0), resolve(hi, 0)) {
            (Ok(Some(lo)), Ok(hi)) => intervals.push(Interval {
                id: id.clone(),
                clock: *clock,
                lo,
                hi,
            }),
            (Ok(None), _) => ctx.err(
                codes::DIAGNOSER_INTERVAL.id,
                id,
                format!("interval `{id}` has no lower bound"),
            ),
            (Err(m), _) | (_, Err(m)) => ctx.err(
                codes::DIAGNOSER_INTERVAL.id,
                id,
                format!("interval `{id}`: {m}"),
            ),
        }
    }
    (clocks, intervals)
}

/// The evolutions the model does not expect, each with the constraint that prunes it
/// (an actuator edge the filter forbids), then each deadline's time-out.
fn unexpected_evolutions(
    states: &[String],
    signals: &[Sig],
    values: &[u64],
    evs: &[Ev],
    filter: Option<&ConstraintSet>,
    g: &[GState],
    intervals: &[Interval],
) -> Vec<Unexpected> {
    let mut unexpected = Vec::new();
    for (x, name) in states.iter().enumerate() {
        for (i, s) in signals.iter().enumerate() {
            let rise = (values[x] >> i) & 1 == 0;
            if evs
                .iter()
                .any(|e| e.from == x && e.sig == i && e.rise == rise)
            {
                continue;
            }
            let mut pruned_by = None;
            if let (Some(set), Space::Output) = (filter, s.var.space) {
                let mut term = Vec::new();
                for (j, t) in signals.iter().enumerate() {
                    let v = (values[x] >> j) & 1 == 1;
                    term.push(Literal {
                        var: Var {
                            prev: true,
                            ..t.var
                        },
                        positive: v,
                    });
                    term.push(Literal {
                        var: t.var,
                        positive: if j == i { !v } else { v },
                    });
                }
                term.sort();
                pruned_by = set
                    .constraints
                    .iter()
                    .find(|k| implies(&term, &k.dnf))
                    .map(|k| k.id.clone());
            }
            unexpected.push(Unexpected {
                state: name.clone(),
                event: format!("{}({})", if rise { "RE" } else { "FE" }, s.name),
                pruned_by,
            });
        }
        if let Some(d) = g[x].deadline {
            unexpected.push(Unexpected {
                state: name.clone(),
                event: format!("tmo({})", intervals[d].id),
                pruned_by: None,
            });
        }
    }
    unexpected
}

/// The signal values of every state, propagated from the initial state along the
/// expected evolutions (a state not reached keeps the initial values).
fn state_values(
    c: &ComponentDef,
    signals: &[Sig],
    evs: &[Ev],
    initial: usize,
    init_val: u64,
    ctx: &mut Ctx<'_>,
) -> Vec<u64> {
    let mut values: Vec<Option<u64>> = vec![None; c.states.len()];
    values[initial] = Some(init_val);
    let mut work = vec![initial];
    while let Some(x) = work.pop() {
        let Some(v) = values[x] else { continue };
        for ev in evs.iter().filter(|e| e.from == x) {
            let before = (v >> ev.sig) & 1 == 1;
            if before == ev.rise {
                ctx.err(
                    codes::DIAGNOSER_INCONSISTENT_VALUES.id,
                    &c.states[x].id,
                    format!(
                        "in state `{}`, `{}` is already {}",
                        c.states[x].id,
                        signals[ev.sig].name,
                        u8::from(before)
                    ),
                );
                continue;
            }
            let nv = v ^ (1 << ev.sig);
            match values[ev.to] {
                None => {
                    values[ev.to] = Some(nv);
                    work.push(ev.to);
                }
                Some(o) if o != nv => ctx.err(
                    codes::DIAGNOSER_INCONSISTENT_VALUES.id,
                    &c.states[ev.to].id,
                    format!(
                        "state `{}` is reached with different signal values",
                        c.states[ev.to].id
                    ),
                ),
                Some(_) => {}
            }
        }
    }
    values.iter().map(|v| v.unwrap_or(init_val)).collect()
}

/// The component's estimates: (name, expression).
fn component_estimates(
    c: &ComponentDef,
    symbols: &Symbols,
    ctx: &mut Ctx<'_>,
) -> Vec<(String, Dnf)> {
    let mut estimates = Vec::new();
    for e in &c.estimates {
        match parse_str(&e.expr).and_then(|x| x.to_dnf(symbols)) {
            Ok(d) => estimates.push((crate::symbols::estimate_name(&e.sensor), d)),
            Err(m) => ctx.err(
                codes::DIAGNOSER_ESTIMATE.id,
                &e.expr,
                format!("estimate of `{}`: {}", e.sensor, m.message),
            ),
        }
    }
    estimates
}

/// Checks the sensors the component assumes and those it declares independent.
fn check_assumptions(c: &ComponentDef, symbols: &Symbols, signals: &[Sig], ctx: &mut Ctx<'_>) {
    for (field, list) in [("assumes", &c.assumes), ("assumes_item", &c.assumes_item)] {
        for a in list {
            if !matches!(symbols.lookup(a), Some((Space::Input, _))) {
                ctx.err(
                    codes::DIAGNOSER_UNKNOWN_SIGNAL.id,
                    a,
                    format!("`{field}`: `{a}` is not a sensor of the plant"),
                );
            }
        }
    }
    for a in &c.independent {
        if !signals
            .iter()
            .any(|s| &s.name == a && s.var.space == Space::Input)
        {
            ctx.err(
                codes::DIAGNOSER_UNKNOWN_SIGNAL.id,
                a,
                format!("`independent`: `{a}` is not a sensor of the component"),
            );
        }
    }
}

/// The component's signals, resolved in the plant (at most 64).
fn component_signals(c: &ComponentDef, symbols: &Symbols, ctx: &mut Ctx<'_>) -> Vec<Sig> {
    let mut signals = Vec::new();
    for s in &c.signals {
        match symbols.lookup(s) {
            Some((space @ (Space::Input | Space::Output), index)) => signals.push(Sig {
                name: s.clone(),
                var: Var {
                    space,
                    index,
                    prev: false,
                },
            }),
            _ => ctx.err(
                codes::DIAGNOSER_UNKNOWN_SIGNAL.id,
                s,
                format!("`{s}` is not a sensor or actuator of the plant"),
            ),
        }
    }
    if signals.len() > 64 {
        ctx.err(
            codes::DIAGNOSER_UNKNOWN_SIGNAL.id,
            &c.id,
            "a component observes at most 64 signals".into(),
        );
    }
    signals
}

/// The edge of an expression: (signal, rising, guard); None for the guard when a term
/// has no other literal.
fn edge_in(
    text: &str,
    symbols: &Symbols,
    signals: &[Sig],
) -> Result<(usize, bool, Option<Dnf>), String> {
    let sig_of = |v: Var| {
        signals
            .iter()
            .position(|s| s.var.space == v.space && s.var.index == v.index)
    };
    let e = parse_str(text).map_err(|e| format!("`{text}`: {}", e.message))?;
    let d = e
        .to_dnf(symbols)
        .map_err(|e| format!("`{text}`: {}", e.message))?;
    let mut edge: Option<(usize, bool)> = None;
    let mut guard: Dnf = Vec::new();
    let mut unguarded = false;
    for term in &d {
        let mut here = None;
        for l in term {
            if !l.var.prev {
                continue;
            }
            let now = Var {
                prev: false,
                ..l.var
            };
            if let Some(n) = term
                .iter()
                .find(|m| m.var == now && m.positive != l.positive)
                && let Some(i) = sig_of(now)
            {
                here = Some((i, n.positive));
            }
        }
        let Some((i, rise)) = here else {
            return Err(format!(
                "`{text}`: every term needs an edge RE(x)/FE(x) of a component signal"
            ));
        };
        if edge.replace((i, rise)).is_some_and(|e| e != (i, rise)) {
            return Err(format!("`{text}` has more than one edge"));
        }
        let now = signals[i].var;
        let rest: Vec<Literal> = term
            .iter()
            .copied()
            .filter(|l| !(l.var == now || l.var == Var { prev: true, ..now }))
            .collect();
        if rest.is_empty() {
            unguarded = true;
        }
        guard.push(rest);
    }
    let Some((i, rise)) = edge else {
        return Err(format!(
            "`{text}` has no edge RE(x)/FE(x) of a component signal"
        ));
    };
    Ok((i, rise, if unguarded { None } else { Some(guard) }))
}

/// The signal values of the initial state.
fn initial_values(c: &ComponentDef, symbols: &Symbols, signals: &[Sig], ctx: &mut Ctx<'_>) -> u64 {
    let sig_of = |v: Var| {
        signals
            .iter()
            .position(|s| s.var.space == v.space && s.var.index == v.index)
    };
    let mut init_val = 0u64;
    match term_of(&c.initial_values, symbols) {
        Ok(t) => {
            for l in t {
                match sig_of(l.var) {
                    Some(i) if !l.var.prev => {
                        if l.positive {
                            init_val |= 1 << i;
                        }
                    }
                    _ => ctx.err(
                        codes::DIAGNOSER_INITIAL_VALUES.id,
                        &c.initial_values,
                        format!("`{}`: only component signals at t", c.initial_values),
                    ),
                }
            }
        }
        Err(m) => ctx.err(codes::DIAGNOSER_INITIAL_VALUES.id, &c.initial_values, m),
    }
    init_val
}

/// The component's partitions, and checks of its injections.
fn component_partitions(c: &ComponentDef, symbols: &Symbols, ctx: &mut Ctx<'_>) -> Vec<Partition> {
    let faults: Vec<String> = c.faults.iter().map(|f| f.id.clone()).collect();
    let mut partitions = Vec::new();
    for p in &c.partitions {
        let mut fs = Vec::new();
        for f in &p.faults {
            match faults.iter().position(|x| x == f) {
                Some(k) => fs.push(k),
                None => ctx.err(
                    codes::DIAGNOSER_PARTITION_OR_INJECTION.id,
                    f,
                    format!("partition `{}` names unknown fault `{f}`", p.id),
                ),
            }
        }
        for a in &p.actuators {
            if !matches!(symbols.lookup(a), Some((Space::Output, _))) {
                ctx.err(
                    codes::DIAGNOSER_PARTITION_OR_INJECTION.id,
                    a,
                    format!(
                        "partition `{}` names `{a}`, not an actuator of the plant",
                        p.id
                    ),
                );
            }
        }
        partitions.push(Partition {
            id: p.id.clone(),
            faults: fs,
            sensor: p.sensor.clone(),
            stop: p.stop,
        });
    }
    for i in &c.injections {
        for e in &i.expected {
            if !c.partitions.iter().any(|p| &p.id == e) {
                ctx.err(
                    codes::DIAGNOSER_PARTITION_OR_INJECTION.id,
                    &i.name,
                    format!(
                        "injection `{}` expects `{e}`, not a partition of `{}`",
                        i.name, c.id
                    ),
                );
            }
        }
        if let Some(when) = &i.when
            && let Err(e) = parse_str(when).and_then(|x| x.to_dnf(symbols))
        {
            ctx.err(
                codes::DIAGNOSER_PARTITION_OR_INJECTION.id,
                when,
                format!("injection `{}`: `when`: {}", i.name, e.message),
            );
        }
    }
    partitions
}

/// A problem at the start of the file (for errors not tied to a name).
pub fn at_start(file: &Path, code: &'static str, msg: String) -> Problem {
    Problem::error(code, msg, Some(Location::new(file, 1, 1)))
}
