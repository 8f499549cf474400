//! Elementary actions of the operative part (seed 003, Naifi 1983, part II ch. II):
//! the plant described as the actions its actuators perform between controlled states,
//! each one the quintuple (II.1) N = (E^I, C, E^f, T, ΔT).
//!
//! - [`ElementaryAction`], [`load_actions`], [`parse_actions`], [`check_actions`]: the
//!   `actions.ron` file and its checks, every problem at the value it rejects.
//! - [`decompose`]: the decomposition rules R1-R3 and phases 1-3 (II.3), which turn
//!   declared transitions ([`RawAction`]) into elementary actions.
//! - [`timing_check`]: the feasibility of monitoring at a given cycle T_D (III.3.2:
//!   T_D < ΔT_min, and (II.4) T − ΔT > T_D).
//! - [`learn_batch`], [`WindowEstimator`]: T = mean, ΔT = α·σ from measured execution
//!   times (II.6 and annex B, offline and online).
//!
//! Expressions use the logic notation of [`crate::expr`]: the initial and final states
//! read inputs (sensors) only, the command reads outputs (orders) only, all as levels at
//! the current cycle (the monitor detects the edges itself).

use crate::diag::codes;
use crate::diag::{Location, Problem, RonField, ron_field, ron_fields, ron_problem};
use crate::expr::{Expr, LeafKind, Span, parse};
use crate::symbols::{Space, Symbols};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// One elementary action N = (initial, command, final, T, ΔT) of seed 003 (II.1).
///
/// The action is validated when V = C·E^I holds (II.6) and must reach its final state
/// within [T − ΔT, T + ΔT] of its validation (II.7); these two conditions are the
/// monitoring database of [`crate::machine::monitor::ActionMonitor`].
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElementaryAction {
    /// Identifier (`N1`): letters, digits and `_`; events and messages name it.
    pub id: String,
    /// The component (actuator) it belongs to (`head`), for messages and for the
    /// implicit commands of the decomposition.
    pub component: String,
    /// E^I: logic expression over inputs (sensors), e.g. `h`.
    pub initial: String,
    /// C: logic expression over outputs (orders), e.g. `DGV`, or `/D` for the implicit
    /// command of a monostable actuator.
    pub command: String,
    /// E^f: logic expression over inputs, e.g. `b1` or `/d`.
    #[serde(rename = "final")]
    pub final_state: String,
    /// T: mean execution time, ms.
    pub t_ms: u64,
    /// ΔT: admissible tolerance on T, ms.
    pub dt_ms: u64,
}

impl ElementaryAction {
    /// T_MIN = T − ΔT, ms: reaching the final state earlier is check (a)'s fault.
    pub fn t_min_ms(&self) -> u64 {
        self.t_ms.saturating_sub(self.dt_ms)
    }

    /// T_MAX = T + ΔT, ms: not reaching the final state by then is check (c)'s fault.
    pub fn t_max_ms(&self) -> u64 {
        self.t_ms.saturating_add(self.dt_ms)
    }

    /// True for a pseudo-controlled action (II.3): its initial state is the negation of
    /// its final state (one of them was undefined and replaced by the negation of the
    /// other). Such actions can be very short, hence condition (II.4) of
    /// [`timing_check`]. Expressions that do not parse, or read more than 16 names, are
    /// not recognised.
    pub fn is_pseudo_controlled(&self) -> bool {
        match (parse_level(&self.initial), parse_level(&self.final_state)) {
            (Some(i), Some(f)) => same_function(&i, &f, true) == Some(true),
            _ => false,
        }
    }

    /// The action with T and ΔT taken from a learned window in milliseconds: T rounded
    /// to the nearest ms, ΔT rounded up (so the learned window never shrinks).
    #[must_use]
    pub fn with_window(&self, window: &LearnedWindow) -> Self {
        Self {
            t_ms: window.t.round().max(0.0) as u64,
            dt_ms: window.dt.ceil().max(0.0) as u64,
            ..self.clone()
        }
    }
}

/// The `actions.ron` file: `Actions(actions: [ (id: "N1", …), … ])`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename = "Actions", deny_unknown_fields)]
pub struct ActionFile {
    /// The elementary actions, in file order.
    pub actions: Vec<ElementaryAction>,
}

