//! The logic notation shared by constraints, observers, control programs and diagnosers.
//!
//! It stays close to the paper (seed 004, section 2):
//!
//! | notation        | meaning                                   | paper          |
//! |-----------------|-------------------------------------------|----------------|
//! | `C7`            | signal, observer or auxiliary at cycle t  | `e_j`, `s_k`   |
//! | `/C7` or `!C7`  | negation                                  | overbar        |
//! | `C7*`, `PRE(C7)`| value at cycle t-1                        | `E*_j`, `S*_k` |
//! | `RE(A4)`        | rising edge, `/A4* . A4`                  | up arrow       |
//! | `FE(A4)`        | falling edge, `A4* . /A4`                 | down arrow     |
//! | `EST(C4)`       | the diagnoser's time-interval estimate of a sensor | hat    |
//! | `a . b`         | and                                       | `.`            |
//! | `a + b`         | or                                        | `+`            |
//! | `( … )`, `0`, `1` | grouping and constants                  |                |
//!
//! Names are letters, digits and `_` (so the paper's `2P` is a name), optionally
//! qualified once with `:` (`turn:infeasible`).
//! Parsing gives an [`Expr`] whose leaves keep their position, so that resolving a name
//! against a [`crate::symbols::Symbols`] table can report an unknown one precisely.

use crate::symbols::{Literal, Symbols, Var};

/// A position in the source text, 1-based line and column (in characters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1.
    pub column: usize,
}

/// How a name is used in a leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeafKind {
    /// Value at t.
    Now,
    /// Value at t-1 (`x*`, `PRE(x)`).
    Prev,
    /// Rising edge `RE(x)`.
    Rise,
    /// Falling edge `FE(x)`.
    Fall,
    /// Time-interval estimate `EST(x)` of a diagnosed sensor.
    Estimate,
}

/// A parsed logic expression.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Expr {
    /// `0` or `1`.
    Const(bool),
    /// A name, possibly wrapped in `PRE`, `RE`, `FE` or `EST`.
    Leaf {
        /// The name as written.
        name: String,
        /// How it is used.
        kind: LeafKind,
        /// Where the name starts.
        span: Span,
    },
    /// Negation.
    Not(Box<Expr>),
    /// Conjunction.
    And(Vec<Expr>),
    /// Disjunction.
    Or(Vec<Expr>),
}

/// A syntax or name error, with its position on the line.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct ExprError {
    /// What went wrong, naming the offending token.
    pub message: String,
    /// Where.
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Tok {
    Name(String),
    Not,
    And,
    Or,
    Star,
    Open,
    Close,
    End,
}

impl Tok {
    fn describe(&self) -> String {
        match self {
            Tok::Name(n) => format!("`{n}`"),
            Tok::Not => "`/`".into(),
            Tok::And => "`.`".into(),
            Tok::Or => "`+`".into(),
            Tok::Star => "`*`".into(),
            Tok::Open => "`(`".into(),
            Tok::Close => "`)`".into(),
            Tok::End => "end of expression".into(),
        }
    }
}

fn lex(text: &str, first: Span) -> Result<Vec<(Tok, Span)>, ExprError> {
    let mut toks = Vec::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let span = Span {
            line: first.line,
            column: first.column + i,
        };
        let single = match c {
            '/' | '!' | '¬' => Some(Tok::Not),
            '.' | '·' => Some(Tok::And),
            '+' => Some(Tok::Or),
            '*' => Some(Tok::Star),
            '(' => Some(Tok::Open),
            ')' => Some(Tok::Close),
            _ => None,
        };
        if let Some(t) = single {
            toks.push((t, span));
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            // One optional `:name` qualifier.
            if i + 1 < chars.len()
                && chars[i] == ':'
                && (chars[i + 1].is_ascii_alphanumeric() || chars[i + 1] == '_')
            {
                i += 1;
                while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
            }
            toks.push((Tok::Name(chars[start..i].iter().collect()), span));
        } else {
            return Err(ExprError {
                message: format!("unexpected character `{c}`"),
                span,
            });
        }
    }
    toks.push((
        Tok::End,
        Span {
            line: first.line,
            column: first.column + chars.len(),
        },
    ));
    Ok(toks)
}

struct Parser {
    toks: Vec<(Tok, Span)>,
    pos: usize,
}

impl Parser {
    fn peek(&self) -> &(Tok, Span) {
        let last = self.toks.len().saturating_sub(1);
        &self.toks[self.pos.min(last)]
    }

    fn bump(&mut self) -> (Tok, Span) {
        let t = self.peek().clone();
        if self.pos < self.toks.len() {
            self.pos += 1;
        }
        t
    }

