//! The stopwatch monitor of a plant's tasks: one [`TaskMonitor`] per task (its state
//! and clocks, its end check, its unexpected events) and a [`Coordinator`] (controller
//! windows, cross-task constraints), with one of two timing back-ends:
//!
//! - the closed form (decentralized): each task's synthesised region for one
//!   interruptible task, `0 ≤ x − y < γ − α ∧ x < γ ∧ y ≤ β`, each window's bound and
//!   the hand-written cross-task constraints;
//! - the synthesised regions, when the task set has them ([`TaskSet::regions`], the
//!   `regions.ron` that `vigie synthesize` writes beside `tasks.ron`): the thesis's
//!   `A*`, one [`RegionMonitor`] over the product of the tasks' and windows' automata,
//!   an alarm as soon as the clocks leave `E*` of the current product location, at the
//!   exact crossing instant. Its alarm is the task's own code when it falls at one of
//!   the task's (or window's) own bounds, T009 when it comes before them (a coupling
//!   with other tasks). The cross-task constraints are not run (the regions hold the
//!   coupling, V1504). After its alarm the product monitor latches (the thesis's SFC2);
//!   with [`Latch::PerTask`] the tasks and windows not in fault keep their own bounds
//!   until the repair event, so that a second fault is still reported.
//!
//! Either way the alarms, the task states published for the safety filter and the
//! operator's panel are the same types.
//!
//! ## Semantics
//! - Each constraint is linear in time with slope `Σ cᵢ·rateᵢ`, so its crossing instant is
//!   computed exactly when the state changes; [`Monitor::next_deadline`] returns the
//!   earliest one so a caller can schedule a timer instead of polling.
//! - A strict constraint (`x − y < γ − α`, `x < γ`) is violated *at* its crossing instant;
//!   a non-strict one (`y ≤ β`, a window `≤ max`) only *after* it ([`Deadline::after`]).
//! - Events at time `t` are applied before the region is checked at `t` (the thesis takes
//!   the edge and then evaluates `E*` of the new location): a violation strictly before
//!   `t` is reported first, then the events of `t`, then [`Monitor::advance`]`(t)`
//!   reports violations at `t`. The reported alarm time is always the exact crossing
//!   instant, whatever the call times.
//! - A violation latches: the task freezes (state, x, y) for the operator until the
//!   repair event `m` ([`Monitor::repair`]). With [`Latch::Global`] the first fault
//!   freezes every task, as the thesis's SFC2 master does.

use super::explain::{Alarm, AlarmCode, Severity};
use super::spec::{Clock, Cmp, Latch, Slowdown, TaskSet, TaskSpec, Unexpected};
use crate::swa::regions::{Options as RegionOptions, RegionMonitor, Taken};
use crate::time::Millis;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};

/// Where a task is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, serde::Deserialize)]
pub enum TaskState {
    /// Not started (rates 0, 0).
    Idle,
    /// In progress and running (rates 1, 1).
    Running,
    /// In progress and interrupted (rates 1, 0).
    Interrupted,
    /// Ended and accepted (rates 0, 0; the clocks keep their final values).
    Done,
    /// Latched fault (frozen).
    Fault,
}

impl TaskState {
    /// Rates `(ẋ, ẏ)`.
    pub fn rates(self) -> (u64, u64) {
        match self {
            TaskState::Running => (1, 1),
            TaskState::Interrupted => (1, 0),
            _ => (0, 0),
        }
    }

    /// Running or interrupted.
    pub fn in_progress(self) -> bool {
        matches!(self, TaskState::Running | TaskState::Interrupted)
    }

    /// Code used in the generated Structured Text (`0` idle … `4` fault).
    pub fn st_code(self) -> i64 {
        self as i64
    }
}

/// What an event does to a task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// Start: `x, y := 0`.
    Start,
    /// End.
    End,
    /// Interrupt.
    Interrupt,
    /// Resume.
    Resume,
}

/// The next instant a constraint is violated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub struct Deadline {
    /// The exact crossing instant.
    pub at: Millis,
    /// False: violated at `at` (strict constraint reached). True: violated just after
    /// `at` (non-strict bound exceeded), i.e. from `at + 1 ms` on integer time.
    pub after: bool,
}

