//! Stochastic timed Petri nets (seed 002, chapter 2): nets as data, their probabilistic
//! state graph, its steady state and the mean time to a first failure (MTFF), in exact
//! rational arithmetic.
//!
//! A transition's delay is immediate, a Dirac `δ(x − d)` or a discrete distribution
//! `Σ p_k δ(x − d_k)` (the subset every example of the thesis needs). A delay is drawn
//! when its transition becomes enabled, so a state is a marking with the residual delay
//! of each enabled transition, and the state graph is finite for a bounded net. From a
//! state the enabled transitions race: those with the smallest residual `m` tie, each
//! firing with probability `1/|tie|` after `θ = m` (the equiprobable tie that gives the
//! thesis's 0.005). Memory is the enabling memory, checked in the intermediate marking:
//! another transition keeps its residual (less `m`) when it stays enabled both after
//! the firing's inputs are taken and after its outputs are put; otherwise it is newly
//! enabled and draws again. (A read loop on the place of a timed transition thus
//! restarts its timer, the "désensibilisation" the thesis warns about.) The arcs of the
//! graph carry `<t, θ, p>`, `p` including the draws of the newly enabled delays.
//!
//! Written in RON:
//!
//! ```ron
//! Net(
//!     places: ["calcul", "attend", "repos", "lost"],
//!     marking: [("calcul", 1)],
//!     transitions: [
//!         (name: "t1", pre: ["calcul"], post: ["attend"], delay: Dirac(80)),
//!         (name: "t4", pre: ["calcul"], post: ["lost"], delay: Discrete([(80, "1/100"), (81, "99/100")])),
//!     ],
//! )
//! ```

use crate::diag::codes;
use crate::diag::{Location, Problem};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};
use std::path::Path;

/// An exact rational.
pub type Q = BigRational;

/// A transition's firing delay.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DelayDef {
    /// Fires as soon as it is enabled, before any timed transition.
    Immediate,
    /// After exactly this time.
    Dirac(u64),
    /// After `d_k` with probability `p_k` (`"1/200"`, `"0.005"`); the `p_k` sum to 1.
    Discrete(Vec<(u64, String)>),
}

/// A transition as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransitionDef {
    /// Its name.
    pub name: String,
    /// Input places (a place twice: weight 2).
    #[serde(default)]
    pub pre: Vec<String>,
    /// Output places.
    #[serde(default)]
    pub post: Vec<String>,
    /// Inhibitor arcs: enabled only while these places are empty.
    #[serde(default)]
    pub inhibit: Vec<String>,
    /// Its delay.
    pub delay: DelayDef,
    /// What it does, for the reports (`"!a_writeloc.rq(var,val)"`).
    #[serde(default)]
    pub label: String,
    /// A flag of the net: the transition exists only when the flag is set (`"write_loss"`),
    /// or only when it is not (`"!write_loss"`).
    #[serde(default)]
    pub when: Option<String>,
}

fn default_max_states() -> usize {
    100_000
}

/// A net as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Net")]
pub struct NetFile {
    /// Place names.
    pub places: Vec<String>,
    /// The initial marking (places not listed are empty).
    #[serde(default)]
    pub marking: Vec<(String, u32)>,
    /// Transitions.
    pub transitions: Vec<TransitionDef>,
    /// The state graph is refused beyond this many states.
    #[serde(default = "default_max_states")]
    pub max_states: usize,
    /// The unit the reports give times in (`"Ut"`).
    #[serde(default = "default_unit")]
    pub unit: String,
    /// Delays are written in ticks; this many ticks make one unit (10: a tick of 0.1 Ut).
    #[serde(default = "one")]
    pub ticks_per_unit: u64,
    /// The variants' flags (`"write_loss"`), set with `vigie stpn --with FLAG`.
    #[serde(default)]
    pub flags: Vec<String>,
    /// The analyses `vigie stpn` reports.
    #[serde(default)]
    pub queries: Vec<QueryDef>,
    /// An analysis horizon (in ticks): past it, no timed transition fires, so the state
    /// graph is finite and ends (the thesis's global clock transition δ(H)).
    #[serde(default)]
    pub horizon: Option<u64>,
}

/// The name of the horizon's place and transition.
pub const HORIZON: &str = "(horizon)";

fn default_unit() -> String {
    "Ut".into()
}

fn one() -> u64 {
    1
}

