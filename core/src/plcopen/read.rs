//! PLCopen XML → [`Program`]: the project's structure, the variables and their binding
//! to the plant, and the symbolic execution of the bodies (see the module docs).

use super::st::{self, BinOp, Pos, StExpr, Stmt};
use super::{ADD_DATA, ld, sfc};
use crate::control::{
    Action, Chart, Counter, CounterKind, Delay, DelayKind, Program, Qualifier, SourcePlace, Step,
    Transition,
};
use crate::diag::codes::{self, Code};
use crate::diag::{Location, Problem};
use crate::expr::{Expr, LeafKind, Span};
use crate::plant::{Address, Plant};
use roxmltree::{Document, Node};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// What a declared name is, for Vigie.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Input,
    Output,
    Panel,
    Memory,
    Trig {
        rising: bool,
    },
    /// A `TON`, `TOF` or `TP` instance.
    Timer(DelayKind),
    /// A `CTU` or `CTD` instance.
    Counter(CounterKind),
    /// An `INT` variable with a constant initial value, never written: its value.
    Integer(i64),
    /// A `TIME` variable with a constant initial value, never written: its ms.
    Duration(u64),
    /// A declared variable of a type Vigie does not run: an error where it is used.
    Unsupported(String),
}

#[derive(Clone, Debug)]
pub(super) struct VarDecl {
    /// The name in the Vigie program (the plant's id for a bound signal).
    pub(super) name: String,
    pub(super) kind: Kind,
}

/// The reading context: the file, its document and the problems found.
pub(super) struct Ctx<'a, 'input> {
    pub(super) file: &'a Path,
    pub(super) doc: &'a Document<'input>,
    pub(super) problems: Vec<Problem>,
}

impl Ctx<'_, '_> {
    pub(super) fn at(&self, node: Node<'_, '_>) -> Location {
        let p = self.doc.text_pos_at(node.range().start);
        Location::new(self.file, p.row as usize, p.col as usize)
    }

    pub(super) fn error(&mut self, code: Code, node: Node<'_, '_>, message: impl Into<String>) {
        let at = self.at(node);
        self.problems
            .push(Problem::error(code.id, message, Some(at)));
    }

    pub(super) fn error_at(&mut self, code: Code, at: Location, message: impl Into<String>) {
        self.problems
            .push(Problem::error(code.id, message, Some(at)));
    }
}

/// ST text found in the file, with the file position of its first character.
#[derive(Clone, Debug)]
pub(super) struct StText {
    pub(super) text: String,
    pub(super) line: usize,
    pub(super) column: usize,
}

impl StText {
    /// The file location of a position in the text.
    pub(super) fn locate(&self, file: &Path, pos: Pos) -> Location {
        if pos.line <= 1 {
            Location::new(file, self.line, self.column + pos.column.saturating_sub(1))
        } else {
            Location::new(file, self.line + pos.line - 1, pos.column)
        }
    }
}

/// The child elements of `node` with this local name.
pub(super) fn children<'a, 'i>(
    node: Node<'a, 'i>,
    name: &'a str,
) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == name)
}

/// The first child element with this local name.
pub(super) fn child<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == name)
}

/// The text of an `<ST>` (or any) element: its descendant text, with the file position
/// of the first text node (inside a CDATA section when there is one).
pub(super) fn st_text(ctx: &Ctx<'_, '_>, node: Node<'_, '_>) -> StText {
    let mut text = String::new();
    let mut first = None;
    for d in node.descendants().filter(Node::is_text) {
        let t = d.text().unwrap_or("");
        if first.is_none() {
            // The layout between the element and its text (`<ST>` then `<xhtml:p>` on
            // the next line) is not the text: its lines would shift every position.
            if t.trim().is_empty() {
                continue;
            }
            let r = d.range();
            let src = ctx.doc.input_text().get(r.clone()).unwrap_or("");
            let skip = if src.starts_with("<![CDATA[") { 9 } else { 0 };
            first = Some(r.start + skip);
        }
        text.push_str(t);
    }
    let (line, column) = match first {
        Some(off) => {
            let p = ctx.doc.text_pos_at(off);
            (p.row as usize, p.col as usize)
        }
        None => {
            let p = ctx.doc.text_pos_at(node.range().start);
            (p.row as usize, p.col as usize)
        }
    };
    StText { text, line, column }
}

/// The program POUs of the project in the order the PLC runs them.
fn program_pous<'a, 'i>(ctx: &mut Ctx<'a, 'i>, project: Node<'a, 'i>) -> Vec<Node<'a, 'i>> {
    let pous: Vec<Node<'a, 'i>> = child(project, "types")
        .and_then(|t| child(t, "pous"))
        .map(|p| children(p, "pou").collect())
        .unwrap_or_default();
    let programs: Vec<Node<'a, 'i>> = pous
        .iter()
        .copied()
        .filter(|p| p.attribute("pouType") == Some("program"))
        .collect();
    // Task order: every pouInstance of every resource, tasks by priority (IEC: a lower
    // number runs first), then the resource's own instances.
    let mut called: Vec<(i64, Node<'a, 'i>, String)> = Vec::new();
    for res in project
        .descendants()
        .filter(|n| n.is_element() && n.tag_name().name() == "resource")
    {
        for task in children(res, "task") {
            let prio = task
                .attribute("priority")
                .and_then(|p| p.parse::<i64>().ok())
                .unwrap_or(0);
            for inst in children(task, "pouInstance") {
                called.push((prio, inst, inst.attribute("typeName").unwrap_or("").into()));
            }
        }
        for inst in children(res, "pouInstance") {
            called.push((
                i64::MAX,
                inst,
                inst.attribute("typeName").unwrap_or("").into(),
            ));
        }
    }
    if called.is_empty() {
        return programs;
    }
    called.sort_by_key(|c| c.0);
    let mut out = Vec::new();
    for (_, inst, ty) in called {
        match programs
            .iter()
            .find(|p| p.attribute("name") == Some(ty.as_str()))
        {
            Some(p) if out.contains(p) => ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                inst,
                format!(
                    "the program `{ty}` is instantiated twice: one instance per program is run"
                ),
            ),
            Some(p) => out.push(*p),
            None => ctx.error(
                codes::PLCOPEN_UNKNOWN_NAME,
                inst,
                format!("the task calls `{ty}`, which is not a POU of type program in this file"),
            ),
        }
    }
    out
}

/// `%IX1.2` → ('I', 10); `%QX0.0` → ('Q', 0); `%MX3` → ('M', 3).
fn parse_address(a: &str) -> Option<(char, u16)> {
    let rest = a.strip_prefix('%')?;
    let mut chars = rest.chars();
    let area = chars.next()?.to_ascii_uppercase();
    let rest = chars.as_str();
    let rest = rest
        .strip_prefix('X')
        .or_else(|| rest.strip_prefix('x'))
        .unwrap_or(rest);
    if !rest.chars().next()?.is_ascii_digit() {
        return None;
    }
    let bit = match rest.split_once('.') {
        Some((byte, bit)) => {
            let byte: u16 = byte.parse().ok()?;
            let bit: u16 = bit.parse().ok()?;
            if bit > 7 {
                return None;
            }
            byte.checked_mul(8)?.checked_add(bit)?
        }
        None => rest.parse().ok()?,
    };
    matches!(area, 'I' | 'Q' | 'M').then_some((area, bit))
}

/// The variable sections of an interface, with their kind of section.
const SECTIONS: &[(&str, bool)] = &[
    ("inputVars", true),
    ("outputVars", false),
    ("inOutVars", false),
    ("localVars", false),
    ("tempVars", false),
    ("externalVars", false),
    ("globalVars", false),
    ("accessVars", false),
];

