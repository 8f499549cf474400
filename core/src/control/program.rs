//! The program format (`programs/*.ron`) and its compilation against a plant.

use super::packed::{Cond, Conds, Layout};
use crate::diag::codes;
use crate::diag::line_col;
use crate::diag::{Location, Problem, ron_problem};
use crate::expr::{self, Dnf, Span};
use crate::plant::{Plant, is_valid_name};
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// How a step action drives its target (IEC 60848 / 61131-3 qualifiers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Qualifier {
    /// Non-stored: true while the step is active.
    N,
    /// Set (stored): the target stays true after the step, until an `R` action.
    S,
    /// Reset of a stored target; reset wins over set in the same scan.
    R,
    /// Time-limited: true while the step is active and for at most this many ms.
    L(u64),
    /// Delayed: true while the step has been active for at least this many ms.
    D(u64),
    /// Pulse: true during the single scan in which the step is activated.
    P,
    /// Stored and delayed: the step's activation starts the time; once it has run, the
    /// target is set (stored) even if the step ended meanwhile, until an `R` (which also
    /// cancels a time running).
    SD(u64),
    /// Delayed and stored: set (stored) if the step is still active when the time has
    /// run, until an `R`.
    DS(u64),
    /// Stored and limited: true from the step's activation for the time, even if the
    /// step ends meanwhile, unless an `R` ends it sooner.
    SL(u64),
}

impl Qualifier {
    /// True for the qualifiers whose value depends on time (L, D, SD, DS, SL).
    pub fn is_timed(self) -> bool {
        matches!(
            self,
            Self::L(_) | Self::D(_) | Self::SD(_) | Self::DS(_) | Self::SL(_)
        )
    }
}

impl std::fmt::Display for Qualifier {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Qualifier::N => f.write_str("N"),
            Qualifier::S => f.write_str("S"),
            Qualifier::R => f.write_str("R"),
            Qualifier::L(ms) => write!(f, "L({ms})"),
            Qualifier::D(ms) => write!(f, "D({ms})"),
            Qualifier::P => f.write_str("P"),
            Qualifier::SD(ms) => write!(f, "SD({ms})"),
            Qualifier::DS(ms) => write!(f, "DS({ms})"),
            Qualifier::SL(ms) => write!(f, "SL({ms})"),
        }
    }
}

/// One action of a step: drives an output or a memory.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Action {
    /// How.
    pub qualifier: Qualifier,
    /// An actuator (`A4`) or a memory of the program.
    pub target: String,
}

/// One GRAFCET step.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Step {
    /// Identifier, unique in the program; also the name of the step variable (`X24`).
    pub id: String,
    /// Active in the initial situation.
    #[serde(default)]
    pub initial: bool,
    /// Actions associated with the step.
    #[serde(default)]
    pub actions: Vec<Action>,
}

/// Which standard timer (IEC 61131-3) a [`Delay`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DelayKind {
    /// `TON`: Q rises when IN has been true for the time, falls with IN.
    On,
    /// `TOF`: Q is true while IN is, and for the time after IN falls.
    Off,
    /// `TP`: a rising edge of IN, when no pulse runs, starts a pulse of the time.
    Pulse,
}

/// A standard timer on an expression: the equation whose target is `id` is its input
/// IN, evaluated in the equations' order; `id` reads its output Q (the last scan's
/// before that equation).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Delay {
    /// Name, also the name of its output.
    pub id: String,
    /// TON, TOF or TP.
    pub kind: DelayKind,
    /// Its time PT, in ms.
    pub ms: u64,
}

/// Which standard counter (IEC 61131-3) a [`Counter`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum CounterKind {
    /// `CTU`: a rising edge of CU adds one to CV (up to 32767), R sets CV to 0; Q is
    /// CV >= PV.
    Up,
    /// `CTD`: a rising edge of CD takes one from CV (down to -32768), LD sets CV to PV;
    /// Q is CV <= 0.
    Down,
}

/// A standard counter: the equation whose target is `id` is its count input (CU or
/// CD), `reset` its R (CTU) or LD (CTD), both evaluated there in the equations' order;
/// `id` reads its output Q (the last scan's before that equation). CV starts at 0.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Counter {
    /// Name, also the name of its output.
    pub id: String,
    /// CTU or CTD.
    pub kind: CounterKind,
    /// PV.
    pub preset: i16,
    /// R or LD, an expression.
    pub reset: String,
}

