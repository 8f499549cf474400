//! The items on the plant's surfaces: the belts of the conveyors and the rollers of
//! the turntables, joined end to end.
//!
//! # Model
//!
//! Every surface is a 1-D axis `0..len` (millionths of its unit). An item lies on
//! `[c - half, c + half]` of the surface its centre `c` is on, and may overhang an end
//! onto the surface joined there: a conveyor's exit joined to the next conveyor's
//! entry (`exit: To(id)`), a turntable's rollers joined to a conveyor while the table
//! stands at a position that joins them. An item moves with the surface under its
//! centre or, when that one is stopped, with a joined surface it lies on by more than
//! the straddle margin (`items.straddle_margin`). Items block each other on contact:
//! on a belt that does not accumulate (`accumulating: false`), a driven item held by
//! one not moving away as fast is a collision. An item whose centre passes an end goes
//! to the surface joined there, into a sink (delivered), or falls (a hazard); an end
//! stop (`exit: Stop`, a conveyor's entry nothing feeds) holds it. An item lying on two
//! surfaces by more than the margin on each, driven by one against the other (stopped
//! or reversed), is pushed against a stopped surface once the driving one has slid
//! under it `items.push_tolerance` without a break. An item overhanging a turntable's
//! edge by more than `items.shear_margin` while the table stands between positions is
//! sheared.
//!
//! This is the sorting station's physics (seed 004, section 6), which its emulator
//! had built into one layout: here every conveyor and turntable of any plant shares it.
//! Integer arithmetic throughout: a run is a function of its seed and its inputs.

use crate::emulator::{Hazard, HazardKind, Place};
use crate::synthetic::SplitMix64;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// An end of a surface: its start (0, the entry) or its end (1, the exit).
pub(crate) const START: usize = 0;
/// The exit end.
pub(crate) const END: usize = 1;

/// The plant-wide constants of the items' physics, in the surfaces' unit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ItemsDef {
    /// An item lying on two surfaces by at most this much on one of them is carried
    /// by the other alone and is not pushed against it.
    #[serde(default = "straddle")]
    pub straddle_margin: f64,
    /// An item overhanging a turntable's edge by more than this while the table turns
    /// is sheared.
    #[serde(default = "shear")]
    pub shear_margin: f64,
    /// How far a surface may slide under an item held by a stopped one, without a
    /// break, before the item is damaged.
    #[serde(default)]
    pub push_tolerance: f64,
    /// Arrivals wait until the entry is free by the item's length and this gap.
    #[serde(default = "gap")]
    pub arrival_gap: f64,
}

fn straddle() -> f64 {
    25.0
}
fn shear() -> f64 {
    2.0
}
fn gap() -> f64 {
    10.0
}

impl Default for ItemsDef {
    fn default() -> Self {
        Self {
            straddle_margin: straddle(),
            shear_margin: shear(),
            push_tolerance: 0.0,
            arrival_gap: gap(),
        }
    }
}

impl ItemsDef {
    pub(crate) fn check(&self) -> Vec<String> {
        let ok = |v: f64| v.is_finite() && (0.0..1e6).contains(&v);
        let mut out = Vec::new();
        for (name, v) in [
            ("straddle_margin", self.straddle_margin),
            ("shear_margin", self.shear_margin),
            ("push_tolerance", self.push_tolerance),
            ("arrival_gap", self.arrival_gap),
        ] {
            if !ok(v) {
                out.push(format!("items: {name} {v} must be from 0 to 1e6"));
            }
        }
        out
    }
}

/// One end of a surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Link {
    pub(crate) surface: usize,
    pub(crate) end: usize,
}

/// What an end does where nothing is joined to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Open {
    /// An end stop: items wait there.
    Stop,
    /// Nothing: an item whose centre passes it falls.
    Drop,
    /// A sink: an item whose centre passes it is delivered.
    Sink,
}

/// A presence beam across a surface.
#[derive(Clone, Debug)]
pub(crate) struct Beam {
    pub(crate) input: usize,
    pub(crate) at: i64,
    pub(crate) sees: Option<String>,
}

