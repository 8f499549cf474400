//! The plant's I/O model: every sensor and actuator with the paper's identifiers.
//!
//! Loaded from `plant.ron` in a plant folder (for the sorting station,
//! `layouts/sorting-station/plant.ron`).

use crate::diag::codes;
use crate::diag::{Location, Problem, ron_problem};
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Direction of a signal, seen from the PLC.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SignalKind {
    /// A PLC input (a sensor, `C…`).
    Sensor,
    /// A PLC output (an actuator, `A…`).
    Actuator,
}

/// A fieldbus address, for display and for the default I/O map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Address {
    /// Modbus discrete input, 0-based.
    DiscreteInput(u16),
    /// Modbus coil, 0-based.
    Coil(u16),
    /// Bit of a Modbus input register.
    InputRegisterBit(u16, u8),
    /// Bit of a Modbus holding register.
    HoldingRegisterBit(u16, u8),
}

impl std::fmt::Display for Address {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Address::DiscreteInput(a) => write!(f, "discrete input {a}"),
            Address::Coil(a) => write!(f, "coil {a}"),
            Address::InputRegisterBit(r, b) => write!(f, "input register {r} bit {b}"),
            Address::HoldingRegisterBit(r, b) => write!(f, "holding register {r} bit {b}"),
        }
    }
}

/// The value an output takes when the filter stops the plant in a safe state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SafeValue {
    /// OFF (the paper's rest state; the default).
    #[default]
    Zero,
    /// ON: the actuator moves when its output is 0 (a monostable cylinder held
    /// extended, a lift whose "down" output off means "up").
    One,
    /// Keep the value last applied (an actuator that must neither start nor stop).
    Hold,
}

/// One signal of the plant.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Signal {
    /// The paper's identifier (`C0`, `A4`).
    pub id: String,
    /// Sensor or actuator.
    pub kind: SignalKind,
    /// What it tells or does.
    pub description: String,
    /// The plant element it belongs to.
    #[serde(default)]
    pub element: String,
    /// Optional fieldbus address.
    #[serde(default)]
    pub address: Option<Address>,
    /// Actuators: the value the fallback prefers (Zero by default, see
    /// [`SafeValue`]).
    #[serde(default)]
    pub safe: SafeValue,
    /// Actuators: what the plant does when the output is OFF, in words ("the table
    /// returns to the loading position"), shown in explanations.
    #[serde(default)]
    pub off: Option<String>,
    /// The value before the first cycle (a cold start's previous values; 0 by default).
    #[serde(default)]
    pub initial: bool,
    /// Sensors: when the plant's physics lets the reading change
    /// ([`crate::plausibility`]); an edge outside it is held and the sensor is suspect.
    #[serde(default)]
    pub plausible: Option<PlausibleRule>,
    /// Actuators: the actuators this one powers (a safety contactor on the drives'
    /// supply, in series with each drive's own contactor): they move only while it is
    /// applied, even with their own contactor welded.
    #[serde(default)]
    pub supplies: Vec<String>,
    /// Actuators: commanded ON every cycle whatever the control program (an output the
    /// safety function owns, such as a safety contactor): only the filter's fallback
    /// takes it off.
    #[serde(default)]
    pub held_on: bool,
    /// Sensors: the actuator whose contactor this input mirrors (its auxiliary contact):
    /// it reads the contactor's state, as commanded, welded or dead, one cycle after
    /// the command.
    #[serde(default)]
    pub feedback_of: Option<String>,
    /// Mirror contacts: the longest the contact may take to follow its output, ms (the
    /// contactor's switching time and a live link's latency). A disagreement with the
    /// output applied at t-1 that has lasted less is read as agreement; 0: none (the
    /// contact follows within one cycle).
    #[serde(default)]
    pub feedback_ms: u64,
}

