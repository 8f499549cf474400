//! The diagnosers' fault campaign: every fault of the injection library, injected at a
//! random time of a production run (one box every 15 s, reference program, filter on,
//! diagnosers on), over many seeds; and fault-free hours. A run counts as *right* when
//! the first certain diagnosis after the injection names an expected partition and none
//! came before it. A run without any certain diagnosis is not hidden: it is classified
//! by the decision the component holds at the end (the fault had no observable effect,
//! or it stays ambiguous with a fault of another partition, which the diagnosability
//! report predicts), with the state the component was in when the fault struck.

use super::Diagnosis;
use super::runtime::Certainty;
use crate::bundle::PlantBundle;
use crate::control::CompiledProgram;
use crate::diag::Problem;
use crate::diag::codes;
use crate::emulator::{ArrivalPlan, FaultKind, FaultSpec, SizeMix, Trigger};
use crate::expr::{Dnf, eval_dnf, parse_str};
use crate::sim::workload::Workload;
use crate::sim::{Options, Simulation};
use crate::time::Millis;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// One fault of the injection library.
#[derive(Clone, Debug, Serialize)]
pub struct Injection {
    /// Readable name.
    pub name: String,
    /// The emulator's fault.
    pub kind: FaultKind,
    /// The partitions a right diagnosis may name.
    pub expected: Vec<String>,
    /// The component whose decisions classify a run without diagnosis.
    pub component: String,
    /// Inject only once this expression over the frame holds after the random time
    /// (e.g. `C4 . /A4`: the table rests at C4), None: at the random time.
    pub when: Option<String>,
}

/// What happened in one run.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub enum Verdict {
    /// The first certain diagnosis after the fault names an expected partition.
    Right {
        /// Detection delay, ms.
        delay_ms: u64,
    },
    /// A certain diagnosis of another partition (or an unexplained observation) first.
    Wrong(String),
    /// A certain diagnosis before the fault was injected (a false alarm).
    Early(String),
    /// No certain diagnosis; the component still hesitates between these faults.
    Ambiguous(String),
    /// No certain diagnosis, and the fault changed no sensor and no output over the
    /// watch (compared with a fault-free twin run of the same seed).
    NoEffect,
    /// No certain diagnosis, but the device monitoring stopped the plant on the faulted
    /// actuator itself: a mirror contact disagreed with it (explanation X419).
    Monitored {
        /// Delay from the fault to that stop, ms.
        delay_ms: u64,
    },
}

/// The figures of one injection over every seed.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Row {
    /// Injection name.
    pub name: String,
    /// Expected partitions.
    pub expected: Vec<String>,
    /// Runs.
    pub runs: usize,
    /// Right partition with certainty.
    pub right: usize,
    /// Wrong certain diagnosis first.
    pub wrong: usize,
    /// False diagnosis before the injection.
    pub early: usize,
    /// Not diagnosed, but stopped by the device monitoring on the faulted actuator (its
    /// mirror contact): localised on the machine by the stop itself.
    pub monitored: usize,
    /// Not diagnosed, ambiguous: reason (faults still possible, state at injection) and count.
    pub ambiguous: BTreeMap<String, usize>,
    /// Not diagnosed, no observable effect: state at injection and count.
    pub no_effect: BTreeMap<String, usize>,
    /// Detection delays of the right and monitored runs, sorted, ms.
    pub delays_ms: Vec<u64>,
    /// Examples of wrong or early runs (seed and text).
    pub failures: Vec<String>,
    /// Runs where the model lost track of the plant ("unexplained" note, no fault
    /// claimed, estimate restarted) before its verdict.
    pub lost: usize,
    /// Examples of those (seed and note).
    pub lost_runs: Vec<String>,
}

impl Row {
    /// Delay quantile (0..=100) of the right runs, ms.
    pub fn delay_quantile(&self, q: usize) -> Option<u64> {
        let n = self.delays_ms.len();
        (n > 0).then(|| self.delays_ms[(n - 1) * q.min(100) / 100])
    }
}

