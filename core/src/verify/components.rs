//! Verification of a plant of components (`components.ron`), one sub-plant at a time
//! (seed 004 §2 and §6.2: the expert checks each dangerous state on the part of the
//! plant it involves, so that a multi-station line is verified in parts).
//!
//! # The abstraction
//! - **Sub-plant**: one component with a position (an axis, a tank) and its hazards:
//!   an end stop that crashes, drives opposed, a tank overflowing or run dry, and the
//!   declared dangers on it (`dangers` of `components.ron`).
//! - **Position**: the travel cut at every point where something changes (its ends,
//!   its sensors' window edges, its dangers' zone edges) into zones: the points
//!   themselves and the open intervals between them. Every sensor and danger is
//!   constant on a zone. Each PLC cycle the component stays in its zone or moves in
//!   the direction of its speed to any zone it can reach in one cycle at its fastest
//!   drive (with `variation_ppm`); it cannot stay on a point while it moves. Time in a
//!   zone is not bounded below: a slow move is included.
//! - **Its surroundings**: every input the relevant constraints, observers, drives or
//!   dangers read that the component does not write takes any value at every cycle
//!   (another station's sensor, a button); inputs nothing relevant reads read 0.
//! - **Control**: the most permissive: any vector of the outputs its drives, its
//!   dangers and its relevant constraints name, every cycle; the others are 0.
//! - **PLC**: one cycle per step in the engine's order: inputs, observers (the real
//!   [`Observers`]), the commanded vector, the real [`Filter`] of the relevant
//!   constraints (those naming one of its signals or an observer that does), then the
//!   sub-plant's step with the applied vector. The latch is abstracted away (the
//!   operator may reset at any cycle).
//!
//! The search is breadth first, so a hazard's trace is a shortest one. It is run twice:
//! without the filter (is the hazard real: can a control error reach it?) and with it
//! (does the constraint set prevent it whatever the control?). Conveyors, detectors
//! and links are not modelled here: the report says so.

use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::constraints::ConstraintSet;
use crate::diag::{Problem, codes};
use crate::expr::{Dnf, eval_dnf, parse_str, simplify};
use crate::filter::Filter;
use crate::frame::Frame;
use crate::machine::description::Components;
use crate::machine::kinds::KindDef;
use crate::machine::kinds::axis::EndStop;
use crate::observers::Observers;
use crate::symbols::Space;
use serde::Serialize;
use std::collections::{BTreeSet, HashMap, VecDeque};

/// Millionths of the unit per unit.
const MICRO: f64 = 1e6;
/// The PLC cycle of the model, ms.
const CYCLE_MS: i64 = 10;
/// Above this many free inputs and outputs together a sub-plant is not explored (2^n
/// vectors a cycle): the report says so.
const MAX_FREE: usize = 14;
/// Above this many states a search stops and says so.
const MAX_STATES: usize = 2_000_000;

/// A hazard of a sub-plant.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum SubHazard {
    /// Driven into an end stop that crashes (`min` or `max`).
    EndStop(String),
    /// Drives in both directions at once.
    OpposedDrives,
    /// An inflow into a full tank that spills.
    Overflow,
    /// An outflow from an empty tank that runs dry.
    DryRun,
    /// A declared danger, by id.
    Declared(String),
}

impl std::fmt::Display for SubHazard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::EndStop(end) => write!(f, "end stop at {end}"),
            Self::OpposedDrives => write!(f, "drives opposed"),
            Self::Overflow => write!(f, "overflow"),
            Self::DryRun => write!(f, "dry run"),
            Self::Declared(id) => write!(f, "danger `{id}`"),
        }
    }
}

/// One cycle of a trace.
#[derive(Clone, Debug, Serialize)]
pub struct TraceStep {
    /// Where the component was at the cycle's start (`(2, 58) mm`).
    pub zone: String,
    /// The inputs on (its own and the free ones).
    pub inputs: Vec<String>,
    /// The outputs the control commanded.
    pub commanded: Vec<String>,
    /// The outputs applied after the filter.
    pub applied: Vec<String>,
}

