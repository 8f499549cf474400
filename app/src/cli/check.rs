//! `vigie check`: validate a plant folder.

use std::io::Write as _;
use std::path::Path;
use std::process::ExitCode;
use vigie_core::constraints::Class;
use vigie_core::diag::Problem;

#[derive(serde::Serialize)]
struct ConstraintRow<'a> {
    id: &'a str,
    class: Class,
    notation: &'a str,
    outputs: Vec<&'a str>,
    line: usize,
}

#[derive(serde::Serialize)]
struct Report<'a> {
    plant: &'a str,
    inputs: usize,
    outputs: usize,
    observers: Vec<&'a str>,
    constraints: Vec<ConstraintRow<'a>>,
    invariants: Vec<&'a str>,
    property6_discharged: &'a [vigie_core::constraints::Discharged],
    /// No safety constraint protects the plant (`V0110`, also among the problems).
    unprotected: bool,
    /// What the existence check of a fallback proved, and what it could not (support
    /// sizes); absent when the check found a context without any.
    fallback: Option<vigie_core::filter::FallbackReport>,
    problems: &'a [Problem],
    /// The physical plant (`components.ron` or `layout.ron`) and its elementary
    /// actions; absent for a plant described by its signals only.
    physical: Option<Physical>,
}

/// What `check` found of the physical plant.
#[derive(serde::Serialize)]
struct Physical {
    /// `components.ron` or `layout.ron`.
    file: &'static str,
    /// Its components (a layout counts its conveyors and turntable).
    components: Vec<String>,
    /// The elementary actions the monitor watches: declared (`actions.ron`) or derived.
    actions: Vec<vigie_core::machine::actions::ElementaryAction>,
    /// `actions.ron` or `components`.
    actions_from: &'static str,
    /// For a plant of components placed on the floor: the turntable cell it derives
    /// (top view, `vigie verify`'s cell model), or why it is drawn as a schematic.
    floor: Option<String>,
}

/// Loads the physical description of `dir` when it has one, checks its signals and its
/// declared actions against the components; its problems join `problems`.
fn physical(
    dir: &Path,
    bundle: &vigie_core::bundle::PlantBundle,
    problems: &mut Vec<Problem>,
) -> Option<Physical> {
    use vigie_core::machine::{Description, physical};
    use vigie_core::sim::actions::{ACTIONS_FILE, compare_with_components};
    let has = |f: &str| dir.join(f).exists();
    if !has(physical::COMPONENTS_FILE) && !has(physical::LAYOUT_FILE) {
        return None;
    }
    let desc = match Description::load(dir) {
        Ok(d) => d,
        Err(p) => {
            problems.extend(p);
            return None;
        }
    };
    let found = desc.check_signals(&bundle.plant);
    let broken = found.iter().any(Problem::is_error);
    problems.extend(found);
    let Description::Components(c) = &desc;
    if !broken {
        problems.extend(vigie_core::machine::safe_state::check(c, &bundle.plant));
        problems.extend(c.warnings());
    }
    // A legacy layout.ron is read as the components it describes: the report names
    // the file it came from.
    let file = if c.file.file_name() == Some(std::ffi::OsStr::new(physical::LAYOUT_FILE)) {
        physical::LAYOUT_FILE
    } else {
        physical::COMPONENTS_FILE
    };
    let components = c
        .components
        .iter()
        .map(|c| format!("{} ({})", c.id, c.kind.label()))
        .collect();
    let placed = c.components.iter().any(|k| k.at.is_some());
    let floor = placed.then(|| match vigie_core::emulator::Layout::cell_of(c) {
        Ok(_) => "a turntable cell: the console draws its top view and `vigie verify` \
                  searches the cell's model"
            .to_string(),
        Err(why) => format!("drawn as a schematic, not a turntable cell: {why}"),
    });
    let mut report = Physical {
        file,
        components,
        actions: Vec::new(),
        actions_from: "components",
        floor,
    };
    let derived = if broken {
        Vec::new()
    } else {
        vigie_core::machine::ComponentPlant::new(c, &bundle.plant, 0)
            .map(|p| p.derived_actions())
            .unwrap_or_default()
    };
    let path = dir.join(ACTIONS_FILE);
    if path.exists() {
        let text = vigie_core::diag::read_text(&path);
        match (vigie_core::machine::actions::load_actions(&path), text) {
            (Ok(actions), Ok(text)) => {
                problems.extend(vigie_core::machine::actions::check_actions(
                    &actions,
                    &bundle.symbols,
                    Some((&path, &text)),
                ));
                if !derived.is_empty() {
                    problems.extend(compare_with_components(&actions, &derived, &path, &text));
                }
                report.actions = actions;
                report.actions_from = ACTIONS_FILE;
            }
            (Err(p), _) => problems.extend(p),
            (_, Err(p)) => problems.push(p),
        }
    } else {
        report.actions = derived
            .into_iter()
            .map(|d| vigie_core::machine::actions::ElementaryAction {
                id: d.id,
                component: d.component,
                initial: d.initial,
                command: d.command,
                final_state: d.final_state,
                t_ms: d.t_ms,
                dt_ms: d.dt_ms,
            })
            .collect();
    }
    Some(report)
}

