//! Safety constraints: the text file, classification (simple / combined) and static checks.
//!
//! A constraint is a logic function that must stay 0 at the end of every PLC cycle
//! (seed 004, equations (1)-(4)). The file holds one per line, `ID = expression`, in the
//! notation of [`crate::expr`]; `#` starts a comment.

use crate::diag::codes;
use crate::diag::{Location, Problem};
use crate::expr::{self, Dnf, Expr, Span};
use crate::symbols::{Literal, Space, Symbols};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Simple constraints act on exactly one output at t, combined ones on several.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Class {
    /// One output at t (the paper's CSs).
    Simple,
    /// Several outputs at t (the paper's CSc).
    Combined,
}

/// One loaded constraint.
#[derive(Clone, Debug)]
pub struct Constraint {
    /// Identifier as written (`CSs10`).
    pub id: String,
    /// The expression text as written.
    pub source: String,
    /// Parsed expression (kept for rendering and for the cooperation rewrite).
    pub expr: Expr,
    /// Sum of products, contradictory and absorbed terms removed.
    pub dnf: Dnf,
    /// Simple or combined.
    pub class: Class,
    /// Outputs read at t, ascending.
    pub outputs: Vec<u32>,
    /// Where the constraint is written.
    pub location: Location,
    /// What it protects, in the operator's words: the comment after `#` on its line,
    /// without a leading reference such as the paper's equation number `(18)`; empty
    /// when the line has no comment.
    pub description: String,
}

/// The constraints of a plant, in file order.
#[derive(Clone, Debug, Default)]
pub struct ConstraintSet {
    /// Constraints in file order.
    pub constraints: Vec<Constraint>,
}

impl ConstraintSet {
    /// Parses a constraint file. Lines with errors are reported and skipped; the rest
    /// is returned, so one bad line does not hide the others.
    pub fn parse(text: &str, file: &Path, symbols: &Symbols) -> (Self, Vec<Problem>) {
        Self::parse_kind(text, file, symbols, SetKind::Constraints)
    }

    /// Parses an invariants file (same notation): situations the plant cannot reach, each
    /// an expression that is 0 in every reachable state. They read inputs, observers,
    /// auxiliaries and previous outputs, never outputs at t.
    pub fn parse_invariants(text: &str, file: &Path, symbols: &Symbols) -> (Self, Vec<Problem>) {
        Self::parse_kind(text, file, symbols, SetKind::Invariants)
    }

