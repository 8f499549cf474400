//! The closed loop in emulator mode and the scenario runner: the plant emulator (the
//! "partie opérative"), the GRAFCET runtime (the "partie commande") and the engine
//! (observers, filter, recorder), driven by a scenario file.
//!
//! One PLC cycle of [`Simulation::cycle`]: the operator actions due are applied, the
//! engine runs one cycle on the emulator's sensors with the program as control, the
//! emulator runs one cycle period with the applied outputs, and the events (trips,
//! hazards, resets) become alarms and journal entries. A trip is explained at once, with
//! the projection computed on clones of the emulator and of the program.

use crate::alarms::{AlarmKind, AlarmList, texts};
use crate::bits::Bits;
use crate::bundle::PlantBundle;
use crate::control::{CompiledProgram, ErrorLibrary, ProgramRuntime};
use crate::diag::codes;
use crate::diag::{Location, Problem, ron_problem};
use crate::emulator::{ArrivalPlan, BoxView, FaultSpec, Hazard, Layout};
use crate::engine::{Commanded, Control as _, Engine, Event, FilterMode};
use crate::explain::{self, Explanation, Highlight, Item, Mark};
use crate::machine::{Description, Physical, Scene};
use crate::symbols::Space;
use crate::time::Millis;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Which control program a scenario runs.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ProgramChoice {
    /// `programs/reference.ron` of the plant.
    Reference,
    /// A variant of the control-error library (`programs/errors.ron`), by id.
    Error(String),
    /// A program file, relative to the scenario file.
    File(String),
}

/// The plant's state at a glance, as the console shows it from across the room.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PlantState {
    /// The safety filter holds the outputs in its safe state until the operator's reset.
    Tripped,
    /// The diagnosers stopped the plant (an actuator at fault, or a doubt on the safe
    /// side) until their reset after a check.
    Stopped,
    /// The operator drives the outputs (manual mode), every request through the filter.
    Manual,
    /// Producing with a sensor read from its estimate or held as suspect.
    Degraded,
    /// The control program is at rest in its initial situation (before Start, after
    /// Stop).
    Idle,
    /// The control program runs.
    Running,
}

/// An operator action.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum OperatorAction {
    /// Press the START button.
    Start,
    /// Press the STOP button.
    Stop,
    /// Reset the filter after a trip.
    Reset,
    /// Pause the plant: every actuator to its safe state (the fallback with priority to
    /// zero) while the program keeps running.
    Pause,
    /// End the pause.
    Resume,
    /// Press a panel button of the program.
    Press(String),
    /// Set a panel switch of the program.
    Switch(String, bool),
    /// Change the filter mode.
    Filter(FilterMode),
    /// After a repair: clear the diagnosers' fault flags (the operator's reset of the
    /// paper). The estimated sensors are read again and a stop by an actuator partition
    /// ends; the models restart from the observed values and decide nothing with
    /// certainty until each is back in its initial state with the normal mode only (a
    /// fault still present is then diagnosed again; one that keeps a model from ever
    /// coming back, such as a table position beam dead at rest, is not).
    ResetDiagnosers,
    /// After a trip that the reset cannot clear (the program or an observer still
    /// believes what a transient made it believe: a box gone that is still under its
    /// beam, a phantom box on the table) and a check of the plant: the control program
    /// back to its initial steps, the sensors taken as read, and the trip ended. With
    /// `emptied`, the operator took every item off the plant first (GEMMA's preparation
    /// for a restart after a failure; the emulator's boxes are removed) and every
    /// observer restarts empty; without, the items stay where the sensors show them
    /// and an observer is cleared only where the sensors leave no room for its item
    /// (`empty_when`). Refused when the filter is not tripped.
    Reinitialise {
        /// The operator emptied the plant of its items.
        emptied: bool,
    },
    /// Enter (`true`) or leave manual mode (seed 004, section 7). Entering keeps the
    /// outputs as they are (a bumpless transfer) and stops scanning the program; it is
    /// refused while the filter holds the plant and on a live link. Leaving restarts the
    /// program from its initial steps (it did not follow what the operator did): press
    /// Start.
    Manual(bool),
    /// Bypass one safety constraint for a limited time (seed 004, section 7: "invalidant
    /// certaines contraintes de sécurité s'il y a lieu"), with a reason and who asked;
    /// at most [`MAX_BYPASS_MIN`] minutes, refused on a live link. It ends by itself.
    Bypass {
        /// The constraint's id.
        constraint: String,
        /// Duration, minutes of plant time.
        minutes: u64,
        /// Why.
        reason: String,
        /// Who (the logged-in user).
        by: String,
    },
    /// End a bypass now.
    EndBypass(String),
    /// The operator's answer to a diagnoser in doubt (seed 004, section 7): whether
    /// an item is at `sensor`, looked at on the machine.
    AnswerDoubt {
        /// The component in doubt.
        component: String,
        /// The sensor asked about.
        sensor: String,
        /// The operator sees an item there.
        item: bool,
    },
    /// On the simulator only: the technician repairs the plant, every fault of the
    /// emulator (injected or still to come) ends now, and the diagnosers' flags are
    /// cleared as after a real repair. The trip stays until the operator's Reset (the
    /// plant may still be in a forbidden situation). Refused on a live link.
    Repair,
    /// Manual mode: request an output ON or OFF. The request is checked against every
    /// constraint with the plant as it is; one that would violate a constraint is
    /// refused with the constraint's own description and never reaches the plant.
    ManualSet(String, bool),
}

/// What the hypothesis says of one diagnoser partition: its faults' descriptions and
/// what to check on the machine.
#[derive(Clone, Debug, Default)]
struct PartitionInfo {
    descriptions: BTreeMap<String, String>,
    check: Vec<String>,
}

impl PartitionInfo {
    fn of(file: &crate::pop::model::DiagnoserFile) -> BTreeMap<String, Self> {
        let mut out = BTreeMap::new();
        for c in &file.components {
            for p in &c.partitions {
                let descriptions = c
                    .faults
                    .iter()
                    .filter(|f| p.faults.contains(&f.id))
                    .map(|f| (f.id.clone(), f.description.clone()))
                    .collect();
                let check = match &p.sensor {
                    Some(s) => vec![s.clone()],
                    None => p.actuators.clone(),
                };
                out.insert(
                    p.id.clone(),
                    Self {
                        descriptions,
                        check,
                    },
                );
            }
        }
        out
    }
}

/// A question the console asks the operator while a diagnoser is in doubt between a
/// drive that stops items and a sensor it cannot estimate: the operator's eyes tell
/// them apart.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct DoubtQuestion {
    /// The component in doubt.
    pub component: String,
    /// The sensor to look at.
    pub sensor: String,
    /// What the sensor reads now.
    pub reading: bool,
    /// The question, in the plant's words.
    pub question: String,
    /// The candidates of the sensor's partition.
    pub sensor_faults: Vec<String>,
    /// The other candidates (the stopping drive's).
    pub other_faults: Vec<String>,
}

/// The longest bypass of a constraint: one shift.
pub const MAX_BYPASS_MIN: u64 = 480;

/// A constraint the filter does not enforce for a while.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Bypass {
    /// When it started.
    pub from: Millis,
    /// When it ends by itself.
    pub until: Millis,
    /// Why.
    pub reason: String,
    /// Who asked.
    pub by: String,
}

/// An operator action at a time.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimedAction {
    /// When, ms from the start.
    pub at_ms: u64,
    /// What.
    pub action: OperatorAction,
}

fn default_cycle() -> u64 {
    10
}
fn default_filter() -> FilterMode {
    FilterMode::Enforce
}
fn default_plant() -> String {
    "..".into()
}
fn default_projection() -> u64 {
    10_000
}

/// A scenario file (`layouts/<plant>/scenarios/*.ron`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Scenario")]
pub struct Scenario {
    /// Display name.
    pub name: String,
    /// What it shows.
    #[serde(default)]
    pub description: String,
    /// The plant folder, relative to the scenario file.
    #[serde(default = "default_plant")]
    pub plant: String,
    /// The control program.
    pub program: ProgramChoice,
    /// Seed of the emulator.
    pub seed: u64,
    /// Box arrivals (default: the layout's plan).
    #[serde(default)]
    pub arrivals: Option<ArrivalPlan>,
    /// Faults to inject.
    #[serde(default)]
    pub faults: Vec<FaultSpec>,
    /// Operator actions.
    #[serde(default)]
    pub actions: Vec<TimedAction>,
    /// Simulated duration, ms.
    pub duration_ms: u64,
    /// Filter mode.
    #[serde(default = "default_filter")]
    pub filter: FilterMode,
    /// PLC cycle, ms.
    #[serde(default = "default_cycle")]
    pub cycle_ms: u64,
    /// Projection horizon of the explanations, ms.
    #[serde(default = "default_projection")]
    pub projection_ms: u64,
    /// Run the diagnosers of `diagnosers.ron` (with the rewritten constraints).
    #[serde(default)]
    pub diagnosers: bool,
    /// Run the sensors' plausibility stage (`plausible` in `plant.ron`); true by
    /// default. A scenario that places boxes by hand faster than the physics may say
    /// `plausibility: false`.
    #[serde(default = "default_plausibility")]
    pub plausibility: bool,
}

