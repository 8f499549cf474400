//! The transient-fault campaign (`vigie campaign transients`): the faults real sensors
//! and actuators have and the diagnoser campaign does not inject, with the filter and
//! the diagnosers on, over many seeds.
//!
//! - **Transients of every sensor** of the layout: dropouts (the reading falls to 0
//!   while the sensor is on, for instance while an item crosses a beam) and spurious
//!   pulses (it reads 1 while off), of every length of [`Config::lengths_ms`], and
//!   flicker (a burst of short inversions), each at a random moment of production.
//! - **Pairs**: two transients of two sensors, the second shortly after the first (so
//!   sometimes during the trip the first caused).
//! - **Welded and dead actuators** (stuck on, stuck off for good) at the highest
//!   arrival rate the program sustains without fault (searched first).
//!
//! Every run counts the hazards of the emulator and the *wrong* certain diagnoses (a
//! certain diagnosis naming a partition that does not hold the faulted element, or any
//! certain diagnosis before the fault). After a transient the operator does what the
//! console tells him: the filter's reset if it tripped, the diagnosers' reset if a
//! partition is flagged, then Start; production counts as *restored* when items are
//! delivered again and the filter is not tripped at the end of the watch.

use super::Diagnosis;
use super::campaign::HORIZON_MS;
use super::campaign::{jobs, mix, parallel};
use crate::bundle::PlantBundle;
use crate::control::CompiledProgram;
use crate::diag::Problem;
use crate::emulator::{ArrivalPlan, FaultKind, FaultSpec, SizeMix, Trigger};
use crate::sim::workload::Workload;
use crate::sim::{OperatorAction, Options, Simulation};
use crate::time::Millis;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::sync::Arc;

/// Settings.
#[derive(Clone, Debug)]
pub struct Config {
    /// Seeds per case.
    pub seeds: u64,
    /// The first seed (`first_seed..first_seed + seeds`): replays one run.
    pub first_seed: u64,
    /// Only cases whose name contains this.
    pub only: Option<String>,
    /// Worker threads.
    pub threads: usize,
    /// Faults strike between `first_ms` and `first_ms + spread_ms`.
    pub first_ms: u64,
    /// See `first_ms`.
    pub spread_ms: u64,
    /// Lengths of the dropouts and pulses, ms.
    pub lengths_ms: Vec<u64>,
    /// After the fault has ended, the time before the operator acts, ms.
    pub settle_ms: u64,
    /// Watch after the operator's reset, ms.
    pub recover_ms: u64,
    /// Watch of a permanent actuator fault, ms.
    pub actuator_watch_ms: u64,
    /// Items that must be delivered after the reset for production to count as
    /// restored.
    pub restored_items: u32,
    /// Simulated hours of fault-free production (one run per hour, its own seed).
    pub fault_free_hours: u64,
    /// Run the plausibility stage (false: every edge as read, the filter as it was
    /// before the stage, for a comparison).
    pub plausibility: bool,
    /// Record every cycle of a run and give the first failed run's changes of signals
    /// (`Row::first_failure_changes`): for replaying one run (`--seeds 1`).
    pub changes: bool,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            seeds: 100,
            first_seed: 0,
            only: None,
            threads: 2,
            first_ms: 20_000,
            spread_ms: 60_000,
            lengths_ms: vec![5, 10, 20, 50, 100, 200, 500],
            settle_ms: 2_000,
            recover_ms: 90_000,
            actuator_watch_ms: 60_000,
            restored_items: 2,
            fault_free_hours: 10,
            plausibility: true,
            changes: false,
        }
    }
}

/// One transient of a sensor.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub enum Transient {
    /// Reads 0 for this long while on.
    Dropout(u64),
    /// Reads 1 for this long while off.
    Pulse(u64),
    /// A burst of short inversions (lengths and gaps drawn from the seed).
    Flicker,
}

/// What a case injects.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub enum CaseKind {
    /// One transient of one sensor.
    Sensor {
        /// Sensor id.
        sensor: String,
        /// The transient.
        transient: Transient,
    },
    /// Two transients of two sensors drawn from the seed.
    Pair,
    /// An actuator stuck for good: on (welded) or off (dead).
    Actuator {
        /// Actuator (output) id.
        actuator: String,
        /// Stuck on.
        on: bool,
    },
}

