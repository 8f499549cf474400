//! [`Program`](crate::control::Program) → PLCopen XML: the charts as one SFC POU, the equations as an ST POU run
//! after it, every variable global (plant signals at their located address), and
//! Vigie's block with the start and stop buttons and the chart names.
//!
//! Vigie's notation has forms that IEC 61131-3 writes differently:
//! - a previous value `x*`, and the edges `RE(x)` and `FE(x)` built on it, read a
//!   variable `x_PRE` that the last statement of the scan sets (`x_PRE := x;`);
//! - a step timer `(t, S, 300)` is the condition `S.T >= T#300ms`;
//! - an equation reading a step `S` reads a memory `S_X` driven by an N action of the
//!   step (steps are visible in their own POU only);
//! - an equation whose target `y` an SFC action also drives is `y := y OR (…);`.
//!
//! Reading the file back gives a program that runs exactly as the original (the
//! station's reference and every variant of its error library are checked scan by
//! scan); reading, writing and reading again gives the same program.

use super::st::write_duration;
use super::{ADD_DATA, NAMESPACE};
use crate::control::{Program, Qualifier};
use crate::diag::codes;
use crate::diag::{Location, Problem};
use crate::expr::{self, Expr, LeafKind};
use crate::plant::{Address, Plant};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::Path;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn is_iec_identifier(s: &str) -> bool {
    let mut c = s.chars();
    c.next()
        .is_some_and(|f| f.is_ascii_alphabetic() || f == '_')
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !s.contains("__")
}

/// What a name of the program is.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    Input,
    Output,
    Panel,
    Memory,
    Step,
    Timer,
    /// A standard timer on an expression (TON, TOF, TP).
    Delay,
}

struct Writer<'a> {
    program: &'a Program,
    plant: &'a Plant,
    roles: BTreeMap<String, Role>,
    /// Timer → (step, ms).
    timers: BTreeMap<String, (String, u64)>,
    /// Variables whose previous value is read (`x_PRE`).
    pre: BTreeSet<String>,
    /// Steps read by the equations (`S_X`).
    mirrors: BTreeSet<String>,
    action_targets: BTreeSet<String>,
    problems: Vec<Problem>,
    file: &'a Path,
}

