//! The decentralized diagnoser at run time: one state estimate per component (the set
//! of automaton states consistent with what was observed, Sampath-style), updated on the
//! edges of the component's signals and on the ends of its time windows, with one
//! decision per fault partition and the flags, intervals and estimates it publishes.

use super::build::{Compiled, Component, Phase};
use crate::expr::eval_dnf;
use crate::frame::Frame;
use crate::symbols::{Space, Symbols};
use crate::time::Millis;
use serde::Serialize;
use std::collections::BTreeSet;

/// How sure a decision is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Certainty {
    /// `{N}`: no fault of the partition.
    Normal,
    /// `{N, F_j}`: cannot decide.
    Ambiguous,
    /// `{F_j}`: a fault of the partition with certainty.
    Certain,
}

/// The decision of one partition.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Decision {
    /// Certainty.
    pub certainty: Certainty,
    /// Fault labels of the partition still possible.
    pub faults: Vec<String>,
}

/// A certain diagnosis, for the run report.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Diagnosis {
    /// When, ms.
    pub time_ms: u64,
    /// Component.
    pub component: String,
    /// Partition.
    pub partition: String,
    /// The fault (several labels when they cannot be told apart).
    pub fault: String,
    /// Certainty: certain, or `ambiguous` for a stop on the safe side (the component is
    /// certainly faulty and a stopping partition is among its candidates, all listed in
    /// `fault`); `unexplained` entries say so in `fault`.
    pub certainty: Certainty,
}

/// Which certain decisions of a component wait on its interface (see
/// [`Diagnosers::interface_blocks`]).
#[derive(Clone, Copy, Debug, Default)]
struct Wait {
    /// Every partition's (a neighbour suspects a sensor the model `assumes`).
    all: bool,
    /// The sensor partitions' (a neighbour suspects a sensor it `assumes_item`).
    sensors: bool,
    /// The sensor partitions', for the plant to confirm (`confirm_ms`): unlike the
    /// waits above, the doubt's safe-side stop still runs meanwhile.
    confirm: bool,
}

impl Wait {
    fn applies_to(self, p: &super::build::Partition) -> bool {
        self.all || ((self.sensors || self.confirm) && p.sensor.is_some())
    }
}

#[derive(Clone, Debug)]
struct Run {
    h: Vec<(u32, i64)>,
    clock: Option<(usize, i64)>,
    /// The intervals whose time-out was emitted since the clock event (a bit each;
    /// a component may have more than 64 with the windows of its early copies).
    emitted: Vec<u64>,
    next_deadline: i64,
    next_boundary: i64,
    latched: Vec<bool>,
    /// Per partition: certainty and the fault indices still possible.
    decisions: Vec<(Certainty, Vec<usize>)>,
    unexplained: bool,
    /// Restarted by the operator's reset (after a trip, a repair or a
    /// re-initialisation) with items half-way whose clocks the model does not know; it
    /// decides nothing with certainty until its estimate is back in its initial state
    /// with the normal mode only.
    resyncing: bool,
    started: bool,
    /// Suspended by the filter's hold, or reset by the operator: the restart does not
    /// know the clock.
    held: bool,
    /// Since when a certain decision waits on the component's interface (see
    /// [`Diagnosers::interface_blocks`]).
    deferred: Option<i64>,
    /// The normal mode is among the hypotheses.
    normal_possible: bool,
    /// The plausibility stage holds a sensor the component assumes (see
    /// [`Diagnosers::follow_held_assumptions`]).
    tainted: bool,
    /// Since when the component is in doubt between a stopping fault that stops items
    /// and a sensor fault it cannot estimate, and those candidates (see
    /// [`safe_side_stop`]).
    doubt: Option<(i64, String)>,
    /// The clock is not known (after a hold): every window is open and nothing times
    /// out until the next clock event.
    clock_unknown: bool,
    def_aux: Vec<Option<u32>>,
    interval_aux: Vec<Option<u32>>,
    estimate_aux: Vec<Option<u32>>,
    /// Per estimate: the sensor's signal index in the component and the fault indices
    /// of the partition about it (see [`state_value`]).
    estimate_of: Vec<Option<(usize, Vec<usize>)>>,
}

/// The diagnosers of a plant.
#[derive(Clone, Debug)]
pub struct Diagnosers {
    /// The compiled models.
    pub compiled: Compiled,
    runs: Vec<Run>,
    by_signal: [Vec<Vec<usize>>; 2],
    /// Whether a component's time matters (intervals or deadlines).
    timed: Vec<bool>,
    /// When each component must be looked at even without an edge (`i64::MIN`: not
    /// started; `i64::MAX`: never), kept dense for the per-cycle scan.
    wake: Vec<i64>,
    /// Certain diagnoses so far, in order.
    pub diagnoses: Vec<Diagnosis>,
    /// Per component; components with the same automaton share one (a plant of many
    /// identical parts keeps one table per part type in the cache, not one per part).
    tables: Vec<std::sync::Arc<Tables>>,
    work: Work,
    touched: Vec<usize>,
    /// The filter held the outputs in the previous cycle.
    was_held: bool,
    /// Per component: the partitions of other components that cover a sensor it
    /// assumes (component, partition, and true for a sensor it `assumes_item`).
    interface: Vec<Vec<(usize, usize, bool)>>,
    /// The components with such an interface, or with a `confirm_ms` (the only ones
    /// whose decisions can wait).
    with_interface: Vec<usize>,
    /// Per component: the `sus_` auxiliaries of the sensors it `assumes` (its orders
    /// are given on them), set while the plausibility stage holds the sensor. Not those
    /// it `assumes_item`: a box held on C6 is still evidence about the exit's drive.
    held_assumed: Vec<Vec<u32>>,
}

/// What the run time derives once from a compiled component.
#[derive(Clone, Debug, Default)]
struct Tables {
    /// The unobservable closure of each automaton state (itself included only when a
    /// fault event leads back to it): target, and whether the path takes a fault event
    /// (then the target starts now, the latest possible moment).
    /// Flat: the closure of `q` is `closure[closure_at[q]..closure_at[q + 1]]`.
    closure: Vec<(u32, bool)>,
    /// See `closure`.
    closure_at: Vec<u32>,
    /// The time-out symbol of each interval.
    timeout_sym: Vec<Option<usize>>,
    /// Candidate symbols of each signal edge (`[falling, rising]`): the guarded ones
    /// first, then the unguarded one.
    by_edge: Vec<[Vec<usize>; 2]>,
    /// The observable transitions of state `q` are `obs[obs_at[q]..obs_at[q + 1]]`,
    /// sorted by symbol: found by a short search in the state's own list. (A dense
    /// state × symbol index costs that product whatever the model observes: 205 MB for
    /// the drilling station's derived head.)
    obs_at: Vec<u32>,
    /// Symbol, target and window interval of each observable transition.
    obs: Vec<(u32, u32, u32)>,
    /// What the updates read of each state, packed.
    info: Vec<Info>,
}

/// The per-state facts the updates read, packed together.
#[derive(Clone, Copy, Debug)]
struct Info {
    phase: Phase,
    mode: Option<u32>,
    deadline: Option<u32>,
    /// ms; a hold beyond `u32::MAX` ms (49 days) is kept as that.
    hold: Option<u32>,
}