fn default_plausibility() -> bool {
    true
}

impl Scenario {
    /// Loads a scenario file: durations, periods and times are checked
    /// ([`scenario`], `V0401`, `V0403`..`V0406`).
    pub fn load(path: &Path) -> Result<Self, Vec<Problem>> {
        let text = crate::diag::read_text(path).map_err(|p| vec![p])?;
        Self::from_ron(&text, path)
    }

    /// Parses and checks scenario text; `path` is used in messages only.
    pub fn from_ron(text: &str, path: &Path) -> Result<Self, Vec<Problem>> {
        let s: Self = ron::from_str(text).map_err(|e| vec![ron_problem(path, &e)])?;
        let problems = scenario::check(&s, text, path);
        if problems.is_empty() {
            Ok(s)
        } else {
            Err(problems)
        }
    }
}

/// One entry of the run's journal (operator actions and events, in order).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct JournalEntry {
    /// Simulated time.
    pub time_ms: u64,
    /// `trip`, `reset`, `reset_refused`, `hazard`, `operator`, `spec_error`, `fault`…
    pub kind: String,
    /// Text (English, the record).
    pub text: String,
    /// What the text says, as data, for a console that shows it in another language:
    /// the id of a message (`journal-trip`, `alarm-hazard`…; empty when none) and its
    /// fields.
    #[serde(skip_serializing_if = "str::is_empty")]
    pub code: String,
    /// See `code`.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub fields: BTreeMap<String, String>,
}

/// The message id of an alarm's text (`alarm-<code>`), empty when it has no code.
fn alarm_code(t: &crate::alarms::AlarmText) -> String {
    if t.code.is_empty() {
        String::new()
    } else {
        format!("alarm-{}", t.code)
    }
}

/// Fields of a journal entry from pairs.
fn fields<const N: usize>(pairs: [(&str, String); N]) -> BTreeMap<String, String> {
    pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
}

/// The plant as drawn at one cycle, for the synoptic's replay.
#[derive(Clone, Debug, PartialEq)]
pub struct PlantSnapshot {
    /// Time of the cycle.
    pub time: Millis,
    /// Boxes.
    pub boxes: Vec<BoxView>,
    /// Turntable angle.
    pub table_angle_mdeg: i32,
    /// A plant of components: each component's position (an axis's, a tank's level)
    /// in the order of its scene ([`crate::machine::ComponentPlant::scene_at`] draws them).
    pub positions: Vec<f64>,
}

/// The state the plant would have reached without the filter (explanation level 1).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProjectedPlant {
    /// Time of the projected picture (the first predicted hazard, or the horizon).
    pub at_ms: u64,
    /// Boxes at that time.
    #[serde(skip)]
    pub boxes: Vec<BoxView>,
    /// Turntable angle at that time.
    pub table_angle_mdeg: i32,
    /// A plant of components at that time.
    #[serde(skip)]
    pub scene: Option<Scene>,
    /// Hazards predicted within the horizon.
    pub hazards: Vec<Hazard>,
}

/// Options of a simulation beyond the scenario file.
#[derive(Clone, Debug)]
pub struct Options {
    /// Cycles kept by the recorder (and plant snapshots for the replay).
    pub history_cycles: usize,
    /// Compute explanations (with projection) at each trip.
    pub explain: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            history_cycles: 30_000,
            explain: true,
        }
    }
}

/// The closed loop.
pub struct Simulation {
    /// Plant, observers, constraints.
    pub bundle: PlantBundle,
    /// The sorting layout's geometry, when the plant is described by one (a plant of
    /// components carries its own in the emulator's scene).
    pub layout: Option<Layout>,
    /// Observers, filter, recorder.
    pub engine: Engine,
    /// The plant's emulator.
    pub emulator: Physical,
    /// The control program.
    pub program: ProgramRuntime,
    /// The program as it was before its last scan (for the explanations).
    program_before: ProgramRuntime,
    /// Alarms.
    pub alarms: AlarmList,
    /// Explanations of the trips, by trip index.
    pub explanations: BTreeMap<usize, Explanation>,
    /// Projections of the trips, by trip index.
    pub projections: BTreeMap<usize, ProjectedPlant>,
    journal: Vec<JournalEntry>,
    journal_taken: usize,
    pending: VecDeque<TimedAction>,
    cycle: Millis,
    projection: Millis,
    hazards_seen: usize,
    snapshots: VecDeque<PlantSnapshot>,
    options: Options,
    name: String,
    /// Timed task monitors (seed 000), when the plant has `tasks.ron`.
    pub tasks: Option<TaskMonitors>,
    /// Fed from a live link (see `observed.rs`): the time of the last observed cycle.
    live_now: Option<Millis>,
    /// Fed from a live link with the PLC's program given (`--program`): the program
    /// followed beside it, as the link follows it (see `observed.rs`).
    follower: Option<crate::live::follow::Follower>,
    /// The diagnosers, when enabled ([`Simulation::enable_diagnosers`]).
    pub diagnosers: Option<crate::pop::Diagnosers>,
    /// The elementary-action monitor (seed 003), on a plant that has actions.
    pub action_monitor: Option<actions::ActionMonitoring>,
    /// Why the action monitor stopped the plant (until the operator's Reset).
    action_stop: Option<String>,
    /// Per diagnoser partition: its fault descriptions and what to check (its sensor or
    /// actuators), from `diagnosers.ron`, for the hypothesis's hardware items.
    partitions: BTreeMap<String, PartitionInfo>,
    diag_seen: usize,
    degraded: Vec<(usize, usize)>,
    /// Manual mode: the outputs the operator requested, in place of the program's (not
    /// scanned meanwhile); every request was checked against the constraints.
    manual: Option<Bits>,
    /// The bypassed constraints, by id.
    bypasses: BTreeMap<String, Bypass>,
    /// The operator's answers to the diagnosers' doubts, by component: the conclusion.
    answers: BTreeMap<String, String>,
}

/// The plant's task monitors, stepped after the filter every cycle.
#[derive(Clone, Debug)]
pub struct TaskMonitors {
    /// The monitor (one stopwatch pair per task, plus the coordinator).
    pub monitor: crate::tasks::Monitor,
    /// The event expressions.
    pub events: crate::tasks::FrameTasks,
    seen: usize,
}

/// The control program fed with estimated sensors (degraded mode): the program reads
/// `EST(x)` in place of each sensor `x` whose partition flag is set.
struct DegradedControl<'a> {
    inner: &'a mut ProgramRuntime,
    subs: &'a [(usize, usize)],
}

impl crate::engine::Control for DegradedControl<'_> {
    fn scan(&mut self, now: Millis, frame: &crate::frame::Frame, outputs: &mut crate::bits::Bits) {
        match diagnosis::estimated_frame(self.subs, frame) {
            None => self.inner.scan(now, frame, outputs),
            Some(f) => self.inner.scan(now, &f, outputs),
        }
    }
}

/// A serialisable summary of a run (the `vigie run --headless` report, without the
/// wall-clock time that only the binary knows).
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Scenario name.
    pub scenario: String,
    /// Seed.
    pub seed: u64,
    /// Filter mode.
    pub filter: FilterMode,
    /// Trips (and reported violations), in order.
    pub trips: Vec<TripSummary>,
    /// Hazards, in order.
    pub hazards: Vec<Hazard>,
    /// Box counts.
    pub boxes: crate::emulator::BoxStats,
    /// Explanations of the trips, in order.
    pub explanations: Vec<Explanation>,
    /// Task monitor alarms (not warnings), in order.
    pub task_alarms: Vec<crate::tasks::Alarm>,
    /// Simulated time, ms.
    pub sim_ms: u64,
    /// PLC cycles run.
    pub cycles: u64,
    /// Certain diagnoses of the diagnosers (empty when they are off).
    pub diagnoses: Vec<crate::pop::Diagnosis>,
    /// The elementary-action monitor's events, completions included (none on a plant
    /// without actions).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub actions: Vec<crate::machine::monitor::ActionEvent>,
}

/// A trip in the run report.
#[derive(Clone, Debug, Serialize)]
pub struct TripSummary {
    /// Time.
    pub time_ms: u64,
    /// Constraint ids.
    pub constraints: Vec<String>,
    /// The fallback vector, output id → value.
    pub fallback: BTreeMap<String, bool>,
    /// The full record.
    pub record: crate::engine::Trip,
}

