//! SFC bodies: the graph of steps, transitions, divergences, convergences and jumps
//! read into transitions from steps to steps, and the action blocks.

use super::ld::Network;
use super::read::{
    Ctx, Declarations, Kind, Machine, Mode, StText, VigieData, and, child, children, leaf, not,
    st_text, vigie_chart, vigie_step, vigie_transition,
};
use super::st::{self, Pos, StExpr};
use crate::control::{Chart as VigieChart, Qualifier};
use crate::diag::Location;
use crate::diag::codes;
use crate::expr::{Expr, LeafKind, Span};
use roxmltree::Node;
use std::collections::{BTreeMap, BTreeSet};

/// A step as read.
pub(super) struct SfcStep {
    pub(super) name: String,
    pub(super) initial: bool,
    pub(super) at: Location,
    /// (qualifier, Vigie target).
    pub(super) actions: Vec<(Qualifier, String)>,
}

/// Where a transition's condition is.
pub(super) enum Condition {
    /// ST text (inline or a named transition).
    St(StText),
    /// An LD or FBD network inside the SFC body; positions are file positions.
    Network(StExpr),
}

/// A transition as read.
pub(super) struct SfcTransition {
    pub(super) id: String,
    pub(super) from: Vec<String>,
    pub(super) to: Vec<String>,
    pub(super) condition: Condition,
    pub(super) at: Location,
    /// Left-to-right place, for the priority of a selection divergence.
    pub(super) x: f64,
}

/// One POU's SFC.
pub(super) struct Chart {
    pub(super) steps: Vec<SfcStep>,
    pub(super) transitions: Vec<SfcTransition>,
}

impl Chart {
    /// The variables its actions drive.
    pub(super) fn action_targets(&self) -> BTreeSet<String> {
        self.steps
            .iter()
            .flat_map(|s| s.actions.iter().map(|a| a.1.clone()))
            .collect()
    }
}

fn local_id(n: Node<'_, '_>) -> Option<u64> {
    n.attribute("localId").and_then(|v| v.parse().ok())
}

/// The `refLocalId`s of the direct `connectionPointIn` children of `n`.
fn preds(n: Node<'_, '_>) -> Vec<u64> {
    children(n, "connectionPointIn")
        .flat_map(|c| children(c, "connection"))
        .filter_map(|c| c.attribute("refLocalId").and_then(|v| v.parse().ok()))
        .collect()
}

/// The `connection` of `n` to `id` (to place a problem on its line).
fn connection_to<'a, 'i>(n: Node<'a, 'i>, id: u64) -> Option<Node<'a, 'i>> {
    children(n, "connectionPointIn")
        .flat_map(|c| children(c, "connection"))
        .find(|c| {
            c.attribute("refLocalId")
                .and_then(|v| v.parse::<u64>().ok())
                == Some(id)
        })
}

struct Graph<'a, 'i> {
    nodes: BTreeMap<u64, Node<'a, 'i>>,
    succs: BTreeMap<u64, Vec<u64>>,
}

impl<'a, 'i> Graph<'a, 'i> {
    fn new(body: Node<'a, 'i>) -> Self {
        let nodes: BTreeMap<u64, Node<'a, 'i>> = body
            .children()
            .filter(Node::is_element)
            .filter_map(|n| local_id(n).map(|id| (id, n)))
            .collect();
        let mut succs: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
        for (&id, n) in &nodes {
            for p in preds(*n) {
                succs.entry(p).or_default().push(id);
            }
        }
        Self { nodes, succs }
    }

    /// Steps before a transition, through selection divergences and simultaneous
    /// convergences.
    fn steps_before(
        &self,
        ctx: &mut Ctx<'_, '_>,
        n: Node<'_, '_>,
        out: &mut Vec<String>,
        depth: usize,
    ) -> bool {
        for p in preds(n) {
            let Some(&pn) = self.nodes.get(&p) else {
                ctx.error(
                    codes::PLCOPEN_SFC_GRAPH,
                    connection_to(n, p).unwrap_or(n),
                    format!("a connection to localId {p}, which no element has"),
                );
                return false;
            };
            match pn.tag_name().name() {
                "step" => out.push(pn.attribute("name").unwrap_or("").to_string()),
                "selectionDivergence" | "simultaneousConvergence" if depth < 64 => {
                    if !self.steps_before(ctx, pn, out, depth + 1) {
                        return false;
                    }
                }
                other => {
                    ctx.error(codes::PLCOPEN_SFC_GRAPH, pn, format!("a transition is preceded by `{other}` (localId {p}); a step, a selection divergence or a simultaneous convergence is expected"));
                    return false;
                }
            }
        }
        true
    }

