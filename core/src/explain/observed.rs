//! Live mode, level 1: "the emulator is initialised from the observed inputs and
//! observers" (seed 004, section 5), so that a projection can be computed without the
//! real plant.
//!
//! From one [`CycleRecord`] (inputs and observers) and the layout:
//! 1. the table angle: the loading (unloading) angle when an ON angle sensor's window
//!    contains it, else the middle of an ON window, else half-way (rotating);
//! 2. a box for each set `Memory` observer whose rule reads `FE(a)` in its set and
//!    `RE(b)` in its reset (a box that left sensor `a` and has not reached `b`): placed at
//!    the world midpoint of `a` and `b`, on the part under that point (`P36`: on the
//!    table between C3 and C6; `P67`: on the table turned to the right exit, between C6
//!    and C7);
//! 3. a box for each ON presence sensor no box covers yet, covering it and as far
//!    towards its part's end as the part allows (`C0` → at the end of the entry
//!    conveyor, `C3` → at the end of the intermediate conveyor, `C6` → on the table,
//!    `C7`, `C8` → at the start of the exits); large when a high beam at the same place
//!    is ON (`C2` with `C1`), small otherwise.
//!
//! Counter observers (`2P`) add no box: the boxes they count cover their sensors.
//! No box arrives afterwards (the arrival plan is empty): what comes next is unknown.
//!
//! The estimate runs on the cell's components: those it was derived from, or those a
//! legacy `layout.ron` describes.

use crate::diag::Problem;
use crate::emulator::{ArrivalPlan, Beam, BoxSize, Layout, SensorKind};
use crate::expr::LeafKind;
use crate::history::CycleRecord;
use crate::machine::Physical;
use crate::observers::{Observers, Rule};
use crate::plant::Plant;

/// Turns the table of the cell's emulator to `mdeg` (the cell's table is placed at
/// heading 0).
fn set_angle(emu: &mut Physical, layout: &Layout, mdeg: i32) {
    let Physical::Components(c) = emu;
    c.set_position(&layout.table.id, f64::from(mdeg) / 1000.0);
}

/// Puts a box with its centre at `centre` mm along `part` (the table: `u`).
fn place_box(emu: &mut Physical, layout: &Layout, part: &str, centre: i64, size: BoxSize) -> bool {
    let Physical::Components(c) = emu;
    let along = if part == layout.table.id {
        centre + layout.table.half_length_mm
    } else {
        centre
    };
    #[allow(clippy::cast_precision_loss)]
    let along = along as f64;
    c.place_item(part, along, usize::from(size == BoxSize::Large))
        .is_ok()
}

/// A box placed so far: part id, centre (mm along the part, table: `u`), half length.
struct Placed {
    part: String,
    centre: i64,
    half: i64,
}

fn input_on(plant: &Plant, record: &CycleRecord, id: &str) -> bool {
    plant.input(id).is_some_and(|i| record.inputs.get(i))
}

/// Table axis direction at an angle in millidegrees.
fn axis(mdeg: i32) -> (f64, f64) {
    let r = f64::from(mdeg) / 1000.0 * std::f64::consts::PI / 180.0;
    (r.cos(), r.sin())
}

/// World position of a presence sensor (table sensors at the given table angle).
fn sensor_world(layout: &Layout, id: &str, angle: i32) -> Option<(f64, f64)> {
    let s = layout.sensors.iter().find(|s| s.id == id)?;
    let SensorKind::Presence { part, at_mm, .. } = &s.kind else {
        return None;
    };
    if *part == layout.table.id {
        let (ax, ay) = axis(angle);
        let c = &layout.table.center;
        return Some((
            c.x as f64 + ax * *at_mm as f64,
            c.y as f64 + ay * *at_mm as f64,
        ));
    }
    let c = layout.conveyors.iter().find(|c| &c.id == part)?;
    let (dx, dy) = ((c.end.x - c.start.x) as f64, (c.end.y - c.start.y) as f64);
    let len = dx.hypot(dy).max(1.0);
    let t = *at_mm as f64 / len;
    Some((c.start.x as f64 + dx * t, c.start.y as f64 + dy * t))
}

/// The part under a world point and the coordinate along it (table first).
fn part_at(layout: &Layout, p: (f64, f64), angle: i32) -> Option<(String, i64)> {
    let t = &layout.table;
    let (ax, ay) = axis(angle);
    let (rx, ry) = (p.0 - t.center.x as f64, p.1 - t.center.y as f64);
    let u = rx * ax + ry * ay;
    let lateral = (-rx * ay + ry * ax).abs();
    if u.abs() <= t.half_length_mm as f64 && lateral <= t.width_mm as f64 / 2.0 {
        return Some((t.id.clone(), u.round() as i64));
    }
    for c in &layout.conveyors {
        let (dx, dy) = ((c.end.x - c.start.x) as f64, (c.end.y - c.start.y) as f64);
        let len = dx.hypot(dy).max(1.0);
        let (qx, qy) = (p.0 - c.start.x as f64, p.1 - c.start.y as f64);
        let along = (qx * dx + qy * dy) / len;
        let lateral = ((-qx * dy + qy * dx) / len).abs();
        if (0.0..=len).contains(&along) && lateral <= c.width_mm as f64 / 2.0 {
            return Some((c.id.clone(), along.round() as i64));
        }
    }
    None
}