/// One case of the campaign.
#[derive(Clone, Debug, Serialize)]
pub struct Case {
    /// Readable name.
    pub name: String,
    /// What it injects.
    pub kind: CaseKind,
}

/// Figures of one case over every seed.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Row {
    /// Case name.
    pub name: String,
    /// Runs.
    pub runs: usize,
    /// Runs where the fault changed what the sensor read (a dropout needs the sensor on).
    pub injected: usize,
    /// Hazards over all runs.
    pub hazards: usize,
    /// Actuator faults: the hazards whose elements include the faulted actuator itself
    /// (a welded conveyor that keeps pushing, a dead one that stops a box under a
    /// moving neighbour), which no other output can always prevent, and what follows
    /// to an item one of them already damaged.
    pub own_hazards: usize,
    /// Wrong certain diagnoses over all runs.
    pub wrong: usize,
    /// Right certain diagnoses (the faulted element's partition).
    pub right: usize,
    /// Runs where the filter tripped.
    pub trips: usize,
    /// Transients only: runs where production came back after the reset.
    pub restored: usize,
    /// Transients only: runs where it did not.
    pub not_restored: usize,
    /// Transients only: runs where the filter tripped again after the operator's
    /// recovery (a consequence of the transient met later, such as a box an observer
    /// still believed in), and the operator recovered again as the console asked.
    pub tripped_again: usize,
    /// Pairs: runs whose second fault struck while the filter was tripped.
    pub during_trip: usize,
    /// Examples of failures (seed and text), at most five of each kind (hazard, wrong
    /// diagnosis, not restored).
    pub failures: Vec<String>,
    /// The journal of the first failed run (seed, then its lines).
    pub first_failure_journal: Vec<String>,
    /// With [`Config::changes`]: every change of a signal in the first failed run, one
    /// line per cycle (`43830 ms: C0=0 | A0=1 (commanded 1) | P01=1 | sus_C0=1`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub first_failure_changes: Vec<String>,
}

/// The campaign report.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Report {
    /// Seeds per case.
    pub seeds: u64,
    /// The arrival plan of the transient runs: period and jitter, ms.
    pub transient_period_ms: (u64, u64),
    /// The shortest arrival period the program sustains without fault, ms (actuator
    /// runs).
    pub sustained_period_ms: u64,
    /// The plausibility stage ran.
    pub plausibility: bool,
    /// One row per case.
    pub rows: Vec<Row>,
    /// The fault-free hours.
    pub fault_free: FaultFree,
}

/// Fault-free production with the plausibility rules, the filter and the diagnosers.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FaultFree {
    /// Simulated hours.
    pub hours: u64,
    /// Items delivered.
    pub delivered: u64,
    /// Trips.
    pub trips: usize,
    /// Hazards.
    pub hazards: usize,
    /// Certain diagnoses (each one false).
    pub diagnoses: usize,
    /// Sensor edges held as implausible (each one a wrong rule).
    pub held_edges: u64,
    /// Examples of held edges and false diagnoses.
    pub examples: Vec<String>,
}

impl Report {
    /// Totals: (runs, hazards, wrong, restored, not restored).
    pub fn totals(&self) -> (usize, usize, usize, usize, usize) {
        self.rows.iter().fold((0, 0, 0, 0, 0), |t, r| {
            (
                t.0 + r.runs,
                t.1 + r.hazards,
                t.2 + r.wrong,
                t.3 + r.restored,
                t.4 + r.not_restored,
            )
        })
    }
}

/// The cases of a plant: transients of every sensor of the layout, pairs, and both
/// stuck faults of every output the emulator drives.
pub fn cases(sensors: &[String], actuators: &[String], lengths: &[u64]) -> Vec<Case> {
    let mut v = Vec::new();
    for s in sensors {
        for &l in lengths {
            v.push(Case {
                name: format!("{s} dropout {l} ms"),
                kind: CaseKind::Sensor {
                    sensor: s.clone(),
                    transient: Transient::Dropout(l),
                },
            });
            v.push(Case {
                name: format!("{s} pulse {l} ms"),
                kind: CaseKind::Sensor {
                    sensor: s.clone(),
                    transient: Transient::Pulse(l),
                },
            });
        }
        v.push(Case {
            name: format!("{s} flicker"),
            kind: CaseKind::Sensor {
                sensor: s.clone(),
                transient: Transient::Flicker,
            },
        });
    }
    if sensors.len() >= 2 {
        v.push(Case {
            name: "pair of transients".into(),
            kind: CaseKind::Pair,
        });
    }
    for a in actuators {
        for on in [true, false] {
            v.push(Case {
                name: format!("{a} {}", if on { "welded" } else { "dead" }),
                kind: CaseKind::Actuator {
                    actuator: a.clone(),
                    on,
                },
            });
        }
    }
    v
}

