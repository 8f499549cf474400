//! Task events as expressions over a PLC frame (`RE(C0)`, `/A1`), for plants whose
//! events are signal changes rather than named messages.
//!
//! Each cycle, [`FrameTasks::step`] evaluates every task's expressions and applies them,
//! gated by the task's state so that level expressions work: the interrupt expression is
//! applied only to a running task (`/A1`: "the conveyor is OFF while the task is in
//! progress") and the resume expression only to an interrupted one. Start and end are
//! applied as they come (an end while idle is an unexpected event, see
//! [`super::spec::Unexpected`]). Per task and cycle the order is: end, start, interrupt,
//! resume — so a task can end and restart in one cycle, and a task started while its
//! actuator is OFF is interrupted at once.

use super::monitor::{Monitor, Role, TaskState};
use super::spec::TaskSet;
use crate::diag::codes;
use crate::diag::{Location, Problem};
use crate::expr::{self, Dnf};
use crate::frame::Frame;
use crate::symbols::{Space, Symbols};
use crate::time::Millis;

/// Compiled event expressions of every task.
#[derive(Clone, Debug)]
pub struct FrameTasks {
    /// Per task: start, end, optional (interrupt, resume).
    pub events: Vec<TaskEvents>,
    aux: Vec<Option<u32>>,
    /// Per task: the event names (start, end, optional interrupt and resume), copied
    /// once so that a cycle allocates nothing.
    names: Vec<EventNames>,
}

/// A task's event names: start, end, and the interrupt and resume pair if any.
type EventNames = (String, String, Option<(String, String)>);

/// The compiled expressions of one task.
#[derive(Clone, Debug)]
pub struct TaskEvents {
    /// Start.
    pub start: Dnf,
    /// End.
    pub end: Dnf,
    /// Interrupt and resume.
    pub interruption: Option<(Dnf, Dnf)>,
}

impl FrameTasks {
    /// Compiles the event expressions against `symbols` (inputs, outputs, observers and
    /// auxiliaries of the plant bundle). Expressions must not read task outputs.
    pub fn compile(set: &TaskSet, symbols: &Symbols) -> Result<Self, Vec<Problem>> {
        let mut problems = Vec::new();
        let mut events = Vec::new();
        let one = |task: &str, what: &str, text: &str, problems: &mut Vec<Problem>| -> Dnf {
            match expr::parse_str(text).and_then(|e| e.to_dnf(symbols)) {
                Ok(d) => expr::simplify(&d),
                Err(e) => {
                    problems.push(Problem::error(
                        codes::TASK_EVENT_INVALID.id,
                        format!(
                            "task `{task}`: `{what}` event `{text}`: {} (column {})",
                            e.message, e.span.column
                        ),
                        Some(Location::new(&set.file, 1, 1)),
                    ));
                    Vec::new()
                }
            }
        };
        for t in &set.tasks {
            let start = one(&t.id, "start", &t.start, &mut problems);
            let end = one(&t.id, "end", &t.end, &mut problems);
            let interruption = t.interruption.as_ref().map(|(i, r)| {
                (
                    one(&t.id, "interrupt", i, &mut problems),
                    one(&t.id, "resume", r, &mut problems),
                )
            });
            events.push(TaskEvents {
                start,
                end,
                interruption,
            });
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        let aux = set
            .aux_names()
            .iter()
            .map(|n| match symbols.lookup(n) {
                Some((Space::Aux, i)) => Some(i),
                _ => None,
            })
            .collect();
        let names = set
            .tasks
            .iter()
            .map(|t| (t.start.clone(), t.end.clone(), t.interruption.clone()))
            .collect();
        Ok(Self { events, aux, names })
    }

    /// One PLC cycle at `now`: violations before `now`, then the events of this cycle,
    /// then violations at `now`.
    pub fn step(&self, monitor: &mut Monitor, now: Millis, frame: &Frame) {
        monitor.on_event(now, "");
        for (i, (ev, (start, end, interruption))) in self.events.iter().zip(&self.names).enumerate()
        {
            if expr::eval_dnf(&ev.end, frame) {
                monitor.apply(now, i, Role::End, end);
            }
            if expr::eval_dnf(&ev.start, frame) {
                monitor.apply(now, i, Role::Start, start);
            }
            if let (Some((int, res)), Some((int_name, res_name))) = (&ev.interruption, interruption)
            {
                let state = monitor.tasks[i].state;
                if state == TaskState::Running && expr::eval_dnf(int, frame) {
                    monitor.apply(now, i, Role::Interrupt, int_name);
                } else if state == TaskState::Interrupted && expr::eval_dnf(res, frame) {
                    monitor.apply(now, i, Role::Resume, res_name);
                }
            }
        }
        monitor.advance(now);
    }

    /// Writes the task outputs (`<task>:running`, `:interrupted`, `:infeasible`) into the
    /// auxiliary space of `frame`, for the safety filter.
    pub fn publish(&self, monitor: &Monitor, frame: &mut Frame) {
        for (slot, value) in self.aux.iter().zip(monitor.aux_values()) {
            if let Some(i) = slot {
                frame.now_mut(Space::Aux).set(*i as usize, value);
            }
        }
    }
}
