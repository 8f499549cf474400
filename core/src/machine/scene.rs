//! What the synoptic draws of a plant described as components: one element per
//! component, with its kind's shape and its state. The console has one painter per
//! shape and no drawing code per plant.

use serde::Serialize;

/// The plant as the synoptic draws it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Scene {
    /// The components, in the order of `components.ron`.
    pub elements: Vec<SceneElement>,
}

/// One component.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneElement {
    /// Its id.
    pub id: String,
    /// Its display name.
    pub name: String,
    /// What to draw.
    pub shape: Shape,
}

/// The shapes of the kinds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Shape {
    /// An axis: its travel, where it is, its sensors' windows and its drives.
    Axis {
        /// How it is drawn.
        symbol: crate::machine::kinds::axis::AxisSymbol,
        /// The unit (`mm`, `deg`).
        unit: String,
        /// Start of the travel.
        min: f64,
        /// End of the travel.
        max: f64,
        /// The position now.
        position: f64,
        /// -1, 0 or 1: the way it moves (0 when blocked or at rest).
        direction: i8,
        /// The sensors along it.
        sensors: Vec<SceneSensor>,
        /// Its drives.
        drives: Vec<SceneDrive>,
        /// Its motion sensor.
        motion: Option<String>,
    },
    /// A tank: its capacity, its level, its level sensors' windows, its flows and
    /// which of them run.
    Tank {
        /// The unit (`l`).
        unit: String,
        /// Full.
        capacity: f64,
        /// The level now.
        level: f64,
        /// The level sensors.
        sensors: Vec<SceneSensor>,
        /// The flows (`speed`: their rate, units/s, + fills).
        flows: Vec<SceneDrive>,
        /// Which flow runs now, by index.
        running: Vec<bool>,
    },
    /// A conveyor: its belt, its items and its beams.
    Conveyor {
        /// The unit (`mm`).
        unit: String,
        /// The belt's length.
        length: f64,
        /// -1, 0 or 1: the way the belt really moves.
        direction: i8,
        /// The items on it, entry first.
        items: Vec<SceneItem>,
        /// The beams (`from` = `to`: the beam's place).
        sensors: Vec<SceneSensor>,
        /// Its drives.
        drives: Vec<SceneDrive>,
        /// Its exit end: `stop`, `drop`, `sink` or the next conveyor's id.
        exit: String,
        /// Its motion sensor.
        motion: Option<String>,
        /// Its feeder's condition.
        feed: Option<String>,
    },
    /// A turntable: its angle and positions, and its rollers with their items.
    Turntable {
        /// The unit of the angle (`deg`).
        unit: String,
        /// The angle now.
        angle: f64,
        /// The positions' angles.
        positions: Vec<f64>,
        /// The position it stands at, by index.
        docked: Option<usize>,
        /// The angle sensors' windows.
        sensors: Vec<SceneSensor>,
        /// What turns it: each position's condition, with the speed towards it.
        turns: Vec<SceneDrive>,
        /// The rollers' length.
        length: f64,
        /// -1, 0 or 1: the way the rollers move.
        direction: i8,
        /// The items on the rollers, from their start.
        items: Vec<SceneItem>,
        /// The beams along the rollers.
        beams: Vec<SceneSensor>,
        /// The rollers' drives.
        rollers: Vec<SceneDrive>,
    },
    /// A device with no geometry (a relay, a bus variable): its signals, drawn in the
    /// schematic strip.
    Device {
        /// The plant signals it reads or writes.
        signals: Vec<String>,
    },
    /// A panel push button.
    Button {
        /// The plant input it closes.
        signal: String,
        /// Held down now.
        pressed: bool,
    },
}

/// A position sensor's window; the painter reads its value from the frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneSensor {
    /// The plant input.
    pub signal: String,
    /// Start of its window.
    pub from: f64,
    /// End of its window.
    pub to: f64,
}

/// A drive, for the legend.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneDrive {
    /// Its condition over the outputs.
    pub when: String,
    /// Units per second, signed.
    pub speed: f64,
    /// A sensor in series that sees it run (a tank line's flow sensor).
    pub sensor: Option<String>,
}

/// An item on a conveyor.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneItem {
    /// Its number.
    pub id: u32,
    /// Its class.
    pub class: String,
    /// Its rear end from the entry.
    pub rear: f64,
    /// Its length.
    pub length: f64,
}
