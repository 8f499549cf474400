//! The registry of codes: every problem code (`V…`), explanation item code (`X…`)
//! and task alarm code (`T…`) is one constant here, with its meaning, and has one
//! catalogue page, `docs/codes/<CODE>.md`, compiled into the binary.
//!
//! A code is never reused for another meaning: a new situation gets a new code. The
//! problem codes go by family:
//!
//! | range | family |
//! |---|---|
//! | V00xx | files and the plant (`plant.ron`, plausibility rules) |
//! | V01xx | constraints and invariants (`constraints.txt`, `invariants.txt`) |
//! | V02xx | observers (`observers.ron`) |
//! | V03xx | traces (CSV) |
//! | V04xx | scenarios |
//! | V05xx | `vigie verify` (V0501, V0520), diagnosers and `vigie learn` (V0502..V0514), the campaigns' production (V0515) |
//! | V06xx | the gateway: I/O map (V0601..V0610), configuration (V0619..V0628) |
//! | V07xx | the emulator: layout, faults, parts |
//! | V08xx | tasks (`tasks.ron`) |
//! | V09xx | control programs and the control-error library |
//! | V10xx | the compiled filter |
//! | V11xx | the machine's elementary actions (`actions.ron`) and their monitor |
//! | V12xx | PLCopen XML control programs (`vigie program import`, `export`) |
//! | V16xx | OPC UA: node map, security, the server's address space |
//!
//! Loaders write `Problem::error(codes::TRACE_EMPTY.id, …)`; no other source file
//! spells a `V` code (a test checks it). [`explain`] returns the page of a code.

/// One code of the registry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Code {
    /// The code as written in messages (`"V0301"`).
    pub id: &'static str,
    /// What it means, in a few words (the title of its page).
    pub meaning: &'static str,
    /// Its catalogue page, `docs/codes/<id>.md`, as Markdown.
    pub page: &'static str,
}

