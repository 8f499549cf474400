//! The synoptic: a top view of the plant drawn from the layout (seed 004, figures 13-17).
//!
//! [`Geometry::new`] is the pure layout (world positions of every drawn element);
//! [`synoptic_ui`] paints a [`Picture`] over it with the palette, handles zoom (wheel)
//! and pan (drag) and shows a tooltip for the sensor or actuator under the pointer.

use crate::theme::Palette;
use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Shape, Stroke, Vec2, pos2, vec2};
use std::collections::{BTreeMap, BTreeSet};
use vigie_core::emulator::{Beam, BoxSize, BoxState, BoxView, Hazard, Layout, SensorKind};
use vigie_core::explain::{Highlight, Mark};
use vigie_core::plant::Plant;

/// Zoom and pan of the synoptic (view state, kept across frames).
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// Zoom factor over "fit to the panel".
    pub zoom: f32,
    /// Pan, in points.
    pub pan: Vec2,
    /// The area shown (an element of `plant.ron`, see [`scene::areas`]), or the whole
    /// plant.
    pub area: Option<String>,
    /// The plant's areas with their components' ids, when it is shown area by area
    /// ([`scene::shown_areas`]); they depend on the plant only, so they are found once.
    pub areas: Option<Vec<(String, Vec<String>)>>,
    /// The signals' descriptions in the language shown (from the plant folder's
    /// `i18n/<lang>.ftl`, `signal-<id>`); a signal without one shows the plant's own.
    pub descriptions: std::collections::BTreeMap<String, String>,
    /// The synoptic's tags in the language shown, by key ([`TAGS`]).
    pub words: std::collections::BTreeMap<&'static str, String>,
    /// The plant's element names in the language shown (`element-<name>`), for the
    /// schematic strip's labels; an element without one shows the plant's own.
    pub elements: std::collections::BTreeMap<String, String>,
    /// A plant of components' component names in the language shown, by id.
    pub parts: std::collections::BTreeMap<String, String>,
    /// Its declared dangers' texts in the language shown, by id.
    pub dangers: std::collections::BTreeMap<String, String>,
    /// Its item classes' names in the language shown (`item-<class>`), by class.
    pub items: std::collections::BTreeMap<String, String>,
    /// Where the last frame put each sensor's name and each explanation tag, by the
    /// element it belongs to (screen points): what the tests check against the
    /// geometry.
    pub placed: Placed,
}

/// The labels of the last frame, by element.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Placed {
    /// Sensor id → its name's rectangle.
    pub names: Vec<(String, Rect)>,
    /// Element → one explanation tag's rectangle (several per element possible).
    pub tags: Vec<(String, Rect)>,
    /// Element → its symbol's rectangle (lamp or actuator).
    pub symbols: Vec<(String, Rect)>,
    /// The overview's area blocks on screen, by area ([`Geometry::frames`]).
    pub frames: Vec<(String, Rect)>,
}

/// The synoptic's tags: key (message `syn-<key>`) and English text (`%kind%` and
/// `%box%` are filled in by the synoptic).
pub const TAGS: [(&str, &str); 27] = [
    ("predicted", "predicted: %kind% box %box%"),
    ("hazard-sheared", "Sheared"),
    ("hazard-dropped", "Dropped"),
    ("hazard-collision", "Collision"),
    ("hazard-pushedagainststopped", "PushedAgainstStopped"),
    ("hazard-endstop", "driven into its end stop"),
    ("hazard-opposeddrives", "driven both ways at once"),
    ("hazard-declared", "dangerous state"),
    ("hazard-overflow", "overflow"),
    ("hazard-dryrun", "pump running dry"),
    ("predicted-component", "predicted: %kind%"),
    ("elevator-left", "Left elevator"),
    ("elevator-right", "Right elevator"),
    ("held-on", "held ON"),
    ("forced-off", "forced OFF"),
    ("stays-on", "stays ON"),
    ("stays-off", "stays OFF"),
    ("suspect", "suspect"),
    ("expected-on", "expected ON"),
    ("expected-off", "expected OFF"),
    ("inferred-box", "inferred box"),
    ("estimated", "estimated"),
    ("no-address", "no fieldbus address"),
    ("other-signals", "Other signals"),
    ("switch-closed", "closed"),
    ("switch-open", "open"),
    ("switch-moving", "operating"),
];

impl View {
    /// The tag `key` in the language shown.
    fn word(&self, key: &str) -> &str {
        self.words.get(key).map_or_else(
            || {
                TAGS.iter()
                    .find(|(k, _)| *k == key)
                    .map_or("", |(_, en)| en)
            },
            String::as_str,
        )
    }
}

impl Default for View {
    fn default() -> Self {
        Self {
            zoom: 1.0,
            pan: Vec2::ZERO,
            area: None,
            areas: None,
            descriptions: std::collections::BTreeMap::new(),
            words: std::collections::BTreeMap::new(),
            elements: std::collections::BTreeMap::new(),
            parts: std::collections::BTreeMap::new(),
            dangers: std::collections::BTreeMap::new(),
            items: std::collections::BTreeMap::new(),
            placed: Placed::default(),
        }
    }
}

/// A drawn sensor.
#[derive(Clone, Debug)]
pub struct SensorGeom {
    /// Signal id.
    pub id: String,
    /// Lamp position, world mm.
    pub lamp: [f32; 2],
    /// Beam across the part (two world points), for presence sensors.
    pub beam: Option<([f32; 2], [f32; 2])>,
    /// High beam.
    pub high: bool,
}

/// A drawn conveyor.
#[derive(Clone, Debug)]
pub struct ConveyorGeom {
    /// Display name.
    pub name: String,
    /// Start, world mm.
    pub start: [f32; 2],
    /// End, world mm.
    pub end: [f32; 2],
    /// Width, mm.
    pub width: f32,
    /// Motor actuator.
    pub actuator: String,
    /// Belt speed, mm/s (for the motion pattern).
    pub speed: f32,
}

/// The pure layout of the synoptic: world positions of every element.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Conveyors.
    pub conveyors: Vec<ConveyorGeom>,
    /// Table centre, world mm.
    pub table_center: [f32; 2],
    /// Table half length and width, mm.
    pub table_size: [f32; 2],
    /// Sensors (C6 at the given table angle).
    pub sensors: Vec<SensorGeom>,
    /// Actuator symbols: id → world position.
    pub actuators: BTreeMap<String, [f32; 2]>,
    /// Elevators: (tag of the label, `elevator-left`…; world position).
    pub elevators: Vec<(String, [f32; 2])>,
    /// World bounds (min, max).
    pub bounds: ([f32; 2], [f32; 2]),
    /// Table actuators: (+u, -u, rotation).
    pub table_actuators: [String; 3],
    /// Whether there is a turntable (a sorting layout) to draw.
    pub has_table: bool,
    /// The axes of a plant of components ([`scene`]).
    pub axes: Vec<scene::AxisGeom>,
    /// The conveyors of a plant of components, with their items ([`scene`]).
    pub belts: Vec<scene::BeltGeom>,
    /// The schematic strip under the layout: the signals `layout.ron` does not place
    /// (a safety contactor, mirror contacts, panel buttons), by their plant element
    /// (`element` in `plant.ron`, "" for none) with the label's world position; their
    /// lamps and symbols are in `sensors` and `actuators` like the placed ones.
    pub schematic: Vec<(String, [f32; 2])>,
    /// The overview's area blocks (ISA-101's level 2 over many areas), each with its
    /// world bounds (min, max); empty for any other view. An overview is drawn compact:
    /// symbols and lamps without their signal names (the tooltip gives them), each
    /// block framed and titled, a click on a block opens its area.
    pub frames: Vec<(String, [f32; 2], [f32; 2])>,
}

