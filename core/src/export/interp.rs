//! An interpreter for the Structured Text subset that [`super::st`] generates, so that
//! the generated code's semantics can be replayed against the native engine.
//!
//! Subset: `FUNCTION_BLOCK` and `PROGRAM` with `VAR_INPUT`, `VAR_OUTPUT` and `VAR`
//! sections (`name : BOOL | INT | DINT | LINT | <function block>;`), statements `:=`,
//! `IF … THEN … ELSIF … ELSE … END_IF;` and function-block calls with named inputs
//! (`inst(a := e, …);`), expressions with `OR`, `XOR`, `AND`, `NOT`, comparisons, `+`,
//! `-`, `*`, integer and Boolean literals, variables and `inst.member`, and `(* *)`
//! comments. Anything else is a parse error, never a panic.

use std::collections::BTreeMap;

/// A value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Val {
    /// `BOOL`.
    Bool(bool),
    /// Any integer type.
    Int(i64),
}

/// A parse or run-time error.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct StError(pub String);

fn err<T>(m: impl Into<String>) -> Result<T, StError> {
    Err(StError(m.into()))
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Tok {
    Id(String),
    Int(i64),
    Assign,
    Semi,
    Colon,
    Comma,
    Dot,
    Open,
    Close,
    Op(&'static str),
}

fn lex(src: &str) -> Result<Vec<Tok>, StError> {
    let c: Vec<char> = src.chars().collect();
    let mut i = 0;
    let mut out = Vec::new();
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch == '(' && c.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < c.len() && !(c[i] == '*' && c[i + 1] == ')') {
                i += 1;
            }
            i += 2;
        } else if ch.is_ascii_alphabetic() || ch == '_' {
            let s = i;
            while i < c.len() && (c[i].is_ascii_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Tok::Id(
                c[s..i].iter().collect::<String>().to_ascii_uppercase(),
            ));
        } else if ch.is_ascii_digit() {
            let s = i;
            while i < c.len() && c[i].is_ascii_digit() {
                i += 1;
            }
            let text: String = c[s..i].iter().collect();
            out.push(Tok::Int(
                text.parse()
                    .map_err(|_| StError(format!("bad integer {text}")))?,
            ));
        } else {
            let two: String = c[i..(i + 2).min(c.len())].iter().collect();
            let (t, n) = match two.as_str() {
                ":=" => (Tok::Assign, 2),
                "<=" => (Tok::Op("<="), 2),
                ">=" => (Tok::Op(">="), 2),
                "<>" => (Tok::Op("<>"), 2),
                _ => match ch {
                    ';' => (Tok::Semi, 1),
                    ':' => (Tok::Colon, 1),
                    ',' => (Tok::Comma, 1),
                    '.' => (Tok::Dot, 1),
                    '(' => (Tok::Open, 1),
                    ')' => (Tok::Close, 1),
                    '<' => (Tok::Op("<"), 1),
                    '>' => (Tok::Op(">"), 1),
                    '=' => (Tok::Op("="), 1),
                    '+' => (Tok::Op("+"), 1),
                    '-' => (Tok::Op("-"), 1),
                    '*' => (Tok::Op("*"), 1),
                    _ => return err(format!("unexpected character `{ch}`")),
                },
            };
            out.push(t);
            i += n;
        }
    }
    Ok(out)
}

#[derive(Clone, Debug)]
enum Expr {
    Lit(Val),
    Var(String),
    Member(String, String),
    Not(Box<Expr>),
    Neg(Box<Expr>),
    Bin(&'static str, Box<Expr>, Box<Expr>),
}

#[derive(Clone, Debug)]
enum Stmt {
    Assign(String, Expr),
    If(Vec<(Expr, Vec<Stmt>)>, Vec<Stmt>),
    Call(String, Vec<(String, Expr)>),
}

#[derive(Clone, Debug)]
struct Pou {
    /// (name, type) of every variable, in declaration order.
    vars: Vec<(String, String)>,
    body: Vec<Stmt>,
}

/// A parsed program: its function blocks and programs.
#[derive(Clone, Debug)]
pub struct Unit {
    pous: BTreeMap<String, Pou>,
}

struct P {
    t: Vec<Tok>,
    i: usize,
}

impl P {
    fn peek(&self) -> Option<&Tok> {
        self.t.get(self.i)
    }
    fn next(&mut self) -> Result<Tok, StError> {
        let t = self
            .t
            .get(self.i)
            .cloned()
            .ok_or_else(|| StError("unexpected end".into()))?;
        self.i += 1;
        Ok(t)
    }
    fn is_kw(&self, k: &str) -> bool {
        matches!(self.peek(), Some(Tok::Id(s)) if s == k)
    }
    fn kw(&mut self, k: &str) -> Result<(), StError> {
        match self.next()? {
            Tok::Id(s) if s == k => Ok(()),
            t => err(format!("expected {k}, found {t:?}")),
        }
    }
    fn tok(&mut self, want: &Tok) -> Result<(), StError> {
        let t = self.next()?;
        if &t == want {
            Ok(())
        } else {
            err(format!("expected {want:?}, found {t:?}"))
        }
    }
    fn id(&mut self) -> Result<String, StError> {
        match self.next()? {
            Tok::Id(s) => Ok(s),
            t => err(format!("expected a name, found {t:?}")),
        }
    }