/// The campaign report.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Report {
    /// Seeds per injection.
    pub seeds: u64,
    /// One row per injection.
    pub rows: Vec<Row>,
    /// Simulated hours of fault-free runs.
    pub fault_free_hours: u64,
    /// Certain diagnoses in the fault-free runs (each one is false).
    pub false_diagnoses: Vec<Diagnosis>,
    /// Boxes delivered in the fault-free runs.
    pub fault_free_delivered: u64,
    /// Hazards in the fault-free runs.
    pub fault_free_hazards: usize,
}

/// Settings.
#[derive(Clone, Debug)]
pub struct Config {
    /// Seeds per injection.
    pub seeds: u64,
    /// The first seed (the runs use `first_seed..first_seed + seeds`): replays one run.
    pub first_seed: u64,
    /// Simulated hours of fault-free runs (one run per hour, its own seed).
    pub fault_free_hours: u64,
    /// Only injections whose name contains this.
    pub only: Option<String>,
    /// Worker threads.
    pub threads: usize,
    /// Faults strike between `first_ms` and `first_ms + spread_ms`.
    pub first_ms: u64,
    /// See `first_ms`.
    pub spread_ms: u64,
    /// Time left to the diagnosers after the injection, ms.
    pub watch_ms: u64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            seeds: 100,
            first_seed: 0,
            fault_free_hours: 10,
            only: None,
            threads: 2,
            first_ms: 60_000,
            spread_ms: 120_000,
            watch_ms: 60_000,
        }
    }
}

/// The injection library: the four sensor faults of every diagnosed sensor (expected:
/// its own partition), each component's own `injections` (mechanical faults, a sensor
/// fault in a given situation), and both stuck faults of every actuator a partition
/// lists in `actuators` (expected: those partitions).
pub fn library(file: &super::model::DiagnoserFile) -> Vec<Injection> {
    let mut v = Vec::new();
    let pulse = 300;
    for c in &file.components {
        for p in &c.partitions {
            let Some(s) = &p.sensor else { continue };
            let one = |name: String, kind: FaultKind, when: Option<&str>| Injection {
                name,
                kind,
                expected: vec![p.id.clone()],
                component: c.id.clone(),
                when: when.map(str::to_string),
            };
            v.push(one(
                format!("{s} stuck at 0"),
                FaultKind::SensorStuckAt0(s.clone()),
                None,
            ));
            v.push(one(
                format!("{s} stuck at 1"),
                FaultKind::SensorStuckAt1(s.clone()),
                None,
            ));
            v.push(one(
                format!("{s} spurious rise {pulse} ms"),
                FaultKind::SpuriousRise {
                    sensor: s.clone(),
                    pulse_ms: pulse,
                },
                None,
            ));
            v.push(one(
                format!("{s} spurious fall {pulse} ms"),
                FaultKind::SpuriousFall {
                    sensor: s.clone(),
                    pulse_ms: pulse,
                },
                None,
            ));
        }
    }
    for c in &file.components {
        for i in &c.injections {
            v.push(Injection {
                name: i.name.clone(),
                kind: i.fault.clone(),
                expected: i.expected.clone(),
                component: c.id.clone(),
                when: i.when.clone(),
            });
        }
    }
    // Actuator faults: expected in every partition that lists the actuator.
    let mut actuators: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for c in &file.components {
        for p in &c.partitions {
            for a in &p.actuators {
                actuators
                    .entry(a.clone())
                    .or_default()
                    .push((c.id.clone(), p.id.clone()));
            }
        }
    }
    for (a, parts) in &actuators {
        let component = parts.first().map(|(c, _)| c.clone()).unwrap_or_default();
        let expected: Vec<String> = parts.iter().map(|(_, p)| p.clone()).collect();
        for (what, kind) in [
            ("stuck off", FaultKind::ActuatorStuckOff(a.clone())),
            ("stuck on", FaultKind::ActuatorStuckOn(a.clone())),
        ] {
            v.push(Injection {
                name: format!("{a} {what}"),
                kind,
                expected: expected.clone(),
                component: component.clone(),
                when: None,
            });
        }
    }
    v
}