pub(crate) fn run(dir: &Path, json: bool) -> anyhow::Result<ExitCode> {
    let (bundle, problems) = match vigie_core::bundle::PlantBundle::load(dir) {
        Ok(v) => v,
        Err(problems) => {
            if json {
                let out = serde_json::json!({ "constraints": [], "problems": problems });
                writeln!(std::io::stdout(), "{}", serde_json::to_string_pretty(&out)?)?;
            } else {
                eprintln!("{}", vigie_core::diag::render(&problems));
            }
            return Ok(ExitCode::FAILURE);
        }
    };
    let mut problems = problems;
    let physical = physical(dir, &bundle, &mut problems);
    // The live link's I/O map, and the fieldbus it names, when the plant has one.
    let map = dir.join("io-map.ron");
    if map.exists() {
        match vigie_core::live::iomap::IoMap::load(&map, &bundle.plant) {
            Ok((_, warnings)) => problems.extend(warnings),
            Err(p) => problems.extend(p),
        }
    }
    let symbols = &bundle.symbols;
    let rows: Vec<ConstraintRow<'_>> = bundle
        .constraints
        .constraints
        .iter()
        .map(|c| ConstraintRow {
            id: &c.id,
            class: c.class,
            notation: &c.source,
            outputs: c
                .outputs
                .iter()
                .map(|&k| symbols.name(vigie_core::symbols::Space::Output, k))
                .collect(),
            line: c.location.line,
        })
        .collect();
    let report = Report {
        plant: &bundle.plant.name,
        inputs: bundle.plant.inputs.len(),
        outputs: bundle.plant.outputs.len(),
        observers: bundle
            .observers
            .defs
            .iter()
            .map(|d| d.id.as_str())
            .collect(),
        constraints: rows,
        invariants: bundle
            .invariants
            .constraints
            .iter()
            .map(|c| c.id.as_str())
            .collect(),
        property6_discharged: &bundle.discharged,
        unprotected: bundle.unprotected().is_some(),
        fallback: bundle.fallback.clone(),
        problems: &problems,
        physical,
    };
    let mut out = std::io::stdout().lock();
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        write_text(&mut out, &bundle, &report, &problems)?;
    }
    Ok(if problems.iter().any(Problem::is_error) {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// The physical plant's section: its components and the elementary actions watched.
fn write_physical(out: &mut std::io::StdoutLock<'_>, p: &Physical) -> anyhow::Result<()> {
    writeln!(
        out,
        "physical plant ({}): {}",
        p.file,
        p.components.join(", ")
    )?;
    if let Some(floor) = &p.floor {
        writeln!(out, "placed on the floor: {floor}")?;
    }
    if !p.actions.is_empty() {
        writeln!(
            out,
            "elementary actions ({}): {}",
            p.actions_from,
            p.actions.len()
        )?;
        for a in &p.actions {
            writeln!(
                out,
                "  {:<18} {:<6} --{:<6}--> {:<6} T {:>6} ms  ±{:>5} ms",
                a.id, a.initial, a.command, a.final_state, a.t_ms, a.dt_ms
            )?;
        }
    }
    writeln!(out)?;
    Ok(())
}

/// The check's text report: the unprotected warning first, the constraints, property
/// (6), the fallback and the verdict (or the problems).
fn write_text(
    out: &mut std::io::StdoutLock<'_>,
    bundle: &vigie_core::bundle::PlantBundle,
    report: &Report<'_>,
    problems: &[Problem],
) -> anyhow::Result<()> {
    // First, before anything else: nothing stops a dangerous command.
    if let Some(w) = bundle.unprotected() {
        let detail = w
            .message
            .strip_prefix("the plant is unprotected: ")
            .unwrap_or(&w.message);
        writeln!(
            out,
            "WARNING[{}]: THE PLANT IS UNPROTECTED: {detail}",
            w.code
        )?;
        writeln!(out)?;
    }
    writeln!(
        out,
        "{}: {} sensors, {} actuators, observers {}",
        report.plant,
        report.inputs,
        report.outputs,
        report.observers.join(", ")
    )?;
    writeln!(out)?;
    writeln!(out, "{:<8} {:<9} {:<10} notation", "id", "class", "outputs")?;
    for r in &report.constraints {
        let class = match r.class {
            Class::Simple => "simple",
            Class::Combined => "combined",
        };
        writeln!(
            out,
            "{:<8} {:<9} {:<10} {}",
            r.id,
            class,
            r.outputs.join(","),
            r.notation
        )?;
    }
    writeln!(out)?;
    let simple = report
        .constraints
        .iter()
        .filter(|r| r.class == Class::Simple)
        .count();
    writeln!(
        out,
        "{} constraints: {} simple, {} combined",
        report.constraints.len(),
        simple,
        report.constraints.len() - simple
    )?;
    if !bundle.discharged.is_empty() {
        writeln!(
            out,
            "property (6): {} logical conflicts, each in a situation an invariant excludes:",
            bundle.discharged.len()
        )?;
        for d in &bundle.discharged {
            writeln!(
                out,
                "  {}: {} forces 0, {} forces 1 when {}; unreachable by {}",
                d.output, d.forces_zero, d.forces_one, d.witness, d.invariant
            )?;
        }
    }
    if let Some(f) = &report.fallback {
        write_fallback(out, f)?;
    }
    if let Some(p) = &report.physical {
        write_physical(out, p)?;
    }
    let fallback_proved = report.fallback.as_ref().is_some_and(|f| f.proved());
    if problems.is_empty() && fallback_proved {
        writeln!(
            out,
            "static checks passed: property (6) holds for every output in every reachable situation \
             ({} invariants), a fallback exists in every reachable context, every name is known",
            report.invariants.len()
        )?;
    } else if problems.is_empty() {
        writeln!(
            out,
            "static checks passed except the fallback's existence, NOT PROVED for the components above: \
             property (6) holds for every output in every reachable situation ({} invariants), every name is known",
            report.invariants.len()
        )?;
    } else {
        writeln!(out, "{}", vigie_core::diag::render(problems))?;
    }
    Ok(())
}

/// What the fallback's existence check proved, in words: the whole support enumerated,
/// or each output component's, and which were too large.
fn write_fallback(
    out: &mut impl std::io::Write,
    f: &vigie_core::filter::FallbackReport,
) -> std::io::Result<()> {
    match f.method {
        "whole" => writeln!(
            out,
            "fallback: exists in every reachable context, {} contexts of the {} variables the constraints read enumerated",
            f.contexts, f.support
        ),
        method => {
            writeln!(
                out,
                "fallback: the constraints read {} variables, too many to enumerate at once (limit {}); checked per output component ({} contexts):",
                f.support,
                vigie_core::filter::EXHAUSTIVE_SUPPORT_LIMIT,
                f.contexts
            )?;
            for c in &f.components {
                writeln!(
                    out,
                    "  {:<28} support {:>3}  {}",
                    c.outputs.join(","),
                    c.support,
                    if c.proved {
                        "proved: a fallback in every reachable context"
                    } else {
                        "NOT PROVED: support too large to enumerate"
                    }
                )?;
            }
            if method == "not_proved" {
                writeln!(
                    out,
                    "fallback: NOT PROVED for every context; the engine still searches one every cycle and drives the outputs to their safe values when none exists"
                )?;
            }
            Ok(())
        }
    }
}
