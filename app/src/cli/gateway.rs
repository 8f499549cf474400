//! `vigie gateway CONFIG`: the live link as a headless service (monitor, gateway or
//! emulator mode, from the configuration file). Logs go to stderr through `tracing`
//! (`RUST_LOG`-style level with `--log`); events go to the historian in the state folder
//! (`vigie.sqlite`: journal, alarm history, process history) and, once committed, to
//! stdout as JSON lines. Neither stderr nor stdout can block
//! the service: both are written by threads of their own through bounded, lossy
//! queues (a reader that stalls loses lines, counted; the journal loses none). SIGINT
//! and SIGTERM stop it cleanly, with the outputs driven to the safe state first.

use std::path::PathBuf;
use std::process::ExitCode;
use vigie_app::live::runtime::{self, CycleStats};
use vigie_app::live::sink::{EventSink, LiveHistory, SinkHistorian};

/// Arguments of `vigie gateway`.
#[derive(clap::Args, Debug)]
pub(crate) struct GatewayArgs {
    /// The gateway configuration (RON), e.g. layouts/sorting-station/gateway-monitor.ron.
    pub(crate) config: PathBuf,
    /// Monitor mode: the program the PLC should run (RON or PLCopen XML), followed
    /// beside it; a `program_divergence` event and alarm when the PLC's outputs leave
    /// its runs. Start it with the PLC's program in its initial situation.
    #[arg(long, value_name = "FILE")]
    pub(crate) program: Option<PathBuf>,
    /// Log level.
    #[arg(long, value_enum, default_value_t = LogLevel::Info)]
    pub(crate) log: LogLevel,
}

/// How much the gateway logs on stderr.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LogLevel {
    /// Errors only.
    Error,
    /// And warnings.
    Warn,
    /// And what the link does (default).
    Info,
    /// And details.
    Debug,
    /// Everything.
    Trace,
}

/// Logs to stderr through a thread of their own (lossy when nobody reads stderr); keep
/// the guard for the whole run, it flushes what is left when dropped.
pub(crate) fn init_tracing(level: LogLevel) -> tracing_appender::non_blocking::WorkerGuard {
    let level = match level {
        LogLevel::Error => tracing::Level::ERROR,
        LogLevel::Warn => tracing::Level::WARN,
        LogLevel::Info => tracing::Level::INFO,
        LogLevel::Debug => tracing::Level::DEBUG,
        LogLevel::Trace => tracing::Level::TRACE,
    };
    let (writer, guard) = tracing_appender::non_blocking::NonBlockingBuilder::default()
        .lossy(true)
        .thread_name("vigie-log")
        .finish(std::io::stderr());
    // async-opcua reports every endpoint and handshake at info: its own lines show
    // from warnings up unless the run asks for debug.
    let opcua = if level >= tracing::Level::DEBUG {
        level
    } else {
        level.min(tracing::Level::WARN)
    };
    let targets = tracing_subscriber::filter::Targets::new()
        .with_default(level)
        .with_target("opcua", opcua)
        // "Endpoint config contains no endpoints": Vigie names its endpoint per session.
        .with_target("opcua_client::config", level.min(tracing::Level::ERROR));
    use tracing_subscriber::layer::SubscriberExt as _;
    use tracing_subscriber::util::SubscriberInitExt as _;
    let _ = tracing_subscriber::fmt()
        .with_max_level(level)
        .with_writer(writer)
        .with_ansi(false)
        .finish()
        .with(targets)
        .try_init();
    guard
}

/// Resolves on SIGINT or SIGTERM; the handlers are installed by the call (inside the
/// runtime), before the configuration is loaded.
fn stop_signal(rt: &tokio::runtime::Runtime) -> impl std::future::Future<Output = ()> {
    let signal = {
        let _inside = rt.enter();
        vigie_app::live::stop_signal()
    };
    async move {
        signal.await;
        tracing::info!("stop requested");
    }
}

