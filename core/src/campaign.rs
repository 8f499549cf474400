//! Mutation campaign: does the hypothesis level localise control errors?
//!
//! Every variant of the control-error library (`programs/errors.ron`) and every single
//! mutation of the reference program ([`crate::control::mutations`]: literal negated,
//! edge swapped, sensor swapped, term dropped, qualifier changed, action moved to another
//! step of its chart) runs in the closed loop
//! ([`crate::sim::Simulation`], filter in Enforce mode, a few boxes to both sides). For a
//! mutant that trips the filter, the first trip's explanation is taken, and the mutant is
//! *localised* when the FIRST suspect of the hypothesis names an element of the mutated
//! place:
//! - the place's own id: the transition (mutated receptivity), the step (mutated action)
//!   or the equation's target (mutated equation); a moved action edits two steps, and
//!   either localises it: the step it was moved to (its place, whose action drives the
//!   output where it must not) or the step it was taken from (which no longer commands
//!   the actuator: a trip can come from that absence alone, before the other step is
//!   ever active);
//! - or a name its mutated expression reads (a literal the mutation dropped does not
//!   count: the suspect must name the place or what it reads now).
//!
//! The names of a suspect are its fields `transition`, `step`, `activated`, `steps`,
//! `transitions`, `equation`, `signals` (program suspects, `X407`-`X413`, `X417`) and
//! `sensor` (the paper's suspects `X401`/`X402`); never the actuator of the constraint
//! itself, which every suspect names.
//!
//! The moved actions (misplaced actions) are also counted apart ([`Report::misplaced`]),
//! with a stricter test: of those that trip, how many have a first suspect that BLAMES
//! the step the action was moved to ([`accused`]: the element a suspect holds
//! responsible, not every name it gives; an `X408` that names the step it activated but
//! blames the receptivity of its transition does not count); and, among them, those
//! whose first trip the moved action drove ([`Outcome::driven`]).
//!
//! Runs are independent and deterministic; they are spread over named threads.

use crate::bundle::PlantBundle;
use crate::control::mutation::{Operator, Place};
use crate::control::{CompiledProgram, Driver, ErrorLibrary, Origin, Patch, Program, mutations};
use crate::diag::Problem;
use crate::emulator::{ArrivalPlan, BoxSize};
use crate::explain::Item;
use crate::sim::{Options, Simulation};
use crate::symbols::Space;
use crate::time::Millis;
use serde::Serialize;
use std::collections::BTreeSet;
use std::path::Path;

/// How each mutant is run.
#[derive(Clone, Debug)]
pub struct Config {
    /// Simulated duration of a run that does not trip, ms.
    pub duration_ms: u64,
    /// Box arrivals (alternate sizes; the reference program alternates the sides).
    pub arrivals: Vec<(u64, BoxSize)>,
    /// Emulator seed.
    pub seed: u64,
    /// Worker threads (at least 1).
    pub threads: usize,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            duration_ms: 40_000,
            arrivals: vec![
                (0, BoxSize::Small),
                (6_000, BoxSize::Large),
                (12_000, BoxSize::Small),
            ],
            seed: 1,
            threads: 2,
        }
    }
}

/// One mutant to run.
#[derive(Clone, Debug)]
pub struct Mutant {
    /// `E01` for a library variant, `M0042` for a generated mutation.
    pub id: String,
    /// The mistake in words.
    pub description: String,
    /// Where: `transition t24`, `step X24`, `equation A1`.
    pub place: String,
    /// Names that localise it (place id and the names its expression reads).
    pub names: BTreeSet<String>,
    /// The place's own element: the transition, the step (for a moved action, the step
    /// it was moved to) or the equation's target; what a suspect must blame
    /// ([`Outcome::blamed`]).
    pub element: String,
    /// The mutation operator (`None` for a library variant).
    pub operator: Option<Operator>,
    /// The mutant program.
    pub program: Program,
}

/// The outcome of one mutant.
#[derive(Clone, Debug, Serialize)]
pub struct Outcome {
    /// Mutant id.
    pub id: String,
    /// Description.
    pub description: String,
    /// Place.
    pub place: String,
    /// Names that localise it.
    pub names: Vec<String>,
    /// The mutation operator (`None` for a library variant).
    pub operator: Option<Operator>,
    /// Time of the first trip, if any.
    pub trip_ms: Option<u64>,
    /// Constraints of the first trip.
    pub constraints: Vec<String>,
    /// The first suspect of the hypothesis.
    pub first: Option<Item>,
    /// Number of names the first suspect gives.
    pub first_names: usize,
    /// True when the first suspect names the place.
    pub localised: bool,
    /// True when the first suspect blames ([`accused`]) the place's own element
    /// ([`Mutant::element`]).
    pub blamed: bool,
    /// True when an action of the place's step drove an actuator of the first trip to
    /// its forbidden value (ON): the mutated action itself, not its absence, tripped.
    pub driven: bool,
    /// Why not, when tripped and not localised (or why the mutant did not run).
    pub why: String,
}