    fn or(&mut self, depth: usize) -> Result<Expr, ExprError> {
        let mut terms = vec![self.and(depth)?];
        while self.peek().0 == Tok::Or {
            self.bump();
            terms.push(self.and(depth)?);
        }
        Ok(if terms.len() == 1 {
            terms.remove(0)
        } else {
            Expr::Or(terms)
        })
    }

    fn and(&mut self, depth: usize) -> Result<Expr, ExprError> {
        let mut factors = vec![self.unary(depth)?];
        while self.peek().0 == Tok::And {
            self.bump();
            factors.push(self.unary(depth)?);
        }
        Ok(if factors.len() == 1 {
            factors.remove(0)
        } else {
            Expr::And(factors)
        })
    }

    fn unary(&mut self, depth: usize) -> Result<Expr, ExprError> {
        if depth > 64 {
            return Err(ExprError {
                message: "expression nested too deeply".into(),
                span: self.peek().1,
            });
        }
        let (tok, span) = self.bump();
        match tok {
            Tok::Not => Ok(Expr::Not(Box::new(self.unary(depth + 1)?))),
            Tok::Open => {
                let inner = self.or(depth + 1)?;
                self.expect_close()?;
                Ok(inner)
            }
            Tok::Name(name) => self.name(name, span),
            other => Err(ExprError {
                message: format!(
                    "expected a name, `/` or `(`, found {}",
                    other.describe()
                ),
                span,
            }),
        }
    }

    fn expect_close(&mut self) -> Result<(), ExprError> {
        let (tok, span) = self.bump();
        if tok == Tok::Close {
            Ok(())
        } else {
            Err(ExprError {
                message: format!("expected `)`, found {}", tok.describe()),
                span,
            })
        }
    }

    fn name(&mut self, name: String, span: Span) -> Result<Expr, ExprError> {
        if name.chars().all(|c| c.is_ascii_digit()) {
            return match name.as_str() {
                "0" => Ok(Expr::Const(false)),
                "1" => Ok(Expr::Const(true)),
                _ => Err(ExprError {
                    message: format!("`{name}` is not a name nor the constant 0 or 1"),
                    span,
                }),
            };
        }
        let function = match name.as_str() {
            "RE" => Some(LeafKind::Rise),
            "FE" => Some(LeafKind::Fall),
            "PRE" => Some(LeafKind::Prev),
            "EST" => Some(LeafKind::Estimate),
            _ => None,
        };
        if let (Some(kind), Tok::Open) = (function, &self.peek().0) {
            self.bump();
            let (tok, inner_span) = self.bump();
            let Tok::Name(inner) = tok else {
                return Err(ExprError {
                    message: format!("expected a name inside `{name}(…)`, found {}", tok.describe()),
                    span: inner_span,
                });
            };
            self.expect_close()?;
            return Ok(Expr::Leaf {
                name: inner,
                kind,
                span: inner_span,
            });
        }
        if self.peek().0 == Tok::Star {
            self.bump();
            return Ok(Expr::Leaf {
                name,
                kind: LeafKind::Prev,
                span,
            });
        }
        Ok(Expr::Leaf {
            name,
            kind: LeafKind::Now,
            span,
        })
    }
}

/// Parses `text`, whose first character sits at `first` in its file.
pub fn parse(text: &str, first: Span) -> Result<Expr, ExprError> {
    let mut p = Parser {
        toks: lex(text, first)?,
        pos: 0,
    };
    let expr = p.or(0)?;
    let (tok, span) = p.bump();
    if tok != Tok::End {
        return Err(ExprError {
            message: format!("expected `.`, `+` or end of expression, found {}", tok.describe()),
            span,
        });
    }
    Ok(expr)
}

/// Parses a one-line expression (position 1:1), as used in RON fields.
pub fn parse_str(text: &str) -> Result<Expr, ExprError> {
    parse(text, Span { line: 1, column: 1 })
}

/// A sum of products: the expression is true when any term has all its literals true.
/// An empty sum is false; an empty term is true.
pub type Dnf = Vec<Vec<Literal>>;

/// Largest number of product terms a single expression may expand to.
pub const MAX_TERMS: usize = 4096;

impl Expr {
    /// Resolves every name against `symbols` and expands to a sum of products.
    ///
    /// Terms are sorted and deduplicated; contradictory terms (`x . /x`) are kept, so
    /// that static checks can report them; use [`simplify`] to drop them.
    pub fn to_dnf(&self, symbols: &Symbols) -> Result<Dnf, ExprError> {
        let mut dnf = self.dnf_signed(symbols, true)?;
        for term in &mut dnf {
            term.sort();
            term.dedup();
        }
        dnf.sort();
        dnf.dedup();
        Ok(dnf)
    }

