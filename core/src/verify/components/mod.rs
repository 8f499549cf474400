//! Verification of a plant of components (`components.ron`), one sub-plant at a time
//! (seed 004 §2 and §6.2: the expert checks each dangerous state on the part of the
//! plant it involves, so that a multi-station line is verified in parts).
//!
//! # The abstraction
//! - **Sub-plant**: one component with a position (an axis, a tank) and its hazards:
//!   an end stop that crashes, drives opposed, a tank overflowing or run dry, and the
//!   declared dangers on it (`dangers` of `components.ron`). For a conveyor: the belt
//!   with its items (`belt.rs`: a collision at its feeder, an item fallen off its end,
//!   drives opposed) together with the axes and tanks whose sensors its feeder, its
//!   taker or its drives read (the pusher whose extended sensor places an item, the
//!   gantry whose gripper opening does), so that the constraint on the pusher's
//!   order is checked against the beam on the belt.
//! - **Position** (`line.rs`): the travel cut at every point where something changes
//!   (its ends, its sensors' window edges, its dangers' zone edges) into zones: the
//!   points themselves and the open intervals between them. Every sensor and danger is
//!   constant on a zone. Each PLC cycle the component stays in its zone or moves in
//!   the direction of its speed to any zone it can reach in one cycle at its fastest
//!   drive (with `variation_ppm`); it cannot stay on a point while it moves. Time in a
//!   zone is not bounded below: a slow move is included.
//! - **Its surroundings**: every input the relevant constraints, observers, drives or
//!   dangers read that the sub-plant does not write takes any value at every cycle
//!   (another station's sensor, a button); inputs nothing relevant reads read 0.
//! - **Control**: the most permissive: any vector of the outputs its drives, its
//!   dangers and its relevant constraints name, every cycle; the others are 0.
//! - **PLC**: one cycle per step in the engine's order: inputs, observers (the real
//!   [`Observers`](crate::observers::Observers)), the commanded vector, the real
//!   [`Filter`] of the relevant constraints (those naming one of its signals or an
//!   observer that does), then the sub-plant's step with the applied vector. The latch
//!   is abstracted away (the operator may reset at any cycle).
//!
//! The search (`search.rs`) is breadth first, so a hazard's trace is a shortest one. It
//! is run three times: with every output at its safe value (a hazard the environment
//! makes, no control prevents), without the filter (is the hazard real: can a control
//! error reach it?) and with it (does the constraint set prevent it whatever the
//! control?). Detectors and links are not modelled here: the report says so.

mod belt;
mod line;
mod search;

use crate::bundle::PlantBundle;
use crate::constraints::ConstraintSet;
use crate::diag::{Problem, codes};
use crate::expr::{Dnf, parse_str, simplify};
use crate::filter::Filter;
use crate::machine::description::Components;
use crate::machine::kinds::KindDef;
use crate::symbols::Space;
use belt::Belt;
use search::{Parts, Sub};
use serde::Serialize;
use std::collections::BTreeSet;

/// Millionths of the unit per unit.
const MICRO: f64 = 1e6;
/// A sub-plant's search stops after this many transitions and says so (about 3 s):
/// `vigie verify --max-transitions` sets another limit.
pub const MAX_TRANSITIONS: u64 = 2_000_000;
/// The PLC cycle of the model, ms.
const CYCLE_MS: i64 = 10;
/// Above this many free inputs and outputs together a sub-plant is not explored (2^n
/// vectors a cycle): the report says so.
const MAX_FREE: usize = 14;

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
    /// An item placed onto another at a conveyor's entry.
    Collision,
    /// An item fallen off a conveyor's end.
    Dropped,
}