impl Deadline {
    /// True when the constraint is violated at some instant `<= t`.
    pub fn violated_by(self, t: Millis) -> bool {
        if self.after {
            self.at < t
        } else {
            self.at <= t
        }
    }

    /// True when the constraint is violated at some instant `< t`.
    pub fn violated_before(self, t: Millis) -> bool {
        self.at < t
    }

    /// The first integer millisecond at which the violation holds.
    pub fn first_violating_ms(self) -> Millis {
        if self.after {
            Millis(self.at.0.saturating_add(1))
        } else {
            self.at
        }
    }
}

/// Crossing of `v(t) = v0 + slope·(t − since)` against a bound, or `None` if never.
/// `strict`: the constraint is `v < bound` (violated when `v >= bound`), otherwise
/// `v <= bound` (violated when `v > bound`).
pub(crate) fn crossing(
    v0: i64,
    slope: i64,
    bound: i64,
    strict: bool,
    since: Millis,
) -> Option<Deadline> {
    let now = Deadline {
        at: since,
        after: false,
    };
    if (strict && v0 >= bound) || (!strict && v0 > bound) {
        return Some(now);
    }
    if slope <= 0 {
        return None;
    }
    let gap = bound - v0; // >= 0
    let whole = gap / slope;
    let exact = gap % slope == 0;
    let at = |d: i64| Millis(since.0.saturating_add(u64::try_from(d).unwrap_or(0)));
    Some(match (strict, exact) {
        (true, true) => Deadline {
            at: at(whole),
            after: false,
        },
        (true, false) | (false, false) => Deadline {
            at: at(whole + 1),
            after: false,
        },
        (false, true) => Deadline {
            at: at(whole),
            after: true,
        },
    })
}

/// Which constraint of a task a deadline belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TaskBound {
    /// `x − y < γ − α` (interruption tolerance).
    Tolerance,
    /// `x < γ`.
    Total,
    /// `y <= β` (slowdown, default variant).
    Effective,
}

/// One task's stopwatch monitor (the local monitor of the decentralized mode).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TaskMonitor {
    /// State.
    pub state: TaskState,
    x0: u64,
    y0: u64,
    since: Millis,
    /// Start time of the current (or last) run.
    pub started: Option<Millis>,
    /// Interruptions in the current (or last) run.
    pub interruptions: u32,
    /// Start of the interruption in progress.
    pub interrupted_at: Option<Millis>,
}

impl Default for TaskMonitor {
    fn default() -> Self {
        Self {
            state: TaskState::Idle,
            x0: 0,
            y0: 0,
            since: Millis::ZERO,
            started: None,
            interruptions: 0,
            interrupted_at: None,
        }
    }
}

impl TaskMonitor {
    /// `(x, y)` at `t` (frozen outside running/interrupted).
    pub fn clocks(&self, t: Millis) -> (u64, u64) {
        let d = t.0.saturating_sub(self.since.0);
        let (rx, ry) = self.state.rates();
        (self.x0 + rx * d, self.y0 + ry * d)
    }

    /// The constraints checked in the current state, each with its next violation.
    pub fn deadlines(&self, spec: &TaskSpec) -> Vec<(TaskBound, Deadline)> {
        if !self.state.in_progress() {
            return Vec::new();
        }
        let (rx, ry) = self.state.rates();
        let (rx, ry) = (to_i(rx), to_i(ry));
        let (x, y) = (to_i(self.x0), to_i(self.y0));
        let mut out = Vec::new();
        let mut push = |b, d: Option<Deadline>| {
            if let Some(d) = d {
                out.push((b, d));
            }
        };
        if spec.interruptible() {
            push(
                TaskBound::Tolerance,
                crossing(x - y, rx - ry, to_i(spec.tolerance()), true, self.since),
            );
        }
        push(
            TaskBound::Total,
            crossing(x, rx, to_i(spec.gamma), true, self.since),
        );
        if spec.interruptible() && spec.slowdown == Slowdown::Strict {
            push(
                TaskBound::Effective,
                crossing(y, ry, to_i(spec.beta), false, self.since),
            );
        }
        out
    }