/// Loads and checks `actions.ron` (without a name table: ids, timing, syntax; names
/// are resolved by [`check_actions`]). Every problem is located at the value it
/// rejects.
pub fn load_actions(path: &Path) -> Result<Vec<ElementaryAction>, Vec<Problem>> {
    let text = crate::diag::read_text(path).map_err(|p| vec![p])?;
    parse_actions(&text, path)
}

/// As [`load_actions`], from the file's text; `file` is used in locations.
pub fn parse_actions(text: &str, file: &Path) -> Result<Vec<ElementaryAction>, Vec<Problem>> {
    let parsed: ActionFile = ron::from_str(text).map_err(|e| vec![ron_problem(file, &e)])?;
    let source = Source::new(Some((file, text)));
    let mut problems = file_level(&parsed.actions, &source);
    problems.extend(expressions(&parsed.actions, None, &source));
    if problems.is_empty() {
        Ok(parsed.actions)
    } else {
        Err(problems)
    }
}

/// Checks actions against the plant's name table: ids, duplicates, timing, and every
/// expression resolved (initial and final over inputs only, command over outputs only),
/// one problem per unknown name or name of the wrong space. `source` is the file and
/// text the actions were read from, so that each problem points at the offending name;
/// `None` for actions built in memory (problems then name the action only).
pub fn check_actions(
    actions: &[ElementaryAction],
    symbols: &Symbols,
    source: Option<(&Path, &str)>,
) -> Vec<Problem> {
    let source = Source::new(source);
    let mut problems = file_level(actions, &source);
    problems.extend(expressions(actions, Some(symbols), &source));
    problems
}

/// Where the actions were read from, to locate problems.
struct Source<'a> {
    file: Option<(&'a Path, &'a str)>,
    fields: Vec<RonField>,
}

impl<'a> Source<'a> {
    fn new(file: Option<(&'a Path, &'a str)>) -> Self {
        let fields = file.map(|(_, text)| ron_fields(text)).unwrap_or_default();
        Self { file, fields }
    }

    /// The value of field `name` of the `k`-th action.
    fn field(&self, k: usize, name: &str) -> Option<&RonField> {
        ron_field(&self.fields, &["actions"], name, k)
    }

    /// Where the value of field `name` of the `k`-th action is written.
    fn at(&self, k: usize, name: &str) -> Option<Location> {
        let (file, _) = self.file?;
        self.field(k, name).map(|f| f.location(file))
    }

    /// Where the first character of the expression in field `name` of the `k`-th
    /// action is (past the opening quote), so that expression spans are file positions.
    fn expression_start(&self, k: usize, name: &str) -> Option<Span> {
        self.file?;
        self.field(k, name).map(|f| Span {
            line: f.line,
            column: f.column + 1,
        })
    }

    /// The location of a span found by the expression parser.
    fn span(&self, span: Span) -> Option<Location> {
        let (file, _) = self.file?;
        Some(Location::new(file, span.line, span.column))
    }
}

/// The checks that need no name table: ids, duplicates, timing, and the initial and
/// final states that cannot be told apart (rule R2 not applied).
fn file_level(actions: &[ElementaryAction], source: &Source<'_>) -> Vec<Problem> {
    let mut problems = Vec::new();
    let mut seen = BTreeSet::new();
    for (k, a) in actions.iter().enumerate() {
        if !crate::plant::is_valid_name(&a.id) {
            problems.push(Problem::error(
                codes::MACHINE_ACTION_ID_INVALID.id,
                format!("action id `{}` must be letters, digits and `_`", a.id),
                source.at(k, "id"),
            ));
        }
        if !seen.insert(a.id.as_str()) {
            problems.push(Problem::error(
                codes::MACHINE_ACTION_DUPLICATE.id,
                format!("action `{}` is declared twice", a.id),
                source.at(k, "id"),
            ));
        }
        if a.dt_ms == 0 {
            problems.push(Problem::error(
                codes::MACHINE_ACTION_TIMING.id,
                format!(
                    "action `{}`: ΔT = 0 ms leaves no tolerance: no cycle can observe the arrival inside the window",
                    a.id
                ),
                source.at(k, "dt_ms"),
            ));
        } else if a.t_ms <= a.dt_ms {
            problems.push(Problem::error(
                codes::MACHINE_ACTION_TIMING.id,
                format!(
                    "action `{}`: T = {} ms must be greater than ΔT = {} ms (T_MIN = T − ΔT must be positive)",
                    a.id, a.t_ms, a.dt_ms
                ),
                source.at(k, "dt_ms"),
            ));
        }
        if let (Some(i), Some(f)) = (parse_level(&a.initial), parse_level(&a.final_state))
            && same_function(&i, &f, false) == Some(true)
        {
            problems.push(Problem::error(
                codes::MACHINE_ACTION_NOT_ELEMENTARY.id,
                format!(
                    "action `{}`: initial state `{}` and final state `{}` cannot be told apart: split it with rule R2 (`decompose`)",
                    a.id, a.initial, a.final_state
                ),
                source.at(k, "final"),
            ));
        }
    }
    problems
}

