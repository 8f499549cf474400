//! Exhaustive verification of a constraint set on an abstract model of the plant
//! (seed 004 §2 and §6.2: safety whatever the control, and controllability).
//!
//! # The abstraction
//! - **Plant** ([`model`]): the emulator's geometry on a grid whose cell is the greatest
//!   common divisor of the lengths the sensors, joints and boxes depend on (20 mm on the
//!   sorting station); one step is the time a surface takes to move one cell (66.7 ms),
//!   the table angle advances by the same time's rotation (2° out, 1.98° back). State:
//!   table angle, boxes (size, frame, rear cell), at most `max_boxes` at once; a box on
//!   an exit past the exit's first sensor is delivered and leaves the model.
//! - **Control**: the most permissive: any vector of the filtered outputs every step;
//!   the exit conveyors run all the time (seed 004 §6.1: "A5 = A6 = 1").
//! - **PLC**: one cycle per step, in the engine's order: inputs, observers (the real
//!   [`Observers`]), commanded vector, the real [`Filter`] (the commanded vector if no
//!   constraint is true, else the fallback), plant step with the applied vector. The
//!   latch is abstracted away (the operator may reset at any cycle), which includes the
//!   latched behaviour since the fallback is also offered every cycle.
//! - **Hazards**: the emulator's list (sheared, dropped, collision, pushed against
//!   stopped) with its margins, evaluated once per step; "no fallback" is reported too.
//!   As in the emulator, the table is joined to the conveyors within the docking
//!   tolerance of the loading/unloading angle, and a box is sheared only when the table
//!   is outside it during the step.
//! - **Sampling**: the real PLC cycle (10 ms) is much shorter than a step, so a sensor
//!   event within a step is seen by the filter. Feed-line beams therefore see a box over
//!   `(rear, front]`: the rear edge that sits on a beam at a step boundary has left it a
//!   cycle later, and a one-cell gap between two boxes shows as the beam falling (P36's
//!   FE(C3), 2P's RE(C0)), as the filter sees it on the real plant.
//!
//! Assumptions (stated in every report): at most `max_boxes` boxes, exits always
//! commanded, safety contactors held ON by the safety function (`held_on`; only the
//! fallback releases them), contactors that neither weld nor die, boxes on the feed line only travel forward, PLC cycle shorter than the
//! time a box takes to cross a 20 mm gap.
//!
//! [`verify`] answers safety, permissiveness (a box can be delivered at each exit),
//! the invariants of `invariants.txt`, and which constraints are necessary. Traces are
//! shortest (breadth-first search) and replayable in the emulator ([`replay`]).

pub mod components;
pub mod model;
pub mod promela;
pub mod scenario;

use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::constraints::ConstraintSet;
use crate::diag::Problem;
use crate::diag::codes;
use crate::emulator::{ArrivalPlan, BoxSize, Hazard, HazardKind, Layout};
use crate::expr;
use crate::filter::Filter;
use crate::frame::Frame;
use crate::observers::Observers;
use crate::symbols::Space;
use crate::time::Millis;
use model::{Geometry, PlantState};
use serde::Serialize;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A small multiplicative hasher (FxHash) for the state table: lookups only, never
/// iterated, so the order of results does not depend on it.
#[derive(Default, Clone, Copy)]
struct Fx(u64);

impl Hasher for Fx {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for c in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..c.len()].copy_from_slice(c);
            self.write_u64(u64::from_le_bytes(w));
        }
    }
    fn write_u8(&mut self, i: u8) {
        self.write_u64(u64::from(i));
    }
    fn write_u16(&mut self, i: u16) {
        self.write_u64(u64::from(i));
    }
    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
}

type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<Fx>>;

/// The key of a memoised filter context: the state's bits, its observers and items, and
/// its four clocks.
type CtxKey = (u64, (u64, u64, u64), [u16; 4]);

/// Options of a verification.
#[derive(Clone, Debug)]
pub struct Options {
    /// Largest number of boxes in the plant at once.
    pub max_boxes: usize,
    /// Also test every constraint for necessity (one exploration per constraint), on a
    /// model with this many boxes (weakened sets have far larger state spaces).
    pub necessity_boxes: Option<usize>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            max_boxes: 2,
            necessity_boxes: Some(1),
        }
    }
}

/// One full abstract state: plant, observers' internal counts, previous cycle's frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct AState {
    /// Plant.
    pub plant: PlantState,
    /// Observer counts.
    pub obs: [u16; 4],
    /// Inputs, applied outputs and observers of the previous cycle.
    pub prev: (u64, u64, u64),
}

/// One step of a trace.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TraceStep {
    /// Start of the step, ms (rounded).
    pub time_ms: u64,
    /// Inputs read at the start of the step, e.g. `C0 C4`.
    pub inputs: String,
    /// Observers true during the step.
    pub observers: String,
    /// Applied outputs during the step.
    pub applied: String,
    /// Applied outputs, by plant output index.
    #[serde(skip)]
    pub applied_bits: u64,
    /// A box arriving at the end of the step.
    pub arrival: Option<BoxSize>,
    /// Table angle at the start, mdeg, and boxes (`frame:rear-cell:size`).
    pub plant: String,
}