    /// The earliest violation of the current state.
    pub fn next_deadline(&self, spec: &TaskSpec) -> Option<(TaskBound, Deadline)> {
        self.deadlines(spec)
            .into_iter()
            .min_by_key(|(b, d)| (*d, *b))
    }

    fn rebase(&mut self, t: Millis, state: TaskState) {
        let (x, y) = self.clocks(t);
        self.x0 = x;
        self.y0 = y;
        self.since = t;
        self.state = state;
    }

    fn freeze_at(&mut self, t: Millis) {
        self.rebase(t, TaskState::Fault);
    }
}

fn to_i(v: u64) -> i64 {
    i64::try_from(v).unwrap_or(i64::MAX)
}

/// Live data of one task, for the operator's panel.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TaskStatus {
    /// Task id.
    pub id: String,
    /// State.
    pub state: TaskState,
    /// Total time x in ms.
    pub x_ms: u64,
    /// Effective time y in ms.
    pub y_ms: u64,
    /// Interruptions of the current (or last) run.
    pub interruptions: u32,
    /// Remaining interruption tolerance `(γ − α) − (x − y)` in ms.
    pub slack_ms: i64,
    /// `γ − x` in ms.
    pub to_gamma_ms: i64,
    /// When the alarm would fire if the task stayed interrupted from now on.
    pub predicted_alarm: Option<Millis>,
    /// The classical watchdog instant (start + γ) of the current run.
    pub watchdog: Option<Millis>,
}

/// Runtime state of a controller window.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
struct WindowRt {
    opened: Option<Millis>,
}

/// The coordinator of the decentralized mode: controller windows and cross-task
/// constraints that no single task monitor can check.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Coordinator {
    windows: Vec<WindowRt>,
    /// Cross constraints already reported (each latches until repair).
    cross_latched: Vec<bool>,
}

/// A slot in the deadline queue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Slot {
    Task(usize),
    Window(usize),
    Cross(usize),
    /// The product monitor of the synthesised regions.
    Region,
}

/// Where the alarm instants come from: the seam between the two timing back-ends.
/// The rest (the tasks' states and clocks, end checks, unexpected events, windows'
/// early closes, latches, alarms) is the monitor's own, whichever runs.
#[derive(Clone, Debug)]
enum Timing {
    /// Each task's closed form, each window's bound, the cross-task constraints.
    ClosedForm,
    /// The synthesised regions of the tasks' product automaton.
    Regions(Box<Product>),
}

/// The region back-end's state.
#[derive(Clone, Debug)]
struct Product {
    monitor: RegionMonitor,
    /// The events the product took at `fed.0`: the frame adapter applies an expression
    /// shared by several tasks once per task ([`Monitor::apply`]), the product takes it
    /// once.
    fed: (Millis, BTreeSet<String>),
}

