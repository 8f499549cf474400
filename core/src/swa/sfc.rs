//! The region monitor `A*` as an IEC 61131-3 program (seed 000, chapter 6.3): the
//! structural translation `A_M → SFC_M` of Allahham's thesis, written as PLCopen TC6
//! XML (two SFC POUs) and as one Structured Text function block that any IEC PLC runs
//! without SFC.
//!
//! - One step per product location whose `E*` is not empty (the others are unreachable
//!   under acceptable behaviour); one transition per edge, its receptivity the edge's
//!   event (`EV_…`, a Boolean input true in the scan the event occurs); several edges
//!   leaving or entering a step are OR-divergences and OR-convergences. An edge into a
//!   location with an empty `E*` is no transition: the event in its source step is a
//!   fault, part of SFC2's receptivity.
//! - A stopwatch `x` is an offset `D_x` (the thesis's `δx`, integer milliseconds):
//!   `x = D_x + T_S` in a step `S` where `x` runs, `x = D_x` where it is stopped, `T_S`
//!   the step's time. The P0 action of a step adds its time to the offsets of the
//!   clocks running there; the reset of `x` by an edge is a P1 `D_x := 0` on its
//!   destination when every edge entering it resets `x` (or finds it at 0), else a P0
//!   on its source when every edge leaving the source does (Fig. 6.7), else the
//!   destination is duplicated, one copy per set of entering edges that agree (Fig.
//!   6.8). A clock that `E*` of a location holds at 0 needs no reset when it leaves.
//! - SFC2 has the steps `ACCEPTABLE` (the thesis's s11) and `FAULT` (s12). Its
//!   receptivity is `OR_i (S_i.X AND NOT E*_i)`, each clock replaced by its offset
//!   expression, each rational coefficient scaled to integers exactly (`3*x <= 2500`,
//!   never a rounded bound), a structural equality `a·x == b` written with a tolerance
//!   `EqTolMs` (one PLC cycle) per unit of `Σ|a|`. `FAULT` sets `Alarm` (N) and freezes
//!   SFC1 (P1); the repair event `Repair` (the thesis's `m`) brings SFC1 back to its
//!   initial step with every offset at 0.
//!
//! The function block `FB_RegionMonitor` runs the same logic scan by scan: step flags
//! `X_S…`, step times `T_S…` that grow by the input `CycleMs`, the P0 and P1 actions as
//! code on the transition taken, and the fault check before and after the events. The
//! XML reads the step flags and times through mirrors of the same names (`X_S3`,
//! `T_S3`, set by each step's actions), so the receptivity is the same text in both.

use super::automaton::Swa;
use super::poly::{Display, Poly, Q};
use super::regions::Region;
use crate::diag::codes;
use crate::diag::{Location as At, Problem};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::Path;

/// Largest value a generated `DINT` expression may reach.
const DINT_MAX: i128 = i32::MAX as i128;
/// A step time saturates here in the function block (about 11.5 days).
const T_MAX: i128 = 1_000_000_000;
/// The headroom of the overflow check: a clock may run this far past its bound in
/// `E*` before the check sees it (a minute of cycles), and `EqTolMs` up to it.
const HEADROOM: i128 = 60_000;

/// Why the monitor cannot be exported.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SfcError {
    /// Two edges leave a location on one event to different places.
    #[error(
        "location `{location}` has {count} edges on event `{event}` that go to different \
         locations or reset different clocks: an SFC transition cannot choose between them"
    )]
    Nondeterministic {
        /// The product location.
        location: String,
        /// The event.
        event: String,
        /// How many edges.
        count: usize,
    },
    /// A constraint may not fit a `DINT`.
    #[error(
        "in `{location}`, `{constraint}` may reach {magnitude} in integer milliseconds, \
         beyond a DINT (2147483647)"
    )]
    Overflow {
        /// The product location.
        location: String,
        /// The constraint as written in the regions.
        constraint: String,
        /// The largest magnitude found.
        magnitude: i128,
    },
}

impl SfcError {
    /// As a problem placed in `file` (the regions file, whose `text` names the
    /// location).
    pub fn problem(&self, file: &Path, text: &str) -> Problem {
        let location = match self {
            SfcError::Nondeterministic { location, .. } | SfcError::Overflow { location, .. } => {
                location
            }
        };
        Problem::error(
            codes::SFC_EXPORT.id,
            self.to_string(),
            Some(At::of_nth(file, text, &format!("\"{location}\""), 0)),
        )
    }
}

/// A step of SFC1: a product location, or one copy of it (Fig. 6.8).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Step {
    /// `S4`, or `S4_1`, `S4_2` for the copies of location 4.
    pub name: String,
    /// The product location.
    pub location: usize,
    /// The initial step (the location of the start, every clock at 0).
    pub initial: bool,
    /// Clocks running here: P0 adds the step's time to their offsets.
    pub running: Vec<usize>,
    /// Offsets P0 sets to 0 (resets moved to the source, Fig. 6.7).
    pub p0_resets: Vec<usize>,
    /// Offsets P1 sets to 0 (resets on the destination).
    pub p1_resets: Vec<usize>,
}

/// A transition of SFC1: one edge of the product leaving one step.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Transition {
    /// `T1`, `T2`, …
    pub name: String,
    /// Source step.
    pub from: usize,
    /// Destination step.
    pub to: usize,
    /// Index in [`Chart::events`].
    pub event: usize,
    /// The product edge.
    pub edge: usize,
}

/// The translation of `A*`: SFC1's steps and transitions and what SFC2 checks.
#[derive(Clone, Debug)]
pub struct Chart {
    /// The product's clocks (`A1.x1`).
    pub clocks: Vec<String>,
    /// The offset variable of each clock (`D_A1_x1`).
    pub offsets: Vec<String>,
    /// `(event, its input variable)`, sorted by event.
    pub events: Vec<(String, String)>,
    /// The product's locations.
    pub locations: Vec<String>,
    /// `E*` per location (empty: unreachable).
    pub regions: Vec<Vec<Poly>>,
    /// The steps, the initial first.
    pub steps: Vec<Step>,
    /// The transitions, by source step then event.
    pub transitions: Vec<Transition>,
    /// `(step, event, edge)`: an event whose edge enters a location with an empty
    /// `E*` (a fault as soon as it occurs in that step).
    pub forbidden: Vec<(usize, usize, usize)>,
    /// Self-loops that change nothing (no clock reset), not written.
    pub idle_loops: usize,
    /// Locations duplicated (Fig. 6.8).
    pub duplicated: Vec<usize>,
}

/// A name made an IEC identifier: letters, digits and single underscores inside.
fn sanitize(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c);
        } else if !out.ends_with('_') {
            out.push('_');
        }
    }
    out.trim_matches('_').to_string()
}