pub(super) struct Declarations {
    /// By lower-case IEC name.
    pub(super) vars: BTreeMap<String, VarDecl>,
    /// Panel inputs and memories, in declaration order (Vigie names).
    pub(super) panel: Vec<String>,
    pub(super) memories: Vec<String>,
    /// Outputs and memories whose initial value is TRUE.
    pub(super) initial: Vec<String>,
}

impl Declarations {
    fn declare(&mut self, ctx: &mut Ctx<'_, '_>, node: Node<'_, '_>, iec: &str, decl: VarDecl) {
        let key = iec.to_ascii_lowercase();
        if let Some(old) = self.vars.get(&key) {
            if old.name != decl.name || old.kind != decl.kind {
                ctx.error(
                    codes::PLCOPEN_BINDING,
                    node,
                    format!(
                        "`{iec}` is declared twice with two bindings ({} and {})",
                        describe(old),
                        describe(&decl)
                    ),
                );
            }
            return;
        }
        match decl.kind {
            Kind::Panel if !self.panel.contains(&decl.name) => self.panel.push(decl.name.clone()),
            Kind::Memory if !self.memories.contains(&decl.name) => {
                self.memories.push(decl.name.clone());
            }
            _ => {}
        }
        self.vars.insert(key, decl);
    }
}

fn describe(d: &VarDecl) -> String {
    match &d.kind {
        Kind::Input => format!("plant input {}", d.name),
        Kind::Output => format!("plant output {}", d.name),
        Kind::Panel => "operator button".into(),
        Kind::Memory => "memory".into(),
        Kind::Trig { rising: true } => "R_TRIG".into(),
        Kind::Trig { rising: false } => "F_TRIG".into(),
        Kind::Timer(DelayKind::On) => "TON".into(),
        Kind::Timer(DelayKind::Off) => "TOF".into(),
        Kind::Timer(DelayKind::Pulse) => "TP".into(),
        Kind::Duration(ms) => format!("TIME {ms} ms"),
        Kind::Counter(CounterKind::Up) => "CTU".into(),
        Kind::Counter(CounterKind::Down) => "CTD".into(),
        Kind::Integer(v) => format!("INT {v}"),
        Kind::Unsupported(t) => t.clone(),
    }
}

fn type_of(var: Node<'_, '_>) -> String {
    let Some(ty) = child(var, "type") else {
        return "?".into();
    };
    match ty.children().find(Node::is_element) {
        Some(t) if t.tag_name().name() == "derived" => t.attribute("name").unwrap_or("?").into(),
        Some(t) => t.tag_name().name().to_string(),
        None => "?".into(),
    }
}

/// Records a BOOL variable's initial value TRUE (outputs and memories only).
fn bool_initial(ctx: &mut Ctx<'_, '_>, var: Node<'_, '_>, d: &VarDecl, initial: &mut Vec<String>) {
    let Some(init) = child(var, "initialValue").and_then(|i| child(i, "simpleValue")) else {
        return;
    };
    let v = init
        .attribute("value")
        .unwrap_or("")
        .trim()
        .to_ascii_uppercase();
    match v.as_str() {
        "FALSE" | "0" | "BOOL#FALSE" | "BOOL#0" => {}
        "TRUE" | "1" | "BOOL#TRUE" | "BOOL#1" => match d.kind {
            Kind::Output | Kind::Memory => {
                if !initial.contains(&d.name) {
                    initial.push(d.name.clone());
                }
            }
            _ => ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                init,
                format!("`{}` is an input: its value comes from the plant or the operator, not from an initial value", d.name),
            ),
        },
        other => ctx.error(
            codes::PLCOPEN_UNSUPPORTED,
            init,
            format!("`{}` starts at `{other}`, which is not a BOOL value", d.name),
        ),
    }
}

/// The failure for reading `shown` (its first part `first`) as a Boolean when it is
/// not one: a timer's or a counter's other members, an INT, a TIME, a type not run.
fn not_boolean(kind: &Kind, shown: &str, first: &str, at: Pos) -> Result<Expr, Failure> {
    match kind {
        Kind::Timer(_) => fail(
            codes::PLCOPEN_UNSUPPORTED,
            at,
            format!("`{shown}`: a timer is read as `.Q` (its elapsed time `.ET` is not run)"),
        ),
        Kind::Counter(_) => fail(
            codes::PLCOPEN_UNSUPPORTED,
            at,
            format!(
                "`{shown}`: a counter is read as `.Q` (its value `.CV` is an INT, which Vigie does not run)"
            ),
        ),
        Kind::Integer(_) => fail(
            codes::PLCOPEN_UNSUPPORTED,
            at,
            format!("`{shown}` is an INT where a Boolean is expected"),
        ),
        Kind::Duration(_) => fail(
            codes::PLCOPEN_UNSUPPORTED,
            at,
            format!("`{shown}` is a TIME where a Boolean is expected"),
        ),
        Kind::Unsupported(t) => fail(
            codes::PLCOPEN_UNSUPPORTED,
            at,
            format!(
                "`{}` is of type {t}: only BOOL variables, R_TRIG and F_TRIG are run",
                first
            ),
        ),
        _ => fail(
            codes::PLCOPEN_UNSUPPORTED,
            at,
            format!("`{shown}` cannot be read"),
        ),
    }
}

/// The constant a function block's input `input` of instance `name` is given: a literal
/// (`literal`), or a variable declared constant (`declared`: an initial value, never
/// written); `what` says which constants are accepted.
fn constant_input<T>(
    (name, input, what): (&str, &str, &str),
    value: &StExpr,
    at: Pos,
    decls: &Declarations,
    literal: impl Fn(&StExpr) -> Option<T>,
    declared: impl Fn(&Kind) -> Option<T>,
) -> Result<T, Failure> {
    if let Some(v) = literal(value) {
        return Ok(v);
    }
    let (shown, at) = match value {
        StExpr::Var { path, at } if path.len() == 1 => {
            let kind = decls
                .vars
                .get(&path[0].to_ascii_lowercase())
                .map(|d| &d.kind);
            if let Some(v) = kind.and_then(&declared) {
                return Ok(v);
            }
            (format!("`{}`", path[0]), *at)
        }
        _ => ("an expression".to_string(), at),
    };
    fail(
        codes::PLCOPEN_UNSUPPORTED,
        at,
        format!("`{name}`: {input} is {shown}, not a constant ({what})"),
    )
}

/// A counter's PV: an integer literal or a constant `INT` variable, within INT's range.
fn constant_int(name: &str, value: &StExpr, at: Pos, decls: &Declarations) -> Result<i16, Failure> {
    let v = constant_input(
        (
            name,
            "PV",
            "an integer or an INT variable with an initial value, never written",
        ),
        value,
        at,
        decls,
        |e| match e {
            StExpr::Int(v) => Some(*v),
            _ => None,
        },
        |k| match k {
            Kind::Integer(v) => Some(*v),
            _ => None,
        },
    )?;
    i16::try_from(v).or_else(|_| {
        fail(
            codes::PLCOPEN_UNSUPPORTED,
            at,
            format!("`{name}`: PV {v} is outside INT (-32768..32767)"),
        )
    })
}

/// The constant initial value of an `INT` variable.
fn int_initial(var: Node<'_, '_>) -> Option<i64> {
    child(var, "initialValue")
        .and_then(|i| child(i, "simpleValue"))
        .and_then(|s| s.attribute("value"))?
        .trim()
        .parse()
        .ok()
}

/// The constant initial value of a `TIME` variable, in ms.
fn time_initial(var: Node<'_, '_>) -> Option<u64> {
    let v = child(var, "initialValue")
        .and_then(|i| child(i, "simpleValue"))
        .and_then(|s| s.attribute("value"))?;
    let (_, body) = v.split_once('#')?;
    st::parse_duration(body)
}