    fn unit(&mut self) -> Result<Unit, StError> {
        let mut pous = BTreeMap::new();
        while self.peek().is_some() {
            let end = if self.is_kw("FUNCTION_BLOCK") {
                "END_FUNCTION_BLOCK"
            } else if self.is_kw("PROGRAM") {
                "END_PROGRAM"
            } else {
                return err(format!(
                    "expected FUNCTION_BLOCK or PROGRAM, found {:?}",
                    self.peek()
                ));
            };
            self.next()?;
            let name = self.id()?;
            let mut vars = Vec::new();
            while self.is_kw("VAR_INPUT") || self.is_kw("VAR_OUTPUT") || self.is_kw("VAR") {
                self.next()?;
                while !self.is_kw("END_VAR") {
                    let n = self.id()?;
                    self.tok(&Tok::Colon)?;
                    let ty = self.id()?;
                    self.tok(&Tok::Semi)?;
                    vars.push((n, ty));
                }
                self.kw("END_VAR")?;
            }
            let body = self.stmts(&[end])?;
            self.kw(end)?;
            pous.insert(name, Pou { vars, body });
        }
        Ok(Unit { pous })
    }

    fn stmts(&mut self, stops: &[&str]) -> Result<Vec<Stmt>, StError> {
        let mut out = Vec::new();
        while !stops.iter().any(|s| self.is_kw(s)) {
            if self.peek().is_none() {
                return err("unexpected end of text");
            }
            out.push(self.stmt()?);
        }
        Ok(out)
    }

    fn stmt(&mut self) -> Result<Stmt, StError> {
        if self.is_kw("IF") {
            self.next()?;
            let mut arms = Vec::new();
            let c = self.expr()?;
            self.kw("THEN")?;
            let b = self.stmts(&["ELSIF", "ELSE", "END_IF"])?;
            arms.push((c, b));
            let mut other = Vec::new();
            loop {
                if self.is_kw("ELSIF") {
                    self.next()?;
                    let c = self.expr()?;
                    self.kw("THEN")?;
                    let b = self.stmts(&["ELSIF", "ELSE", "END_IF"])?;
                    arms.push((c, b));
                } else if self.is_kw("ELSE") {
                    self.next()?;
                    other = self.stmts(&["END_IF"])?;
                } else {
                    break;
                }
            }
            self.kw("END_IF")?;
            self.tok(&Tok::Semi)?;
            return Ok(Stmt::If(arms, other));
        }
        let name = self.id()?;
        match self.next()? {
            Tok::Assign => {
                let e = self.expr()?;
                self.tok(&Tok::Semi)?;
                Ok(Stmt::Assign(name, e))
            }
            Tok::Open => {
                let mut args = Vec::new();
                if self.peek() != Some(&Tok::Close) {
                    loop {
                        let n = self.id()?;
                        self.tok(&Tok::Assign)?;
                        args.push((n, self.expr()?));
                        if self.peek() == Some(&Tok::Comma) {
                            self.next()?;
                        } else {
                            break;
                        }
                    }
                }
                self.tok(&Tok::Close)?;
                self.tok(&Tok::Semi)?;
                Ok(Stmt::Call(name, args))
            }
            t => err(format!("expected `:=` or `(` after {name}, found {t:?}")),
        }
    }