/// `prefix_name` per name, unique without regard to case (a suffix `_2`, `_3`, … on
/// a clash, in order).
fn identifiers(prefix: &str, names: &[String]) -> Vec<String> {
    let mut seen = BTreeSet::new();
    names
        .iter()
        .map(|n| {
            let base = format!("{prefix}_{}", sanitize(n));
            let base = base.trim_end_matches('_').to_string();
            let mut id = base.clone();
            let mut k = 2;
            while !seen.insert(id.to_ascii_uppercase()) {
                id = format!("{base}_{k}");
                k += 1;
            }
            id
        })
        .collect()
}

fn unit(dim: usize, k: usize, sign: i128) -> Vec<Q> {
    let mut d = vec![Q::zero(); dim];
    d[k] = Q::int(sign);
    d
}

/// The clocks `E*` (every member) holds at 0.
fn zero_clocks(region: &[Poly], dim: usize) -> BTreeSet<usize> {
    (0..dim)
        .filter(|&k| {
            !region.is_empty() && region.iter().all(|p| {
                let at_zero =
                    |s: Option<Option<(Q, bool)>>| matches!(s, Some(Some((v, _))) if v.is_zero());
                at_zero(p.sup(&unit(dim, k, 1))) && at_zero(p.sup(&unit(dim, k, -1)))
            })
        })
        .collect()
}

/// A kept edge: `(product edge, from, to, event, resets)`.
struct Kept {
    edge: usize,
    from: usize,
    to: usize,
    event: usize,
    resets: BTreeSet<usize>,
}

/// The edges SFC1 takes from the live locations, the edges into a location with an
/// empty `E*` (`(source, event, edge)`), and the number of self-loops that change
/// nothing.
fn classify(
    swa: &Swa,
    live: &[bool],
    zero: &[BTreeSet<usize>],
    event_names: &[String],
) -> Result<Classified, SfcError> {
    let event_of = |e: &str| event_names.iter().position(|x| x == e).unwrap_or(0);
    let mut kept: Vec<Kept> = Vec::new();
    let mut forbidden_edges: Vec<(usize, usize, usize)> = Vec::new();
    let mut idle_loops = 0;
    for (l, _) in live.iter().enumerate().filter(|(_, v)| **v) {
        let mut by_event: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for (i, e) in swa.edges.iter().enumerate().filter(|(_, e)| e.from == l) {
            by_event.entry(event_of(&e.event)).or_default().push(i);
        }
        for (ev, edges) in by_event {
            let effect = |i: usize| {
                let e = &swa.edges[i];
                let r: BTreeSet<usize> = e
                    .resets
                    .iter()
                    .copied()
                    .filter(|k| !zero[l].contains(k))
                    .collect();
                (e.to, r)
            };
            let distinct: BTreeSet<(usize, BTreeSet<usize>)> =
                edges.iter().map(|&i| effect(i)).collect();
            if distinct.len() > 1 {
                return Err(SfcError::Nondeterministic {
                    location: swa.locations[l].name.clone(),
                    event: event_names[ev].clone(),
                    count: distinct.len(),
                });
            }
            let (to, resets) = effect(edges[0]);
            if !live[to] {
                forbidden_edges.push((l, ev, edges[0]));
            } else if to == l && resets.is_empty() {
                idle_loops += 1;
            } else {
                kept.push(Kept {
                    edge: edges[0],
                    from: l,
                    to,
                    event: ev,
                    resets,
                });
            }
        }
    }

    Ok((kept, forbidden_edges, idle_loops))
}

type Classified = (Vec<Kept>, Vec<(usize, usize, usize)>, usize);

/// Per location: the entering group's candidates ([`BTreeSet`] of clocks every member
/// covers, the resets its members need, whether it holds the start).
type Group = (BTreeSet<usize>, BTreeSet<usize>, bool);

/// What covers a reset on entering by `a`: the clocks it resets or finds at 0.
fn cover(a: &Kept, zero: &[BTreeSet<usize>]) -> BTreeSet<usize> {
    a.resets
        .iter()
        .chain(zero[a.from].iter())
        .copied()
        .collect()
}

/// Where each reset goes: `(P0 resets per location, conflicting clocks per location)`.
/// A reset is a P1 of the destination when every edge entering it covers the clock,
/// else a P0 of the source when every edge leaving it resets the clock (or finds it
/// at 0), else a conflict of the destination (which is duplicated).
fn placement(
    n: usize,
    all: &BTreeSet<usize>,
    zero: &[BTreeSet<usize>],
    kept: &[Kept],
) -> (Vec<BTreeSet<usize>>, Vec<BTreeSet<usize>>) {
    let rin: Vec<BTreeSet<usize>> = (0..n)
        .map(|j| {
            kept.iter()
                .filter(|a| a.to == j)
                .fold(all.clone(), |acc, a| {
                    acc.intersection(&cover(a, zero)).copied().collect()
                })
        })
        .collect();
    let p0ok: Vec<BTreeSet<usize>> = (0..n)
        .map(|i| {
            let out = kept.iter().filter(|a| a.from == i);
            let common = out.fold(all.clone(), |acc, a| {
                acc.intersection(&a.resets).copied().collect()
            });
            common.union(&zero[i]).copied().collect()
        })
        .collect();
    let mut p0_resets: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    let mut conflict: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    for a in kept {
        for &k in a.resets.difference(&rin[a.to]) {
            if p0ok[a.from].contains(&k) {
                p0_resets[a.from].insert(k);
            } else {
                conflict[a.to].insert(k);
            }
        }
    }
    (p0_resets, conflict)
}

/// The groups of the edges entering location `j` (the start too at the initial
/// location), by the conflicting clocks they cover: one step each, the start's first.
fn groups_of(
    j: usize,
    kept: &[Kept],
    zero: &[BTreeSet<usize>],
    conflict: &BTreeSet<usize>,
    all: &BTreeSet<usize>,
) -> Vec<(Vec<usize>, Group)> {
    let key_of = |cov: &BTreeSet<usize>| -> Vec<usize> {
        conflict
            .iter()
            .copied()
            .filter(|k| cov.contains(k))
            .collect()
    };
    // (covers, resets, is the start)
    let mut members: Vec<(BTreeSet<usize>, BTreeSet<usize>, bool)> = kept
        .iter()
        .filter(|a| a.to == j)
        .map(|a| (cover(a, zero), a.resets.clone(), false))
        .collect();
    if j == 0 {
        members.push((all.clone(), all.clone(), true));
    }
    let mut groups: BTreeMap<Vec<usize>, Group> = BTreeMap::new();
    for (cov, resets, start) in &members {
        let g = groups
            .entry(key_of(cov))
            .or_insert_with(|| (all.clone(), BTreeSet::new(), false));
        g.0 = g.0.intersection(cov).copied().collect();
        g.1.extend(resets.iter().copied());
        g.2 |= *start;
    }
    if groups.is_empty() {
        groups.insert(Vec::new(), (all.clone(), BTreeSet::new(), false));
    }
    let mut order: Vec<(Vec<usize>, Group)> = groups.into_iter().collect();
    order.sort_by_key(|(k, g)| (!g.2, k.clone()));
    order
}