impl Writer<'_> {
    fn problem(&mut self, message: String) {
        self.problems.push(Problem::error(
            codes::PLCOPEN_EXPORT.id,
            message,
            Some(Location::new(self.file, 1, 1)),
        ));
    }

    fn parse(&mut self, text: &str, what: &str) -> Expr {
        match expr::parse_str(text) {
            Ok(e) => e,
            Err(e) => {
                self.problem(format!("{what}: {e}"));
                Expr::Const(false)
            }
        }
    }

    fn pre_name(&mut self, v: &str) -> String {
        self.pre.insert(v.to_string());
        format!("{v}_PRE")
    }

    /// A leaf of a transition condition (evaluated before the evolution).
    fn cond_leaf(&mut self, name: &str, kind: LeafKind) -> String {
        let role = self.roles.get(name).copied();
        match (kind, role) {
            (LeafKind::Now | LeafKind::Prev, Some(Role::Delay)) => format!("{name}.Q"),
            (LeafKind::Now, Some(Role::Step)) => format!("{name}.X"),
            (LeafKind::Now, Some(Role::Timer)) => {
                let (step, ms) = self.timers[name].clone();
                format!("({step}.T >= {})", write_duration(ms))
            }
            (LeafKind::Now, _) => name.to_string(),
            // Before the evolution, a step's, an output's or a memory's previous value
            // is its value (the last scan's); an input's or a button's is not.
            (LeafKind::Prev, Some(Role::Input | Role::Panel)) => self.pre_name(name),
            (LeafKind::Prev, Some(Role::Timer)) => {
                self.problem(format!(
                    "the previous value of the timer `{name}` has no PLCopen form"
                ));
                "FALSE".into()
            }
            (LeafKind::Prev, _) => self.cond_leaf(name, LeafKind::Now),
            (LeafKind::Rise, _) => {
                let now = self.cond_leaf(name, LeafKind::Now);
                let pre = self.cond_leaf(name, LeafKind::Prev);
                format!("({now} AND NOT {pre})")
            }
            (LeafKind::Fall, _) => {
                let now = self.cond_leaf(name, LeafKind::Now);
                let pre = self.cond_leaf(name, LeafKind::Prev);
                format!("({pre} AND NOT {now})")
            }
            (LeafKind::Estimate, _) => {
                self.problem(format!(
                    "`EST({name})` is read from the diagnosers, not from the PLC"
                ));
                "FALSE".into()
            }
        }
    }

    /// A leaf of equation `k` (evaluated after the actions and the equations before it).
    fn rung_leaf(&mut self, name: &str, kind: LeafKind, k: usize, targets: &[String]) -> String {
        let role = self.roles.get(name).copied();
        let index = targets.iter().position(|t| t == name);
        let later = index.is_some_and(|i| i >= k);
        let driven = self.action_targets.contains(name);
        match (kind, role) {
            (LeafKind::Now, Some(Role::Delay)) => format!("{name}.Q"),
            (LeafKind::Prev, Some(Role::Delay)) if later => format!("{name}.Q"),
            (LeafKind::Now, Some(Role::Step)) => {
                self.mirrors.insert(name.to_string());
                format!("{name}_X")
            }
            (LeafKind::Now, Some(Role::Timer)) => {
                self.problem(format!("an equation reads the step timer `{name}`: write it in a transition, or keep the program in Vigie's format"));
                "FALSE".into()
            }
            // Before its own equation, a target holds its actions' value: none.
            (LeafKind::Now, _) if later && !driven => "FALSE".into(),
            (LeafKind::Now, _) => name.to_string(),
            (LeafKind::Prev, Some(Role::Output | Role::Memory)) if later && !driven => {
                name.to_string()
            }
            (LeafKind::Prev, Some(Role::Output | Role::Memory)) if index.is_none() && !driven => {
                name.to_string()
            }
            (LeafKind::Prev, Some(Role::Step | Role::Timer)) => {
                self.problem(format!(
                    "an equation reads the previous value of the step `{name}`"
                ));
                "FALSE".into()
            }
            (LeafKind::Prev, _) => self.pre_name(name),
            (LeafKind::Rise, _) => {
                let now = self.rung_leaf(name, LeafKind::Now, k, targets);
                let pre = self.rung_leaf(name, LeafKind::Prev, k, targets);
                format!("({now} AND NOT {pre})")
            }
            (LeafKind::Fall, _) => {
                let now = self.rung_leaf(name, LeafKind::Now, k, targets);
                let pre = self.rung_leaf(name, LeafKind::Prev, k, targets);
                format!("({pre} AND NOT {now})")
            }
            (LeafKind::Estimate, _) => {
                self.problem(format!(
                    "`EST({name})` is read from the diagnosers, not from the PLC"
                ));
                "FALSE".into()
            }
        }
    }

    fn st(
        &mut self,
        e: &Expr,
        parent: u8,
        leaf: &mut dyn FnMut(&mut Self, &str, LeafKind) -> String,
    ) -> String {
        match e {
            Expr::Const(b) => if *b { "TRUE" } else { "FALSE" }.into(),
            Expr::Leaf { name, kind, .. } => leaf(self, name, *kind),
            Expr::Not(x) => format!("NOT {}", self.st(x, 3, leaf)),
            Expr::And(xs) => {
                let parts: Vec<String> = xs.iter().map(|x| self.st(x, 2, leaf)).collect();
                let s = parts.join(" AND ");
                if parent > 2 { format!("({s})") } else { s }
            }
            Expr::Or(xs) => {
                let parts: Vec<String> = xs.iter().map(|x| self.st(x, 1, leaf)).collect();
                let s = parts.join(" OR ");
                if parent > 1 { format!("({s})") } else { s }
            }
        }
    }

    fn condition(&mut self, text: &str, what: &str) -> String {
        let e = self.parse(text, what);
        self.st(&e, 0, &mut |w, n, k| w.cond_leaf(n, k))
    }

    fn rung(&mut self, k: usize, targets: &[String]) -> String {
        let (target, text) = self.program.equations[k].clone();
        let e = self.parse(&text, &format!("equation of `{target}`"));
        if let Some(d) = self.program.delays.iter().find(|d| d.id == target) {
            let ms = d.ms;
            let input = self.st(&e, 0, &mut |w, n, kind| w.rung_leaf(n, kind, k, targets));
            return format!("{target}(IN := {input}, PT := {});", write_duration(ms));
        }
        if let Some(c) = self.program.counters.iter().find(|c| c.id == target) {
            let (count, reset) = match c.kind {
                crate::control::CounterKind::Up => ("CU", "R"),
                crate::control::CounterKind::Down => ("CD", "LD"),
            };
            let preset = c.preset;
            let cleared = self.parse(&c.reset, &format!("reset of counter `{target}`"));
            let cleared = self.st(&cleared, 0, &mut |w, n, kind| {
                w.rung_leaf(n, kind, k, targets)
            });
            let input = self.st(&e, 0, &mut |w, n, kind| w.rung_leaf(n, kind, k, targets));
            return format!("{target}({count} := {input}, {reset} := {cleared}, PV := {preset});");
        }
        // ORed with the actions' value, the body is an operand of OR.
        let driven = self.action_targets.contains(&target);
        let body = self.st(&e, u8::from(driven), &mut |w, n, kind| {
            w.rung_leaf(n, kind, k, targets)
        });
        if driven {
            format!("{target} := {target} OR {body};")
        } else {
            format!("{target} := {body};")
        }
    }
}