/// An analysis of the state graph, as written. Events are transition names: an event
/// happens when its transition fires.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum QueryDef {
    /// The quantitative abstract view on these events: from each event to each one that
    /// comes first after it, `[mean time, probability]`, the sources weighted by how
    /// often the chain is in them (its steady state, or its visits when it ends).
    View {
        /// What it shows.
        name: String,
        /// The observed events.
        events: Vec<String>,
    },
    /// The first passage to one of the events `to`: its probability and its mean time,
    /// from one of the events `from` (weighted as a view's sources) or, `from` empty,
    /// from the initial marking. The other events are passed through: from a write
    /// request to the first erroneous read, this is the thesis's MTFF.
    Passage {
        /// What it measures.
        name: String,
        /// Where it starts (empty: the initial marking).
        #[serde(default)]
        from: Vec<String>,
        /// Where it ends.
        to: Vec<String>,
    },
    /// The dates of the events along the runs of an acyclic graph (one with a horizon):
    /// each date an event happens at, with its probability.
    Timeline {
        /// What it shows.
        name: String,
        /// The events listed.
        events: Vec<String>,
    },
    /// The markings with every place of `marked` marked and every place of `empty`
    /// empty: the probability of reaching one, the mean time to the first, and the mean
    /// time the net stays in them once there.
    Reach {
        /// What the markings mean (`"double fault"`).
        name: String,
        /// Places that hold a token.
        #[serde(default)]
        marked: Vec<String>,
        /// Places that hold none.
        #[serde(default)]
        empty: Vec<String>,
    },
}

#[derive(Clone, Debug)]
enum Delay {
    Fixed(u64),
    Discrete(Vec<(u64, Q)>),
}

#[derive(Clone, Debug)]
struct Trans {
    pre: Vec<u32>,
    post: Vec<u32>,
    inhibit: Vec<usize>,
    delay: Delay,
}

/// A net checked against its places.
#[derive(Clone, Debug)]
pub struct Net {
    /// Place names.
    pub places: Vec<String>,
    /// Transition names.
    pub transitions: Vec<String>,
    /// The transitions' labels.
    pub labels: Vec<String>,
    /// The unit of the reports.
    pub unit: String,
    /// Ticks per unit.
    pub ticks_per_unit: u64,
    /// The analyses to report.
    pub queries: Vec<QueryDef>,
    m0: Vec<u32>,
    trans: Vec<Trans>,
    max_states: usize,
}

/// A state: a marking and the residual delay of each enabled transition.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct State {
    /// Tokens per place.
    pub marking: Vec<u32>,
    /// Per transition, its residual delay when enabled.
    pub residual: Vec<Option<u64>>,
}

/// An arc `<t, θ, p>` of the state graph.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Arc {
    /// Source and target state.
    pub from: usize,
    /// See `from`.
    pub to: usize,
    /// The transition fired.
    pub transition: usize,
    /// The time elapsed.
    pub theta: u64,
    /// The probability.
    #[serde(serialize_with = "ser_q")]
    pub p: Q,
}

fn ser_initial<S: serde::Serializer>(v: &[(usize, Q)], s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeSeq;
    let mut seq = s.serialize_seq(Some(v.len()))?;
    for (state, p) in v {
        seq.serialize_element(&(state, p.to_string()))?;
    }
    seq.end()
}

fn ser_q<S: serde::Serializer>(q: &Q, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&q.to_string())
}

/// The probabilistic state graph.
#[derive(Clone, Debug, Serialize)]
pub struct StateGraph {
    /// The states, the initial ones first.
    pub states: Vec<State>,
    /// The initial distribution (state, probability).
    #[serde(serialize_with = "ser_initial")]
    pub initial: Vec<(usize, Q)>,
    /// The arcs, by source state.
    pub arcs: Vec<Arc>,
}

fn parse_q(text: &str) -> Option<Q> {
    let t = text.trim();
    if let Some((n, d)) = t.split_once('/') {
        let (n, d): (BigInt, BigInt) = (n.trim().parse().ok()?, d.trim().parse().ok()?);
        return (!d.is_zero()).then(|| Q::new(n, d));
    }
    if let Some((i, f)) = t.split_once('.') {
        let digits = format!("{i}{f}");
        let n: BigInt = digits.parse().ok()?;
        let d = num_traits::pow(BigInt::from(10), f.len());
        return Some(Q::new(n, d));
    }
    t.parse::<BigInt>().ok().map(Q::from_integer)
}