/// A hazard reached, with a shortest trace to it.
#[derive(Clone, Debug, Serialize)]
pub struct Reached {
    /// Which.
    pub hazard: SubHazard,
    /// From the start: one entry per cycle, the last one the hazard's.
    pub trace: Vec<TraceStep>,
}

/// One sub-plant's result.
#[derive(Clone, Debug, Serialize)]
pub struct SubReport {
    /// The component.
    pub component: String,
    /// Its hazards, checked.
    pub hazards: Vec<SubHazard>,
    /// The inputs taken as free, each cycle.
    pub free_inputs: Vec<String>,
    /// The outputs the control chooses.
    pub free_outputs: Vec<String>,
    /// The constraints that guard it.
    pub constraints: Vec<String>,
    /// Why it was not explored, if it was not.
    pub skipped: Option<String>,
    /// States and transitions of the search with the filter.
    pub states: usize,
    /// Transitions.
    pub transitions: u64,
    /// The search stopped at its limit of states (two million).
    pub truncated: bool,
    /// Hazards reachable without the filter (each with a shortest trace).
    pub without_filter: Vec<Reached>,
    /// Hazards reachable with it.
    pub with_filter: Vec<Reached>,
    /// Hazards reachable even with every output held at its safe value: the
    /// environment (the free inputs) makes them, no control prevents them (a fault
    /// current on a line); they are reported, not counted against the constraints.
    pub uncontrollable: Vec<SubHazard>,
}

/// The verification of a plant of components.
#[derive(Clone, Debug, Serialize)]
pub struct ComponentsReport {
    /// The plant's name.
    pub plant: String,
    /// The sub-plants, in the order of `components.ron`.
    pub parts: Vec<SubReport>,
    /// Components of kinds the model does not cover (conveyors, detectors, links).
    pub not_modelled: Vec<String>,
    /// The abstraction's assumptions, stated in every report.
    pub assumptions: Vec<String>,
}

impl ComponentsReport {
    /// Every hazard reachable with the filter: the constraint set does not protect.
    pub fn unsafe_parts(&self) -> Vec<(&str, &Reached)> {
        self.parts
            .iter()
            .flat_map(|p| {
                p.with_filter
                    .iter()
                    .filter(|r| !p.uncontrollable.contains(&r.hazard))
                    .map(move |r| (p.component.as_str(), r))
            })
            .collect()
    }
}

/// How the quantity moves: an axis goes at its fastest active drive (opposed drives
/// hold it), a tank at the sum of its running flows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Motion {
    Axis,
    Tank,
}

/// A drive or a flow, compiled.
#[derive(Clone, Debug)]
struct Mover {
    dnf: Dnf,
    /// Millionths of the unit per ms.
    speed: i64,
    /// A flow sensor in series (input index).
    sensor: Option<usize>,
}

/// A one-dimensional component, abstracted.
#[derive(Clone, Debug)]
struct Line {
    motion: Motion,
    unit: String,
    /// The cut points, millionths, sorted: zone `2i` is point `i`, zone `2i+1` the open
    /// interval between points `i` and `i+1`.
    points: Vec<i64>,
    windows: Vec<(usize, i64, i64)>,
    /// An axis's motion sensor.
    moving: Option<usize>,
    movers: Vec<Mover>,
    /// What the low and high ends do (for a tank: dry run, overflow).
    low: EndStop,
    high: EndStop,
    variation_ppm: i64,
    start: usize,
    dangers: Vec<(String, i64, i64, Dnf)>,
}

fn micro(v: f64) -> i64 {
    (v * MICRO).round() as i64
}

impl Line {
    fn zones(&self) -> usize {
        2 * self.points.len() - 1
    }

    /// The zone's bounds (a point: both the same).
    fn bounds(&self, z: usize) -> (i64, i64) {
        (self.points[z / 2], self.points[z.div_ceil(2)])
    }

    fn zone_of(&self, p: i64) -> usize {
        match self.points.binary_search(&p) {
            Ok(i) => 2 * i,
            Err(i) => 2 * i - 1,
        }
    }

    fn within(&self, z: usize, from: i64, to: i64) -> bool {
        let (lo, hi) = self.bounds(z);
        from <= lo && hi <= to
    }

