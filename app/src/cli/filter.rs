//! `vigie filter`: replay a recorded trace through observers and the filter.

use std::io::Write as _;
use std::path::Path;
use std::process::ExitCode;
use vigie_core::engine::{Commanded, Engine, FilterMode, FirstCycle};

pub(crate) fn run(
    dir: &Path,
    trace_path: &Path,
    reset_after_trip: bool,
    explain: bool,
    cold_start: bool,
) -> anyhow::Result<ExitCode> {
    let bundle = super::load_valid_bundle(dir)?;
    let text = std::fs::read_to_string(trace_path)
        .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", trace_path.display()))?;
    let rows = vigie_core::trace::parse(&text, trace_path, &bundle.plant)
        .map_err(|p| anyhow::anyhow!("{p}"))?;
    let mut engine = Engine::new(&bundle, FilterMode::Enforce, 6000);
    // A trace recorded mid-production: its first row is the values at t-1 too (no
    // edge), unless it starts with the plant, cold.
    engine.set_first_cycle(if cold_start {
        FirstCycle::Cold
    } else {
        FirstCycle::Attach
    });
    let mut control = Commanded::default();
    let mut out = std::io::stdout().lock();
    for row in &rows {
        control.0.clone_from(&row.outputs);
        if reset_after_trip && engine.is_tripped() {
            // The reset is checked against the commands of the previous cycle.
            let _ = engine.reset();
        }
        engine.cycle(row.time, &row.inputs, &mut control);
        for event in engine.drain_events() {
            if let vigie_core::engine::Event::Trip { index } = event {
                let mut line = serde_json::to_value(&engine.trips[index])?;
                if explain && let Some(ex) = vigie_core::explain::explain(&engine, index) {
                    line["explanation"] = serde_json::to_value(ex)?;
                }
                writeln!(out, "{line}")?;
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
