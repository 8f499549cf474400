//! The service loops of `vigie gateway`: monitor, gateway and emulator. Each runs one
//! cycle per `cycle_ms` until `shutdown` resolves, reports through `emit` (one JSON
//! object per event: listening, alarm, alarm_cleared, trip, violation,
//! potential_violation, safe_outputs, safe_outputs_released, diagnosis, stopped) and logs through
//! `tracing`; with a [`Tap`], every cycle and the link state also go to the console.
//!
//! Monitor and gateway cycles run on a thread of their own at absolute deadlines, the
//! Modbus client on a tokio task (see `cycle.rs`): the network never delays a cycle.
//!
//! ## Gateway cycle
//! 1. Take the plant's latest values (polled just before the tick by the I/O task,
//!    each stamped with its read time).
//! 2. Take the PLC's commanded coils from the server image.
//! 3. Run the engine (observers, filter in enforce mode) on the last values read.
//! 4. Safe outputs: if the PLC or the plant has been silent for `link_timeout_cycles`
//!    cycles, the outputs are the quantified filter's fallback (whatever the PLC
//!    commands); otherwise, if inputs are stale and some constraint is potentially
//!    violated by the applied outputs for some value of them, the quantified fallback
//!    too (see `vigie_core::live::stale`). An alarm stays raised while this lasts.
//! 5. Diagnosers (when the plant has `diagnosers.ron` and the configuration does not
//!    say `diagnosers: false`): they follow the inputs and the outputs of step 4 and
//!    write their flags, intervals and estimates for the rewritten constraints of the
//!    next cycle, as in the simulation (`vigie_core::sim::diagnosis`); a certain
//!    diagnosis is a `diagnosis` event and a `diag:` alarm.
//! 6. Hand the outputs to the I/O task, which writes them at once; publish the sensors
//!    to the PLC (a sensor whose partition is flagged as its estimate, as the
//!    simulation's program reads it in degraded mode).
//!
//! A plant silent for `link_timeout_cycles` cycles raises the `link:plant` alarm and
//! step 4 holds the safe outputs, written at once if the plant is still connected (its
//! values unreadable) or as soon as the link returns (the client reconnects with
//! backoff); the diagnosers are not stepped while it is lost. Task monitors follow the
//! filter, as in the console. On shutdown the outputs go to the fallback of the current
//! context (every output 0 when none exists); the `stopped` event carries the certain
//! diagnoses of the run.

use super::backend::{EmulatorBackend, IoBackend};
use super::tap::{LinkAlarm, Tap};
use anyhow::Context as _;
use serde_json::json;
use std::future::Future;

use std::time::{Duration, Instant};
use tokio::time::MissedTickBehavior;
use vigie_core::alarms::{AlarmKind, AlarmList, AlarmText};
use vigie_core::bundle::PlantBundle;
use vigie_core::engine::{Engine, Event};
use vigie_core::live::LinkMap;
use vigie_core::live::age::Transition;
use vigie_core::live::config::{GatewayConfig, Mode};
use vigie_core::live::iomap::IoMap;
use vigie_core::pop::build::Compiled;
use vigie_core::symbols::Space;
use vigie_core::{Bits, Millis};

/// Where events go.
pub type Emit<'a> = &'a mut (dyn FnMut(serde_json::Value) + Send);

/// Start times and busy times of the cycles (for the benchmark).
#[derive(Clone, Debug, Default)]
pub struct CycleStats {
    /// When each cycle started.
    pub(crate) starts: Vec<Instant>,
    /// How long each cycle's work took.
    pub(crate) busy: Vec<Duration>,
}

impl CycleStats {
    const CAP: usize = 500_000;

    pub(crate) fn record(&mut self, start: Instant) {
        if self.starts.len() < Self::CAP {
            self.starts.push(start);
            self.busy.push(start.elapsed());
        }
    }
}

/// Milliseconds since the start of the run: the only clock of the service.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Clock(pub(crate) Instant);

impl Clock {
    pub(crate) fn now(&self) -> Millis {
        self.at(Instant::now())
    }

    pub(crate) fn at(&self, t: Instant) -> Millis {
        Millis(u64::try_from(t.saturating_duration_since(self.0).as_millis()).unwrap_or(u64::MAX))
    }
}