    fn text(&self, z: usize) -> String {
        let (lo, hi) = self.bounds(z);
        let f = |v: i64| v as f64 / MICRO;
        if lo == hi {
            format!("{} {}", f(lo), self.unit)
        } else {
            format!("({}, {}) {}", f(lo), f(hi), self.unit)
        }
    }

    /// The signed speed (millionths per ms), the hazards of the cycle and the flow
    /// sensors that see their flow run, for the applied outputs in `frame`, in zone `z`.
    fn speed(&self, z: usize, frame: &Frame) -> (i64, Vec<SubHazard>, Vec<usize>) {
        let (top, bottom) = (z + 1 == self.zones(), z == 0);
        let mut hazards = Vec::new();
        let mut running = Vec::new();
        match self.motion {
            Motion::Axis => {
                let (mut best, mut up, mut down) = (0i64, false, false);
                for m in self.movers.iter().filter(|m| eval_dnf(&m.dnf, frame)) {
                    up |= m.speed > 0;
                    down |= m.speed < 0;
                    if m.speed.abs() > best.abs() {
                        best = m.speed;
                    }
                }
                if up && down {
                    hazards.push(SubHazard::OpposedDrives);
                    best = 0;
                }
                let into = |end: EndStop| end == EndStop::Crash;
                if best > 0 && top && into(self.high) {
                    hazards.push(SubHazard::EndStop("max".into()));
                }
                if best < 0 && bottom && into(self.low) {
                    hazards.push(SubHazard::EndStop("min".into()));
                }
                (best, hazards, running)
            }
            Motion::Tank => {
                let mut net = 0;
                for m in self.movers.iter().filter(|m| eval_dnf(&m.dnf, frame)) {
                    let stopped = (m.speed > 0 && top) || (m.speed < 0 && bottom);
                    if stopped && m.speed > 0 && self.high == EndStop::Crash {
                        hazards.push(SubHazard::Overflow);
                    }
                    if stopped && m.speed < 0 && self.low == EndStop::Crash {
                        hazards.push(SubHazard::DryRun);
                    }
                    if !stopped {
                        net += m.speed;
                        running.extend(m.sensor);
                    }
                }
                hazards.dedup();
                (net, hazards, running)
            }
        }
    }

    /// The zones reachable in one cycle from `z` at speed `v`.
    fn next(&self, z: usize, v: i64) -> Vec<usize> {
        if v == 0 {
            return vec![z];
        }
        let reach = v.abs() * (1_000_000 + self.variation_ppm) / 1_000_000 * CYCLE_MS;
        let (lo, hi) = self.bounds(z);
        let mut out = Vec::new();
        // An interval may be kept (a slow move); a point is left unless it is the end.
        let on_point = lo == hi;
        let at_end = (v > 0 && z + 1 == self.zones()) || (v < 0 && z == 0);
        if !on_point || at_end {
            out.push(z);
        }
        if v > 0 {
            for j in z + 1..self.zones() {
                if self.bounds(j).0 - hi > reach {
                    break;
                }
                out.push(j);
            }
        } else {
            for j in (0..z).rev() {
                if lo - self.bounds(j).1 > reach {
                    break;
                }
                out.push(j);
            }
        }
        out
    }
}

fn compile(text: &str, bundle: &PlantBundle) -> Result<Dnf, Problem> {
    parse_str(text)
        .and_then(|e| e.to_dnf(&bundle.symbols))
        .map(|d| simplify(&d))
        .map_err(|e| {
            Problem::error(
                codes::VERIFY_UNSUPPORTED.id,
                format!("`{text}`: {}", e.message),
                None,
            )
        })
}

fn input(bundle: &PlantBundle, name: &str) -> Result<usize, Problem> {
    match bundle.symbols.lookup(name) {
        Some((Space::Input, i)) => Ok(i as usize),
        _ => Err(Problem::error(
            codes::VERIFY_UNSUPPORTED.id,
            format!("`{name}` is not a plant input"),
            None,
        )),
    }
}

/// A drive's or a flow's text: condition, speed, flow sensor.
type MoverText<'a> = (&'a str, f64, Option<&'a str>);

