//! Post- and pre-initialised stopwatch Petri nets (seed 000, chapter 5) as a modelling
//! front end: a net as data (`*.swpn.ron`), translated into a stopwatch automaton by the
//! thesis's reduced procedure (§5.5.3.B), which the synthesis then runs.
//!
//! A timed transition has a static interval `[EFT, LFT]` and a clock. A non-interruptible
//! transition's clock is *pre-initialised*: reset when the transition is newly enabled
//! (enabled after a firing, not enabled in the intermediate marking). An interruptible
//! transition's clock is *post-initialised*: reset when it fires, and stopped, keeping
//! its value, while it is suspended. A transition may *read* places (`reads`): it takes
//! and gives them back without newly enabling the transitions that need them (the
//! thesis's "lecture" arcs: an interruption does not restart the task's total time).
//!
//! The reduced translation, for tasks made of a *total* transition (its clock is the
//! task's total time `x`, its firing the task's fault), an *end* transition
//! (interruptible, its clock the effective time `y`, its event the task's end), and
//! interruptions and resumptions that read the total's place:
//! 1. the marking graph from the initial marking, the totals never fired (the per-task
//!    fault arcs are deleted, Remark 5.5.1), and the unstable markings (an immediate
//!    transition without event enabled) merged into the edge that reaches them;
//! 2. per marking, rate 1 for the clocks of the enabled transitions, 0 for the others;
//! 3. the invariant `x ≤ LFT` of the enabled and suspended transitions (an end
//!    transition is suspended while its total is enabled and it is not);
//! 4. guards: `EFT ≤ x ≤ LFT`; for an interruption or a resumption, `0 ≤ x_tot < LFT`
//!    of the total it reads; for an end, `EFT ≤ y ≤ LFT ∧ EFT ≤ x_tot < LFT(total)`;
//! 5. resets: the clocks of the newly enabled non-interruptible transitions and the
//!    fired interruptible one.
//!
//! The automaton has one component whose goal is the end of the net's run: its edges
//! into a marking where no timed transition is enabled or suspended are its goal edges,
//! and it is in progress everywhere else. `E*` is then the set of valuations from which
//! every task still to run can end acceptably.

use super::automaton::{ComponentDef, EdgeDef, LocationDef, SwaFile};
use crate::diag::codes;
use crate::diag::{Location as At, Problem};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::Path;

/// What a transition is in the reduced translation.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Role {
    /// An ordinary transition (a start, a controller's window).
    #[default]
    Plain,
    /// A task's total duration: its firing is the task's fault, deleted.
    Total,
    /// A task's end: interruptible, its clock the effective time, `total` the task's
    /// total transition.
    End {
        /// The task's total transition.
        total: String,
    },
    /// An interruption or a resumption (no clock; it reads the total's place).
    Switch {
        /// The task's total transition.
        total: String,
    },
}

/// A transition as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransitionDef {
    /// Its name (`t11`).
    pub name: String,
    /// Input places.
    #[serde(default)]
    pub pre: Vec<String>,
    /// Output places.
    #[serde(default)]
    pub post: Vec<String>,
    /// Places read: taken and given back without newly enabling what needs them.
    #[serde(default)]
    pub reads: Vec<String>,
    /// The observed event; none for an internal transition.
    #[serde(default)]
    pub event: Option<String>,
    /// `[EFT, LFT]`, in the automaton's time unit; `None` for an immediate transition
    /// or a switch (no clock).
    #[serde(default)]
    pub interval: Option<(u64, u64)>,
    /// The clock of a timed transition (`x2`).
    #[serde(default)]
    pub clock: Option<String>,
    /// Its role in the reduced translation.
    #[serde(default)]
    pub role: Role,
}

/// A stopwatch Petri net as written (`*.swpn.ron`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Swpn")]
pub struct SwpnFile {
    /// The automaton's name.
    pub name: String,
    /// Place names.
    pub places: Vec<String>,
    /// Initially marked places (one token each).
    pub marking: Vec<String>,
    /// Transitions.
    pub transitions: Vec<TransitionDef>,
}

