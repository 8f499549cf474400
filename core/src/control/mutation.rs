//! Single mutations of a program, for fault-localisation campaigns.
//!
//! Operators (each mutation changes one place):
//! - [`Operator::NegateLiteral`]: `x` ↔ `/x` in a receptivity or an equation;
//! - [`Operator::SwapEdge`]: `RE(x)` ↔ `FE(x)`;
//! - [`Operator::SwapSignal`]: a sensor replaced by another sensor;
//! - [`Operator::DropTerm`]: one operand of a product or a sum removed;
//! - [`Operator::ChangeQualifier`]: an action's qualifier changed (`N`→`S`, `N`→`P`, …);
//! - [`Operator::MoveAction`]: an action moved from its step to another step of the same
//!   chart that does not act on its target (the action written in the wrong step: the
//!   next or previous one, the symmetric step of another branch, …). Its place is the
//!   step the action was moved TO: that step's action drives the target when it must
//!   not; the step it came from no longer acts on it.

use super::library::Patch;
use super::program::{Action, Program, Qualifier};
use crate::expr::{self, Expr, LeafKind};
use crate::plant::Plant;

/// Where a mutation applies.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Place {
    /// The receptivity of a transition.
    Transition {
        /// Chart name.
        chart: String,
        /// Transition id.
        id: String,
    },
    /// An action of a step.
    Action {
        /// Chart name.
        chart: String,
        /// Step id.
        step: String,
        /// The action's target.
        target: String,
    },
    /// The equation of a target.
    Equation {
        /// Actuator or memory.
        target: String,
    },
}

impl std::fmt::Display for Place {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Place::Transition { chart, id } => write!(f, "chart {chart}, transition {id}"),
            Place::Action {
                chart,
                step,
                target,
            } => {
                write!(f, "chart {chart}, step {step}, action on {target}")
            }
            Place::Equation { target } => write!(f, "equation {target}"),
        }
    }
}

/// The kind of mutation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
pub enum Operator {
    /// A literal negated (or its negation removed).
    NegateLiteral,
    /// A rising edge made falling or the reverse.
    SwapEdge,
    /// A sensor replaced by another.
    SwapSignal,
    /// An operand of a product or a sum removed.
    DropTerm,
    /// An action qualifier changed.
    ChangeQualifier,
    /// An action moved to another step of its chart.
    MoveAction,
}

/// One single mutation of a program.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mutation {
    /// Where.
    pub place: Place,
    /// The signal (or step, memory) involved.
    pub signal: String,
    /// What kind.
    pub operator: Operator,
    /// In words: place, before and after.
    pub description: String,
    /// The edit; [`Patch::apply`] gives the mutant.
    pub patch: Patch,
}

/// Renders an expression in the file notation with minimal parentheses.
pub fn render(e: &Expr) -> String {
    fn go(e: &Expr, parent: u8) -> String {
        // parent: 0 top / or, 1 and, 2 not
        match e {
            Expr::Const(v) => if *v { "1" } else { "0" }.to_string(),
            Expr::Leaf { name, kind, .. } => match kind {
                LeafKind::Now => name.clone(),
                LeafKind::Prev => format!("{name}*"),
                LeafKind::Rise => format!("RE({name})"),
                LeafKind::Fall => format!("FE({name})"),
                LeafKind::Estimate => format!("EST({name})"),
            },
            Expr::Not(inner) => format!("/{}", go(inner, 2)),
            Expr::And(v) => {
                let s = v.iter().map(|x| go(x, 1)).collect::<Vec<_>>().join(" . ");
                if parent >= 2 { format!("({s})") } else { s }
            }
            Expr::Or(v) => {
                let s = v.iter().map(|x| go(x, 0)).collect::<Vec<_>>().join(" + ");
                if parent >= 1 { format!("({s})") } else { s }
            }
        }
    }
    go(e, 0)
}