    fn expr(&mut self) -> Result<Expr, StError> {
        let mut l = self.xor()?;
        while self.is_kw("OR") {
            self.next()?;
            l = Expr::Bin("OR", Box::new(l), Box::new(self.xor()?));
        }
        Ok(l)
    }
    fn xor(&mut self) -> Result<Expr, StError> {
        let mut l = self.and()?;
        while self.is_kw("XOR") {
            self.next()?;
            l = Expr::Bin("XOR", Box::new(l), Box::new(self.and()?));
        }
        Ok(l)
    }
    fn and(&mut self) -> Result<Expr, StError> {
        let mut l = self.cmp()?;
        while self.is_kw("AND") {
            self.next()?;
            l = Expr::Bin("AND", Box::new(l), Box::new(self.cmp()?));
        }
        Ok(l)
    }
    fn cmp(&mut self) -> Result<Expr, StError> {
        let mut l = self.add()?;
        while let Some(Tok::Op(op)) = self.peek() {
            let op = *op;
            if !matches!(op, "<" | ">" | "<=" | ">=" | "=" | "<>") {
                break;
            }
            self.next()?;
            l = Expr::Bin(op, Box::new(l), Box::new(self.add()?));
        }
        Ok(l)
    }
    fn add(&mut self) -> Result<Expr, StError> {
        let mut l = self.mul()?;
        while let Some(Tok::Op(op @ ("+" | "-"))) = self.peek() {
            let op = *op;
            self.next()?;
            l = Expr::Bin(op, Box::new(l), Box::new(self.mul()?));
        }
        Ok(l)
    }
    fn mul(&mut self) -> Result<Expr, StError> {
        let mut l = self.unary()?;
        while let Some(Tok::Op("*")) = self.peek() {
            self.next()?;
            l = Expr::Bin("*", Box::new(l), Box::new(self.unary()?));
        }
        Ok(l)
    }
    fn unary(&mut self) -> Result<Expr, StError> {
        if self.is_kw("NOT") {
            self.next()?;
            return Ok(Expr::Not(Box::new(self.unary()?)));
        }
        if self.peek() == Some(&Tok::Op("-")) {
            self.next()?;
            return Ok(Expr::Neg(Box::new(self.unary()?)));
        }
        match self.next()? {
            Tok::Int(v) => Ok(Expr::Lit(Val::Int(v))),
            Tok::Open => {
                let e = self.expr()?;
                self.tok(&Tok::Close)?;
                Ok(e)
            }
            Tok::Id(s) if s == "TRUE" => Ok(Expr::Lit(Val::Bool(true))),
            Tok::Id(s) if s == "FALSE" => Ok(Expr::Lit(Val::Bool(false))),
            Tok::Id(s) => {
                if self.peek() == Some(&Tok::Dot) {
                    self.next()?;
                    let m = self.id()?;
                    Ok(Expr::Member(s, m))
                } else {
                    Ok(Expr::Var(s))
                }
            }
            t => err(format!("unexpected {t:?} in an expression")),
        }
    }
}

/// Parses generated Structured Text.
pub fn parse(src: &str) -> Result<Unit, StError> {
    let mut p = P { t: lex(src)?, i: 0 };
    p.unit()
}

#[derive(Clone, Debug)]
struct Inst {
    pou: String,
    vars: BTreeMap<String, Val>,
    children: BTreeMap<String, Inst>,
}

/// A running program instance.
#[derive(Clone, Debug)]
pub struct Machine {
    unit: Unit,
    root: Inst,
}

fn default_of(ty: &str) -> Option<Val> {
    match ty {
        "BOOL" => Some(Val::Bool(false)),
        "INT" | "DINT" | "LINT" | "SINT" => Some(Val::Int(0)),
        _ => None,
    }
}

impl Unit {
    fn instantiate(&self, pou: &str, depth: usize) -> Result<Inst, StError> {
        let Some(p) = self.pous.get(pou) else {
            return err(format!("unknown POU {pou}"));
        };
        if depth > 8 {
            return err("function blocks nested too deeply");
        }
        let mut vars = BTreeMap::new();
        let mut children = BTreeMap::new();
        for (n, ty) in &p.vars {
            match default_of(ty) {
                Some(v) => {
                    vars.insert(n.clone(), v);
                }
                None => {
                    children.insert(n.clone(), self.instantiate(ty, depth + 1)?);
                }
            }
        }
        Ok(Inst {
            pou: pou.into(),
            vars,
            children,
        })
    }
}

impl Machine {
    /// An instance of the program `name`, every variable at its default.
    pub fn new(unit: Unit, name: &str) -> Result<Self, StError> {
        let root = unit.instantiate(&name.to_ascii_uppercase(), 0)?;
        Ok(Self { unit, root })
    }

    /// Sets a variable of the program.
    pub fn set(&mut self, name: &str, v: Val) -> Result<(), StError> {
        match self.root.vars.get_mut(&name.to_ascii_uppercase()) {
            Some(slot) => {
                *slot = v;
                Ok(())
            }
            None => err(format!("no variable {name}")),
        }
    }

    /// Reads a variable of the program, or `inst.var` of one of its instances.
    pub fn get(&self, name: &str) -> Result<Val, StError> {
        let name = name.to_ascii_uppercase();
        if let Some((i, m)) = name.split_once('.') {
            return self
                .root
                .children
                .get(i)
                .and_then(|c| c.vars.get(m))
                .copied()
                .ok_or_else(|| StError(format!("no variable {name}")));
        }
        self.root
            .vars
            .get(&name)
            .copied()
            .ok_or_else(|| StError(format!("no variable {name}")))
    }

