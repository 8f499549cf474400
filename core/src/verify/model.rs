//! The abstract plant: the emulator's geometry on a grid of cells, one cell of travel per
//! step, the turntable angle advanced by the distance-equivalent of one step.
//!
//! Everything here is derived from the [`Layout`]: the cell is the greatest common
//! divisor of every length the sensors, joints and boxes depend on, so that each
//! sensor, each joint and each box end falls on a cell boundary and the sensors switch
//! exactly at step boundaries. The dynamics mirror `emulator/dynamics.rs` at the
//! granularity of a step: rotation, drive (surface under the centre, else the other
//! surface by more than the straddle margin), blocking and collisions, transfer
//! (delivery or drop), shear and push hazards, arrivals.

use crate::diag::Problem;
use crate::diag::codes;
use crate::emulator::{BoxSize, HazardKind, Layout, SensorKind};
use crate::plant::Plant;
use serde::Serialize;

/// Largest number of boxes the model holds at once.
pub const MAX_BOXES: usize = 4;

/// One box of the abstract model: size and position of its rear (`lo`) in cells, in the
/// line frame (conveyor chain, then the table at the loading angle) or the table frame
/// (`v = u + half`, beyond the table ends: the exits at the unloading angle).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct ABox {
    /// Table frame rather than line frame.
    pub on_table: bool,
    /// Rear end, cells.
    pub lo: i16,
    /// Large rather than small.
    pub large: bool,
}

/// The plant part of an abstract state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct PlantState {
    /// Table angle, µdeg.
    pub angle: i32,
    /// Number of boxes in use.
    pub n: u8,
    /// Boxes, sorted (`[..n]`), the rest default.
    pub boxes: [ABox; MAX_BOXES],
}

/// What happened during one step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepEvents {
    /// First hazard of the step, if any.
    pub hazard: Option<HazardKind>,
    /// A box was delivered to the exit at the table's end (+u, left at the station).
    pub delivered_plus: bool,
    /// A box was delivered to the exit at the table's start (−u, right at the station).
    pub delivered_minus: bool,
}

/// A presence sensor: input index, frame, position in cells, large boxes only.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Probe {
    pub(crate) input: usize,
    pub(crate) on_table: bool,
    pub(crate) at: i32,
    pub(crate) large_only: bool,
}

/// The model's geometry, in cells and µdeg per step.
#[derive(Clone, Debug, Serialize)]
pub struct Geometry {
    /// Cell length, mm (one step of travel).
    pub cell_mm: i64,
    /// Duration of one step, µs.
    pub step_us: i64,
    /// Joints of the conveyor chain, cells from the source start: the end of each conveyor.
    pub joints: Vec<i32>,
    /// Table length, cells.
    pub table_len: i32,
    /// Box lengths (small, large), cells.
    pub box_len: [i32; 2],
    /// Straddle margin and shear margin, mm.
    pub margin_mm: i64,
    /// Shear margin, mm.
    pub shear_mm: i64,
    /// Loading and unloading angles, µdeg.
    pub load: i32,
    /// Unloading angle, µdeg.
    pub unload: i32,
    /// Docking tolerance, µdeg: within it of an angle the table is joined to the
    /// conveyors there (as in the emulator).
    pub dock_tol: i32,
    /// Rotation per step out and back, µdeg.
    pub rot_out: i32,
    /// Rotation per step back, µdeg.
    pub rot_back: i32,
    /// Output index of each chain conveyor's actuator.
    #[serde(skip)]
    pub(crate) chain_act: Vec<usize>,
    /// Output indices of the rollers (+u, −u) and the rotation.
    #[serde(skip)]
    pub(crate) plus: usize,
    #[serde(skip)]
    pub(crate) minus: usize,
    #[serde(skip)]
    pub(crate) rotate: usize,
    /// Exit conveyors' actuators (forced on, as in seed 004 §6.1).
    #[serde(skip)]
    pub(crate) exit_act: Vec<usize>,
    #[serde(skip)]
    pub(crate) probes: Vec<Probe>,
    /// Angle sensors: input, window in µdeg.
    #[serde(skip)]
    pub(crate) angles: Vec<(usize, i32, i32)>,
    /// Free length the source needs before a new box appears, cells beyond the box.
    pub spawn_gap: i32,
    /// Sensors of the plant the model never sets (beyond the first box length of an exit).
    pub unmodelled_sensors: Vec<String>,
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a.abs() } else { gcd(b, a % b) }
}

