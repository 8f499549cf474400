//! The deterministic plant emulator ("partie opérative") of the box-sorting station.
//!
//! The geometry comes from `layouts/sorting-station/layout.ron` ([`Layout`]), the one
//! source of truth shared with the synoptic. Time is integer milliseconds passed in by
//! the caller; positions are integer micrometres along each part; randomness (arrival
//! jitter, size mix, ±0.3 % turntable speed per rotation) comes from the seed.
//!
//! # Model
//!
//! Every conveyor and the turntable is a 1-D axis; ends closer than 1 mm are joined
//! (the table's ends only while it stands exactly at the loading or unloading angle).
//! A box moves with the drive of the surface under its centre (or, if that one is
//! stopped, with the other surface it lies on by more than `straddle_margin_mm`); boxes
//! on the table turn with it. Boxes block each other on contact. A box whose centre
//! passes an end where nothing continues falls; one passing an exit end is delivered.
//! The corners of the table sweeping over the exit conveyors are not modelled.
//!
//! # Geometry of the sorting station, and why (seed 004, section 6)
//!
//! Boxes are 300 mm (small, 200 mm high) and 380 mm (large, 320 mm high) square; the
//! high beam is at 250 mm. All surfaces run at 300 mm/s (0.3 mm/ms).
//!
//! - Entry conveyor A0, x 0→1200 at y = 0; C0 at 1180 mm: a box front reaches C0 67 ms
//!   (more than two 10 ms PLC cycles) before the joint, so CSc1 stops A0 in time.
//! - Intermediate conveyor A1, x 1200→2400; C1 (low) and C2 (high) at 100 mm,
//!   so C0–C1 = 120 mm < 300 mm (observer 2P); C3 at 1180 mm (CSs2, CSc2 act 67 ms
//!   before the joint).
//! - Turntable centred at (2650, 0), u ∈ [−250, 250]; at 0° its −u end meets A1's end
//!   and +u points at nothing; at 90° +u meets the left exit A5 (y 250→1600) and −u the
//!   right exit A6 (y −250→−1600). C6 is on the table at u = +150: a box stops with its
//!   front there, fully on the table (large: rear at u = −230).
//! - C7 (right) and C8 (left) at 20 mm along their exits; C9 and C10 at 1330 mm.
//!   [C3, C6] = 420 mm and [C6, C7] = 420 mm exceed the largest box (observers P36, P67);
//!   [C6, C8] = 120 mm is shorter than the smallest box. When C7/C8 falls the box rear
//!   is 20 mm past the table edge.
//! - Rotation: 30 mdeg/ms out, 29.7 mdeg/ms back (±0.3 % per rotation); C4 = angle ≤ 3.6°,
//!   C5 = angle ≥ 87.75°. After A4 rises, C4 falls at ~120 ms and C5 rises at ~2925 ms;
//!   after A4 falls, C5 falls at ~76 ms and C4 rises at ~2909 ms (intervals I2, I4, I7, I9).
//! - Hazard margins: a box is pushed against a stopped surface when it lies more than
//!   25 mm on each (so a box whose rear just left C0 or C3 is not), and is sheared when
//!   it passes the table edge by more than 2 mm while the table turns.

mod dynamics;
pub(crate) mod faults;
mod layout;
mod model;
mod training;

pub use faults::{FaultKind, FaultSpec, Position, Trigger};
pub(crate) use layout::quoted_positions;
pub use layout::{
    ArrivalPlan, Beam, BoxDims, BoxSize, Conveyor, Elevator, Layout, Point, SensorDef, SensorKind,
    Side, SizeMix, Source, Turntable,
};
pub use model::{BoxState, BoxStats, BoxView, Hazard, HazardKind, Place};
pub use training::{NamedFault, PlantExercise, load_exercises, load_faults};

use crate::bits::Bits;
use crate::diag::Problem;
use crate::diag::codes;
use crate::frame::Frame;
use crate::plant::Plant;
use crate::symbols::Symbols;
use crate::synthetic::SplitMix64;
use crate::time::Millis;
use faults::{Overrides, Scheduled};
use model::{Body, Part, TablePos};
use std::collections::VecDeque;

