//! `diagnosers.ron`: the component models (PoP) as data, and their loader.

use crate::diag::{Location, Problem, ron_problem};
use serde::{Deserialize, Serialize};
use std::path::Path;

fn default_alpha() -> f64 {
    3.0
}
fn default_margin() -> u64 {
    10
}
fn default_pulse() -> u64 {
    2000
}

/// The whole file: one model per component.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Diagnosers")]
pub struct DiagnoserFile {
    /// Confidence coefficient of the learned tolerance ΔT = α·σ (seed 003, annex B).
    #[serde(default = "default_alpha")]
    pub alpha: f64,
    /// Slack added to every window at run time (one PLC cycle: the sampling error), ms.
    #[serde(default = "default_margin")]
    pub margin_ms: u64,
    /// Longest spurious pulse a sensor fault of kind `Spurious` may produce, ms.
    #[serde(default = "default_pulse")]
    pub pulse_max_ms: u64,
    /// The component models.
    pub components: Vec<ComponentDef>,
}

/// One component (a part of the plant, PoP_i).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComponentDef {
    /// Identifier (`table`).
    pub id: String,
    /// What it is.
    #[serde(default)]
    pub description: String,
    /// The signals it observes (sensors and actuators): their edges are its events.
    pub signals: Vec<String>,
    /// The initial state.
    pub initial: String,
    /// Values of the signals in the initial state, e.g. `/A4 . C4 . /C5`: every other
    /// state's values follow from the expected evolutions.
    pub initial_values: String,
    /// The normal states.
    pub states: Vec<StateDef>,
    /// Expected evolutions; every other evolution is unexpected (generated).
    pub expected: Vec<EvolutionDef>,
    /// Time intervals since the last clock event (`RE(A4)`, `FE(A4)`).
    #[serde(default)]
    pub intervals: Vec<IntervalDef>,
    /// The clock event assumed to have happened long before the start (e.g. `FE(A4)`).
    #[serde(default)]
    pub initial_clock: Option<String>,
    /// Fault labels and the behaviour each one gives the component.
    pub faults: Vec<FaultDef>,
    /// Fault partitions: one `def_<id>` flag each.
    pub partitions: Vec<PartitionDef>,
    /// Sensor estimates from the intervals (`EST(C4) = I1 + I2 + I10`).
    #[serde(default)]
    pub estimates: Vec<EstimateDef>,
    /// The model also describes the plant under the filter's safe state (outputs forced
    /// to 0, as the monostable A4 returning the table). Otherwise the component is
    /// suspended while the filter holds the outputs and restarts from the observed
    /// values when the hold ends.
    #[serde(default)]
    pub follows_safe_state: bool,
    /// Edges of one cycle are taken sensors first, then orders (the controller reacts
    /// in the same scan to what it sees: a push ordered on the rise of C0). By default
    /// orders come first (the plant reacts to them: a rotation ordered, then the table
    /// leaves C4).
    #[serde(default)]
    pub sensors_first: bool,
    /// Sensors of other components this model takes as true (in its guards: the exits
    /// evacuate a box when C5 says the table is there). A certain decision here waits
    /// `settle_ms`, and for as long as another component has lost its normal hypothesis
    /// with a fault of its partition of one of them possible (the local anomaly may be
    /// that neighbour's fault) or has lost track of its plant.
    #[serde(default)]
    pub assumes: Vec<String>,
    /// Sensors of other components that this model takes as saying an item is there
    /// (the box C6 saw come onto the table, which the exits then evacuate). While
    /// another component has lost its normal hypothesis with a fault of one of them
    /// possible, the certain decisions of this model's sensor partitions wait (an item
    /// that never comes may be a phantom of that sensor, not a fault of this beam); its
    /// drive partitions do not (a drive that does not move an item that is there).
    #[serde(default)]
    pub assumes_item: Vec<String>,
    /// How long a certain decision waits at least for the neighbours whose sensors it
    /// `assumes`, ms: a neighbour's window on that sensor may still be open when this
    /// model sees the anomaly (C2 falls without C1 a few ms before the feed's C1
    /// window closes).
    #[serde(default)]
    pub settle_ms: u64,
    /// How long a certain decision of a sensor partition waits for the plant to
    /// confirm it, ms (None: it is issued at once). A welded actuator that moves an
    /// item the model does not follow (the entry conveyor pushing the waiting box onto
    /// the belt behind the belt's own box: two boxes, where the model follows one)
    /// reads at first like a fault of a beam; within this time the plant shows more
    /// than a beam's fault explains (the box clears C0 or reaches C3 unordered), the
    /// model loses track and claims nothing. Drive partitions do not wait.
    #[serde(default)]
    pub confirm_ms: Option<u64>,
    /// The safe side of an ambiguous fault, ms: when the component is certainly faulty
    /// but cannot tell a stopping fault that stops items (`Blocked`: a dead drive) from
    /// a fault of a sensor the cooperation cannot estimate, and is still so after this
    /// long (its longest window that could decide: a box that reaches C3 shows the
    /// belt runs and C1 was the fault), it stops the plant (the stopping partitions
    /// still possible are flagged; the journal says `ambiguous`). None: it waits for
    /// the evidence, however long.
    #[serde(default)]
    pub doubt_ms: Option<u64>,
    /// Sensors of a part that the component's blocking faults do not stop (the next box
    /// reaching C0 on the entry conveyor while the intermediate belt is stopped): a
    /// blocked plant still shows their edges where the expected evolutions foresee them.
    #[serde(default)]
    pub independent: Vec<String>,
    /// The orders a moving state expects come within its sensor edge's window (a
    /// derived axis model: the controller may stop the axis anywhere, but only before
    /// the axis shows its next edge). A copy that lost its clock (a sensor fault hid
    /// an edge) then waits for the plant's next sensor edge no longer than that
    /// window, whatever orders may also leave the state; by default an order that
    /// may leave a state lets the copy wait for ever.
    #[serde(default)]
    pub timed_orders: bool,
    /// Faults the diagnoser campaign injects for this component besides the generated
    /// ones (the four sensor faults of each sensor partition, both stuck faults of each
    /// actuator a partition lists): mechanical faults of the emulator, or a sensor
    /// fault injected only in a given situation.
    #[serde(default)]
    pub injections: Vec<InjectionDef>,
}

