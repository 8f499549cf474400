//! The emulator's internal model: parts (conveyors and the table) as 1-D axes joined at
//! their ends, and the public views (boxes, hazards, statistics).

use super::layout::{BoxSize, Layout, Side};
use serde::Serialize;

/// Start (0) or end (1) of a part axis.
pub(crate) const START: u8 = 0;
/// End of a part axis.
pub(crate) const END: u8 = 1;

/// One end of a part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Link {
    pub(crate) part: u8,
    pub(crate) end: u8,
}

/// What lies beyond one end of a part.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct EndKind {
    /// Always joined to this end.
    pub(crate) fixed: Option<Link>,
    /// Joined while the table is exactly at the loading angle.
    pub(crate) at_load: Option<Link>,
    /// Joined while the table is exactly at the unloading angle.
    pub(crate) at_unload: Option<Link>,
    /// A box whose centre passes this end is delivered to that elevator.
    pub(crate) sink: Option<Side>,
    /// The table is beyond this end (at some angle).
    pub(crate) table_side: bool,
}

/// A conveyor or the table, as an axis `0..len` in µm.
#[derive(Clone, Debug)]
pub(crate) struct Part {
    /// Layout id (`entry`, `table`…), for the place of a hazard in data.
    pub(crate) id: String,
    pub(crate) name: String,
    pub(crate) len: i64,
    /// Drive speed, µm per ms (= mm/s).
    pub(crate) speed: i64,
    pub(crate) ends: [EndKind; 2],
    /// Actuator ids, for hazard reports.
    pub(crate) actuators: Vec<String>,
    /// World start point and unit direction (conveyors), mm.
    pub(crate) origin: (f64, f64),
    pub(crate) dir: (f64, f64),
    pub(crate) angle_mdeg: i32,
}

/// Where the table stands, for joins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TablePos {
    Load,
    Unload,
    Other,
}

/// A box in transit, positions in µm along its part.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Body {
    pub(crate) id: u32,
    pub(crate) size: BoxSize,
    pub(crate) half: i64,
    pub(crate) height_mm: i64,
    pub(crate) part: u8,
    pub(crate) c: i64,
    pub(crate) damaged: bool,
    /// Hazard kinds already reported, one bit per [`HazardKind`].
    pub(crate) reported: u8,
    /// How far a driving surface has slid under it against a stopped one without a
    /// break, µm.
    pub(crate) slip: i64,
}

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

/// Builds the parts of a layout (conveyors first, then the table) and joins their ends
/// by geometry: ends closer than 1 mm are joined, the table's ends are computed at the
/// loading and unloading angles.
pub(crate) fn build_parts(layout: &Layout) -> Vec<Part> {
    let mut parts: Vec<Part> = layout
        .conveyors
        .iter()
        .map(|c| {
            let (dx, dy) = ((c.end.x - c.start.x) as f64, (c.end.y - c.start.y) as f64);
            let len = dx.hypot(dy);
            Part {
                id: c.id.clone(),
                name: c.name.clone(),
                len: (len * 1000.0).round() as i64,
                speed: c.speed_mm_s,
                ends: [EndKind::default(); 2],
                actuators: vec![c.actuator.clone()],
                origin: (c.start.x as f64, c.start.y as f64),
                dir: (dx / len, dy / len),
                angle_mdeg: (dy.atan2(dx).to_degrees() * 1000.0).round() as i32,
            }
        })
        .collect();
    let t = &layout.table;
    let n = parts.len();
    parts.push(Part {
        id: t.id.clone(),
        name: t.name.clone(),
        len: 2 * t.half_length_mm * 1000,
        speed: t.roller_speed_mm_s,
        ends: [EndKind::default(); 2],
        actuators: vec![t.plus_actuator.clone(), t.minus_actuator.clone()],
        origin: (t.center.x as f64, t.center.y as f64),
        dir: (1.0, 0.0),
        angle_mdeg: 0,
    });
    let end_point = |c: &super::layout::Conveyor, e: u8| if e == START { c.start } else { c.end };
    let close = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).hypot(a.1 - b.1) < 1.0;
    let table_end = |mdeg: i32, e: u8| {
        let a = (mdeg as f64 / 1000.0).to_radians();
        let s = if e == START { -1.0 } else { 1.0 } * t.half_length_mm as f64;
        (
            t.center.x as f64 + s * a.cos(),
            t.center.y as f64 + s * a.sin(),
        )
    };
    for (i, ci) in layout.conveyors.iter().enumerate() {
        for ei in [START, END] {
            let pi = end_point(ci, ei);
            let pi = (pi.x as f64, pi.y as f64);
            for (j, cj) in layout.conveyors.iter().enumerate() {
                for ej in [START, END] {
                    let pj = end_point(cj, ej);
                    if (i, ei) != (j, ej) && close(pi, (pj.x as f64, pj.y as f64)) {
                        parts[i].ends[ei as usize].fixed = Some(Link {
                            part: j as u8,
                            end: ej,
                        });
                    }
                }
            }
            for te in [START, END] {
                let tl = Link {
                    part: n as u8,
                    end: te,
                };
                let me = Link {
                    part: i as u8,
                    end: ei,
                };
                if close(pi, table_end(t.loading_mdeg, te)) {
                    parts[i].ends[ei as usize].at_load = Some(tl);
                    parts[i].ends[ei as usize].table_side = true;
                    parts[n].ends[te as usize].at_load = Some(me);
                }
                if close(pi, table_end(t.unloading_mdeg, te)) {
                    parts[i].ends[ei as usize].at_unload = Some(tl);
                    parts[i].ends[ei as usize].table_side = true;
                    parts[n].ends[te as usize].at_unload = Some(me);
                }
            }
        }
    }
    for e in &layout.elevators {
        if let Some(i) = layout.conveyors.iter().position(|c| c.id == e.conveyor) {
            parts[i].ends[END as usize].sink = Some(e.side);
        }
    }
    parts[n].ends[0].table_side = true;
    parts[n].ends[1].table_side = true;
    parts
}
