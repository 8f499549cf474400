//! The decentralized diagnosers derived from the components (seed 004, sections 3, 4
//! and 6.3): one component model (PoP) per axis, written as `diagnosers.ron` by
//! `vigie diagnose derive` so that a plant of components gets its diagnosers, its
//! diagnosability report and its fault campaign without anyone writing the models.
//!
//! # The model of an axis
//!
//! The travel is cut at the edges of the sensor windows into *segments*, each with the
//! sensors it shows; two neighbouring segments differ by one sensor (its rise or its
//! fall is the event between them). The component observes its drives' outputs and
//! those sensors. A state is a segment, the vector of the drives' outputs, and how the
//! segment was entered:
//!
//! - at rest (the outputs ask for no motion): only the outputs may change;
//! - moving, entered by crossing the previous edge: the next sensor edge comes within
//!   the segment's length at the speed (± `variation_ppm`);
//! - moving, started inside the segment by an output edge: the next sensor edge comes
//!   within `[0, length / slowest speed]` of that edge;
//! - moving from the start of the run: the position in the segment is unknown; no
//!   window.
//!
//! Every window gets the axis's `tolerance_ms` and one PLC cycle on each side (the
//! sampling of both edges); the runtime adds `margin_ms`. In a timed moving state the
//! outputs may change too, within the same window: a state whose sensor edge does not
//! come before the window closes dies (the axis is blocked or a sensor is dead). A
//! segment shorter than one cycle's travel may be crossed unseen: the edge after it is
//! expected too. The edges of one cycle are taken sensors first (the controller reacts
//! in the scan that shows the sensor; the plant cannot react to an order in the scan
//! that gives it).
//!
//! Faults: the four faults of each sensor (stuck at 0 and 1, a spurious rise or fall)
//! in a partition named after the sensor; the axis blocked in any moving state, or
//! moving without its order (or otherwise than ordered), in the partition
//! `<component>_drive`, which stops the
//! plant. The fault campaign injects the emulator's `Blocked(component)` besides the
//! stuck sensors and actuators the partitions imply.
//!
//! A kind is derived when [`super::kinds::KindDef::travel`] describes it as a travel
//! with drives and windows (an axis); the others are listed with the reason.

use super::description::Components;
use super::kinds::Travel;
use crate::expr::parse_str;
use crate::pop::model::{
    Behaviour, Bound, ComponentDef, DiagnoserFile, EvolutionDef, FaultDef, InjectionDef,
    IntervalDef, PartitionDef, StateDef,
};
use crate::symbols::{Space, Symbols};
use std::collections::{BTreeMap, BTreeSet, VecDeque};

/// The PLC cycle the windows allow for, ms (each edge is seen up to a cycle late).
const CYCLE_MS: u64 = 10;
/// Drives' outputs a model follows at most (states grow as 2^k).
const MAX_OUTPUTS: usize = 4;

/// What `derive` made of a plant's components.
#[derive(Clone, Debug)]
pub struct Derived {
    /// The models, in the order of `components.ron`.
    pub file: DiagnoserFile,
    /// The components without a model, with the reason.
    pub skipped: Vec<(String, String)>,
}

/// Derives the diagnosers of every component that the library describes as a travel.
pub fn derive(desc: &Components, symbols: &Symbols) -> Derived {
    let mut file = DiagnoserFile {
        alpha: 3.0,
        margin_ms: 10,
        pulse_max_ms: 2000,
        components: Vec::new(),
    };
    let mut skipped = Vec::new();
    for c in &desc.components {
        match c.kind.travel() {
            None => skipped.push((c.id.clone(), format!("a {} (no travel)", c.kind.label()))),
            Some(t) => match model(&c.id, &c.name, &t, symbols) {
                Ok(m) => file.components.push(m),
                Err(reason) => skipped.push((c.id.clone(), reason)),
            },
        }
    }
    Derived { file, skipped }
}