/// The abstract line of a component, or `None` for a kind the model does not cover.
fn line(
    id: &str,
    kind: &KindDef,
    desc: &Components,
    bundle: &PlantBundle,
) -> Result<Option<Line>, Problem> {
    let (mut l, windows, movers): (Line, &Vec<_>, Vec<MoverText<'_>>) = match kind {
        KindDef::Axis(a) => (
            Line {
                motion: Motion::Axis,
                unit: a.unit.clone(),
                points: vec![micro(a.min), micro(a.max), micro(a.start)],
                windows: Vec::new(),
                moving: a.motion.as_deref().map(|m| input(bundle, m)).transpose()?,
                movers: Vec::new(),
                low: a.end_stops.min,
                high: a.end_stops.max,
                variation_ppm: i64::from(a.variation_ppm),
                start: 0,
                dangers: Vec::new(),
            },
            &a.sensors,
            a.drives
                .iter()
                .map(|d| (d.when.as_str(), d.speed, None))
                .collect(),
        ),
        KindDef::Tank(t) => (
            Line {
                motion: Motion::Tank,
                unit: t.unit.clone(),
                points: vec![0, micro(t.capacity), micro(t.start)],
                windows: Vec::new(),
                moving: None,
                movers: Vec::new(),
                low: t.dry_run,
                high: t.overflow,
                variation_ppm: i64::from(t.variation_ppm),
                start: 0,
                dangers: Vec::new(),
            },
            &t.sensors,
            t.flows
                .iter()
                .map(|f| (f.when.as_str(), f.rate, f.sensor.as_deref()))
                .collect(),
        ),
        _ => return Ok(None),
    };
    for w in windows {
        let (from, to) = (micro(w.from), micro(w.to));
        l.windows.push((input(bundle, &w.signal)?, from, to));
        l.points.extend([from, to]);
    }
    for (when, speed, sensor) in movers {
        l.movers.push(Mover {
            dnf: compile(when, bundle)?,
            speed: micro(speed / 1000.0),
            sensor: sensor.map(|s| input(bundle, s)).transpose()?,
        });
    }
    for d in desc.dangers.iter().filter(|d| d.component == id) {
        let (from, to) = (micro(d.from), micro(d.to));
        l.dangers
            .push((d.id.clone(), from, to, compile(&d.when, bundle)?));
        l.points.extend([from, to]);
    }
    let (lo, hi) = (l.points[0], l.points[1]);
    let start = l.points[2];
    l.points.retain(|p| (lo..=hi).contains(p));
    l.points.sort_unstable();
    l.points.dedup();
    l.start = l.zone_of(start);
    Ok(Some(l))
}

/// The variables a DNF reads (space, index), now or at t-1.
fn reads(dnf: &Dnf, out: &mut BTreeSet<(Space, u32)>) {
    for t in dnf {
        for lit in t {
            out.insert((lit.var.space, lit.var.index));
        }
    }
}

/// The variables a DNF reads at t-1.
fn reads_prev(dnf: &Dnf, out: &mut BTreeSet<(Space, u32)>) {
    for t in dnf {
        for lit in t.iter().filter(|l| l.var.prev) {
            out.insert((lit.var.space, lit.var.index));
        }
    }
}

/// An abstract state.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct State {
    zone: u16,
    /// The component's activity sensors (motion, flow sensors) as last seen.
    active: Vec<usize>,
    /// The variables read at t-1 ([`Sub::prev`]), their values.
    prev: Vec<bool>,
    counts: Vec<u32>,
}

/// What one sub-plant's search needs.
struct Sub<'a> {
    bundle: &'a PlantBundle,
    line: Line,
    free_in: Vec<usize>,
    aux: Vec<usize>,
    free_out: Vec<usize>,
    filter: Option<Filter>,
    /// The variables something reads at t-1: only they are kept in a state.
    prev: Vec<(Space, usize)>,
    /// Every output at its safe value every cycle, instead of any vector.
    safe_only: bool,
    sizes: [usize; 4],
}

