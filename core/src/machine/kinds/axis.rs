//! An axis: one degree of freedom driven by outputs and read by position sensors.
//!
//! It covers most actuated mechanisms of a machine: a single- or double-acting
//! cylinder (a monostable one returns when its output is OFF: a drive `when: "/Y1"`),
//! a lift, a stopper or gate, a drill head with two speeds, a rotary table with any
//! number of positions (`unit: "deg"`), a valve or a breaker (a short travel).
//!
//! # Model
//!
//! The position moves at the speed of the active drives: a drive is active while its
//! expression over the applied outputs holds. Several drives in one direction give the
//! fastest (a two-speed motor); drives in both directions at once hold the axis and
//! are a hazard (a motor driven both ways, a cylinder pressurised on both sides). The
//! travel ends at `min` and `max`: an axis driven into an end that says `Crash`
//! (`end_stops: (max: Crash)`)
//! damages the machine (a drill head into its fixture); with `Rest` it stops there (a
//! cylinder against its cushion). Each move (a new direction) draws its speed within
//! `± variation_ppm` of nominal from the emulator's seed. A sensor is on while the
//! position is within its window `[from, to]`.
//!
//! Positions are kept in millionths of the unit and speeds in millionths per ms, so
//! the model is exact integer arithmetic, deterministic for a seed.

use super::{ComponentFaults, StepCtx};
use crate::diag::{Problem, codes};
use crate::expr::{Dnf, eval_dnf, parse_str, simplify};
use crate::machine::HazardKind;
use crate::machine::derive::AxisGeometry;
use crate::machine::scene::{SceneDrive, SceneElement, SceneSensor, Shape};
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};

/// Millionths of the unit per unit.
const MICRO: f64 = 1e6;

/// What an end of the travel does to an axis driven into it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum EndStop {
    /// It rests there, no harm (a cylinder's end cushion).
    #[default]
    Rest,
    /// Driven into it, the machine is damaged (a head into its fixture).
    Crash,
}

/// What each end of the travel does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EndStops {
    /// At `min`.
    #[serde(default)]
    pub min: EndStop,
    /// At `max`.
    #[serde(default)]
    pub max: EndStop,
}

/// A drive: while `when` holds over the applied outputs, the axis moves at `speed`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveDef {
    /// The condition, in the logic notation over outputs (`DGV`, `/Y1`, `KM1 . /KM2`).
    pub when: String,
    /// Units per second, signed: positive towards `max`.
    pub speed: f64,
}

/// A position sensor: on while the axis is within `[from, to]`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindowDef {
    /// The plant input it writes.
    pub signal: String,
    /// Start of the window, in the unit.
    pub from: f64,
    /// End of the window.
    pub to: f64,
}

/// An axis's parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisDef {
    /// The unit of positions and speeds, for display (`mm`, `deg`).
    #[serde(default = "mm")]
    pub unit: String,
    /// Start of the travel.
    pub min: f64,
    /// End of the travel.
    pub max: f64,
    /// Position at the emulator's start.
    pub start: f64,
    /// The drives, in any order.
    pub drives: Vec<DriveDef>,
    /// The position sensors.
    pub sensors: Vec<WindowDef>,
    /// Each move's speed varies within this many millionths of nominal.
    #[serde(default)]
    pub variation_ppm: u32,
    /// What the ends of the travel do.
    #[serde(default)]
    pub end_stops: EndStops,
    /// Extra tolerance added to the derived elementary actions' ΔT, ms (the sensors'
    /// response, the PLC's scan).
    #[serde(default)]
    pub tolerance_ms: u64,
    /// A sensor on while the axis really moves (an encoder, a motion detector: the
    /// thesis's logic sensor of an interruptible task).
    #[serde(default)]
    pub motion: Option<String>,
    /// How the synoptic draws it: a carriage on its guide (the default), or a
    /// switching device.
    #[serde(default)]
    pub symbol: AxisSymbol,
}

/// How the synoptic draws an axis: one symbol per kind of device, not per plant.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum AxisSymbol {
    /// A carriage on its guide with its position written: a cylinder, a lift, a drill
    /// head, a robot's or a gantry's axis.
    #[default]
    Carriage,
    /// A two-position switching device on its line (a circuit breaker, a recloser, a
    /// contactor, an on-off valve): closed at `max`, open at `min`; drawn as the
    /// one-line diagram's square, filled when closed, hollow when open, dashed on the
    /// way, with its state written.
    Switch,
}

fn mm() -> String {
    "mm".to_string()
}

