//! `vigie gateway CONFIG`: the live link as a headless service (monitor, gateway or
//! emulator mode, from the configuration file). Logs go to stderr through `tracing`
//! (`RUST_LOG`-style level with `--log`); events go to stdout as JSON lines. SIGINT and
//! SIGTERM stop it cleanly, with the outputs driven to the safe state first.

use crate::live::runtime::{self, CycleStats};
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `vigie gateway`.
#[derive(clap::Args, Debug)]
pub(crate) struct GatewayArgs {
    /// The gateway configuration (RON), e.g. layouts/sorting-station/gateway-monitor.ron.
    pub(crate) config: PathBuf,
    /// Log level: error, warn, info, debug or trace.
    #[arg(long, default_value = "info")]
    pub(crate) log: String,
}

pub(crate) fn init_tracing(level: &str) {
    let level = level.parse().unwrap_or(tracing::Level::INFO);
    let _ = tracing_subscriber::fmt()
        .with_max_level(level)
        .with_writer(std::io::stderr)
        .with_ansi(false)
        .try_init();
}

/// Resolves on SIGINT or SIGTERM.
async fn stop_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        match signal(SignalKind::terminate()) {
            Ok(mut term) => {
                tokio::select! {
                    _ = tokio::signal::ctrl_c() => {}
                    _ = term.recv() => {}
                }
            }
            Err(e) => {
                tracing::warn!("cannot watch SIGTERM: {e}");
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = tokio::signal::ctrl_c().await;
    }
    tracing::info!("stop requested");
}

pub(crate) fn run(args: &GatewayArgs) -> anyhow::Result<ExitCode> {
    init_tracing(&args.log);
    let setup = runtime::load(&args.config)?;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let mut emit = |line: serde_json::Value| {
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "{line}");
        let _ = out.flush();
    };
    let mut stats = CycleStats::default();
    rt.block_on(runtime::run(setup, stop_signal(), &mut emit, &mut stats))?;
    Ok(ExitCode::SUCCESS)
}
