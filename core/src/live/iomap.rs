//! The I/O map: where every plant signal lives on Modbus (area, 0-based address, unit
//! id) and how often it is polled and how old it may get before it is stale.
//!
//! Written in RON next to the plant (`layouts/sorting-station/io-map.ron`):
//!
//! ```ron
//! IoMap(
//!     unit: 1,
//!     poll_ms: 10,
//!     max_age_ms: 30,
//!     signals: [
//!         (signal: "C0", address: DiscreteInput(0)),
//!         (signal: "A0", address: Coil(0), poll_ms: 20),
//!     ],
//! )
//! ```

use super::ron_options;
use crate::diag::codes;
use crate::diag::{Location, Problem, ron_problem};
use crate::plant::{Address, Plant};
use crate::time::Millis;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The four Modbus data areas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Area {
    /// Read-only bits (function 02).
    DiscreteInput,
    /// Read-write bits (functions 01, 05, 15).
    Coil,
    /// Read-only 16-bit words (function 04).
    InputRegister,
    /// Read-write 16-bit words (functions 03, 06, 16, 22).
    HoldingRegister,
}

impl Area {
    /// True for the bit areas (discrete inputs and coils).
    pub fn is_bit(self) -> bool {
        matches!(self, Area::DiscreteInput | Area::Coil)
    }

    /// True for the areas a client may write (coils and holding registers).
    pub fn is_writable(self) -> bool {
        matches!(self, Area::Coil | Area::HoldingRegister)
    }
}

impl std::fmt::Display for Area {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Area::DiscreteInput => "discrete input",
            Area::Coil => "coil",
            Area::InputRegister => "input register",
            Area::HoldingRegister => "holding register",
        })
    }
}

/// One Modbus bit: an area, a unit id, a 0-based address and, in a register, a bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct Point {
    /// Unit (slave) id.
    pub unit: u8,
    /// Data area.
    pub area: Area,
    /// 0-based address (a bit in the bit areas, a word in the register areas).
    pub address: u16,
    /// Bit 0..=15 of the register (always 0 in the bit areas).
    pub bit: u8,
}

impl Point {
    /// The point of a plant [`Address`] on `unit`.
    pub fn from_address(unit: u8, address: Address) -> Self {
        let (area, address, bit) = match address {
            Address::DiscreteInput(a) => (Area::DiscreteInput, a, 0),
            Address::Coil(a) => (Area::Coil, a, 0),
            Address::InputRegisterBit(a, b) => (Area::InputRegister, a, b),
            Address::HoldingRegisterBit(a, b) => (Area::HoldingRegister, a, b),
        };
        Self {
            unit,
            area,
            address,
            bit,
        }
    }
}

impl std::fmt::Display for Point {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.area.is_bit() {
            write!(f, "unit {} {} {}", self.unit, self.area, self.address)
        } else {
            write!(
                f,
                "unit {} {} {} bit {}",
                self.unit, self.area, self.address, self.bit
            )
        }
    }
}

/// One line of the map as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapEntry {
    /// Plant signal id (`C7`, `A4`).
    pub signal: String,
    /// Where it is, in the notation of `plant.ron`.
    pub address: Address,
    /// Unit id, when not the map's.
    #[serde(default)]
    pub unit: Option<u8>,
    /// Poll period in ms, when not the map's.
    #[serde(default)]
    pub poll_ms: Option<u64>,
    /// Staleness bound in ms, when not the map's.
    #[serde(default)]
    pub max_age_ms: Option<u64>,
}

fn default_unit() -> u8 {
    1
}

fn default_poll_ms() -> u64 {
    10
}

/// The map file as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "IoMap")]
pub struct IoMapFile {
    /// Default unit id (1).
    #[serde(default = "default_unit")]
    pub unit: u8,
    /// Default poll period in ms (10).
    #[serde(default = "default_poll_ms")]
    pub poll_ms: u64,
    /// Default staleness bound in ms (three poll periods when absent).
    #[serde(default)]
    pub max_age_ms: Option<u64>,
    /// One entry per plant signal.
    pub signals: Vec<MapEntry>,
    /// A fieldbus between the plant and the PLC (`bus.ron`, relative to the map): the
    /// inputs its variables deliver are stale when older than what their deadline leaves
    /// once the bus has taken its worst case ([`crate::fieldbus`]), if that is sooner.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bus: Option<String>,
}

/// A signal placed on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Mapped {
    /// Where it is.
    pub point: Point,
    /// How often it is read.
    pub poll: Millis,
    /// How old its value may get before it is stale.
    pub max_age: Millis,
}

