//! Command-line interface: argument parsing and dispatch to the subcommands.

mod bench;
mod check;
mod filter;
mod gateway;
mod run;
mod verify;

use std::path::PathBuf;
use std::process::ExitCode;

/// Vigie: safety filter, diagnosis and explanations beside a PLC-controlled machine.
#[derive(clap::Parser, Debug)]
#[command(name = "vigie", version, about)]
pub(crate) struct Cli {
    /// Plant folder to open.
    #[arg(long, global = true, default_value = "layouts/sorting-station")]
    pub(crate) plant: PathBuf,
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
}

#[derive(clap::Subcommand, Debug)]
pub(crate) enum Command {
    /// Validate a plant folder and print its constraint table and static-check results.
    Check {
        /// The plant folder (defaults to --plant).
        dir: Option<PathBuf>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Run observers and the filter over a recorded cycle trace (CSV) and print one JSON
    /// line per trip.
    Filter {
        /// The plant folder (defaults to --plant).
        dir: Option<PathBuf>,
        /// The trace: `time_ms` and one 0/1 column per signal (outputs as commanded).
        #[arg(long)]
        trace: PathBuf,
        /// After a trip, reset as soon as the commands comply again (the operator's reset
        /// in a recorded trace), so that every episode is reported; by default the trip
        /// latches for the rest of the trace.
        #[arg(long)]
        reset_after_trip: bool,
        /// Add the explanation levels 0, 2, 3 and 4 to each trip line (level 1, the
        /// projection, needs the plant emulator: see `vigie run`).
        #[arg(long)]
        explain: bool,
    },
    /// Run a scenario (emulator + control program + filter).
    Run {
        /// The scenario file (RON).
        scenario: PathBuf,
        /// Run without the console, as fast as possible, and print the JSON report.
        #[arg(long)]
        headless: bool,
        /// Write the per-cycle trace (the CSV format `vigie filter` reads).
        #[arg(long)]
        trace: Option<PathBuf>,
        /// Leave `wall_ms` out of the report, so that it is byte-identical across runs.
        #[arg(long)]
        no_timing: bool,
    },
    /// Run the live link headless (monitor, gateway or emulator mode, from CONFIG).
    Gateway(gateway::GatewayArgs),
    /// Measure the gateway against a pymodbus plant on loopback (cycle rate, jitter,
    /// sensor-to-output latency).
    GatewayBench(gateway::BenchArgs),
    /// Verify the constraint set on the abstract plant model (safety, permissiveness,
    /// invariants, necessity), optionally against SPIN, with benchmarks.
    Verify(verify::VerifyArgs),
    /// Measure the engines and print the figures.
    Bench {
        /// Number of timed repetitions per figure.
        #[arg(long, default_value_t = 200_000)]
        iterations: u32,
    },
}

/// Runs the parsed command line.
pub(crate) fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Some(Command::Check { dir, json }) => check::run(&dir.unwrap_or(cli.plant), json),
        Some(Command::Filter {
            dir,
            trace,
            reset_after_trip,
            explain,
        }) => filter::run(&dir.unwrap_or(cli.plant), &trace, reset_after_trip, explain),
        Some(Command::Gateway(args)) => gateway::run(&args),
        Some(Command::GatewayBench(args)) => gateway::bench(&cli.plant, &args),
        Some(Command::Bench { iterations }) => bench::run(&cli.plant, iterations),
        Some(Command::Verify(args)) => verify::run(&cli.plant, &args),
        Some(Command::Run {
            scenario,
            headless,
            trace,
            no_timing,
        }) => {
            if headless {
                run::run(&scenario, trace.as_deref(), !no_timing)
            } else {
                anyhow::bail!("the console is not built yet: use `vigie run SCENARIO --headless`")
            }
        }
        None => {
            use clap::CommandFactory as _;
            Cli::command().print_help()?;
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// Loads a plant folder, failing with every problem rendered when it cannot be used.
pub(crate) fn load_bundle(
    dir: &std::path::Path,
) -> anyhow::Result<(vigie_core::bundle::PlantBundle, Vec<vigie_core::diag::Problem>)> {
    vigie_core::bundle::PlantBundle::load(dir).map_err(|problems| {
        anyhow::anyhow!(
            "cannot load plant {}:\n{}",
            dir.display(),
            vigie_core::diag::render(&problems)
        )
    })
}
