//! The emulator of a plant described as components: every component of
//! `components.ron` steps on the outputs as applied, writes its sensors, and reports
//! its hazards; the faults of a scenario act on signals or on whole components.
//!
//! Like the sorting station's emulator, time is integer milliseconds passed in by the
//! caller, taken in fixed internal steps (`step_ms`), and randomness (each move's
//! speed) comes from the seed: a run is a function of its seed and its inputs.
//!
//! The outputs reach the components through the plant's pre-actuators: an output
//! welded or dead by a fault is as the fault says, and a drive whose safety contactor
//! (`supplies` in `plant.ron`) is open gets no power. A mirror contact (`feedback_of`)
//! reads its contactor as it is.

use super::description::Components;
use super::kinds::{ComponentFaults, Live, StepCtx};
use super::scene::Scene;
use crate::bits::Bits;
use crate::diag::{Problem, codes};
use crate::emulator::faults::{Effect, Phase, Scheduled};
use crate::emulator::{FaultKind, FaultSpec, Hazard, HazardKind, Place};
use crate::expr::{Dnf, eval_dnf, parse_str, simplify};
use crate::frame::Frame;
use crate::plant::Plant;
use crate::symbols::{Space, Symbols};
use crate::synthetic::SplitMix64;
use crate::time::Millis;

/// A declared danger, compiled.
#[derive(Clone, Debug)]
struct Danger {
    id: String,
    text: String,
    component: usize,
    from: f64,
    to: f64,
    when: Dnf,
    active: bool,
}

/// The emulator of a components plant. Cheap to clone (projections run on copies).
#[derive(Clone, Debug)]
pub struct ComponentPlant {
    /// Id and display name of each component.
    names: Vec<(String, String)>,
    /// The plant inputs the components measure, in plant order.
    measured: Vec<String>,
    /// The number of the last item a feeder placed.
    next_item: u32,
    /// Per component, the component its exit leads to (a conveyor's `To`).
    targets: Vec<Option<usize>>,
    /// Per component, the items its taker carries to a feeder (`feed.from`).
    carried: Vec<std::collections::VecDeque<super::kinds::conveyor::Item>>,
    live: Vec<Live>,
    dangers: Vec<Danger>,
    symbols: Symbols,
    frame: Frame,
    step_ms: u64,
    now: u64,
    carry: u64,
    /// The outputs as the PLC commands them.
    commanded: Bits,
    sensors: Bits,
    hazards: Vec<Hazard>,
    rng: SplitMix64,
    faults: Vec<Scheduled>,
    fault_problems: Vec<Problem>,
    has_conditions: bool,
    /// Forced sensors and outputs (by plant index), and whole-component faults.
    sensor_force: Vec<Option<bool>>,
    output_force: Vec<Option<bool>>,
    component_faults: Vec<ComponentFaults>,
    /// Safety contactors: the output and the outputs it powers.
    supply: Vec<(usize, Vec<usize>)>,
    /// Mirror contacts: the input and the output it mirrors.
    feedback: Vec<(usize, usize)>,
    /// A drive, a flow or a danger reads a sensor or a past value: the frame and the
    /// sensors are then updated at every internal step, not only once per period.
    reads_inputs: bool,
    /// The applied outputs must be recomputed (new commands, a fault changed).
    outputs_dirty: bool,
}