    fn parse_kind(
        text: &str,
        file: &Path,
        symbols: &Symbols,
        kind: SetKind,
    ) -> (Self, Vec<Problem>) {
        let mut set = Self::default();
        let mut problems = Vec::new();
        let mut seen: BTreeMap<String, usize> = BTreeMap::new();
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let (content, comment) = raw.split_once('#').unwrap_or((raw, ""));
            if content.trim().is_empty() {
                continue;
            }
            let at = |col: usize| Some(Location::new(file, line_no, col));
            let Some(eq) = content.find('=') else {
                let col = first_non_space_col(content);
                problems.push(Problem::error(
                    codes::CONSTRAINT_LINE_INVALID.id,
                    format!("expected `ID = expression`, found `{}`", content.trim()),
                    at(col),
                ));
                continue;
            };
            let id = content[..eq].trim();
            let id_col = first_non_space_col(&content[..eq]);
            if !crate::plant::is_valid_name(id) {
                problems.push(Problem::error(
                    codes::CONSTRAINT_LINE_INVALID.id,
                    format!("`{id}` is not a valid constraint id"),
                    at(id_col),
                ));
                continue;
            }
            if let Some(first) = seen.get(id) {
                problems.push(Problem::error(
                    codes::CONSTRAINT_DUPLICATE.id,
                    format!("constraint `{id}` is already defined on line {first}"),
                    at(id_col),
                ));
                continue;
            }
            let rhs = &content[eq + 1..];
            let rhs_col = content[..=eq].chars().count() + 1;
            let source = rhs.trim().to_string();
            let parsed = expr::parse(
                rhs,
                Span {
                    line: line_no,
                    column: rhs_col,
                },
            )
            .and_then(|e| e.to_dnf(symbols).map(|d| (e, d)));
            let (expr, raw_dnf) = match parsed {
                Ok(v) => v,
                Err(err) => {
                    problems.push(Problem::error(
                        codes::CONSTRAINT_SYNTAX.id,
                        err.message,
                        at(err.span.column),
                    ));
                    continue;
                }
            };
            seen.insert(id.to_string(), line_no);
            let location = Location::new(file, line_no, id_col);
            match Constraint::build(id, source, expr, &raw_dnf, location, symbols, kind) {
                Ok((mut c, mut warnings)) => {
                    problems.append(&mut warnings);
                    c.description = description_of(comment);
                    set.constraints.push(c);
                }
                Err(p) => problems.push(p),
            }
        }
        (set, problems)
    }

    /// Loads and parses a constraint file from disk.
    pub fn load(path: &Path, symbols: &Symbols) -> (Self, Vec<Problem>) {
        Self::load_kind(path, symbols, SetKind::Constraints)
    }

    /// Loads an invariants file; a missing file means no invariant.
    pub fn load_invariants(path: &Path, symbols: &Symbols) -> (Self, Vec<Problem>) {
        if !path.exists() {
            return (Self::default(), Vec::new());
        }
        Self::load_kind(path, symbols, SetKind::Invariants)
    }

    /// Reads in bounded memory ([`crate::diag::read_text`]: a file larger than
    /// [`crate::diag::MAX_FILE_BYTES`] is a `V0003` problem, not read).
    fn load_kind(path: &Path, symbols: &Symbols, kind: SetKind) -> (Self, Vec<Problem>) {
        match crate::diag::read_text(path) {
            Ok(text) => Self::parse_kind(&text, path, symbols, kind),
            Err(p) => (Self::default(), vec![p]),
        }
    }

    /// A constraint by id.
    pub fn get(&self, id: &str) -> Option<&Constraint> {
        self.constraints.iter().find(|c| c.id == id)
    }

    /// Property (6) of the paper for every output: no two simple constraints force an
    /// output to 0 and to 1 in the same situation. A conflict whose situation is excluded
    /// by `invariants` (unreachable situations) is *discharged*; the others are errors.
    pub fn check_property_6(
        &self,
        symbols: &Symbols,
        invariants: &ConstraintSet,
    ) -> (Vec<Problem>, Vec<Discharged>) {
        let mut problems = Vec::new();
        let mut discharged = Vec::new();
        // For each output k, the terms that force it to 0 (s_k . h0) and to 1 (/s_k . h1).
        // Per output: (constraint index, the term's other literals), to 0 and to 1.
        type Forcing = Vec<(usize, Vec<Literal>)>;
        let mut forcing: BTreeMap<u32, (Forcing, Forcing)> = BTreeMap::new();
        for (ci, c) in self.constraints.iter().enumerate() {
            if c.class != Class::Simple {
                continue;
            }
            for term in &c.dnf {
                let mut h = Vec::new();
                let mut polarity = None;
                for l in term {
                    if l.var.space == Space::Output && !l.var.prev {
                        polarity = Some((l.var.index, l.positive));
                    } else {
                        h.push(*l);
                    }
                }
                if let Some((k, positive)) = polarity {
                    let entry = forcing.entry(k).or_default();
                    if positive {
                        entry.0.push((ci, h));
                    } else {
                        entry.1.push((ci, h));
                    }
                }
            }
        }
        for (k, (zeros, ones)) in &forcing {
            for (c0, h0) in zeros {
                for (c1, h1) in ones {
                    let mut both: Vec<Literal> = h0.iter().chain(h1).copied().collect();
                    both.sort();
                    both.dedup();
                    if expr::is_contradictory(&both) {
                        continue;
                    }
                    let a = &self.constraints[*c0];
                    let b = &self.constraints[*c1];
                    let excluded_by = invariants
                        .constraints
                        .iter()
                        .find(|inv| implies(&both, &inv.dnf))
                        .map(|inv| inv.id.clone());
                    let witness = if both.is_empty() {
                        "any state".to_string()
                    } else {
                        both.iter()
                            .map(|l| {
                                let mut name = symbols.render_literal(Literal {
                                    positive: true,
                                    ..*l
                                });
                                name.push_str(if l.positive { "=1" } else { "=0" });
                                name
                            })
                            .collect::<Vec<_>>()
                            .join(", ")
                    };
                    if let Some(invariant) = excluded_by {
                        discharged.push(Discharged {
                            output: symbols.name(Space::Output, *k).to_string(),
                            forces_zero: a.id.clone(),
                            forces_one: b.id.clone(),
                            witness,
                            invariant,
                        });
                        continue;
                    }
                    problems.push(Problem::error(
                        codes::PROPERTY_6_VIOLATED.id,
                        format!(
                            "property (6) violated for output {}: {} forces it to 0 and {} forces it to 1 when {}",
                            symbols.name(Space::Output, *k),
                            a.id,
                            b.id,
                            witness
                        ),
                        Some(b.location.clone()),
                    ));
                }
            }
        }
        (problems, discharged)
    }
}

/// A logical conflict of property (6) that an invariant shows unreachable.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Discharged {
    /// The output.
    pub output: String,
    /// The constraint forcing it to 0.
    pub forces_zero: String,
    /// The constraint forcing it to 1.
    pub forces_one: String,
    /// The situation where both act.
    pub witness: String,
    /// The invariant that excludes the situation.
    pub invariant: String,
}

