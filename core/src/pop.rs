//! Decentralized timed diagnosis of the plant's components (seed 004, sections 3, 4 and
//! 6.3): component models (PoP) as data in `diagnosers.ron`, the local diagnosers built
//! from them (unexpected evolutions generated, those the filter forbids pruned), the
//! decisions `N` / `{N, F_j}` / `F_j` per fault partition with their `def_<partition>`
//! flags, the interval variables and sensor estimates they publish for the filter,
//! interval learning, the diagnosability report and the libFAUDES export.
//!
//! - [`model`]: the file format; [`build`]: compilation; [`runtime`]: the cycle;
//! - [`learn`]: interval learning (seed 003, annex B); [`coop`]: constraint rewriting;
//! - [`campaign`]: the fault campaign in the emulator.
//!
//! Assumptions (stated in the report too): one fault at a time per component; the
//! control part is reliable as far as the filter enforces the constraints; the plant
//! keeps cycling (time-outs alone never decide between faults and idling).

pub mod build;
pub mod campaign;
pub mod coop;
pub mod learn;
pub mod model;
pub mod runtime;
pub mod transients;

use crate::bundle::PlantBundle;
use crate::diag::Problem;
use crate::diag::codes;
use crate::plant::Plant;
use build::{Compiled, Component};
use model::DiagnoserFile;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

pub use runtime::{Certainty, Decision, Diagnosers, Diagnosis};

/// A plant folder with its diagnosers: the bundle (auxiliaries declared, constraints
/// rewritten for the cooperation) and the compiled models.
#[derive(Clone, Debug)]
pub struct DiagBundle {
    /// The plant bundle, constraints rewritten.
    pub bundle: PlantBundle,
    /// The compiled diagnosers.
    pub compiled: Compiled,
    /// The parsed file.
    pub file: DiagnoserFile,
    /// The rewritten constraint text.
    pub rewritten: String,
}

/// Loads `diagnosers.ron` of a plant folder, compiles it against the plant and its
/// constraints and rewrites the constraints for the cooperation.
pub fn load(dir: &Path) -> Result<(DiagBundle, Vec<Problem>), Vec<Problem>> {
    let plant = Plant::load(&dir.join("plant.ron"))?;
    let path = dir.join("diagnosers.ron");
    let text = crate::diag::read_text(&path).map_err(|p| vec![p])?;
    from_text(dir, plant, &text, &path)
}

/// As [`load`], with the diagnoser file given as text.
pub fn from_text(
    dir: &Path,
    plant: Plant,
    text: &str,
    path: &Path,
) -> Result<(DiagBundle, Vec<Problem>), Vec<Problem>> {
    let file = DiagnoserFile::from_ron(text, path).map_err(|p| vec![p])?;
    // The task monitors' outputs are auxiliaries too: declared first, as
    // `PlantBundle::load` does, so that both publish into the same frame.
    let (tasks, mut problems) = crate::tasks::TaskSet::load_optional(dir);
    let mut aux = tasks
        .as_ref()
        .map(crate::tasks::TaskSet::aux_names)
        .unwrap_or_default();
    aux.extend(build::aux_names(&file));
    let (mut bundle, mut more) = PlantBundle::from_plant(dir, plant, &aux);
    bundle.tasks = tasks;
    problems.append(&mut more);
    let compiled = build::compile(
        &file,
        text,
        path,
        &bundle.symbols,
        Some(&bundle.constraints),
    )?;
    let safe: Vec<_> = bundle
        .plant
        .outputs
        .iter()
        .map(|s| (!(s.held_on && s.safe == crate::plant::SafeValue::One)).then_some(s.safe))
        .collect();
    let rewritten = coop::rewrite(&bundle.constraints, &bundle.symbols, &compiled, &safe)
        .map_err(|m| vec![Problem::error(codes::DIAGNOSER_REWRITE.id, m, None)])?;
    let file_name = dir.join("constraints.txt (rewritten by the diagnosers)");
    let (set, mut p2) =
        crate::constraints::ConstraintSet::parse(&rewritten, &file_name, &bundle.symbols);
    problems.append(&mut p2);
    bundle.constraints = set;
    Ok((
        DiagBundle {
            bundle,
            compiled,
            file,
            rewritten,
        },
        problems,
    ))
}