/// The three expressions of an action, with their file field and space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Initial,
    Command,
    Final,
}

impl Role {
    const ALL: [Role; 3] = [Role::Initial, Role::Command, Role::Final];

    fn field(self) -> &'static str {
        match self {
            Role::Initial => "initial",
            Role::Command => "command",
            Role::Final => "final",
        }
    }

    fn label(self) -> &'static str {
        match self {
            Role::Initial => "initial state",
            Role::Command => "command",
            Role::Final => "final state",
        }
    }

    fn space(self) -> Space {
        match self {
            Role::Initial | Role::Final => Space::Input,
            Role::Command => Space::Output,
        }
    }

    fn text(self, a: &ElementaryAction) -> &str {
        match self {
            Role::Initial => &a.initial,
            Role::Command => &a.command,
            Role::Final => &a.final_state,
        }
    }
}

/// Syntax, kinds of leaves and, with a name table, names and spaces of every
/// expression.
fn expressions(
    actions: &[ElementaryAction],
    symbols: Option<&Symbols>,
    source: &Source<'_>,
) -> Vec<Problem> {
    let mut problems = Vec::new();
    for (k, a) in actions.iter().enumerate() {
        for role in Role::ALL {
            let first = source
                .expression_start(k, role.field())
                .unwrap_or(Span { line: 1, column: 1 });
            let what = format!("action `{}`, {}", a.id, role.label());
            let expr = match parse(role.text(a), first) {
                Ok(e) => e,
                Err(e) => {
                    problems.push(Problem::error(
                        codes::MACHINE_ACTION_EXPRESSION.id,
                        format!("{what}: {}", e.message),
                        source.span(e.span),
                    ));
                    continue;
                }
            };
            for (name, kind, span) in expr.leaves() {
                let at = source.span(span);
                if let Some(p) = leaf_problem(&what, name, kind, role, symbols, at) {
                    problems.push(p);
                }
            }
        }
    }
    problems
}

/// The problem of one leaf of an expression, if any.
fn leaf_problem(
    what: &str,
    name: &str,
    kind: LeafKind,
    role: Role,
    symbols: Option<&Symbols>,
    at: Option<Location>,
) -> Option<Problem> {
    if kind != LeafKind::Now {
        return Some(Problem::error(
            codes::MACHINE_ACTION_EXPRESSION.id,
            format!(
                "{what}: `{name}` is used as an edge, a past value or an estimate; actions are levels at t (the monitor finds the edges)"
            ),
            at,
        ));
    }
    let symbols = symbols?;
    match symbols.lookup(name) {
        None => Some(Problem::error(
            codes::MACHINE_ACTION_UNKNOWN_SIGNAL.id,
            format!("{what}: unknown signal `{name}`"),
            at,
        )),
        Some((space, _)) if space != role.space() => {
            let wanted = match role.space() {
                Space::Output => "a command reads outputs (orders) only",
                _ => "states read inputs (sensors) only",
            };
            Some(Problem::error(
                codes::MACHINE_ACTION_WRONG_SPACE.id,
                format!("{what}: `{name}` is {}; {wanted}", space_name(space)),
                at,
            ))
        }
        Some(_) => None,
    }
}

fn space_name(space: Space) -> &'static str {
    match space {
        Space::Input => "an input",
        Space::Output => "an output",
        Space::Observer => "an observer",
        Space::Aux => "an auxiliary",
    }
}

/// Parses a one-line expression, `None` when it does not parse.
fn parse_level(text: &str) -> Option<Expr> {
    crate::expr::parse_str(text).ok()
}

/// Largest number of distinct names [`same_function`] enumerates.
const MAX_TRUTH_TABLE_NAMES: usize = 16;