impl ComponentPlant {
    /// Builds the emulator at time 0, every component at its start. Fails when the
    /// description names a signal the plant lacks.
    pub fn new(desc: &Components, plant: &Plant, seed: u64) -> Result<Self, Problem> {
        if let Some(p) = desc
            .check()
            .into_iter()
            .chain(desc.check_signals(plant))
            .next()
        {
            return Err(p);
        }
        let symbols = plant.symbols();
        let measured = measured(desc, plant);
        let mut live = Vec::new();
        for c in &desc.components {
            live.push(c.kind.build(&c.id, &symbols)?);
        }
        let mut dangers = Vec::new();
        for d in &desc.dangers {
            let when = parse_str(&d.when)
                .and_then(|e| e.to_dnf(&symbols))
                .map_err(|e| {
                    desc.error(
                        codes::COMPONENTS_EXPRESSION.id,
                        &d.when,
                        format!("danger `{}`: {}", d.id, e.message),
                    )
                })?;
            dangers.push(Danger {
                id: d.id.clone(),
                text: d.text.clone(),
                component: desc
                    .components
                    .iter()
                    .position(|c| c.id == d.component)
                    .unwrap_or(0),
                from: d.from,
                to: d.to,
                when: simplify(&when),
                active: false,
            });
        }
        let reads_inputs = desc
            .components
            .iter()
            .flat_map(|c| c.kind.expressions())
            .chain(desc.dangers.iter().map(|d| d.when.as_str()))
            .filter_map(|t| parse_str(t).ok()?.to_dnf(&symbols).ok())
            .any(|dnf| {
                dnf.iter()
                    .flatten()
                    .any(|l| l.var.space != Space::Output || l.var.prev)
            });
        let n_out = plant.outputs.len();
        let mut commanded = Bits::zeros(n_out);
        for (i, s) in plant.outputs.iter().enumerate() {
            commanded.set(i, s.initial);
        }
        let mut emu = Self {
            measured,
            next_item: 0,
            targets: targets(desc),
            carried: vec![std::collections::VecDeque::new(); live.len()],
            names: desc
                .components
                .iter()
                .map(|c| (c.id.clone(), c.name.clone()))
                .collect(),
            component_faults: vec![
                ComponentFaults {
                    blocked: false,
                    speed_percent: 100
                };
                live.len()
            ],
            live,
            dangers,
            frame: Frame::new(symbols.sizes()),
            symbols,
            step_ms: desc.step_ms.max(1),
            now: 0,
            carry: 0,
            commanded,
            sensors: Bits::zeros(plant.inputs.len()),
            hazards: Vec::new(),
            rng: SplitMix64::new(seed ^ 0x000C_04D0_4E47),
            faults: Vec::new(),
            fault_problems: Vec::new(),
            has_conditions: false,
            sensor_force: vec![None; plant.inputs.len()],
            output_force: vec![None; n_out],
            supply: plant.supplies(),
            feedback: plant.mirrors(),
            reads_inputs,
            outputs_dirty: true,
        };
        link_carries(desc, &mut emu.live);
        emu.apply_outputs();
        emu.compute_sensors();
        Ok(emu)
    }

    /// Runs `dt` with the given PLC outputs (by plant output index), in fixed steps.
    pub fn step(&mut self, dt: Millis, outputs: &Bits) {
        if !(self.reads_inputs || self.has_conditions) {
            // Nothing reads a past value within the period: one shift per period.
            self.frame.shift();
        }
        if self.commanded != *outputs {
            self.commanded.copy_from(outputs);
            self.outputs_dirty = true;
        }
        self.carry += dt.0;
        while self.carry >= self.step_ms {
            self.carry -= self.step_ms;
            self.tick();
            // At rest on constant outputs, with no fault to come: the remaining steps
            // of the period would change nothing but the time.
            let settled = self.faults.iter().all(|f| f.phase == Phase::Over);
            if settled && self.live.iter().all(Live::idle) {
                let k = self.carry / self.step_ms;
                self.now += k * self.step_ms;
                self.carry -= k * self.step_ms;
            }
        }
        self.apply_outputs();
        self.compute_sensors();
    }

