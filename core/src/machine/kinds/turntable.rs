//! A turntable: a roller surface on a rotary table with any number of positions, each
//! joining the rollers' ends to conveyors (a sorting station's turntable, a pallet
//! line's rotary transfer, an indexing corner).
//!
//! # Model
//!
//! The table turns to the first position whose `when` (over the applied outputs)
//! holds, at `speed` towards larger angles and `back_speed` towards smaller ones; each
//! move draws its speed within `± variation_ppm` from the table's own random stream.
//! With no position asked it stays where it is. Blocked by a fault, or with an output
//! its positions read unpowered (its safety valve released), it stays where it is and
//! keeps the move it was making. Within `dock_tolerance` of a position the table is
//! docked there: the position's `joins` hold (the guides accept the misalignment), and
//! items pass between its rollers and those conveyors. Between positions nothing is
//! joined, and an item overhanging an edge is sheared ([`crate::machine::items`]).
//!
//! The rollers are a surface of `length` (the conveyors' unit) driven by `rollers`,
//! positive towards their `End`; `beams` are presence beams along them from their
//! `Start`, and `sensors` windows on the angle. A fault that blocks the component
//! blocks the rotation; one that slows it slows the rollers.

use super::axis::{DriveDef, WindowDef};
use super::conveyor::{
    BeamDef, CompiledBeam, Drives, compile, compile_beams, input, micro, surface_beams,
};
use super::{ComponentFaults, StepCtx};
use crate::diag::Problem;
use crate::expr::{Dnf, eval_dnf};
use crate::machine::items::{END, Open, START, Surface};
use crate::machine::scene::{SceneDrive, SceneElement, SceneSensor, Shape};
use crate::symbols::{Space, Symbols};
use crate::synthetic::SplitMix64;
use serde::{Deserialize, Serialize};

/// An end of a surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum End {
    /// The start (a conveyor's entry; the rollers' end their negative drive leads to).
    Start,
    /// The end (a conveyor's exit end).
    End,
}

impl End {
    pub(crate) fn index(self) -> usize {
        match self {
            Self::Start => START,
            Self::End => END,
        }
    }
}

/// At a position, the rollers' end `end` meets conveyor `to` at its end `at`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JoinDef {
    /// The rollers' end.
    pub end: End,
    /// The conveyor's id.
    pub to: String,
    /// The conveyor's end.
    pub at: End,
}

/// A position of the table.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PositionDef {
    /// Its angle, in the unit.
    pub at: f64,
    /// The table turns there while this holds (over the applied outputs).
    pub when: String,
    /// What its rollers meet there.
    #[serde(default)]
    pub joins: Vec<JoinDef>,
}

/// A turntable's parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TurntableDef {
    /// The unit of the angle (`deg`).
    #[serde(default = "deg")]
    pub unit: String,
    /// The angle at the emulator's start.
    pub start: f64,
    /// Its positions.
    pub positions: Vec<PositionDef>,
    /// Units per second towards larger angles.
    pub speed: f64,
    /// Units per second towards smaller angles (`speed` when absent).
    #[serde(default)]
    pub back_speed: Option<f64>,
    /// Each move's speed varies within this many millionths of nominal.
    #[serde(default)]
    pub variation_ppm: u32,
    /// Docked within this much of a position.
    #[serde(default)]
    pub dock_tolerance: f64,
    /// Angle sensors.
    #[serde(default)]
    pub sensors: Vec<WindowDef>,
    /// The rollers' length, in the conveyors' unit.
    pub length: f64,
    /// The rollers' drives (speed positive towards their `End`).
    #[serde(default)]
    pub rollers: Vec<DriveDef>,
    /// Presence beams along the rollers, from their `Start`.
    #[serde(default)]
    pub beams: Vec<BeamDef>,
}

fn deg() -> String {
    "deg".to_string()
}

impl TurntableDef {
    pub(super) fn check(&self) -> Vec<String> {
        let mut out = Vec::new();
        let finite = |v: f64| v.is_finite() && v.abs() < 1e9;
        if self.positions.is_empty() {
            out.push("it has no position".to_string());
        }
        for p in &self.positions {
            if !finite(p.at) {
                out.push(format!("position at {} is not a finite angle", p.at));
            }
        }
        for (name, v) in [("speed", Some(self.speed)), ("back_speed", self.back_speed)] {
            if let Some(v) = v
                && (!finite(v) || v <= 0.0)
            {
                out.push(format!("{name} {v} must be positive"));
            }
        }
        if !finite(self.start) || !finite(self.dock_tolerance) || self.dock_tolerance < 0.0 {
            out.push("start and dock_tolerance must be finite (dock_tolerance >= 0)".into());
        }
        if !finite(self.length) || self.length <= 0.0 {
            out.push(format!(
                "its rollers' length {} must be positive",
                self.length
            ));
        }
        out.extend(super::check_beams(&self.beams, self.length, "rollers"));
        out.extend(super::check_variation(self.variation_ppm, "speed"));
        out
    }