impl Tables {
    /// The observable transitions of state `q` on symbol `sym`: target and window.
    fn observed(&self, q: usize, sym: usize) -> impl Iterator<Item = (u32, u32)> + '_ {
        let all = &self.obs[self.obs_at[q] as usize..self.obs_at[q + 1] as usize];
        let sym = sym as u32;
        let from = all.partition_point(|o| o.0 < sym);
        all[from..]
            .iter()
            .take_while(move |o| o.0 == sym)
            .map(|&(_, tq, w)| (tq, w))
    }

    /// Everything [`Tables::new`] reads of a component, as a stream of numbers: equal
    /// shapes give equal tables. A stream, not a vector: a derived model's shape runs
    /// to tens of millions of numbers, hashed and compared without being stored.
    fn shape(c: &Component) -> impl Iterator<Item = u64> + '_ {
        let head = [
            c.g.len() as u64,
            c.symbols.len() as u64,
            c.signals.len() as u64,
            c.intervals.len() as u64,
        ];
        let symbols = c.symbols.iter().flat_map(|s| {
            [
                s.edge.map_or(0, |(i, r)| 1 + 2 * i as u64 + u64::from(r)),
                u64::from(s.guard.is_some()),
                s.timeout.map_or(0, |t| 1 + t as u64),
            ]
        });
        let states = c.g.iter().flat_map(|st| {
            [
                st.phase as u64,
                st.mode.map_or(0, |m| 1 + m as u64),
                st.deadline.map_or(0, |d| 1 + d as u64),
                st.hold_ms.map_or(0, |h| 1 + h),
                st.obs.len() as u64,
            ]
            .into_iter()
            .chain(
                st.obs
                    .iter()
                    .flat_map(|&(s, t, w)| [s as u64, t as u64, w.map_or(0, |w| 1 + w as u64)]),
            )
            .chain(std::iter::once(st.silent.len() as u64))
            .chain(st.silent.iter().map(|&x| x as u64))
            .chain(std::iter::once(st.spawn.len() as u64))
            .chain(st.spawn.iter().flat_map(|&(f, t)| [f as u64, t as u64]))
        });
        head.into_iter().chain(symbols).chain(states)
    }

    /// A hash of [`Tables::shape`] (FNV-1a over its numbers).
    fn shape_hash(c: &Component) -> u64 {
        Self::shape(c).fold(0xcbf2_9ce4_8422_2325, |h, v| {
            (h ^ v).wrapping_mul(0x0100_0000_01b3)
        })
    }

    fn new(c: &Component) -> Self {
        let n = c.g.len();
        let mut closure = Vec::new();
        let mut closure_at = Vec::with_capacity(n + 1);
        // Nodes (state, through a fault event): at most 2n, visited once each.
        let mut seen = vec![[false; 2]; n];
        let mut queue: Vec<(usize, bool)> = Vec::new();
        for q in 0..n {
            queue.clear();
            queue.push((q, false));
            seen[q][0] = true;
            let mut i = 0;
            while i < queue.len() {
                let (x, f) = queue[i];
                i += 1;
                for &(_, y) in &c.g[x].spawn {
                    if !seen[y][1] {
                        seen[y][1] = true;
                        queue.push((y, true));
                    }
                }
                for &y in &c.g[x].silent {
                    if !seen[y][usize::from(f)] {
                        seen[y][usize::from(f)] = true;
                        queue.push((y, f));
                    }
                }
            }
            closure_at.push(closure.len() as u32);
            for &(x, _) in &queue {
                if seen[x][0] || seen[x][1] {
                    let spawned = seen[x][1];
                    if x != q || spawned {
                        closure.push((x as u32, spawned));
                    }
                    seen[x] = [false; 2];
                }
            }
        }
        closure_at.push(closure.len() as u32);
        let timeout_sym = (0..c.intervals.len())
            .map(|k| c.symbols.iter().position(|s| s.timeout == Some(k)))
            .collect();
        let mut by_edge = vec![[Vec::new(), Vec::new()]; c.signals.len()];
        for guarded in [true, false] {
            for (k, s) in c.symbols.iter().enumerate() {
                if let Some((i, rise)) = s.edge
                    && s.guard.is_some() == guarded
                    && let Some(e) = by_edge.get_mut(i)
                {
                    e[usize::from(rise)].push(k);
                }
            }
        }
        let mut obs_at = Vec::with_capacity(n + 1);
        let mut obs = Vec::new();
        for st in &c.g {
            // `st.obs` is sorted by symbol.
            obs_at.push(obs.len() as u32);
            obs.extend(
                st.obs.iter().map(|&(sym, tq, w)| {
                    (sym as u32, tq as u32, w.map_or(NO_WINDOW, |w| w as u32))
                }),
            );
        }
        obs_at.push(obs.len() as u32);
        let info =
            c.g.iter()
                .map(|st| Info {
                    phase: st.phase,
                    mode: st.mode.map(|m| m as u32),
                    deadline: st.deadline.map(|k| k as u32),
                    hold: st.hold_ms.map(|h| u32::try_from(h).unwrap_or(u32::MAX)),
                })
                .collect();
        Self {
            closure,
            closure_at,
            timeout_sym,
            by_edge,
            obs_at,
            obs,
            info,
        }
    }
}

/// Scratch space of the updates, kept between cycles (no allocation per step).
#[derive(Clone, Debug, Default)]
struct Work {
    /// The closure of the estimate (its own states first, in its order).
    cl: Vec<(u32, i64)>,
    /// Per entry of `cl`: reached through a fault event, so it starts anew at every
    /// instant (its hold or pulse limit never falls due).
    renewed: Vec<bool>,
    /// The time `cl` was computed for, while the estimate has not changed since.
    cl_at: Option<i64>,
    /// The next estimate being built.
    next: Vec<(u32, i64)>,
    /// Position of a state in `cl` or `next` (`u32::MAX`: absent); all absent between uses.
    slot: Vec<u32>,
    /// Edges of the cycle: signal index, rising.
    edges: Vec<(usize, bool)>,
    /// Fault modes present in the estimate (last entry: normal).
    modes: Vec<bool>,
    /// Hypotheses a pulse or motion time-out leaves as they are.
    waiting: Vec<(u32, i64)>,
}

impl Work {
    fn for_component(c: &Component) -> Self {
        let mut w = Self::default();
        w.fit(c);
        w
    }

    fn fit(&mut self, c: &Component) {
        if self.slot.len() < c.g.len() {
            self.slot.resize(c.g.len(), u32::MAX);
        }
        if self.modes.len() < c.faults.len() + 1 {
            self.modes.resize(c.faults.len() + 1, false);
        }
    }
}

const ABSENT: u32 = u32::MAX;
/// An observable transition without a window.
const NO_WINDOW: u32 = u32::MAX;

const LONG_AGO: i64 = -1_000_000_000_000;

impl Diagnosers {
    /// Builds the run-time diagnosers; `symbols` must hold the auxiliaries of
    /// [`super::build::aux_names`].
    pub fn new(compiled: Compiled, symbols: &Symbols) -> Self {
        Self::build(compiled, symbols, true)
    }

    /// As [`Diagnosers::new`], but every component gets its own run-time tables even
    /// when its automaton is the same as another's: the cost of a plant whose parts are
    /// all different, for benchmarks.
    pub fn new_unshared(compiled: Compiled, symbols: &Symbols) -> Self {
        Self::build(compiled, symbols, false)
    }