impl Simulation {
    /// Builds the closed loop for `scenario` (read from `scenario_path`).
    pub fn from_scenario(
        scenario: &Scenario,
        scenario_path: &Path,
        options: Options,
    ) -> Result<Self, Vec<Problem>> {
        let base = scenario_path.parent().unwrap_or(Path::new("."));
        let plant_dir = base.join(&scenario.plant);
        let program_path: PathBuf;
        let (bundle, problems) = PlantBundle::load(&plant_dir)?;
        let errors: Vec<Problem> = problems.into_iter().filter(Problem::is_error).collect();
        if !errors.is_empty() {
            return Err(errors);
        }
        let program = match &scenario.program {
            ProgramChoice::Reference => {
                program_path = plant_dir.join("programs/reference.ron");
                CompiledProgram::load(&program_path, &bundle.plant)?
            }
            ProgramChoice::Error(id) => {
                let lib =
                    ErrorLibrary::load(&plant_dir.join("programs/errors.ron"), &bundle.plant)?;
                let Some(v) = lib.variants.into_iter().find(|v| &v.def.id == id) else {
                    return Err(vec![Problem::error(
                        codes::SCENARIO_UNKNOWN_VARIANT.id,
                        format!("no variant `{id}` in the control-error library"),
                        Some(Location::new(scenario_path, 1, 1)),
                    )]);
                };
                v.compiled
            }
            ProgramChoice::File(f) => {
                program_path = base.join(f);
                CompiledProgram::load(&program_path, &bundle.plant)?
            }
        };
        let mut sim = Self::new(bundle, program, scenario.seed, options)?;
        sim.engine.set_plausibility(scenario.plausibility);
        if scenario.diagnosers {
            sim.enable_diagnosers()?;
        }
        sim.name.clone_from(&scenario.name);
        sim.cycle = Millis(scenario.cycle_ms);
        sim.projection = Millis(scenario.projection_ms);
        sim.engine.set_mode(scenario.filter);
        if let Some(plan) = &scenario.arrivals {
            sim.emulator.set_arrivals(plan.clone());
        }
        for f in &scenario.faults {
            sim.emulator
                .try_schedule_fault(f.clone())
                .map_err(|p| vec![p])?;
        }
        let mut actions = scenario.actions.clone();
        actions.sort_by_key(|a| a.at_ms);
        sim.pending = actions.into();
        Ok(sim)
    }

    /// Builds the closed loop for a loaded plant and program.
    pub fn new(
        bundle: PlantBundle,
        program: CompiledProgram,
        seed: u64,
        options: Options,
    ) -> Result<Self, Vec<Problem>> {
        let description = Description::load(&bundle.dir)?;
        let layout = description.layout();
        let tasks = match &bundle.tasks {
            Some(set) => Some(TaskMonitors {
                monitor: crate::tasks::Monitor::new(set, Millis::ZERO),
                events: crate::tasks::FrameTasks::compile(set, &bundle.symbols)?,
                seen: 0,
            }),
            None => None,
        };
        let emulator = Physical::new(&description, &bundle.plant, seed).map_err(|p| vec![p])?;
        let engine = Engine::new(&bundle, FilterMode::Enforce, options.history_cycles);
        let program = ProgramRuntime::new(Arc::new(program));
        let mut sim = Self {
            program_before: program.clone(),
            program,
            bundle,
            layout,
            engine,
            emulator,
            alarms: AlarmList::new(),
            explanations: BTreeMap::new(),
            projections: BTreeMap::new(),
            journal: Vec::new(),
            journal_taken: 0,
            pending: VecDeque::new(),
            cycle: Millis(10),
            projection: Millis(10_000),
            hazards_seen: 0,
            snapshots: VecDeque::new(),
            options,
            name: String::new(),
            tasks,
            live_now: None,
            follower: None,
            diagnosers: None,
            action_monitor: None,
            action_stop: None,
            partitions: BTreeMap::new(),
            diag_seen: 0,
            degraded: Vec::new(),
            manual: None,
            bypasses: BTreeMap::new(),
            answers: BTreeMap::new(),
        };
        sim.enable_action_monitor()?;
        Ok(sim)
    }

    /// Loads `diagnosers.ron` of the plant and runs its diagnosers after the filter, with
    /// the constraints rewritten for the cooperation (estimated sensors, stop on an
    /// actuator partition).
    pub fn enable_diagnosers(&mut self) -> Result<(), Vec<Problem>> {
        let db = diagnosis::load(&self.bundle.dir)?;
        let mode = self.engine.mode();
        let plausibility = self.engine.plausibility_on();
        self.engine = Engine::new(&db.bundle, mode, self.options.history_cycles);
        self.engine.set_plausibility(plausibility);
        // The auxiliaries moved: the task monitors are compiled again on the new table.
        self.tasks = match &db.bundle.tasks {
            Some(set) => Some(TaskMonitors {
                monitor: crate::tasks::Monitor::new(set, self.now()),
                events: crate::tasks::FrameTasks::compile(set, &db.bundle.symbols)?,
                seen: 0,
            }),
            None => None,
        };
        self.engine.set_estimates(diagnosis::estimate_map(
            &db.compiled,
            &db.bundle.plant,
            &db.bundle.symbols,
        ));
        self.partitions = PartitionInfo::of(&db.file);
        self.diagnosers = Some(crate::pop::Diagnosers::new(db.compiled, &db.bundle.symbols));
        self.bundle = db.bundle;
        Ok(())
    }

    /// Simulated time (on a live link: the time of the last observed cycle).
    pub fn now(&self) -> Millis {
        self.live_now.unwrap_or_else(|| self.emulator.now())
    }

    /// The PLC cycle period.
    pub fn cycle_period(&self) -> Millis {
        self.cycle
    }

    /// Replaces the control program (maintenance mode: after a correction) and restarts
    /// it from its initial steps.
    pub fn replace_program(&mut self, program: CompiledProgram) {
        self.restart_program(Arc::new(program));
        self.log("operator", "control program replaced and restarted".into());
    }

    /// Runs `program` from its initial steps.
    fn restart_program(&mut self, program: Arc<CompiledProgram>) {
        self.program = ProgramRuntime::new(program);
        self.program_before = self.program.clone();
    }

    /// Presses the panel button the program names for the console's Start or Stop
    /// (`start` / `stop` in its file).
    fn press_role(&mut self, role: &str) -> Result<(), String> {
        let program = &self.program.program().program;
        let button = match role {
            "start" => program.start.clone(),
            _ => program.stop.clone(),
        };
        match button {
            Some(b) => self.press(&b),
            None => Err(format!(
                "the program `{}` names no {role} button (`{role}: Some(\"…\")` in its file)",
                program.name
            )),
        }
    }

    /// Presses `button`: the program's panel button of that name, else the machine's
    /// push button on that plant input.
    fn press(&mut self, button: &str) -> Result<(), String> {
        match self.program.press(button) {
            Ok(()) => Ok(()),
            Err(_) if self.emulator.press(button) => Ok(()),
            Err(e) => Err(e.to_string()),
        }
    }

    /// The plant's state at a glance, the most serious first.
    pub fn plant_state(&self) -> PlantState {
        if self.engine.is_tripped() {
            return PlantState::Tripped;
        }
        if self.action_stop.is_some() {
            return PlantState::Stopped;
        }
        if self.manual.is_some() {
            return PlantState::Manual;
        }
        let flagged = self
            .diagnosers
            .as_ref()
            .map(crate::pop::Diagnosers::flagged)
            .unwrap_or_default();
        if self.engine.mode() == FilterMode::Enforce && flagged.iter().any(|f| f.1) {
            return PlantState::Stopped;
        }
        if !self.degraded.is_empty() || !self.suspect_sensors().is_empty() {
            return PlantState::Degraded;
        }
        if self.program.at_initial_situation() {
            PlantState::Idle
        } else {
            PlantState::Running
        }
    }