/// The diagnosability of one fault on its component model.
#[derive(Clone, Debug, Serialize)]
pub struct FaultReport {
    /// Component.
    pub component: String,
    /// Fault label.
    pub fault: String,
    /// Its partition.
    pub partition: String,
    /// Certain diagnosis of the partition guaranteed after the fault.
    pub diagnosable: bool,
    /// Largest number of observed edges after the fault before certainty (time-outs
    /// in between not counted), when diagnosable.
    pub max_edges: Option<usize>,
    /// Why not, when not: a normal or other-partition behaviour that looks the same.
    pub witness: Option<String>,
    /// Contexts where certainty needs the controller to act: the fault and another
    /// hypothesis agree on everything but an actuator edge only the fault side allows
    /// (a controller that waits for the faulty sensor leaves the decision ambiguous).
    pub needs_controller: Vec<String>,
    /// The twin plant grew past [`MAX_TWIN_PAIRS`] pairs of states before it decided:
    /// `diagnosable` is false and unproved either way (the fault campaign measures
    /// it). Absent from the report when false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub undecided: bool,
}

/// The twin plant's size at which the report stops deciding a fault (a derived model
/// of a three-speed drill head would need hundreds of millions of pairs).
pub const MAX_TWIN_PAIRS: usize = 30_000;

/// Counts of the generated model, per component.
#[derive(Clone, Debug, Serialize)]
pub struct ComponentReport {
    /// Component.
    pub component: String,
    /// Normal states.
    pub states: usize,
    /// Diagnoser automaton states (normal and fault copies).
    pub automaton_states: usize,
    /// Unexpected evolutions generated.
    pub unexpected: usize,
    /// Of which the filter makes impossible.
    pub pruned: Vec<String>,
}

/// The diagnosability report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The assumptions under which the verdicts hold.
    pub assumptions: Vec<String>,
    /// Per component.
    pub components: Vec<ComponentReport>,
    /// Per fault.
    pub faults: Vec<FaultReport>,
}

fn is_tmo(c: &Component, s: usize) -> bool {
    c.symbols[s].edge.is_none()
}

/// Twin-plant analysis of every fault (untimed abstraction, time-outs as events).
pub fn report(compiled: &Compiled) -> Report {
    let mut faults = Vec::new();
    let mut components = Vec::new();
    for c in &compiled.components {
        components.push(ComponentReport {
            component: c.id.clone(),
            states: c.states.len(),
            automaton_states: c.g.len(),
            unexpected: c.unexpected.len(),
            pruned: c
                .unexpected
                .iter()
                .filter_map(|u| {
                    u.pruned_by
                        .as_ref()
                        .map(|k| format!("{} in {} (by {k})", u.event, u.state))
                })
                .collect(),
        });
        for (f, fname) in c.faults.iter().enumerate() {
            let Some(p) = c.partitions.iter().find(|p| p.faults.contains(&f)) else {
                continue;
            };
            let (diagnosable, max_edges, witness, needs_controller) = twin(c, f, &p.faults);
            let undecided = witness.as_deref().is_some_and(|w| w.starts_with(UNDECIDED));
            faults.push(FaultReport {
                component: c.id.clone(),
                fault: fname.clone(),
                partition: p.id.clone(),
                diagnosable,
                max_edges,
                witness,
                needs_controller,
                undecided,
            });
        }
    }
    Report {
        assumptions: vec![
            "one fault at a time per component (faults of different components are independent)".into(),
            "the control part is reliable where the filter enforces the constraints (evolutions the filter forbids are pruned)".into(),
            "the plant keeps cycling: waiting (time-outs only) never decides, an observed edge eventually comes".into(),
            "time windows are the learned intervals plus margin_ms; delays in ms are measured by `vigie campaign diagnoser`".into(),
        ],
        components,
        faults,
    }
}

