//! A component with one position (an axis, a tank), abstracted into zones.

use super::{CYCLE_MS, MICRO, SubHazard, compile, input};
use crate::bundle::PlantBundle;
use crate::diag::Problem;
use crate::expr::{Dnf, eval_dnf};
use crate::frame::Frame;
use crate::machine::description::Components;
use crate::machine::kinds::KindDef;
use crate::machine::kinds::axis::EndStop;

/// How the quantity moves: an axis goes at its fastest active drive (opposed drives
/// hold it), a tank at the sum of its running flows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Motion {
    Axis,
    Tank,
}

/// A drive or a flow, compiled.
#[derive(Clone, Debug)]
pub(super) struct Mover {
    pub(super) dnf: Dnf,
    /// Millionths of the unit per ms.
    pub(super) speed: i64,
    /// A flow sensor in series (input index).
    pub(super) sensor: Option<usize>,
}

/// A one-dimensional component, abstracted.
#[derive(Clone, Debug)]
pub(super) struct Line {
    pub(super) motion: Motion,
    pub(super) unit: String,
    /// The cut points, millionths, sorted: zone `2i` is point `i`, zone `2i+1` the open
    /// interval between points `i` and `i+1`.
    pub(super) points: Cuts,
    pub(super) windows: Vec<(usize, i64, i64)>,
    /// An axis's motion sensor.
    pub(super) moving: Option<usize>,
    pub(super) movers: Vec<Mover>,
    /// What the low and high ends do (for a tank: dry run, overflow).
    pub(super) low: EndStop,
    pub(super) high: EndStop,
    pub(super) variation_ppm: i64,
    pub(super) start: usize,
    pub(super) dangers: Vec<(String, i64, i64, Dnf)>,
}

pub(super) fn micro(v: f64) -> i64 {
    (v * MICRO).round() as i64
}

/// The speed of the fastest active drive, and whether drives of both directions are
/// active at once (then they hold it: speed 0).
pub(super) fn fastest(movers: &[Mover], frame: &Frame) -> (i64, bool) {
    let (mut best, mut up, mut down) = (0i64, false, false);
    for m in movers.iter().filter(|m| eval_dnf(&m.dnf, frame)) {
        up |= m.speed > 0;
        down |= m.speed < 0;
        if m.speed.abs() > best.abs() {
            best = m.speed;
        }
    }
    if up && down { (0, true) } else { (best, false) }
}

/// Whether drives of both directions exist: they can be driven against each other.
pub(super) fn opposable(movers: &[Mover]) -> bool {
    movers.iter().any(|m| m.speed > 0) && movers.iter().any(|m| m.speed < 0)
}

/// Zones over sorted cut points: zone `2i` is point `i`, zone `2i+1` the open interval
/// between points `i` and `i+1`. Every sensor window and danger is constant on a zone.
#[derive(Clone, Debug, Default)]
pub(super) struct Cuts(pub(super) Vec<i64>);

impl Cuts {
    pub(super) fn zones(&self) -> usize {
        2 * self.0.len() - 1
    }

    /// The zone's bounds (a point: both the same).
    pub(super) fn bounds(&self, z: usize) -> (i64, i64) {
        (self.0[z / 2], self.0[z.div_ceil(2)])
    }

    pub(super) fn zone_of(&self, p: i64) -> usize {
        match self.0.binary_search(&p) {
            Ok(i) => 2 * i,
            Err(i) => 2 * i - 1,
        }
    }

    pub(super) fn within(&self, z: usize, from: i64, to: i64) -> bool {
        let (lo, hi) = self.bounds(z);
        from <= lo && hi <= to
    }

    pub(super) fn text(&self, z: usize, unit: &str) -> String {
        let (lo, hi) = self.bounds(z);
        let f = |v: i64| v as f64 / MICRO;
        if lo == hi {
            format!("{} {unit}", f(lo))
        } else {
            format!("({}, {}) {unit}", f(lo), f(hi))
        }
    }

    /// The zones a position in zone `z` may reach in one cycle at speed `v`
    /// (millionths per ms, `variation_ppm` faster at most), between zones `low` and
    /// `high`. `rest`: it may stay where it is, even on a point (held by something).
    pub(super) fn reach(
        &self,
        z: usize,
        v: i64,
        variation_ppm: i64,
        (low, high): (usize, usize),
        rest: bool,
    ) -> Vec<usize> {
        if v == 0 {
            return vec![z];
        }
        let reach = v.abs() * (1_000_000 + variation_ppm) / 1_000_000 * CYCLE_MS;
        let (lo, hi) = self.bounds(z);
        let mut out = Vec::new();
        // An interval may be kept (a slow move); a point is left unless it is the end.
        let at_end = (v > 0 && z >= high) || (v < 0 && z <= low);
        if rest || lo != hi || at_end {
            out.push(z);
        }
        if v > 0 {
            for j in z + 1..=high {
                if self.bounds(j).0 - hi > reach {
                    break;
                }
                out.push(j);
            }
        } else {
            for j in (low..z).rev() {
                if lo - self.bounds(j).1 > reach {
                    break;
                }
                out.push(j);
            }
        }
        out
    }
}