/// The timed plausibility of a sensor's edges, from the plant's physics: a beam cannot
/// fall sooner than the shortest item takes to cross it (`min_on_ms`), an axis cannot
/// leave a position before its motion is ordered (`fall_when: "A4*"`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlausibleRule {
    /// A fall sooner than this after the last accepted rise is implausible, ms.
    #[serde(default)]
    pub min_on_ms: u64,
    /// A rise sooner than this after the last accepted fall is implausible, ms.
    #[serde(default)]
    pub min_off_ms: u64,
    /// A rise is plausible only when this holds (logic notation, over the inputs read
    /// now and every value of the previous cycle: `A2* + A3*`).
    #[serde(default)]
    pub rise_when: Option<String>,
    /// A fall is plausible only when this holds.
    #[serde(default)]
    pub fall_when: Option<String>,
    /// The rise condition must have held without a break this long, ms (a travel
    /// time: a turntable reaches its far position no sooner than its rotation takes
    /// after the order).
    #[serde(default)]
    pub rise_when_for_ms: u64,
    /// The fall condition must have held without a break this long, ms.
    #[serde(default)]
    pub fall_when_for_ms: u64,
    /// The rise condition must have held this long in all since the last accepted
    /// fall, ms, counted across its breaks (a distance: the drive time that moves an
    /// item its shortest length, which a stop and a restart half-way do not lose).
    #[serde(default)]
    pub rise_when_total_ms: u64,
    /// The fall condition must have held this long in all since the last accepted
    /// rise, ms, across its breaks (a box that waited at a beam leaves it only once the
    /// drives under it have run long enough to move it its length).
    #[serde(default)]
    pub fall_when_total_ms: u64,
    /// A plausible rise is taken once the reading has stayed 1 this long, ms (a
    /// shorter pulse is filtered).
    #[serde(default)]
    pub rise_confirm_ms: u64,
    /// A plausible fall is taken once the reading has stayed 0 this long, ms (a beam
    /// whose fall releases a motion: a shorter dropout is filtered).
    #[serde(default)]
    pub fall_confirm_ms: u64,
    /// While the sensor is suspect, the constraints read it as possibly either value
    /// (the held one and the one read) instead of the held value only. The load's
    /// property (6) and fallback checks say where that leaves no safe output.
    #[serde(default)]
    pub both_values: bool,
    /// An edge sooner than `min_on_ms` / `min_off_ms` after the last accepted one shows
    /// that this one was a transient, not an item (a beam on for less than the shortest
    /// box): the sensor stays held until the reading comes back, not only until the
    /// window has passed (a 500 ms pulse is not taken, 900 ms later, for a box that
    /// has left).
    #[serde(default)]
    pub hold_until_back: bool,
    /// A rise sooner than `ms` after the last cycle where `event` held is implausible (a
    /// travel time from an upstream event: a box that leaves the belt's end sensor
    /// reaches the middle of the table no sooner than its shortest travel takes).
    #[serde(default)]
    pub rise_not_after: Option<AfterEvent>,
    /// A rise is expected only when this holds (logic notation, like `rise_when`); a
    /// rise outside it is taken (the stage holds nothing: an upstream sensor that
    /// missed the item must not hide it), but when the sensor takes part in a stop in
    /// that cycle, level 4 names it first (X418): no item could have reached it, so its
    /// reading, or what the expectation follows, is suspect before the program.
    #[serde(default)]
    pub rise_expected_when: Option<String>,
    /// A fall is expected only when this holds (see `rise_expected_when`).
    #[serde(default)]
    pub fall_expected_when: Option<String>,
}

/// An event and a time after it, for [`PlausibleRule::rise_not_after`]:
/// `(event: "FE(C3)", ms: 100)`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AfterEvent {
    /// The event (logic notation, over the inputs read now and every value of the
    /// previous cycle: `FE(C3)`).
    pub event: String,
    /// How long after it a rise stays implausible, ms.
    pub ms: u64,
}

impl Signal {
    /// A signal with the defaults of the optional fields.
    pub fn new(id: impl Into<String>, kind: SignalKind, description: impl Into<String>) -> Self {
        Self {
            id: id.into(),
            kind,
            description: description.into(),
            element: String::new(),
            address: None,
            safe: SafeValue::Zero,
            off: None,
            initial: false,
            plausible: None,
            supplies: Vec::new(),
            held_on: false,
            feedback_of: None,
            feedback_ms: 0,
        }
    }