    /// Steps after a transition, through selection convergences, simultaneous
    /// divergences and jumps.
    fn steps_after(
        &self,
        ctx: &mut Ctx<'_, '_>,
        id: u64,
        out: &mut Vec<String>,
        depth: usize,
    ) -> bool {
        for &s in self.succs.get(&id).map(Vec::as_slice).unwrap_or(&[]) {
            let Some(&sn) = self.nodes.get(&s) else {
                continue;
            };
            match sn.tag_name().name() {
                "step" => out.push(sn.attribute("name").unwrap_or("").to_string()),
                "jumpStep" => out.push(sn.attribute("targetName").unwrap_or("").to_string()),
                "selectionConvergence" | "simultaneousDivergence" if depth < 64 => {
                    if !self.steps_after(ctx, s, out, depth + 1) {
                        return false;
                    }
                }
                "actionBlock" | "comment" => {}
                other => {
                    ctx.error(codes::PLCOPEN_SFC_GRAPH, sn, format!("a transition is followed by `{other}`; a step, a jump, a selection convergence or a simultaneous divergence is expected"));
                    return false;
                }
            }
        }
        true
    }
}

fn qualifier(ctx: &mut Ctx<'_, '_>, a: Node<'_, '_>) -> Option<Qualifier> {
    let q = a.attribute("qualifier").unwrap_or("N");
    let duration = || {
        let d = a.attribute("duration").unwrap_or("");
        let body = d.split_once('#').map_or(d, |(_, rest)| rest);
        st::parse_duration(body)
    };
    let timed = |ctx: &mut Ctx<'_, '_>, f: fn(u64) -> Qualifier| match duration() {
        Some(ms) => Some(f(ms)),
        None => {
            ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                a,
                format!("action qualifier {q} without a duration (write e.g. duration=\"T#2s\")"),
            );
            None
        }
    };
    match q {
        "N" | "" => Some(Qualifier::N),
        "S" => Some(Qualifier::S),
        "R" => Some(Qualifier::R),
        "P" => Some(Qualifier::P),
        "L" => timed(ctx, Qualifier::L),
        "D" => timed(ctx, Qualifier::D),
        "SD" => timed(ctx, Qualifier::SD),
        "DS" => timed(ctx, Qualifier::DS),
        "SL" => timed(ctx, Qualifier::SL),
        other => {
            ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                a,
                format!(
                    "action qualifier {other} is not run (N, S, R, P, L, D, SD, DS and SL are)"
                ),
            );
            None
        }
    }
}

fn read_actions(
    ctx: &mut Ctx<'_, '_>,
    pou: Node<'_, '_>,
    block: Node<'_, '_>,
    decls: &Declarations,
) -> Vec<(Qualifier, String)> {
    let pou_name = pou.attribute("name").unwrap_or("?");
    let mut out = Vec::new();
    for a in children(block, "action") {
        let Some(q) = qualifier(ctx, a) else { continue };
        let Some(r) = child(a, "reference") else {
            ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                a,
                format!("POU `{pou_name}`: an inline action body: Vigie runs actions on Boolean variables (write the variable's name as the action)"),
            );
            continue;
        };
        let name = r.attribute("name").unwrap_or("");
        match decls.vars.get(&name.to_ascii_lowercase()) {
            Some(d) if matches!(d.kind, Kind::Output | Kind::Memory) => out.push((q, d.name.clone())),
            Some(_) => ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                r,
                format!("POU `{pou_name}`: action on `{name}`, which is not an output or a memory of the program"),
            ),
            None if child(pou, "actions")
                .is_some_and(|acts| children(acts, "action").any(|x| x.attribute("name") == Some(name))) =>
            {
                ctx.error(
                    codes::PLCOPEN_UNSUPPORTED,
                    r,
                    format!("POU `{pou_name}`: action `{name}` has a body of its own: Vigie runs actions on Boolean variables (associate the variable with the step)"),
                );
            }
            None => ctx.error(codes::PLCOPEN_UNKNOWN_NAME, r, format!("POU `{pou_name}`: action `{name}` is neither a declared variable nor an action of the POU")),
        }
    }
    out
}