/// Length of a conveyor, mm.
fn conveyor_len(c: &crate::emulator::Conveyor) -> i64 {
    let (dx, dy) = (c.end.x - c.start.x, c.end.y - c.start.y);
    ((dx * dx + dy * dy) as f64).sqrt().round() as i64
}

/// The chain of conveyors from the source, in order.
fn conveyor_chain(layout: &Layout) -> Result<Vec<usize>, Problem> {
    let mut chain = Vec::new();
    let mut cur = layout
        .conveyors
        .iter()
        .position(|c| c.id == layout.source.conveyor)
        .ok_or_else(|| unsupported("the source conveyor is not in the layout"))?;
    loop {
        if chain.contains(&cur) {
            return Err(unsupported("the conveyor chain loops"));
        }
        chain.push(cur);
        let end = layout.conveyors[cur].end;
        match layout.conveyors.iter().position(|c| c.start == end) {
            Some(n) => cur = n,
            None => break,
        }
    }
    Ok(chain)
}

/// The exit conveyors at the table's + and − ends at the unloading angle, once the chain
/// is checked to end at the table's −u end at the loading angle.
fn table_exits(layout: &Layout, chain: &[usize]) -> Result<(usize, usize), Problem> {
    let t = &layout.table;
    let rad = |mdeg: i32| (f64::from(mdeg) / 1000.0).to_radians();
    let table_end = |mdeg: i32, plus: bool| {
        let a = rad(mdeg);
        let s = if plus { 1.0 } else { -1.0 } * t.half_length_mm as f64;
        (
            t.center.x as f64 + s * a.cos(),
            t.center.y as f64 + s * a.sin(),
        )
    };
    let close =
        |p: crate::emulator::Point, q: (f64, f64)| (p.x as f64 - q.0).hypot(p.y as f64 - q.1) < 1.0;
    let last = layout.conveyors[*chain.last().unwrap_or(&0)].end;
    if !close(last, table_end(t.loading_mdeg, false)) {
        return Err(unsupported(
            "the conveyor chain must end at the table's -u end at the loading angle",
        ));
    }
    let exit_at = |plus: bool| {
        layout
            .conveyors
            .iter()
            .position(|c| close(c.start, table_end(t.unloading_mdeg, plus)))
    };
    let (Some(exit_plus), Some(exit_minus)) = (exit_at(true), exit_at(false)) else {
        return Err(unsupported(
            "the table needs an exit conveyor at each end at the unloading angle",
        ));
    };
    Ok((exit_plus, exit_minus))
}

/// Where the sensors are: presence probes (mm), angle windows, sensors not modelled.
struct SensorPlaces {
    probes_mm: Vec<(usize, bool, i64, bool)>,
    angles: Vec<(usize, i32, i32)>,
    unmodelled: Vec<String>,
}