/// One GRAFCET transition.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transition {
    /// Identifier, unique in the program.
    pub id: String,
    /// Upstream steps (all must be active for the transition to be enabled).
    pub from: Vec<String>,
    /// Downstream steps, activated when it fires.
    pub to: Vec<String>,
    /// The receptivity, in the logic notation of [`crate::expr`].
    pub condition: String,
}

/// One chart (a GRAFCET / SFC).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Chart {
    /// Name, unique in the program.
    pub name: String,
    /// Steps.
    pub steps: Vec<Step>,
    /// Transitions between steps of this chart.
    pub transitions: Vec<Transition>,
}

/// A control program as written in `programs/*.ron`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Program {
    /// Display name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Operator buttons and switches (`START`, `STOP`, `BY_SIZE`).
    #[serde(default)]
    pub panel: Vec<String>,
    /// The panel button the console's Start presses (one of `panel`); none: the
    /// console's Start is refused with a message.
    #[serde(default)]
    pub start: Option<String>,
    /// The panel button the console's Stop presses (one of `panel`).
    #[serde(default)]
    pub stop: Option<String>,
    /// Internal memories (set by `S`/`R` actions or by equations).
    #[serde(default)]
    pub memories: Vec<String>,
    /// Step timers `(id, step, ms)`: `id` is true while `step` has been active ≥ `ms`.
    #[serde(default)]
    pub timers: Vec<(String, String, u64)>,
    /// Outputs and memories true before the first scan (an IEC variable's initial
    /// value TRUE): their previous value at the first scan, and the stored value of the
    /// targets of `S` and `R` actions.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub initial: Vec<String>,
    /// Standard timers on expressions (TON, TOF, TP; see [`Delay`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub delays: Vec<Delay>,
    /// Standard counters (CTU, CTD; see [`Counter`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub counters: Vec<Counter>,
    /// GRAFCET charts.
    pub charts: Vec<Chart>,
    /// Ladder-like equations `(target, expression)`, evaluated top-down after the
    /// actions; a target is the OR of its actions and its equation.
    #[serde(default)]
    pub equations: Vec<(String, String)>,
    /// Where each element of a program imported from PLCopen XML is in its file (by
    /// step, transition or written variable): the hypothesis names them. Not part of
    /// the RON format nor of the version (a program's behaviour, not its layout).
    #[serde(skip)]
    pub places: BTreeMap<String, Vec<SourcePlace>>,
}

/// The place of a program element in the PLCopen file it was imported from.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub struct SourcePlace {
    /// The file's name.
    pub file: String,
    /// The POU.
    pub pou: String,
    /// What the element is there: `step`, `transition`, or the language of the body
    /// that writes a variable (`ST`, `LD`, `FBD`).
    pub kind: String,
    /// 1-based line and column in the file.
    pub line: usize,
    /// See `line`.
    pub column: usize,
}

impl Program {
    /// The program's version: the first 12 hex digits of the BLAKE2s hash of its
    /// canonical RON text. Two programs with the same steps, transitions, actions and
    /// equations have the same version; any edit changes it. The console, the fix
    /// check and the incident report name the program they ran by it.
    pub fn version(&self) -> String {
        use blake2::{Blake2s256, Digest};
        use std::fmt::Write as _;
        let text = ron::to_string(self).unwrap_or_default();
        let hash = Blake2s256::digest(text.as_bytes());
        hash.iter().take(6).fold(String::new(), |mut out, b| {
            let _ = write!(out, "{b:02x}");
            out
        })
    }

    /// Parses program text; `file` is used in messages only.
    pub fn from_ron(text: &str, file: &Path) -> Result<Self, Vec<Problem>> {
        ron::from_str(text).map_err(|e| vec![ron_problem(file, &e)])
    }

    /// Every step of every chart with its chart name.
    pub fn steps(&self) -> impl Iterator<Item = (&str, &Step)> {
        self.charts
            .iter()
            .flat_map(|c| c.steps.iter().map(move |s| (c.name.as_str(), s)))
    }

    /// Every transition of every chart with its chart name.
    pub fn transitions(&self) -> impl Iterator<Item = (&str, &Transition)> {
        self.charts
            .iter()
            .flat_map(|c| c.transitions.iter().map(move |t| (c.name.as_str(), t)))
    }
}

/// Where a program came from, to place problems in its file.
#[derive(Clone, Debug, Default)]
pub struct Origin {
    /// The file, as given to the loader.
    pub file: PathBuf,
    /// Its text (empty when the program was built in code).
    pub text: String,
}