impl Sub<'_> {
    fn names(&self, space: Space, bits: &crate::bits::Bits) -> Vec<String> {
        bits.ones()
            .map(|k| self.bundle.symbols.name(space, k as u32).to_string())
            .collect()
    }

    /// The frame at a cycle's start: the component's sensors, the free inputs (`env`),
    /// the previous cycle; then the observers.
    fn start_frame(&self, s: &State, env: u32, frame: &mut Frame, obs: &mut Observers) {
        let z = usize::from(s.zone);
        for sp in 0..4 {
            frame.now[sp].clear();
            frame.prev[sp].clear();
        }
        for &(i, from, to) in &self.line.windows {
            frame.now[0].set(i, self.line.within(z, from, to));
        }
        for &i in &s.active {
            frame.now[0].set(i, true);
        }
        for (j, &i) in self.free_in.iter().enumerate() {
            frame.now[0].set(i, env >> j & 1 == 1);
        }
        for (j, &i) in self.aux.iter().enumerate() {
            let k = self.free_in.len() + j;
            frame.now[Space::Aux as usize].set(i, env >> k & 1 == 1);
        }
        for (&(sp, k), v) in self.prev.iter().zip(&s.prev) {
            frame.prev[sp as usize].set(k, *v);
        }
        obs.set_counts(&s.counts);
        obs.update(frame);
    }

    /// Commands vector `c` of the free outputs (the safe values with `safe_only`), then
    /// the filter: the frame's outputs are the applied ones; returns the commanded.
    fn apply(
        &self,
        c: u32,
        frame: &mut Frame,
        fallback: Option<&Result<Bits, crate::filter::SpecError>>,
        viol: &mut Vec<usize>,
    ) -> Bits {
        frame.now[1].clear();
        for (j, &o) in self.free_out.iter().enumerate() {
            let v = if self.safe_only {
                self.bundle.plant.outputs[o].safe == crate::plant::SafeValue::One
            } else {
                c >> j & 1 == 1
            };
            frame.now[1].set(o, v);
        }
        let commanded = frame.now[1].clone();
        if let Some(f) = &self.filter {
            f.violations_into(frame, viol);
            if !viol.is_empty() {
                match fallback {
                    Some(Ok(b)) => frame.now[1].copy_from(b),
                    // No fallback: the engine stops everything.
                    _ => frame.now[1].clear(),
                }
            }
        }
        commanded
    }

    /// The values kept for the next cycle's `X*`.
    fn prev_of(&self, inputs: &Bits, applied: &Bits, observers: &Bits, aux: &Bits) -> Vec<bool> {
        self.prev
            .iter()
            .map(|&(sp, k)| match sp {
                Space::Input => inputs.get(k),
                Space::Output => applied.get(k),
                Space::Observer => observers.get(k),
                Space::Aux => aux.get(k),
            })
            .collect()
    }

    /// Breadth-first search: the hazards reached, states, transitions, truncated.
    fn explore(&self) -> (Vec<Reached>, usize, u64, bool) {
        let s0 = State {
            zone: self.line.start as u16,
            active: Vec::new(),
            prev: vec![false; self.prev.len()],
            counts: vec![0; self.sizes[2]],
        };
        let mut index: HashMap<State, u32> = HashMap::new();
        let mut states = vec![s0.clone()];
        let mut parent: Vec<Option<(u32, TraceStep)>> = vec![None];
        index.insert(s0, 0);
        let mut found: Vec<Reached> = Vec::new();
        let mut frame = Frame::new(self.sizes);
        let mut obs = self.bundle.observers.clone();
        let mut viol = Vec::new();
        let mut transitions = 0u64;
        let mut queue = VecDeque::from([0u32]);
        let free = self.free_in.len() + self.aux.len();
        let mut truncated = false;
        while let Some(si) = queue.pop_front() {
            let s = states[si as usize].clone();
            let z = usize::from(s.zone);
            for env in 0..(1u32 << free) {
                self.start_frame(&s, env, &mut frame, &mut obs);
                let counts = obs.counts().to_vec();
                let inputs = frame.now[0].clone();
                let observers = frame.now[2].clone();
                let aux_now = frame.now[3].clone();
                let fallback = self.filter.as_ref().map(|f| f.fallback(&frame));
                let mut applied_seen: Vec<crate::bits::Bits> = Vec::new();
                let vectors = if self.safe_only {
                    1
                } else {
                    1u32 << self.free_out.len()
                };
                for c in 0..vectors {
                    let commanded = self.apply(c, &mut frame, fallback.as_ref(), &mut viol);
                    let applied = frame.now[1].clone();
                    if applied_seen.contains(&applied) {
                        continue;
                    }
                    applied_seen.push(applied.clone());
                    let step = TraceStep {
                        zone: self.line.text(z),
                        inputs: self.names(Space::Input, &inputs),
                        commanded: self.names(Space::Output, &commanded),
                        applied: self.names(Space::Output, &applied),
                    };
                    let (v, moving, running) = self.line.speed(z, &frame);
                    for next in self.line.next(z, v) {
                        transitions += 1;
                        // The cycle's hazards, and the dangers of this successor's zone.
                        let mut hazards = moving.clone();
                        for (id, from, to, when) in &self.line.dangers {
                            let inside = self.line.within(next, *from, *to);
                            if inside && eval_dnf(when, &frame) {
                                hazards.push(SubHazard::Declared(id.clone()));
                            }
                        }
                        // Its motion sensor sees it move (not pushed against its end).
                        let mut active = running.clone();
                        let moved = next != z || self.line.bounds(z).0 != self.line.bounds(z).1;
                        active.extend(self.line.moving.filter(|_| v != 0 && moved));
                        let new: Vec<SubHazard> = hazards
                            .iter()
                            .filter(|h| !found.iter().any(|r| &r.hazard == *h))
                            .cloned()
                            .collect();
                        for h in new {
                            let trace = trace_to(&parent, si, &step);
                            found.push(Reached { hazard: h, trace });
                        }
                        if !hazards.is_empty() {
                            continue;
                        }
                        let n = State {
                            zone: next as u16,
                            active,
                            prev: self.prev_of(&inputs, &applied, &observers, &aux_now),
                            counts: counts.clone(),
                        };
                        if index.contains_key(&n) {
                            continue;
                        }
                        if states.len() >= MAX_STATES {
                            truncated = true;
                            continue;
                        }
                        let id = states.len() as u32;
                        index.insert(n.clone(), id);
                        states.push(n);
                        parent.push(Some((si, step.clone())));
                        queue.push_back(id);
                    }
                }
            }
        }
        found.sort_by(|a, b| a.hazard.cmp(&b.hazard));
        (found, states.len(), transitions, truncated)
    }
}