struct Shared {
    bundle: PlantBundle,
    program: Arc<CompiledProgram>,
    /// Partitions holding each sensor or actuator.
    partitions: BTreeMap<String, BTreeSet<String>>,
    /// The layout's sensors.
    sensors: Vec<String>,
    /// The actuators the emulator drives.
    actuators: Vec<String>,
    /// What keeps the plant producing.
    workload: Workload,
}

fn simulation(
    shared: &Shared,
    seed: u64,
    work: &Workload,
    plausibility: bool,
    history_cycles: usize,
) -> Result<Simulation, Vec<Problem>> {
    let mut sim = Simulation::new(
        shared.bundle.clone(),
        (*shared.program).clone(),
        seed,
        Options {
            history_cycles,
            explain: false,
        },
    )?;
    sim.engine.set_plausibility(plausibility);
    sim.enable_diagnosers()?;
    work.apply(&mut sim, HORIZON_MS);
    Ok(sim)
}

/// A small deterministic generator for the draws of one run.
struct Draw(u64);

impl Draw {
    fn next(&mut self, n: u64) -> u64 {
        self.0 = mix(self.0);
        self.0 % n.max(1)
    }
}

/// What one run found.
#[derive(Default)]
struct Outcome {
    injected: bool,
    hazards: Vec<String>,
    own_hazards: usize,
    wrong: Vec<String>,
    right: usize,
    tripped: bool,
    restored: Option<bool>,
    tripped_again: bool,
    during_trip: bool,
    note: String,
    journal: Vec<String>,
    changes: Vec<String>,
}

fn sensor_value(sim: &Simulation, input: usize) -> bool {
    sim.emulator.sensors().get(input)
}

/// Runs until `input` reads `value` and has for a random 0..hold ms (a random moment of
/// that state), bounded by `limit`. False when it never did.
fn wait_for(sim: &mut Simulation, input: usize, value: bool, hold: u64, limit: Millis) -> bool {
    let mut since: Option<Millis> = None;
    while sim.now() < limit {
        if sensor_value(sim, input) == value {
            let s = *since.get_or_insert(sim.now());
            if sim.now().0 >= s.0 + hold {
                return true;
            }
        } else {
            since = None;
        }
        sim.cycle();
    }
    false
}

/// Schedules a transient of `sensor` now; returns its end (ms) and whether the plant's
/// reading really changed, or None when the sensor never showed the state it needs.
fn strike(
    sim: &mut Simulation,
    sensor: &str,
    t: &Transient,
    draw: &mut Draw,
) -> Result<Option<u64>, Vec<Problem>> {
    let Some(input) = sim.bundle.plant.input(sensor) else {
        return Ok(None);
    };
    let limit = Millis(sim.now().0 + 180_000);
    let (value, pulses): (bool, Vec<(u64, u64)>) = match t {
        Transient::Dropout(l) => (true, vec![(0, *l)]),
        Transient::Pulse(l) => (false, vec![(0, *l)]),
        Transient::Flicker => {
            let value = draw.next(2) == 0;
            let n = 3 + draw.next(6);
            let mut at = 0;
            let mut v = Vec::new();
            for _ in 0..n {
                let len = 5 + draw.next(46);
                v.push((at, len));
                at += len + 5 + draw.next(96);
            }
            (value, v)
        }
    };
    // A random moment of the state: while an item crosses the beam (its crossing takes
    // 1 to 1.3 s on the station; a draw past the crossing waits for the next item).
    let hold = draw.next(if value { 1_300 } else { 3_000 });
    if !wait_for(sim, input, value, hold, limit) {
        return Ok(None);
    }
    let now = sim.now().0;
    let mut end = now;
    for (offset, len) in pulses {
        let fault = if value {
            FaultKind::SpuriousFall {
                sensor: sensor.to_string(),
                pulse_ms: len,
            }
        } else {
            FaultKind::SpuriousRise {
                sensor: sensor.to_string(),
                pulse_ms: len,
            }
        };
        sim.inject(FaultSpec {
            trigger: Trigger::At(now + offset),
            fault,
            duration_ms: None,
        })
        .map_err(|p| vec![p])?;
        end = end.max(now + offset + len);
    }
    Ok(Some(end))
}