/// Translates the monitor of `regions` (one per location of `swa`).
pub fn translate(swa: &Swa, regions: &[Region]) -> Result<Chart, SfcError> {
    let dim = swa.clocks.len();
    let n = swa.locations.len();
    let region: Vec<Vec<Poly>> = (0..n)
        .map(|l| {
            regions
                .get(l)
                .map(|r| r.all.iter().filter(|p| !p.is_empty()).cloned().collect())
                .unwrap_or_default()
        })
        .collect();
    // The initial step exists even when E* is empty there (it alarms at once).
    let live: Vec<bool> = (0..n).map(|l| l == 0 || !region[l].is_empty()).collect();
    let zero: Vec<BTreeSet<usize>> = region.iter().map(|r| zero_clocks(r, dim)).collect();
    let event_names: Vec<String> = swa.events().into_iter().map(str::to_string).collect();
    let event_ids = identifiers("EV", &event_names);
    let all: BTreeSet<usize> = (0..dim).collect();

    let (kept, forbidden_edges, idle_loops) = classify(swa, &live, &zero, &event_names)?;

    let (p0_resets, conflict) = placement(n, &all, &zero, &kept);
    let cover = |a: &Kept| cover(a, &zero);

    // Steps: per live location, one per group of entering edges that agree on the
    // conflicting clocks (the start, at the initial location, resets every clock).
    let mut steps: Vec<Step> = Vec::new();
    // (location, key) → step.
    let mut step_of: BTreeMap<(usize, Vec<usize>), usize> = BTreeMap::new();
    let mut duplicated = Vec::new();
    for j in (0..n).filter(|&j| live[j]) {
        let order = groups_of(j, &kept, &zero, &conflict[j], &all);
        if order.len() > 1 {
            duplicated.push(j);
        }
        let many = order.len() > 1;
        for (i, (key, (cov, needed, start))) in order.into_iter().enumerate() {
            let name = if many {
                format!("S{j}_{}", i + 1)
            } else {
                format!("S{j}")
            };
            let p1: Vec<usize> = if start {
                cov.iter().copied().collect()
            } else {
                cov.intersection(&needed).copied().collect()
            };
            let running = (0..dim)
                .filter(|&k| swa.locations[j].rates[k].is_positive())
                .collect();
            step_of.insert((j, key), steps.len());
            steps.push(Step {
                name,
                location: j,
                initial: start,
                running,
                p0_resets: p0_resets[j].iter().copied().collect(),
                p1_resets: p1,
            });
        }
    }
    let target = |a: &Kept| -> usize {
        let c = &conflict[a.to];
        let cov = cover(a);
        let key: Vec<usize> = c.iter().copied().filter(|k| cov.contains(k)).collect();
        step_of[&(a.to, key)]
    };
    let mut transitions = Vec::new();
    let mut forbidden = Vec::new();
    for (s, step) in steps.iter().enumerate() {
        let l = step.location;
        let mut out: Vec<&Kept> = kept.iter().filter(|a| a.from == l).collect();
        out.sort_by_key(|a| event_ids[a.event].to_ascii_uppercase());
        for a in out {
            transitions.push(Transition {
                name: format!("T{}", transitions.len() + 1),
                from: s,
                to: target(a),
                event: a.event,
                edge: a.edge,
            });
        }
        for &(src, ev, edge) in &forbidden_edges {
            if src == l {
                forbidden.push((s, ev, edge));
            }
        }
    }
    let chart = Chart {
        clocks: swa.clocks.clone(),
        offsets: identifiers("D", &swa.clocks),
        events: event_names.into_iter().zip(event_ids).collect(),
        locations: swa.locations.iter().map(|l| l.name.clone()).collect(),
        regions: region,
        steps,
        transitions,
        forbidden,
        idle_loops,
        duplicated,
    };
    chart.check_overflow()?;
    Ok(chart)
}

/// Integer text of `d·x ⋈ b` for one bound: `(coefficients, right-hand side)` scaled
/// by the bound's denominator.
fn scaled(d: &[i128], b: &Q) -> (Vec<i128>, i128, i128) {
    let s = b.denom();
    (d.iter().map(|c| c * s).collect(), b.numer(), s)
}

impl Chart {
    /// The step's value of clock `k`: `(D_k + T_S)` where it runs, `D_k` elsewhere.
    fn term(&self, s: usize, k: usize) -> String {
        if self.steps[s].running.contains(&k) {
            format!("({} + T_{})", self.offsets[k], self.steps[s].name)
        } else {
            self.offsets[k].clone()
        }
    }

    fn linear(&self, s: usize, c: &[i128]) -> String {
        let mut out = String::new();
        for (k, &c) in c.iter().enumerate().filter(|(_, c)| **c != 0) {
            let t = self.term(s, k);
            let mag = c.abs();
            let body = if mag == 1 { t } else { format!("{mag} * {t}") };
            if out.is_empty() {
                out = if c < 0 { format!("-{body}") } else { body };
            } else {
                let _ = write!(out, " {} {body}", if c < 0 { "-" } else { "+" });
            }
        }
        out
    }

    /// `NOT E*` of step `s`'s location as ST; `None` when `E*` holds everywhere.
    pub fn violation(&self, s: usize) -> Option<String> {
        if self.regions[self.steps[s].location].is_empty() {
            return Some("TRUE".into());
        }
        let mut members = Vec::new();
        for p in &self.regions[self.steps[s].location] {
            let mut ors = Vec::new();
            for (d, b) in p.directions() {
                match (&b.lo, &b.hi) {
                    (Some(lo), Some(hi)) if lo.value == hi.value => {
                        let (c, p, sc) = scaled(d, &lo.value);
                        let n: i128 = d.iter().map(|x| x.abs()).sum::<i128>() * sc;
                        let lin = self.linear(s, &c);
                        ors.push(format!(
                            "({lin} > {p} + {n} * EqTolMs) OR ({lin} < {p} - {n} * EqTolMs)"
                        ));
                    }
                    (lo, hi) => {
                        if let Some(hi) = hi {
                            let (c, p, _) = scaled(d, &hi.value);
                            let op = if hi.strict { ">=" } else { ">" };
                            ors.push(format!("({} {op} {p})", self.linear(s, &c)));
                        }
                        if let Some(lo) = lo {
                            let (c, p, _) = scaled(d, &lo.value);
                            let op = if lo.strict { "<=" } else { "<" };
                            ors.push(format!("({} {op} {p})", self.linear(s, &c)));
                        }
                    }
                }
            }
            if ors.is_empty() {
                return None;
            }
            members.push(if ors.len() == 1 {
                ors.remove(0)
            } else {
                format!("({})", ors.join(" OR "))
            });
        }
        Some(members.join(" AND "))
    }

