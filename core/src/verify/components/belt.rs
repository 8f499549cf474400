//! A conveyor with its items, abstracted for `vigie verify`.
//!
//! # The abstraction
//! - **The item nearest the entry** (the last one placed) is tracked: its class and the
//!   zone of its rear along the belt. The belt is cut at every point where something
//!   about that item changes: each beam's window for each class (`[at - length, at]`),
//!   each placed class's length (the emulator's collision: a rear at or before the new
//!   item's length), the exit's limits (the stop, the middle passing the end, the
//!   taker's reach). Whether other items may lie **ahead** of it is one flag: a beam an
//!   item ahead could cover then reads any value.
//! - It moves with the belt (its fastest active drive, up to `variation_ppm` faster)
//!   and may stop anywhere (an item ahead holds it); driven backwards it stops at the
//!   entry.
//! - A rise of the feeder's expression places an item of any class the feeder places,
//!   or is a **collision** when the tracked item's rear is at or before that class's
//!   length at the cycle's start or end. A feeder that carries items from another belt
//!   (`from`) may also place nothing. An item from the belt upstream may arrive at any
//!   cycle the entry is free for it.
//! - At the exit: an end stop holds the item with its front at the end; a following
//!   belt (`To`) may take it at any cycle there; a sink takes it and a drop lets it
//!   **fall** once its middle passes the end. A rise of `take` removes it once its front
//!   is within half its length of the end. An item ahead may fall off a drop whenever
//!   the belt runs forward.

use super::line::{Cuts, Mover, fastest, micro, opposable};
use super::{SubHazard, compile, input};
use crate::bundle::PlantBundle;
use crate::diag::Problem;
use crate::expr::Dnf;
use crate::frame::Frame;
use crate::machine::description::Components;
use crate::machine::kinds::KindDef;
use crate::machine::kinds::conveyor::{ConveyorDef, Exit, ItemClass};
use std::collections::BTreeSet;

/// A class of items that may lie on the belt.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Class {
    pub(super) name: String,
    /// Millionths of the unit.
    pub(super) length: i64,
    pub(super) tags: Vec<String>,
}

/// The feeder at the entry, compiled.
#[derive(Clone, Debug)]
pub(super) struct Feed {
    pub(super) dnf: Dnf,
    /// The classes it places (indices into [`Belt::classes`]).
    pub(super) places: Vec<usize>,
    /// It places the items a taker carries off another belt: a rise places one only
    /// when the taker holds one, and this is the other belt's `take` (a rise loads one
    /// when that belt has one at its end).
    pub(super) load: Option<Dnf>,
}

/// A conveyor, abstracted.
#[derive(Clone, Debug)]
pub(super) struct Belt {
    pub(super) unit: String,
    /// Millionths of the unit.
    pub(super) length: i64,
    pub(super) movers: Vec<Mover>,
    pub(super) variation_ppm: i64,
    /// Beams: input, place, the tag it sees.
    pub(super) beams: Vec<(usize, i64, Option<String>)>,
    /// The beams something of the sub-plant reads (a constraint, an observer, a drive):
    /// only they take any value when an item ahead may cover them; the others read 0.
    pub(super) read: Vec<bool>,
    pub(super) motion: Option<usize>,
    pub(super) feed: Option<Feed>,
    pub(super) take: Option<Dnf>,
    pub(super) exit: Exit,
    /// Another belt's exit leads to its entry.
    pub(super) upstream: bool,
    pub(super) classes: Vec<Class>,
    /// The cuts of the tracked item's rear.
    pub(super) points: Cuts,
}

/// The tracked item: its class and the zone of its rear; `None` when the belt is empty
/// up to the items ahead.
pub(super) type Tracked = Option<(u8, u16)>;

/// The belt's items after one cycle.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) struct Items {
    pub(super) item: Tracked,
    pub(super) ahead: bool,
    /// Items the carrier holds for its feeder: 0 or 1 (a gripper holds one).
    pub(super) carried: u8,
}

/// What a cycle does at the belt's ends: the feeder's and the taker's rises.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Ends {
    pub(super) feed_rise: bool,
    pub(super) take_rise: bool,
    /// The carrier picks an item off the other belt ([`Feed::load`]).
    pub(super) load_rise: bool,
}