    fn tick(&mut self) {
        self.now += self.step_ms;
        if !self.faults.is_empty() {
            self.update_faults();
        }
        if self.reads_inputs || self.has_conditions {
            self.frame.shift();
        }
        if self.outputs_dirty {
            self.apply_outputs();
        }
        let mut ctx = StepCtx {
            dt: self.step_ms,
            frame: &self.frame,
            rng: &mut self.rng,
            hazards: Vec::new(),
            next_item: &mut self.next_item,
            now: self.now,
            carried: &mut self.carried,
            index: 0,
        };
        let mut found = Vec::new();
        for (k, c) in self.live.iter_mut().enumerate() {
            ctx.index = k;
            c.step(&mut ctx, self.component_faults[k]);
            found.extend(ctx.hazards.drain(..).map(|h| (k, h)));
        }
        self.hand_over();
        for (k, (kind, elements)) in found {
            let (id, name) = &self.names[k];
            self.hazards.push(Hazard {
                time_ms: self.now,
                kind,
                place: name.clone(),
                at: Place::Component { part: id.clone() },
                elements,
                box_id: 0,
            });
        }
        self.check_dangers();
        // The sensors are read at the end of the period; a step needs them only when
        // something reads them within it (a fault's condition, a drive on a sensor).
        if self.has_conditions || self.reads_inputs {
            self.compute_sensors();
        }
    }

    /// Each item waiting at a conveyor's exit end passes to the next conveyor's entry
    /// when it is free; else it waits.
    fn hand_over(&mut self) {
        for from in 0..self.live.len() {
            let Some(to) = self.targets[from] else {
                continue;
            };
            let Live::Conveyor(c) = &self.live[from] else {
                continue;
            };
            let Some(item) = c.ready().cloned() else {
                continue;
            };
            let taken = match &mut self.live[to] {
                Live::Conveyor(next) => next.accept(&item),
                _ => false,
            };
            if taken && let Live::Conveyor(c) = &mut self.live[from] {
                c.hand_over();
            }
        }
    }

    /// The outputs as they reach the components: faults, then the supplies; the
    /// frame's inputs are the sensors as last read.
    fn apply_outputs(&mut self) {
        self.outputs_dirty = false;
        let mut out = self.contactors();
        for (o, fed) in &self.supply {
            if !out.get(*o) {
                for &f in fed {
                    out.set(f, false);
                }
            }
        }
        self.frame.now_mut(Space::Output).copy_from(&out);
        self.frame.now_mut(Space::Input).copy_from(&self.sensors);
    }

    /// Each output's contactor as it is: commanded, unless a fault welds or kills it.
    fn contactors(&self) -> Bits {
        let mut out = self.commanded.clone();
        for (i, f) in self.output_force.iter().enumerate() {
            if let Some(v) = f {
                out.set(i, *v);
            }
        }
        out
    }

    fn check_dangers(&mut self) {
        for d in &mut self.dangers {
            let p = self.live[d.component].position();
            let on = p >= d.from && p <= d.to && eval_dnf(&d.when, &self.frame);
            if on && !d.active {
                let (id, _) = &self.names[d.component];
                self.hazards.push(Hazard {
                    time_ms: self.now,
                    kind: HazardKind::Declared,
                    place: d.text.clone(),
                    at: Place::Danger {
                        part: id.clone(),
                        danger: d.id.clone(),
                    },
                    elements: Vec::new(),
                    box_id: 0,
                });
            }
            d.active = on;
        }
    }

    fn compute_sensors(&mut self) {
        // An input no component drives (the environment: a perturbation on a line)
        // reads 0 unless a fault forces it, and returns to 0 when the fault ends.
        self.sensors.clear();
        for c in &self.live {
            c.sense(&mut self.sensors);
        }
        let closed = self.contactors();
        for &(input, output) in &self.feedback {
            self.sensors.set(input, closed.get(output));
        }
        for (i, f) in self.sensor_force.iter().enumerate() {
            if let Some(v) = f {
                self.sensors.set(i, *v);
            }
        }
        self.frame.now_mut(Space::Input).copy_from(&self.sensors);
    }

    fn update_faults(&mut self) {
        let mut changed = false;
        for f in &mut self.faults {
            changed |= f.update(self.now, &self.frame);
        }
        if changed {
            self.refresh_overrides();
            self.outputs_dirty = true;
        }
    }

