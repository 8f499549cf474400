//! A conveyor: a belt carrying items, driven by outputs and read by presence beams.
//!
//! It covers a belt or roller conveyor in one or two directions (a pallet line, a
//! workstation's transfer, an exit slide with a motor), with a feeder at its entry (a
//! pusher, a magazine, a stack feeder: `feed`), something that takes the item waiting
//! at its exit end (a robot, a gripper, an operator: `take`) and what its exit end
//! leads to (`exit`: an end stop, a drop, a sink that counts deliveries, or another
//! conveyor).
//!
//! # Model
//!
//! The belt moves at the speed of its active drives (as an axis's drives: the fastest
//! of one direction; both directions at once hold it and are a hazard). Each item has
//! a class (its length and its tags: a height, a colour, a material, anything a sensor
//! may discriminate). The items themselves are the plant's, shared by every conveyor
//! and turntable ([`crate::machine::items`]): they move with the belt, queue (an
//! accumulating conveyor) or collide (`accumulating: false`), overhang the joint onto
//! the next conveyor (`To(id)`) and pass onto it when their centre crosses it. At the
//! exit end an item stops (`Stop`, an end stop or a stopper), falls off (`Drop`: a
//! hazard, once its middle passes the end) or leaves into a sink (`Sink`: delivered).
//! Driven backwards, items stop at the entry (unless a turntable joins it there).
//!
//! On each rise of `feed.when` (an expression over the plant's signals: the pusher's
//! output, or its extended sensor) the next item of `feed.items` (in turn) is placed at
//! the entry; an entry still occupied is a collision (a hazard) and nothing is placed.
//! A `source` places arrivals on its own schedule, each waiting until the entry is free.
//! On each rise of `take`, the item at the exit end (its front within half its length
//! of the end) is taken away (counted, as the robot carries it off); a taker whose
//! items another belt's feeder places (`feed.from`, a gripper) holds one at a time: a
//! rise while it holds one takes nothing (it regrips the one it holds). A beam at `at` is
//! on while an item covers it (with `sees`, only items of a class with that tag: a
//! high beam sees tall items only); a motion sensor (`motion`) is on while the belt
//! really moves (not blocked by a fault, not stopped).
//!
//! Lengths are kept in millionths of the unit and speeds in millionths per ms: exact
//! integer arithmetic, deterministic for a seed.

use super::axis::DriveDef;
use super::{ComponentFaults, StepCtx};
use crate::diag::{Problem, codes};
use crate::expr::{Dnf, eval_dnf, parse_str, simplify};
use crate::machine::HazardKind;
use crate::machine::items::{Class, Surface};
use crate::machine::scene::{SceneDrive, SceneElement, SceneSensor, Shape};
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};

const MICRO: f64 = 1e6;

/// A class of items.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ItemClass {
    /// Its name (`pallet`, `red_tall`).
    pub class: String,
    /// Its length along the belt, in the unit.
    pub length: f64,
    /// What sensors may discriminate (`tall`, `metal`, `red`).
    #[serde(default)]
    pub tags: Vec<String>,
    /// Its width across the belt, mm, for a top view (its length when absent).
    #[serde(default)]
    pub width: Option<f64>,
    /// Its height, mm, for the record (a high beam's class is its tag).
    #[serde(default)]
    pub height: Option<f64>,
}

impl ItemClass {
    /// What is wrong with its width or height, if anything.
    fn check_dims(&self) -> Option<String> {
        [("width", self.width), ("height", self.height)]
            .into_iter()
            .find_map(|(what, v)| {
                v.filter(|v| !v.is_finite() || *v <= 0.0 || *v > 1e9)
                    .map(|v| {
                        format!(
                            "item class `{}` has {what} {v}: positive, within 1e9",
                            self.class
                        )
                    })
            })
    }
}