    pub(super) fn signals(&self) -> Vec<(&str, Space)> {
        self.sensors
            .iter()
            .map(|s| s.signal.as_str())
            .chain(self.beams.iter().map(|b| b.signal.as_str()))
            .map(|s| (s, Space::Input))
            .collect()
    }

    pub(super) fn expressions(&self) -> Vec<&str> {
        self.positions
            .iter()
            .map(|p| p.when.as_str())
            .chain(self.rollers.iter().map(|d| d.when.as_str()))
            .collect()
    }

    /// The conveyors its positions join, by id.
    pub(crate) fn joined(&self) -> impl Iterator<Item = &str> {
        self.positions
            .iter()
            .flat_map(|p| p.joins.iter().map(|j| j.to.as_str()))
    }
}

/// A turntable's live state.
#[derive(Clone, Debug)]
pub struct Turntable {
    unit: String,
    /// Positions: angle (millionths), condition, the outputs it reads.
    positions: Vec<(i64, Dnf, Vec<String>)>,
    /// Per position, the plant outputs (by index) its condition reads.
    reads: Vec<Vec<usize>>,
    speed: i64,
    back_speed: i64,
    variation_ppm: i64,
    tolerance: i64,
    windows: Vec<(usize, String, i64, i64)>,
    rollers: Drives,
    length: i64,
    beams: Vec<CompiledBeam>,
    rng: SplitMix64,
    angle: i64,
    rot_dir: i64,
    rot_speed: i64,
    moving: bool,
    /// The position it turns to, while it turns.
    target: Option<i64>,
    /// The position its outputs asked at the last fresh frame (`None`: not read yet).
    asked: Option<Option<usize>>,
    /// The position it stands at, by index.
    pub(crate) docked: Option<usize>,
}

impl Turntable {
    pub(super) fn new(id: &str, def: &TurntableDef, symbols: &Symbols) -> Result<Self, Problem> {
        let mut positions = Vec::new();
        let mut reads = Vec::new();
        for p in &def.positions {
            let (dnf, outputs) = compile(id, "position", &p.when, symbols)?;
            reads.push(
                outputs
                    .iter()
                    .filter_map(|o| match symbols.lookup(o) {
                        Some((Space::Output, i)) => Some(i as usize),
                        _ => None,
                    })
                    .collect(),
            );
            positions.push((micro(p.at), dnf, outputs));
        }
        let mut windows = Vec::new();
        for w in &def.sensors {
            windows.push((
                input(id, &w.signal, symbols)?,
                w.signal.clone(),
                micro(w.from),
                micro(w.to),
            ));
        }
        let beams = compile_beams(id, &def.beams, symbols)?;
        let speed = micro(def.speed / 1000.0);
        let mut t = Self {
            unit: def.unit.clone(),
            positions,
            reads,
            speed,
            back_speed: def.back_speed.map_or(speed, |b| micro(b / 1000.0)),
            variation_ppm: i64::from(def.variation_ppm),
            tolerance: micro(def.dock_tolerance),
            windows,
            rollers: Drives::new(id, &def.rollers, 0, symbols)?,
            length: micro(def.length),
            beams,
            rng: SplitMix64::new(0),
            angle: micro(def.start),
            rot_dir: 0,
            rot_speed: speed,
            moving: false,
            target: None,
            asked: None,
            docked: None,
        };
        t.dock();
        Ok(t)
    }

    /// Seeds its own random stream (each turntable has one, so that its moves do not
    /// depend on what other components draw).
    pub(crate) fn seed(&mut self, seed: u64) {
        self.rng = SplitMix64::new(seed);
    }

    fn dock(&mut self) {
        self.docked = self
            .positions
            .iter()
            .position(|(at, _, _)| (self.angle - at).abs() <= self.tolerance);
    }

