//! Task timing specifications as data (`tasks.ron`) and their validation.
//!
//! Durations are integer milliseconds ([`crate::Millis`]). The thesis counts in abstract
//! time units (u.t.) with halves such as 6.5; the fixtures map **1 u.t. = 1000 ms**, so
//! every value of the thesis is exact.

use crate::diag::codes;
use crate::diag::{Location, Problem, ron_problem};
use crate::swa::regions::TaskRegions;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// What the monitor checks while a task runs without a slowdown sensor (thesis §4.3,
/// Fig. 4.13).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Slowdown {
    /// Default model: the effective time may not exceed β (alarm just after β).
    #[default]
    Strict,
    /// Fig. 4.13.b: the effective time may reach γ; the end guard uses `y ∈ [α, γ]` and a
    /// slowed task is detected at `x = γ`.
    Tolerant,
}

/// What to do with a known event that the current state does not expect (an end while
/// idle, a resume without an interruption).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Unexpected {
    /// Drop it silently.
    Ignore,
    /// Record a warning (code T007), no latch.
    #[default]
    Warn,
    /// Raise and latch a T007 alarm on the task.
    Alarm,
}

/// How far a fault latch freezes the monitor.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Latch {
    /// Only the faulty task freezes (decentralized monitors).
    #[default]
    PerTask,
    /// The first fault freezes every task (the thesis's SFC2 master).
    Global,
}

/// One task as written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskDef {
    /// Identifier: letters, digits and `_`.
    pub id: String,
    /// What the task does.
    #[serde(default)]
    pub description: String,
    /// Start event (a name, or in frame mode an expression such as `RE(C0)`).
    pub start: String,
    /// End event.
    pub end: String,
    /// Interrupt event; present (with `resume`) means the task is interruptible.
    #[serde(default)]
    pub interrupt: Option<String>,
    /// Resume event.
    #[serde(default)]
    pub resume: Option<String>,
    /// Lower bound α of both windows, in ms.
    pub alpha_ms: u64,
    /// Upper bound β of the normal (effective) duration `[α, β]`, in ms.
    pub beta_ms: u64,
    /// Exclusive upper bound γ of the acceptable (total) duration `[α, γ)`, in ms.
    pub gamma_ms: u64,
    /// Slowdown variant.
    #[serde(default)]
    pub slowdown: Slowdown,
}

/// A controller timing window (thesis: "`d` within `[0, 2]` after step s1/s6", `x1 ≤ 2`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindowDef {
    /// Identifier.
    pub id: String,
    /// What it means.
    #[serde(default)]
    pub description: String,
    /// Events that open (or re-open) the window.
    pub open: Vec<String>,
    /// Events that close it.
    pub close: Vec<String>,
    /// The window is open when the monitor starts.
    #[serde(default)]
    pub open_at_start: bool,
    /// Closing earlier than this is a violation, in ms.
    #[serde(default)]
    pub min_ms: u64,
    /// The window must close within this (inclusive), in ms.
    pub max_ms: u64,
}

/// A stopwatch of a task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Clock {
    /// Total time `x`.
    X,
    /// Effective time `y`.
    Y,
}

/// Comparison of a cross-task constraint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Cmp {
    /// `sum < bound`.
    Lt,
    /// `sum <= bound`.
    Le,
}

/// A cross-task constraint held by the coordinator, checked while every task it names is
/// in progress: `Σ coef · clock  op  bound` (e.g. the workshop's `x4 − x2 ≤ 2`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrossDef {
    /// Identifier.
    pub id: String,
    /// What it means.
    #[serde(default)]
    pub description: String,
    /// `(task id, clock, integer coefficient)`.
    pub terms: Vec<(String, Clock, i64)>,
    /// Comparison.
    pub op: Cmp,
    /// Bound in ms.
    pub bound_ms: i64,
}

fn yes() -> bool {
    true
}

/// The `tasks.ron` file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskFile {
    /// Tasks.
    pub tasks: Vec<TaskDef>,
    /// Controller windows.
    #[serde(default)]
    pub windows: Vec<WindowDef>,
    /// Cross-task constraints for the coordinator.
    #[serde(default)]
    pub cross: Vec<CrossDef>,
    /// Unexpected-event policy.
    #[serde(default)]
    pub unexpected: Unexpected,
    /// Latch scope.
    #[serde(default)]
    pub latch: Latch,
    /// The "repair finished" event `m`: resets every latch, task and window.
    #[serde(default)]
    pub repair: Option<String>,
    /// Check the end guard `α ≤ y ≤ β ∧ α ≤ x < γ` on the end event (strict mode).
    #[serde(default = "yes")]
    pub check_end: bool,
}