/// The feeder at the entry.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedDef {
    /// On each rise of this expression, an item is placed at the entry.
    pub when: String,
    /// The items it places, in turn.
    #[serde(default)]
    pub items: Vec<ItemClass>,
    /// The conveyor whose taker carries the item placed (a gripper that picked it off
    /// that belt's end puts it here, class and number kept): on a rise, the item it
    /// took first and has not placed yet, or nothing when it holds none. The items that
    /// conveyor's taker picks are then carried, not counted out.
    #[serde(default)]
    pub from: Option<String>,
}

/// A presence beam across the belt.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamDef {
    /// The plant input it writes.
    pub signal: String,
    /// Its place from the entry, in the unit.
    pub at: f64,
    /// Only items whose class has this tag.
    #[serde(default)]
    pub sees: Option<String>,
}

/// What the exit end leads to.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Exit {
    /// An end stop: items wait there.
    #[default]
    Stop,
    /// Nothing: an item falls off (a hazard).
    Drop,
    /// A sink (a slide, a bin): an item leaves, delivered.
    Sink,
    /// The entry of another conveyor, by id.
    To(String),
}

/// A conveyor's parameters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConveyorDef {
    /// The unit of lengths and speeds, for display.
    #[serde(default = "mm")]
    pub unit: String,
    /// The belt's length, entry to exit end.
    pub length: f64,
    /// The drives: speed positive towards the exit end.
    pub drives: Vec<DriveDef>,
    /// The presence beams.
    #[serde(default)]
    pub sensors: Vec<BeamDef>,
    /// A sensor on while the belt really moves.
    #[serde(default)]
    pub motion: Option<String>,
    /// The feeder at the entry.
    #[serde(default)]
    pub feed: Option<FeedDef>,
    /// On each rise of this expression, the item at the exit end is taken away.
    #[serde(default)]
    pub take: Option<String>,
    /// What the exit end leads to.
    #[serde(default)]
    pub exit: Exit,
    /// Each run's speed varies within this many millionths of nominal.
    #[serde(default)]
    pub variation_ppm: u32,
    /// Items queue against each other without harm (pallets on an accumulating
    /// conveyor). When false, a driven item held by another not moving away as fast
    /// is a collision (boxes on a belt).
    #[serde(default = "yes")]
    pub accumulating: bool,
    /// Items arriving at the entry on their own (an upstream line, an operator): the
    /// classes, and when.
    #[serde(default)]
    pub source: Option<SourceDef>,
}

/// Arrivals at a conveyor's entry: each waits until the entry is free.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SourceDef {
    /// The classes that arrive.
    pub items: Vec<ItemClass>,
    /// When (a scenario may replace it).
    pub arrivals: crate::machine::items::ArrivalsDef,
}

fn yes() -> bool {
    true
}

fn mm() -> String {
    "mm".to_string()
}

impl ConveyorDef {
    pub(super) fn check(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !self.length.is_finite() || self.length <= 0.0 || self.length > 1e9 {
            out.push(format!("its length {} must be positive", self.length));
        }
        for d in &self.drives {
            if !d.speed.is_finite() || d.speed == 0.0 || d.speed.abs() > 1e6 {
                out.push(format!(
                    "drive `{}` has speed {}: from -1e6 to 1e6 units/s, not 0",
                    d.when, d.speed
                ));
            }
        }
        out.extend(super::check_beams(&self.sensors, self.length, "belt"));
        if let Some(f) = &self.feed {
            if f.items.is_empty() && f.from.is_none() {
                out.push(format!(
                    "feed `{}` places no item class and carries from no conveyor (`from`)",
                    f.when
                ));
            }
            for c in &f.items {
                if !c.length.is_finite() || c.length <= 0.0 || c.length > self.length {
                    out.push(format!(
                        "item class `{}` has length {}: positive and at most the belt's {}",
                        c.class, c.length, self.length
                    ));
                }
            }
            out.extend(f.items.iter().filter_map(ItemClass::check_dims));
        }
        if let Some(src) = &self.source {
            if src.items.is_empty() {
                out.push("its source has no item class".to_string());
            }
            for c in &src.items {
                if !c.length.is_finite() || c.length <= 0.0 || c.length > self.length {
                    out.push(format!(
                        "source class `{}` has length {}: positive and at most the belt's {}",
                        c.class, c.length, self.length
                    ));
                }
            }
            out.extend(src.items.iter().filter_map(ItemClass::check_dims));
            if src.arrivals.period_ms == 0 {
                out.push("its source's period_ms must be at least 1".to_string());
            }
        }
        out.extend(super::check_variation(self.variation_ppm, "speed"));
        out
    }