    fn refresh_overrides(&mut self) {
        self.sensor_force.iter_mut().for_each(|f| *f = None);
        self.output_force.iter_mut().for_each(|f| *f = None);
        for c in &mut self.component_faults {
            *c = ComponentFaults {
                blocked: false,
                speed_percent: 100,
            };
        }
        for f in &self.faults {
            if !matches!(f.phase, Phase::Active { .. }) {
                continue;
            }
            match f.effect {
                Effect::Sensor(i, v) => self.sensor_force[i as usize] = Some(v),
                Effect::Actuator(i, v) => self.output_force[i as usize] = Some(v),
                Effect::Block(k) => self.component_faults[k as usize].blocked = true,
                Effect::SlowComponent(k, p) => {
                    let c = &mut self.component_faults[k as usize];
                    c.speed_percent = c.speed_percent.min(p);
                }
                Effect::Table(_) | Effect::Slow(..) => {}
            }
        }
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

    /// Schedules a fault or says why it cannot be.
    pub fn try_schedule_fault(&mut self, fault: FaultSpec) -> Result<(), Problem> {
        let sym = &self.symbols;
        let index = |space: Space| {
            move |id: &str| match sym.lookup(id) {
                Some((s, i)) if s == space => Some(i),
                _ => None,
            }
        };
        let names = &self.names;
        let component = |k: &FaultKind| {
            let find = |c: &str| names.iter().position(|(id, _)| id == c).map(|k| k as u32);
            match k {
                FaultKind::Blocked(c) => find(c).map(Effect::Block),
                FaultKind::Slowed { component, percent } => {
                    find(component).map(|k| Effect::SlowComponent(k, *percent))
                }
                _ => None,
            }
        };
        let s = Scheduled::new(
            fault,
            index(Space::Input),
            index(Space::Output),
            component,
            &self.symbols,
        )?;
        self.has_conditions |= s.condition.is_some();
        self.faults.push(s);
        self.update_faults();
        Ok(())
    }

    /// Schedules a fault; one that cannot be is kept in [`Self::fault_problems`].
    pub fn schedule_fault(&mut self, fault: FaultSpec) {
        if let Err(p) = self.try_schedule_fault(fault) {
            self.fault_problems.push(p);
        }
    }

    /// Faults that could not be scheduled.
    pub fn fault_problems(&self) -> &[Problem] {
        &self.fault_problems
    }

    /// The faults active or still to come.
    pub fn faults_in_force(&self) -> usize {
        self.faults
            .iter()
            .filter(|f| f.phase != Phase::Over)
            .count()
    }

    /// A technician's repair: every fault active or still to come ends now.
    pub fn repair_faults(&mut self) -> usize {
        let mut n = 0;
        for f in &mut self.faults {
            if f.phase != Phase::Over {
                f.phase = Phase::Over;
                n += 1;
            }
        }
        self.refresh_overrides();
        self.outputs_dirty = true;
        self.apply_outputs();
        self.compute_sensors();
        n
    }

    /// The items that left the plant done: delivered into a sink or taken at a
    /// conveyor's exit end.
    pub fn items_out(&self) -> u32 {
        self.live
            .iter()
            .map(|c| match c {
                Live::Conveyor(v) => v.out(),
                _ => 0,
            })
            .sum()
    }

    /// The classes of items the feeders place, sorted.
    pub fn item_classes(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .live
            .iter()
            .flat_map(|c| match c {
                Live::Conveyor(v) => v.classes(),
                _ => Vec::new(),
            })
            .collect();
        v.sort();
        v.dedup();
        v
    }

    /// The items the feeders placed so far.
    pub fn items_in(&self) -> u32 {
        self.next_item
    }

    /// The plant has conveyors (its production is items, not only moves).
    pub fn carries_items(&self) -> bool {
        self.live.iter().any(|c| matches!(c, Live::Conveyor(_)))
    }

    /// The sensors the components drive (the ids a transient may strike), in plant
    /// order; a panel button is not one.
    pub fn sensor_ids(&self) -> Vec<String> {
        self.measured.clone()
    }

    /// The outputs that drive something (the ids a fault may weld or kill): every
    /// output of the plant.
    pub fn actuators(&self) -> Vec<String> {
        self.symbols.names(Space::Output).to_vec()
    }

    /// What the synoptic draws.
    pub fn scene(&self) -> Scene {
        Scene {
            elements: self
                .live
                .iter()
                .zip(&self.names)
                .map(|(c, (id, name))| c.scene(id, name))
                .collect(),
        }
    }

    /// The operator presses the panel button wired to input `signal`; false when no
    /// button component closes it.
    pub fn press(&mut self, signal: &str) -> bool {
        let pressed = self.live.iter_mut().any(|c| c.press(signal));
        if pressed {
            self.compute_sensors();
        }
        pressed
    }

    /// Every component's position (a tank's level), in the order of the scene: what a
    /// replay keeps of each cycle.
    pub fn positions(&self) -> impl Iterator<Item = f64> + '_ {
        self.live.iter().map(Live::position)
    }