impl std::fmt::Display for SubHazard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::EndStop(end) => write!(f, "end stop at {end}"),
            Self::OpposedDrives => write!(f, "drives opposed"),
            Self::Overflow => write!(f, "overflow"),
            Self::DryRun => write!(f, "dry run"),
            Self::Declared(id) => write!(f, "danger `{id}`"),
            Self::Collision => write!(f, "collision at the entry"),
            Self::Dropped => write!(f, "item fallen off the end"),
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
    /// The components verified with it: the axes and tanks whose sensors a conveyor's
    /// feeder, taker or drives read.
    pub with: Vec<String>,
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
    /// The search with the filter stopped at its limit of states or transitions: a
    /// hazard it did not find may still be reachable.
    pub truncated: bool,
    /// Hazards reachable without the filter (each with a shortest trace).
    pub without_filter: Vec<Reached>,
    /// The search without the filter stopped at its limit: a hazard it did not find
    /// may still be reachable.
    pub without_filter_truncated: bool,
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
    /// Components of kinds the model does not cover (detectors, links).
    pub not_modelled: Vec<String>,
    /// The abstraction's assumptions, stated in every report.
    pub assumptions: Vec<String>,
}

impl SubReport {
    /// The hazards reachable with the filter that a constraint could prevent: those the
    /// environment makes alone (`uncontrollable`) aside.
    pub fn violated(&self) -> impl Iterator<Item = &Reached> {
        self.with_filter
            .iter()
            .filter(|r| !self.uncontrollable.contains(&r.hazard))
    }

    /// Not verified, or not to the end (the search stopped at its limit).
    pub fn unproved(&self) -> bool {
        self.skipped.is_some() || self.truncated
    }
}

impl ComponentsReport {
    /// Every hazard reachable with the filter: the constraint set does not protect.
    pub fn unsafe_parts(&self) -> Vec<(&str, &Reached)> {
        self.parts
            .iter()
            .flat_map(|p| p.violated().map(move |r| (p.component.as_str(), r)))
            .collect()
    }