    fn build(compiled: Compiled, symbols: &Symbols, share: bool) -> Self {
        let aux = |n: &str| match symbols.lookup(n) {
            Some((Space::Aux, i)) => Some(i),
            _ => None,
        };
        let mut by_signal = [
            vec![Vec::new(); symbols.len(Space::Input)],
            vec![Vec::new(); symbols.len(Space::Output)],
        ];
        let mut timed = Vec::new();
        let mut runs = Vec::new();
        for (ci, c) in compiled.components.iter().enumerate() {
            for s in &c.signals {
                let t = if s.var.space == Space::Input { 0 } else { 1 };
                if let Some(v) = by_signal[t].get_mut(s.var.index as usize) {
                    v.push(ci);
                }
            }
            timed.push(!c.intervals.is_empty() || c.g.iter().any(|q| q.deadline.is_some()));
            runs.push(Run {
                h: Vec::new(),
                clock: c.initial_clock.map(|k| (k, LONG_AGO)),
                emitted: vec![0; c.intervals.len().div_ceil(64)],
                next_deadline: i64::MAX,
                next_boundary: i64::MIN,
                latched: vec![false; c.partitions.len()],
                decisions: vec![(Certainty::Normal, Vec::new()); c.partitions.len()],
                unexplained: false,
                resyncing: false,
                started: false,
                held: false,
                deferred: None,
                normal_possible: true,
                doubt: None,
                tainted: false,
                clock_unknown: false,
                def_aux: c
                    .partitions
                    .iter()
                    .map(|p| aux(&format!("def_{}", p.id)))
                    .collect(),
                interval_aux: c.intervals.iter().map(|i| aux(&i.id)).collect(),
                estimate_aux: c.estimates.iter().map(|(n, _)| aux(n)).collect(),
                estimate_of: c.estimates.iter().map(|(n, _)| estimate_of(c, n)).collect(),
            });
        }
        let tables = share_tables(&compiled, share);
        let interface = interfaces(&compiled);
        let held_assumed: Vec<Vec<u32>> = compiled
            .components
            .iter()
            .map(|c| {
                c.assumes
                    .iter()
                    .filter_map(|s| aux(&crate::plausibility::suspect_name(s)))
                    .collect()
            })
            .collect();
        let with_interface = (0..compiled.components.len())
            .filter(|&i| {
                !interface[i].is_empty()
                    || !held_assumed[i].is_empty()
                    || compiled.components[i].confirm_ms.is_some()
            })
            .collect();
        let mut work = Work::default();
        for c in &compiled.components {
            work.fit(c);
        }
        Self {
            compiled,
            wake: vec![i64::MIN; runs.len()],
            runs,
            by_signal,
            timed,
            diagnoses: Vec::new(),
            tables,
            work,
            touched: Vec::new(),
            was_held: false,
            interface,
            with_interface,
            held_assumed,
        }
    }

    /// The current decision of every partition: (component, partition, decision).
    pub fn decisions(&self) -> Vec<(String, String, Decision)> {
        let mut out = Vec::new();
        for (c, r) in self.compiled.components.iter().zip(&self.runs) {
            for (p, (certainty, faults)) in c.partitions.iter().zip(&r.decisions) {
                let d = Decision {
                    certainty: *certainty,
                    faults: faults.iter().map(|&f| c.faults[f].clone()).collect(),
                };
                out.push((c.id.clone(), p.id.clone(), d));
            }
        }
        out
    }

    /// Partitions whose flag is set (certain fault, latched): (partition, stop, sensor).
    pub fn flagged(&self) -> Vec<(String, bool, Option<String>)> {
        let mut out = Vec::new();
        for (c, r) in self.compiled.components.iter().zip(&self.runs) {
            for (p, &l) in c.partitions.iter().zip(&r.latched) {
                if l {
                    out.push((p.id.clone(), p.stop, p.sensor.clone()));
                }
            }
        }
        out
    }

    /// The state estimate of a component, as state names.
    pub fn estimate(&self, component: &str) -> Vec<String> {
        self.compiled
            .components
            .iter()
            .position(|c| c.id == component)
            .map(|i| {
                self.runs[i]
                    .h
                    .iter()
                    .map(|&(q, _)| self.compiled.components[i].g[q as usize].name.clone())
                    .collect()
            })
            .unwrap_or_default()
    }

    /// As [`Diagnosers::reset`], and writes the cleared flags into `frame` at once, so
    /// that the filter and the program of the next cycle read the sensors again (the
    /// diagnosers run after them in the cycle).
    pub fn reset_in(&mut self, frame: &mut Frame) {
        self.reset();
        let aux = frame.now_mut(Space::Aux);
        for r in &self.runs {
            for &a in r.def_aux.iter().flatten() {
                aux.set(a as usize, false);
            }
        }
    }

    /// Clears the latched flags (operator's acknowledgement after a repair) and restarts
    /// every estimate from the next cycle. Every component then decides nothing with
    /// certainty until its estimate is back in its initial state with the normal mode
    /// only: the reset comes after a stop (a trip, a repair, a re-initialisation, a
    /// live link back), with items half-way whose clocks the models do not know (a C5
    /// flicker that tripped CSs5 mid-evacuation had the right exit blame C7 with
    /// certainty after the restart, 5 of 100 runs).
    pub fn reset(&mut self) {
        for r in &mut self.runs {
            r.latched.iter_mut().for_each(|l| *l = false);
            r.started = false;
            r.unexplained = false;
            r.resyncing = true;
            r.doubt = None;
            // Restarted mid-motion (an order of the reset's cycle is taken as a value,
            // not as a clock event): the clock is unknown until the next clock event,
            // as after a hold.
            r.held = true;
        }
        self.wake.iter_mut().for_each(|w| *w = i64::MIN);
    }

    /// Follows one cycle: the frame holds inputs and applied outputs at t and t-1; the
    pub fn update(&mut self, now: Millis, frame: &mut Frame) {
        self.update_held(now, frame, false);
    }

    /// As [`Diagnosers::update`], `held` telling whether the filter holds the outputs
    /// in its safe state in this cycle: the orders then are the filter's, not the
    /// controller's, and the plant stops. The components whose model does not describe
    /// that (`follows_safe_state: false`) are suspended; they restart from the observed
    /// values in the first cycle after the hold, keeping their flags.
    pub fn update_held(&mut self, now: Millis, frame: &mut Frame, held: bool) {
        // The first held cycle still shows the plant's own sensor edges (those that
        // tripped the filter): they are followed, the forced orders are not. From the
        // next cycle on, the suspended components wait for the end of the hold.
        let first = held && !self.was_held;
        self.was_held = held;
        if held && !first {
            self.suspend_for_hold();
        }
        let t = i64::try_from(now.0).unwrap_or(i64::MAX);
        let mut touched = std::mem::take(&mut self.touched);
        touched.clear();
        for (k, space) in [(0usize, Space::Input), (1, Space::Output)] {
            let a = frame.now(space).words();
            let b = frame.prev(space).words();
            for (w, (x, y)) in a.iter().zip(b).enumerate() {
                let mut d = x ^ y;
                while d != 0 {
                    let bit = w * 64 + d.trailing_zeros() as usize;
                    d &= d - 1;
                    if let Some(cs) = self.by_signal[k].get(bit) {
                        touched.extend_from_slice(cs);
                    }
                }
            }
        }
        for (i, &w) in self.wake.iter().enumerate() {
            if t >= w {
                touched.push(i);
            }
        }
        self.follow_held_assumptions(frame, &mut touched);
        touched.sort_unstable();
        touched.dedup();
        for &i in &touched {
            let suspend = held && !self.compiled.components[i].follows_safe_state;
            if suspend && !first {
                continue;
            }
            self.component_cycle(i, t, frame, suspend);
            self.rewake(i);
        }
        // Certain decisions that waited on their interface: issued once they have
        // waited `settle_ms` and no neighbour suspects an assumed sensor (while one
        // does, they keep waiting).
        for k in 0..self.with_interface.len() {
            let i = self.with_interface[k];
            if self.runs[i].deferred.is_none() {
                continue;
            }
            let wait = self.interface_blocks(i, t);
            if !wait.all {
                let c = &self.compiled.components[i];
                let r = &mut self.runs[i];
                // Issued now, unless a sensor partition still waits on an item sensor.
                if !wait.sensors && !wait.confirm {
                    r.deferred = None;
                }
                decide(
                    c,
                    &self.tables[i],
                    r,
                    t,
                    &mut self.work,
                    wait,
                    &mut self.diagnoses,
                );
            }
        }
        if first {
            self.suspend_for_hold();
        }
        self.touched = touched;
    }

