//! `vigie campaign mutations`: the localisation campaign of the hypothesis level over
//! the control-error library and every single mutation of the reference program (see
//! `vigie_core::campaign`).

use std::io::Write as _;
use std::path::Path;
use std::process::ExitCode;

/// Which campaign.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(crate) enum Kind {
    /// Library variants and single mutations of the reference program.
    Mutations,
    /// Fault campaign of the diagnosers: every injectable fault over many seeds, and
    /// fault-free hours (`vigie campaign diagnoser`).
    Diagnoser,
    /// Transient sensor faults (dropouts, pulses, flicker, pairs) and welded and dead
    /// actuators, with the filter and the diagnosers on: hazards, wrong diagnoses and
    /// recovery after the reset (`vigie campaign transients`).
    Transients,
}

pub(crate) fn run(
    plant_dir: &Path,
    kind: Kind,
    threads: Option<usize>,
    json: bool,
) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(matches!(kind, Kind::Mutations), "dispatched elsewhere");
    let config = vigie_core::campaign::Config {
        threads: threads
            .or_else(|| std::thread::available_parallelism().ok().map(usize::from))
            .unwrap_or(1)
            .max(1),
        ..vigie_core::campaign::Config::default()
    };
    let report = vigie_core::campaign::run(plant_dir, &config).map_err(|p| {
        anyhow::anyhow!("cannot run the campaign:\n{}", vigie_core::diag::render(&p))
    })?;
    let mut out = std::io::stdout().lock();
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
        return Ok(ExitCode::SUCCESS);
    }
    writeln!(
        out,
        "mutation campaign ({} boxes, up to {} s each, filter Enforce)",
        config.arrivals.len(),
        config.duration_ms / 1000
    )?;
    writeln!(out, "  mutants:    {}", report.mutants)?;
    writeln!(out, "  tripped:    {}", report.tripped)?;
    writeln!(out, "  localised:  {}", report.localised)?;
    writeln!(
        out,
        "  rate:       {:.1} %   goal >= 90 %",
        report.rate_percent()
    )?;
    writeln!(
        out,
        "  names in the first suspect (mean): {:.2}",
        report.mean_first_names
    )?;
    let misses: Vec<_> = report.misses().collect();
    if !misses.is_empty() {
        writeln!(out, "misses:")?;
        for o in misses {
            writeln!(
                out,
                "  {} [{}] {}",
                o.id,
                o.constraints.join(","),
                o.description
            )?;
            writeln!(out, "      {}", o.why)?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