/// A conveyor's belt or a turntable's rollers.
#[derive(Clone, Debug)]
pub(crate) struct Surface {
    /// The component it belongs to.
    pub(crate) component: usize,
    pub(crate) id: String,
    pub(crate) name: String,
    pub(crate) len: i64,
    pub(crate) beams: Vec<Beam>,
    pub(crate) open: [Open; 2],
    pub(crate) fixed: [Option<Link>; 2],
    /// A turntable turns beyond this end (or this is a turntable's end).
    pub(crate) table_side: [bool; 2],
    pub(crate) accumulating: bool,
    /// The outputs its drives read, for the hazards' reports.
    pub(crate) actuators: Vec<String>,
    /// A turntable's rollers: the outputs its rotation reads.
    pub(crate) rotation: Option<Vec<String>>,
}

/// A join that holds while a turntable stands at one of its positions.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dock {
    pub(crate) table: usize,
    pub(crate) position: usize,
    pub(crate) table_end: usize,
    pub(crate) to: Link,
}

/// An item class as the network places it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Class {
    pub(crate) class: String,
    pub(crate) tags: Vec<String>,
    pub(crate) length: i64,
}

/// An item on a surface.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Body {
    /// Its number, from 1, in the order it was placed.
    pub id: u32,
    /// Its class.
    pub class: String,
    /// Its tags.
    pub tags: Vec<String>,
    /// Half its length, millionths.
    pub half: i64,
    /// The surface its centre is on.
    pub surface: usize,
    /// Its centre, millionths from the surface's start.
    pub c: i64,
    /// Damaged by a hazard.
    pub damaged: bool,
    reported: u16,
    slip: i64,
}

/// Arrivals on a surface's entry: one item every period (plus a seeded delay), its
/// class from the source's list in turn or at random.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArrivalsDef {
    /// The period, ms (at least 1).
    pub period_ms: u64,
    /// Each arrival is delayed by a seeded `0..=jitter_ms`.
    #[serde(default)]
    pub jitter_ms: u64,
    /// How many, then no more (unbounded when absent).
    #[serde(default)]
    pub count: Option<u64>,
    /// How the class of each is chosen among the source's.
    #[serde(default)]
    pub mix: Mix,
}

/// How an arrival's class is chosen.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Mix {
    /// The classes in turn.
    #[default]
    InTurn,
    /// The second class with this percentage, else the first.
    SecondPercent(u8),
}

/// An arrival plan: periodic, or a list of (time, class index).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Plan {
    /// No arrivals.
    Off,
    /// Periodic.
    Periodic(ArrivalsDef),
    /// At these times (ms), these classes (by index in the source's list).
    List(Vec<(u64, usize)>),
}

/// A source of arrivals on a surface's entry.
#[derive(Clone, Debug)]
pub(crate) struct Source {
    pub(crate) surface: usize,
    pub(crate) classes: Vec<Class>,
    pub(crate) plan: Plan,
    pub(crate) rng: SplitMix64,
    k: u64,
    origin: u64,
    next: Option<(u64, usize)>,
    pending: VecDeque<usize>,
}

impl Source {
    pub(crate) fn new(surface: usize, classes: Vec<Class>, plan: Plan, seed: u64) -> Self {
        let mut s = Self {
            surface,
            classes,
            plan: Plan::Off,
            rng: SplitMix64::new(seed),
            k: 0,
            origin: 0,
            next: None,
            pending: VecDeque::new(),
        };
        s.set_plan(plan, 0);
        s
    }

    /// Replaces the plan; a periodic plan restarts its period from `now`.
    pub(crate) fn set_plan(&mut self, mut plan: Plan, now: u64) {
        if let Plan::List(list) = &mut plan {
            list.sort_unstable();
        }
        self.plan = plan;
        self.k = 0;
        self.origin = now;
        self.next = None;
        self.plan_next();
    }

    fn plan_next(&mut self) {
        let n = self.classes.len().max(1);
        self.next = match &self.plan {
            Plan::Off => None,
            Plan::List(list) => list.get(self.k as usize).copied(),
            Plan::Periodic(ArrivalsDef { count: Some(c), .. }) if self.k >= *c => None,
            Plan::Periodic(a) => {
                let base = self.origin + self.k.saturating_mul(a.period_ms.max(1));
                let t = base + self.rng.below(a.jitter_ms + 1);
                let class = match a.mix {
                    Mix::InTurn => (self.k % n as u64) as usize,
                    Mix::SecondPercent(p) => {
                        usize::from(self.rng.below(100) < u64::from(p)).min(n - 1)
                    }
                };
                Some((t, class))
            }
        };
    }

    /// A periodic plan's arrivals are due or waiting.
    fn busy(&self, now: u64) -> bool {
        !self.pending.is_empty() || self.next.is_some_and(|(t, _)| t <= now)
    }
}

