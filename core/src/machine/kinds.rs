//! The library of component kinds: the one place that lists them.
//!
//! A kind is a file under `kinds/` with its parameters (deserialised from
//! `components.ron`) and its live state (built against the plant's signals). Adding a
//! kind is that file and one variant in each enum below; nothing else in the code
//! knows the kinds.

pub mod axis;
pub mod button;
pub mod conveyor;
pub mod detector;
pub mod link;
pub mod tank;
pub mod turntable;

use super::scene::SceneElement;
use crate::diag::Problem;
use crate::frame::Frame;
use crate::symbols::{Space, Symbols};
use crate::synthetic::SplitMix64;
use serde::{Deserialize, Serialize};

/// A component's kind and its parameters, as written in `components.ron`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum KindDef {
    /// One degree of freedom driven by outputs and read by position sensors: a
    /// cylinder, a lift, a stopper, a drill head, a rotary table, a valve, a breaker.
    Axis(axis::AxisDef),
    /// A push button of the operator's panel on a plant input.
    Button(button::ButtonDef),
    /// A belt carrying items between a feeder, beams and its exit end.
    Conveyor(conveyor::ConveyorDef),
    /// An input on when a condition has held for a time: a protection relay, a smart
    /// sensor with pre-confirmation, a debounced contact.
    Detector(detector::DetectorDef),
    /// A fieldbus variable: a consumer's copy of a signal, refreshed at poll instants.
    Link(link::LinkDef),
    /// A level filled and emptied by flows: a vessel with its pumps and valves.
    Tank(tank::TankDef),
    /// A roller surface on a rotary table with positions joining it to conveyors.
    Turntable(turntable::TurntableDef),
}

/// A component as a travel between two ends, driven by outputs and read by windows:
/// what the derived diagnosers model ([`super::diagnosers`]).
#[derive(Clone, Debug)]
pub struct Travel {
    /// The unit, for texts.
    pub unit: String,
    /// Start and end of the travel.
    pub min: f64,
    /// End of the travel.
    pub max: f64,
    /// Position at the start.
    pub start: f64,
    /// Drives: condition over outputs, signed speed in units/s (the fastest active
    /// drive moves it; opposed drives hold it).
    pub drives: Vec<(String, f64)>,
    /// Sensor windows: signal, from, to.
    pub windows: Vec<(String, f64, f64)>,
    /// Each move's speed varies within this many millionths.
    pub variation_ppm: u32,
    /// The sensors' response and the PLC's scan, ms.
    pub tolerance_ms: u64,
}

impl KindDef {
    /// The component as a travel, for the kinds that are one (an axis).
    pub fn travel(&self) -> Option<Travel> {
        match self {
            Self::Axis(a) => Some(Travel {
                unit: a.unit.clone(),
                min: a.min,
                max: a.max,
                start: a.start,
                drives: a.drives.iter().map(|d| (d.when.clone(), d.speed)).collect(),
                windows: a
                    .sensors
                    .iter()
                    .map(|w| (w.signal.clone(), w.from, w.to))
                    .collect(),
                variation_ppm: a.variation_ppm,
                tolerance_ms: a.tolerance_ms,
            }),
            Self::Button(_)
            | Self::Conveyor(_)
            | Self::Detector(_)
            | Self::Link(_)
            | Self::Tank(_)
            | Self::Turntable(_) => None,
        }
    }

    /// The kind's name in messages and on the synoptic.
    pub fn label(&self) -> &'static str {
        match self {
            Self::Axis(_) => "axis",
            Self::Button(_) => "button",
            Self::Conveyor(_) => "conveyor",
            Self::Detector(_) => "detector",
            Self::Link(_) => "link",
            Self::Tank(_) => "tank",
            Self::Turntable(_) => "turntable",
        }
    }

    /// The problems of its values alone, as messages.
    pub(crate) fn check(&self) -> Vec<String> {
        match self {
            Self::Axis(a) => a.check(),
            Self::Button(b) => b.check(),
            Self::Conveyor(c) => c.check(),
            Self::Detector(d) => d.check(),
            Self::Link(l) => l.check(),
            Self::Tank(t) => t.check(),
            Self::Turntable(t) => t.check(),
        }
    }

    /// Every plant signal it names, with the space the signal must be in.
    pub(crate) fn signals(&self) -> Vec<(&str, Space)> {
        match self {
            Self::Axis(a) => a.signals(),
            Self::Button(b) => b.signals(),
            Self::Conveyor(c) => c.signals(),
            Self::Detector(d) => d.signals(),
            Self::Link(l) => l.signals(),
            Self::Tank(t) => t.signals(),
            Self::Turntable(t) => t.signals(),
        }
    }

    /// The plant inputs it measures: its sensors (a panel button is the operator's,
    /// not a sensor: none).
    pub(crate) fn sensors(&self) -> Vec<&str> {
        match self {
            Self::Button(_) => Vec::new(),
            Self::Axis(_)
            | Self::Conveyor(_)
            | Self::Detector(_)
            | Self::Link(_)
            | Self::Tank(_)
            | Self::Turntable(_) => self
                .signals()
                .into_iter()
                .filter(|(_, space)| *space == Space::Input)
                .map(|(s, _)| s)
                .collect(),
        }
    }

    /// Every logic expression it holds (checked against the plant).
    pub(crate) fn expressions(&self) -> Vec<&str> {
        match self {
            Self::Axis(a) => a.expressions(),
            Self::Button(_) => Vec::new(),
            Self::Conveyor(c) => c.expressions(),
            Self::Detector(d) => d.expressions(),
            Self::Link(l) => l.expressions(),
            Self::Tank(t) => t.expressions(),
            Self::Turntable(t) => t.expressions(),
        }
    }

    /// Its live state at rest, resolved against the plant's symbols.
    pub(crate) fn build(&self, id: &str, symbols: &Symbols) -> Result<Live, Problem> {
        match self {
            Self::Axis(a) => Ok(Live::Axis(axis::Axis::new(id, a, symbols)?)),
            Self::Button(b) => Ok(Live::Button(button::Button::new(id, b, symbols)?)),
            Self::Conveyor(c) => Ok(Live::Conveyor(conveyor::Conveyor::new(id, c, symbols)?)),
            Self::Detector(d) => Ok(Live::Detector(detector::Detector::new(id, d, symbols)?)),
            Self::Link(l) => Ok(Live::Link(link::Link::new(id, l, symbols)?)),
            Self::Tank(t) => Ok(Live::Tank(tank::Tank::new(id, t, symbols)?)),
            Self::Turntable(t) => Ok(Live::Turntable(turntable::Turntable::new(id, t, symbols)?)),
        }
    }
}

