//! Command-line interface: argument parsing and dispatch to the subcommands.

mod bench;
mod bench_historian;
mod bench_line;
mod bus;
mod campaign;
mod check;
mod export_sfc;
mod export_st;
mod filter;
mod gateway;
mod learn;
mod program;
mod run;
mod stpn;
mod synthesize;
mod verify;

use std::path::PathBuf;
use std::process::ExitCode;

/// The plant folder the sorting station's examples use when none is named.
const DEFAULT_PLANT: &str = "layouts/sorting-station";

/// Vigie: safety filter, diagnosis and explanations beside a PLC-controlled machine.
///
/// Without a subcommand, `vigie` opens the operator console (the options below); every
/// other command has its own options (`vigie help COMMAND`).
#[derive(clap::Parser, Debug)]
#[command(name = "vigie", version, about, args_conflicts_with_subcommands = true)]
pub(crate) struct Cli {
    #[command(flatten)]
    pub(crate) console: ConsoleCmd,
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
}

/// `--plant`: the plant folder of a command that does not name it otherwise.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct PlantOpt {
    /// Plant folder.
    #[arg(long, value_name = "DIR", default_value = DEFAULT_PLANT)]
    pub(crate) plant: PathBuf,
}

/// The plant folder as the command's argument.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct PlantArg {
    /// Plant folder.
    #[arg(value_name = "PLANT", default_value = DEFAULT_PLANT)]
    pub(crate) plant: PathBuf,
}

/// The console on a plant folder (`vigie`, `vigie console`).
#[derive(clap::Args, Debug)]
pub(crate) struct ConsoleCmd {
    #[command(flatten)]
    pub(crate) plant: PlantOpt,
    #[command(flatten)]
    pub(crate) console: ConsoleArgs,
}

/// The console's mode.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default)]
pub(crate) enum ModeArg {
    /// The operator's console.
    #[default]
    Production,
    /// Control charts, edits, verification (maintenance role).
    Maintenance,
    /// Control-error and fault libraries, score.
    Training,
}

/// A language of the console.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(crate) enum LangArg {
    /// Français.
    Fr,
    /// English.
    En,
}

/// Options of the console (`vigie`, `vigie console`, `vigie run SCENARIO`).
#[derive(clap::Args, Debug)]
pub(crate) struct ConsoleArgs {
    /// Initial simulation speed (0.1 to 100).
    #[arg(long, default_value_t = 1.0)]
    pub(crate) speed: f64,
    /// Initial mode.
    #[arg(long, value_enum, default_value_t = ModeArg::Production)]
    pub(crate) mode: ModeArg,
    /// Explanation level to show once a trip is explained (0 current state, 1
    /// projection, 2 before stop, 3 advanced, 4 hypothesis).
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=4))]
    pub(crate) level: Option<u8>,
    /// Run the simulation to this time (ms) before the first frame.
    #[arg(long, value_name = "MS")]
    pub(crate) run_until: Option<u64>,
    /// Start paused.
    #[arg(long)]
    pub(crate) paused: bool,
    /// Press the plant's Start button at once.
    #[arg(long)]
    pub(crate) start: bool,
    /// Load this variant of the control-error library (E01), or this plant-fault
    /// exercise (P01), for training.
    #[arg(long)]
    pub(crate) variant: Option<String>,
    /// Follow the live link of this monitor or gateway configuration (e.g.
    /// layouts/sorting-station/gateway-monitor.ron) instead of the emulator.
    #[arg(long, value_name = "CONFIG")]
    pub(crate) link: Option<PathBuf>,
    /// With `--link` in monitor mode: the program the PLC should run (RON or PLCopen
    /// XML), followed beside it; an alarm when the PLC's outputs leave its runs.
    #[arg(long, value_name = "FILE", requires = "link")]
    pub(crate) program: Option<PathBuf>,
    /// Language shown first (default: VIGIE_LANG, else the system locale; switched at
    /// run time from the toolbar).
    #[arg(long, value_enum)]
    pub(crate) lang: Option<LangArg>,
}