    /// Suspends the components whose model does not describe the filter's safe state:
    /// they restart from the observed values, clock unknown, once the hold ends.
    fn suspend_for_hold(&mut self) {
        for (i, c) in self.compiled.components.iter().enumerate() {
            if !c.follows_safe_state {
                self.runs[i].started = false;
                self.runs[i].held = true;
                self.wake[i] = i64::MIN;
            }
        }
    }

    /// A component whose model assumes a sensor (the loading ordered on C3) while the
    /// plausibility stage holds that sensor (`sus_C3`: a pulse the program took for a
    /// box) follows orders given on a lie: the certain decisions of its sensor
    /// partitions wait while the hold lasts (see [`Diagnosers::interface_blocks`]; its
    /// drive partitions do not: a welded roller still stops the plant), and when it ends the component
    /// restarts from the observed values with its clock unknown (as after the filter's
    /// hold), its flags kept: the windows it opened on the lie (the rollers run for a
    /// box that is still on the belt) would only time out into a wrong diagnosis.
    fn follow_held_assumptions(&mut self, frame: &Frame, touched: &mut Vec<usize>) {
        let aux = frame.now(Space::Aux);
        for k in 0..self.with_interface.len() {
            let i = self.with_interface[k];
            let held = self.held_assumed[i].iter().any(|&a| aux.get(a as usize));
            let r = &mut self.runs[i];
            if held && !r.tainted {
                r.tainted = true;
            } else if !held && r.tainted {
                r.tainted = false;
                r.started = false;
                r.held = true;
                r.doubt = None;
                self.wake[i] = i64::MIN;
                touched.push(i);
            }
        }
    }

    /// When component `i` must next be looked at without an edge.
    fn rewake(&mut self, i: usize) {
        let r = &self.runs[i];
        self.wake[i] = if !r.started {
            i64::MIN
        } else if self.timed[i] {
            r.next_deadline.saturating_add(1).min(r.next_boundary)
        } else {
            i64::MAX
        };
    }

    /// Whether a certain decision of component `ci` must wait at `t`: it assumes
    /// sensors of other components (its model took them as true), and either it has
    /// not waited its `settle_ms` yet (the neighbour may not have seen yet that its
    /// sensor lies: its window is still open), or a neighbour has lost its normal
    /// hypothesis while a fault of its partition covering the sensor is possible (the
    /// local anomaly may be that neighbour's fault), or lost track of its plant (it
    /// cannot vouch for the sensor until the operator's reset).
    ///
    /// The sensors it `assumes_item` make its sensor partitions wait likewise
    /// ([`Wait::sensors`]), not its drive partitions; so does its `confirm_ms`
    /// ([`Wait::confirm`]), for any component.
    fn interface_blocks(&self, ci: usize, t: i64) -> Wait {
        let c = &self.compiled.components[ci];
        let deferred = self.runs[ci].deferred;
        // Whether the certain decision (deferred since then) has waited less than `ms`.
        let waiting = |ms: u64| {
            let w = i64::try_from(ms).unwrap_or(i64::MAX);
            deferred.is_none_or(|since| t.saturating_sub(since) < w)
        };
        // A sensor partition's certain decision waits `confirm_ms` for the plant to
        // confirm it (see `ComponentDef::confirm_ms`).
        let confirming = c.confirm_ms.is_some_and(waiting);
        let tainted = self.runs[ci].tainted;
        let iface = &self.interface[ci];
        if iface.is_empty() {
            return Wait {
                all: false,
                sensors: tainted,
                confirm: confirming,
            };
        }
        let settling = waiting(c.settle_ms);
        let blocks = |item: bool| {
            let mut of_kind = iface.iter().filter(|e| e.2 == item).peekable();
            of_kind.peek().is_some()
                && (settling
                    || of_kind.any(|&(j, pj, _)| {
                        let r = &self.runs[j];
                        r.unexplained
                            || (!r.normal_possible
                                && r.decisions
                                    .get(pj)
                                    .is_some_and(|(c, _)| *c != Certainty::Normal))
                    }))
        };
        Wait {
            all: blocks(false),
            sensors: tainted || blocks(true),
            confirm: confirming,
        }
    }

    /// One cycle of component `ci`; with `orders_forced` (the first cycle the filter
    /// holds the outputs) its actuator edges are the filter's and are not followed.
    fn component_cycle(&mut self, ci: usize, t: i64, frame: &mut Frame, orders_forced: bool) {
        let wait = self.interface_blocks(ci, t);
        let c = &self.compiled.components[ci];
        let tab = &self.tables[ci];
        let ws = &mut self.work;
        let margin = i64::try_from(self.compiled.margin_ms).unwrap_or(0);
        let pulse = i64::try_from(self.compiled.pulse_max_ms).unwrap_or(0);
        let r = &mut self.runs[ci];
        ws.cl_at = None;
        let mut changed = false;
        // A certain fault of a partition that stops the system (DSTOP) freezes the
        // component's estimate until the operator's reset: the outputs forced to 0 are
        // the stop's doing, not the plant's, and would only read as unexplained.
        let stopped = c
            .partitions
            .iter()
            .zip(&r.latched)
            .any(|(p, &l)| p.stop && l);
        if !r.started {
            r.started = true;
            resync(c, r, frame, None);
            if std::mem::take(&mut r.held) {
                // The boxes stopped for as long as the hold lasted: the windows of
                // the motions under way no longer hold until the next order.
                r.clock = None;
                r.clock_unknown = true;
            }
            changed = true;
        } else if stopped {
            r.next_deadline = i64::MAX;
        } else {
            // Edges: actuators first, then sensors (or the reverse, `sensors_first`).
            collect_edges(c, frame, orders_forced, &mut ws.edges);
            for e in 0..ws.edges.len() {
                let (i, rise) = ws.edges[e];
                let cands = &tab.by_edge[i][usize::from(rise)];
                let sym = cands
                    .iter()
                    .copied()
                    .find(|&k| {
                        c.symbols[k]
                            .guard
                            .as_ref()
                            .is_some_and(|g| eval_dnf(g, frame))
                    })
                    .or_else(|| {
                        cands
                            .iter()
                            .copied()
                            .find(|&k| c.symbols[k].guard.is_none())
                    })
                    .unwrap_or(0);
                timeouts(c, tab, r, t, margin, pulse, ws, &mut self.diagnoses);
                let clock_event = c.clocks.iter().position(|&e| e == (i, rise));
                if clock_event.is_some() {
                    // A new period of the clock starts with this edge: the time-outs of
                    // the last one do not make the states it leads to expired (a state
                    // entered on the next order would be refused because some
                    // hypothesis timed out on its window in the previous cycle of the
                    // plant).
                    r.emitted.iter_mut().for_each(|w| *w = 0);
                }
                step(c, tab, r, sym, t, margin, true, ws);
                if let Some(k) = clock_event {
                    r.clock_unknown = false;
                    r.clock = Some((k, t));
                    r.emitted.iter_mut().for_each(|w| *w = 0);
                }
                if r.h.is_empty() {
                    if !r.unexplained {
                        r.unexplained = true;
                        self.diagnoses.push(Diagnosis {
                            time_ms: u64::try_from(t).unwrap_or(0),
                            component: c.id.clone(),
                            partition: String::new(),
                            fault: format!("unexplained {}", c.symbols[sym].name),
                            certainty: Certainty::Certain,
                        });
                    }
                    resync(c, r, frame, Some(t));
                    ws.cl_at = None;
                }
                changed = true;
            }
        }
        if !stopped {
            changed |= timeouts(c, tab, r, t, margin, pulse, ws, &mut self.diagnoses);
        }
        if !stopped && (changed || t > r.next_deadline) {
            // A deadline that passed without a time-out was one of a hypothesis that can
            // start as late as now (a fault that may occur at any time): it moved on.
            r.next_deadline = next_deadline(c, tab, r, t, margin, pulse, ws);
        }
        if changed {
            decide(c, tab, r, t, ws, wait, &mut self.diagnoses);
            r.next_boundary = i64::MIN;
        }
        if !stopped {
            safe_side_stop(c, r, t, &mut self.diagnoses);
        }
        // Flags, intervals, estimates.
        write_flags(c, r, t, frame);
    }
}

