//! The synoptic of a plant described as components: its geometry comes from the
//! emulator's [`Scene`], one painter per shape, no drawing code per plant.
//!
//! An axis is drawn as a vertical guide, its travel's start at the top (a drill head
//! descends, a lift rises to its top), the carriage where it stands, each position
//! sensor's lamp left of the guide at its window, and the outputs of its drives right
//! of it. The signals no component places go to the schematic strip below.

use super::{Canvas, Geometry, SensorGeom, View, Xf, place_schematic};
use egui::{Align2, FontId, Pos2, Rect, Shape as EShape, Stroke, Vec2, vec2};
use std::collections::BTreeMap;
use vigie_core::emulator::{Hazard, Place};
use vigie_core::machine::kinds::axis::AxisSymbol;
use vigie_core::machine::scene::{SceneDrive, SceneItem, SceneSensor};
use vigie_core::machine::{Scene, SceneElement, Shape};
use vigie_core::plant::Plant;

/// Drawn length of an axis's travel, world units.
const GUIDE: f32 = 2400.0;
/// Distance between two axes, world units.
const PITCH: f32 = 2200.0;
/// Distance between two vessels: their lines run right of them.
const VESSEL_PITCH: f32 = 3600.0;
/// Half the width of a drawn vessel.
const VESSEL_HALF: f32 = 420.0;

/// A drawn axis.
#[derive(Clone, Debug)]
pub struct AxisGeom {
    /// Component id.
    pub id: String,
    /// Display name.
    pub name: String,
    /// Top of the guide (the travel's start), world.
    pub top: [f32; 2],
    /// Start and end of the travel, in the component's unit.
    pub range: (f64, f64),
    /// The position, in the unit.
    pub position: f64,
    /// The way it moves.
    pub direction: i8,
    /// The unit.
    pub unit: String,
    /// A vessel (a tank: its level from the bottom) rather than a carriage on a guide
    /// (its travel's start at the top).
    pub vessel: bool,
    /// A switching device (a breaker): drawn as the one-line diagram's square.
    pub switch: bool,
}

impl AxisGeom {
    /// World point of `position` on the guide.
    fn at(&self, position: f64) -> [f32; 2] {
        let span = (self.range.1 - self.range.0).max(1e-9);
        #[allow(clippy::cast_possible_truncation)]
        let k = ((position - self.range.0) / span).clamp(0.0, 1.0) as f32;
        let k = if self.vessel { 1.0 - k } else { k };
        [self.top[0], self.top[1] - GUIDE * k]
    }
}

impl Geometry {
    /// Places every component of `scene`, and every other signal of `plant` in the
    /// schematic strip.
    pub fn from_scene(scene: &Scene, plant: &Plant) -> Self {
        let mut sensors = Vec::new();
        let mut actuators = BTreeMap::new();
        let mut axes: Vec<AxisGeom> = Vec::new();
        // Each from the previous one: a vessel's lines need more room than an axis's.
        let mut x = 0.0;
        for e in &scene.elements {
            if let Some(last) = axes.last() {
                let vessels = [last.vessel, matches!(e.shape, Shape::Tank { .. })];
                x += match vessels {
                    [false, false] => PITCH,
                    [true, true] => VESSEL_PITCH,
                    _ => (PITCH + VESSEL_PITCH) / 2.0,
                };
            }
            match &e.shape {
                Shape::Axis {
                    symbol,
                    unit,
                    min,
                    max,
                    position,
                    direction,
                    sensors: windows,
                    drives,
                    motion,
                } => {
                    let a = AxisGeom {
                        id: e.id.clone(),
                        name: e.name.clone(),
                        top: [x, 0.0],
                        range: (*min, *max),
                        position: *position,
                        direction: *direction,
                        unit: unit.clone(),
                        vessel: false,
                        switch: *symbol == AxisSymbol::Switch,
                    };
                    place_signals(&a, windows, drives, plant, &mut sensors, &mut actuators);
                    if let Some(m) = motion {
                        // The motion sensor under the drives' outputs.
                        sensors.push(SensorGeom {
                            id: m.clone(),
                            lamp: [x + 900.0, -GUIDE * 0.15 - 380.0 * 3.0],
                            beam: None,
                            high: false,
                        });
                    }
                    axes.push(a);
                }
                // A turntable turns as an axis (its rollers are a belt of the rows);
                // buttons go to the schematic strip; conveyors to rows (below).
                Shape::Turntable { .. } | Shape::Tank { .. } => {
                    axes.push(drawn_axis(e, x, plant, &mut sensors, &mut actuators));
                }
                Shape::Button { .. } | Shape::Conveyor { .. } | Shape::Device { .. } => {}
            }
        }
        let belts = place_belts(scene, plant, &mut sensors, &mut actuators);
        let right = if axes.last().is_some_and(|a| a.vessel) {
            VESSEL_PITCH - 900.0
        } else {
            1400.0
        };
        let mut min = [-1100.0, -GUIDE - 500.0];
        let mut max = [x.max(PITCH) + right, 600.0];
        if axes.is_empty() {
            min[1] = -300.0;
        }
        for b in &belts {
            max[0] = max[0].max(b.origin[0] + b.drawn + 900.0);
            max[1] = max[1].max(b.origin[1] + 700.0).max(b.top);
            min[1] = min[1].min(b.origin[1] - 900.0);
        }
        let schematic = place_schematic(plant, &mut sensors, &mut actuators, (&mut min, &mut max));
        Self {
            sensors,
            actuators,
            bounds: (min, max),
            axes,
            belts,
            schematic,
            ..Self::default()
        }
    }
}