/// The trace to state `si` (by the parents' steps), then `last`.
fn trace_to(parent: &[Option<(u32, TraceStep)>], si: u32, last: &TraceStep) -> Vec<TraceStep> {
    let mut trace = vec![last.clone()];
    let mut at = si;
    while let Some((p, st)) = &parent[at as usize] {
        trace.push(st.clone());
        at = *p;
    }
    trace.reverse();
    trace
}

/// The hazards a line can have.
fn hazards_of(l: &Line) -> Vec<SubHazard> {
    let mut out = Vec::new();
    match l.motion {
        Motion::Axis => {
            let up = l.movers.iter().any(|m| m.speed > 0);
            let down = l.movers.iter().any(|m| m.speed < 0);
            if up && down {
                out.push(SubHazard::OpposedDrives);
            }
            if l.low == EndStop::Crash {
                out.push(SubHazard::EndStop("min".into()));
            }
            if l.high == EndStop::Crash {
                out.push(SubHazard::EndStop("max".into()));
            }
        }
        Motion::Tank => {
            if l.high == EndStop::Crash {
                out.push(SubHazard::Overflow);
            }
            if l.low == EndStop::Crash {
                out.push(SubHazard::DryRun);
            }
        }
    }
    out.extend(l.dangers.iter().map(|d| SubHazard::Declared(d.0.clone())));
    out
}

/// What a sub-plant's search reads and chooses.
struct Scope {
    /// The constraints that guard it.
    set: ConstraintSet,
    free_in: Vec<usize>,
    aux: Vec<usize>,
    free_out: Vec<usize>,
    /// The variables read at t-1.
    prev: BTreeSet<(Space, u32)>,
}

