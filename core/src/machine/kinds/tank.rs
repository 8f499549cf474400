//! A tank: a level filled and emptied by flows the outputs drive, read by level
//! sensors. It covers a vessel with its pumps and valves (seed 000's liquid supply), a
//! hopper or a buffer (any quantity that flows in and out).
//!
//! # Model
//!
//! The level changes at the sum of the active flows' rates (a flow is active while its
//! expression over the applied outputs holds; positive rates fill). An inflow into a
//! full tank stops there and, with `overflow: Crash`, spills (a hazard); an outflow
//! from an empty tank stops and, with `dry_run: Crash`, runs its pump dry (a hazard). A
//! flow sensor in series with a flow (`sensor`) is on while that flow really runs: not
//! blocked by a fault, not stopped by a full or an empty tank. A level sensor is on
//! while the level is within its window. `Blocked` (a pipe blocked) stops every flow;
//! `Slowed` scales them.
//!
//! Levels are kept in millionths of the unit, rates in millionths per ms: exact
//! integer arithmetic, deterministic.

use super::axis::{EndStop, WindowDef};
use super::{ComponentFaults, StepCtx};
use crate::diag::{Problem, codes};
use crate::expr::{Dnf, eval_dnf, parse_str, simplify};
use crate::machine::HazardKind;
use crate::machine::derive::AxisGeometry;
use crate::machine::scene::{SceneDrive, SceneElement, SceneSensor, Shape};
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};

const MICRO: f64 = 1e6;

/// A flow: while `when` holds, `rate` units per second go into the tank (out of it
/// when negative).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlowDef {
    /// The condition over the outputs (`M1 . V1`).
    pub when: String,
    /// Units per second, signed: positive fills.
    pub rate: f64,
    /// A flow sensor in series, on while this flow really runs.
    #[serde(default)]
    pub sensor: Option<String>,
}

/// A tank's parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TankDef {
    /// The unit of levels and rates (`l`, `m3`, `kg`).
    #[serde(default = "litre")]
    pub unit: String,
    /// The level at which it is full.
    pub capacity: f64,
    /// The level at the emulator's start.
    pub start: f64,
    /// The flows.
    pub flows: Vec<FlowDef>,
    /// The level sensors.
    pub sensors: Vec<WindowDef>,
    /// An inflow into a full tank: `Crash` spills (a hazard), `Rest` stops.
    #[serde(default)]
    pub overflow: EndStop,
    /// An outflow from an empty tank: `Crash` runs its pump dry (a hazard), `Rest` stops.
    #[serde(default)]
    pub dry_run: EndStop,
    /// Extra tolerance of the derived elementary actions' ΔT, ms.
    #[serde(default)]
    pub tolerance_ms: u64,
    /// Each flow's rate varies within this many millionths of nominal, per start.
    #[serde(default)]
    pub variation_ppm: u32,
}

fn litre() -> String {
    "l".to_string()
}

impl TankDef {
    pub(super) fn check(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !(self.capacity.is_finite() && self.capacity > 0.0 && self.capacity < 1e9) {
            out.push(format!("its capacity {} must be above 0", self.capacity));
        } else if !(0.0..=self.capacity).contains(&self.start) {
            out.push(format!(
                "its start level {} is outside [0, {}]",
                self.start, self.capacity
            ));
        }
        for f in &self.flows {
            if !f.rate.is_finite() || f.rate == 0.0 || f.rate.abs() > 1e6 {
                out.push(format!(
                    "flow `{}` has rate {}: from -1e6 to 1e6 units/s, not 0",
                    f.when, f.rate
                ));
            }
        }
        for s in &self.sensors {
            if !(s.from.is_finite() && s.to.is_finite()) || s.from > s.to {
                out.push(format!(
                    "sensor `{}` has an empty window [{}, {}]",
                    s.signal, s.from, s.to
                ));
            }
        }
        out.extend(super::check_variation(self.variation_ppm, "rate"));
        out
    }