impl super::Placed for Mapped {
    fn poll(&self) -> Millis {
        self.poll
    }
    fn max_age(&self) -> Millis {
        self.max_age
    }
}

/// A validated map: one [`Mapped`] per plant input and per plant output, in plant order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IoMap {
    /// Sensors, indexed like `Plant::inputs`.
    pub inputs: Vec<Mapped>,
    /// Actuators, indexed like `Plant::outputs`.
    pub outputs: Vec<Mapped>,
}

impl IoMap {
    /// Loads and validates a map file against `plant`. Warnings come back with the map;
    /// errors alone when the map cannot be used.
    pub fn load(path: &Path, plant: &Plant) -> Result<(Self, Vec<Problem>), Vec<Problem>> {
        let text = crate::diag::read_text(path)
            .map_err(|p| vec![Problem::error(codes::IO_MAP_UNREADABLE.id, p.message, None)])?;
        let parsed: IoMapFile = ron_options()
            .from_str(&text)
            .map_err(|e| vec![ron_problem(path, &e)])?;
        let (mut map, mut warnings) = Self::from_file(&parsed, plant, &text, path)?;
        if let Some(bus) = &parsed.bus {
            let bus_path = path.parent().unwrap_or(Path::new(".")).join(bus);
            warnings.extend(map.follow_bus(&bus_path, plant)?);
        }
        Ok((map, warnings))
    }

    /// Bounds the staleness of the inputs the variables of the bus at `path` deliver
    /// (see [`IoMapFile::bus`]); its warnings.
    pub fn follow_bus(&mut self, path: &Path, plant: &Plant) -> Result<Vec<Problem>, Vec<Problem>> {
        let (bus, text) = crate::fieldbus::BusFile::load(path)?;
        let analysis = bus.analyse(path, &text)?;
        let bounds = analysis.input_bounds(path, &text)?;
        let mut errors = Vec::new();
        let mut warnings = analysis.warnings.clone();
        for (signal, ms) in bounds {
            let Some(m) = plant.input(&signal).and_then(|i| self.inputs.get_mut(i)) else {
                errors.push(Problem::error(
                    codes::IO_MAP_UNKNOWN_SIGNAL.id,
                    format!(
                        "the bus delivers `{signal}`, which is not an input of plant `{}`",
                        plant.name
                    ),
                    Some(Location::of_nth(path, &text, &format!("\"{signal}\""), 0)),
                ));
                continue;
            };
            m.max_age = m.max_age.min(Millis(ms));
            if m.max_age < m.poll {
                warnings.push(Problem::warning(
                    codes::IO_MAP_MAX_AGE.id,
                    format!(
                        "`{signal}`: the bus leaves {ms} ms of its deadline, below the poll period {} ms: the value will be stale between polls",
                        m.poll.0
                    ),
                    Some(Location::of_nth(path, &text, &format!("\"{signal}\""), 0)),
                ));
            }
        }
        if errors.is_empty() {
            Ok(warnings)
        } else {
            Err(errors)
        }
    }

    /// Parses and validates map text; `file` is used in messages only.
    pub fn from_ron(
        text: &str,
        file: &Path,
        plant: &Plant,
    ) -> Result<(Self, Vec<Problem>), Vec<Problem>> {
        let parsed: IoMapFile = ron_options()
            .from_str(text)
            .map_err(|e| vec![ron_problem(file, &e)])?;
        Self::from_file(&parsed, plant, text, file)
    }