/// Writes `program` (for `plant`) as a PLCopen TC6 v2.01 project. `file` places the
/// problems (the program's own file).
pub fn export(program: &Program, plant: &Plant, file: &Path) -> Result<String, Vec<Problem>> {
    let mut roles = BTreeMap::new();
    for s in &plant.inputs {
        roles.insert(s.id.clone(), Role::Input);
    }
    for s in &plant.outputs {
        roles.insert(s.id.clone(), Role::Output);
    }
    for p in &program.panel {
        roles.insert(p.clone(), Role::Panel);
    }
    for m in &program.memories {
        roles.insert(m.clone(), Role::Memory);
    }
    for (_, s) in program.steps() {
        roles.insert(s.id.clone(), Role::Step);
    }
    let mut timers = BTreeMap::new();
    for (id, step, ms) in &program.timers {
        roles.insert(id.clone(), Role::Timer);
        timers.insert(id.clone(), (step.clone(), *ms));
    }
    // A timer's or a counter's output is read as `.Q`.
    for d in &program.delays {
        roles.insert(d.id.clone(), Role::Delay);
    }
    for c in &program.counters {
        roles.insert(c.id.clone(), Role::Delay);
    }
    let action_targets = program
        .steps()
        .flat_map(|(_, s)| s.actions.iter().map(|a| a.target.clone()))
        .collect();
    let mut w = Writer {
        program,
        plant,
        roles,
        timers,
        pre: BTreeSet::new(),
        mirrors: BTreeSet::new(),
        action_targets,
        problems: Vec::new(),
        file,
    };
    let pou = ident(&program.name);
    let mut conditions = Vec::new();
    for (_, t) in program.transitions() {
        let c = w.condition(&t.condition, &format!("transition `{}`", t.id));
        conditions.push((t.id.clone(), c));
    }
    let targets: Vec<String> = program.equations.iter().map(|e| e.0.clone()).collect();
    let mut rungs = Vec::new();
    for k in 0..program.equations.len() {
        rungs.push(w.rung(k, &targets));
    }
    for v in w.pre.clone() {
        if w.roles.get(&v) == Some(&Role::Delay) {
            rungs.push(format!("{v}_PRE := {v}.Q;"));
        } else {
            rungs.push(format!("{v}_PRE := {v};"));
        }
    }
    // Every name written must be an IEC identifier and the generated ones new.
    let mut used: BTreeSet<String> = BTreeSet::new();
    collect_names(program, &w, &mut used);
    for n in &used {
        if !is_iec_identifier(n) {
            w.problem(format!("`{n}` is not an IEC 61131-3 identifier"));
        }
    }
    let extras: Vec<String> = w
        .pre
        .iter()
        .map(|v| format!("{v}_PRE"))
        .chain(w.mirrors.iter().map(|s| format!("{s}_X")))
        .collect();
    for extra in extras {
        if w.roles.contains_key(&extra) {
            w.problem(format!(
                "`{extra}` is needed for the export and already names something in the program"
            ));
        }
    }
    if !w.problems.is_empty() {
        return Err(w.problems);
    }
    Ok(write_project(&w, &pou, &conditions, &rungs, &used))
}

