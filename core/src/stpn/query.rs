//! The analyses a net file asks for (`queries`), on events: an event is the firing of a
//! transition, and the state graph is split so that the states reached by an event are
//! nodes of their own (a state reached by two transitions becomes two nodes with the
//! same successors). Views and first passages then run between event nodes, and a
//! source event's nodes are weighted by how often the chain visits them: its stationary
//! vector when the graph ends in one cyclic terminal component, its expected visits
//! when every run ends in a sink.

use super::{Arc, Net, Q, QueryDef, StateGraph, solve};
use num_bigint::BigInt;
use num_traits::{One, Zero};
use serde::Serialize;
use std::collections::BTreeMap;

/// One arc of an event view: after `from`, the first of the view's events is `to` with
/// probability `p`, after `t` on average.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ViewArc {
    /// The source event.
    pub from: String,
    /// The event that comes first after it.
    pub to: String,
    /// Its probability.
    #[serde(serialize_with = "super::ser_q")]
    pub p: Q,
    /// The mean time to it, in the net's unit, given that it comes.
    #[serde(serialize_with = "super::ser_q")]
    pub t: Q,
}

/// An event at a date, with the probability that it happens then.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Dated {
    /// The date, in the net's unit, from the initial marking.
    #[serde(serialize_with = "super::ser_q")]
    pub date: Q,
    /// The event.
    pub event: String,
    /// The probability.
    #[serde(serialize_with = "super::ser_q")]
    pub p: Q,
}

/// The answer to a query.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub enum Outcome {
    /// An event view.
    View {
        /// The query's name.
        name: String,
        /// Its arcs, by source then target event.
        arcs: Vec<ViewArc>,
    },
    /// A first passage.
    Passage {
        /// The query's name.
        name: String,
        /// The probability that an event of `to` comes.
        #[serde(serialize_with = "super::ser_q")]
        p: Q,
        /// The mean time to it when it comes (`None`: it never comes).
        #[serde(serialize_with = "ser_opt_q")]
        mean: Option<Q>,
    },
    /// Dated events.
    Timeline {
        /// The query's name.
        name: String,
        /// By date, then event.
        events: Vec<Dated>,
    },
    /// Markings reached.
    Reach {
        /// The query's name.
        name: String,
        /// The probability of reaching one.
        #[serde(serialize_with = "super::ser_q")]
        p: Q,
        /// The mean time to the first, when reached.
        #[serde(serialize_with = "ser_opt_q")]
        first: Option<Q>,
        /// The mean time the net stays there (`None`: never reached, or never left).
        #[serde(serialize_with = "ser_opt_q")]
        stay: Option<Q>,
    },
    /// A query this variant cannot answer.
    Unanswered {
        /// The query's name.
        name: String,
        /// Why.
        why: String,
    },
}

fn ser_opt_q<S: serde::Serializer>(q: &Option<Q>, s: S) -> Result<S::Ok, S::Error> {
    match q {
        Some(q) => s.serialize_str(&q.to_string()),
        None => s.serialize_none(),
    }
}

/// A state graph whose states reached by the chosen events are nodes of their own.
struct Split {
    g: StateGraph,
    /// Per node, the event (transition) that reached it, for an event node.
    event: Vec<Option<usize>>,
}

impl StateGraph {
    /// The arcs leaving state `i` (the arcs are sorted by source).
    pub(crate) fn out(&self, i: usize) -> &[Arc] {
        let lo = self.arcs.partition_point(|a| a.from < i);
        let hi = self.arcs.partition_point(|a| a.from <= i);
        &self.arcs[lo..hi]
    }