/// A component's scope: its own signals; the observers and constraints that read them
/// (an observer's readers too); the other inputs they read, free; the outputs they and
/// the component's drives and dangers name, chosen by the control.
fn scope(l: &Line, bundle: &PlantBundle) -> Result<Scope, Problem> {
    // Its own signals; the constraints and observers that read them.
    let mut own: BTreeSet<(Space, u32)> = BTreeSet::new();
    for &(i, _, _) in &l.windows {
        own.insert((Space::Input, i as u32));
    }
    own.extend(l.moving.map(|i| (Space::Input, i as u32)));
    let mut named: BTreeSet<(Space, u32)> = BTreeSet::new();
    let mut prev: BTreeSet<(Space, u32)> = BTreeSet::new();
    for m in &l.movers {
        own.extend(m.sensor.map(|i| (Space::Input, i as u32)));
        reads(&m.dnf, &mut named);
        reads_prev(&m.dnf, &mut prev);
    }
    for d in &l.dangers {
        reads(&d.3, &mut named);
        reads_prev(&d.3, &mut prev);
    }
    own.extend(named.iter().filter(|v| v.0 == Space::Output).copied());
    let mut relevant_obs: BTreeSet<u32> = BTreeSet::new();
    for (k, o) in bundle.observers.defs.iter().enumerate() {
        let (mut r, mut p) = (BTreeSet::new(), BTreeSet::new());
        for t in o.rule.expressions() {
            let d = compile(t, bundle)?;
            reads(&d, &mut r);
            reads_prev(&d, &mut p);
        }
        if r.iter().any(|v| own.contains(v)) {
            relevant_obs.insert(k as u32);
            named.extend(r);
            prev.extend(p);
        }
    }
    let mut set = ConstraintSet::default();
    for k in &bundle.constraints.constraints {
        let mut r = BTreeSet::new();
        reads(&k.dnf, &mut r);
        let mine = r
            .iter()
            .any(|v| own.contains(v) || (v.0 == Space::Observer && relevant_obs.contains(&v.1)));
        if mine {
            named.extend(r);
            reads_prev(&k.dnf, &mut prev);
            set.constraints.push(k.clone());
        }
    }
    let mut free_in: Vec<usize> = Vec::new();
    let mut aux: Vec<usize> = Vec::new();
    let mut free_out: Vec<usize> = Vec::new();
    for &(space, i) in &named {
        match space {
            Space::Input if !own.contains(&(space, i)) => free_in.push(i as usize),
            Space::Output => free_out.push(i as usize),
            Space::Aux => aux.push(i as usize),
            _ => {}
        }
    }
    Ok(Scope {
        set,
        free_in,
        aux,
        free_out,
        prev,
    })
}