/// A presence sensor, precomputed: layout sensor index, position (µm), least height.
#[derive(Clone, Copy, Debug)]
struct Probe {
    sensor: u8,
    at: i64,
    min_height: i64,
}

/// The plant emulator. Cheap to clone (the explanation engine projects forward on copies).
#[derive(Clone, Debug)]
pub struct Emulator {
    layout: Layout,
    parts: Vec<Part>,
    table: usize,
    /// Presence probes per part.
    probes: Vec<Vec<Probe>>,
    /// Angle sensors: layout sensor index, window in µdeg.
    angles: Vec<(u8, i64, i64)>,
    /// Plant input index of each layout sensor.
    sensor_plant: Vec<usize>,
    /// Plant output index of each actuator role: conveyors, then A2, A3, A4.
    role_plant: Vec<usize>,
    symbols: Symbols,
    step_ms: u64,
    now: u64,
    carry: u64,
    cmd: u64,
    angle: i64,
    rot_speed: i64,
    rot_dir: i64,
    moving: bool,
    /// Take every internal step one by one (tests compare both ways).
    no_skip: bool,
    /// The command the velocities were last computed for.
    driven: Option<u64>,
    pos: TablePos,
    links: Vec<[Option<model::Link>; 2]>,
    vel: Vec<i64>,
    /// Per part, a bit per part joined to it (itself included).
    near: Vec<u64>,
    source_part: Option<usize>,
    bodies: Vec<Body>,
    scratch: Vec<(i64, i64, i64)>,
    done: Vec<(BoxView, u64)>,
    views: Vec<BoxView>,
    sensor_raw: u64,
    sensor_mask: u64,
    sensors: Bits,
    hazards: Vec<Hazard>,
    stats: BoxStats,
    next_id: u32,
    rng_arrivals: SplitMix64,
    rng_table: SplitMix64,
    plan: ArrivalPlan,
    arrival_k: u64,
    plan_origin: u64,
    next_arrival: Option<(u64, BoxSize)>,
    pending: VecDeque<BoxSize>,
    faults: Vec<Scheduled>,
    fault_problems: Vec<Problem>,
    overrides: Overrides,
    slow: Vec<u8>,
    frame: Frame,
    has_conditions: bool,
    /// Safety contactors (`supplies` in `plant.ron`): the contactor's role, and the
    /// roles it powers.
    supply: Vec<(usize, u64)>,
    /// Mirror contacts (`feedback_of`): the plant input, the role of the actuator it
    /// mirrors (`None`: not a drive of the layout, the output itself), its output.
    feedback: Vec<(usize, Option<u8>, usize)>,
}