    /// The expected visits of each state from the initial distribution, the states of
    /// `absorbing` entered but never left: `x_j − Σ_{i not absorbing} p_ij x_i = init_j`.
    fn visits(&self, absorbing: &dyn Fn(usize) -> bool) -> Option<Vec<Q>> {
        let n = self.states.len();
        let mut a = vec![solve::Row::new(); n];
        for (j, row) in a.iter_mut().enumerate() {
            row.insert(j, Q::one());
        }
        for arc in self.arcs.iter().filter(|a| !absorbing(a.from)) {
            solve::add(&mut a[arc.to], arc.from, -arc.p.clone());
        }
        let mut b = vec![Q::zero(); n];
        for (s, p) in &self.initial {
            b[*s] += p.clone();
        }
        solve::solve(a, b)
    }

    /// The graph with a node per (event, state) reached by an arc of one of `events`.
    fn split(&self, events: &[usize]) -> Split {
        let n = self.states.len();
        let mut nodes: std::collections::BTreeMap<(usize, usize), usize> = Default::default();
        let mut origin: Vec<usize> = (0..n).collect();
        let mut event = vec![None; n];
        for a in &self.arcs {
            if events.contains(&a.transition) {
                nodes.entry((a.transition, a.to)).or_insert_with(|| {
                    origin.push(a.to);
                    event.push(Some(a.transition));
                    origin.len() - 1
                });
            }
        }
        let target = |a: &Arc| {
            if events.contains(&a.transition) {
                nodes[&(a.transition, a.to)]
            } else {
                a.to
            }
        };
        let mut arcs = Vec::new();
        for (node, &s) in origin.iter().enumerate() {
            for a in self.out(s) {
                arcs.push(Arc {
                    from: node,
                    to: target(a),
                    transition: a.transition,
                    theta: a.theta,
                    p: a.p.clone(),
                });
            }
        }
        let states = origin.iter().map(|&s| self.states[s].clone()).collect();
        Split {
            g: StateGraph {
                states,
                initial: self.initial.clone(),
                arcs,
            },
            event,
        }
    }

    /// How often the chain is in each state: the stationary vector of its one cyclic
    /// terminal component, or, when every terminal component is a sink, the expected
    /// number of visits from the initial distribution. `None` otherwise (several
    /// cyclic terminal components: the weights depend on which one the run enters).
    fn weights(&self) -> Result<Vec<Q>, String> {
        let n = self.states.len();
        let terminal = self.terminal_components();
        let cyclic: Vec<&Vec<usize>> = terminal
            .iter()
            .filter(|c| !self.out(c[0]).is_empty())
            .collect();
        match cyclic.as_slice() {
            [c] => {
                let gamma = self
                    .stationary(c)
                    .ok_or("the steady state's equations are singular")?;
                let mut w = vec![Q::zero(); n];
                for (&s, g) in c.iter().zip(gamma) {
                    w[s] = g;
                }
                Ok(w)
            }
            [] => self
                .visits(&|_| false)
                .ok_or_else(|| "the visits' equations are singular".into()),
            _ => Err(format!(
                "{} cyclic terminal components: the chain has no single steady state",
                cyclic.len()
            )),
        }
    }

    /// Leaving node `o` by one arc, then the first passage (`h`, `g` of
    /// [`StateGraph::passage`]): `F = Σ_v p_ov h_v`, `G = Σ_v p_ov (θ_ov h_v + g_v)`.
    fn leave(&self, o: usize, h: &[Q], g: &[Q]) -> (Q, Q) {
        let (mut f, mut gg) = (Q::zero(), Q::zero());
        for arc in self.out(o) {
            gg += &arc.p * (Q::from_integer(arc.theta.into()) * &h[arc.to] + &g[arc.to]);
            f += &arc.p * &h[arc.to];
        }
        (f, gg)
    }
}

impl Net {
    fn events(&self, names: &[String]) -> Result<Vec<usize>, String> {
        names
            .iter()
            .map(|e| {
                self.transitions
                    .iter()
                    .position(|t| t == e)
                    .ok_or_else(|| format!("`{e}` is not a transition of this variant"))
            })
            .collect()
    }

    fn in_units(&self, ticks: Q) -> Q {
        ticks / Q::from_integer(BigInt::from(self.ticks_per_unit))
    }