    /// What the output does at `value`, for explanations: "A4 OFF: the table returns
    /// to the loading position".
    pub fn meaning(&self, value: bool) -> String {
        match (value, &self.off) {
            (false, Some(off)) => format!("{} OFF: {off}", self.id),
            (false, None) => format!("{} OFF", self.id),
            (true, _) => format!("{} ON: {}", self.id, self.description),
        }
    }
}

/// The plant file as written.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(rename = "Plant")]
pub struct PlantFile {
    /// Display name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Signals in any order; inputs and outputs are numbered in file order.
    pub signals: Vec<Signal>,
}

/// A loaded plant: sensors and actuators, each numbered from 0 in file order.
#[derive(Clone, Debug)]
pub struct Plant {
    /// Display name.
    pub name: String,
    /// Free text.
    pub description: String,
    /// Sensors, indexed by input number.
    pub inputs: Vec<Signal>,
    /// Actuators, indexed by output number.
    pub outputs: Vec<Signal>,
}

impl Plant {
    /// Parses a plant from RON text; `file` is used in messages only.
    pub fn from_ron(text: &str, file: &Path) -> Result<Self, Vec<Problem>> {
        let parsed: PlantFile = ron::from_str(text).map_err(|e| vec![ron_problem(file, &e)])?;
        Self::validate(parsed, file, Some(text))
    }

    /// Loads `plant.ron` from disk.
    pub fn load(path: &Path) -> Result<Self, Vec<Problem>> {
        let text = crate::diag::read_text(path).map_err(|p| vec![p])?;
        Self::from_ron(&text, path)
    }

    /// Validates a parsed file (problems at 1:1: without the text, positions are not
    /// known; [`Plant::from_ron`] gives them).
    pub fn from_file(file: PlantFile, path: &Path) -> Result<Self, Vec<Problem>> {
        Self::validate(file, path, None)
    }

    /// Validates a parsed file; `text`, when given, is what it was parsed from, and a
    /// bad or repeated id is reported where that signal's `id` is written.
    fn validate(file: PlantFile, path: &Path, text: Option<&str>) -> Result<Self, Vec<Problem>> {
        let fields = text.map(crate::diag::ron_fields).unwrap_or_default();
        let id_at = |i: usize| {
            Some(
                crate::diag::ron_field(&fields, &["signals"], "id", i)
                    .map_or_else(|| Location::new(path, 1, 1), |f| f.location(path)),
            )
        };
        let mut problems = Vec::new();
        let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
        for (i, s) in file.signals.iter().enumerate() {
            if !is_valid_name(&s.id) {
                problems.push(Problem::error(
                    codes::SIGNAL_ID_INVALID.id,
                    format!("signal id `{}` must be letters, digits and `_`", s.id),
                    id_at(i),
                ));
            }
            if s.plausible.is_some() && s.kind != SignalKind::Sensor {
                problems.push(Problem::error(
                    codes::PLAUSIBLE_ON_ACTUATOR.id,
                    format!("`plausible` is for sensors; `{}` is an actuator", s.id),
                    id_at(i),
                ));
            }
            if let Some(&first) = seen.get(s.id.as_str()) {
                let at = crate::diag::ron_field(&fields, &["signals"], "id", first)
                    .map_or(String::new(), |f| format!(" (first on line {})", f.line));
                problems.push(Problem::error(
                    codes::SIGNAL_DUPLICATE.id,
                    format!("signal `{}` is declared twice{at}", s.id),
                    id_at(i),
                ));
            } else {
                seen.insert(&s.id, i);
            }
        }
        check_wiring(&file.signals, &id_at, &mut problems);
        if !problems.is_empty() {
            return Err(problems);
        }
        let (inputs, outputs) = file
            .signals
            .into_iter()
            .partition(|s| s.kind == SignalKind::Sensor);
        Ok(Self {
            name: file.name,
            description: file.description,
            inputs,
            outputs,
        })
    }