    pub(super) fn signals(&self) -> Vec<(&str, Space)> {
        self.sensors
            .iter()
            .map(|s| s.signal.as_str())
            .chain(self.flows.iter().filter_map(|f| f.sensor.as_deref()))
            .map(|s| (s, Space::Input))
            .collect()
    }

    pub(super) fn expressions(&self) -> Vec<&str> {
        self.flows.iter().map(|f| f.when.as_str()).collect()
    }
}

/// A compiled flow.
#[derive(Clone, Debug)]
struct Flow {
    when: String,
    dnf: Dnf,
    /// Millionths of the unit per ms.
    rate: i64,
    sensor: Option<usize>,
    /// The flow sensor's signal, for the synoptic.
    sensor_id: Option<String>,
    outputs: Vec<String>,
    /// Running now (after faults and the tank's bounds), and its drawn factor.
    running: bool,
    active: bool,
    factor_ppm: i64,
}

/// A tank's live state.
#[derive(Clone, Debug)]
pub struct Tank {
    unit: String,
    capacity: i64,
    level: i64,
    flows: Vec<Flow>,
    windows: Vec<(usize, String, i64, i64)>,
    overflow: EndStop,
    dry_run: EndStop,
    tolerance_ms: u64,
    variation_ppm: i64,
    spilling: bool,
    dry: bool,
    blocked: bool,
}

fn micro(v: f64) -> i64 {
    (v * MICRO).round() as i64
}

impl Tank {
    pub(super) fn new(id: &str, def: &TankDef, symbols: &Symbols) -> Result<Self, Problem> {
        let bad = |m: String| Problem::error(codes::COMPONENTS_EXPRESSION.id, m, None);
        let input = |s: &str| match symbols.lookup(s) {
            Some((Space::Input, i)) => Ok(i as usize),
            _ => Err(Problem::error(
                codes::COMPONENTS_UNKNOWN_SIGNAL.id,
                format!("`{id}` names sensor `{s}`, not a plant input"),
                None,
            )),
        };
        let mut flows = Vec::new();
        for f in &def.flows {
            let expr = parse_str(&f.when)
                .map_err(|e| bad(format!("`{id}`: flow `{}`: {}", f.when, e.message)))?;
            let outputs = expr
                .leaves()
                .into_iter()
                .map(|(n, _, _)| n.to_string())
                .collect();
            let dnf = expr
                .to_dnf(symbols)
                .map_err(|e| bad(format!("`{id}`: flow `{}`: {}", f.when, e.message)))?;
            flows.push(Flow {
                when: f.when.clone(),
                dnf: simplify(&dnf),
                rate: micro(f.rate / 1000.0),
                sensor: f.sensor.as_deref().map(input).transpose()?,
                sensor_id: f.sensor.clone(),
                outputs,
                running: false,
                active: false,
                factor_ppm: 1_000_000,
            });
        }
        let mut windows = Vec::new();
        for w in &def.sensors {
            windows.push((
                input(&w.signal)?,
                w.signal.clone(),
                micro(w.from),
                micro(w.to),
            ));
        }
        Ok(Self {
            unit: def.unit.clone(),
            capacity: micro(def.capacity),
            level: micro(def.start),
            flows,
            windows,
            overflow: def.overflow,
            dry_run: def.dry_run,
            tolerance_ms: def.tolerance_ms,
            variation_ppm: i64::from(def.variation_ppm),
            spilling: false,
            dry: false,
            blocked: false,
        })
    }

