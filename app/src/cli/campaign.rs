//! `vigie campaign mutations`: the localisation campaign of the hypothesis level over
//! the control-error library and every single mutation of the reference program (see
//! `vigie_core::campaign`).

use std::io::Write as _;
use std::path::Path;
use std::process::ExitCode;

/// Options every campaign takes.
#[derive(clap::Args, Debug)]
pub(crate) struct Common {
    #[command(flatten)]
    pub(crate) plant: super::PlantOpt,
    /// Worker threads (default: the available parallelism).
    #[arg(long)]
    pub(crate) threads: Option<usize>,
    /// Print the full JSON report.
    #[arg(long)]
    pub(crate) json: bool,
}

/// Options of the fault campaigns (`diagnoser`, `transients`).
#[derive(clap::Args, Debug)]
pub(crate) struct Faults {
    /// Seeds per fault.
    #[arg(long, default_value_t = 100)]
    pub(crate) seeds: u64,
    /// The first seed (`--from-seed 66 --seeds 1` replays seed 66; `transients --seeds
    /// 1 --json` adds every change of a signal of the failed run).
    #[arg(long, default_value_t = 0)]
    pub(crate) from_seed: u64,
    /// Simulated hours of fault-free runs.
    #[arg(long, default_value_t = 10)]
    pub(crate) hours: u64,
    /// Only faults (cases) whose name contains this.
    #[arg(long)]
    pub(crate) only: Option<String>,
}

/// Which campaign.
#[derive(clap::Subcommand, Debug)]
pub(crate) enum CampaignCmd {
    /// Library variants and single mutations of the reference program: does the
    /// hypothesis level localise every control error that trips the filter?
    Mutations {
        #[command(flatten)]
        common: Common,
    },
    /// Fault campaign of the diagnosers: every injectable fault over many seeds, and
    /// fault-free hours.
    Diagnoser {
        #[command(flatten)]
        common: Common,
        #[command(flatten)]
        faults: Faults,
    },
    /// Transient sensor faults (dropouts, pulses, flicker, pairs) and welded and dead
    /// actuators, with the filter and the diagnosers on: hazards, wrong diagnoses and
    /// recovery after the reset.
    Transients {
        #[command(flatten)]
        common: Common,
        #[command(flatten)]
        faults: Faults,
        /// Without the plausibility stage (every edge as read), to compare.
        #[arg(long)]
        no_plausibility: bool,
    },
}

/// Runs the campaign asked for.
pub(crate) fn dispatch(cmd: CampaignCmd) -> anyhow::Result<ExitCode> {
    match cmd {
        CampaignCmd::Mutations { common } => run(&common.plant.plant, common.threads, common.json),
        CampaignCmd::Diagnoser { common, faults } => super::learn::campaign(
            &common.plant.plant,
            (faults.from_seed, faults.seeds),
            faults.hours,
            faults.only.as_deref(),
            common.threads,
            common.json,
        ),
        CampaignCmd::Transients {
            common,
            faults,
            no_plausibility,
        } => super::learn::transients(
            &common.plant.plant,
            (faults.from_seed, faults.seeds),
            faults.hours,
            faults.only.as_deref(),
            common.threads,
            (common.json, !no_plausibility),
        ),
    }
}

fn run(plant_dir: &Path, threads: Option<usize>, json: bool) -> anyhow::Result<ExitCode> {
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
    // Items arrive on a plant fed by a source (the station's boxes); any other runs
    // what one press of Start starts.
    let fed =
        vigie_core::sim::workload::Workload::of(plant_dir, vigie_core::emulator::ArrivalPlan::Off)
            .is_ok_and(|w| matches!(w, vigie_core::sim::workload::Workload::Arrivals(_)));
    let items = if fed {
        format!("{} boxes, ", config.arrivals.len())
    } else {
        String::new()
    };
    writeln!(
        out,
        "mutation campaign ({items}up to {} s each, filter Enforce)",
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
    let m = &report.misplaced;
    writeln!(
        out,
        "misplaced actions (an action moved to another step of its chart): {} mutants, {} tripped",
        m.mutants, m.tripped
    )?;
    writeln!(
        out,
        "  the first suspect blames the step it was moved to: {} ({:.1} %); of the {} trips the moved action drove: {}",
        m.localised, m.rate_percent, m.driven, m.driven_localised
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