impl Emulator {
    /// Builds an emulator at time 0, table at the loading angle, no box; arrivals follow
    /// the layout's plan. Fails when the layout names a signal the plant lacks.
    pub fn new(layout: &Layout, plant: &Plant, seed: u64) -> Result<Self, Problem> {
        if let Some(p) = layout
            .check()
            .into_iter()
            .chain(layout.check_signals(plant))
            .next()
        {
            return Err(p);
        }
        let parts = model::build_parts(layout);
        let table = parts.len() - 1;
        let (probes, angles, sensor_plant) = sensor_probes(layout, plant, table, parts.len());
        let t = &layout.table;
        let role_plant = roles(layout, plant);
        let symbols = plant.symbols();
        let frame = Frame::new(symbols.sizes());
        let n_roles = role_plant.len();
        let n_parts = parts.len();
        let role_of = |o: usize| role_plant.iter().position(|&r| r == o).map(|r| r as u8);
        let supply = plant
            .supplies()
            .into_iter()
            .filter_map(|(o, fed)| {
                let roles = fed.into_iter().filter_map(role_of);
                Some((
                    usize::from(role_of(o)?),
                    roles.fold(0u64, |m, r| m | 1 << r),
                ))
            })
            .collect();
        let feedback = plant
            .mirrors()
            .into_iter()
            .map(|(i, o)| (i, role_of(o), o))
            .collect();
        let mut emu = Self {
            layout: layout.clone(),
            parts,
            table,
            probes,
            angles,
            sensor_plant,
            role_plant,
            symbols,
            step_ms: layout.step_ms.max(1),
            now: 0,
            carry: 0,
            cmd: 0,
            angle: t.loading_mdeg as i64 * 1000,
            rot_speed: t.out_speed_udeg_ms,
            rot_dir: 0,
            moving: false,
            no_skip: false,
            driven: None,
            pos: TablePos::Load,
            links: vec![[None; 2]; n_parts],
            vel: vec![0; n_parts],
            near: vec![0; n_parts],
            source_part: layout
                .conveyors
                .iter()
                .position(|c| c.id == layout.source.conveyor),
            bodies: Vec::with_capacity(16),
            scratch: Vec::with_capacity(16),
            done: Vec::new(),
            views: Vec::with_capacity(16),
            sensor_raw: 0,
            sensor_mask: 0,
            sensors: Bits::zeros(plant.inputs.len()),
            hazards: Vec::new(),
            stats: BoxStats::default(),
            next_id: 1,
            rng_arrivals: SplitMix64::new(seed),
            rng_table: SplitMix64::new(seed ^ 0x5EED_7AB1_E000_0001),
            plan: ArrivalPlan::Off,
            arrival_k: 0,
            plan_origin: 0,
            next_arrival: None,
            pending: VecDeque::with_capacity(8),
            faults: Vec::new(),
            fault_problems: Vec::new(),
            overrides: Overrides::default(),
            slow: vec![100; n_roles],
            frame,
            has_conditions: false,
            supply,
            feedback,
        };
        emu.update_links(true);
        emu.set_arrivals(layout.source.arrivals.clone());
        emu.compute_sensors();
        emu.publish();
        Ok(emu)
    }

    /// Runs `dt` with the given PLC outputs (by plant output index), in fixed internal steps.
    pub fn step(&mut self, dt: Millis, outputs: &Bits) {
        let mut cmd = 0u64;
        for (r, &o) in self.role_plant.iter().enumerate() {
            if outputs.get(o) {
                cmd |= 1 << r;
            }
        }
        self.cmd = cmd;
        self.carry += dt.0;
        while self.carry >= self.step_ms {
            let quiet = self.quiet_steps(self.carry / self.step_ms);
            if quiet > 1 {
                self.carry -= quiet * self.step_ms;
                self.take_quiet_steps(quiet);
                if self.carry < self.step_ms {
                    self.compute_sensors();
                }
                continue;
            }
            self.carry -= self.step_ms;
            self.tick(self.carry < self.step_ms);
        }
        self.publish();
        // Mirror contacts: the contactor as it is (commanded, welded or dead), powered
        // or not; a mirrored output that drives nothing of the layout reads as applied.
        let closed = self.contactors();
        for &(input, role, output) in &self.feedback {
            let on = role.map_or_else(|| outputs.get(output), |r| closed >> r & 1 == 1);
            self.sensors.set(input, on);
        }
    }

    /// The roles whose contactor is closed: commanded, or stuck on by a fault, and not
    /// dead.
    fn contactors(&self) -> u64 {
        (self.cmd & !self.overrides.act_off) | self.overrides.act_on
    }

    /// The roles without power: a safety contactor that supplies them is open
    /// (released, or dead; a fault changes it within the step).
    pub(super) fn unpowered(&self) -> u64 {
        let closed = self.contactors();
        self.supply
            .iter()
            .filter(|(r, _)| closed >> r & 1 == 0)
            .fold(0, |m, (_, mask)| m | mask)
    }

    /// The roles that act: their contactor closed and their supply on.
    pub(super) fn acting(&self) -> u64 {
        self.contactors() & !self.unpowered()
    }