/// What one internal step gives a component and takes from it.
pub(crate) struct StepCtx<'a> {
    /// The step, ms.
    pub dt: u64,
    /// The plant's signals: outputs as applied (faults included), sensors as last read.
    pub frame: &'a Frame,
    /// The emulator's random stream (speed variations).
    pub rng: &'a mut SplitMix64,
    /// Hazards found in this step: kind and the actuators involved.
    pub hazards: Vec<(super::HazardKind, Vec<String>)>,
    /// The emulator's time at the end of this step, ms.
    pub now: u64,
    /// The outputs without power (their safety contactor open), by plant index.
    pub unpowered: &'a crate::bits::Bits,
    /// The frame changed since the previous step (new outputs, a shift, sensors read
    /// again): an expression over it evaluated then still holds its value when not.
    pub fresh: bool,
}

/// The problem of a variation of `variation_ppm` of a `what` (speed, rate): 50 % or
/// more.
pub(crate) fn check_variation(variation_ppm: u32, what: &str) -> Option<String> {
    (variation_ppm >= 500_000)
        .then(|| format!("variation_ppm {variation_ppm} is 50 % or more of the {what}"))
}

/// The problems of beams placed along a surface of `length` (`surface`: belt, rollers).
pub(crate) fn check_beams(beams: &[conveyor::BeamDef], length: f64, surface: &str) -> Vec<String> {
    beams
        .iter()
        .filter(|b| !b.at.is_finite() || b.at < 0.0 || b.at > length)
        .map(|b| {
            format!(
                "beam `{}` at {} is off the {surface} [0, {length}]",
                b.signal, b.at
            )
        })
        .collect()
}

/// A new run's speed factor, millionths of nominal: drawn within `± variation_ppm`
/// from the emulator's stream when the run moves (`dir` not 0), else nominal.
pub(crate) fn run_factor(dir: i64, variation_ppm: i64, rng: &mut SplitMix64) -> i64 {
    if dir != 0 && variation_ppm > 0 {
        let span = 2 * variation_ppm as u64 + 1;
        1_000_000 - variation_ppm + rng.below(span) as i64
    } else {
        1_000_000
    }
}

/// Faults acting on a component as a whole.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct ComponentFaults {
    /// It cannot move.
    pub blocked: bool,
    /// Its speed, percent of nominal.
    pub speed_percent: u8,
    /// It cannot leave this position (millionths of its unit) once there.
    pub stuck_at: Option<i64>,
}

/// A component's live state.
#[derive(Clone, Debug)]
// A plant holds one of each component, in a Vec built once: the variants' sizes do
// not matter, and boxing would add an indirection to every internal step.
#[allow(clippy::large_enum_variant)]
pub(crate) enum Live {
    /// See [`axis::Axis`].
    Axis(axis::Axis),
    /// See [`button::Button`].
    Button(button::Button),
    /// See [`conveyor::Conveyor`].
    Conveyor(conveyor::Conveyor),
    /// See [`detector::Detector`].
    Detector(detector::Detector),
    /// See [`link::Link`].
    Link(link::Link),
    /// See [`tank::Tank`].
    Tank(tank::Tank),
    /// See [`turntable::Turntable`].
    Turntable(turntable::Turntable),
}

