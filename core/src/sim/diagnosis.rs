//! The diagnosers as one stage of a cycle, shared by the simulation, the live monitor
//! and gateway cycles (`vigie gateway`) and the console's mirror of a live run: loading
//! them with the constraints rewritten for the cooperation, the alarm and journal text
//! of each certain diagnosis, the sensors read from their estimates, and when a live
//! link steps them.
//!
//! Order of a cycle: inputs → observers → control → filter → **diagnosers** → outputs →
//! recorder. The diagnosers follow the inputs and the *applied* outputs; the flags
//! `def_<partition>`, the intervals and the estimates they write into the auxiliaries
//! are read by the rewritten constraints from the next cycle on.

use crate::bits::Bits;
use crate::diag::Problem;
use crate::diag::codes;
use crate::frame::Frame;
use crate::plant::Plant;
use crate::pop::{Certainty, DiagBundle, Diagnosers, Diagnosis};
use crate::symbols::{Space, Symbols};
use crate::time::Millis;
use serde::Serialize;
use std::path::Path;

/// Loads `diagnosers.ron` of the plant folder `dir` for a run: the bundle with the
/// auxiliaries declared and the constraints rewritten, and the compiled models. Any
/// error refuses the run except the property (6) findings (V0106) on the rewritten
/// set, accepted as the simulation has always accepted them with its diagnosers.
pub fn load(dir: &Path) -> Result<DiagBundle, Vec<Problem>> {
    let (db, problems) = crate::pop::load(dir)?;
    let errors: Vec<Problem> = problems
        .into_iter()
        .filter(|p| p.is_error() && p.code != codes::PROPERTY_6_VIOLATED.id)
        .collect();
    if errors.is_empty() {
        Ok(db)
    } else {
        Err(errors)
    }
}

/// A certain diagnosis with its alarm and journal text.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Notice {
    /// The diagnosis.
    pub diagnosis: Diagnosis,
    /// Alarm key: `diag:<component>:<partition>`.
    pub key: String,
    /// Alarm and journal text.
    pub text: String,
    /// The partition stops the whole system (`DSTOP_<partition>`).
    pub stop: bool,
    /// The sensor now read from its estimate (degraded mode).
    pub estimated: Option<String>,
    /// The alarm code of the text: `diagnosis-ambiguous`, `diagnosis-actuator`,
    /// `diagnosis-sensor-no-estimate`, `diagnosis-sensor-estimated`, `diagnosis-other`.
    pub code: &'static str,
    /// The sensor of a sensor partition at fault.
    pub sensor: Option<String>,
}

/// What Vigie does with a flag, for the texts of the notices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cooperation {
    /// A flagged stop partition stops the plant (the filter is enforced); otherwise the
    /// `DSTOP_` violation is only reported.
    pub stop: bool,
    /// The control program reads a flagged sensor's estimate (the simulation's program,
    /// the PLC behind a gateway); otherwise only the constraints do.
    pub estimate: bool,
}

/// The diagnoses made since `*seen` (an index into [`Diagnosers::diagnoses`], moved
/// past them), as notices.
pub fn take_notices(d: &Diagnosers, seen: &mut usize, acts: Cooperation) -> Vec<Notice> {
    let new = d.diagnoses.get(*seen..).unwrap_or_default();
    *seen = d.diagnoses.len();
    if new.is_empty() {
        return Vec::new();
    }
    let flagged = d.flagged();
    new.iter()
        .map(|n| {
            let flag = flagged.iter().find(|(p, _, _)| *p == n.partition);
            let (f, p, c) = (&n.fault, &n.partition, &n.component);
            let (text, stop, estimated, code) = match flag {
                Some((_, true, _)) if n.certainty == Certainty::Ambiguous => (
                    format!(
                        "Diagnosis: {c} is faulty, ambiguous between {}: {p} (a drive) may be at fault, {}",
                        f.replace('|', ", "),
                        if acts.stop {
                            "the whole system is stopped on the safe side; check it, then reset the diagnosers"
                        } else {
                            "the filter only reports, the system is not stopped"
                        }
                    ),
                    true,
                    None,
                    "diagnosis-ambiguous",
                ),
                Some((_, true, _)) => (
                    if acts.stop {
                        format!(
                            "Diagnosis: fault {f} on {p} ({c}), certain: actuator partition at fault, the whole system is stopped"
                        )
                    } else {
                        format!(
                            "Diagnosis: fault {f} on {p} ({c}), certain: actuator partition at fault; the filter only reports, the system is not stopped"
                        )
                    },
                    true,
                    None,
                    "diagnosis-actuator",
                ),
                Some((_, false, Some(s))) if !has_estimate(d, s) => (
                    format!(
                        "Diagnosis: fault {f} on sensor {s} (certain); {s} has no estimate in the {c} model: the constraints and the program still read {s}"
                    ),
                    false,
                    None,
                    "diagnosis-sensor-no-estimate",
                ),
                Some((_, false, Some(s))) => (
                    if acts.estimate {
                        format!(
                            "Diagnosis: fault {f} on sensor {s} (certain): {s} estimated from time intervals ({}, the {c} timing); production continues in degraded mode",
                            hat(s)
                        )
                    } else {
                        format!(
                            "Diagnosis: fault {f} on sensor {s} (certain): the constraints read {s} estimated from time intervals ({}, the {c} timing), the control program still reads {s}",
                            hat(s)
                        )
                    },
                    false,
                    Some(s.clone()),
                    "diagnosis-sensor-estimated",
                ),
                _ => (
                    format!("Diagnosis: {f} on {p} ({c})"),
                    false,
                    None,
                    "diagnosis-other",
                ),
            };
            Notice {
                diagnosis: n.clone(),
                key: format!("diag:{c}:{p}"),
                text,
                stop,
                estimated,
                code,
                sensor: match flag {
                    Some((_, false, Some(s))) => Some(s.clone()),
                    _ => None,
                },
            }
        })
        .collect()
}