/// What a surface's component asks of the network in one step.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Requests {
    /// Surface speed, millionths per step, signed (positive towards the exit end).
    pub(crate) velocity: i64,
    /// The feeder rose: place this class at the entry (or a collision).
    pub(crate) feed: Option<usize>,
    /// The feeder rose and carries from this surface's taker.
    pub(crate) feed_carried: Option<usize>,
    /// The taker rose.
    pub(crate) take: bool,
}

/// Every item of the plant and the surfaces they lie on.
#[derive(Clone, Debug)]
pub(crate) struct Items {
    pub(crate) surfaces: Vec<Surface>,
    pub(crate) docks: Vec<Dock>,
    /// Per surface, its component's feeder classes (feeds place these).
    pub(crate) feed_classes: Vec<Vec<Class>>,
    /// Per surface, the outputs its feeder's condition reads (a collision's report).
    pub(crate) feed_outputs: Vec<Vec<String>>,
    /// Per surface: the items its taker holds for a feeder elsewhere (a gripper).
    pub(crate) carried: Vec<VecDeque<Body>>,
    /// Per surface: some feeder places what its taker picks.
    pub(crate) carries: Vec<bool>,
    pub(crate) sources: Vec<Source>,
    /// Per surface: the position each turntable stands at (None: between positions, or
    /// not a turntable).
    docked: Vec<Option<usize>>,
    links: Vec<[Option<Link>; 2]>,
    vel: Vec<i64>,
    pub(crate) bodies: Vec<Body>,
    scratch: Vec<(i64, i64, i64)>,
    straddle: i64,
    shear: i64,
    tolerance: i64,
    gap: i64,
    next_id: u32,
    /// Per surface: items delivered into its sink, taken by its taker (counted out).
    pub(crate) delivered: Vec<u32>,
    pub(crate) taken: Vec<u32>,
    pub(crate) damaged: u32,
    pub(crate) fallen: u32,
    /// Taken off by hand (an operator emptying the plant), fallen ones included.
    pub(crate) removed: u32,
    /// Fallen and still lying where they fell (their surface and centre as they
    /// fell, past its end).
    pub(crate) lying: Vec<Body>,
}

fn micro(v: f64) -> i64 {
    (v * 1e6).round() as i64
}

/// Velocity factor from the axis of a surface, across its end `e`, into the axis of
/// the surface joined at its end `q`: +1 when the axes continue, -1 when they face.
#[inline]
fn factor(e: usize, q: usize) -> i64 {
    if e == q { -1 } else { 1 }
}

/// Length of an item beyond end `e` of a surface of length `len` (negative inside).
#[inline]
fn overhang(b: &Body, e: usize, len: i64) -> i64 {
    if e == END {
        b.c + b.half - len
    } else {
        b.half - b.c
    }
}

impl Items {
    pub(crate) fn new(
        surfaces: Vec<Surface>,
        docks: Vec<Dock>,
        def: &ItemsDef,
        feed_classes: Vec<Vec<Class>>,
    ) -> Self {
        let n = surfaces.len();
        let mut items = Self {
            surfaces,
            docks,
            feed_classes,
            feed_outputs: vec![Vec::new(); n],
            carried: vec![VecDeque::new(); n],
            carries: vec![false; n],
            sources: Vec::new(),
            docked: vec![None; n],
            links: vec![[None; 2]; n],
            vel: vec![0; n],
            bodies: Vec::with_capacity(16),
            scratch: Vec::with_capacity(16),
            straddle: micro(def.straddle_margin),
            shear: micro(def.shear_margin),
            tolerance: micro(def.push_tolerance),
            gap: micro(def.arrival_gap),
            next_id: 1,
            delivered: vec![0; n],
            taken: vec![0; n],
            damaged: 0,
            fallen: 0,
            removed: 0,
            lying: Vec::new(),
        };
        items.update_links();
        items
    }

    /// The items placed so far.
    pub(crate) fn created(&self) -> u32 {
        self.next_id - 1
    }

    /// Sets the position turntable surface `s` stands at; true when it changed.
    pub(crate) fn set_docked(&mut self, s: usize, position: Option<usize>) -> bool {
        if self.docked[s] == position {
            return false;
        }
        self.docked[s] = position;
        self.update_links();
        true
    }