/// How long the operator tries the reset (once a second) before a check of the plant
/// and the re-initialisation.
const RESET_TRIES_MS: u64 = 30_000;

/// The operator's recovery, as the console asks for it: the diagnosers' reset first when
/// a stop partition is flagged, the filter's reset while it is tripped (retried each
/// second while refused, [`RESET_TRIES_MS`]; then, a sensor flagged, the diagnosers'
/// reset and 5 s more), the re-initialisation of an emptied plant when it is still
/// refused, the diagnosers' reset when a partition is flagged, then Start.
fn recover(sim: &mut Simulation) {
    // A flagged stop partition (a certain actuator fault, or a stop on the safe side)
    // refuses the filter's reset until the diagnosers' reset after the check, as the
    // console says.
    if sim
        .diagnosers
        .as_ref()
        .is_some_and(|d| d.flagged().iter().any(|(_, stop, _)| *stop))
    {
        let _ = sim.act(&OperatorAction::ResetDiagnosers);
    }
    try_reset(sim, RESET_TRIES_MS);
    // Refused all along: a sensor the diagnosers flagged is read from its estimate,
    // which may still say what the transient made it say; the operator resets them
    // (the sensor is read again) and tries again.
    if sim.engine.is_tripped()
        && sim
            .diagnosers
            .as_ref()
            .is_some_and(|d| !d.flagged().is_empty())
    {
        let _ = sim.act(&OperatorAction::ResetDiagnosers);
        try_reset(sim, 5_000);
    }
    // Still refused: the program still believes what the transient made it believe (a
    // box gone that is still under its beam, a phantom on the table), which no reset
    // changes. The operator empties the plant and re-initialises, as the console
    // proposes after a refused reset (the program's initial steps expect no box
    // half-way).
    if sim.engine.is_tripped() {
        let _ = sim.act(&OperatorAction::Reinitialise { emptied: true });
    }
    if sim
        .diagnosers
        .as_ref()
        .is_some_and(|d| !d.flagged().is_empty())
    {
        let _ = sim.act(&OperatorAction::ResetDiagnosers);
    }
    let _ = sim.act(&OperatorAction::Start);
}

/// The operator's reset, tried once a second for `ms` until it is accepted.
fn try_reset(sim: &mut Simulation, ms: u64) {
    let limit = Millis(sim.now().0 + ms);
    while sim.engine.is_tripped() && sim.now() < limit {
        if sim.act(&OperatorAction::Reset).is_ok() {
            break;
        }
        let next = Millis(sim.now().0 + 1_000);
        sim.run_until(next);
    }
}

/// The items delivered, or the elementary actions completed on a plant of components.
fn delivered(sim: &Simulation) -> u32 {
    u32::try_from(sim.produced()).unwrap_or(u32::MAX)
}

fn judge(sim: &Simulation, expected: &BTreeSet<String>, at: u64, out: &mut Outcome) {
    out.hazards = sim
        .emulator
        .hazards()
        .iter()
        .map(|h| {
            format!(
                "{} ms {:?} of item {} at {}",
                h.time_ms, h.kind, h.box_id, h.place
            )
        })
        .collect();
    let Some(d) = sim.diagnosers.as_ref() else {
        return;
    };
    // A stop on the safe side (`ambiguous`) claims no fault: it is neither right nor
    // wrong (its trip and the recovery after it are counted).
    for x in d
        .diagnoses
        .iter()
        .filter(|x| !x.partition.is_empty() && x.certainty == super::Certainty::Certain)
    {
        if x.time_ms >= at && expected.contains(&x.partition) {
            out.right += 1;
        } else {
            out.wrong.push(describe(x, at));
        }
    }
}

/// Keeps what the run's journal says and, with [`Config::changes`], its changes of
/// signals.
fn record(sim: &Simulation, config: &Config, out: &mut Outcome) {
    out.journal = sim
        .journal()
        .iter()
        .map(|j| format!("{} ms {}: {}", j.time_ms, j.kind, j.text))
        .collect();
    if config.changes {
        out.changes = changes(sim);
    }
}