fn bind_bool(
    ctx: &mut Ctx<'_, '_>,
    plant: &Plant,
    var: Node<'_, '_>,
    name: &str,
    input_section: bool,
) -> Option<VarDecl> {
    if let Some(addr) = var.attribute("address") {
        let Some((area, bit)) = parse_address(addr) else {
            ctx.error(
                codes::PLCOPEN_BINDING,
                var,
                format!("variable `{name}` at {addr}: only %IX, %QX and %MX bit addresses are mapped to the plant"),
            );
            return None;
        };
        let located = |ctx: &mut Ctx<'_, '_>,
                       list: &[crate::plant::Signal],
                       at: Address,
                       kind: Kind,
                       what: &str| {
            let found = list.iter().find(|s| s.address == Some(at));
            if found.is_none() {
                ctx.error(
                    codes::PLCOPEN_BINDING,
                    var,
                    format!("variable `{name}` at {addr}: no {what} {bit}"),
                );
            }
            found.map(|s| VarDecl {
                name: s.id.clone(),
                kind,
            })
        };
        return match area {
            'I' => located(
                ctx,
                &plant.inputs,
                Address::DiscreteInput(bit),
                Kind::Input,
                "sensor of the plant at discrete input",
            ),
            'Q' => located(
                ctx,
                &plant.outputs,
                Address::Coil(bit),
                Kind::Output,
                "actuator of the plant at coil",
            ),
            _ => Some(VarDecl {
                name: name.to_string(),
                kind: Kind::Memory,
            }),
        };
    }
    let find = |list: &[crate::plant::Signal]| {
        list.iter()
            .find(|s| s.id.eq_ignore_ascii_case(name))
            .map(|s| s.id.clone())
    };
    if let Some(id) = find(&plant.inputs) {
        return Some(VarDecl {
            name: id,
            kind: Kind::Input,
        });
    }
    if let Some(id) = find(&plant.outputs) {
        return Some(VarDecl {
            name: id,
            kind: Kind::Output,
        });
    }
    Some(VarDecl {
        name: name.to_string(),
        kind: if input_section {
            Kind::Panel
        } else {
            Kind::Memory
        },
    })
}

fn declare_interface(
    ctx: &mut Ctx<'_, '_>,
    plant: &Plant,
    scope: Node<'_, '_>,
    decls: &mut Declarations,
) {
    for (section, is_input) in SECTIONS {
        for sec in children(scope, section) {
            for var in children(sec, "variable") {
                let name = var.attribute("name").unwrap_or("");
                let ty = type_of(var);
                let decl = match ty.to_ascii_uppercase().as_str() {
                    "BOOL" => bind_bool(ctx, plant, var, name, *is_input).inspect(|d| {
                        bool_initial(ctx, var, d, &mut decls.initial);
                    }),
                    "R_TRIG" | "F_TRIG" => Some(VarDecl {
                        name: name.to_string(),
                        kind: Kind::Trig {
                            rising: ty.eq_ignore_ascii_case("R_TRIG"),
                        },
                    }),
                    "TON" | "TOF" | "TP" => Some(VarDecl {
                        name: name.to_string(),
                        kind: Kind::Timer(match ty.to_ascii_uppercase().as_str() {
                            "TON" => DelayKind::On,
                            "TOF" => DelayKind::Off,
                            _ => DelayKind::Pulse,
                        }),
                    }),
                    "CTU" | "CTD" => Some(VarDecl {
                        name: name.to_string(),
                        kind: Kind::Counter(if ty.eq_ignore_ascii_case("CTU") {
                            CounterKind::Up
                        } else {
                            CounterKind::Down
                        }),
                    }),
                    "INT" => Some(VarDecl {
                        name: name.to_string(),
                        kind: int_initial(var)
                            .map_or_else(|| Kind::Unsupported("INT".into()), Kind::Integer),
                    }),
                    "TIME" => Some(VarDecl {
                        name: name.to_string(),
                        kind: time_initial(var)
                            .map_or_else(|| Kind::Unsupported("TIME".into()), Kind::Duration),
                    }),
                    _ => Some(VarDecl {
                        name: name.to_string(),
                        kind: Kind::Unsupported(ty.clone()),
                    }),
                };
                if let Some(d) = decl {
                    decls.declare(ctx, var, name, d);
                }
            }
        }
    }
}

/// The symbolic state of one scan, in task order (see the module docs).
pub(super) struct Machine {
    /// The value of each variable written so far in the scan.
    env: BTreeMap<String, Expr>,
    /// Variables in the order of their first write.
    order: Vec<String>,
    /// Variables written by ST or LD anywhere in the program, with their number of
    /// assignment statements.
    written: BTreeMap<String, usize>,
    /// Targets of SFC actions, and those whose chart has already run in this scan.
    pub(super) action_targets: BTreeSet<String>,
    pub(super) charts_done: BTreeSet<String>,
    /// `R_TRIG`/`F_TRIG` outputs after their call.
    trig: BTreeMap<String, Expr>,
    /// `TON`/`TOF`/`TP` instances called, in call order, and their input IN.
    pub(super) delays: Vec<Delay>,
    /// `CTU`/`CTD` instances called, in call order (their count input in `timer_in`).
    pub(super) counters: Vec<Counter>,
    timer_in: BTreeMap<String, Expr>,
    /// Step timers created by `S.T` comparisons: (name, step, ms).
    pub(super) timers: Vec<(String, String, u64)>,
    /// Steps of the POU whose conditions are being read.
    pub(super) visible_steps: BTreeSet<String>,
    /// When each variable was last written (equations follow that order).
    last: BTreeMap<String, usize>,
    writes: usize,
    /// Intermediate values held in memories of their own, so that an expression read
    /// after many writes stays small: name → value.
    pub(super) hidden: BTreeMap<String, Expr>,
    hidden_order: Vec<String>,
    /// Names taken by the program (variables, steps), for the hidden memories.
    taken: BTreeSet<String>,
    /// The POU and the language of the body being run, for the places of its writes.
    pub(super) body: (String, &'static str),
    /// The file's name, for the places.
    pub(super) file: String,
    /// Where each step, transition and written variable is in the file.
    pub(super) places: BTreeMap<String, Vec<SourcePlace>>,
}

/// Values that expand to more product terms than this (or whose negation does) are held
/// in a memory of their own.
const HIDDEN_ABOVE: usize = 64;
/// A value read again, or used twice by an operator, is held in a memory above this.
const HIDDEN_READ_ABOVE: usize = 16;

/// The number of product terms of `e` and of its negation once expanded to a sum of
/// products (an upper bound, before simplification), saturating.
fn terms(e: &Expr) -> (usize, usize) {
    match e {
        Expr::Const(_) | Expr::Leaf { .. } => (1, 1),
        Expr::Not(x) => {
            let (p, n) = terms(x);
            (n, p)
        }
        Expr::And(xs) => xs.iter().map(terms).fold((1, 0), |(p, n), (xp, xn)| {
            (p.saturating_mul(xp), n.saturating_add(xn))
        }),
        Expr::Or(xs) => xs.iter().map(terms).fold((0, 1), |(p, n), (xp, xn)| {
            (p.saturating_add(xp), n.saturating_mul(xn))
        }),
    }
}

/// The larger expansion of `e` or of its negation.
fn size(e: &Expr) -> usize {
    let (p, n) = terms(e);
    p.max(n)
}

/// Where an expression is evaluated.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Mode {
    /// An SFC transition condition, before the evolution.
    Condition,
    /// An ST or LD body.
    Body,
}

pub(super) fn leaf(name: &str, kind: LeafKind, span: Span) -> Expr {
    Expr::Leaf {
        name: name.to_string(),
        kind,
        span,
    }
}

pub(super) fn not(e: Expr) -> Expr {
    match e {
        Expr::Const(b) => Expr::Const(!b),
        Expr::Not(inner) => *inner,
        e => Expr::Not(Box::new(e)),
    }
}