    pub(super) fn signals(&self) -> Vec<(&str, Space)> {
        self.sensors
            .iter()
            .map(|s| s.signal.as_str())
            .chain(self.motion.as_deref())
            .map(|s| (s, Space::Input))
            .collect()
    }

    pub(super) fn expressions(&self) -> Vec<&str> {
        self.drives
            .iter()
            .map(|d| d.when.as_str())
            .chain(self.feed.as_ref().map(|f| f.when.as_str()))
            .chain(self.take.as_deref())
            .collect()
    }

    /// The conveyor whose taken items its feeder places, if any.
    pub(crate) fn carries_from(&self) -> Option<&str> {
        self.feed.as_ref().and_then(|f| f.from.as_deref())
    }

    /// Where an item on the belt still occupies the entry (the feeder would place the
    /// next one onto it) without any entry beam seeing it: for each item length `e`
    /// that may lie on the belt and each length `n` the feeder may place, the rear
    /// positions in `[0, n]` (the emulator's collision: a rear at or before the new
    /// item's length) that no beam reading every class covers (`[at - e, at]`). The
    /// first such stretch of rear positions, as (from, to, e, n), or `None` when the beams see every
    /// item a new one would hit (a beam at the items' length, or several). No feeder,
    /// no gap.
    pub(crate) fn unseen_entry(&self, lengths: &[f64]) -> Option<(f64, f64, f64, f64)> {
        let feed = self.feed.as_ref()?;
        let placed: Vec<f64> = if feed.items.is_empty() {
            lengths.to_vec()
        } else {
            feed.items.iter().map(|c| c.length).collect()
        };
        for &e in lengths {
            let mut covers: Vec<(f64, f64)> = self
                .sensors
                .iter()
                .filter(|b| b.sees.is_none())
                .map(|b| (b.at - e, b.at))
                .collect();
            covers.sort_by(|a, b| a.0.total_cmp(&b.0));
            for &n in &placed {
                // Sweep [0, n]: `seen` is the end of the covered prefix [0, seen].
                let mut seen: Option<f64> = None;
                let mut next = n;
                for &(lo, hi) in &covers {
                    if lo > seen.unwrap_or(0.0) {
                        next = next.min(lo);
                        break;
                    }
                    seen = Some(seen.map_or(hi, |s| s.max(hi)));
                }
                match seen {
                    Some(s) if s >= n => {}
                    s => return Some((s.unwrap_or(0.0), next, e, n)),
                }
            }
        }
        None
    }

    /// The conveyor its exit leads to, if any.
    pub(crate) fn target(&self) -> Option<&str> {
        match &self.exit {
            Exit::To(t) => Some(t),
            _ => None,
        }
    }
}

#[derive(Clone, Debug)]
struct Drive {
    when: String,
    dnf: Dnf,
    speed: i64,
    outputs: Vec<String>,
}

/// A compiled expression watched for its rises.
#[derive(Clone, Debug)]
pub(crate) struct Rise {
    dnf: Dnf,
    pub(crate) outputs: Vec<String>,
    last: bool,
}

impl Rise {
    pub(crate) fn new(dnf: Dnf, outputs: Vec<String>) -> Self {
        Self {
            dnf,
            outputs,
            last: false,
        }
    }

    pub(crate) fn rose(&mut self, frame: &crate::frame::Frame) -> bool {
        let now = eval_dnf(&self.dnf, frame);
        let rose = now && !self.last;
        self.last = now;
        rose
    }
}

