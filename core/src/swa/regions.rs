//! Synthesised monitoring regions as a file (`regions.ron`, written by `vigie
//! synthesize`) and the monitor that runs them (the thesis's `A*`: edges conditioned
//! only by events, an alarm as soon as the valuation leaves `E*` of the current
//! location).
//!
//! The file records a fingerprint of the automata it was synthesised from; loading it
//! against other automata (a `tasks.ron` changed since) is refused (V1503), so a stale
//! region never runs.

use super::automaton::{Swa, SwaFile};
use super::linear;
use super::poly::{Display, Poly, Q};
use super::synth::{Synthesis, Union};
use crate::Millis;
use crate::diag::codes;
use crate::diag::{Location as At, Problem};
use crate::tasks::TaskSet;
use crate::tasks::monitor::Deadline;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A location's region as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocationRegion {
    /// The product location (`conveyor:run robot:idle`).
    pub location: String,
    /// `E*`, a union of conjunctions; empty: not reachable under acceptable behaviour.
    pub region: Vec<String>,
    /// Per component in progress here: the reachable valuations from which it can still
    /// reach its desired space (`E ∩ Pre*(D_c)`); an alarm names the components whose
    /// set the valuation leaves.
    #[serde(default)]
    pub finish: BTreeMap<String, Vec<String>>,
}

/// The regions of one location: `E*` and each in-progress component's own set.
#[derive(Clone, Debug, Default)]
pub struct Region {
    /// `E*`.
    pub all: Union,
    /// `(component, E ∩ Pre*(D_c))`.
    pub finish: Vec<(usize, Union)>,
}

/// The `regions.ron` file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionsFile {
    /// The file the automata came from (for the reader).
    pub source: String,
    /// Fingerprint of the automata ([`fingerprint`]).
    pub fingerprint: String,
    /// The product's clocks.
    pub clocks: Vec<String>,
    /// One entry per product location, in the product's order.
    pub locations: Vec<LocationRegion>,
}