/// The item classes a belt can tell apart: by length and by the tags its beams see
/// (`seen`); classes alike in both are one (its name lists theirs).
fn merge<'a>(classes: impl Iterator<Item = &'a ItemClass>, seen: &BTreeSet<&str>) -> Vec<Class> {
    let mut out: Vec<Class> = Vec::new();
    for k in classes {
        let mut tags: Vec<String> = k
            .tags
            .iter()
            .filter(|t| seen.contains(t.as_str()))
            .cloned()
            .collect();
        tags.sort();
        tags.dedup();
        let length = micro(k.length);
        match out
            .iter_mut()
            .find(|c| c.length == length && c.tags == tags)
        {
            Some(c) => {
                if !c.name.split('/').any(|n| n == k.class) {
                    c.name = format!("{}/{}", c.name, k.class);
                }
            }
            None => out.push(Class {
                name: k.class.clone(),
                length,
                tags,
            }),
        }
    }
    out
}

/// The index of the class `k` falls in.
fn class_of(classes: &[Class], k: &ItemClass, seen: &BTreeSet<&str>) -> usize {
    let one = merge(std::iter::once(k), seen).remove(0);
    classes
        .iter()
        .position(|c| c.length == one.length && c.tags == one.tags)
        .unwrap_or(0)
}

/// The cuts of a rear on a belt of `length` with these beams and classes: where a beam
/// starts or stops seeing an item, where a new item would hit it, where it stops at
/// the end, falls or leaves (its middle past the end) and where the taker reaches it.
fn cuts(length: i64, beams: &[(usize, i64, Option<String>)], classes: &[Class]) -> Cuts {
    let mut points = vec![0, length];
    for c in classes {
        let e = c.length;
        for &(_, at, _) in beams {
            points.extend([at - e, at]);
        }
        points.extend([e, length - e, length - e / 2, length - e - e / 2]);
    }
    points.retain(|p| (0..=length).contains(p));
    points.sort_unstable();
    points.dedup();
    Cuts(points)
}

/// The item classes conveyor `def` places: its feeder's and its source's.
fn placed_by(def: &ConveyorDef) -> Vec<&ItemClass> {
    def.feed
        .iter()
        .flat_map(|f| &f.items)
        .chain(def.source.iter().flat_map(|s| &s.items))
        .collect()
}

/// Every item class the plant's feeders and sources place.
fn placed(desc: &Components) -> Vec<&ItemClass> {
    desc.components
        .iter()
        .flat_map(|c| match &c.kind {
            KindDef::Conveyor(cv) => placed_by(cv),
            _ => Vec::new(),
        })
        .collect()
}

impl Belt {
    /// The conveyor `id` abstracted.
    pub(super) fn build(
        id: &str,
        def: &ConveyorDef,
        desc: &Components,
        bundle: &PlantBundle,
    ) -> Result<Self, Problem> {
        // Items arrive at the entry from a belt upstream, or from its own source
        // (which waits for a free entry: a subset of what an upstream belt may do).
        let upstream = def.source.is_some()
            || desc.components.iter().any(|c| match &c.kind {
                KindDef::Conveyor(other) => other.target() == Some(id),
                _ => false,
            });
        let seen: BTreeSet<&str> = def
            .sensors
            .iter()
            .filter_map(|b| b.sees.as_deref())
            .collect();
        let carried = def.carries_from().is_some();
        // What loads the carrier: the taker of the belt it carries from.
        let load = match def.carries_from() {
            None => None,
            Some(from) => desc
                .components
                .iter()
                .find(|c| c.id == from)
                .and_then(|c| match &c.kind {
                    KindDef::Conveyor(src) => src.take.as_deref(),
                    _ => None,
                })
                .map(|t| compile(t, bundle))
                .transpose()?,
        };
        let own = placed_by(def);
        // What it may hold: what it places, or what any feeder of the plant places when
        // items come from another belt.
        let classes = if upstream || carried || own.is_empty() {
            merge(placed(desc).into_iter(), &seen)
        } else {
            merge(own.iter().copied(), &seen)
        };
        let feed = match &def.feed {
            None => None,
            Some(f) => {
                let mut places: Vec<usize> = if carried || own.is_empty() {
                    (0..classes.len()).collect()
                } else {
                    own.iter().map(|k| class_of(&classes, k, &seen)).collect()
                };
                places.sort_unstable();
                places.dedup();
                Some(Feed {
                    dnf: compile(&f.when, bundle)?,
                    places,
                    load: if carried {
                        Some(load.unwrap_or_default())
                    } else {
                        None
                    },
                })
            }
        };
        let mut movers = Vec::new();
        for d in &def.drives {
            movers.push(Mover {
                dnf: compile(&d.when, bundle)?,
                speed: micro(d.speed / 1000.0),
                sensor: None,
            });
        }
        let mut beams = Vec::new();
        for b in &def.sensors {
            beams.push((input(bundle, &b.signal)?, micro(b.at), b.sees.clone()));
        }
        let length = micro(def.length);
        let points = cuts(length, &beams, &classes);
        Ok(Self {
            unit: def.unit.clone(),
            length,
            movers,
            variation_ppm: i64::from(def.variation_ppm),
            read: vec![true; beams.len()],
            beams,
            motion: def
                .motion
                .as_deref()
                .map(|m| input(bundle, m))
                .transpose()?,
            feed,
            take: def
                .take
                .as_deref()
                .map(|t| compile(t, bundle))
                .transpose()?,
            exit: def.exit.clone(),
            upstream,
            classes,
            points,
        })
    }