    pub(super) fn step(&mut self, ctx: &mut StepCtx<'_>, faults: ComponentFaults) {
        self.blocked = faults.blocked;
        let mut net = 0i64;
        let (mut into_full, mut out_of_empty) = (Vec::new(), Vec::new());
        for f in &mut self.flows {
            let active = eval_dnf(&f.dnf, ctx.frame);
            if active && !f.active {
                f.factor_ppm = if self.variation_ppm > 0 {
                    let span = 2 * self.variation_ppm as u64 + 1;
                    1_000_000 - self.variation_ppm + ctx.rng.below(span) as i64
                } else {
                    1_000_000
                };
            }
            f.active = active;
            let stopped_by_bound =
                (f.rate > 0 && self.level >= self.capacity) || (f.rate < 0 && self.level <= 0);
            if active && stopped_by_bound {
                if f.rate > 0 {
                    into_full.extend(f.outputs.iter().cloned());
                } else {
                    out_of_empty.extend(f.outputs.iter().cloned());
                }
            }
            f.running = active && !faults.blocked && !stopped_by_bound;
            if f.running {
                net += f.rate * f.factor_ppm / 1_000_000 * i64::from(faults.speed_percent) / 100;
            }
        }
        let spilling = !into_full.is_empty() && self.overflow == EndStop::Crash;
        if spilling && !self.spilling {
            ctx.hazards.push((HazardKind::Overflow, sorted(into_full)));
        }
        self.spilling = spilling;
        let dry = !out_of_empty.is_empty() && self.dry_run == EndStop::Crash;
        if dry && !self.dry {
            ctx.hazards.push((HazardKind::DryRun, sorted(out_of_empty)));
        }
        self.dry = dry;
        self.level = (self.level + net * ctx.dt as i64).clamp(0, self.capacity);
    }

    pub(super) fn idle(&self) -> bool {
        self.flows.iter().all(|f| !f.active)
    }

    pub(super) fn sense(&self, sensors: &mut crate::bits::Bits) {
        for &(i, _, from, to) in &self.windows {
            sensors.set(i, (from..=to).contains(&self.level));
        }
        for f in &self.flows {
            if let Some(i) = f.sensor {
                sensors.set(i, f.running);
            }
        }
    }

    pub(super) fn level(&self) -> f64 {
        self.level as f64 / MICRO
    }

    pub(super) fn set_level(&mut self, level: f64) {
        self.level = micro(level).clamp(0, self.capacity);
    }

    pub(super) fn scene(&self, id: &str, name: &str) -> SceneElement {
        let f = |v: i64| v as f64 / MICRO;
        SceneElement {
            id: id.to_string(),
            name: name.to_string(),
            shape: Shape::Tank {
                unit: self.unit.clone(),
                capacity: f(self.capacity),
                level: f(self.level),
                sensors: self
                    .windows
                    .iter()
                    .map(|(_, s, a, b)| SceneSensor {
                        signal: s.clone(),
                        from: f(*a),
                        to: f(*b),
                    })
                    .collect(),
                flows: self
                    .flows
                    .iter()
                    .map(|fl| SceneDrive {
                        when: fl.when.clone(),
                        speed: fl.rate as f64 * 1000.0 / MICRO,
                        sensor: fl.sensor_id.clone(),
                    })
                    .collect(),
                running: self.flows.iter().map(|fl| fl.running).collect(),
            },
        }
    }

    /// The level sensors and flows as an axis, for the derived elementary actions.
    pub(crate) fn geometry(&self, component: &str) -> AxisGeometry {
        let f = |v: i64| v as f64 / MICRO;
        AxisGeometry {
            component: component.to_string(),
            variation_ppm: u32::try_from(self.variation_ppm).unwrap_or(0),
            tolerance_ms: self.tolerance_ms,
            drives: self
                .flows
                .iter()
                .map(|fl| (fl.when.clone(), fl.rate as f64 * 1000.0 / MICRO))
                .collect(),
            windows: self
                .windows
                .iter()
                .map(|(_, s, a, b)| (s.clone(), f(*a), f(*b)))
                .collect(),
        }
    }
}

fn sorted(mut v: Vec<String>) -> Vec<String> {
    v.sort();
    v.dedup();
    v
}