impl AxisDef {
    pub(super) fn check(&self) -> Vec<String> {
        let mut out = Vec::new();
        let finite = [self.min, self.max, self.start]
            .iter()
            .all(|v| v.is_finite() && v.abs() < 1e9);
        if !finite || self.min >= self.max {
            out.push(format!(
                "its travel [{}, {}] must be finite and not empty",
                self.min, self.max
            ));
        } else if self.start < self.min || self.start > self.max {
            out.push(format!(
                "its start {} is outside its travel [{}, {}]",
                self.start, self.min, self.max
            ));
        }
        for d in &self.drives {
            if !d.speed.is_finite() || d.speed == 0.0 || d.speed.abs() > 1e6 {
                out.push(format!(
                    "drive `{}` has speed {}: from -1e6 to 1e6 units/s, not 0",
                    d.when, d.speed
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
        out.extend(super::check_variation(self.variation_ppm, "speed"));
        out
    }

    pub(super) fn signals(&self) -> Vec<(&str, Space)> {
        self.sensors
            .iter()
            .map(|s| s.signal.as_str())
            .chain(self.motion.as_deref())
            .map(|s| (s, Space::Input))
            .collect()
    }

    pub(super) fn expressions(&self) -> Vec<&str> {
        self.drives.iter().map(|d| d.when.as_str()).collect()
    }
}

/// A compiled drive.
#[derive(Clone, Debug)]
struct Drive {
    when: String,
    dnf: Dnf,
    /// Millionths of the unit per ms.
    speed: i64,
    /// The outputs it reads, for hazards.
    outputs: Vec<String>,
}

/// An axis's live state.
#[derive(Clone, Debug)]
pub struct Axis {
    unit: String,
    min: i64,
    max: i64,
    pos: i64,
    drives: Vec<Drive>,
    windows: Vec<(usize, String, i64, i64)>,
    variation_ppm: i64,
    tolerance_ms: u64,
    end_stops: EndStops,
    /// Direction of the current move (-1, 0, 1) and its drawn speed factor, ppm.
    dir: i64,
    factor_ppm: i64,
    /// Hazards in force (reported once per onset).
    opposed: bool,
    at_end: bool,
    blocked: bool,
    /// The motion sensor's input, and whether it moved in the last step.
    motion: Option<usize>,
    motion_id: Option<String>,
    moved: bool,
    symbol: AxisSymbol,
}

fn micro(v: f64) -> i64 {
    (v * MICRO).round() as i64
}

impl Axis {
    pub(super) fn new(id: &str, def: &AxisDef, symbols: &Symbols) -> Result<Self, Problem> {
        let bad = |m: String| Problem::error(codes::COMPONENTS_EXPRESSION.id, m, None);
        let mut drives = Vec::new();
        for d in &def.drives {
            let expr = parse_str(&d.when)
                .map_err(|e| bad(format!("`{id}`: drive `{}`: {}", d.when, e.message)))?;
            let outputs = expr
                .leaves()
                .into_iter()
                .map(|(n, _, _)| n.to_string())
                .collect();
            let dnf = expr
                .to_dnf(symbols)
                .map_err(|e| bad(format!("`{id}`: drive `{}`: {}", d.when, e.message)))?;
            drives.push(Drive {
                when: d.when.clone(),
                dnf: simplify(&dnf),
                // Units per second are millionths per ms, times 1000 / 1000.
                speed: micro(d.speed / 1000.0),
                outputs,
            });
        }
        let mut windows = Vec::new();
        for w in &def.sensors {
            let Some((Space::Input, i)) = symbols.lookup(&w.signal) else {
                return Err(Problem::error(
                    codes::COMPONENTS_UNKNOWN_SIGNAL.id,
                    format!("`{id}` names sensor `{}`, not a plant input", w.signal),
                    None,
                ));
            };
            windows.push((i as usize, w.signal.clone(), micro(w.from), micro(w.to)));
        }
        let motion = match def.motion.as_deref() {
            Some(m) => match symbols.lookup(m) {
                Some((Space::Input, i)) => Some(i as usize),
                _ => {
                    return Err(Problem::error(
                        codes::COMPONENTS_UNKNOWN_SIGNAL.id,
                        format!("`{id}` names motion sensor `{m}`, not a plant input"),
                        None,
                    ));
                }
            },
            None => None,
        };
        Ok(Self {
            unit: def.unit.clone(),
            min: micro(def.min),
            max: micro(def.max),
            pos: micro(def.start),
            drives,
            windows,
            variation_ppm: i64::from(def.variation_ppm),
            tolerance_ms: def.tolerance_ms,
            end_stops: def.end_stops,
            dir: 0,
            factor_ppm: 1_000_000,
            opposed: false,
            at_end: false,
            blocked: false,
            motion,
            motion_id: def.motion.clone(),
            moved: false,
            symbol: def.symbol,
        })
    }

    /// The signed speed the active drives ask for (0 when none, or when opposed), and
    /// whether drives oppose.
    fn asked(&self, frame: &crate::frame::Frame) -> (i64, bool, Vec<usize>) {
        let mut best = 0i64;
        let (mut up, mut down) = (false, false);
        let mut active = Vec::new();
        for (k, d) in self.drives.iter().enumerate() {
            if eval_dnf(&d.dnf, frame) {
                active.push(k);
                up |= d.speed > 0;
                down |= d.speed < 0;
                if d.speed.abs() > best.abs() {
                    best = d.speed;
                }
            }
        }
        if up && down {
            (0, true, active)
        } else {
            (best, false, active)
        }
    }

    pub(super) fn step(&mut self, ctx: &mut StepCtx<'_>, faults: ComponentFaults) {
        let (speed, opposed, active) = self.asked(ctx.frame);
        let outputs = |drives: &[Drive]| -> Vec<String> {
            let mut o: Vec<String> = active
                .iter()
                .flat_map(|&k| drives[k].outputs.iter().cloned())
                .collect();
            o.sort();
            o.dedup();
            o
        };
        if opposed && !self.opposed {
            ctx.hazards
                .push((HazardKind::OpposedDrives, outputs(&self.drives)));
        }
        self.opposed = opposed;
        self.blocked = faults.blocked;
        let dir = speed.signum();
        if dir != self.dir {
            self.dir = dir;
            self.factor_ppm = super::run_factor(dir, self.variation_ppm, ctx.rng);
        }
        let v = if faults.blocked || faults.stuck_at == Some(self.pos) {
            0
        } else {
            speed * self.factor_ppm / 1_000_000 * i64::from(faults.speed_percent) / 100
        };
        let next = self.pos + v * ctx.dt as i64;
        let clamped = next.clamp(self.min, self.max);
        let into_end = dir != 0 && ((dir > 0 && next >= self.max) || (dir < 0 && next <= self.min));
        let end = if dir > 0 {
            self.end_stops.max
        } else {
            self.end_stops.min
        };
        if into_end && !self.at_end && end == EndStop::Crash && !faults.blocked {
            ctx.hazards
                .push((HazardKind::EndStop, outputs(&self.drives)));
        }
        self.at_end = into_end;
        self.moved = clamped != self.pos;
        self.pos = clamped;
    }

    pub(super) fn idle(&self) -> bool {
        self.dir == 0 && !self.opposed
    }

    pub(super) fn sense(&self, sensors: &mut crate::bits::Bits) {
        for &(i, _, from, to) in &self.windows {
            sensors.set(i, (from..=to).contains(&self.pos));
        }
        if let Some(i) = self.motion {
            sensors.set(i, self.moved);
        }
    }

    pub(super) fn position(&self) -> f64 {
        self.pos as f64 / MICRO
    }

    pub(super) fn set_position(&mut self, position: f64) {
        self.pos = micro(position).clamp(self.min, self.max);
    }

    pub(super) fn scene(&self, id: &str, name: &str) -> SceneElement {
        let f = |v: i64| v as f64 / MICRO;
        SceneElement {
            id: id.to_string(),
            name: name.to_string(),
            shape: Shape::Axis {
                symbol: self.symbol,
                unit: self.unit.clone(),
                min: f(self.min),
                max: f(self.max),
                position: f(self.pos),
                direction: if self.blocked { 0 } else { self.dir as i8 },
                sensors: self
                    .windows
                    .iter()
                    .map(|(_, s, a, b)| SceneSensor {
                        signal: s.clone(),
                        from: f(*a),
                        to: f(*b),
                    })
                    .collect(),
                drives: self
                    .drives
                    .iter()
                    .map(|d| SceneDrive {
                        when: d.when.clone(),
                        speed: d.speed as f64 * 1000.0 / MICRO,
                        sensor: None,
                    })
                    .collect(),
                motion: self.motion_id.clone(),
            },
        }
    }

    /// What the elementary actions are derived from.
    pub(crate) fn geometry(&self, component: &str) -> AxisGeometry {
        let f = |v: i64| v as f64 / MICRO;
        AxisGeometry {
            component: component.to_string(),
            variation_ppm: u32::try_from(self.variation_ppm).unwrap_or(0),
            tolerance_ms: self.tolerance_ms,
            drives: self
                .drives
                .iter()
                .map(|d| (d.when.clone(), d.speed as f64 * 1000.0 / MICRO))
                .collect(),
            windows: self
                .windows
                .iter()
                .map(|(_, s, a, b)| (s.clone(), f(*a), f(*b)))
                .collect(),
        }
    }
}