impl NetFile {
    /// Loads a net file.
    pub fn load(path: &Path) -> Result<(Self, String), Vec<Problem>> {
        crate::live::load_ron(path)
    }

    /// The flags set, the transitions' names and flags, the queries' events and places.
    fn check_names(
        &self,
        path: &Path,
        text: &str,
        flags: &[String],
        index: &BTreeMap<&str, usize>,
    ) -> Vec<Problem> {
        let at = |needle: &str| Some(Location::of_nth(path, text, needle, 0));
        let mut errors = Vec::new();
        for f in flags {
            if !self.flags.contains(f) {
                errors.push(Problem::error(
                    codes::STPN_INVALID.id,
                    format!(
                        "{}: `{f}` is not a flag of the net (its flags: {})",
                        path.display(),
                        if self.flags.is_empty() {
                            "none".to_string()
                        } else {
                            self.flags.join(", ")
                        }
                    ),
                    None,
                ));
            }
        }
        if self.ticks_per_unit == 0 {
            errors.push(Problem::error(
                codes::STPN_INVALID.id,
                "ticks_per_unit must be at least 1".to_string(),
                at("ticks_per_unit"),
            ));
        }
        let transition_names: Vec<&str> =
            self.transitions.iter().map(|t| t.name.as_str()).collect();
        for (i, t) in self.transitions.iter().enumerate() {
            if transition_names[..i].contains(&t.name.as_str()) {
                errors.push(Problem::error(
                    codes::STPN_INVALID.id,
                    format!("two transitions are named `{}`", t.name),
                    Some(Location::of_nth(path, text, &format!("\"{}\"", t.name), 1)),
                ));
            }
            if let Some(w) = &t.when
                && !self.flags.contains(&w.trim_start_matches('!').to_string())
            {
                errors.push(Problem::error(
                    codes::STPN_INVALID.id,
                    format!(
                        "transition `{}`: `when: \"{w}\"` names no flag of the net",
                        t.name
                    ),
                    at(&format!("\"{w}\"")),
                ));
            }
        }
        for q in &self.queries {
            let (name, events, places) = match q {
                QueryDef::View { name, events } | QueryDef::Timeline { name, events } => {
                    (name, events.clone(), Vec::new())
                }
                QueryDef::Passage { name, from, to } => {
                    (name, from.iter().chain(to).cloned().collect(), Vec::new())
                }
                QueryDef::Reach {
                    name,
                    marked,
                    empty,
                } => (
                    name,
                    Vec::new(),
                    marked.iter().chain(empty).cloned().collect(),
                ),
            };
            for e in events
                .iter()
                .filter(|e| !transition_names.contains(&e.as_str()))
            {
                errors.push(Problem::error(
                    codes::STPN_INVALID.id,
                    format!("query `{name}`: `{e}` is not a transition of the net"),
                    at(&format!("\"{name}\"")),
                ));
            }
            for p in places.iter().filter(|p| !index.contains_key(p.as_str())) {
                errors.push(Problem::error(
                    codes::STPN_INVALID.id,
                    format!("query `{name}`: `{p}` is not a place of the net"),
                    at(&format!("\"{name}\"")),
                ));
            }
        }
        errors
    }

    /// Checks the net: every place known, probabilities that sum to 1.
    pub fn check(&self, path: &Path, text: &str) -> Result<Net, Vec<Problem>> {
        self.variant(path, text, &[])
    }

