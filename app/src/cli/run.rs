//! `vigie run SCENARIO --headless`: run a scenario as fast as possible and print its
//! JSON report.

use std::io::Write as _;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;
use vigie_core::sim::{Options, Scenario, Simulation};

pub(crate) fn run(
    scenario_path: &Path,
    trace: Option<&Path>,
    timing: bool,
) -> anyhow::Result<ExitCode> {
    let scenario = Scenario::load(scenario_path).map_err(|p| {
        anyhow::anyhow!(
            "cannot load scenario {}:\n{}",
            scenario_path.display(),
            vigie_core::diag::render(&p)
        )
    })?;
    let mut sim =
        Simulation::from_scenario(&scenario, scenario_path, Options::default()).map_err(|p| {
            anyhow::anyhow!(
                "cannot start scenario {}:\n{}",
                scenario_path.display(),
                vigie_core::diag::render(&p)
            )
        })?;
    let mut csv = trace.map(|_| {
        let mut s = vigie_core::trace::header(&sim.bundle.plant);
        s.push('\n');
        s
    });
    let start = Instant::now();
    let end = vigie_core::Millis(scenario.duration_ms);
    while sim.now() < end {
        sim.cycle();
        if let (Some(csv), Some(rec)) = (csv.as_mut(), sim.engine.history.last()) {
            vigie_core::trace::write_row(csv, rec.time, &rec.inputs, &rec.commanded);
        }
    }
    let wall = start.elapsed();
    if let (Some(path), Some(csv)) = (trace, csv) {
        std::fs::write(path, csv)
            .map_err(|e| anyhow::anyhow!("cannot write trace {}: {e}", path.display()))?;
    }
    let mut report = serde_json::to_value(sim.report(scenario.seed))?;
    if timing {
        report["wall_ms"] = serde_json::json!(wall.as_secs_f64() * 1000.0);
    }
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    Ok(ExitCode::SUCCESS)
}