    /// The questions for the diagnosers in doubt now (a stop on the safe side between a
    /// drive and a sensor without estimate), one per sensor among the candidates, not
    /// yet answered.
    pub fn doubt_questions(&self) -> Vec<DoubtQuestion> {
        let Some(d) = self.diagnosers.as_ref() else {
            return Vec::new();
        };
        let flagged = d.flagged();
        let mut out = Vec::new();
        for c in &d.compiled.components {
            if self.answers.contains_key(&c.id) {
                continue;
            }
            // The component's stop on the safe side, still flagged.
            let Some(doubt) = d.diagnoses.iter().rev().find(|x| {
                x.component == c.id
                    && x.certainty == crate::pop::Certainty::Ambiguous
                    && flagged
                        .iter()
                        .any(|(p, stop, _)| *stop && *p == x.partition)
            }) else {
                continue;
            };
            let candidates: Vec<&str> = doubt.fault.split('|').collect();
            for p in c.partitions.iter().filter(|p| !p.stop) {
                let Some(sensor) = p.sensor.as_deref() else {
                    continue;
                };
                let of_p = |f: &str| p.faults.iter().any(|&i| c.faults[i] == f);
                let (sensor_faults, other_faults): (Vec<&str>, Vec<&str>) =
                    candidates.iter().partition(|f| of_p(f));
                if sensor_faults.is_empty() {
                    continue;
                }
                let sensor_faults: Vec<String> =
                    sensor_faults.into_iter().map(str::to_string).collect();
                let other_faults: Vec<String> =
                    other_faults.into_iter().map(str::to_string).collect();
                let Some(k) = self.bundle.plant.inputs.iter().position(|s| s.id == sensor) else {
                    continue;
                };
                let signal = &self.bundle.plant.inputs[k];
                let reading = self.shown_input(k);
                let place = if signal.element.is_empty() {
                    String::new()
                } else {
                    format!("Look at the {}: ", signal.element)
                };
                out.push(DoubtQuestion {
                    component: c.id.clone(),
                    sensor: sensor.to_string(),
                    reading,
                    question: format!(
                        "{place}is there an item at {sensor} ({})? {sensor} reads {}.",
                        signal.description,
                        u8::from(reading)
                    ),
                    sensor_faults,
                    other_faults,
                });
            }
        }
        out
    }

    /// Input `k` as the last cycle recorded it (what the synoptic's lamp shows: after
    /// the plausibility stage).
    fn shown_input(&self, k: usize) -> bool {
        self.engine.history.last().is_some_and(|r| r.inputs.get(k))
    }

    /// The operator's answers so far, by component (cleared by the diagnosers' reset).
    pub fn doubt_answers(&self) -> &BTreeMap<String, String> {
        &self.answers
    }

    fn answer_doubt(&mut self, component: &str, sensor: &str, item: bool) -> Result<(), String> {
        let q = self
            .doubt_questions()
            .into_iter()
            .find(|q| q.component == component && q.sensor == sensor)
            .ok_or_else(|| format!("no open question about {sensor} for {component}"))?;
        let seen = if item { "an item" } else { "no item" };
        let conclusion = if item == q.reading {
            format!(
                "{component}: the operator sees {seen} at {sensor}, as {sensor} reads: \
                 {sensor} is right, the cause is {} (check that drive), then reset the \
                 diagnosers",
                q.other_faults.join(" or ")
            )
        } else {
            format!(
                "{component}: the operator sees {seen} at {sensor}, which reads {}: \
                 {sensor} is at fault ({}); repair it, then reset the diagnosers",
                u8::from(q.reading),
                q.sensor_faults.join(" or ")
            )
        };
        self.answers.insert(component.to_string(), conclusion);
        Ok(())
    }

    /// The constraints bypassed now, by id.
    pub fn bypasses(&self) -> &BTreeMap<String, Bypass> {
        &self.bypasses
    }

    fn bypass(&mut self, id: &str, minutes: u64, reason: &str, by: &str) -> Result<(), String> {
        if self.is_live() {
            return Err(
                "a bypass acts on the filter that drives the plant: on a live link \
                        that is the gateway's, not the console's mirror"
                    .into(),
            );
        }
        if self.bundle.constraints.get(id).is_none() || crate::pop::coop::is_diagnoser_stop(id) {
            return Err(format!("no safety constraint `{id}`"));
        }
        if reason.trim().is_empty() {
            return Err("a bypass needs a reason".into());
        }
        if minutes == 0 || minutes > MAX_BYPASS_MIN {
            return Err(format!(
                "a bypass lasts 1 to {MAX_BYPASS_MIN} min (one shift), not {minutes}"
            ));
        }
        let now = self.now();
        self.bypasses.insert(
            id.to_string(),
            Bypass {
                from: now,
                until: now + Millis(minutes * 60_000),
                reason: reason.trim().to_string(),
                by: by.to_string(),
            },
        );
        self.apply_bypasses();
        Ok(())
    }

    /// Gives the engine the set of bypassed constraints.
    fn apply_bypasses(&mut self) {
        self.engine
            .set_bypassed(self.bypasses.keys().cloned().collect());
    }

    /// Ends the bypasses whose time is up (journaled).
    fn expire_bypasses(&mut self, now: Millis) {
        let ended: Vec<String> = self
            .bypasses
            .iter()
            .filter(|(_, b)| b.until <= now)
            .map(|(id, _)| id.clone())
            .collect();
        if ended.is_empty() {
            return;
        }
        for id in &ended {
            self.bypasses.remove(id);
            self.log_coded(
                "bypass_end",
                format!("{id} enforced again (the bypass's time is up)"),
                "journal-bypass-expired",
                fields([("constraint", id.clone())]),
            );
        }
        self.apply_bypasses();
    }

    /// The outputs requested by hand, in manual mode.
    pub fn manual_outputs(&self) -> Option<&Bits> {
        self.manual.as_ref()
    }

    fn enter_manual(&mut self) -> Result<(), String> {
        if self.manual.is_some() {
            return Err("already in manual mode".into());
        }
        if self.is_live() {
            return Err(
                "manual mode drives the emulator; on a live link the PLC's own \
                        manual mode applies"
                    .into(),
            );
        }
        if self.engine.is_tripped() {
            return Err(format!(
                "refused: the safety filter holds the plant ({}); Reset first",
                self.latched_constraints().join(", ")
            ));
        }
        self.manual = Some(self.engine.frame().now(Space::Output).clone());
        Ok(())
    }

    fn leave_manual(&mut self) -> Result<(), String> {
        if self.manual.take().is_none() {
            return Err("not in manual mode".into());
        }
        self.restart_program(self.program.program().clone());
        // The task monitors did not run by hand: they restart with the program.
        let now = self.now();
        if let (Some(t), Some(set)) = (self.tasks.as_mut(), self.bundle.tasks.as_ref()) {
            t.monitor = crate::tasks::Monitor::new(set, now);
            t.seen = 0;
        }
        Ok(())
    }

    /// The outputs a manual request asks for and the constraints they would violate
    /// (none: the request is taken); an error outside manual mode or for an unknown
    /// output. Changes nothing.
    pub fn check_manual(
        &self,
        id: &str,
        on: bool,
    ) -> Result<(Bits, Vec<crate::engine::FiredConstraint>), String> {
        let Some(current) = self.manual.as_ref() else {
            return Err("not in manual mode: enter manual mode first".into());
        };
        let Some(k) = self.bundle.plant.outputs.iter().position(|s| s.id == id) else {
            return Err(format!("no output `{id}` in the plant"));
        };
        let mut candidate = current.clone();
        candidate.set(k, on);
        let refused = self.engine.check_request(&candidate);
        Ok((candidate, refused))
    }

    /// A manual request, checked against the constraints before it is taken.
    fn manual_set(&mut self, id: &str, on: bool) -> Result<(), String> {
        let (candidate, refused) = self.check_manual(id, on)?;
        if refused.is_empty() {
            self.manual = Some(candidate);
            return Ok(());
        }
        let Some(signal) = self.bundle.plant.outputs.iter().find(|s| s.id == id) else {
            return Err(format!("no output `{id}` in the plant"));
        };
        let what = match (&signal.off, on) {
            (Some(off), false) => format!("{id} OFF ({off})"),
            _ => format!("{id} {}", if on { "ON" } else { "OFF" }),
        };
        Err(texts::refused_request(&self.bundle, &what, &refused))
    }

    /// The constraints of the trip that holds the plant, if it is tripped.
    pub fn latched_constraints(&self) -> Vec<String> {
        match self.engine.trips.last() {
            Some(t) if self.engine.is_tripped() => {
                t.constraints.iter().map(|c| c.id.clone()).collect()
            }
            _ => Vec::new(),
        }
    }

    /// Applies an operator action now; the result is journaled.
    pub fn act(&mut self, action: &OperatorAction) -> Result<(), String> {
        let now = self.now();
        let result = self.apply_action(action);
        self.journal_action(now, action, &result);
        result
    }