/// Every change of a signal over the recorded cycles, one line per cycle that changed
/// something: the raw inputs, the applied outputs (with the commanded value where it
/// differs), the observers and the auxiliary variables (suspect flags, estimates,
/// diagnoser flags), and the trip.
fn changes(sim: &Simulation) -> Vec<String> {
    use crate::bits::Bits;
    use crate::history::CycleRecord;
    use crate::symbols::Space;
    fn bits(r: &CycleRecord, space: Space) -> &Bits {
        match space {
            Space::Input => &r.inputs,
            Space::Output => &r.applied,
            Space::Observer => &r.observers,
            Space::Aux => &r.aux,
        }
    }
    let bit = |b: &Bits, i: usize| i < b.len() && b.get(i);
    let symbols = &sim.engine.symbols;
    let mut lines = Vec::new();
    let mut previous: Option<&CycleRecord> = None;
    for r in sim.engine.history.iter() {
        let mut parts = Vec::new();
        for space in Space::ALL {
            for (i, name) in symbols.names(space).iter().enumerate() {
                let value = bit(bits(r, space), i);
                // An output also shows where the filter changed the program's command.
                let commanded = (space == Space::Output).then(|| bit(&r.commanded, i));
                let changed = previous.is_none_or(|p| {
                    bit(bits(p, space), i) != value
                        || commanded.is_some_and(|c| bit(&p.commanded, i) != c)
                });
                if !changed {
                    continue;
                }
                parts.push(match commanded {
                    Some(c) if c != value => {
                        format!("{name}={} (commanded {})", u8::from(value), u8::from(c))
                    }
                    _ => format!("{name}={}", u8::from(value)),
                });
            }
        }
        if previous.is_none_or(|p| p.tripped != r.tripped) {
            parts.push(format!("tripped={}", u8::from(r.tripped)));
        }
        if !parts.is_empty() {
            lines.push(format!("{} ms: {}", r.time.0, parts.join(" | ")));
        }
        previous = Some(r);
    }
    lines
}

fn describe(d: &Diagnosis, at: u64) -> String {
    format!(
        "{} ms ({:+} ms from the fault) {}/{} {}",
        d.time_ms,
        d.time_ms as i64 - at as i64,
        d.component,
        d.partition,
        d.fault
    )
}