    /// The hazards it can have.
    pub(super) fn hazards(&self) -> Vec<SubHazard> {
        let mut out = Vec::new();
        if opposable(&self.movers) {
            out.push(SubHazard::OpposedDrives);
        }
        if self.feed.is_some() {
            out.push(SubHazard::Collision);
        }
        if self.exit == Exit::Drop {
            out.push(SubHazard::Dropped);
        }
        out
    }

    /// The signed speed for the applied outputs in `frame`, and whether its drives are
    /// opposed.
    pub(super) fn speed(&self, frame: &Frame) -> (i64, bool) {
        fastest(&self.movers, frame)
    }

    /// The beams: those whose value is known (input, value) and those an item ahead
    /// may cover (any value).
    pub(super) fn sense(&self, items: &Items) -> (Vec<(usize, bool)>, Vec<usize>) {
        let (mut known, mut free) = (Vec::new(), Vec::new());
        for ((i, at, sees), &read) in self.beams.iter().zip(&self.read) {
            let mut on = false;
            let mut ahead = items.ahead;
            if let Some((c, z)) = items.item {
                let class = &self.classes[usize::from(c)];
                let z = usize::from(z);
                let sees_it = sees.as_ref().is_none_or(|t| class.tags.contains(t));
                on = sees_it && self.points.within(z, at - class.length, *at);
                // An item ahead lies wholly past the tracked one's front.
                ahead &= *at >= self.points.bounds(z).0 + class.length;
            }
            let any_seen = sees
                .as_ref()
                .is_none_or(|t| self.classes.iter().any(|c| c.tags.contains(t)));
            if !on && ahead && any_seen && read {
                free.push(*i);
            } else {
                known.push((*i, on));
            }
        }
        (known, free)
    }

    /// The zone of a rear at `p`.
    fn zone(&self, p: i64) -> u16 {
        self.points.zone_of(p) as u16
    }

    /// The furthest zone a rear of class `c` reaches: its front at the end (an end stop,
    /// a following belt), or the end itself (it leaves before).
    fn cap(&self, c: usize) -> usize {
        match self.exit {
            Exit::Stop | Exit::To(_) => self
                .points
                .zone_of((self.length - self.classes[c].length).max(0)),
            Exit::Sink | Exit::Drop => self.points.zones() - 1,
        }
    }

    /// Where the tracked item may be after moving at `v` for a cycle: (item, fell).
    fn moves(&self, item: Tracked, v: i64) -> Vec<(Tracked, bool)> {
        let Some((c, z)) = item else {
            return vec![(None, false)];
        };
        let (ci, z) = (usize::from(c), usize::from(z));
        let cap = self.cap(ci);
        let len = self.classes[ci].length;
        let middle = self.points.zone_of(self.length - len / 2);
        let mut out = Vec::new();
        for j in self
            .points
            .reach(z, v, self.variation_ppm, (0, cap.max(z)), true)
        {
            match self.exit {
                Exit::Sink | Exit::Drop if j > middle => {
                    out.push((None, self.exit == Exit::Drop));
                }
                _ => out.push((Some((c, j as u16)), false)),
            }
            if matches!(self.exit, Exit::To(_)) && j >= cap {
                out.push((None, false));
            }
        }
        out.dedup();
        out
    }

    /// A new item of class `p` placed at the entry hits the tracked one at `z`.
    fn hits(&self, z: u16, p: usize) -> bool {
        self.points.bounds(usize::from(z)).1 <= self.classes[p].length
    }

    /// The taker reaches the tracked item: its front within half its length of the end.
    fn reachable(&self, c: u8, z: u16) -> bool {
        let len = self.classes[usize::from(c)].length;
        self.points.bounds(usize::from(z)).0 >= self.length - len - len / 2
    }