impl Line {
    pub(super) fn zones(&self) -> usize {
        self.points.zones()
    }

    pub(super) fn bounds(&self, z: usize) -> (i64, i64) {
        self.points.bounds(z)
    }

    pub(super) fn zone_of(&self, p: i64) -> usize {
        self.points.zone_of(p)
    }

    pub(super) fn within(&self, z: usize, from: i64, to: i64) -> bool {
        self.points.within(z, from, to)
    }

    pub(super) fn text(&self, z: usize) -> String {
        self.points.text(z, &self.unit)
    }

    /// The signed speed (millionths per ms), the hazards of the cycle and the flow
    /// sensors that see their flow run, for the applied outputs in `frame`, in zone `z`.
    pub(super) fn speed(&self, z: usize, frame: &Frame) -> (i64, Vec<SubHazard>, Vec<usize>) {
        let (top, bottom) = (z + 1 == self.zones(), z == 0);
        let mut hazards = Vec::new();
        let mut running = Vec::new();
        match self.motion {
            Motion::Axis => {
                let (best, opposed) = fastest(&self.movers, frame);
                if opposed {
                    hazards.push(SubHazard::OpposedDrives);
                }
                let into = |end: EndStop| end == EndStop::Crash;
                if best > 0 && top && into(self.high) {
                    hazards.push(SubHazard::EndStop("max".into()));
                }
                if best < 0 && bottom && into(self.low) {
                    hazards.push(SubHazard::EndStop("min".into()));
                }
                (best, hazards, running)
            }
            Motion::Tank => {
                let mut net = 0;
                for m in self.movers.iter().filter(|m| eval_dnf(&m.dnf, frame)) {
                    let stopped = (m.speed > 0 && top) || (m.speed < 0 && bottom);
                    if stopped && m.speed > 0 && self.high == EndStop::Crash {
                        hazards.push(SubHazard::Overflow);
                    }
                    if stopped && m.speed < 0 && self.low == EndStop::Crash {
                        hazards.push(SubHazard::DryRun);
                    }
                    if !stopped {
                        net += m.speed;
                        running.extend(m.sensor);
                    }
                }
                hazards.dedup();
                (net, hazards, running)
            }
        }
    }

    /// The zones reachable in one cycle from `z` at speed `v`.
    pub(super) fn next(&self, z: usize, v: i64) -> Vec<usize> {
        self.points
            .reach(z, v, self.variation_ppm, (0, self.zones() - 1), false)
    }

    /// The hazards it can have.
    pub(super) fn hazards(&self) -> Vec<SubHazard> {
        let mut out = Vec::new();
        match self.motion {
            Motion::Axis => {
                if opposable(&self.movers) {
                    out.push(SubHazard::OpposedDrives);
                }
                if self.low == EndStop::Crash {
                    out.push(SubHazard::EndStop("min".into()));
                }
                if self.high == EndStop::Crash {
                    out.push(SubHazard::EndStop("max".into()));
                }
            }
            Motion::Tank => {
                if self.high == EndStop::Crash {
                    out.push(SubHazard::Overflow);
                }
                if self.low == EndStop::Crash {
                    out.push(SubHazard::DryRun);
                }
            }
        }
        out.extend(
            self.dangers
                .iter()
                .map(|d| SubHazard::Declared(d.0.clone())),
        );
        out
    }
}

/// A drive's or a flow's text: condition, speed, flow sensor.
type MoverText<'a> = (&'a str, f64, Option<&'a str>);