/// The campaign figures.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Mutants run (library variants + generated mutations that compile).
    pub mutants: usize,
    /// Mutants that tripped the filter.
    pub tripped: usize,
    /// Tripped mutants whose first suspect names the mutated place.
    pub localised: usize,
    /// Mean number of names in the first suspect (how specific it is).
    pub mean_first_names: f64,
    /// The misplaced actions ([`Operator::MoveAction`]) alone: localised means that the
    /// first suspect blames the step the action was moved to ([`Outcome::blamed`]).
    pub misplaced: Subset,
    /// Every outcome, in mutant order.
    pub outcomes: Vec<Outcome>,
}

/// The figures of one kind of mutant.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Subset {
    /// Mutants of that kind run.
    pub mutants: usize,
    /// Those that tripped the filter.
    pub tripped: usize,
    /// Tripped ones whose first suspect blames the mutated place.
    pub localised: usize,
    /// `localised / tripped` in percent (100 when nothing tripped).
    pub rate_percent: f64,
    /// Tripped ones whose trip the mutated action drove ([`Outcome::driven`]).
    pub driven: usize,
    /// Among those, the ones whose first suspect blames the mutated place.
    pub driven_localised: usize,
}

impl Subset {
    /// The figures of the outcomes `keep` selects, localised when `hit`.
    fn of(
        outcomes: &[Outcome],
        keep: impl Fn(&Outcome) -> bool,
        hit: impl Fn(&Outcome) -> bool,
    ) -> Self {
        let mine: Vec<&Outcome> = outcomes.iter().filter(|o| keep(o)).collect();
        let tripped = mine.iter().filter(|o| o.trip_ms.is_some()).count();
        let localised = mine
            .iter()
            .filter(|o| o.trip_ms.is_some() && hit(o))
            .count();
        let driven: Vec<&&Outcome> = mine
            .iter()
            .filter(|o| o.trip_ms.is_some() && o.driven)
            .collect();
        Self {
            mutants: mine.len(),
            tripped,
            localised,
            driven: driven.len(),
            driven_localised: driven.iter().filter(|o| hit(o)).count(),
            rate_percent: if tripped == 0 {
                100.0
            } else {
                localised as f64 * 100.0 / tripped as f64
            },
        }
    }
}

impl Report {
    /// `localised / tripped` in percent (100 when nothing tripped).
    pub fn rate_percent(&self) -> f64 {
        if self.tripped == 0 {
            100.0
        } else {
            self.localised as f64 * 100.0 / self.tripped as f64
        }
    }

    /// The tripped mutants that were not localised.
    pub fn misses(&self) -> impl Iterator<Item = &Outcome> {
        self.outcomes
            .iter()
            .filter(|o| o.trip_ms.is_some() && !o.localised)
    }
}

/// Names an expression reads (empty when it does not parse).
fn expr_names(text: &str) -> Vec<String> {
    crate::expr::parse_str(text)
        .map(|e| {
            e.leaves()
                .into_iter()
                .map(|(n, _, _)| n.to_string())
                .collect()
        })
        .unwrap_or_default()
}

/// The place's own element of a patch (see [`Mutant::element`]).
fn patch_element(patch: &Patch) -> String {
    match patch {
        Patch::Condition { transition, .. } => transition.clone(),
        Patch::ReplaceAction { step, .. }
        | Patch::RemoveAction { step, .. }
        | Patch::AddAction { step, .. }
        | Patch::MoveAction { to: step, .. } => step.clone(),
        Patch::Equation { target, .. } => target.clone(),
    }
}

/// The names that localise a patch of `reference`, and its place in words.
fn patch_names(patch: &Patch) -> (String, BTreeSet<String>) {
    let mut names = BTreeSet::new();
    let place = match patch {
        Patch::Condition {
            transition,
            condition,
        } => {
            names.insert(transition.clone());
            names.extend(expr_names(condition));
            format!("transition {transition}")
        }
        Patch::ReplaceAction { step, .. }
        | Patch::RemoveAction { step, .. }
        | Patch::AddAction { step, .. } => {
            names.insert(step.clone());
            format!("step {step}")
        }
        Patch::MoveAction { from, to, .. } => {
            names.insert(to.clone());
            names.insert(from.clone());
            format!("step {to}")
        }
        Patch::Equation { target, expression } => {
            names.insert(target.clone());
            names.extend(expr_names(expression));
            format!("equation {target}")
        }
    };
    (place, names)
}