    /// The feeder's rise: a new item at the entry, or a collision with the tracked one
    /// (where it was at the cycle's start, `now`, or is at its end, `moved`); a carrier
    /// that holds nothing places nothing.
    fn feed(
        &self,
        now: &Items,
        stay: Items,
        hazards: &mut Vec<(Items, Option<SubHazard>)>,
    ) -> Vec<Items> {
        let Some(feed) = &self.feed else {
            return vec![stay];
        };
        let carrier = feed.load.is_some();
        if carrier && now.carried == 0 {
            return vec![stay];
        }
        let mut out = Vec::new();
        for &p in &feed.places {
            let hit = [now.item, stay.item]
                .iter()
                .flatten()
                .any(|&(_, z)| self.hits(z, p));
            if hit {
                hazards.push((now.clone(), Some(SubHazard::Collision)));
                continue;
            }
            out.push(Items {
                item: Some((p as u8, self.zone(0))),
                ahead: stay.item.is_some() || stay.ahead,
                carried: 0,
            });
        }
        out
    }

    /// The taker's rise: it takes the frontmost item, the tracked one (`moved` from
    /// `now`, unless a new one was placed) when it is within reach and none is ahead.
    fn take(&self, now: &Items, moved: Tracked, branches: Vec<Items>) -> Vec<Items> {
        let reach = |t: Tracked| t.is_some_and(|(c, z)| self.reachable(c, z));
        let mut out = Vec::new();
        for b in branches {
            if reach(b.item) || (b.item.is_some() && b.item == moved && reach(now.item)) {
                out.push(Items {
                    item: None,
                    ahead: false,
                    carried: b.carried,
                });
                if !b.ahead {
                    continue;
                }
            }
            out.push(b);
        }
        out
    }

    /// The belt upstream hands an item over when the entry is free for it.
    fn arrivals(&self, branches: &[Items]) -> Vec<Items> {
        let mut out = Vec::new();
        for b in branches {
            for p in 0..self.classes.len() {
                if b.item.is_none_or(|(_, z)| !self.hits(z, p)) {
                    out.push(Items {
                        item: Some((p as u8, self.zone(0))),
                        ahead: b.item.is_some() || b.ahead,
                        carried: b.carried,
                    });
                }
            }
        }
        out
    }

    /// One cycle of the belt's items at speed `v`, with the rises at its ends: every
    /// outcome, and the hazard of each that is one (a collision at the entry, an item
    /// fallen off the end).
    pub(super) fn next(&self, now: &Items, v: i64, ends: Ends) -> Vec<(Items, Option<SubHazard>)> {
        let mut out: Vec<(Items, Option<SubHazard>)> = Vec::new();
        if self.exit == Exit::Drop && now.ahead && v > 0 {
            out.push((now.clone(), Some(SubHazard::Dropped)));
        }
        let carrier = self.feed.as_ref().is_some_and(|f| f.load.is_some());
        for (moved, fell) in self.moves(now.item, v) {
            if fell {
                out.push((now.clone(), Some(SubHazard::Dropped)));
                continue;
            }
            let stay = Items {
                item: moved,
                ahead: moved.is_some() && now.ahead,
                carried: now.carried,
            };
            let mut branches = if ends.feed_rise {
                self.feed(now, stay, &mut out)
            } else {
                vec![stay]
            };
            // The carrier, holding nothing, picks one off the other belt's end (if one
            // is there); holding one, it takes nothing more.
            if carrier && ends.load_rise {
                let loaded: Vec<Items> = branches
                    .iter()
                    .filter(|b| b.carried == 0)
                    .map(|b| Items {
                        carried: 1,
                        ..b.clone()
                    })
                    .collect();
                branches.extend(loaded);
            }
            if self.take.is_some() && ends.take_rise {
                branches = self.take(now, moved, branches);
            }
            if self.upstream {
                let arrived = self.arrivals(&branches);
                branches.extend(arrived);
            }
            out.extend(branches.into_iter().map(|b| (b, None)));
        }
        let mut seen = Vec::new();
        out.retain(|o| {
            let new = !seen.contains(o);
            if new {
                seen.push(o.clone());
            }
            new
        });
        out
    }

    /// The items as a trace shows them.
    pub(super) fn text(&self, items: &Items) -> String {
        let mut s = match items.item {
            None => "empty".to_string(),
            Some((c, z)) => format!(
                "{} at rear {}",
                self.classes[usize::from(c)].name,
                self.points.text(usize::from(z), &self.unit)
            ),
        };
        if items.ahead {
            s.push_str(" (more ahead)");
        }
        if self.feed.as_ref().is_some_and(|f| f.load.is_some()) {
            let held = if items.carried == 0 { "nothing" } else { "one" };
            s.push_str(&format!(", the carrier holds {held}"));
        }
        s
    }
}

#[cfg(test)]
mod tests;