/// The drawn length of the longest conveyor, world units.
const BELT: f32 = 3600.0;
/// Distance between two rows of conveyors.
const BELT_ROW: f32 = 1500.0;
/// Beams' lamps closer than this along a belt go on different levels.
const BEAM_ROOM: f32 = 700.0;
/// Half the drawn width of a belt.
const BELT_HALF: f32 = 160.0;

/// A drawn conveyor.
#[derive(Clone, Debug)]
pub struct BeltGeom {
    /// Component id.
    pub id: String,
    /// Display name.
    pub name: String,
    /// The entry end of its centre line, world.
    pub origin: [f32; 2],
    /// Its drawn length, world.
    pub drawn: f32,
    /// World units per unit of length.
    pub scale: f32,
    /// -1, 0 or 1.
    pub direction: i8,
    /// The items: number, class, rear and length in the unit.
    pub items: Vec<vigie_core::machine::scene::SceneItem>,
    /// Its exit: `stop`, `drop`, `sink` or the next conveyor.
    pub exit: String,
    /// The top of its highest beam lamp, world.
    pub top: f32,
}

/// Places a belt's beams' lamps above it, the belt's entry at `at`. Beams close together
/// (a test place's height, colour and metal sensors): their lamps stacked, each on the
/// lowest level no close lamp takes. Returns the top of the highest lamp.
fn place_beams(
    beams: &[vigie_core::machine::scene::SceneSensor],
    [x, y]: [f32; 2],
    scale: f32,
    sensors: &mut Vec<SensorGeom>,
) -> f32 {
    let mut taken: Vec<(f32, usize)> = Vec::new();
    let mut top = y;
    for b in beams {
        #[allow(clippy::cast_possible_truncation)]
        let bx = x + b.from as f32 * scale;
        let level = (0..)
            .find(|l| {
                !taken
                    .iter()
                    .any(|(tx, tl)| tl == l && (tx - bx).abs() < BEAM_ROOM)
            })
            .unwrap_or(0);
        taken.push((bx, level));
        #[allow(clippy::cast_precision_loss)]
        let up = 420.0 + 260.0 * level as f32;
        sensors.push(SensorGeom {
            id: b.signal.clone(),
            lamp: [bx, y + up],
            beam: Some(([bx, y + up - 100.0], [bx, y - BELT_HALF])),
            high: false,
        });
        top = top.max(y + up + 300.0);
    }
    top
}

/// A turntable's rotation as an axis over its positions, with its angle windows and
/// the outputs that turn it; a tank as a vessel over its capacity, with its level
/// windows and its flows.
fn drawn_axis(
    e: &SceneElement,
    x: f32,
    plant: &Plant,
    sensors: &mut Vec<SensorGeom>,
    actuators: &mut BTreeMap<String, [f32; 2]>,
) -> AxisGeom {
    let (unit, angle, positions, windows, turns) = match &e.shape {
        Shape::Turntable {
            unit,
            angle,
            positions,
            sensors,
            turns,
            ..
        } => (
            unit.clone(),
            *angle,
            positions.as_slice(),
            sensors.as_slice(),
            turns.as_slice(),
        ),
        _ => (String::new(), 0.0, &[][..], &[][..], &[][..]),
    };
    let lo = positions.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = positions.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let a = AxisGeom {
        id: e.id.clone(),
        name: e.name.clone(),
        top: [x, 0.0],
        range: if hi > lo { (lo, hi) } else { (0.0, 1.0) },
        position: angle,
        direction: 0,
        unit,
        vessel: false,
        switch: false,
    };
    place_signals(&a, windows, turns, plant, sensors, actuators);
    a
}

/// A belt of the rows: a conveyor, or a turntable's rollers (after the conveyor
/// whose exit leads to it).
type BeltOf<'a> = (
    &'a SceneElement,
    f64,
    i8,
    &'a Vec<SceneItem>,
    &'a Vec<SceneSensor>,
    &'a Vec<SceneDrive>,
    &'a String,
    (&'a Option<String>, &'a Option<String>),
);

fn belt_of(e: &SceneElement) -> Option<BeltOf<'_>> {
    match &e.shape {
        Shape::Conveyor {
            length,
            direction,
            items,
            sensors,
            drives,
            exit,
            motion,
            feed,
            ..
        } => Some((
            e,
            *length,
            *direction,
            items,
            sensors,
            drives,
            exit,
            (motion, feed),
        )),
        // A turntable's rollers, after the conveyor whose exit leads to it.
        Shape::Turntable {
            length,
            direction,
            items,
            beams,
            rollers,
            ..
        } => Some((
            e,
            *length,
            *direction,
            items,
            beams,
            rollers,
            &NO_EXIT,
            (&NOTHING, &NOTHING),
        )),
        _ => None,
    }
}

