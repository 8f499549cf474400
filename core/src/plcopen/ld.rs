//! Ladder networks (LD bodies, and the contacts that feed an SFC transition) as ST:
//! the power flow into each element is the OR of its connections, a contact ANDs its
//! literal, a coil passes the flow on; each coil becomes one statement, in the order of
//! the rungs (top to bottom, then left to right, unless the tool gave an execution
//! order).

use super::read::{Ctx, StText, child, children, st_text};
use super::st::{self, Pos, StExpr, Stmt};
use crate::diag::Location;
use crate::diag::codes::{self, Code};
use roxmltree::Node;
use std::collections::BTreeMap;

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

impl<'a, 'i> Network<'a, 'i> {
    pub(super) fn new(body: Node<'a, 'i>) -> Self {
        let nodes = body
            .children()
            .filter(Node::is_element)
            .filter_map(|n| local_id(n).map(|id| (id, n)))
            .collect();
        Self { nodes }
    }

    /// The power flow into `node` (OR of the connections of its `connectionPointIn`).
    pub(super) fn input(
        &self,
        ctx: &Ctx<'_, '_>,
        node: Node<'_, '_>,
        seen: &mut Vec<u64>,
    ) -> Result<StExpr, NetError> {
        let mut flow: Option<StExpr> = None;
        for cpi in children(node, "connectionPointIn") {
            for c in children(cpi, "connection") {
                let Some(r) = c
                    .attribute("refLocalId")
                    .and_then(|v| v.parse::<u64>().ok())
                else {
                    return Err(NetError {
                        code: codes::PLCOPEN_SFC_GRAPH,
                        at: ctx.at(c),
                        message: "a connection without refLocalId".into(),
                    });
                };
                if c.attribute("formalParameter")
                    .is_some_and(|p| !p.is_empty())
                {
                    return Err(NetError {
                        code: codes::PLCOPEN_UNSUPPORTED,
                        at: ctx.at(c),
                        message: format!(
                            "a connection from the pin `{}` of a block: function blocks in LD and FBD are not run yet",
                            c.attribute("formalParameter").unwrap_or("")
                        ),
                    });
                }
                let f = self.flow(ctx, r, c, seen)?;
                flow = Some(match flow {
                    None => f,
                    Some(prev) => StExpr::Bin(st::BinOp::Or, Box::new(prev), Box::new(f)),
                });
            }
        }
        flow.ok_or_else(|| NetError {
            code: codes::PLCOPEN_SFC_GRAPH,
            at: ctx.at(node),
            message: format!(
                "`{}` (localId {}) is connected to nothing",
                node.tag_name().name(),
                local_id(node).unwrap_or(0)
            ),
        })
    }