/// A stable fingerprint of automata: FNV-1a (64 bits) of their RON text.
pub fn fingerprint(file: &SwaFile) -> String {
    let text = ron::to_string(file).unwrap_or_default();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

impl RegionsFile {
    /// The file of a synthesis.
    pub fn new(source: &str, file: &SwaFile, swa: &Swa, s: &Synthesis) -> Self {
        let show = |u: &Union| -> Vec<String> {
            u.iter()
                .map(|p| {
                    Display {
                        poly: p,
                        names: &swa.clocks,
                    }
                    .to_string()
                })
                .collect()
        };
        RegionsFile {
            source: source.into(),
            fingerprint: fingerprint(file),
            clocks: swa.clocks.clone(),
            locations: swa
                .locations
                .iter()
                .enumerate()
                .map(|(i, l)| LocationRegion {
                    location: l.name.clone(),
                    region: show(&s.regions[i]),
                    finish: s
                        .finishing(swa, i)
                        .into_iter()
                        .map(|(c, u)| (swa.components[c].def.name.clone(), show(&u)))
                        .collect(),
                })
                .collect(),
        }
    }

    /// The RON text (one location per entry, stable).
    pub fn to_ron(&self) -> String {
        let pretty = ron::ser::PrettyConfig::new().depth_limit(3);
        let mut text = ron::ser::to_string_pretty(self, pretty).unwrap_or_default();
        text.push('\n');
        text
    }

    /// Reads `path` and checks it against the automata `file` (compiled as `swa`).
    pub fn load(path: &Path, file: &SwaFile, swa: &Swa) -> Result<Vec<Region>, Problem> {
        let text = crate::diag::read_text(path)?;
        let parsed: RegionsFile =
            ron::from_str(&text).map_err(|e| crate::diag::ron_problem(path, &e))?;
        parsed.check(path, &text, file, swa, None)
    }

    /// Checks the regions against the automata `file` (compiled as `swa`). `source`,
    /// when given, is the file to synthesise again in the stale message (otherwise the
    /// file the regions record).
    fn check(
        &self,
        path: &Path,
        text: &str,
        file: &SwaFile,
        swa: &Swa,
        source: Option<&Path>,
    ) -> Result<Vec<Region>, Problem> {
        let source = source.map_or_else(|| self.source.clone(), |p| p.display().to_string());
        let want = fingerprint(file);
        let at = |needle: &str| At::of_nth(path, text, needle, 0);
        if self.fingerprint != want || self.clocks != swa.clocks {
            return Err(Problem::error(
                codes::REGIONS_STALE.id,
                format!(
                    "these regions were synthesised from other automata (fingerprint {}, \
                     the automata now give {want}); run `vigie synthesize {source}` again",
                    self.fingerprint
                ),
                Some(at(&self.fingerprint)),
            ));
        }
        if self.locations.len() != swa.locations.len() {
            return Err(Problem::error(
                codes::REGIONS_STALE.id,
                format!(
                    "{} locations, the automata have {}; run `vigie synthesize {source}` again",
                    self.locations.len(),
                    swa.locations.len()
                ),
                Some(At::new(path, 1, 1)),
            ));
        }
        let mut out = Vec::new();
        for (entry, loc) in self.locations.iter().zip(&swa.locations) {
            if entry.location != loc.name {
                return Err(Problem::error(
                    codes::REGIONS_STALE.id,
                    format!(
                        "location `{}` where the automata have `{}`; run `vigie synthesize {source}` again",
                        entry.location, loc.name
                    ),
                    Some(at(&entry.location)),
                ));
            }
            let parse = |texts: &[String]| -> Result<Union, Problem> {
                texts
                    .iter()
                    .map(|r| {
                        linear::parse(r, &swa.clocks).map_err(|e| {
                            Problem::error(
                                codes::SWA_INVALID.id,
                                format!("region of `{}`: {}", entry.location, e.message),
                                Some(at(r)),
                            )
                        })
                    })
                    .collect()
            };
            let mut finish = Vec::new();
            for (name, texts) in &entry.finish {
                let c = swa.component(name).ok_or_else(|| {
                    Problem::error(
                        codes::REGIONS_STALE.id,
                        format!(
                            "`{}`: no component `{name}`; run `vigie synthesize {source}` again",
                            entry.location
                        ),
                        Some(at(name)),
                    )
                })?;
                finish.push((c, parse(texts)?));
            }
            out.push(Region {
                all: parse(&entry.region)?,
                finish,
            });
        }
        Ok(out)
    }
}

/// The file of a plant's synthesised regions, beside its `tasks.ron`.
pub const TASK_REGIONS_FILE: &str = "regions.ron";

/// The synthesised regions of a plant's tasks, loaded beside its `tasks.ron` by the
/// layout loader ([`crate::tasks::TaskSet::load_optional`]) and checked against the
/// tasks' automata; the plant's task monitor runs them ([`crate::tasks::Monitor`]).
/// Shared, so cheap to clone. Two are equal when they come from the same file and
/// the same automata.
#[derive(Clone, Debug)]
pub struct TaskRegions {
    /// The regions file.
    pub path: PathBuf,
    /// The fingerprint of the automata ([`fingerprint`]).
    pub fingerprint: String,
    /// The product of the tasks' automata ([`super::from_tasks::automata`]).
    pub swa: Arc<Swa>,
    /// `E*` and the components' own sets, per product location.
    pub regions: Arc<Vec<Region>>,
}

impl PartialEq for TaskRegions {
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path && self.fingerprint == other.fingerprint
    }
}

impl Eq for TaskRegions {}

impl TaskRegions {
    /// The regions beside `set`'s file (`regions.ron` in its folder), checked against
    /// the set's automata: `None` when there is none; a regions file synthesised from
    /// other tasks is refused (V1503), naming the file and the command that makes it
    /// again.
    pub fn beside(set: &TaskSet) -> Result<Option<Self>, Problem> {
        let path = set.file.with_file_name(TASK_REGIONS_FILE);
        if std::fs::symlink_metadata(&path).is_err() {
            return Ok(None);
        }
        let file = super::from_tasks::automata(set);
        let swa = file.compile(&set.file, "")?;
        let text = crate::diag::read_text(&path)?;
        let parsed: RegionsFile =
            ron::from_str(&text).map_err(|e| crate::diag::ron_problem(&path, &e))?;
        let regions = parsed.check(&path, &text, &file, &swa, Some(&set.file))?;
        Ok(Some(TaskRegions {
            path,
            fingerprint: parsed.fingerprint,
            swa: Arc::new(swa),
            regions: Arc::new(regions),
        }))
    }
}