fn read_condition(
    ctx: &mut Ctx<'_, '_>,
    pou: Node<'_, '_>,
    net: &Network<'_, '_>,
    t: Node<'_, '_>,
) -> Option<(Condition, Option<String>)> {
    let pou_name = pou.attribute("name").unwrap_or("?");
    let Some(cond) = child(t, "condition") else {
        ctx.error(
            codes::PLCOPEN_SFC_GRAPH,
            t,
            format!("POU `{pou_name}`: a transition without a condition"),
        );
        return None;
    };
    if let Some(inline) = child(cond, "inline") {
        return match child(inline, "ST") {
            Some(stn) => Some((Condition::St(st_text(ctx, stn)), None)),
            None => {
                ctx.error(
                    codes::PLCOPEN_UNSUPPORTED,
                    inline,
                    format!("POU `{pou_name}`: an inline condition not in ST"),
                );
                None
            }
        };
    }
    if let Some(r) = child(cond, "reference") {
        let name = r.attribute("name").unwrap_or("").to_string();
        let named = child(pou, "transitions").and_then(|ts| {
            children(ts, "transition").find(|x| x.attribute("name") == Some(name.as_str()))
        });
        let Some(named) = named else {
            ctx.error(codes::PLCOPEN_UNKNOWN_NAME, r, format!("POU `{pou_name}`: the condition names the transition `{name}`, which the POU does not define"));
            return None;
        };
        return match child(named, "body").and_then(|b| child(b, "ST")) {
            Some(stn) => Some((Condition::St(st_text(ctx, stn)), Some(name))),
            None => {
                ctx.error(codes::PLCOPEN_UNSUPPORTED, named, format!("POU `{pou_name}`: transition `{name}` is not written in ST (named LD and FBD transitions are not run yet)"));
                None
            }
        };
    }
    let mut em = super::ld::Emitted {
        pure: true,
        ..Default::default()
    };
    match net.input(ctx, cond, &mut Vec::new(), &mut em) {
        Ok(e) => Some((Condition::Network(e), None)),
        Err(e) => {
            ctx.error_at(e.code, e.at, format!("POU `{pou_name}`: {}", e.message));
            None
        }
    }
}

/// Reads a POU's SFC body.
pub(super) fn read(
    ctx: &mut Ctx<'_, '_>,
    pou: Node<'_, '_>,
    body: Node<'_, '_>,
    decls: &Declarations,
) -> Option<Chart> {
    let before = ctx.problems.len();
    let graph = Graph::new(body);
    let net = Network::new(body);
    let mut steps = Vec::new();
    let mut index: BTreeMap<u64, usize> = BTreeMap::new();
    for (&id, n) in &graph.nodes {
        if n.tag_name().name() == "step" {
            index.insert(id, steps.len());
            steps.push(SfcStep {
                name: n.attribute("name").unwrap_or("").to_string(),
                initial: n.attribute("initialStep") == Some("true"),
                at: ctx.at(*n),
                actions: Vec::new(),
            });
        }
    }
    steps.sort_by_key(|s| (s.at.line, s.at.column));
    let mut transitions = Vec::new();
    let mut ids = BTreeSet::new();
    for (&id, n) in &graph.nodes {
        match n.tag_name().name() {
            "actionBlock" => {
                let actions = read_actions(ctx, pou, *n, decls);
                let step = preds(*n)
                    .first()
                    .and_then(|p| graph.nodes.get(p))
                    .filter(|s| s.tag_name().name() == "step")
                    .and_then(|s| s.attribute("name"));
                match step.and_then(|name| steps.iter_mut().find(|s| s.name == name)) {
                    Some(s) => s.actions.extend(actions),
                    None => ctx.error(
                        codes::PLCOPEN_SFC_GRAPH,
                        *n,
                        "an action block not connected to a step",
                    ),
                }
            }
            "transition" => {
                let mut from = Vec::new();
                let mut to = Vec::new();
                if !graph.steps_before(ctx, *n, &mut from, 0)
                    || !graph.steps_after(ctx, id, &mut to, 0)
                {
                    continue;
                }
                if from.is_empty() || to.is_empty() {
                    ctx.error(
                        codes::PLCOPEN_SFC_GRAPH,
                        *n,
                        format!(
                            "transition (localId {id}) has no step {}",
                            if from.is_empty() {
                                "before it"
                            } else {
                                "after it"
                            }
                        ),
                    );
                    continue;
                }
                let Some((condition, name)) = read_condition(ctx, pou, &net, *n) else {
                    continue;
                };
                let mut tid = name.unwrap_or_else(|| format!("t{id}"));
                if !ids.insert(tid.clone()) {
                    tid = format!("{tid}_{id}");
                    ids.insert(tid.clone());
                }
                let x = child(*n, "position")
                    .and_then(|p| p.attribute("x"))
                    .and_then(|v| v.parse::<f64>().ok())
                    .unwrap_or(0.0);
                transitions.push(SfcTransition {
                    id: tid,
                    from,
                    to,
                    condition,
                    at: ctx.at(*n),
                    x,
                });
            }
            _ => {}
        }
    }
    transitions.sort_by_key(|t| (t.at.line, t.at.column));
    (ctx.problems.len() == before).then_some(Chart { steps, transitions })
}