/// The components' tables; with `share`, components of the same shape share theirs.
fn share_tables(compiled: &Compiled, share: bool) -> Vec<std::sync::Arc<Tables>> {
    // By the shape's hash: the components already built with that hash, compared number
    // by number before their tables are shared (a collision builds its own).
    let mut shared: std::collections::HashMap<u64, Vec<(usize, std::sync::Arc<Tables>)>> =
        std::collections::HashMap::new();
    let mut out = Vec::with_capacity(compiled.components.len());
    for (i, c) in compiled.components.iter().enumerate() {
        if !share {
            out.push(std::sync::Arc::new(Tables::new(c)));
            continue;
        }
        let same = shared.entry(Tables::shape_hash(c)).or_default();
        let found = same
            .iter()
            .find(|(j, _)| Tables::shape(&compiled.components[*j]).eq(Tables::shape(c)));
        let tables = match found {
            Some((_, t)) => t.clone(),
            None => {
                let t = std::sync::Arc::new(Tables::new(c));
                same.push((i, t.clone()));
                t
            }
        };
        out.push(tables);
    }
    out
}

/// For each component, the partitions of the others whose sensors it assumes
/// (`(component, partition, item)`).
fn interfaces(compiled: &Compiled) -> Vec<Vec<(usize, usize, bool)>> {
    compiled
        .components
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut v = Vec::new();
            for (j, o) in compiled.components.iter().enumerate() {
                for (pj, p) in o.partitions.iter().enumerate() {
                    let Some(s) = p.sensor.as_ref().filter(|_| j != i) else {
                        continue;
                    };
                    if c.assumes.contains(s) {
                        v.push((j, pj, false));
                    }
                    if c.assumes_item.contains(s) {
                        v.push((j, pj, true));
                    }
                }
            }
            v
        })
        .collect()
}

/// The signal index in `c` of the sensor that the estimate `name` (`EST(C5)`) is about,
/// and the faults of the partition about it.
fn estimate_of(c: &Component, name: &str) -> Option<(usize, Vec<usize>)> {
    let i = c
        .signals
        .iter()
        .position(|s| crate::symbols::estimate_name(&s.name) == name)?;
    let p = c
        .partitions
        .iter()
        .find(|p| p.sensor.as_ref().is_some_and(|s| c.signals[i].name == *s))?;
    Some((i, p.faults.clone()))
}

/// The estimate from the plant's state: when every hypothesis explains the sensor by a
/// fault of its partition (the model saw the sensor lie and still follows the plant),
/// and every plant state they follow gives the sensor the same value, that value (the
/// table seen arriving at C5 before a dropout is at C5, even while its arrival window
/// is still open). None otherwise: the estimate's expression over the intervals, which
/// is pessimistic, decides (after a restart on the observed values, a faulty reading
/// may have chosen the states).
fn state_value(c: &Component, r: &Run, of: Option<&(usize, Vec<usize>)>) -> Option<bool> {
    let (i, faults) = of?;
    if !r.started || r.unexplained || r.clock_unknown || r.clock.is_none() {
        return None;
    }
    let mut values = r.h.iter().map(|&(q, _)| {
        let g = &c.g[q as usize];
        g.mode
            .is_some_and(|m| faults.contains(&m))
            .then_some(c.values[g.x] >> i & 1 == 1)
    });
    let first = values.next()??;
    values.all(|v| v == Some(first)).then_some(first)
}

#[allow(clippy::too_many_arguments)]
fn timeouts(
    c: &Component,
    tab: &Tables,
    r: &mut Run,
    t: i64,
    margin: i64,
    pulse: i64,
    ws: &mut Work,
    diagnoses: &mut Vec<Diagnosis>,
) -> bool {
    if t <= r.next_deadline {
        // Nothing falls due before the earliest deadline of the estimate.
        return false;
    }
    let mut any = false;
    for _ in 0..64 {
        let Some(sym) = due_timeout(c, tab, r, t, margin, pulse, ws) else {
            break;
        };
        if let Some(k) = c.symbols[sym].timeout {
            set_emitted(r, k);
        }
        // `tmo(pulse)` and `tmo(motion)` end the hypotheses whose own limit passed; the
        // others (a younger pulse or motion) wait on, unchanged.
        let mut waiting = std::mem::take(&mut ws.waiting);
        waiting.clear();
        waiting.extend(r.h.iter().copied().filter(|&(q, since)| {
            let st = &tab.info[q as usize];
            let limit = if sym == c.pulse_sym && st.phase == Phase::Spur {
                Some(pulse)
            } else if sym == c.motion_sym && st.phase == Phase::Untimed {
                st.hold.map(|h| i64::from(h).saturating_add(margin))
            } else {
                None
            };
            limit.is_some_and(|l| since.saturating_add(l) >= t)
        }));
        step(c, tab, r, sym, t, margin, true, ws);
        if !waiting.is_empty() {
            for &(q, since) in &waiting {
                match r.h.iter_mut().find(|(x, _)| *x == q) {
                    Some(e) => e.1 = e.1.max(since),
                    None => r.h.push((q, since)),
                }
            }
            r.h.sort_unstable();
        }
        ws.waiting = waiting;
        any = true;
        if r.h.is_empty() {
            if !r.unexplained {
                r.unexplained = true;
                diagnoses.push(Diagnosis {
                    time_ms: u64::try_from(t).unwrap_or(0),
                    component: c.id.clone(),
                    partition: String::new(),
                    fault: format!("unexplained {}", c.symbols[sym].name),
                    certainty: Certainty::Certain,
                });
            }
            // Nothing explains the silence: keep the last state estimate's normal states.
            r.h = (0..c.states.len() as u32).map(|q| (q, t)).collect();
            r.clock = None;
            r.next_deadline = i64::MIN;
            ws.cl_at = None;
            break;
        }
    }
    any
}

fn set_emitted(r: &mut Run, k: usize) {
    if let Some(w) = r.emitted.get_mut(k / 64) {
        *w |= 1 << (k % 64);
    }
}

fn was_emitted(r: &Run, k: usize) -> bool {
    r.emitted
        .get(k / 64)
        .is_some_and(|w| w & (1 << (k % 64)) != 0)
}

fn empty_run() -> Run {
    Run {
        h: Vec::new(),
        clock: None,
        emitted: Vec::new(),
        next_deadline: i64::MAX,
        next_boundary: i64::MIN,
        latched: Vec::new(),
        decisions: Vec::new(),
        unexplained: false,
        resyncing: false,
        started: false,
        held: false,
        deferred: None,
        normal_possible: true,
        doubt: None,
        tainted: false,
        clock_unknown: false,
        def_aux: Vec::new(),
        interval_aux: Vec::new(),
        estimate_aux: Vec::new(),
        estimate_of: Vec::new(),
    }
}

fn valuation(c: &Component, frame: &Frame) -> u64 {
    c.signals.iter().enumerate().fold(0, |acc, (i, s)| {
        acc | (u64::from(frame.now(s.var.space).get(s.var.index as usize)) << i)
    })
}