/// The interval of `t ≥ 0` over which `v + t·r` lies in `p`: `(lo, lo_closed, hi,
/// hi_closed)`, `hi = None` for ever; `None` when empty.
type Interval = (Q, bool, Option<Q>, bool);

fn ray(p: &Poly, v: &[Q], r: &[Q]) -> Option<Interval> {
    if p.trivially_empty() {
        return None;
    }
    let (mut lo, mut lo_c) = (Q::zero(), true);
    let (mut hi, mut hi_c): (Option<Q>, bool) = (None, true);
    for h in p.half_spaces() {
        let s = dot(&h.a, r);
        let room = h.b - dot(&h.a, v);
        if s.is_zero() {
            let ok = if h.strict {
                room.is_positive()
            } else {
                !room.is_negative()
            };
            if !ok {
                return None;
            }
        } else if s.is_positive() {
            let t = room / s;
            let tighter = match &hi {
                None => true,
                Some(x) => t < *x || (t == *x && hi_c && h.strict),
            };
            if tighter {
                hi = Some(t);
                hi_c = !h.strict;
            }
        } else {
            let t = room / s;
            if t > lo || (t == lo && lo_c && h.strict) {
                lo = t;
                lo_c = !h.strict;
            }
        }
    }
    if let Some(h) = &hi
        && (*h < lo || (*h == lo && !(lo_c && hi_c)))
    {
        return None;
    }
    Some((lo, lo_c, hi, hi_c))
}

fn dot(a: &[Q], v: &[Q]) -> Q {
    a.iter().zip(v).fold(Q::zero(), |s, (x, y)| s + x * y)
}

/// When `v` (inside the union at `t = 0`) leaves it along `r`: `(t, closed, member)`,
/// `closed` when the valuation is still inside at `t` (it leaves just after), `member`
/// the polyhedron it leaves by; `None` when it never does or is outside now.
pub fn exit(union: &[Poly], v: &[Q], r: &[Q]) -> Option<Option<(Q, bool, usize)>> {
    let spans: Vec<(usize, Interval)> = union
        .iter()
        .enumerate()
        .filter_map(|(i, p)| ray(p, v, r).map(|s| (i, s)))
        .collect();
    let start = spans
        .iter()
        .find(|(_, (lo, lo_c, _, _))| lo.is_zero() && *lo_c)?;
    let (mut end, mut closed, mut member) = (start.1.2, start.1.3, start.0);
    loop {
        let Some(e) = end else {
            return Some(None);
        };
        // A span that starts before the end (or at it, without a gap) extends it.
        let next = spans.iter().find(|(_, (lo, lo_c, hi, hi_c))| {
            let joins = *lo < e || (*lo == e && (closed || *lo_c));
            let longer = match hi {
                None => true,
                Some(h) => *h > e || (*h == e && *hi_c && !closed),
            };
            joins && longer
        });
        match next {
            Some((i, (_, _, hi, hi_c))) => {
                end = *hi;
                closed = *hi_c;
                member = *i;
            }
            None => return Some(Some((e, closed, member))),
        }
    }
}

/// What a region alarm is about.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub enum RegionAlarmKind {
    /// The valuation left `E*` of the location.
    Outside,
    /// An event's edge was taken outside its guard (an end outside the desired space).
    Guard,
    /// No edge of the location takes the event.
    Unexpected,
}

/// An alarm of the region monitor.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RegionAlarm {
    /// When.
    pub at: Deadline,
    /// What.
    pub kind: RegionAlarmKind,
    /// The product location.
    pub location: String,
    /// The components concerned (whose clocks the violated constraint reads, whose
    /// guard failed, or that cannot take the event).
    pub components: Vec<String>,
    /// The violated constraint or the event, as text.
    pub detail: String,
}