    /// Sensor values by plant input index, faults applied.
    pub fn sensors(&self) -> &Bits {
        &self.sensors
    }

    /// Simulated time.
    pub fn now(&self) -> Millis {
        Millis(self.now)
    }

    /// Every hazard so far, in time order.
    pub fn hazards(&self) -> &[Hazard] {
        &self.hazards
    }

    /// Boxes in transit, fallen, and delivered during the last second.
    pub fn boxes(&self) -> &[BoxView] {
        &self.views
    }

    /// Box counts.
    pub fn stats(&self) -> BoxStats {
        self.stats.clone()
    }

    /// Table angle, millidegrees.
    pub fn table_angle_mdeg(&self) -> i32 {
        (self.angle / 1000) as i32
    }

    /// Schedules a fault; a fault naming an unknown signal or with a bad condition is
    /// dropped and kept in [`Emulator::fault_problems`].
    pub fn schedule_fault(&mut self, fault: FaultSpec) {
        if let Err(p) = self.try_schedule_fault(fault) {
            self.fault_problems.push(p);
        }
    }

    /// Schedules a fault or says why it cannot be.
    pub fn try_schedule_fault(&mut self, fault: FaultSpec) -> Result<(), Problem> {
        let layout = &self.layout;
        let sensor = |id: &str| {
            layout
                .sensors
                .iter()
                .position(|s| s.id == id)
                .map(|i| i as u32)
        };
        let roles = self.actuators();
        let role = |id: &str| roles.iter().position(|a| a == id).map(|i| i as u32);
        // The layout's components: the turntable (blocked where it stands) and the
        // conveyors (slowed by their drive).
        let component = |k: &FaultKind| match k {
            FaultKind::StuckAt {
                component,
                position,
            } if *component == layout.table.id => {
                let mdeg = (position.0 * 1000.0).round();
                if mdeg == f64::from(layout.table.loading_mdeg) {
                    Some(faults::Effect::Table(0))
                } else if mdeg == f64::from(layout.table.unloading_mdeg) {
                    Some(faults::Effect::Table(1))
                } else {
                    None
                }
            }
            FaultKind::Blocked(c) if *c == layout.table.id => Some(faults::Effect::Table(2)),
            FaultKind::Slowed { component, percent } => {
                let c = layout.conveyors.iter().find(|c| c.id == *component)?;
                Some(faults::Effect::Slow(role(&c.actuator)?, *percent))
            }
            _ => None,
        };
        let s = Scheduled::new(fault, sensor, role, component, &self.symbols)?;
        self.has_conditions |= s.condition.is_some();
        self.faults.push(s);
        Ok(())
    }

    /// The layout's sensors, in the layout's order (the ids a transient may strike).
    pub fn sensor_ids(&self) -> Vec<String> {
        self.layout.sensors.iter().map(|s| s.id.clone()).collect()
    }

    /// The actuators the emulator drives, by role (the ids a fault may name): the
    /// layout's drives, then the safety contactors that supply them.
    pub fn actuators(&self) -> Vec<String> {
        self.role_plant
            .iter()
            .map(|&o| {
                self.symbols
                    .name(crate::symbols::Space::Output, o as u32)
                    .to_owned()
            })
            .collect()
    }

    /// The faults active or still to come.
    pub fn faults_in_force(&self) -> usize {
        self.faults
            .iter()
            .filter(|f| f.phase != faults::Phase::Over)
            .count()
    }

    /// A technician's repair on the simulator: every fault active or still to come ends
    /// now (the sensors read the plant again, the drives obey their outputs). Returns
    /// how many faults ended.
    pub fn repair_faults(&mut self) -> usize {
        let mut n = 0;
        for f in &mut self.faults {
            if f.phase != faults::Phase::Over {
                f.phase = faults::Phase::Over;
                n += 1;
            }
        }
        self.refresh_overrides();
        n
    }

    /// Faults that could not be scheduled.
    pub fn fault_problems(&self) -> &[Problem] {
        &self.fault_problems
    }