/// Spacing of the schematic strip's symbols and rows, world mm (room for a name such
/// as `KM0_fb` beside each lamp).
const STRIP_STEP: f32 = 450.0;

/// Places the signals the layout does not (see [`Geometry::schematic`]) in rows under
/// the layout's `min` corner, one block per element in the plant's order, wrapped to
/// the layout's width; returns the blocks' labels and grows `min` and `max` around them.
fn place_schematic(
    plant: &Plant,
    sensors: &mut Vec<SensorGeom>,
    actuators: &mut BTreeMap<String, [f32; 2]>,
    (min, max): (&mut [f32; 2], &mut [f32; 2]),
) -> Vec<(String, [f32; 2])> {
    let mut blocks: Vec<(String, Vec<(&str, bool)>)> = Vec::new();
    for (s, input) in plant
        .inputs
        .iter()
        .map(|s| (s, true))
        .chain(plant.outputs.iter().map(|s| (s, false)))
    {
        let placed = sensors.iter().any(|g| g.id == s.id) || actuators.contains_key(&s.id);
        if placed {
            continue;
        }
        match blocks.iter_mut().find(|(e, _)| *e == s.element) {
            Some((_, v)) => v.push((&s.id, input)),
            None => blocks.push((s.element.clone(), vec![(&s.id, input)])),
        }
    }
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let per_row = (((max[0] - min[0]) / STRIP_STEP) as usize).max(4);
    let mut labels = Vec::new();
    let x0 = min[0] + STRIP_STEP / 2.0;
    let mut y = min[1] - STRIP_STEP * 0.6;
    for (element, signals) in blocks {
        labels.push((element, [min[0], y]));
        // The lamps in rows, then the actuators' symbols in a row of their own, two
        // steps apart: room for their tags (held ON, forced OFF) beside and under them.
        let lamps: Vec<&str> = signals.iter().filter(|s| s.1).map(|s| s.0).collect();
        let symbols: Vec<&str> = signals.iter().filter(|s| !s.1).map(|s| s.0).collect();
        let mut row_y = y - STRIP_STEP * 0.8;
        for (k, id) in lamps.iter().enumerate() {
            #[allow(clippy::cast_precision_loss)]
            let at = [
                x0 + STRIP_STEP * (k % per_row) as f32,
                row_y - STRIP_STEP * (k / per_row) as f32 * 0.9,
            ];
            sensors.push(SensorGeom {
                id: (*id).to_string(),
                lamp: at,
                beam: None,
                high: false,
            });
            max[0] = max[0].max(at[0] + STRIP_STEP);
            min[1] = min[1].min(at[1] - STRIP_STEP * 0.5);
        }
        if !lamps.is_empty() {
            row_y = min[1] - STRIP_STEP * 0.9;
        }
        for (k, id) in symbols.iter().enumerate() {
            #[allow(clippy::cast_precision_loss)]
            let at = [
                x0 + 2.0 * STRIP_STEP * (k % per_row.div_ceil(2)) as f32,
                row_y - STRIP_STEP * 1.4 * (k / per_row.div_ceil(2)) as f32,
            ];
            actuators.insert((*id).to_string(), at);
            max[0] = max[0].max(at[0] + 2.0 * STRIP_STEP);
            min[1] = min[1].min(at[1] - STRIP_STEP * 1.0);
        }
        // A block's label nearer its own signals than the block above: a clear gap.
        y = min[1] - STRIP_STEP * 0.8;
    }
    labels
}

fn unit(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l = dx.hypot(dy).max(1e-3);
    [dx / l, dy / l]
}

fn add(a: [f32; 2], d: [f32; 2], k: f32) -> [f32; 2] {
    [a[0] + d[0] * k, a[1] + d[1] * k]
}

impl Geometry {
    /// Places every element of `layout` with the table at `angle_mdeg`, and every other
    /// signal of `plant` in the schematic strip.
    pub fn new(layout: &Layout, plant: &Plant, angle_mdeg: i32) -> Self {
        #[allow(clippy::cast_precision_loss)]
        let p = |x: i64, y: i64| [x as f32, y as f32];
        let conveyors: Vec<ConveyorGeom> = layout
            .conveyors
            .iter()
            .map(|c| ConveyorGeom {
                name: c.name.clone(),
                start: p(c.start.x, c.start.y),
                end: p(c.end.x, c.end.y),
                #[allow(clippy::cast_precision_loss)]
                width: c.width_mm as f32,
                actuator: c.actuator.clone(),
                #[allow(clippy::cast_precision_loss)]
                speed: c.speed_mm_s as f32,
            })
            .collect();
        let t = &layout.table;
        let tc = p(t.center.x, t.center.y);
        #[allow(clippy::cast_precision_loss)]
        let (half, tw) = (t.half_length_mm as f32, t.width_mm as f32);
        let angle = (angle_mdeg as f32 / 1000.0).to_radians();
        let u = [angle.cos(), angle.sin()];
        let mut actuators = BTreeMap::new();
        for c in &conveyors {
            let d = unit(c.start, c.end);
            // Motor symbol beside the middle of the belt, on the right of travel.
            let right = [d[1], -d[0]];
            let mid = [(c.start[0] + c.end[0]) / 2.0, (c.start[1] + c.end[1]) / 2.0];
            actuators.insert(c.actuator.clone(), add(mid, right, c.width / 2.0 + 170.0));
        }
        let side = t.width_mm as f32 / 2.0 + 520.0;
        actuators.insert(t.plus_actuator.clone(), [tc[0] + side, tc[1] + 170.0]);
        actuators.insert(t.rotate_actuator.clone(), [tc[0] + side, tc[1]]);
        actuators.insert(t.minus_actuator.clone(), [tc[0] + side, tc[1] - 170.0]);
        let mut sensors = place_sensors(layout, &conveyors, tc, u, tw);
        let elevators: Vec<(String, [f32; 2])> = layout
            .elevators
            .iter()
            .map(|e| {
                let side = format!("{:?}", e.side).to_lowercase();
                (format!("elevator-{side}"), p(e.at.x, e.at.y))
            })
            .collect();
        let mut min = [f32::MAX; 2];
        let mut max = [f32::MIN; 2];
        let mut grow = |q: [f32; 2], r: f32| {
            for i in 0..2 {
                min[i] = min[i].min(q[i] - r);
                max[i] = max[i].max(q[i] + r);
            }
        };
        for c in &conveyors {
            grow(c.start, c.width / 2.0 + 300.0);
            grow(c.end, c.width / 2.0 + 300.0);
        }
        grow(tc, half.max(tw) + 600.0);
        for (_, e) in &elevators {
            grow(*e, 200.0);
        }
        let schematic = place_schematic(plant, &mut sensors, &mut actuators, (&mut min, &mut max));
        Self {
            conveyors,
            table_center: tc,
            table_size: [half, tw],
            sensors,
            actuators,
            elevators,
            bounds: (min, max),
            table_actuators: [
                t.plus_actuator.clone(),
                t.minus_actuator.clone(),
                t.rotate_actuator.clone(),
            ],
            has_table: true,
            axes: Vec::new(),
            belts: Vec::new(),
            schematic,
            frames: Vec::new(),
        }
    }

