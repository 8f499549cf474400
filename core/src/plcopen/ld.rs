//! Graphical networks (LD and FBD bodies, and the contacts or blocks that feed an SFC
//! transition) as ST: the power flow into each element is the OR of its connections,
//! a contact ANDs its literal, a coil passes the flow on, a standard function (`AND`,
//! `OR`, `XOR`, `NOT`) combines its inputs, and a function-block instance (`TON`, `TOF`,
//! `TP`, `R_TRIG`, `F_TRIG`) becomes a call, emitted before anything reads its output.
//! Coils, output variables and instances are taken in the order of the network (the
//! tool's execution order when it gives one, else top to bottom, then left to right).

use super::read::{Ctx, StText, child, children, st_text};
use super::st::{self, BinOp, Pos, StExpr, Stmt};
use crate::diag::Location;
use crate::diag::codes::{self, Code};
use roxmltree::Node;
use std::collections::{BTreeMap, BTreeSet};

/// The elements of one graphical body, by `localId`.
pub(super) struct Network<'a, 'i> {
    nodes: BTreeMap<u64, Node<'a, 'i>>,
}

/// Why a flow cannot be read.
pub(super) struct NetError {
    pub(super) code: Code,
    pub(super) at: Location,
    pub(super) message: String,
}

/// The function-block calls emitted so far, in order.
#[derive(Default)]
pub(super) struct Emitted {
    pub(super) stmts: Vec<Stmt>,
    pub(super) done: BTreeSet<u64>,
    /// Calls are refused (an SFC transition's network).
    pub(super) pure: bool,
}

fn local_id(n: Node<'_, '_>) -> Option<u64> {
    n.attribute("localId").and_then(|v| v.parse().ok())
}

/// The position of an element as an ST position (its file line and column), so that the
/// expressions built from it place their problems in the file.
fn pos_of(ctx: &Ctx<'_, '_>, n: Node<'_, '_>) -> Pos {
    let l = ctx.at(n);
    Pos {
        line: l.line,
        column: l.column,
    }
}

/// The text of a `<variable>` child, trimmed.
fn variable_name(n: Node<'_, '_>) -> String {
    child(n, "variable")
        .and_then(|v| v.text())
        .unwrap_or("")
        .trim()
        .to_string()
}

/// A variable name as a path (`a` or `inst.Q`).
fn path_of(name: &str) -> Vec<String> {
    name.split('.').map(str::to_string).collect()
}

fn err<T>(code: Code, at: Location, message: impl Into<String>) -> Result<T, NetError> {
    Err(NetError {
        code,
        at,
        message: message.into(),
    })
}

const INSTANCES: &[&str] = &["TON", "TOF", "TP", "R_TRIG", "F_TRIG"];
const FUNCTIONS: &[&str] = &["AND", "OR", "XOR", "NOT"];

fn and(a: StExpr, b: StExpr) -> StExpr {
    match a {
        StExpr::Bool(true) => b,
        a => StExpr::Bin(BinOp::And, Box::new(a), Box::new(b)),
    }
}