/// Whether `a` and `b` (or `a` and `¬b` when `negate_b`) are the same boolean function
/// of their names, by truth table; `None` beyond [`MAX_TRUTH_TABLE_NAMES`] names.
fn same_function(a: &Expr, b: &Expr, negate_b: bool) -> Option<bool> {
    let names: Vec<&str> = a
        .leaves()
        .into_iter()
        .chain(b.leaves())
        .map(|(n, _, _)| n)
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    if names.len() > MAX_TRUTH_TABLE_NAMES {
        return None;
    }
    let rows = 1u32 << names.len();
    Some((0..rows).all(|row| eval_row(a, &names, row) == (eval_row(b, &names, row) != negate_b)))
}

/// Value of `e` where name `names[i]` has the value of bit `i` of `row`.
fn eval_row(e: &Expr, names: &[&str], row: u32) -> bool {
    match e {
        Expr::Const(v) => *v,
        Expr::Leaf { name, .. } => names
            .binary_search(&name.as_str())
            .is_ok_and(|i| row >> i & 1 == 1),
        Expr::Not(inner) => !eval_row(inner, names, row),
        Expr::And(parts) => parts.iter().all(|p| eval_row(p, names, row)),
        Expr::Or(parts) => parts.iter().any(|p| eval_row(p, names, row)),
    }
}

// ---------------------------------------------------------------------------------
// Decomposition (II.3.1 rules R1-R3, II.3.2 phases 1-3, II.5 special cases)
// ---------------------------------------------------------------------------------

/// A transition as declared or observed, before the decomposition rules make it
/// elementary: its initial or final state may be undefined (II.3), its command
/// implicit (II.5), its initial and final states the same (R2), or it may pass
/// through intermediate controlled states (R1).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawAction {
    /// Identifier of the resulting action (R2 halves get `_I` and `_II` appended).
    pub id: String,
    /// The component (actuator).
    pub component: String,
    /// E^I, `None` when the initial state is not controlled (case a: E^I := ¬E^f).
    #[serde(default)]
    pub initial: Option<String>,
    /// C, `None` for the implicit command of a monostable actuator (II.5): the
    /// negation of the command of the previous action of the same component.
    #[serde(default)]
    pub command: Option<String>,
    /// E^f, `None` when the final state is not controlled (case b: E^f := ¬E^I).
    #[serde(default, rename = "final")]
    pub final_state: Option<String>,
    /// Controlled states the actuator passes through on the way, in order (R1: every
    /// change of the reports other than leaving E^I is a final state). Each ends one
    /// elementary action; the last segment, to E^f, keeps `id`, `t_ms` and `dt_ms`.
    #[serde(default)]
    pub via: Vec<Waypoint>,
    /// T of the (last segment of the) action, ms.
    pub t_ms: u64,
    /// ΔT of the (last segment of the) action, ms.
    pub dt_ms: u64,
    /// For initial = final (R2): (T_I, ΔT_I) of the first half, leaving E^I; the second
    /// half gets T_II = T − T_I and ΔT_II = ΔT (T ≈ T_I + T_II, §2.13).
    #[serde(default)]
    pub first_part: Option<(u64, u64)>,
}

/// An intermediate controlled state of a [`RawAction`] (rule R1).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Waypoint {
    /// Identifier of the elementary action that ends at this state.
    pub id: String,
    /// The controlled state (expression over inputs).
    pub state: String,
    /// T of the segment ending here, ms.
    pub t_ms: u64,
    /// ΔT of the segment ending here, ms.
    pub dt_ms: u64,
}

