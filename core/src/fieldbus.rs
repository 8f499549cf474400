//! A FIP-like fieldbus (seed 002, chapter 3): periodic variables polled by a bus
//! arbitrator from its scan table, and what their timing means for the data read.
//!
//! Each variable has one producer and its consumers. In each elementary cycle (µC) the
//! arbitrator polls the variables of its scan table one transaction after the other: an
//! identification frame `id_dat` (61 TMAC), the turnaround TR, the producer's answer
//! `rp_dat` (61 + 8·bytes TMAC), the turnaround again:
//! `TE = 2·TR + (8·bytes + 122)·TMAC`. The producer's buffer is sampled when it answers;
//! its consumers have the value at the end of the answer. Buffers are overwritten by
//! writes and not consumed by reads, so a consumer sees *samples at poll instants*.
//!
//! The µC is the greatest common divisor of the periods, the macro-cycle (MC) their
//! least common multiple; variable `i` is polled in µC `k` when
//! `(k − φ_i) mod (p_i / µC) = 0`. Its phase `φ_i` is given, or chosen by a greedy
//! balancer (shortest periods first, each at the phase that keeps the most loaded µC
//! least loaded). Written in RON (`bus.ron` beside the plant):
//!
//! ```ron
//! Bus(
//!     bit_rate: 1000000,      // bit/s: TMAC = 1 µs
//!     turnaround_us: 20,      // TR, 10 to 70 TMAC
//!     offset_us: 10000,       // the periodic window starts 10 ms into each µC
//!     variables: [
//!         (name: "DefDep_D1", period_us: 50000, bytes: 2, deadline_us: 100000, signals: ["def1_D2"]),
//!     ],
//! )
//! ```
//!
//! [`Analysis`] gives the scan table, each µC's load, and for each variable its best and
//! worst age at its consumers (from a change at the producer to the value there). A
//! variable's `deadline_us` (Δ: how old its value may be where it is used) bounds that
//! age; its `signals` are the plant inputs it delivers, whose live staleness bound is
//! then what remains of Δ once the bus has taken its worst case
//! ([`Analysis::input_bounds`]).

use crate::diag::codes;
use crate::diag::{Location, Problem};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

fn default_ratio() -> u64 {
    2
}

fn default_max_load() -> u64 {
    70
}

/// The bus as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Bus")]
pub struct BusFile {
    /// Bit rate in bit/s (31 250, 1 000 000, 2 500 000, 5 000 000 for FIP).
    pub bit_rate: u64,
    /// Turnaround time TR in µs, between 10 and 70 TMAC.
    pub turnaround_us: u64,
    /// Where the periodic window starts in each µC, in µs (0: at its start).
    #[serde(default)]
    pub offset_us: u64,
    /// r: a variable's period must be at most its deadline divided by r (2).
    #[serde(default = "default_ratio")]
    pub ratio: u64,
    /// A µC loaded above this percentage of its length is warned about (70).
    #[serde(default = "default_max_load")]
    pub max_load_percent: u64,
    /// The periodic variables, in the order of the scan table.
    pub variables: Vec<BusVariable>,
}

/// A periodic variable.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BusVariable {
    /// Its name, unique on the bus.
    pub name: String,
    /// How often the arbitrator polls it, in µs.
    pub period_us: u64,
    /// Its size in bytes.
    pub bytes: u64,
    /// Δ: how old its value may be at its consumers, in µs.
    #[serde(default)]
    pub deadline_us: Option<u64>,
    /// The µC of the first poll (0 ≤ φ < period / µC); chosen by the balancer when absent.
    #[serde(default)]
    pub phase: Option<u64>,
    /// The plant inputs it delivers (a consumer's image of it).
    #[serde(default)]
    pub signals: Vec<String>,
}

/// One variable as analysed (times in µs).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Polled {
    /// Its name.
    pub name: String,
    /// Its period.
    pub period_us: u64,
    /// Its phase, in µC.
    pub phase: u64,
    /// Its transaction time TE, in ns.
    pub transaction_ns: u64,
    /// From a change at the producer to the value at the consumers: at least (a change
    /// just before the producer answers), in ns.
    pub best_age_ns: u64,
    /// At most (a change just after it answered, seen at the next poll), in ns.
    pub worst_age_ns: u64,
    /// Its deadline Δ, if given.
    pub deadline_us: Option<u64>,
    /// The plant inputs it delivers.
    pub signals: Vec<String>,
}