/// `a . b` (`conj`) or `a + b`, constants folded and nested lists flattened.
fn combine(a: Expr, b: Expr, conj: bool) -> Expr {
    let (absorbing, neutral) = (Expr::Const(!conj), Expr::Const(conj));
    if a == absorbing || b == absorbing {
        return absorbing;
    }
    if a == neutral {
        return b;
    }
    if b == neutral {
        return a;
    }
    let parts = |e: Expr| match e {
        Expr::And(v) if conj => v,
        Expr::Or(v) if !conj => v,
        e => vec![e],
    };
    let mut v = parts(a);
    v.extend(parts(b));
    if conj { Expr::And(v) } else { Expr::Or(v) }
}

pub(super) fn and(a: Expr, b: Expr) -> Expr {
    combine(a, b, true)
}

pub(super) fn or(a: Expr, b: Expr) -> Expr {
    combine(a, b, false)
}

fn xor(a: Expr, b: Expr) -> Expr {
    or(and(a.clone(), not(b.clone())), and(not(a), b))
}

/// An expression failed: the message and where, for the caller to place.
pub(super) struct Failure {
    pub(super) code: Code,
    pub(super) message: String,
    pub(super) at: Pos,
}

fn fail<T>(code: Code, at: Pos, message: impl Into<String>) -> Result<T, Failure> {
    Err(Failure {
        code,
        message: message.into(),
        at,
    })
}

impl Machine {
    pub(super) fn new(
        written: BTreeMap<String, usize>,
        action_targets: BTreeSet<String>,
        taken: BTreeSet<String>,
    ) -> Self {
        Self {
            last: BTreeMap::new(),
            writes: 0,
            hidden: BTreeMap::new(),
            hidden_order: Vec::new(),
            taken,
            env: BTreeMap::new(),
            order: Vec::new(),
            written,
            action_targets,
            charts_done: BTreeSet::new(),
            trig: BTreeMap::new(),
            delays: Vec::new(),
            counters: Vec::new(),
            timer_in: BTreeMap::new(),
            timers: Vec::new(),
            visible_steps: BTreeSet::new(),
            body: (String::new(), "ST"),
            file: String::new(),
            places: BTreeMap::new(),
        }
    }

    /// Records that `name` is at `line`:`column` of the POU being read, as a `kind`.
    pub(super) fn place(&mut self, name: &str, kind: &str, line: usize, column: usize) {
        let place = SourcePlace {
            file: self.file.clone(),
            pou: self.body.0.clone(),
            kind: kind.to_string(),
            line,
            column,
        };
        let places = self.places.entry(name.to_string()).or_default();
        if !places.contains(&place) {
            places.push(place);
        }
    }

    /// The value of a variable at this point of the scan.
    fn read(&mut self, d: &VarDecl, mode: Mode, span: Span) -> Expr {
        if let Some(e) = self.env.get(&d.name) {
            // Before the evolution, a hidden memory still holds the last scan's value:
            // a condition reads the value itself.
            if mode == Mode::Condition {
                return self.expand(e);
            }
            if self.action_targets.contains(&d.name) {
                return e.clone();
            }
            // Written once: its equation, before this one, holds the value.
            if self.written.get(&d.name) == Some(&1) {
                return leaf(&d.name, LeafKind::Now, span);
            }
            if size(e) > HIDDEN_READ_ABOVE {
                let e = e.clone();
                let h = self.hide(e);
                self.writes += 1;
                self.last.insert(d.name.clone(), self.writes);
                let l = leaf(&h, LeafKind::Now, span);
                self.env.insert(d.name.clone(), l.clone());
                return l;
            }
            return e.clone();
        }
        let kind = match (&d.kind, mode) {
            (_, Mode::Condition) | (Kind::Input | Kind::Panel, _) => LeafKind::Now,
            _ if self.action_targets.contains(&d.name) => {
                if self.charts_done.contains(&d.name) {
                    LeafKind::Now
                } else {
                    LeafKind::Prev
                }
            }
            _ if self.written.contains_key(&d.name) => LeafKind::Prev,
            _ => LeafKind::Now,
        };
        leaf(&d.name, kind, span)
    }

    fn expand(&self, e: &Expr) -> Expr {
        match e {
            Expr::Leaf {
                name,
                kind: LeafKind::Now,
                ..
            } if self.hidden.contains_key(name) => self.expand(&self.hidden[name]),
            Expr::Not(x) => not(self.expand(x)),
            Expr::And(xs) => xs
                .iter()
                .map(|x| self.expand(x))
                .fold(Expr::Const(true), and),
            Expr::Or(xs) => xs
                .iter()
                .map(|x| self.expand(x))
                .fold(Expr::Const(false), or),
            e => e.clone(),
        }
    }

    /// A fresh memory name for an intermediate value of `var`.
    fn hidden_name(&mut self, var: &str) -> String {
        let mut n = self.hidden.len() + 1;
        loop {
            let name = format!("{var}_{n}");
            if !self.taken.contains(&name.to_ascii_lowercase()) && !self.hidden.contains_key(&name)
            {
                return name;
            }
            n += 1;
        }
    }

    /// `e`, or a hidden memory holding it when it is large and used twice (XOR, IF).
    fn small(&mut self, e: Expr, mode: Mode, span: Span) -> Expr {
        if mode == Mode::Body && size(&e) > HIDDEN_READ_ABOVE {
            let h = self.hide(e);
            leaf(&h, LeafKind::Now, span)
        } else {
            e
        }
    }

    /// Holds `value` in a new hidden memory; its name.
    fn hide(&mut self, value: Expr) -> String {
        let h = self.hidden_name("V");
        self.writes += 1;
        self.last.insert(h.clone(), self.writes);
        self.order.push(h.clone());
        self.hidden_order.push(h.clone());
        self.hidden.insert(h.clone(), value.clone());
        self.env.insert(h.clone(), value);
        h
    }

    /// The hidden memories, in the order they were made.
    pub(super) fn hidden_memories(&self) -> Vec<String> {
        self.hidden_order.clone()
    }

    fn timer(&mut self, step: &str, ms: u64, span: Span) -> Expr {
        let name = format!("{step}_T{ms}");
        if !self.timers.iter().any(|t| t.0 == name) {
            self.timers.push((name.clone(), step.to_string(), ms));
        }
        leaf(&name, LeafKind::Now, span)
    }