/// The drives of a surface (a belt, a turntable's rollers): the fastest active drive
/// of one direction moves it; both directions at once hold it and are a hazard.
#[derive(Clone, Debug)]
pub(crate) struct Drives {
    drives: Vec<Drive>,
    variation_ppm: i64,
    dir: i64,
    factor_ppm: i64,
    /// Millionths per ms, signed, faults applied.
    pub(crate) speed: i64,
    opposed: bool,
    /// What the drives asked at the last fresh frame (speed, both directions).
    asked: Option<(i64, bool)>,
    /// The faults of the last step (blocked, speed percent): with the same asked
    /// speed, the same speed.
    last_faults: Option<(bool, u8)>,
}

impl Drives {
    pub(crate) fn new(
        id: &str,
        defs: &[DriveDef],
        variation_ppm: u32,
        symbols: &Symbols,
    ) -> Result<Self, Problem> {
        let mut drives = Vec::new();
        for d in defs {
            let (dnf, outputs) = compile(id, "drive", &d.when, symbols)?;
            drives.push(Drive {
                when: d.when.clone(),
                dnf,
                speed: micro(d.speed / 1000.0),
                outputs,
            });
        }
        Ok(Self {
            drives,
            variation_ppm: i64::from(variation_ppm),
            dir: 0,
            factor_ppm: 1_000_000,
            speed: 0,
            opposed: false,
            asked: None,
            last_faults: None,
        })
    }

    /// The speed asked (the fastest active drive of one direction) and whether both
    /// directions are asked at once (the speed is then 0).
    fn asked(&self, frame: &crate::frame::Frame) -> (i64, bool) {
        let mut best = 0i64;
        let (mut up, mut down) = (false, false);
        for d in &self.drives {
            if eval_dnf(&d.dnf, frame) {
                up |= d.speed > 0;
                down |= d.speed < 0;
                if d.speed.abs() > best.abs() {
                    best = d.speed;
                }
            }
        }
        if up && down { (0, true) } else { (best, false) }
    }

    /// The outputs of the active drives, sorted (a hazard's report).
    fn active_outputs(&self, frame: &crate::frame::Frame) -> Vec<String> {
        let mut outputs: Vec<String> = self
            .drives
            .iter()
            .filter(|d| eval_dnf(&d.dnf, frame))
            .flat_map(|d| d.outputs.iter().cloned())
            .collect();
        outputs.sort();
        outputs.dedup();
        outputs
    }

    /// One step: the speed asked, its variation for a new run, the faults.
    pub(crate) fn step(&mut self, ctx: &mut StepCtx<'_>, faults: ComponentFaults) {
        let same_faults = self.last_faults == Some((faults.blocked, faults.speed_percent));
        if !ctx.fresh && same_faults && self.asked.is_some() {
            // The same outputs and faults: the same speed as the last step.
            return;
        }
        self.last_faults = Some((faults.blocked, faults.speed_percent));
        let (speed, opposed) = match self.asked {
            Some(a) if !ctx.fresh => a,
            _ => {
                let a = self.asked(ctx.frame);
                self.asked = Some(a);
                a
            }
        };
        if opposed && !self.opposed {
            let outputs = self.active_outputs(ctx.frame);
            ctx.hazards.push((HazardKind::OpposedDrives, outputs));
        }
        self.opposed = opposed;
        let dir = speed.signum();
        if dir != self.dir {
            self.dir = dir;
            self.factor_ppm = super::run_factor(dir, self.variation_ppm, ctx.rng);
        }
        self.speed = if faults.blocked {
            0
        } else {
            speed * self.factor_ppm / 1_000_000 * i64::from(faults.speed_percent) / 100
        };
    }

    /// Every output its drives read, sorted.
    pub(crate) fn outputs(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .drives
            .iter()
            .flat_map(|d| d.outputs.iter().cloned())
            .collect();
        v.sort();
        v.dedup();
        v
    }

    pub(crate) fn idle(&self) -> bool {
        self.dir == 0 && !self.opposed
    }

    pub(crate) fn scene(&self) -> Vec<SceneDrive> {
        self.drives
            .iter()
            .map(|d| SceneDrive {
                when: d.when.clone(),
                speed: d.speed as f64 * 1000.0 / MICRO,
                sensor: None,
            })
            .collect()
    }
}