/// The component's signal edges of this cycle, in its edge order; actuator edges are
/// skipped when the orders are forced.
fn collect_edges(
    c: &Component,
    frame: &Frame,
    orders_forced: bool,
    edges: &mut Vec<(usize, bool)>,
) {
    edges.clear();
    for space in c.edge_order() {
        if space == Space::Output && orders_forced {
            continue;
        }
        for (i, s) in c.signals.iter().enumerate() {
            if s.var.space != space {
                continue;
            }
            let v = frame.now(space).get(s.var.index as usize);
            if v != frame.prev(space).get(s.var.index as usize) {
                edges.push((i, v));
            }
        }
    }
}

/// Writes a component's flags, and at an interval boundary its intervals and estimates.
fn write_flags(c: &Component, r: &mut Run, t: i64, frame: &mut Frame) {
    let aux = frame.now_mut(Space::Aux);
    for (p, a) in r.latched.iter().zip(&r.def_aux) {
        if let Some(a) = a {
            aux.set(*a as usize, *p);
        }
    }
    if t >= r.next_boundary {
        let mut next = i64::MAX;
        for (k, iv) in c.intervals.iter().enumerate() {
            let on = match r.clock {
                Some((ck, ct)) if ck == iv.clock => {
                    let lo = ct.saturating_add(i64::try_from(iv.lo).unwrap_or(i64::MAX));
                    let hi = iv.hi.map_or(i64::MAX, |h| {
                        ct.saturating_add(i64::try_from(h).unwrap_or(i64::MAX))
                    });
                    if lo > t {
                        next = next.min(lo);
                    } else if hi > t {
                        next = next.min(hi);
                    }
                    t >= lo && t < hi
                }
                _ => false,
            };
            if let Some(a) = r.interval_aux[k] {
                aux.set(a as usize, on);
            }
        }
        r.next_boundary = next;
        for (((_, d), a), of) in c.estimates.iter().zip(&r.estimate_aux).zip(&r.estimate_of) {
            let v = state_value(c, r, of.as_ref()).unwrap_or_else(|| eval_dnf(d, frame));
            if let Some(a) = a {
                frame.now_mut(Space::Aux).set(*a as usize, v);
            }
        }
    }
}

/// Restarts the estimate on the normal states that show the observed values.
fn resync(c: &Component, r: &mut Run, frame: &Frame, at: Option<i64>) {
    let v = valuation(c, frame);
    let t = at.unwrap_or(LONG_AGO);
    r.h = (0..c.states.len())
        .filter(|&x| c.values[x] == v)
        .map(|x| (x as u32, t))
        .collect();
    if r.h.is_empty() {
        r.h = (0..c.states.len() as u32).map(|x| (x, t)).collect();
    }
    r.next_deadline = i64::MIN;
    if at.is_some() {
        r.clock = None;
    }
}

/// The unobservable closure of the estimate at time `t` (fault events from normal
/// states, hidden plant moves) into `ws.cl`: the estimate's own states first, in its
/// order, so that `ws.cl[i]` is in the estimate exactly when `i < h.len()`. A state
/// reached through a fault event starts at `t` (the fault may occur at any time up to
/// now: the latest possible moment is the most permissive for pulse limits and holds);
/// one reached through hidden moves only keeps the latest start of its origins.
fn closure(tab: &Tables, h: &[(u32, i64)], t: i64, ws: &mut Work) {
    if ws.cl_at == Some(t) {
        return;
    }
    let (cl, renewed, slot) = (&mut ws.cl, &mut ws.renewed, &mut ws.slot);
    cl.clear();
    renewed.clear();
    for &(q, s) in h {
        slot[q as usize] = cl.len() as u32;
        cl.push((q, s));
        renewed.push(false);
    }
    for &(q, s) in h {
        let q = q as usize;
        let range = tab.closure_at[q] as usize..tab.closure_at[q + 1] as usize;
        for &(y, spawned) in &tab.closure[range] {
            let ty = if spawned { t } else { s };
            match slot[y as usize] {
                ABSENT => {
                    slot[y as usize] = cl.len() as u32;
                    cl.push((y, ty));
                    renewed.push(spawned);
                }
                j => {
                    let e = &mut cl[j as usize].1;
                    *e = (*e).max(ty);
                    renewed[j as usize] |= spawned;
                }
            }
        }
    }
    for &(q, _) in cl.iter() {
        slot[q as usize] = ABSENT;
    }
    ws.cl_at = Some(t);
}

fn window_ok(c: &Component, r: &Run, w: Option<usize>, t: i64, margin: i64) -> bool {
    let Some(k) = w else { return true };
    if r.clock_unknown {
        return true;
    }
    let iv = &c.intervals[k];
    match r.clock {
        Some((ck, ct)) if ck == iv.clock => {
            let e = t - ct;
            e >= i64::try_from(iv.lo).unwrap_or(i64::MAX) - margin
                && iv
                    .hi
                    .is_none_or(|h| e < i64::try_from(h).unwrap_or(i64::MAX) + margin)
        }
        _ => false,
    }
}

#[allow(clippy::too_many_arguments)]
fn step(
    c: &Component,
    tab: &Tables,
    r: &mut Run,
    sym: usize,
    t: i64,
    margin: i64,
    timed: bool,
    ws: &mut Work,
) {
    closure(tab, &r.h, t, ws);
    let (cl, next, slot) = (&ws.cl, &mut ws.next, &mut ws.slot);
    next.clear();
    let is_edge = c.symbols[sym].edge.is_some();
    for &(q, since) in cl {
        let phase = tab.info[q as usize].phase;
        for (tq, w) in tab.observed(q as usize, sym) {
            let tq = tq as usize;
            let w = (w != NO_WINDOW).then_some(w as usize);
            if timed && phase == Phase::Timed && !window_ok(c, r, w, t, margin) {
                continue;
            }
            // Spurious pulses count from their start; an unexpected motion from entering
            // each state; the rest from the phase's start.
            // A time-out looping on the state changes nothing.
            let keep = (tq == q as usize && !is_edge)
                || (tab.info[tq].phase == phase && phase != Phase::Untimed);
            let ns = if keep { since } else { t };
            match slot[tq] {
                ABSENT => {
                    slot[tq] = next.len() as u32;
                    next.push((tq as u32, ns));
                }
                j => {
                    let e = &mut next[j as usize].1;
                    *e = (*e).max(ns);
                }
            }
        }
    }
    for &(q, _) in next.iter() {
        slot[q as usize] = ABSENT;
    }
    // A timed state whose window already ended (its time-out was emitted since the
    // clock event) cannot be occupied: a silent move into it comes too late.
    next.retain(|&(q, _)| !expired(c, tab, r, q as usize));
    next.sort_unstable();
    std::mem::swap(&mut r.h, next);
    ws.cl_at = None;
    // The estimate changed: its deadlines are to be looked at again.
    r.next_deadline = i64::MIN;
}

fn expired(c: &Component, tab: &Tables, r: &Run, q: usize) -> bool {
    let st = &tab.info[q];
    match (st.phase, st.deadline, r.clock) {
        (Phase::Timed, Some(k), Some((ck, _))) => {
            let k = k as usize;
            c.intervals[k].clock == ck && was_emitted(r, k)
        }
        _ => false,
    }
}

fn deadline_time(
    c: &Component,
    tab: &Tables,
    r: &Run,
    q: usize,
    margin: i64,
) -> Option<(i64, usize)> {
    let st = &tab.info[q];
    if st.phase != Phase::Timed {
        return None;
    }
    let k = st.deadline? as usize;
    let iv = &c.intervals[k];
    let (ck, ct) = r.clock?;
    if ck != iv.clock || was_emitted(r, k) {
        return None;
    }
    Some((ct + i64::try_from(iv.hi?).ok()? + margin, k))
}

