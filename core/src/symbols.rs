//! Names to variables: the table every expression is resolved against.

use crate::expr::{ExprError, LeafKind, Span};
use std::collections::BTreeMap;

/// The four kinds of boolean variables a literal can read.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Space {
    /// PLC inputs: sensors (C0..C10).
    Input = 0,
    /// PLC outputs: actuators (A0..A6).
    Output = 1,
    /// Observers (P36, P67, 2P).
    Observer = 2,
    /// Auxiliary variables published by other engines: diagnoser flags (`def_C4`),
    /// interval variables (`I1`), sensor estimates (`EST(C4)`), task monitor outputs,
    /// and, inside a control program, its steps, timers and panel buttons.
    Aux = 3,
}

impl Space {
    /// All spaces, in index order.
    pub const ALL: [Space; 4] = [Space::Input, Space::Output, Space::Observer, Space::Aux];
}

/// One boolean variable at t or at t-1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Var {
    /// Which table.
    pub space: Space,
    /// Index in that table.
    pub index: u32,
    /// Value at t-1 rather than t.
    pub prev: bool,
}

/// A variable or its negation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Literal {
    /// The variable.
    pub var: Var,
    /// `false` for a negated literal.
    pub positive: bool,
}

/// The name table.
#[derive(Clone, Debug, Default)]
pub struct Symbols {
    by_name: BTreeMap<String, (Space, u32)>,
    names: [Vec<String>; 4],
}

impl Symbols {
    /// An empty table.
    pub fn new() -> Self {
        Self::default()
    }

    /// Declares `name` in `space` and returns its index; an existing name keeps its
    /// place and index (the first declaration wins) and is returned as `Err`.
    pub fn declare(&mut self, name: &str, space: Space) -> Result<u32, (Space, u32)> {
        if let Some(&existing) = self.by_name.get(name) {
            return Err(existing);
        }
        let list = &mut self.names[space as usize];
        let index = u32::try_from(list.len()).unwrap_or(u32::MAX);
        list.push(name.to_string());
        self.by_name.insert(name.to_string(), (space, index));
        Ok(index)
    }

    /// Looks a name up.
    pub fn lookup(&self, name: &str) -> Option<(Space, u32)> {
        self.by_name.get(name).copied()
    }

    /// Number of variables declared in `space`.
    pub fn len(&self, space: Space) -> usize {
        self.names[space as usize].len()
    }

    /// Sizes of the four spaces, for [`crate::frame::Frame::new`].
    pub fn sizes(&self) -> [usize; 4] {
        Space::ALL.map(|s| self.len(s))
    }

    /// The name of a variable.
    pub fn name(&self, space: Space, index: u32) -> &str {
        self.names[space as usize]
            .get(index as usize)
            .map_or("?", String::as_str)
    }

    /// Every name of a space, in index order.
    pub fn names(&self, space: Space) -> &[String] {
        &self.names[space as usize]
    }

    /// Resolves a leaf of an expression.
    pub fn resolve(&self, name: &str, kind: LeafKind, span: Span) -> Result<Var, ExprError> {
        if kind == LeafKind::Estimate {
            match self.lookup(name) {
                Some((Space::Input, _)) => {}
                Some(_) => {
                    return Err(ExprError {
                        message: format!("`EST({name})` needs a sensor, and `{name}` is not one"),
                        span,
                    });
                }
                None => {
                    return Err(ExprError {
                        message: format!("unknown signal `{name}`"),
                        span,
                    });
                }
            }
            let est = estimate_name(name);
            return match self.lookup(&est) {
                Some((space, index)) => Ok(Var {
                    space,
                    index,
                    prev: false,
                }),
                None => Err(ExprError {
                    message: format!("no diagnoser provides the estimate `{est}`"),
                    span,
                }),
            };
        }
        let Some((space, index)) = self.lookup(name) else {
            return Err(ExprError {
                message: format!("unknown signal `{name}`"),
                span,
            });
        };
        Ok(Var {
            space,
            index,
            prev: kind == LeafKind::Prev,
        })
    }

    /// Renders a literal in the file notation.
    pub fn render_literal(&self, lit: Literal) -> String {
        format!(
            "{}{}{}",
            if lit.positive { "" } else { "/" },
            self.name(lit.var.space, lit.var.index),
            if lit.var.prev { "*" } else { "" }
        )
    }
}

/// The auxiliary name under which a diagnoser publishes the estimate of `sensor`.
pub fn estimate_name(sensor: &str) -> String {
    format!("EST({sensor})")
}
