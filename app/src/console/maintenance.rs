//! Maintenance: the draft of the control program (the text of every receptivity, step
//! action list and equation), its typed edits, its compilation, and the fix check, which
//! always runs the text on screen and records what it ran.

use super::{Console, FixOutcome, verify_fix};
use std::collections::BTreeMap;
use vigie_core::control::{CompiledProgram, Origin, Program};

/// One edit of the draft, as the program views send it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DraftEdit {
    /// The receptivity of a transition.
    Condition {
        /// Transition id.
        transition: String,
        /// New receptivity text.
        text: String,
    },
    /// The actions of a step (`N A0, S M1, L(500) A2`).
    Actions {
        /// Step id.
        step: String,
        /// New action list text.
        text: String,
    },
    /// The expression of an output equation.
    Equation {
        /// The equation's target.
        target: String,
        /// New expression text.
        text: String,
    },
}

/// What a fix check ran and found: the console keeps the last one on screen.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FixCheck {
    /// The program's name.
    pub program: String,
    /// The version of the program that ran ([`Program::version`]); empty when the
    /// edit did not compile.
    pub version: String,
    /// What differs from the program running in the console (`transition t24`).
    pub changes: Vec<String>,
    /// The scenario re-run (its title in the language shown when checked).
    pub scenario: String,
    /// The verdict.
    pub outcome: FixOutcome,
}

/// Maintenance drafts: the text of every receptivity, step action list and equation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Draft {
    /// Transition id → condition.
    pub conditions: BTreeMap<String, String>,
    /// Step id → actions (`N A0, S M1, L(500) A2`).
    pub actions: BTreeMap<String, String>,
    /// Equations (target, expression).
    pub equations: Vec<(String, String)>,
}

impl Draft {
    /// The draft of a program.
    pub fn of(p: &Program) -> Self {
        Self {
            conditions: p
                .transitions()
                .map(|(_, t)| (t.id.clone(), t.condition.clone()))
                .collect(),
            actions: p
                .steps()
                .map(|(_, s)| {
                    let text: Vec<String> = s
                        .actions
                        .iter()
                        .map(|a| format!("{} {}", a.qualifier, a.target))
                        .collect();
                    (s.id.clone(), text.join(", "))
                })
                .collect(),
            equations: p.equations.clone(),
        }
    }

    /// Applies the draft to `base`.
    pub fn apply(&self, base: &Program) -> Result<Program, String> {
        let mut p = base.clone();
        for chart in &mut p.charts {
            for t in &mut chart.transitions {
                if let Some(c) = self.conditions.get(&t.id) {
                    t.condition.clone_from(c);
                }
            }
            for s in &mut chart.steps {
                if let Some(text) = self.actions.get(&s.id) {
                    s.actions = parse_actions(text).map_err(|e| format!("step {}: {e}", s.id))?;
                }
            }
        }
        p.equations.clone_from(&self.equations);
        Ok(p)
    }
}

/// Parses `N A0, S M1, L(500) A2`.
pub fn parse_actions(text: &str) -> Result<Vec<vigie_core::control::Action>, String> {
    use vigie_core::control::{Action, Qualifier};
    let mut out = Vec::new();
    for part in text
        .split([',', ';'])
        .map(str::trim)
        .filter(|s| !s.is_empty())
    {
        let mut it = part.split_whitespace();
        let (q, target) = match (it.next(), it.next(), it.next()) {
            (Some(q), Some(t), None) => (q, t),
            (Some(t), None, None) => ("N", t),
            _ => return Err(format!("`{part}`: expected QUALIFIER TARGET")),
        };
        let num = |s: &str| -> Result<u64, String> {
            s.trim_end_matches(')')
                .parse::<u64>()
                .map_err(|_| format!("`{part}`: bad duration"))
        };
        let qualifier = match q {
            "N" => Qualifier::N,
            "S" => Qualifier::S,
            "R" => Qualifier::R,
            "P" => Qualifier::P,
            q if q.starts_with("L(") => Qualifier::L(num(&q[2..])?),
            q if q.starts_with("D(") => Qualifier::D(num(&q[2..])?),
            q if q.starts_with("SD(") => Qualifier::SD(num(&q[3..])?),
            q if q.starts_with("DS(") => Qualifier::DS(num(&q[3..])?),
            q if q.starts_with("SL(") => Qualifier::SL(num(&q[3..])?),
            q => {
                return Err(format!(
                    "`{q}`: unknown qualifier (N, S, R, P, L(ms), D(ms), SD(ms), DS(ms), SL(ms))"
                ));
            }
        };
        out.push(Action {
            qualifier,
            target: target.to_string(),
        });
    }
    Ok(out)
}

impl Draft {
    /// Applies one edit; an unknown transition, step or target changes nothing and
    /// says so.
    pub fn edit(&mut self, edit: DraftEdit) -> Result<(), String> {
        let slot = match &edit {
            DraftEdit::Condition { transition, .. } => self.conditions.get_mut(transition),
            DraftEdit::Actions { step, .. } => self.actions.get_mut(step),
            DraftEdit::Equation { target, .. } => self
                .equations
                .iter_mut()
                .find(|(t, _)| t == target)
                .map(|(_, e)| e),
        };
        let (DraftEdit::Condition { text, .. }
        | DraftEdit::Actions { text, .. }
        | DraftEdit::Equation { text, .. }) = &edit;
        match slot {
            Some(s) => {
                s.clone_from(text);
                Ok(())
            }
            None => Err(format!("no such element in the program: {edit:?}")),
        }
    }
}