impl Origin {
    /// An origin for a file and its text.
    pub fn new(file: &Path, text: &str) -> Self {
        Self {
            file: file.to_path_buf(),
            text: text.to_string(),
        }
    }

    fn location(&self, offset: Option<usize>) -> Location {
        match offset {
            Some(off) => {
                let (line, column) = line_col(&self.text, off);
                Location::new(&self.file, line, column)
            }
            None => Location::new(&self.file, 1, 1),
        }
    }

    /// Byte offset of the string literal `"id"` written after `id:`.
    fn find_id(&self, id: &str) -> Option<usize> {
        let needle = format!("\"{id}\"");
        let mut from = 0;
        while let Some(pos) = self.text.get(from..).and_then(|t| t.find(&needle)) {
            let at = from + pos;
            if self.text[..at].trim_end().ends_with("id:") {
                return Some(at);
            }
            from = at + needle.len();
        }
        None
    }

    /// Byte offset of the first string literal `"name"`, optionally after `after`.
    fn find_quoted(&self, name: &str, after: usize) -> Option<usize> {
        let needle = format!("\"{name}\"");
        self.text.get(after..)?.find(&needle).map(|p| p + after)
    }

    /// Byte offset of the first character of a transition's condition text.
    fn condition_start(&self, transition: &str) -> Option<usize> {
        let at = self.find_id(transition)?;
        let rest = self.text.get(at..)?;
        let key = rest.find("condition")?;
        let quote = rest.get(key..)?.find('"')?;
        Some(at + key + quote + 1)
    }

    /// Byte offset of the first character of an equation's expression text.
    fn equation_start(&self, target: &str) -> Option<usize> {
        let eqs = self.text.find("equations")?;
        let needle = format!("\"{target}\"");
        let mut from = eqs;
        while let Some(pos) = self.text.get(from..).and_then(|t| t.find(&needle)) {
            let at = from + pos;
            if self.text[..at].trim_end().ends_with('(') {
                let rest = self.text.get(at + needle.len()..)?;
                let quote = rest.find('"')?;
                return Some(at + needle.len() + quote + 1);
            }
            from = at + needle.len();
        }
        None
    }
}

/// What an action or an equation drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Target {
    /// An actuator, by output number.
    Output(u32),
    /// A memory, by memory number (its variable is `memory_aux[m]` in the Aux space).
    Memory(u32),
}

/// A compiled step.
#[derive(Clone, Debug)]
pub(crate) struct StepInfo {
    pub(crate) id: String,
    pub(crate) chart: usize,
    pub(crate) initial: bool,
    pub(crate) aux: u32,
}

/// A compiled transition.
#[derive(Clone, Debug)]
pub(crate) struct TransitionInfo {
    pub(crate) id: String,
    pub(crate) from: Vec<u16>,
    pub(crate) to: Vec<u16>,
    pub(crate) condition: Dnf,
    pub(crate) cond: Cond,
    pub(crate) enable: Cond,
}

/// A compiled action.
#[derive(Clone, Debug)]
pub(crate) struct ActionInfo {
    pub(crate) step: u16,
    pub(crate) qualifier: Qualifier,
    /// Index in the combined target space: outputs, then memories.
    pub(crate) slot: usize,
}

/// A compiled timer.
#[derive(Clone, Debug)]
pub(crate) struct TimerInfo {
    pub(crate) step: u16,
    pub(crate) ms: u64,
    pub(crate) aux: u32,
}

/// A compiled standard timer.
#[derive(Clone, Debug)]
pub(crate) struct DelayInfo {
    pub(crate) kind: DelayKind,
    pub(crate) ms: u64,
    pub(crate) aux: u32,
}

/// A compiled standard counter.
#[derive(Clone, Debug)]
pub(crate) struct CounterInfo {
    pub(crate) kind: CounterKind,
    pub(crate) preset: i16,
    pub(crate) aux: u32,
}

/// A compiled equation.
#[derive(Clone, Debug)]
pub(crate) struct EquationInfo {
    pub(crate) slot: usize,
    /// Its place in the program's `equations` (a counter's reset: its count input's).
    pub(crate) index: usize,
    pub(crate) dnf: Dnf,
    pub(crate) cond: Cond,
}

