//! Single-place edits of a program ([`Patch`]) and the library of erroneous variants
//! of a reference program (`programs/errors.ron`).

use super::program::{Action, CompiledProgram, Origin, Program, Step};
use crate::diag::codes;
use crate::diag::{Location, Problem, ron_problem};
use crate::plant::Plant;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One edit of a program, in one place.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Patch {
    /// Replaces the receptivity of a transition.
    Condition {
        /// Transition id.
        transition: String,
        /// The new receptivity.
        condition: String,
    },
    /// Replaces the action of `step` that drives `target`.
    ReplaceAction {
        /// Step id.
        step: String,
        /// The target of the action replaced.
        target: String,
        /// The new action.
        action: Action,
    },
    /// Removes the action of `step` that drives `target`.
    RemoveAction {
        /// Step id.
        step: String,
        /// The target of the action removed.
        target: String,
    },
    /// Adds an action to `step`.
    AddAction {
        /// Step id.
        step: String,
        /// The new action.
        action: Action,
    },
    /// Moves the action of step `from` that drives `target` to step `to` (an action
    /// written in the wrong step); `to` must not act on `target` already.
    MoveAction {
        /// The step the action belongs to.
        from: String,
        /// The step it is moved to.
        to: String,
        /// The target of the action moved.
        target: String,
    },
    /// Replaces (or adds) the equation of `target`.
    Equation {
        /// Actuator or memory.
        target: String,
        /// The new expression.
        expression: String,
    },
}

impl Patch {
    /// The patched copy of `program`, or a message when the place does not exist.
    pub fn apply(&self, program: &Program) -> Result<Program, String> {
        let mut p = program.clone();
        match self {
            Patch::Condition {
                transition,
                condition,
            } => {
                let t = p
                    .charts
                    .iter_mut()
                    .flat_map(|c| c.transitions.iter_mut())
                    .find(|t| t.id == *transition)
                    .ok_or_else(|| format!("no transition `{transition}`"))?;
                t.condition = condition.clone();
            }
            Patch::ReplaceAction { step, target, .. } | Patch::RemoveAction { step, target } => {
                let s = find_step(&mut p, step)?;
                let k = s
                    .actions
                    .iter()
                    .position(|a| a.target == *target)
                    .ok_or_else(|| format!("step `{step}` has no action on `{target}`"))?;
                if let Patch::ReplaceAction { action, .. } = self {
                    s.actions[k] = action.clone();
                } else {
                    s.actions.remove(k);
                }
            }
            Patch::AddAction { step, action } => {
                find_step(&mut p, step)?.actions.push(action.clone());
            }
            Patch::MoveAction { from, to, target } => {
                let s = find_step(&mut p, from)?;
                let k = s
                    .actions
                    .iter()
                    .position(|a| a.target == *target)
                    .ok_or_else(|| format!("step `{from}` has no action on `{target}`"))?;
                let action = s.actions.remove(k);
                let d = find_step(&mut p, to)?;
                if from == to || d.actions.iter().any(|a| a.target == *target) {
                    return Err(format!("step `{to}` already acts on `{target}`"));
                }
                d.actions.push(action);
            }
            Patch::Equation { target, expression } => {
                match p.equations.iter_mut().find(|e| e.0 == *target) {
                    Some(e) => e.1 = expression.clone(),
                    None => p.equations.push((target.clone(), expression.clone())),
                }
            }
        }
        Ok(p)
    }
}

fn find_step<'a>(p: &'a mut Program, id: &str) -> Result<&'a mut Step, String> {
    p.charts
        .iter_mut()
        .flat_map(|c| c.steps.iter_mut())
        .find(|s| s.id == id)
        .ok_or_else(|| format!("no step `{id}`"))
}