/// The translation's result: the automaton and the markings the locations stand for.
#[derive(Clone, Debug)]
pub struct Translation {
    /// One component.
    pub automaton: SwaFile,
    /// Per location, its marked places.
    pub markings: Vec<Vec<String>>,
    /// Per location, the clocks of its active transitions (enabled, or an end
    /// suspended while its task is in progress): those its monitoring reads. The
    /// others are frozen values of finished tasks or clocks not started yet.
    pub live: Vec<Vec<String>>,
}

type Marking = BTreeSet<usize>;

struct Net<'a> {
    def: &'a SwpnFile,
    pre: Vec<Vec<usize>>,
    post: Vec<Vec<usize>>,
    reads: Vec<Vec<usize>>,
    total_of: Vec<Option<usize>>,
}

impl Net<'_> {
    fn enabled(&self, t: usize, m: &Marking) -> bool {
        self.pre[t]
            .iter()
            .chain(&self.reads[t])
            .all(|p| m.contains(p))
    }

    fn timed(&self, t: usize) -> bool {
        self.def.transitions[t].clock.is_some()
    }

    fn interruptible(&self, t: usize) -> bool {
        matches!(self.def.transitions[t].role, Role::End { .. })
    }

    /// Enabled, or an end suspended while its task is in progress.
    fn active(&self, t: usize, m: &Marking) -> bool {
        self.enabled(t, m)
            || (self.interruptible(t) && self.total_of[t].is_some_and(|k| self.enabled(k, m)))
    }

    fn fire(&self, t: usize, m: &Marking) -> (Marking, Marking) {
        let mut mid = m.clone();
        for p in &self.pre[t] {
            mid.remove(p);
        }
        let mut next = mid.clone();
        next.extend(self.post[t].iter().copied());
        // Read places stay in the intermediate marking.
        mid.extend(self.reads[t].iter().copied());
        (mid, next)
    }

    /// The internal immediate transition enabled in `m`, if any (an unstable marking).
    fn unstable(&self, m: &Marking) -> Vec<usize> {
        (0..self.pre.len())
            .filter(|&t| {
                let d = &self.def.transitions[t];
                d.event.is_none()
                    && d.clock.is_none()
                    && d.role == Role::Plain
                    && self.enabled(t, m)
            })
            .collect()
    }
}

fn problem(path: &Path, text: &str, needle: &str, message: String) -> Problem {
    Problem::error(
        codes::SWA_INVALID.id,
        message,
        Some(At::of_nth(path, text, needle, 0)),
    )
}

impl SwpnFile {
    /// Loads a net file.
    pub fn load(path: &Path) -> Result<(Self, String), Vec<Problem>> {
        crate::live::load_ron(path)
    }