/// A program resolved against a plant: names are variables, expressions sums of products.
#[derive(Clone, Debug)]
pub struct CompiledProgram {
    /// The source program.
    pub program: Program,
    /// The program-local name table: plant inputs and outputs, then (Aux) steps,
    /// memories, timers and panel inputs.
    pub symbols: Symbols,
    pub(crate) n_outputs: usize,
    pub(crate) steps: Vec<StepInfo>,
    pub(crate) transitions: Vec<TransitionInfo>,
    pub(crate) actions: Vec<ActionInfo>,
    pub(crate) timers: Vec<TimerInfo>,
    pub(crate) delays: Vec<DelayInfo>,
    pub(crate) counters: Vec<CounterInfo>,
    /// Slots (outputs, then memories) true before the first scan.
    pub(crate) initial: Vec<usize>,
    pub(crate) memory_aux: Vec<u32>,
    pub(crate) panel_aux: Vec<u32>,
    pub(crate) equations: Vec<EquationInfo>,
    pub(crate) layout: Layout,
    pub(crate) conds: Conds,
}

/// Largest number of steps or transitions of a program (indices are `u16`).
pub const MAX_ELEMENTS: usize = 60_000;

impl CompiledProgram {
    /// Compiles `program` for `plant`. Every problem found is returned, placed in
    /// `origin` (the element's id or the expression column when the text is known).
    pub fn new(program: &Program, plant: &Plant, origin: &Origin) -> Result<Self, Vec<Problem>> {
        let mut problems = Vec::new();
        let mut symbols = plant.symbols();
        let n_outputs = plant.outputs.len();

        // Declarations: steps, memories, timers, panel.
        let (step_index, steps) = declare_steps(program, origin, &mut problems, &mut symbols);
        let Others {
            memory_aux,
            memory_index,
            timers,
            panel_aux,
        } = declare_others(program, origin, &step_index, &mut problems, &mut symbols);
        let (delays, delay_index) = declare_delays(program, origin, &mut problems, &mut symbols);
        let (counters, counter_index) =
            declare_counters(program, origin, &mut problems, &mut symbols);

        let target_slot = |name: &str| -> Option<usize> {
            if let Some(o) = plant.output(name) {
                return Some(o);
            }
            memory_index.get(name).map(|&m| n_outputs + m as usize)
        };
        // An equation may also give a standard timer its input.
        let n_memories = memory_aux.len();
        // Then a standard counter its count input (CU, CD), after its reset (R, LD).
        let n_delays = delays.len();
        let n_counters = counters.len();
        let equation_slot = |name: &str| -> Option<usize> {
            target_slot(name)
                .or_else(|| delay_index.get(name).map(|&d| n_outputs + n_memories + d))
                .or_else(|| {
                    counter_index
                        .get(name)
                        .map(|&c| n_outputs + n_memories + n_delays + c)
                })
        };

        let actions = compile_actions(program, origin, &step_index, &target_slot, &mut problems);
        let initial = resolve_initial(program, origin, &target_slot, &mut problems);

        // Expressions.
        let compile_expr =
            |text: &str, start: Option<usize>, what: &str, problems: &mut Vec<Problem>| {
                compile_expr(origin, &symbols, text, start, what, problems)
            };
        let mut transitions = compile_transitions(
            program,
            origin,
            &symbols,
            &step_index,
            &steps,
            &mut problems,
        );
        let mut equations = compile_equations(
            program,
            origin,
            &equation_slot,
            (
                &counter_index,
                n_outputs + n_memories + n_delays + n_counters,
            ),
            &compile_expr,
            &mut problems,
        );
        if !problems.is_empty() {
            return Err(problems);
        }
        let layout = Layout::new(symbols.sizes());
        let conds = link_conds(&mut transitions, &mut equations, &steps, &layout);
        Ok(Self {
            layout,
            conds,
            program: program.clone(),
            symbols,
            n_outputs,
            steps,
            transitions,
            actions,
            timers,
            delays,
            counters,
            initial,
            memory_aux,
            panel_aux,
            equations,
        })
    }

    /// Loads and compiles a program file.
    pub fn load(path: &Path, plant: &Plant) -> Result<Self, Vec<Problem>> {
        let text = crate::diag::read_text(path).map_err(|p| vec![p])?;
        if crate::plcopen::is_plcopen(path) {
            let program = crate::plcopen::import(&text, path, plant)?;
            return Self::new(&program, plant, &Origin::new(path, ""));
        }
        let program = Program::from_ron(&text, path)?;
        Self::new(&program, plant, &Origin::new(path, &text))
    }