    /// Replaces the arrival plan; a periodic plan restarts its period from now.
    pub fn set_arrivals(&mut self, plan: ArrivalPlan) {
        self.plan = plan;
        self.arrival_k = 0;
        self.plan_origin = self.now;
        self.next_arrival = None;
        if let ArrivalPlan::List(list) = &mut self.plan {
            list.sort();
        }
        self.plan_next();
    }

    /// The layout the emulator was built from.
    /// Takes every internal step one by one, never several quiet steps at once (for
    /// tests that check both give the same plant).
    pub fn disable_quiet_steps(&mut self) {
        self.no_skip = true;
    }

    /// The layout the emulator was built from.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Puts a box with its centre at `position_mm` along `part` (conveyor id from its
    /// start, or the table id with the table coordinate `u`). Unknown parts are ignored.
    pub fn place_box(&mut self, part: &str, position_mm: i64, size: BoxSize) {
        let _ = self.try_place_box(part, position_mm, size);
    }

    /// Like [`Emulator::place_box`], returning the new box id or why it was refused.
    pub fn try_place_box(
        &mut self,
        part: &str,
        position_mm: i64,
        size: BoxSize,
    ) -> Result<u32, Problem> {
        let p = if part == self.layout.table.id {
            Some(self.table)
        } else {
            self.layout.conveyors.iter().position(|c| c.id == part)
        };
        let Some(p) = p else {
            return Err(Problem::error(
                codes::EMULATOR_UNKNOWN_PART.id,
                format!("no part `{part}` in the layout"),
                None,
            ));
        };
        let c = if p == self.table {
            (position_mm + self.layout.table.half_length_mm) * 1000
        } else {
            position_mm * 1000
        };
        let id = self.spawn(p, c, size);
        self.compute_sensors();
        self.publish();
        Ok(id)
    }

    /// The operator takes every box off the plant by hand, those in transit and those
    /// that fell (before a re-initialisation of an emptied plant); returns how many.
    /// Arrivals go on as planned.
    pub fn remove_items(&mut self) -> u32 {
        let fallen = self
            .done
            .iter()
            .filter(|(v, _)| v.state == BoxState::Fallen)
            .count();
        let n = (self.bodies.len() + fallen) as u32;
        self.bodies.clear();
        self.done.retain(|(v, _)| v.state != BoxState::Fallen);
        self.stats.removed += n;
        self.compute_sensors();
        self.publish();
        n
    }

    /// Sets the table angle (live-mode initialisation), millidegrees.
    pub fn set_table_angle_mdeg(&mut self, a: i32) {
        self.angle = a as i64 * 1000;
        self.update_links(true);
        self.compute_sensors();
        self.publish();
    }

    fn spawn(&mut self, part: usize, c: i64, size: BoxSize) -> u32 {
        let d = self.layout.dims(size);
        let id = self.next_id;
        self.next_id += 1;
        self.stats.created += 1;
        self.bodies.push(Body {
            id,
            size,
            half: d.length_mm * 500,
            height_mm: d.height_mm,
            part: part as u8,
            c,
            damaged: false,
            reported: 0,
            slip: 0,
        });
        id
    }

    /// Writes the sensor bits and the box views.
    fn publish(&mut self) {
        for (k, &i) in self.sensor_plant.iter().enumerate() {
            self.sensors.set(i, self.sensor_mask >> k & 1 == 1);
        }
        self.views.clear();
        for b in &self.bodies {
            let v = self.view(b, BoxState::Transit);
            self.views.push(v);
        }
        let now = self.now;
        self.done
            .retain(|(v, t)| v.state == BoxState::Fallen || now.saturating_sub(*t) < 1000);
        self.views.extend(self.done.iter().map(|(v, _)| *v));
    }