/// Everything a run needs, loaded and checked.
pub struct Setup {
    /// The configuration.
    pub config: GatewayConfig,
    /// The plant (with the diagnosers: auxiliaries declared, constraints rewritten for
    /// the cooperation).
    pub bundle: PlantBundle,
    /// Where the client finds the signals (monitor, gateway): the I/O map (Modbus) or
    /// the node map (OPC UA).
    pub client_map: Option<LinkMap>,
    /// Where the server serves them (gateway, emulator): the I/O map (Modbus); `None`
    /// for OPC UA, whose server publishes the plant's own address space.
    pub server_map: Option<LinkMap>,
    /// The compiled diagnosers, when the run steps them
    /// ([`GatewayConfig::runs_diagnosers`]).
    pub diagnosers: Option<Compiled>,
    /// Where the run keeps its journal and its latched trip
    /// ([`GatewayConfig::state_dir`], or its default).
    pub state_dir: std::path::PathBuf,
    /// Where the monitor and gateway cycles record the process history (`vigie
    /// gateway` sets it; the console following a link keeps its own).
    pub history: Option<super::sink::LiveHistory>,
    /// The program the PLC should be running (`--program`): the monitor follows it
    /// beside the PLC and alarms when the PLC's outputs leave its runs
    /// ([`vigie_core::live::follow`]).
    pub program: Option<std::sync::Arc<vigie_core::control::CompiledProgram>>,
}

impl Setup {
    /// Follows `file` (RON or PLCopen XML) beside the PLC; monitor mode only (a
    /// gateway's PLC is served by Vigie, an emulator run has no PLC to follow).
    pub fn follow_program(&mut self, file: &std::path::Path) -> anyhow::Result<()> {
        if self.config.mode != Mode::Monitor {
            anyhow::bail!(
                "--program follows the PLC in monitor mode; {} is not a monitor configuration",
                file.display()
            );
        }
        let compiled = vigie_core::control::CompiledProgram::load(file, &self.bundle.plant)
            .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
        self.program = Some(std::sync::Arc::new(compiled));
        Ok(())
    }
}

/// The state folder of the configuration at `path`: its `state_dir`, else the data
/// folder's `gateway/<file stem>`.
pub fn state_dir(config: &GatewayConfig, path: &std::path::Path) -> std::path::PathBuf {
    config.state_dir.clone().unwrap_or_else(|| {
        let stem = path
            .file_stem()
            .map_or_else(|| "gateway".into(), |s| s.to_string_lossy().into_owned());
        crate::console::journal::data_dir_from_env()
            .join("gateway")
            .join(stem)
    })
}

/// Loads the configuration, the plant folder (with its diagnosers when the run steps
/// them) and the I/O map.
pub fn load(path: &std::path::Path) -> anyhow::Result<Setup> {
    let render = vigie_core::diag::render;
    let config = GatewayConfig::load(path).map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    let (bundle, diagnosers) = load_plant(&config)?;
    for w in &config.warnings {
        tracing::warn!("{w}");
    }
    let (client_map, server_map) = load_maps(&config, &bundle.plant)?;
    Ok(Setup {
        state_dir: state_dir(&config, path),
        config,
        bundle,
        client_map,
        server_map,
        diagnosers,
        history: None,
        program: None,
    })
}

/// The maps of the client and of the server: the I/O map for a Modbus side (loaded
/// once), the node map for an OPC UA client (`node_map`, else the plant folder's
/// `node-map.ron`, else the address space Vigie serves for the plant).
pub fn load_maps(
    config: &GatewayConfig,
    plant: &vigie_core::plant::Plant,
) -> anyhow::Result<(Option<LinkMap>, Option<LinkMap>)> {
    use vigie_core::live::config::{ClientLink, ServerLink};
    use vigie_core::live::nodemap::{NodeMap, plant_namespace};
    let render = vigie_core::diag::render;
    let modbus = matches!(config.client, Some(ClientLink::Modbus(_)))
        || matches!(config.server, Some(ServerLink::Modbus(_)));
    let io = if modbus {
        let (map, warnings) = IoMap::load(&config.io_map_path(), plant)
            .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
        for w in &warnings {
            tracing::warn!("{w}");
        }
        Some(map)
    } else {
        None
    };
    let client = match &config.client {
        Some(ClientLink::Modbus(_)) => io.clone().map(LinkMap::Modbus),
        Some(ClientLink::OpcUa(_)) => Some(LinkMap::OpcUa(match config.node_map_path() {
            Some(path) => {
                let (map, warnings) =
                    NodeMap::load(&path, plant).map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
                for w in &warnings {
                    tracing::warn!("{w}");
                }
                map
            }
            None => NodeMap::from_plant(plant, &plant_namespace(&config.plant), config.cycle_ms),
        })),
        None => None,
    };
    let server = match &config.server {
        Some(ServerLink::Modbus(_)) => io.map(LinkMap::Modbus),
        _ => None,
    };
    Ok((client, server))
}