    /// Some sub-plant was not verified, or not to the end.
    pub fn unproved(&self) -> bool {
        self.parts.iter().any(SubReport::unproved)
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

/// What a sub-plant's search reads and chooses.
struct Scope {
    /// The constraints that guard it.
    set: ConstraintSet,
    free_in: Vec<usize>,
    aux: Vec<usize>,
    free_out: Vec<usize>,
    /// The variables read at t-1.
    prev: BTreeSet<(Space, u32)>,
    /// Every variable something of the sub-plant reads.
    named: BTreeSet<(Space, u32)>,
    /// Which free outputs only the constraints read, and only as `o` at t.
    dominated: Vec<bool>,
    /// The free inputs only the constraints read, in one sense at t, with the value
    /// that violates less (taken out of `free_in`).
    fixed_in: Vec<(usize, bool)>,
}

/// The one sense in which the constraints read a variable: `Some(true)` as `v` only,
/// `Some(false)` as `/v` only, at t; `None` when both, at t-1, or never.
fn sense(set: &ConstraintSet, space: Space, i: u32) -> Option<bool> {
    let mut sense: Option<bool> = None;
    for l in set.constraints.iter().flat_map(|k| &k.dnf).flatten() {
        if l.var.space == space && l.var.index == i {
            if l.var.prev || sense.is_some_and(|s| s != l.positive) {
                return None;
            }
            sense = Some(l.positive);
        }
    }
    sense
}

/// What the search may hold instead of choosing, among the variables nothing but the
/// constraints reads (`effect`: what the components and observers read, and every
/// value read at t-1): the free outputs read as `o` only (0 does all 1 does but
/// violate), and the free inputs read in one sense only, taken out of `free_in` with
/// the value that violates less.
fn held(
    set: &ConstraintSet,
    effect: &BTreeSet<(Space, u32)>,
    free_out: &[usize],
    free_in: &mut Vec<usize>,
) -> (Vec<bool>, Vec<(usize, bool)>) {
    let dominated = free_out
        .iter()
        .map(|&o| {
            let o = o as u32;
            !effect.contains(&(Space::Output, o)) && sense(set, Space::Output, o) == Some(true)
        })
        .collect();
    let mut fixed_in = Vec::new();
    free_in.retain(|&i| match sense(set, Space::Input, i as u32) {
        Some(positive) if !effect.contains(&(Space::Input, i as u32)) => {
            fixed_in.push((i, !positive));
            false
        }
        _ => true,
    });
    (dominated, fixed_in)
}

/// A sub-plant's scope: its own signals; the observers and constraints that read them
/// (an observer's readers too); the other inputs they read, free; the outputs they and
/// the components' drives, dangers, feeder and taker name, chosen by the control.
fn scope(parts: &Parts, bundle: &PlantBundle) -> Result<Scope, Problem> {
    // Its own signals; the constraints and observers that read them.
    let mut own: BTreeSet<(Space, u32)> = BTreeSet::new();
    let mut named: BTreeSet<(Space, u32)> = BTreeSet::new();
    let mut prev: BTreeSet<(Space, u32)> = BTreeSet::new();
    let mut dnfs: Vec<&Dnf> = Vec::new();
    for (_, l) in &parts.lines {
        own.extend(l.windows.iter().map(|w| (Space::Input, w.0 as u32)));
        own.extend(l.moving.map(|i| (Space::Input, i as u32)));
        for m in &l.movers {
            own.extend(m.sensor.map(|i| (Space::Input, i as u32)));
            dnfs.push(&m.dnf);
        }
        dnfs.extend(l.dangers.iter().map(|d| &d.3));
    }
    if let Some((_, b)) = &parts.belt {
        own.extend(b.beams.iter().map(|w| (Space::Input, w.0 as u32)));
        own.extend(b.motion.map(|i| (Space::Input, i as u32)));
        dnfs.extend(b.movers.iter().map(|m| &m.dnf));
        dnfs.extend(b.feed.as_ref().map(|f| &f.dnf));
        dnfs.extend(b.feed.as_ref().and_then(|f| f.load.as_ref()));
        dnfs.extend(b.take.as_ref());
    }
    for d in dnfs {
        reads(d, &mut named);
        reads_prev(d, &mut prev);
    }
    own.extend(named.iter().filter(|v| v.0 == Space::Output).copied());
    // What the components and the observers read (and, below, every value read at
    // t-1): a variable read there has an effect.
    let mut effect = named.clone();
    let mut relevant_obs: BTreeSet<u32> = BTreeSet::new();
    for (k, o) in bundle.observers.defs.iter().enumerate() {
        let (mut r, mut p) = (BTreeSet::new(), BTreeSet::new());
        for t in o.rule.expressions() {
            let d = compile(t, bundle)?;
            reads(&d, &mut r);
            reads_prev(&d, &mut p);
        }
        effect.extend(r.iter().copied());
        effect.extend(p.iter().copied());
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
    effect.extend(prev.iter().copied());
    let (dominated, fixed_in) = held(&set, &effect, &free_out, &mut free_in);
    Ok(Scope {
        set,
        free_in,
        aux,
        free_out,
        prev,
        named,
        dominated,
        fixed_in,
    })
}

/// The sub-plant of component `c` and the hazards checked on it, or `None` for a kind
/// the model does not cover.
fn sub_plant(
    c: &crate::machine::description::ComponentDef,
    desc: &Components,
    bundle: &PlantBundle,
) -> Result<Option<(Parts, Vec<SubHazard>)>, Problem> {
    if let KindDef::Conveyor(def) = &c.kind {
        let b = Belt::build(&c.id, def, desc, bundle)?;
        let hazards = b.hazards();
        // The axes and tanks whose sensors its feeder, taker or drives read.
        let mut read = BTreeSet::new();
        let feed = b.feed.as_ref();
        let load = feed.and_then(|f| f.load.as_ref());
        let dnfs = b.movers.iter().map(|m| &m.dnf);
        for d in dnfs
            .chain(feed.map(|f| &f.dnf))
            .chain(b.take.as_ref())
            .chain(load)
        {
            reads(d, &mut read);
        }
        let mut lines = Vec::new();
        for other in &desc.components {
            if let Some(l) = line::line(&other.id, &other.kind, desc, bundle)? {
                let mut sensors = l.windows.iter().map(|w| w.0).chain(l.moving);
                if sensors.any(|i| read.contains(&(Space::Input, i as u32))) {
                    lines.push((other.id.clone(), l));
                }
            }
        }
        let parts = Parts {
            lines,
            belt: Some((c.id.clone(), b)),
        };
        return Ok(Some((parts, hazards)));
    }
    Ok(line::line(&c.id, &c.kind, desc, bundle)?.map(|l| {
        let hazards = l.hazards();
        let parts = Parts {
            lines: vec![(c.id.clone(), l)],
            belt: None,
        };
        (parts, hazards)
    }))
}

/// One sub-plant verified: its scope, then the three searches (safe values only,
/// without the filter, with it).
fn verify_part(
    c: &crate::machine::description::ComponentDef,
    mut sub_parts: Parts,
    hazards: Vec<SubHazard>,
    bundle: &PlantBundle,
    (sizes, limit): ([usize; 4], u64),
) -> Result<SubReport, Problem> {
    let Scope {
        set,
        free_in,
        aux,
        free_out,
        prev,
        named,
        dominated,
        fixed_in,
    } = scope(&sub_parts, bundle)?;
    let mut beams = 0;
    if let Some((_, b)) = &mut sub_parts.belt {
        b.read = b
            .beams
            .iter()
            .map(|w| named.contains(&(Space::Input, w.0 as u32)))
            .collect();
        beams = b.read.iter().filter(|r| **r).count();
    }
    let fixed: Vec<usize> = fixed_in.iter().map(|f| f.0).collect();
    let name = |s: Space, v: &[usize]| -> Vec<String> {
        v.iter()
            .map(|&k| bundle.symbols.name(s, k as u32).to_string())
            .collect()
    };
    let mut report = SubReport {
        component: c.id.clone(),
        with: sub_parts
            .lines
            .iter()
            .map(|(id, _)| id.clone())
            .filter(|id| id != &c.id)
            .collect(),
        hazards: hazards.clone(),
        free_inputs: name(Space::Input, &free_in)
            .into_iter()
            .chain(name(Space::Input, &fixed))
            .chain(name(Space::Aux, &aux))
            .collect(),
        free_outputs: name(Space::Output, &free_out),
        constraints: set.constraints.iter().map(|k| k.id.clone()).collect(),
        skipped: None,
        states: 0,
        transitions: 0,
        truncated: false,
        without_filter: Vec::new(),
        without_filter_truncated: false,
        with_filter: Vec::new(),
        uncontrollable: Vec::new(),
    };
    let chosen = dominated.iter().filter(|d| !**d).count();
    if free_in.len() + aux.len() + chosen + beams > MAX_FREE {
        report.skipped = Some(format!(
            "{} free inputs, {chosen} outputs that act and {beams} beams an item ahead may cover: more than {MAX_FREE} together (2^n vectors a cycle)",
            free_in.len() + aux.len(),
        ));
        return Ok(report);
    }
    let mut sub = Sub {
        bundle,
        parts: sub_parts,
        free_in,
        aux,
        free_out,
        dominated,
        terms: set.constraints.iter().flat_map(|k| k.dnf.clone()).collect(),
        fixed_in,
        filter: None,
        prev: prev.iter().map(|&(sp, k)| (sp, k as usize)).collect(),
        safe_only: true,
        sizes,
        limit,
    };
    let only = |found: Vec<Reached>| -> Vec<Reached> {
        found
            .into_iter()
            .filter(|r| hazards.contains(&r.hazard))
            .collect()
    };
    report.uncontrollable = only(sub.explore().0)
        .into_iter()
        .map(|r| r.hazard)
        .collect();
    sub.safe_only = false;
    let (found, _, _, truncated) = sub.explore();
    report.without_filter = only(found);
    report.without_filter_truncated = truncated;
    sub.filter = Some(Filter::for_plant(&set, &bundle.plant));
    let (found, states, transitions, truncated) = sub.explore();
    report.with_filter = only(found);
    report.states = states;
    report.transitions = transitions;
    report.truncated = truncated;
    Ok(report)
}

/// Verifies every sub-plant of a plant of components, each search stopped after
/// [`MAX_TRANSITIONS`].
pub fn verify_components(
    bundle: &PlantBundle,
    desc: &Components,
) -> Result<ComponentsReport, Problem> {
    verify_components_within(bundle, desc, MAX_TRANSITIONS)
}

/// Verifies every sub-plant of a plant of components, each search stopped after
/// `limit` transitions (the sub-plant is then reported as truncated).
pub fn verify_components_within(
    bundle: &PlantBundle,
    desc: &Components,
    limit: u64,
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
        let Some((sub_parts, hazards)) = sub_plant(c, desc, bundle)? else {
            if !matches!(c.kind, KindDef::Button(_)) {
                not_modelled.push(c.id.clone());
            }
            continue;
        };
        if hazards.is_empty() {
            continue;
        }
        parts.push(verify_part(c, sub_parts, hazards, bundle, (sizes, limit))?);
    }
    Ok(ComponentsReport {
        plant: desc.name.clone(),
        parts,
        not_modelled,
        assumptions: vec![
            "one component at a time, with every input it does not write that its constraints, observers, drives or dangers read free at every cycle".into(),
            "the control commands any vector of the outputs its drives, dangers and constraints name, every cycle; the other outputs are 0".into(),
            "a component moves at most as far as its fastest drive goes in one 10 ms cycle, and may move as slowly as it likes".into(),
            "on a conveyor the item nearest the entry is followed; the others ahead of it may cover any beam past it, and hold it anywhere".into(),
            "an item across a joint is not pushed against a stopped next surface (PushedAgainstStopped between conveyors is not searched; turntables are not modelled)".into(),
            "no fault: the plant's components, sensors and contactors are healthy".into(),
            "the operator may reset the filter at any cycle (the latch is abstracted away)".into(),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Outputs `o`, `p`, `q` and inputs `i`, `j`, `k`, `m`.
    fn set(text: &str) -> ConstraintSet {
        let mut s = crate::symbols::Symbols::new();
        for n in ["o", "p", "q"] {
            s.declare(n, Space::Output).unwrap();
        }
        for n in ["i", "j", "k", "m"] {
            s.declare(n, Space::Input).unwrap();
        }
        let (set, problems) = ConstraintSet::parse(text, std::path::Path::new("t"), &s);
        assert!(problems.is_empty(), "{problems:?}");
        set
    }

    #[test]
    fn only_variables_the_constraints_alone_read_in_one_sense_are_held() {
        let set = set("C1 = o . /i . j\nC2 = p . /i\nC3 = q . RE(k)\nC4 = o . m\nC5 = p . /m\n");
        assert_eq!(sense(&set, Space::Output, 0), Some(true));
        // /i in both: held at 1; j read as j: held at 0; k at t-1 and m both ways: free.
        assert_eq!(sense(&set, Space::Input, 0), Some(false));
        assert_eq!(sense(&set, Space::Input, 1), Some(true));
        assert_eq!(sense(&set, Space::Input, 2), None);
        assert_eq!(sense(&set, Space::Input, 3), None);
        let mut free_in = vec![0, 1, 2, 3];
        let none = BTreeSet::new();
        let (dominated, fixed) = held(&set, &none, &[0, 1, 2], &mut free_in);
        assert_eq!(dominated, [true, true, true]);
        assert_eq!(fixed, [(0, true), (1, false)]);
        assert_eq!(free_in, [2, 3]);
        // What a drive or an observer reads has an effect: it is chosen, not held.
        let effect = BTreeSet::from([(Space::Output, 1), (Space::Input, 0)]);
        let mut free_in = vec![0, 1, 2, 3];
        let (dominated, fixed) = held(&set, &effect, &[0, 1, 2], &mut free_in);
        assert_eq!(dominated, [true, false, true]);
        assert_eq!(fixed, [(1, false)]);
        assert_eq!(free_in, [0, 2, 3]);
    }
}
