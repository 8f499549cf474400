//! The service loops of `vigie gateway`: monitor, gateway and emulator. Each runs one
//! cycle per `cycle_ms` until `shutdown` resolves, reports through `emit` (one JSON
//! object per event: listening, alarm, alarm_cleared, trip, violation,
//! potential_violation, safe_outputs, safe_outputs_released, stopped) and logs through
//! `tracing`.
//!
//! ## Gateway cycle
//! 1. Poll the plant's due blocks (values stamped with their read time).
//! 2. Take the PLC's commanded coils from the server image.
//! 3. Run the engine (observers, filter in enforce mode) on the last values read.
//! 4. Safe outputs: if the PLC has been silent for `link_timeout_cycles` cycles, the
//!    outputs are the quantified filter's fallback (whatever it commands); otherwise, if
//!    inputs are stale and some constraint is potentially violated by the applied
//!    outputs for some value of them, the quantified fallback too (see
//!    `vigie_core::live::stale`). An alarm stays raised while this lasts.
//! 5. Write the outputs to the plant; publish the sensors to the PLC.
//!
//! A plant silent for `link_timeout_cycles` cycles raises the `link:plant` alarm; its
//! inputs are stale by then or soon after, so step 4 holds the safe outputs, written as
//! soon as the link returns (the client reconnects with backoff). On shutdown the
//! outputs go to the fallback of the current context (every output 0 when none exists).

use super::backend::{EmulatorBackend, IoBackend};
use super::client::{Reader, Writer};
use super::server::{self, Shared, SharedImage};
use anyhow::Context as _;
use serde_json::json;
use std::future::Future;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::time::MissedTickBehavior;
use vigie_core::alarms::{AlarmKind, AlarmList};
use vigie_core::bundle::PlantBundle;
use vigie_core::engine::{Commanded, Engine, Event, FilterMode};
use vigie_core::live::age::{AgedBits, Transition, Watchdog};
use vigie_core::live::config::{GatewayConfig, Mode};
use vigie_core::live::image::ServerImage;
use vigie_core::live::iomap::IoMap;
use vigie_core::live::stale::StaleGuard;
use vigie_core::symbols::Space;
use vigie_core::{Bits, Millis};

/// Where events go.
pub(crate) type Emit<'a> = &'a mut (dyn FnMut(serde_json::Value) + Send);

/// Start times and busy times of the cycles (for the benchmark).
#[derive(Clone, Debug, Default)]
pub(crate) struct CycleStats {
    /// When each cycle started.
    pub(crate) starts: Vec<Instant>,
    /// How long each cycle's work took.
    pub(crate) busy: Vec<Duration>,
}

impl CycleStats {
    const CAP: usize = 500_000;

    fn record(&mut self, start: Instant) {
        if self.starts.len() < Self::CAP {
            self.starts.push(start);
            self.busy.push(start.elapsed());
        }
    }
}

/// Milliseconds since the start of the run: the only clock of the service.
struct Clock(Instant);

impl Clock {
    fn now(&self) -> Millis {
        self.at(Instant::now())
    }

    fn at(&self, t: Instant) -> Millis {
        Millis(u64::try_from(t.saturating_duration_since(self.0).as_millis()).unwrap_or(u64::MAX))
    }
}

/// Everything a run needs, loaded and checked.
pub(crate) struct Setup {
    /// The configuration.
    pub(crate) config: GatewayConfig,
    /// The plant.
    pub(crate) bundle: PlantBundle,
    /// The I/O map.
    pub(crate) map: IoMap,
}

/// Loads the configuration, the plant folder and the I/O map.
pub(crate) fn load(path: &std::path::Path) -> anyhow::Result<Setup> {
    let render = vigie_core::diag::render;
    let config = GatewayConfig::load(path).map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    let (bundle, problems) = PlantBundle::load(&config.plant).map_err(|p| {
        anyhow::anyhow!(
            "cannot load plant {}:\n{}",
            config.plant.display(),
            render(&p)
        )
    })?;
    if problems.iter().any(vigie_core::diag::Problem::is_error) {
        anyhow::bail!(
            "plant {} has errors:\n{}",
            config.plant.display(),
            render(&problems)
        );
    }
    let (map, warnings) = IoMap::load(&config.io_map_path(), &bundle.plant)
        .map_err(|p| anyhow::anyhow!("{}", render(&p)))?;
    for w in &warnings {
        tracing::warn!("{w}");
    }
    Ok(Setup {
        config,
        bundle,
        map,
    })
}

