//! The breadth-first search of one sub-plant: its components' zones, its belt's items,
//! the free inputs and the control's outputs, cycle by cycle through the real
//! observers and filter.

use super::belt::{Belt, Ends, Items};
use super::line::Line;
use super::{Reached, SubHazard, TraceStep};
use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::expr::{Dnf, eval_dnf};
use crate::filter::Filter;
use crate::frame::Frame;
use crate::observers::Observers;
use crate::symbols::Literal;
use crate::symbols::Space;
use std::collections::{HashMap, VecDeque};

/// Above this many states a search stops and says so.
const MAX_STATES: usize = 2_000_000;

/// The components of a sub-plant: lines (axes, tanks), each with its id, and at most
/// one belt.
#[derive(Clone, Debug, Default)]
pub(super) struct Parts {
    pub(super) lines: Vec<(String, Line)>,
    pub(super) belt: Option<(String, Belt)>,
}

impl Parts {
    /// Where everything is, as a trace shows it.
    fn text(&self, s: &State) -> String {
        let mut parts: Vec<String> = self
            .lines
            .iter()
            .zip(&s.zones)
            .map(|((id, l), &z)| {
                let z = l.text(usize::from(z));
                if self.lines.len() == 1 && self.belt.is_none() {
                    z
                } else {
                    format!("{id} {z}")
                }
            })
            .collect();
        if let Some((id, b)) = &self.belt {
            parts.push(format!("{id}: {}", b.text(&s.items)));
        }
        parts.join(", ")
    }
}

/// An abstract state.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) struct State {
    zones: Vec<u16>,
    items: Items,
    /// The feeder's, the taker's and the carrier's load expressions at the last
    /// cycle's end.
    ends_prev: [bool; 3],
    /// The components' activity sensors (motion, flow sensors) as last seen.
    active: Vec<usize>,
    /// The variables read at t-1 ([`Sub::prev`]), their values.
    prev: Vec<bool>,
    counts: Vec<u32>,
}

/// What one sub-plant's search needs.
pub(super) struct Sub<'a> {
    pub(super) bundle: &'a PlantBundle,
    pub(super) parts: Parts,
    pub(super) free_in: Vec<usize>,
    pub(super) aux: Vec<usize>,
    pub(super) free_out: Vec<usize>,
    /// The free outputs only the constraints read, and only as `o` (never `/o`, never
    /// at t-1): 0 does all 1 does except violate, so they are held at 0 and a
    /// violation they would make is searched for directly ([`Sub::violation`]).
    pub(super) dominated: Vec<bool>,
    /// The terms of the constraints that guard it.
    pub(super) terms: Vec<Vec<Literal>>,
    /// The inputs only the constraints read, always in the same sense (`/i` only, or
    /// `i` only, never at t-1), each with the value that violates less: held there,
    /// since the other value only forbids more; the fallback a violation brings in the
    /// other values is searched for directly ([`Sub::fallbacks`]).
    pub(super) fixed_in: Vec<(usize, bool)>,
    pub(super) filter: Option<Filter>,
    /// The variables something reads at t-1: only they are kept in a state.
    pub(super) prev: Vec<(Space, usize)>,
    /// Every output at its safe value every cycle, instead of any vector.
    pub(super) safe_only: bool,
    pub(super) sizes: [usize; 4],
    /// The search stops after this many transitions.
    pub(super) limit: u64,
}

/// The successors' search state: what is found and numbered so far.
struct Graph {
    index: HashMap<State, u32>,
    states: Vec<State>,
    parent: Vec<Option<(u32, TraceStep)>>,
    found: Vec<Reached>,
    queue: VecDeque<u32>,
    transitions: u64,
    /// The search stops after this many transitions.
    limit: u64,
    truncated: bool,
}

impl Graph {
    /// Records the hazards of a transition (a shortest trace to each new one), or the
    /// successor state when there is none.
    fn add(&mut self, si: u32, step: &TraceStep, hazards: &[SubHazard], next: State) {
        self.transitions += 1;
        if self.transitions >= self.limit && !self.truncated {
            self.truncated = true;
            self.queue.clear();
        }
        for h in hazards {
            if !self.found.iter().any(|r| &r.hazard == h) {
                let trace = trace_to(&self.parent, si, step);
                self.found.push(Reached {
                    hazard: h.clone(),
                    trace,
                });
            }
        }
        if !hazards.is_empty() || self.index.contains_key(&next) {
            return;
        }
        if self.states.len() >= MAX_STATES {
            self.truncated = true;
            return;
        }
        let id = self.states.len() as u32;
        self.index.insert(next.clone(), id);
        self.states.push(next);
        self.parent.push(Some((si, step.clone())));
        self.queue.push_back(id);
    }
}