/// A turntable's rollers lead nowhere fixed.
static NO_EXIT: String = String::new();
/// No motion sensor, no feeder.
static NOTHING: Option<String> = None;

/// Places the conveyors (and the turntables' rollers) in rows above the axes, each
/// chain of conveyors (one's exit the next one's entry) end to end on its row, at one
/// scale for all; their beams' lamps above them and their drives' outputs below their
/// entry.
fn place_belts(
    scene: &Scene,
    plant: &Plant,
    sensors: &mut Vec<SensorGeom>,
    actuators: &mut BTreeMap<String, [f32; 2]>,
) -> Vec<BeltGeom> {
    let belts: Vec<_> = scene.elements.iter().filter_map(belt_of).collect();
    let longest = belts.iter().map(|b| b.1).fold(0.0f64, f64::max);
    if longest <= 0.0 {
        return Vec::new();
    }
    #[allow(clippy::cast_possible_truncation)]
    let scale = BELT / longest as f32;
    let links: Vec<(&str, &str)> = belts
        .iter()
        .map(|b| (b.0.id.as_str(), b.6.as_str()))
        .collect();
    let order = chains(&links);
    let mut out = Vec::new();
    for (row, chain) in order.iter().enumerate() {
        #[allow(clippy::cast_precision_loss)]
        let y = 1300.0 + BELT_ROW * (order.len() - 1 - row) as f32;
        let mut x = 0.0;
        for &i in chain {
            let (e, length, direction, items, beams, drives, exit, (motion, feed)) = &belts[i];
            #[allow(clippy::cast_possible_truncation)]
            let drawn = *length as f32 * scale;
            let top = place_beams(beams, [x, y], scale, sensors);
            let mut col = 0.0;
            for d in drives.iter() {
                for o in output_names(&d.when, plant) {
                    actuators.entry(o).or_insert_with(|| {
                        col += 1.0;
                        [x + 250.0 + 900.0 * (col - 1.0), y - 480.0]
                    });
                }
            }
            // The feeder's outputs left of the entry (a pusher), the motion sensor
            // under the exit end.
            if let Some(f) = feed {
                for (k, o) in output_names(f, plant).into_iter().enumerate() {
                    #[allow(clippy::cast_precision_loss)]
                    let at = [x - 450.0, y + 420.0 * k as f32];
                    actuators.entry(o).or_insert(at);
                }
            }
            if let Some(m) = motion {
                sensors.push(SensorGeom {
                    id: m.clone(),
                    lamp: [x + drawn - 350.0, y - 480.0],
                    beam: None,
                    high: false,
                });
            }
            out.push(BeltGeom {
                id: e.id.clone(),
                name: e.name.clone(),
                origin: [x, y],
                drawn,
                scale,
                direction: *direction,
                items: (*items).clone(),
                exit: (*exit).clone(),
                top,
            });
            x += drawn + 250.0;
        }
    }
    out
}

/// The rows of conveyors, by index in `links` (id, exit): each chain from a conveyor
/// no other one leads to, along the exits; a conveyor left (a loop) on a row of its
/// own.
fn chains(links: &[(&str, &str)]) -> Vec<Vec<usize>> {
    let mut placed = vec![false; links.len()];
    let mut rows = Vec::new();
    for start in 0..links.len() {
        if links.iter().any(|(_, exit)| *exit == links[start].0) {
            continue;
        }
        let mut chain = Vec::new();
        let mut k = Some(start);
        while let Some(i) = k.filter(|&i| !placed[i]) {
            placed[i] = true;
            chain.push(i);
            k = links.iter().position(|(id, _)| *id == links[i].1);
        }
        rows.push(chain);
    }
    for (i, p) in placed.iter().enumerate() {
        if !p {
            rows.push(vec![i]);
        }
    }
    rows
}