/// A trace from the initial state.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Trace {
    /// What it shows.
    pub what: String,
    /// Steps, in order.
    pub steps: Vec<TraceStep>,
}

/// Result for one invariant.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct InvariantResult {
    /// Id.
    pub id: String,
    /// Text.
    pub source: String,
    /// True in no reachable state.
    pub proved: bool,
    /// Shortest trace to a state where it is true.
    pub counterexample: Option<Trace>,
}

/// Result for one constraint.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ConstraintRole {
    /// Id.
    pub id: String,
    /// Removing it makes a hazard reachable.
    pub necessary: bool,
    /// The hazard reached without it (first found, shortest trace length).
    pub hazard: Option<String>,
    /// Length of that trace, steps.
    pub steps: Option<usize>,
    /// Reachable states without it.
    pub states: usize,
}

/// Outcome of one exploration.
#[derive(Clone, Debug, Serialize)]
pub struct Exploration {
    /// Reachable states (hazard states included).
    pub states: usize,
    /// Transitions explored (distinct applied vectors × arrivals).
    pub transitions: u64,
    /// Shortest trace to a hazard, and its kind.
    pub hazard: Option<(String, Trace)>,
    /// Shortest trace to a context with no fallback.
    pub no_fallback: Option<Trace>,
    /// Shortest witness of a delivery at the +u exit (left) and the −u exit (right).
    pub delivered: [Option<Trace>; 2],
    /// Every reachable non-hazard state can still lead to a delivery at each exit.
    pub always_deliverable: [bool; 2],
    /// Otherwise, a shortest trace to a state from which no delivery at that exit is
    /// reachable any more.
    pub stuck: [Option<Trace>; 2],
    /// Per invariant: shortest trace to a state where it is true.
    pub invariants: Vec<Option<Trace>>,
    /// Hazard kinds reachable (each with the length of its shortest trace).
    pub hazard_kinds: Vec<(String, usize)>,
}

/// The whole report of `vigie verify`.
#[derive(Clone, Debug, Serialize)]
pub struct VerifyReport {
    /// Plant name.
    pub plant: String,
    /// Grid and timing of the abstraction.
    pub geometry: Geometry,
    /// Largest number of boxes at once.
    pub max_boxes: usize,
    /// The full constraint set.
    pub full: Exploration,
    /// No hazard reachable and a fallback in every reachable context.
    pub safe: bool,
    /// A delivery is reachable at both exits.
    pub permissive: bool,
    /// Invariants proved or refuted.
    pub invariants: Vec<InvariantResult>,
    /// Necessity of each constraint (empty when not asked).
    pub constraints: Vec<ConstraintRole>,
}

/// What `vigie verify` searches for a plant folder.
#[derive(Clone, Debug)]
pub enum Subject {
    /// A turntable cell of the station's kind, searched whole by [`verify`]: a legacy
    /// `layout.ron`, or the cell a placed `components.ron` derives.
    Cell(Box<Layout>),
    /// Any other plant of components, searched per sub-plant by [`components`].
    Parts(Box<crate::machine::description::Components>),
}

/// The verification subject of a plant folder (a folder without a physical model is
/// V0744).
pub fn subject_of(dir: &std::path::Path) -> Result<Subject, Vec<Problem>> {
    Ok(match crate::machine::Description::load(dir)? {
        crate::machine::Description::Components(c) => match Layout::from_components(&c) {
            Some(cell) => Subject::Cell(Box::new(cell)),
            None => Subject::Parts(Box::new(c)),
        },
    })
}

/// Hazard name as the emulator serialises it.
pub fn hazard_name(k: HazardKind) -> &'static str {
    match k {
        HazardKind::Sheared => "sheared",
        HazardKind::Dropped => "dropped",
        HazardKind::Collision => "collision",
        HazardKind::PushedAgainstStopped => "pushed_against_stopped",
        HazardKind::EndStop => "end_stop",
        HazardKind::OpposedDrives => "opposed_drives",
        HazardKind::Declared => "declared",
        HazardKind::Overflow => "overflow",
        HazardKind::DryRun => "dry_run",
    }
}

/// The model: geometry, symbols, observers and the names it prints.
#[derive(Clone, Debug)]
pub struct Model {
    /// Grid.
    pub geo: Geometry,
    observers: Observers,
    invariants: Vec<expr::Dnf>,
    n_in: usize,
    n_out: usize,
    n_obs: usize,
    input_names: Vec<String>,
    output_names: Vec<String>,
    obs_names: Vec<String>,
    max_boxes: usize,
    /// Outputs the control may command (all but the exits' and the safety contactors').
    free_outputs: Vec<usize>,
    /// Outputs ON whatever the control: the exits, the safety contactors (`held_on`).
    always_on: u64,
    /// Variables read at t-1 by a constraint, an observer or an invariant (inputs,
    /// outputs, observers): the state keeps only these of the previous cycle.
    prev_mask: (u64, u64, u64),
    /// Mirror contacts (`feedback_of`): the input reads the output applied at t-1 (the
    /// model's contactors neither weld nor die).
    feedback: Vec<(usize, usize)>,
    /// Safety contactors (`supplies`): the output, and the outputs it powers.
    supply: Vec<(usize, u64)>,
}