/// Whether the product `term` implies the sum of products `dnf` (every assignment that
/// makes `term` true makes `dnf` true). Decided by enumerating the variables of `dnf`
/// that `term` leaves free (at most 16; beyond, answers false).
pub fn implies(term: &[Literal], dnf: &Dnf) -> bool {
    let mut free: Vec<crate::symbols::Var> = dnf
        .iter()
        .flatten()
        .map(|l| l.var)
        .filter(|v| !term.iter().any(|l| l.var == *v))
        .collect();
    free.sort();
    free.dedup();
    if free.len() > 16 || dnf.is_empty() {
        return false;
    }
    (0u32..(1u32 << free.len())).all(|assignment| {
        dnf.iter().any(|t| {
            t.iter().all(|l| {
                let value = term
                    .iter()
                    .find(|x| x.var == l.var)
                    .map(|x| x.positive)
                    .or_else(|| {
                        free.iter()
                            .position(|v| *v == l.var)
                            .map(|i| (assignment >> i) & 1 == 1)
                    })
                    .unwrap_or(false);
                value == l.positive
            })
        })
    })
}

/// Which kind of file is being parsed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SetKind {
    Constraints,
    Invariants,
}

impl Constraint {
    fn build(
        id: &str,
        source: String,
        expr: Expr,
        raw: &Dnf,
        location: Location,
        symbols: &Symbols,
        kind: SetKind,
    ) -> Result<(Self, Vec<Problem>), Problem> {
        let mut warnings = Vec::new();
        let dnf = expr::simplify(raw);
        if kind == SetKind::Invariants {
            if dnf
                .iter()
                .flatten()
                .any(|l| l.var.space == Space::Output && !l.var.prev)
            {
                return Err(Problem::error(
                    codes::INVARIANT_READS_OUTPUT.id,
                    format!(
                        "invariant `{id}` reads an output at t; invariants describe situations of the plant (inputs, observers, previous outputs)"
                    ),
                    Some(location),
                ));
            }
            return Ok((
                Self {
                    id: id.to_string(),
                    source,
                    expr,
                    dnf,
                    class: Class::Simple,
                    outputs: Vec::new(),
                    location,
                    description: String::new(),
                },
                warnings,
            ));
        }
        if dnf.is_empty() {
            warnings.push(Problem::warning(
                codes::CONSTRAINT_NEVER_TRUE.id,
                format!("constraint `{id}` can never be true: it never acts"),
                Some(location.clone()),
            ));
        }
        if dnf.iter().any(Vec::is_empty) || is_tautology(&dnf) {
            return Err(Problem::error(
                codes::CONSTRAINT_ALWAYS_TRUE.id,
                format!(
                    "constraint `{id}` is always true: the filter would stop the plant at once"
                ),
                Some(location),
            ));
        }
        let mut outputs: Vec<u32> = Vec::new();
        for term in &dnf {
            let outs: Vec<u32> = term
                .iter()
                .filter(|l| l.var.space == Space::Output && !l.var.prev)
                .map(|l| l.var.index)
                .collect();
            if outs.is_empty() {
                return Err(Problem::error(
                    codes::CONSTRAINT_NOT_ENFORCEABLE.id,
                    format!(
                        "constraint `{id}` has a term with no output at t ({}): the filter cannot enforce it",
                        expr::render_dnf(std::slice::from_ref(term), symbols)
                    ),
                    Some(location),
                ));
            }
            outputs.extend(outs);
        }
        outputs.sort_unstable();
        outputs.dedup();
        let class = if outputs.len() == 1 {
            Class::Simple
        } else {
            Class::Combined
        };
        Ok((
            Self {
                id: id.to_string(),
                source,
                expr,
                dnf,
                class,
                outputs,
                location,
                description: String::new(),
            },
            warnings,
        ))
    }
}

/// A constraint's comment as its description: trimmed, without a leading reference in
/// parentheses (`(18) box leaving to the right` → `box leaving to the right`).
fn description_of(comment: &str) -> String {
    let c = comment.trim();
    let c = match c.strip_prefix('(').and_then(|r| r.split_once(')')) {
        Some((reference, rest)) if !reference.contains(' ') => rest.trim(),
        _ => c,
    };
    c.to_string()
}

fn first_non_space_col(s: &str) -> usize {
    s.chars().take_while(|c| c.is_whitespace()).count() + 1
}

/// Largest support (number of distinct variables) for which tautology is decided by
/// enumeration; larger expressions are only checked for an empty term.
const TAUTOLOGY_ENUM_LIMIT: usize = 20;

fn is_tautology(dnf: &Dnf) -> bool {
    let mut vars: Vec<_> = dnf.iter().flatten().map(|l| l.var).collect();
    vars.sort();
    vars.dedup();
    if dnf.is_empty() || vars.len() > TAUTOLOGY_ENUM_LIMIT {
        return false;
    }
    (0u64..(1u64 << vars.len())).all(|assignment| {
        dnf.iter().any(|term| {
            term.iter().all(|l| {
                let i = vars.binary_search(&l.var).unwrap_or(0);
                ((assignment >> i) & 1 == 1) == l.positive
            })
        })
    })
}

#[cfg(test)]
mod tests;