/// The monitor `A*`: it follows the product location on events and raises an alarm
/// as soon as the valuation leaves the synthesised region. After an alarm it freezes
/// (the thesis's SFC2) until [`RegionMonitor::repair`].
///
/// The automata and the regions are shared ([`Arc`]): a clone of the monitor (a
/// simulation's snapshot) copies only its location and clocks.
#[derive(Clone, Debug)]
pub struct RegionMonitor {
    swa: Arc<Swa>,
    regions: Arc<Vec<Region>>,
    loc: usize,
    v: Vec<Q>,
    since: Millis,
    alarm: Option<RegionAlarm>,
    options: Options,
}

/// What the region monitor treats as an alarm besides leaving the region.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// An event taken outside its edge's guard (an end outside the desired space).
    pub check_guards: bool,
    /// An event that a component observes but cannot take in its location (otherwise
    /// the event is ignored and the location kept).
    pub unexpected: bool,
}

/// What an event did to the region monitor ([`RegionMonitor::take`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Taken {
    /// No component observes the event, or an alarm is latched: nothing changed.
    Ignored,
    /// A component observes it but cannot take it where it is: nothing changed.
    Blocked(Vec<String>),
    /// The edge was taken, its guard holding.
    Edge,
    /// The edge was taken although its guard failed, for these components.
    OutsideGuard(Vec<String>),
}

impl RegionMonitor {
    /// A monitor of `regions` (one union per location of `swa`) started at `start`.
    pub fn new(swa: Swa, regions: Vec<Region>, start: Millis, options: Options) -> Self {
        Self::shared(Arc::new(swa), Arc::new(regions), start, options)
    }

    /// As [`Self::new`], with automata and regions shared with other monitors.
    pub fn shared(
        swa: Arc<Swa>,
        regions: Arc<Vec<Region>>,
        start: Millis,
        options: Options,
    ) -> Self {
        let mut m = RegionMonitor {
            v: swa.zero(),
            swa,
            regions,
            loc: 0,
            since: start,
            alarm: None,
            options,
        };
        m.check_inside(start);
        m
    }

    /// The automata.
    pub fn swa(&self) -> &Swa {
        &self.swa
    }

    /// The latched alarm.
    pub fn alarm(&self) -> Option<&RegionAlarm> {
        self.alarm.as_ref()
    }

    /// The current product location.
    pub fn location(&self) -> &str {
        &self.swa.locations[self.loc].name
    }

    /// The clocks' values at `t` (ms).
    pub fn clocks(&self, t: Millis) -> Vec<Q> {
        let dt = Q::int(i128::from(t.0.saturating_sub(self.since.0)));
        self.v
            .iter()
            .zip(&self.swa.locations[self.loc].rates)
            .map(|(x, r)| x + dt * r)
            .collect()
    }

    /// The next instant the valuation leaves the region, if it ever does.
    pub fn next_deadline(&self) -> Option<Deadline> {
        self.next_exit().map(|(d, ..)| d)
    }

    /// The instant of [`Self::pending`]'s alarm, without building it.
    pub fn due(&self) -> Option<Deadline> {
        if self.alarm.is_none() && !self.inside() {
            return Some(Deadline {
                at: self.since,
                after: false,
            });
        }
        self.next_deadline()
    }

    /// The next exit: its instant, and `(t, closed, member)` of [`exit`].
    fn next_exit(&self) -> Option<(Deadline, Q, bool, usize)> {
        if self.alarm.is_some() {
            return None;
        }
        let rates = &self.swa.locations[self.loc].rates;
        let (t, closed, member) = exit(&self.regions[self.loc].all, &self.v, rates)??;
        let at = self.since.0 + u64::try_from(t.ceil()).unwrap_or(u64::MAX / 2);
        let deadline = Deadline {
            at: Millis(at),
            after: closed && t.is_integer(),
        };
        Some((deadline, t, closed, member))
    }