    /// Carries out an operator action, without journaling it.
    fn apply_action(&mut self, action: &OperatorAction) -> Result<(), String> {
        match action {
            OperatorAction::Start | OperatorAction::Stop if self.manual.is_some() => Err(
                "refused in manual mode: leave manual mode first (the program restarts \
                 from its initial steps)"
                    .to_string(),
            ),
            OperatorAction::Manual(true) => self.enter_manual(),
            OperatorAction::Manual(false) => self.leave_manual(),
            OperatorAction::ManualSet(id, on) => self.manual_set(id, *on),
            OperatorAction::Bypass {
                constraint,
                minutes,
                reason,
                by,
            } => self.bypass(constraint, *minutes, reason, by),
            OperatorAction::AnswerDoubt {
                component,
                sensor,
                item,
            } => self.answer_doubt(component, sensor, *item),
            OperatorAction::EndBypass(id) => {
                if self.bypasses.remove(id).is_some() {
                    self.apply_bypasses();
                    Ok(())
                } else {
                    Err(format!("{id} is not bypassed"))
                }
            }
            OperatorAction::Start if self.action_stop.is_some() => Err(format!(
                "refused: the action monitor stopped the plant ({}); repair, then Reset, \
                 then Start",
                self.action_stop.as_deref().unwrap_or_default()
            )),
            OperatorAction::Start if self.engine.is_tripped() => Err(format!(
                "refused: the safety filter has stopped the plant ({}); Reset first, then \
                 Start",
                self.latched_constraints().join(", ")
            )),
            OperatorAction::Start => self.press_role("start"),
            // Stop always works: while tripped, the program stops too and does not
            // restart at the reset.
            OperatorAction::Stop => self.press_role("stop"),
            OperatorAction::Press(b) => self.press(b),
            OperatorAction::Switch(s, v) => {
                self.program.set_switch(s, *v).map_err(|e| e.to_string())
            }
            OperatorAction::Filter(mode) => {
                self.engine.set_mode(*mode);
                Ok(())
            }
            OperatorAction::Reset if self.action_stop.is_some() => self.reset_action_stop(),
            OperatorAction::Reset => self.engine.reset().map_err(|e| e.to_string()),
            OperatorAction::Repair if self.is_live() => {
                Err("refused on a live link: repair the machine itself".to_string())
            }
            OperatorAction::Repair => {
                self.repair();
                Ok(())
            }
            OperatorAction::ResetDiagnosers => match self.diagnosers.as_mut() {
                Some(d) => {
                    d.reset_in(self.engine.frame_mut());
                    Ok(())
                }
                None => Err("this run has no diagnosers".to_string()),
            },
            &OperatorAction::Reinitialise { emptied } => {
                if self.engine.reinitialise(emptied) {
                    if emptied {
                        let n = self.emulator.remove_items();
                        self.log_coded(
                            "plant_emptied",
                            format!("the operator took {n} items off the plant"),
                            "journal-plant-emptied",
                            fields([("n", n.to_string())]),
                        );
                    }
                    self.restart_program(self.program.program().clone());
                    if let Some(d) = self.diagnosers.as_mut() {
                        d.reset_in(self.engine.frame_mut());
                    }
                    Ok(())
                } else {
                    Err("the filter is not tripped: nothing to re-initialise".to_string())
                }
            }
            OperatorAction::Pause => {
                self.engine.set_hold(true);
                Ok(())
            }
            OperatorAction::Resume if self.action_stop.is_some() => Err(format!(
                "refused: the action monitor stopped the plant ({}); repair, then Reset",
                self.action_stop.as_deref().unwrap_or_default()
            )),
            OperatorAction::Resume => {
                self.engine.set_hold(false);
                Ok(())
            }
        }
    }

    /// The technician's repair on the simulator: the emulator's faults end, the
    /// diagnosers' flags are cleared.
    fn repair(&mut self) {
        let n = self.emulator.repair_faults();
        self.log_coded(
            "repair",
            format!("repair on the simulator: {n} faults removed"),
            "journal-repair",
            fields([("n", n.to_string())]),
        );
        if let Some(d) = self.diagnosers.as_mut() {
            d.reset_in(self.engine.frame_mut());
            self.diagnosers_cleared(
                self.now(),
                "diagnosers reset after the repair: fault flags cleared, sensors read again",
            );
        }
    }

    /// Journals an operator action and its result.
    fn journal_action(
        &mut self,
        now: Millis,
        action: &OperatorAction,
        result: &Result<(), String>,
    ) {
        match (result, action) {
            (Ok(()), OperatorAction::Reset) => {
                for key in self.alarms.active_keys(AlarmKind::FilterTrip) {
                    self.alarms.clear(now, &key);
                }
                self.log_coded(
                    "reset",
                    "operator reset of the filter".into(),
                    "journal-reset",
                    BTreeMap::new(),
                );
            }
            (Err(e), OperatorAction::Reset) => self.log("reset_refused", e.clone()),
            (Ok(()), &OperatorAction::Reinitialise { emptied }) => {
                self.log_reinitialise(now, emptied);
            }
            (Ok(()), OperatorAction::Manual(true)) => self.log_coded(
                "manual",
                "manual mode: the program is no longer scanned, the outputs stay as they \
                 are; every command is checked against the safety constraints"
                    .into(),
                "journal-manual-on",
                BTreeMap::new(),
            ),
            (Ok(()), OperatorAction::Manual(false)) => self.log_coded(
                "manual",
                "automatic mode: the program restarted from its initial steps; press Start".into(),
                "journal-manual-off",
                BTreeMap::new(),
            ),
            (Ok(()), OperatorAction::ManualSet(id, on)) => self.log_coded(
                "manual",
                format!("{id} {} by hand", if *on { "ON" } else { "OFF" }),
                "journal-by-hand",
                fields([("output", id.clone()), ("on", on.to_string())]),
            ),
            (Err(e), OperatorAction::ManualSet(id, on)) => self.log_manual_refused(id, *on, e),
            (
                Ok(()),
                OperatorAction::Bypass {
                    constraint,
                    minutes,
                    reason,
                    by,
                },
            ) => self.log_bypass(now, constraint, *minutes, reason, by),
            (Err(e), OperatorAction::Bypass { .. }) => self.log("bypass_refused", e.clone()),
            (Ok(()), OperatorAction::AnswerDoubt { component, .. }) => {
                let conclusion = self.answers.get(component).cloned().unwrap_or_default();
                self.log("operator_answer", conclusion);
            }
            (Ok(()), OperatorAction::EndBypass(id)) => {
                self.log_coded(
                    "bypass_end",
                    format!("{id} enforced again (bypass ended)"),
                    "journal-bypass-end",
                    fields([("constraint", id.clone())]),
                );
            }
            (Ok(()), OperatorAction::ResetDiagnosers) => self.diagnosers_cleared(
                now,
                "operator reset of the diagnosers after a repair: fault flags cleared, \
                 sensors read again, no certain decision until each model is back in \
                 its initial state",
            ),
            (Ok(()), a) => {
                let (code, f) = match a {
                    OperatorAction::Start
                    | OperatorAction::Stop
                    | OperatorAction::Pause
                    | OperatorAction::Resume => {
                        ("journal-operator", fields([("action", format!("{a:?}"))]))
                    }
                    _ => ("", BTreeMap::new()),
                };
                self.log_coded("operator", format!("{a:?}"), code, f);
            }
            (Err(e), a) => self.log("operator_refused", format!("{a:?}: {e}")),
        }
    }

    /// Clears the trip alarms and journals an operator re-initialisation.
    fn log_reinitialise(&mut self, now: Millis, emptied: bool) {
        for key in self.alarms.active_keys(AlarmKind::FilterTrip) {
            self.alarms.clear(now, &key);
        }
        if self.diagnosers.is_some() {
            self.diagnosers_cleared(
                now,
                "diagnosers restarted with the re-initialisation: fault flags cleared, \
                 sensors read again, no certain decision until each model is back in \
                 its initial state",
            );
        }
        let observers = if emptied {
            "the plant emptied, every observer restarts empty"
        } else {
            "the items left in place, the observers cleared where the sensors \
             leave no room for their item (the others kept)"
        };
        self.log_coded(
            "reinitialise",
            format!(
                "operator re-initialisation after a check of the plant: the \
                 control program back to its initial steps, the sensors taken as \
                 read, {observers}, the trip ended"
            ),
            "journal-reinitialise",
            fields([("emptied", emptied.to_string())]),
        );
    }

    /// Journals a refused manual command with the constraints that refuse it.
    fn log_manual_refused(&mut self, id: &str, on: bool, e: &str) {
        // What the refusal says, as data: the output, the request and each
        // refusing constraint with the values that make it refuse.
        let refused = self
            .check_manual(id, on)
            .map(|(_, r)| r)
            .unwrap_or_default();
        let (code, mut f) = if refused.is_empty() {
            ("", BTreeMap::new())
        } else {
            (
                "journal-manual-refused",
                fields([
                    ("output", id.to_string()),
                    ("on", on.to_string()),
                    (
                        "constraints",
                        refused
                            .iter()
                            .map(|c| c.id.as_str())
                            .collect::<Vec<_>>()
                            .join(","),
                    ),
                ]),
            )
        };
        for c in &refused {
            f.insert(
                format!("with-{}", c.id),
                texts::request_context(c).join(", "),
            );
        }
        self.log_coded("manual_refused", e.to_string(), code, f);
    }