    /// Checks the net and keeps the transitions of the variant with these flags set.
    pub fn variant(&self, path: &Path, text: &str, flags: &[String]) -> Result<Net, Vec<Problem>> {
        let at = |needle: &str| Some(Location::of_nth(path, text, needle, 0));
        let mut errors = Vec::new();
        let index: BTreeMap<&str, usize> = self
            .places
            .iter()
            .enumerate()
            .map(|(i, p)| (p.as_str(), i))
            .collect();
        let n = self.places.len();
        let weights = |names: &[String], what: &str, t: &str, errors: &mut Vec<Problem>| {
            let mut w = vec![0u32; n];
            for p in names {
                match index.get(p.as_str()) {
                    Some(&i) => w[i] += 1,
                    None => errors.push(Problem::error(
                        codes::STPN_INVALID.id,
                        format!("transition `{t}`: {what} place `{p}` is not a place of the net"),
                        at(&format!("\"{t}\"")),
                    )),
                }
            }
            w
        };
        errors.extend(self.check_names(path, text, flags, &index));
        let kept = |t: &TransitionDef| match t.when.as_deref() {
            None => true,
            Some(w) => match w.strip_prefix('!') {
                Some(f) => !flags.iter().any(|x| x == f),
                None => flags.iter().any(|x| x == w),
            },
        };
        let mut trans = Vec::new();
        for t in self.transitions.iter().filter(|t| kept(t)) {
            let pre = weights(&t.pre, "input", &t.name, &mut errors);
            let post = weights(&t.post, "output", &t.name, &mut errors);
            let inhibit = weights(&t.inhibit, "inhibitor", &t.name, &mut errors)
                .iter()
                .enumerate()
                .filter(|(_, w)| **w > 0)
                .map(|(i, _)| i)
                .collect();
            let delay = delay_of(&t.delay).unwrap_or_else(|sum| {
                errors.push(Problem::error(
                    codes::STPN_INVALID.id,
                    format!(
                        "transition `{}`: the probabilities of its delay must be positive fractions summing to 1 (they sum to {sum})",
                        t.name
                    ),
                    at(&format!("\"{}\"", t.name)),
                ));
                Delay::Fixed(0)
            });
            trans.push(Trans {
                pre,
                post,
                inhibit,
                delay,
            });
        }
        let mut m0 = vec![0u32; n];
        for (p, k) in &self.marking {
            match index.get(p.as_str()) {
                Some(&i) => m0[i] = *k,
                None => errors.push(Problem::error(
                    codes::STPN_INVALID.id,
                    format!("the initial marking names `{p}`, which is not a place of the net"),
                    at(&format!("\"{p}\"")),
                )),
            }
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        let mut places = self.places.clone();
        let (mut names, mut labels): (Vec<String>, Vec<String>) = self
            .transitions
            .iter()
            .filter(|t| kept(t))
            .map(|t| (t.name.clone(), t.label.clone()))
            .unzip();
        if let Some(h) = self.horizon {
            add_horizon(h, &mut places, &mut m0, &mut trans);
            names.push(HORIZON.into());
            labels.push("the analysis horizon".into());
        }
        Ok(Net {
            places,
            transitions: names,
            labels,
            unit: self.unit.clone(),
            ticks_per_unit: self.ticks_per_unit,
            queries: self.queries.clone(),
            m0,
            trans,
            max_states: self.max_states,
        })
    }
}

/// A delay as written, checked; `Err` with the sum of its probabilities when they are
/// not positive fractions summing to 1.
fn delay_of(d: &DelayDef) -> Result<Delay, Q> {
    Ok(match d {
        DelayDef::Immediate => Delay::Fixed(0),
        DelayDef::Dirac(d) => Delay::Fixed(*d),
        DelayDef::Discrete(atoms) => {
            let ok: Vec<(u64, Q)> = atoms
                .iter()
                .filter_map(|(d, p)| parse_q(p).map(|q| (*d, q)))
                .collect();
            let sum: Q = ok.iter().map(|(_, p)| p.clone()).sum();
            if ok.len() != atoms.len() || ok.iter().any(|(_, p)| *p <= Q::zero()) || !sum.is_one() {
                return Err(sum);
            }
            Delay::Discrete(ok)
        }
    })
}

/// The thesis's analysis horizon: a clock transition δ(H), appended last, whose firing
/// disables every timed transition, so that the graph ends.
fn add_horizon(h: u64, places: &mut Vec<String>, m0: &mut Vec<u32>, trans: &mut Vec<Trans>) {
    // The thesis's analysis horizon: a clock transition δ(H) whose firing
    // disables every timed transition, so that the graph ends.
    let (running, over) = (places.len(), places.len() + 1);
    places.extend([HORIZON.to_string(), format!("{HORIZON} over")]);
    m0.extend([1, 0]);
    for t in trans.iter_mut() {
        t.pre.extend([0, 0]);
        t.post.extend([0, 0]);
        if !matches!(t.delay, Delay::Fixed(0)) {
            t.inhibit.push(over);
        }
    }
    let mut pre = vec![0; places.len()];
    pre[running] = 1;
    let mut post = vec![0; places.len()];
    post[over] = 1;
    trans.push(Trans {
        pre,
        post,
        inhibit: Vec::new(),
        delay: Delay::Fixed(h),
    });
}

impl Net {
    fn enabled(&self, t: usize, m: &[u32]) -> bool {
        let tr = &self.trans[t];
        tr.pre.iter().zip(m).all(|(w, k)| k >= w) && tr.inhibit.iter().all(|&p| m[p] == 0)
    }

