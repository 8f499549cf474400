//! Command-line interface: argument parsing and dispatch to the subcommands.

mod bench;
mod bench_historian;
mod campaign;
mod check;
mod export_st;
mod filter;
mod gateway;
mod learn;
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
    #[command(flatten)]
    pub(crate) console: ConsoleArgs,
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
}

/// Options of the console (no subcommand, or `vigie run SCENARIO` without `--headless`).
#[derive(clap::Args, Debug)]
pub(crate) struct ConsoleArgs {
    /// Console: initial simulation speed (0.1 to 100).
    #[arg(long, global = true, default_value_t = 1.0)]
    pub(crate) speed: f64,
    /// Console: initial mode (production, maintenance, training).
    #[arg(long, global = true, default_value = "production")]
    pub(crate) mode: String,
    /// Console: explanation level (0-4) to show once a trip is explained.
    #[arg(long, global = true)]
    pub(crate) level: Option<usize>,
    /// Console: run the simulation to this time (ms) before the first frame.
    #[arg(long, global = true)]
    pub(crate) run_until: Option<u64>,
    /// Console: start paused.
    #[arg(long, global = true)]
    pub(crate) paused: bool,
    /// Console: press START at once.
    #[arg(long, global = true)]
    pub(crate) start: bool,
    /// Console: load this variant of the control-error library (training).
    #[arg(long, global = true)]
    pub(crate) variant: Option<String>,
    /// Console: follow the live link of this monitor or gateway configuration (e.g.
    /// layouts/sorting-station/gateway-monitor.ron) instead of the emulator.
    #[arg(long, global = true)]
    pub(crate) link: Option<PathBuf>,
    /// Console: language shown first, `fr` or `en` (default: VIGIE_LANG, else the
    /// system locale; switched at run time from the toolbar).
    #[arg(long, global = true)]
    pub(crate) lang: Option<String>,
}