fn run_one(
    shared: &Shared,
    case: &Case,
    seed: u64,
    config: &Config,
    plans: &(Workload, Workload),
) -> Result<Outcome, Vec<Problem>> {
    let mut draw = Draw(seed ^ mix(case.name.len() as u64 ^ 0x5EED));
    for b in case.name.bytes() {
        draw.0 = mix(draw.0 ^ u64::from(b));
    }
    let actuator = matches!(case.kind, CaseKind::Actuator { .. });
    let plan = if actuator { &plans.1 } else { &plans.0 };
    let history = if config.changes { 100_000 } else { 16 };
    let mut sim = simulation(shared, seed + 1, plan, config.plausibility, history)?;
    let at = config.first_ms + draw.next(config.spread_ms);
    sim.run_until(Millis(at));
    let mut out = Outcome::default();
    let none = BTreeSet::new();
    let parts = |id: &str| shared.partitions.get(id).unwrap_or(&none).clone();
    let (expected, end, struck_at) = match &case.kind {
        CaseKind::Actuator { actuator, on } => {
            let at = sim.now().0;
            sim.inject(FaultSpec {
                trigger: Trigger::At(at),
                fault: if *on {
                    FaultKind::ActuatorStuckOn(actuator.clone())
                } else {
                    FaultKind::ActuatorStuckOff(actuator.clone())
                },
                duration_ms: None,
            })
            .map_err(|p| vec![p])?;
            out.injected = true;
            sim.run_until(Millis(at + config.actuator_watch_ms));
            out.tripped = !sim.engine.trips.is_empty();
            judge(&sim, &parts(actuator), at, &mut out);
            out.own_hazards = own_hazards(sim.emulator.hazards(), actuator);
            record(&sim, config, &mut out);
            return Ok(out);
        }
        CaseKind::Sensor { sensor, transient } => {
            let Some(end) = strike(&mut sim, sensor, transient, &mut draw)? else {
                out.note = format!("{sensor} never showed the state the fault needs");
                judge(&sim, &parts(sensor), u64::MAX, &mut out);
                return Ok(out);
            };
            (parts(sensor), end, sim.now().0)
        }
        CaseKind::Pair => {
            let sensors: Vec<&String> = shared.sensors.iter().collect();
            let a = sensors[draw.next(sensors.len() as u64) as usize].clone();
            let mut b = sensors[draw.next(sensors.len() as u64) as usize].clone();
            if b == a {
                b = sensors
                    [(sensors.iter().position(|s| **s == a).unwrap_or(0) + 1) % sensors.len()]
                .clone();
            }
            let pick = |draw: &mut Draw| {
                let l = config.lengths_ms[draw.next(config.lengths_ms.len() as u64) as usize];
                match draw.next(3) {
                    0 => Transient::Dropout(l),
                    1 => Transient::Pulse(l),
                    _ => Transient::Flicker,
                }
            };
            let (ta, tb) = (pick(&mut draw), pick(&mut draw));
            let gap = draw.next(3_000);
            out.note = format!("{a} {ta:?} then {b} {tb:?} {gap} ms later");
            let Some(end_a) = strike(&mut sim, &a, &ta, &mut draw)? else {
                judge(&sim, &parts(&a), u64::MAX, &mut out);
                return Ok(out);
            };
            let first = sim.now().0;
            sim.run_until(Millis(first + gap));
            out.during_trip = sim.engine.is_tripped();
            let end_b = strike(&mut sim, &b, &tb, &mut draw)?.unwrap_or(end_a);
            let mut e = parts(&a);
            e.extend(parts(&b));
            (e, end_a.max(end_b), first)
        }
    };
    out.injected = true;
    sim.run_until(Millis(end + config.settle_ms));
    let before = delivered(&sim);
    recover(&mut sim);
    let reset_at = sim.now().0;
    // The operator stays at the console for the watch: a later trip (a consequence of
    // the transient met later) gets the same recovery, at most twice.
    watch_recovery(&mut sim, reset_at + config.recover_ms, &mut out);
    out.tripped = !sim.engine.trips.is_empty();
    out.restored =
        Some(!sim.engine.is_tripped() && delivered(&sim) >= before + config.restored_items);
    judge(&sim, &expected, struck_at, &mut out);
    record(&sim, config, &mut out);
    if out.restored == Some(false) {
        out.note = format!(
            "{} not restored: {} produced (items delivered or actions completed) in {} s after the reset at {reset_at} ms, filter {}",
            out.note,
            delivered(&sim) - before,
            config.recover_ms / 1000,
            if sim.engine.is_tripped() {
                "tripped"
            } else {
                "not tripped"
            }
        );
    }
    Ok(out)
}

/// Runs the operator's watch until `watch_end`: a later trip gets the same recovery, at
/// most twice.
fn watch_recovery(sim: &mut Simulation, watch_end: u64, out: &mut Outcome) {
    let mut again = 0;
    while sim.now().0 < watch_end {
        let next = (sim.now().0 + 1_000).min(watch_end);
        sim.run_until(Millis(next));
        if sim.engine.is_tripped() && again < 2 && sim.now().0 < watch_end {
            again += 1;
            out.tripped_again = true;
            recover(sim);
        }
    }
}

/// The hazards of a faulted actuator itself: those whose elements include it (a welded
/// table that turns under a box being loaded, 80 ms after the weld and before any
/// sensor can show it), and what follows to an item such a hazard already damaged (the
/// sheared box then falls off the belt's end as the table turns away).
fn own_hazards(hazards: &[crate::emulator::Hazard], actuator: &str) -> usize {
    let mut damaged = BTreeSet::new();
    hazards
        .iter()
        .filter(|h| {
            let own = h.elements.iter().any(|e| e == actuator) || damaged.contains(&h.box_id);
            if own {
                damaged.insert(h.box_id);
            }
            own
        })
        .count()
}

/// The period and jitter of the plant's production: its source's arrivals (a
/// layout's or a plant of components' first source), or the production scenario's
/// length (no jitter).
fn layout_plan(shared: &Shared) -> Result<(u64, u64), Vec<Problem>> {
    if let Workload::Operator { period_ms, .. } = &shared.workload {
        return Ok((*period_ms, 0));
    }
    Ok(
        match crate::machine::Description::load(&shared.bundle.dir)? {
            crate::machine::Description::Components(c) => c
                .first_source()
                .map_or((15_000, 0), |a| (a.period_ms, a.jitter_ms)),
        },
    )
}

