//! `vigie gateway-bench`: the gateway against a pymodbus plant on loopback, or over OPC
//! UA against the asyncua plant (`Protocol::OpcUa`: the PLC and the probe are
//! async-opcua clients, the gateway's client and server speak OPC UA, security None on
//! loopback), so that the two protocols are measured in the same run.
//!
//! Measures the sustained cycle rate and period jitter of the gateway loop, and the
//! latency from a sensor change at the plant to the filtered output at the plant: with
//! the PLC commanding the intermediate conveyor (A1), C3 rises at the plant
//! (CSs2 = C3 . /C4 . A1), the filter trips and the plant's A1 falls; C3 falls, the
//! trip resets (auto reset) and A1 returns. Both edges are timed from the moment the
//! plant peer is asked to change C3 until a probe client reads the new coil.
//!
//! With `load`, that many busy processes (`sh -c 'while :; do :; done'`) run beside
//! it for the whole run, a fixed background load; every link alarm raised once the
//! PLC's first command has reached the plant is false (nothing is lost in the bench)
//! and is counted. With `seconds`, edges are timed until that much time has passed.

use super::runtime::{self, CycleStats, Setup};
use anyhow::Context as _;
use std::io::{BufRead as _, BufReader, Write as _};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use tokio_modbus::client::{Reader as _, Writer as _};

use vigie_core::live::config::GatewayConfig;

/// Figures of one run.
#[derive(Debug, serde::Serialize)]
pub struct Figures {
    /// The protocol measured.
    pub protocol: Protocol,
    /// Cycles run.
    pub cycles: usize,
    /// Cycles per second over the run.
    pub rate_hz: f64,
    /// Period jitter |period − cycle| percentiles in ms: p50, p99, max.
    pub jitter_ms: [f64; 3],
    /// Work per cycle (poll, engine, write) percentiles in ms: p50, p99, max.
    pub busy_ms: [f64; 3],
    /// Sensor change → filtered output at the plant, percentiles in ms: p50, p99, max.
    pub latency_ms: [f64; 3],
    /// Edges timed.
    pub edges: usize,
    /// Busy background processes.
    pub load: usize,
    /// Seconds measured.
    pub seconds: f64,
    /// Link alarms (`link:plant`, `link:plc`) raised while measuring: all false,
    /// nothing is lost in the bench.
    pub false_alarms: Vec<String>,
    /// Safe outputs applied because inputs were older than their bound (a late plant,
    /// not a lost one: the data-age guard, not a link alarm).
    pub stale_holds: usize,
    /// The cycle thread's real-time priority, when one was asked for.
    pub rt_priority: Option<u8>,
    /// The peers' priority.
    pub peers: String,
}

/// The protocol of both sides of the gateway.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Protocol {
    /// Modbus TCP (pymodbus plant).
    Modbus,
    /// OPC UA (asyncua plant).
    OpcUa,
}

/// What a run does.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// The protocol of the PLC's and the plant's sides.
    pub protocol: Protocol,
    /// Edges to time (at least).
    pub edges: usize,
    /// Run at least this long.
    pub seconds: u64,
    /// Real-time priority of the cycle thread; `None`: normal priority.
    pub rt_priority: Option<u8>,
    /// Busy background processes.
    pub load: usize,
    /// Run the peers (the pymodbus plant, the PLC and the probe) at real-time priority
    /// 40 when the process may: they stand for devices of their own that the
    /// background load must not starve, so that what is measured is the gateway (the
    /// probe then sleeps 0.5 ms between its reads instead of polling in a busy loop).
    pub rt_peers: bool,
}

/// Gives every thread of process `pid` real-time priority 40 through `chrt`
/// (util-linux); returns why not when refused.
fn raise_peer_priority(pid: u32) -> Option<String> {
    match Command::new("chrt")
        .args(["-a", "-f", "-p", "40", &pid.to_string()])
        .output()
    {
        Ok(o) if o.status.success() => None,
        Ok(o) => Some(String::from_utf8_lossy(&o.stderr).trim().to_string()),
        Err(e) => Some(format!("chrt: {e}")),
    }
}