/// A conveyor's live state: its drives and what its feeder and taker ask. Its items
/// are the plant's ([`crate::machine::items`]).
#[derive(Clone, Debug)]
pub struct Conveyor {
    unit: String,
    length: i64,
    drives: Drives,
    beams: Vec<CompiledBeam>,
    motion: Option<usize>,
    motion_id: Option<String>,
    feed_when: Option<String>,
    feed: Option<(Rise, Vec<ItemClass>)>,
    next_class: usize,
    take: Option<Rise>,
    /// The surface whose taken items its feeder places (`feed.from`), by surface.
    pub(crate) feed_from: Option<usize>,
    exit: Exit,
    accumulating: bool,
    moving: bool,
    /// What this step asks of the items.
    pub(crate) requests: crate::machine::items::Requests,
}

pub(crate) fn micro(v: f64) -> i64 {
    (v * MICRO).round() as i64
}

pub(crate) fn compile(
    id: &str,
    what: &str,
    text: &str,
    symbols: &Symbols,
) -> Result<(Dnf, Vec<String>), Problem> {
    let bad = |m: String| Problem::error(codes::COMPONENTS_EXPRESSION.id, m, None);
    let expr =
        parse_str(text).map_err(|e| bad(format!("`{id}`: {what} `{text}`: {}", e.message)))?;
    let outputs = expr
        .leaves()
        .into_iter()
        .map(|(n, _, _)| n.to_string())
        .collect();
    let dnf = expr
        .to_dnf(symbols)
        .map_err(|e| bad(format!("`{id}`: {what} `{text}`: {}", e.message)))?;
    Ok((simplify(&dnf), outputs))
}

/// A beam compiled: its plant input, its signal, its place (millionths), its tag.
pub(crate) type CompiledBeam = (usize, String, i64, Option<String>);

/// The beams of component `id`, against the plant's inputs.
pub(crate) fn compile_beams(
    id: &str,
    defs: &[BeamDef],
    symbols: &Symbols,
) -> Result<Vec<CompiledBeam>, Problem> {
    defs.iter()
        .map(|b| {
            Ok((
                input(id, &b.signal, symbols)?,
                b.signal.clone(),
                micro(b.at),
                b.sees.clone(),
            ))
        })
        .collect()
}

/// The beams as the plant's items read them.
pub(crate) fn surface_beams(beams: &[CompiledBeam]) -> Vec<crate::machine::items::Beam> {
    beams
        .iter()
        .map(|(i, _, at, sees)| crate::machine::items::Beam {
            input: *i,
            at: *at,
            sees: sees.clone(),
        })
        .collect()
}

/// A plant input by name, or the error naming the component.
pub(crate) fn input(id: &str, s: &str, symbols: &Symbols) -> Result<usize, Problem> {
    match symbols.lookup(s) {
        Some((Space::Input, i)) => Ok(i as usize),
        _ => Err(Problem::error(
            codes::COMPONENTS_UNKNOWN_SIGNAL.id,
            format!("`{id}` names sensor `{s}`, not a plant input"),
            None,
        )),
    }
}

impl Conveyor {
    pub(super) fn new(id: &str, def: &ConveyorDef, symbols: &Symbols) -> Result<Self, Problem> {
        let drives = Drives::new(id, &def.drives, def.variation_ppm, symbols)?;
        let beams = compile_beams(id, &def.sensors, symbols)?;
        let motion = def
            .motion
            .as_deref()
            .map(|m| input(id, m, symbols))
            .transpose()?;
        let feed = match &def.feed {
            Some(f) => {
                let (dnf, outputs) = compile(id, "feed", &f.when, symbols)?;
                Some((Rise::new(dnf, outputs), f.items.clone()))
            }
            None => None,
        };
        let take = match &def.take {
            Some(t) => {
                let (dnf, outputs) = compile(id, "take", t, symbols)?;
                Some(Rise::new(dnf, outputs))
            }
            None => None,
        };
        Ok(Self {
            unit: def.unit.clone(),
            length: micro(def.length),
            drives,
            beams,
            motion,
            motion_id: def.motion.clone(),
            feed_when: def.feed.as_ref().map(|f| f.when.clone()),
            feed,
            next_class: 0,
            take,
            feed_from: None,
            exit: def.exit.clone(),
            accumulating: def.accumulating,
            moving: false,
            requests: crate::machine::items::Requests::default(),
        })
    }