impl Live {
    /// Advances one internal step.
    pub(crate) fn step(&mut self, ctx: &mut StepCtx<'_>, faults: ComponentFaults) {
        match self {
            Self::Axis(a) => a.step(ctx, faults),
            Self::Button(b) => b.step(ctx),
            Self::Conveyor(c) => c.step(ctx, faults),
            Self::Detector(d) => d.step(ctx),
            Self::Link(l) => l.step(ctx, faults),
            Self::Tank(t) => t.step(ctx, faults),
            Self::Turntable(t) => t.step(ctx, faults),
        }
    }

    /// True when its last step changed nothing and the next, on the same outputs,
    /// will not either (an axis no drive moves, a tank no flow runs, a button
    /// released): the emulator then skips the rest of the period.
    pub(crate) fn idle(&self) -> bool {
        match self {
            Self::Axis(a) => a.idle(),
            Self::Button(b) => !b.pressed(),
            Self::Conveyor(c) => c.idle(),
            Self::Detector(d) => d.idle(),
            Self::Link(l) => l.idle(),
            Self::Tank(t) => t.idle(),
            Self::Turntable(t) => t.idle(),
        }
    }

    /// Its next steps, on the same outputs, change nothing but its surface's items
    /// (which move straight on a running belt): an idle component, a conveyor, a
    /// turntable whose table does not turn.
    pub(crate) fn steady(&self) -> bool {
        match self {
            Self::Conveyor(_) => true,
            Self::Turntable(t) => t.steady(),
            _ => self.idle(),
        }
    }

    /// How many of the next `max` steps of `dt` ms it may take at once on the same
    /// outputs ([`Self::advance`]): any when steady (an idle component, a conveyor,
    /// a standing turntable), a turning turntable's before it reaches its position,
    /// none for anything else that moves.
    pub(crate) fn quiet_steps(&self, dt: u64, max: u64) -> u64 {
        match self {
            Self::Turntable(t) => t.quiet_steps(dt, max),
            c if c.steady() => max,
            _ => 0,
        }
    }

    /// Takes `k` quiet steps of `dt` ms at once: the state `k` single steps give.
    pub(crate) fn advance(&mut self, dt: u64, k: u64) {
        if let Self::Turntable(t) = self {
            t.advance(dt, k);
        }
    }

    /// Writes its sensors (by plant input index) before sensor faults apply.
    pub(crate) fn sense(&self, sensors: &mut crate::bits::Bits) {
        match self {
            Self::Axis(a) => a.sense(sensors),
            Self::Button(b) => b.sense(sensors),
            Self::Conveyor(c) => c.sense(sensors),
            Self::Detector(d) => d.sense(sensors),
            Self::Link(l) => l.sense(sensors),
            Self::Tank(t) => t.sense(sensors),
            Self::Turntable(t) => t.sense(sensors),
        }
    }

    /// Its position along its travel (a tank: its level), in its unit (dangers are
    /// zones of it).
    pub(crate) fn position(&self) -> f64 {
        match self {
            Self::Axis(a) => a.position(),
            Self::Button(b) => f64::from(u8::from(b.pressed())),
            // A conveyor's: the front of its item nearest the exit (the plant's items).
            Self::Conveyor(_) | Self::Detector(_) | Self::Link(_) => 0.0,
            Self::Tank(t) => t.level(),
            Self::Turntable(t) => t.position(),
        }
    }

    /// What the synoptic draws of it.
    pub(crate) fn scene(&self, id: &str, name: &str) -> SceneElement {
        match self {
            Self::Axis(a) => a.scene(id, name),
            Self::Button(b) => b.scene(id, name),
            Self::Conveyor(c) => c.scene(id, name),
            Self::Detector(d) => d.scene(id, name),
            Self::Link(l) => l.scene(id, name),
            Self::Tank(t) => t.scene(id, name),
            Self::Turntable(t) => t.scene(id, name),
        }
    }

    /// Puts it at `position` (a technician moving it by hand, live-mode
    /// initialisation), clamped to its travel.
    pub(crate) fn set_position(&mut self, position: f64) {
        match self {
            Self::Axis(a) => a.set_position(position),
            Self::Button(_) | Self::Conveyor(_) | Self::Detector(_) | Self::Link(_) => {}
            Self::Tank(t) => t.set_level(position),
            Self::Turntable(t) => t.set_position(position),
        }
    }

    /// The operator presses the button on `signal`; false when this is not it.
    pub(crate) fn press(&mut self, signal: &str) -> bool {
        match self {
            Self::Button(b) => b.press(signal),
            Self::Axis(_)
            | Self::Conveyor(_)
            | Self::Detector(_)
            | Self::Link(_)
            | Self::Tank(_)
            | Self::Turntable(_) => false,
        }
    }

    /// What the elementary actions are derived from (axes only).
    pub(crate) fn axis_geometry(&self, id: &str) -> Option<super::derive::AxisGeometry> {
        match self {
            Self::Axis(a) => Some(a.geometry(id)),
            Self::Tank(t) => Some(t.geometry(id)),
            Self::Button(_)
            | Self::Conveyor(_)
            | Self::Detector(_)
            | Self::Link(_)
            | Self::Turntable(_) => None,
        }
    }
}