/// Applies the decomposition rules to declared transitions, in order:
///
/// 1. implicit command (II.5): C := ¬C of the previous action of the same component;
/// 2. undefined states (II.3, R3): case a E^I := ¬E^f, case b E^f := ¬E^I;
/// 3. R1: one elementary action per segment between the [`RawAction::via`] states;
/// 4. R2: initial = final split into two pseudo-controlled actions
///    (d, R, d) → (d, R, /d) and (/d, R, d);
/// 5. phase 2: an action found twice (same component, E^I, C, E^f) is kept once;
/// 6. phase 3: actions differing only by their final state are merged into one whose
///    final state is the union, with a `V1108` warning (safety is reduced).
///
/// Expressions are compared as written (trimmed) in phases 2 and 3. The result is
/// checked like a file ([`check_actions`] without names): ids, duplicates, timing.
pub fn decompose(raw: &[RawAction]) -> (Vec<ElementaryAction>, Vec<Problem>) {
    let mut problems = Vec::new();
    let mut out = Vec::new();
    let mut last_command: BTreeMap<&str, String> = BTreeMap::new();
    for r in raw {
        let Some(command) = resolve_command(r, &last_command, &mut problems) else {
            continue;
        };
        last_command.insert(r.component.as_str(), command.clone());
        let (initial, final_state) = match (&r.initial, &r.final_state) {
            (Some(i), Some(f)) => (i.trim().to_string(), f.trim().to_string()),
            (None, Some(f)) => (negate(f), f.trim().to_string()),
            (Some(i), None) => (i.trim().to_string(), negate(i)),
            (None, None) => {
                problems.push(Problem::error(
                    codes::MACHINE_ACTION_NOT_ELEMENTARY.id,
                    format!(
                        "action `{}`: neither its initial nor its final state is defined (II.3 needs one of them)",
                        r.id
                    ),
                    None,
                ));
                continue;
            }
        };
        for segment in split_via(r, initial, &command, final_state) {
            split_r2(segment, r.first_part, &mut out, &mut problems);
        }
    }
    let out = phase2_dedup(out, &mut problems);
    let out = phase3_merge(out, &mut problems);
    problems.extend(file_level(&out, &Source::new(None)));
    (out, problems)
}

/// The command of a raw action: its own, or ¬ the previous command of its component.
fn resolve_command(
    r: &RawAction,
    last_command: &BTreeMap<&str, String>,
    problems: &mut Vec<Problem>,
) -> Option<String> {
    if let Some(c) = &r.command {
        return Some(c.trim().to_string());
    }
    let Some(previous) = last_command.get(r.component.as_str()) else {
        problems.push(Problem::error(
            codes::MACHINE_ACTION_NOT_ELEMENTARY.id,
            format!(
                "action `{}`: implicit command, but no earlier action of component `{}` has a command to negate (II.5)",
                r.id, r.component
            ),
            None,
        ));
        return None;
    };
    Some(negate(previous))
}

/// R1: the segments (E^I → via… → E^f) of a raw action, each an elementary action.
fn split_via(
    r: &RawAction,
    initial: String,
    command: &str,
    final_state: String,
) -> Vec<ElementaryAction> {
    let mut out = Vec::new();
    let mut from = initial;
    for w in &r.via {
        let to = w.state.trim().to_string();
        out.push(ElementaryAction {
            id: w.id.clone(),
            component: r.component.clone(),
            initial: std::mem::replace(&mut from, to.clone()),
            command: command.to_string(),
            final_state: to,
            t_ms: w.t_ms,
            dt_ms: w.dt_ms,
        });
    }
    out.push(ElementaryAction {
        id: r.id.clone(),
        component: r.component.clone(),
        initial: from,
        command: command.to_string(),
        final_state,
        t_ms: r.t_ms,
        dt_ms: r.dt_ms,
    });
    out
}

/// R2: an action whose initial and final states cannot be told apart becomes two
/// pseudo-controlled actions, N^I = (d, C, /d, T_I, ΔT_I) and N^II = (/d, C, d, T_II,
/// ΔT_II).
fn split_r2(
    a: ElementaryAction,
    first_part: Option<(u64, u64)>,
    out: &mut Vec<ElementaryAction>,
    problems: &mut Vec<Problem>,
) {
    let same = match (parse_level(&a.initial), parse_level(&a.final_state)) {
        (Some(i), Some(f)) => same_function(&i, &f, false) == Some(true),
        _ => {
            problems.push(Problem::error(
                codes::MACHINE_ACTION_EXPRESSION.id,
                format!(
                    "action `{}`: initial state `{}` or final state `{}` does not parse",
                    a.id, a.initial, a.final_state
                ),
                None,
            ));
            return;
        }
    };
    if !same {
        out.push(a);
        return;
    }
    let Some((t_i, dt_i)) = first_part else {
        problems.push(Problem::error(
            codes::MACHINE_ACTION_NOT_ELEMENTARY.id,
            format!(
                "action `{}`: initial and final states cannot be told apart (rule R2): give `first_part` (T and ΔT of leaving the initial state)",
                a.id
            ),
            None,
        ));
        return;
    };
    let left = negate(&a.initial);
    out.push(ElementaryAction {
        id: format!("{}_I", a.id),
        initial: a.initial.clone(),
        final_state: left.clone(),
        t_ms: t_i,
        dt_ms: dt_i,
        ..a.clone()
    });
    out.push(ElementaryAction {
        id: format!("{}_II", a.id),
        initial: left,
        t_ms: a.t_ms.saturating_sub(t_i),
        ..a
    });
}