    /// A plant built in code (tests, synthetic benchmarks).
    pub fn new(name: &str, inputs: Vec<Signal>, outputs: Vec<Signal>) -> Self {
        Self {
            name: name.to_string(),
            description: String::new(),
            inputs,
            outputs,
        }
    }

    /// A symbol table with the inputs and outputs declared, in index order.
    pub fn symbols(&self) -> Symbols {
        let mut symbols = Symbols::new();
        for s in &self.inputs {
            let _ = symbols.declare(&s.id, Space::Input);
        }
        for s in &self.outputs {
            let _ = symbols.declare(&s.id, Space::Output);
        }
        symbols
    }

    /// Input number of a sensor id.
    pub fn input(&self, id: &str) -> Option<usize> {
        self.inputs.iter().position(|s| s.id == id)
    }

    /// Output number of an actuator id.
    pub fn output(&self, id: &str) -> Option<usize> {
        self.outputs.iter().position(|s| s.id == id)
    }

    /// The safety contactors (`supplies`): each one's output and the outputs it powers.
    pub fn supplies(&self) -> Vec<(usize, Vec<usize>)> {
        self.outputs
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.supplies.is_empty())
            .map(|(o, s)| {
                (
                    o,
                    s.supplies.iter().filter_map(|a| self.output(a)).collect(),
                )
            })
            .collect()
    }

    /// The mirror contacts (`feedback_of`): each one's input and the output it mirrors.
    pub fn mirrors(&self) -> Vec<(usize, usize)> {
        self.inputs
            .iter()
            .enumerate()
            .filter_map(|(i, s)| Some((i, self.output(s.feedback_of.as_deref()?)?)))
            .collect()
    }

    /// A signal by id.
    pub fn signal(&self, id: &str) -> Option<&Signal> {
        self.inputs.iter().chain(&self.outputs).find(|s| s.id == id)
    }
}

/// `supplies`, `held_on` and `feedback_of` name actuators, on the kind of signal they
/// belong to.
fn check_wiring(
    signals: &[Signal],
    id_at: &dyn Fn(usize) -> Option<Location>,
    problems: &mut Vec<Problem>,
) {
    let actuator = |id: &str| {
        signals
            .iter()
            .any(|s| s.id == id && s.kind == SignalKind::Actuator)
    };
    for (i, s) in signals.iter().enumerate() {
        let mut bad = |message: String| {
            problems.push(Problem::error(codes::PLANT_WIRING.id, message, id_at(i)));
        };
        let is_sensor = s.kind == SignalKind::Sensor;
        if is_sensor && (s.held_on || !s.supplies.is_empty()) {
            bad(format!(
                "`supplies` and `held_on` are for actuators; `{}` is a sensor",
                s.id
            ));
        }
        for a in s.supplies.iter().filter(|a| !actuator(a) || *a == &s.id) {
            bad(format!(
                "`{}` supplies `{a}`, which is not another actuator of the plant",
                s.id
            ));
        }
        match &s.feedback_of {
            Some(_) if !is_sensor => bad(format!(
                "`feedback_of` is for sensors (a contactor's mirror contact); `{}` is an actuator",
                s.id
            )),
            Some(a) if !actuator(a) => bad(format!(
                "`{}` mirrors `{a}`, which is not an actuator of the plant",
                s.id
            )),
            None if s.feedback_ms > 0 => bad(format!(
                "`{}` has `feedback_ms` but mirrors nothing (`feedback_of`)",
                s.id
            )),
            _ if s.feedback_ms > 10_000 => bad(format!(
                "`{}`: `feedback_ms` {} is longer than 10 s; a contact that slow cannot watch a contactor",
                s.id, s.feedback_ms
            )),
            _ => {}
        }
    }
}

/// Names are ASCII letters, digits and `_`, not all digits.
pub fn is_valid_name(name: &str) -> bool {
    !name.is_empty()
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !name.chars().all(|c| c.is_ascii_digit())
}

#[cfg(test)]
mod tests;