    /// `S.T op ms` as a step timer, or `None` when neither side is a step time.
    fn step_time(
        &mut self,
        op: BinOp,
        a: &StExpr,
        b: &StExpr,
        mode: Mode,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<Option<Expr>, Failure> {
        let step_of = |e: &StExpr| match e {
            StExpr::Var { path, at } if path.len() == 2 && path[1].eq_ignore_ascii_case("T") => {
                Some((path[0].clone(), *at))
            }
            _ => None,
        };
        let (step, at, ms, op) = match (step_of(a), b, step_of(b), a) {
            (Some((s, at)), StExpr::Time(ms), _, _) => (s, at, *ms, op),
            (_, _, Some((s, at)), StExpr::Time(ms)) => {
                let flipped = match op {
                    BinOp::Lt => BinOp::Gt,
                    BinOp::Le => BinOp::Ge,
                    BinOp::Gt => BinOp::Lt,
                    BinOp::Ge => BinOp::Le,
                    o => o,
                };
                (s, at, *ms, flipped)
            }
            (Some((_, at)), ..) | (_, _, Some((_, at)), _) => {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    "a step time `S.T` is compared with a `T#…` literal only",
                );
            }
            _ => return Ok(None),
        };
        let Some(step) = self.visible_step(&step) else {
            return fail(
                codes::PLCOPEN_UNKNOWN_NAME,
                at,
                format!("`{step}.T`: `{step}` is not a step of this POU's SFC"),
            );
        };
        if mode != Mode::Condition {
            return fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                "a step time is read in a transition condition only",
            );
        }
        let span = loc(at);
        Ok(Some(match op {
            BinOp::Ge => self.timer(&step, ms, span),
            BinOp::Gt => self.timer(&step, ms + 1, span),
            BinOp::Lt => not(self.timer(&step, ms, span)),
            BinOp::Le => not(self.timer(&step, ms + 1, span)),
            _ => {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    "a step time is compared with `>=`, `>`, `<` or `<=` (equality with a time is never exact on a scan)",
                );
            }
        }))
    }

    fn visible_step(&self, name: &str) -> Option<String> {
        self.visible_steps
            .iter()
            .find(|s| s.eq_ignore_ascii_case(name))
            .cloned()
    }

    /// Converts an ST expression into Vigie's logic at this point of the scan.
    pub(super) fn expr(
        &mut self,
        e: &StExpr,
        decls: &Declarations,
        mode: Mode,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<Expr, Failure> {
        match e {
            StExpr::Bool(b) => Ok(Expr::Const(*b)),
            StExpr::Int(_) | StExpr::Time(_) => fail(
                codes::PLCOPEN_UNSUPPORTED,
                Pos::default(),
                "a number where a Boolean is expected",
            ),
            StExpr::Not(x) => Ok(not(self.expr(x, decls, mode, loc)?)),
            StExpr::Bin(op, a, b) => {
                if let Some(t) = self.step_time(*op, a, b, mode, loc)? {
                    return Ok(t);
                }
                let x = self.expr(a, decls, mode, loc)?;
                let y = self.expr(b, decls, mode, loc)?;
                let (x, y) = if matches!(op, BinOp::Xor | BinOp::Ne | BinOp::Eq) {
                    let span = Span { line: 0, column: 0 };
                    (self.small(x, mode, span), self.small(y, mode, span))
                } else {
                    (x, y)
                };
                match op {
                    BinOp::And => Ok(and(x, y)),
                    BinOp::Or => Ok(or(x, y)),
                    BinOp::Xor | BinOp::Ne => Ok(xor(x, y)),
                    BinOp::Eq => Ok(not(xor(x, y))),
                    _ => fail(
                        codes::PLCOPEN_UNSUPPORTED,
                        Pos::default(),
                        "an order comparison between Booleans",
                    ),
                }
            }
            StExpr::Edge { rising, path, at } => {
                let x = self.var(path, *at, decls, mode, loc)?;
                self.edge_of(x, *rising, mode, *at, &path.join("."), loc)
            }
            StExpr::Var { path, at } => self.var(path, *at, decls, mode, loc),
        }
    }

    /// The rising or falling edge of `v`: `RE(x)`/`FE(x)` on a variable read as it is
    /// now; for any other value (a variable written earlier in the scan, or read before
    /// its write, an expression), a hidden memory keeps the value for the next scan and
    /// the edge compares with it.
    fn edge_of(
        &mut self,
        v: Expr,
        rising: bool,
        mode: Mode,
        at: Pos,
        what: &str,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<Expr, Failure> {
        if let Expr::Leaf {
            name,
            kind: LeafKind::Now,
            span,
        } = &v
        {
            let kind = if rising {
                LeafKind::Rise
            } else {
                LeafKind::Fall
            };
            return Ok(leaf(name, kind, *span));
        }
        if mode == Mode::Condition {
            return fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!(
                    "an edge of `{what}` in a transition: take it in a body (R_TRIG/F_TRIG) and read the result"
                ),
            );
        }
        let span = loc(at);
        let v = self.small(v, Mode::Body, span);
        let h = self.hide(v.clone());
        let before = leaf(&h, LeafKind::Prev, span);
        Ok(if rising {
            and(v, not(before))
        } else {
            and(not(v), before)
        })
    }

    fn var(
        &mut self,
        path: &[String],
        at: Pos,
        decls: &Declarations,
        mode: Mode,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<Expr, Failure> {
        let span = loc(at);
        let shown = path.join(".");
        if path.len() == 2
            && let Some(step) = self.visible_step(&path[0])
        {
            {
                return if path[1].eq_ignore_ascii_case("X") {
                    if mode == Mode::Condition {
                        Ok(leaf(&step, LeafKind::Now, span))
                    } else {
                        fail(
                            codes::PLCOPEN_UNSUPPORTED,
                            at,
                            format!(
                                "`{shown}`: a step flag is read in its chart's conditions only"
                            ),
                        )
                    }
                } else {
                    fail(
                        codes::PLCOPEN_UNSUPPORTED,
                        at,
                        format!(
                            "`{shown}`: a step has `.X` (active) and `.T` (compared with a time)"
                        ),
                    )
                };
            }
        }
        let Some(d) = decls.vars.get(&path[0].to_ascii_lowercase()) else {
            return fail(
                codes::PLCOPEN_UNKNOWN_NAME,
                at,
                format!("`{}` is not declared", path[0]),
            );
        };
        match (&d.kind, path.len()) {
            (Kind::Trig { .. }, 2) if path[1].eq_ignore_ascii_case("Q") => {
                match self.trig.get(&d.name) {
                    Some(q) => Ok(q.clone()),
                    None => fail(
                        codes::PLCOPEN_UNSUPPORTED,
                        at,
                        format!(
                            "`{shown}` is read before `{}` is called in the scan",
                            d.name
                        ),
                    ),
                }
            }
            (Kind::Trig { .. }, _) => fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!("`{shown}`: an edge detector is read as `.Q`"),
            ),
            (Kind::Timer(_) | Kind::Counter(_), 2) if path[1].eq_ignore_ascii_case("Q") => {
                let called = self.timer_in.contains_key(&d.name);
                match (mode, called) {
                    (Mode::Body, true) | (Mode::Condition, false) => {
                        Ok(leaf(&d.name, LeafKind::Now, span))
                    }
                    (Mode::Body, false) => Ok(leaf(&d.name, LeafKind::Prev, span)),
                    (Mode::Condition, true) => fail(
                        codes::PLCOPEN_UNSUPPORTED,
                        at,
                        format!(
                            "`{shown}` is read by a chart after its call in the same scan: call the timer in a POU after the chart"
                        ),
                    ),
                }
            }
            (
                Kind::Timer(_)
                | Kind::Counter(_)
                | Kind::Integer(_)
                | Kind::Duration(_)
                | Kind::Unsupported(_),
                _,
            ) => not_boolean(&d.kind, &shown, &path[0], at),
            (_, 1) => Ok(self.read(d, mode, span)),
            _ => fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!("`{shown}`: a Boolean variable has no members"),
            ),
        }
    }

    /// Runs statements under `guard`.
    pub(super) fn run(
        &mut self,
        stmts: &[Stmt],
        guard: &Expr,
        decls: &Declarations,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<(), Failure> {
        for s in stmts {
            match s {
                Stmt::Assign { target, value, at } => {
                    let v = self.expr(value, decls, Mode::Body, loc)?;
                    self.assign(target, *at, v, guard, decls, loc)?;
                }
                Stmt::If {
                    branches,
                    otherwise,
                } => {
                    let mut conds = Vec::new();
                    for (c, _) in branches {
                        let e = self.expr(c, decls, Mode::Body, loc)?;
                        conds.push(self.small(e, Mode::Body, Span { line: 0, column: 0 }));
                    }
                    let mut none_before = Expr::Const(true);
                    for ((_, body), c) in branches.iter().zip(conds) {
                        let g = and(guard.clone(), and(none_before.clone(), c.clone()));
                        self.run(body, &g, decls, loc)?;
                        none_before = and(none_before, not(c));
                    }
                    let g = and(guard.clone(), none_before);
                    self.run(otherwise, &g, decls, loc)?;
                }
                Stmt::Call { instance, args, at } => {
                    self.call(instance, args, *at, guard, decls, loc)?;
                }
            }
        }
        Ok(())
    }

    fn assign(
        &mut self,
        target: &[String],
        at: Pos,
        value: Expr,
        guard: &Expr,
        decls: &Declarations,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<(), Failure> {
        let shown = target.join(".");
        let Some(d) = decls.vars.get(&target[0].to_ascii_lowercase()) else {
            return fail(
                codes::PLCOPEN_UNKNOWN_NAME,
                at,
                format!("`{shown}` is not declared"),
            );
        };
        match (&d.kind, target.len()) {
            (Kind::Output | Kind::Memory, 1) => {}
            (Kind::Input, _) => {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    format!("`{shown}` is a plant input: the program cannot write it"),
                );
            }
            (Kind::Panel, _) => {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    format!(
                        "`{shown}` is an input of the program (an operator button): the program cannot write it"
                    ),
                );
            }
            (Kind::Unsupported(t), _) => {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    format!("`{shown}` is of type {t}: only BOOL variables are run"),
                );
            }
            _ => {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    format!("`{shown}` cannot be assigned"),
                );
            }
        }
        let name = d.name.clone();
        let span = loc(at);
        self.place(&name, self.body.1, span.line, span.column);
        let new = if *guard == Expr::Const(true) {
            value
        } else {
            let old = self.read(d, Mode::Body, loc(at));
            let g = self.small(guard.clone(), Mode::Body, loc(at));
            let value = self.small(value, Mode::Body, loc(at));
            or(and(g.clone(), value), and(not(g), old))
        };
        // A variable written once holds its value in its own equation.
        let once = self.written.get(&name) == Some(&1);
        let new = if size(&new) > HIDDEN_ABOVE && !once && !self.action_targets.contains(&name) {
            let h = self.hide(new);
            leaf(&h, LeafKind::Now, loc(at))
        } else {
            new
        };
        if !self.env.contains_key(&name) {
            self.order.push(name.clone());
        }
        self.writes += 1;
        self.last.insert(name.clone(), self.writes);
        self.env.insert(name, new);
        Ok(())
    }

    fn call(
        &mut self,
        instance: &str,
        args: &[(String, StExpr)],
        at: Pos,
        guard: &Expr,
        decls: &Declarations,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<(), Failure> {
        let Some(d) = decls.vars.get(&instance.to_ascii_lowercase()) else {
            return fail(
                codes::PLCOPEN_UNKNOWN_NAME,
                at,
                format!("`{instance}` is not declared"),
            );
        };
        let (what, timer, rising) = match d.kind {
            Kind::Timer(kind) => ("timers", Some(kind), false),
            Kind::Counter(_) => ("counters", None, false),
            Kind::Trig { rising } => ("edge detectors", None, rising),
            _ => {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    format!(
                        "`{instance}` is called but is not an instance of R_TRIG, F_TRIG, TON, TOF, TP, CTU or CTD: only these function blocks are run"
                    ),
                );
            }
        };
        // Both keep a state from call to call: one call per scan, always.
        if *guard != Expr::Const(true) {
            return fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!(
                    "`{instance}` is called under a condition: call {what} once per scan, outside IF"
                ),
            );
        }
        if self.trig.contains_key(&d.name) || self.timer_in.contains_key(&d.name) {
            return fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!("`{instance}` is called twice in the scan"),
            );
        }
        if let Some(kind) = timer {
            return self.call_timer(d.name.clone(), kind, args, at, decls, loc);
        }
        if let Kind::Counter(kind) = d.kind {
            return self.call_counter(d.name.clone(), kind, args, at, decls, loc);
        }
        let [(input, clk)] = args else {
            return fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!("`{instance}` takes one input, CLK"),
            );
        };
        if !input.eq_ignore_ascii_case("CLK") {
            return fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!("`{instance}` has no input `{input}` (it takes CLK)"),
            );
        }
        let clk = self.expr(clk, decls, Mode::Body, loc)?;
        let q = self.edge_of(clk, rising, Mode::Body, at, instance, loc)?;
        self.trig.insert(d.name.clone(), q);
        Ok(())
    }

    /// A `TON`, `TOF` or `TP` call (checked by [`Self::call`]): its input becomes the
    /// timer's equation, here in the scan.
    fn call_timer(
        &mut self,
        name: String,
        kind: DelayKind,
        args: &[(String, StExpr)],
        at: Pos,
        decls: &Declarations,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<(), Failure> {
        let mut input = None;
        let mut ms = None;
        for (arg, value) in args {
            if arg.eq_ignore_ascii_case("IN") {
                input = Some(self.expr(value, decls, Mode::Body, loc)?);
            } else if arg.eq_ignore_ascii_case("PT") {
                ms = Some(constant_input(
                    (
                        &name,
                        "PT",
                        "a T#… literal or a TIME variable with an initial value, never written",
                    ),
                    value,
                    at,
                    decls,
                    |e| match e {
                        StExpr::Time(ms) => Some(*ms),
                        _ => None,
                    },
                    |k| match k {
                        Kind::Duration(ms) => Some(*ms),
                        _ => None,
                    },
                )?);
            } else {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    format!("`{name}` has no input `{arg}` run by Vigie (IN and PT)"),
                );
            }
        }
        let (Some(input), Some(ms)) = (input, ms) else {
            return fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!("`{name}` is called without IN or PT: both are needed"),
            );
        };
        let input = self.small(input, Mode::Body, loc(at));
        self.writes += 1;
        self.last.insert(name.clone(), self.writes);
        self.order.push(name.clone());
        self.timer_in.insert(name.clone(), input);
        self.delays.push(Delay { id: name, kind, ms });
        Ok(())
    }

    /// A `CTU` or `CTD` call (checked by [`Self::call`]): its count input becomes the
    /// counter's equation, here in the scan, with its reset beside it.
    fn call_counter(
        &mut self,
        name: String,
        kind: CounterKind,
        args: &[(String, StExpr)],
        at: Pos,
        decls: &Declarations,
        loc: &dyn Fn(Pos) -> Span,
    ) -> Result<(), Failure> {
        let (count, reset) = match kind {
            CounterKind::Up => ("CU", "R"),
            CounterKind::Down => ("CD", "LD"),
        };
        let (mut input, mut cleared, mut preset) = (None, None, None);
        for (arg, value) in args {
            if arg.eq_ignore_ascii_case(count) {
                input = Some(self.expr(value, decls, Mode::Body, loc)?);
            } else if arg.eq_ignore_ascii_case(reset) {
                cleared = Some(self.expr(value, decls, Mode::Body, loc)?);
            } else if arg.eq_ignore_ascii_case("PV") {
                preset = Some(constant_int(&name, value, at, decls)?);
            } else {
                return fail(
                    codes::PLCOPEN_UNSUPPORTED,
                    at,
                    format!("`{name}` has no input `{arg}` run by Vigie ({count}, {reset} and PV)"),
                );
            }
        }
        let (Some(input), Some(preset)) = (input, preset) else {
            return fail(
                codes::PLCOPEN_UNSUPPORTED,
                at,
                format!("`{name}` is called without {count} or PV: both are needed"),
            );
        };
        // An input left open is FALSE.
        let cleared = self.small(cleared.unwrap_or(Expr::Const(false)), Mode::Body, loc(at));
        let input = self.small(input, Mode::Body, loc(at));
        self.writes += 1;
        self.last.insert(name.clone(), self.writes);
        self.order.push(name.clone());
        self.timer_in.insert(name.clone(), input);
        self.counters.push(Counter {
            id: name,
            kind,
            preset,
            reset: render(&cleared),
        });
        Ok(())
    }

    /// The equations, in Vigie's order: the variables written by ST or LD only, then
    /// those also written by an SFC action (`x := x OR g` becomes the equation `g`).
    pub(super) fn equations(&self) -> Result<Vec<(String, Expr)>, String> {
        let mut plain = Vec::new();
        let mut with_actions = Vec::new();
        // By last write: an equation reads the hidden memories made before it.
        let mut order = self.order.clone();
        order.sort_by_key(|n| self.last.get(n).copied().unwrap_or(0));
        for name in &order {
            if let Some(input) = self.timer_in.get(name) {
                plain.push((name.clone(), input.clone()));
                continue;
            }
            let e = self.env.get(name).cloned().unwrap_or(Expr::Const(false));
            if !self.action_targets.contains(name) {
                plain.push((name.clone(), e));
                continue;
            }
            let is_self = |x: &Expr| matches!(x, Expr::Leaf { name: n, kind: LeafKind::Now, .. } if n == name);
            let rest = match e {
                Expr::Or(terms) if terms.iter().any(is_self) => terms
                    .into_iter()
                    .filter(|t| !is_self(t))
                    .fold(Expr::Const(false), or),
                e if is_self(&e) => continue,
                _ => {
                    return Err(format!(
                        "`{name}` is driven by an SFC action and written by ST or LD: write it `{name} := {name} OR …` (a coil in parallel with the action), since the actions and the equation are ORed"
                    ));
                }
            };
            with_actions.push((name.clone(), rest));
        }
        // An equation of the second group reading another of that group would see
        // its value after that equation: refused.
        let late: BTreeSet<&str> = with_actions.iter().map(|(n, _)| n.as_str()).collect();
        for (n, e) in &with_actions {
            for (name, kind, _) in e.leaves() {
                if kind != LeafKind::Prev && name != n && late.contains(name) {
                    return Err(format!(
                        "the equation of `{n}` reads `{name}`, both driven by SFC actions and written by ST or LD: write one of them as a plain coil"
                    ));
                }
            }
        }
        plain.extend(with_actions);
        Ok(plain)
    }

    /// Records that the chart driving `targets` has run in this scan: from here on, a
    /// body reads their actions' value now, not their previous value.
    pub(super) fn finish_chart(&mut self, targets: &BTreeSet<String>) {
        self.charts_done.extend(targets.iter().cloned());
    }
}

