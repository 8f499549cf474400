//! Fault injection: what can go wrong in the plant, and when.
//!
//! Faults are data (they appear in scenario RON files). A fault starts at a time
//! (`At(ms)`) or the first time a condition in the logic notation holds over the plant
//! signals (`When("C3 . /C4")`), and lasts `duration_ms` (forever when `None`).

use crate::diag::Problem;
use crate::diag::codes;
use crate::expr::{Dnf, eval_dnf, parse_str, simplify};
use crate::frame::Frame;
use crate::symbols::Symbols;
use serde::{Deserialize, Serialize};

/// A position along a component's travel, in its unit (a finite number).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Position(pub f64);

// Positions are finite (checked where they are used): equality is reflexive.
impl Eq for Position {}

/// When a fault starts.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Trigger {
    /// At this simulated time, ms.
    At(u64),
    /// The first internal step where this expression over sensors and actuators holds.
    When(String),
}

/// What goes wrong.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum FaultKind {
    /// The sensor reads 0 whatever happens.
    SensorStuckAt0(String),
    /// The sensor reads 1 whatever happens.
    SensorStuckAt1(String),
    /// The sensor reads 1 for `pulse_ms`.
    SpuriousRise {
        /// Sensor id.
        sensor: String,
        /// Pulse length, ms.
        pulse_ms: u64,
    },
    /// The sensor reads 0 for `pulse_ms`.
    SpuriousFall {
        /// Sensor id.
        sensor: String,
        /// Pulse length, ms.
        pulse_ms: u64,
    },
    /// The actuator does nothing even when commanded.
    ActuatorStuckOff(String),
    /// The actuator acts even when not commanded.
    ActuatorStuckOn(String),
    /// The component cannot leave `position` (in its unit) once it is there: a
    /// turntable jammed at a position, a cylinder seized at an end.
    StuckAt {
        /// Component id.
        component: String,
        /// The position, in the component's unit.
        position: Position,
    },
    /// The component cannot move (a seized axis, a jammed mechanism; on the sorting
    /// station's layout, the turntable id blocks the table where it is).
    Blocked(String),
    /// The component moves at `percent` of its speed (on a layout, a conveyor id).
    Slowed {
        /// Component id.
        component: String,
        /// Remaining speed, percent.
        percent: u8,
    },
    /// The surface driven by `actuator` runs at `percent` of its speed.
    ConveyorSlowed {
        /// Actuator id of the conveyor or rollers.
        actuator: String,
        /// Remaining speed, percent.
        percent: u8,
    },
}

/// A fault and its schedule.
impl FaultKind {
    /// The fault as data, for a console that tells it in its own words: `fault`
    /// (`stuck-at-0`, `stuck-at-1`, `spurious-rise`, `spurious-fall`, `actuator-off`,
    /// `actuator-on`, `stuck-at-position` (with `position`),
    /// `slowed`, and for a component as a whole `blocked`, `component-slowed`),
    /// `signal` or `component` where one is named, `ms` or `percent` where they apply.
    pub fn fields(&self) -> std::collections::BTreeMap<String, String> {
        let (tag, signal, n) = match self {
            Self::SensorStuckAt0(s) => ("stuck-at-0", s.as_str(), None),
            Self::SensorStuckAt1(s) => ("stuck-at-1", s.as_str(), None),
            Self::SpuriousRise { sensor, pulse_ms } => {
                ("spurious-rise", sensor.as_str(), Some(("ms", *pulse_ms)))
            }
            Self::SpuriousFall { sensor, pulse_ms } => {
                ("spurious-fall", sensor.as_str(), Some(("ms", *pulse_ms)))
            }
            Self::ActuatorStuckOff(a) => ("actuator-off", a.as_str(), None),
            Self::ActuatorStuckOn(a) => ("actuator-on", a.as_str(), None),
            Self::StuckAt { component, .. } => ("stuck-at-position", component.as_str(), None),
            Self::Blocked(c) => ("blocked", c.as_str(), None),
            Self::Slowed { component, percent } => (
                "component-slowed",
                component.as_str(),
                Some(("percent", u64::from(*percent))),
            ),
            Self::ConveyorSlowed { actuator, percent } => (
                "slowed",
                actuator.as_str(),
                Some(("percent", u64::from(*percent))),
            ),
        };
        let mut f = std::collections::BTreeMap::new();
        f.insert("fault".to_string(), tag.to_string());
        let whole = matches!(
            self,
            Self::Blocked(_) | Self::Slowed { .. } | Self::StuckAt { .. }
        );
        if !signal.is_empty() {
            let key = if whole { "component" } else { "signal" };
            f.insert(key.to_string(), signal.to_string());
        }
        if let Some((k, v)) = n {
            f.insert(k.to_string(), v.to_string());
        }
        if let Self::StuckAt { position, .. } = self {
            f.insert("position".to_string(), position.0.to_string());
        }
        f
    }
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// When it starts.
    pub trigger: Trigger,
    /// What it does.
    pub fault: FaultKind,
    /// How long it lasts, ms; `None` for ever (spurious pulses use `pulse_ms`).
    #[serde(default)]
    pub duration_ms: Option<u64>,
}