/// The library variants then the generated mutations of the reference program.
pub fn mutants(bundle: &PlantBundle) -> Result<Vec<Mutant>, Vec<Problem>> {
    let lib = ErrorLibrary::load(&bundle.dir.join("programs/errors.ron"), &bundle.plant)?;
    let mut out = Vec::new();
    for v in &lib.variants {
        let (place, names) = patch_names(&v.def.patch);
        out.push(Mutant {
            id: v.def.id.clone(),
            description: v.def.description.clone(),
            place,
            names,
            element: patch_element(&v.def.patch),
            operator: None,
            program: v.program.clone(),
        });
    }
    for (k, m) in mutations(&lib.reference, &bundle.plant)
        .into_iter()
        .enumerate()
    {
        let Ok(program) = m.patch.apply(&lib.reference) else {
            continue;
        };
        let (place, names) = patch_names(&m.patch);
        debug_assert!(match &m.place {
            Place::Transition { id, .. } => names.contains(id),
            Place::Action { step, .. } => names.contains(step),
            Place::Equation { target } => names.contains(target),
        });
        out.push(Mutant {
            id: format!("M{:04}", k + 1),
            description: m.description,
            place,
            names,
            element: patch_element(&m.patch),
            operator: Some(m.operator),
            program,
        });
    }
    Ok(out)
}

/// The names a suspect gives (see the module doc).
pub fn suspect_names(item: &Item) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for key in [
        "transition",
        "step",
        "activated",
        "steps",
        "transitions",
        "equation",
        "signals",
        "sensor",
    ] {
        if let Some(v) = item.fields.get(key) {
            out.extend(
                v.split(',')
                    .map(str::trim)
                    .filter(|s| !s.is_empty())
                    .map(str::to_string),
            );
        }
    }
    out
}

/// The element a suspect holds responsible: the transition whose receptivity it blames
/// (`X407`, `X408`, `X412`), the step whose action it blames (`X409`, `X413`, `X417`),
/// the equation (`X410`, and `X411` when the actuator has one), the sensor (`X401`,
/// `X402`, `X414`); nothing for the other items.
pub fn accused(item: &Item) -> BTreeSet<String> {
    use crate::diag::codes;
    let key = match item.code {
        c if c == codes::X_TRANSITION_DEACTIVATED_STEP.id
            || c == codes::X_TRANSITION_ACTIVATED_STEP.id
            || c == codes::X_STEP_NOT_LEFT.id =>
        {
            "transition"
        }
        c if c == codes::X_QUALIFIER.id
            || c == codes::X_COMBINED_MISSING.id
            || c == codes::X_MISPLACED_ACTION.id =>
        {
            "step"
        }
        c if c == codes::X_EQUATION_FORBIDDEN_VALUE.id || c == codes::X_NOTHING_COMMANDS.id => {
            "equation"
        }
        c if c == codes::X_SENSOR_CHANGED_NO_EVOLUTION.id
            || c == codes::X_SENSOR_OUTSIDE_CHANGED.id
            || c == codes::X_SUSPECT_SENSOR.id =>
        {
            "sensor"
        }
        _ => return BTreeSet::new(),
    };
    item.fields
        .get(key)
        .map(|v| {
            v.split(',')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(str::to_string)
                .collect()
        })
        .unwrap_or_default()
}

impl Outcome {
    /// A mutant's outcome before its run: no trip.
    fn of(mutant: &Mutant) -> Self {
        Self {
            id: mutant.id.clone(),
            description: mutant.description.clone(),
            place: mutant.place.clone(),
            names: mutant.names.iter().cloned().collect(),
            operator: mutant.operator,
            trip_ms: None,
            constraints: Vec::new(),
            first: None,
            first_names: 0,
            localised: false,
            blamed: false,
            driven: false,
            why: String::new(),
        }
    }
}