    /// Sets `inst.var` of an instance (tests force internal state this way).
    pub fn set_member(&mut self, inst: &str, var: &str, v: Val) -> Result<(), StError> {
        match self
            .root
            .children
            .get_mut(&inst.to_ascii_uppercase())
            .and_then(|c| c.vars.get_mut(&var.to_ascii_uppercase()))
        {
            Some(slot) => {
                *slot = v;
                Ok(())
            }
            None => err(format!("no variable {inst}.{var}")),
        }
    }

    /// Runs one scan of the program body.
    pub fn scan(&mut self) -> Result<(), StError> {
        let Some(pou) = self.unit.pous.get(&self.root.pou) else {
            return err(format!("unknown POU {}", self.root.pou));
        };
        exec(&self.unit, &mut self.root, &pou.body)
    }
}

fn exec(unit: &Unit, inst: &mut Inst, body: &[Stmt]) -> Result<(), StError> {
    for s in body {
        match s {
            Stmt::Assign(n, e) => {
                let v = eval(inst, e)?;
                match inst.vars.get_mut(n) {
                    Some(slot) => *slot = v,
                    None => return err(format!("assignment to unknown {n}")),
                }
            }
            Stmt::If(arms, other) => {
                let mut done = false;
                for (c, b) in arms {
                    if as_bool(eval(inst, c)?)? {
                        exec(unit, inst, b)?;
                        done = true;
                        break;
                    }
                }
                if !done {
                    exec(unit, inst, other)?;
                }
            }
            Stmt::Call(name, args) => {
                let vals: Vec<(String, Val)> = args
                    .iter()
                    .map(|(n, e)| eval(inst, e).map(|v| (n.clone(), v)))
                    .collect::<Result<_, _>>()?;
                let Some(mut child) = inst.children.remove(name) else {
                    return err(format!("call of unknown instance {name}"));
                };
                let result = (|| {
                    for (n, v) in vals {
                        match child.vars.get_mut(&n) {
                            Some(slot) => *slot = v,
                            None => return err(format!("{name} has no input {n}")),
                        }
                    }
                    match unit.pous.get(&child.pou) {
                        Some(p) => exec(unit, &mut child, &p.body),
                        None => err(format!("unknown POU {}", child.pou)),
                    }
                })();
                inst.children.insert(name.clone(), child);
                result?;
            }
        }
    }
    Ok(())
}

fn as_bool(v: Val) -> Result<bool, StError> {
    match v {
        Val::Bool(b) => Ok(b),
        Val::Int(_) => err("integer where a BOOL is needed"),
    }
}

fn as_int(v: Val) -> Result<i64, StError> {
    match v {
        Val::Int(i) => Ok(i),
        Val::Bool(_) => err("BOOL where an integer is needed"),
    }
}

fn eval(inst: &Inst, e: &Expr) -> Result<Val, StError> {
    Ok(match e {
        Expr::Lit(v) => *v,
        Expr::Var(n) => *inst
            .vars
            .get(n)
            .ok_or_else(|| StError(format!("unknown variable {n}")))?,
        Expr::Member(i, m) => *inst
            .children
            .get(i)
            .and_then(|c| c.vars.get(m))
            .ok_or_else(|| StError(format!("unknown {i}.{m}")))?,
        Expr::Not(x) => Val::Bool(!as_bool(eval(inst, x)?)?),
        Expr::Neg(x) => Val::Int(as_int(eval(inst, x)?)?.wrapping_neg()),
        Expr::Bin(op, a, b) => {
            let (a, b) = (eval(inst, a)?, eval(inst, b)?);
            match *op {
                "OR" => Val::Bool(as_bool(a)? || as_bool(b)?),
                "XOR" => Val::Bool(as_bool(a)? ^ as_bool(b)?),
                "AND" => Val::Bool(as_bool(a)? && as_bool(b)?),
                "=" => Val::Bool(a == b),
                "<>" => Val::Bool(a != b),
                "<" => Val::Bool(as_int(a)? < as_int(b)?),
                ">" => Val::Bool(as_int(a)? > as_int(b)?),
                "<=" => Val::Bool(as_int(a)? <= as_int(b)?),
                ">=" => Val::Bool(as_int(a)? >= as_int(b)?),
                "+" => Val::Int(as_int(a)?.wrapping_add(as_int(b)?)),
                "-" => Val::Int(as_int(a)?.wrapping_sub(as_int(b)?)),
                "*" => Val::Int(as_int(a)?.wrapping_mul(as_int(b)?)),
                _ => return err(format!("unknown operator {op}")),
            }
        }
    })
}