/// The identity of an action for phases 2 and 3: component, E^I and C.
fn triple_key(a: &ElementaryAction) -> (&str, &str, &str) {
    (&a.component, &a.initial, &a.command)
}

/// Phase 2: an action found again (same component, E^I, C, E^f) is kept once; found
/// with other times, it is a `V1102` error.
fn phase2_dedup(
    actions: Vec<ElementaryAction>,
    problems: &mut Vec<Problem>,
) -> Vec<ElementaryAction> {
    let mut out: Vec<ElementaryAction> = Vec::new();
    for a in actions {
        let same = out
            .iter()
            .find(|b| triple_key(b) == triple_key(&a) && b.final_state == a.final_state);
        match same {
            None => out.push(a),
            Some(b) if (b.t_ms, b.dt_ms) == (a.t_ms, a.dt_ms) => {}
            Some(b) => problems.push(Problem::error(
                codes::MACHINE_ACTION_DUPLICATE.id,
                format!(
                    "action `{}` repeats `{}` ({}, {}, {}) with other times: T = {} ms, ΔT = {} ms against T = {} ms, ΔT = {} ms",
                    a.id, b.id, a.initial, a.command, a.final_state, a.t_ms, a.dt_ms, b.t_ms, b.dt_ms
                ),
                None,
            )),
        }
    }
    out
}

/// Phase 3: actions that differ only by their final state become one whose final state
/// is the union and whose window [T_MIN, T_MAX] covers theirs; `V1108` warning.
fn phase3_merge(
    actions: Vec<ElementaryAction>,
    problems: &mut Vec<Problem>,
) -> Vec<ElementaryAction> {
    let mut groups: Vec<Vec<ElementaryAction>> = Vec::new();
    for a in actions {
        match groups
            .iter_mut()
            .find(|g| triple_key(&g[0]) == triple_key(&a))
        {
            Some(g) => g.push(a),
            None => groups.push(vec![a]),
        }
    }
    let mut out = Vec::new();
    for group in groups {
        let [first, rest @ ..] = group.as_slice() else {
            continue;
        };
        if rest.is_empty() {
            out.push(first.clone());
            continue;
        }
        let lo = group
            .iter()
            .map(ElementaryAction::t_min_ms)
            .min()
            .unwrap_or(0);
        let hi = group
            .iter()
            .map(ElementaryAction::t_max_ms)
            .max()
            .unwrap_or(0);
        let finals: Vec<&str> = group.iter().map(|a| a.final_state.as_str()).collect();
        let merged = ElementaryAction {
            final_state: union(&finals),
            t_ms: lo + (hi - lo) / 2,
            dt_ms: (hi - lo).div_ceil(2),
            ..first.clone()
        };
        let ids: Vec<String> = group.iter().map(|a| format!("`{}`", a.id)).collect();
        problems.push(Problem::warning(
            codes::MACHINE_ACTIONS_MERGED.id,
            format!(
                "actions {} (component `{}`) differ only by their final state: merged into `{}` with final state `{}`; safety is reduced (reaching the wrong final state is not detected, and T, ΔT cannot be learned per final state)",
                ids.join(", "),
                first.component,
                merged.id,
                merged.final_state
            ),
            None,
        ));
        out.push(merged);
    }
    out
}