/// The connected groups of steps (linked by transitions), as lists of step indices in
/// file order; a transition naming an unknown step is a problem.
fn groups(ctx: &mut Ctx<'_, '_>, pou: &str, chart: &Chart) -> Vec<Vec<usize>> {
    let n = chart.steps.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let pos = |name: &str| chart.steps.iter().position(|s| s.name == name);
    for t in &chart.transitions {
        let all: Vec<usize> = t.from.iter().chain(&t.to).filter_map(|s| pos(s)).collect();
        for w in all.windows(2) {
            let (a, b) = (root(&mut parent, w[0]), root(&mut parent, w[1]));
            parent[a] = b;
        }
        for s in t.from.iter().chain(&t.to) {
            if pos(s).is_none() {
                ctx.error_at(
                    codes::PLCOPEN_SFC_GRAPH,
                    t.at.clone(),
                    format!(
                        "POU `{pou}`: transition `{}` leads to the unknown step `{s}`",
                        t.id
                    ),
                );
            }
        }
    }
    let mut roots: Vec<usize> = Vec::new();
    let mut out: Vec<Vec<usize>> = Vec::new();
    for i in 0..n {
        let r = root(&mut parent, i);
        match roots.iter().position(|&x| x == r) {
            Some(k) => out[k].push(i),
            None => {
                roots.push(r);
                out.push(vec![i]);
            }
        }
    }
    out
}

/// A transition's condition in Vigie's logic, or the problem and where.
fn condition(
    file: &std::path::Path,
    t: &SfcTransition,
    m: &mut Machine,
    decls: &Declarations,
) -> Result<Expr, (codes::Code, Location, String)> {
    match &t.condition {
        Condition::St(text) => {
            let e = st::parse_condition(&text.text).map_err(|e| {
                (
                    codes::PLCOPEN_ST_INVALID,
                    text.locate(file, e.at),
                    e.message,
                )
            })?;
            let loc = |p: Pos| {
                let l = text.locate(file, p);
                Span {
                    line: l.line,
                    column: l.column,
                }
            };
            m.expr(&e, decls, Mode::Condition, &loc)
                .map_err(|f| (f.code, text.locate(file, f.at), f.message))
        }
        Condition::Network(e) => {
            let loc = |p: Pos| Span {
                line: p.line,
                column: p.column,
            };
            m.expr(e, decls, Mode::Condition, &loc).map_err(|f| {
                (
                    f.code,
                    Location::new(file, f.at.line, f.at.column),
                    f.message,
                )
            })
        }
    }
}

