//! IEC 61131-3 Structured Text export of the observers, the safety filter with its
//! fallback, and the task monitors.
//!
//! The generated program `Vigie_Safety` is meant to run **at the end of the PLC cycle**,
//! after the control program has written its commands (`CMD_*`), as the paper's
//! architecture places the filter. Per cycle it calls, in order:
//! 1. `FB_Observers` — the observers of `observers.ron` (memories and counters);
//! 2. `FB_Filter` — constraint evaluation on the commanded outputs, the trip latch and
//!    the fallback vector, decided as the engine decides it (see `crate::filter`): each
//!    output as close to its safe value as the active constraints allow. The search is
//!    exported, not its table, so it works at any size: every product term's context
//!    is evaluated (`FT_<n>`), unit terms force their output (`F0_<id>`, `F1_<id>`),
//!    and each output component (outputs linked by a term on several of them) tries
//!    its candidate vectors in the engine's order (fewest outputs away from their safe
//!    value `FS_<id>`, then lexicographic) as one `IF … ELSIF` chain; with no candidate,
//!    or two unit terms in conflict, every output takes its safe value;
//! 3. `FB_Tasks` — the task monitors, with each stopwatch stored as an offset variable
//!    (`T_<task>_DX`, `T_<task>_DY`) and the entry time of the current state
//!    (`T_<task>_SINCE`), as in the thesis's chapter 6: `x = δx + (NOW_MS − since)` while
//!    the clock runs, `x = δx` while it is frozen. Violations are checked before the
//!    cycle's events (strictly past the bounds) and after them (at the bounds), which
//!    gives the same decisions as the native monitor sampled at the cycle times;
//! 4. the shift of every value to its `_P` (value at t−1) copy.
//!
//! Names: inputs `I_<id>`, commanded outputs `CMD_<id>`, applied outputs `Q_<id>`,
//! observers `O_<id>`, auxiliaries `X_<id>` (`:` and other characters become `_`), and
//! `<name>_P` for the value at t−1. Time `NOW_MS` is a `LINT` in milliseconds supplied by
//! the caller (e.g. from the PLC's system clock).
//!
//! Not exported: controller windows and cross-task constraints of the coordinator, the
//! global latch variant, and unexpected-event warnings (warnings change no decision).

use crate::bundle::PlantBundle;
use crate::expr::{self, Dnf};
use crate::filter::Filter;
use crate::observers::Rule;
use crate::plausibility::ExportRule;
use crate::symbols::{Literal, Space, Symbols, Var};
use crate::tasks::TaskSet;
use crate::tasks::spec::{Slowdown, Unexpected};
use std::collections::BTreeSet;
use std::fmt::Write as _;

/// Largest output component (outputs linked by terms on several of them) whose search
/// is exported: its candidates are unrolled, 2^n of them.
pub const COMPONENT_LIMIT: usize = 10;

/// Why the Structured Text cannot be generated.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ExportError {
    /// An output component too large to unroll its search.
    #[error(
        "the outputs {} are linked by combined constraints into one component of {} outputs; its exported search would try 2^{} candidates (the limit is {COMPONENT_LIMIT} outputs): split the combined constraints",
        outputs.join(", "), outputs.len(), outputs.len()
    )]
    ComponentTooLarge {
        /// The component's outputs.
        outputs: Vec<String>,
    },
}

/// An identifier-safe rendering of a name.
pub fn mangle(name: &str) -> String {
    let mut out = String::new();
    for c in name.chars() {
        let c = if c.is_ascii_alphanumeric() { c } else { '_' };
        if !(c == '_' && out.ends_with('_')) {
            out.push(c);
        }
    }
    out.trim_end_matches('_').to_string()
}

/// The ST identifier of a variable. `filter` selects `CMD_` for outputs at t (the
/// commanded values the filter checks) instead of `Q_` (the applied values).
pub fn ident(symbols: &Symbols, var: Var, filter: bool) -> String {
    let name = mangle(symbols.name(var.space, var.index));
    let base = match var.space {
        Space::Input => format!("I_{name}"),
        Space::Output if filter && !var.prev => format!("CMD_{name}"),
        Space::Output => format!("Q_{name}"),
        Space::Observer => format!("O_{name}"),
        Space::Aux => format!("X_{name}"),
    };
    if var.prev { format!("{base}_P") } else { base }
}

fn render_lit(symbols: &Symbols, l: Literal, filter: bool, used: &mut BTreeSet<String>) -> String {
    let id = ident(symbols, l.var, filter);
    used.insert(id.clone());
    if l.positive { id } else { format!("NOT {id}") }
}

/// A sum of products as an ST expression; the identifiers read go into `used`.
pub fn render_dnf(
    symbols: &Symbols,
    dnf: &Dnf,
    filter: bool,
    used: &mut BTreeSet<String>,
) -> String {
    if dnf.is_empty() {
        return "FALSE".into();
    }
    let terms: Vec<String> = dnf
        .iter()
        .map(|t| {
            if t.is_empty() {
                "TRUE".to_string()
            } else {
                let lits: Vec<String> = t
                    .iter()
                    .map(|l| render_lit(symbols, *l, filter, used))
                    .collect();
                format!("({})", lits.join(" AND "))
            }
        })
        .collect();
    terms.join(" OR ")
}