/// True for a name or a negated name (`d`, `/d`), which need no parentheses.
fn is_literal(text: &str) -> bool {
    let t = text.trim();
    let name = t
        .strip_prefix('/')
        .or_else(|| t.strip_prefix('!'))
        .unwrap_or(t);
    !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The negation of an expression in the file notation: `d` → `/d`, `/d` → `d`,
/// anything else → `/(…)`.
fn negate(text: &str) -> String {
    let t = text.trim();
    if is_literal(t) {
        match t.strip_prefix('/').or_else(|| t.strip_prefix('!')) {
            Some(name) => name.to_string(),
            None => format!("/{t}"),
        }
    } else {
        format!("/({t})")
    }
}

/// The union of expressions: `a + b`, parenthesising the non-literals.
fn union(parts: &[&str]) -> String {
    parts
        .iter()
        .map(|p| {
            if is_literal(p) {
                p.trim().to_string()
            } else {
                format!("({})", p.trim())
            }
        })
        .collect::<Vec<_>>()
        .join(" + ")
}

// ---------------------------------------------------------------------------------
// Timing feasibility (III.3.2 and II.4)
// ---------------------------------------------------------------------------------

/// The regime of an action under a monitor cycle T_D (seed 003, III.3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum Regime {
    /// Case c, T_D < ΔT: the risks of masking and false alarms are minimal.
    C,
    /// Case b, ΔT ≤ T_D < T_MIN: early arrivals may be masked (when T_MIN − λ·T_D <
    /// T_D) and normal arrivals, seen at the next acquisition, may look late.
    B,
    /// Case a, T_MIN ≤ T_D < T_MAX: any early arrival (t0 < t_f < T_MIN) is masked.
    A,
    /// T_D ≥ T_MAX: the whole window fits in one cycle; beyond case a, the action's
    /// timing cannot be checked at all.
    Blind,
}

impl Regime {
    /// The regime's name as the thesis writes it (`a`, `b`, `c`), `blind` beyond a.
    pub fn name(self) -> &'static str {
        match self {
            Regime::C => "c",
            Regime::B => "b",
            Regime::A => "a",
            Regime::Blind => "blind",
        }
    }
}

/// The regime of `action` under a monitor cycle of `cycle_ms`.
pub fn regime(action: &ElementaryAction, cycle_ms: u64) -> Regime {
    if cycle_ms < action.dt_ms {
        Regime::C
    } else if cycle_ms < action.t_min_ms() {
        Regime::B
    } else if cycle_ms < action.t_max_ms() {
        Regime::A
    } else {
        Regime::Blind
    }
}

/// What a [`TimingIssue`] says.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum TimingIssueKind {
    /// T_D ≥ ΔT: the global constraint T_D < ΔT_min fails on this action, which is in
    /// `regime` (b, a or blind).
    CycleNotBelowTolerance {
        /// The action's regime.
        regime: Regime,
    },
    /// (II.4) T − ΔT ≤ T_D: an early arrival of this short action cannot be seen (the
    /// first acquisition after validation is already past T_MIN). The thesis states
    /// it for pseudo-controlled actions, where it bites; it holds for every action.
    TooShort {
        /// Whether the action is pseudo-controlled.
        pseudo_controlled: bool,
    },
}

/// One failure of the timing feasibility check (C5), naming the action.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TimingIssue {
    /// The action's id.
    pub action: String,
    /// Which condition fails.
    pub kind: TimingIssueKind,
    /// What fails and what it risks, with the numbers.
    pub message: String,
}

impl TimingIssue {
    /// The issue as a `V1109` error (no location: it depends on the cycle, not on a
    /// line of the file).
    pub fn to_problem(&self) -> Problem {
        Problem::error(codes::MACHINE_CYCLE_TOO_LONG.id, self.message.clone(), None)
    }
}

/// Checks that a monitor running every `cycle_ms` can watch every action (C5):
/// T_D < ΔT_min (III.3.2), naming each action with ΔT ≤ T_D and its regime, and (II.4)
/// T − ΔT > T_D. Sorted by action id, then kind; empty when monitoring is feasible.
pub fn timing_check(actions: &[ElementaryAction], cycle_ms: u64) -> Vec<TimingIssue> {
    let mut out = Vec::new();
    for a in actions {
        let r = regime(a, cycle_ms);
        if r != Regime::C {
            let risk = match r {
                Regime::B => "early arrivals may be masked, normal arrivals may look late",
                Regime::A => "every early arrival is masked",
                _ => "the whole window fits in one cycle: its timing cannot be checked",
            };
            out.push(TimingIssue {
                action: a.id.clone(),
                kind: TimingIssueKind::CycleNotBelowTolerance { regime: r },
                message: format!(
                    "action `{}` (ΔT = {} ms): cycle T_D = {cycle_ms} ms is not below ΔT: regime {} ({risk})",
                    a.id,
                    a.dt_ms,
                    r.name()
                ),
            });
        }
        if a.t_min_ms() <= cycle_ms {
            let pseudo_controlled = a.is_pseudo_controlled();
            out.push(TimingIssue {
                action: a.id.clone(),
                kind: TimingIssueKind::TooShort { pseudo_controlled },
                message: format!(
                    "{}action `{}`: T − ΔT = {} ms is not above the cycle T_D = {cycle_ms} ms (II.4): its early arrivals cannot be seen",
                    if pseudo_controlled {
                        "pseudo-controlled "
                    } else {
                        ""
                    },
                    a.id,
                    a.t_min_ms()
                ),
            });
        }
    }
    out.sort_by(|x, y| (&x.action, x.kind).cmp(&(&y.action, y.kind)));
    out
}