/// Busy processes, killed when dropped.
struct Load(Vec<std::process::Child>);

impl Load {
    fn start(n: usize) -> anyhow::Result<Self> {
        let mut v = Vec::with_capacity(n);
        for _ in 0..n {
            v.push(
                Command::new("sh")
                    .args(["-c", "while :; do :; done"])
                    .stdin(Stdio::null())
                    .spawn()
                    .context("cannot start a background load process")?,
            );
        }
        Ok(Self(v))
    }
}

impl Drop for Load {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn percentiles(mut v: Vec<f64>) -> [f64; 3] {
    if v.is_empty() {
        return [f64::NAN; 3];
    }
    v.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let i = ((v.len() - 1) as f64 * q).round() as usize;
        v.get(i).copied().unwrap_or(f64::NAN)
    };
    [at(0.5), at(0.99), at(1.0)]
}

fn repo_root() -> PathBuf {
    let here = PathBuf::from(".");
    if here.join("tests/peers/plant.py").is_file() {
        return here;
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Runs the benchmark: `edges` timed sensor edges, then the cycle figures.
pub fn run(plant_dir: &std::path::Path, opts: Options) -> anyhow::Result<Figures> {
    let Options {
        protocol,
        edges,
        seconds,
        rt_priority: cycle_priority,
        load,
        rt_peers,
    } = opts;
    let _load = Load::start(load)?;
    let signals = Signals::of(plant_dir)?;
    let (mut plant, mut plant_in, plant_addr, peers) = start_plant(protocol, &signals, rt_peers)?;

    let (setup, state) = gateway_setup(plant_dir, protocol, plant_addr, cycle_priority)?;
    let measuring = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let alarms = std::sync::Arc::new(std::sync::Mutex::new(Vec::<String>::new()));
    let stale = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let (m, a, s) = (
        std::sync::Arc::clone(&measuring),
        std::sync::Arc::clone(&alarms),
        std::sync::Arc::clone(&stale),
    );

    // The gateway on its own thread and runtime.
    let (addr_tx, addr_rx) = std::sync::mpsc::channel::<SocketAddr>();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let gateway = spawn_gateway(setup, (m, a, s), addr_tx, stop_rx)?;
    let server = addr_rx
        .recv_timeout(Duration::from_secs(10))
        .context("the gateway did not start")?;

    // The PLC (A1 ON, every 5 ms) and the probe on a second runtime (this thread).
    if rt_peers {
        let p = super::cycle::Priority {
            value: 40,
            explicit: true,
        };
        super::cycle::raise_priority(p, "bench PLC and probe");
    }
    let probe_pause = if rt_peers {
        Duration::from_micros(500)
    } else {
        Duration::ZERO
    };
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let result = rt.block_on(measure(
        Peers {
            protocol,
            server,
            plant: plant_addr,
            signals: &signals,
            state: &state,
        },
        &mut plant_in,
        &measuring,
        (edges, seconds),
        probe_pause,
    ));
    let _ = stop_tx.send(());
    let stats = gateway
        .join()
        .map_err(|_| anyhow::anyhow!("gateway thread panicked"))??;
    let _ = writeln!(plant_in, "quit");
    let _ = plant.kill();
    let _ = plant.wait();
    let (latencies, measured) = result?;
    let _ = std::fs::remove_dir_all(&state);
    let false_alarms = std::mem::take(
        &mut *alarms
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner),
    );

    let periods: Vec<f64> = stats
        .starts
        .windows(2)
        .map(|w| (w[1] - w[0]).as_secs_f64() * 1e3)
        .collect();
    let total = stats
        .starts
        .last()
        .zip(stats.starts.first())
        .map_or(0.0, |(l, f)| (*l - *f).as_secs_f64());
    Ok(Figures {
        protocol,
        cycles: stats.starts.len(),
        rate_hz: if total > 0.0 {
            (stats.starts.len() - 1) as f64 / total
        } else {
            0.0
        },
        jitter_ms: percentiles(periods.iter().map(|p| (p - 10.0).abs()).collect()),
        busy_ms: percentiles(stats.busy.iter().map(|d| d.as_secs_f64() * 1e3).collect()),
        latency_ms: percentiles(latencies.clone()),
        edges: latencies.len(),
        load,
        seconds: measured,
        false_alarms,
        stale_holds: stale.load(std::sync::atomic::Ordering::Relaxed),
        rt_priority: cycle_priority,
        peers,
    })
}

/// Starts the pymodbus plant of the venv (its peers at real-time priority if asked)
/// and drains its answers; returns it, its stdin, its address and the peers' priority.
fn start_plant(
    protocol: Protocol,
    signals: &Signals,
    rt_peers: bool,
) -> anyhow::Result<(
    std::process::Child,
    std::process::ChildStdin,
    SocketAddr,
    String,
)> {
    let root = repo_root();
    let venv = std::env::var_os("VIGIE_VENV").map_or_else(|| root.join(".venv"), PathBuf::from);
    let python = venv.join("bin/python");
    anyhow::ensure!(
        python.is_file(),
        "{} not found: create the venv with `scripts/test.sh` (or python3 -m venv .venv && .venv/bin/pip install -r requirements-test.txt)",
        python.display()
    );
    let mut command = Command::new(&python);
    match protocol {
        Protocol::Modbus => command.arg(root.join("tests/peers/plant.py")),
        Protocol::OpcUa => command.arg(root.join("tests/peers/opcua_plant.py")).args([
            "--namespace",
            &signals.namespace,
            "--inputs",
            &signals.inputs.join(","),
            "--outputs",
            &signals.outputs.join(","),
        ]),
    };
    let mut plant = command
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .context("cannot start the pymodbus plant")?;
    let peers = if rt_peers {
        raise_peer_priority(plant.id()).map_or_else(
            || "real-time 40".to_string(),
            |why| format!("normal (real-time refused: {why})"),
        )
    } else {
        "normal".to_string()
    };
    let plant_in = plant.stdin.take().context("plant stdin")?;
    let mut plant_out = BufReader::new(plant.stdout.take().context("plant stdout")?);
    let mut line = String::new();
    plant_out.read_line(&mut line)?;
    let port: u16 = line
        .trim()
        .strip_prefix("listening ")
        .and_then(|p| p.parse().ok())
        .with_context(|| format!("unexpected plant output {line:?}"))?;
    let plant_addr: SocketAddr = ([127, 0, 0, 1], port).into();
    // The plant answers every command with a line: drain them, or its stdout fills
    // after some 20,000 edges and the plant stops answering Modbus too.
    std::thread::Builder::new()
        .name("bench-plant-stdout".into())
        .spawn(move || {
            let mut sink = String::new();
            while plant_out.read_line(&mut sink).is_ok_and(|n| n > 0) {
                sink.clear();
            }
        })?;
    Ok((plant, plant_in, plant_addr, peers))
}

/// The gateway's setup for the bench (plant, its diagnosers, 10 ms cycle, a fresh
/// state folder, returned too).
fn gateway_setup(
    plant_dir: &std::path::Path,
    protocol: Protocol,
    plant_addr: SocketAddr,
    cycle_priority: Option<u8>,
) -> anyhow::Result<(Setup, PathBuf)> {
    let state = std::env::temp_dir().join(format!(
        "vigie-gateway-bench-{}-{protocol:?}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&state);
    let sides = match protocol {
        Protocol::Modbus => format!(
            "client: Modbus(address: \"{plant_addr}\"), server: Modbus(bind: \"127.0.0.1:0\", plc: \"127.0.0.1\")"
        ),
        Protocol::OpcUa => format!(
            "client: OpcUa(endpoint: \"opc.tcp://{plant_addr}/\", security: None), \
             server: OpcUa(bind: \"127.0.0.1:0\", security: [None], anonymous: true, plc_user: \"anonymous\")"
        ),
    };
    let text = format!(
        "Gateway(mode: Gateway, plant: {:?}, cycle_ms: 10, auto_reset: true, {sides}, \
         plausibility: false, cycle_priority: {}, realtime: {}, state_dir: {:?})",
        plant_dir.display().to_string(),
        cycle_priority.map_or_else(|| "None".to_string(), |p| format!("Some({p})")),
        cycle_priority.is_some(),
        state.display().to_string(),
    );
    let config = GatewayConfig::from_ron(&text, std::path::Path::new("bench.ron"))
        .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
    // The gateway as configured by default: with the plant's diagnosers.
    let (bundle, diagnosers) = runtime::load_plant(&config)?;
    let (client_map, server_map) = runtime::load_maps(&config, &bundle.plant)?;
    let setup = Setup {
        config,
        bundle,
        client_map,
        server_map,
        diagnosers,
        state_dir: state.clone(),
        history: None,
        program: None,
    };
    Ok((setup, state))
}

/// Runs the gateway on its own thread and runtime: its address is sent on `addr_tx`,
/// link alarms while measuring go to `alarms`, stale-input holds are counted.
fn spawn_gateway(
    setup: Setup,
    (m, a, s): (
        std::sync::Arc<std::sync::atomic::AtomicBool>,
        std::sync::Arc<std::sync::Mutex<Vec<String>>>,
        std::sync::Arc<std::sync::atomic::AtomicUsize>,
    ),
    addr_tx: std::sync::mpsc::Sender<SocketAddr>,
    stop_rx: tokio::sync::oneshot::Receiver<()>,
) -> std::io::Result<std::thread::JoinHandle<anyhow::Result<CycleStats>>> {
    std::thread::Builder::new()
        .name("gateway".into())
        .spawn(move || {
            let mut stats = CycleStats::default();
            let mut emit = move |e: serde_json::Value| {
                if e["event"] == "listening"
                    && let Some(addr) = e["address"].as_str().and_then(|a| a.parse().ok())
                {
                    let _ = addr_tx.send(addr);
                }
                let key = e["key"].as_str().unwrap_or_default();
                if e["event"] == "alarm" && m.load(std::sync::atomic::Ordering::Acquire) {
                    let text = format!("{key} at {} ms: {}", e["time_ms"], e["message"]);
                    if key.starts_with("link:") {
                        a.lock()
                            .unwrap_or_else(std::sync::PoisonError::into_inner)
                            .push(text);
                    } else if key == "safe:outputs"
                        && e["message"]
                            .as_str()
                            .is_some_and(|t| t.starts_with("stale inputs"))
                    {
                        s.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    }
                }
            };
            let rt = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()?;
            rt.block_on(runtime::run(
                setup,
                async {
                    let _ = stop_rx.await;
                },
                &mut emit,
                &mut stats,
                None,
            ))?;
            anyhow::Ok(stats)
        })
}

/// The plant's signals as the bench drives them: the sensor it moves and the output it
/// watches are the ones at discrete input 3 and coil 1 of the plant's addresses (the
/// sorting station's C3 and A1), by name for OPC UA.
pub(crate) struct Signals {
    namespace: String,
    inputs: Vec<String>,
    outputs: Vec<String>,
    /// The moved sensor's index and name.
    sensor: (usize, String),
    /// The watched output's index and name.
    output: (usize, String),
}

impl Signals {
    fn of(plant_dir: &std::path::Path) -> anyhow::Result<Self> {
        use vigie_core::plant::Address;
        let plant = vigie_core::plant::Plant::load(&plant_dir.join("plant.ron"))
            .map_err(|p| anyhow::anyhow!("{}", vigie_core::diag::render(&p)))?;
        let find = |signals: &[vigie_core::plant::Signal], at: Address| {
            signals
                .iter()
                .position(|s| s.address == Some(at))
                .and_then(|k| signals.get(k).map(|s| (k, s.id.clone())))
        };
        Ok(Self {
            namespace: vigie_core::live::nodemap::plant_namespace(plant_dir),
            inputs: plant.inputs.iter().map(|s| s.id.clone()).collect(),
            outputs: plant.outputs.iter().map(|s| s.id.clone()).collect(),
            sensor: find(&plant.inputs, Address::DiscreteInput(3))
                .context("the bench moves the sensor at discrete input 3; the plant has none")?,
            output: find(&plant.outputs, Address::Coil(1))
                .context("the bench watches the output at coil 1; the plant has none")?,
        })
    }
}

/// Where the bench's PLC and probe connect.
struct Peers<'a> {
    protocol: Protocol,
    /// The gateway's server (the PLC's side).
    server: SocketAddr,
    /// The plant.
    plant: SocketAddr,
    signals: &'a Signals,
    /// A folder for the OPC UA clients' PKI.
    state: &'a std::path::Path,
}

/// An OPC UA session on `endpoint` (security None), its event loop spawned.
async fn opcua_session(
    endpoint: &str,
    pki: &std::path::Path,
) -> anyhow::Result<std::sync::Arc<opcua::client::Session>> {
    let mut client = opcua::client::ClientBuilder::new()
        .application_name("vigie-bench")
        .application_uri("urn:vigie:bench")
        .pki_dir(pki)
        .create_sample_keypair(true)
        .trust_server_certs(true)
        .session_retry_limit(0)
        .client()
        .map_err(|e| anyhow::anyhow!("OPC UA client: {}", e.join("; ")))?;
    let (session, event_loop) = client
        .connect_to_matching_endpoint(
            (
                endpoint,
                opcua::crypto::SecurityPolicy::None.to_str(),
                opcua::types::MessageSecurityMode::None,
            ),
            opcua::client::IdentityToken::Anonymous,
        )
        .await
        .map_err(|e| anyhow::anyhow!("cannot connect to {endpoint}: {e}"))?;
    event_loop.spawn();
    tokio::time::timeout(Duration::from_secs(10), session.wait_for_connection())
        .await
        .map_err(|_| anyhow::anyhow!("no session on {endpoint} within 10 s"))?;
    Ok(session)
}

/// The PLC (the watched output ON, every 5 ms) and the probe reading that output at
/// the plant, in either protocol.
enum Probe {
    Modbus(tokio_modbus::client::Context),
    OpcUa(std::sync::Arc<opcua::client::Session>, opcua::types::NodeId),
}

impl Probe {
    /// Starts the PLC's task and connects the probe.
    async fn start(p: &Peers<'_>) -> anyhow::Result<(Self, tokio::task::JoinHandle<()>)> {
        let (k, name) = p.signals.output.clone();
        let n_out = p.signals.outputs.len();
        let commands: Vec<bool> = (0..n_out).map(|i| i == k).collect();
        match p.protocol {
            Protocol::Modbus => {
                let mut plc =
                    tokio_modbus::client::tcp::connect_slave(p.server, tokio_modbus::Slave(1))
                        .await?;
                let n_in = u16::try_from(p.signals.inputs.len()).unwrap_or(u16::MAX);
                let plc_task = tokio::spawn(async move {
                    loop {
                        let _ = plc.read_discrete_inputs(0, n_in).await;
                        let _ = plc.write_multiple_coils(0, &commands).await;
                        tokio::time::sleep(Duration::from_millis(5)).await;
                    }
                });
                let probe =
                    tokio_modbus::client::tcp::connect_slave(p.plant, tokio_modbus::Slave(1))
                        .await?;
                Ok((Self::Modbus(probe), plc_task))
            }
            Protocol::OpcUa => {
                let plc = opcua_session(
                    &format!("opc.tcp://{}/", p.server),
                    &p.state.join("plc-pki"),
                )
                .await?;
                let ns = plc.get_namespace_index(&p.signals.namespace).await?;
                let writes: Vec<opcua::types::WriteValue> = p
                    .signals
                    .outputs
                    .iter()
                    .zip(&commands)
                    .map(|(id, v)| opcua::types::WriteValue {
                        node_id: opcua::types::NodeId::new(ns, id.clone()),
                        attribute_id: opcua::types::AttributeId::Value as u32,
                        index_range: Default::default(),
                        value: opcua::types::DataValue::value_only(opcua::types::Variant::Boolean(
                            *v,
                        )),
                    })
                    .collect();
                let plc_task = tokio::spawn(async move {
                    loop {
                        let _ = plc.write(&writes).await;
                        tokio::time::sleep(Duration::from_millis(5)).await;
                    }
                });
                let probe = opcua_session(
                    &format!("opc.tcp://{}/", p.plant),
                    &p.state.join("probe-pki"),
                )
                .await?;
                let ns = probe.get_namespace_index(&p.signals.namespace).await?;
                Ok((
                    Self::OpcUa(probe, opcua::types::NodeId::new(ns, name)),
                    plc_task,
                ))
            }
        }
    }

    /// The watched output at the plant (bounded: a plant that stops answering ends
    /// the bench with an error instead of hanging it).
    async fn read(&mut self, k: usize) -> anyhow::Result<bool> {
        let limit = Duration::from_secs(5);
        let late = || anyhow::anyhow!("the plant did not answer the probe within 5 s");
        match self {
            Self::Modbus(probe) => {
                let at = u16::try_from(k).unwrap_or(u16::MAX);
                Ok(tokio::time::timeout(limit, probe.read_coils(at, 1))
                    .await
                    .map_err(|_| late())???
                    .first()
                    .copied()
                    .unwrap_or(false))
            }
            Self::OpcUa(session, node) => {
                let v = tokio::time::timeout(
                    limit,
                    session.read(
                        &[opcua::types::ReadValueId::from(node.clone())],
                        opcua::types::TimestampsToReturn::Neither,
                        0.0,
                    ),
                )
                .await
                .map_err(|_| late())??;
                Ok(matches!(
                    v.first().and_then(|d| d.value.as_ref()),
                    Some(opcua::types::Variant::Boolean(true))
                ))
            }
        }
    }
}

/// The plant peer's command setting the moved sensor.
fn set_sensor(p: &Peers<'_>, on: bool) -> String {
    let (k, name) = &p.signals.sensor;
    match p.protocol {
        Protocol::Modbus => format!("di {k} {}", u8::from(on)),
        Protocol::OpcUa => format!("set {name} {}", u8::from(on)),
    }
}

/// Drives the watched output on through the PLC, then times `edges` sensor edges (and
/// at least `seconds`) from the plant to the filtered output; returns the latencies
/// (ms) and the time measured (s).
async fn measure(
    peers: Peers<'_>,
    plant_in: &mut std::process::ChildStdin,
    measuring: &std::sync::atomic::AtomicBool,
    (edges, seconds): (usize, u64),
    probe_pause: Duration,
) -> anyhow::Result<(Vec<f64>, f64)> {
    let (mut probe, plc_task) = Probe::start(&peers).await?;
    let watched = peers.signals.output.0;
    // Wait for the output at the plant.
    let deadline = Instant::now() + Duration::from_secs(10);
    while !probe.read(watched).await? {
        anyhow::ensure!(
            Instant::now() < deadline,
            "the PLC's command never reached the plant"
        );
        if !probe_pause.is_zero() {
            tokio::time::sleep(probe_pause).await;
        }
    }
    measuring.store(true, std::sync::atomic::Ordering::Release);
    let started = Instant::now();
    let mut latencies = Vec::with_capacity(edges);
    let mut k = 0;
    while k < edges || started.elapsed() < Duration::from_secs(seconds) {
        // Spread the phase of the change over the cycle.
        tokio::time::sleep(Duration::from_micros(3000 + (k as u64 * 7919) % 10_000)).await;
        let rising = k % 2 == 0;
        let t0 = Instant::now();
        writeln!(plant_in, "{}", set_sensor(&peers, rising))?;
        plant_in.flush()?;
        let deadline = t0 + Duration::from_secs(5);
        loop {
            if probe.read(watched).await? != rising {
                break;
            }
            if !probe_pause.is_zero() {
                tokio::time::sleep(probe_pause).await;
            }
            anyhow::ensure!(
                Instant::now() < deadline,
                "edge {k}: no filtered output within 5 s"
            );
        }
        latencies.push(t0.elapsed().as_secs_f64() * 1e3);
        k += 1;
    }
    measuring.store(false, std::sync::atomic::Ordering::Release);
    plc_task.abort();
    anyhow::Ok((latencies, started.elapsed().as_secs_f64()))
}