/// Places the sensors on the chain and the table; their positions join `lens`.
fn place_sensors(
    layout: &Layout,
    plant: &Plant,
    chain: &[usize],
    (exit_plus, exit_minus): (usize, usize),
    lens: &mut Vec<i64>,
) -> SensorPlaces {
    let t = &layout.table;
    let dims = [layout.source.small, layout.source.large];
    let max_box = dims.iter().map(|d| d.length_mm).max().unwrap_or(0);
    let len_of = conveyor_len;
    let mut probes_mm: Vec<(usize, bool, i64, bool)> = Vec::new();
    let mut unmodelled = Vec::new();
    let mut angles = Vec::new();
    for s in &layout.sensors {
        let Some(input) = plant.input(&s.id) else {
            continue;
        };
        match &s.kind {
            SensorKind::Angle { min_mdeg, max_mdeg } => {
                angles.push((input, min_mdeg * 1000, max_mdeg * 1000));
            }
            SensorKind::Presence { part, at_mm, beam } => {
                let large_only = matches!(beam, crate::emulator::Beam::High)
                    && dims[0].height_mm < layout.high_beam_mm;
                if dims[1].height_mm < layout.high_beam_mm
                    && matches!(beam, crate::emulator::Beam::High)
                {
                    unmodelled.push(s.id.clone());
                    continue;
                }
                if *part == t.id {
                    probes_mm.push((input, true, at_mm + t.half_length_mm, large_only));
                    lens.push(at_mm + t.half_length_mm);
                } else if let Some(k) = chain.iter().position(|&c| layout.conveyors[c].id == *part)
                {
                    let base: i64 = chain[..k]
                        .iter()
                        .map(|&c| len_of(&layout.conveyors[c]))
                        .sum();
                    probes_mm.push((input, false, base + at_mm, large_only));
                    lens.push(*at_mm);
                } else if layout.conveyors[exit_plus].id == *part && *at_mm < max_box {
                    probes_mm.push((input, true, 2 * t.half_length_mm + at_mm, large_only));
                    lens.push(*at_mm);
                } else if layout.conveyors[exit_minus].id == *part && *at_mm < max_box {
                    probes_mm.push((input, true, -at_mm, large_only));
                    lens.push(*at_mm);
                } else {
                    unmodelled.push(s.id.clone());
                }
            }
        }
    }
    // In the plant's order, whatever order the layout lists its sensors in.
    unmodelled.sort_by_key(|id| plant.input(id));
    SensorPlaces {
        probes_mm,
        angles,
        unmodelled,
    }
}

fn unsupported(msg: impl Into<String>) -> Problem {
    Problem::error(codes::VERIFY_UNSUPPORTED.id, msg.into(), None)
}