    /// SFC2's receptivity `OR_i (X_Si AND NOT E*_i)`, with the forbidden events.
    pub fn fault_condition(&self) -> String {
        let mut terms = Vec::new();
        for (s, step) in self.steps.iter().enumerate() {
            if let Some(v) = self.violation(s) {
                terms.push(format!("(X_{} AND ({v}))", step.name));
            }
        }
        for &(s, ev, _) in &self.forbidden {
            terms.push(format!(
                "(X_{} AND {})",
                self.steps[s].name, self.events[ev].1
            ));
        }
        if terms.is_empty() {
            "FALSE".into()
        } else {
            terms.join("\n    OR ")
        }
    }

    /// Refuses an export whose expressions may leave a `DINT`.
    fn check_overflow(&self) -> Result<(), SfcError> {
        let dim = self.clocks.len();
        for (l, region) in self.regions.iter().enumerate() {
            // The largest value of each clock in E* (a step time saturates at T_MAX).
            let bound: Vec<i128> = (0..dim)
                .map(|k| {
                    region
                        .iter()
                        .map(|p| match p.sup(&unit(dim, k, 1)) {
                            Some(Some((v, _))) => v.ceil().max(0),
                            _ => 2 * T_MAX,
                        })
                        .max()
                        .unwrap_or(0)
                        + HEADROOM
                })
                .collect();
            for p in region {
                for (d, b) in p.directions() {
                    for v in [&b.lo, &b.hi].into_iter().flatten() {
                        let (c, rhs, s) = scaled(d, &v.value);
                        let norm: i128 = d.iter().map(|x| x.abs()).sum::<i128>() * s;
                        let mag = c
                            .iter()
                            .zip(&bound)
                            .map(|(c, m)| c.abs().saturating_mul(*m))
                            .fold(0i128, i128::saturating_add)
                            .max(rhs.abs().saturating_add(norm.saturating_mul(HEADROOM)));
                        if mag > DINT_MAX {
                            let mut one = Poly::universe(dim);
                            for h in p.half_spaces() {
                                let hd: Vec<i128> = h.a.iter().map(Q::numer).collect();
                                if hd.iter().zip(d).all(|(x, y)| x.abs() == y.abs()) {
                                    one.add(h);
                                }
                            }
                            return Err(SfcError::Overflow {
                                location: self.locations[l].clone(),
                                constraint: Display {
                                    poly: &one,
                                    names: &self.clocks,
                                }
                                .to_string(),
                                magnitude: mag,
                            });
                        }
                    }
                }
            }
        }
        Ok(())
    }

    fn p0_code(&self, s: usize, time: &str, indent: &str) -> String {
        let step = &self.steps[s];
        let mut out = String::new();
        for &k in &step.running {
            let d = &self.offsets[k];
            let _ = writeln!(out, "{indent}{d} := {d} + {time};");
        }
        for &k in &step.p0_resets {
            let _ = writeln!(out, "{indent}{} := 0;", self.offsets[k]);
        }
        out
    }

    fn p1_code(&self, s: usize, indent: &str) -> String {
        let mut out = String::new();
        for &k in &self.steps[s].p1_resets {
            let _ = writeln!(out, "{indent}{} := 0;", self.offsets[k]);
        }
        out
    }

    fn edge_text(&self, t: &Transition) -> String {
        format!(
            "{}: {} --{}--> {} ({} -> {})",
            t.name,
            self.steps[t.from].name,
            self.events[t.event].0,
            self.steps[t.to].name,
            self.locations[self.steps[t.from].location],
            self.locations[self.steps[t.to].location]
        )
    }

    fn region_text(&self, s: usize) -> String {
        self.regions[self.steps[s].location]
            .iter()
            .map(|p| {
                Display {
                    poly: p,
                    names: &self.clocks,
                }
                .to_string()
            })
            .collect::<Vec<_>>()
            .join(" || ")
    }