    /// The default map from the addresses in `plant.ron` (every signal must have one).
    pub fn from_plant(plant: &Plant, unit: u8, poll_ms: u64) -> Result<Self, Vec<Problem>> {
        let mut signals = Vec::new();
        let mut problems = Vec::new();
        for s in plant.inputs.iter().chain(&plant.outputs) {
            match s.address {
                Some(address) => signals.push(MapEntry {
                    signal: s.id.clone(),
                    address,
                    unit: None,
                    poll_ms: None,
                    max_age_ms: None,
                }),
                None => problems.push(Problem::error(
                    codes::IO_MAP_NO_ADDRESS.id,
                    format!("signal `{}` has no address in the plant file", s.id),
                    None,
                )),
            }
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        let file = IoMapFile {
            unit,
            poll_ms,
            max_age_ms: None,
            signals,
            bus: None,
        };
        Self::from_file(&file, plant, "", Path::new("plant.ron")).map(|(m, _)| m)
    }

    /// Validates a parsed map: every signal mapped exactly once, actuators on writable
    /// areas, no two signals on the same bit, bits 0..=15, non-zero periods.
    pub fn from_file(
        file: &IoMapFile,
        plant: &Plant,
        text: &str,
        path: &Path,
    ) -> Result<(Self, Vec<Problem>), Vec<Problem>> {
        let mut errors = Vec::new();
        let mut warnings = Vec::new();
        let at = |needle: &str| Some(Location::of_nth(path, text, needle, 0));
        let mut inputs: Vec<Option<Mapped>> = vec![None; plant.inputs.len()];
        let mut outputs: Vec<Option<Mapped>> = vec![None; plant.outputs.len()];
        let mut taken: BTreeMap<Point, String> = BTreeMap::new();
        if file.poll_ms == 0 {
            errors.push(Problem::error(
                codes::IO_MAP_POLL.id,
                "poll_ms must be at least 1",
                at("poll_ms"),
            ));
        }
        for e in &file.signals {
            let loc = at(&format!("\"{}\"", e.signal));
            let point = Point::from_address(e.unit.unwrap_or(file.unit), e.address);
            let poll = e.poll_ms.unwrap_or(file.poll_ms);
            let max_age = e
                .max_age_ms
                .or(file.max_age_ms)
                .unwrap_or_else(|| poll.saturating_mul(3));
            check_entry(
                &e.signal,
                point,
                poll,
                max_age,
                &loc,
                &mut errors,
                &mut warnings,
            );
            if let Some(other) = taken.insert(point, e.signal.clone()) {
                errors.push(Problem::error(
                    codes::IO_MAP_SHARED_POINT.id,
                    format!("`{}` and `{other}` are both on {point}", e.signal),
                    loc.clone(),
                ));
            }
            let mapped = Mapped {
                point,
                poll: Millis(poll),
                max_age: Millis(max_age),
            };
            let slot = if let Some(i) = plant.input(&e.signal) {
                inputs.get_mut(i)
            } else if let Some(k) = plant.output(&e.signal) {
                if !point.area.is_writable() {
                    errors.push(Problem::error(
                        codes::IO_MAP_ACTUATOR_READ_ONLY.id,
                        format!(
                            "actuator `{}` is on a read-only {}: actuators go on coils or holding registers",
                            e.signal, point.area
                        ),
                        loc.clone(),
                    ));
                }
                outputs.get_mut(k)
            } else {
                errors.push(Problem::error(
                    codes::IO_MAP_UNKNOWN_SIGNAL.id,
                    format!("`{}` is not a signal of plant `{}`", e.signal, plant.name),
                    loc.clone(),
                ));
                continue;
            };
            if let Some(slot) = slot {
                if slot.is_some() {
                    errors.push(Problem::error(
                        codes::IO_MAP_DUPLICATE.id,
                        format!("`{}` is mapped twice", e.signal),
                        loc.clone(),
                    ));
                }
                *slot = Some(mapped);
            }
        }
        errors.extend(super::unmapped(plant, &inputs, &outputs, path));
        if !errors.is_empty() {
            errors.extend(warnings);
            return Err(errors);
        }
        Ok((
            Self {
                inputs: inputs.into_iter().flatten().collect(),
                outputs: outputs.into_iter().flatten().collect(),
            },
            warnings,
        ))
    }

    /// The smallest poll period of the map.
    pub fn fastest_poll(&self) -> Millis {
        super::fastest_poll(self.inputs.iter().chain(&self.outputs))
    }

    /// Staleness bounds of the inputs, in input order.
    pub fn input_bounds(&self) -> Vec<Millis> {
        super::input_bounds(self.inputs.iter())
    }
}

/// Checks one entry's register bit, poll period and maximum age.
fn check_entry(
    signal: &str,
    point: Point,
    poll: u64,
    max_age: u64,
    loc: &Option<Location>,
    errors: &mut Vec<Problem>,
    warnings: &mut Vec<Problem>,
) {
    if point.bit > 15 {
        errors.push(Problem::error(
            codes::IO_MAP_BIT.id,
            format!("`{}`: register bit {} is past 15", signal, point.bit),
            loc.clone(),
        ));
    }
    if poll == 0 {
        errors.push(Problem::error(
            codes::IO_MAP_POLL.id,
            format!("`{}`: poll_ms must be at least 1", signal),
            loc.clone(),
        ));
    }
    if max_age < poll {
        warnings.push(Problem::warning(
            codes::IO_MAP_MAX_AGE.id,
            format!(
                "`{}`: max_age_ms {max_age} is below the poll period {poll}: the value will be stale between polls",
                signal
            ),
            loc.clone(),
        ));
    }
}