impl Geometry {
    /// Derives the grid from a layout. The supported shape is the sorting station's: a
    /// chain of conveyors from the source to the table's −u end at the loading angle, and
    /// at the unloading angle one exit conveyor at each table end; all surfaces at the
    /// same speed.
    pub fn new(layout: &Layout, plant: &Plant) -> Result<Self, Problem> {
        let t = &layout.table;
        let speed = t.roller_speed_mm_s;
        if speed <= 0 || layout.conveyors.iter().any(|c| c.speed_mm_s != speed) {
            return Err(unsupported(
                "the verifier needs every surface at the same speed",
            ));
        }
        let len_of = conveyor_len;
        // Chain from the source.
        let chain = conveyor_chain(layout)?;
        let (exit_plus, exit_minus) = table_exits(layout, &chain)?;
        let dims = [layout.source.small, layout.source.large];
        // Lengths that must fall on cell boundaries.
        let mut lens: Vec<i64> = vec![2 * t.half_length_mm];
        lens.extend(chain.iter().map(|&c| len_of(&layout.conveyors[c])));
        lens.extend(dims.iter().map(|d| d.length_mm));
        let SensorPlaces {
            probes_mm,
            angles,
            unmodelled,
        } = place_sensors(layout, plant, &chain, (exit_plus, exit_minus), &mut lens);
        let cell = lens.iter().fold(0, |g, &l| gcd(g, l));
        if cell <= 0 {
            return Err(unsupported("degenerate layout lengths"));
        }
        let cells = |mm: i64| (mm / cell) as i32;
        let mut joints = Vec::new();
        let mut acc = 0;
        for &c in &chain {
            acc += len_of(&layout.conveyors[c]);
            joints.push(cells(acc));
        }
        let step_us = cell * 1_000_000 / speed;
        let per_step = |udeg_ms: i64| (udeg_ms * cell * 1000 / speed) as i32;
        let out = |id: &str| {
            plant
                .output(id)
                .ok_or_else(|| unsupported(format!("no output `{id}` in the plant")))
        };
        let box_len = [cells(dims[0].length_mm), cells(dims[1].length_mm)];
        Ok(Self {
            cell_mm: cell,
            step_us,
            joints,
            table_len: cells(2 * t.half_length_mm),
            box_len,
            margin_mm: layout.straddle_margin_mm,
            shear_mm: layout.shear_margin_mm,
            load: t.loading_mdeg * 1000,
            unload: t.unloading_mdeg * 1000,
            dock_tol: t.dock_tolerance_mdeg.max(0) * 1000,
            rot_out: per_step(t.out_speed_udeg_ms),
            rot_back: per_step(t.back_speed_udeg_ms),
            chain_act: chain
                .iter()
                .map(|&c| out(&layout.conveyors[c].actuator))
                .collect::<Result<_, _>>()?,
            plus: out(&t.plus_actuator)?,
            minus: out(&t.minus_actuator)?,
            rotate: out(&t.rotate_actuator)?,
            exit_act: vec![
                out(&layout.conveyors[exit_plus].actuator)?,
                out(&layout.conveyors[exit_minus].actuator)?,
            ],
            probes: probes_mm
                .into_iter()
                .map(|(input, on_table, at, large_only)| Probe {
                    input,
                    on_table,
                    at: cells(at),
                    large_only,
                })
                .collect(),
            angles,
            // The emulator spawns when the source start is free by the box length + 10 mm.
            spawn_gap: ((10 + cell - 1) / cell) as i32,
            unmodelled_sensors: unmodelled,
        })
    }

    fn line_end(&self) -> i32 {
        self.joints.last().copied().unwrap_or(0)
    }

    /// Length of a box, cells.
    pub fn len(&self, b: &ABox) -> i32 {
        self.box_len[usize::from(b.large)]
    }

    /// Overhang (cells) greater than the margin (mm).
    fn over(&self, cells: i32, margin_mm: i64) -> bool {
        i64::from(cells) * self.cell_mm > margin_mm
    }

    /// Where the table stands: 0 loading, 1 unloading, 2 elsewhere.
    pub fn pos(&self, angle: i32) -> u8 {
        if (angle - self.load).abs() <= self.dock_tol {
            0
        } else if (angle - self.unload).abs() <= self.dock_tol {
            1
        } else {
            2
        }
    }

    /// Sensor values of a plant state, one bit per input index.
    pub fn sensors(&self, s: &PlantState) -> u64 {
        let mut m = 0u64;
        for &(i, lo, hi) in &self.angles {
            if (lo..=hi).contains(&s.angle) {
                m |= 1 << i;
            }
        }
        let at_load = self.pos(s.angle) == 0;
        let te = self.line_end();
        for b in &s.boxes[..usize::from(s.n)] {
            let (lo, hi) = (i32::from(b.lo), i32::from(b.lo) + self.len(b));
            for p in &self.probes {
                if p.large_only && !b.large {
                    continue;
                }
                // Table probes are seen by line-frame boxes while the table is at the
                // loading angle (the frames coincide there).
                // Feed-line probes see a box over `(lo, hi]`: boxes there only travel
                // forward, so the rear edge leaves the beam within the step that starts
                // with it on the beam; this keeps a one-cell gap between two boxes
                // visible, as a PLC cycle much shorter than a step sees it.
                let at = match (p.on_table, b.on_table) {
                    (false, false) => {
                        if lo < p.at && p.at <= hi {
                            m |= 1 << p.input;
                        }
                        continue;
                    }
                    (true, true) => p.at,
                    (true, false) if at_load && p.at >= 0 && p.at <= self.table_len => p.at + te,
                    _ => continue,
                };
                if lo <= at && at <= hi {
                    m |= 1 << p.input;
                }
            }
        }
        m
    }