/// The whole monitor: task monitors, coordinator, deadline queue and alarm log.
#[derive(Clone, Debug)]
pub struct Monitor {
    set: TaskSet,
    /// Local monitors, in task order.
    pub tasks: Vec<TaskMonitor>,
    /// The coordinator.
    pub coordinator: Coordinator,
    routes: BTreeMap<String, Vec<Route>>,
    cross_of_task: Vec<Vec<usize>>,
    queue: BTreeSet<(Deadline, Slot)>,
    keys: BTreeMap<Slot, Deadline>,
    now: Millis,
    frozen: bool,
    timing: Timing,
    /// Every alarm and warning so far, in order.
    pub alarms: Vec<Alarm>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Route {
    Task(usize, Role),
    Open(usize),
    Close(usize),
    Repair,
}

impl Monitor {
    /// A monitor at time `start`, every task idle; it runs the set's synthesised
    /// regions when it has them ([`TaskSet::regions`]), the closed form otherwise.
    pub fn new(set: &TaskSet, start: Millis) -> Self {
        let mut routes: BTreeMap<String, Vec<Route>> = BTreeMap::new();
        for (i, t) in set.tasks.iter().enumerate() {
            routes
                .entry(t.start.clone())
                .or_default()
                .push(Route::Task(i, Role::Start));
            routes
                .entry(t.end.clone())
                .or_default()
                .push(Route::Task(i, Role::End));
            if let Some((int, res)) = &t.interruption {
                routes
                    .entry(int.clone())
                    .or_default()
                    .push(Route::Task(i, Role::Interrupt));
                routes
                    .entry(res.clone())
                    .or_default()
                    .push(Route::Task(i, Role::Resume));
            }
        }
        for (j, w) in set.windows.iter().enumerate() {
            // Close before open, so an event that does both restarts the window.
            for e in &w.close {
                routes.entry(e.clone()).or_default().push(Route::Close(j));
            }
            for e in &w.open {
                routes.entry(e.clone()).or_default().push(Route::Open(j));
            }
        }
        if let Some(m) = &set.repair {
            routes
                .entry(m.clone())
                .or_default()
                .insert(0, Route::Repair);
        }
        let mut cross_of_task = vec![Vec::new(); set.tasks.len()];
        for (k, c) in set.cross.iter().enumerate() {
            for (task, _, _) in &c.terms {
                if let Some(i) = set.task(task)
                    && !cross_of_task[i].contains(&k)
                {
                    cross_of_task[i].push(k);
                }
            }
        }
        let mut m = Self {
            set: set.clone(),
            tasks: vec![TaskMonitor::default(); set.tasks.len()],
            coordinator: Coordinator {
                windows: vec![WindowRt::default(); set.windows.len()],
                cross_latched: vec![false; set.cross.len()],
            },
            routes,
            cross_of_task,
            queue: BTreeSet::new(),
            keys: BTreeMap::new(),
            now: start,
            frozen: false,
            timing: match &set.regions {
                Some(r) => Timing::Regions(Box::new(Product {
                    monitor: RegionMonitor::shared(
                        r.swa.clone(),
                        r.regions.clone(),
                        start,
                        RegionOptions::default(),
                    ),
                    fed: (start, BTreeSet::new()),
                })),
                None => Timing::ClosedForm,
            },
            alarms: Vec::new(),
        };
        m.reset_all(start);
        m
    }

    /// The product monitor of the synthesised regions, when the monitor runs them.
    pub fn regions(&self) -> Option<&RegionMonitor> {
        match &self.timing {
            Timing::Regions(p) => Some(&p.monitor),
            Timing::ClosedForm => None,
        }
    }

    /// True while the synthesised regions time the tasks (they run and have not
    /// latched an alarm).
    fn regions_live(&self) -> bool {
        self.regions().is_some_and(|r| r.alarm().is_none())
    }

    fn reset_all(&mut self, t: Millis) {
        self.queue.clear();
        self.keys.clear();
        self.frozen = false;
        for tm in &mut self.tasks {
            *tm = TaskMonitor {
                since: t,
                ..TaskMonitor::default()
            };
        }
        for j in 0..self.set.windows.len() {
            self.coordinator.windows[j].opened = self.set.windows[j].open_at_start.then_some(t);
            self.reschedule(Slot::Window(j));
        }
        self.coordinator
            .cross_latched
            .iter_mut()
            .for_each(|c| *c = false);
        if let Timing::Regions(p) = &mut self.timing {
            p.monitor.repair(t);
            p.fed = (t, BTreeSet::new());
        }
        self.reschedule(Slot::Region);
    }

    /// The specification.
    pub fn spec(&self) -> &TaskSet {
        &self.set
    }

    /// Time of the last call.
    pub fn now(&self) -> Millis {
        self.now
    }

    /// True while any fault is latched.
    pub fn fault(&self) -> bool {
        self.frozen || self.tasks.iter().any(|t| t.state == TaskState::Fault)
    }

    /// The earliest future violation if nothing else happens (for timer scheduling).
    pub fn next_deadline(&self) -> Option<Deadline> {
        self.queue.first().map(|(d, _)| *d)
    }

    fn deadline_of(&self, slot: Slot) -> Option<Deadline> {
        match slot {
            Slot::Region => self.regions().and_then(RegionMonitor::due),
            Slot::Task(_) | Slot::Window(_) if self.regions_live() => None,
            Slot::Cross(_) if self.regions().is_some() => None,
            Slot::Task(i) => self.tasks[i]
                .next_deadline(&self.set.tasks[i])
                .map(|(_, d)| d),
            Slot::Window(j) => {
                let w = &self.set.windows[j];
                self.coordinator.windows[j]
                    .opened
                    .and_then(|o| crossing(0, 1, to_i(w.max_ms), false, o))
            }
            Slot::Cross(k) => self.cross_deadline(k).map(|(d, _)| d),
        }
    }