    fn update_links(&mut self) {
        for (s, surface) in self.surfaces.iter().enumerate() {
            self.links[s] = surface.fixed;
        }
        for d in &self.docks {
            if self.docked[d.table] == Some(d.position) {
                self.links[d.table][d.table_end] = Some(d.to);
                self.links[d.to.surface][d.to.end] = Some(Link {
                    surface: d.table,
                    end: d.table_end,
                });
            }
        }
    }

    fn joined(&self, p: usize, q: usize) -> bool {
        p == q
            || self.links[p]
                .iter()
                .any(|l| l.is_some_and(|l| l.surface == q))
    }

    /// Nothing can change without a command: no surface moves, no arrival waits or is
    /// due before `until`.
    pub(crate) fn idle(&self, until: u64) -> bool {
        self.vel.iter().all(|&v| v == 0)
            && self
                .sources
                .iter()
                .all(|s| s.pending.is_empty() && s.next.is_none_or(|(t, _)| t > until))
    }

    /// How many of the next `max` steps (each `step_ms`, from `now`) can be taken at
    /// once with the same velocities: those before an arrival is due or a waiting one
    /// could find its entry free, and before any item reaches an end or a joint, or
    /// its centre crosses one ([`Self::quiet_body`]); items of one surface move
    /// together. 0 when none can.
    pub(crate) fn quiet_steps(
        &self,
        now: u64,
        step_ms: u64,
        max: u64,
        turning: impl Fn(usize) -> bool,
    ) -> u64 {
        let mut k = max;
        for src in &self.sources {
            if let Some((at, _)) = src.next {
                // The arrival is taken in the step whose time reaches `at`.
                let before = at.saturating_sub(now) / step_ms.max(1);
                k = k.min(before.saturating_sub(1));
            }
            // An arrival waits for its entry: the steps before the items there could
            // leave it room (none while they stand).
            let Some(c) = src.pending.front().and_then(|&i| src.classes.get(i)) else {
                continue;
            };
            let v = self.vel[src.surface];
            if v > 0 {
                let need = c.length + self.gap;
                let rear = self
                    .bodies
                    .iter()
                    .filter(|b| b.surface == src.surface)
                    .map(|b| b.c - b.half)
                    .min()
                    .unwrap_or(need);
                if rear >= need {
                    return 0;
                }
                k = k.min(u64::try_from((need - rear - 1) / v).unwrap_or(0));
            } else if v < 0 {
                return 0;
            }
        }
        for b in &self.bodies {
            match self.quiet_body(b, &turning) {
                Some(q) => k = k.min(q),
                None => return 0,
            }
        }
        k
    }

    /// How many steps item `b` may take straight (`None`: not one). On a stopped
    /// surface, any while it does not overhang it (an arrival waiting at a stopped
    /// entry). Moving, those before it reaches an end of its surface; or, when it
    /// overhangs an end already, those before its centre crosses that end, provided
    /// the end is open (a sink, a drop: nothing happens before the centre passes) or
    /// joined to a surface that moves it the same way at the same speed, neither of
    /// them a turning table (nothing slides, pushes or shears).
    fn quiet_body(&self, b: &Body, turning: &impl Fn(usize) -> bool) -> Option<u64> {
        let s = b.surface;
        let len = self.surfaces[s].len;
        let v = self.vel[s];
        let (rear, front) = (b.c - b.half, len - b.c - b.half);
        if v == 0 {
            return (rear >= 0 && front >= 0).then_some(u64::MAX);
        }
        for (e, room) in [(START, rear), (END, front)] {
            if room > 0 {
                continue;
            }
            let along = if e == END { v } else { -v };
            let table_side = self.surfaces[s].table_side[e];
            let joined = match self.links[s][e] {
                // Docked to a table that stands, or between conveyors.
                Some(l) => {
                    self.vel[l.surface] * factor(e, l.end) == v
                        && !turning(s)
                        && !turning(l.surface)
                }
                // A turntable's edge, or a conveyor's end a turntable turns beyond,
                // with nothing docked: the shear is checked step by step.
                None => {
                    !table_side && room < 0 && self.surfaces[s].open[e] != Open::Stop && along > 0
                }
            };
            if !joined {
                return None;
            }
        }
        let steps = |d: i64| u64::try_from((d - 1) / v.abs()).unwrap_or(0);
        Some(if v > 0 {
            if front > 0 {
                steps(front)
            } else {
                steps(len - b.c)
            }
        } else if rear > 0 {
            steps(rear)
        } else {
            steps(b.c)
        })
    }