    /// World position of an element (sensor lamp or actuator symbol).
    pub fn element(&self, id: &str) -> Option<[f32; 2]> {
        self.sensors
            .iter()
            .find(|s| s.id == id)
            .map(|s| s.lamp)
            .or_else(|| self.actuators.get(id).copied())
    }
}

/// Places the sensors' lamps and beams: presence sensors across their conveyor or the
/// turntable (at `tc`, axis `u`, width `tw`), angle sensors right of the table.
fn place_sensors(
    layout: &Layout,
    conveyors: &[ConveyorGeom],
    tc: [f32; 2],
    u: [f32; 2],
    tw: f32,
) -> Vec<SensorGeom> {
    let t = &layout.table;
    let n = [-u[1], u[0]];
    let mut sensors = Vec::new();
    for s in &layout.sensors {
        match &s.kind {
            SensorKind::Presence { part, at_mm, beam } => {
                #[allow(clippy::cast_precision_loss)]
                let at = *at_mm as f32;
                let high = *beam == Beam::High;
                if let Some(c) = conveyors.iter().find(|c| {
                    layout
                        .conveyors
                        .iter()
                        .any(|lc| &lc.id == part && lc.name == c.name)
                }) {
                    let d = unit(c.start, c.end);
                    let left = [-d[1], d[0]];
                    let at_pt = add(c.start, d, at);
                    // Lamps away from the turntable's corner: low beams below the
                    // horizontal belts, beside the vertical ones.
                    let horizontal = d[0].abs() > d[1].abs();
                    let k = match (high, horizontal) {
                        (false, true) | (true, false) => -1.0,
                        _ => 1.0,
                    };
                    let a = add(at_pt, left, c.width / 2.0 * k);
                    let b = add(at_pt, left, -c.width / 2.0 * k);
                    sensors.push(SensorGeom {
                        id: s.id.clone(),
                        lamp: add(at_pt, left, (c.width / 2.0 + 70.0) * k),
                        beam: Some((a, b)),
                        high,
                    });
                } else if part == &t.id {
                    let at_pt = add(tc, u, at);
                    sensors.push(SensorGeom {
                        id: s.id.clone(),
                        lamp: add(at_pt, n, tw / 2.0 + 60.0),
                        beam: Some((add(at_pt, n, tw / 2.0), add(at_pt, n, -tw / 2.0))),
                        high,
                    });
                }
            }
            SensorKind::Angle { min_mdeg, max_mdeg } => {
                // Right of the table, upper for angles towards +y.
                let mid = (*min_mdeg + *max_mdeg) as f32 / 2000.0;
                let y = if mid > 45.0 { 110.0 } else { -110.0 };
                sensors.push(SensorGeom {
                    id: s.id.clone(),
                    lamp: [tc[0] + tw / 2.0 + 190.0, tc[1] + y],
                    beam: None,
                    high: false,
                });
            }
        }
    }
    sensors
}

/// What to draw: the plant at one time, with the marks of an explanation level.
pub struct Picture<'a> {
    /// Boxes.
    pub boxes: &'a [BoxView],
    /// Signal values to draw (sensors and applied actuators).
    pub values: &'a BTreeMap<String, bool>,
    /// Actuators the filter forces (drawn amber).
    pub forced: &'a BTreeSet<String>,
    /// Time, ms (phase of the motion pattern).
    pub time_ms: u64,
    /// Marks of the explanation level shown.
    pub highlights: &'a [Highlight],
    /// Level 1: predicted boxes, table angle and hazards.
    pub ghost: Option<(&'a [BoxView], i32, &'a [Hazard])>,
    /// Banner (trip, replay) drawn at the top of the synoptic.
    pub banner: Option<(String, Color32)>,
    /// Level 1 on a plant of components: the projected picture.
    pub ghost_scene: Option<&'a vigie_core::machine::Scene>,
    /// The overview's areas to flag (a trip's signals, a suspect sensor in them).
    pub flagged: &'a BTreeSet<String>,
}

/// World → screen transform.
#[derive(Clone, Copy)]
struct Xf {
    origin: Pos2,
    center: [f32; 2],
    scale: f32,
}

impl Xf {
    fn p(&self, w: [f32; 2]) -> Pos2 {
        pos2(
            self.origin.x + (w[0] - self.center[0]) * self.scale,
            self.origin.y - (w[1] - self.center[1]) * self.scale,
        )
    }
}