/// A fault the diagnoser campaign injects (`vigie campaign diagnoser`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InjectionDef {
    /// The campaign row's name.
    pub name: String,
    /// The emulator's fault (as in a scenario's `faults`).
    pub fault: crate::emulator::FaultKind,
    /// The partitions a right diagnosis may name.
    pub expected: Vec<String>,
    /// Inject only once this expression over the frame holds after the random time
    /// (`C4 . /A4 . /A4*`: the table rests at C4).
    #[serde(default)]
    pub when: Option<String>,
}

/// A normal state.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateDef {
    /// Identifier.
    pub id: String,
    /// What the component does there.
    #[serde(default)]
    pub description: String,
}

/// An expected evolution: `event` (one edge `RE(x)`/`FE(x)`, optionally and-ed with
/// conditions) from `from` to `to`, within interval `within` when given.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvolutionDef {
    /// Source state.
    pub from: String,
    /// The logical expression: exactly one edge of a component signal, and conditions.
    pub event: String,
    /// Interval of the clock in which it is expected (None: any time).
    #[serde(default)]
    pub within: Option<String>,
    /// Target state.
    pub to: String,
}

/// A bound of an interval.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Bound {
    /// A fixed time since the clock event, ms.
    Ms(u64),
    /// The lower bound of another interval.
    LoOf(String),
    /// The upper bound of another interval.
    HiOf(String),
    /// No upper bound.
    Never,
}