    /// Takes `k` quiet steps at once ([`Self::quiet_steps`]): the same positions as
    /// `k` single steps.
    pub(crate) fn advance(&mut self, k: u64) {
        let k = i64::try_from(k).unwrap_or(0);
        for b in &mut self.bodies {
            b.c += self.vel[b.surface] * k;
            b.slip = 0;
        }
    }

    /// One step at time `now`: the surfaces' velocities and their components'
    /// requests; the feeders place and the takers take, then the items move, pass
    /// from surface to surface and are hurt; then the sources' arrivals come.
    pub(crate) fn step(&mut self, now: u64, requests: &[Requests], hazards: &mut Vec<Hazard>) {
        for (v, r) in self.vel.iter_mut().zip(requests) {
            *v = r.velocity;
        }
        for (s, r) in requests.iter().enumerate() {
            if let Some(from) = r.feed_carried {
                if let Some(b) = self.carried[from].pop_front() {
                    self.feed(now, s, b, hazards);
                }
            } else if let Some(k) = r.feed
                && let Some(class) = self.feed_classes[s].get(k)
            {
                let b = self.body(class);
                self.feed(now, s, b, hazards);
            }
        }
        for (s, r) in requests.iter().enumerate() {
            if r.take {
                self.take(s);
            }
        }
        if !self.bodies.is_empty() {
            self.move_bodies(now, hazards);
            self.transfer(now, hazards);
            self.check_hazards(now, hazards);
        }
        self.arrivals(now);
    }

    fn body(&self, class: &Class) -> Body {
        Body {
            id: 0,
            class: class.class.clone(),
            tags: class.tags.clone(),
            half: class.length / 2,
            surface: 0,
            c: 0,
            damaged: false,
            reported: 0,
            slip: 0,
        }
    }

    /// Places `b` with its rear at the entry of `s`; an item still there is a
    /// collision and nothing is placed.
    fn feed(&mut self, now: u64, s: usize, mut b: Body, hazards: &mut Vec<Hazard>) {
        let len = 2 * b.half;
        let blocker = self
            .bodies
            .iter()
            .filter(|o| self.joined(o.surface, s))
            .filter_map(|o| {
                let (c, _) = self.map_into(o.surface, o.c, s)?;
                Some((o.id, c - o.half, 2 * o.half))
            })
            .find(|&(_, rear, l)| rear <= len && rear + l >= 0);
        if let Some((other, _, _)) = blocker {
            let sf = &self.surfaces[s];
            hazards.push(Hazard {
                time_ms: now,
                kind: HazardKind::Collision,
                place: format!("entry of the {} (against item {other})", sf.name),
                at: Place::Against {
                    part: sf.id.clone(),
                    item: other,
                },
                elements: self.feed_outputs[s].clone(),
                box_id: b.id,
            });
            return;
        }
        if b.id == 0 {
            b.id = self.next_id;
            self.next_id += 1;
        }
        b.surface = s;
        b.c = b.half;
        b.slip = 0;
        self.bodies.push(b);
    }

    /// The taker of `s` rose: the item nearest the exit end, its front within its
    /// length of the end, is taken (carried to a feeder, or counted out).
    fn take(&mut self, s: usize) {
        if self.carries[s] && !self.carried[s].is_empty() {
            // A gripper holds one item: closing again regrips it.
            return;
        }
        let len = self.surfaces[s].len;
        let last = self
            .bodies
            .iter()
            .enumerate()
            .filter(|(_, b)| b.surface == s)
            .max_by_key(|(_, b)| b.c)
            .map(|(i, b)| (i, b.c + 2 * b.half >= len));
        if let Some((i, true)) = last {
            let b = self.bodies.remove(i);
            if self.carries[s] {
                self.carried[s].push_back(b);
            } else {
                self.taken[s] += 1;
            }
        }
    }

    fn arrivals(&mut self, now: u64) {
        for k in 0..self.sources.len() {
            let src = &mut self.sources[k];
            if !src.busy(now) {
                continue;
            }
            while let Some((t, class)) = src.next {
                if t > now {
                    break;
                }
                if src.pending.len() < 64 {
                    src.pending.push_back(class);
                }
                src.k += 1;
                src.plan_next();
            }
            let Some(&class) = src.pending.front() else {
                continue;
            };
            let s = src.surface;
            let Some(c) = src.classes.get(class).cloned() else {
                src.pending.pop_front();
                continue;
            };
            let gap = self.gap;
            let free = self
                .bodies
                .iter()
                .all(|b| b.surface != s || b.c - b.half >= c.length + gap);
            if free {
                self.sources[k].pending.pop_front();
                let mut b = self.body(&c);
                b.id = self.next_id;
                self.next_id += 1;
                b.surface = s;
                b.c = c.length / 2;
                self.bodies.push(b);
            }
        }
    }