/// The Vigie charts of a POU's SFC: one per connected group of steps, named by
/// Vigie's block when the file has one, else after the POU.
pub(super) fn lower(
    ctx: &mut Ctx<'_, '_>,
    pou: &str,
    chart: &Chart,
    m: &mut Machine,
    decls: &Declarations,
    vigie: &VigieData,
) -> Vec<VigieChart> {
    let groups = groups(ctx, pou, chart);
    let file = ctx.file.to_path_buf();
    let mut out = Vec::new();
    for (k, members) in groups.iter().enumerate() {
        let name = members
            .iter()
            .find_map(|&i| vigie.charts.get(&chart.steps[i].name).cloned())
            .unwrap_or_else(|| {
                if groups.len() == 1 {
                    pou.to_string()
                } else {
                    format!("{pou}_{}", k + 1)
                }
            });
        let steps = members
            .iter()
            .map(|&i| {
                let s = &chart.steps[i];
                m.place(&s.name, "step", s.at.line, s.at.column);
                vigie_step(&s.name, s.initial, s.actions.clone())
            })
            .collect();
        let in_group = |t: &&SfcTransition| {
            t.from
                .first()
                .and_then(|s| chart.steps.iter().position(|x| x.name == *s))
                .is_some_and(|i| members.contains(&i))
        };
        let mut transitions = Vec::new();
        for t in chart.transitions.iter().filter(in_group) {
            m.place(&t.id, "transition", t.at.line, t.at.column);
            match condition(&file, t, m, decls) {
                Ok(c) => transitions.push((t, c)),
                Err((code, at, message)) => ctx.error_at(
                    code,
                    at,
                    format!("POU `{pou}`, transition `{}`: {message}", t.id),
                ),
            }
        }
        let conds = with_priorities(&transitions);
        let transitions = transitions
            .iter()
            .zip(conds)
            .map(|((t, _), c)| vigie_transition(&t.id, t.from.clone(), t.to.clone(), &c))
            .collect();
        out.push(vigie_chart(name, steps, transitions));
    }
    // Vigie's block gives the charts' order too.
    out.sort_by_key(|c| {
        vigie
            .chart_order
            .iter()
            .position(|n| *n == c.name)
            .unwrap_or(usize::MAX)
    });
    out
}

/// IEC 61131-3 selection: of the transitions leaving one step, the leftmost whose
/// condition is true fires, the others do not (Vigie's charts fire every enabled
/// transition, as GRAFCET does). Each condition is ANDed with the negation of the
/// conditions of the transitions to its left that can be true with it (a transition
/// with other source steps counts only when they are active); mutually exclusive
/// conditions are kept as written.
fn with_priorities(ts: &[(&SfcTransition, Expr)]) -> Vec<Expr> {
    let mut out: Vec<Expr> = ts.iter().map(|(_, c)| c.clone()).collect();
    for (k, (tk, ck)) in ts.iter().enumerate() {
        for (j, (tj, cj)) in ts.iter().enumerate() {
            if j == k || !tj.from.iter().any(|s| tk.from.contains(s)) {
                continue;
            }
            let left = (tj.x, tj.at.line, tj.at.column) < (tk.x, tk.at.line, tk.at.column);
            if !left {
                continue;
            }
            let mut higher = cj.clone();
            for s in tj.from.iter().filter(|s| !tk.from.contains(s)) {
                higher = and(higher, leaf(s, LeafKind::Now, Span { line: 0, column: 0 }));
            }
            if exclusive(ck, &higher) != Some(true) {
                out[k] = and(out[k].clone(), not(higher));
            }
        }
    }
    out
}

/// True when `a` and `b` are never true together (by enumeration over their atoms; an
/// edge is its value and its previous value), `None` beyond 16 atoms.
pub(super) fn exclusive(a: &Expr, b: &Expr) -> Option<bool> {
    let mut atoms: Vec<(String, bool)> = Vec::new();
    for e in [a, b] {
        for (name, kind, _) in e.leaves() {
            let wanted: &[bool] = match kind {
                LeafKind::Now | LeafKind::Estimate => &[false],
                LeafKind::Prev => &[true],
                LeafKind::Rise | LeafKind::Fall => &[false, true],
            };
            for &p in wanted {
                if !atoms.iter().any(|x| x.0 == name && x.1 == p) {
                    atoms.push((name.to_string(), p));
                }
            }
        }
    }
    if atoms.len() > 16 {
        return None;
    }
    fn eval(e: &Expr, atoms: &[(String, bool)], bits: u32) -> bool {
        let val = |name: &str, prev: bool| {
            atoms
                .iter()
                .position(|x| x.0 == name && x.1 == prev)
                .is_some_and(|i| bits & (1 << i) != 0)
        };
        match e {
            Expr::Const(b) => *b,
            Expr::Leaf { name, kind, .. } => match kind {
                LeafKind::Now | LeafKind::Estimate => val(name, false),
                LeafKind::Prev => val(name, true),
                LeafKind::Rise => val(name, false) && !val(name, true),
                LeafKind::Fall => !val(name, false) && val(name, true),
            },
            Expr::Not(x) => !eval(x, atoms, bits),
            Expr::And(xs) => xs.iter().all(|x| eval(x, atoms, bits)),
            Expr::Or(xs) => xs.iter().any(|x| eval(x, atoms, bits)),
        }
    }
    Some(!(0..1u32 << atoms.len()).any(|bits| eval(a, &atoms, bits) && eval(b, &atoms, bits)))
}