/// The plant folder of `config`: with its diagnosers (`diagnosers.ron`, the constraints
/// rewritten) when the monitor or gateway cycles step them, as they run in the
/// simulation; plain otherwise.
pub fn load_plant(config: &GatewayConfig) -> anyhow::Result<(PlantBundle, Option<Compiled>)> {
    let render = vigie_core::diag::render;
    let dir = &config.plant;
    if config.runs_diagnosers() {
        let db = vigie_core::sim::diagnosis::load(dir).map_err(|p| {
            anyhow::anyhow!(
                "cannot load the diagnosers of {} (`diagnosers: false` in the configuration runs without them):\n{}",
                dir.display(),
                render(&p)
            )
        })?;
        return Ok((db.bundle, Some(db.compiled)));
    }
    let (bundle, problems) = PlantBundle::load(dir)
        .map_err(|p| anyhow::anyhow!("cannot load plant {}:\n{}", dir.display(), render(&p)))?;
    if problems.iter().any(vigie_core::diag::Problem::is_error) {
        anyhow::bail!("plant {} has errors:\n{}", dir.display(), render(&problems));
    }
    Ok((bundle, None))
}

/// Runs the configured mode until `shutdown`; `tap` (monitor and gateway) receives
/// every cycle and the link state for the console.
pub async fn run(
    setup: Setup,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
    tap: Option<Tap>,
) -> anyhow::Result<()> {
    match setup.config.mode {
        Mode::Monitor => super::cycle::monitor(setup, shutdown, emit, stats, tap).await,
        Mode::Gateway => super::cycle::gateway(setup, shutdown, emit, stats, tap).await,
        Mode::Emulator => emulator(setup, shutdown, emit, stats).await,
    }
}

fn ticker(cycle_ms: u64) -> tokio::time::Interval {
    let mut interval = tokio::time::interval(Duration::from_millis(cycle_ms.max(1)));
    interval.set_missed_tick_behavior(MissedTickBehavior::Skip);
    interval
}

pub(crate) fn bits_text(b: &Bits) -> String {
    b.to_string()
}

pub(crate) fn names(bundle: &PlantBundle, space: Space, bits: &Bits) -> Vec<String> {
    bits.ones()
        .map(|i| {
            bundle
                .symbols
                .name(space, u32::try_from(i).unwrap_or(0))
                .to_string()
        })
        .collect()
}

/// Alarms with their events.
pub(crate) struct AlarmBoard {
    pub(crate) alarms: AlarmList,
    pub(crate) tap: Option<Tap>,
}

impl AlarmBoard {
    pub(crate) fn raise(
        &mut self,
        emit: Emit<'_>,
        now: Millis,
        key: &str,
        kind: AlarmKind,
        text: impl Into<AlarmText>,
    ) {
        let text = text.into();
        let message = &text.message;
        tracing::error!(key, "{message}");
        emit(json!({
            "event": "alarm", "key": key, "message": message, "detail": text.detail,
            "priority": kind.priority(), "time_ms": now.0,
        }));
        if let Some(tap) = &self.tap {
            tap.alarm(LinkAlarm::Raised {
                key: key.to_string(),
                message: message.clone(),
                time: now,
            });
        }
        self.alarms.raise(now, key, kind, text);
    }

    pub(crate) fn clear(&mut self, emit: Emit<'_>, now: Millis, key: &str) {
        tracing::info!(key, "alarm cleared");
        emit(json!({"event": "alarm_cleared", "key": key, "time_ms": now.0}));
        if let Some(tap) = &self.tap {
            tap.alarm(LinkAlarm::Cleared {
                key: key.to_string(),
                time: now,
            });
        }
        self.alarms.clear(now, key);
    }

    pub(crate) fn watch(
        &mut self,
        emit: Emit<'_>,
        now: Millis,
        key: &str,
        what: &str,
        t: Option<Transition>,
    ) {
        match t {
            Some(Transition::Lost { last_heard }) => {
                let since = last_heard.map_or_else(
                    || "never heard".to_string(),
                    |t| format!("last heard at {t}"),
                );
                self.raise(
                    emit,
                    now,
                    key,
                    AlarmKind::Link,
                    format!("{what} lost ({since})"),
                );
            }
            Some(Transition::Restored) => self.clear(emit, now, key),
            None => {}
        }
    }
}

