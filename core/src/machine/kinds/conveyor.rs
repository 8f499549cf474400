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
//! may discriminate) and lies on `[rear, rear + length]` from the entry. Items move with
//! the belt and queue: an item stops against the one ahead of it (an accumulating
//! conveyor). At the exit end an item stops (`Stop`, an end stop or a stopper), falls
//! off (`Drop`: a hazard, once its middle passes the end), leaves into a sink (`Sink`:
//! delivered), or passes to the entry of another conveyor (`To(id)`: when that entry is
//! free; else it waits at the end). Driven backwards, items stop at the entry.
//!
//! On each rise of `feed.when` (an expression over the plant's signals: the pusher's
//! output, or its extended sensor) the next item of `feed.items` (in turn) is placed at
//! the entry; an entry still occupied is a collision (a hazard) and nothing is placed.
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
use crate::machine::scene::{SceneDrive, SceneElement, SceneItem, SceneSensor, Shape};
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
        for s in &self.sensors {
            if !s.at.is_finite() || s.at < 0.0 || s.at > self.length {
                out.push(format!(
                    "beam `{}` at {} is off the belt [0, {}]",
                    s.signal, s.at, self.length
                ));
            }
        }
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
        }
        if self.variation_ppm >= 500_000 {
            out.push(format!(
                "variation_ppm {} is 50 % or more of the speed",
                self.variation_ppm
            ));
        }
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

/// An item on a belt.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Item {
    /// Its number, from 1, in the order the plant's feeders placed them.
    pub id: u32,
    /// Its class.
    pub class: String,
    /// Its tags.
    pub tags: Vec<String>,
    /// Its length, millionths.
    pub length: i64,
    /// Its rear end from the entry, millionths.
    pub rear: i64,
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
struct Rise {
    dnf: Dnf,
    outputs: Vec<String>,
    last: bool,
}

impl Rise {
    fn rose(&mut self, frame: &crate::frame::Frame) -> bool {
        let now = eval_dnf(&self.dnf, frame);
        let rose = now && !self.last;
        self.last = now;
        rose
    }
}

/// A conveyor's live state.
#[derive(Clone, Debug)]
pub struct Conveyor {
    unit: String,
    length: i64,
    drives: Vec<Drive>,
    beams: Vec<(usize, String, i64, Option<String>)>,
    motion: Option<usize>,
    motion_id: Option<String>,
    feed_when: Option<String>,
    feed: Option<(Rise, Vec<ItemClass>)>,
    next_class: usize,
    take: Option<Rise>,
    /// The component whose taken items its feeder places (`feed.from`), by index.
    feed_from: Option<usize>,
    /// Some conveyor's feeder places what its taker picks: the items are carried.
    carried: bool,
    exit: Exit,
    variation_ppm: i64,
    /// The items, by rear end (the entry first).
    items: Vec<Item>,
    dir: i64,
    factor_ppm: i64,
    moving: bool,
    opposed: bool,
    blocked: bool,
    /// Items delivered into its sink, taken at its exit end, dropped.
    pub(crate) delivered: u32,
    pub(crate) taken: u32,
}

fn micro(v: f64) -> i64 {
    (v * MICRO).round() as i64
}

