//! The stopwatch automata of a task set (`tasks.ron`): one component per task (Def.
//! 4.3.1, Fig. 4.8) and per controller window, composed on their shared events (a
//! task's end that starts another, an order that starts a task and closes a window).
//! Times are milliseconds.
//!
//! - Interruptible task, clocks `x` (total) and `y` (effective): `idle` (0, 0), `run`
//!   (1, 1), `int` (1, 0); invariant `x ≤ γ ∧ y ≤ β` (`y ≤ γ` in the tolerant slowdown
//!   model, Fig. 4.13.b); start resets both; interrupt and resume under `x < γ`; the end
//!   is the desired space `α ≤ x < γ ∧ α ≤ y ≤ β` and resets both again (the thesis
//!   resets them at the entry of `idle`, so that an idle task's clocks read 0).
//! - Non-interruptible task: `idle` and `run` only, `x = y ≤ γ`, end `α ≤ x < γ`
//!   (Remark 3: one window, no β).
//! - An interrupt or resume event that another component observes too (the same
//!   expression, `/DPV`, for two tasks driven by one actuator) is a level each task
//!   reads on its own, as the frame adapter applies it ([`crate::tasks::FrameTasks`]:
//!   an interrupt to a running task only, a resume to an interrupted one): a task
//!   where it does not apply ignores it (a self-loop), so that the product does not
//!   wait for every task to take it.
//! - Window, clock `w`: `closed` (0) and `open` (1, `w ≤ max`); an opening event resets
//!   `w`; a closing event is the desired space `min ≤ w ≤ max` (and is accepted, without
//!   a guard, while the window is closed).

use super::automaton::{ComponentDef, EdgeDef, LocationDef, SwaFile};
use crate::tasks::spec::{Slowdown, TaskSet, TaskSpec, WindowDef};
use std::collections::BTreeSet;

fn loc(name: &str, label: &str, running: &[&str], invariant: String) -> LocationDef {
    LocationDef {
        name: name.into(),
        label: label.into(),
        running: running.iter().map(|s| (*s).to_string()).collect(),
        invariant,
    }
}

fn edge(from: &str, to: &str, event: &str, guard: String, reset: &[&str], goal: bool) -> EdgeDef {
    EdgeDef {
        from: from.into(),
        to: to.into(),
        event: event.into(),
        guard,
        reset: reset.iter().map(|s| (*s).to_string()).collect(),
        goal,
    }
}

fn task(t: &TaskSpec, shared: &BTreeSet<&str>) -> ComponentDef {
    let (a, b, g) = (t.alpha, t.beta, t.gamma);
    let y_max = match t.slowdown {
        Slowdown::Strict => b,
        Slowdown::Tolerant => g,
    };
    let inv = if t.interruptible() {
        format!("x <= {g} && y <= {y_max}")
    } else {
        // Remark 3: a non-interruptible task has the one window [α, γ) on its time.
        format!("x <= {g}")
    };
    let mut locations = vec![
        loc("idle", "idle", &[], "true".into()),
        loc("run", "running", &["x", "y"], inv.clone()),
    ];
    let mut edges = vec![edge(
        "idle",
        "run",
        &t.start,
        "true".into(),
        &["x", "y"],
        false,
    )];
    let mut progress = vec!["run".to_string()];
    match &t.interruption {
        Some((i, r)) => {
            locations.push(loc("int", "interrupted", &["x"], inv));
            progress.push("int".into());
            edges.push(edge("run", "int", i, format!("x < {g}"), &[], false));
            edges.push(edge("int", "run", r, format!("x < {g}"), &[], false));
            for (event, elsewhere) in [(i, ["idle", "int"]), (r, ["idle", "run"])] {
                if shared.contains(event.as_str()) {
                    for l in elsewhere {
                        edges.push(edge(l, l, event, "true".into(), &[], false));
                    }
                }
            }
            edges.push(edge(
                "run",
                "idle",
                &t.end,
                format!("{a} <= x < {g} && {a} <= y <= {y_max}"),
                &["x", "y"],
                true,
            ));
        }
        None => {
            edges.push(edge(
                "run",
                "idle",
                &t.end,
                format!("{a} <= x < {g} && x - y == 0"),
                &["x", "y"],
                true,
            ));
        }
    }
    ComponentDef {
        name: t.id.clone(),
        clocks: vec!["x".into(), "y".into()],
        initial: "idle".into(),
        progress,
        locations,
        edges,
    }
}

fn window(w: &WindowDef) -> ComponentDef {
    let mut edges = Vec::new();
    for ev in &w.open {
        edges.push(edge("closed", "open", ev, "true".into(), &["w"], false));
        edges.push(edge("open", "open", ev, "true".into(), &["w"], false));
    }
    for ev in &w.close {
        edges.push(edge(
            "open",
            "closed",
            ev,
            format!("{} <= w <= {}", w.min_ms, w.max_ms),
            &["w"],
            true,
        ));
        edges.push(edge("closed", "closed", ev, "true".into(), &[], false));
    }
    ComponentDef {
        name: w.id.clone(),
        clocks: vec!["w".into()],
        initial: if w.open_at_start { "open" } else { "closed" }.into(),
        progress: vec!["open".into()],
        locations: vec![
            loc("closed", "closed", &[], "true".into()),
            loc("open", "open", &["w"], format!("w <= {}", w.max_ms)),
        ],
        edges,
    }
}

/// The components of a task set: its tasks, then its windows.
pub fn automata(set: &TaskSet) -> SwaFile {
    // The events each component observes, and those observed by more than one.
    let alphabets: Vec<BTreeSet<&str>> = set
        .tasks
        .iter()
        .map(|t| {
            let mut a = BTreeSet::from([t.start.as_str(), t.end.as_str()]);
            if let Some((i, r)) = &t.interruption {
                a.extend([i.as_str(), r.as_str()]);
            }
            a
        })
        .chain(
            set.windows
                .iter()
                .map(|w| w.open.iter().chain(&w.close).map(String::as_str).collect()),
        )
        .collect();
    let mut seen = BTreeSet::new();
    let mut shared = BTreeSet::new();
    for e in alphabets.iter().flatten() {
        if !seen.insert(*e) {
            shared.insert(*e);
        }
    }
    SwaFile {
        components: set
            .tasks
            .iter()
            .map(|t| task(t, &shared))
            .chain(set.windows.iter().map(window))
            .collect(),
    }
}
