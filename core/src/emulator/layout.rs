//! The plant layout: world geometry (mm, top view, x right, y up) shared by the emulator
//! and the synoptic, loaded from `layout.ron`.

use crate::diag::codes;
use crate::diag::{Location, Problem, ron_problem};
use crate::plant::Plant;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A point of the world, in millimetres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Point {
    /// Abscissa, mm, to the right.
    pub x: i64,
    /// Ordinate, mm, upwards.
    pub y: i64,
}

/// A straight conveyor driven from `start` to `end` when its actuator is on.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Conveyor {
    /// Part id, referenced by sensors and `place_box` (`entry`, `left_exit`…).
    pub id: String,
    /// Display name.
    pub name: String,
    /// Upstream end.
    pub start: Point,
    /// Downstream end.
    pub end: Point,
    /// Belt width, mm (drawing only).
    pub width_mm: i64,
    /// Belt speed when driven, mm/s.
    pub speed_mm_s: i64,
    /// Motor actuator id (`A0`).
    pub actuator: String,
}

/// The roller turntable. Table coordinate `u` runs along the roller axis, from
/// `-half_length_mm` to `+half_length_mm`; `+u` points along the table angle.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Turntable {
    /// Part id (`table`).
    pub id: String,
    /// Display name.
    pub name: String,
    /// Rotation centre.
    pub center: Point,
    /// Half length along the roller axis, mm.
    pub half_length_mm: i64,
    /// Width across the rollers, mm (drawing only).
    pub width_mm: i64,
    /// Roller surface speed, mm/s.
    pub roller_speed_mm_s: i64,
    /// Actuator driving the rollers towards `+u` (`A2`).
    pub plus_actuator: String,
    /// Actuator driving the rollers towards `-u` (`A3`).
    pub minus_actuator: String,
    /// Monostable rotation actuator (`A4`): on drives to unloading, off back to loading.
    pub rotate_actuator: String,
    /// Loading angle (`+u` world direction), millidegrees, counter-clockwise from +x.
    pub loading_mdeg: i32,
    /// Unloading angle, millidegrees.
    pub unloading_mdeg: i32,
    /// Angular speed towards unloading, micro-degrees per ms.
    pub out_speed_udeg_ms: i64,
    /// Angular speed back to loading, micro-degrees per ms.
    pub back_speed_udeg_ms: i64,
    /// Seeded variation of each rotation's speed, parts per million (±).
    pub speed_variation_ppm: i64,
    /// Misalignment the transfer guides accept, mdeg: within it of the loading or
    /// unloading angle the table is joined to the conveyors (boxes transfer, a
    /// straddling box is not sheared). 0 means exact alignment only.
    #[serde(default)]
    pub dock_tolerance_mdeg: i32,
}

/// Beam height of a presence sensor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Beam {
    /// Sees every box.
    Low,
    /// Sees only boxes taller than `high_beam_mm`.
    High,
}

/// What a sensor measures.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SensorKind {
    /// A point beam across a part at `at_mm` (from the conveyor start; for the table, the
    /// table coordinate `u`, so the sensor turns with the table).
    Presence {
        /// Part id.
        part: String,
        /// Position along the part, mm.
        at_mm: i64,
        /// Beam height.
        beam: Beam,
    },
    /// On while the table angle is within `[min_mdeg, max_mdeg]`.
    Angle {
        /// Lower bound, millidegrees.
        min_mdeg: i32,
        /// Upper bound, millidegrees.
        max_mdeg: i32,
    },
}

/// One sensor of the layout.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorDef {
    /// Plant input id (`C3`).
    pub id: String,
    /// Where and what.
    pub kind: SensorKind,
}

/// Size class of a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum BoxSize {
    /// Small box (seen by the low beam only).
    Small,
    /// Large box (seen by both beams).
    Large,
}

