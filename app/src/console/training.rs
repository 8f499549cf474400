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
    /// The exercise is over (fixed, or the answer asked for): the debrief shows the
    /// answer.
    pub revealed: bool,
    /// Plant-fault exercise: the components the trainee named, in order, and whether
    /// each was right.
    pub diagnoses: Vec<(String, bool)>,
    /// A plant-fault exercise (the result is a component found, not a fix).
    pub plant: bool,
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

    /// The levels consulted (`0, 4`), or "none" in the language `i18n` shows.
    pub fn levels_in(&self, i18n: &I18n) -> String {
        if self.levels.is_empty() {
            return i18n.t("score-none");
        }
        let levels: Vec<String> = self.levels.iter().map(ToString::to_string).collect();
        levels.join(", ")
    }

    /// One line summary, in English.
    pub fn summary(&self) -> String {
        I18n::new(Lang::En, None).map_or_else(|e| e.to_string(), |i| self.summary_in(&i))
    }

    /// One line summary, in the language `i18n` shows.
    pub fn summary_in(&self, i18n: &I18n) -> String {
        let levels = self.levels_in(i18n);
        let result = match (self.fixed, self.located_after_s, self.plant) {
            (true, Some(s), true) => {
                i18n.ta("score-found-in", &[("s", (&format!("{s:.0}")).into())])
            }
            (true, Some(s), false) => {
                i18n.ta("score-fixed-in", &[("s", (&format!("{s:.0}")).into())])
            }
            (true, None, true) => i18n.t("score-found"),
            (true, None, false) => i18n.t("score-fixed"),
            (false, _, true) => i18n.t("score-not-found"),
            (false, _, false) => i18n.t("score-not-fixed"),
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
    let delivered = stats.delivered_total();
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
            .map(|h| format!("{} ({} ms)", h.summary(), h.time_ms))
            .collect();
        FixOutcome::NotFixed { trips, hazards }
    }
}

/// One element of an exercise's correct fix: the element, the exercise's text and the
/// reference program's.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FixLine {
    /// `t24`, `X24`, `A0`.
    pub element: String,
    /// The exercise's (erroneous) text.
    pub wrong: String,
    /// The reference program's text.
    pub right: String,
}

/// The elements where `variant` differs from `reference`: the debrief's correct fix.
pub fn correct_fix(
    reference: &vigie_core::control::Program,
    variant: &vigie_core::control::Program,
) -> Vec<FixLine> {
    let (r, v) = (super::Draft::of(reference), super::Draft::of(variant));
    let mut out = Vec::new();
    let mut map = |a: &std::collections::BTreeMap<String, String>,
                   b: &std::collections::BTreeMap<String, String>| {
        for (k, right) in a {
            let wrong = b.get(k).cloned().unwrap_or_default();
            if &wrong != right {
                out.push(FixLine {
                    element: k.clone(),
                    wrong,
                    right: right.clone(),
                });
            }
        }
    };
    map(&r.conditions, &v.conditions);
    map(&r.actions, &v.actions);
    let eq = |d: &super::Draft| d.equations.iter().cloned().collect();
    map(&eq(&r), &eq(&v));
    out
}

/// A finished exercise, as kept in the training history.
#[derive(Clone, Debug, PartialEq)]
pub struct ScoreRecord {
    /// Wall-clock time of the end, ms since the Unix epoch.
    pub wall_ms: u64,
    /// The trainee (the logged-in user, `-` when nobody is).
    pub user: String,
    /// The exercise (`E01`).
    pub exercise: String,
    /// Fixed (a verified correct fix) or given up (the answer asked for).
    pub fixed: bool,
    /// Fix checks.
    pub attempts: u32,
    /// Levels consulted, `0 4`.
    pub levels: String,
    /// Seconds from the trip to the correct fix.
    pub seconds: Option<f64>,
}

const HISTORY_HEADER: &str = "wall_ms,user,exercise,fixed,attempts,levels,seconds";

/// The training history: one CSV file in the data folder, appended to at the end of
/// each exercise (in memory only without a data folder).
#[derive(Clone, Debug, Default)]
pub struct History {
    path: Option<std::path::PathBuf>,
    /// The records, oldest first.
    pub records: Vec<ScoreRecord>,
    /// Lines of the file that could not be read (`line 3: …`), kept as written.
    pub unreadable: Vec<String>,
}