/// The shortest arrival period, among the layout's own and shorter ones (a step of
/// 500 ms down to 1 s), at which `minutes` of fault-free production with the filter and
/// the diagnosers on give no trip, no hazard, no certain diagnosis and deliver every
/// item but the last few (the queue does not grow).
///
/// A plant of components keeps its production scenario's period: its operator's
/// actions are timed for it.
fn sustained(shared: &Shared, minutes: u64, threads: usize) -> Result<u64, Vec<Problem>> {
    let (nominal, _) = layout_plan(shared)?;
    if matches!(shared.workload, Workload::Operator { .. }) {
        return Ok(nominal);
    }
    let periods: Vec<u64> = (0..)
        .map(|k| nominal.saturating_sub(500 * k))
        .take_while(|&p| p >= 1_000)
        .collect();
    let duration = minutes * 60_000;
    let ok = parallel(&periods, threads, &|&p| -> Result<bool, Vec<Problem>> {
        let plan = ArrivalPlan::Periodic {
            period_ms: p,
            jitter_ms: 0,
            mix: SizeMix::Alternate,
            count: None,
        };
        let mut sim = simulation(shared, 77, &Workload::Arrivals(plan), true, 16)?;
        sim.run_until(Millis(duration));
        let diagnosed = sim
            .diagnosers
            .as_ref()
            .is_some_and(|d| d.diagnoses.iter().any(|x| !x.partition.is_empty()));
        let expected = (duration / p) as u32;
        Ok(sim.engine.trips.is_empty()
            && sim.emulator.hazards().is_empty()
            && !diagnosed
            && delivered(&sim) + 4 >= expected)
    });
    let mut best = nominal;
    for (p, r) in periods.iter().zip(ok) {
        if r? {
            best = *p;
        } else {
            break;
        }
    }
    Ok(best)
}

fn load(dir: &Path) -> Result<Shared, Vec<Problem>> {
    let (bundle, program, file) = super::campaign::load_reference(dir)?;
    let mut partitions: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for c in &file.components {
        for p in &c.partitions {
            if let Some(s) = &p.sensor {
                partitions
                    .entry(s.clone())
                    .or_default()
                    .insert(p.id.clone());
            }
            for a in &p.actuators {
                partitions
                    .entry(a.clone())
                    .or_default()
                    .insert(p.id.clone());
            }
        }
    }
    let physical =
        crate::machine::Physical::new(&crate::machine::Description::load(dir)?, &bundle.plant, 0)
            .map_err(|p| vec![p])?;
    let (sensors, actuators) = (physical.sensor_ids(), physical.actuators());
    // The layout's own arrivals are read by `layout_plan`; this plan is not used there.
    let workload = Workload::of(
        dir,
        ArrivalPlan::Periodic {
            period_ms: 15_000,
            jitter_ms: 0,
            mix: SizeMix::Alternate,
            count: None,
        },
    )?;
    Ok(Shared {
        bundle,
        program,
        partitions,
        sensors,
        actuators,
        workload,
    })
}

/// One fault-free hour of the plant under `plan`.
fn fault_free_hour(
    shared: &Shared,
    work: &Workload,
    config: &Config,
    h: u64,
) -> Result<FaultFree, Vec<Problem>> {
    let mut sim = simulation(shared, 20_000 + h, work, config.plausibility, 16)?;
    sim.run_until(Millis(3_600_000));
    let mut examples: Vec<String> = sim
        .journal()
        .iter()
        .filter(|j| j.kind == "plausibility" || j.kind == "diagnosis")
        .take(3)
        .map(|j| format!("hour {h}, {} ms {}: {}", j.time_ms, j.kind, j.text))
        .collect();
    examples.truncate(3);
    Ok(FaultFree {
        hours: 1,
        delivered: u64::from(delivered(&sim)),
        trips: sim.engine.trips.len(),
        hazards: sim.emulator.hazards().len(),
        diagnoses: sim.diagnosers.as_ref().map_or(0, |d| {
            d.diagnoses
                .iter()
                .filter(|x| !x.partition.is_empty())
                .count()
        }),
        held_edges: sim.engine.plausibility.held_edges,
        examples,
    })
}