/// Renders an expression in Vigie's notation (`a . /b + RE(c)`).
pub(super) fn render(e: &Expr) -> String {
    fn go(e: &Expr, parent: u8, out: &mut String) {
        match e {
            Expr::Const(b) => out.push(if *b { '1' } else { '0' }),
            Expr::Leaf { name, kind, .. } => match kind {
                LeafKind::Now => out.push_str(name),
                LeafKind::Prev => {
                    out.push_str(name);
                    out.push('*');
                }
                LeafKind::Rise => out.push_str(&format!("RE({name})")),
                LeafKind::Fall => out.push_str(&format!("FE({name})")),
                LeafKind::Estimate => out.push_str(&format!("EST({name})")),
            },
            Expr::Not(x) => {
                out.push('/');
                go(x, 3, out);
            }
            Expr::And(xs) => list(xs, " . ", 2, parent, out),
            Expr::Or(xs) => list(xs, " + ", 1, parent, out),
        }
    }
    /// The terms of an AND (level 2) or an OR (level 1), in parentheses inside a
    /// tighter operator.
    fn list(xs: &[Expr], sep: &str, level: u8, parent: u8, out: &mut String) {
        if parent > level {
            out.push('(');
        }
        for (i, x) in xs.iter().enumerate() {
            if i > 0 {
                out.push_str(sep);
            }
            go(x, level, out);
        }
        if parent > level {
            out.push(')');
        }
    }
    let mut out = String::new();
    go(e, 0, &mut out);
    out
}