/// Paints every conveyor: its belt, the way it moves, its items (number and class) and
/// what its exit end leads to.
pub(super) fn paint_belts(cv: &Canvas<'_>, geom: &Geometry, view: &View, t_s: f32) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    let edge = Stroke::new(1.0, pal.equipment_edge);
    for b in &geom.belts {
        let [x, y] = b.origin;
        let body = Rect::from_two_pos(xf.p([x, y + BELT_HALF]), xf.p([x + b.drawn, y - BELT_HALF]));
        painter.rect(
            body,
            2.0,
            pal.equipment.gamma_multiply(0.9),
            edge,
            egui::StrokeKind::Middle,
        );
        if b.direction != 0 {
            let (from, to) = if b.direction > 0 {
                ([x, y], [x + b.drawn, y])
            } else {
                ([x + b.drawn, y], [x, y])
            };
            super::chevrons(
                painter,
                xf,
                from,
                to,
                2.0 * BELT_HALF,
                t_s * 300.0,
                pal.running,
            );
        }
        // The exit end: a wall for an end stop, an arrow into a sink, an open end.
        let end = xf.p([x + b.drawn, y]);
        let h = BELT_HALF * xf.scale;
        match b.exit.as_str() {
            "stop" => {
                painter.line_segment(
                    [end + vec2(0.0, -h * 1.4), end + vec2(0.0, h * 1.4)],
                    Stroke::new(3.0, pal.equipment_edge),
                );
            }
            "sink" => {
                painter.text(
                    end + vec2(6.0, 0.0),
                    Align2::LEFT_CENTER,
                    "⇲",
                    FontId::proportional(16.0),
                    pal.text,
                );
            }
            _ => {}
        }
        for it in &b.items {
            #[allow(clippy::cast_possible_truncation)]
            let (rear, len) = (it.rear as f32 * b.scale, it.length as f32 * b.scale);
            let r = Rect::from_two_pos(
                xf.p([x + rear, y + BELT_HALF * 1.25]),
                xf.p([x + rear + len, y - BELT_HALF * 1.25]),
            );
            painter.rect(
                r,
                2.0,
                pal.box_small,
                Stroke::new(1.0, pal.box_edge),
                egui::StrokeKind::Middle,
            );
            // Its number, and its class when the item is wide enough on screen.
            let class = view.items.get(&it.class).unwrap_or(&it.class);
            let label = if r.width() > 9.0 * (class.chars().count() as f32 + 3.0) {
                format!("{} {class}", it.id)
            } else {
                it.id.to_string()
            };
            painter.text(
                r.center(),
                Align2::CENTER_CENTER,
                label,
                FontId::proportional(10.0),
                pal.text,
            );
        }
        super::component_name(
            cv,
            // Under the row of its drives' outputs (which start under its entry).
            xf.p([x + b.drawn / 2.0, y - 800.0]),
            view.parts.get(&b.id).unwrap_or(&b.name),
        );
    }
}

/// Places an axis's or a tank's sensor lamps left of it at their windows, and the
/// outputs of its drives or flows right of it.
fn place_signals(
    a: &AxisGeom,
    windows: &[vigie_core::machine::scene::SceneSensor],
    drives: &[vigie_core::machine::scene::SceneDrive],
    plant: &Plant,
    sensors: &mut Vec<SensorGeom>,
    actuators: &mut BTreeMap<String, [f32; 2]>,
) {
    let x = a.top[0];
    let half = if a.vessel { VESSEL_HALF } else { 90.0 };
    for w in windows {
        let mid = a.at((w.from + w.to) / 2.0);
        sensors.push(SensorGeom {
            id: w.signal.clone(),
            lamp: [x - half - 610.0, mid[1]],
            beam: Some(([x - half - 510.0, mid[1]], [x - half, mid[1]])),
            high: false,
        });
    }
    if a.vessel {
        place_lines(a, drives, plant, sensors, actuators);
        return;
    }
    let mut row = 0.0;
    for d in drives {
        for out in output_names(&d.when, plant) {
            actuators.entry(out).or_insert_with(|| {
                row += 1.0;
                [x + half + 810.0, -GUIDE * 0.15 - 380.0 * (row - 1.0)]
            });
        }
    }
}

/// A vessel's flows as lines right of it: the inflows enter near its top, the outflows
/// leave near its bottom. Each line is drawn as its flow sensor's beam (lit while the
/// flow runs), the outputs that open it above the line, the sensor's lamp at its end.
fn place_lines(
    a: &AxisGeom,
    flows: &[vigie_core::machine::scene::SceneDrive],
    plant: &Plant,
    sensors: &mut Vec<SensorGeom>,
    actuators: &mut BTreeMap<String, [f32; 2]>,
) {
    let wall = a.top[0] + VESSEL_HALF;
    let (mut ins, mut outs) = (0.0, 0.0);
    for f in flows {
        let y = if f.speed >= 0.0 {
            ins += 1.0;
            a.top[1] - 250.0 - 700.0 * (ins - 1.0)
        } else {
            outs += 1.0;
            a.top[1] - GUIDE + 250.0 + 700.0 * (outs - 1.0)
        };
        let mut col = 0.0;
        for out in output_names(&f.when, plant) {
            actuators.entry(out).or_insert_with(|| {
                col += 1.0;
                [wall + 150.0 + 480.0 * col, y + 260.0]
            });
        }
        let end = wall + 150.0 + 480.0 * col.max(2.0) + 450.0;
        if let Some(id) = &f.sensor {
            sensors.push(SensorGeom {
                id: id.clone(),
                lamp: [end, y],
                beam: Some(([wall, y], [end - 100.0, y])),
                high: false,
            });
        }
    }
}