    /// Translates the net into a stopwatch automaton (module doc). Bad names, a
    /// timed transition without interval or clock, two internal transitions enabled
    /// at once, or an unbounded marking graph are refused with their line.
    pub fn translate(&self, path: &Path, text: &str) -> Result<Translation, Vec<Problem>> {
        let net = self.check(path, text)?;
        let mut errors = Vec::new();
        let m0: Marking = self
            .marking
            .iter()
            .filter_map(|p| self.places.iter().position(|x| x == p))
            .collect();
        let clocks: Vec<String> = self
            .transitions
            .iter()
            .filter_map(|t| t.clock.clone())
            .collect();
        let mut index: BTreeMap<Marking, usize> = BTreeMap::new();
        let mut markings: Vec<Marking> = Vec::new();
        let mut queue = VecDeque::new();
        let mut edges: Vec<(usize, usize, usize, BTreeSet<usize>)> = Vec::new();
        index.insert(m0.clone(), 0);
        markings.push(m0);
        queue.push_back(0);
        while let Some(i) = queue.pop_front() {
            if markings.len() > 10_000 {
                errors.push(problem(
                    path,
                    text,
                    "places",
                    "more than 10000 markings: the net is unbounded".into(),
                ));
                break;
            }
            let m = markings[i].clone();
            for t in 0..self.transitions.len() {
                let def = &self.transitions[t];
                if !net.enabled(t, &m) || def.role == Role::Total || def.event.is_none() {
                    continue;
                }
                // Fire t, then the internal immediate transitions of the unstable
                // markings it reaches; the clocks newly enabled along the way reset.
                let mut resets = BTreeSet::new();
                let mut cur = m.clone();
                let mut fired = t;
                loop {
                    let (mid, next) = net.fire(fired, &cur);
                    for u in 0..self.transitions.len() {
                        if net.timed(u)
                            && net.enabled(u, &next)
                            && !net.interruptible(u)
                            && (!net.enabled(u, &mid) || u == fired)
                        {
                            resets.insert(u);
                        }
                    }
                    if net.interruptible(fired) {
                        resets.insert(fired);
                    }
                    cur = next;
                    match net.unstable(&cur).as_slice() {
                        [] => break,
                        [u] => fired = *u,
                        more => {
                            let names: Vec<&str> = more
                                .iter()
                                .map(|&u| self.transitions[u].name.as_str())
                                .collect();
                            errors.push(problem(
                                path,
                                text,
                                &format!("\"{}\"", def.name),
                                format!(
                                    "after `{}`, internal transitions {} are enabled at once: the merged marking is ambiguous",
                                    def.name,
                                    names.join(", ")
                                ),
                            ));
                            break;
                        }
                    }
                }
                let j = *index.entry(cur.clone()).or_insert_with(|| {
                    markings.push(cur);
                    queue.push_back(markings.len() - 1);
                    markings.len() - 1
                });
                edges.push((i, j, t, resets));
            }
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        Ok(self.automaton(&net, &clocks, &markings, &edges))
    }

    fn check<'a>(&'a self, path: &Path, text: &str) -> Result<Net<'a>, Vec<Problem>> {
        let mut errors = Vec::new();
        let place = |p: &String, t: &str, errors: &mut Vec<Problem>| -> Option<usize> {
            let i = self.places.iter().position(|x| x == p);
            if i.is_none() {
                errors.push(problem(
                    path,
                    text,
                    &format!("\"{t}\""),
                    format!("transition `{t}`: `{p}` is not a place of the net"),
                ));
            }
            i
        };
        let places = |names: &[String], t: &str, errors: &mut Vec<Problem>| -> Vec<usize> {
            names.iter().filter_map(|p| place(p, t, errors)).collect()
        };
        let (mut pre, mut post, mut reads, mut total_of) = (vec![], vec![], vec![], vec![]);
        for t in &self.transitions {
            pre.push(places(&t.pre, &t.name, &mut errors));
            post.push(places(&t.post, &t.name, &mut errors));
            reads.push(places(&t.reads, &t.name, &mut errors));
            let total = match &t.role {
                Role::End { total } | Role::Switch { total } => {
                    let k = self.transitions.iter().position(|u| &u.name == total);
                    if !k.is_some_and(|k| self.transitions[k].role == Role::Total) {
                        errors.push(problem(
                            path,
                            text,
                            &format!("\"{}\"", t.name),
                            format!(
                                "transition `{}`: `{total}` is not a transition of role Total",
                                t.name
                            ),
                        ));
                    }
                    k
                }
                _ => None,
            };
            total_of.push(total);
            let timed = !matches!(t.role, Role::Switch { .. }) && t.interval.is_some();
            if timed != t.clock.is_some() {
                errors.push(problem(
                    path,
                    text,
                    &format!("\"{}\"", t.name),
                    format!(
                        "transition `{}`: a timed transition has both an interval and a clock, a switch or an immediate one neither",
                        t.name
                    ),
                ));
            }
            if let Some((e, l)) = t.interval
                && e > l
            {
                errors.push(problem(
                    path,
                    text,
                    &format!("\"{}\"", t.name),
                    format!("transition `{}`: its interval [{e}, {l}] is empty", t.name),
                ));
            }
        }
        for p in &self.marking {
            if !self.places.contains(p) {
                errors.push(problem(
                    path,
                    text,
                    &format!("\"{p}\""),
                    format!("the initial marking names `{p}`, which is not a place of the net"),
                ));
            }
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        Ok(Net {
            def: self,
            pre,
            post,
            reads,
            total_of,
        })
    }