/// Dimensions of a box, mm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxDims {
    /// Along the direction of travel.
    pub length_mm: i64,
    /// Across.
    pub width_mm: i64,
    /// Height.
    pub height_mm: i64,
}

/// How sizes alternate in a periodic plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SizeMix {
    /// Small, large, small…
    Alternate,
    /// Large with this probability (percent), drawn from the seed.
    RandomLarge(u8),
}

/// When boxes arrive at the start of the source conveyor.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ArrivalPlan {
    /// No arrivals (boxes are placed by hand).
    Off,
    /// One box every `period_ms`, each delayed by a seeded `0..=jitter_ms`.
    Periodic {
        /// Period, ms (at least 1).
        period_ms: u64,
        /// Largest extra delay, ms.
        jitter_ms: u64,
        /// Size sequence.
        mix: SizeMix,
        /// Number of boxes, then no more arrivals (unbounded when absent).
        #[serde(default)]
        count: Option<u64>,
    },
    /// Explicit arrival times (ms) and sizes, in any order.
    List(Vec<(u64, BoxSize)>),
}

/// The box source at the start of a conveyor.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Source {
    /// Conveyor id where boxes appear (rear at its start).
    pub conveyor: String,
    /// Small boxes.
    pub small: BoxDims,
    /// Large boxes.
    pub large: BoxDims,
    /// Arrival plan; a box waits while the start of the conveyor is occupied.
    pub arrivals: ArrivalPlan,
}

/// Which elevator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Side {
    /// Left elevator.
    Left,
    /// Right elevator.
    Right,
}

/// An elevator at the end of a conveyor: a box whose centre passes the end is delivered.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Elevator {
    /// Which side it counts for.
    pub side: Side,
    /// Conveyor id it takes boxes from.
    pub conveyor: String,
    /// Drawing position.
    pub at: Point,
}

/// The whole layout file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layout {
    /// Display name.
    pub name: String,
    /// Internal simulation step, ms.
    pub step_ms: u64,
    /// A box straddling two surfaces is pushed against a stopped one only when it lies
    /// more than this on each, mm.
    pub straddle_margin_mm: i64,
    /// A box straddles the table edge (shear hazard) when it passes it by more than this, mm.
    pub shear_margin_mm: i64,
    /// A box pushed against a stopped surface is damaged once the driving surface has
    /// slid this far under it without a break, mm (0, the default: at once). A belt
    /// that slips a few millimetres under a box before the drives are cut does not
    /// damage it; one that keeps pushing does.
    #[serde(default)]
    pub push_tolerance_mm: i64,
    /// Height of the high beam, mm.
    pub high_beam_mm: i64,
    /// Straight conveyors.
    pub conveyors: Vec<Conveyor>,
    /// The turntable.
    pub table: Turntable,
    /// Sensors.
    pub sensors: Vec<SensorDef>,
    /// Box source.
    pub source: Source,
    /// Elevators.
    pub elevators: Vec<Elevator>,
    /// The file it came from (messages only).
    #[serde(skip)]
    pub file: PathBuf,
    /// First position of each quoted string in the source text, and of the value of
    /// each field under the key `path.name:` (`source.arrivals.period_ms:`), for
    /// messages only.
    #[serde(skip)]
    pub positions: BTreeMap<String, (usize, usize)>,
    /// The components it was derived from ([`Layout::from_components`]): what an
    /// emulator of the cell runs (none for a `layout.ron`).
    #[serde(skip)]
    pub derived_from: DerivedFrom,
}

/// The plant of components a cell was derived from. Not part of the cell's value: two
/// equal cells are equal whatever they came from.
#[derive(Clone, Debug, Default)]
pub struct DerivedFrom(pub Option<std::sync::Arc<crate::machine::Components>>);

impl PartialEq for DerivedFrom {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Eq for DerivedFrom {}

impl Layout {
    /// Loads a layout file.
    pub fn load(path: &Path) -> Result<Self, Vec<Problem>> {
        let text = crate::diag::read_text(path).map_err(|p| vec![p])?;
        Self::from_ron(&text, path)
    }