fn closure_of(
    c: &Component,
    start: &[usize],
    allow_spawn: bool,
    keep: &dyn Fn(Option<usize>) -> bool,
) -> Vec<usize> {
    let mut out: Vec<usize> = start.to_vec();
    let mut i = 0;
    while i < out.len() {
        let q = out[i];
        let st = &c.g[q];
        let mut next: Vec<usize> = st.silent.clone();
        if allow_spawn {
            next.extend(st.spawn.iter().map(|&(_, t)| t));
        }
        for t in next {
            if keep(c.g[t].mode) && !out.contains(&t) {
                out.push(t);
            }
        }
        i += 1;
    }
    out
}

/// The answer of a twin plant that grew past [`MAX_TWIN_PAIRS`].
fn undecided(c: &Component) -> (bool, Option<usize>, Option<String>, Vec<String>) {
    let w = format!(
        "{UNDECIDED} {MAX_TWIN_PAIRS} pairs of states (a model of {} states): `vigie campaign diagnoser` measures it",
        c.g.len()
    );
    (false, None, Some(w), Vec::new())
}

/// How the witness of an undecided fault begins.
const UNDECIDED: &str = "not decided: the twin plant grew past";

fn twin(
    c: &Component,
    f: usize,
    part: &[usize],
) -> (bool, Option<usize>, Option<String>, Vec<String>) {
    use petgraph::graph::{DiGraph, NodeIndex};
    let other = |m: Option<usize>| m.is_none_or(|x| !part.contains(&x));
    let mine = |m: Option<usize>| m == Some(f);
    // Start pairs: for each normal state, a fault copy after the fault and any non-Π state.
    let mut g: DiGraph<(usize, usize), usize> = DiGraph::new();
    let mut idx: BTreeMap<(usize, usize), NodeIndex> = BTreeMap::new();
    let mut work = Vec::new();
    for x in 0..c.states.len() {
        let a0: Vec<usize> = c.g[x]
            .spawn
            .iter()
            .filter(|&&(ff, _)| ff == f)
            .map(|&(_, t)| t)
            .collect();
        let a = closure_of(c, &a0, false, &|m| mine(m));
        let b = closure_of(c, &[x], true, &|m| other(m));
        for &qa in &a {
            for &qb in &b {
                if let std::collections::btree_map::Entry::Vacant(e) = idx.entry((qa, qb)) {
                    e.insert(g.add_node((qa, qb)));
                    work.push((qa, qb));
                }
            }
        }
    }
    while let Some((qa, qb)) = work.pop() {
        if idx.len() > MAX_TWIN_PAIRS {
            return undecided(c);
        }
        let from = idx[&(qa, qb)];
        let ca = closure_of(c, &[qa], false, &|m| mine(m));
        let cb = closure_of(c, &[qb], true, &|m| other(m));
        for &a in &ca {
            for &(s, ta, _) in &c.g[a].obs {
                for &b in &cb {
                    for &(s2, tb, _) in &c.g[b].obs {
                        if s2 != s {
                            continue;
                        }
                        let to = *idx.entry((ta, tb)).or_insert_with(|| {
                            work.push((ta, tb));
                            g.add_node((ta, tb))
                        });
                        if g.find_edge(from, to).is_none_or(|e| g[e] != s) {
                            g.add_edge(from, to, s);
                        }
                    }
                }
            }
        }
    }
    // A cycle with an edge event in one strongly connected component: indeterminate.
    let sccs = petgraph::algo::tarjan_scc(&g);
    let mut comp_of = vec![0usize; g.node_count()];
    for (k, s) in sccs.iter().enumerate() {
        for n in s {
            comp_of[n.index()] = k;
        }
    }
    for e in g.edge_indices() {
        let (a, b) = g
            .edge_endpoints(e)
            .unwrap_or((NodeIndex::new(0), NodeIndex::new(0)));
        if comp_of[a.index()] == comp_of[b.index()] && !is_tmo(c, g[e]) {
            let (qa, qb) = g[a];
            return (
                false,
                None,
                Some(format!(
                    "`{}` and `{}` both repeat `{}`",
                    c.g[qa].name, c.g[qb].name, c.symbols[g[e]].name
                )),
                Vec::new(),
            );
        }
    }
    // Longest path in edge events over the condensation (tarjan gives reverse topological order).
    let mut best = vec![0usize; sccs.len()];
    for (k, s) in sccs.iter().enumerate() {
        let mut m = 0;
        for n in s {
            for e in g.edges(*n) {
                use petgraph::visit::EdgeRef as _;
                let t = comp_of[e.target().index()];
                if t != k {
                    m = m.max(best[t] + usize::from(!is_tmo(c, *e.weight())));
                }
            }
        }
        best[k] = m;
    }
    let (silent, needs) = waiting_pairs(c, f, &g);
    if let Some(w) = silent {
        return (false, None, Some(w), needs.into_iter().collect());
    }
    (
        true,
        Some(best.iter().copied().max().unwrap_or(0)),
        None,
        needs.into_iter().collect(),
    )
}