    /// Journals a bypass granted.
    fn log_bypass(&mut self, now: Millis, constraint: &str, minutes: u64, reason: &str, by: &str) {
        self.log_coded(
            "bypass",
            format!(
                "{constraint} bypassed for {minutes} min by {by}: {reason} (the filter \
             does not enforce it until {} ms)",
                now.0 + minutes * 60_000
            ),
            "journal-bypass",
            fields([
                ("constraint", constraint.to_string()),
                ("minutes", minutes.to_string()),
                ("by", by.to_string()),
                ("reason", reason.to_string()),
                ("until_ms", (now.0 + minutes * 60_000).to_string()),
            ]),
        );
    }

    /// The diagnosers' flags were cleared (operator's reset, or a live link's restart):
    /// the sensors are read again and the diagnosis alarms end.
    fn diagnosers_cleared(&mut self, now: Millis, text: &str) {
        self.degraded.clear();
        self.answers.clear();
        for key in self.alarms.active_keys(AlarmKind::Diagnosis) {
            self.alarms.clear(now, &key);
        }
        self.log("diagnosers_reset", text.to_string());
    }

    /// Injects a fault now (training).
    pub fn inject(&mut self, fault: FaultSpec) -> Result<(), Problem> {
        let text = format!("{:?}", fault.fault);
        let f = fault.fault.fields();
        self.emulator.try_schedule_fault(fault)?;
        self.log_coded(
            "fault",
            format!("fault injected: {text}"),
            "journal-fault",
            f,
        );
        Ok(())
    }

    fn log(&mut self, kind: &str, text: String) {
        self.log_coded(kind, text, "", BTreeMap::new());
    }

    /// A journal entry with its message id and fields (see [`JournalEntry::code`]).
    fn log_coded(
        &mut self,
        kind: &str,
        text: String,
        code: &str,
        fields: BTreeMap<String, String>,
    ) {
        self.journal.push(JournalEntry {
            time_ms: self.now().0,
            kind: kind.to_string(),
            text,
            code: code.to_string(),
            fields,
        });
    }

    /// Journal entries not yet taken (the app appends them to disk as they come).
    pub fn take_journal(&mut self) -> &[JournalEntry] {
        let from = self.journal_taken;
        self.journal_taken = self.journal.len();
        &self.journal[from..]
    }

    /// The sensors the control program and the task monitors read from their estimates
    /// (degraded mode), in input order.
    pub fn degraded_sensors(&self) -> Vec<String> {
        let mut inputs: Vec<usize> = self.degraded.iter().map(|&(i, _)| i).collect();
        inputs.sort_unstable();
        inputs
            .into_iter()
            .filter_map(|i| self.bundle.plant.inputs.get(i).map(|s| s.id.clone()))
            .collect()
    }

    /// The sensors held as suspect now (an edge their physics did not allow), those
    /// whose plausibility alarm is active, in raising order.
    pub fn suspect_sensors(&self) -> Vec<String> {
        self.alarms
            .active_keys(AlarmKind::Plausibility)
            .into_iter()
            .filter_map(|k| k.strip_prefix("plausibility:").map(str::to_string))
            .collect()
    }

    /// What the synoptic marks live: the sensors read from their estimates and those
    /// held as suspect.
    pub fn live_marks(&self) -> Vec<Highlight> {
        let mut marks: Vec<Highlight> = self
            .degraded_sensors()
            .into_iter()
            .map(|element| Highlight {
                element,
                mark: Mark::Estimated,
            })
            .collect();
        marks.extend(self.suspect_sensors().into_iter().map(|element| Highlight {
            element,
            mark: Mark::Suspect,
        }));
        marks
    }

    /// The whole journal of the run.
    pub fn journal(&self) -> &[JournalEntry] {
        &self.journal
    }

    /// Plant snapshots kept for the replay, oldest first.
    pub fn snapshots(&self) -> &VecDeque<PlantSnapshot> {
        &self.snapshots
    }

    /// Runs one PLC cycle.
    pub fn cycle(&mut self) {
        let now = self.now();
        self.expire_bypasses(now);
        while self.pending.front().is_some_and(|a| a.at_ms <= now.0) {
            if let Some(a) = self.pending.pop_front() {
                let _ = self.act(&a.action);
            }
        }
        if self.options.explain {
            self.program_before.copy_state_from(&self.program);
        }
        let applied = match (self.diagnosers.as_mut(), self.manual.as_ref()) {
            (None, Some(m)) => self
                .engine
                .cycle(now, self.emulator.sensors(), &mut Commanded(m.clone()))
                .clone(),
            (Some(d), Some(m)) => self
                .engine
                .cycle_with(
                    now,
                    self.emulator.sensors(),
                    &mut Commanded(m.clone()),
                    &mut |t, f, held| d.update_held(t, f, held),
                )
                .clone(),
            (None, None) => self
                .engine
                .cycle(now, self.emulator.sensors(), &mut self.program)
                .clone(),
            (Some(d), None) => {
                let mut control = DegradedControl {
                    inner: &mut self.program,
                    subs: &self.degraded,
                };
                self.engine
                    .cycle_with(
                        now,
                        self.emulator.sensors(),
                        &mut control,
                        &mut |t, f, held| d.update_held(t, f, held),
                    )
                    .clone()
            }
        };
        self.diagnosis_events(now);
        self.plausibility_events(now);
        self.step_actions(now);
        let tripped = self.record_events(now);
        // By hand, the program did not run: no explanation from it (the alarm and the
        // next-step panel still say why).
        if let (Some(index), true, None) = (tripped, self.options.explain, &self.manual) {
            // The emulator is still at the start of the tripping cycle (the engine only
            // read it); the program has just computed the erroneous command.
            self.explain_trip(index, self.emulator.clone(), self.program_before.clone());
        }
        self.step_tasks(now);
        self.emulator.step(self.cycle, &applied);
        let hazards = self.emulator.hazards();
        if hazards.len() > self.hazards_seen {
            let new: Vec<Hazard> = hazards[self.hazards_seen..].to_vec();
            self.hazards_seen = hazards.len();
            for h in new {
                let text = h.summary();
                let alarm = texts::hazard(&h);
                let f = alarm.fields.clone();
                self.alarms.raise(
                    Millis(h.time_ms),
                    &format!("hazard:{}:{:?}", h.box_id, h.kind),
                    AlarmKind::Hazard,
                    alarm,
                );
                self.log_coded("hazard", text, "alarm-hazard", f);
            }
        }
        self.push_snapshot(now);
    }

    /// Records where the boxes and the table are, for the replay.
    fn push_snapshot(&mut self, now: Millis) {
        let mut snapshot = if self.snapshots.len() >= self.options.history_cycles.max(1) {
            self.snapshots.pop_front()
        } else {
            None
        }
        .unwrap_or_else(|| PlantSnapshot {
            time: now,
            boxes: Vec::new(),
            table_angle_mdeg: 0,
            positions: Vec::new(),
        });
        snapshot.time = now;
        snapshot.boxes.clear();
        self.emulator.boxes_into(&mut snapshot.boxes);
        snapshot.table_angle_mdeg = self.emulator.table_angle_mdeg();
        snapshot.positions.clear();
        if let Some(c) = self.emulator.as_components() {
            snapshot.positions.extend(c.positions());
        }
        self.snapshots.push_back(snapshot);
    }

    /// Turns the engine's events into alarms and journal entries; returns the index of
    /// the trip (or reported violation) of this cycle, if any.
    fn record_events(&mut self, now: Millis) -> Option<usize> {
        let events = self.engine.drain_events();
        let mut tripped = None;
        for e in &events {
            match e {
                Event::Trip { index } | Event::Violation { index } => {
                    let ids: Vec<String> = self.engine.trips[*index]
                        .constraints
                        .iter()
                        .map(|c| c.id.clone())
                        .collect();
                    let key = format!("trip:{}", ids.join("+"));
                    let text = texts::trip(&self.bundle, &self.engine.trips[*index]);
                    self.alarms.raise(now, &key, AlarmKind::FilterTrip, text);
                    self.log_coded(
                        "trip",
                        format!("filter tripped on {}", ids.join(", ")),
                        "journal-trip",
                        fields([("constraints", ids.join(", "))]),
                    );
                    tripped = Some(*index);
                }
                Event::SpecificationError { message } => {
                    self.alarms
                        .raise(now, "spec", AlarmKind::Specification, message.clone());
                    self.log("spec_error", message.clone());
                }
                Event::Reset => {}
            }
        }
        tripped
    }