    /// Initial state: table at the loading angle, no box.
    pub fn initial(&self) -> PlantState {
        PlantState {
            angle: self.load,
            ..PlantState::default()
        }
    }

    /// Part boundaries of a frame at a table position: `(bounds, open_start, open_end)`;
    /// part k spans `bounds[k]..bounds[k+1]`.
    fn parts(&self, on_table: bool, pos: u8) -> Bounds {
        let mut b = Bounds { v: [0; 10], n: 0 };
        let mut push = |x: i32| {
            if b.n < b.v.len() {
                b.v[b.n] = x;
                b.n += 1;
            }
        };
        if on_table {
            if pos == 1 {
                for x in [i32::MIN / 4, 0, self.table_len, i32::MAX / 4] {
                    push(x);
                }
            } else {
                push(0);
                push(self.table_len);
            }
        } else {
            push(0);
            for &j in &self.joints {
                push(j);
            }
            if pos == 0 {
                push(self.line_end() + self.table_len);
            }
        }
        b
    }

    /// Surface velocity (cells per step along the frame axis) of part `k` of a frame.
    fn vel(&self, on_table: bool, pos: u8, k: usize, out: u64) -> i32 {
        let on = |i: usize| i32::from(out >> i & 1 == 1);
        let table = on(self.plus) - on(self.minus);
        if on_table {
            if pos == 1 {
                // The exits run away from the table while their output acts (the
                // control always commands them; a released supply stops them).
                match k {
                    0 => -on(self.exit_act[1]),
                    1 => table,
                    _ => on(self.exit_act[0]),
                }
            } else {
                table
            }
        } else if k < self.chain_act.len() {
            on(self.chain_act[k])
        } else {
            table
        }
    }

    /// One step with the outputs that act `out`; `arrival` puts a new box at the source;
    /// `frozen`: the rotation's supply is released (the table stays where it is).
    /// Returns the successor and the events; a hazard ends the exploration of a path.
    pub fn step(
        &self,
        s: &PlantState,
        (out, frozen): (u64, bool),
        arrival: Option<BoxSize>,
    ) -> (PlantState, StepEvents) {
        let mut ev = StepEvents::default();
        let mut all = s.boxes;
        let boxes = &mut all[..usize::from(s.n)];
        // Rotation.
        let a4 = out >> self.rotate & 1 == 1;
        let target = if a4 { self.unload } else { self.load };
        let old = s.angle;
        let angle = if frozen {
            old
        } else if target > old {
            (old + self.rot_out).min(target)
        } else if target < old {
            (old - self.rot_back).max(target)
        } else {
            old
        };
        let _moving = angle != old;
        let (p0, p1) = (self.pos(old), self.pos(angle));
        let te = self.line_end();
        if p0 == 0 && p1 != 0 {
            // Leaving the loading angle: boxes centred on the table turn with it.
            for b in boxes.iter_mut() {
                let c2 = 2 * i32::from(b.lo) + self.len(b);
                if !b.on_table && c2 > 2 * te {
                    b.on_table = true;
                    b.lo -= te as i16;
                }
            }
        } else if p1 == 0 && p0 != 0 {
            for b in boxes.iter_mut() {
                if b.on_table {
                    b.on_table = false;
                    b.lo += te as i16;
                }
            }
        }
        // Drive.
        let vels = self.drive(boxes, p1, out);
        // Blocking (one cell per step: a blocked box stays).
        self.block(boxes, &vels, &mut ev);
        // Transfer: drops and deliveries.
        let mut kept_a = [ABox::default(); MAX_BOXES];
        let mut nk = 0usize;
        for &b in boxes.iter() {
            let (lo, l) = (i32::from(b.lo), self.len(&b));
            let c2 = 2 * lo + l;
            let bounds = self.parts(b.on_table, p1);
            let bounds = bounds.as_slice();
            let (first, last) = (bounds[0], bounds[bounds.len() - 1]);
            if c2 > 2 * last || c2 < 2 * first {
                ev.hazard.get_or_insert(HazardKind::Dropped);
                continue;
            }
            if b.on_table && p1 == 1 {
                // On an exit, past every modelled exit sensor: gone to the elevator.
                let beyond_plus = lo > self.table_len
                    && self
                        .probes
                        .iter()
                        .all(|p| !p.on_table || p.at < lo || p.at <= self.table_len);
                let beyond_minus = lo + l < 0
                    && self
                        .probes
                        .iter()
                        .all(|p| !p.on_table || p.at > lo + l || p.at >= 0);
                if beyond_plus {
                    ev.delivered_plus = true;
                    continue;
                }
                if beyond_minus {
                    ev.delivered_minus = true;
                    continue;
                }
            }
            kept_a[nk] = b;
            nk += 1;
        }
        let kept = &mut kept_a[..nk];
        // Shear and push.
        self.shear_and_push(kept, p0, p1, out, &mut ev);
        // Arrival at the source start.
        if let Some(size) = arrival {
            let nb = ABox {
                on_table: false,
                lo: 0,
                large: size == BoxSize::Large,
            };
            let l = self.len(&nb);
            let free = kept.iter().all(|b| {
                b.on_table
                    || i32::from(b.lo) >= l + self.spawn_gap
                    || i32::from(b.lo) >= self.joints[0]
            });
            if free && nk < MAX_BOXES {
                kept_a[nk] = nb;
                nk += 1;
            }
        }
        let kept = &mut kept_a[..nk];
        kept.sort_unstable();
        let mut next = PlantState {
            angle,
            n: nk as u8,
            boxes: [ABox::default(); MAX_BOXES],
        };
        next.boxes[..nk].copy_from_slice(kept);
        (next, ev)
    }