    fn automaton(
        &self,
        net: &Net<'_>,
        clocks: &[String],
        markings: &[Marking],
        edges: &[(usize, usize, usize, BTreeSet<usize>)],
    ) -> Translation {
        let name_of = |m: &Marking| -> String {
            m.iter()
                .map(|&p| self.places[p].as_str())
                .collect::<Vec<_>>()
                .join("+")
        };
        let clock = |t: usize| self.transitions[t].clock.clone().unwrap_or_default();
        let lft = |t: usize| self.transitions[t].interval.map_or(0, |i| i.1);
        let eft = |t: usize| self.transitions[t].interval.map_or(0, |i| i.0);
        let busy =
            |m: &Marking| (0..self.transitions.len()).any(|t| net.timed(t) && net.active(t, m));
        let locations: Vec<LocationDef> = markings
            .iter()
            .map(|m| {
                let running: Vec<String> = (0..self.transitions.len())
                    .filter(|&t| net.timed(t) && net.enabled(t, m))
                    .map(clock)
                    .collect();
                let invariant: Vec<String> = (0..self.transitions.len())
                    .filter(|&t| net.timed(t) && net.active(t, m))
                    .map(|t| format!("{} <= {}", clock(t), lft(t)))
                    .collect();
                LocationDef {
                    name: name_of(m),
                    label: String::new(),
                    running,
                    invariant: if invariant.is_empty() {
                        "true".into()
                    } else {
                        invariant.join(" && ")
                    },
                }
            })
            .collect();
        let edges: Vec<EdgeDef> = edges
            .iter()
            .map(|(i, j, t, resets)| {
                let def = &self.transitions[*t];
                let guard = match (&def.role, net.total_of[*t]) {
                    (Role::Switch { .. }, Some(k)) => format!("0 <= {} < {}", clock(k), lft(k)),
                    (Role::End { .. }, Some(k)) => format!(
                        "{e} <= {y} <= {l} && {e} <= {x} < {lk}",
                        e = eft(*t),
                        y = clock(*t),
                        l = lft(*t),
                        x = clock(k),
                        lk = lft(k)
                    ),
                    _ if net.timed(*t) => {
                        format!("{} <= {} <= {}", eft(*t), clock(*t), lft(*t))
                    }
                    _ => "true".into(),
                };
                EdgeDef {
                    from: name_of(&markings[*i]),
                    to: name_of(&markings[*j]),
                    event: def.event.clone().unwrap_or_default(),
                    guard,
                    reset: resets.iter().map(|&u| clock(u)).collect(),
                    goal: busy(&markings[*i]) && !busy(&markings[*j]),
                }
            })
            .collect();
        let progress = markings.iter().filter(|m| busy(m)).map(name_of).collect();
        Translation {
            automaton: SwaFile {
                components: vec![ComponentDef {
                    name: self.name.clone(),
                    clocks: clocks.to_vec(),
                    initial: name_of(&markings[0]),
                    progress,
                    locations,
                    edges,
                }],
            },
            markings: markings
                .iter()
                .map(|m| m.iter().map(|&p| self.places[p].clone()).collect())
                .collect(),
            live: markings
                .iter()
                .map(|m| {
                    (0..self.transitions.len())
                        .filter(|&t| net.timed(t) && net.active(t, m))
                        .map(clock)
                        .collect()
                })
                .collect(),
        }
    }
}