/// Vigie's own block: start and stop buttons, description and chart names.
#[derive(Default)]
pub(super) struct VigieData {
    pub(super) start: Option<String>,
    pub(super) stop: Option<String>,
    pub(super) description: Option<String>,
    /// Chart name by step name.
    pub(super) charts: BTreeMap<String, String>,
    pub(super) chart_order: Vec<String>,
}

fn vigie_data(project: Node<'_, '_>) -> VigieData {
    let mut out = VigieData::default();
    let Some(block) = project.descendants().find(|n| {
        n.is_element() && n.tag_name().name() == "data" && n.attribute("name") == Some(ADD_DATA)
    }) else {
        return out;
    };
    let Some(p) = child(block, "program") else {
        return out;
    };
    out.start = p.attribute("start").map(str::to_string);
    out.stop = p.attribute("stop").map(str::to_string);
    out.description = p.attribute("description").map(str::to_string);
    for c in children(p, "chart") {
        let name = c.attribute("name").unwrap_or("").to_string();
        for s in c.attribute("steps").unwrap_or("").split_whitespace() {
            out.charts.insert(s.to_string(), name.clone());
        }
        out.chart_order.push(name);
    }
    out
}

/// Imports a PLCopen XML project as a Vigie program for `plant`. `file` places the
/// problems. Every problem found is returned; the program only when there is none.
pub fn import(text: &str, file: &Path, plant: &Plant) -> Result<Program, Vec<Problem>> {
    let doc = Document::parse(text).map_err(|e| {
        let p = e.pos();
        vec![Problem::error(
            codes::PLCOPEN_XML_INVALID.id,
            format!("not well-formed XML: {e}"),
            Some(Location::new(file, p.row as usize, p.col as usize)),
        )]
    })?;
    let mut ctx = Ctx {
        file,
        doc: &doc,
        problems: Vec::new(),
    };
    let project = doc.root_element();
    if project.tag_name().name() != "project" {
        ctx.error(
            codes::PLCOPEN_XML_INVALID,
            project,
            format!(
                "the root element is `{}`, not a PLCopen `project`",
                project.tag_name().name()
            ),
        );
        return Err(ctx.problems);
    }
    let pous = program_pous(&mut ctx, project);
    if pous.is_empty() && ctx.problems.is_empty() {
        ctx.error(
            codes::PLCOPEN_XML_INVALID,
            project,
            "the project has no POU of type program",
        );
    }
    let program = build(&mut ctx, plant, project, &pous);
    if ctx.problems.is_empty() {
        Ok(program)
    } else {
        Err(ctx.problems)
    }
}