/// The places where two programs differ: transitions (`transition t24`), step actions
/// (`step X24`), equations (`equation A1`), or anything else (`declarations`).
pub fn differences(a: &Program, b: &Program) -> Vec<String> {
    let mut out = Vec::new();
    let ta: Vec<_> = a.transitions().collect();
    let tb: Vec<_> = b.transitions().collect();
    let sa: Vec<_> = a.steps().collect();
    let sb: Vec<_> = b.steps().collect();
    let same_shape = ta.len() == tb.len()
        && sa.len() == sb.len()
        && ta
            .iter()
            .zip(&tb)
            .all(|(x, y)| x.1.id == y.1.id && x.1.from == y.1.from && x.1.to == y.1.to)
        && sa
            .iter()
            .zip(&sb)
            .all(|(x, y)| x.1.id == y.1.id && x.1.initial == y.1.initial);
    if !same_shape
        || a.panel != b.panel
        || a.memories != b.memories
        || a.timers != b.timers
        || a.charts.len() != b.charts.len()
    {
        out.push("declarations".to_string());
        return out;
    }
    for (x, y) in ta.iter().zip(&tb) {
        if x.1.condition != y.1.condition {
            out.push(format!("transition {}", x.1.id));
        }
    }
    for (x, y) in sa.iter().zip(&sb) {
        if x.1.actions != y.1.actions {
            out.push(format!("step {}", x.1.id));
        }
    }
    let mut targets: Vec<&String> = a
        .equations
        .iter()
        .chain(&b.equations)
        .map(|e| &e.0)
        .collect();
    targets.sort();
    targets.dedup();
    for t in targets {
        let ea = a.equations.iter().find(|e| e.0 == *t);
        let eb = b.equations.iter().find(|e| e.0 == *t);
        if ea != eb {
            out.push(format!("equation {t}"));
        }
    }
    out
}

/// One variant as written in `errors.ron`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VariantDef {
    /// Identifier (`E01`).
    pub id: String,
    /// The mistake, in words.
    pub description: String,
    /// The constraint the filter should trip on in closed loop.
    pub expected_constraint: String,
    /// The edit of the reference program.
    pub patch: Patch,
    /// What happens without the filter (default: a hazard, the plant is damaged).
    #[serde(default)]
    pub consequence: Consequence,
}

/// What an erroneous program does to the plant when no filter stops it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Consequence {
    /// A dangerous state: a box or the plant is damaged.
    #[default]
    Hazard,
    /// No damage, but the sequence the specification wants is broken (the paper's
    /// "contradict the desired sequencing"): production stops or goes wrong.
    Functional,
}

/// The errors file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorsFile {
    /// The reference program file, relative to the errors file.
    pub reference: String,
    /// The variants.
    pub variants: Vec<VariantDef>,
}

/// One erroneous program.
#[derive(Clone, Debug)]
pub struct Variant {
    /// The definition.
    pub def: VariantDef,
    /// The patched program.
    pub program: Program,
    /// The patched program, compiled.
    pub compiled: CompiledProgram,
}

/// The reference program and its erroneous variants.
#[derive(Clone, Debug)]
pub struct ErrorLibrary {
    /// The reference file.
    pub reference_file: PathBuf,
    /// The reference program.
    pub reference: Program,
    /// The variants, in file order.
    pub variants: Vec<Variant>,
}

impl ErrorLibrary {
    /// Loads `errors.ron` and its reference program, applies and compiles every patch.
    pub fn load(path: &Path, plant: &Plant) -> Result<Self, Vec<Problem>> {
        let read = |p: &Path| crate::diag::read_text(p).map_err(|problem| vec![problem]);
        let text = read(path)?;
        let file: ErrorsFile = ron::from_str(&text).map_err(|e| vec![ron_problem(path, &e)])?;
        let reference_file = path
            .parent()
            .unwrap_or_else(|| Path::new("."))
            .join(&file.reference);
        let ref_text = read(&reference_file)?;
        let reference = Program::from_ron(&ref_text, &reference_file)?;
        CompiledProgram::new(&reference, plant, &Origin::new(&reference_file, &ref_text))?;
        let origin = Origin::new(path, &text);
        let mut problems = Vec::new();
        let mut variants = Vec::new();
        let mut ids = std::collections::BTreeSet::new();
        for def in file.variants {
            let loc = Location::of_nth(path, &text, &format!("\"{}\"", def.id), 0);
            if !ids.insert(def.id.clone()) {
                problems.push(Problem::error(
                    codes::LIBRARY_VARIANT_DUPLICATE.id,
                    format!("variant `{}` is declared twice", def.id),
                    Some(loc),
                ));
                continue;
            }
            let program = match def.patch.apply(&reference) {
                Ok(p) => p,
                Err(m) => {
                    problems.push(Problem::error(
                        codes::LIBRARY_VARIANT_INVALID.id,
                        format!("variant `{}`: {m}", def.id),
                        Some(loc),
                    ));
                    continue;
                }
            };
            match CompiledProgram::new(&program, plant, &origin) {
                Ok(compiled) => variants.push(Variant {
                    def,
                    program,
                    compiled,
                }),
                Err(ps) => problems.extend(ps.into_iter().map(|mut p| {
                    p.message = format!("variant `{}`: {}", def.id, p.message);
                    if p.location.as_ref().is_none_or(|l| l.line == 1) {
                        p.location = Some(loc.clone());
                    }
                    p
                })),
            }
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        Ok(Self {
            reference_file,
            reference,
            variants,
        })
    }
}
