//! A legacy `layout.ron` read as the components it describes: the turntable cell of
//! the station's first emulator, re-expressed as conveyors, a turntable and sinks, so
//! that a folder that still holds a layout file runs on the components emulator like
//! every other plant. The inverse of [`Layout::from_components`] (`derive.rs`).
//!
//! What the layout said by geometry becomes data: a conveyor whose end meets another's
//! start (within 1 mm) exits onto it, one with an elevator exits into a sink, one whose
//! end meets a table end at a table position exits onto the table, any other drops its
//! items; the table joins, at each position, the conveyors whose ends meet its ends
//! there. A high beam sees the item classes taller than the layout's `high_beam_mm`
//! (tag `tall`).

use super::{ArrivalPlan, Beam, BoxDims, Conveyor, Layout, Point, SensorKind, SizeMix};
use crate::diag::{Problem, codes};
use crate::machine::Components;
use crate::machine::description::{ComponentDef, Placement};
use crate::machine::items::{ArrivalsDef, ItemsDef, Mix};
use crate::machine::kinds::KindDef;
use crate::machine::kinds::axis::{DriveDef, WindowDef};
use crate::machine::kinds::conveyor::{BeamDef, ConveyorDef, Exit, ItemClass, SourceDef};
use crate::machine::kinds::turntable::{End, JoinDef, PositionDef, TurntableDef};

/// The tag of the classes a high beam sees.
const TALL: &str = "tall";

/// Ends closer than this are joined, mm (the first emulator's rule).
const JOIN_MM: f64 = 1.0;

fn near(a: (f64, f64), b: (f64, f64)) -> bool {
    (a.0 - b.0).hypot(a.1 - b.1) <= JOIN_MM
}

#[allow(clippy::cast_precision_loss)]
fn xy(p: Point) -> (f64, f64) {
    (p.x as f64, p.y as f64)
}

impl Layout {
    /// The components this layout describes (see the module's text). Messages about
    /// them point into the layout file.
    pub fn to_components(&self) -> Result<Components, Vec<Problem>> {
        let mut components: Vec<ComponentDef> = Vec::new();
        for c in &self.conveyors {
            components.push(self.conveyor(c)?);
        }
        components.push(self.turntable());
        let items = ItemsDef {
            straddle_margin: f(self.straddle_margin_mm),
            shear_margin: f(self.shear_margin_mm),
            push_tolerance: f(self.push_tolerance_mm),
            ..ItemsDef::default()
        };
        Components::assembled(
            self.name.clone(),
            self.step_ms,
            components,
            items,
            &self.file,
            self.positions.clone(),
        )
    }

    fn conveyor(&self, c: &Conveyor) -> Result<ComponentDef, Vec<Problem>> {
        let (start, end) = (xy(c.start), xy(c.end));
        let length = (end.0 - start.0).hypot(end.1 - start.1);
        let sensors = self
            .sensors
            .iter()
            .filter_map(|s| match &s.kind {
                SensorKind::Presence { part, at_mm, beam } if part == &c.id => Some(BeamDef {
                    signal: s.id.clone(),
                    at: f(*at_mm),
                    sees: (*beam == Beam::High).then(|| TALL.to_string()),
                }),
                _ => None,
            })
            .collect();
        let source = if self.source.conveyor == c.id {
            Some(self.source_def()?)
        } else {
            None
        };
        let def = ConveyorDef {
            unit: "mm".to_string(),
            length,
            drives: vec![DriveDef {
                when: c.actuator.clone(),
                speed: f(c.speed_mm_s),
            }],
            sensors,
            motion: None,
            feed: None,
            take: None,
            exit: self.exit_of(c),
            variation_ppm: 0,
            accumulating: false,
            source,
        };
        Ok(ComponentDef {
            id: c.id.clone(),
            name: c.name.clone(),
            kind: KindDef::Conveyor(def),
            at: Some(Placement {
                x: start.0,
                y: start.1,
                heading: (end.1 - start.1).atan2(end.0 - start.0).to_degrees(),
                width: f(c.width_mm),
            }),
        })
    }

    /// Where a conveyor's end leads: a sink, the next conveyor, the table, or nothing.
    fn exit_of(&self, c: &Conveyor) -> Exit {
        if self.elevators.iter().any(|e| e.conveyor == c.id) {
            return Exit::Sink;
        }
        let end = xy(c.end);
        if let Some(next) = self
            .conveyors
            .iter()
            .find(|n| n.id != c.id && near(xy(n.start), end))
        {
            return Exit::To(next.id.clone());
        }
        let onto_table = [self.table.loading_mdeg, self.table.unloading_mdeg]
            .iter()
            .any(|&a| self.table_ends(a).iter().any(|&p| near(p, end)));
        if onto_table {
            Exit::To(self.table.id.clone())
        } else {
            Exit::Drop
        }
    }

    /// The table's `-u` and `+u` ends at angle `mdeg`.
    fn table_ends(&self, mdeg: i32) -> [(f64, f64); 2] {
        let t = &self.table;
        let a = (f64::from(mdeg) / 1000.0).to_radians();
        let (c, h) = (xy(t.center), f(t.half_length_mm));
        [
            (c.0 - h * a.cos(), c.1 - h * a.sin()),
            (c.0 + h * a.cos(), c.1 + h * a.sin()),
        ]
    }