// ---------------------------------------------------------------------------------
// Learning T and ΔT (II.6, annex B)
// ---------------------------------------------------------------------------------

/// A learned time window: T = mean, σ the population standard deviation, ΔT = α·σ.
/// Units are those of the measures (ms for [`ElementaryAction::with_window`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LearnedWindow {
    /// Mean execution time T.
    pub t: f64,
    /// Population standard deviation σ.
    pub sigma: f64,
    /// Tolerance ΔT = α·σ.
    pub dt: f64,
}

impl LearnedWindow {
    /// T_MIN = T − ΔT.
    pub fn t_min(&self) -> f64 {
        self.t - self.dt
    }

    /// T_MAX = T + ΔT.
    pub fn t_max(&self) -> f64 {
        self.t + self.dt
    }
}

/// Offline learning (Fig. II.9a): T = Σ τ / n, σ = sqrt(Σ (τ − T)² / n) (the
/// population σ; the thesis's printed extra 1/n is a typo, see annex B), ΔT = α·σ.
/// `None` for no measure, a measure or α that is not finite, or α < 0.
pub fn learn_batch(measures: &[f64], alpha: f64) -> Option<LearnedWindow> {
    if measures.is_empty() || !alpha.is_finite() || alpha < 0.0 {
        return None;
    }
    if measures.iter().any(|m| !m.is_finite()) {
        return None;
    }
    let n = measures.len() as f64;
    let t = measures.iter().sum::<f64>() / n;
    let sigma = (measures.iter().map(|m| (m - t) * (m - t)).sum::<f64>() / n).sqrt();
    Some(LearnedWindow {
        t,
        sigma,
        dt: alpha * sigma,
    })
}

/// Online learning (Fig. II.9b): the recursion of annex B, updated after each normally
/// completed execution, never after a detected fault (the caller feeds it the
/// `elapsed_ms` of `Completed` events only).
///
/// With P_j = 1/j: (B.3) τ̄_{j+1} = (τ̄_j + P_j·τ_{j+1}) / (1 + P_j), and the
/// corrected (B.4) σ²_{j+1} = σ²_j/(1+P_j) + P_j/(1+P_j)·τ²_{j+1} + τ̄²_j/(1+P_j) −
/// τ̄²_{j+1}. After n measures it equals [`learn_batch`] on them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct WindowEstimator {
    count: u64,
    mean: f64,
    variance: f64,
}

impl WindowEstimator {
    /// No measure yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one measure; a measure that is not finite is refused (`false`) and leaves
    /// the estimate as it was.
    pub fn push(&mut self, tau: f64) -> bool {
        if !tau.is_finite() {
            return false;
        }
        if self.count == 0 {
            *self = Self {
                count: 1,
                mean: tau,
                variance: 0.0,
            };
            return true;
        }
        let p = 1.0 / self.count as f64;
        let mean = (self.mean + p * tau) / (1.0 + p);
        self.variance = self.variance / (1.0 + p)
            + p / (1.0 + p) * tau * tau
            + self.mean * self.mean / (1.0 + p)
            - mean * mean;
        self.mean = mean;
        self.count += 1;
        true
    }

    /// Number of measures.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Mean T (0 before the first measure).
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Population σ (rounding can make the recursive variance slightly negative:
    /// it is read as 0).
    pub fn sigma(&self) -> f64 {
        self.variance.max(0.0).sqrt()
    }

    /// The window with ΔT = α·σ, `None` before the first measure or for an α that is
    /// not finite or negative.
    pub fn window(&self, alpha: f64) -> Option<LearnedWindow> {
        if self.count == 0 || !alpha.is_finite() || alpha < 0.0 {
            return None;
        }
        Some(LearnedWindow {
            t: self.mean,
            sigma: self.sigma(),
            dt: alpha * self.sigma(),
        })
    }
}

#[cfg(test)]
mod tests;