/// A fault resolved against the plant: indices instead of ids.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Effect {
    /// Force layout sensor `.0` to `.1`.
    Sensor(u32, bool),
    /// Force actuator role `.0` to `.1`.
    Actuator(u32, bool),
    /// Drive role `.0` slowed to `.1` percent.
    Slow(u32, u8),
    /// Component `.0` of a components plant blocked.
    Block(u32),
    /// Component `.0` of a components plant slowed to `.1` percent.
    SlowComponent(u32, u8),
    /// Component `.0` of a components plant cannot leave its position `.1`
    /// (millionths of its unit) once there.
    StuckAt(u32, i64),
}

/// State of a scheduled fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Phase {
    Pending,
    Active { until: Option<u64> },
    Over,
}

/// A scheduled fault.
#[derive(Clone, Debug)]
pub(crate) struct Scheduled {
    pub(crate) spec: FaultSpec,
    pub(crate) effect: Effect,
    pub(crate) condition: Option<Dnf>,
    pub(crate) length: Option<u64>,
    pub(crate) phase: Phase,
}

impl Scheduled {
    /// Resolves ids with `sensor_index` / `actuator_role`, the faults of a component
    /// as a whole with `component` (`None`: the plant has no such component), and
    /// parses a condition.
    pub(crate) fn new(
        spec: FaultSpec,
        sensor_index: impl Fn(&str) -> Option<u32>,
        actuator_role: impl Fn(&str) -> Option<u32>,
        component: impl Fn(&FaultKind) -> Option<Effect>,
        symbols: &Symbols,
    ) -> Result<Self, Problem> {
        let unknown = |what: &str, id: &str| {
            Problem::error(
                codes::FAULT_UNKNOWN_SIGNAL.id,
                format!("fault names unknown {what} `{id}`"),
                None,
            )
        };
        let sensor = |id: &str| sensor_index(id).ok_or_else(|| unknown("sensor", id));
        let actuator = |id: &str| actuator_role(id).ok_or_else(|| unknown("actuator", id));
        let whole = |k: &FaultKind, id: &str| {
            component(k).ok_or_else(|| {
                Problem::error(
                    codes::FAULT_UNKNOWN_COMPONENT.id,
                    match k {
                        FaultKind::StuckAt { position, .. } => format!(
                            "fault names unknown component `{id}`, or one that cannot \
                             stop at {}",
                            position.0
                        ),
                        _ => format!("fault names unknown component `{id}`"),
                    },
                    None,
                )
            })
        };
        let (effect, length) = match &spec.fault {
            FaultKind::SensorStuckAt0(s) => (Effect::Sensor(sensor(s)?, false), spec.duration_ms),
            FaultKind::SensorStuckAt1(s) => (Effect::Sensor(sensor(s)?, true), spec.duration_ms),
            FaultKind::SpuriousRise {
                sensor: s,
                pulse_ms,
            } => (Effect::Sensor(sensor(s)?, true), Some(*pulse_ms)),
            FaultKind::SpuriousFall {
                sensor: s,
                pulse_ms,
            } => (Effect::Sensor(sensor(s)?, false), Some(*pulse_ms)),
            FaultKind::ActuatorStuckOff(a) => {
                (Effect::Actuator(actuator(a)?, false), spec.duration_ms)
            }
            FaultKind::ActuatorStuckOn(a) => {
                (Effect::Actuator(actuator(a)?, true), spec.duration_ms)
            }
            k @ (FaultKind::Blocked(c)
            | FaultKind::Slowed { component: c, .. }
            | FaultKind::StuckAt { component: c, .. }) => (whole(k, c)?, spec.duration_ms),
            FaultKind::ConveyorSlowed {
                actuator: a,
                percent,
            } => (Effect::Slow(actuator(a)?, *percent), spec.duration_ms),
        };
        let condition = match &spec.trigger {
            Trigger::At(_) => None,
            Trigger::When(text) => {
                let bad = |e: crate::expr::ExprError| {
                    Problem::error(
                        codes::FAULT_CONDITION_INVALID.id,
                        format!(
                            "fault condition `{text}`, column {}: {}",
                            e.span.column, e.message
                        ),
                        None,
                    )
                };
                let expr = parse_str(text).map_err(bad)?;
                Some(simplify(&expr.to_dnf(symbols).map_err(bad)?))
            }
        };
        Ok(Self {
            spec,
            effect,
            condition,
            length,
            phase: Phase::Pending,
        })
    }

    /// Advances the phase at time `now`; true when it changed.
    pub(crate) fn update(&mut self, now: u64, frame: &Frame) -> bool {
        match self.phase {
            Phase::Pending => {
                let start = match (&self.spec.trigger, &self.condition) {
                    (Trigger::At(t), _) => now >= *t,
                    (Trigger::When(_), Some(dnf)) => eval_dnf(dnf, frame),
                    (Trigger::When(_), None) => false,
                };
                if start {
                    self.phase = Phase::Active {
                        until: self.length.map(|l| now.saturating_add(l)),
                    };
                }
                start
            }
            Phase::Active { until: Some(u) } if now >= u => {
                self.phase = Phase::Over;
                true
            }
            _ => false,
        }
    }
}