    /// The alarm due if no event comes: at the last instant when the valuation is
    /// outside the region of its location already, at the exit instant when it leaves
    /// it later; `None` when it stays inside for ever or an alarm is latched.
    pub fn pending(&self) -> Option<RegionAlarm> {
        if self.alarm.is_some() {
            return None;
        }
        if !self.inside() {
            return Some(self.outside_now(self.since));
        }
        let (d, te, closed, member) = self.next_exit()?;
        let rates = &self.swa.locations[self.loc].rates;
        let at_exit: Vec<Q> = self.v.iter().zip(rates).map(|(x, r)| x + te * r).collect();
        let (crossed, detail) = self.violated(member, &at_exit, rates, closed);
        // The components whose own set the valuation leaves at the same instant (a
        // component's own set is cut to the reachable valuations: it is left too when
        // the clocks leave what is reachable, an open window's bound say).
        let own: Vec<String> = self.regions[self.loc]
            .finish
            .iter()
            .filter(|(_, u)| {
                exit(u, &self.v, rates).flatten().map(|(t, c, _)| (t, c)) == Some((te, closed))
            })
            .map(|(c, _)| self.swa.components[*c].def.name.clone())
            .collect();
        let components = if own.is_empty() { crossed } else { own };
        Some(RegionAlarm {
            at: d,
            kind: RegionAlarmKind::Outside,
            location: self.location().to_string(),
            components,
            detail,
        })
    }

    /// Latches `alarm` (one [`Self::pending`] returned): the monitor freezes until
    /// [`Self::repair`].
    pub fn latch(&mut self, alarm: RegionAlarm) {
        self.alarm = Some(alarm);
    }

    /// Latches an alarm raised by an event (or a valuation outside) at `t`.
    fn raise(&mut self, t: Millis, kind: RegionAlarmKind, components: Vec<String>, detail: String) {
        self.alarm = Some(RegionAlarm {
            at: Deadline {
                at: t,
                after: false,
            },
            kind,
            location: self.location().to_string(),
            components,
            detail,
        });
    }

    /// Lets time run to `t`; returns the alarm raised on the way.
    pub fn advance(&mut self, t: Millis) -> Option<&RegionAlarm> {
        if let Some(alarm) = self.pending()
            && alarm.at.violated_by(t)
        {
            self.alarm = Some(alarm);
            return self.alarm.as_ref();
        }
        self.flow(t);
        None
    }

    /// Moves the valuation to `t` (no check).
    fn flow(&mut self, t: Millis) {
        if t > self.since {
            self.v = self.clocks(t);
            self.since = t;
        }
    }

    /// The constraints of region member `m` that the valuation `u` crosses along `r`.
    fn violated(&self, m: usize, u: &[Q], r: &[Q], closed: bool) -> (Vec<String>, String) {
        let Some(p) = self.regions[self.loc].all.get(m) else {
            return (Vec::new(), String::new());
        };
        let mut comps = Vec::new();
        let mut texts = Vec::new();
        for h in p.half_spaces() {
            let lhs = dot(&h.a, u);
            let slope = dot(&h.a, r);
            let crossing = if closed {
                lhs == h.b && slope.is_positive()
            } else {
                (h.strict && lhs >= h.b) || lhs > h.b
            };
            if !crossing {
                continue;
            }
            for (k, c) in h.a.iter().enumerate() {
                if !c.is_zero() {
                    let name = self.swa.components[self.swa.owner(k)].def.name.clone();
                    if !comps.contains(&name) {
                        comps.push(name);
                    }
                }
            }
            let mut one = Poly::universe(h.a.len());
            one.add(h);
            texts.push(
                Display {
                    poly: &one,
                    names: &self.swa.clocks,
                }
                .to_string(),
            );
        }
        comps.sort();
        (comps, texts.join(" && "))
    }

    /// True when the valuation is in the region of the location.
    fn inside(&self) -> bool {
        self.regions[self.loc]
            .all
            .iter()
            .any(|p| p.contains(&self.v))
    }