    /// Answers the net's queries on its state graph `g`.
    pub fn answer(&self, g: &StateGraph) -> Vec<Outcome> {
        self.queries
            .iter()
            .map(|q| {
                let name = match q {
                    QueryDef::View { name, .. }
                    | QueryDef::Timeline { name, .. }
                    | QueryDef::Passage { name, .. }
                    | QueryDef::Reach { name, .. } => name.clone(),
                };
                self.answer_one(g, q)
                    .unwrap_or_else(|why| Outcome::Unanswered {
                        name: name.clone(),
                        why,
                    })
            })
            .collect()
    }

    fn answer_one(&self, g: &StateGraph, q: &QueryDef) -> Result<Outcome, String> {
        match q {
            QueryDef::View { name, events } => self.view(g, name, events),
            QueryDef::Timeline { name, events } => self.timeline(g, name, events),
            QueryDef::Passage { name, from, to } => self.first_passage_of(g, name, from, to),
            QueryDef::Reach {
                name,
                marked,
                empty,
            } => self.reach(g, name, marked, empty),
        }
    }

    fn view(&self, g: &StateGraph, name: &str, events: &[String]) -> Result<Outcome, String> {
        let ev = self.events(events)?;
        let split = g.split(&ev);
        let w = split.g.weights()?;
        let mut arcs = Vec::new();
        for &to in &ev {
            let (h, gg) = split
                .g
                .passage(&|s| split.event[s] == Some(to), &|s| {
                    split.event[s].is_some_and(|e| e != to)
                })
                .ok_or("the first-passage equations are singular")?;
            for &from in &ev {
                let (mut wf, mut wg, mut total) = (Q::zero(), Q::zero(), Q::zero());
                for o in (0..split.g.states.len()).filter(|&o| split.event[o] == Some(from)) {
                    let (f, gsum) = split.g.leave(o, &h, &gg);
                    wf += &w[o] * f;
                    wg += &w[o] * gsum;
                    total += w[o].clone();
                }
                if total.is_zero() || wf.is_zero() {
                    continue;
                }
                arcs.push(ViewArc {
                    from: self.transitions[from].clone(),
                    to: self.transitions[to].clone(),
                    p: &wf / &total,
                    t: self.in_units(&wg / &wf),
                });
            }
        }
        arcs.sort_by(|a, b| (&a.from, &a.to).cmp(&(&b.from, &b.to)));
        Ok(Outcome::View {
            name: name.to_string(),
            arcs,
        })
    }

    fn timeline(&self, g: &StateGraph, name: &str, events: &[String]) -> Result<Outcome, String> {
        let ev = self.events(events)?;
        let mut dg = petgraph::graph::DiGraph::<(), ()>::new();
        let nodes: Vec<_> = g.states.iter().map(|_| dg.add_node(())).collect();
        for a in &g.arcs {
            dg.add_edge(nodes[a.from], nodes[a.to], ());
        }
        let order = petgraph::algo::toposort(&dg, None)
            .map_err(|_| "the state graph has cycles: a timeline needs a horizon".to_string())?;
        let mut at: Vec<BTreeMap<u64, Q>> = vec![BTreeMap::new(); g.states.len()];
        for (s, p) in &g.initial {
            *at[*s].entry(0).or_insert_with(Q::zero) += p.clone();
        }
        // Per (date, event): its probability and the first position, in the
        // topological order, of a state it fires from (so that the events of
        // one instant come in their causal order).
        let mut dated: BTreeMap<(u64, usize), (Q, usize)> = BTreeMap::new();
        for (rank, node) in order.into_iter().enumerate() {
            let s = node.index();
            let here = std::mem::take(&mut at[s]);
            for a in g.out(s) {
                for (date, p) in &here {
                    let (d, p) = (date + a.theta, p * &a.p);
                    if ev.contains(&a.transition) {
                        dated
                            .entry((d, a.transition))
                            .or_insert_with(|| (Q::zero(), rank))
                            .0 += p.clone();
                    }
                    *at[a.to].entry(d).or_insert_with(Q::zero) += p;
                }
            }
        }
        let mut dated: Vec<((u64, usize), (Q, usize))> = dated.into_iter().collect();
        dated.sort_by_key(|((d, t), (_, rank))| (*d, *rank, *t));
        Ok(Outcome::Timeline {
            name: name.to_string(),
            events: dated
                .into_iter()
                .map(|((d, t), (p, _))| Dated {
                    date: self.in_units(Q::from_integer(d.into())),
                    event: self.transitions[t].clone(),
                    p,
                })
                .collect(),
        })
    }

