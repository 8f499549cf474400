//! What keeps a plant producing in a campaign, from its folder: boxes arriving on a
//! sorting layout, or, on a plant described as components, the operator's actions of
//! its production scenario (`scenarios/reference.ron`: the Start presses of a batch or
//! of a work cycle) and its faults at fixed times (the environment a protection system
//! answers: a perturbation on a line) repeated every scenario length. No campaign knows
//! a plant's buttons or cycle: they are the scenario's.

use super::{OperatorAction, Scenario, Simulation, TimedAction};
use crate::diag::{Location, Problem, codes};
use crate::emulator::{ArrivalPlan, FaultSpec, Trigger};
use crate::machine::Description;
use std::path::Path;

/// The plant's production.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Workload {
    /// Items arriving on the layout's source.
    Arrivals(ArrivalPlan),
    /// The operator's actions and the environment's events of one period, repeated
    /// every `period_ms`.
    Operator {
        /// The actions of one period, by time.
        actions: Vec<TimedAction>,
        /// The production scenario's faults at fixed times (the environment: a
        /// perturbation on a line), repeated with the actions.
        events: Vec<FaultSpec>,
        /// The period (the production scenario's length).
        period_ms: u64,
    },
}

/// The production scenario of a plant folder.
pub const PRODUCTION: &str = "scenarios/reference.ron";

impl Workload {
    /// The production of the plant in `dir`: `arrivals` (the campaign's own plan) on a
    /// sorting layout or on a plant of components fed by a source without a
    /// production scenario, the production scenario's actions on any other.
    pub fn of(dir: &Path, arrivals: ArrivalPlan) -> Result<Self, Vec<Problem>> {
        match Description::load(dir)? {
            Description::Components(c) => {
                let path = dir.join(PRODUCTION);
                // A line fed by its own source (the sorting station's boxes) produces
                // from the arrivals, the campaign's own plan.
                if !path.exists() && c.first_source().is_some() {
                    return Ok(Self::Arrivals(arrivals));
                }
                if !path.exists() {
                    return Err(vec![Problem::error(
                        codes::CAMPAIGN_NO_PRODUCTION.id,
                        format!(
                            "a campaign on a plant of components runs its production \
                             scenario, {}: the file is missing",
                            path.display()
                        ),
                        Some(Location::new(&path, 1, 1)),
                    )]);
                }
                let s = Scenario::load(&path)?;
                let mut actions = s.actions;
                actions.sort_by_key(|a| a.at_ms);
                // A plant that runs on its own (a protection system) may have no
                // operator action at all.
                if s.duration_ms == 0 {
                    return Err(vec![Problem::error(
                        codes::CAMPAIGN_NO_PRODUCTION.id,
                        "the production scenario must last more than 0 ms: a campaign \
                         repeats its actions every its length",
                        Some(Location::new(&path, 1, 1)),
                    )]);
                }
                let events = s
                    .faults
                    .into_iter()
                    .filter(|f| matches!(f.trigger, Trigger::At(_)))
                    .collect();
                Ok(Self::Operator {
                    actions,
                    events,
                    period_ms: s.duration_ms,
                })
            }
        }
    }

    /// Sets `sim` producing until `horizon_ms`: the arrivals and a Start now, or the
    /// operator's actions of every period up to the horizon.
    pub fn apply(&self, sim: &mut Simulation, horizon_ms: u64) {
        match self {
            Self::Arrivals(plan) => {
                sim.emulator.set_arrivals(plan.clone());
                let _ = sim.act(&OperatorAction::Start);
            }
            Self::Operator {
                actions,
                events,
                period_ms,
            } => {
                let now = sim.now().0;
                let mut k = 0;
                loop {
                    let base = now + k * period_ms;
                    if base > horizon_ms {
                        break;
                    }
                    sim.pending.extend(actions.iter().map(|a| TimedAction {
                        at_ms: base + a.at_ms,
                        action: a.action.clone(),
                    }));
                    for e in events {
                        if let Trigger::At(t) = e.trigger {
                            // The scenario's own faults were checked when it loaded.
                            let _ = sim.emulator.try_schedule_fault(FaultSpec {
                                trigger: Trigger::At(base + t),
                                ..e.clone()
                            });
                        }
                    }
                    k += 1;
                }
            }
        }
    }