    /// Number of steps.
    pub fn step_count(&self) -> usize {
        self.steps.len()
    }

    /// Number of transitions.
    pub fn transition_count(&self) -> usize {
        self.transitions.len()
    }

    /// The target slot of an output or a memory name.
    pub(crate) fn slot_name(&self, slot: usize) -> &str {
        if slot < self.n_outputs {
            self.symbols
                .name(Space::Output, u32::try_from(slot).unwrap_or(u32::MAX))
        } else {
            let m = slot - self.n_outputs;
            self.memory_aux
                .get(m)
                .map_or("?", |&aux| self.symbols.name(Space::Aux, aux))
        }
    }
}

/// Declares an auxiliary variable for a step, memory, timer or panel input; reports a
/// bad or taken name.
fn declare(
    name: &str,
    what: &str,
    loc: Option<Location>,
    problems: &mut Vec<Problem>,
    symbols: &mut Symbols,
) -> Option<u32> {
    if !is_valid_name(name) {
        problems.push(Problem::error(
            codes::PROGRAM_NAME_INVALID.id,
            format!("{what} `{name}`: names are letters, digits and `_`"),
            loc,
        ));
        return None;
    }
    match symbols.declare(name, Space::Aux) {
        Ok(i) => Some(i),
        Err((space, _)) => {
            let other = if space == Space::Aux {
                "another step, memory, timer or panel input"
            } else {
                "a plant signal"
            };
            problems.push(Problem::error(
                codes::PROGRAM_NAME_TAKEN.id,
                format!("{what} `{name}` has the name of {other}"),
                loc,
            ));
            None
        }
    }
}

/// Declares the charts' steps, checking chart names and initial steps.
fn declare_steps(
    program: &Program,
    origin: &Origin,
    problems: &mut Vec<Problem>,
    symbols: &mut Symbols,
) -> (BTreeMap<String, u16>, Vec<StepInfo>) {
    let at_id = |id: &str| Some(origin.location(origin.find_id(id)));
    let mut step_index: BTreeMap<String, u16> = BTreeMap::new();
    let mut steps = Vec::new();
    let mut chart_names = BTreeMap::new();
    for (ci, chart) in program.charts.iter().enumerate() {
        if chart_names.insert(chart.name.clone(), ci).is_some() {
            problems.push(Problem::error(
                codes::PROGRAM_CHART_DUPLICATE.id,
                format!("chart `{}` is declared twice", chart.name),
                Some(origin.location(origin.find_quoted(&chart.name, 0))),
            ));
        }
        if !chart.steps.iter().any(|s| s.initial) {
            problems.push(Problem::error(
                codes::PROGRAM_NO_INITIAL_STEP.id,
                format!("chart `{}` has no initial step", chart.name),
                Some(origin.location(origin.find_quoted(&chart.name, 0))),
            ));
        }
        for step in &chart.steps {
            if let Some(aux) = declare(
                &step.id,
                &format!("chart `{}`: step", chart.name),
                at_id(&step.id),
                problems,
                symbols,
            ) {
                if steps.len() >= MAX_ELEMENTS {
                    continue;
                }
                step_index.insert(
                    step.id.clone(),
                    u16::try_from(steps.len()).unwrap_or(u16::MAX),
                );
                steps.push(StepInfo {
                    id: step.id.clone(),
                    chart: ci,
                    initial: step.initial,
                    aux,
                });
            }
        }
    }
    (step_index, steps)
}

/// The memories, timers and panel inputs of a program, declared.
struct Others {
    memory_aux: Vec<u32>,
    memory_index: BTreeMap<String, u32>,
    timers: Vec<TimerInfo>,
    panel_aux: Vec<u32>,
}

/// The step actions, each on an actuator or a memory.
fn compile_actions(
    program: &Program,
    origin: &Origin,
    step_index: &BTreeMap<String, u16>,
    target_slot: &dyn Fn(&str) -> Option<usize>,
    problems: &mut Vec<Problem>,
) -> Vec<ActionInfo> {
    let at_id = |id: &str| Some(origin.location(origin.find_id(id)));
    let mut actions = Vec::new();
    for (chart, step) in program.steps() {
        let Some(&si) = step_index.get(&step.id) else {
            continue;
        };
        for a in &step.actions {
            match target_slot(&a.target) {
                Some(slot) => actions.push(ActionInfo {
                    step: si,
                    qualifier: a.qualifier,
                    slot,
                }),
                None => problems.push(Problem::error(
                    codes::PROGRAM_ACTION_TARGET.id,
                    format!(
                        "chart `{chart}`, step `{}`: action target `{}` is neither an actuator nor a memory",
                        step.id, a.target
                    ),
                    at_id(&step.id),
                )),
            }
        }
    }
    actions
}