    /// The function block `FB_RegionMonitor`: SFC1 and SFC2 as explicit code, one
    /// scan per call. Inputs: `CycleMs` (the time since the last call), `EqTolMs` (the
    /// tolerance of a structural equality, one cycle), `Repair` (the event `m`) and one
    /// `EV_…` per event (true in the scan it occurs; one event per scan); output
    /// `Alarm` (SFC2 in `FAULT`, SFC1 frozen until `Repair`).
    pub fn function_block(&self) -> String {
        let mut o = String::new();
        o.push_str(
            "(* The region monitor A* of Vigie's synthesis as an IEC 61131-3 function block\n",
        );
        o.push_str(
            "   (seed 000, ch. 6.3: SFC1, the acceptable behaviour, and SFC2, the fault check).\n",
        );
        o.push_str("   Clocks are offsets D_x in ms: x = D_x + T_S in a step S where x runs, D_x elsewhere.\n");
        o.push_str("   Generated by `vigie export-sfc`. *)\n");
        o.push_str("FUNCTION_BLOCK FB_RegionMonitor\nVAR_INPUT\n");
        o.push_str("    CycleMs : DINT; (* ms since the last call *)\n");
        o.push_str("    EqTolMs : DINT; (* tolerance of a structural equality per unit coefficient, ms: one cycle *)\n");
        o.push_str(
            "    Repair : BOOL; (* the repair event m: back to the initial step, offsets at 0 *)\n",
        );
        for (e, id) in &self.events {
            let _ = writeln!(o, "    {id} : BOOL; (* event {} *)", comment(e));
        }
        o.push_str("END_VAR\nVAR_OUTPUT\n    Alarm : BOOL; (* SFC2 in FAULT: the clocks left E* *)\nEND_VAR\nVAR\n");
        o.push_str("    Started : BOOL;\n");
        for (s, step) in self.steps.iter().enumerate() {
            let _ = writeln!(
                o,
                "    X_{0} : BOOL; (* {1} *)\n    T_{0} : DINT;",
                step.name,
                comment(&self.locations[self.steps[s].location])
            );
        }
        for (k, d) in self.offsets.iter().enumerate() {
            let _ = writeln!(
                o,
                "    {d} : DINT; (* offset of {} *)",
                comment(&self.clocks[k])
            );
        }
        o.push_str("END_VAR\n");
        let viol = self.fault_condition();
        // 1. Time: the active step ages (SFC1 frozen while in FAULT).
        o.push_str("(* SFC1: the active step ages by the cycle; frozen in FAULT *)\n");
        let timed: Vec<usize> = (0..self.steps.len())
            .filter(|&s| !self.steps[s].running.is_empty())
            .collect();
        if !timed.is_empty() {
            o.push_str("IF Started AND NOT Alarm THEN\n");
            for (i, &s) in timed.iter().enumerate() {
                let name = &self.steps[s].name;
                let _ = writeln!(o, "    {}IF X_{name} THEN", if i == 0 { "" } else { "ELS" });
                let _ = writeln!(
                    o,
                    "        IF T_{name} < {T_MAX} THEN\n            T_{name} := T_{name} + CycleMs;\n        END_IF;"
                );
            }
            o.push_str("    END_IF;\nEND_IF;\n");
        }
        // 2. SFC2 before the events.
        o.push_str("(* SFC2: ACCEPTABLE -> FAULT when the clocks left E* of the active step *)\n");
        let _ = writeln!(
            o,
            "IF Started AND NOT Alarm THEN\n    Alarm := {};\nEND_IF;",
            viol.replace('\n', "\n    ")
        );
        // 3. Start and repair.
        o.push_str("(* SFC2: FAULT -> ACCEPTABLE on the repair m, SFC1 to its initial step, every offset at 0 *)\n");
        o.push_str("IF NOT Started OR Repair THEN\n    Started := TRUE;\n    Alarm := FALSE;\n");
        for (s, step) in self.steps.iter().enumerate() {
            let _ = writeln!(
                o,
                "    X_{0} := {1};\n    T_{0} := 0;",
                step.name,
                if s == 0 { "TRUE" } else { "FALSE" }
            );
        }
        for d in &self.offsets {
            let _ = writeln!(o, "    {d} := 0;");
        }
        o.push_str("ELSIF NOT Alarm THEN\n");
        // 4. SFC1: one transition.
        if !self.transitions.is_empty() {
            o.push_str("    (* SFC1: the transition of the event, P0 of the step left, P1 of the step entered *)\n");
            for (i, t) in self.transitions.iter().enumerate() {
                let from = &self.steps[t.from].name;
                let to = &self.steps[t.to].name;
                let _ = writeln!(
                    o,
                    "    {}IF X_{from} AND {} THEN (* {} *)",
                    if i == 0 { "" } else { "ELS" },
                    self.events[t.event].1,
                    comment(&self.edge_text(t))
                );
                o.push_str(&self.p0_code(t.from, &format!("T_{from}"), "        "));
                let _ = writeln!(o, "        X_{from} := FALSE;");
                let _ = writeln!(o, "        X_{to} := TRUE;\n        T_{to} := 0;");
                o.push_str(&self.p1_code(t.to, "        "));
            }
            o.push_str("    END_IF;\n");
        }
        // 5. SFC2 after.
        let _ = writeln!(
            o,
            "    (* SFC2 again, in the step entered *)\n    Alarm := {};",
            viol.replace('\n', "\n        ")
        );
        o.push_str("END_IF;\nEND_FUNCTION_BLOCK\n");
        o
    }

    /// The PLCopen TC6 XML (2.01): the POUs `SFC1` and `SFC2` and the global
    /// variables they share.
    pub fn plcopen(&self, name: &str) -> String {
        let mut o = String::new();
        o.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
        let _ = writeln!(
            o,
            "<project xmlns=\"{}\" xmlns:xhtml=\"http://www.w3.org/1999/xhtml\">",
            crate::plcopen::NAMESPACE
        );
        let _ = writeln!(
            o,
            "  <fileHeader companyName=\"Vigie\" productName=\"Vigie\" productVersion=\"{}\" creationDateTime=\"1970-01-01T00:00:00\"/>",
            env!("CARGO_PKG_VERSION")
        );
        let _ = writeln!(o, "  <contentHeader name=\"{}\">", esc(name));
        o.push_str("    <coordinateInfo>\n      <fbd><scaling x=\"10\" y=\"10\"/></fbd>\n      <ld><scaling x=\"10\" y=\"10\"/></ld>\n      <sfc><scaling x=\"10\" y=\"10\"/></sfc>\n    </coordinateInfo>\n  </contentHeader>\n");
        o.push_str("  <types>\n    <dataTypes/>\n    <pous>\n");
        self.write_sfc1(&mut o);
        self.write_sfc2(&mut o);
        o.push_str("    </pous>\n  </types>\n");
        o.push_str("  <instances>\n    <configurations>\n      <configuration name=\"Config0\">\n        <resource name=\"Res0\">\n          <task name=\"Main\" interval=\"T#10ms\" priority=\"0\">\n");
        o.push_str("            <pouInstance name=\"i_SFC1\" typeName=\"SFC1\"/>\n            <pouInstance name=\"i_SFC2\" typeName=\"SFC2\"/>\n");
        o.push_str("          </task>\n        </resource>\n        <globalVars>\n");
        for (n, ty, doc) in self.globals() {
            let _ = writeln!(
                o,
                "          <variable name=\"{n}\"><type><{ty}/></type><documentation><xhtml:p>{}</xhtml:p></documentation></variable>",
                esc(&doc)
            );
        }
        o.push_str("        </globalVars>\n      </configuration>\n    </configurations>\n  </instances>\n</project>\n");
        o
    }

    /// `(name, type, what)` of every shared variable.
    fn globals(&self) -> Vec<(String, &'static str, String)> {
        let mut g = vec![
            (
                "Repair".to_string(),
                "BOOL",
                "the repair event m".to_string(),
            ),
            ("Alarm".into(), "BOOL", "SFC2 in FAULT".into()),
            ("Freeze".into(), "BOOL", "SFC1 frozen (set by FAULT)".into()),
            (
                "Restart".into(),
                "BOOL",
                "SFC1 back to its initial step (the repair)".into(),
            ),
            (
                "EqTolMs".into(),
                "DINT",
                "tolerance of a structural equality per unit coefficient, ms (one cycle)".into(),
            ),
        ];
        for (e, id) in &self.events {
            g.push((id.clone(), "BOOL", format!("event {e}")));
        }
        for (k, d) in self.offsets.iter().enumerate() {
            g.push((
                d.clone(),
                "DINT",
                format!("offset of {}, ms", self.clocks[k]),
            ));
        }
        for s in &self.steps {
            let l = &self.locations[s.location];
            g.push((
                format!("X_{}", s.name),
                "BOOL",
                format!("{}.X ({l})", s.name),
            ));
            g.push((
                format!("T_{}", s.name),
                "DINT",
                format!("{}.T in ms", s.name),
            ));
        }
        g
    }