    /// The speed of each box: its part's, or a neighbour's under it by more than the margin.
    fn drive(&self, boxes: &[ABox], p1: u8, out: u64) -> [i32; MAX_BOXES] {
        let mut vels = [0i32; MAX_BOXES];
        for (bi, b) in boxes.iter().enumerate() {
            let bounds = self.parts(b.on_table, p1);
            let bounds = bounds.as_slice();
            let (lo, l) = (i32::from(b.lo), self.len(b));
            let c2 = 2 * lo + l;
            let k = part_of(bounds, c2);
            let mut v = self.vel(b.on_table, p1, k, out);
            if v == 0 {
                // Other surface under the box by more than the margin.
                if k > 0 && self.over(bounds[k] - lo, self.margin_mm) {
                    v = self.vel(b.on_table, p1, k - 1, out);
                }
                if v == 0
                    && k + 2 < bounds.len()
                    && self.over(lo + l - bounds[k + 1], self.margin_mm)
                {
                    v = self.vel(b.on_table, p1, k + 1, out);
                }
            }
            vels[bi] = v;
        }
        vels
    }

    /// Moves the boxes by their speeds; a box that would overlap another stays, a collision
    /// when the other does not move away fast enough.
    fn block(&self, boxes: &mut [ABox], vels: &[i32; MAX_BOXES], ev: &mut StepEvents) {
        let mut new = [0i32; MAX_BOXES];
        for (i, b) in boxes.iter().enumerate() {
            new[i] = i32::from(b.lo) + vels[i];
        }
        let mut blocker = [usize::MAX; MAX_BOXES];
        for _ in 0..=boxes.len() {
            let mut changed = false;
            for i in 0..boxes.len() {
                if vels[i] == 0 || new[i] == i32::from(boxes[i].lo) {
                    continue;
                }
                for j in 0..boxes.len() {
                    if i == j || boxes[i].on_table != boxes[j].on_table {
                        continue;
                    }
                    let (li, lj) = (self.len(&boxes[i]), self.len(&boxes[j]));
                    if new[i] < new[j] + lj && new[j] < new[i] + li {
                        new[i] = i32::from(boxes[i].lo);
                        blocker[i] = j;
                        changed = true;
                        break;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        for i in 0..boxes.len() {
            let j = blocker[i];
            if j != usize::MAX && new[i] == i32::from(boxes[i].lo) {
                let dj = (new[j] - i32::from(boxes[j].lo)) * vels[i].signum();
                if dj < vels[i].abs() {
                    ev.hazard.get_or_insert(HazardKind::Collision);
                }
            }
        }
        for (b, n) in boxes.iter_mut().zip(&new) {
            b.lo = *n as i16;
        }
    }

    /// Shear hazards while rotating, and boxes pushed against a stopped surface.
    fn shear_and_push(&self, kept: &[ABox], p0: u8, p1: u8, out: u64, ev: &mut StepEvents) {
        let rotating = p0 == 2 || p1 == 2;
        for b in kept.iter() {
            let (lo, l) = (i32::from(b.lo), self.len(b));
            let c2 = 2 * lo + l;
            let bounds = self.parts(b.on_table, p1);
            let bounds = bounds.as_slice();
            let k = part_of(bounds, c2);
            let n_parts = bounds.len() - 1;
            // Which ends of part k are table-side: in the line frame the end of the last
            // conveyor and both table ends; in the table frame every end at the table.
            let table_side = |end_plus: bool| -> bool {
                if b.on_table {
                    if p1 == 1 {
                        (k == 1) || (k == 0 && end_plus) || (k == 2 && !end_plus)
                    } else {
                        true
                    }
                } else {
                    let tk = self.joints.len(); // index of the table part at load
                    (k + 1 == tk && end_plus) || k == tk
                }
            };
            for end_plus in [false, true] {
                let over = if end_plus {
                    lo + l - bounds[k + 1]
                } else {
                    bounds[k] - lo
                };
                if over <= 0 {
                    continue;
                }
                if rotating && self.over(over, self.shear_mm) && table_side(end_plus) {
                    ev.hazard.get_or_insert(HazardKind::Sheared);
                }
                let q = if end_plus {
                    (k + 1 < n_parts).then_some(k + 1)
                } else {
                    k.checked_sub(1)
                };
                let Some(q) = q else { continue };
                if !self.over(over, self.margin_mm) || !self.over(l - over, self.margin_mm) {
                    continue;
                }
                let dir = if end_plus { 1 } else { -1 };
                let vp = self.vel(b.on_table, p1, k, out) * dir;
                let vq = self.vel(b.on_table, p1, q, out) * dir;
                if (vp > 0 && vq <= 0) || (vq < 0 && vp >= 0) {
                    ev.hazard.get_or_insert(HazardKind::PushedAgainstStopped);
                }
            }
        }
    }

    /// True when a new box of `size` can appear at the source now.
    pub fn can_spawn(&self, s: &PlantState, size: BoxSize) -> bool {
        let l = self.box_len[usize::from(size == BoxSize::Large)];
        s.boxes[..usize::from(s.n)]
            .iter()
            .all(|b| b.on_table || i32::from(b.lo) >= l + self.spawn_gap)
    }
}

/// Part boundaries of a frame, on the stack.
struct Bounds {
    v: [i32; 10],
    n: usize,
}

impl Bounds {
    fn as_slice(&self) -> &[i32] {
        &self.v[..self.n]
    }
}

/// Index of the part whose span holds a centre at `c2 / 2` (a centre on a boundary
/// belongs to the part before it, as the emulator transfers on `c > len`).
fn part_of(bounds: &[i32], c2: i32) -> usize {
    let n = bounds.len() - 1;
    for k in 0..n {
        if c2 <= 2 * bounds[k + 1] {
            return k;
        }
    }
    n - 1
}