    /// Task monitors: events of this cycle (on the frame after the filter), alarms, and
    /// their outputs published for the constraints of the next cycle.
    fn step_tasks(&mut self, now: Millis) {
        // By hand, no task runs as the monitors expect: they restart when the program
        // does.
        if self.manual.is_some() {
            return;
        }
        let Some(t) = self.tasks.as_mut() else {
            return;
        };
        // In degraded mode the tasks read the estimated sensors, as the program does.
        let estimated = diagnosis::estimated_frame(&self.degraded, self.engine.frame());
        if self.engine.cycles() <= 1 {
            // The first scan's previous values are cold (a PLC's first scan): every
            // sensor on would read as a rise. The sensors were in that state before the
            // first scan; the outputs were off. The task events read that warm frame,
            // so an order given in the first scan starts its task and a level the
            // plant starts at ends none.
            let mut warm = estimated.unwrap_or_else(|| self.engine.frame().clone());
            let now_inputs = warm.now(Space::Input).clone();
            *warm.prev_mut(Space::Input) = now_inputs;
            t.events.step(&mut t.monitor, now, &warm);
        } else {
            match estimated {
                None => t.events.step(&mut t.monitor, now, self.engine.frame()),
                Some(f) => t.events.step(&mut t.monitor, now, &f),
            }
        }
        t.events.publish(&t.monitor, self.engine.frame_mut());
        let new: Vec<crate::tasks::Alarm> = t.monitor.alarms[t.seen..].to_vec();
        t.seen = t.monitor.alarms.len();
        for a in new {
            let warning = a.severity == crate::tasks::Severity::Warning;
            let text = texts::task(self.bundle.tasks.as_ref(), &a);
            let (code, f) = (alarm_code(&text), text.fields.clone());
            if !warning {
                self.alarms.raise(
                    a.time,
                    &format!("task:{}:{:?}", a.subject, a.code),
                    AlarmKind::Task,
                    text,
                );
            }
            self.log_coded(
                if warning {
                    "task_warning"
                } else {
                    "task_alarm"
                },
                a.text,
                &code,
                f,
            );
        }
    }

    /// Certain diagnoses of this cycle: alarms and journal lines, and the sensors the
    /// control program reads from their estimates from the next cycle on.
    fn diagnosis_events(&mut self, now: Millis) {
        let Some(d) = self.diagnosers.as_ref() else {
            return;
        };
        let enforced = self.engine.mode() == FilterMode::Enforce;
        let acts = diagnosis::Cooperation {
            stop: enforced,
            // The simulation's program reads the estimates; a followed monitor's PLC
            // does not.
            estimate: enforced || !self.is_live(),
        };
        let notices = diagnosis::take_notices(d, &mut self.diag_seen, acts);
        if notices.is_empty() {
            return;
        }
        self.degraded = diagnosis::estimated_inputs(d, &self.bundle.plant, &self.engine.symbols);
        for n in notices {
            let text = texts::diagnosis(&self.bundle.plant, &n, acts);
            let (code, f) = (alarm_code(&text), text.fields.clone());
            self.alarms.raise(now, &n.key, AlarmKind::Diagnosis, text);
            self.log_coded("diagnosis", n.text, &code, f);
        }
        // A diagnosis made while the plant is stopped completes the stop's hypothesis:
        // the technician reads the hardware first even when it was decided late.
        if self.engine.is_tripped() {
            let faults = self.hardware_faults();
            if let Some(ex) = self.explanations.values_mut().next_back() {
                explain::add_hardware_hypothesis(ex, &faults);
            }
        }
    }

    /// The diagnosers' flagged partitions now, with their last decision: the hardware
    /// the hypothesis names first.
    pub fn hardware_faults(&self) -> Vec<explain::HardwareFault> {
        let Some(d) = self.diagnosers.as_ref() else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (partition, _, _) in d.flagged() {
            let Some(last) = d.diagnoses.iter().rev().find(|x| x.partition == partition) else {
                continue;
            };
            let info = self.partitions.get(&partition);
            let faults = last
                .fault
                .split('|')
                .map(|l| {
                    let l = l.trim().to_string();
                    let text = info
                        .and_then(|i| i.descriptions.get(&l))
                        .cloned()
                        .unwrap_or_default();
                    (l, text)
                })
                .collect();
            out.push(explain::HardwareFault {
                time_ms: last.time_ms,
                component: last.component.clone(),
                partition,
                faults,
                certain: last.certainty != crate::pop::Certainty::Ambiguous,
                check: info.map(|i| i.check.clone()).unwrap_or_default(),
            });
        }
        out
    }

    /// Sensors whose implausible edge was held this cycle (an alarm while suspect) or
    /// that are plausible again (the alarm ends).
    pub(crate) fn plausibility_events(&mut self, now: Millis) {
        for n in self.engine.plausibility.take_notices() {
            let key = format!("plausibility:{}", n.sensor);
            let (code, f) = if n.suspect {
                let text = texts::plausibility(&self.bundle.plant, &n);
                let coded = (alarm_code(&text), text.fields.clone());
                self.alarms.raise(now, &key, AlarmKind::Plausibility, text);
                coded
            } else {
                self.alarms.clear(now, &key);
                (
                    "journal-plausible-again".to_string(),
                    fields([("sensor", n.sensor.clone())]),
                )
            };
            self.log_coded("plausibility", n.text, &code, f);
        }
    }

    /// Runs until the simulated time reaches `end`.
    pub fn run_until(&mut self, end: Millis) {
        while self.now() < end {
            self.cycle();
        }
    }

    fn explain_trip(&mut self, index: usize, emulator: Physical, program: ProgramRuntime) {
        if let Some((ex, projected)) = self.explanation(index, emulator, program, &self.program) {
            self.projections.insert(index, projected);
            self.explanations.insert(index, ex);
        }
    }

    /// The five levels of trip `index` and its projection, from the emulator as it was at
    /// the start of the tripping cycle, the program before its tripping scan (`before`)
    /// and after it (`after`). [`Simulation::cycle`] calls it at each trip; `vigie bench`
    /// times it. `None` for an unknown trip.
    pub fn explanation(
        &self,
        index: usize,
        emulator: Physical,
        before: ProgramRuntime,
        after: &ProgramRuntime,
    ) -> Option<(Explanation, ProjectedPlant)> {
        let mut ex = explain::explain(&self.engine, index)?;
        // Beyond the paper: the program is known, so its elements lead the hypothesis.
        if let Some(trip) = self.engine.trips.get(index) {
            explain::add_program_hypothesis(&mut ex, trip, &before, after);
        }
        // Hardware before program: a component the diagnosers hold faulty comes first.
        explain::add_hardware_hypothesis(&mut ex, &self.hardware_faults());
        let projected = self.project(emulator, after.clone());
        let enforced = self.engine.trips.get(index).is_none_or(|t| t.enforced);
        fill_projection(&mut ex, &projected, &self.bundle, enforced);
        Some((ex, projected))
    }

    /// Level 1: runs clones of the emulator (as it was at the start of the tripping cycle)
    /// and of the program (just after its tripping scan) forward without the filter, for
    /// the projection horizon: the erroneous command is applied, then the program keeps
    /// scanning.
    fn project(&self, mut emu: Physical, mut program: ProgramRuntime) -> ProjectedPlant {
        let start = emu.now();
        let known = emu.hazards().len();
        let mut frame = self.engine.frame().clone();
        let mut outputs = self.engine.commanded().clone();
        let end = start + self.projection;
        let mut first_hazard_picture: Option<(Millis, Vec<BoxView>, i32, Option<Scene>)> = None;
        let mut first = true;
        while emu.now() < end {
            if !first {
                let now = emu.now();
                frame.shift();
                frame.now_mut(Space::Input).copy_from(emu.sensors());
                program.scan(now, &frame, &mut outputs);
                self.engine.hold_on(&mut outputs);
            }
            first = false;
            emu.step(self.cycle, &outputs);
            if first_hazard_picture.is_none() && emu.hazards().len() > known {
                // Let the consequence show for a short while after the hazard.
                let mut show = emu.clone();
                let mut f = frame.clone();
                let mut p = program.clone();
                let mut o = outputs.clone();
                for _ in 0..50 {
                    let t = show.now();
                    f.shift();
                    f.now_mut(Space::Input).copy_from(show.sensors());
                    p.scan(t, &f, &mut o);
                    self.engine.hold_on(&mut o);
                    show.step(self.cycle, &o);
                }
                first_hazard_picture = Some((
                    show.now(),
                    show.boxes(),
                    show.table_angle_mdeg(),
                    show.scene(),
                ));
                break;
            }
        }
        let hazards = emu.hazards()[known..].to_vec();
        let (at, boxes, angle, scene) = first_hazard_picture
            .unwrap_or_else(|| (emu.now(), emu.boxes(), emu.table_angle_mdeg(), emu.scene()));
        ProjectedPlant {
            at_ms: at.0,
            boxes,
            table_angle_mdeg: angle,
            scene,
            hazards,
        }
    }