/// Runs one mutant in the closed loop until its first trip or the end of the run.
pub fn run_one(bundle: &PlantBundle, mutant: &Mutant, config: &Config) -> Outcome {
    let mut outcome = Outcome::of(mutant);
    let compiled = match CompiledProgram::new(&mutant.program, &bundle.plant, &Origin::default()) {
        Ok(c) => c,
        Err(p) => {
            outcome.why = format!(
                "does not compile: {}",
                p.first().map(|p| p.message.clone()).unwrap_or_default()
            );
            return outcome;
        }
    };
    let options = Options {
        history_cycles: 2_000,
        explain: true,
    };
    let mut sim = match Simulation::new(bundle.clone(), compiled, config.seed, options) {
        Ok(s) => s,
        Err(p) => {
            outcome.why = format!(
                "cannot start: {}",
                p.first().map(|p| p.message.clone()).unwrap_or_default()
            );
            return outcome;
        }
    };
    // The plant's production: the campaign's boxes on a sorting layout, the production
    // scenario's actions repeated on a plant of components.
    match crate::sim::workload::Workload::of(
        &bundle.dir,
        ArrivalPlan::List(config.arrivals.clone()),
    ) {
        Ok(w) => w.apply(&mut sim, config.duration_ms),
        Err(p) => {
            outcome.why = format!(
                "no production: {}",
                p.first().map(|p| p.message.clone()).unwrap_or_default()
            );
            return outcome;
        }
    }
    let end = Millis(config.duration_ms);
    let boxes = u32::try_from(config.arrivals.len()).unwrap_or(u32::MAX);
    while sim.now() < end && sim.engine.trips.is_empty() {
        sim.cycle();
        let stats = sim.emulator.stats();
        if stats.delivered_total() + stats.damaged >= boxes {
            break;
        }
    }
    let Some(trip) = sim.engine.trips.first() else {
        outcome.why = "no trip".into();
        return outcome;
    };
    outcome.trip_ms = Some(trip.time_ms);
    outcome.constraints = trip.constraints.iter().map(|c| c.id.clone()).collect();
    outcome.driven = trip
        .constraints
        .iter()
        .flat_map(|c| &c.literals)
        .filter(|l| l.space == Space::Output && !l.previous && l.value)
        .any(|l| {
            sim.program.drivers(&l.name).is_some_and(|ds| {
                ds.iter()
                    .any(|d| matches!(d, Driver::Action { step, .. } if *step == mutant.element))
            })
        });
    let first = sim
        .explanations
        .get(&0)
        .and_then(|ex| ex.hypothesis.items.first())
        .cloned();
    match first {
        Some(item) => {
            let names = suspect_names(&item);
            outcome.first_names = names.len();
            outcome.localised = names.iter().any(|n| mutant.names.contains(n));
            outcome.blamed = accused(&item).contains(&mutant.element);
            if !outcome.localised {
                outcome.why = format!(
                    "first suspect {} names {{{}}}, the place reads {{{}}}",
                    item.code,
                    names.iter().cloned().collect::<Vec<_>>().join(","),
                    outcome.names.join(",")
                );
            }
            outcome.first = Some(item);
        }
        None => outcome.why = "no hypothesis".into(),
    }
    outcome
}

/// Runs every mutant of the plant folder `dir`.
pub fn run(dir: &Path, config: &Config) -> Result<Report, Vec<Problem>> {
    let (bundle, _) = PlantBundle::load(dir)?;
    let all = mutants(&bundle)?;
    Ok(run_mutants(&bundle, &all, config))
}

/// Runs the given mutants on `config.threads` named threads.
pub fn run_mutants(bundle: &PlantBundle, all: &[Mutant], config: &Config) -> Report {
    let threads = config.threads.max(1);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut outcomes: Vec<Option<Outcome>> = vec![None; all.len()];
    std::thread::scope(|scope| {
        let mut handles = Vec::new();
        for w in 0..threads {
            let next = &next;
            let builder = std::thread::Builder::new().name(format!("campaign-{w}"));
            let spawned = builder.spawn_scoped(scope, move || {
                let mut done = Vec::new();
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(m) = all.get(k) else { break };
                    done.push((k, run_one(bundle, m, config)));
                }
                done
            });
            if let Ok(h) = spawned {
                handles.push(h);
            }
        }
        for h in handles {
            if let Ok(done) = h.join() {
                for (k, o) in done {
                    outcomes[k] = Some(o);
                }
            }
        }
    });
    // A mutant left over (no thread could be spawned) runs here.
    let outcomes: Vec<Outcome> = outcomes
        .into_iter()
        .enumerate()
        .map(|(k, o)| o.unwrap_or_else(|| run_one(bundle, &all[k], config)))
        .collect();
    let tripped: Vec<&Outcome> = outcomes.iter().filter(|o| o.trip_ms.is_some()).collect();
    let localised = tripped.iter().filter(|o| o.localised).count();
    let mean_first_names = if tripped.is_empty() {
        0.0
    } else {
        tripped.iter().map(|o| o.first_names as f64).sum::<f64>() / tripped.len() as f64
    };
    let misplaced = Subset::of(
        &outcomes,
        |o| o.operator == Some(Operator::MoveAction),
        |o| o.blamed,
    );
    Report {
        mutants: outcomes.len(),
        tripped: tripped.len(),
        localised,
        mean_first_names,
        misplaced,
        outcomes,
    }
}

#[cfg(test)]
mod tests;
