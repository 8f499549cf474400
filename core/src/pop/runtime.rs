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
    /// Certainty (always certain in the report; `unexplained` entries say so in `fault`).
    pub certainty: Certainty,
}

#[derive(Clone, Debug)]
struct Run {
    h: Vec<(u32, i64)>,
    clock: Option<(usize, i64)>,
    emitted: u64,
    next_deadline: i64,
    next_boundary: i64,
    latched: Vec<bool>,
    decisions: Vec<Decision>,
    unexplained: bool,
    started: bool,
    def_aux: Vec<Option<u32>>,
    interval_aux: Vec<Option<u32>>,
    estimate_aux: Vec<Option<u32>>,
}

/// The diagnosers of a plant.
#[derive(Clone, Debug)]
pub struct Diagnosers {
    /// The compiled models.
    pub compiled: Compiled,
    runs: Vec<Run>,
    by_signal: [Vec<Vec<usize>>; 2],
    timed_only: Vec<usize>,
    /// Certain diagnoses so far, in order.
    pub diagnoses: Vec<Diagnosis>,
    scratch: Vec<(u32, i64)>,
}

const LONG_AGO: i64 = -1_000_000_000_000;

impl Diagnosers {
    /// Builds the run-time diagnosers; `symbols` must hold the auxiliaries of
    /// [`super::build::aux_names`].
    pub fn new(compiled: Compiled, symbols: &Symbols) -> Self {
        let aux = |n: &str| match symbols.lookup(n) {
            Some((Space::Aux, i)) => Some(i),
            _ => None,
        };
        let mut by_signal = [
            vec![Vec::new(); symbols.len(Space::Input)],
            vec![Vec::new(); symbols.len(Space::Output)],
        ];
        let mut timed_only = Vec::new();
        let mut runs = Vec::new();
        for (ci, c) in compiled.components.iter().enumerate() {
            for s in &c.signals {
                let t = if s.var.space == Space::Input { 0 } else { 1 };
                if let Some(v) = by_signal[t].get_mut(s.var.index as usize) {
                    v.push(ci);
                }
            }
            if !c.intervals.is_empty() || c.g.iter().any(|q| q.deadline.is_some()) {
                timed_only.push(ci);
            }
            runs.push(Run {
                h: Vec::new(),
                clock: c.initial_clock.map(|k| (k, LONG_AGO)),
                emitted: 0,
                next_deadline: i64::MAX,
                next_boundary: i64::MIN,
                latched: vec![false; c.partitions.len()],
                decisions: c
                    .partitions
                    .iter()
                    .map(|_| Decision {
                        certainty: Certainty::Normal,
                        faults: Vec::new(),
                    })
                    .collect(),
                unexplained: false,
                started: false,
                def_aux: c
                    .partitions
                    .iter()
                    .map(|p| aux(&format!("def_{}", p.id)))
                    .collect(),
                interval_aux: c.intervals.iter().map(|i| aux(&i.id)).collect(),
                estimate_aux: c.estimates.iter().map(|(n, _)| aux(n)).collect(),
            });
        }
        Self {
            compiled,
            runs,
            by_signal,
            timed_only,
            diagnoses: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// The current decision of every partition: (component, partition, decision).
    pub fn decisions(&self) -> Vec<(String, String, Decision)> {
        let mut out = Vec::new();
        for (c, r) in self.compiled.components.iter().zip(&self.runs) {
            for (p, d) in c.partitions.iter().zip(&r.decisions) {
                out.push((c.id.clone(), p.id.clone(), d.clone()));
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

    /// Clears the latched flags (operator's acknowledgement after a repair) and restarts
    /// every estimate from the next cycle.
    pub fn reset(&mut self) {
        for r in &mut self.runs {
            r.latched.iter_mut().for_each(|l| *l = false);
            r.started = false;
            r.unexplained = false;
        }
    }

    /// Follows one cycle: the frame holds inputs and applied outputs at t and t-1; the
    /// flags, intervals and estimates are written into its auxiliaries at t.
    pub fn update(&mut self, now: Millis, frame: &mut Frame) {
        let t = i64::try_from(now.0).unwrap_or(i64::MAX);
        let mut touched: Vec<usize> = Vec::new();
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
        for i in 0..self.runs.len() {
            if !self.runs[i].started {
                touched.push(i);
            }
        }
        for &i in &self.timed_only {
            let r = &self.runs[i];
            if t > r.next_deadline || t >= r.next_boundary {
                touched.push(i);
            }
        }
        touched.sort_unstable();
        touched.dedup();
        for i in touched {
            self.component_cycle(i, t, frame);
        }
    }

    fn component_cycle(&mut self, ci: usize, t: i64, frame: &mut Frame) {
        let c = &self.compiled.components[ci];
        let margin = i64::try_from(self.compiled.margin_ms).unwrap_or(0);
        let pulse = i64::try_from(self.compiled.pulse_max_ms).unwrap_or(0);
        let mut r = std::mem::replace(&mut self.runs[ci], empty_run());
        let mut changed = false;
        if !r.started {
            r.started = true;
            resync(c, &mut r, frame, None);
            changed = true;
        } else {
            // Edges: actuators first, then sensors.
            let mut edges: Vec<(usize, bool)> = Vec::new();
            for space in [Space::Output, Space::Input] {
                for (i, s) in c
                    .signals
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| s.var.space == space)
                {
                    let v = frame.now(space).get(s.var.index as usize);
                    if v != frame.prev(space).get(s.var.index as usize) {
                        edges.push((i, v));
                    }
                }
            }
            for (i, rise) in edges {
                let sym = c
                    .symbols
                    .iter()
                    .position(|s| {
                        s.edge == Some((i, rise))
                            && s.guard.as_ref().is_some_and(|g| eval_dnf(g, frame))
                    })
                    .or_else(|| {
                        c.symbols
                            .iter()
                            .position(|s| s.edge == Some((i, rise)) && s.guard.is_none())
                    })
                    .unwrap_or(0);
                timeouts(
                    c,
                    &mut r,
                    t,
                    margin,
                    pulse,
                    &mut self.scratch,
                    &mut self.diagnoses,
                );
                step(c, &mut r, sym, t, margin, true, &mut self.scratch);
                if let Some(k) = c.clocks.iter().position(|&e| e == (i, rise)) {
                    r.clock = Some((k, t));
                    r.emitted = 0;
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
                    resync(c, &mut r, frame, Some(t));
                }
                changed = true;
            }
        }
        changed |= timeouts(
            c,
            &mut r,
            t,
            margin,
            pulse,
            &mut self.scratch,
            &mut self.diagnoses,
        );
        if changed {
            r.next_deadline = next_deadline(c, &r, margin, pulse);
            decide(c, &mut r, t, &mut self.diagnoses);
            r.next_boundary = i64::MIN;
        }
        // Flags, intervals, estimates.
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
            for ((_, d), a) in c.estimates.iter().zip(&r.estimate_aux) {
                let v = eval_dnf(d, frame);
                if let Some(a) = a {
                    frame.now_mut(Space::Aux).set(*a as usize, v);
                }
            }
        }
        self.runs[ci] = r;
    }
}

fn timeouts(
    c: &Component,
    r: &mut Run,
    t: i64,
    margin: i64,
    pulse: i64,
    scratch: &mut Vec<(u32, i64)>,
    diagnoses: &mut Vec<Diagnosis>,
) -> bool {
    let mut any = false;
    for _ in 0..64 {
        let Some(sym) = due_timeout(c, r, t, margin, pulse, scratch) else {
            break;
        };
        if let Some(k) = c.symbols[sym].timeout {
            r.emitted |= 1 << (k % 64);
        }
        // `tmo(pulse)` and `tmo(motion)` end the hypotheses whose own limit passed; the
        // others (a younger pulse or motion) wait on, unchanged.
        let waiting: Vec<(u32, i64)> =
            r.h.iter()
                .copied()
                .filter(|&(q, since)| {
                    let limit = if sym == c.pulse_sym && c.g[q as usize].phase == Phase::Spur {
                        Some(pulse)
                    } else if sym == c.motion_sym {
                        hold(c, r, q).map(|h| h.saturating_add(margin))
                    } else {
                        None
                    };
                    limit.is_some_and(|l| since.saturating_add(l) >= t)
                })
                .collect();
        step(c, r, sym, t, margin, true, scratch);
        for (q, since) in waiting {
            match r.h.iter_mut().find(|(x, _)| *x == q) {
                Some(e) => e.1 = e.1.max(since),
                None => r.h.push((q, since)),
            }
        }
        r.h.sort_unstable();
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
            break;
        }
        r.next_deadline = next_deadline(c, r, margin, pulse);
    }
    any
}

fn empty_run() -> Run {
    Run {
        h: Vec::new(),
        clock: None,
        emitted: 0,
        next_deadline: i64::MAX,
        next_boundary: i64::MIN,
        latched: Vec::new(),
        decisions: Vec::new(),
        unexplained: false,
        started: false,
        def_aux: Vec::new(),
        interval_aux: Vec::new(),
        estimate_aux: Vec::new(),
    }
}

fn valuation(c: &Component, frame: &Frame) -> u64 {
    c.signals.iter().enumerate().fold(0, |acc, (i, s)| {
        acc | (u64::from(frame.now(s.var.space).get(s.var.index as usize)) << i)
    })
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
    if at.is_some() {
        r.clock = None;
    }
}

/// The unobservable closure: fault events from normal states, hidden plant moves.
fn closure(c: &Component, h: &[(u32, i64)], t: i64, out: &mut Vec<(u32, i64)>) {
    out.clear();
    out.extend_from_slice(h);
    let mut i = 0;
    while i < out.len() {
        let (q, since) = out[i];
        let st = &c.g[q as usize];
        for &(_, tq) in &st.spawn {
            // The fault may occur at any time up to now: its state starts at the
            // latest possible moment (the most permissive for pulse limits and holds).
            match out.iter_mut().find(|(x, _)| *x as usize == tq) {
                Some(e) => e.1 = e.1.max(t),
                None => out.push((tq as u32, t)),
            }
        }
        for &tq in &st.silent {
            if !out.iter().any(|&(x, _)| x as usize == tq) {
                out.push((tq as u32, since));
            }
        }
        i += 1;
    }
}

fn window_ok(c: &Component, r: &Run, w: Option<usize>, t: i64, margin: i64) -> bool {
    let Some(k) = w else { return true };
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

fn step(
    c: &Component,
    r: &mut Run,
    sym: usize,
    t: i64,
    margin: i64,
    timed: bool,
    scratch: &mut Vec<(u32, i64)>,
) {
    closure(c, &r.h, t, scratch);
    let mut next: Vec<(u32, i64)> = Vec::with_capacity(scratch.len());
    for &(q, since) in scratch.iter() {
        let st = &c.g[q as usize];
        let lo = st.obs.partition_point(|o| o.0 < sym);
        for &(s, tq, w) in &st.obs[lo..] {
            if s != sym {
                break;
            }
            if timed && st.phase == Phase::Timed && !window_ok(c, r, w, t, margin) {
                continue;
            }
            // Spurious pulses count from their start; an unexpected motion from entering
            // each state; the rest from the phase's start.
            // A time-out looping on the state changes nothing.
            let keep = (tq == q as usize && c.symbols[sym].edge.is_none())
                || (c.g[tq].phase == st.phase && st.phase != Phase::Untimed);
            let ns = if keep { since } else { t };
            match next.iter_mut().find(|(x, _)| *x as usize == tq) {
                Some(e) => e.1 = e.1.max(ns),
                None => next.push((tq as u32, ns)),
            }
        }
    }
    // A timed state whose window already ended (its time-out was emitted since the
    // clock event) cannot be occupied: a silent move into it comes too late.
    next.retain(|&(q, _)| !expired(c, r, q as usize));
    next.sort_unstable();
    r.h = next;
}

fn expired(c: &Component, r: &Run, q: usize) -> bool {
    let st = &c.g[q];
    match (st.phase, st.deadline, r.clock) {
        (Phase::Timed, Some(k), Some((ck, _))) => {
            c.intervals[k].clock == ck && r.emitted & (1 << (k % 64)) != 0
        }
        _ => false,
    }
}

fn deadline_time(c: &Component, r: &Run, q: usize, margin: i64) -> Option<(i64, usize)> {
    let st = &c.g[q];
    if st.phase != Phase::Timed {
        return None;
    }
    let k = st.deadline?;
    let iv = &c.intervals[k];
    let (ck, ct) = r.clock?;
    if ck != iv.clock || r.emitted & (1 << (k % 64)) != 0 {
        return None;
    }
    Some((ct + i64::try_from(iv.hi?).ok()? + margin, k))
}

fn next_deadline(c: &Component, r: &Run, margin: i64, pulse: i64) -> i64 {
    let mut scratch = Vec::new();
    closure(c, &r.h, 0, &mut scratch);
    let mut best = i64::MAX;
    for &(q, since) in &scratch {
        if let Some((d, _)) = deadline_time(c, r, q as usize, margin) {
            best = best.min(d);
        }
        if c.g[q as usize].phase == Phase::Spur && r.h.iter().any(|&(x, _)| x == q) {
            best = best.min(since + pulse);
        }
        if let Some(h) = hold(c, r, q) {
            best = best.min(since.saturating_add(h).saturating_add(margin));
        }
    }
    best
}

fn due_timeout(
    c: &Component,
    r: &Run,
    t: i64,
    margin: i64,
    pulse: i64,
    scratch: &mut Vec<(u32, i64)>,
) -> Option<usize> {
    closure(c, &r.h, t, scratch);
    let mut best: Option<(i64, usize)> = None;
    for &(q, since) in scratch.iter() {
        let cand = if let Some((d, k)) = deadline_time(c, r, q as usize, margin) {
            c.symbols
                .iter()
                .position(|s| s.timeout == Some(k))
                .map(|s| (d, s))
        } else if c.g[q as usize].phase == Phase::Spur && r.h.iter().any(|&(x, _)| x == q) {
            Some((since + pulse, c.pulse_sym))
        } else {
            hold(c, r, q).map(|h| (since.saturating_add(h).saturating_add(margin), c.motion_sym))
        };
        if let Some((d, s)) = cand
            && d < t
            && best.is_none_or(|(bd, _)| d < bd)
        {
            best = Some((d, s));
        }
    }
    best.map(|(_, s)| s)
}

/// The hold of an untimed state of the estimate itself (not of its closure), ms.
fn hold(c: &Component, r: &Run, q: u32) -> Option<i64> {
    let st = &c.g[q as usize];
    if st.phase != Phase::Untimed || !r.h.iter().any(|&(x, _)| x == q) {
        return None;
    }
    st.hold_ms.and_then(|h| i64::try_from(h).ok())
}

fn decide(c: &Component, r: &mut Run, t: i64, log: &mut Vec<Diagnosis>) {
    let modes: BTreeSet<Option<usize>> = r.h.iter().map(|&(q, _)| c.g[q as usize].mode).collect();
    if modes.is_empty() {
        return;
    }
    for (pi, p) in c.partitions.iter().enumerate() {
        let inside: Vec<usize> = modes
            .iter()
            .flatten()
            .copied()
            .filter(|f| p.faults.contains(f))
            .collect();
        let certainty = if inside.is_empty() {
            Certainty::Normal
        } else if inside.len() == modes.len() {
            Certainty::Certain
        } else {
            Certainty::Ambiguous
        };
        let d = Decision {
            certainty,
            faults: inside.iter().map(|&f| c.faults[f].clone()).collect(),
        };
        if certainty == Certainty::Certain && (!r.latched[pi] || r.decisions[pi] != d) {
            log.push(Diagnosis {
                time_ms: u64::try_from(t).unwrap_or(0),
                component: c.id.clone(),
                partition: p.id.clone(),
                fault: d.faults.join("|"),
                certainty,
            });
            r.latched[pi] = true;
        }
        r.decisions[pi] = d;
    }
}

/// Replays `events` (symbol names) on a component without timing, from its initial
/// state, and returns the fault labels possible after each event (`None` = normal);
/// an empty set means no hypothesis explains the sequence.
pub fn replay_untimed(
    c: &Component,
    events: &[&str],
) -> Result<Vec<BTreeSet<Option<String>>>, String> {
    let mut r = empty_run();
    r.h = vec![(c.initial as u32, 0)];
    let mut scratch = Vec::new();
    let mut out = Vec::new();
    for e in events {
        let sym = c
            .symbols
            .iter()
            .position(|s| s.name == *e)
            .ok_or_else(|| format!("unknown event `{e}`"))?;
        step(c, &mut r, sym, 0, 0, false, &mut scratch);
        out.push(
            r.h.iter()
                .map(|&(q, _)| c.g[q as usize].mode.map(|f| c.faults[f].clone()))
                .collect(),
        );
    }
    Ok(out)
}