    /// The states reached by drawing the delays of the transitions `fresh` in the state
    /// `(m, residual)`, with their probabilities.
    fn draw(&self, m: &[u32], residual: &[Option<u64>], fresh: &[usize]) -> Vec<(State, Q)> {
        let mut out = vec![(
            State {
                marking: m.to_vec(),
                residual: residual.to_vec(),
            },
            Q::one(),
        )];
        for &t in fresh {
            out = out
                .into_iter()
                .flat_map(|(s, p)| match &self.trans[t].delay {
                    Delay::Fixed(d) => {
                        let mut s = s;
                        s.residual[t] = Some(*d);
                        vec![(s, p)]
                    }
                    Delay::Discrete(atoms) => atoms
                        .iter()
                        .map(|(d, q)| {
                            let mut s = s.clone();
                            s.residual[t] = Some(*d);
                            (s, &p * q)
                        })
                        .collect(),
                })
                .collect();
        }
        out
    }

    /// The successors of `s`: (transition, θ, state, probability).
    fn successors(&self, s: &State) -> Vec<(usize, u64, State, Q)> {
        let enabled: Vec<usize> = (0..self.trans.len())
            .filter(|&t| s.residual[t].is_some())
            .collect();
        let Some(m) = enabled.iter().filter_map(|&t| s.residual[t]).min() else {
            return Vec::new();
        };
        let tie: Vec<usize> = enabled
            .iter()
            .copied()
            .filter(|&t| s.residual[t] == Some(m))
            .collect();
        let share = Q::new(BigInt::one(), BigInt::from(tie.len()));
        let mut out = Vec::new();
        for &t in &tie {
            let tr = &self.trans[t];
            let mid: Vec<u32> = s.marking.iter().zip(&tr.pre).map(|(k, w)| k - w).collect();
            let next: Vec<u32> = mid.iter().zip(&tr.post).map(|(k, w)| k + w).collect();
            let mut residual = vec![None; self.trans.len()];
            let mut fresh = Vec::new();
            for (u, slot) in residual.iter_mut().enumerate() {
                if !self.enabled(u, &next) {
                    continue;
                }
                let kept = u != t && s.residual[u].is_some() && self.enabled(u, &mid);
                if kept {
                    *slot = s.residual[u].map(|r| r - m);
                } else {
                    fresh.push(u);
                }
            }
            for (state, p) in self.draw(&next, &residual, &fresh) {
                out.push((t, m, state, &share * &p));
            }
        }
        out
    }

    /// The probabilistic state graph, breadth first from the initial marking.
    pub fn state_graph(&self) -> Result<StateGraph, String> {
        let none = vec![None; self.trans.len()];
        let fresh: Vec<usize> = (0..self.trans.len())
            .filter(|&t| self.enabled(t, &self.m0))
            .collect();
        let mut index: BTreeMap<State, usize> = BTreeMap::new();
        let mut states = Vec::new();
        let mut queue = VecDeque::new();
        let mut initial = Vec::new();
        let mut add = |s: State, states: &mut Vec<State>, queue: &mut VecDeque<usize>| {
            *index.entry(s.clone()).or_insert_with(|| {
                states.push(s);
                queue.push_back(states.len() - 1);
                states.len() - 1
            })
        };
        for (s, p) in self.draw(&self.m0, &none, &fresh) {
            let i = add(s, &mut states, &mut queue);
            initial.push((i, p));
        }
        let mut arcs: Vec<Arc> = Vec::new();
        while let Some(i) = queue.pop_front() {
            if states.len() > self.max_states {
                return Err(format!(
                    "more than {} states: the net is unbounded, or raise max_states",
                    self.max_states
                ));
            }
            let s = states[i].clone();
            let first = arcs.len();
            for (t, theta, next, p) in self.successors(&s) {
                let to = add(next, &mut states, &mut queue);
                match arcs[first..]
                    .iter_mut()
                    .find(|a| a.to == to && a.transition == t && a.theta == theta)
                {
                    Some(a) => a.p += p,
                    None => arcs.push(Arc {
                        from: i,
                        to,
                        transition: t,
                        theta,
                        p,
                    }),
                }
            }
        }
        Ok(StateGraph {
            states,
            initial,
            arcs,
        })
    }
}

impl StateGraph {
    /// States with no successor.
    pub fn sinks(&self) -> Vec<usize> {
        (0..self.states.len())
            .filter(|&i| self.out(i).is_empty())
            .collect()
    }