impl Model {
    /// Builds the model of a plant bundle and its layout.
    pub fn new(bundle: &PlantBundle, layout: &Layout, max_boxes: usize) -> Result<Self, Problem> {
        let geo = Geometry::new(layout, &bundle.plant)?;
        if bundle.observers.len() > 4 {
            return Err(Problem::error(
                codes::VERIFY_UNSUPPORTED.id,
                "the verifier handles at most 4 observers",
                None,
            ));
        }
        let n_out = bundle.plant.outputs.len();
        // The exits always run, and the safety function holds its contactors ON
        // (`held_on`): the control commands neither; only the fallback releases them.
        let always_on = (0..n_out)
            .filter(|&k| geo.exit_act.contains(&k) || bundle.plant.outputs[k].held_on)
            .fold(0u64, |m, k| m | 1 << k);
        let free_outputs = (0..n_out).filter(|k| always_on >> k & 1 == 0).collect();
        let feedback = bundle.plant.mirrors();
        let prev_mask = prev_reads(bundle, &feedback);
        let supply = bundle
            .plant
            .supplies()
            .into_iter()
            .map(|(o, fed)| (o, fed.iter().fold(0u64, |m, k| m | 1 << k)))
            .collect();
        let n_in = bundle.plant.inputs.len();
        let n_obs = bundle.observers.len();
        let prev_mask = budget(prev_mask, [n_in, n_out, n_obs])?;
        Ok(Self {
            geo,
            observers: bundle.observers.clone(),
            invariants: bundle
                .invariants
                .constraints
                .iter()
                .map(|c| c.dnf.clone())
                .collect(),
            n_in,
            n_out,
            n_obs,
            input_names: bundle.symbols.names(Space::Input).to_vec(),
            output_names: bundle.symbols.names(Space::Output).to_vec(),
            obs_names: bundle.symbols.names(Space::Observer).to_vec(),
            max_boxes: max_boxes.clamp(1, model::MAX_BOXES),
            free_outputs,
            always_on,
            prev_mask,
            feedback,
            supply,
        })
    }

    /// Packs a state into 128 bits (the layout is checked by [`Model::new`]).
    pub fn pack(&self, s: &AState) -> u128 {
        let mut k = u128::from(s.plant.angle as u32);
        k = k << 3 | u128::from(s.plant.n);
        for b in &s.plant.boxes {
            let lo = (i32::from(b.lo) + 512) as u128 & 0x3ff;
            k = k << 12 | u128::from(b.on_table) << 11 | u128::from(b.large) << 10 | lo;
        }
        for c in s.obs {
            k = k << 4 | u128::from(c.min(15));
        }
        for (v, m) in [
            (s.prev.0, self.prev_mask.0),
            (s.prev.1, self.prev_mask.1),
            (s.prev.2, self.prev_mask.2),
        ] {
            k = k << m.count_ones() | u128::from(compact(v, m));
        }
        k
    }

    /// Inverse of [`Model::pack`].
    pub fn unpack(&self, mut k: u128) -> AState {
        let mut take = |m: u64| {
            let n = m.count_ones();
            let v = expand((k & ((1u128 << n) - 1)) as u64, m);
            k >>= n;
            v
        };
        let ov = take(self.prev_mask.2);
        let out = take(self.prev_mask.1);
        let inp = take(self.prev_mask.0);
        let mut obs = [0u16; 4];
        for c in obs.iter_mut().rev() {
            *c = (k & 15) as u16;
            k >>= 4;
        }
        let mut boxes = [model::ABox::default(); model::MAX_BOXES];
        for b in boxes.iter_mut().rev() {
            let v = k & 0xfff;
            k >>= 12;
            *b = model::ABox {
                on_table: v >> 11 & 1 == 1,
                large: v >> 10 & 1 == 1,
                lo: ((v & 0x3ff) as i32 - 512) as i16,
            };
        }
        let n = (k & 7) as u8;
        k >>= 3;
        AState {
            plant: PlantState {
                angle: (k & 0xffff_ffff) as u32 as i32,
                n,
                boxes,
            },
            obs,
            prev: (inp, out, ov),
        }
    }

    /// The outputs that act: `applied` less those whose safety contactor is released;
    /// and whether the rotation is without its supply (the table then stays where it
    /// is, as in the emulator: it does not return on its own).
    fn powered(&self, applied: u64) -> (u64, bool) {
        let unpowered = self
            .supply
            .iter()
            .filter(|(o, _)| applied >> o & 1 == 0)
            .fold(0, |a, (_, mask)| a | mask);
        (applied & !unpowered, unpowered >> self.geo.rotate & 1 == 1)
    }