/// The abstract line of a component, or `None` for a kind the model does not cover.
pub(super) fn line(
    id: &str,
    kind: &KindDef,
    desc: &Components,
    bundle: &PlantBundle,
) -> Result<Option<Line>, Problem> {
    let (mut l, windows, movers): (Line, &Vec<_>, Vec<MoverText<'_>>) = match kind {
        KindDef::Axis(a) => (
            Line {
                motion: Motion::Axis,
                unit: a.unit.clone(),
                points: Cuts(vec![micro(a.min), micro(a.max), micro(a.start)]),
                windows: Vec::new(),
                moving: a.motion.as_deref().map(|m| input(bundle, m)).transpose()?,
                movers: Vec::new(),
                low: a.end_stops.min,
                high: a.end_stops.max,
                variation_ppm: i64::from(a.variation_ppm),
                start: 0,
                dangers: Vec::new(),
            },
            &a.sensors,
            a.drives
                .iter()
                .map(|d| (d.when.as_str(), d.speed, None))
                .collect(),
        ),
        KindDef::Tank(t) => (
            Line {
                motion: Motion::Tank,
                unit: t.unit.clone(),
                points: Cuts(vec![0, micro(t.capacity), micro(t.start)]),
                windows: Vec::new(),
                moving: None,
                movers: Vec::new(),
                low: t.dry_run,
                high: t.overflow,
                variation_ppm: i64::from(t.variation_ppm),
                start: 0,
                dangers: Vec::new(),
            },
            &t.sensors,
            t.flows
                .iter()
                .map(|f| (f.when.as_str(), f.rate, f.sensor.as_deref()))
                .collect(),
        ),
        _ => return Ok(None),
    };
    for w in windows {
        let (from, to) = (micro(w.from), micro(w.to));
        l.windows.push((input(bundle, &w.signal)?, from, to));
        l.points.0.extend([from, to]);
    }
    for (when, speed, sensor) in movers {
        l.movers.push(Mover {
            dnf: compile(when, bundle)?,
            speed: micro(speed / 1000.0),
            sensor: sensor.map(|s| input(bundle, s)).transpose()?,
        });
    }
    for d in desc.dangers.iter().filter(|d| d.component == id) {
        let (from, to) = (micro(d.from), micro(d.to));
        l.dangers
            .push((d.id.clone(), from, to, compile(&d.when, bundle)?));
        l.points.0.extend([from, to]);
    }
    let (lo, hi) = (l.points.0[0], l.points.0[1]);
    let start = l.points.0[2];
    l.points.0.retain(|p| (lo..=hi).contains(p));
    l.points.0.sort_unstable();
    l.points.0.dedup();
    l.start = l.zone_of(start);
    Ok(Some(l))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 60 mm cylinder with windows [0, 2] and [58, 60] at 120 mm/s (1.2 mm a cycle).
    fn cylinder() -> Line {
        Line {
            motion: Motion::Axis,
            unit: "mm".into(),
            points: Cuts([0.0, 2.0, 58.0, 60.0].map(micro).to_vec()),
            windows: vec![(0, micro(0.0), micro(2.0)), (1, micro(58.0), micro(60.0))],
            moving: None,
            movers: Vec::new(),
            low: EndStop::Rest,
            high: EndStop::Crash,
            variation_ppm: 0,
            start: 0,
            dangers: Vec::new(),
        }
    }

    #[test]
    fn zones_are_the_points_and_the_intervals_between_them() {
        let l = cylinder();
        assert_eq!(l.zones(), 7);
        assert_eq!(l.zone_of(0), 0);
        assert_eq!(l.zone_of(micro(1.0)), 1);
        assert_eq!(l.zone_of(micro(2.0)), 2);
        assert_eq!(l.zone_of(micro(30.0)), 3);
        assert_eq!(l.zone_of(micro(60.0)), 6);
        // A window is on exactly on the zones inside it.
        let on: Vec<bool> = (0..7).map(|z| l.within(z, 0, micro(2.0))).collect();
        assert_eq!(on, [true, true, true, false, false, false, false]);
        assert_eq!(l.text(3), "(2, 58) mm");
    }

    #[test]
    fn a_cycle_moves_as_far_as_the_speed_reaches_and_never_rests_on_a_point() {
        let l = cylinder();
        let v = micro(120.0 / 1000.0);
        // From the point 0: into (0, 2); 2 is 2 mm away, beyond a cycle's 1.2 mm.
        assert_eq!(l.next(0, v), vec![1]);
        // From (0, 2): stay, reach 2, or cross it into (2, 58) (the far edge is 2).
        assert_eq!(l.next(1, v), vec![1, 2, 3]);
        // From the point 2: leave it.
        assert_eq!(l.next(2, v), vec![3]);
        // From (2, 58): stay, 58, or past it into (58, 60); not 60 (2 mm away).
        assert_eq!(l.next(3, v), vec![3, 4, 5]);
        // At the end it stays (driven into it).
        assert_eq!(l.next(6, v), vec![6]);
        assert_eq!(l.next(6, -v), vec![5]);
        assert_eq!(l.next(3, 0), vec![3]);
        // Fast enough to skip a window: a 2 mm window at 300 mm/s (3 mm a cycle).
        let fast = micro(300.0 / 1000.0);
        assert_eq!(l.next(3, fast), vec![3, 4, 5, 6]);
    }
}