    fn first_passage_of(
        &self,
        g: &StateGraph,
        name: &str,
        from: &[String],
        to: &[String],
    ) -> Result<Outcome, String> {
        let (from, to) = (self.events(from)?, self.events(to)?);
        let mut all = from.clone();
        all.extend(&to);
        let split = g.split(&all);
        let (h, gg) = split
            .g
            .passage(
                &|s| split.event[s].is_some_and(|e| to.contains(&e)),
                &|_| false,
            )
            .ok_or("the first-passage equations are singular")?;
        let (mut wf, mut wg, mut total) = (Q::zero(), Q::zero(), Q::zero());
        if from.is_empty() {
            for (s, p) in &split.g.initial {
                wf += p * &h[*s];
                wg += p * &gg[*s];
                total += p.clone();
            }
        } else {
            let w = split.g.weights()?;
            for o in (0..split.g.states.len())
                .filter(|&o| split.event[o].is_some_and(|e| from.contains(&e)))
            {
                let (f, gsum) = split.g.leave(o, &h, &gg);
                wf += &w[o] * f;
                wg += &w[o] * gsum;
                total += w[o].clone();
            }
        }
        if total.is_zero() {
            return Err("its starting events never happen".into());
        }
        let mean = (!wf.is_zero()).then(|| self.in_units(&wg / &wf));
        Ok(Outcome::Passage {
            name: name.to_string(),
            p: &wf / &total,
            mean,
        })
    }

    fn reach(
        &self,
        g: &StateGraph,
        name: &str,
        marked: &[String],
        empty: &[String],
    ) -> Result<Outcome, String> {
        let place = |p: &String| self.places.iter().position(|x| x == p);
        let marked: Vec<usize> = marked.iter().filter_map(place).collect();
        let empty: Vec<usize> = empty.iter().filter_map(place).collect();
        let inside = |s: usize| {
            let m = &g.states[s].marking;
            marked.iter().all(|&p| m[p] > 0) && empty.iter().all(|&p| m[p] == 0)
        };
        let (h, gg) = g
            .passage(&inside, &|_| false)
            .ok_or("the first-passage equations are singular")?;
        let (mut p, mut time) = (Q::zero(), Q::zero());
        for (s, w) in &g.initial {
            p += w * &h[*s];
            time += w * &gg[*s];
        }
        if p.is_zero() {
            return Ok(Outcome::Reach {
                name: name.to_string(),
                p,
                first: None,
                stay: None,
            });
        }
        let first = Some(self.in_units(&time / &p));
        // Where the net enters: the visits with the markings inside absorbing.
        let n = g.states.len();
        let x = g
            .visits(&inside)
            .ok_or("the entry equations are singular")?;
        let (lh, lg) = g
            .passage(&|s| !inside(s), &|_| false)
            .ok_or("the leaving equations are singular")?;
        let (mut left, mut stay) = (Q::zero(), Q::zero());
        for s in (0..n).filter(|&s| inside(s)) {
            left += &x[s] * &lh[s];
            stay += &x[s] * &lg[s];
        }
        let entered: Q = (0..n).filter(|&s| inside(s)).map(|s| x[s].clone()).sum();
        let stay = (left == entered).then(|| self.in_units(&stay / &left));
        Ok(Outcome::Reach {
            name: name.to_string(),
            p,
            first,
            stay,
        })
    }
}