/// The signals a component names: its sensors, the outputs of its drives and feeder,
/// its motion sensor, its button, a device's signals.
fn component_signals(e: &SceneElement, plant: &Plant) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut exprs: Vec<&str> = Vec::new();
    match &e.shape {
        Shape::Axis {
            sensors,
            drives,
            motion,
            ..
        } => {
            out.extend(sensors.iter().map(|s| s.signal.clone()));
            out.extend(motion.iter().cloned());
            exprs.extend(drives.iter().map(|d| d.when.as_str()));
        }
        Shape::Tank { sensors, flows, .. } => {
            out.extend(sensors.iter().map(|s| s.signal.clone()));
            out.extend(flows.iter().filter_map(|d| d.sensor.clone()));
            exprs.extend(flows.iter().map(|d| d.when.as_str()));
        }
        Shape::Conveyor {
            sensors,
            drives,
            motion,
            feed,
            ..
        } => {
            out.extend(sensors.iter().map(|s| s.signal.clone()));
            out.extend(motion.iter().cloned());
            exprs.extend(drives.iter().map(|d| d.when.as_str()));
            exprs.extend(feed.iter().map(String::as_str));
        }
        Shape::Turntable {
            sensors,
            turns,
            beams,
            rollers,
            ..
        } => {
            out.extend(sensors.iter().chain(beams).map(|s| s.signal.clone()));
            exprs.extend(turns.iter().chain(rollers).map(|d| d.when.as_str()));
        }
        Shape::Device { signals } => out.extend(signals.iter().cloned()),
        Shape::Button { signal, .. } => out.push(signal.clone()),
    }
    for x in exprs {
        out.extend(output_names(x, plant));
    }
    out
}

/// Fewer components than this: the whole plant is readable at once, drawn as one.
const MANY: usize = 8;

/// The areas the console offers, when the plant has 8 components or more in two
/// areas or more; `None`: the plant is drawn as one.
pub fn shown_areas(scene: &Scene, plant: &Plant) -> Option<Vec<(String, Vec<String>)>> {
    let areas = areas(scene, plant);
    (areas.len() >= 2 && scene.elements.len() >= MANY).then_some(areas)
}

/// Room between two areas' blocks in the overview, world units.
const AREA_GAP: f32 = 1600.0;

impl Geometry {
    /// Moves everything by `d`.
    fn translate(&mut self, d: [f32; 2]) {
        let mv = |p: &mut [f32; 2]| {
            p[0] += d[0];
            p[1] += d[1];
        };
        for s in &mut self.sensors {
            mv(&mut s.lamp);
            if let Some((a, b)) = &mut s.beam {
                mv(a);
                mv(b);
            }
        }
        self.actuators.values_mut().for_each(mv);
        for a in &mut self.axes {
            mv(&mut a.top);
        }
        for b in &mut self.belts {
            mv(&mut b.origin);
        }
        for (_, p) in &mut self.schematic {
            mv(p);
        }
        mv(&mut self.bounds.0);
        mv(&mut self.bounds.1);
    }

    /// The whole plant of many components (ISA-101's area overview): each area drawn
    /// as its own view draws it, the blocks in rows, each titled with its area; the
    /// signals of no area in a last block.
    pub fn overview(scene: &Scene, plant: &Plant, areas: &[(String, Vec<String>)]) -> Self {
        let mut blocks: Vec<(String, Self)> = areas
            .iter()
            .map(|(area, ids)| {
                let (s, p) = area_view(scene, plant, area, ids);
                (area.clone(), Self::from_scene(&s, &p))
            })
            .collect();
        let placed: std::collections::BTreeSet<&str> = blocks
            .iter()
            .flat_map(|(_, g)| {
                g.sensors
                    .iter()
                    .map(|s| s.id.as_str())
                    .chain(g.actuators.keys().map(String::as_str))
            })
            .collect();
        let rest = Plant {
            name: plant.name.clone(),
            description: plant.description.clone(),
            inputs: plant
                .inputs
                .iter()
                .filter(|s| !placed.contains(s.id.as_str()))
                .cloned()
                .collect(),
            outputs: plant
                .outputs
                .iter()
                .filter(|s| !placed.contains(s.id.as_str()))
                .cloned()
                .collect(),
        };
        if !(rest.inputs.is_empty() && rest.outputs.is_empty()) {
            blocks.push((String::new(), Self::from_scene(&Scene::default(), &rest)));
        }
        // Rows of about the square root of the blocks' count, in the plant's order.
        #[allow(
            clippy::cast_precision_loss,
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss
        )]
        let per_row = ((blocks.len() as f32).sqrt().ceil() as usize).max(1);
        let mut out: Option<Self> = None;
        let (mut x, mut top, mut row_h) = (0.0f32, 0.0f32, 0.0f32);
        for (k, (area, mut g)) in blocks.into_iter().enumerate() {
            if k > 0 && k % per_row == 0 {
                x = 0.0;
                top -= row_h + AREA_GAP;
                row_h = 0.0;
            }
            let (min, max) = g.bounds;
            g.translate([x - min[0], top - max[1]]);
            // Room for the block's title above it; the signals of no area are framed
            // under their own label.
            g.bounds.1[1] += 1200.0;
            let (lo, hi) = g.bounds;
            if area.is_empty() {
                g.schematic.retain(|(e, _)| !e.is_empty());
            }
            g.frames.push((area, lo, hi));
            x += max[0] - min[0] + AREA_GAP;
            row_h = row_h.max(g.bounds.1[1] - g.bounds.0[1]);
            out = Some(match out {
                None => g,
                Some(mut acc) => {
                    acc.sensors.extend(g.sensors);
                    acc.actuators.extend(g.actuators);
                    acc.axes.extend(g.axes);
                    acc.belts.extend(g.belts);
                    acc.schematic.extend(g.schematic);
                    acc.frames.extend(g.frames);
                    for i in 0..2 {
                        acc.bounds.0[i] = acc.bounds.0[i].min(g.bounds.0[i]);
                        acc.bounds.1[i] = acc.bounds.1[i].max(g.bounds.1[i]);
                    }
                    acc
                }
            });
        }
        out.unwrap_or_else(|| Self::from_scene(scene, plant))
    }
}