/// True when a component of `d` estimates `sensor` (`EST(sensor)`).
pub fn has_estimate(d: &Diagnosers, sensor: &str) -> bool {
    let name = crate::symbols::estimate_name(sensor);
    d.compiled
        .components
        .iter()
        .any(|c| c.estimates.iter().any(|(n, _)| *n == name))
}

/// `Ĉ4`: a sensor's name with a hat on its first letter (its estimate).
pub fn hat(sensor: &str) -> String {
    let mut chars = sensor.chars();
    let first = chars.next().unwrap_or(' ');
    format!("{first}\u{0302}{}", chars.as_str())
}

/// The sensors read from their estimates: for every flagged partition of a sensor that
/// has an estimate, (input index, auxiliary index of `EST(sensor)`).
pub fn estimated_inputs(d: &Diagnosers, plant: &Plant, symbols: &Symbols) -> Vec<(usize, usize)> {
    d.flagged()
        .iter()
        .filter_map(|(_, _, s)| {
            let s = s.as_ref()?;
            let input = plant.input(s)?;
            match symbols.lookup(&crate::symbols::estimate_name(s))? {
                (Space::Aux, aux) => Some((input, aux as usize)),
                _ => None,
            }
        })
        .collect()
}

/// Every sensor the diagnosers can estimate: (input index, auxiliary of its partition's
/// flag `def_<partition>`, auxiliary of `EST(sensor)`), for [`crate::engine::Engine::set_estimates`].
pub fn estimate_map(
    compiled: &crate::pop::build::Compiled,
    plant: &Plant,
    symbols: &Symbols,
) -> Vec<(usize, usize, usize)> {
    let mut out = Vec::new();
    for c in &compiled.components {
        for p in &c.partitions {
            let Some(s) = &p.sensor else { continue };
            let aux = |name: &str| match symbols.lookup(name) {
                Some((Space::Aux, i)) => Some(i as usize),
                _ => None,
            };
            if let (Some(input), Some(def), Some(est)) = (
                plant.input(s),
                aux(&format!("def_{}", p.id)),
                aux(&crate::symbols::estimate_name(s)),
            ) {
                out.push((input, def, est));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The frame as the control program and the task monitors read it in degraded mode:
/// each estimated sensor replaced, at t and at t−1, by its estimate. None when no sensor
/// is estimated (they read `frame` itself).
pub fn estimated_frame(estimated: &[(usize, usize)], frame: &Frame) -> Option<Frame> {
    if estimated.is_empty() {
        return None;
    }
    let mut f = frame.clone();
    for &(input, aux) in estimated {
        if input >= f.now(Space::Input).len() || aux >= frame.now(Space::Aux).len() {
            continue;
        }
        let (v, p) = (
            frame.now(Space::Aux).get(aux),
            frame.prev(Space::Aux).get(aux),
        );
        f.now_mut(Space::Input).set(input, v);
        f.prev[Space::Input as usize].set(input, p);
    }
    Some(f)
}

/// Replaces, in `inputs`, each estimated sensor by its estimate at t in `frame` (what
/// the control program reads in degraded mode).
pub fn substitute(estimated: &[(usize, usize)], frame: &Frame, inputs: &mut Bits) {
    for &(input, aux) in estimated {
        if input < inputs.len() && aux < frame.now(Space::Aux).len() {
            inputs.set(input, frame.now(Space::Aux).get(aux));
        }
    }
}

/// What a live link's diagnosers did in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LinkStep {
    /// Not stepped: no diagnosers, the peer's values not usable (never heard yet, or
    /// lost), or not yet in the initial state (see [`LinkGate`]). Flags, intervals and
    /// estimates keep their last values.
    #[default]
    Skipped,
    /// Stepped on the cycle's frame.
    Stepped,
    /// The estimates restarted from the cycle's frame ([`Diagnosers::reset`]), then
    /// stepped: after the peer was lost and signals changed meanwhile, nothing being
    /// flagged (see [`LinkGate`]).
    Restarted,
}

/// A change of a live link's diagnosers, reported as an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GateChange {
    /// First stepped: the plant was seen in its initial state.
    Started,
    /// No longer stepped: the peer is lost.
    Suspended,
    /// Stepped again after a loss, the estimates kept (nothing changed meanwhile, or a
    /// partition is flagged).
    Resumed,
    /// Stepped again after a loss, the estimates restarted in the initial state.
    Restarted,
}

/// When a live link steps its diagnosers.
///
/// - The models' clocks and estimates start in their initial state (on the station: the
///   table at C4 with A4 off, no box at any sensor), as in the simulation: started on
///   whatever a link sees first (a table between its positions, a box half-way), the
///   windows would count from long ago and a first time-out would be taken for a
///   fault. So the diagnosers start in the first usable cycle where every component
///   shows its initial values.
/// - Held values of a lost peer are no observation: the diagnosers are not stepped while
///   the peer is lost. When it returns they go on at once if no signal they follow
///   changed meanwhile (the time-outs due in the gap are real: nothing moved), or if a
///   partition is flagged (a certain diagnosis is never dropped because of the link; an
///   estimate that no longer fits restarts as in the simulation, with an `unexplained`
///   note). Otherwise the edges of the gap have no time: the estimates restart in the
///   next cycle that shows the initial state.
#[derive(Clone, Debug, Default)]
pub struct LinkGate {
    started: bool,
    down: bool,
    /// Signal values of every component in the last cycle stepped.
    last: Vec<u64>,
    scratch: Vec<u64>,
}

impl LinkGate {
    /// The step of this cycle, given whether the peer's values are usable now (heard
    /// and not lost) and the frame after the filter (inputs and applied outputs at t),
    /// with the change to report, if any.
    pub fn step(
        &mut self,
        usable: bool,
        d: &Diagnosers,
        frame: &Frame,
    ) -> (LinkStep, Option<GateChange>) {
        if !usable {
            let change = (self.started && !self.down).then_some(GateChange::Suspended);
            self.down |= self.started;
            return (LinkStep::Skipped, change);
        }
        valuations(d, frame, &mut self.scratch);
        let at_initial = d
            .compiled
            .components
            .iter()
            .zip(&self.scratch)
            .all(|(c, v)| c.values.get(c.initial) == Some(v));
        let result = if !self.started {
            if !at_initial {
                return (LinkStep::Skipped, None);
            }
            self.started = true;
            (LinkStep::Stepped, Some(GateChange::Started))
        } else if !self.down {
            (LinkStep::Stepped, None)
        } else if self.scratch == self.last || !d.flagged().is_empty() {
            self.down = false;
            (LinkStep::Stepped, Some(GateChange::Resumed))
        } else if at_initial {
            self.down = false;
            (LinkStep::Restarted, Some(GateChange::Restarted))
        } else {
            return (LinkStep::Skipped, None);
        };
        std::mem::swap(&mut self.last, &mut self.scratch);
        result
    }
}

/// The signal values of every component in `frame` at t (bit i = signal i).
fn valuations(d: &Diagnosers, frame: &Frame, out: &mut Vec<u64>) {
    out.clear();
    out.extend(d.compiled.components.iter().map(|c| {
        c.signals.iter().enumerate().fold(0_u64, |acc, (i, s)| {
            let bit = frame.now(s.var.space).get(s.var.index as usize);
            acc | (u64::from(bit) << i)
        })
    }));
}

/// True when every component shows, in `frame` at t, the signal values of its initial
/// state (inputs and applied outputs).
pub fn at_initial_state(d: &Diagnosers, frame: &Frame) -> bool {
    let mut v = Vec::new();
    valuations(d, frame, &mut v);
    d.compiled
        .components
        .iter()
        .zip(&v)
        .all(|(c, v)| c.values.get(c.initial) == Some(v))
}

/// Runs `step` of a live link's diagnosers on `frame` (inputs and applied outputs at t
/// and t-1, auxiliaries written at t).
pub fn run_link_step(
    d: &mut Diagnosers,
    step: LinkStep,
    now: Millis,
    frame: &mut Frame,
    held: bool,
) {
    match step {
        LinkStep::Skipped => {}
        LinkStep::Stepped => d.update_held(now, frame, held),
        LinkStep::Restarted => {
            d.reset();
            d.update_held(now, frame, held);
        }
    }
}