fn ident(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    while s.contains("__") {
        s = s.replace("__", "_");
    }
    let s = s.trim_matches('_').to_string();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        format!("P_{s}")
    } else {
        s
    }
}

/// Every signal, memory and button the program names (plant signals only when used).
fn collect_names(program: &Program, w: &Writer<'_>, used: &mut BTreeSet<String>) {
    let mut texts: Vec<&str> = program
        .transitions()
        .map(|(_, t)| t.condition.as_str())
        .collect();
    texts.extend(program.equations.iter().map(|e| e.1.as_str()));
    texts.extend(program.counters.iter().map(|c| c.reset.as_str()));
    for t in texts {
        if let Ok(e) = expr::parse_str(t) {
            for (name, _, _) in e.leaves() {
                used.insert(name.to_string());
            }
        }
    }
    for (_, s) in program.steps() {
        used.insert(s.id.clone());
        for a in &s.actions {
            used.insert(a.target.clone());
        }
    }
    for (t, _) in &program.equations {
        used.insert(t.clone());
    }
    used.extend(program.panel.iter().cloned());
    used.extend(program.memories.iter().cloned());
    used.extend(
        program
            .charts
            .iter()
            .flat_map(|c| c.transitions.iter().map(|t| t.id.clone())),
    );
    // Timers are written as step times, not declared.
    used.retain(|n| w.roles.get(n) != Some(&Role::Timer));
}

fn address(plant: &Plant, name: &str) -> Option<String> {
    let s = plant
        .inputs
        .iter()
        .chain(&plant.outputs)
        .find(|s| s.id == name)?;
    match s.address? {
        Address::DiscreteInput(a) => Some(format!("%IX{}.{}", a / 8, a % 8)),
        Address::Coil(a) => Some(format!("%QX{}.{}", a / 8, a % 8)),
        _ => None,
    }
}

fn var(out: &mut String, indent: &str, name: &str, addr: Option<String>) {
    typed_var(out, indent, name, addr, "<BOOL/>");
}

fn typed_var(out: &mut String, indent: &str, name: &str, addr: Option<String>, ty: &str) {
    let addr = addr
        .map(|a| format!(" address=\"{a}\""))
        .unwrap_or_default();
    let _ = writeln!(
        out,
        "{indent}<variable name=\"{}\"{addr}><type>{ty}</type></variable>",
        esc(name)
    );
}