/// The slots of the outputs and memories true before the first scan.
fn resolve_initial(
    program: &Program,
    origin: &Origin,
    target_slot: &dyn Fn(&str) -> Option<usize>,
    problems: &mut Vec<Problem>,
) -> Vec<usize> {
    let mut out = Vec::new();
    for name in &program.initial {
        match target_slot(name) {
            Some(slot) => out.push(slot),
            None => problems.push(Problem::error(
                codes::PROGRAM_EQUATION_TARGET.id,
                format!("initial value of `{name}`: neither an actuator nor a memory"),
                Some(origin.location(origin.find_quoted(name, 0))),
            )),
        }
    }
    out
}

/// Declares the standard timers on expressions; their index by name.
fn declare_delays(
    program: &Program,
    origin: &Origin,
    problems: &mut Vec<Problem>,
    symbols: &mut Symbols,
) -> (Vec<DelayInfo>, BTreeMap<String, usize>) {
    let mut delays = Vec::new();
    let mut index = BTreeMap::new();
    for d in &program.delays {
        let loc = Some(origin.location(origin.find_quoted(&d.id, 0)));
        if let Some(aux) = declare(&d.id, "timer", loc, problems, symbols) {
            index.insert(d.id.clone(), delays.len());
            delays.push(DelayInfo {
                kind: d.kind,
                ms: d.ms,
                aux,
            });
        }
    }
    (delays, index)
}

/// Compiles an expression's text (from `start` in the file) for `what`, its problems
/// added.
type ExprCompiler<'a> = dyn Fn(&str, Option<usize>, &str, &mut Vec<Problem>) -> Option<Dnf> + 'a;

/// The equations, in the program's order; a counter's reset just before its count
/// input, in the slot `resets` + its index.
fn compile_equations(
    program: &Program,
    origin: &Origin,
    equation_slot: &dyn Fn(&str) -> Option<usize>,
    (counter_index, resets): (&BTreeMap<String, usize>, usize),
    compile_expr: &ExprCompiler<'_>,
    problems: &mut Vec<Problem>,
) -> Vec<EquationInfo> {
    let mut equations = Vec::new();
    let mut eq_targets = BTreeMap::new();
    for (index, (target, text)) in program.equations.iter().enumerate() {
        let what = format!("equation `{target}`");
        let start = origin.equation_start(target);
        let Some(slot) = equation_slot(target) else {
            problems.push(Problem::error(
                codes::PROGRAM_EQUATION_TARGET.id,
                format!("{what}: `{target}` is neither an actuator, a memory nor a timer"),
                Some(origin.location(start)),
            ));
            continue;
        };
        if eq_targets.insert(slot, ()).is_some() {
            problems.push(Problem::error(
                codes::PROGRAM_EQUATION_TWICE.id,
                format!("{what}: `{target}` has two equations"),
                Some(origin.location(start)),
            ));
        }
        // A counter's reset comes just before its count input, in a slot of its
        // own after the counters'.
        if let Some(&c) = counter_index.get(target.as_str()) {
            let what = format!("counter `{target}`, its reset");
            let reset = &program.counters[c].reset;
            let start = reset_start(origin, &program.counters[c]);
            if let Some(dnf) = compile_expr(reset, start, &what, problems) {
                equations.push(EquationInfo {
                    slot: resets + c,
                    index,
                    dnf,
                    cond: Cond::default(),
                });
            }
        }
        if let Some(dnf) = compile_expr(text, start, &what, problems) {
            equations.push(EquationInfo {
                slot,
                index,
                dnf,
                cond: Cond::default(),
            });
        }
    }
    for counter in &program.counters {
        if !program.equations.iter().any(|(t, _)| *t == counter.id) {
            problems.push(Problem::error(
                codes::PROGRAM_EQUATION_TARGET.id,
                format!(
                    "counter `{}` has no equation: its count input is missing",
                    counter.id
                ),
                Some(origin.location(origin.find_quoted(&counter.id, 0))),
            ));
        }
    }
    equations
}