fn quad(xf: &Xf, c: [f32; 2], u: [f32; 2], half_l: f32, half_w: f32) -> Vec<Pos2> {
    let n = [-u[1], u[0]];
    [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
        .iter()
        .map(|(a, b)| {
            xf.p([
                c[0] + u[0] * half_l * a + n[0] * half_w * b,
                c[1] + u[1] * half_l * a + n[1] * half_w * b,
            ])
        })
        .collect()
}

fn chevrons(
    painter: &egui::Painter,
    xf: &Xf,
    start: [f32; 2],
    end: [f32; 2],
    width: f32,
    phase: f32,
    color: Color32,
) {
    let d = unit(start, end);
    let n = [-d[1], d[0]];
    let len = (end[0] - start[0]).hypot(end[1] - start[1]);
    let pitch = 160.0;
    let mut s = phase.rem_euclid(pitch);
    let stroke = Stroke::new((xf.scale * 28.0).clamp(1.0, 3.0), color);
    while s < len - 40.0 {
        let tip = add(start, d, s + 40.0);
        let back = add(start, d, s);
        let a = add(back, n, width * 0.28);
        let b = add(back, n, -width * 0.28);
        painter.line_segment([xf.p(a), xf.p(tip)], stroke);
        painter.line_segment([xf.p(b), xf.p(tip)], stroke);
        s += pitch;
    }
}

fn box_shape(xf: &Xf, b: &BoxView) -> Vec<Pos2> {
    let a = (b.angle_mdeg as f32 / 1000.0).to_radians();
    #[allow(clippy::cast_precision_loss)]
    quad(
        xf,
        [b.x_mm, b.y_mm],
        [a.cos(), a.sin()],
        b.length_mm as f32 / 2.0,
        b.width_mm as f32 / 2.0,
    )
}

fn badge(painter: &egui::Painter, at: Pos2, text: &str, fill: Color32, fg: Color32) -> Rect {
    let galley = painter.layout_no_wrap(text.to_string(), FontId::proportional(12.0), fg);
    let rect = Rect::from_min_size(at, galley.size() + vec2(8.0, 4.0));
    painter.rect_filled(rect, 4.0, fill);
    painter.galley(rect.min + vec2(4.0, 2.0), galley, fg);
    rect
}

fn tooltip_text(plant: &Plant, view: &View, id: &str, value: Option<bool>) -> String {
    let Some(s) = plant.signal(id) else {
        return id.to_string();
    };
    let addr = s
        .address
        .map_or_else(|| view.word("no-address").to_string(), |a| a.to_string());
    let v = match value {
        Some(true) => "1",
        Some(false) => "0",
        None => "?",
    };
    let description = view.descriptions.get(id).unwrap_or(&s.description);
    format!("{id} = {v}\n{description}\n{addr}")
}

/// Paints the synoptic into the available space; returns the response (its rect is the
/// synoptic's area).
pub fn synoptic_ui(
    ui: &mut egui::Ui,
    view: &mut View,
    geom: &Geometry,
    table_angle_mdeg: i32,
    pic: &Picture<'_>,
    pal: &Palette,
    plant: &Plant,
) -> egui::Response {
    let size = ui.available_size().max(vec2(100.0, 100.0));
    let (response, painter) = ui.allocate_painter(size, Sense::click_and_drag());
    response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "Synoptic"));
    let rect = response.rect;
    zoom_and_pan(ui, view, &response);
    painter.rect_filled(rect, 0.0, pal.floor);
    let (min, max) = geom.bounds;
    let fit = (rect.width() / (max[0] - min[0])).min(rect.height() / (max[1] - min[1])) * 0.95;
    let xf = Xf {
        origin: rect.center() + view.pan,
        center: [(min[0] + max[0]) / 2.0, (min[1] + max[1]) / 2.0],
        scale: fit * view.zoom,
    };
    let painter = painter.with_clip_rect(rect);
    let (lamp_r, compact) = lamps(geom, &xf);
    let cv = Canvas {
        painter: &painter,
        xf,
        pal,
        values: pic.values,
        rect,
        lamp_r,
        compact,
        claimed: std::cell::RefCell::new(Vec::new()),
        symbols: std::cell::RefCell::new(Vec::new()),
    };
    let edge = Stroke::new(1.0, pal.equipment_edge);
    #[allow(clippy::cast_precision_loss)]
    let t_s = pic.time_ms as f32 / 1000.0;

    let symbols = symbol_rects(&cv, geom);
    cv.symbols
        .borrow_mut()
        .extend(symbols.iter().map(|(_, r)| *r));
    if !geom.has_table {
        // The lines from the lamps to their axis or belt (the windows' leaders): a name
        // or a readout across them reads badly. (The station's layout has its beams
        // across the belts, under the boxes, and keeps its places.)
        cv.symbols
            .borrow_mut()
            .extend(geom.sensors.iter().filter_map(|s| {
                s.beam
                    .map(|(a, b)| Rect::from_two_pos(xf.p(a), xf.p(b)).expand(1.0))
            }));
    }
    if cv.compact {
        // An overview's names go where no lamp or symbol is, or not at all.
        cv.claimed
            .borrow_mut()
            .extend(symbols.iter().map(|(_, r)| *r));
    }
    let frames = paint_frames(&cv, geom, view, pic.flagged);
    paint_conveyors(&cv, geom, t_s);
    paint_elevators(&cv, geom, view);
    paint_schematic_labels(&cv, geom, view);
    if geom.has_table {
        paint_table(&cv, geom, table_angle_mdeg, (pal.equipment, edge), true);
        paint_table_motion(&cv, geom, table_angle_mdeg, t_s);
    }
    scene::paint_axes(&cv, geom, view, pic.ghost_scene);
    scene::paint_belts(&cv, geom, view, t_s);
    paint_boxes(&cv, pic.boxes);
    // Predicted-hazard labels, drawn last so that no equipment hides them.
    let predicted_labels = match pic.ghost {
        Some(ghost) => paint_ghosts(&cv, geom, view, ghost, pic.ghost_scene),
        None => Vec::new(),
    };
    paint_sensors(&cv, geom);
    paint_actuators(&cv, geom, pic.forced);
    let names = if cv.compact {
        Vec::new()
    } else {
        paint_sensor_names(&cv, geom, &symbols)
    };
    let taken: Vec<Rect> = symbols.iter().chain(&names).map(|(_, r)| *r).collect();
    let tags = paint_marks(&cv, geom, view, pic.highlights, &taken);
    repaint_ringed_names(&cv, pic.highlights, &names);
    view.placed = Placed {
        names,
        tags,
        symbols,
        frames,
    };
    if let Some((text, col)) = &pic.banner {
        badge(
            &painter,
            rect.min + vec2(10.0, 10.0),
            text,
            *col,
            Color32::WHITE,
        );
    }
    paint_predicted_labels(&cv, geom, &predicted_labels);
    if let Some(ptr) = response.hover_pos() {
        paint_tooltip(&cv, geom, plant, view, ptr);
    }
    response
}

/// The lamps' radius, and whether the view is compact: an overview, or a schematic
/// drawn so small that its symbols would cover each other (an area in the maintenance
/// view, beside the program), drawn with symbols but without their names, which the
/// tooltip gives. The top view keeps its short names, and is never searched.
fn lamps(geom: &Geometry, xf: &Xf) -> (f32, bool) {
    let lamp = (55.0 * xf.scale).clamp(5.0, 14.0);
    let overview = !geom.frames.is_empty();
    if geom.has_table && !overview {
        return (lamp, false);
    }
    // Searched once a frame, for both the choice and the overview's lamp size.
    let near = nearest_symbols(geom, xf);
    if overview || near < 2.4 * lamp {
        (compact_lamp(lamp, near), true)
    } else {
        (lamp, false)
    }
}

/// The smallest Chebyshev distance between two symbols' centres (lamps and actuators),
/// px: squares of that side do not overlap.
fn nearest_symbols(geom: &Geometry, xf: &Xf) -> f32 {
    let centres: Vec<Pos2> = geom
        .sensors
        .iter()
        .map(|s| xf.p(s.lamp))
        .chain(geom.actuators.values().map(|a| xf.p(*a)))
        .collect();
    let mut near = f32::MAX;
    for (i, a) in centres.iter().enumerate() {
        for b in &centres[i + 1..] {
            near = near.min((a.x - b.x).abs().max((a.y - b.y).abs()));
        }
    }
    near
}

/// The lamps' radius in an overview: `lamp`, the one of any view, but small enough that
/// no two symbols (a lamp's square of `2 r + 2`, an actuator's of `2.4 r`) cover each
/// other however small the blocks are drawn (stacked beams, a cylinder's outputs);
/// `near` is [`nearest_symbols`].
fn compact_lamp(lamp: f32, near: f32) -> f32 {
    lamp.min(near / 2.4).min((near - 2.0) / 2.0).max(1.5)
}

/// What the synoptic's painters share: the clipped painter, the transform, the palette,
/// the signal values, the synoptic's area and the lamps' radius.
struct Canvas<'a> {
    painter: &'a egui::Painter,
    xf: Xf,
    pal: &'a Palette,
    values: &'a BTreeMap<String, bool>,
    rect: Rect,
    lamp_r: f32,
    /// An overview: symbols without their signal names ([`Geometry::frames`]).
    compact: bool,
    /// The rectangles of the names painted so far ([`Canvas::label`]).
    claimed: std::cell::RefCell<Vec<Rect>>,
    /// The lamps' and actuators' symbols on screen, and on a plant of components the
    /// lines from the lamps to their axis or belt.
    symbols: std::cell::RefCell<Vec<Rect>>,
}

impl Canvas<'_> {
    /// Value of a signal (false when not drawn).
    fn val(&self, id: &str) -> bool {
        self.values.get(id).copied().unwrap_or(false)
    }

    /// Paints a name (a component's, an area's) unless it would cross a name painted
    /// before it: the first painted wins, the other one is left to the tooltip and to
    /// the area's own view. Returns its rectangle when painted.
    fn label(
        &self,
        at: Pos2,
        align: Align2,
        text: &str,
        font: FontId,
        color: Color32,
    ) -> Option<Rect> {
        let galley = self.painter.layout_no_wrap(text.to_string(), font, color);
        let r = align.anchor_size(at, galley.size());
        let mut claimed = self.claimed.borrow_mut();
        if claimed.iter().any(|c| c.intersects(r)) {
            return None;
        }
        claimed.push(r);
        self.painter.galley(r.min, galley, color);
        Some(r)
    }
}