struct Fb {
    name: String,
    inputs: BTreeSet<String>,
    extra_inputs: Vec<(String, &'static str)>,
    outputs: Vec<(String, &'static str)>,
    locals: Vec<(String, &'static str)>,
    body: String,
}

impl Fb {
    fn new(name: &str) -> Self {
        Self {
            name: name.into(),
            inputs: BTreeSet::new(),
            extra_inputs: Vec::new(),
            outputs: Vec::new(),
            locals: Vec::new(),
            body: String::new(),
        }
    }

    fn render(&self, out: &mut String, doc: &str) {
        let _ = writeln!(out, "(* {doc} *)");
        let _ = writeln!(out, "FUNCTION_BLOCK {}", self.name);
        section(
            out,
            "VAR_INPUT",
            self.inputs
                .iter()
                .map(|n| (n.clone(), "BOOL"))
                .chain(self.extra_inputs.iter().cloned()),
        );
        section(out, "VAR_OUTPUT", self.outputs.iter().cloned());
        section(out, "VAR", self.locals.iter().cloned());
        out.push_str(&self.body);
        let _ = writeln!(out, "END_FUNCTION_BLOCK\n");
    }

    fn call(&self, instance: &str) -> String {
        let args: Vec<String> = self
            .inputs
            .iter()
            .cloned()
            .chain(self.extra_inputs.iter().map(|(n, _)| n.clone()))
            .map(|n| format!("{n} := {n}"))
            .collect();
        format!("{instance}({});\n", args.join(", "))
    }
}

fn section(out: &mut String, kind: &str, vars: impl Iterator<Item = (String, &'static str)>) {
    let vars: Vec<_> = vars.collect();
    if vars.is_empty() {
        return;
    }
    let _ = writeln!(out, "{kind}");
    for (n, t) in vars {
        let _ = writeln!(out, "    {n} : {t};");
    }
    let _ = writeln!(out, "END_VAR");
}

/// The Structured Text of the bundle's observers and filter, and of the task monitors
/// when `tasks` is given (their event expressions are resolved against the bundle's
/// symbols; an expression that does not resolve is exported as `FALSE` with a comment).
pub fn generate(bundle: &PlantBundle, tasks: Option<&TaskSet>) -> Result<String, ExportError> {
    let symbols = &bundle.symbols;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "(* Generated by Vigie from {}: observers, safety filter with fallback, task monitors.\n   Call Vigie_Safety at the end of every PLC cycle, after the control program. *)\n",
        bundle.dir.display()
    );

    let obs = observers_fb(bundle);
    let fil = filter_fb(bundle)?;

    // Tasks.
    let tfb = tasks.map(|set| task_fb(set, symbols));

    obs.render(&mut out, "Observers (seed 004, section 6.2).");
    fil.render(
        &mut out,
        "Safety filter: constraints on the commanded outputs, latch, fallback.",
    );
    if let Some(t) = &tfb {
        t.render(
            &mut out,
            "Task monitors (seed 000): two stopwatches per task as offset variables.",
        );
    }

    // Program.
    program(&mut out, bundle, &obs, &fil, tfb.as_ref());
    Ok(out)
}

/// The observers' function block.
fn observers_fb(bundle: &PlantBundle) -> Fb {
    let symbols = &bundle.symbols;
    let mut obs = Fb::new("FB_Observers");
    for (i, def) in bundle.observers.defs.iter().enumerate() {
        let o = ident(
            symbols,
            Var {
                space: Space::Observer,
                index: u32::try_from(i).unwrap_or(0),
                prev: false,
            },
            false,
        );
        let dnf = |text: &str, used: &mut BTreeSet<String>| match expr::parse_str(text)
            .and_then(|e| e.to_dnf(symbols))
        {
            Ok(d) => render_dnf(symbols, &expr::simplify(&d), false, used),
            Err(_) => "FALSE (* unresolved *)".into(),
        };
        let _ = writeln!(
            obs.body,
            "(* {}: {} *)",
            def.id,
            def.description.replace("*)", "* )")
        );
        match &def.rule {
            Rule::Memory { set, reset } => {
                let m = format!("M_{}", &o[2..]);
                let s = dnf(set, &mut obs.inputs);
                let r = dnf(reset, &mut obs.inputs);
                let _ = writeln!(
                    obs.body,
                    "IF {s} THEN\n    {m} := TRUE;\nELSIF {r} THEN\n    {m} := FALSE;\nEND_IF;\n{o} := {m};"
                );
                obs.locals.push((m, "BOOL"));
            }
            Rule::Counter {
                up,
                down,
                clear,
                at_least,
            } => {
                let c = format!("CNT_{}", &o[2..]);
                let u = dnf(up, &mut obs.inputs);
                let d = dnf(down, &mut obs.inputs);
                let cl = clear
                    .as_deref()
                    .map_or_else(|| "FALSE".to_string(), |t| dnf(t, &mut obs.inputs));
                let _ = writeln!(
                    obs.body,
                    "IF {cl} THEN\n    {c} := 0;\nELSE\n    IF {u} THEN\n        IF {c} < 1000 THEN\n            {c} := {c} + 1;\n        END_IF;\n    END_IF;\n    IF ({d}) AND {c} > 0 THEN\n        {c} := {c} - 1;\n    END_IF;\nEND_IF;\n{o} := {c} >= {at_least};"
                );
                obs.locals.push((c, "DINT"));
            }
        }
        obs.outputs.push((o, "BOOL"));
    }

    obs
}

/// The safety filter's function block: violations, latch and fallback.
fn filter_fb(bundle: &PlantBundle) -> Result<Fb, ExportError> {
    let symbols = &bundle.symbols;
    let n_out = bundle.plant.outputs.len();
    let filter = Filter::for_plant(&bundle.constraints, &bundle.plant);
    let mut fil = Fb::new("FB_Filter");
    let mut viol = Vec::new();
    for c in &bundle.constraints.constraints {
        let v = format!("V_{}", mangle(&c.id));
        let e = render_dnf(symbols, &c.dnf, true, &mut fil.inputs);
        let _ = writeln!(
            fil.body,
            "(* {} = {} *)\n{v} := {e};",
            c.id,
            c.source.replace("*)", "* )")
        );
        fil.outputs.push((v.clone(), "BOOL"));
        viol.push(v);
    }
    for k in 0..n_out {
        fil.inputs
            .insert(ident(symbols, output_var(k, false), true));
    }
    let any = if viol.is_empty() {
        "FALSE".to_string()
    } else {
        viol.join(" OR ")
    };
    let _ = writeln!(
        fil.body,
        "VIOLATION := {any};\nIF VIOLATION AND NOT LATCHED THEN\n    LATCHED := TRUE;\nEND_IF;\nIF LATCHED THEN\n    (* Fallback: each output as close to its safe value as the constraints allow. *)"
    );
    fallback_search(&filter, symbols, &mut fil)?;
    let _ = writeln!(fil.body, "ELSE");
    for k in 0..n_out {
        let v = output_var(k, false);
        let _ = writeln!(
            fil.body,
            "    {} := {};",
            ident(symbols, v, false),
            ident(symbols, v, true)
        );
    }
    let _ = writeln!(fil.body, "END_IF;\nTRIPPED := LATCHED;");
    for k in 0..n_out {
        let v = output_var(k, false);
        fil.outputs.push((ident(symbols, v, false), "BOOL"));
    }
    fil.outputs.push(("VIOLATION".into(), "BOOL"));
    fil.outputs.push(("TRIPPED".into(), "BOOL"));
    fil.locals.push(("LATCHED".into(), "BOOL"));

    Ok(fil)
}

/// The program `Vigie_Safety`: its variables, the plausibility stage, the calls of the
/// function blocks and the values at t-1.
fn program(out: &mut String, bundle: &PlantBundle, obs: &Fb, fil: &Fb, tfb: Option<&Fb>) {
    let symbols = &bundle.symbols;
    let n_out = bundle.plant.outputs.len();
    let mut all_vars: Vec<Var> = Vec::new();
    for space in Space::ALL {
        for i in 0..symbols.len(space) {
            for prev in [false, true] {
                all_vars.push(Var {
                    space,
                    index: u32::try_from(i).unwrap_or(0),
                    prev,
                });
            }
        }
    }
    let rules = bundle.plausibility.export_rules();
    program_interface(out, symbols, &rules, n_out, tfb);
    let mut locals: Vec<(String, &'static str)> = all_vars
        .iter()
        .filter(|v| v.prev)
        .map(|v| (ident(symbols, *v, false), "BOOL"))
        .collect();
    let (stage, mut stage_locals) = plausibility_stage(symbols, &rules);
    locals.append(&mut stage_locals);
    let (mirror_stage, mut mirror_locals) = mirror_stage(bundle);
    locals.append(&mut mirror_locals);
    locals.push(("fbObservers".into(), "FB_Observers"));
    locals.push(("fbFilter".into(), "FB_Filter"));
    if tfb.is_some() {
        locals.push(("fbTasks".into(), "FB_Tasks"));
    }
    section(out, "VAR", locals.into_iter());
    out.push_str(&stage);
    out.push_str(&mirror_stage);
    out.push_str(&obs.call("fbObservers"));
    for (n, _) in &obs.outputs {
        let _ = writeln!(out, "{n} := fbObservers.{n};");
    }
    for (k, o) in bundle.plant.outputs.iter().enumerate() {
        if o.held_on {
            let cmd = ident(symbols, output_var(k, false), true);
            let _ = writeln!(
                out,
                "{cmd} := TRUE; (* held ON by the safety function: only the fallback releases it *)"
            );
        }
    }
    out.push_str(&fil.call("fbFilter"));
    for k in 0..n_out {
        let q = ident(symbols, output_var(k, false), false);
        let _ = writeln!(out, "{q} := fbFilter.{q};");
    }
    let _ = writeln!(out, "TRIPPED := fbFilter.TRIPPED;");
    if let Some(t) = tfb {
        out.push_str(&t.call("fbTasks"));
        for (n, _) in &t.outputs {
            let _ = writeln!(out, "{n} := fbTasks.{n};");
        }
    }
    let _ = writeln!(out, "(* Values at t-1 for the next cycle. *)");
    for v in all_vars.iter().filter(|v| v.prev) {
        let now = Var { prev: false, ..*v };
        let _ = writeln!(
            out,
            "{} := {};",
            ident(symbols, *v, false),
            ident(symbols, now, false)
        );
    }
    let _ = writeln!(out, "END_PROGRAM");
}

/// The mirror contacts with a `feedback_ms`: a disagreement with the output applied at
/// t-1 that has lasted less is read as agreement, as the engine reads it
/// (`Engine::hold_mirrors`). The code and its locals (`MH_<id>` since when, `MD_<id>`
/// disagreeing).
fn mirror_stage(bundle: &PlantBundle) -> (String, Vec<(String, &'static str)>) {
    let symbols = &bundle.symbols;
    let mut code = String::new();
    let mut locals = Vec::new();
    for (i, o) in bundle.plant.mirrors() {
        let ms = bundle.plant.inputs[i].feedback_ms;
        if ms == 0 {
            continue;
        }
        let input = Var {
            space: Space::Input,
            index: u32::try_from(i).unwrap_or(0),
            prev: false,
        };
        let input = ident(symbols, input, false);
        let applied = ident(symbols, output_var(o, true), false);
        let id = mangle(&bundle.plant.inputs[i].id);
        let (since, on) = (format!("MH_{id}"), format!("MD_{id}"));
        let _ = writeln!(
            code,
            "(* {input} follows its output within {ms} ms: a shorter disagreement reads as agreement. *)
             IF {input} <> {applied} THEN
    IF NOT {on} THEN
        {on} := TRUE;
        {since} := NOW_MS;
    END_IF;
    IF NOW_MS - {since} < {ms} THEN
        {input} := {applied};
    END_IF;
ELSE
    {on} := FALSE;
END_IF;"
        );
        locals.push((since, "LINT"));
        locals.push((on, "BOOL"));
    }
    (code, locals)
}

/// The program's header and its input and output variables.
fn program_interface(
    out: &mut String,
    symbols: &Symbols,
    rules: &[ExportRule<'_>],
    n_out: usize,
    tfb: Option<&Fb>,
) {
    let _ = writeln!(
        out,
        "(* One call per PLC cycle, after the control program. *)\nPROGRAM Vigie_Safety"
    );
    let mut inputs: Vec<(String, &'static str)> = vec![("NOW_MS".into(), "LINT")];
    for i in 0..symbols.len(Space::Input) {
        inputs.push((input_name(symbols, rules, i), "BOOL"));
    }
    for k in 0..n_out {
        inputs.push((ident(symbols, output_var(k, false), true), "BOOL"));
    }
    section(out, "VAR_INPUT", inputs.into_iter());
    let mut outputs: Vec<(String, &'static str)> = Vec::new();
    for k in 0..n_out {
        outputs.push((ident(symbols, output_var(k, false), false), "BOOL"));
    }
    outputs.push(("TRIPPED".into(), "BOOL"));
    for space in [Space::Observer, Space::Aux] {
        for i in 0..symbols.len(space) {
            outputs.push((
                ident(
                    symbols,
                    Var {
                        space,
                        index: u32::try_from(i).unwrap_or(0),
                        prev: false,
                    },
                    false,
                ),
                "BOOL",
            ));
        }
    }
    if let Some(t) = tfb {
        for (n, ty) in &t.outputs {
            if !outputs.iter().any(|(o, _)| o == n) {
                outputs.push((n.clone(), ty));
            }
        }
    }
    section(out, "VAR_OUTPUT", outputs.iter().cloned());
}

/// The name of input `i` in the program's `VAR_INPUT`: its identifier, or, for a sensor
/// with a plausibility rule, the identifier with `_RAW` (the identifier itself is then
/// the accepted value the stage computes).
pub fn input_name(symbols: &Symbols, rules: &[ExportRule<'_>], i: usize) -> String {
    let id = ident(
        symbols,
        Var {
            space: Space::Input,
            index: u32::try_from(i).unwrap_or(0),
            prev: false,
        },
        false,
    );
    if rules.iter().any(|r| r.input == i) {
        format!("{id}_RAW")
    } else {
        id
    }
}

/// The plausibility stage of [`crate::plausibility`] in ST, run first in the program:
/// every rule decides on the readings (`…_RAW`) and writes the accepted value and its
/// `sus_` flag. Returns the statements and the locals they need.
fn plausibility_stage(
    symbols: &Symbols,
    rules: &[ExportRule<'_>],
) -> (String, Vec<(String, &'static str)>) {
    let mut out = String::new();
    let locals: Vec<(String, &'static str)> = Vec::new();
    if rules.is_empty() {
        return (out, locals);
    }
    let _ = writeln!(
        out,
        "(* Plausibility of the sensors (plant.ron, `plausible`): an edge the physics does not allow is held. *)"
    );
    let mut parts = StageParts {
        first: String::new(),
        track: String::new(),
        body: String::new(),
        locals,
    };
    for r in rules {
        stage_rule(symbols, rules, r, &mut parts);
    }
    let StageParts {
        first,
        track,
        body,
        mut locals,
    } = parts;
    let _ = write!(
        out,
        "IF NOT PL_STARTED THEN
{first}    PL_LAST := NOW_MS;
END_IF;
{track}IF PL_STARTED THEN
{body}END_IF;
PL_STARTED := TRUE;
PL_LAST := NOW_MS;
"
    );
    locals.push(("PL_LAST".into(), "LINT"));
    locals.push(("PL_STARTED".into(), "BOOL"));
    locals.push(("PL_OK".into(), "BOOL"));
    locals.push(("PL_W".into(), "BOOL"));
    locals.push(("PL_CF".into(), "BOOL"));
    (out, locals)
}

/// The plausibility stage's text and locals, as they are built rule by rule.
struct StageParts {
    first: String,
    track: String,
    body: String,
    locals: Vec<(String, &'static str)>,
}

/// One rule of the plausibility stage: its tracking, its decision and its locals.
fn stage_rule(
    symbols: &Symbols,
    rules: &[ExportRule<'_>],
    r: &ExportRule<'_>,
    parts: &mut StageParts,
) {
    let raw = input_name(symbols, rules, r.input);
    let acc = ident(
        symbols,
        Var {
            space: Space::Input,
            index: u32::try_from(r.input).unwrap_or(0),
            prev: false,
        },
        false,
    );
    let sus = ident(
        symbols,
        Var {
            space: Space::Aux,
            index: u32::try_from(r.aux).unwrap_or(0),
            prev: false,
        },
        false,
    );
    let k = mangle(symbols.name(Space::Input, u32::try_from(r.input).unwrap_or(0)));
    let k = &k;
    let (rise_timed, fall_timed, reset_totals) = stage_timing(symbols, rules, r, k, parts);
    let _ = writeln!(
        parts.first,
        "    {acc} := {raw};
    {sus} := FALSE;
    PL_{k}_K := FALSE;
    PL_{k}_PK := FALSE;"
    );
    // `hold_until_back`: an edge inside the window latches the hold until the
    // reading agrees again (PL_k_L).
    let (latch_ok, latch_set, latch_clear) = if r.hold_until_back {
        let _ = writeln!(parts.first, "    PL_{k}_L := FALSE;");
        parts.locals.push((format!("PL_{k}_L"), "BOOL"));
        (
            format!(" AND NOT PL_{k}_L"),
            format!(
                "
            IF NOT PL_W THEN
                PL_{k}_L := TRUE;
            END_IF;"
            ),
            format!(
                "
        PL_{k}_L := FALSE;"
            ),
        )
    } else {
        (String::new(), String::new(), String::new())
    };
    let _ = writeln!(
        parts.body,
        "    IF {raw} <> {acc} THEN
        IF {raw} THEN
            PL_W := {};
            PL_OK := PL_W AND ({}) AND ({rise_timed}){latch_ok};
            PL_CF := {};
        ELSE
            PL_W := {};
            PL_OK := PL_W AND ({}) AND ({fall_timed}){latch_ok};
            PL_CF := {};
        END_IF;
        IF NOT PL_OK THEN
            {sus} := TRUE;
            PL_{k}_PK := FALSE;{latch_set}
        ELSE
            {sus} := FALSE;
            IF NOT PL_{k}_PK THEN
                PL_{k}_PK := TRUE;
                PL_{k}_PS := NOW_MS;
            END_IF;
            IF PL_CF THEN
                {acc} := {raw};
                PL_{k}_T := NOW_MS;
                PL_{k}_K := TRUE;
                PL_{k}_PK := FALSE;{reset_totals}
            END_IF;
        END_IF;
    ELSE
        {sus} := FALSE;
        PL_{k}_PK := FALSE;{latch_clear}
    END_IF;",
        since(k, r.min_off_ms),
        stage_cond(symbols, rules, r.rise_when),
        confirm(k, r.rise_confirm_ms),
        since(k, r.min_on_ms),
        stage_cond(symbols, rules, r.fall_when),
        confirm(k, r.fall_confirm_ms),
    );
    parts.locals.push((acc, "BOOL"));
    for (n, t) in [("K", "BOOL"), ("T", "LINT"), ("PK", "BOOL"), ("PS", "LINT")] {
        parts.locals.push((format!("PL_{k}_{n}"), t));
    }
}

/// The timed conditions of a rule (held for a time, in total, after an event), tracked
/// every cycle: the extra tests of a rise and of a fall, and the totals' resets.
fn stage_timing(
    symbols: &Symbols,
    rules: &[ExportRule<'_>],
    r: &ExportRule<'_>,
    k: &str,
    parts: &mut StageParts,
) -> (String, String, String) {
    let cond = |d: Option<&Dnf>| stage_cond(symbols, rules, d);
    // A condition held for a time: tracked every cycle, before the decision.
    let mut timed = |edge: &str, d: Option<&Dnf>, ms: u64| -> String {
        if ms == 0 {
            return "TRUE".to_string();
        }
        let _ = writeln!(parts.first, "    PL_{k}_{edge}K := FALSE;");
        let _ = writeln!(
            parts.track,
            "IF {} THEN
    IF NOT PL_{k}_{edge}K THEN
        PL_{k}_{edge}K := TRUE;
        PL_{k}_{edge}S := NOW_MS;
    END_IF;
ELSE
    PL_{k}_{edge}K := FALSE;
END_IF;",
            cond(d)
        );
        parts.locals.push((format!("PL_{k}_{edge}K"), "BOOL"));
        parts.locals.push((format!("PL_{k}_{edge}S"), "LINT"));
        format!("PL_{k}_{edge}K AND NOW_MS - PL_{k}_{edge}S >= {ms}")
    };
    let mut rise_timed = timed("R", r.rise_when, r.rise_when_for_ms);
    let mut fall_timed = timed("F", r.fall_when, r.fall_when_for_ms);
    // A condition held for a time in all since the last accepted edge (PL_k_RA,
    // PL_k_FA: the time of every cycle where it held; unknown before the first
    // accepted edge, PL_k_K).
    let mut reset_totals = String::new();
    for (edge, d, ms, timed) in [
        ("RA", r.rise_when, r.rise_when_total_ms, &mut rise_timed),
        ("FA", r.fall_when, r.fall_when_total_ms, &mut fall_timed),
    ] {
        if ms == 0 {
            continue;
        }
        let _ = writeln!(parts.first, "    PL_{k}_{edge} := 0;");
        let _ = writeln!(
            parts.track,
            "IF {} THEN
    PL_{k}_{edge} := PL_{k}_{edge} + (NOW_MS - PL_LAST);
END_IF;",
            cond(d)
        );
        let _ = write!(
            reset_totals,
            "
                PL_{k}_{edge} := 0;"
        );
        parts.locals.push((format!("PL_{k}_{edge}"), "LINT"));
        *timed = format!("{timed} AND (NOT PL_{k}_K OR PL_{k}_{edge} >= {ms})");
    }
    // `rise_not_after`: the event's last cycle is tracked every cycle (PL_k_EK,
    // PL_k_ES); a rise is plausible only that long after it.
    if let Some((event, ms)) = r.rise_not_after {
        let _ = writeln!(parts.first, "    PL_{k}_EK := FALSE;");
        let _ = writeln!(
            parts.track,
            "IF {} THEN
    PL_{k}_EK := TRUE;
    PL_{k}_ES := NOW_MS;
END_IF;",
            cond(Some(event))
        );
        parts.locals.push((format!("PL_{k}_EK"), "BOOL"));
        parts.locals.push((format!("PL_{k}_ES"), "LINT"));
        rise_timed = format!("{rise_timed} AND (NOT PL_{k}_EK OR NOW_MS - PL_{k}_ES >= {ms})");
    }
    (rise_timed, fall_timed, reset_totals)
}

/// A plausibility condition in ST (`TRUE` when absent); current readings are the raw inputs.
fn stage_cond(symbols: &Symbols, rules: &[ExportRule<'_>], d: Option<&Dnf>) -> String {
    let Some(d) = d else {
        return "TRUE".into();
    };
    if d.is_empty() {
        return "FALSE".into();
    }
    d.iter()
        .map(|term| {
            if term.is_empty() {
                return "TRUE".to_string();
            }
            let lits: Vec<String> = term
                .iter()
                .map(|l| {
                    let raw = l.var.space == Space::Input && !l.var.prev;
                    let id = if raw {
                        input_name(symbols, rules, l.var.index as usize)
                    } else {
                        ident(symbols, l.var, false)
                    };
                    if l.positive { id } else { format!("NOT {id}") }
                })
                .collect();
            format!("({})", lits.join(" AND "))
        })
        .collect::<Vec<_>>()
        .join(" OR ")
}

/// The ST test that `w` ms have passed since the last accepted edge of `k`.
fn since(k: &str, w: u64) -> String {
    if w == 0 {
        "TRUE".to_string()
    } else {
        format!("(NOT PL_{k}_K OR NOW_MS - PL_{k}_T >= {w})")
    }
}

/// The ST test that the reading has been stable `c` ms (always true for 0).
fn confirm(k: &str, c: u64) -> String {
    if c == 0 {
        "TRUE".to_string()
    } else {
        format!("NOW_MS - PL_{k}_PS >= {c}")
    }
}

fn output_var(k: usize, prev: bool) -> Var {
    Var {
        space: Space::Output,
        index: u32::try_from(k).unwrap_or(0),
        prev,
    }
}

/// The fallback search of `filter` as statements of `fil` (inside `IF LATCHED`), see
/// the module documentation.
fn fallback_search(filter: &Filter, symbols: &Symbols, fil: &mut Fb) -> Result<(), ExportError> {
    let n_out = filter.n_outputs();
    let name = |k: usize| mangle(symbols.name(Space::Output, u32::try_from(k).unwrap_or(0)));
    let q = |k: usize| ident(symbols, output_var(k, false), false);
    let b = &mut fil.body;
    // Terms whose context holds.
    let terms: Vec<_> = filter
        .term_views()
        .filter(|t| !t.outputs.is_empty())
        .collect();
    for (i, t) in terms.iter().enumerate() {
        let ctx = if t.context.is_empty() {
            "TRUE".to_string()
        } else {
            t.context
                .iter()
                .map(|l| render_lit(symbols, *l, true, &mut fil.inputs))
                .collect::<Vec<_>>()
                .join(" AND ")
        };
        let _ = writeln!(b, "    FT_{i} := {ctx};");
        fil.locals.push((format!("FT_{i}"), "BOOL"));
    }
    // Safe values.
    for (k, safe) in filter.safe_values().iter().enumerate() {
        let v = match safe {
            crate::plant::SafeValue::Zero => "FALSE".to_string(),
            crate::plant::SafeValue::One => "TRUE".to_string(),
            crate::plant::SafeValue::Hold => {
                let id = ident(symbols, output_var(k, true), true);
                fil.inputs.insert(id.clone());
                id
            }
        };
        let _ = writeln!(b, "    FS_{} := {v};", name(k));
        fil.locals.push((format!("FS_{}", name(k)), "BOOL"));
    }
    // Unit terms force their output; two opposite ones conflict.
    let mut conflict = Vec::new();
    for k in 0..n_out {
        for (force, positive) in [("F0", true), ("F1", false)] {
            let by: Vec<String> = terms
                .iter()
                .enumerate()
                .filter(|(_, t)| t.outputs == [(u32::try_from(k).unwrap_or(0), positive)])
                .map(|(i, _)| format!("FT_{i}"))
                .collect();
            let e = if by.is_empty() {
                "FALSE".to_string()
            } else {
                by.join(" OR ")
            };
            let _ = writeln!(b, "    {force}_{} := {e};", name(k));
            fil.locals.push((format!("{force}_{}", name(k)), "BOOL"));
        }
        conflict.push(format!("(F0_{n} AND F1_{n})", n = name(k)));
    }
    let _ = writeln!(
        b,
        "    CONFLICT := {};",
        if conflict.is_empty() {
            "FALSE".to_string()
        } else {
            conflict.join(" OR ")
        }
    );
    fil.locals.push(("CONFLICT".into(), "BOOL"));
    for comp in filter.output_components() {
        let multi: Vec<(usize, &crate::filter::TermView<'_>)> = terms
            .iter()
            .enumerate()
            .filter(|(_, t)| t.outputs.len() > 1 && comp.contains(&(t.outputs[0].0 as usize)))
            .collect();
        if multi.is_empty() {
            for &k in &comp {
                let n = name(k);
                let _ = writeln!(b, "    {} := NOT F0_{n} AND (F1_{n} OR FS_{n});", q(k));
            }
            continue;
        }
        if comp.len() > COMPONENT_LIMIT {
            return Err(ExportError::ComponentTooLarge {
                outputs: comp
                    .iter()
                    .map(|&k| {
                        symbols
                            .name(Space::Output, u32::try_from(k).unwrap_or(0))
                            .to_string()
                    })
                    .collect(),
            });
        }
        component_candidates(symbols, &comp, &multi, b);
    }
    let _ = writeln!(
        b,
        "    IF CONFLICT THEN\n        (* No vector satisfies every constraint: the safe values. *)"
    );
    for k in 0..n_out {
        let _ = writeln!(b, "        {} := FS_{};", q(k), name(k));
    }
    let _ = writeln!(b, "    END_IF;");
    Ok(())
}

/// The candidates of a component of outputs bound by multi-output terms, fewest outputs
/// away from their safe value first; none fits: `CONFLICT`.
fn component_candidates(
    symbols: &Symbols,
    comp: &[usize],
    multi: &[(usize, &crate::filter::TermView<'_>)],
    b: &mut String,
) {
    let name = |k: usize| mangle(symbols.name(Space::Output, u32::try_from(k).unwrap_or(0)));
    let q = |k: usize| ident(symbols, output_var(k, false), false);
    let m = comp.len();
    // Candidates: d_j = 1 when output comp[j] is away from its safe value; fewest
    // away first, then lexicographic with comp[0] most significant, 0 first.
    let mut order: Vec<u32> = (0..(1u32 << m)).collect();
    order.sort_by_key(|&d| (d.count_ones(), d.reverse_bits() >> (32 - m)));
    let value = |j: usize, d: u32| {
        let n = name(comp[j]);
        if d >> j & 1 == 1 {
            format!("NOT FS_{n}")
        } else {
            format!("FS_{n}")
        }
    };
    let _ = writeln!(
        b,
        "    (* Outputs {}: {} candidates. *)",
        comp.iter().map(|&k| name(k)).collect::<Vec<_>>().join(", "),
        order.len()
    );
    for (c, &d) in order.iter().enumerate() {
        let mut ok = Vec::new();
        for (j, &k) in comp.iter().enumerate().take(m) {
            let n = name(k);
            // x = 1 against F0, x = 0 against F1.
            if d >> j & 1 == 1 {
                ok.push(format!(
                    "NOT (F0_{n} AND NOT FS_{n}) AND NOT (F1_{n} AND FS_{n})"
                ));
            } else {
                ok.push(format!(
                    "NOT (F0_{n} AND FS_{n}) AND NOT (F1_{n} AND NOT FS_{n})"
                ));
            }
        }
        for (i, t) in multi {
            let lits: Vec<String> = t
                .outputs
                .iter()
                .map(|&(k, positive)| {
                    let j = comp.iter().position(|&o| o == k as usize).unwrap_or(0);
                    let x = value(j, d);
                    if positive {
                        format!("({x})")
                    } else {
                        format!("NOT ({x})")
                    }
                })
                .collect();
            ok.push(format!("NOT (FT_{i} AND {})", lits.join(" AND ")));
        }
        let kw = if c == 0 { "IF" } else { "ELSIF" };
        let _ = writeln!(b, "    {kw} {} THEN", ok.join(" AND "));
        for (j, &k) in comp.iter().enumerate().take(m) {
            let _ = writeln!(b, "        {} := {};", q(k), value(j, d));
        }
    }
    let _ = writeln!(b, "    ELSE\n        CONFLICT := TRUE;\n    END_IF;");
}

fn task_fb(set: &TaskSet, symbols: &Symbols) -> Fb {
    let mut fb = Fb::new("FB_Tasks");
    fb.extra_inputs.push(("NOW_MS".into(), "LINT"));
    let ev = |text: &str, used: &mut BTreeSet<String>| match expr::parse_str(text)
        .and_then(|e| e.to_dnf(symbols))
    {
        Ok(d) => render_dnf(symbols, &expr::simplify(&d), false, used),
        Err(_) => "FALSE (* unresolved *)".into(),
    };
    let mut pre = String::new();
    let mut events = String::new();
    let mut post = String::new();
    for t in &set.tasks {
        let p = format!("T_{}", mangle(&t.id));
        let (st, x, y, dx, dy, since) = (
            format!("{p}_STATE"),
            format!("{p}_X"),
            format!("{p}_Y"),
            format!("{p}_DX"),
            format!("{p}_DY"),
            format!("{p}_SINCE"),
        );
        let clocks = format!(
            "IF {st} = 1 THEN\n    {x} := {dx} + (NOW_MS - {since});\n    {y} := {dy} + (NOW_MS - {since});\nELSIF {st} = 2 THEN\n    {x} := {dx} + (NOW_MS - {since});\n    {y} := {dy};\nELSE\n    {x} := {dx};\n    {y} := {dy};\nEND_IF;\n"
        );
        let freeze =
            format!("{dx} := {x};\n    {dy} := {y};\n    {since} := NOW_MS;\n    {st} := 4;");
        let (a, b, g) = (t.alpha, t.beta, t.gamma);
        let tol = g - a;
        // Violated strictly before NOW (pre) and at NOW (post).
        let mut pre_c = vec![format!("{x} > {g}")];
        let mut post_c = vec![format!("{x} >= {g}")];
        if t.interruptible() {
            pre_c.push(format!("{x} - {y} > {tol}"));
            post_c.push(format!("{x} - {y} >= {tol}"));
            if t.slowdown == Slowdown::Strict {
                pre_c.push(format!("{y} > {b}"));
                post_c.push(format!("{y} > {b}"));
            }
        }
        let _ = writeln!(
            pre,
            "(* {}: [α, β] = [{a}, {b}] ms, [α, γ) = [{a}, {g}) ms *)\n{clocks}IF ({st} = 1 OR {st} = 2) AND ({}) THEN\n    {freeze}\nEND_IF;",
            t.id,
            pre_c.join(" OR ")
        );
        let _ = writeln!(
            post,
            "{clocks}IF ({st} = 1 OR {st} = 2) AND ({}) THEN\n    {freeze}\nEND_IF;",
            post_c.join(" OR ")
        );
        let end = ev(&t.end, &mut fb.inputs);
        let start = ev(&t.start, &mut fb.inputs);
        let strict_unexpected = set.unexpected == Unexpected::Alarm;
        let y_max = if t.slowdown == Slowdown::Strict { b } else { g };
        let end_bad = if t.interruptible() {
            format!("{x} < {a} OR {y} < {a} OR {x} >= {g} OR {y} > {y_max}")
        } else {
            format!("{x} < {a} OR {x} >= {g}")
        };
        let check = if set.check_end {
            format!("\n        IF {end_bad} THEN\n            {st} := 4;\n        END_IF;")
        } else {
            String::new()
        };
        let unexpected_end = if strict_unexpected {
            format!("\n    ELSE\n        {freeze}")
        } else {
            String::new()
        };
        let unexpected_start = if strict_unexpected {
            format!("\n    ELSE\n        {freeze}")
        } else {
            String::new()
        };
        let _ = writeln!(
            events,
            "(* {} *)\nIF {st} <> 4 AND ({end}) THEN\n    IF {st} = 1 OR {st} = 2 THEN\n        {dx} := {x};\n        {dy} := {y};\n        {since} := NOW_MS;\n        {st} := 3;{check}{unexpected_end}\n    END_IF;\nEND_IF;\nIF {st} <> 4 AND ({start}) THEN\n    IF {st} = 0 OR {st} = 3 THEN\n        {dx} := 0;\n        {dy} := 0;\n        {x} := 0;\n        {y} := 0;\n        {since} := NOW_MS;\n        {st} := 1;{unexpected_start}\n    END_IF;\nEND_IF;",
            t.id
        );
        if let Some((int, res)) = &t.interruption {
            let i = ev(int, &mut fb.inputs);
            let r = ev(res, &mut fb.inputs);
            let _ = writeln!(
                events,
                "IF {st} = 1 AND ({i}) THEN\n    {dx} := {x};\n    {dy} := {y};\n    {since} := NOW_MS;\n    {st} := 2;\nELSIF {st} = 2 AND ({r}) THEN\n    {dx} := {x};\n    {dy} := {y};\n    {since} := NOW_MS;\n    {st} := 1;\nEND_IF;"
            );
        }
        fb.outputs.push((st, "INT"));
        fb.outputs.push((x, "LINT"));
        fb.outputs.push((y, "LINT"));
        fb.locals.push((dx, "LINT"));
        fb.locals.push((dy, "LINT"));
        fb.locals.push((since, "LINT"));
    }
    task_body(&mut fb, set, &pre, &events, &post);
    fb
}

/// The body of the task monitors: the three phases, then the auxiliary outputs.
fn task_body(fb: &mut Fb, set: &TaskSet, pre: &str, events: &str, post: &str) {
    fb.body
        .push_str("(* 1. Violations strictly before NOW_MS. *)\n");
    fb.body.push_str(pre);
    fb.body
        .push_str("(* 2. Events of this cycle: end, start, interrupt, resume. *)\n");
    fb.body.push_str(events);
    fb.body.push_str("(* 3. Violations at NOW_MS. *)\n");
    fb.body.push_str(post);
    // Auxiliary outputs for the safety filter.
    let aux: Vec<String> = set.aux_names();
    for (k, t) in set.tasks.iter().enumerate() {
        let st = format!("T_{}_STATE", mangle(&t.id));
        for (j, code) in [1, 2, 4].into_iter().enumerate() {
            let name = aux.get(3 * k + j).cloned().unwrap_or_default();
            let id = format!("X_{}", mangle(&name));
            let _ = writeln!(fb.body, "{id} := {st} = {code};");
            fb.outputs.push((id, "BOOL"));
        }
    }
    if set.unexpected == Unexpected::Warn || set.unexpected == Unexpected::Ignore {
        fb.body.push_str(
            "(* Unexpected events are warnings in the native monitor: no decision here. *)\n",
        );
    }
}
