//! The physical plant a simulation runs: a plant folder's `components.ron` (the
//! plant as components of the library), or a legacy `layout.ron` (the station's
//! first emulator's format), read as the components it describes.
//!
//! Everything that closes the loop (the simulation, the projection of level 1, the
//! campaigns, the console) holds a [`Physical`] and asks it the same questions; what a
//! plant does not have (items, a turntable, arrivals) answers empty.

use super::description::Components;
use super::emulator::ComponentPlant;
use super::scene::Scene;
use crate::bits::Bits;
use crate::diag::{Location, Problem, codes};
use crate::emulator::{ArrivalPlan, BoxStats, BoxView, FaultSpec, Hazard, Layout};
use crate::plant::Plant;
use crate::time::Millis;
use std::path::Path;

/// The file of a plant folder that describes its components.
pub const COMPONENTS_FILE: &str = "components.ron";
/// The file of a plant folder that describes a sorting layout.
pub const LAYOUT_FILE: &str = "layout.ron";

/// A plant folder's physical description, loaded.
#[derive(Clone, Debug)]
pub enum Description {
    /// `components.ron`, or a legacy `layout.ron` read as components
    /// ([`Layout::to_components`]; its `file` is then the layout file).
    Components(Components),
}

impl Description {
    /// Loads the physical description of the plant folder `dir`: `components.ron`
    /// when there is one, else `layout.ron` read as components; V0744 when there is
    /// neither.
    pub fn load(dir: &Path) -> Result<Self, Vec<Problem>> {
        let components = dir.join(COMPONENTS_FILE);
        if components.exists() {
            return Components::load(&components).map(Self::Components);
        }
        let layout = dir.join(LAYOUT_FILE);
        if layout.exists() {
            return Layout::load(&layout)?.to_components().map(Self::Components);
        }
        Err(vec![Problem::error(
            codes::NO_PHYSICAL_MODEL.id,
            format!(
                "no physical model: add {COMPONENTS_FILE} (the plant as components) or \
                 {LAYOUT_FILE} to {}",
                dir.display()
            ),
            Some(Location::new(dir, 1, 1)),
        )])
    }

    /// The layout of its turntable cell: the one a plant of components derives when
    /// its conveyors and turntable are placed on the floor as the sorting station's
    /// are ([`Layout::from_components`]).
    pub fn layout(&self) -> Option<Layout> {
        match self {
            Self::Components(c) => Layout::from_components(c),
        }
    }

    /// The problems of its signals against the plant.
    pub fn check_signals(&self, plant: &Plant) -> Vec<Problem> {
        match self {
            Self::Components(c) => c.check_signals(plant),
        }
    }
}

/// The running emulator of a plant's description.
#[derive(Clone, Debug)]
pub enum Physical {
    /// A plant of components.
    Components(Box<ComponentPlant>),
}

impl Physical {
    /// Builds the emulator of a description at time 0.
    pub fn new(desc: &Description, plant: &Plant, seed: u64) -> Result<Self, Problem> {
        Ok(match desc {
            Description::Components(c) => {
                Self::Components(Box::new(ComponentPlant::new(c, plant, seed)?))
            }
        })
    }

    /// The emulator of a turntable cell: the components it was derived from, or
    /// those a layout read from a file describes ([`Layout::to_components`]).
    pub fn of_cell(layout: &Layout, plant: &Plant, seed: u64) -> Result<Self, Problem> {
        let c = match &layout.derived_from.0 {
            Some(c) => (**c).clone(),
            None => layout.to_components().map_err(|mut p| p.remove(0))?,
        };
        Ok(Self::Components(Box::new(ComponentPlant::new(
            &c, plant, seed,
        )?)))
    }

    /// Runs `dt` with the PLC's outputs.
    pub fn step(&mut self, dt: Millis, outputs: &Bits) {
        match self {
            Self::Components(c) => c.step(dt, outputs),
        }
    }

    /// The sensors, by plant input index, faults applied.
    pub fn sensors(&self) -> &Bits {
        match self {
            Self::Components(c) => c.sensors(),
        }
    }

    /// Simulated time.
    pub fn now(&self) -> Millis {
        match self {
            Self::Components(c) => c.now(),
        }
    }

    /// Every hazard so far, in time order.
    pub fn hazards(&self) -> &[Hazard] {
        match self {
            Self::Components(c) => c.hazards(),
        }
    }