    /// One step: the belt's speed, and the feeder's and the taker's rises.
    pub(super) fn step(&mut self, ctx: &mut StepCtx<'_>, faults: ComponentFaults) {
        self.drives.step(ctx, faults);
        let mut req = crate::machine::items::Requests {
            velocity: self.drives.speed * ctx.dt as i64,
            ..Default::default()
        };
        if let Some((rise, classes)) = self.feed.as_mut()
            && rise.rose(ctx.frame)
        {
            match self.feed_from {
                Some(src) => req.feed_carried = Some(src),
                None if !classes.is_empty() => {
                    req.feed = Some(self.next_class % classes.len());
                    self.next_class += 1;
                }
                None => {}
            }
        }
        if let Some(rise) = self.take.as_mut() {
            req.take = rise.rose(ctx.frame);
        }
        self.moving = req.velocity != 0;
        self.requests = req;
    }

    /// The surface its items lie on, as the plant's items see it.
    pub(crate) fn surface(&self, component: usize, id: &str, name: &str) -> Surface {
        use crate::machine::items::Open;
        Surface {
            component,
            id: id.to_string(),
            name: name.to_string(),
            len: self.length,
            beams: surface_beams(&self.beams),
            open: [
                Open::Stop,
                match self.exit {
                    Exit::Stop => Open::Stop,
                    Exit::Sink => Open::Sink,
                    Exit::Drop | Exit::To(_) => Open::Drop,
                },
            ],
            fixed: [None, None],
            table_side: [false, false],
            accumulating: self.accumulating,
            actuators: self.drives.outputs(),
            rotation: None,
        }
    }

    /// The outputs its feeder's condition reads.
    pub(crate) fn feed_outputs(&self) -> Vec<String> {
        self.feed
            .as_ref()
            .map(|(r, _)| r.outputs.clone())
            .unwrap_or_default()
    }

    /// The classes its feeder places, as the items place them.
    pub(crate) fn feed_classes(&self) -> Vec<Class> {
        self.feed
            .as_ref()
            .map(|(_, c)| c.iter().map(class).collect())
            .unwrap_or_default()
    }

    /// At rest: the feeder and the taker act on rises of their expressions, which
    /// change only with the outputs or a sensor another component moves.
    pub(super) fn idle(&self) -> bool {
        self.drives.idle()
    }

    pub(super) fn sense(&self, sensors: &mut crate::bits::Bits) {
        if let Some(i) = self.motion {
            sensors.set(i, self.moving);
        }
    }

    pub(super) fn scene(&self, id: &str, name: &str) -> SceneElement {
        let f = |v: i64| v as f64 / MICRO;
        SceneElement {
            id: id.to_string(),
            name: name.to_string(),
            shape: Shape::Conveyor {
                unit: self.unit.clone(),
                length: f(self.length),
                direction: if self.moving {
                    self.drives.speed.signum() as i8
                } else {
                    0
                },
                // The plant fills them from its items.
                items: Vec::new(),
                sensors: self
                    .beams
                    .iter()
                    .map(|(_, s, at, _)| SceneSensor {
                        signal: s.clone(),
                        from: f(*at),
                        to: f(*at),
                    })
                    .collect(),
                drives: self.drives.scene(),
                exit: match &self.exit {
                    Exit::Stop => "stop".into(),
                    Exit::Drop => "drop".into(),
                    Exit::Sink => "sink".into(),
                    Exit::To(t) => t.clone(),
                },
                motion: self.motion_id.clone(),
                feed: self.feed_when.clone(),
            },
        }
    }
}

/// An item class as the plant's items place it.
pub(crate) fn class(c: &ItemClass) -> Class {
    Class {
        class: c.class.clone(),
        tags: c.tags.clone(),
        length: micro(c.length),
    }
}