    /// The initial state.
    pub fn initial(&self) -> AState {
        AState {
            plant: self.geo.initial(),
            obs: [0; 4],
            prev: (0, 0, 0),
        }
    }

    fn names(names: &[String], bits: u64) -> String {
        names
            .iter()
            .enumerate()
            .filter(|(i, _)| bits >> i & 1 == 1)
            .map(|(_, n)| n.as_str())
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The frame of a state at the start of its cycle (inputs and observers at t,
    /// previous cycle at t-1), and the updated observer counts.
    fn frame(&self, s: &AState, frame: &mut Frame, obs: &mut Observers) -> (u64, u64, [u16; 4]) {
        let mut inputs = self.geo.sensors(&s.plant);
        for &(i, o) in &self.feedback {
            if s.prev.1 >> o & 1 == 1 {
                inputs |= 1 << i;
            }
        }
        for (i, b) in [s.prev.0, s.prev.1, s.prev.2].iter().enumerate() {
            let space = Space::ALL[i];
            let n = frame.prev[space as usize].len();
            for k in 0..n {
                frame.prev[space as usize].set(k, b >> k & 1 == 1);
            }
        }
        for k in 0..self.n_in {
            frame.now[0].set(k, inputs >> k & 1 == 1);
        }
        let counts: Vec<u32> = s.obs[..self.n_obs].iter().map(|&c| u32::from(c)).collect();
        obs.set_counts(&counts);
        obs.update(frame);
        let mut ov = 0u64;
        for k in 0..self.n_obs {
            if frame.now[Space::Observer as usize].get(k) {
                ov |= 1 << k;
            }
        }
        let mut counts = [0u16; 4];
        for (c, &v) in counts.iter_mut().zip(obs.counts()) {
            *c = v.min(u32::from(u16::MAX)) as u16;
        }
        (inputs, ov, counts)
    }

    fn plant_text(&self, p: &PlantState) -> String {
        let mut s = format!("angle {}", p.angle / 1000);
        for b in &p.boxes[..usize::from(p.n)] {
            s.push_str(&format!(
                " {}:{}:{}",
                if b.on_table { "table" } else { "line" },
                b.lo,
                if b.large { "L" } else { "S" }
            ));
        }
        s
    }
}

/// The variables read at t-1 by a constraint, an observer or an invariant (inputs,
/// outputs, observers), one bit each; a mirror contact read as its output at t-1.
fn prev_reads(bundle: &PlantBundle, feedback: &[(usize, usize)]) -> (u64, u64, u64) {
    let mut prev_mask = (0u64, 0u64, 0u64);
    let mut dnfs: Vec<expr::Dnf> = bundle
        .constraints
        .constraints
        .iter()
        .chain(&bundle.invariants.constraints)
        .map(|c| c.dnf.clone())
        .collect();
    for d in &bundle.observers.defs {
        for t in d.rule.expressions() {
            match expr::parse_str(t).and_then(|e| e.to_dnf(&bundle.symbols)) {
                Ok(dnf) => dnfs.push(dnf),
                // Unreadable rule: keep every previous value.
                Err(_) => prev_mask = (u64::MAX, u64::MAX, u64::MAX),
            }
        }
    }
    // A mirror contact reads its output as applied at t-1, and the model's
    // contactors neither weld nor die: a term that reads a mirror and its output at
    // t-1 with opposite polarities (`KM0 . A1_fb . /A1*`, a welded drive) is never
    // true, and keeps no previous output in the state (both read 0 there).
    let as_read = |l: &crate::symbols::Literal| {
        let mut l = *l;
        if l.var.space == Space::Input
            && !l.var.prev
            && let Some(&(_, o)) = feedback.iter().find(|(i, _)| *i == l.var.index as usize)
        {
            l.var.space = Space::Output;
            l.var.index = o as u32;
            l.var.prev = true;
        }
        l
    };
    let possible = |t: &&Vec<crate::symbols::Literal>| {
        let t: Vec<_> = t.iter().map(as_read).collect();
        !t.iter()
            .any(|a| t.iter().any(|b| a.var == b.var && a.positive != b.positive))
    };
    for l in dnfs
        .iter()
        .flatten()
        .filter(possible)
        .flatten()
        .map(as_read)
    {
        if l.var.prev && l.var.index < 64 {
            let bit = 1u64 << l.var.index;
            match l.var.space {
                Space::Input => prev_mask.0 |= bit,
                Space::Output => prev_mask.1 |= bit,
                Space::Observer => prev_mask.2 |= bit,
                Space::Aux => {}
            }
        }
    }
    prev_mask
}

/// Bits of the state left for the previous-cycle values (the plant's positions, its
/// items and the observers' counts take the other 99 of 128).
const PREV_BITS: usize = 128 - 99;

/// The previous-cycle values the state keeps (`mask` within each kind's width), checked
/// against [`PREV_BITS`]: the state keeps only the values something reads (packed one
/// bit each, [`Model::pack`]), so the plant's size does not count, only those.
fn budget(mask: (u64, u64, u64), widths: [usize; 3]) -> Result<(u64, u64, u64), Problem> {
    let [n_in, n_out, n_obs] = widths;
    let mask = (
        mask.0 & low_bits(n_in),
        mask.1 & low_bits(n_out),
        mask.2 & low_bits(n_obs),
    );
    let kept = [mask.0, mask.1, mask.2]
        .iter()
        .map(|m| m.count_ones() as usize)
        .sum::<usize>();
    if widths.iter().any(|&w| w > 64) || kept > PREV_BITS {
        return Err(Problem::error(
            codes::VERIFY_UNSUPPORTED.id,
            format!(
                "the verifier keeps at most {PREV_BITS} previous-cycle values in its state \
                 and 64 signals of each kind; this plant's constraints, observers and \
                 invariants read {kept} at t-1 ({n_in} inputs, {n_out} outputs, {n_obs} observers)"
            ),
            None,
        ));
    }
    Ok(mask)
}

/// The `n` low bits set.
fn low_bits(n: usize) -> u64 {
    if n >= 64 { u64::MAX } else { (1u64 << n) - 1 }
}

/// The bits of `v` under `mask`, packed to the low end in mask order.
fn compact(v: u64, mask: u64) -> u64 {
    let (mut out, mut k, mut m) = (0u64, 0, mask);
    while m != 0 {
        let bit = m & m.wrapping_neg();
        if v & bit != 0 {
            out |= 1 << k;
        }
        k += 1;
        m &= m - 1;
    }
    out
}

/// Inverse of [`compact`]: the packed low bits of `v` put back under `mask`.
fn expand(v: u64, mask: u64) -> u64 {
    let (mut out, mut k, mut m) = (0u64, 0, mask);
    while m != 0 {
        let bit = m & m.wrapping_neg();
        if v >> k & 1 == 1 {
            out |= bit;
        }
        k += 1;
        m &= m - 1;
    }
    out
}

/// What a transition leads to.
#[derive(Clone, Copy, Debug)]
struct Edge {
    parent: u32,
    applied: u64,
    arrival: Option<BoxSize>,
}

/// Explores the reachable states of `model` under `filter` breadth-first.
pub fn explore(model: &Model, filter: &Filter) -> Exploration {
    let mut index: FxMap<u128, u32> = FxMap::default();
    let mut states: Vec<u128> = Vec::new();
    let mut edges: Vec<Option<Edge>> = Vec::new();
    let s0 = model.initial();
    index.insert(model.pack(&s0), 0);
    states.push(model.pack(&s0));
    edges.push(None);
    let mut frame = Frame::new([model.n_in, model.n_out, model.n_obs, 0]);
    let mut obs = model.observers.clone();
    let mut viol = Vec::new();
    let mut hazard: Option<(String, u32, Edge)> = None;
    let mut kinds: Vec<(HazardKind, u32, Edge)> = Vec::new();
    let mut no_fallback: Option<u32> = None;
    let mut delivered: [Option<(u32, Edge)>; 2] = [None, None];
    let mut inv: Vec<Option<u32>> = vec![None; model.invariants.len()];
    let mut transitions = 0u64;
    let mut cache: FxMap<CtxKey, Ctx> = FxMap::default();
    // Graph for the "always deliverable" check: successors of each state, and the states
    // with a delivering transition.
    let mut succ: Vec<u32> = Vec::new();
    let mut succ_start: Vec<usize> = Vec::new();
    let mut delivers: Vec<[bool; 2]> = Vec::new();
    let exits = model.geo.exit_act.iter().fold(0u64, |m, &k| m | 1 << k);
    let mut head = 0usize;
    while head < states.len() {
        let s = model.unpack(states[head]);
        let si = head as u32;
        head += 1;
        succ_start.push(succ.len());
        delivers.push([false, false]);
        let inputs = model.geo.sensors(&s.plant);
        let key = (inputs, s.prev, s.obs);
        let ctx = cache
            .entry(key)
            .or_insert_with(|| context(model, filter, &s, &mut frame, &mut obs, &mut viol, exits))
            .clone();
        let (ov, counts) = (ctx.ov, ctx.counts);
        first_seen(&ctx, si, &mut inv, &mut no_fallback);
        let applied_set = &ctx.applied;
        let arrivals = arrivals(model, &s);
        for &applied in applied_set.iter() {
            for &arrival in &arrivals {
                transitions += 1;
                let (p, ev) = model.geo.step(&s.plant, model.powered(applied), arrival);
                let edge = Edge {
                    parent: si,
                    applied,
                    arrival,
                };
                if let Some(h) = ev.hazard {
                    if !kinds.iter().any(|(k, _, _)| *k == h) {
                        kinds.push((h, si, edge));
                    }
                    if hazard.is_none() {
                        hazard = Some((hazard_name(h).to_string(), si, edge));
                    }
                    continue;
                }
                for (side, d) in [ev.delivered_plus, ev.delivered_minus].iter().enumerate() {
                    if *d {
                        delivers[si as usize][side] = true;
                        if delivered[side].is_none() {
                            delivered[side] = Some((si, edge));
                        }
                    }
                }
                let next = AState {
                    plant: p,
                    obs: counts,
                    prev: (
                        inputs & model.prev_mask.0,
                        applied & model.prev_mask.1,
                        ov & model.prev_mask.2,
                    ),
                };
                let key = model.pack(&next);
                let id = intern(&mut index, &mut states, &mut edges, key, edge);
                succ.push(id);
            }
        }
    }
    // Backward reachability to a delivering state, per exit.
    drop(index);
    let (always, stuck_at) = deliverable(states.len(), succ, succ_start, &delivers);
    let findings = Findings {
        hazard,
        kinds,
        no_fallback,
        delivered,
        inv,
    };
    report(
        model,
        &states,
        &edges,
        transitions,
        findings,
        always,
        stuck_at,
    )
}

/// The id of state `key`, added (reached by `edge`) when new.
fn intern(
    index: &mut FxMap<u128, u32>,
    states: &mut Vec<u128>,
    edges: &mut Vec<Option<Edge>>,
    key: u128,
    edge: Edge,
) -> u32 {
    match index.get(&key) {
        Some(&id) => id,
        None => {
            let id = states.len() as u32;
            index.insert(key, id);
            states.push(key);
            edges.push(Some(edge));
            id
        }
    }
}

/// Records state `si` as the first where each invariant holds, and where no fallback
/// vector exists, when it is.
fn first_seen(ctx: &Ctx, si: u32, inv: &mut [Option<u32>], no_fallback: &mut Option<u32>) {
    for (k, slot) in inv.iter_mut().enumerate() {
        if slot.is_none() && ctx.inv >> k & 1 == 1 {
            *slot = Some(si);
        }
    }
    if ctx.no_fallback && no_fallback.is_none() {
        *no_fallback = Some(si);
    }
}

/// The arrivals possible in `s`: none, and each box size that fits at the source.
fn arrivals(model: &Model, s: &AState) -> Vec<Option<BoxSize>> {
    let mut arrivals = vec![None];
    if usize::from(s.plant.n) < model.max_boxes {
        for size in [BoxSize::Small, BoxSize::Large] {
            if model.geo.can_spawn(&s.plant, size) {
                arrivals.push(Some(size));
            }
        }
    }
    arrivals
}

/// Backward reachability to a delivering state, per exit: whether every state can still
/// deliver, and the first state that cannot.
fn deliverable(
    n_states: usize,
    succ: Vec<u32>,
    mut succ_start: Vec<usize>,
    delivers: &[[bool; 2]],
) -> ([bool; 2], [Option<u32>; 2]) {
    let mut always = [true, true];
    let mut stuck_at: [Option<u32>; 2] = [None, None];
    succ_start.push(succ.len());
    // Predecessors in compressed rows.
    let n = n_states;
    let mut pstart = vec![0usize; n + 1];
    for &j in &succ {
        pstart[j as usize + 1] += 1;
    }
    for i in 0..n {
        pstart[i + 1] += pstart[i];
    }
    let mut fill = pstart.clone();
    let mut pred = vec![0u32; succ.len()];
    for i in 0..n {
        for &j in &succ[succ_start[i]..succ_start[i + 1]] {
            pred[fill[j as usize]] = i as u32;
            fill[j as usize] += 1;
        }
    }
    drop(succ);
    for side in 0..2 {
        let mut good: Vec<bool> = delivers.iter().map(|d| d[side]).collect();
        let mut stack: Vec<u32> = (0..n_states as u32).filter(|&i| good[i as usize]).collect();
        while let Some(i) = stack.pop() {
            for &p in &pred[pstart[i as usize]..pstart[i as usize + 1]] {
                if !good[p as usize] {
                    good[p as usize] = true;
                    stack.push(p);
                }
            }
        }
        always[side] = good.iter().all(|&g| g);
        stuck_at[side] = good.iter().position(|&g| !g).map(|i| i as u32);
    }
    (always, stuck_at)
}

/// What the exploration found, before traces are built.
struct Findings {
    hazard: Option<(String, u32, Edge)>,
    kinds: Vec<(HazardKind, u32, Edge)>,
    no_fallback: Option<u32>,
    delivered: [Option<(u32, Edge)>; 2],
    inv: Vec<Option<u32>>,
}

/// The exploration's report, with the traces of its findings.
fn report(
    model: &Model,
    states: &[u128],
    edges: &[Option<Edge>],
    transitions: u64,
    findings: Findings,
    always: [bool; 2],
    stuck_at: [Option<u32>; 2],
) -> Exploration {
    let Findings {
        hazard,
        kinds,
        no_fallback,
        delivered,
        inv,
    } = findings;
    let trace = |what: String, last: u32, extra: Option<Edge>| -> Trace {
        build_trace(model, states, edges, what, last, extra)
    };
    Exploration {
        states: states.len() + kinds.len().min(1),
        transitions,
        hazard: hazard.map(|(name, si, e)| {
            let t = trace(format!("hazard: {name}"), si, Some(e));
            (name, t)
        }),
        no_fallback: no_fallback.map(|si| trace("no fallback vector".into(), si, None)),
        delivered: [0, 1].map(|side| {
            delivered[side].map(|(si, e)| {
                trace(
                    format!(
                        "delivery at the {} exit",
                        if side == 0 { "+u (left)" } else { "-u (right)" }
                    ),
                    si,
                    Some(e),
                )
            })
        }),
        always_deliverable: always,
        stuck: [0, 1].map(|side| {
            stuck_at[side].map(|si| trace("no delivery reachable any more".into(), si, None))
        }),
        invariants: inv
            .iter()
            .map(|o| o.map(|si| trace("invariant true".into(), si, None)))
            .collect(),
        hazard_kinds: kinds
            .iter()
            .map(|(k, si, _)| (hazard_name(*k).to_string(), depth(edges, *si) + 1))
            .collect(),
    }
}

/// What a cycle's context allows: observers, invariants, applied vectors.
#[derive(Clone, Debug)]
struct Ctx {
    ov: u64,
    counts: [u16; 4],
    inv: u64,
    no_fallback: bool,
    applied: std::rc::Rc<Vec<u64>>,
}

/// Evaluates observers, invariants and the filter for every commanded vector.
fn context(
    model: &Model,
    filter: &Filter,
    s: &AState,
    frame: &mut Frame,
    obs: &mut Observers,
    viol: &mut Vec<usize>,
    exits: u64,
) -> Ctx {
    let (_, ov, counts) = model.frame(s, frame, obs);
    let mut inv = 0u64;
    for (k, d) in model.invariants.iter().enumerate().take(64) {
        if expr::eval_dnf(d, frame) {
            inv |= 1 << k;
        }
    }
    let fallback = filter.fallback(frame);
    let mut no_fallback = false;
    let mut applied_set: Vec<u64> = Vec::new();
    let n_free = model.free_outputs.len();
    for c in 0..(1u64 << n_free) {
        let mut cmd = model.always_on;
        for (j, &k) in model.free_outputs.iter().enumerate() {
            if c >> j & 1 == 1 {
                cmd |= 1 << k;
            }
        }
        for k in 0..model.n_out {
            frame.now[Space::Output as usize].set(k, cmd >> k & 1 == 1);
        }
        filter.violations_into(frame, viol);
        let applied = if viol.is_empty() {
            cmd
        } else {
            match &fallback {
                Ok(b) => b.ones().fold(exits, |a, k| a | 1 << k),
                Err(_) => {
                    no_fallback = true;
                    continue;
                }
            }
        };
        if !applied_set.contains(&applied) {
            applied_set.push(applied);
        }
    }
    applied_set.sort_unstable();
    Ctx {
        ov,
        counts,
        inv,
        no_fallback,
        applied: std::rc::Rc::new(applied_set),
    }
}

fn depth(edges: &[Option<Edge>], mut i: u32) -> usize {
    let mut d = 0;
    while let Some(e) = edges[i as usize] {
        i = e.parent;
        d += 1;
    }
    d
}

fn build_trace(
    model: &Model,
    states: &[u128],
    edges: &[Option<Edge>],
    what: String,
    last: u32,
    extra: Option<Edge>,
) -> Trace {
    let mut chain: Vec<(u32, Option<Edge>)> = Vec::new();
    let mut out_edge = extra;
    let mut i = last;
    loop {
        chain.push((i, out_edge));
        match edges[i as usize] {
            Some(e) => {
                out_edge = Some(e);
                i = e.parent;
            }
            None => break,
        }
    }
    chain.reverse();
    let mut frame = Frame::new([model.n_in, model.n_out, model.n_obs, 0]);
    let mut obs = model.observers.clone();
    let steps = chain
        .iter()
        .enumerate()
        .map(|(k, (si, e))| {
            let s = &model.unpack(states[*si as usize]);
            let (inputs, ov, _) = model.frame(s, &mut frame, &mut obs);
            let applied = e.map_or(0, |e| e.applied);
            TraceStep {
                time_ms: (k as i64 * model.geo.step_us / 1000) as u64,
                inputs: Model::names(&model.input_names, inputs),
                observers: Model::names(&model.obs_names, ov),
                applied: Model::names(&model.output_names, applied),
                applied_bits: applied,
                arrival: e.and_then(|e| e.arrival),
                plant: model.plant_text(&s.plant),
            }
        })
        .collect();
    Trace { what, steps }
}

/// Loads the layout of a plant folder and verifies its constraint set.
pub fn verify(
    bundle: &PlantBundle,
    layout: &Layout,
    opts: &Options,
) -> Result<VerifyReport, Problem> {
    let model = Model::new(bundle, layout, opts.max_boxes)?;
    let filter = Filter::for_plant(&bundle.constraints, &bundle.plant);
    let full = explore(&model, &filter);
    let invariants = bundle
        .invariants
        .constraints
        .iter()
        .zip(&full.invariants)
        .map(|(c, t)| InvariantResult {
            id: c.id.clone(),
            source: c.source.clone(),
            proved: t.is_none(),
            counterexample: t.clone(),
        })
        .collect();
    let constraints = match opts.necessity_boxes {
        Some(nb) => necessity(bundle, layout, nb)?,
        None => Vec::new(),
    };
    Ok(VerifyReport {
        plant: bundle.plant.name.clone(),
        geometry: model.geo.clone(),
        max_boxes: model.max_boxes,
        safe: full.hazard.is_none() && full.no_fallback.is_none(),
        permissive: full.delivered.iter().all(Option::is_some),
        full,
        invariants,
        constraints,
    })
}

/// Which constraints are necessary: for each, the set without it explored on a model
/// with `max_boxes` boxes.
pub fn necessity(
    bundle: &PlantBundle,
    layout: &Layout,
    max_boxes: usize,
) -> Result<Vec<ConstraintRole>, Problem> {
    let model = Model::new(bundle, layout, max_boxes)?;
    let mut roles = Vec::new();
    for i in 0..bundle.constraints.constraints.len() {
        let set = without(&bundle.constraints, i);
        let e = explore(&model, &Filter::for_plant(&set, &bundle.plant));
        let steps = e.hazard.as_ref().map(|(_, t)| t.steps.len());
        roles.push(ConstraintRole {
            id: bundle.constraints.constraints[i].id.clone(),
            necessary: e.hazard.is_some() || e.no_fallback.is_some(),
            hazard: e
                .hazard
                .as_ref()
                .map(|(h, _)| h.clone())
                .or_else(|| e.no_fallback.as_ref().map(|_| "no_fallback".into())),
            steps,
            states: e.states,
        });
    }
    Ok(roles)
}

/// The constraint set without constraint `i`.
pub fn without(set: &ConstraintSet, i: usize) -> ConstraintSet {
    let mut s = set.clone();
    if i < s.constraints.len() {
        s.constraints.remove(i);
    }
    s
}

/// What the emulator did when driven by a trace's applied outputs.
#[derive(Clone, Debug, Serialize)]
pub struct Replay {
    /// Hazards the emulator reported.
    pub hazards: Vec<Hazard>,
    /// The per-cycle trace (CSV of `crate::trace`), 10 ms cycles, outputs as applied.
    pub csv: String,
    /// Boxes delivered (left, right).
    pub delivered: (u32, u32),
}

/// Replays a trace in the emulator: the arrivals at the step ends, the applied outputs
/// held for each step, sampled every `cycle_ms` into a trace CSV.
pub fn replay(
    layout: &Layout,
    bundle: &PlantBundle,
    trace: &Trace,
    step_us: i64,
    cycle_ms: u64,
) -> Result<Replay, Problem> {
    let plant = &bundle.plant;
    let mut emu = crate::machine::Physical::of_cell(layout, plant, 1)?;
    let arrivals: Vec<(u64, BoxSize)> = trace
        .steps
        .iter()
        .enumerate()
        .filter_map(|(k, s)| {
            s.arrival
                .map(|a| (((k as i64 + 1) * step_us / 1000) as u64, a))
        })
        .collect();
    emu.set_arrivals(ArrivalPlan::List(arrivals));
    let mut csv = String::from("time_ms");
    for s in plant.inputs.iter().chain(&plant.outputs) {
        csv.push(',');
        csv.push_str(&s.id);
    }
    csv.push('\n');
    let n_out = plant.outputs.len();
    let end_ms = (trace.steps.len() as i64 * step_us / 1000) as u64 + 200;
    let cycle = cycle_ms.max(1);
    let mut out = Bits::zeros(n_out);
    for t in 0..end_ms {
        let k = (t as i64 * 1000 / step_us.max(1)) as usize;
        let bits = trace.steps.get(k).map_or(0, |s| s.applied_bits);
        for i in 0..n_out {
            out.set(i, bits >> i & 1 == 1);
        }
        if t % cycle == 0 {
            let row: Vec<String> = emu
                .sensors()
                .to_bools()
                .into_iter()
                .chain(out.to_bools())
                .map(|b| u8::from(b).to_string())
                .collect();
            csv.push_str(&format!("{},{}\n", t, row.join(",")));
        }
        emu.step(Millis(1), &out);
    }
    let st = emu.stats();
    Ok(Replay {
        hazards: emu.hazards().to_vec(),
        csv,
        delivered: {
            let at = |side: crate::emulator::Side| {
                layout
                    .elevators
                    .iter()
                    .find(|e| e.side == side)
                    .map_or(0, |e| st.delivered_at(&e.conveyor))
            };
            (
                at(crate::emulator::Side::Left),
                at(crate::emulator::Side::Right),
            )
        },
    })
}

#[cfg(test)]
mod tests;
