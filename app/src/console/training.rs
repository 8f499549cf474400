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
    pub fn record(&mut self, outcome: String, wall_s: f64) {
        self.attempts += 1;
        self.fixed = outcome.starts_with("correct fix");
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

/// Re-runs `scenario` headless with `program` for its duration (at least 60 s) and tells
/// whether the filter still trips or a hazard occurs.
pub fn verify_fix(scenario: &Scenario, path: &Path, program: CompiledProgram) -> String {
    let options = Options {
        history_cycles: 2_000,
        explain: false,
    };
    let mut sim = match Simulation::from_scenario(scenario, path, options) {
        Ok(s) => s,
        Err(p) => return format!("cannot re-run: {}", vigie_core::diag::render(&p)),
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
            return "not fixed: no trip but no box was delivered in the re-run".into();
        }
        format!(
            "correct fix: no trip and no hazard in {} s, {delivered} boxes delivered",
            sim.now().0 / 1000
        )
    } else {
        let hazards: Vec<String> = sim
            .emulator
            .hazards()
            .iter()
            .map(|h| format!("{:?} of box {} at {} ms", h.kind, h.box_id, h.time_ms))
            .collect();
        format!(
            "not fixed: the re-run has trips [{}] and hazards [{}]",
            trips.join(", "),
            hazards.join("; ")
        )
    }
}