    /// `(deadline, value at now)` of a cross constraint, if active.
    fn cross_deadline(&self, k: usize) -> Option<(Deadline, i64)> {
        if self.coordinator.cross_latched[k] {
            return None;
        }
        let c = &self.set.cross[k];
        let mut v = 0i64;
        let mut slope = 0i64;
        for (task, clock, coef) in &c.terms {
            let i = self.set.task(task)?;
            let tm = &self.tasks[i];
            if !tm.state.in_progress() {
                return None;
            }
            let (x, y) = tm.clocks(self.now);
            let (rx, ry) = tm.state.rates();
            let (val, rate) = match clock {
                Clock::X => (x, rx),
                Clock::Y => (y, ry),
            };
            v += coef * to_i(val);
            slope += coef * to_i(rate);
        }
        crossing(v, slope, c.bound_ms, c.op == Cmp::Lt, self.now).map(|d| (d, v))
    }

    fn reschedule(&mut self, slot: Slot) {
        if let Some(old) = self.keys.remove(&slot) {
            self.queue.remove(&(old, slot));
        }
        if self.frozen {
            return;
        }
        if let Some(d) = self.deadline_of(slot) {
            self.keys.insert(slot, d);
            self.queue.insert((d, slot));
        }
    }

    fn task_changed(&mut self, i: usize) {
        self.reschedule(Slot::Task(i));
        for k in self.cross_of_task[i].clone() {
            self.reschedule(Slot::Cross(k));
        }
    }

    /// Reports every violation at an instant `< t` (`inclusive = false`) or `<= t`.
    fn detect(&mut self, t: Millis, inclusive: bool) {
        while let Some(&(d, slot)) = self.queue.first() {
            let hit = if inclusive {
                d.violated_by(t)
            } else {
                d.violated_before(t)
            };
            if !hit || self.frozen {
                break;
            }
            self.queue.pop_first();
            self.keys.remove(&slot);
            self.fire(slot, d);
        }
    }

    fn fire(&mut self, slot: Slot, d: Deadline) {
        match slot {
            Slot::Task(i) => {
                let spec = &self.set.tasks[i];
                let bound = self.tasks[i]
                    .next_deadline(spec)
                    .map_or(TaskBound::Total, |(b, _)| b);
                let (x, y) = self.tasks[i].clocks(d.at);
                let code = match bound {
                    TaskBound::Tolerance => AlarmCode::T001,
                    TaskBound::Effective => AlarmCode::T002,
                    TaskBound::Total => AlarmCode::T003,
                };
                let alarm = Alarm::task(code, d.at, spec, &self.tasks[i], x, y);
                self.tasks[i].freeze_at(d.at);
                self.latch(alarm);
                self.task_changed(i);
            }
            Slot::Window(j) => {
                let w = &self.set.windows[j];
                let opened = self.coordinator.windows[j].opened.unwrap_or(d.at);
                self.coordinator.windows[j].opened = None;
                let alarm = Alarm::window_late(d.at, w, opened);
                self.latch(alarm);
            }
            Slot::Cross(k) => {
                let value = self.cross_deadline(k).map_or(0, |(_, v)| v);
                self.coordinator.cross_latched[k] = true;
                let alarm = Alarm::cross(d.at, &self.set.cross[k], value);
                self.latch(alarm);
            }
            Slot::Region => self.fire_region(d),
        }
    }