    fn dnf_signed(&self, symbols: &Symbols, positive: bool) -> Result<Dnf, ExprError> {
        match self {
            Expr::Const(v) => Ok(if *v == positive { vec![vec![]] } else { vec![] }),
            Expr::Not(inner) => inner.dnf_signed(symbols, !positive),
            Expr::Leaf { name, kind, span } => {
                let var = symbols.resolve(name, *kind, *span)?;
                let now = var;
                let prev = Var { prev: true, ..var };
                let lits: Vec<Vec<Literal>> = match kind {
                    LeafKind::Now | LeafKind::Prev | LeafKind::Estimate => {
                        vec![vec![Literal { var: now, positive }]]
                    }
                    LeafKind::Rise | LeafKind::Fall => {
                        let rise = *kind == LeafKind::Rise;
                        if positive {
                            // RE(x) = /x* . x ; FE(x) = x* . /x
                            vec![vec![
                                Literal { var: prev, positive: !rise },
                                Literal { var: now, positive: rise },
                            ]]
                        } else {
                            // /RE(x) = x* + /x ; /FE(x) = /x* + x
                            vec![
                                vec![Literal { var: prev, positive: rise }],
                                vec![Literal { var: now, positive: !rise }],
                            ]
                        }
                    }
                };
                Ok(lits)
            }
            Expr::And(parts) | Expr::Or(parts) => {
                let conj = matches!(self, Expr::And(_)) == positive;
                let mut acc: Dnf = if conj { vec![vec![]] } else { vec![] };
                for part in parts {
                    let d = part.dnf_signed(symbols, positive)?;
                    if conj {
                        let mut next = Vec::with_capacity(acc.len() * d.len());
                        for a in &acc {
                            for b in &d {
                                let mut t = a.clone();
                                t.extend_from_slice(b);
                                next.push(t);
                            }
                        }
                        acc = next;
                    } else {
                        acc.extend(d);
                    }
                    if acc.len() > MAX_TERMS {
                        return Err(ExprError {
                            message: format!(
                                "expression expands to more than {MAX_TERMS} product terms"
                            ),
                            span: self.first_span().unwrap_or(Span { line: 1, column: 1 }),
                        });
                    }
                }
                Ok(acc)
            }
        }
    }

    /// Position of the first leaf, if any.
    pub fn first_span(&self) -> Option<Span> {
        match self {
            Expr::Const(_) => None,
            Expr::Leaf { span, .. } => Some(*span),
            Expr::Not(e) => e.first_span(),
            Expr::And(v) | Expr::Or(v) => v.iter().find_map(Expr::first_span),
        }
    }

    /// Every leaf, in source order.
    pub fn leaves(&self) -> Vec<(&str, LeafKind, Span)> {
        let mut out = Vec::new();
        self.collect_leaves(&mut out);
        out
    }

    fn collect_leaves<'a>(&'a self, out: &mut Vec<(&'a str, LeafKind, Span)>) {
        match self {
            Expr::Const(_) => {}
            Expr::Leaf { name, kind, span } => out.push((name, *kind, *span)),
            Expr::Not(e) => e.collect_leaves(out),
            Expr::And(v) | Expr::Or(v) => v.iter().for_each(|e| e.collect_leaves(out)),
        }
    }
}

/// True when a product term holds both `x` and `/x` for some variable.
pub fn is_contradictory(term: &[Literal]) -> bool {
    // Terms are sorted by variable then polarity, so a contradiction is adjacent.
    term.windows(2)
        .any(|w| w[0].var == w[1].var && w[0].positive != w[1].positive)
}

/// Drops contradictory terms and terms absorbed by a shorter one.
pub fn simplify(dnf: &Dnf) -> Dnf {
    let mut terms: Dnf = dnf.iter().filter(|t| !is_contradictory(t)).cloned().collect();
    terms.sort_by_key(Vec::len);
    let mut kept: Dnf = Vec::new();
    for t in terms {
        if !kept.iter().any(|k| k.iter().all(|l| t.contains(l))) {
            kept.push(t);
        }
    }
    kept.sort();
    kept
}

/// Evaluates a sum of products.
#[inline]
pub fn eval_dnf(dnf: &[Vec<Literal>], frame: &crate::frame::Frame) -> bool {
    dnf.iter()
        .any(|term| term.iter().all(|l| frame.literal(*l)))
}

/// Renders a sum of products in the file notation (`/x`, `x*`, ` . `, ` + `).
pub fn render_dnf(dnf: &[Vec<Literal>], symbols: &Symbols) -> String {
    if dnf.is_empty() {
        return "0".into();
    }
    dnf.iter()
        .map(|t| {
            if t.is_empty() {
                "1".to_string()
            } else {
                t.iter()
                    .map(|l| symbols.render_literal(*l))
                    .collect::<Vec<_>>()
                    .join(" . ")
            }
        })
        .collect::<Vec<_>>()
        .join(" + ")
}

#[cfg(test)]
mod tests;