/// A segment of the travel between two cuts, with the sensors on in it.
#[derive(Clone, Debug)]
struct Segment {
    lo: f64,
    hi: f64,
    on: BTreeSet<String>,
    name: String,
}

/// What a moving state is timed from.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Entry {
    /// The output edge that started the motion, and the segment it started in: every
    /// edge of the move is timed from that order (as the paper's table is from `A4`),
    /// so that a copy whose faulty sensor hid an edge keeps its clock.
    Order(String, usize),
    /// At the start of the run: the position is unknown, no window.
    Start,
}

#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Key {
    seg: usize,
    mask: u32,
    /// None at rest.
    entry: Option<Entry>,
}

struct Builder<'a> {
    id: &'a str,
    t: &'a Travel,
    segs: Vec<Segment>,
    outputs: Vec<String>,
    /// Per drive: its terms, and its speed.
    drives: Vec<(Terms, f64)>,
    intervals: BTreeMap<(String, u64, Option<u64>), String>,
}

fn edge(rise: bool, signal: &str) -> String {
    format!("{}({signal})", if rise { "RE" } else { "FE" })
}

impl Builder<'_> {
    /// The signed speed (units/s) the outputs `mask` ask for: the fastest active drive,
    /// none when drives in both directions are active (they hold the axis).
    fn speed(&self, mask: u32) -> f64 {
        let (mut best, mut up, mut down) = (0.0f64, false, false);
        for (terms, speed) in &self.drives {
            let active = terms
                .iter()
                .any(|t| t.iter().all(|&(o, pos)| (mask >> o & 1 == 1) == pos));
            if active {
                up |= *speed > 0.0;
                down |= *speed < 0.0;
                if speed.abs() > best.abs() {
                    best = *speed;
                }
            }
        }
        if up && down { 0.0 } else { best }
    }

    fn mask_text(&self, mask: u32) -> String {
        let on: Vec<&str> = (0..self.outputs.len())
            .filter(|&o| mask >> o & 1 == 1)
            .map(|o| self.outputs[o].as_str())
            .collect();
        if on.is_empty() {
            "none".into()
        } else {
            on.join("+")
        }
    }

    fn state_id(&self, k: &Key) -> String {
        let base = format!("{}|{}", self.segs[k.seg].name, self.mask_text(k.mask));
        match &k.entry {
            None => base,
            Some(Entry::Order(e, from)) if *from == k.seg => format!("{base}|on {e}"),
            Some(Entry::Order(e, from)) => {
                format!("{base}|on {e} in {}", self.segs[*from].name)
            }
            Some(Entry::Start) => format!("{base}|start"),
        }
    }

    /// The interval `[lo, hi[` after `clock`, shared by every evolution that uses it.
    fn interval(&mut self, clock: &str, lo: u64, hi: Option<u64>) -> String {
        let n = self.intervals.len() + 1;
        self.intervals
            .entry((clock.to_string(), lo, hi))
            .or_insert_with(|| format!("{}_I{n}", self.id))
            .clone()
    }

    /// The time to cross `length` units at `speed`: fastest and slowest, ms.
    fn crossing(&self, length: f64, speed: f64) -> (f64, f64) {
        let var = f64::from(self.t.variation_ppm) / 1e6;
        let v = speed.abs() / 1000.0;
        (length / (v * (1.0 + var)), length / (v * (1.0 - var)))
    }

    /// The state for outputs `mask` in segment `seg` entered by `entry` (at rest when
    /// the outputs ask for no motion).
    fn key(&self, seg: usize, mask: u32, entry: Entry) -> Key {
        Key {
            seg,
            mask,
            entry: (self.speed(mask) != 0.0).then_some(entry),
        }
    }

    /// The expected evolutions out of `k`: (event, window, target).
    fn out_of(&mut self, k: &Key) -> Vec<(String, Option<String>, Key)> {
        let speed = self.speed(k.mask);
        let mut out = Vec::new();
        let mut deadline = None;
        if let Some(entry) = &k.entry {
            let dir: isize = if speed > 0.0 { 1 } else { -1 };
            let slack = self.t.tolerance_ms + CYCLE_MS;
            let var = f64::from(self.t.variation_ppm) / 1e6;
            let one_cycle = speed.abs() / 1000.0 * (1.0 + var) * CYCLE_MS as f64;
            let from = self.segs[k.seg].on.clone();
            let mut at = k.seg;
            // The next edge, and those after a segment the axis may cross unseen in one
            // cycle (the sensors show nothing of it; a window between two gaps leaves
            // no edge at all until the next one).
            while let Some(next) = at.checked_add_signed(dir).filter(|&n| n < self.segs.len()) {
                let changed: Vec<(bool, String)> = self.segs[next]
                    .on
                    .difference(&from)
                    .map(|s| (true, s.clone()))
                    .chain(
                        from.difference(&self.segs[next].on)
                            .map(|s| (false, s.clone())),
                    )
                    .collect();
                if changed.len() > 1 {
                    break;
                }
                if let Some((rise, sensor)) = changed.first() {
                    let event = edge(*rise, sensor);
                    let window = match entry {
                        Entry::Start => None,
                        Entry::Order(clock, from) => {
                            // From the order: at least the segments crossed whole, at
                            // most those and the one it started in.
                            let span = |a: usize, b: usize| -> f64 {
                                (a.min(b)..=a.max(b))
                                    .map(|i| self.segs[i].hi - self.segs[i].lo)
                                    .sum()
                            };
                            let most = span(*from, at);
                            let least = most - (self.segs[*from].hi - self.segs[*from].lo);
                            let lo = (self.crossing(least, speed).0.floor() as u64)
                                .saturating_sub(slack);
                            let hi = self.crossing(most, speed).1.ceil() as u64 + slack;
                            deadline = deadline.max(Some(hi));
                            Some(self.interval(clock, lo, Some(hi)))
                        }
                    };
                    let target = self.key(next, k.mask, entry.clone());
                    out.push((event, window, target));
                }
                let silent = changed.is_empty();
                if !silent && self.segs[next].hi - self.segs[next].lo >= one_cycle {
                    break;
                }
                at = next;
            }
        }
        let clock = match &k.entry {
            Some(Entry::Order(c, _)) => Some(c.clone()),
            _ => None,
        };
        for o in 0..self.outputs.len() {
            let rise = k.mask >> o & 1 == 0;
            let event = edge(rise, &self.outputs[o]);
            let target = self.key(k.seg, k.mask ^ (1 << o), Entry::Order(event.clone(), k.seg));
            let window = match (&clock, deadline) {
                (Some(c), Some(hi)) => Some(self.interval(c, 0, Some(hi))),
                _ => None,
            };
            out.push((event, window, target));
        }
        out
    }
}