    /// The product monitor left its region at `d`: it latches, and each component it
    /// names (whose own set the clocks left, or whose clocks the crossed constraint
    /// reads) raises its alarm: its own bound's code when the crossing is that bound,
    /// T009 when it comes before. The tasks and windows not in fault keep their own
    /// bounds from now on, until the repair.
    fn fire_region(&mut self, d: Deadline) {
        let Timing::Regions(p) = &mut self.timing else {
            return;
        };
        let Some(region) = p.monitor.pending() else {
            return;
        };
        p.monitor.latch(region.clone());
        let mut subjects: Vec<&str> = region.components.iter().map(String::as_str).collect();
        // The components the clocks leave the region for can be more than the one at
        // fault: in the product, an invariant (an open window's `w <= max`) stops time
        // for every component, so the others' goals become unreachable with it. The
        // one at fault is the one whose own bounds come first (at this instant: it
        // reached one of them).
        let first = subjects.iter().filter_map(|s| self.own_deadline(s)).min();
        if first.is_some() {
            subjects.retain(|s| self.own_deadline(s) == first);
        }
        if subjects.is_empty() {
            subjects.push(&region.location);
        }
        for subject in subjects {
            if self.frozen {
                break;
            }
            if let Some(i) = self.set.task(subject) {
                if self.tasks[i].state == TaskState::Fault {
                    continue;
                }
                let spec = &self.set.tasks[i];
                let tm = &self.tasks[i];
                let (x, y) = tm.clocks(d.at);
                let own = tm.next_deadline(spec);
                let alarm = match own {
                    Some((bound, o)) if o == d => {
                        let code = match bound {
                            TaskBound::Tolerance => AlarmCode::T001,
                            TaskBound::Effective => AlarmCode::T002,
                            TaskBound::Total => AlarmCode::T003,
                        };
                        Alarm::task(code, d.at, spec, tm, x, y)
                    }
                    _ => Alarm::region_left(
                        d.at,
                        subject,
                        own.map(|(_, o)| o.at),
                        &region,
                        Some((spec, tm, x, y)),
                    ),
                };
                self.tasks[i].freeze_at(d.at);
                self.latch(alarm);
            } else if let Some(j) = self.set.windows.iter().position(|w| w.id == subject) {
                let w = &self.set.windows[j];
                let opened = self.coordinator.windows[j].opened.take();
                let own = opened.and_then(|o| crossing(0, 1, to_i(w.max_ms), false, o));
                let alarm = match (own, opened) {
                    (Some(o), Some(opened)) if o == d => Alarm::window_late(d.at, w, opened),
                    _ => Alarm::region_left(d.at, subject, own.map(|o| o.at), &region, None),
                };
                self.latch(alarm);
            } else {
                let alarm = Alarm::region_left(d.at, subject, None, &region, None);
                self.latch(alarm);
            }
        }
        for i in 0..self.tasks.len() {
            self.reschedule(Slot::Task(i));
        }
        for j in 0..self.set.windows.len() {
            self.reschedule(Slot::Window(j));
        }
    }

    /// The next violation of task or window `id`'s own bounds (its closed form).
    fn own_deadline(&self, id: &str) -> Option<Deadline> {
        if let Some(i) = self.set.task(id) {
            return self.tasks[i]
                .next_deadline(&self.set.tasks[i])
                .map(|(_, d)| d);
        }
        let j = self.set.windows.iter().position(|w| w.id == id)?;
        let opened = self.coordinator.windows[j].opened?;
        crossing(0, 1, to_i(self.set.windows[j].max_ms), false, opened)
    }

    /// Gives `event` at `t` to the product of the synthesised regions, if it runs
    /// them; `once`: not again if it took it at `t` already (the frame adapter's
    /// per-task calls).
    fn feed(&mut self, t: Millis, event: &str, once: bool) {
        if self.frozen {
            return;
        }
        let Timing::Regions(p) = &mut self.timing else {
            return;
        };
        if p.fed.0 != t {
            p.fed = (t, BTreeSet::new());
        }
        let fresh = p.fed.1.insert(event.to_string());
        if once && !fresh {
            return;
        }
        // A blocked event (a component that cannot take it where it is) leaves the
        // product where it is; the task's own policy reports it (T007).
        if !matches!(p.monitor.take(t, event), Taken::Ignored | Taken::Blocked(_)) {
            self.reschedule(Slot::Region);
        }
    }

    fn latch(&mut self, alarm: Alarm) {
        let latching = alarm.severity == Severity::Alarm;
        self.alarms.push(alarm);
        if latching && self.set.latch == Latch::Global {
            self.frozen = true;
            let t = self.alarms.last().map_or(self.now, |a| a.time);
            for tm in &mut self.tasks {
                if tm.state.in_progress() {
                    tm.rebase(t, tm.state);
                    // Frozen in place: rates 0 from now on, state kept for the display.
                    tm.since = Millis(u64::MAX);
                }
            }
            self.queue.clear();
            self.keys.clear();
        }
    }

