//! The turntable cell of a plant of components: the [`Layout`] the top view, the
//! verifier's abstract model and the live estimate of the items read, derived from
//! `components.ron` when its conveyors and its turntable are placed on the floor.
//!
//! A cell is what the paper's station is: placed conveyors with one forward drive
//! each, one of them with a source of two item classes, and one placed turntable with
//! two positions (the second while one output holds, the first while it does not) and
//! rollers driven both ways at one speed. Buttons and detectors may stand beside it.
//! Anything else (an axis, a tank, a third position) is not a cell: the plant is then
//! drawn as a schematic, and `vigie verify` searches its conveyors as belts.

use super::{
    ArrivalPlan, Beam, BoxDims, Conveyor, Elevator, Layout, Point, SensorDef, SensorKind, Side,
    SizeMix, Source, Turntable,
};
use crate::machine::Components;
use crate::machine::description::{ComponentDef, Placement};
use crate::machine::items::Mix;
use crate::machine::kinds::KindDef;
use crate::machine::kinds::conveyor::{ConveyorDef, Exit, ItemClass, SourceDef};
use crate::machine::kinds::turntable::{End, TurntableDef};

/// Rounds to the nearest integer (the layout's millimetres and millidegrees).
#[allow(clippy::cast_possible_truncation)]
fn round(v: f64) -> i64 {
    v.round() as i64
}

#[allow(clippy::cast_possible_truncation)]
fn milli(v: f64) -> i32 {
    (v * 1000.0).round() as i32
}

fn point(x: f64, y: f64) -> Point {
    Point {
        x: round(x),
        y: round(y),
    }
}

/// The one output of `when` (`A4`), or `None` for anything else.
fn output_of(when: &str) -> Option<&str> {
    let ok = !when.is_empty() && when.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    ok.then_some(when)
}

impl Layout {
    /// The cell of `desc`, or `None` when it is not one (see the module's text).
    pub fn from_components(desc: &Components) -> Option<Self> {
        Self::cell_of(desc).ok()
    }

    /// The cell of `desc`, or why it is not one (what `vigie check` says of a plant
    /// placed on the floor that is drawn as a schematic).
    pub fn cell_of(desc: &Components) -> Result<Self, String> {
        let mut conveyors = Vec::new();
        let mut sensors = Vec::new();
        let mut table = None;
        let mut source = None;
        let mut sinks = Vec::new();
        for c in &desc.components {
            match &c.kind {
                KindDef::Conveyor(v) => {
                    let at =
                        c.at.ok_or_else(|| format!("conveyor `{}` is not placed (`at`)", c.id))?;
                    conveyors.push(conveyor(c, v, at).ok_or_else(|| {
                        format!(
                            "conveyor `{}` has not one forward drive on one output",
                            c.id
                        )
                    })?);
                    sensors.extend(conveyor_sensors(c, v));
                    if let Some(src) = &v.source {
                        if source.is_some() {
                            return Err(format!("conveyor `{}` is a second source", c.id));
                        }
                        source = Some((c.id.clone(), src));
                    }
                    if v.exit == Exit::Sink {
                        sinks.push(c.id.clone());
                    }
                }
                KindDef::Turntable(t) if table.is_none() => {
                    let at =
                        c.at.ok_or_else(|| format!("turntable `{}` is not placed (`at`)", c.id))?;
                    table = Some(turntable(c, t, at).ok_or_else(|| {
                        format!(
                            "turntable `{}` is not a cell's: two positions (the second while \
                             one output holds, the first while it does not), heading 0, \
                             rollers driven both ways at one speed",
                            c.id
                        )
                    })?);
                    sensors.extend(table_sensors(c, t));
                }
                KindDef::Button(_) | KindDef::Detector(_) => {}
                KindDef::Turntable(_) => {
                    return Err(format!(
                        "turntable `{}` is a second one: a cell has one",
                        c.id
                    ));
                }
                k => {
                    return Err(format!(
                        "{} `{}` is not part of a turntable cell",
                        k.label(),
                        c.id
                    ));
                }
            }
        }
        let (table, plus_exit) = table.ok_or("there is no turntable")?;
        let (on, src) = source.ok_or("no conveyor has a source")?;
        let source = cell_source(desc, on, src).ok_or(
            "the source must place two classes, the second the only one the high beams see",
        )?;
        let high_beam_mm = (source.small.height_mm + source.large.height_mm) / 2;
        let elevators = elevators(desc, &sinks, plus_exit.as_deref())
            .ok_or("a cell has two placed conveyors ending in a sink")?;
        Ok(Self {
            name: desc.name.clone(),
            step_ms: desc.step_ms,
            straddle_margin_mm: round(desc.items.straddle_margin),
            shear_margin_mm: round(desc.items.shear_margin),
            push_tolerance_mm: round(desc.items.push_tolerance),
            high_beam_mm,
            conveyors,
            table,
            sensors,
            source,
            elevators,
            file: desc.file.clone(),
            positions: std::collections::BTreeMap::new(),
            derived_from: super::DerivedFrom(Some(std::sync::Arc::new(desc.clone()))),
        })
    }
}

/// A conveyor's beams as the layout's presence sensors (a beam that sees a tag is a
/// high beam).
fn conveyor_sensors<'a>(
    c: &'a ComponentDef,
    v: &'a ConveyorDef,
) -> impl Iterator<Item = SensorDef> + 'a {
    v.sensors.iter().map(|s| SensorDef {
        id: s.signal.clone(),
        kind: SensorKind::Presence {
            part: c.id.clone(),
            at_mm: round(s.at),
            beam: if s.sees.is_some() {
                Beam::High
            } else {
                Beam::Low
            },
        },
    })
}