impl History {
    /// Reads `training.csv` of `data_dir` (none yet: empty).
    pub fn load(data_dir: Option<&Path>) -> Self {
        let path = data_dir.map(|d| d.join("training.csv"));
        let mut h = Self {
            path: path.clone(),
            ..Self::default()
        };
        let Some(text) = path.and_then(|p| std::fs::read_to_string(p).ok()) else {
            return h;
        };
        for (n, line) in text.lines().enumerate().skip(1) {
            match parse_record(line) {
                Some(r) => h.records.push(r),
                None => h.unreadable.push(format!("line {}: {line}", n + 1)),
            }
        }
        h
    }

    /// Appends a record, to the file first.
    pub fn push(&mut self, r: ScoreRecord) -> std::io::Result<()> {
        if let Some(path) = &self.path {
            use std::io::Write as _;
            let new = !path.exists();
            let mut f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(path)?;
            if new {
                writeln!(f, "{HISTORY_HEADER}")?;
            }
            writeln!(f, "{}", record_line(&r))?;
            f.sync_data()?;
        }
        self.records.push(r);
        Ok(())
    }

    /// The records of `user`, newest first.
    pub fn of<'a>(&'a self, user: &'a str) -> impl Iterator<Item = &'a ScoreRecord> + 'a {
        self.records.iter().rev().filter(move |r| r.user == user)
    }
}

/// Commas and line breaks cannot occur in a user name or an exercise id of the files
/// Vigie reads; they are replaced anyway so that a line stays one record.
fn clean(s: &str) -> String {
    s.replace([',', '\n', '\r'], " ")
}

fn record_line(r: &ScoreRecord) -> String {
    format!(
        "{},{},{},{},{},{},{}",
        r.wall_ms,
        clean(&r.user),
        clean(&r.exercise),
        r.fixed,
        r.attempts,
        clean(&r.levels),
        r.seconds.map_or(String::new(), |s| format!("{s:.0}"))
    )
}

fn parse_record(line: &str) -> Option<ScoreRecord> {
    let f: Vec<&str> = line.split(',').collect();
    let [wall, user, exercise, fixed, attempts, levels, seconds] = f.as_slice() else {
        return None;
    };
    Some(ScoreRecord {
        wall_ms: wall.parse().ok()?,
        user: (*user).to_string(),
        exercise: (*exercise).to_string(),
        fixed: fixed.parse().ok()?,
        attempts: attempts.parse().ok()?,
        levels: (*levels).to_string(),
        seconds: if seconds.is_empty() {
            None
        } else {
            Some(seconds.parse().ok()?)
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_history_survives_a_restart_and_keeps_unreadable_lines_apart() {
        let dir = std::env::temp_dir().join(format!("vigie-history-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut h = History::load(Some(&dir));
        assert!(h.records.is_empty());
        let r = ScoreRecord {
            wall_ms: 1_700_000_000_000,
            user: "ana, trainee".into(),
            exercise: "E01".into(),
            fixed: true,
            attempts: 2,
            levels: "0 4".into(),
            seconds: Some(42.4),
        };
        h.push(r.clone()).unwrap();
        h.push(ScoreRecord {
            fixed: false,
            seconds: None,
            exercise: "E05".into(),
            ..r.clone()
        })
        .unwrap();
        // A line damaged by hand.
        let path = dir.join("training.csv");
        let mut text = std::fs::read_to_string(&path).unwrap();
        text.push_str("garbage,line\n");
        std::fs::write(&path, text).unwrap();
        let back = History::load(Some(&dir));
        assert_eq!(back.records.len(), 2);
        assert_eq!(back.records[0].user, "ana  trainee");
        assert_eq!(back.records[0].seconds, Some(42.0));
        assert_eq!(back.records[1].seconds, None);
        assert!(!back.records[1].fixed);
        assert_eq!(back.unreadable, ["line 4: garbage,line"]);
        assert_eq!(back.of("ana  trainee").next().unwrap().exercise, "E05");
        assert_eq!(back.of("bob").count(), 0);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