    /// Declares that no more events happen at or before `t` and reports every violation
    /// up to `t` (inclusive). Returns the alarms raised by this call.
    pub fn advance(&mut self, t: Millis) -> &[Alarm] {
        let before = self.alarms.len();
        let t = t.max(self.now);
        self.detect(t, true);
        self.now = t;
        &self.alarms[before..]
    }

    /// An observed event at `t` (a name from the specification; unknown names are
    /// ignored). Times earlier than the last call are taken as the last call's time.
    /// Returns the alarms raised by this call.
    pub fn on_event(&mut self, t: Millis, event: &str) -> &[Alarm] {
        let before = self.alarms.len();
        let t = t.max(self.now);
        self.detect(t, false);
        self.now = t;
        // The frame adapter's tick (no event) every cycle: "" is the least key, so the
        // first key tells whether it routes anything, without comparing strings.
        if event.is_empty()
            && !self
                .routes
                .first_key_value()
                .is_some_and(|(k, _)| k.is_empty())
        {
            return &self.alarms[before..];
        }
        let routes = self.routes.get(event).cloned().unwrap_or_default();
        if !routes.contains(&Route::Repair) {
            self.feed(t, event, false);
        }
        for r in routes {
            match r {
                Route::Repair => {
                    self.repair(t);
                }
                Route::Task(i, role) => self.apply_role(t, i, role, event),
                Route::Open(j) => {
                    if !self.frozen {
                        self.coordinator.windows[j].opened = Some(t);
                        self.reschedule(Slot::Window(j));
                    }
                }
                Route::Close(j) => {
                    if !self.frozen {
                        if let Some(o) = self.coordinator.windows[j].opened.take() {
                            let w = &self.set.windows[j];
                            if t.0 - o.0 < w.min_ms {
                                let alarm = Alarm::window_early(t, w, o);
                                self.latch(alarm);
                            }
                        }
                        self.reschedule(Slot::Window(j));
                    }
                }
            }
        }
        &self.alarms[before..]
    }

    /// Applies `role` to task `i` at `t` (the frame adapter's entry point; [`Self::on_event`]
    /// resolves names to this). `event` is the event's name (its expression in frame
    /// mode): the product of the synthesised regions takes it once per instant however
    /// many tasks it is applied to.
    pub fn apply(&mut self, t: Millis, i: usize, role: Role, event: &str) {
        if self.frozen || i >= self.tasks.len() {
            return;
        }
        let t = t.max(self.now);
        self.feed(t, event, true);
        self.apply_role(t, i, role, event);
    }

    /// [`Self::apply`] without giving the event to the product.
    fn apply_role(&mut self, t: Millis, i: usize, role: Role, event: &str) {
        if self.frozen || i >= self.tasks.len() {
            return;
        }
        let t = t.max(self.now);
        let state = self.tasks[i].state;
        let next = match (role, state) {
            (_, TaskState::Fault) => return,
            (Role::Start, TaskState::Idle | TaskState::Done) => Some(TaskState::Running),
            (Role::Interrupt, TaskState::Running) => Some(TaskState::Interrupted),
            (Role::Resume, TaskState::Interrupted) => Some(TaskState::Running),
            (Role::End, TaskState::Running | TaskState::Interrupted) => Some(TaskState::Done),
            _ => None,
        };
        let Some(next) = next else {
            self.unexpected(t, i, role, event);
            return;
        };
        let tm = &mut self.tasks[i];
        match role {
            Role::Start => {
                *tm = TaskMonitor {
                    state: TaskState::Running,
                    since: t,
                    started: Some(t),
                    ..TaskMonitor::default()
                };
            }
            Role::Interrupt => {
                tm.rebase(t, next);
                tm.interruptions += 1;
                tm.interrupted_at = Some(t);
            }
            Role::Resume => {
                tm.rebase(t, next);
                tm.interrupted_at = None;
            }
            Role::End => {
                tm.rebase(t, next);
                tm.interrupted_at = None;
                if self.set.check_end {
                    let spec = &self.set.tasks[i];
                    if let Some(code) = end_check(spec, tm.x0, tm.y0) {
                        let alarm = Alarm::task(code, t, spec, tm, tm.x0, tm.y0);
                        tm.state = TaskState::Fault;
                        self.latch(alarm);
                    }
                }
            }
        }
        self.task_changed(i);
    }