/// The areas of a plant of components, the units of ISA-101's display hierarchy: a
/// component belongs to the element (`plant.ron`) most of its signals belong to (the
/// first of them on a tie); the areas in the order of their first component, each with
/// its components' ids. A component naming no signal of the plant is in no area.
pub fn areas(scene: &Scene, plant: &Plant) -> Vec<(String, Vec<String>)> {
    let element: BTreeMap<&str, &str> = plant
        .inputs
        .iter()
        .chain(&plant.outputs)
        .map(|s| (s.id.as_str(), s.element.as_str()))
        .collect();
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for e in &scene.elements {
        let mut votes: Vec<(&str, usize)> = Vec::new();
        for s in component_signals(e, plant) {
            if let Some(el) = element.get(s.as_str()) {
                match votes.iter_mut().find(|v| v.0 == *el) {
                    Some(v) => v.1 += 1,
                    None => votes.push((el, 1)),
                }
            }
        }
        // The first of the most voted: `max_by_key` keeps the last maximum.
        let Some(best) = votes.iter().rev().max_by_key(|v| v.1).map(|v| v.0) else {
            continue;
        };
        match out.iter_mut().find(|a| a.0 == best) {
            Some(a) => a.1.push(e.id.clone()),
            None => out.push((best.to_string(), vec![e.id.clone()])),
        }
    }
    out
}

/// The part of `scene` and `plant` an area shows: its components, and the plant's
/// signals of that element (the schematic strip of the area).
pub fn area_view(scene: &Scene, plant: &Plant, area: &str, ids: &[String]) -> (Scene, Plant) {
    let scene = Scene {
        elements: scene
            .elements
            .iter()
            .filter(|e| ids.contains(&e.id))
            .cloned()
            .collect(),
    };
    let placed: std::collections::BTreeSet<String> = scene
        .elements
        .iter()
        .flat_map(|e| component_signals(e, plant))
        .collect();
    let keep = |s: &vigie_core::plant::Signal| s.element == area || placed.contains(&s.id);
    let plant = Plant {
        name: plant.name.clone(),
        description: plant.description.clone(),
        inputs: plant.inputs.iter().filter(|s| keep(s)).cloned().collect(),
        outputs: plant.outputs.iter().filter(|s| keep(s)).cloned().collect(),
    };
    (scene, plant)
}

/// The plant outputs an expression names, in order.
fn output_names(expr: &str, plant: &Plant) -> Vec<String> {
    let mut out = Vec::new();
    for s in &plant.outputs {
        let named = expr
            .split(|c: char| !(c.is_alphanumeric() || c == '_'))
            .any(|w| w == s.id);
        if named {
            out.push(s.id.clone());
        }
    }
    out
}

/// The carriage of an axis at `position`, on screen.
fn carriage(xf: &Xf, a: &AxisGeom, position: f64) -> Rect {
    let c = xf.p(a.at(position));
    Rect::from_center_size(c, vec2(360.0, 160.0) * xf.scale)
}

/// Paints every axis: its guide, its name, its carriage (and the projected one, at
/// level 1) and the way it moves.
pub(super) fn paint_axes(cv: &Canvas<'_>, geom: &Geometry, view: &View, ghost: Option<&Scene>) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    let edge = Stroke::new(1.0, pal.equipment_edge);
    for a in &geom.axes {
        if a.vessel {
            paint_vessel(cv, view, a, ghost);
            continue;
        }
        if a.switch {
            paint_switch(cv, view, a, ghost);
            continue;
        }
        let guide = Rect::from_two_pos(
            xf.p([a.top[0] - 60.0, a.top[1]]),
            xf.p([a.top[0] + 60.0, a.top[1] - GUIDE]),
        );
        painter.rect(
            guide,
            2.0,
            pal.equipment.gamma_multiply(0.9),
            edge,
            egui::StrokeKind::Middle,
        );
        // The name under the guide: the level banner takes the synoptic's top.
        axis_name(cv, view, a);
        let r = carriage(xf, a, a.position);
        painter.rect(
            r,
            3.0,
            pal.equipment,
            Stroke::new(1.5, pal.equipment_edge),
            egui::StrokeKind::Middle,
        );
        if !cv.compact {
            paint_position(cv, r, &format!("{:.1} {}", a.position, a.unit));
        }
        if a.direction != 0 {
            let d = f32::from(a.direction);
            let (x, mut y) = if a.direction > 0 {
                (r.center().x, r.bottom() + 10.0)
            } else {
                (r.center().x, r.top() - 10.0)
            };
            // Driven against the end of its guide: the arrow on the carriage's other
            // side, pointing into it, not over the component's name under the guide.
            if !guide
                .expand2(vec2(0.0, 2.0))
                .contains(Pos2::new(x, y + d * 10.0))
            {
                y = if a.direction > 0 {
                    r.top() - 12.0
                } else {
                    r.bottom() + 12.0
                };
            }
            painter.add(EShape::convex_polygon(
                vec![
                    Pos2::new(x - 8.0, y),
                    Pos2::new(x + 8.0, y),
                    Pos2::new(x, y + d * 10.0),
                ],
                pal.running,
                Stroke::NONE,
            ));
        }
        if let Some(p) = ghost.and_then(|s| projected(s, &a.id)) {
            let g = carriage(xf, a, p);
            painter.rect(
                g,
                3.0,
                pal.ghost.gamma_multiply(0.15),
                Stroke::new(2.0, pal.ghost),
                egui::StrokeKind::Middle,
            );
        }
    }
}