/// Declares one constant per code, the list [`ALL`], and embeds every page (a code
/// without a page does not compile).
macro_rules! registry {
    ($($(#[$attr:meta])* $name:ident = $id:literal, $meaning:literal;)*) => {
        $(
            #[doc = concat!("`", $id, "`: ", $meaning, ".")]
            $(#[$attr])*
            pub const $name: Code = Code {
                id: $id,
                meaning: $meaning,
                page: include_str!(concat!(
                    env!("CARGO_MANIFEST_DIR"),
                    "/../docs/codes/",
                    $id,
                    ".md"
                )),
            };
        )*

        /// Every code of the registry, problem codes first, then explanation items,
        /// then task alarms.
        pub const ALL: &[Code] = &[$($name),*];
    };
}

registry! {
    // V00xx: files and the plant
    RON_INVALID = "V0001", "invalid RON";
    FILE_UNREADABLE = "V0002", "a file cannot be read";
    FILE_TOO_LARGE = "V0003", "a file larger than 8 MiB, refused before it is read";
    SIGNAL_ID_INVALID = "V0010", "invalid signal id";
    SIGNAL_DUPLICATE = "V0011", "a signal declared twice";
    PLAUSIBLE_ON_ACTUATOR = "V0012", "a plausibility rule on an actuator";
    PLAUSIBILITY_INVALID = "V0013", "a plausibility rule that does not parse or names an unknown signal";
    PLANT_WIRING = "V0014", "`supplies`, `held_on` or `feedback_of` on the wrong kind of signal, or naming no actuator";
    // V01xx: constraints and invariants
    CONSTRAINT_SYNTAX = "V0101", "syntax error or unknown name in a constraint";
    CONSTRAINT_DUPLICATE = "V0102", "duplicate constraint id";
    CONSTRAINT_NOT_ENFORCEABLE = "V0103", "a constraint term with no output at t";
    CONSTRAINT_NEVER_TRUE = "V0104", "a constraint that can never be true";
    CONSTRAINT_ALWAYS_TRUE = "V0105", "a constraint that is always true";
    PROPERTY_6_VIOLATED = "V0106", "two constraints force an output to 0 and 1 (property (6))";
    NO_FALLBACK = "V0107", "no fallback output vector in some reachable context";
    CONSTRAINT_LINE_INVALID = "V0108", "a line that is not `ID = expression`";
    INVARIANT_READS_OUTPUT = "V0109", "an invariant reads an output at t";
    PLANT_UNPROTECTED = "V0110", "no safety constraint: the plant is unprotected";
    // V02xx: observers
    OBSERVER_READS_FORBIDDEN = "V0201", "an observer reads something other than inputs, previous outputs and auxiliaries";
    OBSERVER_EXPRESSION_INVALID = "V0202", "an observer expression that does not parse";
    OBSERVER_ID_INVALID = "V0203", "invalid observer id";
    OBSERVER_NAME_TAKEN = "V0204", "an observer with the name of another signal";
    // V03xx: traces
    TRACE_EMPTY = "V0301", "empty trace";
    TRACE_UNKNOWN_SIGNAL = "V0302", "unknown signal in a trace header";
    TRACE_NO_TIME_COLUMN = "V0303", "a trace header without `time_ms`";
    TRACE_MISSING_SIGNAL = "V0304", "a trace without a column for a plant signal";
    TRACE_ROW_WIDTH = "V0305", "a trace row with the wrong number of values";
    TRACE_TIME_INVALID = "V0306", "a trace time that is not a number of milliseconds";
    TRACE_VALUE_INVALID = "V0307", "a trace value that is not 0 or 1";
    TRACE_DUPLICATE_COLUMN = "V0330", "a column twice in a trace header";
    TRACE_TIME_BACKWARDS = "V0331", "a trace's time goes backwards or repeats";
    // V04xx: scenarios
    SCENARIO_CYCLE = "V0401", "a scenario's `cycle_ms` not from 1 to 1000 ms";
    SCENARIO_UNKNOWN_VARIANT = "V0402", "a scenario names no variant of the control-error library";
    SCENARIO_DURATION = "V0403", "a scenario's duration or projection out of range";
    SCENARIO_AFTER_END = "V0404", "a scenario event not before the end of the run";
    SCENARIO_ARRIVALS = "V0405", "a scenario's arrival period or jitter out of range";
    SCENARIO_FAULT_DURATION = "V0406", "a scenario fault or spurious pulse of zero or excessive duration";
    // V05xx: verification, diagnosers, learning
    VERIFY_UNSUPPORTED = "V0501", "a plant the abstract model of `vigie verify` does not support";
    DIAGNOSER_DUPLICATE_COMPONENT = "V0502", "duplicate diagnoser component";
    DIAGNOSER_UNKNOWN_SIGNAL = "V0503", "a diagnoser names an unknown signal, or too many";
    DIAGNOSER_UNKNOWN_STATE = "V0504", "a diagnoser names an unknown state";
    DIAGNOSER_INITIAL_VALUES = "V0505", "invalid initial values of a diagnoser component";
    DIAGNOSER_CLOCK_EVENT = "V0506", "an invalid clock event of a diagnoser interval";
    DIAGNOSER_INTERVAL = "V0507", "an invalid diagnoser interval";
    DIAGNOSER_EDGE = "V0508", "an invalid edge expression in a diagnoser evolution";
    DIAGNOSER_INCONSISTENT_VALUES = "V0509", "inconsistent signal values in a diagnoser component";
    DIAGNOSER_PARTITION_OR_INJECTION = "V0510", "an invalid diagnosis partition or campaign injection";
    DIAGNOSER_FAULT = "V0511", "an invalid diagnoser fault";
    DIAGNOSER_ESTIMATE = "V0512", "an invalid diagnoser estimate";
    DIAGNOSER_REWRITE = "V0513", "the constraints cannot be rewritten with the diagnosers";
    LEARN_WRITE_IN_PLACE = "V0514", "`vigie learn` cannot write the learned bounds into `diagnosers.ron` in place";
    CAMPAIGN_NO_PRODUCTION = "V0515", "a plant of components without a production scenario for the campaigns";
    SPIN_FAILED = "V0520", "`vigie verify --spin`: SPIN, gcc or pan could not run, or failed";
    // V06xx: the gateway's I/O map and configuration
    IO_MAP_UNREADABLE = "V0601", "the I/O map cannot be read";
    IO_MAP_NO_ADDRESS = "V0602", "a signal without an address in the plant file";
    IO_MAP_POLL = "V0603", "an I/O map poll period of 0";
    IO_MAP_BIT = "V0604", "a register bit past 15";
    IO_MAP_MAX_AGE = "V0605", "a signal's `max_age_ms` below its poll period";
    IO_MAP_SHARED_POINT = "V0606", "two signals on the same point";
    IO_MAP_ACTUATOR_READ_ONLY = "V0607", "an actuator on a read-only area";
    IO_MAP_UNKNOWN_SIGNAL = "V0608", "an I/O map entry for an unknown signal";
    IO_MAP_DUPLICATE = "V0609", "a signal mapped twice";
    IO_MAP_UNMAPPED = "V0610", "plant signals not mapped";
    GATEWAY_CONFIG_UNREADABLE = "V0619", "the gateway configuration cannot be read";
    GATEWAY_CYCLE = "V0620", "a gateway `cycle_ms` of 0";
    GATEWAY_LINK_TIMEOUT = "V0621", "a gateway `link_timeout_cycles` of 0";
    GATEWAY_NO_CLIENT = "V0622", "a gateway mode that needs a `client` section without one";
    GATEWAY_NO_SERVER = "V0623", "a gateway mode that needs a `server` section without one";
    GATEWAY_PLC_NOT_ALLOWED = "V0624", "a PLC address outside the allow-list";
    GATEWAY_PRIORITY = "V0625", "a gateway `cycle_priority` outside 1..99";
    GATEWAY_UNIT_ID = "V0626", "a Modbus unit id outside 1..247";
    GATEWAY_MAX_CONNECTIONS = "V0627", "a gateway `max_connections` of 0";
    GATEWAY_IDLE_TIMEOUT = "V0628", "a gateway idle timeout not longer than the link timeout";
    // V07xx: the emulator (formerly V0301..V0305 in these files)
    LAYOUT_INVALID = "V0701", "an invalid layout value";
    LAYOUT_UNKNOWN_SIGNAL = "V0702", "a layout names a signal the plant does not declare";
    FAULT_UNKNOWN_SIGNAL = "V0703", "an emulator fault names an unknown sensor or actuator";
    FAULT_CONDITION_INVALID = "V0704", "an emulator fault condition that does not parse";
    EMULATOR_UNKNOWN_PART = "V0705", "no such part in the layout";
    EXERCISE_DUPLICATE = "V0706", "a plant-fault exercise declared twice";
    EXERCISE_ANSWER = "V0707", "a plant-fault exercise without an answer, or one that names no plant signal";
    COMPONENTS_INVALID = "V0740", "an invalid value in a plant's components file";
    COMPONENTS_UNKNOWN_SIGNAL = "V0741", "a component names a signal the plant does not declare";
    COMPONENTS_EXPRESSION = "V0742", "a component's drive or danger expression that does not resolve";
    COMPONENTS_DUPLICATE = "V0743", "a component declared twice, or a sensor read from two components";
    NO_PHYSICAL_MODEL = "V0744", "a plant folder with neither `components.ron` nor `layout.ron`";
    FAULT_UNKNOWN_COMPONENT = "V0745", "an emulator fault names a component the plant does not have";
    ACTION_NOT_ALLOWED = "V0746", "a declared elementary action the components do not allow, or a window outside theirs";
    SAFE_STATE_HAZARD = "V0747", "the plant's safe state drives a component into a hazard";
    ENTRY_UNSEEN = "V0748", "a conveyor's feeder can place an item onto one its entry beams do not see";
    // V08xx: tasks (formerly V0301..V0307, V0310)
    TASK_ID_INVALID = "V0801", "invalid task id";
    TASK_DUPLICATE = "V0802", "a task declared twice";
    TASK_ALPHA_BEYOND_BETA = "V0803", "a task's α greater than β";
    TASK_BETA_NOT_BELOW_GAMMA = "V0804", "a task's β not less than γ";
    TASK_INTERRUPT_RESUME = "V0805", "a task with `interrupt` but no `resume`, or the reverse";
    TASK_WINDOW_EMPTY = "V0806", "a controller window with min greater than max";
    TASK_CROSS_INVALID = "V0807", "an invalid cross-task constraint";
    TASK_EVENT_INVALID = "V0810", "a task event that does not parse";
    // V09xx: control programs and the control-error library (formerly V0301..V0321)
    PROGRAM_NAME_INVALID = "V0901", "an invalid name in a control program";
    PROGRAM_NAME_TAKEN = "V0902", "a control program name already taken";
    PROGRAM_CHART_DUPLICATE = "V0903", "a chart declared twice";
    PROGRAM_NO_INITIAL_STEP = "V0904", "a chart without an initial step";
    PROGRAM_TIMER_UNKNOWN_STEP = "V0905", "a timer on an unknown step";
    PROGRAM_ACTION_TARGET = "V0906", "a step action on something that is not an actuator or a memory";
    PROGRAM_EXPRESSION_INVALID = "V0907", "a control program expression that does not parse";
    PROGRAM_READS_OBSERVER = "V0908", "a control program reads an observer";
    PROGRAM_TRANSITION_ID_TAKEN = "V0909", "a transition id used twice";
    PROGRAM_TRANSITION_NO_STEP = "V0910", "a transition without source or target step";
    PROGRAM_TRANSITION_OTHER_CHART = "V0911", "a transition linking a step of another chart";
    PROGRAM_TRANSITION_UNKNOWN_STEP = "V0912", "a transition linking an unknown step";
    PROGRAM_EQUATION_TARGET = "V0913", "an equation on something that is not an actuator or a memory";
    PROGRAM_EQUATION_TWICE = "V0914", "two equations for one target";
    PROGRAM_BUTTON_NOT_ON_PANEL = "V0915", "a start or stop button not on the panel";
    LIBRARY_VARIANT_DUPLICATE = "V0920", "a control-error variant declared twice";
    LIBRARY_VARIANT_INVALID = "V0921", "a control-error variant that cannot be built";
    // V10xx: the compiled filter (formerly V0601)
    DTREE_SUPPORT_TOO_LARGE = "V1001", "constraints reading more than 64 variables cannot be compiled";
    // V11xx: the machine's elementary actions (seed 003, part II)
    MACHINE_ACTION_ID_INVALID = "V1101", "invalid elementary action id";
    MACHINE_ACTION_DUPLICATE = "V1102", "an elementary action declared twice";
    MACHINE_ACTION_TIMING = "V1103", "an elementary action with ΔT = 0 or T not greater than ΔT";
    MACHINE_ACTION_EXPRESSION = "V1104", "an elementary action expression that does not parse or is not a level at t";
    MACHINE_ACTION_UNKNOWN_SIGNAL = "V1105", "an elementary action names an unknown signal";
    MACHINE_ACTION_WRONG_SPACE = "V1106", "an action state reading an output, or a command reading an input";
    MACHINE_ACTION_NOT_ELEMENTARY = "V1107", "an action the decomposition rules cannot make elementary";
    MACHINE_ACTIONS_MERGED = "V1108", "actions merged into one with several final states: safety is reduced";
    MACHINE_CYCLE_TOO_LONG = "V1109", "the monitor's cycle too long for an action's timing (T_D < ΔT_min, (II.4))";
    // V12xx: PLCopen XML programs (import and export)
    PLCOPEN_XML_INVALID = "V1201", "a PLCopen file that is not well-formed XML or not a TC6 project";
    PLCOPEN_UNSUPPORTED = "V1202", "a PLCopen construct that Vigie does not run";
    PLCOPEN_ST_INVALID = "V1203", "Structured Text that does not parse";
    PLCOPEN_UNKNOWN_NAME = "V1204", "a name that the PLCopen program does not declare";
    PLCOPEN_BINDING = "V1205", "a PLCopen variable that cannot be bound to the plant";
    PLCOPEN_SFC_GRAPH = "V1206", "a malformed SFC or LD network";
    PLCOPEN_EXPORT = "V1207", "a program that cannot be written as PLCopen XML";
    // V13xx: fieldbus timing (`bus.ron`)
    BUS_INVALID = "V1301", "a bus file with an impossible bit rate, turnaround, period or phase";
    BUS_OVERLOAD = "V1302", "a µC whose periodic transactions do not fit in it";
    BUS_LOAD_HIGH = "V1303", "a µC loaded above the bus's limit";
    BUS_PERIOD_DEADLINE = "V1304", "a variable polled less often than its deadline divided by r";
    BUS_DEADLINE = "V1305", "a variable delivering plant inputs whose deadline the bus cannot keep";
    // V14xx: stochastic timed Petri nets (`vigie stpn`)
    STPN_INVALID = "V1401", "a stochastic Petri net naming an unknown place or with delay probabilities that do not sum to 1";
    // V15xx: stopwatch automata and their synthesis (`vigie synthesize`)
    SWA_INVALID = "V1501", "a stopwatch automaton naming an unknown clock or location, or with a constraint that does not parse";
    SWA_LIMIT = "V1502", "a synthesis that did not converge within its iteration limit";
    REGIONS_STALE = "V1503", "a regions file synthesised from other tasks than the ones it is run with";
    TASK_CROSS_BESIDE_REGIONS = "V1504", "a cross-task constraint not run, the tasks running their synthesised regions";
    SFC_EXPORT = "V1505", "a region monitor that cannot be written as an SFC program (`vigie export-sfc`)";
    // V16xx: OPC UA (node map, security, the server's address space)
    OPCUA_NODE_INVALID = "V1601", "an OPC UA node id or browse path that does not parse";
    OPCUA_NODE_SHARED = "V1602", "two signals on the same OPC UA node";
    OPCUA_NODE_UNKNOWN = "V1603", "an OPC UA node the server does not have, or not a Boolean";
    OPCUA_SECURITY_NONE = "V1604", "an OPC UA endpoint without security";
    OPCUA_CONFIG = "V1605", "an OPC UA section with an impossible security, user or certificate setting";
    // X: explanation items (`core/src/explain/codes.md` lists their fields)
    X_FILTER_STOPPED = "X001", "the safety filter stopped the plant";
    X_ACTUATOR_KEPT_ON = "X002", "an actuator kept ON after the stop";
    X_ACTUATORS_STOPPED = "X003", "the actuators stopped";
    X_OFF_MEANING = "X004", "what an actuator OFF does";
    X_OBSERVER_SET = "X005", "an observer is set";
    X_FILTER_WOULD_STOP = "X006", "monitor mode: the filter would have stopped the plant";
    X_FILTER_WOULD_APPLY = "X007", "monitor mode: what the filter would have applied";
    X_HAZARD_PREDICTED = "X101", "without the filter, a hazard is predicted";
    X_NO_DAMAGE_PREDICTED = "X102", "without the filter, no damage is predicted";
    X_NO_DAMAGE_PREDICTED_MONITOR = "X103", "monitor mode: no damage is predicted as the plant runs on";
    X_COMPONENT_HAZARD_PREDICTED = "X104", "without the filter, a component's hazard is predicted";
    X_CONSTRAINT_BECAME_TRUE = "X201", "a constraint became true";
    X_HELD_ON = "X202", "the filter held an actuator ON";
    X_FORCED_OFF = "X203", "the filter forced an actuator OFF";
    X_LAST_CHANGE = "X301", "the last change of a signal";
    X_STAYS_ON = "X302", "an actuator commanded ON stays ON";
    X_SENSOR_CHANGED_NO_EVOLUTION = "X401", "a sensor of the constraint changed and the control did not follow";
    X_SENSOR_OUTSIDE_CHANGED = "X402", "a sensor outside the constraint changed with an actuator of it";
    X_EXPECTED_ACTION = "X403", "the expected action of the control";
    X_ACTUATOR_CHANGED_NO_INPUT = "X404", "an actuator changed while no input changed";
    X_OBSERVER_CHANGE = "X405", "the constraint became true through an observer change";
    X_NO_RECORDED_CYCLES = "X406", "no recorded cycles before the stop: no hypothesis";
    X_TRANSITION_DEACTIVATED_STEP = "X407", "a transition deactivated the step that held the actuator";
    X_TRANSITION_ACTIVATED_STEP = "X408", "a transition activated a step driving the forbidden value";
    X_QUALIFIER = "X409", "a step action's qualifier makes the difference";
    X_EQUATION_FORBIDDEN_VALUE = "X410", "an output equation commands the forbidden value";
    X_NOTHING_COMMANDS = "X411", "nothing in the program commands the actuator";
    X_STEP_NOT_LEFT = "X412", "a step drives the forbidden value and its transitions did not fire";
    X_COMBINED_MISSING = "X413", "combined constraint: one actuator driven, the other commanded by nothing";
    X_SUSPECT_SENSOR = "X414", "a sensor of the fired term is suspect";
    X_HARDWARE_CERTAIN = "X415", "hardware first: a diagnoser found a fault with certainty";
    X_HARDWARE_AMBIGUOUS = "X416", "hardware first: a diagnoser holds a component faulty between several faults";
    X_MISPLACED_ACTION = "X417", "a step's action drives the actuator where the step's place in its chart forbids it";
    X_UNEXPECTED_EDGE = "X418", "a sensor of the fired term changed where the plant's physics did not expect it";
    X_CONTACTOR_DISAGREES = "X419", "hardware first: a mirror contact of the fired term disagrees with its output (welded or dead)";
    X_SOURCE_PLACE = "X420", "where a suspected program element is in the PLCopen file it was imported from";
    // T: task alarms (`tasks::explain::AlarmCode`)
    T_TOLERANCE_USED_UP = "T001", "interruption tolerance used up: the task can no longer finish before γ";
    T_SLOWDOWN = "T002", "slowdown: effective running time beyond β without the end event";
    T_WATCHDOG = "T003", "total time reached γ (the watchdog bound)";
    T_ENDED_TOO_EARLY = "T004", "ended too early (below α)";
    T_ENDED_OUTSIDE_WINDOW = "T005", "ended outside the acceptable window (x ≥ γ or y beyond β)";
    T_CONTROLLER_WINDOW = "T006", "controller timing window violated";
    T_UNEXPECTED_EVENT = "T007", "unexpected event for the task's state";
    T_CROSS_TASK = "T008", "cross-task constraint of the coordinator violated";
    T_REGION_LEFT = "T009", "synthesised region left: with the other tasks, it can no longer finish in time";
}

/// The registry entry of `code` (`"V0301"`, `"x001"`: case and surrounding spaces do
/// not matter), `None` for a code the registry does not know.
pub fn lookup(code: &str) -> Option<Code> {
    let code = code.trim();
    ALL.iter()
        .copied()
        .find(|c| c.id.eq_ignore_ascii_case(code))
}

/// The catalogue page of `code` (Markdown, from `docs/codes/<CODE>.md`, compiled in:
/// the binary needs no repository), `None` for an unknown code. This is what
/// `vigie explain CODE` prints.
pub fn explain(code: &str) -> Option<&'static str> {
    lookup(code).map(|c| c.page)
}

#[cfg(test)]
mod tests;