/// Runs the configured mode until `shutdown`.
pub(crate) async fn run(
    setup: Setup,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
) -> anyhow::Result<()> {
    match setup.config.mode {
        Mode::Monitor => monitor(setup, shutdown, emit, stats).await,
        Mode::Gateway => gateway(setup, shutdown, emit, stats).await,
        Mode::Emulator => emulator(setup, shutdown, emit, stats).await,
    }
}

fn ticker(cycle_ms: u64) -> tokio::time::Interval {
    let mut interval = tokio::time::interval(Duration::from_millis(cycle_ms.max(1)));
    interval.set_missed_tick_behavior(MissedTickBehavior::Skip);
    interval
}

fn bits_text(b: &Bits) -> String {
    b.to_string()
}

fn names(bundle: &PlantBundle, space: Space, bits: &Bits) -> Vec<String> {
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
struct AlarmBoard {
    alarms: AlarmList,
}

impl AlarmBoard {
    fn raise(&mut self, emit: Emit<'_>, now: Millis, key: &str, kind: AlarmKind, message: String) {
        tracing::error!(key, "{message}");
        emit(json!({"event": "alarm", "key": key, "message": message, "time_ms": now.0}));
        self.alarms.raise(now, key, kind, message);
    }

    fn clear(&mut self, emit: Emit<'_>, now: Millis, key: &str) {
        tracing::info!(key, "alarm cleared");
        emit(json!({"event": "alarm_cleared", "key": key, "time_ms": now.0}));
        self.alarms.clear(now, key);
    }

    fn watch(&mut self, emit: Emit<'_>, now: Millis, key: &str, what: &str, t: Option<Transition>) {
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

/// Reports the engine's events; a specification error is reported when it changes only
/// (the engine repeats it every cycle while it lasts).
/// What the monitor needs to explain a trip: the plant, and its layout for the
/// projection (level 1) when the plant folder has one.
struct Explainer<'a> {
    bundle: &'a PlantBundle,
    layout: Option<vigie_core::emulator::Layout>,
}

fn emit_engine_events(
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
                x.layout.as_ref(),
                index,
                vigie_core::Millis(10_000),
                vigie_core::Millis(10),
            )
        {
            line["explanation"] = serde_json::to_value(ex).unwrap_or_default();
        }
        emit(line);
    }
}

async fn monitor(
    setup: Setup,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
) -> anyhow::Result<()> {
    let Setup {
        config,
        bundle,
        map,
    } = setup;
    let client = config
        .client
        .clone()
        .context("monitor mode needs a client section")?;
    let clock = Clock(Instant::now());
    let peer = client.address;
    let mut link = Reader::new(client, map.clone(), true);
    let mut engine = Engine::new(&bundle, FilterMode::ReportOnly, 6000);
    let explainer = Explainer {
        bundle: &bundle,
        layout: vigie_core::emulator::Layout::load(&bundle.dir.join("layout.ron")).ok(),
    };
    let mut guard = StaleGuard::new(&bundle);
    let mut control = Commanded(Bits::zeros(bundle.plant.outputs.len()));
    let mut inputs = AgedBits::new(bundle.plant.inputs.len());
    let mut outputs = AgedBits::new(bundle.plant.outputs.len());
    let bounds = map.input_bounds();
    let mut dog = Watchdog::new(config.link_timeout(), Millis::ZERO);
    let mut board = AlarmBoard {
        alarms: AlarmList::new(),
    };
    let mut last_potential: Vec<String> = Vec::new();
    let mut last_spec = None;
    emit(json!({"event": "monitoring", "peer": peer.to_string()}));
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
        if link.poll(now, &mut inputs, &mut outputs).await {
            let t = dog.heard(now);
            board.watch(emit, now, "link:peer", &format!("monitored peer {peer}"), t);
        }
        let t = dog.check(now);
        board.watch(emit, now, "link:peer", &format!("monitored peer {peer}"), t);
        control.0.copy_from(outputs.values());
        engine.cycle(now, inputs.values(), &mut control);
        emit_engine_events(&mut engine, emit, Some(&explainer), &mut last_spec);
        let stale = inputs.stale(now, &bounds);
        let verdict = guard.check(engine.frame(), &stale);
        if verdict.potentially_violated != last_potential {
            if !verdict.potentially_violated.is_empty() {
                tracing::warn!(
                    "potentially violated with stale inputs: {}",
                    verdict.potentially_violated.join(", ")
                );
                emit(json!({
                    "event": "potential_violation",
                    "constraints": verdict.potentially_violated,
                    "stale_inputs": names(&bundle, Space::Input, &stale),
                    "time_ms": now.0,
                }));
            }
            last_potential = verdict.potentially_violated;
        }
        stats.record(start);
    }
    emit(json!({"event": "stopped", "connected": link.is_connected()}));
    Ok(())
}