/// Every combination of one element of each list.
fn product(lists: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new()];
    for l in lists {
        out = out
            .into_iter()
            .flat_map(|p| {
                l.iter().map(move |&x| {
                    let mut q = p.clone();
                    q.push(x);
                    q
                })
            })
            .collect();
    }
    out
}

impl Sub<'_> {
    fn names(&self, space: Space, bits: &Bits) -> Vec<String> {
        bits.ones()
            .map(|k| self.bundle.symbols.name(space, k as u32).to_string())
            .collect()
    }

    /// The lines' windows with each line in the given zones.
    fn set_windows(&self, zones: impl Iterator<Item = usize>, inputs: &mut Bits) {
        for ((_, l), z) in self.parts.lines.iter().zip(zones) {
            for &(i, from, to) in &l.windows {
                inputs.set(i, l.within(z, from, to));
            }
        }
    }

    /// The beams an item ahead may cover in state `s` (any value each cycle).
    fn free_beams(&self, s: &State) -> Vec<usize> {
        self.parts
            .belt
            .as_ref()
            .map(|(_, b)| b.sense(&s.items).1)
            .unwrap_or_default()
    }

    /// The frame at a cycle's start: the components' sensors, the free inputs and the
    /// free beams (`env`), the previous cycle; then the observers.
    fn start_frame(&self, s: &State, env: u32, frame: &mut Frame, obs: &mut Observers) {
        for sp in 0..4 {
            frame.now[sp].clear();
            frame.prev[sp].clear();
        }
        self.set_windows(s.zones.iter().map(|&z| usize::from(z)), &mut frame.now[0]);
        for &i in &s.active {
            frame.now[0].set(i, true);
        }
        let mut bits = (0..32).map(|k| env >> k & 1 == 1);
        for &i in &self.free_in {
            frame.now[0].set(i, bits.next().unwrap_or(false));
        }
        for &(i, v) in &self.fixed_in {
            frame.now[0].set(i, v);
        }
        for &i in &self.aux {
            frame.now[Space::Aux as usize].set(i, bits.next().unwrap_or(false));
        }
        if let Some((_, b)) = &self.parts.belt {
            let (known, free) = b.sense(&s.items);
            for (i, v) in known {
                frame.now[0].set(i, v);
            }
            for i in free {
                frame.now[0].set(i, bits.next().unwrap_or(false));
            }
        }
        for (&(sp, k), v) in self.prev.iter().zip(&s.prev) {
            frame.prev[sp as usize].set(k, *v);
        }
        obs.set_counts(&s.counts);
        obs.update(frame);
    }

    /// The commanded vector: bit `j` of `c` for the `j`-th free output that is not
    /// dominated (every output at its safe value with `safe_only`).
    fn commanded(&self, c: u32) -> Bits {
        let mut out = Bits::zeros(self.sizes[1]);
        let mut j = 0;
        for (k, &o) in self.free_out.iter().enumerate() {
            let v = if self.safe_only {
                self.bundle.plant.outputs[o].safe == crate::plant::SafeValue::One
            } else if self.dominated[k] {
                false
            } else {
                j += 1;
                c >> (j - 1) & 1 == 1
            };
            out.set(o, v);
        }
        out
    }

    /// A commanded vector of the free outputs that violates a constraint in this
    /// frame, if there is one: a term whose literals on the other variables hold and
    /// whose output literals agree, its positive outputs on.
    fn violation(&self, frame: &mut Frame) -> Option<Bits> {
        frame.now[1].clear();
        'terms: for t in &self.terms {
            let mut v = Bits::zeros(self.sizes[1]);
            let mut off: Vec<usize> = Vec::new();
            for l in t {
                let o = l.var.index as usize;
                if l.var.space == Space::Output && !l.var.prev && self.free_out.contains(&o) {
                    if l.positive {
                        v.set(o, true);
                    } else {
                        off.push(o);
                    }
                } else if !frame.literal(*l) {
                    continue 'terms;
                }
            }
            if off.iter().all(|&o| !v.get(o)) {
                return Some(v);
            }
        }
        None
    }

    /// The fallbacks a violation brings with the held inputs at their other values:
    /// for each of their combinations but the held one where some vector violates, the
    /// inputs, that vector and what the filter applies for it. The frame's inputs are
    /// left changed.
    fn fallbacks(&self, frame: &mut Frame, viol: &mut Vec<usize>) -> Vec<(Bits, Bits, Bits)> {
        let mut out = Vec::new();
        let Some(f) = &self.filter else {
            return out;
        };
        for a in 1..(1u32 << self.fixed_in.len()) {
            for (k, &(i, v)) in self.fixed_in.iter().enumerate() {
                frame.now[0].set(i, v != (a >> k & 1 == 1));
            }
            if let Some(commanded) = self.violation(frame) {
                let fallback = f.fallback(frame);
                self.apply(&commanded, frame, Some(&fallback), viol);
                out.push((frame.now[0].clone(), commanded, frame.now[1].clone()));
            }
        }
        out
    }

    /// Commands `commanded`, then the filter: the frame's outputs are the applied ones.
    fn apply(
        &self,
        commanded: &Bits,
        frame: &mut Frame,
        fallback: Option<&Result<Bits, crate::filter::SpecError>>,
        viol: &mut Vec<usize>,
    ) {
        frame.now[1].copy_from(commanded);
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

    /// Whether `dnf` holds with the lines anywhere on their way from `from` to `to`
    /// (a window crossed within the cycle is seen by the components it drives), and
    /// whether it holds at the end; the frame's inputs are restored.
    fn during(&self, dnf: &Dnf, from: &[u16], to: &[usize], frame: &mut Frame) -> (bool, bool) {
        let saved = frame.now[0].clone();
        self.set_windows(to.iter().copied(), &mut frame.now[0]);
        let end = eval_dnf(dnf, frame);
        let mut any = end;
        if !any {
            let ways: Vec<Vec<usize>> = from
                .iter()
                .zip(to)
                .map(|(&a, &b)| {
                    let a = usize::from(a);
                    (a.min(b)..=a.max(b)).collect()
                })
                .collect();
            for zones in product(&ways) {
                self.set_windows(zones.into_iter(), &mut frame.now[0]);
                if eval_dnf(dnf, frame) {
                    any = true;
                    break;
                }
            }
        }
        frame.now[0].copy_from(&saved);
        (any, end)
    }

    /// The rises at the belt's ends in a cycle that takes the lines from `s` to
    /// `zones`, and the expressions' values at its end.
    fn ends(&self, s: &State, zones: &[usize], frame: &mut Frame) -> (Ends, [bool; 3]) {
        let Some((_, b)) = &self.parts.belt else {
            return (Ends::default(), [false; 3]);
        };
        let feed = b.feed.as_ref();
        let dnfs = [
            feed.map(|f| &f.dnf),
            b.take.as_ref(),
            feed.and_then(|f| f.load.as_ref()),
        ];
        let (mut rises, mut end) = ([false; 3], [false; 3]);
        for (k, dnf) in dnfs.into_iter().enumerate() {
            if let Some(d) = dnf {
                let (any, at_end) = self.during(d, &s.zones, zones, frame);
                rises[k] = !s.ends_prev[k] && any;
                end[k] = at_end;
            }
        }
        let ends = Ends {
            feed_rise: rises[0],
            take_rise: rises[1],
            load_rise: rises[2],
        };
        (ends, end)
    }

    /// Breadth-first search: the hazards reached, states, transitions, and whether it
    /// stopped at its limit of states or transitions before covering every state.
    pub(super) fn explore(&self) -> (Vec<Reached>, usize, u64, bool) {
        let s0 = State {
            zones: self
                .parts
                .lines
                .iter()
                .map(|(_, l)| l.start as u16)
                .collect(),
            items: Items {
                item: None,
                ahead: false,
                carried: 0,
            },
            ends_prev: [false; 3],
            active: Vec::new(),
            prev: vec![false; self.prev.len()],
            counts: vec![0; self.sizes[2]],
        };
        let mut g = Graph {
            index: HashMap::from([(s0.clone(), 0)]),
            states: vec![s0],
            parent: vec![None],
            found: Vec::new(),
            queue: VecDeque::from([0u32]),
            transitions: 0,
            limit: self.limit,
            truncated: false,
        };
        let mut frame = Frame::new(self.sizes);
        let mut obs = self.bundle.observers.clone();
        let mut viol = Vec::new();
        while let Some(si) = g.queue.pop_front() {
            let s = g.states[si as usize].clone();
            let free = self.free_in.len() + self.aux.len() + self.free_beams(&s).len();
            for env in 0..(1u32 << free) {
                self.start_frame(&s, env, &mut frame, &mut obs);
                let counts = obs.counts().to_vec();
                let inputs = frame.now[0].clone();
                let observers = frame.now[2].clone();
                let aux_now = frame.now[3].clone();
                let fallback = self.filter.as_ref().map(|f| f.fallback(&frame));
                let mut applied_seen: Vec<Bits> = Vec::new();
                let free_out = self.dominated.iter().filter(|d| !**d).count();
                let vectors = if self.safe_only { 1 } else { 1u32 << free_out };
                let mut commands: Vec<Bits> = (0..vectors).map(|c| self.commanded(c)).collect();
                if !self.safe_only && self.filter.is_some() && self.dominated.contains(&true) {
                    commands.extend(self.violation(&mut frame));
                }
                let mut outcomes: Vec<(Bits, Bits, Bits)> = Vec::new();
                for commanded in commands {
                    self.apply(&commanded, &mut frame, fallback.as_ref(), &mut viol);
                    outcomes.push((inputs.clone(), commanded, frame.now[1].clone()));
                }
                if !self.safe_only && self.filter.is_some() {
                    outcomes.extend(self.fallbacks(&mut frame, &mut viol));
                    frame.now[0].copy_from(&inputs);
                }
                for (ins, commanded, applied) in outcomes {
                    if applied_seen.contains(&applied) {
                        continue;
                    }
                    applied_seen.push(applied.clone());
                    frame.now[1].copy_from(&applied);
                    let step = TraceStep {
                        zone: self.parts.text(&s),
                        inputs: self.names(Space::Input, &ins),
                        commanded: self.names(Space::Output, &commanded),
                        applied: self.names(Space::Output, &applied),
                    };
                    let prev = self.prev_of(&inputs, &applied, &observers, &aux_now);
                    self.successors(&mut g, si, &s, &step, &mut frame, (prev, &counts));
                }
            }
        }
        g.found.sort_by(|a, b| a.hazard.cmp(&b.hazard));
        (g.found, g.states.len(), g.transitions, g.truncated)
    }

    /// The successors of `s` for the frame's applied outputs: every line's reachable
    /// zones, the belt's items, with the cycle's hazards.
    fn successors(
        &self,
        g: &mut Graph,
        si: u32,
        s: &State,
        step: &TraceStep,
        frame: &mut Frame,
        (prev, counts): (Vec<bool>, &[u32]),
    ) {
        let mut hazards = Vec::new();
        let mut active = Vec::new();
        let mut nexts = Vec::new();
        let mut speeds = Vec::new();
        for ((_, l), &z) in self.parts.lines.iter().zip(&s.zones) {
            let z = usize::from(z);
            let (v, moving, running) = l.speed(z, frame);
            hazards.extend(moving);
            active.extend(running);
            nexts.push(l.next(z, v));
            speeds.push(v);
        }
        let belt = self.parts.belt.as_ref().map(|(_, b)| {
            let (v, opposed) = b.speed(frame);
            if opposed {
                hazards.push(SubHazard::OpposedDrives);
            }
            (b, v)
        });
        for zones in product(&nexts) {
            let mut hz = hazards.clone();
            let mut act = active.clone();
            for (k, ((_, l), &next)) in self.parts.lines.iter().zip(&zones).enumerate() {
                for (id, from, to, when) in &l.dangers {
                    if l.within(next, *from, *to) && eval_dnf(when, frame) {
                        hz.push(SubHazard::Declared(id.clone()));
                    }
                }
                // Its motion sensor sees it move (not pushed against its end).
                let z = usize::from(s.zones[k]);
                let moved = next != z || l.bounds(z).0 != l.bounds(z).1;
                act.extend(l.moving.filter(|_| speeds[k] != 0 && moved));
            }
            let (ends, ends_prev) = self.ends(s, &zones, frame);
            let items: Vec<(Items, Option<SubHazard>)> = match belt {
                Some((b, v)) => {
                    act.extend(b.motion.filter(|_| v != 0));
                    b.next(&s.items, v, ends)
                }
                None => vec![(s.items.clone(), None)],
            };
            act.sort_unstable();
            act.dedup();
            for (items, hazard) in items {
                let mut h = hz.clone();
                h.extend(hazard);
                h.sort();
                h.dedup();
                let n = State {
                    zones: zones.iter().map(|&z| z as u16).collect(),
                    items,
                    ends_prev,
                    active: act.clone(),
                    prev: prev.clone(),
                    counts: counts.to_vec(),
                };
                g.add(si, step, &h, n);
            }
        }
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