pub(crate) fn run(args: &GatewayArgs) -> anyhow::Result<ExitCode> {
    let _log = init_tracing(args.log);
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let stop = stop_signal(&rt);
    let mut setup = runtime::load(&args.config)?;
    if let Some(p) = &args.program {
        setup.follow_program(p)?;
    }
    let signals = vigie_app::historian::writer::signal_names(&setup.bundle.symbols);
    let plant = setup.bundle.dir.display().to_string();
    let (sink, thread) = EventSink::start(Some(SinkHistorian {
        dir: &setup.state_dir,
        plant: &plant,
        signals: &signals,
        retention: setup.config.retention,
    }))?;
    setup.history = Some(LiveHistory::new(signals.len(), sink.clone()));
    let result = {
        let mut emit = move |line: serde_json::Value| sink.emit(line);
        let mut stats = CycleStats::default();
        rt.block_on(runtime::run(setup, stop, &mut emit, &mut stats, None))
    };
    thread.finish();
    result?;
    Ok(ExitCode::SUCCESS)
}

/// Arguments of `vigie gateway-bench`.
#[derive(clap::Args, Debug)]
pub(crate) struct BenchArgs {
    /// Sensor edges to time.
    #[arg(long, default_value_t = 200)]
    pub(crate) edges: usize,
    /// Print JSON instead of text.
    #[arg(long)]
    pub(crate) json: bool,
    /// Run the gateway's cycle thread at this real-time priority (SCHED_FIFO, 1-99;
    /// needs root or CAP_SYS_NICE), as `cycle_priority` in a gateway configuration;
    /// without it every thread runs at normal priority (`realtime: false`).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=99))]
    pub(crate) rt_priority: Option<u8>,
    /// Busy background processes running beside the bench (a fixed load).
    #[arg(long, default_value_t = 0)]
    pub(crate) load: usize,
    /// Keep timing edges until this many seconds have passed (at least `--edges`).
    #[arg(long, default_value_t = 0)]
    pub(crate) seconds: u64,
    /// Run the peers (pymodbus plant, PLC, probe) at real-time priority 40 when
    /// permitted: they stand for devices of their own that the load must not starve.
    #[arg(long)]
    pub(crate) rt_peers: bool,
    /// The protocol of both sides of the gateway; `both` (the default) measures Modbus
    /// TCP then OPC UA in the same run.
    #[arg(long, value_enum, default_value_t = BenchProtocol::Both)]
    pub(crate) protocol: BenchProtocol,
}

/// The protocols `vigie gateway-bench` measures.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BenchProtocol {
    /// Modbus TCP against pymodbus.
    Modbus,
    /// OPC UA against asyncua.
    Opcua,
    /// Both, one after the other in the same run, and their comparison.
    Both,
}

