//! The public views of a running plant's items and hazards (boxes, hazards,
//! statistics), shared by the emulator, the synoptic and the reports.

use super::layout::{BoxSize, Side};
use serde::Serialize;

/// Where a box is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxState {
    /// On a conveyor or the table.
    Transit,
    /// Fell off; lies where it fell.
    Fallen,
    /// Taken by an elevator.
    Delivered(Side),
}

/// A box as seen from outside (synoptic, explanations).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BoxView {
    /// Box number, from 1 in creation order.
    pub id: u32,
    /// Size class.
    pub size: BoxSize,
    /// Length along travel, mm.
    pub length_mm: i64,
    /// Width, mm.
    pub width_mm: i64,
    /// World centre x, mm.
    pub x_mm: f32,
    /// World centre y, mm.
    pub y_mm: f32,
    /// Orientation of its travel axis, millidegrees.
    pub angle_mdeg: i32,
    /// Damaged by a hazard.
    pub damaged: bool,
    /// Transit, fallen or delivered.
    pub state: BoxState,
}

/// Counts of items.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct BoxStats {
    /// Items put on the line (arrivals, feeders and `place_box`).
    pub created: u32,
    /// Items out, by exit: the conveyor whose end leads into the sink, or whose taker
    /// took them.
    pub delivered: std::collections::BTreeMap<String, u32>,
    /// Boxes damaged by at least one hazard.
    pub damaged: u32,
    /// Boxes taken off the plant by hand (the operator emptying it before a
    /// re-initialisation), fallen ones included.
    pub removed: u32,
}

impl BoxStats {
    /// Items out, all exits together.
    pub fn delivered_total(&self) -> u32 {
        self.delivered.values().sum()
    }

    /// Items out at exit `id`.
    pub fn delivered_at(&self, id: &str) -> u32 {
        self.delivered.get(id).copied().unwrap_or(0)
    }
}

/// The dangerous states the emulator detects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HazardKind {
    /// The table rotated while a box straddled its edge.
    Sheared,
    /// A box was pushed off an end where nothing continues.
    Dropped,
    /// A driven box was blocked by another box not moving away as fast.
    Collision,
    /// A box across two surfaces was pushed by one against the other, stopped or reversed.
    PushedAgainstStopped,
    /// A mechanism was driven into the end of its travel where that is a crash.
    EndStop,
    /// A mechanism was driven both ways at once.
    OpposedDrives,
    /// A state the plant's expert declared dangerous (`dangers` in `components.ron`).
    Declared,
    /// A tank filled past its capacity: it spills.
    Overflow,
    /// A pump drawing from an empty tank: it runs dry.
    DryRun,
}

/// Where a hazard happened, by the layout ids of the parts involved.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Place {
    /// At the edge of the rotating part.
    Edge {
        /// The rotating part.
        part: String,
    },
    /// On a part, against another item.
    Against {
        /// The part.
        part: String,
        /// The other item.
        item: u32,
    },
    /// Off the start or the end of a part.
    Off {
        /// The part.
        part: String,
        /// True at its end, false at its start.
        end: bool,
    },
    /// On a component as a whole (a mechanism).
    Component {
        /// The component.
        part: String,
    },
    /// A declared dangerous state of a component.
    Danger {
        /// The component.
        part: String,
        /// The danger's id.
        danger: String,
    },
    /// Across two parts.
    Between {
        /// The part driving the item.
        part: String,
        /// The part it is pushed against.
        other: String,
    },
}

impl Place {
    /// The place as fields of an explanation or an alarm: `place_kind` (`edge`,
    /// `against`, `end`, `start`, `between`), `part`, and `other` / `other_item` where
    /// they apply.
    pub fn fields(&self) -> Vec<(String, String)> {
        let mut f = Vec::new();
        let mut put = |k: &str, v: String| f.push((k.to_string(), v));
        match self {
            Self::Edge { part } => {
                put("place_kind", "edge".into());
                put("part", part.clone());
            }
            Self::Against { part, item } => {
                put("place_kind", "against".into());
                put("part", part.clone());
                put("other_item", item.to_string());
            }
            Self::Off { part, end } => {
                put("place_kind", if *end { "end" } else { "start" }.into());
                put("part", part.clone());
            }
            Self::Component { part } => {
                put("place_kind", "component".into());
                put("part", part.clone());
            }
            Self::Danger { part, danger } => {
                put("place_kind", "danger".into());
                put("part", part.clone());
                put("danger", danger.clone());
            }
            Self::Between { part, other } => {
                put("place_kind", "between".into());
                put("part", part.clone());
                put("other", other.clone());
            }
        }
        f
    }
}

/// One dangerous state, reported once per box and kind.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Hazard {
    /// When, ms.
    pub time_ms: u64,
    /// What.
    pub kind: HazardKind,
    /// Where, in words (English, from the layout's names).
    pub place: String,
    /// Where, as data, for a translation to build its own words.
    pub at: Place,
    /// Actuators involved.
    pub elements: Vec<String>,
    /// The damaged box.
    pub box_id: u32,
}

impl Hazard {
    /// One line for the journal: the kind, the box for a hazard to a box, the place.
    pub fn summary(&self) -> String {
        match self.at {
            Place::Component { .. } | Place::Danger { .. } => {
                format!("{:?} at {}", self.kind, self.place)
            }
            _ => format!("{:?} of box {} at {}", self.kind, self.box_id, self.place),
        }
    }
}