/// Length of a part, mm; the table is `[-half, half]`.
fn part_range(layout: &Layout, part: &str) -> Option<(i64, i64)> {
    if part == layout.table.id {
        let h = layout.table.half_length_mm;
        return Some((-h, h));
    }
    let c = layout.conveyors.iter().find(|c| c.id == part)?;
    let len = ((c.end.x - c.start.x) as f64).hypot((c.end.y - c.start.y) as f64);
    Some((0, len.round() as i64))
}

/// The first sensor read with `kind` in an observer expression.
fn sensor_with(text: &str, kind: LeafKind, plant: &Plant) -> Option<String> {
    let e = crate::expr::parse_str(text).ok()?;
    e.leaves()
        .into_iter()
        .find(|(n, k, _)| *k == kind && plant.input(n).is_some())
        .map(|(n, _, _)| n.to_string())
}

/// The table angle the angle sensors of `record` indicate, millidegrees.
fn observed_angle(layout: &Layout, plant: &Plant, record: &CycleRecord) -> i32 {
    let t = &layout.table;
    let mut windows = Vec::new();
    for s in &layout.sensors {
        if let SensorKind::Angle { min_mdeg, max_mdeg } = s.kind
            && input_on(plant, record, &s.id)
        {
            windows.push((min_mdeg, max_mdeg));
        }
    }
    for &(lo, hi) in &windows {
        for a in [t.loading_mdeg, t.unloading_mdeg] {
            if (lo..=hi).contains(&a) {
                return a;
            }
        }
    }
    match windows.first() {
        Some(&(lo, hi)) => lo + (hi - lo) / 2,
        None => t.loading_mdeg + (t.unloading_mdeg - t.loading_mdeg) / 2,
    }
}

/// An emulator in the state the observation shows: table angle from the angle sensors,
/// boxes where the presence sensors and the box-presence observers say (see the module
/// doc), no further arrivals. Fails only when the layout does not fit the plant.
pub fn emulator_from_observation(
    layout: &Layout,
    plant: &Plant,
    record: &CycleRecord,
    observers: &Observers,
) -> Result<Physical, Problem> {
    let mut emu = Physical::of_cell(layout, plant, 0)?;
    emu.set_arrivals(ArrivalPlan::List(Vec::new()));
    let angle = observed_angle(layout, plant, record);
    set_angle(&mut emu, layout, angle);
    let mut placed: Vec<Placed> = Vec::new();
    let place =
        |emu: &mut Physical, part: &str, centre: i64, size: BoxSize, placed: &mut Vec<Placed>| {
            let half = layout.dims(size).length_mm / 2;
            let Some((lo, hi)) = part_range(layout, part) else {
                return;
            };
            let centre = centre.clamp(lo + half, (hi - half - 1).max(lo + half));
            if place_box(emu, layout, part, centre, size) {
                placed.push(Placed {
                    part: part.to_string(),
                    centre,
                    half,
                });
            }
        };
    // Observers: boxes between two sensors.
    for (o, def) in observers.defs.iter().enumerate() {
        if !record.observers.get(o) {
            continue;
        }
        let Rule::Memory { set, reset } = &def.rule else {
            continue;
        };
        let (Some(a), Some(b)) = (
            sensor_with(set, LeafKind::Fall, plant),
            sensor_with(reset, LeafKind::Rise, plant),
        ) else {
            continue;
        };
        let (Some(pa), Some(pb)) = (
            sensor_world(layout, &a, angle),
            sensor_world(layout, &b, angle),
        ) else {
            continue;
        };
        let mid = ((pa.0 + pb.0) / 2.0, (pa.1 + pb.1) / 2.0);
        if let Some((part, at)) = part_at(layout, mid, angle) {
            place(&mut emu, &part, at, BoxSize::Small, &mut placed);
        }
    }
    // Presence sensors not covered yet; low beams first so that a high beam at the same
    // place makes the box large.
    let mut presence: Vec<(&str, &str, i64, Beam)> = layout
        .sensors
        .iter()
        .filter_map(|s| match &s.kind {
            SensorKind::Presence { part, at_mm, beam } => {
                Some((s.id.as_str(), part.as_str(), *at_mm, *beam))
            }
            SensorKind::Angle { .. } => None,
        })
        .filter(|(id, ..)| input_on(plant, record, id))
        .collect();
    presence.sort_by_key(|&(_, _, _, beam)| beam == Beam::High);
    for (_, part, at, beam) in presence {
        let covered = placed
            .iter()
            .any(|b| b.part == part && (b.centre - at).abs() <= b.half);
        if covered || beam == Beam::High && presence_high_only(layout, plant, record, part, at) {
            continue;
        }
        let high = layout.sensors.iter().any(|s| {
            matches!(&s.kind, SensorKind::Presence { part: p, at_mm, beam: Beam::High } if p == part && *at_mm == at)
                && input_on(plant, record, &s.id)
        });
        let size = if high { BoxSize::Large } else { BoxSize::Small };
        // Towards the end of the part: the box covers the sensor with its front.
        let half = layout.dims(size).length_mm / 2;
        place(&mut emu, part, at + half - 10, size, &mut placed);
    }
    Ok(emu)
}

/// A high beam ON with no low beam ON at the same place (a fault): no box for it.
fn presence_high_only(
    layout: &Layout,
    plant: &Plant,
    record: &CycleRecord,
    part: &str,
    at: i64,
) -> bool {
    !layout.sensors.iter().any(|s| {
        matches!(&s.kind, SensorKind::Presence { part: p, at_mm, beam: Beam::Low } if p == part && *at_mm == at)
            && input_on(plant, record, &s.id)
    })
}