/// A validated task.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TaskSpec {
    /// Identifier.
    pub id: String,
    /// What the task does.
    pub description: String,
    /// Start event.
    pub start: String,
    /// End event.
    pub end: String,
    /// `(interrupt, resume)` for an interruptible task.
    pub interruption: Option<(String, String)>,
    /// α in ms.
    pub alpha: u64,
    /// β in ms.
    pub beta: u64,
    /// γ in ms.
    pub gamma: u64,
    /// Slowdown variant.
    pub slowdown: Slowdown,
}

impl TaskSpec {
    /// True when the task has interrupt and resume events.
    pub fn interruptible(&self) -> bool {
        self.interruption.is_some()
    }

    /// The tolerance `γ − α` on the accumulated interruption.
    pub fn tolerance(&self) -> u64 {
        self.gamma - self.alpha
    }
}

/// A validated specification set.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TaskSet {
    /// Tasks, in file order.
    pub tasks: Vec<TaskSpec>,
    /// Controller windows.
    pub windows: Vec<WindowDef>,
    /// Cross-task constraints.
    pub cross: Vec<CrossDef>,
    /// Unexpected-event policy.
    pub unexpected: Unexpected,
    /// Latch scope.
    pub latch: Latch,
    /// Repair event.
    pub repair: Option<String>,
    /// Strict end check.
    pub check_end: bool,
    /// Where it was loaded from (messages, and the folder of its regions).
    pub file: PathBuf,
    /// The synthesised regions beside the file (`regions.ron`), checked against the
    /// tasks: the monitor runs them in place of the closed form ([`super::Monitor`]).
    /// Only the layout loader ([`Self::load_optional`]) reads them.
    #[serde(skip)]
    pub regions: Option<TaskRegions>,
}

/// Auxiliary outputs published per task, in this order (see [`TaskSet::aux_names`]).
pub const AUX_QUALIFIERS: [&str; 3] = ["running", "interrupted", "infeasible"];

impl TaskSet {
    /// Parses and validates `tasks.ron` text; `file` is used in messages.
    pub fn from_ron(text: &str, file: &Path) -> Result<Self, Vec<Problem>> {
        let parsed: TaskFile = ron::from_str(text).map_err(|e| vec![ron_problem(file, &e)])?;
        Self::from_file(parsed, file, Some(text))
    }

    /// Loads the optional `tasks.ron` of a plant folder with its synthesised regions
    /// (`regions.ron` beside it, if any): `None` without problems when the folder has
    /// no tasks, `None` with the problems when they cannot be used, a regions file
    /// synthesised from other tasks included (V1503: it is refused, never run and
    /// never replaced by the closed form). With regions, the coordinator's cross-task
    /// constraints are not run (a V1504 warning each): the regions hold the coupling.
    pub fn load_optional(dir: &Path) -> (Option<Self>, Vec<Problem>) {
        let path = dir.join("tasks.ron");
        if !path.exists() {
            return (None, Vec::new());
        }
        let text = match crate::diag::read_text(&path) {
            Ok(text) => text,
            Err(p) => return (None, vec![p]),
        };
        let mut set = match Self::from_ron(&text, &path) {
            Ok(set) => set,
            Err(p) => return (None, p),
        };
        match TaskRegions::beside(&set) {
            Ok(regions) => set.regions = regions,
            Err(p) => return (None, vec![p]),
        }
        let mut problems = Vec::new();
        if let Some(regions) = &set.regions {
            for c in &set.cross {
                problems.push(Problem::warning(
                    codes::TASK_CROSS_BESIDE_REGIONS.id,
                    format!(
                        "cross-task constraint `{}` is not run: the tasks run the regions of {}, \
                         which hold the coupling their automata imply (add it to the automata, \
                         or remove the regions file to run the closed form and the constraint)",
                        c.id,
                        regions.path.display()
                    ),
                    Some(locate(&path, Some(&text), &c.id)),
                ));
            }
        }
        (Some(set), problems)
    }

    /// Loads `tasks.ron` from disk.
    pub fn load(path: &Path) -> Result<Self, Vec<Problem>> {
        let text = crate::diag::read_text(path).map_err(|p| vec![p])?;
        Self::from_ron(&text, path)
    }