/// `vigie gateway-bench`: the gateway against a pymodbus plant (Modbus TCP) and an
/// asyncua plant (OPC UA) on loopback.
pub(crate) fn bench(plant: &std::path::Path, args: &BenchArgs) -> anyhow::Result<ExitCode> {
    use vigie_app::live::bench::Protocol;
    let _log = init_tracing(LogLevel::Warn);
    let protocols = match args.protocol {
        BenchProtocol::Modbus => vec![Protocol::Modbus],
        BenchProtocol::Opcua => vec![Protocol::OpcUa],
        BenchProtocol::Both => vec![Protocol::Modbus, Protocol::OpcUa],
    };
    let mut all = Vec::new();
    for protocol in protocols {
        let f = vigie_app::live::bench::run(
            plant,
            vigie_app::live::bench::Options {
                protocol,
                edges: args.edges,
                seconds: args.seconds,
                rt_priority: args.rt_priority,
                load: args.load,
                rt_peers: args.rt_peers,
            },
        )?;
        if args.json {
            println!("{}", serde_json::to_string(&f)?);
        } else {
            print_figures(&f, args);
        }
        all.push(f);
    }
    if let [m, o] = all.as_slice()
        && !args.json
    {
        println!("OPC UA against Modbus TCP in this run (p50 / p99):");
        println!(
            "  period jitter (ms)    {:.3} / {:.3}  against  {:.3} / {:.3}",
            o.jitter_ms[0], o.jitter_ms[1], m.jitter_ms[0], m.jitter_ms[1]
        );
        println!(
            "  sensor -> output (ms) {:.2} / {:.2}  against  {:.2} / {:.2}",
            o.latency_ms[0], o.latency_ms[1], m.latency_ms[0], m.latency_ms[1]
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn print_figures(f: &vigie_app::live::bench::Figures, args: &BenchArgs) {
    let peer = match f.protocol {
        vigie_app::live::bench::Protocol::Modbus => "Modbus TCP, against pymodbus",
        vigie_app::live::bench::Protocol::OpcUa => "OPC UA (security None), against asyncua",
    };
    println!(
        "gateway {peer} on loopback, 10 ms cycle, {} cycles over {:.0} s, {} busy background processes, cycle thread {}",
        f.cycles,
        f.seconds,
        f.load,
        args.rt_priority.map_or_else(
            || "at normal priority".to_string(),
            |p| format!("at real-time priority {p} (if granted, see the log)")
        )
    );
    println!("  peers                 {} priority", f.peers);
    println!("  cycle rate            {:.2} Hz", f.rate_hz);
    println!(
        "  period jitter (ms)    p50 {:.3}  p99 {:.3}  max {:.3}",
        f.jitter_ms[0], f.jitter_ms[1], f.jitter_ms[2]
    );
    println!(
        "  cycle work (ms)       p50 {:.3}  p99 {:.3}  max {:.3}",
        f.busy_ms[0], f.busy_ms[1], f.busy_ms[2]
    );
    println!(
        "  sensor -> output (ms) p50 {:.2}  p99 {:.2}  max {:.2}  ({} edges)",
        f.latency_ms[0], f.latency_ms[1], f.latency_ms[2], f.edges
    );
    println!(
        "  false link alarms     {}   (safe outputs for stale inputs: {})",
        f.false_alarms.len(),
        f.stale_holds
    );
    for a in &f.false_alarms {
        println!("    {a}");
    }
}

/// `vigie opcua …`.
#[derive(clap::Subcommand, Debug)]
pub(crate) enum OpcuaAction {
    /// Vigie's application certificate for the run of CONFIG (created on first use, in
    /// the state folder's `pki/own/cert.der`): its path and thumbprint, to give to the
    /// peer's administrator, who must trust it.
    Cert {
        /// The gateway configuration.
        config: PathBuf,
    },
    /// Trusts a peer's certificate (DER or PEM) for the run of CONFIG: copied to the
    /// PKI's `trusted/` folder (and out of `rejected/`).
    Trust {
        /// The gateway configuration.
        config: PathBuf,
        /// The peer's certificate.
        cert: PathBuf,
    },
    /// Reads a password on stdin and prints its argon2id hash, for `users` in an
    /// `OpcUa` server section.
    HashPassword,
}

pub(crate) fn opcua(action: OpcuaAction) -> anyhow::Result<ExitCode> {
    let pki = |config: &std::path::Path| -> anyhow::Result<PathBuf> {
        let c = vigie_core::live::config::GatewayConfig::load(config)
            .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
        Ok(vigie_app::live::opcua_pki(&runtime::state_dir(&c, config)))
    };
    match action {
        OpcuaAction::Cert { config } => {
            let dir = pki(&config)?;
            let (path, thumbprint) = vigie_app::live::opcua_certificate(&dir)?;
            println!("certificate {}", path.display());
            println!("thumbprint {thumbprint}");
            println!("trusted {}", dir.join("trusted").display());
            println!("rejected {}", dir.join("rejected").display());
        }
        OpcuaAction::Trust { config, cert } => {
            let dir = pki(&config)?;
            let path = vigie_app::live::opcua_trust(&dir, &cert)?;
            println!("trusted {}", path.display());
        }
        OpcuaAction::HashPassword => {
            use argon2::password_hash::{PasswordHasher as _, SaltString, rand_core::OsRng};
            let mut password = String::new();
            std::io::stdin().read_line(&mut password)?;
            let password = password.trim_end_matches(['\n', '\r']);
            if password.is_empty() {
                anyhow::bail!("empty password: type it on stdin");
            }
            let salt = SaltString::generate(&mut OsRng);
            let hash = argon2::Argon2::default()
                .hash_password(password.as_bytes(), &salt)
                .map_err(|e| anyhow::anyhow!("cannot hash the password: {e}"))?;
            println!("{hash}");
        }
    }
    Ok(ExitCode::SUCCESS)
}