/// The fault-free hours added up (at most five examples).
fn sum_fault_free(free: Vec<Result<FaultFree, Vec<Problem>>>) -> Result<FaultFree, Vec<Problem>> {
    let mut fault_free = FaultFree::default();
    for f in free {
        let f = f?;
        fault_free.hours += f.hours;
        fault_free.delivered += f.delivered;
        fault_free.trips += f.trips;
        fault_free.hazards += f.hazards;
        fault_free.diagnoses += f.diagnoses;
        fault_free.held_edges += f.held_edges;
        if fault_free.examples.len() < 5 {
            fault_free.examples.extend(f.examples);
        }
    }
    Ok(fault_free)
}

/// Runs the campaign on the plant in `dir`.
pub fn run(dir: &Path, config: &Config) -> Result<Report, Vec<Problem>> {
    let shared = load(dir)?;
    let (period, jitter) = layout_plan(&shared)?;
    let sustained_ms = sustained(&shared, 20, config.threads)?;
    let plans = match &shared.workload {
        Workload::Operator { .. } => (shared.workload.clone(), shared.workload.clone()),
        Workload::Arrivals(_) => (
            Workload::Arrivals(ArrivalPlan::Periodic {
                period_ms: period,
                jitter_ms: jitter,
                mix: SizeMix::Alternate,
                count: None,
            }),
            Workload::Arrivals(ArrivalPlan::Periodic {
                period_ms: sustained_ms,
                jitter_ms: 0,
                mix: SizeMix::Alternate,
                count: None,
            }),
        ),
    };
    let all: Vec<Case> = cases(&shared.sensors, &shared.actuators, &config.lengths_ms)
        .into_iter()
        .filter(|c| config.only.as_deref().is_none_or(|o| c.name.contains(o)))
        .collect();
    let jobs = jobs(all.len(), config.first_seed, config.seeds);
    let results = parallel(&jobs, config.threads, &|&(i, s)| {
        run_one(&shared, &all[i], s, config, &plans)
    });
    let mut rows: Vec<Row> = all
        .iter()
        .map(|c| Row {
            name: c.name.clone(),
            ..Row::default()
        })
        .collect();
    let mut examples: BTreeMap<(usize, &str), usize> = BTreeMap::new();
    for (&(i, seed), r) in jobs.iter().zip(results) {
        let o = r?;
        let row = &mut rows[i];
        row.runs += 1;
        row.injected += usize::from(o.injected);
        row.hazards += o.hazards.len();
        row.own_hazards += o.own_hazards;
        row.wrong += o.wrong.len();
        row.right += o.right;
        row.trips += usize::from(o.tripped);
        row.during_trip += usize::from(o.during_trip);
        row.tripped_again += usize::from(o.tripped_again);
        match o.restored {
            Some(true) => row.restored += 1,
            Some(false) => row.not_restored += 1,
            None => {}
        }
        // At most five examples of each kind of failure, hazards first.
        let mut fail = |kind: &'static str, t: String| {
            let n = examples.entry((i, kind)).or_insert(0);
            if *n < 5 {
                *n += 1;
                row.failures.push(format!("seed {seed}: {t}"));
            }
        };
        for h in &o.hazards {
            fail("hazard", format!("hazard {h} ({})", o.note));
        }
        for w in &o.wrong {
            fail(
                "wrong diagnosis",
                format!("wrong diagnosis {w} ({})", o.note),
            );
        }
        if o.restored == Some(false) {
            fail("not restored", o.note.clone());
        }
        let failed = !o.hazards.is_empty() || !o.wrong.is_empty() || o.restored == Some(false);
        if failed && row.first_failure_journal.is_empty() {
            row.first_failure_journal.push(format!("seed {seed}"));
            row.first_failure_journal.extend(o.journal);
            row.first_failure_changes = o.changes;
        }
    }
    let hours: Vec<u64> = (0..config.fault_free_hours).collect();
    let free = parallel(&hours, config.threads, &|&h| {
        fault_free_hour(&shared, &plans.0, config, h)
    });
    let fault_free = sum_fault_free(free)?;
    Ok(Report {
        seeds: config.seeds,
        transient_period_ms: (period, jitter),
        sustained_period_ms: sustained_ms,
        plausibility: config.plausibility,
        rows,
        fault_free,
    })
}
