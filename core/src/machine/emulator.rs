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
use super::items::{Items, Requests};
use super::kinds::{ComponentFaults, Live, StepCtx};
use super::scene::Scene;
use super::scene::SceneItem;
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
    /// The items on the conveyors and turntables.
    items: Items,
    /// Per component, its surface among the items' (conveyors, turntables).
    surface_of: Vec<Option<usize>>,
    /// The outputs without power (their safety contactor open).
    unpowered: Bits,
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
    /// The surfaces' requests of a step (kept to reuse its allocation).
    requests: Vec<Requests>,
    /// Quiet steps may be taken at once: nothing reads a sensor within a period and
    /// no declared danger watches a conveyor's position.
    quiet_allowed: bool,
    /// Where the placed surfaces stand on the floor, for the top view.
    top: Option<super::topview::TopView>,
    /// The frame changed since the components' last step ([`StepCtx::fresh`]).
    fresh: bool,
    /// The contactors as they are, computed into this (no allocation per period).
    closed: Bits,
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
        let dangers = compile_dangers(desc, &symbols)?;
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
        let (items, surface_of) = build_items(desc, &mut live, seed);
        let quiet_allowed =
            !reads_inputs && dangers.iter().all(|d| surface_of[d.component].is_none());
        let mut emu = Self {
            measured,
            items,
            surface_of,
            unpowered: Bits::zeros(n_out),
            names: desc
                .components
                .iter()
                .map(|c| (c.id.clone(), c.name.clone()))
                .collect(),
            component_faults: vec![
                ComponentFaults {
                    blocked: false,
                    speed_percent: 100,
                    stuck_at: None,
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
            quiet_allowed,
            requests: Vec::new(),
            top: super::topview::TopView::new(desc),
            fresh: true,
            closed: Bits::zeros(n_out),
            reads_inputs,
            outputs_dirty: true,
        };
        emu.apply_outputs();
        emu.compute_sensors();
        Ok(emu)
    }

    /// Runs `dt` with the given PLC outputs (by plant output index), in fixed steps.
    pub fn step(&mut self, dt: Millis, outputs: &Bits) {
        if !(self.reads_inputs || self.has_conditions) {
            // Nothing reads a past value within the period: one shift per period.
            self.frame.shift();
            self.fresh = true;
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
            let k = self.carry / self.step_ms;
            if settled
                && self.live.iter().all(Live::idle)
                && self.items.idle(self.now + k * self.step_ms)
            {
                self.now += k * self.step_ms;
                self.carry -= k * self.step_ms;
            } else if k > 0 && settled && self.quiet_allowed {
                // Only items moving straight on running belts and tables turning on:
                // the steps until an item could reach an end, a joint or an arrival,
                // and a table its position, are taken at once.
                let dt = self.step_ms;
                let q = self
                    .live
                    .iter()
                    .map(|c| c.quiet_steps(dt, k))
                    .min()
                    .unwrap_or(k);
                let q = if q > 0 {
                    let (live, surfaces) = (&self.live, &self.items.surfaces);
                    let turning = |s: usize| !live[surfaces[s].component].steady();
                    self.items.quiet_steps(self.now, dt, q, turning)
                } else {
                    0
                };
                if q > 0 {
                    self.items.advance(q);
                    for c in &mut self.live {
                        c.advance(dt, q);
                    }
                    self.now += q * dt;
                    self.carry -= q * dt;
                }
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
            self.fresh = true;
        }
        if self.outputs_dirty {
            self.apply_outputs();
        }
        let mut ctx = StepCtx {
            dt: self.step_ms,
            frame: &self.frame,
            rng: &mut self.rng,
            hazards: Vec::new(),
            now: self.now,
            unpowered: &self.unpowered,
            fresh: self.fresh,
        };
        self.fresh = false;
        let mut found = Vec::new();
        for (k, c) in self.live.iter_mut().enumerate() {
            c.step(&mut ctx, self.component_faults[k]);
            if !ctx.hazards.is_empty() {
                found.extend(ctx.hazards.drain(..).map(|h| (k, h)));
            }
        }
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
        if !self.items.surfaces.is_empty() {
            self.step_items();
        }
        self.check_dangers();
        // The sensors are read at the end of the period; a step needs them only when
        // something reads them within it (a fault's condition, a drive on a sensor).
        if self.has_conditions || self.reads_inputs {
            self.compute_sensors();
        }
    }

    /// The items move on the surfaces as their components ask.
    fn step_items(&mut self) {
        let mut requests = std::mem::take(&mut self.requests);
        requests.clear();
        for s in 0..self.items.surfaces.len() {
            let k = self.items.surfaces[s].component;
            requests.push(match &self.live[k] {
                Live::Conveyor(c) => c.requests,
                Live::Turntable(t) => {
                    self.items.set_docked(s, t.docked);
                    Requests {
                        velocity: t.roller_speed() * self.step_ms as i64,
                        ..Requests::default()
                    }
                }
                _ => Requests::default(),
            });
        }
        self.items.step(self.now, &requests, &mut self.hazards);
        self.requests = requests;
    }

    /// The outputs as they reach the components: faults, then the supplies; the
    /// frame's inputs are the sensors as last read.
    fn apply_outputs(&mut self) {
        self.outputs_dirty = false;
        let mut out = std::mem::take(&mut self.closed);
        self.contactors_into(&mut out);
        self.unpowered.clear();
        for (o, fed) in &self.supply {
            if !out.get(*o) {
                for &f in fed {
                    self.unpowered.set(f, true);
                }
            }
        }
        for (o, fed) in &self.supply {
            if !out.get(*o) {
                for &f in fed {
                    out.set(f, false);
                }
            }
        }
        self.frame.now_mut(Space::Output).copy_from(&out);
        self.frame.now_mut(Space::Input).copy_from(&self.sensors);
        self.fresh = true;
        self.closed = out;
    }

    /// Each output's contactor as it is: commanded, unless a fault welds or kills it.
    fn contactors_into(&self, out: &mut Bits) {
        out.clone_from(&self.commanded);
        for (i, f) in self.output_force.iter().enumerate() {
            if let Some(v) = f {
                out.set(i, *v);
            }
        }
    }

    fn check_dangers(&mut self) {
        for d in &mut self.dangers {
            let p = match (&self.live[d.component], self.surface_of[d.component]) {
                (Live::Conveyor(_), Some(s)) => self.items.front(s),
                (c, _) => c.position(),
            };
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
        self.items.sense(&mut self.sensors);
        if !self.feedback.is_empty() {
            let mut closed = std::mem::take(&mut self.closed);
            self.contactors_into(&mut closed);
            for &(input, output) in &self.feedback {
                self.sensors.set(input, closed.get(output));
            }
            self.closed = closed;
        }
        for (i, f) in self.sensor_force.iter().enumerate() {
            if let Some(v) = f {
                self.sensors.set(i, *v);
            }
        }
        self.frame.now_mut(Space::Input).copy_from(&self.sensors);
        self.fresh = true;
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
                stuck_at: None,
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
                Effect::StuckAt(k, p) => self.component_faults[k as usize].stuck_at = Some(p),
                Effect::Slow(o, p) => {
                    // The surfaces a drive output moves.
                    let name = &self.symbols.names(Space::Output)[o as usize];
                    for f in &self.items.surfaces {
                        if f.actuators.contains(name) {
                            let c = &mut self.component_faults[f.component];
                            c.speed_percent = c.speed_percent.min(p);
                        }
                    }
                }
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
        let live = &self.live;
        let component = |k: &FaultKind| {
            let find = |c: &str| names.iter().position(|(id, _)| id == c).map(|k| k as u32);
            match k {
                // What stops at a position: an axis, a turntable.
                FaultKind::StuckAt {
                    component,
                    position,
                } => find(component)
                    .filter(|&k| {
                        matches!(live[k as usize], Live::Axis(_) | Live::Turntable(_))
                            && position.0.is_finite()
                    })
                    .map(|k| Effect::StuckAt(k, (position.0 * 1e6).round() as i64)),
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
        // It takes effect at the next internal step, as every fault due then: a pulse
        // of one PLC cycle injected between two cycles is seen by the next one.
        self.faults.push(s);
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
        self.items.delivered.iter().sum::<u32>() + self.items.taken.iter().sum::<u32>()
    }

    /// The classes of items the feeders and sources place, sorted.
    pub fn item_classes(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .items
            .feed_classes
            .iter()
            .flatten()
            .chain(self.items.sources.iter().flat_map(|s| &s.classes))
            .map(|c| c.class.clone())
            .collect();
        v.sort();
        v.dedup();
        v
    }

    /// The items the feeders and sources placed so far.
    pub fn items_in(&self) -> u32 {
        self.items.created()
    }

    /// Items damaged so far, and items that fell off.
    pub fn items_damaged(&self) -> (u32, u32) {
        (self.items.damaged, self.items.fallen)
    }

    /// Per sink or taker (by component id, sorted), the items that left there.
    pub fn items_out_by_exit(&self) -> Vec<(String, u32)> {
        let mut v: Vec<(String, u32)> = self
            .items
            .surfaces
            .iter()
            .enumerate()
            .map(|(s, f)| (f.id.clone(), self.items.delivered[s] + self.items.taken[s]))
            .filter(|(_, n)| *n > 0)
            .collect();
        v.sort();
        v
    }

    /// The items on the placed surfaces as the top view draws them (none when no
    /// surface is placed), and those lying where they fell.
    pub fn boxes(&self) -> Vec<crate::emulator::BoxView> {
        let mut out = Vec::new();
        self.boxes_into(&mut out);
        out
    }

    /// [`Self::boxes`] appended to `out`.
    pub fn boxes_into(&self, out: &mut Vec<crate::emulator::BoxView>) {
        if let Some(t) = &self.top {
            t.boxes_into(&self.items, |k| self.live[k].position(), out);
        }
    }

    /// The angle of the first placed turntable on the floor, millidegrees from +x (0
    /// when there is none).
    pub fn table_angle_mdeg(&self) -> i32 {
        self.top.as_ref().map_or(0, |t| {
            t.table_angle_mdeg(&self.items, |k| self.live[k].position())
        })
    }

    /// Puts an item of the `class`-th class of the plant's first source (`Small` and
    /// `Large` are its first and second) with its centre at `centre` on conveyor or
    /// turntable `id` (from its start, in its unit): a live-mode estimate of the plant
    /// from its sensors. Returns the item's number, or why it was refused.
    pub fn place_item(&mut self, id: &str, centre: f64, class: usize) -> Result<u32, String> {
        let k = self
            .names
            .iter()
            .position(|(c, _)| c == id)
            .ok_or_else(|| format!("no component `{id}`"))?;
        let s = self.surface_of[k].ok_or_else(|| format!("`{id}` carries no item"))?;
        let n = self
            .items
            .place(s, (centre * 1e6).round() as i64, class)
            .ok_or_else(|| format!("the plant has no source with a class {class}"))?;
        self.compute_sensors();
        Ok(n)
    }

    /// The plant has conveyors (its production is items, not only moves).
    pub fn carries_items(&self) -> bool {
        !self.items.surfaces.is_empty()
    }

    /// Items the operator took off the plant by hand so far.
    pub fn items_removed(&self) -> u32 {
        self.items.removed
    }

    /// The operator takes every item off the plant by hand; how many.
    pub fn remove_items(&mut self) -> u32 {
        let n = self.items.clear();
        self.compute_sensors();
        n
    }

    /// Replaces the arrivals of the plant's first source: periodic, or a list of
    /// (time, index of the class in the source's list); false when it has none.
    pub fn set_arrivals(&mut self, plan: super::items::Plan) -> bool {
        let now = self.now;
        match self.items.sources.first_mut() {
            Some(s) => {
                s.set_plan(plan, now);
                true
            }
            None => false,
        }
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
        let mut elements: Vec<_> = self
            .live
            .iter()
            .zip(&self.names)
            .map(|(c, (id, name))| c.scene(id, name))
            .collect();
        for (k, e) in elements.iter_mut().enumerate() {
            let Some(s) = self.surface_of[k] else {
                continue;
            };
            let on: Vec<SceneItem> = self
                .items
                .on(s)
                .into_iter()
                .map(|b| SceneItem {
                    id: b.id,
                    class: b.class.clone(),
                    rear: (b.c - b.half) as f64 / 1e6,
                    length: (2 * b.half) as f64 / 1e6,
                })
                .collect();
            match &mut e.shape {
                super::Shape::Conveyor { items, .. } | super::Shape::Turntable { items, .. } => {
                    *items = on;
                }
                _ => {}
            }
        }
        Scene { elements }
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
        (0..self.live.len()).map(|k| self.position_of(k))
    }

    /// Component `k`'s position: a conveyor's is the front of its item nearest the
    /// exit end (0 when empty).
    fn position_of(&self, k: usize) -> f64 {
        match (&self.live[k], self.surface_of[k]) {
            (Live::Conveyor(_), Some(s)) => self.items.front(s),
            (c, _) => c.position(),
        }
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
        Some(self.position_of(k))
    }

    /// Takes every internal step one at a time (the quiet steps' reference).
    #[cfg(test)]
    pub(crate) fn disable_quiet_steps(&mut self) {
        self.quiet_allowed = false;
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
#[path = "emulator/tests/conveyor.rs"]
mod conveyor_tests;
#[cfg(test)]
#[path = "emulator/tests/device.rs"]
mod device_tests;
#[cfg(test)]
#[path = "emulator/tests/station.rs"]
mod station_tests;
#[cfg(test)]
mod tests;

/// The declared dangers of `desc`, compiled against the plant's symbols.
fn compile_dangers(desc: &Components, symbols: &Symbols) -> Result<Vec<Danger>, Problem> {
    let mut dangers = Vec::new();
    for d in &desc.dangers {
        let when = parse_str(&d.when)
            .and_then(|e| e.to_dnf(symbols))
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
    Ok(dangers)
}

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

/// The items' surfaces of `desc` (its conveyors and turntables, in order), their
/// joins, feeders and sources; per component, its surface.
fn build_items(desc: &Components, live: &mut [Live], seed: u64) -> (Items, Vec<Option<usize>>) {
    use super::items::{Dock, Link, Open, Plan, Source};
    use super::kinds::KindDef;
    let mut surfaces = Vec::new();
    let mut surface_of = vec![None; live.len()];
    for (k, c) in live.iter().enumerate() {
        let (id, name) = (&desc.components[k].id, &desc.components[k].name);
        let s = match c {
            Live::Conveyor(v) => v.surface(k, id, name),
            Live::Turntable(t) => t.surface(k, id, name),
            _ => continue,
        };
        surface_of[k] = Some(surfaces.len());
        surfaces.push(s);
    }
    let by_id = |id: &str| {
        let k = desc.components.iter().position(|c| c.id == id)?;
        surface_of[k]
    };
    let mut docks = Vec::new();
    let mut feed_classes = vec![Vec::new(); surfaces.len()];
    let mut feed_outputs = vec![Vec::new(); surfaces.len()];
    let mut carries = vec![false; surfaces.len()];
    let mut sources = Vec::new();
    let mut tables = 0u64;
    for (k, c) in desc.components.iter().enumerate() {
        let Some(s) = surface_of[k] else { continue };
        match &c.kind {
            KindDef::Conveyor(v) => {
                if let Some(t) = v.target().and_then(by_id)
                    && surfaces[t].rotation.is_none()
                {
                    surfaces[s].fixed[1] = Some(Link { surface: t, end: 0 });
                    surfaces[t].fixed[0] = Some(Link { surface: s, end: 1 });
                }
                if let Live::Conveyor(live) = &mut live[k] {
                    feed_classes[s] = live.feed_classes();
                    feed_outputs[s] = live.feed_outputs();
                    live.feed_from = v.carries_from().and_then(by_id);
                    if let Some(f) = live.feed_from {
                        carries[f] = true;
                    }
                }
                if let Some(src) = &v.source {
                    let n = sources.len() as u64;
                    sources.push(Source::new(
                        s,
                        src.items
                            .iter()
                            .map(super::kinds::conveyor::class)
                            .collect(),
                        Plan::Periodic(src.arrivals.clone()),
                        seed ^ n.wrapping_mul(0x9E37_79B9_7F4A_7C15),
                    ));
                }
            }
            KindDef::Turntable(t) => {
                if let Live::Turntable(live) = &mut live[k] {
                    // The first turntable draws from the stream the sorting
                    // station's emulator gave its table.
                    live.seed(
                        seed ^ 0x5EED_7AB1_E000_0001 ^ tables.wrapping_mul(0x9E37_79B9_7F4A_7C15),
                    );
                    tables += 1;
                }
                for (p, pos) in t.positions.iter().enumerate() {
                    for j in &pos.joins {
                        let Some(to) = by_id(&j.to) else { continue };
                        let to = Link {
                            surface: to,
                            end: j.at.index(),
                        };
                        surfaces[to.surface].table_side[to.end] = true;
                        if to.end == 0 {
                            surfaces[to.surface].open[0] = Open::Drop;
                        }
                        docks.push(Dock {
                            table: s,
                            position: p,
                            table_end: j.end.index(),
                            to,
                        });
                    }
                }
            }
            _ => {}
        }
    }
    // A conveyor's entry another conveyor's exit leads to is joined, not a stop.
    let mut items = Items::new(surfaces, docks, &desc.items, feed_classes);
    items.carries = carries;
    items.feed_outputs = feed_outputs;
    items.sources = sources;
    for (k, c) in live.iter().enumerate() {
        if let (Live::Turntable(t), Some(s)) = (c, surface_of[k]) {
            items.set_docked(s, t.docked);
        }
    }
    (items, surface_of)
}