fn open_console(
    plant: &std::path::Path,
    scenario: Option<PathBuf>,
    args: &ConsoleArgs,
) -> anyhow::Result<ExitCode> {
    let mut opts = vigie_app::ConsoleOptions::new(plant);
    opts.scenario = scenario;
    opts.speed = args.speed;
    opts.mode = match args.mode {
        ModeArg::Production => vigie_app::Mode::Production,
        ModeArg::Maintenance => vigie_app::Mode::Maintenance,
        ModeArg::Training => vigie_app::Mode::Training,
    };
    opts.level = args.level.map(usize::from);
    opts.paused = args.paused;
    opts.run_until_ms = args.run_until;
    opts.start = args.start;
    opts.variant.clone_from(&args.variant);
    opts.link.clone_from(&args.link);
    opts.program.clone_from(&args.program);
    opts.open_files = true;
    if let Some(l) = args.lang {
        opts.lang = match l {
            LangArg::Fr => vigie_app::i18n::Lang::Fr,
            LangArg::En => vigie_app::i18n::Lang::En,
        };
    }
    let _log = opts.link.is_some().then(|| {
        vigie_app::console::link::watch_signals(true);
        gateway::init_tracing(gateway::LogLevel::Warn)
    });
    vigie_app::run_console(&opts)?;
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Subcommand, Debug)]
pub(crate) enum Command {
    /// Open the operator console (what `vigie` alone does).
    Console(ConsoleCmd),
    /// Validate a plant folder and print its constraint table and static-check results.
    Check {
        #[command(flatten)]
        plant: PlantArg,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Run observers and the filter over a recorded cycle trace (CSV) and print one JSON
    /// line per trip.
    Filter {
        #[command(flatten)]
        plant: PlantArg,
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
    /// Run a scenario (emulator + control program + filter) in the console, or headless
    /// with `--headless`. The scenario names its plant folder.
    Run {
        /// The scenario file (RON).
        scenario: PathBuf,
        /// Run without the console, as fast as possible, and print the JSON report.
        #[arg(long, conflicts_with = "ConsoleArgs")]
        headless: bool,
        /// Write the per-cycle trace (the CSV format `vigie filter` reads); headless.
        #[arg(long, requires = "headless")]
        trace: Option<PathBuf>,
        /// Leave `wall_ms` out of the report, so that it is byte-identical across runs;
        /// headless.
        #[arg(long, requires = "headless")]
        no_timing: bool,
        #[command(flatten)]
        console: ConsoleArgs,
    },
    /// Run the live link headless (monitor, gateway or emulator mode, from CONFIG; the
    /// configuration names its plant folder).
    Gateway(gateway::GatewayArgs),
    /// Measure the gateway on loopback, over Modbus TCP (pymodbus plant) and OPC UA
    /// (asyncua plant) in the same run: cycle rate, jitter, sensor-to-output latency.
    GatewayBench {
        #[command(flatten)]
        plant: PlantOpt,
        #[command(flatten)]
        args: gateway::BenchArgs,
    },
    /// Write the observers, the filter and the task monitors as IEC 61131-3 Structured
    /// Text (function blocks and a program to call at the end of the PLC cycle).
    ExportSt {
        #[command(flatten)]
        plant: PlantArg,
        /// Write to this file instead of the standard output.
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Write the region monitor of stopwatch automata (`*.swa.ron`) or of a plant's
    /// `tasks.ron`, from its committed regions, as IEC 61131-3: SFC in PLCopen XML
    /// (`X.sfc.xml`) and an ST function block (`X.monitor.st`).
    ExportSfc {
        /// `tasks.ron` or `*.swa.ron` (its regions file beside it).
        file: PathBuf,
        /// Write the two files in this folder instead of beside FILE.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// A FIP-like fieldbus (`bus.ron`): its scan table, the load of each elementary
    /// cycle, and each variable's transaction time and best and worst age at its
    /// consumers, with what its deadline leaves the live link.
    Bus {
        /// The bus file.
        file: PathBuf,
        /// Print the analysis as JSON.
        #[arg(long)]
        json: bool,
    },
    /// A stochastic timed Petri net (seed 002): its probabilistic state graph, its
    /// terminal components and steady state, and with `--failed PLACE` the mean time to
    /// a first failure (exact rationals).
    Stpn {
        /// The net file.
        file: PathBuf,
        /// The variant: flags of the net to set (`--with write_loss,sync_loss`).
        #[arg(long, value_delimiter = ',')]
        with: Vec<String>,
        /// A place whose marking is a failure: report the MTFF to it.
        #[arg(long)]
        failed: Option<String>,
        /// Places whose marking is observed: report the abstract view on those states
        /// (`[mean time, probability]` from each to the next one reached).
        #[arg(long, value_delimiter = ',')]
        observe: Vec<String>,
        /// Print the state graph as JSON.
        #[arg(long)]
        json: bool,
    },
    /// The monitoring regions E* of timed tasks (seed 000): the stopwatch automata of a
    /// `tasks.ron` (or a `*.swa.ron`), their product, and per location the valuations
    /// from which every task in progress can still finish acceptably. Writes
    /// `regions.ron` beside a `tasks.ron` (`X.regions.ron` beside `X.swa.ron`), which
    /// the plant's task monitor then runs.
    Synthesize {
        /// `tasks.ron`, `*.swa.ron` or a stopwatch Petri net `*.swpn.ron`.
        file: PathBuf,
        /// Write the regions here instead.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write nothing; fail when the regions file is not what the automata give.
        #[arg(long)]
        check: bool,
        /// Bound of each fixed point, in polyhedra processed (V1502 beyond).
        #[arg(long, default_value_t = 20_000)]
        limit: usize,
        /// Polyhedra kept per location before its union is replaced by a template hull
        /// (an over-approximation); `--check` needs the value the file was written with.
        #[arg(long, default_value_t = 4)]
        members: usize,
    },
    /// The PLC's own program in PLCopen TC6 XML: write a control program for the PLC's
    /// tool, or read one (SFC, ST, LD) and check it against the plant.
    Program {
        #[command(subcommand)]
        action: program::ProgramCmd,
    },
    /// Measure the stochastic Petri nets (seed 002): per net and variant, the state
    /// graph's size, the median time to build it and the time of its analyses.
    BenchStpn {
        /// The net files (by default those of `layouts/substation/nets/`).
        nets: Vec<PathBuf>,
        /// Builds per variant; the median is reported.
        #[arg(long, default_value_t = 5)]
        repeat: usize,
    },
    /// Measure the stopwatch synthesis: time and product size against the number of
    /// interruptible tasks (1 to N, independent, α = 3 s, β = 4 s, γ = 5 s); a size is
    /// not run once the one before took longer than the budget.
    BenchSynthesis {
        /// Largest number of tasks.
        #[arg(long, default_value_t = 8)]
        max_tasks: usize,
        /// Seconds a size may take before the larger ones are skipped.
        #[arg(long, default_value_t = 60.0)]
        budget: f64,
    },
    /// Measure the console: CPU time per frame at 1x (headless egui, no GPU) and memory
    /// over a simulated hour at 100x.
    BenchConsole {
        #[command(flatten)]
        plant: PlantOpt,
        /// Frames timed.
        #[arg(long, default_value_t = 600)]
        frames: usize,
        /// Skip the simulated hour.
        #[arg(long)]
        no_memory: bool,
    },
    /// Run a campaign and print its figures.
    Campaign {
        #[command(subcommand)]
        kind: campaign::CampaignCmd,
    },
    /// Verify the constraint set on the abstract plant model (safety, permissiveness,
    /// invariants, necessity), optionally against SPIN, with benchmarks.
    Verify(verify::VerifyArgs),
    /// The diagnosers: learn their intervals, report diagnosability, measure them.
    Diagnose {
        #[command(subcommand)]
        action: DiagnoseCmd,
    },
    /// OPC UA: Vigie's certificate, the peers' certificates it trusts, password hashes
    /// for the users of its server.
    Opcua {
        #[command(subcommand)]
        action: gateway::OpcuaAction,
    },
    /// The console's user accounts (roles, argon2id password hashes in
    /// `users.ron` of the data folder).
    User {
        #[command(subcommand)]
        action: UserAction,
    },
    /// Measure the historian: a durable journal insert, recording a week of process
    /// history at the plant's cycle, and trend queries over it.
    BenchHistorian {
        #[command(flatten)]
        plant: PlantOpt,
        #[command(flatten)]
        args: bench_historian::Args,
    },
    /// Measure the closed loop against the plant's size: generated lines of 1, 10 and
    /// 100 stations (simulated / wall time, cost per component).
    BenchLine(bench_line::Args),
    /// Measure the engines and print the figures.
    Bench {
        #[command(flatten)]
        plant: PlantOpt,
        /// Number of timed repetitions per figure.
        #[arg(long, default_value_t = 200_000)]
        iterations: u32,
    },
    /// Explain a problem code (V…), an explanation item's code (X…) or a task alarm's
    /// code (T…): its page of the catalogue (`docs/codes/`).
    Explain {
        /// The code, e.g. V0301, X101 or T003.
        code: String,
    },
    /// Print the shell completion script of `vigie` (bash, zsh, fish, elvish,
    /// powershell) to the standard output.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Write the manual pages of `vigie` and of each command (roff) into a folder.
    Man {
        /// The folder (created if needed).
        #[arg(long, default_value = "man")]
        out: PathBuf,
    },
}

/// What `vigie diagnose` does.
#[derive(clap::Subcommand, Debug)]
pub(crate) enum DiagnoseCmd {
    /// Learn the diagnosers' intervals from normal-run traces into `diagnosers.ron`.
    Learn {
        #[command(flatten)]
        plant: PlantOpt,
        /// Trace files (CSV, `vigie run --headless --trace`).
        #[arg(required = true)]
        traces: Vec<PathBuf>,
        /// Confidence coefficient α of ΔT = α·σ (default: the file's).
        #[arg(long)]
        alpha: Option<f64>,
        /// Print the figures without writing the file.
        #[arg(long)]
        dry_run: bool,
    },
    /// Derive the diagnosers of a plant of components from its axes into
    /// `diagnosers.ron` (a file written by hand is never replaced).
    Derive {
        #[command(flatten)]
        plant: PlantOpt,
        /// Print the file instead of writing it.
        #[arg(long)]
        stdout: bool,
    },
    /// Print the diagnosability report (JSON).
    Report {
        #[command(flatten)]
        plant: PlantOpt,
    },
    /// Measure the diagnosers (per cycle, build) and libFAUDES' centralized diagnoser.
    Bench {
        #[command(flatten)]
        plant: PlantOpt,
    },
}

/// A role of the console, for `vigie user add`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(crate) enum RoleArg {
    /// Production operator.
    Operator,
    /// Maintenance technician: program edits, filter mode, bypasses.
    Maintenance,
    /// Trainer: exercises and faults.
    Trainer,
    /// Everything, and the accounts.
    Administrator,
}

/// What `vigie user` does.
#[derive(clap::Subcommand, Debug)]
pub(crate) enum UserAction {
    /// Add an account, or replace its role and password; the password is the first
    /// line of standard input (at least 8 characters), never an argument.
    Add {
        /// Login name (one word).
        name: String,
        /// The account's role.
        #[arg(long, value_enum)]
        role: RoleArg,
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
            let role = match role {
                RoleArg::Operator => vigie_core::access::Role::Operator,
                RoleArg::Maintenance => vigie_core::access::Role::Maintenance,
                RoleArg::Trainer => vigie_core::access::Role::Trainer,
                RoleArg::Administrator => vigie_core::access::Role::Administrator,
            };
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

/// Runs the parsed command line.
pub(crate) fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    let Some(command) = cli.command else {
        return open_console(&cli.console.plant.plant, None, &cli.console.console);
    };
    match command {
        Command::Console(c) => open_console(&c.plant.plant, None, &c.console),
        Command::User { action } => user(action),
        Command::Opcua { action } => gateway::opcua(action),
        Command::Check { plant, json } => check::run(&plant.plant, json),
        Command::Filter {
            plant,
            trace,
            reset_after_trip,
            explain,
            cold_start,
        } => filter::run(&plant.plant, &trace, reset_after_trip, explain, cold_start),
        Command::Gateway(args) => gateway::run(&args),
        Command::GatewayBench { plant, args } => gateway::bench(&plant.plant, &args),
        Command::Diagnose { action } => match action {
            DiagnoseCmd::Learn {
                plant,
                traces,
                alpha,
                dry_run,
            } => learn::learn(&plant.plant, &traces, alpha, dry_run),
            DiagnoseCmd::Derive { plant, stdout } => learn::derive(&plant.plant, stdout),
            DiagnoseCmd::Report { plant } => learn::report(&plant.plant),
            DiagnoseCmd::Bench { plant } => learn::bench(&plant.plant),
        },
        Command::Bench { plant, iterations } => bench::run(&plant.plant, iterations),
        Command::BenchHistorian { plant, args } => bench_historian::run(&plant.plant, &args),
        Command::BenchLine(args) => bench_line::run(&args),
        Command::ExportSt { plant, out } => export_st::run(&plant.plant, out.as_deref()),
        Command::ExportSfc { file, out } => export_sfc::run(&file, out.as_deref()),
        Command::Program { action } => program::run(action),
        Command::Bus { file, json } => bus::run(&file, json),
        Command::Stpn {
            file,
            with,
            failed,
            observe,
            json,
        } => stpn::run(&file, &with, failed.as_deref(), &observe, json),
        Command::Synthesize {
            file,
            out,
            check,
            limit,
            members,
        } => synthesize::run(&file, out.as_deref(), check, limit, members),
        Command::BenchStpn { nets, repeat } => stpn::bench(&nets, repeat),
        Command::BenchSynthesis { max_tasks, budget } => {
            synthesize::bench(max_tasks, budget);
            Ok(ExitCode::SUCCESS)
        }
        Command::BenchConsole {
            plant,
            frames,
            no_memory,
        } => bench_console(&plant.plant, frames, no_memory),
        Command::Campaign { kind } => campaign::dispatch(kind),
        Command::Verify(args) => verify::run(&args),
        Command::Run {
            scenario,
            headless,
            trace,
            no_timing,
            console,
        } => {
            if headless {
                run::run(&scenario, trace.as_deref(), !no_timing)
            } else {
                // The console finds the plant folder from the scenario.
                open_console(
                    std::path::Path::new(DEFAULT_PLANT),
                    Some(scenario),
                    &console,
                )
            }
        }
        Command::Explain { code } => match vigie_core::diag::codes::explain(&code) {
            Some(page) => {
                print!("{page}");
                Ok(ExitCode::SUCCESS)
            }
            None => anyhow::bail!(
                "no code `{}` in the catalogue (V…: problems, X…: explanation items, T…: task alarms; docs/codes/)",
                code.trim()
            ),
        },
        Command::Completions { shell } => {
            let mut cmd = <Cli as clap::CommandFactory>::command();
            clap_complete::generate(shell, &mut cmd, "vigie", &mut std::io::stdout());
            Ok(ExitCode::SUCCESS)
        }
        Command::Man { out } => man(&out),
    }
}

/// `vigie bench-console`.
fn bench_console(
    plant: &std::path::Path,
    frames: usize,
    no_memory: bool,
) -> anyhow::Result<ExitCode> {
    let opts = vigie_app::ConsoleOptions::new(plant);
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

/// `vigie man`: `vigie.1` and one page per command (`vigie-check.1`…) into `out`.
fn man(out: &std::path::Path) -> anyhow::Result<ExitCode> {
    fn write(cmd: &clap::Command, name: &str, out: &std::path::Path) -> anyhow::Result<()> {
        let cmd = cmd.clone().name(name.to_string());
        let mut page = Vec::new();
        clap_mangen::Man::new(cmd.clone()).render(&mut page)?;
        let path = out.join(format!("{name}.1"));
        std::fs::write(&path, page)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
        for sub in cmd.get_subcommands().filter(|s| s.get_name() != "help") {
            write(sub, &format!("{name}-{}", sub.get_name()), out)?;
        }
        Ok(())
    }
    std::fs::create_dir_all(out)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", out.display()))?;
    let mut cmd = <Cli as clap::CommandFactory>::command();
    cmd.build();
    write(&cmd, "vigie", out)?;
    println!("manual pages written to {}", out.display());
    Ok(ExitCode::SUCCESS)
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