/// The pairs of the twin graph where both sides wait for ever on time-outs alone: the
/// first silent one, and the actuator edges that certainty needs.
fn waiting_pairs(
    c: &Component,
    f: usize,
    g: &petgraph::graph::DiGraph<(usize, usize), usize>,
) -> (Option<String>, std::collections::BTreeSet<String>) {
    let mine = |m: Option<usize>| m == Some(f);
    // Pairs where the twins agree on nothing but time-outs and neither has a deadline
    // (both wait for ever): the fault side must leave through an edge the other cannot
    // make. None at all: the fault stays silent and the other hypothesis explains the
    // silence (not diagnosable). Only actuator edges: certainty waits for the
    // controller, and a controller that waits for the faulty sensor never gives it.
    let tmo_syms: Vec<usize> = (0..c.symbols.len()).filter(|&s| is_tmo(c, s)).collect();
    let waits = |q: usize| {
        tmo_syms
            .iter()
            .all(|&s| c.g[q].obs.iter().any(|&(x, t, _)| x == s && t == q))
    };
    let mut needs = std::collections::BTreeSet::new();
    let mut silent = None;
    for n in g.node_indices() {
        if g.edges(n).any(|e| !is_tmo(c, *e.weight())) {
            continue;
        }
        let (qa, qb) = g[n];
        if !waits(qa) || !waits(qb) {
            continue;
        }
        let ca = closure_of(c, &[qa], false, &|m| mine(m));
        let outs: Vec<(bool, &str)> = ca
            .iter()
            .flat_map(|&a| c.g[a].obs.iter())
            .filter_map(|(s, _, _)| {
                let (sig, _) = c.symbols[*s].edge?;
                Some((
                    c.signals[sig].var.space == crate::symbols::Space::Output,
                    c.symbols[*s].name.as_str(),
                ))
            })
            .collect();
        let other = c.g[qb]
            .mode
            .map_or_else(|| "normal".to_string(), |m| c.faults[m].clone());
        if outs.is_empty() {
            silent.get_or_insert_with(|| {
                format!(
                    "after the fault `{}` shows no edge any more and `{}` ({other}) explains the silence",
                    c.g[qa].name, c.g[qb].name
                )
            });
        } else if outs.iter().all(|(actuator, _)| *actuator) {
            let mut names: Vec<&str> = outs.iter().map(|(_, n)| *n).collect();
            names.sort_unstable();
            names.dedup();
            needs.insert(format!(
                "in `{}` the fault looks like {other} (`{}`) until the controller issues {}",
                c.g[qa].name,
                c.g[qb].name,
                names.join(" or ")
            ));
        }
    }
    (silent, needs)
}

/// A name as libFAUDES accepts it in a token file (no blanks, no `*`, `+`, `"`):
/// `RE(C0) . (A0* + A1*)` becomes `RE(C0)_._(A0__+_A1_)` mapped character by character.
pub fn faudes_name(n: &str) -> String {
    n.chars()
        .map(|ch| {
            if ch.is_ascii_alphanumeric() || "()./_-".contains(ch) {
                ch
            } else {
                '_'
            }
        })
        .collect()
}