    /// The terminal strongly connected components (no arc leaves them).
    pub fn terminal_components(&self) -> Vec<Vec<usize>> {
        let mut g = petgraph::graph::DiGraph::<(), ()>::new();
        let nodes: Vec<_> = self.states.iter().map(|_| g.add_node(())).collect();
        for a in &self.arcs {
            g.add_edge(nodes[a.from], nodes[a.to], ());
        }
        let mut out: Vec<Vec<usize>> = petgraph::algo::tarjan_scc(&g)
            .into_iter()
            .map(|c| {
                let mut c: Vec<usize> = c.into_iter().map(|n| n.index()).collect();
                c.sort_unstable();
                c
            })
            .filter(|c| {
                self.arcs
                    .iter()
                    .filter(|a| c.binary_search(&a.from).is_ok())
                    .all(|a| c.binary_search(&a.to).is_ok())
            })
            .collect();
        out.sort();
        out
    }

    /// The mean time spent in a state before leaving it, `η_i = Σ_j p_ij θ_ij`.
    fn sojourn(&self, i: usize) -> Q {
        self.out(i)
            .iter()
            .map(|a| &a.p * Q::from_integer(a.theta.into()))
            .sum()
    }

    /// The steady state of the terminal component `c` (the graph's only one, for the
    /// chain to have one): per state, the fraction of time spent in it
    /// (`π_i = η_i γ_i / Σ η_k γ_k`, `γ` the embedded chain's stationary vector), and the
    /// mean time between two visits of its first state.
    pub fn steady_state(&self, c: &[usize]) -> Option<(Vec<(usize, Q)>, Q)> {
        let gamma = self.stationary(c)?;
        let weighted: Vec<Q> = c
            .iter()
            .zip(&gamma)
            .map(|(&s, g)| self.sojourn(s) * g)
            .collect();
        let total: Q = weighted.iter().cloned().sum();
        if total.is_zero() {
            return None;
        }
        let pi = c
            .iter()
            .zip(&weighted)
            .map(|(&s, w)| (s, w / &total))
            .collect();
        let cycle = &total / &gamma[0];
        Some((pi, cycle))
    }

    /// The stationary vector `γ` of the embedded chain on the terminal component `c`:
    /// `γ (P − I) = 0`, `Σγ = 1`.
    pub fn stationary(&self, c: &[usize]) -> Option<Vec<Q>> {
        let n = c.len();
        let pos = |s: usize| c.binary_search(&s).ok();
        // The transposed system, its last row replaced by Σγ = 1.
        let mut a = vec![solve::Row::new(); n];
        for arc in &self.arcs {
            if let (Some(i), Some(j)) = (pos(arc.from), pos(arc.to)) {
                solve::add(&mut a[j], i, arc.p.clone());
            }
        }
        for (i, row) in a.iter_mut().enumerate() {
            solve::add(row, i, -Q::one());
        }
        a[n - 1] = (0..n).map(|i| (i, Q::one())).collect();
        let mut b = vec![Q::zero(); n];
        b[n - 1] = Q::one();
        solve::solve(a, b)
    }

    /// From each state, the probability of reaching `target` and the mean time to it
    /// (conditioned on reaching it), by the first-passage equations
    /// `f_u = Σ_v p_uv h_v`, `g_u = Σ_v p_uv (θ_uv h_v + [v ∉ T] g_v)` with `h_v = 1` on
    /// the target; the target's own states are 1 and 0.
    pub fn first_passage(&self, target: &[usize]) -> Option<Vec<(Q, Q)>> {
        let (f, g) = self.passage(&|s| target.contains(&s), &|_| false)?;
        Some(
            f.into_iter()
                .zip(g)
                .map(|(f, g)| {
                    let t = if f.is_zero() { Q::zero() } else { &g / &f };
                    (f, t)
                })
                .collect(),
        )
    }