/// The key of an element in network order.
fn order_key(n: Node<'_, '_>) -> (u64, f64, f64, usize) {
    let order = n
        .attribute("executionOrderId")
        .and_then(|v| v.parse::<u64>().ok())
        .unwrap_or(0);
    let pos = child(n, "position");
    let coord = |a: &str| {
        pos.and_then(|p| p.attribute(a))
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (order, coord("y"), coord("x"), n.range().start)
}

impl<'a, 'i> Network<'a, 'i> {
    pub(super) fn new(body: Node<'a, 'i>) -> Self {
        let nodes = body
            .children()
            .filter(Node::is_element)
            .filter_map(|n| local_id(n).map(|id| (id, n)))
            .collect();
        Self { nodes }
    }

    /// The flow into a `connectionPointIn` (OR of its connections).
    fn point(
        &self,
        ctx: &Ctx<'_, '_>,
        cpi: Node<'_, '_>,
        owner: Node<'_, '_>,
        seen: &mut Vec<u64>,
        em: &mut Emitted,
    ) -> Result<StExpr, NetError> {
        let mut flow: Option<StExpr> = None;
        for c in children(cpi, "connection") {
            let Some(r) = c
                .attribute("refLocalId")
                .and_then(|v| v.parse::<u64>().ok())
            else {
                return err(
                    codes::PLCOPEN_SFC_GRAPH,
                    ctx.at(c),
                    "a connection without refLocalId",
                );
            };
            let pin = c.attribute("formalParameter").unwrap_or("");
            let f = self.flow(ctx, r, pin, c, seen, em)?;
            flow = Some(match flow {
                None => f,
                Some(prev) => StExpr::Bin(BinOp::Or, Box::new(prev), Box::new(f)),
            });
        }
        flow.ok_or_else(|| NetError {
            code: codes::PLCOPEN_SFC_GRAPH,
            at: ctx.at(owner),
            message: format!(
                "`{}` (localId {}) is connected to nothing",
                owner.tag_name().name(),
                local_id(owner).unwrap_or(0)
            ),
        })
    }

    /// The power flow into `node` (its direct `connectionPointIn`).
    pub(super) fn input(
        &self,
        ctx: &Ctx<'_, '_>,
        node: Node<'_, '_>,
        seen: &mut Vec<u64>,
        em: &mut Emitted,
    ) -> Result<StExpr, NetError> {
        match child(node, "connectionPointIn") {
            Some(cpi) => self.point(ctx, cpi, node, seen, em),
            None => err(
                codes::PLCOPEN_SFC_GRAPH,
                ctx.at(node),
                format!(
                    "`{}` (localId {}) is connected to nothing",
                    node.tag_name().name(),
                    local_id(node).unwrap_or(0)
                ),
            ),
        }
    }

    fn flow(
        &self,
        ctx: &Ctx<'_, '_>,
        id: u64,
        pin: &str,
        from: Node<'_, '_>,
        seen: &mut Vec<u64>,
        em: &mut Emitted,
    ) -> Result<StExpr, NetError> {
        let Some(&n) = self.nodes.get(&id) else {
            return err(
                codes::PLCOPEN_SFC_GRAPH,
                ctx.at(from),
                format!("a connection to localId {id}, which no element has"),
            );
        };
        if seen.contains(&id) {
            return err(
                codes::PLCOPEN_SFC_GRAPH,
                ctx.at(n),
                format!("the network loops back through localId {id}"),
            );
        }
        seen.push(id);
        let out = match n.tag_name().name() {
            "leftPowerRail" => Ok(StExpr::Bool(true)),
            "contact" => self.contact(ctx, n, seen, em),
            "coil" => self.input(ctx, n, seen, em),
            "inVariable" | "inOutVariable" => expression(ctx, n),
            "block" => self.block_output(ctx, n, pin, seen, em),
            other => err(
                codes::PLCOPEN_UNSUPPORTED,
                ctx.at(n),
                format!(
                    "`{other}` elements are not run (LD: power rails, contacts, coils and blocks; FBD: variables and blocks)"
                ),
            ),
        };
        seen.pop();
        out
    }

    fn contact(
        &self,
        ctx: &Ctx<'_, '_>,
        n: Node<'_, '_>,
        seen: &mut Vec<u64>,
        em: &mut Emitted,
    ) -> Result<StExpr, NetError> {
        let name = variable_name(n);
        if name.is_empty() {
            return err(
                codes::PLCOPEN_SFC_GRAPH,
                ctx.at(n),
                "a contact without a variable",
            );
        }
        let at = pos_of(ctx, n);
        let path = path_of(&name);
        let lit = match n.attribute("edge").unwrap_or("none") {
            "rising" => StExpr::Edge {
                rising: true,
                path,
                at,
            },
            "falling" => StExpr::Edge {
                rising: false,
                path,
                at,
            },
            _ => StExpr::Var { path, at },
        };
        let lit = if n.attribute("negated") == Some("true") {
            StExpr::Not(Box::new(lit))
        } else {
            lit
        };
        let input = self.input(ctx, n, seen, em)?;
        Ok(and(input, lit))
    }

    /// A block's inputs by formal parameter, with EN checked (always true or absent).
    fn block_inputs(
        &self,
        ctx: &Ctx<'_, '_>,
        n: Node<'_, '_>,
        seen: &mut Vec<u64>,
        em: &mut Emitted,
    ) -> Result<Vec<(String, StExpr)>, NetError> {
        let mut out = Vec::new();
        let vars = child(n, "inputVariables");
        for v in vars.iter().flat_map(|vs| children(*vs, "variable")) {
            let param = v.attribute("formalParameter").unwrap_or("").to_string();
            let Some(cpi) = child(v, "connectionPointIn") else {
                continue;
            };
            if children(cpi, "connection").next().is_none() {
                continue;
            }
            let mut flow = self.point(ctx, cpi, n, seen, em)?;
            if v.attribute("negated") == Some("true") {
                flow = StExpr::Not(Box::new(flow));
            }
            if param.eq_ignore_ascii_case("EN") {
                if flow != StExpr::Bool(true) {
                    return err(
                        codes::PLCOPEN_UNSUPPORTED,
                        ctx.at(v),
                        format!(
                            "block `{}`: EN is not always true; a call under a condition is not run",
                            n.attribute("instanceName")
                                .or(n.attribute("typeName"))
                                .unwrap_or("?")
                        ),
                    );
                }
                continue;
            }
            out.push((param, flow));
        }
        Ok(out)
    }

    fn block_output(
        &self,
        ctx: &Ctx<'_, '_>,
        n: Node<'_, '_>,
        pin: &str,
        seen: &mut Vec<u64>,
        em: &mut Emitted,
    ) -> Result<StExpr, NetError> {
        let ty = n.attribute("typeName").unwrap_or("").to_ascii_uppercase();
        let instance = n.attribute("instanceName").unwrap_or("");
        if pin.eq_ignore_ascii_case("ENO") {
            // EN is always true (checked with the inputs).
            self.block_inputs(ctx, n, seen, em)?;
            if !instance.is_empty() {
                self.call(ctx, n, seen, em)?;
            }
            return Ok(StExpr::Bool(true));
        }
        if instance.is_empty() {
            let inputs = self.block_inputs(ctx, n, seen, em)?;
            let mut args = inputs.into_iter().map(|(_, e)| e);
            let first = args.next();
            return match (ty.as_str(), first) {
                ("NOT", Some(x)) => Ok(StExpr::Not(Box::new(x))),
                ("AND" | "OR" | "XOR", Some(x)) => {
                    let op = match ty.as_str() {
                        "AND" => BinOp::And,
                        "OR" => BinOp::Or,
                        _ => BinOp::Xor,
                    };
                    Ok(args.fold(x, |acc, y| StExpr::Bin(op, Box::new(acc), Box::new(y))))
                }
                (t, _) if FUNCTIONS.contains(&t) => err(
                    codes::PLCOPEN_SFC_GRAPH,
                    ctx.at(n),
                    format!("block `{t}` has no input connected"),
                ),
                (t, _) => err(
                    codes::PLCOPEN_UNSUPPORTED,
                    ctx.at(n),
                    format!("the function `{t}` is not run (AND, OR, XOR and NOT are)"),
                ),
            };
        }
        if !pin.eq_ignore_ascii_case("Q") {
            return err(
                codes::PLCOPEN_UNSUPPORTED,
                ctx.at(n),
                format!("`{instance}.{pin}` is read: only the Q output of {ty} is run"),
            );
        }
        self.call(ctx, n, seen, em)?;
        Ok(StExpr::Var {
            path: vec![instance.to_string(), "Q".into()],
            at: pos_of(ctx, n),
        })
    }

    /// Emits the call of a function-block instance, once.
    fn call(
        &self,
        ctx: &Ctx<'_, '_>,
        n: Node<'_, '_>,
        seen: &mut Vec<u64>,
        em: &mut Emitted,
    ) -> Result<(), NetError> {
        let id = local_id(n).unwrap_or(0);
        if em.done.contains(&id) {
            return Ok(());
        }
        let ty = n.attribute("typeName").unwrap_or("").to_ascii_uppercase();
        let instance = n.attribute("instanceName").unwrap_or("").to_string();
        if !INSTANCES.contains(&ty.as_str()) {
            return err(
                codes::PLCOPEN_UNSUPPORTED,
                ctx.at(n),
                format!(
                    "`{instance}` is an instance of {ty}: the function blocks run are TON, TOF, TP, R_TRIG and F_TRIG"
                ),
            );
        }
        if em.pure {
            return err(
                codes::PLCOPEN_UNSUPPORTED,
                ctx.at(n),
                format!("`{instance}` is called in a transition's network: call it in a body"),
            );
        }
        em.done.insert(id);
        let args = self.block_inputs(ctx, n, seen, em)?;
        em.stmts.push(Stmt::Call {
            instance,
            args,
            at: pos_of(ctx, n),
        });
        Ok(())
    }

    /// The elements that act, in network order: coils, output variables and
    /// function-block instances.
    fn actors(&self) -> Vec<Node<'a, 'i>> {
        let mut v: Vec<Node<'a, 'i>> = self
            .nodes
            .values()
            .copied()
            .filter(|n| match n.tag_name().name() {
                "coil" | "outVariable" => true,
                "block" => n.attribute("instanceName").is_some_and(|i| !i.is_empty()),
                _ => false,
            })
            .collect();
        v.sort_by(|a, b| {
            let (ka, kb) = (order_key(*a), order_key(*b));
            ka.0.cmp(&kb.0)
                .then(ka.1.total_cmp(&kb.1))
                .then(ka.2.total_cmp(&kb.2))
                .then(ka.3.cmp(&kb.3))
        });
        v
    }
}

/// The expression of an FBD variable (`<expression>`), at its file position.
fn expression(ctx: &Ctx<'_, '_>, n: Node<'_, '_>) -> Result<StExpr, NetError> {
    let Some(e) = child(n, "expression") else {
        return err(
            codes::PLCOPEN_SFC_GRAPH,
            ctx.at(n),
            "a variable without an expression",
        );
    };
    let text = st_text(ctx, e);
    st::parse_condition(&text.text)
        .map(|x| relocate(x, &text))
        .map_err(|e| NetError {
            code: codes::PLCOPEN_ST_INVALID,
            at: text.locate(ctx.file, e.at),
            message: e.message,
        })
}

/// Moves the positions of an expression parsed from `text` to file positions.
fn relocate(e: StExpr, text: &StText) -> StExpr {
    let map = |p: Pos| {
        if p.line <= 1 {
            Pos {
                line: text.line,
                column: text.column + p.column.saturating_sub(1),
            }
        } else {
            Pos {
                line: text.line + p.line - 1,
                column: p.column,
            }
        }
    };
    match e {
        StExpr::Var { path, at } => StExpr::Var { path, at: map(at) },
        StExpr::Edge { rising, path, at } => StExpr::Edge {
            rising,
            path,
            at: map(at),
        },
        StExpr::Not(x) => StExpr::Not(Box::new(relocate(*x, text))),
        StExpr::Bin(op, a, b) => StExpr::Bin(
            op,
            Box::new(relocate(*a, text)),
            Box::new(relocate(*b, text)),
        ),
        other => other,
    }
}

/// The statement of a coil or an output variable fed by `flow`.
fn actor_statement(ctx: &Ctx<'_, '_>, n: Node<'_, '_>, flow: StExpr) -> Result<Stmt, NetError> {
    let at = pos_of(ctx, n);
    let target = if n.tag_name().name() == "coil" {
        path_of(&variable_name(n))
    } else {
        let Some(e) = child(n, "expression") else {
            return err(
                codes::PLCOPEN_SFC_GRAPH,
                ctx.at(n),
                "an output variable without an expression",
            );
        };
        path_of(e.text().unwrap_or("").trim())
    };
    let assign = |value: StExpr| Stmt::Assign {
        target: target.clone(),
        value,
        at,
    };
    if n.attribute("edge").is_some_and(|e| e != "none") {
        return err(
            codes::PLCOPEN_UNSUPPORTED,
            ctx.at(n),
            format!(
                "coil `{}`: transition-sensing coils are not run",
                target.join(".")
            ),
        );
    }
    Ok(
        match (
            n.attribute("storage").unwrap_or("none"),
            n.attribute("negated") == Some("true"),
        ) {
            ("set", _) => Stmt::If {
                branches: vec![(flow, vec![assign(StExpr::Bool(true))])],
                otherwise: Vec::new(),
            },
            ("reset", _) => Stmt::If {
                branches: vec![(flow, vec![assign(StExpr::Bool(false))])],
                otherwise: Vec::new(),
            },
            (_, true) => assign(StExpr::Not(Box::new(flow))),
            _ => assign(flow),
        },
    )
}

/// An LD or FBD body as statements; positions are file positions (the returned text's
/// origin is 1:1).
pub(super) fn read_body(
    ctx: &mut Ctx<'_, '_>,
    pou: &str,
    body: Node<'_, '_>,
) -> Option<(Vec<Stmt>, StText)> {
    let allowed: &[&str] = &[
        "leftPowerRail",
        "rightPowerRail",
        "contact",
        "coil",
        "comment",
        "inVariable",
        "outVariable",
        "block",
    ];
    let mut failed = false;
    for n in body.children().filter(Node::is_element) {
        let name = n.tag_name().name();
        if !allowed.contains(&name) {
            ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                n,
                format!("POU `{pou}`: `{name}` elements are not run (power rails, contacts, coils, variables and blocks are)"),
            );
            failed = true;
        }
    }
    if failed {
        return None;
    }
    let net = Network::new(body);
    let mut em = Emitted::default();
    for actor in net.actors() {
        let result = if actor.tag_name().name() == "block" {
            net.call(ctx, actor, &mut Vec::new(), &mut em)
        } else {
            net.input(ctx, actor, &mut Vec::new(), &mut em)
                .and_then(|flow| actor_statement(ctx, actor, flow))
                .map(|s| em.stmts.push(s))
        };
        if let Err(e) = result {
            ctx.error_at(e.code, e.at, format!("POU `{pou}`: {}", e.message));
            failed = true;
        }
    }
    (!failed).then(|| {
        (
            em.stmts,
            StText {
                text: String::new(),
                line: 1,
                column: 1,
            },
        )
    })
}