/// Verifies every sub-plant of a plant of components.
pub fn verify_components(
    bundle: &PlantBundle,
    desc: &Components,
) -> Result<ComponentsReport, Problem> {
    let sizes = [
        bundle.plant.inputs.len(),
        bundle.plant.outputs.len(),
        bundle.observers.len(),
        bundle.symbols.names(Space::Aux).len(),
    ];
    let mut parts = Vec::new();
    let mut not_modelled = Vec::new();
    for c in &desc.components {
        let Some(l) = line(&c.id, &c.kind, desc, bundle)? else {
            if !matches!(c.kind, KindDef::Button(_)) {
                not_modelled.push(c.id.clone());
            }
            continue;
        };
        let hazards = hazards_of(&l);
        if hazards.is_empty() {
            continue;
        }
        let Scope {
            set,
            free_in,
            aux,
            free_out,
            prev,
        } = scope(&l, bundle)?;
        let name = |s: Space, v: &[usize]| -> Vec<String> {
            v.iter()
                .map(|&k| bundle.symbols.name(s, k as u32).to_string())
                .collect()
        };
        let mut report = SubReport {
            component: c.id.clone(),
            hazards,
            free_inputs: name(Space::Input, &free_in)
                .into_iter()
                .chain(name(Space::Aux, &aux))
                .collect(),
            free_outputs: name(Space::Output, &free_out),
            constraints: set.constraints.iter().map(|k| k.id.clone()).collect(),
            skipped: None,
            states: 0,
            transitions: 0,
            truncated: false,
            without_filter: Vec::new(),
            with_filter: Vec::new(),
            uncontrollable: Vec::new(),
        };
        if free_in.len() + aux.len() + free_out.len() > MAX_FREE {
            report.skipped = Some(format!(
                "{} free inputs and {} free outputs: more than {MAX_FREE} together (2^n vectors a cycle)",
                free_in.len() + aux.len(),
                free_out.len()
            ));
            parts.push(report);
            continue;
        }
        let mut sub = Sub {
            bundle,
            line: l,
            free_in,
            aux,
            free_out,
            filter: None,
            prev: prev.iter().map(|&(sp, k)| (sp, k as usize)).collect(),
            safe_only: true,
            sizes,
        };
        report.uncontrollable = sub.explore().0.into_iter().map(|r| r.hazard).collect();
        sub.safe_only = false;
        report.without_filter = sub.explore().0;
        sub.filter = Some(Filter::for_plant(&set, &bundle.plant));
        let (found, states, transitions, truncated) = sub.explore();
        report.with_filter = found;
        report.states = states;
        report.transitions = transitions;
        report.truncated = truncated;
        parts.push(report);
    }
    Ok(ComponentsReport {
        plant: desc.name.clone(),
        parts,
        not_modelled,
        assumptions: vec![
            "one component at a time, with every input it does not write that its constraints, observers, drives or dangers read free at every cycle".into(),
            "the control commands any vector of the outputs its drives, dangers and constraints name, every cycle; the other outputs are 0".into(),
            "a component moves at most as far as its fastest drive goes in one 10 ms cycle, and may move as slowly as it likes".into(),
            "no fault: the plant's components, sensors and contactors are healthy".into(),
            "the operator may reset the filter at any cycle (the latch is abstracted away)".into(),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 60 mm cylinder with windows [0, 2] and [58, 60] at 120 mm/s (1.2 mm a cycle).
    fn cylinder() -> Line {
        Line {
            motion: Motion::Axis,
            unit: "mm".into(),
            points: [0.0, 2.0, 58.0, 60.0].map(micro).to_vec(),
            windows: vec![(0, micro(0.0), micro(2.0)), (1, micro(58.0), micro(60.0))],
            moving: None,
            movers: Vec::new(),
            low: EndStop::Rest,
            high: EndStop::Crash,
            variation_ppm: 0,
            start: 0,
            dangers: Vec::new(),
        }
    }

    #[test]
    fn zones_are_the_points_and_the_intervals_between_them() {
        let l = cylinder();
        assert_eq!(l.zones(), 7);
        assert_eq!(l.zone_of(0), 0);
        assert_eq!(l.zone_of(micro(1.0)), 1);
        assert_eq!(l.zone_of(micro(2.0)), 2);
        assert_eq!(l.zone_of(micro(30.0)), 3);
        assert_eq!(l.zone_of(micro(60.0)), 6);
        // A window is on exactly on the zones inside it.
        let on: Vec<bool> = (0..7).map(|z| l.within(z, 0, micro(2.0))).collect();
        assert_eq!(on, [true, true, true, false, false, false, false]);
        assert_eq!(l.text(3), "(2, 58) mm");
    }

    #[test]
    fn a_cycle_moves_as_far_as_the_speed_reaches_and_never_rests_on_a_point() {
        let l = cylinder();
        let v = micro(120.0 / 1000.0);
        // From the point 0: into (0, 2); 2 is 2 mm away, beyond a cycle's 1.2 mm.
        assert_eq!(l.next(0, v), vec![1]);
        // From (0, 2): stay, reach 2, or cross it into (2, 58) (the far edge is 2).
        assert_eq!(l.next(1, v), vec![1, 2, 3]);
        // From the point 2: leave it.
        assert_eq!(l.next(2, v), vec![3]);
        // From (2, 58): stay, 58, or past it into (58, 60); not 60 (2 mm away).
        assert_eq!(l.next(3, v), vec![3, 4, 5]);
        // At the end it stays (driven into it).
        assert_eq!(l.next(6, v), vec![6]);
        assert_eq!(l.next(6, -v), vec![5]);
        assert_eq!(l.next(3, 0), vec![3]);
        // Fast enough to skip a window: a 2 mm window at 300 mm/s (3 mm a cycle).
        let fast = micro(300.0 / 1000.0);
        assert_eq!(l.next(3, fast), vec![3, 4, 5, 6]);
    }
}