    /// The alarm of a valuation outside the region of its location at `t`.
    fn outside_now(&self, t: Millis) -> RegionAlarm {
        let region = &self.regions[self.loc];
        let outside: Vec<usize> = region
            .finish
            .iter()
            .filter(|(_, u)| !u.iter().any(|p| p.contains(&self.v)))
            .map(|(c, _)| *c)
            .collect();
        let comps = if outside.is_empty() {
            self.swa.in_progress(self.loc)
        } else {
            outside
        };
        let components = comps
            .iter()
            .map(|&c| self.swa.components[c].def.name.clone())
            .collect();
        let detail = region
            .all
            .iter()
            .map(|p| {
                Display {
                    poly: p,
                    names: &self.swa.clocks,
                }
                .to_string()
            })
            .collect::<Vec<_>>()
            .join(" || ");
        RegionAlarm {
            at: Deadline {
                at: t,
                after: false,
            },
            kind: RegionAlarmKind::Outside,
            location: self.location().to_string(),
            components,
            detail,
        }
    }

    fn check_inside(&mut self, t: Millis) {
        if self.alarm.is_none() && !self.inside() {
            self.alarm = Some(self.outside_now(t));
        }
    }

    /// Lets time run to `t` and takes the edge of `event`, without checking the region
    /// nor raising any alarm: the caller decides ([`Self::pending`] tells whether the
    /// new valuation is outside). An edge whose guard holds is preferred.
    pub fn take(&mut self, t: Millis, event: &str) -> Taken {
        if self.alarm.is_some() {
            return Taken::Ignored;
        }
        self.flow(t);
        let candidates: Vec<usize> = (0..self.swa.edges.len())
            .filter(|&e| self.swa.edges[e].from == self.loc && self.swa.edges[e].event == event)
            .collect();
        if candidates.is_empty() {
            let parts = &self.swa.locations[self.loc].parts;
            let blocked: Vec<String> = self
                .swa
                .components
                .iter()
                .enumerate()
                .filter(|(ci, c)| c.knows(event) && !c.accepts(parts[*ci], event))
                .map(|(_, c)| c.def.name.clone())
                .collect();
            return if blocked.is_empty() {
                Taken::Ignored
            } else {
                Taken::Blocked(blocked)
            };
        }
        let inside = |e: usize| self.swa.edges[e].guard.contains(&self.v);
        let (e, taken) = match candidates.iter().copied().find(|&e| inside(e)) {
            Some(e) => (e, Taken::Edge),
            None => {
                let edge = &self.swa.edges[candidates[0]];
                let failing: Vec<String> = edge
                    .moves
                    .iter()
                    .filter(|&&(ci, ce)| !self.swa.components[ci].guard(ce).contains(&self.v))
                    .map(|&(ci, _)| self.swa.components[ci].def.name.clone())
                    .collect();
                (candidates[0], Taken::OutsideGuard(failing))
            }
        };
        let edge = &self.swa.edges[e];
        for &r in &edge.resets {
            self.v[r] = Q::zero();
        }
        self.loc = edge.to;
        taken
    }

    /// An observed event at `t`: follows its edge, or raises an alarm. Returns the alarm
    /// raised (by the time that passed or by the event).
    pub fn on_event(&mut self, t: Millis, event: &str) -> Option<&RegionAlarm> {
        if self.alarm.is_some() {
            return None;
        }
        if self.advance(t).is_some() {
            return self.alarm.as_ref();
        }
        let before = self.location().to_string();
        match self.take(t, event) {
            Taken::Ignored | Taken::Edge => {}
            Taken::Blocked(blocked) => {
                if self.options.unexpected {
                    self.raise(t, RegionAlarmKind::Unexpected, blocked, event.to_string());
                    return self.alarm.as_ref();
                }
            }
            Taken::OutsideGuard(failing) => {
                if self.options.check_guards {
                    // The alarm names the location the event came in.
                    self.raise(t, RegionAlarmKind::Guard, failing, event.to_string());
                    if let Some(a) = self.alarm.as_mut() {
                        a.location = before;
                    }
                    return self.alarm.as_ref();
                }
            }
        }
        self.check_inside(t);
        self.alarm.as_ref()
    }

    /// The repair event: back to the initial location, every clock at 0, no alarm.
    pub fn repair(&mut self, t: Millis) {
        self.loc = 0;
        self.v = self.swa.zero();
        self.since = t;
        self.alarm = None;
    }
}