fn compile(
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

impl Conveyor {
    pub(super) fn new(id: &str, def: &ConveyorDef, symbols: &Symbols) -> Result<Self, Problem> {
        let mut drives = Vec::new();
        for d in &def.drives {
            let (dnf, outputs) = compile(id, "drive", &d.when, symbols)?;
            drives.push(Drive {
                when: d.when.clone(),
                dnf,
                speed: micro(d.speed / 1000.0),
                outputs,
            });
        }
        let input = |s: &str| match symbols.lookup(s) {
            Some((Space::Input, i)) => Ok(i as usize),
            _ => Err(Problem::error(
                codes::COMPONENTS_UNKNOWN_SIGNAL.id,
                format!("`{id}` names sensor `{s}`, not a plant input"),
                None,
            )),
        };
        let mut beams = Vec::new();
        for b in &def.sensors {
            beams.push((
                input(&b.signal)?,
                b.signal.clone(),
                micro(b.at),
                b.sees.clone(),
            ));
        }
        let motion = def.motion.as_deref().map(input).transpose()?;
        let feed = match &def.feed {
            Some(f) => {
                let (dnf, outputs) = compile(id, "feed", &f.when, symbols)?;
                Some((
                    Rise {
                        dnf,
                        outputs,
                        last: false,
                    },
                    f.items.clone(),
                ))
            }
            None => None,
        };
        let take = match &def.take {
            Some(t) => {
                let (dnf, outputs) = compile(id, "take", t, symbols)?;
                Some(Rise {
                    dnf,
                    outputs,
                    last: false,
                })
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
            carried: false,
            exit: def.exit.clone(),
            variation_ppm: i64::from(def.variation_ppm),
            items: Vec::new(),
            dir: 0,
            factor_ppm: 1_000_000,
            moving: false,
            opposed: false,
            blocked: false,
            delivered: 0,
            taken: 0,
        })
    }

    fn asked(&self, frame: &crate::frame::Frame) -> (i64, bool, Vec<String>) {
        let mut best = 0i64;
        let (mut up, mut down) = (false, false);
        let mut outputs = Vec::new();
        for d in &self.drives {
            if eval_dnf(&d.dnf, frame) {
                outputs.extend(d.outputs.iter().cloned());
                up |= d.speed > 0;
                down |= d.speed < 0;
                if d.speed.abs() > best.abs() {
                    best = d.speed;
                }
            }
        }
        outputs.sort();
        outputs.dedup();
        if up && down {
            (0, true, outputs)
        } else {
            (best, false, outputs)
        }
    }

    /// The entry is free for an item of `length`: no item lies on `[0, length]`.
    fn entry_free(&self, length: i64) -> bool {
        self.items.iter().all(|i| i.rear > length)
    }

    /// Takes `item` at the entry if it is free; false otherwise.
    pub(crate) fn accept(&mut self, item: &Item) -> bool {
        if !self.entry_free(item.length) {
            return false;
        }
        self.items.insert(
            0,
            Item {
                rear: 0,
                ..item.clone()
            },
        );
        true
    }

    /// One step.
    pub(super) fn step(&mut self, ctx: &mut StepCtx<'_>, faults: ComponentFaults) {
        let (speed, opposed, outputs) = self.asked(ctx.frame);
        if opposed && !self.opposed {
            ctx.hazards
                .push((HazardKind::OpposedDrives, outputs.clone()));
        }
        self.opposed = opposed;
        self.blocked = faults.blocked;
        if let Some((rise, classes)) = self.feed.as_mut()
            && rise.rose(ctx.frame)
        {
            // A carried item (kept whole), else the next class of its list.
            let item = match self.feed_from {
                Some(src) => ctx.carried[src].pop_front(),
                None => {
                    let class = &classes[self.next_class % classes.len()];
                    self.next_class += 1;
                    // Numbered when placed (below): a collision places nothing.
                    Some(Item {
                        id: 0,
                        class: class.class.clone(),
                        tags: class.tags.clone(),
                        length: micro(class.length),
                        rear: 0,
                    })
                }
            };
            if let Some(mut item) = item {
                if self.items.iter().all(|i| i.rear > item.length) {
                    item.rear = 0;
                    if item.id == 0 {
                        *ctx.next_item += 1;
                        item.id = *ctx.next_item;
                    }
                    self.items.insert(0, item);
                } else {
                    ctx.hazards
                        .push((HazardKind::Collision, rise.outputs.clone()));
                }
            }
        }
        // A taker that carries (a gripper) holds one item: closing again while it holds
        // one regrips it and takes nothing more off the belt.
        let full = self.carried && !ctx.carried[ctx.index].is_empty();
        if let Some(rise) = self.take.as_mut()
            && rise.rose(ctx.frame)
            && !full
            && let Some(last) = self.items.last()
            && last.rear + last.length / 2 + last.length >= self.length
        {
            let item = self.items.pop();
            match item {
                Some(item) if self.carried => ctx.carried[ctx.index].push_back(item),
                _ => self.taken += 1,
            }
        }
        let dir = speed.signum();
        if dir != self.dir {
            self.dir = dir;
            self.factor_ppm = if dir != 0 && self.variation_ppm > 0 {
                let span = 2 * self.variation_ppm as u64 + 1;
                1_000_000 - self.variation_ppm + ctx.rng.below(span) as i64
            } else {
                1_000_000
            };
        }
        let v = if faults.blocked {
            0
        } else {
            speed * self.factor_ppm / 1_000_000 * i64::from(faults.speed_percent) / 100
        };
        self.moving = v != 0;
        self.carry(v * ctx.dt as i64, ctx, &outputs);
    }

    /// Moves the items by `d` (millionths, signed): each stops against the one ahead,
    /// at an end stop, or leaves at the exit end (dropped, delivered).
    fn carry(&mut self, d: i64, ctx: &mut StepCtx<'_>, outputs: &[String]) {
        if d > 0 {
            // From the exit end back: each item stops against the one ahead.
            let mut limit = i64::MAX;
            let mut k = self.items.len();
            while k > 0 {
                k -= 1;
                let it = &mut self.items[k];
                let mut rear = it.rear + d;
                if limit != i64::MAX {
                    rear = rear.min(limit - it.length);
                }
                it.rear = rear.max(it.rear);
                let front = it.rear + it.length;
                let gone = match &self.exit {
                    // Waits at the end until the next conveyor takes it (`ready`).
                    Exit::Stop | Exit::To(_) => {
                        if front > self.length {
                            it.rear = self.length - it.length;
                        }
                        false
                    }
                    Exit::Drop => {
                        let middle = it.rear + it.length / 2;
                        if middle > self.length {
                            ctx.hazards.push((HazardKind::Dropped, outputs.to_vec()));
                            true
                        } else {
                            false
                        }
                    }
                    Exit::Sink => {
                        let middle = it.rear + it.length / 2;
                        if middle > self.length {
                            self.delivered += 1;
                            true
                        } else {
                            false
                        }
                    }
                };
                if gone {
                    self.items.remove(k);
                } else {
                    limit = self.items[k].rear;
                }
            }
        } else if d < 0 {
            let mut limit = i64::MIN;
            for it in &mut self.items {
                let mut rear = (it.rear + d).max(0);
                if limit != i64::MIN {
                    rear = rear.max(limit);
                }
                it.rear = rear.min(it.rear);
                limit = it.rear + it.length;
            }
        }
    }

    /// The item waiting at the exit end for the next conveyor, if any.
    pub(crate) fn ready(&self) -> Option<&Item> {
        match (&self.exit, self.items.last()) {
            (Exit::To(_), Some(i)) if i.rear + i.length >= self.length => Some(i),
            _ => None,
        }
    }

    /// The next conveyor took the item waiting at the exit end.
    pub(crate) fn hand_over(&mut self) {
        self.items.pop();
    }

    /// At rest: the feeder and the taker act on rises of their expressions, which
    /// change only with the outputs or a sensor another component moves.
    pub(super) fn idle(&self) -> bool {
        self.dir == 0 && !self.opposed
    }

    pub(super) fn sense(&self, sensors: &mut crate::bits::Bits) {
        for (i, _, at, sees) in &self.beams {
            let on = self.items.iter().any(|it| {
                it.rear <= *at
                    && *at <= it.rear + it.length
                    && sees.as_ref().is_none_or(|t| it.tags.contains(t))
            });
            sensors.set(*i, on);
        }
        if let Some(i) = self.motion {
            sensors.set(i, self.moving);
        }
    }

    /// The front of the item nearest the exit end (0 when empty): a conveyor's
    /// position for dangers.
    pub(super) fn position(&self) -> f64 {
        self.items
            .last()
            .map_or(0.0, |i| (i.rear + i.length) as f64 / MICRO)
    }

    pub(super) fn scene(&self, id: &str, name: &str) -> SceneElement {
        let f = |v: i64| v as f64 / MICRO;
        SceneElement {
            id: id.to_string(),
            name: name.to_string(),
            shape: Shape::Conveyor {
                unit: self.unit.clone(),
                length: f(self.length),
                direction: if self.moving { self.dir as i8 } else { 0 },
                items: self
                    .items
                    .iter()
                    .map(|i| SceneItem {
                        id: i.id,
                        class: i.class.clone(),
                        rear: f(i.rear),
                        length: f(i.length),
                    })
                    .collect(),
                sensors: self
                    .beams
                    .iter()
                    .map(|(_, s, at, _)| SceneSensor {
                        signal: s.clone(),
                        from: f(*at),
                        to: f(*at),
                    })
                    .collect(),
                drives: self
                    .drives
                    .iter()
                    .map(|d| SceneDrive {
                        when: d.when.clone(),
                        speed: d.speed as f64 * 1000.0 / MICRO,
                        sensor: None,
                    })
                    .collect(),
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

    /// The items on it, entry first.
    #[cfg(test)]
    pub(crate) fn items(&self) -> &[Item] {
        &self.items
    }

    /// Links its feeder to the conveyor it carries from (`from`, by index), and tells
    /// it whether another conveyor's feeder places what its taker picks.
    pub(crate) fn link_carry(&mut self, from: Option<usize>, carried: bool) {
        self.feed_from = from;
        self.carried = carried;
    }

    /// The classes its feeder places.
    pub(crate) fn classes(&self) -> Vec<String> {
        self.feed
            .as_ref()
            .map(|(_, c)| c.iter().map(|c| c.class.clone()).collect())
            .unwrap_or_default()
    }

    /// The items that left it done: into its sink, or taken at its exit end.
    pub(crate) fn out(&self) -> u32 {
        self.delivered + self.taken
    }
}