/// The time-outs that may fall due for the state at `ws.cl[i]`: (when, symbol).
fn due_of(
    c: &Component,
    tab: &Tables,
    r: &Run,
    i: usize,
    margin: i64,
    pulse: i64,
    ws: &Work,
) -> Option<(i64, usize)> {
    let (q, since) = ws.cl[i];
    // A limit counted from the state's start only applies to the estimate's own states,
    // and not to those a fault event keeps starting anew.
    let in_h = i < r.h.len() && !ws.renewed[i];
    let st = &tab.info[q as usize];
    if let Some((d, k)) = deadline_time(c, tab, r, q as usize, margin) {
        tab.timeout_sym[k].map(|s| (d, s))
    } else if st.phase == Phase::Spur && in_h {
        Some((since + pulse, c.pulse_sym))
    } else if st.phase == Phase::Untimed && in_h {
        // The hold of an untimed state of the estimate itself (not of its closure).
        let h = i64::from(st.hold?);
        Some((since.saturating_add(h).saturating_add(margin), c.motion_sym))
    } else {
        None
    }
}

/// The earliest time-out the estimate may fall due for at or after `t`: (when, symbol).
fn earliest_due(
    c: &Component,
    tab: &Tables,
    r: &Run,
    t: i64,
    margin: i64,
    pulse: i64,
    ws: &mut Work,
) -> Option<(i64, usize)> {
    closure(tab, &r.h, t, ws);
    let mut best: Option<(i64, usize)> = None;
    for i in 0..ws.cl.len() {
        if let Some((d, s)) = due_of(c, tab, r, i, margin, pulse, ws)
            && best.is_none_or(|(bd, _)| d < bd)
        {
            best = Some((d, s));
        }
    }
    best
}

fn next_deadline(
    c: &Component,
    tab: &Tables,
    r: &Run,
    t: i64,
    margin: i64,
    pulse: i64,
    ws: &mut Work,
) -> i64 {
    earliest_due(c, tab, r, t, margin, pulse, ws).map_or(i64::MAX, |(d, _)| d)
}

fn due_timeout(
    c: &Component,
    tab: &Tables,
    r: &Run,
    t: i64,
    margin: i64,
    pulse: i64,
    ws: &mut Work,
) -> Option<usize> {
    earliest_due(c, tab, r, t, margin, pulse, ws)
        .filter(|&(d, _)| d < t)
        .map(|(_, s)| s)
}

fn decide(
    c: &Component,
    tab: &Tables,
    r: &mut Run,
    t: i64,
    ws: &mut Work,
    wait: Wait,
    log: &mut Vec<Diagnosis>,
) {
    if r.h.is_empty() {
        return;
    }
    let nf = c.faults.len();
    let modes = &mut ws.modes[..=nf];
    modes.iter_mut().for_each(|m| *m = false);
    for &(q, _) in &r.h {
        modes[tab.info[q as usize].mode.map_or(nf, |m| m as usize)] = true;
    }
    let count = modes.iter().filter(|&&m| m).count();
    r.normal_possible = modes[nf];
    if r.resyncing
        && count == 1
        && r.normal_possible
        && r.h.iter().any(|&(q, _)| q as usize == c.initial)
    {
        r.resyncing = false;
    }
    for (pi, p) in c.partitions.iter().enumerate() {
        // Faults of the partition still possible, in fault order.
        let inside = || (0..nf).filter(|&f| modes[f] && p.faults.contains(&f));
        let n = inside().count();
        // A component that lost track of its plant (an evolution nothing of its model
        // explains, `unexplained`) restarted on a guess: a fault outside its model (an
        // actuator of no partition, a welded one) may explain what follows as well as
        // its own faults do, so it decides nothing with certainty until the reset.
        let certainty = if n == 0 {
            Certainty::Normal
        } else if n == count && !r.unexplained && !r.resyncing {
            Certainty::Certain
        } else {
            Certainty::Ambiguous
        };
        let (old_certainty, old) = &mut r.decisions[pi];
        let same =
            *old_certainty == certainty && old.len() == n && old.iter().copied().eq(inside());
        if same && (certainty != Certainty::Certain || r.latched[pi]) {
            continue;
        }
        *old_certainty = certainty;
        old.clear();
        old.extend(inside());
        if certainty == Certainty::Certain && wait.applies_to(p) {
            r.deferred.get_or_insert(t);
        } else if certainty == Certainty::Certain {
            r.deferred = None;
            log.push(Diagnosis {
                time_ms: u64::try_from(t).unwrap_or(0),
                component: c.id.clone(),
                partition: p.id.clone(),
                fault: old
                    .iter()
                    .map(|&f| c.faults[f].as_str())
                    .collect::<Vec<_>>()
                    .join("|"),
                certainty,
            });
            r.latched[pi] = true;
        }
    }
    if wait.all || wait.sensors {
        r.doubt = None;
    } else {
        doubt(c, r, modes, t);
    }
}

/// Whether the component is in doubt (issue 17): certainly faulty (no normal hypothesis
/// left, nothing unexplained) without telling a stopping fault that stops items (a
/// `Blocked` behaviour: a dead drive, a jammed table) from a fault of a sensor the
/// cooperation cannot replace (no estimate). Keeps `r.doubt` (since when, and the
/// candidates); [`safe_side_stop`] stops the plant once it has lasted `doubt_ms`. A
/// motion without its order (a `Moves` fault) is no doubt that stops: every transient
/// of a beam reads like one, and a stop in the middle of a transfer costs more than it
/// saves (a box half on the table). A sensor the cooperation covers (C4, C5: the
/// paper's degraded mode) keeps the decision open.
fn doubt(c: &Component, r: &mut Run, modes: &[bool], t: i64) {
    let nf = c.faults.len();
    let stop_of = |f: usize| c.partitions.iter().any(|p| p.stop && p.faults.contains(&f));
    // A fault of a sensor partition whose sensor has an estimate (`estimate_of`).
    let covered = |f: usize| {
        r.estimate_of
            .iter()
            .flatten()
            .any(|(_, faults)| faults.contains(&f))
    };
    let blocking_stop = |f: usize| stop_of(f) && c.blocking.get(f).copied().unwrap_or(false);
    let possible = || (0..nf).filter(|&f| modes[f]);
    let doubtful = c.doubt_ms.is_some()
        && !r.unexplained
        && !modes[nf]
        && possible().any(blocking_stop)
        && !possible().all(|f| stop_of(f) || covered(f));
    if !doubtful {
        r.doubt = None;
        return;
    }
    let candidates = possible()
        .map(|f| c.faults[f].as_str())
        .collect::<Vec<_>>()
        .join("|");
    let since = r.doubt.as_ref().map_or(t, |d| d.0);
    r.doubt = Some((since, candidates));
}

/// The safe side of a doubt that lasted the component's `doubt_ms` (see [`doubt`]):
/// rather than wait longer for the evidence that would decide, the plant stops. A
/// belt that died under a box pushed from C0 reads, for a while, like a C1 stuck at 0,
/// and the entry conveyor brings the next box against the stuck one; within the
/// feed's longest window a box that reaches C3 shows the belt runs. The stopping
/// partitions still possible are flagged (their `DSTOP_` holds, the operator's reset
/// clears them, as for a certain fault), and the log says `ambiguous` with every
/// candidate.
fn safe_side_stop(c: &Component, r: &mut Run, t: i64, log: &mut Vec<Diagnosis>) {
    let (Some(wait), Some((since, _))) = (c.doubt_ms, r.doubt.as_ref()) else {
        return;
    };
    let due = since.saturating_add(i64::try_from(wait).unwrap_or(i64::MAX));
    if t < due {
        r.next_deadline = r.next_deadline.min(due - 1);
        return;
    }
    let Some((_, candidates)) = r.doubt.take() else {
        return;
    };
    for (pi, p) in c.partitions.iter().enumerate() {
        if p.stop && !r.latched[pi] && !r.decisions[pi].1.is_empty() {
            r.latched[pi] = true;
            r.deferred = None;
            log.push(Diagnosis {
                time_ms: u64::try_from(t).unwrap_or(0),
                component: c.id.clone(),
                partition: p.id.clone(),
                fault: candidates.clone(),
                certainty: Certainty::Ambiguous,
            });
        }
    }
}