/// Everything a run needs, loaded once.
struct Shared {
    bundle: PlantBundle,
    program: Arc<CompiledProgram>,
    /// What keeps the plant producing: boxes every 15 ± 2 s on a sorting layout, the
    /// production scenario's actions on a plant of components.
    workload: Workload,
}

/// The longest a campaign's run lasts: an injection's watch, or a fault-free hour.
pub(crate) const HORIZON_MS: u64 = 2 * 3_600_000;

fn simulation(shared: &Shared, seed: u64) -> Result<Simulation, Vec<Problem>> {
    let program = (*shared.program).clone();
    let mut sim = Simulation::new(
        shared.bundle.clone(),
        program,
        seed,
        Options {
            history_cycles: 16,
            explain: false,
        },
    )?;
    sim.enable_diagnosers()?;
    shared.workload.apply(&mut sim, HORIZON_MS);
    Ok(sim)
}

/// SplitMix64 of the seed: the injection time.
pub(crate) fn mix(seed: u64) -> u64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn describe(d: &Diagnosis) -> String {
    format!(
        "{} ms {}/{} {}",
        d.time_ms, d.component, d.partition, d.fault
    )
}

/// Runs one injection with one seed, beside a fault-free twin run of the same seed
/// (to tell a fault that changed nothing observable from one that stays ambiguous).
fn run_one(
    shared: &Shared,
    inj: &Injection,
    seed: u64,
    config: &Config,
) -> Result<(Verdict, String, Option<String>), Vec<Problem>> {
    let mut sim = simulation(shared, seed + 1)?;
    let at = config.first_ms + mix(seed) % config.spread_ms.max(1);
    sim.run_until(Millis(at));
    if let Some(when) = &inj.when {
        let dnf: Dnf = parse_str(when)
            .and_then(|e| e.to_dnf(&sim.engine.symbols))
            .map_err(|e| {
                vec![Problem::error(
                    codes::DIAGNOSER_PARTITION_OR_INJECTION.id,
                    format!("`{when}`: {}", e.message),
                    None,
                )]
            })?;
        let limit = Millis(at + 120_000);
        while !eval_dnf(&dnf, sim.engine.frame()) && sim.now() < limit {
            sim.cycle();
        }
    }
    let at = sim.now().0;
    let mut twin = simulation(shared, seed + 1)?;
    twin.run_until(Millis(at));
    let context = sim
        .diagnosers
        .as_ref()
        .map(|d| {
            d.estimate(&inj.component)
                .into_iter()
                .filter(|s| !s.contains('/'))
                .collect::<Vec<_>>()
                .join(",")
        })
        .unwrap_or_default();
    sim.inject(FaultSpec {
        trigger: Trigger::At(at),
        fault: inj.kind.clone(),
        duration_ms: None,
    })
    .map_err(|p| vec![p])?;
    let end = Millis(at + config.watch_ms);
    let mut effect = false;
    while sim.now() < end {
        sim.cycle();
        if !effect {
            twin.cycle();
            effect = sim.emulator.sensors() != twin.emulator.sensors()
                || sim.engine.applied() != twin.engine.applied();
        }
    }
    let Some(d) = sim.diagnosers.as_ref() else {
        return Ok((Verdict::NoEffect, context, None));
    };
    if let Some(e) = d.diagnoses.iter().find(|x| x.time_ms < at) {
        return Ok((Verdict::Early(describe(e)), context, None));
    }
    // An "unexplained" note claims no fault (no flag, no stop): the model lost track of
    // the plant and restarted from the observed values. It is counted apart (`lost`),
    // and the verdict goes to the first diagnosis that names a partition.
    // A stop on the safe side (`ambiguous`: a stopping fault among the candidates) is
    // no verdict: it leaves the decision open, as the component does.
    let first_named = d
        .diagnoses
        .iter()
        .position(|x| !x.partition.is_empty() && x.certainty == Certainty::Certain);
    let lost = d.diagnoses[..first_named.unwrap_or(d.diagnoses.len())]
        .iter()
        .find(|x| x.partition.is_empty())
        .map(describe);
    let (verdict, context) = verdict_of(inj, d, first_named, at, effect, context);
    let verdict = match verdict {
        Verdict::Ambiguous(_) | Verdict::NoEffect => monitored(&sim, &inj.kind, at)
            .map_or(verdict, |delay_ms| Verdict::Monitored { delay_ms }),
        v => v,
    };
    Ok((verdict, context, lost))
}