    /// Its period: of the arrivals when periodic, of the operator's actions else.
    pub fn period_ms(&self) -> Option<u64> {
        match self {
            Self::Arrivals(ArrivalPlan::Periodic { period_ms, .. }) => Some(*period_ms),
            Self::Arrivals(_) => None,
            Self::Operator { period_ms, .. } => Some(*period_ms),
        }
    }
}

impl Simulation {
    /// Repeats the operator's actions still pending (a scenario's, before its run) every
    /// `period_ms` until `horizon_ms`: a short production scenario made long enough to
    /// measure.
    pub fn repeat_pending(&mut self, period_ms: u64, horizon_ms: u64) {
        if period_ms == 0 {
            return;
        }
        let once: Vec<TimedAction> = self.pending.iter().cloned().collect();
        let mut k = 1;
        while k * period_ms <= horizon_ms {
            self.pending.extend(once.iter().map(|a| TimedAction {
                at_ms: a.at_ms + k * period_ms,
                action: a.action.clone(),
            }));
            k += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn repo() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
    }

    #[test]
    fn a_plant_of_components_repeats_its_production_scenario() {
        let dir = repo().join("layouts/liquid-supply");
        let w = Workload::of(&dir, ArrivalPlan::List(Vec::new())).unwrap();
        let Workload::Operator {
            actions, period_ms, ..
        } = &w
        else {
            panic!("{w:?}");
        };
        let s = Scenario::load(&dir.join(PRODUCTION)).unwrap();
        assert_eq!(*period_ms, s.duration_ms);
        assert_eq!(actions.len(), s.actions.len());
        let mut sim =
            Simulation::from_scenario(&s, &dir.join(PRODUCTION), Default::default()).unwrap();
        sim.pending.clear();
        w.apply(&mut sim, 3 * period_ms);
        // Periods starting at 0, 1, 2 and 3 periods: the last one at the horizon.
        let at: Vec<u64> = sim.pending.iter().map(|a| a.at_ms).collect();
        let mut expected = Vec::new();
        for k in 0..4 {
            expected.extend(s.actions.iter().map(|a| k * period_ms + a.at_ms));
        }
        assert_eq!(at, expected);
    }

    #[test]
    fn the_production_scenarios_environment_is_repeated_with_its_actions() {
        let dir = repo().join("layouts/substation");
        let w = Workload::of(&dir, ArrivalPlan::List(Vec::new())).unwrap();
        let s = Scenario::load(&dir.join(PRODUCTION)).unwrap();
        let (bundle, _) = crate::bundle::PlantBundle::load(&dir).unwrap();
        let program = crate::control::CompiledProgram::load(
            &dir.join("programs/reference.ron"),
            &bundle.plant,
        )
        .unwrap();
        assert_eq!(s.duration_ms, 3_000);
        // A fresh simulation, as a campaign's: the scenario's own faults not scheduled.
        let mut sim2 = Simulation::new(bundle, program, 1, Default::default()).unwrap();
        w.apply(&mut sim2, 3 * 3_000);
        let pert1 = sim2.bundle.plant.input("pert1").unwrap();
        let mut rises = Vec::new();
        let mut last = false;
        while sim2.now().0 < 9_000 {
            sim2.cycle();
            let v = sim2.emulator.sensors().get(pert1);
            if v && !last {
                rises.push(sim2.now().0);
            }
            last = v;
        }
        assert_eq!(rises, vec![40, 3_040, 6_040]);
    }

    #[test]
    fn a_sorting_layout_keeps_the_campaigns_arrivals() {
        let dir = repo().join("layouts/sorting-station");
        let plan = ArrivalPlan::List(vec![(1_000, crate::emulator::BoxSize::Small)]);
        assert_eq!(
            Workload::of(&dir, plan.clone()).unwrap(),
            Workload::Arrivals(plan)
        );
    }

    #[test]
    fn a_plant_of_components_without_production_is_told_which_file_to_write() {
        let tmp = std::env::temp_dir().join(format!("vigie-workload-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir_all(&tmp).unwrap();
        let src = repo().join("layouts/drilling-station");
        for f in ["plant.ron", "components.ron", "constraints.txt"] {
            std::fs::copy(src.join(f), tmp.join(f)).unwrap();
        }
        let e = Workload::of(&tmp, ArrivalPlan::List(Vec::new())).unwrap_err();
        let _ = std::fs::remove_dir_all(&tmp);
        assert_eq!(e[0].code, codes::CAMPAIGN_NO_PRODUCTION.id, "{e:?}");
        assert!(e[0].message.contains("scenarios/reference.ron"), "{e:?}");
    }
}
