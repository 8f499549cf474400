//! The closed loop fed from a live link instead of the emulator: the console opened on a
//! monitor or gateway run (`vigie --link CONFIG`).
//!
//! Every cycle the link ran (the plant's inputs, the outputs the PLC commanded, the
//! outputs the link applied, whether its engine was reset first) goes through this
//! simulation's engine, which mirrors the link's own engine: same filter mode, same
//! inputs, same commands, same resets, hence the same trips at the same cycles. The
//! recorder, the explanations (level 1 from an emulator initialised from the
//! observation), the task monitors, the diagnosers (stepped when the link stepped its
//! own, on the same frames: the same decisions, the same flags for the rewritten
//! constraints), the alarms and the journal then work as in emulator mode. The emulator
//! never runs: it only shows where the boxes are estimated to be, rebuilt from the
//! observation whenever the sensors or the observers change.

use super::diagnosis::{LinkStep, run_link_step};
use super::{OperatorAction, Simulation, explain_live_projected};
use crate::bits::Bits;
use crate::emulator::ArrivalPlan;
use crate::engine::{Commanded, FilterMode};
use crate::explain;
use crate::time::Millis;

/// One cycle of a live link, as the console receives it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObservedCycle {
    /// Time of the cycle since the start of the link.
    pub time: Millis,
    /// The plant's inputs used by the cycle (held values for stale ones).
    pub inputs: Bits,
    /// The outputs the PLC commanded (monitor mode: the outputs read).
    pub commanded: Bits,
    /// The outputs the link applied to the plant (gateway mode: after the filter and the
    /// safe outputs of a lost PLC or of stale inputs; monitor mode: the commanded ones).
    pub applied: Bits,
    /// The link's engine was reset (operator or automatic reset) just before this cycle.
    pub reset: bool,
    /// What the link's diagnosers did in this cycle (the mirror's do the same).
    pub diagnosers: LinkStep,
    /// The link's engine attached to the running plant at this cycle (its first
    /// values read are also its values at t-1, see [`crate::engine::FirstCycle`]).
    pub attach: bool,
    /// A trip latched before the link restarted, restored by its engine before this
    /// cycle (the mirror restores it too).
    pub restored: Option<crate::engine::Trip>,
    /// The link's follower of the PLC's program (`--program`) stepped this cycle (the
    /// mirror's steps too; once it stops, the mirror's stops for good).
    pub followed: bool,
}

impl Simulation {
    /// Switches to observation of a live link whose engine runs in `mode` (report-only
    /// in monitor mode, enforce in gateway mode): scheduled actions are dropped, no box
    /// arrives, and time follows the link's cycles from now on.
    pub fn follow_link(&mut self, mode: FilterMode) {
        self.live_now = Some(self.live_now.unwrap_or(Millis::ZERO));
        self.pending.clear();
        self.engine.set_mode(mode);
        if mode == FilterMode::ReportOnly {
            // A monitor: the PLC drives the safety devices, Vigie writes nothing.
            self.engine.observe_safety_devices();
        }
        self.emulator.set_arrivals(ArrivalPlan::List(Vec::new()));
        self.log("link", format!("following a live link, filter {mode:?}"));
    }

    /// Follows `program` beside the live PLC as the link does (`--program`): the
    /// program shown is that one, and the explanations of a trip read its situation
    /// (the hypothesis names its elements, the projection runs it).
    pub fn follow_program(&mut self, program: std::sync::Arc<crate::control::CompiledProgram>) {
        self.follower = Some(crate::live::follow::Follower::new(
            std::sync::Arc::clone(&program),
            &self.bundle.plant,
            crate::live::follow::TOLERANCE,
        ));
        let name = format!(
            "{} (version {})",
            program.program.name,
            program.program.version()
        );
        self.program = crate::control::ProgramRuntime::new(program);
        self.program_before = self.program.clone();
        self.log("link", format!("following the PLC with the program {name}"));
    }

    /// True when fed from a live link.
    pub fn is_live(&self) -> bool {
        self.live_now.is_some()
    }

    /// Runs one observed cycle (see the module documentation). Cycles older than the
    /// last one observed are taken at the last time (time never goes back).
    pub fn observe(&mut self, cycle: &ObservedCycle) {
        let now = cycle.time.max(self.now());
        self.live_now = Some(now);
        if cycle.reset && self.engine.is_tripped() {
            let _ = self.act(&OperatorAction::Reset);
        }
        if let Some(trip) = &cycle.restored {
            self.engine.restore_trip(trip.clone());
            self.log(
                "trip",
                format!(
                    "a trip latched before the link restarted holds ({})",
                    trip.constraints
                        .iter()
                        .map(|c| c.id.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            );
        }
        if cycle.attach {
            self.engine.attach_next_cycle();
        }
        let mut control = Commanded(cycle.commanded.clone());
        self.engine.cycle(now, &cycle.inputs, &mut control);
        match (&mut self.follower, cycle.followed) {
            (Some(f), true) => {
                let _ = f.step(now, &cycle.inputs, &cycle.commanded);
            }
            // The link stopped following (its peer was lost): so does the mirror.
            (Some(f), false) if f.started() => self.follower = None,
            _ => {}
        }
        // What the plant really received (gateway: safe outputs for a lost PLC or stale
        // inputs), as the link's engine records it for the next cycle.
        self.engine.set_applied(&cycle.applied);
        // The diagnosers follow those outputs, stepped as the link stepped its own.
        if let Some(d) = self.diagnosers.as_mut() {
            let step = cycle.diagnosers;
            let had_flags = !d.flagged().is_empty();
            self.engine
                .after_filter(&mut |t, f, held| run_link_step(d, step, t, f, held));
            if step == LinkStep::Restarted && had_flags {
                self.diagnosers_cleared(
                    now,
                    "diagnosers restarted by the link (operator's reset after a repair, or \
                     the peer back): fault flags cleared, sensors read again",
                );
            }
        }
        self.diagnosis_events(now);
        self.plausibility_events(now);
        if let Some(index) = self.record_events(now)
            && self.options.explain
            && let Some((ex, projected)) = explain_live_projected(
                &self.engine,
                &self.bundle,
                self.layout.as_ref(),
                index,
                (self.projection, self.cycle),
                self.follower
                    .as_ref()
                    .and_then(crate::live::follow::Follower::program),
            )
        {
            if let Some(p) = projected {
                self.projections.insert(index, p);
            }
            self.explanations.insert(index, ex);
        }
        self.step_tasks(now);
        self.estimate_boxes();
        self.push_snapshot(now);
    }

    /// Rebuilds the box estimate when the sensors or observers changed.
    fn estimate_boxes(&mut self) {
        let changed = match (self.engine.history.back(0), self.engine.history.back(1)) {
            (Some(a), Some(b)) => a.inputs != b.inputs || a.observers != b.observers,
            (Some(_), None) => true,
            _ => false,
        };
        if !changed {
            return;
        }
        let (Some(record), Some(layout)) = (self.engine.history.last(), &self.layout) else {
            return;
        };
        if let Ok(emu) = explain::emulator_from_observation(
            layout,
            &self.bundle.plant,
            record,
            &self.engine.observers,
        ) {
            self.emulator = emu;
        }
    }
}