    fn view(&self, b: &Body, state: BoxState) -> BoxView {
        let d = self.layout.dims(b.size);
        let p = &self.parts[b.part as usize];
        let (x, y, angle) = if b.part as usize == self.table {
            let a = (self.angle as f64 / 1e6).to_radians();
            let u = (b.c - p.len / 2) as f64 / 1000.0;
            (
                p.origin.0 + u * a.cos(),
                p.origin.1 + u * a.sin(),
                (self.angle / 1000) as i32,
            )
        } else {
            let s = b.c as f64 / 1000.0;
            (
                p.origin.0 + s * p.dir.0,
                p.origin.1 + s * p.dir.1,
                p.angle_mdeg,
            )
        };
        BoxView {
            id: b.id,
            size: b.size,
            length_mm: d.length_mm,
            width_mm: d.width_mm,
            x_mm: x as f32,
            y_mm: y as f32,
            angle_mdeg: angle,
            damaged: b.damaged,
            state,
        }
    }

    fn plan_next(&mut self) {
        self.next_arrival = match &self.plan {
            ArrivalPlan::Off => None,
            ArrivalPlan::List(list) => list.get(self.arrival_k as usize).map(|&(t, s)| (t, s)),
            ArrivalPlan::Periodic { count: Some(n), .. } if self.arrival_k >= *n => None,
            ArrivalPlan::Periodic {
                period_ms,
                jitter_ms,
                mix,
                ..
            } => {
                let base = self.plan_origin + self.arrival_k.saturating_mul((*period_ms).max(1));
                let t = base + self.rng_arrivals.below(jitter_ms + 1);
                let size = match mix {
                    SizeMix::Alternate if self.arrival_k.is_multiple_of(2) => BoxSize::Small,
                    SizeMix::Alternate => BoxSize::Large,
                    SizeMix::RandomLarge(p) => {
                        if self.rng_arrivals.below(100) < u64::from(*p) {
                            BoxSize::Large
                        } else {
                            BoxSize::Small
                        }
                    }
                };
                Some((t, size))
            }
        };
    }
}

/// Presence probes per part, angle windows `(sensor, min, max)`, and each sensor's plant input.
type SensorPlacement = (Vec<Vec<Probe>>, Vec<(u8, i64, i64)>, Vec<usize>);

/// Places each sensor: presence probes per part, angle windows, and its plant input.
fn sensor_probes(layout: &Layout, plant: &Plant, table: usize, n_parts: usize) -> SensorPlacement {
    let part_index = |id: &str| {
        if id == layout.table.id {
            Some(table)
        } else {
            layout.conveyors.iter().position(|c| c.id == id)
        }
    };
    let mut probes = vec![Vec::new(); n_parts];
    let mut angles = Vec::new();
    let mut sensor_plant = Vec::new();
    for (k, s) in layout.sensors.iter().enumerate() {
        sensor_plant.push(plant.input(&s.id).unwrap_or(usize::MAX));
        match &s.kind {
            SensorKind::Presence { part, at_mm, beam } => {
                let Some(p) = part_index(part) else { continue };
                let at = if p == table {
                    (at_mm + layout.table.half_length_mm) * 1000
                } else {
                    at_mm * 1000
                };
                let min_height = match beam {
                    Beam::Low => 0,
                    Beam::High => layout.high_beam_mm,
                };
                probes[p].push(Probe {
                    sensor: k as u8,
                    at,
                    min_height,
                });
            }
            SensorKind::Angle { min_mdeg, max_mdeg } => {
                angles.push((k as u8, *min_mdeg as i64 * 1000, *max_mdeg as i64 * 1000));
            }
        }
    }
    (probes, angles, sensor_plant)
}

/// The plant output of each role: the layout's drives ([`Layout::drives`]), then each
/// safety contactor that is not one
/// (`supplies`): a fault may weld or kill it like any other contactor.
fn roles(layout: &Layout, plant: &Plant) -> Vec<usize> {
    let mut role_plant = layout
        .drives()
        .map(|a| plant.output(a).unwrap_or(usize::MAX))
        .collect::<Vec<_>>();
    for (o, _) in plant.supplies() {
        if !role_plant.contains(&o) {
            role_plant.push(o);
        }
    }
    role_plant
}

#[cfg(test)]
mod tests;
