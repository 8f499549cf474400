//! `vigie bus FILE`: the timing of a FIP-like fieldbus (`core/src/fieldbus.rs`).

use std::fmt::Write as _;
use std::path::Path;
use std::process::ExitCode;

pub(crate) fn run(file: &Path, json: bool) -> anyhow::Result<ExitCode> {
    let render = |p: &[vigie_core::diag::Problem]| vigie_core::diag::render(p);
    let (bus, text) =
        vigie_core::fieldbus::BusFile::load(file).map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    let a = bus
        .analyse(file, &text)
        .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    let bounds = a.input_bounds(file, &text);
    if json {
        println!("{}", serde_json::to_string_pretty(&a)?);
    } else {
        print!("{}", report(&a, bounds.as_ref().ok()));
    }
    if !a.warnings.is_empty() {
        eprintln!("{}", render(&a.warnings));
    }
    match bounds {
        Ok(_) => Ok(ExitCode::SUCCESS),
        Err(p) => anyhow::bail!("{}", render(&p)),
    }
}

/// The analysis as text: the cycles, the table, then one line per variable.
fn report(
    a: &vigie_core::fieldbus::Analysis,
    bounds: Option<&std::collections::BTreeMap<String, u64>>,
) -> String {
    let us = |ns: u64| format!("{}.{:03}", ns / 1000, ns % 1000);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "µC {} µs, macro-cycle {} µs ({} µC), TMAC {} ns",
        a.micro_cycle_us,
        a.macro_cycle_us,
        a.table.len(),
        a.tmac_ns
    );
    for (m, row) in a.table.iter().enumerate() {
        let names: Vec<String> = row
            .iter()
            .map(|(i, start)| format!("{} at {} µs", a.variables[*i].name, us(*start)))
            .collect();
        let _ = writeln!(
            out,
            "  µC {m}: load {} µs ({}%): {}",
            us(a.load_ns[m]),
            a.load_ns[m] * 100 / (a.micro_cycle_us * 1000),
            names.join(", ")
        );
    }
    for v in &a.variables {
        let left = v
            .signals
            .iter()
            .map(|s| {
                let ms = bounds
                    .and_then(|b| b.get(s))
                    .map_or("?".into(), |m| format!("{m} ms"));
                format!("{ms} of its deadline left for {s} on the link")
            })
            .collect::<Vec<_>>();
        let _ = writeln!(
            out,
            "{}: every {} µs (phase {}), TE {} µs, age {}..{} µs{}{}",
            v.name,
            v.period_us,
            v.phase,
            us(v.transaction_ns),
            us(v.best_age_ns),
            us(v.worst_age_ns),
            v.deadline_us
                .map_or(String::new(), |d| format!(", deadline {d} µs")),
            if left.is_empty() {
                String::new()
            } else {
                format!("; {}", left.join(", "))
            }
        );
    }
    out
}