/// A turntable's angle windows and its beams (along `u`, from the table's centre).
fn table_sensors(c: &ComponentDef, t: &TurntableDef) -> Vec<SensorDef> {
    let windows = t.sensors.iter().map(|w| SensorDef {
        id: w.signal.clone(),
        kind: SensorKind::Angle {
            min_mdeg: milli(w.from),
            max_mdeg: milli(w.to),
        },
    });
    let beams = t.beams.iter().map(|b| SensorDef {
        id: b.signal.clone(),
        kind: SensorKind::Presence {
            part: c.id.clone(),
            at_mm: round(b.at - t.length / 2.0),
            beam: Beam::Low,
        },
    });
    windows.chain(beams).collect()
}

/// The source of two classes (the second the one the high beams see), its arrivals
/// as the layout's plan.
fn cell_source(desc: &Components, on: String, src: &SourceDef) -> Option<Source> {
    let [small, large] = &src.items[..] else {
        return None;
    };
    let tags: Vec<&String> = desc
        .components
        .iter()
        .filter_map(|c| match &c.kind {
            KindDef::Conveyor(v) => Some(&v.sensors),
            _ => None,
        })
        .flatten()
        .filter_map(|s| s.sees.as_ref())
        .collect();
    if tags
        .iter()
        .any(|t| small.tags.contains(t) || !large.tags.contains(t))
    {
        return None;
    }
    let (small, mut large) = (dims(small), dims(large));
    large.height_mm = large.height_mm.max(small.height_mm + 2);
    Some(Source {
        conveyor: on,
        small,
        large,
        arrivals: ArrivalPlan::Periodic {
            period_ms: src.arrivals.period_ms,
            jitter_ms: src.arrivals.jitter_ms,
            mix: match src.arrivals.mix {
                Mix::InTurn => SizeMix::Alternate,
                Mix::SecondPercent(p) => SizeMix::RandomLarge(p),
            },
            count: src.arrivals.count,
        },
    })
}

fn conveyor(c: &ComponentDef, v: &ConveyorDef, at: Placement) -> Option<Conveyor> {
    let [drive] = &v.drives[..] else {
        return None;
    };
    if drive.speed <= 0.0 || output_of(&drive.when).is_none() {
        return None;
    }
    let h = at.heading.to_radians();
    Some(Conveyor {
        id: c.id.clone(),
        name: c.name.clone(),
        start: point(at.x, at.y),
        end: point(at.x + v.length * h.cos(), at.y + v.length * h.sin()),
        width_mm: round(at.width),
        speed_mm_s: round(drive.speed),
        actuator: drive.when.clone(),
    })
}

/// The table, and the conveyor its rollers' end (`+u`) meets at the second position.
fn turntable(
    c: &ComponentDef,
    t: &TurntableDef,
    at: Placement,
) -> Option<(Turntable, Option<String>)> {
    let [load, unload] = &t.positions[..] else {
        return None;
    };
    let rotate = output_of(&unload.when)?;
    if load.when != format!("/{rotate}") || at.heading != 0.0 {
        return None;
    }
    let [a, b] = &t.rollers[..] else {
        return None;
    };
    let (plus, minus) = if a.speed > 0.0 { (a, b) } else { (b, a) };
    if plus.speed <= 0.0 || minus.speed != -plus.speed {
        return None;
    }
    let plus_exit = unload
        .joins
        .iter()
        .find(|j| j.end == End::End)
        .map(|j| j.to.clone());
    let table = Turntable {
        id: c.id.clone(),
        name: c.name.clone(),
        center: point(at.x, at.y),
        half_length_mm: round(t.length / 2.0),
        width_mm: round(at.width),
        roller_speed_mm_s: round(plus.speed),
        plus_actuator: output_of(&plus.when)?.to_string(),
        minus_actuator: output_of(&minus.when)?.to_string(),
        rotate_actuator: rotate.to_string(),
        loading_mdeg: milli(load.at),
        unloading_mdeg: milli(unload.at),
        out_speed_udeg_ms: round(t.speed * 1000.0),
        back_speed_udeg_ms: round(t.back_speed.unwrap_or(t.speed) * 1000.0),
        speed_variation_ppm: i64::from(t.variation_ppm),
        dock_tolerance_mdeg: milli(t.dock_tolerance),
    };
    Some((table, plus_exit))
}

fn dims(c: &ItemClass) -> BoxDims {
    BoxDims {
        length_mm: round(c.length),
        width_mm: round(c.width.unwrap_or(c.length)),
        height_mm: round(c.height.unwrap_or(c.length)),
    }
}

/// The two sinks: the one the rollers' `+u` end leads to is the left, the other the
/// right; each drawn 150 mm past its conveyor's end.
fn elevators(desc: &Components, sinks: &[String], plus: Option<&str>) -> Option<Vec<Elevator>> {
    let [a, b] = sinks else {
        return None;
    };
    let (left, right) = if plus == Some(b.as_str()) {
        (b, a)
    } else {
        (a, b)
    };
    let place = |id: &String| {
        let c = desc.components.iter().find(|c| &c.id == id)?;
        let (KindDef::Conveyor(v), Some(at)) = (&c.kind, c.at) else {
            return None;
        };
        let h = at.heading.to_radians();
        let d = v.length + 150.0;
        Some(point(at.x + d * h.cos(), at.y + d * h.sin()))
    };
    Some(vec![
        Elevator {
            side: Side::Left,
            conveyor: left.clone(),
            at: place(left)?,
        },
        Elevator {
            side: Side::Right,
            conveyor: right.clone(),
            at: place(right)?,
        },
    ])
}