/// An axis's, a switch's or a tank's name under its guide, in the language shown.
fn axis_name(cv: &Canvas<'_>, view: &View, a: &AxisGeom) {
    super::component_name(
        cv,
        cv.xf.p([a.top[0], a.top[1] - GUIDE - 120.0]),
        view.parts.get(&a.id).unwrap_or(&a.name),
    );
}

/// An axis's position: in its carriage when it fits there, else beside it, right of
/// the guide (the robot's narrow carriage), where no name is.
fn paint_position(cv: &Canvas<'_>, carriage: Rect, text: &str) {
    let font = FontId::monospace(10.0);
    let width = cv
        .painter
        .layout_no_wrap(text.to_string(), font.clone(), cv.pal.text)
        .size()
        .x;
    if width + 4.0 <= carriage.width() {
        cv.painter.text(
            carriage.center(),
            Align2::CENTER_CENTER,
            text,
            font,
            cv.pal.text,
        );
        return;
    }
    // Beside it, right then left, then under or over it on the guide, where no name,
    // no symbol and no lamp's line is (the drill head's outputs sit right of its
    // guide, its windows' lines left); else over it.
    let galley = cv
        .painter
        .layout_no_wrap(text.to_string(), font, cv.pal.text);
    let size = galley.size();
    // A clear gap: a readout against a badge reads as one word (`98.3 mm MGV`).
    let free = |r: &Rect| {
        let r = r.expand(4.0);
        cv.claimed.borrow().iter().all(|c| !c.intersects(r))
            && cv.symbols.borrow().iter().all(|s| !s.intersects(r))
    };
    let beside = [
        Align2::LEFT_CENTER.anchor_size(carriage.right_center() + vec2(4.0, 0.0), size),
        Align2::RIGHT_CENTER.anchor_size(carriage.left_center() - vec2(4.0, 0.0), size),
        Align2::CENTER_TOP.anchor_size(carriage.center_bottom() + vec2(0.0, 3.0), size),
        Align2::CENTER_BOTTOM.anchor_size(carriage.center_top() - vec2(0.0, 3.0), size),
    ];
    let at = beside
        .into_iter()
        .find(free)
        .unwrap_or_else(|| Rect::from_center_size(carriage.center(), size));
    // Over the guide (below or above the carriage): a plate of the floor's colour.
    cv.painter.rect_filled(at.expand(1.0), 2.0, cv.pal.floor);
    cv.claimed.borrow_mut().push(at);
    cv.painter.galley(at.min, galley, cv.pal.text);
}

/// A switching device (a breaker, a recloser): its line through the one-line diagram's
/// square, filled when closed (at the end of its travel), hollow when open, dashed on
/// the way, its state beside it; at level 1 the projected state's square is ringed.
fn paint_switch(cv: &Canvas<'_>, view: &View, a: &AxisGeom, ghost: Option<&Scene>) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    let x = a.top[0];
    let (top, bottom) = (xf.p([x, a.top[1]]), xf.p([x, a.top[1] - GUIDE]));
    let line = Stroke::new(2.0, pal.equipment_edge);
    let side = (240.0 * xf.scale).clamp(14.0, 36.0);
    let r = Rect::from_center_size(
        Pos2::new(top.x, (top.y + bottom.y) / 2.0),
        Vec2::splat(side),
    );
    painter.line_segment([top, r.center_top()], line);
    painter.line_segment([r.center_bottom(), bottom], line);
    let state = |p: f64| {
        let span = (a.range.1 - a.range.0).max(1e-9);
        let k = (p - a.range.0) / span;
        if k >= 1.0 - 1e-9 {
            "switch-closed"
        } else if k <= 1e-9 {
            "switch-open"
        } else {
            "switch-moving"
        }
    };
    let now = state(a.position);
    match now {
        "switch-closed" => painter.rect(r, 2.0, pal.equipment_edge, line, egui::StrokeKind::Middle),
        "switch-open" => painter.rect(r, 2.0, pal.floor, line, egui::StrokeKind::Middle),
        _ => {
            let c = [
                r.left_top(),
                r.right_top(),
                r.right_bottom(),
                r.left_bottom(),
                r.left_top(),
            ];
            painter.add(EShape::dashed_line(&c, line, 4.0, 3.0))
        }
    };
    if let Some(p) = ghost.and_then(|s| projected(s, &a.id))
        && state(p) != now
    {
        painter.rect_stroke(
            r.expand(5.0),
            3.0,
            Stroke::new(2.0, pal.ghost),
            egui::StrokeKind::Middle,
        );
    }
    if !cv.compact {
        cv.label(
            r.right_center() + vec2(8.0, 0.0),
            Align2::LEFT_CENTER,
            view.word(now),
            FontId::proportional(12.0),
            pal.text,
        );
    }
    axis_name(cv, view, a);
}