    /// Item counts (none on a plant of components without items).
    pub fn stats(&self) -> BoxStats {
        match self {
            Self::Components(c) => BoxStats {
                created: c.items_in(),
                delivered: c.items_out_by_exit().into_iter().collect(),
                damaged: c.items_damaged().0,
                removed: c.items_removed(),
            },
        }
    }

    /// Items in transit, fallen, and delivered during the last second.
    /// (a plant of components: on its placed surfaces only).
    pub fn boxes(&self) -> Vec<BoxView> {
        match self {
            Self::Components(c) => c.boxes(),
        }
    }

    /// [`Self::boxes`] appended to `out` (no allocation on a plant of components).
    pub fn boxes_into(&self, out: &mut Vec<BoxView>) {
        match self {
            Self::Components(c) => c.boxes_into(out),
        }
    }

    /// The turntable's angle (millidegrees) on the floor; 0 without one.
    pub fn table_angle_mdeg(&self) -> i32 {
        match self {
            Self::Components(c) => c.table_angle_mdeg(),
        }
    }

    /// What the synoptic draws of a plant of components.
    pub fn scene(&self) -> Option<Scene> {
        match self {
            Self::Components(c) => Some(c.scene()),
        }
    }

    /// Schedules a fault or says why it cannot be.
    pub fn try_schedule_fault(&mut self, fault: FaultSpec) -> Result<(), Problem> {
        match self {
            Self::Components(c) => c.try_schedule_fault(fault),
        }
    }

    /// Schedules a fault; one that cannot be is kept in [`Self::fault_problems`].
    pub fn schedule_fault(&mut self, fault: FaultSpec) {
        match self {
            Self::Components(c) => c.schedule_fault(fault),
        }
    }

    /// Faults that could not be scheduled.
    pub fn fault_problems(&self) -> &[Problem] {
        match self {
            Self::Components(c) => c.fault_problems(),
        }
    }

    /// The faults active or still to come.
    pub fn faults_in_force(&self) -> usize {
        match self {
            Self::Components(c) => c.faults_in_force(),
        }
    }

    /// A technician's repair: every fault active or to come ends now.
    pub fn repair_faults(&mut self) -> usize {
        match self {
            Self::Components(c) => c.repair_faults(),
        }
    }

    /// The sensors the plant drives (those a transient may strike).
    pub fn sensor_ids(&self) -> Vec<String> {
        match self {
            Self::Components(c) => c.sensor_ids(),
        }
    }

    /// The actuators a fault may weld or kill.
    pub fn actuators(&self) -> Vec<String> {
        match self {
            Self::Components(c) => c.actuators(),
        }
    }

    /// The operator takes every item off the plant; how many.
    pub fn remove_items(&mut self) -> u32 {
        match self {
            Self::Components(c) => c.remove_items(),
        }
    }

    /// Replaces the arrival plan of the plant's source (a plant of components: its
    /// first conveyor with a `source`, `Small` and `Large` naming the source's first
    /// and second classes; nothing to do when it has none).
    pub fn set_arrivals(&mut self, plan: ArrivalPlan) {
        use super::items::{ArrivalsDef, Mix, Plan};
        use crate::emulator::{BoxSize, SizeMix};
        match self {
            Self::Components(c) => {
                let class = |s: BoxSize| usize::from(s == BoxSize::Large);
                let plan = match plan {
                    ArrivalPlan::Off => Plan::Off,
                    ArrivalPlan::List(l) => {
                        Plan::List(l.into_iter().map(|(t, s)| (t, class(s))).collect())
                    }
                    ArrivalPlan::Periodic {
                        period_ms,
                        jitter_ms,
                        mix,
                        count,
                    } => Plan::Periodic(ArrivalsDef {
                        period_ms,
                        jitter_ms,
                        count,
                        mix: match mix {
                            SizeMix::Alternate => Mix::InTurn,
                            SizeMix::RandomLarge(p) => Mix::SecondPercent(p),
                        },
                    }),
                };
                c.set_arrivals(plan);
            }
        }
    }

    /// The operator presses the plant's panel button on input `signal` (a plant of
    /// components' `Button`); false when the plant has none.
    pub fn press(&mut self, signal: &str) -> bool {
        match self {
            Self::Components(c) => c.press(signal),
        }
    }

    /// The plant of components, for what only it can do.
    pub fn as_components(&self) -> Option<&ComponentPlant> {
        match self {
            Self::Components(c) => Some(c),
        }
    }
}