/// A component's name under its symbol: in the area's own view, not in the overview
/// (where the block's title says the area and the lamps crowd).
fn component_name(cv: &Canvas<'_>, at: Pos2, text: &str) {
    if !cv.compact {
        cv.label(
            at,
            Align2::CENTER_TOP,
            text,
            FontId::proportional(13.0),
            cv.pal.text,
        );
    }
}

/// The overview's area blocks: a frame round each, its title at its top left, both in
/// the trip's colour when the area is flagged; returns them on screen.
fn paint_frames(
    cv: &Canvas<'_>,
    geom: &Geometry,
    view: &View,
    flagged: &BTreeSet<String>,
) -> Vec<(String, Rect)> {
    let mut out = Vec::new();
    for (area, lo, hi) in &geom.frames {
        // Lamps keep a legible size however small the block: room for them.
        let r = Rect::from_two_pos(cv.xf.p(*lo), cv.xf.p(*hi)).expand(cv.lamp_r);
        let (stroke, fg) = if flagged.contains(area) {
            (Stroke::new(2.5, cv.pal.trip), cv.pal.trip)
        } else {
            (
                Stroke::new(1.0, cv.pal.equipment_edge.gamma_multiply(0.5)),
                cv.pal.text,
            )
        };
        cv.painter.rect(
            r,
            6.0,
            cv.pal.equipment.gamma_multiply(0.12),
            stroke,
            egui::StrokeKind::Middle,
        );
        let name = if area.is_empty() {
            view.word("other-signals").to_string()
        } else if flagged.contains(area) {
            format!("⚠ {}", view.elements.get(area).unwrap_or(area))
        } else {
            view.elements.get(area).unwrap_or(area).clone()
        };
        // Always written, on one line cut to the block's width (`Poste de
        // manipulation` over a narrow station): the names and lamps give way to it.
        let mut job = egui::text::LayoutJob::single_section(
            name,
            egui::TextFormat::simple(FontId::proportional(15.0), fg),
        );
        job.wrap = egui::text::TextWrapping {
            max_width: (r.width() - 12.0).max(20.0),
            max_rows: 1,
            break_anywhere: true,
            overflow_character: Some('…'),
        };
        let galley = cv.painter.layout_job(job);
        let at = r.left_top() + vec2(8.0, 4.0);
        cv.claimed
            .borrow_mut()
            .push(Rect::from_min_size(at, galley.size()).expand(2.0));
        cv.painter.galley(at, galley, fg);
        out.push((area.clone(), r));
    }
    out
}

/// Zooms with the wheel around the pointer, pans with a drag, resets on a double click.
fn zoom_and_pan(ui: &egui::Ui, view: &mut View, response: &egui::Response) {
    let rect = response.rect;
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y + (i.zoom_delta() - 1.0) * 200.0);
        if scroll.abs() > 0.0 {
            let factor = (scroll / 400.0).exp();
            let new_zoom = (view.zoom * factor).clamp(0.3, 12.0);
            if let Some(ptr) = response.hover_pos() {
                let c = rect.center() + view.pan;
                let k = new_zoom / view.zoom;
                view.pan += (ptr - c) * (1.0 - k);
            }
            view.zoom = new_zoom;
        }
    }
    if response.dragged() {
        view.pan += response.drag_delta();
    }
    if response.double_clicked() {
        view.zoom = 1.0;
        view.pan = Vec2::ZERO;
    }
}

/// Paints the conveyors, with moving chevrons on those running.
fn paint_conveyors(cv: &Canvas<'_>, geom: &Geometry, t_s: f32) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    let edge = Stroke::new(1.0, pal.equipment_edge);
    for c in &geom.conveyors {
        let d = unit(c.start, c.end);
        let len = (c.end[0] - c.start[0]).hypot(c.end[1] - c.start[1]);
        let mid = add(c.start, d, len / 2.0);
        let on = cv.val(&c.actuator);
        let fill = if on {
            pal.equipment
        } else {
            pal.equipment.gamma_multiply(0.9)
        };
        painter.add(Shape::convex_polygon(
            quad(xf, mid, d, len / 2.0, c.width / 2.0),
            fill,
            edge,
        ));
        if on {
            chevrons(
                painter,
                xf,
                c.start,
                c.end,
                c.width,
                t_s * c.speed,
                pal.running,
            );
        }
    }
}

/// Paints the elevators with their names.
fn paint_elevators(cv: &Canvas<'_>, geom: &Geometry, view: &View) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    for (key, at) in &geom.elevators {
        let name = view.word(key);
        let p = xf.p(*at);
        let r = Rect::from_center_size(p, Vec2::splat(300.0 * xf.scale));
        painter.rect_stroke(
            r,
            2.0,
            Stroke::new(1.5, pal.equipment_edge),
            egui::StrokeKind::Middle,
        );
        painter.text(
            r.center(),
            Align2::CENTER_CENTER,
            name,
            FontId::proportional(11.0),
            pal.text_dim,
        );
    }
}

/// The schematic strip's labels: each element's name in the language shown.
fn paint_schematic_labels(cv: &Canvas<'_>, geom: &Geometry, view: &View) {
    for (element, at) in &geom.schematic {
        // An overview's block is titled already.
        if geom.frames.iter().any(|(a, ..)| a == element) {
            continue;
        }
        let name = if element.is_empty() {
            view.word("other-signals")
        } else {
            view.elements.get(element).unwrap_or(element)
        };
        cv.label(
            cv.xf.p(*at),
            Align2::LEFT_BOTTOM,
            name,
            FontId::proportional(12.0),
            cv.pal.text_dim,
        );
    }
}

/// Paints the turntable at `angle_mdeg` with a fill and stroke, its rollers if asked.
fn paint_table(
    cv: &Canvas<'_>,
    geom: &Geometry,
    angle_mdeg: i32,
    (fill, stroke): (Color32, Stroke),
    rollers: bool,
) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    let a = (angle_mdeg as f32 / 1000.0).to_radians();
    let u = [a.cos(), a.sin()];
    let tc = geom.table_center;
    let [half, w] = geom.table_size;
    painter.add(Shape::convex_polygon(
        quad(xf, tc, u, half, w / 2.0),
        fill,
        stroke,
    ));
    let n = [-u[1], u[0]];
    if rollers {
        let mut s = -half + 40.0;
        while s < half {
            let c = add(tc, u, s);
            painter.line_segment(
                [
                    xf.p(add(c, n, w / 2.0 - 15.0)),
                    xf.p(add(c, n, -w / 2.0 + 15.0)),
                ],
                Stroke::new(1.0, pal.equipment_edge.gamma_multiply(0.5)),
            );
            s += 50.0;
        }
    }
    painter.circle_stroke(
        xf.p(tc),
        (half + 25.0) * xf.scale,
        Stroke::new(1.0, pal.equipment_edge.gamma_multiply(0.4)),
    );
}

