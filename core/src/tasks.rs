//! Timed task monitoring with stopwatches (seed 000, Allahham 2008).
//!
//! A task (a conveyor transfer, a table rotation) has a normal duration `[α, β]` of
//! effective (running) time and an acceptable duration `[α, γ)` of total time, and may be
//! interrupted and resumed where it stopped. Two stopwatches per task, total `x` and
//! effective `y` (rates idle (0,0), running (1,1), interrupted (1,0)), let the monitor
//! raise an alarm as soon as the task can no longer finish acceptably:
//! `0 ≤ x − y < γ − α ∧ x < γ ∧ y ≤ β` — earlier than the classical watchdog at start + γ.
//!
//! - [`spec`]: `tasks.ron` (tasks, controller windows, cross-task constraints) and checks.
//! - [`monitor`]: the monitor (one [`monitor::TaskMonitor`] per task plus a
//!   [`monitor::Coordinator`]) with exact crossing-time prediction, timed by the
//!   closed form or by the synthesised regions.
//! - [`explain`]: alarms, stable codes `T001`…`T009`, operator texts, watchdog comparison.
//! - [`events`]: events as expressions over a PLC frame, and the task outputs published
//!   as auxiliary variables (`turn_out:infeasible`) for the safety filter.
//!
//! Time is [`crate::Millis`]; the thesis's fixtures use 1 u.t. = 1000 ms.
//!
//! The monitor has two timing back-ends behind one seam ([`monitor`]): the per-task
//! closed form (sound, but it may detect later than the product region `E*` when tasks
//! are coupled, which hand-written cross-task constraints of the coordinator can
//! partly make up for), and the synthesised regions `E*` of the tasks' product
//! automaton ([`crate::swa`]: `vigie synthesize` writes them as `regions.ron` beside
//! `tasks.ron`). When a plant folder has a `regions.ron`, the layout loader
//! ([`TaskSet::load_optional`]) checks it against the tasks (a stale one is refused,
//! V1503) and the plant's monitor, which the emulator, the live link and the console
//! run, raises its alarms from the regions ([`crate::swa::regions::RegionMonitor`]);
//! without one it runs the closed form. The alarms (codes, texts), the operator's
//! panel and the published variables are the same either way.

pub mod events;
pub mod explain;
pub mod monitor;
pub mod spec;

pub use events::FrameTasks;
pub use explain::{Alarm, AlarmCode, Severity};
pub use monitor::{Deadline, Monitor, Role, TaskMonitor, TaskState, TaskStatus};
pub use spec::{TaskFile, TaskSet, TaskSpec};

/// A synthetic set of `n` independent interruptible tasks (`t0`…), each with its own
/// events `s<i>`, `e<i>`, `i<i>`, `r<i>` and bounds α = 3 s, β = 4 s, γ = 5 s, for
/// benchmarks of the monitor's cost against the number of tasks.
pub fn synthetic(n: usize) -> TaskSet {
    TaskSet {
        tasks: (0..n)
            .map(|i| TaskSpec {
                id: format!("t{i}"),
                description: String::new(),
                start: format!("s{i}"),
                end: format!("e{i}"),
                interruption: Some((format!("i{i}"), format!("r{i}"))),
                alpha: 3000,
                beta: 4000,
                gamma: 5000,
                slowdown: spec::Slowdown::Strict,
            })
            .collect(),
        windows: Vec::new(),
        cross: Vec::new(),
        unexpected: spec::Unexpected::Warn,
        latch: spec::Latch::PerTask,
        repair: Some("m".into()),
        check_end: true,
        file: std::path::PathBuf::from("<synthetic>"),
        regions: None,
    }
}

#[cfg(test)]
mod tests;