    /// What the table's ends meet at angle `mdeg`.
    fn joins_at(&self, mdeg: i32) -> Vec<JoinDef> {
        let mut joins = Vec::new();
        for (end, p) in [End::Start, End::End]
            .into_iter()
            .zip(self.table_ends(mdeg))
        {
            for c in &self.conveyors {
                for (at, q) in [(End::Start, c.start), (End::End, c.end)] {
                    if near(xy(q), p) {
                        joins.push(JoinDef {
                            end,
                            to: c.id.clone(),
                            at,
                        });
                    }
                }
            }
        }
        joins
    }

    fn turntable(&self) -> ComponentDef {
        let t = &self.table;
        let deg = |mdeg: i32| f64::from(mdeg) / 1000.0;
        let mut sensors = Vec::new();
        let mut beams = Vec::new();
        for s in &self.sensors {
            match &s.kind {
                SensorKind::Angle { min_mdeg, max_mdeg } => sensors.push(WindowDef {
                    signal: s.id.clone(),
                    from: deg(*min_mdeg),
                    to: deg(*max_mdeg),
                }),
                SensorKind::Presence { part, at_mm, beam } if part == &t.id => {
                    beams.push(BeamDef {
                        signal: s.id.clone(),
                        at: f(*at_mm + t.half_length_mm),
                        sees: (*beam == Beam::High).then(|| TALL.to_string()),
                    });
                }
                SensorKind::Presence { .. } => {}
            }
        }
        let rotate = &t.rotate_actuator;
        let def = TurntableDef {
            unit: "deg".to_string(),
            start: deg(t.loading_mdeg),
            positions: vec![
                PositionDef {
                    at: deg(t.loading_mdeg),
                    when: format!("/{rotate}"),
                    joins: self.joins_at(t.loading_mdeg),
                },
                PositionDef {
                    at: deg(t.unloading_mdeg),
                    when: rotate.clone(),
                    joins: self.joins_at(t.unloading_mdeg),
                },
            ],
            speed: f(t.out_speed_udeg_ms) / 1000.0,
            back_speed: Some(f(t.back_speed_udeg_ms) / 1000.0),
            variation_ppm: u32::try_from(t.speed_variation_ppm).unwrap_or(u32::MAX),
            dock_tolerance: deg(t.dock_tolerance_mdeg),
            sensors,
            length: f(2 * t.half_length_mm),
            rollers: vec![
                DriveDef {
                    when: t.plus_actuator.clone(),
                    speed: f(t.roller_speed_mm_s),
                },
                DriveDef {
                    when: t.minus_actuator.clone(),
                    speed: -f(t.roller_speed_mm_s),
                },
            ],
            beams,
        };
        ComponentDef {
            id: t.id.clone(),
            name: t.name.clone(),
            kind: KindDef::Turntable(def),
            at: Some(Placement {
                x: xy(t.center).0,
                y: xy(t.center).1,
                heading: 0.0,
                width: f(t.width_mm),
            }),
        }
    }

    /// The source: the two box sizes as classes (the taller than the high beam tagged
    /// `tall`), and its periodic arrivals.
    fn source_def(&self) -> Result<SourceDef, Vec<Problem>> {
        let class = |name: &str, d: &BoxDims| ItemClass {
            class: name.to_string(),
            length: f(d.length_mm),
            tags: if d.height_mm > self.high_beam_mm {
                vec![TALL.to_string()]
            } else {
                Vec::new()
            },
            width: Some(f(d.width_mm)),
            height: Some(f(d.height_mm)),
        };
        let arrivals = match &self.source.arrivals {
            ArrivalPlan::Off => ArrivalsDef {
                period_ms: 1,
                jitter_ms: 0,
                count: Some(0),
                mix: Mix::InTurn,
            },
            ArrivalPlan::Periodic {
                period_ms,
                jitter_ms,
                mix,
                count,
            } => ArrivalsDef {
                period_ms: *period_ms,
                jitter_ms: *jitter_ms,
                count: *count,
                mix: match mix {
                    SizeMix::Alternate => Mix::InTurn,
                    SizeMix::RandomLarge(p) => Mix::SecondPercent(*p),
                },
            },
            ArrivalPlan::List(_) => {
                return Err(vec![Problem::error(
                    codes::LAYOUT_INVALID.id,
                    "an explicit list of arrivals in layout.ron has no equivalent in a \
                     plant's description: move it to the scenarios (`arrivals: \
                     Some(List([...]))`) and give the layout `Periodic` or `Off`"
                        .to_string(),
                    self.location_of("arrivals:"),
                )]);
            }
        };
        Ok(SourceDef {
            items: vec![
                class("small", &self.source.small),
                class("large", &self.source.large),
            ],
            arrivals,
        })
    }
}

#[allow(clippy::cast_precision_loss)]
fn f(v: i64) -> f64 {
    v as f64
}