    /// Parses and checks a layout; `file` is used in messages only.
    pub fn from_ron(text: &str, file: &Path) -> Result<Self, Vec<Problem>> {
        let mut layout: Layout = ron::from_str(text).map_err(|e| vec![ron_problem(file, &e)])?;
        layout.file = file.to_path_buf();
        layout.positions = quoted_positions(text);
        for f in crate::diag::ron_fields(text) {
            let mut key = f.path.join(".");
            if !key.is_empty() {
                key.push('.');
            }
            key.push_str(&f.name);
            key.push(':');
            layout.positions.entry(key).or_insert((f.line, f.column));
        }
        let problems = layout.check();
        if problems.is_empty() {
            Ok(layout)
        } else {
            Err(problems)
        }
    }

    /// Where `id` first appears in the source, for messages.
    pub fn location_of(&self, id: &str) -> Option<Location> {
        let (line, col) = self.positions.get(id).copied().unwrap_or((1, 1));
        Some(Location::new(&self.file, line, col))
    }

    /// Where the value of field `name` (`source.small`) is written, for messages.
    fn field_location(&self, name: &str) -> Option<Location> {
        self.location_of(&format!("{name}:"))
    }

    fn part_exists(&self, id: &str) -> bool {
        id == self.table.id || self.conveyors.iter().any(|c| c.id == id)
    }

    /// The simulation step and the push tolerance are within their bounds.
    fn check_steps(&self, out: &mut Vec<Problem>) {
        if !(1..=MAX_STEP_MS).contains(&self.step_ms) {
            out.push(Problem::error(
                codes::LAYOUT_INVALID.id,
                format!(
                    "step_ms is {} ms: the simulation step is from 1 to {MAX_STEP_MS} ms",
                    self.step_ms
                ),
                self.field_location("step_ms"),
            ));
        }
        if !(0..=1000).contains(&self.push_tolerance_mm) {
            out.push(Problem::error(
                codes::LAYOUT_INVALID.id,
                format!(
                    "push_tolerance_mm is {} mm: from 0 to 1000 mm",
                    self.push_tolerance_mm
                ),
                self.field_location("push_tolerance_mm"),
            ));
        }
    }

    /// Internal consistency: parts referenced exist, sizes are positive.
    pub fn check(&self) -> Vec<Problem> {
        let mut out = Vec::new();
        self.check_steps(&mut out);
        if let ArrivalPlan::Periodic {
            period_ms,
            jitter_ms,
            ..
        } = &self.source.arrivals
        {
            let max = crate::sim::scenario::MAX_RUN_MS;
            if !(1..=max).contains(period_ms) {
                out.push(Problem::error(
                    codes::LAYOUT_INVALID.id,
                    format!(
                        "period_ms is {period_ms} ms: an arrival period is from 1 ms to {max} ms"
                    ),
                    self.field_location("source.arrivals.period_ms"),
                ));
            }
            if *jitter_ms > max {
                out.push(Problem::error(
                    codes::LAYOUT_INVALID.id,
                    format!("jitter_ms is {jitter_ms} ms: at most {max} ms"),
                    self.field_location("source.arrivals.jitter_ms"),
                ));
            }
        }
        let mut err = |id: &str, msg: String| {
            out.push(Problem::error(
                codes::LAYOUT_INVALID.id,
                msg,
                self.location_of(id),
            ));
        };
        for c in &self.conveyors {
            if c.start == c.end || c.speed_mm_s < 0 {
                err(
                    &c.id,
                    format!(
                        "conveyor `{}` needs two distinct ends and a speed >= 0",
                        c.id
                    ),
                );
            }
        }
        for s in &self.sensors {
            if let SensorKind::Presence { part, .. } = &s.kind
                && !self.part_exists(part)
            {
                err(
                    part,
                    format!("sensor `{}` is on unknown part `{part}`", s.id),
                );
            }
        }
        if self.sensors.len() > 64 {
            err("sensors:", "at most 64 sensors".into());
        }
        if self.conveyors.len() > 60 {
            err("conveyors:", "at most 60 conveyors".into());
        }
        if !self.conveyors.iter().any(|c| c.id == self.source.conveyor) {
            err(
                &self.source.conveyor,
                format!("source on unknown conveyor `{}`", self.source.conveyor),
            );
        }
        for e in &self.elevators {
            if !self.conveyors.iter().any(|c| c.id == e.conveyor) {
                err(
                    &e.conveyor,
                    format!("elevator on unknown conveyor `{}`", e.conveyor),
                );
            }
        }
        for (name, d) in [("small", self.source.small), ("large", self.source.large)] {
            if d.length_mm <= 0 || d.width_mm <= 0 || d.height_mm <= 0 {
                err(
                    &format!("source.{name}:"),
                    format!("{name} box dimensions must be positive"),
                );
            }
        }
        if self.table.half_length_mm <= 0 || self.table.loading_mdeg >= self.table.unloading_mdeg {
            err(
                &self.table.id,
                "table needs a positive length and loading < unloading angle".into(),
            );
        }
        out
    }