fn open_console(
    plant: &std::path::Path,
    scenario: Option<PathBuf>,
    args: &ConsoleArgs,
) -> anyhow::Result<ExitCode> {
    let mode = vigie_app::Mode::parse(&args.mode).ok_or_else(|| {
        anyhow::anyhow!(
            "unknown mode `{}` (production, maintenance, training)",
            args.mode
        )
    })?;
    let mut opts = vigie_app::ConsoleOptions::new(plant);
    opts.scenario = scenario;
    opts.speed = args.speed;
    opts.mode = mode;
    opts.level = args.level;
    opts.paused = args.paused;
    opts.run_until_ms = args.run_until;
    opts.start = args.start;
    opts.variant.clone_from(&args.variant);
    opts.link.clone_from(&args.link);
    opts.open_files = true;
    if let Some(l) = &args.lang {
        opts.lang = vigie_app::i18n::Lang::parse(l)
            .ok_or_else(|| anyhow::anyhow!("unknown language `{l}` (fr, en)"))?;
    }
    let _log = opts.link.is_some().then(|| {
        vigie_app::console::link::watch_signals(true);
        gateway::init_tracing("warn")
    });
    vigie_app::run_console(&opts)?;
    Ok(ExitCode::SUCCESS)
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
        /// The trace starts with the plant (a PLC's first scan: every previous value
        /// is the signal's initial value); by default the first row is also taken as
        /// the values at t-1, for a trace recorded mid-production.
        #[arg(long)]
        cold_start: bool,
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
    /// Write the observers, the filter and the task monitors as IEC 61131-3 Structured
    /// Text (function blocks and a program to call at the end of the PLC cycle).
    ExportSt {
        /// The plant folder (defaults to --plant).
        dir: Option<PathBuf>,
        /// Write to this file instead of the standard output.
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Measure the console: CPU time per frame at 1x (headless egui, no GPU) and memory
    /// over a simulated hour at 100x.
    BenchConsole {
        /// Frames timed.
        #[arg(long, default_value_t = 600)]
        frames: usize,
        /// Skip the simulated hour.
        #[arg(long)]
        no_memory: bool,
    },
    /// Run a campaign and print its figures (`mutations`: does the hypothesis level
    /// localise every control error that trips the filter?).
    Campaign {
        /// Which campaign.
        #[arg(value_enum)]
        kind: campaign::Kind,
        /// Worker threads (default: the available parallelism).
        #[arg(long)]
        threads: Option<usize>,
        /// Print the full JSON report.
        #[arg(long)]
        json: bool,
        /// `diagnoser`, `transients`: seeds per fault.
        #[arg(long, default_value_t = 100)]
        seeds: u64,
        /// `diagnoser`, `transients`: the first seed (`--from-seed 66 --seeds 1` replays seed 66;
        /// `transients --seeds 1 --json` adds every change of a signal of the failed run).
        #[arg(long, default_value_t = 0)]
        from_seed: u64,
        /// `diagnoser`, `transients`: simulated hours of fault-free runs.
        #[arg(long, default_value_t = 10)]
        hours: u64,
        /// `diagnoser`, `transients`: only faults (cases) whose name contains this.
        #[arg(long)]
        only: Option<String>,
        /// `transients`: without the plausibility stage (every edge as read), to compare.
        #[arg(long)]
        no_plausibility: bool,
    },
    /// Verify the constraint set on the abstract plant model (safety, permissiveness,
    /// invariants, necessity), optionally against SPIN, with benchmarks.
    Verify(verify::VerifyArgs),
    /// Learn the diagnosers' intervals from normal-run traces into `diagnosers.ron`.
    Learn {
        /// Trace files (CSV, `vigie run --trace`).
        traces: Vec<PathBuf>,
        /// Confidence coefficient α of ΔT = α·σ (default: the file's).
        #[arg(long)]
        alpha: Option<f64>,
        /// Print the figures without writing the file.
        #[arg(long)]
        dry_run: bool,
    },
    /// Diagnosers: `--report` prints the diagnosability report.
    Diagnose {
        /// Print the diagnosability report (JSON).
        #[arg(long)]
        report: bool,
    },
    /// Measure the diagnosers (per cycle, build) and libFAUDES' centralized diagnoser.
    BenchDiag,
    /// The console's user accounts (roles, argon2id password hashes in
    /// `users.ron` of the data folder).
    User {
        #[command(subcommand)]
        action: UserAction,
    },
    /// Measure the historian: a durable journal insert, recording a week of process
    /// history at the plant's cycle, and trend queries over it.
    BenchHistorian(bench_historian::Args),
    /// Measure the engines and print the figures.
    Bench {
        /// Number of timed repetitions per figure.
        #[arg(long, default_value_t = 200_000)]
        iterations: u32,
    },
}

/// Runs the parsed command line.
/// What `vigie user` does.
#[derive(clap::Subcommand, Debug)]
pub(crate) enum UserAction {
    /// Add an account, or replace its role and password; the password is the first
    /// line of standard input (at least 8 characters), never an argument.
    Add {
        /// Login name (one word).
        name: String,
        /// operator, maintenance, trainer or administrator.
        #[arg(long)]
        role: String,
        /// The data folder (default: `VIGIE_DATA_DIR`, else `$XDG_DATA_HOME/vigie`,
        /// else `~/.local/share/vigie`).
        #[arg(long)]
        data_dir: Option<PathBuf>,
    },
    /// List the accounts and their roles.
    List {
        /// The data folder (as for `add`).
        #[arg(long)]
        data_dir: Option<PathBuf>,
    },
}

fn user(action: UserAction) -> anyhow::Result<ExitCode> {
    use vigie_app::console::users::Users;
    let dir = |d: Option<PathBuf>| d.unwrap_or_else(vigie_app::console::journal::data_dir_from_env);
    match action {
        UserAction::Add {
            name,
            role,
            data_dir,
        } => {
            let dir = dir(data_dir);
            let role = vigie_core::access::Role::parse(&role).ok_or_else(|| {
                anyhow::anyhow!(
                    "unknown role `{role}` (operator, maintenance, trainer, administrator)"
                )
            })?;
            let mut password = String::new();
            std::io::stdin().read_line(&mut password)?;
            let password = password.trim_end_matches(['\n', '\r']);
            let mut users = Users::load(&dir)?;
            users.set(&name, role, password)?;
            users.save(&dir)?;
            println!("{name}: {} ({})", role.name(), Users::path(&dir).display());
        }
        UserAction::List { data_dir } => {
            let dir = dir(data_dir);
            for a in Users::load(&dir)?.accounts {
                println!("{}\t{}", a.name, a.role.name());
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

pub(crate) fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Some(Command::User { action }) => user(action),
        Some(Command::Check { dir, json }) => check::run(&dir.unwrap_or(cli.plant), json),
        Some(Command::Filter {
            dir,
            trace,
            reset_after_trip,
            explain,
            cold_start,
        }) => filter::run(
            &dir.unwrap_or(cli.plant),
            &trace,
            reset_after_trip,
            explain,
            cold_start,
        ),
        Some(Command::Gateway(args)) => gateway::run(&args),
        Some(Command::GatewayBench(args)) => gateway::bench(&cli.plant, &args),
        Some(Command::Learn {
            traces,
            alpha,
            dry_run,
        }) => learn::learn(&cli.plant, &traces, alpha, dry_run),
        Some(Command::Diagnose { report }) => {
            anyhow::ensure!(report, "use `vigie diagnose --report`");
            learn::report(&cli.plant)
        }
        Some(Command::BenchDiag) => learn::bench(&cli.plant),
        Some(Command::Bench { iterations }) => bench::run(&cli.plant, iterations),
        Some(Command::BenchHistorian(args)) => bench_historian::run(&cli.plant, &args),
        Some(Command::ExportSt { dir, out }) => {
            export_st::run(&dir.unwrap_or(cli.plant), out.as_deref())
        }
        Some(Command::BenchConsole { frames, no_memory }) => {
            let opts = vigie_app::ConsoleOptions::new(&cli.plant);
            let b = vigie_app::bench_frames(&opts, frames, !no_memory)?;
            println!(
                "console frame (logic + ui + tessellation, 1600x1000, 1x): median {:.2} ms, p95 {:.2} ms over {} frames   goal <= 4 ms",
                b.median_ms, b.p95_ms, b.frames
            );
            if !no_memory {
                println!(
                    "memory over {} s simulated at 100x: RSS {} KiB after 10 min, {} KiB at the end (growth {} KiB)",
                    b.memory_sim_s,
                    b.rss_warm_kib,
                    b.rss_end_kib,
                    b.rss_end_kib.saturating_sub(b.rss_warm_kib)
                );
            }
            Ok(ExitCode::SUCCESS)
        }
        Some(Command::Campaign {
            kind: campaign::Kind::Diagnoser,
            seeds,
            from_seed,
            hours,
            only,
            threads,
            json,
            ..
        }) => learn::campaign(
            &cli.plant,
            (from_seed, seeds),
            hours,
            only.as_deref(),
            threads,
            json,
        ),
        Some(Command::Campaign {
            kind: campaign::Kind::Transients,
            seeds,
            from_seed,
            hours,
            only,
            threads,
            json,
            no_plausibility,
        }) => learn::transients(
            &cli.plant,
            (from_seed, seeds),
            hours,
            only.as_deref(),
            threads,
            (json, !no_plausibility),
        ),
        Some(Command::Campaign {
            kind,
            threads,
            json,
            ..
        }) => campaign::run(&cli.plant, kind, threads, json),
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
                open_console(&cli.plant, Some(scenario), &cli.console)
            }
        }
        None => open_console(&cli.plant, None, &cli.console),
    }
}

/// Loads a plant folder and refuses it when any problem is an error.
pub(crate) fn load_valid_bundle(
    dir: &std::path::Path,
) -> anyhow::Result<vigie_core::bundle::PlantBundle> {
    let (bundle, problems) = load_bundle(dir)?;
    if problems.iter().any(vigie_core::diag::Problem::is_error) {
        anyhow::bail!(
            "plant {} has errors:\n{}",
            dir.display(),
            vigie_core::diag::render(&problems)
        );
    }
    Ok(bundle)
}

/// Loads a plant folder, failing with every problem rendered when it cannot be used.
pub(crate) fn load_bundle(
    dir: &std::path::Path,
) -> anyhow::Result<(
    vigie_core::bundle::PlantBundle,
    Vec<vigie_core::diag::Problem>,
)> {
    vigie_core::bundle::PlantBundle::load(dir).map_err(|problems| {
        anyhow::anyhow!(
            "cannot load plant {}:\n{}",
            dir.display(),
            vigie_core::diag::render(&problems)
        )
    })
}