/// The scan table and the timing of every variable.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Analysis {
    /// TMAC, the time of one bit, in ns.
    pub tmac_ns: u64,
    /// The µC, in µs.
    pub micro_cycle_us: u64,
    /// The macro-cycle, in µs.
    pub macro_cycle_us: u64,
    /// The variables, in the file's order.
    pub variables: Vec<Polled>,
    /// Per µC of the macro-cycle: the variables polled, in table order, with the start
    /// of their transaction from the start of the µC, in ns.
    pub table: Vec<Vec<(usize, u64)>>,
    /// Per µC: the time its periodic transactions take, in ns.
    pub load_ns: Vec<u64>,
    /// Warnings (a period above Δ/r, a µC loaded above the limit).
    pub warnings: Vec<Problem>,
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// The frame times of a transaction of `bytes` at `tmac_ns`: `id_dat`, `rp_dat`, in ns.
pub fn frames_ns(bytes: u64, tmac_ns: u64) -> (u64, u64) {
    (61 * tmac_ns, (61 + 8 * bytes) * tmac_ns)
}

/// The transaction time TE = 2·TR + (8·bytes + 122)·TMAC, in ns.
pub fn transaction_ns(bytes: u64, tmac_ns: u64, turnaround_ns: u64) -> u64 {
    2 * turnaround_ns + (8 * bytes + 122) * tmac_ns
}

impl BusFile {
    /// Loads a bus file.
    pub fn load(path: &Path) -> Result<(Self, String), Vec<Problem>> {
        crate::live::load_ron(path)
    }

