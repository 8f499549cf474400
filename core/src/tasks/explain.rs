//! Alarms with stable codes, structured fields and the operator text built on the
//! thesis's own argument.
//!
//! | code | meaning |
//! |------|---------|
//! | T001 | interruption tolerance used up: the task can no longer finish before γ |
//! | T002 | slowdown: effective running time beyond β without the end event |
//! | T003 | total time reached γ (the watchdog bound) |
//! | T004 | ended too early (below α) |
//! | T005 | ended outside the acceptable window (x ≥ γ or y beyond β) |
//! | T006 | controller timing window violated |
//! | T007 | unexpected event for the task's state |
//! | T008 | cross-task constraint of the coordinator violated |
//! | T009 | synthesised region left before the task's (or window's) own bounds |

use super::monitor::{Role, TaskMonitor, TaskState};
use super::spec::{Cmp, CrossDef, TaskSpec, WindowDef};
use crate::diag::codes;
use crate::swa::regions::RegionAlarm;
use crate::time::Millis;
use serde::Serialize;

/// Stable alarm codes.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, serde::Deserialize,
)]
pub enum AlarmCode {
    /// Interruption tolerance used up.
    T001,
    /// Slowdown beyond β.
    T002,
    /// Total time reached γ.
    T003,
    /// Ended too early.
    T004,
    /// Ended outside the acceptable window.
    T005,
    /// Controller window violated.
    T006,
    /// Unexpected event.
    T007,
    /// Cross-task constraint violated.
    T008,
    /// Synthesised region left before the subject's own bounds.
    T009,
}

impl AlarmCode {
    /// The code as text (`T001`), from the registry [`codes`].
    pub fn as_str(self) -> &'static str {
        match self {
            AlarmCode::T001 => codes::T_TOLERANCE_USED_UP.id,
            AlarmCode::T002 => codes::T_SLOWDOWN.id,
            AlarmCode::T003 => codes::T_WATCHDOG.id,
            AlarmCode::T004 => codes::T_ENDED_TOO_EARLY.id,
            AlarmCode::T005 => codes::T_ENDED_OUTSIDE_WINDOW.id,
            AlarmCode::T006 => codes::T_CONTROLLER_WINDOW.id,
            AlarmCode::T007 => codes::T_UNEXPECTED_EVENT.id,
            AlarmCode::T008 => codes::T_CROSS_TASK.id,
            AlarmCode::T009 => codes::T_REGION_LEFT.id,
        }
    }

    /// What is wrong, in the operator's words.
    pub fn meaning(self) -> &'static str {
        match self {
            AlarmCode::T001 => "stopped too long, it can no longer finish in time",
            AlarmCode::T002 => "slower than normal",
            AlarmCode::T003 => "not finished within its acceptable time",
            AlarmCode::T004 => "finished sooner than possible (a sensor or a missed step?)",
            AlarmCode::T005 => "finished outside its acceptable time",
            AlarmCode::T006 => "the controller missed its time window",
            AlarmCode::T007 => "an event came when none was expected",
            AlarmCode::T008 => "two tasks out of step",
            AlarmCode::T009 => "can no longer finish in time with the tasks it depends on",
        }
    }
}

/// Alarm or warning.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Latches.
    Alarm,
    /// Recorded only.
    Warning,
}

/// One alarm: code, exact time, the subject, the values that prove it, and the text.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Alarm {
    /// Stable code.
    pub code: AlarmCode,
    /// Alarm or warning.
    pub severity: Severity,
    /// The exact instant (crossing instant or event time).
    pub time: Millis,
    /// Task, window or cross-constraint id.
    pub subject: String,
    /// Total time x at `time` (tasks).
    pub x_ms: Option<u64>,
    /// Effective time y at `time` (interruptible tasks).
    pub y_ms: Option<u64>,
    /// `(α, β, γ)` of the task.
    pub bounds_ms: Option<(u64, u64, u64)>,
    /// Start of the run.
    pub started: Option<Millis>,
    /// When the classical watchdog (start + γ) would alarm, if it would at all.
    pub watchdog: Option<Millis>,
    /// `watchdog − time`: how much earlier this alarm came.
    pub earlier_by_ms: Option<u64>,
    /// Interruptions in the run.
    pub interruptions: u32,
    /// Operator text.
    pub text: String,
}

