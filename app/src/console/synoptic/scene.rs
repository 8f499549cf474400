//! The synoptic of a plant described as components: its geometry comes from the
//! emulator's [`Scene`], one painter per shape, no drawing code per plant.
//!
//! An axis is drawn as a vertical guide, its travel's start at the top (a drill head
//! descends, a lift rises to its top), the carriage where it stands, each position
//! sensor's lamp left of the guide at its window, and the outputs of its drives right
//! of it. The signals no component places go to the schematic strip below.

use super::{Canvas, Geometry, SensorGeom, View, Xf, place_schematic};
use egui::{Align2, FontId, Pos2, Rect, Shape as EShape, Stroke, vec2};
use std::collections::BTreeMap;
use vigie_core::emulator::{Hazard, Place};
use vigie_core::machine::{Scene, Shape};
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
        // Each component's place from the previous one's: a vessel's lines need more
        // room right of it than an axis's outputs.
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
                    unit,
                    min,
                    max,
                    position,
                    direction,
                    sensors: windows,
                    drives,
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
                    };
                    place_signals(&a, windows, drives, plant, &mut sensors, &mut actuators);
                    axes.push(a);
                }
                Shape::Tank {
                    unit,
                    capacity,
                    level,
                    sensors: windows,
                    flows,
                    ..
                } => {
                    let a = AxisGeom {
                        id: e.id.clone(),
                        name: e.name.clone(),
                        top: [x, 0.0],
                        range: (0.0, *capacity),
                        position: *level,
                        direction: 0,
                        unit: unit.clone(),
                        vessel: true,
                    };
                    place_signals(&a, windows, flows, plant, &mut sensors, &mut actuators);
                    axes.push(a);
                }
                // A panel button's input goes to the schematic strip, under its
                // element (`plant.ron`), with the other panel signals.
                Shape::Button { .. } => {}
            }
        }
        let right = if axes.last().is_some_and(|a| a.vessel) {
            VESSEL_PITCH - 900.0
        } else {
            1400.0
        };
        let mut min = [-1100.0, -GUIDE - 500.0];
        let mut max = [x.max(PITCH) + right, 600.0];
        let schematic = place_schematic(plant, &mut sensors, &mut actuators, (&mut min, &mut max));
        Self {
            conveyors: Vec::new(),
            table_center: [0.0, 0.0],
            table_size: [0.0, 0.0],
            sensors,
            actuators,
            elevators: Vec::new(),
            bounds: (min, max),
            table_actuators: Default::default(),
            has_table: false,
            axes,
            schematic,
        }
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
        painter.text(
            xf.p([a.top[0], a.top[1] - GUIDE - 120.0]),
            Align2::CENTER_TOP,
            view.parts.get(&a.id).unwrap_or(&a.name),
            FontId::proportional(13.0),
            pal.text,
        );
        let r = carriage(xf, a, a.position);
        painter.rect(
            r,
            3.0,
            pal.equipment,
            Stroke::new(1.5, pal.equipment_edge),
            egui::StrokeKind::Middle,
        );
        painter.text(
            r.center(),
            Align2::CENTER_CENTER,
            format!("{:.1} {}", a.position, a.unit),
            FontId::monospace(10.0),
            pal.text,
        );
        if a.direction != 0 {
            let y = if a.direction > 0 {
                r.bottom() + 10.0
            } else {
                r.top() - 10.0
            };
            let tip = Pos2::new(r.center().x, y + f32::from(a.direction) * 10.0);
            painter.add(EShape::convex_polygon(
                vec![
                    Pos2::new(r.center().x - 8.0, y),
                    Pos2::new(r.center().x + 8.0, y),
                    tip,
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
    painter.text(
        Pos2::new(vessel.center().x, (surface - 4.0).max(vessel.top() + 12.0)),
        Align2::CENTER_BOTTOM,
        format!("{:.1} {}", a.position, a.unit),
        FontId::monospace(11.0),
        pal.text,
    );
    painter.text(
        xf.p([x, a.top[1] - GUIDE - 120.0]),
        Align2::CENTER_TOP,
        view.parts.get(&a.id).unwrap_or(&a.name),
        FontId::proportional(13.0),
        pal.text,
    );
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
            Shape::Button { .. } => None,
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