    /// Puts an item of the `class`-th class of the first source with its centre at
    /// `centre` (millionths from the start of surface `s`): a live-mode estimate, a
    /// technician's hand. Returns its number; `None` when there is no such class.
    pub(crate) fn place(&mut self, s: usize, centre: i64, class: usize) -> Option<u32> {
        let c = self.sources.first()?.classes.get(class)?.clone();
        let mut b = self.body(&c);
        b.id = self.next_id;
        self.next_id += 1;
        b.surface = s;
        b.c = centre;
        let id = b.id;
        self.bodies.push(b);
        Some(id)
    }

    /// Centre of an item on `sj` at `cj`, in the axis of surface `p`, with the
    /// velocity factor.
    #[inline]
    fn map_into(&self, sj: usize, cj: i64, p: usize) -> Option<(i64, i64)> {
        if sj == p {
            return Some((cj, 1));
        }
        for e in [START, END] {
            if let Some(q) = self.links[p][e]
                && q.surface == sj
            {
                let len_j = self.surfaces[sj].len;
                let dj = if q.end == START { cj } else { len_j - cj };
                let c = if e == END {
                    self.surfaces[p].len + dj
                } else {
                    -dj
                };
                return Some((c, factor(e, q.end)));
            }
        }
        None
    }

    fn move_bodies(&mut self, now: u64, hazards: &mut Vec<Hazard>) {
        let margin = self.straddle;
        self.scratch.clear();
        for b in &self.bodies {
            let s = b.surface;
            let len = self.surfaces[s].len;
            let mut v = self.vel[s];
            if v == 0 {
                for e in [START, END] {
                    if overhang(b, e, len) > margin
                        && let Some(q) = self.links[s][e]
                    {
                        v = self.vel[q.surface] * factor(e, q.end);
                        if v != 0 {
                            break;
                        }
                    }
                }
            }
            let mut target = b.c + v;
            // End stops hold the item inside.
            for e in [START, END] {
                if self.links[s][e].is_none() && self.surfaces[s].open[e] == Open::Stop {
                    target = if e == END {
                        target.min((len - b.half).max(b.c))
                    } else {
                        target.max(b.half.min(b.c))
                    };
                }
            }
            self.scratch.push((v, target, -1));
        }
        let n = self.bodies.len();
        // Each pass settles at least one more item of a queue in contact.
        for _ in 0..=n {
            let mut changed = false;
            for i in 0..n {
                let (v, ci, _) = self.scratch[i];
                if v == 0 {
                    continue;
                }
                let bi = &self.bodies[i];
                for j in 0..n {
                    let bj = &self.bodies[j];
                    if i == j || !self.joined(bi.surface, bj.surface) {
                        continue;
                    }
                    let Some((cj, _)) = self.map_into(bj.surface, self.scratch[j].1, bi.surface)
                    else {
                        continue;
                    };
                    let reach = bi.half + bj.half;
                    let d = cj - self.scratch[i].1;
                    if d.signum() == v.signum() && d.abs() < reach {
                        let mut target = cj - v.signum() * reach;
                        if (target - bi.c) * v.signum() < 0 {
                            target = bi.c;
                        }
                        if target != ci {
                            changed = true;
                        }
                        self.scratch[i].1 = target;
                        self.scratch[i].2 = j as i64;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        for i in 0..n {
            let (v, ci, blk) = self.scratch[i];
            let bi = &self.bodies[i];
            if blk < 0 || ci - bi.c == v || self.surfaces[bi.surface].accumulating {
                continue;
            }
            let j = blk as usize;
            let bj = &self.bodies[j];
            let f = self
                .map_into(bj.surface, bj.c, bi.surface)
                .map_or(0, |m| m.1);
            let dj = (self.scratch[j].1 - bj.c) * f;
            if dj * v.signum() < v.abs() && self.first(i, HazardKind::Collision) {
                let (pi, pj) = (bi.surface, bj.surface);
                let other = bj.id;
                let place = format!("{} (against box {other})", self.surfaces[pi].name);
                let mut el = self.surfaces[pi].actuators.clone();
                if pj != pi {
                    el.extend(self.surfaces[pj].actuators.iter().cloned());
                }
                let at = Place::Against {
                    part: self.surfaces[pi].id.clone(),
                    item: other,
                };
                self.report(now, i, HazardKind::Collision, (place, at), el, hazards);
            }
        }
        for (b, s) in self.bodies.iter_mut().zip(&self.scratch) {
            b.c = s.1;
        }
    }

    /// Moves the items whose centre left their surface: to the joined one, a sink, or
    /// the floor.
    fn transfer(&mut self, now: u64, hazards: &mut Vec<Hazard>) {
        let mut i = 0;
        while i < self.bodies.len() {
            let b = &self.bodies[i];
            let s = b.surface;
            let len = self.surfaces[s].len;
            let (e, over) = if b.c > len {
                (END, b.c - len)
            } else if b.c < 0 {
                (START, -b.c)
            } else {
                i += 1;
                continue;
            };
            if let Some(q) = self.links[s][e] {
                let lq = self.surfaces[q.surface].len;
                let body = &mut self.bodies[i];
                body.surface = q.surface;
                body.c = if q.end == START { over } else { lq - over };
                i += 1;
            } else if self.surfaces[s].open[e] == Open::Sink {
                self.delivered[s] += 1;
                self.bodies.remove(i);
            } else {
                if self.first(i, HazardKind::Dropped) {
                    let p = &self.surfaces[s];
                    let place = format!(
                        "{} of the {}",
                        if e == END { "end" } else { "start" },
                        p.name
                    );
                    let mut el = p.actuators.clone();
                    if let Some(r) = &p.rotation {
                        el.extend(r.iter().cloned());
                    }
                    let at = Place::Off {
                        part: p.id.clone(),
                        end: e == END,
                    };
                    self.report(now, i, HazardKind::Dropped, (place, at), el, hazards);
                }
                self.fallen += 1;
                let b = self.bodies.remove(i);
                self.lying.push(b);
            }
        }
    }

    fn check_hazards(&mut self, now: u64, hazards: &mut Vec<Hazard>) {
        let margin = self.straddle;
        let shear = self.shear;
        let tolerance = self.tolerance;
        for i in 0..self.bodies.len() {
            let b = &self.bodies[i];
            let p = b.surface;
            let mut pushing = 0;
            for e in [START, END] {
                let b = &self.bodies[i];
                let over = overhang(b, e, self.surfaces[p].len);
                if over <= 0 {
                    continue;
                }
                if over > shear
                    && self.surfaces[p].table_side[e]
                    && self.turning_beyond(p, e)
                    && self.first(i, HazardKind::Sheared)
                {
                    self.report_sheared(now, i, p, e, hazards);
                }
                let Some(q) = self.links[p][e] else {
                    continue;
                };
                let b = &self.bodies[i];
                if over <= margin || 2 * b.half - over <= margin {
                    continue;
                }
                let out = if e == END { 1 } else { -1 };
                let vp = self.vel[p] * out;
                let vq = self.vel[q.surface] * if q.end == START { 1 } else { -1 };
                if (vp > 0 && vq <= 0) || (vq < 0 && vp >= 0) {
                    // The driving surface slides under the item held by the other:
                    // damage once it has slid the tolerance without a break.
                    pushing = pushing.max((vp - vq).abs());
                    if self.bodies[i].slip + pushing > tolerance
                        && self.first(i, HazardKind::PushedAgainstStopped)
                    {
                        self.report_pushed(now, i, q, hazards);
                    }
                }
            }
            let b = &mut self.bodies[i];
            b.slip = if pushing > 0 { b.slip + pushing } else { 0 };
        }
    }

    /// A turntable turns beyond end `e` of surface `p`: `p` is a turntable between
    /// positions, or a conveyor whose end a turntable between positions may join.
    fn turning_beyond(&self, p: usize, e: usize) -> bool {
        if self.surfaces[p].rotation.is_some() {
            return self.docked[p].is_none();
        }
        self.docks
            .iter()
            .any(|d| d.to == Link { surface: p, end: e } && self.docked[d.table].is_none())
    }

    fn report_sheared(
        &mut self,
        now: u64,
        i: usize,
        p: usize,
        e: usize,
        hazards: &mut Vec<Hazard>,
    ) {
        // The table: this surface, or the one whose docks name this end.
        let t = if self.surfaces[p].rotation.is_some() {
            p
        } else {
            self.docks
                .iter()
                .find(|d| d.to == Link { surface: p, end: e })
                .map_or(p, |d| d.table)
        };
        let table = &self.surfaces[t];
        let place = format!("edge of the {}", table.name);
        let mut el = table.rotation.clone().unwrap_or_default();
        el.extend(self.surfaces[p].actuators.iter().cloned());
        let at = Place::Edge {
            part: table.id.clone(),
        };
        self.report(now, i, HazardKind::Sheared, (place, at), el, hazards);
    }

    fn report_pushed(&mut self, now: u64, i: usize, q: Link, hazards: &mut Vec<Hazard>) {
        let p = self.bodies[i].surface;
        let (a, b) = (&self.surfaces[p], &self.surfaces[q.surface]);
        let place = format!("between the {} and the {}", a.name, b.name);
        let mut el = a.actuators.clone();
        el.extend(b.actuators.iter().cloned());
        let at = Place::Between {
            part: a.id.clone(),
            other: b.id.clone(),
        };
        self.report(
            now,
            i,
            HazardKind::PushedAgainstStopped,
            (place, at),
            el,
            hazards,
        );
    }

    /// True when item `i` has not yet reported `kind`.
    #[inline]
    fn first(&self, i: usize, kind: HazardKind) -> bool {
        self.bodies[i].reported & (1 << kind as u16) == 0
    }

    fn report(
        &mut self,
        now: u64,
        i: usize,
        kind: HazardKind,
        (place, at): (String, Place),
        elements: Vec<String>,
        hazards: &mut Vec<Hazard>,
    ) {
        let b = &mut self.bodies[i];
        b.reported |= 1 << kind as u16;
        if !b.damaged {
            b.damaged = true;
            self.damaged += 1;
        }
        hazards.push(Hazard {
            time_ms: now,
            kind,
            place,
            at,
            elements,
            box_id: b.id,
        });
    }

    /// Writes the beams (by plant input index): an item covers a beam of the surface
    /// it is on or of the one it overhangs.
    pub(crate) fn sense(&self, sensors: &mut crate::bits::Bits) {
        for s in &self.surfaces {
            for beam in &s.beams {
                sensors.set(beam.input, false);
            }
        }
        for b in &self.bodies {
            let p = b.surface;
            self.probe(p, b.c, b, sensors);
            for e in [START, END] {
                if overhang(b, e, self.surfaces[p].len) <= 0 {
                    continue;
                }
                if let Some(q) = self.links[p][e] {
                    let dist = if e == END {
                        self.surfaces[p].len - b.c
                    } else {
                        b.c
                    };
                    let cq = if q.end == START {
                        -dist
                    } else {
                        self.surfaces[q.surface].len + dist
                    };
                    self.probe(q.surface, cq, b, sensors);
                }
            }
        }
    }

    #[inline]
    fn probe(&self, s: usize, c: i64, b: &Body, sensors: &mut crate::bits::Bits) {
        for beam in &self.surfaces[s].beams {
            if (c - beam.at).abs() <= b.half
                && beam.sees.as_ref().is_none_or(|t| b.tags.contains(t))
            {
                sensors.set(beam.input, true);
            }
        }
    }

    /// The items on surface `s` (their centre on it), entry first.
    pub(crate) fn on(&self, s: usize) -> Vec<&Body> {
        let mut v: Vec<&Body> = self.bodies.iter().filter(|b| b.surface == s).collect();
        v.sort_by_key(|b| b.c);
        v
    }

    /// The front of the item nearest the exit end of `s` (0 when empty), in the unit.
    pub(crate) fn front(&self, s: usize) -> f64 {
        self.bodies
            .iter()
            .filter(|b| b.surface == s)
            .map(|b| b.c + b.half)
            .max()
            .map_or(0.0, |f| f as f64 / 1e6)
    }

    /// Takes every item off the plant, those that fell included (an operator
    /// emptying it); returns how many.
    pub(crate) fn clear(&mut self) -> u32 {
        let n = self.bodies.len()
            + self.carried.iter().map(VecDeque::len).sum::<usize>()
            + self.lying.len();
        self.lying.clear();
        self.bodies.clear();
        self.carried.iter_mut().for_each(VecDeque::clear);
        self.removed += n as u32;
        n as u32
    }
}

#[cfg(test)]
#[path = "items/tests.rs"]
mod tests;