    /// The first-passage equations: `h_u = Σ_v p_uv h_v` and
    /// `g_u = Σ_v p_uv (θ_uv h_v + g_v)` on the states neither `reached` nor `stopped`;
    /// `h` is 1 on the reached states and 0 on the stopped ones, `g` 0 on both.
    pub(crate) fn passage(
        &self,
        reached: &dyn Fn(usize) -> bool,
        stopped: &dyn Fn(usize) -> bool,
    ) -> Option<(Vec<Q>, Vec<Q>)> {
        let n = self.states.len();
        // The states that cannot reach the target count as stopped (h = 0): without
        // them, a closed class that never reaches it would make the system singular.
        let mut into: Vec<Vec<usize>> = vec![Vec::new(); n];
        for arc in &self.arcs {
            into[arc.to].push(arc.from);
        }
        let mut can: Vec<bool> = (0..n).map(reached).collect();
        let mut queue: Vec<usize> = (0..n).filter(|&s| can[s]).collect();
        while let Some(v) = queue.pop() {
            for &u in &into[v] {
                if !can[u] && !stopped(u) {
                    can[u] = true;
                    queue.push(u);
                }
            }
        }
        let stopped = |s: usize| stopped(s) || !can[s];
        let end = |s: usize| reached(s) || stopped(s);
        let mut a = vec![solve::Row::new(); n];
        let mut bh = vec![Q::zero(); n];
        for (i, row) in a.iter_mut().enumerate() {
            row.insert(i, Q::one());
            if reached(i) {
                bh[i] = Q::one();
            }
        }
        for arc in self.arcs.iter().filter(|a| !end(a.from)) {
            if reached(arc.to) {
                bh[arc.from] += arc.p.clone();
            } else if !stopped(arc.to) {
                solve::add(&mut a[arc.from], arc.to, -arc.p.clone());
            }
        }
        let h = solve::solve(a.clone(), bh)?;
        let mut bg = vec![Q::zero(); n];
        for arc in self.arcs.iter().filter(|a| !end(a.from)) {
            bg[arc.from] += &arc.p * Q::from_integer(arc.theta.into()) * &h[arc.to];
        }
        let g = solve::solve(a, bg)?;
        Some((h, g))
    }

    /// The quantitative abstract view on the observable states `observable` (AJ95 in the thesis, the
    /// thesis's views): from each observable state `o` to each observable state `o'`
    /// reached first (through unobservable states only), the probability `F(o, o')` and
    /// the mean time `T = G/F`, with `F(o,o') = Σ_v p_ov h_v(o')` and
    /// `G(o,o') = Σ_v p_ov (θ_ov h_v(o') + [v ∉ O] g_v(o'))`. Arcs of probability 0 are
    /// left out. `None` when a system is singular (unobservable states that loop forever).
    pub fn abstract_view(&self, observable: &[usize]) -> Option<Vec<(usize, usize, Q, Q)>> {
        let mut out = Vec::new();
        for &target in observable {
            // h and g over the unobservable states, for this target: the target counts
            // as reached, the other observable states stop the path.
            let (h, g) = self.passage(&|s| s == target, &|s| {
                s != target && observable.contains(&s)
            })?;
            for &o in observable {
                let (mut f, mut gg) = (Q::zero(), Q::zero());
                for arc in self.out(o) {
                    let (h, gv) = (&h[arc.to], &g[arc.to]);
                    gg += &arc.p * (Q::from_integer(arc.theta.into()) * h + gv);
                    f += &arc.p * h;
                }
                if !f.is_zero() {
                    let t = &gg / &f;
                    out.push((o, target, f, t));
                }
            }
        }
        out.sort_by_key(|a| (a.0, a.1));
        Some(out)
    }

    /// The mean time to a first failure from the initial distribution: the mean time to
    /// reach a state of `failed`, which must be reached with probability 1.
    pub fn mttf(&self, failed: &[usize]) -> Option<Q> {
        let fp = self.first_passage(failed)?;
        let mut total = Q::zero();
        for (s, p) in &self.initial {
            if !fp[*s].0.is_one() {
                return None;
            }
            total += p * &fp[*s].1;
        }
        Some(total)
    }

    /// The states whose marking has a token in place `p`.
    pub fn marked(&self, p: usize) -> Vec<usize> {
        (0..self.states.len())
            .filter(|&s| self.states[s].marking.get(p).is_some_and(|k| *k > 0))
            .collect()
    }
}

mod query;
mod solve;

pub use query::{Dated, Outcome, ViewArc};

#[cfg(test)]
mod tests;