/// Paints the chevrons of the turntable's rollers when they run (+u or -u).
fn paint_table_motion(cv: &Canvas<'_>, geom: &Geometry, table_angle_mdeg: i32, t_s: f32) {
    let a = (table_angle_mdeg as f32 / 1000.0).to_radians();
    let u = [a.cos(), a.sin()];
    let [half, w] = geom.table_size;
    let [plus, minus, _] = &geom.table_actuators;
    let dir = if cv.val(plus) {
        Some(1.0)
    } else if cv.val(minus) {
        Some(-1.0)
    } else {
        None
    };
    if let Some(k) = dir {
        let s = add(geom.table_center, u, -half * k);
        let e = add(geom.table_center, u, half * k);
        chevrons(cv.painter, &cv.xf, s, e, w, t_s * 300.0, cv.pal.running);
    }
}

/// Paints the boxes not yet delivered, with their id and size.
fn paint_boxes(cv: &Canvas<'_>, boxes: &[BoxView]) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    for b in boxes {
        if matches!(b.state, BoxState::Delivered(_)) {
            continue;
        }
        let fill = if b.damaged {
            pal.trip
        } else if b.size == BoxSize::Large {
            pal.box_large
        } else {
            pal.box_small
        };
        let stroke = Stroke::new(if b.damaged { 2.0 } else { 1.0 }, pal.box_edge);
        painter.add(Shape::convex_polygon(box_shape(xf, b), fill, stroke));
        let label = match b.size {
            BoxSize::Small => format!("{} S", b.id),
            BoxSize::Large => format!("{} L", b.id),
        };
        painter.text(
            xf.p([b.x_mm, b.y_mm]),
            Align2::CENTER_CENTER,
            label,
            FontId::proportional(11.0),
            pal.text,
        );
    }
}

/// Paints the projection (ghost table, boxes and hazard crosses); returns the
/// predicted-hazard labels to draw last.
fn paint_ghosts(
    cv: &Canvas<'_>,
    geom: &Geometry,
    view: &View,
    (boxes, angle, hazards): (&[BoxView], i32, &[Hazard]),
    ghost_scene: Option<&vigie_core::machine::Scene>,
) -> Vec<(Pos2, String)> {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    let mut predicted_labels = Vec::new();
    if geom.has_table {
        paint_table(
            cv,
            geom,
            angle,
            (pal.ghost.gamma_multiply(0.12), Stroke::new(1.5, pal.ghost)),
            false,
        );
    }
    for b in boxes {
        if matches!(b.state, BoxState::Delivered(_)) {
            continue;
        }
        let col = if b.damaged { pal.trip } else { pal.ghost };
        painter.add(Shape::convex_polygon(
            box_shape(xf, b),
            col.gamma_multiply(0.2),
            Stroke::new(2.0, col),
        ));
    }
    for h in hazards {
        if let Some((p, label)) = scene::hazard_label(geom, view, h, xf, ghost_scene) {
            let s = Stroke::new(3.0, pal.trip);
            painter.line_segment([p - vec2(16.0, 16.0), p + vec2(16.0, 16.0)], s);
            painter.line_segment([p - vec2(16.0, -16.0), p + vec2(16.0, -16.0)], s);
            predicted_labels.push((p, label));
        } else if let Some(b) = boxes.iter().find(|b| b.id == h.box_id) {
            let p = xf.p([b.x_mm, b.y_mm]);
            let r = 16.0;
            let s = Stroke::new(3.0, pal.trip);
            painter.line_segment([p - vec2(r, r), p + vec2(r, r)], s);
            painter.line_segment([p - vec2(r, -r), p + vec2(r, -r)], s);
            let kind = view.word(&format!("hazard-{:?}", h.kind).to_lowercase());
            let label = view
                .word("predicted")
                .replace("%kind%", kind)
                .replace("%box%", &h.box_id.to_string());
            predicted_labels.push((p, label));
        }
    }
    predicted_labels
}

/// Paints the sensors: beams (dashed for high ones), lamps and ids.
fn paint_sensors(cv: &Canvas<'_>, geom: &Geometry) {
    let (painter, xf, pal, lamp_r) = (cv.painter, &cv.xf, cv.pal, cv.lamp_r);
    for s in &geom.sensors {
        let on = cv.val(&s.id);
        if let Some((a, b)) = s.beam {
            let col = if on {
                pal.sensor_on
            } else {
                pal.equipment_edge.gamma_multiply(0.6)
            };
            let stroke = Stroke::new(if on { 2.5 } else { 1.0 }, col);
            if s.high {
                painter.add(Shape::dashed_line(&[xf.p(a), xf.p(b)], stroke, 4.0, 3.0));
            } else {
                painter.line_segment([xf.p(a), xf.p(b)], stroke);
            }
        }
        let p = xf.p(s.lamp);
        painter.circle(
            p,
            lamp_r,
            if on { pal.sensor_on } else { pal.sensor_off },
            Stroke::new(1.2, pal.equipment_edge),
        );
    }
}

/// The symbols' rectangles on screen: sensor lamps and actuator symbols.
fn symbol_rects(cv: &Canvas<'_>, geom: &Geometry) -> Vec<(String, Rect)> {
    let (xf, lamp_r) = (&cv.xf, cv.lamp_r);
    geom.sensors
        .iter()
        .map(|s| {
            (
                s.id.clone(),
                Rect::from_center_size(xf.p(s.lamp), Vec2::splat(lamp_r * 2.0 + 2.0)),
            )
        })
        .chain(
            geom.actuators
                .iter()
                .map(|(id, at)| (id.clone(), actuator_rect(cv, id, xf.p(*at)))),
        )
        .collect()
}

/// An actuator symbol's rectangle at `p`: a square, widened to its id (`KM0`).
fn actuator_rect(cv: &Canvas<'_>, id: &str, p: Pos2) -> Rect {
    let side = cv.lamp_r * 2.4;
    if cv.compact {
        return Rect::from_center_size(p, Vec2::splat(side));
    }
    let text = cv
        .painter
        .layout_no_wrap(id.to_string(), FontId::proportional(11.0), cv.pal.text)
        .size()
        .x;
    Rect::from_center_size(p, vec2(side.max(text + 4.0), side))
}

/// Paints the sensors' names, each beside its lamp on no symbol and no other name.
fn paint_sensor_names(
    cv: &Canvas<'_>,
    geom: &Geometry,
    symbols: &[(String, Rect)],
) -> Vec<(String, Rect)> {
    let (painter, xf, pal, lamp_r) = (cv.painter, &cv.xf, cv.pal, cv.lamp_r);
    let font = FontId::proportional(12.0);
    let galleys: Vec<_> = geom
        .sensors
        .iter()
        .map(|s| painter.layout_no_wrap(s.id.clone(), font.clone(), pal.text))
        .collect();
    let labels: Vec<(Pos2, Vec2)> = geom
        .sensors
        .iter()
        .zip(&galleys)
        .map(|(s, g)| (xf.p(s.lamp), g.size()))
        .collect();
    // The symbols and, on a plant of components, the lamps' lines ([`Canvas::symbols`]).
    let mut obstacles: Vec<Rect> = cv.symbols.borrow().clone();
    // A name's galley is taller than its glyphs: a name may touch another's box.
    obstacles.extend(cv.claimed.borrow().iter().map(|r| r.shrink(3.0)));
    let centres: Vec<Pos2> = symbols.iter().map(|(_, r)| r.center()).collect();
    let rects = super::placement::place(&labels, &centres, &obstacles, cv.rect, lamp_r + 3.0);
    let mut out = Vec::new();
    for ((s, g), r) in geom.sensors.iter().zip(galleys).zip(rects) {
        painter.galley(r.min, g, pal.text);
        out.push((s.id.clone(), r));
    }
    out
}