/// The delay to the first stop after `at` whose constraint shows the faulted actuator's
/// contactor at fault through its mirror contact, if any.
fn monitored(sim: &Simulation, kind: &FaultKind, at: u64) -> Option<u64> {
    let (FaultKind::ActuatorStuckOff(a) | FaultKind::ActuatorStuckOn(a)) = kind else {
        return None;
    };
    let mirrors = sim.bundle.plant.mirrors();
    sim.engine
        .trips
        .iter()
        .filter(|t| t.time_ms >= at)
        .find_map(|t| {
            t.constraints
                .iter()
                .flat_map(|c| crate::explain::contactors_at_fault(&sim.engine.symbols, &mirrors, c))
                .any(|(o, _, _)| &o == a)
                .then(|| t.time_ms - at)
        })
}

fn verdict_of(
    inj: &Injection,
    d: &crate::pop::Diagnosers,
    first_named: Option<usize>,
    at: u64,
    effect: bool,
    context: String,
) -> (Verdict, String) {
    if let Some(first) = first_named.map(|k| &d.diagnoses[k]) {
        return if inj.expected.contains(&first.partition) {
            (
                Verdict::Right {
                    delay_ms: first.time_ms - at,
                },
                context,
            )
        } else {
            (Verdict::Wrong(describe(first)), context)
        };
    }
    let open: Vec<String> = d
        .decisions()
        .into_iter()
        .filter(|(c, _, dec)| *c == inj.component && dec.certainty != Certainty::Normal)
        .map(|(_, p, dec)| format!("{} ({p})", dec.faults.join("|")))
        .chain(
            d.diagnoses
                .iter()
                .filter(|x| x.certainty == Certainty::Ambiguous && x.component == inj.component)
                .map(|x| format!("{} (stopped on the safe side, {})", x.fault, x.partition)),
        )
        .collect();
    if !effect {
        (Verdict::NoEffect, context)
    } else if open.is_empty() {
        (
            Verdict::Ambiguous("nothing unexpected seen by the component".into()),
            context,
        )
    } else {
        (Verdict::Ambiguous(open.join(" or ")), context)
    }
}

/// Every (case, seed) pair of a campaign: `cases` cases, each over the seeds
/// `first_seed..first_seed + seeds`, case by case.
pub(crate) fn jobs(cases: usize, first_seed: u64, seeds: u64) -> Vec<(usize, u64)> {
    let seeds = first_seed..first_seed.saturating_add(seeds);
    (0..cases)
        .flat_map(|i| seeds.clone().map(move |s| (i, s)))
        .collect()
}

pub(crate) fn parallel<T: Send + Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: &(dyn Fn(&T) -> R + Sync),
) -> Vec<R> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut out: Vec<Option<R>> = (0..items.len()).map(|_| None).collect();
    std::thread::scope(|scope| {
        let mut handles = Vec::new();
        for w in 0..threads.max(1) {
            let next = &next;
            let builder = std::thread::Builder::new().name(format!("diag-campaign-{w}"));
            if let Ok(h) = builder.spawn_scoped(scope, move || {
                let mut done = Vec::new();
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(item) = items.get(k) else { break };
                    done.push((k, f(item)));
                }
                done
            }) {
                handles.push(h);
            }
        }
        for h in handles {
            if let Ok(done) = h.join() {
                for (k, r) in done {
                    out[k] = Some(r);
                }
            }
        }
    });
    out.into_iter()
        .enumerate()
        .map(|(k, r)| r.unwrap_or_else(|| f(&items[k])))
        .collect()
}

/// What the diagnosers' campaigns load from a plant folder: the bundle, its reference
/// program compiled, and its diagnoser file.
pub(crate) fn load_reference(
    dir: &Path,
) -> Result<
    (
        PlantBundle,
        Arc<CompiledProgram>,
        super::model::DiagnoserFile,
    ),
    Vec<Problem>,