    /// The report of the run so far.
    pub fn report(&self, seed: u64) -> RunReport {
        RunReport {
            scenario: self.name.clone(),
            seed,
            filter: self.engine.mode(),
            trips: self
                .engine
                .trips
                .iter()
                .map(|t| TripSummary {
                    time_ms: t.time_ms,
                    constraints: t.constraints.iter().map(|c| c.id.clone()).collect(),
                    fallback: t.fallback.iter().cloned().collect(),
                    record: t.clone(),
                })
                .collect(),
            hazards: self.emulator.hazards().to_vec(),
            boxes: self.emulator.stats(),
            explanations: self.explanations.values().cloned().collect(),
            task_alarms: self
                .tasks
                .as_ref()
                .map(|t| {
                    t.monitor
                        .alarms
                        .iter()
                        .filter(|a| a.severity != crate::tasks::Severity::Warning)
                        .cloned()
                        .collect()
                })
                .unwrap_or_default(),
            sim_ms: self.now().0,
            cycles: self.engine.cycles(),
            diagnoses: self
                .diagnosers
                .as_ref()
                .map(|d| d.diagnoses.clone())
                .unwrap_or_default(),
            actions: self.action_events().to_vec(),
        }
    }
}

pub use crate::live::follow::Followed;

/// The explanation of a trip seen on a live plant: levels 0, 2, 3 and 4 from the
/// recorder, and level 1 from an emulator initialised from the observed inputs and
/// observers of the tripping cycle (boxes placed where sensors and observers see them,
/// the table angle from its position sensors), run forward for `horizon`. When the
/// program the PLC runs is known (`program`, followed beside it), its elements lead the
/// hypothesis as in emulator mode, and the projection runs it on the projected plant;
/// otherwise the outputs the PLC commanded in the tripping cycle are held. Without a
/// layout, level 1 stays empty.
pub fn explain_live(
    engine: &Engine,
    bundle: &PlantBundle,
    layout: Option<&Layout>,
    index: usize,
    (horizon, cycle): (Millis, Millis),
    program: Option<Followed<'_>>,
) -> Option<Explanation> {
    explain_live_projected(engine, bundle, layout, index, (horizon, cycle), program)
        .map(|(ex, _)| ex)
}

/// [`explain_live`] with the projected plant (`None` without a layout or when the
/// emulator cannot be initialised from the observation).
pub fn explain_live_projected(
    engine: &Engine,
    bundle: &PlantBundle,
    layout: Option<&Layout>,
    index: usize,
    (horizon, cycle): (Millis, Millis),
    program: Option<Followed<'_>>,
) -> Option<(Explanation, Option<ProjectedPlant>)> {
    let mut ex = explain::explain(engine, index)?;
    let trip = engine.trips.get(index)?;
    if let Some(p) = program {
        explain::add_program_hypothesis(&mut ex, trip, p.before, p.after);
    }
    let Some(layout) = layout else {
        return Some((ex, None));
    };
    let Some(record) = engine.history.iter().find(|r| r.time.0 == trip.time_ms) else {
        return Some((ex, None));
    };
    let Ok(mut emu) =
        explain::emulator_from_observation(layout, &bundle.plant, record, &engine.observers)
    else {
        return Some((ex, None));
    };
    let start = emu.now();
    let known = emu.hazards().len();
    let step = Millis(cycle.0.max(1));
    let shift = |t: u64| trip.time_ms + t.saturating_sub(start.0);
    // The PLC's outputs of the tripping cycle; then its program's, scan after scan,
    // on the projected plant's sensors (the program's clock is the link's). The
    // outputs the program does not drive (the safety contactors, which the PLC's safety
    // function holds) keep the PLC's values.
    let mut outputs = record.commanded.clone();
    let mut frame = engine.frame().clone();
    let mut rt = program.map(|p| p.after.clone());
    let driven = program.map_or(&[][..], |p| p.driven);
    let mut scan = |emu: &Physical, outputs: &mut Bits| {
        if let Some(rt) = rt.as_mut() {
            frame.shift();
            frame.now_mut(Space::Input).copy_from(emu.sensors());
            rt.scan(Millis(shift(emu.now().0)), &frame, outputs);
            for k in (0..outputs.len()).filter(|k| !driven.contains(k)) {
                outputs.set(k, record.commanded.get(k));
            }
        }
    };
    while emu.now() < start + horizon {
        emu.step(step, &outputs);
        scan(&emu, &mut outputs);
        if emu.hazards().len() > known {
            for _ in 0..(500 / step.0).max(1) {
                emu.step(step, &outputs);
                scan(&emu, &mut outputs);
            }
            break;
        }
    }
    let projected = ProjectedPlant {
        at_ms: shift(emu.now().0),
        boxes: emu.boxes().to_vec(),
        table_angle_mdeg: emu.table_angle_mdeg(),
        scene: None,
        hazards: emu.hazards()[known..]
            .iter()
            .map(|h| Hazard {
                time_ms: shift(h.time_ms),
                ..h.clone()
            })
            .collect(),
    };
    fill_projection(&mut ex, &projected, bundle, trip.enforced);
    Some((ex, Some(projected)))
}

fn fill_projection(ex: &mut Explanation, p: &ProjectedPlant, bundle: &PlantBundle, enforced: bool) {
    let level = &mut ex.projection;
    level.title = "Projection".into();
    if p.hazards.is_empty() && !enforced {
        let horizon = p.at_ms.saturating_sub(ex.time_ms);
        level.items.push(Item {
            code: codes::X_NO_DAMAGE_PREDICTED_MONITOR.id,
            fields: [("horizon_ms".to_string(), horizon.to_string())]
                .into_iter()
                .collect(),
            text: format!(
                "Monitor mode: as the plant runs on, no damage is predicted within {horizon} ms; the violation is still one the constraints forbid."
            ),
        });
    } else if p.hazards.is_empty() {
        level.items.push(Item {
            code: codes::X_NO_DAMAGE_PREDICTED.id,
            fields: [("horizon_ms".to_string(), p.at_ms.saturating_sub(ex.time_ms).to_string())]
                .into_iter()
                .collect(),
            text: format!(
                "Without the filter, no damage is predicted within {} ms; the stop prevented a situation the constraints forbid.",
                p.at_ms.saturating_sub(ex.time_ms)
            ),
        });
    }
    for h in &p.hazards {
        let after = h.time_ms.saturating_sub(ex.time_ms);
        if h.box_id == 0 {
            level.items.push(component_hazard_item(h, after));
        } else {
            level.items.push(Item {
                code: codes::X_HAZARD_PREDICTED.id,
                fields: [
                    ("kind".to_string(), format!("{:?}", h.kind)),
                    ("place".to_string(), h.place.clone()),
                    ("box".to_string(), h.box_id.to_string()),
                    ("after_ms".to_string(), after.to_string()),
                    ("elements".to_string(), h.elements.join(",")),
                ]
                .into_iter()
                .chain(h.at.fields())
                .collect(),
                text: format!(
                    "Without the filter, {after} ms later: box {} {} at the {} ({}).",
                    h.box_id,
                    hazard_verb(h),
                    h.place,
                    h.elements.join(", ")
                ),
            });
        }
        for e in &h.elements {
            if bundle.plant.signal(e).is_some() {
                let hl = Highlight {
                    element: e.clone(),
                    mark: Mark::Circle,
                };
                if !level.highlights.contains(&hl) {
                    level.highlights.push(hl);
                }
            }
        }
    }
}

/// X104: a mechanism's hazard (no item involved) predicted by the projection.
fn component_hazard_item(h: &Hazard, after: u64) -> Item {
    let what = match h.kind {
        crate::emulator::HazardKind::EndStop => "driven into the end of its travel",
        crate::emulator::HazardKind::OpposedDrives => "driven both ways at once",
        crate::emulator::HazardKind::Overflow => "overflowing",
        crate::emulator::HazardKind::DryRun => "with a pump running dry",
        _ => "in a dangerous state",
    };
    let text = if matches!(h.at, crate::emulator::Place::Danger { .. }) {
        format!("Without the filter, {after} ms later: {}.", h.place)
    } else {
        format!(
            "Without the filter, {after} ms later: {} {what} ({}).",
            h.place,
            h.elements.join(", ")
        )
    };
    Item {
        code: codes::X_COMPONENT_HAZARD_PREDICTED.id,
        fields: [
            ("kind".to_string(), format!("{:?}", h.kind)),
            ("place".to_string(), h.place.clone()),
            ("after_ms".to_string(), after.to_string()),
            ("elements".to_string(), h.elements.join(",")),
        ]
        .into_iter()
        .chain(h.at.fields())
        .collect(),
        text,
    }
}

fn hazard_verb(h: &Hazard) -> String {
    let kind = serde_json::to_value(h.kind)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default();
    match kind.as_str() {
        "sheared" => "would be sheared by the rotating turntable".into(),
        "dropped" => "would fall off".into(),
        "collision" => "would be pushed into another box".into(),
        "pushed_against_stopped" => "would be pushed against a stopped conveyor".into(),
        other => format!("would suffer: {other}"),
    }
}

pub mod actions;
pub mod diagnosis;
mod observed;
pub mod scenario;
pub mod workload;

pub use observed::ObservedCycle;

#[cfg(test)]
mod tests;