    /// One step: the rotation, then the rollers.
    pub(super) fn step(&mut self, ctx: &mut StepCtx<'_>, faults: ComponentFaults) {
        let asked = match self.asked {
            Some(a) if !ctx.fresh => a,
            _ => {
                let a = self
                    .positions
                    .iter()
                    .position(|(_, dnf, _)| eval_dnf(dnf, ctx.frame));
                self.asked = Some(a);
                a
            }
        };
        let target = asked.map(|p| (self.positions[p].0, &self.reads[p]));
        let old = self.angle;
        match target {
            Some((at, outputs)) if at != self.angle => {
                let dir = (at - self.angle).signum();
                let unpowered = outputs.iter().any(|&o| ctx.unpowered.get(o));
                let stuck = faults.stuck_at == Some(self.angle);
                if !(faults.blocked || unpowered || stuck) {
                    if dir != self.rot_dir {
                        let base = if dir > 0 { self.speed } else { self.back_speed };
                        let v = self.variation_ppm;
                        let r = self.rng.below(2 * v as u64 + 1) as i64 - v;
                        self.rot_speed = (base * (1_000_000 + r) / 1_000_000).max(1);
                        self.rot_dir = dir;
                    }
                    let d = self.rot_speed * ctx.dt as i64;
                    self.angle = if dir > 0 {
                        (self.angle + d).min(at)
                    } else {
                        (self.angle - d).max(at)
                    };
                }
            }
            _ => self.rot_dir = 0,
        }
        self.moving = self.angle != old;
        self.target = target.map(|(at, _)| at).filter(|_| self.moving);
        self.dock();
        let rollers = ComponentFaults {
            blocked: false,
            stuck_at: None,
            ..faults
        };
        self.rollers.step(ctx, rollers);
    }

    /// Its rollers' speed, millionths per ms.
    pub(crate) fn roller_speed(&self) -> i64 {
        self.rollers.speed
    }

    /// The surface of its rollers, as the plant's items see it.
    pub(crate) fn surface(&self, component: usize, id: &str, name: &str) -> Surface {
        Surface {
            component,
            id: id.to_string(),
            name: name.to_string(),
            len: self.length,
            beams: surface_beams(&self.beams),
            open: [Open::Drop, Open::Drop],
            fixed: [None, None],
            table_side: [true, true],
            accumulating: true,
            actuators: self.rollers.outputs(),
            rotation: Some({
                let mut v: Vec<String> = self
                    .positions
                    .iter()
                    .flat_map(|(_, _, o)| o.iter().cloned())
                    .collect();
                v.sort();
                v.dedup();
                v
            }),
        }
    }

    /// The table does not turn (its rollers may run).
    pub(super) fn steady(&self) -> bool {
        !self.moving
    }

    /// How many of the next `max` steps of `dt` ms it may take at once on the same
    /// outputs: any while it stands, while it turns those before it reaches its
    /// position (it turns on, not docking).
    pub(super) fn quiet_steps(&self, dt: u64, max: u64) -> u64 {
        match (self.moving, self.target) {
            (false, _) => max,
            (true, Some(at)) => {
                let d = (self.rot_speed * dt as i64).max(1);
                let steps = ((at - self.angle).abs() + d - 1) / d;
                max.min(u64::try_from(steps - 1).unwrap_or(0))
            }
            (true, None) => 0,
        }
    }

    /// Takes `k` quiet steps of `dt` ms at once ([`Self::quiet_steps`]).
    pub(super) fn advance(&mut self, dt: u64, k: u64) {
        if self.moving {
            self.angle += self.rot_dir * self.rot_speed * (dt * k) as i64;
            self.dock();
        }
    }

    pub(super) fn idle(&self) -> bool {
        !self.moving && self.rollers.idle()
    }

    pub(super) fn sense(&self, sensors: &mut crate::bits::Bits) {
        for &(i, _, from, to) in &self.windows {
            sensors.set(i, (from..=to).contains(&self.angle));
        }
    }

    /// The angle, in its unit.
    pub(super) fn position(&self) -> f64 {
        self.angle as f64 / 1e6
    }

    pub(super) fn set_position(&mut self, angle: f64) {
        self.angle = micro(angle);
        self.dock();
    }

    pub(super) fn scene(&self, id: &str, name: &str) -> SceneElement {
        let f = |v: i64| v as f64 / 1e6;
        SceneElement {
            id: id.to_string(),
            name: name.to_string(),
            shape: Shape::Turntable {
                unit: self.unit.clone(),
                angle: f(self.angle),
                positions: self.positions.iter().map(|(at, _, _)| f(*at)).collect(),
                docked: self.docked,
                sensors: self
                    .windows
                    .iter()
                    .map(|(_, s, from, to)| SceneSensor {
                        signal: s.clone(),
                        from: f(*from),
                        to: f(*to),
                    })
                    .collect(),
                turns: self
                    .positions
                    .iter()
                    .map(|(at, _, outputs)| SceneDrive {
                        when: outputs.join(" . "),
                        speed: if *at >= self.angle {
                            self.speed as f64 * 1000.0 / 1e6
                        } else {
                            -(self.back_speed as f64) * 1000.0 / 1e6
                        },
                        sensor: None,
                    })
                    .collect(),
                length: f(self.length),
                direction: self.rollers.speed.signum() as i8,
                // The plant fills them from its items.
                items: Vec::new(),
                beams: self
                    .beams
                    .iter()
                    .map(|(_, s, at, _)| SceneSensor {
                        signal: s.clone(),
                        from: f(*at),
                        to: f(*at),
                    })
                    .collect(),
                rollers: self.rollers.scene(),
            },
        }
    }
}