/// Rewrites leaf number `target` (source order) with `f`; `f` receives the leaf and
/// whether it sits directly under a `/`, and returns the replacement of that node.
fn rewrite_leaf(e: &Expr, target: usize, k: &mut usize, f: &dyn Fn(&Expr, bool) -> Expr) -> Expr {
    match e {
        Expr::Not(inner) if matches!(**inner, Expr::Leaf { .. }) => {
            let hit = *k == target;
            *k += 1;
            if hit { f(inner, true) } else { e.clone() }
        }
        Expr::Leaf { .. } => {
            let hit = *k == target;
            *k += 1;
            if hit { f(e, false) } else { e.clone() }
        }
        Expr::Const(_) => e.clone(),
        Expr::Not(inner) => Expr::Not(Box::new(rewrite_leaf(inner, target, k, f))),
        Expr::And(v) => Expr::And(v.iter().map(|x| rewrite_leaf(x, target, k, f)).collect()),
        Expr::Or(v) => Expr::Or(v.iter().map(|x| rewrite_leaf(x, target, k, f)).collect()),
    }
}

/// Removes operand `j` of the n-ary node number `target` (preorder over And/Or nodes).
fn drop_operand(e: &Expr, target: usize, j: usize, k: &mut usize) -> Expr {
    match e {
        Expr::And(v) | Expr::Or(v) => {
            let hit = *k == target;
            *k += 1;
            let mut parts: Vec<Expr> = v.iter().map(|x| drop_operand(x, target, j, k)).collect();
            if hit && j < parts.len() {
                parts.remove(j);
            }
            if parts.len() == 1 {
                return parts.remove(0);
            }
            if matches!(e, Expr::And(_)) {
                Expr::And(parts)
            } else {
                Expr::Or(parts)
            }
        }
        Expr::Not(inner) => Expr::Not(Box::new(drop_operand(inner, target, j, k))),
        _ => e.clone(),
    }
}

fn nary_nodes(e: &Expr, out: &mut Vec<usize>) {
    match e {
        Expr::And(v) | Expr::Or(v) => {
            out.push(v.len());
            v.iter().for_each(|x| nary_nodes(x, out));
        }
        Expr::Not(inner) => nary_nodes(inner, out),
        _ => {}
    }
}

fn expr_mutations(
    text: &str,
    place: &Place,
    plant: &Plant,
    make: &dyn Fn(String) -> Patch,
    out: &mut Vec<Mutation>,
) {
    let Ok(e) = expr::parse_str(text) else { return };
    let leaves: Vec<(String, LeafKind)> = e
        .leaves()
        .into_iter()
        .map(|(n, k, _)| (n.to_string(), k))
        .collect();
    let before = render(&e);
    let mut push = |operator, signal: &str, new: Expr| {
        let after = render(&new);
        if after == before {
            return;
        }
        out.push(Mutation {
            place: place.clone(),
            signal: signal.to_string(),
            operator,
            description: format!("{place}: `{text}` → `{after}`"),
            patch: make(after),
        });
    };
    for (i, (name, kind)) in leaves.iter().enumerate() {
        let negated = rewrite_leaf(&e, i, &mut 0, &|leaf, under_not| {
            if under_not {
                leaf.clone()
            } else {
                Expr::Not(Box::new(leaf.clone()))
            }
        });
        push(Operator::NegateLiteral, name, negated);
        if matches!(kind, LeafKind::Rise | LeafKind::Fall) {
            let swapped = rewrite_leaf(&e, i, &mut 0, &|leaf, under_not| {
                let new = match leaf {
                    Expr::Leaf { name, kind, span } => Expr::Leaf {
                        name: name.clone(),
                        kind: if *kind == LeafKind::Rise {
                            LeafKind::Fall
                        } else {
                            LeafKind::Rise
                        },
                        span: *span,
                    },
                    other => other.clone(),
                };
                if under_not {
                    Expr::Not(Box::new(new))
                } else {
                    new
                }
            });
            push(Operator::SwapEdge, name, swapped);
        }
        if plant.input(name).is_some() {
            // Another process sensor: a mirror contact (`feedback_of`) belongs to the
            // device monitoring, which a sequence does not read.
            for other in &plant.inputs {
                if other.id == *name || other.feedback_of.is_some() {
                    continue;
                }
                let swapped = rewrite_leaf(&e, i, &mut 0, &|leaf, under_not| {
                    let new = match leaf {
                        Expr::Leaf { kind, span, .. } => Expr::Leaf {
                            name: other.id.clone(),
                            kind: *kind,
                            span: *span,
                        },
                        other => other.clone(),
                    };
                    if under_not {
                        Expr::Not(Box::new(new))
                    } else {
                        new
                    }
                });
                push(Operator::SwapSignal, name, swapped);
            }
        }
    }
    let mut nodes = Vec::new();
    nary_nodes(&e, &mut nodes);
    for (n, &arity) in nodes.iter().enumerate() {
        for j in 0..arity {
            let dropped = drop_operand(&e, n, j, &mut 0);
            let mut found = String::new();
            find_operand(&e, n, j, &mut 0, &mut found);
            let signal = found;
            push(Operator::DropTerm, &signal, dropped);
        }
    }
}