    /// The actuators of the drives, in the emulator's role order: the conveyors, then
    /// the table's rollers + and -, then its rotation.
    pub fn drives(&self) -> impl Iterator<Item = &str> {
        let t = &self.table;
        self.conveyors.iter().map(|c| c.actuator.as_str()).chain([
            t.plus_actuator.as_str(),
            t.minus_actuator.as_str(),
            t.rotate_actuator.as_str(),
        ])
    }

    /// Every signal the layout names must exist in the plant, with the right kind.
    pub fn check_signals(&self, plant: &Plant) -> Vec<Problem> {
        let mut out = Vec::new();
        for a in self.drives() {
            if plant.output(a).is_none() {
                out.push(Problem::error(
                    codes::LAYOUT_UNKNOWN_SIGNAL.id,
                    format!("layout names actuator `{a}`, which the plant does not declare"),
                    self.location_of(a),
                ));
            }
        }
        for s in &self.sensors {
            if plant.input(&s.id).is_none() {
                out.push(Problem::error(
                    codes::LAYOUT_UNKNOWN_SIGNAL.id,
                    format!(
                        "layout names sensor `{}`, which the plant does not declare",
                        s.id
                    ),
                    self.location_of(&s.id),
                ));
            }
        }
        out
    }

    /// Dimensions of a size class.
    pub fn dims(&self, size: BoxSize) -> BoxDims {
        match size {
            BoxSize::Small => self.source.small,
            BoxSize::Large => self.source.large,
        }
    }
}

/// Longest internal simulation step of a layout, ms.
const MAX_STEP_MS: u64 = 1_000;

/// Line and column (1-based) of the first occurrence of each `"…"` string.
pub(crate) fn quoted_positions(text: &str) -> BTreeMap<String, (usize, usize)> {
    let mut map = BTreeMap::new();
    for (ln, line) in text.lines().enumerate() {
        let mut rest = line;
        let mut col = 0;
        while let Some(open) = rest.find('"') {
            // A `//` before the next quote starts a comment: a name quoted there is
            // not where the file declares it.
            if rest.find("//").is_some_and(|c| c < open) {
                break;
            }
            let after = &rest[open + 1..];
            let Some(close) = after.find('"') else { break };
            let s = &after[..close];
            let ccol = line[..col + open].chars().count() + 2;
            map.entry(s.to_string()).or_insert((ln + 1, ccol));
            col += open + close + 2;
            rest = &after[close + 1..];
        }
    }
    map
}

mod convert;
mod derive;

#[cfg(test)]
mod tests;