    /// The analysis of this bus; `path` and `text` place the problems.
    pub fn analyse(&self, path: &Path, text: &str) -> Result<Analysis, Vec<Problem>> {
        let at = |needle: &str| Some(Location::of_nth(path, text, needle, 0));
        let mut errors = Vec::new();
        let bad = |errors: &mut Vec<Problem>, needle: &str, message: String| {
            errors.push(Problem::error(codes::BUS_INVALID.id, message, at(needle)));
        };
        if self.bit_rate == 0 || 1_000_000_000 % self.bit_rate != 0 {
            bad(
                &mut errors,
                "bit_rate",
                format!(
                    "bit_rate {} bit/s: a bit must last a whole number of ns (1 000 000 000 divisible by it)",
                    self.bit_rate
                ),
            );
            return Err(errors);
        }
        let tmac_ns = 1_000_000_000 / self.bit_rate;
        let tr_ns = self.turnaround_us * 1000;
        if tr_ns < 10 * tmac_ns || tr_ns > 70 * tmac_ns {
            bad(
                &mut errors,
                "turnaround_us",
                format!(
                    "turnaround {} µs: TR must be between 10 and 70 TMAC ({} to {} µs at {} bit/s)",
                    self.turnaround_us,
                    10 * tmac_ns / 1000,
                    70 * tmac_ns / 1000,
                    self.bit_rate
                ),
            );
        }
        let mut names = BTreeMap::new();
        for v in &self.variables {
            let needle = format!("\"{}\"", v.name);
            if names.insert(v.name.clone(), ()).is_some() {
                bad(
                    &mut errors,
                    &needle,
                    format!("variable `{}` declared twice", v.name),
                );
            }
            if v.period_us == 0 {
                bad(
                    &mut errors,
                    &needle,
                    format!("variable `{}`: a period of 0", v.name),
                );
            }
        }
        if self.variables.is_empty() {
            bad(&mut errors, "variables", "the bus has no variable".into());
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        let micro = self.variables.iter().map(|v| v.period_us).fold(0, gcd);
        let macro_us = self
            .variables
            .iter()
            .map(|v| v.period_us)
            .fold(micro, |l, p| l / gcd(l, p) * p);
        let k = usize::try_from(macro_us / micro).unwrap_or(usize::MAX);
        if k > 10_000 {
            bad(
                &mut errors,
                "variables",
                format!(
                    "the macro-cycle ({macro_us} µs) is {k} µC of {micro} µs: choose periods with a larger common divisor"
                ),
            );
            return Err(errors);
        }
        let te: Vec<u64> = self
            .variables
            .iter()
            .map(|v| transaction_ns(v.bytes, tmac_ns, tr_ns))
            .collect();
        let phases = self.phases(micro, k, &te, &mut errors, &at);
        if !errors.is_empty() {
            return Err(errors);
        }
        self.timing(tmac_ns, (micro, macro_us, k), &te, &phases, &at)
    }

    /// The phases: given, or chosen shortest periods first, each where the most loaded
    /// µC it occupies is least loaded.
    fn phases(
        &self,
        micro: u64,
        k: usize,
        te: &[u64],
        errors: &mut Vec<Problem>,
        at: &dyn Fn(&str) -> Option<Location>,
    ) -> Vec<u64> {
        let mut load = vec![0u64; k];
        let mut phases = vec![0u64; self.variables.len()];
        let mut order: Vec<usize> = (0..self.variables.len()).collect();
        // Given phases first, then the others by period.
        order.sort_by_key(|&i| {
            (
                self.variables[i].phase.is_none(),
                self.variables[i].period_us,
            )
        });
        for i in order {
            let v = &self.variables[i];
            let every = v.period_us / micro;
            let slots = |phi: u64| (0..k as u64).filter(move |m| m % every == phi);
            let phi = match v.phase {
                Some(phi) if phi < every => phi,
                Some(phi) => {
                    errors.push(Problem::error(
                        codes::BUS_INVALID.id,
                        format!(
                            "variable `{}`: phase {phi}, but it is polled every {every} µC (phase 0 to {})",
                            v.name,
                            every - 1
                        ),
                        at(&format!("\"{}\"", v.name)),
                    ));
                    continue;
                }
                None => (0..every)
                    .min_by_key(|&phi| {
                        slots(phi)
                            .map(|m| load[usize::try_from(m).unwrap_or(0)])
                            .max()
                            .unwrap_or(0)
                    })
                    .unwrap_or(0),
            };
            for m in slots(phi) {
                load[usize::try_from(m).unwrap_or(0)] += te[i];
            }
            phases[i] = phi;
        }
        phases
    }

    /// The table, the loads and every variable's ages.
    fn timing(
        &self,
        tmac_ns: u64,
        (micro, macro_us, k): (u64, u64, usize),
        te: &[u64],
        phases: &[u64],
        at: &dyn Fn(&str) -> Option<Location>,
    ) -> Result<Analysis, Vec<Problem>> {
        let micro_ns = micro * 1000;
        let mut table: Vec<Vec<(usize, u64)>> = vec![Vec::new(); k];
        let mut load_ns = vec![0u64; k];
        for (m, row) in table.iter_mut().enumerate() {
            let mut t = self.offset_us * 1000;
            for (i, v) in self.variables.iter().enumerate() {
                if (m as u64) % (v.period_us / micro) == phases[i] {
                    row.push((i, t));
                    t += te[i];
                    load_ns[m] += te[i];
                }
            }
        }
        let (mut errors, mut warnings) = (Vec::new(), Vec::new());
        for (m, &l) in load_ns.iter().enumerate() {
            if self.offset_us * 1000 + l > micro_ns {
                errors.push(Problem::error(
                    codes::BUS_OVERLOAD.id,
                    format!(
                        "µC {m}: its periodic transactions take {} µs from {} µs, longer than the µC ({micro} µs)",
                        l / 1000,
                        self.offset_us
                    ),
                    at("variables"),
                ));
            } else if l * 100 > micro_ns * self.max_load_percent {
                warnings.push(Problem::warning(
                    codes::BUS_LOAD_HIGH.id,
                    format!(
                        "µC {m} is loaded at {}% (more than {}%): little room is left for aperiodic traffic",
                        l * 100 / micro_ns,
                        self.max_load_percent
                    ),
                    at("variables"),
                ));
            }
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        let mut variables = Vec::new();
        for (i, v) in self.variables.iter().enumerate() {
            let (req, resp) = frames_ns(v.bytes, tmac_ns);
            let tr = self.turnaround_us * 1000;
            // Sampled when the producer answers, at the consumers at the end of it.
            let polls: Vec<u64> = table
                .iter()
                .enumerate()
                .filter_map(|(m, row)| {
                    row.iter()
                        .find(|(j, _)| *j == i)
                        .map(|(_, start)| m as u64 * micro_ns + start + req + tr)
                })
                .collect();
            let gap = polls
                .iter()
                .zip(polls.iter().cycle().skip(1))
                .map(|(a, b)| {
                    if b > a {
                        b - a
                    } else {
                        b + macro_us * 1000 - a
                    }
                })
                .max()
                .unwrap_or(macro_us * 1000);
            let worst = gap + resp;
            if let Some(d) = v.deadline_us
                && v.period_us * self.ratio > d
            {
                warnings.push(Problem::warning(
                    codes::BUS_PERIOD_DEADLINE.id,
                    format!(
                        "variable `{}`: period {} µs above its deadline / r = {d} / {} µs: the constraint P ≤ Δ/r is not respected",
                        v.name, v.period_us, self.ratio
                    ),
                    at(&format!("\"{}\"", v.name)),
                ));
            }
            variables.push(Polled {
                name: v.name.clone(),
                period_us: v.period_us,
                phase: phases[i],
                transaction_ns: te[i],
                best_age_ns: resp,
                worst_age_ns: worst,
                deadline_us: v.deadline_us,
                signals: v.signals.clone(),
            });
        }
        Ok(Analysis {
            tmac_ns,
            micro_cycle_us: micro,
            macro_cycle_us: macro_us,
            variables,
            table,
            load_ns,
            warnings,
        })
    }
}

impl Analysis {
    /// When a change at the producer at `change_ns` (from the start of the first µC) is
    /// at the consumers of variable `name`: at the end of the first answer sampled at or
    /// after it.
    pub fn delivered_ns(&self, name: &str, change_ns: u64, bus: &BusFile) -> Option<u64> {
        let i = self.variables.iter().position(|v| v.name == name)?;
        let v = &bus.variables[i];
        let (req, resp) = frames_ns(v.bytes, self.tmac_ns);
        let tr = bus.turnaround_us * 1000;
        let macro_ns = self.macro_cycle_us * 1000;
        let micro_ns = self.micro_cycle_us * 1000;
        let first = (change_ns / macro_ns).saturating_sub(1);
        (first..first + 3)
            .flat_map(|c| {
                self.table.iter().enumerate().filter_map(move |(m, row)| {
                    row.iter()
                        .find(|(j, _)| *j == i)
                        .map(|(_, s)| c * macro_ns + m as u64 * micro_ns + s + req + tr)
                })
            })
            .find(|&sample| sample >= change_ns)
            .map(|sample| sample + resp)
    }

    /// The staleness bound of each plant input a variable delivers: its deadline less
    /// its worst age on the bus, in ms (rounded down). A variable that delivers inputs
    /// must have a deadline its worst age leaves room in.
    pub fn input_bounds(
        &self,
        path: &Path,
        text: &str,
    ) -> Result<BTreeMap<String, u64>, Vec<Problem>> {
        let mut out = BTreeMap::new();
        let mut errors = Vec::new();
        for v in self.variables.iter().filter(|v| !v.signals.is_empty()) {
            let at = Some(Location::of_nth(path, text, &format!("\"{}\"", v.name), 0));
            let Some(d) = v.deadline_us else {
                errors.push(Problem::error(
                    codes::BUS_DEADLINE.id,
                    format!(
                        "variable `{}` delivers {} but has no deadline_us: how old may its value be?",
                        v.name,
                        v.signals.join(", ")
                    ),
                    at,
                ));
                continue;
            };
            let left_ms = (d * 1000).saturating_sub(v.worst_age_ns) / 1_000_000;
            if left_ms == 0 {
                errors.push(Problem::error(
                    codes::BUS_DEADLINE.id,
                    format!(
                        "variable `{}`: the bus delivers it up to {} µs after a change, which leaves less than 1 ms of its deadline ({d} µs) for the link",
                        v.name,
                        v.worst_age_ns / 1000
                    ),
                    at,
                ));
                continue;
            }
            for s in &v.signals {
                out.insert(s.clone(), left_ms);
            }
        }
        if errors.is_empty() {
            Ok(out)
        } else {
            Err(errors)
        }
    }
}

#[cfg(test)]
mod tests;