    fn unexpected(&mut self, t: Millis, i: usize, role: Role, event: &str) {
        let severity = match self.set.unexpected {
            Unexpected::Ignore => return,
            Unexpected::Warn => Severity::Warning,
            Unexpected::Alarm => Severity::Alarm,
        };
        let spec = &self.set.tasks[i];
        let tm = &self.tasks[i];
        let alarm = Alarm::unexpected(t, spec, tm.state, role, event, severity);
        if severity == Severity::Alarm {
            self.tasks[i].freeze_at(t);
        }
        self.latch(alarm);
        self.task_changed(i);
    }

    /// The repair event `m`: every task idle, clocks 0, latches cleared, windows as at start.
    pub fn repair(&mut self, t: Millis) {
        let t = t.max(self.now);
        self.now = t;
        self.reset_all(t);
    }

    /// Live data of every task at `t` (`t` should be `>= now`; the alarm-free
    /// extrapolation is used, so call [`Self::advance`] first).
    pub fn status(&self, t: Millis) -> Vec<TaskStatus> {
        // An interrupted task's alarm, if nothing happens, is the regions' next one
        // when it names the task (it may come before the task's own bounds).
        let region = self
            .regions()
            .filter(|_| !self.frozen)
            .and_then(RegionMonitor::pending);
        self.set
            .tasks
            .iter()
            .zip(&self.tasks)
            .map(|(spec, tm)| {
                let (x, y) = if self.frozen || tm.since.0 == u64::MAX {
                    (tm.x0, tm.y0)
                } else {
                    tm.clocks(t.max(tm.since))
                };
                let slack = to_i(spec.tolerance()) - (to_i(x) - to_i(y));
                let to_gamma = to_i(spec.gamma) - to_i(x);
                let predicted = (tm.state.in_progress() && !self.frozen).then(|| {
                    let d = if spec.interruptible() {
                        slack.min(to_gamma)
                    } else {
                        to_gamma
                    };
                    let own = Millis(t.0.saturating_add(u64::try_from(d.max(0)).unwrap_or(0)));
                    match &region {
                        Some(r)
                            if tm.state == TaskState::Interrupted
                                && r.components.contains(&spec.id) =>
                        {
                            own.min(r.at.first_violating_ms().max(t))
                        }
                        _ => own,
                    }
                });
                TaskStatus {
                    id: spec.id.clone(),
                    state: tm.state,
                    x_ms: x,
                    y_ms: y,
                    interruptions: tm.interruptions,
                    slack_ms: slack,
                    to_gamma_ms: to_gamma,
                    predicted_alarm: predicted,
                    watchdog: tm.started.map(|s| Millis(s.0 + spec.gamma)),
                }
            })
            .collect()
    }

    /// Values of the auxiliary outputs named by [`TaskSet::aux_names`], in that order.
    pub fn aux_values(&self) -> Vec<bool> {
        self.tasks
            .iter()
            .flat_map(|tm| {
                [
                    tm.state == TaskState::Running,
                    tm.state == TaskState::Interrupted,
                    tm.state == TaskState::Fault,
                ]
            })
            .collect()
    }
}

/// The end guard: `α ≤ y ≤ β' ∧ α ≤ x < γ` (β' = β, or γ in the tolerant variant); for a
/// non-interruptible task `α ≤ x < γ`.
pub(crate) fn end_check(spec: &TaskSpec, x: u64, y: u64) -> Option<AlarmCode> {
    let y_max = match spec.slowdown {
        Slowdown::Strict => spec.beta,
        Slowdown::Tolerant => spec.gamma,
    };
    let early = x < spec.alpha || (spec.interruptible() && y < spec.alpha);
    let late = x >= spec.gamma || (spec.interruptible() && y > y_max);
    if early {
        Some(AlarmCode::T004)
    } else if late {
        Some(AlarmCode::T005)
    } else {
        None
    }
}