/// Durations and instants in seconds with no trailing zeros (`6.5 s`, `3 s`).
pub fn fmt_ms(ms: u64) -> String {
    let s = ms / 1000;
    let frac = ms % 1000;
    if frac == 0 {
        format!("{s} s")
    } else {
        let f = format!("{frac:03}");
        format!("{s}.{} s", f.trim_end_matches('0'))
    }
}

impl Alarm {
    pub(crate) fn task(
        code: AlarmCode,
        time: Millis,
        spec: &TaskSpec,
        tm: &TaskMonitor,
        x: u64,
        y: u64,
    ) -> Self {
        let watchdog = tm.started.map(|s| Millis(s.0 + spec.gamma));
        // A watchdog on γ never sees an early end; an end at or after γ it sees at γ.
        let (watchdog, earlier) = match code {
            AlarmCode::T004 => (None, None),
            _ => (watchdog, watchdog.map(|w| w.0.saturating_sub(time.0))),
        };
        let (a, b, g) = (spec.alpha, spec.beta, spec.gamma);
        let id = &spec.id;
        let tail = match (watchdog, earlier) {
            (Some(w), Some(e)) => format!(
                " Detected {} before the watchdog (start + γ = {}).",
                fmt_ms(e),
                fmt_ms(w.0)
            ),
            _ => " A watchdog on γ would not detect this.".to_string(),
        };
        let text = match code {
            AlarmCode::T001 => format!(
                "Task {id} cannot finish within its acceptable time. Effective progress y = {} of α = {}; at least α − y = {} more running time is needed, so the total would be x + (α − y) = {} + {} = {} >= γ = {}.{tail}",
                fmt_ms(y),
                fmt_ms(a),
                fmt_ms(a.saturating_sub(y)),
                fmt_ms(x),
                fmt_ms(a.saturating_sub(y)),
                fmt_ms(x + a.saturating_sub(y)),
                fmt_ms(g),
            ),
            AlarmCode::T002 => format!(
                "Task {id} is running longer than its maximum normal duration: effective time y = {} has passed β = {} without the end event (slowdown).{tail}",
                fmt_ms(y),
                fmt_ms(b)
            ),
            AlarmCode::T003 => format!(
                "Task {id} reached its acceptable total duration: x = {} = γ = {} without the end event (effective time y = {}).{tail}",
                fmt_ms(x),
                fmt_ms(g),
                fmt_ms(y)
            ),
            AlarmCode::T004 => format!(
                "Task {id} ended too early: x = {}, y = {}, below α = {}.{tail}",
                fmt_ms(x),
                fmt_ms(y),
                fmt_ms(a)
            ),
            _ => format!(
                "Task {id} ended outside its acceptable window: x = {} (must be < γ = {}), y = {} (must be within [α, β] = [{}, {}]).{tail}",
                fmt_ms(x),
                fmt_ms(g),
                fmt_ms(y),
                fmt_ms(a),
                fmt_ms(b)
            ),
        };
        Self {
            code,
            severity: Severity::Alarm,
            time,
            subject: spec.id.clone(),
            x_ms: Some(x),
            y_ms: Some(y),
            bounds_ms: Some((a, b, g)),
            started: tm.started,
            watchdog,
            earlier_by_ms: earlier,
            interruptions: tm.interruptions,
            text,
        }
    }

    fn bare(
        code: AlarmCode,
        severity: Severity,
        time: Millis,
        subject: &str,
        text: String,
    ) -> Self {
        Self {
            code,
            severity,
            time,
            subject: subject.to_string(),
            x_ms: None,
            y_ms: None,
            bounds_ms: None,
            started: None,
            watchdog: None,
            earlier_by_ms: None,
            interruptions: 0,
            text,
        }
    }