fn write_project(
    w: &Writer<'_>,
    pou: &str,
    conditions: &[(String, String)],
    rungs: &[String],
    used: &BTreeSet<String>,
) -> String {
    let p = w.program;
    let mut out = String::new();
    let _ = writeln!(out, "<?xml version=\"1.0\" encoding=\"utf-8\"?>");
    let _ = writeln!(
        out,
        "<project xmlns=\"{NAMESPACE}\" xmlns:xhtml=\"http://www.w3.org/1999/xhtml\">"
    );
    let _ = writeln!(
        out,
        "  <fileHeader companyName=\"Vigie\" productName=\"Vigie\" productVersion=\"{}\" creationDateTime=\"1970-01-01T00:00:00\"/>",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(out, "  <contentHeader name=\"{}\">", esc(&p.name));
    out.push_str("    <coordinateInfo>\n      <fbd><scaling x=\"10\" y=\"10\"/></fbd>\n      <ld><scaling x=\"10\" y=\"10\"/></ld>\n      <sfc><scaling x=\"10\" y=\"10\"/></sfc>\n    </coordinateInfo>\n  </contentHeader>\n");
    out.push_str("  <types>\n    <dataTypes/>\n    <pous>\n");
    write_sfc_pou(&mut out, w, pou, conditions);
    if !rungs.is_empty() {
        write_rungs_pou(&mut out, w, pou, rungs, used);
    }
    out.push_str("    </pous>\n  </types>\n");
    out.push_str("  <instances>\n    <configurations>\n      <configuration name=\"Config0\">\n        <resource name=\"Res0\">\n          <task name=\"Main\" interval=\"T#10ms\" priority=\"0\">\n");
    let _ = writeln!(
        out,
        "            <pouInstance name=\"i_{pou}\" typeName=\"{pou}\"/>"
    );
    if !rungs.is_empty() {
        let _ = writeln!(
            out,
            "            <pouInstance name=\"i_{pou}_rungs\" typeName=\"{pou}_rungs\"/>"
        );
    }
    out.push_str("          </task>\n        </resource>\n        <globalVars>\n");
    for g in globals(w, used) {
        let a = address(w.plant, &g);
        if w.program.initial.contains(&g) {
            let a = a.map(|a| format!(" address=\"{a}\"")).unwrap_or_default();
            let _ = writeln!(
                out,
                "          <variable name=\"{}\"{a}><type><BOOL/></type><initialValue><simpleValue value=\"TRUE\"/></initialValue></variable>",
                esc(&g)
            );
            continue;
        }
        typed_var(&mut out, "          ", &g, a, type_xml(w, &g));
    }
    out.push_str(
        "        </globalVars>\n      </configuration>\n    </configurations>\n  </instances>\n",
    );
    // Vigie's block.
    out.push_str("  <addData>\n");
    let _ = writeln!(
        out,
        "    <data name=\"{ADD_DATA}\" handleUnknown=\"preserve\">"
    );
    let attr = |k: &str, v: &Option<String>| {
        v.as_ref()
            .map(|v| format!(" {k}=\"{}\"", esc(v)))
            .unwrap_or_default()
    };
    let _ = writeln!(
        out,
        "      <program xmlns=\"{ADD_DATA}\"{}{} description=\"{}\">",
        attr("start", &p.start),
        attr("stop", &p.stop),
        esc(&p.description)
    );
    for c in &p.charts {
        let steps: Vec<&str> = c.steps.iter().map(|s| s.id.as_str()).collect();
        let _ = writeln!(
            out,
            "        <chart name=\"{}\" steps=\"{}\"/>",
            esc(&c.name),
            steps.join(" ")
        );
    }
    out.push_str("      </program>\n    </data>\n  </addData>\n</project>\n");
    out
}

/// The ST POU of the equations, run after the chart.
fn write_rungs_pou(
    out: &mut String,
    w: &Writer<'_>,
    pou: &str,
    rungs: &[String],
    used: &BTreeSet<String>,
) {
    let p = w.program;
    let _ = writeln!(out, "      <pou name=\"{pou}_rungs\" pouType=\"program\">");
    out.push_str("        <interface>\n");
    let panel: Vec<&String> = p
        .panel
        .iter()
        .filter(|b| rungs.iter().any(|r| mentions(r, b)))
        .collect();
    if !panel.is_empty() {
        out.push_str("          <inputVars>\n");
        for b in panel {
            var(out, "            ", b, None);
        }
        out.push_str("          </inputVars>\n");
    }
    out.push_str("          <externalVars>\n");
    for g in globals(w, used) {
        if rungs.iter().any(|r| mentions(r, &g)) {
            typed_var(out, "            ", &g, None, type_xml(w, &g));
        }
    }
    out.push_str("          </externalVars>\n        </interface>\n");
    out.push_str("        <body>\n          <ST>\n            <xhtml:p><![CDATA[");
    for r in rungs {
        out.push('\n');
        out.push_str(r);
    }
    out.push_str("\n]]></xhtml:p>\n          </ST>\n        </body>\n      </pou>\n");
}

/// True when `text` names `name` as a whole word.
fn mentions(text: &str, name: &str) -> bool {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .any(|w| w == name)
}

/// The global variables: plant signals used, memories, then the generated ones.
fn globals(w: &Writer<'_>, used: &BTreeSet<String>) -> Vec<String> {
    let p = w.program;
    let mut out: Vec<String> = Vec::new();
    for s in w.plant.inputs.iter().chain(&w.plant.outputs) {
        if used.contains(&s.id) {
            out.push(s.id.clone());
        }
    }
    out.extend(p.memories.iter().cloned());
    out.extend(p.delays.iter().map(|d| d.id.clone()));
    out.extend(p.counters.iter().map(|c| c.id.clone()));
    out.extend(w.pre.iter().map(|v| format!("{v}_PRE")));
    out.extend(w.mirrors.iter().map(|s| format!("{s}_X")));
    out
}

/// The PLCopen type of a global.
fn type_xml(w: &Writer<'_>, name: &str) -> &'static str {
    match w
        .program
        .delays
        .iter()
        .find(|d| d.id == name)
        .map(|d| d.kind)
    {
        Some(crate::control::DelayKind::On) => "<derived name=\"TON\"/>",
        Some(crate::control::DelayKind::Off) => "<derived name=\"TOF\"/>",
        Some(crate::control::DelayKind::Pulse) => "<derived name=\"TP\"/>",
        None => match w
            .program
            .counters
            .iter()
            .find(|c| c.id == name)
            .map(|c| c.kind)
        {
            Some(crate::control::CounterKind::Up) => "<derived name=\"CTU\"/>",
            Some(crate::control::CounterKind::Down) => "<derived name=\"CTD\"/>",
            None => "<BOOL/>",
        },
    }
}

/// The SFC POU: steps, actions, transitions, divergences and convergences.
fn write_sfc_pou(out: &mut String, w: &Writer<'_>, pou: &str, conditions: &[(String, String)]) {
    let p = w.program;
    let _ = writeln!(out, "      <pou name=\"{pou}\" pouType=\"program\">");
    out.push_str("        <interface>\n");
    if !p.panel.is_empty() {
        out.push_str("          <inputVars>\n");
        for b in &p.panel {
            var(out, "            ", b, None);
        }
        out.push_str("          </inputVars>\n");
    }
    let mut sfc_names: Vec<&str> = Vec::new();
    for (_, c) in conditions {
        for word in c.split(|ch: char| !(ch.is_ascii_alphanumeric() || ch == '_')) {
            sfc_names.push(word);
        }
    }
    for (_, s) in p.steps() {
        for a in &s.actions {
            sfc_names.push(&a.target);
        }
    }
    let mut ext: Vec<String> = Vec::new();
    for g in globals(w, &BTreeSet::new()).into_iter().chain(
        w.plant
            .inputs
            .iter()
            .chain(&w.plant.outputs)
            .map(|s| s.id.clone()),
    ) {
        let is_mirror = w.mirrors.iter().any(|s| format!("{s}_X") == g);
        if (sfc_names.contains(&g.as_str()) || is_mirror)
            && !ext.contains(&g)
            && !p.panel.contains(&g)
        {
            ext.push(g);
        }
    }
    if !ext.is_empty() {
        out.push_str("          <externalVars>\n");
        for g in &ext {
            typed_var(out, "            ", g, None, type_xml(w, g));
        }
        out.push_str("          </externalVars>\n");
    }
    out.push_str("        </interface>\n");
    if !conditions.is_empty() {
        out.push_str("        <transitions>\n");
        for (id, c) in conditions {
            let _ = writeln!(
                out,
                "          <transition name=\"{id}\"><body><ST><xhtml:p><![CDATA[{c}]]></xhtml:p></ST></body></transition>"
            );
        }
        out.push_str("        </transitions>\n");
    }
    out.push_str("        <body>\n          <SFC>\n");
    write_graph(out, w);
    out.push_str("          </SFC>\n        </body>\n      </pou>\n");
}

/// Element ids and connections of the SFC graph.
struct Graph<'p> {
    steps: Vec<&'p crate::control::Step>,
    trans: Vec<&'p crate::control::Transition>,
    step_id: BTreeMap<&'p str, u64>,
    trans_id: Vec<u64>,
    sel_div: BTreeMap<&'p str, u64>,
    sel_conv: BTreeMap<&'p str, u64>,
    sim_conv: BTreeMap<usize, u64>,
    sim_div: BTreeMap<usize, u64>,
    next: u64,
    y: u64,
}

impl<'p> Graph<'p> {
    fn new(p: &'p Program) -> Self {
        let steps: Vec<&crate::control::Step> = p.steps().map(|(_, s)| s).collect();
        let trans: Vec<&crate::control::Transition> = p.transitions().map(|(_, t)| t).collect();
        let mut g = Self {
            steps,
            trans,
            step_id: BTreeMap::new(),
            trans_id: Vec::new(),
            sel_div: BTreeMap::new(),
            sel_conv: BTreeMap::new(),
            sim_conv: BTreeMap::new(),
            sim_div: BTreeMap::new(),
            next: 1,
            y: 0,
        };
        let steps = g.steps.clone();
        for s in &steps {
            let i = g.id();
            g.step_id.insert(s.id.as_str(), i);
        }
        for _ in 0..g.trans.len() {
            let i = g.id();
            g.trans_id.push(i);
        }
        for s in &steps {
            if g.outgoing(&s.id) > 1 {
                let i = g.id();
                g.sel_div.insert(s.id.as_str(), i);
            }
            if g.incoming(&s.id).len() > 1 {
                let i = g.id();
                g.sel_conv.insert(s.id.as_str(), i);
            }
        }
        for k in 0..g.trans.len() {
            if g.trans[k].from.len() > 1 {
                let i = g.id();
                g.sim_conv.insert(k, i);
            }
            if g.trans[k].to.len() > 1 {
                let i = g.id();
                g.sim_div.insert(k, i);
            }
        }
        g
    }

    fn id(&mut self) -> u64 {
        let i = self.next;
        self.next += 1;
        i
    }

    fn outgoing(&self, s: &str) -> usize {
        self.trans
            .iter()
            .filter(|t| t.from.iter().any(|f| f == s))
            .count()
    }

    /// The transitions leading to step `s`.
    fn incoming(&self, s: &str) -> Vec<usize> {
        (0..self.trans.len())
            .filter(|&i| self.trans[i].to.iter().any(|f| f == s))
            .collect()
    }

    /// What a transition leaving step `s` connects to.
    fn source_of_step(&self, s: &str) -> u64 {
        self.sel_div
            .get(s)
            .copied()
            .unwrap_or_else(|| self.step_id.get(s).copied().unwrap_or(0))
    }

    /// What the steps after transition `i` connect to.
    fn out_of_trans(&self, i: usize) -> u64 {
        self.sim_div.get(&i).copied().unwrap_or(self.trans_id[i])
    }

    fn pos(&mut self, out: &mut String, x: u64) {
        self.y += 60;
        let _ = writeln!(out, "              <position x=\"{x}\" y=\"{}\"/>", self.y);
    }
}

fn conn(out: &mut String, refs: &[u64]) {
    out.push_str("              <connectionPointIn>");
    for r in refs {
        let _ = write!(out, "<connection refLocalId=\"{r}\"/>");
    }
    out.push_str("</connectionPointIn>\n");
}

/// The SFC graph, in program order: each step, its convergence and divergence, its
/// action block, then the transitions whose first source it is.
fn write_graph(out: &mut String, w: &Writer<'_>) {
    let p = w.program;
    let mut g = Graph::new(p);
    let chart_of = |s: &str| {
        p.charts
            .iter()
            .position(|c| c.steps.iter().any(|x| x.id == s))
            .unwrap_or(0) as u64
    };
    let steps = g.steps.clone();
    for s in steps {
        let x = 40 + 300 * chart_of(&s.id);
        write_step(out, &mut g, s, x);
        write_actions(out, w, &mut g, s, x);
        for i in 0..g.trans.len() {
            if g.trans[i].from.first() == Some(&s.id) {
                write_transition(out, &mut g, i, x);
            }
        }
    }
}

fn write_step(out: &mut String, g: &mut Graph<'_>, s: &crate::control::Step, x: u64) {
    let sid = g.step_id[s.id.as_str()];
    let _ = writeln!(
        out,
        "            <step localId=\"{sid}\" name=\"{}\" initialStep=\"{}\" height=\"30\" width=\"60\">",
        s.id, s.initial
    );
    g.pos(out, x);
    let ins: Vec<u64> = match g.sel_conv.get(s.id.as_str()) {
        Some(&c) => vec![c],
        None => g
            .incoming(&s.id)
            .into_iter()
            .map(|i| g.out_of_trans(i))
            .collect(),
    };
    if !ins.is_empty() {
        conn(out, &ins);
    }
    out.push_str("              <connectionPointOut formalParameter=\"\"/>\n");
    if !s.actions.is_empty() {
        out.push_str("              <connectionPointOutAction formalParameter=\"\"/>\n");
    }
    out.push_str("            </step>\n");
    if let Some(&c) = g.sel_conv.get(s.id.as_str()) {
        let _ = writeln!(
            out,
            "            <selectionConvergence localId=\"{c}\" height=\"1\" width=\"60\">"
        );
        g.pos(out, x);
        for i in g.incoming(&s.id) {
            conn(out, &[g.out_of_trans(i)]);
        }
        out.push_str("              <connectionPointOut/>\n            </selectionConvergence>\n");
    }
    if let Some(&d) = g.sel_div.get(s.id.as_str()) {
        let _ = writeln!(
            out,
            "            <selectionDivergence localId=\"{d}\" height=\"1\" width=\"60\">"
        );
        g.pos(out, x);
        conn(out, &[sid]);
        for _ in 0..g.outgoing(&s.id) {
            out.push_str("              <connectionPointOut formalParameter=\"\"/>\n");
        }
        out.push_str("            </selectionDivergence>\n");
    }
}

fn write_actions(
    out: &mut String,
    w: &Writer<'_>,
    g: &mut Graph<'_>,
    s: &crate::control::Step,
    x: u64,
) {
    let mirror = w.mirrors.contains(&s.id);
    if s.actions.is_empty() && !mirror {
        return;
    }
    let sid = g.step_id[s.id.as_str()];
    let bid = g.id();
    let _ = writeln!(
        out,
        "            <actionBlock localId=\"{bid}\" height=\"30\" width=\"100\">"
    );
    g.pos(out, x + 100);
    conn(out, &[sid]);
    for a in &s.actions {
        let (q, d) = match a.qualifier {
            Qualifier::L(ms) => ("L", Some(ms)),
            Qualifier::D(ms) => ("D", Some(ms)),
            Qualifier::N => ("N", None),
            Qualifier::S => ("S", None),
            Qualifier::R => ("R", None),
            Qualifier::P => ("P", None),
            Qualifier::SD(ms) => ("SD", Some(ms)),
            Qualifier::DS(ms) => ("DS", Some(ms)),
            Qualifier::SL(ms) => ("SL", Some(ms)),
        };
        let d = d
            .map(|ms| format!(" duration=\"{}\"", write_duration(ms)))
            .unwrap_or_default();
        let _ = writeln!(
            out,
            "              <action localId=\"0\" qualifier=\"{q}\"{d}><reference name=\"{}\"/></action>",
            a.target
        );
    }
    if mirror {
        let _ = writeln!(
            out,
            "              <action localId=\"0\" qualifier=\"N\"><reference name=\"{}_X\"/></action>",
            s.id
        );
    }
    out.push_str("            </actionBlock>\n");
}

fn write_transition(out: &mut String, g: &mut Graph<'_>, i: usize, x: u64) {
    let t = g.trans[i];
    if let Some(&c) = g.sim_conv.get(&i) {
        let _ = writeln!(
            out,
            "            <simultaneousConvergence localId=\"{c}\" height=\"3\" width=\"60\">"
        );
        g.pos(out, x);
        for f in &t.from {
            conn(out, &[g.source_of_step(f)]);
        }
        out.push_str(
            "              <connectionPointOut/>\n            </simultaneousConvergence>\n",
        );
    }
    let tin = g
        .sim_conv
        .get(&i)
        .copied()
        .unwrap_or_else(|| g.source_of_step(&t.from[0]));
    let _ = writeln!(
        out,
        "            <transition localId=\"{}\" height=\"2\" width=\"20\">",
        g.trans_id[i]
    );
    g.pos(out, x);
    conn(out, &[tin]);
    out.push_str("              <connectionPointOut/>\n");
    let _ = writeln!(
        out,
        "              <condition><reference name=\"{}\"/></condition>",
        t.id
    );
    out.push_str("            </transition>\n");
    if let Some(&d) = g.sim_div.get(&i) {
        let _ = writeln!(
            out,
            "            <simultaneousDivergence localId=\"{d}\" height=\"3\" width=\"60\">"
        );
        g.pos(out, x);
        conn(out, &[g.trans_id[i]]);
        for _ in &t.to {
            out.push_str("              <connectionPointOut formalParameter=\"\"/>\n");
        }
        out.push_str("            </simultaneousDivergence>\n");
    }
}