/// Paints the actuators' symbols (amber when forced, lit when on).
fn paint_actuators(cv: &Canvas<'_>, geom: &Geometry, forced: &BTreeSet<String>) {
    let (painter, xf, pal) = (cv.painter, &cv.xf, cv.pal);
    for (id, at) in &geom.actuators {
        let p = xf.p(*at);
        let on = cv.val(id);
        let forced = forced.contains(id);
        let r = actuator_rect(cv, id, p);
        let fill = if forced {
            pal.forced
        } else if on {
            pal.running
        } else {
            pal.equipment
        };
        painter.rect_filled(r, 3.0, fill);
        painter.rect_stroke(
            r,
            3.0,
            Stroke::new(1.2, pal.equipment_edge),
            egui::StrokeKind::Middle,
        );
        let fg = if on && !forced {
            pal.sensor_on
        } else {
            pal.text
        };
        if cv.compact {
            continue;
        }
        painter.text(
            r.center(),
            Align2::CENTER_CENTER,
            id,
            FontId::proportional(11.0),
            fg,
        );
    }
}

/// A ring (suspect, estimated) is wider than the lamp the name sits beside: the name is
/// painted again over it, on the floor's colour, so that the ring never crosses it.
fn repaint_ringed_names(cv: &Canvas<'_>, highlights: &[Highlight], names: &[(String, Rect)]) {
    let ringed = |h: &Highlight| matches!(h.mark, Mark::Suspect | Mark::Estimated);
    for (id, r) in names {
        if highlights.iter().any(|h| ringed(h) && &h.element == id) {
            cv.painter.rect_filled(r.expand(1.0), 2.0, cv.pal.floor);
            cv.painter.text(
                r.min,
                Align2::LEFT_TOP,
                id,
                FontId::proportional(12.0),
                cv.pal.text,
            );
        }
    }
}

/// Paints the explanation marks: rings on their elements and tags beside them, on no
/// symbol, no sensor name and no other tag, with a leader line when moved away.
fn paint_marks(
    cv: &Canvas<'_>,
    geom: &Geometry,
    view: &View,
    highlights: &[Highlight],
    taken: &[Rect],
) -> Vec<(String, Rect)> {
    let (painter, xf, pal, lamp_r) = (cv.painter, &cv.xf, cv.pal, cv.lamp_r);
    // The tags first, then their places all at once.
    let mut tags: Vec<(String, Pos2, String, Color32, Color32)> = Vec::new();
    for h in highlights {
        let Some(w) = geom.element(&h.element) else {
            continue;
        };
        let p = xf.p(w);
        let mut put = |text: &str, fill: Color32, fg: Color32| {
            tags.push((h.element.clone(), p, text.to_string(), fill, fg));
        };
        match &h.mark {
            Mark::Circle => {
                painter.circle_stroke(p, lamp_r * 2.0, Stroke::new(3.0, pal.trip));
            }
            Mark::ForcedOn => put(view.word("held-on"), pal.forced, pal.text),
            Mark::ForcedOff => put(view.word("forced-off"), pal.forced, pal.text),
            Mark::Change { from, to } => put(
                &format!("{}→{}", u8::from(*from), u8::from(*to)),
                pal.highlight,
                Color32::WHITE,
            ),
            Mark::Steady { value } => put(
                view.word(if *value { "stays-on" } else { "stays-off" }),
                pal.equipment_edge,
                Color32::WHITE,
            ),
            Mark::Suspect => {
                painter.add(dashed_ring(p, lamp_r, pal.alarm));
                put(view.word("suspect"), pal.alarm, pal.text);
            }
            Mark::Expected { value } => put(
                view.word(if *value {
                    "expected-on"
                } else {
                    "expected-off"
                }),
                pal.highlight,
                Color32::WHITE,
            ),
            Mark::InferredBox => put(view.word("inferred-box"), pal.highlight, Color32::WHITE),
            Mark::Estimated => {
                painter.add(dashed_ring(p, lamp_r, pal.caution));
                put(view.word("estimated"), pal.caution, pal.text);
            }
        }
    }
    let font = FontId::proportional(12.0);
    let galleys: Vec<_> = tags
        .iter()
        .map(|(_, _, text, _, fg)| painter.layout_no_wrap(text.clone(), font.clone(), *fg))
        .collect();
    let labels: Vec<(Pos2, Vec2)> = tags
        .iter()
        .zip(&galleys)
        .map(|((_, p, ..), g)| (*p, g.size() + vec2(8.0, 4.0)))
        .collect();
    let centres: Vec<Pos2> = symbol_rects(cv, geom)
        .iter()
        .map(|(_, r)| r.center())
        .collect();
    let rects = super::placement::place(&labels, &centres, taken, cv.rect, lamp_r * 1.3 + 4.0);
    let mut out = Vec::new();
    for (((element, p, _, fill, fg), g), r) in tags.into_iter().zip(galleys).zip(rects) {
        let near = r.clamp(p);
        if near.distance(p) > lamp_r * 1.3 + 6.0 {
            painter.line_segment([p, near], Stroke::new(1.2, fill));
        }
        painter.rect_filled(r, 4.0, fill);
        painter.galley(r.min + vec2(4.0, 2.0), g, fg);
        out.push((element, r));
    }
    out
}

/// Paints the predicted-hazard labels, each with a leader line to its box.
fn paint_predicted_labels(cv: &Canvas<'_>, geom: &Geometry, predicted_labels: &[(Pos2, String)]) {
    let (painter, xf, pal, lamp_r, rect) = (cv.painter, &cv.xf, cv.pal, cv.lamp_r, cv.rect);
    // Below and to the left of the box, away from the actuator lamps on the right,
    // with a leader line to the box.
    // The first of a few places around the box that covers no sensor or actuator lamp.
    let lamps: Vec<Pos2> = geom
        .sensors
        .iter()
        .map(|s| xf.p(s.lamp))
        .chain(geom.actuators.values().map(|p| xf.p(*p)))
        .collect();
    for (p, text) in predicted_labels {
        let galley =
            painter.layout_no_wrap(text.clone(), FontId::proportional(12.0), Color32::WHITE);
        let size = galley.size() + vec2(8.0, 4.0);
        let candidates = [
            pos2(p.x + 40.0, p.y + 70.0),
            pos2(p.x - 40.0 - size.x, p.y + 70.0),
            pos2(p.x + 40.0, p.y - 70.0 - size.y),
            pos2(p.x - 40.0 - size.x, p.y - 70.0 - size.y),
        ];
        let clear = |at: &Pos2| {
            let r = Rect::from_min_size(*at, size).expand(lamp_r + 6.0);
            lamps.iter().all(|l| !r.contains(*l))
                && rect.contains_rect(Rect::from_min_size(*at, size))
        };
        // None clear (a narrow synoptic): the first, kept inside the synoptic.
        let at = candidates.iter().copied().find(clear).unwrap_or_else(|| {
            let c = candidates[0];
            pos2(
                c.x.min(rect.right() - size.x - 4.0).max(rect.left() + 4.0),
                c.y.min(rect.bottom() - size.y - 4.0).max(rect.top() + 4.0),
            )
        });
        let anchor = pos2(
            p.x.clamp(at.x, at.x + size.x),
            if at.y > p.y { at.y } else { at.y + size.y },
        );
        painter.line_segment([anchor, *p], Stroke::new(1.5, pal.trip));
        badge(painter, at, text, pal.trip, Color32::WHITE);
    }
}