    /// Validates a parsed file. `text` (the source) lets problems point at the id.
    pub fn from_file(f: TaskFile, file: &Path, text: Option<&str>) -> Result<Self, Vec<Problem>> {
        let mut problems = Vec::new();
        let at = |id: &str| Some(locate(file, text, id));
        let mut seen = BTreeSet::new();
        let mut tasks = Vec::new();
        for t in f.tasks {
            let before = problems.len();
            if !crate::plant::is_valid_name(&t.id) {
                problems.push(Problem::error(
                    codes::TASK_ID_INVALID.id,
                    format!("task id `{}` must be letters, digits and `_`", t.id),
                    at(&t.id),
                ));
            }
            if !seen.insert(t.id.clone()) {
                problems.push(Problem::error(
                    codes::TASK_DUPLICATE.id,
                    format!("task `{}` is declared twice", t.id),
                    at(&t.id),
                ));
            }
            check_durations(&t, at(&t.id), &mut problems);
            let interruption = match (t.interrupt, t.resume) {
                (Some(i), Some(r)) => Some((i, r)),
                (None, None) => None,
                _ => {
                    problems.push(Problem::error(
                        codes::TASK_INTERRUPT_RESUME.id,
                        format!(
                            "task `{}`: give both `interrupt` and `resume`, or neither",
                            t.id
                        ),
                        at(&t.id),
                    ));
                    None
                }
            };
            if problems.len() == before {
                tasks.push(TaskSpec {
                    id: t.id,
                    description: t.description,
                    start: t.start,
                    end: t.end,
                    interruption,
                    alpha: t.alpha_ms,
                    beta: t.beta_ms,
                    gamma: t.gamma_ms,
                    slowdown: t.slowdown,
                });
            }
        }
        for w in &f.windows {
            if w.min_ms > w.max_ms {
                problems.push(Problem::error(
                    codes::TASK_WINDOW_EMPTY.id,
                    format!(
                        "window `{}`: min = {} ms is greater than max = {} ms",
                        w.id, w.min_ms, w.max_ms
                    ),
                    at(&w.id),
                ));
            }
        }
        for c in &f.cross {
            for (task, _, _) in &c.terms {
                if !seen.contains(task) {
                    problems.push(Problem::error(
                        codes::TASK_CROSS_INVALID.id,
                        format!(
                            "cross constraint `{}` names the unknown task `{task}`",
                            c.id
                        ),
                        at(&c.id),
                    ));
                }
            }
            if c.terms.is_empty() {
                problems.push(Problem::error(
                    codes::TASK_CROSS_INVALID.id,
                    format!("cross constraint `{}` has no term", c.id),
                    at(&c.id),
                ));
            }
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        Ok(Self {
            tasks,
            windows: f.windows,
            cross: f.cross,
            unexpected: f.unexpected,
            latch: f.latch,
            repair: f.repair,
            check_end: f.check_end,
            file: file.to_path_buf(),
            regions: None,
        })
    }

    /// Index of a task by id.
    pub fn task(&self, id: &str) -> Option<usize> {
        self.tasks.iter().position(|t| t.id == id)
    }

    /// Names of the auxiliary variables the monitor publishes for the safety filter:
    /// `<task>:running`, `<task>:interrupted`, `<task>:infeasible` for every task, in
    /// task order. Declare them with [`crate::bundle::PlantBundle::from_plant`].
    pub fn aux_names(&self) -> Vec<String> {
        self.tasks
            .iter()
            .flat_map(|t| AUX_QUALIFIERS.iter().map(move |q| format!("{}:{q}", t.id)))
            .collect()
    }
}

/// Checks a task's durations: α ≤ β < γ.
fn check_durations(t: &TaskDef, loc: Option<Location>, problems: &mut Vec<Problem>) {
    if t.alpha_ms > t.beta_ms {
        problems.push(Problem::error(
            codes::TASK_ALPHA_BEYOND_BETA.id,
            format!(
                "task `{}`: α = {} ms is greater than β = {} ms; the normal duration [α, β] is empty",
                t.id, t.alpha_ms, t.beta_ms
            ),
            loc.clone(),
        ));
    }
    if t.beta_ms >= t.gamma_ms {
        problems.push(Problem::error(
            codes::TASK_BETA_NOT_BELOW_GAMMA.id,
            format!(
                "task `{}`: β = {} ms must be less than γ = {} ms (the acceptable duration [α, γ) must extend the normal one)",
                t.id, t.beta_ms, t.gamma_ms
            ),
            loc.clone(),
        ));
    }
}

/// The position of `"id"` in the source, or 1:1.
fn locate(file: &Path, text: Option<&str>, id: &str) -> Location {
    let needle = format!("\"{id}\"");
    if let Some(text) = text {
        for (i, line) in text.lines().enumerate() {
            if let Some(col) = line.find(&needle) {
                return Location::new(file, i + 1, line[..col].chars().count() + 1);
            }
        }
    }
    Location::new(file, 1, 1)
}