    /// The scene with the components at `positions` (as [`Self::positions`] gave
    /// them): a cycle of the replay drawn.
    pub fn scene_at(&self, positions: &[f64]) -> Scene {
        let mut copy = self.clone();
        for (c, &p) in copy.live.iter_mut().zip(positions) {
            c.set_position(p);
        }
        copy.scene()
    }

    /// The declared dangers: id and text.
    pub fn dangers(&self) -> Vec<(String, String)> {
        self.dangers
            .iter()
            .map(|d| (d.id.clone(), d.text.clone()))
            .collect()
    }

    /// Component `id`'s position in its unit.
    pub fn position(&self, id: &str) -> Option<f64> {
        let k = self.names.iter().position(|(c, _)| c == id)?;
        Some(self.live[k].position())
    }

    /// Moves component `id` to `position` by hand (a technician, a live-mode
    /// initialisation); false when there is no such component.
    pub fn set_position(&mut self, id: &str, position: f64) -> bool {
        let Some(k) = self.names.iter().position(|(c, _)| c == id) else {
            return false;
        };
        self.live[k].set_position(position);
        self.compute_sensors();
        true
    }

    /// The elementary actions the components allow (seed 003, R1), sorted by id:
    /// what a monitor checks when the plant declares none of its own.
    pub fn derived_actions(&self) -> Vec<super::derive::DerivedAction> {
        let mut out: Vec<_> = self
            .live
            .iter()
            .zip(&self.names)
            .filter_map(|(c, (id, _))| c.axis_geometry(id))
            .flat_map(|g| super::derive::axis_actions(&g))
            .collect();
        out.sort_by(|a, b| a.id.cmp(&b.id));
        out
    }
}

#[cfg(test)]
mod conveyor_tests;
#[cfg(test)]
mod device_tests;
#[cfg(test)]
mod tests;

/// The plant inputs the components of `desc` measure, in plant order.
fn measured(desc: &Components, plant: &Plant) -> Vec<String> {
    let named: std::collections::BTreeSet<&str> = desc
        .components
        .iter()
        .flat_map(|c| c.kind.sensors())
        .collect();
    plant
        .inputs
        .iter()
        .filter(|s| named.contains(s.id.as_str()))
        .map(|s| s.id.clone())
        .collect()
}

/// Links the feeders that place what another conveyor's taker picked (`feed.from`).
fn link_carries(desc: &Components, live: &mut [Live]) {
    let from: Vec<Option<usize>> = desc
        .components
        .iter()
        .map(|c| match &c.kind {
            super::kinds::KindDef::Conveyor(v) => v
                .carries_from()
                .and_then(|f| desc.components.iter().position(|o| o.id == f)),
            _ => None,
        })
        .collect();
    for (k, c) in live.iter_mut().enumerate() {
        if let Live::Conveyor(v) = c {
            v.link_carry(from[k], from.contains(&Some(k)));
        }
    }
}

/// Per component of `desc`, the index of the component its exit leads to.
fn targets(desc: &Components) -> Vec<Option<usize>> {
    desc.components
        .iter()
        .map(|c| match &c.kind {
            super::kinds::KindDef::Conveyor(v) => v
                .target()
                .and_then(|t| desc.components.iter().position(|o| o.id == t)),
            _ => None,
        })
        .collect()
}