/// Declares the standard counters; their index by name.
fn declare_counters(
    program: &Program,
    origin: &Origin,
    problems: &mut Vec<Problem>,
    symbols: &mut Symbols,
) -> (Vec<CounterInfo>, BTreeMap<String, usize>) {
    let mut counters = Vec::new();
    let mut index = BTreeMap::new();
    for c in &program.counters {
        let loc = Some(origin.location(origin.find_quoted(&c.id, 0)));
        if let Some(aux) = declare(&c.id, "counter", loc, problems, symbols) {
            index.insert(c.id.clone(), counters.len());
            counters.push(CounterInfo {
                kind: c.kind,
                preset: c.preset,
                aux,
            });
        }
    }
    (counters, index)
}

/// Where the reset expression of counter `c` starts in the program's text.
fn reset_start(origin: &Origin, c: &Counter) -> Option<usize> {
    let id = origin.find_quoted(&c.id, 0)?;
    origin.find_quoted(&c.reset, id).map(|p| p + 1)
}

/// Declares memories, timers and panel inputs, and checks the start and stop buttons.
fn declare_others(
    program: &Program,
    origin: &Origin,
    step_index: &BTreeMap<String, u16>,
    problems: &mut Vec<Problem>,
    symbols: &mut Symbols,
) -> Others {
    let mut memory_aux = Vec::new();
    let mut memory_index = BTreeMap::new();
    for m in &program.memories {
        let loc = Some(origin.location(origin.find_quoted(m, 0)));
        if let Some(aux) = declare(m, "memory", loc, problems, symbols) {
            memory_index.insert(
                m.clone(),
                u32::try_from(memory_aux.len()).unwrap_or(u32::MAX),
            );
            memory_aux.push(aux);
        }
    }
    let mut timers = Vec::new();
    for (id, step, ms) in &program.timers {
        let loc = Some(origin.location(origin.find_quoted(id, 0)));
        let Some(aux) = declare(id, "timer", loc.clone(), problems, symbols) else {
            continue;
        };
        match step_index.get(step) {
            Some(&s) => timers.push(TimerInfo {
                step: s,
                ms: *ms,
                aux,
            }),
            None => problems.push(Problem::error(
                codes::PROGRAM_TIMER_UNKNOWN_STEP.id,
                format!("timer `{id}`: unknown step `{step}`"),
                loc,
            )),
        }
    }
    let mut panel_aux = Vec::new();
    for p in &program.panel {
        let loc = Some(origin.location(origin.find_quoted(p, 0)));
        if let Some(aux) = declare(p, "panel input", loc, problems, symbols) {
            panel_aux.push(aux);
        }
    }
    // A start or stop button is the program's own panel button, or a push button of
    // the machine's panel wired to a plant input (the emulator's `Button` presses it).
    let wired = |b: &str| matches!(symbols.lookup(b), Some((Space::Input, _)));
    for (what, button) in [("start", &program.start), ("stop", &program.stop)] {
        if let Some(b) = button
            .as_ref()
            .filter(|b| !program.panel.contains(b) && !wired(b))
        {
            problems.push(Problem::error(
                codes::PROGRAM_BUTTON_NOT_ON_PANEL.id,
                format!("`{what}`: `{b}` is neither a panel button nor a plant input"),
                Some(origin.location(origin.find_quoted(b, 0))),
            ));
        }
    }
    Others {
        memory_aux,
        memory_index,
        timers,
        panel_aux,
    }
}

/// Parses and resolves an expression of the program, which may not read observers.
fn compile_expr(
    origin: &Origin,
    symbols: &Symbols,
    text: &str,
    start: Option<usize>,
    what: &str,
    problems: &mut Vec<Problem>,
) -> Option<Dnf> {
    let (line, column) = start.map_or((1, 1), |s| line_col(&origin.text, s));
    let span = Span { line, column };
    match expr::parse(text, span).and_then(|e| e.to_dnf(symbols)) {
        Ok(d) => {
            if let Some(l) = d.iter().flatten().find(|l| l.var.space == Space::Observer) {
                problems.push(Problem::error(
                    codes::PROGRAM_READS_OBSERVER.id,
                    format!(
                        "{what}: a program cannot read the observer `{}`",
                        symbols.name(l.var.space, l.var.index)
                    ),
                    Some(Location::new(&origin.file, line, column)),
                ));
                return None;
            }
            Some(d)
        }
        Err(e) => {
            problems.push(Problem::error(
                codes::PROGRAM_EXPRESSION_INVALID.id,
                format!("{what}: {}", e.message),
                Some(Location::new(&origin.file, e.span.line, e.span.column)),
            ));
            None
        }
    }
}