    pub(crate) fn window_late(time: Millis, w: &WindowDef, opened: Millis) -> Self {
        Self::bare(
            AlarmCode::T006,
            Severity::Alarm,
            time,
            &w.id,
            format!(
                "Controller window {} violated: opened at {}, not closed within {} (by {}).",
                w.id,
                fmt_ms(opened.0),
                fmt_ms(w.max_ms),
                fmt_ms(opened.0 + w.max_ms)
            ),
        )
    }

    pub(crate) fn window_early(time: Millis, w: &WindowDef, opened: Millis) -> Self {
        Self::bare(
            AlarmCode::T006,
            Severity::Alarm,
            time,
            &w.id,
            format!(
                "Controller window {} violated: opened at {}, closed after {}, before its minimum {}.",
                w.id,
                fmt_ms(opened.0),
                fmt_ms(time.0.saturating_sub(opened.0)),
                fmt_ms(w.min_ms)
            ),
        )
    }

    pub(crate) fn cross(time: Millis, c: &CrossDef, value: i64) -> Self {
        let sum = c
            .terms
            .iter()
            .map(|(t, clock, k)| {
                format!(
                    "{k}·{t}.{}",
                    if *clock == super::spec::Clock::X {
                        "x"
                    } else {
                        "y"
                    }
                )
            })
            .collect::<Vec<_>>()
            .join(" + ");
        Self::bare(
            AlarmCode::T008,
            Severity::Alarm,
            time,
            &c.id,
            format!(
                "Cross-task constraint {} violated: {sum} {} {} ms no longer holds (value {} ms when checked).",
                c.id,
                if c.op == Cmp::Lt { "<" } else { "<=" },
                c.bound_ms,
                value
            ),
        )
    }

    /// A T009 alarm: the synthesised region `region` was left at `time` before the
    /// subject's own bounds; `own` is when they would alarm (if they would). `task`:
    /// the subject is this task, with its clocks at `time`; otherwise a window.
    pub(crate) fn region_left(
        time: Millis,
        subject: &str,
        own: Option<Millis>,
        region: &RegionAlarm,
        task: Option<(&TaskSpec, &TaskMonitor, u64, u64)>,
    ) -> Self {
        let own_text = match own {
            Some(o) => format!(
                "its own bound alone would alarm at {}, {} later",
                fmt_ms(o.0),
                fmt_ms(o.0.saturating_sub(time.0))
            ),
            None => "its own bound alone would not alarm yet".to_string(),
        };
        let why = format!(
            "in {} the clocks left the synthesised region ({}); {own_text}",
            region.location, region.detail
        );
        let Some((spec, tm, x, y)) = task else {
            return Self::bare(
                AlarmCode::T009,
                Severity::Alarm,
                time,
                subject,
                format!(
                    "Controller window {subject} can no longer close in time with the tasks it shares events with: {why}."
                ),
            );
        };
        let mut alarm = Self::task(AlarmCode::T009, time, spec, tm, x, y);
        let tail = match (alarm.watchdog, alarm.earlier_by_ms) {
            (Some(w), Some(e)) => format!(
                " Detected {} before the watchdog (start + γ = {}).",
                fmt_ms(e),
                fmt_ms(w.0)
            ),
            _ => String::new(),
        };
        alarm.text = format!(
            "Task {subject} can no longer finish within its acceptable time together with the tasks it shares events with (x = {}, y = {}): {why}.{tail}",
            fmt_ms(x),
            fmt_ms(y)
        );
        alarm
    }

    pub(crate) fn unexpected(
        time: Millis,
        spec: &TaskSpec,
        state: TaskState,
        role: Role,
        event: &str,
        severity: Severity,
    ) -> Self {
        let role = match role {
            Role::Start => "start",
            Role::End => "end",
            Role::Interrupt => "interrupt",
            Role::Resume => "resume",
        };
        let state = match state {
            TaskState::Idle => "idle",
            TaskState::Running => "running",
            TaskState::Interrupted => "interrupted",
            TaskState::Done => "done",
            TaskState::Fault => "in fault",
        };
        Self::bare(
            AlarmCode::T007,
            severity,
            time,
            &spec.id,
            format!(
                "Unexpected {role} event `{event}` for task {} while it is {state}.",
                spec.id
            ),
        )
    }
}
