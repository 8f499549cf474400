//! Training: the score of a session (time to locate the error, levels consulted, correct
//! fix) and the check of a fix by a re-run of the scenario.

use crate::i18n::{I18n, Lang};
use std::collections::BTreeSet;

use std::path::Path;
use vigie_core::control::CompiledProgram;
use vigie_core::sim::{Options, Scenario, Simulation};
use vigie_core::time::Millis;

/// The score of a training session.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Score {
    /// The control-error variant being trained on.
    pub variant: Option<String>,
    /// Console wall time of the first trip, s.
    pub trip_wall_s: Option<f64>,
    /// Explanation levels consulted.
    pub levels: BTreeSet<usize>,
    /// Seconds from the trip to the first correct fix.
    pub located_after_s: Option<f64>,
    /// Fix attempts.
    pub attempts: u32,
    /// The last verification passed.
    pub fixed: bool,
}

impl Score {
    /// Records a verification outcome.
    pub fn record(&mut self, outcome: &FixOutcome, wall_s: f64) {
        self.attempts += 1;
        self.fixed = outcome.is_fixed();
        if self.fixed && self.located_after_s.is_none() {
            self.located_after_s = Some(wall_s - self.trip_wall_s.unwrap_or(0.0));
        }
    }

    /// One line summary, in English.
    pub fn summary(&self) -> String {
        I18n::new(Lang::En, None).map_or_else(|e| e.to_string(), |i| self.summary_in(&i))
    }

    /// One line summary, in the language `i18n` shows.
    pub fn summary_in(&self, i18n: &I18n) -> String {
        let levels: Vec<String> = self.levels.iter().map(ToString::to_string).collect();
        let levels = if levels.is_empty() {
            i18n.t("score-none")
        } else {
            levels.join(", ")
        };
        let result = match (self.fixed, self.located_after_s) {
            (true, Some(s)) => i18n.ta("score-fixed-in", &[("s", (&format!("{s:.0}")).into())]),
            (true, None) => i18n.t("score-fixed"),
            (false, _) => i18n.t("score-not-fixed"),
        };
        i18n.ta(
            "score-summary",
            &[
                ("levels", (&levels).into()),
                ("attempts", self.attempts.into()),
                ("result", (&result).into()),
            ],
        )
    }
}

/// What the re-run of a fix found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FixOutcome {
    /// The scenario could not be re-run (the rendered problems).
    CannotRun(String),
    /// No trip, no hazard, and no box delivered either.
    NothingDelivered,
    /// No trip and no hazard over `s` seconds, `delivered` boxes delivered.
    Fixed {
        /// Length of the re-run, s.
        s: u64,
        /// Boxes delivered.
        delivered: u64,
    },
    /// The re-run still trips or damages.
    NotFixed {
        /// The constraints that tripped.
        trips: Vec<String>,
        /// The hazards (`Sheared of box 1 at 11756 ms`).
        hazards: Vec<String>,
    },
}

impl FixOutcome {
    /// True for a correct fix.
    pub fn is_fixed(&self) -> bool {
        matches!(self, Self::Fixed { .. })
    }

    /// The message that tells it (`fix-…`) and its arguments.
    pub fn message(&self) -> (&'static str, Vec<(&'static str, String)>) {
        match self {
            Self::CannotRun(e) => ("fix-cannot-run", vec![("error", e.clone())]),
            Self::NothingDelivered => ("fix-nothing-delivered", Vec::new()),
            Self::Fixed { s, delivered } => (
                "fix-correct",
                vec![("s", s.to_string()), ("delivered", delivered.to_string())],
            ),
            Self::NotFixed { trips, hazards } => (
                "fix-not-fixed",
                vec![("trips", trips.join(", ")), ("hazards", hazards.join("; "))],
            ),
        }
    }
}

/// Re-runs `scenario` headless with `program` for its duration (at least 60 s) and tells
/// whether the filter still trips or a hazard occurs.
pub fn verify_fix(scenario: &Scenario, path: &Path, program: CompiledProgram) -> FixOutcome {
    let options = Options {
        history_cycles: 2_000,
        explain: false,
    };
    let mut sim = match Simulation::from_scenario(scenario, path, options) {
        Ok(s) => s,
        Err(p) => return FixOutcome::CannotRun(vigie_core::diag::render(&p)),
    };
    sim.replace_program(program);
    sim.run_until(Millis(scenario.duration_ms.max(60_000)));
    let trips: Vec<String> = sim
        .engine
        .trips
        .iter()
        .flat_map(|t| t.constraints.iter().map(|c| c.id.clone()))
        .collect();
    let stats = sim.emulator.stats();
    let delivered = stats.delivered_left + stats.delivered_right;
    if trips.is_empty() && sim.emulator.hazards().is_empty() {
        if delivered == 0 {
            return FixOutcome::NothingDelivered;
        }
        FixOutcome::Fixed {
            s: sim.now().0 / 1000,
            delivered: u64::from(delivered),
        }
    } else {
        let hazards: Vec<String> = sim
            .emulator
            .hazards()
            .iter()
            .map(|h| format!("{:?} of box {} at {} ms", h.kind, h.box_id, h.time_ms))
            .collect();
        FixOutcome::NotFixed { trips, hazards }
    }
}