/// Where a transition's ends are checked: its description, place, chart and the steps.
struct EndsContext<'a> {
    what: &'a str,
    at: Option<Location>,
    chart: usize,
    step_index: &'a BTreeMap<String, u16>,
    steps: &'a [StepInfo],
}

/// Resolves a transition's upstream or downstream steps, sorted and deduplicated.
fn transition_ends(
    list: &[String],
    dir: &str,
    cx: &EndsContext<'_>,
    problems: &mut Vec<Problem>,
) -> Vec<u16> {
    let EndsContext {
        what,
        chart: ci,
        step_index,
        steps,
        ..
    } = *cx;
    let mut out = Vec::new();
    if list.is_empty() {
        problems.push(Problem::error(
            codes::PROGRAM_TRANSITION_NO_STEP.id,
            format!("{what}: no {dir} step"),
            cx.at.clone(),
        ));
    }
    for s in list {
        match step_index.get(s) {
            Some(&i)
                if steps
                    .get(i as usize)
                    .is_some_and(|st: &StepInfo| st.chart == ci) =>
            {
                out.push(i)
            }
            Some(_) => problems.push(Problem::error(
                codes::PROGRAM_TRANSITION_OTHER_CHART.id,
                format!("{what}: {dir} step `{s}` belongs to another chart"),
                cx.at.clone(),
            )),
            None => problems.push(Problem::error(
                codes::PROGRAM_TRANSITION_UNKNOWN_STEP.id,
                format!("{what}: unknown {dir} step `{s}`"),
                cx.at.clone(),
            )),
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Compiles the charts' transitions: ids, ends and conditions.
fn compile_transitions(
    program: &Program,
    origin: &Origin,
    symbols: &Symbols,
    step_index: &BTreeMap<String, u16>,
    steps: &[StepInfo],
    problems: &mut Vec<Problem>,
) -> Vec<TransitionInfo> {
    let at_id = |id: &str| Some(origin.location(origin.find_id(id)));
    let compile_expr =
        |text: &str, start: Option<usize>, what: &str, problems: &mut Vec<Problem>| {
            compile_expr(origin, symbols, text, start, what, problems)
        };
    let mut transitions = Vec::new();
    let mut transition_ids = BTreeMap::new();
    for (ci, chart) in program.charts.iter().enumerate() {
        for t in &chart.transitions {
            let what = format!("chart `{}`, transition `{}`", chart.name, t.id);
            if transition_ids.insert(t.id.clone(), ()).is_some() || step_index.contains_key(&t.id) {
                problems.push(Problem::error(
                    codes::PROGRAM_TRANSITION_ID_TAKEN.id,
                    format!("{what}: the id is used twice"),
                    at_id(&t.id),
                ));
            }
            let cx = EndsContext {
                what: &what,
                at: at_id(&t.id),
                chart: ci,
                step_index,
                steps,
            };
            let ends = |list: &[String], dir: &str, problems: &mut Vec<Problem>| {
                transition_ends(list, dir, &cx, problems)
            };
            let from = ends(&t.from, "upstream", problems);
            let to = ends(&t.to, "downstream", problems);
            let condition =
                compile_expr(&t.condition, origin.condition_start(&t.id), &what, problems);
            if let Some(condition) = condition.filter(|_| transitions.len() < MAX_ELEMENTS) {
                transitions.push(TransitionInfo {
                    id: t.id.clone(),
                    from,
                    to,
                    condition,
                    cond: Cond::default(),
                    enable: Cond::default(),
                });
            }
        }
    }
    transitions
}

/// Packs the transitions' conditions and enables and the equations' conditions.
fn link_conds(
    transitions: &mut [TransitionInfo],
    equations: &mut [EquationInfo],
    steps: &[StepInfo],
    layout: &Layout,
) -> Conds {
    let mut conds = Conds::default();
    for t in transitions.iter_mut() {
        t.cond = conds.add(&t.condition, layout);
        let vars: Vec<(usize, u64)> = t
            .from
            .iter()
            .filter_map(|&s| steps.get(s as usize))
            .map(|st| layout.locate(Space::Aux, st.aux as usize, false))
            .collect();
        t.enable = conds.add_all(&vars);
    }
    for e in equations.iter_mut() {
        e.cond = conds.add(&e.dnf, layout);
    }
    conds
}