fn find_operand(e: &Expr, target: usize, j: usize, k: &mut usize, found: &mut String) {
    match e {
        Expr::And(v) | Expr::Or(v) => {
            let hit = *k == target;
            *k += 1;
            if let Some(x) = v.get(j).filter(|_| hit) {
                *found = render(x);
            }
            v.iter().for_each(|x| find_operand(x, target, j, k, found));
        }
        Expr::Not(inner) => find_operand(inner, target, j, k, found),
        _ => {}
    }
}

/// Alternative qualifiers tried for an action.
fn qualifier_alternatives(q: Qualifier) -> Vec<Qualifier> {
    match q {
        Qualifier::N => vec![
            Qualifier::S,
            Qualifier::P,
            Qualifier::L(1000),
            Qualifier::D(1000),
        ],
        Qualifier::S => vec![Qualifier::N, Qualifier::R],
        Qualifier::R => vec![Qualifier::S, Qualifier::N],
        Qualifier::L(_) | Qualifier::D(_) => vec![Qualifier::N],
        Qualifier::P => vec![Qualifier::N],
        Qualifier::SD(ms) | Qualifier::DS(ms) | Qualifier::SL(ms) => {
            vec![Qualifier::N, Qualifier::D(ms), Qualifier::L(ms)]
        }
    }
}

/// The actions of every step moved to each other step of the same chart that does not
/// act on their target already, in program order (source step, action, destination).
fn moved_actions(program: &Program, out: &mut Vec<Mutation>) {
    for chart in &program.charts {
        for s in &chart.steps {
            for a in &s.actions {
                for d in &chart.steps {
                    if d.id == s.id || d.actions.iter().any(|x| x.target == a.target) {
                        continue;
                    }
                    let place = Place::Action {
                        chart: chart.name.clone(),
                        step: d.id.clone(),
                        target: a.target.clone(),
                    };
                    out.push(Mutation {
                        description: format!(
                            "{place}: `{} {}` moved there from step {}",
                            a.qualifier, a.target, s.id
                        ),
                        place,
                        signal: a.target.clone(),
                        operator: Operator::MoveAction,
                        patch: Patch::MoveAction {
                            from: s.id.clone(),
                            to: d.id.clone(),
                            target: a.target.clone(),
                        },
                    });
                }
            }
        }
    }
}

/// Every single mutation of `program`, in program order: receptivities, then step
/// actions (qualifiers changed), then equations, then actions moved to another step.
pub fn mutations(program: &Program, plant: &Plant) -> Vec<Mutation> {
    let mut out = Vec::new();
    for (chart, t) in program.transitions() {
        let place = Place::Transition {
            chart: chart.to_string(),
            id: t.id.clone(),
        };
        let id = t.id.clone();
        expr_mutations(
            &t.condition,
            &place,
            plant,
            &|c| Patch::Condition {
                transition: id.clone(),
                condition: c,
            },
            &mut out,
        );
    }
    for (chart, s) in program.steps() {
        for a in &s.actions {
            let place = Place::Action {
                chart: chart.to_string(),
                step: s.id.clone(),
                target: a.target.clone(),
            };
            for q in qualifier_alternatives(a.qualifier) {
                out.push(Mutation {
                    description: format!("{place}: qualifier {} → {q}", a.qualifier),
                    place: place.clone(),
                    signal: a.target.clone(),
                    operator: Operator::ChangeQualifier,
                    patch: Patch::ReplaceAction {
                        step: s.id.clone(),
                        target: a.target.clone(),
                        action: Action {
                            qualifier: q,
                            target: a.target.clone(),
                        },
                    },
                });
            }
        }
    }
    for (target, text) in &program.equations {
        let place = Place::Equation {
            target: target.clone(),
        };
        let tg = target.clone();
        expr_mutations(
            text,
            &place,
            plant,
            &|e| Patch::Equation {
                target: tg.clone(),
                expression: e,
            },
            &mut out,
        );
    }
    moved_actions(program, &mut out);
    out
}