/// A tank: the vessel, its liquid up to the level, the level in its unit, and the
/// projected level at level 1 as a dashed line.
fn paint_vessel(cv: &Canvas<'_>, view: &View, a: &AxisGeom, ghost: Option<&Scene>) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    let x = a.top[0];
    let vessel = Rect::from_two_pos(
        xf.p([x - VESSEL_HALF, a.top[1]]),
        xf.p([x + VESSEL_HALF, a.top[1] - GUIDE]),
    );
    painter.rect(
        vessel,
        4.0,
        pal.equipment.gamma_multiply(0.9),
        Stroke::new(1.5, pal.equipment_edge),
        egui::StrokeKind::Middle,
    );
    let surface = xf.p(a.at(a.position)).y;
    let liquid = Rect::from_min_max(Pos2::new(vessel.left(), surface), vessel.right_bottom());
    painter.rect_filled(liquid, 3.0, pal.running.gamma_multiply(0.45));
    if !cv.compact {
        painter.text(
            Pos2::new(vessel.center().x, (surface - 4.0).max(vessel.top() + 12.0)),
            Align2::CENTER_BOTTOM,
            format!("{:.1} {}", a.position, a.unit),
            FontId::monospace(11.0),
            pal.text,
        );
    }
    axis_name(cv, view, a);
    if let Some(p) = ghost.and_then(|s| projected(s, &a.id)) {
        let y = xf.p(a.at(p)).y;
        painter.add(EShape::dashed_line(
            &[Pos2::new(vessel.left(), y), Pos2::new(vessel.right(), y)],
            Stroke::new(2.0, pal.ghost),
            6.0,
            4.0,
        ));
    }
}

/// The position of component `id` in a projected scene.
fn projected(scene: &Scene, id: &str) -> Option<f64> {
    scene
        .elements
        .iter()
        .find(|e| e.id == id)
        .and_then(|e| match &e.shape {
            Shape::Axis { position, .. } => Some(*position),
            Shape::Tank { level, .. } => Some(*level),
            Shape::Turntable { angle, .. } => Some(*angle),
            Shape::Button { .. } | Shape::Conveyor { .. } | Shape::Device { .. } => None,
        })
}

/// Where to mark a predicted hazard of a component, and its label.
pub(super) fn hazard_label(
    geom: &Geometry,
    view: &View,
    h: &Hazard,
    xf: &Xf,
    ghost: Option<&Scene>,
) -> Option<(Pos2, String)> {
    let part = match &h.at {
        Place::Component { part } | Place::Danger { part, .. } => part,
        _ => return None,
    };
    let a = geom.axes.iter().find(|a| &a.id == part)?;
    // At the projected carriage, where the hazard happens.
    let at = ghost.and_then(|s| projected(s, part)).unwrap_or(a.position);
    let p = carriage(xf, a, at).center();
    let kind = view.word(&format!("hazard-{:?}", h.kind).to_lowercase());
    let kind = match &h.at {
        Place::Danger { danger, .. } => {
            format!("{kind}: {}", view.dangers.get(danger).unwrap_or(&h.place))
        }
        _ => kind.to_string(),
    };
    Some((p, view.word("predicted-component").replace("%kind%", &kind)))
}

#[cfg(test)]
mod tests {
    use super::chains;
    use crate::console::synoptic::Geometry;
    use vigie_core::bundle::PlantBundle;
    use vigie_core::machine::{ComponentPlant, Description};

    /// The substation's breakers say `symbol: Switch`: the synoptic draws them as
    /// switching devices, its other axes (none) and every other plant's as carriages.
    #[test]
    fn a_breaker_is_drawn_as_a_switch_and_an_axis_as_a_carriage() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts");
        for (plant, switches) in [("substation", 2), ("drilling-station", 0), ("workshop", 0)] {
            let dir = root.join(plant);
            let (bundle, _) = PlantBundle::load(&dir).unwrap();
            let Ok(Description::Components(desc)) = Description::load(&dir) else {
                panic!("{plant}: no components");
            };
            let emu = ComponentPlant::new(&desc, &bundle.plant, 1).unwrap();
            let g = Geometry::from_scene(&emu.scene(), &bundle.plant);
            assert!(!g.axes.is_empty(), "{plant}");
            assert_eq!(
                g.axes.iter().filter(|a| a.switch).count(),
                switches,
                "{plant}"
            );
        }
    }

    #[test]
    fn conveyors_are_drawn_along_their_chains_and_a_loop_gets_its_own_row() {
        // b1 leads to b2, b2 to an end stop; c leads to itself (a loop).
        let links = [("b2", "stop"), ("b1", "b2"), ("c", "c"), ("d", "sink")];
        assert_eq!(chains(&links), vec![vec![1, 0], vec![3], vec![2]]);
    }
}