/// The untimed abstraction of a component as a libFAUDES generator file (`.gen`, with
/// fault events `f_<label>` and hidden plant moves `hidden` unobservable) and its
/// failure type map, in libFAUDES token format.
pub fn faudes_export(c: &Component) -> (String, String) {
    let mut s = String::new();
    let q = |n: &str| format!("\"{}\"", faudes_name(n));
    let _ = writeln!(s, "<Generator>\n{}", q(&c.id));
    let _ = writeln!(s, "<Alphabet>");
    for sy in &c.symbols {
        let _ = writeln!(s, "{}", q(&sy.name));
    }
    for f in &c.faults {
        let _ = writeln!(s, "{} +o+", q(&format!("f_{f}")));
    }
    let _ = writeln!(s, "\"hidden\" +o+\n</Alphabet>\n<States>");
    for st in &c.g {
        let _ = writeln!(s, "{}", q(&st.name));
    }
    let _ = writeln!(s, "</States>\n<TransRel>");
    for st in &c.g {
        for &(sym, t, _) in &st.obs {
            let _ = writeln!(
                s,
                "{} {} {}",
                q(&st.name),
                q(&c.symbols[sym].name),
                q(&c.g[t].name)
            );
        }
        for &t in &st.silent {
            let _ = writeln!(s, "{} \"hidden\" {}", q(&st.name), q(&c.g[t].name));
        }
        for &(f, t) in &st.spawn {
            let _ = writeln!(
                s,
                "{} {} {}",
                q(&st.name),
                q(&format!("f_{}", c.faults[f])),
                q(&c.g[t].name)
            );
        }
    }
    let _ = writeln!(
        s,
        "</TransRel>\n<InitStates>\n{}\n</InitStates>\n<MarkedStates>\n</MarkedStates>\n</Generator>",
        q(&c.g[c.initial].name)
    );
    let mut m = String::from("<FailureTypes>\n");
    for f in &c.faults {
        let _ = writeln!(
            m,
            "{} <FailureEvents> {} </FailureEvents>",
            q(f),
            q(&format!("f_{f}"))
        );
    }
    m.push_str("</FailureTypes>\n");
    (s, m)
}

/// A synthetic model of `n` identical copies of a component (the turntable: `A4_<i>`,
/// `C4_<i>`, `C5_<i>`), with its plant, for benchmarks. Its guards may only read its own
/// signals.
pub fn synthetic(n: usize, table: &model::ComponentDef) -> (Plant, DiagnoserFile) {
    use crate::plant::{Signal, SignalKind};
    let sig = |id: String, kind| Signal::new(id, kind, String::new());
    let mut inputs = Vec::new();
    let mut outputs = Vec::new();
    let mut comps = Vec::new();
    for i in 0..n {
        for s in &table.signals {
            let kind = if s.starts_with('A') {
                SignalKind::Actuator
            } else {
                SignalKind::Sensor
            };
            let id = format!("{s}_{i}");
            if kind == SignalKind::Actuator {
                outputs.push(sig(id, kind))
            } else {
                inputs.push(sig(id, kind))
            }
        }
        comps.push(synthetic_copy(table, i));
    }
    (
        Plant::new("synthetic turntables", inputs, outputs),
        DiagnoserFile {
            alpha: 3.0,
            margin_ms: 10,
            pulse_max_ms: 2000,
            components: comps,
        },
    )
}