    fn flow(
        &self,
        ctx: &Ctx<'_, '_>,
        id: u64,
        from: Node<'_, '_>,
        seen: &mut Vec<u64>,
    ) -> Result<StExpr, NetError> {
        let Some(&n) = self.nodes.get(&id) else {
            return Err(NetError {
                code: codes::PLCOPEN_SFC_GRAPH,
                at: ctx.at(from),
                message: format!("a connection to localId {id}, which no element has"),
            });
        };
        if seen.contains(&id) {
            return Err(NetError {
                code: codes::PLCOPEN_SFC_GRAPH,
                at: ctx.at(n),
                message: format!("the network loops back through localId {id}"),
            });
        }
        seen.push(id);
        let out = match n.tag_name().name() {
            "leftPowerRail" => Ok(StExpr::Bool(true)),
            "contact" => {
                let name = variable_name(n);
                if name.is_empty() {
                    return Err(NetError {
                        code: codes::PLCOPEN_SFC_GRAPH,
                        at: ctx.at(n),
                        message: "a contact without a variable".into(),
                    });
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
                let input = self.input(ctx, n, seen)?;
                Ok(and(input, lit))
            }
            "coil" => self.input(ctx, n, seen),
            "inVariable" => {
                let Some(e) = child(n, "expression") else {
                    return Err(NetError {
                        code: codes::PLCOPEN_SFC_GRAPH,
                        at: ctx.at(n),
                        message: "an input variable without an expression".into(),
                    });
                };
                let text = st_text(ctx, e);
                st::parse_condition(&text.text)
                    .map(|x| relocate(x, &text))
                    .map_err(|err| NetError {
                        code: codes::PLCOPEN_ST_INVALID,
                        at: text.locate(ctx.file, err.at),
                        message: err.message,
                    })
            }
            other => Err(NetError {
                code: codes::PLCOPEN_UNSUPPORTED,
                at: ctx.at(n),
                message: format!(
                    "`{other}` elements are not run (LD: power rails, contacts and coils)"
                ),
            }),
        };
        seen.pop();
        out
    }

    /// The coils of the network in rung order.
    fn coils(&self) -> Vec<Node<'a, 'i>> {
        let mut coils: Vec<Node<'a, 'i>> = self
            .nodes
            .values()
            .copied()
            .filter(|n| n.tag_name().name() == "coil")
            .collect();
        let key = |n: &Node<'_, '_>| {
            let order = n
                .attribute("executionOrderId")
                .and_then(|v| v.parse::<u64>().ok())
                .unwrap_or(0);
            let pos = child(*n, "position");
            let coord = |a: &str| {
                pos.and_then(|p| p.attribute(a))
                    .and_then(|v| v.parse::<f64>().ok())
                    .unwrap_or(0.0)
            };
            (order, coord("y"), coord("x"), n.range().start)
        };
        coils.sort_by(|a, b| {
            let (ka, kb) = (key(a), key(b));
            ka.0.cmp(&kb.0)
                .then(ka.1.total_cmp(&kb.1))
                .then(ka.2.total_cmp(&kb.2))
                .then(ka.3.cmp(&kb.3))
        });
        coils
    }
}

fn and(a: StExpr, b: StExpr) -> StExpr {
    match a {
        StExpr::Bool(true) => b,
        a => StExpr::Bin(st::BinOp::And, Box::new(a), Box::new(b)),
    }
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

/// An LD body as statements; positions are file positions (the returned text's origin
/// is 1:1).
pub(super) fn read_body(
    ctx: &mut Ctx<'_, '_>,
    pou: &str,
    body: Node<'_, '_>,
) -> Option<(Vec<Stmt>, StText)> {
    let net = Network::new(body);
    let mut stmts = Vec::new();
    let mut failed = false;
    for n in body.children().filter(Node::is_element) {
        let name = n.tag_name().name();
        if !matches!(
            name,
            "leftPowerRail" | "rightPowerRail" | "contact" | "coil" | "comment" | "inVariable"
        ) {
            ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                n,
                format!("POU `{pou}`: `{name}` elements are not run (LD: power rails, contacts and coils; function blocks in LD are not run yet)"),
            );
            failed = true;
        }
    }
    if failed {
        return None;
    }
    for coil in net.coils() {
        let var = variable_name(coil);
        let at = pos_of(ctx, coil);
        let flow = match net.input(ctx, coil, &mut Vec::new()) {
            Ok(f) => f,
            Err(e) => {
                ctx.error_at(e.code, e.at, format!("POU `{pou}`: {}", e.message));
                failed = true;
                continue;
            }
        };
        let target = path_of(&var);
        let assign = |value: StExpr| Stmt::Assign {
            target: target.clone(),
            value,
            at,
        };
        let storage = coil.attribute("storage").unwrap_or("none");
        let stmt = match (storage, coil.attribute("negated") == Some("true")) {
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
        };
        if coil.attribute("edge").is_some_and(|e| e != "none") {
            ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                coil,
                format!("POU `{pou}`: coil `{var}`: transition-sensing coils are not run"),
            );
            failed = true;
            continue;
        }
        stmts.push(stmt);
    }
    (!failed).then(|| {
        (
            stmts,
            StText {
                text: String::new(),
                line: 1,
                column: 1,
            },
        )
    })
}