/// Learned statistics of an interval (written by `vigie diagnose learn`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Learned {
    /// Number of normally completed evolutions measured.
    pub samples: u64,
    /// Shortest observed time, ms.
    pub min_ms: u64,
    /// Longest observed time, ms.
    pub max_ms: u64,
    /// Mean, ms.
    pub mean_ms: f64,
    /// Population standard deviation, ms.
    pub sigma_ms: f64,
    /// α used.
    pub alpha: f64,
    /// ΔT = α·σ, ms.
    pub delta_ms: f64,
}

/// A time interval `[lo, hi[` since the clock event `after`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntervalDef {
    /// Identifier, published as an auxiliary variable (`I2`).
    pub id: String,
    /// The clock event it is measured from (`RE(A4)`).
    pub after: String,
    /// Lower bound.
    pub lo: Bound,
    /// Upper bound (exclusive).
    pub hi: Bound,
    /// What it means.
    #[serde(default)]
    pub description: String,
    /// Learned statistics, when learned.
    #[serde(default)]
    pub learned: Option<Learned>,
}

/// How a fault changes what the component shows.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Behaviour {
    /// The sensor reads this value from the fault on.
    StuckAt(String, bool),
    /// The sensor takes this value for a while, then reads the plant again.
    Spurious(String, bool),
    /// In these states the plant stops evolving (no more sensor edges).
    Blocked(Vec<String>),
    /// In state `.0` the plant moves as if the actuator edge `.1` had happened
    /// (unexpected motion); afterwards its timing is unknown.
    Moves(String, String),
    /// In state `.0` the plant starts behaving as in state `.1` (a motion reversed by
    /// a failed actuator: the table released or pushed back half-way); afterwards its
    /// timing is unknown.
    Jumps(String, String),
    /// The plant moves without its order: every expected evolution may happen without
    /// its condition (a drive stuck on, seen through guarded sensor edges).
    Unguarded,
}

/// A fault label.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultDef {
    /// Label (`F1`).
    pub id: String,
    /// What it is.
    #[serde(default)]
    pub description: String,
    /// Its behaviours (one or several).
    pub behaviours: Vec<Behaviour>,
}

/// A fault partition.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartitionDef {
    /// Identifier: the flag is `def_<id>`.
    pub id: String,
    /// Fault labels.
    pub faults: Vec<String>,
    /// The sensor the partition is about, estimated while the flag is set.
    #[serde(default)]
    pub sensor: Option<String>,
    /// A certain fault here stops the whole system (actuator partitions).
    #[serde(default)]
    pub stop: bool,
    /// The actuators whose failures (stuck off, stuck on) show as a fault of this
    /// partition: what the fault campaign expects when it injects them.
    #[serde(default)]
    pub actuators: Vec<String>,
}

/// An estimate of a sensor from the interval variables.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimateDef {
    /// The sensor.
    pub sensor: String,
    /// Expression over the interval variables of the component.
    pub expr: String,
}

impl DiagnoserFile {
    /// Parses the file text; RON errors carry file, line and column.
    pub fn from_ron(text: &str, file: &Path) -> Result<Self, Problem> {
        ron::Options::default()
            .from_str(text)
            .map_err(|e| ron_problem(file, &e))
    }

    /// Reads and parses a file.
    pub fn load(path: &Path) -> Result<Self, Problem> {
        let text = crate::diag::read_text(path)?;
        Self::from_ron(&text, path)
    }

    /// The file text (pretty RON), as `vigie diagnose learn` writes it.
    pub fn to_ron(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new().struct_names(true);
        ron::ser::to_string_pretty(self, cfg).unwrap_or_default()
    }
}

/// Where `needle` (a quoted name) first appears in `text`, for semantic errors.
pub fn locate(text: &str, file: &Path, needle: &str) -> Location {
    Location::of_nth(file, text, &format!("\"{needle}\""), 0)
}