> {
    let (bundle, _) = PlantBundle::load(dir)?;
    let program = Arc::new(CompiledProgram::load(
        &dir.join("programs/reference.ron"),
        &bundle.plant,
    )?);
    let file =
        super::model::DiagnoserFile::load(&dir.join("diagnosers.ron")).map_err(|p| vec![p])?;
    Ok((bundle, program, file))
}

/// The campaign's plant, program and workload (boxes every 15 ± 2 s on a sorting
/// layout), and the diagnosers' file.
fn load_shared(dir: &Path) -> Result<(Shared, super::model::DiagnoserFile), Vec<Problem>> {
    let (bundle, program, file) = load_reference(dir)?;
    let workload = Workload::of(
        dir,
        ArrivalPlan::Periodic {
            period_ms: 15_000,
            jitter_ms: 2_000,
            mix: SizeMix::Alternate,
            count: None,
        },
    )?;
    let shared = Shared {
        bundle,
        program,
        workload,
    };
    Ok((shared, file))
}

/// Runs the campaign on the plant in `dir`.
pub fn run(dir: &Path, config: &Config) -> Result<Report, Vec<Problem>> {
    let (shared, file) = load_shared(dir)?;
    let injections: Vec<Injection> = library(&file)
        .into_iter()
        .filter(|i| config.only.as_deref().is_none_or(|o| i.name.contains(o)))
        .collect();
    let jobs = jobs(injections.len(), config.first_seed, config.seeds);
    let results = parallel(&jobs, config.threads, &|&(i, s)| {
        run_one(&shared, &injections[i], s, config)
    });
    let mut rows: Vec<Row> = injections
        .iter()
        .map(|i| Row {
            name: i.name.clone(),
            expected: i.expected.clone(),
            ..Row::default()
        })
        .collect();
    for (&(i, seed), r) in jobs.iter().zip(results) {
        let (verdict, context, lost) = r?;
        let row = &mut rows[i];
        row.runs += 1;
        if let Some(l) = lost {
            row.lost += 1;
            if row.lost_runs.len() < 5 {
                row.lost_runs.push(format!("seed {seed}: {l}"));
            }
        }
        match verdict {
            Verdict::Right { delay_ms } => {
                row.right += 1;
                row.delays_ms.push(delay_ms);
            }
            Verdict::Wrong(t) => {
                row.wrong += 1;
                row.failures.push(format!(
                    "seed {seed}, table/component in {context}: wrong {t}"
                ));
            }
            Verdict::Early(t) => {
                row.early += 1;
                row.failures
                    .push(format!("seed {seed}: before the fault {t}"));
            }
            Verdict::Ambiguous(t) => {
                *row.ambiguous
                    .entry(format!("{t}, injected in {context}"))
                    .or_default() += 1;
            }
            Verdict::Monitored { delay_ms } => {
                row.monitored += 1;
                row.delays_ms.push(delay_ms);
            }
            Verdict::NoEffect => {
                *row.no_effect
                    .entry(format!("injected in {context}"))
                    .or_default() += 1
            }
        }
    }
    for r in &mut rows {
        r.delays_ms.sort_unstable();
        r.failures.truncate(5);
    }
    let hours: Vec<u64> = (0..config.fault_free_hours).collect();
    let free = parallel(&hours, config.threads, &|&h| -> Result<
        (Vec<Diagnosis>, u64, usize),
        Vec<Problem>,
    > {
        let mut sim = simulation(&shared, 10_000 + h)?;
        sim.run_until(Millis(3_600_000));
        Ok((
            sim.diagnosers
                .as_ref()
                .map(|d| d.diagnoses.clone())
                .unwrap_or_default(),
            sim.produced(),
            sim.emulator.hazards().len(),
        ))
    });
    let mut report = Report {
        seeds: config.seeds,
        rows,
        fault_free_hours: config.fault_free_hours,
        ..Report::default()
    };
    for r in free {
        let (d, delivered, hazards) = r?;
        report.false_diagnoses.extend(d);
        report.fault_free_delivered += delivered;
        report.fault_free_hazards += hazards;
    }
    Ok(report)
}