/// Paints the tooltip of the sensor or actuator under the pointer, if any.
fn paint_tooltip(cv: &Canvas<'_>, geom: &Geometry, plant: &Plant, view: &View, ptr: Pos2) {
    let (painter, xf, pal, lamp_r, rect) = (cv.painter, &cv.xf, cv.pal, cv.lamp_r, cv.rect);
    let hit = geom
        .sensors
        .iter()
        .map(|s| (s.id.as_str(), s.lamp))
        .chain(geom.actuators.iter().map(|(id, p)| (id.as_str(), *p)))
        .find(|(_, w)| xf.p(*w).distance(ptr) <= lamp_r * 1.4);
    if let Some((id, _)) = hit {
        let text = tooltip_text(plant, view, id, cv.values.get(id).copied());
        let galley = painter.layout(text, FontId::proportional(13.0), pal.text, 320.0);
        let r = Rect::from_min_size(ptr + vec2(14.0, 14.0), galley.size() + vec2(12.0, 10.0));
        let r = r.translate(vec2(
            (rect.right() - r.right()).min(0.0),
            (rect.bottom() - r.bottom()).min(0.0),
        ));
        painter.rect_filled(r, 4.0, pal.panel);
        painter.rect_stroke(
            r,
            4.0,
            Stroke::new(1.0, pal.equipment_edge),
            egui::StrokeKind::Middle,
        );
        painter.galley(r.min + vec2(6.0, 5.0), galley, pal.text);
    }
}

/// The dashed ring around a sensor's lamp that marks its reading as not taken as is
/// (suspect, estimated).
fn dashed_ring(p: egui::Pos2, lamp_r: f32, color: Color32) -> Vec<Shape> {
    Shape::dashed_line(
        &circle_points(p, lamp_r * 2.2),
        Stroke::new(2.5, color),
        5.0,
        4.0,
    )
}

/// 33 points around a circle (closed).
fn circle_points(c: Pos2, r: f32) -> Vec<Pos2> {
    (0..=32)
        .map(|i| {
            let a = i as f32 / 32.0 * std::f32::consts::TAU;
            c + vec2(r * a.cos(), r * a.sin())
        })
        .collect()
}

/// A formula in the paper's notation, wrapped between its terms (a constraint rewritten
/// with its estimates and suspect flags runs over several lines rather than widening
/// the panel that shows it).
pub fn overbar_formula(ui: &mut egui::Ui, text: &str, size: f32, color: Color32) {
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = 0.0;
        let terms: Vec<&str> = text.split(" + ").collect();
        for (k, term) in terms.iter().enumerate() {
            if k + 1 < terms.len() {
                overbar_label(ui, &format!("{term} + "), size, color);
            } else {
                overbar_label(ui, term, size, color);
            }
        }
    });
}

/// A label in the paper's notation: characters followed by U+0305 are drawn with a bar
/// above them (egui does not compose combining marks). Its accessible name is the text.
pub fn overbar_label(ui: &mut egui::Ui, text: &str, size: f32, color: Color32) -> egui::Response {
    let mut runs: Vec<(String, bool)> = Vec::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '\u{305}' {
            i += 1;
            continue;
        }
        let neg = chars.get(i + 1) == Some(&'\u{305}');
        match runs.last_mut() {
            Some((s, n)) if *n == neg => s.push(c),
            _ => runs.push((c.to_string(), neg)),
        }
        i += 1;
    }
    let font = FontId::proportional(size);
    let galleys: Vec<_> = runs
        .iter()
        .map(|(s, n)| {
            (
                ui.painter().layout_no_wrap(s.clone(), font.clone(), color),
                *n,
            )
        })
        .collect();
    let w: f32 = galleys.iter().map(|(g, _)| g.size().x).sum();
    let h = galleys.iter().map(|(g, _)| g.size().y).fold(size, f32::max) + 3.0;
    let (rect, resp) = ui.allocate_exact_size(vec2(w, h), Sense::hover());
    let label = text.to_string();
    resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Label, true, label.clone()));
    let mut x = rect.left();
    for (g, neg) in galleys {
        let gw = g.size().x;
        if neg {
            let y = rect.top() + 2.0;
            ui.painter().line_segment(
                [pos2(x + 1.0, y), pos2(x + gw - 1.0, y)],
                Stroke::new(1.5, color),
            );
        }
        ui.painter().galley(pos2(x, rect.top() + 3.0), g, color);
        x += gw;
    }
    resp
}

pub mod scene;

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn station() -> (Layout, Plant) {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station");
        (
            vigie_core::machine::Description::load(&dir)
                .unwrap()
                .layout()
                .unwrap(),
            Plant::load(&dir.join("plant.ron")).unwrap(),
        )
    }

    /// Every signal of the plant is drawn: the ones `layout.ron` places where it says,
    /// the others (the safety contactor and valve, the mirror contacts) in one row per
    /// element under the layout, apart from each other and from the equipment; a signal
    /// of no element goes to a row of its own.
    #[test]
    fn every_signal_is_drawn_and_the_unplaced_ones_sit_under_the_layout() {
        let (layout, mut plant) = station();
        let mut extra = plant.inputs[0].clone();
        extra.id = "PB1".into();
        extra.element = String::new();
        extra.address = None;
        plant.inputs.push(extra);
        let g = Geometry::new(&layout, &plant, 0);
        for s in plant.inputs.iter().chain(&plant.outputs) {
            assert!(g.element(&s.id).is_some(), "{} not drawn", s.id);
        }
        let rows: Vec<&str> = g.schematic.iter().map(|(e, _)| e.as_str()).collect();
        assert_eq!(rows, ["Safety", ""]);
        // The layout's lowest point: the conveyors' and the table's edges.
        let floor = layout
            .conveyors
            .iter()
            .flat_map(|c| [c.start.y, c.end.y].map(|y| y - c.width_mm / 2))
            .chain([layout.table.center.y - layout.table.half_length_mm])
            .min()
            .unwrap();
        #[allow(clippy::cast_precision_loss)]
        let floor = floor as f32;
        let strip: Vec<(&str, [f32; 2])> = plant
            .inputs
            .iter()
            .chain(&plant.outputs)
            .filter(|s| s.element == "Safety" || s.id == "PB1")
            .map(|s| (s.id.as_str(), g.element(&s.id).unwrap()))
            .collect();
        assert_eq!(strip.len(), 12, "{strip:?}");
        for (i, (a, pa)) in strip.iter().enumerate() {
            assert!(
                pa[1] < floor - 100.0,
                "{a} at {pa:?} is not under the layout"
            );
            assert!(
                pa[1] > g.bounds.0[1] && pa[0] < g.bounds.1[0],
                "{a} out of bounds"
            );
            for (b, pb) in &strip[i + 1..] {
                let d = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt();
                assert!(d >= STRIP_STEP * 0.75, "{a} and {b} overlap");
            }
        }
        // The paper's signals keep their places.
        let mut bare = plant.clone();
        bare.inputs
            .retain(|s| s.element != "Safety" && s.id != "PB1");
        bare.outputs.retain(|s| s.element != "Safety");
        let paper = Geometry::new(&layout, &bare, 0);
        for s in ["C4", "A0", "A4"] {
            assert_eq!(g.element(s), paper.element(s), "{s}");
        }
        assert!(paper.schematic.is_empty());
    }
}