/// One program POU's body, read.
enum Body {
    Sfc(sfc::Chart),
    /// Statements, their text, and the body's language (`ST`, `LD`, `FBD`).
    Stmts(Vec<Stmt>, StText, &'static str),
}

fn build(
    ctx: &mut Ctx<'_, '_>,
    plant: &Plant,
    project: Node<'_, '_>,
    pous: &[Node<'_, '_>],
) -> Program {
    let vigie = vigie_data(project);
    let mut decls = Declarations {
        vars: BTreeMap::new(),
        panel: Vec::new(),
        memories: Vec::new(),
        initial: Vec::new(),
    };
    for globals in project
        .descendants()
        .filter(|n| n.is_element() && matches!(n.tag_name().name(), "configuration" | "resource"))
    {
        declare_interface(ctx, plant, globals, &mut decls);
    }
    for pou in pous {
        if let Some(i) = child(*pou, "interface") {
            declare_interface(ctx, plant, i, &mut decls);
        }
    }
    let bodies = read_bodies(ctx, pous, &decls);
    if !ctx.problems.is_empty() {
        return empty_program();
    }
    let step_names = check_step_names(ctx, &bodies, &decls);
    let written = written_vars(&bodies, &decls);
    let action_targets: BTreeSet<String> = bodies
        .iter()
        .filter_map(|(_, b)| match b {
            Body::Sfc(c) => Some(c.action_targets()),
            Body::Stmts(..) => None,
        })
        .flatten()
        .collect();
    let mut taken: BTreeSet<String> = decls.vars.keys().cloned().collect();
    taken.extend(step_names.keys().cloned());
    let mut m = Machine::new(written, action_targets, taken);
    m.file = ctx.file.file_name().map_or_else(
        || ctx.file.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    let mut charts = Vec::new();
    for (pou, body) in &bodies {
        m.body = (
            pou.clone(),
            match body {
                Body::Sfc(_) => "SFC",
                Body::Stmts(_, _, lang) => lang,
            },
        );
        match body {
            Body::Sfc(c) => {
                m.visible_steps = c.steps.iter().map(|s| s.name.clone()).collect();
                charts.extend(sfc::lower(ctx, pou, c, &mut m, &decls, &vigie));
                m.finish_chart(&c.action_targets());
                m.visible_steps.clear();
            }
            Body::Stmts(stmts, text, _) => {
                let file = ctx.file.to_path_buf();
                let loc = |p: Pos| {
                    let l = text.locate(&file, p);
                    Span {
                        line: l.line,
                        column: l.column,
                    }
                };
                if let Err(f) = m.run(stmts, &Expr::Const(true), &decls, &loc) {
                    let at = text.locate(ctx.file, f.at);
                    ctx.error_at(f.code, at, format!("POU `{pou}`: {}", f.message));
                }
            }
        }
    }
    let equations = match m.equations() {
        Ok(e) => e,
        Err(message) => {
            let at = Location::new(ctx.file, 1, 1);
            ctx.error_at(codes::PLCOPEN_UNSUPPORTED, at, message);
            Vec::new()
        }
    };
    let name = child(project, "contentHeader")
        .and_then(|h| h.attribute("name"))
        .or_else(|| pous.first().and_then(|p| p.attribute("name")))
        .unwrap_or("PLCopen program")
        .to_string();
    assemble(&decls, &m, &vigie, name, charts, &equations)
}

/// Reads each program POU's body (SFC, ST or LD).
fn read_bodies(
    ctx: &mut Ctx<'_, '_>,
    pous: &[Node<'_, '_>],
    decls: &Declarations,
) -> Vec<(String, Body)> {
    let mut bodies = Vec::new();
    for pou in pous {
        let name = pou.attribute("name").unwrap_or("?").to_string();
        let Some(body) = child(*pou, "body") else {
            ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                *pou,
                format!("POU `{name}` has no body"),
            );
            continue;
        };
        let Some(lang) = body.children().find(Node::is_element) else {
            ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                body,
                format!("POU `{name}` has an empty body"),
            );
            continue;
        };
        match lang.tag_name().name() {
            "SFC" => {
                if let Some(c) = sfc::read(ctx, *pou, lang, decls) {
                    bodies.push((name, Body::Sfc(c)));
                }
            }
            "ST" => {
                let text = st_text(ctx, lang);
                match st::parse_statements(&text.text) {
                    Ok(s) => bodies.push((name, Body::Stmts(s, text, "ST"))),
                    Err(e) => {
                        let at = text.locate(ctx.file, e.at);
                        ctx.error_at(
                            codes::PLCOPEN_ST_INVALID,
                            at,
                            format!("POU `{name}`: {}", e.message),
                        );
                    }
                }
            }
            "LD" | "FBD" => {
                let language = if lang.tag_name().name() == "LD" {
                    "LD"
                } else {
                    "FBD"
                };
                if let Some((stmts, text)) = ld::read_body(ctx, &name, lang) {
                    bodies.push((name, Body::Stmts(stmts, text, language)));
                }
            }
            other => ctx.error(
                codes::PLCOPEN_UNSUPPORTED,
                lang,
                format!("POU `{name}` is written in {other}: Vigie runs SFC, ST and LD bodies"),
            ),
        }
    }
    bodies
}

/// Steps share one namespace with the variables: their names by lower case, with
/// their POU.
fn check_step_names(
    ctx: &mut Ctx<'_, '_>,
    bodies: &[(String, Body)],
    decls: &Declarations,
) -> BTreeMap<String, String> {
    let mut step_names: BTreeMap<String, String> = BTreeMap::new();
    for (pou, body) in bodies {
        if let Body::Sfc(c) = body {
            for s in &c.steps {
                let key = s.name.to_ascii_lowercase();
                if decls.vars.contains_key(&key) || step_names.insert(key, pou.clone()).is_some() {
                    ctx.error_at(
                        codes::PLCOPEN_UNSUPPORTED,
                        s.at.clone(),
                        format!("step `{}` of POU `{pou}`: the name is also a variable or a step of another POU (Vigie's steps share one namespace)", s.name),
                    );
                }
            }
        }
    }
    step_names
}

/// The program read: the declarations, the scan's equations and the charts.
fn assemble(
    decls: &Declarations,
    m: &Machine,
    vigie: &VigieData,
    name: String,
    charts: Vec<Chart>,
    equations: &[(String, Expr)],
) -> Program {
    let check_button = |b: &Option<String>| {
        b.as_ref().and_then(|n| {
            decls
                .vars
                .get(&n.to_ascii_lowercase())
                .filter(|d| matches!(d.kind, Kind::Panel | Kind::Input))
                .map(|d| d.name.clone())
        })
    };
    Program {
        name,
        description: vigie.description.clone().unwrap_or_default(),
        panel: decls.panel.clone(),
        start: check_button(&vigie.start),
        stop: check_button(&vigie.stop),
        memories: decls
            .memories
            .iter()
            .cloned()
            .chain(m.hidden_memories())
            .collect(),
        timers: m.timers.clone(),
        initial: decls.initial.clone(),
        delays: m.delays.clone(),
        counters: m.counters.clone(),
        charts,
        equations: equations
            .iter()
            .map(|(n, e)| (n.clone(), render(e)))
            .collect(),
        places: m.places.clone(),
    }
}

fn empty_program() -> Program {
    Program {
        name: String::new(),
        description: String::new(),
        panel: Vec::new(),
        start: None,
        stop: None,
        memories: Vec::new(),
        timers: Vec::new(),
        delays: Vec::new(),
        counters: Vec::new(),
        initial: Vec::new(),
        charts: Vec::new(),
        equations: Vec::new(),
        places: BTreeMap::new(),
    }
}

/// The Vigie names of the variables that some ST or LD body writes.
fn written_vars(bodies: &[(String, Body)], decls: &Declarations) -> BTreeMap<String, usize> {
    fn walk(stmts: &[Stmt], decls: &Declarations, out: &mut BTreeMap<String, usize>) {
        for s in stmts {
            match s {
                Stmt::Assign { target, .. } => {
                    if let Some(d) = decls.vars.get(&target[0].to_ascii_lowercase()) {
                        *out.entry(d.name.clone()).or_default() += 1;
                    }
                }
                Stmt::If {
                    branches,
                    otherwise,
                } => {
                    for (_, b) in branches {
                        walk(b, decls, out);
                    }
                    walk(otherwise, decls, out);
                }
                Stmt::Call { .. } => {}
            }
        }
    }
    let mut out = BTreeMap::new();
    for (_, b) in bodies {
        if let Body::Stmts(s, _, _) = b {
            walk(s, decls, &mut out);
        }
    }
    out
}

/// Builds a chart's Vigie steps from the read SFC (used by [`sfc::lower`]).
pub(super) fn vigie_step(name: &str, initial: bool, actions: Vec<(Qualifier, String)>) -> Step {
    Step {
        id: name.to_string(),
        initial,
        actions: actions
            .into_iter()
            .map(|(qualifier, target)| Action { qualifier, target })
            .collect(),
    }
}

/// A Vigie transition.
pub(super) fn vigie_transition(
    id: &str,
    from: Vec<String>,
    to: Vec<String>,
    condition: &Expr,
) -> Transition {
    Transition {
        id: id.to_string(),
        from,
        to,
        condition: render(condition),
    }
}

/// A Vigie chart.
pub(super) fn vigie_chart(name: String, steps: Vec<Step>, transitions: Vec<Transition>) -> Chart {
    Chart {
        name,
        steps,
        transitions,
    }
}