async fn gateway(
    setup: Setup,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
) -> anyhow::Result<()> {
    let Setup {
        config,
        bundle,
        map,
    } = setup;
    let client = config
        .client
        .clone()
        .context("gateway mode needs a client section")?;
    let server_config = config
        .server
        .clone()
        .context("gateway mode needs a server section")?;
    let (n_in, n_out) = (bundle.plant.inputs.len(), bundle.plant.outputs.len());
    let clock = Clock(Instant::now());
    let shared: SharedImage = Arc::new(Mutex::new(Shared {
        inputs: Bits::zeros(n_in),
        outputs: Bits::zeros(n_out),
        ..Shared::default()
    }));
    let server = server::start(
        &server_config,
        ServerImage::new(&map, server_config.unit),
        Arc::clone(&shared),
    )
    .await
    .with_context(|| format!("cannot listen on {}", server_config.bind))?;
    tracing::info!(
        "serving the PLC on {}, plant at {}",
        server.local,
        client.address
    );
    emit(
        json!({"event": "listening", "address": server.local.to_string(), "plant": client.address.to_string()}),
    );
    let plant_peer = client.address;
    let mut plant = Writer::new(client, map.clone());
    let mut engine = Engine::new(&bundle, FilterMode::Enforce, 6000);
    let mut guard = StaleGuard::new(&bundle);
    let mut control = Commanded(Bits::zeros(n_out));
    let mut inputs = AgedBits::new(n_in);
    let bounds = map.input_bounds();
    let mut plant_dog = Watchdog::new(config.link_timeout(), Millis::ZERO);
    let mut plc_dog = Watchdog::new(config.link_timeout(), Millis::ZERO);
    let mut plc_last: Option<Instant> = None;
    let mut board = AlarmBoard {
        alarms: AlarmList::new(),
    };
    let mut safe_reason: Option<String> = None;
    let mut last_spec = None;
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
        // 1. The plant.
        if plant.poll(now, &mut inputs).await {
            let t = plant_dog.heard(now);
            board.watch(emit, now, "link:plant", &format!("plant {plant_peer}"), t);
        }
        let t = plant_dog.check(now);
        board.watch(emit, now, "link:plant", &format!("plant {plant_peer}"), t);
        // 2. The PLC.
        let heard = match shared.lock() {
            Ok(s) => {
                control.0.copy_from(&s.outputs);
                s.plc_heard
            }
            Err(_) => None,
        };
        if heard.is_some() && heard != plc_last {
            plc_last = heard;
            let t = plc_dog.heard(heard.map_or(now, |h| clock.at(h)));
            board.watch(emit, now, "link:plc", "PLC", t);
        }
        let t = plc_dog.check(now);
        board.watch(emit, now, "link:plc", "PLC", t);
        // 3. The engine.
        if config.auto_reset && engine.is_tripped() {
            let _ = engine.reset();
        }
        engine.cycle(now, inputs.values(), &mut control);
        emit_engine_events(&mut engine, emit, None, &mut last_spec);
        // 4. Safe outputs.
        let stale = inputs.stale(now, &bounds);
        let mut applied = engine.applied().clone();
        let reason = if plc_dog.is_lost() {
            applied = guard
                .safe_outputs(engine.frame(), &stale)
                .unwrap_or_else(|_| Bits::zeros(n_out));
            Some("PLC lost: outputs held at the safe fallback".to_string())
        } else if stale.count_ones() > 0 {
            let v = guard.check(engine.frame(), &stale);
            if v.potentially_violated.is_empty() {
                None
            } else {
                applied = v
                    .fallback
                    .and_then(Result::ok)
                    .unwrap_or_else(|| Bits::zeros(n_out));
                Some(format!(
                    "stale inputs {}: {} potentially violated, safe fallback applied",
                    names(&bundle, Space::Input, &stale).join(" "),
                    v.potentially_violated.join(", ")
                ))
            }
        } else {
            None
        };
        if reason != safe_reason {
            match &reason {
                Some(r) => {
                    emit(
                        json!({"event": "safe_outputs", "reason": r, "outputs": bits_text(&applied), "time_ms": now.0}),
                    );
                    if safe_reason.is_some() {
                        board.clear(emit, now, "safe:outputs");
                    }
                    board.raise(emit, now, "safe:outputs", AlarmKind::Link, r.clone());
                }
                None => {
                    emit(json!({"event": "safe_outputs_released", "time_ms": now.0}));
                    board.clear(emit, now, "safe:outputs");
                }
            }
            safe_reason = reason;
        }
        engine
            .frame_mut()
            .now_mut(Space::Output)
            .copy_from(&applied);
        // 5. Outputs to the plant, sensors to the PLC.
        if plant.is_connected() {
            plant.write(now, &applied).await;
        }
        if let Ok(mut s) = shared.lock() {
            s.inputs.copy_from(inputs.values());
        }
        stats.record(start);
    }
    // Shutdown: the fallback of the current context, whatever the PLC commands.
    let now = clock.now();
    let stale = inputs.stale(now, &bounds);
    let safe = guard
        .safe_outputs(engine.frame(), &stale)
        .unwrap_or_else(|_| Bits::zeros(n_out));
    let written = plant.is_connected() && plant.write(now, &safe).await;
    tracing::info!(
        "stopped; safe outputs {safe} {}",
        if written {
            "written"
        } else {
            "not written (plant unreachable)"
        }
    );
    emit(json!({"event": "stopped", "outputs": bits_text(&safe), "written": written}));
    drop(server);
    Ok(())
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
        map,
    } = setup;
    let server_config = config
        .server
        .clone()
        .context("emulator mode needs a server section")?;
    let layout_path = config.plant.join("layout.ron");
    let layout = vigie_core::emulator::Layout::load(&layout_path)
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    let emulator = vigie_core::emulator::Emulator::new(&layout, &bundle.plant, config.seed)
        .map_err(|p| anyhow::anyhow!("{p}"))?;
    serve_backend(
        &config,
        &server_config,
        &map,
        EmulatorBackend(emulator),
        shutdown,
        emit,
        stats,
    )
    .await
}

/// Serves any backend: every cycle the outputs the PLC wrote go to the backend and the
/// backend's sensors to the image.
pub(crate) async fn serve_backend(
    config: &GatewayConfig,
    server_config: &vigie_core::live::config::ServerConfig,
    map: &IoMap,
    mut backend: impl IoBackend,
    shutdown: impl Future<Output = ()>,
    emit: Emit<'_>,
    stats: &mut CycleStats,
) -> anyhow::Result<()> {
    let n_out = map.outputs.len();
    let shared: SharedImage = Arc::new(Mutex::new(Shared {
        inputs: backend.read_inputs().clone(),
        outputs: Bits::zeros(n_out),
        ..Shared::default()
    }));
    let server = server::start(
        server_config,
        ServerImage::new(map, server_config.unit),
        Arc::clone(&shared),
    )
    .await
    .with_context(|| format!("cannot listen on {}", server_config.bind))?;
    tracing::info!("serving on {}", server.local);
    emit(json!({"event": "listening", "address": server.local.to_string()}));
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