/// Copy `i` of the component `table`: ids, signals, expressions and intervals renamed.
fn synthetic_copy(table: &model::ComponentDef, i: usize) -> model::ComponentDef {
    let rename = |t: &str| -> String {
        let mut out = t.to_string();
        for s in &table.signals {
            out = out.replace(&format!("({s})"), &format!("({s}_{i})"));
        }
        out
    };
    let mut c = table.clone();
    c.id = format!("{}_{i}", table.id);
    // The campaign's injections name the original signals: not copied.
    c.injections.clear();
    c.signals = table.signals.iter().map(|s| format!("{s}_{i}")).collect();
    let mut vals = table.initial_values.clone();
    for s in &table.signals {
        vals = vals
            .split(" . ")
            .map(|l| {
                if l.trim_start_matches('/') == s {
                    format!("{l}_{i}")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join(" . ");
    }
    c.initial_values = vals;
    for e in &mut c.expected {
        e.event = rename(&e.event);
        e.within = e.within.as_ref().map(|w| format!("{w}_{i}"));
    }
    for iv in &mut c.intervals {
        iv.id = format!("{}_{i}", iv.id);
        iv.after = rename(&iv.after);
        let rb = |b: &model::Bound| match b {
            model::Bound::LoOf(x) => model::Bound::LoOf(format!("{x}_{i}")),
            model::Bound::HiOf(x) => model::Bound::HiOf(format!("{x}_{i}")),
            other => other.clone(),
        };
        iv.lo = rb(&iv.lo);
        iv.hi = rb(&iv.hi);
    }
    c.initial_clock = c.initial_clock.as_deref().map(rename);
    for f in &mut c.faults {
        for b in &mut f.behaviours {
            match b {
                model::Behaviour::StuckAt(s, _) | model::Behaviour::Spurious(s, _) => {
                    *s = format!("{s}_{i}")
                }
                model::Behaviour::Moves(_, e) => *e = rename(e),
                model::Behaviour::Blocked(_)
                | model::Behaviour::Jumps(..)
                | model::Behaviour::Unguarded => {}
            }
        }
    }
    for p in &mut c.partitions {
        p.id = format!("{}_{i}", p.id);
        p.sensor = p.sensor.as_ref().map(|s| format!("{s}_{i}"));
        // Actuators the component does not observe (A1 for the box beam) are not in
        // the synthetic plant.
        p.actuators = p
            .actuators
            .iter()
            .filter(|a| table.signals.contains(a))
            .map(|a| format!("{a}_{i}"))
            .collect();
    }
    // The neighbours whose sensors a component assumes are not in the synthetic
    // plant: each copy stands alone.
    c.assumes.clear();
    c.assumes_item.clear();
    c.independent = c.independent.iter().map(|a| format!("{a}_{i}")).collect();
    for e in &mut c.estimates {
        e.sensor = format!("{}_{i}", e.sensor);
        let mut x = e.expr.clone();
        for iv in &table.intervals {
            x = x
                .split(" + ")
                .map(|t| {
                    if t == iv.id {
                        format!("{t}_{i}")
                    } else {
                        t.to_string()
                    }
                })
                .collect::<Vec<_>>()
                .join(" + ");
        }
        e.expr = x;
    }
    c
}

#[cfg(test)]
mod tests;

/// The result of one closed-loop run with the diagnosers (campaign).
#[derive(Clone, Debug, Serialize)]
pub struct RunOutcome {
    /// Certain diagnoses.
    pub diagnoses: Vec<Diagnosis>,
    /// Hazards seen.
    pub hazards: usize,
    /// Boxes delivered.
    pub delivered: u32,
    /// Filter trips.
    pub trips: usize,
}

/// Runs the reference program of the plant in `dir` with the diagnosers for
/// `duration_ms`, a box every 15 s, with `fault` injected at `at_ms` (none if `None`).
pub fn closed_loop(
    dir: &Path,
    seed: u64,
    duration_ms: u64,
    fault: Option<(crate::emulator::FaultKind, u64)>,
) -> Result<(RunOutcome, crate::sim::Simulation), Vec<Problem>> {
    use crate::sim::{OperatorAction, Options, Simulation};
    let (bundle, _) = PlantBundle::load(dir)?;
    let program =
        crate::control::CompiledProgram::load(&dir.join("programs/reference.ron"), &bundle.plant)?;
    let mut sim = Simulation::new(
        bundle,
        program,
        seed,
        Options {
            history_cycles: 16,
            explain: false,
        },
    )?;
    sim.enable_diagnosers()?;
    sim.emulator
        .set_arrivals(crate::emulator::ArrivalPlan::Periodic {
            period_ms: 15_000,
            jitter_ms: 2_000,
            mix: crate::emulator::SizeMix::Alternate,
            count: None,
        });
    if let Some((kind, at)) = fault {
        sim.emulator
            .try_schedule_fault(crate::emulator::FaultSpec {
                trigger: crate::emulator::Trigger::At(at),
                fault: kind,
                duration_ms: None,
            })
            .map_err(|p| vec![p])?;
    }
    let _ = sim.act(&OperatorAction::Start);
    sim.run_until(crate::Millis(duration_ms));
    let d = sim
        .diagnosers
        .as_ref()
        .map(|d| d.diagnoses.clone())
        .unwrap_or_default();
    let out = RunOutcome {
        diagnoses: d,
        hazards: sim.emulator.hazards().len(),
        delivered: {
            let s = sim.emulator.stats();
            s.delivered_total()
        },
        trips: sim.engine.trips.len(),
    };
    Ok((out, sim))
}