impl Console {
    /// Applies a typed edit of the draft; the compiled edit is then stale and dropped,
    /// so that nothing runs a text other than the one on screen.
    pub(super) fn edit_draft(&mut self, edit: DraftEdit) {
        if self.draft.is_none() {
            self.enter_maintenance();
        }
        let Some(draft) = self.draft.as_mut() else {
            return;
        };
        match draft.edit(edit) {
            Ok(()) => {
                self.compiled_edit = None;
                self.problems.clear();
            }
            Err(e) => self.status = e,
        }
    }

    /// Compiles the draft against the running program.
    pub(super) fn recompile(&mut self) {
        let Some(draft) = &self.draft else {
            return;
        };
        let base = self.sim.program.program().program.clone();
        let result = draft.apply(&base).and_then(|p| {
            CompiledProgram::new(&p, &self.sim.bundle.plant, &Origin::default())
                .map_err(|e| vigie_core::diag::render(&e))
        });
        match result {
            Ok(c) => {
                let diff = vigie_core::control::differences(&base, &c.program);
                self.problems = if diff.is_empty() {
                    "compiled: no change".into()
                } else {
                    format!("compiled: {}", diff.join("; "))
                };
                self.compiled_edit = Some(c);
                self.say(None, "say-compiled", &[]);
            }
            Err(e) => {
                self.problems = e;
                self.compiled_edit = None;
                self.say(None, "say-compile-failed", &[]);
            }
        }
        let text = self.status.clone();
        self.journal.push(self.now().0, "maintenance", &text);
    }

    /// The compiled text on screen: compiled now, every time, so that a restart or a
    /// fix check never runs an earlier edit.
    pub(super) fn compile_on_screen(&mut self) -> Option<CompiledProgram> {
        if self.draft.is_none() {
            self.enter_maintenance();
        }
        self.recompile();
        self.compiled_edit.clone()
    }

    /// Writes the program on screen (the edits compiled) as PLCopen XML to `path` (an
    /// empty path: `<program>-<version>.xml`; relative: under the data folder), for the
    /// PLC's own tool; says and journals what was written, or why not.
    pub(super) fn export_program(&mut self, path: &std::path::Path, now: u64) {
        let Some(program) = self.compile_on_screen() else {
            self.say(
                None,
                "say-program-export-refused",
                &[("problems", self.problems.len().to_string())],
            );
            return;
        };
        let p = &program.program;
        let path = if path.as_os_str().is_empty() {
            let slug: String = p
                .name
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
                .collect();
            self.export_path(std::path::Path::new(&format!("{slug}-{}.xml", p.version())))
        } else {
            self.export_path(path)
        };
        let path = path.as_path();
        let written = vigie_core::plcopen::export(p, &self.sim.bundle.plant, path)
            .map_err(|e| vigie_core::diag::render(&e))
            .and_then(|xml| {
                if let Some(dir) = path.parent() {
                    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
                }
                std::fs::write(path, xml).map_err(|e| e.to_string())
            });
        match written {
            Ok(()) => self.say(
                Some(("maintenance", now)),
                "say-program-exported",
                &[
                    ("name", p.name.clone()),
                    ("version", p.version()),
                    ("path", path.display().to_string()),
                ],
            ),
            Err(e) => self.say(
                None,
                "say-program-export-failed",
                &[("path", path.display().to_string()), ("error", e)],
            ),
        }
    }

    /// Re-runs the scenario with the text on screen, scores it and keeps what ran.
    pub(super) fn verify(&mut self) {
        let base: Program = self.sim.program.program().program.clone();
        let scenario = self.source.title(&self.i18n);
        let Some(program) = self.compile_on_screen() else {
            self.last_fix = Some(FixCheck {
                program: base.name.clone(),
                version: String::new(),
                changes: Vec::new(),
                scenario,
                outcome: FixOutcome::CannotRun(self.problems.clone()),
            });
            self.say(None, "say-nothing-to-verify", &[]);
            return;
        };
        let version = program.program.version();
        let changes = vigie_core::control::differences(&base, &program.program);
        let outcome = verify_fix(&self.source.scenario, &self.source.path, program);
        if self.score.variant.is_none() {
            self.score.variant = Some(self.source.scenario.name.clone());
        }
        self.score.record(&outcome, self.wall_s);
        let fixed = outcome.is_fixed();
        let (id, mut args) = outcome.message();
        args.push(("version", version.clone()));
        self.last_fix = Some(FixCheck {
            program: base.name.clone(),
            version,
            changes,
            scenario,
            outcome,
        });
        if fixed && !self.score.revealed {
            self.finish_exercise(true);
        }
        // The verdict is the status line's last word.
        self.say(Some(("training", self.now().0)), id, &args);
    }

    /// Ends the exercise: the debrief shows the answer, and the trainee's history
    /// records it (fixed, or given up when `fixed` is false).
    pub(super) fn finish_exercise(&mut self, fixed: bool) {
        let Some(exercise) = self.exercise_id().map(str::to_string) else {
            self.say(None, "say-no-exercise", &[]);
            return;
        };
        if self.score.revealed {
            return;
        }
        self.score.revealed = true;
        let levels: Vec<String> = self.score.levels.iter().map(ToString::to_string).collect();
        let record = super::ScoreRecord {
            wall_ms: crate::historian::wall_ms(),
            user: self.user.clone().unwrap_or_else(|| "-".to_string()),
            exercise: exercise.clone(),
            fixed,
            attempts: self.score.attempts,
            levels: levels.join(" "),
            seconds: self.score.located_after_s,
        };
        let result = self.history.push(record);
        let id = if fixed {
            "say-exercise-fixed"
        } else {
            "say-exercise-given-up"
        };
        self.say(Some(("training", self.now().0)), id, &[("id", exercise)]);
        if let Err(e) = result {
            self.say(None, "say-history-unwritable", &[("error", e.to_string())]);
        }
    }
}