    /// The ST body of each SFC1 action: `(name, qualifier, body)` per step.
    pub fn sfc1_actions(&self) -> Vec<(String, &'static str, String)> {
        let mut out = Vec::new();
        for (s, step) in self.steps.iter().enumerate() {
            let n = &step.name;
            let mut p1 = String::new();
            if step.initial {
                p1.push_str("IF Restart THEN\n");
                for d in &self.offsets {
                    let _ = writeln!(p1, "    {d} := 0;");
                }
                p1.push_str("    Restart := FALSE;\nEND_IF;\n");
            }
            p1.push_str(&self.p1_code(s, ""));
            let _ = write!(p1, "X_{n} := TRUE;\nT_{n} := 0;\n");
            out.push((format!("{n}_P1"), "P1", p1));
            out.push((
                format!("{n}_N"),
                "N",
                format!("X_{n} := TRUE;\nT_{n} := TIME_TO_DINT({n}.T);\n"),
            ));
            let mut p0 = self.p0_code(s, &format!("TIME_TO_DINT({n}.T)"), "");
            let _ = writeln!(p0, "X_{n} := FALSE;");
            out.push((format!("{n}_P0"), "P0", p0));
        }
        out
    }

    fn write_sfc1(&self, o: &mut String) {
        o.push_str("      <pou name=\"SFC1\" pouType=\"program\">\n        <interface>\n          <externalVars>\n");
        for (n, ty, _) in self.globals() {
            if n != "Alarm" && n != "Repair" && n != "EqTolMs" {
                let _ = writeln!(
                    o,
                    "            <variable name=\"{n}\"><type><{ty}/></type></variable>"
                );
            }
        }
        o.push_str("          </externalVars>\n        </interface>\n        <actions>\n");
        for (name, _, body) in self.sfc1_actions() {
            let _ = writeln!(
                o,
                "          <action name=\"{name}\"><body><ST><xhtml:p><![CDATA[{body}]]></xhtml:p></ST></body></action>"
            );
        }
        o.push_str("        </actions>\n        <body>\n          <SFC>\n");
        // Transitions: the restart of each step (first: priority), then the edges.
        let mut trans: Vec<(String, usize, usize, String)> = Vec::new();
        for (s, _) in self.steps.iter().enumerate() {
            trans.push((format!("R_{}", self.steps[s].name), s, 0, "Restart".into()));
            for t in self.transitions.iter().filter(|t| t.from == s) {
                trans.push((
                    t.name.clone(),
                    t.from,
                    t.to,
                    format!("{} AND NOT Freeze AND NOT Restart", self.events[t.event].1),
                ));
            }
        }
        let actions: Vec<(String, &'static str)> = self
            .sfc1_actions()
            .into_iter()
            .map(|(n, q, _)| (n, q))
            .collect();
        let steps: Vec<GraphStep> = self
            .steps
            .iter()
            .map(|s| {
                let mine = actions
                    .iter()
                    .filter(|(n, _)| n.rsplit_once('_').is_some_and(|(p, _)| p == s.name))
                    .cloned()
                    .collect();
                (s.name.clone(), s.initial, mine)
            })
            .collect();
        write_graph(o, &steps, &trans, |t| {
            self.transitions
                .iter()
                .find(|x| x.name == t)
                .map(|x| self.edge_text(x))
                .unwrap_or_else(|| format!("{t}: restart"))
        });
        o.push_str("          </SFC>\n        </body>\n");
        let _ = writeln!(
            o,
            "        <documentation><xhtml:p>{}</xhtml:p></documentation>",
            esc(&self
                .steps
                .iter()
                .enumerate()
                .map(|(s, st)| format!(
                    "{}: {} E* = {}",
                    st.name,
                    self.locations[st.location],
                    self.region_text(s)
                ))
                .collect::<Vec<_>>()
                .join("; "))
        );
        o.push_str("      </pou>\n");
    }

    /// SFC2's action bodies: `(name, qualifier, body)`.
    pub fn sfc2_actions(&self) -> Vec<(String, &'static str, String)> {
        vec![
            (
                "ACCEPTABLE_P1".into(),
                "P1",
                "Freeze := FALSE;\nRestart := TRUE;\n".into(),
            ),
            (
                "ACCEPTABLE_N".into(),
                "N",
                "IF Repair THEN\n    Restart := TRUE;\nEND_IF;\n".into(),
            ),
            ("FAULT_P1".into(), "P1", "Freeze := TRUE;\n".into()),
        ]
    }

    /// SFC2's transition conditions: `(name, condition)`.
    pub fn sfc2_conditions(&self) -> Vec<(String, String)> {
        vec![
            (
                "T21".into(),
                format!("NOT Restart AND (\n    {}\n)", self.fault_condition()),
            ),
            ("T22".into(), "Repair".into()),
        ]
    }

    fn write_sfc2(&self, o: &mut String) {
        o.push_str("      <pou name=\"SFC2\" pouType=\"program\">\n        <interface>\n          <externalVars>\n");
        for (n, ty, _) in self.globals() {
            let _ = writeln!(
                o,
                "            <variable name=\"{n}\"><type><{ty}/></type></variable>"
            );
        }
        o.push_str("          </externalVars>\n        </interface>\n        <actions>\n");
        for (name, _, body) in self.sfc2_actions() {
            let _ = writeln!(
                o,
                "          <action name=\"{name}\"><body><ST><xhtml:p><![CDATA[{body}]]></xhtml:p></ST></body></action>"
            );
        }
        o.push_str("        </actions>\n        <body>\n          <SFC>\n");
        let c = self.sfc2_conditions();
        let trans = vec![
            ("T21".to_string(), 0, 1, c[0].1.clone()),
            ("T22".to_string(), 1, 0, c[1].1.clone()),
        ];
        let steps = vec![
            (
                "ACCEPTABLE".to_string(),
                true,
                vec![
                    ("ACCEPTABLE_P1".to_string(), "P1"),
                    ("ACCEPTABLE_N".to_string(), "N"),
                ],
            ),
            (
                "FAULT".to_string(),
                false,
                vec![("FAULT_P1".to_string(), "P1"), ("Alarm".to_string(), "N")],
            ),
        ];
        write_graph(o, &steps, &trans, |t| {
            if t == "T21" {
                "T21: the clocks left E* of SFC1's step (or a forbidden event)".into()
            } else {
                "T22: the repair m".into()
            }
        });
        o.push_str("          </SFC>\n        </body>\n      </pou>\n");
    }
}

/// An action block of step `step` (its position written by the caller before).
fn action_block(o: &mut String, id: u64, step: u64, actions: &[(String, &'static str)]) {
    let _ = writeln!(
        o,
        "            <actionBlock localId=\"{id}\" height=\"30\" width=\"100\">"
    );
    let _ = writeln!(
        o,
        "              <connectionPointIn><connection refLocalId=\"{step}\"/></connectionPointIn>"
    );
    for (a, q) in actions {
        let _ = writeln!(
            o,
            "              <action localId=\"0\" qualifier=\"{q}\"><reference name=\"{a}\"/></action>"
        );
    }
    o.push_str("            </actionBlock>\n");
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Text safe inside an ST comment.
fn comment(s: &str) -> String {
    s.replace("(*", "( *").replace("*)", "* )")
}

/// A step of [`write_graph`]: `(name, initial, actions (name, qualifier))`.
type GraphStep = (String, bool, Vec<(String, &'static str)>);

/// Steps `(name, initial, actions (name, qualifier))` and transitions `(name, from,
/// to, inline ST condition)` as a PLCopen SFC body: divergences and convergences where
/// a step has several transitions out or in.
fn write_graph(
    o: &mut String,
    steps: &[GraphStep],
    trans: &[(String, usize, usize, String)],
    doc: impl Fn(&str) -> String,
) {
    let mut next = 1u64;
    let mut id = || {
        let i = next;
        next += 1;
        i
    };
    let step_id: Vec<u64> = steps.iter().map(|_| id()).collect();
    let trans_id: Vec<u64> = trans.iter().map(|_| id()).collect();
    let outs = |s: usize| trans.iter().filter(|t| t.1 == s).count();
    let ins = |s: usize| -> Vec<usize> { (0..trans.len()).filter(|&i| trans[i].2 == s).collect() };
    let div: Vec<Option<u64>> = (0..steps.len())
        .map(|s| (outs(s) > 1).then(&mut id))
        .collect();
    let conv: Vec<Option<u64>> = (0..steps.len())
        .map(|s| (ins(s).len() > 1).then(&mut id))
        .collect();
    let mut y = 0u64;
    let mut pos = |o: &mut String, x: u64| {
        y += 60;
        let _ = writeln!(o, "              <position x=\"{x}\" y=\"{y}\"/>");
    };
    let conn = |o: &mut String, refs: &[u64]| {
        o.push_str("              <connectionPointIn>");
        for r in refs {
            let _ = write!(o, "<connection refLocalId=\"{r}\"/>");
        }
        o.push_str("</connectionPointIn>\n");
    };
    for (s, (name, initial, actions)) in steps.iter().enumerate() {
        let _ = writeln!(
            o,
            "            <step localId=\"{}\" name=\"{name}\" initialStep=\"{initial}\" height=\"30\" width=\"60\">",
            step_id[s]
        );
        pos(o, 40);
        let into: Vec<u64> = match conv[s] {
            Some(c) => vec![c],
            None => ins(s).into_iter().map(|i| trans_id[i]).collect(),
        };
        if !into.is_empty() {
            conn(o, &into);
        }
        o.push_str("              <connectionPointOut formalParameter=\"\"/>\n");
        if !actions.is_empty() {
            o.push_str("              <connectionPointOutAction formalParameter=\"\"/>\n");
        }
        o.push_str("            </step>\n");
        if let Some(c) = conv[s] {
            let _ = writeln!(
                o,
                "            <selectionConvergence localId=\"{c}\" height=\"1\" width=\"60\">"
            );
            pos(o, 40);
            for i in ins(s) {
                conn(o, &[trans_id[i]]);
            }
            o.push_str(
                "              <connectionPointOut/>\n            </selectionConvergence>\n",
            );
        }
        if let Some(d) = div[s] {
            let _ = writeln!(
                o,
                "            <selectionDivergence localId=\"{d}\" height=\"1\" width=\"60\">"
            );
            pos(o, 40);
            conn(o, &[step_id[s]]);
            for _ in 0..outs(s) {
                o.push_str("              <connectionPointOut formalParameter=\"\"/>\n");
            }
            o.push_str("            </selectionDivergence>\n");
        }
        if !actions.is_empty() {
            let block = id();
            pos(o, 140);
            action_block(o, block, step_id[s], actions);
        }
        for (k, (_, _, _, cond)) in trans.iter().enumerate().filter(|(_, t)| t.1 == s) {
            let _ = writeln!(
                o,
                "            <transition localId=\"{}\" height=\"2\" width=\"20\">",
                trans_id[k]
            );
            pos(o, 40);
            conn(o, &[div[s].unwrap_or(step_id[s])]);
            o.push_str("              <connectionPointOut/>\n");
            let _ = writeln!(
                o,
                "              <condition><inline name=\"{}\"><ST><xhtml:p><![CDATA[{cond}]]></xhtml:p></ST></inline></condition>",
                trans[k].0
            );
            let _ = writeln!(
                o,
                "              <documentation><xhtml:p>{}</xhtml:p></documentation>",
                esc(&doc(&trans[k].0))
            );
            o.push_str("            </transition>\n");
        }
    }
}

/// The automata of `input` (a `*.swa.ron`, a stopwatch Petri net `*.swpn.ron`, or a
/// plant's `tasks.ron`) and their
/// committed regions (`X.regions.ron`, `regions.ron` beside it), checked against them
/// as `vigie synthesize --check` does (V1503 when they were synthesised from other
/// automata): `(product, regions, the regions file)`.
pub fn load_monitor(input: &Path) -> Result<(Swa, Vec<Region>, std::path::PathBuf), Vec<Problem>> {
    let name = input.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let (file, text, regions_path) = if let Some(stem) = name.strip_suffix(".swpn.ron") {
        let (net, text) = super::swpn::SwpnFile::load(input)?;
        (
            net.translate(input, &text)?.automaton,
            String::new(),
            input.with_file_name(format!("{stem}.regions.ron")),
        )
    } else if let Some(stem) = name.strip_suffix(".swa.ron") {
        let text = crate::diag::read_text(input).map_err(|p| vec![p])?;
        let file: super::SwaFile =
            ron::from_str(&text).map_err(|e| vec![crate::diag::ron_problem(input, &e)])?;
        (
            file,
            text,
            input.with_file_name(format!("{stem}.regions.ron")),
        )
    } else {
        let set = crate::tasks::TaskSet::load(input)?;
        (
            super::from_tasks::automata(&set),
            String::new(),
            input.with_file_name(super::regions::TASK_REGIONS_FILE),
        )
    };
    let swa = file.compile(input, &text).map_err(|p| vec![p])?;
    if std::fs::symlink_metadata(&regions_path).is_err() {
        return Err(vec![Problem::error(
            codes::REGIONS_STALE.id,
            format!(
                "no regions file {}; run `vigie synthesize {}` first",
                regions_path.display(),
                input.display()
            ),
            Some(At::new(input, 1, 1)),
        )]);
    }
    let regions =
        super::regions::RegionsFile::load(&regions_path, &file, &swa).map_err(|p| vec![p])?;
    Ok((swa, regions, regions_path))
}

/// What a PLCopen file holds, read back with the XML parser: per POU its steps, its
/// transitions' inline conditions and its actions' ST bodies.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Outline {
    /// `(POU, its SFC)`, in file order.
    pub pous: Vec<(String, PouOutline)>,
}

/// One POU of an [`Outline`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PouOutline {
    /// Step names, the initial ones marked.
    pub steps: Vec<(String, bool)>,
    /// `(transition, inline ST condition)`.
    pub conditions: Vec<(String, String)>,
    /// `(action, ST body)`.
    pub actions: Vec<(String, String)>,
    /// `(step, qualifier, action)` of the action blocks.
    pub blocks: Vec<(String, String, String)>,
}

/// Reads a PLCopen file's SFC POUs ([`Outline`]); an error when it is not well formed.
pub fn outline(xml: &str) -> Result<Outline, String> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| e.to_string())?;
    let text_of = |n: roxmltree::Node<'_, '_>| -> String {
        n.descendants()
            .filter(|d| d.is_text())
            .filter_map(|d| d.text())
            .collect::<String>()
    };
    let mut out = Outline::default();
    for pou in doc.descendants().filter(|n| n.has_tag_name("pou")) {
        let name = pou.attribute("name").unwrap_or("").to_string();
        let mut p = PouOutline::default();
        let mut step_by_id = BTreeMap::new();
        for n in pou.descendants() {
            match n.tag_name().name() {
                "step" => {
                    let s = n.attribute("name").unwrap_or("").to_string();
                    step_by_id.insert(n.attribute("localId").unwrap_or("").to_string(), s.clone());
                    p.steps
                        .push((s, n.attribute("initialStep") == Some("true")));
                }
                "inline" => {
                    p.conditions
                        .push((n.attribute("name").unwrap_or("").to_string(), text_of(n)));
                }
                "action" if n.attribute("name").is_some() => {
                    p.actions
                        .push((n.attribute("name").unwrap_or("").to_string(), text_of(n)));
                }
                _ => {}
            }
        }
        for b in pou.descendants().filter(|n| n.has_tag_name("actionBlock")) {
            let step = b
                .descendants()
                .find(|n| n.has_tag_name("connection"))
                .and_then(|c| c.attribute("refLocalId"))
                .and_then(|r| step_by_id.get(r))
                .cloned()
                .unwrap_or_default();
            for a in b.children().filter(|n| n.has_tag_name("action")) {
                let r = a
                    .children()
                    .find(|n| n.has_tag_name("reference"))
                    .and_then(|r| r.attribute("name"))
                    .unwrap_or("");
                p.blocks.push((
                    step.clone(),
                    a.attribute("qualifier").unwrap_or("").to_string(),
                    r.to_string(),
                ));
            }
        }
        out.pous.push((name, p));
    }
    Ok(out)
}

/// Every ST body of an [`Outline`] as one Structured Text unit (a function block
/// `FB_SfcBodies` and one `ACTION` per action body and per transition condition,
/// `Cond := …;`), for a parser of plain ST: the step variables `S.T` read as members.
pub fn bodies_as_st(o: &Outline) -> String {
    let mut t = String::from(
        "FUNCTION_BLOCK FB_SfcBodies\nVAR\n    Cond : BOOL;\nEND_VAR\nEND_FUNCTION_BLOCK\n",
    );
    for (pou, p) in &o.pous {
        for (a, body) in &p.actions {
            let _ = writeln!(t, "ACTION {pou}_{a}:\n{body}END_ACTION");
        }
        for (c, cond) in &p.conditions {
            let _ = writeln!(t, "ACTION {pou}_COND_{c}:\nCond := {cond};\nEND_ACTION");
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::swa::SwaFile;
    use crate::swa::regions::RegionsFile;

    fn workshop() -> (Swa, Vec<Region>) {
        let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../layouts/workshop"));
        let text = std::fs::read_to_string(dir.join("workshop.swa.ron")).unwrap();
        let file: SwaFile = ron::from_str(&text).unwrap();
        let swa = file.compile(&dir.join("workshop.swa.ron"), &text).unwrap();
        let regions = RegionsFile::load(&dir.join("workshop.regions.ron"), &file, &swa).unwrap();
        (swa, regions)
    }

    #[test]
    fn identifiers_are_iec_and_unique_without_case() {
        let ids = identifiers(
            "EV",
            &["R".into(), "r".into(), "P . /P*".into(), "RE(b)".into()],
        );
        assert_eq!(ids, ["EV_R", "EV_r_2", "EV_P_P", "EV_RE_b"]);
    }

    #[test]
    fn workshop_has_a_step_per_location_and_an_offset_per_clock() {
        let (swa, regions) = workshop();
        let c = translate(&swa, &regions).unwrap();
        assert_eq!(c.steps.len(), 12);
        assert_eq!(c.offsets.len(), 5);
        assert!(c.duplicated.is_empty());
        assert!(c.steps[0].initial && c.steps[0].name == "S0");
        // The start zeroes every clock; its P1 resets what every edge entering it resets.
        assert_eq!(c.transitions.len(), swa.edges.len());
    }

    /// An exact bound keeps its fraction: `x <= 2500/3` is `3 * x <= 2500`, and an
    /// equality gets the tolerance of its coefficients.
    #[test]
    fn rational_bounds_are_scaled_not_rounded() {
        let file: SwaFile = ron::from_str(
            r#"(components: [(name: "a", clocks: ["x", "y"], initial: "i", progress: ["r"],
               locations: [(name: "i"), (name: "r", running: ["x", "y"], invariant: "3*x <= 2500")],
               edges: [(from: "i", to: "r", event: "go", reset: ["x", "y"])])])"#,
        )
        .unwrap();
        let swa = file.compile(Path::new("t.swa.ron"), "").unwrap();
        let s = crate::swa::synthesize(&swa, crate::swa::Limits::default()).unwrap();
        let c = translate(&swa, &s.monitor_regions(&swa)).unwrap();
        let v = c.violation(1).unwrap();
        assert!(v.contains("(3 * (D_a_x + T_S1) > 2500)"), "{v}");
        assert!(
            v.contains("(D_a_x + T_S1) - (D_a_y + T_S1) > 0 + 2 * EqTolMs"),
            "{v}"
        );
    }

    #[test]
    fn the_xml_reads_back() {
        let (swa, regions) = workshop();
        let c = translate(&swa, &regions).unwrap();
        let o = outline(&c.plcopen("workshop")).unwrap();
        assert_eq!(o.pous.len(), 2);
        assert_eq!(o.pous[0].1.steps.len(), 12);
        assert_eq!(o.pous[0].1.conditions.len(), c.transitions.len() + 12);
        assert_eq!(o.pous[1].1.steps.len(), 2);
        let st = crate::export::interp::parse(&c.function_block());
        assert!(st.is_ok(), "{st:?}");
    }
}