/// Replays `events` (symbol names) on a component without timing, from its initial
/// state, and returns the fault labels possible after each event (`None` = normal);
/// an empty set means no hypothesis explains the sequence.
pub fn replay_untimed(
    c: &Component,
    events: &[&str],
) -> Result<Vec<BTreeSet<Option<String>>>, String> {
    let tab = Tables::new(c);
    let mut ws = Work::for_component(c);
    let mut r = empty_run();
    r.emitted = vec![0; c.intervals.len().div_ceil(64)];
    r.h = vec![(c.initial as u32, 0)];
    let mut out = Vec::new();
    for e in events {
        let sym = c
            .symbols
            .iter()
            .position(|s| s.name == *e)
            .ok_or_else(|| format!("unknown event `{e}`"))?;
        step(c, &tab, &mut r, sym, 0, 0, false, &mut ws);
        out.push(
            r.h.iter()
                .map(|&(q, _)| c.g[q as usize].mode.map(|f| c.faults[f].clone()))
                .collect(),
        );
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::station_dir;

    /// The precomputed closures and transition index say what the automaton says, for
    /// every state of every station model: reachability through fault events and hidden
    /// moves computed naively, and the observable transitions by linear search.
    #[test]
    fn run_time_tables_match_the_automaton() {
        let bundle = super::super::tests::station();
        for c in &bundle.compiled.components {
            let tab = Tables::new(c);
            for q in 0..c.g.len() {
                // Naive: every path; `true` when it takes a fault event.
                let mut reach: BTreeSet<(usize, bool)> = BTreeSet::new();
                let mut todo = vec![(q, false)];
                while let Some((x, f)) = todo.pop() {
                    let next = c.g[x]
                        .spawn
                        .iter()
                        .map(|&(_, y)| (y, true))
                        .chain(c.g[x].silent.iter().map(|&y| (y, f)));
                    for n in next {
                        if reach.insert(n) {
                            todo.push(n);
                        }
                    }
                }
                let want: BTreeSet<(u32, bool)> = reach
                    .iter()
                    .map(|&(y, _)| (y as u32, reach.contains(&(y, true))))
                    .filter(|&(y, spawned)| y as usize != q || spawned)
                    .collect();
                let range = tab.closure_at[q] as usize..tab.closure_at[q + 1] as usize;
                let got: BTreeSet<(u32, bool)> = tab.closure[range].iter().copied().collect();
                assert_eq!(got, want, "{} state {}", c.id, c.g[q].name);
                for sym in 0..c.symbols.len() {
                    let got: Vec<(usize, Option<usize>)> = tab
                        .observed(q, sym)
                        .map(|(t, w)| (t as usize, (w != NO_WINDOW).then_some(w as usize)))
                        .collect();
                    let want: Vec<(usize, Option<usize>)> = c.g[q]
                        .obs
                        .iter()
                        .filter(|o| o.0 == sym)
                        .map(|&(_, t, w)| (t, w))
                        .collect();
                    assert_eq!(got, want, "{} state {} symbol {sym}", c.id, c.g[q].name);
                }
            }
        }
    }

    /// The run-time index of a derived model (the drilling station's head: 149,930
    /// states, 342 symbols, 48 million observable transitions) holds each transition
    /// once, indexed by state; and components of one shape share their tables, a
    /// different shape never does. Finding the shared ones no longer stores each
    /// model's shape (1 GB for this one: the console took 3.3 GB on this plant).
    #[test]
    fn a_derived_models_tables_hold_each_transition_once() {
        let dir =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/drilling-station");
        let (db, _) = crate::pop::load(&dir).expect("the drilling station's diagnosers");
        let c = &db.compiled.components[0];
        let tab = Tables::new(c);
        let transitions: usize = c.g.iter().map(|st| st.obs.len()).sum();
        assert_eq!(tab.obs.len(), transitions);
        assert_eq!(tab.obs_at.len(), c.g.len() + 1);
        // Sharing: the station's models of one shape get one table, the others their own.
        let station = super::super::tests::station();
        let shared = share_tables(&station.compiled, true);
        for (i, a) in station.compiled.components.iter().enumerate() {
            for (j, b) in station.compiled.components.iter().enumerate() {
                let same = Tables::shape(a).eq(Tables::shape(b));
                assert_eq!(
                    std::sync::Arc::ptr_eq(&shared[i], &shared[j]),
                    same,
                    "{} and {}",
                    a.id,
                    b.id
                );
            }
        }
    }

    /// A certain fault of the actuator partition stops the station (DSTOP_P); the outputs
    /// it forces to 0 are not the plant's doing: the table's estimate is frozen, no
    /// "unexplained" note follows the diagnosis, and the flag stays set.
    #[test]
    fn a_stop_freezes_the_component_that_ordered_it() {
        let (out, sim) = super::super::closed_loop(
            &station_dir(),
            5,
            120_000,
            Some((
                crate::emulator::FaultKind::StuckAt {
                    component: "table".into(),
                    position: crate::emulator::Position(0.0),
                },
                60_000,
            )),
        )
        .unwrap();
        let table: Vec<_> = out
            .diagnoses
            .iter()
            .filter(|d| d.component == "table")
            .collect();
        assert!(
            table.first().is_some_and(|d| d.partition == "P"),
            "{table:#?}"
        );
        assert!(
            table.iter().all(|d| !d.fault.starts_with("unexplained")),
            "{table:#?}"
        );
        let d = sim.diagnosers.as_ref().unwrap();
        assert!(d.flagged().iter().any(|(p, stop, _)| p == "P" && *stop));
    }

    /// The time-outs emitted since the clock event are one bit per interval, however
    /// many intervals (the early copies add relaxed windows).
    #[test]
    fn emitted_time_outs_beyond_64_intervals_stay_apart() {
        let mut r = empty_run();
        r.emitted = vec![0; 130usize.div_ceil(64)];
        set_emitted(&mut r, 70);
        assert!(was_emitted(&r, 70));
        assert!(!was_emitted(&r, 6));
        set_emitted(&mut r, 129);
        assert!(was_emitted(&r, 129) && !was_emitted(&r, 1) && !was_emitted(&r, 65));
    }

    /// Identical automata share their run-time tables; different ones do not.
    #[test]
    fn identical_components_share_their_tables() {
        let bundle = super::super::tests::station();
        let d = Diagnosers::new(bundle.compiled.clone(), &bundle.bundle.symbols);
        let distinct = |d: &Diagnosers| {
            let mut v: Vec<*const Tables> = d.tables.iter().map(std::sync::Arc::as_ptr).collect();
            v.sort();
            v.dedup();
            v.len()
        };
        // The station's models are all different: one table each.
        assert_eq!(distinct(&d), d.compiled.components.len());
        // Three identical turntables share one; unshared, each has its own.
        let table = bundle
            .file
            .components
            .iter()
            .find(|c| c.id == "table")
            .unwrap();
        let (plant, syn) = crate::pop::synthetic(3, table);
        let mut symbols = plant.symbols();
        for a in crate::pop::build::aux_names(&syn) {
            let _ = symbols.declare(&a, Space::Aux);
        }
        let compiled = crate::pop::build::compile(
            &syn,
            &syn.to_ron(),
            std::path::Path::new("<synthetic>"),
            &symbols,
            None,
        )
        .unwrap();
        let shared = Diagnosers::new(compiled.clone(), &symbols);
        assert_eq!(distinct(&shared), 1);
        let own = Diagnosers::new_unshared(compiled, &symbols);
        assert_eq!(distinct(&own), 3);
    }
}