/// Cuts the travel into segments at the windows' edges; neighbours must differ by one
/// sensor.
fn segments(t: &Travel) -> Result<Vec<Segment>, String> {
    let mut cuts = vec![t.min, t.max];
    for (_, from, to) in &t.windows {
        cuts.extend(
            [*from, *to]
                .into_iter()
                .filter(|p| *p > t.min && *p < t.max),
        );
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    // Zones: each cut (a point: an end switch is on there only) and the open interval
    // after it; neighbours showing the same sensors merge.
    let mut zones: Vec<(f64, f64)> = Vec::new();
    for (i, &p) in cuts.iter().enumerate() {
        zones.push((p, p));
        if let Some(&q) = cuts.get(i + 1) {
            zones.push((p, q));
        }
    }
    let mut segs: Vec<Segment> = Vec::new();
    for (lo, hi) in zones {
        let on: BTreeSet<String> = t
            .windows
            .iter()
            .filter(|(_, from, to)| *from <= lo && hi <= *to)
            .map(|(s, _, _)| s.clone())
            .collect();
        match segs.last_mut() {
            Some(last) if last.on == on => last.hi = hi,
            _ => segs.push(Segment {
                lo,
                hi,
                on,
                name: String::new(),
            }),
        }
    }
    for i in 1..segs.len() {
        let changed: Vec<&String> = segs[i].on.symmetric_difference(&segs[i - 1].on).collect();
        if changed.len() != 1 {
            return Err(format!(
                "sensors {} change together at {}",
                changed
                    .iter()
                    .map(|s| s.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                segs[i].lo
            ));
        }
    }
    let n = segs.len();
    for i in 0..n {
        let name = if segs[i].on.is_empty() {
            let below = (i > 0)
                .then(|| segs[i - 1].on.iter().next().cloned())
                .flatten();
            let above = segs.get(i + 1).and_then(|s| s.on.iter().next().cloned());
            match (below, above) {
                (Some(b), Some(a)) => format!("{b}..{a}"),
                (None, Some(a)) => format!("below {a}"),
                (Some(b), None) => format!("beyond {b}"),
                (None, None) => "travel".into(),
            }
        } else {
            segs[i].on.iter().cloned().collect::<Vec<_>>().join("+")
        };
        segs[i].name = name;
    }
    Ok(segs)
}

/// A drive's condition: terms of (output index, positive) literals.
type Terms = Vec<Vec<(usize, bool)>>;

/// The outputs the drives read, and each drive as terms over them with its speed.
type Drives = (Vec<String>, Vec<(Terms, f64)>);

fn drives(t: &Travel, symbols: &Symbols) -> Result<Drives, String> {
    let mut outputs: Vec<String> = Vec::new();
    let mut out = Vec::new();
    for (when, speed) in &t.drives {
        let dnf = parse_str(when)
            .and_then(|e| e.to_dnf(symbols))
            .map_err(|e| format!("drive `{when}`: {}", e.message))?;
        let mut terms = Vec::new();
        for term in &dnf {
            let mut lits = Vec::new();
            for lit in term {
                if lit.var.space != Space::Output || lit.var.prev {
                    return Err(format!(
                        "drive `{when}` reads `{}`, not an output at t",
                        symbols.name(lit.var.space, lit.var.index)
                    ));
                }
                let name = symbols.name(Space::Output, lit.var.index).to_string();
                let o = match outputs.iter().position(|n| *n == name) {
                    Some(o) => o,
                    None => {
                        outputs.push(name);
                        outputs.len() - 1
                    }
                };
                lits.push((o, lit.positive));
            }
            terms.push(lits);
        }
        out.push((terms, *speed));
    }
    if outputs.len() > MAX_OUTPUTS {
        return Err(format!(
            "{} drive outputs (a model follows {MAX_OUTPUTS} at most)",
            outputs.len()
        ));
    }
    Ok((outputs, out))
}

/// The component model of one travel.
fn model(id: &str, name: &str, t: &Travel, symbols: &Symbols) -> Result<ComponentDef, String> {
    if t.windows.is_empty() {
        return Err("no position sensor".into());
    }
    let segs = segments(t)?;
    let (outputs, drives) = drives(t, symbols)?;
    let sensors: Vec<String> = t
        .windows
        .iter()
        .map(|(s, _, _)| s.clone())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let start_seg = start_segment(t, &segs)?;
    let mut b = Builder {
        id,
        t,
        segs,
        outputs,
        drives,
        intervals: BTreeMap::new(),
    };
    let initial = b.key(start_seg, 0, Entry::Start);
    let (order, seen, expected) = reachable(&mut b, &initial);
    let moving: Vec<String> = order
        .iter()
        .filter(|k| k.entry.is_some())
        .map(|k| b.state_id(k))
        .collect();
    let states = order
        .iter()
        .map(|k| StateDef {
            id: b.state_id(k),
            description: describe(&b, k),
        })
        .collect();
    let motion = motions(&b, &order, &seen);
    let (mut faults, mut partitions) = sensor_faults(&sensors);
    let drive = format!("{id}_drive");
    drive_faults(
        &b,
        (id, name),
        moving,
        motion,
        (&mut faults, &mut partitions),
    );
    let mut signals = b.outputs.clone();
    signals.extend(sensors.iter().cloned());
    let initial_values = signals
        .iter()
        .map(|s| {
            if b.segs[start_seg].on.contains(s) {
                s.clone()
            } else {
                format!("/{s}")
            }
        })
        .collect::<Vec<_>>()
        .join(" . ");
    let intervals = intervals(&b, id);
    Ok(ComponentDef {
        id: id.to_string(),
        description: format!(
            "{name}: derived from components.ron by `vigie diagnose derive` (segments {})",
            b.segs
                .iter()
                .map(|s| format!("{} [{}, {}]", s.name, s.lo, s.hi))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        signals,
        initial: b.state_id(&initial),
        initial_values,
        states,
        expected,
        intervals,
        initial_clock: None,
        faults,
        partitions,
        estimates: Vec::new(),
        follows_safe_state: true,
        sensors_first: true,
        timed_orders: true,
        assumes: Vec::new(),
        assumes_item: Vec::new(),
        settle_ms: 0,
        confirm_ms: None,
        doubt_ms: None,
        independent: Vec::new(),
        injections: vec![InjectionDef {
            name: format!("{name} blocked"),
            fault: crate::emulator::FaultKind::Blocked(id.to_string()),
            expected: vec![drive],
            when: None,
        }],
    })
}

/// The drive's faults (blocked on the way, moving without its order) in the stopping
/// partition `<id>_drive` that names the drive outputs.
fn drive_faults(
    b: &Builder<'_>,
    (id, name): (&str, &str),
    moving: Vec<String>,
    motion: Vec<Behaviour>,
    (faults, partitions): (&mut Vec<FaultDef>, &mut Vec<PartitionDef>),
) {
    let mut drive_faults = Vec::new();
    if !moving.is_empty() {
        faults.push(FaultDef {
            id: format!("{id}_blocked"),
            description: format!("{name} blocked (the axis does not move, or stops on the way)"),
            behaviours: vec![Behaviour::Blocked(moving)],
        });
        drive_faults.push(format!("{id}_blocked"));
    }
    if !motion.is_empty() {
        faults.push(FaultDef {
            id: format!("{id}_motion"),
            description: format!("{name} moves without its order (a welded actuator)"),
            behaviours: motion,
        });
        drive_faults.push(format!("{id}_motion"));
    }
    if !drive_faults.is_empty() {
        partitions.push(PartitionDef {
            id: format!("{id}_drive"),
            faults: drive_faults,
            sensor: None,
            stop: true,
            actuators: b.outputs.clone(),
        });
    }
}

/// The segment the axis starts in: the one at its start position showing the sensors
/// whose windows hold it.
fn start_segment(t: &Travel, segs: &[Segment]) -> Result<usize, String> {
    let at_start: BTreeSet<String> = t
        .windows
        .iter()
        .filter(|(_, from, to)| (*from..=*to).contains(&t.start))
        .map(|(s, _, _)| s.clone())
        .collect();
    segs.iter()
        .position(|s| s.lo <= t.start && t.start <= s.hi && s.on == at_start)
        .or_else(|| segs.iter().position(|s| s.lo <= t.start && t.start <= s.hi))
        .ok_or_else(|| format!("start {} is outside the travel", t.start))
}

/// The states reachable from `initial` by the expected evolutions, breadth first:
/// their keys in order, their index, and the evolutions.
fn reachable(
    b: &mut Builder<'_>,
    initial: &Key,
) -> (Vec<Key>, BTreeMap<Key, usize>, Vec<EvolutionDef>) {
    let mut seen: BTreeMap<Key, usize> = BTreeMap::from([(initial.clone(), 0)]);
    let mut order: Vec<Key> = vec![initial.clone()];
    let mut queue = VecDeque::from([initial.clone()]);
    let mut expected = Vec::new();
    while let Some(k) = queue.pop_front() {
        for (event, within, to) in b.out_of(&k) {
            if !seen.contains_key(&to) {
                seen.insert(to.clone(), order.len());
                order.push(to.clone());
                queue.push_back(to.clone());
            }
            expected.push(EvolutionDef {
                from: b.state_id(&k),
                event,
                within,
                to: b.state_id(&to),
            });
        }
    }
    (order, seen, expected)
}

/// Unexpected motion: from each rest state, the axis moves as an order would move it;
/// while it moves, a drive switched on unordered (a welded actuator) or off (a dead
/// one: a monostable drive then returns) changes its speed or its direction.
fn motions(b: &Builder<'_>, order: &[Key], seen: &BTreeMap<Key, usize>) -> Vec<Behaviour> {
    let mut motion = Vec::new();
    for k in order {
        for o in 0..b.outputs.len() {
            let rise = k.mask >> o & 1 == 0;
            if k.entry.is_some() && b.speed(k.mask ^ 1 << o) == b.speed(k.mask) {
                continue;
            }
            let order = edge(rise, &b.outputs[o]);
            let target = b.key(k.seg, k.mask ^ (1 << o), Entry::Order(order.clone(), k.seg));
            if target.entry.is_some() && seen.contains_key(&target) {
                motion.push(Behaviour::Moves(b.state_id(k), order));
            }
        }
    }
    motion
}

/// The intervals the evolutions use, in the order they were made (`<id>_I1`, ...).
fn intervals(b: &Builder<'_>, id: &str) -> Vec<IntervalDef> {
    let mut intervals: Vec<IntervalDef> = b
        .intervals
        .iter()
        .map(|((clock, lo, hi), iid)| IntervalDef {
            id: iid.clone(),
            after: clock.clone(),
            lo: Bound::Ms(*lo),
            hi: hi.map_or(Bound::Never, Bound::Ms),
            description: String::new(),
            learned: None,
        })
        .collect();
    intervals.sort_by_key(|i| i.id[id.len() + 2..].parse::<u64>().unwrap_or(0));
    intervals
}

/// The four faults of each sensor, one partition per sensor.
fn sensor_faults(sensors: &[String]) -> (Vec<FaultDef>, Vec<PartitionDef>) {
    let mut faults = Vec::new();
    let mut partitions = Vec::new();
    for s in sensors {
        let ids = [
            (
                format!("{s}_stuck0"),
                format!("{s} stuck at 0"),
                Behaviour::StuckAt(s.clone(), false),
            ),
            (
                format!("{s}_stuck1"),
                format!("{s} stuck at 1"),
                Behaviour::StuckAt(s.clone(), true),
            ),
            (
                format!("{s}_rise"),
                format!("unexpected rise of {s}"),
                Behaviour::Spurious(s.clone(), true),
            ),
            (
                format!("{s}_fall"),
                format!("unexpected fall of {s}"),
                Behaviour::Spurious(s.clone(), false),
            ),
        ];
        partitions.push(PartitionDef {
            id: s.clone(),
            faults: ids.iter().map(|(i, _, _)| i.clone()).collect(),
            sensor: Some(s.clone()),
            stop: false,
            actuators: Vec::new(),
        });
        for (id, description, behaviour) in ids {
            faults.push(FaultDef {
                id,
                description,
                behaviours: vec![behaviour],
            });
        }
    }
    (faults, partitions)
}

fn describe(b: &Builder<'_>, k: &Key) -> String {
    let seg = &b.segs[k.seg];
    let place = format!("in {} [{}, {}] {}", seg.name, seg.lo, seg.hi, b.t.unit);
    let speed = b.speed(k.mask);
    match &k.entry {
        None => format!("at rest {place}, outputs {}", b.mask_text(k.mask)),
        Some(e) => {
            let how = match e {
                Entry::Order(o, from) => format!("started in {} on {o}", b.segs[*from].name),
                Entry::Start => "since the start".into(),
            };
            format!("moving at {speed} {}/s {place}, {how}", b.t.unit)
        }
    }
}

#[cfg(test)]
mod tests;