/// What the monitor needs to explain a trip: the plant, and its layout for the
/// projection (level 1) when the plant folder has one.
pub(crate) struct Explainer<'a> {
    pub(crate) bundle: &'a PlantBundle,
    pub(crate) layout: Option<&'a vigie_core::emulator::Layout>,
    /// The PLC's program followed beside it (`--program`), in its closest situation.
    pub(crate) program: Option<vigie_core::sim::Followed<'a>>,
}

/// Reports the engine's events; a specification error is reported when it changes only
/// (the engine repeats it every cycle while it lasts).
pub(crate) fn emit_engine_events(
    engine: &mut Engine,
    emit: Emit<'_>,
    explain: Option<&Explainer<'_>>,
    last_spec: &mut Option<String>,
) {
    let events = engine.drain_events();
    if !events
        .iter()
        .any(|e| matches!(e, Event::SpecificationError { .. }))
    {
        *last_spec = None;
    }
    for event in events {
        let (kind, index) = match event {
            Event::Trip { index } => ("trip", index),
            Event::Violation { index } => ("violation", index),
            Event::SpecificationError { message } => {
                if last_spec.as_ref() == Some(&message) {
                    continue;
                }
                *last_spec = Some(message.clone());
                tracing::error!("specification error: {message}");
                emit(json!({"event": "specification_error", "message": message}));
                continue;
            }
            Event::Reset => {
                emit(json!({"event": "reset"}));
                continue;
            }
        };
        let Some(trip) = engine.trips.get(index) else {
            continue;
        };
        let ids: Vec<&str> = trip.constraints.iter().map(|c| c.id.as_str()).collect();
        tracing::warn!(cycle = trip.cycle, "{kind}: {}", ids.join(", "));
        let mut line = json!({"event": kind, "record": trip});
        if let Some(x) = explain
            && let Some(ex) = vigie_core::sim::explain_live(
                engine,
                x.bundle,
                x.layout,
                index,
                (vigie_core::Millis(10_000), vigie_core::Millis(10)),
                x.program,
            )
        {
            line["explanation"] = serde_json::to_value(ex).unwrap_or_default();
        }
        emit(line);
    }
}

async fn emulator(
    setup: Setup,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
) -> anyhow::Result<()> {
    let Setup {
        config,
        bundle,
        client_map: _,
        server_map,
        diagnosers: _,
        state_dir,
        history: _,
        program: _,
    } = setup;
    let server_config = config
        .server
        .clone()
        .context("emulator mode needs a server section")?;
    // The plant folder's physical description, whatever it is: any plant is served.
    let description = vigie_core::machine::Description::load(&config.plant)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let emulator = vigie_core::machine::Physical::new(&description, &bundle.plant, config.seed)
        .map_err(|p| anyhow::anyhow!("{p}"))?;
    let pki = super::opcua::pki::folder(&state_dir);
    let serve = super::link::Serve {
        config: &config,
        server: &server_config,
        map: server_map.as_ref(),
        plant: &bundle.plant,
        pki: &pki,
    };
    serve_backend(&serve, EmulatorBackend(emulator), shutdown, emit, stats).await
}

/// Serves any backend: every cycle the outputs the PLC wrote go to the backend and the
/// backend's sensors to the image.
pub(crate) async fn serve_backend(
    serve: &super::link::Serve<'_>,
    mut backend: impl IoBackend,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
) -> anyhow::Result<()> {
    let n_out = serve.plant.outputs.len();
    let config = serve.config;
    let (shared, server) = super::link::serve_plc(serve, backend.read_inputs().clone()).await?;
    tracing::info!("serving on {}", server.address());
    emit(json!({
        "event": "listening", "address": server.local().to_string(), "endpoint": server.address(),
    }));
    let clock = Clock(Instant::now());
    let mut last = Millis::ZERO;
    let mut outputs = Bits::zeros(n_out);
    let mut interval = ticker(config.cycle_ms);
    tokio::pin!(shutdown);
    loop {
        tokio::select! {
            biased;
            () = &mut shutdown => break,
            _ = interval.tick() => {}
        }
        let start = Instant::now();
        let now = clock.now();
        if let Ok(s) = shared.lock() {
            outputs.copy_from(&s.outputs);
        }
        backend.write_outputs(now.saturating_sub(last), &outputs);
        last = now;
        if let Ok(mut s) = shared.lock() {
            s.inputs.copy_from(backend.read_inputs());
        }
        stats.record(start);
    }
    emit(json!({"event": "stopped"}));
    drop(server);
    Ok(())
}
